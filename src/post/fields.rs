//! Per-point fields of a fitted knit, and their transfer to the leg's vertices.
//!
//! * **Stitch density** at a yarn point is the stitches of the faces around it over their area,
//!   in stitches per cm² ([`Knit::faces`]: a grid cell is one stitch, a heel-pocket cell the
//!   stitches its short rows add; the toe seam's faces are sewn, not knitted, and count neither
//!   way). A face's area is the norm of its vector area (for a quad, half the norm of the cross
//!   product of its diagonals; exact when planar). A point on no knitted face gets 0.
//! * **Tension** at a yarn point is the mean signed force `c1 (|x_b − x_a| − l)` of its springs
//!   (positive in tension), in the solver's force units (unit mass, per time unit squared, metres).
//! * **Stretch** at a yarn point, along the course and along the wale: the summed length of its
//!   springs in that direction over their summed rest length (1 at rest, 1.5 stretched by half;
//!   the `_STRETCH_COURSE` / `_STRETCH_WALE` attributes).
//! * **Coverage** at a yarn point, 0–1: the fraction of skin hidden by yarn seen along the
//!   normal (`_COVERAGE`). The knit is read as two families of opaque strips of yarn width `2r`:
//!   course yarns, one per course, so spaced by the local wale spacing `s_w` (the length of the
//!   point's wale springs), and wale yarn (the loops' legs), spaced by the local course spacing
//!   `s_c`. The holes are the rectangles between strips, so
//!   `coverage = 1 − (1 − min(1, 2 r_course / s_w)) · (1 − min(1, 2 r_wale / s_c))`,
//!   with `r_course` the radius of the point's course yarn and `r_wale` that of its wale springs.
//!   Overlap where strips cross is counted once; yarn flattening and loop curvature are ignored.
//! * **On the leg**, a vertex takes the kernel-weighted mean of the yarn points within a bandwidth
//!   (a biweight kernel, compactly supported, so far-away yarn has no say): smooth where the fit is
//!   smooth, and 0 where no yarn is near (uncovered skin).

use std::collections::HashMap;

use nalgebra::Point3;

use crate::base::{Direction, PerYarn, Vec3};
use crate::knit::{Knit, PointId};
use crate::leg::Leg;
use crate::sim::ForceTerms;

/// Square metres per square centimetre.
const M2_PER_CM2: f64 = 1e-4;

/// Stitches per cm² at every point of `knit` (see module docs).
pub fn stitch_density(knit: &Knit) -> Vec<f64> {
    let x = &knit.particles.x;
    let mut area_sum = vec![0.0; knit.len()];
    let mut stitch_sum = vec![0.0; knit.len()];
    for face in knit.faces().iter().filter(|f| f.stitches > 0.0) {
        let corners: Vec<Vec3> = face.corners.iter().map(|p| x[p.index()]).collect();
        let area = polygon_area(&corners);
        for p in &face.corners {
            area_sum[p.index()] += area;
            stitch_sum[p.index()] += face.stitches;
        }
    }
    area_sum
        .iter()
        .zip(&stitch_sum)
        .map(|(&area, &stitches)| {
            // Written as one over the area per stitch, so a grid (one stitch a cell) gives the
            // bytes it always has.
            let per_stitch = area / stitches;
            if stitches > 0.0 && per_stitch > 0.0 {
                M2_PER_CM2 / per_stitch
            } else {
                0.0
            }
        })
        .collect()
}

/// The norm of a polygon's vector area, `½ |Σ p_i × p_{i+1}|` (its area when planar), taken
/// about the first corner; for a quad, half the norm of its diagonals' cross product.
fn polygon_area(corners: &[Vec3]) -> f64 {
    match corners {
        [a, b, c, d] => (c - a).cross(&(d - b)).norm() / 2.0,
        [first, rest @ ..] => {
            rest.windows(2)
                .map(|pair| (pair[0] - first).cross(&(pair[1] - first)))
                .sum::<Vec3>()
                .norm()
                / 2.0
        }
        [] => 0.0,
    }
}

/// Mean signed spring force of every point's springs (see module docs).
pub fn tension(knit: &Knit, terms: &ForceTerms) -> Vec<f64> {
    let x = &knit.particles.x;
    (0..knit.len())
        .map(|i| {
            let incident = knit.incident(PointId(i as u32));
            let sum: f64 = incident
                .iter()
                .map(|inc| {
                    let s = &knit.springs[inc.spring as usize];
                    let c1 = terms.c1(knit, inc.spring);
                    c1 * ((x[s.b.index()] - x[s.a.index()]).norm() - s.rest)
                })
                .sum();
            sum / incident.len().max(1) as f64
        })
        .collect()
}

