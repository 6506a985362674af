//! Field D* (D. Ferguson and A. Stentz, "The Field D* Algorithm for Improved Path Planning and
//! Replanning in Uniform and Non-Uniform Cost Environments", CMU-RI-TR-05-19, 2005, and "Using
//! interpolation to improve path planning", J. Field Robotics 23(2), 2006): the global planner
//! integrated into MER flight software next to GESTALT (paper 003, section 2).
//!
//! Nodes sit at cell corners. A node's value is not restricted to its 8 neighbours: for each of
//! the 8 triangles formed by the node and two consecutive neighbours `s1` (axis) and `s2`
//! (diagonal) the path may leave through any point of the cell edge `s1 s2`, whose value is
//! interpolated linearly between `g(s1)` and `g(s2)`. With `c` the cost of the cell the triangle
//! lies in and `b` the cost of the cell across the edge `s s1`, the minimum has the closed form
//! of Ferguson and Stentz's `ComputeCost`:
//!
//! - `g(s1) <= g(s2)`: go along `s s1`, cost `min(c, b) + g(s1)`;
//! - else with `f = g(s1) - g(s2)`: if `f <= b`, cross `c` to the point at distance
//!   `y = min(f / sqrt(c^2 - f^2), 1)` from `s1` (straight to `s2` when `c <= f`), cost
//!   `c sqrt(1 + y^2) + f (1 - y) + g(s2)`; if `f > b`, run along the cheaper edge for
//!   `x = 1 - min(b / sqrt(c^2 - b^2), 1)` and cut across `c` to `s2`, cost
//!   `c sqrt(1 + (1 - x)^2) + b x + g(s2)` (straight to `s2` when `c <= b`).
//!
//! The plain 8-connected moves (`min(c, b) + g(s1)` along an axis edge, `c sqrt 2 + g(s2)`
//! across the cell) are always among the candidates, so Field D*'s value is never above the
//! corner-graph optimum; and since costs are >= 1 and linear interpolation of a convex distance
//! overestimates it, never below the straight-line distance. The search is D* Lite's (the engine
//! shared with [`crate::DStarLite`]) with half the Euclidean distance as heuristic (see
//! `HEURISTIC_WEIGHT`); after a node's value drops only the two triangles of each neighbour that
//! contain it are re-evaluated.
//!
//! Start and goal cells map to their minimum-row, minimum-column corner node
//! ([`Cell::corner`]); the path is extracted by interpolation too: from the current point
//! (a node or a point on a cell edge) it moves to the point on the boundary of an adjacent cell
//! minimising `cell cost x distance + interpolated g`, which gives an any-angle polyline; a local
//! shortcut pass then straightens kinks next to obstacles, where linear interpolation of g is
//! least accurate. [`crate::Plan::cost`] is that polyline's cost on the grid (the figure the
//! data README's Field D* references give), [`crate::Plan::value`] the interpolated g-value.

use crate::incremental::{Engine, Model, Values};
use crate::lattice::Lattice;
use crate::{Cell, CostGrid, GraphKind};
use rovernav_core::Point2;
use std::f64::consts::SQRT_2;

/// Weight of the Euclidean heuristic. Interpolated values are not a graph metric: a node
/// expanded early can still be lowered through a triangle whose other corner is settled later,
/// and with the full Euclidean distance such re-openings cascade (hundreds of expansions per
/// node on an open 200x200 map) and the search stops before the start's value settles. Half the
/// distance keeps the search focused while every node is expanded about once, and gives the
/// same values as Dijkstra order (h = 0).
const HEURISTIC_WEIGHT: f64 = 0.5;

/// Field D*'s interpolating model.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Interpolated;

/// For triangle `p` (directions `p`, `p + 1`): axis direction, diagonal direction, and which of
/// the node's cells (0 = NE, 1 = NW, 2 = SE, 3 = SW) are `c` (inside) and `b` (across `s s1`).
const TRIANGLES: [(usize, usize, usize, usize); 8] = [
    (0, 1, 0, 2),
    (2, 1, 0, 1),
    (2, 3, 1, 0),
    (4, 3, 1, 3),
    (4, 5, 3, 1),
    (6, 5, 3, 2),
    (6, 7, 2, 3),
    (0, 7, 2, 0),
];

