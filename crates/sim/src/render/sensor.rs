//! The camera sensor: exposure, noise, 12-bit quantisation, dead pixels and optional JPEG-like
//! compression.
//!
//! A pixel's mean signal is `DN = k I/F` (`k` the exposure, DN per unit radiance factor).
//! Noise (Janesick, "Photon transfer", 2007): shot noise is Poisson in electrons, so in DN its
//! variance is `DN / g` for a gain of `g` electrons per DN; read noise adds a constant variance
//! `sigma_r^2`. The sum is drawn as a Gaussian of variance `DN / g + sigma_r^2` (departure:
//! Gaussian instead of Poisson, exact enough above a few tens of electrons). The result is
//! rounded and clamped to 12 bits. Dead pixels read 0 and are a property of the detector, so
//! their places depend on the camera name only; the noise depends on the seed and the name.
//! Compression quantises the 8x8 DCT blocks of the image with the JPEG luminance table
//! (ITU-T T.81 Annex K) scaled by a quality factor as libjpeg does.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use rayon::prelude::*;

/// Largest 12-bit value.
pub const FULL_SCALE_DN: u16 = 4095;

/// How the exposure is chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Exposure {
    /// Scale so that the given quantile of the image's radiance lands on `target_dn`.
    Auto {
        /// Target DN.
        target_dn: f64,
        /// Radiance quantile (0..1) placed at the target.
        quantile: f64,
    },
    /// A fixed DN per unit radiance factor.
    Fixed(f64),
}

/// Detector and electronics of a camera.
#[derive(Clone, Debug, PartialEq)]
pub struct Sensor {
    /// Exposure control.
    pub exposure: Exposure,
    /// Electrons per DN.
    pub gain_e_per_dn: f64,
    /// Read noise standard deviation (DN).
    pub read_noise_dn: f64,
    /// Number of dead pixels.
    pub dead_pixels: usize,
    /// JPEG-like compression quality (1..100); `None` leaves the image uncompressed.
    pub jpeg_quality: Option<u8>,
    /// Whether noise is added at all (false gives the exposed, quantised mean signal).
    pub noise: bool,
}

impl Default for Sensor {
    fn default() -> Self {
        // MER engineering cameras: 12-bit, full well ~170 ke- (Maki et al. 2003), so ~40 e-/DN
        // over 4096 DN and ~25 e- read noise.
        Self {
            exposure: Exposure::Auto { target_dn: 3200.0, quantile: 0.995 },
            gain_e_per_dn: 40.0,
            read_noise_dn: 0.6,
            dead_pixels: 6,
            jpeg_quality: None,
            noise: true,
        }
    }
}

impl Sensor {
    /// The exposure (DN per unit I/F) for an image of radiances.
    pub fn exposure_for(&self, radiance: &[f32]) -> f64 {
        match self.exposure {
            Exposure::Fixed(k) => k,
            Exposure::Auto { target_dn, quantile } => {
                let mut v: Vec<f32> = radiance.iter().copied().filter(|r| r.is_finite()).collect();
                if v.is_empty() {
                    return target_dn;
                }
                let i = ((v.len() - 1) as f64 * quantile.clamp(0.0, 1.0)) as usize;
                let (_, q, _) = v.select_nth_unstable_by(i, f32::total_cmp);
                target_dn / (*q as f64).max(1e-6)
            }
        }
    }

    /// Exposes, adds noise and quantises an image of radiances (`width` per row); deterministic
    /// for `seed` and the camera `name`.
    pub fn expose(&self, radiance: &[f32], width: usize, k: f64, seed: u64, name: &str) -> Vec<u16> {
        let mut out = vec![0u16; radiance.len()];
        let key = name_key(name);
        out.par_chunks_mut(width.max(1)).zip(radiance.par_chunks(width.max(1))).enumerate().for_each(
            |(row, (dst, src))| {
                let mut rng = ChaCha8Rng::seed_from_u64(seed ^ key);
                rng.set_stream(row as u64);
                for (d, &l) in dst.iter_mut().zip(src) {
                    let mean = (l as f64 * k).max(0.0);
                    let z: f64 = rng.sample(StandardNormal);
                    let sigma = (mean / self.gain_e_per_dn + self.read_noise_dn.powi(2)).sqrt();
                    let dn = if self.noise { mean + z * sigma } else { mean };
                    *d = dn.round().clamp(0.0, FULL_SCALE_DN as f64) as u16;
                }
            },
        );
        if let Some(q) = self.jpeg_quality {
            compress(&mut out, width, q);
        }
        for i in dead_pixels(self.dead_pixels, out.len(), key) {
            out[i] = 0;
        }
        out
    }
}

/// A 64-bit key of a camera name (FNV-1a).
fn name_key(name: &str) -> u64 {
    name.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ b as u64).wrapping_mul(0x1000_0000_01b3))
}

/// Indices of the dead pixels of the detector `key` among `n` pixels.
pub fn dead_pixels(count: usize, n: usize, key: u64) -> Vec<usize> {
    if n == 0 {
        return Vec::new();
    }
    let mut rng = ChaCha8Rng::seed_from_u64(key);
    (0..count).map(|_| rng.random_range(0..n)).collect()
}

