//! The messages the components exchange on the bus, and the topics that carry them.
//!
//! Message types are serde mirrors of the core types (the core crate stays dependency-free), with
//! exact conversions both ways, so a component that receives a message hands the autonomy the
//! very value the sender had. Frames and units follow ROS conventions (REP 103): world x east,
//! y north, z up; body x forward, y left, z up; metres, radians, seconds. A non-finite number
//! (a faulty compass reads NaN) travels as JSON `null` and comes back as NaN.

use crate::components::JausState;
use rovernav_bus::Topic;
use rovernav_core::{
    CameraImage, CameraKind, DriveGuard, Goal, ImuSample, NavCommand, OdometrySample, Outcome, Point2,
    PointCloud, Pose3, PoseEstimate, ProximityReading, SenseRequest, SensorFrame, Wedge,
};
use serde::{Deserialize, Serialize};

/// Every topic of the stack, by layer.
pub mod topics {
    use super::*;

    /// Platform -> everyone: what the sensors reported after one platform action.
    pub const PLATFORM_FRAME: Topic<FrameMsg> = Topic::new("/platform/frame");
    /// Camera server -> everyone: each camera image the platform took.
    pub const CAMERA_IMAGE: Topic<ImageMsg> = Topic::new("/camera/image");
    /// Motion controller -> platform: the one motion or sensing command to execute now.
    pub const PLATFORM_COMMAND: Topic<MotionRequest> = Topic::new("/platform/command");
    /// Deliberative layer or tooling arm -> platform: stand still, sampling, until a time.
    pub const PLATFORM_HOLD: Topic<HoldMsg> = Topic::new("/platform/hold");
    /// Navigator -> motion controller: the navigator's next command.
    pub const NAVIGATION_COMMAND: Topic<MotionRequest> = Topic::new("/navigation/command");
    /// Navigator -> displays and logs: the current plan (world frame).
    pub const NAVIGATION_PLAN: Topic<PlanMsg> = Topic::new("/navigation/plan");
    /// Deliberative layer -> motion controller: operator and task motion or sensing commands.
    pub const EXECUTIVE_MOTION: Topic<MotionRequest> = Topic::new("/executive/motion");
    /// Deliberative layer -> navigator: drive to a goal (one leg of the mission plan).
    pub const EXECUTIVE_DRIVE_TO: Topic<DriveToMsg> = Topic::new("/executive/drive_to");
    /// Deliberative layer -> reflexive layer: stop working on a task.
    pub const EXECUTIVE_CANCEL: Topic<CancelMsg> = Topic::new("/executive/cancel");
    /// Deliberative layer -> tooling arm: place an instrument or scoop.
    pub const ARM_COMMAND: Topic<ArmTaskMsg> = Topic::new("/arm/command");
    /// Reflexive layer -> deliberative layer: the state of each command it works on.
    pub const TASK_STATUS: Topic<TaskStatusMsg> = Topic::new("/executive/task_status");
    /// Pose estimator -> everyone: the pose estimate after each frame.
    pub const LOCALIZATION_ESTIMATE: Topic<EstimateMsg> = Topic::new("/localization/estimate");
    /// Deliberative layer -> pose estimator: an authoritative external position (operator fix).
    pub const LOCALIZATION_RESET: Topic<PoseMsg> = Topic::new("/localization/reset");
    /// Anyone -> runtime: JAUS state commands (emergency stop, standby, resume...).
    pub const SYSTEM_CONTROL: Topic<ControlMsg> = Topic::new("/system/control");
    /// Runtime -> everyone: a component's state after every change.
    pub const SYSTEM_STATUS: Topic<ComponentStatusMsg> = Topic::new("/system/status");
    /// Operator -> deliberative layer: one command-language line.
    pub const OPERATOR_COMMAND: Topic<String> = Topic::new("/operator/command");
    /// Deliberative layer -> operator: the answer to a command line.
    pub const OPERATOR_REPLY: Topic<String> = Topic::new("/operator/reply");
}

