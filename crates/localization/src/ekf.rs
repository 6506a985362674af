//! Pose estimator: gyro + inclinometer attitude, odometry displacement, zero-velocity update,
//! slip correction and map-matching fixes in an extended Kalman filter (paper 004 section 3.2).
//!
//! The MRPTA pose estimator first builds the rotational pose from the azimuth gyro (yaw) and the
//! absolute inclinometer (roll, pitch), then adds the odometer's incremental displacement
//! projected through that attitude. Two features from the paper:
//!
//! - *zero-update*: when the rover has been consistently still for a configurable time, the
//!   heading is held constant (the gyro output is then pure bias plus noise) and each gyro
//!   sample updates the bias estimate;
//! - *slip correction*: the platform rotation measured by the gyro is compared with the one
//!   from differential odometry; a disagreement beyond the gyro noise is blamed on the side
//!   whose wheels over-read (slipping wheels turn more than the ground moves), and that side's
//!   travel is corrected so that both rotations agree before the displacement is integrated.
//!
//! The filter state is (x, y, yaw, gyro bias); z integrates the pitch-projected vertical travel
//! and roll/pitch are the inclinometer readings. Absolute fixes from map matching (paper 000
//! section 4) are fused with their covariance through [`Ekf::fuse_fix`].

use nalgebra::{Matrix3, Matrix3x4, Matrix4, Vector3, Vector4};
use rovernav_core::{
    ImuSample, Localizer, LocalizerStats, OdometrySample, Pose3, PoseEstimate, RoverConfig, SensorFrame,
    angle_diff, wrap_angle,
};

use crate::matching::MatchResult;

/// Measurement variance standing for "not measured" (rad^2): it leaves the state as it was.
const UNMEASURED_VARIANCE: f64 = 1e12;

/// Noise and behaviour parameters of the pose estimator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EkfParams {
    /// Gyro rate noise density (rad/s/sqrt(Hz)): heading random walk.
    pub gyro_noise: f64,
    /// Gyro bias random walk (rad/s/sqrt(s)).
    pub bias_walk: f64,
    /// Initial standard deviation of the gyro bias (rad/s).
    pub initial_bias_sigma: f64,
    /// Initial standard deviation of position (m) and heading (rad).
    pub initial_pose_sigma: (f64, f64),
    /// Along-track odometry error per metre travelled (fraction, one sigma).
    pub along_track_fraction: f64,
    /// Cross-track odometry error per metre travelled (fraction, one sigma).
    pub cross_track_fraction: f64,
    /// Time the rover must be still before the zero-velocity update starts (s).
    pub zero_update_delay: f64,
    /// Largest bias-corrected gyro rate that still counts as "not moving" (rad/s).
    pub still_rate: f64,
    /// Rotation disagreement (gyro vs differential odometry) per metre of wheel travel beyond
    /// which an odometry step is treated as slipping (rad/m), on top of the gyro noise and the
    /// encoder quantisation over the step.
    pub slip_threshold_per_m: f64,
    /// Fixes whose failure probability exceeds this are ignored by [`Ekf::fuse_fix`].
    pub max_fix_failure_probability: f64,
    /// Standard deviation of the compass heading when it is fused (rad); `None` ignores it
    /// (the MRPTA estimator has no compass).
    pub compass_sigma: Option<f64>,
    /// Standard deviation of a sun-sensor heading (rad); `None` ignores the sun sensor.
    pub sun_sigma: Option<f64>,
}

impl Default for EkfParams {
    fn default() -> Self {
        Self {
            gyro_noise: 1e-4,
            bias_walk: 1e-6,
            initial_bias_sigma: 2e-3,
            initial_pose_sigma: (0.01, 0.5f64.to_radians()),
            along_track_fraction: 0.02,
            cross_track_fraction: 0.01,
            zero_update_delay: 2.0,
            still_rate: 0.02,
            slip_threshold_per_m: 0.1,
            max_fix_failure_probability: 0.2,
            compass_sigma: None,
            sun_sigma: Some(1f64.to_radians()),
        }
    }
}

