//! The two solvers: the multilevel one (the default) reaches the paper's rest state, and the
//! run says which solver ran and what it did.

use knitfit::base::Direction;
use knitfit::fit::SolvedFit;
use knitfit::plan::Plan;
use knitfit::report::{FitDetails, Report, SolverDetails};
use knitfit::scene::Scene;
use knitfit::sim::SolverMethod;

use crate::support::{fit, sample_legs, shared_fit, solve_on, stage_names, OPEN_TUBE};

fn solve(leg: &std::path::Path, method: SolverMethod, tolerance: f64) -> (SolvedFit, Scene) {
    solve_grid(leg, method, tolerance, (60, 60))
}

fn solve_grid(
    leg: &std::path::Path,
    method: SolverMethod,
    tolerance: f64,
    (wales, courses): (usize, usize),
) -> (SolvedFit, Scene) {
    let mut scene = Scene::load(None).unwrap();
    // The open tube: these compare solvers on grids too coarse for a foot.
    scene.tube.bottom = Some(knitfit::knit::TubeBottom::Ankle);
    scene.tube.wales = wales;
    scene.tube.courses = Some(courses);
    scene.solver.method = method;
    scene.solver.tolerance = tolerance;
    solve_scene(leg, scene)
}

fn solve_scene(leg: &std::path::Path, scene: Scene) -> (SolvedFit, Scene) {
    (solve_on(leg, &scene), scene)
}

fn leg_density(fit: &SolvedFit, scene: &Scene) -> Vec<f64> {
    let terms = Plan::fit(scene).forces;
    knitfit::fit::measure::fields(fit, &scene.fabric(), &terms)
        .on_leg
        .stitch_density
}

#[test]
fn both_solvers_reach_the_same_rest_state_on_every_sample_leg() {
    // The paper's solver is the slow one: on two samples here, on every one in the long profile.
    for leg in crate::support::long::samples(sample_legs()) {
        let (paper, scene) = solve(&leg, SolverMethod::Paper, 1e-4);
        let (fast, _) = solve(&leg, SolverMethod::Multilevel, 1e-4);
        assert!(
            paper.solver.converged() && fast.solver.converged(),
            "{}: paper {} steps, residual {:.2e}; multilevel {} iterations, residual {:.2e}",
            leg.display(),
            paper.solver.steps(),
            paper.solver.residual(),
            fast.solver.steps(),
            fast.solver.residual()
        );
        let (a, b) = (leg_density(&paper, &scene), leg_density(&fast, &scene));
        let (mut diff, mut norm) = (0.0, 0.0);
        for (a, b) in a.iter().zip(&b) {
            diff += (a - b) * (a - b);
            norm += a * a;
        }
        let relative = (diff / norm).sqrt();
        println!(
            "{}: density fields differ by {:.3}% (L2); paper {} steps, multilevel {} iterations",
            leg.display(),
            100.0 * relative,
            paper.solver.steps(),
            fast.solver.steps()
        );
        // The heavy sample holds two rest states on a grid this coarse since the yarns are
        // blended (issue 21): the solvers settle in different ones, each a converged stocking
        // without penetration. They differ in how much the fabric bunches along the wale at
        // the open ankle edge (wale stretch 0.69 against 0.83, so 620 against 380 stitches per
        // cm²), which the fields' span of exactly 8 mm resolves and the 10 mm span of whole
        // steps smoothed (decision 0057): 32 % apart, measured over the covered skin alone (skin
        // past the open ankle ring is bare, decision 0069). Every other sample has one rest
        // state.
        let limit = if leg.ends_with("makehuman_hips_heavy.glb") {
            0.35
        } else {
            0.01
        };
        assert!(
            relative < limit,
            "{}: density fields differ by {relative:.4}",
            leg.display()
        );
        assert_eq!(paper.max_penetration_m, 0.0);
        assert_eq!(fast.max_penetration_m, 0.0);
    }
}

#[test]
fn the_report_says_which_solver_ran_and_how_each_level_went() {
    let leg = &sample_legs()[0];
    let (_dir, r) = shared_fit(leg, "60x60", OPEN_TUBE);
    let solver = &r.details.solver;
    let SolverDetails::Multilevel { levels, .. } = solver else {
        panic!("not multilevel: {solver:?}")
    };
    assert!(levels.len() >= 2, "{solver:?}");
    let last = levels.last().unwrap();
    assert_eq!((last.wales, last.courses), (60, 60));
    assert!(last.residual < 1e-3);
    assert!(last.force_step < 1e-3);
    assert!(r.metrics.force_step.unwrap() < 1e-3);
    assert!(r.metrics.max_move.is_finite());
    let stages = stage_names(r);
    assert!(!stages.iter().any(|s| s == "knit tube"), "{stages:?}");

    let (_dir, r) = fit(leg, "30x30", &["--solver", "paper", "--bottom", "ankle"]);
    let SolverDetails::Paper {
        time_step_limit, ..
    } = r.details.solver
    else {
        panic!("not paper: {:?}", r.details.solver)
    };
    assert!(time_step_limit > 0.0);
    assert!(r.metrics.force_step.is_none());
}