/// Ferguson and Stentz's closed-form cost of leaving a node through one triangle, or when that is not below `bound`, possibly the cost along the edge
/// instead (then also not below `bound`). The cut across the cell costs its square roots and
/// a division; it is skipped when a lower bound on it already reaches the cheaper of the run
/// along the edge and `bound`:
///
/// - `c + g2` (the crossing is at least one cell side long), which holds in floating point as
///   it is computed: every term after `g2` is `c` times a square root of at least 1 plus
///   non-negative terms, and rounding is monotone;
/// - `g2 + min(min(f, b) + c / sqrt 2, c sqrt 2)` from the closed forms' minima (`g1 +
///   sqrt(c^2 - f^2)` with `f <= c / sqrt 2` when crossing to the edge `s1 s2`, `g2 + b +
///   sqrt(c^2 - b^2)` with `b <= c / sqrt 2` after running along the edge, `g2 + c sqrt 2`
///   otherwise), less a relative margin of 1e-12 for rounding (the computed cost is within a
///   few ulps of the exact one).
#[inline]
pub(crate) fn triangle_cost_below(g1: f64, g2: f64, c: f64, b: f64, bound: f64) -> f64 {
    let along = c.min(b) + g1;
    if g1 <= g2 || g2.is_infinite() {
        return along;
    }
    let f = g1 - g2;
    let cut = along.min(bound);
    let closed_form = g2 + (f.min(b) + c * std::f64::consts::FRAC_1_SQRT_2).min(c * SQRT_2);
    if c + g2 >= cut || closed_form * (1.0 - 1e-12) >= cut {
        return along;
    }
    let across = if f <= b {
        if c <= f {
            c * SQRT_2 + g2
        } else {
            let y = (f / (c * c - f * f).sqrt()).min(1.0);
            c * (1.0 + y * y).sqrt() + f * (1.0 - y) + g2
        }
    } else if c <= b {
        c * SQRT_2 + g2
    } else {
        let x = 1.0 - (b / (c * c - b * b).sqrt()).min(1.0);
        c * (1.0 + (1.0 - x) * (1.0 - x)).sqrt() + b * x + g2
    };
    across.min(along)
}

impl Interpolated {
    #[inline]
    fn triangle(lat: &Lattice, g: Values<'_>, s: usize, p: usize, bound: f64) -> f64 {
        let (ak, dk, ci, bi) = TRIANGLES[p];
        let w = lat.w;
        let cells = [s, s - 1, s - w, s - w - 1];
        let c = lat.cost[cells[ci]] as f64;
        let b = lat.cost[cells[bi]] as f64;
        if c.is_infinite() && b.is_infinite() {
            return f64::INFINITY;
        }
        triangle_cost_below(g[lat.step(s, ak)], g[lat.step(s, dk)], c, b, bound)
    }
}

impl Model for Interpolated {
    const NAME: &'static str = "field-dstar";
    const GRAPH: GraphKind = GraphKind::CornerNodes;

    #[inline]
    fn rhs(lat: &Lattice, g: Values<'_>, s: usize) -> f64 {
        (0..8).map(|p| Self::triangle(lat, g, s, p, f64::INFINITY)).fold(f64::INFINITY, f64::min)
    }

    #[inline]
    fn via(lat: &Lattice, g: Values<'_>, s: usize, k: usize) -> f64 {
        Self::via_below(lat, g, s, k, f64::INFINITY)
    }

    #[inline]
    fn via_below(lat: &Lattice, g: Values<'_>, s: usize, k: usize, bound: f64) -> f64 {
        Self::triangle(lat, g, s, k, bound).min(Self::triangle(lat, g, s, (k + 7) % 8, bound))
    }

    #[inline]
    fn h_rc(dr: usize, dc: usize) -> f64 {
        // Lattice::euclid's arithmetic.
        let (dr, dc) = (dr as f64, dc as f64);
        HEURISTIC_WEIGHT * (dr * dr + dc * dc).sqrt()
    }

    fn extract(
        lat: &Lattice,
        grid: &CostGrid,
        g: Values<'_>,
        start: usize,
        goal: usize,
    ) -> Option<(Vec<Point2>, f64)> {
        interpolated_path(lat, grid, g, start, goal)
    }
}

/// Positions closer than this (grid units) are the same point.
const SNAP: f64 = 1e-9;

/// g of corner node (i, j) given as possibly out-of-range integers.
fn node_g(lat: &Lattice, g: Values<'_>, i: i64, j: i64) -> f64 {
    if i < 0 || j < 0 || i > lat.rows as i64 || j > lat.cols as i64 {
        f64::INFINITY
    } else {
        g[lat.index(Cell::new(i as usize, j as usize))]
    }
}

