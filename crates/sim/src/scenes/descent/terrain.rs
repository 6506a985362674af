//! The ground under a descent sequence: the 1 m Gale DEM around the landing site where it is
//! given, fractal relief with Mars-like roughness at every scale elsewhere, and fractal detail
//! below the DEM's resolution everywhere (paper 002 section 4 asks for terrain seen from 8 km
//! down to 9 m; no single grid spans 10 m/pixel to 1 cm/pixel, so the ground is a function).
//!
//! Relief is fractional Brownian motion: octaves of seeded gradient noise
//! ([`rovernav_terrain::procedural::noise::gradient_noise`]) at wavelengths 8192 m / 2^k down to
//! about 8 mm, octave amplitude proportional to wavelength^H with Hurst exponent H = 0.8 (the
//! self-affine roughness reported for Mars at metre to kilometre baselines), scaled so that
//! height differences over 1 m have an RMS near 0.14 m (an RMS slope near 8 deg, the Gale DEM's
//! mean slope). Every query takes the shortest wavelength to include: an image renders the
//! ground band-limited to two of its pixels, so nothing finer than it can resolve aliases.
//! Albedo varies with its own fractal, nearly the same contrast at every scale (H = 0.1, 4 %
//! per octave at 1 m wavelength): dust, sand and rock differ in brightness at every scale.

use rovernav_terrain::Dem;
use rovernav_terrain::procedural::noise::gradient_noise;

/// Longest wavelength of the fractal (m).
const LONGEST_M: f64 = 8192.0;
/// Number of octaves (the shortest is `LONGEST_M / 2^(OCTAVES - 1)`, about 8 mm).
const OCTAVES: u32 = 21;
/// Hurst exponent of the relief.
const HURST: f64 = 0.8;
/// Relief amplitude: octave of wavelength L has amplitude `RELIEF_SCALE * L^HURST` (m); 0.12
/// gives 0.14 m RMS height differences over 1 m (checked by a test).
const RELIEF_SCALE: f64 = 0.12;
/// Shortest wavelength the 1 m DEM carries (m): finer octaves are added on top of it. A
/// stereo DEM posted at 1 m resolves about 3 posts (the correlation window smooths it), so
/// octaves from 2 m down are added.
const DEM_WAVELENGTH_M: f64 = 4.0;
/// Width of the blend from the DEM to procedural relief inside the DEM's edge (m).
const DEM_TAPER_M: f64 = 40.0;

/// The descent scene's ground: heights and albedo in a local frame whose origin is the
/// landing site (x east, y north, z up, z = 0 at the landing site's DEM height).
#[derive(Clone, Debug)]
pub struct DescentTerrain {
    /// Seed of the fractal relief and albedo.
    pub seed: u32,
    /// The real DEM (its local frame shifted so that its centre is the landing site).
    dem: Option<Dem>,
    /// DEM local coordinates of the landing site and its DEM height.
    dem_site: [f64; 3],
    /// Distance of each DEM cell from the nearest cell without data or the grid's edge
    /// (cells, chamfer 3-4 metric).
    edge_distance: Vec<f32>,
    /// Height of the long-wavelength fractal at the landing site (subtracted, so that the
    /// procedural ground meets the DEM near z = 0).
    fractal_site: f64,
}

impl DescentTerrain {
    /// Procedural ground only, deterministic for `seed`.
    pub fn procedural(seed: u32) -> Self {
        let mut t =
            Self { seed, dem: None, dem_site: [0.0; 3], edge_distance: Vec::new(), fractal_site: 0.0 };
        t.fractal_site = t.fractal(0.0, 0.0, DEM_WAVELENGTH_M, f64::INFINITY, 0.8, RELIEF_SCALE, 0);
        t
    }

    /// The DEM at the landing site (its centre) blended into procedural ground; `None` when
    /// the DEM has no height at its centre.
    pub fn with_dem(dem: Dem, seed: u32) -> Option<Self> {
        let g = *dem.geometry();
        let (cx, cy) = (g.origin_x + 0.5 * g.width_m(), g.origin_y + 0.5 * g.height_m());
        let z = catmull_rom(&dem, cx, cy)?;
        let mut t = Self::procedural(seed);
        t.edge_distance = edge_distance(&dem);
        t.dem = Some(dem);
        t.dem_site = [cx, cy, z];
        Some(t)
    }