/// Counters of the estimator's special events.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EkfStats {
    /// Odometry steps in which slip was detected and corrected.
    pub slip_corrections: u64,
    /// Wheel travel removed by slip correction (m, absolute).
    pub slip_removed: f64,
    /// Gyro samples used for zero-velocity bias updates.
    pub zero_updates: u64,
    /// Map-matching fixes fused.
    pub fixes_fused: u64,
    /// Map-matching fixes rejected.
    pub fixes_rejected: u64,
}

/// The pose-estimation EKF over (x, y, yaw, gyro bias).
#[derive(Clone, Debug)]
pub struct Ekf {
    params: EkfParams,
    counts_per_m: f64,
    track: f64,
    state: Vector4<f64>,
    cov: Matrix4<f64>,
    z: f64,
    roll: f64,
    pitch: f64,
    last_counts: (i64, i64),
    last_imu_t: Option<f64>,
    /// Gyro rotation (bias corrected) integrated since the last odometry sample.
    gyro_rotation_since_odometry: f64,
    /// Time the gyro rotation above started accumulating.
    gyro_rotation_start: Option<f64>,
    heading_at_last_odometry: f64,
    /// Start of the current still period and the heading then.
    still_since: Option<(f64, f64)>,
    /// Gyro samples seen during the still period before the zero-update engaged.
    pending_still_rates: Vec<(f64, f64)>,
    zero_update_active: bool,
    stats: EkfStats,
}

impl Ekf {
    /// An estimator starting at `initial`, with encoder counts taken as zero now.
    pub fn new(config: &RoverConfig, initial: Pose3) -> Self {
        Self::with_params(config, initial, EkfParams::default())
    }

    /// Same as [`Ekf::new`] with explicit parameters.
    pub fn with_params(config: &RoverConfig, initial: Pose3, params: EkfParams) -> Self {
        let (ps, ys) = params.initial_pose_sigma;
        Self {
            params,
            counts_per_m: config.encoder_counts_per_cm * 100.0,
            track: config.track,
            state: Vector4::new(initial.x, initial.y, wrap_angle(initial.yaw), 0.0),
            cov: Matrix4::from_diagonal(&Vector4::new(
                ps * ps,
                ps * ps,
                ys * ys,
                params.initial_bias_sigma.powi(2),
            )),
            z: initial.z,
            roll: initial.roll,
            pitch: initial.pitch,
            last_counts: (0, 0),
            last_imu_t: None,
            gyro_rotation_since_odometry: 0.0,
            gyro_rotation_start: None,
            heading_at_last_odometry: initial.yaw,
            still_since: None,
            pending_still_rates: Vec::new(),
            zero_update_active: false,
            stats: EkfStats::default(),
        }
    }

    /// Sets the encoder counts that correspond to the current pose.
    pub fn set_encoder_baseline(&mut self, left_counts: i64, right_counts: i64) {
        self.last_counts = (left_counts, right_counts);
    }

    /// The estimated gyro bias (rad/s).
    pub fn gyro_bias(&self) -> f64 {
        self.state[3]
    }

    /// Standard deviation of the gyro bias estimate (rad/s).
    pub fn gyro_bias_sigma(&self) -> f64 {
        self.cov[(3, 3)].max(0.0).sqrt()
    }

    /// Event counters.
    pub fn stats(&self) -> EkfStats {
        self.stats
    }

    /// Whether the zero-velocity update is currently holding the heading.
    pub fn zero_update_active(&self) -> bool {
        self.zero_update_active
    }

    /// The full 4x4 covariance over (x, y, yaw, gyro bias).
    pub fn full_covariance(&self) -> [[f64; 4]; 4] {
        let mut out = [[0.0; 4]; 4];
        for (r, row) in out.iter_mut().enumerate() {
            for (c, v) in row.iter_mut().enumerate() {
                *v = self.cov[(r, c)];
            }
        }
        out
    }

