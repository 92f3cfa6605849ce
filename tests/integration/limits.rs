//! Resource limits: a fit too large for memory is refused up front, with its estimate and the
//! override; the override skips the check.

use knitfit::limits::{LimitSource, MemoryEstimate};

use crate::support::{
    files_in, knitfit, knitfit_within, procedural_leg, read_fit_report, stderr, stdout, write,
};

/// A .gltf whose one primitive declares a billion triangles over a buffer file that does not
/// exist: decoding it would fail on the buffer, so a refusal by size proves the check came first.
const HUGE_GLTF: &str = r#"{"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
  "nodes": [{"mesh": 0}], "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
  "buffers": [{"byteLength": 36, "uri": "missing.bin"}],
  "bufferViews": [{"buffer": 0, "byteLength": 36}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3000000000, "type": "VEC3",
                 "min": [0, 0, 0], "max": [1, 1, 1]}]}"#;

/// A knitting machine of 30,000 needles, so that a 30000-wale grid stands for its stitches.
const FINE_MACHINE: &str = r#"{"knit": {"needles": 30000},
  "effects": ["yarn_connection", "alternating_yarns", "contact", "penetration_fix"]}"#;

/// The arguments of `knitfit fit s.json` on `leg` at `resolution`.
fn fit_args<'a>(leg: &'a std::path::Path, resolution: &'a str) -> [&'a str; 6] {
    let leg = leg.to_str().unwrap();
    ["fit", "s.json", "--leg", leg, "--resolution", resolution]
}

/// Asserts a one-line refusal with exit code 2 that contains every `expect`, and no file written.
fn assert_refused(dir: &std::path::Path, out: &std::process::Output, expect: &[&str]) {
    let err = stderr(out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    for e in expect {
        assert!(err.contains(e), "{e:?} in {err}");
    }
    assert!(files_in(&dir.join("out")).is_empty());
}

#[test]
fn a_huge_resolution_is_refused_before_any_work_with_its_estimate_and_the_override() {
    // 9·10^8 points need terabytes: more than any machine this runs on has available (on a
    // machine of as many needles, so that the grid is not refused for being finer than them).
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "fine.json", FINE_MACHINE);
    let leg = crate::support::procedural_leg();
    let args = [
        "fit",
        "fine.json",
        "--leg",
        leg.to_str().unwrap(),
        "--resolution",
        "30000x30000",
    ];
    let out = knitfit(dir.path(), &args);
    assert_refused(
        dir.path(),
        &out,
        &[
            "30000×30000 points",
            "needs about",
            "GiB",
            "available",
            "lower --resolution",
            "--allow-large",
        ],
    );
}

#[test]
fn a_leg_declaring_too_many_triangles_is_refused_before_it_is_decoded() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "huge.gltf", HUGE_GLTF);
    let args = ["fit", "--leg", "huge.gltf", "--resolution", "20x12"];
    let out = knitfit(dir.path(), &args);
    assert_refused(
        dir.path(),
        &out,
        &[
            "huge.gltf",
            "1000000000 triangles",
            "fewer triangles",
            "--allow-large",
        ],
    );
    // The override skips the check: the run goes on to decode the leg, and only then meets
    // the missing buffer.
    let out = knitfit(dir.path(), &[&args[..], &["--allow-large"]].concat());
    assert_refused(dir.path(), &out, &["huge.gltf", "cannot load buffers"]);
}

#[test]
fn the_override_runs_a_fit_that_a_low_limit_refuses() {
    let dir = tempfile::tempdir().unwrap();
    let leg = procedural_leg();
    let base = [
        "fit",
        "--leg",
        leg.to_str().unwrap(),
        "--resolution",
        "20x12",
        "--memory-limit",
        "0.01",
        "-q",
    ];
    let out = knitfit(dir.path(), &base);
    assert_refused(
        dir.path(),
        &out,
        &["needs about", "10 MiB available", "limits.memory_gib"],
    );

    let out = knitfit(dir.path(), &[&base[..], &["--allow-large"]].concat());
    assert!(out.status.success(), "{}", stderr(&out));
    let memory = read_fit_report(&dir.path().join("out")).details.memory;
    assert!(memory.check.allow_large);
    assert!(memory.check.estimate.total_bytes > 10 << 20);

    // The same from the scene file.
    let scene = write(
        dir.path(),
        "s.json",
        r#"{"limits": {"memory_gib": 0.01, "allow_large": true}, "outputs": []}"#,
    );
    let (_, fitted) = crate::support::fit(&leg, "20x12", &[scene.to_str().unwrap()]);
    assert_eq!(fitted.details.memory.check.limit.source, LimitSource::Scene);
}

