//! PLY writer (binary little-endian): the yarn points as a `vertex` element with every point
//! attribute, and the yarn segments as an `edge` element, which Blender imports as loose edges.

use ply_rs_bw::ply::{
    Addable, DefaultElement, ElementDef, Encoding, Ply, Property, PropertyDef, PropertyType,
    ScalarType,
};
use ply_rs_bw::writer::Writer;

use super::{SurfaceMesh, YarnGeometry};
use crate::error::{Error, Result};
use crate::knit::Direction;

/// Vertex properties [`write_ply`] writes itself, so no point attribute may take their names.
const YARN_VERTEX_PROPERTIES: [&str; 4] = ["x", "y", "z", "part"];

/// Vertex properties [`write_mesh_ply`] writes itself.
const MESH_VERTEX_PROPERTIES: [&str; 9] = ["x", "y", "z", "nx", "ny", "nz", "red", "green", "blue"];

/// Encodes `parts` as one binary little-endian PLY file.
///
/// `vertex`: `x`, `y`, `z` (float, metres, each part's `offset_m` added, as PLY has no
/// transforms), every point attribute (float, in the map's order), `part` (uchar, index into
/// `parts`). `edge`: `vertex1`, `vertex2` (int, indices into all parts' vertices in order),
/// `yarn_kind` (uchar, [`YarnKind::index`](crate::knit::YarnKind::index)), `direction` (uchar,
/// 0 course, 1 wale). The header holds `comments`, then the unit/axis convention, then one line
/// per part giving its name and the offset added. The bytes depend only on the arguments.
///
/// Fails with [`Error::Encode`] if the parts carry different attribute names, if a part is
/// inconsistent (see [`check_yarn_geometry`]), if there are more than 256 parts or 2^31
/// vertices, or if a comment holds a line break.
pub fn write_ply(parts: &[YarnGeometry], comments: &[String]) -> Result<Vec<u8>> {
    let encode_error = |message: String| Error::Encode {
        what: "PLY".into(),
        message,
    };
    for part in parts {
        check_yarn_geometry(part).map_err(encode_error)?;
        refuse_clashing_names(
            "part",
            &part.name,
            &part.point_attributes,
            &YARN_VERTEX_PROPERTIES,
        )
        .map_err(encode_error)?;
    }
    let attribute_names: Vec<&String> = parts
        .first()
        .map(|p| p.point_attributes.keys().collect())
        .unwrap_or_default();
    if parts
        .iter()
        .any(|p| p.point_attributes.keys().collect::<Vec<_>>() != attribute_names)
    {
        return Err(encode_error(
            "parts carry different point attributes".into(),
        ));
    }
    if parts.len() > usize::from(u8::MAX) + 1 {
        return Err(encode_error(format!(
            "{} parts; the uchar `part` property holds at most 256",
            parts.len()
        )));
    }

    let mut ply = Ply::<DefaultElement>::new();
    ply.header.encoding = Encoding::BinaryLittleEndian;
    ply.header.comments.extend(comments.iter().cloned());
    ply.header
        .comments
        .push("units: metres; PLY has no axis convention: +Y is up as in glTF".into());
    for (i, part) in parts.iter().enumerate() {
        let [x, y, z] = part.offset_m;
        ply.header.comments.push(format!(
            "part {i} {:?}: offset ({x}, {y}, {z}) m added to positions for viewing",
            part.name
        ));
    }

    let scalar =
        |name: &str, t: ScalarType| PropertyDef::new(name.to_string(), PropertyType::Scalar(t));
    let mut vertex = ElementDef::new("vertex".into());
    for axis in ["x", "y", "z"] {
        vertex.properties.add(scalar(axis, ScalarType::Float));
    }
    for name in &attribute_names {
        vertex.properties.add(scalar(name, ScalarType::Float));
    }
    vertex.properties.add(scalar("part", ScalarType::UChar));
    ply.header.elements.add(vertex);
    let mut edge = ElementDef::new("edge".into());
    edge.properties.add(scalar("vertex1", ScalarType::Int));
    edge.properties.add(scalar("vertex2", ScalarType::Int));
    edge.properties.add(scalar("yarn_kind", ScalarType::UChar));
    edge.properties.add(scalar("direction", ScalarType::UChar));
    ply.header.elements.add(edge);

    let mut vertices = Vec::new();
    let mut edges = Vec::new();
    let mut first_vertex = 0usize;
    for (part_index, part) in parts.iter().enumerate() {
        for (i, p) in part.positions.iter().enumerate() {
            let mut v = DefaultElement::new();
            for (axis, k) in ["x", "y", "z"].iter().zip(0..3) {
                v.insert(
                    axis.to_string(),
                    Property::Float((p[k] + part.offset_m[k]) as f32),
                );
            }
            for (name, values) in &part.point_attributes {
                v.insert(name.clone(), Property::Float(values[i]));
            }
            // At most 256 parts, checked above.
            v.insert("part".into(), Property::UChar(part_index as u8));
            vertices.push(v);
        }
        for s in &part.segments {
            let index = |p: u32| {
                i32::try_from(first_vertex + p as usize)
                    .map_err(|_| encode_error("more than 2^31 vertices".into()))
            };
            let mut e = DefaultElement::new();
            e.insert("vertex1".into(), Property::Int(index(s.a)?));
            e.insert("vertex2".into(), Property::Int(index(s.b)?));
            e.insert("yarn_kind".into(), Property::UChar(s.yarn.index()));
            let direction = match s.direction {
                Direction::Course => 0,
                Direction::Wale => 1,
            };
            e.insert("direction".into(), Property::UChar(direction));
            edges.push(e);
        }
        first_vertex += part.positions.len();
    }
    ply.payload.insert("vertex".into(), vertices);
    ply.payload.insert("edge".into(), edges);

    let mut bytes = Vec::new();
    Writer::new()
        .write_ply(&mut bytes, &mut ply)
        .map_err(|e| encode_error(e.to_string()))?;
    Ok(bytes)
}

