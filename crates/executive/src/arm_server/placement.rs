//! One instrument placement by AutoPlace (paper 003 section 4; `rovernav_manipulation`) from the
//! images the platform took: the ultimate front Hazcam pair (target selection and terrain), the
//! penultimate one taken a step back (it sees the ground in front of the body the rover now
//! stands over; its points move into the final body frame by the two pose estimates) and the
//! Navcam pair pointed down at the work volume (terrain above the Hazcams' height and a second
//! look at each candidate's normal), all correlated on board, as `rovernav eval autoplace` does.
//! Only images and the pose estimates come in; the simulator's truth never.

use crate::messages::ImageMsg;
use nalgebra::Isometry3;
use rovernav_core::{Pose3, RoverConfig};
use rovernav_manipulation::geometry::V3;
use rovernav_manipulation::motion::{Timing, schedule};
use rovernav_manipulation::sensing::{Correlation, Pair, correlate, mask_rover};
use rovernav_manipulation::{Arm, AutoPlaceParams, Cell, Outcome, View, autoplace};
use rovernav_vision::image::Grey16;
use rovernav_vision::rig::Rig;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Navcam tilt of the work-volume pair (rad): the head looks 52 deg down at the arm's reach.
pub const NAVCAM_TILT: f64 = -52.0 * std::f64::consts::PI / 180.0;

/// Every N-th sensed point of the Hazcam pair goes into the placement message (for the picture).
const POINT_STRIDE: usize = 4;

/// One joint state of the arm.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct JointStateMsg {
    /// Simulated time (s).
    pub t: f64,
    /// Joint angles: azimuth, shoulder, elbow, wrist, turret (rad).
    pub q: [f64; 5],
}

/// The chosen target (body frame at the placement).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct TargetMsg {
    /// Surface point (m).
    pub point: [f64; 3],
    /// Estimated outward surface normal.
    pub normal: [f64; 3],
    /// Height variation across the patch relative to its plane (m).
    pub roughness: f64,
}

/// The terrain octree, compactly: every stored occupied and unknown leaf as its centre and side
/// (merged octants whole; what is neither is free: verified by a line of sight).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct OctreeMsg {
    /// Lower corner of the cube (body frame, m).
    pub min: [f64; 3],
    /// Side of the cube (m).
    pub size: f64,
    /// Leaf cell size (m).
    pub leaf: f64,
    /// Occupied cells: x, y, z of the centre and the side (m).
    pub occupied: Vec<[f32; 4]>,
    /// Unknown cells: x, y, z of the centre and the side (m).
    pub unknown: Vec<[f32; 4]>,
}

/// One placement: the decision, the arm's joint states over time and the terrain model.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct PlacementMsg {
    /// The arm command's task id.
    pub task: u64,
    /// Simulated time of the decision (s).
    pub t: f64,
    /// `placed` or `refused`.
    pub outcome: String,
    /// Why refused: `no_data`, `normal`, `roughness`, `reach` or `collision`.
    pub reason: Option<String>,
    /// Candidates examined.
    pub examined: usize,
    /// The pose estimate the body frame stands at (world frame).
    pub pose: Pose3,
    /// The commanded target (body frame, m).
    pub commanded: [f64; 3],
    /// The chosen target, if placed.
    pub target: Option<TargetMsg>,
    /// Direction the instrument moves along into the surface (body frame), if placed.
    pub axis: Option<[f64; 3]>,
    /// Angle between the approach and the estimated surface normal (deg), if placed.
    pub contact_angle_deg: Option<f64>,
    /// The plan's via-points: stowed, unstowed, at the work azimuth, standoff (rad).
    pub via: Vec<[f64; 5]>,
    /// The straight move from standoff to contact, one pose per centimetre (rad).
    pub approach: Vec<[f64; 5]>,
    /// The arm's joint states over time (simulated time, s): out, the dwell, back to stowed.
    pub joints: Vec<JointStateMsg>,
    /// The terrain octree.
    pub octree: OctreeMsg,
    /// Every fourth point the Hazcam pair sensed inside the octree's cube (body frame, m).
    pub points: Vec<[f32; 3]>,
    /// Points each pair sensed, by pair.
    pub sensed: BTreeMap<String, usize>,
}

impl PlacementMsg {
    /// A body-frame point in the world frame, by the pose estimate.
    pub fn to_world(&self, p: [f64; 3]) -> [f64; 3] {
        self.pose.transform(p)
    }

    /// The report's summary (world frame by the pose estimate).
    pub fn report(&self) -> crate::report::PlacementReport {
        let r = self.pose.rotation();
        let rotate = |v: [f64; 3]| [0, 1, 2].map(|i| r[i][0] * v[0] + r[i][1] * v[1] + r[i][2] * v[2]);
        crate::report::PlacementReport {
            outcome: self.outcome.clone(),
            reason: self.reason.clone(),
            contact_angle_deg: self.contact_angle_deg,
            target: self.target.map(|t| self.to_world(t.point)),
            normal: self.target.map(|t| rotate(t.normal)),
            examined: self.examined,
        }
    }

