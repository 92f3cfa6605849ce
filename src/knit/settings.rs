//! The knit's settings (the scene's `knit`, `yarns`, `tube` and `patch`): the pattern and the
//! relaxed stitch, the two yarn materials, the tube a fit starts from, and the flat patch of the
//! paper's experiment. Lengths in metres; yarn sizes in denier; stiffness relative to one nylon
//! stitch ([`super::fabric`]).

use serde::{Deserialize, Serialize};

use super::nylon::yarn_diameter_m;
use super::Pattern;
use crate::base::settings::{self, Invalid};
use crate::base::{GridSize, PerYarn, YarnKind};

/// Knit structure.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct KnitSettings {
    /// `"plain"` (one nylon yarn) or `"alternating"` (nylon and support yarn in alternate courses,
    /// the paper's 交編). Default: `"alternating"`.
    pub pattern: Pattern,
    /// Needles of the knitting machine: real stitches (wales) around the stocking, fixed down
    /// the leg (default: 400, a sheer stocking's machine). At least the grid's `tube.wales`.
    /// Unused where `tube.relaxed_circumference_m` is given: the stitches around are then that
    /// over `course_spacing_m`.
    pub needles: usize,
    /// The relaxed stitch's width: the distance between neighbouring wales along a course, in
    /// metres (default: 0.0005, i.e. 20 wales per cm, typical of a sheer stocking).
    pub course_spacing_m: f64,
    /// The relaxed stitch's height: the distance between neighbouring courses along a wale, in
    /// metres (default: 0.00074). With the width it sets the fabric's stitch shape, which a fit
    /// keeps at any grid size (`Knit::with_stitch_shape`; why not a square stitch:
    /// docs/decisions/0024), and the real stitch count each grid cell stands for.
    pub wale_spacing_m: f64,
    /// Connection factor c2 of eq. (2), dimensionless (default: 0.2, the paper's value). Used only
    /// when `effects` lists `yarn_connection`.
    pub connection_factor: f64,
}

impl Default for KnitSettings {
    fn default() -> Self {
        KnitSettings {
            pattern: Pattern::Alternating,
            needles: 400,
            course_spacing_m: 0.0005,
            wale_spacing_m: 0.00074,
            connection_factor: 0.2,
        }
    }
}

/// The two yarn materials.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Yarns {
    /// Nylon yarn (default: stiffness 1, 20 denier). The only yarn of a plain pattern.
    pub nylon: Yarn,
    /// Support yarn, an elastane core wrapped in nylon (default: stiffness 10, 40 denier). Used
    /// by the alternating pattern.
    pub support: Yarn,
}

impl Default for Yarns {
    fn default() -> Self {
        Yarns {
            nylon: Yarn {
                stiffness: 1.0,
                denier: 20.0,
                colour: [0.16, 0.11, 0.09],
            },
            support: Yarn {
                stiffness: 10.0,
                denier: 40.0,
                colour: [0.08, 0.07, 0.10],
            },
        }
    }
}

impl Yarns {
    /// A value of each yarn kind's material, in [`YarnKind::index`] order.
    pub fn each<T>(&self, value: impl Fn(&Yarn) -> T) -> PerYarn<T> {
        YarnKind::ALL.map(|kind| value(self.get(kind)))
    }

    /// The material of a yarn kind.
    pub fn get(&self, kind: YarnKind) -> &Yarn {
        match kind.material() {
            YarnKind::Support => &self.support,
            _ => &self.nylon,
        }
    }
}

/// One yarn material.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Yarn {
    /// Spring stiffness c1 of eq. (1), relative to one stitch of the nylon yarn (whose loop
    /// stiffness follows from its denier and nylon's modulus, [`super::fabric`]). The paper uses
    /// 1 for nylon, 10 for support.
    pub stiffness: f64,
    /// Yarn size, denier (grams per 9 km); its diameter follows from nylon's density
    /// ([`Yarn::diameter_m`]): the contact offset (nylon), the coverage and every
    /// picture. Under 10 is ultra-sheer, 15–20 sheer, 30–40 semi-opaque, 50 and up opaque.
    pub denier: f64,
    /// Linear-RGB base colour, each channel 0–1.
    #[serde(default = "default_colour")]
    pub colour: [f64; 3],
}

impl Yarn {
    /// The yarn's diameter, metres, from its denier as solid nylon
    /// ([`super::nylon::yarn_diameter_m`]).
    pub fn diameter_m(&self) -> f64 {
        yarn_diameter_m(self.denier)
    }

    /// The yarn's radius, metres: half its [`diameter_m`](Yarn::diameter_m).
    pub fn radius_m(&self) -> f64 {
        self.diameter_m() / 2.0
    }
}

