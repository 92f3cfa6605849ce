//! A stocking to the toe (`tube.bottom: "toe"`): down the bent leg, around the heel and along
//! the foot, closed by a toe seam. On the sample leg with a foot it converges, keeps every
//! point out of the leg, keeps its courses in order and reaches the toe tip.

use nalgebra::{Point3, Vector3};

use knitfit::base::YarnKind;
use knitfit::knit::tube::end_rings;
use knitfit::knit::TubeBottom;
use knitfit::leg::AxisSource;
use knitfit::plan::Plan;
use knitfit::report::StageClock;
use knitfit::run::fit::{solve_fit, FitInputs, SolvedFit};
use knitfit::run::NoProgress;
use knitfit::scene::Scene;

fn sample(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("samples")
        .join(name)
}

fn to_the_toe(leg: &std::path::Path) -> SolvedFit {
    let mut scene = Scene::load(None).unwrap();
    scene.tube.bottom = Some(TubeBottom::Toe);
    let plan = Plan::fit(&scene);
    let inputs = FitInputs {
        leg: leg.to_path_buf(),
        axis_source: AxisSource::Scene,
    };
    solve_fit(
        &scene,
        &plan,
        &inputs,
        "test",
        &mut StageClock::new(&plan),
        &mut NoProgress,
    )
    .unwrap()
}

#[test]
fn a_stocking_to_the_toe_converges_on_the_leg_and_reaches_the_toe_tip() {
    let fit = to_the_toe(&sample("makehuman_leg_foot.glb"));
    assert!(fit.solver.converged(), "residual {}", fit.solver.residual());
    assert_eq!(fit.max_penetration_m, 0.0);
    let knit = &fit.knit;
    assert!(knit.has_toe_seam());
    assert!(fit.bunched_courses * 10 <= knit.courses);
    // Only the welt is held; the toe rests on the foot.
    for (i, held) in end_rings(knit).into_iter().enumerate() {
        assert_eq!(held, i < knit.wales, "point {i}");
    }
    let seams = knit
        .yarn_springs()
        .filter(|(_, s)| s.yarn == YarnKind::Seam)
        .count();
    assert_eq!(seams, knit.wales / 2 - 1);
    let foot = fit.landmarks.as_ref().unwrap().foot.unwrap();
    let tip = Point3::from(foot.toe_tip);
    let nearest = knit
        .particles
        .x
        .iter()
        .map(|p| (Point3::from(*p) - tip).norm())
        .fold(f64::INFINITY, f64::min);
    assert!(
        nearest < 0.005,
        "the toe tip is {:.1} mm from the yarn",
        1e3 * nearest
    );
    // The last course lies across the toes, in front of the foot's middle.
    let along = Vector3::from(foot.direction);
    let last = knit.courses - 1;
    let reach = (0..knit.wales)
        .map(|w| (Point3::from(knit.particles.x[knit.point(w, last).index()]) - tip).dot(&along))
        .fold(f64::NEG_INFINITY, f64::max);
    assert!(
        reach > -0.01,
        "the toe seam ends {:.1} mm short of the tip",
        -1e3 * reach
    );
}

#[test]
fn a_heel_pocket_adds_short_rows_over_the_back_and_still_fits() {
    let mut scene = Scene::load(None).unwrap();
    scene.tube.bottom = Some(TubeBottom::Toe);
    scene.tube.heel = knitfit::knit::TubeHeel::Pocket;
    let plan = Plan::fit(&scene);
    let inputs = FitInputs {
        leg: sample("makehuman_leg_foot.glb"),
        axis_source: AxisSource::Scene,
    };
    let fit = solve_fit(
        &scene,
        &plan,
        &inputs,
        "test",
        &mut StageClock::new(&plan),
        &mut NoProgress,
    )
    .unwrap();
    assert!(fit.solver.converged(), "residual {}", fit.solver.residual());
    let rows = fit.knit.short_rows().expect("a pocket");
    assert!(rows.rows >= 2);
    assert!(fit.knit.len() > fit.knit.grid_len());
    assert_eq!(fit.max_penetration_m, 0.0);
    assert!(fit.bunched_courses * 10 <= fit.knit.courses);
}
