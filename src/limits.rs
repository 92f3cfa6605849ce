//! Resource limits: a fit too large for the memory it may use is refused before its leg is
//! decoded or its knit allocated, with the estimate and how to override it.
//!
//! The estimate is linear in the tube's points, the leg's triangles and the preview's pixels,
//! with per-unit costs measured as the peak resident memory (`/usr/bin/time -v`) of real fits,
//! each the slope between two sizes rounded up by about 10% (the measurements:
//! docs/decisions/0020). The parts add, which overestimates a fit writing several files. The
//! limit is the scene's `limits.memory_gib`, else what the system says is available, else
//! [`FALLBACK_LIMIT_GIB`].

use serde::{Deserialize, Serialize};

use crate::base::settings::Invalid;
use crate::base::GridSize;
use crate::error::{Error, Result};
use crate::export::Output;

/// The memory a fit may use. A fit whose estimate is over it is refused before the leg is
/// decoded or the knit allocated.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct Limits {
    /// Memory the fit may use, GiB; absent means what the system has available (`MemAvailable`
    /// in `/proc/meminfo`, or the cgroup's limit when lower), or
    /// [`FALLBACK_LIMIT_GIB`] where neither can be read (default: absent).
    /// `--memory-limit` overrides it.
    pub memory_gib: Option<f64>,
    /// Run the fit even when its estimate is over the limit: the check is skipped
    /// (default: false). `--allow-large` sets it.
    pub allow_large: bool,
}

impl Limits {
    /// Checks every value; the error names the field under `limits`.
    pub fn validate(&self) -> std::result::Result<(), Invalid> {
        match self.memory_gib {
            Some(gib) if !(gib.is_finite() && gib > 0.0) => Err(Invalid::new(
                "memory_gib",
                format!("must be a positive number of GiB, got {gib}"),
            )),
            _ => Ok(()),
        }
    }
}

const MIB: f64 = 1024.0 * 1024.0;
const GIB: f64 = 1024.0 * MIB;

/// What a fit needs whatever its size: the binary, thread stacks, the scene.
const BASE_BYTES: f64 = 24.0 * MIB;
/// Knit, solver workspaces (every multilevel level included), contact caches, the exact pass
/// and the penetration check, per tube point.
const SOLVE_BYTES_PER_POINT: f64 = 640.0;
/// The yarns and stocking surface of `stocking.glb`, with the penetration fix, per tube
/// point.
const GLB_BYTES_PER_POINT: f64 = 380.0;
/// `stocking.ply`, with the penetration fix, per tube point.
const PLY_BYTES_PER_POINT: f64 = 160.0;
/// Leg vertices and triangles, the contact BVH and the penetration check, per triangle.
const LEG_BYTES_PER_TRIANGLE: f64 = 340.0;
/// The leg's node in `stocking.glb` and its attributes, per triangle.
const LEG_GLB_BYTES_PER_TRIANGLE: f64 = 120.0;
/// `leg.ply` and the leg's attributes, per triangle.
const LEG_PLY_BYTES_PER_TRIANGLE: f64 = 130.0;
/// `density.png` and the leg's attributes, per triangle.
const LEG_PICTURE_BYTES_PER_TRIANGLE: f64 = 70.0;
/// The preview's yarn grid and the penetration fix it needs, per tube point.
const PREVIEW_BYTES_PER_POINT: f64 = 250.0;
/// The preview's picture and measurement buffers, per pixel.
const PREVIEW_BYTES_PER_PIXEL: f64 = 52.0;
/// The preview's BVH of the leg, per triangle.
const PREVIEW_BYTES_PER_TRIANGLE: f64 = 200.0;

/// Twelve samples a stitch drawn as loops, the preview's yarn grid over them or the penetration
/// fix of their files, per real stitch (peaks of 717 MB for 280,400 stitches written as loops
/// and 1.04 GB for 322,000 stitches written with a preview, less the parts above, +10%).
const LOOP_BYTES_PER_STITCH: f64 = 1800.0;

/// Memory assumed available where the system does not say (not Linux, or `/proc` unreadable),
/// GiB: a laptop's.
pub const FALLBACK_LIMIT_GIB: f64 = 8.0;

