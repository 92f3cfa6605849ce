//! The yarn-level preview (`preview.png`, `knitfit render`): a ray-traced still of the fitted
//! stocking on the leg, after Sakaguchi & Miyata §7–8 (Fig. 17), or the leg coloured by stitch
//! density (Fig. 18).
//!
//! Per sample: the camera ray is cast against the leg's triangles; at the skin hit the ray's
//! last stretch through the yarn layer — the skin's normal height `layer_m` divided by the
//! cosine of the view angle, at most three layers — is tested against the yarn capsules
//! nearby; the nearest yarn before the skin is shaded with its cylinder normal and tangent, else
//! the skin shows (see `yarn_lookup.rs` for why the ray, not only the normal, decides). A ray
//! that misses the skin sees the background: yarn hovering beyond the outline is a few
//! hundredths of a millimetre wide, far below a pixel.
//!
//! Every camera ray leaves the eye, so both lookups go through screen bins (`screen_bins.rs`,
//! decision 0054): per pixel, the triangles and capsules whose projection may cover it, nearest
//! first. A pixel no triangle covers is background without a ray. Each candidate is tested
//! exactly as the whole-scene structures would test it (parry's triangle test, the same
//! ray–capsule quadratic from the same start), so the picture is the one the leg's BVH and one
//! grid over every yarn segment give (`Lookup::Whole`, which a test compares); those serve
//! what the bins cannot hold (a camera inside or against the leg).
//!
//! Anti-aliasing and determinism: [`super::sampling`].

use nalgebra::{Point3, Vector3};
use parry3d_f64::query::{PointQuery, Ray, RayCast};
use parry3d_f64::shape::{FeatureId, TriMesh, Triangle};
use rayon::prelude::*;

use super::camera::Camera;
use super::sampling::{strata, PixelSamples};
use super::screen_bins::{Entry, ScreenBins, ScreenView, SubPixel};
use super::shading::{self, Lights};
use super::yarn_lookup::{self, grid_cell, ray_capsule, Capsule, YarnHit, YarnIndex};
use crate::base::colour::{heat, linear_to_srgb8};
use crate::base::{PerYarn, Stance, SurfaceMesh, YarnGeometry, YarnKind};
use crate::error::{Error, Result};
use crate::knit::Yarns;
use crate::preview::{PreviewSettings, RenderMode};

/// Width of the colour bar panel of the density mode, as a fraction of the image height.
const BAR_PANEL_FRACTION: f64 = 0.16;

/// What the renderer draws: the leg, its yarns and their materials.
#[derive(Clone, Copy, Debug)]
pub struct PreviewInput<'a> {
    /// The leg surface, world space, metres. Its `coverage` and `stitch_density` point
    /// attributes are used where present (the `coverage` buffer, the density mode).
    pub leg: &'a SurfaceMesh,
    /// The yarn polylines (after the penetration fix), world space plus their `offset_m`.
    pub yarns: &'a YarnGeometry,
    /// Yarn radius per kind (`YarnKind::index`), metres.
    pub radius_m: PerYarn<f64>,
    /// Linear-RGB yarn colour per kind.
    pub yarn_colour: PerYarn<[f64; 3]>,
    /// How the character stands: what an auto-framed camera's views are taken from.
    pub stance: Stance,
}

impl<'a> PreviewInput<'a> {
    /// The input for `leg` and `yarns` with the radii and colours of `materials`, the
    /// character standing in `stance`.
    pub fn new(
        leg: &'a SurfaceMesh,
        yarns: &'a YarnGeometry,
        materials: &Yarns,
        stance: Stance,
    ) -> PreviewInput<'a> {
        PreviewInput {
            leg,
            yarns,
            radius_m: YarnKind::ALL.map(|k| materials.get(k).radius_m()),
            yarn_colour: YarnKind::ALL.map(|k| materials.get(k).colour),
            stance,
        }
    }
}

/// Renders the preview of `input` as `settings` ask, and encodes it as the PNG file `name`;
/// returns the bytes and the render's counters.
///
/// Errors: [`Error::Encode`] naming `name` when the leg has no triangle or PNG encoding fails.
pub fn encode_preview(
    input: PreviewInput,
    settings: &PreviewSettings,
    name: &str,
) -> Result<(Vec<u8>, PreviewStats)> {
    let preview = render_preview(input, settings, name)?;
    Ok((
        crate::draw::encode_png(&preview.image, name)?,
        preview.stats,
    ))
}

/// Per-pixel buffers besides the picture, for measuring what the picture shows. Each is
/// `width × height`, row-major from the top-left; 0 where no sample hit the leg.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PreviewBuffers {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Fraction of the pixel's samples whose ray hit the leg (through yarn or not).
    pub leg: Vec<f32>,
    /// Of the samples that hit the leg, the fraction that met yarn first: the yarn-covered
    /// fraction of the pixel.
    pub yarn: Vec<f32>,
    /// Mean of the leg's `coverage` attribute at the skin hits (0 without the attribute).
    pub attribute_coverage: Vec<f32>,
    /// Mean world height (y, metres) of the skin hits.
    pub height_m: Vec<f32>,
    /// Mean |cos| of the angle between the ray and the skin's normal at the hits: 1 facing the
    /// camera, 0 at the outline.
    pub facing: Vec<f32>,
}

