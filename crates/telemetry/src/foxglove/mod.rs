//! Foxglove's well-known message schemas, so that Foxglove (and Lichtblick) show a run natively:
//! the rover's frames in the 3D panel, the belief map as a grid, the navigator's drawings as a
//! scene, the log in the Log panel and camera images in the Image panel.
//!
//! The types follow Foxglove's published schemas (<https://docs.foxglove.dev/docs/visualization/
//! message-schemas/>, JSON encoding): the field names, the `{sec, nsec}` times, integer enums
//! and base64 `bytes` are theirs; the JSON Schemas are derived from these types and named as
//! Foxglove names them (`foxglove.FrameTransform`), which is what Foxglove matches a channel on.
//! Only the fields rovernav fills are declared; Foxglove treats a missing field as its default.
//!
//! Frames: `map` is the world frame (x east, y north, z up); `rover` is the pose estimate (what
//! the autonomy believes) and `rover_truth` the simulator's true pose, on a topic of its own
//! marked as simulation truth.

use rovernav_bus::schema::titled_schema_of;
use rovernav_core::Pose3;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use serde_json::Value;

pub mod grid;
pub mod image;
pub mod publisher;
pub mod scene;

pub use grid::{BeliefMap, GridMsg, PackedElementField};
pub use image::CompressedImageMsg;
pub use publisher::FoxglovePublisher;
pub use scene::{ColorMsg, LinePrimitive, SceneEntity, SceneEntityDeletion, SceneUpdateMsg};

/// The Foxglove topics of a run, with their schema names.
pub mod topics {
    /// The world frame every other frame hangs from.
    pub const MAP_FRAME: &str = "map";
    /// The estimated rover frame.
    pub const ROVER_FRAME: &str = "rover";
    /// The true rover frame (simulation truth).
    pub const TRUTH_FRAME: &str = "rover_truth";
    /// `foxglove.FrameTransform`: `map` -> `rover` after every cycle (the pose estimate).
    pub const TF: &str = "/tf";
    /// `foxglove.FrameTransform`: `map` -> `rover_truth` after every cycle (simulation truth).
    pub const TRUTH_TF: &str = "/sim/tf";
    /// `foxglove.Grid`: the belief map (elevation) whenever new range data changed it.
    pub const BELIEF_GRID: &str = "/map/belief";
    /// `foxglove.Grid`: traversability and goodness whenever new range data changed them.
    pub const TRAVERSABILITY_GRID: &str = "/map/traversability";
    /// `foxglove.SceneUpdate`: the rover body, the plan, the sensed wedges and the navigator's
    /// drawings (C-obstacles, arcs, subpaths), every cycle (unchanged entities are not resent).
    pub const SCENE: &str = "/navigation/scene";
    /// `foxglove.SceneUpdate`: the true rover body, rocks, goal and hazard contacts (truth).
    pub const TRUTH_SCENE: &str = "/sim/scene";
    /// `foxglove.Log`: one line per command, operator lines and answers, component and task
    /// states, the outcome.
    pub const LOG: &str = "/log";
    /// Schema name of [`TF`] and [`TRUTH_TF`].
    pub const FRAME_TRANSFORM: &str = "foxglove.FrameTransform";
    /// Schema name of the grids.
    pub const GRID: &str = "foxglove.Grid";
    /// Schema name of the scenes.
    pub const SCENE_UPDATE: &str = "foxglove.SceneUpdate";
    /// Schema name of [`LOG`].
    pub const LOG_SCHEMA: &str = "foxglove.Log";
    /// Schema name of camera images.
    pub const COMPRESSED_IMAGE: &str = "foxglove.CompressedImage";
}

