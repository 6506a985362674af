//! Rock fields with the size-frequency distribution of Mars landing sites.
//!
//! Golombek and Rapp (1997) fit the cumulative fractional area covered by rocks of diameter D
//! or larger as F(D) = k exp(-q(k) D), with q(k) = 1.79 + 0.152 / k and k the total rock
//! abundance (k = 0.16 at the Viking Lander 1 site, about 0.2 at Pathfinder's). Differentiating,
//! the number of rocks per unit area and unit diameter is
//! dN/dD = -F'(D) / (pi D^2 / 4) = k q exp(-q D) / (pi D^2 / 4).
//! Rocks are modelled as half-ellipsoids (domes) of height about half their diameter (Golombek
//! et al., 2003), sitting on the ground: their heights are added to the DEM.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Poisson};

use crate::dem::{Dem, Rock};
use crate::ops::LocalRect;

/// Parameters of a rock field.
#[derive(Clone, Debug, PartialEq)]
pub struct RockFieldParams {
    /// Total rock abundance k: fractional area covered by rocks of all sizes.
    pub abundance: f64,
    /// Smallest rock diameter modelled (m).
    pub min_diameter_m: f64,
    /// Largest rock diameter modelled (m).
    pub max_diameter_m: f64,
    /// Smallest height/diameter ratio (heights are uniform between the two ratios).
    pub height_ratio_min: f64,
    /// Largest height/diameter ratio.
    pub height_ratio_max: f64,
}

impl Default for RockFieldParams {
    fn default() -> Self {
        Self {
            abundance: 0.16,
            min_diameter_m: 0.1,
            max_diameter_m: 2.0,
            height_ratio_min: 0.4,
            height_ratio_max: 0.6,
        }
    }
}

/// A disc kept free of rocks (e.g. around a mission's start and goal).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClearPad {
    /// Centre east (local m).
    pub x: f64,
    /// Centre north (local m).
    pub y: f64,
    /// Radius no part of a rock may enter (m).
    pub radius: f64,
}

/// Golombek-Rapp exponent q(k) = 1.79 + 0.152 / k (1/m).
pub fn golombek_q(abundance: f64) -> f64 {
    1.79 + 0.152 / abundance
}

/// Cumulative fractional area F(D) = k exp(-q(k) D) of rocks of diameter D or larger.
pub fn cumulative_fractional_area(abundance: f64, diameter: f64) -> f64 {
    abundance * (-golombek_q(abundance) * diameter).exp()
}

