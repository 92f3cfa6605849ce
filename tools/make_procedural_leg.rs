//! Builds `samples/procedural_leg.glb`: a smooth procedural human leg from the ankle to the upper
//! thigh, for tests and demos that need a leg without an artist's model.
//!
//! The leg is a tube of [`RINGS_ALONG`] rings of [`POINTS_AROUND`] vertices stacked along +Y, in
//! metres, Y up, +Z the front of the leg and −Z the back. It stands on a floor at y = 0: the bottom
//! ring (the ankle) is at y = 0.08 m, the top ring (the upper thigh) at y = 0.83 m. Each ring is an
//! egg-shaped ellipse, wider side to side (X) at the thigh and deeper front to back (Z) at the
//! calf, whose bulk can lean backward (the calf) or forward (the thigh), around a centre that moves
//! backward at the calf and forward at the knee. Girth, width/depth ratio, back bulge and centre
//! offset come from the control sections in [`CONTROL`], interpolated along y by monotone cubics
//! (Fritsch–Carlson), so every extremum of the table (ankle minimum, calf maximum, the narrowing
//! below the knee) sits exactly at its control point with no overshoot.
//!
//! Smooth radial features from [`FEATURES`] are carved into the rings: two hollows flanking the
//! Achilles tendon above the ankle and the popliteal fossa behind the knee, both concave (tests
//! need concave regions), and a slight patella bump in front of the knee. Each ring is then scaled
//! about its centre so that its polygon perimeter equals the interpolated girth exactly.
//!
//! Both ends are closed with a flat triangle fan on their own rim vertices (normal −Y at the
//! bottom, +Y at the top), so the tube keeps smooth normals up to its rims and the mesh is
//! watertight once duplicate vertices are merged. Triangles are counter-clockwise seen from
//! outside; every vertex has a unit NORMAL (area-weighted face normals). The GLB is written with
//! knitfit's own [`GlbBuilder`]: one mesh "leg" under one node "leg", no material.
//!
//! Run: `cargo run --release --example make_procedural_leg -- samples/procedural_leg.glb`
//! (add `--preview leg.png` to render front, side and back views plus cross-sections).

use std::collections::BTreeMap;
use std::error::Error;
use std::f64::consts::{FRAC_PI_2, PI, TAU};
use std::path::{Path, PathBuf};

use clap::Parser;
use gltf_json as json;
use json::validation::Checked::Valid;
use knitfit::export::gltf::GlbBuilder;

/// Vertices per ring.
const POINTS_AROUND: usize = 128;
/// Rings from the ankle to the thigh (one more than the segments along the leg).
const RINGS_ALONG: usize = 161;
/// Height of the bottom (ankle) ring above the floor, m.
const BOTTOM_Y_M: f64 = 0.08;
/// Height of the top (upper thigh) ring above the floor, m.
const TOP_Y_M: f64 = 0.83;

/// One control cross-section of the leg.
struct Section {
    /// Height above the floor, m.
    y_m: f64,
    /// Girth: perimeter of the cross-section, m.
    girth_m: f64,
    /// Width (side to side, X) over depth (front to back, Z); dimensionless.
    width_over_depth: f64,
    /// Backward lean of the section's bulk: the back half-depth is (1 + k) and the front
    /// (1 − k) times the mean half-depth. Dimensionless; negative leans forward.
    back_bulge: f64,
    /// Offset of the section centre toward the front (+Z), m; negative is backward.
    centre_z_m: f64,
}

/// Control sections, bottom to top. Units: metres, except the two dimensionless shape columns.
const CONTROL: [Section; 14] = [
    section(0.080, 0.212, 1.00, 0.00, 0.000), // bottom end, just above the malleoli
    section(0.100, 0.200, 0.90, 0.02, 0.000), // ankle: narrowest
    section(0.140, 0.206, 0.86, 0.06, -0.002),
    section(0.200, 0.238, 0.84, 0.12, -0.006),
    section(0.270, 0.300, 0.86, 0.18, -0.010),
    section(0.350, 0.350, 0.88, 0.20, -0.012), // calf: widest, bulging backward
    section(0.400, 0.342, 0.90, 0.16, -0.008),
    section(0.440, 0.327, 0.95, 0.08, -0.002), // narrowing just below the knee
    section(0.500, 0.340, 1.02, 0.00, 0.008),  // knee: centre forward
    section(0.560, 0.365, 1.06, -0.02, 0.008),
    section(0.650, 0.420, 1.10, -0.04, 0.006),
    section(0.740, 0.475, 1.13, -0.04, 0.004),
    section(0.800, 0.500, 1.15, -0.03, 0.003), // thigh: wider than deep
    section(0.830, 0.510, 1.15, -0.03, 0.003), // top end
];

