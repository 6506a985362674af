//! The sensing-horizon reference: how close to the optimal path a rover can come when it knows
//! the terrain only within its sensing range.
//!
//! A navigator's path ratio (distance driven over the optimal length with full knowledge) mixes
//! two costs: what the rover could not know yet, and what its planner made of what it knew. The
//! reference isolates the first. It is an idealised rover: it senses the simulator's true hazard
//! map (the same one [`crate::optimal::optimal_length`] plans on) without noise or occlusion,
//! inside a disc (or a wedge about its heading) of the given radius, at every `step` metres of
//! its path; it remembers everything sensed, takes unsensed ground as free (the freespace
//! assumption) and drives the shortest path (Field D*) on that map, replanning whenever newly
//! sensed hazards cut the path it is on. Under the freespace assumption a newly sensed hazard
//! only ever lengthens paths, so a path nothing cuts stays the shortest and needs no replan.
//!
//! This is an evaluation tool, like the optimal length: it reads simulation truth on purpose and
//! is never part of the autonomy.

use crate::optimal::{OPTIMAL_PATH_RESOLUTION as RESOLUTION, optimal_length_on, true_hazard};
use rovernav_core::{Grid2, GridGeometry, Point2, angle_diff};
use rovernav_executive::World;
use rovernav_planning::{Cell, CellChange, CostGrid, FieldDStar, GlobalPlanner};

/// The reference rover's sensing and driving.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HorizonConfig {
    /// Sensing radius (m).
    pub range_m: f64,
    /// Field of view about the direction of travel (deg); 360 senses all around.
    pub fov_deg: f64,
    /// Distance driven between two sensings (m).
    pub step_m: f64,
    /// Margin the true hazard cells are grown by (m): the reference's share of a navigator's
    /// safety buffer.
    pub margin_m: f64,
    /// Fraction of the rover's belly clearance at which the reference's truth marks a step or
    /// belly hazard: its share of a navigator's hazard-detection margin.
    pub clearance_fraction: f64,
    /// Give up after this many metres driven (a guard; the reference always has a path when
    /// the optimal one exists).
    pub max_distance_m: f64,
}

impl Default for HorizonConfig {
    fn default() -> Self {
        Self {
            range_m: 5.0,
            fov_deg: 360.0,
            step_m: 1.0,
            margin_m: 0.0,
            clearance_fraction: 1.0,
            max_distance_m: 500.0,
        }
    }
}

impl HorizonConfig {
    /// Checks every setting is in range, naming the first that is not.
    pub fn validate(&self) -> Result<(), HorizonError> {
        let positive = |v: f64| v.is_finite() && v > 0.0;
        for (name, value) in
            [("range", self.range_m), ("step", self.step_m), ("distance limit", self.max_distance_m)]
        {
            if !positive(value) {
                return Err(HorizonError::Config(format!("{name} {value} m must be positive")));
            }
        }
        if !(self.margin_m.is_finite() && self.margin_m >= 0.0) {
            return Err(HorizonError::Config(format!("margin {} m must be >= 0", self.margin_m)));
        }
        if !(self.clearance_fraction > 0.0 && self.clearance_fraction <= 1.0) {
            return Err(HorizonError::Config(format!(
                "clearance fraction {} is outside (0, 1]",
                self.clearance_fraction
            )));
        }
        if !(self.fov_deg > 0.0 && self.fov_deg <= 360.0) {
            return Err(HorizonError::Config(format!(
                "field of view {} deg is outside (0, 360]",
                self.fov_deg
            )));
        }
        Ok(())
    }
}

/// One reference run.
#[derive(Clone, Debug, PartialEq)]
pub struct HorizonRun {
    /// Whether the reference came within the goal's tolerance.
    pub reached: bool,
    /// Distance driven (m).
    pub driven_m: f64,
    /// Plans made (the first one and every replan a newly sensed hazard forced).
    pub plans: usize,
    /// The optimal length with full knowledge of the unmodified truth (m), if a path exists:
    /// [`crate::optimal::optimal_length`], planned on the same hazard grid.
    pub optimal_m: Option<f64>,
    /// The path driven, start first (m, terrain frame).
    pub track: Vec<Point2>,
}

/// Why the reference could not run.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum HorizonError {
    /// A setting out of range.
    #[error("horizon reference: {0}")]
    Config(String),
    /// Start or goal off the terrain.
    #[error("horizon reference: the {0} lies outside the terrain")]
    OffTerrain(&'static str),
}

