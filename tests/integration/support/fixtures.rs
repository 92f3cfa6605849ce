//! The meshes the tests fit, query and damage: the bundled sample legs (loaded as knitfit loads
//! them, or raw, as their files hold them), closed surfaces made on a grid (a sphere, a rod, a
//! torus, a leg-like body of revolution), and an open tube, written as GLB files by knitfit's own
//! writer (no hand-written glTF), and legs as PLY in each encoding.

use std::path::{Path, PathBuf};

use knitfit::base::{SurfaceMesh, Vec3};
use knitfit::export::gltf::{write_nodes_glb, GlbNode};
use knitfit::export::ply::write_mesh_ply;
use knitfit::fit::{FitSettings, SolvedFit};
use knitfit::leg::{load_leg, Leg, Units, UpAxis, UpChoice};
use knitfit::plan::Plan;
use knitfit::scene::{LoadedScene, Scene};
use knitfit::stage::NoProgress;
use nalgebra::{Matrix4, Point3};
use ply_rs_bw::ply::{DefaultElement, Encoding};

/// The bundled sample file `name` (in `samples/`).
pub fn sample(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("samples")
        .join(name)
}

/// Every bundled sample leg.
pub fn sample_legs() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("samples");
    let mut legs: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "glb"))
        .collect();
    legs.sort();
    assert!(!legs.is_empty());
    legs
}

/// The bundled sample legs with a foot (the stocking runs to the toe on them).
pub const FEET: [&str; 4] = [
    "makehuman_leg_foot.glb",
    "lowpoly_leg.glb",
    "makehuman_body.glb",
    "makehuman_hips_heavy.glb",
];

/// The procedural sample leg: closed, Y-up, at the origin; the tests that edit a leg file or
/// know its triangle count use it.
pub fn procedural_leg() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("samples/procedural_leg.glb")
}

/// A sample leg loaded as glTF says: metres, +Y up.
pub fn load_sample(path: &Path) -> Leg {
    load_leg(path, Units::Metres, UpChoice::Axis(UpAxis::PosY)).unwrap()
}

/// The stocking `scene` fits onto the leg file `leg`, solved and nothing more (no fields, no
/// products): the fit library's one call, as a script would make it.
pub fn solve_on(leg: &Path, scene: &Scene) -> SolvedFit {
    let loaded = LoadedScene {
        scene: scene.clone(),
        name: "test".into(),
        path: None,
        overrides: Vec::new(),
    };
    let settings = FitSettings {
        measure: false,
        products: None,
        ..Plan::fit(scene).fit_settings(&loaded)
    };
    let (leg, _) = knitfit::fit::load(leg, &settings, &mut ()).unwrap();
    knitfit::fit::fit(leg, &settings, &mut (), &mut NoProgress)
        .unwrap()
        .solved
}

