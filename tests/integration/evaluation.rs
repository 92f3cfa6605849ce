//! Property tests of the force evaluation every solver shares (`sim::evaluation`): over random
//! small knits, random positions (coincident points included) and random coefficients, the net
//! force obeys Newton's third law, every value is finite, and the per-point stiffness bound
//! covers the stiffness the forces really have (measured by finite differences).
//!
//! The kernels themselves and the contact projection are checked in `properties.rs`.

use nalgebra::{DMatrix, Matrix3};
use proptest::prelude::*;

use knitfit::base::Vec3;
use knitfit::knit::{Knit, Pattern, PointId, Tile};
use knitfit::sim::evaluation::{
    connection_stiffness_bound, evaluate, spring_stiffness_bound, Workspace,
};
use knitfit::sim::forces::{connection_force, spring_force, spring_tension};
use knitfit::sim::ForceTerms;

use crate::support::prop_config;

/// A small knit, as the numbers it is built from (so a failing case prints short).
#[derive(Clone, Debug)]
struct Case {
    wales: usize,
    courses: usize,
    closed: bool,
    pattern: Pattern,
    /// Course rest length, metres; wale rest length over it.
    rest: f64,
    aspect: f64,
    /// Per point, its move from its grid place, in course rest lengths.
    moves: Vec<[f64; 3]>,
    /// (to, from): point `to` put exactly where point `from` is.
    same: Vec<(usize, usize)>,
    /// On a closed knit, per wale the depth of short rows above the first course, and a toe
    /// seam across the last (the hosiery shaping); empty for a plain grid.
    short_rows: Vec<usize>,
    terms: ForceTerms,
}

impl Case {
    fn knit(&self) -> Knit {
        let (rest_course, rest_wale) = (self.rest, self.rest * self.aspect);
        let tile = Tile::of(self.pattern);
        let mut knit = Knit::grid(
            self.wales,
            self.courses,
            self.closed,
            &tile,
            rest_course,
            rest_wale,
            |w, c| Vec3::new(w as f64 * rest_course, c as f64 * rest_wale, 0.0),
        );
        for (x, m) in knit.particles.x.iter_mut().zip(&self.moves) {
            *x += Vec3::from(*m) * self.rest;
        }
        for &(to, from) in &self.same {
            knit.particles.x[to] = knit.particles.x[from];
        }
        if !self.short_rows.is_empty() {
            let x = knit.particles.x.clone();
            let wales = self.wales;
            knit = knit.with_toe_seam(rest_wale).with_short_rows(
                0,
                self.short_rows.clone(),
                &tile,
                rest_course,
                rest_wale,
                |w, t| {
                    // Between the wale's two grid points, bowed out so no two coincide.
                    let (a, b) = (x[w], x[wales + w]);
                    a * (1.0 - t) + b * t + Vec3::new(0.0, 0.0, t * (1.0 - t) * rest_course)
                },
            );
        }
        knit
    }
}

/// Knits of 2–5 × 2–5 points (closed courses, sometimes, when there are 3 or more wales), each
/// point moved at random by up to `jitter` rest lengths from its grid place, and, when
/// `coincide`, some points put exactly on top of others; c1 in [0.1, 1000] per yarn, and c2 in
/// [0, 0.99) when `connection`.
fn cases(jitter: f64, coincide: bool, connection: bool) -> impl Strategy<Value = Case> {
    sized_cases(2..=5, 2..=5, jitter, coincide, connection)
}

