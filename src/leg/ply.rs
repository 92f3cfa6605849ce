//! Reading a leg mesh from PLY: ASCII, or binary little- or big-endian, as knitfit's own
//! `leg.ply` and most scanning and mesh tools write it.
//!
//! What is read: the `vertex` element's `x`, `y`, `z` (float or double), in the file's
//! coordinates and units; and the `face` element's `vertex_indices` list (or `vertex_index`, as
//! some tools name it; any integer type), each polygon triangulated in its own plane: a convex
//! one as a fan from its first vertex, any other by ear clipping (a fan would cover the notch
//! of a concave quad and fold back over itself). Every other property and element (normals, colours, edges, materials) is read past.
//! What is checked, as for glTF geometry: every coordinate finite, every index naming a vertex,
//! at least one triangle. A refusal is [`Error::Leg`] in one line.
//!
//! Why two steps: [`read_header`] reads and checks the header alone, so that a fit can weigh the
//! leg's memory from the declared face count before any payload is decoded, as it does with a
//! glTF file's accessor counts ([`crate::limits`]); [`decode`] then reads the payload. Units and
//! up axis are not this file's business: PLY has no convention for either, and
//! [`decode_leg`](super::load::decode_leg) converts the positions of both formats in one place.
//!
//! A header is checked before its payload is read so that a damaged file cannot make the reader
//! loop or allocate beyond the file's size: an element with items but no properties would be
//! read forever without consuming a byte, and a binary file shorter than its header's counts
//! demand is refused as truncated at once.

use std::io::ErrorKind;
use std::path::Path;

use nalgebra::Point3;
use ply_rs_bw::parser::{ParseError, Parser, Reader};
use ply_rs_bw::ply::{
    ElementDef, Encoding, Header, PropertyAccess, PropertyAccessResult, PropertyType, ScalarType,
};

use crate::error::{Error, Result};

/// The names the `face` element's index list goes by.
const INDEX_LISTS: [&str; 2] = ["vertex_indices", "vertex_index"];

/// Longest message taken from the PLY parser, in characters: its messages quote the line they
/// failed on, which in a damaged file can be any length.
const MAX_PARSER_MESSAGE: usize = 200;

/// What a PLY leg file's checked header declares.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PlyHeader {
    /// Vertices declared.
    pub vertices: usize,
    /// Faces declared; each gives one triangle, or more when it is a polygon.
    pub faces: usize,
}

/// A PLY leg's mesh, in the file's coordinates and units.
#[derive(Clone, Debug)]
pub struct PlyMesh {
    /// Vertex positions, file coordinates.
    pub positions: Vec<Point3<f64>>,
    /// Triangles as indices into `positions`, wound as the file's faces are.
    pub triangles: Vec<[u32; 3]>,
}

/// Reads and checks the header of the PLY file `path` holding `bytes`: a `vertex` element with
/// float or double `x`, `y`, `z`, a `face` element with an integer index list, and (for binary
/// files) as many bytes after the header as its counts need at least.
pub fn read_header(path: &Path, bytes: &[u8]) -> Result<PlyHeader> {
    open(bytes)
        .map(|(_, _, declared)| declared)
        .map_err(|message| leg_error(path, message))
}

/// Reads the mesh of the PLY file `path` holding `bytes`, checking the header as
/// [`read_header`] does and the payload as the module doc says.
pub fn decode(path: &Path, bytes: &[u8]) -> Result<PlyMesh> {
    decode_bytes(bytes).map_err(|message| leg_error(path, message))
}

fn leg_error(path: &Path, message: String) -> Error {
    Error::Leg {
        path: path.to_path_buf(),
        message,
    }
}

/// The header read (the reader left at the payload) and checked.
fn open(bytes: &[u8]) -> std::result::Result<(Reader<&[u8]>, Header, PlyHeader), String> {
    if bytes.is_empty() {
        return Err("is empty, not a PLY file".into());
    }
    let mut reader = Reader::new(bytes);
    let header = Parser::<Skip>::new()
        .read_header(&mut reader)
        .map_err(|e| parser_message(&e))?;
    let declared = check_header(&header, reader.get_ref().len())?;
    Ok((reader, header, declared))
}