/// Serializes non-finite floats as `null` and reads `null` back as NaN (JSON has no NaN).
mod nan_as_null {
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
        if v.is_finite() { s.serialize_f64(*v) } else { s.serialize_none() }
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
    }
}

/// [`nan_as_null`] for a 3x3 matrix.
mod nan_as_null_matrix {
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    pub fn serialize<S: Serializer>(m: &[[f64; 3]; 3], s: S) -> Result<S::Ok, S::Error> {
        let rows = m.map(|row| row.map(|v| v.is_finite().then_some(v)));
        rows.serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<[[f64; 3]; 3], D::Error> {
        let rows = <[[Option<f64>; 3]; 3]>::deserialize(d)?;
        Ok(rows.map(|row| row.map(|v| v.unwrap_or(f64::NAN))))
    }
}

/// A 3D pose (world frame; roll, pitch, yaw in rad).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PoseMsg {
    /// East (m).
    #[serde(with = "nan_as_null")]
    pub x: f64,
    /// North (m).
    #[serde(with = "nan_as_null")]
    pub y: f64,
    /// Up (m).
    #[serde(with = "nan_as_null")]
    pub z: f64,
    /// Roll (rad).
    #[serde(with = "nan_as_null")]
    pub roll: f64,
    /// Pitch (rad).
    #[serde(with = "nan_as_null")]
    pub pitch: f64,
    /// Yaw, counter-clockwise from east (rad).
    #[serde(with = "nan_as_null")]
    pub yaw: f64,
}

impl From<Pose3> for PoseMsg {
    fn from(p: Pose3) -> Self {
        Self { x: p.x, y: p.y, z: p.z, roll: p.roll, pitch: p.pitch, yaw: p.yaw }
    }
}

impl From<PoseMsg> for Pose3 {
    fn from(p: PoseMsg) -> Self {
        Pose3 { x: p.x, y: p.y, z: p.z, roll: p.roll, pitch: p.pitch, yaw: p.yaw }
    }
}

/// The pose estimator's belief after integrating a frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct EstimateMsg {
    /// Sequence number of the last frame integrated.
    pub frame_seq: u64,
    /// Time of that frame (s).
    pub t: f64,
    /// Estimated pose.
    pub pose: PoseMsg,
    /// Covariance of (x, y, yaw).
    #[serde(with = "nan_as_null_matrix")]
    pub covariance: [[f64; 3]; 3],
    /// The localiser's localisation target: the body-frame mast pan (rad) predicted to localise
    /// best from here (absent when the localiser does not match terrain).
    #[serde(default)]
    pub localization_target: Option<f64>,
}

impl EstimateMsg {
    /// The core estimate.
    pub fn estimate(&self) -> PoseEstimate {
        PoseEstimate { pose: self.pose.into(), covariance: self.covariance }
    }
}

/// Which sensor produced a cloud.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CameraMsg {
    /// Mast stereo pair.
    Mast,
    /// Forward body stereo pair.
    BodyFront,
    /// Rear body stereo pair.
    BodyRear,
    /// Nodding LIDAR.
    Lidar,
}

impl From<CameraKind> for CameraMsg {
    fn from(c: CameraKind) -> Self {
        match c {
            CameraKind::Mast => Self::Mast,
            CameraKind::BodyFront => Self::BodyFront,
            CameraKind::BodyRear => Self::BodyRear,
            CameraKind::Lidar => Self::Lidar,
        }
    }
}

impl From<CameraMsg> for CameraKind {
    fn from(c: CameraMsg) -> Self {
        match c {
            CameraMsg::Mast => Self::Mast,
            CameraMsg::BodyFront => Self::BodyFront,
            CameraMsg::BodyRear => Self::BodyRear,
            CameraMsg::Lidar => Self::Lidar,
        }
    }
}

/// The region a range image covers (body frame).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct WedgeMsg {
    /// Bearing of the wedge centre (rad, counter-clockwise from forward).
    pub bearing: f64,
    /// Half the field of view (rad).
    pub half_angle: f64,
    /// Nearest range (m).
    pub min_range: f64,
    /// Far range (m).
    pub max_range: f64,
}

