//! The leg zoo (issue 45): legs made the ways users bring them, crossed along the axes they
//! vary, each fitted by the binary as a user runs it (at the defaults; the CI subset at 100×100,
//! where 60×60 leaves a cut leg's forefoot unsettled, and tolerance 3e-3) and held to what its
//! construction knows.
//!
//! A variant is a **source** cut to an **export form** (the MakeHuman body whole, as a lower body,
//! its left leg cut open, closed, slanted or in pieces, the whole body as a mannequin in pieces;
//! the second body model, MHR's, cut the same seven ways; the procedural leg closed, open,
//! slanted or in pieces), written in a **mesh form** (as
//! exported, subdivided, as quads in a PLY, damaged with repeated and zero-area faces and small
//! holes, cluttered with debris and a floor) and a
//! **frame** (Y-up metres, Z-up metres, Z-up centimetres, turned and moved, inches, Z-up
//! millimetres). Randomness (the turn, where the holes and debris go) comes from the variant's
//! seed, so a variant is the same file on every run.
//!
//! The truth a variant is held to is its source's landmarks found once on the clean source in
//! world space (`find_landmarks`), taken through the variant's frame: ankle, knee and toe tip
//! within 1.5 cm of where the clean source has them. Every variant fits (exit 0) with no yarn
//! inside the leg, passes the fit's checks and, where the source has a foot, gets a stocking to
//! the toe. Each fitted variant is also held to
//! the same leg made another way, where that fitted (metamorphic checks: its frame against Y-up
//! metres, remeshed against as exported, closed at the cut against open): landmarks within 1 cm
//! of each other, every region's stitch density within 3 %. The body mirrored left to right
//! is held to the same in its own CI test, and legs posed as strides without a rig are
//! tabulated by [`the_stride_zoo_table`].
//!
//! The whole zoo (every crossing, 540 variants) is the long profile:
//! `KNITFIT_LONG=1 cargo test --release zoo -- --include-ignored --nocapture`; it writes its table
//! to `target/zoo/all.md` (`KNITFIT_ZOO_KEEP=DIR` keeps every variant's file in DIR, named after
//! it; `KNITFIT_ZOO_ONLY=TEXT` runs only the variants whose name holds it). CI runs
//! [`ci_subset`], 44 variants covering every value of every axis, and writes `target/zoo/ci.md`.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::time::Instant;

use knitfit::knit::TubeBottom;
use knitfit::leg::unbend::Bend;
use knitfit::leg::{Side, Units, UpChoice};
use knitfit::report::{FitDetails, LandmarkDetails, Report};
use nalgebra::{Point3, Rotation3, Unit, Vector3};

use crate::support::variants::{closed_at_the_cut, cube, cut_below, leg_as_quads};
use crate::support::{knitfit, read_glb_meshes, sample, stderr, write_raw_meshes, RawMesh};

/// Where a leg comes from and how the user cut it out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Form {
    /// The MakeHuman body as exported: both legs, arms, head.
    Body,
    /// The body cut 15 cm above the crotch: both legs and the pelvis, open at the waist.
    LowerBody,
    /// Its left leg cut 4 cm below the crotch, open at the cut.
    LeftLegOpen,
    /// The same, closed at the cut (watertight).
    LeftLegClosed,
    /// Cut on a 20° slant and closed.
    LeftLegSlanted,
    /// The closed left leg in three watertight pieces (foot, shin, thigh), each a little wider
    /// than the one below where they overlap by 2 cm, with a ball joint inside at the knee: a
    /// mannequin's limb.
    LeftLegPieces,
    /// The body as a mannequin in pieces: each leg in foot, shin and thigh as
    /// [`Form::LeftLegPieces`], with ball joints inside at the knee and the ankle, and the body
    /// above the thighs (trunk, arms, head) one piece closed at its cut, overlapping the
    /// thighs by 2 cm.
    BodyPieces,
    /// The procedural leg (no foot) as made: closed at both ends.
    Procedural,
    /// Cut 3 cm below its top, open there.
    ProceduralOpen,
    /// Cut 3 cm below its top on a 20° slant, closed.
    ProceduralSlanted,
    /// In two watertight pieces overlapping 2 cm at the knee, with a ball joint inside.
    ProceduralPieces,
    /// The second body model (`samples/mhr/body.glb`, Meta's MHR at rest, a T-pose) as
    /// exported, and cut as the MakeHuman body is in each form above of that name.
    MhrBody,
    MhrLowerBody,
    MhrLeftLegOpen,
    MhrLeftLegClosed,
    MhrLeftLegSlanted,
    MhrLeftLegPieces,
    MhrBodyPieces,
}

const FORMS: [Form; 18] = [
    Form::Body,
    Form::LowerBody,
    Form::LeftLegOpen,
    Form::LeftLegClosed,
    Form::LeftLegSlanted,
    Form::LeftLegPieces,
    Form::BodyPieces,
    Form::Procedural,
    Form::ProceduralOpen,
    Form::ProceduralSlanted,
    Form::ProceduralPieces,
    Form::MhrBody,
    Form::MhrLowerBody,
    Form::MhrLeftLegOpen,
    Form::MhrLeftLegClosed,
    Form::MhrLeftLegSlanted,
    Form::MhrLeftLegPieces,
    Form::MhrBodyPieces,
];

impl Form {
    /// The MakeHuman form cut the same way, and the body it is cut from.
    fn cut_from(self) -> (Form, &'static Source) {
        let mhr = |form| (form, mhr());
        match self {
            Form::MhrBody => mhr(Form::Body),
            Form::MhrLowerBody => mhr(Form::LowerBody),
            Form::MhrLeftLegOpen => mhr(Form::LeftLegOpen),
            Form::MhrLeftLegClosed => mhr(Form::LeftLegClosed),
            Form::MhrLeftLegSlanted => mhr(Form::LeftLegSlanted),
            Form::MhrLeftLegPieces => mhr(Form::LeftLegPieces),
            Form::MhrBodyPieces => mhr(Form::BodyPieces),
            _ => (self, body()),
        }
    }
}

/// How the mesh is written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum MeshForm {
    /// Triangles as cut, in a GLB.
    AsIs,
    /// Every triangle split in four at its edges' middles (flat).
    Subdivided,
    /// Welded and written as quads in an ASCII PLY, concave ones included.
    QuadPly,
    /// Every 10th face repeated, a zero-area face every 15th, three small holes.
    Damaged,
    /// Four small boxes floating beside the leg and a 2 m floor under the sole.
    Cluttered,
}

const MESH_FORMS: [MeshForm; 5] = [
    MeshForm::AsIs,
    MeshForm::Subdivided,
    MeshForm::QuadPly,
    MeshForm::Damaged,
    MeshForm::Cluttered,
];

/// The file's frame and units.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Frame {
    YUpMetres,
    ZUpMetres,
    ZUpCentimetres,
    /// Turned about up by any angle, tipped up to 10°, moved up to a metre; metres.
    TurnedMetres,
    YUpInches,
    ZUpMillimetres,
}

const FRAMES: [Frame; 6] = [
    Frame::YUpMetres,
    Frame::ZUpMetres,
    Frame::ZUpCentimetres,
    Frame::TurnedMetres,
    Frame::YUpInches,
    Frame::ZUpMillimetres,
];