    /// Resets only the horizontal position to an external fix with standard deviation `sigma`
    /// (m), keeping heading and bias and dropping their correlation with position.
    pub fn reset_position(&mut self, x: f64, y: f64, sigma: f64) {
        self.state[0] = x;
        self.state[1] = y;
        for i in 0..2 {
            for j in 0..4 {
                self.cov[(i, j)] = 0.0;
                self.cov[(j, i)] = 0.0;
            }
            self.cov[(i, i)] = sigma * sigma;
        }
    }

    /// Adds process noise to the position (m^2, both axes) and heading (rad^2) variances: for
    /// error sources the odometry model leaves out (e.g. systematic slip).
    pub fn add_pose_noise(&mut self, position_variance: f64, heading_variance: f64) {
        self.cov[(0, 0)] += position_variance.max(0.0);
        self.cov[(1, 1)] += position_variance.max(0.0);
        self.cov[(2, 2)] += heading_variance.max(0.0);
    }

    /// Multiplies the position block of the covariance by `factor` (its rows and columns by
    /// the square root), keeping its correlations: covariance intersection's inflation of the
    /// filter's side before an ordinary update.
    pub fn scale_position_covariance(&mut self, factor: f64) {
        let s = factor.max(0.0).sqrt();
        for i in 0..2 {
            for j in 0..4 {
                self.cov[(i, j)] *= s;
                self.cov[(j, i)] *= s;
            }
        }
    }

    /// Replaces the (x, y, yaw) block of the covariance, dropping its correlation with the gyro
    /// bias: used after a map-relative fix, whose error is the map's own placement error.
    pub fn set_pose_covariance(&mut self, covariance: &[[f64; 3]; 3]) {
        for (i, row) in covariance.iter().enumerate() {
            for (j, v) in row.iter().enumerate() {
                self.cov[(i, j)] = *v;
            }
            self.cov[(i, 3)] = 0.0;
            self.cov[(3, i)] = 0.0;
        }
    }

    /// Fuses a map-matching fix (position and heading with covariance). Returns whether the fix
    /// was used: fixes with a high failure probability or a non-finite covariance are rejected.
    pub fn fuse_fix(&mut self, fix: &MatchResult) -> bool {
        let r = Matrix3::from_fn(|i, j| fix.covariance[i][j]);
        let ok = fix.failure_probability <= self.params.max_fix_failure_probability
            && r.iter().all(|v| v.is_finite())
            && fix.pose.x.is_finite()
            && fix.pose.y.is_finite()
            && fix.pose.yaw.is_finite();
        if !ok {
            self.stats.fixes_rejected += 1;
            return false;
        }
        let h = Matrix3x4::new(1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0);
        let mut innovation = Vector3::new(
            fix.pose.x - self.state[0],
            fix.pose.y - self.state[1],
            angle_diff(fix.pose.yaw, self.state[2]),
        );
        // A heading variance of 0 means the match held the heading fixed (a window of no
        // heading width) rather than measured it: fuse the position only.
        let mut r = r;
        if fix.covariance[2][2] <= 0.0 {
            r.fill_row(2, 0.0);
            r.fill_column(2, 0.0);
            r[(2, 2)] = UNMEASURED_VARIANCE;
            innovation[2] = 0.0;
        }
        if !self.kalman_update(&h, &innovation, &r) {
            self.stats.fixes_rejected += 1;
            return false;
        }
        self.heading_at_last_odometry = self.state[2];
        self.stats.fixes_fused += 1;
        true
    }

    /// Generic EKF update with a 3-row measurement; false when the innovation covariance is
    /// singular.
    fn kalman_update(&mut self, h: &Matrix3x4<f64>, innovation: &Vector3<f64>, r: &Matrix3<f64>) -> bool {
        let s = h * self.cov * h.transpose() + r;
        let Some(s_inv) = s.try_inverse() else {
            return false;
        };
        let k = self.cov * h.transpose() * s_inv;
        self.state += k * innovation;
        self.state[2] = wrap_angle(self.state[2]);
        // Joseph form keeps the covariance symmetric and positive.
        let i_kh = Matrix4::identity() - k * h;
        self.cov = i_kh * self.cov * i_kh.transpose() + k * r * k.transpose();
        true
    }

