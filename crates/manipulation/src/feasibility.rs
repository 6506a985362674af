//! Reachability and trajectory generation (paper 003 section 4.1 steps 5, 7 and 8; section 4.2):
//! inverse kinematics to the target with the instrument along the surface normal (or within
//! 10 deg of it), via-points from the stowed pose, and every via-point and the swept volume
//! between them tested against the terrain octree (occupied and unknown cells) and the rover.
//!
//! The trajectory: stowed -> unstowed (turned to the work azimuth; the safe-to-unstow check is
//! this first segment) -> standoff (the instrument [`PlanParams::standoff`] above the target on
//! the approach axis) -> a straight guarded move along the axis to the contact, 1 cm past the
//! sensed surface (the paper's overdrive). Joint-space segments are sampled so that no point of
//! the arm moves more than [`PlanParams::step`] between samples; each sample's capsules are
//! covered by spheres grown by half a step and the clearance, and every sphere must lie in
//! verified-free cells.
//!
//! On the straight move the instrument's part lower than [`PlanParams::contact_zone`] above the
//! target is exempt from the terrain test: that is where it meets the surface on purpose (the
//! surface's own cells reach a cell above it), inside the patch whose roughness was checked.

use crate::arm::{Arm, Joints, cost_between, lever_arms};
use crate::geometry::{Capsule, V3};
use crate::octree::Octree;

/// Trajectory settings.
#[derive(Clone, Debug, PartialEq)]
pub struct PlanParams {
    /// Instrument distance above the target before the straight move (m).
    pub standoff: f64,
    /// How far past the sensed surface the contact is commanded (m).
    pub overdrive: f64,
    /// On the straight move, the instrument's part lower than this above the target is exempt
    /// from the terrain test (m).
    pub contact_zone: f64,
    /// Margin kept between the arm and any cell not verified free (m).
    pub clearance: f64,
    /// Largest motion of any arm point between two checked samples (m).
    pub step: f64,
    /// Approach directions tried: tilts from the normal (deg), each at several azimuths.
    pub tilts_deg: Vec<f64>,
}

impl Default for PlanParams {
    fn default() -> Self {
        Self {
            standoff: 0.10,
            overdrive: 0.01,
            contact_zone: 0.07,
            clearance: 0.01,
            step: 0.01,
            tilts_deg: vec![0.0, 5.0],
        }
    }
}

/// A safe trajectory to a target.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Plan {
    /// Joint-space via-points: stowed, unstowed in place, unstowed at the work azimuth,
    /// standoff (rad).
    pub via: Vec<Joints>,
    /// The straight move from standoff to contact, one pose per centimetre (rad).
    pub approach: Vec<Joints>,
    /// Unit direction the instrument moves along (into the surface).
    pub axis: [f64; 3],
    /// Commanded contact point (m).
    pub contact: [f64; 3],
}

/// Why no trajectory was found.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Infeasible {
    /// No joint solution within limits for any allowed approach.
    Reach,
    /// Every solution's trajectory meets unverified space, itself or the rover.
    Collision,
}

/// Unit directions within the allowed tilts of `axis`, the axis itself first.
pub fn approach_axes(axis: &V3, tilts_deg: &[f64]) -> Vec<V3> {
    let a = axis.normalize();
    let helper = if a.x.abs() < 0.9 { V3::x() } else { V3::y() };
    let u = a.cross(&helper).normalize();
    let v = a.cross(&u);
    let mut out = Vec::new();
    for &t in tilts_deg {
        let t = t.to_radians();
        if t == 0.0 {
            out.push(a);
            continue;
        }
        for k in 0..8 {
            let phi = k as f64 * std::f64::consts::FRAC_PI_4;
            out.push(a * t.cos() + (u * phi.cos() + v * phi.sin()) * t.sin());
        }
    }
    out
}

