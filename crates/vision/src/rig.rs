//! The rover's cameras: named linear (CAHV) models in the frame they are mounted in.
//!
//! MER-like layout (Maki et al. 2003, "Mars Exploration Rover engineering cameras"): a Navcam
//! stereo pair on the mast's pan/tilt head (45 deg field of view, 0.20 m baseline, 1024 x 1024),
//! front and rear Hazcam pairs on the body (0.10 m baseline, pointing 45 deg down). MER's Hazcams
//! see 124 deg through a fish-eye lens (a CAHVORE model); the rig's cameras are already-rectified
//! linear models, so the Hazcams here see 100 deg, the widest a pinhole model renders without
//! wasting most of its pixels on the image edges. A pair's cameras share their pointing axis and
//! image plane and are offset along H (left camera at +y of the head), as the stereo correlator
//! expects of a rectified pair.
//!
//! Frames: body cameras are in the rover body frame (x forward, y left, z up, origin on the
//! ground plane of the wheels); the `lander` and `descent` cameras are in the site frame, the
//! mission start pose levelled (x along the start heading, origin on the ground at the start).
//! [`RigCamera::in_world`] moves either to the world frame.
//!
//! The lander carries a rectified stereo pair on a pan/tilt mast (paper 002 section 2: "the
//! lander has a stereo pair of cameras on a pan/tilt platform"): `lander` (left, at
//! `lander_position`) and `lander_right` (`lander_baseline` to its right). [`Rig::camera`] aims
//! them at `lander_target`; [`Rig::lander_camera`] points them anywhere by site-frame pan and
//! tilt, and [`Rig::lander_aim`] gives the pan and tilt that look at a site-frame point.

use crate::Cahv;
use crate::camera::Movable;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use rovernav_core::{Pose3, RoverConfig};

/// Names of every rig camera, pairs left before right.
pub const CAMERA_NAMES: [&str; 9] = [
    "navcam_left",
    "navcam_right",
    "hazcam_front_left",
    "hazcam_front_right",
    "hazcam_rear_left",
    "hazcam_rear_right",
    "lander",
    "descent",
    "lander_right",
];

/// The frame a rig camera's model is expressed in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mount {
    /// The rover body frame: move it with the rover's true pose.
    Body,
    /// The site frame (the mission start, levelled): move it with the site pose.
    Site,
}

/// One camera of the rig.
#[derive(Clone, Debug, PartialEq)]
pub struct RigCamera {
    /// The camera's name.
    pub name: &'static str,
    /// Linear camera model in the frame of `mount`.
    pub model: Cahv,
    /// Which frame `model` is expressed in.
    pub mount: Mount,
    /// The other camera of its stereo pair, if any.
    pub partner: Option<&'static str>,
}

impl RigCamera {
    /// The camera in the world frame: moved by the rover's true pose (body cameras) or by the
    /// site pose (lander and descent).
    pub fn in_world(&self, body: &Pose3, site: &Pose3) -> Cahv {
        let pose = match self.mount {
            Mount::Body => body,
            Mount::Site => site,
        };
        self.model.moved(&pose_isometry(pose))
    }
}

/// The rigid motion of a pose: body-frame points map to world points (same as
/// [`Pose3::transform`]).
pub fn pose_isometry(pose: &Pose3) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(pose.x, pose.y, pose.z),
        UnitQuaternion::from_euler_angles(pose.roll, pose.pitch, pose.yaw),
    )
}

/// Mounting and optics of the rig's cameras.
#[derive(Clone, Debug, PartialEq)]
pub struct Rig {
    /// Height of the Navcam head's tilt axis above the wheel plane (m).
    pub mast_height: f64,
    /// Navcam horizontal field of view (rad).
    pub navcam_fov: f64,
    /// Navcam stereo baseline (m).
    pub navcam_baseline: f64,
    /// Navcam image size (pixels, square).
    pub navcam_size: usize,
    /// Hazcam horizontal field of view (rad).
    pub hazcam_fov: f64,
    /// Hazcam stereo baseline (m).
    pub hazcam_baseline: f64,
    /// Hazcam image size (pixels, square).
    pub hazcam_size: usize,
    /// Hazcam pointing below the horizon (rad).
    pub hazcam_depression: f64,
    /// Hazcam height above the wheel plane (m).
    pub hazcam_height: f64,
    /// Body x of the front Hazcams (the rear ones sit at minus this) (m).
    pub hazcam_x: f64,
    /// Lander camera position in the site frame (m).
    pub lander_position: [f64; 3],
    /// Site-frame point the lander camera looks at (m).
    pub lander_target: [f64; 3],
    /// Lander camera horizontal field of view (rad).
    pub lander_fov: f64,
    /// Lander image size (pixels, square).
    pub lander_size: usize,
    /// Lander stereo baseline (m): `lander_right` sits this far to the right of `lander`.
    pub lander_baseline: f64,
    /// Descent camera altitude above the site origin (m).
    pub descent_altitude: f64,
    /// Descent camera field of view (rad).
    pub descent_fov: f64,
    /// Descent image size (pixels, square).
    pub descent_size: usize,
}