    /// Scalar EKF update of one state component with measurement variance `var`.
    fn scalar_update(&mut self, index: usize, innovation: f64, var: f64) {
        let s = self.cov[(index, index)] + var;
        if s <= 0.0 || !s.is_finite() {
            return;
        }
        let k: Vector4<f64> = self.cov.column(index) / s;
        self.state += k * innovation;
        self.state[2] = wrap_angle(self.state[2]);
        let mut h = Vector4::zeros();
        h[index] = 1.0;
        let i_kh = Matrix4::identity() - k * h.transpose();
        self.cov = i_kh * self.cov * i_kh.transpose() + k * k.transpose() * var;
    }

    fn apply_imu(&mut self, s: &ImuSample, wheels_moving: bool) {
        if s.incl_roll.is_finite() {
            self.roll = s.incl_roll;
        }
        if s.incl_pitch.is_finite() {
            self.pitch = s.incl_pitch;
        }
        let Some(t0) = self.last_imu_t.replace(s.t) else {
            self.fuse_heading_sensors(s);
            return;
        };
        let dt = (s.t - t0).max(0.0);
        if !s.gyro_z.is_finite() || dt == 0.0 {
            self.fuse_heading_sensors(s);
            return;
        }
        let rate = s.gyro_z - self.state[3];
        let still = !wheels_moving && rate.abs() < self.params.still_rate;
        if still {
            let (since, _) = *self.still_since.get_or_insert((t0, self.state[2]));
            if !self.zero_update_active && s.t - since >= self.params.zero_update_delay {
                // Consistently still: the heading drift accumulated while waiting was bias,
                // so restore the heading of the start of the still period and learn the bias
                // from every gyro sample of the period.
                self.zero_update_active = true;
                if let Some((_, heading)) = self.still_since {
                    self.state[2] = heading;
                }
                for (rate_sample, sample_dt) in std::mem::take(&mut self.pending_still_rates) {
                    self.zero_update(rate_sample, sample_dt);
                }
            }
            if self.zero_update_active {
                self.zero_update(s.gyro_z, dt);
                self.fuse_heading_sensors(s);
                return;
            }
            self.pending_still_rates.push((s.gyro_z, dt));
        } else {
            self.still_since = None;
            self.pending_still_rates.clear();
            self.zero_update_active = false;
        }
        self.propagate_heading(rate, dt);
        self.fuse_heading_sensors(s);
    }

    /// Integrates the bias-corrected gyro rate over `dt`.
    fn propagate_heading(&mut self, rate: f64, dt: f64) {
        self.state[2] = wrap_angle(self.state[2] + rate * dt);
        self.gyro_rotation_since_odometry += rate * dt;
        let mut f = Matrix4::identity();
        f[(2, 3)] = -dt;
        let mut q = Matrix4::zeros();
        q[(2, 2)] = self.params.gyro_noise.powi(2) * dt;
        q[(3, 3)] = self.params.bias_walk.powi(2) * dt;
        self.cov = f * self.cov * f.transpose() + q;
    }

    /// Zero-velocity update: the heading is held, and the raw gyro rate measures the bias.
    fn zero_update(&mut self, raw_rate: f64, dt: f64) {
        if dt <= 0.0 {
            return;
        }
        self.cov[(3, 3)] += self.params.bias_walk.powi(2) * dt;
        // A rate averaged over dt has variance noise_density^2 / dt.
        let var = self.params.gyro_noise.powi(2) / dt;
        self.scalar_update(3, raw_rate - self.state[3], var);
        self.stats.zero_updates += 1;
    }

    fn fuse_heading_sensors(&mut self, s: &ImuSample) {
        if let (Some(sigma), true) = (self.params.compass_sigma, s.compass_yaw.is_finite()) {
            let innovation = angle_diff(s.compass_yaw, self.state[2]);
            self.scalar_update(2, innovation, sigma * sigma);
        }
        if let (Some(sigma), Some(sun)) = (self.params.sun_sigma, s.sun_yaw)
            && sun.is_finite()
        {
            let innovation = angle_diff(sun, self.state[2]);
            self.scalar_update(2, innovation, sigma * sigma);
        }
    }

