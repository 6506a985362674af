//! The `lander` localiser: `ekf-ml` (the EKF of paper 004 section 3.2 with terrain-matching
//! fixes against the rover's own map, paper 000 section 4) plus absolute fixes from the
//! lander's stereo sightings of the rover (paper 002 section 2, approach (a)).
//!
//! A sighting arrives in the frame of the command during which the lander watched the rover
//! turn in place ([`rovernav_core::SensorFrame::lander`]; the simulator's lander station
//! differences its images, takes the largest changed region, correlates it in the other camera
//! and triangulates, as `rovernav_vision::lander` does). The localiser turns it into the rover's
//! position with its own heading ([`crate::lander::lander_fix`]: "orientation comes from the
//! rover's own sensors"), checks the position innovation against a chi-square gate and fuses it
//! as a position-only fix; a fused fix moves the rover's map with the estimate
//! (`EkfMl::fuse_absolute_fix`).
//!
//! The fix's covariance is the stereo range error along the line of sight (Matthies' sigma
//! from a 0.1 px disparity sigma) and the image-position sigma across it, each plus a 0.06 m
//! sigma for where on the body the detected region falls, fitted on `eval lander` seeds
//! 1001-1150; on seeds 1-150 its mean NEES is 1.77 over 149 fixes at 2-10 m, inside the
//! 95 % band 1.68-2.32 (`docs/results/2026-11-28-lander-localizer.md`). `covariance_scale` multiplies it (1 by default: no tuning). Sightings from
//! one place share their error (where on the body the changed region's box falls depends on
//! the rover's pose seen from the lander and on its shadow), so a sighting within
//! `independent_after_m` of the last fused one is fused by covariance intersection
//! (`EkfMl::fuse_correlated_fix`): turning back and forth in one spot does not shrink the
//! covariance below one sighting's.
//!
//! Departure from the paper: its rover is commanded to turn 0.3 rad for each sighting; here the
//! lander watches every in-place turn the navigator makes near it (see
//! `rovernav_sim::lander_station`), so the fixes cost the traverse nothing.

use rovernav_core::{Localizer, LocalizerStats, Point2, Pose3, PoseEstimate, RoverConfig, SensorFrame};

use crate::lander::{LanderFixParams, lander_fix};
use crate::matching::MatchResult;
use crate::orbital_map::innovation_nees;
use crate::{EkfMl, EkfMlParams};

/// Settings of the `lander` localiser.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LanderLocalizerParams {
    /// The map matcher's settings between lander fixes.
    pub ekf_ml: EkfMlParams,
    /// Whether the rover's own map is matched between lander fixes (`ekf-ml`); without it the
    /// filter is the EKF with lander fixes only.
    pub map_matching: bool,
    /// Factor on a lander fix's covariance before it is fused.
    pub covariance_scale: f64,
    /// Chi-square gate (2 degrees of freedom) on the position innovation.
    pub gate: f64,
    /// A sighting within this distance (m) of the estimate at the last fused one is fused by
    /// covariance intersection: sightings from one place share their error (where on the body
    /// the changed region's box falls depends on the rover's pose seen from the lander).
    pub independent_after_m: f64,
}

impl Default for LanderLocalizerParams {
    fn default() -> Self {
        Self {
            ekf_ml: EkfMlParams::default(),
            map_matching: true,
            covariance_scale: 1.0,
            // 99.9 % of a chi-square with 2 degrees of freedom.
            gate: 13.8,
            independent_after_m: 1.0,
        }
    }
}

/// One lander fix: the estimate before it, the fix, whether it was fused.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LanderFix {
    /// The filter's estimate when the sighting arrived (after the frame's motion).
    pub before: PoseEstimate,
    /// The rover's position from the sighting, with the covariance fused.
    pub fix: MatchResult,
    /// Whether the filter fused it.
    pub used: bool,
    /// Frames given so far (this one included).
    pub at_update: u64,
}