/// Every Foxglove topic a run logs (camera topics aside): topic, schema name, derived schema,
/// whether it carries simulation truth.
pub fn foxglove_topic_table() -> Vec<(&'static str, &'static str, Value, bool)> {
    use topics::*;
    let tf = titled_schema_of::<FrameTransformMsg>(FRAME_TRANSFORM);
    let grid = titled_schema_of::<GridMsg>(GRID);
    let scene = titled_schema_of::<SceneUpdateMsg>(SCENE_UPDATE);
    vec![
        (TF, FRAME_TRANSFORM, tf.clone(), false),
        (TRUTH_TF, FRAME_TRANSFORM, tf, true),
        (BELIEF_GRID, GRID, grid.clone(), false),
        (TRAVERSABILITY_GRID, GRID, grid, false),
        (SCENE, SCENE_UPDATE, scene.clone(), false),
        (TRUTH_SCENE, SCENE_UPDATE, scene, true),
        (LOG, LOG_SCHEMA, titled_schema_of::<LogMsg>(LOG_SCHEMA), false),
    ]
}

/// `time`: seconds and nanoseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
pub struct TimeMsg {
    /// Whole seconds.
    pub sec: u32,
    /// Nanoseconds within the second.
    pub nsec: u32,
}

impl TimeMsg {
    /// A simulated time (s); negative or non-finite times are 0.
    pub fn of_seconds(t: f64) -> Self {
        let t = if t.is_finite() { t.clamp(0.0, f64::from(u32::MAX)) } else { 0.0 };
        let sec = t.floor();
        Self { sec: sec as u32, nsec: (((t - sec) * 1e9) as u32).min(999_999_999) }
    }

    /// A log time in nanoseconds.
    pub fn of_nanos(ns: u64) -> Self {
        Self { sec: (ns / 1_000_000_000).min(u64::from(u32::MAX)) as u32, nsec: (ns % 1_000_000_000) as u32 }
    }
}

/// `foxglove.Vector3` (also used for sizes).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct Vector3 {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
}

/// `foxglove.Quaternion`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct Quaternion {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
    /// w.
    pub w: f64,
}

impl Default for Quaternion {
    fn default() -> Self {
        Self { x: 0.0, y: 0.0, z: 0.0, w: 1.0 }
    }
}

impl Quaternion {
    /// The rotation of roll, pitch and yaw (rad) applied as z-y-x (REP 103), the rotation
    /// `Pose3::rotation` builds.
    pub fn of_rpy(roll: f64, pitch: f64, yaw: f64) -> Self {
        let (sr, cr) = (roll / 2.0).sin_cos();
        let (sp, cp) = (pitch / 2.0).sin_cos();
        let (sy, cy) = (yaw / 2.0).sin_cos();
        Self {
            w: cr * cp * cy + sr * sp * sy,
            x: sr * cp * cy - cr * sp * sy,
            y: cr * sp * cy + sr * cp * sy,
            z: cr * cp * sy - sr * sp * cy,
        }
    }

    /// A rotation about z by `yaw` (rad).
    pub fn of_yaw(yaw: f64) -> Self {
        Self::of_rpy(0.0, 0.0, yaw)
    }
}

/// `foxglove.Pose`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct PoseMsg {
    /// Position.
    pub position: Vector3,
    /// Orientation.
    pub orientation: Quaternion,
}

impl PoseMsg {
    /// A position with no rotation.
    pub fn at(x: f64, y: f64, z: f64) -> Self {
        Self { position: Vector3 { x, y, z }, orientation: Quaternion::default() }
    }
}

/// `foxglove.FrameTransform`: where `child_frame_id` is in `parent_frame_id`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct FrameTransformMsg {
    /// Time of the transform.
    pub timestamp: TimeMsg,
    /// Parent frame.
    pub parent_frame_id: String,
    /// Child frame.
    pub child_frame_id: String,
    /// Translation of the child in the parent.
    pub translation: Vector3,
    /// Rotation of the child in the parent.
    pub rotation: Quaternion,
}

impl FrameTransformMsg {
    /// The transform `map` -> `child` of a rover pose; non-finite components become 0 (JSON
    /// has no NaN, and Foxglove would drop the frame).
    pub fn of_pose(t: f64, child: &str, pose: &Pose3) -> Self {
        let f = |v: f64| if v.is_finite() { v } else { 0.0 };
        Self {
            timestamp: TimeMsg::of_seconds(t),
            parent_frame_id: topics::MAP_FRAME.into(),
            child_frame_id: child.into(),
            translation: Vector3 { x: f(pose.x), y: f(pose.y), z: f(pose.z) },
            rotation: Quaternion::of_rpy(f(pose.roll), f(pose.pitch), f(pose.yaw)),
        }
    }
}

