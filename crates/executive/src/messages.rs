//! The messages the components exchange on the bus, and the topics that carry them.
//!
//! One message set: a message that carries a core type carries it as it is (the core types
//! derive `Serialize`, `Deserialize` and `JsonSchema`); the names below that are core types
//! (`PoseMsg` is `Pose3`, `CloudMsg` is `PointCloud`, ...) are aliases kept for the call sites.
//! The types defined here add only what the bus needs around them: sequence numbers,
//! requesters, task ids and component states. Frames and units follow ROS conventions
//! (REP 103): world x east, y north, z up; body x forward, y left, z up; metres, radians,
//! seconds. A non-finite number (a faulty compass reads NaN) travels as JSON `null` and comes
//! back as NaN ([`rovernav_core::wire`]).

use crate::components::JausState;
use rovernav_bus::Topic;
use rovernav_core::{
    CameraImage, CameraKind, Goal, ImuSample, NavCommand, OdometrySample, PointCloud, Pose3, PoseEstimate,
    SenseRequest, SensorFrame, Wedge,
};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// A 3D pose (world frame; roll, pitch, yaw in rad).
pub type PoseMsg = Pose3;
/// Which sensor produced a cloud.
pub type CameraMsg = CameraKind;
/// The region a range image covers (body frame).
pub type WedgeMsg = Wedge;
/// One range image: points in the body frame at capture.
pub type CloudMsg = PointCloud;
/// One inertial sample (gyro, inclinometer, compass, sun sensor).
pub type ImuMsg = ImuSample;
/// Cumulative wheel encoder counts.
pub type OdometryMsg = OdometrySample;
/// A range request.
pub type SenseMsg = SenseRequest;
/// A command for the platform, or a navigator's next command.
pub type CommandMsg = NavCommand;
/// One grey camera image.
pub type ImageMsg = CameraImage;
/// A goal: position, arrival tolerance, waypoints and keep-out zones (world frame).
pub type GoalMsg = Goal;

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
    /// Navigator -> displays and logs: what the shadow navigator (`shadow_navigator`) would have
    /// done at each step, never obeyed.
    pub const NAVIGATION_SHADOW: Topic<crate::shadow::ShadowMsg> = Topic::new("/navigation/shadow");
    /// Deliberative layer -> motion controller: operator and task motion or sensing commands.
    pub const EXECUTIVE_MOTION: Topic<MotionRequest> = Topic::new("/executive/motion");
    /// Deliberative layer -> navigator: drive to a goal (one leg of the mission plan).
    pub const EXECUTIVE_DRIVE_TO: Topic<DriveToMsg> = Topic::new("/executive/drive_to");
    /// Deliberative layer -> reflexive layer: stop working on a task.
    pub const EXECUTIVE_CANCEL: Topic<CancelMsg> = Topic::new("/executive/cancel");
    /// Deliberative layer -> tooling arm: place an instrument or scoop.
    pub const ARM_COMMAND: Topic<ArmTaskMsg> = Topic::new("/arm/command");
    /// Tooling arm -> displays and logs: one instrument placement (AutoPlace): the chosen target
    /// or the refusal, the arm's joint states over time, the terrain octree.
    pub const ARM_PLACEMENT: Topic<crate::arm_server::PlacementMsg> = Topic::new("/arm/placement");
    /// Deliberative layer -> displays and logs: a science watch's compact summary when it ends
    /// (events by kind, times, positions in the images, what was sent, bytes against budget).
    pub const SCIENCE_SUMMARY: Topic<crate::deliberative::WatchSummary> = Topic::new("/science/summary");
    /// Deliberative layer -> platform: a Navcam pair to take alongside each of the navigator's
    /// sensing commands (visual target tracking's track-only mode), or none.
    pub const PLATFORM_RIDE_ALONG: Topic<RideAlongMsg> = Topic::new("/platform/ride_along");
    /// Deliberative layer -> displays and logs: each image visual target tracking saw, with the
    /// template, the match and its score, and the target's estimate.
    pub const VTT_TRACK: Topic<crate::deliberative::VttTrackMsg> = Topic::new("/vtt/track");
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

    /// Every topic above with its message type's derived JSON Schema (a recorder's channel
    /// schema for the messages it taps off the bus).
    pub fn all() -> Vec<(&'static str, serde_json::Value)> {
        fn row<T: JsonSchema>(t: Topic<T>) -> (&'static str, serde_json::Value) {
            (t.name(), t.schema())
        }
        vec![
            row(PLATFORM_FRAME),
            row(CAMERA_IMAGE),
            row(PLATFORM_COMMAND),
            row(PLATFORM_HOLD),
            row(NAVIGATION_COMMAND),
            row(NAVIGATION_PLAN),
            row(NAVIGATION_SHADOW),
            row(EXECUTIVE_MOTION),
            row(EXECUTIVE_DRIVE_TO),
            row(EXECUTIVE_CANCEL),
            row(ARM_COMMAND),
            row(ARM_PLACEMENT),
            row(SCIENCE_SUMMARY),
            row(PLATFORM_RIDE_ALONG),
            row(VTT_TRACK),
            row(TASK_STATUS),
            row(LOCALIZATION_ESTIMATE),
            row(LOCALIZATION_RESET),
            row(SYSTEM_CONTROL),
            row(SYSTEM_STATUS),
            row(OPERATOR_COMMAND),
            row(OPERATOR_REPLY),
        ]
    }
}