impl RockFieldParams {
    /// Expected number of rocks per square metre with diameters in [min, max].
    pub fn expected_density(&self) -> f64 {
        let k = self.abundance;
        let (a, b) = (self.min_diameter_m, self.max_diameter_m);
        if !(k > 0.0 && a > 0.0 && b > a && k.is_finite() && b.is_finite()) {
            return 0.0;
        }
        let q = golombek_q(k);
        // With t = 1/D the integral of exp(-q D) / D^2 over [a, b] becomes the integral of
        // exp(-q / t) over [1/b, 1/a], a smooth integrand: composite Simpson is exact enough.
        let (t0, t1) = (1.0 / b, 1.0 / a);
        let n = 2000;
        let h = (t1 - t0) / n as f64;
        let f = |t: f64| (-q / t).exp();
        let mut sum = f(t0) + f(t1);
        for i in 1..n {
            sum += f(t0 + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
        }
        let integral = sum * h / 3.0;
        k * q * integral * 4.0 / std::f64::consts::PI
    }

    /// One rock diameter from dN/dD restricted to [min, max]: a draw from the 1/D^2 part by
    /// inverting its distribution function, kept with probability exp(-q (D - min)).
    fn sample_diameter(&self, q: f64, rng: &mut impl Rng) -> f64 {
        let (a, b) = (self.min_diameter_m, self.max_diameter_m);
        loop {
            let u: f64 = rng.random();
            let d = 1.0 / (1.0 / a - u * (1.0 / a - 1.0 / b));
            if rng.random::<f64>() < (-q * (d - a)).exp() {
                return d;
            }
        }
    }
}

/// Samples the rocks whose centres fall in `area`: a Poisson number of them at the expected
/// density, centres uniform, diameters from dN/dD, heights a uniform fraction of the diameter.
/// Rocks reaching into a clear pad are dropped.
pub fn sample_rocks(
    params: &RockFieldParams,
    area: LocalRect,
    pads: &[ClearPad],
    rng: &mut impl Rng,
) -> Vec<Rock> {
    let width = area.x_max - area.x_min;
    let height = area.y_max - area.y_min;
    let lambda = params.expected_density() * width.max(0.0) * height.max(0.0);
    if !(lambda > 0.0 && lambda.is_finite()) {
        return Vec::new();
    }
    let count = match Poisson::new(lambda) {
        Ok(p) => p.sample(rng) as usize,
        Err(_) => return Vec::new(),
    };
    let q = golombek_q(params.abundance);
    let (r_lo, r_hi) = (params.height_ratio_min, params.height_ratio_max.max(params.height_ratio_min));
    let mut rocks = Vec::with_capacity(count);
    for _ in 0..count {
        let x = area.x_min + rng.random::<f64>() * width;
        let y = area.y_min + rng.random::<f64>() * height;
        let diameter = params.sample_diameter(q, rng);
        let ratio = r_lo + rng.random::<f64>() * (r_hi - r_lo);
        let clear = pads.iter().all(|p| (x - p.x).hypot(y - p.y) >= p.radius + 0.5 * diameter);
        if clear {
            rocks.push(Rock { x, y, diameter, height: ratio * diameter });
        }
    }
    rocks
}

/// `sample_rocks` with a ChaCha8 generator seeded from `seed`.
pub fn sample_rocks_seeded(
    params: &RockFieldParams,
    area: LocalRect,
    pads: &[ClearPad],
    seed: u64,
) -> Vec<Rock> {
    sample_rocks(params, area, pads, &mut ChaCha8Rng::seed_from_u64(seed))
}

/// Adds rocks to a DEM as half-ellipsoid domes, z = h sqrt(1 - (r / R)^2) inside radius R;
/// where rocks overlap the taller dome wins, so touching rocks do not stack.
pub fn add_rocks(dem: &mut Dem, rocks: &[Rock]) {
    let g = dem.heights.geometry;
    if g.is_empty() || rocks.is_empty() {
        return;
    }
    let mut bump = vec![0.0f32; g.len()];
    let inv_res = 1.0 / g.resolution;
    for rock in rocks {
        let radius = 0.5 * rock.diameter;
        if !(radius > 0.0 && rock.height > 0.0) {
            continue;
        }
        // Cells whose centres may lie within the footprint.
        let col_lo = ((rock.x - radius - g.origin_x) * inv_res - 0.5).ceil().max(0.0);
        let col_hi = ((rock.x + radius - g.origin_x) * inv_res - 0.5).floor().min(g.cols as f64 - 1.0);
        let row_lo = ((rock.y - radius - g.origin_y) * inv_res - 0.5).ceil().max(0.0);
        let row_hi = ((rock.y + radius - g.origin_y) * inv_res - 0.5).floor().min(g.rows as f64 - 1.0);
        if col_hi < col_lo || row_hi < row_lo {
            continue;
        }
        let inv_r2 = 1.0 / (radius * radius);
        for row in row_lo as usize..=row_hi as usize {
            let dy = g.origin_y + (row as f64 + 0.5) * g.resolution - rock.y;
            let base = row * g.cols;
            for col in col_lo as usize..=col_hi as usize {
                let dx = g.origin_x + (col as f64 + 0.5) * g.resolution - rock.x;
                let s = 1.0 - (dx * dx + dy * dy) * inv_r2;
                if s > 0.0 {
                    let z = (rock.height * s.sqrt()) as f32;
                    let cell = &mut bump[base + col];
                    if z > *cell {
                        *cell = z;
                    }
                }
            }
        }
    }
    for (h, b) in dem.heights.data.iter_mut().zip(bump) {
        *h += b;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn q_and_fractional_area_match_golombek_rapp() {
        // k = 0.16 (Viking 1): q = 1.79 + 0.95 = 2.74.
        assert!((golombek_q(0.16) - 2.74).abs() < 1e-12);
        assert!((cumulative_fractional_area(0.16, 0.0) - 0.16).abs() < 1e-12);
        assert!((cumulative_fractional_area(0.16, 1.0) - 0.16 * (-2.74f64).exp()).abs() < 1e-12);
    }

    #[test]
    fn expected_density_matches_an_independent_quadrature() {
        // Midpoint rule directly on dN/dD over [0.1, 2] with a fine step.
        let p = RockFieldParams::default();
        let q = golombek_q(p.abundance);
        let n = 400_000;
        let h = (p.max_diameter_m - p.min_diameter_m) / n as f64;
        let direct: f64 = (0..n)
            .map(|i| {
                let d = p.min_diameter_m + (i as f64 + 0.5) * h;
                p.abundance * q * (-q * d).exp() / (std::f64::consts::PI * d * d / 4.0) * h
            })
            .sum();
        assert!(
            (p.expected_density() - direct).abs() < 1e-6 * direct,
            "{} vs {direct}",
            p.expected_density()
        );
    }

    #[test]
    fn dome_heights_follow_the_ellipsoid() {
        let mut dem = Dem::flat(40, 40, 0.05, 1.0);
        let rock = Rock { x: 1.025, y: 1.025, diameter: 0.8, height: 0.4 };
        add_rocks(&mut dem, &[rock]);
        // The rock centre is a cell centre: full height there.
        let (c, r) = dem.geometry().cell_of(rock.x, rock.y).unwrap();
        assert!((*dem.heights.get(c, r) - 1.4).abs() < 1e-6);
        // 0.2 m east (half the radius): h sqrt(1 - 1/4).
        assert!((*dem.heights.get(c + 4, r) as f64 - (1.0 + 0.4 * 0.75f64.sqrt())).abs() < 1e-6);
        // Outside the footprint, bare ground.
        assert_eq!(*dem.heights.get(c + 9, r), 1.0);
    }

    #[test]
    fn pads_stay_clear() {
        let pads = [ClearPad { x: 5.0, y: 5.0, radius: 1.5 }];
        let area = LocalRect::from_corner_size(0.0, 0.0, 10.0, 10.0);
        let rocks = sample_rocks_seeded(&RockFieldParams::default(), area, &pads, 3);
        assert!(rocks.len() > 100);
        for r in &rocks {
            assert!((r.x - 5.0).hypot(r.y - 5.0) >= 1.5 + r.diameter / 2.0);
        }
    }
}