#[derive(Clone, Copy, Debug)]
struct Variant {
    form: Form,
    mesh: MeshForm,
    frame: Frame,
    seed: u64,
}

impl Variant {
    fn name(&self) -> String {
        format!("{:?} / {:?} / {:?}", self.form, self.mesh, self.frame)
    }
}

/// Every crossing of the axes.
fn all_variants() -> Vec<Variant> {
    let mut all = Vec::new();
    for form in FORMS {
        for mesh in MESH_FORMS {
            for frame in FRAMES {
                let seed = all.len() as u64 + 1;
                all.push(Variant {
                    form,
                    mesh,
                    frame,
                    seed,
                });
            }
        }
    }
    all
}

/// 44 variants, every form at least twice, every mesh form and frame at least six times, and no
/// two alike.
fn ci_subset() -> Vec<Variant> {
    let all = all_variants();
    (0..44)
        .map(|i| {
            let turn = i + i / FORMS.len();
            let (form, mesh, frame) = (i % FORMS.len(), turn % 5, turn % 6);
            all[(form * 5 + mesh) * 6 + frame]
        })
        .collect()
}

/// A small seeded generator (SplitMix64): the variants' randomness.
struct Seeded(u64);

impl Seeded {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        (z ^ (z >> 31)) as f64 / u64::MAX as f64
    }
}

/// A source's meshes (world space: metres, Y up, the character facing +Z) and its landmarks.
struct Source {
    meshes: Vec<RawMesh>,
    truth: LandmarkDetails,
}

fn source(path: PathBuf) -> Source {
    let leg = knitfit::leg::load_leg(&path, Units::Metres, UpChoice::Auto).unwrap();
    let landmarks =
        knitfit::leg::find_landmarks(&leg.positions, &leg.triangles, leg.up, Side::Left, None)
            .unwrap();
    Source {
        meshes: read_glb_meshes(&path),
        truth: LandmarkDetails::of(&landmarks, &leg),
    }
}

fn body() -> &'static Source {
    static BODY: OnceLock<Source> = OnceLock::new();
    BODY.get_or_init(|| source(sample("makehuman_body.glb")))
}

fn mhr() -> &'static Source {
    static MHR: OnceLock<Source> = OnceLock::new();
    MHR.get_or_init(|| source(sample("mhr/body.glb")))
}

fn procedural() -> &'static Source {
    static LEG: OnceLock<Source> = OnceLock::new();
    LEG.get_or_init(|| source(sample("procedural_leg.glb")))
}

/// `meshes` below the plane through `at` tilted `tilt_deg` about the front–back axis, where
/// `keep` accepts a triangle's centre.
fn cut(
    meshes: &[RawMesh],
    at: Point3<f64>,
    tilt_deg: f64,
    keep: impl Fn(&Point3<f64>) -> bool + Copy,
) -> Vec<RawMesh> {
    let t = tilt_deg.to_radians();
    let up = Vector3::new(t.sin(), t.cos(), 0.0);
    meshes.iter().map(|m| cut_below(m, at, up, keep)).collect()
}

/// The part of the closed `meshes` between heights `low` and `high`, closed at both cuts, and
/// widened `widen` times about the vertical line through `centre`: a piece modelled apart, whose
/// skin does not coincide with its neighbour's where they overlap.
fn piece(meshes: &[RawMesh], low: f64, high: f64, centre: [f64; 3], widen: f64) -> Vec<RawMesh> {
    meshes
        .iter()
        .map(|m| {
            let below = cut_below(m, Point3::new(0.0, high, 0.0), Vector3::y(), |_| true);
            let between = cut_below(&below, Point3::new(0.0, low, 0.0), -Vector3::y(), |_| true);
            let mut closed = closed_at_the_cut(&between);
            for p in &mut closed.positions {
                p.x = centre[0] + (p.x - centre[0]) * widen;
                p.z = centre[2] + (p.z - centre[2]) * widen;
            }
            closed
        })
        .filter(|m| !m.triangles.is_empty())
        .collect()
}

/// A ball joint: a sphere at `centre` inside the limb's section of `girth`, nine tenths of its
/// radius.
fn ball(name: &str, centre: [f64; 3], girth: f64) -> RawMesh {
    let radius = 0.9 * girth / std::f64::consts::TAU;
    let centre = Point3::from(centre);
    let (bands, around) = (12, 24);
    let mut positions = Vec::new();
    for i in 0..=bands {
        let polar = std::f64::consts::PI * i as f64 / bands as f64;
        for k in 0..around {
            let azimuth = std::f64::consts::TAU * k as f64 / around as f64;
            let (sp, cp) = polar.sin_cos();
            positions
                .push(centre + radius * Vector3::new(sp * azimuth.cos(), cp, sp * azimuth.sin()));
        }
    }
    let at = |i: u32, k: u32| i * around + k % around;
    let mut triangles = Vec::new();
    for i in 0..bands {
        for k in 0..around {
            triangles.push([at(i, k), at(i, k + 1), at(i + 1, k)]);
            triangles.push([at(i, k + 1), at(i + 1, k + 1), at(i + 1, k)]);
        }
    }
    RawMesh {
        name: name.into(),
        positions,
        triangles,
    }
}

/// The closed `leg` in three pieces (foot, shin, thigh), each a little wider than the one below
/// where they overlap by 2 cm, with a ball joint inside at the knee, and at the ankle too where
/// `ankle_ball`: a mannequin's limb. Its joints are where `truth` has the left leg's, their
/// sideways coordinate times `side` (-1: the right leg of a body that is mirror-symmetric).
fn limb_in_pieces(
    leg: &[RawMesh],
    truth: &LandmarkDetails,
    side: f64,
    ankle_ball: bool,
) -> Vec<RawMesh> {
    let sided = |p: [f64; 3]| [side * p[0], p[1], p[2]];
    let (a, k) = (sided(truth.ankle.centre.m), sided(truth.knee.centre.m));
    let mut pieces = piece(leg, -10.0, a[1] + 0.01, a, 1.0);
    pieces.extend(piece(leg, a[1] - 0.01, k[1] + 0.01, a, 1.01));
    pieces.extend(piece(leg, k[1] - 0.01, 10.0, k, 1.02));
    pieces.push(ball("knee joint", k, truth.knee.girth_m));
    if ankle_ball {
        pieces.push(ball("ankle joint", a, truth.ankle.girth_m));
    }
    pieces
}

