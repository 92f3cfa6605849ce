//! The preview's settings (the scene's `render`): picture size, samples, view or camera, what
//! the pixels show, and the lights and colours of the shading. Colours are linear RGB, 0–1.

use serde::{Deserialize, Serialize};

use crate::base::settings::{self, Invalid};

/// Which side the auto-framed camera looks at the leg from. glTF's character faces +Z with +Y
/// up (as in `density.png`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum View {
    /// From +Z towards −Z (default).
    #[default]
    Front,
    /// From +X towards −X (the outer side of a left leg).
    Side,
    /// From −Z towards +Z.
    Back,
    /// From +X+Z, halfway between front and side.
    #[serde(rename = "three-quarter", alias = "three_quarter")]
    ThreeQuarter,
}

impl View {
    /// Every view, in the order the command line lists them.
    pub const ALL: [View; 4] = [View::Front, View::Side, View::Back, View::ThreeQuarter];

    /// Name as in scene files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            View::Front => "front",
            View::Side => "side",
            View::Back => "back",
            View::ThreeQuarter => "three-quarter",
        }
    }
}

/// What a preview pixel shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum RenderMode {
    /// The yarns as cylinders over the skin, shaded (paper §7–8, Fig. 17) (default).
    #[default]
    Yarn,
    /// The leg coloured by stitch density, with a colour bar (paper Fig. 18).
    Density,
}

impl RenderMode {
    /// Name as in scene files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            RenderMode::Yarn => "yarn",
            RenderMode::Density => "density",
        }
    }
}

/// A camera given by the scene instead of the auto-framed one.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraSettings {
    /// Eye position, metres, world space (the leg's frame after units and up axis: +Y up).
    pub position: [f64; 3],
    /// The point looked at, metres, world space.
    pub target: [f64; 3],
    /// Vertical field of view, degrees (default: 25).
    #[serde(default = "default_fov_deg")]
    pub fov_deg: f64,
}

fn default_fov_deg() -> f64 {
    25.0
}

/// The yarn-level preview (`preview.png`, `knitfit render`). Colours are linear RGB, 0–1.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PreviewSettings {
    /// Image width, pixels (default: 768; 16 to 8192).
    pub width: u32,
    /// Image height, pixels (default: 768; 16 to 8192).
    pub height: u32,
    /// Side the auto-framed camera looks from (default: `"front"`); ignored with `camera`.
    pub view: View,
    /// Samples per pixel, stratified on a grid of ⌈√spp⌉ columns and as many rows as needed,
    /// so a non-square count is rounded up to fill the grid (default: 16; 1 to 1024).
    pub spp: u32,
    /// What the pixels show (default: `"yarn"`).
    pub mode: RenderMode,
    /// A fixed camera; absent means auto-framed on the leg from `view` (default: absent).
    pub camera: Option<CameraSettings>,
    /// Skin albedo (default: `[0.52, 0.31, 0.22]`, a warm light skin tone).
    pub skin_colour: [f64; 3],
    /// Background (default: `[0.78, 0.78, 0.80]`, a light grey).
    pub background: [f64; 3],
    /// Direction towards the key light in the camera's frame (right, up, towards the viewer),
    /// any length (default: `[-0.45, 0.55, 0.70]`: from the upper left, in front).
    pub light_direction: [f64; 3],
    /// Radiance of the key light (default: 1.1).
    pub light_intensity: f64,
    /// Ambient (environment) light, as a fraction of the key light (default: 0.35).
    pub ambient: f64,
    /// Strength of the yarn's anisotropic highlight (Kajiya–Kay), 0 = none (default: 0.5).
    pub yarn_sheen: f64,
    /// Exponent of the highlight: higher is narrower (default: 48).
    pub yarn_sheen_exponent: f64,
}

impl Default for PreviewSettings {
    fn default() -> Self {
        PreviewSettings {
            width: 768,
            height: 768,
            view: View::Front,
            spp: 16,
            mode: RenderMode::Yarn,
            camera: None,
            skin_colour: [0.52, 0.31, 0.22],
            background: [0.78, 0.78, 0.80],
            light_direction: [-0.45, 0.55, 0.70],
            light_intensity: 1.1,
            ambient: 0.35,
            yarn_sheen: 0.5,
            yarn_sheen_exponent: 48.0,
        }
    }
}

