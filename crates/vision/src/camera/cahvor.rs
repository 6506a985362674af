//! The CAHVOR camera model: CAHV plus radial distortion about an optical axis O (Gennery,
//! "Least-squares camera calibration including lens distortion and automatic editing of
//! calibration points", in Calibration and Orientation of Cameras in Computer Vision, 2001;
//! the form JPL's camera-model library and the PDS labels use).
//!
//! For a point P, with d = P - C, zeta = d.O the distance along O, lambda = d - zeta O the
//! perpendicular part and tau = |lambda|^2 / zeta^2, the distortion moves the point to
//! d' = d + mu lambda with mu = r0 + r1 tau + r2 tau^2, which then projects as in CAHV:
//! x = d'.H / d'.A, y = d'.V / d'.A.
//!
//! Unprojection inverts the distortion: with chi = |lambda| / zeta the distortion maps chi to
//! chi' = (1 + r0) chi + r1 chi^3 + r2 chi^5, so the CAHV ray of the pixel gives chi' and a
//! Newton iteration (safeguarded by bisection, and limited to the polynomial's first rising
//! branch) recovers chi to machine precision. JPL's library iterates on the same polynomial.
//! Departure: where JPL's library reports an error (a pixel whose chi' the polynomial never
//! reaches, or more than 90 degrees from O) the unprojection returns the linear model's ray,
//! since the trait's `unproject` cannot fail; such pixels lie outside any calibrated image.

use nalgebra::{Isometry3, Matrix2x3, Matrix3, Point2, Point3, Unit, Vector3};

use super::{Cahv, CameraModel, Movable, Ray};

/// A CAHVOR camera model with its image size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cahvor {
    /// Camera centre.
    pub c: Vector3<f64>,
    /// Unit pointing axis.
    pub a: Vector3<f64>,
    /// Horizontal image vector.
    pub h: Vector3<f64>,
    /// Vertical image vector.
    pub v: Vector3<f64>,
    /// Unit optical axis of the distortion.
    pub o: Vector3<f64>,
    /// Radial distortion coefficients (r0, r1, r2).
    pub r: Vector3<f64>,
    /// Image width in pixels.
    pub width: usize,
    /// Image height in pixels.
    pub height: usize,
}

impl Cahvor {
    /// A CAHVOR model from its linear part and the distortion terms O (normalised) and R.
    pub fn new(linear: Cahv, o: Vector3<f64>, r: Vector3<f64>) -> Self {
        Self {
            c: linear.c,
            a: linear.a,
            h: linear.h,
            v: linear.v,
            o: o.normalize(),
            r,
            width: linear.width,
            height: linear.height,
        }
    }

    /// The model of the terrain crate's PDS3 reader, for an image of `width` x `height`. A and
    /// O are normalised: labels print them to six digits, the inversion assumes unit vectors,
    /// and normalising moves a Navcam projection by under 1e-3 px.
    pub fn from_terrain(m: &rovernav_terrain::io::CahvorModel, width: usize, height: usize) -> Self {
        let v3 = |x: [f64; 3]| Vector3::new(x[0], x[1], x[2]);
        let a = v3(m.a).normalize();
        let linear = Cahv { c: v3(m.c), a, h: v3(m.h), v: v3(m.v), width, height };
        Self::new(linear, v3(m.o), v3(m.r))
    }

    /// The linear part (C, A, H, V) of the model.
    pub fn linear(&self) -> Cahv {
        Cahv { c: self.c, a: self.a, h: self.h, v: self.v, width: self.width, height: self.height }
    }

    /// Horizontal focal length in pixels: |A x H|.
    pub fn focal_h(&self) -> f64 {
        self.linear().focal_h()
    }

    /// Vertical focal length in pixels: |A x V|.
    pub fn focal_v(&self) -> f64 {
        self.linear().focal_v()
    }

    /// Image centre (H.A, V.A).
    pub fn image_centre(&self) -> (f64, f64) {
        self.linear().image_centre()
    }

    /// The distorted vector d' = d + mu lambda of a point, or `None` at or behind the O plane.
    fn distort(&self, d: &Vector3<f64>) -> Option<Vector3<f64>> {
        let zeta = d.dot(&self.o);
        if zeta <= 0.0 {
            return None;
        }
        let lambda = d - self.o * zeta;
        let tau = lambda.norm_squared() / (zeta * zeta);
        let mu = self.r[0] + self.r[1] * tau + self.r[2] * tau * tau;
        Some(d + lambda * mu)
    }
}

/// Solves (1 + r0) chi + r1 chi^3 + r2 chi^5 = target for the root on the polynomial's first
/// rising branch: Newton steps from target / (1 + r0), with bisection whenever a step leaves
/// the bracket. The branch ends where the derivative first vanishes (a quadratic in chi^2,
/// solved in closed form); `None` when the polynomial turns over before reaching `target` (the
/// pixel lies outside the model's valid field).
pub(crate) fn invert_radial(r: &Vector3<f64>, target: f64) -> Option<f64> {
    let k0 = 1.0 + r[0];
    let f = |x: f64| {
        let x2 = x * x;
        (k0 + r[1] * x2 + r[2] * x2 * x2) * x - target
    };
    let df = |x: f64| {
        let x2 = x * x;
        k0 + 3.0 * r[1] * x2 + 5.0 * r[2] * x2 * x2
    };
    if target <= 0.0 {
        return Some(0.0);
    }
    if k0 <= 0.0 {
        return None;
    }
    let (mut lo, mut hi) = (0.0, f64::INFINITY);
    if let Some(u) = smallest_positive_root(5.0 * r[2], 3.0 * r[1], k0) {
        hi = u.sqrt();
        if f(hi) < 0.0 {
            return None;
        }
    }
    let mut x = (target / k0).min(hi);
    for _ in 0..100 {
        let fx = f(x);
        if fx == 0.0 {
            return Some(x);
        }
        if fx < 0.0 {
            lo = x;
        } else {
            hi = x;
        }
        let mut next = x - fx / df(x);
        if !(next > lo && next < hi) {
            next = 0.5 * (lo + hi);
        }
        if (next - x).abs() <= 1e-14 * (1.0 + x) {
            return Some(next);
        }
        x = next;
    }
    Some(x)
}

