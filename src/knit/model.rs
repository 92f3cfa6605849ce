//! The knit as a mass-spring system (Sakaguchi & Miyata §4, Fig. 5): a grid of mass points at the
//! yarn crossings, joined to their four neighbours by springs that stand for yarn, and the
//! shaping hosiery adds to the grid: a toe seam and the short rows of a heel pocket.
//!
//! This is the one model of the knit's topology. Grid points come first (`course * wales +
//! wale`), then the points of short rows; grid springs first (course by course, then wale
//! springs), then the shaping's springs. Short rows replace a grid wale spring by a chain of
//! extra points; the replaced slot stays in place (so the grid keeps its layout) marked
//! [`Spring::cut`], and carries no force. Everything after the fit reads the same model: the
//! per-point lists ([`Knit::incident`], [`Knit::connections`]), the wales as chains of points
//! ([`Knit::wale_chain`]), the fabric's faces ([`Knit::faces`]) and each point's place in the
//! fabric ([`Knit::fabric_coords`]).
//!
//! Particle state is kept as parallel arrays ([`Particles`]); springs and the per-point lists
//! are built here. The force pass (`sim::evaluation`) finds the grid's neighbours from its layout
//! instead of reading the lists, and the shaping's springs from the lists; a property test holds
//! the two together.

use std::collections::BTreeMap;

use super::pattern::Tile;
use crate::base::{Direction, PerDirection, PerYarn, Segment, Vec3, YarnGeometry, YarnKind};

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
    /// A grid slot that short rows replaced: no yarn runs here and it carries no force. Kept so
    /// the grid's springs stay where the force pass finds them.
    pub cut: bool,
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
    pub stiffness_scale: PerDirection,
    /// On a grid that stands for the fabric ([`Knit::with_stitch_shape`]): the share of each
    /// yarn kind among the grid's springs along each direction, which every spring of that
    /// direction then stands for together. `None` on a knit of single stitches (the patch),
    /// which knits the pattern spring by spring.
    pub yarn_blend: Option<PerDirection<PerYarn<f64>>>,
    /// Springs of the grid (the first ones); those after are the shaping's.
    grid_springs: usize,
    /// True when the last course is closed by a toe seam.
    toe_seam: bool,
    /// See [`Knit::toe_seam_steps`].
    toe_seam_steps: f64,
    /// The heel pocket's short rows, if knitted.
    short_rows: Option<ShortRows>,
    /// Grid points that shaping springs reach, ascending.
    shaped_grid_points: Vec<u32>,
    /// Springs that carry yarn (not cut).
    yarn_spring_count: usize,
    incident_start: Vec<u32>,
    incident: Vec<Incident>,
    connection_start: Vec<u32>,
    connections: Vec<Connection>,
}

/// Short rows knitted between grid courses `course` and `course + 1` (a heel pocket): `rows`
/// partial rows that first shorten, then lengthen again. Row `r` of the shortening half
/// (1 ≤ r ≤ rows/2) runs over the wales of depth ≥ r; its mirror, row `rows + 1 − r`, over the
/// same wales. So wale `w` of depth `d` gains `2 d` points between the two courses: those of rows
/// `1..=d`, then those of rows `rows + 1 − d..=rows`.
#[derive(Clone, Debug, PartialEq)]
pub struct ShortRows {
    /// The grid course the short rows start above.
    pub course: usize,
    /// Rows in all (even).
    pub rows: usize,
    /// Per wale, how many rows of each half run over it.
    pub depth: Vec<usize>,
    /// Per wale, its first extra point (its extra points are consecutive, in chain order).
    first_point: Vec<u32>,
}

impl ShortRows {
    /// The short row of wale `w`'s `k`-th extra point (0-based, in chain order): 1..=rows.
    fn row_of(&self, w: usize, k: usize) -> usize {
        let d = self.depth[w];
        if k < d {
            k + 1
        } else {
            self.rows + 1 - d + (k - d)
        }
    }

    /// Wale `w`'s extra point in short row `row`, if that row runs over it.
    fn point_in_row(&self, w: usize, row: usize) -> Option<PointId> {
        let d = self.depth[w];
        let k = if row <= d {
            row - 1
        } else if row + d > self.rows {
            d + row - (self.rows + 1 - d)
        } else {
            return None;
        };
        Some(PointId(self.first_point[w] + k as u32))
    }
}

