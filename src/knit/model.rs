//! The knit as a mass-spring system (Sakaguchi & Miyata §4, Fig. 5): a grid of mass points at the
//! yarn crossings, joined to their four neighbours by springs that stand for yarn.
//!
//! Particle state is kept as parallel arrays ([`Particles`]); springs and the per-point lists of
//! what acts on each point are built once, here. The force pass (`sim::evaluation`) finds the
//! same neighbours from the grid layout instead of reading the lists; a property test holds the
//! two together, and the lists serve the fields computed after the fit.

use std::collections::BTreeMap;

use super::pattern::Tile;
use crate::base::{Direction, Segment, Vec3, YarnGeometry, YarnKind};

/// Index of a mass point: `course * wales + wale`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct PointId(pub u32);

impl PointId {
    /// The index as `usize`, for slicing the particle arrays.
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// One piece of yarn between two neighbouring crossings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spring {
    /// Lower-numbered end (left along a course, below along a wale).
    pub a: PointId,
    /// The other end.
    pub b: PointId,
    /// Rest length `l` of eq. (1), in metres.
    pub rest: f64,
    /// Which yarn this piece belongs to.
    pub yarn: YarnKind,
    /// Along the course or along the wale.
    pub direction: Direction,
}

/// Particle state as parallel arrays, one entry per point.
#[derive(Clone, Debug, Default)]
pub struct Particles {
    /// Positions, metres.
    pub x: Vec<Vec3>,
    /// Velocities, metres per solver time unit.
    pub v: Vec<Vec3>,
    /// Inverse mass; 0 pins the point (held edges). The paper uses unit mass.
    pub inv_mass: Vec<f64>,
}

impl Particles {
    /// Number of points.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// True when there are no points.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }
}

/// A spring incident to a point, seen from that point.
#[derive(Clone, Copy, Debug)]
pub struct Incident {
    /// Index into [`Knit::springs`].
    pub spring: u32,
    /// The point at the other end.
    pub other: PointId,
}

/// A connection-force term acting on a point `i` (eq. 2): the tension of spring `j–k`, where `j`
/// is `i`'s neighbour along the same course and `k` is the next point on from `j`.
#[derive(Clone, Copy, Debug)]
pub struct Connection {
    /// The middle point `j`, towards which `i` is drawn.
    pub via: PointId,
    /// Index into [`Knit::springs`] of spring `j–k`.
    pub spring: u32,
}

/// The knit: grid topology, springs, per-point classes and the particle state.
#[derive(Clone, Debug)]
pub struct Knit {
    /// Points around / across a course.
    pub wales: usize,
    /// Points along a wale.
    pub courses: usize,
    /// True for a tube: the last wale joins the first (the seam is closed).
    pub closed_courses: bool,
    /// Positions, velocities, inverse masses.
    pub particles: Particles,
    /// All springs: course springs first (course by course), then wale springs.
    pub springs: Vec<Spring>,
    /// Point class 1–4 (paper Fig. 6), per point.
    pub class: Vec<u8>,
    /// Yarn of the course through each point.
    pub course_yarn: Vec<YarnKind>,
    /// Factor on the yarn's stiffness c1 for course and wale springs (indexed by
    /// [`Direction::index`]): 1 when a grid cell is one stitch, as in the paper; see
    /// [`Knit::with_stitch_shape`] for a grid coarser than the stitches.
    pub stiffness_scale: [f64; 2],
    incident_start: Vec<u32>,
    incident: Vec<Incident>,
    connection_start: Vec<u32>,
    connections: Vec<Connection>,
}

