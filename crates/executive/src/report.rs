//! `report.json`: the run summary other tools read (contract in DESIGN.md; fields only added).

use serde::{Deserialize, Serialize};

/// The outcome and figures of one traverse.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
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
}

/// Mean wall-clock seconds per cycle spent in each stage of the loop.
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct StageTimes {
    /// The navigator's step: perception, mapping and planning (s per cycle).
    pub navigation_s: f64,
    /// The localiser's update (s per cycle).
    pub localization_s: f64,
    /// The platform (simulator) executing the command and sensing (s per cycle).
    pub platform_s: f64,
}

/// One hazard contact of the true rover.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
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