/// Counters and sizes of one render.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PreviewStats {
    /// Image size, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Samples per pixel actually taken (the requested count rounded up to fill the grid).
    pub spp: u32,
    /// What the pixels show.
    pub mode: RenderMode,
    /// Leg triangles in the ray-casting BVH.
    pub bvh_triangles: usize,
    /// Yarn segments indexed.
    pub segments: usize,
    /// Side of the yarn grid's cells, metres.
    pub cell_m: f64,
    /// Height above the skin within which yarn is looked for, metres.
    pub layer_m: f64,
    /// Samples whose ray hit the leg.
    pub leg_samples: u64,
    /// Of those, samples that met yarn first.
    pub yarn_samples: u64,
    /// Camera eye, metres, world space.
    pub eye_m: [f64; 3],
    /// Vertical field of view, degrees.
    pub fov_deg: f64,
}

/// A rendered preview.
#[derive(Clone, Debug)]
pub struct Preview {
    /// The picture, 8-bit sRGB.
    pub image: image::RgbImage,
    /// The per-pixel measurement buffers.
    pub buffers: PreviewBuffers,
    /// Counters.
    pub stats: PreviewStats,
}

/// The leg and yarns made ready for ray casting from any camera.
pub struct PreparedScene<'a> {
    input: PreviewInput<'a>,
    mesh: TriMesh,
    /// The mesh's triangles (only those with valid indices), as indices into the leg.
    triangles: Vec<[u32; 3]>,
    /// Yarn segments with finite ends.
    segments: usize,
    /// Side of the yarn grid's cells, metres: bounds `layer_m`, and sizes the grid of the
    /// yarn a camera's bins cannot hold.
    cell_m: f64,
    layer_m: f64,
    coverage: Option<&'a [f32]>,
    density: Option<&'a [f32]>,
    /// The box the auto-framed camera frames, along the character's left, up and facing.
    bounds: ([f64; 3], [f64; 3]),
}

