//! Partial-Hausdorff terrain matching of high-pass filtered elevation maps (paper 002
//! section 3.2).
//!
//! Both maps are high-pass filtered (no vertical search), turned into 3D occupancy grids with
//! z discretised at the grid scale, and the relative pose is the one that maximises the number
//! of local occupied cells lying within `tolerance` of an occupied global cell. The search is
//! the same hierarchical cell decomposition as the maximum-likelihood matcher, starting from
//! the dead-reckoned pose and bounding each cell with the global distance transform.

use rovernav_core::Grid2;

use super::elevation::high_pass_mean;
use super::engine::{
    BoundKind, DistanceScore, LocalCells, MatchDetails, PeakAnalysis, Scorer, SplitRule, VoxelMap, run_match,
};
use super::{MatchError, MatchResult, SearchWindow};

/// Parameters of the Hausdorff matcher.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HausdorffParams {
    /// A local cell counts when its distance to the global surface is at most this many cells.
    pub tolerance_cells: f64,
    /// Side of the high-pass filter window (m).
    pub high_pass_window: f64,
    /// Height layers are `resolution / vertical_exaggeration` thick (1 = the grid scale).
    pub vertical_exaggeration: f64,
    /// Count differences per unit of log-probability, for covariance and failure probability.
    pub temperature: f64,
    /// Competitors weaker by more than this many temperature units are not searched for.
    pub failure_margin: f64,
    /// How cells of poses are bounded.
    pub bound: BoundKind,
    /// How cells of poses are split.
    pub split: SplitRule,
}

impl Default for HausdorffParams {
    fn default() -> Self {
        Self {
            tolerance_cells: 1.0,
            high_pass_window: 1.0,
            vertical_exaggeration: 1.0,
            temperature: 10.0,
            failure_margin: 12.0,
            bound: BoundKind::MinPool,
            split: SplitRule::HeadingFirst,
        }
    }
}

/// The count score: 1 within the tolerance, 0 beyond.
#[derive(Clone, Copy, Debug, PartialEq)]
struct WithinTolerance {
    tolerance: f64,
}

impl DistanceScore for WithinTolerance {
    fn score(&self, d: f64) -> f64 {
        if d <= self.tolerance { 1.0 } else { 0.0 }
    }
}

/// A Hausdorff matcher holding the prepared global map.
#[derive(Clone, Debug)]
pub struct HausdorffMatcher {
    params: HausdorffParams,
    voxels: VoxelMap,
    count: WithinTolerance,
}

impl HausdorffMatcher {
    /// Prepares a world-frame global elevation map for matching.
    pub fn new(global: &Grid2<f32>, params: HausdorffParams) -> Result<Self, MatchError> {
        for (field, value) in [
            ("tolerance_cells", params.tolerance_cells),
            ("high_pass_window", params.high_pass_window),
            ("temperature", params.temperature),
            ("failure_margin", params.failure_margin),
        ] {
            if !(value > 0.0 && value.is_finite()) {
                return Err(MatchError::BadParameter { field, value, expected: "> 0" });
            }
        }
        let voxels = VoxelMap::new(
            &high_pass_mean(global, params.high_pass_window),
            params.tolerance_cells.ceil() as u32 + 1,
            params.vertical_exaggeration,
            super::ml::pool_levels(params.bound),
        )?;
        let count = WithinTolerance {
            // Squared voxel distances are integers: a hair of slack keeps d == tolerance in.
            tolerance: params.tolerance_cells * voxels.resolution() * (1.0 + 1e-9),
        };
        Ok(Self { params, voxels, count })
    }

    /// Distance whose score a cell gets over an unknown part of the global map: beyond the
    /// tolerance, so unknown areas neither count nor penalise.
    fn neutral_distance(&self) -> f64 {
        f64::INFINITY
    }

    /// Matches a rover-frame local map by hierarchical search around the window's centre.
    pub fn match_map(&self, local: &Grid2<f32>, window: &SearchWindow) -> Result<MatchResult, MatchError> {
        Ok(self.match_detailed(local, window, false)?.result)
    }

    /// Matches by scoring every pose of the lattice.
    pub fn exhaustive_search(
        &self,
        local: &Grid2<f32>,
        window: &SearchWindow,
    ) -> Result<MatchResult, MatchError> {
        Ok(self.match_detailed(local, window, true)?.result)
    }

    /// Matches and returns the search details.
    pub fn match_detailed(
        &self,
        local: &Grid2<f32>,
        window: &SearchWindow,
        exhaustive: bool,
    ) -> Result<MatchDetails, MatchError> {
        window.validate()?;
        let cells =
            LocalCells::new(&high_pass_mean(local, self.params.high_pass_window), &self.voxels, None)?;
        let mut scorer = Scorer::new(
            &self.voxels,
            &cells,
            &self.count,
            window,
            self.params.bound,
            self.params.split,
            self.neutral_distance(),
        );
        let analysis = PeakAnalysis {
            temperature: self.params.temperature,
            failure_margin: self.params.failure_margin,
            min_exclusion: 3,
            fit_radius: 2,
            max_competitors: 4,
        };
        Ok(run_match(&mut scorer, &analysis, exhaustive))
    }
}
