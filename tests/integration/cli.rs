//! The command line's contract: outputs, report, determinism, and clean refusals of bad input.

use std::path::Path;

use knitfit::leg::{Side, Units, UpAxis};
use knitfit::report::SolverDetails;
use knitfit::scene::Effect;

use crate::support::{
    files_in, knitfit, knitfit_env, procedural_leg, read_fit_report, read_patch_report,
    stage_names, stderr, stdout, write,
};

#[test]
fn no_arguments_fits_the_bundled_sample_and_says_where_outputs_went() {
    let dir = tempfile::tempdir().unwrap();
    let out = knitfit(dir.path(), &[]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(
        files_in(&dir.path().join("out")),
        [
            "density.png",
            "leg.ply",
            "preview.png",
            "report.json",
            "stocking.glb",
            "stocking.ply"
        ]
    );
    let text = stdout(&out);
    assert!(text.contains("wrote to out/"), "{text}");
    assert!(text.contains("converged"), "{text}");
    // It says what to open next: the file, and the yarn-level still it rendered.
    assert!(
        text.contains("next: open out/stocking.glb in Blender"),
        "{text}"
    );
    assert!(
        text.contains("out/preview.png is the yarn-level still"),
        "{text}"
    );
    // The yarn files hold the fitted grid; the real stitches are laid for the preview only, and
    // the summary does not claim them written.
    assert!(
        text.contains("yarns: the fitted grid's (the preview draws every real stitch, 400 × "),
        "{text}"
    );
    // The second line says where the stocking went: the bundled leg has no foot and is cut.
    let extent = text.lines().nth(1).unwrap();
    assert!(
        extent.starts_with(
            "stocking: from the ankle (0.030 m above the sole) to 0.050 m below the cut, "
        ),
        "{text}"
    );
}

/// The lines of a `--help` section (`Commands:`, `Arguments:`, `Options:`), each split into
/// its names (`-q, --quiet`, `--leg <LEG>`, `[SCENE]`, `fit`) and its description.
fn help_section(help: &str, heading: &str) -> Vec<(String, String)> {
    let mut lines = help.lines().skip_while(|l| *l != heading).skip(1);
    let mut entries = Vec::new();
    for line in lines.by_ref() {
        if line.trim().is_empty() {
            break;
        }
        let entry = line.trim_start();
        let (names, description) = entry.split_once("  ").unwrap_or((entry, ""));
        entries.push((names.trim().to_string(), description.trim().to_string()));
    }
    entries
}

/// The long flags in `text` (`--memory-limit`).
fn long_flags(text: &str) -> std::collections::BTreeSet<String> {
    text.split(|c: char| !(c.is_ascii_alphanumeric() || c == '-'))
        .filter(|w| {
            w.strip_prefix("--")
                .is_some_and(|f| f.starts_with(|c: char| c.is_ascii_lowercase()))
        })
        .map(String::from)
        .collect()
}

/// The section of docs/GUIDE.md on `knitfit COMMAND`: from its heading to the next heading of
/// the same or a higher level.
fn guide_section(guide: &str, command: &str) -> String {
    let heading = format!("### `knitfit {command}`");
    let start = guide
        .find(&heading)
        .unwrap_or_else(|| panic!("docs/GUIDE.md has no {heading}"));
    let rest = &guide[start + heading.len()..];
    let end = ["\n### ", "\n## "]
        .iter()
        .filter_map(|h| rest.find(h))
        .min()
        .unwrap_or(rest.len());
    rest[..end].to_string()
}

/// Every subcommand (nested ones too) has `--help`; every argument and flag it lists has a
/// description; and the guide's section on the command names every flag the command takes
/// and no flag it does not.
#[test]
fn help_describes_every_subcommand_and_flag_and_the_guide_documents_each() {
    let dir = tempfile::tempdir().unwrap();
    let guide =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/GUIDE.md"))
            .unwrap();
    let top = knitfit(dir.path(), &["--help"]);
    assert!(top.status.success());
    let mut pending: Vec<Vec<String>> = help_section(&stdout(&top), "Commands:")
        .into_iter()
        .map(|(name, _)| vec![name])
        .filter(|path| path[0] != "help")
        .collect();
    let names: Vec<&str> = pending.iter().map(|p| p[0].as_str()).collect();
    assert_eq!(names, ["fit", "patch", "bench", "render", "plan"]);
    let mut checked = 0;
    while let Some(path) = pending.pop() {
        let mut args: Vec<&str> = path.iter().map(String::as_str).collect();
        args.push("--help");
        let out = knitfit(dir.path(), &args);
        assert!(out.status.success(), "{args:?}");
        let help = stdout(&out);
        let mut subcommands = Vec::new();
        for (sub, description) in help_section(&help, "Commands:") {
            if sub != "help" {
                assert!(!description.is_empty(), "{path:?} {sub} has no description");
                pending.push([path.clone(), vec![sub.clone()]].concat());
                subcommands.push(sub);
            }
        }
        let entries = [
            help_section(&help, "Arguments:"),
            help_section(&help, "Options:"),
        ]
        .concat();
        assert!(!entries.is_empty(), "{path:?}: no arguments or options");
        // A command that plans others (`plan`, `plan fit`) takes their flags: the guide may
        // document them in its own section or in theirs.
        let sections: Vec<String> = path
            .iter()
            .chain(&subcommands)
            .map(|c| guide_section(&guide, c))
            .collect();
        let documented: std::collections::BTreeSet<String> =
            sections.iter().flat_map(|s| long_flags(s)).collect();
        let mut taken = std::collections::BTreeSet::new();
        for (names, description) in entries {
            assert!(
                !description.is_empty(),
                "{path:?}: {names} has no description"
            );
            for flag in long_flags(&names) {
                if ["--help", "--version", "--quiet"].contains(&flag.as_str()) {
                    continue;
                }
                assert!(
                    documented.contains(&flag),
                    "docs/GUIDE.md does not document `knitfit {}` {flag}",
                    path.join(" ")
                );
                taken.insert(flag);
                checked += 1;
            }
        }
        if path.len() == 1 {
            let stale: Vec<String> = long_flags(&sections[0])
                .difference(&taken)
                .filter(|f| !["--help", "--quiet"].contains(&f.as_str()))
                .cloned()
                .collect();
            assert!(
                stale.is_empty(),
                "docs/GUIDE.md documents flags `knitfit {}` does not take: {stale:?}",
                path[0]
            );
        }
    }
    assert!(checked > 30, "only {checked} flags checked");
}

#[test]
fn report_has_the_agreed_fields_and_stages_in_order() {
    let dir = tempfile::tempdir().unwrap();
    let out = knitfit(
        dir.path(),
        &[
            "patch",
            "--size",
            "8x6",
            "--stretch",
            "wale=1.2",
            "--out",
            "o",
            "-q",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stdout(&out).is_empty(), "-q prints nothing");
    let r = read_patch_report(&dir.path().join("o"));
    assert_eq!(r.command, "patch");
    assert_eq!(
        r.effects,
        [Effect::YarnConnection, Effect::AlternatingYarns]
    );
    let stages = stage_names(&r);
    assert_eq!(
        stages,
        [
            "knit wale=1.2",
            "relax wale=1.2",
            "measure stitches",
            "encode patch.ply",
            "encode patch.glb",
            "encode patch.png",
            "write files"
        ]
    );
    assert!(r.stages.iter().all(|s| s.seconds >= 0.0));
    assert_eq!(r.metrics.points, 48);
    assert!(r.metrics.converged);
    assert!(r.metrics.residual < 1e-3);
    assert!(r.metrics.steps > 0);
    assert_eq!(
        r.outputs,
        ["patch.ply", "patch.glb", "patch.png", "report.json"]
    );
    assert!(r.wall_seconds > 0.0);
}

#[test]
fn only_the_outputs_and_effects_the_scene_names_run() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write(
        dir.path(),
        "s.json",
        r#"{"effects": ["alternating_yarns"], "outputs": ["glb"]}"#,
    );
    let out = knitfit(
        dir.path(),
        &["patch", scene.to_str().unwrap(), "--out", "o"],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(
        files_in(&dir.path().join("o")),
        ["patch.glb", "report.json"]
    );
    let r = read_patch_report(&dir.path().join("o"));
    assert_eq!(r.effects, [Effect::AlternatingYarns]);
    // Each stage's name and reason.
    let stages: String = r
        .stages
        .iter()
        .map(|s| format!("{} {}\n", s.name, s.why))
        .collect();
    assert!(
        !stages.contains("ply") && !stages.contains("png"),
        "{stages}"
    );
    assert!(r.details.anisotropy.is_some());
}

#[test]
fn outputs_are_byte_identical_across_runs_and_thread_counts() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write(
        dir.path(),
        "s.json",
        r#"{"patch": {"size": [70, 70]}, "solver": {"max_steps": 300}}"#,
    );
    let run = |out: &str, threads: &str| {
        let o = knitfit_env(
            dir.path(),
            &["patch", "s.json", "--out", out, "-q"],
            &[("RAYON_NUM_THREADS", threads)],
        );
        // 300 steps do not settle 70×70: exit 3, files written.
        assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    };
    let _ = scene;
    run("a", "1");
    run("b", "2");
    run("c", "2");
    for file in ["patch.ply", "patch.glb", "patch.png"] {
        let a = std::fs::read(dir.path().join("a").join(file)).unwrap();
        assert_eq!(
            a,
            std::fs::read(dir.path().join("b").join(file)).unwrap(),
            "{file}: 1 vs 2 threads"
        );
        assert_eq!(
            a,
            std::fs::read(dir.path().join("c").join(file)).unwrap(),
            "{file}: run to run"
        );
    }
    assert!(!read_patch_report(&dir.path().join("a")).metrics.converged);
}

/// Runs knitfit expecting a one-line error with exit code 2 (bad input) and no output.
fn refused(args: &[&str], files: &[(&str, &str)], expect: &str) {
    fails(2, args, files, expect);
}

/// Runs knitfit in a fresh directory holding `files`, expecting exit `code`, a one-line error
/// containing `expect`, and nothing written to `out/`.
fn fails(code: i32, args: &[&str], files: &[(&str, &str)], expect: &str) {
    let dir = tempfile::tempdir().unwrap();
    for (name, text) in files {
        write(dir.path(), name, text);
    }
    let out = knitfit(dir.path(), args);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(code), "{args:?}: {err}");
    assert_eq!(err.lines().count(), 1, "one line: {err}");
    assert!(
        err.contains(expect),
        "{args:?}: expected {expect:?} in {err}"
    );
    assert!(
        files_in(&dir.path().join("out")).is_empty(),
        "nothing written for {args:?}"
    );
}