/// [`cases`] with `wales` and `courses` drawn from the given ranges.
fn sized_cases(
    wales: std::ops::RangeInclusive<usize>,
    courses: std::ops::RangeInclusive<usize>,
    jitter: f64,
    coincide: bool,
    connection: bool,
) -> impl Strategy<Value = Case> {
    (wales, courses, any::<bool>(), any::<bool>(), any::<bool>())
        .prop_flat_map(move |(wales, courses, closed, plain, shaped)| {
            let n = wales * courses;
            let closed = closed && wales >= 3;
            let depths = if closed && shaped { wales } else { 0 };
            (
                Just((wales, courses, closed, plain)),
                proptest::collection::vec(0usize..=2, depths),
                1e-4f64..1.0,
                0.3f64..3.0,
                proptest::collection::vec(prop::array::uniform3(-jitter..=jitter), n),
                proptest::collection::vec((0..n, 0..n), if coincide { 1..=n } else { 0..=0 }),
                (0.1f64..1000.0, 0.1f64..1000.0, 0.0f64..0.99),
            )
        })
        .prop_map(
            move |(
                (wales, courses, closed, plain),
                short_rows,
                rest,
                aspect,
                moves,
                same,
                (c_a, c_b, c2),
            )| {
                Case {
                    wales,
                    courses,
                    closed,
                    pattern: if plain {
                        Pattern::Plain
                    } else {
                        Pattern::Alternating
                    },
                    rest,
                    aspect,
                    moves,
                    same,
                    short_rows,
                    terms: ForceTerms {
                        stiffness: [c_a, c_b, c_a],
                        connection_factor: connection.then_some(c2),
                    },
                }
            },
        )
}

/// Net force and stiffness bound of every point.
fn forces(knit: &Knit, terms: &ForceTerms) -> (Vec<Vec3>, Vec<f64>) {
    let mut ws = Workspace::new(knit);
    evaluate(knit, terms, &mut ws);
    (ws.force, ws.stiffness_bound)
}

/// The Jacobian of the net force with respect to the positions, by central differences, as
/// `3n × 3n` (row: force component, column: coordinate).
fn jacobian(knit: &Knit, terms: &ForceTerms) -> DMatrix<f64> {
    let n = knit.len();
    let h = 1e-6
        * knit
            .springs
            .iter()
            .map(|s| s.rest)
            .fold(f64::INFINITY, f64::min);
    let mut j = DMatrix::zeros(3 * n, 3 * n);
    for col in 0..3 * n {
        let mut moved = knit.clone();
        moved.particles.x[col / 3][col % 3] += h;
        let (plus, _) = forces(&moved, terms);
        moved.particles.x[col / 3][col % 3] -= 2.0 * h;
        let (minus, _) = forces(&moved, terms);
        for row in 0..3 * n {
            j[(row, col)] = (plus[row / 3][row % 3] - minus[row / 3][row % 3]) / (2.0 * h);
        }
    }
    j
}

/// Point `p`'s Gershgorin row: Σ over points `q` of the spectral norm of the 3×3 block ∂F_p/∂x_q.
fn row_sum(j: &DMatrix<f64>, p: usize) -> f64 {
    (0..j.ncols() / 3)
        .map(|q| {
            let block: Matrix3<f64> = j.fixed_view::<3, 3>(3 * p, 3 * q).into_owned();
            block.singular_values().max()
        })
        .sum()
}

/// How far [`preconditioned_spectral_radius`] may exceed 1 from its own slack (the Frobenius
/// norm of a 75 × 75 matrix over its spectral norm, and eigenvector conditioning, to the power
/// 1/4096 stay well below this).
const SPECTRAL_SLACK: f64 = 1e-2;

