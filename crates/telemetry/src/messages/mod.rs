//! The telemetry topics and their messages (JSON, with a JSON Schema each, derived).
//!
//! Units and frames follow ROS (REP 103): metres, radians, seconds; world x east, y north, z up;
//! body x forward, y left, z up. Per-cycle messages carry the navigator `cycle` (0 for the state
//! before the first command) and the simulated time around the core value they log (a
//! `SensorFrame`, a `NavCommand`, a `PoseEstimate`: the same types the bus carries). Messages on
//! `/sim/*` topics are simulator truth (they say so in a `simulation_truth` field): the autonomy
//! never saw them, they are logged to score and re-draw the run.
//!
//! Floats keep every bit through JSON and base64, so a replay rebuilds the run's world and trace
//! bit for bit.

use rovernav_bus::schema::titled_schema_of;
use rovernav_core::{NavCommand, Overlay, Point2, Pose2, Pose3, PoseEstimate, SensorFrame};
use rovernav_executive::{Report, RunSettings};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use serde_json::Value;

/// Topic names.
pub mod topics {
    /// The world, once at the start (simulation truth).
    pub const WORLD: &str = "/sim/world";
    /// The run settings, once at the start.
    pub const SETTINGS: &str = "/executive/settings";
    /// What the platform reported after each command (and before the first).
    pub const SENSOR_FRAME: &str = "/platform/sensor_frame";
    /// Each command the navigator issued.
    pub const COMMAND: &str = "/navigation/command";
    /// The navigator's plan, whenever it changes.
    pub const PLAN: &str = "/navigation/plan";
    /// The localiser's estimate after each frame.
    pub const ESTIMATE: &str = "/localization/estimate";
    /// The true pose after each command (simulation truth).
    pub const TRUTH: &str = "/sim/truth";
    /// Each new hazard contact of the true rover (simulation truth).
    pub const HAZARD_CONTACTS: &str = "/sim/hazard_contacts";
    /// End of each cycle: written last, so a cycle is complete in the log once this is there.
    pub const CYCLE: &str = "/executive/cycle";
    /// The final report, once at the end.
    pub const REPORT: &str = "/executive/report";
    /// The navigator's drawings at the end of the run.
    pub const OVERLAYS: &str = "/navigation/overlays";
    /// Each instrument placement, as the tooling arm published it on the bus (AutoPlace).
    pub const ARM_PLACEMENT: &str = "/bus/arm/placement";
    /// Each science watch's compact summary, as the deliberative layer published it on the bus.
    pub const SCIENCE_SUMMARY: &str = "/bus/science/summary";
    /// Each image visual target tracking saw (template, match, score, target estimate), as
    /// the deliberative layer published it on the bus.
    pub const VTT_TRACK: &str = "/bus/vtt/track";
    /// The power system's reading after each command (battery, panel, loads).
    pub const POWER: &str = "/power";
    /// Every topic a run logs, in the order they are first written.
    pub const ALL: [&str; 12] = [
        WORLD,
        SETTINGS,
        SENSOR_FRAME,
        ESTIMATE,
        TRUTH,
        CYCLE,
        COMMAND,
        PLAN,
        HAZARD_CONTACTS,
        OVERLAYS,
        REPORT,
        POWER,
    ];
}

/// A point in the world plane.
pub type Point2Msg = Point2;
/// A planar pose.
pub type Pose2Msg = Pose2;
/// A 3D pose.
pub type Pose3Msg = Pose3;

mod world;

pub use crate::foxglove::image::camera_topic;
pub use world::{TerrainMsg, WorldMsg};

/// Every curated topic with its schema name, derived schema and whether it carries simulation
/// truth (camera topics are declared on first use with `foxglove.CompressedImage`'s schema).
pub fn topic_table() -> Vec<(&'static str, &'static str, Value, bool)> {
    fn row<T: JsonSchema>(
        topic: &'static str,
        name: &'static str,
        truth: bool,
    ) -> (&'static str, &'static str, Value, bool) {
        (topic, name, titled_schema_of::<T>(name), truth)
    }
    vec![
        row::<WorldMsg>(topics::WORLD, "rovernav.World", true),
        row::<SettingsMsg>(topics::SETTINGS, "rovernav.RunSettings", false),
        row::<SensorFrameMsg>(topics::SENSOR_FRAME, "rovernav.SensorFrame", false),
        row::<EstimateMsg>(topics::ESTIMATE, "rovernav.PoseEstimate", false),
        row::<TruthMsg>(topics::TRUTH, "rovernav.Truth", true),
        row::<CycleMsg>(topics::CYCLE, "rovernav.Cycle", false),
        row::<CommandMsg>(topics::COMMAND, "rovernav.NavCommand", false),
        row::<PlanMsg>(topics::PLAN, "rovernav.Plan", false),
        row::<HazardContactMsg>(topics::HAZARD_CONTACTS, "rovernav.HazardContact", true),
        row::<OverlaysMsg>(topics::OVERLAYS, "rovernav.Overlays", false),
        row::<Report>(topics::REPORT, "rovernav.Report", false),
        row::<rovernav_core::PowerReading>(topics::POWER, "rovernav.Power", false),
    ]
}

