//! The path a whole stocking starts from: down the leg's bent axis (thigh, knee, ankle), around
//! the heel and along the foot to the toe, as a sequence of plane sections of the leg
//! ([`Station`]s) that the tube's rings are placed around.
//!
//! Method. The leg part follows the centres thigh top → knee → ankle, its planes square to that
//! polyline (the turn at the knee spread over [`KNEE_BLEND_M`] either side, so neighbouring
//! rings do not cross). The foot part is a run of planes square to the foot's direction. Between
//! them the heel is a fan of planes about one line across the front of the ankle, the *pivot*,
//! placed [`PIVOT_CLEARANCE_M`] in front of the shin and above the instep: every plane of the fan
//! passes through it, so the rings around the heel (the heel–instep diagonal among them) meet
//! only there, outside the skin, and never cross one another. This is how a heel-less tube lies
//! on a foot: bunched over the front of the ankle, spread over the heel.
//!
//! Each station keeps the convex hull of its section (the loop around the previous station's
//! centre; at the toes, every loop near it, so separate toes count as one section), as its
//! extent from the hull's centre at [`RADIUS_SAMPLES`] angles. A ring is placed at a given
//! distance along the centres, around the larger extent of the two stations either side, with a
//! margin: every ring starts clear of the skin, and the tube is a different mesh at each grid
//! size of the same path.

use nalgebra::{Point3, Vector3};

use crate::leg::{slice, Landmarks};

/// Distance between stations along the leg and the foot, metres.
pub const STATION_STEP_M: f64 = 0.0025;
/// How far the heel's pivot is kept in front of the shin and above the instep, metres.
pub const PIVOT_CLEARANCE_M: f64 = 0.015;
/// Half the length over which the planes turn at the knee, metres.
pub const KNEE_BLEND_M: f64 = 0.08;
/// Planes in the heel's fan.
pub const FAN_STATIONS: usize = 48;
/// The last station lies this far behind the toe tip, metres: closer, the section is too small
/// to place a ring around, and the toe seam covers the rest.
pub const TOE_END_M: f64 = 0.004;
/// How far the toe box reaches past the toe tip, metres.
const TOE_BOX_PAST_M: f64 = 0.002;
/// A foot section whose area is below this fraction of its hull's dips between toes.
const TOE_CLEFT_SOLIDITY: f64 = 0.95;
/// The toe box starts this far before the first section that dips between toes, metres: its
/// open rim must lie where the hull fits the skin, or fabric slips under the rim and chatters
/// there (at 400 wales the fit never settled).
const TOE_BOX_LEAD_M: f64 = 0.02;
/// Skin this close outside the toe box is replaced by it too, metres.
const TOE_BOX_SLACK_M: f64 = 0.005;
/// Angles at which a station keeps its section's extent.
pub const RADIUS_SAMPLES: usize = 128;
/// Gap kept between the leg and a ring before the fit, as a fraction of the ring's extent.
const RADIAL_MARGIN: f64 = 0.08;
/// Gap kept in any case, metres.
const MIN_GAP_M: f64 = 0.003;

/// Which part of the leg a station is on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PathPart {
    /// From the thigh down to the ankle.
    Leg,
    /// The fan around the heel.
    Heel,
    /// Along the foot to the toe.
    Foot,
}

/// One plane section of the leg on the path.
#[derive(Clone, Debug)]
pub struct Station {
    /// Centre of the section's hull.
    pub centre: Point3<f64>,
    /// Unit normal of the plane, pointing on along the path (towards the toe).
    pub t: Vector3<f64>,
    /// Unit vector across the leg, side to side, square to `t`.
    pub u: Vector3<f64>,
    /// `t × u`: front of the leg on the leg part, top of the foot on the foot part.
    pub v: Vector3<f64>,
    /// Distance along the centres from the first station, metres.
    pub s: f64,
    /// The part of the leg.
    pub part: PathPart,
    /// The hull's extent from `centre` at angle `2π k / RADIUS_SAMPLES` from `u` towards `v`.
    extent: Vec<f64>,
    /// The section's area over its hull's: 1 where the section is convex, less where the
    /// skin dips between toes.
    solidity: f64,
}