/// What a fit's memory grows with.
#[derive(Clone, Copy, Debug, PartialEq)]
struct FitSize<'a> {
    /// The tube's grid (`tube.wales` by `tube.courses`).
    pub tube: GridSize,
    /// Triangles the leg file declares.
    pub leg_triangles: usize,
    /// The outputs that write files (a fit's plan has them).
    pub outputs: &'a [Output],
    /// Pixels of the preview (`render.width × render.height`), if one is written.
    pub preview_pixels: u64,
    /// The tube's points are real stitches drawn as loops (for `loops` or the preview).
    pub loops: bool,
    /// A level with more points than the tube that the solver relaxes first, if any: an N×N
    /// stocking follows the real count's levels up to its wales (docs/decisions/0072).
    pub solved_on: Option<GridSize>,
}

/// What a fit's memory estimate reads besides its grid and its leg: the files it writes, the
/// preview's size, and the limits it is held to.
#[derive(Clone, Debug, PartialEq)]
pub struct FitMemory {
    /// The scene's `limits`.
    pub limits: Limits,
    /// The outputs that write files (a fit's plan has them).
    pub outputs: Vec<Output>,
    /// Pixels of the preview (`render.width × render.height`), if one is written.
    pub preview_pixels: u64,
}

/// Courses per wale the memory estimate takes where the scene leaves the courses out, before
/// the stocking's length is known: 1.6–2.0 on the samples' stockings to the toe.
pub const COURSES_PER_WALE_ESTIMATE: usize = 2;

impl FitMemory {
    /// The check of a fit on a `tube` grid over a leg of `leg_triangles`, relaxed first on the
    /// larger level `solved_on` where it has one; `loops` where the tube is the real stitches,
    /// drawn as loops.
    pub fn check(
        &self,
        tube: GridSize,
        leg_triangles: usize,
        solved_on: Option<GridSize>,
        loops: bool,
    ) -> MemoryCheck {
        let size = FitSize {
            tube,
            leg_triangles,
            outputs: &self.outputs,
            preview_pixels: self.preview_pixels,
            loops,
            solved_on,
        };
        MemoryCheck::fit(&size, &self.limits)
    }

    /// The check made before the leg is decoded, of `wales` by `courses` (left out: up to
    /// [`COURSES_PER_WALE_ESTIMATE`] times the wales, as on the samples' stockings to the toe;
    /// checked again once known) over the triangles the leg file declares.
    pub fn before_the_leg(
        &self,
        wales: usize,
        courses: Option<usize>,
        declared_triangles: usize,
    ) -> MemoryCheck {
        let courses = courses.unwrap_or(COURSES_PER_WALE_ESTIMATE * wales);
        self.check(
            GridSize::new(wales, courses),
            declared_triangles,
            None,
            false,
        )
    }
}

/// The peak memory a fit is estimated to need, by part, in bytes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MemoryEstimate {
    /// Tube size, wales × courses (for messages).
    #[serde(skip)]
    pub tube: GridSize,
    /// The larger level the solver relaxes first, if any (for messages).
    #[serde(skip)]
    pub solved_on: Option<GridSize>,
    /// Tube points (wales × courses).
    pub tube_points: u64,
    /// Triangles the leg file declares.
    pub leg_triangles: u64,
    /// What does not grow with the fit.
    pub base_bytes: u64,
    /// What grows with the tube: knit, solver, yarn outputs.
    pub tube_bytes: u64,
    /// What grows with the leg: mesh, collider, leg outputs.
    pub leg_bytes: u64,
    /// The preview (0 without it).
    pub preview_bytes: u64,
    /// All parts together.
    pub total_bytes: u64,
}

