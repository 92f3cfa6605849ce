//! The stitch picture of relaxed patches, after Sakaguchi & Miyata Fig. 8/9: each patch drawn
//! flat as a stitch diagram, its yarn grid drawn as yarn, panels side by side at one common scale
//! so stitch sizes compare across panels.
//!
//! Every yarn segment is an anti-aliased capsule shaded like a cylinder seen from above (light on
//! the crest, dark at the flanks). Segments are drawn in passes: the grip under held edges, then
//! wale yarn, then course yarn over it, then a mark on every held point. Within a pass the
//! capsules are merged as one shape ([`LinearImage::strokes`]), so joints between the segments
//! of one yarn are seamless.
//!
//! Pure and deterministic: no randomness, no threads, the same bytes for the same input.

use image::RgbImage;

use super::canvas::{Canvas, Capsule, LinearImage, Rect};
use crate::base::{Direction, PerYarn, YarnGeometry};

/// One patch to draw.
#[derive(Clone, Copy, Debug)]
pub struct Panel<'a> {
    /// The patch's yarn geometry: positions in metres in the XY plane (x along the course, y
    /// along the wale; z is ignored). `offset_m` is ignored: each panel is centred on the
    /// bounding box of its own points.
    pub geometry: &'a YarnGeometry,
    /// Per point: true where the point is held (pinned). Shorter than `positions` means the
    /// missing points are free; extra entries are ignored.
    pub held: &'a [bool],
}

/// How the picture looks.
#[derive(Clone, Debug, PartialEq)]
pub struct PictureStyle {
    /// Side of each square panel, pixels (default: 480; at least 16 is used).
    pub panel_px: u32,
    /// Yarn radius per yarn kind ([`crate::base::YarnKind::index`]), metres (default: 0.03 mm
    /// nylon, 0.04 mm support, as the scene defaults). Drawn at least 1.2 px, and at most 30 % of
    /// the panel's median segment length so stitches stay open.
    pub yarn_radius_m: PerYarn<f64>,
    /// Linear-RGB yarn colour per yarn kind, each channel 0–1 (default: the scene defaults, a
    /// dark brown nylon and a dark blue-black support yarn).
    pub yarn_colour: PerYarn<[f64; 3]>,
}

impl Default for PictureStyle {
    fn default() -> Self {
        PictureStyle {
            panel_px: 480,
            yarn_radius_m: [0.000_03, 0.000_04, 0.000_03],
            yarn_colour: [[0.16, 0.11, 0.09], [0.08, 0.07, 0.10], [0.16, 0.11, 0.09]],
        }
    }
}

/// Linear-RGB background: a light warm grey, like paper.
const BACKGROUND: [f32; 3] = [0.80, 0.78, 0.74];
/// Linear-RGB colour of the grip drawn under held edges: a pale rust tint.
const GRIP: [f32; 3] = [0.86, 0.52, 0.40];
/// Linear-RGB colour of the square on each held point: a deep red, dark but not yarn-coloured.
const HELD_MARK: [f32; 3] = [0.50, 0.03, 0.02];
/// Smallest panel side, pixels.
const MIN_PANEL_PX: u32 = 16;
/// Empty border of each panel, as a fraction of its side.
const MARGIN: f64 = 0.06;
/// Thinnest yarn drawn from the style's radius, pixels (thinner would vanish or alias).
const MIN_RADIUS_PX: f64 = 1.2;
/// Thickest yarn drawn, as a fraction of the panel's median segment length, so stitches stay open.
/// Wins over [`MIN_RADIUS_PX`] on very dense panels, which then read as a tone.
const MAX_RADIUS_FRACTION: f64 = 0.3;
/// Thinnest yarn drawn at all, pixels: a one-pixel line.
const FLOOR_RADIUS_PX: f64 = 0.5;
/// Largest half-side of a held point's square, as a fraction of the median segment length.
const MARK_FRACTION: f64 = 0.4;
/// Grip half-width under held edges, as a fraction of the median segment length.
const GRIP_FRACTION: f64 = 0.22;

