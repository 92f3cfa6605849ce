//! Rigged characters: a glTF skin poses the mesh as viewers show it, its joints' names say which
//! leg is which, and a posed leg gets its stocking in the pose (fitted in the rest pose, carried
//! by the skin, relaxed there). The samples are samples/rigged/ (tools/makehuman_rigged.py).

use std::path::{Path, PathBuf};

use knitfit::knit::TubeBottom;
use knitfit::leg::{load_leg, Units, UpAxis, UpChoice};
use knitfit::report::FitDetails;
use nalgebra::Point3;
use serde_json::json;

use crate::support::{
    edited_glb, float, knitfit, load_sample, read_fit_report, read_ply, run_scene, sample,
    scene_for, stage_names, stderr, write_mesh,
};

fn rigged(name: &str) -> PathBuf {
    sample(&format!("rigged/{name}"))
}

/// The left knee joint of the walk sample as posed, metres (tools/makehuman_rigged.py prints it:
/// hip flexed 30°, knee bent 45°).
const WALK_KNEE: [f64; 3] = [0.1354, 0.5148, 0.2299];

#[test]
fn a_skinned_character_is_read_as_its_joints_pose_it_and_keeps_its_rest_pose() {
    let rest = load_sample(&rigged("makehuman_rigged.glb"));
    let walk = load_sample(&rigged("makehuman_rigged_walk.glb"));
    // At rest the joints pose nothing: the mesh as stored, and no rest pose kept beside it.
    assert!(rest.rest.is_none());
    let rig = rest.rig.as_ref().expect("the Mixamo joints are read");
    assert_eq!(rig.naming, "mixamo");
    let (left, right) = (rig.left.unwrap(), rig.right.unwrap());
    assert!(left.knee[0] > 0.1 && right.knee[0] < -0.1, "{rig:?}");
    assert!(left.hip[1] > left.knee[1] && left.knee[1] > left.ankle[1]);
    // The same woman as makehuman_body.glb, standing on y = 0.
    let body = load_sample(&sample("makehuman_body.glb"));
    let (rest_lo, rest_hi) = rest.bounds();
    let (body_lo, body_hi) = body.bounds();
    assert!(rest_lo.y.abs() < 1e-6, "{rest_lo:?}");
    assert!(((rest_hi - rest_lo) - (body_hi - body_lo)).norm() < 1e-5);

    // Posed: the left leg swings forward; its rest pose is the stored mesh.
    let kept = walk
        .rest
        .as_ref()
        .expect("a posed skin keeps its rest pose");
    assert_eq!(kept.leg.positions.len(), rest.positions.len());
    let off = (kept.leg.positions.iter().zip(&rest.positions))
        .map(|(a, b)| (a - b).norm())
        .fold(0.0, f64::max);
    assert!(
        off < 1e-5,
        "the rest pose differs from the rest file by {off} m"
    );
    let knee = walk.rig.as_ref().unwrap().left.unwrap().knee;
    let miss = (0..3)
        .map(|k| (knee[k] - WALK_KNEE[k]).abs())
        .fold(0.0, f64::max);
    assert!(miss < 1e-3, "posed knee {knee:?}, built at {WALK_KNEE:?}");
    let moved: Vec<(f64, f64)> = (walk.positions.iter().zip(&kept.leg.positions))
        .map(|(p, r)| (r.x, (p - r).norm()))
        .collect();
    let left_most = moved.iter().map(|m| m.1).fold(0.0, f64::max);
    // The generator's weights move one right-knee vertex by 0.9 mm (a stray weight it ships).
    let right_most = (moved.iter().filter(|m| m.0 < -0.05))
        .map(|m| m.1)
        .fold(0.0, f64::max);
    assert!(
        left_most > 0.1 && right_most < 0.001,
        "{left_most} {right_most}"
    );
}