/// Joint-space samples from `a` to `b` (both included), close enough that no arm point moves
/// more than `step` between two. Joints move linearly between their values (never through
/// +-180 deg: the limits lie inside one turn).
pub fn interpolate(arm: &Arm, a: &Joints, b: &Joints, step: f64) -> Vec<Joints> {
    let la = lever_arms(arm, a);
    let lb = lever_arms(arm, b);
    let travel: f64 = (0..5).map(|i| (b[i] - a[i]).abs() * la[i].max(lb[i])).sum();
    let n = ((travel / step).ceil() as usize).max(1);
    (0..=n)
        .map(|s| {
            let f = s as f64 / n as f64;
            std::array::from_fn(|i| a[i] + (b[i] - a[i]) * f)
        })
        .collect()
}

/// Whether the arm at `q` is clear of itself, the rover and every cell not verified free; the
/// instrument's last `exempt` metres are not tested against the terrain.
pub fn pose_clear(arm: &Arm, octree: &Octree, q: &Joints, exempt: f64, params: &PlanParams) -> bool {
    if !arm.within_limits(q) || arm.self_collides(q) || arm.hits_rover(q) {
        return false;
    }
    let caps = arm.capsules(q);
    let grow = params.clearance + 0.5 * params.step;
    caps.iter().enumerate().all(|(i, c)| {
        let c = if i == 4 { trimmed(c, exempt) } else { Some(*c) };
        let Some(c) = c else { return true };
        let spacing = 0.01;
        let extra = if c.a == c.b { 0.0 } else { 0.5 * spacing };
        c.cover(spacing).all(|p| !octree.blocked(&p, c.radius + grow + extra))
    })
}

/// Whether every sample of the joint-space motion `a` -> `b` is clear ([`pose_clear`]); the
/// samples are tested coarse to fine (every 16th first, then the ones between), so a blocked
/// motion is found early. The result does not depend on the order.
pub fn path_clear(
    arm: &Arm,
    octree: &Octree,
    a: &Joints,
    b: &Joints,
    exempt: f64,
    params: &PlanParams,
) -> bool {
    let samples = interpolate(arm, a, b, params.step);
    let n = samples.len();
    let mut stride = 16usize;
    let mut done = vec![false; n];
    loop {
        for i in (0..n).step_by(stride) {
            if !done[i] {
                done[i] = true;
                if !pose_clear(arm, octree, &samples[i], exempt, params) {
                    return false;
                }
            }
        }
        if stride == 1 {
            return true;
        }
        stride /= 2;
    }
}

/// The instrument capsule without its last `exempt` metres (`None` if nothing is left).
pub fn trimmed(c: &Capsule, exempt: f64) -> Option<Capsule> {
    let d = c.b - c.a;
    let len = d.norm();
    if exempt <= 0.0 {
        return Some(*c);
    }
    if len <= exempt {
        return None;
    }
    Some(Capsule { b: c.a + d * ((len - exempt) / len), ..*c })
}

/// Searches a safe trajectory to `point` with the instrument along `-normal` (or within the
/// allowed tilts of it).
pub fn plan(
    arm: &Arm,
    octree: &Octree,
    point: &V3,
    normal: &V3,
    params: &PlanParams,
) -> Result<Plan, Infeasible> {
    let mut reached = false;
    let stowed = arm.stowed();
    for axis in approach_axes(&-normal, &params.tilts_deg) {
        let standoff_tip = point - axis * params.standoff;
        let contact_tip = point + axis * params.overdrive;
        let azimuth = (standoff_tip.y - arm.geometry.base.y).atan2(standoff_tip.x - arm.geometry.base.x);
        let prefer = arm.unstowed(azimuth);
        for q_standoff in arm.inverse(&standoff_tip, &axis, &prefer) {
            // The straight move, one IK per centimetre, each the solution nearest the last.
            let total = params.standoff + params.overdrive;
            let n = (total / 0.01).ceil() as usize;
            let mut approach = vec![q_standoff];
            for s in 1..=n {
                let tip = standoff_tip.lerp(&contact_tip, s as f64 / n as f64);
                let last = *approach.last().expect("starts with the standoff");
                match arm.inverse(&tip, &axis, &last).first() {
                    Some(q) if cost_between(q, &last) < 0.3 => approach.push(*q),
                    _ => break,
                }
            }
            if approach.len() != n + 1 {
                continue;
            }
            reached = true;
            // Lift in place first, then turn to the work azimuth.
            let via = vec![stowed, arm.unstowed(stowed[0]), arm.unstowed(q_standoff[0]), q_standoff];
            // Along the straight move, the instrument's part lower than `contact_zone` above the
            // target may meet the surface.
            let per_pose = (params.standoff + params.overdrive) / n as f64;
            let approach_ok = approach.windows(2).enumerate().all(|(k, w)| {
                let height = params.standoff - per_pose * (k + 1) as f64;
                let exempt = (params.contact_zone - height).max(0.0);
                path_clear(arm, octree, &w[0], &w[1], exempt, params)
            });
            if approach_ok && via.windows(2).rev().all(|w| path_clear(arm, octree, &w[0], &w[1], 0.0, params))
            {
                return Ok(Plan { via, approach, axis: axis.into(), contact: contact_tip.into() });
            }
        }
    }
    Err(if reached { Infeasible::Collision } else { Infeasible::Reach })
}

