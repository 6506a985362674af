//! Flat, padded storage shared by the grid planners: cell costs and node indexing for the
//! cell-centre graph and the corner-node graph, without bounds checks in the inner loops.
//!
//! Both graphs use one row-major index space of width `w = cols + 3`. Cell (r, c) lives at
//! `(r + 1) * w + (c + 1)`, surrounded by a ring of obstacle cells; corner node (i, j) (the corner
//! at grid point x = j, y = i) lives at `(i + 1) * w + (j + 1)`, so node `n` touches the four
//! cells `n` (north-east quadrant), `n - 1` (north-west), `n - w` (south-east) and `n - w - 1`
//! (south-west). Directions are numbered counter-clockwise from east: E, NE, N, NW, W, SW, S, SE
//! ("north" = increasing row).

use crate::{Cell, CostGrid, GraphKind};
use rovernav_core::Point2;
use std::f64::consts::SQRT_2;

/// Padded cost storage plus node validity for one graph.
#[derive(Clone, Debug)]
pub(crate) struct Lattice {
    /// Grid rows.
    pub rows: usize,
    /// Grid columns.
    pub cols: usize,
    /// Row stride of the padded index space.
    pub w: usize,
    /// Padded cell costs (ring = infinity).
    pub cost: Vec<f32>,
    /// Whether an index is a node of the graph.
    pub valid: Vec<bool>,
    /// Index offsets of the 8 directions.
    pub off: [isize; 8],
    /// Which graph the nodes belong to.
    pub graph: GraphKind,
}

impl Lattice {
    /// Builds padded storage for a grid.
    pub fn new(grid: &CostGrid, graph: GraphKind) -> Self {
        let (rows, cols) = (grid.rows(), grid.cols());
        let w = cols + 3;
        let len = (rows + 3) * w;
        let mut cost = vec![f32::INFINITY; len];
        for r in 0..rows {
            let dst = (r + 1) * w + 1;
            cost[dst..dst + cols].copy_from_slice(&grid.costs()[r * cols..(r + 1) * cols]);
        }
        let (node_rows, node_cols) = match graph {
            GraphKind::CellCentres => (rows, cols),
            GraphKind::CornerNodes => (rows + 1, cols + 1),
        };
        let mut valid = vec![false; len];
        for r in 0..node_rows {
            let base = (r + 1) * w + 1;
            valid[base..base + node_cols].fill(true);
        }
        let wi = w as isize;
        Self { rows, cols, w, cost, valid, off: [1, wi + 1, wi, wi - 1, -1, -wi - 1, -wi, -wi + 1], graph }
    }

    /// Number of indices.
    pub fn len(&self) -> usize {
        self.cost.len()
    }

    /// Padded index of a cell (or of the cell's minimum corner node).
    #[inline]
    pub fn index(&self, cell: Cell) -> usize {
        (cell.row + 1) * self.w + cell.col + 1
    }

    /// (row, col) of an index (cell, or corner node (i, j)).
    #[inline]
    pub fn coords(&self, n: usize) -> (usize, usize) {
        (n / self.w - 1, n % self.w - 1)
    }

    /// Neighbour of `n` in direction `k`.
    #[inline]
    pub fn step(&self, n: usize, k: usize) -> usize {
        (n as isize + self.off[k]) as usize
    }

    /// The point in grid units a node stands for.
    pub fn point(&self, n: usize) -> Point2 {
        let (r, c) = self.coords(n);
        match self.graph {
            GraphKind::CellCentres => Cell::new(r, c).center(),
            GraphKind::CornerNodes => Cell::new(r, c).corner(),
        }
    }

    /// Sets one cell's cost.
    pub fn set_cost(&mut self, cell: Cell, cost: f32) {
        let i = self.index(cell);
        self.cost[i] = cost;
    }

    /// Cost of the edge from node `n` in direction `k` (infinity when not traversable).
    ///
    /// Cell centres: the mean of the two cells' costs times the edge length; a diagonal also
    /// needs both cells it passes between to be traversable (no corner cutting).
    /// Corner nodes (Ferguson and Stentz's graph): a diagonal crosses one cell at its cost times
    /// sqrt 2; an axis edge runs between two cells at the cheaper one's cost.
    #[inline]
    pub fn edge(&self, n: usize, k: usize) -> f64 {
        let w = self.w;
        match self.graph {
            GraphKind::CellCentres => {
                let m = self.step(n, k);
                let (cu, cv) = (self.cost[n], self.cost[m]);
                if k.is_multiple_of(2) {
                    0.5 * (cu as f64 + cv as f64)
                } else {
                    let side_a = self.cost[self.step(n, k - 1)];
                    let side_b = self.cost[self.step(n, (k + 1) % 8)];
                    if side_a.is_infinite() || side_b.is_infinite() {
                        f64::INFINITY
                    } else {
                        0.5 * (cu as f64 + cv as f64) * SQRT_2
                    }
                }
            }
            GraphKind::CornerNodes => {
                let c = &self.cost;
                match k {
                    0 => c[n].min(c[n - w]) as f64,
                    1 => c[n] as f64 * SQRT_2,
                    2 => c[n].min(c[n - 1]) as f64,
                    3 => c[n - 1] as f64 * SQRT_2,
                    4 => c[n - 1].min(c[n - w - 1]) as f64,
                    5 => c[n - w - 1] as f64 * SQRT_2,
                    6 => c[n - w].min(c[n - w - 1]) as f64,
                    _ => c[n - w] as f64 * SQRT_2,
                }
            }
        }
    }

    /// Padded row and column of an index. In 32 bits when the index space fits (every grid a
    /// planner takes in practice): a 32-bit division is several times cheaper than a 64-bit
    /// one, and the heuristics divide twice per key.
    #[inline]
    fn row_col(&self, n: usize) -> (usize, usize) {
        if let (Ok(n32), Ok(w32)) = (u32::try_from(n), u32::try_from(self.w)) {
            ((n32 / w32) as usize, (n32 % w32) as usize)
        } else {
            (n / self.w, n % self.w)
        }
    }

    /// Octile distance between two nodes (a lower bound on path cost since costs are >= 1).
    #[inline]
    pub fn octile(&self, a: usize, b: usize) -> f64 {
        let ((ar, ac), (br, bc)) = (self.row_col(a), self.row_col(b));
        crate::octile_distance(ar.abs_diff(br), ac.abs_diff(bc))
    }

    /// Euclidean distance between two nodes in grid units.
    #[inline]
    pub fn euclid(&self, a: usize, b: usize) -> f64 {
        let ((ar, ac), (br, bc)) = (self.row_col(a), self.row_col(b));
        let (dr, dc) = (ar.abs_diff(br) as f64, ac.abs_diff(bc) as f64);
        (dr * dr + dc * dc).sqrt()
    }

    /// The nodes whose incident edges change when `cell` changes cost.
    ///
    /// Cell centres: the cell and its 8 neighbours (its own edges, and the diagonals between its
    /// 4-neighbours that pass by it). Corner nodes: the cell's 4 corners.
    pub fn affected_nodes(&self, cell: Cell, out: &mut Vec<usize>) {
        let n = self.index(cell);
        match self.graph {
            GraphKind::CellCentres => {
                out.push(n);
                for k in 0..8 {
                    let m = self.step(n, k);
                    if self.valid[m] {
                        out.push(m);
                    }
                }
            }
            GraphKind::CornerNodes => {
                out.extend_from_slice(&[n, n + 1, n + self.w, n + self.w + 1]);
            }
        }
    }
}
