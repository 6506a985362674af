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
    /// `ceil(2^64 / w)`: `n / w` is the high half of `n * w_magic` for every `n < 2^32`
    /// (Granlund and Montgomery 1994), a multiplication instead of a division.
    w_magic: u64,
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
        let off = [1, wi + 1, wi, wi - 1, -1, -wi - 1, -wi, -wi + 1];
        Self { rows, cols, w, cost, valid, off, graph, w_magic: (u64::MAX / w as u64).wrapping_add(1) }
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

    /// Cost of the cell-centre edge from cell `n` in direction `k` (infinity when not
    /// traversable): [`Lattice::edge`] on [`GraphKind::CellCentres`] without the match on the
    /// graph, the same arithmetic.
    #[inline(always)]
    pub fn centre_edge(&self, n: usize, k: usize) -> f64 {
        let (cu, cv) = (self.cost[n], self.cost[self.step(n, k)]);
        if k.is_multiple_of(2) {
            0.5 * (cu as f64 + cv as f64)
        } else if self.cost[self.step(n, k - 1)].is_infinite()
            || self.cost[self.step(n, (k + 1) % 8)].is_infinite()
        {
            f64::INFINITY
        } else {
            0.5 * (cu as f64 + cv as f64) * SQRT_2
        }
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
            GraphKind::CellCentres => self.centre_edge(n, k),
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

    /// Padded row and column of an index, the quotient by a multiplication (exact for every
    /// index below 2^32 and `w` below 2^32: the error of `w_magic` is below `w`, so
    /// `n * w_magic / 2^64` is within `n / 2^64 < 1 / w` of `n / w`; larger indices divide).
    /// The heuristics take two of these per key.
    #[inline]
    pub fn row_col(&self, n: usize) -> (usize, usize) {
        if n >> 32 == 0 && self.w >> 32 == 0 && self.w > 1 {
            let q = ((n as u128 * self.w_magic as u128) >> 64) as usize;
            (q, n - q * self.w)
        } else {
            (n / self.w, n % self.w)
        }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn row_col_by_multiplication_equals_division() {
        for cols in [1, 2, 5, 13, 29, 61, 125, 253, 509, 997, 1021, 4093, 65533, 1 << 20] {
            let lat = Lattice::new(&CostGrid::uniform(1, cols, 1.0).unwrap(), GraphKind::CellCentres);
            let w = lat.w;
            let mut ns: Vec<usize> =
                (0..5000).chain((1..64).map(|k| k * w - 1)).chain((1..64).map(|k| k * w)).collect();
            ns.extend([u32::MAX as usize, u32::MAX as usize - 1, (u32::MAX as usize / w) * w, (1 << 33) + 7]);
            for n in ns {
                assert_eq!(lat.row_col(n), (n / w, n % w), "n {n} w {w}");
            }
        }
    }
}