/// `/executive/settings`: the run settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct SettingsMsg {
    /// Navigator registry name.
    pub navigator: String,
    /// Localiser registry name.
    pub localizer: String,
    /// Seed of every sensor's noise.
    pub seed: u64,
    /// Mission time budget (s).
    pub time_limit_s: f64,
    /// Navigator cycle budget.
    pub max_cycles: u64,
    /// Mission name.
    pub name: String,
    /// Navigator parameters the mission sets (absent in recordings made before they existed).
    #[serde(default)]
    pub navigator_params: Vec<NavigatorParamMsg>,
}

/// One navigator parameter of the run settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct NavigatorParamMsg {
    /// Parameter name, as in the mission file.
    pub name: String,
    /// Value, in the parameter's unit.
    pub value: f64,
}

impl SettingsMsg {
    /// The message of run settings.
    pub fn of(s: &RunSettings) -> Self {
        Self {
            navigator: s.navigator.clone(),
            localizer: s.localizer.clone(),
            seed: s.seed,
            time_limit_s: s.time_limit_s,
            max_cycles: s.max_cycles,
            name: s.name.clone(),
            navigator_params: s
                .navigator_params
                .iter()
                .map(|(name, &value)| NavigatorParamMsg { name: name.clone(), value })
                .collect(),
        }
    }

    /// The run settings.
    pub fn to_settings(&self) -> RunSettings {
        RunSettings {
            navigator: self.navigator.clone(),
            localizer: self.localizer.clone(),
            seed: self.seed,
            time_limit_s: self.time_limit_s,
            max_cycles: self.max_cycles,
            name: self.name.clone(),
            navigator_params: self.navigator_params.iter().map(|p| (p.name.clone(), p.value)).collect(),
        }
    }
}

/// `/platform/sensor_frame`: what the platform reported after a command, by cycle.
///
/// A frame is logged once: when the log holds the component bus, the frame is the
/// `/bus/platform/frame` message numbered `bus_seq` (logged just before) and this message only
/// ties it to its cycle; otherwise (a recorder not fed the bus) the frame is here, without its
/// images (they go to their own `/camera/NAME` topics).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct SensorFrameMsg {
    /// Cycle (0: the frame before the first command).
    pub cycle: u64,
    /// `seq` of the `/bus/platform/frame` message that holds the frame.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bus_seq: Option<u64>,
    /// The frame itself, when the bus is not logged.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frame: Option<SensorFrame>,
}

impl SensorFrameMsg {
    /// The message of a frame logged here, without its images.
    pub fn of(cycle: u64, f: &SensorFrame) -> Self {
        Self { cycle, bus_seq: None, frame: Some(without_images(f)) }
    }

    /// The message of a frame logged on the bus as message `bus_seq`.
    pub fn on_bus(cycle: u64, bus_seq: u64) -> Self {
        Self { cycle, bus_seq: Some(bus_seq), frame: None }
    }
}

/// A frame without its camera images.
pub fn without_images(f: &SensorFrame) -> SensorFrame {
    SensorFrame {
        t: f.t,
        clouds: f.clouds.clone(),
        imu: f.imu.clone(),
        odometry: f.odometry.clone(),
        proximity: f.proximity,
        motion_stopped: f.motion_stopped.clone(),
        images: Vec::new(),
        power: f.power,
        lander: f.lander.clone(),
    }
}

/// `/navigation/command`: the command the navigator issued.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct CommandMsg {
    /// Cycle.
    pub cycle: u64,
    /// Simulated time after the command (s).
    pub sim_time_s: f64,
    /// The command.
    pub command: NavCommand,
}

impl CommandMsg {
    /// The message of a command.
    pub fn of(cycle: u64, sim_time_s: f64, c: &NavCommand) -> Self {
        Self { cycle, sim_time_s, command: c.clone() }
    }
}

/// `/navigation/plan`: the navigator's plan, logged when it changes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct PlanMsg {
    /// Cycle at which the plan was announced.
    pub cycle: u64,
    /// Simulated time (s).
    pub sim_time_s: f64,
    /// Waypoints of the plan, world frame.
    pub points: Vec<Point2>,
}

