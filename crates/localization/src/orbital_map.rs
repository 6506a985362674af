//! The `orbital-map` localiser: `ekf-ml` (the EKF of paper 004 section 3.2 with terrain-matching
//! fixes against the rover's own map, paper 000 section 4) plus absolute fixes from matching the
//! rover's map against an orbital DEM given to it before the traverse (paper 002 section 5,
//! [`crate::orbital`]).
//!
//! Between orbital fixes the rover localises as `ekf-ml` does. Every
//! [`OrbitalMapParams::fix_interval_m`] of estimated travel (and at once when a frame brings a
//! panorama, at least `min_wedges` clouds), the part of the rover's own elevation map within
//! `range_m` of the estimate is averaged into `cell`-sized cells and matched against the
//! orbital map around the estimate, in a window of `window_sigmas` of the filter's covariance
//! (heading searched too). A fix is rejected when its false-match probability exceeds
//! `max_failure_probability`, when its best pose lies on the window's edge, or when its
//! position innovation fails the chi-square gate `gate` against the filter's and the fix's
//! covariances; a rejected fix is retried `retry_interval_m` later, at most `max_retries`
//! times before the next interval. A fused fix moves the
//! rover's map with the estimate (`EkfMl::fuse_correlated_fix`).
//!
//! In the `fix_lead_m` before a fix is due, the localiser offers the look-back decorator
//! sideways localisation targets (pans of +-45 to +-135 deg, in turn), so that the map to match
//! is wider than the corridor the forward views cover.
//!
//! Departures from paper 002 section 5, with reasons:
//! - The paper matches a panorama taken at one stop; here the map is the rover's own, built
//!   while driving (a panorama at every fix would cost the traverse a stop each time). A
//!   panorama, when the mission takes one, is used the same way.
//! - The fix is fused as a position only: the match's heading, from a map a dozen metres
//!   across at 1 m, is poorer than the gyro and sun sensor's, and its error is correlated
//!   with the position's.
//! - The match covariance is scaled by `covariance_scale` before fusion: the matcher's
//!   covariance counts 20 local cells per independent measurement (its temperature, measured
//!   for rover-to-rover maps at 5 cm), which over-counts the correlation of 0.5 m cells of a
//!   map smoothed to 1 m; the scale was measured as the mean NEES of the fixes against the
//!   simulator's truth on development traverses (see `docs/results/2026-11-28-localization-scales.md`).
//! - The fix is fused by covariance intersection (`EkfMl::fuse_correlated_fix`), not as an
//!   independent measurement: the map matched is the rover's own, placed with the estimate,
//!   and a weak match is drawn towards the window's centre, so the fix's error is correlated
//!   with the filter's. Fused as independent, the fixes' own NEES was honest (1.96 over 16
//!   fixes) while the filter after them was over-confident (mean final NEES 3.85 over 12
//!   seeds, above its 95 % bound).

use rovernav_core::{
    Grid2, GridGeometry, Localizer, LocalizerStats, Point2, Pose2, Pose3, PoseEstimate, RoverConfig,
    SensorFrame,
};

use crate::matching::MatchResult;
use crate::orbital::{OrbitalParams, degrade, match_orbital, reference_around};
use crate::{EkfMl, EkfMlParams, SearchWindow};

