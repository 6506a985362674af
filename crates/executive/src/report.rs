//! `report.json`: the run summary other tools read (contract in DESIGN.md; fields only added).

use serde::{Deserialize, Serialize};

/// The report's message: the navigator's words, and for a reached goal the true error the
/// simulator measured beside the estimate's (navigators judge arrival on their estimate).
pub fn run_message(outcome: rovernav_core::Outcome, navigator_message: &str, goal_error_m: f64) -> String {
    if outcome == rovernav_core::Outcome::Reached {
        format!("{navigator_message}; true error {goal_error_m:.2} m")
    } else {
        navigator_message.to_string()
    }
}

impl Report {
    /// The report with the route's figures: of `waypoints + 1` route points, how many the
    /// route's drive tasks (the plan's first `drive_to` tasks) reached; and the peak resident
    /// memory when `measure_memory`.
    pub fn with_route_and_memory(mut self, waypoints: usize, measure_memory: bool) -> Self {
        let total = waypoints + 1;
        let drives = self.tasks.iter().filter(|t| t.kind == "drive_to").take(total);
        self.waypoints_reached = drives.filter(|t| t.state == "success").count() as u32;
        self.waypoints_total = total as u32;
        self.peak_rss_mb = if measure_memory { peak_rss_mb() } else { None };
        self
    }
}

/// The process's peak resident set size (MB) from `/proc/self/status` (VmHWM), to 0.1 MB;
/// None where that file is missing.
pub fn peak_rss_mb() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.trim_start_matches("VmHWM:").trim().trim_end_matches("kB").trim().parse().ok()?;
    Some((kb / 1024.0 * 10.0).round() / 10.0)
}

/// The outcome and figures of one traverse.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
pub struct Report {
    /// `reached` | `unreachable` | `help_requested` | `aborted` | `timeout`.
    pub outcome: String,
    /// Why the run ended, in words.
    pub message: String,
    /// True final position to goal (m).
    pub goal_error_m: f64,
    /// True path length driven (m).
    pub distance_driven_m: f64,
    /// Shortest safe path with full knowledge of the terrain (m); null when none exists.
    pub optimal_length_m: Option<f64>,
    /// Times the true rover entered a hazard.
    pub hazard_contacts: u32,
    /// Simulated mission time (s).
    pub sim_time_s: f64,
    /// Wall-clock time of the run (s).
    pub wall_time_s: f64,
    /// Navigator cycles (commands issued).
    pub cycles: u64,
    /// Range images taken.
    pub sensing_actions: u64,
    /// Final |estimate - truth| in the plane (m).
    pub localization_error_m: f64,
    /// Navigator registry name.
    pub navigator: String,
    /// Localiser registry name.
    pub localizer: String,
    /// Seed of the run.
    pub seed: u64,
    /// Mission name.
    pub mission: String,
    /// Straight-line distance from start to goal (m).
    pub straight_line_m: f64,
    /// Where and why the true rover met a hazard.
    pub hazard_events: Vec<HazardEvent>,
    /// Wall-clock compute per navigator cycle, by stage.
    #[serde(default)]
    pub compute_per_cycle: StageTimes,
    /// Every component's JAUS state at the end of the run, in stepping order.
    #[serde(default)]
    pub components: Vec<ComponentReport>,
    /// The fault that made fault protection stop the rover, if one did.
    #[serde(default)]
    pub fault: Option<FaultReport>,
    /// The mission plan's tasks and how each ended.
    #[serde(default)]
    pub tasks: Vec<TaskReport>,
    /// Faults injected by the mission's `[[faults]]` (drills), in order.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub injected_faults: Vec<InjectedFaultReport>,
    /// The localiser's correction counters (null when unknown, e.g. recomputed from a cut-off log).
    #[serde(default)]
    pub localization_stats: Option<LocalizationStats>,
    /// Waypoints and goal the rover reached (by its own judgement: the route's drive tasks that
    /// succeeded).
    #[serde(default)]
    pub waypoints_reached: u32,
    /// Waypoints plus the goal.
    #[serde(default)]
    pub waypoints_total: u32,
    /// Peak resident memory of the process at the end of the run (MB, VmHWM); null when not
    /// measured (runs inside tests) or unknown.
    #[serde(default)]
    pub peak_rss_mb: Option<f64>,
    /// The battery and the rover's sleep (absent without power readings).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub power: Option<crate::power::PowerReport>,
    /// The navigator run in shadow beside the driving one (`shadow_navigator`), if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shadow: Option<crate::shadow::ShadowReport>,
}

