//! The yarn-level preview: what the picture shows (coverage from the knit's structure, the
//! darker outline), that it is deterministic and finite, and the command line's refusals.

use std::path::PathBuf;
use std::sync::OnceLock;

use knitfit::base::{Direction, Segment, Stance, SurfaceMesh, YarnGeometry, YarnKind};
use knitfit::export::gltf::read::read_stocking_glb;
use knitfit::preview::{render_preview, PreviewBuffers, PreviewInput};
use knitfit::preview::{CameraSettings, PreviewSettings};
use knitfit::scene::Scene;

use crate::support::{
    files_in, knitfit, knitfit_env, procedural_leg, read_fit_report, read_render_report,
    stage_names, stderr, write,
};

/// Yarn 0.2/0.25 mm in radius: thicker than the bundled scene's, so that a coarse 40×40 fit
/// (fast) still covers a measurable share of the skin; a stocking of 40 needles (5 mm × 12 mm
/// stitches), every stitch written as its loop, so that the preview drawn from the file shows
/// the real knit.
const THICK_YARN_SCENE: &str = r#"{
  "knit": { "needles": 40, "course_spacing_m": 0.005, "wale_spacing_m": 0.012 },
  "tube": { "wales": 40, "courses": 40 },
  "yarns": { "nylon":   { "stiffness": 1.0,  "denier": 1289 },
             "support": { "stiffness": 10.0, "denier": 2015 } },
  "effects": ["yarn_connection", "alternating_yarns", "contact", "penetration_fix"],
  "outputs": ["glb", "loops"]
}"#;

/// A 40×40 fit of the procedural leg with thick yarn, made once for every test here.
fn thick_fit() -> &'static (tempfile::TempDir, PathBuf, Scene) {
    static FIT: OnceLock<(tempfile::TempDir, PathBuf, Scene)> = OnceLock::new();
    FIT.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        let scene_path = write(dir.path(), "thick.json", THICK_YARN_SCENE);
        let out = knitfit(
            dir.path(),
            &[
                "fit",
                scene_path.to_str().unwrap(),
                "--leg",
                procedural_leg().to_str().unwrap(),
                "--resolution",
                "40x40",
                "--out",
                "fit",
                "-q",
            ],
        );
        assert!(out.status.success(), "{}", stderr(&out));
        let scene = Scene::load(Some(&scene_path)).unwrap();
        let glb = dir.path().join("fit/stocking.glb");
        (dir, glb, scene)
    })
}

/// Renders the thick fit's GLB with `settings` and returns the buffers.
fn buffers(settings: &PreviewSettings) -> PreviewBuffers {
    let (_, glb, scene) = thick_fit();
    let stocking = read_stocking_glb(glb).unwrap();
    let input = PreviewInput::new(
        &stocking.leg,
        &stocking.yarns,
        &scene.yarns,
        Stance::default(),
    );
    render_preview(input, settings, "test").unwrap().buffers
}

/// Mean of (yarn-covered fraction, `_COVERAGE`) over the pixels wholly on the leg whose skin
/// height lies in `heights` and facing (|cos| of the view angle) in `facing`; and their count.
fn band(b: &PreviewBuffers, heights: (f32, f32), facing: (f32, f32)) -> (f64, f64, usize) {
    let (mut yarn, mut attr, mut n) = (0.0, 0.0, 0);
    for i in 0..b.leg.len() {
        let inside = b.leg[i] >= 0.999
            && (heights.0..heights.1).contains(&b.height_m[i])
            && (facing.0..=facing.1).contains(&b.facing[i]);
        if inside {
            yarn += f64::from(b.yarn[i]);
            attr += f64::from(b.attribute_coverage[i]);
            n += 1;
        }
    }
    let k = n.max(1) as f64;
    (yarn / k, attr / k, n)
}

/// Lowest and highest yarn height of the thick fit, metres.
fn stocking_heights() -> (f32, f32) {
    let (_, glb, _) = thick_fit();
    yarn_heights(&read_stocking_glb(glb).unwrap().yarns)
}

/// Lowest and highest height of `yarns`, metres.
fn yarn_heights(yarns: &YarnGeometry) -> (f32, f32) {
    yarns
        .positions
        .iter()
        .fold((f32::MAX, f32::MIN), |(lo, hi), p| {
            (lo.min(p[1] as f32), hi.max(p[1] as f32))
        })
}

