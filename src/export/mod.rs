//! Writers for the files a run produces. One [`YarnGeometry`] feeds every format, so PLY and glTF
//! carry the same points, segments and attributes.
//!
//! Every writer returns bytes; [`atomic::write_all`] puts them on disk (temporary name, then
//! rename), so a failed run leaves nothing half-written.

pub mod atomic;
pub mod gltf;
pub mod ply;

use std::collections::BTreeMap;

use crate::knit::{Direction, Knit, YarnKind};

/// Yarn points, the segments between them and per-point attributes, ready to write.
///
/// Positions are in metres, glTF convention (Y up). Attribute names are written as-is to PLY
/// (`course`) and upper-cased with a `_` prefix to glTF (`_COURSE`). A `BTreeMap` keeps the
/// order, and so the bytes, deterministic.
#[derive(Clone, Debug, PartialEq)]
pub struct YarnGeometry {
    /// Name of this part (a glTF node name, a PLY comment).
    pub name: String,
    /// Where the part is placed for viewing, metres: a glTF node translation; added to the PLY
    /// positions (and said so in the PLY header), as PLY has no transforms.
    pub offset_m: [f64; 3],
    /// Point positions, metres.
    pub positions: Vec<[f64; 3]>,
    /// Per-point attributes, one value per position: `course`, `wale`, `class`, `yarn_kind`, ….
    pub point_attributes: BTreeMap<String, Vec<f32>>,
    /// Yarn segments (springs).
    pub segments: Vec<Segment>,
}

/// A triangle surface to write: the leg, or the fitted stocking as a surface.
///
/// Positions in metres, Y up; triangles counter-clockwise seen from outside. Point attributes
/// follow the same naming rule as [`YarnGeometry`].
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
            point_attributes: BTreeMap::new(),
        }
    }
}

/// Area-weighted vertex normals; a vertex on no triangle (or on only degenerate ones) gets +Y, so
/// every normal is a unit vector as glTF requires. A triangle with an index past the last
/// position is skipped: the writers refuse such a mesh with a message, rather than panic here.
pub fn vertex_normals(positions: &[[f64; 3]], triangles: &[[u32; 3]]) -> Vec<[f32; 3]> {
    use nalgebra::Vector3;
    let mut sum = vec![Vector3::<f64>::zeros(); positions.len()];
    for t in triangles {
        if t.iter().any(|&i| i as usize >= positions.len()) {
            continue;
        }
        let [a, b, c] = t.map(|i| Vector3::from(positions[i as usize]));
        let n = (b - a).cross(&(c - a));
        for &i in t {
            sum[i as usize] += n;
        }
    }
    sum.iter()
        .map(|n| {
            let len = n.norm();
            if len > 0.0 && len.is_finite() {
                let u = n / len;
                [u.x as f32, u.y as f32, u.z as f32]
            } else {
                [0.0, 1.0, 0.0]
            }
        })
        .collect()
}

/// One yarn segment between two points of a [`YarnGeometry`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Segment {
    /// Index of the first point.
    pub a: u32,
    /// Index of the second point.
    pub b: u32,
    /// The yarn this segment belongs to.
    pub yarn: YarnKind,
    /// Along the course or along the wale.
    pub direction: Direction,
}

impl YarnGeometry {
    /// The yarn geometry of a knit: every point with its `course`, `wale`, `class` and
    /// `yarn_kind` (the yarn of its course), every spring as a segment.
    pub fn from_knit(name: &str, knit: &Knit, offset_m: [f64; 3]) -> YarnGeometry {
        let n = knit.len();
        let mut course = Vec::with_capacity(n);
        let mut wale = Vec::with_capacity(n);
        for i in 0..n {
            let (w, c) = knit.grid_coords(crate::knit::PointId(i as u32));
            course.push(c as f32);
            wale.push(w as f32);
        }
        let mut point_attributes = BTreeMap::new();
        point_attributes.insert("course".to_string(), course);
        point_attributes.insert("wale".to_string(), wale);
        point_attributes.insert(
            "class".to_string(),
            knit.class.iter().map(|&c| c as f32).collect(),
        );
        point_attributes.insert(
            "yarn_kind".to_string(),
            knit.course_yarn.iter().map(|k| k.index() as f32).collect(),
        );
        YarnGeometry {
            name: name.to_string(),
            offset_m,
            positions: knit.particles.x.iter().map(|p| [p.x, p.y, p.z]).collect(),
            point_attributes,
            segments: knit
                .springs
                .iter()
                .map(|s| Segment {
                    a: s.a.0,
                    b: s.b.0,
                    yarn: s.yarn,
                    direction: s.direction,
                })
                .collect(),
        }
    }
}

/// A three-point, two-segment geometry (one nylon course segment, one support wale segment)
/// with `course`, `wale` and `yarn_kind` attributes, for the writers' tests.
#[cfg(test)]
pub(crate) fn sample_geometry(name: &str, offset_x: f64) -> YarnGeometry {
    let mut point_attributes = BTreeMap::new();
    point_attributes.insert("course".to_string(), vec![0.0, 0.0, 1.0]);
    point_attributes.insert("wale".to_string(), vec![0.0, 1.0, 0.0]);
    point_attributes.insert("yarn_kind".to_string(), vec![0.0, 0.0, 1.0]);
    YarnGeometry {
        name: name.into(),
        offset_m: [offset_x, 0.0, 0.0],
        positions: vec![[0.0, 0.0, 0.0], [0.001, 0.0, 0.0], [0.0, 0.002, 0.0]],
        point_attributes,
        segments: vec![
            Segment {
                a: 0,
                b: 1,
                yarn: YarnKind::Nylon,
                direction: Direction::Course,
            },
            Segment {
                a: 0,
                b: 2,
                yarn: YarnKind::Support,
                direction: Direction::Wale,
            },
        ],
    }
}
