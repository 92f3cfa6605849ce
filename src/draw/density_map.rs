//! The stitch-density picture (`density.png`): the leg seen from the front and from the side, side
//! by side, coloured by the stitch density of the fitted stocking at each leg vertex, with a
//! colour bar in stitches/cm².
//!
//! Choices, and why:
//!
//! - **Orthographic views at one scale.** Lengths compare across the two views and along the leg
//!   (a perspective camera would enlarge whatever is nearer to it). Both views are framed on the
//!   drawn triangles' extent along their axes, with a margin. They are taken from how the
//!   character stands ([`Stance`]): the *front* view looks at its face (its left on the right;
//!   for glTF's stance, from +Z with +X to the right), the *side* view at its left (its front on
//!   the left: for a left leg, its outer side).
//! - **Colour.** Density maps linearly over [min, max] of the covered vertices (density > 0) onto
//!   the heat map, the same as the vertex colours of `stocking.glb` and `leg.ply` and the
//!   colour bar's ([`super::colour_bar`]). Vertices without yarn (density 0, negative or not
//!   finite) are skin, drawn neutral grey rather than the coldest colour.
//! - **Shading.** Per-vertex coverage and normalised density are interpolated across each
//!   triangle (Gouraud) and mapped to colour per sample, so the leg shows the bar's colours (not
//!   blends of them); a Lambert term from a light fixed relative to the camera (up, left and in
//!   front) over a 30 % ambient floor darkens them just enough that the leg's form reads. Faces
//!   seen from behind (through an open cut) are drawn darker and flat.
//! - **Anti-aliasing.** Each view is z-buffered at `supersample`² samples per pixel and
//!   box-filtered in linear light ([`super::canvas::LinearImage`]).
//! - **Colour bar** at the right ([`super::colour_bar`]), the unit above it.
//!
//! Pure and deterministic: no randomness, no threads, the same bytes for the same input; bad input
//! (out-of-range indices, non-finite positions, degenerate triangles) is skipped, never a panic.

use super::canvas::{Anchor, Canvas, Font, LinearImage};
use super::colour_bar::{draw_bar, BarPlace, ColourScale, HeatLut, UNCOVERED, UNIT_LABEL};
use crate::base::colour::linear_to_srgb8;
use crate::base::Stance;
use image::RgbImage;

/// How the density picture looks.
#[derive(Clone, Debug, PartialEq)]
pub struct DensityPictureStyle {
    /// Height of each view, pixels (default: 640; 64 to 4096 is used). Widths follow the leg's
    /// proportions; the font size follows this height.
    pub view_px: u32,
    /// Samples per pixel along each axis, for anti-aliasing (default: 2, i.e. 2×2; 1 to 4 is
    /// used).
    pub supersample: u32,
}

impl Default for DensityPictureStyle {
    fn default() -> Self {
        DensityPictureStyle {
            view_px: 640,
            supersample: 2,
        }
    }
}

/// Linear-RGB background: the light warm grey of the patch picture.
const BACKGROUND: [f32; 3] = [0.80, 0.78, 0.74];
/// Shading floor: the fraction of a colour kept where the light does not reach.
const AMBIENT: f32 = 0.3;
/// Shading gain of the Lambert term on top of [`AMBIENT`].
const DIFFUSE: f32 = 0.7;
/// Extra darkening of faces seen from behind (the inside of the leg, seen through a cut).
const BACK_FACE_DIM: f32 = 0.6;
/// Light direction in camera terms (right, up, towards the viewer), normalised where used.
const LIGHT_CAMERA: [f64; 3] = [-0.5, 0.4, 0.75];
/// Empty border around the leg in each view, as a fraction of `view_px`.
const MARGIN: f64 = 0.05;
/// Widest view, as a multiple of `view_px` (a mesh wider than tall is scaled down to fit).
const MAX_VIEW_ASPECT: f64 = 1.5;
/// Smallest and largest `view_px` used.
const VIEW_PX_RANGE: (u32, u32) = (64, 2048);
/// Largest `supersample` used.
const MAX_SUPERSAMPLE: u32 = 4;
/// Most samples along a view's height (`view_px × supersample`), which bounds the buffers'
/// memory; `supersample` is lowered to stay within it.
const MAX_SAMPLES_HIGH: u32 = 4096;

