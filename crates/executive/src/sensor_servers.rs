//! Sensor servers: one component per sensor family, each judging its sensor's health from the
//! data alone (never from simulator truth) and going to Failure when the data shows a fault.
//!
//! The platform delivers the samples of one command together in a frame (the stop-and-go cycle
//! keeps a command's range images and proprioceptive samples in one message), so the servers
//! read the frame rather than re-publish it; their state on `/system/status` is what fault
//! protection watches.

use crate::components::{Component, ComponentFault, Ctx, JausState, Port, Ports};
use crate::messages::{CameraMsg, CommandMsg, EstimateMsg, FrameMsg, topics};
use rovernav_bus::{Bus, BusError, Subscriber};
use rovernav_core::{angle_diff, wrap_angle};
use std::collections::BTreeMap;

/// Images in a row without a single range point after which a camera is declared silent.
pub const SILENT_IMAGES: u32 = 3;
/// Least spread of the directions of those images (rad): 60 deg.
pub const SILENT_SPREAD: f64 = std::f64::consts::FRAC_PI_3;

/// Wheel travel below which a side counts as not turning (m).
const STILL_M: f64 = 0.002;
/// Wheel travel of the other side, and commanded travel of this side, that make a still side a
/// stuck wheel (m): 2 cm is 40 encoder counts, far above quantisation.
const MOVED_M: f64 = 0.02;

fn camera_name(c: CameraMsg) -> &'static str {
    match c {
        CameraMsg::Mast => "mast stereo",
        CameraMsg::BodyFront => "front body stereo",
        CameraMsg::BodyRear => "rear body stereo",
        CameraMsg::Lidar => "lidar",
    }
}

/// Reads frames, in every live state (a server must keep its counts even while standing by).
fn frames(
    ctx: &mut Ctx<'_>,
    sub: &Option<Subscriber<FrameMsg>>,
) -> Result<Vec<std::sync::Arc<FrameMsg>>, ComponentFault> {
    Ok(match sub {
        Some(s) => ctx.bus.take(s)?,
        None => Vec::new(),
    })
}

/// Range sensors (stereo pairs, LIDAR): a camera that returns no point in
/// [`SILENT_IMAGES`] consecutive images, pointed in directions at least [`SILENT_SPREAD`] apart,
/// is silent. One direction is not enough: a camera staring past the edge of the world (or into
/// the sky) sees nothing either.
#[derive(Default)]
pub struct RangeSensors {
    frames: Option<Subscriber<FrameMsg>>,
    estimates: Option<Subscriber<EstimateMsg>>,
    yaw: f64,
    /// World bearings of each camera's latest run of empty images.
    empty_in_a_row: BTreeMap<&'static str, Vec<f64>>,
}

impl RangeSensors {
    /// A server with clean counts.
    pub fn new() -> Self {
        Self::default()
    }

    fn check(&mut self, ctx: &mut Ctx<'_>) -> Result<(), ComponentFault> {
        // The pose before the frame's command: sensing does not move the rover.
        if let Some(s) = &self.estimates
            && let Some(e) = ctx.bus.latest(s)?
        {
            self.yaw = e.pose.yaw;
        }
        for f in frames(ctx, &self.frames)? {
            for cloud in &f.clouds {
                let name = camera_name(cloud.camera);
                let bad = cloud.points.iter().filter(|p| !p.iter().all(|v| v.is_finite())).count();
                if bad > 0 {
                    return Err(ComponentFault(format!(
                        "sensor fault: {name} returned {bad} non-finite range points of {}",
                        cloud.points.len()
                    )));
                }
                let run = self.empty_in_a_row.entry(name).or_default();
                if !cloud.points.is_empty() {
                    run.clear();
                    continue;
                }
                run.push(wrap_angle(self.yaw + cloud.wedge.bearing));
                let spread = run
                    .iter()
                    .flat_map(|a| run.iter().map(move |b| angle_diff(*a, *b).abs()))
                    .fold(0.0, f64::max);
                if run.len() >= SILENT_IMAGES as usize && spread >= SILENT_SPREAD {
                    return Err(ComponentFault(format!(
                        "sensor silent: {name} returned no range points in {} consecutive images across {:.0} deg",
                        run.len(),
                        spread.to_degrees()
                    )));
                }
            }
        }
        Ok(())
    }
}