    fn apply_odometry(&mut self, s: &OdometrySample, have_gyro: bool) {
        let mut dl = (s.left_counts - self.last_counts.0) as f64 / self.counts_per_m;
        let mut dr = (s.right_counts - self.last_counts.1) as f64 / self.counts_per_m;
        self.last_counts = (s.left_counts, s.right_counts);
        let gyro_rotation = std::mem::take(&mut self.gyro_rotation_since_odometry);
        let interval = self.gyro_rotation_start.replace(s.t).map_or(0.0, |t0| (s.t - t0).max(0.0));
        if dl == 0.0 && dr == 0.0 {
            self.heading_at_last_odometry = self.state[2];
            return;
        }
        if have_gyro && self.track > 0.0 {
            let odometry_rotation = (dr - dl) / self.track;
            let disagreement = odometry_rotation - gyro_rotation;
            let quantisation = 2.0 / (self.counts_per_m * self.track);
            let tolerance = self.params.slip_threshold_per_m * 0.5 * (dl.abs() + dr.abs())
                + quantisation
                + 3.0 * self.params.gyro_noise * interval.sqrt();
            if disagreement.abs() > tolerance {
                self.correct_slip(&mut dl, &mut dr, disagreement);
            }
        } else if self.track > 0.0 {
            // No gyro this frame: differential odometry is the only rotation source.
            let rotation = (dr - dl) / self.track;
            self.state[2] = wrap_angle(self.state[2] + rotation);
            self.cov[(2, 2)] += (self.params.cross_track_fraction * rotation).powi(2);
        }
        let ds = 0.5 * (dl + dr);
        let heading =
            self.heading_at_last_odometry + 0.5 * angle_diff(self.state[2], self.heading_at_last_odometry);
        let (sp, cp) = self.pitch.sin_cos();
        let horizontal = ds * cp;
        let (sh, ch) = heading.sin_cos();
        self.state[0] += horizontal * ch;
        self.state[1] += horizontal * sh;
        self.z -= ds * sp;
        self.heading_at_last_odometry = self.state[2];
        // Jacobian of the position step with respect to heading.
        let mut f = Matrix4::identity();
        f[(0, 2)] = -horizontal * sh;
        f[(1, 2)] = horizontal * ch;
        let along = (self.params.along_track_fraction * ds).powi(2);
        let cross = (self.params.cross_track_fraction * ds).powi(2);
        let mut q = Matrix4::zeros();
        q[(0, 0)] = along * ch * ch + cross * sh * sh;
        q[(1, 1)] = along * sh * sh + cross * ch * ch;
        q[(0, 1)] = (along - cross) * ch * sh;
        q[(1, 0)] = q[(0, 1)];
        self.cov = f * self.cov * f.transpose() + q;
    }

    /// Removes the over-read travel of the slipping side so that differential odometry agrees
    /// with the gyro rotation (`disagreement` = odometry rotation - gyro rotation).
    fn correct_slip(&mut self, dl: &mut f64, dr: &mut f64, disagreement: f64) {
        let excess = disagreement * self.track;
        // Either the right side over-read by `excess` or the left side by `-excess`; slip makes
        // wheels read more travel than the ground gave, so pick the side whose magnitude the
        // correction reduces (and that has the travel to lose).
        let right_fixed = *dr - excess;
        let left_fixed = *dl + excess;
        let right_ok = right_fixed.abs() < dr.abs() && right_fixed * *dr >= 0.0;
        let left_ok = left_fixed.abs() < dl.abs() && left_fixed * *dl >= 0.0;
        match (right_ok, left_ok) {
            (true, false) => *dr = right_fixed,
            (false, true) => *dl = left_fixed,
            // Opposite-signed sides (a pivot or spin): both skid, share the correction so a
            // spin in place stays in place.
            (true, true) => {
                *dr -= 0.5 * excess;
                *dl += 0.5 * excess;
            }
            (false, false) => return,
        }
        self.stats.slip_removed += excess.abs();
        self.stats.slip_corrections += 1;
    }
}

