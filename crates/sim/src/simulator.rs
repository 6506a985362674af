//! The simulated platform: executes navigator commands on the true terrain and reports sensors.
//!
//! Implements the platform layer of the stop-sense-plan-drive cycle (paper 000 section 2, paper
//! 004 section 2): a `Sense` command images wedges, `Drive` follows an arc and `Turn` turns in
//! place, both integrated in substeps of one proprioceptive sample period (0.1 s, 1 cm at full
//! speed) with wheel slip, hazard detection and the guards of a guarded move. Motions are
//! commanded in wheel travel (the platform stops when its encoders say the distance is done), so
//! slip shortens the true motion. All randomness comes from ChaCha8 streams derived from the
//! seed, one stream per subsystem, so a run is reproducible and one sensor's draws do not shift
//! another's.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rovernav_core::{
    CameraImage, CameraKind, DriveGuard, NavCommand, OdometrySample, PointCloud, Pose2, Pose3,
    ProximityReading, RoverConfig, SenseRequest, SensorFrame, wrap_angle,
};
use rovernav_terrain::Terrain;

use crate::navcam;
use crate::power::PowerModel;
use crate::raycast::HeightField;
use crate::sensors::{self, Proprioception, RangeGeometry, SensorModel, gaussian};
use crate::stereo_range::{self, RangeSource};
use crate::terrain_window::TerrainWindow;
use crate::vehicle::{self, VehicleGeometry};

/// Time the motor-current monitor takes to declare a stalled wheel (s).
const STALL_DETECT_TIME: f64 = 0.5;

/// A failure injected into the simulated platform, for fault-protection tests.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Fault {
    /// The sensor returns images without points.
    SilentSensor(CameraKind),
    /// The sensor returns images whose points are NaN (a failed correlator or a bad frame
    /// buffer: the count of points is right, their values are not).
    NanRange(CameraKind),
    /// The gyro's bias jumps by this much (rad/s) and stays there.
    GyroBiasJump(f64),
    /// The wheels of one side do not turn; the motor-current monitor stops the motion.
    StalledWheel {
        /// Left side when true, right side otherwise.
        left: bool,
    },
    /// The compass reports NaN.
    CompassNaN,
}

/// Active faults.
#[derive(Clone, Debug, Default)]
struct Faults {
    silent: Vec<CameraKind>,
    nan_range: Vec<CameraKind>,
    stalled_left: Option<bool>,
    compass_nan: bool,
}

/// The world truth and the simulated sensors of one traverse.
#[derive(Clone, Debug)]
pub struct Simulator {
    terrain: Terrain,
    field: HeightField,
    rover: RoverConfig,
    model: SensorModel,
    geometry: VehicleGeometry,
    pose: Pose2,
    truth: Pose3,
    on_terrain: bool,
    in_hazard: bool,
    time: f64,
    hazard_contacts: u32,
    distance: f64,
    sensing_actions: u64,
    /// Cumulative wheel travel, left and right (m).
    wheel_travel: [f64; 2],
    proprio: Proprioception,
    motion_rng: ChaCha8Rng,
    range_rng: ChaCha8Rng,
    /// Sensor noise of the pictures (one draw per image pair).
    image_rng: ChaCha8Rng,
    proximity_rng: ChaCha8Rng,
    faults: Faults,
    /// The proximity reading that stopped the current motion, if a guard did.
    guard_reading: Option<ProximityReading>,
    /// The window onto a tiled terrain that `terrain` is, for long traverses (none for a fixed
    /// terrain).
    window: Option<Box<TerrainWindow>>,
    /// The solar panel, battery and loads.
    power: PowerModel,
}

/// A random stream of the run seed.
fn stream(seed: u64, id: u64) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(id);
    rng
}