/// One range image: points in the body frame at capture (x forward, y left, z up; m).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CloudMsg {
    /// Sensor.
    pub camera: CameraMsg,
    /// Sensor origin in the body frame (m).
    pub origin: [f64; 3],
    /// Covered region.
    pub wedge: WedgeMsg,
    /// Points.
    pub points: Vec<[f32; 3]>,
}

impl From<&PointCloud> for CloudMsg {
    fn from(c: &PointCloud) -> Self {
        let w = c.wedge;
        Self {
            camera: c.camera.into(),
            origin: c.origin,
            wedge: WedgeMsg {
                bearing: w.bearing,
                half_angle: w.half_angle,
                min_range: w.min_range,
                max_range: w.max_range,
            },
            points: c.points.clone(),
        }
    }
}

impl From<&CloudMsg> for PointCloud {
    fn from(c: &CloudMsg) -> Self {
        let w = c.wedge;
        Self {
            camera: c.camera.into(),
            origin: c.origin,
            wedge: Wedge {
                bearing: w.bearing,
                half_angle: w.half_angle,
                min_range: w.min_range,
                max_range: w.max_range,
            },
            points: c.points.clone(),
        }
    }
}

/// One inertial sample (gyro, inclinometer, compass, sun sensor).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ImuMsg {
    /// Time (s).
    pub t: f64,
    /// Yaw rate (rad/s).
    #[serde(with = "nan_as_null")]
    pub gyro_z: f64,
    /// Inclinometer roll (rad).
    #[serde(with = "nan_as_null")]
    pub incl_roll: f64,
    /// Inclinometer pitch (rad).
    #[serde(with = "nan_as_null")]
    pub incl_pitch: f64,
    /// Compass heading (rad, counter-clockwise from east); NaN from a faulty compass.
    #[serde(with = "nan_as_null")]
    pub compass_yaw: f64,
    /// Sun-sensor heading (rad) when the sun is visible.
    pub sun_yaw: Option<f64>,
}

impl From<&ImuSample> for ImuMsg {
    fn from(s: &ImuSample) -> Self {
        Self {
            t: s.t,
            gyro_z: s.gyro_z,
            incl_roll: s.incl_roll,
            incl_pitch: s.incl_pitch,
            compass_yaw: s.compass_yaw,
            sun_yaw: s.sun_yaw,
        }
    }
}

impl From<&ImuMsg> for ImuSample {
    fn from(s: &ImuMsg) -> Self {
        Self {
            t: s.t,
            gyro_z: s.gyro_z,
            incl_roll: s.incl_roll,
            incl_pitch: s.incl_pitch,
            compass_yaw: s.compass_yaw,
            sun_yaw: s.sun_yaw,
        }
    }
}

/// Cumulative wheel encoder counts.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct OdometryMsg {
    /// Time (s).
    pub t: f64,
    /// Left side counts.
    pub left_counts: i64,
    /// Right side counts.
    pub right_counts: i64,
}

/// A range request.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SenseMsg {
    /// Mast stereo at a body-frame pan (rad).
    Mast {
        /// Pan (rad).
        pan: f64,
    },
    /// Full-resolution mast stereo at a body-frame pan (rad).
    MastFine {
        /// Pan (rad).
        pan: f64,
    },
    /// Forward body stereo.
    BodyFront,
    /// Rear body stereo.
    BodyRear,
    /// LIDAR sweep at a pan (rad).
    Lidar {
        /// Pan (rad).
        pan: f64,
    },
    /// Both Navcam images at a pan and tilt (rad).
    Navcam {
        /// Pan (rad).
        pan: f64,
        /// Tilt (rad, positive up).
        tilt: f64,
    },
}