/// The best point on edge `pa -> pb` (unit, axis-aligned) to head for from `p` across a cell
/// of cost `c`: minimises `c |p - q| + g_lin(q)`. Returns (value, q, step length).
fn best_on_edge(p: Point2, pa: Point2, pb: Point2, ga: f64, gb: f64, c: f64) -> (f64, Point2, f64) {
    let e = pb.sub(pa);
    let rel = p.sub(pa);
    let t0 = rel.dot(e);
    let d = e.cross(rel).abs();
    let eval = |t: f64| {
        let q = pa.add(e.scale(t));
        let len = p.dist(q);
        let gq = if t <= 0.0 {
            ga
        } else if t >= 1.0 {
            gb
        } else {
            ga + t * (gb - ga)
        };
        (c * len + gq, q, len)
    };
    let worst = (f64::INFINITY, p, 0.0);
    let pick = |a: (f64, Point2, f64), b: (f64, Point2, f64)| {
        let a = if a.2 > SNAP { a } else { worst };
        let b = if b.2 > SNAP { b } else { worst };
        if b.0 < a.0 { b } else { a }
    };
    if ga.is_infinite() && gb.is_infinite() {
        return worst;
    }
    if ga.is_infinite() {
        return pick(worst, eval(1.0));
    }
    if gb.is_infinite() {
        return pick(eval(0.0), worst);
    }
    let ends = pick(eval(0.0), eval(1.0));
    if d <= SNAP {
        return ends;
    }
    let f = gb - ga;
    if f.abs() >= c {
        return ends;
    }
    let t = (t0 - f * d / (c * c - f * f).sqrt()).clamp(0.0, 1.0);
    pick(ends, eval(t))
}

/// Interpolated path extraction (see the module doc).
fn interpolated_path(
    lat: &Lattice,
    grid: &CostGrid,
    g: Values<'_>,
    start: usize,
    goal: usize,
) -> Option<(Vec<Point2>, f64)> {
    let goal_pt = lat.point(goal);
    let mut p = lat.point(start);
    let mut points = vec![p];
    let max_steps = 4 * (lat.rows + 2) * (lat.cols + 2);
    if p.dist(goal_pt) <= SNAP {
        return Some((points, 0.0));
    }
    for _ in 0..max_steps {
        let cols_near = near_lines(p.x);
        let rows_near = near_lines(p.y);
        let mut best = (f64::INFINITY, p);
        for &r in &rows_near {
            for &c in &cols_near {
                if r < 0 || c < 0 || r >= lat.rows as i64 || c >= lat.cols as i64 {
                    continue;
                }
                let cc = grid.cost(Cell::new(r as usize, c as usize)) as f64;
                if cc.is_infinite() {
                    continue;
                }
                let corners = [(r, c), (r, c + 1), (r + 1, c + 1), (r + 1, c)];
                for k in 0..4 {
                    let (ia, ja) = corners[k];
                    let (ib, jb) = corners[(k + 1) % 4];
                    let pa = Point2::new(ja as f64, ia as f64);
                    let pb = Point2::new(jb as f64, ib as f64);
                    let (v, q, _) =
                        best_on_edge(p, pa, pb, node_g(lat, g, ia, ja), node_g(lat, g, ib, jb), cc);
                    if v < best.0 {
                        best = (v, q);
                    }
                }
            }
        }
        if !best.0.is_finite() {
            return None;
        }
        let q = snap_to_node(best.1);
        points.push(q);
        p = q;
        if p.dist(goal_pt) <= SNAP {
            let shortened = shortcut(grid, points);
            let cost = grid.polyline_cost(&shortened);
            return Some((shortened, cost));
        }
    }
    None
}

/// How many points ahead [`shortcut`] tries to reach directly.
const SHORTCUT_WINDOW: usize = 6;

/// Replaces runs of up to [`SHORTCUT_WINDOW`] pieces by one straight piece where that is
/// cheaper on the grid. Interpolation assumes g varies linearly along cell edges, which is
/// wrong next to obstacles; there the greedy extraction can bend more than needed, and this
/// local pass removes such kinks (it can only lower the path's cost).
fn shortcut(grid: &CostGrid, points: Vec<Point2>) -> Vec<Point2> {
    let piece: Vec<f64> = points.windows(2).map(|w| grid.segment_cost(w[0], w[1])).collect();
    let mut out = vec![points[0]];
    let mut i = 0;
    while i + 1 < points.len() {
        let mut next = i + 1;
        let last = (i + SHORTCUT_WINDOW).min(points.len() - 1);
        for j in (i + 2..=last).rev() {
            let run: f64 = piece[i..j].iter().sum();
            if grid.segment_cost(points[i], points[j]) < run - 1e-9 {
                next = j;
                break;
            }
        }
        out.push(points[next]);
        i = next;
    }
    out
}

/// The integer grid lines a coordinate lies on or between: `[floor]`, or both neighbours of a
/// line it lies on.
fn near_lines(v: f64) -> Vec<i64> {
    let r = v.round();
    if (v - r).abs() <= SNAP { vec![r as i64 - 1, r as i64] } else { vec![v.floor() as i64] }
}

