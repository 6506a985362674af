//! The telemetry topics and their messages (JSON, with a JSON Schema each).
//!
//! Units and frames follow ROS (REP 103): metres, radians, seconds; world x east, y north, z up;
//! body x forward, y left, z up. Per-cycle messages carry the navigator `cycle` (0 for the state
//! before the first command) and the simulated time. Messages on `/sim/*` topics are simulator
//! truth (they say so in a `simulation_truth` field): the autonomy never saw them, they are
//! logged to score and re-draw the run.
//!
//! Conversions are exact both ways (floats keep every bit through JSON and base64), so a replay
//! rebuilds the run's world and trace bit for bit.

use crate::base64;
use crate::schema::{
    array, boolean, bytes, enumeration, fixed_array, integer, message, nullable, number, object, string,
};
use rovernav_core::{
    CameraKind, DriveGuard, ImuSample, NavCommand, OdometrySample, Outcome, Overlay, OverlayKind, Point2,
    PointCloud, Pose3, PoseEstimate, ProximityReading, SenseRequest, SensorFrame, Wedge,
};
use rovernav_executive::RunSettings;
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
    /// Every topic a run logs, in the order they are first written.
    pub const ALL: [&str; 11] = [
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
    ];
}

/// A point in the world plane.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Point2Msg {
    /// East (m).
    pub x: f64,
    /// North (m).
    pub y: f64,
}

impl From<Point2> for Point2Msg {
    fn from(p: Point2) -> Self {
        Self { x: p.x, y: p.y }
    }
}

impl From<Point2Msg> for Point2 {
    fn from(p: Point2Msg) -> Self {
        Point2::new(p.x, p.y)
    }
}

fn point_schema() -> Value {
    object("point in the world plane", &[("x", number("east (m)")), ("y", number("north (m)"))])
}

fn points_schema(description: &str) -> Value {
    array(description, point_schema())
}

/// A planar pose.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Pose2Msg {
    /// East (m).
    pub x: f64,
    /// North (m).
    pub y: f64,
    /// Heading, counter-clockwise from east (rad).
    pub yaw: f64,
}

fn pose2_schema(description: &str) -> Value {
    object(
        description,
        &[
            ("x", number("east (m)")),
            ("y", number("north (m)")),
            ("yaw", number("heading, counter-clockwise from east (rad)")),
        ],
    )
}

/// A 3D pose (roll, pitch, yaw applied as in `Pose3`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Pose3Msg {
    /// East (m).
    pub x: f64,
    /// North (m).
    pub y: f64,
    /// Up (m).
    pub z: f64,
    /// Roll (rad).
    pub roll: f64,
    /// Pitch (rad).
    pub pitch: f64,
    /// Yaw, counter-clockwise from east (rad).
    pub yaw: f64,
}

impl From<&Pose3> for Pose3Msg {
    fn from(p: &Pose3) -> Self {
        Self { x: p.x, y: p.y, z: p.z, roll: p.roll, pitch: p.pitch, yaw: p.yaw }
    }
}

impl From<&Pose3Msg> for Pose3 {
    fn from(p: &Pose3Msg) -> Self {
        Pose3 { x: p.x, y: p.y, z: p.z, roll: p.roll, pitch: p.pitch, yaw: p.yaw }
    }
}

fn pose3_schema(description: &str) -> Value {
    object(
        description,
        &[
            ("x", number("east (m)")),
            ("y", number("north (m)")),
            ("z", number("up (m)")),
            ("roll", number("roll (rad)")),
            ("pitch", number("pitch (rad)")),
            ("yaw", number("yaw, counter-clockwise from east (rad)")),
        ],
    )
}

mod image;
mod world;

pub use image::{RawImageMsg, TimeMsg, camera_topic};
pub use world::{
    GoalMsg, GridMsg, ImagerMsg, LidarMsg, ProximityModelMsg, RockMsg, RoverMsg, SensorModelMsg, SlipMsg,
    TerrainMsg, WorldMsg,
};

// ---------------------------------------------------------------------------------------------
// /executive/settings