/// The whole path, first station at the stocking's top.
#[derive(Clone, Debug)]
pub struct TubePath {
    /// Stations from the top to the toe.
    pub stations: Vec<Station>,
    /// The heel fan's pivot line passes through here (along the stations' `u`).
    pub pivot: Point3<f64>,
    /// The toes as the stocking meets them: the sections' convex hulls from just before the
    /// toes' clefts to the last section (see [`TubePath::box_the_toes`]).
    pub toes: Vec<Station>,
}

impl TubePath {
    /// Length along the centres, metres.
    pub fn length(&self) -> f64 {
        self.stations.last().map_or(0.0, |s| s.s)
    }

    /// The centres, top to toe: the stocking's centreline.
    pub fn centreline(&self) -> Vec<Point3<f64>> {
        self.stations.iter().map(|s| s.centre).collect()
    }

    /// Distance along the path where the heel's fan starts and ends, metres.
    pub fn heel_range(&self) -> [f64; 2] {
        let heel = self.stations.iter().filter(|s| s.part == PathPart::Heel);
        let (lo, hi) = heel.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), s| {
            (lo.min(s.s), hi.max(s.s))
        });
        [lo, hi]
    }

    /// The ring of `wales` points at distance `s` along the path (see module docs), each
    /// clear of the section by a margin. Wale `w` lies at angle `2π w / wales` from `u` towards
    /// `v`, so wale 0 and wale `wales / 2` are the two sides of the leg and the foot.
    pub fn ring(&self, s: f64, wales: usize) -> Vec<Point3<f64>> {
        let (a, b, _) = self.bracket(s);
        let (centre, _, u, v) = self.frame_at(s);
        (0..wales)
            .map(|w| {
                let theta = std::f64::consts::TAU * w as f64 / wales as f64;
                let r = a.extent_at(theta).max(b.extent_at(theta));
                let r = r + (r * RADIAL_MARGIN).max(MIN_GAP_M);
                centre + (u * theta.cos() + v * theta.sin()) * r
            })
            .collect()
    }

    /// The frame at distance `s`: `(centre, t, u, v)`.
    pub fn frame_at(&self, s: f64) -> (Point3<f64>, Vector3<f64>, Vector3<f64>, Vector3<f64>) {
        let (a, b, f) = self.bracket(s);
        let t = (a.t * (1.0 - f) + b.t * f).normalize();
        let u = a.u * (1.0 - f) + b.u * f;
        let u = (u - t * t.dot(&u)).normalize();
        (a.centre + (b.centre - a.centre) * f, t, u, t.cross(&u))
    }

    /// The stations either side of distance `s` and the fraction between them.
    fn bracket(&self, s: f64) -> (&Station, &Station, f64) {
        let n = self.stations.len();
        let k = self.stations.partition_point(|st| st.s < s).clamp(1, n - 1);
        let (a, b) = (&self.stations[k - 1], &self.stations[k]);
        let span = b.s - a.s;
        let f = if span > 0.0 {
            ((s - a.s) / span).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (a, b, f)
    }
}

impl Station {
    /// The section's extent from the centre at angle `theta` (from `u` towards `v`).
    fn extent_at(&self, theta: f64) -> f64 {
        let n = self.extent.len();
        let x = theta.rem_euclid(std::f64::consts::TAU) / std::f64::consts::TAU * n as f64;
        let k = (x.floor() as usize).min(n - 1);
        let f = x - k as f64;
        self.extent[k] * (1.0 - f) + self.extent[(k + 1) % n] * f
    }
}