    /// Sum of the octaves with wavelengths in `[min_m, max_m)` (each faded in over the octave
    /// above `min_m`), amplitude `scale * L^hurst`.
    #[allow(clippy::too_many_arguments)]
    fn fractal(&self, x: f64, y: f64, min_m: f64, max_m: f64, hurst: f64, scale: f64, salt: u32) -> f64 {
        let mut sum = 0.0;
        let mut wavelength = LONGEST_M;
        for k in 0..OCTAVES {
            if wavelength < min_m {
                break;
            }
            if wavelength < max_m {
                // Fade in between min and 2 min, so that the band limit moves smoothly.
                let w = ((wavelength / min_m) - 1.0).clamp(0.0, 1.0);
                // Each octave's lattice is rotated and offset, so that no grid lines align.
                let angle = 0.7 * k as f64 + 0.3;
                let (s, c) = angle.sin_cos();
                let (u, v) = ((c * x - s * y) / wavelength + 0.37 * k as f64, (s * x + c * y) / wavelength);
                let seed = self.seed.wrapping_mul(0x9e37_79b1).wrapping_add(salt).wrapping_add(k * 0x85eb);
                sum += w * scale * wavelength.powf(hurst) * gradient_noise(u, v, seed);
            }
            wavelength *= 0.5;
        }
        sum
    }

    /// Weight of the DEM at a point (1 well inside it, 0 outside) and its height there.
    fn dem_part(&self, x: f64, y: f64) -> Option<(f64, f64)> {
        let dem = self.dem.as_ref()?;
        let (dx, dy) = (x + self.dem_site[0], y + self.dem_site[1]);
        let z = catmull_rom(dem, dx, dy)? - self.dem_site[2];
        let g = dem.geometry();
        let edge = match g.cell_of(dx, dy) {
            Some((c, r)) => self.edge_distance[g.index(c, r)] as f64 * g.resolution,
            None => 0.0,
        };
        let t = (edge / DEM_TAPER_M).clamp(0.0, 1.0);
        Some((t * t * (3.0 - 2.0 * t), z))
    }

    /// Height at (x, y) with wavelengths shorter than `min_wavelength_m` left out (m).
    pub fn height(&self, x: f64, y: f64, min_wavelength_m: f64) -> f64 {
        let min = min_wavelength_m.max(1e-3);
        let fine = self.fractal(x, y, min, DEM_WAVELENGTH_M, HURST, RELIEF_SCALE, 0);
        let procedural =
            || self.fractal(x, y, min.max(DEM_WAVELENGTH_M), f64::INFINITY, HURST, RELIEF_SCALE, 0);
        let coarse = match self.dem_part(x, y) {
            Some((w, z)) if w >= 1.0 => z,
            Some((w, z)) => w * z + (1.0 - w) * (procedural() - self.fractal_site),
            None => procedural() - self.fractal_site,
        };
        coarse + fine
    }

    /// Albedo at (x, y), band-limited like [`DescentTerrain::height`].
    pub fn albedo(&self, x: f64, y: f64, min_wavelength_m: f64) -> f64 {
        let a = self.fractal(x, y, min_wavelength_m.max(1e-3), 2048.0, 0.1, 0.04, 0x5eed);
        0.25 * (1.0 + a.clamp(-0.6, 0.6))
    }

    /// Whether the DEM covers (x, y) (its weight is positive there).
    pub fn in_dem(&self, x: f64, y: f64) -> bool {
        self.dem_part(x, y).is_some_and(|(w, _)| w > 0.0)
    }
}

/// Each cell's distance (cells) from the nearest cell without data or outside the grid, by the
/// two-pass chamfer transform with weights 3 (side) and 4 (diagonal), divided by 3.
fn edge_distance(dem: &Dem) -> Vec<f32> {
    let g = dem.geometry();
    let (w, h) = (g.cols as isize, g.rows as isize);
    let mut d: Vec<f32> =
        dem.heights.data.iter().map(|v| if v.is_finite() { f32::MAX } else { 0.0 }).collect();
    let at = |d: &[f32], c: isize, r: isize| {
        if c < 0 || r < 0 || c >= w || r >= h { 0.0 } else { d[(r * w + c) as usize] }
    };
    let pass = |d: &mut Vec<f32>, order: &[(isize, isize, f32)], forward: bool| {
        for k in 0..w * h {
            let i = if forward { k } else { w * h - 1 - k };
            let (c, r) = (i % w, i / w);
            let mut best = d[i as usize];
            for &(dc, dr, cost) in order {
                best = best.min(at(d, c + dc, r + dr) + cost);
            }
            d[i as usize] = best;
        }
    };
    pass(&mut d, &[(-1, 0, 3.0), (-1, -1, 4.0), (0, -1, 3.0), (1, -1, 4.0)], true);
    pass(&mut d, &[(1, 0, 3.0), (1, 1, 4.0), (0, 1, 3.0), (-1, 1, 4.0)], false);
    d.iter().map(|v| v / 3.0).collect()
}

