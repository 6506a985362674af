//! A 5-degree-of-freedom instrument arm on the rover's front, after MER's Instrument Deployment
//! Device (IDD): forward and closed-form inverse kinematics, joint limits, the stowed pose,
//! collision with itself and with the rover body.
//!
//! The IDD (Baumgartner et al., "The Mars Exploration Rover instrument positioning system",
//! IEEE Aerospace 2005; "Robotic arm in-situ operations for the Mars Exploration Rovers surface
//! mission", IEEE SMC 2005; JPL Robotics, MER manipulating arm): five joints - azimuth (1),
//! shoulder elevation (2), elbow (3), wrist (4), turret (5) - carrying a turret of four
//! instruments, each with a contact sensor; it reaches about 0.75-0.8 m in front of the rover at
//! full extent, weighs about 4 kg with a 2 kg payload, stows for driving in a volume in front of
//! the body, and places with about 1 mm and 1 deg repeatability.
//!
//! Geometry here (body frame: x forward, y left, z up, origin on the wheels' ground plane):
//! - azimuth axis vertical through the shoulder at [`ArmGeometry::base`] = (0.50, -0.12, 0.32) m,
//!   on a bracket ahead of the body's front face, right of the Hazcams (as on MER the stowed
//!   arm lies across the front below the Hazcams);
//! - joints 2-4 are parallel pitch axes perpendicular to the arm's vertical plane: upper arm
//!   0.35 m, forearm 0.35 m, wrist link 0.10 m to the turret centre;
//! - joint 5 turns the turret about the wrist link; the instrument points perpendicular to the
//!   wrist link and its contact face is 0.15 m from the turret centre. The approach direction is
//!   therefore free in two angles, the tool's roll about its own axis is not (no instrument here
//!   needs it);
//! - reach: the contact face reaches 0.785 m horizontally from the azimuth axis on level ground
//!   with a vertical approach (1.28 m ahead of the body centre, 0.88 m ahead of the body);
//! - joint limits: azimuth -100..100 deg, shoulder -40..110 deg, elbow -175..-5 deg (the elbow
//!   bends one way, elbow up), wrist and turret -180..180 deg. These are this project's figures
//!   chosen for the stowed pose and elbow-up work, not the flight values (not published in the
//!   sources above).
//!
//! Collision model: capsules for the upper arm, forearm, wrist link and instrument, a 5 cm
//! sphere for the turret; boxes for the rover (body, deck, wheels, Hazcam bar, arm bracket).
//! Adjacent links are not checked against each other (their joint keeps them apart). The stow
//! volume (a box around the stowed arm grown 3 cm) holds no terrain by construction.
//!
//! Kinematics are written by hand rather than with the `k` crate: `k` 0.32 pulls a second
//! nalgebra (0.30) beside the workspace's 0.35, and the closed form of this arm is a planar
//! two-link solution plus two angles, shorter than a generic solver's setup and exact.

use crate::geometry::{Aabb, Capsule, V3};
use rovernav_core::RoverConfig;
use std::f64::consts::PI;

/// Joint angles (rad): azimuth, shoulder, elbow, wrist, turret.
pub type Joints = [f64; 5];

/// Dimensions and limits of the arm.
#[derive(Clone, Debug, PartialEq)]
pub struct ArmGeometry {
    /// Shoulder point on the azimuth axis (body frame, m).
    pub base: V3,
    /// Upper arm length, shoulder to elbow (m).
    pub upper: f64,
    /// Forearm length, elbow to wrist (m).
    pub fore: f64,
    /// Wrist joint to turret centre (m).
    pub wrist: f64,
    /// Turret centre to the instrument's contact face (m).
    pub tool: f64,
    /// Lower and upper limit of each joint (rad).
    pub limits: [(f64, f64); 5],
    /// Radii of the upper arm, forearm, wrist link, turret and instrument (m).
    pub radii: [f64; 5],
}

impl Default for ArmGeometry {
    fn default() -> Self {
        let d = f64::to_radians;
        Self {
            base: V3::new(0.50, -0.12, 0.32),
            upper: 0.35,
            fore: 0.35,
            wrist: 0.10,
            tool: 0.15,
            limits: [(d(-100.0), d(100.0)), (d(-40.0), d(110.0)), (d(-175.0), d(-5.0)), (-PI, PI), (-PI, PI)],
            radii: [0.03, 0.025, 0.03, 0.05, 0.02],
        }
    }
}