/// Smallest and largest image side accepted, pixels.
pub const RENDER_SIDE_PX: (u32, u32) = (16, 8192);
/// Largest samples per pixel accepted.
pub const MAX_SPP: u32 = 1024;
/// Most pixels and most samples one preview may take: beyond them a render needs gigabytes
/// of buffers or hours.
pub const MAX_RENDER_PIXELS: u64 = 4096 * 4096;
/// See [`MAX_RENDER_PIXELS`].
pub const MAX_RENDER_SAMPLES: u64 = 1 << 31;

impl PreviewSettings {
    /// Checks every value; the error names the field under `render`.
    pub fn validate(&self) -> Result<(), Invalid> {
        let (lo, hi) = RENDER_SIDE_PX;
        for (field, px) in [("width", self.width), ("height", self.height)] {
            if !(lo..=hi).contains(&px) {
                return Err(Invalid::new(
                    field,
                    format!("must be {lo} to {hi} pixels, got {px}"),
                ));
            }
        }
        if !(1..=MAX_SPP).contains(&self.spp) {
            return Err(Invalid::new(
                "spp",
                format!("must be 1 to {MAX_SPP} samples per pixel, got {}", self.spp),
            ));
        }
        self.check_budget(self.spp)?;
        settings::colour("skin_colour", self.skin_colour)?;
        settings::colour("background", self.background)?;
        let l = self.light_direction;
        if !l.iter().all(|c| c.is_finite()) || l.iter().all(|&c| c == 0.0) {
            return Err(Invalid::new(
                "light_direction",
                format!("must be a finite, non-zero vector, got {l:?}"),
            ));
        }
        settings::non_negative("light_intensity", self.light_intensity)?;
        settings::non_negative("ambient", self.ambient)?;
        settings::non_negative("yarn_sheen", self.yarn_sheen)?;
        let e = self.yarn_sheen_exponent;
        if !(e.is_finite() && e >= 1.0) {
            return Err(Invalid::new(
                "yarn_sheen_exponent",
                format!("must be at least 1, got {e}"),
            ));
        }
        if let Some(camera) = &self.camera {
            let finite = camera
                .position
                .iter()
                .chain(&camera.target)
                .all(|c| c.is_finite());
            if !finite || camera.position == camera.target {
                return Err(Invalid::new(
                    "camera",
                    "position and target must be finite and different points",
                ));
            }
            let fov = camera.fov_deg;
            if !(fov.is_finite() && fov > 0.5 && fov < 170.0) {
                return Err(Invalid::new(
                    "camera.fov_deg",
                    format!("must be between 0.5 and 170 degrees, got {fov}"),
                ));
            }
        }
        Ok(())
    }

    /// Checks that this picture at `spp` samples per pixel stays within [`MAX_RENDER_PIXELS`]
    /// and [`MAX_RENDER_SAMPLES`]; the error names `spp` (or `width` for the pixels alone) and
    /// blames the other sizes too.
    pub fn check_budget(&self, spp: u32) -> Result<(), Invalid> {
        let (width, height) = (self.width, self.height);
        let pixels = u64::from(width) * u64::from(height);
        let samples = pixels * u64::from(spp);
        if pixels > MAX_RENDER_PIXELS {
            Err(Invalid::new(
                "width",
                format!(
                    "{width}×{height} is over the limit of {MAX_RENDER_PIXELS} pixels (4096×4096)"
                ),
            )
            .with(&["height"]))
        } else if samples > MAX_RENDER_SAMPLES {
            Err(Invalid::new(
                "spp",
                format!(
                    "{width}×{height} at {spp} spp is {samples} samples, over the limit of \
                     {MAX_RENDER_SAMPLES}; lower the size or the samples per pixel"
                ),
            )
            .with(&["width", "height"]))
        } else {
            Ok(())
        }
    }
}
