//! Every real stitch as a knitted loop: the yarn of a knit of the real stitch count, sampled as
//! polylines for export and for the ray-traced preview, whose sheerness comes from this shape.
//!
//! **Loop.** Choi & Lo (2003), "An energy model of plain knitted fabric", *Textile Research
//! Journal* 73(8), 739–748. A half loop, `t ∈ [0, 1]` from the sinker (`t = 0`) to the middle of
//! the needle-loop head (`t = 1`), in a relaxed stitch of width `w` (between wales along the
//! course, [`Fabric::stitch_m`]`.course`) and height `c` (between courses, `.wale`), yarn diameter `d`:
//! `x = a t³ − 1.5 a t² + ½ (a + w) t`, `y = ½ (c + 2e)(1 − cos π t)`,
//! `z = ½ (t_h − d)(1 − cos 2π t)`; the other half is its mirror `x → w − x`. The legs' `x`
//! extremes lie at `β₁,₂ = ½ (1 ∓ √((a − 2w) / 3a))`, and the loops of two courses interlock
//! there: `x(β₁) − x(β₂) = √((a − 2w) / 3a) (a − 2w) / 6 = χ d` ([`KNOT_SEPARATION`] `χ = 1`, the
//! legs touch) is solved for `a` by bisection, and `e = (c/2)(1 / cos πβ₁ − 1)` puts a head's
//! widest point (`β₂`) at the height of the next course's neck (`β₁`). `t_h = 2d`: the fabric is
//! two yarns thick, the legs lying one diameter over the heads they cross (Choi & Lo's `β₃, β₄`
//! condition for `t_h` is not used). Computed once per yarn kind ([`LoopShape::of`]).
//!
//! **Limits of the model, clamped.** As `d / w → 0`, `β₁ → ½` and `e` grows without bound: `e` is
//! held at `c / 2` (a head never rises past the sinkers two courses up), which binds below
//! `d ≈ w / 18` (some 6 den at `w` = 0.5 mm). Past `d = w / 2` two legs no longer fit in a
//! stitch (the jamming limit) and the head would leave its stitch: the shape is solved with
//! `d ≤ w / 2` (the thickness keeps the true `d`). Each yarn's loop is solved as if the courses
//! around it were of its yarn: where two yarns alternate, a head's widest point and the neck
//! above it differ in height by their `y(β₁)` (40 µm for 20 and 40 den), still side by side.
//!
//! **Placement.** A stitch spans one course spring `p → q` of the knit. Its loop, in relaxed
//! stitch units `u = x / w ∈ [0, 1]`, `v = y / c ∈ [0, (c + 2e) / c] ⊂ [0, 2]`, is mapped
//! bilinearly onto the fitted fabric: over the quad `p, q` and the points one step up their wales
//! ([`Knit::wale_chain`], short rows included) for `v ≤ 1`, and over the next quad up for
//! `v > 1`, so every sample lies inside the two quads above its course. Above the last course
//! the wales are continued straight (`p_up = p + (p − p_down)`). `z` goes along the stitch's
//! outward normal, the cross product of its quad's mean course and wale edges (faces are
//! counter-clockwise seen from outside), with a fallback where the quad is degenerate: never
//! NaN for finite positions. `z ≥ 0` keeps the yarn off the skin the lattice rests on.
//!
//! **Output.** [`SAMPLES_PER_LOOP`] points per stitch, the first at `p` itself (the sinker);
//! consecutive samples of a course joined by segments of the course's yarn
//! ([`Direction::Course`]), a closed course's last stitch joined to its first; an open course
//! ends with one more point at its last lattice point. No wale segments (the loops' legs are the
//! wale's yarn); the toe seam's springs stay straight segments between their lattice points.
//! Attributes: `course`, `wale` (the samples' fabric coordinates, mapped like the positions: a
//! head of course `k` lies at `k + (c + 2e) / c`) and `yarn_kind`. Courses come in point order
//! (grid courses, then short rows); the output is the same bytes for the same input.

use std::collections::BTreeMap;

use rayon::prelude::*;

use crate::base::{perpendicular_frame, Direction, PerYarn, Segment, Vec3, YarnGeometry, YarnKind};
use crate::knit::{Fabric, Knit, PointId};

/// Points per stitch: per half loop the sinker, the neck (`β₁`), the leg's middle (`½`, highest
/// `z`), the head's widest point (`β₂`), the head's top, and one point inside each of the two
/// arcs (at two fifths of the way from the sinker to `β₁`, and from the top to `β₂`): 6 + 6.
/// The knot is sampled exactly, and the polyline stays within 0.35 d of the curve for 20 den,
/// 0.26 d for 40 den, at the default 0.5 × 0.74 mm stitch (8 points, without the arcs' inner
/// ones, stray 1.4 d; 12 evenly spaced in `t`, 0.54 d).
pub const SAMPLES_PER_LOOP: usize = 12;

/// `χ`: centre-to-centre distance of the interlocking legs at the knot, in yarn diameters (1:
/// they touch).
pub const KNOT_SEPARATION: f64 = 1.0;

/// Where the inner sample of each arc lies, as a fraction of the arc's parameter span from its
/// end (sinker or head top); two fifths balances the errors either side of it.
const ARC_SAMPLE: f64 = 0.4;

