//! Yarns that follow the skin, and the per-vertex attributes a shader needs (paper §6.3 and past
//! it): every yarn polyline sampled densely against the exact leg, on every sample leg, in
//! concave and sharp places, with and without the penetration fix; the leg's attributes in both
//! file formats; the density picture.

use std::path::Path;

use knitfit::leg::{load_leg, Collider, ContactMethod, Units, UpAxis, UpChoice};
use nalgebra::Point3;

use crate::support::{
    fit, float, knitfit, point, read_fit_report, read_ply, sample_legs, shared_fit, stage_names,
    stderr, write_tube_leg, OPEN_TUBE,
};

/// How deep a yarn polyline may reach into the leg: 0.05 mm.
const MAX_DEPTH_M: f64 = 5e-5;
/// Spacing of the samples along every yarn segment.
const SAMPLE_SPACING_M: f64 = 2.5e-5;

/// A sample along a yarn polyline that lies inside the leg.
pub(crate) struct Depth {
    pub deepest: f64,
    /// Where the deepest sample is.
    pub at: Point3<f64>,
    pub samples: usize,
}

/// Samples every edge of `stocking.ply` in `out` that meets the skin, at most
/// [`SAMPLE_SPACING_M`] apart where it could be inside, against the exact
/// leg, keeping the samples `region` accepts; returns the deepest.
pub(crate) fn polyline_depth(
    out: &Path,
    collider: &Collider,
    region: impl Fn(&Point3<f64>) -> bool,
) -> Depth {
    let yarns = read_ply(&out.join("stocking.ply"));
    let points: Vec<Point3<f64>> = yarns.payload["vertex"].iter().map(point).collect();
    let index = |e: &ply_rs_bw::ply::DefaultElement, name: &str| match e[name] {
        ply_rs_bw::ply::Property::Int(i) => i as usize,
        ref other => panic!("{name}: {other:?}"),
    };
    let mut depth = Depth {
        deepest: 0.0,
        at: Point3::origin(),
        samples: 0,
    };
    for e in &yarns.payload["edge"] {
        let (a, b) = (points[index(e, "vertex1")], points[index(e, "vertex2")]);
        let length = (b - a).norm();
        let (outside_a, outside_b) = (
            collider.closest(&a).signed_distance,
            collider.closest(&b).signed_distance,
        );
        // A segment whose ends are outside and that meets no skin between them is outside
        // all along: its ends are its samples. Any other is sampled along its length.
        let crosses = length > 0.0
            && collider
                .first_hit(&a, &((b - a) / length), length)
                .is_some();
        if outside_a >= 0.0 && outside_b >= 0.0 && !crosses {
            depth.samples += [a, b].iter().filter(|p| region(p)).count();
            continue;
        }
        let mut along = 0.0;
        loop {
            let p = a + (b - a) * if length > 0.0 { along / length } else { 0.0 };
            let outside_by = collider.closest(&p).signed_distance;
            if region(&p) {
                depth.samples += 1;
                if -outside_by > depth.deepest {
                    depth.deepest = -outside_by;
                    depth.at = p;
                }
            }
            if along >= length {
                break;
            }
            // No skin lies nearer a point than its distance to the skin, so the segment stays
            // outside that far on: the next sample can be there (sphere tracing). Inside the
            // leg, or nearer than the spacing, the samples are the spacing apart.
            along = (along + outside_by.max(SAMPLE_SPACING_M)).min(length);
        }
    }
    depth
}

pub(crate) fn collider_of(leg: &Path) -> Collider {
    let leg = load_leg(leg, Units::Metres, UpChoice::Axis(UpAxis::PosY)).unwrap();
    Collider::new(&leg, ContactMethod::Bvh).unwrap()
}

#[test]
fn every_yarn_polyline_stays_on_the_skin_of_every_sample_leg() {
    for leg in sample_legs() {
        let (dir, r) = shared_fit(&leg, "60x60", OPEN_TUBE);
        let out = dir.path().join("out");
        let name = leg.display();
        let fix = r.details.penetration_fix.unwrap();
        assert_eq!(fix.still_crossing, 0, "{name}: {fix:?}");
        assert_eq!(fix.repaired, fix.crossing, "{name}: {fix:?}");
        let depth = polyline_depth(&out, &collider_of(&leg), |_| true);
        eprintln!(
            "{name}: {} samples, deepest {:.2e} m, fix {fix:?}",
            depth.samples, depth.deepest
        );
        assert!(
            depth.deepest <= MAX_DEPTH_M,
            "{name}: a yarn polyline is {} mm inside the leg at {:?}",
            depth.deepest * 1e3,
            depth.at
        );
    }
}