/// Settings of the `orbital-map` localiser.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrbitalMapParams {
    /// The orbital match's settings.
    pub orbital: OrbitalParams,
    /// The map matcher's settings between orbital fixes.
    pub ekf_ml: EkfMlParams,
    /// Resolution the orbital map is degraded to before use (m; a finer map is averaged over
    /// blocks of it, see [`degrade`]); at or below the given map's it is used as given.
    pub orbital_resolution_m: f64,
    /// Cell size of the matched maps (m).
    pub cell: f64,
    /// Half-side of the rover's map matched (m).
    pub range_m: f64,
    /// Estimated travel between orbital fixes (m).
    pub fix_interval_m: f64,
    /// Travel before a rejected or impossible fix is tried again (m).
    pub retry_interval_m: f64,
    /// Fixes tried again at most this many times before waiting a whole interval.
    pub max_retries: u32,
    /// Travel before a fix is due over which the look-backs pan sideways (m).
    pub fix_lead_m: f64,
    /// Clouds a frame must bring to count as a panorama (a fix is tried at once).
    pub min_wedges: usize,
    /// Fewest known cells of the rover's map worth matching.
    pub min_cells: usize,
    /// Search half-width in filter standard deviations.
    pub window_sigmas: f64,
    /// Smallest search half-width (m).
    pub min_window_m: f64,
    /// Largest search half-width (m).
    pub max_window_m: f64,
    /// Smallest heading search half-width (rad).
    pub min_yaw: f64,
    /// Largest heading search half-width (rad).
    pub max_yaw: f64,
    /// Fixes more likely than this to be false are rejected.
    pub max_failure_probability: f64,
    /// Factor on the match covariance before fusion.
    pub covariance_scale: f64,
    /// Chi-square gate (2 degrees of freedom) on the position innovation.
    pub gate: f64,
}

impl Default for OrbitalMapParams {
    fn default() -> Self {
        Self {
            orbital: OrbitalParams::default(),
            ekf_ml: EkfMlParams::default(),
            orbital_resolution_m: 1.0,
            cell: 0.5,
            range_m: 12.0,
            fix_interval_m: 100.0,
            retry_interval_m: 5.0,
            max_retries: 4,
            fix_lead_m: 8.0,
            min_wedges: 6,
            min_cells: 150,
            window_sigmas: 3.0,
            min_window_m: 1.0,
            max_window_m: 8.0,
            min_yaw: 2f64.to_radians(),
            max_yaw: 10f64.to_radians(),
            // `rovernav eval orbital`'s flag threshold (docs/results/2026-11-28-orbital.md).
            max_failure_probability: 0.3,
            // The mean NEES of 17 fused fixes on development traverses (seeds 3001-3004) was
            // 0.40 at 1.0 (docs/results/2026-11-28-localization-scales.md).
            covariance_scale: 0.2,
            // 99.9 % of a chi-square with 2 degrees of freedom.
            gate: 13.8,
        }
    }
}

/// One orbital fix tried: the filter's estimate before it, the fix (the rover's pose with its
/// scaled covariance) and whether it was fused.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrbitalFix {
    /// The estimate the match started from.
    pub before: PoseEstimate,
    /// The rover's pose from the match, with the covariance that was (or would have been) fused.
    pub fix: MatchResult,
    /// Whether the filter fused it.
    pub used: bool,
    /// Frames the localiser had been given when it tried the fix (this one included).
    pub at_update: u64,
}

/// Counters of the orbital fixes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct OrbitalStats {
    /// Orbital matches tried.
    pub attempted: u64,
    /// Orbital fixes fused.
    pub used: u64,
    /// Fixes rejected for their false-match probability.
    pub rejected_uncertain: u64,
    /// Fixes rejected on the window's edge.
    pub rejected_on_edge: u64,
    /// Fixes rejected by the innovation gate (or the filter).
    pub rejected_gate: u64,
    /// Fixes not tried for too little of the rover's map, or matches that failed.
    pub not_matched: u64,
}

/// `ekf-ml` with orbital-map fixes.
#[derive(Clone, Debug)]
pub struct OrbitalMapLocalizer {
    inner: EkfMl,
    orbital: Grid2<f32>,
    params: OrbitalMapParams,
    stats: OrbitalStats,
    fixes: Vec<OrbitalFix>,
    /// Estimated travel since the last fused orbital fix (or the start), in metres, counted
    /// towards the next one.
    travel: f64,
    previous: Point2,
    /// Sideways look-backs offered so far.
    side_looks: usize,
    /// Frames given so far.
    updates: u64,
    /// Failed fixes since the last fused one.
    retries: u32,
}