impl<'a> PreparedScene<'a> {
    /// Builds the leg's BVH and measures the yarn: its finite segments, the grid cell and the
    /// layer above the skin where yarn is looked for.
    ///
    /// Errors: [`Error::Encode`] naming `what` when the leg has no usable triangle.
    pub fn new(input: PreviewInput<'a>, what: &str) -> Result<PreparedScene<'a>> {
        let leg = input.leg;
        let n = leg.positions.len();
        let finite: Vec<bool> = leg
            .positions
            .iter()
            .map(|p| p.iter().all(|c| c.is_finite()))
            .collect();
        let triangles: Vec<[u32; 3]> = leg
            .triangles
            .iter()
            .copied()
            .filter(|t| t.iter().all(|&i| (i as usize) < n && finite[i as usize]))
            .collect();
        let vertices: Vec<Point3<f64>> = leg
            .positions
            .iter()
            .map(|p| {
                if p.iter().all(|c| c.is_finite()) {
                    Point3::from(*p)
                } else {
                    Point3::origin()
                }
            })
            .collect();
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for t in &triangles {
            for &i in t {
                for k in 0..3 {
                    lo[k] = lo[k].min(vertices[i as usize][k]);
                    hi[k] = hi[k].max(vertices[i as usize][k]);
                }
            }
        }
        // The camera frames the stocking, not the whole file (a body): the yarn's points where
        // it has any within the leg's box, else the leg; boxed along the character's left, up
        // and facing, so a character turned in its file is framed as tightly as an upright one.
        let stance = &input.stance;
        let box_of = |points: &mut dyn Iterator<Item = [f64; 3]>| {
            let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
            for c in points.map(|p| stance.coordinates(p)) {
                for k in 0..3 {
                    lo[k] = lo[k].min(c[k]);
                    hi[k] = hi[k].max(c[k]);
                }
            }
            (0..3).all(|k| lo[k] <= hi[k]).then_some((lo, hi))
        };
        let in_leg_box = |p: &&[f64; 3]| (0..3).all(|k| p[k] >= lo[k] && p[k] <= hi[k]);
        let yarn = box_of(&mut input.yarns.positions.iter().filter(in_leg_box).copied());
        let leg_box = || {
            let corners = triangles
                .iter()
                .flatten()
                .map(|&i| vertices[i as usize].coords.into());
            box_of(&mut corners.collect::<Vec<[f64; 3]>>().into_iter())
        };
        (lo, hi) = yarn.or_else(leg_box).unwrap_or((lo, hi));
        let mesh = TriMesh::new(vertices, triangles.clone()).map_err(|e| Error::Encode {
            what: what.into(),
            message: format!("the leg has no triangle to render: {e}"),
        })?;
        let yarn = measure_yarn(input.yarns, input.radius_m);
        let layer_m = yarn_layer(&mesh, input.yarns, yarn.max_radius);
        let attribute = |name: &str| {
            leg.point_attributes
                .get(name)
                .map(Vec::as_slice)
                .filter(|v| v.len() == n)
        };
        Ok(PreparedScene {
            input,
            mesh,
            triangles,
            segments: yarn.segments,
            cell_m: yarn.cell_m,
            layer_m,
            coverage: attribute("coverage"),
            density: attribute("stitch_density"),
            bounds: (lo, hi),
        })
    }

    /// The capsule of yarn segment `i`, if its ends are finite.
    fn capsule(&self, i: usize) -> Option<Capsule> {
        yarn_lookup::capsule(self.input.yarns, self.input.radius_m, i)
    }

    /// The camera the settings ask for: the scene's, or framed on the leg.
    pub fn camera(&self, settings: &PreviewSettings) -> Camera {
        let aspect = settings.width as f64 / settings.height as f64;
        match &settings.camera {
            Some(c) => Camera::from_settings(c, aspect),
            None => Camera::framing(
                self.bounds.0,
                self.bounds.1,
                settings.view,
                &self.input.stance,
                aspect,
            ),
        }
    }
}

/// Height above the skin within which yarn is looked for: the greatest height of a sample of
/// yarn points above the skin, plus the yarn radius, at least four radii, at most
/// [`MAX_YARN_LAYER_M`]. Most yarn lies at the contact offset; a stocking to the toe bridges the
/// toes' clefts and floats up to about 9 mm over them, and that yarn must be found where the toes
/// are seen face on. The screen bins list every capsule a pixel's rays can meet, nearest first,
/// so a deep layer costs little; the cap bounds the whole-scene grid's walk where they do not
/// serve.
fn yarn_layer(mesh: &TriMesh, yarns: &YarnGeometry, max_radius: f64) -> f64 {
    let r = max_radius;
    let offset = Vector3::from(yarns.offset_m);
    let step = (yarns.positions.len() / 4000).max(1);
    let highest = yarns
        .positions
        .par_iter()
        .step_by(step)
        .filter(|p| p.iter().all(|c| c.is_finite()))
        .map(|p| {
            let q = Point3::from(*p) + offset;
            (mesh.project_local_point(&q, false).point - q).norm()
        })
        .reduce(|| 0.0, f64::max);
    (highest + r).max(4.0 * r).min(MAX_YARN_LAYER_M)
}

/// The deepest yarn layer looked through, metres (see [`yarn_layer`]).
const MAX_YARN_LAYER_M: f64 = 0.012;

/// What the renderer needs to know of the yarn before a camera is chosen.
struct YarnMeasure {
    /// Segments with finite ends.
    segments: usize,
    /// The largest radius, metres.
    max_radius: f64,
    /// The side the yarn grid's cells would have ([`grid_cell`]), metres.
    cell_m: f64,
}

/// Measures the capsules of `yarns`, as [`YarnIndex::new`] would index them.
fn measure_yarn(yarns: &YarnGeometry, radius_m: PerYarn<f64>) -> YarnMeasure {
    // One pass: lengths (the median is the same in any order), and minima and maxima (the
    // same in any order).
    let empty = || {
        (
            Vec::new(),
            Point3::from([f64::INFINITY; 3]),
            Point3::from([f64::NEG_INFINITY; 3]),
            0.0,
        )
    };
    let (mut lengths, lo, hi, max_radius) = (0..yarns.segments.len())
        .into_par_iter()
        .fold(
            empty,
            |(mut lengths, lo, hi, r), i| match yarn_lookup::capsule(yarns, radius_m, i) {
                Some(c) => {
                    lengths.push((c.b - c.a).norm());
                    let pad = Vector3::repeat(c.radius);
                    let (c_lo, c_hi) = (c.a.inf(&c.b) - pad, c.a.sup(&c.b) + pad);
                    (lengths, lo.inf(&c_lo), hi.sup(&c_hi), f64::max(r, c.radius))
                }
                None => (lengths, lo, hi, r),
            },
        )
        .reduce(empty, |(mut la, lo_a, hi_a, r_a), (lb, lo_b, hi_b, r_b)| {
            la.extend(lb);
            (la, lo_a.inf(&lo_b), hi_a.sup(&hi_b), f64::max(r_a, r_b))
        });
    let extent = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
    YarnMeasure {
        segments: lengths.len(),
        max_radius,
        cell_m: grid_cell(&mut lengths, max_radius, extent),
    }
}

/// One sample's outcome.
#[derive(Clone, Copy, Default)]
struct Sample {
    radiance: [f64; 3],
    leg: bool,
    yarn: bool,
    coverage: f64,
    height: f64,
    facing: f64,
}

/// Renders the preview of `input` as `settings` ask. `what` names the output in errors.
pub fn render_preview(
    input: PreviewInput,
    settings: &PreviewSettings,
    what: &str,
) -> Result<Preview> {
    let scene = PreparedScene::new(input, what)?;
    Ok(render_prepared(&scene, settings))
}

/// Renders an already prepared scene (the spp sweep renders one scene several times).
pub fn render_prepared(scene: &PreparedScene, settings: &PreviewSettings) -> Preview {
    render_with(scene, settings, Lookup::Binned)
}

/// How the renderer finds what a camera ray meets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Lookup {
    /// Per-pixel lists ([`ScreenBins`]), and the BVH or a grid for what they cannot hold.
    Binned,
    /// The leg's BVH and one grid over every yarn segment, for every ray: what the bins must
    /// reproduce.
    #[cfg_attr(not(test), allow(dead_code))]
    Whole,
}

