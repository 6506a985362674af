//! The mission file's `[terrain]` table: a procedural Mars yard or a real elevation model.

use serde::Deserialize;
use std::path::PathBuf;

/// Where the terrain comes from.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(tag = "kind", rename_all = "lowercase", deny_unknown_fields)]
pub enum TerrainSpec {
    /// A procedural Mars yard.
    Procedural {
        /// Side of the square yard (m).
        #[serde(default = "default_size")]
        size_m: f64,
        /// Height-grid resolution (m).
        #[serde(default = "default_resolution")]
        resolution_m: f64,
        /// Golombek-Rapp rock abundance k (cumulative fractional area of rocks).
        #[serde(default = "default_rock_abundance")]
        rock_abundance: f64,
        /// Amplitude of the fractal relief (m).
        #[serde(default = "default_relief")]
        relief_m: f64,
        /// Regional slope (deg).
        #[serde(default)]
        slope_deg: f64,
        /// Craters per 100 m x 100 m with diameter at least 1 m.
        #[serde(default)]
        craters_per_hectare: Option<f64>,
    },
    /// A real elevation model.
    Dem {
        /// File path: absolute, relative to the mission file, or relative to `ROVERNAV_DATA`.
        path: PathBuf,
        /// Region [min easting, min northing, max easting, max northing] in projected metres.
        region: Option<[f64; 4]>,
        /// Resampled resolution (m).
        #[serde(default = "default_dem_resolution")]
        resolution_m: f64,
        /// Rock abundance k of rocks added on top of the DEM (0 for none).
        #[serde(default)]
        rock_abundance: f64,
    },
    /// Procedural terrain without edges, generated in tiles around the rover (long traverses).
    Tiled(TiledSpec),
}

/// A tiled procedural terrain: the Mars-yard model at every scale from rocks to ridges,
/// generated around the rover as it drives (`kind = "tiled"`).
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TiledSpec {
    /// Finest cell size, near the rover (m).
    #[serde(default = "default_resolution")]
    pub resolution_m: f64,
    /// Golombek-Rapp rock abundance k (Pathfinder's site about 0.2).
    #[serde(default = "default_tiled_rocks")]
    pub rock_abundance: f64,
    /// Amplitude of the fractal relief (m).
    #[serde(default = "default_relief")]
    pub relief_m: f64,
    /// Wavelength of the largest relief features (m).
    #[serde(default = "default_relief_wavelength")]
    pub relief_wavelength_m: f64,
    /// Roughness: amplitude ratio between successive relief octaves (0..1; lower is smoother
    /// at small scales).
    #[serde(default = "default_roughness")]
    pub roughness: f64,
    /// Height of the ridge lines (m).
    #[serde(default)]
    pub ridge_m: f64,
    /// Spacing of the ridge lines across their direction (m).
    #[serde(default = "default_ridge_wavelength")]
    pub ridge_wavelength_m: f64,
    /// Direction the ridge crests run (deg counter-clockwise from east).
    #[serde(default)]
    pub ridge_azimuth_deg: f64,
    /// Regional slope (deg).
    #[serde(default)]
    pub slope_deg: f64,
    /// Craters per 100 m x 100 m with diameter at least 1 m.
    #[serde(default)]
    pub craters_per_hectare: f64,
    /// Largest crater diameter (m).
    #[serde(default = "default_crater_max")]
    pub crater_max_diameter_m: f64,
    /// Side of the square window of finest cells the simulator keeps around the rover (m).
    #[serde(default = "default_window")]
    pub window_m: f64,
}

fn default_tiled_rocks() -> f64 {
    0.2
}
fn default_relief_wavelength() -> f64 {
    12.0
}
fn default_roughness() -> f64 {
    0.5
}
fn default_ridge_wavelength() -> f64 {
    9.0
}
fn default_crater_max() -> f64 {
    8.0
}
fn default_window() -> f64 {
    80.0
}

fn default_size() -> f64 {
    30.0
}
fn default_resolution() -> f64 {
    0.05
}
fn default_rock_abundance() -> f64 {
    0.16
}
fn default_relief() -> f64 {
    0.25
}
fn default_dem_resolution() -> f64 {
    0.1
}