#[test]
fn a_rigged_leg_posed_mid_stride_gets_its_stocking_in_the_pose_in_any_frame() {
    // As exported, and with the armature scaled to centimetres (the skin's rest pose is placed
    // as its skeleton is, so it is read in the same units as the pose).
    let dir = tempfile::tempdir().unwrap();
    let walk = rigged("makehuman_rigged_walk.glb");
    let in_cm = edited_glb(&walk, dir.path(), "walk_cm.glb", |root| {
        let armature = (root.nodes.iter_mut())
            .find(|n| n.name.as_deref() == Some("Armature"))
            .unwrap();
        armature.scale = Some([100.0; 3]);
    });
    for (leg, units, scale) in [(walk, "m", 1.0), (in_cm, "cm", 0.01)] {
        let scene = scene_for(&leg, json!({ "units": units }), json!({}));
        // How the leg is read and carried, not how far the solver settles (`solvers.rs`): the
        // zoo's CI grid and tolerance.
        let (dir, out) = run_scene(&scene, "100x100", &["--tolerance", "3e-3"]);
        assert!(out.status.success(), "{units}: {}", stderr(&out));
        let report = read_fit_report(&dir.path().join("out"));
        let pose = report.details.pose.as_ref().expect("the pose stage ran");
        assert!(
            pose.converged && pose.skin_moved_m > 0.1,
            "{units}: {pose:?}"
        );
        assert!(stage_names(&report).contains(&"pose".to_string()));
        assert_eq!(report.metrics.max_penetration_m, Some(0.0));
        assert!(report.details.checks.failures().is_empty(), "{units}");
        // The yarn is on the posed foot, not where the foot stood: at rest the toes reach
        // z = 0.20 m, mid-stride 6 cm further forward.
        let yarn = read_ply(&dir.path().join("out/stocking.ply"));
        let reach = yarn.payload["vertex"]
            .iter()
            .map(|v| float(v, "z"))
            .fold(f64::MIN, f64::max);
        assert!(reach > 0.24, "{units}: the stocking reaches z = {reach} m");
        // The landmarks are the rest pose's, with the rig's joints beside them.
        let landmarks = report.details.leg.landmarks.as_ref().unwrap();
        let rig = landmarks.rig.as_ref().unwrap();
        assert_eq!(rig.naming, "mixamo");
        let file_knee = rig.knee.file[1] * scale;
        assert!((file_knee - 0.4496).abs() < 1e-3, "{units}: {rig:?}");
    }
}