impl Localizer for Ekf {
    fn name(&self) -> &str {
        "ekf"
    }

    fn stats(&self) -> LocalizerStats {
        let s = Ekf::stats(self);
        LocalizerStats {
            matches_attempted: s.fixes_fused + s.fixes_rejected,
            fixes_used: s.fixes_fused,
            fixes_rejected: s.fixes_rejected,
            zero_velocity_updates: s.zero_updates,
            slip_corrections: s.slip_corrections,
            ..LocalizerStats::default()
        }
    }

    fn reset(&mut self, pose: Pose3) {
        let (ps, ys) = self.params.initial_pose_sigma;
        self.state[0] = pose.x;
        self.state[1] = pose.y;
        self.state[2] = wrap_angle(pose.yaw);
        self.z = pose.z;
        self.roll = pose.roll;
        self.pitch = pose.pitch;
        let bias_var = self.cov[(3, 3)];
        self.cov = Matrix4::from_diagonal(&Vector4::new(ps * ps, ps * ps, ys * ys, bias_var));
        self.heading_at_last_odometry = self.state[2];
        self.still_since = None;
        self.pending_still_rates.clear();
        self.zero_update_active = false;
    }

    fn update(&mut self, frame: &SensorFrame) {
        let have_gyro = !frame.imu.is_empty();
        // The wheels count as moving at an IMU sample when the encoders change between the
        // odometry samples bracketing it.
        let (mut i, mut o) = (0, 0);
        let mut previous_counts = self.last_counts;
        while i < frame.imu.len() || o < frame.odometry.len() {
            let take_imu = match (frame.imu.get(i), frame.odometry.get(o)) {
                (Some(a), Some(b)) => a.t <= b.t,
                (Some(_), None) => true,
                _ => false,
            };
            if take_imu {
                let moving = frame
                    .odometry
                    .get(o)
                    .is_some_and(|next| (next.left_counts, next.right_counts) != previous_counts);
                let s = frame.imu[i];
                self.apply_imu(&s, moving);
                i += 1;
            } else {
                let s = frame.odometry[o];
                previous_counts = (s.left_counts, s.right_counts);
                self.apply_odometry(&s, have_gyro);
                o += 1;
            }
        }
    }

    fn estimate(&self) -> PoseEstimate {
        let mut covariance = [[0.0; 3]; 3];
        for (r, row) in covariance.iter_mut().enumerate() {
            for (c, v) in row.iter_mut().enumerate() {
                *v = self.cov[(r, c)];
            }
        }
        PoseEstimate {
            pose: Pose3 {
                x: self.state[0],
                y: self.state[1],
                z: self.z,
                roll: self.roll,
                pitch: self.pitch,
                yaw: self.state[2],
            },
            covariance,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, Normal};

    /// One control step of the synthetic rover: true wheel travel (left, right, m), extra
    /// left/right encoder over-read from slip (m), duration (s).
    #[derive(Clone, Copy)]
    struct Step {
        left: f64,
        right: f64,
        slip_left: f64,
        slip_right: f64,
        dt: f64,
    }

    fn step(left: f64, right: f64, dt: f64) -> Step {
        Step { left, right, slip_left: 0.0, slip_right: 0.0, dt }
    }

    /// Simulates the sensors along the steps; returns the frame and the true final pose.
    fn simulate(
        config: &RoverConfig,
        steps: &[Step],
        gyro_bias: f64,
        gyro_noise: f64,
        seed: u64,
    ) -> (SensorFrame, Pose3) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let noise = Normal::new(0.0, 1.0).unwrap();
        let cpm = config.encoder_counts_per_cm * 100.0;
        let mut truth = Pose3::default();
        let (mut l, mut r, mut t) = (0.0f64, 0.0f64, 0.0f64);
        let mut frame = SensorFrame::default();
        frame.imu.push(ImuSample { t, gyro_z: gyro_bias, compass_yaw: f64::NAN, ..Default::default() });
        for s in steps {
            let dyaw = (s.right - s.left) / config.track;
            let ds = 0.5 * (s.left + s.right);
            let mid = truth.yaw + 0.5 * dyaw;
            truth.x += ds * mid.cos();
            truth.y += ds * mid.sin();
            truth.yaw = wrap_angle(truth.yaw + dyaw);
            t += s.dt;
            l += s.left + s.slip_left;
            r += s.right + s.slip_right;
            frame.imu.push(ImuSample {
                t,
                gyro_z: dyaw / s.dt + gyro_bias + gyro_noise / s.dt.sqrt() * noise.sample(&mut rng),
                compass_yaw: f64::NAN,
                ..Default::default()
            });
            frame.odometry.push(OdometrySample {
                t,
                left_counts: (l * cpm).round() as i64,
                right_counts: (r * cpm).round() as i64,
            });
        }
        frame.t = t;
        (frame, truth)
    }