/// Counters of the lander fixes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LanderStats {
    /// Sightings received.
    pub sightings: u64,
    /// Fixes fused.
    pub used: u64,
    /// Sightings that gave no fix (invalid values).
    pub invalid: u64,
    /// Fixes rejected by the innovation gate (or the filter).
    pub rejected_gate: u64,
}

/// `ekf-ml` with lander fixes.
#[derive(Clone, Debug)]
pub struct LanderLocalizer {
    inner: EkfMl,
    body: LanderFixParams,
    params: LanderLocalizerParams,
    stats: LanderStats,
    fixes: Vec<LanderFix>,
    updates: u64,
    /// The estimate's position when the last sighting was fused.
    last_fused: Option<Point2>,
}

impl LanderLocalizer {
    /// A localiser for `config`'s body starting at `initial`.
    pub fn new(config: &RoverConfig, initial: Pose3, params: LanderLocalizerParams) -> Self {
        Self {
            inner: EkfMl::with_params(config, initial, params.ekf_ml),
            body: LanderFixParams::for_rover(config),
            params,
            stats: LanderStats::default(),
            fixes: Vec::new(),
            updates: 0,
            last_fused: None,
        }
    }

    /// The lander counters.
    pub fn lander_stats(&self) -> LanderStats {
        self.stats
    }

    /// Every lander fix tried, in order.
    pub fn fixes(&self) -> &[LanderFix] {
        &self.fixes
    }

    /// Turns a sighting into a fix and fuses it when it passes the gate.
    fn sighted(&mut self, sighting: &rovernav_core::LanderSighting) {
        self.stats.sightings += 1;
        let before = self.inner.estimate();
        let Ok(mut fix) = lander_fix(sighting, before.pose.yaw, &self.body) else {
            self.stats.invalid += 1;
            return;
        };
        for row in fix.covariance.iter_mut().take(2) {
            for v in row.iter_mut().take(2) {
                *v *= self.params.covariance_scale;
            }
        }
        let gated = innovation_nees(&before, &fix).is_none_or(|d| d > self.params.gate);
        let here = before.pose.pose2().position();
        let same_place = self.last_fused.is_some_and(|p| p.dist(here) < self.params.independent_after_m);
        let used = !gated
            && if same_place {
                self.inner.fuse_correlated_fix(&fix)
            } else {
                self.inner.fuse_absolute_fix(&fix)
            };
        if used {
            self.last_fused = Some(self.inner.estimate().pose.pose2().position());
        }
        self.fixes.push(LanderFix { before, fix, used, at_update: self.updates });
        if used {
            self.stats.used += 1;
        } else {
            self.stats.rejected_gate += 1;
        }
    }
}

impl Localizer for LanderLocalizer {
    fn name(&self) -> &str {
        "lander"
    }

    fn reset(&mut self, pose: Pose3) {
        self.inner.reset(pose);
        self.last_fused = None;
    }

    fn update(&mut self, frame: &SensorFrame) {
        self.updates += 1;
        if self.params.map_matching || frame.clouds.is_empty() {
            self.inner.update(frame);
        } else {
            self.inner.update(&SensorFrame { clouds: Vec::new(), ..frame.clone() });
        }
        if let Some(sighting) = &frame.lander {
            self.sighted(sighting);
        }
    }

    fn localization_target(&self) -> Option<f64> {
        self.inner.localization_target()
    }

    fn estimate(&self) -> PoseEstimate {
        self.inner.estimate()
    }