fn decode_bytes(bytes: &[u8]) -> std::result::Result<PlyMesh, String> {
    let (mut reader, header, _) = open(bytes)?;
    let mut vertices = Vec::new();
    let mut faces = Vec::new();
    for element in header.elements.values() {
        match element.name.as_str() {
            "vertex" => {
                vertices = Parser::<VertexRow>::new()
                    .read_payload_for_element(&mut reader, element, &header)
                    .map_err(|e| parser_message(&e))?;
            }
            "face" => {
                faces = Parser::<FaceRow>::new()
                    .read_payload_for_element(&mut reader, element, &header)
                    .map_err(|e| parser_message(&e))?;
            }
            _ => {
                Parser::<Skip>::new()
                    .read_payload_for_element(&mut reader, element, &header)
                    .map_err(|e| parser_message(&e))?;
            }
        }
    }
    let positions = vertices
        .iter()
        .enumerate()
        .map(|(i, VertexRow(p))| {
            if p.iter().all(|c| c.is_finite()) {
                Ok(Point3::from(*p))
            } else {
                Err(format!(
                    "vertex {i} has a non-finite coordinate ({}, {}, {})",
                    p[0], p[1], p[2]
                ))
            }
        })
        .collect::<std::result::Result<Vec<_>, _>>()?;
    let triangles = triangulate(&faces, &positions)?;
    Ok(PlyMesh {
        positions,
        triangles,
    })
}

/// Every face of three or more vertices as triangles: a convex polygon as a fan from its first
/// vertex, any other by ear clipping in its own plane ([`ear_clip`]); each index must name one
/// of the `positions`.
fn triangulate(
    faces: &[FaceRow],
    positions: &[Point3<f64>],
) -> std::result::Result<Vec<[u32; 3]>, String> {
    let vertices = positions.len();
    let mut triangles = Vec::with_capacity(faces.len());
    for (f, FaceRow(indices)) in faces.iter().enumerate() {
        // At most u32::MAX vertices, checked with the header, so an index in range fits.
        let index = |i: i64| match usize::try_from(i) {
            Ok(u) if u < vertices => Ok(u as u32),
            _ => Err(format!(
                "face {f} names vertex {i}, but the file has {vertices} vertices"
            )),
        };
        let indices = indices
            .iter()
            .map(|&i| index(i))
            .collect::<std::result::Result<Vec<u32>, _>>()?;
        let corners: Vec<Point3<f64>> = indices.iter().map(|&i| positions[i as usize]).collect();
        match ear_clip(&corners) {
            Some(ears) => triangles.extend(ears.iter().map(|t| t.map(|k| indices[k]))),
            None => {
                for k in 1..indices.len().saturating_sub(1) {
                    triangles.push([indices[0], indices[k], indices[k + 1]]);
                }
            }
        }
    }
    if triangles.is_empty() {
        return Err(if faces.is_empty() {
            "has no faces, so no triangles to fit onto".into()
        } else {
            "has no face of three or more vertices, so no triangles to fit onto".into()
        });
    }
    Ok(triangles)
}

/// The most corners a polygon is ear-clipped with: clipping costs up to the cube of the corners,
/// and a file must not be able to stall the reader with one face of a million (a larger
/// polygon is fanned; modellers' n-gons have tens).
pub const MAX_EAR_CLIPPED: usize = 256;