impl Component for RangeSensors {
    fn name(&self) -> &'static str {
        "range-sensors"
    }
    fn ports(&self) -> Ports {
        Ports {
            inputs: vec![Port::of(topics::PLATFORM_FRAME), Port::of(topics::LOCALIZATION_ESTIMATE)],
            outputs: vec![],
        }
    }
    fn connect(&mut self, bus: &mut Bus) -> Result<(), BusError> {
        self.frames = Some(bus.subscribe(topics::PLATFORM_FRAME)?);
        self.estimates = Some(bus.subscribe(topics::LOCALIZATION_ESTIMATE)?);
        Ok(())
    }
    fn step(&mut self, ctx: &mut Ctx<'_>) -> Result<(), ComponentFault> {
        self.check(ctx)
    }
    fn idle(&mut self, ctx: &mut Ctx<'_>, _state: JausState) -> Result<(), ComponentFault> {
        self.check(ctx)
    }
}

/// Largest gyro rate the rover may read while its wheels are still (rad/s): 0.05 deg/s, that
/// is 180 deg/h, 18 times the gyro's bias stability (10 deg/h, 1 sigma) plus six times a sample's
/// noise (4 deg/h/sqrt(Hz) at 10 Hz: 13 deg/h). Planetary rovers hold still between commands
/// (stop and go), so every command ends with samples at rest.
pub const GYRO_REST_LIMIT: f64 = 0.05 * std::f64::consts::PI / 180.0;
/// Consecutive at-rest samples beyond [`GYRO_REST_LIMIT`] that make a gyro fault: one outlier
/// is not enough.
pub const GYRO_REST_SAMPLES: u32 = 2;

/// Inertial sensors (gyro, inclinometer, compass): a non-finite reading is a fault, and so is
/// a gyro that reads a turn while the wheels stand still (a bias jump).
#[derive(Default)]
pub struct InertialSensors {
    frames: Option<Subscriber<FrameMsg>>,
    /// The last wheel counts seen, to tell samples at rest.
    counts: Option<(i64, i64)>,
    /// At-rest samples in a row beyond the limit.
    turning_at_rest: u32,
}

impl InertialSensors {
    /// A server.
    pub fn new() -> Self {
        Self::default()
    }

    fn check(&mut self, ctx: &mut Ctx<'_>) -> Result<(), ComponentFault> {
        for f in frames(ctx, &self.frames)? {
            self.check_rest(&f)?;
            for s in &f.imu {
                for (name, value) in [
                    ("compass", s.compass_yaw),
                    ("gyro", s.gyro_z),
                    ("inclinometer", s.incl_roll + s.incl_pitch),
                ] {
                    if !value.is_finite() {
                        return Err(ComponentFault(format!(
                            "sensor fault: {name} reads {value} at t = {:.1} s",
                            s.t
                        )));
                    }
                }
            }
        }
        Ok(())
    }
}

impl InertialSensors {
    /// The gyro at rest: a sample whose wheel counts equal the previous sample's (the rover
    /// has not moved during it) must read about zero.
    fn check_rest(&mut self, f: &FrameMsg) -> Result<(), ComponentFault> {
        for (odo, imu) in f.odometry.iter().zip(&f.imu) {
            let counts = (odo.left_counts, odo.right_counts);
            let still = self.counts == Some(counts);
            self.counts = Some(counts);
            if !still || !imu.gyro_z.is_finite() {
                continue;
            }
            if imu.gyro_z.abs() > GYRO_REST_LIMIT {
                self.turning_at_rest += 1;
                if self.turning_at_rest >= GYRO_REST_SAMPLES {
                    return Err(ComponentFault(format!(
                        "sensor fault: gyro reads {:.3} deg/s with the wheels still at t = {:.1} s (limit {:.2})",
                        imu.gyro_z.to_degrees(),
                        imu.t,
                        GYRO_REST_LIMIT.to_degrees()
                    )));
                }
            } else {
                self.turning_at_rest = 0;
            }
        }
        Ok(())
    }
}

