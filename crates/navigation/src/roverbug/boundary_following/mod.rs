//! Boundary following (paper 000 section 2.2): the positive sense chosen by the shorter side
//! around the blocking obstacle, the blocking obstacle as a connected group of overlapping
//! C-obstacles, its silhouette vertex in the interior of the conglomerate wedge, the mast scan
//! at `2 k alpha_mast` alternating sides, and the loop test through `V_loop`. The two submodes
//! are [`virtual_mode`] (swing the mast until a silhouette vertex shows) and [`normal_mode`]
//! (circumnavigate, leaving when a node beats `d_reach`).
//!
//! Departures kept here, each for the platform's mast, which sees over low rocks and so shows
//! the blocking obstacle's far side that a Bug algorithm's planar sensor never shows:
//! * `V_loop` and `d_reach` are taken on the near side of the boundary, among the vertices the
//!   rover sees across free space (over every vertex in view, seed 18's rock field held a
//!   vertex 4.3 m from the goal while the rover followed a boundary 10 m from it, and it never
//!   left; the ring scenario's `V_loop` lay on the ring's inner side and the loop never closed);
//! * the loop through `V_loop` proves the goal unreachable only when the positions of the
//!   boundary-following segment wind around the goal (more than 3/4 of a turn): in clutter the
//!   rover can come back near `V_loop` around another obstacle
//!   ([`RoverBug::encircles_goal`]); "the same place" is within 1 m of `V_loop` after leaving
//!   it by more than 2 m;
//! * normal boundary following looks with the mast as well as the forward body pair (the body
//!   pair alone sees 1.5 m) and turns the gaze in steps of `2 alpha_mast`.

mod normal_mode;
mod virtual_mode;

use super::{Ltg, Mode, Point2, RoverBug, angle_diff};
use std::f64::consts::PI;

impl RoverBug {
    /// Enters virtual boundary following: positive sense by the shorter side around the
    /// blocking obstacle.
    pub(in crate::roverbug) fn start_boundary_following(&mut self, x: Point2, goal: Point2) {
        let ltg = self.build_ltg(x, goal);
        let reference = goal.sub(x).angle();
        let mut sense = 1.0;
        if let Some(comp) = self.blocking_component(x, goal) {
            let side = |s: f64| {
                Self::boundary_nodes(&ltg, &comp)
                    .into_iter()
                    .map(|i| ltg.nodes[i].p)
                    .max_by(|a, b| {
                        (s * Self::rel_angle(x, *a, reference))
                            .total_cmp(&(s * Self::rel_angle(x, *b, reference)))
                    })
                    .map_or(f64::INFINITY, |v| x.dist(v) + v.dist(goal))
            };
            if side(-1.0) < side(1.0) {
                sense = -1.0;
            }
        }
        self.mode = Mode::Virtual { sense, scans: vec![0] };
        self.visited = vec![x];
        self.remember(x);
    }

    /// Connected groups of overlapping C-obstacles (the obstacles of the paper's "∂O").
    pub(in crate::roverbug) fn components(&self) -> Vec<Vec<usize>> {
        let n = self.obstacles.len();
        let mut group: Vec<usize> = (0..n).collect();
        fn root(g: &mut [usize], mut i: usize) -> usize {
            while g[i] != i {
                g[i] = g[g[i]];
                i = g[i];
            }
            i
        }
        for i in 0..n {
            for j in i + 1..n {
                let (a, b) = (&self.obstacles[i], &self.obstacles[j]);
                let touch = a.vertices.iter().any(|&v| b.contains(v))
                    || b.vertices.iter().any(|&v| a.contains(v))
                    || a.vertices
                        .iter()
                        .enumerate()
                        .any(|(k, &v)| b.clip_segment(v, a.vertices[(k + 1) % a.vertices.len()]).is_some());
                if touch {
                    let (ri, rj) = (root(&mut group, i), root(&mut group, j));
                    group[ri] = rj;
                }
            }
        }
        let mut out: Vec<Vec<usize>> = Vec::new();
        let mut index = vec![usize::MAX; n];
        for i in 0..n {
            let r = root(&mut group, i);
            if index[r] == usize::MAX {
                index[r] = out.len();
                out.push(Vec::new());
            }
            out[index[r]].push(i);
        }
        out
    }

    /// The component blocking the way from `x` toward the goal (first hit along the line),
    /// or else the one nearest to `x`.
    pub(in crate::roverbug) fn blocking_component(&self, x: Point2, goal: Point2) -> Option<Vec<usize>> {
        let comps = self.components();
        let dir = goal.sub(x);
        let far = x.add(dir.scale(self.range() / dir.norm().max(1e-9)));
        let hit = |c: &Vec<usize>| {
            c.iter()
                .filter_map(|&k| self.obstacles[k].clip_segment(x, far).map(|(t0, _)| t0))
                .fold(f64::INFINITY, f64::min)
        };
        let nearest = |c: &Vec<usize>| {
            c.iter().map(|&k| self.obstacles[k].signed_clearance(x)).fold(f64::INFINITY, f64::min)
        };
        let blocking = comps.iter().filter(|c| hit(c).is_finite()).min_by(|a, b| hit(a).total_cmp(&hit(b)));
        blocking.or_else(|| comps.iter().min_by(|a, b| nearest(a).total_cmp(&nearest(b)))).cloned()
    }