/// A command for the platform, the wire form of [`NavCommand`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CommandMsg {
    /// Acquire range images.
    Sense {
        /// Requested images.
        requests: Vec<SenseMsg>,
    },
    /// Drive an arc.
    Drive {
        /// Signed arc length (m).
        distance: f64,
        /// Curvature (1/m, positive left).
        curvature: f64,
        /// Stop when a proximity sensor triggers.
        proximity_guard: bool,
        /// Stop beyond this tilt (rad).
        max_tilt: Option<f64>,
    },
    /// Turn in place (rad, positive counter-clockwise).
    Turn {
        /// Signed angle (rad).
        angle: f64,
    },
    /// The navigator is done (never sent to the platform).
    Finish {
        /// `report.json` outcome name.
        outcome: String,
        /// Why.
        message: String,
    },
}

impl From<&NavCommand> for CommandMsg {
    fn from(c: &NavCommand) -> Self {
        match c {
            NavCommand::Sense(requests) => Self::Sense {
                requests: requests
                    .iter()
                    .map(|r| match *r {
                        SenseRequest::Mast { pan } => SenseMsg::Mast { pan },
                        SenseRequest::MastFine { pan } => SenseMsg::MastFine { pan },
                        SenseRequest::BodyFront => SenseMsg::BodyFront,
                        SenseRequest::BodyRear => SenseMsg::BodyRear,
                        SenseRequest::Lidar { pan } => SenseMsg::Lidar { pan },
                        SenseRequest::Navcam { pan, tilt } => SenseMsg::Navcam { pan, tilt },
                    })
                    .collect(),
            },
            NavCommand::Drive { distance, curvature, guard } => Self::Drive {
                distance: *distance,
                curvature: *curvature,
                proximity_guard: guard.proximity,
                max_tilt: guard.max_tilt,
            },
            NavCommand::Turn { angle } => Self::Turn { angle: *angle },
            NavCommand::Finish(outcome, message) => {
                Self::Finish { outcome: outcome.as_str().to_string(), message: message.clone() }
            }
        }
    }
}

impl CommandMsg {
    /// The core command (an unknown outcome name reads as `aborted`).
    pub fn command(&self) -> NavCommand {
        match self {
            Self::Sense { requests } => NavCommand::Sense(
                requests
                    .iter()
                    .map(|r| match *r {
                        SenseMsg::Mast { pan } => SenseRequest::Mast { pan },
                        SenseMsg::MastFine { pan } => SenseRequest::MastFine { pan },
                        SenseMsg::BodyFront => SenseRequest::BodyFront,
                        SenseMsg::BodyRear => SenseRequest::BodyRear,
                        SenseMsg::Lidar { pan } => SenseRequest::Lidar { pan },
                        SenseMsg::Navcam { pan, tilt } => SenseRequest::Navcam { pan, tilt },
                    })
                    .collect(),
            ),
            Self::Drive { distance, curvature, proximity_guard, max_tilt } => NavCommand::Drive {
                distance: *distance,
                curvature: *curvature,
                guard: DriveGuard { proximity: *proximity_guard, max_tilt: *max_tilt },
            },
            Self::Turn { angle } => NavCommand::Turn { angle: *angle },
            Self::Finish { outcome, message } => {
                NavCommand::Finish(Outcome::parse(outcome).unwrap_or(Outcome::Aborted), message.clone())
            }
        }
    }
}

/// Who asked for a platform command.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Origin {
    /// The navigator, driving a mission leg.
    Navigator,
    /// The operator (`drive`, `turn`).
    Operator,
    /// A mission task (panorama, science image), by task id.
    Task(u64),
}

/// A platform command with its id and requester.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MotionRequest {
    /// Unique per requester and run.
    pub id: u64,
    /// Requester.
    pub origin: Origin,
    /// The command.
    pub command: CommandMsg,
}

/// Stand still and keep sampling until a time.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct HoldMsg {
    /// Simulated time to hold until (s).
    pub until_s: f64,
}

/// What produced a frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FrameSource {
    /// Samples at rest before the first command.
    Initial,
    /// Samples while holding still.
    Hold,
    /// The result of an executed command.
    Command(MotionRequest),
}