/// A polygon that is not convex as triangles of its corners (indices into `corners`), clipped
/// ear by ear in the polygon's own plane, as modellers triangulate (Eberly, "Triangulation by
/// Ear Clipping", 2002); the winding of each triangle is the polygon's. `None` where the fan
/// from the first corner is right: a triangle, a convex polygon (so files of convex faces read
/// as they always have), or one without a plane (no area); and past [`MAX_EAR_CLIPPED`].
fn ear_clip(corners: &[Point3<f64>]) -> Option<Vec<[usize; 3]>> {
    let n = corners.len();
    if !(4..=MAX_EAR_CLIPPED).contains(&n) {
        return None;
    }
    // Newell's normal: the polygon's plane even where some corners are off it.
    let mut normal = nalgebra::Vector3::zeros();
    for k in 0..n {
        let (a, b) = (corners[k], corners[(k + 1) % n]);
        normal += nalgebra::Vector3::new(
            (a.y - b.y) * (a.z + b.z),
            (a.z - b.z) * (a.x + b.x),
            (a.x - b.x) * (a.y + b.y),
        );
    }
    let normal = normal.try_normalize(0.0)?;
    let u = normal.cross(&if normal.x.abs() < 0.9 {
        nalgebra::Vector3::x()
    } else {
        nalgebra::Vector3::y()
    });
    let u = u.normalize();
    let v = normal.cross(&u);
    // Counter-clockwise about the normal in (u, v).
    let flat: Vec<[f64; 2]> = corners
        .iter()
        .map(|p| [p.coords.dot(&u), p.coords.dot(&v)])
        .collect();
    let turn = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    };
    if (0..n).all(|k| turn(flat[k], flat[(k + 1) % n], flat[(k + 2) % n]) >= 0.0) {
        return None;
    }
    // On an edge (to rounding) counts as inside: clipping there would leave a triangle of no
    // area behind.
    let size = corners
        .iter()
        .map(|p| (p - corners[0]).norm())
        .fold(0.0, f64::max);
    let on = -1e-12 * size * size;
    let inside = |p: [f64; 2], [a, b, c]: [[f64; 2]; 3]| {
        turn(a, b, p) >= on && turn(b, c, p) >= on && turn(c, a, p) >= on
    };
    let mut ring: Vec<usize> = (0..n).collect();
    let mut triangles = Vec::with_capacity(n - 2);
    while ring.len() > 3 {
        let m = ring.len();
        let ear = (0..m).find(|&k| {
            let [a, b, c] = [ring[(k + m - 1) % m], ring[k], ring[(k + 1) % m]];
            let corner = [flat[a], flat[b], flat[c]];
            turn(corner[0], corner[1], corner[2]) > 0.0
                && ring
                    .iter()
                    .filter(|&&o| o != a && o != b && o != c)
                    .all(|&o| !inside(flat[o], corner))
        });
        // A polygon that crosses itself may have no ear: its most convex corner goes next.
        let k = ear.unwrap_or_else(|| {
            (0..m)
                .max_by(|&i, &j| {
                    let area = |k: usize| {
                        turn(
                            flat[ring[(k + m - 1) % m]],
                            flat[ring[k]],
                            flat[ring[(k + 1) % m]],
                        )
                    };
                    area(i).total_cmp(&area(j))
                })
                .expect("a ring of more than three corners")
        });
        triangles.push([ring[(k + m - 1) % m], ring[k], ring[(k + 1) % m]]);
        ring.remove(k);
    }
    triangles.push([ring[0], ring[1], ring[2]]);
    Some(triangles)
}