/// One orthographic camera: world directions of the image's right and of the viewer; up is the
/// character's.
#[derive(Clone, Copy, Debug)]
struct ViewFrame {
    label: &'static str,
    right: [f64; 3],
    toward_viewer: [f64; 3],
}

/// The two views of a character standing in `stance`, left to right: the front looks at its
/// face (its left on the image's right), the side at its left (its front on the left).
fn views(stance: &Stance) -> [ViewFrame; 2] {
    let (facing, left) = (stance.facing, stance.left());
    [
        ViewFrame {
            label: "front",
            right: left.into(),
            toward_viewer: facing.into(),
        },
        ViewFrame {
            label: "side",
            right: (-facing).into(),
            toward_viewer: left.into(),
        },
    ]
}

/// Draws the density picture: the front view, the side view, then the colour bar, left to right.
///
/// `positions`: leg vertices, metres, world space, seen as the character stands in `stance`
/// (glTF's: +Y up, facing +Z, by default). `triangles`: vertex indices, counter-clockwise seen from outside; a triangle naming a
/// vertex that does not exist or has a non-finite coordinate is skipped. `density`: per vertex,
/// stitches per cm²; 0, negative or non-finite means no yarn there (drawn grey); a vertex beyond
/// the end of `density` has none.
///
/// The image is `view_px` high plus a label band; its width follows the leg's proportions. An
/// empty mesh gives empty views and the bar.
pub fn draw_density(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    density: &[f64],
    stance: &Stance,
    style: &DensityPictureStyle,
) -> RgbImage {
    let mesh = PreparedMesh::new(positions, triangles);
    let scale = ColourScale::of(density);
    let layout = Layout::new(&mesh, &scale, stance, style);
    let shading = VertexColouring::new(positions.len(), density, &scale);
    let mut canvas = Canvas::new(layout.width, layout.height, BACKGROUND.map(linear_to_srgb8));
    let lut = HeatLut::new();
    for view in 0..2 {
        draw_view(&mut canvas, &mesh, &shading, &lut, view, &layout);
    }
    draw_bar(&mut canvas, layout.bar, &scale, &lut, layout.font);
    draw_labels(&mut canvas, &layout);
    canvas.into_image()
}

/// The triangles that can be drawn, with per-vertex normals.
struct PreparedMesh<'a> {
    positions: &'a [[f64; 3]],
    /// Triangles whose indices exist and whose corners are finite.
    triangles: Vec<[usize; 3]>,
    /// Per vertex: unit area-weighted normal, or zero where no drawable triangle gives one.
    normals: Vec<[f64; 3]>,
}

impl<'a> PreparedMesh<'a> {
    fn new(positions: &'a [[f64; 3]], triangles: &[[u32; 3]]) -> Self {
        let finite: Vec<bool> = positions
            .iter()
            .map(|p| p.iter().all(|c| c.is_finite()))
            .collect();
        let drawable: Vec<[usize; 3]> = triangles
            .iter()
            .map(|t| t.map(|i| i as usize))
            .filter(|t| t.iter().all(|&i| finite.get(i).copied().unwrap_or(false)))
            .collect();
        let mut normals = vec![[0.0; 3]; positions.len()];
        for t in &drawable {
            // The cross product's length is twice the area: larger faces weigh more.
            let n = face_normal(positions, *t);
            for &i in t {
                normals[i] = add(normals[i], n);
            }
        }
        for n in &mut normals {
            *n = normalised(*n).unwrap_or([0.0; 3]);
        }
        PreparedMesh {
            positions,
            triangles: drawable,
            normals,
        }
    }

