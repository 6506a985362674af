//! Procedural Mars terrain from a seed: a test yard like the JPL MarsYard where paper 000
//! (Laubach et al., sections 1-2) tested Rocky 7, "an outdoor testing arena featuring simulated
//! martian terrain" whose rocks the stereo step/slope model turns into obstacles.
//!
//! The height field is the sum of
//! - fractal relief: fBm of gradient noise (`noise`), amplitude and roughness (per-octave gain);
//! - ridges: ridged noise stretched along an azimuth;
//! - a regional slope (a tilted plane);
//! - craters: a size-frequency law N(>D) ~ D^-2, each a parabolic bowl of depth 0.2 D inside
//!   a rim of height 0.04 D that falls off as r^-3 outside (fresh simple craters);
//! - rocks: Golombek-Rapp size-frequency distribution, half-ellipsoid domes (`rocks`).
//!
//! `rocky_region` puts the same kind of rock field on a real DEM (e.g. the Gale mission DEM).

pub mod noise;
pub mod rocks;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Poisson};
use rovernav_core::{Grid2, GridGeometry};

pub use rocks::{
    ClearPad, RockFieldParams, add_rocks, cumulative_fractional_area, golombek_q, sample_rocks,
    sample_rocks_seeded,
};

use crate::dem::{Dem, GeoReference, Rock, Terrain};
use crate::ops::{DemError, LocalRect};

/// Largest grid `generate` builds (cells); larger requests are clamped in resolution.
pub const MAX_GENERATED_CELLS: usize = 50_000_000;

/// Parameters of a procedural Mars yard.
#[derive(Clone, Debug, PartialEq)]
pub struct MarsYardParams {
    /// Extent east-west (m).
    pub width_m: f64,
    /// Extent south-north (m).
    pub height_m: f64,
    /// Cell size (m).
    pub resolution: f64,
    /// Seed of every random choice.
    pub seed: u64,
    /// Amplitude of the fractal relief (m): the fBm sum lies within about +- this.
    pub relief_amplitude_m: f64,
    /// Wavelength of the largest relief features (m).
    pub relief_wavelength_m: f64,
    /// Roughness: amplitude ratio between successive octaves (0..1; 0.5 is Brownian-like).
    pub roughness: f64,
    /// Number of relief octaves (each halves the wavelength).
    pub relief_octaves: u32,
    /// Craters per square metre with diameter at least `crater_min_diameter_m`.
    pub crater_density: f64,
    /// Smallest crater diameter (m).
    pub crater_min_diameter_m: f64,
    /// Largest crater diameter (m).
    pub crater_max_diameter_m: f64,
    /// Height of the ridges (m).
    pub ridge_amplitude_m: f64,
    /// Spacing of the ridges across their direction (m).
    pub ridge_wavelength_m: f64,
    /// Direction the ridge crests run (deg counter-clockwise from east).
    pub ridge_azimuth_deg: f64,
    /// Regional slope (deg).
    pub regional_slope_deg: f64,
    /// Uphill direction of the regional slope (deg counter-clockwise from east).
    pub slope_azimuth_deg: f64,
    /// The rock field.
    pub rocks: RockFieldParams,
    /// Discs kept free of rocks (start and goal of a mission).
    pub clear_pads: Vec<ClearPad>,
}

impl Default for MarsYardParams {
    /// A 30 m x 30 m yard at 5 cm: gentle relief, a few craters, Viking-1 rock abundance.
    fn default() -> Self {
        Self {
            width_m: 30.0,
            height_m: 30.0,
            resolution: 0.05,
            seed: 0,
            relief_amplitude_m: 0.3,
            relief_wavelength_m: 12.0,
            roughness: 0.5,
            relief_octaves: 6,
            crater_density: 0.004,
            crater_min_diameter_m: 1.0,
            crater_max_diameter_m: 8.0,
            ridge_amplitude_m: 0.15,
            ridge_wavelength_m: 9.0,
            ridge_azimuth_deg: 30.0,
            regional_slope_deg: 2.0,
            slope_azimuth_deg: 0.0,
            rocks: RockFieldParams::default(),
            clear_pads: Vec::new(),
        }
    }
}

