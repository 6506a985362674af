//! The `orbital-map` localiser: the EKF (paper 004 section 3.2) with fixes from matching each
//! mast panorama against an orbital DEM ([`crate::orbital`], paper 002 section 5).
//!
//! Dead reckoning runs in the EKF. When a frame brings a panorama (at least
//! `min_wedges` non-empty clouds), its points are levelled with the estimate's roll and pitch
//! and binned into a rover-frame map, the orbital map is interpolated around the estimate, and
//! the match is searched within `window_sigmas` of the estimate's covariance (at least
//! `min_window_m`, at most `max_window_m`; heading +-`half_yaw`). A fix whose false-match
//! probability exceeds `max_failure_probability`, or whose best pose lies on the window's edge,
//! is rejected; the others are fused with their covariance (`Ekf::fuse_fix`).
//!
//! Unlike `ekf-ml`, whose map is its own and whose windows cover only the drift since that map
//! was made, the orbital map is absolute: the window follows the filter's whole uncertainty.

use rovernav_core::{Grid2, Localizer, LocalizerStats, Pose3, PoseEstimate, RoverConfig, SensorFrame};

use crate::orbital::{OrbitalParams, match_orbital, panorama_map, reference_around};
use crate::{Ekf, SearchWindow};

/// Settings of the `orbital-map` localiser.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrbitalMapParams {
    /// The match's settings.
    pub orbital: OrbitalParams,
    /// Cell size of the matched maps (m).
    pub cell: f64,
    /// Half-side of the rover-frame map (m): the panorama's range.
    pub range_m: f64,
    /// Clouds a frame must bring to count as a panorama.
    pub min_wedges: usize,
    /// Search half-width in estimate standard deviations.
    pub window_sigmas: f64,
    /// Smallest and largest search half-width (m).
    pub min_window_m: f64,
    /// Largest search half-width (m).
    pub max_window_m: f64,
    /// Heading search half-width (rad).
    pub half_yaw: f64,
    /// Fixes more likely than this to be false are rejected.
    pub max_failure_probability: f64,
}

impl Default for OrbitalMapParams {
    fn default() -> Self {
        Self {
            orbital: OrbitalParams::default(),
            cell: 0.5,
            range_m: 12.0,
            min_wedges: 6,
            window_sigmas: 3.0,
            min_window_m: 1.0,
            max_window_m: 8.0,
            half_yaw: 10f64.to_radians(),
            // `rovernav eval orbital`'s flag threshold (docs/results/2026-11-28-orbital.md).
            max_failure_probability: 0.3,
        }
    }
}

/// The EKF with orbital-map fixes.
#[derive(Clone, Debug)]
pub struct OrbitalMapLocalizer {
    ekf: Ekf,
    orbital: Grid2<f32>,
    params: OrbitalMapParams,
    stats: LocalizerStats,
}

impl OrbitalMapLocalizer {
    /// A localiser starting at `initial` with the world-frame orbital map `orbital` (any
    /// resolution; NaN unknown).
    pub fn new(config: &RoverConfig, initial: Pose3, orbital: Grid2<f32>, params: OrbitalMapParams) -> Self {
        Self { ekf: Ekf::new(config, initial), orbital, params, stats: LocalizerStats::default() }
    }

    /// The underlying filter (e.g. to set its initial uncertainty).
    pub fn ekf_mut(&mut self) -> &mut Ekf {
        &mut self.ekf
    }

