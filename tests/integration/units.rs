//! The stocking, not the grid (issue 21): the leg's fields are the real stocking's, in physical
//! units, whatever grid the solver used; the scene's real stocking is checked by field.

use std::path::Path;

use knitfit::report::{FitDetails, Report};
use serde_json::json;

use crate::support::{
    files_in, fit, float, knitfit, procedural_leg, read_ply, run_scene, sample, scene_for, stderr,
};

/// Per leg vertex: stitch density, coverage and pressure, from a fit's `leg.ply`.
fn leg_fields(out: &Path) -> Vec<[f64; 3]> {
    read_ply(&out.join("leg.ply")).payload["vertex"]
        .iter()
        .map(|v| {
            [
                float(v, "stitch_density"),
                float(v, "coverage"),
                float(v, "pressure"),
            ]
        })
        .collect()
}

/// `‖a − b‖ / ‖b‖` of field `k` over the vertices both cover.
fn relative_l2(a: &[[f64; 3]], b: &[[f64; 3]], k: usize) -> f64 {
    let both = a.iter().zip(b).filter(|(x, y)| x[0] > 0.0 && y[0] > 0.0);
    let (diff, norm) = both.fold((0.0, 0.0), |(d, n), (x, y)| {
        (d + (x[k] - y[k]).powi(2), n + y[k].powi(2))
    });
    (diff / norm).sqrt()
}

/// Asserts that stitch density, coverage and pressure of `a` are each within 3 % of `b`'s
/// (relative L2 over the vertices both cover, as issue 21 asks), printing each figure.
fn assert_fields_agree(a: &[[f64; 3]], b: &[[f64; 3]], what: &str) {
    for (k, field) in ["stitch_density", "coverage", "pressure"]
        .iter()
        .enumerate()
    {
        let error = relative_l2(a, b, k);
        eprintln!("{field}: {what}: {:.2}%", 100.0 * error);
        assert!(error < 0.03, "{field}: {what}: {:.2}% apart", 100.0 * error);
    }
}

#[test]
fn the_legs_fields_are_the_same_on_a_coarse_grid_and_at_the_real_stitch_count() {
    let leg = procedural_leg();
    let (coarse_dir, coarse) = fit(&leg, "100x100", &[]);
    // The real count: a point per needle around, a course per knitted course along.
    let knit = &coarse.details.knit;
    assert_eq!(knit.needles, 400.0);
    let courses = knit.courses.round() as usize + 1;
    let (real_dir, real) = fit(&leg, &format!("400x{courses}"), &[]);
    let per_cell = real.details.knit.stitches_per_cell;
    assert!((per_cell.course - 1.0).abs() < 1e-9, "{per_cell:?}");
    assert!((per_cell.wale - 1.0).abs() < 0.01, "{per_cell:?}");
    for (r, name) in [(&coarse, "100x100"), (&real, "real")] {
        assert!(r.metrics.converged, "{name}");
    }
    let a = leg_fields(&coarse_dir.path().join("out"));
    let b = leg_fields(&real_dir.path().join("out"));
    assert_fields_agree(&a, &b, &format!("100x100 against 400x{courses}"));
}

#[test]
fn a_whole_stockings_fields_are_the_same_on_coarse_grids_and_at_the_real_stitch_count() {
    // Over the heel and the toe, closed by the toe seam: the fields are measured over the same
    // fabric on every grid, on over the seam, and cut back at its folds (decision 0057).
    let leg = sample("makehuman_leg_foot.glb");
    // The default grid: 150 wales, the courses following the stitch (150×264 here).
    let (coarse_dir, coarse) = fit(&leg, "150", &[]);
    assert_eq!(coarse.details.tube.courses, 264);
    // Its cells, 1.97 mm of fabric, are short enough for the toe's tip: even.
    assert!(coarse.details.tube.toe_tip_wale_spacing_m.is_none());
    let courses = coarse.details.knit.courses.round() as usize + 1;
    let (real_dir, _) = fit(&leg, &format!("400x{courses}"), &[]);
    let a = leg_fields(&coarse_dir.path().join("out"));
    let b = leg_fields(&real_dir.path().join("out"));
    let above = above_the_ankle(&coarse_dir.path().join("out"), &coarse);
    let (a_leg, b_leg) = (kept(&a, &above), kept(&b, &above));
    // The grids follow the real count's coarse levels (decision 0063), with cells as many
    // stitches long as wide and the finest level polished (decision 0069), so they agree as
    // the issue asks over the whole leg, toes included (0.3 / 0.1 / 2.0 % measured), and
    // above the ankle (0.1 / 0.1 / 0.3 %).
    let real = format!("150 against 400x{courses}");
    assert_fields_agree(&a, &b, &real);
    assert_fields_agree(&a_leg, &b_leg, &format!("{real} above the ankle"));
    // A stocking of 100 wales, and one of 100×100 points, agree over the whole leg too: their
    // grids are graded to 2 mm cells over the toe's tip, whose 3–5 mm ones cut it (decisions
    // 0071, 0073), the 100×100 one relaxed first on the real count's 100×176 level (0072):
    // 0.3 / 0.1 / 1.9 % and 1.1 / 0.2 / 2.7 % measured.
    for grid in ["100", "100x100"] {
        let (dir, report) = fit(&leg, grid, &[]);
        let tip = report.details.tube.toe_tip_wale_spacing_m;
        assert!(
            tip.is_some_and(|m| (m - 0.002).abs() < 1e-4),
            "{grid}: {tip:?}"
        );
        let c = leg_fields(&dir.path().join("out"));
        assert_fields_agree(&c, &b, &format!("{grid} against 400x{courses}"));
    }
}

