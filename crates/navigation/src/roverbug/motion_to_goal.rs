//! Motion-to-goal (paper 000 section 2.1): monotonic progress toward the goal. `d_LEAVE`,
//! recorded at the start and reset when boundary following is left, bounds how far from the
//! goal a motion-to-goal segment may stray; each step searches the subgraph G1 of LTG nodes no
//! farther from the goal than `min(d(x, T), d_LEAVE)` for the locally shortest path and drives
//! it cut at the wedge radius, or switches to boundary following when a blocking obstacle
//! stops it. [`RoverBug::plan`] dispatches a step to the current mode.
//!
//! Departure: a subpath that ends nearer the goal than every restart point (see
//! `recovery::way_on`) is progress, and forgets them, as past a Bug algorithm's hit points.

use super::{Mode, NavCommand, Node, Point2, Pose2, RoverBug};

impl RoverBug {
    /// Plans after new sensing; returns a command when the mode asks for more data or halts.
    pub(super) fn plan(&mut self, pose: Pose2, goal: Point2) -> Option<NavCommand> {
        let x = pose.position();
        for _ in 0..3 {
            match self.mode {
                Mode::MotionToGoal => {
                    if self.d_leave.is_none() {
                        self.d_leave = Some(x.dist(goal));
                    }
                    if self.motion_to_goal(x, goal) {
                        return None;
                    }
                    self.start_boundary_following(x, goal);
                }
                Mode::Virtual { .. } => {
                    let cmd = self.virtual_step(pose, goal);
                    if cmd.is_some() || !self.waypoints.is_empty() {
                        return cmd;
                    }
                }
                Mode::Normal { .. } => {
                    let cmd = self.normal_step(pose, goal);
                    if cmd.is_some() || !self.waypoints.is_empty() {
                        return cmd;
                    }
                }
            }
        }
        None
    }

    /// Motion-to-goal planning on the current view; false when a blocking obstacle stops it.
    pub(super) fn motion_to_goal(&mut self, x: Point2, goal: Point2) -> bool {
        let ltg = self.build_ltg(x, goal);
        let bound = x.dist(goal).min(self.d_leave.unwrap_or(f64::INFINITY));
        let Some(path) = self.search(&ltg, goal, &|n: &Node| n.arrival || n.p.dist(goal) <= bound + 1e-9)
        else {
            return false;
        };
        let points: Vec<Point2> = path.iter().map(|&i| ltg.nodes[i].p).collect();
        let sub = self.truncate(&points, x);
        let length: f64 = sub.windows(2).map(|w| w[0].dist(w[1])).sum();
        if length < 0.1 {
            return false;
        }
        // Motion-to-goal drives on toward a node of G1; its restart points are forgotten only
        // when that is progress past all of them (as Bug's hit points: a subpath back toward
        // a place boundary following started from is not).
        let end = *sub.last().expect("a subpath of positive length");
        if self.been.iter().all(|b| end.dist(goal) < b.dist(goal) - 0.3) {
            self.been.clear();
        }
        self.execute(sub);
        true
    }

    /// Whether the direct line toward the goal is free within the view (T_g exists).
    pub(super) fn motion_to_goal_clear(&self, x: Point2, goal: Point2) -> bool {
        let d = goal.sub(x);
        let tg = x.add(d.scale(d.norm().min(self.range()) / d.norm().max(1e-9)));
        !self.obstacles.iter().any(|o| o.contains_strict(goal) && o.contains(tg))
            && self.segment_free(x, tg, x)
            && self.segment_visible(x, tg)
            && tg.dist(goal) <= self.d_leave.unwrap_or(f64::INFINITY) + 1e-9
            && self.leg_clear(tg)
    }

    /// Queues a subpath for execution and records it for display.
    pub(super) fn execute(&mut self, path: Vec<Point2>) {
        self.stats.plans += 1;
        self.waypoints = path.iter().skip(1).copied().collect();
        self.drawn_paths.push(path.clone());
        self.subpath = path;
    }
}
