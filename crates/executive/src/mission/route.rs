//! The mission file's `[start]` pose and `[goal]` (waypoints, keep-out zones).

use serde::Deserialize;

/// A pose in either local or projected coordinates.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PoseSpec {
    /// Local east (m).
    pub x: Option<f64>,
    /// Local north (m).
    pub y: Option<f64>,
    /// Projected easting (m), for DEM missions.
    pub easting: Option<f64>,
    /// Projected northing (m), for DEM missions.
    pub northing: Option<f64>,
    /// Heading, counter-clockwise from east (deg).
    #[serde(default)]
    pub yaw_deg: f64,
}

/// The goal, waypoints and keep-out zones.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct GoalSpec {
    /// Local east (m).
    pub x: Option<f64>,
    /// Local north (m).
    pub y: Option<f64>,
    /// Projected easting (m).
    pub easting: Option<f64>,
    /// Projected northing (m).
    pub northing: Option<f64>,
    /// Arrival tolerance (m).
    #[serde(default = "default_tolerance")]
    pub tolerance_m: f64,
    /// Waypoints to visit first, as [x, y] in the same frame as the goal.
    #[serde(default)]
    pub waypoints: Vec<[f64; 2]>,
    /// Keep-out polygons, each a list of [x, y] vertices in the same frame as the goal.
    #[serde(default)]
    pub keep_out: Vec<Vec<[f64; 2]>>,
}

fn default_tolerance() -> f64 {
    0.5
}
