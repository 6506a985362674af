//! Maximum-likelihood terrain matching (paper 000 section 4, Olson's formulation).
//!
//! The measurements are the distances `D_i` from the occupied cells of the local map, placed at
//! a candidate pose, to the closest occupied cells of the global map (both maps as 3D occupancy
//! grids, z discretised at the grid scale, after a high-pass filter that removes the unknown
//! vertical offset). The log-likelihood of a pose is `sum_i ln(alpha p1(D_i) + (1 - alpha) K)`
//! with `p1` a zero-mean normal of standard deviation `sigma` (inliers) and `K` a constant
//! density (outliers: range shadows in the global map, bad range data in the local one). The
//! search, subpixel fit, covariance and failure probability are in [`super::engine`].

use rovernav_core::Grid2;

use super::elevation::{fill_gaps, high_pass};
use super::engine::{
    BoundKind, DistanceScore, LocalCells, MatchDetails, PeakAnalysis, PoseLattice, Scorer, SearchOutcome,
    SplitRule, VoxelMap, find_peak, finish_match, run_match,
};
use super::{MatchError, MatchResult, SearchWindow};

/// Parameters of the maximum-likelihood matcher.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MlParams {
    /// Standard deviation of the inlier distance distribution, in grid cells.
    pub sigma_cells: f64,
    /// Probability that a local cell is an inlier (alpha).
    pub inlier_fraction: f64,
    /// Outlier density K as a fraction of the inlier density's peak `p1(0)`.
    pub outlier_ratio: f64,
    /// Side of the high-pass filter window (m); `None` matches raw heights (then both maps
    /// must share a vertical datum).
    pub high_pass_window: Option<f64>,
    /// Height layers are `resolution / vertical_exaggeration` thick (1 = the grid scale, as
    /// in the paper; more makes gentle relief count on coarse grids).
    pub vertical_exaggeration: f64,
    /// Distances saturate at this many sigmas (beyond it the inlier term is negligible).
    pub cap_sigmas: f64,
    /// Score differences per unit of log-probability: the number of local cells that behave
    /// as one independent measurement (neighbouring cells share stereo errors).
    pub temperature: f64,
    /// Competitors weaker than the best by more than this many temperature units are not
    /// searched for (their failure probability is below e^-margin).
    pub failure_margin: f64,
    /// A local cell over an unknown part of the global map scores as if at this many sigmas
    /// (neither rewarded nor punished: the map has no information there). The paper scores
    /// it as an outlier, which biases matches towards maximum overlap.
    pub unknown_sigmas: f64,
    /// Score each local cell over unknown global terrain with its own background score (its
    /// mean score over known terrain at misaligned poses, see
    /// [`Scorer::use_background_neutral`]) instead of the constant `unknown_sigmas` score.
    pub background_neutral: bool,
    /// Score only the local cells that land on known global terrain, at least this many cells
    /// from its unknown parts, at the window's centre (and, for full matches, again at the
    /// first match's pose); `None` scores every local cell. See [`MlMatcher::match_detailed`].
    pub overlap_margin_cells: Option<u32>,
    /// Fill gaps of up to this many cells between measurements in both maps before the
    /// high-pass filter (see [`super::elevation::fill_gaps`]); 0 leaves them.
    pub fill_gaps_cells: usize,
    /// How cells of poses are bounded.
    pub bound: BoundKind,
    /// How cells of poses are split.
    pub split: SplitRule,
    /// Score at most this many local cells (an even subsample of the occupied cells, taken
    /// after the high-pass filter); `None` scores them all. Matching time is proportional to it.
    pub max_local_cells: Option<usize>,
}