impl Simulator {
    /// Places the rover at `start` on the terrain; the run's randomness derives from `seed`.
    pub fn new(
        terrain: Terrain,
        rover: RoverConfig,
        sensors: SensorModel,
        start: Pose2,
        seed: u64,
    ) -> Simulator {
        let field = HeightField::new(&terrain.dem);
        let geometry = VehicleGeometry::new(&rover);
        let start = Pose2::new(start.x, start.y, wrap_angle(start.yaw));
        let contact = vehicle::settle(&terrain.dem, &geometry, start);
        let in_hazard =
            contact.as_ref().is_some_and(|c| vehicle::body_hazard(&terrain.dem, &geometry, c).is_some());
        let truth = contact
            .as_ref()
            .map_or(Pose3 { x: start.x, y: start.y, yaw: start.yaw, ..Default::default() }, |c| c.pose);
        let proprio = Proprioception::new(&sensors, stream(seed, 1));
        Simulator {
            field,
            geometry,
            pose: start,
            truth,
            on_terrain: contact.is_some(),
            in_hazard,
            time: 0.0,
            hazard_contacts: 0,
            distance: 0.0,
            sensing_actions: 0,
            wheel_travel: [0.0; 2],
            proprio,
            motion_rng: stream(seed, 2),
            range_rng: stream(seed, 3),
            proximity_rng: stream(seed, 4),
            image_rng: stream(seed, 5),
            faults: Faults::default(),
            guard_reading: None,
            window: None,
            power: PowerModel::new(sensors.power.clone()),
            terrain,
            rover,
            model: sensors,
        }
    }

    /// Executes one navigator command (Sense / Drive / Turn; Finish is a no-op) and returns what
    /// the sensors report.
    pub fn execute(&mut self, cmd: &NavCommand) -> SensorFrame {
        let mut frame = SensorFrame::default();
        match cmd {
            NavCommand::Sense(requests) => {
                for r in requests {
                    self.sense(r, &mut frame);
                }
                self.rest_sample(&mut frame);
            }
            NavCommand::Drive { distance, curvature, guard } => {
                let v = self.rover.max_speed / (1.0 + curvature.abs() * 0.5 * self.rover.track);
                let duration = if v > 0.0 { distance.abs() / v } else { 0.0 };
                self.move_wheels(*distance, curvature * distance, duration, *guard, &mut frame);
                self.rest_sample(&mut frame);
            }
            NavCommand::Turn { angle } => {
                let rate = self.rover.turn_rate;
                let duration = if rate > 0.0 { angle.abs() / rate } else { 0.0 };
                let before = self.truth;
                self.move_wheels(0.0, *angle, duration, DriveGuard::default(), &mut frame);
                self.rest_sample(&mut frame);
                if let Some(station) = self.model.lander {
                    let poses = [before, self.truth];
                    frame.lander = station
                        .watch(&self.terrain, &self.field, &self.rover, poses, &mut self.image_rng)
                        .map(Box::new);
                }
            }
            NavCommand::Finish(..) => {}
        }
        frame.t = self.time;
        frame.power = Some(self.power.reading());
        // A proximity guard stop reports the reading that stopped the motion.
        frame.proximity = match self.guard_reading.take() {
            Some(reading) => reading,
            None => self.read_proximity(),
        };
        frame
    }

    /// Proprioceptive samples at rest before the first command (lets a localiser estimate the
    /// gyro bias by a zero-velocity update, paper 004 section 3.2).
    pub fn initial_frame(&mut self) -> SensorFrame {
        let mut frame = SensorFrame::default();
        for _ in 0..self.model.initial_rest_samples {
            self.rest_sample(&mut frame);
        }
        frame.t = self.time;
        frame.proximity = self.read_proximity();
        frame.power = Some(self.power.reading());
        frame
    }

    /// Sleeps until `until_s` (the computer in its sleep mode, motors and cameras off, no
    /// sampling), then wakes for one sample at rest (SR2's SLEEP mode, paper 001 section 3).
    pub fn sleep(&mut self, until_s: f64) -> SensorFrame {
        let dt = until_s - self.time;
        if dt.is_finite() && dt > 0.0 {
            self.power.set_asleep(true);
            self.time = until_s;
            self.proprio.elapse(&self.model, dt);
            self.power.advance(self.time, 0.0, 0);
            self.power.set_asleep(false);
        }
        let mut frame = SensorFrame::default();
        self.rest_sample(&mut frame);
        frame.t = self.time;
        frame.proximity = self.read_proximity();
        frame.power = Some(self.power.reading());
        frame
    }

    /// The power system (truth: its totals are for scoring and tests).
    pub fn power(&self) -> &PowerModel {
        &self.power
    }

    /// Injects a fault; it stays until the end of the run.
    pub fn inject_fault(&mut self, fault: Fault) {
        match fault {
            Fault::SilentSensor(kind) => {
                if !self.faults.silent.contains(&kind) {
                    self.faults.silent.push(kind);
                }
            }
            Fault::NanRange(kind) => {
                if !self.faults.nan_range.contains(&kind) {
                    self.faults.nan_range.push(kind);
                }
            }
            Fault::GyroBiasJump(delta) => self.proprio.jump_bias(delta),
            Fault::StalledWheel { left } => self.faults.stalled_left = Some(left),
            Fault::CompassNaN => self.faults.compass_nan = true,
        }
    }