/// The path from the section at height `top_s` on the thigh to the toe (module docs), on the
/// leg `positions`/`triangles` (world space, welded). The error says why there is none: no
/// foot, or a section the path cannot follow.
pub fn path_to_toe(
    landmarks: &Landmarks,
    top_s: f64,
    positions: &[Point3<f64>],
    triangles: &[[u32; 3]],
) -> Result<TubePath, String> {
    let foot = landmarks
        .foot
        .ok_or("the leg has no foot (its mesh ends above the ankle)")?;
    let top = Point3::from(landmarks.ring_at(top_s).centre);
    let knee = Point3::from(landmarks.knee.centre);
    let ankle = Point3::from(landmarks.ankle.centre);
    let down = (ankle - knee).normalize();
    let forward = Vector3::from(foot.direction);
    let forward = (forward - down * down.dot(&forward)).normalize();
    let side = down.cross(&forward);
    let sections = Sections {
        positions,
        triangles,
        piece: crate::leg::solid::triangle_pieces(positions, triangles),
        side,
    };

    // The pivot: in front of the shin at the ankle, above the instep in front of it.
    let at_ankle = sections
        .cut(&ankle, &down, &ankle, None, false)
        .ok_or("no closed section of the leg at the ankle")?;
    let shin_front = (at_ankle.centre - ankle).dot(&forward) + at_ankle.reach(&forward);
    let instep_top = positions
        .iter()
        .map(|p| p - ankle)
        .filter(|d| {
            d.dot(&forward) >= shin_front
                && d.dot(&down) > 0.0
                && d.dot(&side).abs() < 0.1
                && d.norm() < 0.4
        })
        .map(|d| -d.dot(&down))
        .fold(f64::NEG_INFINITY, f64::max);
    if !instep_top.is_finite() {
        return Err("nothing of the foot lies in front of the shin below the ankle".into());
    }
    let pivot_height = (instep_top + PIVOT_CLEARANCE_M).min(0.0);
    let pivot = ankle + forward * (shin_front + PIVOT_CLEARANCE_M) - down * pivot_height;

    let mut stations: Vec<Station> = Vec::new();
    let mut probe = top;
    let push = |stations: &mut Vec<Station>,
                origin: Point3<f64>,
                t: Vector3<f64>,
                part: PathPart,
                probe: &mut Point3<f64>|
     -> Result<(), String> {
        let gather = part == PathPart::Foot;
        let hull = sections
            .cut(&origin, &t, probe, stations.last(), gather)
            .ok_or_else(|| {
                format!(
                    "no closed section of the leg {:.0} cm along the stocking's path ({})",
                    100.0 * stations.last().map_or(0.0, |s| s.s),
                    match part {
                        PathPart::Leg => "on the leg",
                        PathPart::Heel => "around the heel",
                        PathPart::Foot => "along the foot",
                    }
                )
            })?;
        let s = stations
            .last()
            .map_or(0.0, |prev| prev.s + (hull.centre - prev.centre).norm());
        *probe = hull.centre;
        stations.push(Station {
            centre: hull.centre,
            t,
            u: hull.u,
            v: t.cross(&hull.u),
            s,
            part,
            extent: hull.extent,
            solidity: hull.solidity,
        });
        Ok(())
    };

    // The leg: thigh top → knee → the fan's first plane, turning smoothly at the knee.
    let bottom = ankle + down * (pivot - ankle).dot(&down);
    let upper = knee - top;
    let lower = bottom - knee;
    let (upper_len, lower_len) = (upper.norm(), lower.norm());
    let leg_len = upper_len + lower_len;
    let steps = (leg_len / STATION_STEP_M).ceil() as usize;
    for k in 0..steps {
        let q = leg_len * k as f64 / steps as f64;
        let origin = if q < upper_len {
            top + upper * (q / upper_len)
        } else {
            knee + lower * ((q - upper_len) / lower_len)
        };
        let blend = ((q - upper_len + KNEE_BLEND_M) / (2.0 * KNEE_BLEND_M)).clamp(0.0, 1.0);
        let blend = blend * blend * (3.0 - 2.0 * blend);
        let t = (upper.normalize() * (1.0 - blend) + down * blend).normalize();
        push(&mut stations, origin, t, PathPart::Leg, &mut probe)?;
    }
    // The heel: planes about the pivot, from square to the shin to square to the foot.
    for k in 0..=FAN_STATIONS {
        let alpha = std::f64::consts::FRAC_PI_2 * k as f64 / FAN_STATIONS as f64;
        let t = down * alpha.cos() + forward * alpha.sin();
        push(&mut stations, pivot, t, PathPart::Heel, &mut probe)?;
    }
    // The foot, to just behind the toe tip.
    let foot_len = (Point3::from(foot.toe_tip) - pivot).dot(&forward) - TOE_END_M;
    let steps = (foot_len / STATION_STEP_M).floor() as usize;
    for k in 1..=steps {
        let x = foot_len * k as f64 / steps as f64;
        let origin = pivot + forward * x;
        if let Err(message) = push(&mut stations, origin, forward, PathPart::Foot, &mut probe) {
            // The last few millimetres of a toe may be open or too thin to cut: the cap
            // covers them.
            if x > 0.8 * foot_len {
                break;
            }
            return Err(message);
        }
    }
    let toes = add_toe_cap(&mut stations, foot.toe_tip.into());
    // The cap moved some centres: distances along the path from the centres as they are.
    for k in 1..stations.len() {
        stations[k].s = stations[k - 1].s + (stations[k].centre - stations[k - 1].centre).norm();
    }
    Ok(TubePath {
        stations,
        pivot,
        toes,
    })
}

