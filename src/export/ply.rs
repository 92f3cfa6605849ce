//! PLY writer (binary little-endian): the yarn points as a `vertex` element with every point
//! attribute, and the yarn segments as an `edge` element, which Blender imports as loose edges.

use std::borrow::Cow;

use ply_rs_bw::ply::{
    Addable, ElementDef, Encoding, Ply, PropertyAccess, PropertyDef, PropertyType, ScalarType,
};
use ply_rs_bw::writer::Writer;

use crate::base::{Direction, SurfaceMesh, YarnGeometry};
use crate::error::{Error, Result};

/// Vertex properties [`write_ply`] writes itself, so no point attribute may take their names.
const YARN_VERTEX_PROPERTIES: [&str; 4] = ["x", "y", "z", "part"];

/// Vertex properties [`write_mesh_ply`] writes itself.
const MESH_VERTEX_PROPERTIES: [&str; 10] = [
    "x", "y", "z", "nx", "ny", "nz", "red", "green", "blue", "alpha",
];

/// Encodes `parts` as one binary little-endian PLY file.
///
/// `vertex`: `x`, `y`, `z` (float, metres, each part's `offset_m` added, as PLY has no
/// transforms), every point attribute (float, in the map's order), `part` (uchar, index into
/// `parts`). `edge`: `vertex1`, `vertex2` (int, indices into all parts' vertices in order),
/// `yarn_kind` (uchar, [`YarnKind::index`](crate::base::YarnKind::index)), `direction` (uchar,
/// 0 course, 1 wale). The header holds `comments`, then the unit/axis convention, then one line
/// per part giving its name and the offset added. The bytes depend only on the arguments.
///
/// Fails with [`Error::Encode`] if the parts carry different attribute names, if a part is
/// inconsistent (indices past the points, attributes of the wrong length, non-finite
/// positions), if there are more than 256 parts or 2^31
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

    let mut ply = header(comments);
    for (i, part) in parts.iter().enumerate() {
        let [x, y, z] = part.offset_m;
        ply.header.comments.push(format!(
            "part {i} {:?}: offset ({x}, {y}, {z}) m added to positions for viewing",
            part.name
        ));
    }

    let mut vertex = Table::default();
    for k in 0..3 {
        let coordinate = parts.iter().flat_map(|part| {
            let offset = part.offset_m[k];
            part.positions.iter().map(move |p| (p[k] + offset) as f32)
        });
        vertex.add(["x", "y", "z"][k], Column::Float(coordinate.collect()));
    }
    for name in &attribute_names {
        let values = match parts {
            [one] => Cow::Borrowed(&one.point_attributes[*name][..]),
            _ => Cow::Owned(
                parts
                    .iter()
                    .flat_map(|part| part.point_attributes[*name].iter().copied())
                    .collect(),
            ),
        };
        vertex.add(name, Column::Float(values));
    }
    // At most 256 parts, checked above.
    let part_of_vertex = parts
        .iter()
        .enumerate()
        .flat_map(|(i, part)| std::iter::repeat_n(i as u8, part.positions.len()));
    vertex.add("part", Column::UChar(part_of_vertex.collect()));

    let mut ends = [Vec::new(), Vec::new()];
    let (mut yarn_kind, mut direction) = (Vec::new(), Vec::new());
    let mut first_vertex = 0usize;
    for part in parts {
        let index = |p: u32| {
            i32::try_from(first_vertex + p as usize)
                .map_err(|_| encode_error("more than 2^31 vertices".into()))
        };
        for s in &part.segments {
            ends[0].push(index(s.a)?);
            ends[1].push(index(s.b)?);
            yarn_kind.push(s.yarn.index());
            direction.push(match s.direction {
                Direction::Course => 0,
                Direction::Wale => 1,
            });
        }
        first_vertex += part.positions.len();
    }
    let mut edge = Table::default();
    let [vertex1, vertex2] = ends;
    edge.add("vertex1", Column::Int(vertex1));
    edge.add("vertex2", Column::Int(vertex2));
    edge.add("yarn_kind", Column::UChar(yarn_kind));
    edge.add("direction", Column::UChar(direction));

    encode(ply, &[("vertex", &vertex), ("edge", &edge)]).map_err(encode_error)
}

/// A binary little-endian PLY with `comments` and the unit/axis convention, and no elements yet.
fn header<'a>(comments: &[String]) -> Ply<Row<'a>> {
    let mut ply = Ply::<Row>::new();
    ply.header.encoding = Encoding::BinaryLittleEndian;
    ply.header.comments.extend(comments.iter().cloned());
    ply.header
        .comments
        .push("units: metres; PLY has no axis convention: +Y is up as in glTF".into());
    ply
}