/// The DEM's height at a local point by Catmull-Rom interpolation between cell centres (the
/// slope is continuous, so shading shows no cell edges as bilinear facets would); `None`
/// outside the grid or next to a cell without data.
fn catmull_rom(dem: &Dem, x: f64, y: f64) -> Option<f64> {
    let g = dem.geometry();
    let (fx, fy) = ((x - g.origin_x) / g.resolution - 0.5, (y - g.origin_y) / g.resolution - 0.5);
    if !(fx >= 0.0 && fy >= 0.0 && fx <= (g.cols - 1) as f64 && fy <= (g.rows - 1) as f64) {
        return None;
    }
    let (c0, r0) = (fx.floor() as isize, fy.floor() as isize);
    let (tx, ty) = (fx - c0 as f64, fy - r0 as f64);
    let weights = |t: f64| {
        let (t2, t3) = (t * t, t * t * t);
        [
            0.5 * (-t3 + 2.0 * t2 - t),
            0.5 * (3.0 * t3 - 5.0 * t2 + 2.0),
            0.5 * (-3.0 * t3 + 4.0 * t2 + t),
            0.5 * (t3 - t2),
        ]
    };
    let (wx, wy) = (weights(tx), weights(ty));
    let mut sum = 0.0;
    for (j, wyj) in wy.iter().enumerate() {
        let r = (r0 + j as isize - 1).clamp(0, g.rows as isize - 1) as usize;
        for (i, wxi) in wx.iter().enumerate() {
            let c = (c0 + i as isize - 1).clamp(0, g.cols as isize - 1) as usize;
            let v = *dem.heights.get(c, r);
            if !v.is_finite() || dem.nodata == Some(v) {
                return None;
            }
            sum += wxi * wyj * v as f64;
        }
    }
    Some(sum)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn roughness_over_one_metre_is_mars_like_and_self_affine() {
        let t = DescentTerrain::procedural(7);
        let rms = |lag: f64| {
            let n = 400;
            let s: f64 = (0..n)
                .map(|k| {
                    let (x, y) = (37.1 * k as f64, -23.3 * k as f64);
                    (t.height(x + lag, y, 0.01) - t.height(x, y, 0.01)).powi(2)
                })
                .sum();
            (s / n as f64).sqrt()
        };
        let (r1, r16) = (rms(1.0), rms(16.0));
        assert!((0.08..0.25).contains(&r1), "RMS height difference over 1 m {r1:.3} m");
        // Self-affine: over 16x the lag the RMS difference grows by about 16^H = 9.2.
        let ratio = r16 / r1;
        assert!((5.0..14.0).contains(&ratio), "16 m / 1 m roughness ratio {ratio:.2}");
    }

    #[test]
    fn band_limit_removes_only_short_wavelengths() {
        let t = DescentTerrain::procedural(3);
        // Leaving out wavelengths below 8 m changes heights by about the 8 m octave amplitude.
        let mut worst: f64 = 0.0;
        for k in 0..50 {
            let (x, y) = (13.7 * k as f64, 5.1 * k as f64);
            worst = worst.max((t.height(x, y, 8.0) - t.height(x, y, 0.01)).abs());
        }
        assert!(worst > 0.01 && worst < 5.0, "largest change {worst:.3} m");
        assert!(t.albedo(1.0, 2.0, 0.1) > 0.0);
    }

    #[test]
    fn the_dem_sits_at_the_landing_site_and_its_interpolation_keeps_planes() {
        use rovernav_core::{Grid2, GridGeometry};
        let geometry = GridGeometry { cols: 200, rows: 200, resolution: 1.0, origin_x: 0.0, origin_y: 0.0 };
        let mut grid = Grid2::filled(geometry, 0f32);
        for r in 0..200 {
            for c in 0..200 {
                let (x, y) = geometry.center(c, r);
                *grid.get_mut(c, r) = (100.0 + 0.2 * x - 0.1 * y) as f32;
            }
        }
        let dem = Dem::from_grid(grid);
        // Catmull-Rom reproduces a plane between cell centres.
        let z = catmull_rom(&dem, 37.3, 81.9).unwrap();
        assert!((z - (100.0 + 0.2 * 37.3 - 0.1 * 81.9)).abs() < 1e-3, "{z}");
        assert!(catmull_rom(&dem, -3.0, 5.0).is_none());
        // Inside the taper the ground is the DEM (shifted to z = 0 at the site) plus fine detail.
        let t = DescentTerrain::with_dem(dem, 9).unwrap();
        let (x, y) = (20.0, -30.0);
        let expected = 0.2 * x - 0.1 * y;
        assert!((t.height(x, y, 2.0) - expected).abs() < 1e-3, "{} vs {expected}", t.height(x, y, 2.0));
        assert!((t.height(x, y, 0.01) - expected).abs() < 1.0);
        assert!(t.in_dem(x, y) && !t.in_dem(500.0, 0.0));
        // A cell without data: the DEM's weight falls to zero there and is full 40 m away.
        let mut holed = t.dem.clone().unwrap();
        *holed.heights.get_mut(150, 100) = f32::NAN;
        let t = DescentTerrain::with_dem(holed, 9).unwrap();
        assert_eq!(t.dem_part(50.5, 0.5).map(|(w, _)| w), None);
        assert!(t.dem_part(45.0, 0.5).is_some_and(|(w, _)| w > 0.0 && w < 0.1));
        assert_eq!(t.dem_part(0.0, 0.5).map(|(w, _)| w), Some(1.0));
    }
}