/// The localiser's counters: terrain-matching fixes used and rejected, zero-velocity updates, slip
/// corrections (issue 5: a failed or uncertain match is reported, not used).
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
pub struct LocalizationStats {
    /// Terrain matches tried.
    pub matches_attempted: u64,
    /// Fixes fused into the estimate.
    pub fixes_used: u64,
    /// Fixes rejected or matches that failed.
    pub fixes_rejected: u64,
    /// Of the rejected, those judged uncertain (failure probability or wide covariance).
    pub rejected_uncertain: u64,
    /// Of the rejected, those whose best pose lay on the search window's edge.
    pub rejected_on_edge: u64,
    /// Gyro samples used by zero-velocity (bias) updates.
    pub zero_velocity_updates: u64,
    /// Odometry steps with wheel slip detected and corrected.
    pub slip_corrections: u64,
}

impl From<rovernav_core::LocalizerStats> for LocalizationStats {
    fn from(s: rovernav_core::LocalizerStats) -> Self {
        Self {
            matches_attempted: s.matches_attempted,
            fixes_used: s.fixes_used,
            fixes_rejected: s.fixes_rejected,
            rejected_uncertain: s.rejected_uncertain,
            rejected_on_edge: s.rejected_on_edge,
            zero_velocity_updates: s.zero_velocity_updates,
            slip_corrections: s.slip_corrections,
        }
    }
}

/// A component's final state.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
pub struct ComponentReport {
    /// Component name.
    pub name: String,
    /// JAUS state (`Ready`, `Standby`, `Emergency`, `Failure`...).
    pub state: String,
    /// Why it last changed state (the fault, for `Failure`).
    pub message: String,
}

/// The fault that stopped the mission.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
pub struct FaultReport {
    /// `sensor_fault` | `stuck_wheel` | `localization_failure` | `no_progress` | `hazard_contact` |
    /// `component_failure`.
    pub kind: String,
    /// The component that reported it, if one did.
    pub component: Option<String>,
    /// What was seen.
    pub message: String,
    /// Commands executed when fault protection acted.
    pub cycle: u64,
    /// Simulated time when fault protection acted (s).
    pub time_s: f64,
}

/// A fault the mission injected, and what the true rover did after it.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
pub struct InjectedFaultReport {
    /// The mission file's kind (`silent_sensor`, `nan_range`, `stalled_wheel`, `compass_nan`,
    /// `gyro_bias_jump`, `component_crash`).
    pub kind: String,
    /// The crashed component, for `component_crash`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub component: Option<String>,
    /// Simulated time of the injection (s).
    pub time_s: f64,
    /// Hazard contacts of the true rover after the injection.
    pub hazard_contacts_after: u32,
}

/// One task of the mission plan.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
pub struct TaskReport {
    /// Plan id.
    pub id: u64,
    /// `drive_to` | `panorama` | `science_image` | `place_instrument` | `scoop`.
    pub kind: String,
    /// Target [x, y] (m), if the task has one.
    pub target: Option<[f64; 2]>,
    /// `pending` | `in_process` | `success` | `failure` | `aborted` | `cancelled`.
    pub state: String,
    /// The last word on it.
    pub message: String,
    /// For `place_instrument`: what AutoPlace decided (absent for other tasks).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub placement: Option<PlacementReport>,
}

/// What AutoPlace decided for a `place_instrument` task.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
pub struct PlacementReport {
    /// `placed` | `refused`.
    pub outcome: String,
    /// Why refused: `no_data` | `normal` | `roughness` | `reach` | `collision`.
    pub reason: Option<String>,
    /// Angle between the approach and the sensed surface normal (deg), if placed.
    pub contact_angle_deg: Option<f64>,
    /// The chosen target (world frame by the pose estimate, m), if placed.
    pub target: Option<[f64; 3]>,
    /// Its sensed surface normal (world frame), if placed.
    pub normal: Option<[f64; 3]>,
    /// Candidate targets examined.
    pub examined: usize,
}

/// Mean wall-clock seconds per cycle spent in each stage of the loop.
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
pub struct StageTimes {
    /// The navigator's step: perception, mapping and planning (s per cycle).
    pub navigation_s: f64,
    /// The localiser's update (s per cycle).
    pub localization_s: f64,
    /// The platform (simulator) executing the command and sensing (s per cycle).
    pub platform_s: f64,
}

/// One hazard contact of the true rover.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
pub struct HazardEvent {
    /// True east (m).
    pub x: f64,
    /// True north (m).
    pub y: f64,
    /// Navigator cycle.
    pub cycle: u64,
    /// The simulator's description.
    pub cause: String,
}
