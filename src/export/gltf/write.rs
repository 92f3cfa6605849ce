//! Binary glTF 2.0 writer. The document is built with `gltf-json` and packed into a GLB with
//! `gltf::binary::Glb`; no JSON is written by hand.
//!
//! Yarns are `LINES` primitives, one per yarn kind with a material each, sharing one set of
//! vertex accessors: `POSITION` and every point attribute as a custom `_UPPERCASE` float attribute
//! (the validator requires custom attributes to start with `_`; Blender imports them as point
//! attributes). Positions are metres, Y up.
//!
//! A surface is one `TRIANGLES` primitive. The leg is [`GlbNode::Opaque`]: a material of its own
//! (skin, or the one its file had) and no `COLOR_0`, which viewers would paint over it. The
//! stocking surface is [`GlbNode::Sheer`]: a material of the yarn's
//! colour with `alphaMode` `BLEND`, and its opacity (the knit's coverage) as the alpha of an RGBA
//! `COLOR_0` whose RGB is white. glTF multiplies `COLOR_0` into the base colour, alpha included,
//! so core glTF alone draws it sheer: Blender's importer (4.5) wires the colour attribute's alpha
//! into the Principled BSDF's Alpha and renders the material `BLENDED`; three.js's `GLTFLoader`
//! turns on vertex colours, four-component ones multiply the alpha, and `BLEND` makes the
//! material transparent. Why this way: docs/decisions/0052.

use std::borrow::Cow;
use std::collections::BTreeMap;

use gltf_json as json;
use json::validation::{Checked::Valid, USize64};
use json::Index;

use crate::base::{Material, PerYarn, SurfaceMesh, YarnGeometry, YarnKind};
use crate::error::{Error, Result};
use crate::export::ply::{check_surface_mesh, check_yarn_geometry};

