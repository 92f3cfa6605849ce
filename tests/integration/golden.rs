//! The bytes of the files users import do not change by accident: a small fit (with a preview)
//! and the default patch are hashed and compared with the hashes of the files knitfit 0.1.0
//! wrote for the same commands. A change that means to alter a file updates its hash here, and
//! says so in CHANGELOG.md.

use std::path::Path;

use crate::support::{knitfit, procedural_leg, stderr, write};

/// FNV-1a, 64 bits: enough to tell two files apart, and no dependency.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

fn hashes(dir: &Path, files: &[&str]) -> Vec<(String, String)> {
    files
        .iter()
        .map(|f| {
            let bytes = std::fs::read(dir.join(f)).unwrap();
            (f.to_string(), format!("{:016x}", fnv1a(&bytes)))
        })
        .collect()
}

fn expected(pairs: &[(&str, &str)]) -> Vec<(String, String)> {
    pairs
        .iter()
        .map(|(f, h)| (f.to_string(), h.to_string()))
        .collect()
}

#[test]
fn a_small_fit_writes_the_bytes_it_always_has() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write(
        dir.path(),
        "s.json",
        r#"{"effects": ["yarn_connection", "alternating_yarns", "penetration_fix"],
            "outputs": ["glb", "ply", "picture", "preview"],
            "render": {"width": 64, "height": 96, "spp": 4}}"#,
    );
    let leg = procedural_leg();
    let out = knitfit(
        dir.path(),
        &[
            "fit",
            scene.to_str().unwrap(),
            "--leg",
            leg.to_str().unwrap(),
            "--resolution",
            "24x24",
            "-q",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let files = [
        "stocking.glb",
        "stocking.ply",
        "leg.ply",
        "density.png",
        "preview.png",
    ];
    assert_eq!(
        hashes(&dir.path().join("out"), &files),
        expected(&[
            ("stocking.glb", "3d12c2471e46609c"),
            ("stocking.ply", "f196bd7575efe45c"),
            ("leg.ply", "f94c183bec98988b"),
            ("density.png", "764601b884fb2522"),
            ("preview.png", "2aa730e52856e6c0"),
        ])
    );
}

#[test]
fn the_default_patch_writes_the_bytes_it_always_has() {
    let dir = tempfile::tempdir().unwrap();
    let out = knitfit(dir.path(), &["patch", "-q"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(
        hashes(
            &dir.path().join("out"),
            &["patch.ply", "patch.glb", "patch.png"]
        ),
        expected(&[
            ("patch.ply", "8f9afd27f4a8cffd"),
            ("patch.glb", "c6a59c6102528c3d"),
            ("patch.png", "c61491efa9588651")
        ])
    );
}
