//! Recovery after a hazard contact or a stop at the terrain's edge (departure): the place the
//! body met the terrain is recorded as a small C-obstacle (the paper passes "explicitly
//! recorded points" between steps), so that no later subpath leads there again, and the rover
//! backs out along the ground its wheels just crossed, at most 0.3 m and no farther than the
//! drive went (reversing farther leads onto ground the body has not covered). After
//! `max_contacts_here` contacts around one place (within 0.6 m) it asks for help.

use crate::roverbug::{CObstacle, DriveGuard, NavCommand, Outcome, Point2, Pose2, RoverBug};

impl RoverBug {
    /// Records where the body met the terrain and backs out the way the wheels came (forward
    /// after a contact driving in reverse), or asks for help after repeated contacts here.
    pub(in crate::roverbug) fn back_out(&mut self, pose: Pose2) -> NavCommand {
        let x = pose.position();
        let half = 0.5 * self.rover.length;
        let touched: Vec<Point2> = match self.last_motion {
            Some(sign) if sign.abs() < 2.0 => vec![pose.transform(Point2::new(sign * half, 0.0))],
            _ => vec![
                pose.transform(Point2::new(half, 0.5 * self.rover.width)),
                pose.transform(Point2::new(half, -0.5 * self.rover.width)),
            ],
        };
        for p in touched {
            let growth = self.terrain.growth();
            self.contacts.push(CObstacle::from_hull(vec![p], growth, self.terrain.max_arc_step, 0));
        }
        let here = self.contacts.iter().filter(|o| o.hull.iter().any(|h| h.dist(x) < 0.6)).count();
        if here >= self.config.budgets.max_contacts_here {
            return self.finish_now(
                Outcome::HelpRequested,
                "repeated hazard contacts or terrain-edge stops at the same place",
            );
        }
        // Back out along the ground the wheels just crossed: reversing farther than the drive
        // went (after a turn in place, hardly at all) leads onto ground the body has not
        // covered.
        let back = match (self.last_motion, self.drive_from) {
            (Some(sign), Some(from)) if sign.abs() < 2.0 => x.dist(from).clamp(0.1, 0.3),
            _ => 0.3,
        };
        // Out the way the wheels came: forward after a contact driving in reverse.
        let dir = if self.last_motion.is_some_and(|s| s < 0.0) { 1.0 } else { -1.0 };
        self.backing_out = true;
        self.reversing = false;
        self.last_motion = Some(dir);
        NavCommand::Drive { distance: dir * back, curvature: 0.0, guard: DriveGuard::default() }
    }
}