fn tall_settings() -> PreviewSettings {
    PreviewSettings {
        width: 200,
        height: 640,
        spp: 16,
        ..PreviewSettings::default()
    }
}

#[test]
fn the_ankle_is_more_covered_than_the_thigh_and_both_follow_the_coverage_attribute() {
    let b = buffers(&tall_settings());
    let (lo, hi) = stocking_heights();
    let l = hi - lo;
    let ankle = band(&b, (lo + 0.04 * l, lo + 0.14 * l), (0.85, 1.0));
    let thigh = band(&b, (hi - 0.22 * l, hi - 0.08 * l), (0.85, 1.0));
    eprintln!(
        "ankle: rendered {:.3}, _COVERAGE {:.3} ({} px); thigh: rendered {:.3}, _COVERAGE {:.3} \
         ({} px)",
        ankle.0, ankle.1, ankle.2, thigh.0, thigh.1, thigh.2
    );
    assert!(ankle.2 > 100 && thigh.2 > 100, "bands too small");
    assert!(
        ankle.0 > 1.3 * thigh.0,
        "ankle {:.3} vs thigh {:.3}",
        ankle.0,
        thigh.0
    );
    for (name, (rendered, attribute, _)) in [("ankle", ankle), ("thigh", thigh)] {
        // `_COVERAGE` is the loops' own yarn seen along the normal: the facing pixels show it.
        assert!(
            (rendered - attribute).abs() < 0.1,
            "{name}: rendered {rendered:.3} vs _COVERAGE {attribute:.3}"
        );
    }
}

#[test]
fn the_outline_is_more_covered_than_the_middle_of_the_same_band() {
    let b = buffers(&tall_settings());
    let (lo, hi) = stocking_heights();
    let l = hi - lo;
    let heights = (lo + 0.3 * l, hi - 0.1 * l);
    let middle = band(&b, heights, (0.9, 1.0));
    let outline = band(&b, heights, (0.0, 0.35));
    eprintln!(
        "middle (|cos| > 0.9): {:.3} ({} px); outline (|cos| < 0.35): {:.3} ({} px)",
        middle.0, middle.2, outline.0, outline.2
    );
    assert!(middle.2 > 100 && outline.2 > 20, "bands too small");
    assert!(
        outline.0 > 1.5 * middle.0,
        "outline {:.3} vs middle {:.3}",
        outline.0,
        middle.0
    );
}

#[test]
fn the_preview_is_byte_identical_with_one_and_two_threads() {
    let (dir, glb, _) = thick_fit();
    let scene = dir.path().join("thick.json");
    let run = |threads: &str, name: &str| {
        let out = knitfit_env(
            dir.path(),
            &[
                "render",
                glb.to_str().unwrap(),
                "--scene",
                scene.to_str().unwrap(),
                "--width",
                "96",
                "--height",
                "160",
                "--spp",
                "4",
                "--out",
                name,
                "-q",
            ],
            &[("RAYON_NUM_THREADS", threads)],
        );
        assert!(out.status.success(), "{}", stderr(&out));
        std::fs::read(dir.path().join(name)).unwrap()
    };
    let one = run("1", "one.png");
    let two = run("2", "two.png");
    assert!(one == two, "the thread count changed the picture");
    assert!(image::load_from_memory(&one).is_ok());
}

#[test]
fn broken_geometry_renders_finite_pixels_without_panicking() {
    let (_, glb, scene) = thick_fit();
    let mut stocking = read_stocking_glb(glb).unwrap();
    // A NaN yarn point, a yarn segment of zero length, a degenerate and an out-of-range triangle.
    stocking.yarns.positions[3] = [f64::NAN, 0.0, 0.0];
    let s = stocking.yarns.segments[10];
    stocking
        .yarns
        .segments
        .push(knitfit::base::Segment { b: s.a, ..s });
    stocking.leg.triangles.push([0, 0, 0]);
    stocking.leg.triangles.push([0, 1, u32::MAX]);
    stocking.leg.normals[5] = [0.0, 0.0, 0.0];
    let input = PreviewInput::new(
        &stocking.leg,
        &stocking.yarns,
        &scene.yarns,
        Stance::default(),
    );
    let settings = PreviewSettings {
        width: 64,
        height: 128,
        spp: 4,
        ..PreviewSettings::default()
    };
    let preview = render_preview(input, &settings, "test").unwrap();
    let b = &preview.buffers;
    for buffer in [
        &b.leg,
        &b.yarn,
        &b.attribute_coverage,
        &b.height_m,
        &b.facing,
    ] {
        assert!(buffer.iter().all(|v| v.is_finite()));
    }
    // A NaN sample would come out black: every pixel is background or lit skin or yarn.
    assert!(preview.image.pixels().all(|p| p.0 != [0, 0, 0]));
    assert!(b.leg.iter().any(|&f| f > 0.0), "the leg is in the picture");
}