#[test]
fn the_default_tolerance_does_not_stall_on_points_that_hover_at_the_top_of_the_thigh() {
    // MakeHuman 200×200 at 1e-3: a few hundred points just off the skin at the top of the inner
    // thigh oscillate while the rest of the grid coasts; the grid's power stays positive. The
    // stall test (accelerated.rs, docs/decisions/0047) must restart them. The axis is the one
    // the principal-axis detection gave when the case was found (its top 1 cm from the cut).
    let leg = &sample_legs()
        .into_iter()
        .find(|p| p.ends_with("makehuman_leg.glb"))
        .unwrap();
    let axis = "0.21278062419064464,-0.6238740933305751,-0.018902966328417183,\
                0.12936193253866085,-0.21649956614454455,0.03861066644978582";
    let (_dir, r) = fit(leg, "200x200", &["--tolerance", "1e-3", "--axis", axis]);
    let SolverDetails::Multilevel { levels, .. } = &r.details.solver else {
        panic!("not multilevel: {:?}", r.details.solver)
    };
    let finest = levels.last().unwrap();
    // The fabric of blended yarns (issue 21) no longer hovers here: the case settles without
    // the stall restart it was found with (tested on its own in `sim::accelerated`).
    assert!(finest.converged, "{finest:?}");
    assert!(finest.iterations <= 200, "{finest:?}");
}

#[test]
fn the_bench_reference_tolerance_converges_on_every_sample_leg() {
    // 1e-6 is the bench's reference: re-queries that moved points from facet to facet used to
    // keep it from converging on the faceted legs (docs/decisions/0027).
    for leg in sample_legs() {
        let mut scene = Scene::load(None).unwrap();
        (scene.tube.wales, scene.tube.courses) = (50, Some(50));
        scene.tube.bottom = Some(knitfit::knit::TubeBottom::Ankle);
        scene.solver.tolerance = 1e-6;
        scene.solver.max_steps = 20_000;
        let (fit, _) = solve_scene(&leg, scene);
        assert!(
            fit.solver.converged(),
            "{}: {} iterations, residual {:.2e}",
            leg.display(),
            fit.solver.steps(),
            fit.solver.residual()
        );
        assert_eq!(fit.max_penetration_m, 0.0, "{}", leg.display());
    }
}

#[test]
fn a_tighter_tolerance_gives_a_smaller_residual() {
    let leg = &sample_legs()[0];
    let (_d, loose) = fit(leg, "50x50", &["--tolerance", "1e-2", "--bottom", "ankle"]);
    let (_d, tight) = fit(leg, "50x50", &["--tolerance", "1e-4", "--bottom", "ankle"]);
    let residual = |r: &Report<FitDetails>| r.metrics.residual;
    assert!(residual(&loose) < 1e-2 && residual(&tight) < 1e-4);
    assert!(residual(&tight) < residual(&loose));
}

#[test]
fn a_bad_solver_or_tolerance_flag_is_refused_before_any_work() {
    for (args, expect) in [
        (
            &["--solver", "fast"][..],
            "--solver: unknown variant `fast`, expected `multilevel` or `paper`",
        ),
        (&["--tolerance", "0"][..], "--tolerance: must be in (0, 1)"),
        (&["--tolerance", "2"][..], "--tolerance: must be in (0, 1)"),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let mut all = vec!["fit", "--resolution", "20x20"];
        all.extend_from_slice(args);
        let out = crate::support::knitfit(dir.path(), &all);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = crate::support::stderr(&out);
        assert!(err.contains(expect), "{args:?}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(crate::support::files_in(&dir.path().join("out")).is_empty());
    }
}

/// A grid whose cells are 2.7× wider than long (25×101 on the MakeHuman leg, the coarsest level
/// of the real count 400×1600) is the same fabric as a square-celled one: its springs are
/// rescaled for the stitch's shape. Unscaled, its rings were 7× too stiff against its wales,
/// squeezed the lower 40% of the tube into folds on the ankle, and did not converge in 100,000
/// iterations.
#[test]
fn a_grid_of_long_thin_cells_fits_without_folding_the_tube() {
    let leg = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("samples/makehuman_leg.glb");
    let (fit, scene) = solve_grid(&leg, SolverMethod::Multilevel, 1e-3, (25, 101));
    assert!(
        fit.solver.converged(),
        "residual {:.2e}",
        fit.solver.residual()
    );
    let knit = &fit.knit;
    let [course, wale] = knit.stiffness_scale.to_array();
    let rest = |d| knit.springs.iter().find(|s| s.direction == d).unwrap().rest;
    let cell = rest(Direction::Course) / rest(Direction::Wale);
    let stitch = scene.knit.course_spacing_m / scene.knit.wale_spacing_m;
    assert!((course * cell / stitch - 1.0).abs() < 1e-12 && (course * wale - 1.0).abs() < 1e-12);
    // A wale spring pointing down the axis is a fold.
    let axis = fit.placement.axis.direction();
    let wales: Vec<_> = knit
        .springs
        .iter()
        .filter(|s| s.direction == Direction::Wale)
        .collect();
    let folded = wales
        .iter()
        .filter(|s| {
            (knit.particles.x[s.b.index()] - knit.particles.x[s.a.index()]).dot(&axis) < 0.0
        })
        .count();
    assert!(
        folded * 20 < wales.len(),
        "{folded} of {} wale springs fold back",
        wales.len()
    );
}