/// The variant's meshes in world space and which source it is held to.
fn formed(form: Form) -> (Vec<RawMesh>, &'static Source) {
    let at = |p: [f64; 3], dy: f64| Point3::new(p[0], p[1] + dy, p[2]);
    let left = |c: &Point3<f64>| c.x > 0.0;
    let all = |_: &Point3<f64>| true;
    let closed = |m: Vec<RawMesh>| m.iter().map(closed_at_the_cut).collect::<Vec<_>>();
    let (form, b) = form.cut_from();
    let p = procedural();
    let crotch = b.truth.thigh_top.centre.m;
    let top = p.truth.thigh_top.centre.m;
    let meshes = match form {
        Form::Body => return (b.meshes.clone(), b),
        Form::LowerBody => cut(&b.meshes, at(crotch, 0.15), 0.0, all),
        Form::LeftLegOpen => cut(&b.meshes, at(crotch, -0.04), 0.0, left),
        Form::LeftLegClosed => closed(cut(&b.meshes, at(crotch, -0.04), 0.0, left)),
        Form::LeftLegSlanted => closed(cut(&b.meshes, at(crotch, -0.04), 20.0, left)),
        Form::LeftLegPieces => {
            let leg = closed(cut(&b.meshes, at(crotch, -0.04), 0.0, left));
            limb_in_pieces(&leg, &b.truth, 1.0, false)
        }
        Form::BodyPieces => {
            let above = |m: &RawMesh| cut_below(m, at(crotch, -0.04), -Vector3::y(), all);
            let mut pieces = closed(b.meshes.iter().map(above).collect());
            let right = |c: &Point3<f64>| c.x < 0.0;
            let legs = [(1.0, cut(&b.meshes, at(crotch, -0.02), 0.0, left))]
                .into_iter()
                .chain([(-1.0, cut(&b.meshes, at(crotch, -0.02), 0.0, right))]);
            for (side, leg) in legs {
                pieces.extend(limb_in_pieces(&closed(leg), &b.truth, side, true));
            }
            pieces
        }
        Form::Procedural => return (p.meshes.clone(), p),
        Form::MhrBody
        | Form::MhrLowerBody
        | Form::MhrLeftLegOpen
        | Form::MhrLeftLegClosed
        | Form::MhrLeftLegSlanted
        | Form::MhrLeftLegPieces
        | Form::MhrBodyPieces => unreachable!("cut as their MakeHuman twins"),
        Form::ProceduralOpen => cut(&p.meshes, at(top, -0.03), 0.0, all),
        Form::ProceduralSlanted => closed(cut(&p.meshes, at(top, -0.03), 20.0, all)),
        Form::ProceduralPieces => {
            let knee = &p.truth.knee;
            let k = knee.centre.m;
            let mut pieces = piece(&p.meshes, -10.0, k[1] + 0.01, k, 1.0);
            pieces.extend(piece(&p.meshes, k[1] - 0.01, 10.0, k, 1.02));
            pieces.push(ball("knee joint", k, knee.girth_m));
            pieces
        }
    };
    let source = match form {
        Form::ProceduralOpen | Form::ProceduralSlanted | Form::ProceduralPieces => p,
        _ => b,
    };
    (meshes, source)
}

/// `meshes` in `form`, made with `rng`; world space still.
fn meshed(meshes: Vec<RawMesh>, form: MeshForm, rng: &mut Seeded) -> Vec<RawMesh> {
    match form {
        MeshForm::AsIs | MeshForm::QuadPly => meshes,
        MeshForm::Subdivided => meshes.iter().map(subdivided).collect(),
        MeshForm::Damaged => meshes.iter().map(|m| damaged(m, rng)).collect(),
        MeshForm::Cluttered => {
            let mut meshes = meshes;
            let (low, high) = bounds(&meshes);
            for k in 0..4 {
                let side = if k % 2 == 0 { 1.0 } else { -1.0 };
                let centre = Point3::new(
                    (high.x + low.x) / 2.0 + side * (0.25 + 0.2 * rng.next()),
                    low.y + 0.1 + (high.y - low.y - 0.2) * rng.next(),
                    (high.z + low.z) / 2.0 + 0.3 * (rng.next() - 0.5),
                );
                meshes.push(debris(
                    &format!("debris{k}"),
                    centre,
                    0.01 + 0.02 * rng.next(),
                ));
            }
            meshes.push(floor(
                low.y - 0.001,
                Point3::from((low.coords + high.coords) / 2.0),
            ));
            meshes
        }
    }
}

fn bounds(meshes: &[RawMesh]) -> (Point3<f64>, Point3<f64>) {
    let points = meshes.iter().flat_map(|m| &m.positions);
    let low = points
        .clone()
        .fold(Point3::from([f64::MAX; 3]), |a, p| a.inf(p));
    let high = points.fold(Point3::from([f64::MIN; 3]), |a, p| a.sup(p));
    (low, high)
}

fn subdivided(mesh: &RawMesh) -> RawMesh {
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    // Each edge's middle from its ends in one order: the two triangles on an edge get the same
    // point, and the loader welds them.
    let middle = |a: Point3<f64>, b: Point3<f64>| {
        let (a, b) = if [a.x, a.y, a.z] < [b.x, b.y, b.z] {
            (a, b)
        } else {
            (b, a)
        };
        nalgebra::center(&a, &b)
    };
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
        let (ab, bc, ca) = (middle(a, b), middle(b, c), middle(c, a));
        for corners in [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]] {
            let first = positions.len() as u32;
            positions.extend(corners);
            triangles.push([first, first + 1, first + 2]);
        }
    }
    RawMesh {
        name: mesh.name.clone(),
        positions,
        triangles,
    }
}

fn damaged(mesh: &RawMesh, rng: &mut Seeded) -> RawMesh {
    let mut out = mesh.clone();
    let n = mesh.triangles.len();
    // Three small holes: a triangle each, away from the ends.
    let mut holes: Vec<usize> = (0..3)
        .map(|_| (n as f64 * (0.2 + 0.6 * rng.next())) as usize)
        .collect();
    holes.sort_unstable();
    holes.dedup();
    for &h in holes.iter().rev() {
        if h < out.triangles.len() {
            out.triangles.remove(h);
        }
    }
    let kept = out.triangles.clone();
    for (k, t) in kept.iter().enumerate() {
        if k % 10 == 0 {
            out.triangles.push(*t);
        }
        if k % 15 == 0 {
            out.triangles.push([t[0], t[1], t[1]]);
        }
    }
    out
}

/// A box of half side `half` around `centre`: debris beside the leg.
fn debris(name: &str, centre: Point3<f64>, half: f64) -> RawMesh {
    let (positions, triangles) = cube(&centre, half);
    RawMesh {
        name: name.into(),
        positions,
        triangles,
    }
}

fn floor(y: f64, centre: Point3<f64>) -> RawMesh {
    let corner = |dx: f64, dz: f64| Point3::new(centre.x + dx, y, centre.z + dz);
    RawMesh {
        name: "floor".into(),
        positions: vec![
            corner(-1.0, -1.0),
            corner(1.0, -1.0),
            corner(1.0, 1.0),
            corner(-1.0, 1.0),
        ],
        triangles: vec![[0, 2, 1], [0, 3, 2]],
    }
}