fn default_colour() -> [f64; 3] {
    [0.15, 0.1, 0.1]
}

/// The stocking tube before fitting (paper §6.1).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TubeSettings {
    /// Points around the tube (wales) (default: 150, the paper's smaller fit).
    pub wales: usize,
    /// Rings along the tube (courses). Absent means as many as make each grid cell the same
    /// number of real stitches along as around, once the stocking's length is known
    /// ([`super::Fabric::grid_courses`]: some 260 for 150 wales on a stocking to the toe)
    /// (default: absent).
    pub courses: Option<usize>,
    /// Circumference of the stocking lying relaxed, metres. Absent means `knit.needles` ×
    /// `knit.course_spacing_m` (default: absent, 0.20 m for 400 needles at 0.5 mm, a typical
    /// sheer stocking's leg measured flat and doubled).
    pub relaxed_circumference_m: Option<f64>,
    /// Length of the relaxed stocking along its centreline (between the two axis points of an
    /// open tube; from the welt over the heel to the toe of a whole stocking), metres; must be
    /// shorter than that line, since a stocking is worn stretched along the leg. Absent means
    /// [`RELAXED_LENGTH_FRACTION`] of its length (default: absent).
    pub relaxed_length_m: Option<f64>,
    /// Where the stocking ends at the bottom: `"toe"` (over the foot, closed by a toe seam) or
    /// `"ankle"` (an open end at the ankle). Absent means the toe on a leg with a foot and the
    /// ankle on one without, or where `leg.axis` is given (default: absent).
    pub bottom: Option<TubeBottom>,
    /// The heel: `"none"` (a heel-less tube, as most sheer hosiery is knitted) or `"pocket"`
    /// (short rows over the back of the heel). Only a stocking that reaches the toe has one
    /// (default: `"none"`).
    pub heel: TubeHeel,
    /// Where the stocking ends on the thigh (default: `{"below_crotch_m": 0.05}`, a
    /// thigh-high's welt).
    pub top: TubeTop,
}

/// Where the stocking starts.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum TubeBottom {
    /// Over the heel and down the foot, closed across the toes by a toe seam.
    #[default]
    Toe,
    /// At the ankle: the narrowest girth above the foot (or just inside the cut of a leg that
    /// has no foot). The stocking's end is open and held there.
    Ankle,
}

impl TubeBottom {
    /// Name as in scene files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            TubeBottom::Toe => "toe",
            TubeBottom::Ankle => "ankle",
        }
    }
}

/// The heel of a stocking that reaches the toe.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum TubeHeel {
    /// No heel: the tube goes straight over the heel ("sandal foot").
    #[default]
    None,
    /// A heel pocket of short rows over the back half of the tube (see `knit::tube`).
    Pocket,
}

impl TubeHeel {
    /// Name as in scene files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            TubeHeel::None => "none",
            TubeHeel::Pocket => "pocket",
        }
    }
}

/// Where the stocking ends.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum TubeTop {
    /// This far below the crotch, metres (on a leg cut below the crotch: just inside the cut).
    BelowCrotchM(f64),
    /// At this fraction of the leg's height from the sole to the top of the thigh (1 = the
    /// crotch or the cut).
    Fraction(f64),
}

impl Default for TubeTop {
    fn default() -> Self {
        TubeTop::BelowCrotchM(0.05)
    }
}

/// A stocking's relaxed length as a fraction of the leg length it covers, when the scene does
/// not give one: sheer stockings are worn stretched by about 1.4× along the leg.
pub const RELAXED_LENGTH_FRACTION: f64 = 0.7;

impl Default for TubeSettings {
    fn default() -> Self {
        TubeSettings {
            wales: 150,
            courses: None,
            relaxed_circumference_m: None,
            relaxed_length_m: None,
            bottom: None,
            heel: TubeHeel::None,
            top: TubeTop::default(),
        }
    }
}

/// Direction a patch is stretched in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StretchAxis {
    /// Along the course: the two end wales are held and pulled apart.
    Course,
    /// Along the wale: the first and last courses are held and pulled apart.
    Wale,
}

impl StretchAxis {
    /// Name as in scene files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            StretchAxis::Course => "course",
            StretchAxis::Wale => "wale",
        }
    }
}

/// One stretch of the patch experiment.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Stretch {
    /// Which pair of edges is held and pulled apart.
    pub axis: StretchAxis,
    /// Held-edge distance over rest distance, dimensionless (1 = unstretched).
    pub factor: f64,
}

impl std::fmt::Display for Stretch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}={}", self.axis.name(), self.factor)
    }
}

