//! Every real stitch (issue 21): `outputs` `stitches` writes the knit at its real count, laid on
//! the skin by interpolating the fitted grid; on every sample leg it keeps the real pattern and
//! topology and no yarn enters the leg.

use std::path::Path;

use knitfit::export::YarnsWritten;
use serde_json::json;

use crate::skin::{collider_of, polyline_depth};
use crate::support::{
    float, read_fit_report, read_ply, run_scene, sample_legs, scene_for, stage_names, stderr,
};

/// A stocking of the default's relaxed size knitted with a coarser stitch (100 needles, 4×
/// the stitch), so that every sample's real stitches can be sampled against the leg quickly.
fn coarse_stitch_scene(leg: &Path, outputs: &[&str]) -> serde_json::Value {
    scene_for(
        leg,
        json!({}),
        json!({
            "outputs": outputs,
            "effects": ["yarn_connection", "alternating_yarns", "contact", "penetration_fix"],
            "knit": { "needles": 100, "course_spacing_m": 0.002, "wale_spacing_m": 0.00296 },
        }),
    )
}

#[test]
fn every_real_stitch_lies_outside_the_leg_with_its_pattern_on_every_sample() {
    for leg in sample_legs() {
        let name = leg.file_name().unwrap().to_string_lossy().to_string();
        let (dir, out) = run_scene(
            &coarse_stitch_scene(&leg, &["ply", "stitches"]),
            "100x100",
            &[],
        );
        assert!(out.status.success(), "{name}: {}", stderr(&out));
        let out = dir.path().join("out");
        let r = read_fit_report(&out);
        let real = r.details.yarns.real_stitches.unwrap();
        let courses = r.details.knit.courses.round() as u64 + 1;
        assert_eq!(r.details.yarns.written, YarnsWritten::Stitches, "{name}");
        assert_eq!(real.wales, 100, "{name}");
        assert_eq!(real.courses as u64, courses, "{name}");
        // Every real stitch is written (short rows and the fix's inserted points add more).
        let ply = read_ply(&out.join("stocking.ply"));
        let vertices = &ply.payload["vertex"];
        assert!(vertices.len() as u64 >= 100 * courses, "{name}");
        // The real pattern: each course is one yarn, nylon and support alternating.
        let mut kind_of_course = std::collections::BTreeMap::new();
        for v in vertices.iter() {
            let course = float(v, "course");
            if course.fract() == 0.0 {
                let kind = float(v, "yarn_kind");
                let first = *kind_of_course.entry(course as i64).or_insert(kind);
                assert_eq!(kind, first, "{name}: course {course} has two yarns");
            }
        }
        assert_eq!(kind_of_course.len() as u64, courses, "{name}");
        let kinds: Vec<f64> = kind_of_course.values().copied().collect();
        assert!(kinds.windows(2).all(|k| k[0] != k[1]), "{name}: {kinds:?}");
        // No yarn inside the leg: every segment sampled every 25 µm.
        let depth = polyline_depth(&out, &collider_of(&leg), |_| true);
        assert!(
            depth.deepest <= 1e-7,
            "{name}: a stitch is {:.1} µm inside at {:?}",
            1e6 * depth.deepest,
            depth.at
        );
    }
}

#[test]
fn the_default_stocking_writes_all_its_real_stitches() {
    let leg = crate::support::procedural_leg();
    let scene = scene_for(
        &leg,
        json!({}),
        json!({ "outputs": ["ply", "glb", "stitches"] }),
    );
    let (dir, out) = run_scene(&scene, "60x60", &[]);
    assert!(out.status.success(), "{}", stderr(&out));
    let r = read_fit_report(&dir.path().join("out"));
    let yarns = &r.details.yarns;
    let real = yarns.real_stitches.unwrap();
    assert_eq!(real.wales, 400);
    let points = real.wales * real.courses;
    assert_eq!(real.points, points);
    assert!(yarns.points >= points);
    let stages = stage_names(&r);
    assert!(stages.contains(&"lay stitches".to_string()), "{stages:?}");
}

#[test]
fn every_real_stitch_as_a_loop_stays_outside_a_whole_stocking() {
    let leg = crate::support::sample_legs()
        .into_iter()
        .find(|p| p.ends_with("makehuman_leg_foot.glb"))
        .unwrap();
    let (dir, out) = run_scene(
        &coarse_stitch_scene(&leg, &["ply", "loops"]),
        "100x100",
        &[],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let out = dir.path().join("out");
    let r = read_fit_report(&out);
    let yarns = &r.details.yarns;
    assert_eq!(yarns.written, YarnsWritten::Loops);
    let stitches = yarns.real_stitches.unwrap().points;
    // Twelve samples a stitch; the fix adds a few where a loop crossed a crease.
    let points = yarns.points;
    assert!(
        points >= 12 * stitches && points < 13 * stitches,
        "{yarns:?}"
    );
    assert_eq!(r.details.penetration_fix.unwrap().still_crossing, 0);
    let depth = polyline_depth(&out, &collider_of(&leg), |_| true);
    assert!(
        depth.deepest <= 1e-7,
        "a loop is {:.1} µm inside at {:?}",
        1e6 * depth.deepest,
        depth.at
    );
    // That each course's loops join end to end into one yarn is held by post::loops' tests.
}
