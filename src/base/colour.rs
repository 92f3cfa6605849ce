//! Colour maps and colour encoding shared by every picture and vertex-colour output.

/// A perceptually ordered heat map (dark purple → red → yellow, after matplotlib's "inferno"),
/// for `t` in 0..1 (clamped); linear RGB 0–1.
pub fn heat(t: f64) -> [f32; 3] {
    // sRGB control points of inferno at t = 0, 0.25, 0.5, 0.75, 1.
    const STOPS: [[f32; 3]; 5] = [
        [0.001, 0.000, 0.014],
        [0.341, 0.062, 0.429],
        [0.735, 0.216, 0.330],
        [0.978, 0.557, 0.035],
        [0.988, 0.998, 0.645],
    ];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    } as f32;
    let x = t * (STOPS.len() - 1) as f32;
    let k = (x.floor() as usize).min(STOPS.len() - 2);
    let f = x - k as f32;
    let srgb: [f32; 3] = std::array::from_fn(|c| STOPS[k][c] * (1.0 - f) + STOPS[k + 1][c] * f);
    srgb.map(srgb_to_linear)
}

/// sRGB-encoded 0–1 to linear 0–1.
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.040_45 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Linear 0–1 to an sRGB-encoded byte.
pub fn linear_to_srgb8(c: f32) -> u8 {
    let c = if c.is_finite() {
        c.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let s = if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5) as u8
}