    fn stats(&self) -> LocalizerStats {
        let (i, l) = (self.inner.stats(), self.stats);
        let e = self.inner.ekf().stats();
        LocalizerStats {
            matches_attempted: i.matches_attempted + l.sightings,
            fixes_used: i.fixes_used + l.used,
            fixes_rejected: i.fixes_rejected + l.sightings - l.used,
            rejected_uncertain: i.rejected_uncertain,
            rejected_on_edge: i.rejected_on_edge,
            zero_velocity_updates: e.zero_updates,
            slip_corrections: e.slip_corrections,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rovernav_core::LanderSighting;

    /// A sighting of a rover standing at (x, y) from a lander camera at the origin, 1.8 m up:
    /// the triangulated point where `lander_fix` puts the body centre back at (x, y) for the
    /// heading `yaw`.
    fn sighting_of(x: f64, y: f64, yaw: f64, body: &LanderFixParams) -> LanderSighting {
        let r = x.hypot(y);
        let depth = body.depth_fraction
            * crate::lander::body_depth(body.half_length, body.half_width, yaw - y.atan2(x));
        let k = (r - depth) / r;
        LanderSighting {
            camera: [0.0, 0.0, 1.8],
            point: [x * k, y * k, 0.3],
            range_sigma_m: 0.05,
            angle_sigma_rad: 0.01,
        }
    }

    #[test]
    fn a_sighting_pulls_the_estimate_to_the_lander_fix_and_a_wild_one_is_gated() {
        let config = RoverConfig::default();
        let start = Pose3 { x: 6.0, y: 1.0, yaw: 0.4, ..Default::default() };
        let mut loc = LanderLocalizer::new(&config, start, LanderLocalizerParams::default());
        loc.inner.reset_position(6.0, 1.0, 0.5);
        // The rover is really 0.4 m further east than it believes.
        let body = LanderFixParams::for_rover(&config);
        let frame =
            SensorFrame { lander: Some(Box::new(sighting_of(6.4, 1.0, 0.4, &body))), ..Default::default() };
        loc.update(&frame);
        let e = loc.estimate();
        assert_eq!(loc.lander_stats().used, 1);
        // Kalman update of a 0.5 m prior with a fix of about 0.05 m along x: within a few cm.
        assert!((e.pose.x - 6.4).abs() < 0.03 && (e.pose.y - 1.0).abs() < 0.02, "{:?}", e.pose);
        assert!(e.covariance[0][0] < 0.01, "{:?}", e.covariance);
        // A sighting 5 m away from a now confident estimate fails the 99.9 % gate.
        let wild =
            SensorFrame { lander: Some(Box::new(sighting_of(11.4, 1.0, 0.4, &body))), ..Default::default() };
        loc.update(&wild);
        assert_eq!((loc.lander_stats().used, loc.lander_stats().rejected_gate), (1, 1));
        assert!((loc.estimate().pose.x - 6.4).abs() < 0.05);
        assert_eq!(loc.fixes().len(), 2);
        assert!(loc.fixes()[0].used && !loc.fixes()[1].used);
    }

    #[test]
    fn repeated_sightings_from_one_place_do_not_shrink_the_covariance() {
        let config = RoverConfig::default();
        let body = LanderFixParams::for_rover(&config);
        let start = Pose3 { x: 6.0, y: 1.0, yaw: 0.4, ..Default::default() };
        let frame =
            SensorFrame { lander: Some(Box::new(sighting_of(6.0, 1.0, 0.4, &body))), ..Default::default() };
        let variances = |independent_after_m: f64| {
            let params = LanderLocalizerParams { independent_after_m, ..Default::default() };
            let mut loc = LanderLocalizer::new(&config, start, params);
            loc.inner.reset_position(6.0, 1.0, 0.5);
            loc.update(&frame);
            let first = loc.estimate().covariance[0][0];
            for _ in 0..9 {
                loc.update(&frame);
            }
            (first, loc.estimate().covariance[0][0], loc.lander_stats().used)
        };
        // Fused as independent, ten sightings from one spot claim a tenth of one's variance;
        // by covariance intersection they keep about one sighting's (a little more: each
        // intersection weighs the tighter filter 0.99, the sighting 0.01).
        let (first, independent, used) = variances(0.0);
        assert_eq!(used, 10);
        assert!(independent < 0.15 * first, "{independent} against {first}");
        let (first, intersected, used) = variances(1.0);
        assert_eq!(used, 10);
        assert!(intersected > 0.95 * first && intersected < 1.1 * first, "{intersected} against {first}");
    }
}
