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

/// Encodes `parts` as one PLY file. Each part's `offset_m` is added to its positions (PLY has no
/// transforms); a `part` property says which part a vertex came from. `comments` go into the
/// header, followed by the unit/axis convention and the offsets used.
///
/// All parts must carry the same attribute names.
pub fn write_ply(parts: &[YarnGeometry], comments: &[String]) -> Result<Vec<u8>> {
    let encode_error = |message: String| Error::Encode {
        what: "PLY".into(),
        message,
    };
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

    let mut ply = Ply::<DefaultElement>::new();
    ply.header.encoding = Encoding::BinaryLittleEndian;
    ply.header.comments.extend(comments.iter().cloned());
    ply.header
        .comments
        .push("units: metres; PLY has no axis convention: +Y is up as in glTF".into());
    for (i, part) in parts.iter().enumerate() {
        let [x, y, z] = part.offset_m;
        ply.header.comments.push(format!(
            "part {i} \"{}\": offset ({x}, {y}, {z}) m added to positions for viewing",
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

/// Encodes a triangle surface as a PLY file: `vertex` (x, y, z, nx, ny, nz, every point
/// attribute, and red/green/blue when the mesh has colours) and `face` (vertex_indices).
pub fn write_mesh_ply(mesh: &SurfaceMesh, comments: &[String]) -> Result<Vec<u8>> {
    let encode_error = |message: String| Error::Encode {
        what: "PLY".into(),
        message,
    };
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

#[cfg(test)]
mod tests {
    use super::*;

    use crate::export::sample_geometry as part;

    #[test]
    fn round_trips_through_the_ply_parser() {
        let bytes = write_ply(&[part("a", 0.0), part("b", 0.5)], &["test".into()]).unwrap();
        let ply = ply_rs_bw::parser::Parser::<DefaultElement>::new()
            .read_ply(&mut bytes.as_slice())
            .unwrap();
        assert!(ply.header.comments.iter().any(|c| c.contains("metres")));
        let vertices = &ply.payload["vertex"];
        let edges = &ply.payload["edge"];
        assert_eq!((vertices.len(), edges.len()), (6, 4));
        assert_eq!(vertices[4]["x"], Property::Float(0.501));
        assert_eq!(vertices[5]["y"], Property::Float(0.002));
        assert_eq!(vertices[2]["course"], Property::Float(1.0));
        assert_eq!(vertices[4]["wale"], Property::Float(1.0));
        assert_eq!(vertices[3]["part"], Property::UChar(1));
        assert_eq!(edges[3]["vertex1"], Property::Int(3));
        assert_eq!(edges[3]["vertex2"], Property::Int(5));
        assert_eq!(edges[3]["yarn_kind"], Property::UChar(1));
        assert_eq!(edges[3]["direction"], Property::UChar(1));
    }

    #[test]
    fn is_deterministic() {
        let parts = [part("a", 0.0)];
        assert_eq!(
            write_ply(&parts, &[]).unwrap(),
            write_ply(&parts, &[]).unwrap()
        );
    }

    #[test]
    fn mismatched_attributes_are_an_error() {
        let mut b = part("b", 0.0);
        b.point_attributes.remove("wale");
        assert!(write_ply(&[part("a", 0.0), b], &[]).is_err());
    }
}
