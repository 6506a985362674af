//! Terrain map matching: the rover's local elevation map against a global one.
//!
//! - [`ml`]: maximum-likelihood matching with branch-and-bound search (paper 000 section 4).
//! - [`hausdorff`]: partial-Hausdorff matching of high-passed maps (paper 002 section 3.2).
//! - [`engine`]: the occupancy grids, distance transform, branch and bound and peak fit they
//!   share; [`distance_transform`] and [`elevation`] are their building blocks.
//!
//! Maps are `Grid2<f32>` elevation grids with NaN for unknown cells. The local map is in the
//! rover frame at the time it was taken (x forward, y left, levelled with the inclinometer, the
//! rover at the origin); the global map is in the world frame. Both should share one
//! resolution: the pose space is discretised at it.

pub mod distance_transform;
pub mod elevation;
pub mod engine;
pub mod hausdorff;
pub mod ml;

pub use engine::{BoundKind, MatchDetails, SplitRule};
pub use hausdorff::{HausdorffMatcher, HausdorffParams};
pub use ml::{MlMatcher, MlParams};

use rovernav_core::{Pose2, PoseEstimate};

/// The outcome of matching a local map against a global map.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MatchResult {
    /// Estimated rover pose in the global map's frame (subpixel).
    pub pose: Pose2,
    /// Covariance of (x, y, yaw).
    pub covariance: [[f64; 3]; 3],
    /// Score of the best discrete pose (log-likelihood, or inlier count for Hausdorff).
    pub log_likelihood: f64,
    /// Estimated probability that the match picked the wrong place.
    pub failure_probability: f64,
    /// The main search's work in pose evaluations: its distance-transform lookups divided by
    /// the local cells scored per pose (poses scored count one each, box bounds the fraction
    /// of the local cells they looked up).
    pub poses_evaluated: u64,
}

impl MatchResult {
    /// Normalised estimation error squared of the matched position against a true position
    /// (x, y): e^T C^-1 e with the covariance's position block (2 on average for an honest
    /// covariance); `None` when that block is singular.
    pub fn position_nees(&self, x: f64, y: f64) -> Option<f64> {
        let c = &self.covariance;
        let block = [[c[0][0], c[0][1]], [c[1][0], c[1][1]]];
        crate::consistency::squared_mahalanobis_2d(self.pose.x - x, self.pose.y - y, &block)
    }
}

/// The region of pose space to search, around the dead-reckoned pose.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SearchWindow {
    /// The dead-reckoned pose (tested first).
    pub center: Pose2,
    /// Half-width of the window along world x (m).
    pub half_x: f64,
    /// Half-width of the window along world y (m).
    pub half_y: f64,
    /// Half-width of the window in heading (rad).
    pub half_yaw: f64,
}

impl SearchWindow {
    /// A window of `k_sigma` standard deviations of a pose estimate, at least `min_xy` (m) and
    /// `min_yaw` (rad) wide on each side.
    pub fn from_estimate(estimate: &PoseEstimate, k_sigma: f64, min_xy: f64, min_yaw: f64) -> Self {
        let c = &estimate.covariance;
        Self {
            center: estimate.pose.pose2(),
            half_x: (k_sigma * c[0][0].max(0.0).sqrt()).max(min_xy),
            half_y: (k_sigma * c[1][1].max(0.0).sqrt()).max(min_xy),
            half_yaw: (k_sigma * c[2][2].max(0.0).sqrt()).max(min_yaw),
        }
    }
}

/// Why a match could not be run.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MatchError {
    /// A map has no known cell.
    #[error("the {map} map has no known cell")]
    EmptyMap {
        /// "local" or "global".
        map: &'static str,
    },
    /// A map's resolution is not a positive number.
    #[error("the {map} map's resolution {value} is not a positive number")]
    BadResolution {
        /// "local" or "global".
        map: &'static str,
        /// The offending value.
        value: f64,
    },
    /// A parameter is out of range.
    #[error("parameter `{field}` = {value} is out of range ({expected})")]
    BadParameter {
        /// The parameter's field name.
        field: &'static str,
        /// The offending value.
        value: f64,
        /// What is accepted.
        expected: &'static str,
    },
    /// The occupancy grid would be too large.
    #[error("the global occupancy grid would need {voxels} voxels")]
    TooLarge {
        /// Voxels needed.
        voxels: usize,
    },
    /// A search window value is not finite.
    #[error("search window field `{field}` is not finite")]
    BadWindow {
        /// The offending field.
        field: &'static str,
    },
}

impl SearchWindow {
    /// Checks that every field is finite.
    pub fn validate(&self) -> Result<(), MatchError> {
        for (field, v) in [
            ("center.x", self.center.x),
            ("center.y", self.center.y),
            ("center.yaw", self.center.yaw),
            ("half_x", self.half_x),
            ("half_y", self.half_y),
            ("half_yaw", self.half_yaw),
        ] {
            if !v.is_finite() {
                return Err(MatchError::BadWindow { field });
            }
        }
        Ok(())
    }
}
