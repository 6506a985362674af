//! The navigator and localiser interfaces: how an algorithm plugs into the executive loop.
//!
//! The loop is the planetary rover's stop-sense-plan-drive cycle (paper 000 section 2, paper 003
//! section 2): the navigator receives the latest sensing and pose estimate and answers with one
//! command: sense (which wedges), drive an arc, turn in place, or finish with an outcome.

use crate::{Point2, Pose3, SensorFrame};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// How a traverse ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// The rover believes it is at the goal.
    Reached,
    /// The navigator proved the goal cannot be reached.
    Unreachable,
    /// The navigator stopped and asked the operators for help.
    HelpRequested,
    /// Stopped by the executive or fault protection.
    Aborted,
    /// The time or step budget ran out.
    Timeout,
}

impl Outcome {
    /// The stable name used in `report.json`.
    pub fn as_str(self) -> &'static str {
        match self {
            Outcome::Reached => "reached",
            Outcome::Unreachable => "unreachable",
            Outcome::HelpRequested => "help_requested",
            Outcome::Aborted => "aborted",
            Outcome::Timeout => "timeout",
        }
    }
    /// Parses the stable name.
    pub fn parse(s: &str) -> Option<Self> {
        [Self::Reached, Self::Unreachable, Self::HelpRequested, Self::Aborted, Self::Timeout]
            .into_iter()
            .find(|o| o.as_str() == s)
    }
}

/// The goal of a traverse.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct Goal {
    /// Goal position (world frame, m).
    pub position: Point2,
    /// Distance within which the goal counts as reached (m).
    pub tolerance: f64,
    /// Intermediate waypoints to visit in order before the goal.
    pub waypoints: Vec<Point2>,
    /// Keep-out polygons (world frame) the rover must not enter.
    pub keep_out: Vec<Vec<Point2>>,
}

/// The autonomy's belief about the rover pose.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct PoseEstimate {
    /// Estimated pose.
    pub pose: Pose3,
    /// Covariance of (x, y, yaw); a non-finite entry travels as `null` and reads back as NaN.
    #[serde(deserialize_with = "crate::wire::nan_from_null_matrix")]
    #[schemars(with = "[[Option<f64>; 3]; 3]")]
    pub covariance: [[f64; 3]; 3],
}

/// A request for range data.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum SenseRequest {
    /// Point the mast stereo pair at a body-frame pan angle (rad) and image one wedge.
    Mast {
        /// Pan angle, counter-clockwise from forward (rad).
        pan: f64,
    },
    /// Point the mast stereo pair at a body-frame pan angle (rad) and image one wedge at the
    /// cameras' full resolution: the terrain-matching image, denser and slower than the
    /// navigation image [`SenseRequest::Mast`] takes.
    MastFine {
        /// Pan angle, counter-clockwise from forward (rad).
        pan: f64,
    },
    /// Image with the forward body stereo pair.
    BodyFront,
    /// Image with the rear body stereo pair.
    BodyRear,
    /// One nodding-LIDAR sweep at a body-frame pan angle (rad).
    Lidar {
        /// Pan angle (rad).
        pan: f64,
    },
    /// Both Navcam images (left and right, a rectified pair) with the mast head at a body-frame
    /// pan and tilt: pictures for target tracking, science and the operator, no range.
    Navcam {
        /// Pan angle, counter-clockwise from forward (rad).
        pan: f64,
        /// Tilt angle, positive up (rad).
        tilt: f64,
    },
    /// Both images of a body (Hazcam) stereo pair, a rectified pair: pictures for the tooling
    /// arm's terrain model (AutoPlace), no range.
    BodyPair {
        /// The front pair (else the rear).
        front: bool,
    },
}

/// Conditions that stop a motion early, as a real rover's guarded moves do.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct DriveGuard {
    /// Stop when any proximity sensor triggers.
    pub proximity: bool,
    /// Stop when the inclinometer tilt exceeds this (rad).
    pub max_tilt: Option<f64>,
}

