//! The leg's long axis: two points, bottom (ankle end) and top (thigh end), between which the
//! stocking is stretched (paper §6.2). Given by the scene or the command line, or detected.
//!
//! Detection: the principal axis of the surface (eigenvector of the area-weighted covariance of
//! the triangles' centroids with the largest eigenvalue), oriented upwards; bottom and top are the
//! extreme projections of the vertices onto it, moved inwards by [`END_INSET`] of the length so
//! that the tube's end rings lie on skin rather than on an open cut.

use nalgebra::{Matrix3, Point3, SymmetricEigen, Vector3};
use serde::Serialize;

use super::Leg;

/// Fraction of the leg's length kept free at each end by a detected axis.
pub const END_INSET: f64 = 0.03;

/// Where an axis came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum AxisSource {
    /// `leg.axis` in the scene.
    Scene,
    /// `--axis` on the command line.
    CommandLine,
    /// Detected from the mesh (principal axis).
    Detected,
}

/// The stocking's axis, world space (metres, Y up).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Axis {
    /// Bottom point (ankle end).
    pub bottom: [f64; 3],
    /// Top point (thigh end).
    pub top: [f64; 3],
    /// Where it came from.
    pub source: AxisSource,
}

impl Axis {
    /// Bottom as a point.
    pub fn bottom(&self) -> Point3<f64> {
        Point3::from(self.bottom)
    }

    /// Top as a point.
    pub fn top(&self) -> Point3<f64> {
        Point3::from(self.top)
    }

    /// Distance from bottom to top, metres.
    pub fn length(&self) -> f64 {
        (self.top() - self.bottom()).norm()
    }

    /// Unit vector from bottom to top.
    pub fn direction(&self) -> Vector3<f64> {
        (self.top() - self.bottom()).normalize()
    }
}

/// Detects the leg's axis (see module docs). `None` for a mesh with no area.
pub fn detect_axis(leg: &Leg) -> Option<Axis> {
    let mut area_sum = 0.0;
    let mut centroid = Vector3::zeros();
    let mut second = Matrix3::zeros();
    for t in &leg.triangles {
        let [a, b, c] = t.map(|i| leg.positions[i as usize].coords);
        let area = (b - a).cross(&(c - a)).norm() / 2.0;
        let m = (a + b + c) / 3.0;
        area_sum += area;
        centroid += m * area;
        second += m * m.transpose() * area;
    }
    if !(area_sum > 0.0 && area_sum.is_finite()) {
        return None;
    }
    centroid /= area_sum;
    let covariance = second / area_sum - centroid * centroid.transpose();
    let eigen = SymmetricEigen::new(covariance);
    let (k, _) =
        eigen
            .eigenvalues
            .iter()
            .enumerate()
            .fold((0, f64::NEG_INFINITY), |best, (i, &v)| {
                if v > best.1 {
                    (i, v)
                } else {
                    best
                }
            });
    let mut dir: Vector3<f64> = eigen.eigenvectors.column(k).into_owned();
    // Point it up (or, for a lying leg, along the largest positive component).
    let up_component = if dir.y.abs() > 1e-9 {
        dir.y
    } else {
        dir.x + dir.z
    };
    if up_component < 0.0 {
        dir = -dir;
    }
    let (lo, hi) = leg
        .positions
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
            let s = (p.coords - centroid).dot(&dir);
            (lo.min(s), hi.max(s))
        });
    let inset = END_INSET * (hi - lo);
    let at = |s: f64| (centroid + dir * s).into();
    Some(Axis {
        bottom: at(lo + inset),
        top: at(hi - inset),
        source: AxisSource::Detected,
    })
}