/// How far the toe cap reaches beyond the toe tip, metres.
pub const TOE_CAP_M: f64 = 0.012;
/// The cap's last ring's height, as a fraction of the widest foot section's.
const TOE_CAP_END: f64 = 0.05;

/// Shapes the toe as a stocking's toe lies before it is pulled on: from the widest section of
/// the foot (the ball) on, each ring keeps that section's width and flattens linearly to a slit
/// [`TOE_CAP_M`] in front of the toe tip (while still clearing the toes' own sections), where
/// the toe seam joins its two sides. Without this the rings would follow the toes down to the
/// big toe alone, and the toe's courses would start bunched many times over.
/// Returns the foot's stations from the start of the toe box on (a lead before the toes'
/// clefts, [`TOE_BOX_LEAD_M`]) as they were (their own hulls).
fn add_toe_cap(stations: &mut Vec<Station>, toe_tip: Point3<f64>) -> Vec<Station> {
    let foot: Vec<usize> = (0..stations.len())
        .filter(|&k| stations[k].part == PathPart::Foot)
        .collect();
    let Some(&widest) = foot.iter().max_by(|&&a, &&b| {
        let width =
            |k: usize| stations[k].extent_at(0.0) + stations[k].extent_at(std::f64::consts::PI);
        width(a).total_cmp(&width(b))
    }) else {
        return Vec::new();
    };
    // The box of the toes starts on skin its hull fits closely: a lead before the run of
    // sections, up to the ball, that dip between the toes.
    let mut cleft = widest;
    while cleft > foot[0] && stations[cleft - 1].solidity < TOE_CLEFT_SOLIDITY {
        cleft -= 1;
    }
    let lead = (TOE_BOX_LEAD_M / STATION_STEP_M).round() as usize;
    let toes = stations[cleft.saturating_sub(lead).max(foot[0])..].to_vec();
    let ball = stations[widest].clone();
    let last = stations.last().cloned().expect("the foot has stations");
    let end = (toe_tip - ball.centre).dot(&ball.t) + TOE_CAP_M;
    let ball_points = ball.outline();
    // The ball's outline flattened by `k` towards its own middle line, at distance `x` along
    // the foot, in a station's frame around `centre`.
    let wedge = |x: f64, centre: &Point3<f64>| -> Vec<[f64; 2]> {
        let k = (1.0 - x / end).max(TOE_CAP_END);
        let shift = ball.centre + ball.t * x - centre;
        let (su, sv) = (shift.dot(&ball.u), shift.dot(&ball.v));
        ball_points
            .iter()
            .map(|p| [p[0] + su, p[1] * k + sv])
            .collect()
    };
    for st in &mut stations[widest + 1..] {
        let x = (st.centre - ball.centre).dot(&ball.t);
        let mut points = st.outline();
        points.extend(wedge(x, &st.centre));
        let (centre_shift, extent) = star_extent(points);
        st.centre += st.u * centre_shift[0] + st.v * centre_shift[1];
        st.extent = extent;
    }
    // Beyond the last section: the wedge alone, to the slit.
    let from = (last.centre - ball.centre).dot(&ball.t);
    let steps = ((end - from) / STATION_STEP_M).ceil().max(1.0) as usize;
    let mut previous = stations.last().expect("the foot has stations").clone();
    for k in 1..=steps {
        let x = from + (end - from) * k as f64 / steps as f64;
        let centre = ball.centre + ball.t * x;
        let (centre_shift, extent) = star_extent(wedge(x, &centre));
        let centre = centre + ball.u * centre_shift[0] + ball.v * centre_shift[1];
        let station = Station {
            centre,
            s: previous.s + (centre - previous.centre).norm(),
            part: PathPart::Foot,
            extent,
            ..previous.clone()
        };
        stations.push(station.clone());
        previous = station;
    }
    toes
}

