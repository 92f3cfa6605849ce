//! Sliding contact as in Sakaguchi & Miyata §6.2 (Fig. 13): a point's move is kept up to where it
//! meets the leg, and the part that would go inside is projected onto the surface it hit, so the
//! point slides. We keep the yarn's centre line `offset` (the yarn radius) off the skin, repeat the
//! projection when the slide meets another face (concave regions), and finish with a check
//! against the closest point: a point never ends a step inside the leg.
//!
//! The tube's end rings are also held at their heights along the axis (they may still shrink
//! radially), which keeps the stocking stretched between the two axis points.
//!
//! Exact queries are skipped where they cannot change the answer:
//! * a point away from the leg keeps a lower bound on its distance to the surface (from its last
//!   exact query, minus how far it has moved since) and is only queried when its move could use
//!   up that clearance;
//! * a point resting on the leg keeps the tangent plane of its last exact query and slides on that
//!   plane until it has moved [`PLANE_REUSE_M`] from where the plane was taken, within which a
//!   surface whose radius of curvature is at least 1 cm departs from its tangent plane by under
//!   13 µm, less than half the default yarn offset (30 µm), so the point stays outside.
//!   Sharper creases and coarse facets can let it dip a few micrometres: the exact pass after the
//!   fit ([`LegContact::finish`]) moves such points out. A point that rises off its plane by more
//!   than half the offset (the most an exact query calls touching) stops touching there and is
//!   queried on its next move (docs/decisions/0031).
//!
//! The plane cache is also what lets tight tolerances converge: an exact query on a faceted leg
//! can put a point on another facet's plane, a jump the forces then have to settle again, and
//! the cache makes those jumps rare. Why [`PLANE_REUSE_M`] does not shrink with the tolerance:
//! docs/decisions/0027.

use nalgebra::Point3;
use rayon::prelude::*;

use super::Constraints;
use crate::base::Vec3;
use crate::leg::{Closest, Collider};

/// How many in-plane pushes a held end-ring point gets before it is pushed along the normal.
const PUSH_TRIES: usize = 4;
/// How many times one move may slide from face to face before it stops where it is.
const MAX_SLIDES: usize = 4;
/// Points per parallel chunk, at most: a small knit is split in at least 16 chunks (down to
/// [`MIN_CHUNK`] points), as its moves are long and its queries many, and two chunks of
/// unequal size left one thread with most of them. Counters are the only sums, so the split
/// changes no result.
const CHUNK: usize = 1024;
/// Points per parallel chunk, at least.
const MIN_CHUNK: usize = 64;

/// Points per parallel chunk for a knit of `points` points.
fn chunk_for(points: usize) -> usize {
    (points / 16).clamp(MIN_CHUNK, CHUNK)
}
/// How far a point may slide on a cached tangent plane before it is queried again, metres: the
/// plane departs from a skin of 1 cm radius by `d² / 2R` = 12.5 µm there, under half the default
/// yarn offset (module docs).
pub const PLANE_REUSE_M: f64 = 0.0005;

/// Per-point contact bookkeeping, besides the normal (kept in its own array, as every force
/// evaluation reads it and nothing else of this).
#[derive(Clone, Copy, Debug, Default)]
struct PointContact {
    /// Lower bound on the distance to the surface, metres (0 = unknown: query).
    clearance: f64,
    /// A point of the plane the point slides on while touching (surface + offset · normal).
    plane_point: Vec3,
    /// Where the point was at its last exact query.
    queried_at: Vec3,
}

/// Counters for the report.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactCounters {
    /// Exact closest-point queries made.
    pub closest_queries: u64,
    /// Moves that hit the leg and slid.
    pub slides: u64,
    /// Points pushed back out by the final check (a slide that ended inside).
    pub pushed_out: u64,
    /// Points the exact pass after the fit ([`LegContact::finish`]) moved out to the offset.
    pub finished_out: u64,
    /// Points moved out when a level of the multilevel solver started from positions
    /// interpolated from the coarser level ([`Constraints::settle`]).
    pub settled_out: u64,
}

impl ContactCounters {
    /// Adds another chunk's counts to these.
    pub fn add(&mut self, other: &ContactCounters) {
        self.closest_queries += other.closest_queries;
        self.slides += other.slides;
        self.pushed_out += other.pushed_out;
        self.finished_out += other.finished_out;
        self.settled_out += other.settled_out;
    }
}

/// Contact with the leg plus the tube's locked end rings.
pub struct LegContact<'a> {
    collider: &'a Collider,
    offset: f64,
    /// Beyond this distance a point is not queried exactly: a multiple of the rest spacing.
    query_radius: f64,
    axis: Vec3,
    axially_locked: Vec<bool>,
    state: Vec<PointContact>,
    /// Per point, the outward normal of the surface it rests on, or zero when it is not touching.
    normals: Vec<Vec3>,
    counters: ContactCounters,
}