impl MarsYardParams {
    /// The default yard with a given seed.
    pub fn with_seed(seed: u64) -> Self {
        Self { seed, ..Self::default() }
    }

    /// Adds a rock-free disc around a point (builder style).
    pub fn clear_around(mut self, x: f64, y: f64, radius: f64) -> Self {
        self.clear_pads.push(ClearPad { x, y, radius });
        self
    }
}

/// A crater: centre, diameter, depth below and rim height above the surroundings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Crater {
    /// Centre east (local m).
    pub x: f64,
    /// Centre north (local m).
    pub y: f64,
    /// Rim-to-rim diameter (m).
    pub diameter: f64,
}

impl Crater {
    /// Depth of the floor below the pre-impact surface: 0.2 D.
    pub fn depth(&self) -> f64 {
        0.2 * self.diameter
    }

    /// Rim height above the pre-impact surface: 0.04 D.
    pub fn rim_height(&self) -> f64 {
        0.04 * self.diameter
    }

    /// Outer radius of the ejecta blanket, where the rim profile reaches zero.
    pub fn reach(&self) -> f64 {
        CRATER_REACH * 0.5 * self.diameter
    }

    /// Height change at distance `dist` from the centre.
    pub fn profile(&self, dist: f64) -> f64 {
        let rel = dist / (0.5 * self.diameter);
        let (depth, rim) = (self.depth(), self.rim_height());
        if rel < 1.0 {
            // Parabolic bowl from -depth at the centre up to the rim crest.
            (rim + depth) * rel * rel - depth
        } else if rel < CRATER_REACH {
            // Ejecta falling off as r^-3, shifted to reach zero at the blanket's edge.
            let edge = CRATER_REACH.powi(-3);
            rim * (rel.powi(-3) - edge) / (1.0 - edge)
        } else {
            0.0
        }
    }
}

/// Distance, in crater radii, a crater's centre keeps from a clear pad's edge: beyond 1.5 radii
/// the ejecta rises at most 1 % of the diameter.
pub(crate) const PAD_CRATER_CLEARANCE: f64 = 1.5;

/// Ejecta blanket radius in crater radii.
const CRATER_REACH: f64 = 2.5;

/// Samples craters whose influence reaches `area`: Poisson count, N(>D) ~ D^-2 between the
/// diameter bounds (inverse of the truncated Pareto distribution function).
pub fn sample_craters(params: &MarsYardParams, area: LocalRect, rng: &mut impl Rng) -> Vec<Crater> {
    let (d_min, d_max) = (params.crater_min_diameter_m, params.crater_max_diameter_m);
    if !(params.crater_density > 0.0 && d_min > 0.0 && d_max > d_min) {
        return Vec::new();
    }
    // Craters centred up to one blanket radius outside the area still shape its edges.
    let margin = CRATER_REACH * 0.5 * d_max;
    let (w, h) = (area.x_max - area.x_min + 2.0 * margin, area.y_max - area.y_min + 2.0 * margin);
    let lambda = params.crater_density * w * h;
    let count = match Poisson::new(lambda) {
        Ok(p) if lambda.is_finite() => p.sample(rng) as usize,
        _ => return Vec::new(),
    };
    let ratio2 = (d_min / d_max).powi(2);
    (0..count)
        .map(|_| {
            let x = area.x_min - margin + rng.random::<f64>() * w;
            let y = area.y_min - margin + rng.random::<f64>() * h;
            let u: f64 = rng.random();
            let diameter = d_min / (1.0 - u * (1.0 - ratio2)).sqrt();
            Crater { x, y, diameter }
        })
        .collect()
}

/// Derives an independent 32-bit noise seed from the yard seed and a purpose tag.
pub(crate) fn sub_seed(seed: u64, tag: u64) -> u32 {
    // splitmix64 finaliser
    let mut z = seed ^ tag.wrapping_mul(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    (z ^ (z >> 31)) as u32
}

/// A generator for one purpose (craters, rocks), independent of the others, so that changing
/// one layer's parameters leaves the other layers of the same seed unchanged.
fn stream(seed: u64, purpose: u64) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(purpose);
    rng
}

