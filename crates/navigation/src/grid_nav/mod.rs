//! The grid navigator: sense a fan of stereo wedges, fold them into the world map, plan on the
//! inflated hazard grid with a global planner (unknown terrain optimistic), drive the part of the
//! plan that lies in sensed terrain, and repeat.
//!
//! With the octile A* planner and unknown cells as free this is rovernav's first navigator
//! (`astar-grid`); with D* Lite on MRPTA traversability costs, where unsensed cells are neutral,
//! and incremental replanning after each map update, it is MRPTA's navigation (`mrpta`, paper 004
//! sections 3.4-3.5: the planner's path is cut to its sensed part and handed to a segment driver
//! that rotates in place when consecutive segments differ by more than 10 deg).
//!
//! The rover's shape is respected in three places. The planning grid walls off only where the
//! body could not pass driving straight (half its width from a hazard) and makes the band where
//! it could not turn in place (its half-diagonal) expensive; each plan's in-place turns are
//! swept with the body outline and a vertex whose turn would meet a hazard is closed and the
//! plan redone; and the rover drives only over ground it has seen under its whole footprint and
//! stops only where it can turn. A turn that becomes unsafe after new sensing is refused at
//! execution and the rover retraces its latest motions to room to turn.
//!
//! A goal counts as reached anywhere within its tolerance, so when the grown hazards wall off
//! the goal cell itself (a waypoint among rocks) the plan goes to the reachable cell nearest the
//! goal inside 70 % of the tolerance (margin for the estimate's error) rather than declaring the
//! goal unreachable.

use crate::params::{Field, Param, Unit, map_params, turn_threshold_param};
use crate::registry::{NavigatorEntry, Variant, param_info};
use crate::terrain_model::{CostMode, TerrainModel, cells_in_disc};
use rovernav_core::{
    DriveGuard, GridGeometry, NavCommand, NavInput, Navigator, NavigatorStats, Outcome, Overlay, Point2,
    Pose2, RoverConfig, SenseRequest, angle_diff,
};
use rovernav_planning::{Cell, GlobalPlanner, PlanError, SegmentDriverConfig, planner_by_name, segment_path};
use std::collections::VecDeque;

mod goal_region;
use goal_region::{GOAL_REGION_FRACTION, goal_region};

/// Tunable parameters of the grid navigator.
#[derive(Clone, Debug)]
pub struct GridNavigatorConfig {
    /// Global planner registry name.
    pub planner: &'static str,
    /// Longest distance driven between sensing stops (m).
    pub max_step: f64,
    /// Map cell size (m).
    pub map_resolution: f64,
    /// Margin of the world map around the start-goal box (m).
    pub map_margin: f64,
    /// Extra clearance added to the rover radius when growing hazards (m).
    pub safety_buffer: f64,
    /// Mast pan offsets around the direction of interest (rad).
    pub mast_fan: Vec<f64>,
    /// Heading error above which the rover turns in place before driving (rad); paper 004's
    /// segment driver uses 10 deg.
    pub turn_threshold: f64,
    /// Planning cycles without getting closer to the goal before asking for help.
    pub patience: u32,
}

impl GridNavigatorConfig {
    /// The parameters a mission file may set (`[navigator_params]`).
    pub fn params() -> Vec<Param<Self>> {
        use Unit::*;
        let mut params: Vec<Param<Self>> = vec![
            Param {
                name: "max_step_m",
                doc: "longest distance driven between sensing stops",
                unit: PositiveMetres,
                field: |c| Field::Real(&mut c.max_step),
            },
            turn_threshold_param(|c| Field::Real(&mut c.turn_threshold)),
            Param {
                name: "patience",
                doc: "planning cycles without getting closer to the goal before asking for help",
                unit: Count,
                field: |c| Field::U32(&mut c.patience),
            },
        ];
        params.extend(map_params::<Self>(
            |c| Field::Real(&mut c.map_resolution),
            |c| Field::Real(&mut c.map_margin),
            |c| Field::Real(&mut c.safety_buffer),
        ));
        params
    }
}
impl Default for GridNavigatorConfig {
    fn default() -> Self {
        Self {
            planner: "astar",
            max_step: 2.5,
            map_resolution: 0.1,
            map_margin: 15.0,
            safety_buffer: 0.1,
            mast_fan: vec![-0.7, 0.0, 0.7],
            turn_threshold: 10f64.to_radians(),
            patience: 25,
        }
    }
}

