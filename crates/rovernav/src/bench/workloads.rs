//! The workloads of `rovernav bench report`, one function per group of rows. Each runs
//! rovernav's implementation and its baseline on the same input in this process and checks
//! that they agree (path costs, optima, distances) before reporting times.

use super::edt::{chamfer_3_4, felzenszwalb_huttenlocher, random_occupancy};
use super::report::{Row, alternate};
use anyhow::{Context, anyhow, ensure};
use rovernav_executive::{Mission, Run};
use rovernav_harness::JudgedRun;
use rovernav_localization::benchmark::{
    MatcherWorkload, compare, localisation_workload, scan_window_workload,
};
use rovernav_localization::matching::distance_transform::squared_distance_3d;
use rovernav_planning::baseline::pathfinding_cost;
use rovernav_planning::benchmark::window_update;
use rovernav_planning::pgm::parse_cost_map;
use rovernav_planning::{AStar, Cell, CostGrid, DStarLite, FieldDStar, GlobalPlanner, GraphKind};
use serde_json::json;
use std::time::Instant;

/// The data README's reference cost of Field D* on map1000.
pub const FIELD_DSTAR_MAP1000_REFERENCE: f64 = 24145.3;

/// Reads `costmaps/NAME.pgm` from the data directory.
pub fn cost_map(name: &str) -> anyhow::Result<CostGrid> {
    let path = rovernav_core::data_dir().join(format!("costmaps/{name}.pgm"));
    let bytes = std::fs::read(&path).with_context(|| {
        format!("{}: cannot read (set ROVERNAV_DATA to the data directory)", path.display())
    })?;
    parse_cost_map(&bytes).map_err(|e| anyhow!(e.in_file(path.display().to_string())))
}

/// The README's query on an N x N map: (N/10, N/10) to (N-1-N/10, N-1-N/10).
fn readme_query(grid: &CostGrid) -> (Cell, Cell) {
    let n = grid.rows();
    (Cell::new(n / 10, n / 10), Cell::new(n - 1 - n / 10, n - 1 - n / 10))
}

/// `astar-map1000` and `dijkstra-map1000`: rovernav's A* (and Dijkstra) against the
/// `pathfinding` crate on the identical graph; equal path costs asserted.
pub fn graph_search(grid: &CostGrid, reps: usize) -> anyhow::Result<Vec<Row>> {
    let (s, t) = readme_query(grid);
    let mut rows = Vec::new();
    for informed in [true, false] {
        let mut ours = if informed {
            AStar::new(GraphKind::CellCentres)
        } else {
            AStar::dijkstra(GraphKind::CellCentres)
        };
        ours.set_grid(grid.clone());
        let theirs = || pathfinding_cost(grid, s, t, informed).unwrap_or(f64::INFINITY);
        let (times, plan, base) = alternate(reps, || ours.plan(s, t), theirs);
        let plan = plan.map_err(|e| anyhow!("map1000: {e}"))?;
        ensure!(
            (plan.cost - base).abs() <= 1e-9 * base,
            "map1000: rovernav's path costs {} but pathfinding's {base}",
            plan.cost
        );
        let (workload, what, theirs_name) = if informed {
            ("astar-map1000", "A* (octile, cell centres)", "pathfinding::astar, same graph")
        } else {
            ("dijkstra-map1000", "Dijkstra (cell centres)", "pathfinding::dijkstra, same graph")
        };
        rows.push(
            Row::timed(
                workload,
                what,
                theirs_name,
                times,
                "binary-heap pops (one dependent key load and comparison per level) and random access to 1M-node arrays (memory latency)",
            )
            .costs(plan.cost, base)
            .details(json!({
                "expansions": plan.expansions,
                "ns_per_expansion": times.0 * 1e9 / plan.expansions.max(1) as f64,
                "target_speedup": if informed { Some(4.0) } else { None },
            })),
        );
    }
    Ok(rows)
}

/// A planner per repetition, its grid already set (so that only the search is timed).
fn fresh<P: GlobalPlanner>(reps: usize, grid: &CostGrid, make: impl Fn() -> P) -> Vec<P> {
    (0..reps)
        .map(|_| {
            let mut p = make();
            p.set_grid(grid.clone());
            p
        })
        .collect()
}