/// `/executive/settings`: the run settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
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
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
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

    /// The JSON Schema.
    pub fn schema() -> Value {
        message(
            "rovernav.RunSettings",
            "The settings of the run",
            &[
                ("navigator", string("navigator registry name")),
                ("localizer", string("localiser registry name")),
                ("seed", integer("seed of every sensor's noise")),
                ("time_limit_s", number("mission time budget (s)")),
                ("max_cycles", integer("navigator cycle budget")),
                ("name", string("mission name")),
                (
                    "navigator_params",
                    array(
                        "navigator parameters the mission sets",
                        object(
                            "one navigator parameter",
                            &[
                                ("name", string("parameter name, as in the mission file")),
                                ("value", number("value, in the parameter's unit")),
                            ],
                        ),
                    ),
                ),
            ],
        )
    }
}

// ---------------------------------------------------------------------------------------------
// /platform/sensor_frame

/// One inertial sample.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ImuMsg {
    /// Time (s).
    pub t: f64,
    /// Gyro yaw rate (rad/s).
    pub gyro_z: f64,
    /// Inclinometer roll (rad).
    pub incl_roll: f64,
    /// Inclinometer pitch (rad).
    pub incl_pitch: f64,
    /// Compass heading (rad); null on a faulty compass (NaN in the sample).
    pub compass_yaw: Option<f64>,
    /// Sun sensor heading (rad), when the sun is visible.
    pub sun_yaw: Option<f64>,
}

/// One encoder sample.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct OdometryMsg {
    /// Time (s).
    pub t: f64,
    /// Left cumulative counts.
    pub left_counts: i64,
    /// Right cumulative counts.
    pub right_counts: i64,
}

/// The planar region a range image covers.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct WedgeMsg {
    /// Bearing of the centre, body frame (rad).
    pub bearing: f64,
    /// Half field of view (rad).
    pub half_angle: f64,
    /// Nearest range (m).
    pub min_range: f64,
    /// Far range (m).
    pub max_range: f64,
}

/// One range image as a point cloud in the body frame at capture.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CloudMsg {
    /// `mast` | `body_front` | `body_rear` | `lidar`.
    pub camera: String,
    /// Sensor origin, body frame (m).
    pub origin: [f64; 3],
    /// Covered region.
    pub wedge: WedgeMsg,
    /// Number of points.
    pub point_count: u64,
    /// Points as little-endian f32 triples (x forward, y left, z up; m), 12 bytes per point.
    pub points_xyz_f32le: String,
}

/// `/platform/sensor_frame`: what the platform reported after a command.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SensorFrameMsg {
    /// Cycle (0: the frame before the first command).
    pub cycle: u64,
    /// Time at the end of the command (s).
    pub t: f64,
    /// Inertial samples in time order.
    pub imu: Vec<ImuMsg>,
    /// Encoder samples in time order.
    pub odometry: Vec<OdometryMsg>,
    /// The ten proximity sensors, index 0 leftmost; true when triggered.
    pub proximity: Vec<bool>,
    /// Why a motion stopped early, if it did.
    pub motion_stopped: Option<String>,
    /// Range images.
    pub clouds: Vec<CloudMsg>,
}

/// The sensor name of a full-resolution mast image request.
const MAST_FINE: &str = "mast_fine";

/// The sensor name of a Navcam image-pair request.
const NAVCAM: &str = "navcam";

/// The sensor names a sensing request may carry.
const SENSE_SENSORS: [&str; 6] = ["mast", MAST_FINE, "body_front", "body_rear", "lidar", NAVCAM];

const CAMERAS: [CameraKind; 4] =
    [CameraKind::Mast, CameraKind::BodyFront, CameraKind::BodyRear, CameraKind::Lidar];

impl SensorFrameMsg {
    /// The message of a frame.
    pub fn of(cycle: u64, f: &SensorFrame) -> Self {
        Self {
            cycle,
            t: f.t,
            imu: f
                .imu
                .iter()
                .map(|s| ImuMsg {
                    t: s.t,
                    gyro_z: s.gyro_z,
                    incl_roll: s.incl_roll,
                    incl_pitch: s.incl_pitch,
                    compass_yaw: Some(s.compass_yaw).filter(|v| !v.is_nan()),
                    sun_yaw: s.sun_yaw,
                })
                .collect(),
            odometry: f
                .odometry
                .iter()
                .map(|o| OdometryMsg { t: o.t, left_counts: o.left_counts, right_counts: o.right_counts })
                .collect(),
            proximity: f.proximity.raw.to_vec(),
            motion_stopped: f.motion_stopped.clone(),
            clouds: f
                .clouds
                .iter()
                .map(|c| CloudMsg {
                    camera: c.camera.as_str().into(),
                    origin: c.origin,
                    wedge: WedgeMsg {
                        bearing: c.wedge.bearing,
                        half_angle: c.wedge.half_angle,
                        min_range: c.wedge.min_range,
                        max_range: c.wedge.max_range,
                    },
                    point_count: c.points.len() as u64,
                    points_xyz_f32le: base64::encode_f32s(c.points.iter().flatten().copied()),
                })
                .collect(),
        }
    }