/// The relaxed loop of one yarn (see module docs): Choi & Lo's parameters, metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoopShape {
    /// `w`: width of a stitch, between wales along the course.
    pub width_m: f64,
    /// `c`: height of a stitch, between courses along the wale.
    pub height_m: f64,
    /// `d`: the yarn's diameter.
    pub diameter_m: f64,
    /// `a`: the cubic's shape parameter (> 2w).
    pub a_m: f64,
    /// `e`: half the overlap of a head with the course above (> 0).
    pub e_m: f64,
    /// `t_h`: the fabric's thickness, `2d`.
    pub thickness_m: f64,
    /// `β₁ < ½ < β₂`: the half loop's parameters at its `x` extremes (neck and head's widest).
    pub beta: [f64; 2],
}

impl LoopShape {
    /// The loop of a yarn of diameter `diameter_m` in a stitch `width_m × height_m`. Finite for
    /// any input; a non-positive or non-finite size or diameter gives the thin-yarn limit.
    pub fn of(width_m: f64, height_m: f64, diameter_m: f64) -> LoopShape {
        let positive = |v: f64| if v.is_finite() && v > 0.0 { v } else { 0.0 };
        let (w, c, d) = (positive(width_m), positive(height_m), positive(diameter_m));
        let delta = if w > 0.0 {
            (KNOT_SEPARATION * d / w).min(0.5)
        } else {
            0.0
        };
        // In units of w: a = 2 + u with s(u) u / 6 = δ, s = √(u / 3(u + 2)), increasing in u.
        let separation = |u: f64| (u / (3.0 * (u + 2.0))).sqrt() * u / 6.0;
        let (mut lo, mut hi) = (0.0_f64, 1.0_f64);
        while separation(hi) < delta {
            hi *= 2.0;
        }
        for _ in 0..64 {
            let mid = 0.5 * (lo + hi);
            if separation(mid) < delta {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let u = if delta > 0.0 { 0.5 * (lo + hi) } else { 0.0 };
        let s = (u / (3.0 * (u + 2.0))).sqrt();
        let beta1 = 0.5 * (1.0 - s);
        // cos πβ₁ ∈ [0, 0.79) for β₁ ∈ (0.21, ½]: e / c ≥ 0.13 before the clamp, never NaN.
        let cosine = (std::f64::consts::PI * beta1).cos();
        let e_over_c = if cosine > 0.0 {
            (0.5 * (1.0 / cosine - 1.0)).min(0.5)
        } else {
            0.5
        };
        LoopShape {
            width_m: w,
            height_m: c,
            diameter_m: d,
            a_m: (2.0 + u) * w,
            e_m: e_over_c * c,
            thickness_m: 2.0 * d,
            beta: [beta1, 1.0 - beta1],
        }
    }

    /// Height of the head's top above the sinker, `c + 2e`, metres.
    pub fn head_height_m(&self) -> f64 {
        self.height_m + 2.0 * self.e_m
    }

    /// The half loop at `t ∈ [0, 1]` in the relaxed stitch: `(x, y, z)` metres, `x` along the
    /// course from the sinker, `y` up the wale, `z` out of the fabric.
    pub fn half_loop_m(&self, t: f64) -> Vec3 {
        let (a, w) = (self.a_m, self.width_m);
        let pi = std::f64::consts::PI;
        Vec3::new(
            a * t * t * t - 1.5 * a * t * t + 0.5 * (a + w) * t,
            0.5 * self.head_height_m() * (1.0 - (pi * t).cos()),
            0.5 * (self.thickness_m - self.diameter_m) * (1.0 - (2.0 * pi * t).cos()),
        )
    }

    /// The whole loop at `s ∈ [0, 2]`: the half loop up to `s = 1`, its mirror `x → w − x` back
    /// down to the next sinker. Metres, as [`LoopShape::half_loop_m`].
    pub fn loop_m(&self, s: f64) -> Vec3 {
        if s <= 1.0 {
            self.half_loop_m(s)
        } else {
            let p = self.half_loop_m(2.0 - s);
            Vec3::new(self.width_m - p.x, p.y, p.z)
        }
    }

    /// The loop's length seen along the fabric's normal, per stitch stretch: what the yarn of
    /// one stitch hides of the skin, over its diameter (see [`InPlaneLength`]).
    pub fn in_plane_length(&self) -> InPlaneLength {
        let (a, w, h) = (self.a_m, self.width_m, self.head_height_m());
        let pi = std::f64::consts::PI;
        let dt = 1.0 / LENGTH_STEPS as f64;
        // Simpson's rule over the half loop: the derivative at each node times its weight
        // (1, 4, 2, …, 4, 1) × dt / 3; the other half is its mirror, as long, hence 2×.
        let steps = std::array::from_fn(|k| {
            let t = k as f64 * dt;
            let weight = match k {
                0 | LENGTH_STEPS => 1.0,
                k if k % 2 == 1 => 4.0,
                _ => 2.0,
            };
            let scale = 2.0 * weight * dt / 3.0;
            [
                scale * (3.0 * a * t * t - 3.0 * a * t + 0.5 * (a + w)),
                scale * 0.5 * h * pi * (pi * t).sin(),
            ]
        });
        InPlaneLength { steps }
    }

    /// The loop parameters `s ∈ [0, 2)` of the samples (see [`SAMPLES_PER_LOOP`]).
    pub fn sample_parameters(&self) -> [f64; SAMPLES_PER_LOOP] {
        let [b1, b2] = self.beta;
        let half = [
            0.0,
            ARC_SAMPLE * b1,
            b1,
            0.5,
            b2,
            1.0 - ARC_SAMPLE * b1,
            1.0,
        ];
        std::array::from_fn(|k| if k < 7 { half[k] } else { 2.0 - half[12 - k] })
    }

    /// The samples in relaxed stitch units: `[u, v, z]` with `u = x / w`, `v = y / c` and `z` in
    /// metres. A zero width or height gives 0 along it.
    fn samples_uvz(&self) -> [[f64; 3]; SAMPLES_PER_LOOP] {
        let over = |x: f64, by: f64| if by > 0.0 { x / by } else { 0.0 };
        self.sample_parameters().map(|s| {
            let p = self.loop_m(s);
            [
                over(p.x, self.width_m).clamp(0.0, 1.0),
                over(p.y, self.height_m).clamp(0.0, 2.0),
                p.z,
            ]
        })
    }
}

/// Simpson intervals over a half loop for its length: 64 hold it to better than a part in 10⁶
/// (the hand check in `post::fields`' tests).
const LENGTH_STEPS: usize = 64;

/// A loop's length in the fabric's plane, `∫ √((s_c x')² + (s_w y')²) dt`, for the stitch
/// stretched `s_c` along the course and `s_w` along the wale: the loop is stretched with its
/// stitch, as [`loops`] places it (bilinearly), so this is the length the exported and
/// rendered loops have.
#[derive(Clone, Debug)]
pub struct InPlaneLength {
    /// The derivative `(x', y')` at each Simpson node, times its weight, both halves.
    steps: [[f64; 2]; LENGTH_STEPS + 1],
}

impl InPlaneLength {
    /// Metres of yarn per stitch seen along the normal at stretch `[s_c, s_w]`.
    pub fn at(&self, [s_course, s_wale]: [f64; 2]) -> f64 {
        self.steps
            .iter()
            .map(|[dx, dy]| (s_course * dx).hypot(s_wale * dy))
            .sum()
    }
}

/// The relaxed loop of each yarn kind of `fabric`, in [`YarnKind::index`] order.
pub fn loop_shapes(fabric: &Fabric) -> PerYarn<LoopShape> {
    let [w, c] = fabric.stitch_m.to_array();
    fabric.yarn_diameter_m.map(|d| LoopShape::of(w, c, d))
}

/// The yarn of `knit` (a knit of the real stitches, fitted) with every stitch a knitted loop of
/// `fabric`'s yarns (see module docs): positions in metres, course segments along the loops, the
/// toe seam's segments straight; `course`, `wale` and `yarn_kind` per point.
pub fn loops(knit: &Knit, fabric: &Fabric) -> YarnGeometry {
    let tables = loop_shapes(fabric).map(|shape| shape.samples_uvz());
    let lattice = Lattice::of(knit);
    let courses = course_chains(knit);
    let seams: Vec<(PointId, PointId)> = knit
        .yarn_springs()
        .filter(|(_, s)| s.direction != Direction::Course && s.yarn == YarnKind::Seam)
        .map(|(_, s)| (s.a, s.b))
        .collect();
    let loop_points: usize = courses.iter().map(Course::samples).sum();
    let loop_segments: usize = courses.iter().map(Course::segments).sum();
    let mut positions = vec![[0.0; 3]; loop_points];
    let mut course_attr = vec![0.0f32; loop_points];
    let mut wale_attr = vec![0.0f32; loop_points];
    let mut kind_attr = vec![0.0f32; loop_points];

    // Each course fills its own slice of the outputs, so the order is fixed whatever the threads.
    let mut jobs = Vec::with_capacity(courses.len());
    let mut rest = CourseOut {
        positions: &mut positions[..],
        course: &mut course_attr[..],
        wale: &mut wale_attr[..],
        yarn_kind: &mut kind_attr[..],
    };
    for course in &courses {
        let (out, after) = rest.split_at(course.samples());
        jobs.push((course, out));
        rest = after;
    }
    jobs.into_par_iter()
        .for_each(|(course, out)| lattice.lay(course, &tables, out));

    let mut segments = Vec::with_capacity(loop_segments + seams.len());
    let mut sinker = vec![u32::MAX; if seams.is_empty() { 0 } else { knit.len() }];
    let mut start = 0u32;
    for course in &courses {
        let n = course.samples() as u32;
        let yarn = |i: u32| {
            knit.course_yarn[course.points[(i / SAMPLES_PER_LOOP as u32) as usize].index()]
        };
        for i in 0..n - 1 {
            segments.push(course_segment(start + i, start + i + 1, yarn(i)));
        }
        if course.closed {
            segments.push(course_segment(start + n - 1, start, yarn(n - 1)));
        }
        if !sinker.is_empty() {
            for (j, p) in course.points.iter().enumerate() {
                sinker[p.index()] = start + (j * SAMPLES_PER_LOOP).min(n as usize - 1) as u32;
            }
        }
        start += n;
    }
    // A seam's end on no course (none in a knit's toe seam) gets a point of its own.
    for &(a, b) in &seams {
        let [a, b] = [a, b].map(|p| {
            if sinker[p.index()] == u32::MAX {
                sinker[p.index()] = positions.len() as u32;
                let (at, place) = (lattice.x[p.index()], lattice.coords[p.index()]);
                positions.push([at.x, at.y, at.z]);
                wale_attr.push(place.x as f32);
                course_attr.push(place.y as f32);
                kind_attr.push(knit.course_yarn[p.index()].index() as f32);
            }
            sinker[p.index()]
        });
        segments.push(Segment {
            a,
            b,
            yarn: YarnKind::Seam,
            direction: Direction::Wale,
        });
    }

    let mut point_attributes = BTreeMap::new();
    point_attributes.insert("course".to_string(), course_attr);
    point_attributes.insert("wale".to_string(), wale_attr);
    point_attributes.insert("yarn_kind".to_string(), kind_attr);
    YarnGeometry {
        name: "yarns".to_string(),
        offset_m: [0.0; 3],
        positions,
        point_attributes,
        segments,
    }
}

fn course_segment(a: u32, b: u32, yarn: YarnKind) -> Segment {
    Segment {
        a,
        b,
        yarn,
        direction: Direction::Course,
    }
}

/// What a course's loops are laid on: the fitted points, their fabric coordinates, the wales.
struct Lattice<'a> {
    x: &'a [Vec3],
    /// `[wale, course, 0]` per point ([`Knit::fabric_coords`]).
    coords: Vec<Vec3>,
    course_yarn: &'a [YarnKind],
    wales: Wales,
}

/// One course's share of the outputs, one entry per sample.
struct CourseOut<'a> {
    positions: &'a mut [[f64; 3]],
    course: &'a mut [f32],
    wale: &'a mut [f32],
    yarn_kind: &'a mut [f32],
}