    /// The instant the arm is back in its stowed pose (s).
    pub fn end_s(&self) -> f64 {
        self.joints.last().map_or(self.t, |j| j.t)
    }
}

/// The two images of a named pair in a frame, as images.
fn pair_images(images: &[ImageMsg], left: &str, right: &str) -> Result<(Grey16, Grey16, u32), String> {
    let find = |name: &str| {
        let i = images.iter().find(|i| i.camera == name).ok_or(format!("no {name} image"))?;
        let img = Grey16::from_raw(i.width, i.height, i.pixels.clone()).ok_or(format!(
            "{name}: {} pixels for a {}x{} image",
            i.pixels.len(),
            i.width,
            i.height
        ))?;
        Ok::<_, String>((img, i.width))
    };
    let (l, w) = find(left)?;
    let (r, _) = find(right)?;
    Ok((l, r, w))
}

/// The images of a placement: the ultimate frame's, and the penultimate Hazcam pair's with the
/// pose estimate it was taken at.
pub struct Views<'a> {
    /// Ultimate front Hazcam pair and the Navcam pair.
    pub ultimate: &'a [ImageMsg],
    /// Penultimate front Hazcam pair and its pose estimate.
    pub penultimate: Option<(&'a [ImageMsg], &'a Pose3)>,
}

/// A pose as an isometry (body -> world).
fn isometry(p: &Pose3) -> Isometry3<f64> {
    let r = nalgebra::Matrix3::from_fn(|i, j| p.rotation()[i][j]);
    let rot = nalgebra::UnitQuaternion::from_matrix(&r);
    Isometry3::from_parts(nalgebra::Translation3::new(p.x, p.y, p.z), rot)
}

/// Correlates one pair of `images` taken in the body frame `to_final` moves into the final one.
fn sense_pair(
    name: &str,
    images: &[ImageMsg],
    (left, right, tilt): (&str, &str, f64),
    to_final: &Isometry3<f64>,
    rover: &RoverConfig,
) -> Result<Pair, String> {
    let (l, r, width) = pair_images(images, left, right)?;
    let rig = Rig::new(rover).with_size(width as usize);
    let model = |n: &str| rig.camera(n, 0.0, tilt).map(|c| c.model).ok_or(format!("no rig camera {n}"));
    correlate(name, &model(left)?, &model(right)?, &l, &r, to_final, &Correlation::default())
}

/// Correlates the ultimate Hazcam, Navcam and (if taken) penultimate Hazcam pairs, in the final
/// body frame (the estimate `pose`), in that order.
pub fn sense(views: &Views, pose: &Pose3, rover: &RoverConfig, arm: &Arm) -> Result<Vec<Pair>, String> {
    const HAZCAM: (&str, &str, f64) = ("hazcam_front_left", "hazcam_front_right", 0.0);
    let here = Isometry3::identity();
    let mut pairs = vec![sense_pair("hazcam_ultimate", views.ultimate, HAZCAM, &here, rover)?];
    let mut navcam =
        sense_pair("navcam", views.ultimate, ("navcam_left", "navcam_right", NAVCAM_TILT), &here, rover)?;
    // The Navcams look down past the deck (the Hazcams sit in the body's front face).
    mask_rover(&mut navcam, &arm.rover);
    pairs.push(navcam);
    if let Some((images, at)) = views.penultimate {
        let to_final = isometry(pose).inverse() * isometry(at);
        pairs.push(sense_pair("hazcam_penultimate", images, HAZCAM, &to_final, rover)?);
    }
    Ok(pairs)
}

/// The commanded world point (x, y) in the body frame of `pose`, at the height of the sensed
/// surface there (the median height of the Hazcam points within 5 cm; the body's ground plane
/// when none).
pub fn commanded_in_body(pose: &Pose3, xy: [f64; 2], points: &[[f32; 3]]) -> V3 {
    let r = pose.rotation();
    let d = [xy[0] - pose.x, xy[1] - pose.y, 0.0];
    // R^T d with the world height left at the body origin's.
    let body = V3::new(
        r[0][0] * d[0] + r[1][0] * d[1],
        r[0][1] * d[0] + r[1][1] * d[1],
        r[0][2] * d[0] + r[1][2] * d[1],
    );
    let mut near: Vec<f32> = points
        .iter()
        .filter(|p| (p[0] as f64 - body.x).hypot(p[1] as f64 - body.y) < 0.05)
        .map(|p| p[2])
        .collect();
    near.sort_by(f32::total_cmp);
    let z = near.get(near.len() / 2).map_or(body.z, |z| *z as f64);
    V3::new(body.x, body.y, z)
}

