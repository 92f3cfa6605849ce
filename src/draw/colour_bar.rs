//! The colour bar of the density pictures (paper Fig. 18): the heat map from the lowest covered
//! stitch density (bottom) to the highest (top), 4–6 ticks at round numbers, and a grey swatch
//! for skin without yarn, so "no stocking here" never reads as "very sparse stocking". One bar
//! for `density.png` and the preview's density mode: the same map, ticks and font in both.

use image::RgbImage;

use super::canvas::{Anchor, Canvas, Font, INK};
use crate::base::colour::{heat, linear_to_srgb8};

/// The caption of the colour bar.
pub const UNIT_LABEL: &str = "stitches/cm²";
/// The label for skin without yarn (the grey swatch, or the whole bar when nothing is covered).
pub const NO_YARN_LABEL: &str = "no yarn";
/// Linear-RGB colour of skin without yarn, before shading: a neutral mid grey.
pub const UNCOVERED: [f32; 3] = [0.30, 0.30, 0.30];
/// Half-width of the colour range used when every covered vertex has the same density, as a
/// fraction of that density.
const FLAT_RANGE_FRACTION: f64 = 0.05;
/// Entries in the colour look-up table.
const LUT_SIZE: usize = 1024;

/// The density range the colours span, and the bar's ticks.
#[derive(Clone, Debug, PartialEq)]
pub struct ColourScale {
    /// Density at the bottom and top of the bar, or `None` when no vertex is covered.
    pub range: Option<(f64, f64)>,
    /// Tick values and their labels, ascending.
    pub ticks: Vec<(f64, String)>,
}

impl ColourScale {
    /// The scale of these densities (stitches per cm²; 0, negative or not finite is no yarn).
    pub fn of(density: &[f64]) -> Self {
        let covered = density.iter().copied().filter(|&d| is_covered(d));
        ColourScale::spanning(covered.fold(None, |acc: Option<(f64, f64)>, d| match acc {
            None => Some((d, d)),
            Some((lo, hi)) => Some((lo.min(d), hi.max(d))),
        }))
    }

    /// The scale over `range`; a range of a single value is widened by ±5 % so it still draws
    /// mid-map.
    pub fn spanning(range: Option<(f64, f64)>) -> Self {
        let range = range.map(|(lo, hi)| {
            if hi - lo > 1e-9 * hi {
                (lo, hi)
            } else {
                let half = FLAT_RANGE_FRACTION * hi;
                (hi - half, hi + half)
            }
        });
        let ticks = range.map(|(lo, hi)| nice_ticks(lo, hi)).unwrap_or_default();
        ColourScale { range, ticks }
    }

    /// Where `d` falls on the map, 0–1, or `None` where there is no yarn.
    pub fn position(&self, d: f64) -> Option<f64> {
        let (lo, hi) = self.range?;
        let t = (d - lo) / (hi - lo);
        (is_covered(d) && t.is_finite()).then(|| t.clamp(0.0, 1.0))
    }

    /// The longest tick label, characters (at least enough for "no yarn" on an empty bar).
    fn label_chars(&self) -> usize {
        let longest = self
            .ticks
            .iter()
            .map(|(_, s)| s.chars().count())
            .max()
            .unwrap_or(0);
        longest.max(if self.range.is_none() {
            NO_YARN_LABEL.len()
        } else {
            4
        })
    }
}

fn is_covered(d: f64) -> bool {
    d.is_finite() && d > 0.0
}

/// [`heat`] tabulated, linear RGB.
pub struct HeatLut(Vec<[f32; 3]>);

impl HeatLut {
    /// The table.
    pub fn new() -> Self {
        HeatLut(
            (0..LUT_SIZE)
                .map(|k| heat(k as f64 / (LUT_SIZE - 1) as f64))
                .collect(),
        )
    }

    /// The colour at `t` in 0–1 (clamped; not finite is 0).
    pub fn get(&self, t: f32) -> [f32; 3] {
        let t = if t.is_finite() {
            t.clamp(0.0, 1.0)
        } else {
            0.0
        };
        self.0[(t * (LUT_SIZE - 1) as f32).round() as usize]
    }
}

impl Default for HeatLut {
    fn default() -> Self {
        HeatLut::new()
    }
}

/// Where a bar goes, in picture pixels: its left edge and width, and its top and bottom
/// (exclusive) rows. The swatch and the labels go below and to the right of it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BarPlace {
    /// Left edge.
    pub x0: usize,
    /// Width.
    pub width: usize,
    /// Top row.
    pub top: usize,
    /// One past the bottom row.
    pub bottom: usize,
}

