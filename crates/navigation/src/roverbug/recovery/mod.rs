//! The departures from paper 000 that replace its halts and aborts, as separate recovery
//! behaviours tried in a fixed order (as Nav2 keeps spin, back-up and wait as behaviour
//! plugins). The paper's halts that are proofs (the loop through `V_loop` around the goal, the
//! goal inside a C-obstacle) stand; only planning's give-ups ("trapped", "no boundary vertex
//! leads on", no subpath from the current view) and refused motions are recovered from.
//!
//! After planning gives up ([`RoverBug::recover_from_give_up`]), in order:
//! 1. [`squeeze`]: motion-to-goal once more without the safety buffer;
//! 2. [`escape`]: a short straight drive out when safety-layer hazards forbid every turn;
//! 3. [`retreat`]: back along the recorded trail, recording the dead end.
//!
//! After a motion the safety check refused ([`refuse`]): a new step; after repeated refusals
//! at one place, the escape, then the retreat, then a call for help.
//!
//! After a hazard contact or a stop at the terrain's edge ([`back_out`]): the place is recorded
//! as a small C-obstacle and the rover backs out along the ground its wheels just crossed.
//!
//! Within boundary following, [`way_on`] steps on where the paper aborts. Each module states
//! its reason and what it measured; docs/navigators/roverbug.md gathers the evidence.

mod back_out;
mod escape;
mod refuse;
mod retreat;
mod squeeze;
mod way_on;

use super::{Goal, NavCommand, Pose2, RoverBug};

/// What a recovery behaviour did.
pub(super) enum Recovered {
    /// Motion-to-goal planned a new subpath (the squeeze).
    Replanned,
    /// A motion to command (the escape, or the first motion of the retreat).
    Command(NavCommand),
    /// None applies: planning's give-up stands.
    Nothing,
}

impl RoverBug {
    /// The recoveries after planning's give-up without a proof, in order: the squeeze, the
    /// escape, the retreat.
    pub(super) fn recover_from_give_up(&mut self, pose: Pose2, goal: &Goal) -> Recovered {
        if self.squeeze(pose, goal) {
            return Recovered::Replanned;
        }
        if let Some(escape) = self.escape(pose) {
            return Recovered::Command(escape);
        }
        if self.retreat(pose.position(), goal.position) {
            return Recovered::Command(self.drive_waypoints(pose, goal.position));
        }
        Recovered::Nothing
    }
}