#[cfg(test)]
#[cfg(test)]
mod tests {
    use super::*;
    use crate::autoplace::terrain_model;
    use crate::octree::{OctreeParams, View};
    use rovernav_core::RoverConfig;

    /// Flat ground at z = 0 seen by two cameras high above it: everything above the ground in
    /// the work volume is verified free.
    fn flat_view() -> (Vec<V3>, Vec<[f32; 3]>) {
        let cams = vec![V3::new(0.9, 0.0, 1.5), V3::new(0.9, -0.2, 1.5)];
        let mut pts = Vec::new();
        for i in 0..140 {
            for j in 0..140 {
                pts.push([0.0 + i as f32 * 0.012, -0.7 + j as f32 * 0.01, 0.0]);
            }
        }
        (cams, pts)
    }

    #[test]
    fn a_seen_flat_target_is_placed_and_a_far_one_is_out_of_reach() {
        let arm = Arm::new(&RoverConfig::default());
        let (cams, pts) = flat_view();
        let tree = terrain_model(&arm, &[View { cameras: &cams, points: &pts }], &OctreeParams::default());
        let params = PlanParams::default();
        let stowed = arm.stowed();
        assert!(pose_clear(&arm, &tree, &stowed, 0.0, &params), "stowed");
        assert!(pose_clear(&arm, &tree, &arm.unstowed(0.2), 0.0, &params), "unstowed");
        let plan = plan(&arm, &tree, &V3::new(0.95, 0.0, 0.0), &V3::z(), &params).expect("placed");
        let last = arm.forward(plan.approach.last().unwrap());
        assert!((last.tip - V3::new(0.95, 0.0, -0.01)).norm() < 1e-9);
        assert!(last.axis.angle(&-V3::z()) < 1e-9, "straight down on flat ground");
        assert_eq!(plan.via[0], arm.stowed());
        let far = super::plan(&arm, &tree, &V3::new(1.5, 0.0, 0.0), &V3::z(), &params);
        assert_eq!(far, Err(Infeasible::Reach));
    }

    #[test]
    fn an_unseen_work_volume_refuses_for_collision() {
        let arm = Arm::new(&RoverConfig::default());
        let (cams, pts) = flat_view();
        let tree = terrain_model(&arm, &[View { cameras: &cams, points: &pts }], &OctreeParams::default());
        let params = PlanParams::default();
        // Without the lines of sight, the same points leave the volume above them unknown.
        let blind = terrain_model(&arm, &[View { cameras: &[], points: &pts }], &OctreeParams::default());
        assert_eq!(
            plan(&arm, &blind, &V3::new(0.95, 0.0, 0.0), &V3::z(), &params),
            Err(Infeasible::Collision)
        );
        assert!(plan(&arm, &tree, &V3::new(0.95, 0.0, 0.0), &V3::z(), &params).is_ok());
    }
}
