//! Profiling driver: plans on one data-directory cost map (or a MovingAI map's scenarios)
//! with one registered planner, repeatedly, and prints the cost, expansions and time per
//! expansion. Made for `perf stat -e cycles:u,instructions:u` and `perf record`, whose counts
//! do not depend on the other load of a shared machine the way wall time does.
//!
//! `cargo run --release -p rovernav-planning --example plan_repeat -- PLANNER MAP [REPEATS]`,
//! e.g. `astar map1000 10`, `field-dstar map1000 3`, `dstar-lite-replan map1000 20` (D* Lite's
//! update and replan after the 121x121 window change of the benchmarks, and back).

use rovernav_planning::benchmark::window_update;
use rovernav_planning::pgm::parse_cost_map;
use rovernav_planning::{Cell, planner_by_name};
use std::time::Instant;

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [planner, map, rest @ ..] = args.as_slice() else {
        return Err("usage: plan_repeat PLANNER MAP [REPEATS]".into());
    };
    let repeats: usize = rest.first().map_or(Ok(5), |r| r.parse()).map_err(|e| format!("REPEATS: {e}"))?;
    let path = rovernav_core::data_dir().join(format!("costmaps/{map}.pgm"));
    let bytes = std::fs::read(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let grid = parse_cost_map(&bytes).map_err(|e| format!("{}: {e}", path.display()))?;
    let n = grid.rows();
    let (start, goal) = (Cell::new(n / 10, n / 10), Cell::new(n - 1 - n / 10, n - 1 - n / 10));
    let replan = planner == "dstar-lite-replan";
    let name = if replan { "dstar-lite" } else { planner.as_str() };
    let mut p = planner_by_name(name).ok_or_else(|| format!("unknown planner {name}"))?;
    p.set_grid(grid.clone());
    let updates = [window_update(&grid, start, true), window_update(&grid, start, false)];
    if replan {
        p.plan(start, goal).map_err(|e| e.to_string())?;
    }
    let (mut cost, mut expansions, mut s) = (0.0, 0, 0.0);
    for i in 0..repeats {
        if !replan {
            p.set_grid(grid.clone()); // untimed: the next plan searches from scratch
        }
        let t0 = Instant::now();
        let plan = if replan {
            p.update_cells(&updates[i % 2]).map_err(|e| e.to_string())?;
            p.replan()
        } else {
            p.plan(start, goal)
        }
        .map_err(|e| e.to_string())?;
        s += t0.elapsed().as_secs_f64();
        cost = plan.cost;
        expansions += plan.expansions;
    }
    println!(
        "{planner} {map}: cost {cost:.6}, {expansions} expansions in {repeats} runs, {:.3} ms per run, {:.1} ns per expansion",
        s * 1e3 / repeats as f64,
        s * 1e9 / expansions.max(1) as f64
    );
    Ok(())
}
