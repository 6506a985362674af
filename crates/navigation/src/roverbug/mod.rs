//! RoverBug: sensor-based path planning on the local tangent graph (paper 000 section 2,
//! Laubach, Olson, Burdick and Hayati, after the WedgeBug algorithm).
//!
//! The rover keeps no global map: at every sensing position the C-obstacles are rebuilt from the
//! wedges sensed there (step/slope hazards, convex hulls grown by the rover radius plus a safety
//! buffer), and the local tangent graph (LTG) is built inside the visible region. The files
//! follow the paper:
//!
//! | file | what | paper |
//! |---|---|---|
//! | [`ltg`] | the local tangent graph, A* over it, the cut at the wedge radius | section 2 |
//! | [`motion_to_goal`] | motion-to-goal, `d_LEAVE`, the mode dispatch | section 2.1 |
//! | [`boundary_following`] | the blocking obstacle, its silhouette, `d_reach`, `V_loop`, the virtual and normal submodes | section 2.2 |
//! | [`view`] | the view renewed at every step and gaze control | section 2 |
//! | [`execute`] | driving a subpath's waypoints | section 3 |
//! | [`safety`], [`unseen`] | the safety layer and the sensed-ground check | departures |
//! | [`recovery`] | the ordered recovery behaviours replacing the paper's give-ups | departures |
//! | [`config`] | the parameters, grouped, each written once | |
//!
//! Every departure from the paper is named in the module doc of the file that implements it,
//! with its reason and its measured effect; docs/navigators/roverbug.md lists them all with
//! the evidence. Mission keep-out polygons are C-obstacles like sensed ones (their hulls, grown
//! alike).

mod boundary_following;
pub mod config;
mod execute;
mod ltg;
mod motion_to_goal;
mod recovery;
mod safety;
#[cfg(test)]
mod tests;
mod unseen;
mod view;

pub use config::{
    Budgets, PaperParams, RecoveryParams, RoverBugConfig, SafetyParams, c_obstacle_terrain, safety_terrain,
};

use crate::registry::{NavigatorEntry, param_info};
use ltg::{Ltg, Node};
use recovery::Recovered;
use rovernav_core::{
    DriveGuard, Goal, Grid2, NavCommand, NavInput, Navigator, NavigatorStats, Outcome, Overlay, OverlayKind,
    Point2, Pose2, RoverConfig, SenseRequest, angle_diff,
};
use rovernav_perception::{CObstacle, SensedWedge, TerrainConfig, TerrainEvaluator};
use std::collections::VecDeque;

/// Operational mode (paper 000 sections 2.1-2.2).
#[derive(Clone, Debug, PartialEq)]
enum Mode {
    /// Monotonic progress toward the goal.
    MotionToGoal,
    /// Mast scans at `2 k alpha_mast` from the goal direction; `scans` are the k already sensed.
    Virtual { sense: f64, scans: Vec<i32> },
    /// Circumnavigating the obstacle in the positive `sense` (+1 counter-clockwise).
    Normal { sense: f64, d_reach: f64, v_loop: Point2, left_loop: bool, scans: Vec<i32> },
}

/// Everything sensed at the current position (renewed at every step: no global map).
struct View {
    evaluator: TerrainEvaluator,
    wedges: Vec<SensedWedge>,
    origin: Point2,
}

