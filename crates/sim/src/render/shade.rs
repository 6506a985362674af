//! Light: surface albedo texture, the sky, the dusty atmosphere and Lambertian shading.
//!
//! Radiances are radiance factors I/F (`pi L / F_sun`, the unit of rover image calibration:
//! a Lambertian surface of albedo `a` lit at incidence `i` without an atmosphere has
//! `I/F = a cos i`).
//!
//! - Surfaces are Lambertian. Hapke's model (Hapke 1981) fits Martian soil better near
//!   opposition and at grazing angles, but its parameters for a procedural yard are unknown and
//!   the stereo correlator is insensitive to the mild view dependence; Lambert keeps the
//!   renderer exact and cheap. Departure: no opposition surge, no phase dependence.
//! - Direct sunlight reaches the ground attenuated by the dust column: transmission
//!   `T = exp(-tau / sin e)` (Beer's law, plane-parallel atmosphere, sun elevation `e`).
//!   Diffuse sky light, from the light the dust scatters: `E_d = f sin e (1 - T)` with a fraction
//!   `f` of it reaching the ground (forward-scattering dust: `f = 0.7`, assumed), weighted by
//!   the sky-view factor `(1 + n_z) / 2` of the surface. So a shadow is lit by `E_d` alone.
//! - The sky (no radiative transfer; an empirical shape fit to what MER Navcam and Pancam sky
//!   images show): `S = A (1 - exp(-tau)) (0.3 + 0.7 exp(-el / 0.3)) (1 + 2 exp(-gamma / 0.2))`,
//!   `el` the elevation of the line of sight, `gamma` its angle from the sun (rad), `A = 0.45`:
//!   brightest at the horizon and around the sun, darker towards the zenith, and brighter
//!   with more dust.
//! - Aerial perspective: a surface at distance `d` is seen through `exp(-tau d / H)` of the
//!   dust (scale height `H`, 11.1 km on Mars) and the rest of its pixel is the horizon sky:
//!   `L = L_s exp(-tau d / H) + S(horizon) (1 - exp(-tau d / H))`.
//! - Albedo texture: multi-octave value noise in world coordinates (wavelengths 4 mm to 4 m),
//!   band-limited per pixel: an octave shorter than twice the pixel's ground footprint fades
//!   out (to its mean, so the mean albedo is kept), which avoids aliasing without
//!   supersampling. Rocks have their own darker albedo with a per-rock variation.

use rovernav_terrain::Rock;

use super::sun::Sun;

/// Mars' atmospheric scale height (m).
pub const MARS_SCALE_HEIGHT_M: f64 = 11_100.0;

/// The dusty atmosphere.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Atmosphere {
    /// Normal optical depth of the dust column (MER sites: 0.3 to 1 outside dust storms).
    pub tau: f64,
    /// Extinction scale height for horizontal paths (m).
    pub scale_height_m: f64,
    /// Fraction of the scattered sunlight that reaches the ground as diffuse light.
    pub diffuse_fraction: f64,
}

impl Default for Atmosphere {
    fn default() -> Self {
        Self { tau: 0.5, scale_height_m: MARS_SCALE_HEIGHT_M, diffuse_fraction: 0.7 }
    }
}

/// The sun and the atmosphere together: everything that lights the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lighting {
    /// Unit vector towards the sun (world).
    pub sun: [f64; 3],
    /// Direct-beam transmission of the dust column.
    pub direct: f64,
    /// Diffuse irradiance on a horizontal surface (I/F units).
    pub diffuse: f64,
    /// The atmosphere.
    pub atmosphere: Atmosphere,
}

impl Lighting {
    /// The lighting of a sun through an atmosphere.
    pub fn new(sun: &Sun, atmosphere: Atmosphere) -> Self {
        let dir = sun.direction();
        let s = sun.elevation.sin();
        let (direct, diffuse) = if s > 1e-3 {
            let t = (-atmosphere.tau / s).exp();
            (t, atmosphere.diffuse_fraction * s * (1.0 - t))
        } else {
            // Twilight: a little diffuse light only.
            (0.0, 0.002)
        };
        Self { sun: dir, direct, diffuse, atmosphere }
    }

