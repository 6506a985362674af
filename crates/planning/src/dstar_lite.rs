//! D* Lite (S. Koenig and M. Likhachev, "D* Lite", AAAI 2002; optimised version, their
//! figure 4) on the 8-connected cell-centre graph: the incremental planner MRPTA's path planning
//! is based on (paper 004, section 3.5), replanning after map updates and rover motion by
//! repairing only the affected part of a backward search from the goal.
//!
//! Edge costs are those of [`crate::AStar`] on cell centres (mean of the two cells' costs times
//! the step length, no corner cutting), so both give the same optimal costs.

use crate::incremental::{Engine, Model, Values};
use crate::lattice::Lattice;
use crate::{CostGrid, GraphKind};
use rovernav_core::Point2;

/// Graph model: rhs(s) = min over neighbours s' of c(s, s') + g(s').
#[derive(Clone, Copy, Debug)]
pub(crate) struct CentreGraph;

impl Model for CentreGraph {
    const NAME: &'static str = "dstar-lite";
    const GRAPH: GraphKind = GraphKind::CellCentres;

    #[inline]
    fn rhs(lat: &Lattice, g: Values<'_>, s: usize) -> f64 {
        // `via` for the 8 directions written out with the cell's own cost loaded once and a
        // diagonal's side cells checked only when its far node has a value; the same edge
        // arithmetic, so the same value.
        let cost = &lat.cost;
        let cu = cost[s] as f64;
        let mut best = f64::INFINITY;
        for k in 0..8 {
            let n = lat.step(s, k);
            let gn = g[n];
            if gn.is_infinite() {
                continue;
            }
            let e = 0.5 * (cu + cost[n] as f64);
            let e = if k % 2 == 0 {
                e
            } else if cost[lat.step(s, k - 1)].is_infinite() || cost[lat.step(s, (k + 1) % 8)].is_infinite() {
                continue;
            } else {
                e * std::f64::consts::SQRT_2
            };
            best = best.min(e + gn);
        }
        best
    }

    #[inline]
    fn via(lat: &Lattice, g: Values<'_>, s: usize, k: usize) -> f64 {
        let gn = g[lat.step(s, k)];
        if gn.is_infinite() { f64::INFINITY } else { lat.centre_edge(s, k) + gn }
    }

    #[inline]
    fn h_rc(dr: usize, dc: usize) -> f64 {
        crate::octile_distance(dr, dc)
    }

    fn extract(
        lat: &Lattice,
        _grid: &CostGrid,
        g: Values<'_>,
        start: usize,
        goal: usize,
    ) -> Option<(Vec<Point2>, f64)> {
        descend(lat, g, start, goal)
    }
}

/// Follows the values `g` downhill from `start` to `goal` on a graph: each step takes the
/// neighbour minimising edge cost plus g. Returns the node points and the summed edge cost.
pub(crate) fn descend(lat: &Lattice, g: Values<'_>, start: usize, goal: usize) -> Option<(Vec<Point2>, f64)> {
    let mut points = vec![lat.point(start)];
    let mut cost = 0.0;
    let mut s = start;
    let mut steps = 0;
    while s != goal {
        let (mut best, mut best_k) = (f64::INFINITY, 8);
        for k in 0..8 {
            let n = lat.step(s, k);
            if !lat.valid[n] {
                continue;
            }
            let v = lat.edge(s, k) + g[n];
            if v < best {
                best = v;
                best_k = k;
            }
        }
        steps += 1;
        if best_k == 8 || !best.is_finite() || steps > lat.len() {
            return None;
        }
        cost += lat.edge(s, best_k);
        s = lat.step(s, best_k);
        points.push(lat.point(s));
    }
    Some((points, cost))
}

/// The D* Lite planner on cell centres.
#[derive(Clone, Debug, Default)]
pub struct DStarLite {
    engine: Engine<CentreGraph>,
}

impl DStarLite {
    /// A planner without a grid.
    pub fn new() -> Self {
        Self::default()
    }
}

crate::incremental::impl_global_planner!(DStarLite, CentreGraph);