/// Stretch along the course and along the wale at every point: `(course, wale)` (see module
/// docs). A point with no spring in a direction gets 1 there.
pub fn stretch(knit: &Knit) -> (Vec<f64>, Vec<f64>) {
    (0..knit.len())
        .map(|i| {
            let spacing = local_spacing(knit, PointId(i as u32));
            let ratio = |d: usize| {
                if spacing.rest[d] > 0.0 {
                    spacing.length[d] / spacing.rest[d]
                } else {
                    1.0
                }
            };
            (ratio(0), ratio(1))
        })
        .unzip()
}

/// Coverage at every point (see module docs); `radius_m` is the yarn radius per
/// [`YarnKind::index`](crate::base::YarnKind::index), metres.
pub fn coverage(knit: &Knit, radius_m: PerYarn<f64>) -> Vec<f64> {
    (0..knit.len())
        .map(|i| {
            let spacing = local_spacing(knit, PointId(i as u32));
            let hidden = |radius: f64, count: u32, length: f64| {
                if count == 0 || length <= 0.0 {
                    0.0
                } else {
                    (2.0 * radius * count as f64 / length).min(1.0)
                }
            };
            let r_course = radius_m[knit.course_yarn[i].index() as usize];
            let r_wale = spacing
                .wale_yarn
                .map_or(0.0, |k| radius_m[k.index() as usize]);
            // Course yarns are spaced by the wale springs' length, and the other way round.
            let by_courses = hidden(r_course, spacing.count[1], spacing.length[1]);
            let by_wales = hidden(r_wale, spacing.count[0], spacing.length[0]);
            1.0 - (1.0 - by_courses) * (1.0 - by_wales)
        })
        .collect()
}

/// The springs at one point, summed per direction (index 0 course, 1 wale).
struct LocalSpacing {
    length: [f64; 2],
    rest: [f64; 2],
    count: [u32; 2],
    /// The yarn of the point's wale springs (the first one met).
    wale_yarn: Option<crate::base::YarnKind>,
}

fn local_spacing(knit: &Knit, p: PointId) -> LocalSpacing {
    let x = &knit.particles.x;
    let mut out = LocalSpacing {
        length: [0.0; 2],
        rest: [0.0; 2],
        count: [0; 2],
        wale_yarn: None,
    };
    for inc in knit.incident(p) {
        let s = &knit.springs[inc.spring as usize];
        let d = match s.direction {
            Direction::Course => 0,
            Direction::Wale => {
                out.wale_yarn.get_or_insert(s.yarn);
                1
            }
        };
        out.length[d] += (x[s.b.index()] - x[s.a.index()]).norm();
        out.rest[d] += s.rest;
        out.count[d] += 1;
    }
    out
}

/// The fields a fitted knit hands to a shader, one value per point (yarn point or leg vertex).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct KnitFields {
    /// Stitches per cm².
    pub stitch_density: Vec<f64>,
    /// Spacing along the course over its rest spacing.
    pub stretch_course: Vec<f64>,
    /// Spacing along the wale over its rest spacing.
    pub stretch_wale: Vec<f64>,
    /// Fraction of skin hidden by yarn, 0–1.
    pub coverage: Vec<f64>,
}

impl KnitFields {
    /// Every field at every point of `knit`; `radius_m` per yarn kind, metres.
    pub fn measure(knit: &Knit, radius_m: PerYarn<f64>) -> KnitFields {
        let (stretch_course, stretch_wale) = stretch(knit);
        KnitFields {
            stitch_density: stitch_density(knit),
            stretch_course,
            stretch_wale,
            coverage: coverage(knit, radius_m),
        }
    }