impl Rig {
    /// The MER-like rig on a rover of the given size and mast height.
    pub fn new(rover: &RoverConfig) -> Self {
        Self {
            mast_height: rover.mast_height,
            navcam_fov: rover.mast_fov,
            navcam_baseline: 0.20,
            navcam_size: 1024,
            hazcam_fov: 100f64.to_radians(),
            hazcam_baseline: 0.10,
            hazcam_size: 1024,
            hazcam_depression: 45f64.to_radians(),
            hazcam_height: rover.body_camera_height,
            // Just ahead of the body's front face, so the body does not hide the view.
            hazcam_x: 0.5 * rover.length + 0.03,
            // A lander mast (Pathfinder's IMP stood 1.5 m high) 4 m behind and 2 m beside the
            // start, looking at the ground 2 m ahead of the start.
            lander_position: [-4.0, 2.0, 1.8],
            lander_target: [2.0, 0.0, 0.0],
            lander_fov: 50f64.to_radians(),
            lander_size: 1024,
            // Pathfinder's IMP: 15 cm between its two eyes.
            lander_baseline: 0.15,
            descent_altitude: 100.0,
            descent_fov: 45f64.to_radians(),
            descent_size: 1024,
        }
    }

    /// Sets the image size of every camera (square images of `size` pixels).
    pub fn with_size(mut self, size: usize) -> Self {
        self.navcam_size = size;
        self.hazcam_size = size;
        self.lander_size = size;
        self.descent_size = size;
        self
    }

    /// The named camera; `pan` (about body z, positive left) and `tilt` (elevation, positive up)
    /// point the Navcam head and are ignored by the other cameras (rad). `None` for an unknown
    /// name.
    pub fn camera(&self, name: &str, pan: f64, tilt: f64) -> Option<RigCamera> {
        let name = *CAMERA_NAMES.iter().find(|n| **n == name)?;
        let half = |fov: f64| 0.5 * fov;
        let (model, mount, partner) = match name {
            "navcam_left" | "navcam_right" => {
                let side = if name == "navcam_left" { 0.5 } else { -0.5 };
                let head = [0.0, 0.0, self.mast_height];
                let model = pointed(
                    head,
                    pan,
                    tilt,
                    side * self.navcam_baseline,
                    half(self.navcam_fov),
                    self.navcam_size,
                );
                let partner = if side > 0.0 { "navcam_right" } else { "navcam_left" };
                (model, Mount::Body, Some(partner))
            }
            "hazcam_front_left" | "hazcam_front_right" | "hazcam_rear_left" | "hazcam_rear_right" => {
                let front = name.starts_with("hazcam_front");
                let left = name.ends_with("left");
                let (x, yaw) =
                    if front { (self.hazcam_x, 0.0) } else { (-self.hazcam_x, std::f64::consts::PI) };
                let model = pointed(
                    [x, 0.0, self.hazcam_height],
                    yaw,
                    -self.hazcam_depression,
                    if left { 0.5 } else { -0.5 } * self.hazcam_baseline,
                    half(self.hazcam_fov),
                    self.hazcam_size,
                );
                let partner = match (front, left) {
                    (true, true) => "hazcam_front_right",
                    (true, false) => "hazcam_front_left",
                    (false, true) => "hazcam_rear_right",
                    (false, false) => "hazcam_rear_left",
                };
                (model, Mount::Body, Some(partner))
            }
            "lander" | "lander_right" => {
                let (pan, tilt) = self.lander_aim(self.lander_target);
                return self.lander_camera(name, pan, tilt);
            }
            _ => {
                // "descent": straight down, image up = site +x.
                let p = Vector3::new(0.0, 0.0, self.descent_altitude);
                let model =
                    square(p, -Vector3::z(), -Vector3::y(), half(self.descent_fov), self.descent_size);
                (model, Mount::Site, None)
            }
        };
        Some(RigCamera { name, model, mount, partner })
    }
}

impl Rig {
    /// Site-frame pan (azimuth from site +x, positive left) and tilt (elevation, positive up)
    /// (rad) that point the lander mast's left camera at the site-frame point `target`.
    pub fn lander_aim(&self, target: [f64; 3]) -> (f64, f64) {
        let d = Vector3::from(target) - Vector3::from(self.lander_position);
        (d.y.atan2(d.x), d.z.atan2(d.x.hypot(d.y)))
    }

