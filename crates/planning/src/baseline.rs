//! The graph of [`crate::AStar`]'s cell-centre mode written out as a successor function, so that
//! a general-purpose search library (the `pathfinding` crate in `rovernav bench report` and the
//! planner benchmarks) can search the identical graph: same nodes, same edge costs (the mean of
//! the two cells' costs times the step length, no corner cutting), same octile heuristic.
//! Costs are wrapped in [`OrdCost`] because such libraries need a totally ordered cost type.

use crate::{Cell, CostGrid};
use std::f64::consts::SQRT_2;

/// An `f64` path cost with a total order (costs here are finite and non-negative).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct OrdCost(pub f64);

impl Eq for OrdCost {}

impl PartialOrd for OrdCost {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for OrdCost {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
}

impl std::ops::Add for OrdCost {
    type Output = OrdCost;
    fn add(self, rhs: OrdCost) -> OrdCost {
        OrdCost(self.0 + rhs.0)
    }
}

impl pathfinding::num_traits::Zero for OrdCost {
    fn zero() -> Self {
        OrdCost(0.0)
    }
    fn is_zero(&self) -> bool {
        self.0 == 0.0
    }
}

/// Row and column steps of the 8 directions (E, NE, N, NW, W, SW, S, SE).
const STEPS: [(isize, isize); 8] = [(0, 1), (1, 1), (1, 0), (1, -1), (0, -1), (-1, -1), (-1, 0), (-1, 1)];

/// The traversable 8-connected neighbours of `cell` with their edge costs (nothing from a
/// blocked cell).
pub fn centre_successors(grid: &CostGrid, cell: Cell) -> Vec<(Cell, OrdCost)> {
    let (rows, cols) = (grid.rows() as isize, grid.cols() as isize);
    let cost_at = |r: isize, c: isize| {
        if r < 0 || c < 0 || r >= rows || c >= cols {
            f32::INFINITY
        } else {
            grid.cost(Cell::new(r as usize, c as usize))
        }
    };
    let (r, c) = (cell.row as isize, cell.col as isize);
    let cu = cost_at(r, c);
    let mut out = Vec::with_capacity(8);
    if cu.is_infinite() {
        return out;
    }
    for (k, &(dr, dc)) in STEPS.iter().enumerate() {
        let cv = cost_at(r + dr, c + dc);
        if cv.is_infinite() {
            continue;
        }
        let mean = 0.5 * (cu as f64 + cv as f64);
        let e = if k % 2 == 0 {
            mean
        } else if cost_at(r + dr, c).is_infinite() || cost_at(r, c + dc).is_infinite() {
            continue;
        } else {
            mean * SQRT_2
        };
        out.push((Cell::new((r + dr) as usize, (c + dc) as usize), OrdCost(e)));
    }
    out
}

/// The cost of the path the `pathfinding` crate finds from `start` to `goal` on this graph: its
/// A* with the octile heuristic (`informed`) or its Dijkstra; `None` without a path.
pub fn pathfinding_cost(grid: &CostGrid, start: Cell, goal: Cell, informed: bool) -> Option<f64> {
    let successors = |n: &Cell| centre_successors(grid, *n);
    let found = if informed {
        pathfinding::directed::astar::astar(
            &start,
            successors,
            |n| octile_heuristic(*n, goal),
            |n| *n == goal,
        )
    } else {
        pathfinding::directed::dijkstra::dijkstra(&start, successors, |n| *n == goal)
    };
    found.map(|(_, OrdCost(c))| c)
}

/// The octile distance between two cells (the heuristic both searches use).
pub fn octile_heuristic(a: Cell, b: Cell) -> OrdCost {
    OrdCost(crate::octile_distance(a.row.abs_diff(b.row), a.col.abs_diff(b.col)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lattice::Lattice;
    use crate::{AStar, GlobalPlanner, GraphKind, octile_distance};

    #[test]
    fn successors_are_the_lattice_edges() {
        // 0 = obstacle; the lattice (the planners' own storage) is the independent reference.
        let codes = [1u8, 2, 0, 3, 4, 1, 5, 0, 2, 1, 1, 3, 0, 2, 6, 1, 1, 2, 7, 1];
        let costs = codes.iter().map(|&v| if v == 0 { f32::INFINITY } else { v as f32 }).collect();
        let grid = CostGrid::from_costs(4, 5, costs).unwrap();
        let lat = Lattice::new(&grid, GraphKind::CellCentres);
        for r in 0..4 {
            for c in 0..5 {
                let cell = Cell::new(r, c);
                let succ = centre_successors(&grid, cell);
                let n = lat.index(cell);
                let mut expected = Vec::new();
                for k in 0..8 {
                    let e = lat.edge(n, k);
                    if e.is_finite() && grid.cost(cell).is_finite() {
                        let (mr, mc) = lat.coords(lat.step(n, k));
                        expected.push((Cell::new(mr, mc), OrdCost(e)));
                    }
                }
                assert_eq!(succ, expected, "cell {cell:?}");
            }
        }
        assert_eq!(octile_heuristic(Cell::new(0, 0), Cell::new(3, 1)).0, octile_distance(3, 1));
        // Both library searches agree with rovernav's A* and Dijkstra on every pair of cells.
        let mut ours = [AStar::new(GraphKind::CellCentres), AStar::dijkstra(GraphKind::CellCentres)];
        for p in &mut ours {
            p.set_grid(grid.clone());
        }
        let cells: Vec<Cell> = (0..4).flat_map(|r| (0..5).map(move |c| Cell::new(r, c))).collect();
        for &s in &cells {
            // rovernav's planners refuse a blocked start or goal (even when they coincide).
            for &t in cells.iter().filter(|&&t| !grid.is_blocked(s) && !grid.is_blocked(t)) {
                for (p, informed) in ours.iter_mut().zip([true, false]) {
                    let theirs = pathfinding_cost(&grid, s, t, informed);
                    match p.plan(s, t) {
                        Ok(plan) => assert!((plan.cost - theirs.unwrap()).abs() < 1e-12, "{s:?}->{t:?}"),
                        Err(_) => assert_eq!(theirs, None, "{s:?}->{t:?}"),
                    }
                }
            }
        }
    }
}