/// A leg's positions and triangles with its toes boxed ([`TubePath::box_the_toes`]).
pub type BoxedLeg = (Vec<Point3<f64>>, Vec<[u32; 3]>);

impl TubePath {
    /// The toe box's open rim ([`TubePath::box_the_toes`]): its centre, its plane's normal
    /// towards the toe, and the box's length from that plane to just past the tip, metres;
    /// `None` where the path has no toes.
    pub fn toe_box_rim(&self) -> Option<(Point3<f64>, Vector3<f64>, f64)> {
        let [first, .., last] = &self.toes[..] else {
            return None;
        };
        let length = (last.centre - first.centre).dot(&first.t) + TOE_END_M + TOE_BOX_PAST_M;
        Some((first.centre, first.t, length))
    }

    /// The leg `positions`/`triangles` with its toes boxed: the skin from a little before the
    /// toes' clefts on replaced by the convex hull of the sections there, closed just past the
    /// tip. This is the leg the stocking's contact sees: fabric bridges the gaps between toes,
    /// and a point let into one chatters between its two sides (the futility watch stopped the
    /// whole body's fit there). The box holds the toes to within the sections' sampling (under a
    /// millimetre), which the exact contact pass after the fit settles. `None` where the path
    /// has no toes or their hull cannot be built: the fit's contact sees the skin itself.
    pub fn box_the_toes(
        &self,
        positions: &[Point3<f64>],
        triangles: &[[u32; 3]],
    ) -> Option<BoxedLeg> {
        let toes = &self.toes;
        let (rim, t, box_length) = self.toe_box_rim()?;
        let last = &toes[toes.len() - 1];
        let along = |p: &Point3<f64>| (p - rim).dot(&t);
        // In the box or within a few millimetres of it (it is interpolated between sections):
        // skin the box replaces must not be left overlapping it, where the closest surface
        // would flip between the two. What little of it the box misses, the exact pass after
        // the fit settles against the real skin.
        let inside = |p: &Point3<f64>| {
            let x = along(p);
            if x <= 0.001 || x > box_length + TOE_BOX_SLACK_M {
                return false;
            }
            let k = toes
                .partition_point(|st| along(&st.centre) < x)
                .clamp(1, toes.len() - 1);
            let (a, b) = (&toes[k - 1], &toes[k]);
            let span = along(&b.centre) - along(&a.centre);
            let f = if span > 0.0 {
                ((x - along(&a.centre)) / span).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let centre = a.centre + (b.centre - a.centre) * f;
            let d = p - centre;
            let (du, dv) = (d.dot(&a.u), d.dot(&a.v));
            let theta = dv.atan2(du);
            let reach = a.extent_at(theta) * (1.0 - f) + b.extent_at(theta) * f;
            (du * du + dv * dv).sqrt() <= reach + TOE_BOX_SLACK_M
        };
        let mut out_positions = positions.to_vec();
        let mut out_triangles: Vec<[u32; 3]> = triangles
            .iter()
            .filter(|tri| !tri.iter().all(|&i| inside(&positions[i as usize])))
            .copied()
            .collect();
        // The box is the convex hull of the toes' section outlines and of the last one again
        // just past the tip, less its face on the first section (the rim, on the skin): being
        // convex it has no valley where a point's closest face flips from one side to the other
        // (a loft through the outlines has one wherever the sections change shape fast, and
        // the fit chattered there at 100 wales).
        let beyond = t * (TOE_END_M + TOE_BOX_PAST_M);
        let mut outlines: Vec<Point3<f64>> = toes
            .iter()
            .flat_map(|st| {
                st.outline()
                    .into_iter()
                    .map(|p| st.centre + st.u * p[0] + st.v * p[1])
            })
            .collect();
        outlines.extend(
            last.outline()
                .into_iter()
                .map(|p| last.centre + beyond + last.u * p[0] + last.v * p[1]),
        );
        let (corners, faces) = parry3d_f64::transformation::try_convex_hull(&outlines).ok()?;
        let middle =
            corners.iter().fold(Vector3::zeros(), |m, c| m + c.coords) / corners.len() as f64;
        let base = out_positions.len() as u32;
        for face in &faces {
            let [a, b, c] = face.map(|i| corners[i as usize]);
            if [a, b, c].iter().all(|p| along(p) < 1e-9) {
                continue;
            }
            // Outward winding, whatever the hull's own.
            let outward = (b - a).cross(&(c - a)).dot(&(a.coords - middle)) >= 0.0;
            let [i, j, k] = face.map(|i| base + i);
            out_triangles.push(if outward { [i, j, k] } else { [i, k, j] });
        }
        out_positions.extend(corners);
        Some((out_positions, out_triangles))
    }
}

impl Station {
    /// The section's outline (the extent at each sampled angle), 2-D from the centre in
    /// `(u, v)`.
    fn outline(&self) -> Vec<[f64; 2]> {
        let n = self.extent.len();
        (0..n)
            .map(|k| {
                let theta = std::f64::consts::TAU * k as f64 / n as f64;
                [theta.cos() * self.extent[k], theta.sin() * self.extent[k]]
            })
            .collect()
    }
}

/// The convex hull of `points` (2-D) as its centroid (from the points' origin) and its extent
/// from that centroid at [`RADIUS_SAMPLES`] angles.
fn star_extent(points: Vec<[f64; 2]>) -> ([f64; 2], Vec<f64>) {
    let hull = slice::convex_hull(points);
    let [cx, cy] = polygon_centroid(&hull);
    let corners: Vec<[f64; 2]> = hull.iter().map(|c| [c[0] - cx, c[1] - cy]).collect();
    let extent = (0..RADIUS_SAMPLES)
        .map(|k| {
            let theta = std::f64::consts::TAU * k as f64 / RADIUS_SAMPLES as f64;
            ray_to_polygon(&corners, [theta.cos(), theta.sin()])
        })
        .collect();
    ([cx, cy], extent)
}

/// Sections of the leg in any plane, measured for the path.
struct Sections<'a> {
    positions: &'a [Point3<f64>],
    triangles: &'a [[u32; 3]],
    /// Each triangle's connected piece: the sections of a leg modelled in pieces are their
    /// union.
    piece: Vec<u32>,
    /// The leg's side-to-side direction: each station's `u` is this made square to its plane's
    /// normal.
    side: Vector3<f64>,
}

