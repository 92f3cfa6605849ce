//! The real stocking a fit stands for: its needles, its relaxed stitch, its yarns' diameters and
//! the stiffness of one knitted loop. The simulation grid is a numerical choice; this is what
//! turns its cells back into stitches, so every output is in physical units at any grid size.
//!
//! * **Stitches per cell.** A grid cell of rest size `l_c × l_w` (the tube's relaxed
//!   circumference over its wales, its relaxed length over its courses) stands for
//!   `l_c / a` real stitches around and `l_w / b` along, `a × b` being the relaxed stitch
//!   (`knit.course_spacing_m`, `knit.wale_spacing_m`). The grid's springs are homogenized so that
//!   it is the stitch's membrane at any size ([`crate::knit::Knit::with_stitch_shape`]), so the
//!   fitted shape, and with it every field, converges as the grid is refined.
//! * **Yarn diameter** of each yarn, from its denier as a solid nylon filament bundle
//!   ([`Yarn::diameter_m`](super::Yarn::diameter_m), [`super::nylon`]).
//! * **Loop stiffness.** A knitted loop stretches by bending its legs, not by stretching its yarn
//!   (the elastica loop of Postle & Munden, J. Textile Inst. 58, 1967); we take each leg as a
//!   cantilever one course long, so one nylon stitch resists `k = 3 E I / b³` newtons per metre
//!   of extension, `I = π d⁴ / 64`, `E` = [`NYLON_MODULUS_PA`]. This is an order-of-magnitude
//!   model (the paper's springs have no units): it puts a 20-den stocking's pressure in the few
//!   mmHg that sheer hosiery is measured at. A yarn's `stiffness` scales it (the support yarn's
//!   10, the paper's c1 ratio).
//! * **Membrane tension.** Around the leg, one stitch's loop spans `a` and a metre of fabric
//!   along the leg holds `1 / b` courses, so a course strain `ε` pulls with `c̄1 · k · (a / b) · ε`
//!   newtons per metre of relaxed fabric (`c̄1` the mean stiffness of the course yarns), divided
//!   by the wale stretch per metre of fitted fabric; along the leg, `a` and `b` trade places.

use crate::base::{GridSize, PerDirection, PerYarn, YarnKind};

use super::nylon::NYLON_MODULUS_PA;
use super::settings::{KnitSettings, TubeSettings, Yarns};

/// Pascals per millimetre of mercury, the unit hosiery pressure is quoted in.
pub const PA_PER_MMHG: f64 = 133.322;

/// The real stocking: stitch, yarns, loop stiffness (see module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fabric {
    /// Real stitches (wales) around the stocking: the machine's needles.
    pub needles: f64,
    /// The relaxed stitch: distance between wales along a course, and between courses along a
    /// wale, metres.
    pub stitch_m: PerDirection,
    /// Diameter of each yarn kind, metres, in [`YarnKind::index`] order.
    pub yarn_diameter_m: PerYarn<f64>,
    /// Stiffness of one nylon stitch (a yarn `stiffness` of 1), newtons per metre of extension.
    pub loop_stiffness_n_per_m: f64,
}

impl Fabric {
    /// The stocking the scene describes. Its stitches around are `knit.needles`, or where
    /// `tube.relaxed_circumference_m` is given, that circumference over the stitch's width.
    pub fn of(knit: &KnitSettings, yarns: &Yarns, tube: &TubeSettings) -> Fabric {
        let [course, wale] = [knit.course_spacing_m, knit.wale_spacing_m];
        let needles = match tube.relaxed_circumference_m {
            Some(c) => c / course,
            None => knit.needles as f64,
        };
        let d = yarns.nylon.diameter_m();
        let second_moment = std::f64::consts::PI * d.powi(4) / 64.0;
        Fabric {
            needles,
            stitch_m: PerDirection::new(course, wale),
            yarn_diameter_m: YarnKind::ALL.map(|k| yarns.get(k).diameter_m()),
            loop_stiffness_n_per_m: 3.0 * NYLON_MODULUS_PA * second_moment / wale.powi(3),
        }
    }

    /// Circumference of the stocking lying relaxed: the needles times the course spacing, metres.
    pub fn relaxed_circumference_m(&self) -> f64 {
        self.needles * self.stitch_m.course
    }

    /// The real stitch count of a stocking `relaxed_length_m` long: its wales around (the
    /// needles, at least 3) and its courses (one per relaxed wale spacing, both ends included).
    pub fn real_count(&self, relaxed_length_m: f64) -> GridSize {
        // `as usize` saturates, and the `+ 1` must too: a stitch of 1e-300 m would wrap to 0
        // courses. The caller refuses a count over the 32-bit bound.
        let courses = ((relaxed_length_m / self.stitch_m.wale).round() as usize).saturating_add(1);
        GridSize::new((self.needles.round() as usize).max(3), courses.max(2))
    }