#[test]
fn outputs_names_the_files_a_fit_writes_and_no_stage_runs_for_the_others() {
    let dir = tempfile::tempdir().unwrap();
    let leg = procedural_leg();
    let leg = leg.to_str().unwrap();
    let args = [
        "fit",
        "--leg",
        leg,
        "--resolution",
        "20x12",
        "--bottom",
        "ankle",
        "-q",
    ];
    let out = knitfit(
        dir.path(),
        &[&args[..], &["--outputs", "ply, glb"]].concat(),
    );
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(
        files_in(&dir.path().join("out")),
        ["leg.ply", "report.json", "stocking.glb", "stocking.ply"]
    );
    let stages = stage_names(&read_fit_report(&dir.path().join("out")));
    for picture in ["render preview", "lay stitches", "encode density.png"] {
        assert!(!stages.iter().any(|s| s == picture), "{stages:?}");
    }
    // An unknown name is refused naming the flag, before anything is read or written.
    refused(
        &[&args[..], &["--outputs", "ply,jpeg"]].concat(),
        &[],
        "--outputs: unknown variant `jpeg`, expected one of `ply`, `glb`, `picture`, `preview`",
    );
}

#[test]
fn a_bad_units_up_axis_or_side_is_refused_naming_the_flag() {
    for command in ["fit", "plan"] {
        for (flag, value, expect) in [
            (
                "--units",
                "km",
                "--units: unknown variant `km`, expected one of `m`, `dm`",
            ),
            (
                "--up-axis",
                "y",
                "--up-axis: unknown up axis \"y\": expected \"auto\", \"+y\"",
            ),
            (
                "--side",
                "both",
                "--side: unknown variant `both`, expected `left` or `right`",
            ),
        ] {
            refused(&[command, flag, value], &[], expect);
        }
    }
}