/// The flat-patch experiment (paper §5, Fig. 8/9).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PatchSettings {
    /// Patch size as `[wales, courses]`, points (default: `[10, 10]`, the paper's patch).
    pub size: GridSize,
    /// Stretches to run, each on a fresh patch; drawn side by side (default: course ×1.5 and
    /// wale ×1.5, the paper's Fig. 9).
    pub stretch: Vec<Stretch>,
}

impl Default for PatchSettings {
    fn default() -> Self {
        PatchSettings {
            size: GridSize::new(10, 10),
            stretch: vec![
                Stretch {
                    axis: StretchAxis::Course,
                    factor: 1.5,
                },
                Stretch {
                    axis: StretchAxis::Wale,
                    factor: 1.5,
                },
            ],
        }
    }
}

/// Largest stretch factor accepted: beyond it the mass-spring model has long stopped being yarn.
pub const MAX_STRETCH: f64 = 10.0;
/// Largest patch accepted, in points.
pub const MAX_PATCH_POINTS: usize = 4_000_000;
/// Largest tube a knit can hold, in points: its points, springs (two per point) and entries of
/// its per-point spring lists (four per point) are numbered in 32 bits. Below it, what limits a
/// tube is the memory it needs (`crate::limits`), which can be overridden; this cannot.
pub const MAX_TUBE_POINTS: usize = (u32::MAX / 4) as usize;

/// Most needles accepted: hosiery machines have a few hundred; beyond this a "stocking" is a
/// mistake in the scene, and its stitch count would overflow what a run can hold.
pub const MAX_NEEDLES: usize = 100_000;
/// Largest relaxed stitch accepted, metres: a knitted stitch is well under a centimetre.
pub const MAX_STITCH_M: f64 = 0.02;
/// Smallest relaxed stitch accepted, metres: a stitch is several of its yarn's diameters, and the
/// finest yarn (about 7 den) is some 30 µm across.
pub const MIN_STITCH_M: f64 = 1e-5;
/// Heaviest yarn accepted, denier (10,000 den is a nylon cord over 1 mm across).
pub const MAX_DENIER: f64 = 10_000.0;
/// Largest yarn stiffness accepted, relative to nylon's: far past any yarn pair the solver can
/// balance.
pub const MAX_STIFFNESS: f64 = 1e6;
/// Smallest yarn stiffness accepted, relative to nylon's: as far below as the largest is above.
pub const MIN_STIFFNESS: f64 = 1e-6;
/// Longest relaxed circumference or length of a stocking accepted, metres.
pub const MAX_STOCKING_M: f64 = 10.0;

impl KnitSettings {
    /// Checks every value; the error names the field under `knit`.
    pub fn validate(&self) -> Result<(), Invalid> {
        if !(3..=MAX_NEEDLES).contains(&self.needles) {
            return Err(Invalid::new(
                "needles",
                format!(
                    "must be 3 to {MAX_NEEDLES} (a sheer stocking has about 400), got {}",
                    self.needles
                ),
            ));
        }
        let stitch =
            |field: &str, value: f64| settings::within(field, value, MIN_STITCH_M, MAX_STITCH_M);
        stitch("course_spacing_m", self.course_spacing_m)?;
        stitch("wale_spacing_m", self.wale_spacing_m)?;
        let c2 = self.connection_factor;
        if !(c2.is_finite() && (0.0..1.0).contains(&c2)) {
            return Err(Invalid::new(
                "connection_factor",
                format!("must be in [0, 1), got {c2}"),
            ));
        }
        Ok(())
    }
}

impl Yarns {
    /// Checks every value; the error names the field under `yarns`.
    pub fn validate(&self) -> Result<(), Invalid> {
        for kind in YarnKind::KNITTED {
            let yarn = self.get(kind);
            let check = || -> Result<(), Invalid> {
                settings::within("stiffness", yarn.stiffness, MIN_STIFFNESS, MAX_STIFFNESS)?;
                settings::positive_at_most("denier", yarn.denier, MAX_DENIER)?;
                settings::colour("colour", yarn.colour)
            };
            check().map_err(|e| e.within(kind.name()))?;
        }
        Ok(())
    }
}

/// Refuses a tube `grid` too small to be a tube or too large for a knit's 32-bit point indices;
/// the message says which.
pub fn check_grid_size(grid: GridSize) -> Result<(), String> {
    let GridSize {
        wales: w,
        courses: c,
    } = grid;
    if w < 3 || c < 2 {
        return Err(format!("needs at least 3 wales and 2 courses, got {w}×{c}"));
    }
    if w.checked_mul(c).is_none_or(|n| n > MAX_TUBE_POINTS) {
        return Err(format!(
            "{w}×{c} points is over the {MAX_TUBE_POINTS} points a knit's 32-bit indices can \
             number"
        ));
    }
    Ok(())
}