    /// The fields with their attribute names (`_STITCH_DENSITY` … in glTF), in a fixed order.
    pub fn named(&self) -> [(&'static str, &[f64]); 4] {
        [
            ("stitch_density", &self.stitch_density),
            ("stretch_course", &self.stretch_course),
            ("stretch_wale", &self.stretch_wale),
            ("coverage", &self.coverage),
        ]
    }

    /// The fields carried over to leg vertices by [`transfer_to_leg`]: 0 where no yarn is near.
    pub fn transfer_to_leg(
        &self,
        yarn_points: &[Vec3],
        leg_vertices: &[Point3<f64>],
        bandwidth: f64,
    ) -> KnitFields {
        let fields = self.named().map(|(_, values)| values);
        let [stitch_density, stretch_course, stretch_wale, coverage] =
            transfer_to_leg(yarn_points, &fields, leg_vertices, bandwidth)
                .try_into()
                .expect("four fields in, four out");
        KnitFields {
            stitch_density,
            stretch_course,
            stretch_wale,
            coverage,
        }
    }
}

/// Transfers per-yarn-point fields to leg vertices with a biweight kernel of radius `bandwidth`
/// metres; vertices with no yarn point within the bandwidth get 0. Returns one vector per
/// field, in order.
pub fn transfer_to_leg(
    yarn_points: &[Vec3],
    fields: &[&[f64]],
    leg_vertices: &[Point3<f64>],
    bandwidth: f64,
) -> Vec<Vec<f64>> {
    let grid = PointGrid::new(yarn_points, bandwidth);
    let mut out = vec![Vec::with_capacity(leg_vertices.len()); fields.len()];
    let mut sums = vec![0.0; fields.len()];
    for v in leg_vertices {
        let mut weight_sum = 0.0;
        sums.iter_mut().for_each(|s| *s = 0.0);
        grid.for_each_near(&v.coords, |i| {
            let d2 = (yarn_points[i] - v.coords).norm_squared() / (bandwidth * bandwidth);
            if d2 < 1.0 {
                let w = (1.0 - d2) * (1.0 - d2);
                weight_sum += w;
                for (sum, field) in sums.iter_mut().zip(fields) {
                    *sum += w * field[i];
                }
            }
        });
        for (values, sum) in out.iter_mut().zip(&sums) {
            values.push(if weight_sum > 0.0 {
                sum / weight_sum
            } else {
                0.0
            });
        }
    }
    out
}

/// A uniform grid over points, cell size = query radius: a query visits 27 cells.
struct PointGrid {
    cell: f64,
    cells: HashMap<[i64; 3], Vec<u32>>,
}

impl PointGrid {
    fn new(points: &[Vec3], cell: f64) -> PointGrid {
        let mut cells: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
        for (i, p) in points.iter().enumerate() {
            if let Some(key) = Self::key(p, cell) {
                cells.entry(key).or_default().push(i as u32);
            }
        }
        PointGrid { cell, cells }
    }

    fn key(p: &Vec3, cell: f64) -> Option<[i64; 3]> {
        let k = p.map(|c| (c / cell).floor());
        k.iter()
            .all(|c| c.is_finite() && c.abs() < 1e15)
            .then(|| [k.x as i64, k.y as i64, k.z as i64])
    }

    /// Calls `f` with every point in the 27 cells around `p`, in a fixed order.
    fn for_each_near(&self, p: &Vec3, mut f: impl FnMut(usize)) {
        let Some([x, y, z]) = Self::key(p, self.cell) else {
            return;
        };
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(list) = self.cells.get(&[x + dx, y + dy, z + dz]) {
                        list.iter().for_each(|&i| f(i as usize));
                    }
                }
            }
        }
    }
}

/// Per-point stitch fields of `knit` and their transfer to the leg's vertices.
pub fn measure_fields(knit: &Knit, leg: &Leg, radius_m: PerYarn<f64>) -> (KnitFields, KnitFields) {
    let per_point = KnitFields::measure(knit, radius_m);
    // Wide enough to span a nylon and a support course whichever way the knit runs, so the
    // alternation of the yarns does not print through as speckle.
    let bandwidth =
        3.0 * mean_spacing(knit, Direction::Course).max(mean_spacing(knit, Direction::Wale));
    let on_leg = per_point.transfer_to_leg(&knit.particles.x, &leg.positions, bandwidth);
    (per_point, on_leg)
}