/// What a single point's contact needs, shared by all points of a step.
#[derive(Clone, Copy)]
struct SlideParams<'a> {
    collider: &'a Collider,
    offset: f64,
    query_radius: f64,
    axis: Vec3,
}

impl<'a> LegContact<'a> {
    /// Contact for `points` points against `collider`, keeping `offset` metres off the skin.
    /// Points flagged in `axially_locked` cannot move along `axis` (a unit vector).
    /// `query_radius` bounds the distance exact queries look (metres; larger is safe, slower).
    pub fn new(
        collider: &'a Collider,
        offset: f64,
        query_radius: f64,
        axis: Vec3,
        axially_locked: Vec<bool>,
    ) -> LegContact<'a> {
        let points = axially_locked.len();
        LegContact {
            collider,
            offset,
            query_radius,
            axis,
            axially_locked,
            state: vec![PointContact::default(); points],
            normals: vec![Vec3::zeros(); points],
            counters: ContactCounters::default(),
        }
    }

    /// What contact has done so far.
    pub fn counters(&self) -> ContactCounters {
        self.counters
    }

    /// What one point's contact needs, copied out so parallel chunks can share it.
    fn slide_params(&self) -> SlideParams<'a> {
        SlideParams {
            collider: self.collider,
            offset: self.offset,
            query_radius: self.query_radius,
            axis: self.axis,
        }
    }

    /// The exact pass after the fit: every point is checked against the exact triangles and
    /// any closer than the offset is moved out to it, as the final check of a slide would. During
    /// the fit a point resting on the leg slides on a cached tangent plane, which a sharp crease
    /// or a coarse mesh can dip below by a few micrometres; this pass is what makes "no yarn
    /// point inside the leg" exact. Points with `inv_mass` 0 are left alone.
    pub fn finish(&mut self, x: &mut [Vec3], inv_mass: &[f64]) {
        let moved = self.push_out_all(x, inv_mass);
        self.counters.finished_out += moved;
    }

    /// [`LegContact::finish`] against `exact` instead of the surface the fit slid on: where the
    /// fit's contact saw a simplified leg (toes boxed), the last word is the leg's own skin.
    pub fn finish_on(&mut self, exact: &'a Collider, x: &mut [Vec3], inv_mass: &[f64]) {
        self.collider = exact;
        self.finish(x, inv_mass);
    }

    /// Moves every free point closer to the skin than the offset (or inside) out to it, by exact
    /// queries; returns how many moved.
    fn push_out_all(&mut self, x: &mut [Vec3], inv_mass: &[f64]) -> u64 {
        let params = self.slide_params();
        let locked = &self.axially_locked;
        let size = chunk_for(x.len());
        let counters: Vec<(ContactCounters, u64)> = x
            .par_chunks_mut(size)
            .enumerate()
            .map(|(chunk, x)| {
                let mut counters = ContactCounters::default();
                let mut moved = 0;
                for (k, p) in x.iter_mut().enumerate() {
                    let i = chunk * size + k;
                    if inv_mass[i] == 0.0 {
                        continue;
                    }
                    let at = Point3::from(*p);
                    counters.closest_queries += 1;
                    if let Some(c) = params.collider.closest_within(&at, params.query_radius) {
                        if c.signed_distance < params.offset * (1.0 - 1e-6) {
                            *p = params.push_out(&at, &c, locked[i], &mut counters).0.coords;
                            moved += 1;
                        }
                    }
                }
                (counters, moved)
            })
            .collect();
        let mut moved = 0;
        for (c, m) in counters {
            self.counters.add(&c);
            moved += m;
        }
        moved
    }
}

