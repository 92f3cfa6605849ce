//! The flat patch of the paper's §5 experiment (Fig. 8/9): a `wales × courses` knit in the XY
//! plane (x along the course, y along the wale, centred on the origin), with two opposite edges
//! held and pulled apart.
//!
//! The patch starts at its rest shape; only the held edges are moved, by `factor` about the
//! centre. Relaxation then lets the free points follow.

use super::{Knit, Pattern, Tile};
use crate::base::{GridSize, Vec3};
use crate::knit::{Stretch, StretchAxis};

/// Size, pattern and rest spacing of a flat patch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PatchSpec {
    /// Points along a course (wales) by points along a wale (courses).
    pub grid: GridSize,
    /// Knit pattern (yarn kinds of the springs).
    pub pattern: Pattern,
    /// Rest length of course springs, metres.
    pub course_spacing_m: f64,
    /// Rest length of wale springs, metres.
    pub wale_spacing_m: f64,
}

/// Builds the patch at rest, then pins the two edges that `stretch` pulls and moves them apart.
pub fn build_patch(spec: &PatchSpec, stretch: Stretch) -> Knit {
    let (lc, lw) = (spec.course_spacing_m, spec.wale_spacing_m);
    let GridSize { wales, courses } = spec.grid;
    let cx = (wales as f64 - 1.0) / 2.0;
    let cy = (courses as f64 - 1.0) / 2.0;
    let mut knit = Knit::grid(
        wales,
        courses,
        false,
        &Tile::of(spec.pattern),
        lc,
        lw,
        |w, c| Vec3::new((w as f64 - cx) * lc, (c as f64 - cy) * lw, 0.0),
    );
    let held: Vec<_> = match stretch.axis {
        StretchAxis::Course => (0..courses)
            .flat_map(|c| [knit.point(0, c), knit.point(wales - 1, c)])
            .collect(),
        StretchAxis::Wale => (0..wales)
            .flat_map(|w| [knit.point(w, 0), knit.point(w, courses - 1)])
            .collect(),
    };
    for p in held {
        knit.pin(p);
        let x = &mut knit.particles.x[p.index()];
        match stretch.axis {
            StretchAxis::Course => x.x *= stretch.factor,
            StretchAxis::Wale => x.y *= stretch.factor,
        }
    }
    knit
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn held_edges_are_pinned_and_pulled() {
        let spec = PatchSpec {
            grid: GridSize::new(5, 4),
            pattern: Pattern::Plain,
            course_spacing_m: 0.001,
            wale_spacing_m: 0.002,
        };
        let knit = build_patch(
            &spec,
            Stretch {
                axis: StretchAxis::Course,
                factor: 2.0,
            },
        );
        let left = knit.point(0, 1);
        let right = knit.point(4, 1);
        assert!(!knit.is_free(left) && !knit.is_free(right));
        assert!(knit.is_free(knit.point(2, 0)), "free edges stay free");
        let width = knit.particles.x[right.index()].x - knit.particles.x[left.index()].x;
        assert!((width - 2.0 * 4.0 * 0.001).abs() < 1e-15);
    }
}
