//! Normal boundary following (paper 000 section 2.2): at each step look toward the goal and
//! leave when a reachable node of G1 is closer to the goal than `d_reach` (the leaving
//! condition d(V, T) < d_reach, resetting `d_LEAVE`), halt as unreachable when the loop point
//! `V_loop` comes back, and otherwise move to the farthest visible boundary vertex in the
//! positive sense, turning the gaze when none is in view.
//!
//! Departures: the way to a node that beats `d_reach` must lie on sensed ground (beyond the
//! cut radius the tangent graph also crosses unimaged ground, where the ring scenario's rocks
//! have no C-obstacles, and each leave through it restarted boundary following); when the gaze
//! has turned all around without a silhouette vertex (the paper aborts), the rover takes
//! boundary following's blocked step (`recovery::way_on`).

use crate::roverbug::{Mode, NavCommand, Node, Outcome, Point2, Pose2, RoverBug};

impl RoverBug {
    /// Normal boundary following: leave when a reachable node beats `d_reach`, halt when the
    /// loop point comes back, else move to the next silhouette vertex in the positive sense
    /// (turning the gaze when none is in view).
    pub(in crate::roverbug) fn normal_step(&mut self, pose: Pose2, goal: Point2) -> Option<NavCommand> {
        let x = pose.position();
        let Mode::Normal { sense, d_reach, v_loop, mut left_loop, scans } = self.mode.clone() else {
            return None;
        };
        let ltg = self.build_ltg(x, goal);
        // Leaving condition: a reachable node of G1 closer to the goal than d_reach.
        let bound = x.dist(goal).min(self.d_leave.unwrap_or(f64::INFINITY));
        let leave = self.search(&ltg, goal, &|n: &Node| {
            n.arrival || (n.p.dist(goal) <= bound + 1e-9 && n.p.dist(goal) < d_reach)
        });
        // The way to a node that beats d_reach must lie on sensed ground: beyond the cut radius
        // the tangent graph also crosses ground no image covered, where an encircling
        // obstacle's rocks have no C-obstacles, and a leave through it would restart boundary
        // following (with a new V_loop) each time the rover drives up to it.
        let leave = leave.filter(|path| {
            path.windows(2).all(|w| self.segment_sensed(ltg.nodes[w[0]].p, ltg.nodes[w[1]].p))
        });
        if let Some(path) = leave {
            let end = ltg.nodes[*path.last().expect("non-empty path")];
            self.d_leave = Some(end.p.dist(goal));
            self.been.clear();
            self.mode = Mode::MotionToGoal;
            let points: Vec<Point2> = path.iter().map(|&i| ltg.nodes[i].p).collect();
            let sub = self.truncate(&points, x);
            self.execute(sub);
            return None;
        }
        self.visited.push(x);
        left_loop |= x.dist(v_loop) > 2.0;
        if left_loop && x.dist(v_loop) < 1.0 && self.encircles_goal(goal, None) {
            return self.halt(
                Outcome::Unreachable,
                "boundary following completed a loop around the obstacle (V_loop): the goal is unreachable",
            );
        }
        if let Some((path, seen_reach, _)) = self.silhouette(x, goal, sense, false) {
            let target = *path.last().expect("non-empty subpath");
            if left_loop && target.dist(v_loop) < 1.0 && self.encircles_goal(goal, Some(target)) {
                return self.halt(
                    Outcome::Unreachable,
                    "boundary following reached V_loop again: the goal is unreachable",
                );
            }
            let d_reach = d_reach.min(seen_reach);
            self.mode = Mode::Normal { sense, d_reach, v_loop, left_loop, scans: vec![0] };
            self.execute(path);
            return None;
        }
        let Some((next, angle)) = self.next_scan(&scans, sense) else {
            // The gaze has turned all around without a silhouette vertex in the interior of the
            // conglomerate wedge (paper: abort). In clutter, step on instead (along the boundary,
            // or toward the goal once it has led too far away); abort only when there is none.
            // The graph built for the leaving condition: nothing it depends on has changed.
            if let Some(path) = self.blocked_step(&ltg, x, goal, sense, d_reach) {
                self.mode = Mode::Normal { sense, d_reach, v_loop, left_loop, scans: vec![0] };
                self.execute(path);
                return None;
            }
            self.stuck = true;
            return self.halt(
                Outcome::HelpRequested,
                "boundary following: the scans overlap all around and no boundary vertex leads on",
            );
        };
        let mut scans = scans;
        scans.push(next);
        self.mode = Mode::Normal { sense, d_reach, v_loop, left_loop, scans };
        Some(self.sense(vec![self.mast_at(pose, goal.sub(x).angle() + angle)]))
    }
}