    fn try_fix(&mut self, frame: &SensorFrame) {
        let p = self.params;
        let estimate = self.ekf.estimate();
        let points: Vec<[f32; 3]> = frame.clouds.iter().flat_map(|c| c.points.iter().copied()).collect();
        let local = panorama_map(&points, estimate.pose.roll, estimate.pose.pitch, p.range_m, p.cell);
        let mut window = SearchWindow::from_estimate(&estimate, p.window_sigmas, p.min_window_m, p.half_yaw);
        window.half_x = window.half_x.min(p.max_window_m);
        window.half_y = window.half_y.min(p.max_window_m);
        window.half_yaw = window.half_yaw.min(p.half_yaw);
        let reach = p.range_m + window.half_x.max(window.half_y) + 6.0;
        let c = window.center;
        let reference = reference_around(&self.orbital, c.x, c.y, reach, p.cell);
        self.stats.matches_attempted += 1;
        let Ok(fix) = match_orbital(&local, &reference, &window, &p.orbital) else {
            self.stats.fixes_rejected += 1;
            return;
        };
        let edge = 1.01 * p.cell;
        let on_edge = (fix.pose.x - c.x).abs() > window.half_x - edge
            || (fix.pose.y - c.y).abs() > window.half_y - edge;
        let uncertain = fix.failure_probability > p.max_failure_probability;
        if uncertain || on_edge || !self.ekf.fuse_fix(&fix) {
            self.stats.fixes_rejected += 1;
            self.stats.rejected_uncertain += u64::from(uncertain);
            self.stats.rejected_on_edge += u64::from(on_edge && !uncertain);
            return;
        }
        self.stats.fixes_used += 1;
    }
}

impl Localizer for OrbitalMapLocalizer {
    fn name(&self) -> &str {
        "orbital-map"
    }

    fn reset(&mut self, pose: Pose3) {
        self.ekf.reset(pose);
    }

    fn update(&mut self, frame: &SensorFrame) {
        self.ekf.update(frame);
        if frame.clouds.iter().filter(|c| !c.points.is_empty()).count() >= self.params.min_wedges {
            self.try_fix(frame);
        }
    }

    fn estimate(&self) -> PoseEstimate {
        self.ekf.estimate()
    }

    fn stats(&self) -> LocalizerStats {
        let e = self.ekf.stats();
        LocalizerStats {
            zero_velocity_updates: e.zero_updates,
            slip_corrections: e.slip_corrections,
            ..self.stats
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::orbital::degrade;
    use crate::synthetic::{StereoModel, TerrainParams, fractal_terrain, stereo_points};
    use rovernav_core::{CameraKind, PointCloud, Wedge};

    /// A rover whose estimate is 1.4 m off: the first panorama matched against the terrain's
    /// 1 m orbital map brings it within 0.5 m of the truth, with a fix counted as used.
    #[test]
    fn a_panorama_pulls_a_wrong_estimate_to_the_truth() {
        let params = TerrainParams { size: 50.0, resolution: 0.1, relief: 0.8, ..TerrainParams::default() };
        let terrain = fractal_terrain(&params, 7);
        let orbital = degrade(&terrain.heights, 1.0);
        let truth = Pose3 { x: 1.0, y: -2.0, yaw: 0.4, ..Default::default() };
        let clouds: Vec<PointCloud> = (0..8)
            .map(|k| {
                let bearing = k as f64 * std::f64::consts::FRAC_PI_4;
                let model = StereoModel {
                    bearing,
                    fov: 50f64.to_radians(),
                    max_range: 12.0,
                    ray_spacing: 0.1,
                    ..StereoModel::default()
                };
                PointCloud {
                    camera: CameraKind::Mast,
                    origin: [0.0, 0.0, 1.2],
                    wedge: Wedge { bearing, half_angle: 25f64.to_radians(), min_range: 1.0, max_range: 12.0 },
                    points: stereo_points(&terrain, &truth, &model, 100 + k),
                }
            })
            .collect();
        let start = Pose3 { x: truth.x + 1.2, y: truth.y - 0.7, ..truth };
        let mut loc =
            OrbitalMapLocalizer::new(&RoverConfig::default(), start, orbital, OrbitalMapParams::default());
        loc.ekf_mut().reset_position(start.x, start.y, 1.5);
        loc.update(&SensorFrame { clouds, ..SensorFrame::default() });
        let e = loc.estimate().pose;
        assert!((e.x - truth.x).hypot(e.y - truth.y) < 0.5, "estimate {e:?}, {:?}", loc.stats());
        assert_eq!(loc.stats().fixes_used, 1);
        // A frame without a panorama leaves the estimate alone.
        loc.update(&SensorFrame::default());
        assert_eq!(loc.stats().matches_attempted, 1);
    }
}