impl MemoryEstimate {
    /// The estimate for a fit of this size.
    fn fit(size: &FitSize) -> MemoryEstimate {
        let points = size.tube.wales as f64 * size.tube.courses as f64;
        let triangles = size.leg_triangles as f64;
        let writes = |output| size.outputs.contains(&output);
        let mut tube = SOLVE_BYTES_PER_POINT;
        let mut leg = LEG_BYTES_PER_TRIANGLE;
        if writes(Output::Glb) {
            tube += GLB_BYTES_PER_POINT;
            leg += LEG_GLB_BYTES_PER_TRIANGLE;
        }
        if writes(Output::Ply) {
            tube += PLY_BYTES_PER_POINT;
            leg += LEG_PLY_BYTES_PER_TRIANGLE;
        }
        if writes(Output::Picture) {
            leg += LEG_PICTURE_BYTES_PER_TRIANGLE;
        }
        if size.loops {
            tube += LOOP_BYTES_PER_STITCH;
        }
        let preview = if writes(Output::Preview) {
            size.preview_pixels as f64 * PREVIEW_BYTES_PER_PIXEL
                + points * PREVIEW_BYTES_PER_POINT
                + triangles * PREVIEW_BYTES_PER_TRIANGLE
        } else {
            0.0
        };
        // The solver's part on the larger level it relaxes first; the files' on the tube.
        let solved = size
            .solved_on
            .map_or(points, |g| (g.wales as f64 * g.courses as f64).max(points));
        let tube = points * tube + (solved - points) * SOLVE_BYTES_PER_POINT;
        // f64 → u64 saturates, so an absurd size reads as "more than any machine has".
        let (base_bytes, tube_bytes) = (BASE_BYTES as u64, tube as u64);
        let (leg_bytes, preview_bytes) = ((triangles * leg) as u64, preview as u64);
        MemoryEstimate {
            tube: size.tube,
            solved_on: size.solved_on,
            tube_points: points as u64,
            leg_triangles: size.leg_triangles as u64,
            base_bytes,
            tube_bytes,
            leg_bytes,
            preview_bytes,
            total_bytes: base_bytes
                .saturating_add(tube_bytes)
                .saturating_add(leg_bytes)
                .saturating_add(preview_bytes),
        }
    }
}

/// Where the memory limit came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LimitSource {
    /// The scene's `limits.memory_gib` (or `--memory-limit`).
    Scene,
    /// `MemAvailable` in `/proc/meminfo`.
    MemAvailable,
    /// The process's cgroup memory limit less what the cgroup uses, when below `MemAvailable`
    /// (a container sees the host's `/proc/meminfo`).
    Cgroup,
    /// [`FALLBACK_LIMIT_GIB`]: the system did not say.
    Fallback,
}

impl LimitSource {
    /// How the source is named in messages.
    pub fn describe(self) -> &'static str {
        match self {
            LimitSource::Scene => "limits.memory_gib",
            LimitSource::MemAvailable => "MemAvailable in /proc/meminfo",
            LimitSource::Cgroup => "the cgroup's memory limit",
            LimitSource::Fallback => "fallback: the system does not say",
        }
    }
}

/// The memory a run may use.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MemoryLimit {
    /// Bytes.
    pub bytes: u64,
    /// Where the figure came from.
    pub source: LimitSource,
}

impl MemoryLimit {
    /// The scene's limit, else the system's available memory, else the fallback.
    pub fn of(limits: &Limits) -> MemoryLimit {
        if let Some(gib) = limits.memory_gib {
            return MemoryLimit {
                bytes: (gib * GIB) as u64,
                source: LimitSource::Scene,
            };
        }
        let meminfo = std::fs::read_to_string("/proc/meminfo")
            .ok()
            .and_then(|text| mem_available(&text));
        let cgroup = cgroup_available();
        match (meminfo, cgroup) {
            (Some(m), Some(c)) if c < m => MemoryLimit {
                bytes: c,
                source: LimitSource::Cgroup,
            },
            (Some(m), _) => MemoryLimit {
                bytes: m,
                source: LimitSource::MemAvailable,
            },
            (None, Some(c)) => MemoryLimit {
                bytes: c,
                source: LimitSource::Cgroup,
            },
            (None, None) => MemoryLimit {
                bytes: (FALLBACK_LIMIT_GIB * GIB) as u64,
                source: LimitSource::Fallback,
            },
        }
    }
}

/// `MemAvailable` of a `/proc/meminfo` text, bytes.
fn mem_available(meminfo: &str) -> Option<u64> {
    let line = meminfo.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib.saturating_mul(1024))
}