/// `field-dstar-map1000`: Field D* from scratch against A* on the corner-node graph (the
/// 8-connected optimum it improves on), cost against the README reference.
pub fn field_dstar(grid: &CostGrid, reps: usize) -> anyhow::Result<Row> {
    let (s, t) = readme_query(grid);
    let mut ours = fresh(reps, grid, FieldDStar::new);
    let mut base = fresh(reps, grid, || AStar::new(GraphKind::CornerNodes));
    let (times, plan, corner) = alternate(
        reps,
        || ours.pop().expect("one per repetition").plan(s, t),
        || base.pop().expect("one per repetition").plan(s, t),
    );
    let (plan, corner) =
        (plan.map_err(|e| anyhow!("map1000: {e}"))?, corner.map_err(|e| anyhow!("map1000: {e}"))?);
    let off = plan.cost / FIELD_DSTAR_MAP1000_REFERENCE - 1.0;
    ensure!(
        off.abs() <= 1e-3,
        "map1000: Field D* path costs {} ({:+.3} % from the reference {FIELD_DSTAR_MAP1000_REFERENCE})",
        plan.cost,
        100.0 * off
    );
    Ok(Row::timed(
        "field-dstar-map1000",
        "Field D* from scratch (interpolated, corner nodes)",
        "A* on the corner-node graph (rovernav astar-corners)",
        times,
        "the interpolated triangles' square roots and divisions (up to 16 triangles per expansion; a cut across a cell is skipped when a lower bound cannot win) and the D* Lite key/heap work",
    )
    .costs(plan.cost, corner.cost)
    .details(json!({
        "expansions": plan.expansions,
        "us_per_expansion": times.0 * 1e6 / plan.expansions.max(1) as f64,
        "reference_cost": FIELD_DSTAR_MAP1000_REFERENCE,
        "cost_vs_reference_percent": 100.0 * off,
        "target_us_per_expansion": 0.25,
    })))
}

/// `dstar-lite-replan-map1000`: D* Lite repairing its search after a 121x121 window near the
/// rover changes, against A* from scratch on the changed map; equal costs asserted.
pub fn dstar_lite_replan(grid: &CostGrid, reps: usize) -> anyhow::Result<Row> {
    let (start, goal) = (Cell::new(100, 100), Cell::new(899, 899));
    let change = window_update(grid, start, true);
    let undo = window_update(grid, start, false);
    let mut changed = grid.clone();
    changed.apply(&change).map_err(|e| anyhow!("map1000 window: {e}"))?;
    let mut lite = DStarLite::new();
    lite.set_grid(grid.clone());
    lite.plan(start, goal).map_err(|e| anyhow!("map1000: {e}"))?;
    let mut astar = AStar::new(GraphKind::CellCentres);
    astar.set_grid(changed);
    let (mut t_ours, mut t_base) = (f64::INFINITY, f64::INFINITY);
    let (mut replanned, mut scratch) = (None, None);
    for _ in 0..reps.max(1) {
        let t0 = Instant::now();
        lite.update_cells(&change).map_err(|e| anyhow!("{e}"))?;
        let plan = lite.replan().map_err(|e| anyhow!("map1000 replan: {e}"))?;
        t_ours = t_ours.min(t0.elapsed().as_secs_f64());
        replanned = Some(plan);
        // Back to the unchanged map, untimed, so that every repetition repairs the same change.
        lite.update_cells(&undo).map_err(|e| anyhow!("{e}"))?;
        lite.replan().map_err(|e| anyhow!("map1000 replan: {e}"))?;
        let t0 = Instant::now();
        let plan = astar.plan(start, goal).map_err(|e| anyhow!("map1000 changed: {e}"))?;
        t_base = t_base.min(t0.elapsed().as_secs_f64());
        scratch = Some(plan);
    }
    let (replanned, scratch) = (replanned.expect("ran"), scratch.expect("ran"));
    ensure!(
        (replanned.cost - scratch.cost).abs() <= 1e-9 * scratch.cost,
        "map1000: D* Lite's repaired path costs {} but A* from scratch finds {}",
        replanned.cost,
        scratch.cost
    );
    Ok(Row::timed(
        "dstar-lite-replan-map1000",
        "D* Lite update + replan after a 121x121 change near the rover",
        "A* from scratch on the changed map (rovernav astar)",
        (t_ours, t_base),
        "nodes whose values the change invalidates (the region behind the new obstacles), each re-expanded",
    )
    .costs(replanned.cost, scratch.cost)
    .details(json!({
        "changed_cells": change.len(),
        "replan_expansions": replanned.expansions,
        "scratch_expansions": scratch.expansions,
        "target_speedup": 10.0,
    })))
}