/// The pose estimator's belief after integrating a frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct EstimateMsg {
    /// Sequence number of the last frame integrated.
    pub frame_seq: u64,
    /// Time of that frame (s).
    pub t: f64,
    /// Estimated pose.
    pub pose: Pose3,
    /// Covariance of (x, y, yaw); a non-finite entry travels as `null`.
    #[serde(deserialize_with = "rovernav_core::wire::nan_from_null_matrix")]
    #[schemars(with = "[[Option<f64>; 3]; 3]")]
    pub covariance: [[f64; 3]; 3],
    /// The localiser's localisation target: the body-frame mast pan (rad) predicted to localise
    /// best from here (absent when the localiser does not match terrain).
    #[serde(default)]
    pub localization_target: Option<f64>,
}

impl EstimateMsg {
    /// The core estimate.
    pub fn estimate(&self) -> PoseEstimate {
        PoseEstimate { pose: self.pose, covariance: self.covariance }
    }
}

/// Who asked for a platform command.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Origin {
    /// The navigator, driving a mission leg.
    Navigator,
    /// The operator (`drive`, `turn`).
    Operator,
    /// A mission task (panorama, science image), by task id.
    Task(u64),
    /// The tooling arm imaging its work volume for a task (AutoPlace), by task id: the task's
    /// state is the arm's to report, not the platform's.
    Arm(u64),
}

/// A platform command with its id and requester.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct MotionRequest {
    /// Unique per requester and run.
    pub id: u64,
    /// Requester.
    pub origin: Origin,
    /// The command.
    pub command: CommandMsg,
}

/// Stand still and keep sampling until a time.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct HoldMsg {
    /// Simulated time to hold until (s).
    pub until_s: f64,
    /// Hold in the power system's sleep mode (no sampling until the end; SR2's SLEEP mode).
    #[serde(default)]
    pub sleep: bool,
}

/// Pictures the platform takes alongside the navigator's own sensing commands, exposed while
/// that sensing holds the rover still: they cost the run no time and change nothing it does.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct RideAlongMsg {
    /// The Navcam head's body-frame pan and tilt (rad) for a pair with each of the navigator's
    /// sensing commands; none: take no pictures.
    pub navcam: Option<[f64; 2]>,
}

/// What produced a frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum FrameSource {
    /// Samples at rest before the first command.
    Initial,
    /// Samples while holding still.
    Hold,
    /// The result of an executed command.
    Command(MotionRequest),
}

/// What the platform's sensors reported after one action: a core frame with its number and
/// what produced it. It dereferences to the frame (`msg.clouds`, `msg.t`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct FrameMsg {
    /// Frame number (0 for the initial frame).
    pub seq: u64,
    /// What produced it.
    pub source: FrameSource,
    /// The sensor data.
    pub frame: SensorFrame,
}

impl std::ops::Deref for FrameMsg {
    type Target = SensorFrame;

    fn deref(&self) -> &SensorFrame {
        &self.frame
    }
}

impl FrameMsg {
    /// Wraps a core frame.
    pub fn new(seq: u64, source: FrameSource, f: &SensorFrame) -> Self {
        Self { seq, source, frame: f.clone() }
    }