/// The cgroup's memory limit less its usage, bytes (cgroup v2, then v1); `None` without a
/// limit. An unlimited v1 cgroup reports a limit near 2^63, which is never below `MemAvailable`.
fn cgroup_available() -> Option<u64> {
    let read =
        |path: &str| -> Option<u64> { std::fs::read_to_string(path).ok()?.trim().parse().ok() };
    let (limit, usage) = match read("/sys/fs/cgroup/memory.max") {
        Some(limit) => (limit, read("/sys/fs/cgroup/memory.current")?),
        None => (
            read("/sys/fs/cgroup/memory/memory.limit_in_bytes")?,
            read("/sys/fs/cgroup/memory/memory.usage_in_bytes")?,
        ),
    };
    Some(limit.saturating_sub(usage))
}

/// A fit's estimate against its limit: the `memory` of the plan and of `report.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MemoryCheck {
    /// What the fit is estimated to need.
    pub estimate: MemoryEstimate,
    /// What it may use.
    pub limit: MemoryLimit,
    /// `limits.allow_large`: run even when over the limit.
    pub allow_large: bool,
}

impl MemoryCheck {
    /// The check of a fit of this size against `limits`.
    fn fit(size: &FitSize, limits: &Limits) -> MemoryCheck {
        MemoryCheck {
            estimate: MemoryEstimate::fit(size),
            limit: MemoryLimit::of(limits),
            allow_large: limits.allow_large,
        }
    }

    /// True when the estimate is within the limit.
    pub fn fits(&self) -> bool {
        self.estimate.total_bytes <= self.limit.bytes
    }

    /// One line: the estimate, the limit, and what a run does with them.
    pub fn summary(&self) -> String {
        let verdict = if self.fits() {
            "fits"
        } else if self.allow_large {
            "over the limit, run anyway (allow_large)"
        } else {
            "over the limit: the run would be refused"
        };
        format!(
            "about {} (tube {}, leg {}, preview {}, base {}), {} available ({}): {verdict}",
            human_bytes(self.estimate.total_bytes),
            human_bytes(self.estimate.tube_bytes),
            human_bytes(self.estimate.leg_bytes),
            human_bytes(self.estimate.preview_bytes),
            human_bytes(self.estimate.base_bytes),
            human_bytes(self.limit.bytes),
            self.limit.source.describe(),
        )
    }

    /// Refuses a fit over its limit, unless `allow_large`: [`Error::TooLarge`] naming the tube
    /// and the leg (`leg_name`) and saying how to go on.
    pub fn enforce(&self, leg_name: &str) -> Result<()> {
        if self.allow_large || self.fits() {
            return Ok(());
        }
        let e = &self.estimate;
        let how_to_override = if e.leg_bytes > e.tube_bytes {
            "use a leg with fewer triangles"
        } else {
            "lower --resolution (tube.wales, tube.courses)"
        };
        let first = e.solved_on.map_or(String::new(), |level| {
            format!(", relaxed first on the real stitch count's {level} level,")
        });
        Err(self.too_large(
            format!(
                "a fit of {} points{first} on {leg_name} ({} triangles)",
                e.tube, e.leg_triangles
            ),
            how_to_override,
        ))
    }

    /// [`MemoryCheck::enforce`] for the real stitches a fit lays once its stocking's length is
    /// known (`outputs` `stitches` or `loops`): the estimate's tube is the real stitch count.
    pub fn enforce_real_stitches(&self, leg_name: &str) -> Result<()> {
        if self.allow_large || self.fits() {
            return Ok(());
        }
        let e = &self.estimate;
        Err(self.too_large(
            format!(
                "the real stitches of this stocking, {}, on {leg_name}",
                e.tube
            ),
            "ask for fewer knit.needles or a larger stitch (knit.wale_spacing_m), or leave \
             \"stitches\", \"loops\" and \"preview\" out of outputs",
        ))
    }

    fn too_large(&self, what: String, how_to_override: &str) -> Error {
        Error::TooLarge {
            what,
            estimate: human_bytes(self.estimate.total_bytes),
            available: human_bytes(self.limit.bytes),
            limit_source: self.limit.source.describe().into(),
            how_to_override: format!(
                "{how_to_override}, or pass --allow-large (limits.allow_large) to run anyway"
            ),
        }
    }
}

