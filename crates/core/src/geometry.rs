//! Plane and space poses and small angle helpers.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// A point in the plane (metres).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct Point2 {
    /// East (world) or forward (body) coordinate.
    pub x: f64,
    /// North (world) or left (body) coordinate.
    pub y: f64,
}

impl Point2 {
    /// Builds a point.
    pub const fn new(x: f64, y: f64) -> Self {
        Self { x, y }
    }
    /// Euclidean distance to another point.
    pub fn dist(self, o: Point2) -> f64 {
        (self.x - o.x).hypot(self.y - o.y)
    }
    /// Vector length.
    pub fn norm(self) -> f64 {
        self.x.hypot(self.y)
    }
    /// Vector difference `self - o`.
    #[allow(clippy::should_implement_trait)]
    pub fn sub(self, o: Point2) -> Point2 {
        Point2::new(self.x - o.x, self.y - o.y)
    }
    /// Vector sum.
    #[allow(clippy::should_implement_trait)]
    pub fn add(self, o: Point2) -> Point2 {
        Point2::new(self.x + o.x, self.y + o.y)
    }
    /// Scales the vector.
    pub fn scale(self, k: f64) -> Point2 {
        Point2::new(self.x * k, self.y * k)
    }
    /// Dot product.
    pub fn dot(self, o: Point2) -> f64 {
        self.x * o.x + self.y * o.y
    }
    /// z component of the cross product (positive when `o` is counter-clockwise of `self`).
    pub fn cross(self, o: Point2) -> f64 {
        self.x * o.y - self.y * o.x
    }
    /// Direction angle of the vector (radians, counter-clockwise from +x).
    pub fn angle(self) -> f64 {
        self.y.atan2(self.x)
    }
    /// Whether both coordinates are finite.
    pub fn is_finite(self) -> bool {
        self.x.is_finite() && self.y.is_finite()
    }
}

/// A planar pose: position and heading (yaw, counter-clockwise from east).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct Pose2 {
    /// East (m).
    pub x: f64,
    /// North (m).
    pub y: f64,
    /// Heading (rad), counter-clockwise from +x.
    pub yaw: f64,
}

impl Pose2 {
    /// Builds a pose.
    pub const fn new(x: f64, y: f64, yaw: f64) -> Self {
        Self { x, y, yaw }
    }
    /// The position part.
    pub fn position(&self) -> Point2 {
        Point2::new(self.x, self.y)
    }
    /// Maps a body-frame point (x forward, y left) into the world frame.
    pub fn transform(&self, p: Point2) -> Point2 {
        let (s, c) = self.yaw.sin_cos();
        Point2::new(self.x + c * p.x - s * p.y, self.y + s * p.x + c * p.y)
    }
    /// Maps a world point into this pose's body frame.
    pub fn inverse_transform(&self, p: Point2) -> Point2 {
        let (s, c) = self.yaw.sin_cos();
        let d = p.sub(self.position());
        Point2::new(c * d.x + s * d.y, -s * d.x + c * d.y)
    }
}

/// A full 3D pose: position and roll/pitch/yaw (ZYX Euler angles, ROS convention).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct Pose3 {
    /// East (m).
    #[serde(deserialize_with = "crate::wire::nan_from_null")]
    #[schemars(with = "Option<f64>")]
    pub x: f64,
    /// North (m).
    #[serde(deserialize_with = "crate::wire::nan_from_null")]
    #[schemars(with = "Option<f64>")]
    pub y: f64,
    /// Up (m).
    #[serde(deserialize_with = "crate::wire::nan_from_null")]
    #[schemars(with = "Option<f64>")]
    pub z: f64,
    /// Rotation about the body x axis (rad); positive rolls the left side up.
    #[serde(deserialize_with = "crate::wire::nan_from_null")]
    #[schemars(with = "Option<f64>")]
    pub roll: f64,
    /// Rotation about the body y axis (rad); positive pitches the nose down (REP 103).
    #[serde(deserialize_with = "crate::wire::nan_from_null")]
    #[schemars(with = "Option<f64>")]
    pub pitch: f64,
    /// Heading (rad).
    #[serde(deserialize_with = "crate::wire::nan_from_null")]
    #[schemars(with = "Option<f64>")]
    pub yaw: f64,
}

