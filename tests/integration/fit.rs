//! The fit on every sample leg (paper §6.1–6.2): invariants checked on the written files against
//! the exact leg, legs read from PLY as from glTF, and clean refusals of bad leg files.

use std::path::{Path, PathBuf};

use knitfit::leg::{
    load_leg, read_leg_file, AxisSource, Collider, ContactMethod, Units, UpAxis, UpChoice,
};
use knitfit::scene::Effect;
use nalgebra::Point3;
use ply_rs_bw::ply::Encoding;

use crate::support::variants::{fanned, leg_as_quads};
use crate::support::{
    base64, edited_sample, files_in, fit, float, knitfit, leg_as_ply, load_sample, point,
    procedural_leg, read_fit_report, read_ply, sample, sample_legs, shared_fit, stderr,
    write_tube_leg, OPEN_TUBE,
};

#[test]
fn every_sample_leg_fits_without_penetration_between_the_axis_points() {
    for leg_path in sample_legs() {
        let (dir, r) = shared_fit(&leg_path, "60x60", OPEN_TUBE);
        let out = dir.path().join("out");
        let name = leg_path.display();
        assert!(r.metrics.converged, "{name}");
        assert!(r.metrics.residual < 1e-3, "{name}");
        assert_eq!(r.metrics.points, 3600);
        assert_eq!(r.metrics.max_penetration_m, Some(0.0), "{name}");
        assert_eq!(
            r.effects,
            [
                Effect::YarnConnection,
                Effect::AlternatingYarns,
                Effect::Contact,
                Effect::PenetrationFix
            ]
        );

        // Independently of the report: every yarn point from the PLY, against the exact leg.
        let leg = load_leg(&leg_path, Units::Metres, UpChoice::Axis(UpAxis::PosY)).unwrap();
        let collider = Collider::new(&leg, ContactMethod::Bvh).unwrap();
        let yarns = read_ply(&out.join("stocking.ply"));
        let points: Vec<Point3<f64>> = yarns.payload["vertex"].iter().map(point).collect();
        let inserted = r.details.penetration_fix.unwrap().points_inserted;
        assert_eq!(points.len(), 3600 + inserted);
        let deepest = points
            .iter()
            .map(|p| collider.closest(p).signed_distance)
            .fold(f64::INFINITY, f64::min);
        // The PLY holds f32 positions: allow their rounding (0.1 µm at 0.6 m), no more.
        assert!(
            deepest >= -1e-7,
            "{name}: a yarn point is {deepest} m inside the leg"
        );

        // The tube stays between the two axis points.
        let (bottom, top) = (r.details.axis.bottom(), r.details.axis.top());
        let dir_axis = (top - bottom).normalize();
        let length = (top - bottom).norm();
        // The knit's own points exactly; points the penetration fix put on the skin between
        // two end-ring points follow the skin, which may lean out of the ring's plane by a
        // few tenths of a millimetre on a coarsely faceted leg (the unsubdivided body).
        for (i, p) in points.iter().enumerate() {
            let s = (p - bottom).dot(&dir_axis);
            let slack = if i < 3600 { 1e-6 } else { 5e-4 };
            assert!(
                (-slack..=length + slack).contains(&s),
                "{name}: point {i}: {s} outside 0..{length}"
            );
        }
    }
}