/// The grid navigator (see the module documentation).
pub struct GridNavigator {
    name: &'static str,
    rover: RoverConfig,
    config: GridNavigatorConfig,
    terrain: Option<TerrainModel>,
    planner: Box<dyn GlobalPlanner>,
    waypoints: VecDeque<Point2>,
    plan: Vec<Point2>,
    stats: NavigatorStats,
    finish: Option<(Outcome, String)>,
    look_bearing: Option<f64>,
    best_distance: f64,
    cycles_without_progress: u32,
    blocked_senses: u32,
    backing_out: bool,
    last_command: LastCommand,
    full_scan_at: Option<Point2>,
    full_scan_pending: bool,
    /// Where the safety buffer was dropped to pass a tight spot (restored 3 m away).
    squeezed_at: Option<Point2>,
    /// The latest motions, newest last, to retrace out of a spot too tight to turn in.
    trail: Vec<Motion>,
    /// The current goal's tolerance (m): a plan may end anywhere this close to the goal.
    goal_tolerance: f64,
}

/// Replans allowed per planning cycle to route around turns the body cannot make.
const MAX_TURN_REPAIRS: usize = 6;

/// Radius closed around a vertex where the rover cannot turn (m).
const TURN_CLOSE_RADIUS_M: f64 = 0.15;

/// A motion the rover made, to undo.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Motion {
    /// An arc: distance (m) and curvature (1/m).
    Drive(f64, f64),
    /// A turn in place (rad).
    Turn(f64),
}

/// The result of one planning attempt.
enum PlanAttempt {
    /// Waypoints queued, or the navigator decided to look or finish.
    Done,
    /// The plan needs an in-place turn here that the body's sweep cannot make.
    TurnBlocked(Point2),
}

/// Turns needed within this distance of the rover (m) are its own, checked when executed.
const NEAR_START_M: f64 = 0.3;

/// Motions remembered for retracing.
const MAX_TRAIL: usize = 8;

/// How far the rover backs out when it cannot turn in place (m).
const BACK_OUT_M: f64 = 0.3;

/// Distance from the squeeze point after which the safety buffer is restored (m).
const SQUEEZE_RELEASE_M: f64 = 3.0;

/// The kind of the last motion commanded, to locate a hazard contact.
#[derive(Clone, Copy, Debug, PartialEq)]
enum LastCommand {
    Forward,
    Reverse,
    Turn(f64),
    Other,
}

impl GridNavigator {
    /// A navigator with the given registry name, rover and parameters.
    pub fn new(name: &'static str, rover: RoverConfig, config: GridNavigatorConfig) -> Self {
        let planner = planner_by_name(config.planner).expect("navigator registry names a known planner");
        Self {
            name,
            rover,
            config,
            terrain: None,
            planner,
            waypoints: VecDeque::new(),
            plan: Vec::new(),
            stats: NavigatorStats::default(),
            finish: None,
            look_bearing: None,
            best_distance: f64::INFINITY,
            cycles_without_progress: 0,
            blocked_senses: 0,
            backing_out: false,
            last_command: LastCommand::Other,
            full_scan_at: None,
            full_scan_pending: false,
            squeezed_at: None,
            trail: Vec::new(),
            goal_tolerance: 0.0,
        }
    }

    /// Records a motion for retracing, forgetting the oldest beyond [`MAX_TRAIL`].
    fn remember(&mut self, motion: Motion) {
        self.trail.push(motion);
        if self.trail.len() > MAX_TRAIL {
            self.trail.remove(0);
        }
    }