/// A face of the fabric: a grid cell, a cell of the heel pocket (more than four corners where
/// one side has short rows the other lacks), or a piece of the toe seam. Corners run
/// counter-clockwise seen from outside a tube: around, then up the wales.
#[derive(Clone, Debug, PartialEq)]
pub struct Face {
    /// The corners.
    pub corners: Vec<PointId>,
    /// Knitted stitches the face stands for, in grid cells: the mean of its two sides' wale
    /// intervals (1 for a grid cell, its interval over the first on a graded grid), 0 for the
    /// toe seam, which is sewn, not knitted.
    pub stitches: f64,
}

/// The wale a toe seam joins wale `w` of `wales` to, facing it across the flattened last
/// course: `wales − w`. `None` at the folds (wales 0 and `wales / 2`, facing themselves) and for
/// an odd course's middle pair, which are course neighbours already.
fn seam_facing(wales: usize, w: usize) -> Option<usize> {
    let facing = (wales - w % wales) % wales;
    (facing != w && facing != w + 1 && facing + 1 != w).then_some(facing)
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
        // Within `u32`: a grid is at most `MAX_TUBE_POINTS` (`TubeSettings::validate`), and the
        // fit refuses a real stitch count past it (`fit::size`); patches are smaller still.
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
                    cut: false,
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
                    cut: false,
                });
            }
        }

        let grid_springs = springs.len();
        let mut knit = Knit {
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
            stiffness_scale: PerDirection::new(1.0, 1.0),
            yarn_blend: None,
            grid_springs,
            toe_seam: false,
            toe_seam_steps: 1.0,
            short_rows: None,
            shaped_grid_points: Vec::new(),
            yarn_spring_count: 0,
            incident_start: Vec::new(),
            incident: Vec::new(),
            connection_start: Vec::new(),
            connections: Vec::new(),
        };
        knit.build_lists();
        knit
    }

    /// The same grid with its courses `intervals[c]` metres of relaxed fabric apart along the
    /// wale (course `c` to `c + 1`), rather than all one rest length: a grid graded finer where
    /// its cells would be too long for the shape they wrap (a toe's tip). The springs stay the
    /// same fabric per strain: a wale spring is stiffer by the first interval over its own
    /// (shorter yarn, stiffer), and a ring's course springs by the fabric it stands for (half
    /// its intervals either side) over the first interval. On an even grid every factor is 1.
    /// Before the shaping, whose springs take the first interval as their step.
    pub fn with_course_intervals(mut self, intervals: &[f64]) -> Knit {
        assert_eq!(
            intervals.len() + 1,
            self.courses,
            "an interval between each two courses"
        );
        assert_eq!(self.grid_springs, self.springs.len(), "before the shaping");
        let start = self.courses * self.course_springs_per_row();
        for (c, &rest) in intervals.iter().enumerate() {
            for s in &mut self.springs[start + c * self.wales..][..self.wales] {
                s.rest = rest;
            }
        }
        self
    }

    /// Relaxed fabric between course `c` and `c + 1` along the wale, metres (the rest of the
    /// grid's wale springs there; see [`Knit::with_course_intervals`]).
    pub fn course_interval(&self, c: usize) -> f64 {
        self.springs[self.courses * self.course_springs_per_row() + c * self.wales].rest
    }

    /// Relaxed fabric from the first course to each course along the wale, metres.
    pub fn course_places(&self) -> Vec<f64> {
        let intervals: Vec<f64> = (0..self.courses.saturating_sub(1))
            .map(|c| self.course_interval(c))
            .collect();
        places_along(&intervals)
    }

    /// [`Knit::grid_spring_factors`] of spring `s`: its row's for a grid spring, 1 for the
    /// shaping's (whose own factors, the toe seam's, are its yarn's).
    pub fn spring_factor(&self, s: usize) -> f64 {
        if s >= self.grid_springs {
            return 1.0;
        }
        let per_row = self.course_springs_per_row();
        let start = self.courses * per_row;
        match s < start {
            true => self.grid_spring_factors(s / per_row.max(1))[0],
            false => self.grid_spring_factors((s - start) / self.wales)[1],
        }
    }

    /// On a graded grid, the fabric each point stands for as a share of an even grid's point:
    /// its ring's ([`Knit::grid_spring_factors`]), 1 for a short row's; `None` on an even grid,
    /// whose points are alike.
    pub fn point_fabric_shares(&self) -> Option<Vec<f64>> {
        self.is_graded().then(|| {
            (0..self.len())
                .map(|i| match i < self.grid_len() {
                    true => self.grid_spring_factors(i / self.wales)[0],
                    false => 1.0,
                })
                .collect()
        })
    }

    /// True when the courses are not all one rest length apart (a graded grid).
    pub fn is_graded(&self) -> bool {
        if self.courses < 3 || self.wales == 0 {
            return false;
        }
        let first = self.course_interval(0);
        (1..self.courses - 1).any(|c| self.course_interval(c) != first)
    }

    /// Factor on the stiffness of the grid's springs in course row `c` and of its wale springs
    /// from course `c` up (`[course, wale]`): 1 on an even grid (see
    /// [`Knit::with_course_intervals`]).
    pub fn grid_spring_factors(&self, c: usize) -> [f64; 2] {
        let last = self.courses.saturating_sub(1);
        if last == 0 || self.wales == 0 {
            return [1.0, 1.0];
        }
        // Read per row by the force pass: the first interval directly, not by a search.
        let first = self.course_interval(0);
        if first <= 0.0 {
            return [1.0, 1.0];
        }
        let height = match c {
            0 => first,
            _ if c == last => self.course_interval(last - 1),
            _ => 0.5 * (self.course_interval(c - 1) + self.course_interval(c)),
        };
        let wale = match c < last {
            true => first / self.course_interval(c),
            false => 1.0,
        };
        [height / first, wale]
    }

    /// Closes the last course with a toe seam, as hosiery is closed: the course laid flat with
    /// wale 0 and wale `wales / 2` at its folds, each wale `w` linked to the wale `wales − w`
    /// facing it, by a seam spring of rest length `rest` (metres). The seam continues the wales
    /// across the toe, so its springs run along the wale.
    pub fn with_toe_seam(mut self, rest: f64) -> Knit {
        let (wales, last) = (self.wales, self.courses - 1);
        for w in 1..wales.div_ceil(2) {
            let Some(facing) = seam_facing(wales, w) else {
                continue;
            };
            self.springs.push(Spring {
                a: self.point(w, last),
                b: self.point(facing, last),
                rest,
                yarn: YarnKind::Seam,
                direction: Direction::Wale,
                cut: false,
            });
        }
        self.toe_seam = true;
        let wale_rest = self.grid_rest_m().wale;
        if rest > 0.0 && wale_rest > 0.0 {
            self.toe_seam_steps = rest / wale_rest;
        }
        self.build_lists();
        self
    }

    /// Knits short rows between grid courses `course` and `course + 1` (see [`ShortRows`]):
    /// `depth[w]` rows of each half over wale `w`. `tile` gives their yarns (row `r` knits as
    /// course `course + r` would), `rest_course` and `rest_wale` their rest lengths, and
    /// `position(wale, fraction)` each new point's start, `fraction` (0–1) its place between the
    /// two courses along its wale's chain.
    pub fn with_short_rows(
        mut self,
        course: usize,
        depth: Vec<usize>,
        tile: &Tile,
        rest_course: f64,
        rest_wale: f64,
        position: impl Fn(usize, f64) -> Vec3,
    ) -> Knit {
        let wales = self.wales;
        assert_eq!(depth.len(), wales, "a depth per wale");
        assert!(
            course + 1 < self.courses,
            "short rows lie between two courses"
        );
        let half = depth.iter().copied().max().unwrap_or(0);
        let mut first_point = Vec::with_capacity(wales);
        for (w, &d) in depth.iter().enumerate() {
            first_point.push(self.particles.x.len() as u32);
            for k in 0..2 * d {
                let row = if k < d {
                    k + 1
                } else {
                    2 * half + 1 - d + (k - d)
                };
                let c = (course + row) as isize;
                self.particles
                    .x
                    .push(position(w, (k + 1) as f64 / (2 * d + 1) as f64));
                self.particles.v.push(Vec3::zeros());
                self.particles.inv_mass.push(1.0);
                self.class.push(tile.point_class(w as isize, c));
                self.course_yarn.push(tile.course_yarn(w as isize, c));
            }
        }
        let rows = ShortRows {
            course,
            rows: 2 * half,
            depth,
            first_point,
        };
        // Each wale with short rows: its grid spring across them is cut, and a chain of wale
        // springs runs through its points instead.
        let wale_start = self.courses * self.course_springs_per_row();
        for w in 0..wales {
            let d = rows.depth[w];
            if d == 0 {
                continue;
            }
            let slot = wale_start + course * wales + w;
            self.springs[slot].cut = true;
            let chain: Vec<PointId> = std::iter::once(self.point(w, course))
                .chain((0..2 * d).map(|k| PointId(rows.first_point[w] + k as u32)))
                .chain(std::iter::once(self.point(w, course + 1)))
                .collect();
            for (k, pair) in chain.windows(2).enumerate() {
                let row = if k == 0 { 0 } else { rows.row_of(w, k - 1) };
                self.springs.push(Spring {
                    a: pair[0],
                    b: pair[1],
                    rest: rest_wale,
                    yarn: tile.spring_kind(w as isize, (course + row) as isize, Direction::Wale),
                    direction: Direction::Wale,
                    cut: false,
                });
            }
        }
        // Each row's course springs, between neighbouring wales it runs over.
        let across = self.course_springs_per_row();
        for row in 1..=rows.rows {
            for w in 0..across {
                let next = (w + 1) % wales;
                if let (Some(a), Some(b)) =
                    (rows.point_in_row(w, row), rows.point_in_row(next, row))
                {
                    self.springs.push(Spring {
                        a,
                        b,
                        rest: rest_course,
                        yarn: tile.course_yarn(w as isize, (course + row) as isize),
                        direction: Direction::Course,
                        cut: false,
                    });
                }
            }
        }
        self.short_rows = Some(rows);
        self.build_lists();
        self
    }

    /// Course springs per grid row: around a closed course, one more than across an open one.
    fn course_springs_per_row(&self) -> usize {
        if self.closed_courses {
            self.wales
        } else {
            self.wales.saturating_sub(1)
        }
    }

    /// Builds the per-point lists from the springs (cut slots left out).
    fn build_lists(&mut self) {
        let n = self.len();
        let springs = &self.springs;
        let nowhere = PointId(0);
        let (incident_start, incident) = lists(
            n,
            Incident {
                spring: 0,
                other: nowhere,
            },
            |push| {
                for (s, spring) in springs.iter().enumerate().filter(|(_, s)| !s.cut) {
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
        let mut shaped: Vec<u32> = springs[self.grid_springs..]
            .iter()
            .flat_map(|s| [s.a.0, s.b.0])
            .filter(|&p| (p as usize) < self.wales * self.courses)
            .collect();
        shaped.sort_unstable();
        shaped.dedup();
        self.shaped_grid_points = shaped;
        self.yarn_spring_count = springs.iter().filter(|s| !s.cut).count();
        self.incident_start = incident_start;
        self.incident = incident;
        self.connection_start = connection_start;
        self.connections = connections;
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
    /// springs by `α` and `1/α`, with `α = (stitch_m.course / stitch_m.wale) · (rest_wale /
    /// rest_course)`, gives every grid the stitch's membrane, so the grid size only sets how
    /// finely that fabric is resolved (and the multilevel solver's coarse grids are the same
    /// fabric as the fine one).
    ///
    /// A cell that stands for a block of stitches holds both yarns of an alternating pattern,
    /// so the springs are blended ([`Knit::yarn_blend`]) rather than alternating cell by cell:
    /// knitted cell by cell, the yarns' stripes would be as wide as a cell, and how much they
    /// stiffen the fabric would change with the cells' shape. A grid of the real stitches is
    /// blended too: knitted spring by spring, its soft nylon courses zigzag between the support
    /// courses, a loop-scale wrinkle that is not the fabric's shape and that the solver takes
    /// ten times longer to settle (docs/decisions/0053).
    pub fn with_stitch_shape(mut self, stitch_m: PerDirection) -> Knit {
        let rest = self.grid_rest_m();
        if rest.course > 0.0 && rest.wale > 0.0 {
            let alpha = (stitch_m.course / stitch_m.wale) * (rest.wale / rest.course);
            self.stiffness_scale = PerDirection::new(alpha, 1.0 / alpha);
            self.yarn_blend = Some(self.yarn_shares());
        }
        self
    }

    /// The share of each yarn kind among the grid's springs, along the course and the wale.
    pub fn yarn_shares(&self) -> PerDirection<PerYarn<f64>> {
        let mut count = [[0usize; 3]; 2];
        for s in &self.springs[..self.grid_springs] {
            count[s.direction.index()][s.yarn.index() as usize] += 1;
        }
        PerDirection::from(count.map(|per_yarn| {
            let total = per_yarn.iter().sum::<usize>().max(1) as f64;
            per_yarn.map(|n| n as f64 / total)
        }))
    }

    /// Rest lengths of the grid's course and wale springs, metres (the first of each; a grid's
    /// are all alike). 0 for a direction without springs.
    pub fn grid_rest_m(&self) -> PerDirection {
        let rest = |direction| {
            self.springs
                .iter()
                .find(|s| s.direction == direction)
                .map_or(0.0, |s| s.rest)
        };
        PerDirection::new(rest(Direction::Course), rest(Direction::Wale))
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

    /// `(wale, course)` of a grid point.
    pub fn grid_coords(&self, p: PointId) -> (usize, usize) {
        debug_assert!(p.index() < self.grid_len(), "a grid point");
        (p.index() % self.wales, p.index() / self.wales)
    }

    /// Points of the grid; the points after them are short rows'.
    pub fn grid_len(&self) -> usize {
        self.wales * self.courses
    }

    /// The springs the grid does not have: the toe seam's and the short rows'.
    pub fn shaping_springs(&self) -> std::ops::Range<usize> {
        self.grid_springs..self.springs.len()
    }

    /// Grid points that shaping springs reach, ascending: the force pass adds those springs to
    /// what the grid gives them.
    pub fn shaped_grid_points(&self) -> &[u32] {
        &self.shaped_grid_points
    }

    /// True when the last course is closed by a toe seam.
    pub fn has_toe_seam(&self) -> bool {
        self.toe_seam
    }

    /// The wale the toe seam joins wale `w` to at the last course (see [`Knit::with_toe_seam`]),
    /// along which the fabric runs on over the toe; `None` without a seam and at the folds (wales
    /// 0 and `wales / 2`, and an odd course's middle pair, which a course spring joins).
    pub fn toe_seam_partner(&self, w: usize) -> Option<usize> {
        seam_facing(self.wales, w).filter(|_| self.toe_seam)
    }

    /// The toe seam's rest length in grid wale steps (1 without a seam): on a grid coarser than
    /// the stitches, the seam is a fraction of a step of fabric; its springs are stiffer by
    /// as much, so that per strain they are the same fabric as the wales.
    pub fn toe_seam_steps(&self) -> f64 {
        self.toe_seam_steps
    }

    /// The heel pocket's short rows, if knitted.
    pub fn short_rows(&self) -> Option<&ShortRows> {
        self.short_rows.as_ref()
    }

    /// How many springs carry yarn.
    pub fn yarn_spring_count(&self) -> usize {
        self.yarn_spring_count
    }

    /// The springs that carry yarn (cut grid slots left out), with their indices.
    pub fn yarn_springs(&self) -> impl Iterator<Item = (usize, &Spring)> {
        self.springs.iter().enumerate().filter(|(_, s)| !s.cut)
    }

    /// A point's place in the fabric as `[wale, course]`: whole numbers on the grid; a short
    /// row's point lies between the two grid courses it was knitted between, spread evenly
    /// along its wale. Continuous across the fabric (texture coordinates, interpolation
    /// between grids).
    pub fn fabric_coords(&self, p: PointId) -> [f64; 2] {
        let i = p.index();
        if i < self.grid_len() {
            let (w, c) = self.grid_coords(p);
            return [w as f64, c as f64];
        }
        let rows = self
            .short_rows
            .as_ref()
            .expect("extra points are short rows'");
        let w = rows.first_point.partition_point(|&f| f as usize <= i) - 1;
        let k = i - rows.first_point[w] as usize;
        let d = rows.depth[w];
        [
            w as f64,
            rows.course as f64 + (k + 1) as f64 / (2 * d + 1) as f64,
        ]
    }

    /// The points of wale `w` from the first course to the last, short rows' included.
    pub fn wale_chain(&self, w: usize) -> Vec<PointId> {
        let grid = |c: usize| self.point(w, c);
        match &self.short_rows {
            Some(rows) if rows.depth[w] > 0 => (0..=rows.course)
                .map(grid)
                .chain((0..2 * rows.depth[w]).map(|k| PointId(rows.first_point[w] + k as u32)))
                .chain((rows.course + 1..self.courses).map(grid))
                .collect(),
            _ => (0..self.courses).map(grid).collect(),
        }
    }

    /// Relaxed fabric from the first course to each point of [`Knit::wale_chain`] `w`, metres:
    /// the grid's intervals, and through a heel pocket its short rows' wale springs.
    pub fn wale_chain_places(&self, w: usize) -> Vec<f64> {
        let pocket = self.short_rows.as_ref().filter(|rows| rows.depth[w] > 0);
        let mut steps = Vec::with_capacity(self.courses + 8);
        for c in 0..self.courses.saturating_sub(1) {
            match pocket {
                Some(rows) if rows.course == c => {
                    // The short rows' springs are the shaping's, one first interval each.
                    let step = self.course_interval(0);
                    steps.extend(std::iter::repeat_n(step, 2 * rows.depth[w] + 1));
                }
                _ => steps.push(self.course_interval(c)),
            }
        }
        places_along(&steps)
    }

    /// [`Knit::wale_chain`] of wale `w`, and where a toe seam joins it to another wale, on over
    /// the toe and back along that wale to its first course: the fabric's path along the wale.
    pub fn wale_path_over_toe(&self, w: usize) -> Vec<PointId> {
        let mut path = self.wale_chain(w);
        if let Some(facing) = self.toe_seam_partner(w) {
            path.extend(self.wale_chain(facing).into_iter().rev());
        }
        path
    }

    /// The fabric's faces (see [`Face`]): the grid's cells, the heel pocket's in place of the
    /// cells its short rows divide, and the toe seam's, which close the last course.
    pub fn faces(&self) -> Vec<Face> {
        let wales = self.wales;
        let across = self.course_springs_per_row();
        let mut faces = Vec::with_capacity(across * self.courses);
        let first = self.grid_rest_m().wale;
        for c in 0..self.courses.saturating_sub(1) {
            // A graded grid's cell is its interval's share of an even one's.
            let cell = match first > 0.0 {
                true => self.course_interval(c) / first,
                false => 1.0,
            };
            for w in 0..across {
                let next = (w + 1) % wales;
                match &self.short_rows {
                    Some(rows)
                        if rows.course == c && (rows.depth[w] > 0 || rows.depth[next] > 0) =>
                    {
                        self.pocket_faces(rows, w, next, &mut faces)
                    }
                    _ => faces.push(Face {
                        corners: vec![
                            self.point(w, c),
                            self.point(next, c),
                            self.point(next, c + 1),
                            self.point(w, c + 1),
                        ],
                        stitches: cell,
                    }),
                }
            }
        }
        if self.toe_seam {
            // The last course folded flat: each face spans two neighbouring wales and the two
            // facing them.
            let last = self.courses - 1;
            let facing = |w: usize| (wales - w) % wales;
            for w in 0..wales / 2 {
                let mut corners = vec![self.point(w, last), self.point(w + 1, last)];
                for f in [facing(w + 1), facing(w)] {
                    if !corners.contains(&self.point(f, last)) {
                        corners.push(self.point(f, last));
                    }
                }
                if corners.len() >= 3 {
                    faces.push(Face {
                        corners,
                        stitches: 0.0,
                    });
                }
            }
        }
        faces
    }

    /// The faces between wales `w` and `next` across the short rows: one between each two rows
    /// both wales have (the grid courses included), with the rows only one side has between.
    fn pocket_faces(&self, rows: &ShortRows, w: usize, next: usize, faces: &mut Vec<Face>) {
        let c = rows.course;
        // Rows 0 and rows + 1 are the grid courses below and above.
        let at = |wale: usize, row: usize| -> Option<PointId> {
            if row == 0 {
                Some(self.point(wale, c))
            } else if row == rows.rows + 1 {
                Some(self.point(wale, c + 1))
            } else {
                rows.point_in_row(wale, row)
            }
        };
        let mut lower = 0;
        for row in 1..=rows.rows + 1 {
            let (Some(_), Some(_)) = (at(w, row), at(next, row)) else {
                continue;
            };
            let right: Vec<PointId> = (lower..=row).filter_map(|r| at(next, r)).collect();
            let left: Vec<PointId> = (lower..=row).rev().filter_map(|r| at(w, r)).collect();
            faces.push(Face {
                stitches: (right.len() - 1 + left.len() - 1) as f64 / 2.0,
                corners: std::iter::once(left[left.len() - 1])
                    .chain(right)
                    .chain(left[..left.len() - 1].iter().copied())
                    .collect(),
            });
            lower = row;
        }
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
            let [w, c] = self.fabric_coords(PointId(i as u32));
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
                .yarn_springs()
                .map(|(_, s)| Segment {
                    a: s.a.0,
                    b: s.b.0,
                    yarn: s.yarn,
                    direction: s.direction,
                })
                .collect(),
        }
    }
}

/// Where points lie along a line, from its first, whose steps are `intervals` long (one more
/// place than intervals): a wale's relaxed fabric to each of its courses.
pub fn places_along(intervals: &[f64]) -> Vec<f64> {
    std::iter::once(0.0)
        .chain(intervals.iter().scan(0.0, |place, &r| {
            *place += r;
            Some(*place)
        }))
        .collect()
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