/// Checks what [`decode`] relies on; `payload_bytes` is what follows the header.
fn check_header(header: &Header, payload_bytes: usize) -> std::result::Result<PlyHeader, String> {
    for element in header.elements.values() {
        if element.count > 0 && element.properties.is_empty() {
            return Err(format!(
                "its element {:?} declares {} items but no properties",
                element.name, element.count
            ));
        }
    }
    let vertex = header
        .elements
        .get("vertex")
        .ok_or("has no vertex element")?;
    for name in ["x", "y", "z"] {
        match vertex.properties.get(name).map(|p| &p.data_type) {
            Some(PropertyType::Scalar(ScalarType::Float | ScalarType::Double)) => {}
            Some(other) => {
                return Err(format!(
                    "its vertex property {name} is {}, not float or double",
                    type_name(other)
                ))
            }
            None => return Err(format!("its vertex element has no property {name}")),
        }
    }
    if u32::try_from(vertex.count).is_err() {
        return Err(format!(
            "declares {} vertices, more than the 2^32 knitfit can index",
            vertex.count
        ));
    }
    let face = header
        .elements
        .get("face")
        .ok_or("has no face element, so no triangles to fit onto")?;
    let list = INDEX_LISTS
        .iter()
        .find_map(|name| face.properties.get(*name))
        .ok_or("its face element has no vertex_indices (or vertex_index) list")?;
    match &list.data_type {
        PropertyType::List(count, item) if is_integer(count) && is_integer(item) => {}
        other => {
            return Err(format!(
                "its face property {} is {}, not a list of integers",
                list.name,
                type_name(other)
            ))
        }
    }
    if header.encoding != Encoding::Ascii {
        let needed = header
            .elements
            .values()
            .map(|e| e.count.saturating_mul(min_binary_size(e)))
            .fold(0usize, usize::saturating_add);
        if needed > payload_bytes {
            return Err(format!(
                "is truncated: its header declares at least {needed} bytes of data, and \
                 {payload_bytes} follow it"
            ));
        }
    }
    Ok(PlyHeader {
        vertices: vertex.count,
        faces: face.count,
    })
}

/// The fewest bytes one item of `element` takes in a binary file (a list at its shortest: the
/// count alone).
fn min_binary_size(element: &ElementDef) -> usize {
    element
        .properties
        .values()
        .map(|p| match &p.data_type {
            PropertyType::Scalar(t) | PropertyType::List(t, _) => scalar_size(t),
        })
        .sum()
}

fn scalar_size(t: &ScalarType) -> usize {
    match t {
        ScalarType::Char | ScalarType::UChar => 1,
        ScalarType::Short | ScalarType::UShort => 2,
        ScalarType::Int | ScalarType::UInt | ScalarType::Float => 4,
        ScalarType::Double => 8,
    }
}

fn is_integer(t: &ScalarType) -> bool {
    !matches!(t, ScalarType::Float | ScalarType::Double)
}

/// A property type as PLY headers spell it.
fn type_name(t: &PropertyType) -> String {
    let scalar = |t: &ScalarType| match t {
        ScalarType::Char => "char",
        ScalarType::UChar => "uchar",
        ScalarType::Short => "short",
        ScalarType::UShort => "ushort",
        ScalarType::Int => "int",
        ScalarType::UInt => "uint",
        ScalarType::Float => "float",
        ScalarType::Double => "double",
    };
    match t {
        PropertyType::Scalar(s) => scalar(s).into(),
        PropertyType::List(count, item) => format!("list {} {}", scalar(count), scalar(item)),
    }
}

/// The PLY parser's error in one line of bounded length: its messages span lines and quote the
/// line they failed on.
fn parser_message(e: &ParseError) -> String {
    let mut text = e
        .to_string()
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ");
    if let Some((cut, _)) = text.char_indices().nth(MAX_PARSER_MESSAGE) {
        text.truncate(cut);
        text.push('…');
    }
    match e.kind() {
        ErrorKind::UnexpectedEof => format!("is truncated: {text}"),
        _ => format!("not a readable PLY file: {text}"),
    }
}

/// A `vertex` item: its position; every other property is read past.
struct VertexRow([f64; 3]);

impl VertexRow {
    fn set(&mut self, name: &str, value: f64) -> PropertyAccessResult {
        let k = match name {
            "x" => 0,
            "y" => 1,
            "z" => 2,
            _ => return PropertyAccessResult::Ignored,
        };
        self.0[k] = value;
        PropertyAccessResult::Set
    }
}

impl PropertyAccess for VertexRow {
    fn new() -> Self {
        VertexRow([0.0; 3])
    }

    fn set_float(&mut self, name: &str, value: f32) -> PropertyAccessResult {
        self.set(name, f64::from(value))
    }

