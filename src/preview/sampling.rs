//! Where a preview pixel's samples fall, and the fixed hash every one comes from.
//!
//! Anti-aliasing: each pixel is split into a grid of ⌈√spp⌉ × ⌈spp/⌈√spp⌉⌉ strata with one
//! sample each, placed by correlated multi-jittered sampling (Kensler, "Correlated
//! Multi-Jittered Sampling", Pixar 2013): stratified in 2D *and* along each axis alone, so that
//! yarns running along the picture's axes (wales down a standing leg, courses across it) are
//! sampled at spp distinct offsets, not ⌈√spp⌉. A plain jittered grid is no better than random
//! samples when the yarn period equals a stratum. All samples belong to one box-filtered pixel,
//! and their radiance is averaged *before* tone mapping, so where the yarn spacing is below a
//! pixel the pixel converges to the area-weighted mix of yarn and skin — the mean sheerness —
//! instead of aliasing into moiré (as one centred sample would) or vanishing.
//!
//! Determinism: every random number comes from a hash of (pixel index, sample index) and a fixed
//! seed (SplitMix64), rows are rendered in parallel but each pixel depends only on its own
//! samples, summed in a fixed order: the same bytes whatever the thread count.

/// The seed every preview sample is derived from.
pub const SEED: u64 = 0x6b6e_6974_6669_7421;
/// Most strata along one axis: ⌈√1024⌉.
const MAX_STRATA: usize = 32;

/// Samples per pixel as (columns, rows) of the stratification grid for a requested count.
pub fn strata(spp: u32) -> (u32, u32) {
    let spp = spp.max(1);
    let cols = (spp as f64).sqrt().ceil() as u32;
    (cols, spp.div_ceil(cols))
}

/// The sample positions of one pixel: one per stratum of a `cols × rows` grid, placed by
/// correlated multi-jitter from the pixel's own seed.
pub struct PixelSamples {
    seed: u64,
    cols: u32,
    rows: u32,
    col_perm: [u32; MAX_STRATA],
    row_perm: [u32; MAX_STRATA],
}

impl PixelSamples {
    /// The samples of the pixel numbered `pixel_index` (row-major from the top left).
    pub fn new(pixel_index: u64, cols: u32, rows: u32) -> PixelSamples {
        let seed = splitmix64(SEED ^ pixel_index.wrapping_mul(0x9e37_79b9_7f4a_7c15));
        PixelSamples {
            seed,
            cols,
            rows,
            col_perm: permutation(cols, splitmix64(seed ^ 0xa511_e9b3)),
            row_perm: permutation(rows, splitmix64(seed ^ 0x63d8_3595)),
        }
    }

    /// The sample of stratum (`i`, `j`) as an offset within the pixel, each axis in [0, 1).
    pub fn offset(&self, i: u32, j: u32) -> (f64, f64) {
        let (cols, rows) = (self.cols, self.rows);
        let k = u64::from(j * cols + i);
        let bits = splitmix64(self.seed ^ k.wrapping_mul(0xd1b5_4a32_d192_ed03));
        let (jx, jy) = (unit(bits), unit(bits >> 32));
        // Correlated multi-jitter: stratum (i, j), and within it the sub-stratum given by the
        // other axis's permuted index, so the samples are also stratified along x alone and
        // along y alone.
        let sx = (f64::from(self.row_perm[j as usize]) + jx) / f64::from(rows);
        let sy = (f64::from(self.col_perm[i as usize]) + jy) / f64::from(cols);
        (
            (f64::from(i) + sx) / f64::from(cols),
            (f64::from(j) + sy) / f64::from(rows),
        )
    }
}

/// SplitMix64 (Steele, Lea & Flood 2014): a fixed, high-quality 64-bit mix.
pub fn splitmix64(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// A permutation of `0..n` (n ≤ [`MAX_STRATA`]) drawn by Fisher–Yates from `seed`.
fn permutation(n: u32, seed: u64) -> [u32; MAX_STRATA] {
    let mut p: [u32; MAX_STRATA] = std::array::from_fn(|i| i as u32);
    let n = (n as usize).min(MAX_STRATA);
    let mut state = seed;
    for i in (1..n).rev() {
        state = splitmix64(state);
        let j = (state % (i as u64 + 1)) as usize;
        p.swap(i, j);
    }
    p
}

/// The low 32 bits as a number in [0, 1).
fn unit(bits: u64) -> f64 {
    (bits & 0xffff_ffff) as f64 / 4_294_967_296.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spp_fills_a_near_square_grid() {
        assert_eq!(strata(1), (1, 1));
        assert_eq!(strata(4), (2, 2));
        assert_eq!(strata(16), (4, 4));
        assert_eq!(strata(8), (3, 3));
        assert_eq!(strata(6), (3, 2));
    }

    #[test]
    fn samples_fill_every_stratum_and_every_column_and_row_alone() {
        let (cols, rows) = (4, 4);
        let samples = PixelSamples::new(12_345, cols, rows);
        let mut by_x = vec![0; (cols * rows) as usize];
        let mut by_y = vec![0; (cols * rows) as usize];
        for j in 0..rows {
            for i in 0..cols {
                let (x, y) = samples.offset(i, j);
                assert_eq!((x * f64::from(cols)) as u32, i);
                assert_eq!((y * f64::from(rows)) as u32, j);
                by_x[(x * f64::from(cols * rows)) as usize] += 1;
                by_y[(y * f64::from(cols * rows)) as usize] += 1;
            }
        }
        assert!(
            by_x.iter().chain(&by_y).all(|&n| n == 1),
            "{by_x:?} {by_y:?}"
        );
    }
}