impl Frame {
    /// The file's coordinates from world space (metres, Y up), and the file's units.
    fn placement(self, rng: &mut Seeded) -> (nalgebra::Similarity3<f64>, Units) {
        use nalgebra::{Similarity3, Translation3, UnitQuaternion};
        let z_up = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(
            nalgebra::Matrix3::new(1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 1.0, 0.0),
        ));
        let none = Translation3::identity();
        let (rotation, translation, scale, units) = match self {
            Frame::YUpMetres => (UnitQuaternion::identity(), none, 1.0, Units::Metres),
            Frame::ZUpMetres => (z_up, none, 1.0, Units::Metres),
            Frame::ZUpCentimetres => (z_up, none, 100.0, Units::Centimetres),
            Frame::ZUpMillimetres => (z_up, none, 1000.0, Units::Millimetres),
            Frame::YUpInches => (
                UnitQuaternion::identity(),
                none,
                1.0 / 0.0254,
                Units::Inches,
            ),
            Frame::TurnedMetres => {
                let yaw = UnitQuaternion::from_axis_angle(
                    &Vector3::y_axis(),
                    std::f64::consts::TAU * rng.next(),
                );
                let about = std::f64::consts::TAU * rng.next();
                let tip = UnitQuaternion::from_axis_angle(
                    &Unit::new_normalize(Vector3::new(about.cos(), 0.0, about.sin())),
                    10f64.to_radians() * rng.next(),
                );
                let shift =
                    Vector3::new(rng.next(), rng.next(), rng.next()) * 2.0 - Vector3::repeat(1.0);
                (tip * yaw, Translation3::from(shift), 1.0, Units::Metres)
            }
        };
        (Similarity3::from_parts(translation, rotation, scale), units)
    }
}

/// What happened to one variant.
struct Outcome {
    variant: Variant,
    code: Option<i32>,
    seconds: f64,
    /// The error's or warning's line, where there was one.
    said: String,
    report: Option<Report<FitDetails>>,
    /// The worst of ankle, knee and toe tip off their truth, metres.
    landmarks_off_m: Option<f64>,
    /// Ankle, knee and toe tip as found, taken back to world space (metres): for comparing
    /// variants with each other.
    world_landmarks: Option<[Option<Point3<f64>>; 3]>,
    /// The source has a foot: the stocking must cover it.
    has_foot: bool,
}

impl Outcome {
    /// Why this variant is known not to fit yet, where it is: the table lists it, and the test
    /// fails on any other outcome.
    fn known_not_fitting(&self) -> Option<&'static str> {
        let mhr_pieces = matches!(
            self.variant.form,
            Form::MhrLeftLegPieces | Form::MhrBodyPieces
        );
        (mhr_pieces && self.code == Some(4)).then_some(
            "at the defaults a few yarn pieces still cross the skin at MHR's knee, where its \
             shin, ball and thigh pieces meet, after the penetration fix (4 pieces, points 2 µm \
             inside): exit 4, and said so; the MakeHuman mannequin's knee does not show it",
        )
    }

    fn fits(&self) -> bool {
        self.code == Some(0)
            && self.report.as_ref().is_some_and(|r| {
                r.metrics.max_penetration_m == Some(0.0)
                    && r.details.checks.passed()
                    && (!self.has_foot || r.details.tube.bottom == TubeBottom::Toe)
            })
            && self.landmarks_off_m.is_some_and(|off| off <= 0.015)
    }

    fn row(&self) -> String {
        let r = self.report.as_ref();
        let outcome = if self.fits() {
            "fits".to_string()
        } else {
            match self.code {
                Some(0) => "fits, off its truth".to_string(),
                Some(code) => format!("exit {code}: {}", self.said.replace('|', "/")),
                None => "killed".to_string(),
            }
        };
        format!(
            "| {} | {outcome} | {} | {} | {:.1} |",
            self.variant.name(),
            r.map_or("–".into(), |r| format!(
                "{:?} {}×{}",
                r.details.tube.bottom, r.details.tube.wales, r.details.tube.courses
            )),
            self.landmarks_off_m
                .map_or("–".into(), |m| format!("{:.1}", 1e3 * m)),
            self.seconds
        )
    }
}

/// Writes `variant` into `dir` and fits it with the flags `settings` (the defaults where empty)
/// as a user would.
fn run(dir: &Path, variant: Variant, settings: &[&str]) -> Outcome {
    let mut rng = Seeded(variant.seed);
    let (world, source) = formed(variant.form);
    let world = meshed(world, variant.mesh, &mut rng);
    let (file_from_world, units) = variant.frame.placement(&mut rng);
    let in_file: Vec<RawMesh> = (world.iter())
        .map(|m| RawMesh {
            positions: m.positions.iter().map(|p| file_from_world * p).collect(),
            ..m.clone()
        })
        .collect();
    let leg = write_variant(dir, &in_file, variant.mesh);
    if let Some(keep) = std::env::var_os("KNITFIT_ZOO_KEEP") {
        // The variant's file, to run by hand: named after the variant.
        let name = variant.name().replace(" / ", "-");
        let extension = leg.extension().unwrap().to_str().unwrap();
        std::fs::create_dir_all(&keep).unwrap();
        std::fs::copy(&leg, Path::new(&keep).join(format!("{name}.{extension}"))).unwrap();
    }
    let units_flag = serde_json::to_value(units).unwrap();
    let units_flag = units_flag.as_str().unwrap();
    let start = Instant::now();
    let mut args = vec!["fit", "--leg", leg.to_str().unwrap(), "--units", units_flag];
    args.extend(["--outputs", "ply", "-q"]);
    args.extend(settings);
    let out = knitfit(dir, &args);
    let seconds = start.elapsed().as_secs_f64();
    let said = stderr(&out).lines().next().unwrap_or("").to_string();
    // Exit 3 stopped early writes nothing.
    let report = (dir.join("out/report.json").is_file())
        .then(|| crate::support::read_fit_report(&dir.join("out")));
    let metres_per_unit = 1.0 / file_from_world.scaling();
    let landmarks_off_m = (report.as_ref())
        .and_then(|r| r.details.leg.landmarks.as_ref())
        .map(|got| {
            let truth = &source.truth;
            let mut pairs = vec![
                (got.ankle.centre.file, truth.ankle.centre.m),
                (got.knee.centre.file, truth.knee.centre.m),
            ];
            if let (Some(g), Some(t)) = (&got.toe_tip, &truth.toe_tip) {
                pairs.push((g.file, t.m));
            } else if got.toe_tip.is_some() != truth.toe_tip.is_some() {
                return f64::INFINITY;
            }
            pairs
                .into_iter()
                .map(|(g, t)| {
                    let t = file_from_world * Point3::from(t);
                    (Point3::from(g) - t).norm() * metres_per_unit
                })
                .fold(0.0, f64::max)
        });
    let world_from_file = file_from_world.inverse();
    let world_landmarks = (report.as_ref())
        .and_then(|r| r.details.leg.landmarks.as_ref())
        .map(|got| {
            [
                Some(got.ankle.centre.file),
                Some(got.knee.centre.file),
                got.toe_tip.as_ref().map(|t| t.file),
            ]
            .map(|p| p.map(|p| world_from_file * Point3::from(p)))
        });
    Outcome {
        variant,
        code: out.status.code(),
        seconds,
        said,
        report,
        landmarks_off_m,
        world_landmarks,
        has_foot: source.truth.toe_tip.is_some(),
    }
}

/// Writes the file of a variant: a GLB, or for [`MeshForm::QuadPly`] an ASCII PLY of its meshes
/// welded into one.
fn write_variant(dir: &Path, meshes: &[RawMesh], form: MeshForm) -> PathBuf {
    if form != MeshForm::QuadPly {
        return write_raw_meshes(dir, "leg.glb", meshes);
    }
    let mut welded: std::collections::HashMap<[u64; 3], u32> = Default::default();
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for m in meshes {
        let ids: Vec<u32> = (m.positions.iter())
            .map(|p| {
                let key = [p.x, p.y, p.z].map(|c| (c as f32).to_bits() as u64);
                *welded.entry(key).or_insert_with(|| {
                    positions.push(*p);
                    positions.len() as u32 - 1
                })
            })
            .collect();
        triangles.extend(m.triangles.iter().map(|t| t.map(|i| ids[i as usize])));
    }
    let (text, _) = leg_as_quads(&positions, &triangles);
    let path = dir.join("leg.ply");
    std::fs::write(&path, text).unwrap();
    path
}

