//! The straight-line navigator: an example of adding a navigator from outside the navigation
//! crate. It turns toward the next waypoint (then the goal) and drives straight at it in
//! steps, never sensing and never swerving: the baseline a navigator that looks must beat (its
//! hazard contacts are what sensing buys). Only too much tilt stops a step early.
//!
//! Registering it is one line: `Registry::builtin().with(ENTRY)` installed with
//! `rovernav_navigation::registry::install` before the first run.

use rovernav_core::{
    DriveGuard, NavCommand, NavInput, Navigator, NavigatorStats, Outcome, Point2, angle_diff,
};
use rovernav_navigation::params::{Field, Param, Unit};
use rovernav_navigation::registry::{NavigatorEntry, param_info};

/// Registry entry of the straight-line navigator.
pub const ENTRY: NavigatorEntry = NavigatorEntry {
    name: "straight-line",
    doc: "turn to the goal and drive straight at it, never sensing (example baseline)",
    global_planners: &[],
    params: || param_info(StraightLineConfig::default(), StraightLineConfig::params()),
    build: |b| {
        Ok(Box::new(StraightLine::new(
            b.configured(StraightLineConfig::default(), &StraightLineConfig::params())?,
        )))
    },
};

/// Settings of the straight-line navigator.
#[derive(Clone, Debug)]
pub struct StraightLineConfig {
    /// Longest drive between checks (m).
    pub step: f64,
    /// Heading error above which the rover turns in place first (rad).
    pub turn_threshold: f64,
    /// Drive steps before giving up.
    pub max_steps: u32,
}

impl Default for StraightLineConfig {
    fn default() -> Self {
        Self { step: 1.0, turn_threshold: 10f64.to_radians(), max_steps: 200 }
    }
}

impl StraightLineConfig {
    /// The parameters a mission file may set (`[navigator_params]`).
    pub fn params() -> Vec<Param<Self>> {
        vec![
            Param {
                name: "step_m",
                doc: "longest drive between checks",
                unit: Unit::PositiveMetres,
                field: |c| Field::Real(&mut c.step),
            },
            Param {
                name: "turn_threshold_deg",
                doc: "heading error above which the rover turns in place first",
                unit: Unit::Degrees,
                field: |c| Field::Real(&mut c.turn_threshold),
            },
            Param {
                name: "max_steps",
                doc: "drive steps before giving up",
                unit: Unit::Count,
                field: |c| Field::U32(&mut c.max_steps),
            },
        ]
    }
}

/// The straight-line navigator.
pub struct StraightLine {
    config: StraightLineConfig,
    /// Waypoints reached so far.
    reached: usize,
    steps: u32,
    path: Vec<Point2>,
}

impl StraightLine {
    /// A navigator with these settings.
    pub fn new(config: StraightLineConfig) -> Self {
        Self { config, reached: 0, steps: 0, path: Vec::new() }
    }
}

impl Navigator for StraightLine {
    fn name(&self) -> &str {
        ENTRY.name
    }

    fn step(&mut self, input: &NavInput<'_>) -> NavCommand {
        let pose = input.estimate.pose;
        let here = Point2::new(pose.x, pose.y);
        let goal = input.goal;
        while let Some(w) = goal.waypoints.get(self.reached) {
            if here.dist(*w) > goal.tolerance {
                break;
            }
            self.reached += 1;
        }
        let target = goal.waypoints.get(self.reached).copied().unwrap_or(goal.position);
        self.path = vec![here, target];
        let distance = here.dist(target);
        if self.reached == goal.waypoints.len() && distance <= goal.tolerance {
            return NavCommand::Finish(Outcome::Reached, "at the goal".into());
        }
        if self.steps >= self.config.max_steps {
            return NavCommand::Finish(Outcome::Timeout, "step budget spent".into());
        }
        let error = angle_diff((target.y - pose.y).atan2(target.x - pose.x), pose.yaw);
        if error.abs() > self.config.turn_threshold {
            return NavCommand::Turn { angle: error };
        }
        self.steps += 1;
        let guard = DriveGuard { proximity: false, max_tilt: Some(20f64.to_radians()) };
        NavCommand::Drive { distance: distance.min(self.config.step), curvature: 0.0, guard }
    }

    fn planned_path(&self) -> Vec<Point2> {
        self.path.clone()
    }

    fn stats(&self) -> NavigatorStats {
        NavigatorStats::default()
    }
}
