//! Vectors and frames: the 3-vector every stage computes with, the frame across an axis that
//! the leg's cross-sections and the tube's rings are laid out in, and the stance a character
//! stands in, which the pictures are seen from.

use nalgebra::Vector3;

/// 3-vector of `f64`, in metres unless a name says otherwise.
pub type Vec3 = Vector3<f64>;

/// Two unit vectors perpendicular to `a` and to each other, with `u × v = a`.
pub fn perpendicular_frame(a: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let helper = if a.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let u = a.cross(&helper).normalize();
    let v = a.cross(&u);
    (u, v)
}

/// An up within this of +Y is pictured as +Y, degrees (see [`Stance::pictured`]): a leg alone
/// leans 10–15° along its own axis, thighs converging to the knees.
pub const UP_SNAP_DEG: f64 = 20.0;
/// A facing within this of +Z is pictured as +Z, degrees: a foot's toe-out is 5–15°.
pub const FACING_SNAP_DEG: f64 = 20.0;

/// How a character stands in world space: unit `up`, and `facing` where it faces, square to
/// each other. Pictures take their front and side views from it; glTF's convention (+Y up,
/// facing +Z) by default.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stance {
    /// Up the body.
    pub up: Vec3,
    /// Where the character faces.
    pub facing: Vec3,
}

impl Default for Stance {
    fn default() -> Self {
        Stance {
            up: Vec3::y(),
            facing: Vec3::z(),
        }
    }
}

impl Stance {
    /// The stance with `up` and `facing` made unit and square (`facing`'s part along `up`
    /// removed); the default where `up` is degenerate or not finite, [`Stance::upright`] where
    /// `facing` is.
    pub fn new(up: Vec3, facing: Vec3) -> Stance {
        let unit = |v: Vec3| {
            v.try_normalize(1e-12)
                .filter(|v| v.iter().all(|c| c.is_finite()))
        };
        let Some(up) = unit(up) else {
            return Stance::default();
        };
        match unit(facing - up * up.dot(&facing)) {
            Some(facing) => Stance { up, facing },
            None => Stance::upright(up),
        }
    }

    /// Standing along `up`, facing glTF's +Z as far as that is square to `up` (+X where `up` is
    /// along Z).
    pub fn upright(up: Vec3) -> Stance {
        let up = up.try_normalize(1e-12).unwrap_or_else(Vec3::y);
        Stance::new(
            up,
            if up.z.abs() < 0.99 {
                Vec3::z()
            } else {
                Vec3::x()
            },
        )
    }

    /// The stance a character standing along `up`, facing `facing`, is pictured in: glTF's
    /// wherever it roughly keeps that convention (up within [`UP_SNAP_DEG`] of +Y, then facing
    /// within [`FACING_SNAP_DEG`] of +Z), so that a file that keeps it is seen along its axes,
    /// its body's lean and its feet's toe-out not taken for a turn; its own where it does not
    /// (a character turned in its file, or tilted from the file axis nearest its up).
    pub fn pictured(up: Vec3, facing: Vec3) -> Stance {
        let near = |a: &Vec3, b: &Vec3, degrees: f64| {
            a.try_normalize(1e-12)
                .is_some_and(|a| a.dot(b) >= degrees.to_radians().cos())
        };
        let up = if near(&up, &Vec3::y(), UP_SNAP_DEG) {
            Vec3::y()
        } else {
            up
        };
        let stance = Stance::new(up, facing);
        let upright = Stance::upright(stance.up);
        if near(&stance.facing, &upright.facing, FACING_SNAP_DEG) {
            upright
        } else {
            stance
        }
    }

    /// The character's left: `up × facing`.
    pub fn left(&self) -> Vec3 {
        self.up.cross(&self.facing)
    }

    /// `p`'s coordinates along the character's left, up and facing.
    pub fn coordinates(&self, p: [f64; 3]) -> [f64; 3] {
        [self.left(), self.up, self.facing].map(|a| a.x * p[0] + a.y * p[1] + a.z * p[2])
    }

    /// The world point with coordinates `c` along the character's left, up and facing.
    pub fn world(&self, c: [f64; 3]) -> [f64; 3] {
        (self.left() * c[0] + self.up * c[1] + self.facing * c[2]).into()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Rotation3;

    fn about(axis: &nalgebra::Unit<Vec3>, degrees: f64) -> Rotation3<f64> {
        Rotation3::from_axis_angle(axis, degrees.to_radians())
    }

    #[test]
    fn a_file_keeping_gltfs_convention_is_pictured_along_its_axes_a_turned_one_as_it_stands() {
        // Leaning 14° (as a leg alone does) and toed out 15°: glTF's stance.
        let lean = about(&Vec3::x_axis(), 14.0) * Vec3::y();
        let toe_out = about(&Vec3::y_axis(), 15.0) * Vec3::z();
        assert_eq!(Stance::pictured(lean, toe_out), Stance::default());
        // Turned 40° about up: as it stands.
        let turned = about(&Vec3::y_axis(), 40.0) * Vec3::z();
        let stance = Stance::pictured(Vec3::y(), turned);
        assert_eq!(stance.up, Vec3::y());
        assert!((stance.facing - turned).norm() < 1e-12, "{stance:?}");
        // Lying along +Z, face down: as it lies, its left along +X.
        let lying = Stance::pictured(Vec3::z(), -Vec3::y());
        assert_eq!((lying.up, lying.facing), (Vec3::z(), -Vec3::y()));
        assert!((lying.left() - Vec3::x()).norm() < 1e-12);
        // Nothing to go by: glTF's.
        assert_eq!(
            Stance::pictured(Vec3::zeros(), Vec3::z()),
            Stance::default()
        );
        assert_eq!(Stance::new(Vec3::y(), Vec3::y()), Stance::default());
        // Coordinates along left, up and facing, and back: exact in glTF's stance.
        let p = [0.1234, -0.8, 0.333];
        assert_eq!(Stance::default().coordinates(p), p);
        assert_eq!(Stance::default().world(p), p);
        let c = stance.coordinates(p);
        let back = Vec3::from(stance.world(c));
        assert!((back - Vec3::from(p)).norm() < 1e-12, "{back}");
        assert!((c[2] - Vec3::from(p).dot(&turned)).abs() < 1e-12);
        assert_eq!(
            Stance::new(Vec3::z(), Vec3::z()),
            Stance::upright(Vec3::z())
        );
        assert_eq!(
            Stance::new(Vec3::y(), Vec3::new(f64::NAN, 0.0, 1.0)),
            Stance::default()
        );
        assert_eq!(
            Stance::new(Vec3::repeat(f64::INFINITY), Vec3::z()),
            Stance::default()
        );
    }
}
