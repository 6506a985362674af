//! GESTALT local navigation, alone or assisted by Field D* (paper 003 section 2).
//!
//! Every cycle the rover images the terrain ahead (the front body pair plus one mast wedge
//! toward the goal, or the three-wedge mast fan after a turn or back-up),
//! folds the range data into a goodness map (GESTALT goodness, 0..1, evaluated with the hazard
//! margin of [`crate::terrain_model::HAZARD_MARGIN`]), and scores a fixed set of candidate
//! arcs: turns in place, forward arcs of several curvatures and a straight back-up. Each arc
//! receives three votes, as on MER: a hazard vote (the worst goodness under the rover centre
//! along the arc, which is the worst footprint it sweeps, since goodness rates the rover's
//! footprint centred on each cell), a steering-bias vote (small curvature changes are
//! preferred) and a waypoint vote (progress toward the goal). The weighted merge picks the arc,
//! which is driven one step (0.5 m), provided its end lies in sensed terrain. Hazards (the
//! grown hazard layer, and keep-out zones) on the driven part or within 0.3 m past its end
//! veto an arc; farther along the look-ahead they only lower its vote. A turn in place is
//! scored as the turn followed by a straight step. After 80 steps without progress the rover
//! asks for help, and its step budget ends the traverse.
//!
//! In `gestalt+field-dstar` the waypoint vote becomes the drop of the Field D* cost-to-goal
//! from the rover to the arc's end, computed on a global map that combines the sensed goodness
//! and the mission's keep-out zones: the combination the paper credits with getting the rovers
//! around wide obstacles and rock clusters where GESTALT alone fails (Spirit, sol 108).

use crate::params::{Field, Param, Unit, map_params};
use crate::registry::{NavigatorEntry, Variant, param_info};
use crate::terrain_model::TerrainModel;
use rovernav_core::{
    DriveGuard, Goal, GridGeometry, NavCommand, NavInput, Navigator, NavigatorStats, Outcome, Overlay,
    Point2, Pose2, RoverConfig, SenseRequest, angle_diff, wrap_angle,
};
use rovernav_planning::{Cell, CellChange, CostGrid, FieldDStar, GlobalPlanner};
use std::collections::VecDeque;

/// Field D* cost per metre of unsensed terrain (that of goodness 0.75).
const UNKNOWN_COST: f32 = 1.5;

/// Field D* cost per metre of terrain of goodness `g` (> 0): 1 on ideal ground, 3 at the
/// veto threshold's neighbourhood, so that rough but safe ground is crossed rather than
/// detoured around at any length; goodness 0 is an obstacle.
pub fn goodness_to_cost(g: f32) -> f32 {
    if g <= 0.0 { f32::INFINITY } else { 1.0 + 2.0 * (1.0 - g.min(1.0)) }
}

/// Distance past the end of a driven arc within which hazards still veto it (m).
const HAZARD_LOOKAHEAD: f64 = 0.3;

/// Hazard vote of an arc over terrain of goodness 0 outside the grown hazards.
const LOW_GOODNESS_VOTE: f64 = 0.05;

/// Tunable parameters of GESTALT.
#[derive(Clone, Debug)]
pub struct GestaltConfig {
    /// Distance driven per cycle (m); MER normally drives 50 cm.
    pub step: f64,
    /// How far along each arc the votes look (m).
    pub lookahead: f64,
    /// Forward arc curvatures (1/m).
    pub curvatures: Vec<f64>,
    /// Turn-in-place angles (rad).
    pub turns: Vec<f64>,
    /// Weight of the hazard vote.
    pub hazard_weight: f64,
    /// Weight of the steering-bias vote.
    pub steering_weight: f64,
    /// Weight of the waypoint vote.
    pub waypoint_weight: f64,
    /// Map cell size (m).
    pub map_resolution: f64,
    /// Margin of the map around the start-goal box (m).
    pub map_margin: f64,
    /// Extra clearance added to the rover radius when growing hazards (m).
    pub safety_buffer: f64,
    /// Mast pan angles of the three wedges (rad, body frame).
    pub mast_fan: Vec<f64>,
    /// Use the Field D* cost-to-goal for the waypoint vote.
    pub field_dstar: bool,
    /// Cell size of the Field D* grid, in map cells.
    pub dstar_cells_per_cell: usize,
    /// Drive steps allowed before giving up (the step budget).
    pub max_steps: u32,
    /// Drive and turn steps without getting 0.25 m closer to the goal before asking for help.
    pub patience: u32,
}

