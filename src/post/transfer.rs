//! The fields' transfer from the fitted knit to the leg's vertices, what `leg.ply`, `leg.glb`'s
//! attributes and `density.png` show.
//!
//! A vertex takes the biweight-kernel mean (compactly supported, so far-away yarn has no say) of
//! the fabric within [`TRANSFER_BANDWIDTH_M`], 16 mm, the same on every grid and the real
//! stitches, so that every grid hands the leg the same fields (docs/decisions/0065). A grid
//! whose points lie further apart than a third of that is sampled inside its faces (bilinear,
//! each sample weighted by the stitches it stands for, as each point counts once on a finer
//! grid): a kernel three coarse spacings wide blurred a 100×100 stocking's heel. Skin with no
//! fabric that near takes the mean of the grid's points within three grid spacings (a loose
//! stocking round a thin ankle still covers it), and 0 where no yarn is near even so (uncovered
//! skin). Skin beyond the stocking's open ends (the welt's plane, an open tube's ankle ring)
//! takes nothing, however near their yarn ([`OpenEnd`]). Pressure is not carried: the stress is,
//! and pressed on the skin's curvature at the vertex itself ([`crate::post::fields`]).
//!
//! Deterministic whatever the thread count: the kernel sums run in the vertices' order.

use nalgebra::{Matrix3, Point3};
use rayon::prelude::*;

use crate::base::{Direction, PointGrid, Vec3};
use crate::knit::{Knit, PointId};
use crate::leg::SkinCurvature;
use crate::post::fields::{pressed, KnitFields, MEASURE_SPAN_M};

/// Radius of the kernel that carries the fields to the leg's vertices, metres: the same on every
/// grid ([`carry_to_leg`]), and the fabric each point's fields are measured over.
pub const TRANSFER_BANDWIDTH_M: f64 = 2.0 * MEASURE_SPAN_M;

/// A kernel is at least this many spacings of what it averages wide: of the samples inside a
/// coarse grid's cells under [`TRANSFER_BANDWIDTH_M`], of a grid's own points under the wider
/// kernel that reaches skin the fabric hangs further off.
const SPACINGS_PER_KERNEL: f64 = 3.0;

/// At most this many samples along each side of a cell (a leg at absurd scale widens the
/// kernel instead of sampling millions).
const MAX_SAMPLES_PER_CELL_SIDE: usize = 4;

/// An open end of a stocking (its welt, an open tube's ankle): the plane of its held ring and
/// the side the fabric lies on. Skin beyond it is bare, however near the ring's yarn: the kernel
/// and the three grid spacings reach past the end, and would cover a band as wide as the grid
/// is coarse. Fabric folded back past a slack ring (a quarter course at most) is not counted.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OpenEnd {
    /// The ring's centre.
    pub centre: Point3<f64>,
    /// Unit vector from the ring into the stocking.
    pub inward: Vec3,
}

impl OpenEnd {
    /// The open ends of a tube's knit: its first ring, and its last unless a toe seam closes
    /// it. Each ring's plane is fitted to its points (the normal is the least-spread direction
    /// of their scatter), facing the knit's centroid: the next ring can fold past a held one at
    /// a slack end, so the line to it is no guide.
    pub fn of_tube(knit: &Knit) -> Vec<OpenEnd> {
        let x = &knit.particles.x;
        if knit.courses < 2 || x.is_empty() {
            return Vec::new();
        }
        let middle: Vec3 = x.iter().sum::<Vec3>() / x.len() as f64;
        let end = |c: usize| {
            let ring: Vec<Vec3> = (0..knit.wales)
                .map(|w| x[knit.point(w, c).index()])
                .collect();
            let centre = ring.iter().sum::<Vec3>() / ring.len() as f64;
            let scatter: Matrix3<f64> = ring
                .iter()
                .map(|p| (p - centre) * (p - centre).transpose())
                .sum();
            let eigen = scatter.symmetric_eigen();
            let least = eigen.eigenvalues.imin();
            let normal: Vec3 = eigen.eigenvectors.column(least).into_owned();
            let towards = middle - centre;
            let inward = if normal.dot(&towards) < 0.0 {
                -normal
            } else {
                normal
            };
            OpenEnd {
                centre: Point3::from(centre),
                inward,
            }
        };
        let mut ends = vec![end(0)];
        if !knit.has_toe_seam() {
            ends.push(end(knit.courses - 1));
        }
        ends
    }