fn render_with(scene: &PreparedScene, settings: &PreviewSettings, lookup: Lookup) -> Preview {
    let camera = scene.camera(settings);
    let (w, h) = (settings.width, settings.height);
    let (cols, rows) = strata(settings.spp);
    let spp = cols * rows;
    let view_frame = [camera.right, camera.up, -camera.forward];
    let l = Vector3::from(settings.light_direction);
    let key_direction =
        (view_frame[0] * l.x + view_frame[1] * l.y + view_frame[2] * l.z).normalize();
    let lights = Lights {
        key_direction,
        key_intensity: settings.light_intensity,
        ambient: settings.ambient * settings.light_intensity,
        sheen: settings.yarn_sheen,
        sheen_exponent: settings.yarn_sheen_exponent,
    };
    let density_range = scene.density.and_then(|d| {
        let covered = d.iter().copied().filter(|v| v.is_finite() && *v > 0.0);
        covered.fold(None, |acc: Option<(f32, f32)>, v| match acc {
            None => Some((v, v)),
            Some((lo, hi)) => Some((lo.min(v), hi.max(v))),
        })
    });
    let view = ScreenView {
        camera: &camera,
        width: w,
        height: h,
    };
    let (skin, yarn) = match (lookup, settings.mode) {
        (_, RenderMode::Density) => (SkinLookup::new(scene, &view), YarnLookup::None),
        (Lookup::Binned, RenderMode::Yarn) => {
            (SkinLookup::new(scene, &view), YarnLookup::new(scene, &view))
        }
        (Lookup::Whole, RenderMode::Yarn) => (
            SkinLookup::Mesh,
            YarnLookup::Grid(YarnIndex::new(scene.input.yarns, scene.input.radius_m)),
        ),
    };
    let ctx = Context {
        scene,
        settings,
        camera: &camera,
        lights: &lights,
        density_range,
        background: settings.background.map(inverse_aces),
        skin,
        yarn,
    };
    // One row per task, written in place; each row's pixels in order, each pixel's samples in
    // order. The counts are sums of integers: the same in any order.
    // No `u32` overflow: `PreviewSettings::validate` holds w × h to `MAX_RENDER_PIXELS` (4096²).
    let n = (w * h) as usize;
    let row = w as usize;
    let mut buffers = PreviewBuffers {
        width: w,
        height: h,
        leg: vec![0.0; n],
        yarn: vec![0.0; n],
        attribute_coverage: vec![0.0; n],
        height_m: vec![0.0; n],
        facing: vec![0.0; n],
    };
    let mut image = image::RgbImage::new(w, h);
    let (leg_samples, yarn_samples) = image
        .par_chunks_mut(3 * row)
        .zip(buffers.leg.par_chunks_mut(row))
        .zip(buffers.yarn.par_chunks_mut(row))
        .zip(buffers.attribute_coverage.par_chunks_mut(row))
        .zip(buffers.height_m.par_chunks_mut(row))
        .zip(buffers.facing.par_chunks_mut(row))
        .enumerate()
        .map(|(y, (((((srgb, leg), yarn), coverage), height), facing))| {
            let (mut leg_samples, mut yarn_samples) = (0u64, 0u64);
            for x in 0..row {
                let p = ctx.pixel(x as u32, y as u32, cols, rows);
                srgb[3 * x..3 * x + 3].copy_from_slice(&p.srgb);
                leg_samples += u64::from(p.leg_samples);
                yarn_samples += u64::from(p.yarn_samples);
                let legs = p.leg_samples.max(1) as f32;
                leg[x] = p.leg_samples as f32 / spp as f32;
                yarn[x] = p.yarn_samples as f32 / legs;
                coverage[x] = p.coverage / legs;
                height[x] = p.height / legs;
                facing[x] = p.facing / legs;
            }
            (leg_samples, yarn_samples)
        })
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
    if settings.mode == RenderMode::Density {
        image = crate::draw::colour_bar::with_bar(
            &image,
            density_range.map(|(lo, hi)| (f64::from(lo), f64::from(hi))),
            BAR_PANEL_FRACTION,
        );
    }
    let fov_deg = 2.0 * camera.tan_half_fov.atan().to_degrees();
    Preview {
        image,
        buffers,
        stats: PreviewStats {
            width: w,
            height: h,
            spp,
            mode: settings.mode,
            bvh_triangles: scene.triangles.len(),
            segments: scene.segments,
            cell_m: scene.cell_m,
            layer_m: scene.layer_m,
            leg_samples,
            yarn_samples,
            eye_m: camera.eye.coords.into(),
            fov_deg,
        },
    }
}

struct PixelOut {
    srgb: [u8; 3],
    leg_samples: u32,
    yarn_samples: u32,
    coverage: f32,
    height: f32,
    facing: f32,
}