#[test]
fn a_leg_posed_mid_stride_without_its_rig_is_straightened_from_its_sections_and_fitted_in_the_pose()
{
    // Baked (the posed mesh alone, as a tool bakes it): hip flexed 30°, knee bent 45°. Before,
    // it was refused: "the axis placed on the landmarks runs outside the leg".
    let dir = tempfile::tempdir().unwrap();
    let (file, _) = posed_file(dir.path(), Pose::MidStride, Rigging::Baked, RigFrame::ZUp);
    let scene = scene_for(&file, json!({}), json!({}));
    let (run, out) = run_scene(&scene, "100x100", &["--tolerance", "3e-3"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let report = read_fit_report(&run.path().join("out"));
    let pose = report.details.pose.as_ref().expect("the pose stage ran");
    let bend = pose
        .bend
        .as_ref()
        .expect("the geometry's joints straightened it");
    assert!((bend.knee_deg - 45.0).abs() < 15.0, "{bend:?}");
    assert!((bend.thigh_deg - 30.0).abs() < 12.0, "{bend:?}");
    assert!(pose.converged, "{pose:?}");
    assert_eq!(report.metrics.max_penetration_m, Some(0.0));
    assert!(report.details.checks.failures().is_empty());
    // The yarn reaches the posed ball of the foot, where the rig (kept aside) puts it.
    let rigged_leg = load_leg(
        &dir.path().join("rigged.glb"),
        Units::Metres,
        UpChoice::Auto,
    )
    .unwrap();
    let toe = Point3::from(rigged_leg.rig.as_ref().unwrap().left.unwrap().toe.unwrap());
    let yarn = read_ply(&run.path().join("out/stocking.ply"));
    let toe_gap = (yarn.payload["vertex"].iter())
        .map(|v| (Point3::new(float(v, "x"), float(v, "y"), float(v, "z")) - toe).norm())
        .fold(f64::INFINITY, f64::min);
    assert!(
        toe_gap < 0.03,
        "the yarn is {toe_gap} m from the ball of the foot"
    );
    // plan says where the rest pose came from.
    let plan = knitfit(dir.path(), &["plan", "--leg", file.to_str().unwrap()]);
    let said = String::from_utf8_lossy(&plan.stdout);
    assert!(
        said.contains("no rig") && said.contains("straightened"),
        "{said}"
    );
}

#[test]
fn the_rig_names_the_leg_dressed_and_plan_says_the_pose() {
    let leg = rigged("makehuman_rigged.glb");
    let dir = tempfile::tempdir().unwrap();
    for side in ["left", "right"] {
        let out = knitfit(
            dir.path(),
            &[
                "plan",
                "--json",
                "--leg",
                leg.to_str().unwrap(),
                "--side",
                side,
            ],
        );
        assert!(out.status.success(), "{}", stderr(&out));
        let plan: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let rig = &plan["landmarks"]["rig"];
        assert_eq!(rig["side"], side, "{rig}");
        assert_eq!(plan["landmarks"]["side"], side);
        let x = plan["landmarks"]["ankle"]["centre"]["m"][0]
            .as_f64()
            .unwrap();
        assert_eq!(x > 0.0, side == "left", "{side} ankle at x = {x}");
        assert!(
            rig["ankle_from_section_m"].as_f64().unwrap() < 0.06,
            "{rig}"
        );
    }
    let walk = rigged("makehuman_rigged_walk.glb");
    let out = knitfit(dir.path(), &["plan", "--leg", walk.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        text.contains("rest pose's") && text.contains("mixamo joints"),
        "{text}"
    );
}

#[test]
fn a_knee_bent_further_than_the_skin_folds_cleanly_is_said_not_passed_as_done() {
    // The rig's linear blend skinning folds the skin into itself behind a knee bent 90°: the
    // stocking carried there cannot settle clear of it, and the run says so.
    let dir = tempfile::tempdir().unwrap();
    let deep = edited_glb(
        &rigged("makehuman_rigged_walk.glb"),
        dir.path(),
        "deep.glb",
        |root| {
            let knee = (root.nodes.iter_mut())
                .find(|n| n.name.as_deref() == Some("mixamorig:LeftLeg"))
                .unwrap();
            let half = 45f32.to_radians();
            knee.rotation = Some(gltf_json::scene::UnitQuaternion([
                half.sin(),
                0.0,
                0.0,
                half.cos(),
            ]));
        },
    );
    let scene = scene_for(&deep, json!({}), json!({}));
    let (run, out) = run_scene(&scene, "100x100", &["--tolerance", "3e-3"]);
    let code = out.status.code();
    assert!(
        matches!(code, Some(3 | 4)),
        "exit {code:?}: {}",
        stderr(&out)
    );
    let err = stderr(&out);
    assert!(
        err.contains("pose") || err.contains("cross the skin"),
        "{err}"
    );
    let report: knitfit::report::Report<FitDetails> = read_fit_report(&run.path().join("out"));
    assert!(report.details.pose.is_some());
    assert!(report.metrics.residual.is_finite());
}

#[test]
fn a_damaged_skin_is_refused_naming_what_is_wrong() {
    let dir = tempfile::tempdir().unwrap();
    let source = rigged("makehuman_rigged_walk.glb");
    let one_joint = edited_glb(&source, dir.path(), "one_joint.glb", |root| {
        root.skins[0].joints.truncate(1);
    });
    let vec3_binds = edited_glb(&source, dir.path(), "vec3_binds.glb", |root| {
        let positions = root.meshes[0].primitives[0]
            .attributes
            .get(&gltf_json::validation::Checked::Valid(
                gltf_json::mesh::Semantic::Positions,
            ))
            .copied()
            .unwrap();
        root.skins[0].inverse_bind_matrices = Some(positions);
    });
    // Float weights 16 bytes long read 4 bytes apart: gltf's reader asserts on it (a panic).
    let short_stride = edited_glb(&source, dir.path(), "short_stride.glb", |root| {
        let weights = root.meshes[0].primitives[0]
            .attributes
            .get(&gltf_json::validation::Checked::Valid(
                gltf_json::mesh::Semantic::Weights(0),
            ))
            .copied()
            .unwrap();
        let view = root.accessors[weights.value()].buffer_view.unwrap();
        root.buffer_views[view.value()].byte_stride = Some(gltf_json::buffer::Stride(4));
    });
    for (path, says) in [
        (one_joint, "names joint"),
        (vec3_binds, "not float MAT4"),
        (short_stride, "bytes apart but"),
    ] {
        let out = knitfit(dir.path(), &["plan", "--leg", path.to_str().unwrap()]);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{err}");
        let name = path.file_name().unwrap().to_str().unwrap();
        assert!(err.contains(name) && err.contains(says), "{err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
    }
}

/// A pose of the rigged character's left leg: its joints' rotations from rest, degrees about the
/// body's left–right axis (X), or for spreading the legs about the forward axis (Z).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Pose {
    Rest,
    LegsApart,
    HipFlexed40,
    KneeBent30,
    /// Hip 30°, knee 45°: the walk sample.
    MidStride,
    /// Hip 40°, knee 60°.
    MidStrideDeep,
    KneeBent90,
    /// Hip 90°, knee 90°.
    Sitting,
    /// Hip 20°, knee 110°.
    Kneeling,
    /// The foot pointed 45° (a high heel).
    FootPointed,
    /// Both arms raised over the head (the legs at rest): the hands, not the feet, end the
    /// body's slimmer end.
    ArmsRaised,
}

const POSES: [Pose; 11] = [
    Pose::Rest,
    Pose::LegsApart,
    Pose::HipFlexed40,
    Pose::KneeBent30,
    Pose::MidStride,
    Pose::MidStrideDeep,
    Pose::KneeBent90,
    Pose::Sitting,
    Pose::Kneeling,
    Pose::FootPointed,
    Pose::ArmsRaised,
];

impl Pose {
    /// (joint, axis, degrees) set on the rest file's joint nodes.
    fn joints(self) -> Vec<(&'static str, usize, f32)> {
        let (hip, knee, foot) = (
            "mixamorig:LeftUpLeg",
            "mixamorig:LeftLeg",
            "mixamorig:LeftFoot",
        );
        match self {
            Pose::Rest => vec![],
            Pose::LegsApart => vec![(hip, 2, 10.0), ("mixamorig:RightUpLeg", 2, -10.0)],
            Pose::HipFlexed40 => vec![(hip, 0, -40.0)],
            Pose::KneeBent30 => vec![(knee, 0, 30.0)],
            Pose::MidStride => vec![(hip, 0, -30.0), (knee, 0, 45.0)],
            Pose::MidStrideDeep => vec![(hip, 0, -40.0), (knee, 0, 60.0)],
            Pose::KneeBent90 => vec![(knee, 0, 90.0)],
            Pose::Sitting => vec![(hip, 0, -90.0), (knee, 0, 90.0)],
            Pose::Kneeling => vec![(hip, 0, -20.0), (knee, 0, 110.0)],
            Pose::FootPointed => vec![(foot, 0, 45.0)],
            // From the rest's A-pose, 47° below level, to 78° above it.
            Pose::ArmsRaised => vec![
                ("mixamorig:LeftArm", 2, 125.0),
                ("mixamorig:RightArm", 2, -125.0),
            ],
        }
    }
}

/// How the posed character is exported.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Rigging {
    /// With its skin: joints posed, the mesh at rest.
    Rigged,
    /// The posed mesh alone, as a tool bakes it (no skin, no joints).
    Baked,
}

/// The file's frame: what the exporter put on the armature.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum RigFrame {
    AsExported,
    /// The armature turned to Z up.
    ZUp,
    /// The armature scaled to centimetres, read with `--units cm`.
    Centimetres,
    /// The armature turned 120° about up.
    Turned,
}

const RIG_FRAMES: [RigFrame; 4] = [
    RigFrame::AsExported,
    RigFrame::ZUp,
    RigFrame::Centimetres,
    RigFrame::Turned,
];

/// Why a posed variant is known not to fit yet, where it is.
fn pose_known_failing(pose: Pose, rigging: Rigging, frame: RigFrame) -> Option<&'static str> {
    let deep = matches!(
        pose,
        Pose::MidStrideDeep | Pose::KneeBent90 | Pose::Sitting | Pose::Kneeling | Pose::FootPointed
    );
    match rigging {
        Rigging::Rigged if deep => Some(
            "the rig's linear blend skinning folds the skin into itself behind a knee bent past \
             about 60° (and at a pointed foot's toes): the carried stocking crosses it there, \
             exit 3 or 4 (decision 0077)",
        ),
        Rigging::Baked if matches!(pose, Pose::KneeBent90 | Pose::Sitting | Pose::Kneeling) => {
            Some(
                "without its rig, a leg whose foot is lifted is refused (exit 2): its sections \
                 along up do not rise from its foot, and no curve skeleton follows it from \
                 elsewhere yet (issue 45 item 2)",
            )
        }
        Rigging::Baked if pose == Pose::MidStrideDeep && frame == RigFrame::Turned => Some(
            "turned 120°, straightened and carried back, the stocking crosses the skin behind the \
             knee bent 60° (66 pieces, points 3 µm inside), exit 4, as the rigged one turned does",
        ),
        Rigging::Baked if pose == Pose::FootPointed => Some(
            "the foot is read and turned back 41° to stand, and the stocking covers it to the \
             toe, but carried into the pose it crosses a crumpled fold of skin at the little \
             toe (42 pieces, points 18 µm inside), exit 4, as the rigged one does",
        ),
        _ => None,
    }
}