/// The same leg made another way fits the same: landmarks within this of each other, metres...
const SAME_LANDMARKS_M: f64 = 0.01;
/// ...and each region's mean stitch area (so its stitch density) within this fraction.
const SAME_DENSITY: f64 = 0.03;

/// The metamorphic checks (issue 45): each fitted variant against the same leg made another
/// way, where that fitted too: in Y-up metres instead of its frame; as exported instead of
/// remeshed (subdivided, or quads in a PLY); open at the cut instead of closed. Returns a line
/// per pair compared and whether it held.
fn metamorphic<'a>(outcomes: &'a [Outcome]) -> Vec<(String, bool)> {
    let find = |form: Form, mesh: MeshForm, frame: Frame| {
        (outcomes.iter())
            .find(|o| (o.variant.form, o.variant.mesh, o.variant.frame) == (form, mesh, frame))
    };
    let mut lines = Vec::new();
    for o in outcomes.iter().filter(|o| o.fits()) {
        let v = o.variant;
        let mut references = Vec::new();
        if v.frame != Frame::YUpMetres {
            references.push(("frame", find(v.form, v.mesh, Frame::YUpMetres)));
        }
        if matches!(v.mesh, MeshForm::Subdivided | MeshForm::QuadPly) {
            references.push(("remeshed", find(v.form, MeshForm::AsIs, v.frame)));
        }
        let open = match v.form {
            Form::LeftLegClosed => Some(Form::LeftLegOpen),
            Form::MhrLeftLegClosed => Some(Form::MhrLeftLegOpen),
            _ => None,
        };
        if let Some(open) = open {
            references.push(("closed", find(open, v.mesh, v.frame)));
        }
        for (how, reference) in references {
            let Some(r) = reference.filter(|r| r.fits()) else {
                continue;
            };
            let (Some(a), Some(b)) = (&o.world_landmarks, &r.world_landmarks) else {
                continue;
            };
            let landmarks_m = (a.iter().zip(b))
                .filter_map(|(p, q)| Some((p.as_ref()? - q.as_ref()?).norm()))
                .fold(0.0, f64::max);
            // Both stockings over the same regions, or they differ however alike the rest is.
            let regions = |o: &'a Outcome| &o.report.as_ref().unwrap().details.stretch_by_region;
            let (x, y) = (regions(o), regions(r));
            let same_regions =
                !x.is_empty() && x.iter().map(|a| a.region).eq(y.iter().map(|b| b.region));
            let density = match same_regions {
                true => (x.iter().zip(y))
                    .map(|(a, b)| (b.area / a.area - 1.0).abs())
                    .fold(0.0, f64::max),
                false => f64::INFINITY,
            };
            let held = landmarks_m <= SAME_LANDMARKS_M && density <= SAME_DENSITY;
            lines.push((
                format!(
                    "| {} | {how}: {} | {:.2} | {:.2} | {} |",
                    v.name(),
                    r.variant.name(),
                    1e3 * landmarks_m,
                    1e2 * density,
                    if held { "same" } else { "differs" }
                ),
                held,
            ));
        }
    }
    lines
}

/// Runs `variants` with the flags `settings` (the defaults where empty), writes their table to
/// `target/zoo/NAME.md` and returns what failed unexpectedly.
fn run_zoo(variants: &[Variant], settings: &[&str], name: &str) -> Vec<String> {
    let mut rows = vec![
        "| variant (form / mesh / frame) | outcome | stocking | landmarks off, mm | seconds |"
            .to_string(),
        "|---|---|---|---:|---:|".to_string(),
    ];
    let (mut failed, mut known) = (Vec::new(), Vec::new());
    let mut fitted = 0;
    // `KNITFIT_ZOO_ONLY=Pieces` runs the variants whose name holds it: for a look at a few.
    let only = std::env::var("KNITFIT_ZOO_ONLY").unwrap_or_default();
    let variants: Vec<Variant> = (variants.iter())
        .filter(|v| v.name().contains(only.as_str()))
        .copied()
        .collect();
    let mut outcomes = Vec::new();
    for &variant in &variants {
        let dir = tempfile::tempdir().unwrap();
        let outcome = run(dir.path(), variant, settings);
        let row = outcome.row();
        println!("{row}");
        rows.push(row.clone());
        fitted += usize::from(outcome.fits());
        match outcome.known_not_fitting() {
            _ if outcome.fits() => {}
            Some(why) => known.push(format!("{} ({why})", variant.name())),
            None => failed.push(row),
        }
        outcomes.push(outcome);
    }
    rows.push(String::new());
    rows.push(format!(
        "{fitted} of {} variants fit at {}: exit 0, no yarn inside the leg, the fit's \
         checks passed, a stocking to the toe where the leg has a foot, landmarks within 15 mm \
         of their truth.",
        variants.len(),
        if settings.is_empty() {
            "the defaults".to_string()
        } else {
            settings.join(" ")
        },
    ));
    if !known.is_empty() {
        rows.push(format!("Known not to fit yet: {}.", known.len()));
        rows.extend(known.iter().map(|k| format!("- {k}")));
    }
    let pairs = metamorphic(&outcomes);
    if !pairs.is_empty() {
        let held = pairs.iter().filter(|(_, held)| *held).count();
        rows.push(String::new());
        rows.push(format!(
            "The same leg made another way (metamorphic checks): {held} of {} pairs of fitted \
             variants have landmarks within {} mm of each other and every region's stitch \
             density within {} %.",
            pairs.len(),
            1e3 * SAME_LANDMARKS_M,
            1e2 * SAME_DENSITY
        ));
        rows.push(String::new());
        rows.push("| variant | against | landmarks apart, mm | density apart, % | |".to_string());
        rows.push("|---|---|---:|---:|---|".to_string());
        for (line, held) in pairs {
            if !held {
                failed.push(line.clone());
            }
            rows.push(line);
        }
    }
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("../zoo");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join(format!("{name}.md")), rows.join("\n") + "\n").unwrap();
    failed
}

/// The zoo's CI settings: it tests how a leg is read, not how far the solver settles
/// (`solvers.rs` does); a coarser grid and tolerance than the defaults, where penetration, the
/// checks and the reach to the toe hold all the same, halve its time.
const CI_SETTINGS: [&str; 4] = ["--resolution", "100x100", "--tolerance", "3e-3"];

#[test]
fn the_zoo_ci_subset_fits_every_leg_it_should() {
    let failed = run_zoo(&ci_subset(), &CI_SETTINGS, "ci");
    assert!(failed.is_empty(), "{}", failed.join("\n"));
}

#[test]
#[ignore = "the whole zoo, 540 fits: the long profile (docs/TESTING.md)"]
fn the_whole_zoo_fits_every_leg_it_should() {
    let failed = run_zoo(&all_variants(), &[], "all");
    assert!(failed.is_empty(), "{}", failed.join("\n"));
}