    /// Rebuilds the frame; the error names the field that does not fit.
    pub fn to_frame(&self) -> Result<SensorFrame, String> {
        let mut clouds = Vec::with_capacity(self.clouds.len());
        for (i, c) in self.clouds.iter().enumerate() {
            let camera = CAMERAS
                .into_iter()
                .find(|k| k.as_str() == c.camera)
                .ok_or_else(|| format!("field `clouds[{i}].camera`: unknown camera `{}`", c.camera))?;
            let flat = base64::decode_f32s(&c.points_xyz_f32le)
                .map_err(|e| format!("field `clouds[{i}].points_xyz_f32le`: {e}"))?;
            if flat.len() as u64 != c.point_count * 3 {
                return Err(format!(
                    "field `clouds[{i}].points_xyz_f32le`: {} floats for {} points",
                    flat.len(),
                    c.point_count
                ));
            }
            clouds.push(PointCloud {
                camera,
                origin: c.origin,
                wedge: Wedge {
                    bearing: c.wedge.bearing,
                    half_angle: c.wedge.half_angle,
                    min_range: c.wedge.min_range,
                    max_range: c.wedge.max_range,
                },
                points: flat.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect(),
            });
        }
        let raw: [bool; 10] =
            self.proximity.as_slice().try_into().map_err(|_| {
                format!("field `proximity`: expected 10 sensors, found {}", self.proximity.len())
            })?;
        Ok(SensorFrame {
            t: self.t,
            clouds,
            imu: self
                .imu
                .iter()
                .map(|s| ImuSample {
                    t: s.t,
                    gyro_z: s.gyro_z,
                    incl_roll: s.incl_roll,
                    incl_pitch: s.incl_pitch,
                    compass_yaw: s.compass_yaw.unwrap_or(f64::NAN),
                    sun_yaw: s.sun_yaw,
                })
                .collect(),
            odometry: self
                .odometry
                .iter()
                .map(|o| OdometrySample { t: o.t, left_counts: o.left_counts, right_counts: o.right_counts })
                .collect(),
            proximity: ProximityReading { raw },
            motion_stopped: self.motion_stopped.clone(),
            // Images go to their own topics (`/camera/NAME`); no consumer of a replayed frame
            // reads them.
            images: Vec::new(),
        })
    }

    /// The JSON Schema.
    pub fn schema() -> Value {
        message(
            "rovernav.SensorFrame",
            "What the platform reported after one command (body frame: x forward, y left, z up)",
            &[
                ("cycle", integer("navigator cycle (0: before the first command)")),
                ("t", number("time at the end of the command (s)")),
                (
                    "imu",
                    array(
                        "inertial samples in time order",
                        object(
                            "inertial sample",
                            &[
                                ("t", number("time (s)")),
                                ("gyro_z", number("gyro yaw rate (rad/s)")),
                                ("incl_roll", number("inclinometer roll (rad)")),
                                ("incl_pitch", number("inclinometer pitch (rad)")),
                                ("compass_yaw", nullable(number("compass heading (rad); null: faulty"))),
                                ("sun_yaw", nullable(number("sun sensor heading (rad); null: no sun"))),
                            ],
                        ),
                    ),
                ),
                (
                    "odometry",
                    array(
                        "encoder samples in time order",
                        object(
                            "encoder sample",
                            &[
                                ("t", number("time (s)")),
                                ("left_counts", integer("left cumulative counts")),
                                ("right_counts", integer("right cumulative counts")),
                            ],
                        ),
                    ),
                ),
                ("proximity", fixed_array("proximity sensors, 0 leftmost; true: triggered", boolean(""), 10)),
                ("motion_stopped", nullable(string("why a motion stopped early"))),
                (
                    "clouds",
                    array(
                        "range images",
                        object(
                            "point cloud in the body frame at capture",
                            &[
                                ("camera", enumeration("sensor", &CAMERAS.map(CameraKind::as_str))),
                                ("origin", fixed_array("sensor origin, body frame (m)", number("m"), 3)),
                                (
                                    "wedge",
                                    object(
                                        "covered planar region, body frame",
                                        &[
                                            ("bearing", number("centre bearing (rad)")),
                                            ("half_angle", number("half field of view (rad)")),
                                            ("min_range", number("nearest range (m)")),
                                            ("max_range", number("far range (m)")),
                                        ],
                                    ),
                                ),
                                ("point_count", integer("number of points")),
                                (
                                    "points_xyz_f32le",
                                    bytes("points as little-endian f32 x, y, z triples (m), 12 bytes each"),
                                ),
                            ],
                        ),
                    ),
                ),
            ],
        )
    }
}

