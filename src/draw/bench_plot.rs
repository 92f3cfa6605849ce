//! `bench.png`: accuracy against time, log–log, one curve per solver and grid (the points of a
//! curve are its tolerances). Drawn with the picture layer of [`super::canvas`]: the grid and
//! curves as anti-aliased strokes in linear light, then axes, labels and legend in crisp pixels.

use super::canvas::{Anchor, Canvas, Capsule, Font, LinearImage, Rect, INK};
use crate::base::colour::srgb_to_linear;
use crate::error::Result;

/// Picture size, pixels.
const SIZE: (usize, usize) = (1100, 760);
/// Plot area inside the picture: left, right, top, bottom edges, pixels.
const PLOT: Rect = Rect {
    x0: 110,
    x1: 1070,
    y0: 60,
    y1: 690,
};
/// Errors below this are drawn at it (a log axis has no zero).
const ERROR_FLOOR: f64 = 1e-7;
/// Curve colours, sRGB (Tableau 10): distinct in print and for most colour-blind readers.
const PALETTE: [[u8; 3]; 10] = [
    [31, 119, 180],
    [255, 127, 14],
    [44, 160, 44],
    [214, 39, 40],
    [148, 103, 189],
    [140, 86, 75],
    [227, 119, 194],
    [127, 127, 127],
    [188, 189, 34],
    [23, 190, 207],
];
/// sRGB of the grid lines.
const GRID: [u8; 3] = [225, 225, 225];
const WHITE: [u8; 3] = [255, 255, 255];

/// One curve: a solver on one leg and grid, its points `(seconds, density error)`.
#[derive(Clone, Debug, PartialEq)]
pub struct Curve {
    /// Legend text.
    pub label: String,
    /// The paper's solver (drawn thinner, with hollow markers).
    pub paper: bool,
    /// `(seconds, relative density error)`, in tolerance order.
    pub points: Vec<(f64, f64)>,
}

/// Draws the curves and encodes the PNG for the file `file_name`.
///
/// Errors: [`crate::Error::Encode`] naming `file_name` when encoding fails.
pub fn draw(curves: &[Curve], file_name: &str) -> Result<Vec<u8>> {
    let mut canvas = Canvas::new(SIZE.0, SIZE.1, WHITE);
    let axes = Axes::fitting(curves);
    let mut strokes = LinearImage::new(SIZE.0, SIZE.1, 1, linear(WHITE));
    let grid = |a: [f64; 2], b: [f64; 2]| Capsule {
        a,
        b,
        radius: 0.5,
        colour: linear(GRID),
        shaded: false,
    };
    let decades_x = axes.x.decades();
    let decades_y = axes.y.decades();
    strokes.strokes(
        PLOT,
        decades_x
            .iter()
            .map(|&v| {
                let x = axes.x.to_px(v);
                grid([x, PLOT.y0 as f64], [x, PLOT.y1 as f64])
            })
            .chain(decades_y.iter().map(|&v| {
                let y = axes.y.to_px(v);
                grid([PLOT.x0 as f64, y], [PLOT.x1 as f64, y])
            })),
    );
    for (i, curve) in curves.iter().enumerate() {
        let colour = linear(PALETTE[i % PALETTE.len()]);
        let points: Vec<[f64; 2]> = curve
            .points
            .iter()
            .map(|&(t, e)| [axes.x.to_px(t), axes.y.to_px(e.max(ERROR_FLOOR))])
            .filter(|p| p.iter().all(|c| c.is_finite()))
            .collect();
        let width = if curve.paper { 0.75 } else { 1.5 };
        let stroke = |a: [f64; 2], b: [f64; 2], radius: f64, colour: [f32; 3]| Capsule {
            a,
            b,
            radius,
            colour,
            shaded: false,
        };
        strokes.strokes(
            PLOT,
            points.windows(2).map(|w| stroke(w[0], w[1], width, colour)),
        );
        strokes.strokes(PLOT, points.iter().map(|&p| stroke(p, p, 5.0, colour)));
        if curve.paper {
            strokes.strokes(
                PLOT,
                points.iter().map(|&p| stroke(p, p, 3.0, linear(WHITE))),
            );
        }
    }
    strokes.resolve(&mut canvas, 0, 0);

    let font = Font::for_height(SIZE.1);
    let small = Font::for_height(400);
    canvas.outline(PLOT.x0, PLOT.x1, PLOT.y0, PLOT.y1);
    for &v in &decades_x {
        let x = axes.x.to_px(v).round() as usize;
        canvas.fill_rect(x, x + 1, PLOT.y1, PLOT.y1 + 6, INK);
        canvas.text(&format!("{v:.2}"), x, PLOT.y1 + 18, Anchor::Centre, small);
    }
    for &v in &decades_y {
        let y = axes.y.to_px(v).round() as usize;
        canvas.fill_rect(PLOT.x0 - 6, PLOT.x0, y, y + 1, INK);
        let label = format!("{v:.0e}");
        let x = PLOT.x0 - 10 - small.text_width(&label);
        canvas.text(&label, x, y, Anchor::Left, small);
    }
    let centre = (PLOT.x0 + PLOT.x1) / 2;
    canvas.text(
        "knitfit bench: accuracy against solve time",
        centre,
        20,
        Anchor::Centre,
        font,
    );
    canvas.text(
        "stitch-density error vs reference (log)",
        PLOT.x0,
        PLOT.y0 - 14,
        Anchor::Left,
        small,
    );
    canvas.text(
        "solve time, seconds (log)",
        centre,
        PLOT.y1 + 48,
        Anchor::Centre,
        small,
    );
    legend(&mut canvas, curves, small);
    super::encode_png(&canvas.into_image(), file_name)
}