/// The sideways pans offered before a fix (rad, body frame), in turn.
const SIDE_PANS: [f64; 6] = [
    std::f64::consts::FRAC_PI_2,
    -std::f64::consts::FRAC_PI_2,
    3.0 * std::f64::consts::FRAC_PI_4,
    -3.0 * std::f64::consts::FRAC_PI_4,
    std::f64::consts::FRAC_PI_4,
    -std::f64::consts::FRAC_PI_4,
];

impl OrbitalMapLocalizer {
    /// A localiser starting at `initial` with the world-frame orbital map `orbital` (NaN
    /// unknown), degraded to `params.orbital_resolution_m`.
    pub fn new(config: &RoverConfig, initial: Pose3, orbital: &Grid2<f32>, params: OrbitalMapParams) -> Self {
        let orbital = if params.orbital_resolution_m > 1.01 * orbital.resolution() {
            degrade(orbital, params.orbital_resolution_m)
        } else {
            orbital.clone()
        };
        Self {
            inner: EkfMl::with_params(config, initial, params.ekf_ml),
            orbital,
            params,
            stats: OrbitalStats::default(),
            fixes: Vec::new(),
            travel: 0.0,
            previous: Point2::new(initial.x, initial.y),
            side_looks: 0,
            updates: 0,
            retries: 0,
        }
    }

    /// Resets the filter's position to (x, y) with standard deviation `sigma` (m), keeping the
    /// rest (e.g. to start from an uncertain landing position).
    pub fn reset_position(&mut self, x: f64, y: f64, sigma: f64) {
        self.inner.reset_position(x, y, sigma);
        self.previous = Point2::new(x, y);
    }

    /// The orbital counters.
    pub fn orbital_stats(&self) -> OrbitalStats {
        self.stats
    }

    /// Every orbital fix tried, in order.
    pub fn fixes(&self) -> &[OrbitalFix] {
        &self.fixes
    }

    /// The orbital map as used (after degradation).
    pub fn orbital_map(&self) -> &Grid2<f32> {
        &self.orbital
    }

    /// Tries an orbital fix; true when one was fused.
    fn try_fix(&mut self) -> bool {
        let p = self.params;
        let before = self.inner.estimate();
        let here = before.pose.pose2().position();
        let crop = self.inner.map_heights(here, p.range_m, p.cell);
        if crop.data.iter().filter(|h| h.is_finite()).count() < p.min_cells {
            self.stats.not_matched += 1;
            return false;
        }
        // The rover's map in a frame at the estimate with world-aligned axes: the match's pose
        // is then the rover's position and its heading correction.
        let g = crop.geometry;
        let local = Grid2 {
            geometry: GridGeometry { origin_x: g.origin_x - here.x, origin_y: g.origin_y - here.y, ..g },
            data: crop.data,
        };
        let c = &before.covariance;
        let half = |v: f64| (p.window_sigmas * v.max(0.0).sqrt()).clamp(p.min_window_m, p.max_window_m);
        let window = SearchWindow {
            center: Pose2::new(here.x, here.y, 0.0),
            half_x: half(c[0][0]),
            half_y: half(c[1][1]),
            half_yaw: (p.window_sigmas * c[2][2].max(0.0).sqrt()).clamp(p.min_yaw, p.max_yaw),
        };
        let reach = p.range_m + window.half_x.max(window.half_y) + 6.0;
        let reference = reference_around(&self.orbital, here.x, here.y, reach, p.cell);
        self.stats.attempted += 1;
        let Ok(m) = match_orbital(&local, &reference, &window, &p.orbital) else {
            self.stats.not_matched += 1;
            return false;
        };
        // Position only: the heading is left to the gyro and the sun sensor (a heading
        // variance of 0 tells the filter the heading was not measured).
        let mut fix = m;
        fix.pose.yaw = before.pose.yaw;
        for (i, row) in fix.covariance.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                *v = if i < 2 && j < 2 { *v * p.covariance_scale } else { 0.0 };
            }
        }
        let edge = 1.01 * p.cell;
        let on_edge = (m.pose.x - here.x).abs() > window.half_x - edge
            || (m.pose.y - here.y).abs() > window.half_y - edge;
        let uncertain = m.failure_probability > p.max_failure_probability;
        let gated = innovation_nees(&before, &fix).is_none_or(|d| d > p.gate);
        // Each orbital fix is fused by covariance intersection: its error is correlated with
        // the filter's (see the module doc).
        let used = !uncertain && !on_edge && !gated && self.inner.fuse_correlated_fix(&fix);
        self.fixes.push(OrbitalFix { before, fix, used, at_update: self.updates });
        if used {
            self.stats.used += 1;
        } else if uncertain {
            self.stats.rejected_uncertain += 1;
        } else if on_edge {
            self.stats.rejected_on_edge += 1;
        } else {
            self.stats.rejected_gate += 1;
        }
        used
    }
}

