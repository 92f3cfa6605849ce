//! The physics of the paper's patch experiment (§5), through the library.

use knitfit::knit::patch::{build_patch, PatchSpec};
use knitfit::knit::{Knit, Pattern, Stretch, StretchAxis};
use knitfit::post::{anisotropy, measure_stitches, StitchStats};
use knitfit::sim::{relax, stability_limit, ForceTerms, OnUnstable, RelaxStats, SolverSettings};
use knitfit::Error;

const PAPER_TERMS: ForceTerms = ForceTerms {
    stiffness: [1.0, 10.0, 1.0],
    connection_factor: Some(0.2),
};

fn spec(size: usize, pattern: Pattern) -> PatchSpec {
    PatchSpec {
        grid: knitfit::base::GridSize::new(size, size),
        pattern,
        course_spacing_m: 0.0005,
        wale_spacing_m: 0.0005,
    }
}

fn stretch(axis: StretchAxis, factor: f64) -> Stretch {
    Stretch { axis, factor }
}

fn relaxed(
    pattern: Pattern,
    terms: &ForceTerms,
    s: Stretch,
    settings: &SolverSettings,
) -> (Knit, RelaxStats, StitchStats) {
    let mut knit = build_patch(&spec(10, pattern), s);
    let stats = relax(&mut knit, terms, settings, &mut ()).unwrap();
    let stitches = measure_stitches(&knit).unwrap();
    (knit, stats, stitches)
}

fn all_finite(knit: &Knit) -> bool {
    knit.particles
        .x
        .iter()
        .chain(&knit.particles.v)
        .all(|p| p.iter().all(|c| c.is_finite()))
}

#[test]
fn papers_10x10_patch_settles_in_the_order_of_100_steps() {
    // Paper §5 / Fig. 8: 10×10, t = 0.1, c1 = 1 / 10, c2 = 0.2: "about 100 steps".
    let settings = SolverSettings::default();
    assert_eq!(settings.time_step, 0.1);
    for axis in [StretchAxis::Course, StretchAxis::Wale] {
        let (knit, stats, _) = relaxed(
            Pattern::Alternating,
            &PAPER_TERMS,
            stretch(axis, 1.5),
            &settings,
        );
        assert!(stats.converged, "{axis:?}: {stats:?}");
        assert!(stats.residual < 1e-3 && stats.max_move < 1e-3);
        assert!(
            (50..=400).contains(&stats.steps),
            "{axis:?}: {} steps",
            stats.steps
        );
        assert_eq!(
            stats.substeps_per_step, 1,
            "t = 0.1 is below the stability limit"
        );
        assert!(all_finite(&knit));
    }
}

#[test]
fn course_and_wale_stretch_differ_only_with_yarn_connection() {
    let settings = SolverSettings::default();
    let plain = |terms: &ForceTerms| {
        let (_, _, c) = relaxed(
            Pattern::Plain,
            terms,
            stretch(StretchAxis::Course, 1.5),
            &settings,
        );
        let (_, _, w) = relaxed(
            Pattern::Plain,
            terms,
            stretch(StretchAxis::Wale, 1.5),
            &settings,
        );
        anisotropy(&c, &w)
    };
    let with = plain(&ForceTerms {
        stiffness: [1.0; 3],
        connection_factor: Some(0.2),
    });
    let without = plain(&ForceTerms {
        stiffness: [1.0; 3],
        connection_factor: None,
    });
    assert!(
        with > 0.01,
        "yarn connection makes the directions differ: {with}"
    );
    assert!(without < 0.002, "without it they are transposes: {without}");
    assert!(with > 10.0 * without, "{with} vs {without}");
}

#[test]
fn yarn_connection_draws_stitches_wider_at_the_held_edges() {
    // Tension in a course draws yarn towards the middle of the course: the first free point is
    // pulled inwards, so the stitches next to the held wales are wider than those in the middle.
    let settings = SolverSettings::default();
    let terms = ForceTerms {
        stiffness: [1.0; 3],
        connection_factor: Some(0.2),
    };
    let (knit, _, _) = relaxed(
        Pattern::Plain,
        &terms,
        stretch(StretchAxis::Course, 1.5),
        &settings,
    );
    let x = |w| knit.particles.x[knit.point(w, 5).index()].x;
    let edge = x(1) - x(0);
    let middle = x(5) - x(4);
    assert!(
        edge > middle * 1.05,
        "edge stitch {edge} vs middle {middle}"
    );
}