/// `foxglove.Log` levels.
pub mod level {
    /// Debug.
    pub const DEBUG: u8 = 1;
    /// Info.
    pub const INFO: u8 = 2;
    /// Warning.
    pub const WARNING: u8 = 3;
    /// Error.
    pub const ERROR: u8 = 4;
}

/// `foxglove.Log`: one log line.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct LogMsg {
    /// Time (simulated).
    pub timestamp: TimeMsg,
    /// Level: 1 debug, 2 info, 3 warning, 4 error (Foxglove's `LogLevel`).
    pub level: u8,
    /// The line.
    pub message: String,
    /// Who says it (a component, `executive`, `operator`).
    pub name: String,
    /// Source file (empty: not from a source line).
    pub file: String,
    /// Source line (0).
    pub line: u32,
}

impl LogMsg {
    /// A line from `name` at simulated time `t`.
    pub fn new(t: f64, level: u8, name: &str, message: String) -> Self {
        Self {
            timestamp: TimeMsg::of_seconds(t),
            level,
            message,
            name: name.into(),
            file: String::new(),
            line: 0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rovernav_bus::schema::check;

    #[test]
    fn the_quaternion_rotates_as_the_pose_rotation_matrix() {
        // Independent truth: the pose's own rotation matrix (core geometry).
        let pose = Pose3 { x: 0.0, y: 0.0, z: 0.0, roll: 0.3, pitch: -0.2, yaw: 2.5 };
        let q = Quaternion::of_rpy(pose.roll, pose.pitch, pose.yaw);
        let r = pose.rotation();
        let (w, x, y, z) = (q.w, q.x, q.y, q.z);
        let from_q = [
            [1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - w * z), 2.0 * (x * z + w * y)],
            [2.0 * (x * y + w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - w * x)],
            [2.0 * (x * z - w * y), 2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y)],
        ];
        for i in 0..3 {
            for j in 0..3 {
                assert!((from_q[i][j] - r[i][j]).abs() < 1e-12, "{i},{j}: {from_q:?} vs {r:?}");
            }
        }
    }

    #[test]
    fn times_split_into_seconds_and_nanoseconds() {
        assert_eq!(TimeMsg::of_seconds(12.25), TimeMsg { sec: 12, nsec: 250_000_000 });
        assert_eq!(TimeMsg::of_seconds(f64::NAN), TimeMsg::default());
        assert_eq!(TimeMsg::of_seconds(-3.0), TimeMsg::default());
        assert_eq!(TimeMsg::of_nanos(3_000_000_007), TimeMsg { sec: 3, nsec: 7 });
    }

    #[test]
    fn messages_fit_their_schemas_and_carry_foxglove_field_names() {
        let pose = Pose3 { x: 1.0, y: 2.0, z: f64::NAN, roll: 0.0, pitch: 0.0, yaw: 1.0 };
        let tf = serde_json::to_value(FrameTransformMsg::of_pose(3.5, "rover", &pose)).unwrap();
        let table = foxglove_topic_table();
        check(&table[0].2, &tf).unwrap();
        for key in ["timestamp", "parent_frame_id", "child_frame_id", "translation", "rotation"] {
            assert!(tf.get(key).is_some(), "{key}");
        }
        assert_eq!(tf["translation"]["z"], 0.0, "a non-finite height is not sent as null");
        let log = serde_json::to_value(LogMsg::new(1.0, level::INFO, "executive", "hello".into())).unwrap();
        check(&table.iter().find(|r| r.0 == topics::LOG).unwrap().2, &log).unwrap();
        for (topic, name, schema, _) in &table {
            assert_eq!(schema["title"], *name, "{topic}");
            assert!(schema["properties"].as_object().is_some_and(|p| !p.is_empty()), "{topic}");
        }
    }
}