const STREAM_CRATERS: u64 = 1;
const STREAM_ROCKS: u64 = 2;

/// The smooth part of a yard's ground: fractal relief, ridges and the regional slope (no
/// craters, no rocks), a function of world coordinates alone, so any grid or tile of the same
/// parameters samples one continuous surface.
#[derive(Clone, Debug)]
pub struct Relief {
    amplitude: f64,
    relief_seed: u32,
    ridge_seed: u32,
    inv_wave: f64,
    gain: f64,
    octaves: u32,
    ridge_amplitude: f64,
    ridge_cos: f64,
    ridge_sin: f64,
    inv_ridge: f64,
    tan_slope: f64,
    slope_cos: f64,
    slope_sin: f64,
}

impl Relief {
    /// The relief of a yard's parameters.
    pub fn new(params: &MarsYardParams) -> Self {
        let (ridge_cos, ridge_sin) = {
            let a = params.ridge_azimuth_deg.to_radians();
            (a.cos(), a.sin())
        };
        let (slope_cos, slope_sin) = {
            let a = params.slope_azimuth_deg.to_radians();
            (a.cos(), a.sin())
        };
        Self {
            amplitude: params.relief_amplitude_m,
            relief_seed: sub_seed(params.seed, 11),
            ridge_seed: sub_seed(params.seed, 12),
            inv_wave: 1.0 / params.relief_wavelength_m.max(1e-6),
            gain: params.roughness.clamp(0.0, 1.0),
            octaves: params.relief_octaves.min(16),
            ridge_amplitude: params.ridge_amplitude_m,
            ridge_cos,
            ridge_sin,
            inv_ridge: 1.0 / params.ridge_wavelength_m.max(1e-6),
            tan_slope: params.regional_slope_deg.to_radians().tan(),
            slope_cos,
            slope_sin,
        }
    }

    /// Height (m) at a world point.
    pub fn height(&self, x: f64, y: f64) -> f64 {
        let inv_wave = self.inv_wave;
        let mut z = self.amplitude
            * noise::fbm(x * inv_wave, y * inv_wave, self.relief_seed, self.octaves, self.gain);
        if self.ridge_amplitude != 0.0 {
            // Across-ridge coordinate at the ridge spacing, along-ridge stretched four times,
            // so crests run along the azimuth; centred so ridges add no net height.
            let across = (-x * self.ridge_sin + y * self.ridge_cos) * self.inv_ridge;
            let along = (x * self.ridge_cos + y * self.ridge_sin) * self.inv_ridge * 0.25;
            z += self.ridge_amplitude * (noise::ridged(across, along, self.ridge_seed, 3, 0.45) - 0.5);
        }
        z + self.tan_slope * (x * self.slope_cos + y * self.slope_sin)
    }
}

/// The ground of a yard (relief, ridges, slope, craters) without rocks.
pub fn generate_ground(params: &MarsYardParams) -> Dem {
    let geometry = ground_geometry(params);
    let (cols, rows, res) = (geometry.cols, geometry.rows, geometry.resolution);
    let relief = Relief::new(params);
    let mut data = Vec::with_capacity(geometry.len());
    for r in 0..rows {
        let y = (r as f64 + 0.5) * res;
        for c in 0..cols {
            let x = (c as f64 + 0.5) * res;
            data.push(relief.height(x, y) as f32);
        }
    }
    let mut dem = Dem {
        heights: Grid2 { geometry, data },
        nodata: None,
        geo: GeoReference { crs: "local (procedural Mars yard)".into(), easting: 0.0, northing: 0.0 },
    };
    let mut craters = yard_craters(params);
    // A pad is where a rover stands or must arrive: a crater bowl or steep inner rim there would
    // make the mission infeasible from the start. Dropping after sampling keeps every other
    // crater where the seed put it.
    craters.retain(|c| {
        params
            .clear_pads
            .iter()
            .all(|p| (c.x - p.x).hypot(c.y - p.y) >= p.radius + PAD_CRATER_CLEARANCE * 0.5 * c.diameter)
    });
    add_craters(&mut dem, &craters);
    dem
}