impl<'a> CourseOut<'a> {
    /// The first `n` samples' share, and the rest.
    fn split_at(self, n: usize) -> (CourseOut<'a>, CourseOut<'a>) {
        let (positions, p) = self.positions.split_at_mut(n);
        let (course, c) = self.course.split_at_mut(n);
        let (wale, w) = self.wale.split_at_mut(n);
        let (yarn_kind, k) = self.yarn_kind.split_at_mut(n);
        (
            CourseOut {
                positions,
                course,
                wale,
                yarn_kind,
            },
            CourseOut {
                positions: p,
                course: c,
                wale: w,
                yarn_kind: k,
            },
        )
    }

    fn set(&mut self, i: usize, position: Vec3, place: Vec3, kind: YarnKind) {
        self.positions[i] = [position.x, position.y, position.z];
        self.wale[i] = place.x as f32;
        self.course[i] = place.y as f32;
        self.yarn_kind[i] = kind.index() as f32;
    }
}

impl Lattice<'_> {
    fn of(knit: &Knit) -> Lattice<'_> {
        Lattice {
            x: &knit.particles.x,
            coords: (0..knit.len())
                .map(|i| {
                    let [w, c] = knit.fabric_coords(PointId(i as u32));
                    Vec3::new(w, c, 0.0)
                })
                .collect(),
            course_yarn: &knit.course_yarn,
            wales: Wales::of(knit),
        }
    }

    /// Lays `course`'s loops, each stitch the samples of its yarn's `tables` (see
    /// [`LoopShape::samples_uvz`]), into `out`.
    fn lay(
        &self,
        course: &Course,
        tables: &PerYarn<[[f64; 3]; SAMPLES_PER_LOOP]>,
        mut out: CourseOut,
    ) {
        let at = |i: PointId| self.x[i.index()];
        let place = |i: PointId| self.coords[i.index()];
        let stitches = course.stitches();
        for s in 0..stitches {
            let p = course.points[s];
            let q = course.points[(s + 1) % course.points.len()];
            let kind = self.course_yarn[p.index()];
            let (xp, xq) = (
                self.wales.levels(p, at, Vec3::zeros()),
                self.wales.levels(q, at, Vec3::zeros()),
            );
            let (cp, cq) = (
                self.wales.levels(p, place, Vec3::y()),
                self.wales.levels(q, place, Vec3::y()),
            );
            let normal = outward_normal(&xp, &xq);
            for (k, &[u, v, z]) in tables[kind.index() as usize].iter().enumerate() {
                out.set(
                    s * SAMPLES_PER_LOOP + k,
                    bilinear(&xp, &xq, u, v) + normal * z,
                    bilinear(&cp, &cq, u, v),
                    kind,
                );
            }
        }
        if !course.closed {
            let last = course.points[stitches];
            let kind = self.course_yarn[course.points[stitches - 1].index()];
            out.set(stitches * SAMPLES_PER_LOOP, at(last), place(last), kind);
        }
    }
}

