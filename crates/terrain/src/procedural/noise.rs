//! Seeded 2-D gradient noise and its fractal sums, for procedural relief.
//!
//! Gradient noise in the manner of Perlin (1985, quintic fade of 2002): each integer lattice
//! point gets a pseudo-random unit gradient from an integer hash of (x, y, seed), and the noise
//! at a point blends the four corners' linear ramps. No tables, so any seed costs nothing.

const C1: f64 = 0.923_879_532_511_286_7; // cos 22.5 deg
const C2: f64 = std::f64::consts::FRAC_1_SQRT_2; // cos 45 deg
const C3: f64 = 0.382_683_432_365_089_8; // cos 67.5 deg

/// Sixteen unit gradient directions, k * 22.5 deg for k = 0..16.
const GRADIENTS: [(f64, f64); 16] = [
    (1.0, 0.0),
    (C1, C3),
    (C2, C2),
    (C3, C1),
    (0.0, 1.0),
    (-C3, C1),
    (-C2, C2),
    (-C1, C3),
    (-1.0, 0.0),
    (-C1, -C3),
    (-C2, -C2),
    (-C3, -C1),
    (0.0, -1.0),
    (C3, -C1),
    (C2, -C2),
    (C1, -C3),
];

/// A 32-bit integer hash of a lattice point and a seed (a multiply-xorshift finaliser).
fn hash(ix: i64, iy: i64, seed: u32) -> u32 {
    let mut h = (ix as u32).wrapping_mul(0x8da6_b343)
        ^ (iy as u32).wrapping_mul(0xd816_3841)
        ^ seed.wrapping_mul(0xcb1a_b31f);
    h ^= h >> 16;
    h = h.wrapping_mul(0x7feb_352d);
    h ^= h >> 15;
    h = h.wrapping_mul(0x846c_a68b);
    h ^ (h >> 16)
}

fn fade(t: f64) -> f64 {
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

/// Gradient noise at (x, y) in lattice units; zero on lattice points, within about [-1, 1].
pub fn gradient_noise(x: f64, y: f64, seed: u32) -> f64 {
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let (ix, iy) = (x0 as i64, y0 as i64);
    let ramp = |cx: i64, cy: i64, dx: f64, dy: f64| {
        let (gx, gy) = GRADIENTS[(hash(cx, cy, seed) >> 28) as usize];
        gx * dx + gy * dy
    };
    let n00 = ramp(ix, iy, fx, fy);
    let n10 = ramp(ix + 1, iy, fx - 1.0, fy);
    let n01 = ramp(ix, iy + 1, fx, fy - 1.0);
    let n11 = ramp(ix + 1, iy + 1, fx - 1.0, fy - 1.0);
    let (u, v) = (fade(fx), fade(fy));
    let bottom = n00 + u * (n10 - n00);
    let top = n01 + u * (n11 - n01);
    // Unit gradients bound 2-D noise by sqrt(1/2); scale to about [-1, 1].
    std::f64::consts::SQRT_2 * (bottom + v * (top - bottom))
}

/// Fractional Brownian motion: `octaves` layers of noise, each at twice the frequency and
/// `gain` times the amplitude of the last, normalised by the sum of amplitudes.
pub fn fbm(x: f64, y: f64, seed: u32, octaves: u32, gain: f64) -> f64 {
    let (mut sum, mut norm, mut amp, mut freq) = (0.0, 0.0, 1.0, 1.0);
    for o in 0..octaves {
        sum += amp * gradient_noise(x * freq, y * freq, seed.wrapping_add(o.wrapping_mul(0x9e37)));
        norm += amp;
        amp *= gain;
        freq *= 2.0;
    }
    if norm > 0.0 { sum / norm } else { 0.0 }
}

/// Ridged fractal noise: sharp crests where the noise crosses zero, in [0, 1].
pub fn ridged(x: f64, y: f64, seed: u32, octaves: u32, gain: f64) -> f64 {
    let (mut sum, mut norm, mut amp, mut freq) = (0.0, 0.0, 1.0, 1.0);
    for o in 0..octaves {
        let n = gradient_noise(x * freq, y * freq, seed.wrapping_add(o.wrapping_mul(0x7f4a)));
        let crest = 1.0 - n.abs().min(1.0);
        sum += amp * crest * crest;
        norm += amp;
        amp *= gain;
        freq *= 2.0;
    }
    if norm > 0.0 { sum / norm } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gradients_are_unit_and_distinct() {
        for (k, &(gx, gy)) in GRADIENTS.iter().enumerate() {
            let angle = k as f64 * std::f64::consts::PI / 8.0;
            assert!((gx - angle.cos()).abs() < 1e-12 && (gy - angle.sin()).abs() < 1e-12, "{k}");
        }
    }

    #[test]
    fn noise_is_zero_on_the_lattice_bounded_and_seeded() {
        let mut max: f64 = 0.0;
        let mut differs = false;
        for i in 0..2000 {
            let (x, y) = (i as f64 * 0.137 - 50.0, i as f64 * 0.291 - 120.0);
            let n = gradient_noise(x, y, 7);
            max = max.max(n.abs());
            differs |= (n - gradient_noise(x, y, 8)).abs() > 1e-6;
            assert_eq!(gradient_noise(x.floor(), y.floor(), 7), 0.0);
        }
        assert!(max <= 1.0 + 1e-9 && max > 0.3, "{max}");
        assert!(differs);
    }

    #[test]
    fn noise_is_continuous() {
        // Across a lattice line the value must not jump.
        let a = gradient_noise(2.999_999, 0.4, 3);
        let b = gradient_noise(3.000_001, 0.4, 3);
        assert!((a - b).abs() < 1e-4);
    }
}