impl BarPlace {
    /// Length of a tick mark, pixels.
    pub fn tick_len(&self) -> usize {
        (self.width / 3).max(3)
    }

    /// The row of a tick at density `value` on a bar spanning [lo, hi].
    pub fn tick_y(&self, value: f64, lo: f64, hi: f64) -> usize {
        let t = ((value - lo) / (hi - lo)).clamp(0.0, 1.0);
        let span = (self.bottom - self.top).saturating_sub(1) as f64;
        self.top + ((1.0 - t) * span).round() as usize
    }

    /// The "no yarn" swatch under the bar: top and bottom (exclusive) rows.
    pub fn swatch_rows(&self, font: Font) -> (usize, usize) {
        let char_h = font.char_height();
        let top = self.bottom + char_h / 2;
        (top, top + char_h)
    }

    /// Widths of the bar's two label rows, pixels: the bar with a tick and the longest tick
    /// label, and the swatch with its label.
    pub fn row_widths(width: usize, scale: &ColourScale, font: Font) -> (usize, usize) {
        let char_w = font.char_width();
        let bar_row = width + (width / 3).max(3) + char_w / 2 + scale.label_chars() * char_w;
        let swatch_row = width + char_w + font.text_width(NO_YARN_LABEL);
        (bar_row, swatch_row)
    }
}

/// Draws the bar at `place`: the map (maximum at the top), its outline, ticks and their labels,
/// and the "no yarn" swatch; an all-grey bar labelled "no yarn" when nothing is covered.
pub fn draw_bar(
    canvas: &mut Canvas,
    place: BarPlace,
    scale: &ColourScale,
    lut: &HeatLut,
    font: Font,
) {
    let (x0, x1) = (place.x0, place.x0 + place.width);
    let (top, bottom) = (place.top, place.bottom);
    let height = (bottom - top) as f64;
    let grey = UNCOVERED.map(linear_to_srgb8);
    for y in top..bottom {
        let colour = match scale.range {
            Some(_) => {
                let t = 1.0 - (y - top) as f64 / (height - 1.0).max(1.0);
                lut.get(t as f32).map(linear_to_srgb8)
            }
            None => grey,
        };
        canvas.fill_rect(x0, x1, y, y + 1, colour);
    }
    canvas.outline(x0, x1, top, bottom);
    let label_x = x1 + place.tick_len() + font.char_width() / 2;
    match scale.range {
        Some((lo, hi)) => {
            for (value, _) in &scale.ticks {
                let y = place.tick_y(*value, lo, hi);
                canvas.fill_rect(x1, x1 + place.tick_len(), y, y + 1, INK);
            }
            let (s_top, s_bottom) = place.swatch_rows(font);
            canvas.fill_rect(x0, x1, s_top, s_bottom, grey);
            canvas.outline(x0, x1, s_top, s_bottom);
            for (value, label) in &scale.ticks {
                let y = place.tick_y(*value, lo, hi);
                canvas.text(label, label_x, y, Anchor::Left, font);
            }
            let x = x1 + font.char_width();
            canvas.text(NO_YARN_LABEL, x, (s_top + s_bottom) / 2, Anchor::Left, font);
        }
        None => {
            let y = (top + bottom) / 2;
            canvas.text(NO_YARN_LABEL, label_x, y, Anchor::Left, font);
        }
    }
}

/// `picture` with a colour-bar panel appended on the right, `fraction` of its height wide (at
/// least wide enough for the labels): the bar of the preview's density mode. `range`: density
/// at the bar's bottom and top, stitches per cm², or `None` when nothing is covered.
pub fn with_bar(picture: &RgbImage, range: Option<(f64, f64)>, fraction: f64) -> RgbImage {
    let (w, h) = (picture.width() as usize, picture.height() as usize);
    let font = Font::for_height(h);
    let (char_w, char_h) = (font.char_width(), font.char_height());
    let scale = ColourScale::spanning(range);
    let bar_width = (h / 28).max(8);
    let (bar_row, swatch_row) = BarPlace::row_widths(bar_width, &scale, font);
    let needed = 2 * char_w + bar_row.max(swatch_row).max(font.text_width(UNIT_LABEL));
    let panel = ((fraction * h as f64) as usize).max(needed);
    let mut canvas = Canvas::new(w + panel, h, picture.get_pixel(0, 0).0);
    canvas.paste(picture, 0, 0);
    let top = 3 * char_h;
    // Room below the bar for the "no yarn" swatch: half a line of space, then one line.
    let bottom = h.saturating_sub(3 * char_h + char_h / 2).max(top + 2);
    let place = BarPlace {
        x0: w + char_w,
        width: bar_width,
        top,
        bottom,
    };
    draw_bar(&mut canvas, place, &scale, &HeatLut::new(), font);
    canvas.text(
        UNIT_LABEL,
        w + char_w,
        char_h + char_h / 2,
        Anchor::Left,
        font,
    );
    canvas.into_image()
}

