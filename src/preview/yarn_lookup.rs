//! Finding the yarn a camera ray meets just above the skin: the ray–capsule test, and a uniform
//! hash grid over the yarn segments' bounding boxes for rays from anywhere. The preview's camera
//! rays look up the capsules in its screen bins instead (`screen_bins.rs`, decision 0054); the
//! grid holds the few the bins cannot (reaching behind the eye, or over thousands of pixels),
//! and it is the reference the bins are tested against.
//!
//! Method. Sakaguchi & Miyata §7 (Fig. 16): for a point on the skin, look up the springs nearby,
//! treat each as a cylinder of radius r in a local frame whose xy-plane is tangent to the skin;
//! the point lies under a yarn when its in-plane distance d to the yarn's centre line is below
//! r, and then the yarn surface is at height z = √(r² − d²) above the centre line, with the
//! circle's normal. That is exact for a ray along the skin normal. For an oblique ray we
//! intersect the ray itself with the cylinders (capsules: a cylinder with spherical ends, so the
//! segments of one polyline join without gaps) in the layer just above the skin hit, and keep
//! the nearest hit before the skin. At normal incidence this is the paper's test, height and
//! normal ([`paper_tangent_frame`] is that form, and a test checks both agree); at a grazing
//! angle a ray crosses the layer over a longer stretch and meets more yarns, so the outline of
//! the leg darkens by itself, as a real stocking's does (paper §9).
//!
//! The grid: cubic cells of side ≈ three median segment lengths; every segment is listed in each
//! cell its radius-inflated bounding box touches. A query walks the cells the ray's stretch
//! through the yarn layer crosses, front to back, and stops once the nearest hit is settled. Cells are found through a hash map
//! with a fixed multiplicative hash (no per-process seed, so behaviour is reproducible), its
//! bits mixed down so that keys differing only in their y or z cell still spread over the
//! table. A capsule whose box covers more than `LARGE_CAPSULE_CELLS` (512) cells is not listed in
//! cells at all but tried by every query: a fit writes none, but a damaged file can hold a
//! segment kilometres long, and listing it cell by cell would be work without bound (issue 22).

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use nalgebra::{Point3, Vector3};
use rayon::prelude::*;

use crate::base::{PerYarn, YarnGeometry, YarnKind};

/// One yarn segment as the renderer sees it: a capsule.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Capsule {
    /// First end, metres, world space.
    pub a: Point3<f64>,
    /// Second end, metres.
    pub b: Point3<f64>,
    /// Radius, metres.
    pub radius: f64,
    /// The yarn.
    pub yarn: YarnKind,
}

/// Where a ray meets a yarn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct YarnHit {
    /// Distance along the (unit) ray, metres.
    pub t: f64,
    /// Outward unit normal of the yarn surface at the hit (the cylinder's circle normal).
    pub normal: Vector3<f64>,
    /// Unit direction of the yarn's centre line.
    pub tangent: Vector3<f64>,
    /// The yarn.
    pub yarn: YarnKind,
}

/// The yarn segments with a hash grid over them.
pub struct YarnIndex {
    capsules: Vec<Capsule>,
    cell: f64,
    origin: Point3<f64>,
    /// Cell key → range in `items`.
    cells: HashMap<u64, (u32, u32), BuildHasherDefault<CellHasher>>,
    items: Vec<u32>,
    /// Capsules over [`LARGE_CAPSULE_CELLS`] cells, tried by every query.
    large: Vec<u32>,
    max_radius: f64,
}

/// Most cells a capsule's box may cover and still be listed in each (8 × 8 × 8). A fit's
/// segments cover a few: the cell is at least the median segment length. Bounds the grid's
/// (cell, segment) pairs to this many per segment.
const LARGE_CAPSULE_CELLS: u64 = 512;

/// Side of a grid cell in median segment lengths. Real loops have segments a tenth of a
/// millimetre long: cells of one segment listed each in eight cells or more, and building the
/// grid (sorting and hashing its pairs) cost more than tracing a 1024² picture at 4 samples a
/// pixel; at three, a capsule touches one or two cells and a cell holds a dozen capsules.
const CELL_PER_MEDIAN_SEGMENT: f64 = 3.0;

/// Cell coordinates are packed in 21 bits each; a grid wider than this many cells is coarsened.
const MAX_CELLS_PER_AXIS: f64 = 2_000_000.0;