// ---------------------------------------------------------------------------------------------
// /navigation/command

/// `/navigation/command`: the command the navigator issued.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CommandMsg {
    /// Cycle.
    pub cycle: u64,
    /// Simulated time after the command (s).
    pub sim_time_s: f64,
    /// `sense` | `drive` | `turn` | `finish`.
    pub kind: String,
    /// Sensing requests (sense).
    pub sense: Vec<SenseRequestMsg>,
    /// Signed arc length (drive, m).
    pub distance: Option<f64>,
    /// Curvature (drive, 1/m, positive left).
    pub curvature: Option<f64>,
    /// Stop on proximity (drive).
    pub guard_proximity: Option<bool>,
    /// Stop above this tilt (drive, rad).
    pub guard_max_tilt: Option<f64>,
    /// Signed turn angle (turn, rad).
    pub angle: Option<f64>,
    /// Outcome (finish).
    pub outcome: Option<String>,
    /// Why (finish).
    pub message: Option<String>,
}

/// One sensing request (owned form for deserialisation).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SenseRequestMsg {
    /// `mast` | `mast_fine` | `body_front` | `body_rear` | `lidar`.
    pub sensor: String,
    /// Pan angle for the mast and LIDAR (rad).
    pub pan: Option<f64>,
    /// Tilt angle for the Navcam pair (rad, positive up).
    #[serde(default)]
    pub tilt: Option<f64>,
}

impl CommandMsg {
    /// The message of a command.
    pub fn of(cycle: u64, sim_time_s: f64, c: &NavCommand) -> Self {
        let mut m = Self {
            cycle,
            sim_time_s,
            kind: String::new(),
            sense: Vec::new(),
            distance: None,
            curvature: None,
            guard_proximity: None,
            guard_max_tilt: None,
            angle: None,
            outcome: None,
            message: None,
        };
        match c {
            NavCommand::Sense(requests) => {
                m.kind = "sense".into();
                m.sense = requests
                    .iter()
                    .map(|r| {
                        let (sensor, pan, tilt) = match *r {
                            SenseRequest::Mast { pan } => (CameraKind::Mast.as_str(), Some(pan), None),
                            SenseRequest::MastFine { pan } => (MAST_FINE, Some(pan), None),
                            SenseRequest::BodyFront => (CameraKind::BodyFront.as_str(), None, None),
                            SenseRequest::BodyRear => (CameraKind::BodyRear.as_str(), None, None),
                            SenseRequest::Lidar { pan } => (CameraKind::Lidar.as_str(), Some(pan), None),
                            SenseRequest::Navcam { pan, tilt } => (NAVCAM, Some(pan), Some(tilt)),
                        };
                        SenseRequestMsg { sensor: sensor.into(), pan, tilt }
                    })
                    .collect();
            }
            NavCommand::Drive { distance, curvature, guard } => {
                m.kind = "drive".into();
                m.distance = Some(*distance);
                m.curvature = Some(*curvature);
                m.guard_proximity = Some(guard.proximity);
                m.guard_max_tilt = guard.max_tilt;
            }
            NavCommand::Turn { angle } => {
                m.kind = "turn".into();
                m.angle = Some(*angle);
            }
            NavCommand::Finish(outcome, message) => {
                m.kind = "finish".into();
                m.outcome = Some(outcome.as_str().into());
                m.message = Some(message.clone());
            }
        }
        m
    }