/// Fewest wales or courses a stocking to the toe is fitted on: below it the rings are
/// centimetres apart over the heel and the toe. Its coarse levels may go to
/// `sim::multilevel::STOCKING_COARSEST`, as they only start the next level.
pub const SMALLEST_STOCKING: usize = 60;

impl TubeSettings {
    /// Refuses a grid too coarse for a stocking to the toe; the error names `wales` (and
    /// `courses`) under `tube`. Courses left out are taken at the fewest allowed here, and
    /// checked again once the stocking's length gives them.
    pub fn check_to_the_toe(&self) -> Result<(), Invalid> {
        let (wales, courses) = (self.wales, self.courses.unwrap_or(SMALLEST_STOCKING));
        if wales.min(courses) >= SMALLEST_STOCKING {
            return Ok(());
        }
        Err(Invalid::new(
            "wales",
            format!(
                "at {wales}×{courses} the rings would be centimetres apart over the heel and the \
                 toe, where such a coarse fit chatters instead of settling; give at least \
                 {SMALLEST_STOCKING}×{SMALLEST_STOCKING} (--resolution, tube.wales and \
                 tube.courses), or end the stocking at the ankle (--bottom ankle)"
            ),
        )
        .with(&["courses"]))
    }

    /// Checks every value; the error names the field under `tube`.
    pub fn validate(&self) -> Result<(), Invalid> {
        let w = self.wales;
        let grid = match self.courses {
            Some(c) => check_grid_size(GridSize::new(w, c)),
            // Courses left out are known, and checked, once the stocking's length is.
            None if w < 3 => Err(format!("needs at least 3 wales, got {w}")),
            None if w > MAX_TUBE_POINTS / 2 => Err(format!(
                "{w} wales by at least 2 courses is over the {MAX_TUBE_POINTS} points a knit's \
                 32-bit indices can number"
            )),
            None => Ok(()),
        };
        grid.map_err(|message| Invalid::new("", message))?;
        if let Some(circumference) = self.relaxed_circumference_m {
            settings::positive_at_most("relaxed_circumference_m", circumference, MAX_STOCKING_M)?;
        }
        if let Some(length) = self.relaxed_length_m {
            settings::positive_at_most("relaxed_length_m", length, MAX_STOCKING_M)?;
        }
        if self.heel == TubeHeel::Pocket && self.bottom == Some(TubeBottom::Ankle) {
            return Err(Invalid::new(
                "heel",
                "a heel pocket needs a stocking that reaches the toe; tube.bottom is \"ankle\"",
            ));
        }
        if self.bottom != Some(TubeBottom::Ankle) && w < 4 {
            return Err(Invalid::new(
                "wales",
                format!("a stocking closed at the toe needs at least 4 wales, got {w}"),
            ));
        }
        match self.top {
            TubeTop::BelowCrotchM(d) => {
                settings::non_negative("top.below_crotch_m", d)?;
                if d >= 1.0 {
                    return Err(Invalid::new(
                        "top.below_crotch_m",
                        format!("{d} m below the crotch is off the leg; give metres under 1"),
                    ));
                }
            }
            TubeTop::Fraction(f) => {
                if !(f > 0.0 && f <= 1.0) {
                    return Err(Invalid::new(
                        "top.fraction",
                        format!("must be above 0 and at most 1, got {f}"),
                    ));
                }
            }
        }
        Ok(())
    }
}

impl PatchSettings {
    /// Checks every value; the error names the field under `patch`.
    pub fn validate(&self) -> Result<(), Invalid> {
        let GridSize { wales, courses } = self.size;
        if wales < 2 || courses < 2 {
            return Err(Invalid::new(
                "size",
                format!("needs at least 2x2 points (two held edges), got {wales}x{courses}"),
            ));
        }
        if wales
            .checked_mul(courses)
            .is_none_or(|n| n > MAX_PATCH_POINTS)
        {
            return Err(Invalid::new(
                "size",
                format!(
                    "{wales}×{courses} points is over the patch limit of {MAX_PATCH_POINTS} \
                     points"
                ),
            ));
        }
        if self.stretch.is_empty() {
            return Err(Invalid::new(
                "stretch",
                "needs at least one stretch, e.g. {\"axis\": \"course\", \"factor\": 1.5}",
            ));
        }
        for (i, s) in self.stretch.iter().enumerate() {
            let factor = s.factor;
            if !(factor.is_finite() && factor > 0.0 && factor <= MAX_STRETCH) {
                return Err(Invalid::new(
                    format!("stretch[{i}].factor"),
                    format!("must be in (0, {MAX_STRETCH}], got {factor}"),
                ));
            }
        }
        Ok(())
    }
}
