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
    /// The yarns in `stocking.ply` and `stocking.glb` are every real stitch's crossing points
    /// (`knit.needles` around, one course per `knit.wale_spacing_m` of relaxed length), laid on
    /// the skin by interpolating the fitted grid, instead of the grid's own points.
    Stitches,
    /// The yarns in `stocking.ply` and `stocking.glb` are every real stitch as a knitted loop
    /// sampled as a polyline (Choi & Lo's loop, `post::loops`).
    Loops,
}

pub(crate) fn default_outputs() -> Vec<Output> {
    vec![Output::Ply, Output::Glb, Output::Picture]
}

/// Which yarns the yarn files hold: the simulation grid's, or the real stitches'.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum YarnsWritten {
    /// The fitted grid's points and springs (a grid point stands for a block of stitches).
    Grid,
    /// Every real stitch's crossing point, joined along courses and wales.
    Stitches,
    /// Every real stitch as a loop polyline.
    Loops,
}

impl Output {
    /// Name as written in scene files.
    pub fn name(self) -> &'static str {
        match self {
            Output::Ply => "ply",
            Output::Glb => "glb",
            Output::Picture => "picture",
            Output::Preview => "preview",
            Output::Stitches => "stitches",
            Output::Loops => "loops",
        }
    }
}