/// One root node of a GLB file.
pub enum GlbNode<'a> {
    /// A triangle surface without a material (a leg made for a test).
    Surface(&'a SurfaceMesh),
    /// An opaque triangle surface in `material` (the leg in `stocking.glb`). Its vertex colours
    /// are not written: glTF multiplies `COLOR_0` into the base colour, and most viewers apply
    /// it, so a heat map there would replace the skin.
    Opaque {
        /// The surface.
        mesh: &'a SurfaceMesh,
        /// Its material.
        material: &'a Material,
    },
    /// A see-through triangle surface (the stocking): as [`GlbNode::Surface`], with a material
    /// named after the mesh: base colour `colour` (linear RGB) with alpha 1, `alphaMode`
    /// `BLEND`, double-sided, metallic 0, roughness 0.6. Its opacity, the alpha of `COLOR_0`,
    /// is what makes it sheer; a mesh without one is drawn opaque in that colour.
    Sheer {
        /// The surface.
        mesh: &'a SurfaceMesh,
        /// Base colour, linear RGB 0–1.
        colour: [f64; 3],
    },
    /// Yarn polylines.
    Yarns(&'a YarnGeometry),
}

/// Encodes `parts` as one GLB of yarns only (the patch experiment).
///
/// One scene; a root node per part, named after it and translated by its `offset_m` (metres;
/// no translation when zero). Its mesh has a `LINES` primitive per yarn kind that has segments
/// (`u32` indices, material `nylon` / `support` with base colour `yarn_colours[kind.index()]`,
/// linear RGB, alpha 1, metallic 0, roughness 0.6). The primitives share `POSITION` (f32
/// metres, in the node's frame, with min/max) and one `_UPPERCASE` float scalar per point
/// attribute. A part without segments is a node without a mesh. The bytes depend only on the
/// arguments.
///
/// Fails with [`Error::Encode`] if a part is inconsistent (indices past the points, attributes
/// of the wrong length, non-finite positions).
pub fn write_glb(parts: &[YarnGeometry], yarn_colours: PerYarn<[f64; 3]>) -> Result<Vec<u8>> {
    let nodes: Vec<GlbNode> = parts.iter().map(GlbNode::Yarns).collect();
    write_nodes_glb(&nodes, yarn_colours)
}

/// Encodes surfaces and yarns as one GLB, a root node each, in the given order. Yarns are
/// written as by [`write_glb`]; a surface is one `TRIANGLES` primitive with `POSITION`,
/// `NORMAL`, `TEXCOORD_0` and `COLOR_0` where present (f32 `VEC3`, or `VEC4` with the opacity as
/// alpha; not for an [`GlbNode::Opaque`]), and its point attributes, no translation, and the
/// material of an opaque or sheer node (a surface without triangles is a node without a mesh,
/// and then no material either).
///
/// Fails with [`Error::Encode`] if a node's geometry is inconsistent, or a sheer colour is not
/// within 0–1.
pub fn write_nodes_glb(nodes: &[GlbNode], yarn_colours: PerYarn<[f64; 3]>) -> Result<Vec<u8>> {
    write_scenes_glb(&[("knitfit", nodes)], yarn_colours)
}

/// Encodes `scenes` (a name and its root nodes each, written as by [`write_nodes_glb`]) as one
/// GLB whose default scene (`"scene": 0`) is the first. Viewers draw the default scene only and
/// keep the others a click away: three.js's `GLTFLoader` puts them in `gltf.scenes`, not
/// `gltf.scene`; Blender 4.5's importer makes each a collection and excludes all but the
/// default from the view layer. That is how `stocking.glb` keeps its yarn lines without
/// drawing them over the stocking.
///
/// Fails as [`write_nodes_glb`] does.
pub fn write_scenes_glb(
    scenes: &[(&str, &[GlbNode])],
    yarn_colours: PerYarn<[f64; 3]>,
) -> Result<Vec<u8>> {
    let nodes: Vec<&GlbNode> = scenes.iter().flat_map(|(_, nodes)| nodes.iter()).collect();
    for node in &nodes {
        match node {
            GlbNode::Yarns(part) => check_yarn_geometry(part),
            GlbNode::Surface(mesh) => check_surface_mesh(mesh),
            GlbNode::Opaque { mesh, material } => check_surface_mesh(mesh)
                .and_then(|()| check_colour(&mesh.name, &material.base_colour))
                .and_then(|()| check_factors(&mesh.name, material)),
            GlbNode::Sheer { mesh, colour } => {
                check_surface_mesh(mesh).and_then(|()| check_colour(&mesh.name, colour))
            }
        }
        .map_err(|message| Error::Encode {
            what: "glTF".into(),
            message,
        })?;
    }
    let mut doc = GlbBuilder::default();
    // A material per yarn kind that some segment uses (an unused one is a validator notice).
    let materials = YarnKind::ALL.map(|kind| {
        let used = nodes.iter().any(|n| match n {
            GlbNode::Yarns(p) => p.segments.iter().any(|s| s.yarn == kind),
            GlbNode::Surface(_) | GlbNode::Opaque { .. } | GlbNode::Sheer { .. } => false,
        });
        used.then(|| {
            let [r, g, b] = yarn_colours[kind.index() as usize].map(|c| c as f32);
            doc.material(kind.name(), [r, g, b])
        })
    });
    let mut node_of = |node: &GlbNode| match node {
        GlbNode::Yarns(part) => doc.yarn_node(part, &materials),
        GlbNode::Surface(mesh) => doc.surface_node(mesh, None, true),
        GlbNode::Opaque { mesh, material } => {
            let material = (!mesh.triangles.is_empty()).then(|| doc.opaque_material(material));
            doc.surface_node(mesh, material, false)
        }
        GlbNode::Sheer { mesh, colour } => {
            let material = (!mesh.triangles.is_empty()).then(|| {
                let [r, g, b] = colour.map(|c| c as f32);
                doc.sheer_material(&mesh.name, [r, g, b])
            });
            doc.surface_node(mesh, material, true)
        }
    };
    let scenes: Vec<json::Scene> = scenes
        .iter()
        .map(|(name, nodes)| json::Scene {
            extensions: None,
            extras: Default::default(),
            name: Some(name.to_string()),
            nodes: nodes.iter().map(&mut node_of).collect(),
        })
        .collect();
    for (k, scene) in scenes.into_iter().enumerate() {
        let index = doc.root.push(scene);
        if k == 0 {
            doc.root.scene = Some(index);
        }
    }
    doc.finish()
}

/// An opaque material's metalness and roughness: each within 0–1 (a NaN is not).
fn check_factors(mesh: &str, material: &Material) -> std::result::Result<(), String> {
    let factors = [material.metallic, material.roughness];
    if factors.iter().all(|c| (0.0..=1.0).contains(c)) {
        Ok(())
    } else {
        Err(format!(
            "mesh {mesh:?}: material {:?} has metallic {} and roughness {}, not within 0–1",
            material.name, material.metallic, material.roughness
        ))
    }
}

/// A surface's colour: linear RGB, each channel within 0–1 (a NaN is not).
fn check_colour(mesh: &str, colour: &[f64; 3]) -> std::result::Result<(), String> {
    if colour.iter().all(|c| (0.0..=1.0).contains(c)) {
        Ok(())
    } else {
        Err(format!(
            "mesh {mesh:?}: colour {colour:?} is not linear RGB within 0–1"
        ))
    }
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

    /// `material` as a core-glTF opaque metallic-roughness material.
    pub fn opaque_material(&mut self, material: &Material) -> Index<json::Material> {
        let [r, g, b] = material.base_colour.map(|c| c as f32);
        self.root.push(json::Material {
            name: Some(material.name.clone()),
            pbr_metallic_roughness: json::material::PbrMetallicRoughness {
                base_color_factor: json::material::PbrBaseColorFactor([r, g, b, 1.0]),
                metallic_factor: json::material::StrengthFactor(material.metallic as f32),
                roughness_factor: json::material::StrengthFactor(material.roughness as f32),
                ..Default::default()
            },
            ..Default::default()
        })
    }

    /// [`GlbBuilder::material`] blended (`alphaMode` `BLEND`) and double-sided: a thin fabric
    /// whose opacity comes from `COLOR_0`'s alpha, seen from both sides (inside the welt, the far
    /// side of the tube where the leg does not hide it).
    pub fn sheer_material(&mut self, name: &str, rgb: [f32; 3]) -> Index<json::Material> {
        let index = self.material(name, rgb);
        let material = &mut self.root.materials[index.value()];
        material.alpha_mode = Valid(json::material::AlphaMode::Blend);
        material.double_sided = true;
        index
    }

    /// A node of yarn polylines: `LINES`, one primitive per yarn kind, shared vertex accessors.
    fn yarn_node(
        &mut self,
        part: &YarnGeometry,
        materials: &PerYarn<Option<Index<json::Material>>>,
    ) -> Index<json::Node> {
        let by_kind: Vec<(YarnKind, Vec<u32>)> = YarnKind::ALL
            .into_iter()
            .map(|kind| {
                let indices = part
                    .segments
                    .iter()
                    .filter(|s| s.yarn == kind)
                    .flat_map(|s| [s.a, s.b])
                    .collect();
                (kind, indices)
            })
            .filter(|(_, indices): &(_, Vec<u32>)| !indices.is_empty())
            .collect();
        // Accessors only when some primitive uses them: an unused one is a validator notice,
        // and an empty one an error.
        let mut primitives = Vec::new();
        if !by_kind.is_empty() {
            let mut attributes = custom_attributes(self, &part.point_attributes);
            attributes.insert(
                Valid(json::mesh::Semantic::Positions),
                self.positions(&part.positions),
            );
            for (kind, indices) in by_kind {
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
        }
        let [x, y, z] = part.offset_m.map(|c| c as f32);
        let translation = (part.offset_m != [0.0; 3]).then_some([x, y, z]);
        self.node(&part.name, primitives, translation)
    }

    /// A node of one `TRIANGLES` primitive with normals, optional texture coordinates and
    /// colours (RGBA with the opacity), the custom attributes, and `material`.
    fn surface_node(
        &mut self,
        mesh: &SurfaceMesh,
        material: Option<Index<json::Material>>,
        vertex_colours: bool,
    ) -> Index<json::Node> {
        use json::mesh::Semantic;
        if mesh.triangles.is_empty() {
            return self.node(&mesh.name, Vec::new(), None);
        }
        let mut attributes = custom_attributes(self, &mesh.point_attributes);
        attributes.insert(Valid(Semantic::Positions), self.positions(&mesh.positions));
        attributes.insert(Valid(Semantic::Normals), self.vectors(&mesh.normals));
        if let Some(uv) = &mesh.texcoords {
            attributes.insert(Valid(Semantic::TexCoords(0)), self.vectors(uv));
        }
        let colours = match (&mesh.colours, &mesh.opacity) {
            _ if !vertex_colours => None,
            (Some(rgb), None) => Some(self.vectors(rgb)),
            (Some(rgb), Some(alpha)) => {
                let rgba: Vec<[f32; 4]> = rgb
                    .iter()
                    .zip(alpha)
                    .map(|(&[r, g, b], &a)| [r, g, b, a])
                    .collect();
                Some(self.vectors(&rgba))
            }
            // `check_surface_mesh` refuses an opacity without colours.
            (None, _) => None,
        };
        if let Some(colours) = colours {
            attributes.insert(Valid(Semantic::Colors(0)), colours);
        }
        let indices: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
        let primitive = json::mesh::Primitive {
            attributes,
            extensions: None,
            extras: Default::default(),
            indices: Some(self.indices(&indices)),
            material,
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

    /// A float `VEC2`/`VEC3`/`VEC4` accessor (normals, colours, texture coordinates): no bounds.
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
        check_glb_length(json_bytes.len(), self.bin.len()).map_err(encode_error)?;
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

/// Refuses a GLB whose length would not fit its header's `u32`: gltf's writer casts the length
/// with `as u32`, so a file over 4 GiB (a fit of about 10⁸ points or more) would be written
/// with a wrapped length, unreadable.
fn check_glb_length(json_len: usize, bin_len: usize) -> std::result::Result<(), String> {
    // Header 12 bytes, two chunk headers of 8, each chunk padded to 4.
    let total = 12 + 8 + json_len.div_ceil(4) as u64 * 4 + 8 + bin_len.div_ceil(4) as u64 * 4;
    if total > u64::from(u32::MAX) {
        return Err(format!(
            "the file would be {total} bytes, over the 4 GiB a GLB can hold; write \"ply\" \
             instead, or fewer points (--resolution, \"stitches\" or \"loops\" left out)"
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_glb_over_4_gib_is_refused_not_written_with_a_wrapped_length() {
        assert!(check_glb_length(1000, 1 << 20).is_ok());
        let err = check_glb_length(1000, u32::MAX as usize).unwrap_err();
        assert!(err.contains("over the 4 GiB a GLB can hold"), "{err}");
    }

    use crate::base::yarn::sample_geometry as part;

    const COLOURS: PerYarn<[f64; 3]> = [[0.5, 0.25, 0.125], [0.2, 0.4, 0.6], [0.1, 0.1, 0.1]];

    /// The values of a float accessor (custom attributes, which the reader has no method for).
    fn floats<T: gltf::accessor::Item>(
        accessor: gltf::Accessor,
        buffers: &[gltf::buffer::Data],
    ) -> Vec<T> {
        gltf::accessor::Iter::<T>::new(accessor, |b| Some(&buffers[b.index()]))
            .unwrap()
            .collect()
    }

    fn attribute<'a>(prim: &gltf::Primitive<'a>, name: &str) -> gltf::Accessor<'a> {
        prim.attributes()
            .find(|(s, _)| *s == gltf::Semantic::Extras(name.into()))
            .unwrap_or_else(|| panic!("_{name} is written"))
            .1
    }

    #[test]
    fn round_trips_through_the_gltf_reader() {
        let bytes = write_glb(&[part("a", 0.0), part("b", 0.5)], COLOURS).unwrap();
        let (doc, buffers, _) = gltf::import_slice(&bytes).unwrap();
        assert_eq!(
            doc.as_json().asset.generator.as_deref(),
            Some(concat!("knitfit ", env!("CARGO_PKG_VERSION")))
        );
        assert_eq!(doc.scenes().count(), 1);
        let roots: Vec<_> = doc.default_scene().unwrap().nodes().collect();
        let names: Vec<_> = roots.iter().map(|n| n.name().unwrap()).collect();
        assert_eq!(names, ["a", "b"]);
        assert_eq!(roots[0].transform().decomposed().0, [0.0, 0.0, 0.0]);
        assert_eq!(roots[1].transform().decomposed().0, [0.5, 0.0, 0.0]);

        let prims: Vec<_> = roots[1].mesh().unwrap().primitives().collect();
        assert_eq!(prims.len(), 2, "one primitive per yarn kind");
        let expected = [("nylon", [0, 1]), ("support", [0, 2])];
        for (prim, (material, indices)) in prims.iter().zip(expected) {
            assert_eq!(prim.mode(), gltf::mesh::Mode::Lines);
            assert_eq!(prim.material().name(), Some(material));
            let reader = prim.reader(|b| Some(&buffers[b.index()]));
            let read: Vec<u32> = reader.read_indices().unwrap().into_u32().collect();
            assert_eq!(read, indices);
        }
        let reader = prims[1].reader(|b| Some(&buffers[b.index()]));
        let positions: Vec<_> = reader.read_positions().unwrap().collect();
        assert_eq!(
            positions,
            [[0.0, 0.0, 0.0], [0.001, 0.0, 0.0], [0.0, 0.002, 0.0]],
            "positions are in the node's frame, without the offset"
        );
        let position = prims[1].get(&gltf::Semantic::Positions).unwrap();
        assert_eq!(position.min(), Some(serde_json::json!([0.0, 0.0, 0.0])));
        // Bounds are the f32 values stored, widened exactly to f64.
        let max = [0.001f32, 0.002, 0.0].map(f64::from);
        assert_eq!(position.max(), Some(serde_json::json!(max)));
        assert_eq!(
            floats::<f32>(attribute(&prims[1], "COURSE"), &buffers),
            [0.0, 0.0, 1.0]
        );
        assert_eq!(
            floats::<f32>(attribute(&prims[1], "WALE"), &buffers),
            [0.0, 1.0, 0.0]
        );
        assert_eq!(
            floats::<f32>(attribute(&prims[0], "YARN_KIND"), &buffers),
            [0.0, 0.0, 1.0]
        );
        assert_eq!(
            attribute(&prims[0], "COURSE").index(),
            attribute(&prims[1], "COURSE").index(),
            "primitives share their vertex accessors"
        );
    }

    #[test]
    fn materials_carry_the_yarn_colours() {
        let bytes = write_glb(&[part("a", 0.0)], COLOURS).unwrap();
        let (doc, _, _) = gltf::import_slice(&bytes).unwrap();
        let support = doc.materials().nth(1).unwrap();
        assert_eq!(support.name(), Some("support"));
        let pbr = support.pbr_metallic_roughness();
        assert_eq!(pbr.base_color_factor(), [0.2, 0.4, 0.6, 1.0]);
        assert_eq!((pbr.metallic_factor(), pbr.roughness_factor()), (0.0, 0.6));
    }

    /// A triangle with white vertex colours and `coverage` as their opacity, as the stocking
    /// surface has them.
    fn sheer_triangle(coverage: [f32; 3]) -> SurfaceMesh {
        let mut mesh = SurfaceMesh::new(
            "stocking",
            vec![[0.0, 0.0, 0.0], [0.01, 0.0, 0.0], [0.0, 0.01, 0.0]],
            vec![[0, 1, 2]],
        );
        mesh.colours = Some(vec![[1.0; 3]; 3]);
        mesh.opacity = Some(coverage.to_vec());
        mesh.point_attributes
            .insert("coverage".into(), coverage.to_vec());
        mesh
    }

    #[test]
    fn the_stocking_surface_is_blended_in_the_yarn_colour_with_coverage_as_alpha() {
        let mut leg = sheer_triangle([0.0; 3]);
        leg.name = "leg".into();
        leg.opacity = None;
        leg.colours = Some(vec![[0.5, 0.25, 0.0]; 3]);
        let stocking = sheer_triangle([0.2, 0.35, 1.0]);
        let nodes = [
            GlbNode::Surface(&leg),
            GlbNode::Sheer {
                mesh: &stocking,
                colour: [0.16, 0.11, 0.09],
            },
        ];
        let bytes = write_nodes_glb(&nodes, COLOURS).unwrap();
        let (doc, buffers, _) = gltf::import_slice(&bytes).unwrap();
        let prim = |node: usize| {
            let node = doc.nodes().nth(node).unwrap();
            node.mesh().unwrap().primitives().next().unwrap()
        };

        let sheer = prim(1);
        let material = sheer.material();
        assert_eq!(material.name(), Some("stocking"));
        assert_eq!(material.alpha_mode(), gltf::material::AlphaMode::Blend);
        assert!(material.double_sided());
        let pbr = material.pbr_metallic_roughness();
        assert_eq!(pbr.base_color_factor(), [0.16, 0.11, 0.09, 1.0]);
        assert_eq!((pbr.metallic_factor(), pbr.roughness_factor()), (0.0, 0.6));
        let reader = sheer.reader(|b| Some(&buffers[b.index()]));
        let Some(gltf::mesh::util::ReadColors::RgbaF32(colours)) = reader.read_colors(0) else {
            panic!("COLOR_0 is RGBA float");
        };
        let colours: Vec<[f32; 4]> = colours.collect();
        assert_eq!(
            colours,
            [[1.0, 1.0, 1.0, 0.2], [1.0, 1.0, 1.0, 0.35], [1.0; 4]],
            "white, so base colour × COLOR_0 is the yarn's colour; alpha the coverage"
        );
        assert_eq!(
            floats::<f32>(attribute(&sheer, "COVERAGE"), &buffers),
            [0.2, 0.35, 1.0],
            "_COVERAGE stays"
        );

        // The leg keeps its look: no material, RGB colours.
        let leg = prim(0);
        assert!(leg.material().index().is_none());
        let reader = leg.reader(|b| Some(&buffers[b.index()]));
        assert!(matches!(
            reader.read_colors(0),
            Some(gltf::mesh::util::ReadColors::RgbF32(_))
        ));
        assert_eq!(doc.materials().count(), 1);
    }

    #[test]
    fn a_sheer_surface_without_triangles_has_no_material() {
        let mut bare = sheer_triangle([0.5; 3]);
        bare.triangles.clear();
        let nodes = [GlbNode::Sheer {
            mesh: &bare,
            colour: [0.5; 3],
        }];
        let (doc, _, _) = gltf::import_slice(write_nodes_glb(&nodes, COLOURS).unwrap()).unwrap();
        assert!(doc.nodes().next().unwrap().mesh().is_none());
        assert_eq!(
            doc.materials().count(),
            0,
            "an unused material is a validator notice"
        );
    }

    #[test]
    fn a_sheer_colour_outside_0_to_1_is_an_error() {
        let mesh = sheer_triangle([0.5; 3]);
        for colour in [[1.5, 0.0, 0.0], [f64::NAN, 0.0, 0.0]] {
            let nodes = [GlbNode::Sheer {
                mesh: &mesh,
                colour,
            }];
            let err = write_nodes_glb(&nodes, COLOURS).unwrap_err();
            assert!(err.to_string().contains("within 0–1"), "{err}");
        }
    }

    #[test]
    fn only_used_yarn_kinds_get_a_material() {
        let mut nylon_only = part("a", 0.0);
        nylon_only.segments.retain(|s| s.yarn == YarnKind::Nylon);
        let bytes = write_glb(&[nylon_only], COLOURS).unwrap();
        let (doc, _, _) = gltf::import_slice(&bytes).unwrap();
        let names: Vec<_> = doc.materials().map(|m| m.name().unwrap()).collect();
        assert_eq!(names, ["nylon"]);
    }

    #[test]
    fn part_without_segments_is_a_node_without_accessors() {
        let mut bare = part("bare", 0.1);
        bare.segments.clear();
        let bytes = write_glb(&[bare], COLOURS).unwrap();
        let (doc, _, _) = gltf::import_slice(&bytes).unwrap();
        let node = doc.nodes().next().unwrap();
        assert_eq!(node.name(), Some("bare"));
        assert!(node.mesh().is_none());
        assert_eq!(doc.accessors().count(), 0);
        assert_eq!(doc.buffers().count(), 0);
    }

    #[test]
    fn non_finite_position_is_an_error() {
        let mut a = part("a", 0.0);
        a.positions[1][0] = f64::NAN;
        let err = write_glb(&[a], COLOURS).unwrap_err();
        assert!(matches!(err, Error::Encode { .. }), "{err}");
    }

    #[test]
    fn segment_past_the_last_point_is_an_error() {
        let mut a = part("a", 0.0);
        a.segments[0].b = 3;
        let err = write_glb(&[a], COLOURS).unwrap_err();
        assert!(matches!(err, Error::Encode { .. }), "{err}");
    }

    #[test]
    fn is_deterministic() {
        let parts = [part("a", 0.0), part("b", 0.5)];
        assert_eq!(
            write_glb(&parts, COLOURS).unwrap(),
            write_glb(&parts, COLOURS).unwrap()
        );
    }
}