#[test]
fn plan_shows_the_estimate_and_whether_the_run_would_be_refused() {
    let dir = tempfile::tempdir().unwrap();
    let scenes = tempfile::tempdir().unwrap();
    let scene = write(scenes.path(), "fine.json", FINE_MACHINE);
    let leg = crate::support::procedural_leg();
    let plan = |extra: &[&str]| {
        let args = [
            "plan",
            scene.to_str().unwrap(),
            "--leg",
            leg.to_str().unwrap(),
            "--resolution",
            "30000x30000",
        ];
        let out = knitfit(dir.path(), &[&args[..], extra].concat());
        assert!(out.status.success(), "{}", stderr(&out));
        stdout(&out)
    };
    let text = plan(&[]);
    assert!(text.contains("the run would be refused"), "{text}");
    assert!(plan(&["--allow-large"]).contains("run anyway"));
    let json: serde_json::Value = serde_json::from_str(&plan(&["--json"])).unwrap();
    // The plan's `memory` has no type of its own (`fits` is the plan's); its estimate is typed.
    let memory = &json["memory"];
    assert_eq!(memory["fits"], false);
    let estimate: MemoryEstimate = serde_json::from_value(memory["estimate"].clone()).unwrap();
    assert!(estimate.tube_bytes > 500 << 30, "{memory}");
    assert_eq!(estimate.tube_points, 900_000_000u64);
    assert!(files_in(dir.path()).is_empty());
}

#[test]
fn a_bad_memory_limit_is_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let out = knitfit(dir.path(), &["fit", "--memory-limit", "0"]);
    assert_refused(dir.path(), &out, &["--memory-limit", "positive"]);
    write(dir.path(), "s.json", r#"{"limits": {"memory_gib": 0}}"#);
    let out = knitfit(dir.path(), &["fit", "s.json"]);
    assert_refused(dir.path(), &out, &["limits.memory_gib", "positive"]);
}

/// Finite but absurd physical settings are refused where the scene is read, naming the field and
/// the range any stocking lies in: before, each passed the checks and the fit diverged or
/// bunched (exit 1) with a message printing the value in hundreds of digits.
#[test]
fn regression_absurd_physical_settings_are_refused_at_the_load_not_run() {
    for (scene, expect) in [
        (
            r#"{"yarns": {"support": {"stiffness": 1e-300, "denier": 40,
                "colour": [0.08, 0.07, 0.10]}}}"#,
            "s.json: yarns.support.stiffness: must be from 1e-6 to 1e6, got 1e-300",
        ),
        (
            r#"{"knit": {"course_spacing_m": 1e-300}}"#,
            "s.json: knit.course_spacing_m: must be from 1e-5 to 0.02, got 1e-300",
        ),
        (
            r#"{"contact": {"offset_m": 1e308}}"#,
            "s.json: contact.offset_m: must be from 0 to 0.01, got 1e308",
        ),
    ] {
        let dir = tempfile::tempdir().unwrap();
        write(dir.path(), "s.json", scene);
        let out = knitfit(dir.path(), &["fit", "s.json"]);
        assert_refused(dir.path(), &out, &[expect]);
    }
}

/// The finest stitch accepted, 10 µm, on 30,000 needles (a stocking's girth): the fitted grid is
/// small, but the real stitches it stands for, 30000 × about 47,000, number more points than
/// 32-bit indices can. `--allow-large` lifts the memory check, not this bound; before it a fit of
/// such a count aborted allocating hundreds of GB (exit 134), and on a machine that had them
/// the ids wrapped.
const FINE_STITCH: &str = r#"{"knit": {"needles": 30000, "course_spacing_m": 1e-5,
  "wale_spacing_m": 1e-5}, "limits": {"allow_large": true}}"#;

#[test]
fn regression_real_stitches_past_32_bit_indices_are_refused_even_with_allow_large() {
    let leg = procedural_leg();
    for (outputs, expect) in [
        (
            r#"["ply", "stitches"]"#,
            "over the 1073741823 points a knit's 32-bit indices can number",
        ),
        (
            r#"["ply", "preview"]"#,
            "over the 89478485 stitches that 32-bit indices can number drawn as loops",
        ),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let mut scene: serde_json::Value = serde_json::from_str(FINE_STITCH).unwrap();
        scene["outputs"] = serde_json::from_str(outputs).unwrap();
        write(dir.path(), "s.json", &scene.to_string());
        let args = fit_args(&leg, "16x16");
        let out = knitfit(dir.path(), &args);
        assert_refused(
            dir.path(),
            &out,
            &[
                "s.json: knit.needles: the real stitches of this stocking, 30000×",
                expect,
            ],
        );
    }
}

