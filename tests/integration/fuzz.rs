//! Fuzzing the readers and the PLY writer with proptest over mutated inputs: the glTF leg loader
//! (the bundled legs and a small tube, bit-flipped, truncated, with JSON chunks spliced from
//! another file or edited at random, and binary data overwritten with NaN, infinities and
//! out-of-range indices), the PLY leg loader (the small tube in each encoding, bit-flipped,
//! truncated, with header lines replaced and payload overwritten), the scene parser (the bundled scene, edited and mangled), and the PLY
//! writers' inputs (non-finite values, empty parts, bad attributes). Nothing may panic; a
//! refusal is one line naming the file; what is accepted or written holds no NaN. The command
//! line's side of it (exit code 2, nothing written) is checked on a few of the malformed files.

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::OnceLock;

use knitfit::base::{Direction, Segment, SurfaceMesh, YarnGeometry, YarnKind};
use knitfit::export::ply::{write_mesh_ply, write_ply};
use knitfit::leg::load::{MAX_COORDINATE_M, PLAUSIBLE_HEIGHT_M};
use knitfit::leg::{load_leg, Collider, ContactMethod, Leg, Units, UpAxis, UpChoice};
use knitfit::{Error, Scene};
use ply_rs_bw::ply::Encoding;
use proptest::prelude::*;
use serde_json::{json, Value};

use crate::support::prop_config::config;
use crate::support::{
    base64, files_in, knitfit, leg_as_ply, load_sample, sample_legs, stderr, write_tube_leg,
};

// ---------------------------------------------------------------------------------------------
// GLB files and how to take them apart

/// The chunks of a GLB file: its JSON and its binary buffer.
#[derive(Clone, Debug)]
pub(crate) struct Glb {
    pub(crate) json: Value,
    pub(crate) bin: Vec<u8>,
}

impl Glb {
    pub(crate) fn parse(bytes: &[u8]) -> Glb {
        let u32_at = |i: usize| u32::from_le_bytes(bytes[i..i + 4].try_into().unwrap()) as usize;
        let json_len = u32_at(12);
        let json = serde_json::from_slice(&bytes[20..20 + json_len]).unwrap();
        let bin_at = 20 + json_len;
        let bin = if bytes.len() > bin_at {
            bytes[bin_at + 8..bin_at + 8 + u32_at(bin_at)].to_vec()
        } else {
            Vec::new()
        };
        Glb { json, bin }
    }

    /// The file, with a consistent header and chunk lengths.
    pub(crate) fn bytes(&self) -> Vec<u8> {
        let mut json = serde_json::to_vec(&self.json).unwrap();
        while !json.len().is_multiple_of(4) {
            json.push(b' ');
        }
        let mut bin = self.bin.clone();
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        let total = 12 + 8 + json.len() + if bin.is_empty() { 0 } else { 8 + bin.len() };
        let mut out = Vec::with_capacity(total);
        out.extend(b"glTF");
        out.extend(2u32.to_le_bytes());
        out.extend((total as u32).to_le_bytes());
        out.extend((json.len() as u32).to_le_bytes());
        out.extend(b"JSON");
        out.extend(json);
        if !bin.is_empty() {
            out.extend((bin.len() as u32).to_le_bytes());
            out.extend(b"BIN\0");
            out.extend(bin);
        }
        out
    }
}

/// A small leg (an open tube, 0.8 m tall, 64 triangles) written by our own glTF writer, so that
/// most cases are cheap.
pub(crate) fn small_tube_glb() -> Vec<u8> {
    let dir = tempfile::tempdir().unwrap();
    let path = write_tube_leg(dir.path(), "tube.glb", 8, 4, |t, angle| {
        [0.05 * angle.cos(), 0.8 * t, -0.05 * angle.sin()]
    });
    std::fs::read(path).unwrap()
}

/// The files mutations start from: the small tube first, then every bundled leg.
fn originals() -> &'static [Vec<u8>] {
    static ORIGINALS: OnceLock<Vec<Vec<u8>>> = OnceLock::new();
    ORIGINALS.get_or_init(|| {
        let mut all = vec![small_tube_glb()];
        all.extend(sample_legs().iter().map(|p| std::fs::read(p).unwrap()));
        all
    })
}