/// The vertices' fields where `keep` is true.
fn kept(fields: &[[f64; 3]], keep: &[bool]) -> Vec<[f64; 3]> {
    let pairs = fields.iter().zip(keep).filter(|(_, &k)| k);
    pairs.map(|(f, _)| *f).collect()
}

/// For each vertex of `out/leg.ply`, whether it lies above the ankle the report found.
fn above_the_ankle(out: &Path, report: &Report<FitDetails>) -> Vec<bool> {
    let marks = report.details.leg.landmarks.as_ref().expect("landmarks");
    let (up, ankle) = (marks.up, marks.ankle.centre.m);
    let height = |p: [f64; 3]| (0..3).map(|i| p[i] * up[i]).sum::<f64>();
    read_ply(&out.join("leg.ply")).payload["vertex"]
        .iter()
        .map(|v| height(["x", "y", "z"].map(|k| float(v, k))) >= height(ankle))
        .collect()
}

#[test]
fn a_20_denier_stocking_has_the_density_coverage_and_pressure_of_sheer_hosiery() {
    let (dir, r) = fit(&procedural_leg(), "100x100", &[]);
    let d = &r.details;
    // 20 den nylon is 50 µm across (solid nylon, 1.14 g/cm³); the support yarn's 40 den, 70 µm.
    let diameter = d.knit.yarn_diameter_um;
    assert!((diameter.nylon - 49.9).abs() < 0.1);
    assert!((diameter.support - 70.5).abs() < 0.1);
    // Hundreds of real stitches per cm² at the ankle, as the paper's density map shows, not the
    // tens a 100-point grid has.
    let density = &d.stitch_density_per_cm2;
    assert!(density.max > 150.0, "{density:?}");
    // Sheer: most of the skin shows; stretched over the thigh, more of it.
    let coverage = d.coverage;
    let (lo, hi) = (coverage.min, coverage.max);
    assert!(lo > 0.05 && hi < 0.5, "{coverage:?}");
    // Far below the lightest medical compression class (15–21 mmHg at the ankle), but not
    // nothing where the stocking is stretched.
    let pressure = d.pressure_mmhg;
    assert!(pressure.max < 15.0, "{pressure:?}");
    assert!(pressure.median > 0.2, "{pressure:?}");
    let fields = leg_fields(&dir.path().join("out"));
    assert!(fields.iter().flatten().all(|v| v.is_finite() && *v >= 0.0));
}

#[test]
fn a_heavier_yarn_covers_more_of_the_same_fit() {
    let leg = procedural_leg();
    let mean_coverage = |denier: f64| {
        let scene = scene_for(
            &leg,
            json!({}),
            json!({ "yarns": { "nylon": { "stiffness": 1, "denier": denier },
                               "support": { "stiffness": 10, "denier": 2.0 * denier } } }),
        );
        let (dir, out) = run_scene(&scene, "60x60", &[]);
        assert!(out.status.success(), "{}", stderr(&out));
        let fields = leg_fields(&dir.path().join("out"));
        let covered: Vec<f64> = fields.iter().filter(|f| f[0] > 0.0).map(|f| f[1]).collect();
        covered.iter().sum::<f64>() / covered.len() as f64
    };
    let [ten, twenty, forty] = [10.0, 20.0, 40.0].map(mean_coverage);
    eprintln!("mean coverage: 10 den {ten:.3}, 20 den {twenty:.3}, 40 den {forty:.3}");
    assert!(ten < twenty && twenty < forty);
}

#[test]
fn an_impossible_real_stocking_is_refused_by_field_with_nothing_written() {
    let dir = tempfile::tempdir().unwrap();
    let cases: [(&str, &str, &[&str], &str); 6] = [
        (
            "fit",
            r#"{"yarns": {"nylon": {"stiffness": 1, "denier": 0}}}"#,
            &[],
            "yarns.nylon.denier: must be a positive number, got 0",
        ),
        (
            "fit",
            r#"{"knit": {"needles": 120}}"#,
            &[],
            "knit.needles: 120 needles are fewer than the grid's 150 wales",
        ),
        (
            "fit",
            "{}",
            &["--resolution", "500x500"],
            "--resolution: 400 needles are fewer than the grid's 500 wales",
        ),
        (
            "patch",
            r#"{"outputs": ["ply", "loops"]}"#,
            &[],
            "outputs: \"stitches\" and \"loops\" lay a fit's real stitches on the leg",
        ),
        (
            "fit",
            r#"{"outputs": ["ply", "stitches", "loops"]}"#,
            &[],
            "outputs: lists both \"stitches\" and \"loops\"",
        ),
        (
            "fit",
            r#"{"outputs": ["picture", "loops"]}"#,
            &[],
            "outputs: \"loops\" says which yarns stocking.ply and stocking.glb hold",
        ),
    ];
    for (i, (command, scene, flags, message)) in cases.iter().enumerate() {
        let path = dir.path().join(format!("scene{i}.json"));
        std::fs::write(&path, scene).unwrap();
        let out_dir = dir.path().join(format!("out{i}"));
        let mut args = vec![
            command,
            path.to_str().unwrap(),
            "--out",
            out_dir.to_str().unwrap(),
        ];
        args.extend_from_slice(flags);
        let out = knitfit(dir.path(), &args);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(err.contains(message), "{err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(!out_dir.exists() || files_in(&out_dir).is_empty());
    }
}