    /// The true 3D pose.
    pub fn truth(&self) -> Pose3 {
        self.truth
    }

    /// The simulation clock (s).
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Times the true rover met a hazard (each stopped motion counts once).
    pub fn hazard_contacts(&self) -> u32 {
        self.hazard_contacts
    }

    /// True path length of the body origin (m, 3D along the surface).
    pub fn distance_driven(&self) -> f64 {
        self.distance
    }

    /// Range images taken.
    pub fn sensing_actions(&self) -> u64 {
        self.sensing_actions
    }

    /// The true terrain.
    pub fn terrain(&self) -> &Terrain {
        &self.terrain
    }

    /// Makes the terrain a window onto a tiled terrain: filled around the rover now (which
    /// settles on it again) and re-filled whenever a motion brings the rover within the
    /// window's margin of its edge.
    pub fn with_window(mut self, window: TerrainWindow) -> Self {
        self.window = Some(Box::new(window));
        self.keep_in_window(self.pose.x, self.pose.y);
        let contact = vehicle::settle(&self.terrain.dem, &self.geometry, self.pose);
        self.in_hazard = contact
            .as_ref()
            .is_some_and(|c| vehicle::body_hazard(&self.terrain.dem, &self.geometry, c).is_some());
        if let Some(c) = &contact {
            self.truth = c.pose;
        }
        self.on_terrain = contact.is_some();
        self
    }

    /// The window onto a tiled terrain, if the terrain is one.
    pub fn window(&self) -> Option<&TerrainWindow> {
        self.window.as_deref()
    }

    /// Re-fills the window around (x, y) when that point is within its margin of the edge.
    fn keep_in_window(&mut self, x: f64, y: f64) {
        if let Some(window) = self.window.as_mut()
            && window.needs_refill(x, y)
        {
            self.terrain = window.fill_around(x, y);
            self.field = HeightField::new(&self.terrain.dem);
        }
    }

    /// The rover parameters.
    pub fn rover(&self) -> &RoverConfig {
        &self.rover
    }

    /// The sensor and slip parameters.
    pub fn sensor_model(&self) -> &SensorModel {
        &self.model
    }

    /// Cumulative true wheel travel of the left and right sides (m), before quantisation.
    pub fn wheel_travel(&self) -> [f64; 2] {
        self.wheel_travel
    }

    /// The gyro's current true bias (rad/s), for evaluating bias estimators.
    pub fn gyro_bias(&self) -> f64 {
        self.proprio.bias()
    }

    /// Encoder counts of the current wheel travel.
    fn odometry(&self) -> OdometrySample {
        let per_m = 100.0 * self.rover.encoder_counts_per_cm;
        OdometrySample {
            t: self.time,
            left_counts: (self.wheel_travel[0] * per_m).floor() as i64,
            right_counts: (self.wheel_travel[1] * per_m).floor() as i64,
        }
    }

    /// Appends one sample of every proprioceptive sensor with the given true yaw rate.
    fn push_sample(&mut self, frame: &mut SensorFrame, yaw_rate: f64) {
        let imu = self.proprio.sample(&self.model, self.time, &self.truth, yaw_rate, self.faults.compass_nan);
        frame.imu.push(imu);
        frame.odometry.push(self.odometry());
    }

    /// One sample period at rest, then a sample.
    fn rest_sample(&mut self, frame: &mut SensorFrame) {
        let period = 1.0 / self.model.sample_rate.max(1e-3);
        self.time += period;
        self.proprio.elapse(&self.model, period);
        self.power.advance(self.time, 0.0, 0);
        self.push_sample(frame, 0.0);
    }

    /// Reads the proximity sensors for a guard; keeps the reading when it trips.
    fn proximity_guard_trips(&mut self) -> bool {
        let reading = self.read_proximity();
        if reading.any() {
            self.guard_reading = Some(reading);
        }
        reading.any()
    }

    fn read_proximity(&mut self) -> ProximityReading {
        sensors::proximity(
            &self.terrain.dem,
            &self.field,
            &self.truth,
            &self.rover,
            &self.model.proximity,
            &mut self.proximity_rng,
        )
    }

