//! The stitch picture of relaxed patches (Sakaguchi & Miyata Fig. 8/9): each patch drawn flat,
//! yarn by yarn, panels side by side at one common scale so stitch sizes compare across panels.
//!
//! Each yarn segment is an anti-aliased capsule shaded like a cylinder seen from above; course
//! yarn is drawn over wale yarn; held points are marked. Pure and deterministic.

use image::{ImageEncoder, RgbImage};

use super::colormap::linear_to_srgb8;
use crate::error::{Error, Result};
use crate::export::YarnGeometry;
use crate::knit::Direction;

/// One patch to draw.
pub struct Panel<'a> {
    /// The patch's yarn geometry (positions in the XY plane; `offset_m` is ignored).
    pub geometry: &'a YarnGeometry,
    /// Per point: true where the point is held (pinned).
    pub held: &'a [bool],
}

/// How the picture looks.
#[derive(Clone, Debug, PartialEq)]
pub struct PictureStyle {
    /// Side of each square panel, pixels (default: 480).
    pub panel_px: u32,
    /// Yarn radius per yarn kind (`YarnKind::index()`), metres (default: 0.03 / 0.04 mm).
    pub yarn_radius_m: [f64; 2],
    /// Linear-RGB yarn colour per yarn kind, 0–1.
    pub yarn_colour: [[f64; 3]; 2],
}

impl Default for PictureStyle {
    fn default() -> Self {
        PictureStyle {
            panel_px: 480,
            yarn_radius_m: [0.00003, 0.00004],
            yarn_colour: [[0.16, 0.11, 0.09], [0.08, 0.07, 0.10]],
        }
    }
}

/// Linear-RGB background.
const BACKGROUND: [f32; 3] = [0.80, 0.78, 0.74];
/// Linear-RGB colour of held-point marks.
const HELD_MARK: [f32; 3] = [0.55, 0.05, 0.03];
/// Empty border of each panel, as a fraction of its side.
const MARGIN: f64 = 0.06;
/// Thinnest yarn drawn, pixels (thinner would vanish or alias).
const MIN_RADIUS_PX: f64 = 1.2;
/// Thickest yarn drawn, as a fraction of the mean segment length, so stitches stay open.
const MAX_RADIUS_FRACTION: f64 = 0.3;

/// Draws `panels` side by side.
pub fn draw_patches(panels: &[Panel], style: &PictureStyle) -> RgbImage {
    let side = style.panel_px.max(16);
    let width = side * panels.len().max(1) as u32;
    let mut canvas = Canvas {
        width: width as usize,
        height: side as usize,
        pixels: vec![BACKGROUND; width as usize * side as usize],
    };
    let extent = panels
        .iter()
        .filter_map(|p| bounds(p.geometry))
        .map(|(lo, hi)| (hi[0] - lo[0]).max(hi[1] - lo[1]))
        .fold(0.0, f64::max);
    let px_per_m = if extent > 0.0 {
        side as f64 * (1.0 - 2.0 * MARGIN) / extent
    } else {
        1.0
    };
    for (i, panel) in panels.iter().enumerate() {
        let Some((lo, hi)) = bounds(panel.geometry) else {
            continue;
        };
        let centre = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0];
        let origin = [(i as f64 + 0.5) * side as f64, side as f64 / 2.0];
        // Image y grows downwards; the patch's y (along the wale) grows upwards.
        let to_px = |p: &[f64; 3]| {
            [
                origin[0] + (p[0] - centre[0]) * px_per_m,
                origin[1] - (p[1] - centre[1]) * px_per_m,
            ]
        };
        draw_panel(&mut canvas, panel, style, px_per_m, &to_px);
    }
    canvas.to_srgb()
}