/// The rest file posed by `pose` in `frame`, rigged or baked, written into `dir`; and the
/// `--units` to read it with.
fn posed_file(
    dir: &Path,
    pose: Pose,
    rigging: Rigging,
    frame: RigFrame,
) -> (PathBuf, &'static str) {
    let rigged_file = edited_glb(&rigged("makehuman_rigged.glb"), dir, "rigged.glb", |root| {
        for (name, axis, degrees) in pose.joints() {
            let node = (root.nodes.iter_mut())
                .find(|n| n.name.as_deref() == Some(name))
                .unwrap();
            node.rotation = Some(quaternion(axis, degrees));
        }
        let armature = (root.nodes.iter_mut())
            .find(|n| n.name.as_deref() == Some("Armature"))
            .unwrap();
        match frame {
            RigFrame::AsExported => {}
            RigFrame::ZUp => armature.rotation = Some(quaternion(0, 90.0)),
            RigFrame::Centimetres => armature.scale = Some([100.0; 3]),
            RigFrame::Turned => armature.rotation = Some(quaternion(1, 120.0)),
        }
    });
    let units = if frame == RigFrame::Centimetres {
        "cm"
    } else {
        "m"
    };
    match rigging {
        Rigging::Rigged => (rigged_file, units),
        Rigging::Baked => {
            // The skin as the loader poses it, written back in the file's own frame and units.
            let choice = UpChoice::Axis(if frame == RigFrame::ZUp {
                UpAxis::PosZ
            } else {
                UpAxis::PosY
            });
            let unit = if units == "cm" {
                Units::Centimetres
            } else {
                Units::Metres
            };
            let leg = load_leg(&rigged_file, unit, choice).unwrap();
            let file: Vec<Point3<f64>> = leg
                .positions
                .iter()
                .map(|p| leg.file_from_world(p))
                .collect();
            (
                write_mesh(dir, "baked.glb", &file, leg.triangles.clone()),
                units,
            )
        }
    }
}