/// Runs `knitfit render` with `args` in a fresh directory holding a copy of the thick fit's
/// GLB, a leg without yarns and a file that is not glTF; returns (dir, stderr, exit code).
fn render_refusal(args: &[&str]) -> (tempfile::TempDir, String, Option<i32>) {
    let (_, glb, _) = thick_fit();
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(glb, dir.path().join("stocking.glb")).unwrap();
    write(dir.path(), "notes.glb", "this is not glTF\n");
    std::fs::copy(procedural_leg(), dir.path().join("leg_only.glb")).unwrap();
    let mut all = vec!["render"];
    all.extend_from_slice(args);
    let out = knitfit(dir.path(), &all);
    (dir, stderr(&out), out.status.code())
}

#[test]
fn bad_render_arguments_are_refused_by_name_and_write_nothing() {
    for (args, expect) in [
        (
            &["stocking.glb", "--view", "top"][..],
            "--view: unknown variant `top`, expected one of `front`, `side`, `back`, `three-quarter`",
        ),
        (
            &["stocking.glb", "--spp", "0"][..],
            "--spp: must be 1 to 1024",
        ),
        (
            &["stocking.glb", "--width", "3"][..],
            "--width: must be 16 to 8192",
        ),
        (
            &["stocking.glb", "--mode", "xray"][..],
            "--mode: unknown variant `xray`, expected `yarn` or `density`",
        ),
        (
            &["stocking.glb", "--out", "p.jpg"][..],
            "--out: must name a .png file",
        ),
        (
            &["stocking.glb", "--width", "5000", "--height", "5000"][..],
            "5000×5000 is over the limit",
        ),
        (&["missing.glb"][..], "missing.glb: cannot read"),
        (&["notes.glb"][..], "notes.glb: not a glTF file"),
        (
            &["leg_only.glb"][..],
            "leg_only.glb: no node named \"yarns\"",
        ),
    ] {
        let (dir, err, code) = render_refusal(args);
        let line = err.trim_end();
        assert_eq!(code, Some(2), "{args:?}: {err}");
        assert!(!line.contains('\n'), "{args:?}: one line, got {err}");
        assert!(line.contains(expect), "{args:?}: {err}");
        assert_eq!(
            files_in(dir.path()),
            ["leg_only.glb", "notes.glb", "stocking.glb"],
            "{args:?}"
        );
    }
}

