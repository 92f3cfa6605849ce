//! The one 2-D layer every picture is drawn with. Shapes that need anti-aliasing or depth are
//! drawn in linear light on a [`LinearImage`] (a buffer of linear-RGB samples, optionally
//! supersampled, resolved by a box filter); the result lands on a [`Canvas`], the picture in
//! sRGB bytes, where crisp rectangles, outlines and text go last. Text uses the
//! `embedded-graphics` ISO 8859-1 bitmap fonts, so "cm²" is spelt with its superscript and no
//! picture depends on the fonts a render-farm node happens to have.
//!
//! Everything clips to the picture: pixels outside it are dropped, never a panic. Pure and
//! deterministic: the same calls give the same bytes.

use std::convert::Infallible;

use embedded_graphics::mono_font::{iso_8859_1, MonoFont, MonoTextStyle};
use embedded_graphics::pixelcolor::Rgb888;
use embedded_graphics::prelude::{
    DrawTarget, Drawable, OriginDimensions, Pixel, Point, RgbColor, Size,
};
use embedded_graphics::text::{Alignment, Baseline, Text, TextStyleBuilder};
use image::{Rgb, RgbImage};

use crate::base::colour::linear_to_srgb8;

/// sRGB of text, ticks and outlines: a near-black grey.
pub const INK: [u8; 3] = [40, 40, 40];

/// A bitmap font.
#[derive(Clone, Copy)]
pub struct Font(&'static MonoFont<'static>);

impl std::fmt::Debug for Font {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let size = self.0.character_size;
        write!(f, "Font({}x{})", size.width, size.height)
    }
}

impl Font {
    /// The font for a picture (or panel) `height_px` high: 20, 15, 13 or 10 pixels tall.
    pub fn for_height(height_px: usize) -> Font {
        Font(if height_px >= 560 {
            &iso_8859_1::FONT_10X20
        } else if height_px >= 400 {
            &iso_8859_1::FONT_9X15
        } else if height_px >= 280 {
            &iso_8859_1::FONT_7X13
        } else {
            &iso_8859_1::FONT_6X10
        })
    }

    /// Advance from one character to the next, pixels.
    pub fn char_width(self) -> usize {
        (self.0.character_size.width + self.0.character_spacing) as usize
    }

    /// Height of a line, pixels.
    pub fn char_height(self) -> usize {
        self.0.character_size.height as usize
    }

    /// Width of `text`, pixels.
    pub fn text_width(self, text: &str) -> usize {
        text.chars().count() * self.char_width()
    }
}

/// Where a text's anchor point is, along the text; vertically the anchor is always the line's
/// middle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Anchor {
    /// The anchor is the start of the text.
    Left,
    /// The anchor is the middle of the text.
    Centre,
}

/// A picture in sRGB bytes.
pub struct Canvas {
    image: RgbImage,
}

impl Canvas {
    /// A `width × height` picture filled with `background` (sRGB).
    pub fn new(width: usize, height: usize, background: [u8; 3]) -> Canvas {
        Canvas {
            image: RgbImage::from_pixel(width as u32, height as u32, Rgb(background)),
        }
    }

    /// Width, pixels.
    pub fn width(&self) -> usize {
        self.image.width() as usize
    }

    /// Height, pixels.
    pub fn height(&self) -> usize {
        self.image.height() as usize
    }

    /// The picture.
    pub fn into_image(self) -> RgbImage {
        self.image
    }

    /// Sets one pixel, if it is inside the picture.
    pub fn put(&mut self, x: usize, y: usize, colour: [u8; 3]) {
        if x < self.width() && y < self.height() {
            self.image.put_pixel(x as u32, y as u32, Rgb(colour));
        }
    }

    /// Copies `picture` with its top-left corner at (`x0`, `y0`).
    pub fn paste(&mut self, picture: &RgbImage, x0: usize, y0: usize) {
        for (x, y, px) in picture.enumerate_pixels() {
            self.put(x0 + x as usize, y0 + y as usize, px.0);
        }
    }

    /// Fills columns `x0..x1` of rows `y0..y1`.
    pub fn fill_rect(&mut self, x0: usize, x1: usize, y0: usize, y1: usize, colour: [u8; 3]) {
        let (w, h) = (self.width(), self.height());
        for y in y0.min(h)..y1.min(h) {
            for x in x0.min(w)..x1.min(w) {
                self.image.put_pixel(x as u32, y as u32, Rgb(colour));
            }
        }
    }

    /// A one-pixel [`INK`] frame just outside columns `x0..x1`, rows `y0..y1`.
    pub fn outline(&mut self, x0: usize, x1: usize, y0: usize, y1: usize) {
        let (xa, ya) = (x0.saturating_sub(1), y0.saturating_sub(1));
        self.fill_rect(xa, x1 + 1, ya, y0, INK);
        self.fill_rect(xa, x1 + 1, y1, y1 + 1, INK);
        self.fill_rect(xa, x0, y0, y1, INK);
        self.fill_rect(x1, x1 + 1, y0, y1, INK);
    }