#[test]
fn stitch_density_is_positive_on_covered_skin_and_higher_at_the_ankle_than_the_thigh() {
    for leg_path in sample_legs() {
        let (dir, r) = shared_fit(&leg_path, "60x60", OPEN_TUBE);
        let name = leg_path.display();
        let legply = read_ply(&dir.path().join("out").join("leg.ply"));
        let vertices = &legply.payload["vertex"];
        let density: Vec<f64> = vertices
            .iter()
            .map(|v| float(v, "stitch_density"))
            .collect();
        assert!(density.iter().all(|d| d.is_finite() && *d >= 0.0), "{name}");
        let axis = &r.details.axis;
        let (bottom, top) = (axis.bottom[1], axis.top[1]);
        // In a file with both legs (the sample bodies, symmetric about x = 0): the dressed side.
        let both = r.details.leg.landmarks.as_ref().map(|l| l.legs_found) == Some(2);
        let side = axis.bottom[0].signum();
        let band = |lo: f64, hi: f64| {
            let values: Vec<f64> = vertices
                .iter()
                .zip(&density)
                .filter(|(v, _)| {
                    let t = (float(v, "y") - bottom) / (top - bottom);
                    (lo..hi).contains(&t) && (!both || float(v, "x") * side > 0.0)
                })
                .map(|(_, d)| *d)
                .collect();
            assert!(!values.is_empty(), "{name}: no vertex in band {lo}..{hi}");
            values
        };
        let ankle = band(0.05, 0.15);
        let thigh = band(0.85, 0.95);
        assert!(
            ankle.iter().all(|&d| d > 0.0),
            "{name}: uncovered skin at the ankle"
        );
        assert!(
            thigh.iter().all(|&d| d > 0.0),
            "{name}: uncovered skin at the thigh"
        );
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        assert!(
            mean(&ankle) > 1.5 * mean(&thigh),
            "{name}: ankle {} vs thigh {} stitches/cm²",
            mean(&ankle),
            mean(&thigh)
        );
    }
}

#[test]
fn ply_and_gltf_outputs_agree_and_read_back_with_their_counts() {
    let leg_path = &procedural_leg();
    let (dir, r) = fit(leg_path, "30x20", &[]);
    let out = dir.path().join("out");
    let yarns = read_ply(&out.join("stocking.ply"));
    // Every knit point, then the points the penetration fix inserted, each of which splits a
    // segment in two.
    let inserted = r.details.penetration_fix.unwrap().points_inserted;
    assert_eq!(yarns.payload["vertex"].len(), 600 + inserted);
    assert_eq!(
        yarns.payload["edge"].len(),
        30 * 20 + 30 * 19 + inserted,
        "closed courses + wales, split where repaired"
    );
    let legply = read_ply(&out.join("leg.ply"));
    assert_eq!(
        legply.payload["face"].len(),
        r.metrics.leg_triangles.unwrap()
    );
    // leg.ply reads back as the leg it was fitted on.
    let leg = load_sample(leg_path);
    let again = load_sample(&out.join("leg.ply"));
    assert_eq!(again.triangles, leg.triangles);
    assert_eq!(again.positions, leg.positions);

    let (doc, buffers, _) = gltf::import(out.join("stocking.glb")).unwrap();
    let names: Vec<_> = doc.nodes().map(|n| n.name().unwrap().to_string()).collect();
    assert_eq!(names, ["leg", "stocking", "yarns"]);
    // Viewers draw the default scene: the leg and the sheer stocking; the yarn lines wait in a
    // scene of their own instead of sitting on top of the stocking.
    let scenes: Vec<(String, Vec<String>)> = doc
        .scenes()
        .map(|s| {
            let nodes = s.nodes().map(|n| n.name().unwrap().to_string()).collect();
            (s.name().unwrap().to_string(), nodes)
        })
        .collect();
    assert_eq!(
        scenes,
        [
            ("knitfit".into(), vec!["leg".into(), "stocking".into()]),
            ("knitfit yarns".into(), vec!["yarns".into()])
        ]
    );
    assert_eq!(doc.default_scene().map(|s| s.index()), Some(0));
    let yarn_node = doc.nodes().nth(2).unwrap();
    let prim = yarn_node.mesh().unwrap().primitives().next().unwrap();
    let positions: Vec<[f32; 3]> = prim
        .reader(|b| Some(&buffers[b.index()]))
        .read_positions()
        .unwrap()
        .collect();
    for (gl, ply) in positions.iter().zip(&yarns.payload["vertex"]) {
        assert_eq!(
            *gl,
            [
                float(ply, "x") as f32,
                float(ply, "y") as f32,
                float(ply, "z") as f32
            ]
        );
    }
    let semantics: Vec<String> = prim.attributes().map(|(s, _)| s.to_string()).collect();
    for name in ["_COURSE", "_WALE", "_YARN_KIND", "_TENSION"] {
        assert!(
            semantics.iter().any(|s| s == name),
            "{name} missing from {semantics:?}"
        );
    }
    let leg_node = doc.nodes().next().unwrap();
    let leg_prim = leg_node.mesh().unwrap().primitives().next().unwrap();
    let semantics: Vec<String> = leg_prim.attributes().map(|(s, _)| s.to_string()).collect();
    for name in [
        "_STITCH_DENSITY",
        "_STRETCH_COURSE",
        "_STRETCH_WALE",
        "_COVERAGE",
        "NORMAL",
    ] {
        assert!(
            semantics.iter().any(|s| s == name),
            "{name} missing from {semantics:?}"
        );
    }
    // No heat map a viewer would paint over the leg's skin.
    assert!(!semantics.iter().any(|s| s == "COLOR_0"), "{semantics:?}");
    let stocking = doc.nodes().nth(1).unwrap().mesh().unwrap();
    let stocking = stocking.primitives().next().unwrap();
    let semantics: Vec<String> = stocking.attributes().map(|(s, _)| s.to_string()).collect();
    assert!(semantics.iter().any(|s| s == "TEXCOORD_0"), "{semantics:?}");
    // Sheer in the nylon's colour: COLOR_0's alpha is the coverage (clamped to 0–1).
    let material = stocking.material();
    assert_eq!(material.name(), Some("stocking"));
    assert_eq!(material.alpha_mode(), gltf::material::AlphaMode::Blend);
    let nylon = knitfit::scene::Scene::load(None)
        .unwrap()
        .yarns
        .nylon
        .colour;
    let [r, g, b] = nylon.map(|c| c as f32);
    assert_eq!(
        material.pbr_metallic_roughness().base_color_factor(),
        [r, g, b, 1.0]
    );
    let reader = stocking.reader(|b| Some(&buffers[b.index()]));
    let alpha: Vec<f32> = reader
        .read_colors(0)
        .unwrap()
        .into_rgba_f32()
        .map(|c| c[3])
        .collect();
    let coverage = stocking
        .attributes()
        .find(|(s, _)| *s == gltf::Semantic::Extras("COVERAGE".into()))
        .unwrap()
        .1;
    let coverage: Vec<f32> =
        gltf::accessor::Iter::<f32>::new(coverage, |b| Some(&buffers[b.index()]))
            .unwrap()
            .collect();
    assert_eq!(alpha.len(), coverage.len());
    for (a, c) in alpha.iter().zip(&coverage) {
        assert_eq!(*a, c.clamp(0.0, 1.0));
    }
    assert!(alpha.iter().any(|&a| a > 0.0 && a < 1.0), "a sheer knit");
}