fn draw_panel(
    canvas: &mut Canvas,
    panel: &Panel,
    style: &PictureStyle,
    px_per_m: f64,
    to_px: &dyn Fn(&[f64; 3]) -> [f64; 2],
) {
    let g = panel.geometry;
    let lengths: Vec<f64> = g
        .segments
        .iter()
        .map(|s| {
            let (a, b) = (
                to_px(&g.positions[s.a as usize]),
                to_px(&g.positions[s.b as usize]),
            );
            (a[0] - b[0]).hypot(a[1] - b[1])
        })
        .filter(|l| l.is_finite())
        .collect();
    let mean_length = lengths.iter().sum::<f64>() / lengths.len().max(1) as f64;
    // Wale yarn first, course yarn over it.
    for direction in [Direction::Wale, Direction::Course] {
        for s in g.segments.iter().filter(|s| s.direction == direction) {
            let kind = s.yarn.index() as usize;
            let radius = (style.yarn_radius_m[kind] * px_per_m)
                .max(MIN_RADIUS_PX)
                .min((MAX_RADIUS_FRACTION * mean_length).max(MIN_RADIUS_PX));
            let colour = style.yarn_colour[kind].map(|c| c as f32);
            let (a, b) = (
                to_px(&g.positions[s.a as usize]),
                to_px(&g.positions[s.b as usize]),
            );
            canvas.capsule(a, b, radius, colour);
        }
    }
    for (p, _) in g.positions.iter().zip(panel.held).filter(|(_, &held)| held) {
        canvas.square(to_px(p), 2.5, HELD_MARK);
    }
}

/// XY bounds of the finite positions, or `None` when there are none.
fn bounds(g: &YarnGeometry) -> Option<([f64; 2], [f64; 2])> {
    let finite = g
        .positions
        .iter()
        .filter(|p| p.iter().all(|c| c.is_finite()));
    finite.fold(None, |acc, p| {
        let (lo, hi) = acc.unwrap_or(([p[0], p[1]], [p[0], p[1]]));
        Some((
            [lo[0].min(p[0]), lo[1].min(p[1])],
            [hi[0].max(p[0]), hi[1].max(p[1])],
        ))
    })
}

/// A linear-RGB float image.
struct Canvas {
    width: usize,
    height: usize,
    pixels: Vec<[f32; 3]>,
}

impl Canvas {
    fn blend(&mut self, x: usize, y: usize, colour: [f32; 3], alpha: f32) {
        let p = &mut self.pixels[y * self.width + x];
        for k in 0..3 {
            p[k] += (colour[k] - p[k]) * alpha;
        }
    }

    /// Pixel ranges covering `[lo, hi]`, clipped to the image; `None` if off-image or not finite.
    fn span(
        &self,
        lo: [f64; 2],
        hi: [f64; 2],
    ) -> Option<(std::ops::Range<usize>, std::ops::Range<usize>)> {
        if !(lo.iter().chain(&hi).all(|c| c.is_finite())) {
            return None;
        }
        let clip = |v: f64, n: usize| v.clamp(0.0, n as f64) as usize;
        let xs = clip(lo[0].floor(), self.width)..clip(hi[0].ceil() + 1.0, self.width);
        let ys = clip(lo[1].floor(), self.height)..clip(hi[1].ceil() + 1.0, self.height);
        (!xs.is_empty() && !ys.is_empty()).then_some((xs, ys))
    }

