//! Only the asked-for effects run: `knitfit plan` shows the stages a run executes and why, and the
//! reports of real runs show what was (not) built, loaded or applied.

use std::path::Path;

use knitfit::knit::StretchAxis;
use knitfit::leg::{Axis, AxisSource, Side, ThighTopKind, UpAxis};
use knitfit::report::{FitDetails, LandmarkDetails, PatchDetails, Report};
use knitfit::scene::Effect;

use crate::support::{
    exact_json, files_in, knitfit, procedural_leg, read_fit_report, read_patch_report,
    read_render_report, revolved, stage_names, stderr, stdout, write, write_mesh,
};

/// Fits the procedural leg at 20×12 with the scene `scene` (written to `dir/NAME.json`) and
/// `extra` flags, expecting success; returns the report.
fn fit(dir: &Path, scene: &str, name: &str, extra: &[&str]) -> Report<FitDetails> {
    let scene = write(dir, &format!("{name}.json"), scene);
    let args = [&[scene.to_str().unwrap()][..], extra].concat();
    crate::support::fit(&procedural_leg(), "20x12", &args).1
}

/// The plan (`knitfit plan --json ARGS`) as JSON, its numbers exactly as written (so that they
/// compare with a report's to the last digit); the command must succeed. Untyped: the plan's
/// JSON has no type of its own in the library (`run::plan` builds it from private structs); its
/// parts that are report types (`landmarks`, `axis`, `effects`) are read typed where compared.
fn plan_json(dir: &Path, args: &[&str]) -> serde_json::Value {
    let mut all = vec!["plan", "--json"];
    all.extend_from_slice(args);
    let run = knitfit(dir, &all);
    assert!(run.status.success(), "{}", stderr(&run));
    exact_json(&stdout(&run))
}

/// The plan's `landmarks`, typed as the report's (`null` where the axis is given).
fn plan_landmarks(plan: &serde_json::Value) -> Option<LandmarkDetails> {
    serde_json::from_value(plan["landmarks"].clone()).unwrap()
}

/// The plan's `axis`, typed as the report's (`null` where no leg was read).
fn plan_axis(plan: &serde_json::Value) -> Option<Axis> {
    serde_json::from_value(plan["axis"].clone()).unwrap()
}

fn names(list: &serde_json::Value) -> Vec<String> {
    list.as_array()
        .unwrap()
        .iter()
        .map(|s| s["name"].as_str().unwrap().to_string())
        .collect()
}

