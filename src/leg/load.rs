//! Loading a leg from glTF 2.0 (`.glb`, or `.gltf` with external or embedded buffers) or PLY
//! (`.ply`, read by [`super::ply`]), the format chosen by the file's extension.
//!
//! From glTF, every triangle primitive under the default scene's nodes is taken, with node
//! transforms applied; a skinned mesh is posed by its joints instead (linear blend skinning,
//! glTF 2.0 §3.7.3), as viewers show it, and where that moves it from its rest pose, the rest
//! pose is kept beside it ([`RestPose`], for [`crate::fit::pose`]) with the joints' names and
//! places for [`super::rig`]. From PLY, every face, triangulated in its own plane. Either way the mesh
//! is then handled here, in one place: scaled to metres, cleaned ([`super::clean`]: repeated
//! vertices and faces, slivers, debris), and turned so that the file's up axis is +Y (glTF's
//! own convention, so a well-formed glTF file needs no turning; PLY has none). With
//! `up_axis: auto` the up axis is the file axis nearest the body's own up ([`anatomical_up`])
//! where its shape makes that clear, else glTF's +Y.
//! The mesh is checked: it must have triangles, finite coordinates, no compressed geometry, and
//! a plausible height.

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

use nalgebra::{Matrix4, Point3, Vector3};

use super::clean::{clean_mesh, Cleaned};
use super::landmarks::{anatomical_up, BodyUp};
use super::orient::orient_outward;
use super::ply::{self, PlyHeader};
use super::rig::Rig;
use crate::base::Material;
use crate::error::{Error, Result};
use crate::leg::{Units, UpAxis, UpChoice, UpFrom};

/// A leg mesh in world space: metres, Y up.
#[derive(Clone, Debug)]
pub struct Leg {
    /// The file it came from.
    pub path: PathBuf,
    /// Vertex positions, metres, Y up.
    pub positions: Vec<Point3<f64>>,
    /// Triangles as vertex indices, counter-clockwise seen from outside (rewound where the file
    /// had them the other way, see [`orient_outward`]).
    pub triangles: Vec<[u32; 3]>,
    /// How many of the file's triangles were wound inwards and have been flipped.
    pub reoriented_triangles: usize,
    /// The units the file was read in.
    pub units: Units,
    /// The up axis the file was read with (given, or the nearest to the body's up).
    pub up_axis: UpAxis,
    /// Where `up_axis` came from: given, or with `leg.up_axis: auto` the anatomy or, where
    /// that is not clear, glTF's +Y.
    pub up_from: UpFrom,
    /// Unit vector up the body, world space: +Y where the up axis was given; found from the
    /// anatomy with `auto` (then it turns with the body, so a turned copy of a leg gets the
    /// same landmarks, turned).
    pub up: Vector3<f64>,
    /// What cleaning removed.
    pub cleaned: Cleaned,
    /// The material most of the file's triangles had, where it is one `stocking.glb` can carry
    /// over (a glTF material without a base-colour texture: the leg is written without texture
    /// coordinates); `None` for a PLY file or an untextured-material-less glTF.
    pub material: Option<Material>,
    /// The leg joints the file's skins name, world space; `None` where it has no skin, or no
    /// skin naming a leg's hip, knee and ankle.
    pub rig: Option<Rig>,
    /// Where the file's skin poses the leg away from its rest pose: the leg at rest, where the
    /// stocking is fitted before the skin carries it into the pose ([`crate::fit::pose`]).
    pub rest: Option<Box<RestPose>>,
}

/// Shortest and tallest leg accepted, metres: outside this range the file is almost certainly
/// in other units than assumed.
pub const PLAUSIBLE_HEIGHT_M: (f64, f64) = (0.2, 3.0);

/// Largest coordinate accepted, metres from the file's origin, on any axis. Beyond it 32-bit
/// floats (glTF's positions) are coarser than a millimetre, several stitches, and a coordinate
/// far beyond it (a flipped exponent bit gives up to 3.4e38) makes the products of contact's
/// closest-point arithmetic overflow into infinities and NaN; so it is refused at the load.
pub const MAX_COORDINATE_M: f64 = 10_000.0;

/// Geometry compression extensions we cannot decode.
const COMPRESSION_EXTENSIONS: [&str; 3] = [
    "KHR_draco_mesh_compression",
    "EXT_meshopt_compression",
    "KHR_mesh_quantization",
];

impl Leg {
    /// A leg already in world space (metres, +Y up), cleaned and wound outwards: for meshes
    /// made in code.
    pub fn from_world(path: PathBuf, positions: &[Point3<f64>], triangles: &[[u32; 3]]) -> Leg {
        let (positions, mut triangles, cleaned) = clean_mesh(positions, triangles);
        let reoriented_triangles = orient_outward(&positions, &mut triangles);
        Leg {
            path,
            positions,
            triangles,
            reoriented_triangles,
            units: Units::Metres,
            up_axis: UpAxis::PosY,
            up_from: UpFrom::Given,
            up: Vector3::y(),
            cleaned,
            material: None,
            rig: None,
            rest: None,
        }
    }

    /// An open round tube up +Y for tests: `radius`, `height`, `sides` around, `bands` of
    /// triangles along.
    #[cfg(test)]
    pub fn round(radius: f64, height: f64, sides: u32, bands: u32) -> Leg {
        let mut positions = Vec::new();
        for ring in 0..=bands {
            for k in 0..sides {
                let a = std::f64::consts::TAU * k as f64 / sides as f64;
                let y = height * ring as f64 / bands as f64;
                positions.push(Point3::new(radius * a.cos(), y, radius * a.sin()));
            }
        }
        let mut triangles = Vec::new();
        for ring in 0..bands {
            for k in 0..sides {
                let (a, b) = (ring * sides + k, ring * sides + (k + 1) % sides);
                triangles.push([a, a + sides, b]);
                triangles.push([b, a + sides, b + sides]);
            }
        }
        Leg::from_world("round".into(), &positions, &triangles)
    }

    /// Converts a point in world space to the file's coordinates and units.
    pub fn file_from_world(&self, p: &Point3<f64>) -> Point3<f64> {
        let turned = turn_back(self.up_axis, p);
        Point3::from(turned.coords / self.units.metres())
    }

    /// Converts a point given in the file's coordinates and units to world space.
    pub fn world_from_file(&self, p_file: &Point3<f64>) -> Point3<f64> {
        world_from_file(self.units, self.up_axis, p_file)
    }