    /// Takes one range image.
    fn sense(&mut self, request: &SenseRequest, frame: &mut SensorFrame) {
        match *request {
            SenseRequest::Navcam { pan, tilt } => {
                return self.take_pictures(navcam::Pair::Navcam { pan, tilt }, frame);
            }
            SenseRequest::BodyPair { front } => {
                return self.take_pictures(navcam::Pair::Body { front }, frame);
            }
            _ => {}
        }
        let (geometry, imager) = match *request {
            SenseRequest::Mast { pan } => {
                (RangeGeometry::mast(&self.rover, &self.model, pan), &self.model.mast)
            }
            SenseRequest::MastFine { pan } => {
                (RangeGeometry::mast_fine(&self.rover, &self.model, pan), &self.model.mast_fine)
            }
            SenseRequest::BodyFront => {
                (RangeGeometry::body(&self.rover, &self.model, true), &self.model.body)
            }
            SenseRequest::BodyRear => {
                (RangeGeometry::body(&self.rover, &self.model, false), &self.model.body)
            }
            SenseRequest::Lidar { pan } => (RangeGeometry::lidar(&self.model, pan), &self.model.lidar.imager),
            SenseRequest::Navcam { .. } | SenseRequest::BodyPair { .. } => {
                unreachable!("pictures are taken above")
            }
        };
        let stereo = self.model.range_source == RangeSource::Stereo && geometry.camera != CameraKind::Lidar;
        let mut cloud = if stereo {
            let capture = stereo_range::capture(
                &self.terrain,
                &self.field,
                &self.truth,
                &geometry,
                &self.model.stereo,
                &mut self.range_rng,
            );
            frame.images.push(CameraImage {
                camera: stereo_range::left_camera_name(geometry.camera).into(),
                t: self.time,
                width: capture.left.image.width(),
                height: capture.left.image.height(),
                bits: 12,
                pixels: capture.left.image.into_raw(),
                // The wedge's pointing: bearing, and the middle of its elevation span.
                pan: geometry.bearing,
                tilt: 0.5 * (geometry.elevation_min + geometry.elevation_max),
            });
            // The navigators' wedge is the one the ray grid would have covered.
            PointCloud { wedge: geometry.wedge(imager), ..capture.cloud }
        } else {
            sensors::capture(
                &self.terrain.dem,
                &self.field,
                &self.truth,
                &geometry,
                imager,
                &mut self.range_rng,
            )
        };
        if self.faults.silent.contains(&geometry.camera) {
            cloud.points.clear();
        }
        if self.faults.nan_range.contains(&geometry.camera) {
            for p in &mut cloud.points {
                *p = [f32::NAN; 3];
            }
        }
        let dt = imager.capture_time.max(0.0);
        self.time += dt;
        self.proprio.elapse(&self.model, dt);
        // A stereo pair's two images, or a LIDAR nod counted as much.
        self.power.advance(self.time, 0.0, 2);
        self.sensing_actions += 1;
        frame.clouds.push(cloud);
    }

    /// Renders a pair at the current true pose and clock without changing the simulator (no
    /// time, energy or noise draws of its own streams; `seed` draws the pictures' noise):
    /// pictures exposed while another command's sensing holds the rover still, so that taking
    /// them cannot change the run (visual target tracking's track-only mode).
    pub fn pictures_alongside(&self, pair: navcam::Pair, seed: u64) -> [CameraImage; 2] {
        navcam::capture_pair(
            &self.terrain,
            &self.field,
            &self.rover,
            &self.truth,
            &self.model.stereo,
            &self.model.navcam,
            pair,
            self.time,
            seed,
        )
    }

    /// Takes a stereo pair's pictures: no range, not a sensing action.
    fn take_pictures(&mut self, pair: navcam::Pair, frame: &mut SensorFrame) {
        let seed: u64 = self.image_rng.random();
        let images = self.pictures_alongside(pair, seed);
        let taken = images.len() as u32;
        frame.images.extend(images);
        let dt = self.model.navcam.capture_time_s.max(0.0);
        self.time += dt;
        self.proprio.elapse(&self.model, dt);
        self.power.advance(self.time, 0.0, taken);
    }

