//! A placement in time: the joint states the arm passes through, from the stowed pose out to
//! the contact, a dwell while the instrument works, and back to the stowed pose the same way.
//!
//! Each joint-space segment lasts as long as its largest joint change takes at
//! [`Timing::joint_rate`] (all joints move together, arriving at once); the straight move of
//! the approach runs at [`Timing::approach_speed`] along the instrument's axis. The rates are
//! this project's (MER's IDD moved its joints at a few degrees per second; the flight figures
//! are not in the sources).

use crate::arm::{Arm, Joints};
use crate::feasibility::Plan;

/// How fast the arm moves and how long the instrument works.
#[derive(Clone, Debug, PartialEq)]
pub struct Timing {
    /// Joint rate of the free moves (rad/s).
    pub joint_rate: f64,
    /// Speed of the straight move to contact (m/s).
    pub approach_speed: f64,
    /// The instrument's time in contact (s).
    pub dwell_s: f64,
}

impl Default for Timing {
    fn default() -> Self {
        Self { joint_rate: 5f64.to_radians(), approach_speed: 0.005, dwell_s: 30.0 }
    }
}

/// One joint state of the arm at a time after the placement started.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct JointState {
    /// Time since the arm started moving (s).
    pub t: f64,
    /// Joint angles: azimuth, shoulder, elbow, wrist, turret (rad).
    pub q: Joints,
}

/// The joint states of a placement: out along the via-points and the approach, the dwell at
/// contact, and back the same way to the stowed pose. The first and last are the plan's first
/// via-point (stowed); times strictly increase.
pub fn schedule(arm: &Arm, plan: &Plan, timing: &Timing) -> Vec<JointState> {
    let rate = timing.joint_rate.max(1e-6);
    let speed = timing.approach_speed.max(1e-6);
    let mut path: Vec<(Joints, f64)> = Vec::new();
    let push = |path: &mut Vec<(Joints, f64)>, q: Joints, by_tip: bool| {
        let Some(&(prev, _)) = path.last() else {
            path.push((q, 0.0));
            return;
        };
        let dt = if by_tip {
            (arm.forward(&q).tip - arm.forward(&prev).tip).norm() / speed
        } else {
            prev.iter().zip(&q).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max) / rate
        };
        if dt > 0.0 {
            path.push((q, dt));
        }
    };
    for q in &plan.via {
        push(&mut path, *q, false);
    }
    for q in &plan.approach {
        push(&mut path, *q, true);
    }
    let out = path.len();
    // The dwell: the contact pose held.
    if let Some(&(q, _)) = path.last() {
        path.push((q, timing.dwell_s.max(0.0)));
    }
    let back: Vec<Joints> = plan.via.iter().chain(&plan.approach).rev().skip(1).copied().collect();
    let approach_back = plan.approach.len().saturating_sub(1);
    for (i, q) in back.into_iter().enumerate() {
        push(&mut path, q, i < approach_back);
    }
    let mut t = 0.0;
    let mut states = Vec::with_capacity(path.len());
    for (i, (q, dt)) in path.into_iter().enumerate() {
        t += dt;
        if i == out && dt == 0.0 {
            continue;
        }
        states.push(JointState { t, q });
    }
    states
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::V3;
    use crate::octree::{Octree, OctreeParams};
    use rovernav_core::RoverConfig;

    #[test]
    fn a_schedule_goes_out_dwells_and_comes_back_at_the_stated_rates() {
        let arm = Arm::new(&RoverConfig::default());
        let mut tree = Octree::unknown(OctreeParams::default());
        let all = crate::geometry::Aabb::new([-5.0, -5.0, 0.0], [5.0, 5.0, 5.0]);
        tree.clear_box(&all);
        let p = crate::feasibility::plan(
            &arm,
            &tree,
            &V3::new(0.95, -0.1, 0.0),
            &V3::new(0.0, 0.0, 1.0),
            &Default::default(),
        )
        .expect("level open ground in reach");
        let timing = Timing::default();
        let s = schedule(&arm, &p, &timing);
        assert_eq!(s.first().unwrap().q, arm.stowed());
        assert_eq!(s.last().unwrap().q, arm.stowed());
        assert!(s.windows(2).all(|w| w[1].t > w[0].t), "times increase");
        // No joint ever moves faster than the rate; the tip's straight move no faster than its speed.
        for w in s.windows(2) {
            let dt = w[1].t - w[0].t;
            let dq = w[0].q.iter().zip(&w[1].q).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
            let dtip = (arm.forward(&w[1].q).tip - arm.forward(&w[0].q).tip).norm();
            assert!(dq / dt <= timing.joint_rate + 1e-9 || dtip / dt <= timing.approach_speed + 1e-9);
        }
        // The dwell: the contact pose held for the instrument's time.
        let contact = *p.approach.last().unwrap();
        let held: Vec<&JointState> = s.iter().filter(|j| j.q == contact).collect();
        assert_eq!(held.len(), 2);
        assert!((held[1].t - held[0].t - timing.dwell_s).abs() < 1e-9);
    }
}