fn snap_to_node(q: Point2) -> Point2 {
    let snap = |v: f64| {
        let r = v.round();
        if (v - r).abs() <= SNAP { r } else { v }
    };
    Point2::new(snap(q.x), snap(q.y))
}

/// The Field D* planner.
#[derive(Clone, Debug, Default)]
pub struct FieldDStar {
    engine: Engine<Interpolated>,
}

impl FieldDStar {
    /// A planner without a grid.
    pub fn new() -> Self {
        Self::default()
    }
}

crate::incremental::impl_global_planner!(FieldDStar, Interpolated);

#[cfg(test)]
mod tests {
    use super::*;
    use crate::GlobalPlanner;

    /// The closed form without the skip (the code before the skip was added).
    fn triangle_cost(g1: f64, g2: f64, c: f64, b: f64) -> f64 {
        let along = c.min(b) + g1;
        if g1 <= g2 || g2.is_infinite() {
            return along;
        }
        let f = g1 - g2;
        let across = if f <= b {
            if c <= f {
                c * SQRT_2 + g2
            } else {
                let y = (f / (c * c - f * f).sqrt()).min(1.0);
                c * (1.0 + y * y).sqrt() + f * (1.0 - y) + g2
            }
        } else if c <= b {
            c * SQRT_2 + g2
        } else {
            let x = 1.0 - (b / (c * c - b * b).sqrt()).min(1.0);
            c * (1.0 + (1.0 - x) * (1.0 - x)).sqrt() + b * x + g2
        };
        across.min(along)
    }

    /// The skip never changes a value below the bound (bit for bit) and never returns a value
    /// below the bound when the true one is not: random triangles with costs 1-64 (some
    /// obstacles), values up to 30000, bounds near the value.
    #[test]
    fn skipping_the_cut_keeps_every_value_below_the_bound() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let cost = |rng: &mut rand_chacha::ChaCha8Rng| {
            if rng.random_bool(0.05) { f64::INFINITY } else { rng.random_range(1..=64) as f64 }
        };
        let mut skipped = 0;
        for _ in 0..1_000_000 {
            let (c, b) = (cost(&mut rng), cost(&mut rng));
            let g2 = rng.random_range(0.0..30000.0);
            let g1 = g2 + rng.random_range(-2.0..70.0);
            let exact = triangle_cost(g1, g2, c, b);
            assert_eq!(triangle_cost_below(g1, g2, c, b, f64::INFINITY).to_bits(), exact.to_bits());
            let bound = exact + rng.random_range(-3.0..3.0);
            let v = triangle_cost_below(g1, g2, c, b, bound);
            if exact < bound {
                assert_eq!(v.to_bits(), exact.to_bits(), "({g1}, {g2}, {c}, {b}) below {bound}");
            } else {
                assert!(v >= bound, "({g1}, {g2}, {c}, {b}): {v} under {bound}, exact {exact}");
                skipped += usize::from(v != exact);
            }
        }
        assert!(skipped > 10_000, "the skip is exercised ({skipped})");
    }

    #[test]
    fn triangle_cost_matches_brute_force_minimum() {
        // Minimise over the exit point on s1-s2 and the bottom-edge run by sampling.
        let cases: [(f64, f64, f64, f64); 5] = [
            (3.0, 2.5, 1.0, 1.0),
            (5.0, 4.2, 2.0, 3.0),
            (10.0, 7.0, 2.0, 1.5),
            (4.0, 1.0, 2.0, 5.0),
            (1.0, 2.0, 3.0, 1.0),
        ];
        for (g1, g2, c, b) in cases {
            let mut best = c.min(b) + g1;
            let n = 20000;
            for i in 0..=n {
                let y = i as f64 / n as f64;
                best = best.min(c * (1.0 + y * y).sqrt() + (1.0 - y) * g1 + y * g2);
                // along the s-s1 edge for x, then across to s2
                best = best.min(b.min(c) * y + c * (1.0 + (1.0 - y) * (1.0 - y)).sqrt() + g2);
            }
            let v = triangle_cost_below(g1, g2, c, b, f64::INFINITY);
            assert!((v - best).abs() < 1e-6, "({g1},{g2},{c},{b}): {v} vs {best}");
        }
    }

    #[test]
    fn straight_run_on_uniform_grid_is_exact() {
        let grid = CostGrid::uniform(5, 12, 1.0).unwrap();
        let mut p = FieldDStar::new();
        p.set_grid(grid);
        let plan = p.plan(Cell::new(2, 1), Cell::new(2, 11)).unwrap();
        assert!((plan.cost - 10.0).abs() < 1e-9);
        assert!((plan.value - 10.0).abs() < 1e-9);
    }
}