/// The grid of a yard's DEM: the requested size and resolution, coarsened until it fits
/// [`MAX_GENERATED_CELLS`].
fn ground_geometry(params: &MarsYardParams) -> GridGeometry {
    let mut res =
        if params.resolution.is_finite() && params.resolution > 0.0 { params.resolution } else { 0.05 };
    let width = if params.width_m.is_finite() { params.width_m.max(res) } else { res };
    let height = if params.height_m.is_finite() { params.height_m.max(res) } else { res };
    while (width / res).round() * (height / res).round() > MAX_GENERATED_CELLS as f64 {
        res *= 2.0;
    }
    let cols = ((width / res).round() as usize).max(1);
    let rows = ((height / res).round() as usize).max(1);
    GridGeometry { cols, rows, resolution: res, origin_x: 0.0, origin_y: 0.0 }
}

/// Every crater the seed puts on a yard, before those overlapping a clear pad are dropped.
pub fn yard_craters(params: &MarsYardParams) -> Vec<Crater> {
    let g = ground_geometry(params);
    let area = LocalRect::from_corner_size(0.0, 0.0, g.width_m(), g.height_m());
    sample_craters(params, area, &mut stream(params.seed, STREAM_CRATERS))
}

/// Adds crater profiles to a DEM (superposed).
pub fn add_craters(dem: &mut Dem, craters: &[Crater]) {
    let g = dem.heights.geometry;
    for crater in craters {
        let reach = crater.reach();
        let col_lo = (((crater.x - reach - g.origin_x) / g.resolution).floor().max(0.0)) as usize;
        let row_lo = (((crater.y - reach - g.origin_y) / g.resolution).floor().max(0.0)) as usize;
        let col_hi = ((crater.x + reach - g.origin_x) / g.resolution).ceil().min(g.cols as f64);
        let row_hi = ((crater.y + reach - g.origin_y) / g.resolution).ceil().min(g.rows as f64);
        if col_hi <= 0.0 || row_hi <= 0.0 {
            continue;
        }
        for row in row_lo..row_hi as usize {
            let dy = g.origin_y + (row as f64 + 0.5) * g.resolution - crater.y;
            for col in col_lo..col_hi as usize {
                let dx = g.origin_x + (col as f64 + 0.5) * g.resolution - crater.x;
                let dz = crater.profile(dx.hypot(dy));
                if dz != 0.0 {
                    dem.heights.data[row * g.cols + col] += dz as f32;
                }
            }
        }
    }
}

/// The rocks `generate` places on a yard (its rock stream), without rendering any heights.
pub fn yard_rocks(params: &MarsYardParams, extent: LocalRect) -> Vec<Rock> {
    sample_rocks(&params.rocks, extent, &params.clear_pads, &mut stream(params.seed, STREAM_ROCKS))
}

/// Generates a Mars yard: ground, craters and rocks (rock heights included in the DEM).
pub fn generate(params: &MarsYardParams) -> Terrain {
    let mut dem = generate_ground(params);
    let g = dem.heights.geometry;
    let extent = LocalRect::from_corner_size(g.origin_x, g.origin_y, g.width_m(), g.height_m());
    let rocks = yard_rocks(params, extent);
    add_rocks(&mut dem, &rocks);
    Terrain { dem, rocks }
}

/// How to turn a region of a real DEM into a rocky terrain at rover scale.
#[derive(Clone, Debug, PartialEq)]
pub struct RockyRegionParams {
    /// The region to cut, in the source DEM's local frame.
    pub region: LocalRect,
    /// Cell size of the result (m).
    pub resolution: f64,
    /// The rock field.
    pub rocks: RockFieldParams,
    /// Amplitude of fine fractal relief added below the source's resolution (m; 0 for none).
    pub micro_relief_m: f64,
    /// Seed of the rocks and the micro-relief.
    pub seed: u64,
    /// Discs kept free of rocks.
    pub clear_pads: Vec<ClearPad>,
}