impl Default for MlParams {
    fn default() -> Self {
        Self {
            sigma_cells: 1.0,
            inlier_fraction: 0.5,
            outlier_ratio: 0.05,
            high_pass_window: Some(1.0),
            vertical_exaggeration: 1.0,
            cap_sigmas: 5.0,
            temperature: 20.0,
            failure_margin: 12.0,
            unknown_sigmas: 1.0,
            background_neutral: true,
            overlap_margin_cells: Some(1),
            fill_gaps_cells: 1,
            bound: BoundKind::MinPool,
            split: SplitRule::HeadingFirst,
            max_local_cells: None,
        }
    }
}

impl MlParams {
    /// Checks every field's range.
    pub fn validate(&self) -> Result<(), MatchError> {
        let checks: [(&'static str, f64, bool, &'static str); 6] = [
            ("sigma_cells", self.sigma_cells, self.sigma_cells > 0.0, "> 0"),
            (
                "inlier_fraction",
                self.inlier_fraction,
                self.inlier_fraction > 0.0 && self.inlier_fraction <= 1.0,
                "in (0, 1]",
            ),
            ("outlier_ratio", self.outlier_ratio, self.outlier_ratio > 0.0, "> 0"),
            ("cap_sigmas", self.cap_sigmas, self.cap_sigmas >= 1.0, ">= 1"),
            ("temperature", self.temperature, self.temperature > 0.0, "> 0"),
            ("failure_margin", self.failure_margin, self.failure_margin > 0.0, "> 0"),
        ];
        for (field, value, ok, expected) in checks {
            if !ok || !value.is_finite() {
                return Err(MatchError::BadParameter { field, value, expected });
            }
        }
        if let Some(w) = self.high_pass_window
            && !(w > 0.0 && w.is_finite())
        {
            return Err(MatchError::BadParameter { field: "high_pass_window", value: w, expected: "> 0" });
        }
        Ok(())
    }
}

/// The per-cell log-likelihood `ln(alpha p1(D) + (1 - alpha) K)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MixtureLikelihood {
    sigma: f64,
    alpha: f64,
    outlier_density: f64,
}

impl MixtureLikelihood {
    /// The mixture for a grid resolution (m) and matcher parameters.
    pub fn new(resolution: f64, params: &MlParams) -> Self {
        let sigma = params.sigma_cells * resolution;
        let peak = 1.0 / (sigma * (2.0 * std::f64::consts::PI).sqrt());
        Self { sigma, alpha: params.inlier_fraction, outlier_density: params.outlier_ratio * peak }
    }
}

impl DistanceScore for MixtureLikelihood {
    fn score(&self, d: f64) -> f64 {
        let z = d / self.sigma;
        let p1 = (-0.5 * z * z).exp() / (self.sigma * (2.0 * std::f64::consts::PI).sqrt());
        (self.alpha * p1 + (1.0 - self.alpha) * self.outlier_density).ln()
    }
}

/// Pyramid levels of the distance transform kept for a bound kind (blocks of 1 x 2 up to 64 x 64
/// cells).
pub(crate) fn pool_levels(bound: BoundKind) -> usize {
    match bound {
        BoundKind::MinPool => 12,
        BoundKind::Distance => 0,
    }
}

/// A maximum-likelihood matcher holding the prepared global map.
#[derive(Clone, Debug)]
pub struct MlMatcher {
    params: MlParams,
    voxels: VoxelMap,
    likelihood: MixtureLikelihood,
}

impl MlMatcher {
    /// Prepares a world-frame global elevation map (NaN = unknown) for matching.
    pub fn new(global: &Grid2<f32>, params: MlParams) -> Result<Self, MatchError> {
        params.validate()?;
        let filled = fill_gaps(global, params.fill_gaps_cells);
        let filtered = match params.high_pass_window {
            Some(w) => high_pass(&filled, w),
            None => filled,
        };
        let cap_cells = (params.cap_sigmas * params.sigma_cells).ceil() as u32;
        let voxels =
            VoxelMap::new(&filtered, cap_cells, params.vertical_exaggeration, pool_levels(params.bound))?;
        let likelihood = MixtureLikelihood::new(voxels.resolution(), &params);
        Ok(Self { params, voxels, likelihood })
    }

