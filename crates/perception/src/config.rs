//! Parameters of terrain assessment, derived from the rover's dimensions.

use crate::PerceptionError;
use crate::footprint::{FootprintParams, GroundRefit};
use crate::goodness::GoodnessParams;
use crate::traversability::TraversabilityParams;
use rovernav_core::RoverConfig;
pub use rovernav_core::{RangeNoise, SensorNoise};

/// When the terrain evaluator asks for more range data (paper 004 section 3.3).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DensityConfig {
    /// Minimum point density over the checked area (points per square metre).
    pub min_points_per_m2: f64,
    /// Nearest distance in front of the rover that is checked (m).
    pub near: f64,
    /// Farthest distance in front of the rover that is checked (m): the "shorter, configurable
    /// distance" over which a minimal density is guaranteed.
    pub far: f64,
    /// Half-angle of the checked area about the rover heading (rad).
    pub half_angle: f64,
    /// Angular sectors the area is split into; the sparsest one is reported.
    pub sectors: usize,
}

impl Default for DensityConfig {
    fn default() -> Self {
        Self {
            // About one point per 0.15 m cell.
            min_points_per_m2: 50.0,
            near: 0.5,
            far: 2.0,
            half_angle: 45f64.to_radians(),
            sectors: 3,
        }
    }
}

/// The height of a cell the step/slope hazard model sees.
///
/// A cell straddling a rock's edge holds points on the rock and on the ground around it, and
/// range noise smears a small rock's top over its neighbours: the cell mean then loses part of
/// the rock's height, and a rock just taller than the clearance measures just under it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum HazardHeight {
    /// The mean of the cell's points (paper 004's elevation cell).
    #[default]
    Mean,
    /// The mean plus the spread of the points beyond the sensor noise, capped at the highest
    /// point: a cell half on a rock of height h reads about h, a flat noisy cell reads its mean.
    Top,
    /// The highest point (noise then biases every cell upwards).
    Max,
}

/// Everything terrain assessment needs: grid size, hazard limits and C-obstacle growth.
#[derive(Clone, Debug, PartialEq)]
pub struct TerrainConfig {
    /// Columns of the robot-centred grid (paper 004: 121).
    pub cols: usize,
    /// Rows of the robot-centred grid (paper 004: 121).
    pub rows: usize,
    /// Cell size (m; paper 004: 0.15).
    pub resolution: f64,
    /// Belly clearance: the step limit (m).
    pub clearance: f64,
    /// Maximum safe tilt: the slope limit (rad).
    pub max_tilt: f64,
    /// Radius of the footprint window used by the step/slope model (m).
    pub footprint_radius: f64,
    /// Fraction of a footprint window's cells that must be sensed for it to be assessed.
    pub min_window_fraction: f64,
    /// Cells with fewer points are treated as unsensed.
    pub min_points_per_cell: u32,
    /// Per-cell roughness (RMS about the cell's plane) that makes a cell not traversable (m).
    pub cell_roughness_limit: f64,
    /// Footprint roughness (RMS of cell heights about the footprint plane) at goodness 0 (m).
    pub footprint_roughness_limit: f64,
    /// Range noise in height (m), discounted from the per-cell roughness.
    pub sensor_noise: f64,
    /// Half-size in cells of the block whose points each cell's slope plane is fitted through.
    pub slope_block: usize,
    /// Radius of the circle enclosing the rover body (m).
    pub rover_radius: f64,
    /// Empirical safety buffer added to the rover radius when growing C-obstacles (m).
    pub safety_buffer: f64,
    /// Largest angle between the tangent directions that approximate a grown corner (rad).
    pub max_arc_step: f64,
    /// Point-density check in front of the rover.
    pub density: DensityConfig,
    /// Which height of each cell the step/slope hazard model runs on.
    pub hazard_height: HazardHeight,
    /// Per-sensor range error; when set, each point carries the height noise its range and
    /// viewing angle imply, which `hazard_confidence` turns into each cell's tolerance
    /// ([`HazardHeight::Top`] discounts `sensor_noise` alone).
    pub range_noise: Option<SensorNoise>,
    /// Standard deviations of a cell's height noise beyond `sensor_noise` (from `range_noise`)
    /// within which a raised cell counts as reaching the step limit; such hazards are flagged
    /// uncertain. 0 = the measured height must exceed the limit itself.
    pub hazard_confidence: f64,
    /// How a hazardous window's ground is refitted and where low cells are pits (see
    /// [`GroundRefit`]).
    pub ground: GroundRefit,
}

impl Default for TerrainConfig {
    fn default() -> Self {
        Self::for_rover(&RoverConfig::default())
    }
}

impl TerrainConfig {
    /// The MRPTA grid (121 x 121 cells of 0.15 m) with limits from the rover's dimensions.
    pub fn for_rover(rover: &RoverConfig) -> Self {
        Self {
            cols: 121,
            rows: 121,
            resolution: 0.15,
            clearance: rover.clearance,
            max_tilt: rover.max_tilt,
            footprint_radius: rover.radius(),
            min_window_fraction: 0.25,
            min_points_per_cell: 1,
            hazard_height: HazardHeight::Mean,
            cell_roughness_limit: rover.clearance / 3.0,
            footprint_roughness_limit: rover.clearance / 2.0,
            // Typical stereo/LIDAR height noise at a few metres.
            sensor_noise: 0.01,
            slope_block: 1,
            rover_radius: rover.radius(),
            safety_buffer: 0.1,
            max_arc_step: 30f64.to_radians(),
            density: DensityConfig::default(),
            range_noise: None,
            hazard_confidence: 0.0,
            ground: GroundRefit::WholeWindow,
        }
    }