/// A relaxed circumference sets the needles (circumference / knit.course_spacing_m), which then
/// passed knit.needles' bound unchecked: 10 m of 1e-5 m stitches is 10⁶ needles. Refused where
/// the scene is read, naming the field; before, the fit ran and ended in a misleading refusal
/// ("not on the leg") or, for a finer stitch, a diverged solver (exit 1).
#[test]
fn regression_a_circumference_of_more_needles_than_the_bound_is_refused_at_the_load() {
    let dir = tempfile::tempdir().unwrap();
    write(
        dir.path(),
        "s.json",
        r#"{"tube": {"relaxed_circumference_m": 10}, "knit": {"course_spacing_m": 1e-5}}"#,
    );
    let out = knitfit(dir.path(), &["fit", "s.json"]);
    assert_refused(
        dir.path(),
        &out,
        &[
            "s.json: tube.relaxed_circumference_m: 10 m of 1e-5 m stitches is 1e6 needles, over \
           the 100000 knit.needles allows",
        ],
    );
}

/// The paper's solver splits a step above the stability limit into `time_step / limit`
/// sub-steps; a time step of 1e308 saturated that to `usize::MAX` and the fit never ended (as
/// did a finite step over a limit of 1e-149, from a stitch of 1e-300 m, now refused itself).
/// More than 10,000 sub-steps a step is refused, with the largest time step that would do.
#[test]
fn regression_a_time_step_past_the_sub_step_bound_is_refused_not_run_for_ever() {
    let dir = tempfile::tempdir().unwrap();
    write(
        dir.path(),
        "s.json",
        r#"{"solver": {"method": "paper", "time_step": 1e308}}"#,
    );
    let leg = procedural_leg();
    let args = fit_args(&leg, "16x16");
    let out = knitfit_within(dir.path(), &args, std::time::Duration::from_secs(60))
        .expect("the fit ends within the bound");
    assert_refused(
        dir.path(),
        &out,
        &[
            "solver.time_step 1e308 would take more than 10000 sub-steps a step",
            "use a time step of at most",
        ],
    );
}

/// A heel pocket's rows on the grid are its length (a sixth of the stitches around, of the
/// relaxed stitch) over the grid's course spacing. A relaxed stocking of 1e-9 m made that
/// 10⁸ rows a wale and the fit aborted allocating them (exit 134); a pocket longer than the
/// stocking it is knitted into is refused before any grid is built.
#[test]
fn regression_a_heel_pocket_longer_than_the_stocking_is_refused_not_allocated() {
    let dir = tempfile::tempdir().unwrap();
    write(
        dir.path(),
        "s.json",
        r#"{"tube": {"heel": "pocket", "relaxed_length_m": 1e-9}, "outputs": ["ply"]}"#,
    );
    let leg = crate::support::sample("makehuman_leg_foot.glb");
    let args = fit_args(&leg, "60x60");
    let out = knitfit(dir.path(), &args);
    assert_refused(
        dir.path(),
        &out,
        &[
            "s.json: tube.heel: the heel pocket would be 0.049 m of fabric each way",
            "longer than the relaxed stocking (1e-9 m)",
        ],
    );
}

#[test]
fn an_nxn_stocking_is_checked_for_the_larger_level_it_is_relaxed_on_first() {
    // 100×100 to the toe is relaxed first on the real count's 100×176 level (decision 0072):
    // about 37 MiB as the grid alone (the check before the leg is read passes), about 41 MiB
    // with that level's solver; a limit between the two refuses it once the level is known.
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "s.json", r#"{"outputs": ["ply"]}"#);
    let leg = crate::support::sample("makehuman_leg_foot.glb");
    let args = [
        &fit_args(&leg, "100x100")[..],
        &["--memory-limit", "0.0385"],
    ]
    .concat();
    let out = knitfit(dir.path(), &args);
    assert_refused(
        dir.path(),
        &out,
        &[
            "a fit of 100×100 points, relaxed first on the real stitch count's 100×176 level",
            "needs about 41 MiB",
            "lower --resolution",
        ],
    );
}