    /// Axis-aligned bounds of the vertices, world space.
    pub fn bounds(&self) -> (Point3<f64>, Point3<f64>) {
        let mut lo = Point3::from([f64::INFINITY; 3]);
        let mut hi = Point3::from([f64::NEG_INFINITY; 3]);
        for p in &self.positions {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        (lo, hi)
    }
}

/// Converts file coordinates to world space: scale to metres, then rotate the file's up axis
/// onto +Y (right-handed rotations only, so winding and handedness are kept).
pub fn world_from_file(units: Units, up: UpAxis, p: &Point3<f64>) -> Point3<f64> {
    turn(up, &Point3::from(p.coords * units.metres()))
}

/// Turns `p` so that the axis `up` points along +Y (a right-handed rotation by quarter turns:
/// exact in floating point).
fn turn(up: UpAxis, p: &Point3<f64>) -> Point3<f64> {
    let (x, y, z) = (p.x, p.y, p.z);
    let [x, y, z] = match up {
        UpAxis::PosY => [x, y, z],
        UpAxis::NegY => [x, -y, -z],
        UpAxis::PosZ => [x, z, -y],
        UpAxis::NegZ => [x, -z, y],
        UpAxis::PosX => [-y, x, z],
        UpAxis::NegX => [y, -x, z],
    };
    Point3::new(x, y, z)
}

/// The inverse of [`turn`].
fn turn_back(up: UpAxis, p: &Point3<f64>) -> Point3<f64> {
    let (x, y, z) = (p.x, p.y, p.z);
    let [x, y, z] = match up {
        UpAxis::PosY => [x, y, z],
        UpAxis::NegY => [x, -y, -z],
        UpAxis::PosZ => [x, -z, y],
        UpAxis::NegZ => [x, z, -y],
        UpAxis::PosX => [y, -x, z],
        UpAxis::NegX => [-y, x, z],
    };
    Point3::new(x, y, z)
}

/// The file axis nearest to `up` (a unit vector in file coordinates); ties go to the first in
/// [`UpAxis::ALL`].
fn nearest_axis(up: &Vector3<f64>) -> UpAxis {
    UpAxis::ALL
        .into_iter()
        .map(|axis| {
            (
                axis,
                turn_back(axis, &Point3::new(0.0, 1.0, 0.0)).coords.dot(up),
            )
        })
        .fold((UpAxis::PosY, f64::NEG_INFINITY), |best, (axis, along)| {
            if along > best.1 {
                (axis, along)
            } else {
                best
            }
        })
        .0
}

/// Loads the leg in `path`, read in `units` with `up` as its up axis.
pub fn load_leg(path: &Path, units: Units, up: UpChoice) -> Result<Leg> {
    decode_leg(read_leg_file(path)?, units, up)
}

/// A leg file whose document (a glTF document, or a PLY header) has been read and checked,
/// before any geometry is decoded: what a fit looks at to estimate the memory the leg will take
/// ([`crate::limits`]).
pub struct LegFile {
    path: PathBuf,
    document: Document,
}

/// A leg file's document, by format.
enum Document {
    Gltf(Box<gltf::Gltf>),
    /// The whole file, and what its header declares.
    Ply {
        bytes: Vec<u8>,
        header: PlyHeader,
    },
}

/// The leg file formats, by extension.
#[derive(Clone, Copy)]
enum Format {
    Gltf,
    Ply,
}

/// The format of the leg file `path`, from its extension (in any case).
fn format_of(path: &Path) -> Result<Format> {
    let extension = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    match extension.as_deref() {
        Some("glb" | "gltf") => Ok(Format::Gltf),
        Some("ply") => Ok(Format::Ply),
        other => Err(Error::Leg {
            path: path.to_path_buf(),
            message: match other {
                Some(ext) => format!("knitfit reads .glb, .gltf and .ply leg files, not .{ext}"),
                None => {
                    "knitfit reads .glb, .gltf and .ply leg files; this one has no extension".into()
                }
            },
        }),
    }
}

/// Reads the leg file `path` and checks its document: by extension, glTF (valid, no compressed
/// geometry) or PLY (a header [`ply::read_header`] accepts).
pub fn read_leg_file(path: &Path) -> Result<LegFile> {
    let format = format_of(path)?;
    let bytes = std::fs::read(path).map_err(|source| Error::Read {
        path: path.to_path_buf(),
        source,
    })?;
    let document = match format {
        Format::Gltf => Document::Gltf(Box::new(read_gltf(path, &bytes)?)),
        Format::Ply => {
            let header = ply::read_header(path, &bytes)?;
            Document::Ply { bytes, header }
        }
    };
    Ok(LegFile {
        path: path.to_path_buf(),
        document,
    })
}

/// Reads and checks the glTF document in `bytes`.
fn read_gltf(path: &Path, bytes: &[u8]) -> Result<gltf::Gltf> {
    let fail = |message: String| Error::Leg {
        path: path.to_path_buf(),
        message,
    };
    // Look at the extensions before validating: the validator rejects unsupported required
    // extensions with a message that does not say which one.
    let unchecked = gltf::Gltf::from_slice_without_validation(bytes)
        .map_err(|e| fail(format!("not a readable glTF file: {e}")))?;
    let mut extensions: Vec<&str> = unchecked
        .extensions_used()
        .chain(unchecked.extensions_required())
        .collect();
    extensions.sort_unstable();
    extensions.dedup();
    if let Some(ext) = extensions
        .iter()
        .find(|e| COMPRESSION_EXTENSIONS.contains(e))
    {
        return Err(fail(format!(
            "uses compressed geometry ({ext}), which knitfit cannot decode; re-export the leg \
             without mesh compression"
        )));
    }
    check_position_accessors(unchecked.document.as_json()).map_err(fail)?;
    gltf::Gltf::from_slice(bytes).map_err(|e| fail(invalid_gltf(&e)))
}

impl LegFile {
    /// Triangles the file declares, before decoding: for glTF, from the accessors' counts of the
    /// primitives under the default scene (a mesh instanced by two nodes counts twice, as it is
    /// loaded twice); for PLY, the header's face count (a polygon fans into more than one).
    pub fn declared_triangles(&self) -> usize {
        match &self.document {
            Document::Gltf(gltf) => declared_gltf_triangles(gltf),
            Document::Ply { header, .. } => header.faces,
        }
    }
}

/// Triangles the primitives under `gltf`'s default scene declare.
fn declared_gltf_triangles(gltf: &gltf::Gltf) -> usize {
    use gltf::mesh::Mode;
    let document = &gltf.document;
    let Some(scene) = document
        .default_scene()
        .or_else(|| document.scenes().next())
    else {
        return 0;
    };
    let mut stack: Vec<gltf::Node> = scene.nodes().collect();
    // glTF nodes form a tree, so a well-formed file visits each node at most once; the
    // bound keeps a malformed one (a node its own ancestor) from looping.
    let mut visits_left = document.nodes().len();
    let mut triangles = 0usize;
    while let Some(node) = stack.pop() {
        if visits_left == 0 {
            break;
        }
        visits_left -= 1;
        for prim in node.mesh().iter().flat_map(|m| m.primitives()) {
            let vertices = prim
                .indices()
                .or_else(|| prim.get(&gltf::Semantic::Positions))
                .map_or(0, |a| a.count());
            triangles = triangles.saturating_add(match prim.mode() {
                Mode::Triangles => vertices / 3,
                Mode::TriangleStrip | Mode::TriangleFan => vertices.saturating_sub(2),
                _ => 0,
            });
        }
        stack.extend(node.children());
    }
    triangles
}

/// Decodes the triangles of a leg file into world space, read in `units` with `choice` as its
/// up axis, cleans and checks them. A skinned mesh is read as its joints pose it, and where
/// that is not its rest pose, the rest pose is kept beside it ([`Leg::rest`]).
pub fn decode_leg(file: LegFile, units: Units, choice: UpChoice) -> Result<Leg> {
    let LegFile { path, document } = file;
    let mesh = match document {
        Document::Gltf(gltf) => decode_gltf(&path, *gltf)?,
        Document::Ply { bytes, .. } => {
            let mesh = ply::decode(&path, &bytes)?;
            FileMesh {
                positions_file: mesh.positions,
                triangles: mesh.triangles,
                material: None,
                skin: None,
            }
        }
    };
    let mut leg = leg_in_world(
        path.clone(),
        &mesh.positions_file,
        &mesh.triangles,
        units,
        choice,
    )?;
    leg.material = mesh.material;
    check_height(&leg)?;
    let Some(skin) = mesh.skin else {
        return Ok(leg);
    };
    let joints_in = |leg: &Leg, rest: bool| -> Vec<(String, Point3<f64>)> {
        let joints = skin.joints.iter();
        joints
            .map(|j| {
                (
                    j.name.clone(),
                    leg.world_from_file(if rest { &j.rest } else { &j.posed }),
                )
            })
            .collect()
    };
    leg.rig = Rig::from_joints(&joints_in(&leg, false));
    let moved = (mesh.positions_file.iter().zip(&skin.rest))
        .map(|(posed, rest)| (posed - rest).norm() * units.metres())
        .fold(0.0, f64::max);
    if moved <= POSED_M {
        return Ok(leg);
    }
    // A rest pose that is no plausible leg (no closed section to find up by, a height outside
    // the plausible range) is left: the leg is fitted as shown.
    let Ok(mut rest) = leg_in_world(path, &skin.rest, &mesh.triangles, units, choice) else {
        return Ok(leg);
    };
    if check_height(&rest).is_err() {
        return Ok(leg);
    }
    rest.rig = Rig::from_joints(&joints_in(&rest, true));
    let pose_from_rest = per_vertex(&rest, &skin.rest, &skin.pose_from_rest);
    leg.rest = Some(Box::new(RestPose {
        leg: rest,
        pose_from_rest,
        skin_moved_m: moved,
    }));
    Ok(leg)
}

/// A skinned leg whose vertices move further than this from the rest pose to the pose shown is
/// posed, metres.
pub const POSED_M: f64 = 0.001;

/// A posed leg's rest pose: a rigged leg's mesh as stored, before its skin moves it
/// ([`Leg::rest`]), or a leg straightened where its sections show it bends
/// ([`super::unbend`]).
#[derive(Clone, Debug)]
pub struct RestPose {
    /// The leg in its rest pose: cleaned and turned as the posed leg is, with its own up.
    pub leg: Leg,
    /// For each of its vertices, the matrix from the rest pose to the pose shown, in the
    /// file's coordinates and units (its skinning matrices blended by its weights).
    pub pose_from_rest: Vec<Matrix4<f64>>,
    /// Furthest a vertex moves from the rest pose to the pose shown, metres.
    pub skin_moved_m: f64,
}

/// Each vertex of `leg`'s matrix among `matrices`, one per file vertex `file_positions`
/// (cleaning keeps the file's coordinates, and adds only the centres of filled holes).
fn per_vertex(
    leg: &Leg,
    file_positions: &[Point3<f64>],
    matrices: &[Matrix4<f64>],
) -> Vec<Matrix4<f64>> {
    let world: Vec<Point3<f64>> = file_positions
        .iter()
        .map(|p| leg.world_from_file(p))
        .collect();
    matrices_at(&leg.positions, &world, matrices)
}

/// The matrix of each of `points` among `matrices`, one per vertex of `positions`: the vertex
/// at the point's very place, or where none is (a vertex added by cleaning or by splitting
/// pieces where they meet), the nearest.
pub(crate) fn matrices_at(
    points: &[Point3<f64>],
    positions: &[Point3<f64>],
    matrices: &[Matrix4<f64>],
) -> Vec<Matrix4<f64>> {
    let key = |p: &Point3<f64>| -> [u64; 3] { p.coords.map(f64::to_bits).into() };
    let mut index: HashMap<[u64; 3], usize> = HashMap::with_capacity(positions.len());
    for (i, p) in positions.iter().enumerate() {
        index.entry(key(p)).or_insert(i);
    }
    points
        .iter()
        .map(|p| {
            let i = index.get(&key(p)).copied().unwrap_or_else(|| {
                (0..positions.len())
                    .min_by(|&a, &b| {
                        (positions[a] - p)
                            .norm()
                            .total_cmp(&(positions[b] - p).norm())
                    })
                    .unwrap_or(0)
            });
            matrices.get(i).copied().unwrap_or_else(Matrix4::identity)
        })
        .collect()
}

/// The leg made of `positions_file` and `triangles`: scaled to metres, cleaned, turned so that
/// its up axis (given, or found from the anatomy) is +Y, and wound outwards. No material, rig
/// or rest pose.
fn leg_in_world(
    path: PathBuf,
    positions_file: &[Point3<f64>],
    triangles: &[[u32; 3]],
    units: Units,
    choice: UpChoice,
) -> Result<Leg> {
    let fail = |message: String| Error::Leg {
        path: path.clone(),
        message,
    };
    let scaled: Vec<Point3<f64>> = positions_file
        .iter()
        .map(|p| Point3::from(p.coords * units.metres()))
        .collect();
    check_coordinates(&scaled, triangles, units).map_err(fail)?;
    let (scaled, mut triangles, cleaned) = clean_mesh(&scaled, triangles);
    if triangles.is_empty() {
        return Err(fail("has no triangles with area".into()));
    }
    let (up_axis, up, up_from) = match choice {
        UpChoice::Axis(axis) => (axis, Vector3::y(), UpFrom::Given),
        UpChoice::Auto => match anatomical_up(&scaled, &triangles).filter(BodyUp::clear) {
            Some(body) => {
                let axis = nearest_axis(&body.up);
                let up = turn(axis, &Point3::from(body.up)).coords;
                (axis, up, UpFrom::Anatomy)
            }
            // The shape does not say (no closed section, or ends of a like girth): the file is
            // taken as glTF says files are.
            None => (UpAxis::PosY, Vector3::y(), UpFrom::Convention),
        },
    };
    let positions: Vec<Point3<f64>> = scaled.iter().map(|p| turn(up_axis, p)).collect();
    let reoriented_triangles = orient_outward(&positions, &mut triangles);
    Ok(Leg {
        path,
        positions,
        triangles,
        reoriented_triangles,
        units,
        up_axis,
        up_from,
        up,
        cleaned,
        material: None,
        rig: None,
        rest: None,
    })
}

/// A leg file's triangles as the file gives them, before the conversion to world space.
struct FileMesh {
    /// Vertex positions, file coordinates and units.
    positions_file: Vec<Point3<f64>>,
    /// Triangles as indices into `positions_file`, wound as in the file.
    triangles: Vec<[u32; 3]>,
    /// See [`Leg::material`].
    material: Option<Material>,
    /// Where a mesh is skinned: its rest pose and joints.
    skin: Option<FileSkin>,
}

/// A skinned file's rest pose and joints (file coordinates and units).
struct FileSkin {
    /// Each vertex at rest (as stored, off a skin: as placed).
    rest: Vec<Point3<f64>>,
    /// Each vertex's matrix from rest to the pose shown.
    pose_from_rest: Vec<Matrix4<f64>>,
    /// The skins' joints.
    joints: Vec<Joint>,
}

/// The triangles under `gltf`'s default scene, node transforms applied and skins posing theirs.
fn decode_gltf(path: &Path, gltf: gltf::Gltf) -> Result<FileMesh> {
    let fail = |message: String| Error::Leg {
        path: path.to_path_buf(),
        message,
    };
    let base = path.parent().filter(|p| !p.as_os_str().is_empty());
    let buffers = gltf::import_buffers(&gltf.document, base.or(Some(Path::new("."))), gltf.blob)
        .map_err(|e| fail(format!("cannot load buffers: {e}")))?;

    let mut mesh = MeshCollector::default();
    let scene = gltf
        .document
        .default_scene()
        .or_else(|| gltf.document.scenes().next())
        .ok_or_else(|| fail("has no scene".into()))?;
    mesh.scene(&scene, gltf.document.nodes().len(), &buffers)
        .map_err(fail)?;
    if mesh.triangles.is_empty() {
        return Err(fail(if mesh.other_primitives > 0 {
            format!(
                "has only line or point primitives ({}), no triangles to fit onto",
                mesh.other_primitives
            )
        } else {
            "has no triangles under its default scene".into()
        }));
    }
    let material = mesh.carried_material(&gltf.document);
    Ok(FileMesh {
        positions_file: mesh.positions,
        triangles: mesh.triangles,
        material,
        skin: mesh.skinned.then(|| FileSkin {
            rest: mesh.rest,
            pose_from_rest: mesh.pose_from_rest,
            joints: mesh.joints.into_values().collect(),
        }),
    })
}

/// The message for a document gltf refuses: its validation errors already say "invalid glTF:"
/// and end each with ";", so they are not prefixed again.
fn invalid_gltf(e: &gltf::Error) -> String {
    match e {
        gltf::Error::Validation(_) => e.to_string().trim_end_matches(';').to_string(),
        _ => format!("invalid glTF: {e}"),
    }
}

/// Refuses a primitive whose `POSITION` names an accessor the file does not have. The glTF
/// validator would report it, but gltf-json 1.4's check of the accessor's bounds indexes it
/// first and panics; so it is checked here, before validating.
pub(crate) fn check_position_accessors(root: &gltf::json::Root) -> std::result::Result<(), String> {
    let positions = gltf::json::validation::Checked::Valid(gltf::Semantic::Positions);
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            if let Some(accessor) = prim.attributes.get(&positions) {
                if accessor.value() >= root.accessors.len() {
                    return Err(format!(
                        "mesh {m} primitive {p}: POSITION names accessor {}, but the file has {}",
                        accessor.value(),
                        root.accessors.len()
                    ));
                }
            }
        }
    }
    Ok(())
}