/// A matcher row from [`rovernav_localization::benchmark`]'s workload: branch and bound
/// (`repeats` times, the fastest kept) against exhaustive search of the same poses (once), the
/// best score required identical.
fn matcher_row(
    workload: &'static str,
    w: &MatcherWorkload,
    repeats: usize,
    limits: &str,
) -> anyhow::Result<Row> {
    let c = compare(w, repeats).map_err(|e| anyhow!("{workload}: {e}"))?;
    ensure!(
        c.same_optimum(),
        "{workload}: branch and bound's best score {} differs from exhaustive search's {}",
        c.rovernav.score,
        c.exhaustive.score
    );
    let what = if w.full_match { "full match: search, peak fit, failure search" } else { "search only" };
    Ok(Row::timed(
        workload,
        &format!("ML map matcher, branch and bound ({what})"),
        "exhaustive search of the same pose lattice",
        (c.rovernav.seconds, c.exhaustive.seconds),
        limits,
    )
    .costs(c.rovernav.score, c.exhaustive.score)
    .details(json!({
        "cost_is": "log-likelihood score of the best lattice pose",
        "optimum_identical": true,
        "lattice_poses": c.rovernav.lattice_poses,
        "poses_evaluated": c.rovernav.poses_evaluated,
        "boxes": c.rovernav.boxes,
        "exhaustive_poses_evaluated": c.exhaustive.poses_evaluated,
        "error_to_truth_m": c.rovernav.error_m(&w.truth),
        "matches_per_s": 1.0 / c.rovernav.seconds.max(1e-12),
    })))
}

/// `matcher-localisation`: the map-matching localiser's workload (`localisation_workload`).
pub fn matcher_localisation(quick: bool) -> anyhow::Result<Row> {
    let w = localisation_workload().map_err(|e| anyhow!("matcher-localisation: {e}"))?;
    matcher_row(
        "matcher-localisation",
        &w,
        if quick { 1 } else { 3 },
        "distance-transform lookups of the boxes bounded (every known local cell), the peak fit and the failure search",
    )
}

/// `matcher-scan-window`: about 340 points at 5 cm, a +-7 m, +-30 deg window
/// (`scan_window_workload`, Cartographer's defaults).
pub fn matcher_scan_window(quick: bool) -> anyhow::Result<Row> {
    let w = scan_window_workload().map_err(|e| anyhow!("matcher-scan-window: {e}"))?;
    let mut row = matcher_row(
        "matcher-scan-window",
        &w,
        if quick { 1 } else { 3 },
        "boxes bounded before the optimum's score prunes the rest; exhaustive search scores every lattice pose x 340 cells",
    )?;
    row.details["target_s"] = json!(0.034);
    Ok(row)
}

/// `edt-4096`: rovernav's exact EDT (localization's Meijster-Roerdink-Hesselink transform) against the
/// straightforward Felzenszwalb-Huttenlocher transform and a 3-4 chamfer, on a 2 % occupied grid.
pub fn edt(quick: bool) -> anyhow::Result<Row> {
    let reps = if quick { 1 } else { 3 };
    let mut details = serde_json::Map::new();
    let mut main = None;
    for side in [1024usize, 4096] {
        let occ = random_occupancy(side, side, 0.02, 43);
        let cells = (side * side) as f64;
        let ((t_ours, t_base), ours, exact) = alternate(
            reps,
            || squared_distance_3d(&occ, side, side, 1, u16::MAX),
            || felzenszwalb_huttenlocher(&occ, side, side),
        );
        if let Some(i) =
            ours.iter().zip(&exact).position(|(&a, &b)| f64::from(a) != b.min(f64::from(u16::MAX)))
        {
            return Err(anyhow!("edt {side}: cell {i}: rovernav {} vs exact baseline {}", ours[i], exact[i]));
        }
        let ((t_chamfer, _), _, ()) = alternate(reps, || chamfer_3_4(&occ, side, side), || ());
        details.insert(
            format!("ns_per_cell_{side}"),
            json!({
                "rovernav_exact": t_ours * 1e9 / cells,
                "felzenszwalb_huttenlocher": t_base * 1e9 / cells,
                "chamfer_3_4": t_chamfer * 1e9 / cells,
            }),
        );
        main = Some((t_ours, t_base));
    }
    details.insert("target_ns_per_cell".into(), json!(10.0));
    details.insert("bandwidth_floor_ns_per_cell".into(), json!(1.4));
    Ok(Row::timed(
        "edt-4096",
        "exact EDT (localization distance_transform, 4096x4096)",
        "straightforward Felzenszwalb-Huttenlocher (f64, per-line buffers)",
        main.expect("ran"),
        "the row envelopes' data-dependent branches (hull pops), about 90 % of the time; memory passes are contiguous",
    )
    .details(details.into()))
}