    fn cost_mode(&self) -> CostMode {
        if self.config.planner == "dstar-lite" { CostMode::Traversability } else { CostMode::Optimistic }
    }

    fn init_map(&mut self, from: Point2, goal: Point2) {
        let m = self.config.map_margin;
        let res = self.config.map_resolution;
        let x0 = from.x.min(goal.x) - m;
        let y0 = from.y.min(goal.y) - m;
        let cols = ((from.x.max(goal.x) + m - x0) / res).ceil() as usize;
        let rows = ((from.y.max(goal.y) + m - y0) / res).ceil() as usize;
        let geometry = GridGeometry { cols, rows, resolution: res, origin_x: x0, origin_y: y0 };
        self.terrain = Some(TerrainModel::new(&self.rover, geometry, self.config.safety_buffer));
    }

    /// Plans from the estimate to the goal and queues the waypoints of the sensed, safe prefix.
    ///
    /// The grid keeps the rover's centre where it fits driving straight, so a plan may run
    /// through gaps too tight to turn in: each plan is checked for the in-place turns its
    /// segments need, and a vertex where the body's sweep would meet a hazard is closed and the
    /// plan redone (lazy collision checking), a few times at most.
    fn replan(&mut self, from: Point2, yaw: f64, goal: Point2) {
        self.waypoints.clear();
        let mut closed: Vec<Point2> = Vec::new();
        for _attempt in 0..=MAX_TURN_REPAIRS {
            match self.plan_once(from, yaw, goal, &closed) {
                PlanAttempt::Done => return,
                PlanAttempt::TurnBlocked(at) => closed.push(at),
            }
        }
        // Every repair found another blocked turn: drive what the last plan allows; the
        // execution-time check refuses any turn that would still meet a hazard.
        self.waypoints.clear();
    }

