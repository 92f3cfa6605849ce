//! The size of a knit's grid: points around (wales) by rings along (courses). One type for every
//! grid a fit names: the tube asked for, the multilevel solver's levels, the real stitch count,
//! what the memory estimate counts. In files and messages it reads as `W×C`; in JSON as
//! `[wales, courses]`.

use std::fmt;

use serde::{Deserialize, Serialize};

/// A grid of `wales` points around (or across, on a flat patch) by `courses` rings along.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(from = "[usize; 2]", into = "[usize; 2]")]
pub struct GridSize {
    /// Points around: the wales (a tube's, the machine's needles for the real count).
    pub wales: usize,
    /// Rings along: the courses.
    pub courses: usize,
}

impl GridSize {
    /// `wales` by `courses`.
    pub const fn new(wales: usize, courses: usize) -> GridSize {
        GridSize { wales, courses }
    }

    /// Its points, `wales × courses`; saturates rather than wrapping, so an absurd size reads
    /// as more than any bound.
    pub fn points(self) -> usize {
        self.wales.saturating_mul(self.courses)
    }
}

impl From<[usize; 2]> for GridSize {
    fn from([wales, courses]: [usize; 2]) -> GridSize {
        GridSize { wales, courses }
    }
}

impl From<GridSize> for [usize; 2] {
    fn from(grid: GridSize) -> [usize; 2] {
        [grid.wales, grid.courses]
    }
}

impl fmt::Display for GridSize {
    /// `150×264`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}×{}", self.wales, self.courses)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_grid_reads_as_wales_by_courses_and_saturates_its_points() {
        let grid = GridSize::new(150, 264);
        assert_eq!(grid.to_string(), "150×264");
        assert_eq!(grid.points(), 39_600);
        assert_eq!(serde_json::to_string(&grid).unwrap(), "[150,264]");
        let back: GridSize = serde_json::from_str("[150,264]").unwrap();
        assert_eq!(back, grid);
        assert_eq!(GridSize::new(usize::MAX, 2).points(), usize::MAX);
    }
}