/// Values that break assumptions: huge, negative, fractional, subnormal, of the wrong type.
pub(crate) fn nasty_value() -> impl Strategy<Value = Value> {
    prop_oneof![
        Just(json!(0)),
        Just(json!(1)),
        Just(json!(-1)),
        Just(json!(3)),
        Just(json!(4_294_967_295u64)),
        Just(json!(2_147_483_648u64)),
        Just(json!(9_007_199_254_740_993u64)),
        Just(json!(u64::MAX)),
        Just(json!(1e308)),
        Just(json!(-1e308)),
        Just(json!(1e-320)),
        Just(json!(0.5)),
        Just(json!(null)),
        Just(json!(true)),
        Just(json!("")),
        Just(json!("VEC2")),
        Just(json!("data:application/octet-stream;base64,AAAA")),
        Just(json!("../../../nonexistent.bin")),
        Just(json!([])),
        Just(json!([0, 0, 0])),
        Just(json!([1e308, 1e308, 1e308, 1e308])),
        Just(json!({})),
        (0u64..100_000).prop_map(|n| json!(n)),
    ]
}

/// One edit of a GLB's JSON: the `at`-th node of the tree (in document order, wrapping) is
/// replaced by `value`, or, when it is an object or array, loses or gains a member.
#[derive(Clone, Debug)]
pub(crate) enum JsonEdit {
    Replace {
        at: usize,
        value: Value,
    },
    Remove {
        at: usize,
        member: usize,
    },
    Insert {
        at: usize,
        key: String,
        value: Value,
    },
}

pub(crate) fn json_edit() -> impl Strategy<Value = JsonEdit> {
    let key = prop_oneof![
        Just("count"),
        Just("byteOffset"),
        Just("byteStride"),
        Just("byteLength"),
        Just("indices"),
        Just("children"),
        Just("matrix"),
        Just("sparse"),
        Just("extensionsRequired"),
        Just("mode"),
        Just("unknown_field"),
    ];
    prop_oneof![
        3 => (any::<usize>(), nasty_value()).prop_map(|(at, value)| JsonEdit::Replace { at, value }),
        1 => (any::<usize>(), any::<usize>()).prop_map(|(at, member)| JsonEdit::Remove { at, member }),
        1 => (any::<usize>(), key, nasty_value()).prop_map(|(at, key, value)| JsonEdit::Insert {
            at,
            key: key.into(),
            value,
        }),
    ]
}

/// Applies `f` to the `target`-th node of `v` in document order (`index` counts the nodes
/// passed); true once it has.
fn visit(v: &mut Value, index: &mut usize, target: usize, f: &mut dyn FnMut(&mut Value)) -> bool {
    if *index == target {
        f(v);
        return true;
    }
    *index += 1;
    match v {
        Value::Array(items) => items.iter_mut().any(|x| visit(x, index, target, f)),
        Value::Object(members) => members.values_mut().any(|x| visit(x, index, target, f)),
        _ => false,
    }
}

fn node_count(v: &Value) -> usize {
    1 + match v {
        Value::Array(items) => items.iter().map(node_count).sum(),
        Value::Object(members) => members.values().map(node_count).sum(),
        _ => 0,
    }
}

impl JsonEdit {
    pub(crate) fn apply(&self, json: &mut Value) {
        let n = node_count(json);
        match self {
            JsonEdit::Replace { at, value } => {
                visit(json, &mut 0, at % n, &mut |v| *v = value.clone())
            }
            JsonEdit::Remove { at, member } => visit(json, &mut 0, at % n, &mut |v| match v {
                Value::Array(items) if !items.is_empty() => {
                    items.remove(member % items.len());
                }
                Value::Object(members) if !members.is_empty() => {
                    let key = members.keys().nth(member % members.len()).unwrap().clone();
                    members.remove(&key);
                }
                _ => {}
            }),
            JsonEdit::Insert { at, key, value } => visit(json, &mut 0, at % n, &mut |v| match v {
                Value::Object(members) => {
                    members.insert(key.clone(), value.clone());
                }
                Value::Array(items) => items.push(value.clone()),
                _ => {}
            }),
        };
    }
}

/// How a file is damaged.
#[derive(Clone, Debug)]
enum Mutation {
    /// Bits flipped at these places (fractions of the length) and bit numbers.
    FlipBits(Vec<(f64, u8)>),
    /// Cut at this fraction of the length.
    Truncate(f64),
    /// The JSON chunk of another original with this file's binary buffer.
    Splice(usize),
    /// Edits of the JSON, in a well-formed GLB.
    Json(Vec<JsonEdit>),
    /// 4-byte words of the binary buffer (at these fractions) overwritten: NaN, infinities, and
    /// indices past any vertex.
    Bin(Vec<(f64, u32)>),
    /// Written as a `.gltf` (JSON text) with the buffer as a data URI, then JSON-edited.
    Gltf(Vec<JsonEdit>),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    let word = prop_oneof![
        Just(f32::NAN.to_bits()),
        Just(f32::INFINITY.to_bits()),
        Just(f32::NEG_INFINITY.to_bits()),
        Just(f32::MAX.to_bits()),
        Just(u32::MAX),
        Just(0x8000_0000),
        Just(0x0000_ffff),
        any::<u32>(),
    ];
    prop_oneof![
        proptest::collection::vec((0.0f64..1.0, 0u8..8), 1..16).prop_map(Mutation::FlipBits),
        (0.0f64..1.0).prop_map(Mutation::Truncate),
        any::<usize>().prop_map(Mutation::Splice),
        proptest::collection::vec(json_edit(), 1..6).prop_map(Mutation::Json),
        proptest::collection::vec((0.0f64..1.0, word), 1..8).prop_map(Mutation::Bin),
        proptest::collection::vec(json_edit(), 0..4).prop_map(Mutation::Gltf),
    ]
}