/// Runs AutoPlace on a frame's images: the placement message (joint times from `t`, the dwell
/// `dwell_s`), or an error when the images cannot be used.
pub fn place(
    task: u64,
    t: f64,
    images: &Views,
    pose: &Pose3,
    target_xy: [f64; 2],
    rover: &RoverConfig,
    timing: &Timing,
) -> PlacementMsg {
    let arm = Arm::new(rover);
    let mut msg = PlacementMsg {
        task,
        t,
        outcome: "refused".into(),
        reason: Some("no_data".into()),
        examined: 0,
        pose: *pose,
        commanded: [f64::NAN; 3],
        target: None,
        axis: None,
        contact_angle_deg: None,
        via: Vec::new(),
        approach: Vec::new(),
        joints: Vec::new(),
        octree: OctreeMsg::default(),
        points: Vec::new(),
        sensed: BTreeMap::new(),
    };
    let Ok(pairs) = sense(images, pose, rover, &arm) else {
        msg.commanded = commanded_in_body(pose, target_xy, &[]).into();
        return msg;
    };
    let (hazcam, navcam) = (&pairs[0], &pairs[1]);
    let commanded = commanded_in_body(pose, target_xy, &hazcam.points);
    msg.commanded = commanded.into();
    msg.sensed = pairs.iter().map(|p| (p.name.clone(), p.points.len())).collect();
    let views: Vec<View> = pairs.iter().map(|p| View { cameras: &p.cameras, points: &p.points }).collect();
    let params = AutoPlaceParams::default();
    let (outcome, tree) = autoplace(&arm, &views, &hazcam.points, Some(&navcam.points), &commanded, &params);
    let p = tree.params();
    let size = p.leaf * tree.side() as f64;
    msg.octree = OctreeMsg { min: p.min, size, leaf: p.leaf, ..OctreeMsg::default() };
    for (cell, min, side) in tree.leaves() {
        let c = min + V3::repeat(0.5 * side);
        let row = [c.x as f32, c.y as f32, c.z as f32, side as f32];
        match cell {
            Cell::Occupied => msg.octree.occupied.push(row),
            Cell::Unknown => msg.octree.unknown.push(row),
            Cell::Free => {}
        }
    }
    let inside = |q: &[f32; 3]| (0..3).all(|k| (p.min[k]..p.min[k] + size).contains(&(q[k] as f64)));
    msg.points = hazcam.points.iter().filter(|q| inside(q)).step_by(POINT_STRIDE).copied().collect();
    match outcome {
        Outcome::Placed { target, plan, examined } => {
            msg.outcome = "placed".into();
            msg.reason = None;
            msg.examined = examined;
            let angle = V3::from(plan.axis).angle(&-V3::from(target.normal)).to_degrees();
            msg.contact_angle_deg = Some(angle);
            msg.target =
                Some(TargetMsg { point: target.point, normal: target.normal, roughness: target.roughness });
            msg.axis = Some(plan.axis);
            msg.joints = schedule(&arm, &plan, timing)
                .into_iter()
                .map(|j| JointStateMsg { t: t + j.t, q: j.q })
                .collect();
            msg.via = plan.via;
            msg.approach = plan.approach;
        }
        Outcome::Refused { reason, examined } => {
            msg.reason = Some(reason.name().into());
            msg.examined = examined;
        }
    }
    msg
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_commanded_point_moves_into_the_body_frame_at_the_sensed_height() {
        let pose = Pose3 { x: 10.0, y: 5.0, z: 2.0, yaw: std::f64::consts::FRAC_PI_2, ..Default::default() };
        // 1 m ahead of a rover facing north is (10, 6); the sensed ground there is 4 cm up.
        let points = [[1.0f32, 0.01, 0.04], [1.02, -0.01, 0.05], [1.0, 0.0, 0.03], [2.0, 0.0, 0.5]];
        let b = commanded_in_body(&pose, [10.0, 6.0], &points);
        assert!((b - V3::new(1.0, 0.0, 0.04)).norm() < 1e-6, "{b:?}");
        let nothing = commanded_in_body(&pose, [9.0, 5.0], &points);
        assert!((nothing - V3::new(0.0, 1.0, 0.0)).norm() < 1e-9, "{nothing:?}");
    }

    #[test]
    fn missing_images_refuse_for_no_data_and_move_nothing() {
        let rover = RoverConfig::default();
        let views = Views { ultimate: &[], penultimate: None };
        let m = place(3, 1.0, &views, &Pose3::default(), [1.0, 0.0], &rover, &Timing::default());
        assert_eq!((m.outcome.as_str(), m.reason.as_deref()), ("refused", Some("no_data")));
        assert!(m.joints.is_empty() && m.via.is_empty());
    }
}