/// JPEG luminance quantisation table (ITU-T T.81, Table K.1), row-major.
const LUMA_TABLE: [f64; 64] = [
    16., 11., 10., 16., 24., 40., 51., 61., 12., 12., 14., 19., 26., 58., 60., 55., 14., 13., 16., 24., 40.,
    57., 69., 56., 14., 17., 22., 29., 51., 87., 80., 62., 18., 22., 37., 56., 68., 109., 103., 77., 24.,
    35., 55., 64., 81., 104., 113., 92., 49., 64., 78., 87., 103., 121., 120., 101., 72., 92., 95., 98.,
    112., 100., 103., 99.,
];

/// Quantises the 8x8 DCT blocks of a 12-bit image in place (quality 1..100 as libjpeg; the
/// table is scaled by 16 for 12-bit samples, as 12-bit JPEG does).
pub fn compress(image: &mut [u16], width: usize, quality: u8) {
    if width == 0 {
        return;
    }
    let q = quality.clamp(1, 100) as f64;
    let scale = if q < 50.0 { 50.0 / q } else { 2.0 - q / 50.0 };
    let table: Vec<f64> = LUMA_TABLE.iter().map(|t| ((t * scale).round().max(1.0)) * 16.0).collect();
    let basis = dct_basis();
    let height = image.len() / width;
    let blocks_x = width.div_ceil(8);
    let blocks: Vec<(usize, usize)> =
        (0..height.div_ceil(8)).flat_map(|by| (0..blocks_x).map(move |bx| (bx, by))).collect();
    let processed: Vec<(usize, usize, [f64; 64])> = blocks
        .par_iter()
        .map(|&(bx, by)| {
            let mut block = [0.0; 64];
            for (i, b) in block.iter_mut().enumerate() {
                // Edge blocks replicate the last row and column.
                let x = (bx * 8 + i % 8).min(width - 1);
                let y = (by * 8 + i / 8).min(height - 1);
                *b = image[y * width + x] as f64 - 2048.0;
            }
            let coeffs = transform(&block, &basis, false);
            let mut quantised = [0.0; 64];
            for i in 0..64 {
                quantised[i] = (coeffs[i] / table[i]).round() * table[i];
            }
            (bx, by, transform(&quantised, &basis, true))
        })
        .collect();
    for (bx, by, block) in processed {
        for (i, v) in block.iter().enumerate() {
            let (x, y) = (bx * 8 + i % 8, by * 8 + i / 8);
            if x < width && y < height {
                image[y * width + x] = (v + 2048.0).round().clamp(0.0, FULL_SCALE_DN as f64) as u16;
            }
        }
    }
}

/// Separable orthonormal 8x8 DCT-II (`inverse` false) or its inverse.
fn transform(block: &[f64; 64], basis: &[f64], inverse: bool) -> [f64; 64] {
    // basis[u * 8 + x] = c(u) cos((2x + 1) u pi / 16); forward X = B S B^T, inverse S = B^T X B.
    let b = |u: usize, x: usize| if inverse { basis[x * 8 + u] } else { basis[u * 8 + x] };
    let mut tmp = [0.0; 64];
    for r in 0..8 {
        for u in 0..8 {
            tmp[r * 8 + u] = (0..8).map(|x| b(u, x) * block[r * 8 + x]).sum();
        }
    }
    let mut out = [0.0; 64];
    for v in 0..8 {
        for u in 0..8 {
            out[v * 8 + u] = (0..8).map(|y| b(v, y) * tmp[y * 8 + u]).sum();
        }
    }
    out
}

/// The orthonormal 8-point DCT-II basis, row u (frequency) by column x (sample).
fn dct_basis() -> Vec<f64> {
    (0..64)
        .map(|i| {
            let (u, x) = (i / 8, i % 8);
            let c = if u == 0 { (0.125f64).sqrt() } else { 0.5 };
            c * (((2 * x + 1) as f64 * u as f64 * std::f64::consts::PI) / 16.0).cos()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dct_round_trips_and_compression_keeps_smooth_images() {
        let width = 24;
        let mut image: Vec<u16> =
            (0..width * 16).map(|i| (1000 + (i % width) * 20 + (i / width) * 7) as u16).collect();
        let original = image.clone();
        compress(&mut image, width, 100);
        let max_err = image.iter().zip(&original).map(|(a, b)| (*a as i32 - *b as i32).abs()).max().unwrap();
        assert!(max_err <= 40, "{max_err}");
        // Quality 10 on a random image loses a lot.
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let noisy: Vec<u16> = (0..64 * 64).map(|_| rng.random_range(0..4096)).collect();
        let mut c = noisy.clone();
        compress(&mut c, 64, 10);
        let err: f64 =
            c.iter().zip(&noisy).map(|(a, b)| (*a as f64 - *b as f64).abs()).sum::<f64>() / c.len() as f64;
        assert!(err > 300.0, "{err}");
    }

    #[test]
    fn forward_then_inverse_dct_is_identity() {
        let basis = dct_basis();
        let mut block = [0.0; 64];
        for (i, b) in block.iter_mut().enumerate() {
            *b = ((i * 37) % 101) as f64 - 50.0;
        }
        let back = transform(&transform(&block, &basis, false), &basis, true);
        for i in 0..64 {
            assert!((back[i] - block[i]).abs() < 1e-9);
        }
    }
}