    /// The least and greatest `axis · p` over the drawable triangles' corners; `(0, 0)` for
    /// none.
    fn range(&self, axis: [f64; 3]) -> (f64, f64) {
        self.triangles
            .iter()
            .flatten()
            .map(|&i| dot(self.positions[i], axis))
            .fold(None, |range, x| match range {
                None => Some((x, x)),
                Some((lo, hi)) => Some((f64::min(lo, x), f64::max(hi, x))),
            })
            .unwrap_or((0.0, 0.0))
    }
}

/// Per-vertex inputs of the colour: coverage (0 or 1) and position on the colour map.
struct VertexColouring {
    covered: Vec<f32>,
    t: Vec<f32>,
}

impl VertexColouring {
    fn new(vertices: usize, density: &[f64], scale: &ColourScale) -> Self {
        let position: Vec<Option<f64>> = (0..vertices)
            .map(|i| density.get(i).and_then(|&d| scale.position(d)))
            .collect();
        VertexColouring {
            covered: position
                .iter()
                .map(|p| f32::from(u8::from(p.is_some())))
                .collect(),
            t: position.iter().map(|p| p.unwrap_or(0.0) as f32).collect(),
        }
    }
}

/// A view's horizontal place in the image, pixels.
#[derive(Clone, Copy, Debug)]
struct ViewRect {
    x0: usize,
    width: usize,
}

/// Where everything goes, in image pixels.
#[derive(Clone, Debug)]
struct Layout {
    width: usize,
    height: usize,
    /// Height of the label band above the views.
    band: usize,
    /// Height of the views (below the band).
    view_px: usize,
    supersample: usize,
    views: [ViewRect; 2],
    /// Each view's directions (see [`views`]).
    frames: [ViewFrame; 2],
    /// Up in both views: the character's.
    up: [f64; 3],
    /// Pixels per metre, both views.
    px_per_m: f64,
    /// The point drawn at each view's centre, metres.
    centres_m: [[f64; 3]; 2],
    font: Font,
    /// The colour bar.
    bar: BarPlace,
    /// The bar panel: left edge and width.
    panel_x0: usize,
    panel_width: usize,
}

impl Layout {
    fn new(
        mesh: &PreparedMesh,
        scale: &ColourScale,
        stance: &Stance,
        style: &DensityPictureStyle,
    ) -> Self {
        let view_px = style.view_px.clamp(VIEW_PX_RANGE.0, VIEW_PX_RANGE.1) as usize;
        let supersample = style
            .supersample
            .min(MAX_SAMPLES_HIGH / view_px as u32)
            .clamp(1, MAX_SUPERSAMPLE) as usize;
        let font = Font::for_height(view_px);
        let (char_w, char_h) = (font.char_width(), font.char_height());
        let band = 2 * char_h;
        let margin_px = (MARGIN * view_px as f64).round();

        let (frames, up) = (views(stance), stance.up.into());
        let extent = |axis: [f64; 3]| {
            let (lo, hi) = mesh.range(axis);
            hi - lo
        };
        let height_m = extent(up);
        let widths_m = frames.map(|v| extent(v.right));
        let inner_h = view_px as f64 - 2.0 * margin_px;
        let inner_w = MAX_VIEW_ASPECT * view_px as f64 - 2.0 * margin_px;
        let px_per_m = [
            inner_h / height_m,
            inner_w / widths_m[0],
            inner_w / widths_m[1],
        ]
        .into_iter()
        .filter(|s| s.is_finite() && *s > 0.0)
        .fold(f64::INFINITY, f64::min);
        let px_per_m = if px_per_m.is_finite() { px_per_m } else { 1.0 };
        // Each view centred on the mesh's extent along its three directions.
        let mid = |axis: [f64; 3]| {
            let (lo, hi) = mesh.range(axis);
            scaled(axis, (lo + hi) / 2.0)
        };
        let centres_m = frames.map(|f| add(add(mid(f.right), mid(up)), mid(f.toward_viewer)));

        let min_view_w = (view_px / 5).max(font.text_width("front") + 2 * char_w);
        let mut x = 0;
        let views = widths_m.map(|w_m| {
            let w = (w_m * px_per_m + 2.0 * margin_px).ceil();
            let w = (w.min(MAX_VIEW_ASPECT * view_px as f64) as usize).max(min_view_w);
            let rect = ViewRect { x0: x, width: w };
            x += w;
            rect
        });

        let bar_width = (view_px / 28).max(8);
        let (bar_row, swatch_row) = BarPlace::row_widths(bar_width, scale, font);
        let unit_w = font.text_width(UNIT_LABEL);
        let panel_width = 2 * char_w + unit_w.max(bar_row).max(swatch_row);
        let panel_x0 = x;
        let bar_top = band + margin_px as usize;
        // Below the bar: half a line of space, then the swatch (one line high).
        let bar_bottom = (band + view_px - margin_px as usize)
            .saturating_sub(char_h + char_h / 2)
            .max(bar_top + 2);
        let bar = BarPlace {
            x0: panel_x0 + char_w + (unit_w.saturating_sub(bar_row)) / 2,
            width: bar_width,
            top: bar_top,
            bottom: bar_bottom,
        };
        Layout {
            width: panel_x0 + panel_width,
            height: band + view_px,
            band,
            view_px,
            supersample,
            views,
            frames,
            up,
            px_per_m,
            centres_m,
            font,
            bar,
            panel_x0,
            panel_width,
        }
    }