impl TerrainSpec {
    /// The first field out of range, as (field, why).
    pub(super) fn check(&self) -> Result<(), (&'static str, &'static str)> {
        let positive = |v: f64| v.is_finite() && v > 0.0;
        match self {
            TerrainSpec::Procedural { size_m, resolution_m, rock_abundance, relief_m, slope_deg, .. } => {
                if !positive(*size_m) || *size_m > 2000.0 {
                    return Err(("terrain.size_m", "must be in (0, 2000] m"));
                }
                if !positive(*resolution_m) || *resolution_m > *size_m / 4.0 {
                    return Err(("terrain.resolution_m", "must be positive and much smaller than the yard"));
                }
                if (size_m / resolution_m).powi(2) > 1.0e8 {
                    return Err((
                        "terrain.resolution_m",
                        "yard too large at this resolution (over 1e8 cells)",
                    ));
                }
                if !(0.0..=0.5).contains(rock_abundance) {
                    return Err(("terrain.rock_abundance", "must be in [0, 0.5]"));
                }
                if !(relief_m.is_finite() && *relief_m >= 0.0) {
                    return Err(("terrain.relief_m", "must be a non-negative number"));
                }
                if !(slope_deg.is_finite() && slope_deg.abs() < 45.0) {
                    return Err(("terrain.slope_deg", "must be within (-45, 45) deg"));
                }
            }
            TerrainSpec::Dem { resolution_m, rock_abundance, region, .. } => {
                // Bounded both ways: the mission fuzz target found 4294967296 (capacity overflow
                // panic), and a tiny one would resample the DEM into a grid no memory holds.
                if !(0.01..=100.0).contains(resolution_m) {
                    return Err(("terrain.resolution_m", "must be in [0.01, 100] m"));
                }
                if let Some([e0, n0, e1, n1]) = region
                    && ((e1 - e0) / resolution_m) * ((n1 - n0) / resolution_m) > 1.0e8
                {
                    return Err((
                        "terrain.resolution_m",
                        "region too large at this resolution (over 1e8 cells)",
                    ));
                }
                if !(0.0..=0.5).contains(rock_abundance) {
                    return Err(("terrain.rock_abundance", "must be in [0, 0.5]"));
                }
                if let Some(r) = region
                    && !(r.iter().all(|v| v.is_finite()) && r[2] > r[0] && r[3] > r[1])
                {
                    return Err(("terrain.region", "must be [min E, min N, max E, max N] with max > min"));
                }
            }
            TerrainSpec::Tiled(t) => t.check()?,
        }
        Ok(())
    }
}

impl TiledSpec {
    /// The first field out of range, as (field, why).
    fn check(&self) -> Result<(), (&'static str, &'static str)> {
        let positive = |v: f64| v.is_finite() && v > 0.0;
        let non_negative = |v: f64| v.is_finite() && v >= 0.0;
        if !(0.01..=0.2).contains(&self.resolution_m) {
            return Err(("terrain.resolution_m", "must be in [0.01, 0.2] m"));
        }
        if !(0.0..=0.5).contains(&self.rock_abundance) {
            return Err(("terrain.rock_abundance", "must be in [0, 0.5]"));
        }
        if !non_negative(self.relief_m) || self.relief_m > 500.0 {
            return Err(("terrain.relief_m", "must be in [0, 500] m"));
        }
        if !positive(self.relief_wavelength_m) || self.relief_wavelength_m > 1.0e5 {
            return Err(("terrain.relief_wavelength_m", "must be in (0, 100000] m"));
        }
        if !(0.0..=1.0).contains(&self.roughness) {
            return Err(("terrain.roughness", "must be in [0, 1]"));
        }
        if !non_negative(self.ridge_m) || self.ridge_m > 500.0 {
            return Err(("terrain.ridge_m", "must be in [0, 500] m"));
        }
        if !positive(self.ridge_wavelength_m) || self.ridge_wavelength_m > 1.0e5 {
            return Err(("terrain.ridge_wavelength_m", "must be in (0, 100000] m"));
        }
        if !self.ridge_azimuth_deg.is_finite() {
            return Err(("terrain.ridge_azimuth_deg", "must be a number"));
        }
        if !(self.slope_deg.is_finite() && self.slope_deg.abs() < 45.0) {
            return Err(("terrain.slope_deg", "must be within (-45, 45) deg"));
        }
        if !non_negative(self.craters_per_hectare) || self.craters_per_hectare > 1.0e4 {
            return Err(("terrain.craters_per_hectare", "must be in [0, 10000]"));
        }
        if !(1.0..=100.0).contains(&self.crater_max_diameter_m) {
            return Err(("terrain.crater_max_diameter_m", "must be in [1, 100] m"));
        }
        if !(20.0..=400.0).contains(&self.window_m) || (self.window_m / self.resolution_m).powi(2) > 1.6e7 {
            return Err(("terrain.window_m", "must be in [20, 400] m and hold at most 1.6e7 cells"));
        }
        Ok(())
    }
}