impl YarnIndex {
    /// Indexes the segments of `yarns` (offset by its `offset_m`), each of the radius of its
    /// yarn kind (`radius_m[kind.index()]`, metres). Segments with a non-finite end are left
    /// out.
    pub fn new(yarns: &YarnGeometry, radius_m: PerYarn<f64>) -> YarnIndex {
        let capsules: Vec<Capsule> = (0..yarns.segments.len())
            .into_par_iter()
            .filter_map(|i| capsule(yarns, radius_m, i))
            .collect();
        YarnIndex::from_capsules(capsules)
    }

    /// Indexes the given capsules.
    pub fn from_capsules(capsules: Vec<Capsule>) -> YarnIndex {
        let max_radius = capsules.iter().map(|c| c.radius).fold(0.0, f64::max);
        let mut lo = Point3::from([f64::INFINITY; 3]);
        let mut hi = Point3::from([f64::NEG_INFINITY; 3]);
        for c in &capsules {
            for p in [c.a, c.b] {
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k] - c.radius);
                    hi[k] = hi[k].max(p[k] + c.radius);
                }
            }
        }
        let mut lengths: Vec<f64> = capsules.iter().map(|c| (c.b - c.a).norm()).collect();
        let extent = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
        let cell = grid_cell(&mut lengths, max_radius, extent);
        let origin = if lo.iter().all(|c| c.is_finite()) {
            lo
        } else {
            Point3::origin()
        };
        let mut index = YarnIndex {
            capsules,
            cell,
            origin,
            cells: HashMap::default(),
            items: Vec::new(),
            large: Vec::new(),
            max_radius,
        };
        let boxes: Vec<(Point3<f64>, Point3<f64>)> = index
            .capsules
            .iter()
            .map(|c| {
                let r = Vector3::repeat(c.radius);
                (c.a.inf(&c.b) - r, c.a.sup(&c.b) + r)
            })
            .collect();
        let is_large: Vec<bool> = boxes
            .iter()
            .map(|(lo, hi)| index.cell_count(lo, hi) > LARGE_CAPSULE_CELLS)
            .collect();
        index.large = (0..index.capsules.len() as u32)
            .filter(|&i| is_large[i as usize])
            .collect();
        // (cell, segment) pairs, sorted: the layout, and so every query, is the same whatever
        // the thread count.
        let mut pairs: Vec<(u64, u32)> = boxes
            .par_iter()
            .enumerate()
            .filter(|(i, _)| !is_large[*i])
            .flat_map_iter(|(i, (lo, hi))| index.cell_range(lo, hi).map(move |key| (key, i as u32)))
            .collect();
        pairs.par_sort_unstable();
        let mut cells = HashMap::default();
        let mut items = Vec::with_capacity(pairs.len());
        let mut start = 0;
        while start < pairs.len() {
            let key = pairs[start].0;
            let mut end = start;
            while end < pairs.len() && pairs[end].0 == key {
                items.push(pairs[end].1);
                end += 1;
            }
            cells.insert(key, (start as u32, (end - start) as u32));
            start = end;
        }
        index.cells = cells;
        index.items = items;
        index
    }

    /// Number of segments indexed.
    pub fn len(&self) -> usize {
        self.capsules.len()
    }

    /// True when there is no segment.
    pub fn is_empty(&self) -> bool {
        self.capsules.is_empty()
    }

    /// The largest yarn radius, metres.
    pub fn max_radius(&self) -> f64 {
        self.max_radius
    }

    /// Side of a grid cell, metres.
    pub fn cell_size(&self) -> f64 {
        self.cell
    }

    fn coord(&self, x: f64, k: usize) -> u64 {
        let c = ((x - self.origin[k]) / self.cell).floor();
        c.clamp(0.0, (1u64 << 21) as f64 - 1.0) as u64
    }

    /// How many cells the box `lo..hi` overlaps.
    fn cell_count(&self, lo: &Point3<f64>, hi: &Point3<f64>) -> u64 {
        // At most 2²¹ per axis, so the product fits in a u64 (2⁶³).
        (0..3)
            .map(|k| self.coord(hi[k], k).max(self.coord(lo[k], k)) - self.coord(lo[k], k) + 1)
            .product()
    }

    /// The keys of the cells the box `lo..hi` overlaps.
    fn cell_range(&self, lo: &Point3<f64>, hi: &Point3<f64>) -> impl Iterator<Item = u64> {
        let l: [u64; 3] = std::array::from_fn(|k| self.coord(lo[k], k));
        let h: [u64; 3] = std::array::from_fn(|k| self.coord(hi[k], k).max(l[k]));
        (l[0]..=h[0]).flat_map(move |i| {
            (l[1]..=h[1]).flat_map(move |j| (l[2]..=h[2]).map(move |k| i | j << 21 | k << 42))
        })
    }

    /// The nearest yarn the ray `origin + t·dir` (`dir` a unit vector) meets for `t` in
    /// `t0..t1`, walking the grid cells that stretch crosses (its cost grows with its length:
    /// keep it to the layer above the skin). A ray starting inside a yarn hits it at `t0`.
    pub fn nearest_hit(
        &self,
        origin: &Point3<f64>,
        dir: &Vector3<f64>,
        t0: f64,
        t1: f64,
    ) -> Option<YarnHit> {
        if self.capsules.is_empty() || t1.partial_cmp(&t0) != Some(std::cmp::Ordering::Greater) {
            return None;
        }
        // Work from the start of the stretch: keeps the quadratic's terms at millimetre scale,
        // far from cancellation.
        let start = origin + dir * t0;
        let span = t1 - t0;
        let mut best: Option<(f64, u32)> = None;
        let try_capsule = |i: u32, best: &mut Option<(f64, u32)>| {
            let c = &self.capsules[i as usize];
            if let Some(t) = ray_capsule(&start, dir, c) {
                let better = best.is_none_or(|(bt, bi)| t < bt || (t == bt && i < bi));
                if t <= span && better {
                    *best = Some((t, i));
                }
            }
        };
        // The capsules too large for the grid first: the walk below stops at the first cell
        // past the best hit, which may be one of theirs.
        for &i in &self.large {
            try_capsule(i, &mut best);
        }
        // Cells in the order the ray crosses them (Amanatides & Woo's traversal), so a long
        // stretch costs the cells it crosses, not its bounding box; and it stops at the first
        // cell whose exit lies beyond the best hit: a capsule is listed in every cell its box
        // touches, so the cell holding any nearer hit point has been visited already.
        let rel = (start - self.origin) / self.cell;
        let mut cell: [i64; 3] = std::array::from_fn(|k| rel[k].floor() as i64);
        let mut step = [0i64; 3];
        let mut t_max = [f64::INFINITY; 3];
        let mut t_delta = [f64::INFINITY; 3];
        for k in 0..3 {
            if dir[k] > 0.0 {
                step[k] = 1;
                t_max[k] = ((cell[k] + 1) as f64 - rel[k]) * self.cell / dir[k];
                t_delta[k] = self.cell / dir[k];
            } else if dir[k] < 0.0 {
                step[k] = -1;
                t_max[k] = (cell[k] as f64 - rel[k]) * self.cell / dir[k];
                t_delta[k] = -self.cell / dir[k];
            }
        }
        const LIMIT: i64 = 1 << 21;
        loop {
            if cell.iter().all(|&c| (0..LIMIT).contains(&c)) {
                let key = cell[0] as u64 | (cell[1] as u64) << 21 | (cell[2] as u64) << 42;
                if let Some(&(first, count)) = self.cells.get(&key) {
                    for &i in &self.items[first as usize..(first + count) as usize] {
                        try_capsule(i, &mut best);
                    }
                }
            }
            let axis = (0..3)
                .min_by(|&a, &b| t_max[a].total_cmp(&t_max[b]))
                .unwrap_or(0);
            let exit = t_max[axis];
            if exit > span || exit.is_nan() || best.is_some_and(|(bt, _)| bt <= exit) {
                break;
            }
            cell[axis] += step[axis];
            t_max[axis] += t_delta[axis];
        }
        let (t, i) = best?;
        Some(hit_on(&self.capsules[i as usize], &start, dir, t0, t))
    }
}

