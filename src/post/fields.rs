//! Per-point fields of a fitted knit, and their transfer to the leg's vertices.
//!
//! * **Stitch density** at a yarn point is one stitch over the mean area of the (up to four)
//!   stitches around it, in stitches per cm². A stitch is a grid cell; its area is half the norm
//!   of the cross product of its diagonals (exact for a planar quad).
//! * **Tension** at a yarn point is the mean signed force `c1 (|x_b − x_a| − l)` of its springs
//!   (positive in tension), in the solver's force units (unit mass, per time unit squared, metres).
//! * **On the leg**, a vertex takes the kernel-weighted mean of the yarn points within a bandwidth
//!   (a biweight kernel, compactly supported, so far-away yarn has no say): smooth where the fit is
//!   smooth, and 0 where no yarn is near (uncovered skin).

use std::collections::HashMap;

use nalgebra::Point3;

use crate::knit::{Knit, PointId, Vec3};
use crate::sim::ForceTerms;

/// Square metres per square centimetre.
const M2_PER_CM2: f64 = 1e-4;

/// Stitches per cm² at every yarn point of a grid knit.
pub fn stitch_density(knit: &Knit) -> Vec<f64> {
    let (wales, courses) = (knit.wales, knit.courses);
    let x = &knit.particles.x;
    let cells_across = if knit.closed_courses {
        wales
    } else {
        wales - 1
    };
    let cell_area = |w: usize, c: usize| {
        let at = |w: usize, c: usize| x[knit.point(w % wales, c).index()];
        let diagonal_a = at(w + 1, c + 1) - at(w, c);
        let diagonal_b = at(w, c + 1) - at(w + 1, c);
        diagonal_a.cross(&diagonal_b).norm() / 2.0
    };
    let mut area_sum = vec![0.0; knit.len()];
    let mut area_count = vec![0u32; knit.len()];
    for c in 0..courses.saturating_sub(1) {
        for w in 0..cells_across {
            let area = cell_area(w, c);
            for (dw, dc) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                let p = knit.point((w + dw) % wales, c + dc).index();
                area_sum[p] += area;
                area_count[p] += 1;
            }
        }
    }
    area_sum
        .iter()
        .zip(&area_count)
        .map(|(&sum, &n)| {
            let mean = sum / n.max(1) as f64;
            if n > 0 && mean > 0.0 {
                M2_PER_CM2 / mean
            } else {
                0.0
            }
        })
        .collect()
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
                    let c1 = terms.stiffness[s.yarn.index() as usize];
                    c1 * ((x[s.b.index()] - x[s.a.index()]).norm() - s.rest)
                })
                .sum();
            sum / incident.len().max(1) as f64
        })
        .collect()
}

/// Transfers a per-yarn-point field to leg vertices with a biweight kernel of radius
/// `bandwidth` metres; vertices with no yarn point within the bandwidth get 0.
pub fn transfer_to_leg(
    yarn_points: &[Vec3],
    values: &[f64],
    leg_vertices: &[Point3<f64>],
    bandwidth: f64,
) -> Vec<f64> {
    let grid = PointGrid::new(yarn_points, bandwidth);
    leg_vertices
        .iter()
        .map(|v| {
            let (mut weight_sum, mut value_sum) = (0.0, 0.0);
            grid.for_each_near(&v.coords, |i| {
                let d2 = (yarn_points[i] - v.coords).norm_squared() / (bandwidth * bandwidth);
                if d2 < 1.0 {
                    let w = (1.0 - d2) * (1.0 - d2);
                    weight_sum += w;
                    value_sum += w * values[i];
                }
            });
            if weight_sum > 0.0 {
                value_sum / weight_sum
            } else {
                0.0
            }
        })
        .collect()
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
    fn transfer_is_zero_far_from_yarn_and_exact_for_a_constant_field() {
        let points = vec![Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.001, 0.0, 0.0)];
        let values = vec![7.0, 7.0];
        let leg = vec![Point3::new(0.0005, 0.0, 0.0), Point3::new(1.0, 0.0, 0.0)];
        let out = transfer_to_leg(&points, &values, &leg, 0.002);
        assert!((out[0] - 7.0).abs() < 1e-12);
        assert_eq!(out[1], 0.0);
    }
}