    /// Rebuilds the command; the error names the field that does not fit.
    pub fn to_command(&self) -> Result<NavCommand, String> {
        let need = |v: Option<f64>, field: &str| v.ok_or_else(|| format!("field `{field}`: missing"));
        Ok(match self.kind.as_str() {
            "sense" => NavCommand::Sense(
                self.sense
                    .iter()
                    .enumerate()
                    .map(|(i, r)| {
                        let pan = || need(r.pan, &format!("sense[{i}].pan"));
                        Ok(match r.sensor.as_str() {
                            "mast" => SenseRequest::Mast { pan: pan()? },
                            MAST_FINE => SenseRequest::MastFine { pan: pan()? },
                            "body_front" => SenseRequest::BodyFront,
                            "body_rear" => SenseRequest::BodyRear,
                            "lidar" => SenseRequest::Lidar { pan: pan()? },
                            NAVCAM => SenseRequest::Navcam {
                                pan: pan()?,
                                tilt: need(r.tilt, &format!("sense[{i}].tilt"))?,
                            },
                            other => {
                                return Err(format!("field `sense[{i}].sensor`: unknown sensor `{other}`"));
                            }
                        })
                    })
                    .collect::<Result<_, String>>()?,
            ),
            "drive" => NavCommand::Drive {
                distance: need(self.distance, "distance")?,
                curvature: need(self.curvature, "curvature")?,
                guard: DriveGuard {
                    proximity: self.guard_proximity.unwrap_or(false),
                    max_tilt: self.guard_max_tilt,
                },
            },
            "turn" => NavCommand::Turn { angle: need(self.angle, "angle")? },
            "finish" => {
                let name = self.outcome.as_deref().unwrap_or_default();
                let outcome = Outcome::parse(name)
                    .ok_or_else(|| format!("field `outcome`: unknown outcome `{name}`"))?;
                NavCommand::Finish(outcome, self.message.clone().unwrap_or_default())
            }
            other => return Err(format!("field `kind`: unknown command kind `{other}`")),
        })
    }

    /// The JSON Schema.
    pub fn schema() -> Value {
        message(
            "rovernav.NavCommand",
            "The command the navigator issued; fields that do not apply to its kind are null",
            &[
                ("cycle", integer("navigator cycle")),
                ("sim_time_s", number("simulated time after the command (s)")),
                ("kind", enumeration("command kind", &["sense", "drive", "turn", "finish"])),
                (
                    "sense",
                    array(
                        "sensing requests (sense)",
                        object(
                            "sensing request",
                            &[
                                ("sensor", enumeration("sensor", &SENSE_SENSORS)),
                                ("pan", nullable(number("pan angle, body frame (rad); mast, lidar, navcam"))),
                                ("tilt", nullable(number("tilt angle, positive up (rad); navcam"))),
                            ],
                        ),
                    ),
                ),
                ("distance", nullable(number("signed arc length (drive, m)"))),
                ("curvature", nullable(number("curvature (drive, 1/m, positive left)"))),
                ("guard_proximity", nullable(boolean("stop when a proximity sensor triggers (drive)"))),
                ("guard_max_tilt", nullable(number("stop above this tilt (drive, rad)"))),
                ("angle", nullable(number("signed turn angle (turn, rad)"))),
                ("outcome", nullable(string("outcome (finish)"))),
                ("message", nullable(string("why (finish)"))),
            ],
        )
    }
}

// ---------------------------------------------------------------------------------------------
// /navigation/plan, /localization/estimate, /sim/truth, /sim/hazard_contacts, /executive/cycle

/// `/navigation/plan`: the navigator's plan, logged when it changes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlanMsg {
    /// Cycle at which the plan was announced.
    pub cycle: u64,
    /// Simulated time (s).
    pub sim_time_s: f64,
    /// Waypoints of the plan, world frame.
    pub points: Vec<Point2Msg>,
}

impl PlanMsg {
    /// The JSON Schema.
    pub fn schema() -> Value {
        message(
            "rovernav.Plan",
            "The navigator's planned path (world frame), logged when it changes",
            &[
                ("cycle", integer("navigator cycle")),
                ("sim_time_s", number("simulated time (s)")),
                ("points", points_schema("plan vertices")),
            ],
        )
    }
}

