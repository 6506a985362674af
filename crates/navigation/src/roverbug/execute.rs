//! Subpath execution (paper 000 section 3): the waypoints of a subpath are driven one by one,
//! a turn in place toward the next waypoint (the rear when reversing along a retreat) when the
//! heading error exceeds the turn threshold, else an arc to it. Each motion is checked by the
//! safety layer first (see `safety`), and each forward drive for unseen ground (see `unseen`);
//! a refused motion goes to `recovery::refuse`.

use super::{DriveGuard, NavCommand, Outcome, Point2, Pose2, RoverBug, angle_diff};
use std::f64::consts::PI;

/// Margin by which a drive held back from unseen ground stops short of it (m).
const UNSEEN_BACKOFF: f64 = 0.1;
/// Shortest drive toward unseen ground worth commanding before looking at it (m).
const UNSEEN_MIN_DRIVE: f64 = 0.3;

impl RoverBug {
    /// Drives the queued subpath: a turn in place toward the next waypoint (the rear of the
    /// rover when reversing) or an arc to it, each checked for safety first; a new step once
    /// the subpath is done.
    pub(super) fn drive_waypoints(&mut self, pose: Pose2, goal: Point2) -> NavCommand {
        let x = pose.position();
        while let Some(&next) = self.waypoints.front() {
            if next.dist(x) < 0.05 {
                self.waypoints.pop_front();
                continue;
            }
            // Reversing, the rear leads: the heading error is taken from the reversed heading.
            let sign = if self.reversing { -1.0 } else { 1.0 };
            let lead = if self.reversing { pose.yaw + PI } else { pose.yaw };
            let error = angle_diff(next.sub(x).angle(), lead);
            if error.abs() > self.config.paper.turn_threshold {
                // The shorter way round, else the longer one, if the body's sweep is clear.
                let long = error - error.signum() * 2.0 * PI;
                let short_cells = self.motion_hazards(pose, &Self::turn_poses(pose, error));
                let angle = if short_cells.is_empty() {
                    error
                } else if self.motion_hazards(pose, &Self::turn_poses(pose, long)).is_empty() {
                    long
                } else if let Some(arc) = self.reverse_arc(pose, next, error) {
                    return arc;
                } else {
                    return self.refuse(pose, goal);
                };
                self.last_motion = Some(2.0);
                return NavCommand::Turn { angle };
            }
            let (distance, curvature) = Self::arc_to(x.dist(next), error);
            // Backwards along an arc the yaw turns the other way for the same bend.
            let (distance, curvature) = (sign * distance, sign * curvature);
            let poses = Self::arc_poses(pose, distance, curvature);
            let cells = self.motion_hazards(pose, &poses);
            if !cells.is_empty() {
                return self.refuse(pose, goal);
            }
            // Forward, the body covers only sensed ground: the seen part of the arc is driven
            // (the waypoint stays), and short of that the next step looks at the unseen part.
            // Reversing retraces the trail.
            let checked = self.config.safety.unseen_looks > 0 && !self.reversing;
            if let Some(j) = checked.then(|| self.first_unseen(pose, &poses)).flatten() {
                let seen = distance * j as f64 / poses.len() as f64 - UNSEEN_BACKOFF;
                if seen >= UNSEEN_MIN_DRIVE {
                    self.last_motion = Some(sign);
                    self.drive_from = Some(x);
                    return NavCommand::Drive { distance: seen, curvature, guard: DriveGuard::default() };
                }
                let (count, at) = self.looks;
                let count = if at.dist(x) < 0.3 { count + 1 } else { 1 };
                self.looks = (count, x);
                if count > self.config.safety.unseen_looks {
                    return self.refuse(pose, goal);
                }
                self.look_at = Some(poses[j].position());
                self.waypoints.clear();
                return self.open_step(pose, goal);
            }
            self.waypoints.pop_front();
            self.last_motion = Some(sign);
            self.drive_from = Some(x);
            return NavCommand::Drive { distance, curvature, guard: DriveGuard::default() };
        }
        // Subpath done: a goal vertex reached, or a new step.
        if self
            .obstacles
            .iter()
            .any(|o| o.contains_strict(goal) && o.vertices.iter().any(|v| v.dist(x) < 0.3))
        {
            return NavCommand::Finish(Outcome::Reached, "at a vertex of the goal's C-obstacle".into());
        }
        self.open_step(pose, goal)
    }

    /// Length and curvature of the arc that starts along the current heading and ends at a
    /// point `chord` metres away, `error` radians off the heading.
    pub(super) fn arc_to(chord: f64, error: f64) -> (f64, f64) {
        let curvature = if chord > 1e-6 { 2.0 * error.sin() / chord } else { 0.0 };
        let distance = if error.abs() > 1e-6 { chord * error / error.sin() } else { chord };
        (distance, curvature)
    }

    /// Poses along a turn in place by `angle` from `pose`, a few degrees apart.
    pub(super) fn turn_poses(pose: Pose2, angle: f64) -> Vec<Pose2> {
        let n = (angle.abs() / 4f64.to_radians()).ceil().max(1.0) as usize;
        (1..=n).map(|k| Pose2::new(pose.x, pose.y, pose.yaw + angle * k as f64 / n as f64)).collect()
    }

    /// Poses along an arc of signed length `distance` and `curvature` from `pose`, 5 cm apart.
    pub(super) fn arc_poses(pose: Pose2, distance: f64, curvature: f64) -> Vec<Pose2> {
        let n = (distance.abs() / 0.05).ceil().max(1.0) as usize;
        (1..=n)
            .map(|k| {
                let s = distance * k as f64 / n as f64;
                let yaw = pose.yaw + curvature * s;
                if curvature.abs() < 1e-9 {
                    Pose2::new(pose.x + s * pose.yaw.cos(), pose.y + s * pose.yaw.sin(), pose.yaw)
                } else {
                    Pose2::new(
                        pose.x + (yaw.sin() - pose.yaw.sin()) / curvature,
                        pose.y - (yaw.cos() - pose.yaw.cos()) / curvature,
                        yaw,
                    )
                }
            })
            .collect()
    }
}