    /// Radiance factor of a Lambertian surface with albedo `albedo` and unit normal `n`, lit by
    /// the sun unless `shadowed`.
    pub fn surface(&self, albedo: f64, n: [f64; 3], shadowed: bool) -> f64 {
        let cos_i = n[0] * self.sun[0] + n[1] * self.sun[1] + n[2] * self.sun[2];
        let direct = if shadowed || cos_i <= 0.0 { 0.0 } else { cos_i * self.direct };
        albedo * (direct + self.diffuse * 0.5 * (1.0 + n[2]))
    }

    /// Sky radiance factor along the unit direction `dir`.
    pub fn sky(&self, dir: [f64; 3]) -> f64 {
        let el = dir[2].clamp(0.0, 1.0).asin();
        self.sky_at(el, dir[0] * self.sun[0] + dir[1] * self.sun[1] + dir[2] * self.sun[2])
    }

    /// A surface radiance `l` seen at distance `d` along `dir`, through the dust.
    pub fn aerial(&self, l: f64, d: f64, dir: [f64; 3]) -> f64 {
        let t = (-self.atmosphere.tau * d / self.atmosphere.scale_height_m).exp();
        if t >= 1.0 {
            return l;
        }
        // The sky at the horizon in the ray's azimuth (elevation 0 in `sky`).
        let n = (dir[0] * dir[0] + dir[1] * dir[1]).sqrt().max(1e-9);
        let cos_g = (dir[0] * self.sun[0] + dir[1] * self.sun[1]) / n;
        let horizon = self.sky_at(0.0, cos_g);
        l * t + horizon * (1.0 - t)
    }

    /// Sky radiance factor at elevation `el` (rad) and cosine `cos_g` of the angle to the sun.
    fn sky_at(&self, el: f64, cos_g: f64) -> f64 {
        let gamma = cos_g.clamp(-1.0, 1.0).acos();
        let brightness = if self.sun[2] > -0.1 { 1.0 } else { 0.01 };
        0.45 * brightness
            * (1.0 - (-self.atmosphere.tau).exp())
            * (0.3 + 0.7 * (-el / 0.3).exp())
            * (1.0 + 2.0 * (-gamma / 0.2).exp())
    }
}

/// Shortest and longest texture wavelengths (m).
const WAVELENGTH_MIN: f64 = 0.004;
const OCTAVES: usize = 11;
/// Mean albedo of the soil and of rocks.
const SOIL_ALBEDO: f64 = 0.24;
const ROCK_ALBEDO: f64 = 0.16;

/// Soil albedo at world point (x, y) for a pixel footprint of `footprint` metres.
pub fn soil_albedo(x: f64, y: f64, footprint: f64) -> f64 {
    SOIL_ALBEDO * (1.0 + 0.6 * fractal(x, y, footprint, 0))
}

/// Albedo of rock `index` at world point (x, y) for a pixel footprint of `footprint` metres.
pub fn rock_albedo(rock: &Rock, index: usize, x: f64, y: f64, footprint: f64) -> f64 {
    let own = 0.75 + 0.5 * unit_hash(index as i64, 7, 99);
    // Coarser grain than the soil, and dust settled on top (brighter where the rock is low).
    ROCK_ALBEDO * own * (1.0 + 0.35 * fractal(x - rock.x, y - rock.y, footprint, 1 + index as u64 % 1024))
}