    /// A lander camera (`lander` or `lander_right`) with the mast at site-frame `pan` and `tilt`
    /// (rad); the left camera's centre is `lander_position`, the right one `lander_baseline`
    /// to its right, both sharing axis and image plane (a rectified pair). `None` for another
    /// name.
    pub fn lander_camera(&self, name: &str, pan: f64, tilt: f64) -> Option<RigCamera> {
        let (name, partner, lateral) = match name {
            "lander" => ("lander", "lander_right", 0.0),
            "lander_right" => ("lander_right", "lander", -self.lander_baseline),
            _ => return None,
        };
        let model =
            pointed(self.lander_position, pan, tilt, lateral, 0.5 * self.lander_fov, self.lander_size);
        Some(RigCamera { name, model, mount: Mount::Site, partner: Some(partner) })
    }
}

/// A camera of a pan/tilt head at `head` offset `lateral` along the head's left axis.
fn pointed(head: [f64; 3], pan: f64, tilt: f64, lateral: f64, half_fov: f64, size: usize) -> Cahv {
    let (sp, cp) = pan.sin_cos();
    let (st, ct) = tilt.sin_cos();
    let axis = Vector3::new(ct * cp, ct * sp, st);
    let left = Vector3::new(-sp, cp, 0.0);
    let centre = Vector3::from(head) + left * lateral;
    square(centre, axis, -left, half_fov, size)
}

/// A square linear camera with its image centre in the middle of the image.
fn square(centre: Vector3<f64>, axis: Vector3<f64>, right: Vector3<f64>, half_fov: f64, size: usize) -> Cahv {
    let f = 0.5 * size as f64 / half_fov.tan();
    let c = 0.5 * (size as f64 - 1.0);
    Cahv::from_intrinsics(centre, axis, right, f, f, c, c, size, size)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::CameraModel;
    use nalgebra::Point3;

    #[test]
    fn pose_isometry_matches_pose3_transform() {
        let pose = Pose3 { x: 1.0, y: -2.0, z: 0.3, roll: 0.1, pitch: -0.2, yaw: 2.5 };
        let p = [0.4, -0.3, 1.1];
        let a = pose.transform(p);
        let b = pose_isometry(&pose) * Point3::from(p);
        for k in 0..3 {
            assert!((a[k] - b[k]).abs() < 1e-12);
        }
    }

    #[test]
    fn pairs_are_rectified_along_h() {
        let rig = Rig::new(&RoverConfig::default());
        for (l, r) in [("navcam_left", "navcam_right"), ("hazcam_rear_left", "hazcam_rear_right")] {
            let cl = rig.camera(l, 0.3, -0.4).unwrap();
            let cr = rig.camera(r, 0.3, -0.4).unwrap();
            assert_eq!(cl.partner, Some(r));
            assert_eq!(cr.partner, Some(l));
            // A far point lands on the same line in both images, left sample larger.
            let p = Point3::from(cl.model.c + cl.model.a * 3.0 + cl.model.h_axis() * 0.2);
            let (pl, pr) = (cl.model.project(&p).unwrap(), cr.model.project(&p).unwrap());
            assert!((pl.y - pr.y).abs() < 1e-9 && pl.x > pr.x);
            let baseline = (cl.model.c - cr.model.c).norm();
            assert!(baseline > 0.05 && (cl.model.c - cr.model.c).dot(&cl.model.h_axis()) < 0.0);
        }
        assert!(rig.camera("pancam", 0.0, 0.0).is_none());
    }

    #[test]
    fn the_lander_pair_is_rectified_and_aims_at_its_target() {
        let rig = Rig::new(&RoverConfig::default());
        let target = [3.0, -4.0, 0.4];
        let (pan, tilt) = rig.lander_aim(target);
        let l = rig.lander_camera("lander", pan, tilt).unwrap();
        let r = rig.lander_camera("lander_right", pan, tilt).unwrap();
        assert_eq!((l.partner, r.partner), (Some("lander_right"), Some("lander")));
        // The target projects on the left image's centre.
        let p = l.model.project(&Point3::from(target)).unwrap();
        let c = 0.5 * (rig.lander_size as f64 - 1.0);
        assert!((p.x - c).abs() < 1e-9 && (p.y - c).abs() < 1e-9, "{p:?}");
        // Rectified along H with the stated baseline, the left camera at the mast position.
        assert!((l.model.c - Vector3::from(rig.lander_position)).norm() < 1e-12);
        let b = r.model.c - l.model.c;
        assert!((b.norm() - rig.lander_baseline).abs() < 1e-12);
        assert!((b.normalize() - l.model.h_axis()).norm() < 1e-9);
        assert!((l.model.a - r.model.a).norm() < 1e-12);
        // Rig::camera aims the same pair at lander_target.
        let d = rig.camera("lander", 0.0, 0.0).unwrap();
        let q = d.model.project(&Point3::from(rig.lander_target)).unwrap();
        assert!((q.x - c).abs() < 1e-9 && (q.y - c).abs() < 1e-9);
        assert_eq!(rig.camera("lander_right", 0.0, 0.0).unwrap().mount, Mount::Site);
        assert!(rig.lander_camera("navcam_left", 0.0, 0.0).is_none());
    }
}