/// Refuses a primitive whose positions are not float 3-vectors or whose indices are not
/// unsigned integer scalars, as glTF requires. Validation lets such types through, and the
/// reader then misreads the positions or, for indices, panics (`unreachable!`).
pub(crate) fn check_accessor_types(prim: &gltf::Primitive) -> std::result::Result<(), String> {
    use gltf::accessor::{DataType, Dimensions};
    if let Some(a) = prim.get(&gltf::Semantic::Positions) {
        if (a.data_type(), a.dimensions()) != (DataType::F32, Dimensions::Vec3) {
            return Err(format!(
                "its POSITION (accessor {}) is {:?} {:?}, not float VEC3",
                a.index(),
                a.data_type(),
                a.dimensions()
            ));
        }
        check_stride(&a, "its POSITION")?;
    }
    if let Some(a) = prim.indices() {
        let unsigned = matches!(a.data_type(), DataType::U8 | DataType::U16 | DataType::U32);
        if !unsigned || a.dimensions() != Dimensions::Scalar {
            return Err(format!(
                "its indices (accessor {}) are {:?} {:?}, not unsigned integer SCALAR",
                a.index(),
                a.data_type(),
                a.dimensions()
            ));
        }
    }
    Ok(())
}

/// Refuses a mesh with a vertex of its triangles further than [`MAX_COORDINATE_M`] from the
/// origin on any axis (`scaled`: metres, file axes), before anything computes with it.
fn check_coordinates(
    scaled: &[Point3<f64>],
    triangles: &[[u32; 3]],
    units: Units,
) -> std::result::Result<(), String> {
    // Every index names a vertex: both decoders refuse one past the last.
    let far = triangles
        .iter()
        .flatten()
        .map(|&i| (i, &scaled[i as usize]))
        // NaN is beyond every bound: `c.abs() > MAX` alone would let it through.
        .find(|(_, p)| p.iter().any(|c| c.is_nan() || c.abs() > MAX_COORDINATE_M));
    match far {
        None => Ok(()),
        Some((i, p)) => Err(format!(
            "vertex {i} is at ({:e}, {:e}, {:e}) m, beyond the ±{MAX_COORDINATE_M} m knitfit \
             accepts on any axis: the file is damaged, or not in {} (leg.units, --units)",
            p.x,
            p.y,
            p.z,
            units.name()
        )),
    }
}

