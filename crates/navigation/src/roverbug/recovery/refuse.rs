//! Recovery for a motion the safety check refused (departure): a new step on fresh sensing
//! (the new plan's first leg is checked); after `max_refusals_here` refusals at one place
//! (within 0.3 m) the escape, then the retreat, then a call for help.

use crate::roverbug::{NavCommand, Outcome, Point2, Pose2, RoverBug};

impl RoverBug {
    /// The new step to command instead of a motion the safety check refused (a later leg of
    /// the subpath: the first leg of every plan is checked); after repeated refusals here,
    /// backs out if it can (see [`Self::escape`]), else retreats along the trail (see
    /// [`Self::retreat`]), else asks for help.
    pub(in crate::roverbug) fn refuse(&mut self, pose: Pose2, goal: Point2) -> NavCommand {
        let x = pose.position();
        self.waypoints.clear();
        let (count, at) = self.refusals;
        let count = if at.dist(x) < 0.3 { count + 1 } else { 1 };
        self.refusals = (count, x);
        if count > self.config.budgets.max_refusals_here {
            if let Some(escape) = self.escape(pose) {
                return escape;
            }
            // Every plan from here is refused: back out over the ground the body came by.
            if self.retreat(x, goal) {
                self.refusals = (0, x);
                return self.drive_waypoints(pose, goal);
            }
            return self.finish_now(
                Outcome::HelpRequested,
                "every motion from here sweeps the body over a sensed hazard",
            );
        }
        // Replan on fresh sensing: the new plan's first leg is checked.
        self.open_step(pose, goal)
    }
}