/// What the platform's sensors reported after one action.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrameMsg {
    /// Frame number (0 for the initial frame).
    pub seq: u64,
    /// What produced it.
    pub source: FrameSource,
    /// Time at the end of the action (s).
    pub t: f64,
    /// Range images.
    pub clouds: Vec<CloudMsg>,
    /// Inertial samples in time order.
    pub imu: Vec<ImuMsg>,
    /// Encoder samples in time order.
    pub odometry: Vec<OdometryMsg>,
    /// The ten proximity sensors at the end, leftmost first.
    pub proximity: [bool; 10],
    /// Why a motion stopped early, if it did.
    pub motion_stopped: Option<String>,
    /// Camera images taken during the action.
    #[serde(default)]
    pub images: Vec<ImageMsg>,
}

/// One grey camera image.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ImageMsg {
    /// The camera's name.
    pub camera: String,
    /// Time of exposure (s).
    pub t: f64,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Bits per pixel used.
    pub bits: u8,
    /// Pixel values, row-major (base64 of little-endian u16 on the wire).
    #[serde(with = "pixels_base64")]
    pub pixels: Vec<u16>,
    /// Mast pan when taken (rad).
    #[serde(default)]
    pub pan: f64,
    /// Mast tilt when taken (rad).
    #[serde(default)]
    pub tilt: f64,
}

/// Pixels as base64 of their little-endian bytes: a third larger than the bytes, where a JSON
/// number array is about three times larger.
mod pixels_base64 {
    use base64::Engine as _;
    use base64::engine::general_purpose::STANDARD;
    use serde::{Deserialize, Deserializer, Serializer, de::Error as _};

    pub fn serialize<S: Serializer>(pixels: &[u16], s: S) -> Result<S::Ok, S::Error> {
        let bytes: Vec<u8> = pixels.iter().flat_map(|v| v.to_le_bytes()).collect();
        s.serialize_str(&STANDARD.encode(bytes))
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<u16>, D::Error> {
        let text = String::deserialize(d)?;
        let bytes = STANDARD.decode(text.as_bytes()).map_err(D::Error::custom)?;
        if bytes.len() % 2 != 0 {
            return Err(D::Error::custom("pixels: an odd number of bytes for 16-bit pixels"));
        }
        Ok(bytes.chunks_exact(2).map(|b| u16::from_le_bytes([b[0], b[1]])).collect())
    }
}

impl From<&CameraImage> for ImageMsg {
    fn from(i: &CameraImage) -> Self {
        Self {
            camera: i.camera.clone(),
            t: i.t,
            width: i.width,
            height: i.height,
            bits: i.bits,
            pixels: i.pixels.clone(),
            pan: i.pan,
            tilt: i.tilt,
        }
    }
}

impl From<&ImageMsg> for CameraImage {
    fn from(i: &ImageMsg) -> Self {
        Self {
            camera: i.camera.clone(),
            t: i.t,
            width: i.width,
            height: i.height,
            bits: i.bits,
            pixels: i.pixels.clone(),
            pan: i.pan,
            tilt: i.tilt,
        }
    }
}

impl FrameMsg {
    /// Wraps a core frame.
    pub fn new(seq: u64, source: FrameSource, f: &SensorFrame) -> Self {
        Self {
            seq,
            source,
            t: f.t,
            clouds: f.clouds.iter().map(CloudMsg::from).collect(),
            imu: f.imu.iter().map(ImuMsg::from).collect(),
            odometry: f
                .odometry
                .iter()
                .map(|o| OdometryMsg { t: o.t, left_counts: o.left_counts, right_counts: o.right_counts })
                .collect(),
            proximity: f.proximity.raw,
            motion_stopped: f.motion_stopped.clone(),
            images: f.images.iter().map(ImageMsg::from).collect(),
        }
    }

    /// The core frame.
    pub fn frame(&self) -> SensorFrame {
        SensorFrame {
            t: self.t,
            clouds: self.clouds.iter().map(PointCloud::from).collect(),
            imu: self.imu.iter().map(ImuSample::from).collect(),
            odometry: self
                .odometry
                .iter()
                .map(|o| OdometrySample { t: o.t, left_counts: o.left_counts, right_counts: o.right_counts })
                .collect(),
            proximity: ProximityReading { raw: self.proximity },
            motion_stopped: self.motion_stopped.clone(),
            images: self.images.iter().map(CameraImage::from).collect(),
        }
    }