/// A unit quaternion turning `degrees` about axis `axis` (0 X, 1 Y, 2 Z).
fn quaternion(axis: usize, degrees: f32) -> gltf_json::scene::UnitQuaternion {
    let half = degrees.to_radians() / 2.0;
    let mut q = [0.0, 0.0, 0.0, half.cos()];
    q[axis] = half.sin();
    gltf_json::scene::UnitQuaternion(q)
}

/// Fits one posed variant at the defaults: its table row, and whether it fits (exit 0, no yarn
/// inside the leg, the checks passed, a stocking to the toe, the yarn within 3 cm of the posed
/// ball of the foot).
fn posed_variant(pose: Pose, rigging: Rigging, frame: RigFrame) -> (String, bool) {
    let dir = tempfile::tempdir().unwrap();
    let (file, units) = posed_file(dir.path(), pose, rigging, frame);
    // `KNITFIT_ZOO_KEEP=DIR` keeps each variant's file, as the zoo does.
    if let Some(keep) = std::env::var_os("KNITFIT_ZOO_KEEP") {
        let name = format!("{pose:?}-{rigging:?}-{frame:?}.glb");
        std::fs::create_dir_all(&keep).unwrap();
        std::fs::copy(&file, Path::new(&keep).join(name)).unwrap();
    }
    // The posed ball of the foot, where the skin's joints put it (world space).
    let rigged_leg = load_leg(
        &dir.path().join("rigged.glb"),
        if units == "cm" {
            Units::Centimetres
        } else {
            Units::Metres
        },
        UpChoice::Auto,
    )
    .unwrap();
    let toe = Point3::from(rigged_leg.rig.as_ref().unwrap().left.unwrap().toe.unwrap());
    let scene = scene_for(&file, json!({ "units": units }), json!({}));
    let run = tempfile::tempdir().unwrap();
    std::fs::write(run.path().join("scene.json"), scene.to_string()).unwrap();
    let started = std::time::Instant::now();
    let out = knitfit(run.path(), &["fit", "scene.json", "-q"]);
    let seconds = started.elapsed().as_secs_f64();
    let name = format!("{pose:?} / {rigging:?} / {frame:?}");
    let code = out.status.code();
    let report_path = run.path().join("out/report.json");
    if !report_path.exists() {
        let why = stderr(&out).lines().last().unwrap_or_default().to_string();
        // The file by its name: the table is the same from run to run.
        let why = why.replace(&format!("{}/", dir.path().display()), "");
        return (
            format!("| {name} | exit {code:?}: {why} | | | | {seconds:.1} |"),
            false,
        );
    }
    let report = read_fit_report(&run.path().join("out"));
    let pose_stage = report.details.pose.as_ref().map_or("–".to_string(), |p| {
        format!("{} it., residual {:.1e}", p.iterations, p.residual)
    });
    // The zoo's scene names no effects, so the penetration fix does not run and nothing is
    // counted: "–", not 0.
    let crossing =
        (report.details.checks.yarn_pieces_crossing).map_or("–".to_string(), |n| n.to_string());
    let yarn = read_ply(&run.path().join("out/stocking.ply"));
    let toe_gap = yarn.payload["vertex"]
        .iter()
        .map(|v| (Point3::new(float(v, "x"), float(v, "y"), float(v, "z")) - toe).norm())
        .fold(f64::INFINITY, f64::min);
    // A stocking: over the foot to its toe, not a tube open where the foot was not found.
    let to_toe = report.details.tube.bottom == TubeBottom::Toe;
    let fits = code == Some(0)
        && report.metrics.max_penetration_m == Some(0.0)
        && report.details.checks.failures().is_empty()
        && toe_gap <= 0.03
        && to_toe;
    let outcome = if fits {
        "fits".to_string()
    } else if code == Some(0) && !to_toe {
        "exit Some(0), open at the ankle: no foot found".to_string()
    } else {
        format!("exit {code:?}")
    };
    (
        format!(
            "| {name} | {outcome} | {pose_stage} | {crossing} | {:.0} | {seconds:.1} |",
            1e3 * toe_gap
        ),
        fits,
    )
}

