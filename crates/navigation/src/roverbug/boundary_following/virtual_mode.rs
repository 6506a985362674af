//! Virtual boundary following (paper 000 section 2.2): swing the mast at `2 k alpha_mast`
//! alternately on both sides of the goal direction until the conglomerate wedge shows a
//! silhouette vertex of the blocking obstacle in its interior (then move there and start
//! normal boundary following), or halt as trapped once the scans overlap all around.
//!
//! Departure: when the scans overlap without a silhouette vertex (in clutter the C-obstacles
//! hide each other's silhouettes), the rover takes the best way on of the local tangent graph
//! (`recovery::way_on`) and halts as trapped only when there is none.

use crate::roverbug::{Mode, NavCommand, Outcome, Point2, Pose2, RoverBug};

impl RoverBug {
    /// Virtual boundary following on the conglomerate wedge: move to an interior silhouette
    /// vertex, or ask for the next mast wedge, or halt as trapped.
    pub(in crate::roverbug) fn virtual_step(&mut self, pose: Pose2, goal: Point2) -> Option<NavCommand> {
        let x = pose.position();
        let Mode::Virtual { sense, scans } = self.mode.clone() else { return None };
        if self.motion_to_goal_clear(x, goal) {
            self.mode = Mode::MotionToGoal;
            return None;
        }
        for s in [sense, -sense] {
            if let Some((path, d_reach, v_loop)) = self.silhouette(x, goal, s, true) {
                self.mode = Mode::Normal { sense: s, d_reach, v_loop, left_loop: false, scans: vec![0] };
                self.execute(path);
                return None;
            }
        }
        let Some((next, angle)) = self.next_scan(&scans, sense) else {
            // No silhouette vertex in the interior of the conglomerate wedge: in clutter the
            // blocking C-obstacles hide each other's silhouettes. Follow the best way on the
            // local tangent graph instead; halt as trapped only when there is none.
            if let Some(path) = self.best_exit(&self.build_ltg(x, goal), x, goal) {
                let d_reach = x.dist(goal);
                self.mode = Mode::Normal { sense, d_reach, v_loop: x, left_loop: false, scans: vec![0] };
                self.execute(path);
                return None;
            }
            self.stuck = true;
            return self.halt(
                Outcome::Unreachable,
                "trapped: the mast scans overlap all around and no boundary vertex leads out",
            );
        };
        let mut scans = scans;
        scans.push(next);
        self.mode = Mode::Virtual { sense, scans };
        Some(self.sense(vec![self.mast_at(pose, goal.sub(x).angle() + angle)]))
    }
}