/// How a camera ray finds the skin.
enum SkinLookup {
    /// Every triangle binned under the pixels it may cover; the few that reach behind the eye
    /// or cover too many pixels in a BVH of their own, with their indices into the scene's.
    Bins {
        bins: ScreenBins,
        global: Option<Box<(TriMesh, Vec<u32>)>>,
    },
    /// Through the leg's BVH: the bins would hold too many entries.
    Mesh,
}

impl SkinLookup {
    fn new(scene: &PreparedScene, view: &ScreenView) -> SkinLookup {
        let vertices = scene.mesh.vertices();
        let binning = ScreenBins::build(view, scene.triangles.len(), |i| {
            let corners = scene.triangles[i].map(|v| vertices[v as usize]);
            Some(view.camera_box(&corners, 0.0))
        });
        let Some(b) = binning else {
            return SkinLookup::Mesh;
        };
        let subset: Vec<[u32; 3]> = b
            .global
            .iter()
            .map(|&i| scene.triangles[i as usize])
            .collect();
        let global = match subset.is_empty() {
            true => None,
            false => match TriMesh::new(vertices.to_vec(), subset) {
                Ok(mesh) => Some(Box::new((mesh, b.global))),
                Err(_) => return SkinLookup::Mesh,
            },
        };
        SkinLookup::Bins {
            bins: b.bins,
            global,
        }
    }
}

/// How a camera ray finds the yarn above its skin hit.
enum YarnLookup {
    /// No yarn is drawn (the density mode).
    None,
    /// Every capsule binned under the pixels it may cover; the few that reach behind the eye
    /// or cover too many pixels in a grid of their own.
    Bins {
        bins: ScreenBins,
        global: Option<YarnIndex>,
    },
    /// One grid over every capsule: the bins would hold 2³² entries or more.
    Grid(YarnIndex),
}

impl YarnLookup {
    fn new(scene: &PreparedScene, view: &ScreenView) -> YarnLookup {
        let binning = ScreenBins::build(view, scene.input.yarns.segments.len(), |i| {
            scene
                .capsule(i)
                .map(|c| view.camera_box(&[c.a, c.b], c.radius))
        });
        match binning {
            Some(b) => {
                let global: Vec<Capsule> = b
                    .global
                    .iter()
                    .filter_map(|&i| scene.capsule(i as usize))
                    .collect();
                YarnLookup::Bins {
                    bins: b.bins,
                    global: (!global.is_empty()).then(|| YarnIndex::from_capsules(global)),
                }
            }
            None => YarnLookup::Grid(YarnIndex::new(scene.input.yarns, scene.input.radius_m)),
        }
    }
}

/// Where a camera ray meets the skin.
struct SkinHit {
    /// Distance along the ray, metres.
    t: f64,
    /// Index into the scene's triangles.
    triangle: usize,
    /// The triangle's unit normal.
    normal: Vector3<f64>,
}

struct Context<'a> {
    scene: &'a PreparedScene<'a>,
    settings: &'a PreviewSettings,
    camera: &'a Camera,
    lights: &'a Lights,
    density_range: Option<(f32, f32)>,
    /// The background's linear radiance.
    background: [f64; 3],
    skin: SkinLookup,
    yarn: YarnLookup,
}

/// The binned lists of one pixel.
#[derive(Clone, Copy)]
struct PixelLists<'a> {
    triangles: &'a [Entry],
    capsules: &'a [Entry],
}

