//! The yarn-level preview (`preview.png`, `knitfit render`): a ray-traced still of the fitted
//! stocking on the leg, after Sakaguchi & Miyata §7–8 (Fig. 17), or the leg coloured by stitch
//! density (Fig. 18).
//!
//! Per sample: the camera ray is cast against the leg's triangles (parry's BVH); at the skin hit
//! the ray's last stretch through the yarn layer — the skin's normal height `layer_m` divided by
//! the cosine of the view angle, at most two grid cells — is tested against the yarn cylinders
//! nearby ([`YarnIndex`]); the nearest yarn before the skin is shaded with its cylinder normal
//! and tangent, else the skin shows (see `yarn_lookup.rs` for why the ray, not only the normal,
//! decides). A ray that misses the skin sees the background: yarn hovering beyond the outline
//! is a few hundredths of a millimetre wide, far below a pixel.
//!
//! Anti-aliasing and determinism: [`super::sampling`].

use nalgebra::{Point3, Vector3};
use parry3d_f64::query::{PointQuery, Ray, RayCast};
use parry3d_f64::shape::{FeatureId, TriMesh};
use rayon::prelude::*;

use super::camera::Camera;
use super::sampling::{strata, PixelSamples};
use super::shading::{self, Lights};
use super::yarn_lookup::YarnIndex;
use crate::base::colour::{heat, linear_to_srgb8};
use crate::base::{PerYarn, SurfaceMesh, YarnGeometry, YarnKind};
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
}

impl<'a> PreviewInput<'a> {
    /// The input for `leg` and `yarns` with the radii and colours of `materials`.
    pub fn new(
        leg: &'a SurfaceMesh,
        yarns: &'a YarnGeometry,
        materials: &Yarns,
    ) -> PreviewInput<'a> {
        PreviewInput {
            leg,
            yarns,
            radius_m: YarnKind::ALL.map(|k| materials.get(k).radius_m()),
            yarn_colour: YarnKind::ALL.map(|k| materials.get(k).colour),
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
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
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

/// The leg and yarns made ready for ray casting.
pub struct PreparedScene<'a> {
    input: PreviewInput<'a>,
    mesh: TriMesh,
    /// The mesh's triangles (only those with valid indices), as indices into the leg.
    triangles: Vec<[u32; 3]>,
    yarns: YarnIndex,
    layer_m: f64,
    coverage: Option<&'a [f32]>,
    density: Option<&'a [f32]>,
    bounds: ([f64; 3], [f64; 3]),
}

impl<'a> PreparedScene<'a> {
    /// Builds the leg's BVH and the yarn grid.
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
        // it has any within the leg's box, else the leg.
        let mut yarn_lo = [f64::INFINITY; 3];
        let mut yarn_hi = [f64::NEG_INFINITY; 3];
        for p in &input.yarns.positions {
            if (0..3).all(|k| p[k] >= lo[k] && p[k] <= hi[k]) {
                for k in 0..3 {
                    yarn_lo[k] = yarn_lo[k].min(p[k]);
                    yarn_hi[k] = yarn_hi[k].max(p[k]);
                }
            }
        }
        if (0..3).all(|k| yarn_lo[k] <= yarn_hi[k]) {
            (lo, hi) = (yarn_lo, yarn_hi);
        }
        let mesh = TriMesh::new(vertices, triangles.clone()).map_err(|e| Error::Encode {
            what: what.into(),
            message: format!("the leg has no triangle to render: {e}"),
        })?;
        let yarns = YarnIndex::new(input.yarns, input.radius_m);
        let layer_m = yarn_layer(&mesh, input.yarns, &yarns);
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
            yarns,
            layer_m,
            coverage: attribute("coverage"),
            density: attribute("stitch_density"),
            bounds: (lo, hi),
        })
    }

    /// The camera the settings ask for: the scene's, or framed on the leg.
    pub fn camera(&self, settings: &PreviewSettings) -> Camera {
        let aspect = settings.width as f64 / settings.height as f64;
        match &settings.camera {
            Some(c) => Camera::from_settings(c, aspect),
            None => Camera::framing(self.bounds.0, self.bounds.1, settings.view, aspect),
        }
    }
}