/// An error naming the first point attribute of `owner` that would take the name of one of the
/// vertex properties a writer writes itself (`reserved`).
fn refuse_clashing_names<V>(
    kind: &str,
    owner: &str,
    attributes: &std::collections::BTreeMap<String, V>,
    reserved: &[&str],
) -> std::result::Result<(), String> {
    match attributes
        .keys()
        .find(|name| reserved.contains(&name.as_str()))
    {
        Some(name) => Err(format!(
            "{kind} {owner:?}: point attribute {name:?} would clash with a vertex property"
        )),
        None => Ok(()),
    }
}

/// Encodes a triangle surface as a binary little-endian PLY file: `vertex` (x, y, z in metres,
/// nx, ny, nz, every point attribute, and red/green/blue as sRGB uchar when the mesh has
/// colours) and `face` (vertex_indices).
///
/// Fails with [`Error::Encode`] if the mesh is inconsistent (see [`check_surface_mesh`]), an
/// attribute takes the name of a vertex property, or a comment holds a line break.
pub fn write_mesh_ply(mesh: &SurfaceMesh, comments: &[String]) -> Result<Vec<u8>> {
    let encode_error = |message: String| Error::Encode {
        what: "PLY".into(),
        message,
    };
    check_surface_mesh(mesh).map_err(encode_error)?;
    refuse_clashing_names(
        "mesh",
        &mesh.name,
        &mesh.point_attributes,
        &MESH_VERTEX_PROPERTIES,
    )
    .map_err(encode_error)?;
    let mut ply = Ply::<DefaultElement>::new();
    ply.header.encoding = Encoding::BinaryLittleEndian;
    ply.header.comments.extend(comments.iter().cloned());
    ply.header
        .comments
        .push("units: metres; PLY has no axis convention: +Y is up as in glTF".into());
    let scalar =
        |name: &str, t: ScalarType| PropertyDef::new(name.to_string(), PropertyType::Scalar(t));
    let mut vertex = ElementDef::new("vertex".into());
    for name in ["x", "y", "z", "nx", "ny", "nz"] {
        vertex.properties.add(scalar(name, ScalarType::Float));
    }
    for name in mesh.point_attributes.keys() {
        vertex.properties.add(scalar(name, ScalarType::Float));
    }
    if mesh.colours.is_some() {
        for name in ["red", "green", "blue"] {
            vertex.properties.add(scalar(name, ScalarType::UChar));
        }
    }
    ply.header.elements.add(vertex);
    let mut face = ElementDef::new("face".into());
    face.properties.add(PropertyDef::new(
        "vertex_indices".into(),
        PropertyType::List(ScalarType::UChar, ScalarType::Int),
    ));
    ply.header.elements.add(face);

    let mut vertices = Vec::with_capacity(mesh.positions.len());
    for (i, p) in mesh.positions.iter().enumerate() {
        let mut v = DefaultElement::new();
        let n = mesh.normals[i];
        for (name, value) in ["x", "y", "z"].iter().zip(p) {
            v.insert(name.to_string(), Property::Float(*value as f32));
        }
        for (name, value) in ["nx", "ny", "nz"].iter().zip(n) {
            v.insert(name.to_string(), Property::Float(value));
        }
        for (name, values) in &mesh.point_attributes {
            v.insert(name.clone(), Property::Float(values[i]));
        }
        if let Some(colours) = &mesh.colours {
            let srgb = colours[i].map(crate::render::colormap::linear_to_srgb8);
            for (name, value) in ["red", "green", "blue"].iter().zip(srgb) {
                v.insert(name.to_string(), Property::UChar(value));
            }
        }
        vertices.push(v);
    }
    let faces = mesh
        .triangles
        .iter()
        .map(|t| {
            let mut f = DefaultElement::new();
            let indices = t
                .iter()
                .map(|&i| i32::try_from(i).map_err(|_| encode_error("index past 2^31".into())))
                .collect::<Result<Vec<i32>>>()?;
            f.insert("vertex_indices".into(), Property::ListInt(indices));
            Ok(f)
        })
        .collect::<Result<Vec<_>>>()?;
    ply.payload.insert("vertex".into(), vertices);
    ply.payload.insert("face".into(), faces);
    let mut bytes = Vec::new();
    Writer::new()
        .write_ply(&mut bytes, &mut ply)
        .map_err(|e| encode_error(e.to_string()))?;
    Ok(bytes)
}