#[test]
fn a_fit_without_preview_in_its_outputs_renders_nothing_and_one_with_it_writes_preview_png() {
    let dir = tempfile::tempdir().unwrap();
    let fit = |outputs: &str, out: &str| {
        let scene = write(
            dir.path(),
            &format!("{out}.json"),
            &format!(
                r#"{{"outputs": {outputs}, "effects": ["penetration_fix"],
                    "render": {{"width": 64, "height": 96, "spp": 1}}}}"#
            ),
        );
        let run = knitfit(
            dir.path(),
            &[
                "fit",
                scene.to_str().unwrap(),
                "--leg",
                procedural_leg().to_str().unwrap(),
                "--resolution",
                "20x12",
                "--out",
                out,
                "-q",
            ],
        );
        assert!(run.status.success(), "{}", stderr(&run));
        dir.path().join(out)
    };
    let without = fit(r#"["glb"]"#, "without");
    assert_eq!(files_in(&without), ["report.json", "stocking.glb"]);
    let stages = stage_names(&read_fit_report(&without));
    assert!(
        !stages
            .iter()
            .any(|s| s.contains("render") || s.contains("preview")),
        "{stages:?}"
    );

    let with = fit(r#"["preview"]"#, "with");
    assert_eq!(files_in(&with), ["preview.png", "report.json"]);
    let r = read_fit_report(&with);
    let stages = stage_names(&r);
    assert!(stages.contains(&"render preview".to_string()), "{stages:?}");
    // The preview draws every real stitch as a loop; no yarn file, so nothing to mend.
    for stage in ["lay stitches", "knit loops"] {
        assert!(stages.contains(&stage.to_string()), "{stages:?}");
    }
    assert!(
        !stages.contains(&"penetration fix".to_string()),
        "{stages:?}"
    );
    let png = image::open(with.join("preview.png")).unwrap();
    assert_eq!((png.width(), png.height()), (64, 96));
}

#[test]
fn render_writes_preview_png_next_to_the_input_with_its_own_report() {
    let (fit_dir, glb, _) = thick_fit();
    let dir = tempfile::tempdir().unwrap();
    let copy = dir.path().join("stocking.glb");
    std::fs::copy(glb, &copy).unwrap();
    let out = knitfit(
        fit_dir.path(),
        &[
            "render",
            dir.path().to_str().unwrap(),
            "--width",
            "48",
            "--height",
            "64",
            "--spp",
            "1",
            "-q",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(
        files_in(dir.path()),
        ["preview.png", "preview.report.json", "stocking.glb"]
    );
    let r = read_render_report(dir.path());
    assert_eq!(r.command, "render");
    assert!(stage_names(&r).contains(&"render preview".to_string()));
    // Refuses to overwrite its input.
    let clash = knitfit(
        dir.path(),
        &["render", "stocking.glb", "--out", "stocking.glb", "-q"],
    );
    assert_eq!(clash.status.code(), Some(2), "{}", stderr(&clash));
}

/// A flat square of skin (side `side` metres, facing +Z, at z = 0) under a square grid of
/// yarns `spacing` apart and `radius` thick, their centre lines `radius` above the skin.
fn grid_scene(side: f64, spacing: f64, radius: f64) -> (SurfaceMesh, YarnGeometry) {
    let h = side / 2.0;
    let leg = SurfaceMesh::new(
        "leg",
        vec![[-h, -h, 0.0], [h, -h, 0.0], [h, h, 0.0], [-h, h, 0.0]],
        vec![[0, 1, 2], [0, 2, 3]],
    );
    let mut positions = Vec::new();
    let mut segments = Vec::new();
    let lines = (side / spacing) as usize;
    // Each line in pieces of four spacings, as a fitted yarn is a polyline of short springs.
    let pieces = lines / 4;
    for i in 0..=lines {
        let c = -h + i as f64 * spacing;
        for along_x in [true, false] {
            let first = positions.len() as u32;
            for k in 0..=pieces {
                let t = -h + side * k as f64 / pieces as f64;
                positions.push(if along_x {
                    [t, c, radius]
                } else {
                    [c, t, radius]
                });
            }
            for k in 0..pieces as u32 {
                segments.push(Segment {
                    a: first + k,
                    b: first + k + 1,
                    yarn: YarnKind::Nylon,
                    direction: Direction::Course,
                });
            }
        }
    }
    let yarns = YarnGeometry {
        name: "yarns".into(),
        offset_m: [0.0; 3],
        positions,
        point_attributes: Default::default(),
        segments,
    };
    (leg, yarns)
}

#[test]
fn yarn_finer_than_a_pixel_averages_to_the_true_coverage_without_moire() {
    // 0.5 mm spacing, 0.04 mm radius: 1 − (1 − 2r/s)² = 0.294 of the skin is hidden. The
    // camera sees 96 mm of it on 48 pixels: 2 mm per pixel, four yarn spacings, as a whole
    // stocking seen from a few metres is. One sample per pixel lands on yarn or skin by chance
    // (noise; a fixed centred sample would beat against the grid as moiré); the pixel's true
    // value is the area mix, which stratified samples converge to.
    let (spacing, radius): (f64, f64) = (5e-4, 4e-5);
    let exact = 1.0 - (1.0 - 2.0 * radius / spacing).powi(2);
    let (leg, yarns) = grid_scene(0.1, spacing, radius);
    let input = PreviewInput {
        leg: &leg,
        yarns: &yarns,
        radius_m: [radius; 3],
        yarn_colour: [[0.1; 3]; 3],
        stance: Stance::default(),
    };
    let distance = 0.5;
    let fov = 2.0 * (0.048f64 / distance).atan().to_degrees();
    let settings = |spp: u32| PreviewSettings {
        width: 48,
        height: 48,
        spp,
        camera: Some(CameraSettings {
            position: [0.0, 0.0, distance],
            target: [0.0, 0.0, 0.0],
            fov_deg: fov,
        }),
        ..PreviewSettings::default()
    };
    let stats = |spp: u32| {
        let b = render_preview(input, &settings(spp), "test")
            .unwrap()
            .buffers;
        let v: Vec<f64> = b.yarn.iter().map(|&y| f64::from(y)).collect();
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        let spread = (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / v.len() as f64).sqrt();
        (mean, spread)
    };
    let (mean64, spread64) = stats(64);
    let (mean16, spread16) = stats(16);
    let (mean1, spread1) = stats(1);
    eprintln!(
        "exact {exact:.4}; per-pixel mean and spread: 1 spp {mean1:.4} ± {spread1:.3}, 16 spp \
         {mean16:.4} ± {spread16:.3}, 64 spp {mean64:.4} ± {spread64:.3}"
    );
    // The mean is right at any sample count (the samples are unbiased): the yarn neither
    // vanishes nor fills in ...
    assert!((mean64 - exact).abs() < 0.02 * exact, "{mean64} vs {exact}");
    assert!((mean16 - exact).abs() < 0.03 * exact, "{mean16} vs {exact}");
    assert!((mean1 - exact).abs() < 0.1 * exact, "{mean1} vs {exact}");
    // ... and every pixel converges to it, at least as fast as 1/√spp.
    assert!(spread16 < 0.25 * spread1 * 1.1, "{spread16} vs {spread1}");
    assert!(spread64 < 0.5 * spread16 * 1.1, "{spread64} vs {spread16}");
}

#[test]
fn density_mode_draws_the_denser_ankle_hotter_than_the_thigh_with_a_colour_bar() {
    let (_, glb, scene) = thick_fit();
    let stocking = read_stocking_glb(glb).unwrap();
    let input = PreviewInput::new(
        &stocking.leg,
        &stocking.yarns,
        &scene.yarns,
        Stance::default(),
    );
    let settings = PreviewSettings {
        mode: knitfit::preview::RenderMode::Density,
        ..tall_settings()
    };
    let preview = render_preview(input, &settings, "test").unwrap();
    let b = &preview.buffers;
    assert!(preview.image.width() > b.width, "the bar panel is appended");
    let (lo, hi) = stocking_heights();
    let l = hi - lo;
    // Inferno runs dark to bright, so brighter means denser.
    let brightness = |heights: (f32, f32)| {
        let (mut sum, mut n) = (0.0, 0);
        for y in 0..b.height {
            for x in 0..b.width {
                let i = (y * b.width + x) as usize;
                if b.leg[i] >= 0.999 && (heights.0..heights.1).contains(&b.height_m[i]) {
                    let p = preview.image.get_pixel(x, y).0;
                    sum += p.iter().map(|&c| f64::from(c)).sum::<f64>();
                    n += 1;
                }
            }
        }
        sum / n.max(1) as f64
    };
    let ankle = brightness((lo + 0.04 * l, lo + 0.14 * l));
    let thigh = brightness((hi - 0.22 * l, hi - 0.08 * l));
    assert!(ankle > thigh + 30.0, "ankle {ankle:.0} vs thigh {thigh:.0}");
}

#[test]
fn the_spp_sweep_prints_time_and_error_per_sample_count_and_writes_nothing() {
    let (_, glb, _) = thick_fit();
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(glb, dir.path().join("stocking.glb")).unwrap();
    let out = knitfit(
        dir.path(),
        &[
            "render",
            ".",
            "--width",
            "32",
            "--height",
            "48",
            "--spp-sweep",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let text = crate::support::stdout(&out);
    let rows: Vec<Vec<f64>> = text
        .lines()
        .filter(|l| l.starts_with("| ") && !l.contains("spp"))
        .map(|l| {
            l.split('|')
                .filter_map(|c| c.trim().parse::<f64>().ok())
                .collect()
        })
        .collect();
    assert_eq!(rows.len(), 3, "{text}");
    assert_eq!(
        rows.iter().map(|r| r[0]).collect::<Vec<_>>(),
        [1.0, 4.0, 16.0]
    );
    assert!(rows[2][2] < rows[0][2], "error falls with samples: {text}");
    assert_eq!(files_in(dir.path()), ["stocking.glb"]);
}

/// The rendered stocking's yarn-covered share at the ankle and the thigh, facing the camera
/// (|cos| ≥ 0.9), against the leg's `_COVERAGE` there, for a fit of the procedural leg whose
/// yarn files hold every real stitch as a loop: `[(rendered, _COVERAGE); 2]`, ankle first.
fn loop_sheerness(needles: u32, stitch_m: [f64; 2], denier: f64) -> [(f64, f64); 2] {
    let dir = tempfile::tempdir().unwrap();
    let scene = serde_json::json!({
        "knit": { "needles": needles, "course_spacing_m": stitch_m[0], "wale_spacing_m": stitch_m[1] },
        "yarns": { "nylon": { "stiffness": 1.0, "denier": denier },
                   "support": { "stiffness": 10.0, "denier": 2.0 * denier } },
        "effects": ["yarn_connection", "alternating_yarns", "contact", "penetration_fix"],
        "outputs": ["glb", "loops"],
        "tube": { "wales": 60, "courses": 60 }
    });
    let scene_path = write(dir.path(), "scene.json", &scene.to_string());
    let leg = procedural_leg();
    let args = [
        "fit",
        scene_path.to_str().unwrap(),
        "--leg",
        leg.to_str().unwrap(),
    ];
    let out = knitfit(dir.path(), &[&args[..], &["-q"]].concat());
    assert!(out.status.success(), "{}", stderr(&out));
    let scene = Scene::load(Some(&scene_path)).unwrap();
    let stocking = read_stocking_glb(&dir.path().join("out/stocking.glb")).unwrap();
    let (lo, hi) = yarn_heights(&stocking.yarns);
    let input = PreviewInput::new(
        &stocking.leg,
        &stocking.yarns,
        &scene.yarns,
        Stance::default(),
    );
    let b = render_preview(input, &tall_settings(), "test")
        .unwrap()
        .buffers;
    let l = hi - lo;
    let ankle = band(&b, (lo + 0.04 * l, lo + 0.14 * l), (0.9, 1.0));
    let thigh = band(&b, (hi - 0.22 * l, hi - 0.08 * l), (0.9, 1.0));
    assert!(ankle.2 > 100 && thigh.2 > 100, "bands too small");
    [(ankle.0, ankle.1), (thigh.0, thigh.1)]
}

#[test]
fn the_loops_are_as_sheer_as_the_coverage_says_and_a_finer_yarn_is_sheerer() {
    // 10, 20 and 40 den on a stitch 4× the default's each way and yarn 16× the denier (4× the
    // diameter): the same geometry as the real stocking, scaled, with 16× fewer loops to
    // render. `KNITFIT_REAL_STITCH=1` measures the real 400-needle stocking instead (slow).
    let real = std::env::var_os("KNITFIT_REAL_STITCH").is_some();
    let (needles, stitch, scale) = match real {
        true => (400, [0.0005, 0.00074], 1.0),
        false => (100, [0.002, 0.00296], 16.0),
    };
    let mut previous: Option<[(f64, f64); 2]> = None;
    for denier in [10.0, 20.0, 40.0] {
        let [ankle, thigh] = loop_sheerness(needles, stitch, scale * denier);
        eprintln!(
            "{denier} den: skin seen at the ankle {:.3} (1 − _COVERAGE {:.3}), at the thigh {:.3} \
             (1 − _COVERAGE {:.3})",
            1.0 - ankle.0,
            1.0 - ankle.1,
            1.0 - thigh.0,
            1.0 - thigh.1
        );
        assert!(
            thigh.0 < ankle.0,
            "{denier} den: the thigh is stretched sheerer"
        );
        // `_COVERAGE` is the loops' own yarn seen along the normal (post::fields), so the
        // render shows as much skin as it says, up to the view's slant and the polyline's
        // corners: within 0.1, the bar of a preview that reads as the attribute says.
        for (name, (rendered, coverage)) in [("ankle", ankle), ("thigh", thigh)] {
            assert!(
                (rendered - coverage).abs() < 0.1,
                "{denier} den, {name}: rendered {rendered:.3} vs _COVERAGE {coverage:.3}"
            );
        }
        if let Some([a, t]) = previous {
            assert!(ankle.0 > a.0 && thigh.0 > t.0, "{denier} den is not denser");
        }
        previous = Some([ankle, thigh]);
    }
}