/// Where each part of the arm is for one set of joint angles.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArmFrames {
    /// Shoulder (m).
    pub shoulder: V3,
    /// Elbow (m).
    pub elbow: V3,
    /// Wrist joint (m).
    pub wrist: V3,
    /// Turret centre (m).
    pub turret: V3,
    /// Centre of the instrument's contact face (m).
    pub tip: V3,
    /// Unit direction the instrument points (into the surface when placed).
    pub axis: V3,
}

/// The arm: geometry and the rover it is mounted on.
#[derive(Clone, Debug, PartialEq)]
pub struct Arm {
    /// Dimensions and limits.
    pub geometry: ArmGeometry,
    /// The rover body as boxes (body frame).
    pub rover: Vec<Aabb>,
}

/// Wraps an angle to (-pi, pi].
pub fn wrap(a: f64) -> f64 {
    let mut x = (a + PI).rem_euclid(2.0 * PI) - PI;
    if x <= -PI {
        x += 2.0 * PI;
    }
    x
}

impl Arm {
    /// The default arm on a rover of the given size (wheel radius 0.10 m, half width 0.07 m, the
    /// simulator's).
    pub fn new(rover: &RoverConfig) -> Self {
        let geometry = ArmGeometry::default();
        let (l, w, c) = (rover.length, rover.width, rover.clearance);
        let deck = c + 0.22;
        let (wr, whw) = (0.10, 0.07);
        let mut boxes = vec![
            Aabb::new([-0.5 * l, -0.4 * w, c], [0.5 * l, 0.4 * w, deck]),
            Aabb::new(
                [-0.5 * l - 0.02, -0.5 * w - 0.02, deck],
                [0.5 * l + 0.02, 0.5 * w + 0.02, deck + 0.02],
            ),
            // Hazcam bar just ahead of the front face.
            Aabb::new(
                [0.5 * l, -0.08, rover.body_camera_height - 0.03],
                [0.5 * l + 0.05, 0.08, rover.body_camera_height + 0.03],
            ),
        ];
        let b = geometry.base;
        boxes.push(Aabb::new([0.5 * l, b.y - 0.04, b.z - 0.04], [b.x - 0.04, b.y + 0.04, b.z + 0.04]));
        let wx = (0.5 * l - wr).max(0.0);
        for x in [wx, 0.0, -wx] {
            for y in [0.5 * rover.track, -0.5 * rover.track] {
                boxes.push(Aabb::new([x - wr, y - whw, 0.0], [x + wr, y + whw, 2.0 * wr]));
            }
        }
        Self { geometry, rover: boxes }
    }

    /// The stowed-for-driving pose: arm pointing left across the front, forearm folded back
    /// under it, wrist link 40 deg below the upper arm's direction, instrument pointing forward.
    pub fn stowed(&self) -> Joints {
        let d = f64::to_radians;
        [d(90.0), 0.0, d(-170.0), d(130.0), d(-90.0)]
    }

    /// The unstowed pose for a work azimuth (rad): upper arm raised 60 deg, elbow opened to
    /// -130 deg, wrist link and instrument as when stowed. From the stowed pose only the
    /// shoulder, elbow and wrist move, keeping the wrist link's direction, so the folded end
    /// rises with the upper arm.
    pub fn unstowed(&self, azimuth: f64) -> Joints {
        let d = f64::to_radians;
        [azimuth, d(60.0), d(-130.0), d(30.0), d(-90.0)]
    }

    /// The stow volume: the box around the stowed arm grown by 3 cm. It holds no terrain: the
    /// rover drives with the arm in it, and terrain there would have met the arm.
    pub fn stow_volume(&self) -> Aabb {
        let mut b = Aabb { min: V3::repeat(f64::INFINITY), max: V3::repeat(f64::NEG_INFINITY) };
        for c in self.capsules(&self.stowed()) {
            let r = V3::repeat(c.radius + 0.03);
            b.min = b.min.inf(&(c.a.inf(&c.b) - r));
            b.max = b.max.sup(&(c.a.sup(&c.b) + r));
        }
        b
    }

