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
        }
        Ok(())
    }
}