impl Pose3 {
    /// The planar projection of this pose.
    pub fn pose2(&self) -> Pose2 {
        Pose2::new(self.x, self.y, self.yaw)
    }
    /// Rotation matrix body -> world (R = Rz(yaw) Ry(pitch) Rx(roll)).
    pub fn rotation(&self) -> [[f64; 3]; 3] {
        rotation_rpy(self.roll, self.pitch, self.yaw)
    }
    /// Maps a body-frame point into the world frame.
    pub fn transform(&self, p: [f64; 3]) -> [f64; 3] {
        let r = self.rotation();
        [
            self.x + r[0][0] * p[0] + r[0][1] * p[1] + r[0][2] * p[2],
            self.y + r[1][0] * p[0] + r[1][1] * p[1] + r[1][2] * p[2],
            self.z + r[2][0] * p[0] + r[2][1] * p[1] + r[2][2] * p[2],
        ]
    }
    /// Maps a world point into the body frame.
    pub fn inverse_transform(&self, p: [f64; 3]) -> [f64; 3] {
        let r = self.rotation();
        let d = [p[0] - self.x, p[1] - self.y, p[2] - self.z];
        [
            r[0][0] * d[0] + r[1][0] * d[1] + r[2][0] * d[2],
            r[0][1] * d[0] + r[1][1] * d[1] + r[2][1] * d[2],
            r[0][2] * d[0] + r[1][2] * d[1] + r[2][2] * d[2],
        ]
    }
    /// Tilt of the body z axis from vertical (rad).
    pub fn tilt(&self) -> f64 {
        (self.roll.cos() * self.pitch.cos()).clamp(-1.0, 1.0).acos()
    }
}

/// Rotation matrix from roll, pitch, yaw (R = Rz Ry Rx).
pub fn rotation_rpy(roll: f64, pitch: f64, yaw: f64) -> [[f64; 3]; 3] {
    let (sr, cr) = roll.sin_cos();
    let (sp, cp) = pitch.sin_cos();
    let (sy, cy) = yaw.sin_cos();
    [
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ]
}

/// Wraps an angle into (-pi, pi].
pub fn wrap_angle(a: f64) -> f64 {
    let mut a = a % (2.0 * PI);
    if a <= -PI {
        a += 2.0 * PI;
    } else if a > PI {
        a -= 2.0 * PI;
    }
    a
}

/// Signed smallest difference `a - b`, wrapped into (-pi, pi].
pub fn angle_diff(a: f64, b: f64) -> f64 {
    wrap_angle(a - b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn pose3_inverse_undoes_transform(
            x in -10.0..10.0f64, y in -10.0..10.0f64, z in -10.0..10.0f64,
            r in -0.5..0.5f64, p in -0.5..0.5f64, yaw in -3.0..3.0f64,
            px in -5.0..5.0f64, py in -5.0..5.0f64, pz in -5.0..5.0f64,
        ) {
            let pose = Pose3 { x, y, z, roll: r, pitch: p, yaw };
            let w = pose.transform([px, py, pz]);
            let b = pose.inverse_transform(w);
            prop_assert!((b[0] - px).abs() < 1e-9 && (b[1] - py).abs() < 1e-9 && (b[2] - pz).abs() < 1e-9);
        }

        #[test]
        fn wrap_angle_stays_in_range(a in -100.0..100.0f64) {
            let w = wrap_angle(a);
            prop_assert!(w > -PI - 1e-12 && w <= PI + 1e-12);
            prop_assert!(((a - w) / (2.0 * PI)).fract().abs() < 1e-9 || (1.0 - ((a - w) / (2.0 * PI)).fract().abs()) < 1e-9);
        }
    }

    #[test]
    fn positive_pitch_lowers_the_nose() {
        let pose = Pose3 { pitch: 0.3, ..Default::default() };
        assert!(pose.transform([1.0, 0.0, 0.0])[2] < 0.0);
    }

    #[test]
    fn pose2_body_forward_follows_heading() {
        let p = Pose2::new(1.0, 2.0, PI / 2.0);
        let w = p.transform(Point2::new(1.0, 0.0));
        assert!((w.x - 1.0).abs() < 1e-12 && (w.y - 3.0).abs() < 1e-12);
        let b = p.inverse_transform(w);
        assert!((b.x - 1.0).abs() < 1e-12 && b.y.abs() < 1e-12);
    }
}
