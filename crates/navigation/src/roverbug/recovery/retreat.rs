//! Recovery 3, the retreat (departure). When planning finds no way on without a proof (the
//! local C-obstacles hem the rover in; in clutter they close gaps a nearer view may open),
//! the rover records the dead end as a small C-obstacle and drives back in reverse along its
//! recorded trail (ground the body has crossed) before a new motion-to-goal segment, at most
//! `max_retreats` times. A retreat whose turn in place the safety check refuses backs along an
//! arc to its waypoint when that sweep is clear and the waypoint lies within 45 degrees of the
//! rear: pinned where it stood, seed 14 of the default yard spent every retreat on the spot and
//! boxed itself in with dead ends (scenario test `seed_14_pinned_retreats_*`).

use crate::roverbug::{CObstacle, DriveGuard, Mode, NavCommand, Point2, Pose2, RoverBug};
use std::f64::consts::PI;

impl RoverBug {
    /// When planning finds no way on without a proof that the goal is unreachable (the local
    /// C-obstacles hem the rover in: in clutter they close gaps a nearer view may open), drives
    /// back in reverse along the recorded trail, over ground the body has already crossed, and
    /// records the dead end as a small C-obstacle so that the next motion-to-goal segment
    /// plans around it. At most `max_retreats` times; false when there is no trail to retrace.
    pub(in crate::roverbug) fn retreat(&mut self, x: Point2, goal: Point2) -> bool {
        if self.retreats >= self.config.recovery.max_retreats
            || self.stats.sensing_actions >= self.config.budgets.max_wedges
            || self.steps >= self.config.budgets.max_steps
        {
            return false;
        }
        let mut trail = self.trail.clone();
        let mut path = vec![x];
        let mut length = 0.0;
        while let Some(p) = trail.pop() {
            let last = *path.last().unwrap_or(&x);
            if p.dist(last) < 0.05 {
                continue;
            }
            length += p.dist(last);
            path.push(p);
            if length >= self.config.recovery.retreat_distance {
                break;
            }
        }
        if length < 0.3 {
            return false;
        }
        // The retreat's end stays on the trail; the retraced part is left behind.
        trail.push(*path.last().unwrap_or(&x));
        self.trail = trail;
        self.retreats += 1;
        let growth = self.terrain.growth();
        // Never around the goal: a goal inside a C-obstacle turns its vertices into goals.
        if x.dist(goal) > growth {
            self.dead_ends.push(CObstacle::from_hull(vec![x], growth, self.terrain.max_arc_step, 0));
        }
        self.finish = None;
        self.mode = Mode::MotionToGoal;
        self.visited.clear();
        self.reversing = true;
        self.execute(path);
        true
    }

    /// A retreat whose turn in place the safety check refuses backs along an arc to the
    /// waypoint instead, if that sweep is clear and the waypoint lies within 45 degrees of the
    /// rear (the arc then strays from the chord by at most about a fifth of its length): pinned where
    /// it stands, the rover otherwise spends every retreat on the spot and, each one recording
    /// a dead end there, boxes itself in (seed 14 of the default yard).
    pub(in crate::roverbug) fn reverse_arc(
        &mut self,
        pose: Pose2,
        next: Point2,
        error: f64,
    ) -> Option<NavCommand> {
        if !self.reversing || error.abs() > 0.25 * PI {
            return None;
        }
        let x = pose.position();
        let (distance, curvature) = Self::arc_to(x.dist(next), error);
        let (distance, curvature) = (-distance, -curvature);
        if !self.motion_hazards(pose, &Self::arc_poses(pose, distance, curvature)).is_empty() {
            return None;
        }
        self.waypoints.pop_front();
        self.last_motion = Some(-1.0);
        self.drive_from = Some(x);
        Some(NavCommand::Drive { distance, curvature, guard: DriveGuard::default() })
    }
}
