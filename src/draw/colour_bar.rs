//! The colour bar of the preview's density mode (paper Fig. 18): a panel to the right of the
//! ray-traced picture with the heat map from the lowest covered density (bottom) to the highest
//! (top), round ticks and the unit; the same map, ticks and font as `density.png`.

use embedded_graphics::mono_font::MonoTextStyle;
use embedded_graphics::pixelcolor::Rgb888;
use embedded_graphics::prelude::{Drawable, Point};
use embedded_graphics::text::{Alignment, Baseline, Text, TextStyleBuilder};
use image::{Rgb, RgbImage};

use super::density_map::{font_for, nice_ticks, ImageTarget, NO_YARN_LABEL, UNIT_LABEL};
use crate::base::colour::{heat, linear_to_srgb8};

/// sRGB of text and outlines.
const INK: [u8; 3] = [40, 40, 40];
/// sRGB of the "no yarn" swatch: the grey the preview gives skin without yarn (linear 0.3).
const UNCOVERED_SRGB: [u8; 3] = [149, 149, 149];

/// `picture` with a colour-bar panel appended on the right, `fraction` of its height wide (at
/// least wide enough for the labels). `range`: density at the bar's bottom and top, stitches
/// per cm², or `None` when nothing is covered (the panel then says "no yarn").
pub fn with_bar(picture: &RgbImage, range: Option<(f64, f64)>, fraction: f64) -> RgbImage {
    let (w, h) = (picture.width(), picture.height());
    let font = font_for(h as usize);
    let char_w = font.character_size.width + font.character_spacing;
    let char_h = font.character_size.height;
    let ticks = range.map(|(lo, hi)| nice_ticks(lo, hi)).unwrap_or_default();
    let label_chars = ticks
        .iter()
        .map(|(_, s)| s.chars().count() as u32)
        .max()
        .unwrap_or(0);
    let bar_w = (h / 28).max(8);
    let needed = 3 * char_w + bar_w + label_chars.max(UNIT_LABEL.chars().count() as u32) * char_w;
    let panel = ((fraction * h as f64) as u32).max(needed);
    let background = *picture.get_pixel(0, 0);
    let mut out = RgbImage::from_pixel(w + panel, h, background);
    for (x, y, px) in picture.enumerate_pixels() {
        out.put_pixel(x, y, *px);
    }
    let x0 = w + char_w;
    let top = 3 * char_h;
    // Room below the bar for the "no yarn" swatch: half a line of space, then one line.
    let bottom = h.saturating_sub(3 * char_h + char_h / 2).max(top + 2);
    for y in top..bottom {
        let t = 1.0 - (y - top) as f64 / (bottom - top - 1).max(1) as f64;
        let c = match range {
            Some(_) => heat(t).map(linear_to_srgb8),
            None => UNCOVERED_SRGB,
        };
        for x in x0..x0 + bar_w {
            out.put_pixel(x, y, Rgb(c));
        }
    }
    for y in [top, bottom - 1] {
        for x in x0..x0 + bar_w {
            out.put_pixel(x, y, Rgb(INK));
        }
    }
    for y in top..bottom {
        out.put_pixel(x0, y, Rgb(INK));
        out.put_pixel(x0 + bar_w - 1, y, Rgb(INK));
    }
    let style = MonoTextStyle::new(font, Rgb888::new(INK[0], INK[1], INK[2]));
    let left = TextStyleBuilder::new()
        .alignment(Alignment::Left)
        .baseline(Baseline::Middle)
        .build();
    let tick_x = x0 + bar_w;
    let mut labels = Vec::new();
    match range {
        Some((lo, hi)) => {
            for (value, label) in &ticks {
                let t = ((value - lo) / (hi - lo)).clamp(0.0, 1.0);
                let y = top + ((1.0 - t) * (bottom - top - 1) as f64).round() as u32;
                for x in tick_x..tick_x + bar_w / 3 {
                    out.put_pixel(x, y, Rgb(INK));
                }
                labels.push((label.clone(), tick_x + bar_w / 3 + char_w / 2, y));
            }
            // Skin without yarn is drawn grey on the leg; the swatch says so.
            let s_top = bottom + char_h / 2;
            for y in s_top..(s_top + char_h).min(h) {
                for x in x0..x0 + bar_w {
                    let edge =
                        y == s_top || y + 1 == s_top + char_h || x == x0 || x + 1 == x0 + bar_w;
                    out.put_pixel(x, y, Rgb(if edge { INK } else { UNCOVERED_SRGB }));
                }
            }
            labels.push((
                NO_YARN_LABEL.to_string(),
                tick_x + char_w,
                s_top + char_h / 2,
            ));
        }
        None => labels.push((
            NO_YARN_LABEL.to_string(),
            tick_x + char_w,
            (top + bottom) / 2,
        )),
    }
    labels.push((UNIT_LABEL.to_string(), w + char_w, char_h + char_h / 2));
    let mut target = ImageTarget(&mut out);
    for (text, x, y) in labels {
        let at = Point::new(x as i32, y as i32);
        let Ok(_) = Text::with_text_style(&text, at, style, left).draw(&mut target);
    }
    out
}
