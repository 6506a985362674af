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
        let cos_g = dir[0] * self.sun[0] + dir[1] * self.sun[1] + dir[2] * self.sun[2];
        let gamma = cos_g.clamp(-1.0, 1.0).acos();
        let brightness = if self.sun[2] > -0.1 { 1.0 } else { 0.01 };
        0.45 * brightness
            * (1.0 - (-self.atmosphere.tau).exp())
            * (0.3 + 0.7 * (-el / 0.3).exp())
            * (1.0 + 2.0 * (-gamma / 0.2).exp())
    }

    /// A surface radiance `l` seen at distance `d` along `dir`, through the dust.
    pub fn aerial(&self, l: f64, d: f64, dir: [f64; 3]) -> f64 {
        let t = (-self.atmosphere.tau * d / self.atmosphere.scale_height_m).exp();
        let horizon = [dir[0], dir[1], 0.0];
        let n = (horizon[0] * horizon[0] + horizon[1] * horizon[1]).sqrt().max(1e-9);
        l * t + self.sky([horizon[0] / n, horizon[1] / n, 0.0]) * (1.0 - t)
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

/// Slope (dz/dx, dz/dy) of the millimetre-scale roughness of rock `index` at (x, y): bumps a
/// few millimetres high that the 5 cm DEM cannot hold, band-limited like the albedo.
pub fn rock_roughness(index: usize, x: f64, y: f64, footprint: f64) -> (f64, f64) {
    const AMPLITUDE_M: f64 = 0.006;
    let e = footprint.max(0.003);
    let salt = 2048 + index as u64 % 1024;
    let f = |u: f64, v: f64| AMPLITUDE_M * fractal(u, v, footprint, salt);
    ((f(x + e, y) - f(x - e, y)) / (2.0 * e), (f(x, y + e) - f(x, y - e)) / (2.0 * e))
}

/// Band-limited fractal noise in about [-1, 1], zero mean.
fn fractal(x: f64, y: f64, footprint: f64, salt: u64) -> f64 {
    let (mut sum, mut norm) = (0.0, 0.0);
    let mut lambda = WAVELENGTH_MIN;
    for k in 0..OCTAVES {
        // Amplitude grows slowly with wavelength: fine grain as visible as large patches.
        let amp = lambda.powf(0.15);
        norm += amp;
        let w = (lambda / footprint.max(1e-9) - 1.0).clamp(0.0, 1.0);
        if w > 0.0 {
            sum +=
                amp * w * value_noise(x / lambda, y / lambda, salt.wrapping_mul(31).wrapping_add(k as u64));
        }
        lambda *= 2.0;
    }
    1.6 * sum / norm
}

/// Smoothly interpolated lattice noise in [-1, 1].
fn value_noise(u: f64, v: f64, salt: u64) -> f64 {
    let (fu, fv) = (u.floor(), v.floor());
    let (iu, iv) = (fu as i64, fv as i64);
    let (su, sv) = (smooth(u - fu), smooth(v - fv));
    let h = |a: i64, b: i64| 2.0 * unit_hash(a, b, salt) - 1.0;
    let top = h(iu, iv) + (h(iu + 1, iv) - h(iu, iv)) * su;
    let bottom = h(iu, iv + 1) + (h(iu + 1, iv + 1) - h(iu, iv + 1)) * su;
    top + (bottom - top) * sv
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