    /// Writes `text` in [`INK`] with `font`, its `anchor` at (`x`, `y`), vertically centred on
    /// `y`.
    pub fn text(&mut self, text: &str, x: usize, y: usize, anchor: Anchor, font: Font) {
        let style = MonoTextStyle::new(font.0, Rgb888::new(INK[0], INK[1], INK[2]));
        let alignment = match anchor {
            Anchor::Left => Alignment::Left,
            Anchor::Centre => Alignment::Center,
        };
        let text_style = TextStyleBuilder::new()
            .alignment(alignment)
            .baseline(Baseline::Middle)
            .build();
        let at = Point::new(x as i32, y as i32);
        let Ok(_) = Text::with_text_style(text, at, style, text_style).draw(&mut Target(self));
    }
}

/// `embedded-graphics` drawing onto a [`Canvas`]; pixels outside it are dropped.
struct Target<'a>(&'a mut Canvas);

impl OriginDimensions for Target<'_> {
    fn size(&self) -> Size {
        Size::new(self.0.image.width(), self.0.image.height())
    }
}

impl DrawTarget for Target<'_> {
    type Color = Rgb888;
    type Error = Infallible;

    fn draw_iter<I>(&mut self, pixels: I) -> Result<(), Self::Error>
    where
        I: IntoIterator<Item = Pixel<Self::Color>>,
    {
        for Pixel(at, c) in pixels {
            if let (Ok(x), Ok(y)) = (usize::try_from(at.x), usize::try_from(at.y)) {
                self.0.put(x, y, [c.r(), c.g(), c.b()]);
            }
        }
        Ok(())
    }
}

/// A buffer of linear-RGB samples, `supersample`² per picture pixel, for shapes that need
/// anti-aliasing or a depth test; [`LinearImage::resolve`] puts it on a [`Canvas`].
pub struct LinearImage {
    /// Width, samples.
    pub width: usize,
    /// Height, samples.
    pub height: usize,
    /// Samples per pixel along each axis.
    pub supersample: usize,
    /// Row-major samples, linear RGB.
    pub pixels: Vec<[f32; 3]>,
}

impl LinearImage {
    /// `width × height` picture pixels, each `supersample × supersample` samples, all
    /// `background` (linear RGB).
    pub fn new(width: usize, height: usize, supersample: usize, background: [f32; 3]) -> Self {
        let s = supersample.max(1);
        LinearImage {
            width: width * s,
            height: height * s,
            supersample: s,
            pixels: vec![background; width * s * height * s],
        }
    }

    /// Box-filters the samples in linear light and writes them, sRGB-encoded, with the top-left
    /// corner at picture pixel (`x0`, `y0`) of `canvas`.
    pub fn resolve(&self, canvas: &mut Canvas, x0: usize, y0: usize) {
        let s = self.supersample;
        let inv = 1.0 / (s * s) as f32;
        for y in 0..self.height / s {
            for x in 0..self.width / s {
                let mut sum = [0.0f32; 3];
                for sy in 0..s {
                    let row = (y * s + sy) * self.width + x * s;
                    for sample in &self.pixels[row..row + s] {
                        for ch in 0..3 {
                            sum[ch] += sample[ch];
                        }
                    }
                }
                canvas.put(x0 + x, y0 + y, sum.map(|v| linear_to_srgb8(v * inv)));
            }
        }
    }
}

/// A rectangle of samples, `x0..x1` × `y0..y1`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Rect {
    /// First column.
    pub x0: usize,
    /// One past the last column.
    pub x1: usize,
    /// First row.
    pub y0: usize,
    /// One past the last row.
    pub y1: usize,
}

/// A stroke from `a` to `b` with round ends (a disc when `a == b`), in samples.
#[derive(Clone, Copy, Debug)]
pub struct Capsule {
    /// One end.
    pub a: [f64; 2],
    /// The other end.
    pub b: [f64; 2],
    /// Half the stroke's width.
    pub radius: f64,
    /// Linear RGB.
    pub colour: [f32; 3],
    /// Shaded as a cylinder seen from above (yarn), or flat.
    pub shaded: bool,
}