    /// A copy of the core frame.
    pub fn frame(&self) -> SensorFrame {
        self.frame.clone()
    }

    /// The executed command, when the frame is a command's result.
    pub fn request(&self) -> Option<&MotionRequest> {
        match &self.source {
            FrameSource::Command(r) => Some(r),
            _ => None,
        }
    }
}

/// Drive to a goal as task `task`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct DriveToMsg {
    /// Task id.
    pub task: u64,
    /// Where.
    pub goal: GoalMsg,
}

/// Stop working on a task.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
pub struct CancelMsg {
    /// Task id.
    pub task: u64,
}

/// A tooling-arm operation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ArmAction {
    /// Place an instrument on the target.
    PlaceInstrument,
    /// Scoop a soil sample at the target.
    Scoop,
}

/// Ask the tooling arm to work on a target.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct ArmTaskMsg {
    /// Task id.
    pub task: u64,
    /// Operation.
    pub action: ArmAction,
    /// Target [x, y] (world frame, m).
    pub target: [f64; 2],
}

/// The execution state of a command (paper 004 section 2).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, JsonSchema)]
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
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
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
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
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
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
pub struct ControlMsg {
    /// Component name; `None` addresses every component.
    pub target: Option<String>,
    /// Command.
    pub action: ControlAction,
}