    /// True for a point beyond the end, where there is no fabric.
    pub fn beyond(&self, p: &Point3<f64>) -> bool {
        (p - self.centre).dot(&self.inward) < 0.0
    }
}

/// `per_point`, the fields at the points of `knit`, carried to `leg_vertices` (module docs): by
/// the 16 mm kernel over samples inside the grid's cells where its points lie further apart
/// than a third of that, over its points where they do not; skin with no fabric that near, by
/// the grid's points within three grid spacings; skin beyond one of the `ends`, none.
pub fn carry_to_leg(
    knit: &Knit,
    per_point: &KnitFields,
    leg_vertices: &[Point3<f64>],
    skin: &SkinCurvature,
    ends: &[OpenEnd],
) -> KnitFields {
    let bare: Vec<bool> = leg_vertices
        .iter()
        .map(|v| ends.iter().any(|end| end.beyond(v)))
        .collect();
    let spacing = mean_spacing(knit, Direction::Course).max(mean_spacing(knit, Direction::Wale));
    // A graded grid's point stands for its ring's share of an even one's fabric.
    let ring_shares = knit.point_fabric_shares();
    let points = Carrier {
        fields: per_point,
        at: &knit.particles.x,
        weights: ring_shares.as_deref(),
        bandwidth: (SPACINGS_PER_KERNEL * spacing).max(TRANSFER_BANDWIDTH_M),
    };
    let n = samples_per_side(spacing);
    if n == 1 {
        return from_first_near(&[points], leg_vertices, &bare, skin);
    }
    let samples = CellSamples::of(knit, n);
    let sampled = samples.of_fields(per_point);
    let inside_cells = Carrier {
        fields: &sampled,
        at: &samples.positions,
        weights: Some(&samples.weights),
        // 16 mm, wider only where `n` is at its cap (a leg at an absurd scale).
        bandwidth: (SPACINGS_PER_KERNEL * spacing / n as f64).max(TRANSFER_BANDWIDTH_M),
    };
    from_first_near(&[inside_cells, points], leg_vertices, &bare, skin)
}

/// Samples along each side of a grid cell whose points lie `spacing` metres apart: enough that
/// [`TRANSFER_BANDWIDTH_M`] spans [`SPACINGS_PER_KERNEL`] of them, at most
/// [`MAX_SAMPLES_PER_CELL_SIDE`]; 1 (the points alone) for a grid that fine already.
fn samples_per_side(spacing: f64) -> usize {
    let n = (SPACINGS_PER_KERNEL * spacing / TRANSFER_BANDWIDTH_M).ceil();
    n.clamp(1.0, MAX_SAMPLES_PER_CELL_SIDE as f64) as usize
}

/// Points on a knit's faces, each a weighted mean of its face's corners, with the knitted
/// fabric it stands for: `(n + 1) × (n + 1)` per four-cornered face (bilinear, its corners and
/// edges included, weighted by the trapezoid rule), `n × n` per triangle of any other face
/// fanned from its centroid (the heel pocket's wider faces, the toe seam's folds).
struct CellSamples {
    positions: Vec<Vec3>,
    /// The stitches each sample stands for, in grid cells: a face's samples share its
    /// [`Face::stitches`] (a toe seam's face, sewn, counts as a cell), as a grid point stands
    /// for one cell where the points are carried alone. Not fitted area: that would weigh
    /// stretched fabric more on a coarse grid than on a fine one, where every point counts once.
    weights: Vec<f64>,
    /// Each sample's corners and their weights: `terms[starts[k]..starts[k + 1]]`.
    starts: Vec<usize>,
    terms: Vec<(PointId, f64)>,
}