/// Slope (dz/dx, dz/dy) of the millimetre-scale roughness of rock `index` at (x, y): bumps
/// that the 5 cm DEM cannot hold (wavelengths 4 to 64 mm, self-similar: the same slope at
/// every scale), band-limited like the albedo.
pub fn rock_roughness(index: usize, x: f64, y: f64, footprint: f64) -> (f64, f64) {
    const SLOPE_PER_OCTAVE: f64 = 0.12;
    let salt = 2048 + index as u64 % 1024;
    let (mut gx, mut gy) = (0.0, 0.0);
    let mut lambda = WAVELENGTH_MIN;
    for k in 0..5 {
        let w = (lambda / footprint.max(1e-9) - 1.0).clamp(0.0, 1.0);
        if w > 0.0 {
            // Height SLOPE * lambda * n(x / lambda): its gradient is SLOPE * grad n.
            let (_, du, dv) = value_noise_grad(x / lambda, y / lambda, salt.wrapping_mul(31).wrapping_add(k));
            gx += SLOPE_PER_OCTAVE * w * du;
            gy += SLOPE_PER_OCTAVE * w * dv;
        }
        lambda *= 2.0;
    }
    (gx, gy)
}

/// Per-octave amplitudes of [`fractal`] and their sum.
static AMPLITUDES: std::sync::LazyLock<([f64; OCTAVES], f64)> = std::sync::LazyLock::new(|| {
    let mut a = [0.0; OCTAVES];
    for (k, v) in a.iter_mut().enumerate() {
        // Amplitude grows slowly with wavelength: fine grain as visible as large patches.
        *v = (WAVELENGTH_MIN * 2f64.powi(k as i32)).powf(0.15);
    }
    (a, a.iter().sum())
});

/// Band-limited fractal noise in about [-1, 1], zero mean.
fn fractal(x: f64, y: f64, footprint: f64, salt: u64) -> f64 {
    let (amps, norm) = &*AMPLITUDES;
    let mut sum = 0.0;
    let mut lambda = WAVELENGTH_MIN;
    for (k, amp) in amps.iter().enumerate() {
        let w = (lambda / footprint.max(1e-9) - 1.0).clamp(0.0, 1.0);
        if w > 0.0 {
            let (n, _, _) =
                value_noise_grad(x / lambda, y / lambda, salt.wrapping_mul(31).wrapping_add(k as u64));
            sum += amp * w * n;
        }
        lambda *= 2.0;
    }
    1.6 * sum / norm
}

/// Lattice size of the noise tables (the finest octave repeats every 4096 wavelengths: 16 m).
const LATTICE: usize = 4096;

/// A permutation of the lattice indices and a random value in [-1, 1] per index (Perlin's
/// table-driven lattice: two look-ups per corner instead of a 64-bit hash).
static TABLES: std::sync::LazyLock<(Vec<u16>, Vec<f32>)> = std::sync::LazyLock::new(|| {
    let mut perm: Vec<u16> = (0..LATTICE as u16).collect();
    let mut values = Vec::with_capacity(LATTICE);
    for i in 0..LATTICE {
        perm.swap(i, i + (unit_hash(i as i64, 1, 5) * (LATTICE - i) as f64) as usize);
        values.push((2.0 * unit_hash(i as i64, 2, 5) - 1.0) as f32);
    }
    (perm, values)
});

/// Smoothly interpolated lattice noise in [-1, 1] and its gradient (d/du, d/dv).
fn value_noise_grad(u: f64, v: f64, salt: u64) -> (f64, f64, f64) {
    let (perm, values) = &*TABLES;
    let (fu, fv) = (fast_floor(u), fast_floor(v));
    let mask = LATTICE as i64 - 1;
    // Each salt shifts the lattice, so octaves and rocks do not share a pattern.
    let (iu, iv) = (fu as i64 + (salt as i64 * 1327), fv as i64 + (salt as i64 * 2131));
    let (tu, tv) = (u - fu, v - fv);
    let (su, sv) = (smooth(tu), smooth(tv));
    let (dsu, dsv) = (6.0 * tu * (1.0 - tu), 6.0 * tv * (1.0 - tv));
    let col = |a: i64| perm[(a & mask) as usize] as i64;
    let (c0, c1) = (col(iu), col(iu + 1));
    let h = |c: i64, b: i64| values[perm[((c + b) & mask) as usize] as usize] as f64;
    let (h00, h10, h01, h11) = (h(c0, iv), h(c1, iv), h(c0, iv + 1), h(c1, iv + 1));
    let top = h00 + (h10 - h00) * su;
    let bottom = h01 + (h11 - h01) * su;
    let value = top + (bottom - top) * sv;
    let du = ((h10 - h00) + (h11 - h01 - h10 + h00) * sv) * dsu;
    let dv = (bottom - top) * dsv;
    (value, du, dv)
}