/// One course's yarn: its lattice points in order along the course springs.
struct Course {
    points: Vec<PointId>,
    /// The last point joins the first (a tube's ring).
    closed: bool,
}

impl Course {
    fn stitches(&self) -> usize {
        if self.closed {
            self.points.len()
        } else {
            self.points.len() - 1
        }
    }

    fn samples(&self) -> usize {
        self.stitches() * SAMPLES_PER_LOOP + usize::from(!self.closed)
    }

    fn segments(&self) -> usize {
        self.samples() - usize::from(!self.closed)
    }
}

/// The knit's courses as chains of points along its course springs (`a → b`): open chains from
/// the points with no spring arriving, in point order, then the rings, each from its
/// lowest-numbered point.
fn course_chains(knit: &Knit) -> Vec<Course> {
    let n = knit.len();
    let mut next = vec![u32::MAX; n];
    let mut has_prev = vec![false; n];
    for (_, s) in knit
        .yarn_springs()
        .filter(|(_, s)| s.direction == Direction::Course)
    {
        if next[s.a.index()] == u32::MAX && s.a != s.b {
            next[s.a.index()] = s.b.0;
            has_prev[s.b.index()] = true;
        }
    }
    let mut visited = vec![false; n];
    let mut chains = Vec::new();
    let walk = |first: usize, visited: &mut Vec<bool>| {
        let mut points = vec![PointId(first as u32)];
        visited[first] = true;
        let mut at = first;
        let mut closed = false;
        while next[at] != u32::MAX {
            let to = next[at] as usize;
            if visited[to] {
                closed = to == first;
                break;
            }
            visited[to] = true;
            points.push(PointId(to as u32));
            at = to;
        }
        Course { points, closed }
    };
    for i in 0..n {
        if next[i] != u32::MAX && !has_prev[i] && !visited[i] {
            chains.push(walk(i, &mut visited));
        }
    }
    for i in 0..n {
        if next[i] != u32::MAX && !visited[i] {
            chains.push(walk(i, &mut visited));
        }
    }
    chains.retain(|c| c.points.len() >= 2 && c.stitches() > 0);
    chains
}