#[test]
fn the_ci_subset_covers_every_value_of_every_axis_once_each_variant() {
    let subset = ci_subset();
    let names: std::collections::HashSet<String> = subset.iter().map(Variant::name).collect();
    assert_eq!(names.len(), 44);
    assert!(FORMS
        .iter()
        .all(|f| subset.iter().filter(|v| v.form == *f).count() >= 2));
    assert!(MESH_FORMS
        .iter()
        .all(|m| subset.iter().filter(|v| v.mesh == *m).count() >= 6));
    assert!(FRAMES
        .iter()
        .all(|f| subset.iter().filter(|v| v.frame == *f).count() >= 6));
}

/// A turn of `degrees` about the line through `pivot` along X (the body's left): a joint's
/// bend in the sagittal plane, positive turning +Z (forward) down.
fn turn_about(pivot: &Point3<f64>, degrees: f64) -> nalgebra::IsometryMatrix3<f64> {
    let turn = Rotation3::from_axis_angle(&Vector3::x_axis(), degrees.to_radians());
    nalgebra::Translation3::from(pivot.coords) * turn * nalgebra::Translation3::from(-pivot.coords)
}

/// The weight across a joint's 4 cm band: 0 to 1, smooth at both ends.
fn smoothstep(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// `meshes` (a left leg, cut or in pieces, or a mannequin) in a mannequin's stride: the foot
/// pointed `foot_deg` down about its ankle (2 cm under the ankle's section), the shin and foot
/// turned `knee_deg` back about the knee, then the whole leg `hip_deg` forward about the top of
/// the thigh (`source`'s truth; the body faces +Z, its left is +X). A piece that ends near the
/// knee is turned whole, as a mannequin's are, by where its centre lies (the knee's ball with
/// the thigh, the ankle's with the shin); a mesh across a joint is blended over 4 cm there, as a
/// skin blends it. A mannequin's other pieces (its trunk, above the thigh top, and its right
/// leg) stay. Also the toe tip, posed.
fn strided(
    meshes: &[RawMesh],
    source: &Source,
    (knee_deg, hip_deg, foot_deg): (f64, f64, f64),
) -> (Vec<RawMesh>, Option<Point3<f64>>) {
    let ankle = Point3::from(source.truth.ankle.centre.m) - Vector3::y() * 0.02;
    let knee = Point3::from(source.truth.knee.centre.m);
    let top = Point3::from(source.truth.thigh_top.centre.m);
    // The pieces of the left leg, by their centre: all but a mannequin's trunk and right leg.
    let on_the_leg = |c: &Vector3<f64>| c.y < top.y && c.x > top.x - 0.1;
    let (pointed, bent, flexed) = (
        turn_about(&ankle, foot_deg),
        turn_about(&knee, knee_deg),
        turn_about(&top, -hip_deg),
    );
    let pose = |p: &Point3<f64>, on_shin: f64, on_foot: f64| {
        let p = Point3::from(p.coords * (1.0 - on_foot) + (pointed * p).coords * on_foot);
        let at_knee = p.coords * (1.0 - on_shin) + (bent * p).coords * on_shin;
        flexed * Point3::from(at_knee)
    };
    let posed = (meshes.iter())
        .map(|m| {
            let centre = m
                .positions
                .iter()
                .fold(Vector3::zeros(), |s, p| s + p.coords)
                / m.positions.len() as f64;
            // A mesh across the knee is a limb modelled whole; a piece ends near it.
            let (low, high) = (m.positions.iter())
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
                    (l.min(p.y), h.max(p.y))
                });
            let whole = low > knee.y - 0.06 || high < knee.y + 0.06;
            if !on_the_leg(&centre) {
                return m.clone();
            }
            RawMesh {
                positions: (m.positions.iter())
                    .map(|p| match whole {
                        true => pose(
                            p,
                            f64::from(u8::from(centre.y < knee.y - 0.01)),
                            f64::from(u8::from(centre.y < ankle.y - 0.01)),
                        ),
                        false => pose(
                            p,
                            smoothstep((knee.y - p.y + 0.02) / 0.04),
                            smoothstep((ankle.y - p.y + 0.02) / 0.04),
                        ),
                    })
                    .collect(),
                ..m.clone()
            }
        })
        .collect();
    let toe = (source.truth.toe_tip.as_ref()).map(|t| pose(&Point3::from(t.m), 1.0, 1.0));
    (posed, toe)
}

/// Fits `meshes`, written as a GLB into `dir` (and, with `KNITFIT_ZOO_KEEP=DIR`, kept there as
/// `name.glb`), with the binary writing only `stocking.ply` beside its report, and `flags`.
fn fit_meshes(dir: &Path, meshes: &[RawMesh], name: &str, flags: &[&str]) -> std::process::Output {
    let leg = write_raw_meshes(dir, "leg.glb", meshes);
    if let Some(keep) = std::env::var_os("KNITFIT_ZOO_KEEP") {
        std::fs::create_dir_all(&keep).unwrap();
        std::fs::copy(&leg, Path::new(&keep).join(format!("{name}.glb"))).unwrap();
    }
    let leg = leg.to_str().unwrap();
    let args = ["fit", "--leg", leg, "--outputs", "ply", "-q"];
    knitfit(dir, &[&args[..], flags].concat())
}

/// How near the yarn of the fit written into `out` (`stocking.ply`) comes to `point`, metres.
fn yarn_gap_to(out: &Path, point: &Point3<f64>) -> f64 {
    let yarn = crate::support::read_ply(&out.join("stocking.ply"));
    (yarn.payload["vertex"].iter())
        .map(|v| {
            let at = |k: &str| crate::support::float(v, k);
            (Point3::new(at("x"), at("y"), at("z")) - point).norm()
        })
        .fold(f64::INFINITY, f64::min)
}

/// `form` (a leg with a foot) posed by `strided` (knee, hip and foot degrees) fitted at
/// [`CI_SETTINGS`], held to exit 0, no yarn inside the leg, the checks passed, a stocking to the
/// toe and its yarn within 1.5 cm of the posed toe tip; and the bend its straightening read.
fn posed_fit(form: Form, pose: (f64, f64, f64), name: &str) -> Bend {
    let (meshes, source) = formed(form);
    let (posed, toe) = strided(&meshes, source, pose);
    let dir = tempfile::tempdir().unwrap();
    let out = fit_meshes(
        dir.path(),
        &posed,
        &format!("{form:?}-{name}"),
        &CI_SETTINGS,
    );
    assert_eq!(out.status.code(), Some(0), "{form:?}: {}", stderr(&out));
    let report = crate::support::read_fit_report(&dir.path().join("out"));
    assert_eq!(report.metrics.max_penetration_m, Some(0.0), "{form:?}");
    assert!(report.details.checks.failures().is_empty(), "{form:?}");
    // The stocking is on the posed foot, to its toe: its yarn reaches the toe tip.
    let toe = toe.unwrap_or_else(|| panic!("{form:?} has a foot"));
    assert_eq!(report.details.tube.bottom, TubeBottom::Toe, "{form:?}");
    let gap = yarn_gap_to(&dir.path().join("out"), &toe);
    assert!(
        gap < 0.015,
        "{form:?}: the yarn is {gap} m from the toe tip"
    );
    (report.details.pose.as_ref())
        .and_then(|p| p.bend)
        .unwrap_or_else(|| panic!("{form:?}: not straightened"))
}