impl Component for InertialSensors {
    fn name(&self) -> &'static str {
        "inertial-sensors"
    }
    fn ports(&self) -> Ports {
        Ports { inputs: vec![Port::of(topics::PLATFORM_FRAME)], outputs: vec![] }
    }
    fn connect(&mut self, bus: &mut Bus) -> Result<(), BusError> {
        self.frames = Some(bus.subscribe(topics::PLATFORM_FRAME)?);
        Ok(())
    }
    fn step(&mut self, ctx: &mut Ctx<'_>) -> Result<(), ComponentFault> {
        self.check(ctx)
    }
    fn idle(&mut self, ctx: &mut Ctx<'_>, _state: JausState) -> Result<(), ComponentFault> {
        self.check(ctx)
    }
}

/// Wheel odometry (encoders and motor-current monitors): a side whose encoders do not move
/// while the other side's do, under a command that turns both, is a stuck wheel; so is a stall
/// the motor-current monitor reports.
pub struct WheelOdometry {
    frames: Option<Subscriber<FrameMsg>>,
    counts_per_m: f64,
    half_track: f64,
    counts: Option<(i64, i64)>,
}

impl WheelOdometry {
    /// A server for wheels with the given encoder resolution and track.
    pub fn new(encoder_counts_per_cm: f64, track_m: f64) -> Self {
        Self {
            frames: None,
            counts_per_m: 100.0 * encoder_counts_per_cm,
            half_track: 0.5 * track_m,
            counts: None,
        }
    }

    /// Wheel travel (left, right) a command asks for (m).
    fn commanded(&self, command: &CommandMsg) -> Option<(f64, f64)> {
        match *command {
            CommandMsg::Drive { distance, curvature, .. } => {
                let turn = curvature * distance * self.half_track;
                Some((distance - turn, distance + turn))
            }
            CommandMsg::Turn { angle } => Some((-angle * self.half_track, angle * self.half_track)),
            _ => None,
        }
    }

    fn check(&mut self, ctx: &mut Ctx<'_>) -> Result<(), ComponentFault> {
        for f in frames(ctx, &self.frames)? {
            let before = self.counts;
            if let Some(o) = f.odometry.last() {
                self.counts = Some((o.left_counts, o.right_counts));
            }
            let Some(request) = f.request() else { continue };
            let Some((want_l, want_r)) = self.commanded(&request.command) else { continue };
            if let Some(why) = f.motion_stopped.as_deref().filter(|w| w.starts_with("stall")) {
                return Err(ComponentFault(format!("stuck wheel: motor current monitor reports `{why}`")));
            }
            let (Some((l0, r0)), Some((l1, r1))) = (before, self.counts) else { continue };
            let moved = |a: i64, b: i64| (b - a) as f64 / self.counts_per_m;
            let (dl, dr) = (moved(l0, l1), moved(r0, r1));
            for (side, d, want, other_side, other) in
                [("left", dl, want_l, "right", dr), ("right", dr, want_r, "left", dl)]
            {
                if d.abs() < STILL_M && want.abs() >= MOVED_M && other.abs() >= MOVED_M {
                    return Err(ComponentFault(format!(
                        "stuck wheel: {side} wheels turned {:.3} m of {:.3} m commanded while the {other_side} wheels turned {:.3} m",
                        d.abs(),
                        want.abs(),
                        other.abs()
                    )));
                }
            }
        }
        Ok(())
    }
}

impl Component for WheelOdometry {
    fn name(&self) -> &'static str {
        "wheel-odometry"
    }
    fn ports(&self) -> Ports {
        Ports { inputs: vec![Port::of(topics::PLATFORM_FRAME)], outputs: vec![] }
    }
    fn connect(&mut self, bus: &mut Bus) -> Result<(), BusError> {
        self.frames = Some(bus.subscribe(topics::PLATFORM_FRAME)?);
        Ok(())
    }
    fn step(&mut self, ctx: &mut Ctx<'_>) -> Result<(), ComponentFault> {
        self.check(ctx)
    }
    fn idle(&mut self, ctx: &mut Ctx<'_>, _state: JausState) -> Result<(), ComponentFault> {
        self.check(ctx)
    }
}

/// Body contacts the platform may report in one run before fault protection stops the rover.
/// A navigator that meets the terrain backs away and looks again (the first contact) and may
/// try once more; a third contact means it keeps driving into what it cannot see.
pub const MAX_BODY_CONTACTS: u32 = 3;

/// The body-contact monitor (belly and tilt switches, the hazard sensors of paper 001): counts
/// motions the platform stopped because the body met the terrain, and fails when a navigator
/// keeps running into it, so that fault protection halts the rover instead of letting it ram
/// the same rock again and again.
pub struct ContactMonitor {
    frames: Option<Subscriber<FrameMsg>>,
    contacts: u32,
    limit: u32,
}