/// Refuses a leg whose height is implausible in the assumed units, and says which units would fit.
fn check_height(leg: &Leg) -> Result<()> {
    let (lo, hi) = leg.bounds();
    let height = hi.y - lo.y;
    let (min, max) = PLAUSIBLE_HEIGHT_M;
    if (min..=max).contains(&height) {
        return Ok(());
    }
    let file_height = height / leg.units.metres();
    let fitting: Vec<&str> = [
        Units::Metres,
        Units::Decimetres,
        Units::Centimetres,
        Units::Millimetres,
        Units::Inches,
    ]
    .into_iter()
    .filter(|u| (min..=max).contains(&(file_height * u.metres())))
    .map(Units::name)
    .collect();
    let hint = if fitting.is_empty() {
        format!("check leg.up_axis or --up-axis ({})", leg.up_chosen())
    } else {
        format!(
            "it is probably in other units: set leg.units or --units to \"{}\" (now \"{}\"), \
             or check leg.up_axis ({})",
            fitting[0],
            leg.units.name(),
            leg.up_chosen()
        )
    };
    Err(Error::Leg {
        path: leg.path.clone(),
        message: format!(
            "the leg is {height:.4} m tall along its up axis, outside the plausible {min}–{max} m; \
             {hint}"
        ),
    })
}