#[test]
#[ignore = "the posed zoo, 88 fits: the long profile (docs/TESTING.md)"]
fn the_posed_zoo_fits_every_pose_the_skin_bends_cleanly() {
    let only = std::env::var("KNITFIT_ZOO_ONLY").unwrap_or_default();
    let mut rows = vec![
        "| pose / rigging / frame | outcome | pose stage | yarn pieces crossing | yarn to the ball \
         of the foot, mm | seconds |"
            .to_string(),
        "|---|---|---|---:|---:|---:|".to_string(),
    ];
    let (mut fitted, mut total, mut failed, mut known) = (0, 0, Vec::new(), Vec::new());
    for pose in POSES {
        for rigging in [Rigging::Rigged, Rigging::Baked] {
            for frame in RIG_FRAMES {
                let name = format!("{pose:?} / {rigging:?} / {frame:?}");
                if !name.contains(only.as_str()) {
                    continue;
                }
                let (row, fits) = posed_variant(pose, rigging, frame);
                println!("{row}");
                rows.push(row.clone());
                total += 1;
                fitted += usize::from(fits);
                match pose_known_failing(pose, rigging, frame) {
                    None if !fits => failed.push(row),
                    Some(why) if !fits => known.push(format!("{name} ({why})")),
                    _ => {}
                }
            }
        }
    }
    rows.push(String::new());
    rows.push(format!(
        "{fitted} of {total} posed variants fit at the defaults: exit 0, no yarn inside the \
         leg, the fit's checks passed, a stocking to the toe, the yarn within 3 cm of the posed ball \
         of the foot. Known not to fit yet: {}.",
        known.len()
    ));
    rows.extend(known.iter().map(|k| format!("- {k}")));
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("../zoo");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("posed.md"), rows.join("\n") + "\n").unwrap();
    assert!(failed.is_empty(), "{}", failed.join("\n"));
}