/// Each point's neighbours along its wale, short rows included.
struct Wales {
    up: Vec<u32>,
    down: Vec<u32>,
}

impl Wales {
    fn of(knit: &Knit) -> Wales {
        let mut up = vec![u32::MAX; knit.len()];
        let mut down = vec![u32::MAX; knit.len()];
        for w in 0..knit.wales {
            for pair in knit.wale_chain(w).windows(2) {
                up[pair[0].index()] = pair[1].0;
                down[pair[1].index()] = pair[0].0;
            }
        }
        Wales { up, down }
    }

    fn up(&self, p: PointId) -> Option<PointId> {
        (self.up[p.index()] != u32::MAX).then(|| PointId(self.up[p.index()]))
    }

    fn down(&self, p: PointId) -> Option<PointId> {
        (self.down[p.index()] != u32::MAX).then(|| PointId(self.down[p.index()]))
    }

    /// `value` at `p` and one and two steps up its wale; past the wale's end continued straight
    /// from the step below, or by `lone_step` on a wale of one point.
    fn levels(&self, p: PointId, value: impl Fn(PointId) -> Vec3, lone_step: Vec3) -> [Vec3; 3] {
        let here = value(p);
        match self.up(p) {
            Some(up) => {
                let one = value(up);
                let two = self.up(up).map_or(2.0 * one - here, &value);
                [here, one, two]
            }
            None => {
                let step = self.down(p).map_or(lone_step, |down| here - value(down));
                [here, here + step, here + 2.0 * step]
            }
        }
    }
}

/// The point at `(u, v)` of the two quads stacked on `p`'s and `q`'s wale columns (levels 0, 1,
/// 2): `v ≤ 1` in the lower quad, `v > 1` in the upper.
fn bilinear(p: &[Vec3; 3], q: &[Vec3; 3], u: f64, v: f64) -> Vec3 {
    let column = |c: &[Vec3; 3]| {
        if v <= 1.0 {
            c[0] + (c[1] - c[0]) * v
        } else {
            c[1] + (c[2] - c[1]) * (v - 1.0)
        }
    };
    column(p) * (1.0 - u) + column(q) * u
}

/// The outward unit normal of the quad `p₀ q₀ q₁ p₁` (counter-clockwise seen from outside):
/// mean course edge × mean wale edge; where that vanishes, any direction across the course edge,
/// then across the wale edge, then +z.
fn outward_normal(p: &[Vec3; 3], q: &[Vec3; 3]) -> Vec3 {
    let along = (q[0] - p[0]) + (q[1] - p[1]);
    let up = (p[1] - p[0]) + (q[1] - q[0]);
    unit(along.cross(&up))
        .or_else(|| unit(along).map(|a| perpendicular_frame(&a).0))
        .or_else(|| unit(up).map(|a| perpendicular_frame(&a).0))
        .unwrap_or_else(Vec3::z)
}

/// `v` scaled to unit length, or `None` when it is zero or not finite. Scaled by its largest
/// component first, so that neither tiny nor huge vectors under- or overflow.
fn unit(v: Vec3) -> Option<Vec3> {
    if !v.iter().all(|c| c.is_finite()) {
        return None;
    }
    let largest = v.amax();
    if largest <= 0.0 {
        return None;
    }
    let scaled = v / largest;
    Some(scaled / scaled.norm())
}

#[cfg(test)]
mod tests {
    use std::f64::consts::TAU;

    use super::*;
    use crate::knit::nylon::yarn_diameter_m;
    use crate::knit::{Pattern, Tile};

    /// The relaxed stitch of the default stocking: 0.5 mm between wales, 0.74 mm between courses.
    const W: f64 = 0.0005;
    const C: f64 = 0.00074;

    /// The stocking's fabric: 20-den nylon, 40-den support, a 20-den seam.
    fn fabric() -> Fabric {
        Fabric {
            needles: 400.0,
            stitch_m: crate::base::PerDirection::new(W, C),
            yarn_diameter_m: [
                yarn_diameter_m(20.0),
                yarn_diameter_m(40.0),
                yarn_diameter_m(20.0),
            ],
            loop_stiffness_n_per_m: 5.0,
        }
    }

    /// A flat `wales × courses` patch in the xy-plane at exactly the relaxed stitch.
    fn patch(pattern: Pattern, wales: usize, courses: usize) -> Knit {
        Knit::grid(wales, courses, false, &Tile::of(pattern), W, C, |w, c| {
            Vec3::new(w as f64 * W, c as f64 * C, 0.0)
        })
    }

    /// A relaxed tube of `wales` stitches up +Y, its courses counter-clockwise seen from outside.
    fn tube(wales: usize, courses: usize) -> Knit {
        let radius = wales as f64 * W / TAU;
        Knit::grid(
            wales,
            courses,
            true,
            &Tile::of(Pattern::Alternating),
            W,
            C,
            |w, c| {
                let theta = TAU * w as f64 / wales as f64;
                Vec3::new(radius * theta.sin(), c as f64 * C, radius * theta.cos())
            },
        )
    }

