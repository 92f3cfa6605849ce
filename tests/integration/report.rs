//! `report.json` read back typed: every command's report deserialises into its `Report<D>` and
//! serialises again to the same bytes (the types are the whole record, `null`s, tags, flattened
//! counters and stage names included), and a field the types do not know fails the read, so a
//! renamed or added field cannot pass a test as `null`.

use std::path::Path;

use knitfit::report::{FitDetails, PatchDetails, RenderDetails, Report};
use serde_json::Value;

use crate::support::{
    exact_json, knitfit, procedural_leg, read_report_file, sample, stderr, write,
};

/// Runs knitfit with `args` in `dir`, expecting exit `code`.
fn run(dir: &Path, args: &[&str], code: i32) {
    let out = knitfit(dir, args);
    assert_eq!(out.status.code(), Some(code), "{args:?}: {}", stderr(&out));
}

/// Reads the report `file` as `Report<D>`, writes it again, and checks the bytes are the file's.
fn assert_reads_back<D>(file: &Path)
where
    D: serde::de::DeserializeOwned + serde::Serialize + knitfit::report::CommandDetails,
{
    let written = std::fs::read_to_string(file).unwrap();
    let report: Report<D> = read_report_file(file);
    let again = String::from_utf8(report.to_json()).unwrap();
    assert!(
        again == written,
        "{} does not read back as written:\n--- written\n{written}\n--- read and written again\n{again}",
        file.display()
    );
}

#[test]
fn every_commands_report_reads_back_typed_to_the_same_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let leg = procedural_leg();
    let leg = leg.to_str().unwrap();
    // An open tube on the multilevel solver, every file and the preview (the penetration fix, the
    // stocking surface and the preview's counters all present).
    let every = write(
        d,
        "every.json",
        r#"{"outputs": ["glb", "ply", "picture", "preview"],
            "render": {"width": 32, "height": 48, "spp": 1}}"#,
    );
    let every = every.to_str().unwrap();
    let fit = ["fit", every, "--leg", leg, "--resolution", "24x24", "-q"];
    run(d, &[&fit[..], &["--out", "every"]].concat(), 0);
    assert_reads_back::<FitDetails>(&d.join("every/report.json"));
    // The paper's solver on a given axis with nothing but the report: the solver's other tag,
    // no landmarks, no fix, no surface, no preview (`null`s and absent fields).
    let nothing = write(d, "nothing.json", r#"{"outputs": []}"#);
    let nothing = nothing.to_str().unwrap();
    let paper = [
        "fit",
        nothing,
        "--leg",
        leg,
        "--resolution",
        "16x12",
        "--solver",
        "paper",
        "--tolerance",
        "0.01",
        "--axis",
        "0,0.30,0,0,0.60,0",
        "--out",
        "paper",
        "-q",
    ];
    run(d, &paper, 0);
    assert_reads_back::<FitDetails>(&d.join("paper/report.json"));
    // A stocking to the toe with a heel pocket: the toe box, the graded toe's tip, the slack.
    let foot = sample("lowpoly_leg.glb");
    let toe = [
        "fit",
        nothing,
        "--leg",
        foot.to_str().unwrap(),
        "--resolution",
        "60x60",
        "--heel",
        "pocket",
        "--out",
        "toe",
        "-q",
    ];
    run(d, &toe, 0);
    assert_reads_back::<FitDetails>(&d.join("toe/report.json"));
    // `knitfit render` of the first fit: its own report, next to the stocking.
    let render = [
        "render", "every", "--width", "24", "--height", "24", "--spp", "1", "-q",
    ];
    run(d, &render, 0);
    assert_reads_back::<RenderDetails>(&d.join("every/preview.report.json"));
    // The default patch, and a 2×2 patch whose every point is held: no free point, so its
    // stability limit is infinite (written `null`).
    run(d, &["patch", "--out", "patch", "-q"], 0);
    assert_reads_back::<PatchDetails>(&d.join("patch/report.json"));
    let held = write(
        d,
        "held.json",
        r#"{"outputs": [], "patch": {"size": [2, 2], "stretch": [{"axis": "course", "factor": 1.2}]}}"#,
    );
    run(
        d,
        &["patch", held.to_str().unwrap(), "--out", "held", "-q"],
        0,
    );
    let text = std::fs::read_to_string(d.join("held/report.json")).unwrap();
    assert!(text.contains(r#""time_step_limit": null"#), "{text}");
    assert_reads_back::<PatchDetails>(&d.join("held/report.json"));
}

/// The JSON of `value` with `edit` applied, read as a fit's report.
fn read_edited(value: &Value, edit: impl FnOnce(&mut Value)) -> Result<Report<FitDetails>, String> {
    let mut value = value.clone();
    edit(&mut value);
    serde_json::from_value(value).map_err(|e| e.to_string())
}

#[test]
fn a_field_the_report_types_do_not_know_fails_the_read() {
    let dir = tempfile::tempdir().unwrap();
    let leg = procedural_leg();
    run(
        dir.path(),
        &[
            "fit",
            "--leg",
            leg.to_str().unwrap(),
            "--resolution",
            "16x12",
            "-q",
        ],
        0,
    );
    let file = dir.path().join("out/report.json");
    let value = exact_json(&std::fs::read_to_string(&file).unwrap());
    assert!(read_edited(&value, |_| {}).is_ok());
    // A field added at each level, in a flattened record, in an internally tagged one, and in
    // a type from a stage's module; a field renamed; a field dropped.
    type Edit = fn(&mut Value);
    let cases: [(&str, Edit); 8] = [
        ("report", |v| v["extra"] = 1.into()),
        ("metrics", |v| v["metrics"]["extra"] = 1.into()),
        ("details", |v| v["details"]["extra"] = 1.into()),
        ("contact counters (flattened)", |v| {
            v["details"]["contact"]["extra"] = 1.into()
        }),
        ("solver (tagged)", |v| {
            v["details"]["solver"]["extra"] = 1.into()
        }),
        ("penetration fix", |v| {
            v["details"]["penetration_fix"]["extra"] = 1.into()
        }),
        ("renamed", |v| {
            let tube = v["details"]["tube"].as_object_mut().unwrap();
            let courses = tube.remove("courses").unwrap();
            tube.insert("course_count".into(), courses);
        }),
        ("dropped", |v| {
            v["details"]["knit"]
                .as_object_mut()
                .unwrap()
                .remove("needles");
        }),
    ];
    for (what, edit) in cases {
        let error = read_edited(&value, edit).expect_err(what);
        assert!(
            error.contains("unknown field") || error.contains("missing field"),
            "{what}: {error}"
        );
    }
    // A patch's report is not a fit's.
    run(dir.path(), &["patch", "--out", "p", "-q"], 0);
    let patch = exact_json(&std::fs::read_to_string(dir.path().join("p/report.json")).unwrap());
    let error = read_edited(&patch, |v| v["details"] = value["details"].clone()).unwrap_err();
    assert!(error.contains("a report of `patch`"), "{error}");
}