#[test]
fn brute_force_contact_gives_the_same_fit_as_the_bvh() {
    // A coarse leg keeps the brute-force reference affordable.
    let dir = tempfile::tempdir().unwrap();
    let leg = coarse_leg(dir.path());
    let (bvh_dir, bvh) = fit(&leg, "16x12", &[]);
    let (brute_dir, brute) = fit(&leg, "16x12", &["--contact", "brute"]);
    assert_eq!(bvh.details.contact.method, ContactMethod::Bvh);
    assert_eq!(brute.details.contact.method, ContactMethod::Brute);
    assert_eq!(bvh.metrics.steps, brute.metrics.steps);
    let a = read_ply(&bvh_dir.path().join("out/stocking.ply"));
    let b = read_ply(&brute_dir.path().join("out/stocking.ply"));
    for (p, q) in a.payload["vertex"].iter().zip(&b.payload["vertex"]) {
        assert!((point(p) - point(q)).norm() < 1e-6);
    }
}

/// A leg-sized elliptic tube of 32 × 24 quads, open at both ends, written as a GLB into `dir`.
fn coarse_leg(dir: &Path) -> PathBuf {
    write_tube_leg(dir, "coarse_leg.glb", 32, 24, |h, t| {
        let y = 0.08 + 0.75 * h;
        let r = 0.035 + 0.045 * h;
        [r * 1.1 * t.cos(), y, -r * 0.9 * t.sin()]
    })
}

/// Runs `fit --leg FILE` on a leg file holding `bytes`, expecting a one-line error with exit
/// code 2 that names the file and contains `expect`, and nothing written.
fn bad_leg(name: &str, bytes: &[u8], expect: &str) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join(name), bytes).unwrap();
    let out = knitfit(dir.path(), &["fit", "--leg", name, "--resolution", "8x8"]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{name}: {err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains(name), "names the file: {err}");
    assert!(err.contains(expect), "expected {expect:?}: {err}");
    assert!(files_in(&dir.path().join("out")).is_empty());
}