const fn section(
    y_m: f64,
    girth_m: f64,
    width_over_depth: f64,
    back_bulge: f64,
    centre_z_m: f64,
) -> Section {
    Section {
        y_m,
        girth_m,
        width_over_depth,
        back_bulge,
        centre_z_m,
    }
}

/// A smooth radial dent (or bump, with a negative depth): Gaussian in height and in the angle
/// around the ring.
struct Feature {
    /// Height of its centre above the floor, m.
    y_m: f64,
    /// Standard deviation along y, m.
    sigma_y_m: f64,
    /// Ring angle of its centre, rad: 0 is +X (side), π/2 the front (+Z), −π/2 the back (−Z).
    angle_rad: f64,
    /// Standard deviation around the ring, rad.
    sigma_angle_rad: f64,
    /// Inward displacement at its centre before the ring is scaled to its girth, m.
    depth_m: f64,
}

/// Angle between the back midline and each hollow beside the Achilles tendon, rad.
const ACHILLES_HOLLOW_OFFSET_RAD: f64 = 0.45;

/// Surface features carved into the rings.
const FEATURES: [Feature; 4] = [
    // Hollows either side of the Achilles tendon, between it and the malleoli.
    Feature {
        y_m: 0.135,
        sigma_y_m: 0.028,
        angle_rad: -FRAC_PI_2 + ACHILLES_HOLLOW_OFFSET_RAD,
        sigma_angle_rad: 0.2,
        depth_m: 0.003,
    },
    Feature {
        y_m: 0.135,
        sigma_y_m: 0.028,
        angle_rad: -FRAC_PI_2 - ACHILLES_HOLLOW_OFFSET_RAD,
        sigma_angle_rad: 0.2,
        depth_m: 0.003,
    },
    // Popliteal fossa: the hollow at the back of the knee.
    Feature {
        y_m: 0.49,
        sigma_y_m: 0.03,
        angle_rad: -FRAC_PI_2,
        sigma_angle_rad: 0.25,
        depth_m: 0.005,
    },
    // Patella: a slight bump in front of the knee.
    Feature {
        y_m: 0.52,
        sigma_y_m: 0.028,
        angle_rad: FRAC_PI_2,
        sigma_angle_rad: 0.35,
        depth_m: -0.003,
    },
];

/// Writes the procedural leg as a GLB.
#[derive(Parser)]
struct Args {
    /// Output file (.glb).
    output: PathBuf,
    /// Also render a preview PNG: front, side, back and other side, and cross-sections.
    #[arg(long, value_name = "FILE.png")]
    preview: Option<PathBuf>,
}

fn main() -> Result<(), Box<dyn Error>> {
    let args = Args::parse();
    let profile = Profile::new();
    let rings: Vec<Ring> = (0..RINGS_ALONG)
        .map(|j| {
            let t = j as f64 / (RINGS_ALONG - 1) as f64;
            profile.ring(BOTTOM_Y_M + t * (TOP_Y_M - BOTTOM_Y_M))
        })
        .collect();
    let mesh = Mesh::from_rings(&rings);
    mesh.check_orientation()?;

    report_rings(&rings);
    let bytes = write_glb(&mesh)?;
    std::fs::write(&args.output, &bytes)?;
    println!(
        "wrote {} ({} bytes): {} vertices, {} triangles",
        args.output.display(),
        bytes.len(),
        mesh.positions.len(),
        mesh.indices.len() / 3
    );
    read_back(&bytes)?;

    if let Some(path) = &args.preview {
        render_preview(&mesh, &rings, path)?;
        println!("preview: {}", path.display());
    }
    Ok(())
}

/// Monotone cubic Hermite interpolation (Fritsch–Carlson slopes, Brodlie's weighted harmonic
/// mean); constant beyond the end points.
struct Monotone {
    xs: Vec<f64>,
    ys: Vec<f64>,
    slopes: Vec<f64>,
}