/// The legend, in the plot's upper right corner: a line and marker per curve, and its label.
fn legend(canvas: &mut Canvas, curves: &[Curve], font: Font) {
    if curves.is_empty() {
        return;
    }
    let line_h = font.char_height() + 6;
    let label_w = curves
        .iter()
        .map(|c| font.text_width(&c.label))
        .max()
        .unwrap_or(0);
    let (w, h) = (label_w + 56, curves.len() * line_h + 10);
    let (x0, y0) = (PLOT.x1 - w - 10, PLOT.y0 + 10);
    canvas.fill_rect(x0, x0 + w, y0, y0 + h, WHITE);
    canvas.outline(x0, x0 + w, y0, y0 + h);
    for (i, curve) in curves.iter().enumerate() {
        let colour = PALETTE[i % PALETTE.len()];
        let y = y0 + 5 + i * line_h + line_h / 2;
        let thickness = if curve.paper { 1 } else { 3 };
        canvas.fill_rect(
            x0 + 8,
            x0 + 40,
            y - thickness / 2,
            y - thickness / 2 + thickness,
            colour,
        );
        canvas.fill_rect(x0 + 20, x0 + 28, y - 4, y + 4, colour);
        if curve.paper {
            canvas.fill_rect(x0 + 22, x0 + 26, y - 2, y + 2, WHITE);
        }
        canvas.text(&curve.label, x0 + 48, y, Anchor::Left, font);
    }
}

/// A logarithmic axis from `lo` to `hi` onto pixels `from` to `to`.
#[derive(Clone, Copy, Debug)]
struct LogAxis {
    lo: f64,
    hi: f64,
    from: f64,
    to: f64,
}

impl LogAxis {
    /// Pixel coordinate of `v`.
    fn to_px(self, v: f64) -> f64 {
        let t = (v.log10() - self.lo.log10()) / (self.hi.log10() - self.lo.log10());
        self.from + t * (self.to - self.from)
    }

    /// The powers of ten within the axis (and the ends, when it spans less than two decades).
    fn decades(self) -> Vec<f64> {
        let first = self.lo.log10().ceil() as i32;
        let last = self.hi.log10().floor() as i32;
        let mut out: Vec<f64> = (first..=last).map(|e| 10f64.powi(e)).collect();
        if out.len() < 2 {
            out = vec![self.lo, self.hi];
        }
        out
    }
}

/// The two axes of the plot.
struct Axes {
    x: LogAxis,
    y: LogAxis,
}

impl Axes {
    /// Axes spanning every curve's points, with a margin (fixed ones when there are none).
    fn fitting(curves: &[Curve]) -> Axes {
        let (mut t_lo, mut t_hi, mut e_lo, mut e_hi) =
            (f64::INFINITY, 0.0f64, f64::INFINITY, 0.0f64);
        for &(t, e) in curves.iter().flat_map(|c| c.points.iter()) {
            if t > 0.0 && t.is_finite() && e.is_finite() {
                t_lo = t_lo.min(t);
                t_hi = t_hi.max(t);
                e_lo = e_lo.min(e.max(ERROR_FLOOR));
                e_hi = e_hi.max(e.max(ERROR_FLOOR));
            }
        }
        if !(t_lo.is_finite() && e_lo.is_finite()) {
            (t_lo, t_hi, e_lo, e_hi) = (0.01, 1.0, ERROR_FLOOR, 1.0);
        }
        Axes {
            x: LogAxis {
                lo: t_lo / 1.5,
                hi: t_hi * 1.5,
                from: PLOT.x0 as f64,
                to: PLOT.x1 as f64,
            },
            y: LogAxis {
                lo: e_lo / 2.0,
                hi: e_hi * 2.0,
                from: PLOT.y1 as f64,
                to: PLOT.y0 as f64,
            },
        }
    }
}

/// An sRGB colour in linear light.
fn linear(srgb: [u8; 3]) -> [f32; 3] {
    srgb.map(|c| srgb_to_linear(f32::from(c) / 255.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::base::colour::linear_to_srgb8;

    #[test]
    fn the_plot_is_a_png_of_its_size_with_its_curves_drawn() {
        let curves = vec![
            Curve {
                label: "paper 50x50".into(),
                paper: true,
                points: vec![(1.0, 1e-2), (2.0, 1e-3), (4.0, 0.0)],
            },
            Curve {
                label: "multilevel 50x50".into(),
                paper: false,
                points: vec![(0.05, 1e-2), (0.1, 1e-3)],
            },
        ];
        let png = draw(&curves, "bench.png").unwrap();
        let image = image::load_from_memory(&png).unwrap().to_rgb8();
        assert_eq!(image.dimensions(), (SIZE.0 as u32, SIZE.1 as u32));
        let ink = image.pixels().filter(|p| p.0 != WHITE).count();
        assert!(ink > 5000, "only {ink} non-white pixels");
        // The second curve's first point is drawn in its colour.
        let axes = Axes::fitting(&curves);
        let (x, y) = (axes.x.to_px(0.05), axes.y.to_px(1e-2));
        assert_eq!(image.get_pixel(x as u32, y as u32).0, PALETTE[1]);
    }

    #[test]
    fn no_curves_and_bad_points_still_draw() {
        for curves in [
            vec![],
            vec![Curve {
                label: "nan".into(),
                paper: false,
                points: vec![(f64::NAN, 1.0), (0.0, f64::INFINITY), (-1.0, -1.0)],
            }],
        ] {
            assert!(draw(&curves, "bench.png").is_ok());
        }
    }

    #[test]
    fn colours_round_trip_through_linear_light() {
        for c in PALETTE {
            assert_eq!(linear(c).map(linear_to_srgb8), c);
        }
    }
}