/// Drives the sensing-horizon reference from the world's start toward its goal.
pub fn horizon_reference(world: &World, config: &HorizonConfig) -> Result<HorizonRun, HorizonError> {
    config.validate()?;
    let exact = true_hazard(world);
    let optimal_m = optimal_length_on(world, &exact);
    let truth = if config.clearance_fraction == 1.0 {
        grow(&exact, config.margin_m)
    } else {
        let rover = rovernav_core::RoverConfig {
            clearance: world.rover.clearance * config.clearance_fraction,
            ..world.rover.clone()
        };
        grow(&rovernav_sim::true_hazard_grid(&world.terrain, &rover, RESOLUTION), config.margin_m)
    };
    let g = truth.geometry;
    let (start, goal) = (world.start.position(), world.goal.position);
    let start_cell = corner_cell(&g, start).ok_or(HorizonError::OffTerrain("start"))?;
    let goal_cell = corner_cell(&g, goal).ok_or(HorizonError::OffTerrain("goal"))?;
    let mut known = Grid2::filled(g, false);
    let mut grid = CostGrid::uniform(g.rows, g.cols, 1.0).expect("a non-empty grid");
    grid.set_geometry(g);
    let mut planner = FieldDStar::new();
    planner.set_grid(grid);

    let mut x = start;
    let mut heading = goal.sub(start).angle();
    let mut track = vec![x];
    let mut driven = 0.0;
    let mut reached = x.dist(goal) <= world.goal.tolerance;
    let mut plans = 0;
    let mut path: Vec<Point2> = Vec::new();
    // The start and goal pads are safe by construction, as for the optimal length.
    let pads = [start_cell, goal_cell];
    while !reached && driven < config.max_distance_m {
        let changes = sense(&truth, &mut known, x, heading, config, &pads);
        if !changes.is_empty() {
            planner.update_cells(&changes).expect("cells inside the grid");
        }
        // The planner's grid holds every hazard sensed so far: the path is cut when it now
        // costs infinity on Field D*'s own segment model.
        let grid = planner.grid().expect("the grid set above");
        let in_grid = |p: Point2| grid.world_to_grid(p);
        let cut = !changes.is_empty()
            && !grid.polyline_cost(&path.iter().map(|&p| in_grid(p)).collect::<Vec<_>>()).is_finite();
        if path.len() < 2 || cut {
            let from = corner_cell(&g, x).ok_or(HorizonError::OffTerrain("rover"))?;
            let plan = if plans == 0 {
                planner.plan(from, goal_cell)
            } else {
                planner.move_start(from).and_then(|()| planner.replan())
            };
            let Ok(plan) = plan else { break };
            plans += 1;
            let grid = planner.grid().expect("the grid set above");
            let mut points: Vec<Point2> = plan.points.iter().map(|&p| grid.grid_to_world(p)).collect();
            points.push(goal);
            // The plan starts at the lattice corner nearest the rover: join the rover straight
            // to a later point of the plan when nothing known blocks the way, so that snapping
            // to the lattice adds no length.
            let free =
                |p: Point2| grid.segment_cost(grid.world_to_grid(x), grid.world_to_grid(p)).is_finite();
            let skip = (1..points.len().min(4)).rev().find(|&i| free(points[i])).unwrap_or(0);
            path = std::iter::once(x).chain(points.into_iter().skip(skip)).collect();
            path.dedup_by(|a, b| a.dist(*b) < 1e-9);
            if path.len() < 2 {
                break;
            }
        }
        // Drive `step` metres along the path, or until within the goal's tolerance.
        let mut left = config.step_m;
        while left > 1e-9 && path.len() >= 2 {
            let next = path[1];
            let d = x.dist(next);
            let arrival = goal_tolerance_crossing(x, next, goal, world.goal.tolerance).filter(|&t| t <= left);
            let stop = arrival.unwrap_or(d.min(left));
            if d > 1e-9 {
                let dir = next.sub(x);
                heading = dir.angle();
                x = if stop >= d {
                    next
                } else {
                    Point2::new(x.x + dir.x * stop / d, x.y + dir.y * stop / d)
                };
            }
            driven += stop.min(d);
            left -= stop.min(d).max(1e-9);
            track.push(x);
            if arrival.is_some() {
                reached = true;
                break;
            }
            if stop >= d {
                path.remove(0);
            } else {
                path[0] = x;
            }
        }
        if reached {
            break;
        }
    }
    Ok(HorizonRun { reached, driven_m: driven, plans, optimal_m, track })
}

/// The true hazard cells grown by `margin` (see [`Grid2::dilate_into`]).
fn grow(mask: &Grid2<bool>, margin: f64) -> Grid2<bool> {
    if margin <= 0.0 {
        return mask.clone();
    }
    let mut out = mask.clone();
    mask.dilate_into(margin, &mut out);
    out
}