/// The capsule of segment `i` of `yarns` (offset by its `offset_m`), of the radius of its yarn
/// kind (`radius_m[kind.index()]`, metres); `None` when an end is missing or not finite.
pub fn capsule(yarns: &YarnGeometry, radius_m: PerYarn<f64>, i: usize) -> Option<Capsule> {
    let s = yarns.segments.get(i)?;
    let offset = Vector3::from(yarns.offset_m);
    let at = |i: u32| {
        yarns
            .positions
            .get(i as usize)
            .map(|p| Point3::from(*p) + offset)
    };
    let (a, b) = (at(s.a)?, at(s.b)?);
    let finite = a.iter().chain(b.iter()).all(|c| c.is_finite());
    finite.then_some(Capsule {
        a,
        b,
        radius: radius_m[s.yarn.index() as usize],
        yarn: s.yarn,
    })
}

/// Side of the grid's cells for capsules of these `lengths` (reordered), the largest radius
/// `max_radius` and a bounding box whose longest side is `extent`, metres: three median lengths,
/// at least four radii, coarsened to at most two million cells along the box (cell coordinates
/// are packed in 21 bits).
pub fn grid_cell(lengths: &mut [f64], max_radius: f64, extent: f64) -> f64 {
    let middle = lengths.len() / 2;
    let median = match lengths.is_empty() {
        true => 1.0,
        false => *lengths.select_nth_unstable_by(middle, f64::total_cmp).1,
    };
    let mut cell = (CELL_PER_MEDIAN_SEGMENT * median)
        .max(4.0 * max_radius)
        .max(1e-9);
    if extent.is_finite() && extent / cell > MAX_CELLS_PER_AXIS {
        cell = extent / MAX_CELLS_PER_AXIS;
    }
    cell
}