/// Checks what every writer relies on in a yarn geometry: attribute names of the form
/// `[a-z][a-z0-9_]*` (valid PLY identifiers, distinct once upper-cased for glTF), one value per
/// point in every attribute, segments between existing points, and positions (also with the
/// offset added), offset and attribute values finite in single precision, as the files store
/// them. The message names the part and what is wrong.
pub(super) fn check_yarn_geometry(part: &YarnGeometry) -> std::result::Result<(), String> {
    let n = part.positions.len();
    let fail = |what: String| Err(format!("part {:?}: {what}", part.name));
    if let Err(what) = check_attributes(&part.point_attributes, n) {
        return fail(what);
    }
    if let Some(s) = part
        .segments
        .iter()
        .find(|s| s.a as usize >= n || s.b as usize >= n)
    {
        return fail(format!(
            "segment {}–{} past the last of {n} points",
            s.a, s.b
        ));
    }
    if !fits_f32(&part.offset_m) {
        return fail(format!("offset {:?} m is not finite", part.offset_m));
    }
    // PLY holds each point with the offset added.
    let with_offset = |p: &[f64; 3]| [0, 1, 2].map(|k| p[k] + part.offset_m[k]);
    if let Some(i) = part
        .positions
        .iter()
        .position(|p| !fits_f32(p) || !fits_f32(&with_offset(p)))
    {
        return fail(format!("point {i} is not finite: {:?}", part.positions[i]));
    }
    Ok(())
}