/// A minimal glTF document with one primitive of `mode` over three embedded vertices.
fn gltf_text(positions: [[&str; 3]; 3], mode: u32, extensions: &str) -> String {
    let floats: Vec<f32> = positions
        .iter()
        .flatten()
        .map(|s| match *s {
            "nan" => f32::NAN,
            s => s.parse().unwrap(),
        })
        .collect();
    let bytes: Vec<u8> = floats.iter().flat_map(|f| f.to_le_bytes()).collect();
    let data = base64(&bytes);
    format!(
        r#"{{"asset":{{"version":"2.0"}},{extensions}"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"mode":{mode}}}]}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}}],
"bufferViews":[{{"buffer":0,"byteLength":36}}],
"buffers":[{{"byteLength":36,"uri":"data:application/octet-stream;base64,{data}"}}]}}"#
    )
}

const TRIANGLE: [[&str; 3]; 3] = [["0", "0", "0"], ["1", "0", "0"], ["0", "1", "0"]];

#[test]
fn a_file_that_is_not_gltf_is_refused() {
    bad_leg(
        "leg.glb",
        b"solid leg\nendsolid\n",
        "not a readable glTF file",
    );
}

#[test]
fn an_invalid_document_is_refused_with_what_is_wrong_said_once() {
    let name = "dangling.gltf";
    let text = r#"{"asset":{"version":"2.0"},"scenes":[{"nodes":[7]}]}"#;
    bad_leg(
        name,
        text.as_bytes(),
        "invalid glTF: scenes[0].nodes[0]: Index out of bounds",
    );
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join(name), text).unwrap();
    let err = stderr(&knitfit(dir.path(), &["fit", "--leg", name]));
    assert_eq!(err.matches("invalid glTF").count(), 1, "{err}");
    assert!(!err.trim_end().ends_with(';'), "{err}");
}

#[test]
fn a_leg_of_lines_only_is_refused() {
    bad_leg(
        "lines.gltf",
        gltf_text(TRIANGLE, 1, "").as_bytes(),
        "only line or point primitives",
    );
}

#[test]
fn compressed_geometry_is_refused_by_name() {
    let ext = r#""extensionsUsed":["KHR_draco_mesh_compression"],"extensionsRequired":["KHR_draco_mesh_compression"],"#;
    bad_leg(
        "draco.gltf",
        gltf_text(TRIANGLE, 4, ext).as_bytes(),
        "KHR_draco_mesh_compression",
    );
}

#[test]
fn non_finite_coordinates_are_refused() {
    let nan = [["0", "0", "0"], ["nan", "0", "0"], ["0", "1", "0"]];
    bad_leg("nan.gltf", gltf_text(nan, 4, "").as_bytes(), "non-finite");
}

#[test]
fn a_sample_leg_written_as_ply_reads_back_the_same_in_every_encoding() {
    let glb = Path::new(env!("CARGO_MANIFEST_DIR")).join("samples/makehuman_leg_coarse.glb");
    let leg = load_sample(&glb);
    let dir = tempfile::tempdir().unwrap();
    for encoding in [
        Encoding::BinaryLittleEndian,
        Encoding::BinaryBigEndian,
        Encoding::Ascii,
    ] {
        let path = dir.path().join("leg.ply");
        std::fs::write(&path, leg_as_ply(&leg, encoding)).unwrap();
        let file = read_leg_file(&path).unwrap();
        assert_eq!(
            file.declared_triangles(),
            leg.triangles.len(),
            "{encoding:?}"
        );
        let again = load_leg(&path, Units::Metres, UpChoice::Axis(UpAxis::PosY)).unwrap();
        assert_eq!(again.triangles, leg.triangles, "{encoding:?}");
        // The glTF file holds single-precision positions, and PLY writes them as floats.
        assert_eq!(again.positions, leg.positions, "{encoding:?}");
        assert_eq!(again.reoriented_triangles, 0, "{encoding:?}");
    }
}