/// Adds each table to `ply` as an element (properties in the table's column order) and
/// encodes the file.
fn encode<'a>(
    mut ply: Ply<Row<'a>>,
    elements: &[(&str, &'a Table<'a>)],
) -> std::result::Result<Vec<u8>, String> {
    for (name, table) in elements {
        let mut def = ElementDef::new(name.to_string());
        for (property, column) in &table.columns {
            def.properties
                .add(PropertyDef::new(property.clone(), column.property_type()));
        }
        ply.header.elements.add(def);
        let rows = (0..table.rows())
            .map(|row| Row {
                table: Some(table),
                row,
            })
            .collect();
        ply.payload.insert(name.to_string(), rows);
    }
    let mut bytes = Vec::new();
    Writer::new()
        .write_ply(&mut bytes, &mut ply)
        .map_err(|e| e.to_string())?;
    Ok(bytes)
}

/// One element's values, a column per property in the order the file lists them: the writer
/// reads them row by row through [`Row`], instead of building a map of named values per row
/// (docs/decisions/0026).
#[derive(Default)]
struct Table<'a> {
    columns: Vec<(String, Column<'a>)>,
}

/// One property's values, one per row.
enum Column<'a> {
    Float(Cow<'a, [f32]>),
    UChar(Vec<u8>),
    Int(Vec<i32>),
    /// A list of three `int`s with a `uchar` count: a triangle's vertex indices.
    Triangles(Vec<[i32; 3]>),
}

impl Column<'_> {
    fn property_type(&self) -> PropertyType {
        match self {
            Column::Float(_) => PropertyType::Scalar(ScalarType::Float),
            Column::UChar(_) => PropertyType::Scalar(ScalarType::UChar),
            Column::Int(_) => PropertyType::Scalar(ScalarType::Int),
            Column::Triangles(_) => PropertyType::List(ScalarType::UChar, ScalarType::Int),
        }
    }

    fn len(&self) -> usize {
        match self {
            Column::Float(v) => v.len(),
            Column::UChar(v) => v.len(),
            Column::Int(v) => v.len(),
            Column::Triangles(v) => v.len(),
        }
    }
}

impl<'a> Table<'a> {
    fn add(&mut self, name: &str, column: Column<'a>) {
        self.columns.push((name.to_string(), column));
    }

    fn rows(&self) -> usize {
        self.columns.first().map_or(0, |(_, c)| c.len())
    }

    fn column(&self, name: &str) -> Option<&Column<'a>> {
        self.columns.iter().find(|(n, _)| n == name).map(|(_, c)| c)
    }
}

/// Row `row` of a [`Table`], as the writer asks for it: by property name.
struct Row<'a> {
    table: Option<&'a Table<'a>>,
    row: usize,
}

impl PropertyAccess for Row<'_> {
    fn new() -> Self {
        Row {
            table: None,
            row: 0,
        }
    }

    fn get_float(&self, name: &str) -> Option<f32> {
        match self.table?.column(name)? {
            Column::Float(v) => v.get(self.row).copied(),
            _ => None,
        }
    }

    fn get_uchar(&self, name: &str) -> Option<u8> {
        match self.table?.column(name)? {
            Column::UChar(v) => v.get(self.row).copied(),
            _ => None,
        }
    }

    fn get_int(&self, name: &str) -> Option<i32> {
        match self.table?.column(name)? {
            Column::Int(v) => v.get(self.row).copied(),
            _ => None,
        }
    }

    fn get_list_int(&self, name: &str) -> Option<&[i32]> {
        match self.table?.column(name)? {
            Column::Triangles(v) => v.get(self.row).map(|t| &t[..]),
            _ => None,
        }
    }
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
/// nx, ny, nz, every point attribute, red/green/blue as sRGB uchar when the mesh has colours,
/// and alpha as linear uchar (opacity × 255, rounded) when it has an opacity) and `face`
/// (vertex_indices).
///
/// Fails with [`Error::Encode`] if the mesh is inconsistent (as for [`write_ply`]), an
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
    let mut vertex = Table::default();
    for k in 0..3 {
        let coordinate = mesh.positions.iter().map(|p| p[k] as f32);
        vertex.add(["x", "y", "z"][k], Column::Float(coordinate.collect()));
    }
    for k in 0..3 {
        let normal = mesh.normals.iter().map(|n| n[k]);
        vertex.add(["nx", "ny", "nz"][k], Column::Float(normal.collect()));
    }
    for (name, values) in &mesh.point_attributes {
        vertex.add(name, Column::Float(Cow::Borrowed(values)));
    }
    if let Some(colours) = &mesh.colours {
        for k in 0..3 {
            let channel = colours
                .iter()
                .map(|c| crate::base::colour::linear_to_srgb8(c[k]));
            vertex.add(
                ["red", "green", "blue"][k],
                Column::UChar(channel.collect()),
            );
        }
    }
    if let Some(opacity) = &mesh.opacity {
        // Checked 0–1 above; alpha is a fraction, not a light level, so it is not sRGB-encoded.
        let alpha = opacity.iter().map(|&a| (a * 255.0).round() as u8);
        vertex.add("alpha", Column::UChar(alpha.collect()));
    }
    let triangles = mesh
        .triangles
        .iter()
        .map(|t| {
            let index =
                |i: u32| i32::try_from(i).map_err(|_| encode_error("index past 2^31".into()));
            Ok([index(t[0])?, index(t[1])?, index(t[2])?])
        })
        .collect::<Result<Vec<_>>>()?;
    let mut face = Table::default();
    face.add("vertex_indices", Column::Triangles(triangles));
    encode(header(comments), &[("vertex", &vertex), ("face", &face)]).map_err(encode_error)
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