    /// One planning attempt with the turn vertices in `closed` blocked.
    fn plan_once(&mut self, from: Point2, yaw: f64, goal: Point2, closed: &[Point2]) -> PlanAttempt {
        self.waypoints.clear();
        let terrain = self.terrain.as_ref().expect("map initialised before planning");
        let mut grid = terrain.cost_grid(self.cost_mode(), from, goal);
        let g = grid.geometry();
        for &p in closed {
            for (c, r) in cells_in_disc(&g, p, TURN_CLOSE_RADIUS_M) {
                let _ = grid.set_cost(Cell::new(r, c), f32::INFINITY);
            }
        }
        let to_cell = |p: Point2| -> Option<Cell> { g.cell_of(p.x, p.y).map(|(c, r)| Cell::new(r, c)) };
        let (Some(start), Some(goal_cell)) = (to_cell(from), to_cell(goal)) else {
            self.finish = Some((Outcome::Unreachable, "goal or rover outside the navigation map".into()));
            return PlanAttempt::Done;
        };
        self.planner.set_grid(grid);
        self.stats.plans += 1;
        // The goal counts as reached anywhere within its tolerance: when a hazard's margin walls
        // off the goal cell itself, plan to the reachable cell nearest it inside the tolerance.
        let mut target = goal;
        let planned = match self.planner.plan(start, goal_cell) {
            Err(PlanError::NoPath { .. }) => {
                let radius = GOAL_REGION_FRACTION * self.goal_tolerance;
                let grid = self.planner.grid().expect("grid set above");
                match goal_region(grid, start, goal, radius).filter(|&c| c != goal_cell) {
                    Some(cell) => {
                        let (x, y) = g.center(cell.col, cell.row);
                        target = Point2::new(x, y);
                        self.planner.plan(start, cell)
                    }
                    None => Err(PlanError::NoPath { start, goal: goal_cell }),
                }
            }
            other => other,
        };
        let plan = match planned {
            Ok(plan) => plan,
            Err(PlanError::NoPath { .. }) => {
                if !closed.is_empty() {
                    // Only the closed turn vertices block the way: keep the rover where it is
                    // and look again rather than declare the goal unreachable.
                    return PlanAttempt::Done;
                }
                // Before giving up, look all around from here: close-range views replace the
                // noisier far-range assessments that may have closed the way.
                if self.full_scan_at.is_none_or(|p| p.dist(from) > 0.5) {
                    self.full_scan_at = Some(from);
                    self.full_scan_pending = true;
                    return PlanAttempt::Done;
                }
                // Then squeeze: the safety buffer is margin for sensing error, not the rover's
                // size, so a way that only the buffer closes is taken with the bare rover
                // radius, and the buffer comes back once the rover is clear of the tight spot.
                if self.squeezed_at.is_none() && self.config.safety_buffer > 0.0 {
                    self.squeezed_at = Some(from);
                    self.terrain.as_mut().expect("map initialised").set_safety_buffer(0.0);
                    return self.plan_once(from, yaw, goal, closed);
                }
                self.finish = Some((
                    Outcome::Unreachable,
                    "no path to the goal through known-safe and unknown terrain".into(),
                ));
                return PlanAttempt::Done;
            }
            Err(e) => {
                self.finish = Some((Outcome::Aborted, format!("planner failed: {e}")));
                return PlanAttempt::Done;
            }
        };
        let grid = self.planner.grid().expect("grid set above");
        let mut world: Vec<Point2> = plan.points.iter().map(|p| grid.grid_to_world(*p)).collect();
        if let Some(first) = world.first_mut() {
            *first = from;
        }
        if let Some(last) = world.last_mut() {
            *last = target;
        }
        self.plan = world.clone();

        // The segment driver keeps the part of the plan (cut at the step length) that lies in
        // assessed, passable terrain and straightens it into segments.
        let terrain = self.terrain.as_ref().expect("map initialised");
        let step_path = truncate_polyline(&world, self.config.max_step);
        let safe = |p: Point2| {
            // The cells under the rover itself may be unsensed (the cameras look ahead).
            let near_rover = p.dist(from) < 0.3;
            let passable = grid.cost_at_point(grid.world_to_grid(p)).is_finite();
            near_rover || passable && terrain.footprint_seen(p, from, 0.5 * self.rover.length)
        };
        let driver = SegmentDriverConfig {
            turn_threshold: self.config.turn_threshold,
            collinear_tolerance: 0.03,
            ..Default::default()
        };
        let segments = segment_path(Pose2::new(from.x, from.y, 0.0), &step_path, safe, &driver);
        // The turns the waypoints need, from the rover's heading: the first one the execution
        // check handles (the rover can back out); later ones are repaired by replanning.
        let mut heading = yaw;
        let mut at = from;
        for (i, &next) in segments.waypoints.iter().enumerate() {
            let bearing = next.sub(at).angle();
            let turn = angle_diff(bearing, heading);
            if i > 0 && at.dist(from) > NEAR_START_M && turn.abs() > self.config.turn_threshold {
                let pose = Pose2::new(at.x, at.y, heading);
                let other_way = turn - std::f64::consts::TAU * turn.signum();
                if !terrain.turn_is_clear(pose, turn) && !terrain.turn_is_clear(pose, other_way) {
                    return PlanAttempt::TurnBlocked(at);
                }
            }
            heading = bearing;
            at = next;
        }
        // Look where the plan leaves sensed terrain (or toward the goal).
        let look_at = if segments.complete {
            target
        } else {
            step_path[segments.sensed_points.min(step_path.len() - 1)]
        };
        self.look_bearing = Some(look_at.sub(from).angle());
        let length: f64 = std::iter::once(from)
            .chain(segments.waypoints.iter().copied())
            .collect::<Vec<_>>()
            .windows(2)
            .map(|w| w[0].dist(w[1]))
            .sum();
        if length >= 0.15 {
            let waypoints = stop_where_turnable(from, &segments.waypoints, |p| terrain.can_turn_freely(p));
            self.waypoints.extend(waypoints);
        }
        PlanAttempt::Done
    }