    /// Checks every parameter, naming the first one out of range.
    pub fn validate(&self) -> Result<(), PerceptionError> {
        let positive = |field: &'static str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(PerceptionError::InvalidConfig {
                    field,
                    reason: format!("must be a positive finite number, got {v}"),
                })
            }
        };
        if self.cols == 0 || self.rows == 0 {
            return Err(PerceptionError::InvalidConfig {
                field: "cols/rows",
                reason: format!("the grid needs at least one cell, got {}x{}", self.cols, self.rows),
            });
        }
        positive("resolution", self.resolution)?;
        positive("clearance", self.clearance)?;
        positive("max_tilt", self.max_tilt)?;
        positive("footprint_radius", self.footprint_radius)?;
        positive("cell_roughness_limit", self.cell_roughness_limit)?;
        positive("footprint_roughness_limit", self.footprint_roughness_limit)?;
        positive("rover_radius", self.rover_radius)?;
        positive("max_arc_step", self.max_arc_step)?;
        positive("density.far", self.density.far)?;
        positive("density.half_angle", self.density.half_angle)?;
        if !(self.min_window_fraction.is_finite() && (0.0..=1.0).contains(&self.min_window_fraction)) {
            return Err(PerceptionError::InvalidConfig {
                field: "min_window_fraction",
                reason: format!("must lie in 0..=1, got {}", self.min_window_fraction),
            });
        }
        let non_negative = [
            ("sensor_noise", self.sensor_noise),
            ("safety_buffer", self.safety_buffer),
            ("hazard_confidence", self.hazard_confidence),
            ("density.near", self.density.near),
            ("density.min_points_per_m2", self.density.min_points_per_m2),
        ];
        for (field, v) in non_negative {
            if !(v.is_finite() && v >= 0.0) {
                return Err(PerceptionError::InvalidConfig {
                    field,
                    reason: format!("must be finite and >= 0, got {v}"),
                });
            }
        }
        if let Some(noise) = &self.range_noise {
            for (field, v) in [
                ("range_noise.mast", noise.mast),
                ("range_noise.body", noise.body),
                ("range_noise.lidar", noise.lidar),
            ] {
                if !(v.constant.is_finite()
                    && v.constant >= 0.0
                    && v.quadratic.is_finite()
                    && v.quadratic >= 0.0)
                {
                    return Err(PerceptionError::InvalidConfig {
                        field,
                        reason: format!(
                            "needs finite terms >= 0, got constant {} and quadratic {}",
                            v.constant, v.quadratic
                        ),
                    });
                }
            }
        }
        if self.density.sectors == 0 || self.density.near >= self.density.far {
            return Err(PerceptionError::InvalidConfig {
                field: "density",
                reason: "needs at least one sector and near < far".into(),
            });
        }
        Ok(())
    }

    /// Half-width of the footprint window in cells (at least 1).
    pub fn footprint_half_window(&self) -> usize {
        ((self.footprint_radius / self.resolution).round() as usize).max(1)
    }

    /// Parameters of the step/slope model.
    pub fn footprint_params(&self) -> FootprintParams {
        let k = self.footprint_half_window();
        let window = ((2 * k + 1) * (2 * k + 1)) as f64;
        FootprintParams {
            half_window: k,
            min_cells: ((self.min_window_fraction * window).ceil() as usize).max(3),
            step_limit: self.clearance,
            slope_limit: self.max_tilt,
            ground: self.ground,
        }
    }

    /// Parameters of MRPTA traversability.
    pub fn traversability_params(&self) -> TraversabilityParams {
        TraversabilityParams {
            max_slope: self.max_tilt,
            max_roughness: self.cell_roughness_limit,
            max_step: self.clearance,
            sensor_noise: self.sensor_noise,
            slope_block: self.slope_block,
        }
    }

    /// Parameters of GESTALT goodness.
    pub fn goodness_params(&self) -> GoodnessParams {
        GoodnessParams {
            max_step: self.clearance,
            max_slope: self.max_tilt,
            max_roughness: self.footprint_roughness_limit,
        }
    }

    /// Distance C-obstacles are grown by: rover radius plus safety buffer (m).
    pub fn growth(&self) -> f64 {
        self.rover_radius + self.safety_buffer
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rovernav_core::CameraKind;

    #[test]
    fn a_negative_range_noise_term_is_named() {
        let mut config =
            TerrainConfig { range_noise: Some(SensorNoise::default()), ..TerrainConfig::default() };
        assert!(config.validate().is_ok());
        config.range_noise.as_mut().unwrap().body.quadratic = -0.01;
        let err = config.validate().unwrap_err();
        assert!(matches!(err, PerceptionError::InvalidConfig { field: "range_noise.body", .. }), "{err:?}");
        // The stereo model grows with the square of range.
        let mast = SensorNoise::default().of(CameraKind::Mast);
        assert!((mast.sigma(5.0) - 4.0 * mast.sigma(2.5)).abs() < 1e-12);
    }
}