/// Compute per cycle of one run: navigator + localiser (s), the report's stages and the run.
fn mission_run(navigator: Option<&str>) -> anyhow::Result<rovernav_executive::Report> {
    let mut mission = Mission::default_mission();
    if let Some(n) = navigator {
        mission.navigator = n.into();
    }
    let run = Run::mission(&mission, "default")
        .and_then(Run::execute)
        .map_err(|e| anyhow!("default mission: {e}"))?;
    Ok(run.report)
}

/// `cycle-default` and `sim-default` from runs of the default mission (in full mode, every
/// registered navigator's cycle too).
pub fn mission_rows(quick: bool) -> anyhow::Result<Vec<Row>> {
    let runs = if quick { 1 } else { 3 };
    let mut best: Option<rovernav_executive::Report> = None;
    for _ in 0..runs {
        let r = mission_run(None)?;
        if best.as_ref().is_none_or(|b| r.wall_time_s < b.wall_time_s) {
            best = Some(r);
        }
    }
    let r = best.expect("ran");
    let c = &r.compute_per_cycle;
    let compute = c.navigation_s + c.localization_s;
    let mut cycle_details = json!({
        "navigator": r.navigator,
        "cycles": r.cycles,
        "navigation_s": c.navigation_s,
        "localization_s": c.localization_s,
        "platform_s": c.platform_s,
        "budget_s": 0.010,
    });
    if !quick {
        // Every registered navigator on the same mission, by stage (RoverBug's budget is 30 ms).
        let mut per_navigator = serde_json::Map::new();
        for name in rovernav_navigation::navigator_names() {
            let run = match mission_run(Some(name)) {
                Ok(run) => run,
                Err(e) => {
                    per_navigator.insert(name.into(), json!({ "error": e.to_string() }));
                    continue;
                }
            };
            let t = &run.compute_per_cycle;
            per_navigator.insert(
                name.into(),
                json!({
                    "outcome": run.outcome,
                    "cycles": run.cycles,
                    "navigation_s": t.navigation_s,
                    "localization_s": t.localization_s,
                    "platform_s": t.platform_s,
                    "budget_s": if name == "roverbug" { 0.030 } else { 0.010 },
                }),
            );
        }
        cycle_details["navigators"] = per_navigator.into();
    }
    let cycle = Row::timed(
        "cycle-default",
        &format!("one navigation cycle, default mission ({}: navigation + localisation)", r.navigator),
        "budget: 10 ms per cycle on one core (a budget, not a measurement)",
        (compute, 0.010),
        "the navigator's step (terrain assessment, map update, planning on the 121x121 grid)",
    )
    .details(cycle_details);
    let sim = Row::timed(
        "sim-default",
        "whole default mission, wall clock",
        "real time: the simulated rover's own clock",
        (r.wall_time_s, r.sim_time_s),
        "the run's truth set-up (the true hazard grid for the optimal-path reference, about 45 % of the run), the navigator and the PNG output; the simulator steps in under 1 ms per cycle",
    )
    .details(json!({
        "distance_m": r.distance_driven_m,
        "metres_per_wall_s": r.distance_driven_m / r.wall_time_s.max(1e-12),
        "platform_s_per_cycle": c.platform_s,
        "cycles": r.cycles,
    }));
    Ok(vec![cycle, sim])
}
