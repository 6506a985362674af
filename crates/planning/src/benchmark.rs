//! The logic behind `rovernav bench`: MovingAI scenario runs checked against the published
//! optimal lengths, and an incremental-replanning event sequence on a cost map. Inputs are
//! parsed values (the CLI reads the files); results are plain structs.

use crate::movingai::{MovingAiMap, Scenario, check_scenarios};
use crate::{Cell, CellChange, CostGrid, GlobalPlanner, ParseError, PlanError, planner_by_name};
use std::time::Instant;

/// Why a benchmark could not run.
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    /// The planner name is not registered.
    #[error("unknown planner `{0}` (known: astar, astar-corners, dstar-lite, field-dstar)")]
    UnknownPlanner(String),
    /// A planner failed where a path must exist.
    #[error("{event}: {source}")]
    Plan {
        /// Which step failed.
        event: String,
        /// The planner's error.
        source: PlanError,
    },
    /// A file or argument did not parse.
    #[error(transparent)]
    Parse(#[from] ParseError),
}

/// Summary of a MovingAI run.
#[derive(Clone, Debug, PartialEq)]
pub struct MovingAiReport {
    /// Planner name.
    pub planner: String,
    /// Map label.
    pub map: String,
    /// Graph label (`cell-centres` / `corner-nodes`).
    pub graph: &'static str,
    /// Scenarios run.
    pub scenarios: usize,
    /// Scenarios with a path.
    pub solved: usize,
    /// Scenarios failing the check: cell-centre planners `|cost - optimal| > 1e-4`; corner
    /// planners cost more than 1 % above the optimum or below the straight line; unsolved ones.
    pub mismatches: usize,
    /// Mean of cost / published optimum over solved scenarios.
    pub mean_cost_ratio: f64,
    /// Largest cost / optimum.
    pub max_cost_ratio: f64,
    /// Smallest cost / straight-line distance (>= 1 when no path beats the straight line).
    pub min_straight_ratio: f64,
    /// Mean wall time per `plan` call (microseconds).
    pub mean_us_per_query: f64,
    /// Total node expansions.
    pub expansions: u64,
}

/// Runs every `stride`-th scenario (1 = all) with a fresh planner of the given name on the map.
pub fn run_movingai(
    map: &MovingAiMap,
    map_label: &str,
    scenarios: &[Scenario],
    planner_name: &str,
    stride: usize,
) -> Result<MovingAiReport, BenchError> {
    check_scenarios(map, scenarios)?;
    let mut planner =
        planner_by_name(planner_name).ok_or_else(|| BenchError::UnknownPlanner(planner_name.into()))?;
    planner.set_grid(map.cost_grid());
    let graph = planner.graph();
    let mut report = MovingAiReport {
        planner: planner.name().to_string(),
        map: map_label.to_string(),
        graph: graph.label(),
        scenarios: 0,
        solved: 0,
        mismatches: 0,
        mean_cost_ratio: 0.0,
        max_cost_ratio: 0.0,
        min_straight_ratio: f64::INFINITY,
        mean_us_per_query: 0.0,
        expansions: 0,
    };
    let mut ratio_sum = 0.0;
    let mut seconds = 0.0;
    for s in scenarios.iter().step_by(stride.max(1)) {
        report.scenarios += 1;
        let t0 = Instant::now();
        let result = planner.plan(s.start, s.goal);
        seconds += t0.elapsed().as_secs_f64();
        let Ok(plan) = result else {
            report.mismatches += 1;
            continue;
        };
        report.solved += 1;
        report.expansions += plan.expansions as u64;
        let ratio = if s.optimal > 0.0 { plan.cost / s.optimal } else { 1.0 };
        ratio_sum += ratio;
        report.max_cost_ratio = report.max_cost_ratio.max(ratio);
        let straight = s.start.center().dist(s.goal.center());
        if straight > 0.0 {
            report.min_straight_ratio = report.min_straight_ratio.min(plan.cost / straight);
        }
        let bad = match graph {
            crate::GraphKind::CellCentres => (plan.cost - s.optimal).abs() > 1e-4,
            crate::GraphKind::CornerNodes => {
                plan.cost > s.optimal * 1.01 + 1e-9 || plan.cost < straight - 1e-9
            }
        };
        if bad {
            report.mismatches += 1;
        }
    }
    if report.solved > 0 {
        report.mean_cost_ratio = ratio_sum / report.solved as f64;
    }
    if report.scenarios > 0 {
        report.mean_us_per_query = seconds * 1e6 / report.scenarios as f64;
    }
    Ok(report)
}