impl Leg {
    /// How its up axis was chosen, for a message: the axis given, or what `auto` made of it.
    pub fn up_chosen(&self) -> String {
        let axis = self.up_axis.name();
        match self.up_from {
            UpFrom::Given => format!("now \"{axis}\""),
            UpFrom::Anatomy => format!("now \"auto\", which found {axis} from the anatomy"),
            UpFrom::Convention => format!(
                "now \"auto\", which took {axis}, glTF's convention, as the shape does not \
                 show which end is up"
            ),
        }
    }
}

/// Gathers triangles from a node tree, in the file's coordinates.
#[derive(Default)]
struct MeshCollector {
    positions: Vec<Point3<f64>>,
    triangles: Vec<[u32; 3]>,
    other_primitives: usize,
    /// Triangles per glTF material index.
    triangles_by_material: BTreeMap<usize, usize>,
    /// Every skin's joints by node index: name, and place in the file's coordinates as posed
    /// and in the rest pose.
    joints: BTreeMap<usize, Joint>,
    /// Each vertex in the rest pose (a skinned mesh's stored position; any other's as placed),
    /// file coordinates.
    rest: Vec<Point3<f64>>,
    /// Each vertex's matrix from the rest pose to the pose shown (identity off a skin).
    pose_from_rest: Vec<Matrix4<f64>>,
    /// True when a skinned mesh was read.
    skinned: bool,
}

/// A skin's joint: its name, and its place in the file's coordinates as posed and at rest (its
/// inverse bind matrix's inverse).
#[derive(Clone, Debug)]
struct Joint {
    name: String,
    posed: Point3<f64>,
    rest: Point3<f64>,
}

/// How a mesh's vertices are placed in the file: by its node's transform, or posed by a skin.
enum Placed {
    Rigid(Matrix4<f64>),
    Skinned(Skinning),
}

/// A skin as posed: each joint's matrix from the bind pose to the file's coordinates, as glTF
/// defines it (the joint node's transform in the file times its inverse bind matrix). A
/// skinned mesh's own node transform is not applied (glTF 2.0 §3.7.3.1).
struct Skinning {
    matrices: Vec<Matrix4<f64>>,
    /// The bind pose (the mesh as stored) placed in the file: the transform of the node above
    /// the skeleton's root joint.
    file_from_bind: Matrix4<f64>,
    bind_from_file: Matrix4<f64>,
}

/// A skinned primitive's skin and each of its vertices' matrix from the bind pose to the file.
type SkinnedVertices<'a> = (&'a Skinning, Vec<Matrix4<f64>>);

/// Every node's transform in the file's coordinates and its parent, by node index (`None` for a
/// node outside the scene, or a root).
struct PlacedNodes {
    file_from_node: Vec<Option<Matrix4<f64>>>,
    parent: Vec<Option<usize>>,
}