#[test]
fn a_stocking_to_the_toe_on_fewer_than_60_wales_or_courses_is_refused() {
    // Its solver coarsens to 48 a side, but a stocking is not fitted on fewer than 60.
    let leg = crate::support::sample("makehuman_leg_foot.glb");
    let leg = leg.to_str().unwrap();
    for grid in ["59x100", "100x59"] {
        let args = ["fit", "--leg", leg, "--bottom", "toe", "--resolution", grid];
        refused(&args, &[], "give at least 60×60 (--resolution");
    }
}

#[test]
fn units_up_axis_and_side_flags_reach_the_fit() {
    let leg = Path::new(env!("CARGO_MANIFEST_DIR")).join("samples/makehuman_hips_heavy.glb");
    let (_dir, r) = crate::support::fit(
        &leg,
        "32x32",
        &[
            "--side",
            "right",
            "--up-axis",
            "+y",
            "--units",
            "m",
            "--bottom",
            "ankle",
        ],
    );
    let l = &r.details.leg;
    assert_eq!((l.units, l.up_axis), (Units::Metres, UpAxis::PosY));
    assert_eq!(l.up_axis_from, knitfit::leg::UpFrom::Given);
    assert_eq!(l.landmarks.as_ref().unwrap().side, Some(Side::Right));
    // The character's right is -X (glTF characters face +Z, their left on +X).
    assert!(r.details.axis.bottom[0] < 0.0, "{:?}", r.details.axis);
}