#[test]
fn a_ply_leg_fits_as_its_gltf_original_does() {
    let dir = tempfile::tempdir().unwrap();
    let leg = load_sample(&procedural_leg());
    let ply = dir.path().join("leg.ply");
    std::fs::write(&ply, leg_as_ply(&leg, Encoding::Ascii)).unwrap();
    let (glb_dir, glb_report) = fit(&procedural_leg(), "16x12", &[]);
    let (ply_dir, ply_report) = fit(&ply, "16x12", &[]);
    assert_eq!(glb_report.metrics, ply_report.metrics);
    let a = read_ply(&glb_dir.path().join("out/stocking.ply"));
    let b = read_ply(&ply_dir.path().join("out/stocking.ply"));
    assert_eq!(a.payload["vertex"], b.payload["vertex"]);
}

#[test]
fn a_ply_leg_in_a_scene_file_is_read_with_its_units_and_up_axis() {
    // The sample leg in centimetres with +Z up, as a scanner might write it.
    let leg = load_sample(&procedural_leg());
    let mut turned = leg.clone();
    for p in &mut turned.positions {
        *p = Point3::new(p.x * 100.0, -p.z * 100.0, p.y * 100.0);
    }
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scan.ply");
    std::fs::write(&path, leg_as_ply(&turned, Encoding::BinaryBigEndian)).unwrap();
    let back = load_leg(&path, Units::Centimetres, UpChoice::Axis(UpAxis::PosZ)).unwrap();
    assert_eq!(back.triangles, leg.triangles);
    for (p, q) in back.positions.iter().zip(&leg.positions) {
        assert!((p - q).norm() < 1e-6, "{p} vs {q}");
    }
    let refused = load_leg(&path, Units::Metres, UpChoice::Axis(UpAxis::PosY)).unwrap_err();
    assert!(refused.to_string().contains("leg.up_axis"), "{refused}");
}

#[test]
fn malformed_ply_legs_are_refused_in_one_line() {
    let leg = load_sample(&procedural_leg());
    let binary = leg_as_ply(&leg, Encoding::BinaryLittleEndian);
    bad_leg("cut.ply", &binary[..binary.len() / 2], "is truncated");
    let ascii = String::from_utf8(leg_as_ply(&leg, Encoding::Ascii)).unwrap();
    bad_leg(
        "header.ply",
        ascii.replacen("format ascii", "format asci", 1).as_bytes(),
        "not a readable PLY file",
    );
    let last_face = ascii.trim_end().rsplit_once('\n').unwrap().0;
    bad_leg(
        "index.ply",
        format!("{last_face}\n3 0 1 99999999\n").as_bytes(),
        "names vertex 99999999",
    );
    let header_end = ascii.find("end_header\n").unwrap() + "end_header\n".len();
    let (header, body) = ascii.split_at(header_end);
    // ASCII PLY has no NaN token; a float past its range reads as an infinity.
    let (first, rest) = body.split_once('\n').unwrap();
    let mut values: Vec<&str> = first.split(' ').collect();
    values[1] = "1e39";
    bad_leg(
        "inf.ply",
        format!("{header}{}\n{rest}", values.join(" ")).as_bytes(),
        "non-finite coordinate",
    );
}

#[test]
fn a_leg_file_of_another_format_is_refused_by_its_extension() {
    bad_leg(
        "leg.obj",
        b"v 0 0 0\n",
        "knitfit reads .glb, .gltf and .ply leg files, not .obj",
    );
    bad_leg("leg", b"ply\n", "this one has no extension");
}

#[test]
fn a_leg_in_millimetres_read_as_metres_is_refused_with_the_units_that_fit() {
    let leg = std::fs::read(procedural_leg()).unwrap();
    let dir = tempfile::tempdir().unwrap();
    // The sample leg, scaled ×1000 by a node transform.
    let mut gltf = gltf::Gltf::from_slice(&leg).unwrap();
    let mut root = gltf.document.clone().into_json();
    for node in &mut root.nodes {
        node.scale = Some([1000.0; 3]);
    }
    let json = gltf_json::serialize::to_vec(&root).unwrap();
    let blob = gltf.blob.take().unwrap();
    let glb = gltf::binary::Glb {
        header: gltf::binary::Header {
            magic: *b"glTF",
            version: 2,
            length: 0,
        },
        json: std::borrow::Cow::Owned(json),
        bin: Some(std::borrow::Cow::Owned(blob)),
    };
    let path = dir.path().join("leg_mm.glb");
    std::fs::write(&path, glb.to_vec().unwrap()).unwrap();
    bad_leg(
        "leg_mm.glb",
        &std::fs::read(&path).unwrap(),
        "set leg.units or --units to \"mm\"",
    );
}