impl Placed {
    /// The transform of each of a skinned primitive's `count` vertices: linear blend skinning
    /// (the vertex's weights, sets 0 and 1, over its joints' matrices, weights scaled to sum to
    /// 1); `None` for a rigid mesh, placed by its node's transform alone.
    fn vertex_transforms<'a, 's, F>(
        &self,
        prim: &gltf::Primitive,
        reader: &gltf::mesh::Reader<'a, 's, F>,
        count: usize,
    ) -> std::result::Result<Option<SkinnedVertices<'_>>, String>
    where
        F: Clone + Fn(gltf::Buffer<'a>) -> Option<&'s [u8]>,
    {
        let skinning = match self {
            Placed::Rigid(_) => return Ok(None),
            Placed::Skinned(skinning) => skinning,
        };
        let mut sums = vec![Matrix4::zeros(); count];
        let mut weight_sums = vec![0.0f64; count];
        let mut sets = 0;
        for set in 0..2 {
            check_skin_accessor_types(prim, set)?;
            let (Some(joints), Some(weights)) = (reader.read_joints(set), reader.read_weights(set))
            else {
                continue;
            };
            sets += 1;
            let joints: Vec<[u16; 4]> = joints.into_u16().collect();
            let weights: Vec<[f32; 4]> = weights.into_f32().collect();
            if joints.len() != count || weights.len() != count {
                return Err(format!(
                    "JOINTS_{set} and WEIGHTS_{set} have {} and {} entries for {count} vertices",
                    joints.len(),
                    weights.len()
                ));
            }
            for (v, (js, ws)) in joints.iter().zip(&weights).enumerate() {
                for (&j, &w) in js.iter().zip(ws) {
                    if !(w.is_finite() && w >= 0.0) {
                        return Err(format!("vertex {v} has the joint weight {w}"));
                    }
                    if w == 0.0 {
                        continue;
                    }
                    let matrix = skinning.matrices.get(j as usize).ok_or_else(|| {
                        format!(
                            "vertex {v} names joint {j} of a skin with {}",
                            skinning.matrices.len()
                        )
                    })?;
                    sums[v] += matrix * f64::from(w);
                    weight_sums[v] += f64::from(w);
                }
            }
        }
        if sets == 0 {
            return Err("is skinned but has no JOINTS_0 and WEIGHTS_0".into());
        }
        if let Some(v) = weight_sums.iter().position(|&w| w <= 0.0) {
            return Err(format!(
                "vertex {v} of a skinned mesh has no joint weight (viewers draw it at the origin)"
            ));
        }
        let matrices = sums.into_iter().zip(weight_sums).map(|(m, w)| m / w);
        Ok(Some((skinning, matrices.collect())))
    }
}

/// The nodes of `scene`, depth first in document order, each with its transform in the file's
/// coordinates. Walked with a stack of its own, not recursion, and each node taken once: a
/// hierarchy with a cycle (which glTF forbids, and a damaged file can have) is refused instead
/// of overflowing the stack.
fn nodes_in_scene<'a>(
    scene: &gltf::Scene<'a>,
    node_count: usize,
) -> std::result::Result<Vec<SceneNode<'a>>, String> {
    let mut seen = vec![false; node_count];
    let mut nodes = Vec::new();
    let mut stack: Vec<(gltf::Node, Matrix4<f64>, Option<usize>)> = scene
        .nodes()
        .map(|root| (root, Matrix4::identity(), None))
        .collect();
    stack.reverse();
    while let Some((node, file_from_parent, parent)) = stack.pop() {
        if std::mem::replace(&mut seen[node.index()], true) {
            return Err(format!(
                "node {} is reached twice: its node hierarchy has a cycle or a node with two \
                 parents, which glTF does not allow",
                node.index()
            ));
        }
        let local = Matrix4::from(node.transform().matrix()).cast::<f64>();
        let file_from_node = file_from_parent * local;
        let first_child = stack.len();
        let index = node.index();
        stack.extend(
            node.children()
                .map(|child| (child, file_from_node, Some(index))),
        );
        stack[first_child..].reverse();
        nodes.push(SceneNode {
            node,
            file_from_node,
            parent,
        });
    }
    Ok(nodes)
}

/// Where a skin's bind pose (the mesh as stored) lies in the file: glTF leaves it to the
/// exporter whether the inverse bind matrices undo the node above the skeleton's root joint (an
/// armature turned to Z up, or scaled to centimetres) or only the joints below it. Of the two,
/// the one that puts the joints' bind places (`placed`: each joint's transform in the file and
/// its bind matrix) nearest where the file places them now: a pose turns limbs about their
/// joints, not the whole skeleton through a right angle or a hundredfold.
fn file_from_bind(
    joints: &[gltf::Node],
    nodes: &PlacedNodes,
    placed: &[(Matrix4<f64>, Matrix4<f64>)],
) -> Matrix4<f64> {
    let is_joint = |i: usize| joints.iter().any(|j| j.index() == i);
    // The root joint: the first whose parent is no joint (or which has none).
    let above_root = joints
        .iter()
        .find(|j| !nodes.parent[j.index()].is_some_and(is_joint))
        .and_then(|j| nodes.parent[j.index()])
        .and_then(|p| nodes.file_from_node[p]);
    let Some(above_root) = above_root else {
        return Matrix4::identity();
    };
    let origin = Point3::origin();
    let apart = |file_from_bind: &Matrix4<f64>| -> f64 {
        (placed.iter())
            .map(|(now, bind)| {
                let then = (file_from_bind * bind).transform_point(&origin);
                (now.transform_point(&origin) - then).norm()
            })
            .sum()
    };
    if apart(&above_root) < apart(&Matrix4::identity()) {
        above_root
    } else {
        Matrix4::identity()
    }
}

/// Refuses an accessor whose buffer view's stride is shorter than one of its elements: gltf's
/// reader asserts it is not (a panic), and the validator lets strides down to 4 bytes through.
fn check_stride(a: &gltf::Accessor, what: &str) -> std::result::Result<(), String> {
    let stride = a.view().and_then(|v| v.stride());
    if stride.is_some_and(|s| s < a.size()) {
        return Err(format!(
            "{what} (accessor {}): its elements are {} bytes apart but {} bytes long",
            a.index(),
            stride.unwrap_or(a.size()),
            a.size()
        ));
    }
    Ok(())
}

/// A node of the scene, with its transform in the file's coordinates and its parent's index.
struct SceneNode<'a> {
    node: gltf::Node<'a>,
    file_from_node: Matrix4<f64>,
    parent: Option<usize>,
}

/// Refuses joint indices that are not unsigned 8- or 16-bit VEC4 and weights that are not
/// float or normalized unsigned VEC4, as glTF requires: the reader panics on other types.
fn check_skin_accessor_types(prim: &gltf::Primitive, set: u32) -> std::result::Result<(), String> {
    use gltf::accessor::{DataType, Dimensions};
    if let Some(a) = prim.get(&gltf::Semantic::Joints(set)) {
        if !matches!(a.data_type(), DataType::U8 | DataType::U16)
            || a.dimensions() != Dimensions::Vec4
        {
            return Err(format!(
                "its JOINTS_{set} (accessor {}) is {:?} {:?}, not unsigned byte or short VEC4",
                a.index(),
                a.data_type(),
                a.dimensions()
            ));
        }
        check_stride(&a, &format!("its JOINTS_{set}"))?;
    }
    if let Some(a) = prim.get(&gltf::Semantic::Weights(set)) {
        let allowed = match a.data_type() {
            DataType::F32 => true,
            DataType::U8 | DataType::U16 => a.normalized(),
            _ => false,
        };
        if !allowed || a.dimensions() != Dimensions::Vec4 {
            return Err(format!(
                "its WEIGHTS_{set} (accessor {}) is {:?} {:?}, not float or normalized VEC4",
                a.index(),
                a.data_type(),
                a.dimensions()
            ));
        }
        check_stride(&a, &format!("its WEIGHTS_{set}"))?;
    }
    Ok(())
}