impl Monotone {
    fn new(xs: Vec<f64>, ys: Vec<f64>) -> Monotone {
        let n = xs.len();
        let h: Vec<f64> = xs.windows(2).map(|w| w[1] - w[0]).collect();
        let delta: Vec<f64> = (0..n - 1).map(|k| (ys[k + 1] - ys[k]) / h[k]).collect();
        let mut slopes = vec![0.0; n];
        slopes[0] = delta[0];
        slopes[n - 1] = delta[n - 2];
        for k in 1..n - 1 {
            if delta[k - 1] * delta[k] > 0.0 {
                let w1 = 2.0 * h[k] + h[k - 1];
                let w2 = h[k] + 2.0 * h[k - 1];
                slopes[k] = (w1 + w2) / (w1 / delta[k - 1] + w2 / delta[k]);
            }
        }
        Monotone { xs, ys, slopes }
    }

    fn at(&self, x: f64) -> f64 {
        let n = self.xs.len();
        if x <= self.xs[0] {
            return self.ys[0];
        }
        if x >= self.xs[n - 1] {
            return self.ys[n - 1];
        }
        let k = self.xs.partition_point(|&xk| xk <= x) - 1;
        let h = self.xs[k + 1] - self.xs[k];
        let t = (x - self.xs[k]) / h;
        let (t2, t3) = (t * t, t * t * t);
        (2.0 * t3 - 3.0 * t2 + 1.0) * self.ys[k]
            + (t3 - 2.0 * t2 + t) * h * self.slopes[k]
            + (-2.0 * t3 + 3.0 * t2) * self.ys[k + 1]
            + (t3 - t2) * h * self.slopes[k + 1]
    }
}

/// The control table interpolated along y.
struct Profile {
    girth_m: Monotone,
    width_over_depth: Monotone,
    back_bulge: Monotone,
    centre_z_m: Monotone,
}

/// One cross-section of the generated tube.
struct Ring {
    /// Height above the floor, m.
    y_m: f64,
    /// Centre, (x, z), m.
    centre: [f64; 2],
    /// Vertices, (x, z), m, counter-clockwise seen from above (from +X toward +Z).
    points: Vec<[f64; 2]>,
}

impl Profile {
    fn new() -> Profile {
        let column = |f: fn(&Section) -> f64| {
            Monotone::new(
                CONTROL.iter().map(|s| s.y_m).collect(),
                CONTROL.iter().map(f).collect(),
            )
        };
        Profile {
            girth_m: column(|s| s.girth_m),
            width_over_depth: column(|s| s.width_over_depth),
            back_bulge: column(|s| s.back_bulge),
            centre_z_m: column(|s| s.centre_z_m),
        }
    }

    /// The ring at height `y_m`, scaled so its polygon perimeter is the interpolated girth.
    fn ring(&self, y_m: f64) -> Ring {
        let girth = self.girth_m.at(y_m);
        let ratio = self.width_over_depth.at(y_m);
        let bulge = self.back_bulge.at(y_m);
        let centre = [0.0, self.centre_z_m.at(y_m)];
        // Semi-axes with about the right perimeter (Ramanujan), so feature depths are in metres;
        // the exact scale is set below.
        let (a, b) = (ratio, 1.0);
        let h = ((a - b) / (a + b)).powi(2);
        let unit_perimeter = PI * (a + b) * (1.0 + 3.0 * h / (10.0 + (4.0 - 3.0 * h).sqrt()));
        let (a, b) = (a * girth / unit_perimeter, b * girth / unit_perimeter);
        let shape: Vec<[f64; 2]> = (0..POINTS_AROUND)
            .map(|i| {
                let theta = TAU * i as f64 / POINTS_AROUND as f64;
                let (sin, cos) = theta.sin_cos();
                let q = [a * cos, b * (sin - bulge * sin * sin)];
                let r = q[0].hypot(q[1]);
                let dent: f64 = FEATURES.iter().map(|f| f.depth_at(y_m, theta)).sum();
                let s = (r - dent) / r;
                [q[0] * s, q[1] * s]
            })
            .collect();
        let scale = girth / perimeter(&shape);
        let points = shape
            .iter()
            .map(|q| [centre[0] + scale * q[0], centre[1] + scale * q[1]])
            .collect();
        Ring {
            y_m,
            centre,
            points,
        }
    }
}

