//! Dead reckoning from compass heading and wheel encoders (paper 001, SR2 sensor section and
//! field test).
//!
//! SR2 positions itself by combining the magnetic compass heading with the average of the left
//! and right encoder counts (a spin in place averages to zero); the closed-loop field test found
//! the final position within 2% of the distance travelled. Here the displacement is further
//! projected through the inclinometer pitch so that driving on a slope advances the horizontal
//! position by `cos(pitch)` of the wheel travel, and the vertical position integrates
//! `-sin(pitch)` of it (REP 103: positive pitch lowers the nose). When the compass reports NaN
//! (a faulty sensor) the heading is carried on by integrating the gyro yaw rate, and the fault
//! is flagged; without any IMU sample the heading follows differential odometry.

use rovernav_core::{
    ImuSample, Localizer, OdometrySample, Pose3, PoseEstimate, RoverConfig, SensorFrame, angle_diff,
    wrap_angle,
};

/// Noise parameters of dead reckoning.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DeadReckoningParams {
    /// Position error as a fraction of the distance travelled (paper 001: 2%).
    pub distance_error_fraction: f64,
    /// Standard deviation of a compass heading (rad; paper 001: +-0.5 deg).
    pub compass_sigma: f64,
    /// Heading drift rate while integrating the gyro (rad/s, one sigma).
    pub gyro_drift_sigma: f64,
    /// Heading error per metre of differential-odometry turning (rad/m, one sigma).
    pub odometry_yaw_sigma_per_m: f64,
}

impl Default for DeadReckoningParams {
    fn default() -> Self {
        Self {
            distance_error_fraction: 0.02,
            compass_sigma: 0.5f64.to_radians(),
            gyro_drift_sigma: 2e-4,
            odometry_yaw_sigma_per_m: 0.05,
        }
    }
}

/// Compass + encoder dead reckoning, the SR2 localiser.
#[derive(Clone, Debug)]
pub struct DeadReckoning {
    params: DeadReckoningParams,
    counts_per_m: f64,
    track: f64,
    pose: Pose3,
    /// Encoder counts at the last integrated odometry sample (counts are cumulative from zero
    /// when the localiser is built).
    last_counts: (i64, i64),
    /// Time of the last IMU sample, for gyro integration.
    last_imu_t: Option<f64>,
    /// Heading used at the last odometry sample, to integrate with the midpoint heading.
    heading_at_last_odometry: f64,
    /// Position standard deviation accumulated from distance travelled (m).
    position_sigma: f64,
    /// Heading variance (rad^2).
    yaw_variance: f64,
    compass_fault: bool,
    distance: f64,
    have_imu: bool,
}

impl DeadReckoning {
    /// A dead reckoner for a rover, starting at `initial`, with encoder counts taken as zero now.
    pub fn new(config: &RoverConfig, initial: Pose3) -> Self {
        Self::with_params(config, initial, DeadReckoningParams::default())
    }

    /// Same as [`DeadReckoning::new`] with explicit noise parameters.
    pub fn with_params(config: &RoverConfig, initial: Pose3, params: DeadReckoningParams) -> Self {
        Self {
            params,
            counts_per_m: config.encoder_counts_per_cm * 100.0,
            track: config.track,
            pose: initial,
            last_counts: (0, 0),
            last_imu_t: None,
            heading_at_last_odometry: initial.yaw,
            position_sigma: 0.0,
            yaw_variance: 0.0,
            compass_fault: false,
            distance: 0.0,
            have_imu: false,
        }
    }

    /// Sets the encoder counts that correspond to the current pose (for platforms whose counters
    /// do not start at zero).
    pub fn set_encoder_baseline(&mut self, left_counts: i64, right_counts: i64) {
        self.last_counts = (left_counts, right_counts);
    }

    /// Whether the compass reported NaN at any time since construction or the last reset.
    pub fn compass_fault(&self) -> bool {
        self.compass_fault
    }

    /// Wheel travel integrated so far (m, absolute).
    pub fn distance_travelled(&self) -> f64 {
        self.distance
    }

    fn apply_imu(&mut self, s: &ImuSample) {
        self.have_imu = true;
        if s.incl_roll.is_finite() {
            self.pose.roll = s.incl_roll;
        }
        if s.incl_pitch.is_finite() {
            self.pose.pitch = s.incl_pitch;
        }
        if s.compass_yaw.is_finite() {
            self.pose.yaw = wrap_angle(s.compass_yaw);
            self.yaw_variance = self.params.compass_sigma.powi(2);
        } else {
            self.compass_fault = true;
            if let Some(t0) = self.last_imu_t {
                let dt = (s.t - t0).max(0.0);
                if s.gyro_z.is_finite() {
                    self.pose.yaw = wrap_angle(self.pose.yaw + s.gyro_z * dt);
                }
                self.yaw_variance +=
                    (self.params.gyro_drift_sigma * dt).powi(2) + self.params.gyro_drift_sigma.powi(2) * dt;
            }
        }
        self.last_imu_t = Some(s.t);
    }