    /// An anti-aliased capsule from `a` to `b`, shaded as a cylinder lit from above-left.
    fn capsule(&mut self, a: [f64; 2], b: [f64; 2], radius: f64, colour: [f32; 3]) {
        let pad = radius + 1.0;
        let lo = [a[0].min(b[0]) - pad, a[1].min(b[1]) - pad];
        let hi = [a[0].max(b[0]) + pad, a[1].max(b[1]) + pad];
        let Some((xs, ys)) = self.span(lo, hi) else {
            return;
        };
        let ab = [b[0] - a[0], b[1] - a[1]];
        let len_sq = ab[0] * ab[0] + ab[1] * ab[1];
        for y in ys {
            for x in xs.clone() {
                let p = [x as f64 + 0.5 - a[0], y as f64 + 0.5 - a[1]];
                let t = if len_sq > 0.0 {
                    ((p[0] * ab[0] + p[1] * ab[1]) / len_sq).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                let d = [p[0] - t * ab[0], p[1] - t * ab[1]];
                let dist = d[0].hypot(d[1]);
                let coverage = (radius + 0.5 - dist).clamp(0.0, 1.0) as f32;
                if coverage <= 0.0 {
                    continue;
                }
                // Height of a unit cylinder across its width: bright on the crest, dark at the
                // flanks, plus a narrow sheen on the crest.
                let across = (dist / radius).min(1.0);
                let crest = (1.0 - across * across).sqrt() as f32;
                let shade = 0.45 + 0.75 * crest;
                let sheen = 0.35 * crest.powi(8);
                let shaded = colour.map(|c| c * shade + sheen);
                self.blend(x, y, shaded, coverage);
            }
        }
    }

    /// A filled square of half-size `half` centred on `c`.
    fn square(&mut self, c: [f64; 2], half: f64, colour: [f32; 3]) {
        let Some((xs, ys)) = self.span(
            [c[0] - half, c[1] - half],
            [c[0] + half - 1.0, c[1] + half - 1.0],
        ) else {
            return;
        };
        for y in ys {
            for x in xs.clone() {
                self.blend(x, y, colour, 1.0);
            }
        }
    }

    fn to_srgb(&self) -> RgbImage {
        RgbImage::from_fn(self.width as u32, self.height as u32, |x, y| {
            image::Rgb(self.pixels[y as usize * self.width + x as usize].map(linear_to_srgb8))
        })
    }
}

/// Encodes an image as PNG bytes.
pub fn encode_png(image: &RgbImage) -> Result<Vec<u8>> {
    let mut bytes = Vec::new();
    image::codecs::png::PngEncoder::new(&mut bytes)
        .write_image(
            image.as_raw(),
            image.width(),
            image.height(),
            image::ExtendedColorType::Rgb8,
        )
        .map_err(|e| Error::Encode {
            what: "PNG".into(),
            message: e.to_string(),
        })?;
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::export::Segment;
    use crate::knit::YarnKind;
    use std::collections::BTreeMap;

    fn line(positions: Vec<[f64; 3]>) -> YarnGeometry {
        YarnGeometry {
            name: "t".into(),
            offset_m: [0.0; 3],
            segments: (1..positions.len() as u32)
                .map(|b| Segment {
                    a: b - 1,
                    b,
                    yarn: YarnKind::Nylon,
                    direction: Direction::Course,
                })
                .collect(),
            positions,
            point_attributes: BTreeMap::new(),
        }
    }

    #[test]
    fn yarn_covers_pixels_under_it_and_leaves_the_background_elsewhere() {
        let g = line(vec![[-0.001, 0.0, 0.0], [0.001, 0.0, 0.0]]);
        let held = [false, false];
        let style = PictureStyle {
            panel_px: 100,
            ..PictureStyle::default()
        };
        let img = draw_patches(
            &[Panel {
                geometry: &g,
                held: &held,
            }],
            &style,
        );
        let background = img.get_pixel(50, 5);
        let yarn = img.get_pixel(50, 50);
        assert!(yarn[0] < background[0] - 40, "{yarn:?} vs {background:?}");
    }

    #[test]
    fn panels_sit_side_by_side() {
        let g = line(vec![[0.0; 3], [0.001, 0.0, 0.0]]);
        let held = [true, false];
        let panel = || Panel {
            geometry: &g,
            held: &held,
        };
        let style = PictureStyle {
            panel_px: 64,
            ..PictureStyle::default()
        };
        let img = draw_patches(&[panel(), panel()], &style);
        assert_eq!(img.dimensions(), (128, 64));
        assert_eq!(
            encode_png(&img).unwrap(),
            encode_png(&draw_patches(&[panel(), panel()], &style)).unwrap()
        );
    }

    #[test]
    fn degenerate_geometry_does_not_panic() {
        for positions in [
            vec![],
            vec![[0.0; 3]],
            vec![[0.0; 3], [0.0; 3]],
            vec![[f64::NAN, 0.0, 0.0], [1.0, 0.0, 0.0]],
        ] {
            let g = line(positions);
            let held = vec![true; g.positions.len()];
            draw_patches(
                &[Panel {
                    geometry: &g,
                    held: &held,
                }],
                &PictureStyle::default(),
            );
        }
    }
}
