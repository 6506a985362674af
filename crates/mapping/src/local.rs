//! The per-cell layers a terrain evaluator hands to the map manager (the T-grid contents of
//! paper 004 section 3.4), all placed on one world-aligned grid geometry.

use crate::MappingError;
use rovernav_core::{Grid2, Pose2};

/// One local map: elevation statistics and assessments over a robot-centred window.
///
/// Unknown cells are `NaN` in the float layers, `0` in `point_count` and `traversability`.
#[derive(Clone, Debug, PartialEq)]
pub struct LocalMap {
    /// The pose estimate that placed the range data in the world when the map was built.
    pub reference: Pose2,
    /// Mean height of each cell (m, world z); NaN when unsensed.
    pub elevation: Grid2<f32>,
    /// Variance of the point heights in each cell (m^2); NaN when unsensed.
    pub variance: Grid2<f32>,
    /// Number of range points binned into each cell.
    pub point_count: Grid2<u32>,
    /// MRPTA traversability 1..14 (higher better), 0 when unsensed.
    pub traversability: Grid2<u8>,
    /// GESTALT goodness 0..1 (1 best, 0 obstacle), NaN when unknown.
    pub goodness: Grid2<f32>,
}

impl LocalMap {
    /// Checks that every layer has the elevation layer's geometry and the right length.
    pub fn validate(&self) -> Result<(), MappingError> {
        let g = self.elevation.geometry;
        let layers: [(&'static str, rovernav_core::GridGeometry, usize); 5] = [
            ("elevation", g, self.elevation.data.len()),
            ("variance", self.variance.geometry, self.variance.data.len()),
            ("point_count", self.point_count.geometry, self.point_count.data.len()),
            ("traversability", self.traversability.geometry, self.traversability.data.len()),
            ("goodness", self.goodness.geometry, self.goodness.data.len()),
        ];
        for (layer, geometry, len) in layers {
            if geometry != g {
                return Err(MappingError::GeometryMismatch { layer });
            }
            if len != geometry.len() {
                return Err(MappingError::LayerSize { layer, expected: geometry.len(), got: len });
            }
        }
        if !(g.resolution.is_finite() && g.resolution > 0.0) {
            return Err(MappingError::InvalidParameter {
                field: "elevation.geometry.resolution",
                reason: format!("must be a positive finite length, got {}", g.resolution),
            });
        }
        Ok(())
    }

    /// Whether cell `(col, row)` holds range data.
    pub fn is_sensed(&self, col: usize, row: usize) -> bool {
        *self.point_count.get(col, row) > 0
    }
}