/// The lattice cell whose corner Field D* starts from for a point (the nearest corner).
fn corner_cell(g: &GridGeometry, p: Point2) -> Option<Cell> {
    let col = ((p.x - g.origin_x) / g.resolution).round();
    let row = ((p.y - g.origin_y) / g.resolution).round();
    let inside = col >= 0.0 && row >= 0.0 && (col as usize) < g.cols && (row as usize) < g.rows;
    inside.then(|| Cell::new(row as usize, col as usize))
}

/// Senses the true hazard map around `x`; returns the newly known hazard cells as cost changes.
fn sense(
    truth: &Grid2<bool>,
    known: &mut Grid2<bool>,
    x: Point2,
    heading: f64,
    config: &HorizonConfig,
    pads: &[Cell],
) -> Vec<CellChange> {
    let g = truth.geometry;
    let half_fov = config.fov_deg.to_radians() / 2.0;
    let r = (config.range_m / g.resolution).ceil() as i64 + 1;
    let (c0, r0) = (((x.x - g.origin_x) / g.resolution) as i64, ((x.y - g.origin_y) / g.resolution) as i64);
    let mut changes = Vec::new();
    for row in (r0 - r).max(0)..=(r0 + r).min(g.rows as i64 - 1) {
        for col in (c0 - r).max(0)..=(c0 + r).min(g.cols as i64 - 1) {
            let (col, row) = (col as usize, row as usize);
            if *known.get(col, row) {
                continue;
            }
            let (cx, cy) = g.center(col, row);
            let d = Point2::new(cx, cy).sub(x);
            if d.norm() > config.range_m {
                continue;
            }
            if config.fov_deg < 360.0 && d.norm() > 1e-9 && angle_diff(d.angle(), heading).abs() > half_fov {
                continue;
            }
            *known.get_mut(col, row) = true;
            let cell = Cell::new(row, col);
            if *truth.get(col, row) && !pads.contains(&cell) {
                changes.push(CellChange { cell, cost: f32::INFINITY });
            }
        }
    }
    changes
}

