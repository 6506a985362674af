//! Camera models: the map between 3-D points and image pixels.
//!
//! JPL's rovers describe every camera with the CAHV family of models (Yakimovsky and
//! Cunningham 1978; Gennery 2001 for the distortion terms): CAHV is a linear (pinhole) model,
//! CAHVOR adds radial distortion about an optical axis O, CAHVORE adds entrance-pupil motion for
//! fish-eye lenses. Pixel coordinates are (sample, line): x to the right along a row, y down,
//! with (0, 0) at the centre of the top-left pixel, as in the PDS labels.

mod any;
mod cahv;
mod cahvor;
mod cahvore;
pub mod read;

pub use any::AnyCamera;
pub use cahv::Cahv;
pub use cahvor::Cahvor;
pub use cahvore::{Cahvore, CahvoreType};
pub use read::CameraReadError;

use nalgebra::{Isometry3, Matrix2x3, Point2, Point3, Unit, Vector3};

/// A ray in space: where a pixel looks from, and in which direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Start of the ray (the camera centre, or the entrance pupil for CAHVORE).
    pub origin: Point3<f64>,
    /// Unit direction.
    pub direction: Unit<Vector3<f64>>,
}

impl Ray {
    /// The point at distance `t` along the ray.
    pub fn at(&self, t: f64) -> Point3<f64> {
        self.origin + self.direction.into_inner() * t
    }
}

/// A camera model: projection of points to pixels and of pixels back to rays.
pub trait CameraModel: Send + Sync {
    /// Image width in pixels (samples per line).
    fn width(&self) -> usize;
    /// Image height in pixels (lines).
    fn height(&self) -> usize;
    /// The pixel (sample, line) where a point appears; `None` behind the camera.
    fn project(&self, point: &Point3<f64>) -> Option<Point2<f64>>;
    /// The ray a pixel (sample, line) looks along.
    fn unproject(&self, pixel: &Point2<f64>) -> Ray;
    /// The camera centre.
    fn centre(&self) -> Point3<f64>;
    /// Whether a pixel lies inside the image (the half-pixel borders included).
    fn contains(&self, pixel: &Point2<f64>) -> bool {
        pixel.x >= -0.5
            && pixel.y >= -0.5
            && pixel.x < self.width() as f64 - 0.5
            && pixel.y < self.height() as f64 - 0.5
    }
    /// The pixel of a point and the 2x3 Jacobian d(sample, line)/d(point); `None` behind the
    /// camera. The default differentiates [`CameraModel::project`] by central differences;
    /// the CAHV family overrides it with the analytic derivative.
    fn project_jacobian(&self, point: &Point3<f64>) -> Option<(Point2<f64>, Matrix2x3<f64>)> {
        let pixel = self.project(point)?;
        let step = 1e-6 * (point - self.centre()).norm().max(1e-3);
        let mut jac = Matrix2x3::zeros();
        for k in 0..3 {
            let mut dp = Vector3::zeros();
            dp[k] = step;
            let plus = self.project(&(point + dp))?;
            let minus = self.project(&(point - dp))?;
            jac.set_column(k, &((plus - minus) / (2.0 * step)));
        }
        Some((pixel, jac))
    }
}

/// A camera model that can be carried by a rigid motion (a mounted camera moved to the world).
pub trait Movable {
    /// The same camera after the rigid motion `pose` (points map as `pose * p`).
    fn moved(&self, pose: &Isometry3<f64>) -> Self;
}