#[test]
fn alternating_yarns_differ_measurably_from_plain() {
    // Stretched along the wale, the stiffer support yarn stretches less than nylon, so stitch
    // heights alternate; a plain knit stretches uniformly.
    let settings = SolverSettings::default();
    let s = stretch(StretchAxis::Wale, 1.5);
    let (_, _, plain) = relaxed(
        Pattern::Plain,
        &ForceTerms {
            stiffness: [1.0; 3],
            ..PAPER_TERMS
        },
        s,
        &settings,
    );
    let (_, _, alt) = relaxed(Pattern::Alternating, &PAPER_TERMS, s, &settings);
    assert!(plain.height_variation < 0.002, "{plain:?}");
    assert!(alt.height_variation > 0.02, "{alt:?}");
    assert!((alt.mean_aspect - plain.mean_aspect).abs() > 0.01);
}

/// Runs the paper's patch with `c1 = [1, ratio]`, a time step of `multiple` × the stability
/// limit, and the given policy.
fn stability_run(
    ratio: f64,
    multiple: f64,
    policy: OnUnstable,
) -> Result<(Knit, RelaxStats), Error> {
    let terms = ForceTerms {
        stiffness: [1.0, ratio, 1.0],
        connection_factor: Some(0.2),
    };
    let mut knit = build_patch(
        &spec(10, Pattern::Alternating),
        stretch(StretchAxis::Course, 1.5),
    );
    let limit = stability_limit(&knit, &terms);
    let settings = SolverSettings {
        time_step: multiple * limit,
        on_unstable: policy,
        max_steps: 200_000,
        ..SolverSettings::default()
    };
    let stats = relax(&mut knit, &terms, &settings, &mut ())?;
    Ok((knit, stats))
}

#[test]
fn every_step_size_converges_by_substepping_for_stiffness_ratios_10_and_1000() {
    for ratio in [10.0, 1000.0] {
        for multiple in [0.25, 0.5, 1.0, 2.0, 4.0] {
            let (knit, stats) = stability_run(ratio, multiple, OnUnstable::Substep)
                .unwrap_or_else(|e| panic!("ratio {ratio}, {multiple}× limit: {e}"));
            assert!(
                stats.converged,
                "ratio {ratio}, {multiple}× limit: {stats:?}"
            );
            assert!(all_finite(&knit));
            let expected_substeps = if multiple <= 1.0 {
                1
            } else {
                multiple.ceil() as usize
            };
            assert_eq!(
                stats.substeps_per_step, expected_substeps,
                "ratio {ratio}, {multiple}×"
            );
        }
    }
}

#[test]
fn step_above_the_limit_is_refused_with_the_limit_when_asked() {
    for ratio in [10.0, 1000.0] {
        let err = stability_run(ratio, 2.0, OnUnstable::Error).unwrap_err();
        assert!(matches!(err, Error::TimeStepTooLarge { .. }), "{err}");
        let text = err.to_string();
        assert!(
            text.contains("stability limit") && text.contains("substep"),
            "{text}"
        );
        assert!(!text.contains('\n'));
        assert_eq!(err.exit_code(), 2);
    }
}

#[test]
fn ignoring_the_limit_is_caught_by_the_divergence_watchdog_not_nan() {
    // 4× our bound is still more than 2× the true limit (the bound is within √2 of it): the run
    // blows up, and the watchdog must stop it with a message rather than let NaN through.
    for ratio in [10.0, 1000.0] {
        match stability_run(ratio, 4.0, OnUnstable::Ignore) {
            Err(Error::Diverged { step, what, .. }) => {
                assert!(step > 0, "ratio {ratio}");
                assert!(
                    what.contains("energy grew") || what.contains("finite"),
                    "{what}"
                );
            }
            other => panic!("ratio {ratio}: expected divergence, got {other:?}"),
        }
    }
}

#[test]
fn unstretched_patch_is_already_at_rest() {
    let (knit, stats, stitches) = relaxed(
        Pattern::Alternating,
        &PAPER_TERMS,
        stretch(StretchAxis::Course, 1.0),
        &SolverSettings::default(),
    );
    assert!(stats.converged && stats.steps == 0, "{stats:?}");
    assert!((stitches.mean_aspect - 1.0).abs() < 1e-12);
    assert!(all_finite(&knit));
}

#[test]
fn relaxed_patch_is_bit_identical_with_one_and_two_threads() {
    // 80×80 points spans several parallel chunks.
    let run = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                let mut knit = build_patch(
                    &spec(80, Pattern::Alternating),
                    stretch(StretchAxis::Wale, 1.3),
                );
                let settings = SolverSettings {
                    max_steps: 300,
                    ..SolverSettings::default()
                };
                let stats = relax(&mut knit, &PAPER_TERMS, &settings, &mut ()).unwrap();
                (knit.particles.x, stats.residual)
            })
    };
    let (x1, r1) = run(1);
    let (x2, r2) = run(2);
    assert_eq!(r1.to_bits(), r2.to_bits());
    assert!(x1.iter().zip(&x2).all(|(a, b)| a
        .iter()
        .zip(b.iter())
        .all(|(p, q)| p.to_bits() == q.to_bits())));
}