impl GestaltConfig {
    /// The parameters a mission file may set (`[navigator_params]`).
    pub fn params() -> Vec<Param<Self>> {
        use Unit::*;
        let mut params: Vec<Param<Self>> = vec![
            Param {
                name: "step_m",
                doc: "distance driven per cycle",
                unit: PositiveMetres,
                field: |c| Field::Real(&mut c.step),
            },
            Param {
                name: "lookahead_m",
                doc: "how far along each arc the votes look",
                unit: PositiveMetres,
                field: |c| Field::Real(&mut c.lookahead),
            },
            Param {
                name: "hazard_weight",
                doc: "weight of the hazard vote",
                unit: Weight,
                field: |c| Field::Real(&mut c.hazard_weight),
            },
            Param {
                name: "steering_weight",
                doc: "weight of the steering-bias vote",
                unit: Weight,
                field: |c| Field::Real(&mut c.steering_weight),
            },
            Param {
                name: "waypoint_weight",
                doc: "weight of the waypoint vote",
                unit: Weight,
                field: |c| Field::Real(&mut c.waypoint_weight),
            },
            Param {
                name: "max_steps",
                doc: "drive steps allowed before giving up (the step budget)",
                unit: Count,
                field: |c| Field::U32(&mut c.max_steps),
            },
            Param {
                name: "patience",
                doc: "drive and turn steps without getting 0.25 m closer to the goal before asking for help",
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
impl Default for GestaltConfig {
    fn default() -> Self {
        Self {
            step: 0.5,
            lookahead: 1.5,
            curvatures: vec![0.0, 0.25, -0.25, 0.5, -0.5, 1.0, -1.0, 2.0, -2.0],
            turns: vec![0.5, -0.5, 1.0, -1.0, 1.6, -1.6, 3.1],
            hazard_weight: 1.0,
            steering_weight: 0.2,
            waypoint_weight: 2.0,
            map_resolution: 0.1,
            map_margin: 10.0,
            safety_buffer: 0.05,
            mast_fan: vec![-0.7, 0.0, 0.7],
            field_dstar: false,
            dstar_cells_per_cell: 2,
            max_steps: 400,
            patience: 80,
        }
    }
}

/// One candidate motion.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Candidate {
    /// Drive `distance` (signed) at `curvature`.
    Arc { distance: f64, curvature: f64 },
    /// Turn in place by `angle`.
    Turn { angle: f64 },
}

/// Pose after driving `s` metres along an arc of curvature `k` from `p`.
pub fn arc_pose(p: Pose2, k: f64, s: f64) -> Pose2 {
    if k.abs() < 1e-9 {
        let (sn, cs) = p.yaw.sin_cos();
        return Pose2::new(p.x + s * cs, p.y + s * sn, p.yaw);
    }
    let yaw = p.yaw + k * s;
    Pose2::new(p.x + (yaw.sin() - p.yaw.sin()) / k, p.y - (yaw.cos() - p.yaw.cos()) / k, wrap_angle(yaw))
}

/// Whether `p` lies inside the polygon (even-odd rule).
pub fn point_in_polygon(p: Point2, polygon: &[Point2]) -> bool {
    let mut inside = false;
    let n = polygon.len();
    for i in 0..n {
        let (a, b) = (polygon[i], polygon[(i + n - 1) % n]);
        if (a.y > p.y) != (b.y > p.y) && p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x {
            inside = !inside;
        }
    }
    inside
}

/// Distance from `p` to the nearest keep-out polygon (0 inside one); infinity without any.
pub fn keep_out_distance(goal: &Goal, p: Point2) -> f64 {
    crate::terrain_model::distance_to_zones(&goal.keep_out, p)
}

/// The GESTALT navigator (see the module documentation).
pub struct GestaltNavigator {
    name: &'static str,
    rover: RoverConfig,
    config: GestaltConfig,
    terrain: Option<TerrainModel>,
    dstar: Option<DStarField>,
    need_sense: bool,
    last_curvature: f64,
    steps: u32,
    best_distance: f64,
    steps_without_progress: u32,
    last_motion: Option<Candidate>,
    trail: VecDeque<Point2>,
    stats: NavigatorStats,
}

impl GestaltNavigator {
    /// A navigator with a registry name, a rover and parameters.
    pub fn new(name: &'static str, rover: RoverConfig, config: GestaltConfig) -> Self {
        Self {
            name,
            rover,
            config,
            terrain: None,
            dstar: None,
            need_sense: true,
            last_curvature: 0.0,
            steps: 0,
            best_distance: f64::INFINITY,
            steps_without_progress: 0,
            last_motion: None,
            trail: VecDeque::new(),
            stats: NavigatorStats::default(),
        }
    }

    fn init_map(&mut self, from: Point2, goal: &Goal) {
        let m = self.config.map_margin;
        let res = self.config.map_resolution;
        let xs = goal.waypoints.iter().map(|p| p.x).chain([from.x, goal.position.x]);
        let ys = goal.waypoints.iter().map(|p| p.y).chain([from.y, goal.position.y]);
        let (x0, x1) = xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
        let (y0, y1) = ys.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
        let geometry = GridGeometry {
            cols: ((x1 - x0 + 2.0 * m) / res).ceil() as usize,
            rows: ((y1 - y0 + 2.0 * m) / res).ceil() as usize,
            resolution: res,
            origin_x: x0 - m,
            origin_y: y0 - m,
        };
        self.terrain = Some(TerrainModel::with_hazard_height(
            &self.rover,
            geometry,
            self.config.safety_buffer,
            // Its arc evaluation treats every grown hazard as a wall, so the denser map of
            // top heights (tuned for the grid planners' graded costs) boxes it in.
            rovernav_perception::HazardHeight::Mean,
        ));
    }

    /// Hazard vote of the path of poses (0 = vetoed): the worst goodness swept, with the end
    /// of the driven part required to be sensed.
    fn hazard_vote(&self, goal: &Goal, from: Point2, path: &[(Point2, bool)], require_known: bool) -> f64 {
        let terrain = self.terrain.as_ref().expect("map initialised");
        let world = terrain.world();
        let mut vote: f64 = 1.0;
        // The rover's own footprint is not visible to its cameras; it stood there safely. The
        // cameras also miss a band of ground just ahead of the body, which an arc end may lie
        // in without being unknown terrain in GESTALT's sense (it was imaged from afar, or is
        // the cleared start area).
        let blind = 0.5 * self.rover.length;
        let unseen_band = blind + 0.3;
        let driven_end = path.iter().rev().find(|(_, driven)| *driven).map_or(from, |(p, _)| *p);
        for &(p, driven) in path {
            // Hazards on the driven part, or just past its end (where the rover stops, and
            // from where it must still be able to turn away), veto the arc; farther along they
            // only halve its vote, so that narrow passages stay open to precise arcs.
            let strict = driven || p.dist(driven_end) < HAZARD_LOOKAHEAD;
            if keep_out_distance(goal, p) < self.rover.radius() {
                if strict {
                    return 0.0;
                }
                vote = vote.min(0.5);
                continue;
            }
            let near = p.dist(from) < blind;
            if terrain.is_grown_hazard(p) && !near {
                if strict {
                    return 0.0;
                }
                vote = vote.min(0.5);
                continue;
            }
            match world.cell_at(p.x, p.y).and_then(|c| c.goodness) {
                // Goodness grades the terrain; the grown hazard layer alone vetoes (above), as
                // goodness 0 marks footprints that merely touch the rim of a hazard.
                Some(g) if !near => vote = vote.min((g as f64).max(LOW_GOODNESS_VOTE)),
                // Goodness needs a whole footprint of data; the driven part of the arc only
                // needs its ground to have been seen (and found free of hazards above).
                None if driven
                    && require_known
                    && p.dist(from) >= unseen_band
                    && !world.is_sensed(p.x, p.y) =>
                {
                    return 0.0;
                }
                _ => {}
            }
        }
        vote
    }

    /// Samples the rover centre along a candidate: (point, part of the driven motion).
    fn sweep(&self, pose: Pose2, c: Candidate) -> (Vec<(Point2, bool)>, Pose2) {
        let ds = 0.5 * self.config.map_resolution;
        let mut out = Vec::new();
        let (start, k, driven, total) = match c {
            Candidate::Arc { distance, curvature } => {
                (pose, curvature, distance, if distance > 0.0 { self.config.lookahead } else { distance })
            }
            // A turn is only worth making if the step straight ahead after it is clear.
            Candidate::Turn { angle } => (
                Pose2::new(pose.x, pose.y, wrap_angle(pose.yaw + angle)),
                0.0,
                self.config.step,
                self.config.lookahead,
            ),
        };
        let n = (total.abs() / ds).ceil().max(1.0) as usize;
        let mut end = start;
        for i in 0..=n {
            let s = total * i as f64 / n as f64;
            let p = arc_pose(start, k, s);
            out.push((p.position(), s.abs() <= driven.abs() + 1e-9));
            end = p;
        }
        (out, end)
    }

    fn choose(&mut self, input: &NavInput<'_>) -> Option<Candidate> {
        let est = input.estimate.pose.pose2();
        let here = est.position();
        let goal = input.goal.position;
        let mut candidates: Vec<Candidate> = self
            .config
            .curvatures
            .iter()
            .map(|&k| Candidate::Arc { distance: self.config.step, curvature: k })
            .collect();
        candidates.extend(self.config.turns.iter().map(|&a| Candidate::Turn { angle: a }));
        candidates.push(Candidate::Arc { distance: -self.config.step, curvature: 0.0 });

        let to_goal_here = self.cost_to_goal(here, goal);
        let max_k = self.config.curvatures.iter().fold(0.0f64, |a, k| a.max(k.abs())).max(1e-6);
        let mut best: Option<(f64, Candidate)> = None;
        for c in candidates {
            let (path, end) = self.sweep(est, c);
            // Ground ahead after a turn is imaged before the rover drives there.
            let hazard = self.hazard_vote(input.goal, here, &path, matches!(c, Candidate::Arc { .. }));
            if hazard <= 0.0 {
                continue;
            }
            // Progress per metre looked ahead, mapped to 0..1 (0.5 = no progress).
            let reach = match c {
                Candidate::Arc { distance, .. } if distance < 0.0 => self.config.step,
                _ => self.config.lookahead,
            };
            let progress = (to_goal_here - self.cost_to_goal(end.position(), goal)) / reach;
            let waypoint = if progress.is_finite() { (0.5 + 0.5 * progress).clamp(0.0, 1.0) } else { 0.0 };
            let steering = match c {
                Candidate::Arc { curvature, distance } if distance > 0.0 => {
                    1.0 - (curvature - self.last_curvature).abs() / (2.0 * max_k)
                }
                _ => 0.0,
            };
            // Undoing the previous turn or back-up is what traps a purely local planner in
            // oscillation; the steering bias discourages it.
            let reversal = match (c, self.last_motion) {
                (Candidate::Turn { angle }, Some(Candidate::Turn { angle: last })) if angle * last < 0.0 => {
                    0.3
                }
                _ => 0.0,
            };
            let vote = self.config.hazard_weight * hazard
                + self.config.steering_weight * (steering - reversal)
                + self.config.waypoint_weight * waypoint;
            if best.is_none_or(|(v, _)| vote > v) {
                best = Some((vote, c));
            }
        }
        best.map(|(_, c)| c)
    }

    /// The waypoint vote's measure of distance to go: Euclidean for GESTALT alone, the Field D*
    /// cost-to-goal (in metres of best terrain) when assisted.
    fn cost_to_goal(&mut self, p: Point2, goal: Point2) -> f64 {
        match &mut self.dstar {
            Some(field) if field.valid => field.cost_from(p).unwrap_or(f64::INFINITY),
            _ => p.dist(goal),
        }
    }

    /// Images the terrain ahead: the front body pair and one mast wedge toward the goal while
    /// driving on, the whole mast fan after a turn or back-up (a new view is needed then).
    fn sense(&mut self, input: &NavInput<'_>) -> NavCommand {
        let est = input.estimate.pose;
        let exploring = !matches!(self.last_motion, Some(Candidate::Arc { distance, .. }) if distance > 0.0);
        let fan = self.config.mast_fan.iter().fold(0.0f64, |a, p| a.max(p.abs()));
        let toward = match self.dstar.as_ref().and_then(|f| f.path.get(1).copied()) {
            Some(next) => next,
            None => input.goal.position,
        };
        let pan = angle_diff(toward.sub(Point2::new(est.x, est.y)).angle(), est.yaw).clamp(-fan, fan);
        let mut requests: Vec<SenseRequest> = if exploring {
            self.config.mast_fan.iter().map(|&pan| SenseRequest::Mast { pan }).collect()
        } else {
            vec![SenseRequest::Mast { pan }]
        };
        requests.push(SenseRequest::BodyFront);
        self.stats.sensing_actions += requests.len() as u64;
        self.need_sense = false;
        NavCommand::Sense(requests)
    }
}

/// The Field D* cost-to-goal field over the sensed map and keep-out zones.
struct DStarField {
    planner: FieldDStar,
    geometry: GridGeometry,
    costs: Vec<f32>,
    goal: Cell,
    valid: bool,
    planned: bool,
    path: Vec<Point2>,
}

impl DStarField {
    fn new(fine: GridGeometry, factor: usize, goal: Point2) -> Option<Self> {
        let res = fine.resolution * factor as f64;
        let geometry = GridGeometry {
            cols: fine.cols.div_ceil(factor),
            rows: fine.rows.div_ceil(factor),
            resolution: res,
            origin_x: fine.origin_x,
            origin_y: fine.origin_y,
        };
        let (c, r) = geometry.cell_of(goal.x, goal.y)?;
        Some(Self {
            planner: FieldDStar::new(),
            costs: vec![1.0; geometry.len()],
            geometry,
            goal: Cell::new(r, c),
            valid: false,
            planned: false,
            path: Vec::new(),
        })
    }

    /// Rebuilds the costs from the terrain model and replans from the rover.
    fn update(&mut self, terrain: &TerrainModel, goal: &Goal, rover: Point2, rover_radius: f64) {
        let g = self.geometry;
        let world = terrain.world();
        let fine = world.geometry();
        let factor = (g.resolution / fine.resolution).round().max(1.0) as usize;
        let mut costs = vec![1.0f32; g.len()];
        for r in 0..g.rows {
            for c in 0..g.cols {
                let (x, y) = g.center(c, r);
                let centre = Point2::new(x, y);
                let mut worst: Option<f32> = None;
                let mut blocked = keep_out_distance(goal, centre) < rover_radius;
                for fr in r * factor..((r + 1) * factor).min(fine.rows) {
                    for fc in c * factor..((c + 1) * factor).min(fine.cols) {
                        let (fx, fy) = fine.center(fc, fr);
                        if terrain.is_grown_hazard(Point2::new(fx, fy)) {
                            blocked = true;
                        }
                        let v = *world.goodness().get(fc, fr);
                        if v.is_finite() {
                            worst = Some(worst.map_or(v, |w| w.min(v)));
                        }
                    }
                }
                // The rover's own cells stay passable so that it can always plan out.
                let own = centre.dist(rover) <= rover_radius;
                costs[g.index(c, r)] = if blocked && !own {
                    f32::INFINITY
                } else {
                    // Unsensed terrain costs as much as fair sensed terrain, so that the plan
                    // neither shuns nor seeks it.
                    let cost = worst.map_or(UNKNOWN_COST, goodness_to_cost);
                    if own { cost.min(UNKNOWN_COST) } else { cost }
                };
            }
        }
        let Some((sc, sr)) = g.cell_of(rover.x, rover.y) else {
            self.valid = false;
            return;
        };
        let start = Cell::new(sr, sc);
        // Field D* is only asked about goals it can reach: a flood fill answers that first.
        if !reachable(&costs, g, start, self.goal) {
            self.valid = false;
            self.path.clear();
            return;
        }
        let result = if self.planned {
            let changes: Vec<CellChange> = costs
                .iter()
                .zip(&self.costs)
                .enumerate()
                .filter(|(_, (a, b))| a != b)
                .map(|(i, (&cost, _))| CellChange { cell: Cell::new(i / g.cols, i % g.cols), cost })
                .collect();
            self.planner
                .update_cells(&changes)
                .and_then(|_| self.planner.move_start(start))
                .and_then(|_| self.planner.replan())
        } else {
            let mut grid =
                CostGrid::from_costs(g.rows, g.cols, costs.clone()).expect("costs are >= 1 or infinite");
            grid.set_geometry(g);
            self.planner.set_grid(grid);
            self.planner.plan(start, self.goal)
        };
        self.costs = costs;
        match result {
            Ok(plan) => {
                self.planned = true;
                self.valid = true;
                let grid = self.planner.grid().expect("grid set");
                self.path = plan.points.iter().map(|p| grid.grid_to_world(*p)).collect();
            }
            Err(_) => {
                self.valid = false;
                self.planned = false;
                self.path.clear();
            }
        }
    }

    /// Cost-to-goal (m of best terrain) from a point, by moving the search start there.
    fn cost_from(&mut self, p: Point2) -> Option<f64> {
        let (c, r) = self.geometry.cell_of(p.x, p.y)?;
        let cell = Cell::new(r, c);
        if !self.costs[self.geometry.index(c, r)].is_finite() {
            return None;
        }
        self.planner.move_start(cell).ok()?;
        let plan = self.planner.replan().ok()?;
        // Interpolate within the cell: the value is the corner node's, so add the way there.
        let grid = self.planner.grid()?;
        let corner = grid.grid_to_world(cell.corner());
        let to_corner = (p.x - corner.x).hypot(p.y - corner.y);
        Some(plan.value * self.geometry.resolution + to_corner)
    }
}

/// Whether `start` and `goal` are joined through finite-cost cells (8-connected flood fill).
fn reachable(costs: &[f32], g: GridGeometry, start: Cell, goal: Cell) -> bool {
    let mut seen = vec![false; costs.len()];
    let mut queue = VecDeque::from([goal]);
    seen[g.index(goal.col, goal.row)] = true;
    while let Some(cell) = queue.pop_front() {
        if cell == start {
            return true;
        }
        for dr in -1isize..=1 {
            for dc in -1isize..=1 {
                let (r, c) = (cell.row as isize + dr, cell.col as isize + dc);
                if r < 0 || c < 0 || r as usize >= g.rows || c as usize >= g.cols {
                    continue;
                }
                let i = g.index(c as usize, r as usize);
                if !seen[i] && costs[i].is_finite() {
                    seen[i] = true;
                    queue.push_back(Cell::new(r as usize, c as usize));
                }
            }
        }
    }
    false
}

impl Navigator for GestaltNavigator {
    fn name(&self) -> &str {
        self.name
    }

    fn step(&mut self, input: &NavInput<'_>) -> NavCommand {
        let est = input.estimate.pose;
        let here = Point2::new(est.x, est.y);
        let goal = input.goal.position;
        if self.terrain.is_none() {
            self.init_map(here, input.goal);
        }
        let d = here.dist(goal);
        if d <= input.goal.tolerance {
            return NavCommand::Finish(Outcome::Reached, format!("estimate within {d:.2} m of the goal"));
        }
        if let Some(why) = &input.frame.motion_stopped
            && why.starts_with("hazard")
        {
            // The body met something perception missed: remember it and back away.
            let ahead = est.pose2().transform(Point2::new(0.5 * self.rover.length, 0.0));
            self.terrain.as_mut().expect("map initialised").mark_contact(ahead);
            if !matches!(self.last_motion, Some(Candidate::Arc { distance, .. }) if distance < 0.0) {
                let back = Candidate::Arc { distance: -0.3, curvature: 0.0 };
                self.last_motion = Some(back);
                self.need_sense = true;
                return NavCommand::Drive { distance: -0.3, curvature: 0.0, guard: DriveGuard::default() };
            }
        }
        if self.need_sense {
            return self.sense(input);
        }
        if !input.frame.clouds.is_empty() {
            let terrain = self.terrain.as_mut().expect("map initialised");
            terrain.ingest(&input.frame.clouds, &input.estimate);
            if self.config.field_dstar {
                if self.dstar.is_none() {
                    let geometry = terrain.world().geometry();
                    self.dstar = DStarField::new(geometry, self.config.dstar_cells_per_cell, goal);
                }
                let radius = self.rover.radius();
                if let Some(field) = &mut self.dstar {
                    field.update(self.terrain.as_ref().expect("map"), input.goal, here, radius);
                    self.stats.plans += 1;
                }
            }
        }
        // Progress is measured the way the waypoint vote measures distance to go: along the
        // Field D* route when assisted (a detour around a cluster is progress there). A map
        // update that lengthens the route restarts the count from the new value.
        let to_go = self.cost_to_goal(here, goal);
        if to_go < self.best_distance - 0.25 || to_go > self.best_distance + 2.0 {
            self.best_distance = to_go;
            self.steps_without_progress = 0;
        } else {
            self.steps_without_progress += 1;
        }
        if self.steps >= self.config.max_steps {
            return NavCommand::Finish(
                Outcome::Timeout,
                format!("step budget of {} drive steps used up", self.config.max_steps),
            );
        }
        if self.steps_without_progress > self.config.patience {
            return NavCommand::Finish(
                Outcome::HelpRequested,
                format!("no progress toward the goal in {} steps", self.config.patience),
            );
        }
        self.need_sense = true;
        self.steps += 1;
        self.trail.push_back(here);
        let Some(choice) = self.choose(input) else {
            // Nothing is safe from here: look around by turning in place.
            self.last_motion = Some(Candidate::Turn { angle: 1.0 });
            return NavCommand::Turn { angle: 1.0 };
        };
        self.last_motion = Some(choice);
        match choice {
            Candidate::Arc { distance, curvature } => {
                if distance > 0.0 {
                    self.last_curvature = curvature;
                }
                NavCommand::Drive { distance, curvature, guard: DriveGuard::default() }
            }
            Candidate::Turn { angle } => NavCommand::Turn { angle },
        }
    }

    fn planned_path(&self) -> Vec<Point2> {
        self.dstar.as_ref().map(|f| f.path.clone()).unwrap_or_default()
    }

    fn overlays(&self) -> Vec<Overlay> {
        self.terrain.as_ref().map(TerrainModel::overlays).unwrap_or_default()
    }

    fn stats(&self) -> NavigatorStats {
        self.stats.clone()
    }
}

/// Registry entry: GESTALT alone or under Field D* (`gestalt`, `gestalt+field-dstar`).
pub const ENTRY: NavigatorEntry = NavigatorEntry {
    name: "gestalt",
    doc: "GESTALT arc voting on a goodness map, alone or with a Field D* waypoint vote (paper 003 section 2)",
    global_planners: &[
        Variant { global_planner: "none", label: "gestalt" },
        Variant { global_planner: "field-dstar", label: "gestalt+field-dstar" },
    ],
    params: || param_info(GestaltConfig::default(), GestaltConfig::params()),
    build: |b| {
        let field_dstar = b.global_planner == Some("field-dstar");
        let config =
            b.configured(GestaltConfig { field_dstar, ..Default::default() }, &GestaltConfig::params())?;
        Ok(Box::new(GestaltNavigator::new(b.label, b.rover.clone(), config)))
    },
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arc_pose_follows_a_circle() {
        // A quarter circle of radius 2 from the origin heading east ends at (2, 2) heading north.
        let p = arc_pose(Pose2::new(0.0, 0.0, 0.0), 0.5, std::f64::consts::PI);
        assert!((p.x - 2.0).abs() < 1e-9 && (p.y - 2.0).abs() < 1e-9);
        assert!((p.yaw - std::f64::consts::FRAC_PI_2).abs() < 1e-9);
    }

    #[test]
    fn keep_out_distance_of_a_square() {
        let square =
            vec![Point2::new(0.0, 0.0), Point2::new(1.0, 0.0), Point2::new(1.0, 1.0), Point2::new(0.0, 1.0)];
        let goal = Goal {
            position: Point2::new(5.0, 5.0),
            tolerance: 0.5,
            waypoints: vec![],
            keep_out: vec![square],
        };
        assert_eq!(keep_out_distance(&goal, Point2::new(0.5, 0.5)), 0.0);
        assert!((keep_out_distance(&goal, Point2::new(3.0, 0.5)) - 2.0).abs() < 1e-12);
        assert!((keep_out_distance(&goal, Point2::new(4.0, 5.0)) - 5.0).abs() < 1e-12);
    }

    #[test]
    fn flood_fill_sees_walls() {
        let g = GridGeometry { cols: 5, rows: 5, resolution: 1.0, origin_x: 0.0, origin_y: 0.0 };
        let mut costs = vec![1.0f32; 25];
        for r in 0..5 {
            costs[g.index(2, r)] = f32::INFINITY;
        }
        assert!(!reachable(&costs, g, Cell::new(0, 0), Cell::new(4, 4)));
        costs[g.index(2, 4)] = 1.0;
        assert!(reachable(&costs, g, Cell::new(0, 0), Cell::new(4, 4)));
    }
}