impl MeshCollector {
    /// Every node of `scene`, depth first in document order, with its mesh's triangles in the
    /// file's coordinates: a plain mesh placed by its node's transform, a skinned one posed by
    /// its joints ([`Skinning`]), as viewers show it.
    fn scene(
        &mut self,
        scene: &gltf::Scene,
        node_count: usize,
        buffers: &[gltf::buffer::Data],
    ) -> std::result::Result<(), String> {
        let nodes = nodes_in_scene(scene, node_count)?;
        let mut placed_nodes = PlacedNodes {
            file_from_node: vec![None; node_count],
            parent: vec![None; node_count],
        };
        for n in &nodes {
            placed_nodes.file_from_node[n.node.index()] = Some(n.file_from_node);
            placed_nodes.parent[n.node.index()] = n.parent;
        }
        for SceneNode {
            node,
            file_from_node,
            ..
        } in &nodes
        {
            let Some(mesh) = node.mesh() else { continue };
            self.skinned |= node.skin().is_some();
            let placed = match node.skin() {
                None => Placed::Rigid(*file_from_node),
                Some(skin) => Placed::Skinned(
                    self.skinning(&skin, &placed_nodes, buffers)
                        .map_err(|e| format!("skin {}: {e}", skin.index()))?,
                ),
            };
            for prim in mesh.primitives() {
                self.primitive(&prim, &placed, buffers).map_err(|e| {
                    format!("mesh {} primitive {}: {e}", mesh.index(), prim.index())
                })?;
            }
        }
        Ok(())
    }

    /// Each joint's skinning matrix (its node's transform in the file times its inverse bind
    /// matrix), and the joints' names and places kept for [`super::rig`].
    fn skinning(
        &mut self,
        skin: &gltf::Skin,
        nodes: &PlacedNodes,
        buffers: &[gltf::buffer::Data],
    ) -> std::result::Result<Skinning, String> {
        let joints: Vec<gltf::Node> = skin.joints().collect();
        let file_from_nodes = &nodes.file_from_node;
        let inverse_binds: Vec<Matrix4<f64>> = match skin.inverse_bind_matrices() {
            None => vec![Matrix4::identity(); joints.len()],
            Some(a) => {
                use gltf::accessor::{DataType, Dimensions};
                if (a.data_type(), a.dimensions()) != (DataType::F32, Dimensions::Mat4) {
                    return Err(format!(
                        "its inverse bind matrices (accessor {}) are {:?} {:?}, not float MAT4",
                        a.index(),
                        a.data_type(),
                        a.dimensions()
                    ));
                }
                check_stride(&a, "its inverse bind matrices")?;
                if a.count() < joints.len() {
                    return Err(format!(
                        "it has {} joints but {} inverse bind matrices",
                        joints.len(),
                        a.count()
                    ));
                }
                let reader = skin.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
                reader
                    .read_inverse_bind_matrices()
                    .ok_or("its inverse bind matrices cannot be read")?
                    .map(|m| Matrix4::from(m).cast::<f64>())
                    .collect()
            }
        };
        if inverse_binds.len() < joints.len() {
            return Err(format!(
                "it has {} joints but {} inverse bind matrices",
                joints.len(),
                inverse_binds.len()
            ));
        }
        let mut matrices = Vec::with_capacity(joints.len());
        let mut placed = Vec::with_capacity(joints.len());
        for (joint, inverse_bind) in joints.iter().zip(&inverse_binds) {
            let file_from_joint = file_from_nodes[joint.index()]
                .ok_or_else(|| format!("its joint node {} is not in the scene", joint.index()))?;
            let matrix = file_from_joint * inverse_bind;
            let bind = inverse_bind.try_inverse();
            if !matrix.iter().all(|v| v.is_finite()) || bind.is_none() {
                return Err(format!(
                    "joint node {} has a non-finite transform or an inverse bind matrix that \
                     cannot be undone",
                    joint.index()
                ));
            }
            matrices.push(matrix);
            placed.push((file_from_joint, bind.unwrap_or_else(Matrix4::identity)));
        }
        let file_from_bind = file_from_bind(&joints, nodes, &placed);
        let bind_from_file = file_from_bind
            .try_inverse()
            .ok_or("the node above its skeleton has a transform that cannot be undone")?;
        for (joint, (file_from_joint, bind)) in joints.iter().zip(&placed) {
            let name = joint
                .name()
                .map_or_else(|| format!("node {}", joint.index()), str::to_string);
            let origin = Point3::origin();
            let posed = file_from_joint.transform_point(&origin);
            let rest = (file_from_bind * bind).transform_point(&origin);
            self.joints
                .entry(joint.index())
                .or_insert(Joint { name, posed, rest });
        }
        Ok(Skinning {
            matrices,
            file_from_bind,
            bind_from_file,
        })
    }