    fn set_double(&mut self, name: &str, value: f64) -> PropertyAccessResult {
        self.set(name, value)
    }
}

/// A `face` item: its vertex indices, widened to `i64` whatever their type (negative ones are
/// refused when the faces are fanned); every other property is read past.
struct FaceRow(Vec<i64>);

impl FaceRow {
    fn set<T: Into<i64>>(&mut self, name: &str, values: Vec<T>) -> PropertyAccessResult {
        if !INDEX_LISTS.contains(&name) {
            return PropertyAccessResult::Ignored;
        }
        self.0 = values.into_iter().map(Into::into).collect();
        PropertyAccessResult::Set
    }
}

impl PropertyAccess for FaceRow {
    fn new() -> Self {
        FaceRow(Vec::new())
    }

    fn set_list_char(&mut self, name: &str, values: Vec<i8>) -> PropertyAccessResult {
        self.set(name, values)
    }

    fn set_list_uchar(&mut self, name: &str, values: Vec<u8>) -> PropertyAccessResult {
        self.set(name, values)
    }

    fn set_list_short(&mut self, name: &str, values: Vec<i16>) -> PropertyAccessResult {
        self.set(name, values)
    }

    fn set_list_ushort(&mut self, name: &str, values: Vec<u16>) -> PropertyAccessResult {
        self.set(name, values)
    }

    fn set_list_int(&mut self, name: &str, values: Vec<i32>) -> PropertyAccessResult {
        self.set(name, values)
    }

    fn set_list_uint(&mut self, name: &str, values: Vec<u32>) -> PropertyAccessResult {
        self.set(name, values)
    }
}

/// An item of an element the leg does not use: read, then dropped.
struct Skip;

impl PropertyAccess for Skip {
    fn new() -> Self {
        Skip
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn path() -> &'static Path {
        Path::new("leg.ply")
    }

    /// A unit square in the z = 0 plane as one quad, its indices of type `face_type`.
    fn ascii_quad(face_type: &str) -> String {
        format!(
            "ply\nformat ascii 1.0\ncomment a quad\nelement vertex 4\nproperty float x\n\
             property float y\nproperty double z\nproperty uchar red\nelement face 1\n\
             property list uchar {face_type} vertex_index\nend_header\n\
             0 0 0 255\n1 0 0 255\n1 1 0 255\n0 1 0 255\n4 0 1 2 3\n"
        )
    }