#[test]
fn without_the_fix_straight_segments_cut_through_the_coarse_leg() {
    // The coarse MakeHuman leg (2.6k triangles): one yarn segment spans several triangles, so
    // straight segments cut through the skin, as the paper describes. This is what the fix is
    // for, and it shows the sampling above would catch a miss.
    let leg = Path::new(env!("CARGO_MANIFEST_DIR")).join("samples/makehuman_leg_coarse.glb");
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("nofix.json"),
        format!(
            r#"{{"leg": {{"file": {:?}}}, "outputs": ["ply"],
                "effects": ["yarn_connection", "alternating_yarns"]}}"#,
            leg.display().to_string()
        ),
    )
    .unwrap();
    let out = knitfit(
        dir.path(),
        &["fit", "nofix.json", "--resolution", "40x40", "-q"],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let r = read_fit_report(&dir.path().join("out"));
    assert!(r.details.penetration_fix.is_none());
    let stages = stage_names(&r);
    assert!(!stages.iter().any(|s| s == "penetration fix"), "{stages:?}");
    let depth = polyline_depth(&dir.path().join("out"), &collider_of(&leg), |_| true);
    assert!(
        depth.deepest > MAX_DEPTH_M,
        "straight segments only {} mm deep",
        depth.deepest * 1e3
    );

    // The same fit with the fix: repaired, and on the skin.
    let (fixed_dir, fixed) = fit(&leg, "40x40", &[]);
    let fix = fixed.details.penetration_fix.unwrap();
    assert!(fix.repaired > 100, "{fix:?}");
    assert!(fix.points_inserted >= fix.repaired, "{fix:?}");
    let depth = polyline_depth(&fixed_dir.path().join("out"), &collider_of(&leg), |_| true);
    assert!(depth.deepest <= MAX_DEPTH_M, "{} mm", depth.deepest * 1e3);
}

#[test]
fn the_back_of_the_knee_and_the_achilles_tendon_are_not_cut_through() {
    // The MakeHuman leg faces +Z: the back of the knee and the Achilles tendon are its concave
    // places, on the -Z side. Heights as fractions of the leg's extent along Y.
    let leg = Path::new(env!("CARGO_MANIFEST_DIR")).join("samples/makehuman_leg.glb");
    let (dir, r) = fit(&leg, "90x90", &[]);
    let out = dir.path().join("out");
    let collider = collider_of(&leg);
    let (lo, hi) = (-0.642, -0.177);
    for (region, from, to) in [
        ("Achilles tendon", 0.02, 0.2),
        ("back of the knee", 0.42, 0.58),
    ] {
        let behind = |p: &Point3<f64>| {
            let h = (p.y - lo) / (hi - lo);
            // Behind the leg's mid-plane: z below the centre of the cross-section at the ankle
            // (0.03 m) and knee (0.02 m) of this leg.
            (from..to).contains(&h) && p.z < 0.02
        };
        let depth = polyline_depth(&out, &collider, behind);
        assert!(depth.samples > 1000, "{region}: {} samples", depth.samples);
        assert!(
            depth.deepest <= MAX_DEPTH_M,
            "{region}: {} mm inside at {:?}",
            depth.deepest * 1e3,
            depth.at
        );
    }
    assert_eq!(r.metrics.max_penetration_m, Some(0.0));
}

/// A leg-sized tube with a sharp V-shaped crease running down its back (concave) and a sharp
/// ridge down its front (convex, like a shin), 48 quads around, written as a GLB.
fn creased_leg(dir: &Path) -> std::path::PathBuf {
    write_tube_leg(dir, "creased_leg.glb", 48, 30, |h, t| {
        let y = 0.05 + 0.5 * h;
        let r0 = 0.04 + 0.025 * h;
        // Angle from the back (-Z) and from the front (+Z), 0..π.
        let from_back = (t - 1.5 * std::f64::consts::PI).abs();
        let from_front = (t - 0.5 * std::f64::consts::PI).abs();
        let crease = 0.012 * (1.0 - from_back / 0.35).max(0.0);
        let ridge = 0.006 * (1.0 - from_front / 0.25).max(0.0);
        let r = r0 - crease + ridge;
        [r * t.cos(), y, -r * t.sin()]
    })
}

