//! What a fit hands to artists' tools: the yarns (the grid's, or every real stitch as a
//! crossing or a knitted loop), mended where they cut through the skin (paper §6.3), the leg
//! and the stocking as surfaces with their attributes; then each file's bytes and the preview.
//! Stages [`Stage::LayStitches`] to [`Stage::StockingSurface`], [`Stage::Encode`] of each file
//! and [`Stage::RenderPreview`].

use crate::base::{Material, PerYarn, Stance, SurfaceMesh, YarnGeometry, YarnKind};
use crate::draw;
use crate::draw::density_map::{self, DensityPictureStyle};
use crate::error::{Error, Result};
use crate::export;
use crate::export::gltf::GlbNode;
use crate::export::YarnsWritten;
use crate::knit::tube::{build_stocking, build_tube, CourseSpacing, TubeSpec};
use crate::knit::{Fabric, Knit, Yarns};
use crate::leg::landmarks::stance_of;
use crate::post::fields;
use crate::post::lattice::{lay_on_skin, lay_stitches, LaidStitches};
use crate::post::loops::loops;
use crate::post::penetration::{fix_penetrations, PenetrationStats};
use crate::post::stitches::slack;
use crate::post::surfaces::{leg_surface, lift_clear_of, stocking_surface};
use crate::preview::{encode_preview, PreviewInput, PreviewSettings, PreviewStats};
use crate::sim::ForceTerms;
use crate::stage::{timed, FitFile, Stage, StageTimes};

use super::size::RealStitches;
use super::{Fields, SolvedFit};

/// Which products a fit makes, as its plan says: the yarns its files hold, the real stitches
/// (for those files or the preview), the penetration fix, the stocking surface and the pictures'
/// view.
#[derive(Clone, Debug, PartialEq)]
pub struct ProductSettings {
    /// Which yarns `stocking.ply` and `stocking.glb` hold.
    pub yarns_written: YarnsWritten,
    /// The real stitches laid, and whether as loops ([`Stage::LayStitches`],
    /// [`Stage::KnitLoops`]).
    pub real_stitches: RealStitches,
    /// Reroute yarn segments that cut through the skin ([`Stage::PenetrationFix`]).
    pub penetration_fix: bool,
    /// The knit as a sheer surface for `stocking.glb` ([`Stage::StockingSurface`]).
    pub stocking_surface: bool,
    /// A picture is drawn from the character's front (the density picture, or a preview
    /// without the scene's camera): the stance is found for it.
    pub pictured: bool,
    /// Each yarn kind's linear-RGB colour, for `stocking.glb`.
    pub colours: PerYarn<[f64; 3]>,
}

/// A fit's products: what its files are encoded from and its preview drawn from.
pub struct Products {
    /// The yarns the files hold, mended where the fix ran.
    pub yarns: YarnGeometry,
    /// The real loops, where they were made for the preview only (drawn unmended: a loop
    /// dipping a few micrometres into the skin is hidden where it dips).
    preview_loops: Option<YarnGeometry>,
    /// How the real stitches were laid, where they were.
    pub laid: Option<LaidStitches>,
    /// What the penetration fix did, where it ran.
    pub penetration_fix: Option<PenetrationStats>,
    /// The stocking surface, lifted clear of the skin, and how many of its triangles still dip
    /// into it.
    pub stocking: Option<(SurfaceMesh, usize)>,
    /// The leg with its attributes.
    pub leg_mesh: SurfaceMesh,
    /// The leg's look in `stocking.glb`: its file's material, or skin.
    pub leg_material: Material,
    /// How the character stands: what the pictures are seen from.
    pub stance: Stance,
    /// Each yarn kind's colour.
    colours: PerYarn<[f64; 3]>,
}

/// Makes the products `settings` asks for from `fit` and its leg `fields`, knitted as `fabric`
/// with the stiffness of `terms`; each stage timed in `times`.
pub fn products(
    fit: &SolvedFit,
    fields: &Fields,
    fabric: &Fabric,
    terms: &ForceTerms,
    settings: &ProductSettings,
    times: &mut dyn StageTimes,
) -> Products {
    // The real stitches, for the yarn files (`stitches`, `loops`) or the preview, which draws
    // every stitch as a loop so that its sheerness comes out of the knit's structure.
    let real = (settings.real_stitches != RealStitches::None)
        .then(|| timed(times, Stage::LayStitches, || real_stitches(fit)));
    let real_loops = match (&real, settings.real_stitches) {
        (Some((real, _)), RealStitches::Loops) => {
            Some(timed(times, Stage::KnitLoops, || loops(real, fabric)))
        }
        _ => None,
    };
    // The yarns the files hold: the grid's, or the real stitches' (as crossings, or as loops
    // laid on the skin: a loop bulges past its stitch's corners). Loops made only for the
    // preview are drawn as they are.
    let (mut yarns, preview_loops) = match (settings.yarns_written, &real, real_loops) {
        (YarnsWritten::Stitches, Some((real, _)), loops) => {
            (knit_yarns(real, fabric, terms), loops)
        }
        (YarnsWritten::Loops, _, Some(mut loops)) => {
            lay_on_skin(&mut loops.positions, &fit.collider, fit.offset);
            (loops, None)
        }
        (_, _, loops) => (knit_yarns(&fit.knit, fabric, terms), loops),
    };
    let penetration_fix = settings.penetration_fix.then(|| {
        let (fixed, stats) = timed(times, Stage::PenetrationFix, || {
            fix_penetrations(&yarns, &fit.collider, fit.offset)
        });
        yarns = fixed;
        stats
    });
    let stocking = settings.stocking_surface.then(|| {
        timed(times, Stage::StockingSurface, || {
            // The fitted grid's surface: it reads the grid's yarn attributes.
            let grid_yarns = match settings.yarns_written {
                YarnsWritten::Grid => None,
                _ => Some(knit_yarns(&fit.knit, fabric, terms)),
            };
            let grid = grid_yarns.as_ref().unwrap_or(&yarns);
            let mut surface = stocking_surface(&fit.knit, &fields.on_knit, grid);
            let dipping = lift_clear_of(&mut surface, &fit.collider);
            (surface, dipping)
        })
    });
    // The pictures are seen from the character's front: its stance, where one is drawn from it
    // (a leg placed by a given axis has no landmarks yet; they are found for this).
    let stance = match (&fit.placement.landmarks, settings.pictured) {
        (_, false) => Stance::default(),
        (Some(landmarks), true) => landmarks.stance(),
        (None, true) => stance_of(&fit.leg.positions, &fit.leg.triangles),
    };
    Products {
        yarns,
        preview_loops,
        laid: real.map(|(_, laid)| laid),
        penetration_fix,
        stocking,
        leg_mesh: leg_surface(&fit.leg, &fields.on_leg),
        leg_material: fit.leg.material.clone().unwrap_or_else(Material::skin),
        stance,
        colours: settings.colours,
    }
}