/// A component's state, published on every change.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
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
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct PlanMsg {
    /// Task the plan serves.
    pub task: u64,
    /// Points.
    pub points: Vec<[f64; 2]>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use rovernav_bus::schema::check;
    use rovernav_bus::{decode, encode};
    use rovernav_core::{DriveGuard, Outcome, Point2, ProximityReading};

    fn sample_frame() -> SensorFrame {
        SensorFrame {
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
            power: Some(rovernav_core::PowerReading { t: 12.3, state_of_charge: 0.5, ..Default::default() }),
            lander: Some(Box::new(rovernav_core::LanderSighting {
                camera: [1.0, -2.0, 1.8],
                point: [7.25, 0.5, 0.3],
                range_sigma_m: 0.04,
                angle_sigma_rad: 0.011,
            })),
        }
    }

    /// Crosses the wire as the zenoh transport carries it, checking the JSON against the
    /// topic's derived schema; NaN compares by its JSON form (`null`).
    fn through<T: rovernav_bus::Message + JsonSchema + std::fmt::Debug>(topic: Topic<T>, msg: &T) -> T {
        let bytes = encode(&topic, msg).unwrap();
        let value: serde_json::Value = serde_json::from_slice(&bytes).unwrap();
        check(&topic.schema(), &value).unwrap_or_else(|e| panic!("{}: {e}\n{value}", topic.name()));
        let back = decode(&topic, &bytes).unwrap();
        assert_eq!(encode(&topic, &back).unwrap(), bytes, "{}: not the same message back", topic.name());
        back
    }

    fn plain<T: rovernav_bus::Message + JsonSchema + PartialEq + std::fmt::Debug>(msg: T) {
        let topic: Topic<T> = Topic::new("/test/plain");
        let back: T = through(topic, &msg);
        assert_eq!(back, msg);
    }

    #[test]
    fn every_message_crosses_the_wire_unchanged_and_fits_its_schema() {
        let request = MotionRequest {
            id: 4,
            origin: Origin::Task(2),
            command: NavCommand::Drive {
                distance: -0.3,
                curvature: 0.2,
                guard: DriveGuard { proximity: true, max_tilt: Some(0.4) },
            },
        };
        let frame = FrameMsg::new(9, FrameSource::Command(request.clone()), &sample_frame());
        let back = through(topics::PLATFORM_FRAME, &frame);
        assert!(back.imu[0].compass_yaw.is_nan(), "a faulty compass stays faulty");
        assert_eq!(back.request(), Some(&request));
        assert_eq!(back.images, frame.images);
        for source in [FrameSource::Initial, FrameSource::Hold] {
            through(topics::PLATFORM_FRAME, &FrameMsg::new(0, source, &SensorFrame::default()));
        }
        plain(sample_frame().images[0].clone());
        let commands = [
            NavCommand::Sense(vec![
                SenseRequest::Mast { pan: 0.25 },
                SenseRequest::MastFine { pan: 3.0 },
                SenseRequest::BodyFront,
                SenseRequest::BodyRear,
                SenseRequest::Lidar { pan: -0.5 },
                SenseRequest::Navcam { pan: 0.25, tilt: 0.75 },
                SenseRequest::BodyPair { front: true },
            ]),
            NavCommand::Drive { distance: 1.0, curvature: 0.0, guard: DriveGuard::default() },
            NavCommand::Turn { angle: -1.25 },
            NavCommand::Finish(Outcome::HelpRequested, "stuck".into()),
        ];
        for (i, command) in commands.into_iter().enumerate() {
            for origin in [Origin::Navigator, Origin::Operator, Origin::Task(7), Origin::Arm(8)] {
                plain(MotionRequest { id: i as u64, origin, command: command.clone() });
            }
        }
        let estimate = EstimateMsg {
            frame_seq: 3,
            t: 1.5,
            pose: Pose3 { x: 1.0, y: -2.0, z: 0.3, roll: 0.01, pitch: -0.02, yaw: 3.0 },
            covariance: [[0.1, 0.0, 0.0], [0.0, 0.2, 0.0], [0.0, 0.0, 0.3]],
            localization_target: Some(0.7),
        };
        plain(estimate);
        let unknown = EstimateMsg { covariance: [[f64::INFINITY; 3]; 3], ..estimate };
        assert!(through(topics::LOCALIZATION_ESTIMATE, &unknown).covariance[1][2].is_nan());
        let goal = Goal {
            position: Point2::new(3.0, 4.0),
            tolerance: 0.5,
            waypoints: vec![Point2::new(1.0, 1.0)],
            keep_out: vec![vec![Point2::new(0.0, 0.0), Point2::new(1.0, 0.0), Point2::new(0.0, 1.0)]],
        };
        plain(DriveToMsg { task: 1, goal });
        plain(HoldMsg { until_s: 30.0, sleep: false });
        plain(RideAlongMsg { navcam: Some([0.25, -0.3]) });
        plain(RideAlongMsg { navcam: None });
        plain(CancelMsg { task: 2 });
        for action in [ArmAction::PlaceInstrument, ArmAction::Scoop] {
            plain(ArmTaskMsg { task: 3, action, target: [1.0, 2.0] });
        }
        for state in [TaskState::Pending, TaskState::InProcess, TaskState::Success, TaskState::Cancelled] {
            plain(TaskStatusMsg {
                task: 4,
                component: "navigator".into(),
                state,
                outcome: Some("reached".into()),
                message: "ok".into(),
            });
        }
        for action in [ControlAction::Resume, ControlAction::EmergencyStop, ControlAction::Shutdown] {
            plain(ControlMsg { target: Some("platform".into()), action });
        }
        plain(ControlMsg { target: None, action: ControlAction::Reset });
        for state in [JausState::Initialization, JausState::Ready, JausState::Failure] {
            plain(ComponentStatusMsg { component: "c".into(), state, message: "m".into(), time_s: 2.0 });
        }
        plain(PlanMsg { task: 5, points: vec![[0.0, 1.0], [2.0, 3.0]] });
        plain(String::from("status"));
    }

    #[test]
    fn a_wire_form_the_schema_forbids_is_caught() {
        let bad = serde_json::json!({"id": 1, "origin": "navigator", "command": {"fly": {}}});
        assert!(check(&topics::PLATFORM_COMMAND.schema(), &bad).is_err());
        let value = serde_json::to_value(FrameMsg::new(0, FrameSource::Initial, &sample_frame())).unwrap();
        let mut short = value.clone();
        short["frame"]["proximity"] = serde_json::json!([true]);
        assert!(check(&topics::PLATFORM_FRAME.schema(), &short).unwrap_err().contains("$.frame.proximity"));
    }

    #[test]
    fn every_topic_name_is_valid_and_has_a_schema() {
        let all = topics::all();
        let names: std::collections::BTreeSet<&str> = all.iter().map(|(name, _)| *name).collect();
        assert_eq!(names.len(), all.len(), "each topic listed once");
        assert!(
            names.contains(topics::NAVIGATION_SHADOW.name()) && names.contains(topics::OPERATOR_REPLY.name())
        );
        for (name, schema) in all {
            assert!(rovernav_bus::check_topic_name(name).is_ok(), "{name}");
            assert!(schema["type"].is_string() || schema["oneOf"].is_array(), "{name}: {schema}");
        }
    }
}