    fn point(geometry: &YarnGeometry, i: usize) -> Vec3 {
        Vec3::from(geometry.positions[i])
    }

    /// The course segments as yarns: each connected piece must be one path or one ring (every
    /// point on at most two segments; a piece of `n` points has `n − 1` or `n` segments), with no
    /// segment longer than `longest`. Returns (paths, rings).
    fn yarns(geometry: &YarnGeometry, longest: f64) -> (usize, usize) {
        let n = geometry.positions.len();
        let mut parent: Vec<usize> = (0..n).collect();
        fn root(parent: &mut [usize], mut i: usize) -> usize {
            while parent[i] != i {
                parent[i] = parent[parent[i]];
                i = parent[i];
            }
            i
        }
        let mut degree = vec![0usize; n];
        let mut on_yarn = vec![false; n];
        let course: Vec<&Segment> = geometry
            .segments
            .iter()
            .filter(|s| s.direction == Direction::Course)
            .collect();
        for s in &course {
            let (a, b) = (s.a as usize, s.b as usize);
            let length = (point(geometry, a) - point(geometry, b)).norm();
            assert!(length < longest, "a gap: segment {a}–{b} is {length} m");
            degree[a] += 1;
            degree[b] += 1;
            on_yarn[a] = true;
            on_yarn[b] = true;
            let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
            parent[ra] = rb;
        }
        assert!(degree.iter().all(|&d| d <= 2), "a yarn branches");
        let mut points = BTreeMap::new();
        let mut edges = BTreeMap::new();
        for i in (0..n).filter(|&i| on_yarn[i]) {
            *points.entry(root(&mut parent, i)).or_insert(0usize) += 1;
        }
        for s in &course {
            *edges
                .entry(root(&mut parent, s.a as usize))
                .or_insert(0usize) += 1;
        }
        let (mut paths, mut rings) = (0, 0);
        for (r, &count) in &points {
            match edges[r] {
                e if e + 1 == count => paths += 1,
                e if e == count => rings += 1,
                e => panic!("a yarn of {count} points and {e} segments"),
            }
        }
        (paths, rings)
    }

    #[test]
    fn hosiery_loops_have_a_positive_overlap_and_touching_legs_at_the_knot() {
        for (denier, kind) in [(20.0, YarnKind::Nylon), (40.0, YarnKind::Support)] {
            let shape = loop_shapes(&fabric())[kind.index() as usize];
            let d = yarn_diameter_m(denier);
            let [b1, b2] = shape.beta;
            eprintln!(
                "{denier} den (d = {:.1} µm): a = {:.4} mm ({:.3} w), e = {:.4} mm, t_h = {:.1} µm, \
                 β = {b1:.4}, {b2:.4}, head {:.4} mm above the sinker",
                d * 1e6,
                shape.a_m * 1e3,
                shape.a_m / W,
                shape.e_m * 1e3,
                shape.thickness_m * 1e6,
                shape.head_height_m() * 1e3
            );
            assert!(shape.a_m > 2.0 * W && shape.e_m > 0.0 && shape.e_m < 0.5 * C);
            assert!(b1 < 0.5 && 0.5 < b2);
            let (neck, bulge) = (shape.half_loop_m(b1), shape.half_loop_m(b2));
            // The closed form and the curve agree, and the legs are χ d apart.
            let s = ((shape.a_m - 2.0 * W) / (3.0 * shape.a_m)).sqrt();
            assert!((s * (shape.a_m - 2.0 * W) / 6.0 - d).abs() < 1e-12);
            assert!((neck.x - bulge.x - KNOT_SEPARATION * d).abs() < 1e-12);
            // They are the x extremes: no denser sample of the leg goes beyond them.
            for k in 0..=1000 {
                let t = k as f64 / 1000.0;
                let x = shape.half_loop_m(t).x;
                assert!(t > b2 || x <= neck.x + 1e-15, "{t}: {x} beyond the neck");
                assert!(t < b1 || x >= bulge.x - 1e-15, "{t}: {x} beyond the head");
            }
            // The head's widest point is level with the next course's neck.
            assert!((bulge.y - (C + neck.y)).abs() < 1e-12);
            assert!(
                (shape.half_loop_m(1.0) - Vec3::new(0.5 * W, C + 2.0 * shape.e_m, 0.0)).norm()
                    < 1e-15
            );
        }
    }

    #[test]
    fn thin_and_degenerate_yarns_give_finite_clamped_loops() {
        for d in [
            0.0,
            1e-9,
            W / 18.0,
            W / 2.0,
            W,
            f64::NAN,
            f64::INFINITY,
            -1.0,
        ] {
            let shape = LoopShape::of(W, C, d);
            assert!(
                shape.e_m > 0.0 && shape.e_m <= 0.5 * C,
                "{d}: e = {}",
                shape.e_m
            );
            for s in shape.sample_parameters() {
                let p = shape.loop_m(s);
                assert!(p.iter().all(|c| c.is_finite()), "{d}");
                assert!((0.0..=W).contains(&p.x), "{d}: the loop leaves its stitch");
            }
        }
    }