/// Bytes as GiB (one decimal) from 1 GiB up, else MiB.
pub fn human_bytes(bytes: u64) -> String {
    let b = bytes as f64;
    if b >= GIB {
        format!("{:.1} GiB", b / GIB)
    } else {
        format!("{:.0} MiB", b / MIB)
    }
}

/// Starts a new peak-memory measurement (Linux: resets the process's peak resident set).
pub fn reset_peak_memory() {
    // Writing 5 to clear_refs resets VmHWM to the current resident set (Linux ≥ 4.0). Where it
    // fails, the peak is the process's since it began, which is still an upper bound.
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

/// Peak resident memory since the process began or the last [`reset_peak_memory`], bytes
/// (Linux `VmHWM`).
pub fn peak_memory() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn size(outputs: &[Output]) -> FitSize<'_> {
        FitSize {
            tube: GridSize::new(150, 150),
            leg_triangles: 10_000,
            outputs,
            preview_pixels: 768 * 768,
            loops: false,
            solved_on: None,
        }
    }

    #[test]
    fn the_estimate_grows_with_the_tube_the_leg_and_the_outputs() {
        let small = MemoryEstimate::fit(&size(&[]));
        let larger_tube = MemoryEstimate::fit(&FitSize {
            tube: GridSize::new(300, 150),
            ..size(&[])
        });
        assert_eq!(larger_tube.tube_bytes, 2 * small.tube_bytes);
        let larger_leg = MemoryEstimate::fit(&FitSize {
            leg_triangles: 20_000,
            ..size(&[])
        });
        assert_eq!(larger_leg.leg_bytes, 2 * small.leg_bytes);
        assert!(MemoryEstimate::fit(&size(&[Output::Ply])).tube_bytes > small.tube_bytes);
        let drawn_as_loops = FitSize {
            loops: true,
            ..size(&[])
        };
        assert!(MemoryEstimate::fit(&drawn_as_loops).tube_bytes > small.tube_bytes);
        assert_eq!(small.preview_bytes, 0);
        assert!(MemoryEstimate::fit(&size(&[Output::Preview])).preview_bytes > 0);
        // A larger level relaxed first adds its solver's part only: the files are the tube's.
        let through = |solved_on| {
            MemoryEstimate::fit(&FitSize {
                solved_on,
                ..size(&[Output::Ply])
            })
            .tube_bytes
        };
        let plain = through(None);
        let extra = (150.0 * 150.0 * SOLVE_BYTES_PER_POINT) as u64;
        assert_eq!(through(Some(GridSize::new(150, 300))), plain + extra);
        assert_eq!(
            through(Some(GridSize::new(100, 100))),
            plain,
            "a smaller level costs nothing more"
        );
    }

    #[test]
    fn an_absurd_tube_saturates_instead_of_overflowing() {
        let e = MemoryEstimate::fit(&FitSize {
            tube: GridSize::new(usize::MAX / 2, usize::MAX / 2),
            leg_triangles: usize::MAX,
            ..size(&[Output::Ply])
        });
        assert_eq!(e.total_bytes, u64::MAX);
    }

    #[test]
    fn the_scene_limit_wins_and_allow_large_skips_the_refusal() {
        let mut limits = Limits {
            memory_gib: Some(0.001),
            allow_large: false,
        };
        let fit = FitSize {
            leg_triangles: 41_000,
            ..size(&[])
        };
        let check = MemoryCheck::fit(&fit, &limits);
        assert_eq!(check.limit.source, LimitSource::Scene);
        assert!(!check.fits());
        let err = check.enforce("leg.glb").unwrap_err().to_string();
        assert!(err.contains("--allow-large"), "{err}");
        assert!(err.contains("1 MiB available"), "{err}");
        limits.allow_large = true;
        assert!(MemoryCheck::fit(&fit, &limits).enforce("leg.glb").is_ok());
    }

    #[test]
    fn mem_available_is_read_in_kib() {
        let text = "MemTotal:       24683584 kB\nMemAvailable:   23680008 kB\n";
        assert_eq!(mem_available(text), Some(23_680_008 * 1024));
        assert_eq!(mem_available("MemTotal: 1 kB\n"), None);
    }
}
