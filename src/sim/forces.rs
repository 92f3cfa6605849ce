//! Force kernels of Sakaguchi & Miyata §5, as pure functions of positions.
//!
//! * Spring force, eq. (1): `F_i = c1 (l − |x_i − x_j|) (x_i − x_j) / |x_i − x_j|`.
//! * Connection force, eq. (2): for three consecutive points `i, j, k` on one course yarn, the
//!   tension of spring `j–k` acts on `i` along the line `i–j`, scaled by `c2`.
//!
//! **Sign of eq. (2).** As printed, `c2 |F_jk| (x_i − x_j)/|x_i − x_j|` pushes `i` away from `j`.
//! We take the reading that matches the paper's explanation (Fig. 7: the yarn is pulled through
//! its loop): tension in `j–k` draws yarn from `i` towards `j`, so the force on `i` points from `i`
//! to `j`. A pushing force would make a stretched course spread its own ends apart, the opposite
//! of yarn being drawn through. We also use the *tension* `c1 · max(|x_j − x_k| − l, 0)` rather
//! than `|F_jk|`: a slack or compressed yarn cannot pull anything through a loop.
//!
//! Coincident points have no direction: the kernels return zero there rather than NaN.

use crate::base::Vec3;

/// Unit vector from `from` to `to` and the distance, or `None` when the points coincide.
pub fn direction(from: &Vec3, to: &Vec3) -> Option<(Vec3, f64)> {
    let d = to - from;
    let len = d.norm();
    if len > 0.0 && len.is_finite() {
        Some((d / len, len))
    } else {
        None
    }
}

/// Eq. (1): the force on `x_i` from the spring `i–j` of rest length `rest` and stiffness `c1`.
/// Restoring: it pushes `i` away from `j` when compressed and pulls it towards `j` when
/// stretched. The force on `j` is the negation.
pub fn spring_force(x_i: &Vec3, x_j: &Vec3, rest: f64, c1: f64) -> Vec3 {
    match direction(x_j, x_i) {
        Some((from_j_to_i, len)) => from_j_to_i * (c1 * (rest - len)),
        None => Vec3::zeros(),
    }
}

/// Tension carried by spring `j–k`: `c1 · max(|x_j − x_k| − l, 0)`; zero when slack.
pub fn spring_tension(x_j: &Vec3, x_k: &Vec3, rest: f64, c1: f64) -> f64 {
    let len = (x_k - x_j).norm();
    if len.is_finite() {
        c1 * (len - rest).max(0.0)
    } else {
        0.0
    }
}

/// Eq. (2) with our sign: the force on `x_i` from the tension `tension_jk` of the next spring
/// along its course, drawing `i` towards `j` with factor `c2`.
pub fn connection_force(x_i: &Vec3, x_j: &Vec3, tension_jk: f64, c2: f64) -> Vec3 {
    match direction(x_i, x_j) {
        Some((towards_j, _)) => towards_j * (c2 * tension_jk),
        None => Vec3::zeros(),
    }
}

/// Potential energy of a spring, `½ c1 (|x_i − x_j| − l)²`. Used to watch for divergence.
pub fn spring_energy(x_i: &Vec3, x_j: &Vec3, rest: f64, c1: f64) -> f64 {
    let stretch = (x_i - x_j).norm() - rest;
    0.5 * c1 * stretch * stretch
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64, z: f64) -> Vec3 {
        Vec3::new(x, y, z)
    }

    #[test]
    fn spring_force_is_zero_at_rest_length() {
        let f = spring_force(&v(0.0, 0.0, 0.0), &v(0.6, 0.8, 0.0), 1.0, 3.0);
        assert!(f.norm() < 1e-15, "{f}");
    }

    #[test]
    fn spring_force_is_equal_and_opposite() {
        let (a, b) = (v(0.1, -0.2, 0.3), v(1.5, 0.7, -0.4));
        let on_a = spring_force(&a, &b, 1.0, 2.0);
        let on_b = spring_force(&b, &a, 1.0, 2.0);
        assert!((on_a + on_b).norm() < 1e-14);
        assert!(on_a.norm() > 0.1);
    }

    #[test]
    fn spring_force_restores_length() {
        let (a, b) = (v(0.0, 0.0, 0.0), v(2.0, 0.0, 0.0));
        // Stretched (length 2, rest 1): a is pulled towards b with magnitude c1 · 1.
        assert_eq!(spring_force(&a, &b, 1.0, 3.0), v(3.0, 0.0, 0.0));
        // Compressed (length 2, rest 4): a is pushed away from b.
        assert_eq!(spring_force(&a, &b, 4.0, 3.0), v(-6.0, 0.0, 0.0));
    }

    #[test]
    fn connection_force_draws_i_towards_j_when_j_k_is_in_tension() {
        let (i, j, k) = (v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(3.0, 0.0, 0.0));
        let tension = spring_tension(&j, &k, 1.0, 10.0);
        assert_eq!(tension, 10.0);
        let f = connection_force(&i, &j, tension, 0.2);
        assert_eq!(f, v(2.0, 0.0, 0.0), "towards j, magnitude c2 · tension");
        // Slack j–k transmits nothing.
        assert_eq!(spring_tension(&j, &k, 5.0, 10.0), 0.0);
    }

    #[test]
    fn kernels_are_finite_for_coincident_points() {
        let p = v(1.0, 2.0, 3.0);
        assert_eq!(spring_force(&p, &p, 1.0, 1.0), Vec3::zeros());
        assert_eq!(connection_force(&p, &p, 5.0, 0.2), Vec3::zeros());
        assert_eq!(spring_tension(&p, &p, 1.0, 1.0), 0.0);
    }
}