    /// Whether every joint is within its limits.
    pub fn within_limits(&self, q: &Joints) -> bool {
        q.iter().zip(&self.geometry.limits).all(|(a, (lo, hi))| *a >= lo - 1e-9 && *a <= hi + 1e-9)
    }

    /// Forward kinematics.
    pub fn forward(&self, q: &Joints) -> ArmFrames {
        let g = &self.geometry;
        let (s1, c1) = q[0].sin_cos();
        let er = V3::new(c1, s1, 0.0);
        let ez = V3::z();
        let yl = V3::new(-s1, c1, 0.0);
        let dir = |angle: f64| er * angle.cos() + ez * angle.sin();
        let shoulder = g.base;
        let elbow = shoulder + dir(q[1]) * g.upper;
        let wrist = elbow + dir(q[1] + q[2]) * g.fore;
        let phi = q[1] + q[2] + q[3];
        let turret = wrist + dir(phi) * g.wrist;
        let w = er * phi.sin() - ez * phi.cos();
        let axis = w * q[4].cos() + yl * q[4].sin();
        ArmFrames { shoulder, elbow, wrist, turret, tip: turret + axis * g.tool, axis }
    }

    /// Every joint solution within limits that puts the contact face at `tip` pointing along
    /// `axis` (normalised here), best first (closest to `prefer`). Empty when out of reach.
    pub fn inverse(&self, tip: &V3, axis: &V3, prefer: &Joints) -> Vec<Joints> {
        let g = &self.geometry;
        let Some(a) = axis.try_normalize(1e-12) else { return Vec::new() };
        let turret = tip - a * g.tool;
        let d = turret - g.base;
        if d.x.hypot(d.y) < 1e-9 {
            return Vec::new();
        }
        let mut out = Vec::new();
        let az0 = d.y.atan2(d.x);
        for q1 in [az0, wrap(az0 + PI)] {
            let (s1, c1) = q1.sin_cos();
            let er = V3::new(c1, s1, 0.0);
            let yl = V3::new(-s1, c1, 0.0);
            let (ar, az) = (a.dot(&er), a.z);
            if ar.hypot(az) < 1e-9 {
                continue; // the axis is across the arm's plane: the wrist link is undetermined
            }
            let phi0 = (-ar).atan2(az);
            for phi in [phi0, wrap(phi0 + PI)] {
                let w = er * phi.sin() - V3::z() * phi.cos();
                let q5 = a.dot(&yl).atan2(a.dot(&w));
                let r = d.dot(&er) - g.wrist * phi.cos();
                let z = d.z - g.wrist * phi.sin();
                let cos3 = (r * r + z * z - g.upper * g.upper - g.fore * g.fore) / (2.0 * g.upper * g.fore);
                if !(-1.0 - 1e-12..=1.0 + 1e-12).contains(&cos3) {
                    continue;
                }
                let base3 = cos3.clamp(-1.0, 1.0).acos();
                for q3 in [base3, -base3] {
                    let q2 = z.atan2(r) - (g.fore * q3.sin()).atan2(g.upper + g.fore * q3.cos());
                    let q = [wrap(q1), wrap(q2), wrap(q3), wrap(phi - q2 - q3), wrap(q5)];
                    if self.within_limits(&q) {
                        out.push(q);
                    }
                }
            }
        }
        out.sort_by(|x, y| cost_between(x, prefer).total_cmp(&cost_between(y, prefer)));
        out.dedup_by(|x, y| cost_between(x, y) < 1e-9);
        out
    }

    /// The arm's collision shapes: upper arm, forearm, wrist link, turret (a sphere), instrument.
    pub fn capsules(&self, q: &Joints) -> [Capsule; 5] {
        let f = self.forward(q);
        let r = self.geometry.radii;
        let tool_start = f.turret + f.axis * r[3];
        [
            Capsule { a: f.shoulder, b: f.elbow, radius: r[0] },
            Capsule { a: f.elbow, b: f.wrist, radius: r[1] },
            Capsule { a: f.wrist, b: f.turret, radius: r[2] },
            Capsule { a: f.turret, b: f.turret, radius: r[3] },
            Capsule { a: tool_start, b: f.tip, radius: r[4] },
        ]
    }

