//! The preview's pinhole camera: a perspective camera given by the scene, or auto-framed so the
//! stocking's bounding box (its yarn's; the leg's for a leg without yarn) fills the picture from one
//! of four sides.
//!
//! Framing: the eight corners of the box are expressed in the view's frame (right, up, towards
//! the viewer); the eye is put on the view axis through the box's centre, back far enough that
//! every corner lies inside the field of view with [`MARGIN`] to spare. The fixed vertical field
//! of view keeps perspective mild, as a portrait lens would.

use nalgebra::{Point3, Vector3};

use crate::base::Stance;
use crate::preview::{CameraSettings, View};

/// Vertical field of view of the auto-framed camera, degrees.
pub const AUTO_FOV_DEG: f64 = 25.0;
/// Border left around the framed box, as a fraction of the half-extent.
pub const MARGIN: f64 = 0.06;

/// A pinhole camera: world-space eye and orthonormal frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    /// Eye position, metres.
    pub eye: Point3<f64>,
    /// Unit vector the camera looks along.
    pub forward: Vector3<f64>,
    /// Unit vector to the image's right.
    pub right: Vector3<f64>,
    /// Unit vector to the image's top.
    pub up: Vector3<f64>,
    /// tan(vertical field of view / 2).
    pub tan_half_fov: f64,
    /// Image width over height.
    pub aspect: f64,
}

impl Camera {
    /// A camera at `eye` looking at `target`, +Y roughly up (or +Z when looking along Y).
    pub fn look_at(eye: Point3<f64>, target: Point3<f64>, fov_deg: f64, aspect: f64) -> Camera {
        let forward = (target - eye).normalize();
        let world_up = if forward.y.abs() > 0.99 {
            Vector3::z()
        } else {
            Vector3::y()
        };
        Camera::looking(eye, target, world_up, fov_deg, aspect)
    }

    /// A camera at `eye` looking at `target`, `world_up` roughly up (not along the view).
    fn looking(
        eye: Point3<f64>,
        target: Point3<f64>,
        world_up: Vector3<f64>,
        fov_deg: f64,
        aspect: f64,
    ) -> Camera {
        let forward = (target - eye).normalize();
        let right = forward.cross(&world_up).normalize();
        let up = right.cross(&forward);
        Camera {
            eye,
            forward,
            right,
            up,
            tan_half_fov: (fov_deg.to_radians() / 2.0).tan(),
            aspect,
        }
    }

    /// The scene's camera.
    pub fn from_settings(settings: &CameraSettings, aspect: f64) -> Camera {
        Camera::look_at(
            Point3::from(settings.position),
            Point3::from(settings.target),
            settings.fov_deg,
            aspect,
        )
    }

    /// The camera that frames the box `lo..hi` (metres, along the character's left, up and
    /// facing: [`Stance::coordinates`]) seen from `view` of a character standing in `stance`:
    /// its front, its left side, its back, or between front and left.
    pub fn framing(lo: [f64; 3], hi: [f64; 3], view: View, stance: &Stance, aspect: f64) -> Camera {
        let s = std::f64::consts::FRAC_1_SQRT_2;
        let (facing, left) = (stance.facing, stance.left());
        let toward_viewer = match view {
            View::Front => facing,
            View::Side => left,
            View::Back => -facing,
            View::ThreeQuarter => (facing + left) * s,
        };
        let centre = Point3::from(stance.world(std::array::from_fn(|k| (lo[k] + hi[k]) / 2.0)));
        let cam = Camera::looking(
            centre + toward_viewer,
            centre,
            stance.up,
            AUTO_FOV_DEG,
            aspect,
        );
        let tan_y = cam.tan_half_fov;
        let tan_x = tan_y * aspect;
        // For each corner: the eye distance from the centre at which it just fits.
        let mut distance: f64 = 1e-6;
        for corner in 0..8 {
            let d = Point3::from(stance.world(box_corner(lo, hi, corner))) - centre;
            let (x, y, z) = (d.dot(&cam.right), d.dot(&cam.up), d.dot(&toward_viewer));
            let need_x = x.abs() * (1.0 + MARGIN) / tan_x + z;
            let need_y = y.abs() * (1.0 + MARGIN) / tan_y + z;
            distance = distance.max(need_x).max(need_y);
        }
        if !distance.is_finite() {
            distance = 1.0;
        }
        Camera {
            eye: centre + toward_viewer * distance,
            ..cam
        }
    }

    /// The unit ray direction through image position (`u`, `v`), both 0–1 from the top-left
    /// corner.
    pub fn direction(&self, u: f64, v: f64) -> Vector3<f64> {
        let x = (2.0 * u - 1.0) * self.tan_half_fov * self.aspect;
        let y = (1.0 - 2.0 * v) * self.tan_half_fov;
        (self.forward + self.right * x + self.up * y).normalize()
    }
}

/// Corner `corner` (0–7: bit `k` picks `hi` on axis `k`) of the box `lo`–`hi`.
fn box_corner(lo: [f64; 3], hi: [f64; 3], corner: usize) -> [f64; 3] {
    std::array::from_fn(|k| if corner >> k & 1 == 1 { hi[k] } else { lo[k] })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn framing_keeps_every_corner_inside_the_picture() {
        let (lo, hi) = ([-0.1, 0.0, -0.08], [0.1, 0.9, 0.12]);
        for view in View::ALL {
            let cam = Camera::framing(lo, hi, view, &Stance::default(), 0.75);
            for corner in 0..8 {
                let d = Point3::from(box_corner(lo, hi, corner)) - cam.eye;
                let z = d.dot(&cam.forward);
                assert!(z > 0.0, "{view:?}: corner behind the eye");
                let x = d.dot(&cam.right) / (z * cam.tan_half_fov * cam.aspect);
                let y = d.dot(&cam.up) / (z * cam.tan_half_fov);
                assert!(x.abs() <= 1.0 && y.abs() <= 1.0, "{view:?}: {x} {y}");
            }
        }
    }

    #[test]
    fn centre_ray_looks_along_forward() {
        let cam = Camera::look_at(Point3::new(0.0, 0.0, 2.0), Point3::origin(), 30.0, 1.0);
        let d = cam.direction(0.5, 0.5);
        assert!((d - Vector3::new(0.0, 0.0, -1.0)).norm() < 1e-12);
        assert!(cam.direction(0.5, 0.0).y > 0.0, "v = 0 is the top");
        assert!(cam.direction(1.0, 0.5).x > 0.0, "u = 1 is the right");
    }

    #[test]
    fn an_auto_framed_camera_looks_at_the_character_as_it_stands() {
        let facing = Vector3::new(0.6, 0.0, 0.8);
        let stance = Stance::new(Vector3::y(), facing);
        let (lo, hi) = ([-0.1, 0.0, -0.08], [0.1, 0.9, 0.12]);
        let front = Camera::framing(lo, hi, View::Front, &stance, 0.75);
        assert!(
            (front.forward + facing).norm() < 1e-9,
            "{:?}",
            front.forward
        );
        assert!((front.up - Vector3::y()).norm() < 1e-9);
        // Its left on the image's right, as a person facing it sees it.
        assert!(
            (front.right - stance.left()).norm() < 1e-9,
            "{:?}",
            front.right
        );
        let side = Camera::framing(lo, hi, View::Side, &stance, 0.75);
        assert!((side.forward + stance.left()).norm() < 1e-9);
    }
}