    /// A world point in a view's supersampled buffer: x right, y down, samples; and its depth
    /// towards the viewer, metres.
    fn project_samples(&self, view: usize, p: [f64; 3]) -> [f64; 3] {
        let (frame, rect) = (&self.frames[view], &self.views[view]);
        let d = sub(p, self.centres_m[view]);
        let s = self.supersample as f64;
        [
            (rect.width as f64 / 2.0 + dot(d, frame.right) * self.px_per_m) * s,
            (self.view_px as f64 / 2.0 - dot(d, self.up) * self.px_per_m) * s,
            dot(d, frame.toward_viewer),
        ]
    }

    /// A world point in image pixels (x, y), in the given view (0 front, 1 side).
    #[cfg(test)]
    fn project_image(&self, view: usize, p: [f64; 3]) -> [f64; 2] {
        let rect = &self.views[view];
        let q = self.project_samples(view, p);
        let s = self.supersample as f64;
        [rect.x0 as f64 + q[0] / s, self.band as f64 + q[1] / s]
    }
}

/// Rasterises one view into its rectangle of `canvas`.
fn draw_view(
    canvas: &mut Canvas,
    mesh: &PreparedMesh,
    colouring: &VertexColouring,
    lut: &HeatLut,
    view: usize,
    layout: &Layout,
) {
    let (frame, rect) = (&layout.frames[view], &layout.views[view]);
    let ss = layout.supersample;
    let (w, h) = (rect.width * ss, layout.view_px * ss);
    let light = normalised(add(
        add(
            scaled(frame.right, LIGHT_CAMERA[0]),
            scaled(layout.up, LIGHT_CAMERA[1]),
        ),
        scaled(frame.toward_viewer, LIGHT_CAMERA[2]),
    ))
    .unwrap_or(frame.toward_viewer);
    let lambert = |n: [f64; 3]| AMBIENT + DIFFUSE * dot(n, light).max(0.0) as f32;
    let projected: Vec<[f64; 3]> = mesh
        .positions
        .iter()
        .map(|&p| layout.project_samples(view, p))
        .collect();
    let vertex_shade: Vec<f32> = mesh
        .normals
        .iter()
        .map(|&n| {
            if n == [0.0; 3] {
                lambert(frame.toward_viewer)
            } else {
                lambert(n)
            }
        })
        .collect();

    let mut depth = vec![f64::NEG_INFINITY; w * h];
    let mut samples = LinearImage::new(rect.width, layout.view_px, ss, BACKGROUND);
    for &tri in &mesh.triangles {
        let [a, b, c] = tri.map(|i| projected[i]);
        let area = edge(a, b, c);
        // Also skips NaN areas (a vertex projected from an overflowing coordinate).
        if area.is_nan() || area.abs() <= 1e-12 {
            continue;
        }
        let n_face = face_normal(mesh.positions, tri);
        let front_facing = dot(n_face, frame.toward_viewer) >= 0.0;
        let back_shade = normalised(scaled(n_face, -1.0))
            .map(|n| lambert(n) * BACK_FACE_DIM)
            .unwrap_or(AMBIENT * BACK_FACE_DIM);
        let xs = [a[0], b[0], c[0]];
        let ys = [a[1], b[1], c[1]];
        let x_lo = (min3(xs) - 0.5).floor().max(0.0);
        let x_hi = (max3(xs) - 0.5).ceil().min(w as f64 - 1.0);
        let y_lo = (min3(ys) - 0.5).floor().max(0.0);
        let y_hi = (max3(ys) - 0.5).ceil().min(h as f64 - 1.0);
        if !(x_lo <= x_hi && y_lo <= y_hi) {
            continue;
        }
        let cov = tri.map(|i| colouring.covered[i]);
        let t = tri.map(|i| colouring.t[i]);
        let shade = tri.map(|i| vertex_shade[i]);
        for y in y_lo as usize..=y_hi as usize {
            for x in x_lo as usize..=x_hi as usize {
                let p = [x as f64 + 0.5, y as f64 + 0.5, 0.0];
                let wa = edge(b, c, p) / area;
                let wb = edge(c, a, p) / area;
                let wc = 1.0 - wa - wb;
                if wa < 0.0 || wb < 0.0 || wc < 0.0 {
                    continue;
                }
                let z = wa * a[2] + wb * b[2] + wc * c[2];
                let k = y * w + x;
                if z <= depth[k] {
                    continue;
                }
                depth[k] = z;
                let bary = [wa as f32, wb as f32, wc as f32];
                let coverage = bary[0] * cov[0] + bary[1] * cov[1] + bary[2] * cov[2];
                let base = if coverage > 0.0 {
                    let tt = (bary[0] * cov[0] * t[0]
                        + bary[1] * cov[1] * t[1]
                        + bary[2] * cov[2] * t[2])
                        / coverage;
                    let hot = lut.get(tt);
                    std::array::from_fn(|ch| UNCOVERED[ch] * (1.0 - coverage) + hot[ch] * coverage)
                } else {
                    UNCOVERED
                };
                let s = if front_facing {
                    bary[0] * shade[0] + bary[1] * shade[1] + bary[2] * shade[2]
                } else {
                    back_shade
                };
                samples.pixels[k] = base.map(|v| v * s);
            }
        }
    }

    samples.resolve(canvas, rect.x0, layout.band);
}