    fn sense(&mut self, heading: f64, bearing: f64) -> NavCommand {
        let centre = angle_diff(bearing, heading);
        let mut requests: Vec<SenseRequest> =
            self.config.mast_fan.iter().map(|d| SenseRequest::Mast { pan: centre + d }).collect();
        requests.push(SenseRequest::BodyFront);
        self.stats.sensing_actions += requests.len() as u64;
        NavCommand::Sense(requests)
    }
}

/// The waypoints cut so the rover stops where it can turn in place freely: the last point of
/// the polyline from `from` through `waypoints` (sampled every 5 cm) where `turnable` holds and
/// at least 0.15 m from the start. Unchanged when no such point exists.
fn stop_where_turnable(from: Point2, waypoints: &[Point2], turnable: impl Fn(Point2) -> bool) -> Vec<Point2> {
    let mut best: Option<(usize, Point2)> = None;
    let mut prev = from;
    let mut travelled = 0.0;
    for (i, &next) in waypoints.iter().enumerate() {
        let d = prev.dist(next);
        let n = (d / 0.05).ceil().max(1.0) as usize;
        for k in 1..=n {
            let p = prev.add(next.sub(prev).scale(k as f64 / n as f64));
            if travelled + d * k as f64 / n as f64 >= 0.15 && turnable(p) {
                best = Some((i, p));
            }
        }
        travelled += d;
        prev = next;
    }
    match best {
        Some((i, p)) => {
            let mut out = waypoints[..i].to_vec();
            out.push(p);
            out
        }
        None => waypoints.to_vec(),
    }
}

/// The polyline cut after `length` metres.
fn truncate_polyline(points: &[Point2], length: f64) -> Vec<Point2> {
    let mut out = vec![points[0]];
    let mut left = length;
    for w in points.windows(2) {
        let d = w[0].dist(w[1]);
        if d >= left {
            out.push(w[0].add(w[1].sub(w[0]).scale(left / d.max(1e-12))));
            return out;
        }
        left -= d;
        out.push(w[1]);
    }
    out
}

impl Navigator for GridNavigator {
    fn name(&self) -> &str {
        self.name
    }