    /// The executed command, when the frame is a command's result.
    pub fn request(&self) -> Option<&MotionRequest> {
        match &self.source {
            FrameSource::Command(r) => Some(r),
            _ => None,
        }
    }
}

/// A goal: position, arrival tolerance and keep-out zones (world frame).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GoalMsg {
    /// Position [x, y] (m).
    pub position: [f64; 2],
    /// Arrival tolerance (m).
    pub tolerance: f64,
    /// Waypoints the navigator itself visits first (the deliberative layer sends legs without).
    pub waypoints: Vec<[f64; 2]>,
    /// Keep-out polygons.
    pub keep_out: Vec<Vec<[f64; 2]>>,
}

impl From<&Goal> for GoalMsg {
    fn from(g: &Goal) -> Self {
        let xy = |p: &Point2| [p.x, p.y];
        Self {
            position: xy(&g.position),
            tolerance: g.tolerance,
            waypoints: g.waypoints.iter().map(xy).collect(),
            keep_out: g.keep_out.iter().map(|z| z.iter().map(xy).collect()).collect(),
        }
    }
}

impl GoalMsg {
    /// The core goal.
    pub fn goal(&self) -> Goal {
        let pt = |p: &[f64; 2]| Point2::new(p[0], p[1]);
        Goal {
            position: pt(&self.position),
            tolerance: self.tolerance,
            waypoints: self.waypoints.iter().map(pt).collect(),
            keep_out: self.keep_out.iter().map(|z| z.iter().map(pt).collect()).collect(),
        }
    }
}

/// Drive to a goal as task `task`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DriveToMsg {
    /// Task id.
    pub task: u64,
    /// Where.
    pub goal: GoalMsg,
}

/// Stop working on a task.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct CancelMsg {
    /// Task id.
    pub task: u64,
}

/// A tooling-arm operation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ArmAction {
    /// Place an instrument on the target.
    PlaceInstrument,
    /// Scoop a soil sample at the target.
    Scoop,
}

/// Ask the tooling arm to work on a target.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ArmTaskMsg {
    /// Task id.
    pub task: u64,
    /// Operation.
    pub action: ArmAction,
    /// Target [x, y] (world frame, m).
    pub target: [f64; 2],
}

/// The execution state of a command (paper 004 section 2).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TaskState {
    /// Not started yet.
    Pending,
    /// Being executed.
    InProcess,
    /// Done as asked.
    Success,
    /// Could not be done.
    Failure,
    /// Stopped by the reflexive layer itself (emergency stop, component fault).
    Aborted,
    /// Withdrawn by the deliberative layer or the operator.
    Cancelled,
}

impl TaskState {
    /// Whether the task is over.
    pub fn is_final(self) -> bool {
        !matches!(self, TaskState::Pending | TaskState::InProcess)
    }

    /// A stable lower-case name.
    pub fn as_str(self) -> &'static str {
        match self {
            TaskState::Pending => "pending",
            TaskState::InProcess => "in_process",
            TaskState::Success => "success",
            TaskState::Failure => "failure",
            TaskState::Aborted => "aborted",
            TaskState::Cancelled => "cancelled",
        }
    }
}

/// A task's state as the component working on it reports it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TaskStatusMsg {
    /// Task id.
    pub task: u64,
    /// Reporting component.
    pub component: String,
    /// State.
    pub state: TaskState,
    /// For a finished drive: the navigator's `report.json` outcome name.
    pub outcome: Option<String>,
    /// Why, in words.
    pub message: String,
}

/// A JAUS state command.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ControlAction {
    /// Standby -> Ready.
    Resume,
    /// Ready -> Standby.
    Standby,
    /// Any -> Emergency (except Failure and Shutdown).
    EmergencyStop,
    /// Emergency -> Standby.
    ClearEmergency,
    /// Failure -> Initialization (the component initializes again).
    Reset,
    /// Any -> Shutdown.
    Shutdown,
}