/// The RoverBug navigator (see the module documentation).
pub struct RoverBug {
    rover: RoverConfig,
    config: RoverBugConfig,
    terrain: TerrainConfig,
    mode: Mode,
    d_leave: Option<f64>,
    view: Option<View>,
    obstacles: Vec<CObstacle>,
    carried: Vec<CObstacle>,
    /// C-obstacles around recorded hazard contacts.
    contacts: Vec<CObstacle>,
    /// The pose estimate the current plan starts from (its first leg is checked for safety).
    here: Option<Pose2>,
    /// How many of `obstacles` come from sensing (this view's and the carried ones).
    sensed_len: usize,
    /// Top-height hazard cells in a robot-centred grid kept across steps: the swept body of
    /// every turn and drive is checked against it before the motion is commanded.
    safety: Option<TerrainEvaluator>,
    /// The safety layer's hazard cells that stand out from the ground around them (see
    /// [`RoverBug::confirm_hazards`]).
    safety_hazard: Option<Grid2<bool>>,
    /// Motions refused by the safety check at this place (the count restarts 0.3 m away), and where.
    refusals: (u32, Point2),
    /// Escapes from a boxed-in position, and where the last one started.
    escapes: (u32, Point2),
    /// Looks at ground a drive would cover unseen, at this place (the count restarts 0.3 m
    /// away), and where.
    looks: (u32, Point2),
    /// Where the next step's sensing also looks: the first unseen ground of the drive that
    /// was held back.
    look_at: Option<Point2>,
    /// Sign of the last motion: 1 forward, -1 reverse, 2 turn in place.
    last_motion: Option<f64>,
    /// Where the last forward drive started (estimate).
    drive_from: Option<Point2>,
    /// Positions of the current boundary-following segment.
    visited: Vec<Point2>,
    /// Where boundary following started and escapes started since motion-to-goal last made
    /// progress: unlike `visited` they survive a restart, so boundary following cannot cycle
    /// between the same places.
    been: Vec<Point2>,
    /// Positions the rover has stood at (estimate), oldest first: ground its body has crossed.
    trail: Vec<Point2>,
    /// Where planning found no way on: recorded as small C-obstacles so that no later subpath
    /// leads back into the same dead end.
    dead_ends: Vec<CObstacle>,
    /// Retreats from dead ends so far.
    retreats: u32,
    /// Whether the current subpath is driven in reverse (a retreat along the trail).
    reversing: bool,
    /// Whether the latest halt is planning's give-up (no way on) rather than a proof.
    stuck: bool,
    /// The step (sensing position) at which a squeeze was last tried, and whether it found a
    /// way on: then C-obstacles go without the safety buffer for `squeeze_views` steps.
    squeezed: Option<(u32, bool)>,
    /// Distance from the goal within which the rover has arrived (m; from the goal given).
    goal_tolerance: f64,
    waypoints: VecDeque<Point2>,
    subpath: Vec<Point2>,
    finish: Option<(Outcome, String)>,
    stats: NavigatorStats,
    steps: u32,
    backing_out: bool,
    drawn_wedges: Vec<Vec<Point2>>,
    drawn_obstacles: Vec<Vec<Point2>>,
    drawn_paths: Vec<Vec<Point2>>,
}

impl RoverBug {
    /// A RoverBug navigator for a rover.
    pub fn new(rover: RoverConfig, config: RoverBugConfig) -> Self {
        let terrain = c_obstacle_terrain(&rover, &config);
        Self {
            rover,
            config,
            terrain,
            mode: Mode::MotionToGoal,
            d_leave: None,
            view: None,
            obstacles: Vec::new(),
            carried: Vec::new(),
            visited: Vec::new(),
            been: Vec::new(),
            trail: Vec::new(),
            dead_ends: Vec::new(),
            retreats: 0,
            reversing: false,
            stuck: false,
            squeezed: None,
            contacts: Vec::new(),
            here: None,
            sensed_len: 0,
            safety: None,
            safety_hazard: None,
            refusals: (0, Point2::new(f64::NAN, f64::NAN)),
            escapes: (0, Point2::new(f64::NAN, f64::NAN)),
            looks: (0, Point2::new(f64::NAN, f64::NAN)),
            look_at: None,
            last_motion: None,
            drive_from: None,
            goal_tolerance: 0.0,
            waypoints: VecDeque::new(),
            subpath: Vec::new(),
            finish: None,
            stats: NavigatorStats::default(),
            steps: 0,
            backing_out: false,
            drawn_wedges: Vec::new(),
            drawn_obstacles: Vec::new(),
            drawn_paths: Vec::new(),
        }
    }

    /// Records a final outcome and returns the command that reports it.
    pub(super) fn finish_now(&mut self, outcome: Outcome, why: &str) -> NavCommand {
        self.finish = Some((outcome, why.to_string()));
        NavCommand::Finish(outcome, why.to_string())
    }

    /// [`Self::finish_now`] for the planning functions that may return a command.
    pub(super) fn halt(&mut self, outcome: Outcome, why: &str) -> Option<NavCommand> {
        Some(self.finish_now(outcome, why))
    }
}

impl Navigator for RoverBug {
    fn name(&self) -> &str {
        "roverbug"
    }

