//! The solvers' settings (the scene's `solver` and `contact`): which solver, its step, damping,
//! tolerance and step limit, and the contact's offset from the skin. Times are in the paper's
//! solver units, lengths in metres.

use serde::{Deserialize, Serialize};

use crate::base::settings::{self, Invalid};
use crate::knit::settings::Yarns;
use crate::leg::ContactMethod;

/// What the solver does when the time step is above the explicit stability limit.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum OnUnstable {
    /// Split each step into equal sub-steps below the limit (default).
    #[default]
    Substep,
    /// Stop with an error naming the limit.
    Error,
    /// Run at the given step anyway; the divergence watchdog stops the run if it blows up. For
    /// experiments that show why the limit matters.
    Ignore,
}

/// Which solver relaxes a fit.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum SolverMethod {
    /// Coarse-to-fine grids with an accelerated (momentum with restart) iteration on each
    /// (`sim::multilevel`; default). The same rest state as `paper`, in a small fraction of the
    /// time; `time_step`, `damping` and `on_unstable` do not apply to it.
    #[default]
    Multilevel,
    /// The paper's explicit damped steps (§5) on the full grid: the reference.
    Paper,
}

impl SolverMethod {
    /// Name as in scene files.
    pub fn name(self) -> &'static str {
        match self {
            SolverMethod::Multilevel => "multilevel",
            SolverMethod::Paper => "paper",
        }
    }
}

/// Relaxation solver settings. `knitfit patch` always runs the paper's explicit solver, since it
/// reproduces the paper's experiment; `knitfit fit` runs `method`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SolverSettings {
    /// Which solver relaxes a fit (default: `"multilevel"`).
    pub method: SolverMethod,
    /// Time step t, in solver time units (default: 0.1, the paper's value).
    pub time_step: f64,
    /// Velocity damper: velocities decay as `exp(-damping · t)` each step; per solver time unit
    /// (default: 1.0, close to the fastest settling of the paper's 10×10 patch,
    /// docs/decisions/0003).
    pub damping: f64,
    /// Convergence tolerance, dimensionless (default: 0.001). A run has converged when the
    /// relative residual (RMS net force on free points over RMS spring force) is below it, and
    /// so is the largest move per step (`paper`) or the largest move the unbalanced force alone
    /// would make in one iteration (`multilevel`), each over the shortest rest length.
    pub tolerance: f64,
    /// Step limit (for `multilevel`, iterations per grid level); a run that reaches it is
    /// reported as not converged (default: 100000).
    pub max_steps: usize,
    /// What to do when `time_step` is above the explicit stability limit (default: `"substep"`).
    pub on_unstable: OnUnstable,
}

impl Default for SolverSettings {
    fn default() -> Self {
        SolverSettings {
            method: SolverMethod::Multilevel,
            time_step: 0.1,
            damping: 1.0,
            tolerance: 1e-3,
            max_steps: 100_000,
            on_unstable: OnUnstable::Substep,
        }
    }
}

/// Contact between yarn and leg (paper §6.2). How its queries are answered
/// ([`ContactMethod`]) belongs to the leg's collider, which `leg` owns.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ContactSettings {
    /// How contact is found (default: `"bvh"`).
    pub method: ContactMethod,
    /// Distance kept between yarn centre line and skin, metres; absent means the nylon yarn
    /// radius (default: absent).
    pub offset_m: Option<f64>,
}

impl Default for ContactSettings {
    fn default() -> Self {
        ContactSettings {
            method: ContactMethod::Bvh,
            offset_m: None,
        }
    }
}

impl SolverSettings {
    /// Checks every value; the error names the field under `solver`.
    pub fn validate(&self) -> Result<(), Invalid> {
        settings::positive("time_step", self.time_step)?;
        settings::non_negative("damping", self.damping)?;
        let tolerance = self.tolerance;
        if !(tolerance.is_finite() && tolerance > 0.0 && tolerance < 1.0) {
            return Err(Invalid::new(
                "tolerance",
                format!("must be in (0, 1), got {tolerance}"),
            ));
        }
        if self.max_steps == 0 {
            return Err(Invalid::new("max_steps", "must be at least 1"));
        }
        Ok(())
    }
}

/// Largest contact offset accepted, metres: a yarn's centre line a centimetre off the skin is
/// no longer on it (the default is the nylon's radius, 25 µm).
pub const MAX_OFFSET_M: f64 = 0.01;

impl ContactSettings {
    /// The contact offset in metres.
    pub fn offset(&self, yarns: &Yarns) -> f64 {
        self.offset_m.unwrap_or(yarns.nylon.radius_m())
    }

    /// Checks every value; the error names the field under `contact`.
    pub fn validate(&self) -> Result<(), Invalid> {
        match self.offset_m {
            Some(offset) => settings::within("offset_m", offset, 0.0, MAX_OFFSET_M),
            None => Ok(()),
        }
    }
}