/// The damaged file's bytes and the extension it is written with.
fn mutate(original: &[u8], m: &Mutation) -> (Vec<u8>, &'static str) {
    let at = |f: f64, len: usize| ((f * len as f64) as usize).min(len.saturating_sub(1));
    match m {
        Mutation::FlipBits(flips) => {
            let mut bytes = original.to_vec();
            for &(f, bit) in flips {
                let i = at(f, bytes.len());
                bytes[i] ^= 1 << bit;
            }
            (bytes, "glb")
        }
        Mutation::Truncate(f) => (original[..at(*f, original.len())].to_vec(), "glb"),
        Mutation::Splice(other) => {
            let donor = Glb::parse(&originals()[other % originals().len()]);
            let glb = Glb {
                json: donor.json,
                bin: Glb::parse(original).bin,
            };
            (glb.bytes(), "glb")
        }
        Mutation::Json(edits) => {
            let mut glb = Glb::parse(original);
            for e in edits {
                e.apply(&mut glb.json);
            }
            (glb.bytes(), "glb")
        }
        Mutation::Bin(words) => {
            let mut glb = Glb::parse(original);
            for &(f, w) in words {
                let i = at(f, glb.bin.len() / 4) * 4;
                glb.bin[i..i + 4].copy_from_slice(&w.to_le_bytes());
            }
            (glb.bytes(), "glb")
        }
        Mutation::Gltf(edits) => {
            let glb = Glb::parse(original);
            let mut json = glb.json;
            json["buffers"][0] = json!({
                "byteLength": glb.bin.len(),
                "uri": format!("data:application/octet-stream;base64,{}", base64(&glb.bin)),
            });
            for e in edits {
                e.apply(&mut json);
            }
            (serde_json::to_vec(&json).unwrap(), "gltf")
        }
    }
}

/// Loads `bytes` as a leg file and checks the contract: a leg with finite vertices, triangles
/// between them and a plausible height that the collider can take, or a one-line
/// [`Error::Leg`] / [`Error::Read`] naming the file (exit code 2).
fn check_loader(bytes: &[u8], extension: &str) -> Result<(), TestCaseError> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(format!("leg.{extension}"));
    std::fs::write(&path, bytes).unwrap();
    match load_leg(&path, Units::Metres, UpChoice::Axis(UpAxis::PosY)) {
        Ok(leg) => check_leg(&leg),
        Err(e) => check_refusal(&e, &path),
    }
}

fn check_leg(leg: &Leg) -> Result<(), TestCaseError> {
    prop_assert!(!leg.triangles.is_empty());
    prop_assert!(leg
        .positions
        .iter()
        .all(|p| p.iter().all(|c| c.is_finite())));
    let n = leg.positions.len() as u32;
    prop_assert!(leg.triangles.iter().flatten().all(|&i| i < n));
    let (lo, hi) = leg.bounds();
    let (min, max) = PLAUSIBLE_HEIGHT_M;
    prop_assert!((min..=max).contains(&(hi.y - lo.y)));
    prop_assert!(leg
        .positions
        .iter()
        .all(|p| p.iter().all(|c| c.abs() <= MAX_COORDINATE_M)));
    // What the fit does next: the collider, then a query; a refusal must be an error too.
    match Collider::new(leg, ContactMethod::Bvh) {
        Ok(collider) => {
            let c = collider.closest(&nalgebra::center(&lo, &hi));
            prop_assert!(c.signed_distance.is_finite());
        }
        Err(e) => check_refusal(&e, &leg.path)?,
    }
    Ok(())
}

fn check_refusal(e: &Error, path: &Path) -> Result<(), TestCaseError> {
    let text = e.to_string();
    prop_assert!(matches!(e, Error::Leg { .. } | Error::Read { .. }), "{e:?}");
    prop_assert_eq!(e.exit_code(), 2);
    prop_assert_eq!(text.lines().count(), 1, "one line: {}", text);
    prop_assert!(
        text.starts_with(&path.display().to_string()),
        "names the file: {}",
        text
    );
    Ok(())
}