/// Round tick values in [lo, hi]: steps of 1, 2, 2.5 or 5 × 10ᵏ, preferring 4–6 ticks (closest
/// to 5), then steps without the half digit. Labels carry as many decimals as the step needs, or
/// use exponent notation for steps below 10⁻⁴ or from 10⁶.
pub fn nice_ticks(lo: f64, hi: f64) -> Vec<(f64, String)> {
    let span = hi - lo;
    if !(span > 0.0 && span.is_finite() && lo.is_finite()) {
        return Vec::new();
    }
    let e0 = span.log10().floor() as i32;
    // Candidates in a fixed order; the first with the lowest score wins.
    let mut best: Option<TickStep> = None;
    for e in (e0 - 2)..=(e0 + 1) {
        for (mantissa, half_digit) in [(1.0, false), (2.0, false), (2.5, true), (5.0, false)] {
            let step = mantissa * 10f64.powi(e);
            let first = (lo / step - 1e-9).ceil();
            let last = (hi / step + 1e-9).floor();
            if !(first.is_finite() && last.is_finite()) || (last - first).abs() > 1e6 {
                continue;
            }
            let count = (last - first) as i64 + 1;
            let outside = if count < 4 {
                4 - count
            } else if count > 6 {
                count - 6
            } else {
                0
            };
            let candidate = TickStep {
                score: (outside, (count - 5).abs(), u8::from(half_digit)),
                step,
                first: first as i64,
                count,
                decimals: (-e + i32::from(half_digit)).max(0) as usize,
            };
            if best.as_ref().is_none_or(|b| candidate.score < b.score) {
                best = Some(candidate);
            }
        }
    }
    let Some(TickStep {
        step,
        first,
        count,
        decimals,
        ..
    }) = best
    else {
        return Vec::new();
    };
    (0..count.clamp(0, 12))
        .map(|k| {
            let value = (first + k) as f64 * step;
            let label = if (1e-4..1e6).contains(&step) {
                format!("{value:.decimals$}")
            } else {
                format!("{value:e}")
            };
            (value, label)
        })
        .collect()
}

/// One candidate spacing of the bar's ticks.
struct TickStep {
    /// Ticks outside 4–6, distance from 5 ticks, 1 for a 2.5 step: lower is better.
    score: (i64, i64, u8),
    step: f64,
    /// The first tick, in steps.
    first: i64,
    count: i64,
    decimals: usize,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_round_and_four_to_six() {
        for (lo, hi) in [
            (8.5, 29.2),
            (5.5, 19.1),
            (19.0, 21.0),
            (0.013, 0.071),
            (123.0, 9876.0),
            (1.0, 1.3),
        ] {
            let ticks = nice_ticks(lo, hi);
            assert!(
                (4..=6).contains(&ticks.len()),
                "{lo}..{hi}: {ticks:?} should have 4 to 6 ticks"
            );
            for (v, label) in &ticks {
                assert!(*v >= lo - 1e-9 && *v <= hi + 1e-9, "{v} outside {lo}..{hi}");
                assert!((label.parse::<f64>().unwrap() - v).abs() < 1e-9 * v.abs().max(1.0));
            }
        }
        assert_eq!(
            nice_ticks(19.0, 21.0)
                .into_iter()
                .map(|t| t.1)
                .collect::<Vec<_>>(),
            ["19.0", "19.5", "20.0", "20.5", "21.0"]
        );
    }

    #[test]
    fn the_preview_panel_runs_cold_at_the_bottom_to_hot_at_the_top() {
        let picture = RgbImage::from_pixel(200, 300, image::Rgb([200, 200, 200]));
        let out = with_bar(&picture, Some((10.0, 40.0)), 0.16);
        assert!(out.width() > 200 && out.height() == 300);
        let font = Font::for_height(300);
        let x = (200 + font.char_width() + 4) as u32;
        let (top, bottom) = (3 * font.char_height(), 300 - 3 * font.char_height());
        let upper = out.get_pixel(x, (top + 3) as u32).0;
        let lower = out.get_pixel(x, (bottom - 12) as u32).0;
        let brightness = |c: [u8; 3]| c.iter().map(|&v| u32::from(v)).sum::<u32>();
        assert!(brightness(upper) > brightness(lower), "{upper:?} {lower:?}");
        assert_eq!(
            out.get_pixel(10, 10).0,
            [200, 200, 200],
            "the picture is kept"
        );
    }
}