impl SlideParams<'_> {
    /// Where a point too close to (or inside) the leg goes: `offset` out along the normal, or,
    /// for a point held at its height, out within its ring's plane (up to [`PUSH_TRIES`]
    /// pushes), falling back to the normal, the lesser evil, where that does not clear it.
    /// Returns the new position and the closest point that goes with it.
    fn push_out(
        &self,
        p: &Point3<f64>,
        c: &Closest,
        locked: bool,
        counters: &mut ContactCounters,
    ) -> (Point3<f64>, Closest) {
        let along_normal = |c: &Closest| c.point + c.outward * self.offset;
        if !locked {
            return (along_normal(c), *c);
        }
        // Moving along in_plane / len gains len of distance per unit if the surface is flat:
        // check, and push again from the new closest point where it fell short (a curved or
        // faceted surface). Where that does not settle (beside an open cut, or a surface nearly
        // square to the axis), go out along the normal after all.
        let (mut q, mut c) = (*p, *c);
        for _ in 0..PUSH_TRIES {
            let in_plane = c.outward - self.axis * c.outward.dot(&self.axis);
            let len = in_plane.norm();
            if len <= 0.3 {
                break;
            }
            let needed = self.offset - c.signed_distance;
            q += in_plane / len * (needed / len);
            counters.closest_queries += 1;
            match self.collider.closest_within(&q, self.query_radius) {
                Some(again) if again.signed_distance < self.offset * (1.0 - 1e-3) => c = again,
                Some(again) => return (q, again),
                None => return (q, c),
            }
        }
        (along_normal(&c), c)
    }

    /// The closest point of the leg for the check that ends a move: within the query radius,
    /// or, where nothing is that close, at any distance if `p` is inside, since a point that
    /// started a little inside and moved deeper than the radius must still be brought out.
    /// `None`: `p` is outside and further than the radius.
    fn closest_for_check(
        &self,
        p: &Point3<f64>,
        counters: &mut ContactCounters,
    ) -> Option<Closest> {
        self.collider
            .closest_within(p, self.query_radius)
            .or_else(|| {
                counters.closest_queries += 1;
                Some(self.collider.closest(p)).filter(|c| c.signed_distance < 0.0)
            })
    }

    /// Where a free point moving from `from` towards `to` may go, updating its contact state.
    fn constrain_point(
        &self,
        from: &Vec3,
        to: &Vec3,
        locked: bool,
        state: &mut PointContact,
        normal: &mut Vec3,
        counters: &mut ContactCounters,
    ) -> Vec3 {
        let mut delta = to - from;
        if locked {
            delta -= self.axis * delta.dot(&self.axis);
        }
        let to = from + delta;
        let touching = *normal != Vec3::zeros();
        let on_plane =
            touching && (to - state.queried_at).norm_squared() < PLANE_REUSE_M * PLANE_REUSE_M;
        if let Some(slid) = on_plane
            .then(|| self.onto_cached_plane(&to, locked, state, normal))
            .flatten()
        {
            if (slid - state.plane_point).dot(normal) > 0.5 * self.offset {
                // Risen off its plane by more than an exact query would call touching: nothing
                // holds it any more, and its next move queries again. Kept touching, it had the
                // force that presses it back held while momentum carried it on up, until the
                // plane expired and the whole force came back at once (module docs).
                *normal = Vec3::zeros();
                state.clearance = 0.0;
            }
            slid
        } else if !touching && delta.norm() + self.offset < state.clearance {
            // Cannot reach the leg this step: move freely, spend clearance.
            state.clearance -= delta.norm();
            to
        } else {
            let (p, new_state, new_normal) = self.slide(from, delta, locked, counters);
            (*state, *normal) = (new_state, new_normal);
            p
        }
    }

    /// Slides a point that moved to `to` on its cached tangent plane: the part of the move below
    /// the plane is dropped, along the normal, or for a point held at its height, within its
    /// ring's plane (dropping it along the normal and then removing the axial part would put it
    /// back below a tilted plane). `None` when the plane is too steep to slide on within the ring
    /// (its normal nearly along the axis): the caller queries exactly.
    fn onto_cached_plane(
        &self,
        to: &Vec3,
        locked: bool,
        state: &PointContact,
        n: &Vec3,
    ) -> Option<Vec3> {
        let n = *n;
        let below = (to - state.plane_point).dot(&n);
        if below >= 0.0 {
            return Some(*to);
        }
        if !locked {
            return Some(to - n * below);
        }
        let in_plane = n - self.axis * n.dot(&self.axis);
        let len = in_plane.norm();
        // Moving along in_plane / len gains len of height above the plane per unit.
        (len > 0.3).then(|| to - in_plane / len * (below / len))
    }

    /// Moves a point from `from` by `delta`, sliding on the leg; returns where it ends with its
    /// new contact state and normal. A slide that runs out of [`MAX_SLIDES`] stops there.
    /// A `locked` point's moves keep no component along the axis.
    fn slide(
        &self,
        from: &Vec3,
        mut delta: Vec3,
        locked: bool,
        counters: &mut ContactCounters,
    ) -> (Vec3, PointContact, Vec3) {
        let mut p = Point3::from(*from);
        for _ in 0..MAX_SLIDES {
            if locked {
                delta -= self.axis * delta.dot(&self.axis);
            }
            let len = delta.norm();
            if len.is_nan() || len <= 0.0 {
                break;
            }
            if len < 0.5 * self.offset {
                // Too short to pass through any part of a leg: no ray needed, the closest-point
                // check below catches a move that ends inside.
                p += delta;
                break;
            }
            let dir = delta / len;
            match self.collider.first_hit(&p, &dir, len + self.offset) {
                None => {
                    p += delta;
                    break;
                }
                Some((toi, n)) => {
                    counters.slides += 1;
                    // Stop where the centre line is `offset` off the face (at most back to the
                    // start), then keep only the tangential part of what is left of the move.
                    let cos = (-dir.dot(&n)).max(1e-3);
                    let advance = (toi - self.offset / cos).max(0.0);
                    p += dir * advance;
                    let rest = delta - dir * advance;
                    delta = rest - n * rest.dot(&n).min(0.0);
                }
            }
        }
        // Final check against the closest point: never end inside, never closer than offset.
        counters.closest_queries += 1;
        let (state, normal) = match self.closest_for_check(&p, counters) {
            Some(mut c) => {
                if c.signed_distance < self.offset * (1.0 - 1e-6) {
                    if c.signed_distance < 0.0 {
                        counters.pushed_out += 1;
                    }
                    (p, c) = self.push_out(&p, &c, locked, counters);
                }
                let gap = c.signed_distance.max(self.offset);
                let touching = gap <= self.offset * 1.5 + 1e-9;
                let state = PointContact {
                    clearance: gap,
                    plane_point: c.point.coords + c.outward * self.offset,
                    queried_at: p.coords,
                };
                (state, if touching { c.outward } else { Vec3::zeros() })
            }
            None => {
                let state = PointContact {
                    clearance: self.query_radius,
                    queried_at: p.coords,
                    ..PointContact::default()
                };
                (state, Vec3::zeros())
            }
        };
        (p.coords, state, normal)
    }
}