impl ContactMonitor {
    /// A monitor that fails at the `limit`-th body contact.
    pub fn new(limit: u32) -> Self {
        Self { frames: None, contacts: 0, limit: limit.max(1) }
    }

    fn check(&mut self, ctx: &mut Ctx<'_>) -> Result<(), ComponentFault> {
        for f in frames(ctx, &self.frames)? {
            let Some(why) = f.motion_stopped.as_deref().filter(|w| w.starts_with("hazard")) else { continue };
            self.contacts += 1;
            if self.contacts >= self.limit {
                return Err(ComponentFault(format!(
                    "body contact: the motion stopped on the terrain {} times (last: `{why}`)",
                    self.contacts
                )));
            }
        }
        Ok(())
    }
}

impl Component for ContactMonitor {
    fn name(&self) -> &'static str {
        "contact-monitor"
    }
    fn ports(&self) -> Ports {
        Ports { inputs: vec![Port::of(topics::PLATFORM_FRAME)], outputs: vec![] }
    }
    fn connect(&mut self, bus: &mut Bus) -> Result<(), BusError> {
        self.frames = Some(bus.subscribe(topics::PLATFORM_FRAME)?);
        Ok(())
    }
    fn step(&mut self, ctx: &mut Ctx<'_>) -> Result<(), ComponentFault> {
        self.check(ctx)
    }
    fn idle(&mut self, ctx: &mut Ctx<'_>, _state: JausState) -> Result<(), ComponentFault> {
        self.check(ctx)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::messages::{CloudMsg, FrameSource, ImuMsg, MotionRequest, OdometryMsg, Origin, WedgeMsg};
    use rovernav_core::{DriveGuard, SensorFrame};

    fn frame(seq: u64, command: Option<CommandMsg>) -> FrameMsg {
        FrameMsg {
            seq,
            source: match command {
                Some(command) => {
                    FrameSource::Command(MotionRequest { id: seq, origin: Origin::Navigator, command })
                }
                None => FrameSource::Hold,
            },
            frame: SensorFrame { t: seq as f64, ..Default::default() },
        }
    }

    /// A frame with its sensor data edited.
    fn edited(mut f: FrameMsg, edit: impl FnOnce(&mut SensorFrame)) -> FrameMsg {
        edit(&mut f.frame);
        f
    }

    fn cloud(camera: CameraMsg, points: usize) -> CloudMsg {
        aimed(camera, points, 0.0)
    }

    fn aimed(camera: CameraMsg, points: usize, bearing: f64) -> CloudMsg {
        let wedge = WedgeMsg { bearing, half_angle: 0.4, min_range: 1.0, max_range: 5.0 };
        CloudMsg { camera, origin: [0.0; 3], wedge, points: vec![[2.0, 0.0, 0.0]; points] }
    }

    /// Feeds frames to a server one at a time; returns the first fault.
    fn feed(server: &mut dyn Component, frames: Vec<FrameMsg>) -> Option<String> {
        let mut bus = Bus::in_process();
        server.connect(&mut bus).unwrap();
        for f in frames {
            bus.publish(topics::PLATFORM_FRAME, f).unwrap();
            if let Err(ComponentFault(why)) = server.step(&mut Ctx { bus: &mut bus, time_s: 0.0 }) {
                return Some(why);
            }
        }
        None
    }

    fn sense(seq: u64, clouds: Vec<CloudMsg>) -> FrameMsg {
        edited(frame(seq, Some(CommandMsg::Sense(vec![]))), |f| f.clouds = clouds)
    }

    #[test]
    fn the_contact_monitor_fails_at_the_limit_and_ignores_other_stops() {
        let stopped = |seq: u64, why: &str| {
            edited(frame(seq, Some(CommandMsg::Turn { angle: 0.1 })), |f| f.motion_stopped = Some(why.into()))
        };
        let two = vec![
            stopped(1, "hazard: belly contact, terrain 0.190 m above the wheel plane"),
            stopped(2, "proximity: middle"),
            stopped(3, "hazard: tilt 27.0 deg"),
        ];
        assert_eq!(feed(&mut ContactMonitor::new(3), two.clone()), None, "two contacts are allowed");
        let third = two.into_iter().chain([stopped(4, "hazard: belly contact")]).collect();
        let why = feed(&mut ContactMonitor::new(3), third).expect("the third contact fails");
        assert!(why.contains("3 times") && why.contains("belly contact"), "{why}");
    }

    #[test]
    fn a_camera_is_silent_after_three_empty_images_in_a_row_in_different_directions() {
        let fan = |points: [usize; 3]| {
            [-0.7, 0.0, 0.7]
                .iter()
                .zip(points)
                .map(|(b, n)| aimed(CameraMsg::Mast, n, *b))
                .collect::<Vec<_>>()
        };
        let interrupted = vec![sense(1, fan([0, 0, 40])), sense(2, fan([0, 0, 12]))];
        assert_eq!(feed(&mut RangeSensors::new(), interrupted), None, "data resets the count");
        let others = vec![
            sense(1, vec![cloud(CameraMsg::Lidar, 0), aimed(CameraMsg::Mast, 0, 1.0)]),
            sense(2, fan([5, 0, 0])),
        ];
        assert_eq!(feed(&mut RangeSensors::new(), others), None, "counts are per camera");
        // Staring past the edge of the world in one direction is not silence.
        let staring = (1..6).map(|k| sense(k, vec![cloud(CameraMsg::BodyFront, 0)])).collect();
        assert_eq!(feed(&mut RangeSensors::new(), staring), None);
        let why = feed(&mut RangeSensors::new(), vec![sense(1, fan([0, 0, 0]))]).expect("silent");
        assert!(
            why.contains("mast stereo") && why.contains("3 consecutive") && why.contains("80 deg"),
            "{why}"
        );
    }

    #[test]
    fn a_nan_compass_or_gyro_is_a_sensor_fault() {
        let imu = |compass: f64, gyro: f64| ImuMsg {
            t: 1.0,
            gyro_z: gyro,
            incl_roll: 0.0,
            incl_pitch: 0.0,
            compass_yaw: compass,
            sun_yaw: None,
        };
        let ok = edited(frame(1, None), |f| f.imu = vec![imu(0.3, 0.01)]);
        assert_eq!(feed(&mut InertialSensors::new(), vec![ok]), None);
        for (bad, name) in [(imu(f64::NAN, 0.0), "compass"), (imu(0.2, f64::INFINITY), "gyro")] {
            let why = feed(&mut InertialSensors::new(), vec![edited(frame(1, None), |f| f.imu = vec![bad])])
                .unwrap();
            assert!(why.contains(name), "{why}");
        }
    }

    /// A frame of a command with encoder counts at its end.
    fn moved(seq: u64, command: CommandMsg, left: i64, right: i64) -> FrameMsg {
        let odometry = vec![OdometryMsg { t: seq as f64, left_counts: left, right_counts: right }];
        edited(frame(seq, Some(command)), |f| f.odometry = odometry)
    }

    #[test]
    fn one_side_still_while_the_other_turns_is_a_stuck_wheel() {
        let drive = CommandMsg::Drive { distance: 1.0, curvature: 0.0, guard: DriveGuard::default() };
        let server = || WheelOdometry::new(20.0, 0.5);
        // 2000 counts per metre: both sides turning, then both stopping early (a hazard) are fine.
        let normal = vec![moved(1, drive.clone(), 2000, 2000), moved(2, drive.clone(), 2100, 2100)];
        assert_eq!(feed(&mut server(), normal), None);
        let stuck = vec![moved(1, drive.clone(), 2000, 2000), moved(2, drive.clone(), 2002, 2200)];
        let why = feed(&mut server(), stuck).expect("stuck");
        assert!(
            why.contains("left wheels turned 0.001 m") && why.contains("right wheels turned 0.100 m"),
            "{why}"
        );
        // A turn in place moves the sides in opposite directions; a stalled right side shows too.
        let turn = CommandMsg::Turn { angle: 1.0 };
        let stuck = vec![moved(1, turn.clone(), 0, 0), moved(2, turn, -250, 0)];
        assert!(feed(&mut server(), stuck).unwrap().contains("right wheels"));
        // The motor-current monitor's stall report is enough by itself.
        let report = edited(moved(1, drive, 0, 0), |f| {
            f.motion_stopped = Some("stall: left wheels not turning".into())
        });
        assert!(feed(&mut server(), vec![report]).unwrap().contains("motor current"));
    }
}
