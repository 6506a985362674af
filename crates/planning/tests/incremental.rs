//! Incremental replanning must give what planning from scratch gives: after random batches of
//! cost increases, decreases, new and removed obstacles and start moves, D* Lite's and Field
//! D*'s replanned costs equal a fresh plan on the changed map; D* Lite's also equal an
//! independent Dijkstra search written here from the edge-cost definition.

use pathfinding::directed::dijkstra::dijkstra;
use proptest::prelude::*;
use rovernav_planning::baseline::OrdCost as Cost;
use rovernav_planning::{Cell, CellChange, CostGrid, GlobalPlanner, PlanError, planner_by_name};
use std::f64::consts::SQRT_2;

const N: usize = 20;

/// Optimal cell-centre cost: steps cost the mean of the two cells' costs times the length,
/// diagonals need both side cells free.
fn dijkstra_cell_centres(grid: &CostGrid, start: Cell, goal: Cell) -> Option<f64> {
    // Already there: the empty path, whatever the cell costs (as every planner answers).
    if start == goal {
        return Some(0.0);
    }
    if grid.is_blocked(start) || grid.is_blocked(goal) {
        return None;
    }
    let free = |r: i64, c: i64| {
        r >= 0
            && c >= 0
            && (r as usize) < grid.rows()
            && (c as usize) < grid.cols()
            && !grid.is_blocked(Cell::new(r as usize, c as usize))
    };
    let succ = |&(r, c): &(i64, i64)| {
        let mut out = Vec::new();
        for dr in -1i64..=1 {
            for dc in -1i64..=1 {
                if (dr, dc) == (0, 0) || !free(r + dr, c + dc) {
                    continue;
                }
                if dr != 0 && dc != 0 && !(free(r + dr, c) && free(r, c + dc)) {
                    continue;
                }
                let a = grid.cost(Cell::new(r as usize, c as usize)) as f64;
                let b = grid.cost(Cell::new((r + dr) as usize, (c + dc) as usize)) as f64;
                let len = if dr != 0 && dc != 0 { SQRT_2 } else { 1.0 };
                out.push(((r + dr, c + dc), Cost(0.5 * (a + b) * len)));
            }
        }
        out
    };
    let target = (goal.row as i64, goal.col as i64);
    dijkstra(&(start.row as i64, start.col as i64), succ, |&p| p == target).map(|(_, c)| c.0)
}

fn grid_from(costs: &[u8]) -> CostGrid {
    let cost = costs.iter().map(|&v| if v == 0 { f32::INFINITY } else { v as f32 }).collect();
    CostGrid::from_costs(N, N, cost).expect("valid costs")
}

/// A random batch: (cell index, new cost code; 0 = obstacle).
fn batch() -> impl Strategy<Value = Vec<(usize, u8)>> {
    prop::collection::vec((0..N * N, 0u8..8), 1..25)
}

/// A batch of changes and an optional new start (cell indices).
type Batch = (Vec<(usize, u8)>, Option<usize>);

fn cell_of(i: usize) -> Cell {
    Cell::new(i / N, i % N)
}

fn costs_strategy() -> impl Strategy<Value = Vec<u8>> {
    // 0 (obstacle) about 1 in 6; otherwise cost 1..=5.
    prop::collection::vec(prop_oneof![1 => Just(0u8), 5 => 1u8..6], N * N)
}

fn fresh(name: &str, grid: &CostGrid, start: Cell, goal: Cell) -> Result<(f64, f64), PlanError> {
    let mut p = planner_by_name(name).expect("registered");
    p.set_grid(grid.clone());
    p.plan(start, goal).map(|p| (p.value, p.cost))
}

fn check_incremental(
    name: &str,
    costs: Vec<u8>,
    start: usize,
    goal: usize,
    batches: Vec<Batch>,
) -> Result<(), TestCaseError> {
    let mut grid = grid_from(&costs);
    let (mut start, goal) = (cell_of(start), cell_of(goal));
    let mut planner: Box<dyn GlobalPlanner> = planner_by_name(name).expect("registered");
    planner.set_grid(grid.clone());
    let first = planner.plan(start, goal).map(|p| (p.value, p.cost));
    prop_assert_eq!(first.is_ok(), fresh(name, &grid, start, goal).is_ok());
    for (changes, new_start) in batches {
        let changes: Vec<CellChange> = changes
            .iter()
            .map(|&(i, v)| CellChange {
                cell: cell_of(i),
                cost: if v == 0 { f32::INFINITY } else { v as f32 },
            })
            .collect();
        grid.apply(&changes).expect("valid changes");
        planner.update_cells(&changes).expect("valid changes");
        if let Some(s) = new_start {
            start = cell_of(s);
            planner.move_start(start).expect("inside");
        }
        let replanned = planner.replan().map(|p| (p.value, p.cost));
        let scratch = fresh(name, &grid, start, goal);
        match (replanned, scratch) {
            (Ok((rv, rc)), Ok((fv, fc))) => {
                prop_assert!((rv - fv).abs() <= 1e-9 * (1.0 + fv), "{name} value {rv} vs fresh {fv}");
                prop_assert!((rc - fc).abs() <= 1e-6 * (1.0 + fc), "{name} cost {rc} vs fresh {fc}");
                if name == "dstar-lite" {
                    let truth = dijkstra_cell_centres(&grid, start, goal);
                    prop_assert!(truth.is_some_and(|t| (t - rc).abs() <= 1e-9 * (1.0 + t)));
                }
            }
            (Err(_), Err(_)) => {
                if name == "dstar-lite" {
                    prop_assert!(dijkstra_cell_centres(&grid, start, goal).is_none());
                }
            }
            (r, f) => prop_assert!(false, "{name}: replanned {r:?} vs fresh {f:?}"),
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn dstar_lite_replans_like_a_fresh_search(
        costs in costs_strategy(),
        start in 0..N * N,
        goal in 0..N * N,
        batches in prop::collection::vec((batch(), prop::option::of(0..N * N)), 1..4),
    ) {
        check_incremental("dstar-lite", costs, start, goal, batches)?;
    }

    #[test]
    fn field_dstar_replans_like_a_fresh_search(
        costs in costs_strategy(),
        start in 0..N * N,
        goal in 0..N * N,
        batches in prop::collection::vec((batch(), prop::option::of(0..N * N)), 1..4),
    ) {
        check_incremental("field-dstar", costs, start, goal, batches)?;
    }
}