/// The views' labels and the bar's caption, in the band above them.
fn draw_labels(canvas: &mut Canvas, layout: &Layout) {
    let band_mid = layout.band / 2;
    for (frame, rect) in layout.frames.iter().zip(&layout.views) {
        let x = rect.x0 + rect.width / 2;
        canvas.text(frame.label, x, band_mid, Anchor::Centre, layout.font);
    }
    let x = layout.panel_x0 + layout.panel_width / 2;
    canvas.text(UNIT_LABEL, x, band_mid, Anchor::Centre, layout.font);
}

/// Twice the signed area of (a, b, p) in the xy plane.
fn edge(a: [f64; 3], b: [f64; 3], p: [f64; 3]) -> f64 {
    (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
}

/// Unnormalised outward normal of a counter-clockwise triangle (length: twice its area).
fn face_normal(positions: &[[f64; 3]], [i, j, k]: [usize; 3]) -> [f64; 3] {
    cross(
        sub(positions[j], positions[i]),
        sub(positions[k], positions[i]),
    )
}

fn min3(v: [f64; 3]) -> f64 {
    v[0].min(v[1]).min(v[2])
}

fn max3(v: [f64; 3]) -> f64 {
    v[0].max(v[1]).max(v[2])
}

fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| a[i] + b[i])
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| a[i] - b[i])
}

