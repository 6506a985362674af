//! Disparity to range for a rectified linear camera pair, with Matthies' range uncertainty.
//!
//! Two CAHV cameras with the same A, H and V whose baseline b = C_right - C_left is orthogonal
//! to A and V see a point at depth z = (P - C_left).A at columns differing by
//! d = x_left - x_right = (b.H) / z, so z = (b.H) / d, where b.H = f b (focal length in pixels
//! times baseline). A disparity error sigma_d then gives the depth error, to first order,
//! sigma_z = z^2 sigma_d / (f b) (L. Matthies and S. Shafer, "Error modeling in stereo
//! navigation", IEEE J. Robotics and Automation 3(3), 1987; the model JPL's rover stereo
//! uses), and the range error along the pixel's ray scales with it by range / depth.
//!
//! sigma_d is the standard deviation of the subpixel disparity on correctly matched pixels.
//! [`DEFAULT_SIGMA_D_PX`] = 0.25 px is conservative: on the synthetic textured ground plane of
//! this crate's tests (12-bit, 2 DN read noise) the matcher's rms disparity error is 0.10 px;
//! the margin covers what that scene lacks (shading, shadows, compression, rectification
//! resampling). Matthies reports 0.1 to 0.3 px for window correlation on rover imagery.

use nalgebra::{Point2, Vector3};
use rovernav_core::{CameraKind, PointCloud, Wedge};

use super::{Disparity, StereoError};
use crate::camera::{Cahv, CameraModel};

/// Standard deviation (px) of the subpixel disparity assumed by default for the range
/// uncertainty.
pub const DEFAULT_SIGMA_D_PX: f64 = 0.25;

/// A rectified linear stereo pair.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StereoRig {
    /// Left (reference) camera.
    pub left: Cahv,
    /// Right camera: same A, H, V; centre displaced along H'.
    pub right: Cahv,
}

/// Per-pixel triangulation of a disparity map; NaN where the disparity is invalid or zero.
#[derive(Clone, Debug, PartialEq)]
pub struct RangeImage {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// 3-D points in the cameras' frame (row-major).
    pub points: Vec<[f32; 3]>,
    /// Range from the left camera centre along the pixel's ray (m).
    pub range: Vec<f32>,
    /// Standard deviation of the range (m).
    pub range_sigma: Vec<f32>,
}

impl StereoRig {
    /// Checks that two linear models form a rectified pair (common A, H, V within 1e-6
    /// relative; baseline orthogonal to A and V within 1e-6 of its length; the right camera
    /// on the +H side).
    pub fn new(left: Cahv, right: Cahv) -> Result<Self, StereoError> {
        let close = |a: &Vector3<f64>, b: &Vector3<f64>| (a - b).norm() <= 1e-6 * a.norm().max(1.0);
        if !close(&left.a, &right.a) || !close(&left.h, &right.h) || !close(&left.v, &right.v) {
            return Err(StereoError::NotRectified("the two models differ in A, H or V".into()));
        }
        if left.width != right.width || left.height != right.height {
            return Err(StereoError::NotRectified("the two models differ in image size".into()));
        }
        let b = right.c - left.c;
        let len = b.norm();
        if len == 0.0 || b.dot(&left.a).abs() > 1e-6 * len || b.dot(&left.v_axis()).abs() > 1e-6 * len {
            return Err(StereoError::NotRectified("the baseline is not along the image rows".into()));
        }
        if b.dot(&left.h) <= 0.0 {
            return Err(StereoError::NotRectified("the right camera is not on the right".into()));
        }
        Ok(Self { left, right })
    }

    /// Focal length (px) times baseline (m): b.H.
    pub fn focal_baseline(&self) -> f64 {
        (self.right.c - self.left.c).dot(&self.left.h)
    }

    /// Depth along A of a point seen at disparity `d` (px).
    pub fn depth(&self, d: f64) -> f64 {
        self.focal_baseline() / d
    }

    /// Matthies' depth standard deviation at depth `z` for a disparity error `sigma_d` (px).
    pub fn depth_sigma(&self, z: f64, sigma_d: f64) -> f64 {
        z * z * sigma_d / self.focal_baseline()
    }

    /// Triangulates every valid, positive disparity; `sigma_d` (px) feeds the uncertainty.
    pub fn range_image(&self, disp: &Disparity, sigma_d: f64) -> RangeImage {
        let n = disp.width * disp.height;
        let nan = f32::NAN;
        let mut img = RangeImage {
            width: disp.width,
            height: disp.height,
            points: vec![[nan; 3]; n],
            range: vec![nan; n],
            range_sigma: vec![nan; n],
        };
        for y in 0..disp.height {
            for x in 0..disp.width {
                let Some(d) = disp.get(x, y).filter(|&d| d > 0.0) else { continue };
                let z = self.depth(f64::from(d));
                let ray = self.left.unproject(&Point2::new(x as f64, y as f64));
                let t = z / ray.direction.dot(&self.left.a);
                let p = ray.at(t);
                let i = y * disp.width + x;
                img.points[i] = [p.x as f32, p.y as f32, p.z as f32];
                img.range[i] = t as f32;
                img.range_sigma[i] = (self.depth_sigma(z, sigma_d) * t / z) as f32;
            }
        }
        img
    }

    /// The valid points within `max_range` (m) as a navigators' point cloud, for cameras whose
    /// models are expressed in the rover body frame. The wedge is the smallest one about the
    /// pointing axis' azimuth that holds every kept point, seen from the body origin as
    /// [`Wedge::contains`] tests it (bearing, largest bearing difference, nearest and farthest
    /// planar distance).
    pub fn point_cloud(&self, range: &RangeImage, camera: CameraKind, max_range: f64) -> PointCloud {
        let points: Vec<[f32; 3]> = range
            .points
            .iter()
            .zip(&range.range)
            .filter(|&(_, &r)| r.is_finite() && f64::from(r) <= max_range)
            .map(|(p, _)| *p)
            .collect();
        let a = self.left.a;
        let bearing = a.y.atan2(a.x);
        let (mut min_range, mut max_kept, mut half_angle) = (f64::INFINITY, 0.0f64, 0.0f64);
        for p in &points {
            let (x, y) = (f64::from(p[0]), f64::from(p[1]));
            let r = x.hypot(y);
            min_range = min_range.min(r);
            max_kept = max_kept.max(r);
            half_angle = half_angle.max(rovernav_core::angle_diff(y.atan2(x), bearing).abs());
        }
        PointCloud {
            camera,
            origin: [self.left.c.x, self.left.c.y, self.left.c.z],
            wedge: Wedge {
                bearing,
                half_angle,
                min_range: if points.is_empty() { 0.0 } else { min_range },
                max_range: max_kept,
            },
            points,
        }
    }
}