    fn primitive(
        &mut self,
        prim: &gltf::Primitive,
        placed: &Placed,
        buffers: &[gltf::buffer::Data],
    ) -> std::result::Result<(), String> {
        use gltf::mesh::Mode;
        let mode = prim.mode();
        if !matches!(
            mode,
            Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
        ) {
            self.other_primitives += 1;
            return Ok(());
        }
        check_accessor_types(prim)?;
        let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
        let positions: Vec<[f32; 3]> = reader
            .read_positions()
            .ok_or("has no POSITION attribute")?
            .collect();
        // Triangles index the leg's vertices as u32: the whole leg must have fewer (the memory
        // check refuses such a file first, unless `allow_large`).
        if self.positions.len() + positions.len() > u32::MAX as usize {
            return Err("has more vertices than 32-bit indices can reach".into());
        }
        let n = positions.len() as u32;
        let indices: Vec<u32> = match reader.read_indices() {
            Some(i) => i.into_u32().collect(),
            None => (0..n).collect(),
        };
        if let Some(bad) = indices.iter().find(|&&i| i >= n) {
            return Err(format!("index {bad} is past its {n} vertices"));
        }
        let skinned = placed.vertex_transforms(prim, &reader, positions.len())?;
        // A mirroring transform (negative determinant) flips the winding; undo it. A skinned
        // vertex's is its joints' blend, which `orient_outward` rewinds where it mirrors.
        let rigid = match placed {
            Placed::Rigid(m) => *m,
            Placed::Skinned(_) => Matrix4::identity(),
        };
        let flip = skinned.is_none() && rigid.fixed_view::<3, 3>(0, 0).determinant() < 0.0;
        // The rest pose is kept only once a skin is met: the vertices before it are at rest.
        if skinned.is_some() && self.rest.len() < self.positions.len() {
            self.rest.clone_from(&self.positions);
            self.pose_from_rest = vec![Matrix4::identity(); self.positions.len()];
        }
        let keep_rest = !self.rest.is_empty();
        // Fits: checked with `n` above.
        let first = self.positions.len() as u32;
        for (k, p) in positions.iter().enumerate() {
            if !p.iter().all(|c| c.is_finite()) {
                return Err(format!("has a non-finite vertex coordinate {p:?}"));
            }
            let p = Point3::new(p[0] as f64, p[1] as f64, p[2] as f64);
            let (q, rest, pose_from_rest) = match &skinned {
                Some((skinning, m)) => (
                    m[k].transform_point(&p),
                    skinning.file_from_bind.transform_point(&p),
                    m[k] * skinning.bind_from_file,
                ),
                None => {
                    let q = rigid.transform_point(&p);
                    (q, q, Matrix4::identity())
                }
            };
            if !q.iter().chain(rest.iter()).all(|c| c.is_finite()) {
                return Err("its node transform or skin gives non-finite coordinates".into());
            }
            self.positions.push(q);
            if keep_rest {
                self.rest.push(rest);
                self.pose_from_rest.push(pose_from_rest);
            }
        }
        let before = self.triangles.len();
        let mut push = |a: u32, b: u32, c: u32| {
            let t = if flip { [a, c, b] } else { [a, b, c] };
            self.triangles.push(t.map(|i| first + i));
        };
        match mode {
            Mode::Triangles => {
                for t in indices.chunks_exact(3) {
                    push(t[0], t[1], t[2]);
                }
            }
            // Every index is below `n`, checked above, and `first + n` fits in u32.
            Mode::TriangleStrip => {
                for (k, t) in indices.windows(3).enumerate() {
                    if k % 2 == 0 {
                        push(t[0], t[1], t[2]);
                    } else {
                        push(t[1], t[0], t[2]);
                    }
                }
            }
            _ => {
                for k in 1..indices.len().saturating_sub(1) {
                    push(indices[0], indices[k], indices[k + 1]);
                }
            }
        }
        if let Some(material) = prim.material().index() {
            *self.triangles_by_material.entry(material).or_default() +=
                self.triangles.len() - before;
        }
        Ok(())
    }

    /// The material of most triangles (the lowest index on a tie), where it has no base-colour
    /// texture: its factors alone would draw a textured skin white. Factors clamped to 0–1; a
    /// non-finite one (a damaged file) carries nothing over.
    fn carried_material(&self, document: &gltf::Document) -> Option<Material> {
        let (&index, _) = self
            .triangles_by_material
            .iter()
            .max_by(|a, b| a.1.cmp(b.1).then(b.0.cmp(a.0)))?;
        let material = document.materials().nth(index)?;
        let pbr = material.pbr_metallic_roughness();
        if pbr.base_color_texture().is_some() {
            return None;
        }
        let [r, g, b, _] = pbr.base_color_factor();
        let factors = [r, g, b, pbr.metallic_factor(), pbr.roughness_factor()];
        if !factors.iter().all(|v| v.is_finite()) {
            return None;
        }
        let unit = |v: f32| f64::from(v).clamp(0.0, 1.0);
        Some(Material {
            name: material
                .name()
                .map_or_else(|| format!("material {index}"), str::to_string),
            base_colour: [r, g, b].map(unit),
            metallic: unit(pbr.metallic_factor()),
            roughness: unit(pbr.roughness_factor()),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A closed prism of 16 sides along +Z from z = 0 to 0.8 m, its radius going from
    /// `bottom` to `top`.
    fn prism_along_z(bottom: f64, top: f64) -> (Vec<Point3<f64>>, Vec<[u32; 3]>) {
        const SIDES: u32 = 16;
        const RINGS: u32 = 9;
        let mut positions = Vec::new();
        for ring in 0..RINGS {
            let t = f64::from(ring) / f64::from(RINGS - 1);
            let r = bottom + (top - bottom) * t;
            for k in 0..SIDES {
                let a = std::f64::consts::TAU * f64::from(k) / f64::from(SIDES);
                positions.push(Point3::new(r * a.cos(), r * a.sin(), 0.8 * t));
            }
        }
        let mut triangles = Vec::new();
        for ring in 0..RINGS - 1 {
            for k in 0..SIDES {
                let (a, b) = (ring * SIDES + k, ring * SIDES + (k + 1) % SIDES);
                triangles.push([a, b, b + SIDES]);
                triangles.push([a, b + SIDES, a + SIDES]);
            }
        }
        let (low, high) = (positions.len() as u32, positions.len() as u32 + 1);
        positions.push(Point3::new(0.0, 0.0, 0.0));
        positions.push(Point3::new(0.0, 0.0, 0.8));
        let last = (RINGS - 1) * SIDES;
        for k in 0..SIDES {
            triangles.push([low, (k + 1) % SIDES, k]);
            triangles.push([high, last + k, last + (k + 1) % SIDES]);
        }
        (positions, triangles)
    }

    #[test]
    fn up_is_the_anatomys_where_the_ends_differ_and_gltfs_plus_y_where_they_do_not() {
        let read = |(positions, triangles): (Vec<Point3<f64>>, Vec<[u32; 3]>), choice| {
            leg_in_world(
                "leg.glb".into(),
                &positions,
                &triangles,
                Units::Metres,
                choice,
            )
            .unwrap()
        };
        // A limb along +Z, slim at its foot: +Z is up, as its shape says.
        let limb = read(prism_along_z(0.03, 0.08), UpChoice::Auto);
        assert_eq!(
            (limb.up_axis, limb.up_from),
            (UpAxis::PosZ, UpFrom::Anatomy)
        );
        // As wide at both ends (1.1 times): the shape does not say, so glTF's +Y stands.
        let even = read(prism_along_z(0.05, 0.055), UpChoice::Auto);
        assert_eq!(
            (even.up_axis, even.up_from),
            (UpAxis::PosY, UpFrom::Convention)
        );
        assert_eq!(even.up, Vector3::y());
        // Named, the axis is the file's, whatever the shape.
        let given = read(prism_along_z(0.05, 0.055), UpChoice::Axis(UpAxis::PosZ));
        assert_eq!(
            (given.up_axis, given.up_from),
            (UpAxis::PosZ, UpFrom::Given)
        );
    }
}