/// `floor` without the libm call (the baseline x86-64 target has no rounding instruction).
fn fast_floor(x: f64) -> f64 {
    let t = x as i64 as f64;
    if t > x { t - 1.0 } else { t }
}

fn smooth(t: f64) -> f64 {
    t * t * (3.0 - 2.0 * t)
}

/// A hash of a lattice point to [0, 1).
fn unit_hash(a: i64, b: i64, salt: u64) -> f64 {
    let mut h = (a as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (b as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
        ^ salt.wrapping_mul(0x1656_67B1_9E37_79F9);
    h ^= h >> 31;
    h = h.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    h ^= h >> 29;
    h = h.wrapping_mul(0x94D0_49BB_1331_11EB);
    h ^= h >> 32;
    (h >> 11) as f64 / (1u64 << 53) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_gradient_matches_finite_differences() {
        for &(u, v) in &[(0.3, 0.7), (12.9, -3.2), (-7.45, 100.01)] {
            let (_, du, dv) = value_noise_grad(u, v, 9);
            let e = 1e-6;
            let fd_u = (value_noise_grad(u + e, v, 9).0 - value_noise_grad(u - e, v, 9).0) / (2.0 * e);
            let fd_v = (value_noise_grad(u, v + e, 9).0 - value_noise_grad(u, v - e, 9).0) / (2.0 * e);
            assert!((du - fd_u).abs() < 1e-6 && (dv - fd_v).abs() < 1e-6, "{du} {fd_u} {dv} {fd_v}");
        }
    }

    #[test]
    fn band_limiting_keeps_the_mean_and_removes_fine_detail() {
        let n = 20_000;
        let sample = |footprint: f64| -> (f64, f64) {
            let v: Vec<f64> = (0..n)
                .map(|i| soil_albedo(i as f64 * 0.0137, (i as f64 * 0.731).sin() * 40.0, footprint))
                .collect();
            let m = v.iter().sum::<f64>() / n as f64;
            (m, (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / n as f64).sqrt())
        };
        let (m_fine, s_fine) = sample(0.001);
        let (m_coarse, s_coarse) = sample(0.5);
        assert!((m_fine - SOIL_ALBEDO).abs() < 0.01 && (m_coarse - SOIL_ALBEDO).abs() < 0.01);
        assert!(s_coarse < 0.8 * s_fine, "{s_coarse} vs {s_fine}");
    }

    #[test]
    fn sky_falls_with_elevation_and_shadows_keep_diffuse_light() {
        let sun = Sun::at(14.0, -14.6, 0.0);
        let lit = Lighting::new(&sun, Atmosphere::default());
        let away = [-lit.sun[0], -lit.sun[1]];
        let n = away[0].hypot(away[1]);
        let mut last = f64::INFINITY;
        for el in [0.0f64, 0.2, 0.5, 0.8] {
            let s = lit.sky([away[0] / n * el.cos(), away[1] / n * el.cos(), el.sin()]);
            assert!(s < last);
            last = s;
        }
        let up = [0.0, 0.0, 1.0];
        let (bright, dark) = (lit.surface(0.25, up, false), lit.surface(0.25, up, true));
        assert!(dark > 0.0 && dark < 0.6 * bright);
    }
}