    fn apply_odometry(&mut self, s: &OdometrySample, heading_from_imu: bool) {
        let dl = (s.left_counts - self.last_counts.0) as f64 / self.counts_per_m;
        let dr = (s.right_counts - self.last_counts.1) as f64 / self.counts_per_m;
        self.last_counts = (s.left_counts, s.right_counts);
        let ds = 0.5 * (dl + dr);
        if !heading_from_imu && self.track > 0.0 {
            // No attitude sensor in this frame: turn with differential odometry.
            let dyaw = (dr - dl) / self.track;
            self.pose.yaw = wrap_angle(self.pose.yaw + dyaw);
            self.yaw_variance += (self.params.odometry_yaw_sigma_per_m * 0.5 * (dl.abs() + dr.abs())).powi(2);
        }
        let mid_heading =
            self.heading_at_last_odometry + 0.5 * angle_diff(self.pose.yaw, self.heading_at_last_odometry);
        let (sp, cp) = self.pose.pitch.sin_cos();
        let horizontal = ds * cp;
        self.pose.x += horizontal * mid_heading.cos();
        self.pose.y += horizontal * mid_heading.sin();
        self.pose.z -= ds * sp;
        self.heading_at_last_odometry = self.pose.yaw;
        self.distance += ds.abs();
        self.position_sigma += self.params.distance_error_fraction * ds.abs();
    }
}

impl Localizer for DeadReckoning {
    fn name(&self) -> &str {
        "dead-reckoning"
    }

    fn reset(&mut self, pose: Pose3) {
        self.pose = pose;
        self.heading_at_last_odometry = pose.yaw;
        self.position_sigma = 0.0;
        self.yaw_variance = 0.0;
        self.compass_fault = false;
    }

    fn update(&mut self, frame: &SensorFrame) {
        // Merge the two streams in time order; IMU first on ties so the odometry step sees the
        // attitude of its own instant.
        let heading_from_imu = !frame.imu.is_empty();
        let (mut i, mut o) = (0, 0);
        while i < frame.imu.len() || o < frame.odometry.len() {
            let take_imu = match (frame.imu.get(i), frame.odometry.get(o)) {
                (Some(a), Some(b)) => a.t <= b.t,
                (Some(_), None) => true,
                _ => false,
            };
            if take_imu {
                let s = frame.imu[i];
                self.apply_imu(&s);
                i += 1;
            } else {
                let s = frame.odometry[o];
                self.apply_odometry(&s, heading_from_imu || self.have_imu);
                o += 1;
            }
        }
        if frame.odometry.is_empty() {
            self.heading_at_last_odometry = self.pose.yaw;
        }
    }