/// Mean length of the springs along `direction`, metres.
fn mean_spacing(knit: &Knit, direction: Direction) -> f64 {
    let x = &knit.particles.x;
    let lengths: Vec<f64> = knit
        .springs
        .iter()
        .filter(|s| s.direction == direction)
        .map(|s| (x[s.b.index()] - x[s.a.index()]).norm())
        .collect();
    lengths.iter().sum::<f64>() / lengths.len().max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::knit::{Pattern, Tile};

    #[test]
    fn flat_grid_at_1mm_spacing_has_100_stitches_per_cm2() {
        let knit = Knit::grid(
            5,
            5,
            false,
            &Tile::of(Pattern::Plain),
            0.001,
            0.001,
            |w, c| Vec3::new(w as f64 * 0.001, c as f64 * 0.001, 0.0),
        );
        for d in stitch_density(&knit) {
            assert!((d - 100.0).abs() < 1e-9, "{d}");
        }
    }

    #[test]
    fn a_heel_pockets_short_rows_add_stitches_and_the_toe_seam_none() {
        // A flat 4×3 grid, 2 mm across a wale and 1 mm along it, closed by a toe seam, with
        // short rows over wales 1 and 2 (one each way) laid on the wales between courses 0 and 1.
        let (a, b) = (0.002, 0.001);
        let tile = Tile::of(Pattern::Plain);
        let at = |w: usize, c: f64| Vec3::new(w as f64 * a, c * b, 0.0);
        let knit = Knit::grid(4, 3, false, &tile, a, b, |w, c| at(w, c as f64))
            .with_toe_seam(b)
            .with_short_rows(0, vec![0, 1, 1, 0], &tile, a, b, at);
        let density = stitch_density(&knit);
        let cell = a * b / M2_PER_CM2;
        let expect = |p: PointId, stitches_per_cell: f64| {
            let d = density[p.index()];
            assert!(
                (d - stitches_per_cell / cell).abs() < 1e-9,
                "{p:?}: {d} vs {}",
                stitches_per_cell / cell
            );
        };
        // The toe seam's faces (across the flat last course) count for nothing.
        for w in 0..4 {
            expect(knit.point(w, 2), 1.0);
        }
        // The cells beside the pocket hold two stitches (one side three, the other one): wale 0's
        // first point has only that one; above it, one plain cell joins.
        expect(knit.point(0, 0), 2.0);
        expect(knit.point(0, 1), 3.0 / 2.0);
        // Between the two short-rowed wales, three faces of one stitch a third of a cell each:
        // wale 1's grid point meets the two-stitch cell and one of them (3 stitches over 4/3 of
        // a cell), its first short-row point the two-stitch cell and two (4 over 5/3).
        expect(knit.point(1, 0), 3.0 / (1.0 + 1.0 / 3.0));
        let first_short = PointId(knit.grid_len() as u32);
        assert_eq!(knit.fabric_coords(first_short), [1.0, 1.0 / 3.0]);
        expect(first_short, 4.0 / (1.0 + 2.0 / 3.0));
    }

    /// A flat 6×6 grid at `spacing` metres, stretched by `sx` along the course and `sy` along
    /// the wale.
    fn flat(pattern: Pattern, spacing: f64, sx: f64, sy: f64) -> Knit {
        Knit::grid(6, 6, false, &Tile::of(pattern), spacing, spacing, |w, c| {
            Vec3::new(w as f64 * spacing * sx, c as f64 * spacing * sy, 0.0)
        })
    }

    #[test]
    fn stretch_is_one_at_rest_and_follows_each_direction() {
        let (course, wale) = stretch(&flat(Pattern::Plain, 0.0005, 1.0, 1.0));
        assert!(course.iter().chain(&wale).all(|&s| (s - 1.0).abs() < 1e-12));
        let (course, wale) = stretch(&flat(Pattern::Plain, 0.0005, 1.5, 1.2));
        assert!(course.iter().all(|&s| (s - 1.5).abs() < 1e-12));
        assert!(wale.iter().all(|&s| (s - 1.2).abs() < 1e-12));
    }

    #[test]
    fn coverage_of_an_unstretched_patch_is_the_hand_calculation() {
        // Plain knit, nylon yarn of radius 0.03 mm, 0.5 mm apart both ways: strips of 0.06 mm
        // every 0.5 mm, so 12% of each direction is hidden and the holes are 0.88 × 0.88.
        let knit = flat(Pattern::Plain, 0.0005, 1.0, 1.0);
        let expected = 1.0 - 0.88 * 0.88;
        for c in coverage(&knit, [0.00003, 0.00004, 0.00003]) {
            assert!((c - expected).abs() < 1e-12, "{c} vs {expected}");
        }
        // Stretched ×2 along the course: wale strips twice as far apart.
        let knit = flat(Pattern::Plain, 0.0005, 2.0, 1.0);
        let expected = 1.0 - 0.88 * 0.94;
        for c in coverage(&knit, [0.00003, 0.00004, 0.00003]) {
            assert!((c - expected).abs() < 1e-12, "{c} vs {expected}");
        }
        // Yarn wider than the gap hides everything.
        assert!(coverage(&knit, [0.001; 3]).iter().all(|&c| c == 1.0));
    }

    #[test]
    fn coverage_uses_each_courses_own_yarn() {
        let knit = flat(Pattern::Alternating, 0.0005, 1.0, 1.0);
        let cov = coverage(&knit, [0.00003, 0.00004, 0.00003]);
        let values: std::collections::BTreeSet<u64> =
            cov.iter().map(|c| (c * 1e9).round() as u64).collect();
        assert!(
            values.len() > 1,
            "nylon and support courses differ: {values:?}"
        );
    }

    #[test]
    fn transfer_is_zero_far_from_yarn_and_exact_for_a_constant_field() {
        let points = vec![Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.001, 0.0, 0.0)];
        let values = vec![7.0, 7.0];
        let leg = vec![Point3::new(0.0005, 0.0, 0.0), Point3::new(1.0, 0.0, 0.0)];
        let out = transfer_to_leg(&points, &[&values], &leg, 0.002);
        assert!((out[0][0] - 7.0).abs() < 1e-12);
        assert_eq!(out[0][1], 0.0);
    }
}