/// Mean stitch density of the covered leg vertices in a fit's leg.ply.
fn mean_density(out: &Path) -> f64 {
    let leg = read_ply(&out.join("leg.ply"));
    let d: Vec<f64> = leg.payload["vertex"]
        .iter()
        .map(|v| float(v, "stitch_density"))
        .filter(|&d| d > 0.0)
        .collect();
    d.iter().sum::<f64>() / d.len() as f64
}

#[test]
fn a_z_up_leg_fits_like_the_y_up_one_when_the_scene_says_so() {
    let dir = tempfile::tempdir().unwrap();
    // Rotate +90° about X: the file's up becomes +Z.
    let s = std::f32::consts::FRAC_1_SQRT_2;
    let z_up = edited_sample(dir.path(), "z_up.glb", |root| {
        for node in &mut root.nodes {
            node.rotation = Some(gltf_json::scene::UnitQuaternion([s, 0.0, 0.0, s]));
        }
    });
    let scene = dir.path().join("z.json");
    std::fs::write(&scene, r#"{"leg": {"file": "z_up.glb", "up_axis": "+z"}}"#).unwrap();
    let out = knitfit(
        dir.path(),
        &["fit", "z.json", "--resolution", "40x40", "--out", "z", "-q"],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let (y_dir, _) = fit(&procedural_leg(), "40x40", &[]);
    let (z, y) = (
        mean_density(&dir.path().join("z")),
        mean_density(&y_dir.path().join("out")),
    );
    assert!(
        (z - y).abs() < 0.01 * y,
        "+z leg {z} vs +y leg {y} stitches/cm²"
    );
    assert_eq!(
        read_fit_report(&dir.path().join("z")).details.leg.up_axis,
        UpAxis::PosZ
    );
    // Read as +Y, the same file lies on its side: the tube then follows the detected axis, but
    // the report must say what was assumed.
    let _ = z_up;
}

#[test]
fn a_gltf_with_an_external_buffer_loads() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = std::fs::read(procedural_leg()).unwrap();
    let mut gltf = gltf::Gltf::from_slice(&bytes).unwrap();
    let mut root = gltf.document.clone().into_json();
    root.buffers[0].uri = Some("leg.bin".into());
    std::fs::write(dir.path().join("leg.bin"), gltf.blob.take().unwrap()).unwrap();
    std::fs::write(
        dir.path().join("leg.gltf"),
        gltf_json::serialize::to_vec(&root).unwrap(),
    )
    .unwrap();
    let out = knitfit(
        dir.path(),
        &["fit", "--leg", "leg.gltf", "--resolution", "12x12", "-q"],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(
        read_fit_report(&dir.path().join("out"))
            .metrics
            .leg_triangles,
        Some(41216)
    );
}

#[test]
fn axis_from_the_command_line_sets_where_the_stocking_ends() {
    let leg = &procedural_leg();
    let (dir, r) = fit(leg, "40x40", &["--axis", "0,0.30,0,0,0.60,0"]);
    assert_eq!(r.details.axis.source, AxisSource::CommandLine);
    assert!(r.metrics.converged);
    let yarns = read_ply(&dir.path().join("out/stocking.ply"));
    // The knit's points exactly; points the penetration fix inserted within 0.1 mm.
    for (i, v) in yarns.payload["vertex"].iter().enumerate() {
        let y = float(v, "y");
        let slack = if i < 1600 { 1e-6 } else { 1e-4 };
        assert!((0.3 - slack..=0.6 + slack).contains(&y), "yarn at y = {y}");
    }
}

#[test]
fn a_bad_axis_flag_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    for (axis, expect) in [
        ("1,2,3", "expected six numbers"),
        ("0,0.3,0,0,0.3,0", "different points"),
        ("0,nan,0,0,1,0", "finite"),
    ] {
        let out = knitfit(dir.path(), &["fit", "--axis", axis]);
        assert_eq!(out.status.code(), Some(2), "{axis}");
        assert!(stderr(&out).contains(expect), "{axis}: {}", stderr(&out));
    }
    assert!(files_in(&dir.path().join("out")).is_empty());
}

#[test]
fn a_stocking_longer_than_the_axis_is_refused_before_fitting() {
    let dir = tempfile::tempdir().unwrap();
    let leg = procedural_leg().display().to_string();
    std::fs::write(
        dir.path().join("s.json"),
        r#"{"tube": {"relaxed_length_m": 0.9}}"#,
    )
    .unwrap();
    let out = knitfit(dir.path(), &["fit", "s.json", "--leg", &leg]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out)
            .contains("tube.relaxed_length_m: 0.9 m is not shorter than the stocking's centreline"),
        "{}",
        stderr(&out)
    );
    assert!(files_in(&dir.path().join("out")).is_empty());
}