impl CellSamples {
    fn of(knit: &Knit, n: usize) -> CellSamples {
        assert!(n >= 1, "at least one sample along a cell's side");
        let x = &knit.particles.x;
        let mut samples = CellSamples {
            positions: Vec::new(),
            weights: Vec::new(),
            starts: vec![0],
            terms: Vec::new(),
        };
        // The trapezoid rule on an `(n + 1) × (n + 1)` lattice: a cell's corners and edges are
        // its neighbours' too (their weights add up), and the fabric's edge rows are sampled.
        let lattice = (0..=n).map(|i| {
            let end = i == 0 || i == n;
            (i as f64 / n as f64, if end { 0.5 } else { 1.0 })
        });
        let cells: Vec<(f64, f64, f64)> = lattice
            .clone()
            .flat_map(|(u, wu)| lattice.clone().map(move |(v, wv)| (u, v, wu * wv)))
            .collect();
        let per_sample = 1.0 / (n * n) as f64;
        // The toe seam's faces, sewn, count as a cell of the last course's.
        let seam_face = knit.grid_spring_factors(knit.courses.saturating_sub(1))[0];
        for face in knit.faces() {
            let c = &face.corners;
            let stitches = match face.stitches > 0.0 {
                true => face.stitches,
                false => seam_face,
            };
            if let [a, b, cc, d] = c[..] {
                // Corners in order round the face (`Knit::faces`), so the map is bilinear.
                for &(u, v, share) in &cells {
                    let terms = [
                        (a, (1.0 - u) * (1.0 - v)),
                        (b, u * (1.0 - v)),
                        (cc, u * v),
                        (d, (1.0 - u) * v),
                    ];
                    samples.push(x, &terms, stitches * share * per_sample);
                }
                continue;
            }
            // A fan from the centroid, each triangle its share of the face's stitches by area
            // (alike where the face has none), sampled at the centroids of an `n`-fold
            // subdivision.
            let corner_share = 1.0 / c.len() as f64;
            let centroid = c.iter().map(|p| x[p.index()]).sum::<Vec3>() * corner_share;
            let fan: Vec<(PointId, PointId, f64)> = (0..c.len())
                .map(|k| {
                    let (p, q) = (c[k], c[(k + 1) % c.len()]);
                    let (xp, xq) = (x[p.index()] - centroid, x[q.index()] - centroid);
                    (p, q, 0.5 * xp.cross(&xq).norm())
                })
                .collect();
            let area: f64 = fan.iter().map(|t| t.2).sum();
            for (p, q, triangle) in fan {
                let share = if area > 0.0 {
                    triangle / area
                } else {
                    corner_share
                };
                for (bp, bq) in sub_triangle_centroids(n) {
                    let mut terms: Vec<(PointId, f64)> = c
                        .iter()
                        .map(|&r| (r, (1.0 - bp - bq) * corner_share))
                        .collect();
                    terms.extend([(p, bp), (q, bq)]);
                    samples.push(x, &terms, stitches * share * per_sample);
                }
            }
        }
        samples
    }

    fn push(&mut self, x: &[Vec3], terms: &[(PointId, f64)], weight: f64) {
        self.positions
            .push(terms.iter().map(|&(p, w)| x[p.index()] * w).sum());
        self.weights.push(weight);
        self.terms.extend_from_slice(terms);
        self.starts.push(self.terms.len());
    }

    /// `values` (one per point) at every sample.
    fn interpolate<T>(&self, values: &[T]) -> Vec<T>
    where
        T: Copy + std::ops::Mul<f64, Output = T> + std::iter::Sum<T>,
    {
        self.starts
            .windows(2)
            .map(|span| {
                let terms = &self.terms[span[0]..span[1]];
                terms.iter().map(|&(p, w)| values[p.index()] * w).sum()
            })
            .collect()
    }

