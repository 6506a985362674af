//! Boundary following's ways on where the paper halts or aborts (departures), and the memory
//! of restart points they rely on:
//! * the blocked step: when normal boundary following has turned the gaze all around without a
//!   silhouette vertex, the wall follower's step ([`RoverBug::fallback_step`]: the first
//!   directly reachable node not yet visited past the goal direction in the positive sense;
//!   turning as far as possible took seed 10 of the default yard 8 m south of a goal to the
//!   north-east and back), then the locally best way on ([`RoverBug::best_exit`]: TangentBug's
//!   heuristic, path length plus distance to the goal); in the other order once boundary
//!   following has led the rover more than `wander_limit_m` farther from the goal than
//!   `d_reach` (seed 19 wandered up to 10 m from a goal it had been 3 m from, until the time
//!   limit). Measured with the wander limit: seeds 1..160 140 / 5 / 142 against 137 / 5 / 139,
//!   seeds 161..320 134 / 5 / 137 against 128 / 6 / 131 (clean / with contacts / reached);
//! * the restart points: where boundary following and escapes started are remembered across
//!   the restarts this implementation adds (escapes, retreats), unlike `visited`, which holds
//!   one boundary-following segment, and forgotten when the leaving condition fires or
//!   motion-to-goal makes progress past all of them. The ways on avoid nodes near them, so the
//!   rover cannot shuttle between the same places of a pocket its own C-obstacles close
//!   (seed 4 of the default yard); when every way on is near one, one is taken anyway.

use crate::roverbug::{Ltg, Node, Point2, RoverBug};

impl RoverBug {
    /// Boundary following's step when the gaze has turned all around without a silhouette
    /// vertex: the wall follower's step, then the locally best way on; in the other order once
    /// the rover is more than `wander_limit` farther from the goal than d_reach. Following a
    /// boundary away from the goal through clutter, the wall follower's step keeps leading
    /// away (seed 19 of the default yard wandered until the time limit).
    pub(in crate::roverbug) fn blocked_step(
        &self,
        ltg: &Ltg,
        x: Point2,
        goal: Point2,
        sense: f64,
        d_reach: f64,
    ) -> Option<Vec<Point2>> {
        let limit = self.config.recovery.wander_limit;
        if limit > 0.0 && x.dist(goal) > d_reach + limit {
            self.best_exit(ltg, x, goal).or_else(|| self.fallback_step(ltg, x, goal, sense))
        } else {
            self.fallback_step(ltg, x, goal, sense).or_else(|| self.best_exit(ltg, x, goal))
        }
    }

    /// The step of boundary following when the gaze has turned all around without a silhouette
    /// vertex: the first node past the goal direction in the positive sense `s` joined to the
    /// rover by a free tangent segment, away from every position of this boundary-following
    /// segment and every restart point; the most extreme such node in the sense when none lies
    /// on the positive side. Turning from the goal direction only as far as the way is blocked
    /// keeps the obstacle at hand, as a wall follower does: the most extreme node, up to half a
    /// turn from the goal, led the rover away from it (seed 10 of the default yard: 8 m south
    /// of a goal to the north-east and back).
    pub(in crate::roverbug) fn fallback_step(
        &self,
        ltg: &Ltg,
        x: Point2,
        goal: Point2,
        s: f64,
    ) -> Option<Vec<Point2>> {
        let reference = goal.sub(x).angle();
        let key = |p: &Point2| s * Self::rel_angle(x, *p, reference);
        let candidates: Vec<Point2> = ltg.adj[0]
            .iter()
            .map(|&(j, _)| ltg.nodes[j].p)
            .filter(|&p| p.dist(x) > 0.2 && self.away_from_visits(p, 0.5))
            .collect();
        candidates
            .iter()
            .filter(|p| key(p) > -0.05)
            .min_by(|a, b| key(a).total_cmp(&key(b)))
            .or_else(|| candidates.iter().max_by(|a, b| key(a).total_cmp(&key(b))))
            .map(|&p| vec![x, p])
    }

    /// The locally best way on (TangentBug's heuristic): the LTG path from the rover to a node
    /// away from every position of this boundary-following segment and every restart point that
    /// minimises its length plus the node's distance to the goal, cut at the wedge radius. `ltg`
    /// is the local tangent graph from `x`.
    pub(in crate::roverbug) fn best_exit(&self, ltg: &Ltg, x: Point2, goal: Point2) -> Option<Vec<Point2>> {
        // The restart points are a preference: with every way on near one, one near a restart
        // point beats halting.
        self.best_exit_avoiding(ltg, x, goal, &self.been)
            .or_else(|| self.best_exit_avoiding(ltg, x, goal, &[]))
    }

    /// [`Self::best_exit`] avoiding this segment's positions and the points `avoid`.
    pub(in crate::roverbug) fn best_exit_avoiding(
        &self,
        ltg: &Ltg,
        x: Point2,
        goal: Point2,
        avoid: &[Point2],
    ) -> Option<Vec<Point2>> {
        let fresh = |p: Point2| p.dist(x) > 0.2 && self.visited.iter().chain(avoid).all(|q| q.dist(p) > 0.5);
        let path =
            self.search_with(ltg, goal, &|i, n: &Node| (i != 0 && fresh(n.p)).then(|| n.p.dist(goal)))?;
        let points: Vec<Point2> = path.iter().map(|&i| ltg.nodes[i].p).collect();
        let sub = self.truncate(&points, x);
        (sub.len() >= 2).then_some(sub)
    }

    /// Whether `p` lies farther than `radius` from every position of this boundary-following
    /// segment and from every restart point since motion-to-goal last made progress.
    pub(in crate::roverbug) fn away_from_visits(&self, p: Point2, radius: f64) -> bool {
        self.visited.iter().chain(&self.been).all(|q| q.dist(p) > radius)
    }

    /// Remembers a restart point (see `been`).
    pub(in crate::roverbug) fn remember(&mut self, x: Point2) {
        if self.been.last().is_none_or(|q| q.dist(x) > 1e-9) {
            self.been.push(x);
        }
    }
}