impl Feature {
    fn depth_at(&self, y_m: f64, angle_rad: f64) -> f64 {
        let dy = (y_m - self.y_m) / self.sigma_y_m;
        let da = ((angle_rad - self.angle_rad + PI).rem_euclid(TAU) - PI) / self.sigma_angle_rad;
        self.depth_m * (-0.5 * (dy * dy + da * da)).exp()
    }
}

/// Perimeter of a closed polygon in the plane.
fn perimeter(points: &[[f64; 2]]) -> f64 {
    (0..points.len())
        .map(|i| {
            let (p, q) = (points[i], points[(i + 1) % points.len()]);
            (q[0] - p[0]).hypot(q[1] - p[1])
        })
        .sum()
}

/// Vertices of a ring where the outline turns clockwise (concave seen from outside).
fn concave_vertices(ring: &Ring) -> usize {
    let n = ring.points.len();
    (0..n)
        .filter(|&i| {
            let [p, q, r] = [(i + n - 1) % n, i, (i + 1) % n].map(|k| ring.points[k]);
            let turn = (q[0] - p[0]) * (r[1] - q[1]) - (q[1] - p[1]) * (r[0] - q[0]);
            turn < 0.0
        })
        .count()
}

/// Width (X extent) and depth (Z extent) of a ring, m.
fn extents(ring: &Ring) -> (f64, f64) {
    let span = |k: usize| {
        let lo = ring
            .points
            .iter()
            .map(|p| p[k])
            .fold(f64::INFINITY, f64::min);
        let hi = ring
            .points
            .iter()
            .map(|p| p[k])
            .fold(f64::NEG_INFINITY, f64::max);
        hi - lo
    };
    (span(0), span(1))
}

/// Prints the girths measured on the generated rings at the landmarks, and where rings are
/// concave.
fn report_rings(rings: &[Ring]) {
    let nearest = |y: f64| {
        rings
            .iter()
            .min_by(|a, b| (a.y_m - y).abs().total_cmp(&(b.y_m - y).abs()))
            .expect("rings")
    };
    let extreme = |lo: f64, hi: f64, max: bool| {
        rings
            .iter()
            .filter(|r| (lo..=hi).contains(&r.y_m))
            .max_by(|a, b| {
                let order = perimeter(&a.points).total_cmp(&perimeter(&b.points));
                if max {
                    order
                } else {
                    order.reverse()
                }
            })
            .expect("rings in range")
    };
    let landmarks = [
        ("ankle (ring nearest y=0.10)", nearest(0.10)),
        ("calf max (y in 0.25..0.45)", extreme(0.25, 0.45, true)),
        (
            "below-knee min (y in 0.40..0.49)",
            extreme(0.40, 0.49, false),
        ),
        ("knee (ring nearest y=0.50)", nearest(0.50)),
        ("thigh (ring nearest y=0.80)", nearest(0.80)),
    ];
    println!("measured girths (polygon perimeter of the generated rings):");
    for (name, ring) in landmarks {
        let (width, depth) = extents(ring);
        println!(
            "  {name:34} y = {:.3} m  girth = {:.1} cm  width x depth = {:.1} x {:.1} cm  centre z = {:+.1} cm",
            ring.y_m,
            100.0 * perimeter(&ring.points),
            100.0 * width,
            100.0 * depth,
            100.0 * ring.centre[1],
        );
    }
    let concave: Vec<(f64, usize)> = rings
        .iter()
        .map(|r| (r.y_m, concave_vertices(r)))
        .filter(|&(_, n)| n > 0)
        .collect();
    let mut bands: Vec<(f64, f64, usize)> = Vec::new();
    let step = (TOP_Y_M - BOTTOM_Y_M) / (RINGS_ALONG - 1) as f64;
    for (y, n) in concave {
        match bands.last_mut() {
            Some(band) if y - band.1 < 1.5 * step => {
                band.1 = y;
                band.2 = band.2.max(n);
            }
            _ => bands.push((y, y, n)),
        }
    }
    for (lo, hi, n) in bands {
        println!("  concave ring vertices for y in {lo:.3}..{hi:.3} m (up to {n} per ring)");
    }
}

/// The triangle surface: positions, unit normals and counter-clockwise triangles.
struct Mesh {
    positions: Vec<[f64; 3]>,
    normals: Vec<[f64; 3]>,
    indices: Vec<u32>,
}