proptest! {
    #![proptest_config(config(2500))]

    /// Whatever is done to a leg file, loading it either gives a usable leg or refuses it with
    /// one line naming the file; it never panics.
    #[test]
    fn a_damaged_leg_file_loads_or_is_refused_cleanly(
        original in 0..originals().len(),
        // The small tube most of the time: the bundled legs are larger, so slower to load.
        small in prop::bool::weighted(0.9),
        m in mutation(),
    ) {
        let bytes = &originals()[if small { 0 } else { original }];
        let (damaged, extension) = mutate(bytes, &m);
        check_loader(&damaged, extension)?;
    }
}

// ---------------------------------------------------------------------------------------------
// PLY leg files

/// The small tube as PLY, in each encoding: binary little-endian (knitfit's own writer), binary
/// big-endian and ASCII.
pub(crate) fn ply_originals() -> &'static [Vec<u8>] {
    static ORIGINALS: OnceLock<Vec<Vec<u8>>> = OnceLock::new();
    ORIGINALS.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        let glb = dir.path().join("tube.glb");
        std::fs::write(&glb, small_tube_glb()).unwrap();
        let tube = load_sample(&glb);
        [
            Encoding::BinaryLittleEndian,
            Encoding::BinaryBigEndian,
            Encoding::Ascii,
        ]
        .map(|encoding| leg_as_ply(&tube, encoding))
        .to_vec()
    })
}

/// Header lines that break a PLY reader's assumptions: huge or zero counts, elements without
/// properties, coordinates and indices of the wrong type, lists counted by floats, another
/// encoding than the payload's.
const NASTY_HEADER_LINES: [&str; 14] = [
    "element vertex 4294967296",
    "element vertex 0",
    "element face 18446744073709551615",
    "element face 0",
    "element junk 1000000000",
    "element junk 3\nproperty list uint uchar stuff",
    "property int x",
    "property double y",
    "property list uint int vertex_indices",
    "property list float int vertex_indices",
    "property list uchar float vertex_indices",
    "format binary_big_endian 1.0",
    "format ascii 1.0",
    "",
];

/// How a PLY file is damaged.
#[derive(Clone, Debug)]
enum PlyMutation {
    /// Bits flipped at these places (fractions of the length) and bit numbers.
    FlipBits(Vec<(f64, u8)>),
    /// Cut at this fraction of the length.
    Truncate(f64),
    /// Header lines (at these fractions of the header's lines) replaced by nasty ones.
    Header(Vec<(f64, usize)>),
    /// 4-byte words of the payload (at these fractions) overwritten: NaN, infinities, and
    /// indices past any vertex, as in the binary buffer of a GLB.
    Payload(Vec<(f64, u32)>),
}

fn ply_mutation() -> impl Strategy<Value = PlyMutation> {
    let word = prop_oneof![
        Just(f32::NAN.to_bits()),
        Just(f32::INFINITY.to_bits()),
        Just(u32::MAX),
        Just(0x8000_0000),
        Just(0x0000_ffff),
        any::<u32>(),
    ];
    prop_oneof![
        proptest::collection::vec((0.0f64..1.0, 0u8..8), 1..16).prop_map(PlyMutation::FlipBits),
        (0.0f64..1.0).prop_map(PlyMutation::Truncate),
        proptest::collection::vec((0.0f64..1.0, 0..NASTY_HEADER_LINES.len()), 1..4)
            .prop_map(PlyMutation::Header),
        proptest::collection::vec((0.0f64..1.0, word), 1..8).prop_map(PlyMutation::Payload),
    ]
}

fn mutate_ply(original: &[u8], m: &PlyMutation) -> Vec<u8> {
    let at = |f: f64, len: usize| ((f * len as f64) as usize).min(len.saturating_sub(1));
    let marker = b"end_header\n";
    let payload = marker.len()
        + original
            .windows(marker.len())
            .position(|w| w == marker)
            .unwrap();
    match m {
        PlyMutation::FlipBits(flips) => {
            let mut bytes = original.to_vec();
            for &(f, bit) in flips {
                let i = at(f, bytes.len());
                bytes[i] ^= 1 << bit;
            }
            bytes
        }
        PlyMutation::Truncate(f) => original[..at(*f, original.len())].to_vec(),
        PlyMutation::Header(edits) => {
            let header = std::str::from_utf8(&original[..payload]).unwrap();
            let mut lines: Vec<&str> = header.lines().collect();
            for &(f, nasty) in edits {
                // Never the first line ("ply") or the last ("end_header").
                let i = 1 + at(f, lines.len() - 2);
                lines[i] = NASTY_HEADER_LINES[nasty];
            }
            let mut bytes = format!("{}\n", lines.join("\n")).into_bytes();
            bytes.extend(&original[payload..]);
            bytes
        }
        PlyMutation::Payload(words) => {
            let mut bytes = original.to_vec();
            let body = bytes.len() - payload;
            for &(f, w) in words {
                let i = payload + at(f, body / 4) * 4;
                bytes[i..i + 4].copy_from_slice(&w.to_le_bytes());
            }
            bytes
        }
    }
}