#[test]
fn a_ply_of_partly_concave_quads_reads_as_its_triangles() {
    // Fanned from their first corner, concave quads folded back over the skin: the fit said
    // "converged" with yarn through the leg and density spanning three orders of magnitude.
    let dir = tempfile::tempdir().unwrap();
    for name in ["lowpoly_leg.glb", "makehuman_body.glb"] {
        let leg = load_sample(&sample(name));
        let (text, outside) = leg_as_quads(&leg.positions, &leg.triangles);
        assert!(
            outside.len() > 10,
            "{name}: {} concave quads",
            outside.len()
        );
        let path = dir.path().join(name.replace(".glb", ".ply"));
        std::fs::write(&path, text).unwrap();
        let quads = load_leg(&path, Units::Metres, UpChoice::Axis(UpAxis::PosY)).unwrap();
        assert_eq!(quads.triangles.len(), leg.triangles.len(), "{name}");
        // No concave quad is cut along its outside diagonal (the vertices keep their numbers).
        let edges: std::collections::HashSet<[u32; 2]> = quads
            .triangles
            .iter()
            .flat_map(|t| (0..3).map(move |e| [t[e].min(t[(e + 1) % 3]), t[e].max(t[(e + 1) % 3])]))
            .collect();
        let folded = outside.iter().filter(|d| edges.contains(*d)).count();
        // Fanned, every one folds. Ear-clipped, 2 of the body's 435 still take the outside
        // diagonal (issue 45: not yet understood); at most 1 % is allowed until they are.
        assert!(
            folded * 100 <= outside.len(),
            "{name}: {folded} of {} concave quads folded",
            outside.len()
        );
    }
    let path = dir.path().join("lowpoly_leg.ply");
    let (_dir, r) = fit(&path, "60x60", OPEN_TUBE);
    assert!(r.metrics.converged);
    assert_eq!(r.metrics.max_penetration_m, Some(0.0));
    assert_eq!(r.details.penetration_fix.unwrap().still_crossing, 0);
}

#[test]
fn a_fit_with_yarn_left_through_a_folded_skin_is_written_but_not_done() {
    // The whole body with its concave quads fanned across their outside diagonals: the fit
    // converged with yarn through the leg and density spanning three orders of magnitude, and
    // said "converged", exit 0.
    let dir = tempfile::tempdir().unwrap();
    let (quads, outside) = {
        let body = load_sample(&sample("makehuman_body.glb"));
        leg_as_quads(&body.positions, &body.triangles)
    };
    assert!(outside.len() > 100, "{} concave quads", outside.len());
    let path = dir.path().join("folded.ply");
    std::fs::write(&path, fanned(&quads)).unwrap();
    let out = crate::support::knitfit(
        dir.path(),
        &[
            "fit",
            "--leg",
            path.to_str().unwrap(),
            "--resolution",
            "60x60",
            "-q",
        ],
    );
    let err = crate::support::stderr(&out);
    eprintln!("{err}");
    assert_eq!(out.status.code(), Some(4), "{err}");
    assert!(err.contains("converged but is not sound"), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    let report = crate::support::read_fit_report(&dir.path().join("out"));
    assert!(report.metrics.converged);
    let failures = report.details.checks.failures();
    assert!(
        !failures.is_empty() && err.contains(&failures[0]),
        "{failures:?}\n{err}"
    );
    // The files are written, to show where.
    assert!(dir.path().join("out/stocking.glb").is_file());
}
