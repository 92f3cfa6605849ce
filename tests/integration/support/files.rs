//! Reading the files knitfit writes, for assertions on their contents.

use std::path::Path;

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