    /// The parameters.
    pub fn params(&self) -> &MlParams {
        &self.params
    }

    /// Distance whose score a local cell gets over an unknown part of the global map.
    fn neutral_distance(&self) -> f64 {
        self.params.unknown_sigmas * self.params.sigma_cells * self.voxels.resolution()
    }

    /// Matches a rover-frame local map by branch and bound around the window's centre.
    pub fn match_map(&self, local: &Grid2<f32>, window: &SearchWindow) -> Result<MatchResult, MatchError> {
        Ok(self.match_detailed(local, window, false)?.result)
    }

    /// Matches by scoring every pose of the lattice (the reference for tests).
    pub fn exhaustive_search(
        &self,
        local: &Grid2<f32>,
        window: &SearchWindow,
    ) -> Result<MatchResult, MatchError> {
        Ok(self.match_detailed(local, window, true)?.result)
    }

    /// Matches and returns the search details (lattice, best index, failure search).
    ///
    /// With [`MlParams::overlap_margin_cells`], the local cells scored are those that fall on
    /// known global terrain at the window's centre; when the best pose lies elsewhere, they are
    /// chosen again at that pose and the match is run once more. Why: a view taken closer to
    /// a rock sees more of its top than the global view did; those extra cells lie over the
    /// global map's shadow at the true pose and score only when the pose moves them onto the
    /// rock, which pulls the match towards the earlier view point (measured: 5-6 cm downrange
    /// bias between stereo views 1 m apart). Cells the global map cannot judge at the true
    /// pose carry no information about it, so they are left out.
    pub fn match_detailed(
        &self,
        local: &Grid2<f32>,
        window: &SearchWindow,
        exhaustive: bool,
    ) -> Result<MatchDetails, MatchError> {
        if self.params.overlap_margin_cells.is_none() {
            return self.match_detailed_at(local, window, exhaustive, window.center);
        }
        let r = local.resolution();
        if !(r > 0.0 && r.is_finite()) {
            return Err(MatchError::BadResolution { map: "local", value: r });
        }
        window.validate()?;
        let analysis = self.analysis();
        let filtered = self.filtered(local);
        let at_centre = self.masked(&filtered, window.center);
        // The first run's failure search is only needed when its answer stands: when the
        // match did not move, or moved to where the same local cells are chosen (the second
        // run would repeat the first exactly).
        let first = self.with_scorer_on(&at_centre, window, |scorer| {
            let peak = find_peak(scorer, &analysis, exhaustive);
            let p = peak.pose();
            let moved = (p.x - window.center.x).hypot(p.y - window.center.y) > peak.lattice.step
                || (p.yaw - window.center.yaw).abs() > peak.lattice.yaw_step;
            if !moved {
                return Ok(finish_match(scorer, &analysis, &peak));
            }
            let at_peak = self.masked(&filtered, p);
            let same = at_peak.data.iter().zip(&at_centre.data).all(|(a, b)| a.to_bits() == b.to_bits());
            if same {
                Ok(finish_match(scorer, &analysis, &peak))
            } else {
                Err((at_peak, peak.main.evaluations))
            }
        })?;
        match first {
            Ok(details) => Ok(details),
            Err((at_peak, first_evaluations)) => {
                let mut out =
                    self.with_scorer_on(&at_peak, window, |scorer| run_match(scorer, &analysis, exhaustive))?;
                // Both runs report their work: the second is the answer, the first found its
                // cells.
                out.result.poses_evaluated += first_evaluations;
                Ok(out)
            }
        }
    }

    /// The peak analysis of a match.
    fn analysis(&self) -> PeakAnalysis {
        PeakAnalysis {
            temperature: self.params.temperature,
            failure_margin: self.params.failure_margin,
            min_exclusion: 3,
            // The likelihood of sparse stereo views is skewed away from its peak: a normal
            // fitted to +-2 steps followed the skew (measured on the simulator's mast stereo
            // sequence: 4.2 cm mean downrange error, 3.5 cm with +-1 step).
            fit_radius: 1,
            max_competitors: 4,
        }
    }