    /// Whether two non-adjacent parts of the arm meet.
    pub fn self_collides(&self, q: &Joints) -> bool {
        let c = self.capsules(q);
        [(0, 2), (0, 3), (0, 4), (1, 3), (1, 4)].iter().any(|&(i, j)| c[i].touches(&c[j]))
    }

    /// Whether any part of the arm meets the rover body.
    pub fn hits_rover(&self, q: &Joints) -> bool {
        let c = self.capsules(q);
        // The upper arm's first few centimetres sit on the bracket by design.
        let upper = Capsule { a: c[0].a + (c[0].b - c[0].a) * 0.15, ..c[0] };
        std::iter::once(upper)
            .chain(c[1..].iter().copied())
            .any(|k| self.rover.iter().any(|b| k.touches_box(b)))
    }
}

/// Sum of joint differences (joints move within their limits, never through +-180 deg).
pub fn cost_between(x: &Joints, y: &Joints) -> f64 {
    x.iter().zip(y).map(|(a, b)| (a - b).abs()).sum()
}

/// The largest distance any arm point moves per radian of each joint at this pose (m/rad): a
/// bound to sample joint-space motions densely enough.
pub fn lever_arms(arm: &Arm, q: &Joints) -> [f64; 5] {
    let f = arm.forward(q);
    let reach = arm.geometry.upper + arm.geometry.fore + arm.geometry.wrist + arm.geometry.tool;
    let from = |p: V3| (f.tip - p).norm().max((f.turret - p).norm()) + arm.geometry.radii[3];
    [reach + 0.1, from(f.shoulder), from(f.elbow), from(f.wrist), arm.geometry.tool + 0.01]
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn the_stowed_pose_is_within_limits_and_touches_nothing() {
        let arm = Arm::new(&RoverConfig::default());
        let q = arm.stowed();
        assert!(arm.within_limits(&q));
        assert!(!arm.self_collides(&q), "stowed self-collision");
        assert!(!arm.hits_rover(&q), "stowed meets the rover");
        let lowest = arm.capsules(&q).iter().map(|c| c.a.z.min(c.b.z) - c.radius).fold(f64::MAX, f64::min);
        assert!(lowest > 0.12, "stowed arm {lowest} m above the wheels' plane");
        for az in [-0.5, 0.0, 0.5] {
            let u = arm.unstowed(az);
            assert!(arm.within_limits(&u) && !arm.self_collides(&u) && !arm.hits_rover(&u), "{az}");
        }
    }

    #[test]
    fn the_reach_is_the_stated_one() {
        let arm = Arm::new(&RoverConfig::default());
        let down = -V3::z();
        let reaches =
            |x: f64| !arm.inverse(&V3::new(x, arm.geometry.base.y, 0.0), &down, &arm.stowed()).is_empty();
        let mut x = arm.geometry.base.x;
        while reaches(x + 0.005) || x < arm.geometry.base.x + 0.3 {
            x += 0.005;
        }
        let reach = x - arm.geometry.base.x;
        assert!((0.76..0.80).contains(&reach), "reach {reach}");
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]
        /// Forward then inverse kinematics returns the same joints (one of the solutions) and the
        /// same tool pose, over the joint space minus the singular turret angles.
        #[test]
        fn inverse_of_forward_is_identity(
            q1 in -1.7f64..1.7, q2 in -0.65f64..1.9, q3 in -3.0f64..-0.1,
            q4 in -3.0f64..3.0, q5 in -3.0f64..3.0,
        ) {
            prop_assume!(q5.sin().abs() < 0.97);
            let arm = Arm::new(&RoverConfig::default());
            let q = [q1, q2, q3, q4, q5];
            let f = arm.forward(&q);
            let horizontal = (f.turret - arm.geometry.base).xy().norm();
            prop_assume!(horizontal > 0.02);
            let sols = arm.inverse(&f.tip, &f.axis, &q);
            prop_assert!(!sols.is_empty(), "no solution for {q:?}");
            prop_assert!(cost_between(&sols[0], &q) < 1e-6, "{:?} vs {q:?}", sols[0]);
            for s in &sols {
                let g = arm.forward(s);
                prop_assert!((g.tip - f.tip).norm() < 1e-9 && (g.axis - f.axis).norm() < 1e-9);
            }
        }
    }
}