/// One step of the replanning event sequence.
#[derive(Clone, Debug, PartialEq)]
pub struct GridEvent {
    /// `initial`, `obstacle`, `move-start` or `fresh`.
    pub name: &'static str,
    /// Wall time of the (re)plan (ms).
    pub ms: f64,
    /// Node expansions of the (re)plan.
    pub expansions: usize,
    /// Cost of the returned path ([`crate::Plan::cost`]).
    pub cost: f64,
    /// The planner's value at the start ([`crate::Plan::value`]).
    pub value: f64,
    /// Start cell of this plan.
    pub start: Cell,
}

/// The replanning event sequence's results.
#[derive(Clone, Debug, PartialEq)]
pub struct GridReport {
    /// Planner name.
    pub planner: String,
    /// Graph label.
    pub graph: &'static str,
    /// Events in order: initial plan, obstacle block dropped on the path (replan), start moved
    /// (replan), fresh plan by a new planner instance on the changed map.
    pub events: Vec<GridEvent>,
    /// The cells turned into obstacles.
    pub obstacle: Vec<Cell>,
}

/// Side of the square obstacle block dropped on the path.
pub const OBSTACLE_BLOCK: usize = 10;
/// How many path points the start advances.
pub const START_ADVANCE: usize = 10;

fn timed(
    planner: &mut dyn GlobalPlanner,
    name: &'static str,
    start: Cell,
    run: impl FnOnce(&mut dyn GlobalPlanner) -> Result<crate::Plan, PlanError>,
) -> Result<(GridEvent, crate::Plan), BenchError> {
    let t0 = Instant::now();
    let plan = run(planner).map_err(|source| BenchError::Plan { event: name.to_string(), source })?;
    let ms = t0.elapsed().as_secs_f64() * 1e3;
    Ok((GridEvent { name, ms, expansions: plan.expansions, cost: plan.cost, value: plan.value, start }, plan))
}

/// The cells of the obstacle block centred on the point a third of the way along `points`,
/// clipped to the grid and sparing the start and goal cells.
pub fn obstacle_block(
    grid: &CostGrid,
    points: &[rovernav_core::Point2],
    start: Cell,
    goal: Cell,
) -> Vec<Cell> {
    let Some(&p) = points.get(points.len() / 3) else {
        return Vec::new();
    };
    let Some(centre) = Cell::containing(p) else {
        return Vec::new();
    };
    let half = OBSTACLE_BLOCK / 2;
    let r0 = centre.row.saturating_sub(half);
    let c0 = centre.col.saturating_sub(half);
    let mut cells = Vec::new();
    for row in r0..(r0 + OBSTACLE_BLOCK).min(grid.rows()) {
        for col in c0..(c0 + OBSTACLE_BLOCK).min(grid.cols()) {
            let cell = Cell::new(row, col);
            if cell != start && cell != goal {
                cells.push(cell);
            }
        }
    }
    cells
}

