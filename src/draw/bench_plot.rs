//! `bench.png`: accuracy against time, log–log, one curve per solver and grid (the points of a
//! curve are its tolerances), drawn with `plotters`. Labels use DejaVu Sans Mono, compiled in
//! (`assets/fonts/`, Bitstream Vera licence), so the picture does not depend on the fonts a
//! render-farm node happens to have.

use std::sync::Once;

use image::RgbImage;
use plotters::prelude::*;
use plotters::style::FontStyle;

use crate::error::{Error, Result};

/// Picture size, pixels.
const SIZE: (u32, u32) = (1100, 760);
/// Errors below this are drawn at it (a log axis has no zero).
const ERROR_FLOOR: f64 = 1e-7;

static FONT: Once = Once::new();

/// One curve: a solver on one leg and grid, its points `(seconds, density error)`.
#[derive(Clone, Debug, PartialEq)]
pub struct Curve {
    /// Legend text.
    pub label: String,
    /// The paper's solver (drawn dashed-looking: thinner, hollow markers).
    pub paper: bool,
    /// `(seconds, relative density error)`, in tolerance order.
    pub points: Vec<(f64, f64)>,
}

/// Draws the curves and encodes the PNG for the file `file_name`.
///
/// Errors: [`Error::Encode`] naming `file_name` when drawing or encoding fails.
pub fn draw(curves: &[Curve], file_name: &str) -> Result<Vec<u8>> {
    FONT.call_once(|| {
        // The bytes are a valid TrueType font compiled in; a failure here is a build defect,
        // and plotters then draws no text rather than failing.
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            include_bytes!("../../assets/fonts/DejaVuSansMono.ttf"),
        );
    });
    let encode_error = |e: String| Error::Encode {
        what: file_name.into(),
        message: e,
    };
    let mut buffer = vec![0u8; (SIZE.0 * SIZE.1 * 3) as usize];
    draw_into(&mut buffer, curves).map_err(encode_error)?;
    let image = RgbImage::from_raw(SIZE.0, SIZE.1, buffer)
        .ok_or_else(|| encode_error("picture buffer has the wrong size".into()))?;
    super::encode_png(&image, file_name)
}

fn draw_into(buffer: &mut [u8], curves: &[Curve]) -> std::result::Result<(), String> {
    let err = |e: &dyn std::fmt::Display| e.to_string();
    let root = BitMapBackend::with_buffer(buffer, SIZE).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let points = curves.iter().flat_map(|c| c.points.iter());
    let (mut t_lo, mut t_hi, mut e_lo, mut e_hi) = (f64::INFINITY, 0.0f64, f64::INFINITY, 0.0f64);
    for &(t, e) in points {
        t_lo = t_lo.min(t);
        t_hi = t_hi.max(t);
        e_lo = e_lo.min(e.max(ERROR_FLOOR));
        e_hi = e_hi.max(e.max(ERROR_FLOOR));
    }
    if !(t_lo.is_finite() && e_lo.is_finite()) {
        (t_lo, t_hi, e_lo, e_hi) = (0.01, 1.0, ERROR_FLOOR, 1.0);
    }
    let mut chart = ChartBuilder::on(&root)
        .caption(
            "knitfit bench: accuracy against solve time",
            ("sans-serif", 24),
        )
        .margin(16)
        .x_label_area_size(48)
        .y_label_area_size(80)
        .build_cartesian_2d(
            (t_lo / 1.5..t_hi * 1.5).log_scale(),
            (e_lo / 2.0..e_hi * 2.0).log_scale(),
        )
        .map_err(|e| err(&e))?;
    chart
        .configure_mesh()
        .x_desc("solve time, seconds (log)")
        .y_desc("stitch-density error vs reference (log)")
        .x_label_formatter(&|v| format!("{v:.2}"))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .label_style(("sans-serif", 15))
        .axis_desc_style(("sans-serif", 17))
        .draw()
        .map_err(|e| err(&e))?;
    for (i, curve) in curves.iter().enumerate() {
        let colour = Palette99::pick(i).to_rgba();
        let line: Vec<(f64, f64)> = curve
            .points
            .iter()
            .map(|&(t, e)| (t, e.max(ERROR_FLOOR)))
            .collect();
        let width = if curve.paper { 1 } else { 3 };
        chart
            .draw_series(LineSeries::new(line.clone(), colour.stroke_width(width)))
            .map_err(|e| err(&e))?
            .label(curve.label.clone())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 24, y)], colour.stroke_width(width))
            });
        let paper = curve.paper;
        chart
            .draw_series(line.into_iter().map(move |p| {
                if paper {
                    Circle::new(p, 5, colour.stroke_width(2))
                } else {
                    Circle::new(p, 5, colour.filled())
                }
            }))
            .map_err(|e| err(&e))?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font(("sans-serif", 14))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_plot_is_a_png_of_its_size_with_something_drawn() {
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
        assert_eq!(image.dimensions(), SIZE);
        let ink = image.pixels().filter(|p| p.0 != [255, 255, 255]).count();
        assert!(ink > 5000, "only {ink} non-white pixels");
    }
}