    /// A triangle and a quad as binary PLY: doubles for positions, a `short`-counted `uint`
    /// index list, an `edge` element between them that must be read past.
    fn binary(encoding: &str, big: bool) -> Vec<u8> {
        let mut bytes = format!(
            "ply\nformat {encoding} 1.0\nelement vertex 5\nproperty double x\nproperty double y\n\
             property double z\nelement edge 1\nproperty int vertex1\nproperty int vertex2\n\
             element face 2\nproperty list short uint vertex_indices\nproperty float quality\n\
             end_header\n"
        )
        .into_bytes();
        let mut put = |b: &[u8]| {
            let mut b = b.to_vec();
            if big {
                b.reverse();
            }
            bytes.extend(b);
        };
        let points = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ];
        for p in points.iter().chain(&[[0.5, 2.0, -1.0]]) {
            for c in p {
                put(&f64::to_le_bytes(*c));
            }
        }
        put(&0i32.to_le_bytes());
        put(&1i32.to_le_bytes());
        put(&3i16.to_le_bytes());
        for i in [2u32, 3, 4] {
            put(&i.to_le_bytes());
        }
        put(&1.0f32.to_le_bytes());
        put(&4i16.to_le_bytes());
        for i in [0u32, 1, 2, 3] {
            put(&i.to_le_bytes());
        }
        put(&0.5f32.to_le_bytes());
        bytes
    }

    /// Where the payload of `bytes` begins.
    fn payload_start(bytes: &[u8]) -> usize {
        let marker = b"end_header\n";
        marker.len()
            + bytes
                .windows(marker.len())
                .position(|w| w == marker)
                .unwrap()
    }

    fn refusal(bytes: &[u8]) -> String {
        let err = decode(path(), bytes).unwrap_err();
        assert!(matches!(err, Error::Leg { .. }), "{err:?}");
        let text = err.to_string();
        assert_eq!(text.lines().count(), 1, "one line: {text}");
        assert!(text.starts_with("leg.ply: "), "{text}");
        text
    }

    #[test]
    fn a_concave_polygon_is_cut_into_ears_that_cover_it_once() {
        // An arrowhead quad from a wing: the fan from corner 0 would fill the notch and fold
        // back over the arrow. And an L-shaped hexagon; both tilted out of every axis plane.
        let arrow = [(-1.0, -1.0), (0.0, -0.4), (1.0, -1.0), (0.0, 1.0)];
        let l_shape = [(0., 0.), (2., 0.), (2., 1.), (1., 1.), (1., 2.), (0., 2.)];
        let tilt = nalgebra::Rotation3::from_euler_angles(0.3, 0.5, 0.7);
        for outline in [&arrow[..], &l_shape[..]] {
            let corners: Vec<Point3<f64>> = outline
                .iter()
                .map(|&(x, y)| tilt * Point3::new(x, y, 0.0))
                .collect();
            let triangles = ear_clip(&corners).expect("not convex");
            assert_eq!(triangles.len(), outline.len() - 2);
            // Same winding as the polygon, and areas that add up to the polygon's (shoelace).
            let normal = tilt * nalgebra::Vector3::z();
            let area: f64 = triangles
                .iter()
                .map(|[a, b, c]| {
                    let (a, b, c) = (corners[*a], corners[*b], corners[*c]);
                    let signed = (b - a).cross(&(c - a)).dot(&normal) / 2.0;
                    assert!(signed > 0.0, "{outline:?}: a triangle wound the other way");
                    signed
                })
                .sum();
            let shoelace: f64 = (0..outline.len())
                .map(|k| {
                    let ((x0, y0), (x1, y1)) = (outline[k], outline[(k + 1) % outline.len()]);
                    x0 * y1 - x1 * y0
                })
                .sum::<f64>()
                / 2.0;
            assert!(
                (area - shoelace).abs() < 1e-12,
                "{outline:?}: {area} vs {shoelace}"
            );
        }
        // A convex quad is left to the fan, as files of convex faces always read.
        let square = [(0., 0.), (1., 0.), (1., 1.), (0., 1.)].map(|(x, y)| Point3::new(x, y, 0.0));
        assert_eq!(ear_clip(&square), None);
    }

    #[test]
    fn an_ascii_quad_is_fanned_into_two_triangles() {
        for face_type in ["uchar", "int", "uint", "char", "short", "ushort"] {
            let mesh = decode(path(), ascii_quad(face_type).as_bytes()).unwrap();
            assert_eq!(mesh.positions.len(), 4);
            assert_eq!(mesh.positions[2], Point3::new(1.0, 1.0, 0.0));
            assert_eq!(mesh.triangles, [[0, 1, 2], [0, 2, 3]], "{face_type}");
        }
    }

    #[test]
    fn binary_little_and_big_endian_read_the_same_mesh() {
        for (encoding, big) in [("binary_little_endian", false), ("binary_big_endian", true)] {
            let bytes = binary(encoding, big);
            assert_eq!(
                read_header(path(), &bytes).unwrap(),
                PlyHeader {
                    vertices: 5,
                    faces: 2
                }
            );
            let mesh = decode(path(), &bytes).unwrap();
            assert_eq!(mesh.positions[4], Point3::new(0.5, 2.0, -1.0), "{encoding}");
            assert_eq!(
                mesh.triangles,
                [[2, 3, 4], [0, 1, 2], [0, 2, 3]],
                "{encoding}"
            );
        }
    }

    #[test]
    fn a_truncated_binary_file_is_refused_at_every_length() {
        let bytes = binary("binary_little_endian", false);
        let payload = payload_start(&bytes);
        for len in 0..bytes.len() {
            let text = refusal(&bytes[..len]);
            if len >= payload {
                assert!(text.contains("is truncated"), "{len}: {text}");
            }
        }
    }

    #[test]
    fn a_truncated_ascii_file_is_refused() {
        let text = ascii_quad("int");
        let cut = text.find("1 1 0").unwrap();
        let message = refusal(&text.as_bytes()[..cut]);
        assert!(message.contains("is truncated"), "{message}");
    }

    #[test]
    fn a_bad_header_is_refused_with_what_is_wrong() {
        let quad = ascii_quad("int");
        let cases = [
            (quad.replace("ply\n", "plyx\n"), "not a readable PLY file"),
            (
                quad.replace("format ascii 1.0\n", ""),
                "not a readable PLY file",
            ),
            (quad.replace("end_header\n", ""), "not a readable PLY file"),
            (
                quad.replace("property float x", "property int x"),
                "vertex property x is int",
            ),
            (quad.replace("property float y\n", ""), "no property y"),
            (quad.replace("vertex_index", "corners"), "no vertex_indices"),
            (
                quad.replace("list uchar int", "list uchar float"),
                "not a list of integers",
            ),
            (
                quad.replace("element face 1", "element face 0"),
                "has no faces",
            ),
            (
                quad.replace("element vertex 4", "element points 4"),
                "has no vertex element",
            ),
        ];
        for (text, expect) in cases {
            let message = refusal(text.as_bytes());
            assert!(message.contains(expect), "{expect:?}: {message}");
        }
        assert!(refusal(b"").contains("is empty"));
    }

    #[test]
    fn an_element_without_properties_is_refused_not_read_forever() {
        let text = "ply\nformat binary_little_endian 1.0\nelement nothing 18446744073709551615\n\
                    element vertex 0\nproperty float x\nproperty float y\nproperty float z\n\
                    element face 0\nproperty list uchar int vertex_indices\nend_header\n";
        let message = refusal(text.as_bytes());
        assert!(message.contains("no properties"), "{message}");
    }

    #[test]
    fn an_index_out_of_range_is_refused() {
        let text = ascii_quad("int").replace("4 0 1 2 3", "4 0 1 2 4");
        let message = refusal(text.as_bytes());
        assert!(
            message.contains("face 0 names vertex 4, but the file has 4 vertices"),
            "{message}"
        );
        let text = ascii_quad("int").replace("4 0 1 2 3", "3 0 -1 2");
        assert!(refusal(text.as_bytes()).contains("names vertex -1"));
    }

    #[test]
    fn a_non_finite_coordinate_is_refused() {
        let mut bytes = binary("binary_little_endian", false);
        let at = payload_start(&bytes) + 8;
        bytes[at..at + 8].copy_from_slice(&f64::NAN.to_le_bytes());
        let message = refusal(&bytes);
        assert!(
            message.contains("vertex 0 has a non-finite coordinate (0, NaN, 0)"),
            "{message}"
        );
        // ASCII has no NaN token; a value past float's range reads as an infinity.
        let text = ascii_quad("int").replace("1 1 0 255", "1 1e39 0 255");
        assert!(refusal(text.as_bytes()).contains("non-finite"));
    }

    #[test]
    fn faces_of_fewer_than_three_vertices_give_no_triangles() {
        let text = ascii_quad("int").replace("4 0 1 2 3", "2 0 1");
        let message = refusal(text.as_bytes());
        assert!(message.contains("no face of three or more"), "{message}");
    }

    #[test]
    fn a_parser_message_is_one_bounded_line() {
        let long = format!("{}\n", "x ".repeat(10_000));
        let text = ascii_quad("int").replace("0 1 0 255\n", &long);
        let message = refusal(text.as_bytes());
        assert!(message.chars().count() < 300, "{message}");
    }
}