    #[test]
    fn the_polyline_follows_the_loop_within_two_fifths_of_a_diameter() {
        for shape in &loop_shapes(&fabric())[..2] {
            let s = shape.sample_parameters();
            let mut worst: f64 = 0.0;
            for k in 0..SAMPLES_PER_LOOP {
                let (s0, s1) = (
                    s[k],
                    if k + 1 < SAMPLES_PER_LOOP {
                        s[k + 1]
                    } else {
                        2.0
                    },
                );
                let (a, b) = (shape.loop_m(s0), shape.loop_m(s1));
                for j in 0..=200 {
                    let p = shape.loop_m(s0 + (s1 - s0) * j as f64 / 200.0);
                    let h = ((p - a).dot(&(b - a)) / (b - a).norm_squared()).clamp(0.0, 1.0);
                    worst = worst.max((p - a - (b - a) * h).norm());
                }
            }
            eprintln!(
                "polyline within {:.1} µm = {:.2} d of the curve",
                worst * 1e6,
                worst / shape.diameter_m
            );
            assert!(worst < 0.4 * shape.diameter_m, "{worst}");
        }
    }

    #[test]
    fn a_relaxed_patch_has_the_models_knot_head_and_thickness() {
        let fabric = fabric();
        let shapes = loop_shapes(&fabric);
        let (wales, courses) = (6, 5);
        for pattern in [Pattern::Plain, Pattern::Alternating] {
            let knit = patch(pattern, wales, courses);
            let geometry = loops(&knit, &fabric);
            let per_course = (wales - 1) * SAMPLES_PER_LOOP + 1;
            assert_eq!(geometry.positions.len(), courses * per_course);
            assert_eq!(yarns(&geometry, W), (courses, 0));
            let sample = |c: usize, stitch: usize, k: usize| {
                point(&geometry, c * per_course + stitch * SAMPLES_PER_LOOP + k)
            };
            for c in 0..courses {
                let shape = &shapes[knit.course_yarn[knit.point(0, c).index()].index() as usize];
                let d = shape.diameter_m;
                for stitch in 0..wales - 1 {
                    let sinker = sample(c, stitch, 0);
                    assert!(
                        (sinker - knit.particles.x[knit.point(stitch, c).index()]).norm() < 1e-15
                    );
                    // The head's top: c + 2e above the sinker, half a stitch along.
                    let top = sample(c, stitch, 6) - sinker;
                    assert!((top - Vec3::new(0.5 * W, shape.head_height_m(), 0.0)).norm() < 1e-12);
                    // Within a loop, neck and head's widest are χ d apart, on both legs.
                    for (neck, bulge) in [(2, 4), (10, 8)] {
                        let gap = (sample(c, stitch, neck).x - sample(c, stitch, bulge).x).abs();
                        assert!((gap - d).abs() < 1e-12, "{gap} vs {d}");
                    }
                    // The next course's neck passes inside this head, level with its widest point
                    // (each yarn's `e` is its own: between two yarns, within the thicker's
                    // diameter), the two yarns' centres the mean of their diameters apart.
                    if c + 1 < courses {
                        let above = &shapes
                            [knit.course_yarn[knit.point(0, c + 1).index()].index() as usize];
                        let (neck, bulge) = (sample(c + 1, stitch, 2), sample(c, stitch, 4));
                        let level = if above == shape {
                            1e-12
                        } else {
                            d.max(above.diameter_m)
                        };
                        assert!(
                            (neck.y - bulge.y).abs() < level,
                            "{pattern:?}: {} vs {}",
                            neck.y,
                            bulge.y
                        );
                        let gap = neck.x - bulge.x;
                        assert!((gap - 0.5 * (d + above.diameter_m)).abs() < 1e-12, "{gap}");
                    }
                }
            }
            // z: off the skin, no higher than t_h − d, which the legs' middles reach.
            for (i, p) in geometry.positions.iter().enumerate() {
                let kind = geometry.point_attributes["yarn_kind"][i] as usize;
                let rise = shapes[kind].thickness_m - shapes[kind].diameter_m;
                assert!(p[2] >= 0.0 && p[2] <= rise + 1e-15, "{i}: z = {}", p[2]);
            }
            let nylon = &shapes[0];
            assert!((sample(0, 0, 3).z - (nylon.thickness_m - nylon.diameter_m)).abs() < 1e-15);
        }
    }

    #[test]
    fn a_tubes_courses_are_rings_with_their_loops_outside() {
        let (wales, courses) = (24, 4);
        let knit = tube(wales, courses);
        let geometry = loops(&knit, &fabric());
        assert_eq!(geometry.positions.len(), courses * wales * SAMPLES_PER_LOOP);
        assert_eq!(geometry.segments.len(), courses * wales * SAMPLES_PER_LOOP);
        assert_eq!(yarns(&geometry, W), (0, courses));
        let radius = wales as f64 * W / TAU;
        for (i, p) in geometry.positions.iter().enumerate() {
            let r = p[0].hypot(p[2]);
            // Chords cut inside the circle by at most r (1 − cos(π / wales)); z lifts outside.
            assert!(
                r > radius * (TAU / 2.0 / wales as f64).cos() - 1e-12,
                "{i}: {r}"
            );
        }
        // Each leg's middle stands out from the ring by about t_h − d.
        let d = yarn_diameter_m(20.0);
        let middle = point(&geometry, 3);
        assert!(middle.x.hypot(middle.z) > radius + 0.5 * d);
    }