impl Knit {
    /// Builds a `wales × courses` grid. `position(wale, course)` gives each point's start position
    /// in metres; `rest_course` / `rest_wale` are the rest lengths of course and wale springs.
    pub fn grid(
        wales: usize,
        courses: usize,
        closed_courses: bool,
        tile: &Tile,
        rest_course: f64,
        rest_wale: f64,
        position: impl Fn(usize, usize) -> Vec3,
    ) -> Knit {
        let n = wales * courses;
        let id = |w: usize, c: usize| PointId((c * wales + w) as u32);
        let mut x = Vec::with_capacity(n);
        let mut class = Vec::with_capacity(n);
        let mut course_yarn = Vec::with_capacity(n);
        // A point's class depends only on its cell of the tile: classify each cell once.
        let (tile_w, tile_h) = tile.size();
        let cell_class: Vec<u8> = (0..tile_w * tile_h)
            .map(|k| tile.point_class((k % tile_w) as isize, (k / tile_w) as isize))
            .collect();
        for c in 0..courses {
            for w in 0..wales {
                x.push(position(w, c));
                class.push(cell_class[(c % tile_h) * tile_w + w % tile_w]);
                course_yarn.push(tile.course_yarn(w as isize, c as isize));
            }
        }

        let mut springs = Vec::with_capacity(2 * n);
        // A closed ring needs at least 3 points, or the wrap spring would duplicate another.
        let wraps = closed_courses && wales >= 3;
        let course_springs_per_row = if wraps {
            wales
        } else {
            wales.saturating_sub(1)
        };
        for c in 0..courses {
            for w in 0..course_springs_per_row {
                springs.push(Spring {
                    a: id(w, c),
                    b: id((w + 1) % wales, c),
                    rest: rest_course,
                    yarn: tile.spring_kind(w as isize, c as isize, Direction::Course),
                    direction: Direction::Course,
                });
            }
        }
        for c in 0..courses.saturating_sub(1) {
            for w in 0..wales {
                springs.push(Spring {
                    a: id(w, c),
                    b: id(w, c + 1),
                    rest: rest_wale,
                    yarn: tile.spring_kind(w as isize, c as isize, Direction::Wale),
                    direction: Direction::Wale,
                });
            }
        }

        let nowhere = PointId(0);
        let (incident_start, incident) = lists(
            n,
            Incident {
                spring: 0,
                other: nowhere,
            },
            |push| {
                for (s, spring) in springs.iter().enumerate() {
                    let s = s as u32;
                    push(
                        spring.a.index(),
                        Incident {
                            spring: s,
                            other: spring.b,
                        },
                    );
                    push(
                        spring.b.index(),
                        Incident {
                            spring: s,
                            other: spring.a,
                        },
                    );
                }
            },
        );
        let incident_of =
            |i: usize| &incident[incident_start[i] as usize..incident_start[i + 1] as usize];
        // Connection terms: for i, each course neighbour j, and j's other course spring j–k.
        let is_course =
            |inc: &Incident| springs[inc.spring as usize].direction == Direction::Course;
        let filler = Connection {
            via: nowhere,
            spring: 0,
        };
        let (connection_start, connections) = lists(n, filler, |push| {
            for i in 0..n {
                for inc in incident_of(i).iter().filter(|inc| is_course(inc)) {
                    let j = inc.other;
                    for onward in incident_of(j.index()) {
                        if is_course(onward) && onward.other.index() != i {
                            push(
                                i,
                                Connection {
                                    via: j,
                                    spring: onward.spring,
                                },
                            );
                        }
                    }
                }
            }
        });

        Knit {
            wales,
            courses,
            closed_courses: wraps,
            particles: Particles {
                v: vec![Vec3::zeros(); n],
                inv_mass: vec![1.0; n],
                x,
            },
            springs,
            class,
            course_yarn,
            stiffness_scale: [1.0, 1.0],
            incident_start,
            incident,
            connection_start,
            connections,
        }
    }

    /// The same grid standing for a knit whose stitch is `course_spacing × wale_spacing`
    /// (metres), whatever its own rest lengths.
    ///
    /// A grid of springs is a membrane whose stiffness around (along the courses), per unit
    /// length along the wales, is `c1 · rest_course / rest_wale`, and the other way
    /// `c1 · rest_wale / rest_course`. So a grid whose cells have another shape than the stitch
    /// would be another fabric: a 400×1600 tube of a 0.20 m × 0.29 m stocking has cells 2.7
    /// times wider than long, its rings 7× stiffer than its wales compared with a square stitch,
    /// and the rings squeeze the lower leg of the tube into folds. Scaling each direction's
    /// springs by `α` and `1/α`, with `α = (course_spacing / wale_spacing) · (rest_wale /
    /// rest_course)`, gives every grid the stitch's membrane, so the grid size only sets how
    /// finely that fabric is resolved (and the multilevel solver's coarse grids are the same
    /// fabric as the fine one).
    pub fn with_stitch_shape(mut self, course_spacing: f64, wale_spacing: f64) -> Knit {
        let rest = |direction: Direction| {
            self.springs
                .iter()
                .find(|s| s.direction == direction)
                .map(|s| s.rest)
        };
        if let (Some(course), Some(wale)) = (rest(Direction::Course), rest(Direction::Wale)) {
            let alpha = (course_spacing / wale_spacing) * (wale / course);
            self.stiffness_scale = [alpha, 1.0 / alpha];
        }
        self
    }

    /// Number of mass points.
    pub fn len(&self) -> usize {
        self.particles.len()
    }

    /// True for an empty knit.
    pub fn is_empty(&self) -> bool {
        self.particles.is_empty()
    }

    /// The point at `(wale, course)`.
    pub fn point(&self, wale: usize, course: usize) -> PointId {
        PointId((course * self.wales + wale) as u32)
    }

    /// `(wale, course)` of a point.
    pub fn grid_coords(&self, p: PointId) -> (usize, usize) {
        (p.index() % self.wales, p.index() / self.wales)
    }

    /// Springs incident to point `p`, in a fixed order.
    pub fn incident(&self, p: PointId) -> &[Incident] {
        let i = p.index();
        &self.incident[self.incident_start[i] as usize..self.incident_start[i + 1] as usize]
    }

    /// Connection-force terms acting on point `p` (eq. 2), in a fixed order.
    pub fn connections(&self, p: PointId) -> &[Connection] {
        let i = p.index();
        &self.connections[self.connection_start[i] as usize..self.connection_start[i + 1] as usize]
    }