/// Checks what every writer relies on in a surface: one normal (and texture coordinate and
/// colour, where present) per vertex, triangles between existing vertices, positions finite in
/// single precision, and attributes as in [`check_yarn_geometry`].
pub(super) fn check_surface_mesh(mesh: &SurfaceMesh) -> std::result::Result<(), String> {
    let n = mesh.positions.len();
    let fail = |what: String| Err(format!("mesh {:?}: {what}", mesh.name));
    let lengths = [
        ("normals", Some(mesh.normals.len())),
        ("texture coordinates", mesh.texcoords.as_ref().map(Vec::len)),
        ("colours", mesh.colours.as_ref().map(Vec::len)),
    ];
    for (what, len) in lengths {
        if let Some(len) = len.filter(|&len| len != n) {
            return fail(format!("{len} {what} for {n} vertices"));
        }
    }
    if let Err(what) = check_attributes(&mesh.point_attributes, n) {
        return fail(what);
    }
    if let Some(t) = mesh
        .triangles
        .iter()
        .find(|t| t.iter().any(|&i| i as usize >= n))
    {
        return fail(format!("triangle {t:?} past the last of {n} vertices"));
    }
    if let Some(i) = mesh.positions.iter().position(|p| !fits_f32(p)) {
        return fail(format!("vertex {i} is not finite: {:?}", mesh.positions[i]));
    }
    let finite = |v: &[f32]| v.iter().all(|c| c.is_finite());
    let vectors_finite = [
        ("normal", mesh.normals.iter().all(|v| finite(v))),
        (
            "texture coordinate",
            mesh.texcoords.iter().flatten().all(|v| finite(v)),
        ),
        ("colour", mesh.colours.iter().flatten().all(|v| finite(v))),
    ];
    if let Some((what, _)) = vectors_finite.iter().find(|(_, ok)| !ok) {
        return fail(format!("a {what} is not finite"));
    }
    Ok(())
}

/// Attribute names `[a-z][a-z0-9_]*`, `points` finite values each.
fn check_attributes(
    attributes: &std::collections::BTreeMap<String, Vec<f32>>,
    points: usize,
) -> std::result::Result<(), String> {
    for (name, values) in attributes {
        let mut chars = name.chars();
        let well_formed = chars.next().is_some_and(|c| c.is_ascii_lowercase())
            && chars.all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_');
        if !well_formed {
            return Err(format!(
                "point attribute name {name:?} is not of the form [a-z][a-z0-9_]*"
            ));
        }
        if values.len() != points {
            return Err(format!(
                "point attribute {name:?} has {} values for {points} points",
                values.len()
            ));
        }
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(format!(
                "point attribute {name:?} is not finite at point {i}: {}",
                values[i]
            ));
        }
    }
    Ok(())
}