#[test]
fn malformed_json_is_refused_with_line_and_column() {
    refused(
        &["patch", "bad.json"],
        &[(
            "bad.json",
            "{\n  \"knit\": {\n    \"pattern\": \"plain\",,\n  }\n}",
        )],
        "bad.json:3:",
    );
}

#[test]
fn unknown_field_is_refused() {
    refused(
        &["patch", "s.json"],
        &[("s.json", r#"{"solver": {"step": 0.1}}"#)],
        "unknown field `step`",
    );
}

#[test]
fn negative_stiffness_is_refused() {
    refused(
        &["patch", "s.json"],
        &[(
            "s.json",
            r#"{"yarns": {"nylon": {"stiffness": -1, "denier": 20}}}"#,
        )],
        "s.json: yarns.nylon.stiffness: must be from 1e-6 to 1e6, got -1",
    );
}

#[test]
fn zero_size_is_refused() {
    refused(
        &["patch", "--size", "0x10"],
        &[],
        "--size: needs at least 2x2 points",
    );
    refused(
        &["patch", "s.json"],
        &[("s.json", r#"{"patch": {"size": [10, 0]}}"#)],
        "patch.size",
    );
}

#[test]
fn bad_stretch_flag_is_refused() {
    refused(
        &["patch", "--stretch", "diagonal=2"],
        &[],
        "--stretch: unknown variant `diagonal`, expected `course` or `wale`",
    );
    refused(
        &["patch", "--stretch", "course=-1"],
        &[],
        "--stretch: must be in (0, 10]",
    );
}

#[test]
fn missing_scene_file_is_refused() {
    refused(&["patch", "nope.json"], &[], "nope.json: cannot read");
}

#[test]
fn output_directory_under_a_file_is_refused_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "file", "not a directory");
    let out = knitfit(dir.path(), &["patch", "--out", "file/out"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert_eq!(stderr(&out).lines().count(), 1);
    assert!(
        stderr(&out).contains("file/out: cannot be the output directory: file is a file"),
        "{}",
        stderr(&out)
    );
    assert_eq!(files_in(dir.path()), ["file"]);
}

/// Found by hand: `--out` naming a file was refused as "output directory is not writable: File
/// exists", which sent users looking at permissions.
#[test]
fn out_naming_a_file_says_it_is_a_file_and_writes_nothing() {
    for args in [&["patch", "--out", "f"][..], &["fit", "--out", "f", "-q"]] {
        let dir = tempfile::tempdir().unwrap();
        write(dir.path(), "f", "mine");
        let out = knitfit(dir.path(), args);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(
            err.contains("f: cannot be the output directory: f is a file, not a directory"),
            "{err}"
        );
        assert!(!err.contains("not writable"), "{err}");
        assert_eq!(files_in(dir.path()), ["f"]);
        assert_eq!(
            std::fs::read_to_string(dir.path().join("f")).unwrap(),
            "mine"
        );
    }
}

/// Found by hand: `knitfit fit --leg missing.glb --out x` left an empty `x` behind.
#[test]
fn a_failed_run_leaves_no_output_directory_it_made() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "cut.glb", "glTF");
    let scene = r#"{"solver": {"time_step": 2.0, "on_unstable": "ignore"}}"#;
    write(dir.path(), "diverges.json", scene);
    let runs: [&[&str]; 4] = [
        &["fit", "--leg", "missing.glb", "--out", "x"],
        &["fit", "--leg", "cut.glb", "--out", "new/deeper/x"],
        &["fit", "--leg", "missing.glb"],
        // A run that fails in its solver, long after the directory was checked.
        &["patch", "diverges.json", "--out", "y"],
    ];
    for args in runs {
        let out = knitfit(dir.path(), args);
        assert!(!out.status.success(), "{args:?}");
        assert_eq!(
            files_in(dir.path()),
            ["cut.glb", "diverges.json"],
            "{args:?}: {}",
            stderr(&out)
        );
    }
}

#[test]
fn a_failed_run_leaves_an_existing_output_directory_as_it_was() {
    let dir = tempfile::tempdir().unwrap();
    for existing in ["empty", "full"] {
        std::fs::create_dir(dir.path().join(existing)).unwrap();
    }
    write(&dir.path().join("full"), "keep.txt", "kept");
    for out_dir in ["empty", "full"] {
        let out = knitfit(
            dir.path(),
            &["fit", "--leg", "missing.glb", "--out", out_dir],
        );
        assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    }
    assert_eq!(files_in(dir.path()), ["empty", "full"]);
    assert!(files_in(&dir.path().join("empty")).is_empty());
    assert_eq!(files_in(&dir.path().join("full")), ["keep.txt"]);
}

#[test]
fn an_output_never_overwrites_the_scene_file() {
    // The scene lives where report.json would be written.
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("o")).unwrap();
    let scene = write(&dir.path().join("o"), "report.json", "{}");
    let out = knitfit(dir.path(), &["patch", "o/report.json", "--out", "o"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("refusing to overwrite an input"),
        "{}",
        stderr(&out)
    );
    assert_eq!(std::fs::read_to_string(scene).unwrap(), "{}");
    assert_eq!(files_in(&dir.path().join("o")), ["report.json"]);
}

#[test]
fn unstable_step_with_on_unstable_error_is_refused_before_writing() {
    let scene = r#"{"solver": {"time_step": 2.0, "on_unstable": "error"}}"#;
    refused(
        &["patch", "s.json"],
        &[("s.json", scene)],
        "above the explicit stability limit",
    );
}

#[test]
fn diverging_run_stops_with_a_clear_message_and_writes_nothing() {
    let scene = r#"{"solver": {"time_step": 2.0, "on_unstable": "ignore"}}"#;
    fails(1, &["patch", "s.json"], &[("s.json", scene)], "diverged");
}

#[test]
fn written_files_read_back() {
    let dir = tempfile::tempdir().unwrap();
    let out = knitfit(
        dir.path(),
        &["patch", "--size", "6x5", "--stretch", "course=1.4", "-q"],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let o = dir.path().join("out");

    let (doc, buffers, _) = gltf::import(o.join("patch.glb")).unwrap();
    let node = doc.nodes().next().unwrap();
    assert_eq!(node.name(), Some("patch course=1.4"));
    let mesh = node.mesh().unwrap();
    let mut segments = 0;
    for prim in mesh.primitives() {
        assert_eq!(prim.mode(), gltf::mesh::Mode::Lines);
        let reader = prim.reader(|b| Some(&buffers[b.index()]));
        assert_eq!(reader.read_positions().unwrap().count(), 30);
        segments += reader.read_indices().unwrap().into_u32().count() / 2;
    }
    assert_eq!(segments, 5 * 5 + 4 * 6, "every spring once");

    let mut file = std::fs::File::open(o.join("patch.ply")).unwrap();
    let ply = ply_rs_bw::parser::Parser::<ply_rs_bw::ply::DefaultElement>::new()
        .read_ply(&mut file)
        .unwrap();
    assert_eq!(ply.payload["vertex"].len(), 30);
    assert_eq!(ply.payload["edge"].len(), 49);

    let png = image::open(o.join("patch.png")).unwrap();
    assert!(png.width() > 0 && png.height() > 0);
}

#[test]
fn a_fit_without_its_preview_says_how_to_render_it() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write(dir.path(), "s.json", r#"{"outputs": ["glb"]}"#);
    let out = knitfit(
        dir.path(),
        &[
            "fit",
            scene.to_str().unwrap(),
            "--leg",
            procedural_leg().to_str().unwrap(),
            "--resolution",
            "24x24",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let text = stdout(&out);
    assert!(
        text.contains("knitfit render out draws the yarn-level still"),
        "{text}"
    );
}

#[test]
fn a_fit_out_of_steps_is_written_and_says_where_it_had_not_settled() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write(
        dir.path(),
        "s.json",
        r#"{"outputs": ["ply"], "solver": {"max_steps": 20}}"#,
    );
    let out = knitfit(
        dir.path(),
        &[
            "fit",
            scene.to_str().unwrap(),
            "--leg",
            procedural_leg().to_str().unwrap(),
            "--resolution",
            "40x40",
            "-q",
        ],
    );
    // Exit 3: written, not converged; the warning and the report say where it had not settled.
    assert_eq!(out.status.code(), Some(3), "{}", stderr(&out));
    let text = stderr(&out);
    assert!(
        text.contains("did not converge within solver.max_steps = 20"),
        "{text}"
    );
    assert!(text.contains("had not settled"), "{text}");
    assert!(
        text.contains("up the stocking from its bottom end"),
        "{text}"
    );
    let r = read_fit_report(&dir.path().join("out"));
    assert!(!r.metrics.converged);
    let SolverDetails::Multilevel {
        unsettled_at,
        levels,
        ..
    } = &r.details.solver
    else {
        panic!("{:?}", r.details.solver)
    };
    let place = unsettled_at.as_deref().unwrap();
    assert!(
        place.starts_with("course") && text.contains(place),
        "{place}"
    );
    assert!(place.contains("cm above the sole, at "), "{place}");
    let fine = levels.last().unwrap();
    assert!(fine.unsettled.unwrap().worst_force_step > 1e-3);
    assert!(dir.path().join("out/stocking.ply").exists());
}
