//! Triangle surfaces as the writers and the preview take them: the leg, and the fitted stocking
//! as a surface.

use std::collections::BTreeMap;

use super::Vec3;

/// An opaque surface's look, as core glTF's metallic-roughness material gives it: what the leg
/// is drawn in. Colours are linear RGB 0–1.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// The material's name.
    pub name: String,
    /// Base colour, linear RGB 0–1.
    pub base_colour: [f64; 3],
    /// Metalness 0–1.
    pub metallic: f64,
    /// Roughness 0–1.
    pub roughness: f64,
}

impl Material {
    /// Skin in daylight, neutral enough to show a stocking over it: linear RGB (0.64, 0.42,
    /// 0.33), sRGB about (209, 172, 154) — a light skin tone, as a reference rather than a
    /// portrait; dielectric, roughness 0.5 (skin's sheen, not a mirror).
    pub fn skin() -> Material {
        Material {
            name: "skin".into(),
            base_colour: [0.64, 0.42, 0.33],
            metallic: 0.0,
            roughness: 0.5,
        }
    }
}

/// A triangle surface to write: the leg, or the fitted stocking as a surface.
///
/// Positions in metres, Y up; triangles counter-clockwise seen from outside. Point attributes
/// follow the same naming rule as [`YarnGeometry`](super::YarnGeometry).
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceMesh {
    /// Node and mesh name.
    pub name: String,
    /// Vertex positions, metres.
    pub positions: Vec<[f64; 3]>,
    /// Triangles as vertex indices.
    pub triangles: Vec<[u32; 3]>,
    /// Unit vertex normals.
    pub normals: Vec<[f32; 3]>,
    /// Texture coordinates (`TEXCOORD_0`), if any.
    pub texcoords: Option<Vec<[f32; 2]>>,
    /// Linear-RGB vertex colours 0–1 (`COLOR_0`), if any.
    pub colours: Option<Vec<[f32; 3]>>,
    /// Per-vertex opacity 0–1, the alpha of the vertex colours (`COLOR_0` as RGBA; PLY
    /// `alpha`), if any; only with `colours`. Drawn only by a material that blends (glTF
    /// `alphaMode` `BLEND`): the stocking surface's.
    pub opacity: Option<Vec<f32>>,
    /// Per-vertex attributes, one value per position.
    pub point_attributes: BTreeMap<String, Vec<f32>>,
}

impl SurfaceMesh {
    /// A surface with area-weighted vertex normals and no attributes yet.
    pub fn new(name: &str, positions: Vec<[f64; 3]>, triangles: Vec<[u32; 3]>) -> SurfaceMesh {
        let normals = vertex_normals(&positions, &triangles);
        SurfaceMesh {
            name: name.to_string(),
            positions,
            triangles,
            normals,
            texcoords: None,
            colours: None,
            opacity: None,
            point_attributes: BTreeMap::new(),
        }
    }
}

/// Area-weighted vertex normals; a vertex on no triangle (or on only degenerate ones) gets +Y, so
/// every normal is a unit vector as glTF requires. A triangle with an index past the last
/// position is skipped: the writers refuse such a mesh with a message, rather than panic here.
pub fn vertex_normals(positions: &[[f64; 3]], triangles: &[[u32; 3]]) -> Vec<[f32; 3]> {
    let positions: Vec<Vec3> = positions.iter().map(|&p| Vec3::from(p)).collect();
    area_weighted_normals(&positions, triangles)
        .into_iter()
        .map(|n| n.map_or([0.0, 1.0, 0.0], |u| [u.x as f32, u.y as f32, u.z as f32]))
        .collect()
}

/// Unit area-weighted vertex normals, `None` for a vertex on no triangle or on only degenerate
/// ones; a triangle with an index past the last position is skipped.
pub fn area_weighted_normals(positions: &[Vec3], triangles: &[[u32; 3]]) -> Vec<Option<Vec3>> {
    let mut sum = vec![Vec3::zeros(); positions.len()];
    for t in triangles {
        if t.iter().any(|&i| i as usize >= positions.len()) {
            continue;
        }
        let [a, b, c] = t.map(|i| positions[i as usize]);
        let n = (b - a).cross(&(c - a));
        for &i in t {
            sum[i as usize] += n;
        }
    }
    sum.iter()
        .map(|n| {
            let len = n.norm();
            (len > 0.0 && len.is_finite()).then(|| n / len)
        })
        .collect()
}