/// `/localization/estimate`: the localiser's belief.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct EstimateMsg {
    /// Cycle.
    pub cycle: u64,
    /// Simulated time (s).
    pub sim_time_s: f64,
    /// The estimate (its fields beside `cycle`; a non-finite covariance entry is `null`).
    #[serde(flatten)]
    pub estimate: PoseEstimate,
}

impl EstimateMsg {
    /// The message of an estimate.
    pub fn of(cycle: u64, sim_time_s: f64, e: &PoseEstimate) -> Self {
        Self { cycle, sim_time_s, estimate: *e }
    }
}

/// `/sim/truth`: the true pose after a command.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct TruthMsg {
    /// Always true: simulator ground truth.
    pub simulation_truth: bool,
    /// Cycle.
    pub cycle: u64,
    /// Simulated time (s).
    pub sim_time_s: f64,
    /// True pose.
    pub pose: Pose3,
    /// Hazard contacts so far.
    pub hazard_contacts: u32,
}

/// `/sim/hazard_contacts`: a new hazard contact of the true rover.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct HazardContactMsg {
    /// Always true: simulator ground truth.
    pub simulation_truth: bool,
    /// Cycle.
    pub cycle: u64,
    /// Simulated time (s).
    pub sim_time_s: f64,
    /// True east (m).
    pub x: f64,
    /// True north (m).
    pub y: f64,
    /// Hazard contacts so far.
    pub contacts: u32,
    /// The simulator's description.
    pub cause: String,
}

/// `/executive/cycle`: the end of a cycle; every message of the cycle precedes it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct CycleMsg {
    /// Cycle (0: the start).
    pub cycle: u64,
    /// Simulated time (s).
    pub sim_time_s: f64,
    /// Wall-clock time since the recorder opened (s).
    pub wall_time_s: f64,
}