    #[test]
    fn every_sample_stays_among_its_stitchs_points_and_none_is_nan() {
        // A crumpled patch: every point moved by a fixed pseudo-random amount up to half a stitch.
        let (wales, courses) = (7, 6);
        let jitter = |w: usize, c: usize, axis: usize| {
            let h = ((w * 73 + c * 151 + axis * 37) as f64 * 12.9898).sin() * 43758.5453;
            (h - h.floor() - 0.5) * W
        };
        let knit = Knit::grid(
            wales,
            courses,
            false,
            &Tile::of(Pattern::Alternating),
            W,
            C,
            |w, c| {
                Vec3::new(
                    w as f64 * W + jitter(w, c, 0),
                    c as f64 * C + jitter(w, c, 1),
                    jitter(w, c, 2),
                )
            },
        );
        let fabric = fabric();
        let geometry = loops(&knit, &fabric);
        let x = |w: usize, c: usize| knit.particles.x[knit.point(w, c).index()];
        // A column's points one and two steps up, continued straight past the last course.
        let column = |w: usize, c: usize| -> [Vec3; 3] {
            let at = |k: usize| {
                if c + k < courses {
                    x(w, c + k)
                } else {
                    let top = x(w, courses - 1);
                    top + (top - x(w, courses - 2)) * (c + k + 1 - courses) as f64
                }
            };
            [at(0), at(1), at(2)]
        };
        let per_course = (wales - 1) * SAMPLES_PER_LOOP + 1;
        let lift = 2.0 * yarn_diameter_m(40.0);
        for c in 0..courses {
            for stitch in 0..wales - 1 {
                let corners: Vec<Vec3> = column(stitch, c)
                    .into_iter()
                    .chain(column(stitch + 1, c))
                    .collect();
                let lo = corners.iter().fold(Vec3::repeat(f64::MAX), |m, p| m.inf(p))
                    - Vec3::repeat(lift);
                let hi = corners.iter().fold(Vec3::repeat(f64::MIN), |m, p| m.sup(p))
                    + Vec3::repeat(lift);
                for k in 0..SAMPLES_PER_LOOP {
                    let p = point(&geometry, c * per_course + stitch * SAMPLES_PER_LOOP + k);
                    assert!(
                        p.iter()
                            .zip(lo.iter().zip(hi.iter()))
                            .all(|(v, (l, h))| l <= v && v <= h),
                        "course {c}, stitch {stitch}, sample {k}: {p:?} outside {lo:?}–{hi:?}"
                    );
                }
            }
        }
        assert_eq!(yarns(&geometry, 4.0 * W), (courses, 0));

        // Every point in one place, and a row of them: finite, one yarn per course still.
        let places: [fn(usize, usize) -> Vec3; 3] = [
            |_: usize, _: usize| Vec3::zeros(),
            |w: usize, _: usize| Vec3::new(w as f64 * W, 0.0, 0.0),
            |_: usize, c: usize| Vec3::new(0.0, c as f64 * C, 0.0),
        ];
        for place in places {
            let knit = Knit::grid(5, 4, false, &Tile::of(Pattern::Alternating), W, C, place);
            let geometry = loops(&knit, &fabric);
            assert!(geometry.positions.iter().flatten().all(|v| v.is_finite()));
            assert!(geometry
                .point_attributes
                .values()
                .flatten()
                .all(|v| v.is_finite()));
            assert_eq!(yarns(&geometry, 4.0 * W), (4, 0));
        }
        let single = Knit::grid(5, 1, true, &Tile::of(Pattern::Plain), W, C, |w, _| {
            Vec3::new(w as f64 * W, 0.0, 0.0)
        });
        assert!(loops(&single, &fabric)
            .positions
            .iter()
            .flatten()
            .all(|v| v.is_finite()));
    }

    #[test]
    fn short_rows_and_a_toe_seam_keep_every_course_one_yarn() {
        // The shaped tube of the surfaces' tests at the real stitch: 8 wales, a pocket of four
        // short rows over wales 5–1 (depths 1 at the sides, 2 in the middle), a toe seam.
        let wales = 8;
        let radius = wales as f64 * W / TAU;
        let tile = Tile::of(Pattern::Alternating);
        let at = |w: usize, c: f64| {
            let theta = TAU * w as f64 / wales as f64;
            Vec3::new(radius * theta.sin(), c * C, radius * theta.cos())
        };
        let knit = Knit::grid(wales, 5, true, &tile, W, C, |w, c| at(w, c as f64))
            .with_toe_seam(C)
            .with_short_rows(1, vec![2, 1, 0, 0, 0, 1, 2, 2], &tile, W, C, |w, f| {
                at(w, 1.0 + f)
            });
        let geometry = loops(&knit, &fabric());
        assert!(geometry.positions.iter().flatten().all(|v| v.is_finite()));
        // Five grid rings; rows 1 and 4 run over wales 5, 6, 7, 0, 1; rows 2 and 3 over 6, 7, 0.
        assert_eq!(yarns(&geometry, 4.0 * W), (4, 5));
        let seams: Vec<&Segment> = geometry
            .segments
            .iter()
            .filter(|s| s.yarn == YarnKind::Seam)
            .collect();
        assert_eq!(
            seams.len(),
            knit.yarn_springs()
                .filter(|(_, s)| s.yarn == YarnKind::Seam)
                .count()
        );
        assert!(!seams.is_empty());
        // The seam joins the last course's sinkers, which are its lattice points.
        for s in seams {
            assert_eq!(s.direction, Direction::Wale);
            for end in [s.a, s.b] {
                let p = point(&geometry, end as usize);
                assert!(knit.particles.x.iter().any(|x| (x - p).norm() < 1e-15));
                assert!((geometry.point_attributes["course"][end as usize] - 4.0).abs() < 1e-6);
            }
        }
        assert_eq!(
            loops(&knit, &fabric()),
            geometry,
            "the same knit gives the same yarn"
        );
    }
}