proptest! {
    #![proptest_config(config(1500))]

    /// Whatever is done to a PLY leg file, loading it either gives a usable leg or refuses it
    /// with one line naming the file; it never panics, loops or allocates past the file.
    #[test]
    fn a_damaged_ply_leg_file_loads_or_is_refused_cleanly(
        original in 0..ply_originals().len(),
        m in ply_mutation(),
    ) {
        let damaged = mutate_ply(&ply_originals()[original], &m);
        check_loader(&damaged, "ply")?;
    }
}

// ---------------------------------------------------------------------------------------------
// The scene parser

/// The bundled scene with every optional part filled in (the preview's render settings with a
/// camera, an axis and a contact offset), so edits reach every field.
fn full_scene() -> Value {
    let mut scene: Value = serde_json::from_str(knitfit::scene::BUNDLED_SCENE).unwrap();
    scene["render"] = json!({
        "width": 64, "height": 64, "view": "front", "spp": 2, "mode": "yarn",
        "camera": { "position": [0.0, 0.5, 2.0], "target": [0.0, 0.5, 0.0], "fov_deg": 25.0 }
    });
    scene["leg"]["axis"] = json!({ "bottom": [0.0, 0.1, 0.0], "top": [0.0, 0.8, 0.0] });
    scene["contact"] = json!({ "method": "bvh", "offset_m": 0.00003 });
    scene["tube"]["relaxed_length_m"] = json!(0.5);
    scene
}

/// How a scene text is damaged: JSON edits, then perhaps bytes flipped or the text cut.
#[derive(Clone, Debug)]
struct SceneDamage {
    edits: Vec<JsonEdit>,
    flips: Vec<(f64, u8)>,
    cut: Option<f64>,
}

fn scene_damage() -> impl Strategy<Value = SceneDamage> {
    (
        proptest::collection::vec(json_edit(), 0..6),
        proptest::collection::vec((0.0f64..1.0, 0u8..7), 0..3),
        proptest::option::weighted(0.1, 0.0f64..1.0),
    )
        .prop_map(|(edits, flips, cut)| SceneDamage { edits, flips, cut })
}

