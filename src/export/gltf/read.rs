//! Reading a fit's `stocking.glb` back for `knitfit render`: the node `leg` (triangles, normals,
//! `_COVERAGE`, `_STITCH_DENSITY`) and the node `yarns` (`LINES`), each in world space (the node
//! transforms of the default scene applied).
//!
//! A segment's yarn kind is that of its primitive's material (`nylon` / `support`, one primitive
//! per kind as `export::gltf` writes them); without a known material name, the `_YARN_KIND`
//! attribute of the segment's first point (the yarn of its course) is used. The GLB does not
//! say whether a segment runs along the course or the wale; every segment read back is marked
//! `Course`, which the renderer never looks at.

use std::collections::BTreeMap;
use std::path::Path;

use nalgebra::{Matrix3, Matrix4, Point3, Vector3};

use crate::base::{vertex_normals, Direction, Segment, SurfaceMesh, YarnGeometry, YarnKind};
use crate::error::{Error, Result};
use crate::leg::load::MAX_COORDINATE_M;
use crate::leg::load::{check_accessor_types, check_position_accessors};

/// The leg and yarns of a `stocking.glb`, world space, metres.
#[derive(Clone, Debug)]
pub struct StockingGlb {
    /// The leg, with the `coverage` and `stitch_density` attributes the file has.
    pub leg: SurfaceMesh,
    /// The yarn polylines.
    pub yarns: YarnGeometry,
}