    fn step(&mut self, input: &NavInput<'_>) -> NavCommand {
        let pose = input.estimate.pose.pose2();
        let x = pose.position();
        let goal = input.goal.position;
        if let Some((outcome, why)) = self.finish.clone() {
            return NavCommand::Finish(outcome, why);
        }
        self.goal_tolerance = input.goal.tolerance;
        if x.dist(goal) <= input.goal.tolerance {
            return NavCommand::Finish(
                Outcome::Reached,
                format!("estimate within {:.2} m of the goal", x.dist(goal)),
            );
        }
        if let Some(why) = &input.frame.motion_stopped {
            self.waypoints.clear();
            // The edge of the terrain stops the wheels like a hazard does: both are recorded.
            let blocked = why.starts_with("hazard") || why.starts_with("left the terrain");
            if blocked && !self.backing_out {
                return self.back_out(pose);
            }
        }
        self.backing_out = false;
        if !self.reversing && self.trail.last().is_none_or(|p| p.dist(x) > 0.05) {
            self.trail.push(x);
        }
        if !input.frame.clouds.is_empty() {
            self.here = Some(pose);
            self.ingest(input);
            if let Some((outcome, why)) = self.finish.clone() {
                return NavCommand::Finish(outcome, why);
            }
            let mut cmd = self.plan(pose, goal);
            // Resting at a vertex of the goal's C-obstacle is arrival, not a reason to back out.
            let at_goal_vertex = cmd.is_none()
                && self.waypoints.is_empty()
                && self.obstacles.iter().any(|o| o.contains_strict(goal))
                && self
                    .obstacles
                    .iter()
                    .any(|o| o.contains(goal) && o.vertices.iter().any(|v| v.dist(x) < 0.3));
            let gave_up = match &self.finish {
                Some((outcome, _)) => *outcome != Outcome::Reached,
                None => cmd.is_none() && self.waypoints.is_empty() && !at_goal_vertex,
            };
            let stuck = gave_up && (self.finish.is_none() || self.stuck);
            self.stuck = false;
            // Only a give-up is squeezed, escaped or retreated from: a loop through V_loop is a
            // proof.
            if stuck {
                match self.recover_from_give_up(pose, input.goal) {
                    Recovered::Replanned => cmd = None,
                    Recovered::Command(recovery) => return recovery,
                    Recovered::Nothing => {}
                }
            }
            if let Some(cmd) = cmd {
                return cmd;
            }
            if let Some((outcome, why)) = self.finish.clone() {
                return NavCommand::Finish(outcome, why);
            }
            if self.waypoints.is_empty() {
                // Nothing to do from here: the goal vertex was reached, or no plan exists.
                if at_goal_vertex {
                    return NavCommand::Finish(
                        Outcome::Reached,
                        "at a vertex of the goal's C-obstacle".into(),
                    );
                }
                self.finish = Some((Outcome::HelpRequested, "no subpath from the current view".into()));
                return NavCommand::Finish(Outcome::HelpRequested, "no subpath from the current view".into());
            }
        }
        self.drive_waypoints(pose, goal)
    }

    fn planned_path(&self) -> Vec<Point2> {
        self.subpath.clone()
    }

    fn overlays(&self) -> Vec<Overlay> {
        let wedges = self.drawn_wedges.iter().map(|w| Overlay::Polygon(w.clone(), OverlayKind::Wedge));
        let obstacles =
            self.drawn_obstacles.iter().map(|o| Overlay::Polygon(o.clone(), OverlayKind::CObstacle));
        let paths = self.drawn_paths.iter().map(|p| Overlay::Polyline(p.clone(), OverlayKind::Plan));
        wedges.chain(obstacles).chain(paths).collect()
    }

    fn stats(&self) -> NavigatorStats {
        self.stats.clone()
    }
}

/// Registry entry: RoverBug.
pub const ENTRY: NavigatorEntry = NavigatorEntry {
    name: "roverbug",
    doc: "RoverBug: local tangent graph on sensed wedges, no global map (paper 000 section 2)",
    global_planners: &[],
    params: || param_info(RoverBugConfig::default(), RoverBugConfig::params()),
    build: |b| {
        Ok(Box::new(RoverBug::new(
            b.rover.clone(),
            b.configured(RoverBugConfig::default(), &RoverBugConfig::params())?,
        )))
    },
};