/// `/localization/estimate`: the localiser's belief.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EstimateMsg {
    /// Cycle.
    pub cycle: u64,
    /// Simulated time (s).
    pub sim_time_s: f64,
    /// Estimated pose.
    pub pose: Pose3Msg,
    /// Covariance of (x, y, yaw), row-major; null where not finite (JSON has no infinities).
    pub covariance: Vec<Option<f64>>,
}

impl EstimateMsg {
    /// The message of an estimate.
    pub fn of(cycle: u64, sim_time_s: f64, e: &PoseEstimate) -> Self {
        Self {
            cycle,
            sim_time_s,
            pose: (&e.pose).into(),
            covariance: e.covariance.iter().flatten().map(|&v| Some(v).filter(|v| v.is_finite())).collect(),
        }
    }

    /// The JSON Schema.
    pub fn schema() -> Value {
        message(
            "rovernav.PoseEstimate",
            "The localiser's estimate after the cycle's frame",
            &[
                ("cycle", integer("navigator cycle")),
                ("sim_time_s", number("simulated time (s)")),
                ("pose", pose3_schema("estimated pose")),
                ("covariance", fixed_array("covariance of (x, y, yaw), row-major", nullable(number("")), 9)),
            ],
        )
    }
}

/// `/sim/truth`: the true pose after a command.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TruthMsg {
    /// Always true: simulator ground truth.
    pub simulation_truth: bool,
    /// Cycle.
    pub cycle: u64,
    /// Simulated time (s).
    pub sim_time_s: f64,
    /// True pose.
    pub pose: Pose3Msg,
    /// Hazard contacts so far.
    pub hazard_contacts: u32,
}

impl TruthMsg {
    /// The JSON Schema.
    pub fn schema() -> Value {
        message(
            "rovernav.Truth",
            "The true rover pose (simulation truth: the autonomy never sees it)",
            &[
                ("simulation_truth", boolean("always true")),
                ("cycle", integer("navigator cycle")),
                ("sim_time_s", number("simulated time (s)")),
                ("pose", pose3_schema("true pose")),
                ("hazard_contacts", integer("hazard contacts so far")),
            ],
        )
    }
}

/// `/sim/hazard_contacts`: a new hazard contact of the true rover.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
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

impl HazardContactMsg {
    /// The JSON Schema.
    pub fn schema() -> Value {
        message(
            "rovernav.HazardContact",
            "The true rover entered a hazard (simulation truth)",
            &[
                ("simulation_truth", boolean("always true")),
                ("cycle", integer("navigator cycle")),
                ("sim_time_s", number("simulated time (s)")),
                ("x", number("true east (m)")),
                ("y", number("true north (m)")),
                ("contacts", integer("hazard contacts so far")),
                ("cause", string("the simulator's description")),
            ],
        )
    }
}

/// `/executive/cycle`: the end of a cycle.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CycleMsg {
    /// Cycle (0: the start).
    pub cycle: u64,
    /// Simulated time (s).
    pub sim_time_s: f64,
    /// Wall-clock time since the recorder opened (s).
    pub wall_time_s: f64,
}

impl CycleMsg {
    /// The JSON Schema.
    pub fn schema() -> Value {
        message(
            "rovernav.Cycle",
            "End of a navigator cycle: every message of the cycle precedes it",
            &[
                ("cycle", integer("navigator cycle (0: the start)")),
                ("sim_time_s", number("simulated time (s)")),
                ("wall_time_s", number("wall-clock time since the log opened (s)")),
            ],
        )
    }
}

// ---------------------------------------------------------------------------------------------
// /navigation/overlays, /executive/report

/// One navigator drawing.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OverlayMsg {
    /// `polygon` (closed) | `polyline` (open).
    pub shape: String,
    /// `plan` | `c_obstacle` | `wedge` | `other`.
    pub kind: String,
    /// Vertices, world frame.
    pub points: Vec<Point2Msg>,
}

/// `/navigation/overlays`: the navigator's drawings at the end of the run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OverlaysMsg {
    /// Simulated time (s).
    pub sim_time_s: f64,
    /// The drawings.
    pub overlays: Vec<OverlayMsg>,
}

const OVERLAY_KINDS: [(OverlayKind, &str); 4] = [
    (OverlayKind::Plan, "plan"),
    (OverlayKind::CObstacle, "c_obstacle"),
    (OverlayKind::Wedge, "wedge"),
    (OverlayKind::Other, "other"),
];

