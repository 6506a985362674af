//! The CAHVORE camera model: CAHVOR for wide-angle and fish-eye lenses, with an entrance pupil
//! that moves along the optical axis with the incidence angle (Gennery, "Generalized camera
//! calibration including fish-eye lenses", IJCV 68(3), 2006; the conventions of JPL's
//! camera-model library and the PDS labels: E = (e0, e1, e2), a model type 1 perspective,
//! 2 fish-eye, 3 general with a linearity parameter).
//!
//! A ray entering at angle theta from O passes through the pupil point C + s(theta) O with
//! s = (theta / sin theta - 1)(e0 + e1 theta^2 + e2 theta^4). For a point P with d = P - C,
//! zeta = d.O and lambda = |d - zeta O|, theta therefore solves
//! zeta sin theta - lambda cos theta - (theta - sin theta)(e0 + e1 theta^2 + e2 theta^4) = 0
//! (Newton's method from atan2(lambda, zeta)). The angle maps to chi = tan(L theta) / L
//! (L > 0), sin(L theta) / L (L < 0) or theta (L = 0), with the linearity L = 1 for type 1,
//! 0 for type 2 and the given parameter for type 3; then as in CAHVOR the radial distortion
//! scales the perpendicular part by 1 + mu, mu = r0 + r1 chi^2 + r2 chi^4, and the vector
//! (lambda / chi) O + (1 + mu) lambda_vec projects through C, A, H, V.
//!
//! With type 1 and E = 0 the model is exactly CAHVOR (tested against [`super::Cahvor`]).
//! As in JPL's library, points whose L theta reaches 90 degrees do not project; pixels outside
//! the model's valid field unproject along the linear model's ray (see [`super::Cahvor`]).

use nalgebra::{Isometry3, Matrix2x3, Matrix3, Point2, Point3, Unit, Vector3};

use super::cahvor::{cahv_direction, cahv_project_jacobian, invert_radial};
use super::{Cahv, CameraModel, Movable, Ray};

/// The projection type of a CAHVORE model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CahvoreType {
    /// Type 1: perspective (linearity 1).
    Perspective,
    /// Type 2: fish-eye (linearity 0).
    Fisheye,
    /// Type 3: general, with its linearity parameter.
    General(f64),
}

impl CahvoreType {
    /// The type of JPL's numeric code (1, 2 or 3) with the model parameter used by type 3.
    pub fn from_code(code: f64, parameter: f64) -> Option<Self> {
        if code == 1.0 {
            Some(Self::Perspective)
        } else if code == 2.0 {
            Some(Self::Fisheye)
        } else if code == 3.0 && parameter.is_finite() {
            Some(Self::General(parameter))
        } else {
            None
        }
    }

    /// JPL's numeric code of the type.
    pub fn code(&self) -> u8 {
        match self {
            Self::Perspective => 1,
            Self::Fisheye => 2,
            Self::General(_) => 3,
        }
    }

    /// The linearity L of the angle mapping.
    pub fn linearity(&self) -> f64 {
        match *self {
            Self::Perspective => 1.0,
            Self::Fisheye => 0.0,
            Self::General(l) => l,
        }
    }
}

/// A CAHVORE camera model with its image size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cahvore {
    /// Camera centre (the entrance pupil for rays along O).
    pub c: Vector3<f64>,
    /// Unit pointing axis.
    pub a: Vector3<f64>,
    /// Horizontal image vector.
    pub h: Vector3<f64>,
    /// Vertical image vector.
    pub v: Vector3<f64>,
    /// Unit optical axis.
    pub o: Vector3<f64>,
    /// Radial distortion coefficients (r0, r1, r2).
    pub r: Vector3<f64>,
    /// Entrance-pupil motion coefficients (e0, e1, e2), in the units of C.
    pub e: Vector3<f64>,
    /// Projection type.
    pub kind: CahvoreType,
    /// Image width in pixels.
    pub width: usize,
    /// Image height in pixels.
    pub height: usize,
}

/// Below this angle (radians) from O the small-angle forms are used (as JPL's library does).
const SMALL_ANGLE: f64 = 1e-9;