impl RockyRegionParams {
    /// A square of half-size `half` (m) around a local point, 5 cm cells, default rocks.
    pub fn around(x: f64, y: f64, half: f64, seed: u64) -> Self {
        Self {
            region: LocalRect::centered(x, y, half),
            resolution: 0.05,
            rocks: RockFieldParams::default(),
            micro_relief_m: 0.03,
            seed,
            clear_pads: Vec::new(),
        }
    }
}

/// Crops a real DEM, resamples it to rover scale, adds fine relief and a rock field. The
/// result stays in the source's local frame (same georeference); `Terrain::rebased` moves it.
pub fn rocky_region(source: &Dem, params: &RockyRegionParams) -> Result<Terrain, DemError> {
    let mut dem = source.crop(params.region)?.resample(params.resolution)?;
    let g = dem.heights.geometry;
    if params.micro_relief_m != 0.0 {
        let seed = sub_seed(params.seed, 13);
        // Wavelengths from 2 m (about the source's Nyquist scale) down to the cell size.
        let octaves = ((2.0 / g.resolution).log2().ceil().max(1.0) as u32).min(8);
        for r in 0..g.rows {
            let y = g.origin_y + (r as f64 + 0.5) * g.resolution;
            for c in 0..g.cols {
                let x = g.origin_x + (c as f64 + 0.5) * g.resolution;
                let z = params.micro_relief_m * noise::fbm(x * 0.5, y * 0.5, seed, octaves, 0.5);
                dem.heights.data[r * g.cols + c] += z as f32;
            }
        }
    }
    let extent = LocalRect::from_corner_size(g.origin_x, g.origin_y, g.width_m(), g.height_m());
    let rocks =
        sample_rocks(&params.rocks, extent, &params.clear_pads, &mut stream(params.seed, STREAM_ROCKS));
    add_rocks(&mut dem, &rocks);
    Ok(Terrain { dem, rocks })
}

impl Terrain {
    /// The same terrain with its grid origin at local (0, 0): the DEM is rebased and the rocks
    /// shifted with it, so projected positions are unchanged.
    pub fn rebased(self) -> Terrain {
        let (dx, dy) = (self.dem.geometry().origin_x, self.dem.geometry().origin_y);
        let rocks = self.rocks.into_iter().map(|r| Rock { x: r.x - dx, y: r.y - dy, ..r }).collect();
        Terrain { dem: self.dem.rebased(), rocks }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crater_profile_depth_rim_and_continuity() {
        let c = Crater { x: 0.0, y: 0.0, diameter: 10.0 };
        assert!((c.profile(0.0) + 2.0).abs() < 1e-12); // depth 0.2 D
        assert!((c.profile(5.0) - 0.4).abs() < 1e-12); // rim 0.04 D
        assert!((c.profile(5.0 - 1e-9) - c.profile(5.0 + 1e-9)).abs() < 1e-6);
        assert!(c.profile(12.4999).abs() < 1e-4);
        assert_eq!(c.profile(20.0), 0.0);
    }

    #[test]
    fn crater_sizes_follow_the_inverse_square_law() {
        // N(>D) / N(>D_min) = (D_min / D)^2 (truncation at D_max corrected).
        let params = MarsYardParams { crater_density: 0.5, ..MarsYardParams::default() };
        let area = LocalRect::from_corner_size(0.0, 0.0, 200.0, 200.0);
        let craters = sample_craters(&params, area, &mut ChaCha8Rng::seed_from_u64(5));
        let n = craters.len() as f64;
        assert!(n > 10_000.0);
        for d in [2.0, 4.0] {
            let frac = craters.iter().filter(|c| c.diameter >= d).count() as f64 / n;
            let cut = (1.0f64 / 8.0).powi(2);
            let expected = ((1.0 / d).powi(2) - cut) / (1.0 - cut);
            let sigma = (expected * (1.0 - expected) / n).sqrt();
            assert!((frac - expected).abs() < 5.0 * sigma, "D {d}: {frac} vs {expected}");
        }
    }
}