impl OverlaysMsg {
    /// The message of a navigator's overlays.
    pub fn of(sim_time_s: f64, overlays: &[Overlay]) -> Self {
        let name = |k: OverlayKind| OVERLAY_KINDS.iter().find(|(o, _)| *o == k).map_or("other", |(_, n)| n);
        Self {
            sim_time_s,
            overlays: overlays
                .iter()
                .map(|o| {
                    let (shape, pts, kind) = match o {
                        Overlay::Polygon(p, k) => ("polygon", p, *k),
                        Overlay::Polyline(p, k) => ("polyline", p, *k),
                    };
                    OverlayMsg {
                        shape: shape.into(),
                        kind: name(kind).into(),
                        points: pts.iter().map(|&p| p.into()).collect(),
                    }
                })
                .collect(),
        }
    }

    /// Rebuilds the overlays; the error names the entry that does not fit.
    pub fn to_overlays(&self) -> Result<Vec<Overlay>, String> {
        self.overlays
            .iter()
            .enumerate()
            .map(|(i, o)| {
                let kind = OVERLAY_KINDS
                    .iter()
                    .find(|(_, n)| *n == o.kind)
                    .map(|(k, _)| *k)
                    .ok_or_else(|| format!("field `overlays[{i}].kind`: unknown kind `{}`", o.kind))?;
                let pts: Vec<Point2> = o.points.iter().map(|&p| p.into()).collect();
                match o.shape.as_str() {
                    "polygon" => Ok(Overlay::Polygon(pts, kind)),
                    "polyline" => Ok(Overlay::Polyline(pts, kind)),
                    other => Err(format!("field `overlays[{i}].shape`: unknown shape `{other}`")),
                }
            })
            .collect()
    }

    /// The JSON Schema.
    pub fn schema() -> Value {
        message(
            "rovernav.Overlays",
            "The navigator's drawings (C-obstacles, wedges, subpaths) at the end of the run, world frame",
            &[
                ("sim_time_s", number("simulated time (s)")),
                (
                    "overlays",
                    array(
                        "drawings",
                        object(
                            "one drawing",
                            &[
                                (
                                    "shape",
                                    enumeration("closed polygon or open polyline", &["polygon", "polyline"]),
                                ),
                                ("kind", enumeration("what it shows", &OVERLAY_KINDS.map(|(_, n)| n))),
                                ("points", points_schema("vertices")),
                            ],
                        ),
                    ),
                ),
            ],
        )
    }
}