/// One command from a navigator to the platform.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum NavCommand {
    /// Acquire range data.
    Sense(Vec<SenseRequest>),
    /// Drive along an arc: signed distance (m, negative backs up) at constant curvature (1/m,
    /// positive turns left).
    Drive {
        /// Signed arc length (m).
        distance: f64,
        /// Curvature (1/m).
        curvature: f64,
        /// Early-stop conditions.
        guard: DriveGuard,
    },
    /// Turn in place by a signed angle (rad, positive counter-clockwise).
    Turn {
        /// Signed angle (rad).
        angle: f64,
    },
    /// The navigator is done.
    Finish(Outcome, String),
}

/// What the navigator sees at each step.
#[derive(Clone, Debug)]
pub struct NavInput<'a> {
    /// Mission time (s).
    pub time: f64,
    /// Current pose estimate.
    pub estimate: PoseEstimate,
    /// The goal and constraints.
    pub goal: &'a Goal,
    /// What the platform reported for the previous command.
    pub frame: &'a SensorFrame,
    /// The body-frame mast pan (rad) whose view the localiser predicts will localise the rover
    /// best from here ([`Localizer::localization_target`]); `None` if it does not match terrain.
    pub localization_target: Option<f64>,
}

/// A drawing primitive a navigator exposes for the traverse picture.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Overlay {
    /// A closed polygon (e.g. a C-obstacle), world frame.
    Polygon(Vec<Point2>, OverlayKind),
    /// An open polyline (e.g. a planned subpath), world frame.
    Polyline(Vec<Point2>, OverlayKind),
}

/// What an overlay shows, to choose its colour.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum OverlayKind {
    /// A planned path.
    Plan,
    /// An obstacle grown by the rover size.
    CObstacle,
    /// A sensed wedge.
    Wedge,
    /// Anything else.
    Other,
}

/// Counters a navigator keeps for the report.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NavigatorStats {
    /// Range images (wedges) requested.
    pub sensing_actions: u64,
    /// Plans computed.
    pub plans: u64,
}

/// A navigation algorithm, chosen by name in the mission file.
pub trait Navigator: Send {
    /// Registry name (e.g. "astar-grid").
    fn name(&self) -> &str;
    /// Decides the next command.
    fn step(&mut self, input: &NavInput<'_>) -> NavCommand;
    /// The path the navigator currently intends to follow (world frame), for display.
    fn planned_path(&self) -> Vec<Point2> {
        Vec::new()
    }
    /// Extra drawings for the traverse picture.
    fn overlays(&self) -> Vec<Overlay> {
        Vec::new()
    }
    /// Counters for the report.
    fn stats(&self) -> NavigatorStats;
}

/// Counters a localiser keeps about its corrections, for the report (all zero for a localiser
/// that makes none, e.g. dead reckoning).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LocalizerStats {
    /// Terrain matches tried.
    pub matches_attempted: u64,
    /// Fixes fused into the estimate.
    pub fixes_used: u64,
    /// Fixes rejected or matches that failed (reported, not used).
    pub fixes_rejected: u64,
    /// Of the rejected fixes, those judged uncertain (failure probability or wide covariance).
    pub rejected_uncertain: u64,
    /// Of the rejected fixes, those whose best pose lay on the search window's edge.
    pub rejected_on_edge: u64,
    /// Gyro samples used by zero-velocity (bias) updates.
    pub zero_velocity_updates: u64,
    /// Odometry steps in which wheel slip was detected and corrected.
    pub slip_corrections: u64,
}

/// A pose estimator fed by proprioceptive sensors and optional absolute fixes.
pub trait Localizer: Send {
    /// Registry name.
    fn name(&self) -> &str;
    /// Sets the pose (an authoritative external fix, e.g. from the operators).
    fn reset(&mut self, pose: Pose3);
    /// Integrates the proprioceptive samples of one command.
    fn update(&mut self, frame: &SensorFrame);
    /// The current estimate.
    fn estimate(&self) -> PoseEstimate;
    /// Counters for the report.
    fn stats(&self) -> LocalizerStats {
        LocalizerStats::default()
    }
    /// The body-frame mast pan (rad) whose view is predicted, from the localiser's own map, to
    /// localise the rover best from the current estimate (paper 000 section 4.4); `None` for a
    /// localiser that does not match terrain, or before it has a map there.
    fn localization_target(&self) -> Option<f64> {
        None
    }
}