/// A JAUS state command for one component or all.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ControlMsg {
    /// Component name; `None` addresses every component.
    pub target: Option<String>,
    /// Command.
    pub action: ControlAction,
}

/// A component's state, published on every change.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ComponentStatusMsg {
    /// Component name.
    pub component: String,
    /// JAUS state.
    pub state: JausState,
    /// Why it changed (the fault, for Failure).
    pub message: String,
    /// Time of the change (s).
    pub time_s: f64,
}

/// The navigator's plan (world frame, [x, y] in m).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PlanMsg {
    /// Task the plan serves.
    pub task: u64,
    /// Points.
    pub points: Vec<[f64; 2]>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use rovernav_bus::{decode, encode};

    #[test]
    fn frames_cross_the_wire_unchanged_and_nan_survives() {
        let frame = SensorFrame {
            t: 12.3,
            clouds: vec![PointCloud {
                camera: CameraKind::BodyRear,
                origin: [0.1, -0.2, 0.35],
                wedge: Wedge { bearing: 3.1, half_angle: 0.7, min_range: 0.3, max_range: 1.5 },
                points: vec![[1.0 / 3.0, -2.0, 0.125]],
            }],
            imu: vec![ImuSample {
                t: 12.2,
                gyro_z: 1e-4,
                incl_roll: 0.01,
                incl_pitch: -0.02,
                compass_yaw: f64::NAN,
                sun_yaw: Some(0.5),
            }],
            odometry: vec![OdometrySample { t: 12.2, left_counts: -5, right_counts: 7 }],
            proximity: ProximityReading {
                raw: [false, true, false, false, false, false, false, false, false, true],
            },
            motion_stopped: Some("stall".into()),
            images: vec![CameraImage {
                camera: "navcam_left".into(),
                t: 12.0,
                width: 3,
                height: 2,
                bits: 12,
                pixels: vec![0, 1, 4095, 7, 8, 9],
                pan: 0.25,
                tilt: -0.5,
            }],
        };
        let request = MotionRequest {
            id: 4,
            origin: Origin::Task(2),
            command: CommandMsg::from(&NavCommand::Drive {
                distance: -0.3,
                curvature: 0.2,
                guard: DriveGuard { proximity: true, max_tilt: Some(0.4) },
            }),
        };
        let msg = FrameMsg::new(9, FrameSource::Command(request.clone()), &frame);
        let back = decode(&topics::PLATFORM_FRAME, &encode(&topics::PLATFORM_FRAME, &msg).unwrap()).unwrap();
        let f = back.frame();
        assert!(f.imu[0].compass_yaw.is_nan());
        let mut expected = frame.clone();
        expected.imu[0].compass_yaw = 0.0;
        let mut got = f.clone();
        got.imu[0].compass_yaw = 0.0;
        assert_eq!(got, expected);
        assert_eq!(back.request(), Some(&request));
        assert_eq!(
            request.command.command(),
            NavCommand::Drive {
                distance: -0.3,
                curvature: 0.2,
                guard: DriveGuard { proximity: true, max_tilt: Some(0.4) },
            }
        );
    }

    #[test]
    fn every_topic_name_is_valid() {
        use topics::*;
        for name in [
            PLATFORM_FRAME.name(),
            CAMERA_IMAGE.name(),
            PLATFORM_COMMAND.name(),
            PLATFORM_HOLD.name(),
            NAVIGATION_COMMAND.name(),
            NAVIGATION_PLAN.name(),
            EXECUTIVE_MOTION.name(),
            EXECUTIVE_DRIVE_TO.name(),
            EXECUTIVE_CANCEL.name(),
            ARM_COMMAND.name(),
            TASK_STATUS.name(),
            LOCALIZATION_ESTIMATE.name(),
            LOCALIZATION_RESET.name(),
            SYSTEM_CONTROL.name(),
            SYSTEM_STATUS.name(),
            OPERATOR_COMMAND.name(),
            OPERATOR_REPLY.name(),
        ] {
            assert!(rovernav_bus::check_topic_name(name).is_ok(), "{name}");
        }
    }
}