    #[test]
    fn straight_drive_without_bias_tracks_truth() {
        let config = RoverConfig::default();
        let steps: Vec<_> = (0..300).map(|_| step(0.01, 0.0105, 0.1)).collect();
        let (frame, truth) = simulate(&config, &steps, 0.0, 0.0, 1);
        let mut ekf = Ekf::new(&config, Pose3::default());
        ekf.update(&frame);
        let e = ekf.estimate();
        assert!((e.pose.x - truth.x).hypot(e.pose.y - truth.y) < 0.01);
        assert!(angle_diff(e.pose.yaw, truth.yaw).abs() < 1e-3);
        assert_eq!(ekf.stats().slip_corrections, 0);
        // Position covariance grows with distance (2% along-track of ~3 m gives ~6 cm).
        let sigma = (e.covariance[0][0] + e.covariance[1][1]).sqrt();
        assert!(sigma > 0.03 && sigma < 0.2, "sigma {sigma}");
    }

    #[test]
    fn zero_update_holds_heading_and_learns_gyro_bias() {
        let config = RoverConfig::default();
        let bias = 0.002;
        let mut steps: Vec<_> = (0..300).map(|_| step(0.0, 0.0, 0.1)).collect();
        steps.extend((0..200).map(|_| step(0.01, 0.01, 0.1)));
        let (frame, truth) = simulate(&config, &steps, bias, 1e-4, 7);
        let mut ekf = Ekf::new(&config, Pose3::default());
        ekf.update(&frame);
        assert!(ekf.stats().zero_updates > 200);
        // The bias is learnt from 30 s of stillness: noise 1e-4/sqrt(30) ~ 2e-5.
        assert!((ekf.gyro_bias() - bias).abs() < 1e-4, "bias {}", ekf.gyro_bias());
        assert!(ekf.gyro_bias_sigma() < 1e-4);
        // Integrating the raw gyro would have turned 0.002 * 50 s = 0.1 rad.
        let e = ekf.estimate();
        assert!(angle_diff(e.pose.yaw, truth.yaw).abs() < 0.005, "yaw {}", e.pose.yaw);
        assert!((e.pose.y - truth.y).abs() < 0.01);
    }

    #[test]
    fn without_stillness_the_bias_is_not_learnt() {
        let config = RoverConfig::default();
        let steps: Vec<_> = (0..300).map(|_| step(0.01, 0.01, 0.1)).collect();
        let (frame, _) = simulate(&config, &steps, 0.002, 1e-4, 7);
        let mut ekf = Ekf::new(&config, Pose3::default());
        ekf.update(&frame);
        assert_eq!(ekf.stats().zero_updates, 0);
        assert!(ekf.gyro_bias().abs() < 1e-9);
    }

