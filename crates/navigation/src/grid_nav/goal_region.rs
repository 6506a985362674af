//! The goal region of the grid navigators: a goal counts as reached anywhere within its
//! tolerance, so when the grown hazards wall off the goal cell itself the plan may end at the
//! reachable cell nearest the goal inside the tolerance (see the parent module).

use rovernav_core::Point2;
use rovernav_planning::{Cell, CostGrid};
use std::collections::VecDeque;

/// Fraction of the goal's tolerance within which a plan to the goal region may end: margin for
/// the estimate's error and the segment driver's cut.
pub(super) const GOAL_REGION_FRACTION: f64 = 0.7;

/// The cell reachable from `start` through passable cells (8-connected, no corner cutting, as
/// the planners move) whose centre lies nearest `goal` and within `radius` of it; `None` when
/// there is none. A breadth-first search over the start's connected region.
pub(super) fn goal_region(grid: &CostGrid, start: Cell, goal: Point2, radius: f64) -> Option<Cell> {
    let (rows, cols) = (grid.rows(), grid.cols());
    if radius <= 0.0 || !grid.contains(start) {
        return None;
    }
    let g = grid.geometry();
    let passable = |r: usize, c: usize| grid.cost(Cell::new(r, c)).is_finite();
    let mut seen = vec![false; rows * cols];
    let mut queue = VecDeque::from([start]);
    seen[start.row * cols + start.col] = true;
    let mut best: Option<(f64, Cell)> = None;
    while let Some(cell) = queue.pop_front() {
        let (x, y) = g.center(cell.col, cell.row);
        let d = goal.dist(Point2::new(x, y));
        if d <= radius && best.is_none_or(|(b, _)| d < b) {
            best = Some((d, cell));
        }
        for (dr, dc) in [(-1i64, -1i64), (-1, 0), (-1, 1), (0, -1), (0, 1), (1, -1), (1, 0), (1, 1)] {
            let (r, c) = (cell.row as i64 + dr, cell.col as i64 + dc);
            if r < 0 || c < 0 || r >= rows as i64 || c >= cols as i64 {
                continue;
            }
            let (r, c) = (r as usize, c as usize);
            let diagonal_clear = dr == 0 || dc == 0 || (passable(cell.row, c) && passable(r, cell.col));
            if !seen[r * cols + c] && passable(r, c) && diagonal_clear {
                seen[r * cols + c] = true;
                queue.push_back(Cell::new(r, c));
            }
        }
    }
    best.map(|(_, cell)| cell)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rovernav_core::GridGeometry;
    use rovernav_planning::planner_by_name;

    /// The goal region's cell against a second implementation: A* itself, asked for a path to
    /// every cell within the radius, on 300 random grids a third blocked.
    #[test]
    fn the_goal_region_is_the_nearest_cell_a_star_reaches() {
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let (rows, cols, res) = (16usize, 16usize, 0.1);
        let mut found = 0;
        for _ in 0..300 {
            let costs: Vec<f32> =
                (0..rows * cols).map(|_| if next() % 3 == 0 { f32::INFINITY } else { 1.0 }).collect();
            let mut grid = CostGrid::from_costs(rows, cols, costs).unwrap();
            grid.set_geometry(GridGeometry { cols, rows, resolution: res, origin_x: 0.0, origin_y: 0.0 });
            let start = Cell::new(next() as usize % rows, next() as usize % cols);
            let _ = grid.set_cost(start, 1.0);
            let goal = Point2::new((next() % 1600) as f64 / 1000.0, (next() % 1600) as f64 / 1000.0);
            let radius = 0.25;
            let g = grid.geometry();
            let mut astar = planner_by_name("astar").unwrap();
            astar.set_grid(grid.clone());
            let centre = |c: Cell| {
                let (x, y) = g.center(c.col, c.row);
                goal.dist(Point2::new(x, y))
            };
            let expected = (0..rows)
                .flat_map(|r| (0..cols).map(move |c| Cell::new(r, c)))
                .filter(|&c| centre(c) <= radius && astar.plan(start, c).is_ok())
                .map(centre)
                .fold(f64::INFINITY, f64::min);
            match goal_region(&grid, start, goal, radius) {
                Some(cell) => {
                    found += 1;
                    assert!((centre(cell) - expected).abs() < 1e-12, "{cell:?} vs {expected}");
                }
                None => assert!(expected.is_infinite(), "A* reaches a cell {expected} m from the goal"),
            }
        }
        assert!(found > 50 && found < 300, "both cases drawn: {found} of 300 reachable");
    }
}