#[test]
fn a_fit_without_a_preview_builds_no_render_structures() {
    let dir = tempfile::tempdir().unwrap();
    let render = r#""render": {"width": 32, "height": 48, "spp": 1}"#;
    let without = fit(
        dir.path(),
        &format!(r#"{{"outputs": ["glb", "picture"], {render}}}"#),
        "without",
        &[],
    );
    // The preview stage reports the BVH and yarn grid it built; without it there is nothing.
    assert!(
        without.details.preview.is_none(),
        "{:?}",
        without.details.preview
    );
    assert!(!stage_names(&without).iter().any(|s| s.contains("preview")));

    let with = fit(
        dir.path(),
        &format!(r#"{{"outputs": ["preview"], {render}}}"#),
        "with",
        &[],
    );
    let built = with.details.preview.unwrap();
    assert!(built.bvh_triangles > 0, "{built:?}");
    assert!(built.segments > 0, "{built:?}");
}

#[test]
fn without_polyline_outputs_no_penetration_fix_runs() {
    let dir = tempfile::tempdir().unwrap();
    let effects = r#""effects": ["yarn_connection", "alternating_yarns", "penetration_fix"]"#;
    let picture_only = fit(
        dir.path(),
        &format!(r#"{{{effects}, "outputs": ["picture"]}}"#),
        "picture",
        &[],
    );
    assert!(picture_only.details.penetration_fix.is_none());
    assert!(!stage_names(&picture_only).contains(&"penetration fix".to_string()));
    assert!(!picture_only.effects.contains(&Effect::PenetrationFix));
    // The plan says why it was left out.
    let scene = dir.path().join("picture.json");
    let leg = procedural_leg();
    let plan = plan_json(
        dir.path(),
        &[scene.to_str().unwrap(), "--leg", leg.to_str().unwrap()],
    );
    assert!(names(&plan["left_out"]).contains(&"penetration fix".to_string()));

    let ply = fit(
        dir.path(),
        &format!(r#"{{{effects}, "outputs": ["ply"]}}"#),
        "ply",
        &[],
    );
    let fix = ply.details.penetration_fix.unwrap();
    assert!(fix.segments > 0, "{fix:?}");
    assert!(stage_names(&ply).contains(&"penetration fix".to_string()));
}

#[test]
fn the_patch_command_loads_no_leg() {
    // A scene whose leg does not exist: a patch never opens it, a fit stops at it.
    let dir = tempfile::tempdir().unwrap();
    let scene = write(
        dir.path(),
        "s.json",
        r#"{"leg": {"file": "no_such_leg.glb"}, "outputs": []}"#,
    );
    let scene = scene.to_str().unwrap();
    let patch = knitfit(dir.path(), &["patch", scene, "--out", "p", "-q"]);
    assert!(patch.status.success(), "{}", stderr(&patch));
    // Read as a patch's report, whose details have no `leg` (an unknown field fails the read).
    let r = read_patch_report(&dir.path().join("p"));
    assert!(!stage_names(&r).iter().any(|s| s.contains("leg")), "{r:?}");
    assert!(r.metrics.leg_triangles.is_none());

    let fit = knitfit(dir.path(), &["fit", scene, "--out", "f", "-q"]);
    assert_eq!(fit.status.code(), Some(2));
    assert!(stderr(&fit).contains("no_such_leg.glb"), "{}", stderr(&fit));
}

#[test]
fn turning_yarn_connection_off_makes_course_and_wale_stretch_alike() {
    // The paper (§5, Fig. 9): stitches deform differently by stretch direction because one yarn
    // runs continuously along the course, which the connection force (eq. 2) models. In a plain
    // knit nothing else tells the directions apart, so without it the two stretches are
    // transposes of each other; with it, course tension draws yarn towards the middle of the
    // course and the stitches by the held wales open wider. Square stitches, as the paper's, so
    // that nothing but the yarn tells the directions apart.
    let dir = tempfile::tempdir().unwrap();
    let patch = |effects: &str, out: &str| {
        let scene = write(
            dir.path(),
            &format!("{out}.json"),
            &format!(
                r#"{{"knit": {{"pattern": "plain", "wale_spacing_m": 0.0005}}, "effects": {effects}, "outputs": [],
                    "patch": {{"size": [10, 10], "stretch": [{{"axis": "course", "factor": 1.5}},
                                                       {{"axis": "wale", "factor": 1.5}}]}}}}"#
            ),
        );
        let run = knitfit(
            dir.path(),
            &["patch", scene.to_str().unwrap(), "--out", out, "-q"],
        );
        assert!(run.status.success(), "{}", stderr(&run));
        read_patch_report(&dir.path().join(out))
    };
    let on = patch(r#"["yarn_connection"]"#, "on");
    let off = patch("[]", "off");
    let anisotropy = |r: &Report<PatchDetails>| r.details.anisotropy.unwrap();
    let course_spread = |r: &Report<PatchDetails>| {
        let s = r.details.patches[0].stitches.as_ref().unwrap();
        assert_eq!(r.details.patches[0].stretch.axis, StretchAxis::Course);
        s.max_aspect - s.min_aspect
    };
    assert!(anisotropy(&on) > 0.01, "on: {}", anisotropy(&on));
    assert!(anisotropy(&off) < 0.002, "off: {}", anisotropy(&off));
    assert!(course_spread(&on) > 0.05, "on: {}", course_spread(&on));
    assert!(course_spread(&off) < 0.01, "off: {}", course_spread(&off));
    assert_eq!(on.effects, [Effect::YarnConnection]);
    assert_eq!(off.effects, []);
}

/// Checks that a run's report lists exactly the plan's stages, in order, each with its time.
fn assert_report_follows_plan<D>(plan: &serde_json::Value, report: &Report<D>) {
    assert_eq!(
        names(&plan["stages"]),
        stage_names(report),
        "plan vs report"
    );
    let mut total = 0.0;
    for (s, planned) in report.stages.iter().zip(plan["stages"].as_array().unwrap()) {
        assert!(s.seconds.is_finite() && s.seconds >= 0.0, "{s:?}");
        total += s.seconds;
        // A stage the run times but the plan does not list gets no reason: it shows here.
        assert!(!s.why.is_empty(), "{s:?}");
        assert_eq!(s.why, planned["why"].as_str().unwrap(), "{s:?}");
    }
    assert!(total <= report.wall_seconds);
    let written: Vec<&str> = report.outputs.iter().map(String::as_str).collect();
    let planned: Vec<String> = plan["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| {
            Path::new(f.as_str().unwrap())
                .file_name()
                .unwrap()
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    assert_eq!(planned, written);
}

#[test]
fn the_plan_lists_the_stages_a_real_run_reports_each_with_its_time() {
    let dir = tempfile::tempdir().unwrap();
    let leg = procedural_leg();
    let leg = leg.to_str().unwrap();
    for (name, scene, extra) in [
        ("multilevel", r#"{}"#, &[][..]),
        (
            "paper_preview",
            r#"{"outputs": ["preview", "ply"], "render": {"width": 32, "height": 48, "spp": 1}}"#,
            &["--solver", "paper", "--tolerance", "0.01"][..],
        ),
        (
            "nothing",
            r#"{"outputs": [], "effects": ["penetration_fix"]}"#,
            &[][..],
        ),
    ] {
        let report = fit(dir.path(), scene, name, extra);
        let scene = dir.path().join(format!("{name}.json"));
        let mut args = vec![
            scene.to_str().unwrap(),
            "--leg",
            leg,
            "--resolution",
            "20x12",
            "--out",
            name,
        ];
        args.extend_from_slice(extra);
        let plan = plan_json(dir.path(), &args);
        assert_report_follows_plan(&plan, &report);
        let planned: Vec<Effect> = serde_json::from_value(plan["effects"].clone()).unwrap();
        assert_eq!(planned, report.effects, "{name}");
    }
    let patch = knitfit(dir.path(), &["patch", "--size", "6x6", "--out", "p", "-q"]);
    assert!(patch.status.success(), "{}", stderr(&patch));
    let plan = plan_json(dir.path(), &["patch", "--size", "6x6", "--out", "p"]);
    assert_report_follows_plan(&plan, &read_patch_report(&dir.path().join("p")));

    // knitfit render has no `plan`: its report's stages must each carry the reason its plan gave.
    let fitted = knitfit(
        dir.path(),
        &[
            "fit",
            "--leg",
            leg,
            "--resolution",
            "20x12",
            "--out",
            "r",
            "-q",
        ],
    );
    assert!(fitted.status.success(), "{}", stderr(&fitted));
    let render = knitfit(
        dir.path(),
        &[
            "render", "r", "--width", "32", "--height", "32", "--spp", "1", "-q",
        ],
    );
    assert!(render.status.success(), "{}", stderr(&render));
    let r = read_render_report(&dir.path().join("r"));
    assert_eq!(
        stage_names(&r),
        ["read stocking.glb", "render preview", "write files"]
    );
    for s in &r.stages {
        assert!(!s.why.is_empty(), "{s:?}");
    }
}

#[test]
fn plan_says_why_each_stage_runs_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let run = knitfit(dir.path(), &["plan"]);
    assert!(run.status.success(), "{}", stderr(&run));
    let text = stdout(&run);
    for expected in [
        "stages, in order:",
        "load leg",
        "outputs lists \"glb\"",
        "effect penetration_fix",
        "render preview       outputs lists \"preview\"",
        "memory: about",
    ] {
        assert!(text.contains(expected), "{expected:?} in\n{text}");
    }
    let patch = stdout(&knitfit(dir.path(), &["plan", "patch"]));
    assert!(patch.contains("left out:") && patch.contains("load leg"));
    assert!(patch.contains("a flat patch has no leg"));
    assert!(
        files_in(dir.path()).is_empty(),
        "{:?}",
        files_in(dir.path())
    );

    // Flags given before the subcommand would be silently dropped: refused instead.
    for stray in [
        &["plan", "--resolution", "20x20", "patch"][..],
        &["plan", "--out", "elsewhere", "fit"][..],
    ] {
        let run = knitfit(dir.path(), stray);
        assert_eq!(run.status.code(), Some(2), "{stray:?}");
    }
    // A leg the run could not read is refused as the run would refuse it.
    let missing = knitfit(dir.path(), &["plan", "--leg", "missing.glb"]);
    assert_eq!(missing.status.code(), Some(2));
    assert!(stderr(&missing).contains("missing.glb"));
    assert!(files_in(dir.path()).is_empty());
}

fn sample(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("samples")
        .join(name)
}

/// The line of `text` that starts with `start`.
fn line_starting<'a>(text: &'a str, start: &str) -> &'a str {
    text.lines()
        .find(|l| l.starts_with(start))
        .unwrap_or_else(|| panic!("no line starting {start:?} in\n{text}"))
}

#[test]
fn plan_shows_the_landmarks_and_the_axis_the_fit_then_uses() {
    let dir = tempfile::tempdir().unwrap();
    for (leg, side, extent) in [
        (
            "makehuman_body.glb",
            "left",
            "stocking: the left leg, from the ankle (",
        ),
        (
            "makehuman_hips_heavy.glb",
            "right",
            "stocking: the right leg, from the ankle (",
        ),
        ("makehuman_leg.glb", "left", "stocking: from the ankle ("),
    ] {
        let leg = sample(leg);
        let args = [
            "--leg",
            leg.to_str().unwrap(),
            "--side",
            side,
            "--resolution",
            // The heavy sample does not converge on coarser grids.
            "32x32",
            // The open tube, whose axis the plan and the fit share.
            "--bottom",
            "ankle",
        ];
        let plan = plan_json(dir.path(), &args);
        let text = stdout(&knitfit(dir.path(), &[&["plan"][..], &args].concat()));
        let fit = knitfit(
            dir.path(),
            &[&["fit"][..], &args, &["--out", side]].concat(),
        );
        assert!(fit.status.success(), "{}", stderr(&fit));
        let r = read_fit_report(&dir.path().join(side));
        // The same landmarks and axis, to the last digit, and the same words for the extent.
        assert_eq!(plan_landmarks(&plan), r.details.leg.landmarks, "{leg:?}");
        let axis = plan_axis(&plan).unwrap();
        assert_eq!(axis, r.details.axis, "{leg:?}");
        assert_eq!(axis.source, AxisSource::Landmarks);
        assert_eq!(
            serde_json::from_value::<UpAxis>(plan["leg"]["up_axis"].clone()).unwrap(),
            r.details.leg.up_axis
        );
        assert_eq!(plan["leg"]["up_axis_from"], "anatomy");
        let extent = line_starting(&text, extent);
        assert_eq!(
            extent,
            line_starting(&stdout(&fit), "stocking: "),
            "{leg:?}"
        );
        assert!(extent.ends_with(" m long"), "{extent}");
        for row in [
            "  up ",
            "  legs ",
            "  sole ",
            "  toe tip ",
            "  ankle ",
            "  knee ",
        ] {
            line_starting(&text, row);
        }
        // The axis as --axis takes it, in file coordinates (these files are in metres, +Y up).
        let as_axis = line_starting(&text, "  as --axis");
        let file = &plan["axis_file"];
        let x = file["bottom"][0].as_f64().unwrap();
        assert!(as_axis.contains(&format!("{x:.3},")), "{as_axis} vs {file}");
    }
    // Both legs found on the body, the side asked for dressed; the character's left is +X.
    let body = plan_json(
        dir.path(),
        &["--leg", sample("makehuman_body.glb").to_str().unwrap()],
    );
    let l = plan_landmarks(&body).unwrap();
    assert_eq!((l.legs_found, l.side), (2, Some(Side::Left)));
    assert_eq!(l.thigh_top_kind, ThighTopKind::Crotch);
    assert!(l.toe_tip.is_some() && l.foot_direction.is_some(), "{l:?}");
    let axis = plan_axis(&body).unwrap();
    assert!(axis.bottom[0] > 0.0, "{axis:?}");
    let cut = plan_json(
        dir.path(),
        &["--leg", sample("makehuman_leg.glb").to_str().unwrap()],
    );
    let l = plan_landmarks(&cut).unwrap();
    assert!(l.toe_tip.is_none() && l.side.is_none(), "{l:?}");
    let text = stdout(&knitfit(
        dir.path(),
        &[
            "plan",
            "--leg",
            sample("makehuman_leg.glb").to_str().unwrap(),
        ],
    ));
    assert!(
        line_starting(&text, "  toe tip ").ends_with("no foot"),
        "{text}"
    );
    assert!(
        line_starting(&text, "  thigh top ").contains("the cut"),
        "{text}"
    );
    assert!(files_in(dir.path())
        .iter()
        .all(|f| f == "left" || f == "right"));
}

#[test]
fn plan_of_a_given_axis_shows_it_in_world_and_file_coordinates() {
    let dir = tempfile::tempdir().unwrap();
    let leg = procedural_leg();
    let args = ["--leg", leg.to_str().unwrap(), "--axis", "0,0.1,0,0,0.8,0"];
    let plan = plan_json(dir.path(), &args);
    assert!(plan_landmarks(&plan).is_none(), "{}", plan["landmarks"]);
    assert_eq!(plan_axis(&plan).unwrap().source, AxisSource::CommandLine);
    assert_eq!(
        plan["axis_file"]["bottom"],
        serde_json::json!([0.0, 0.1, 0.0])
    );
    assert_eq!(plan["axis_file"]["top"], serde_json::json!([0.0, 0.8, 0.0]));
    let text = stdout(&knitfit(dir.path(), &[&["plan"][..], &args].concat()));
    assert_eq!(
        line_starting(&text, "stocking: "),
        "stocking: along --axis, 0.700 m long"
    );
    assert!(line_starting(&text, "  landmarks ").contains("the axis is given"));
    assert!(line_starting(&text, "  as --axis ").contains("0.000,0.100,0.000,0.000,0.800,0.000"));
}

/// Found in review: `knitfit plan` read only the leg file's header, so it said "fits" for a leg
/// whose landmarks the fit then could not find, or whose axis it refused.
#[test]
fn plan_refuses_a_leg_the_fit_refuses_with_the_same_line() {
    let dir = tempfile::tempdir().unwrap();
    // A rod 1 cm across: closed sections, none as thick as a leg.
    let rod = revolved("rod", 24, 40, (0.0, 0.5), |_| 0.005);
    let rod = write_mesh(dir.path(), "rod.glb", &rod.positions, rod.triangles);
    let short = write(
        dir.path(),
        "short.json",
        r#"{"tube": {"top": {"fraction": 0.05}}, "outputs": []}"#,
    );
    let leg = procedural_leg();
    let (leg, rod, short) = (
        leg.to_str().unwrap(),
        rod.to_str().unwrap(),
        short.to_str().unwrap(),
    );
    let before = files_in(dir.path());
    for (args, expect) in [
        (
            &["--leg", rod][..],
            "cannot find the leg's landmarks: no closed cross-section",
        ),
        (&[short, "--leg", leg][..], "the stocking would run only"),
        (
            &["--leg", leg, "--axis", "0.3,0.1,0,0.3,0.8,0"][..],
            "--axis runs outside the leg",
        ),
        (
            &["--leg", leg, "--units", "cm"][..],
            "outside the plausible",
        ),
    ] {
        let plan = knitfit(dir.path(), &[&["plan"][..], args].concat());
        let fit = knitfit(
            dir.path(),
            &[&["fit"][..], args, &["--resolution", "12x12", "-q"]].concat(),
        );
        assert_eq!(
            plan.status.code(),
            Some(2),
            "plan {args:?}: {}",
            stderr(&plan)
        );
        assert_eq!(fit.status.code(), Some(2), "fit {args:?}: {}", stderr(&fit));
        assert_eq!(stderr(&plan), stderr(&fit), "{args:?}");
        assert_eq!(stderr(&plan).lines().count(), 1, "{}", stderr(&plan));
        assert!(
            stderr(&plan).contains(expect),
            "{args:?}: {}",
            stderr(&plan)
        );
        assert!(stdout(&plan).is_empty(), "{}", stdout(&plan));
    }
    assert_eq!(files_in(dir.path()), before);
}