#[test]
fn a_synthetic_crease_and_ridge_are_followed_without_cutting_through() {
    let dir = tempfile::tempdir().unwrap();
    let leg = creased_leg(dir.path());
    let (fit_dir, r) = fit(&leg, "48x40", &[]);
    assert!(r.metrics.converged);
    assert_eq!(r.metrics.max_penetration_m, Some(0.0));
    let fix = r.details.penetration_fix.unwrap();
    assert!(fix.repaired > 0, "{fix:?}");
    let depth = polyline_depth(&fit_dir.path().join("out"), &collider_of(&leg), |_| true);
    assert!(
        depth.deepest <= MAX_DEPTH_M,
        "{} mm inside at {:?}",
        depth.deepest * 1e3,
        depth.at
    );
}

/// One leg vertex's values from the leg PLY.
#[derive(Clone, Copy)]
struct LegVertex {
    pub at: Point3<f64>,
    density: f64,
    stretch_course: f64,
    coverage: f64,
    pressure: f64,
}

fn leg_fields(out: &Path) -> Vec<LegVertex> {
    read_ply(&out.join("leg.ply")).payload["vertex"]
        .iter()
        .map(|v| LegVertex {
            at: point(v),
            density: float(v, "stitch_density"),
            stretch_course: float(v, "stretch_course"),
            coverage: float(v, "coverage"),
            pressure: float(v, "pressure"),
        })
        .collect()
}

#[test]
fn coverage_and_density_rise_where_the_leg_is_thin_and_fall_where_it_is_stretched() {
    for leg in sample_legs() {
        let (dir, r) = shared_fit(&leg, "60x60", OPEN_TUBE);
        let name = leg.display();
        let (bottom, top) = (r.details.axis.bottom[1], r.details.axis.top[1]);
        let fields = leg_fields(&dir.path().join("out"));
        let band = |from: f64, to: f64| {
            let picked: Vec<&LegVertex> = fields
                .iter()
                .filter(|v| {
                    let h = (v.at.y - bottom) / (top - bottom);
                    v.density > 0.0 && (from..to).contains(&h)
                })
                .collect();
            // The low-poly game leg has about 15 vertices to a band.
            assert!(picked.len() >= 10, "{name}: {} vertices", picked.len());
            let mean = |f: fn(&LegVertex) -> f64| {
                picked.iter().map(|v| f(v)).sum::<f64>() / picked.len() as f64
            };
            (
                mean(|v| v.density),
                mean(|v| v.stretch_course),
                mean(|v| v.coverage),
            )
        };
        let (ankle_density, ankle_stretch, ankle_coverage) = band(0.05, 0.15);
        let (thigh_density, thigh_stretch, thigh_coverage) = band(0.85, 0.95);
        assert!(ankle_density > thigh_density, "{name}");
        assert!(
            ankle_stretch < thigh_stretch,
            "{name}: course stretch ankle {ankle_stretch} thigh {thigh_stretch}"
        );
        assert!(
            ankle_coverage > 1.2 * thigh_coverage,
            "{name}: coverage ankle {ankle_coverage} thigh {thigh_coverage}"
        );
        for v in &fields {
            assert!(v.density.is_finite() && v.stretch_course.is_finite());
            assert!((0.0..=1.0).contains(&v.coverage));
        }
    }
}