impl Capsule {
    /// Sample centres whose distance to the capsule's axis might be within `radius + 0.5`,
    /// clipped to `rect`; `None` when none.
    fn sample_box(&self, rect: Rect) -> Option<Rect> {
        let pad = self.radius + 1.0;
        let lo = [
            self.a[0].min(self.b[0]) - pad,
            self.a[1].min(self.b[1]) - pad,
        ];
        let hi = [
            self.a[0].max(self.b[0]) + pad,
            self.a[1].max(self.b[1]) + pad,
        ];
        if !lo.iter().chain(&hi).all(|c| c.is_finite()) {
            return None;
        }
        let clip = |v: f64, lo: usize, hi: usize| v.clamp(lo as f64, hi as f64) as usize;
        let r = Rect {
            x0: clip(lo[0].floor(), rect.x0, rect.x1),
            x1: clip(hi[0].ceil(), rect.x0, rect.x1),
            y0: clip(lo[1].floor(), rect.y0, rect.y1),
            y1: clip(hi[1].ceil(), rect.y0, rect.y1),
        };
        (r.x0 < r.x1 && r.y0 < r.y1).then_some(r)
    }

    /// Distance from `p` to the axis segment `a`–`b`.
    fn axis_distance(&self, p: [f64; 2]) -> f64 {
        let ab = [self.b[0] - self.a[0], self.b[1] - self.a[1]];
        let ap = [p[0] - self.a[0], p[1] - self.a[1]];
        let len_sq = ab[0] * ab[0] + ab[1] * ab[1];
        let t = if len_sq > 0.0 {
            ((ap[0] * ab[0] + ap[1] * ab[1]) / len_sq).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (ap[0] - t * ab[0]).hypot(ap[1] - t * ab[1])
    }

    /// The colour at distance `dist` from the axis: for a shaded stroke, a cylinder seen from
    /// above, lit head-on (bright crest, dark flanks) with a narrow sheen along the crest.
    fn colour_at(&self, dist: f64) -> [f32; 3] {
        if !self.shaded {
            return self.colour;
        }
        let across = (dist / self.radius).min(1.0) as f32;
        let height = (1.0 - across * across).sqrt();
        let shade = 0.4 + 0.8 * height;
        // Absolute, so dark yarn still shows its round; small, so it stays dark.
        let sheen = 0.06 * height.powi(4);
        self.colour.map(|c| c * shade + sheen)
    }
}

/// Layer value of a sample no capsule reached.
const EMPTY: (f32, [f32; 3]) = (f32::INFINITY, [0.0; 3]);

impl LinearImage {
    /// Draws `capsules` as one shape (their union, each sample coloured by the nearest),
    /// anti-aliased with a one-sample edge, over what is already inside `rect`. One shape, not
    /// one stroke after another, so the joints of a polyline are seamless rather than darkened
    /// twice by overlapping edges.
    pub fn strokes(&mut self, rect: Rect, capsules: impl Iterator<Item = Capsule>) {
        let boxed: Vec<(Capsule, Rect)> = capsules
            .filter_map(|c| c.sample_box(rect).map(|r| (c, r)))
            .collect();
        let Some(t) = boxed.iter().map(|(_, r)| *r).reduce(|t, r| Rect {
            x0: t.x0.min(r.x0),
            x1: t.x1.max(r.x1),
            y0: t.y0.min(r.y0),
            y1: t.y1.max(r.y1),
        }) else {
            return;
        };
        // Per sample of the strokes' box: signed distance to the nearest stroke's edge (negative
        // inside) and that stroke's colour there.
        let box_width = t.x1 - t.x0;
        let mut nearest = vec![EMPTY; box_width * (t.y1 - t.y0)];
        for (capsule, r) in &boxed {
            for y in r.y0..r.y1 {
                for x in r.x0..r.x1 {
                    let dist = capsule.axis_distance([x as f64 + 0.5, y as f64 + 0.5]);
                    let edge = (dist - capsule.radius) as f32;
                    let cell = &mut nearest[(y - t.y0) * box_width + (x - t.x0)];
                    if edge < cell.0 && edge < 0.5 {
                        *cell = (edge, capsule.colour_at(dist));
                    }
                }
            }
        }
        for y in t.y0..t.y1 {
            for x in t.x0..t.x1 {
                let (edge, colour) = nearest[(y - t.y0) * box_width + (x - t.x0)];
                let coverage = (0.5 - edge).clamp(0.0, 1.0);
                if coverage > 0.0 {
                    let p = &mut self.pixels[y * self.width + x];
                    for k in 0..3 {
                        p[k] += (colour[k] - p[k]) * coverage;
                    }
                }
            }
        }
    }

    /// A filled square of half-side `half` samples centred on `c`, clipped to `rect`.
    pub fn square(&mut self, rect: Rect, c: [f64; 2], half: f64, colour: [f32; 3]) {
        let clip = |v: f64, lo: usize, hi: usize| v.round().clamp(lo as f64, hi as f64) as usize;
        let (x0, x1) = (
            clip(c[0] - half, rect.x0, rect.x1),
            clip(c[0] + half, rect.x0, rect.x1),
        );
        let (y0, y1) = (
            clip(c[1] - half, rect.y0, rect.y1),
            clip(c[1] + half, rect.y0, rect.y1),
        );
        for y in y0..y1 {
            self.pixels[y * self.width + x0..y * self.width + x1].fill(colour);
        }
    }
}
