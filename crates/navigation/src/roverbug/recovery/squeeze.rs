//! Recovery 1, the squeeze (departure). When planning finds no way on without a proof that
//! the goal is unreachable, motion-to-goal is tried once more (once per sensing position) on
//! C-obstacles grown by the rover radius alone: the empirical safety buffer closes gaps of a
//! rock field that the rover's disc fits through, while the safety layer still checks every
//! motion against the body outline for step hazards (slope hazards have only their
//! C-obstacles; keep-out zones keep the buffer). When that finds a way on, the next
//! `squeeze_views` views keep the smaller growth (the rover then stands within the buffer of
//! the gap's rocks); otherwise the buffered C-obstacles come back.
//!
//! Measured when added: seeds 8 and 14 of the default yard fell from path ratios 1.77 and 2.63
//! to 1.07 and 1.26; a half buffer kept almost none of the gain, squeezing before every
//! boundary following brought contacts. Scenario tests `boxed_in_start_*` and
//! `seed_8_squeezes_through_*`.

use crate::roverbug::{Mode, Pose2, RoverBug};

impl RoverBug {
    /// When planning found no way on without a proof, tries motion-to-goal once more on
    /// C-obstacles grown by the rover radius alone: the empirical safety buffer closes gaps of
    /// a rock field that the rover's disc fits through. The first leg of the plan is still
    /// checked against the safety layer's step hazards (body outline plus margin), later legs
    /// at execution; slope hazards (crater walls) have only their C-obstacles. On success the
    /// next `squeeze_views` views keep the smaller growth (the rover is then within the buffer
    /// of the gap's rocks); otherwise the buffered C-obstacles come back. Tried at most once
    /// per sensing position.
    pub(in crate::roverbug) fn squeeze(&mut self, pose: Pose2, goal: &rovernav_core::Goal) -> bool {
        if self.config.recovery.squeeze_views == 0 || self.squeezed.is_some_and(|(at, _)| at == self.steps) {
            return false;
        }
        self.squeezed = Some((self.steps, true));
        self.rebuild_obstacles(pose, goal, false);
        self.waypoints.clear();
        if self.motion_to_goal(pose.position(), goal.position) {
            // Drawn as planned on.
            self.rebuild_obstacles(pose, goal, true);
            self.finish = None;
            self.mode = Mode::MotionToGoal;
            return true;
        }
        self.squeezed = Some((self.steps, false));
        self.rebuild_obstacles(pose, goal, false);
        false
    }
}