#[test]
fn leg_attributes_are_smooth_across_the_mesh() {
    // No speckle from how yarn points fall on vertices: across the leg's edges, a covered
    // vertex's value differs from its neighbour's by little compared with the field's range
    // over the leg (ankle to thigh).
    let leg = Path::new(env!("CARGO_MANIFEST_DIR")).join("samples/makehuman_leg.glb");
    let (dir, r) = fit(&leg, "150x150", &[]);
    // Inside the covered part: the field ends where the stocking does, by design.
    let (bottom, top) = (r.details.axis.bottom[1], r.details.axis.top[1]);
    let inside = |p: &Point3<f64>| (0.05..0.95).contains(&((p.y - bottom) / (top - bottom)));
    // Vertices outside count as uncovered (density 0), keeping the mesh's numbering.
    let fields: Vec<LegVertex> = leg_fields(&dir.path().join("out"))
        .into_iter()
        .map(|v| LegVertex {
            density: if inside(&v.at) { v.density } else { 0.0 },
            ..v
        })
        .collect();
    let mesh = load_leg(&leg, Units::Metres, UpChoice::Axis(UpAxis::PosY)).unwrap();
    let mut ratios = Vec::new();
    type Field = fn(&LegVertex) -> f64;
    let fields_of: [(&str, Field); 4] = [
        ("coverage", |v| v.coverage),
        ("pressure", |v| v.pressure),
        ("stitch_density", |v| v.density),
        ("stretch_course", |v| v.stretch_course),
    ];
    for (field, pick) in fields_of {
        let covered: Vec<f64> = fields
            .iter()
            .filter(|v| v.density > 0.0)
            .map(pick)
            .collect();
        let range = covered.iter().copied().fold(f64::NEG_INFINITY, f64::max)
            - covered.iter().copied().fold(f64::INFINITY, f64::min);
        // Each covered vertex against the mean of its covered neighbours: a smooth field,
        // however steep, differs from it by a second-order amount; speckle does not.
        let mut sums = vec![(0.0, 0u32); fields.len()];
        for t in &mesh.triangles {
            for k in 0..3 {
                let (i, j) = (t[k] as usize, t[(k + 1) % 3] as usize);
                if fields[i].density > 0.0 && fields[j].density > 0.0 {
                    sums[i].0 += pick(&fields[j]);
                    sums[i].1 += 1;
                    sums[j].0 += pick(&fields[i]);
                    sums[j].1 += 1;
                }
            }
        }
        let mut deviations: Vec<f64> = fields
            .iter()
            .zip(&sums)
            .filter(|(v, (_, n))| v.density > 0.0 && *n > 0)
            .map(|(v, (sum, n))| (pick(v) - sum / *n as f64).abs())
            .collect();
        deviations.sort_by(f64::total_cmp);
        let p99 = deviations[deviations.len() * 99 / 100];
        eprintln!("{field}: 99th percentile deviation {p99}, range {range}");
        ratios.push((field, p99 / range));
    }
    for (field, ratio) in ratios {
        assert!(
            ratio < 0.05,
            "{field}: 99th percentile deviation from the neighbours is {ratio} of the range"
        );
    }
}

#[test]
fn the_leg_attributes_in_the_glb_are_those_of_the_ply() {
    let leg = Path::new(env!("CARGO_MANIFEST_DIR")).join("samples/makehuman_leg.glb");
    let (dir, _) = fit(&leg, "40x40", &[]);
    let out = dir.path().join("out");
    let ply = read_ply(&out.join("leg.ply"));
    let (doc, buffers, _) = gltf::import(out.join("stocking.glb")).unwrap();
    let leg_node = doc.nodes().find(|n| n.name() == Some("leg")).unwrap();
    let prim = leg_node.mesh().unwrap().primitives().next().unwrap();
    for (gltf_name, ply_name) in [
        ("STITCH_DENSITY", "stitch_density"),
        ("STRETCH_COURSE", "stretch_course"),
        ("STRETCH_WALE", "stretch_wale"),
        ("COVERAGE", "coverage"),
        ("TENSION", "tension"),
        ("PRESSURE", "pressure"),
    ] {
        let accessor = prim
            .attributes()
            .find(|(s, _)| *s == gltf::Semantic::Extras(gltf_name.into()))
            .unwrap_or_else(|| panic!("_{gltf_name}"))
            .1;
        let values: Vec<f32> =
            gltf::accessor::Iter::<f32>::new(accessor, |b| Some(&buffers[b.index()]))
                .unwrap()
                .collect();
        assert_eq!(values.len(), ply.payload["vertex"].len());
        for (v, e) in values.iter().zip(&ply.payload["vertex"]) {
            assert_eq!(*v as f64, float(e, ply_name), "_{gltf_name}");
        }
    }
}

#[test]
fn the_density_picture_shows_front_and_side() {
    let leg = Path::new(env!("CARGO_MANIFEST_DIR")).join("samples/makehuman_leg.glb");
    let (dir, r) = fit(&leg, "40x40", &["--outputs", "picture"]);
    let out = dir.path().join("out");
    assert!(r.outputs.iter().any(|o| o == "density.png"));
    let picture = image::open(out.join("density.png")).unwrap().to_rgb8();
    assert!(picture.width() > picture.height(), "two views side by side");
    // Coloured pixels (not grey, not background) make up a real part of the picture.
    let coloured = picture
        .pixels()
        .filter(|p| {
            let [r, g, b] = p.0.map(i32::from);
            (r - g).abs() + (g - b).abs() + (r - b).abs() > 60
        })
        .count();
    assert!(
        coloured * 20 > (picture.width() * picture.height()) as usize,
        "{coloured} coloured pixels"
    );
}