impl Cahvore {
    /// A CAHVORE model from its linear part and the terms O (normalised), R, E and the type.
    pub fn new(linear: Cahv, o: Vector3<f64>, r: Vector3<f64>, e: Vector3<f64>, kind: CahvoreType) -> Self {
        Self {
            c: linear.c,
            a: linear.a,
            h: linear.h,
            v: linear.v,
            o: o.normalize(),
            r,
            e,
            kind,
            width: linear.width,
            height: linear.height,
        }
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

    /// e0 + e1 t^2 + e2 t^4 and its derivative.
    fn pupil_poly(&self, theta: f64) -> (f64, f64) {
        let t2 = theta * theta;
        let e = &self.e;
        (e[0] + e[1] * t2 + e[2] * t2 * t2, 2.0 * e[1] * theta + 4.0 * e[2] * theta * t2)
    }

    /// The pupil shift s(theta) along O.
    pub fn pupil_shift(&self, theta: f64) -> f64 {
        if theta.abs() < 1e-4 {
            // theta / sin theta - 1 = theta^2 / 6 + 7 theta^4 / 360 + ...
            let t2 = theta * theta;
            (t2 / 6.0 + 7.0 * t2 * t2 / 360.0) * self.pupil_poly(theta).0
        } else {
            (theta / theta.sin() - 1.0) * self.pupil_poly(theta).0
        }
    }

    /// The incidence angle theta of a point at (zeta, lambda) and the derivative of the
    /// defining equation with respect to theta; `None` if Newton's method fails.
    fn incidence(&self, zeta: f64, lambda: f64) -> Option<(f64, f64)> {
        let derivative = |theta: f64| {
            let (s, c) = theta.sin_cos();
            let (ep, dep) = self.pupil_poly(theta);
            zeta * c + lambda * s - (1.0 - c) * ep - (theta - s) * dep
        };
        let mut theta = lambda.atan2(zeta);
        for _ in 0..100 {
            let (s, c) = theta.sin_cos();
            let upsilon = derivative(theta);
            if upsilon == 0.0 || !upsilon.is_finite() {
                return None;
            }
            let step = (zeta * s - lambda * c - (theta - s) * self.pupil_poly(theta).0) / upsilon;
            theta -= step;
            if step.abs() <= 1e-14 * (1.0 + theta.abs()) {
                return (theta.is_finite() && theta >= 0.0).then(|| (theta, derivative(theta)));
            }
        }
        None
    }

    /// chi(theta) and d chi / d theta for the model's linearity.
    fn chi_of_theta(&self, theta: f64) -> (f64, f64) {
        let l = self.kind.linearity();
        if l > 1e-15 {
            let c = (l * theta).cos();
            ((l * theta).tan() / l, 1.0 / (c * c))
        } else if l < -1e-15 {
            ((l * theta).sin() / l, (l * theta).cos())
        } else {
            (theta, 1.0)
        }
    }

    /// theta(chi), the inverse of [`Self::chi_of_theta`].
    fn theta_of_chi(&self, chi: f64) -> f64 {
        let l = self.kind.linearity();
        if l > 1e-15 {
            (l * chi).atan() / l
        } else if l < -1e-15 {
            (l * chi).clamp(-1.0, 1.0).asin() / l
        } else {
            chi
        }
    }

    /// Whether the angle mapping is defined at theta (L theta below 90 degrees).
    fn angle_ok(&self, theta: f64) -> bool {
        theta * self.kind.linearity().abs() < std::f64::consts::FRAC_PI_2
    }
}

impl CameraModel for Cahvore {
    fn width(&self) -> usize {
        self.width
    }

    fn height(&self) -> usize {
        self.height
    }

    fn project(&self, point: &Point3<f64>) -> Option<Point2<f64>> {
        self.project_jacobian(point).map(|(px, _)| px)
    }

    fn unproject(&self, pixel: &Point2<f64>) -> Ray {
        let rp = cahv_direction(&self.a, &self.h, &self.v, pixel);
        let zeta = rp.dot(&self.o);
        let lambda = rp - self.o * zeta;
        let lambda_norm = lambda.norm();
        if zeta <= 0.0 || lambda_norm < SMALL_ANGLE * zeta {
            let direction = if zeta > 0.0 { self.o * zeta + lambda / (1.0 + self.r[0]) } else { rp };
            return Ray { origin: Point3::from(self.c), direction: Unit::new_normalize(direction) };
        }
        let Some(chi) = invert_radial(&self.r, lambda_norm / zeta) else {
            return Ray { origin: Point3::from(self.c), direction: Unit::new_normalize(rp) };
        };
        let theta = self.theta_of_chi(chi);
        let origin = self.c + self.o * self.pupil_shift(theta);
        let direction = self.o * theta.cos() + lambda * (theta.sin() / lambda_norm);
        Ray { origin: Point3::from(origin), direction: Unit::new_normalize(direction) }
    }

    fn centre(&self) -> Point3<f64> {
        Point3::from(self.c)
    }

    fn project_jacobian(&self, point: &Point3<f64>) -> Option<(Point2<f64>, Matrix2x3<f64>)> {
        let d = point.coords - self.c;
        let zeta = d.dot(&self.o);
        let lambda_vec = d - self.o * zeta;
        let lambda = lambda_vec.norm();
        let proj = Matrix3::identity() - self.o * self.o.transpose();
        if lambda <= SMALL_ANGLE * zeta.abs() {
            // On the axis: the linear model with the perpendicular part scaled by 1 + r0.
            if zeta <= 0.0 {
                return None;
            }
            let q = self.o * zeta + lambda_vec * (1.0 + self.r[0]);
            let dq = self.o * self.o.transpose() + proj * (1.0 + self.r[0]);
            return cahv_project_jacobian(&self.a, &self.h, &self.v, &q, &dq);
        }
        let (theta, upsilon) = self.incidence(zeta, lambda)?;
        if !self.angle_ok(theta) {
            return None;
        }
        let (chi, dchi_dtheta) = self.chi_of_theta(theta);
        if chi <= 0.0 {
            return None;
        }
        let chi2 = chi * chi;
        let mu = self.r[0] + self.r[1] * chi2 + self.r[2] * chi2 * chi2;
        let dmu_dchi = 2.0 * self.r[1] * chi + 4.0 * self.r[2] * chi * chi2;
        let q = self.o * (lambda / chi) + lambda_vec * (1.0 + mu);
        // Implicit differentiation of the incidence equation: d theta / dp =
        // (cos theta u^T - sin theta O^T) / upsilon, with u the unit perpendicular direction.
        let u = lambda_vec / lambda;
        let (st, ct) = theta.sin_cos();
        let dtheta = (u.transpose() * ct - self.o.transpose() * st) / upsilon;
        let dchi = dtheta * dchi_dtheta;
        let dq = self.o * (u.transpose() / chi - dchi * (lambda / chi2))
            + lambda_vec * (dchi * dmu_dchi)
            + proj * (1.0 + mu);
        cahv_project_jacobian(&self.a, &self.h, &self.v, &q, &dq)
    }
}

impl Movable for Cahvore {
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