    #[test]
    fn slip_of_one_side_is_detected_and_removed() {
        let config = RoverConfig::default();
        // The left wheels over-read by 30% while the rover drives straight.
        let steps: Vec<_> = (0..200).map(|_| Step { slip_left: 0.003, ..step(0.01, 0.01, 0.1) }).collect();
        let (frame, truth) = simulate(&config, &steps, 0.0, 0.0, 3);
        let mut ekf = Ekf::new(&config, Pose3::default());
        ekf.update(&frame);
        let e = ekf.estimate().pose;
        assert!(ekf.stats().slip_corrections > 150);
        // Averaging the encoders would overshoot by 15% (0.3 m of 2 m), as dead reckoning does.
        assert!((e.x - truth.x).abs() < 0.01, "x {} truth {}", e.x, truth.x);
        assert!(angle_diff(e.yaw, truth.yaw).abs() < 1e-3);
        let mut dead = crate::DeadReckoning::new(&config, Pose3::default());
        dead.update(&SensorFrame { imu: Vec::new(), ..frame.clone() });
        assert!(dead.distance_travelled() > truth.x + 0.2);
    }

    #[test]
    fn fix_fusion_matches_scalar_kalman_gain() {
        let config = RoverConfig::default();
        let mut ekf = Ekf::new(&config, Pose3::default());
        let p = ekf.full_covariance();
        let r = 0.02f64.powi(2);
        let fix = MatchResult {
            pose: rovernav_core::Pose2::new(0.1, -0.05, 0.01),
            covariance: [[r, 0.0, 0.0], [0.0, r, 0.0], [0.0, 0.0, r]],
            log_likelihood: 0.0,
            failure_probability: 0.0,
            poses_evaluated: 1,
        };
        assert!(ekf.fuse_fix(&fix));
        let e = ekf.estimate();
        // Diagonal, uncorrelated case: x' = p / (p + r) * z, P' = p r / (p + r).
        let gain = p[0][0] / (p[0][0] + r);
        assert!((e.pose.x - gain * 0.1).abs() < 1e-12);
        assert!((e.pose.y + gain * 0.05).abs() < 1e-12);
        assert!((e.covariance[0][0] - p[0][0] * r / (p[0][0] + r)).abs() < 1e-12);
        let yaw_gain = p[2][2] / (p[2][2] + r);
        assert!((e.pose.yaw - yaw_gain * 0.01).abs() < 1e-12);
        let bad = MatchResult { failure_probability: 0.9, ..fix };
        assert!(!ekf.fuse_fix(&bad));
        assert_eq!(ekf.stats().fixes_rejected, 1);
    }

    #[test]
    fn a_fix_with_its_heading_held_fixed_updates_the_position_only() {
        let config = RoverConfig::default();
        let mut ekf = Ekf::new(&config, Pose3::default());
        let p = ekf.full_covariance();
        let r = 0.02f64.powi(2);
        let fix = MatchResult {
            pose: rovernav_core::Pose2::new(0.1, 0.0, 0.3),
            covariance: [[r, 0.0, 0.0], [0.0, r, 0.0], [0.0, 0.0, 0.0]],
            log_likelihood: 0.0,
            failure_probability: 0.0,
            poses_evaluated: 1,
        };
        assert!(ekf.fuse_fix(&fix));
        let e = ekf.estimate();
        assert!((e.pose.x - p[0][0] / (p[0][0] + r) * 0.1).abs() < 1e-9);
        // The heading and its variance are as before: a held heading is no measurement.
        assert!(e.pose.yaw.abs() < 1e-9, "yaw {}", e.pose.yaw);
        assert!((e.covariance[2][2] - p[2][2]).abs() < 1e-9 * p[2][2].max(1e-12));
    }

    #[test]
    fn reset_and_position_reset() {
        let config = RoverConfig::default();
        let mut ekf = Ekf::new(&config, Pose3::default());
        let pose = Pose3 { x: 3.0, y: 4.0, yaw: -1.0, ..Default::default() };
        ekf.reset(pose);
        assert_eq!(ekf.estimate().pose, pose);
        ekf.reset_position(1.0, 2.0, 0.5);
        let e = ekf.estimate();
        assert_eq!((e.pose.x, e.pose.y, e.pose.yaw), (1.0, 2.0, -1.0));
        assert!((e.covariance[0][0] - 0.25).abs() < 1e-12 && e.covariance[0][2] == 0.0);
    }
}