impl Context<'_> {
    fn pixel(&self, x: u32, y: u32, cols: u32, rows: u32) -> PixelOut {
        let (w, h) = (self.settings.width, self.settings.height);
        let pixel_index = u64::from(y) * u64::from(w) + u64::from(x);
        let mut sum = [0.0f64; 3];
        let (mut legs, mut yarns) = (0u32, 0u32);
        let (mut coverage, mut height, mut facing) = (0.0f64, 0.0f64, 0.0f64);
        let lists = PixelLists {
            triangles: match &self.skin {
                SkinLookup::Bins { bins, .. } => bins.pixel(x, y),
                SkinLookup::Mesh => &[],
            },
            capsules: match &self.yarn {
                YarnLookup::Bins { bins, .. } => bins.pixel(x, y),
                _ => &[],
            },
        };
        let binned_only = matches!(self.skin, SkinLookup::Bins { global: None, .. });
        if lists.triangles.is_empty() && binned_only {
            // No triangle can lie under this pixel: every sample sees the background.
            for _ in 0..cols * rows {
                for (total, r) in sum.iter_mut().zip(self.background) {
                    *total += r;
                }
            }
        } else {
            let samples = PixelSamples::new(pixel_index, cols, rows);
            for j in 0..rows {
                for i in 0..cols {
                    let (ox, oy) = samples.offset(i, j);
                    let u = (f64::from(x) + ox) / f64::from(w);
                    let v = (f64::from(y) + oy) / f64::from(h);
                    let s = self.sample(u, v, SubPixel::new(ox, oy), lists);
                    for (total, r) in sum.iter_mut().zip(s.radiance) {
                        *total += r;
                    }
                    if s.leg {
                        legs += 1;
                        yarns += u32::from(s.yarn);
                        coverage += s.coverage;
                        height += s.height;
                        facing += s.facing;
                    }
                }
            }
        }
        let n = f64::from(cols * rows);
        let srgb = sum.map(|c| {
            let mean = c / n;
            linear_to_srgb8(shading::aces(if mean.is_finite() { mean } else { 0.0 }) as f32)
        });
        PixelOut {
            srgb,
            leg_samples: legs,
            yarn_samples: yarns,
            coverage: coverage as f32,
            height: height as f32,
            facing: facing as f32,
        }
    }

    /// The nearest skin the ray meets: over the pixel's triangles, nearest first, until the
    /// next lies beyond the best hit, and the BVH of those not binned; or through the leg's BVH.
    fn skin_hit(&self, ray: &Ray, forward: f64, sub: SubPixel, list: &[Entry]) -> Option<SkinHit> {
        let scene = self.scene;
        // Parry's ray cast through a mesh whose triangle `k` is the scene's `index(k)`.
        let through = |mesh: &TriMesh, index: &dyn Fn(u32) -> usize| {
            let hit = mesh.cast_local_ray_and_get_normal(ray, f64::MAX, false)?;
            let FeatureId::Face(face) = hit.feature else {
                return None;
            };
            Some(SkinHit {
                t: hit.time_of_impact,
                triangle: index(face % mesh.indices().len() as u32),
                normal: hit.normal,
            })
        };
        let global = match &self.skin {
            SkinLookup::Mesh => return through(&scene.mesh, &|k| k as usize),
            SkinLookup::Bins { global, .. } => global
                .as_ref()
                .and_then(|g| through(&g.0, &|k| g.1[k as usize] as usize)),
        };
        let vertices = scene.mesh.vertices();
        let mut best: Option<SkinHit> = None;
        for e in list {
            if best
                .as_ref()
                .is_some_and(|b| f64::from(e.near) > b.t * forward)
            {
                break;
            }
            if !e.covers(sub) {
                continue;
            }
            let triangle = e.item as usize;
            let [a, b, c] = scene.triangles[triangle].map(|v| vertices[v as usize]);
            // Parry's own triangle test, as its BVH would run it.
            let Some(hit) =
                Triangle::new(a, b, c).cast_local_ray_and_get_normal(ray, f64::MAX, false)
            else {
                continue;
            };
            let better = best.as_ref().is_none_or(|b| {
                hit.time_of_impact < b.t || (hit.time_of_impact == b.t && triangle < b.triangle)
            });
            if better {
                best = Some(SkinHit {
                    t: hit.time_of_impact,
                    triangle,
                    normal: hit.normal,
                });
            }
        }
        match (best, global) {
            (Some(b), Some(g)) if g.t < b.t || (g.t == b.t && g.triangle < b.triangle) => Some(g),
            (None, g) => g,
            (b, _) => b,
        }
    }

    /// The nearest yarn the ray `eye + t·dir` meets for `t` in `t0..t1`: over the pixel's
    /// capsules nearest first, as [`YarnIndex::nearest_hit`] finds it over its grid.
    #[allow(clippy::too_many_arguments)]
    fn yarn_hit(
        &self,
        eye: &Point3<f64>,
        dir: &Vector3<f64>,
        forward: f64,
        (t0, t1): (f64, f64),
        sub: SubPixel,
        list: &[Entry],
    ) -> Option<YarnHit> {
        let global = match &self.yarn {
            YarnLookup::None => return None,
            YarnLookup::Grid(grid) => return grid.nearest_hit(eye, dir, t0, t1),
            YarnLookup::Bins { global, .. } => global,
        };
        if t1.partial_cmp(&t0) != Some(std::cmp::Ordering::Greater) {
            return None;
        }
        // From the start of the stretch, as the grid does: the same quadratic, the same roots.
        let start = eye + dir * t0;
        let span = t1 - t0;
        let (z0, z1) = (t0 * forward, t1 * forward);
        let mut best: Option<(f64, u32, Capsule)> = None;
        for e in list {
            let z_best = best.as_ref().map_or(z1, |b| (t0 + b.0) * forward);
            if f64::from(e.near) > z_best {
                break;
            }
            if f64::from(e.far) < z0 || !e.covers(sub) {
                continue;
            }
            let Some(c) = self.scene.capsule(e.item as usize) else {
                continue;
            };
            if let Some(t) = ray_capsule(&start, dir, &c) {
                let better = best
                    .as_ref()
                    .is_none_or(|&(bt, bi, _)| t < bt || (t == bt && e.item < bi));
                if t <= span && better {
                    best = Some((t, e.item, c));
                }
            }
        }
        let binned = best.map(|(t, _, c)| yarn_lookup::hit_on(&c, &start, dir, t0, t));
        let global = global
            .as_ref()
            .and_then(|g| g.nearest_hit(eye, dir, t0, t1));
        match (binned, global) {
            (Some(b), Some(g)) if g.t < b.t => Some(g),
            (None, g) => g,
            (b, _) => b,
        }
    }

    fn sample(&self, u: f64, v: f64, sub: SubPixel, lists: PixelLists) -> Sample {
        let scene = self.scene;
        let dir = self.camera.direction(u, v);
        let eye = self.camera.eye;
        let background = Sample {
            radiance: self.background,
            ..Sample::default()
        };
        let ray = Ray::new(eye, dir);
        let forward = dir.dot(&self.camera.forward);
        let Some(hit) = self.skin_hit(&ray, forward, sub, lists.triangles) else {
            return background;
        };
        let t_skin = hit.t;
        let tri = scene.triangles[hit.triangle];
        let p = eye + dir * t_skin;
        let corners = tri.map(|i| Point3::from(scene.input.leg.positions[i as usize]));
        let bary = barycentric(&corners, &p);
        let normals = tri.map(|i| Vector3::from(scene.input.leg.normals[i as usize]).cast::<f64>());
        let mut n = normals[0] * bary[0] + normals[1] * bary[1] + normals[2] * bary[2];
        let mut geometric = hit.normal;
        if geometric.dot(&dir) > 0.0 {
            geometric = -geometric;
        }
        if n.norm_squared() < 1e-20 || !n.iter().all(|c| c.is_finite()) {
            n = geometric;
        }
        n = n.normalize();
        if n.dot(&dir) > 0.0 {
            // Seen from behind (inside the leg through an open cut): shade the side we see.
            n = -n;
        }
        let cos = (-dir.dot(&geometric)).clamp(0.0, 1.0);
        let interpolate = |values: Option<&[f32]>| {
            values.map_or(0.0, |a| {
                (0..3)
                    .map(|k| f64::from(a[tri[k] as usize]) * bary[k])
                    .sum::<f64>()
            })
        };
        let mut s = Sample {
            leg: true,
            coverage: interpolate(scene.coverage),
            height: p.y,
            facing: cos,
            ..Sample::default()
        };
        let view = -dir;
        match self.settings.mode {
            RenderMode::Yarn => {
                let stretch = (scene.layer_m / cos.max(1e-6)).min(3.0 * scene.layer_m);
                let window = ((t_skin - stretch).max(0.0), t_skin);
                let yarn = self.yarn_hit(&eye, &dir, forward, window, sub, lists.capsules);
                s.radiance = match yarn {
                    Some(y) => {
                        s.yarn = true;
                        let mut yn = y.normal;
                        if yn.dot(&view) < 0.0 {
                            // A ray starting inside the yarn: shade the side facing the eye.
                            yn = view;
                        }
                        let albedo = self.scene.input.yarn_colour[y.yarn.index() as usize];
                        shading::yarn(albedo, &yn, &y.tangent, &view, self.lights)
                    }
                    None => shading::skin(self.settings.skin_colour, &n, self.lights),
                };
            }
            RenderMode::Density => {
                let d = interpolate(scene.density);
                let albedo = match self.density_range {
                    Some((lo, hi)) if d > 0.0 => {
                        let t = if hi > lo {
                            (d - f64::from(lo)) / f64::from(hi - lo)
                        } else {
                            0.5
                        };
                        heat(t).map(f64::from)
                    }
                    _ => [0.3; 3],
                };
                // Flat enough that the bar's colours read on the leg: ambient floor + Lambert.
                let lambert = n.dot(&self.lights.key_direction).max(0.0);
                s.radiance = albedo.map(|a| inverse_aces(a * (0.45 + 0.55 * lambert)));
            }
        }
        s
    }
}

