//! AutoPlace (paper 003 section 4): from stereo views and a commanded target to a safe
//! placement, or a refusal naming its reason with nothing moved.
//!
//! Order of operations (section 4.1): the terrain model from every view (lines of sight from
//! each view's cameras; volumes known to hold no terrain - the rover's body and the stowed arm -
//! are marked free, the rest of what no line of sight crossed stays unknown); candidate targets
//! from the targeting view only (the "ultimate" pair); each candidate's normal and roughness;
//! then reachability and a safe trajectory. The first feasible candidate is placed.
//!
//! A second view's points, when given, check each candidate's normal (see [`crate::targets`]).
//!
//! A refusal reports the furthest stage any candidate reached: no_data (no sensed point near
//! the target, or too few around every candidate) < normal < roughness < reach < collision.

use crate::arm::Arm;
use crate::feasibility::{Infeasible, Plan, PlanParams, plan};
use crate::geometry::{Aabb, V3};
use crate::octree::{Octree, OctreeParams, View};
use crate::targets::{Candidate, Rejection, Surface, TargetParams};

/// Every setting of AutoPlace.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AutoPlaceParams {
    /// Terrain model.
    pub octree: OctreeParams,
    /// Target selection.
    pub targets: TargetParams,
    /// Trajectory generation.
    pub plan: PlanParams,
}

/// Why AutoPlace refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Reason {
    /// No sensed surface near the target, or too few points around every candidate.
    NoData,
    /// No candidate's normal can be approached within 10 deg.
    Normal,
    /// Every approachable candidate is too rough.
    Roughness,
    /// No candidate is within the arm's reach and joint limits.
    Reach,
    /// Every reachable candidate's trajectory meets unverified space, the arm or the rover.
    Collision,
}

impl Reason {
    /// Every reason, in order.
    pub const ALL: [Reason; 5] =
        [Reason::NoData, Reason::Normal, Reason::Roughness, Reason::Reach, Reason::Collision];

    /// The reason's name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Reason::NoData => "no_data",
            Reason::Normal => "normal",
            Reason::Roughness => "roughness",
            Reason::Reach => "reach",
            Reason::Collision => "collision",
        }
    }
}

/// The result of one AutoPlace request.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
#[serde(tag = "outcome", rename_all = "snake_case")]
pub enum Outcome {
    /// A safe trajectory to a target was found.
    Placed {
        /// The chosen target.
        target: Candidate,
        /// The trajectory.
        plan: Plan,
        /// Candidates examined (this one included).
        examined: usize,
    },
    /// Nothing moves.
    Refused {
        /// Why.
        reason: Reason,
        /// Candidates examined.
        examined: usize,
    },
}

impl Outcome {
    /// The refusal reason, if refused.
    pub fn reason(&self) -> Option<Reason> {
        match self {
            Outcome::Refused { reason, .. } => Some(*reason),
            Outcome::Placed { .. } => None,
        }
    }
}

/// The terrain model from the views, with the rover's body and the stowed arm marked free.
pub fn terrain_model(arm: &Arm, views: &[View], params: &OctreeParams) -> Octree {
    let mut tree = Octree::build(params.clone(), views);
    let mut known: Vec<Aabb> = arm.rover.clone();
    known.push(arm.stow_volume());
    for b in &known {
        tree.clear_box(b);
    }
    tree
}

/// Runs AutoPlace: `views` build the terrain model, `targeting` (the ultimate pair's points)
/// chooses the target near `commanded` (body frame, m), `check` (another pair's points, if
/// any) must agree with each candidate's normal. Returns the outcome and the model.
pub fn autoplace(
    arm: &Arm,
    views: &[View],
    targeting: &[[f32; 3]],
    check: Option<&[[f32; 3]]>,
    commanded: &V3,
    params: &AutoPlaceParams,
) -> (Outcome, Octree) {
    let tree = terrain_model(arm, views, &params.octree);
    let outcome = place_with(arm, &tree, targeting, check, commanded, params);
    (outcome, tree)
}

/// Target selection and trajectory search against a terrain model already built.
pub fn place_with(
    arm: &Arm,
    tree: &Octree,
    targeting: &[[f32; 3]],
    check: Option<&[[f32; 3]]>,
    commanded: &V3,
    params: &AutoPlaceParams,
) -> Outcome {
    let surface = Surface::new(targeting);
    let second = check.map(Surface::new);
    let Some(candidates) = surface.candidates(commanded, &params.targets) else {
        return Outcome::Refused { reason: Reason::NoData, examined: 0 };
    };
    let mut furthest = Reason::NoData;
    for (i, p) in candidates.iter().enumerate() {
        let checked = surface.evaluate(p, &params.targets).and_then(|c| match &second {
            None => Ok(c),
            Some(s) => match s.normal_at(&V3::from(c.point), &params.targets) {
                None => Err(Rejection::NoData),
                Some(n)
                    if n.angle(&V3::from(c.normal)).to_degrees() > params.targets.max_disagreement_deg =>
                {
                    Err(Rejection::Normal)
                }
                Some(_) => Ok(c),
            },
        });
        let c = match checked {
            Ok(c) => c,
            Err(r) => {
                furthest = furthest.max(match r {
                    Rejection::NoData => Reason::NoData,
                    Rejection::Normal => Reason::Normal,
                    Rejection::Roughness => Reason::Roughness,
                });
                continue;
            }
        };
        match plan(arm, tree, &V3::from(c.point), &V3::from(c.normal), &params.plan) {
            Ok(plan) => return Outcome::Placed { target: c, plan, examined: i + 1 },
            Err(Infeasible::Reach) => furthest = furthest.max(Reason::Reach),
            Err(Infeasible::Collision) => furthest = furthest.max(Reason::Collision),
        }
    }
    Outcome::Refused { reason: furthest, examined: candidates.len() }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rovernav_core::RoverConfig;

    /// Level ground (or tilted by `slope`) every centimetre, seen from high above.
    fn ground(slope: f32) -> Vec<[f32; 3]> {
        let mut pts = Vec::new();
        for i in 0..140 {
            for j in 0..140 {
                let x = i as f32 * 0.012;
                pts.push([x, -0.7 + j as f32 * 0.01, slope * (x - 0.95)]);
            }
        }
        pts
    }

    #[test]
    fn a_second_view_that_disagrees_or_saw_nothing_refuses_the_candidate() {
        let arm = Arm::new(&RoverConfig::default());
        let cams = [V3::new(0.9, 0.0, 1.5), V3::new(0.9, -0.2, 1.5)];
        let pts = ground(0.0);
        let views = [View { cameras: &cams, points: &pts }];
        let params = AutoPlaceParams::default();
        let target = V3::new(0.95, 0.0, 0.0);
        let run = |check: Option<&[[f32; 3]]>| autoplace(&arm, &views, &pts, check, &target, &params).0;
        assert!(matches!(run(None), Outcome::Placed { .. }));
        assert!(matches!(run(Some(&pts)), Outcome::Placed { .. }));
        // 0.2 rise per metre: 11 deg off the targeting view's level normal.
        assert_eq!(run(Some(&ground(0.2))).reason(), Some(Reason::Normal));
        let elsewhere: Vec<[f32; 3]> = pts.iter().filter(|p| p[0] < 0.5).copied().collect();
        assert_eq!(run(Some(&elsewhere)).reason(), Some(Reason::NoData));
    }
}