    /// Exterior vertices of a component as LTG node indices.
    pub(in crate::roverbug) fn boundary_nodes(ltg: &Ltg, comp: &[usize]) -> Vec<usize> {
        (0..ltg.nodes.len())
            .filter(|&i| ltg.nodes[i].vertex.is_some_and(|(k, _)| comp.contains(&k)))
            .collect()
    }

    /// Signed angle of `p` seen from `x`, relative to the direction `reference`.
    pub(in crate::roverbug) fn rel_angle(x: Point2, p: Point2, reference: f64) -> f64 {
        angle_diff(p.sub(x).angle(), reference)
    }

    /// The silhouette vertex of the obstacle blocking the way to the goal in the sense `s`
    /// (+1 counter-clockwise from the goal direction): the most extreme boundary node the rover
    /// reaches by a free tangent segment, lying in the interior of the conglomerate wedge with
    /// sensed free ground past it. Returns the subpath to it, the boundary nodes' closest
    /// distance to the goal and the extreme node in the other sense.
    pub(in crate::roverbug) fn silhouette(
        &self,
        x: Point2,
        goal: Point2,
        s: f64,
        virtual_mode: bool,
    ) -> Option<(Vec<Point2>, f64, Point2)> {
        let ltg = self.build_ltg(x, goal);
        let reference = goal.sub(x).angle();
        let comp = self.blocking_component(x, goal)?;
        let nodes = Self::boundary_nodes(&ltg, &comp);
        let key = |i: usize| s * Self::rel_angle(x, ltg.nodes[i].p, reference);
        // The near side of the boundary: the vertices the rover sees across free space. Over
        // low rocks the mast also sees the far side, which a planar sensor never shows.
        let near: Vec<usize> =
            nodes.iter().copied().filter(|&i| ltg.adj[0].iter().any(|&(j, _)| j == i)).collect();
        let direct: Vec<usize> = near
            .iter()
            .copied()
            .filter(|&i| ltg.nodes[i].p.dist(x) > 0.1)
            // Never back to where this segment has been, nor to a restart point.
            .filter(|&i| self.away_from_visits(ltg.nodes[i].p, 0.3))
            // Onward in the positive sense: on that side of the goal direction.
            .filter(|&i| virtual_mode || key(i) > -0.05)
            .collect();
        let v = direct.iter().copied().max_by(|&a, &b| key(a).total_cmp(&key(b)))?;
        let target = ltg.nodes[v].p;
        // Virtual boundary following also needs free ground past the silhouette (the obstacle
        // ends there); following the boundary, the next vertex of a curved boundary hides the
        // rest of it, as the paper's farthest visible boundary vertex does.
        if !self.interior(target) || (virtual_mode && !self.free_past(x, target)) {
            return None;
        }
        // d_reach, "the closest distance to T encountered so far on ∂O": on the near side too.
        // Over every boundary vertex in view, far side included, it can be metres nearer the
        // goal than any boundary the rover follows in a rock field, so that the rover never
        // leaves.
        let d_reach = near.iter().map(|&i| ltg.nodes[i].p.dist(goal)).fold(x.dist(goal), f64::min);
        // V_loop lies on the near side of the boundary (paper 000 section 2.2): the most extreme
        // near vertex in the negative sense. Taken among all, it can lie on the far side of an
        // encircling obstacle, which the rover following the near side never comes back to.
        // `near` holds the target, so it is not empty.
        let other =
            near.iter().copied().min_by(|&a, &b| key(a).total_cmp(&key(b))).map_or(x, |i| ltg.nodes[i].p);
        // The target is a sensed node joined to the rover by a sensed free segment: no cut.
        Some((vec![x, target], d_reach, other))
    }

    /// The next mast wedge of a scan that alternates sides, k = 1, -1, 2, -2, ... in units of
    /// 2 alpha_mast from the goal direction; None once the scans overlap all around.
    pub(in crate::roverbug) fn next_scan(&self, scans: &[i32], sense: f64) -> Option<(i32, f64)> {
        let last = *scans.last().unwrap_or(&0);
        let next = if last <= 0 { -last + 1 } else { -last };
        let angle = 2.0 * self.alpha_mast() * next as f64 * sense;
        (angle.abs() - self.alpha_mast() <= PI + 1e-9 && scans.len() <= 16).then_some((next, angle))
    }

    /// Whether the positions of this boundary-following segment (and `next`) wind around the
    /// goal: a loop around an obstacle proves the goal unreachable only when the obstacle
    /// encloses the goal; in clutter the rover can come back near `V_loop` around another one.
    pub(in crate::roverbug) fn encircles_goal(&self, goal: Point2, next: Option<Point2>) -> bool {
        let pts: Vec<Point2> = self.visited.iter().copied().chain(next).collect();
        let winding: f64 =
            pts.windows(2).map(|w| angle_diff(w[1].sub(goal).angle(), w[0].sub(goal).angle())).sum();
        winding.abs() > 1.5 * PI
    }
}