/// `/navigation/overlays`: the navigator's drawings (C-obstacles, wedges, subpaths) at the end of
/// the run, world frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct OverlaysMsg {
    /// Simulated time (s).
    pub sim_time_s: f64,
    /// The drawings.
    pub overlays: Vec<Overlay>,
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use rovernav_bus::schema::check;
    use rovernav_core::{
        CameraKind, DriveGuard, ImuSample, OdometrySample, Outcome, OverlayKind, PointCloud,
        ProximityReading, SenseRequest, Wedge,
    };

    /// JSON text round trip, as the log does it, checking the value against the channel's schema.
    pub(crate) fn through_json<T: Serialize + serde::de::DeserializeOwned + JsonSchema>(v: &T) -> T {
        let text = serde_json::to_string(v).unwrap();
        let schema = titled_schema_of::<T>("test");
        check(&schema, &serde_json::from_str::<Value>(&text).unwrap())
            .unwrap_or_else(|e| panic!("{e}\n{text}"));
        serde_json::from_str(&text).unwrap()
    }

    fn sample_frame() -> SensorFrame {
        let cloud = |camera, n: usize| PointCloud {
            camera,
            origin: [0.1, -0.2, 1.2],
            wedge: Wedge { bearing: 0.3, half_angle: 0.4, min_range: 1.0, max_range: 5.0 },
            points: (0..n).map(|i| [i as f32 * 0.1, -(i as f32) / 3.0, 1e-7 * i as f32]).collect(),
        };
        SensorFrame {
            t: 12.5,
            clouds: vec![
                cloud(CameraKind::Mast, 7),
                cloud(CameraKind::Lidar, 0),
                cloud(CameraKind::BodyRear, 1),
            ],
            imu: vec![
                ImuSample {
                    t: 12.0,
                    gyro_z: 1e-5,
                    incl_roll: 0.01,
                    incl_pitch: -0.02,
                    compass_yaw: 0.5,
                    sun_yaw: None,
                },
                ImuSample {
                    t: 12.5,
                    gyro_z: 0.0,
                    incl_roll: 0.0,
                    incl_pitch: 0.0,
                    compass_yaw: f64::NAN,
                    sun_yaw: Some(-3.1),
                },
            ],
            odometry: vec![OdometrySample { t: 12.5, left_counts: -5, right_counts: 1 << 40 }],
            proximity: ProximityReading {
                raw: [true, false, false, false, true, false, false, false, false, true],
            },
            motion_stopped: Some("proximity".into()),
            images: Vec::new(),
            power: None,
            lander: None,
        }
    }

    #[test]
    fn sensor_frame_round_trips_and_fits_its_schema() {
        let frame = sample_frame();
        let back = through_json(&SensorFrameMsg::of(4, &frame)).frame.unwrap();
        assert!(back.imu[1].compass_yaw.is_nan(), "a faulty compass stays faulty");
        let mut expected = frame.clone();
        expected.imu[1].compass_yaw = 0.0;
        let mut got = back;
        got.imu[1].compass_yaw = 0.0;
        assert_eq!(got, expected);
    }

    #[test]
    fn every_command_round_trips_and_fits_its_schema() {
        // Each shape of variant (the bus tests cover every command): a list, fields, a tuple.
        let commands = [
            NavCommand::Sense(vec![
                SenseRequest::MastFine { pan: 3.0 },
                SenseRequest::Navcam { pan: 0.25, tilt: 0.75 },
            ]),
            NavCommand::Drive {
                distance: -0.3,
                curvature: 0.7,
                guard: DriveGuard { proximity: true, max_tilt: None },
            },
            NavCommand::Finish(Outcome::HelpRequested, "stuck".into()),
        ];
        for c in commands {
            assert_eq!(through_json(&CommandMsg::of(3, 9.0, &c)).command, c);
        }
    }

    #[test]
    fn per_cycle_messages_round_trip_and_fit_their_schemas() {
        let pose = Pose3 { x: 1.0, y: 2.0, z: 0.5, roll: 0.01, pitch: -0.02, yaw: 3.0 };
        let e =
            PoseEstimate { pose, covariance: [[0.1, 0.0, 0.0], [0.0, 0.2, 0.0], [0.0, 0.0, f64::INFINITY]] };
        let back = through_json(&EstimateMsg::of(2, 3.0, &e));
        assert_eq!(back.estimate.pose, pose);
        assert!(back.estimate.covariance[2][2].is_nan(), "an unknown variance reads back as NaN");
        let truth = TruthMsg { simulation_truth: true, cycle: 2, sim_time_s: 3.0, pose, hazard_contacts: 1 };
        assert_eq!(through_json(&truth), truth);
        let plan = PlanMsg { cycle: 1, sim_time_s: 2.0, points: vec![Point2::new(1.0, 2.0)] };
        assert_eq!(through_json(&plan), plan);
        let contact = HazardContactMsg {
            simulation_truth: true,
            cycle: 4,
            sim_time_s: 5.0,
            x: 1.0,
            y: 2.0,
            contacts: 1,
            cause: "hazard: tilt".into(),
        };
        assert_eq!(through_json(&contact), contact);
        let cycle = CycleMsg { cycle: 4, sim_time_s: 5.0, wall_time_s: 0.25 };
        assert_eq!(through_json(&cycle), cycle);
    }

    #[test]
    fn overlays_round_trip_and_fit_their_schema() {
        let pts = vec![Point2::new(1.0, 2.0), Point2::new(0.1, 0.2)];
        let overlays = vec![
            Overlay::Polygon(pts.clone(), OverlayKind::CObstacle),
            Overlay::Polyline(pts.clone(), OverlayKind::Plan),
            Overlay::Polygon(pts.clone(), OverlayKind::Wedge),
            Overlay::Polyline(vec![], OverlayKind::Other),
        ];
        let msg = OverlaysMsg { sim_time_s: 5.0, overlays: overlays.clone() };
        assert_eq!(through_json(&msg).overlays, overlays);
    }

    #[test]
    fn settings_and_report_fit_their_schemas() {
        let s = RunSettings {
            navigator: "astar-grid".into(),
            localizer: "ekf".into(),
            seed: 9,
            time_limit_s: 60.0,
            max_cycles: 10,
            name: "m".into(),
            navigator_params: [("safety_buffer_m".to_string(), 0.2)].into(),
        };
        assert_eq!(through_json(&SettingsMsg::of(&s)).to_settings(), s);
        let report = Report {
            outcome: "reached".into(),
            optimal_length_m: None,
            hazard_events: vec![rovernav_executive::HazardEvent {
                x: 1.0,
                y: 2.0,
                cycle: 3,
                cause: "rock".into(),
            }],
            ..Default::default()
        };
        assert_eq!(through_json(&report), report);
        let with_stats = Report {
            localization_stats: Some(rovernav_executive::LocalizationStats {
                matches_attempted: 7,
                fixes_used: 5,
                fixes_rejected: 2,
                rejected_on_edge: 1,
                ..Default::default()
            }),
            ..report
        };
        assert_eq!(through_json(&with_stats), with_stats);
    }

    #[test]
    fn every_channel_schema_is_titled_with_its_schema_name() {
        for (topic, name, schema, _) in topic_table() {
            assert_eq!(schema["title"], name, "{topic}");
            assert_eq!(schema["$schema"], "https://json-schema.org/draft/2020-12/schema", "{topic}");
        }
    }
}