impl Mesh {
    /// The tube through `rings` plus a fan cap at each end on its own rim vertices.
    fn from_rings(rings: &[Ring]) -> Mesh {
        let n = POINTS_AROUND;
        let mut positions: Vec<[f64; 3]> = rings
            .iter()
            .flat_map(|r| r.points.iter().map(|p| [p[0], r.y_m, p[1]]))
            .collect();
        let index = |j: usize, i: usize| (j * n + i % n) as u32;
        let mut indices = Vec::with_capacity(6 * n * rings.len());
        for j in 0..rings.len() - 1 {
            for i in 0..n {
                // Around (+i) then up (+j) is clockwise seen from outside, so go up first.
                let [v00, v10, v01, v11] = [
                    index(j, i),
                    index(j, i + 1),
                    index(j + 1, i),
                    index(j + 1, i + 1),
                ];
                indices.extend_from_slice(&[v00, v01, v10, v10, v01, v11]);
            }
        }
        let mut normals = vec![[0.0; 3]; positions.len()];
        for t in indices.chunks_exact(3) {
            let face = face_normal(&positions, t);
            for &v in t {
                for k in 0..3 {
                    normals[v as usize][k] += face[k];
                }
            }
        }
        for normal in &mut normals {
            *normal = normalized(*normal);
        }
        // Caps: a centre vertex and a copy of the rim, all with the cap's flat normal.
        for (ring, down) in [(&rings[0], true), (&rings[rings.len() - 1], false)] {
            let centre = positions.len() as u32;
            positions.push([ring.centre[0], ring.y_m, ring.centre[1]]);
            positions.extend(ring.points.iter().map(|p| [p[0], ring.y_m, p[1]]));
            let normal = [0.0, if down { -1.0 } else { 1.0 }, 0.0];
            normals.resize(positions.len(), normal);
            for i in 0..n as u32 {
                let (a, b) = (centre + 1 + i, centre + 1 + (i + 1) % n as u32);
                // The rim runs counter-clockwise seen from above (+Y).
                if down {
                    indices.extend_from_slice(&[centre, a, b]);
                } else {
                    indices.extend_from_slice(&[centre, b, a]);
                }
            }
        }
        Mesh {
            positions,
            normals,
            indices,
        }
    }

    /// Checks that the winding is outward: the enclosed volume is positive and every face normal
    /// agrees with its vertices' normals.
    fn check_orientation(&self) -> Result<(), Box<dyn Error>> {
        let mut volume = 0.0;
        for t in self.indices.chunks_exact(3) {
            let [a, b, c] = [0, 1, 2].map(|k| self.positions[t[k] as usize]);
            volume += dot(a, cross(b, c)) / 6.0;
            let face = face_normal(&self.positions, t);
            if t.iter()
                .any(|&v| dot(face, self.normals[v as usize]) <= 0.0)
            {
                return Err(format!("triangle {t:?} disagrees with its vertex normals").into());
            }
        }
        if volume <= 0.0 {
            return Err(format!("enclosed volume {volume} m³ is not positive").into());
        }
        println!("enclosed volume: {:.2} L", volume * 1000.0);
        Ok(())
    }
}