    fn estimate(&self) -> PoseEstimate {
        let pv = self.position_sigma.powi(2);
        PoseEstimate {
            pose: self.pose,
            covariance: [[pv, 0.0, 0.0], [0.0, pv, 0.0], [0.0, 0.0, self.yaw_variance]],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Samples of a rover driving along a known path of (left, right) wheel increments (m) with
    /// a compass reporting the true heading.
    struct Trajectory {
        imu: Vec<ImuSample>,
        odometry: Vec<OdometrySample>,
        truth: Pose3,
    }

    fn drive(config: &RoverConfig, start: Pose3, steps: &[(f64, f64, f64)], compass_ok: bool) -> Trajectory {
        let cpm = config.encoder_counts_per_cm * 100.0;
        let mut truth = start;
        let (mut l, mut r) = (0.0f64, 0.0f64);
        let mut imu = Vec::new();
        let mut odometry = Vec::new();
        let dt = 0.1;
        for (k, &(dl, dr, pitch)) in steps.iter().enumerate() {
            let t = (k + 1) as f64 * dt;
            let dyaw = (dr - dl) / config.track;
            let ds = 0.5 * (dl + dr);
            let mid = truth.yaw + 0.5 * dyaw;
            truth.x += ds * pitch.cos() * mid.cos();
            truth.y += ds * pitch.cos() * mid.sin();
            truth.z -= ds * pitch.sin();
            truth.yaw = wrap_angle(truth.yaw + dyaw);
            truth.pitch = pitch;
            l += dl;
            r += dr;
            imu.push(ImuSample {
                t,
                gyro_z: dyaw / dt,
                incl_roll: 0.0,
                incl_pitch: pitch,
                compass_yaw: if compass_ok { truth.yaw } else { f64::NAN },
                sun_yaw: None,
            });
            odometry.push(OdometrySample {
                t,
                left_counts: (l * cpm).round() as i64,
                right_counts: (r * cpm).round() as i64,
            });
        }
        Trajectory { imu, odometry, truth }
    }

    fn frame(tr: &Trajectory) -> SensorFrame {
        SensorFrame {
            t: tr.imu.last().map_or(0.0, |s| s.t),
            imu: tr.imu.clone(),
            odometry: tr.odometry.clone(),
            ..Default::default()
        }
    }

    #[test]
    fn straight_drive_on_flat_ground_advances_along_heading() {
        let config = RoverConfig::default();
        let start = Pose3 { yaw: 0.7, ..Default::default() };
        let tr = drive(&config, start, &[(0.01, 0.01, 0.0); 200], true);
        let mut dr = DeadReckoning::new(&config, start);
        dr.update(&frame(&tr));
        let e = dr.estimate();
        // 2 m along heading 0.7 worked by hand.
        assert!((e.pose.x - 2.0 * 0.7f64.cos()).abs() < 1e-3);
        assert!((e.pose.y - 2.0 * 0.7f64.sin()).abs() < 1e-3);
        // 2% of 2 m, one sigma.
        assert!((e.covariance[0][0].sqrt() - 0.04).abs() < 1e-6);
    }

    #[test]
    fn slope_odometry_gives_horizontal_displacement() {
        let config = RoverConfig::default();
        let pitch = -0.3; // nose up: climbing
        let tr = drive(&config, Pose3::default(), &[(0.01, 0.01, pitch); 100], true);
        let mut dr = DeadReckoning::new(&config, Pose3::default());
        dr.update(&frame(&tr));
        let e = dr.estimate().pose;
        assert!((e.x - pitch.cos()).abs() < 1e-3, "x {}", e.x);
        assert!((e.z - pitch.sin().abs()).abs() < 1e-3, "climbing raises z: {}", e.z);
        assert!((e.pitch - pitch).abs() < 1e-12);
    }

    #[test]
    fn arc_follows_compass_and_split_frames_agree() {
        let config = RoverConfig::default();
        let steps: Vec<_> =
            (0..300).map(|k| if k % 100 < 50 { (0.008, 0.012, 0.05) } else { (0.012, 0.009, 0.0) }).collect();
        let tr = drive(&config, Pose3::default(), &steps, true);
        let mut whole = DeadReckoning::new(&config, Pose3::default());
        whole.update(&frame(&tr));
        let err = whole.estimate().pose.x - tr.truth.x;
        let err_y = whole.estimate().pose.y - tr.truth.y;
        assert!(err.hypot(err_y) < 0.01, "error {err} {err_y}");
        // Feeding the same samples in two frames gives the same answer.
        let mut split = DeadReckoning::new(&config, Pose3::default());
        let half = Trajectory {
            imu: tr.imu[..150].to_vec(),
            odometry: tr.odometry[..150].to_vec(),
            truth: tr.truth,
        };
        let rest = Trajectory {
            imu: tr.imu[150..].to_vec(),
            odometry: tr.odometry[150..].to_vec(),
            truth: tr.truth,
        };
        split.update(&frame(&half));
        split.update(&frame(&rest));
        assert!((split.estimate().pose.x - whole.estimate().pose.x).abs() < 1e-9);
        assert!((split.estimate().pose.y - whole.estimate().pose.y).abs() < 1e-9);
    }

    #[test]
    fn nan_compass_falls_back_to_gyro_and_flags_fault() {
        let config = RoverConfig::default();
        let steps: Vec<_> = (0..200).map(|_| (0.009, 0.011, 0.0)).collect();
        let tr = drive(&config, Pose3::default(), &steps, false);
        let mut dr = DeadReckoning::new(&config, Pose3::default());
        dr.update(&frame(&tr));
        assert!(dr.compass_fault());
        let e = dr.estimate();
        // The first gyro sample has no predecessor, so one step of turn is lost.
        let one_step = 0.002 / config.track;
        assert!((angle_diff(e.pose.yaw, tr.truth.yaw) + one_step).abs() < 1e-9);
        assert!(e.pose.x.hypot(e.pose.y) > 1.5);
        assert!(e.covariance[2][2] > 0.0);
    }

    #[test]
    fn spin_in_place_does_not_move() {
        let config = RoverConfig::default();
        let tr = drive(&config, Pose3::default(), &[(-0.01, 0.01, 0.0); 100], true);
        let mut dr = DeadReckoning::new(&config, Pose3::default());
        dr.update(&frame(&tr));
        let e = dr.estimate().pose;
        assert!(e.x.abs() < 1e-9 && e.y.abs() < 1e-9);
        assert!((angle_diff(e.yaw, tr.truth.yaw)).abs() < 1e-9);
    }

    #[test]
    fn reset_sets_pose_and_clears_covariance() {
        let config = RoverConfig::default();
        let tr = drive(&config, Pose3::default(), &[(0.01, 0.01, 0.0); 50], true);
        let mut dr = DeadReckoning::new(&config, Pose3::default());
        dr.update(&frame(&tr));
        let fix = Pose3 { x: 5.0, y: -2.0, yaw: 1.0, ..Default::default() };
        dr.reset(fix);
        assert_eq!(dr.estimate().pose, fix);
        assert_eq!(dr.estimate().covariance[0][0], 0.0);
    }
}