/// A knit's points and springs as yarns, with each point's `tension` (N/m around) and `slack`.
fn knit_yarns(knit: &Knit, fabric: &Fabric, forces: &ForceTerms) -> YarnGeometry {
    let stretch = fields::stretch(knit);
    let tension = fields::tension(knit, fabric, forces, &stretch).course;
    let mut yarns = knit.yarn_geometry("yarns", [0.0; 3]);
    let as_f32 = |v: &[f64]| v.iter().map(|&x| x as f32).collect();
    yarns
        .point_attributes
        .insert("tension".into(), as_f32(&tension));
    yarns
        .point_attributes
        .insert("slack".into(), as_f32(&slack(knit)));
    yarns
}

/// The knit at the real stitch count, built like the fitted grid (path, toe seam, heel pocket)
/// and laid in it on the skin ([`lay_stitches`]).
fn real_stitches(fit: &SolvedFit) -> (Knit, LaidStitches) {
    let placement = &fit.placement;
    let spec = TubeSpec {
        grid: fit.real_count,
        ..fit.spec
    };
    let mut real = match &placement.path {
        Some(path) => build_stocking(&spec, path, fit.heel, CourseSpacing::Even),
        None => build_tube(
            &spec,
            &placement.axis,
            &fit.leg.positions,
            &fit.leg.triangles,
        ),
    };
    let laid = lay_stitches(
        &fit.knit,
        &mut real,
        &fit.collider,
        fit.offset,
        fit.lock_axis,
    );
    (real, laid)
}

impl Products {
    /// The yarn-level preview still (paper §7–8) of these products, with `yarns`' radii and
    /// colours and `settings`, encoded as the PNG `name` (stage [`Stage::RenderPreview`]): the
    /// real loops where they were made, else the yarns the files hold (a density preview draws
    /// none).
    pub fn render_preview(
        &self,
        yarns: &Yarns,
        settings: &PreviewSettings,
        name: &str,
    ) -> Result<(Vec<u8>, PreviewStats)> {
        let drawn = self.preview_loops.as_ref().unwrap_or(&self.yarns);
        let input = PreviewInput::new(&self.leg_mesh, drawn, yarns, self.stance);
        encode_preview(input, settings, name)
    }

    /// Encodes `file`.
    pub fn encode(&self, file: FitFile) -> Result<Vec<u8>> {
        let comments = || vec![format!("knitfit {} fit", env!("CARGO_PKG_VERSION"))];
        match file {
            FitFile::StockingGlb => {
                let Some((stocking, _)) = &self.stocking else {
                    // The plan builds it wherever it encodes stocking.glb.
                    return Err(Error::Encode {
                        what: "glTF".into(),
                        message: "stocking.glb has no stocking surface to hold".into(),
                    });
                };
                // The yarn lines in a scene of their own: drawn in the default one they would
                // sit on top of the sheer stocking (docs/decisions/0056).
                export::gltf::write_scenes_glb(
                    &[
                        (
                            "knitfit",
                            &[
                                GlbNode::Opaque {
                                    mesh: &self.leg_mesh,
                                    material: &self.leg_material,
                                },
                                // Sheer in the nylon's colour: its coverage is the vertex
                                // colours' alpha (docs/decisions/0052).
                                GlbNode::Sheer {
                                    mesh: stocking,
                                    colour: self.colours[YarnKind::Nylon.index() as usize],
                                },
                            ],
                        ),
                        // Named apart from its node: three.js renames a node that shares a name.
                        ("knitfit yarns", &[GlbNode::Yarns(&self.yarns)]),
                    ],
                    self.colours,
                )
            }
            FitFile::StockingPly => {
                export::ply::write_ply(std::slice::from_ref(&self.yarns), &comments())
            }
            FitFile::LegPly => export::ply::write_mesh_ply(&self.leg_mesh, &comments()),
            FitFile::DensityPicture => {
                let density: Vec<f64> = self
                    .leg_mesh
                    .point_attributes
                    .get("stitch_density")
                    .map(|d| d.iter().map(|&v| f64::from(v)).collect())
                    .unwrap_or_default();
                let picture = density_map::draw_density(
                    &self.leg_mesh.positions,
                    &self.leg_mesh.triangles,
                    &density,
                    &self.stance,
                    &DensityPictureStyle::default(),
                );
                draw::encode_png(&picture, file.name())
            }
        }
    }
}