    /// Pins point `p` in place (inverse mass 0, velocity 0).
    pub fn pin(&mut self, p: PointId) {
        self.particles.inv_mass[p.index()] = 0.0;
        self.particles.v[p.index()] = Vec3::zeros();
    }

    /// Indices of points that are free to move.
    pub fn is_free(&self, p: PointId) -> bool {
        self.particles.inv_mass[p.index()] > 0.0
    }

    /// The knit as yarn geometry, placed at `offset_m`: every point with its `course`, `wale`,
    /// `class` and `yarn_kind` (the yarn of its course), every spring as a segment.
    pub fn yarn_geometry(&self, name: &str, offset_m: [f64; 3]) -> YarnGeometry {
        let n = self.len();
        let mut course = Vec::with_capacity(n);
        let mut wale = Vec::with_capacity(n);
        for i in 0..n {
            let (w, c) = self.grid_coords(PointId(i as u32));
            course.push(c as f32);
            wale.push(w as f32);
        }
        let mut point_attributes = BTreeMap::new();
        point_attributes.insert("course".to_string(), course);
        point_attributes.insert("wale".to_string(), wale);
        point_attributes.insert(
            "class".to_string(),
            self.class.iter().map(|&c| c as f32).collect(),
        );
        point_attributes.insert(
            "yarn_kind".to_string(),
            self.course_yarn.iter().map(|k| k.index() as f32).collect(),
        );
        YarnGeometry {
            name: name.to_string(),
            offset_m,
            positions: self.particles.x.iter().map(|p| [p.x, p.y, p.z]).collect(),
            point_attributes,
            segments: self
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

/// Per-point lists in a compressed layout (start offsets, then all entries), from `entries`,
/// which calls `push(point, item)` for each item in order (`filler` only fills space before it
/// is written). `entries` runs twice, to count and then to fill, so no list is a `Vec` of its
/// own: the multilevel solver builds a knit per level, and per-point allocations add up.
fn lists<T: Copy>(
    points: usize,
    filler: T,
    entries: impl Fn(&mut dyn FnMut(usize, T)),
) -> (Vec<u32>, Vec<T>) {
    let mut start = vec![0u32; points + 1];
    entries(&mut |i, _| start[i + 1] += 1);
    for i in 0..points {
        start[i + 1] += start[i];
    }
    let mut flat = vec![filler; start[points] as usize];
    let mut next = start.clone();
    entries(&mut |i, item| {
        flat[next[i] as usize] = item;
        next[i] += 1;
    });
    (start, flat)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::knit::pattern::Pattern;

    fn flat(wales: usize, courses: usize, closed: bool) -> Knit {
        Knit::grid(
            wales,
            courses,
            closed,
            &Tile::of(Pattern::Alternating),
            1.0,
            1.0,
            |w, c| Vec3::new(w as f64, c as f64, 0.0),
        )
    }

    #[test]
    fn grid_has_four_neighbours_inside_and_fewer_on_the_border() {
        let knit = flat(4, 3, false);
        assert_eq!(knit.springs.len(), 3 * 3 + 2 * 4);
        assert_eq!(knit.incident(knit.point(1, 1)).len(), 4);
        assert_eq!(knit.incident(knit.point(0, 0)).len(), 2);
        assert_eq!(knit.incident(knit.point(3, 1)).len(), 3);
    }

    #[test]
    fn closed_courses_join_the_seam() {
        let knit = flat(4, 3, true);
        assert_eq!(knit.springs.len(), 4 * 3 + 2 * 4);
        assert_eq!(knit.incident(knit.point(0, 1)).len(), 4);
        // Every point on a closed course has two connection terms (one through each neighbour).
        assert_eq!(knit.connections(knit.point(0, 1)).len(), 2);
    }

    #[test]
    fn connections_follow_the_course_only() {
        let knit = flat(4, 3, false);
        let i = knit.point(0, 1);
        let terms = knit.connections(i);
        assert_eq!(
            terms.len(),
            1,
            "end of a course: only one neighbour with a further spring"
        );
        assert_eq!(terms[0].via, knit.point(1, 1));
        let s = knit.springs[terms[0].spring as usize];
        assert_eq!((s.a, s.b), (knit.point(1, 1), knit.point(2, 1)));
        assert_eq!(s.direction, Direction::Course);
    }

    #[test]
    fn spring_kinds_and_classes_come_from_the_tile() {
        let knit = flat(4, 4, false);
        let tile = Tile::of(Pattern::Alternating);
        for s in &knit.springs {
            let (w, c) = knit.grid_coords(s.a);
            assert_eq!(
                s.yarn,
                tile.spring_kind(w as isize, c as isize, s.direction)
            );
        }
        for c in 0..4 {
            for w in 0..4 {
                let p = knit.point(w, c);
                assert_eq!(
                    knit.class[p.index()],
                    tile.point_class(w as isize, c as isize)
                );
            }
        }
    }
}
