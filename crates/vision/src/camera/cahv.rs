//! The CAHV linear camera model (Yakimovsky and Cunningham, "A system for extracting
//! three-dimensional measurements from a stereo pair of TV cameras", CGIP 7, 1978).
//!
//! C is the camera centre, A the unit pointing axis, H = f_x H' + h_c A and V = f_y V' + v_c A
//! where H' and V' are the unit image-plane axes, f_x and f_y the focal lengths in pixels and
//! (h_c, v_c) the image centre. A point P projects to x = (P - C).H / (P - C).A,
//! y = (P - C).V / (P - C).A.

use nalgebra::{Isometry3, Matrix2x3, Matrix3, Point2, Point3, Unit, Vector3};

use super::{CameraModel, Movable, Ray};

/// A CAHV (pinhole) camera model with its image size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cahv {
    /// Camera centre.
    pub c: Vector3<f64>,
    /// Unit pointing axis.
    pub a: Vector3<f64>,
    /// Horizontal image vector.
    pub h: Vector3<f64>,
    /// Vertical image vector.
    pub v: Vector3<f64>,
    /// Image width in pixels.
    pub width: usize,
    /// Image height in pixels.
    pub height: usize,
}

impl Cahv {
    /// A camera at `centre` looking along `axis`, with `right` the direction of increasing
    /// sample (made orthogonal to the axis), focal lengths `fx`, `fy` in pixels and the image
    /// centre `(hc, vc)`. Lines increase along `axis x right` (down, for a level camera).
    #[allow(clippy::too_many_arguments)]
    pub fn from_intrinsics(
        centre: Vector3<f64>,
        axis: Vector3<f64>,
        right: Vector3<f64>,
        fx: f64,
        fy: f64,
        hc: f64,
        vc: f64,
        width: usize,
        height: usize,
    ) -> Self {
        let a = axis.normalize();
        let hs = (right - a * right.dot(&a)).normalize();
        let vs = a.cross(&hs);
        Self { c: centre, a, h: hs * fx + a * hc, v: vs * fy + a * vc, width, height }
    }

    /// Horizontal focal length in pixels: |A x H|.
    pub fn focal_h(&self) -> f64 {
        self.a.cross(&self.h).norm()
    }

    /// Vertical focal length in pixels: |A x V|.
    pub fn focal_v(&self) -> f64 {
        self.a.cross(&self.v).norm()
    }

    /// Image centre (h_c, v_c) = (H.A, V.A).
    pub fn image_centre(&self) -> (f64, f64) {
        (self.h.dot(&self.a), self.v.dot(&self.a))
    }

    /// Unit horizontal image-plane axis H' = (H - h_c A) / f_x.
    pub fn h_axis(&self) -> Vector3<f64> {
        (self.h - self.a * self.h.dot(&self.a)).normalize()
    }

    /// Unit vertical image-plane axis V' = (V - v_c A) / f_y.
    pub fn v_axis(&self) -> Vector3<f64> {
        (self.v - self.a * self.v.dot(&self.a)).normalize()
    }
}

impl CameraModel for Cahv {
    fn width(&self) -> usize {
        self.width
    }

    fn height(&self) -> usize {
        self.height
    }

    fn project(&self, point: &Point3<f64>) -> Option<Point2<f64>> {
        let d = point.coords - self.c;
        let depth = d.dot(&self.a);
        (depth > 0.0).then(|| Point2::new(d.dot(&self.h) / depth, d.dot(&self.v) / depth))
    }

    fn unproject(&self, pixel: &Point2<f64>) -> Ray {
        // The ray is orthogonal to H - x A and to V - y A.
        let n = (self.v - self.a * pixel.y).cross(&(self.h - self.a * pixel.x));
        let n = if n.dot(&self.a) < 0.0 { -n } else { n };
        Ray { origin: Point3::from(self.c), direction: Unit::new_normalize(n) }
    }

    fn centre(&self) -> Point3<f64> {
        Point3::from(self.c)
    }

    fn project_jacobian(&self, point: &Point3<f64>) -> Option<(Point2<f64>, Matrix2x3<f64>)> {
        let d = point.coords - self.c;
        super::cahvor::cahv_project_jacobian(&self.a, &self.h, &self.v, &d, &Matrix3::identity())
    }
}

impl Movable for Cahv {
    fn moved(&self, pose: &Isometry3<f64>) -> Self {
        let r = pose.rotation;
        Self { c: (pose * Point3::from(self.c)).coords, a: r * self.a, h: r * self.h, v: r * self.v, ..*self }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn navcam_like() -> Cahv {
        Cahv::from_intrinsics(
            Vector3::new(0.1, 0.2, 1.2),
            Vector3::new(1.0, 0.0, -0.3),
            Vector3::new(0.0, -1.0, 0.0),
            1236.0,
            1236.0,
            511.5,
            511.5,
            1024,
            1024,
        )
    }

    #[test]
    fn intrinsics_round_trip() {
        let cam = navcam_like();
        assert!((cam.focal_h() - 1236.0).abs() < 1e-9);
        assert!((cam.focal_v() - 1236.0).abs() < 1e-9);
        let (hc, vc) = cam.image_centre();
        assert!((hc - 511.5).abs() < 1e-9 && (vc - 511.5).abs() < 1e-9);
        // A point on the axis lands on the image centre.
        let p = Point3::from(cam.c + cam.a * 4.0);
        let px = cam.project(&p).unwrap();
        assert!((px.x - 511.5).abs() < 1e-9 && (px.y - 511.5).abs() < 1e-9);
        // Lines grow downwards for a level camera looking along +x with +y to its left.
        let below = Point3::new(4.0, 0.2, 0.0);
        let above = Point3::new(4.0, 0.2, 2.0);
        assert!(cam.project(&below).unwrap().y > cam.project(&above).unwrap().y);
    }

    #[test]
    fn unproject_then_project_returns_the_pixel() {
        let cam = navcam_like();
        for &(x, y) in &[(0.0, 0.0), (1023.0, 0.0), (300.25, 700.75), (1023.0, 1023.0)] {
            let ray = cam.unproject(&Point2::new(x, y));
            let back = cam.project(&ray.at(7.0)).unwrap();
            assert!((back.x - x).abs() < 1e-9 && (back.y - y).abs() < 1e-9, "{x},{y} -> {back}");
        }
        assert!(cam.project(&Point3::new(-5.0, 0.0, 1.0)).is_none());
    }
}
