//! Points near a point: a uniform grid over a point set, for the radius queries of the fields'
//! transfer to the leg and the skin's curvature fits.

use std::collections::HashMap;

use super::Vec3;

/// A uniform grid over points, cell size about the usual query radius: a query of that radius
/// visits 27 cells. Non-finite or astronomically far points are left out (never near anything).
pub struct PointGrid {
    cell: f64,
    cells: HashMap<[i64; 3], Vec<u32>>,
}

impl PointGrid {
    /// The grid over `points` (indices must fit `u32`, as every mesh's here do) with cells
    /// `cell` metres wide.
    pub fn new(points: impl IntoIterator<Item = Vec3>, cell: f64) -> PointGrid {
        let mut cells: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
        for (i, p) in points.into_iter().enumerate() {
            if let Some(key) = Self::key(&p, cell) {
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

    /// Calls `f` with every point in the cells within `radius` of `p` (a superset of the points
    /// within `radius`: the caller measures), in a fixed order.
    pub fn for_each_within(&self, p: &Vec3, radius: f64, mut f: impl FnMut(usize)) {
        let Some([x, y, z]) = Self::key(p, self.cell) else {
            return;
        };
        // At most a few cells either way: the callers' radii are small multiples of the cell.
        let reach = (radius / self.cell).ceil().clamp(1.0, 8.0) as i64;
        for dx in -reach..=reach {
            for dy in -reach..=reach {
                for dz in -reach..=reach {
                    if let Some(list) = self.cells.get(&[x + dx, y + dy, z + dz]) {
                        list.iter().for_each(|&i| f(i as usize));
                    }
                }
            }
        }
    }
}