/// A leg made of `positions` and `triangles`, in metres with +Y up, named `name`.
fn leg(name: &str, positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> Leg {
    Leg {
        path: name.into(),
        positions: positions.into_iter().map(Point3::from).collect(),
        triangles,
        units: Units::Metres,
        up_axis: UpAxis::PosY,
        up_from: knitfit::leg::UpFrom::Given,
        up: Vec3::y(),
        cleaned: Default::default(),
        reoriented_triangles: 0,
        material: None,
        rig: None,
        rest: None,
    }
}

/// A closed surface of `around × along` quads from `point(u, v)`, u around (0..1, periodic) and
/// v along (0..1); without `periodic_v`, the rings at v = 0 and v = 1 are capped by a fan from
/// their centre (a sphere whose poles are small rings, a rod); with it, v is periodic too (a
/// torus). Counter-clockwise seen from outside when `point` turns counter-clockwise seen from
/// +v's end.
pub fn grid_surface(
    name: &str,
    around: usize,
    along: usize,
    periodic_v: bool,
    point: impl Fn(f64, f64) -> Vec3,
) -> Leg {
    let rings = if periodic_v { along } else { along + 1 };
    let mut positions = Vec::new();
    for j in 0..rings {
        for i in 0..around {
            positions.push(point(i as f64 / around as f64, j as f64 / along as f64));
        }
    }
    let id = |i: usize, j: usize| ((j % rings) * around + i % around) as u32;
    let mut triangles = Vec::new();
    for j in 0..along {
        for i in 0..around {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
    }
    if !periodic_v {
        for (j, outward_down) in [(0, true), (along, false)] {
            let centre: Vec3 = (0..around)
                .map(|i| positions[id(i, j) as usize])
                .sum::<Vec3>()
                / around as f64;
            let c = positions.len() as u32;
            positions.push(centre);
            for i in 0..around {
                let (a, b) = (id(i, j), id(i + 1, j));
                triangles.push(if outward_down { [c, b, a] } else { [c, a, b] });
            }
        }
    }
    leg(name, positions, triangles)
}

/// A closed body of revolution around +Y from `y0` to `y1`: radius `radius(h)` at `h` in 0..1,
/// `along + 1` rings of `around` vertices, capped at both ends (a rod, or a leg-like shape).
pub fn revolved(
    name: &str,
    around: usize,
    along: usize,
    (y0, y1): (f64, f64),
    radius: impl Fn(f64) -> f64,
) -> Leg {
    grid_surface(name, around, along, false, |u, h| {
        let (t, r) = (std::f64::consts::TAU * u, radius(h));
        Vec3::new(r * t.cos(), y0 + (y1 - y0) * h, -r * t.sin())
    })
}

/// An open tube: `along + 1` rings of `around` vertices, ring `j`'s vertex `i` at
/// `ring_point(j / along, angle)` (angle 0..2π), quads split in two, counter-clockwise seen from
/// outside for a ring that runs counter-clockwise seen from +Y.
fn tube_mesh(
    around: usize,
    along: usize,
    ring_point: impl Fn(f64, f64) -> [f64; 3],
) -> SurfaceMesh {
    let mut positions = Vec::new();
    for j in 0..=along {
        for i in 0..around {
            let angle = std::f64::consts::TAU * i as f64 / around as f64;
            positions.push(ring_point(j as f64 / along as f64, angle));
        }
    }
    let mut triangles = Vec::new();
    for j in 0..along {
        for i in 0..around {
            let a = (j * around + i) as u32;
            let b = (j * around + (i + 1) % around) as u32;
            let (c, d) = (b + around as u32, a + around as u32);
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
    }
    SurfaceMesh::new("leg", positions, triangles)
}

/// Writes [`tube_mesh`] as a GLB `dir/name`.
pub fn write_tube_leg(
    dir: &Path,
    name: &str,
    around: usize,
    along: usize,
    ring_point: impl Fn(f64, f64) -> [f64; 3],
) -> PathBuf {
    write_meshes(dir, name, &[tube_mesh(around, along, ring_point)])
}

/// Writes one GLB `dir/name` with a root node per mesh.
pub fn write_meshes(dir: &Path, name: &str, meshes: &[SurfaceMesh]) -> PathBuf {
    let nodes: Vec<GlbNode> = meshes.iter().map(GlbNode::Surface).collect();
    let path = dir.join(name);
    std::fs::write(&path, write_nodes_glb(&nodes, [[0.5; 3]; 3]).unwrap()).unwrap();
    path
}

/// Writes `positions` and `triangles` as a one-mesh GLB `dir/name`.
pub fn write_mesh(
    dir: &Path,
    name: &str,
    positions: &[Point3<f64>],
    triangles: Vec<[u32; 3]>,
) -> PathBuf {
    let positions = positions.iter().map(|p| p.coords.into()).collect();
    write_meshes(dir, name, &[SurfaceMesh::new("leg", positions, triangles)])
}

/// The axis a fit at the defaults places on `leg`'s landmarks.
pub fn landmark_axis(leg: &Leg) -> knitfit::leg::Axis {
    use knitfit::knit::tube::tube_axis;
    use knitfit::knit::{TubeBottom, TubeTop};
    use knitfit::leg::{find_landmarks, Side};
    let landmarks =
        find_landmarks(&leg.positions, &leg.triangles, leg.up, Side::Left, None).unwrap();
    tube_axis(&landmarks, TubeBottom::Ankle, TubeTop::default()).unwrap()
}

/// `leg`'s mesh as a PLY file in `encoding`: written by knitfit's own writer (binary
/// little-endian, as `leg.ply`), then re-encoded by the PLY crate for the other encodings.
pub fn leg_as_ply(leg: &Leg, encoding: Encoding) -> Vec<u8> {
    let positions = leg.positions.iter().map(|p| p.coords.into()).collect();
    let mesh = SurfaceMesh::new("leg", positions, leg.triangles.clone());
    let bytes = write_mesh_ply(&mesh, &[]).unwrap();
    if encoding == Encoding::BinaryLittleEndian {
        return bytes;
    }
    let mut ply = ply_rs_bw::parser::Parser::<DefaultElement>::new()
        .read_ply(&mut &bytes[..])
        .unwrap();
    ply.header.encoding = encoding;
    let mut out = Vec::new();
    ply_rs_bw::writer::Writer::new()
        .write_ply(&mut out, &mut ply)
        .unwrap();
    out
}

/// One mesh of a GLB file as the file holds it: nothing welded, cleaned or rewound.
#[derive(Clone, Debug)]
pub struct RawMesh {
    /// The mesh's name (its node's where the mesh has none).
    pub name: String,
    /// Vertex positions, file coordinates (node transforms applied).
    pub positions: Vec<Point3<f64>>,
    /// Triangles as indices into `positions`, wound as in the file.
    pub triangles: Vec<[u32; 3]>,
}

/// The meshes under the default scene of the GLB `path`, one per node with a mesh, in the order
/// knitfit's loader takes them (depth first, document order). Only triangle lists and
/// transforms that keep handedness, as the sample legs have.
pub fn read_glb_meshes(path: &Path) -> Vec<RawMesh> {
    let (document, buffers, _) = gltf::import(path).unwrap();
    let scene = document
        .default_scene()
        .or_else(|| document.scenes().next())
        .unwrap();
    let mut meshes = Vec::new();
    let mut stack: Vec<(gltf::Node, Matrix4<f64>)> =
        scene.nodes().map(|n| (n, Matrix4::identity())).collect();
    stack.reverse();
    while let Some((node, file_from_parent)) = stack.pop() {
        let file_from_node =
            file_from_parent * Matrix4::from(node.transform().matrix()).cast::<f64>();
        assert!(file_from_node.fixed_view::<3, 3>(0, 0).determinant() > 0.0);
        if let Some(mesh) = node.mesh() {
            let name = mesh.name().or(node.name()).unwrap_or("mesh").to_string();
            let mut raw = RawMesh {
                name,
                positions: Vec::new(),
                triangles: Vec::new(),
            };
            for prim in mesh.primitives() {
                assert_eq!(
                    prim.mode(),
                    gltf::mesh::Mode::Triangles,
                    "{}",
                    path.display()
                );
                let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
                let first = raw.positions.len() as u32;
                raw.positions
                    .extend(reader.read_positions().unwrap().map(|p| {
                        file_from_node.transform_point(&Point3::new(p[0], p[1], p[2]).cast::<f64>())
                    }));
                let count = raw.positions.len() as u32 - first;
                let indices: Vec<u32> = match reader.read_indices() {
                    Some(i) => i.into_u32().collect(),
                    None => (0..count).collect(),
                };
                raw.triangles.extend(
                    indices
                        .chunks_exact(3)
                        .map(|t| [first + t[0], first + t[1], first + t[2]]),
                );
            }
            meshes.push(raw);
        }
        let first_child = stack.len();
        stack.extend(node.children().map(|c| (c, file_from_node)));
        stack[first_child..].reverse();
    }
    assert!(!meshes.is_empty(), "{}", path.display());
    meshes
}

/// Writes `meshes` as one GLB `dir/name`, a root node per mesh, positions as given (rounded to
/// 32-bit floats, as glTF stores them).
pub fn write_raw_meshes(dir: &Path, name: &str, meshes: &[RawMesh]) -> PathBuf {
    let surfaces: Vec<SurfaceMesh> = meshes
        .iter()
        .map(|m| {
            let positions = m.positions.iter().map(|p| p.coords.into()).collect();
            SurfaceMesh::new(&m.name, positions, m.triangles.clone())
        })
        .collect();
    write_meshes(dir, name, &surfaces)
}

/// Rewrites the procedural sample leg's JSON with `edit`, writing `name` (`.glb`) into `dir`.
pub fn edited_sample(dir: &Path, name: &str, edit: impl FnOnce(&mut gltf_json::Root)) -> PathBuf {
    edited_glb(&procedural_leg(), dir, name, edit)
}

/// Rewrites the JSON of the GLB file `source` with `edit`, its binary chunk kept, writing `name`
/// into `dir`.
pub fn edited_glb(
    source: &Path,
    dir: &Path,
    name: &str,
    edit: impl FnOnce(&mut gltf_json::Root),
) -> PathBuf {
    let bytes = std::fs::read(source).unwrap();
    let mut gltf = gltf::Gltf::from_slice(&bytes).unwrap();
    let mut root = gltf.document.clone().into_json();
    edit(&mut root);
    let glb = gltf::binary::Glb {
        header: gltf::binary::Header {
            magic: *b"glTF",
            version: 2,
            length: 0,
        },
        json: std::borrow::Cow::Owned(gltf_json::serialize::to_vec(&root).unwrap()),
        bin: Some(std::borrow::Cow::Owned(gltf.blob.take().unwrap())),
    };
    let path = dir.join(name);
    std::fs::write(&path, glb.to_vec().unwrap()).unwrap();
    path
}