/// An upper bound on the largest |eigenvalue| of the Jacobian with each point's rows divided by
/// its bound: Gelfand's `‖A^k‖^(1/k)` for `k = 2^12`, by repeated squaring with the scale kept
/// as a logarithm (an eigen-solver may not converge on such a matrix; this always ends). It
/// exceeds the spectral radius by at most the matrix's conditioning to the power 1/4096.
fn preconditioned_spectral_radius(case: &Case) -> f64 {
    const SQUARINGS: i32 = 12;
    let knit = case.knit();
    let (_, bound) = forces(&knit, &case.terms);
    let mut a = jacobian(&knit, &case.terms);
    for (r, mut row) in a.row_iter_mut().enumerate() {
        row /= bound[r / 3];
    }
    // Invariant: (the preconditioned Jacobian)^(2^i) = exp(log_scale) · a.
    let mut log_scale = 0.0;
    for _ in 0..SQUARINGS {
        let norm = a.norm();
        if norm == 0.0 {
            return 0.0;
        }
        a /= norm;
        log_scale = 2.0 * (log_scale + norm.ln());
        a = &a * &a;
    }
    ((log_scale + a.norm().ln()) / 2f64.powi(SQUARINGS)).exp()
}

/// The shortest spring over its rest length.
fn shortest_strain(knit: &Knit) -> f64 {
    let x = &knit.particles.x;
    knit.yarn_springs()
        .map(|(_, s)| (x[s.b.index()] - x[s.a.index()]).norm() / s.rest)
        .fold(f64::INFINITY, f64::min)
}

/// Point `i`'s net force and stiffness bound the plain way: the kernels of `forces.rs` summed
/// over the point's lists ([`Knit::incident`], [`Knit::connections`]); with the sum of the
/// terms' magnitudes, the scale of their rounding.
fn forces_from_lists(knit: &Knit, terms: &ForceTerms, i: usize) -> (Vec3, f64, f64) {
    let x = &knit.particles.x;
    let inv_len = |a: &Vec3, b: &Vec3| {
        let len = (a - b).norm();
        if len > 0.0 {
            1.0 / len
        } else {
            0.0
        }
    };
    let (mut force, mut bound, mut scale) = (Vec3::zeros(), 0.0, 0.0);
    let p = PointId(i as u32);
    for inc in knit.incident(p) {
        let s = &knit.springs[inc.spring as usize];
        let c1 = terms.c1(knit, inc.spring);
        let other = &x[inc.other.index()];
        let f = spring_force(&x[i], other, s.rest, c1);
        (force, scale) = (force + f, scale + f.norm());
        bound += spring_stiffness_bound(c1, s.rest, inv_len(&x[i], other));
    }
    if let Some(c2) = terms.connection_factor {
        for conn in knit.connections(p) {
            let s = &knit.springs[conn.spring as usize];
            let c1 = terms.c1(knit, conn.spring);
            let tension = spring_tension(&x[s.a.index()], &x[s.b.index()], s.rest, c1);
            let via = &x[conn.via.index()];
            let f = connection_force(&x[i], via, tension, c2);
            (force, scale) = (force + f, scale + f.norm());
            bound += connection_stiffness_bound(c2, c1, tension, inv_len(&x[i], via));
        }
    }
    (force, bound, scale)
}