/// Reads `path`. Errors ([`Error::Read`], [`Error::RenderInput`]) name the file: missing,
/// not glTF, no `leg` node with triangles, no `yarns` node with lines, a vertex of the leg's
/// triangles or of the yarns' segments further than [`MAX_COORDINATE_M`] from the origin on an
/// axis (world space; the bound `knitfit fit` puts on the leg it reads, so no fit writes one:
/// such a point is damage, and one flipped exponent bit puts a yarn point at 1e37 m).
pub fn read_stocking_glb(path: &Path) -> Result<StockingGlb> {
    let bad = |message: String| Error::RenderInput {
        path: path.to_path_buf(),
        message,
    };
    let bytes = std::fs::read(path).map_err(|source| Error::Read {
        path: path.to_path_buf(),
        source,
    })?;
    let not_gltf = |e: gltf::Error| {
        bad(format!(
            "not a glTF file ({e}); give the stocking.glb a `knitfit fit` wrote, or its directory"
        ))
    };
    // gltf's validation panics on a POSITION naming an accessor past the last (found by fuzz
    // shard 4): checked first, as the leg loader does.
    let unchecked = gltf::Gltf::from_slice_without_validation(&bytes).map_err(not_gltf)?;
    check_position_accessors(unchecked.document.as_json()).map_err(bad)?;
    let (doc, buffers, _) = gltf::import(path).map_err(not_gltf)?;
    // Every scene's nodes, the default scene's first: `knitfit fit` keeps the yarns in a scene
    // of their own. Each node is taken once, so a damaged file's cycle cannot loop.
    let default = doc.default_scene().map(|s| s.index());
    let mut scenes: Vec<gltf::Scene> = doc.scenes().collect();
    scenes.sort_by_key(|s| Some(s.index()) != default);
    if scenes.is_empty() {
        return Err(bad("the glTF file has no scene".into()));
    }
    let mut found: BTreeMap<String, (gltf::Node, Matrix4<f64>)> = BTreeMap::new();
    let mut seen = vec![false; doc.nodes().len()];
    let mut stack: Vec<(gltf::Node, Matrix4<f64>)> = scenes
        .iter()
        .rev()
        .flat_map(|scene| scene.nodes().collect::<Vec<_>>().into_iter().rev())
        .map(|n| (n, Matrix4::identity()))
        .collect();
    while let Some((node, parent)) = stack.pop() {
        if std::mem::replace(&mut seen[node.index()], true) {
            continue;
        }
        let local = Matrix4::from(node.transform().matrix()).cast::<f64>();
        let world = parent * local;
        if let Some(name) = node.name() {
            found
                .entry(name.to_string())
                .or_insert((node.clone(), world));
        }
        stack.extend(node.children().map(|c| (c, world)));
    }
    let missing = |name: &str| {
        bad(format!(
            "no node named {name:?} (a `knitfit fit` stocking.glb has nodes \"leg\" and \"yarns\")"
        ))
    };
    let (leg_node, leg_world) = found.get("leg").ok_or_else(|| missing("leg"))?;
    let (yarn_node, yarn_world) = found.get("yarns").ok_or_else(|| missing("yarns"))?;
    let get = |b: gltf::Buffer| buffers.get(b.index()).map(|d| &d.0[..]);

    let normal_from = |m: &Matrix4<f64>| -> Matrix3<f64> {
        let upper = m.fixed_view::<3, 3>(0, 0).into_owned();
        upper.try_inverse().map(|i| i.transpose()).unwrap_or(upper)
    };
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    let mut normals: Vec<[f32; 3]> = Vec::new();
    let mut has_normals = true;
    let mut attributes: BTreeMap<String, Vec<f32>> = BTreeMap::new();
    let names = ["coverage", "stitch_density"];
    let nm = normal_from(leg_world);
    for prim in leg_node.mesh().iter().flat_map(|m| m.primitives()) {
        if prim.mode() != gltf::mesh::Mode::Triangles {
            continue;
        }
        // gltf's readers take the accessors' types on trust (float indices panic): checked.
        check_accessor_types(&prim)
            .map_err(|e| bad(format!("node \"leg\" primitive {}: {e}", prim.index())))?;
        let normals_ok = prim.get(&gltf::Semantic::Normals).is_none_or(|a| {
            (a.data_type(), a.dimensions())
                == (
                    gltf::accessor::DataType::F32,
                    gltf::accessor::Dimensions::Vec3,
                )
        });
        let reader = prim.reader(get);
        let Some(p) = reader.read_positions() else {
            continue;
        };
        let p: Vec<[f64; 3]> = p
            .map(|q| {
                let w = leg_world.transform_point(&Point3::from(q).cast::<f64>());
                [w.x, w.y, w.z]
            })
            .collect();
        // Indices are u32: with the vertices read so far they must fit (then neither the
        // casts nor `base + i` wrap).
        if positions.len() + p.len() > u32::MAX as usize {
            return Err(bad(
                "node \"leg\" has more vertices than 32-bit indices can reach".into(),
            ));
        }
        let (base, count) = (positions.len() as u32, p.len() as u32);
        match reader.read_indices() {
            Some(ix) => {
                let ix: Vec<u32> = ix.into_u32().collect();
                for t in ix.chunks_exact(3) {
                    if t.iter().all(|&i| i < count) {
                        triangles.push([t[0] + base, t[1] + base, t[2] + base]);
                    }
                }
            }
            None => {
                for i in (0..count.saturating_sub(2)).step_by(3) {
                    triangles.push([base + i, base + i + 1, base + i + 2]);
                }
            }
        }
        match reader.read_normals().filter(|_| normals_ok) {
            Some(n) => normals.extend(n.map(|v| {
                let w = nm * Vector3::from(v).cast::<f64>();
                let w = w.try_normalize(1e-12).unwrap_or(Vector3::y());
                [w.x as f32, w.y as f32, w.z as f32]
            })),
            None => has_normals = false,
        }
        for name in names {
            let semantic = gltf::Semantic::Extras(name.to_uppercase());
            let values: Vec<f32> = prim
                .get(&semantic)
                .and_then(|acc| gltf::accessor::Iter::<f32>::new(acc, get))
                .map(|it| it.collect())
                .unwrap_or_default();
            let column = attributes.entry(name.to_string()).or_default();
            column.resize(base as usize, 0.0);
            if values.len() == p.len() {
                column.extend(values);
            }
        }
        positions.extend(p);
    }
    if triangles.is_empty() {
        return Err(bad("node \"leg\" has no triangles".into()));
    }
    if let Some(message) = far_vertex("leg", &positions, triangles.iter().flatten().copied()) {
        return Err(bad(message));
    }
    let mut leg = SurfaceMesh::new("leg", positions, triangles);
    if has_normals && normals.len() == leg.positions.len() {
        leg.normals = normals;
    } else {
        leg.normals = vertex_normals(&leg.positions, &leg.triangles);
    }
    leg.point_attributes = attributes
        .into_iter()
        .filter(|(_, v)| v.len() == leg.positions.len())
        .collect();

    let mut yarn_positions = Vec::new();
    let mut segments = Vec::new();
    for prim in yarn_node.mesh().iter().flat_map(|m| m.primitives()) {
        if prim.mode() != gltf::mesh::Mode::Lines {
            continue;
        }
        check_accessor_types(&prim)
            .map_err(|e| bad(format!("node \"yarns\" primitive {}: {e}", prim.index())))?;
        let reader = prim.reader(get);
        let Some(p) = reader.read_positions() else {
            continue;
        };
        let base = yarn_positions.len();
        yarn_positions.extend(p.map(|q| {
            let w = yarn_world.transform_point(&Point3::from(q).cast::<f64>());
            [w.x, w.y, w.z]
        }));
        // Indices are u32 (see the leg's primitives above).
        if yarn_positions.len() > u32::MAX as usize {
            return Err(bad(
                "node \"yarns\" has more vertices than 32-bit indices can reach".into(),
            ));
        }
        let (base, count) = (base as u32, (yarn_positions.len() - base) as u32);
        let by_material = prim
            .material()
            .name()
            .and_then(|n| YarnKind::ALL.into_iter().find(|k| k.name() == n));
        let kinds: Vec<f32> = prim
            .get(&gltf::Semantic::Extras("YARN_KIND".into()))
            .and_then(|acc| gltf::accessor::Iter::<f32>::new(acc, get))
            .map(|it| it.collect())
            .unwrap_or_default();
        let kind_of = |i: u32| {
            by_material.unwrap_or_else(|| match kinds.get(i as usize) {
                Some(k) if *k >= 0.5 => YarnKind::Support,
                _ => YarnKind::Nylon,
            })
        };
        let ix: Vec<u32> = match reader.read_indices() {
            Some(ix) => ix.into_u32().collect(),
            None => (0..count).collect(),
        };
        for pair in ix.chunks_exact(2) {
            if pair.iter().all(|&i| i < count) {
                segments.push(Segment {
                    a: base + pair[0],
                    b: base + pair[1],
                    yarn: kind_of(pair[0]),
                    direction: Direction::Course,
                });
            }
        }
    }
    if segments.is_empty() {
        return Err(bad("node \"yarns\" has no line segments".into()));
    }
    let ends = segments.iter().flat_map(|s| [s.a, s.b]);
    if let Some(message) = far_vertex("yarns", &yarn_positions, ends) {
        return Err(bad(message));
    }
    let yarns = YarnGeometry {
        name: "yarns".into(),
        offset_m: [0.0; 3],
        positions: yarn_positions,
        point_attributes: BTreeMap::new(),
        segments,
    };
    Ok(StockingGlb { leg, yarns })
}

/// The refusal for the first of `used` (indices into `positions`, world space, metres) further
/// than [`MAX_COORDINATE_M`] from the origin on an axis; `None` when every one is within it.
/// Every index in `used` is in range (checked where triangles and segments are kept).
/// Points that are not finite pass here: the renderer leaves them out.
fn far_vertex(
    node: &str,
    positions: &[[f64; 3]],
    used: impl IntoIterator<Item = u32>,
) -> Option<String> {
    let (i, p) = used
        .into_iter()
        .map(|i| (i, positions[i as usize]))
        .find(|(_, p)| {
            p.iter()
                .any(|c| c.is_finite() && c.abs() > MAX_COORDINATE_M)
        })?;
    Some(format!(
        "node {node:?}: vertex {i} is at ({:e}, {:e}, {:e}) m, beyond the ±{MAX_COORDINATE_M} m \
         knitfit accepts on any axis; the file is damaged: give the stocking.glb a `knitfit \
         fit` wrote",
        p[0], p[1], p[2]
    ))
}