/// The hit on capsule `c` of the ray `start + t·dir` at `t` (`dir` a unit vector), reported at
/// `t0 + t`: the ray's distance from where `start` lies on it.
pub fn hit_on(c: &Capsule, start: &Point3<f64>, dir: &Vector3<f64>, t0: f64, t: f64) -> YarnHit {
    let p = start + dir * t;
    let ab = c.b - c.a;
    let len2 = ab.norm_squared();
    let s = if len2 > 0.0 {
        ((p - c.a).dot(&ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let axis_point = c.a + ab * s;
    let outward = p - axis_point;
    let normal = if outward.norm() > 1e-12 * c.radius.max(1e-12) {
        outward.normalize()
    } else {
        -dir
    };
    let tangent = if len2 > 0.0 {
        ab / len2.sqrt()
    } else {
        Vector3::x()
    };
    YarnHit {
        t: t0 + t,
        normal,
        tangent,
        yarn: c.yarn,
    }
}

/// The first `t ≥ 0` where the ray `o + t·d` (`d` a unit vector) meets the capsule; 0 when `o`
/// is inside it. After Quilez's capsule intersection: the infinite cylinder by a quadratic, its
/// hit kept when it falls between the ends, else the sphere at the nearer end.
pub fn ray_capsule(o: &Point3<f64>, d: &Vector3<f64>, c: &Capsule) -> Option<f64> {
    let r2 = c.radius * c.radius;
    let ba = c.b - c.a;
    let oa = o - c.a;
    let baba = ba.norm_squared();
    // Inside the capsule already: the ray starts under this yarn.
    let s = if baba > 0.0 {
        (oa.dot(&ba) / baba).clamp(0.0, 1.0)
    } else {
        0.0
    };
    if (oa - ba * s).norm_squared() < r2 {
        return Some(0.0);
    }
    let bard = ba.dot(d);
    let baoa = ba.dot(&oa);
    let rdoa = d.dot(&oa);
    let oaoa = oa.norm_squared();
    let qa = baba - bard * bard;
    let qb = baba * rdoa - baoa * bard;
    let qc = baba * oaoa - baoa * baoa - r2 * baba;
    let h = qb * qb - qa * qc;
    if qa > 1e-30 * baba && h >= 0.0 {
        let t = (-qb - h.sqrt()) / qa;
        let y = baoa + t * bard;
        if y > 0.0 && y < baba {
            return (t >= 0.0).then_some(t);
        }
    }
    // The end caps.
    let mut best: Option<f64> = None;
    for end in [c.a, c.b] {
        let oc = o - end;
        let b = d.dot(&oc);
        let cc = oc.norm_squared() - r2;
        let h = b * b - cc;
        if h >= 0.0 {
            let t = -b - h.sqrt();
            if t >= 0.0 && best.is_none_or(|bt| t < bt) {
                best = Some(t);
            }
        }
    }
    best
}

/// The paper's test (§7, Fig. 16) for a skin point `p` with unit normal `n` and one yarn
/// segment: in the frame whose xy-plane is tangent to the skin at `p`, project the segment's
/// centre line onto the plane; if the in-plane distance d from `p` to it is below the radius,
/// the yarn covers `p`, its surface lies z = √(r² − d²) above the centre line, and its normal is
/// the circle's, `(in-plane offset direction · d + n · z) / r`. Returns the height of the yarn
/// surface above the skin plane (metres) and that normal, or `None` where the skin shows.
pub fn paper_tangent_frame(
    p: &Point3<f64>,
    n: &Vector3<f64>,
    c: &Capsule,
) -> Option<(f64, Vector3<f64>)> {
    let flat = |q: &Point3<f64>| {
        let v = q - p;
        (v - n * v.dot(n), v.dot(n))
    };
    let ((a_xy, a_z), (b_xy, b_z)) = (flat(&c.a), flat(&c.b));
    let ab = b_xy - a_xy;
    let len2 = ab.norm_squared();
    let s = if len2 > 0.0 {
        (-a_xy.dot(&ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    // Offset from the centre line to p, in the plane.
    let offset = -(a_xy + ab * s);
    let d = offset.norm();
    if d >= c.radius {
        return None;
    }
    let z = (c.radius * c.radius - d * d).sqrt();
    let centre_height = a_z + (b_z - a_z) * s;
    let dir = if d > 0.0 {
        offset / d
    } else {
        Vector3::zeros()
    };
    let normal = (dir * d + n * z) / c.radius;
    Some((centre_height + z, normal))
}

/// FxHash-style multiplicative hasher for cell keys: fast and the same in every process.
/// `finish` mixes the high bits down (MurmurHash3's fmix64): a product's low bits depend only
/// on the key's low bits, the x cell, and the table picks buckets by the low bits, so without
/// it every cell of one x column lands in one probe sequence (a yarn segment 10³⁷ m long in y
/// made 2 million such keys, and building the table ran past the process fuzz's 60 s).
#[derive(Default)]
pub struct CellHasher(u64);

impl Hasher for CellHasher {
    fn finish(&self) -> u64 {
        let mut h = self.0;
        h ^= h >> 33;
        h = h.wrapping_mul(0xff51_afd7_ed55_8ccd);
        h ^= h >> 33;
        h = h.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
        h ^ (h >> 33)
    }

    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }

    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(0x517c_c1b7_2722_0a95);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn capsule(a: [f64; 3], b: [f64; 3], r: f64) -> Capsule {
        Capsule {
            a: Point3::from(a),
            b: Point3::from(b),
            radius: r,
            yarn: YarnKind::Nylon,
        }
    }

    #[test]
    fn at_normal_incidence_the_ray_hit_is_the_papers_circle_equation() {
        // A yarn along x, its centre line 0.03 mm above the skin plane z = 0.
        let r = 3e-5;
        let c = capsule([-1e-3, 0.0, r], [1e-3, 0.0, r], r);
        let n = Vector3::z();
        for d in [0.0, 0.3 * r, 0.7 * r, 0.99 * r] {
            let p = Point3::new(1e-4, d, 0.0);
            let (height, paper_normal) = paper_tangent_frame(&p, &n, &c).unwrap();
            let origin = p + n * 1e-3;
            let index = YarnIndex::from_capsules(vec![c]);
            let hit = index.nearest_hit(&origin, &-n, 0.0, 1e-3).unwrap();
            let ray_height = 1e-3 - hit.t;
            assert!((height - ray_height).abs() < 1e-12, "d = {d}");
            assert!((hit.normal - paper_normal).norm() < 1e-6, "d = {d}");
        }
        let beside = Point3::new(0.0, 1.01 * r, 0.0);
        assert!(paper_tangent_frame(&beside, &n, &c).is_none());
        let index = YarnIndex::from_capsules(vec![c]);
        assert!(index
            .nearest_hit(&(beside + n * 1e-3), &-n, 0.0, 1e-3)
            .is_none());
    }

    #[test]
    fn an_oblique_ray_is_covered_over_a_wider_strip() {
        // Across-the-ray yarns: the covered strip on the skin widens as 1/cos θ.
        let r = 3e-5;
        let c = capsule([0.0, -1e-3, r], [0.0, 1e-3, r], r);
        let index = YarnIndex::from_capsules(vec![c]);
        let covered = |theta: f64| {
            let dir = Vector3::new(theta.sin(), 0.0, -theta.cos());
            let n = 4000;
            let hits = (0..n)
                .filter(|i| {
                    let x = -4e-4 + 8e-4 * (*i as f64 + 0.5) / n as f64;
                    let skin = Point3::new(x, 0.0, 0.0);
                    let t_skin = 5e-4;
                    let origin = skin - dir * t_skin;
                    index.nearest_hit(&origin, &dir, 0.0, t_skin).is_some()
                })
                .count();
            hits as f64 / n as f64 * 8e-4
        };
        let frontal = covered(0.0);
        assert!((frontal - 2.0 * r).abs() < 0.05 * r, "{frontal}");
        let oblique = covered(60f64.to_radians());
        assert!(
            (oblique - 2.0 * r / 0.5).abs() < 0.1 * r,
            "{oblique} vs {}",
            4.0 * r
        );
    }

    #[test]
    fn the_grid_finds_the_same_nearest_hit_as_a_scan() {
        let r = 4e-5;
        let mut capsules = Vec::new();
        for i in 0..20 {
            let y = i as f64 * 5e-4;
            capsules.push(capsule([0.0, y, r], [1e-2, y, r], r));
            let x = i as f64 * 5e-4;
            capsules.push(capsule([x, 0.0, r], [x, 1e-2, r], r));
        }
        let index = YarnIndex::from_capsules(capsules.clone());
        let dir = Vector3::new(0.3, 0.2, -1.0).normalize();
        for k in 0..400 {
            let skin = Point3::new(
                (k % 20) as f64 * 4.7e-4 + 1e-5,
                (k / 20) as f64 * 4.9e-4 + 2e-5,
                0.0,
            );
            let t = 3e-4;
            let origin = skin - dir * t;
            let scan = capsules
                .iter()
                .filter_map(|c| ray_capsule(&origin, &dir, c))
                .filter(|&s| s <= t)
                .fold(None, |acc: Option<f64>, s| {
                    Some(acc.map_or(s, |a| a.min(s)))
                });
            let grid = index.nearest_hit(&origin, &dir, 0.0, t).map(|h| h.t);
            match (scan, grid) {
                (None, None) => {}
                (Some(a), Some(b)) => assert!((a - b).abs() < 1e-12),
                other => panic!("{k}: {other:?}"),
            }
        }
    }

    #[test]
    fn a_capsule_too_large_for_the_grid_is_still_found_and_lists_in_no_cell() {
        let r = 4e-5;
        let mut capsules: Vec<Capsule> = (0..20)
            .map(|i| {
                let y = i as f64 * 5e-4;
                capsule([0.0, y, r], [1e-2, y, r], r)
            })
            .collect();
        // Kilometres long in y and z: millions of cells by two axes.
        capsules.push(capsule([5e-3, 0.0, r], [5e-3, 5e3, 5e3], r));
        let index = YarnIndex::from_capsules(capsules.clone());
        assert_eq!(index.large, vec![20]);
        assert!(index.items.len() < 100 * capsules.len());
        // Straight down onto the long capsule's start.
        let dir = -Vector3::z();
        let origin = Point3::new(5e-3, 2.5e-4, 1e-3);
        let hit = index.nearest_hit(&origin, &dir, 0.0, 1e-3).unwrap();
        let scan = capsules
            .iter()
            .filter_map(|c| ray_capsule(&origin, &dir, c))
            .fold(f64::INFINITY, f64::min);
        assert!((hit.t - scan).abs() < 1e-12, "{} vs {scan}", hit.t);
    }

    #[test]
    fn cell_keys_differing_only_in_y_or_z_spread_over_the_table() {
        use std::hash::BuildHasher;
        let build = BuildHasherDefault::<CellHasher>::default();
        let low: std::collections::BTreeSet<u64> = (0..1024u64)
            .flat_map(|j| [j << 21, j << 42])
            .map(|key| build.hash_one(key) & 1023)
            .collect();
        assert!(low.len() > 512, "{} distinct low bits", low.len());
    }
}