proptest! {
    #![proptest_config(prop_config::config(64))]

    /// The force pass walks the grid row by row with the neighbours' places worked out from
    /// the layout; it gives what the kernels of eq. (1) and (2) summed over each point's own
    /// lists give, at the ends of rings and courses, across the seam, with coincident points,
    /// for single wales and courses, and with several rows per parallel chunk (9 courses and
    /// more).
    #[test]
    fn the_force_pass_matches_the_kernels_summed_over_each_point_s_lists(
        case in sized_cases(1..=7, 1..=20, 2.0, true, true)
    ) {
        let knit = case.knit();
        let (f, bound) = forces(&knit, &case.terms);
        for i in 0..knit.len() {
            let (expect, expect_bound, scale) = forces_from_lists(&knit, &case.terms, i);
            prop_assert!(
                (f[i] - expect).norm() <= 1e-12 * scale,
                "point {i}: force {} against {expect}", f[i]
            );
            prop_assert!(
                (bound[i] - expect_bound).abs() <= 1e-12 * expect_bound,
                "point {i}: bound {} against {expect_bound}", bound[i]
            );
        }
    }

    /// Eq. (1) acts equally and oppositely on a spring's two ends, so the spring forces on the
    /// whole knit sum to zero, whatever the positions (the connection force is not an
    /// interaction of pairs and is left out here).
    #[test]
    fn spring_forces_on_the_whole_knit_sum_to_zero(case in cases(2.0, true, false)) {
        let (f, _) = forces(&case.knit(), &case.terms);
        let total: Vec3 = f.iter().sum();
        let scale: f64 = f.iter().map(|f| f.norm()).sum();
        prop_assert!(total.norm() <= 1e-12 * scale + 1e-300, "Σ F = {total} (Σ |F| = {scale})");
    }

    /// Coincident points, zero-length springs and springs compressed to nothing give finite
    /// forces and bounds, and every point with a spring has a positive bound.
    #[test]
    fn forces_and_bounds_are_finite_even_for_coincident_points(case in cases(2.0, true, true)) {
        let (f, bound) = forces(&case.knit(), &case.terms);
        for (p, (f, b)) in f.iter().zip(&bound).enumerate() {
            prop_assert!(f.iter().all(|c| c.is_finite()), "point {p}: force {f}");
            prop_assert!(b.is_finite() && *b > 0.0, "point {p}: bound {b}");
        }
    }

    /// The bound of each point is at least its Gershgorin row of the true stiffness (the
    /// Jacobian of eq. 1 and, when it runs, eq. 2), so a step divided by it never overshoots:
    /// what the accelerated solver and the stability limit rely on.
    #[test]
    fn stiffness_bound_covers_each_point_s_row_of_the_jacobian(
        case in any::<bool>().prop_flat_map(|connection| cases(1.5, false, connection))
            .prop_filter("no spring near zero length", |c| shortest_strain(&c.knit()) > 0.05)
    ) {
        let knit = case.knit();
        let (_, bound) = forces(&knit, &case.terms);
        let j = jacobian(&knit, &case.terms);
        for (p, b) in bound.iter().enumerate() {
            let row = row_sum(&j, p);
            prop_assert!(row <= b * (1.0 + 1e-4), "point {p}: row {row} over bound {b}");
        }
    }

    /// What the bound is for, checked without Gershgorin's theorem: the Jacobian with each
    /// point's rows divided by its bound has no eigenvalue beyond 1.
    #[test]
    fn steps_divided_by_the_bound_have_spectral_radius_at_most_one(
        case in cases(1.5, false, true)
            .prop_filter("no spring near zero length", |c| shortest_strain(&c.knit()) > 0.05)
    ) {
        let rho = preconditioned_spectral_radius(&case);
        prop_assert!(rho <= 1.0 + SPECTRAL_SLACK, "spectral radius {rho}");
    }
}

/// Found by `steps_divided_by_the_bound_have_spectral_radius_at_most_one`: with c2 near 1 and a
/// strained knit, a bound that left out the turning of eq. (2)'s direction let the
/// preconditioned Jacobian reach a spectral radius of 1.36.
#[test]
fn regression_connection_turning_is_in_the_stiffness_bound() {
    let case = Case {
        wales: 3,
        courses: 2,
        closed: true,
        pattern: Pattern::Alternating,
        rest: 1e-4,
        aspect: 0.3,
        moves: vec![
            [0.0; 3],
            [0.0; 3],
            [0.0; 3],
            [-1.0594268894389458, 1.1975061484638405, 1.4888183127454535],
            [0.0, -1.0502074499578011, -0.8569563689584261],
            [-0.8022855633160448, -1.242953958657946, -0.9337057828847074],
        ],
        same: vec![],
        short_rows: vec![],
        terms: ForceTerms {
            stiffness: [0.1; 3],
            connection_factor: Some(0.9653009032664419),
        },
    };
    let rho = preconditioned_spectral_radius(&case);
    assert!(rho <= 1.0 + SPECTRAL_SLACK, "spectral radius {rho}");
}
