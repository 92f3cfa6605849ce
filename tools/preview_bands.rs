//! Measures what a fit's yarn preview shows, band by band: the yarn-covered fraction of the
//! pixels facing the camera at the ankle and the thigh, against the `_COVERAGE` attribute on
//! the same pixels, and the outline against the middle of the leg.
//!
//!     cargo run --release --example preview_bands -- OUT_DIR [WIDTH HEIGHT SPP]
//!
//! Bands are fractions of the stocking's height (lowest to highest yarn point): ankle
//! 4–14 %, thigh 78–92 %; facing means |cos| of the view angle ≥ 0.85; outline vs middle over
//! 30–90 %, |cos| < 0.35 vs > 0.9. The front view of the bundled scene's render settings.

use std::path::PathBuf;

use knitfit::base::Stance;
use knitfit::export::gltf::read::read_stocking_glb;
use knitfit::preview::{render_preview, PreviewBuffers, PreviewInput};
use knitfit::scene::Scene;

fn band(b: &PreviewBuffers, heights: (f32, f32), facing: (f32, f32)) -> (f64, f64, usize) {
    let (mut yarn, mut attr, mut n) = (0.0, 0.0, 0);
    for i in 0..b.leg.len() {
        if b.leg[i] >= 0.999
            && (heights.0..heights.1).contains(&b.height_m[i])
            && (facing.0..=facing.1).contains(&b.facing[i])
        {
            yarn += f64::from(b.yarn[i]);
            attr += f64::from(b.attribute_coverage[i]);
            n += 1;
        }
    }
    let k = n.max(1) as f64;
    (yarn / k, attr / k, n)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(dir) = args.first().map(PathBuf::from) else {
        eprintln!("usage: preview_bands OUT_DIR [WIDTH HEIGHT SPP]");
        std::process::exit(2);
    };
    let number =
        |i: usize, default: u32| args.get(i).and_then(|s| s.parse().ok()).unwrap_or(default);
    let mut scene = Scene::load(None).expect("the bundled scene is valid");
    scene.render.width = number(1, 512);
    scene.render.height = number(2, 1024);
    scene.render.spp = number(3, 16);
    let stocking = match read_stocking_glb(&dir.join("stocking.glb")) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("preview_bands: {e}");
            std::process::exit(2);
        }
    };
    let (lo, hi) = stocking
        .yarns
        .positions
        .iter()
        .fold((f32::MAX, f32::MIN), |(lo, hi), p| {
            (lo.min(p[1] as f32), hi.max(p[1] as f32))
        });
    let input = PreviewInput::new(
        &stocking.leg,
        &stocking.yarns,
        &scene.yarns,
        Stance::default(),
    );
    let preview = match render_preview(input, &scene.render, "preview") {
        Ok(p) => p,
        Err(e) => {
            eprintln!("preview_bands: {e}");
            std::process::exit(1);
        }
    };
    let b = &preview.buffers;
    let l = hi - lo;
    let at = |a: f32, z: f32| (lo + a * l, lo + z * l);
    let ankle = band(b, at(0.04, 0.14), (0.85, 1.0));
    let thigh = band(b, at(0.78, 0.92), (0.85, 1.0));
    let middle = band(b, at(0.3, 0.9), (0.9, 1.0));
    let outline = band(b, at(0.3, 0.9), (0.0, 0.35));
    println!(
        "{}: {}×{} at {} spp",
        dir.display(),
        b.width,
        b.height,
        preview.stats.spp
    );
    println!("| band | yarn-covered (rendered) | _COVERAGE | pixels |");
    println!("|---|---|---|---|");
    for (name, (y, a, n)) in [("ankle, facing", ankle), ("thigh, facing", thigh)] {
        println!("| {name} | {y:.3} | {a:.3} | {n} |");
    }
    for (name, (y, _, n)) in [
        ("middle, |cos| > 0.9", middle),
        ("outline, |cos| < 0.35", outline),
    ] {
        println!("| {name} | {y:.3} | | {n} |");
    }
}
