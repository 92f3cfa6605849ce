//! Writers for the files a run produces (and the reader of a fit's own `stocking.glb`). One
//! [`YarnGeometry`](crate::base::YarnGeometry) feeds every format, so PLY and glTF carry the
//! same points, segments and attributes.
//!
//! Every writer returns bytes; [`atomic::write_all`] puts them on disk (temporary name, then
//! rename), so a failed run leaves nothing half-written.

pub mod atomic;
pub mod gltf;
pub mod ply;

use serde::{Deserialize, Serialize};

/// A file a run can write (besides `report.json`, which every run writes).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Output {
    /// PLY: yarn points with an edge element (`patch.ply`; `stocking.ply` and `leg.ply` for a
    /// fit).
    Ply,
    /// Binary glTF (`patch.glb`; `stocking.glb` for a fit).
    Glb,
    /// PNG picture: the relaxed stitches (`patch.png`), or for a fit the leg coloured by
    /// stitch density, front and side, with a colour bar (`density.png`).
    Picture,
    /// PNG: the ray-traced yarn-level still of the fitted stocking on the leg (`preview.png`,
    /// `knitfit fit` only; settings in `render`).
    Preview,
}

pub(crate) fn default_outputs() -> Vec<Output> {
    vec![Output::Ply, Output::Glb, Output::Picture]
}

impl Output {
    /// Name as written in scene files.
    pub fn name(self) -> &'static str {
        match self {
            Output::Ply => "ply",
            Output::Glb => "glb",
            Output::Picture => "picture",
            Output::Preview => "preview",
        }
    }
}