/// The linear radiance that tone-maps to display value `y` (so a background or a density colour
/// given in display terms comes out as given).
fn inverse_aces(y: f64) -> f64 {
    let y = y.clamp(0.0, 0.999);
    // Solve y (c x² + d x + e) = a x² + b x for x ≥ 0.
    let (a, b, c, d, e) = (2.51, 0.03, 2.43, 0.59, 0.14);
    let qa = y * c - a;
    let qb = y * d - b;
    let qc = y * e;
    let disc = (qb * qb - 4.0 * qa * qc).max(0.0);
    ((-qb - disc.sqrt()) / (2.0 * qa)).max(0.0)
}

/// Barycentric coordinates of `p` (on the triangle's plane) in the triangle `c`.
fn barycentric(c: &[Point3<f64>; 3], p: &Point3<f64>) -> [f64; 3] {
    let (e0, e1, ep) = (c[1] - c[0], c[2] - c[0], p - c[0]);
    let (d00, d01, d11) = (e0.dot(&e0), e0.dot(&e1), e1.dot(&e1));
    let (d20, d21) = (ep.dot(&e0), ep.dot(&e1));
    let denom = d00 * d11 - d01 * d01;
    if denom.abs() <= 0.0 || !denom.is_finite() {
        return [1.0, 0.0, 0.0];
    }
    let v = ((d11 * d20 - d01 * d21) / denom).clamp(0.0, 1.0);
    let w = ((d00 * d21 - d01 * d20) / denom).clamp(0.0, 1.0 - v);
    [1.0 - v - w, v, w]
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::base::{Direction, Segment};
    use crate::preview::CameraSettings;

    /// An open cylinder of radius 5 cm along y, and rings of yarn just outside and just inside
    /// its surface, each a closed polyline of 0.4 mm segments, nylon and support in turn.
    fn cylinder_and_rings() -> (SurfaceMesh, YarnGeometry) {
        let (around, along, radius, length) = (48u32, 24u32, 0.05, 0.2);
        let mut positions = Vec::new();
        let mut normals = Vec::new();
        for j in 0..=along {
            for i in 0..around {
                let a = f64::from(i) / f64::from(around) * std::f64::consts::TAU;
                positions.push([
                    radius * a.cos(),
                    f64::from(j) / f64::from(along) * length,
                    radius * a.sin(),
                ]);
                normals.push([a.cos() as f32, 0.0, a.sin() as f32]);
            }
        }
        let mut triangles = Vec::new();
        for j in 0..along {
            for i in 0..around {
                let at = |i: u32, j: u32| j * around + i % around;
                let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i, j + 1), at(i + 1, j + 1));
                triangles.push([a, c, b]);
                triangles.push([b, c, d]);
            }
        }
        let mut leg = SurfaceMesh::new("cylinder", positions, triangles);
        leg.normals = normals;
        let mut points = Vec::new();
        let mut segments = Vec::new();
        // Outside the surface, and inside it (seen from within).
        for r in [radius + 4e-5, radius - 4e-5] {
            let per_ring = (std::f64::consts::TAU * r / 4e-4) as u32;
            for ring in 0..200u32 {
                let y = 1e-3 * f64::from(ring);
                let first = points.len() as u32;
                for k in 0..per_ring {
                    let a = f64::from(k) / f64::from(per_ring) * std::f64::consts::TAU;
                    points.push([r * a.cos(), y, r * a.sin()]);
                    segments.push(Segment {
                        a: first + k,
                        b: first + (k + 1) % per_ring,
                        yarn: match ring % 2 {
                            0 => YarnKind::Nylon,
                            _ => YarnKind::Support,
                        },
                        direction: Direction::Course,
                    });
                }
            }
        }
        let yarns = YarnGeometry {
            name: "rings".into(),
            offset_m: [0.0; 3],
            positions: points,
            point_attributes: Default::default(),
            segments,
        };
        (leg, yarns)
    }

    /// The same picture and buffers by the bins as by the BVH and one grid, from outside the
    /// leg (everything binned) and from inside it (triangles and yarn reaching behind the eye).
    #[test]
    fn the_bins_find_what_the_bvh_and_the_grid_find() {
        let (leg, yarns) = cylinder_and_rings();
        let input = PreviewInput {
            leg: &leg,
            yarns: &yarns,
            radius_m: [3e-5, 4e-5, 3e-5],
            yarn_colour: [[0.16, 0.11, 0.09], [0.08, 0.07, 0.10], [0.5; 3]],
            stance: Stance::default(),
        };
        let scene = PreparedScene::new(input, "test").unwrap();
        let outside = PreviewSettings {
            width: 48,
            height: 64,
            spp: 4,
            view: crate::preview::View::ThreeQuarter,
            ..PreviewSettings::default()
        };
        let inside = PreviewSettings {
            camera: Some(CameraSettings {
                position: [0.0, 0.1, 0.0],
                target: [0.05, 0.1, 0.01],
                fov_deg: 100.0,
            }),
            ..outside.clone()
        };
        // Against the skin: a triangle covers the whole picture.
        let near = PreviewSettings {
            width: 96,
            height: 96,
            camera: Some(CameraSettings {
                position: [0.0017, 0.1022, 0.0503],
                target: [0.0017, 0.1022, 0.0],
                fov_deg: 90.0,
            }),
            ..outside.clone()
        };
        for (settings, skin_global_expected, yarn_global) in [
            (outside, false, false),
            (inside, true, true),
            (near, true, false),
        ] {
            let camera = scene.camera(&settings);
            let view = ScreenView {
                camera: &camera,
                width: settings.width,
                height: settings.height,
            };
            let skin = SkinLookup::new(&scene, &view);
            let case = format!("{:?}", settings.camera);
            let SkinLookup::Bins {
                global: skin_global,
                ..
            } = skin
            else {
                panic!("the skin is not binned");
            };
            assert_eq!(skin_global.is_some(), skin_global_expected, "{case}");
            let YarnLookup::Bins { global, .. } = YarnLookup::new(&scene, &view) else {
                panic!("the yarn is not binned");
            };
            assert_eq!(global.is_some(), yarn_global, "{case}");
            let binned = render_with(&scene, &settings, Lookup::Binned);
            let whole = render_with(&scene, &settings, Lookup::Whole);
            assert!(binned.stats.yarn_samples > 0, "{case}");
            assert_eq!(binned.stats, whole.stats, "{case}");
            assert_eq!(binned.buffers, whole.buffers, "{case}");
            assert!(binned.image == whole.image, "{case}");
        }
    }

    #[test]
    fn inverse_tone_mapping_round_trips() {
        for y in [0.0, 0.1, 0.5, 0.78, 0.95] {
            assert!((shading::aces(inverse_aces(y)) - y).abs() < 1e-9, "{y}");
        }
    }
}