/// Runs the event sequence: initial plan; a 10x10 obstacle block dropped on the path a third of
/// the way along (replan on the same instance); start moved 10 path points along (replan); a
/// fresh plan by a new instance on the changed map from the moved start.
pub fn run_grid_events(
    grid: &CostGrid,
    start: Cell,
    goal: Cell,
    planner_name: &str,
) -> Result<GridReport, BenchError> {
    let unknown = || BenchError::UnknownPlanner(planner_name.into());
    let mut planner = planner_by_name(planner_name).ok_or_else(unknown)?;
    planner.set_grid(grid.clone());
    let (initial, plan) = timed(planner.as_mut(), "initial", start, |p| p.plan(start, goal))?;

    let obstacle = obstacle_block(grid, &plan.points, start, goal);
    let changes: Vec<CellChange> =
        obstacle.iter().map(|&cell| CellChange { cell, cost: f32::INFINITY }).collect();
    let (blocked, plan) = timed(planner.as_mut(), "obstacle", start, |p| {
        p.update_cells(&changes)?;
        p.replan()
    })?;

    let advanced = plan.points[START_ADVANCE.min(plan.points.len() - 1)];
    let new_start = Cell::containing(advanced)
        .map(|c| Cell::new(c.row.min(grid.rows() - 1), c.col.min(grid.cols() - 1)))
        .unwrap_or(start);
    let (moved, _) = timed(planner.as_mut(), "move-start", new_start, |p| {
        p.move_start(new_start)?;
        p.replan()
    })?;

    let changed = planner
        .grid()
        .cloned()
        .ok_or_else(|| BenchError::Plan { event: "fresh".into(), source: PlanError::NoGrid })?;
    let mut fresh_planner = planner_by_name(planner_name).ok_or_else(unknown)?;
    fresh_planner.set_grid(changed);
    let (fresh, _) = timed(fresh_planner.as_mut(), "fresh", new_start, |p| p.plan(new_start, goal))?;
    Ok(GridReport {
        planner: planner.name().to_string(),
        graph: planner.graph().label(),
        events: vec![initial, blocked, moved, fresh],
        obstacle,
    })
}

/// Parses `ROW,COL`.
pub fn parse_cell(text: &str) -> Result<Cell, String> {
    let mut parts = text.split(',').map(str::trim);
    match (parts.next(), parts.next(), parts.next()) {
        (Some(r), Some(c), None) => match (r.parse(), c.parse()) {
            (Ok(row), Ok(col)) => Ok(Cell::new(row, col)),
            _ => Err(format!("expected ROW,COL with non-negative integers, got `{text}`")),
        },
        _ => Err(format!("expected ROW,COL, got `{text}`")),
    }
}

/// Decodes a grid file's bytes: a binary PGM cost map (`P5` magic) or a MovingAI `.map`.
pub fn parse_grid_file(bytes: &[u8]) -> Result<CostGrid, ParseError> {
    if bytes.starts_with(b"P5") {
        crate::pgm::parse_cost_map(bytes)
    } else {
        let text = std::str::from_utf8(bytes)
            .map_err(|e| ParseError::whole(format!("neither a P5 PGM nor UTF-8 text: {e}")))?;
        Ok(crate::movingai::parse_map(text)?.cost_grid())
    }
}

/// Side of the local terrain window MRPTA senses around the rover (paper 004 section 3.3).
pub const LOCAL_WINDOW: usize = 121;

/// A 121x121 window of newly sensed terrain centred 40 cells ahead (row and column) of `rover`,
/// clipped to the grid: with `changed`, every cost doubled and a row of obstacles across it
/// (25 cells blocked in every 30, so the path must bend); without, the grid's own costs (the
/// update that undoes it).
pub fn window_update(grid: &CostGrid, rover: Cell, changed: bool) -> Vec<CellChange> {
    let centre_row = (rover.row + 40).min(grid.rows().saturating_sub(1));
    let centre_col = (rover.col + 40).min(grid.cols().saturating_sub(1));
    let r0 = centre_row.saturating_sub(LOCAL_WINDOW / 2);
    let c0 = centre_col.saturating_sub(LOCAL_WINDOW / 2);
    let mut changes = Vec::with_capacity(LOCAL_WINDOW * LOCAL_WINDOW);
    for row in r0..(r0 + LOCAL_WINDOW).min(grid.rows()) {
        for col in c0..(c0 + LOCAL_WINDOW).min(grid.cols()) {
            let cell = Cell::new(row, col);
            let base = grid.cost(cell);
            let cost = if !changed {
                base
            } else if row == centre_row && (col - c0) % 30 < 25 {
                f32::INFINITY
            } else {
                base * 2.0
            };
            changes.push(CellChange { cell, cost });
        }
    }
    changes
}