    /// Every field of `fields` (per point) at every sample.
    fn of_fields(&self, fields: &KnitFields) -> KnitFields {
        KnitFields {
            stitch_density: self.interpolate(&fields.stitch_density),
            stretch_course: self.interpolate(&fields.stretch_course),
            stretch_wale: self.interpolate(&fields.stretch_wale),
            coverage: self.interpolate(&fields.coverage),
            tension: self.interpolate(&fields.tension),
            pressure: self.interpolate(&fields.pressure),
            stress: self.interpolate(&fields.stress),
        }
    }
}

/// Barycentric weights `(b, c)` of the corners other than the first of the `n × n`
/// sub-triangles' centroids of a triangle divided `n` times along each side.
fn sub_triangle_centroids(n: usize) -> Vec<(f64, f64)> {
    let n_f = n as f64;
    let mut out = Vec::with_capacity(n * n);
    for i in 0..n {
        for j in 0..n - i {
            // The upright sub-triangle at (i, j), and the inverted one beside it.
            out.push(((i as f64 + 1.0 / 3.0) / n_f, (j as f64 + 1.0 / 3.0) / n_f));
            if i + j + 1 < n {
                out.push(((i as f64 + 2.0 / 3.0) / n_f, (j as f64 + 2.0 / 3.0) / n_f));
            }
        }
    }
    out
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

/// Fields on the fabric, where they are, and the kernel that carries them to the leg.
struct Carrier<'a> {
    /// The fields, one per point of `at`.
    fields: &'a KnitFields,
    /// The points.
    at: &'a [Vec3],
    /// The stitches each point stands for, in grid cells (`None`: one each).
    weights: Option<&'a [f64]>,
    /// The kernel's radius, metres.
    bandwidth: f64,
}