#[test]
fn a_leg_closed_or_open_at_its_cut_mid_stride_is_straightened_and_fitted_in_its_pose() {
    // Issue 45's table: a closed leg with its knee bent, and a mannequin's leg (pieces, a ball
    // at the knee) mid-stride, were refused. Knee 45°, hip 30°, no rig, the MakeHuman left leg
    // closed and open at its cut. Not every stride fits yet: the stride zoo's table in ZOO.md
    // (`the_stride_zoo_table`) says which.
    for form in [Form::LeftLegClosed, Form::LeftLegOpen] {
        let bend = posed_fit(form, (45.0, 30.0, 0.0), "Stride");
        assert!((bend.knee_deg - 45.0).abs() < 15.0, "{form:?}: {bend:?}");
    }
}

#[test]
fn a_foot_pointed_down_without_a_rig_is_turned_back_to_stand_and_dressed_to_its_toe() {
    // Issue 45's "a foot pointed 45° (high heels)": sections along up cut a pointed foot
    // through its toes, or read its ankle and fit a standing stocking's foot onto it, which
    // cannot settle (exit 3). The MakeHuman left leg closed and open at its cut, its foot
    // pointed 45° and no rig: the foot is turned back to stand, fitted, and carried back.
    for form in [Form::LeftLegClosed, Form::LeftLegOpen] {
        let bend = posed_fit(form, (0.0, 0.0, 45.0), "Pointed");
        assert!((bend.foot_deg - 45.0).abs() < 10.0, "{form:?}: {bend:?}");
    }
}

#[test]
fn a_slim_foot_hanging_under_its_ankle_is_turned_back_not_dressed_to_the_ankle() {
    // MHR's left leg closed at its cut, its foot pointed 70°: the foot is slim enough to hang
    // under the ankle, so sections along up find the ankle where it is, 24.5 cm above the toe
    // tip, and no foot reaching out from it. It was dressed to the ankle, exit 0, 24 cm short
    // of the toe; the foot is now turned back about its hinge before the fit (the plan says).
    let (meshes, source) = formed(Form::MhrLeftLegClosed);
    let (posed, _) = strided(&meshes, source, (0.0, 0.0, 70.0));
    let dir = tempfile::tempdir().unwrap();
    let leg = write_raw_meshes(dir.path(), "leg.glb", &posed);
    let out = knitfit(
        dir.path(),
        &["plan", "--leg", leg.to_str().unwrap(), "--json"],
    );
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let plan: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let foot = plan["leg"]["straightened"]["foot_deg"].as_f64();
    assert!(foot.is_some_and(|f| (f - 70.0).abs() < 10.0), "{plan}");
    assert!(
        !plan["landmarks"]["toe_tip"].is_null(),
        "the rest pose has its foot"
    );
}

/// `meshes` (a body, whole or a mannequin in pieces) with the foot on `side` (+1 left, -1
/// right) pointed `degrees` down about its ankle (2 cm under `source`'s ankle, mirrored for the
/// right), as [`strided`] points the left: a piece below the ankle is turned whole, a mesh
/// across it blended over 4 cm, vertex by vertex on that side of the body's middle.
fn foot_pointed(meshes: &[RawMesh], source: &Source, side: f64, degrees: f64) -> Vec<RawMesh> {
    let truth = source.truth.ankle.centre.m;
    let pivot = Point3::new(side * truth[0], truth[1] - 0.02, truth[2]);
    let turn = turn_about(&pivot, degrees);
    (meshes.iter())
        .map(|m| {
            let n = m.positions.len() as f64;
            let centre = m
                .positions
                .iter()
                .fold(Vector3::zeros(), |s, p| s + p.coords)
                / n;
            let high = m
                .positions
                .iter()
                .map(|p| p.y)
                .fold(f64::NEG_INFINITY, f64::max);
            // A mannequin's foot piece: below the ankle's ball, on this side.
            let piece = high < pivot.y + 0.06 && side * centre.x > 0.0;
            let weight = |p: &Point3<f64>| match piece {
                true => f64::from(u8::from(centre.y < pivot.y - 0.01)),
                false => {
                    smoothstep((pivot.y - p.y + 0.02) / 0.04)
                        * f64::from(u8::from(side * p.x > 0.0))
                }
            };
            RawMesh {
                positions: (m.positions.iter())
                    .map(|p| {
                        let w = weight(p);
                        Point3::from(p.coords * (1.0 - w) + (turn * p).coords * w)
                    })
                    .collect(),
                ..m.clone()
            }
        })
        .collect()
}

#[test]
fn a_body_on_the_toes_of_one_foot_or_both_is_read_standing_and_dressed_to_the_toe() {
    // A right foot on its toes (pointed 45°) puts the body's lowest point under it, and the
    // left, flat, was first cut at its very sole, with nothing below to read a foot from: MHR's
    // body was dressed from the ankle, 0.14 m up, exit 0. Both feet pointed (a high heel's
    // pose, issue 45's table): MHR's mannequin straightened its left foot, then read it so.
    // Each left leg is planned with its foot, so to the toe (MHR's tip within 2 cm); a
    // straightened one turned back about as far as it was pointed.
    for (form, both) in [
        (Form::MhrBody, false),
        (Form::Body, false),
        (Form::MhrBodyPieces, true),
    ] {
        let (meshes, source) = formed(form);
        let mut posed = foot_pointed(&meshes, source, -1.0, 45.0);
        if both {
            posed = foot_pointed(&posed, source, 1.0, 45.0);
        }
        let dir = tempfile::tempdir().unwrap();
        let leg = write_raw_meshes(dir.path(), "leg.glb", &posed);
        let args = [
            "plan",
            "--leg",
            leg.to_str().unwrap(),
            "--side",
            "left",
            "--json",
        ];
        let out = knitfit(dir.path(), &args);
        assert_eq!(out.status.code(), Some(0), "{form:?}: {}", stderr(&out));
        let plan: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let toe = &plan["landmarks"]["toe_tip"]["m"];
        assert!(!toe.is_null(), "{form:?}: no foot read: {plan}");
        let foot = plan["leg"]["straightened"]["foot_deg"].as_f64();
        if both {
            assert!(
                foot.is_some_and(|f| (f - 45.0).abs() < 10.0),
                "{form:?}: {plan}"
            );
        } else {
            assert!(foot.is_none(), "{form:?}: the left foot stands: {plan}");
            // MakeHuman's flat foot is cut 1 cm above its sole and read there, its toe tip
            // 2.3 cm short (decision 0079); MHR's is read from higher up.
            if form == Form::Body {
                continue;
            }
            let truth = source.truth.toe_tip.as_ref().unwrap().m;
            let off = (0..3)
                .map(|k| (toe[k].as_f64().unwrap() - truth[k]).powi(2))
                .sum::<f64>();
            assert!(off.sqrt() < 0.02, "{form:?}: toe {toe} for {truth:?}");
        }
    }
}

