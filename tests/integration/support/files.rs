//! Reading the files knitfit writes, for assertions on their contents, and listing its own
//! source files for the tests that read the source.

use std::path::{Path, PathBuf};

use nalgebra::Point3;
use ply_rs_bw::ply::{DefaultElement, Property};

/// The PLY file at `path`, parsed.
pub fn read_ply(path: &Path) -> ply_rs_bw::ply::Ply<DefaultElement> {
    let mut file = std::fs::File::open(path).unwrap();
    ply_rs_bw::parser::Parser::<DefaultElement>::new()
        .read_ply(&mut file)
        .unwrap()
}

pub fn float(e: &DefaultElement, name: &str) -> f64 {
    match &e[name] {
        Property::Float(v) => *v as f64,
        other => panic!("{name}: {other:?}"),
    }
}

pub fn point(e: &DefaultElement) -> Point3<f64> {
    Point3::new(float(e, "x"), float(e, "y"), float(e, "z"))
}

/// The JSON `text` as a value whose numbers are exactly those written: each float read as Rust
/// reads one (`str::parse`, correctly rounded). serde_json's own parser, without its
/// `float_roundtrip` feature (which knitfit does not enable: it would change how scenes and glTF
/// files are read), rounds a 17-digit number twice and lands one unit in the last place off for
/// about one in twenty, so a report read with it is not the report written. Integers, strings and
/// the literals are serde_json's; an object's keys come back sorted.
pub fn exact_json(text: &str) -> serde_json::Value {
    use serde_json::value::RawValue;
    use serde_json::Value;
    let raw = text.trim();
    match raw.as_bytes().first() {
        Some(b'{') => {
            let fields: Vec<(String, &RawValue)> =
                serde_json::from_str::<std::collections::BTreeMap<String, &RawValue>>(raw)
                    .unwrap()
                    .into_iter()
                    .collect();
            Value::Object(
                fields
                    .into_iter()
                    .map(|(k, v)| (k, exact_json(v.get())))
                    .collect(),
            )
        }
        Some(b'[') => {
            let items: Vec<&RawValue> = serde_json::from_str(raw).unwrap();
            Value::Array(items.into_iter().map(|v| exact_json(v.get())).collect())
        }
        Some(b'-' | b'0'..=b'9') if raw.contains(['.', 'e', 'E']) => {
            let x: f64 = raw.parse().unwrap_or_else(|e| panic!("{raw}: {e}"));
            Value::Number(serde_json::Number::from_f64(x).unwrap())
        }
        _ => serde_json::from_str(raw).unwrap_or_else(|e| panic!("{raw}: {e}")),
    }
}

/// Standard base64 with padding, for the data URIs of `.gltf` buffers.
pub fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = (b[0] as u32) << 16 | (b[1] as u32) << 8 | b[2] as u32;
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(ALPHABET[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// Every `.rs` file under `dir`, sorted.
pub fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    let mut dirs = vec![dir.to_path_buf()];
    while let Some(d) = dirs.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                dirs.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                files.push(path);
            }
        }
    }
    files.sort();
    files
}