    fn step(&mut self, input: &NavInput<'_>) -> NavCommand {
        let est = input.estimate.pose;
        let here = Point2::new(est.x, est.y);
        let goal = input.goal.position;
        if self.terrain.is_none() {
            self.init_map(here, goal);
            self.terrain.as_mut().expect("map initialised").set_keep_out(&input.goal.keep_out);
        }
        if let Some((outcome, why)) = self.finish.clone() {
            return NavCommand::Finish(outcome, why);
        }
        self.goal_tolerance = input.goal.tolerance;
        if here.dist(goal) <= input.goal.tolerance {
            return NavCommand::Finish(
                Outcome::Reached,
                format!("estimate within {:.2} m of the goal", here.dist(goal)),
            );
        }
        if let Some(why) = &input.frame.motion_stopped {
            self.waypoints.clear();
            if why.starts_with("hazard") && self.backing_out {
                // Even backing away meets the terrain: the body is caught. Stop before more
                // attempts do damage, as flight fault protection does.
                let why = format!("stuck in contact with the terrain ({why}); operators must help");
                self.finish = Some((Outcome::HelpRequested, why.clone()));
                return NavCommand::Finish(Outcome::HelpRequested, why);
            }
            if why.starts_with("hazard") && !self.backing_out {
                // Remember where the body met the terrain: ahead of the rover for a forward
                // drive, behind it when reversing, under the leading corners when turning.
                let ahead = |d: f64, side: f64| {
                    est.pose2()
                        .transform(Point2::new(d * 0.5 * self.rover.length, side * 0.5 * self.rover.width))
                };
                let terrain = self.terrain.as_mut().expect("map initialised");
                match self.last_command {
                    LastCommand::Forward => terrain.mark_contact(ahead(1.0, 0.0)),
                    LastCommand::Reverse => terrain.mark_contact(ahead(-1.0, 0.0)),
                    LastCommand::Turn(sign) => {
                        terrain.mark_contact(ahead(1.0, sign));
                        terrain.mark_contact(ahead(-1.0, -sign));
                    }
                    LastCommand::Other => {}
                }
                // Back away from whatever the body met, then look again.
                self.trail.clear();
                self.backing_out = true;
                self.last_command = LastCommand::Reverse;
                return NavCommand::Drive { distance: -0.3, curvature: 0.0, guard: DriveGuard::default() };
            }
        }
        self.backing_out = false;
        if let Some(p) = self.squeezed_at
            && p.dist(here) > SQUEEZE_RELEASE_M
        {
            self.squeezed_at = None;
            let buffer = self.config.safety_buffer;
            self.terrain.as_mut().expect("map initialised").set_safety_buffer(buffer);
        }
        if !input.frame.clouds.is_empty() {
            self.terrain.as_mut().expect("map initialised").ingest(&input.frame.clouds, &input.estimate);
            self.replan(here, est.yaw, goal);
            if let Some((outcome, why)) = self.finish.clone() {
                return NavCommand::Finish(outcome, why);
            }
            let d = here.dist(goal);
            if d < self.best_distance - 0.1 {
                self.best_distance = d;
                self.cycles_without_progress = 0;
            } else {
                self.cycles_without_progress += 1;
                if self.cycles_without_progress > self.config.patience {
                    self.finish = Some((
                        Outcome::HelpRequested,
                        format!("no progress toward the goal in {} planning cycles", self.config.patience),
                    ));
                    return NavCommand::Finish(Outcome::HelpRequested, self.finish.clone().unwrap().1);
                }
            }
            if self.waypoints.is_empty() {
                self.blocked_senses += 1;
            } else {
                self.blocked_senses = 0;
            }
        }
        if let Some(&next) = self.waypoints.front() {
            let bearing = next.sub(here).angle();
            let error = angle_diff(bearing, est.yaw);
            if error.abs() > self.config.turn_threshold {
                // The body sweeps its whole outline when turning in place: take the way round
                // that stays clear of sensed hazards, or back out and plan again from there.
                let terrain = self.terrain.as_ref().expect("map initialised");
                let pose = est.pose2();
                let other_way = error - std::f64::consts::TAU * error.signum();
                let angle = [error, other_way].into_iter().find(|&a| terrain.turn_is_clear(pose, a));
                if let Some(angle) = angle {
                    self.last_command = LastCommand::Turn(angle.signum());
                    self.remember(Motion::Turn(angle));
                    return NavCommand::Turn { angle };
                }
                self.waypoints.clear();
                // Undo the latest motion: the rover made it without meeting anything, and
                // stops only where it could turn (see `plan_once`), so retracing gets it back
                // to room to turn.
                match self.trail.pop() {
                    Some(Motion::Drive(distance, curvature)) => {
                        self.last_command = LastCommand::Reverse;
                        return NavCommand::Drive {
                            distance: -distance,
                            curvature,
                            guard: DriveGuard::default(),
                        };
                    }
                    Some(Motion::Turn(angle)) => {
                        self.last_command = LastCommand::Turn(-angle.signum());
                        return NavCommand::Turn { angle: -angle };
                    }
                    None => {}
                }
                if terrain.drive_is_clear(pose, -BACK_OUT_M) {
                    self.last_command = LastCommand::Reverse;
                    return NavCommand::Drive {
                        distance: -BACK_OUT_M,
                        curvature: 0.0,
                        guard: DriveGuard::default(),
                    };
                }
                let why =
                    "boxed in: neither turning in place nor backing out keeps clear of the sensed hazards";
                self.finish = Some((Outcome::HelpRequested, why.into()));
                return NavCommand::Finish(Outcome::HelpRequested, why.into());
            }
            self.last_command = LastCommand::Forward;
            self.waypoints.pop_front();
            let chord = here.dist(next);
            // The arc through `next` that starts along the current heading.
            let curvature = if chord > 1e-6 { 2.0 * error.sin() / chord } else { 0.0 };
            let distance = if error.abs() > 1e-6 { chord * error / error.sin() } else { chord };
            self.remember(Motion::Drive(distance, curvature));
            return NavCommand::Drive { distance, curvature, guard: DriveGuard::default() };
        }
        if self.full_scan_pending {
            self.full_scan_pending = false;
            self.last_command = LastCommand::Other;
            let mut requests: Vec<SenseRequest> =
                (0..8).map(|k| SenseRequest::Mast { pan: k as f64 * std::f64::consts::FRAC_PI_4 }).collect();
            requests.extend([SenseRequest::BodyFront, SenseRequest::BodyRear]);
            self.stats.sensing_actions += requests.len() as u64;
            return NavCommand::Sense(requests);
        }
        let bearing = self.look_bearing.unwrap_or_else(|| goal.sub(here).angle());
        // When repeated looks in one direction reveal nothing drivable, widen the search.
        let bearing = bearing
            + [0.0, 1.2, -1.2, 2.4, -2.4, std::f64::consts::PI]
                [(self.blocked_senses.saturating_sub(1) as usize) % 6];
        self.last_command = LastCommand::Other;
        self.sense(est.yaw, bearing)
    }