/// Checks what every writer relies on in a surface: one normal (and texture coordinate, colour
/// and opacity, where present) per vertex, an opacity only with colours and within 0–1,
/// triangles between existing vertices, positions finite in single precision, and attributes as
/// in [`check_yarn_geometry`].
pub(super) fn check_surface_mesh(mesh: &SurfaceMesh) -> std::result::Result<(), String> {
    let n = mesh.positions.len();
    let fail = |what: String| Err(format!("mesh {:?}: {what}", mesh.name));
    let lengths = [
        ("normals", Some(mesh.normals.len())),
        ("texture coordinates", mesh.texcoords.as_ref().map(Vec::len)),
        ("colours", mesh.colours.as_ref().map(Vec::len)),
        ("opacities", mesh.opacity.as_ref().map(Vec::len)),
    ];
    for (what, len) in lengths {
        if let Some(len) = len.filter(|&len| len != n) {
            return fail(format!("{len} {what} for {n} vertices"));
        }
    }
    if mesh.opacity.is_some() && mesh.colours.is_none() {
        return fail("an opacity without colours (it is their alpha)".into());
    }
    if let Some(a) = mesh
        .opacity
        .iter()
        .flatten()
        .find(|a| !(0.0..=1.0).contains(*a))
    {
        return fail(format!("opacity {a} is outside 0–1"));
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
    use ply_rs_bw::ply::{DefaultElement, Property};

    use crate::base::yarn::sample_geometry as part;

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
    fn surface_opacity_is_a_linear_alpha_after_the_colours() {
        let mut mesh = SurfaceMesh::new("stocking", vec![[0.0; 3]; 3], vec![[0, 1, 2]]);
        mesh.colours = Some(vec![[1.0; 3]; 3]);
        mesh.opacity = Some(vec![0.0, 0.25, 1.0]);
        let ply = parse(&write_mesh_ply(&mesh, &[]).unwrap());
        assert_eq!(
            property_names(&ply, "vertex")[6..],
            ["red", "green", "blue", "alpha"]
        );
        let alpha: Vec<_> = ply.payload["vertex"]
            .iter()
            .map(|v| v["alpha"].clone())
            .collect();
        assert_eq!(
            alpha,
            [0, 64, 255].map(Property::UChar),
            "0.25 × 255 = 63.75 rounds to 64, not sRGB-encoded"
        );
    }

    #[test]
    fn opacity_without_colours_or_outside_0_to_1_is_an_error() {
        let mut mesh = SurfaceMesh::new("stocking", vec![[0.0; 3]; 3], vec![[0, 1, 2]]);
        mesh.opacity = Some(vec![0.5; 3]);
        let err = write_mesh_ply(&mesh, &[]).unwrap_err();
        assert!(err.to_string().contains("without colours"), "{err}");
        mesh.colours = Some(vec![[1.0; 3]; 3]);
        for bad in [1.5, -0.1, f32::NAN] {
            mesh.opacity = Some(vec![0.5, bad, 0.5]);
            let err = write_mesh_ply(&mesh, &[]).unwrap_err();
            assert!(err.to_string().contains("outside 0–1"), "{err}");
        }
    }

    #[test]
    fn surface_with_a_missing_normal_is_an_error_not_a_panic() {
        let mut mesh = SurfaceMesh::new("leg", vec![[0.0; 3]; 3], vec![[0, 1, 2]]);
        mesh.normals.pop();
        let err = write_mesh_ply(&mesh, &[]).unwrap_err();
        assert!(matches!(err, Error::Encode { .. }), "{err}");
    }
}
