//! Nylon, the yarn every stocking here is knitted from: its density and stiffness, and the
//! diameter of a yarn of a given denier. Below the scene's yarns (a [`super::Yarn`] knows its
//! diameter from this) and the real stocking ([`super::fabric`]: a loop's stiffness from the
//! diameter and the modulus).
//!
//! * **Yarn diameter** from its denier (grams per 9 km) as a solid nylon filament bundle of
//!   density [`NYLON_DENSITY_KG_M3`]: `d = √(4 · denier / (9000 m · ρ · π))`, about 35 µm at
//!   10 den, 50 µm at 20, 70 µm at 40.

/// Density of nylon 6,6 (and nylon 6), kg/m³: 1.14 g/cm³.
pub const NYLON_DENSITY_KG_M3: f64 = 1140.0;
/// Young's modulus of drawn nylon 6,6 filament, pascals: about 3 GPa (an initial modulus of
/// some 2.5–3.5 N/tex at 1.14 g/cm³; Morton & Hearle, *Physical Properties of Textile Fibres*).
pub const NYLON_MODULUS_PA: f64 = 3.0e9;
/// Metres of yarn that weigh its denier in grams.
const DENIER_LENGTH_M: f64 = 9000.0;

/// Diameter of a nylon yarn of `denier` (grams per 9 km), metres.
pub fn yarn_diameter_m(denier: f64) -> f64 {
    let mass_per_metre = denier * 1e-3 / DENIER_LENGTH_M;
    (4.0 * mass_per_metre / (NYLON_DENSITY_KG_M3 * std::f64::consts::PI)).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn denier_gives_the_diameters_hosiery_is_quoted_at() {
        // 35 µm at 10 den, 50 µm at 20, 70 µm at 40 (solid nylon, 1.14 g/cm³).
        for (denier, micrometres) in [(10.0, 35.3), (20.0, 49.9), (40.0, 70.5)] {
            let d = yarn_diameter_m(denier) * 1e6;
            assert!((d - micrometres).abs() < 0.1, "{denier} den: {d} µm");
        }
    }
}
