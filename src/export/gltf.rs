//! Binary glTF 2.0 writer. The document is built with `gltf-json` and packed into a GLB with
//! `gltf::binary::Glb`; no JSON is written by hand.
//!
//! Yarns are `LINES` primitives, one per yarn kind with a material each, sharing one set of
//! vertex accessors: `POSITION` and every point attribute as a custom `_UPPERCASE` float attribute
//! (the validator requires custom attributes to start with `_`; Blender imports them as point
//! attributes). Positions are metres, Y up.

use std::borrow::Cow;
use std::collections::BTreeMap;

use gltf_json as json;
use json::validation::{Checked::Valid, USize64};
use json::Index;

use super::{SurfaceMesh, YarnGeometry};
use crate::error::{Error, Result};
use crate::knit::YarnKind;

/// One root node of a GLB file.
pub enum GlbNode<'a> {
    /// A triangle surface (the leg, the stocking surface).
    Surface(&'a SurfaceMesh),
    /// Yarn polylines.
    Yarns(&'a YarnGeometry),
}

/// Encodes `parts` as one GLB of yarns only (the patch experiment): a root node per part, named
/// after it and translated by its `offset_m`. `yarn_colours` are linear RGB per yarn kind.
pub fn write_glb(parts: &[YarnGeometry], yarn_colours: [[f64; 3]; 2]) -> Result<Vec<u8>> {
    let nodes: Vec<GlbNode> = parts.iter().map(GlbNode::Yarns).collect();
    write_nodes_glb(&nodes, yarn_colours)
}

/// Encodes surfaces and yarns as one GLB, a root node each, in the given order.
pub fn write_nodes_glb(nodes: &[GlbNode], yarn_colours: [[f64; 3]; 2]) -> Result<Vec<u8>> {
    let mut doc = GlbBuilder::default();
    // A material per yarn kind that some segment uses (an unused one is a validator notice).
    let materials = YarnKind::ALL.map(|kind| {
        let used = nodes.iter().any(|n| match n {
            GlbNode::Yarns(p) => p.segments.iter().any(|s| s.yarn == kind),
            GlbNode::Surface(_) => false,
        });
        used.then(|| {
            let [r, g, b] = yarn_colours[kind.index() as usize].map(|c| c as f32);
            doc.material(kind.name(), [r, g, b])
        })
    });
    let roots = nodes
        .iter()
        .map(|node| match node {
            GlbNode::Yarns(part) => doc.yarn_node(part, &materials),
            GlbNode::Surface(mesh) => doc.surface_node(mesh),
        })
        .collect();
    let scene = doc.root.push(json::Scene {
        extensions: None,
        extras: Default::default(),
        name: Some("knitfit".into()),
        nodes: roots,
    });
    doc.root.scene = Some(scene);
    doc.finish()
}

/// Custom attributes as glTF wants them: `_UPPERCASE` float scalars.
fn custom_attributes(
    doc: &mut GlbBuilder,
    attributes: &BTreeMap<String, Vec<f32>>,
) -> BTreeMap<json::validation::Checked<json::mesh::Semantic>, Index<json::Accessor>> {
    attributes
        .iter()
        .map(|(name, values)| {
            (
                Valid(json::mesh::Semantic::Extras(name.to_uppercase())),
                doc.scalars(values),
            )
        })
        .collect()
}

/// A glTF document under construction and its binary chunk.
#[derive(Default)]
pub struct GlbBuilder {
    /// The JSON document.
    pub root: json::Root,
    bin: Vec<u8>,
}

impl GlbBuilder {
    /// Appends `bytes` to the binary chunk (4-byte aligned) as a buffer view.
    fn view(&mut self, bytes: &[u8], target: json::buffer::Target) -> Index<json::buffer::View> {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        self.root.push(json::buffer::View {
            buffer: Index::new(0),
            byte_length: USize64(bytes.len() as u64),
            byte_offset: Some(USize64(offset as u64)),
            byte_stride: None,
            name: None,
            target: Some(Valid(target)),
            extensions: None,
            extras: Default::default(),
        })
    }

    fn accessor(
        &mut self,
        view: Index<json::buffer::View>,
        count: usize,
        component: json::accessor::ComponentType,
        type_: json::accessor::Type,
        bounds: Option<(serde_json::Value, serde_json::Value)>,
    ) -> Index<json::Accessor> {
        let (min, max) = bounds.unzip();
        self.root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: USize64(count as u64),
            component_type: Valid(json::accessor::GenericComponentType(component)),
            extensions: None,
            extras: Default::default(),
            type_: Valid(type_),
            min,
            max,
            name: None,
            normalized: false,
            sparse: None,
        })
    }

    /// A metallic-free material of a base colour (linear RGB).
    pub fn material(&mut self, name: &str, [r, g, b]: [f32; 3]) -> Index<json::Material> {
        self.root.push(json::Material {
            name: Some(name.to_string()),
            pbr_metallic_roughness: json::material::PbrMetallicRoughness {
                base_color_factor: json::material::PbrBaseColorFactor([r, g, b, 1.0]),
                metallic_factor: json::material::StrengthFactor(0.0),
                roughness_factor: json::material::StrengthFactor(0.6),
                ..Default::default()
            },
            ..Default::default()
        })
    }

    /// A node of yarn polylines: `LINES`, one primitive per yarn kind, shared vertex accessors.
    fn yarn_node(
        &mut self,
        part: &YarnGeometry,
        materials: &[Option<Index<json::Material>>; 2],
    ) -> Index<json::Node> {
        let mut attributes = custom_attributes(self, &part.point_attributes);
        attributes.insert(
            Valid(json::mesh::Semantic::Positions),
            self.positions(&part.positions),
        );
        let mut primitives = Vec::new();
        for kind in YarnKind::ALL {
            let indices: Vec<u32> = part
                .segments
                .iter()
                .filter(|s| s.yarn == kind)
                .flat_map(|s| [s.a, s.b])
                .collect();
            if indices.is_empty() {
                continue;
            }
            primitives.push(json::mesh::Primitive {
                attributes: attributes.clone(),
                extensions: None,
                extras: Default::default(),
                indices: Some(self.indices(&indices)),
                material: materials[kind.index() as usize],
                mode: Valid(json::mesh::Mode::Lines),
                targets: None,
            });
        }
        let [x, y, z] = part.offset_m.map(|c| c as f32);
        let translation = (part.offset_m != [0.0; 3]).then_some([x, y, z]);
        self.node(&part.name, primitives, translation)
    }

    /// A node of one `TRIANGLES` primitive with normals, optional texture coordinates and
    /// colours, and the custom attributes.
    fn surface_node(&mut self, mesh: &SurfaceMesh) -> Index<json::Node> {
        use json::mesh::Semantic;
        let mut attributes = custom_attributes(self, &mesh.point_attributes);
        attributes.insert(Valid(Semantic::Positions), self.positions(&mesh.positions));
        attributes.insert(Valid(Semantic::Normals), self.vectors(&mesh.normals));
        if let Some(uv) = &mesh.texcoords {
            attributes.insert(Valid(Semantic::TexCoords(0)), self.vectors(uv));
        }
        if let Some(colours) = &mesh.colours {
            attributes.insert(Valid(Semantic::Colors(0)), self.vectors(colours));
        }
        let indices: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
        let primitive = json::mesh::Primitive {
            attributes,
            extensions: None,
            extras: Default::default(),
            indices: Some(self.indices(&indices)),
            material: None,
            mode: Valid(json::mesh::Mode::Triangles),
            targets: None,
        };
        self.node(&mesh.name, vec![primitive], None)
    }

    /// A node holding a mesh of `primitives` (none: an empty node).
    fn node(
        &mut self,
        name: &str,
        primitives: Vec<json::mesh::Primitive>,
        translation: Option<[f32; 3]>,
    ) -> Index<json::Node> {
        let mesh = (!primitives.is_empty()).then(|| {
            self.root.push(json::Mesh {
                extensions: None,
                extras: Default::default(),
                name: Some(name.to_string()),
                primitives,
                weights: None,
            })
        });
        self.root.push(json::Node {
            mesh,
            name: Some(name.to_string()),
            translation,
            ..Default::default()
        })
    }

    /// A float `VEC2`/`VEC3` accessor (normals, colours, texture coordinates): no bounds.
    pub fn vectors<const N: usize>(&mut self, values: &[[f32; N]]) -> Index<json::Accessor> {
        let bytes: Vec<u8> = values
            .iter()
            .flatten()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let view = self.view(&bytes, json::buffer::Target::ArrayBuffer);
        let type_ = match N {
            2 => json::accessor::Type::Vec2,
            3 => json::accessor::Type::Vec3,
            _ => json::accessor::Type::Vec4,
        };
        self.accessor(
            view,
            values.len(),
            json::accessor::ComponentType::F32,
            type_,
            None,
        )
    }

    /// A `VEC3` float accessor of positions (metres, stored as f32) with the min/max glTF needs.
    pub fn positions(&mut self, positions: &[[f64; 3]]) -> Index<json::Accessor> {
        let mut min = [f32::INFINITY; 3];
        let mut max = [f32::NEG_INFINITY; 3];
        let mut bytes = Vec::with_capacity(positions.len() * 12);
        for p in positions {
            for k in 0..3 {
                let c = p[k] as f32;
                min[k] = min[k].min(c);
                max[k] = max[k].max(c);
                bytes.extend_from_slice(&c.to_le_bytes());
            }
        }
        let view = self.view(&bytes, json::buffer::Target::ArrayBuffer);
        let bounds =
            (!positions.is_empty()).then(|| (serde_json::json!(min), serde_json::json!(max)));
        self.accessor(
            view,
            positions.len(),
            json::accessor::ComponentType::F32,
            json::accessor::Type::Vec3,
            bounds,
        )
    }

    /// A `SCALAR` float accessor.
    pub fn scalars(&mut self, values: &[f32]) -> Index<json::Accessor> {
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let view = self.view(&bytes, json::buffer::Target::ArrayBuffer);
        self.accessor(
            view,
            values.len(),
            json::accessor::ComponentType::F32,
            json::accessor::Type::Scalar,
            None,
        )
    }

    /// An index accessor (`u32`).
    pub fn indices(&mut self, indices: &[u32]) -> Index<json::Accessor> {
        let bytes: Vec<u8> = indices.iter().flat_map(|v| v.to_le_bytes()).collect();
        let view = self.view(&bytes, json::buffer::Target::ElementArrayBuffer);
        self.accessor(
            view,
            indices.len(),
            json::accessor::ComponentType::U32,
            json::accessor::Type::Scalar,
            None,
        )
    }

    /// Packs the document and the binary chunk into GLB bytes.
    pub fn finish(mut self) -> Result<Vec<u8>> {
        let encode_error = |message: String| Error::Encode {
            what: "glTF".into(),
            message,
        };
        self.root.asset.generator = Some(format!("knitfit {}", env!("CARGO_PKG_VERSION")));
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        if !self.bin.is_empty() {
            self.root.buffers = vec![json::Buffer {
                byte_length: USize64(self.bin.len() as u64),
                name: None,
                uri: None,
                extensions: None,
                extras: Default::default(),
            }];
        }
        let json_bytes = self
            .root
            .to_vec()
            .map_err(|e| encode_error(e.to_string()))?;
        let glb = gltf::binary::Glb {
            header: gltf::binary::Header {
                magic: *b"glTF",
                version: 2,
                length: 0, // computed by to_vec
            },
            json: Cow::Owned(json_bytes),
            bin: (!self.bin.is_empty()).then_some(Cow::Owned(self.bin)),
        };
        glb.to_vec().map_err(|e| encode_error(e.to_string()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::export::sample_geometry as part;

    #[test]
    fn round_trips_through_the_gltf_reader() {
        let bytes = write_glb(&[part("a", 0.0), part("b", 0.5)], [[0.1; 3], [0.2; 3]]).unwrap();
        let (doc, buffers, _) = gltf::import_slice(&bytes).unwrap();
        let nodes: Vec<_> = doc.nodes().collect();
        assert_eq!(nodes[1].name(), Some("b"));
        assert_eq!(nodes[1].transform().decomposed().0, [0.5, 0.0, 0.0]);
        let prims: Vec<_> = nodes[1].mesh().unwrap().primitives().collect();
        assert_eq!(prims.len(), 2, "one primitive per yarn kind");
        assert_eq!(prims[1].material().name(), Some("support"));
        let reader = prims[1].reader(|b| Some(&buffers[b.index()]));
        assert_eq!(prims[1].mode(), gltf::mesh::Mode::Lines);
        assert_eq!(
            reader
                .read_indices()
                .unwrap()
                .into_u32()
                .collect::<Vec<_>>(),
            [0, 2]
        );
        let positions: Vec<_> = reader.read_positions().unwrap().collect();
        assert_eq!(positions[2], [0.0, 0.002, 0.0]);
        let course = prims[1]
            .attributes()
            .find(|(s, _)| *s == gltf::Semantic::Extras("COURSE".into()))
            .expect("_COURSE is written")
            .1;
        assert_eq!(course.count(), 3);
        let view = course.view().unwrap();
        let data = &buffers[0][view.offset()..view.offset() + view.length()];
        assert_eq!(f32::from_le_bytes(data[8..12].try_into().unwrap()), 1.0);
    }

    #[test]
    fn only_used_yarn_kinds_get_a_material() {
        let mut nylon_only = part("a", 0.0);
        nylon_only.segments.retain(|s| s.yarn == YarnKind::Nylon);
        let bytes = write_glb(&[nylon_only], [[0.1; 3]; 2]).unwrap();
        let (doc, _, _) = gltf::import_slice(&bytes).unwrap();
        let names: Vec<_> = doc
            .materials()
            .map(|m| m.name().unwrap().to_string())
            .collect();
        assert_eq!(names, ["nylon"]);
    }

    #[test]
    fn is_deterministic() {
        let parts = [part("a", 0.0)];
        assert_eq!(
            write_glb(&parts, [[0.1; 3]; 2]).unwrap(),
            write_glb(&parts, [[0.1; 3]; 2]).unwrap()
        );
    }
}