/// Draws `panels` side by side, left to right, each `style.panel_px` square; the image is
/// `panel_px × panels.len()` wide (one blank panel when `panels` is empty) and `panel_px` high.
///
/// One scale (metres per pixel) serves every panel: the largest panel's larger bounding-box side
/// fills the panel less its margin. Each panel is centred on its own bounding-box centre; the
/// patch's +y (along the wale) points up. Points with a non-finite coordinate, and segments that
/// touch them or name a point that does not exist, are skipped.
pub fn draw_patches(panels: &[Panel], style: &PictureStyle) -> RgbImage {
    let side = style.panel_px.max(MIN_PANEL_PX);
    let width = side.saturating_mul(panels.len().max(1) as u32);
    let mut canvas = LinearImage::new(width as usize, side as usize, 1, BACKGROUND);
    let bounds: Vec<Option<Bounds>> = panels.iter().map(|p| bounds(p.geometry)).collect();
    let extent_m = bounds
        .iter()
        .flatten()
        .map(|b| (b.hi[0] - b.lo[0]).max(b.hi[1] - b.lo[1]))
        .fold(0.0, f64::max);
    let px_per_m = if extent_m > 0.0 && extent_m.is_finite() {
        f64::from(side) * (1.0 - 2.0 * MARGIN) / extent_m
    } else {
        1.0
    };
    for (i, (panel, bounds)) in panels.iter().zip(&bounds).enumerate() {
        let Some(bounds) = bounds else {
            continue;
        };
        let rect = Rect {
            x0: i * side as usize,
            x1: (i + 1) * side as usize,
            y0: 0,
            y1: side as usize,
        };
        let centre_m = [
            (bounds.lo[0] + bounds.hi[0]) / 2.0,
            (bounds.lo[1] + bounds.hi[1]) / 2.0,
        ];
        let origin_px = [
            (rect.x0 + rect.x1) as f64 / 2.0,
            (rect.y0 + rect.y1) as f64 / 2.0,
        ];
        // Image y grows downwards; the patch's y grows upwards.
        let points_px: Vec<Option<[f64; 2]>> = panel
            .geometry
            .positions
            .iter()
            .map(|p| {
                p.iter().all(|c| c.is_finite()).then(|| {
                    [
                        origin_px[0] + (p[0] - centre_m[0]) * px_per_m,
                        origin_px[1] - (p[1] - centre_m[1]) * px_per_m,
                    ]
                })
            })
            .collect();
        draw_panel(&mut canvas, rect, panel, &points_px, style, px_per_m);
    }
    let mut picture = Canvas::new(width as usize, side as usize, [0; 3]);
    canvas.resolve(&mut picture, 0, 0);
    picture.into_image()
}

/// Draws one panel inside `rect`, from its points already in pixels (`None`: not drawable).
fn draw_panel(
    canvas: &mut LinearImage,
    rect: Rect,
    panel: &Panel,
    points_px: &[Option<[f64; 2]>],
    style: &PictureStyle,
    px_per_m: f64,
) {
    let point = |i: u32| points_px.get(i as usize).copied().flatten();
    let held = |i: u32| panel.held.get(i as usize).copied().unwrap_or(false);
    // Drawable segments with their ends in pixels.
    let segments: Vec<_> = panel
        .geometry
        .segments
        .iter()
        .filter_map(|s| Some((s, point(s.a)?, point(s.b)?)))
        .collect();
    let typical_px = median(
        segments
            .iter()
            .map(|(_, a, b)| (a[0] - b[0]).hypot(a[1] - b[1]))
            .filter(|l| *l > 0.0 && l.is_finite())
            .collect(),
    );
    let radius_px = style.yarn_radius_m.map(|r| {
        (r * px_per_m)
            .max(MIN_RADIUS_PX)
            .min(MAX_RADIUS_FRACTION * typical_px.unwrap_or(f64::INFINITY))
            .max(FLOOR_RADIUS_PX)
    });
    let colour = style.yarn_colour.map(|c| c.map(|v| v as f32));
    let thickest = radius_px[0].max(radius_px[1]);

    let grip_radius = typical_px.map_or(thickest * 2.0, |t| GRIP_FRACTION * t);
    let grip = segments
        .iter()
        .filter(|(s, _, _)| held(s.a) && held(s.b))
        .map(|&(_, a, b)| Capsule {
            a,
            b,
            radius: grip_radius,
            colour: GRIP,
            shaded: false,
        });
    canvas.strokes(rect, grip);
    for direction in [Direction::Wale, Direction::Course] {
        let yarn = segments
            .iter()
            .filter(|(s, _, _)| s.direction == direction)
            .map(|&(s, a, b)| {
                let kind = s.yarn.index() as usize;
                Capsule {
                    a,
                    b,
                    radius: radius_px[kind],
                    colour: colour[kind],
                    shaded: true,
                }
            });
        canvas.strokes(rect, yarn);
    }

    // Big enough to see next to the yarn, small enough not to fill a dense panel's stitches.
    let mark_half = (thickest + 1.0)
        .max(2.5)
        .min(MARK_FRACTION * typical_px.unwrap_or(f64::INFINITY))
        .max(1.0);
    for (i, p) in points_px.iter().enumerate() {
        if let (Some(p), true) = (p, held(i as u32)) {
            canvas.square(rect, *p, mark_half, HELD_MARK);
        }
    }
}