/// True when every coordinate is finite once stored as `f32`, as both formats store them (a
/// finite `f64` beyond `f32::MAX` would be written as an infinity).
fn fits_f32(p: &[f64; 3]) -> bool {
    p.iter().all(|&c| (c as f32).is_finite())
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::export::sample_geometry as part;

    fn parse(bytes: &[u8]) -> Ply<DefaultElement> {
        ply_rs_bw::parser::Parser::<DefaultElement>::new()
            .read_ply(&mut &bytes[..])
            .unwrap()
    }

    fn property_names(ply: &Ply<DefaultElement>, element: &str) -> Vec<String> {
        ply.header.elements[element]
            .properties
            .keys()
            .cloned()
            .collect()
    }

    #[test]
    fn round_trips_through_the_ply_parser() {
        let bytes = write_ply(&[part("a", 0.0), part("b", 0.5)], &["test".into()]).unwrap();
        let ply = parse(&bytes);
        assert_eq!(ply.header.encoding, Encoding::BinaryLittleEndian);
        assert_eq!(
            property_names(&ply, "vertex"),
            ["x", "y", "z", "course", "wale", "yarn_kind", "part"]
        );
        assert_eq!(
            property_names(&ply, "edge"),
            ["vertex1", "vertex2", "yarn_kind", "direction"]
        );
        let vertices = &ply.payload["vertex"];
        let edges = &ply.payload["edge"];
        assert_eq!((vertices.len(), edges.len()), (6, 4));
        assert_eq!(vertices[1]["x"], Property::Float(0.001));
        assert_eq!(vertices[4]["x"], Property::Float(0.501), "offset added");
        assert_eq!(vertices[5]["y"], Property::Float(0.002));
        assert_eq!(vertices[2]["course"], Property::Float(1.0));
        assert_eq!(vertices[4]["wale"], Property::Float(1.0));
        assert_eq!(vertices[5]["yarn_kind"], Property::Float(1.0));
        assert_eq!(vertices[2]["part"], Property::UChar(0));
        assert_eq!(vertices[3]["part"], Property::UChar(1));
        assert_eq!(edges[0]["yarn_kind"], Property::UChar(0));
        assert_eq!(edges[0]["direction"], Property::UChar(0));
        assert_eq!(edges[3]["vertex1"], Property::Int(3));
        assert_eq!(edges[3]["vertex2"], Property::Int(5));
        assert_eq!(edges[3]["yarn_kind"], Property::UChar(1));
        assert_eq!(edges[3]["direction"], Property::UChar(1));
    }

    #[test]
    fn header_states_units_and_each_offset() {
        let bytes = write_ply(&[part("a", 0.0), part("b", 0.5)], &["test".into()]).unwrap();
        let comments = parse(&bytes).header.comments;
        assert_eq!(comments.len(), 4, "{comments:?}");
        assert_eq!(comments[0], "test");
        assert_eq!(
            comments[1],
            "units: metres; PLY has no axis convention: +Y is up as in glTF"
        );
        assert_eq!(
            comments[3],
            "part 1 \"b\": offset (0.5, 0, 0) m added to positions for viewing"
        );
    }

    #[test]
    fn is_deterministic() {
        let parts = [part("a", 0.0), part("b", 0.5)];
        assert_eq!(
            write_ply(&parts, &[]).unwrap(),
            write_ply(&parts, &[]).unwrap()
        );
    }

    #[test]
    fn mismatched_attributes_are_an_error() {
        let mut b = part("b", 0.0);
        b.point_attributes.remove("wale");
        let err = write_ply(&[part("a", 0.0), b], &[]).unwrap_err();
        assert!(matches!(err, Error::Encode { .. }), "{err}");
    }

    #[test]
    fn attribute_of_the_wrong_length_is_an_error_not_a_panic() {
        let mut a = part("a", 0.0);
        a.point_attributes.get_mut("wale").unwrap().pop();
        let err = write_ply(&[a], &[]).unwrap_err();
        assert!(err.to_string().contains("2 values for 3 points"), "{err}");
    }

    #[test]
    fn segment_past_the_last_point_is_an_error() {
        let mut a = part("a", 0.0);
        a.segments[1].b = 3;
        let err = write_ply(&[a], &[]).unwrap_err();
        assert!(matches!(err, Error::Encode { .. }), "{err}");
    }

    #[test]
    fn attribute_named_like_a_vertex_property_is_refused() {
        let mut a = part("a", 0.0);
        a.point_attributes.insert("part".into(), vec![0.0; 3]);
        let err = write_ply(&[a], &[]).unwrap_err();
        assert!(err.to_string().contains("clash"), "{err}");
    }

    #[test]
    fn comment_with_a_line_break_is_an_error() {
        let err = write_ply(&[part("a", 0.0)], &["two\nlines".into()]).unwrap_err();
        assert!(matches!(err, Error::Encode { .. }), "{err}");
    }

    #[test]
    fn surface_round_trips_with_normals_and_faces() {
        let mut mesh = SurfaceMesh::new(
            "leg",
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]],
            vec![[0, 1, 2]],
        );
        mesh.point_attributes
            .insert("stitch_density".into(), vec![1.0, 2.0, 3.0]);
        let ply = parse(&write_mesh_ply(&mesh, &[]).unwrap());
        let vertices = &ply.payload["vertex"];
        assert_eq!(vertices[1]["x"], Property::Float(1.0));
        assert_eq!(vertices[0]["ny"], Property::Float(1.0));
        assert_eq!(vertices[2]["stitch_density"], Property::Float(3.0));
        assert_eq!(
            ply.payload["face"][0]["vertex_indices"],
            Property::ListInt(vec![0, 1, 2])
        );
    }

    #[test]
    fn surface_with_a_missing_normal_is_an_error_not_a_panic() {
        let mut mesh = SurfaceMesh::new("leg", vec![[0.0; 3]; 3], vec![[0, 1, 2]]);
        mesh.normals.pop();
        let err = write_mesh_ply(&mesh, &[]).unwrap_err();
        assert!(matches!(err, Error::Encode { .. }), "{err}");
    }
}