    fn planned_path(&self) -> Vec<Point2> {
        self.plan.clone()
    }

    fn overlays(&self) -> Vec<Overlay> {
        self.terrain.as_ref().map(TerrainModel::overlays).unwrap_or_default()
    }

    fn stats(&self) -> NavigatorStats {
        self.stats.clone()
    }
}

/// Registry entry: the grid navigator under a choice of global planner (`astar-grid`,
/// `mrpta`).
pub const ENTRY: NavigatorEntry = NavigatorEntry {
    name: "grid",
    doc: "inflated hazard grid, global planner, segment driver (MER/MSL-style; paper 004 sections 3.4-3.5)",
    global_planners: &[
        Variant { global_planner: "astar", label: "astar-grid" },
        Variant { global_planner: "dstar-lite", label: "mrpta" },
    ],
    params: || param_info(GridNavigatorConfig::default(), GridNavigatorConfig::params()),
    build: |b| {
        let planner = b.global_planner.unwrap_or("astar");
        let config = b.configured(
            GridNavigatorConfig { planner, ..Default::default() },
            &GridNavigatorConfig::params(),
        )?;
        Ok(Box::new(GridNavigator::new(b.label, b.rover.clone(), config)))
    },
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_rover_stops_at_the_last_point_where_it_can_turn() {
        let wps = [Point2::new(1.0, 0.0), Point2::new(1.0, 2.0)];
        // Room to turn only for x < 0.6 or y > 1.5.
        let turnable = |p: Point2| p.x < 0.6 || p.y > 1.5;
        let cut = stop_where_turnable(Point2::new(0.0, 0.0), &wps, turnable);
        assert_eq!(cut.len(), 2);
        assert!(cut[1].dist(Point2::new(1.0, 2.0)) < 1e-9, "the end is turnable: {cut:?}");
        let cut = stop_where_turnable(Point2::new(0.0, 0.0), &wps, |p: Point2| p.x < 0.6);
        assert_eq!(cut.len(), 1);
        assert!((cut[0].x - 0.55).abs() < 1e-9 && cut[0].y.abs() < 1e-9, "{cut:?}");
        // Nowhere to turn: the plan is kept as it was.
        assert_eq!(stop_where_turnable(Point2::new(0.0, 0.0), &wps, |_| false), wps.to_vec());
    }

    #[test]
    fn truncated_polyline_has_the_requested_length() {
        let pts = [Point2::new(0.0, 0.0), Point2::new(1.0, 0.0), Point2::new(1.0, 3.0)];
        let cut = truncate_polyline(&pts, 2.5);
        let len: f64 = cut.windows(2).map(|w| w[0].dist(w[1])).sum();
        assert!((len - 2.5).abs() < 1e-12);
        assert!(cut.last().unwrap().dist(Point2::new(1.0, 1.5)) < 1e-12);
        assert_eq!(truncate_polyline(&pts, 10.0).len(), 3);
    }
}