/// The smallest positive root of a u^2 + b u + c with c > 0, if any.
fn smallest_positive_root(a: f64, b: f64, c: f64) -> Option<f64> {
    if a == 0.0 {
        return (b < 0.0).then(|| -c / b);
    }
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        return None;
    }
    let q = -0.5 * (b + b.signum() * disc.sqrt());
    let roots = [q / a, if q != 0.0 { c / q } else { f64::NAN }];
    roots.into_iter().filter(|u| *u > 0.0).min_by(|x, y| x.total_cmp(y))
}

/// The CAHV ray direction of a pixel (not normalised), oriented along +A.
pub(crate) fn cahv_direction(
    a: &Vector3<f64>,
    h: &Vector3<f64>,
    v: &Vector3<f64>,
    pixel: &Point2<f64>,
) -> Vector3<f64> {
    let n = (v - a * pixel.y).cross(&(h - a * pixel.x));
    if n.dot(a) < 0.0 { -n } else { n }
}

/// Pixel and 2x3 Jacobian of the CAHV projection of a vector q (from the centre), given
/// dq/dp; `None` when q is behind the image plane.
pub(crate) fn cahv_project_jacobian(
    a: &Vector3<f64>,
    h: &Vector3<f64>,
    v: &Vector3<f64>,
    q: &Vector3<f64>,
    dq: &Matrix3<f64>,
) -> Option<(Point2<f64>, Matrix2x3<f64>)> {
    let alpha = q.dot(a);
    if alpha <= 0.0 {
        return None;
    }
    let (x, y) = (q.dot(h) / alpha, q.dot(v) / alpha);
    let gx = (h - a * x).transpose() * dq / alpha;
    let gy = (v - a * y).transpose() * dq / alpha;
    Some((Point2::new(x, y), Matrix2x3::from_rows(&[gx, gy])))
}

impl CameraModel for Cahvor {
    fn width(&self) -> usize {
        self.width
    }

    fn height(&self) -> usize {
        self.height
    }

    fn project(&self, point: &Point3<f64>) -> Option<Point2<f64>> {
        let q = self.distort(&(point.coords - self.c))?;
        let alpha = q.dot(&self.a);
        (alpha > 0.0).then(|| Point2::new(q.dot(&self.h) / alpha, q.dot(&self.v) / alpha))
    }

    fn unproject(&self, pixel: &Point2<f64>) -> Ray {
        let rp = cahv_direction(&self.a, &self.h, &self.v, pixel);
        let zeta = rp.dot(&self.o);
        let lambda = rp - self.o * zeta;
        let lambda_norm = lambda.norm();
        let direction = if zeta <= 0.0 {
            // Beyond 90 degrees from O the model is undefined; keep the linear ray.
            rp
        } else if lambda_norm < 1e-12 * zeta {
            self.o * zeta + lambda / (1.0 + self.r[0])
        } else {
            let chi_d = lambda_norm / zeta;
            match invert_radial(&self.r, chi_d) {
                Some(chi) => self.o + lambda * (chi / lambda_norm),
                None => rp,
            }
        };
        Ray { origin: Point3::from(self.c), direction: Unit::new_normalize(direction) }
    }

    fn centre(&self) -> Point3<f64> {
        Point3::from(self.c)
    }

    fn project_jacobian(&self, point: &Point3<f64>) -> Option<(Point2<f64>, Matrix2x3<f64>)> {
        let d = point.coords - self.c;
        let zeta = d.dot(&self.o);
        if zeta <= 0.0 {
            return None;
        }
        let lambda = d - self.o * zeta;
        let l2 = lambda.norm_squared();
        let tau = l2 / (zeta * zeta);
        let mu = self.r[0] + self.r[1] * tau + self.r[2] * tau * tau;
        let dmu_dtau = self.r[1] + 2.0 * self.r[2] * tau;
        // d lambda / dp = I - O O^T; d tau / dp = 2 lambda^T / zeta^2 - 2 |lambda|^2 O^T / zeta^3.
        let proj = Matrix3::identity() - self.o * self.o.transpose();
        let dtau =
            lambda.transpose() * (2.0 / (zeta * zeta)) - self.o.transpose() * (2.0 * l2 / zeta.powi(3));
        let dq = Matrix3::identity() + proj * mu + lambda * (dtau * dmu_dtau);
        cahv_project_jacobian(&self.a, &self.h, &self.v, &(d + lambda * mu), &dq)
    }
}

impl Movable for Cahvor {
    fn moved(&self, pose: &Isometry3<f64>) -> Self {
        let r = pose.rotation;
        Self {
            c: (pose * Point3::from(self.c)).coords,
            a: r * self.a,
            h: r * self.h,
            v: r * self.v,
            o: r * self.o,
            ..*self
        }
    }
}