/// A station's section: its hull's centre, the plane's `u`, and its extent by angle.
struct Hull {
    centre: Point3<f64>,
    u: Vector3<f64>,
    extent: Vec<f64>,
    /// The hull's corners, 2-D from `centre` in `(u, t × u)`.
    corners: Vec<[f64; 2]>,
    v: Vector3<f64>,
    /// The section's area over its hull's.
    solidity: f64,
}

impl Hull {
    /// How far the hull reaches from its centre along the unit vector `d` (in its plane).
    fn reach(&self, d: &Vector3<f64>) -> f64 {
        let (du, dv) = (d.dot(&self.u), d.dot(&self.v));
        self.corners
            .iter()
            .map(|c| c[0] * du + c[1] * dv)
            .fold(f64::NEG_INFINITY, f64::max)
    }
}

impl Sections<'_> {
    /// The section of the plane through `origin` square to `t`: the closed loop around `probe`,
    /// or else the one whose centre is nearest it within reach of the previous station; with
    /// `gather`, every other loop whose centre is as near (toes). `None` where there is none.
    fn cut(
        &self,
        origin: &Point3<f64>,
        t: &Vector3<f64>,
        probe: &Point3<f64>,
        previous: Option<&Station>,
        gather: bool,
    ) -> Option<Hull> {
        let u = (self.side - t * t.dot(&self.side)).normalize();
        let v = t.cross(&u);
        let loops: Vec<slice::Loop> =
            slice::section(self.positions, self.triangles, &self.piece, origin, t)
                .into_iter()
                .filter(|l| l.closed && l.points.len() >= 3)
                .collect();
        let flat = |p: &Point3<f64>| [(p - origin).dot(&u), (p - origin).dot(&v)];
        let probe_flat = flat(probe);
        let reach = previous.map_or(f64::INFINITY, |s| {
            1.5 * s.extent.iter().copied().fold(0.0, f64::max)
        });
        let distance = |l: &slice::Loop| {
            let [x, y] = flat(&l.centre());
            ((x - probe_flat[0]).powi(2) + (y - probe_flat[1]).powi(2)).sqrt()
        };
        let around = loops
            .iter()
            .find(|l| encloses(&l.points, &flat, probe_flat));
        let chosen = around.or_else(|| {
            loops
                .iter()
                .filter(|l| distance(l) < reach)
                .min_by(|a, b| distance(a).total_cmp(&distance(b)))
        })?;
        let loop_area = |l: &slice::Loop| {
            let flat: Vec<[f64; 2]> = l.points.iter().map(flat).collect();
            polygon_area(&flat).abs()
        };
        let mut points: Vec<Point3<f64>> = chosen.points.clone();
        let mut area = loop_area(chosen);
        if gather {
            // The toes: every loop whose centre lies within the last section's extent.
            let near = previous.map_or(0.0, |s| s.extent.iter().copied().fold(0.0, f64::max));
            for l in &loops {
                if !std::ptr::eq(l, chosen) && distance(l) < near {
                    points.extend(&l.points);
                    area += loop_area(l);
                }
            }
        }
        let hull = slice::hull_in_plane(points.into_iter(), origin, &u, &v);
        if hull.len() < 3 {
            return None;
        }
        let hull_area = polygon_area(&hull).abs();
        let [cx, cy] = polygon_centroid(&hull);
        let corners: Vec<[f64; 2]> = hull.iter().map(|c| [c[0] - cx, c[1] - cy]).collect();
        let (_, extent) = star_extent(hull);
        Some(Hull {
            centre: origin + u * cx + v * cy,
            u,
            extent,
            corners,
            v,
            solidity: if hull_area > 0.0 {
                (area / hull_area).min(1.0)
            } else {
                1.0
            },
        })
    }
}