/// The stride zoo's poses: knee, hip and foot degrees.
const STRIDES: [(f64, f64, f64); 7] = [
    (30.0, 0.0, 0.0),
    (45.0, 0.0, 0.0),
    (45.0, 30.0, 0.0),
    (60.0, 40.0, 0.0),
    (20.0, 40.0, 0.0),
    (0.0, 0.0, 45.0),
    (0.0, 0.0, 70.0),
];

#[test]
#[ignore = "the stride zoo, 98 fits at the defaults: the long profile (docs/TESTING.md)"]
fn the_stride_zoo_table() {
    // Each left leg of the zoo, cut or in pieces, posed without a rig at five strides (knee,
    // hip degrees) and on a foot pointed 45° (a high heel's) and 70° (a dancer's), fitted at
    // the defaults: the table ZOO.md's "Strides without a rig" has. Not every stride fits yet
    // (the table says which); none may exit 0 with yarn inside the leg or short of the posed
    // toe.
    let mut rows = vec![
        "| form / knee° / hip° / foot° | outcome | bend read (knee°, thigh°, foot°) | yarn to the toe tip, mm \
         | seconds |"
            .to_string(),
        "|---|---|---|---:|---:|".to_string(),
    ];
    // A stride turns one leg: every form but the two whose legs are one mesh with the body.
    let forms: Vec<Form> = (FORMS.into_iter())
        .filter(|f| {
            !matches!(
                f,
                Form::Body | Form::LowerBody | Form::MhrBody | Form::MhrLowerBody
            )
        })
        .collect();
    // `KNITFIT_ZOO_ONLY=TEXT` fits only the strides whose row names contain TEXT.
    let only = std::env::var("KNITFIT_ZOO_ONLY").unwrap_or_default();
    let (mut fitted, mut total, mut silent) = (0, 0, Vec::new());
    for &form in &forms {
        for (knee, hip, foot) in STRIDES {
            let name = format!("{form:?} / {knee} / {hip} / {foot}");
            if !name.contains(only.as_str()) {
                continue;
            }
            total += 1;
            let (meshes, source) = formed(form);
            let (posed, toe) = strided(&meshes, source, (knee, hip, foot));
            let dir = tempfile::tempdir().unwrap();
            let started = Instant::now();
            let file = format!("{form:?}-{knee}-{hip}-{foot}");
            let out = fit_meshes(dir.path(), &posed, &file, &[]);
            let seconds = started.elapsed().as_secs_f64();
            let report_path = dir.path().join("out/report.json");
            if !report_path.is_file() {
                let said = stderr(&out).lines().next().unwrap_or("").to_string();
                // What it said, less "knitfit: error: " and the temporary file's name.
                let said = (said.split(": ").skip(2))
                    .filter(|part| !part.ends_with("leg.glb"))
                    .collect::<Vec<_>>()
                    .join(": ");
                rows.push(format!(
                    "| {name} | exit {:?}: {said} | | | {seconds:.1} |",
                    out.status.code()
                ));
                println!("{}", rows.last().unwrap());
                continue;
            }
            let report = crate::support::read_fit_report(&dir.path().join("out"));
            let bend = (report.details.pose.as_ref()).and_then(|p| p.bend);
            let read = bend.map_or("not straightened".to_string(), |b| {
                format!("{:.0}, {:.0}, {:.0}", b.knee_deg, b.thigh_deg, b.foot_deg)
            });
            let gap = toe.map(|toe| yarn_gap_to(&dir.path().join("out"), &toe));
            let crossing = report.details.checks.yarn_pieces_crossing.unwrap_or(0);
            let exit_0 = out.status.code() == Some(0);
            let sound = report.metrics.max_penetration_m == Some(0.0) && gap.unwrap_or(0.0) <= 0.03;
            if exit_0 && !sound {
                silent.push(name.clone());
            }
            let fits = exit_0 && sound;
            fitted += usize::from(fits);
            let gap = gap.map_or("–".to_string(), |g| format!("{:.0}", 1e3 * g));
            let outcome = match fits {
                true => "fits".to_string(),
                false => format!(
                    "exit {:?}, {crossing} yarn pieces crossing",
                    out.status.code()
                ),
            };
            rows.push(format!(
                "| {name} | {outcome} | {read} | {gap} | {seconds:.1} |"
            ));
            println!("{}", rows.last().unwrap());
        }
    }
    rows.push(String::new());
    rows.push(format!("{fitted} of {} strides fit at the defaults: exit 0, no yarn inside the leg, the yarn within 3 cm of the posed toe tip.", total));
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("../zoo");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("strides.md"), rows.join("\n") + "\n").unwrap();
    assert!(silent.is_empty(), "exit 0 on a bad fit: {silent:?}");
}

#[test]
fn the_body_mirrored_left_to_right_dresses_its_right_leg_as_the_left_was() {
    // Issue 45's mirrored metamorphic check: the MakeHuman body mirrored across its middle
    // (x → −x, each triangle rewound), its right leg dressed (the mirror of the left), against
    // the body as exported, its left leg dressed: landmarks within 1 cm once mirrored back, and
    // every region's stitch density within 3 %.
    let b = body();
    let mirrored: Vec<RawMesh> = (b.meshes.iter())
        .map(|m| RawMesh {
            positions: m
                .positions
                .iter()
                .map(|p| Point3::new(-p.x, p.y, p.z))
                .collect(),
            triangles: m.triangles.iter().map(|t| [t[0], t[2], t[1]]).collect(),
            ..m.clone()
        })
        .collect();
    let fit = |meshes: &[RawMesh], side: &str| {
        let dir = tempfile::tempdir().unwrap();
        let flags = [&["--side", side][..], &CI_SETTINGS[..]].concat();
        let out = fit_meshes(dir.path(), meshes, &format!("Body-{side}"), &flags);
        assert_eq!(out.status.code(), Some(0), "{side}: {}", stderr(&out));
        crate::support::read_fit_report(&dir.path().join("out"))
    };
    let (left, right) = (fit(&b.meshes, "left"), fit(&mirrored, "right"));
    let (l, r) = (
        left.details.leg.landmarks.as_ref().unwrap(),
        right.details.leg.landmarks.as_ref().unwrap(),
    );
    let back = |p: [f64; 3]| Point3::new(-p[0], p[1], p[2]);
    let pairs = [
        (l.ankle.centre.m, r.ankle.centre.m),
        (l.knee.centre.m, r.knee.centre.m),
        (l.toe_tip.as_ref().unwrap().m, r.toe_tip.as_ref().unwrap().m),
    ];
    let mut furthest = 0.0f64;
    for (a, b) in pairs {
        let off = (Point3::from(a) - back(b)).norm();
        assert!(
            off <= SAME_LANDMARKS_M,
            "{a:?} against {b:?} mirrored: {off} m"
        );
        furthest = furthest.max(off);
    }
    let (x, y) = (
        &left.details.stretch_by_region,
        &right.details.stretch_by_region,
    );
    assert!(!x.is_empty() && x.iter().map(|a| a.region).eq(y.iter().map(|b| b.region)));
    let mut most = 0.0f64;
    for (a, b) in x.iter().zip(y) {
        let differs = (b.area / a.area - 1.0).abs();
        assert!(differs <= SAME_DENSITY, "{:?}: {differs}", a.region);
        most = most.max(differs);
    }
    println!("mirrored: landmarks {furthest:.2e} m apart, region densities within {most:.2e}");
}