impl Constraints for LegContact<'_> {
    fn constrain(&mut self, from: &[Vec3], x: &mut [Vec3], inv_mass: &[f64]) {
        let params = self.slide_params();
        let locked = &self.axially_locked;
        let size = chunk_for(x.len());
        let counters: Vec<ContactCounters> = self
            .state
            .par_chunks_mut(size)
            .zip(self.normals.par_chunks_mut(size))
            .zip(x.par_chunks_mut(size))
            .zip(from.par_chunks(size))
            .enumerate()
            .map(|(chunk, (((states, normals), x), from))| {
                let mut counters = ContactCounters::default();
                for k in 0..x.len() {
                    let i = chunk * size + k;
                    if inv_mass[i] > 0.0 {
                        x[k] = params.constrain_point(
                            &from[k],
                            &x[k],
                            locked[i],
                            &mut states[k],
                            &mut normals[k],
                            &mut counters,
                        );
                    }
                }
                counters
            })
            .collect();
        for c in counters {
            self.counters.add(&c);
        }
    }

    fn settle(&mut self, x: &mut [Vec3], inv_mass: &[f64]) {
        // Forget cached planes and clearances: they belong to positions before the jump.
        self.state.fill(PointContact::default());
        self.normals.fill(Vec3::zeros());
        let moved = self.push_out_all(x, inv_mass);
        self.counters.settled_out += moved;
    }

    fn unheld_forces_from(&self, first: usize, forces: &mut [Vec3]) {
        let range = first..first + forces.len();
        let (normals, locked) = (&self.normals[range.clone()], &self.axially_locked[range]);
        for ((f, n), &locked) in forces.iter_mut().zip(normals).zip(locked) {
            *f = self.unheld_at(n, locked, f);
        }
    }

    fn unheld_force(&self, i: usize, f: &Vec3) -> Vec3 {
        self.unheld_at(&self.normals[i], self.axially_locked[i], f)
    }
}

impl LegContact<'_> {
    /// The unheld part of force `f` on a point with contact normal `n` (zero when not touching),
    /// held at its height when `locked`.
    #[inline]
    fn unheld_at(&self, n: &Vec3, locked: bool, f: &Vec3) -> Vec3 {
        let n = *n;
        if locked {
            let in_plane = f - self.axis * f.dot(&self.axis);
            if in_plane.dot(&n) >= 0.0 {
                return in_plane;
            }
            // Pressed onto the leg and held at its height: only sliding around the ring, along
            // axis × normal, is free.
            let along = self.axis.cross(&n);
            let len = along.norm();
            if len > 1e-9 {
                let t = along / len;
                t * in_plane.dot(&t)
            } else {
                Vec3::zeros()
            }
        } else {
            let into_leg = f.dot(&n);
            if into_leg < 0.0 {
                f - n * into_leg
            } else {
                *f
            }
        }
    }
}