/// The position innovation's squared Mahalanobis length against the sum of the estimate's and
/// the fix's position covariances; `None` when that sum is singular.
pub fn innovation_nees(estimate: &PoseEstimate, fix: &MatchResult) -> Option<f64> {
    let (p, r) = (&estimate.covariance, &fix.covariance);
    let s = [[p[0][0] + r[0][0], p[0][1] + r[0][1]], [p[1][0] + r[1][0], p[1][1] + r[1][1]]];
    crate::consistency::squared_mahalanobis_2d(fix.pose.x - estimate.pose.x, fix.pose.y - estimate.pose.y, &s)
}

impl Localizer for OrbitalMapLocalizer {
    fn name(&self) -> &str {
        "orbital-map"
    }

    fn reset(&mut self, pose: Pose3) {
        self.inner.reset(pose);
        (self.travel, self.side_looks, self.retries) = (0.0, 0, 0);
        self.previous = Point2::new(pose.x, pose.y);
    }

    fn update(&mut self, frame: &SensorFrame) {
        self.updates += 1;
        self.inner.update(frame);
        let here = self.inner.estimate().pose.pose2().position();
        let step = here.dist(self.previous);
        if step.is_finite() {
            self.travel += step;
        }
        self.previous = here;
        let clouds = frame.clouds.iter().filter(|c| !c.points.is_empty()).count();
        let panorama = clouds >= self.params.min_wedges;
        if clouds > 0 && self.travel >= self.params.fix_interval_m - self.params.fix_lead_m {
            self.side_looks += 1;
        }
        if panorama || (clouds > 0 && self.travel >= self.params.fix_interval_m) {
            if self.try_fix() {
                (self.travel, self.side_looks, self.retries) = (0.0, 0, 0);
            } else if !panorama && self.retries < self.params.max_retries {
                self.retries += 1;
                self.travel = self.params.fix_interval_m - self.params.retry_interval_m;
            } else if !panorama {
                (self.travel, self.side_looks, self.retries) = (0.0, 0, 0);
            }
            self.previous = self.inner.estimate().pose.pose2().position();
        }
    }

    fn localization_target(&self) -> Option<f64> {
        if self.travel >= self.params.fix_interval_m - self.params.fix_lead_m {
            Some(SIDE_PANS[self.side_looks % SIDE_PANS.len()])
        } else {
            self.inner.localization_target()
        }
    }

    fn estimate(&self) -> PoseEstimate {
        self.inner.estimate()
    }

    fn stats(&self) -> LocalizerStats {
        let (i, o) = (self.inner.stats(), self.stats);
        let e = self.inner.ekf().stats();
        LocalizerStats {
            matches_attempted: i.matches_attempted + o.attempted,
            fixes_used: i.fixes_used + o.used,
            fixes_rejected: i.fixes_rejected + o.attempted - o.used,
            rejected_uncertain: i.rejected_uncertain + o.rejected_uncertain,
            rejected_on_edge: i.rejected_on_edge + o.rejected_on_edge,
            zero_velocity_updates: e.zero_updates,
            slip_corrections: e.slip_corrections,
        }
    }
}

#[cfg(test)]
#[path = "orbital_map_tests.rs"]
mod tests;