/// Distance along a-b at which the rover first comes within `tolerance` of the goal, if it does.
fn goal_tolerance_crossing(a: Point2, b: Point2, goal: Point2, tolerance: f64) -> Option<f64> {
    let d = b.sub(a);
    let len = d.norm();
    if len < 1e-12 {
        return None;
    }
    let u = Point2::new(d.x / len, d.y / len);
    let f = a.sub(goal);
    // |f + t u|^2 = tol^2: t^2 + 2 (f.u) t + |f|^2 - tol^2 = 0.
    let bq = f.x * u.x + f.y * u.y;
    let cq = f.x * f.x + f.y * f.y - tolerance * tolerance;
    let disc = bq * bq - cq;
    if disc < 0.0 {
        return None;
    }
    let t = -bq - disc.sqrt();
    (t >= 0.0 && t <= len).then_some(t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rovernav_core::{Goal, Pose2, RoverConfig};
    use rovernav_sim::SensorModel;
    use rovernav_terrain::procedural::add_rocks;
    use rovernav_terrain::{Dem, Rock, Terrain};

    /// A flat 0.05 m DEM of `size` metres with 0.35 m rock domes at `rocks` (x, y, diameter).
    fn world(size: (f64, f64), rocks: &[(f64, f64, f64)], start: Point2, goal: Point2) -> World {
        let rocks: Vec<Rock> =
            rocks.iter().map(|&(x, y, diameter)| Rock { x, y, diameter, height: 0.35 }).collect();
        let mut dem = Dem::flat((size.0 / 0.05) as usize, (size.1 / 0.05) as usize, 0.05, 0.0);
        add_rocks(&mut dem, &rocks);
        World {
            terrain: Terrain { dem, rocks },
            rover: RoverConfig::default(),
            sensor_model: SensorModel::default(),
            start: Pose2::new(start.x, start.y, 0.0),
            goal: Goal { position: goal, tolerance: 0.3, waypoints: vec![], keep_out: vec![] },
        }
    }

    /// A U of rocks open toward a start on its left, the goal beyond its back wall.
    fn u_trap() -> World {
        let mut rocks: Vec<(f64, f64, f64)> = (0..8).map(|i| (9.5, 4.0 + 1.1 * i as f64, 0.6)).collect();
        for i in 0..4 {
            rocks.push((5.1 + 1.1 * i as f64, 4.0, 0.6));
            rocks.push((5.1 + 1.1 * i as f64, 11.7, 0.6));
        }
        world((18.0, 16.0), &rocks, Point2::new(2.0, 7.85), Point2::new(15.0, 7.85))
    }

    fn with_range(range_m: f64) -> HorizonConfig {
        HorizonConfig { range_m, ..Default::default() }
    }

    #[test]
    fn open_ground_is_driven_straight_to_the_goal_tolerance() {
        let (a, b) = (Point2::new(2.0, 3.0), Point2::new(12.0, 7.0));
        let w = world((14.0, 10.0), &[], a, b);
        let run = horizon_reference(&w, &with_range(3.0)).unwrap();
        assert!(run.reached);
        assert_eq!(run.plans, 1, "nothing sensed cuts the first path");
        let straight = a.dist(b) - w.goal.tolerance;
        assert!((run.driven_m - straight).abs() < 1e-6, "driven {} against {straight}", run.driven_m);
    }

    #[test]
    fn a_u_trap_costs_a_short_horizon_a_detour_and_a_long_one_nothing() {
        let w = u_trap();
        let optimal = crate::optimal::optimal_length(&w).expect("a path around the U");
        let far = horizon_reference(&w, &with_range(40.0)).unwrap();
        let near = horizon_reference(&w, &with_range(2.0)).unwrap();
        assert!(far.reached && near.reached);
        // Knowing everything, the reference drives the optimal path (to the goal's tolerance;
        // the two Field D* runs differ by their lattice snapping only).
        let ratio = far.driven_m / (optimal - w.goal.tolerance);
        assert!((0.98..1.02).contains(&ratio), "full-knowledge ratio {ratio}");
        // Seeing 2 m, it drives into the U before it sees the back wall.
        assert!(near.driven_m > 1.2 * optimal, "near {} against optimal {optimal}", near.driven_m);
        let deepest = near.track.iter().map(|p| p.x).fold(f64::MIN, f64::max);
        assert!(deepest > 6.5, "never entered the U (deepest x {deepest})");
        assert!(near.plans > far.plans);
    }

    #[test]
    fn the_track_never_enters_a_true_hazard_cell() {
        let w = u_trap();
        let truth = rovernav_sim::true_hazard_grid(&w.terrain, &w.rover, RESOLUTION);
        let g = truth.geometry;
        let wedge = |range_m| HorizonConfig { range_m, fov_deg: 45.0, ..Default::default() };
        for (range, config) in
            [1.5, 2.0, 3.0, 5.0].map(|r| (r, with_range(r))).into_iter().chain([(3.0, wedge(3.0))])
        {
            let run = horizon_reference(&w, &config).unwrap();
            assert!(run.reached, "range {range}");
            for seg in run.track.windows(2) {
                let n = (seg[0].dist(seg[1]) / 0.01).ceil().max(1.0) as usize;
                for i in 0..=n {
                    let t = i as f64 / n as f64;
                    let p = Point2::new(
                        seg[0].x + (seg[1].x - seg[0].x) * t,
                        seg[0].y + (seg[1].y - seg[0].y) * t,
                    );
                    // Inside a hazard cell, not on its edge (Field D* runs along cell edges).
                    let (c, r) = g.cell_of(p.x, p.y).expect("on the terrain");
                    let (cx, cy) = g.center(c, r);
                    let inside = (p.x - cx).abs().max((p.y - cy).abs()) < 0.5 * g.resolution - 1e-6;
                    assert!(
                        !(inside && *truth.get(c, r)),
                        "range {range}: ({:.3}, {:.3}) is inside a true hazard cell",
                        p.x,
                        p.y
                    );
                }
            }
        }
    }

    #[test]
    fn a_margin_keeps_the_track_farther_from_the_rocks() {
        let w = u_trap();
        let disc = horizon_reference(&w, &with_range(3.0)).unwrap();
        let rock_clearance = |run: &HorizonRun| {
            run.track
                .iter()
                .flat_map(|p| w.terrain.rocks.iter().map(move |r| p.dist(Point2::new(r.x, r.y))))
                .fold(f64::INFINITY, f64::min)
        };
        let wide = horizon_reference(&w, &HorizonConfig { margin_m: 0.3, ..with_range(3.0) }).unwrap();
        assert!(rock_clearance(&wide) > rock_clearance(&disc) + 0.2);
    }

    #[test]
    fn settings_out_of_range_are_named() {
        let w = u_trap();
        for (config, what) in [
            (HorizonConfig { range_m: 0.0, ..Default::default() }, "range"),
            (HorizonConfig { step_m: f64::NAN, ..Default::default() }, "step"),
            (HorizonConfig { fov_deg: 400.0, ..Default::default() }, "field of view"),
            (HorizonConfig { margin_m: -1.0, ..Default::default() }, "margin"),
            (HorizonConfig { clearance_fraction: 0.0, ..Default::default() }, "clearance fraction"),
        ] {
            let e = horizon_reference(&w, &config).unwrap_err().to_string();
            assert!(e.contains(what), "{e}");
        }
    }
}