/// Height above the skin within which yarn is looked for: the 99th percentile of how far a
/// sample of yarn points lies from the skin, plus the yarn radius, at least four radii. Most
/// yarn lies at the contact offset; the percentile is there for the few stretches that bridge
/// a hollow or hang off an end ring, millimetres up. At most two grid cells, which bounds each
/// ray's walk: yarn floating higher still is missed where its skin is seen face on.
fn yarn_layer(mesh: &TriMesh, yarns: &YarnGeometry, index: &YarnIndex) -> f64 {
    let r = index.max_radius();
    let offset = Vector3::from(yarns.offset_m);
    let step = (yarns.positions.len() / 2000).max(1);
    let mut distances: Vec<f64> = yarns
        .positions
        .par_iter()
        .step_by(step)
        .filter(|p| p.iter().all(|c| c.is_finite()))
        .map(|p| {
            let q = Point3::from(*p) + offset;
            (mesh.project_local_point(&q, false).point - q).norm()
        })
        .collect();
    distances.sort_by(f64::total_cmp);
    let p99 = distances
        .get(distances.len() * 99 / 100)
        .copied()
        .unwrap_or(0.0);
    (p99 + r).max(4.0 * r).min(6.0 * index.cell_size())
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
    let ctx = Context {
        scene,
        settings,
        camera: &camera,
        lights: &lights,
        density_range,
    };
    // One row per task; each row's pixels in order, each pixel's samples in order.
    let rows_out: Vec<Vec<PixelOut>> = (0..h)
        .into_par_iter()
        .map(|y| {
            (0..w)
                .map(|x| ctx.pixel(x, y, cols, rows))
                .collect::<Vec<_>>()
        })
        .collect();
    let n = (w * h) as usize;
    let mut buffers = PreviewBuffers {
        width: w,
        height: h,
        leg: Vec::with_capacity(n),
        yarn: Vec::with_capacity(n),
        attribute_coverage: Vec::with_capacity(n),
        height_m: Vec::with_capacity(n),
        facing: Vec::with_capacity(n),
    };
    let mut image = image::RgbImage::new(w, h);
    let (mut leg_samples, mut yarn_samples) = (0u64, 0u64);
    for (y, row) in rows_out.iter().enumerate() {
        for (x, p) in row.iter().enumerate() {
            image.put_pixel(x as u32, y as u32, image::Rgb(p.srgb));
            leg_samples += p.leg_samples as u64;
            yarn_samples += p.yarn_samples as u64;
            let legs = p.leg_samples.max(1) as f32;
            buffers.leg.push(p.leg_samples as f32 / spp as f32);
            buffers.yarn.push(p.yarn_samples as f32 / legs);
            buffers.attribute_coverage.push(p.coverage / legs);
            buffers.height_m.push(p.height / legs);
            buffers.facing.push(p.facing / legs);
        }
    }
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
            segments: scene.yarns.len(),
            cell_m: scene.yarns.cell_size(),
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

struct Context<'a> {
    scene: &'a PreparedScene<'a>,
    settings: &'a PreviewSettings,
    camera: &'a Camera,
    lights: &'a Lights,
    density_range: Option<(f32, f32)>,
}

impl Context<'_> {
    fn pixel(&self, x: u32, y: u32, cols: u32, rows: u32) -> PixelOut {
        let (w, h) = (self.settings.width, self.settings.height);
        let pixel_index = u64::from(y) * u64::from(w) + u64::from(x);
        let mut sum = [0.0f64; 3];
        let (mut legs, mut yarns) = (0u32, 0u32);
        let (mut coverage, mut height, mut facing) = (0.0f64, 0.0f64, 0.0f64);
        let samples = PixelSamples::new(pixel_index, cols, rows);
        for j in 0..rows {
            for i in 0..cols {
                let (ox, oy) = samples.offset(i, j);
                let u = (f64::from(x) + ox) / f64::from(w);
                let v = (f64::from(y) + oy) / f64::from(h);
                let s = self.sample(u, v);
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

    fn sample(&self, u: f64, v: f64) -> Sample {
        let scene = self.scene;
        let dir = self.camera.direction(u, v);
        let eye = self.camera.eye;
        let background = Sample {
            radiance: self.settings.background.map(inverse_aces),
            ..Sample::default()
        };
        let ray = Ray::new(eye, dir);
        let Some(hit) = scene
            .mesh
            .cast_local_ray_and_get_normal(&ray, f64::MAX, false)
        else {
            return background;
        };
        let t_skin = hit.time_of_impact;
        let tri_count = scene.triangles.len() as u32;
        let FeatureId::Face(face) = hit.feature else {
            return background;
        };
        let tri = scene.triangles[(face % tri_count) as usize];
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
                let yarn = scene
                    .yarns
                    .nearest_hit(&eye, &dir, (t_skin - stretch).max(0.0), t_skin);
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

    #[test]
    fn inverse_tone_mapping_round_trips() {
        for y in [0.0, 0.1, 0.5, 0.78, 0.95] {
            assert!((shading::aces(inverse_aces(y)) - y).abs() < 1e-9, "{y}");
        }
    }
}
