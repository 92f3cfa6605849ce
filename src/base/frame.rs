//! Vectors and frames: the 3-vector every stage computes with, and the frame across an axis that
//! the leg's cross-sections and the tube's rings are laid out in.

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