    /// Moves the wheels: `centre` metres of signed centre-line wheel travel and `rotation`
    /// radians of signed differential rotation, spread evenly over `duration` seconds.
    fn move_wheels(
        &mut self,
        centre: f64,
        rotation: f64,
        duration: f64,
        guard: DriveGuard,
        frame: &mut SensorFrame,
    ) {
        if !duration.is_finite() || duration <= 0.0 {
            return;
        }
        if !self.on_terrain {
            frame.motion_stopped = Some("left the terrain model".into());
            return;
        }
        let forward = centre > 0.0;
        if guard.proximity && forward && self.proximity_guard_trips() {
            frame.motion_stopped = Some("guard: proximity sensor triggered".into());
            return;
        }
        let period = 1.0 / self.model.sample_rate.max(1e-3);
        let slip = self.model.slip.clone();
        let slip_offset = gaussian(&mut self.motion_rng, slip.per_command_sigma);
        let scrubbed_half_track = 0.5 * self.rover.track * (1.0 + slip.turn_scrub);
        let mut elapsed = 0.0;
        self.keep_in_window(self.pose.x, self.pose.y);
        let mut contact = match vehicle::settle(&self.terrain.dem, &self.geometry, self.pose) {
            Some(c) => c,
            None => {
                frame.motion_stopped = Some("left the terrain model".into());
                return;
            }
        };
        while elapsed < duration {
            let dt = period.min(duration - elapsed);
            let fraction = dt / duration;
            let (s_w, rot_w) = (centre * fraction, rotation * fraction);
            let mut wheels = [s_w - rot_w * scrubbed_half_track, s_w + rot_w * scrubbed_half_track];
            if let Some(left) = self.faults.stalled_left {
                wheels[if left { 0 } else { 1 }] = 0.0;
            }
            // Body motion from the wheel travel, reduced by slip.
            let grade = if s_w > 0.0 { -self.truth.pitch } else { self.truth.pitch };
            let ratio = if s_w != 0.0 { slip.slip_ratio(grade) } else { slip.slip_ratio(0.0) };
            let keep = 1.0 - (ratio + slip_offset).clamp(0.0, slip.max);
            let s_true = 0.5 * (wheels[0] + wheels[1]) * keep;
            let d_yaw = (wheels[1] - wheels[0]) / (2.0 * scrubbed_half_track) * keep;
            let advance = s_true * self.truth.pitch.cos();
            let creep = -slip.lateral_gain * self.truth.roll.sin() * s_true.abs();
            let mid = self.pose.yaw + 0.5 * d_yaw;
            let (sm, cm) = mid.sin_cos();
            let next = Pose2::new(
                self.pose.x + cm * advance - sm * creep,
                self.pose.y + sm * advance + cm * creep,
                wrap_angle(self.pose.yaw + d_yaw),
            );
            self.keep_in_window(next.x, next.y);
            let Some(next_contact) = vehicle::settle(&self.terrain.dem, &self.geometry, next) else {
                frame.motion_stopped = Some("left the terrain model".into());
                break;
            };
            let dem = &self.terrain.dem;
            // The wheels lead: a step at a wheel is reported before the body reaches it.
            let hazard = vehicle::motion_step_hazard(dem, &self.geometry, &contact, &next_contact)
                .or_else(|| vehicle::body_hazard(dem, &self.geometry, &next_contact));
            if let Some(h) = hazard {
                if !self.in_hazard {
                    // The body meets the hazard: it stops there, touching it.
                    self.hazard_contacts += 1;
                    frame.motion_stopped = Some(h.to_string());
                    break;
                }
            } else {
                self.in_hazard = false;
            }
            let (a, b) = (self.truth, next_contact.pose);
            self.distance += ((b.x - a.x).powi(2) + (b.y - a.y).powi(2) + (b.z - a.z).powi(2)).sqrt();
            self.pose = next;
            self.truth = next_contact.pose;
            contact = next_contact;
            self.wheel_travel[0] += wheels[0];
            self.wheel_travel[1] += wheels[1];
            self.time += dt;
            elapsed += dt;
            self.proprio.elapse(&self.model, dt);
            let motors = self.power.motors_w(wheels, dt, grade);
            self.power.advance(self.time, motors, 0);
            self.push_sample(frame, d_yaw / dt);
            if self.faults.stalled_left.is_some() && elapsed >= STALL_DETECT_TIME {
                let side = if self.faults.stalled_left == Some(true) { "left" } else { "right" };
                frame.motion_stopped = Some(format!("stall: {side} wheels not turning (motor current)"));
                break;
            }
            if let Some(limit) = guard.max_tilt
                && let Some(s) = frame.imu.last()
                && (s.incl_roll.cos() * s.incl_pitch.cos()).clamp(-1.0, 1.0).acos() > limit
            {
                frame.motion_stopped = Some("guard: inclinometer tilt beyond the limit".into());
                break;
            }
            if guard.proximity && forward && self.proximity_guard_trips() {
                frame.motion_stopped = Some("guard: proximity sensor triggered".into());
                break;
            }
        }
    }
}