/// Crossing-number test of `p` against the loop `points` flattened by `flat`.
fn encloses(points: &[Point3<f64>], flat: &impl Fn(&Point3<f64>) -> [f64; 2], p: [f64; 2]) -> bool {
    let flat: Vec<[f64; 2]> = points.iter().map(flat).collect();
    let mut inside = false;
    for (a, b) in flat.iter().zip(flat.iter().cycle().skip(1)) {
        if (a[1] > p[1]) != (b[1] > p[1]) {
            let x = a[0] + (b[0] - a[0]) * (p[1] - a[1]) / (b[1] - a[1]);
            if x > p[0] {
                inside = !inside;
            }
        }
    }
    inside
}

/// Signed area of a simple polygon (positive counter-clockwise).
fn polygon_area(corners: &[[f64; 2]]) -> f64 {
    0.5 * corners
        .iter()
        .zip(corners.iter().cycle().skip(1))
        .map(|(a, b)| a[0] * b[1] - b[0] * a[1])
        .sum::<f64>()
}

/// Area centroid of a simple polygon (its corners' mean if it has no area).
fn polygon_centroid(corners: &[[f64; 2]]) -> [f64; 2] {
    let (mut area, mut cx, mut cy) = (0.0, 0.0, 0.0);
    for (a, b) in corners.iter().zip(corners.iter().cycle().skip(1)) {
        let cross = a[0] * b[1] - b[0] * a[1];
        area += cross;
        cx += (a[0] + b[0]) * cross;
        cy += (a[1] + b[1]) * cross;
    }
    if area.abs() > 1e-18 {
        [cx / (3.0 * area), cy / (3.0 * area)]
    } else {
        let n = corners.len() as f64;
        let sum = corners
            .iter()
            .fold([0.0, 0.0], |s, c| [s[0] + c[0], s[1] + c[1]]);
        [sum[0] / n, sum[1] / n]
    }
}

/// Distance from the origin to a convex polygon around it along the unit direction `d`.
fn ray_to_polygon(corners: &[[f64; 2]], d: [f64; 2]) -> f64 {
    let mut best: f64 = 0.0;
    for (a, b) in corners.iter().zip(corners.iter().cycle().skip(1)) {
        // Solve a + (b − a) s = d r for s in [0, 1], r > 0.
        let e = [b[0] - a[0], b[1] - a[1]];
        let denom = d[0] * e[1] - d[1] * e[0];
        if denom.abs() < 1e-18 {
            continue;
        }
        let r = (a[0] * e[1] - a[1] * e[0]) / denom;
        let s = (a[0] * d[1] - a[1] * d[0]) / denom;
        if (-1e-9..=1.0 + 1e-9).contains(&s) && r > 0.0 {
            best = best.max(r);
        }
    }
    best
}
