//! Shading of the preview: skin and yarn under one key light and a uniform environment, then
//! tone mapping to display values.
//!
//! - Skin: a warm Lambertian albedo with "wrapped" diffuse (the cosine shifted by
//!   [`SKIN_WRAP`] and renormalised), a cheap stand-in for the soft falloff that subsurface
//!   scattering gives skin.
//! - Yarn: the paper shades the yarn with the normal of its cylinder (§7–8, Fig. 17); we keep
//!   that Lambertian term and add the highlight the paper names as future work (§9) as
//!   Kajiya & Kay's anisotropic term for fibres (SIGGRAPH 1989), in the half-vector form
//!   `sin(T, H)^p`: bright where the half-vector is perpendicular to the yarn, so highlights run
//!   across the yarn direction as on real nylon. It is masked by the cylinder normal's cosine
//!   to the light so the yarn's unlit side has none.
//! - Environment: a constant ambient term scaled by the albedo, brighter from above (a simple
//!   hemisphere light) so that downward faces are not flat.
//! - Tone mapping: Narkowicz's fit of the ACES filmic curve, applied to each pixel's mean
//!   radiance (averaging before the curve keeps the mean of sub-pixel yarn and skin right).
//!
//! There are no shadow rays: yarns are 0.03–0.04 mm thick and their shadows on the skin are
//! below the preview's resolution, and a skin point's lighting is not blocked by the leg
//! except where the Lambert term is already zero.

use nalgebra::Vector3;

/// Wrap of the skin's diffuse term: light reaches this far past the terminator (0 = Lambert).
pub const SKIN_WRAP: f64 = 0.35;

/// The lights, in world space.
#[derive(Clone, Debug, PartialEq)]
pub struct Lights {
    /// Unit direction towards the key light.
    pub key_direction: Vector3<f64>,
    /// Radiance of the key light.
    pub key_intensity: f64,
    /// Ambient radiance (environment).
    pub ambient: f64,
    /// Strength of the yarn highlight.
    pub sheen: f64,
    /// Exponent of the yarn highlight.
    pub sheen_exponent: f64,
}

impl Lights {
    fn environment(&self, n: &Vector3<f64>) -> f64 {
        // Hemisphere light: full from straight above, 60 % from below.
        self.ambient * (0.8 + 0.2 * n.y.clamp(-1.0, 1.0))
    }
}

/// Linear radiance of skin with albedo `albedo` and unit normal `n` (facing the viewer).
pub fn skin(albedo: [f64; 3], n: &Vector3<f64>, lights: &Lights) -> [f64; 3] {
    let cos = n.dot(&lights.key_direction);
    let wrapped = ((cos + SKIN_WRAP) / (1.0 + SKIN_WRAP)).max(0.0);
    let e = lights.key_intensity * wrapped + lights.environment(n);
    albedo.map(|a| a * e)
}

/// Linear radiance of yarn with albedo `albedo`, cylinder normal `n`, unit tangent `t` and
/// unit direction towards the viewer `v`.
pub fn yarn(
    albedo: [f64; 3],
    n: &Vector3<f64>,
    t: &Vector3<f64>,
    v: &Vector3<f64>,
    lights: &Lights,
) -> [f64; 3] {
    let l = &lights.key_direction;
    let lambert = n.dot(l).max(0.0);
    let diffuse = lights.key_intensity * lambert + lights.environment(n);
    let h = l + v;
    let specular = if h.norm_squared() > 1e-24 && lambert > 0.0 {
        let th = t.dot(&h.normalize());
        let sin = (1.0 - th * th).max(0.0).sqrt();
        // The mask fades the highlight in over the first few degrees of the lit side.
        let mask = (lambert * 4.0).min(1.0);
        lights.sheen * lights.key_intensity * sin.powf(lights.sheen_exponent) * mask
    } else {
        0.0
    };
    albedo.map(|a| a * diffuse + specular)
}

/// Narkowicz's ACES filmic fit: linear radiance to display-linear 0–1.
pub fn aces(x: f64) -> f64 {
    if !x.is_finite() || x <= 0.0 {
        return 0.0;
    }
    let (a, b, c, d, e) = (2.51, 0.03, 2.43, 0.59, 0.14);
    ((x * (a * x + b)) / (x * (c * x + d) + e)).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lights() -> Lights {
        Lights {
            key_direction: Vector3::new(0.0, 0.0, 1.0),
            key_intensity: 2.0,
            ambient: 0.3,
            sheen: 0.5,
            sheen_exponent: 40.0,
        }
    }

    #[test]
    fn highlight_is_brightest_when_the_half_vector_is_across_the_yarn() {
        let n = Vector3::z();
        let v = Vector3::z();
        let across = yarn([0.1; 3], &n, &Vector3::x(), &v, &lights());
        let tilted = Vector3::new(1.0, 0.0, 0.6).normalize();
        let along = yarn([0.1; 3], &n, &tilted, &v, &lights());
        assert!(across[0] > along[0] + 0.3, "{across:?} vs {along:?}");
    }

    #[test]
    fn tone_mapping_is_monotone_and_bounded() {
        let mut last = 0.0;
        for i in 0..100 {
            let y = aces(i as f64 * 0.1);
            assert!((0.0..=1.0).contains(&y) && y >= last);
            last = y;
        }
        assert_eq!(aces(f64::NAN), 0.0);
    }
}
