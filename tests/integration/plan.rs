//! Only the asked-for effects run: `knitfit plan` shows the stages a run executes and why, and the
//! reports of real runs show what was (not) built, loaded or applied.

use std::path::Path;

use crate::support::{
    files_in, knitfit, procedural_leg, report, stage_names, stderr, stdout, write,
};

/// Fits the procedural leg at 20×12 with the scene `scene` (written to `dir/NAME.json`) and
/// `extra` flags, expecting success; returns the report.
fn fit(dir: &Path, scene: &str, name: &str, extra: &[&str]) -> serde_json::Value {
    let scene = write(dir, &format!("{name}.json"), scene);
    let args = [&[scene.to_str().unwrap()][..], extra].concat();
    crate::support::fit(&procedural_leg(), "20x12", &args).1
}

/// The plan (`knitfit plan --json ARGS`) as JSON; the command must succeed.
fn plan_json(dir: &Path, args: &[&str]) -> serde_json::Value {
    let mut all = vec!["plan", "--json"];
    all.extend_from_slice(args);
    let run = knitfit(dir, &all);
    assert!(run.status.success(), "{}", stderr(&run));
    serde_json::from_str(&stdout(&run)).unwrap()
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
        without["details"]["preview"].is_null(),
        "{}",
        without["details"]
    );
    assert!(!stage_names(&without).iter().any(|s| s.contains("preview")));

    let with = fit(
        dir.path(),
        &format!(r#"{{"outputs": ["preview"], {render}}}"#),
        "with",
        &[],
    );
    let built = &with["details"]["preview"];
    assert!(built["bvh_triangles"].as_u64().unwrap() > 0, "{built}");
    assert!(built["segments"].as_u64().unwrap() > 0, "{built}");
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
    assert!(picture_only["details"]["penetration_fix"].is_null());
    assert!(!stage_names(&picture_only).contains(&"penetration fix".to_string()));
    assert!(!picture_only["effects"]
        .as_array()
        .unwrap()
        .contains(&"penetration_fix".into()));
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
    let fix = &ply["details"]["penetration_fix"];
    assert!(fix["segments"].as_u64().unwrap() > 0, "{fix}");
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
    let r = report(&dir.path().join("p"));
    assert!(!stage_names(&r).iter().any(|s| s.contains("leg")), "{r}");
    assert!(r["details"].get("leg").is_none());
    assert!(r["metrics"].get("leg_triangles").is_none());

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
        report(&dir.path().join(out))
    };
    let on = patch(r#"["yarn_connection"]"#, "on");
    let off = patch("[]", "off");
    let anisotropy = |r: &serde_json::Value| r["details"]["anisotropy"].as_f64().unwrap();
    let course_spread = |r: &serde_json::Value| {
        let s = &r["details"]["patches"][0]["stitches"];
        assert_eq!(r["details"]["patches"][0]["stretch"]["axis"], "course");
        s["max_aspect"].as_f64().unwrap() - s["min_aspect"].as_f64().unwrap()
    };
    assert!(anisotropy(&on) > 0.01, "on: {}", anisotropy(&on));
    assert!(anisotropy(&off) < 0.002, "off: {}", anisotropy(&off));
    assert!(course_spread(&on) > 0.05, "on: {}", course_spread(&on));
    assert!(course_spread(&off) < 0.01, "off: {}", course_spread(&off));
    assert_eq!(on["effects"], serde_json::json!(["yarn_connection"]));
    assert_eq!(off["effects"], serde_json::json!([]));
}

/// Checks that a run's report lists exactly the plan's stages, in order, each with its time.
fn assert_report_follows_plan(plan: &serde_json::Value, report: &serde_json::Value) {
    assert_eq!(
        names(&plan["stages"]),
        stage_names(report),
        "plan vs report"
    );
    let stages = report["stages"].as_array().unwrap();
    let mut total = 0.0;
    for (s, planned) in stages.iter().zip(plan["stages"].as_array().unwrap()) {
        let seconds = s["seconds"].as_f64().unwrap();
        assert!(seconds.is_finite() && seconds >= 0.0, "{s}");
        total += seconds;
        // A stage the run times but the plan does not list gets no reason: it shows here.
        assert!(!s["why"].as_str().unwrap().is_empty(), "{s}");
        assert_eq!(s["why"], planned["why"], "{s}");
    }
    assert!(total <= report["wall_seconds"].as_f64().unwrap());
    let written: Vec<&str> = report["outputs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|o| o.as_str().unwrap())
        .collect();
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
        assert_eq!(plan["effects"], report["effects"], "{name}");
    }
    let patch = knitfit(dir.path(), &["patch", "--size", "6x6", "--out", "p", "-q"]);
    assert!(patch.status.success(), "{}", stderr(&patch));
    let plan = plan_json(dir.path(), &["patch", "--size", "6x6", "--out", "p"]);
    assert_report_follows_plan(&plan, &report(&dir.path().join("p")));

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
    let r: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("r/preview.report.json")).unwrap())
            .unwrap();
    assert_eq!(
        stage_names(&r),
        ["read stocking.glb", "render preview", "write files"]
    );
    for s in r["stages"].as_array().unwrap() {
        assert!(!s["why"].as_str().unwrap().is_empty(), "{s}");
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
        "left out:",
        "render preview",
        "memory: about",
    ] {
        assert!(text.contains(expected), "{expected:?} in\n{text}");
    }
    let patch = stdout(&knitfit(dir.path(), &["plan", "patch"]));
    assert!(patch.contains("load leg") && patch.contains("a flat patch has no leg"));
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