/// The median of `values`, or `None` when empty.
fn median(mut values: Vec<f64>) -> Option<f64> {
    values.sort_by(f64::total_cmp);
    values.get(values.len() / 2).copied()
}

/// An axis-aligned box in metres.
#[derive(Clone, Copy, Debug)]
struct Bounds {
    lo: [f64; 2],
    hi: [f64; 2],
}

/// XY bounds of the finite positions, or `None` when there are none.
fn bounds(g: &YarnGeometry) -> Option<Bounds> {
    g.positions
        .iter()
        .filter(|p| p.iter().all(|c| c.is_finite()))
        .fold(None, |acc: Option<Bounds>, p| {
            let b = acc.unwrap_or(Bounds {
                lo: [p[0], p[1]],
                hi: [p[0], p[1]],
            });
            Some(Bounds {
                lo: [b.lo[0].min(p[0]), b.lo[1].min(p[1])],
                hi: [b.hi[0].max(p[0]), b.hi[1].max(p[1])],
            })
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::base::colour::linear_to_srgb8;
    use crate::base::{Segment, YarnKind};
    use std::collections::BTreeMap;

    fn geometry(positions: Vec<[f64; 3]>, segments: Vec<Segment>) -> YarnGeometry {
        YarnGeometry {
            name: "t".into(),
            offset_m: [0.0; 3],
            positions,
            point_attributes: BTreeMap::new(),
            segments,
        }
    }

    fn segment(a: u32, b: u32, yarn: YarnKind, direction: Direction) -> Segment {
        Segment {
            a,
            b,
            yarn,
            direction,
        }
    }

    /// A polyline of nylon course segments through `positions`.
    fn line(positions: Vec<[f64; 3]>) -> YarnGeometry {
        let segments = (1..positions.len() as u32)
            .map(|b| segment(b - 1, b, YarnKind::Nylon, Direction::Course))
            .collect();
        geometry(positions, segments)
    }

    fn style(panel_px: u32) -> PictureStyle {
        PictureStyle {
            panel_px,
            yarn_radius_m: [0.000_1; 3],
            yarn_colour: [[0.9, 0.05, 0.05], [0.05, 0.05, 0.9], [0.9, 0.05, 0.05]],
        }
    }

    fn draw_one(g: &YarnGeometry, held: &[bool], style: &PictureStyle) -> RgbImage {
        draw_patches(&[Panel { geometry: g, held }], style)
    }

    fn background_srgb() -> image::Rgb<u8> {
        image::Rgb(BACKGROUND.map(linear_to_srgb8))
    }

    #[test]
    fn yarn_covers_pixels_under_it_and_leaves_the_background_elsewhere() {
        let g = line(vec![[-0.001, 0.0, 0.0], [0.001, 0.0, 0.0]]);
        let img = draw_one(&g, &[false, false], &style(100));
        let yarn = img.get_pixel(50, 50);
        assert!(
            yarn[0] > 150 && yarn[1] < 100 && yarn[2] < 100,
            "pixel on the yarn is not the (red) yarn colour: {yarn:?}"
        );
        assert_eq!(*img.get_pixel(50, 5), background_srgb());
        assert_eq!(*img.get_pixel(50, 95), background_srgb());
    }

    #[test]
    fn course_yarn_is_drawn_over_wale_yarn() {
        let g = geometry(
            vec![
                [-0.001, 0.0, 0.0],
                [0.001, 0.0, 0.0],
                [0.0, -0.001, 0.0],
                [0.0, 0.001, 0.0],
            ],
            // Course listed first, so only the pass order can put it on top.
            vec![
                segment(0, 1, YarnKind::Nylon, Direction::Course),
                segment(2, 3, YarnKind::Support, Direction::Wale),
            ],
        );
        let img = draw_one(&g, &[], &style(100));
        let crossing = img.get_pixel(50, 50);
        assert!(crossing[0] > crossing[2], "{crossing:?}");
        let wale = img.get_pixel(50, 20);
        assert!(wale[2] > wale[0], "{wale:?}");
    }

    #[test]
    fn panels_sit_side_by_side_and_share_one_scale() {
        let long = line(vec![[0.0; 3], [0.002, 0.0, 0.0]]);
        let short = line(vec![[0.0; 3], [0.001, 0.0, 0.0]]);
        let img = draw_patches(
            &[
                Panel {
                    geometry: &long,
                    held: &[],
                },
                Panel {
                    geometry: &short,
                    held: &[],
                },
            ],
            &style(100),
        );
        assert_eq!(img.dimensions(), (200, 100));
        let yarn_px = |x0: u32| {
            (x0..x0 + 100)
                .filter(|&x| *img.get_pixel(x, 50) != background_srgb())
                .count() as f64
        };
        let ratio = yarn_px(100) / yarn_px(0);
        assert!((ratio - 0.5).abs() < 0.1, "short/long drawn length {ratio}");
    }

    #[test]
    fn held_points_are_marked() {
        let g = line(vec![[-0.001, 0.0, 0.0], [0.0, 0.0, 0.0], [0.001, 0.0, 0.0]]);
        let img = draw_one(&g, &[true, false, false], &style(100));
        let mark = image::Rgb(HELD_MARK.map(linear_to_srgb8));
        // The left end sits at the margin: 6 % of 100 px.
        assert_eq!(*img.get_pixel(6, 50), mark);
        assert_ne!(*img.get_pixel(50, 50), mark);
    }

    #[test]
    fn dense_patches_keep_their_stitches_open() {
        // 40 × 40 grid in a 100 px panel: 2.2 px per stitch, much less than the 0.1 mm yarn.
        let n = 40u32;
        let positions = (0..n * n)
            .map(|i| [f64::from(i % n) * 1e-3, f64::from(i / n) * 1e-3, 0.0])
            .collect();
        let segments = (0..n * n)
            .filter(|i| i % n + 1 < n)
            .map(|i| segment(i, i + 1, YarnKind::Nylon, Direction::Course))
            .collect();
        let img = draw_one(&geometry(positions, segments), &[], &style(100));
        let column: Vec<_> = (30..70).map(|y| img.get_pixel(50, y)[0]).collect();
        let (lo, hi) = (column.iter().min().unwrap(), column.iter().max().unwrap());
        assert!(hi - lo > 40, "courses merged into a block: {column:?}");
    }

    #[test]
    fn output_bytes_are_deterministic() {
        let g = line(vec![[0.0; 3], [0.001, 0.0005, 0.0], [0.002, 0.0, 0.0]]);
        let held = [true, false, true];
        let draw = || {
            let panel = Panel {
                geometry: &g,
                held: &held,
            };
            crate::draw::encode_png(
                &draw_patches(&[panel, panel], &PictureStyle::default()),
                "patch.png",
            )
            .unwrap()
        };
        let bytes = draw();
        assert_eq!(&bytes[1..4], b"PNG");
        assert_eq!(bytes, draw());
    }

    #[test]
    fn degenerate_geometry_does_not_panic() {
        let nan = f64::NAN;
        let cases = [
            line(vec![]),
            line(vec![[0.0; 3]]),
            line(vec![[0.0; 3], [0.0; 3]]),
            line(vec![[0.0; 3], [0.0; 3], [0.001, 0.0, 0.0]]),
            line(vec![[nan, 0.0, 0.0], [0.001, 0.0, 0.0], [0.0, 0.001, 0.0]]),
            line(vec![[f64::INFINITY, 0.0, 0.0], [0.0, nan, 0.0]]),
            line(vec![[1e300, 0.0, 0.0], [-1e300, 0.0, 0.0]]),
            geometry(
                vec![[0.0; 3]],
                vec![segment(0, 7, YarnKind::Support, Direction::Wale)],
            ),
        ];
        let bad_style = PictureStyle {
            panel_px: 0,
            yarn_radius_m: [nan, f64::INFINITY, nan],
            ..PictureStyle::default()
        };
        for g in &cases {
            for held in [vec![], vec![true; 5]] {
                for style in [&PictureStyle::default(), &bad_style] {
                    let img = draw_one(g, &held, style);
                    assert!(img.width() > 0 && img.height() > 0);
                }
            }
        }
        let img = draw_patches(&[], &PictureStyle::default());
        assert_eq!(img.dimensions(), (480, 480));
        assert!(img.pixels().all(|p| *p == background_srgb()));
    }
}