proptest! {
    #![proptest_config(config(1024))]

    /// Any scene text is parsed into a scene that passes its own checks, or refused with one
    /// line that starts with the file's name; never a panic.
    #[test]
    fn a_damaged_scene_parses_or_is_refused_cleanly(damage in scene_damage()) {
        let mut scene = full_scene();
        for e in &damage.edits {
            e.apply(&mut scene);
        }
        let mut bytes = serde_json::to_vec_pretty(&scene).unwrap();
        for &(f, bit) in &damage.flips {
            let i = ((f * bytes.len() as f64) as usize).min(bytes.len() - 1);
            bytes[i] ^= 1 << bit; // bits 0–6: stays ASCII, so stays UTF-8
        }
        if let Some(f) = damage.cut {
            bytes.truncate((f * bytes.len() as f64) as usize);
        }
        let text = String::from_utf8(bytes).unwrap();
        match Scene::from_json(&text, "s.json") {
            Ok(scene) => {
                prop_assert!(scene.validate().is_ok());
                // What every command does next with a scene: its plan.
                let _ = knitfit::plan::Plan::fit(&scene);
            }
            Err(e) => {
                let message = e.to_string();
                prop_assert_eq!(e.exit_code(), 2);
                prop_assert_eq!(message.lines().count(), 1, "one line: {}", message);
                prop_assert!(message.starts_with("s.json"), "{}", message);
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// The PLY writers' inputs

/// Coordinates and attribute values with non-finite and out-of-`f32`-range ones among them.
fn wild_f64() -> impl Strategy<Value = f64> {
    prop_oneof![
        8 => -10.0f64..10.0,
        1 => Just(f64::NAN),
        1 => Just(f64::INFINITY),
        1 => Just(-1e300),
        1 => Just(3.5e38),
        1 => Just(1e-320),
    ]
}

fn wild_f32() -> impl Strategy<Value = f32> {
    prop_oneof![8 => -10.0f32..10.0, 1 => Just(f32::NAN), 1 => Just(f32::NEG_INFINITY)]
}

fn attribute_name() -> impl Strategy<Value = String> {
    prop_oneof![
        Just("course".to_string()),
        Just("tension".to_string()),
        Just("x".to_string()),
        Just("part".to_string()),
        Just("Bad Name".to_string()),
        Just(String::new()),
        "[a-z][a-z0-9_]{0,6}",
    ]
}

/// Attributes over about `n` points: the right length mostly, sometimes one off.
fn attributes(n: usize) -> impl Strategy<Value = BTreeMap<String, Vec<f32>>> {
    proptest::collection::btree_map(
        attribute_name(),
        prop_oneof![
            6 => proptest::collection::vec(prop_oneof![20 => -10.0f32..10.0, 1 => wild_f32()], n),
            1 => proptest::collection::vec(wild_f32(), 0..n + 2),
        ],
        0..4,
    )
}

fn yarn_geometry() -> impl Strategy<Value = YarnGeometry> {
    (0usize..8).prop_flat_map(|n| {
        (
            proptest::collection::vec(
                prop::array::uniform3(prop_oneof![12 => -1.0f64..1.0, 1 => wild_f64()]),
                n,
            ),
            prop::array::uniform3(prop_oneof![12 => -1.0f64..1.0, 1 => wild_f64()]),
            attributes(n),
            proptest::collection::vec(
                (
                    0u32..n as u32 + 2,
                    0u32..n as u32 + 2,
                    any::<bool>(),
                    any::<bool>(),
                ),
                0..2 * n + 1,
            ),
        )
            .prop_map(
                |(positions, offset_m, point_attributes, segments)| YarnGeometry {
                    name: "part".into(),
                    offset_m,
                    positions,
                    point_attributes,
                    segments: segments
                        .into_iter()
                        .map(|(a, b, support, wale)| Segment {
                            a,
                            b,
                            yarn: if support {
                                YarnKind::Support
                            } else {
                                YarnKind::Nylon
                            },
                            direction: if wale {
                                Direction::Wale
                            } else {
                                Direction::Course
                            },
                        })
                        .collect(),
                },
            )
    })
}

fn surface_mesh() -> impl Strategy<Value = SurfaceMesh> {
    (0usize..8).prop_flat_map(|n| {
        (
            proptest::collection::vec(
                prop::array::uniform3(prop_oneof![12 => -1.0f64..1.0, 1 => wild_f64()]),
                n,
            ),
            proptest::collection::vec(prop::array::uniform3(0u32..n as u32 + 1), 0..2 * n + 1),
            attributes(n),
            proptest::option::of(proptest::collection::vec(
                prop::array::uniform3(prop_oneof![20 => 0.0f32..1.0, 1 => wild_f32()]),
                n,
            )),
            proptest::option::of(proptest::collection::vec(
                prop_oneof![20 => 0.0f32..1.0, 1 => wild_f32()],
                n,
            )),
            any::<bool>(),
        )
            .prop_map(
                |(positions, triangles, point_attributes, colours, opacity, drop_normal)| {
                    let mut mesh = SurfaceMesh::new("leg", positions, triangles);
                    mesh.point_attributes = point_attributes;
                    mesh.colours = colours;
                    mesh.opacity = opacity;
                    if drop_normal {
                        mesh.normals.pop();
                    }
                    mesh
                },
            )
    })
}

fn comment() -> impl Strategy<Value = String> {
    prop_oneof![
        Just("made by knitfit".to_string()),
        Just("two\nlines".to_string()),
        Just("ünïcödé ✓".to_string()),
        Just(String::new()),
        Just("end\r".to_string())
    ]
}

/// Parses PLY bytes and checks that every float in them is finite and the element counts are
/// `vertices` and `others`.
fn check_ply(bytes: &[u8], vertices: usize, others: (&str, usize)) -> Result<(), TestCaseError> {
    use ply_rs_bw::ply::{DefaultElement, Property};
    let ply = ply_rs_bw::parser::Parser::<DefaultElement>::new()
        .read_ply(&mut &bytes[..])
        .map_err(|e| TestCaseError::fail(format!("written PLY does not parse: {e}")))?;
    prop_assert_eq!(ply.payload["vertex"].len(), vertices);
    prop_assert_eq!(ply.payload[others.0].len(), others.1);
    for element in ply.payload.values().flatten() {
        for (name, value) in element.iter() {
            if let Property::Float(v) = value {
                prop_assert!(v.is_finite(), "{} = {}", name, v);
            }
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(config(512))]

    /// The yarn PLY writer refuses bad geometry with [`Error::Encode`] or writes a file that
    /// parses, with every point and segment and only finite numbers.
    #[test]
    fn the_yarn_ply_writer_refuses_or_writes_a_valid_file(
        parts in proptest::collection::vec(yarn_geometry(), 0..3),
        comments in proptest::collection::vec(comment(), 0..2),
    ) {
        match write_ply(&parts, &comments) {
            Ok(bytes) => {
                let points = parts.iter().map(|p| p.positions.len()).sum();
                let segments = parts.iter().map(|p| p.segments.len()).sum();
                check_ply(&bytes, points, ("edge", segments))?;
            }
            Err(e) => prop_assert!(matches!(e, Error::Encode { .. }), "{e:?}"),
        }
    }

    /// The same for the surface PLY writer.
    #[test]
    fn the_mesh_ply_writer_refuses_or_writes_a_valid_file(
        mesh in surface_mesh(),
        comments in proptest::collection::vec(comment(), 0..2),
    ) {
        match write_mesh_ply(&mesh, &comments) {
            Ok(bytes) => check_ply(&bytes, mesh.positions.len(), ("face", mesh.triangles.len()))?,
            Err(e) => prop_assert!(matches!(e, Error::Encode { .. }), "{e:?}"),
        }
    }
}

// ---------------------------------------------------------------------------------------------
// The command line on malformed files

/// A few damaged legs and scenes, each run through `knitfit fit`: exit code 2, one line on
/// standard error naming the file, and no output directory.
#[test]
fn the_command_line_refuses_malformed_files_with_one_line_and_writes_nothing() {
    let tube = &originals()[0];
    let mut nan_positions = Glb::parse(tube);
    for word in nan_positions.bin.chunks_exact_mut(4).take(24) {
        word.copy_from_slice(&f32::NAN.to_bits().to_le_bytes());
    }
    let mut huge_count = Glb::parse(tube);
    huge_count.json["accessors"][0]["count"] = json!(4_294_967_295u64);
    let mut past_the_end = Glb::parse(tube);
    past_the_end.json["bufferViews"][0]["byteOffset"] = json!(1_000_000_000);
    let legs: Vec<(&str, Vec<u8>)> = vec![
        ("truncated.glb", tube[..tube.len() / 2].to_vec()),
        ("header_only.glb", tube[..12].to_vec()),
        ("nan_positions.glb", nan_positions.bytes()),
        ("huge_count.glb", huge_count.bytes()),
        ("past_the_end.glb", past_the_end.bytes()),
        ("text.glb", b"not a leg".to_vec()),
    ];
    for (name, bytes) in legs {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join(name), bytes).unwrap();
        refused(dir.path(), &["fit", "--leg", name, "-q"], name);
    }
    let scenes = [
        ("cut.json", "{\"knit\": {\"pattern\": \"pla"),
        ("huge.json", "{\"tube\": {\"wales\": 1e400}}"),
        ("nan.json", "{\"knit\": {\"course_spacing_m\": NaN}}"),
        ("wrong_type.json", "{\"outputs\": \"ply\"}"),
        ("deep.json", &"[".repeat(100_000)),
    ];
    for (name, text) in scenes {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join(name), text).unwrap();
        refused(dir.path(), &["fit", name, "-q"], name);
    }
}

/// Runs knitfit in `dir` expecting exit code 2, one line naming `file`, and no `out/`.
fn refused(dir: &Path, args: &[&str], file: &str) {
    let out = knitfit(dir, args);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{file}: {err}");
    assert_eq!(err.lines().count(), 1, "{file}: one line: {err}");
    assert!(err.contains(file), "{file}: names the file: {err}");
    assert!(
        files_in(&dir.join("out")).is_empty(),
        "{file}: nothing written"
    );
}

/// Found by `the_mesh_ply_writer_refuses_or_writes_a_valid_file`: building the mesh to write
/// (its normals) panicked on a triangle past the last vertex, before the writer could refuse it.
#[test]
fn regression_a_triangle_past_the_last_vertex_is_refused_not_a_panic() {
    let mesh = SurfaceMesh::new("leg", vec![[0.0; 3]; 2], vec![[0, 1, 2]]);
    let err = write_mesh_ply(&mesh, &[]).unwrap_err();
    assert!(
        err.to_string().contains("past the last of 2 vertices"),
        "{err}"
    );
}

/// Found by `the_yarn_ply_writer_refuses_or_writes_a_valid_file`: a finite position beyond
/// `f32`'s range passed the checks and was written as an infinity.
#[test]
fn regression_a_position_beyond_f32_range_is_refused_not_written_as_infinity() {
    let part = YarnGeometry {
        name: "part".into(),
        offset_m: [0.0; 3],
        positions: vec![[3.5e38, 0.0, 0.0]],
        point_attributes: BTreeMap::new(),
        segments: vec![],
    };
    let result = write_ply(&[part], &[]);
    assert!(result.is_err(), "{result:?}");
    let mesh = SurfaceMesh::new("leg", vec![[0.0, -3.5e38, 0.0]; 3], vec![[0, 1, 2]]);
    let result = write_mesh_ply(&mesh, &[]);
    assert!(result.is_err(), "{result:?}");
}

/// Found by `a_damaged_leg_file_loads_or_is_refused_cleanly` (at 5000 cases): a POSITION
/// attribute naming an accessor past the last one panicked inside the glTF validator.
#[test]
fn regression_a_position_accessor_past_the_last_is_refused_not_a_panic() {
    let mut glb = Glb::parse(&originals()[0]);
    let accessors = glb.json["accessors"].as_array().unwrap().len();
    glb.json["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(accessors);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("leg.glb");
    std::fs::write(&path, glb.bytes()).unwrap();
    let err = load_leg(&path, Units::Metres, UpChoice::Axis(UpAxis::PosY)).unwrap_err();
    assert!(err.to_string().contains("POSITION names accessor"), "{err}");
}

/// Found by `a_damaged_leg_file_loads_or_is_refused_cleanly` (at 20000 cases): a primitive
/// whose indices named a float accessor (its positions) passed validation and the glTF reader
/// hit `unreachable!`.
#[test]
fn regression_float_indices_are_refused_not_a_panic() {
    let mut glb = Glb::parse(&originals()[0]);
    let positions = glb.json["meshes"][0]["primitives"][0]["attributes"]["POSITION"].clone();
    glb.json["meshes"][0]["primitives"][0]["indices"] = positions;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("leg.glb");
    std::fs::write(&path, glb.bytes()).unwrap();
    let err = load_leg(&path, Units::Metres, UpChoice::Axis(UpAxis::PosY)).unwrap_err();
    assert!(
        err.to_string().contains("not unsigned integer SCALAR"),
        "{err}"
    );
}

/// Found while fuzzing the loader: a node listed among its own children sent the loader's
/// recursion round for ever, and the process died of a stack overflow with no message.
#[test]
fn regression_a_node_that_is_its_own_child_is_refused_not_a_stack_overflow() {
    let mut glb = Glb::parse(&originals()[0]);
    glb.json["nodes"][0]["children"] = json!([0]);
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("cycle.glb"), glb.bytes()).unwrap();
    refused(
        dir.path(),
        &["fit", "--leg", "cycle.glb", "-q"],
        "cycle.glb",
    );
    let err = stderr(&knitfit(dir.path(), &["fit", "--leg", "cycle.glb", "-q"]));
    assert!(err.contains("node 0 is reached twice"), "{err}");
}

/// Issue 22: `Collider::closest` panicked ("a non-empty mesh always has a closest point") when
/// parry's best-first search found no triangle, which it does when it cannot rank them: a query
/// point that is not finite, or one so far out that squared distances overflow. Now every
/// triangle is tried instead, and the distance it gives is left to the callers' finiteness
/// checks.
#[test]
fn regression_closest_to_a_point_the_bvh_cannot_rank_is_not_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("tube.glb");
    std::fs::write(&path, small_tube_glb()).unwrap();
    let leg = load_sample(&path);
    let collider = Collider::new(&leg, ContactMethod::Bvh).unwrap();
    for p in [
        nalgebra::Point3::new(f64::NAN, 0.4, 0.0),
        nalgebra::Point3::new(1e200, 0.4, 1e200),
    ] {
        assert!(collider.closest_within(&p, f64::MAX).is_none(), "{p:?}");
        let c = collider.closest(&p);
        assert!((c.triangle as usize) < collider.triangles().len());
        assert!(
            !c.signed_distance.is_finite() || c.signed_distance > 1e199,
            "{c:?}"
        );
    }
}

/// Issue 22: a coordinate far beyond any body (here f32::MAX, as a flipped exponent bit makes)
/// was accepted whenever cleaning kept a triangle using it, and contact's arithmetic on it can
/// overflow; it is refused at the load, by the bound `MAX_COORDINATE_M`, in one line.
#[test]
fn regression_a_coordinate_beyond_the_limit_is_refused_at_the_load() {
    let mut glb = Glb::parse(&originals()[0]);
    // Vertex 9's x and vertex 10's z: a triangle with two far corners that is no sliver.
    glb.bin[9 * 12..9 * 12 + 4].copy_from_slice(&f32::MAX.to_le_bytes());
    glb.bin[10 * 12 + 8..10 * 12 + 12].copy_from_slice(&f32::MAX.to_le_bytes());
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("far.glb"), glb.bytes()).unwrap();
    let err = load_leg(
        &dir.path().join("far.glb"),
        Units::Metres,
        UpChoice::Axis(UpAxis::PosY),
    )
    .unwrap_err();
    assert!(err.to_string().contains("beyond the ±10000 m"), "{err}");
    refused(dir.path(), &["fit", "--leg", "far.glb", "-q"], "far.glb");
}
