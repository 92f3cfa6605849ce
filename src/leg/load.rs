//! Loading a leg from glTF 2.0 (`.glb`, or `.gltf` with external or embedded buffers) or PLY
//! (`.ply`, read by [`super::ply`]), the format chosen by the file's extension.
//!
//! From glTF, every triangle primitive under the default scene's nodes is taken, with node
//! transforms applied; from PLY, every face, triangulated in its own plane. Either way the mesh
//! is then handled here, in one place: scaled to metres, cleaned ([`super::clean`]: repeated
//! vertices and faces, slivers, debris), and turned so that the file's up axis is +Y (glTF's
//! own convention, so a well-formed glTF file needs no turning; PLY has none). With
//! `up_axis: auto` the up axis is the file axis nearest the body's own up ([`anatomical_up`]).
//! The mesh is checked: it must have triangles, finite coordinates, no compressed geometry, and
//! a plausible height.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use nalgebra::{Matrix4, Point3, Vector3};

use super::clean::{clean_mesh, Cleaned};
use super::landmarks::anatomical_up;
use super::orient::orient_outward;
use super::ply::{self, PlyHeader};
use crate::base::Material;
use crate::error::{Error, Result};
use crate::leg::{Units, UpAxis, UpChoice};

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
    /// True when `up_axis` was found from the anatomy (`leg.up_axis: auto`).
    pub up_axis_found: bool,
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
            up_axis_found: false,
            up: Vector3::y(),
            cleaned,
            material: None,
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
/// up axis, cleans and checks them.
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
            }
        }
    };
    let fail = |message: String| Error::Leg {
        path: path.clone(),
        message,
    };
    let scaled: Vec<Point3<f64>> = mesh
        .positions_file
        .iter()
        .map(|p| Point3::from(p.coords * units.metres()))
        .collect();
    check_coordinates(&scaled, &mesh.triangles, units).map_err(fail)?;
    let (scaled, mut triangles, cleaned) = clean_mesh(&scaled, &mesh.triangles);
    if triangles.is_empty() {
        return Err(fail("has no triangles with area".into()));
    }
    let (up_axis, up) = match choice {
        UpChoice::Axis(axis) => (axis, Vector3::y()),
        UpChoice::Auto => {
            let body_up = anatomical_up(&scaled, &triangles).ok_or_else(|| {
                fail(
                    "cannot tell which way is up: no cross-section of the mesh is closed; set \
                     leg.up_axis (or --up-axis)"
                        .into(),
                )
            })?;
            let axis = nearest_axis(&body_up);
            (axis, turn(axis, &Point3::from(body_up)).coords)
        }
    };
    let positions: Vec<Point3<f64>> = scaled.iter().map(|p| turn(up_axis, p)).collect();
    let reoriented_triangles = orient_outward(&positions, &mut triangles);
    let leg = Leg {
        path,
        positions,
        triangles,
        reoriented_triangles,
        units,
        up_axis,
        up_axis_found: choice == UpChoice::Auto,
        up,
        cleaned,
        material: mesh.material,
    };
    check_height(&leg)?;
    Ok(leg)
}

/// A leg file's triangles as the file gives them, before the conversion to world space.
struct FileMesh {
    /// Vertex positions, file coordinates and units.
    positions_file: Vec<Point3<f64>>,
    /// Triangles as indices into `positions_file`, wound as in the file.
    triangles: Vec<[u32; 3]>,
    /// See [`Leg::material`].
    material: Option<Material>,
}

/// The triangles under `gltf`'s default scene, node transforms applied.
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
        .find(|(_, p)| p.iter().any(|c| c.abs() > MAX_COORDINATE_M));
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
        format!(
            "check leg.up_axis or --up-axis (now \"{}\")",
            leg.up_axis.name()
        )
    } else {
        format!(
            "it is probably in other units: set leg.units or --units to \"{}\" (now \"{}\"), \
             or check leg.up_axis (now \"{}\")",
            fitting[0],
            leg.units.name(),
            leg.up_axis.name()
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

/// Gathers triangles from a node tree, in the file's coordinates.
#[derive(Default)]
struct MeshCollector {
    positions: Vec<Point3<f64>>,
    triangles: Vec<[u32; 3]>,
    other_primitives: usize,
    /// Triangles per glTF material index.
    triangles_by_material: BTreeMap<usize, usize>,
}

impl MeshCollector {
    /// Every node of `scene`, depth first in document order, with its mesh's triangles in the
    /// file's coordinates. Walked with a stack of its own, not recursion, and each node taken
    /// once: a hierarchy with a cycle (which glTF forbids, and a damaged file can have) is
    /// refused instead of overflowing the stack.
    fn scene(
        &mut self,
        scene: &gltf::Scene,
        node_count: usize,
        buffers: &[gltf::buffer::Data],
    ) -> std::result::Result<(), String> {
        let mut seen = vec![false; node_count];
        let mut stack: Vec<(gltf::Node, Matrix4<f64>)> = scene
            .nodes()
            .map(|root| (root, Matrix4::identity()))
            .collect();
        stack.reverse();
        while let Some((node, file_from_parent)) = stack.pop() {
            if std::mem::replace(&mut seen[node.index()], true) {
                return Err(format!(
                    "node {} is reached twice: its node hierarchy has a cycle or a node with two \
                     parents, which glTF does not allow",
                    node.index()
                ));
            }
            let local = Matrix4::from(node.transform().matrix()).cast::<f64>();
            let file_from_node = file_from_parent * local;
            if let Some(mesh) = node.mesh() {
                for prim in mesh.primitives() {
                    self.primitive(&prim, &file_from_node, buffers)
                        .map_err(|e| {
                            format!("mesh {} primitive {}: {e}", mesh.index(), prim.index())
                        })?;
                }
            }
            let first_child = stack.len();
            stack.extend(node.children().map(|child| (child, file_from_node)));
            stack[first_child..].reverse();
        }
        Ok(())
    }

    fn primitive(
        &mut self,
        prim: &gltf::Primitive,
        file_from_node: &Matrix4<f64>,
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
        // A mirroring transform (negative determinant) flips the winding; undo it.
        let flip = file_from_node.fixed_view::<3, 3>(0, 0).determinant() < 0.0;
        // Fits: checked with `n` above.
        let first = self.positions.len() as u32;
        for p in &positions {
            if !p.iter().all(|c| c.is_finite()) {
                return Err(format!("has a non-finite vertex coordinate {p:?}"));
            }
            let p = Point3::new(p[0] as f64, p[1] as f64, p[2] as f64);
            let q = file_from_node.transform_point(&p);
            if !q.iter().all(|c| c.is_finite()) {
                return Err("its node transform gives non-finite coordinates".into());
            }
            self.positions.push(q);
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
