//! The yarn vocabulary every stage shares: the yarn kinds (two knitted, and the toe seam), the two directions a yarn runs in
//! the knit, and [`YarnGeometry`], the one list of yarn points and segments that the
//! penetration fix, the writers and the renderers take.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

/// A yarn of the stocking. Indexes per-yarn arrays: nylon, support, then the toe seam.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum YarnKind {
    /// Plain nylon yarn (paper: c1 = 1).
    Nylon,
    /// Support yarn: polyurethane core wrapped in nylon, stiffer and more elastic (paper: c1 = 10).
    Support,
    /// The toe seam: the thread that links the last course's loops across the toe. It has the
    /// support yarn's material (a seam is sewn to be the strongest line of the stocking; a
    /// weaker one would let the wales pull the toe back between the toes); it is a kind of its
    /// own so that exports and pictures can show where the seam runs.
    Seam,
}

impl YarnKind {
    /// Every kind, in index order.
    pub const ALL: [YarnKind; 3] = [YarnKind::Nylon, YarnKind::Support, YarnKind::Seam];
    /// The kinds a pattern knits with (each has its own material in the scene's `yarns`).
    pub const KNITTED: [YarnKind; 2] = [YarnKind::Nylon, YarnKind::Support];

    /// 0 for nylon, 1 for support, 2 for the toe seam: the value written to `yarn_kind` /
    /// `_YARN_KIND` attributes.
    pub fn index(self) -> u8 {
        match self {
            YarnKind::Nylon => 0,
            YarnKind::Support => 1,
            YarnKind::Seam => 2,
        }
    }

    /// Lower-case name, as in scene files and glTF material names.
    pub fn name(self) -> &'static str {
        match self {
            YarnKind::Nylon => "nylon",
            YarnKind::Support => "support",
            YarnKind::Seam => "seam",
        }
    }

    /// The knitted kind whose material this yarn has: itself, or support for the seam.
    pub fn material(self) -> YarnKind {
        match self {
            YarnKind::Seam => YarnKind::Support,
            kind => kind,
        }
    }
}

/// One value per yarn kind, indexed by [`YarnKind::index`].
pub type PerYarn<T> = [T; 3];

/// Direction of a spring in the knit grid.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Direction {
    /// Along a course (row): joins wale `w` to wale `w + 1`. The yarn is continuous this way.
    Course,
    /// Along a wale (column): joins course `c` to course `c + 1`.
    Wale,
}

impl Direction {
    /// 0 for course, 1 for wale: the index of per-direction arrays.
    pub fn index(self) -> usize {
        match self {
            Direction::Course => 0,
            Direction::Wale => 1,
        }
    }
}

/// A value per knit direction: along the course (around the leg) and along the wale. Indexed
/// by [`Direction`]; reads as `{"course": …, "wale": …}` in reports.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PerDirection<T = f64> {
    /// Along the course.
    pub course: T,
    /// Along the wale.
    pub wale: T,
}

impl<T> PerDirection<T> {
    /// `course` along the course, `wale` along the wale.
    pub const fn new(course: T, wale: T) -> PerDirection<T> {
        PerDirection { course, wale }
    }

    /// The two values in [`Direction::index`] order, for kernels that index by direction.
    pub fn to_array(self) -> [T; 2] {
        [self.course, self.wale]
    }

    /// `f` of each direction's value.
    pub fn map<U>(self, mut f: impl FnMut(T) -> U) -> PerDirection<U> {
        PerDirection {
            course: f(self.course),
            wale: f(self.wale),
        }
    }
}

impl<T> From<[T; 2]> for PerDirection<T> {
    /// `[course, wale]`, in [`Direction::index`] order.
    fn from([course, wale]: [T; 2]) -> PerDirection<T> {
        PerDirection { course, wale }
    }
}

impl<T> std::ops::Index<Direction> for PerDirection<T> {
    type Output = T;
    fn index(&self, direction: Direction) -> &T {
        match direction {
            Direction::Course => &self.course,
            Direction::Wale => &self.wale,
        }
    }
}

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