    /// One match with the local cells chosen at `overlap_pose`.
    fn match_detailed_at(
        &self,
        local: &Grid2<f32>,
        window: &SearchWindow,
        exhaustive: bool,
        overlap_pose: rovernav_core::Pose2,
    ) -> Result<MatchDetails, MatchError> {
        let r = local.resolution();
        if !(r > 0.0 && r.is_finite()) {
            return Err(MatchError::BadResolution { map: "local", value: r });
        }
        let analysis = self.analysis();
        self.with_scorer(local, window, overlap_pose, |scorer| run_match(scorer, &analysis, exhaustive))
    }

    /// Runs only the search (no peak fit, no failure search): the best lattice pose by branch
    /// and bound or by scoring every pose, with the lattice searched.
    pub fn search(
        &self,
        local: &Grid2<f32>,
        window: &SearchWindow,
        exhaustive: bool,
    ) -> Result<(SearchOutcome, PoseLattice), MatchError> {
        self.with_scorer(local, window, window.center, |scorer| {
            let outcome = if exhaustive {
                scorer.exhaustive()
            } else {
                scorer.branch_and_bound(f64::NEG_INFINITY, Some([0, 0, 0]), &[])
            };
            (outcome, scorer.lattice())
        })
    }

    /// Validates the window, filters, masks (at `overlap_pose`) and samples the local map, and
    /// hands a scorer over it to `f`.
    fn with_scorer<R>(
        &self,
        local: &Grid2<f32>,
        window: &SearchWindow,
        overlap_pose: rovernav_core::Pose2,
        f: impl FnOnce(&mut Scorer<'_, MixtureLikelihood>) -> R,
    ) -> Result<R, MatchError> {
        window.validate()?;
        let masked = self.masked(&self.filtered(local), overlap_pose);
        self.with_scorer_on(&masked, window, f)
    }

    /// The local map with its gaps filled and high-passed, as the matcher scores it.
    fn filtered(&self, local: &Grid2<f32>) -> Grid2<f32> {
        let filled = fill_gaps(local, self.params.fill_gaps_cells);
        match self.params.high_pass_window {
            Some(w) => high_pass(&filled, w),
            None => filled,
        }
    }

    /// A filtered local map masked to its overlap with known global terrain at `pose` (see
    /// [`MlParams::overlap_margin_cells`]).
    fn masked(&self, filtered: &Grid2<f32>, pose: rovernav_core::Pose2) -> Grid2<f32> {
        match self.params.overlap_margin_cells {
            Some(margin) => self.overlap_only(filtered.clone(), pose, margin),
            None => filtered.clone(),
        }
    }

    /// Hands a scorer over a filtered and masked local map to `f`.
    fn with_scorer_on<R>(
        &self,
        filtered: &Grid2<f32>,
        window: &SearchWindow,
        f: impl FnOnce(&mut Scorer<'_, MixtureLikelihood>) -> R,
    ) -> Result<R, MatchError> {
        let cells = LocalCells::new(filtered, &self.voxels, self.params.max_local_cells)?;
        let mut scorer = Scorer::new(
            &self.voxels,
            &cells,
            &self.likelihood,
            window,
            self.params.bound,
            self.params.split,
            self.neutral_distance(),
        );
        if self.params.background_neutral {
            // Displacements of 0.3 m and 0.6 m (at least 3 and 6 steps): beyond the size of
            // most rocks, so the cell is misaligned, yet within the local terrain's character.
            let step = |m: f64| ((m / self.voxels.resolution()).round() as i32).max(1);
            scorer.use_background_neutral(&[step(0.3).max(3), step(0.6).max(6)]);
        }
        Ok(f(&mut scorer))
    }

    /// The local map with the cells that land on unknown global terrain at `pose`, or within
    /// `margin` cells of it, made unknown; unchanged if fewer than a tenth of its cells (or
    /// fewer than 20) would remain, as a match on so little overlap is better judged whole.
    fn overlap_only(&self, mut local: Grid2<f32>, pose: rovernav_core::Pose2, margin: u32) -> Grid2<f32> {
        let limit = margin.saturating_mul(margin).min(u32::from(u16::MAX)) as u16;
        let mut keep = Vec::with_capacity(local.data.len());
        let (mut known, mut kept) = (0usize, 0usize);
        for r in 0..local.rows() {
            for c in 0..local.cols() {
                let h = *local.get(c, r);
                let (x, y) = local.geometry.center(c, r);
                let w = pose.transform(rovernav_core::Point2::new(x, y));
                let k = h.is_finite() && self.voxels.squared_distance_to_unknown(w.x, w.y) > limit;
                known += usize::from(h.is_finite());
                kept += usize::from(k);
                keep.push(k);
            }
        }
        if kept < 20 || kept * 10 < known {
            return local;
        }
        for (v, k) in local.data.iter_mut().zip(keep) {
            if !k {
                *v = f32::NAN;
            }
        }
        local
    }

    /// Expected log-likelihood, at every pose of the window's lattice, of a probability map:
    /// weighted rover-frame points `[x, y, z, weight]` (z already high-passed), the weight
    /// being the probability that the point's voxel is seen occupied (paper 000 section 4.4).
    /// Returns the lattice and its scores indexed `((k + half[2]) * ny + j + half[1]) * nx + i
    /// + half[0]` with `nx`, `ny` the lattice's sizes along x and y.
    ///
    /// As the map-matching localiser does with a real view, points that could leave the mapped
    /// terrain at some pose of the window (within the window's reach, plus a cell, of unknown
    /// terrain at its centre) are left out: scoring them would reward or spare poses for overlap,
    /// not alignment. `EmptyMap` if none remain.
    pub fn expected_log_likelihoods(
        &self,
        points: &[[f64; 4]],
        window: &SearchWindow,
    ) -> Result<(PoseLattice, Vec<f64>), MatchError> {
        window.validate()?;
        let r = self.voxels.resolution();
        let radius = points.iter().map(|p| p[0].hypot(p[1])).fold(r, f64::max);
        let reach = (window.half_x.hypot(window.half_y) + radius * window.half_yaw) / r + 1.0;
        let limit = (reach * reach).ceil().min(f64::from(u16::MAX - 1)) as u16;
        let centre = window.center;
        let points: Vec<[f64; 4]> = points
            .iter()
            .copied()
            .filter(|&[x, y, _, _]| {
                let w = centre.transform(rovernav_core::Point2::new(x, y));
                self.voxels.squared_distance_to_unknown(w.x, w.y) > limit
            })
            .collect();
        if points.is_empty() {
            return Err(MatchError::EmptyMap { map: "local" });
        }
        let lattice = PoseLattice::new(window, r, radius);
        // Squared distances are capped small integers: score each once.
        let table: Vec<f64> = (0..4096usize).map(|n| self.likelihood.score((n as f64).sqrt() * r)).collect();
        let [hx, hy, hk] = lattice.half;
        let mut scores = Vec::with_capacity(lattice.size() as usize);
        for k in -hk..=hk {
            for j in -hy..=hy {
                for i in -hx..=hx {
                    let pose = lattice.pose([f64::from(i), f64::from(j), f64::from(k)]);
                    let (s, c) = pose.yaw.sin_cos();
                    let total: f64 = points
                        .iter()
                        .map(|&[x, y, z, w]| {
                            let (wx, wy) = (pose.x + c * x - s * y, pose.y + s * x + c * y);
                            let n = usize::from(self.voxels.squared_distance_at(wx, wy, z));
                            let score = table
                                .get(n)
                                .copied()
                                .unwrap_or_else(|| self.likelihood.score((n as f64).sqrt() * r));
                            w * score
                        })
                        .sum();
                    scores.push(total);
                }
            }
        }
        Ok((lattice, scores))
    }

    /// Log-likelihood of a local map at a continuous pose (nearest-voxel lookup), for
    /// diagnostics and target selection.
    pub fn log_likelihood_at(&self, local: &Grid2<f32>, pose: rovernav_core::Pose2) -> f64 {
        let filtered = match self.params.high_pass_window {
            Some(w) => high_pass(local, w),
            None => local.clone(),
        };
        let r = self.voxels.resolution();
        super::elevation::occupied_cells(&filtered)
            .into_iter()
            .map(|[x, y, z]| {
                let w = pose.transform(rovernav_core::Point2::new(x, y));
                let n = self.voxels.squared_distance_at(w.x, w.y, z);
                self.likelihood.score(f64::from(n).sqrt() * r)
            })
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synthetic::{TerrainParams, fractal_terrain};
    use rovernav_core::{GridGeometry, Point2, Pose2};

    /// Rocky synthetic terrain, 8 m square at 5 cm around the origin.
    fn rocky_map() -> Grid2<f32> {
        let params = TerrainParams { size: 8.0, resolution: 0.05, ..Default::default() };
        fractal_terrain(&params, 11).heights
    }

    #[test]
    fn expected_log_likelihood_of_certain_points_is_the_log_likelihood_and_peaks_at_the_truth() {
        let global = rocky_map();
        let matcher = MlMatcher::new(&global, MlParams::default()).expect("matcher");
        let truth = Pose2::new(0.3, -0.2, 0.4);
        // The local map: the global heights seen from the true pose, 2 m around it.
        let geometry = GridGeometry { cols: 80, rows: 80, resolution: 0.05, origin_x: -2.0, origin_y: -2.0 };
        let mut local = Grid2::filled(geometry, f32::NAN);
        for row in 0..80 {
            for col in 0..80 {
                let (x, y) = geometry.center(col, row);
                let w = truth.transform(Point2::new(x, y));
                if let Some(&h) = global.at_world(w.x, w.y) {
                    *local.get_mut(col, row) = h;
                }
            }
        }
        let filtered = high_pass(&local, MlParams::default().high_pass_window.expect("window"));
        // Each point certain, once as one point and once split in two halves (the expectation
        // is linear in the probabilities).
        let whole: Vec<[f64; 4]> = super::super::elevation::occupied_cells(&filtered)
            .into_iter()
            .map(|[x, y, z]| [x, y, z, 1.0])
            .collect();
        let halves: Vec<[f64; 4]> =
            whole.iter().flat_map(|&[x, y, z, _]| [[x, y, z, 0.5], [x, y, z, 0.5]]).collect();
        let window = SearchWindow { center: truth, half_x: 0.1, half_y: 0.1, half_yaw: 0.04 };
        let (lattice, scores) = matcher.expected_log_likelihoods(&whole, &window).expect("scores");
        let (_, split) = matcher.expected_log_likelihoods(&halves, &window).expect("scores");
        assert_eq!(scores.len() as u64, lattice.size());
        let [hx, hy, hk] = lattice.half;
        let mut n = 0;
        let mut best = (f64::NEG_INFINITY, [0; 3]);
        for k in -hk..=hk {
            for j in -hy..=hy {
                for i in -hx..=hx {
                    let direct = matcher
                        .log_likelihood_at(&local, lattice.pose([f64::from(i), f64::from(j), f64::from(k)]));
                    assert!((scores[n] - direct).abs() < 1e-6 * direct.abs().max(1.0), "pose {i} {j} {k}");
                    assert!((split[n] - scores[n]).abs() < 1e-6 * direct.abs().max(1.0));
                    if scores[n] > best.0 {
                        best = (scores[n], [i, j, k]);
                    }
                    n += 1;
                }
            }
        }
        assert_eq!(best.1, [0, 0, 0], "the true pose scores best");
    }
}