    /// Courses of a grid of `wales` around on a stocking `relaxed_length_m` long when the scene
    /// leaves `tube.courses` out: as many as make each cell the same number of real stitches
    /// along as around (the real count's courses scaled by `wales / needles`), so the cell is a
    /// block of real stitches and has the stitch's shape. A grid of N×N points on a stocking to the
    /// toe has cells 1.75–2× as many stitches long as wide, and its courses, not its wales, decide
    /// the fit over the toes (docs/decisions/0069). At least 2; at the needles, the real count.
    pub fn grid_courses(&self, wales: usize, relaxed_length_m: f64) -> usize {
        let GridSize {
            wales: real_wales,
            courses: real_courses,
        } = self.real_count(relaxed_length_m);
        let intervals = (real_courses - 1) as f64 * wales as f64 / real_wales as f64;
        // `as usize` saturates; the caller checks the grid's size.
        (intervals.round() as usize).saturating_add(1).max(2)
    }

    /// Real stitches a grid cell of rest size `rest_m` (course spring, wale spring) stands for,
    /// around and along.
    pub fn stitches_per_cell(&self, rest_m: PerDirection) -> PerDirection {
        PerDirection::new(
            rest_m.course / self.stitch_m.course,
            rest_m.wale / self.stitch_m.wale,
        )
    }

    /// Real stitches per square metre of relaxed fabric.
    pub fn relaxed_stitches_per_m2(&self) -> f64 {
        1.0 / (self.stitch_m.course * self.stitch_m.wale)
    }

    /// Tension per metre of relaxed fabric per unit strain of a yarn stiffness of 1, along the
    /// course and along the wale, N/m.
    pub fn membrane_n_per_m(&self) -> PerDirection {
        let PerDirection { course: a, wale: b } = self.stitch_m;
        let k = self.loop_stiffness_n_per_m;
        PerDirection::new(k * a / b, k * b / a)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cell_of_the_real_stitch_is_one_stitch_and_a_coarser_one_more() {
        let fabric = Fabric::of(
            &KnitSettings::default(),
            &Yarns::default(),
            &TubeSettings::default(),
        );
        assert_eq!(
            fabric.stitches_per_cell(fabric.stitch_m),
            PerDirection::new(1.0, 1.0)
        );
        let PerDirection {
            course: around,
            wale: along,
        } = fabric.stitches_per_cell(PerDirection::new(
            fabric.relaxed_circumference_m() / 150.0,
            0.006,
        ));
        assert!((around - 400.0 / 150.0).abs() < 1e-12);
        assert!((along - 0.006 / 0.00074).abs() < 1e-12);
    }

    #[test]
    fn courses_left_out_make_cells_of_as_many_stitches_along_as_around() {
        let fabric = Fabric::of(
            &KnitSettings::default(),
            &Yarns::default(),
            &TubeSettings::default(),
        );
        // 0.5187 m of relaxed stocking is 701 real courses of 0.74 mm (700 intervals).
        let length = 700.0 * 0.00074;
        assert_eq!(fabric.real_count(length), GridSize::new(400, 701));
        assert_eq!(
            fabric.grid_courses(400, length),
            701,
            "at the needles, the real count"
        );
        assert_eq!(fabric.grid_courses(150, length), 264);
        assert_eq!(fabric.grid_courses(100, length), 176);
        let rest = |courses: usize| {
            let wales = 150.0;
            PerDirection::new(
                fabric.relaxed_circumference_m() / wales,
                length / (courses - 1) as f64,
            )
        };
        let PerDirection {
            course: around,
            wale: along,
        } = fabric.stitches_per_cell(rest(fabric.grid_courses(150, length)));
        assert!(
            (along / around - 1.0).abs() < 0.01,
            "{around} × {along} stitches"
        );
        assert_eq!(
            fabric.grid_courses(3, 0.001),
            2,
            "never fewer than the two end rings"
        );
    }

    #[test]
    fn a_given_circumference_sets_the_stitches_around() {
        let tube = TubeSettings {
            relaxed_circumference_m: Some(0.16),
            ..TubeSettings::default()
        };
        let fabric = Fabric::of(&KnitSettings::default(), &Yarns::default(), &tube);
        assert_eq!(fabric.stitch_m, PerDirection::new(0.0005, 0.00074));
        assert!((fabric.needles - 320.0).abs() < 1e-9);
        assert!((fabric.relaxed_circumference_m() - 0.16).abs() < 1e-12);
    }
}