/// The biweight-kernel means of `fields` (one value per yarn point each) at `leg_vertices`,
/// over the yarn points within `bandwidth` metres, each weighted by `weights` where given (the
/// stitches a sample stands for); and per vertex whether any yarn point lay that near (0 where
/// none did). One vector per field, in order.
fn kernel_means(
    yarn_points: &[Vec3],
    weights: Option<&[f64]>,
    fields: &[&[f64]],
    leg_vertices: &[Point3<f64>],
    bandwidth: f64,
) -> (Vec<Vec<f64>>, Vec<bool>) {
    let grid = PointGrid::new(yarn_points.iter().copied(), bandwidth);
    let mut out = vec![Vec::with_capacity(leg_vertices.len()); fields.len()];
    let mut near = Vec::with_capacity(leg_vertices.len());
    let mut sums = vec![0.0; fields.len()];
    for v in leg_vertices {
        let mut weight_sum = 0.0;
        sums.iter_mut().for_each(|s| *s = 0.0);
        grid.for_each_within(&v.coords, bandwidth, |i| {
            let d2 = (yarn_points[i] - v.coords).norm_squared() / (bandwidth * bandwidth);
            if d2 < 1.0 {
                let w = (1.0 - d2) * (1.0 - d2) * weights.map_or(1.0, |weights| weights[i]);
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
        near.push(weight_sum > 0.0);
    }
    (out, near)
}

/// The fields carried over to leg vertices (0 where no yarn is near, and where `bare`): each
/// vertex takes them from the first of `carriers` with fabric within its kernel, pressure
/// apart: the stress is carried over, and pressed on the skin at each vertex (its curvature
/// there, not the yarn's, whatever the grid).
fn from_first_near(
    carriers: &[Carrier],
    leg_vertices: &[Point3<f64>],
    bare: &[bool],
    skin: &SkinCurvature,
) -> KnitFields {
    // The stress's six components, (0,0) (0,1) (0,2) (1,1) (1,2) (2,2).
    const UPPER: [(usize, usize); 6] = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)];
    let mut moved = vec![vec![0.0; leg_vertices.len()]; 5 + UPPER.len()];
    // Bare skin is taken as found already, so that no carrier gives it fields.
    let mut found = bare.to_vec();
    for carrier in carriers {
        let per_point = carrier.fields;
        let components: Vec<Vec<f64>> = UPPER
            .iter()
            .map(|&(r, c)| per_point.stress.iter().map(|s| s[(r, c)]).collect())
            .collect();
        let fields: Vec<&[f64]> = per_point
            .named()
            .iter()
            .take(5)
            .map(|(_, values)| *values)
            .chain(components.iter().map(|c| &c[..]))
            .collect();
        let (means, near) = kernel_means(
            carrier.at,
            carrier.weights,
            &fields,
            leg_vertices,
            carrier.bandwidth,
        );
        for (v, found) in found.iter_mut().enumerate() {
            if near[v] && !*found {
                *found = true;
                for (out, mean) in moved.iter_mut().zip(&means) {
                    out[v] = mean[v];
                }
            }
        }
    }
    let components = moved.split_off(5);
    let stress: Vec<Matrix3<f64>> = (0..leg_vertices.len())
        .map(|v| {
            let mut m = Matrix3::zeros();
            for (&(r, c), values) in UPPER.iter().zip(&components) {
                m[(r, c)] = values[v];
                m[(c, r)] = values[v];
            }
            m
        })
        .collect();
    let pressure = leg_vertices
        .par_iter()
        .zip(&stress)
        .map(|(v, stress)| pressed(skin, v, 0.0, stress))
        .collect();
    let [stitch_density, stretch_course, stretch_wale, coverage, tension] =
        moved.try_into().expect("five fields in, five out");
    KnitFields {
        stitch_density,
        stretch_course,
        stretch_wale,
        coverage,
        tension,
        pressure,
        stress,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::knit::{Pattern, Tile};
    use crate::post::fields::tests::{flat, pocket_knit, round_skin};

    /// Fields on a flat `spacing` grid 6 cm across: `density(x)` as the stitch density, the
    /// rest 1, no stress.
    fn flat_fields(spacing: f64, density: impl Fn(&Vec3) -> f64) -> (Knit, KnitFields) {
        let n = (0.06 / spacing).round() as usize + 1;
        let knit = flat(Pattern::Plain, n, spacing, 1.0, 1.0);
        let x = &knit.particles.x;
        let ones = vec![1.0; x.len()];
        let fields = KnitFields {
            stitch_density: x.iter().map(density).collect(),
            stretch_course: ones.clone(),
            stretch_wale: ones.clone(),
            coverage: ones.clone(),
            tension: ones.clone(),
            pressure: ones,
            stress: vec![Matrix3::zeros(); x.len()],
        };
        (knit, fields)
    }

    #[test]
    fn a_grids_samples_are_the_trapezoid_rules_lattice_over_it() {
        // A flat 4×4 grid of 6 mm cells sampled 3 times along each side: together its 9 cells'
        // samples are the 10 × 10 lattice at 2 mm (edges shared between cells add up), each
        // weighted by the trapezoid rule, a cell's worth in all.
        let knit = flat(Pattern::Plain, 4, 0.006, 1.0, 1.0);
        let samples = CellSamples::of(&knit, 3);
        let mut lattice = std::collections::BTreeMap::new();
        for (p, w) in samples.positions.iter().zip(&samples.weights) {
            let at = [p.x, p.y].map(|v| (v / 0.002).round() as i64);
            assert!((p.x - at[0] as f64 * 0.002).abs() < 1e-12, "{p}");
            assert!((p.y - at[1] as f64 * 0.002).abs() < 1e-12, "{p}");
            *lattice.entry(at).or_insert(0.0) += w;
        }
        assert_eq!(lattice.len(), 100);
        for ([i, j], w) in lattice {
            let edge = |k: i64| if k == 0 || k == 9 { 0.5 } else { 1.0 };
            let want = edge(i) * edge(j) / 9.0;
            assert!((w - want).abs() < 1e-12, "({i}, {j}): {w} against {want}");
        }
    }

    #[test]
    fn a_heel_pockets_faces_are_sampled_by_their_stitches() {
        // Its faces of five and more corners are fanned from their centroid, and every face's
        // samples share its stitches.
        let knit = pocket_knit(0.002, 0.001);
        let faces = knit.faces();
        assert!(faces.iter().any(|f| f.corners.len() > 4), "a fanned face");
        let stitches: f64 = faces.iter().map(|f| f.stitches.max(1.0)).sum();
        for n in 1..=4 {
            let samples = CellSamples::of(&knit, n);
            let total: f64 = samples.weights.iter().sum();
            assert!(
                (total - stitches).abs() < 1e-12,
                "{n}: {total} against {stitches}"
            );
            for span in samples.starts.windows(2) {
                let terms = &samples.terms[span[0]..span[1]];
                let sum: f64 = terms.iter().map(|t| t.1).sum();
                assert!((sum - 1.0).abs() < 1e-12 && terms.iter().all(|t| t.1 >= 0.0));
            }
            let finite = |p: &Vec3| p.iter().all(|v| v.is_finite());
            assert!(samples.positions.iter().all(finite));
        }
    }

    #[test]
    fn sub_triangles_centroids_are_inside_and_centred() {
        for n in 1..5 {
            let centroids = sub_triangle_centroids(n);
            assert_eq!(centroids.len(), n * n);
            assert!(centroids
                .iter()
                .all(|&(b, c)| b > 0.0 && c > 0.0 && b + c < 1.0));
            let mean_b = centroids.iter().map(|c| c.0).sum::<f64>() / (n * n) as f64;
            assert!((mean_b - 1.0 / 3.0).abs() < 1e-12, "{n}: {mean_b}");
        }
    }

    #[test]
    fn a_coarse_and_a_fine_grid_hand_the_leg_the_same_kernels_mean() {
        // A curved field (x² across 6 cm of flat fabric) on 1 mm and 8 mm grids: each leg vertex
        // takes the mean of the same 16 mm kernel over it, so they agree but for the coarse
        // grid's linear interpolation; a kernel three coarse spacings wide (24 mm), as the
        // coarse grid's points alone would need, blurs it twice as much.
        assert_eq!((samples_per_side(0.001), samples_per_side(0.008)), (1, 2));
        let field = |p: &Vec3| 1e4 * p.x * p.x;
        let leg: Vec<Point3<f64>> = (0..5)
            .map(|k| Point3::new(0.022 + 0.004 * k as f64, 0.03, 0.001))
            .collect();
        let surface = round_skin(0.04);
        let skin = SkinCurvature::of(&surface, MEASURE_SPAN_M);
        let on_leg = |spacing: f64| {
            let (knit, fields) = flat_fields(spacing, field);
            carry_to_leg(&knit, &fields, &leg, &skin, &[]).stitch_density
        };
        let (fine, coarse) = (on_leg(0.001), on_leg(0.008));
        let points_alone = {
            let (knit, fields) = flat_fields(0.008, field);
            let values = &fields.stitch_density;
            kernel_means(&knit.particles.x, None, &[values], &leg, 0.024)
                .0
                .remove(0)
        };
        for (k, (f, c)) in fine.iter().zip(&coarse).enumerate() {
            let exact = field(&leg[k].coords);
            // The wider kernel adds 1e4 (24² − 16²) mm² / 8 = 0.4; the coarse grid's linear
            // interpolation adds a quarter of that.
            assert!((c - f).abs() < 0.15, "vertex {k}: fine {f}, coarse {c}");
            let wide = points_alone[k];
            assert!(wide - f > 0.3, "vertex {k}: fine {f}, wide {wide}");
            // The kernel's own blur, what every grid adds alike: the biweight's variance along
            // x over a disc, R²/8, times the field's 1e4.
            let blur = 1e4 * TRANSFER_BANDWIDTH_M.powi(2) / 8.0;
            assert!(
                (f - exact - blur).abs() < 0.1 * blur,
                "vertex {k}: {f} against {exact}"
            );
        }
    }

    #[test]
    fn skin_beyond_an_open_end_is_bare_however_near_its_yarn() {
        // Flat fabric of density 5 over x from 0 to 6 cm, its end across x = 3 cm: skin 1 mm
        // under the fabric takes 5 on the fabric's side and nothing past the end.
        let (knit, fields) = flat_fields(0.001, |_| 5.0);
        let surface = round_skin(0.04);
        let skin = SkinCurvature::of(&surface, MEASURE_SPAN_M);
        let end = OpenEnd {
            centre: Point3::new(0.03, 0.03, 0.0),
            inward: Vec3::x(),
        };
        let leg = [0.031, 0.029].map(|x| Point3::new(x, 0.03, 0.001));
        let carried = |ends: &[OpenEnd]| carry_to_leg(&knit, &fields, &leg, &skin, ends);
        let cut = carried(&[end]);
        assert!((cut.stitch_density[0] - 5.0).abs() < 1e-12, "{cut:?}");
        // Every field is 0 past the end, which without it takes the fabric's.
        assert!(cut.named().iter().all(|(_, values)| values[1] == 0.0));
        assert!((carried(&[]).stitch_density[1] - 5.0).abs() < 1e-12);
    }

    #[test]
    fn a_tubes_open_ends_are_its_first_ring_and_its_last_unless_a_seam_closes_it() {
        // A tube along +y, rings 1 cm apart from y = 0.
        let tube = Knit::grid(8, 5, true, &Tile::of(Pattern::Plain), 0.01, 0.01, |w, c| {
            let t = std::f64::consts::TAU * w as f64 / 8.0;
            Vec3::new(0.02 * t.cos(), 0.01 * c as f64, 0.02 * t.sin())
        });
        let ends = OpenEnd::of_tube(&tube);
        assert_eq!(ends.len(), 2);
        assert!((ends[0].centre - Point3::origin()).norm() < 1e-12);
        assert!((ends[0].inward - Vec3::y()).norm() < 1e-12);
        assert!((ends[1].centre - Point3::new(0.0, 0.04, 0.0)).norm() < 1e-12);
        assert!((ends[1].inward + Vec3::y()).norm() < 1e-12);
        assert!(ends[0].beyond(&Point3::new(0.02, -0.001, 0.0)));
        assert!(!ends[0].beyond(&Point3::new(0.02, 0.001, 0.0)));
        let closed = tube.with_toe_seam(0.01);
        assert_eq!(OpenEnd::of_tube(&closed), ends[..1]);
    }

    #[test]
    fn skin_the_fabric_hangs_further_off_takes_the_grids_points() {
        // An 8 mm grid of density 5: skin 2 cm under it has no sample within 16 mm, but the
        // grid's points within three spacings (24 mm) reach it; skin 3 cm under, nothing.
        let (knit, fields) = flat_fields(0.008, |_| 5.0);
        let surface = round_skin(0.04);
        let skin = SkinCurvature::of(&surface, MEASURE_SPAN_M);
        let leg = [0.0, -0.02, -0.03].map(|z| Point3::new(0.03, 0.03, z));
        let density = carry_to_leg(&knit, &fields, &leg, &skin, &[]).stitch_density;
        assert!((density[0] - 5.0).abs() < 1e-12 && (density[1] - 5.0).abs() < 1e-12);
        assert_eq!(density[2], 0.0);
    }

    #[test]
    fn transfer_is_zero_far_from_yarn_and_exact_for_a_constant_field() {
        let points = vec![Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.001, 0.0, 0.0)];
        let values = vec![7.0, 7.0];
        let leg = vec![Point3::new(0.0005, 0.0, 0.0), Point3::new(1.0, 0.0, 0.0)];
        let (out, near) = kernel_means(&points, None, &[&values], &leg, 0.002);
        assert_eq!(near, [true, false]);
        assert!((out[0][0] - 7.0).abs() < 1e-12);
        assert_eq!(out[0][1], 0.0);
    }
}