#[test]
fn a_posed_leg_without_its_rig_is_refused_saying_so_not_dressed_on_the_other_leg() {
    // Baked (no skin): a knee bent 90° lifts the left foot off the ground. Before, it was
    // fitted on the right leg, exit 0; a deep stride (its foot on its toes) was refused as "up
    // may be the wrong way", and then as "lifted or bent out of standing", until its toes were
    // read as one foot (`a_deep_stride_on_its_toes_is_read_from_its_toes_up`).
    // Sitting and kneeling lift it too.
    for (pose, says, never) in [
        (Pose::KneeBent90, "the only leg standing", "up may be"),
        (Pose::Sitting, "the only leg standing", "up may be"),
        (Pose::Kneeling, "the only leg standing", "up may be"),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let (file, _) = posed_file(dir.path(), pose, Rigging::Baked, RigFrame::AsExported);
        let out = knitfit(dir.path(), &["plan", "--leg", file.to_str().unwrap()]);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{pose:?}: {err}");
        assert!(
            err.contains(says) && !err.contains(never),
            "{pose:?}: {err}"
        );
        assert!(err.contains("rig"), "{pose:?}: {err}");
    }
}

#[test]
fn arms_raised_over_the_head_do_not_turn_the_character_upside_down() {
    // The hands end the slimmer end of the body, which read up from the slimmer end before:
    // the arm was taken for a leg. Rigged or baked, as exported or Z up, up is the feet's.
    for rigging in [Rigging::Rigged, Rigging::Baked] {
        for (frame, axis) in [(RigFrame::AsExported, "+y"), (RigFrame::ZUp, "+z")] {
            let dir = tempfile::tempdir().unwrap();
            let (file, _) = posed_file(dir.path(), Pose::ArmsRaised, rigging, frame);
            let out = knitfit(
                dir.path(),
                &["plan", "--leg", file.to_str().unwrap(), "--json"],
            );
            let case = format!("{rigging:?} {frame:?}");
            assert_eq!(out.status.code(), Some(0), "{case}: {}", stderr(&out));
            let plan: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
            assert_eq!(plan["leg"]["up_axis"], axis, "{case}");
            assert_eq!(plan["landmarks"]["legs_found"], 2, "{case}");
            assert!(!plan["landmarks"]["toe_tip"].is_null(), "{case}");
        }
    }
}

#[test]
fn a_deep_stride_on_its_toes_is_read_from_its_toes_up() {
    // Baked, hip 40° and knee 60°: the back foot stands on its toes, cut by the lowest
    // sections as two loops a few centimetres apart. Read as one foot, the leg is followed up
    // from it to the crotch (its girth jumping as the toes meet the foot is not the crotch), and
    // straightened at the knee its sections show.
    let dir = tempfile::tempdir().unwrap();
    let (file, _) = posed_file(
        dir.path(),
        Pose::MidStrideDeep,
        Rigging::Baked,
        RigFrame::AsExported,
    );
    let out = knitfit(
        dir.path(),
        &["plan", "--leg", file.to_str().unwrap(), "--json"],
    );
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let plan: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let bend = &plan["leg"]["straightened"];
    let knee = bend["knee_deg"].as_f64().unwrap();
    let thigh = bend["thigh_deg"].as_f64().unwrap();
    assert!((knee - 60.0).abs() < 10.0, "{bend}");
    assert!((thigh - 40.0).abs() < 10.0, "{bend}");
    assert_eq!(plan["landmarks"]["thigh_top_kind"], "crotch", "{plan}");
}