fn scaled(a: [f64; 3], s: f64) -> [f64; 3] {
    a.map(|v| v * s)
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// `a` scaled to unit length, or `None` if it has none (zero or not finite).
fn normalised(a: [f64; 3]) -> Option<[f64; 3]> {
    let len = dot(a, a).sqrt();
    (len > 0.0 && len.is_finite()).then(|| scaled(a, 1.0 / len))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::base::colour::heat;
    use crate::draw::encode_png;

    const RADIUS_M: f64 = 0.05;
    const HEIGHT_M: f64 = 0.5;

    /// An open vertical cylinder, radius 5 cm, 0.5 m tall from y = 0, triangles counter-clockwise
    /// seen from outside.
    fn cylinder(segments: usize, rings: usize) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        let mut positions = Vec::new();
        for r in 0..=rings {
            let y = HEIGHT_M * r as f64 / rings as f64;
            for s in 0..segments {
                let a = std::f64::consts::TAU * s as f64 / segments as f64;
                positions.push([RADIUS_M * a.sin(), y, RADIUS_M * a.cos()]);
            }
        }
        let id = |r: usize, s: usize| (r * segments + s % segments) as u32;
        let mut triangles = Vec::new();
        for r in 0..rings {
            for s in 0..segments {
                // Angle grows from +Z towards +X: counter-clockwise seen from outside is
                // (r, s) → (r, s+1) → (r+1, s+1).
                triangles.push([id(r, s), id(r, s + 1), id(r + 1, s + 1)]);
                triangles.push([id(r, s), id(r + 1, s + 1), id(r + 1, s)]);
            }
        }
        (positions, triangles)
    }

    /// Density rising towards the bottom: 10 stitches/cm² at the top, 40 at the bottom.
    fn rising_density(positions: &[[f64; 3]]) -> Vec<f64> {
        positions
            .iter()
            .map(|p| 10.0 + 30.0 * (1.0 - p[1] / HEIGHT_M))
            .collect()
    }

    fn pixel_at(image: &RgbImage, xy: [f64; 2]) -> [u8; 3] {
        image.get_pixel(xy[0] as u32, xy[1] as u32).0
    }

    fn distance(a: [u8; 3], b: [u8; 3]) -> f64 {
        (0..3)
            .map(|c| (f64::from(a[c]) - f64::from(b[c])).powi(2))
            .sum::<f64>()
            .sqrt()
    }

    fn layout_for(
        positions: &[[f64; 3]],
        triangles: &[[u32; 3]],
        density: &[f64],
        style: &DensityPictureStyle,
    ) -> Layout {
        let mesh = PreparedMesh::new(positions, triangles);
        Layout::new(&mesh, &ColourScale::of(density), &Stance::default(), style)
    }

    #[test]
    fn denser_bottom_of_cylinder_draws_hotter_than_top_in_front_view() {
        let (positions, triangles) = cylinder(48, 40);
        let density = rising_density(&positions);
        let style = DensityPictureStyle::default();
        let image = draw_density(&positions, &triangles, &density, &Stance::default(), &style);
        let layout = layout_for(&positions, &triangles, &density, &style);
        let hot = heat(1.0).map(linear_to_srgb8);
        // The column facing the camera, 5 cm in from each end.
        let bottom = pixel_at(&image, layout.project_image(0, [0.0, 0.05, RADIUS_M]));
        let top = pixel_at(&image, layout.project_image(0, [0.0, 0.45, RADIUS_M]));
        assert!(
            distance(bottom, hot) < distance(top, hot),
            "bottom {bottom:?} should be nearer heat(1) {hot:?} than top {top:?}"
        );
        let background = BACKGROUND.map(linear_to_srgb8);
        assert_ne!(bottom, background);
        assert_ne!(top, background);
    }

    #[test]
    fn background_stays_plain_and_uncovered_skin_is_neutral_grey() {
        let (positions, triangles) = cylinder(48, 40);
        // Yarn on the lower half only.
        let density: Vec<f64> = positions
            .iter()
            .map(|p| if p[1] < 0.2 { 20.0 + p[1] } else { 0.0 })
            .collect();
        let style = DensityPictureStyle::default();
        let image = draw_density(&positions, &triangles, &density, &Stance::default(), &style);
        let layout = layout_for(&positions, &triangles, &density, &style);
        let background = BACKGROUND.map(linear_to_srgb8);
        for view in 0..2 {
            let rect = layout.views[view];
            for (x, y) in [
                (rect.x0 + 2, layout.band + 2),
                (rect.x0 + rect.width - 3, layout.band + layout.view_px - 3),
            ] {
                assert_eq!(image.get_pixel(x as u32, y as u32).0, background);
            }
            let skin = pixel_at(&image, layout.project_image(view, [0.0, 0.4, 0.0]));
            let grey = skin[0] == skin[1] && skin[1] == skin[2];
            assert!(grey, "uncovered skin should be grey, got {skin:?}");
            assert_ne!(skin, background);
        }
        let covered = pixel_at(&image, layout.project_image(0, [0.0, 0.05, RADIUS_M]));
        assert!(covered[0] != covered[1] || covered[1] != covered[2]);
    }

    #[test]
    fn colour_bar_runs_cold_at_the_bottom_to_hot_at_the_top() {
        let (positions, triangles) = cylinder(24, 10);
        let density = rising_density(&positions);
        let style = DensityPictureStyle::default();
        let image = draw_density(&positions, &triangles, &density, &Stance::default(), &style);
        let layout = layout_for(&positions, &triangles, &density, &style);
        let x = (layout.bar.x0 + layout.bar.width / 2) as u32;
        let samples = 9;
        let span = (layout.bar.bottom - 1 - layout.bar.top) as f64;
        for k in 0..samples {
            let t = k as f64 / (samples - 1) as f64;
            let y = layout.bar.top as f64 + (1.0 - t) * span;
            let got = image.get_pixel(x, y.round() as u32).0;
            let want = heat(t).map(linear_to_srgb8);
            assert!(
                distance(got, want) <= 6.0,
                "bar at t = {t}: got {got:?}, want {want:?}"
            );
        }
        // Ticks at round numbers within 10..40.
        let scale = ColourScale::of(&density);
        let values: Vec<f64> = scale.ticks.iter().map(|t| t.0).collect();
        assert_eq!(values, vec![10.0, 20.0, 30.0, 40.0]);
    }

    #[test]
    fn same_input_gives_same_png_bytes() {
        let (positions, triangles) = cylinder(32, 20);
        let density = rising_density(&positions);
        let style = DensityPictureStyle::default();
        let a = encode_png(
            &draw_density(&positions, &triangles, &density, &Stance::default(), &style),
            "density.png",
        )
        .unwrap();
        let b = encode_png(
            &draw_density(&positions, &triangles, &density, &Stance::default(), &style),
            "density.png",
        )
        .unwrap();
        assert_eq!(a, b);
    }

    #[test]
    fn bad_input_draws_a_picture_without_panicking() {
        let (positions, triangles) = cylinder(16, 8);
        let density = rising_density(&positions);
        let n = positions.len() as u32;
        let mut nan_positions = positions.clone();
        nan_positions[3] = [f64::NAN, 0.0, f64::INFINITY];
        let mut bad_triangles = triangles.clone();
        bad_triangles.extend([[0, 0, 0], [0, 1, n], [u32::MAX, 1, 2], [0, 16, 32]]);
        let mut bad_density = density.clone();
        bad_density[0] = f64::NAN;
        bad_density[1] = -3.0;
        bad_density[2] = f64::INFINITY;
        bad_density[5] = f64::NEG_INFINITY;
        let same = vec![12.0; positions.len()];
        let none = vec![0.0; positions.len()];
        let nan = vec![f64::NAN; positions.len()];
        let point = vec![[0.1, 0.2, 0.3]; 3];
        type Case<'a> = (&'a [[f64; 3]], &'a [[u32; 3]], &'a [f64]);
        let cases: Vec<Case> = vec![
            (&[], &[], &[]),
            (&positions, &[], &density),
            (&positions, &bad_triangles, &bad_density),
            (&nan_positions, &triangles, &density),
            (&positions, &triangles, &density[..10]),
            (&positions, &triangles, &same),
            (&positions, &triangles, &none),
            (&positions, &triangles, &nan),
            (&point, &[[0, 1, 2]], &[1.0, 2.0, 3.0]),
            (
                &[[1e300, 0.0, 0.0], [-1e300, 1e300, 0.0], [0.0, 0.0, 1e300]],
                &[[0, 1, 2]],
                &[1e300, 1e-300, 5.0],
            ),
        ];
        for style in [
            DensityPictureStyle::default(),
            DensityPictureStyle {
                view_px: 0,
                supersample: 0,
            },
            DensityPictureStyle {
                view_px: u32::MAX,
                supersample: u32::MAX,
            },
        ] {
            for (i, (p, t, d)) in cases.iter().enumerate() {
                if style.view_px == u32::MAX && i > 0 {
                    continue; // the largest size is slow; the empty mesh shows it clamps
                }
                let image = draw_density(p, t, d, &Stance::default(), &style);
                assert!(image.width() > 0 && image.height() > 0, "case {i}");
                assert!(encode_png(&image, "density.png").is_ok(), "case {i}");
            }
        }
    }

    #[test]
    fn nothing_covered_draws_grey_bar_and_grey_leg() {
        let (positions, triangles) = cylinder(24, 10);
        let density = vec![0.0; positions.len()];
        let style = DensityPictureStyle::default();
        let image = draw_density(&positions, &triangles, &density, &Stance::default(), &style);
        let layout = layout_for(&positions, &triangles, &density, &style);
        let x = (layout.bar.x0 + layout.bar.width / 2) as u32;
        let grey = UNCOVERED.map(linear_to_srgb8);
        for y in [layout.bar.top + 2, layout.bar.bottom - 3] {
            assert_eq!(image.get_pixel(x, y as u32).0, grey);
        }
        let skin = pixel_at(&image, layout.project_image(0, [0.0, 0.25, RADIUS_M]));
        assert!(skin[0] == skin[1] && skin[1] == skin[2], "{skin:?}");
    }

    /// A character turned in its file is drawn as it stands: an oval cylinder (twice as wide
    /// as deep, density rising with height and towards its front) turned 40° about up, drawn
    /// in the stance turned with it, gives the upright picture; drawn along the file's axes,
    /// another.
    #[test]
    fn a_turned_mesh_drawn_in_its_stance_gives_the_upright_picture() {
        let (cylinder, triangles) = cylinder(48, 20);
        let oval: Vec<[f64; 3]> = cylinder.iter().map(|p| [2.0 * p[0], p[1], p[2]]).collect();
        let density: Vec<f64> = oval
            .iter()
            .map(|p| 10.0 + 100.0 * p[2] + 30.0 * p[1])
            .collect();
        let turn = nalgebra::Rotation3::from_axis_angle(&nalgebra::Vector3::y_axis(), 0.7);
        let turned: Vec<[f64; 3]> = oval
            .iter()
            .map(|&p| (turn * nalgebra::Vector3::from(p)).into())
            .collect();
        let style = DensityPictureStyle {
            view_px: 160,
            supersample: 2,
        };
        let upright = draw_density(&oval, &triangles, &density, &Stance::default(), &style);
        let stance = Stance::new(nalgebra::Vector3::y(), turn * nalgebra::Vector3::z());
        let seen = draw_density(&turned, &triangles, &density, &stance, &style);
        assert_eq!(seen.dimensions(), upright.dimensions());
        let differing = |image: &RgbImage| {
            image
                .pixels()
                .zip(upright.pixels())
                .filter(|(a, b)| (0..3).any(|c| a[c].abs_diff(b[c]) > 8))
                .count()
        };
        assert!(differing(&seen) * 1000 < seen.len(), "{}", differing(&seen));
        let along_axes = draw_density(&turned, &triangles, &density, &Stance::default(), &style);
        assert!(
            along_axes.dimensions() != upright.dimensions()
                || differing(&along_axes) * 20 > along_axes.len(),
            "the file's axes draw the same picture"
        );
    }
}