/// The JSON Schema of `/executive/report` (the `report.json` contract of DESIGN.md). Fields may
/// be added to the report, so unlike the other schemas this one allows more properties.
pub fn report_schema() -> Value {
    let stage = |d: &str| number(d);
    let mut schema = message(
        "rovernav.Report",
        "The run's report.json",
        &[
            (
                "outcome",
                enumeration(
                    "how the run ended",
                    &["reached", "unreachable", "help_requested", "aborted", "timeout"],
                ),
            ),
            ("message", string("why the run ended")),
            ("goal_error_m", number("true final position to goal (m)")),
            ("distance_driven_m", number("true path length driven (m)")),
            ("optimal_length_m", nullable(number("shortest safe path with full knowledge (m)"))),
            ("hazard_contacts", integer("times the true rover entered a hazard")),
            ("sim_time_s", number("simulated mission time (s)")),
            ("wall_time_s", number("wall-clock time of the run (s)")),
            ("cycles", integer("navigator cycles")),
            ("sensing_actions", integer("range images taken")),
            ("localization_error_m", number("final |estimate - truth| in the plane (m)")),
            ("navigator", string("navigator registry name")),
            ("localizer", string("localiser registry name")),
            ("seed", integer("seed")),
            ("mission", string("mission name")),
            ("straight_line_m", number("start to goal (m)")),
            (
                "hazard_events",
                array(
                    "hazard contacts",
                    object(
                        "hazard contact",
                        &[
                            ("x", number("true east (m)")),
                            ("y", number("true north (m)")),
                            ("cycle", integer("navigator cycle")),
                            ("cause", string("the simulator's description")),
                        ],
                    ),
                ),
            ),
            (
                "compute_per_cycle",
                object(
                    "mean wall-clock seconds per cycle by stage",
                    &[
                        ("navigation_s", stage("navigator step (s)")),
                        ("localization_s", stage("localiser update (s)")),
                        ("platform_s", stage("platform execute (s)")),
                    ],
                ),
            ),
            (
                "localization_stats",
                nullable(object(
                    "the localiser's correction counters",
                    &[
                        ("matches_attempted", integer("terrain matches tried")),
                        ("fixes_used", integer("fixes fused into the estimate")),
                        ("fixes_rejected", integer("fixes rejected or matches failed")),
                        ("rejected_uncertain", integer("rejected as uncertain")),
                        ("rejected_on_edge", integer("rejected on the search window's edge")),
                        ("zero_velocity_updates", integer("gyro samples used by zero-velocity updates")),
                        ("slip_corrections", integer("odometry steps with slip corrected")),
                    ],
                )),
            ),
        ],
    );
    schema["additionalProperties"] = Value::Bool(true);
    schema
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::schema::check;

    /// JSON text round trip, as the log does it.
    pub(super) fn through_json<T: Serialize + serde::de::DeserializeOwned>(v: &T, schema: &Value) -> T {
        let text = serde_json::to_string(v).unwrap();
        check(schema, &serde_json::from_str::<Value>(&text).unwrap()).unwrap();
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
        }
    }

    #[test]
    fn sensor_frame_round_trips_and_fits_its_schema() {
        let frame = sample_frame();
        let back =
            through_json(&SensorFrameMsg::of(4, &frame), &SensorFrameMsg::schema()).to_frame().unwrap();
        assert!(back.imu[1].compass_yaw.is_nan(), "a faulty compass stays faulty");
        let mut expected = frame.clone();
        expected.imu[1].compass_yaw = 0.0;
        let mut got = back;
        got.imu[1].compass_yaw = 0.0;
        assert_eq!(got, expected);
    }

    #[test]
    fn a_cloud_whose_byte_count_disagrees_with_its_point_count_is_an_error() {
        let mut msg = SensorFrameMsg::of(1, &sample_frame());
        msg.clouds[0].point_count += 1;
        assert!(msg.to_frame().unwrap_err().contains("clouds[0].points_xyz_f32le"));
        let mut msg = SensorFrameMsg::of(1, &sample_frame());
        msg.clouds[2].camera = "periscope".into();
        assert!(msg.to_frame().unwrap_err().contains("unknown camera `periscope`"));
    }

    #[test]
    fn every_command_round_trips_and_fits_its_schema() {
        let commands = [
            NavCommand::Sense(vec![
                SenseRequest::Mast { pan: 0.25 },
                SenseRequest::MastFine { pan: 3.0 },
                SenseRequest::BodyFront,
                SenseRequest::BodyRear,
                SenseRequest::Lidar { pan: -0.5 },
                SenseRequest::Navcam { pan: 0.25, tilt: 0.75 },
            ]),
            NavCommand::Drive {
                distance: -0.3,
                curvature: 0.7,
                guard: DriveGuard { proximity: true, max_tilt: Some(0.2) },
            },
            NavCommand::Drive { distance: 1.0, curvature: 0.0, guard: DriveGuard::default() },
            NavCommand::Turn { angle: -1.25 },
            NavCommand::Finish(Outcome::HelpRequested, "stuck".into()),
        ];
        for c in commands {
            let back = through_json(&CommandMsg::of(3, 9.0, &c), &CommandMsg::schema()).to_command().unwrap();
            assert_eq!(back, c);
        }
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
        let back =
            through_json(&OverlaysMsg::of(5.0, &overlays), &OverlaysMsg::schema()).to_overlays().unwrap();
        assert_eq!(back, overlays);
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
        assert_eq!(through_json(&SettingsMsg::of(&s), &SettingsMsg::schema()).to_settings(), s);
        let report = rovernav_executive::Report {
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
        assert_eq!(through_json(&report, &report_schema()), report);
        let with_stats = rovernav_executive::Report {
            localization_stats: Some(rovernav_executive::LocalizationStats {
                matches_attempted: 7,
                fixes_used: 5,
                fixes_rejected: 2,
                rejected_on_edge: 1,
                ..Default::default()
            }),
            ..report
        };
        assert_eq!(through_json(&with_stats, &report_schema()), with_stats);
    }
}