fn face_normal(positions: &[[f64; 3]], t: &[u32]) -> [f64; 3] {
    let [a, b, c] = [0, 1, 2].map(|k| positions[t[k] as usize]);
    cross(sub(b, a), sub(c, a))
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn normalized(a: [f64; 3]) -> [f64; 3] {
    let length = dot(a, a).sqrt();
    [a[0] / length, a[1] / length, a[2] / length]
}

/// Encodes the mesh as a GLB: one TRIANGLES primitive with POSITION and NORMAL, in mesh "leg"
/// under node "leg".
fn write_glb(mesh: &Mesh) -> Result<Vec<u8>, Box<dyn Error>> {
    let mut doc = GlbBuilder::default();
    let mut attributes = BTreeMap::new();
    attributes.insert(
        Valid(json::mesh::Semantic::Positions),
        doc.positions(&mesh.positions),
    );
    // `positions` writes any VEC3 float accessor; the min/max it adds are allowed on normals.
    attributes.insert(
        Valid(json::mesh::Semantic::Normals),
        doc.positions(&mesh.normals),
    );
    let indices = doc.indices(&mesh.indices);
    let leg = doc.root.push(json::Mesh {
        extensions: None,
        extras: Default::default(),
        name: Some("leg".into()),
        primitives: vec![json::mesh::Primitive {
            attributes,
            extensions: None,
            extras: Default::default(),
            indices: Some(indices),
            material: None,
            mode: Valid(json::mesh::Mode::Triangles),
            targets: None,
        }],
        weights: None,
    });
    let node = doc.root.push(json::Node {
        mesh: Some(leg),
        name: Some("leg".into()),
        ..Default::default()
    });
    let scene = doc.root.push(json::Scene {
        extensions: None,
        extras: Default::default(),
        name: Some("procedural leg".into()),
        nodes: vec![node],
    });
    doc.root.scene = Some(scene);
    Ok(doc.finish()?)
}

/// Reads the GLB back with the `gltf` crate and prints its triangle count and bounding box.
fn read_back(bytes: &[u8]) -> Result<(), Box<dyn Error>> {
    let (document, buffers, _) = gltf::import_slice(bytes)?;
    let mut triangles = 0;
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    let mut worst_normal = 0.0_f32;
    for mesh in document.meshes() {
        for primitive in mesh.primitives() {
            if primitive.mode() != gltf::mesh::Mode::Triangles {
                return Err("read back a primitive that is not TRIANGLES".into());
            }
            let reader = primitive.reader(|b| Some(&buffers[b.index()]));
            triangles += reader
                .read_indices()
                .ok_or("read back a primitive without indices")?
                .into_u32()
                .count()
                / 3;
            for p in reader.read_positions().ok_or("no POSITION")? {
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
            for n in reader.read_normals().ok_or("no NORMAL")? {
                let length = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
                worst_normal = worst_normal.max((length - 1.0).abs());
            }
        }
    }
    println!(
        "read back with gltf: {triangles} triangles; bounding box x {:.4}..{:.4}, y {:.4}..{:.4}, \
         z {:.4}..{:.4} m; normals unit to within {worst_normal:.1e}",
        lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]
    );
    Ok(())
}

/// Preview scale, pixels per metre.
const PX_PER_M: f64 = 1000.0;
/// Width of one view in the preview, pixels.
const PANEL_PX: u32 = 260;
/// Height of the preview, pixels (0.9 m).
const PREVIEW_HEIGHT_PX: u32 = 900;

/// Renders four shaded orthographic views (front, right side, back, left side) and a panel of
/// cross-sections drawn at their heights (front up, concave vertices red), on a 10 cm grid.
fn render_preview(mesh: &Mesh, rings: &[Ring], path: &Path) -> Result<(), Box<dyn Error>> {
    let views: [([f64; 3], [f64; 3]); 4] = [
        ([0.0, 0.0, 1.0], [1.0, 0.0, 0.0]),   // front: camera at +Z
        ([1.0, 0.0, 0.0], [0.0, 0.0, -1.0]),  // side: camera at +X, front to the left
        ([0.0, 0.0, -1.0], [-1.0, 0.0, 0.0]), // back: camera at -Z
        ([-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]),  // other side: front to the right
    ];
    let width = PANEL_PX * (views.len() as u32 + 1);
    let mut image = image::RgbImage::from_pixel(width, PREVIEW_HEIGHT_PX, image::Rgb([255; 3]));
    let to_row = |y: f64| PREVIEW_HEIGHT_PX as f64 - y * PX_PER_M;
    for step in 0..=9 {
        let row = to_row(step as f64 * 0.1).round() as u32;
        let shade = if step == 0 { 120 } else { 225 };
        for x in 0..width {
            image.put_pixel(x, row.min(PREVIEW_HEIGHT_PX - 1), image::Rgb([shade; 3]));
        }
    }
    for (panel, (toward, right)) in views.iter().enumerate() {
        let centre = (panel as f64 + 0.5) * PANEL_PX as f64;
        let project = |p: [f64; 3]| {
            [
                centre + dot(p, *right) * PX_PER_M,
                to_row(p[1]),
                dot(p, *toward),
            ]
        };
        let light = normalized([toward[0] + 0.4 * right[0], 0.5, toward[2] + 0.4 * right[2]]);
        let mut depth = vec![f64::NEG_INFINITY; (PANEL_PX * PREVIEW_HEIGHT_PX) as usize];
        let mut normal_at = vec![[0.0; 3]; depth.len()];
        for t in mesh.indices.chunks_exact(3) {
            let v = [0, 1, 2].map(|k| project(mesh.positions[t[k] as usize]));
            let n = [0, 1, 2].map(|k| mesh.normals[t[k] as usize]);
            let area = (v[1][0] - v[0][0]) * (v[2][1] - v[0][1])
                - (v[1][1] - v[0][1]) * (v[2][0] - v[0][0]);
            if area.abs() < 1e-12 {
                continue;
            }
            let x0 = v
                .iter()
                .map(|p| p[0])
                .fold(f64::INFINITY, f64::min)
                .floor()
                .max(0.0) as u32;
            let x1 = v
                .iter()
                .map(|p| p[0])
                .fold(f64::NEG_INFINITY, f64::max)
                .ceil() as u32;
            let y0 = v
                .iter()
                .map(|p| p[1])
                .fold(f64::INFINITY, f64::min)
                .floor()
                .max(0.0) as u32;
            let y1 = v
                .iter()
                .map(|p| p[1])
                .fold(f64::NEG_INFINITY, f64::max)
                .ceil() as u32;
            let panel_x0 = panel as u32 * PANEL_PX;
            for py in y0..y1.min(PREVIEW_HEIGHT_PX) {
                for px in x0.max(panel_x0)..x1.min(panel_x0 + PANEL_PX) {
                    let (sx, sy) = (px as f64 + 0.5, py as f64 + 0.5);
                    let edge = |a: [f64; 3], b: [f64; 3]| {
                        ((b[0] - a[0]) * (sy - a[1]) - (b[1] - a[1]) * (sx - a[0])) / area
                    };
                    let w = [edge(v[1], v[2]), edge(v[2], v[0]), edge(v[0], v[1])];
                    if w.iter().any(|&wk| wk < 0.0) {
                        continue;
                    }
                    let z = w[0] * v[0][2] + w[1] * v[1][2] + w[2] * v[2][2];
                    let cell = (py * PANEL_PX + px - panel_x0) as usize;
                    if z > depth[cell] {
                        depth[cell] = z;
                        normal_at[cell] =
                            [0, 1, 2].map(|k| w[0] * n[0][k] + w[1] * n[1][k] + w[2] * n[2][k]);
                    }
                }
            }
        }
        for (cell, z) in depth.iter().enumerate() {
            if z.is_finite() {
                let lambert = dot(normalized(normal_at[cell]), light).max(0.0);
                let shade = 0.2 + 0.8 * lambert;
                let colour = [230.0, 180.0, 150.0].map(|c| (c * shade) as u8);
                let (px, py) = (cell as u32 % PANEL_PX, cell as u32 / PANEL_PX);
                image.put_pixel(panel as u32 * PANEL_PX + px, py, image::Rgb(colour));
            }
        }
    }
    // Cross-sections, seen from above with the front up, each at its own height.
    let centre = (views.len() as f64 + 0.5) * PANEL_PX as f64;
    for y in [0.13, 0.35, 0.49, 0.80] {
        let ring = rings
            .iter()
            .min_by(|a, b| (a.y_m - y).abs().total_cmp(&(b.y_m - y).abs()))
            .expect("rings");
        let n = ring.points.len();
        let to_pixel = |p: [f64; 2]| [centre + p[0] * PX_PER_M, to_row(ring.y_m) - p[1] * PX_PER_M];
        for i in 0..n {
            let [p, q, r] = [(i + n - 1) % n, i, (i + 1) % n].map(|k| ring.points[k]);
            let turn = (q[0] - p[0]) * (r[1] - q[1]) - (q[1] - p[1]) * (r[0] - q[0]);
            let colour = if turn < 0.0 {
                [220, 0, 0]
            } else {
                [40, 40, 40]
            };
            let (a, b) = (to_pixel(q), to_pixel(r));
            for s in 0..=20 {
                let t = s as f64 / 20.0;
                let (x, y) = (a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]));
                if x >= 0.0 && y >= 0.0 && (x as u32) < width && (y as u32) < PREVIEW_HEIGHT_PX {
                    image.put_pixel(x as u32, y as u32, image::Rgb(colour));
                }
            }
        }
        let [cx, cy] = to_pixel([0.0, 0.0]);
        for d in -3..=3 {
            image.put_pixel((cx as i32 + d) as u32, cy as u32, image::Rgb([0, 0, 200]));
            image.put_pixel(cx as u32, (cy as i32 + d) as u32, image::Rgb([0, 0, 200]));
        }
    }
    image.save(path)?;
    Ok(())
}
