//! Recovery 2, the escape (departure). When planning gave up with the rover pinned by
//! safety-layer hazards (it cannot turn all the way round in place), a short straight drive
//! out, backwards first, replaces the halt: the hazards restrict its turns, not the
//! C-obstacles its way. At most twice in one place (within 0.5 m). Boundary following goes on
//! in the same sense toward the same `V_loop` across an escape: a restart chose the shorter
//! side afresh, and inside the U-trap scenario that flipped from place to place.

use crate::roverbug::{DriveGuard, Mode, NavCommand, Pose2, RoverBug};
use std::f64::consts::PI;

impl RoverBug {
    /// When planning gave up with the rover pinned by safety-layer hazards (it cannot turn
    /// all the way round in place), a short straight drive out, backwards first (the way the
    /// rover came), replaces the halt: the hazards restrict its turns, not the C-obstacles its
    /// way. At most twice in one place.
    pub(in crate::roverbug) fn escape(&mut self, pose: Pose2) -> Option<NavCommand> {
        if self.stats.sensing_actions >= self.config.budgets.max_wedges {
            return None;
        }
        let pinned = !self.motion_hazards(pose, &Self::turn_poses(pose, 2.0 * PI)).is_empty();
        let x = pose.position();
        let (count, at) = self.escapes;
        let count = if at.dist(x) < 0.5 { count + 1 } else { 1 };
        if !pinned || count > 2 {
            return None;
        }
        let distance = [-self.config.recovery.escape_distance, self.config.recovery.escape_distance]
            .into_iter()
            .find(|&d| self.motion_hazards(pose, &Self::arc_poses(pose, d, 0.0)).is_empty())?;
        self.escapes = (count, x);
        self.remember(x);
        self.finish = None;
        // The short drive out is a motion, not a decision of the planner: boundary following
        // goes on in the same sense toward the same V_loop (a restart would choose the sense
        // afresh, and inside a U-shaped trap the shorter side flips from place to place).
        if !matches!(self.mode, Mode::Normal { .. }) {
            self.mode = Mode::MotionToGoal;
        }
        self.last_motion = Some(distance.signum());
        self.drive_from = Some(x);
        Some(NavCommand::Drive { distance, curvature: 0.0, guard: DriveGuard::default() })
    }
}
