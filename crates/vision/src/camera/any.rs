//! A camera model of any of the CAHV family, as read from a label whose model type is known
//! only at run time.

use nalgebra::{Isometry3, Matrix2x3, Point2, Point3};

use super::{Cahv, Cahvor, Cahvore, CameraModel, Movable, Ray};

/// A CAHV, CAHVOR or CAHVORE model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AnyCamera {
    /// Linear model.
    Cahv(Cahv),
    /// Radial distortion about O.
    Cahvor(Cahvor),
    /// Radial distortion and entrance-pupil motion.
    Cahvore(Cahvore),
}

impl AnyCamera {
    /// The linear part (C, A, H, V) of the model.
    pub fn linear(&self) -> Cahv {
        match self {
            Self::Cahv(m) => *m,
            Self::Cahvor(m) => m.linear(),
            Self::Cahvore(m) => m.linear(),
        }
    }

    /// The model's name as in the labels: "CAHV", "CAHVOR" or "CAHVORE".
    pub fn type_name(&self) -> &'static str {
        match self {
            Self::Cahv(_) => "CAHV",
            Self::Cahvor(_) => "CAHVOR",
            Self::Cahvore(_) => "CAHVORE",
        }
    }

    /// The model as a trait object.
    pub fn as_model(&self) -> &dyn CameraModel {
        match self {
            Self::Cahv(m) => m,
            Self::Cahvor(m) => m,
            Self::Cahvore(m) => m,
        }
    }
}

impl From<Cahv> for AnyCamera {
    fn from(m: Cahv) -> Self {
        Self::Cahv(m)
    }
}

impl From<Cahvor> for AnyCamera {
    fn from(m: Cahvor) -> Self {
        Self::Cahvor(m)
    }
}

impl From<Cahvore> for AnyCamera {
    fn from(m: Cahvore) -> Self {
        Self::Cahvore(m)
    }
}

impl CameraModel for AnyCamera {
    fn width(&self) -> usize {
        self.as_model().width()
    }

    fn height(&self) -> usize {
        self.as_model().height()
    }

    fn project(&self, point: &Point3<f64>) -> Option<Point2<f64>> {
        self.as_model().project(point)
    }

    fn unproject(&self, pixel: &Point2<f64>) -> Ray {
        self.as_model().unproject(pixel)
    }

    fn centre(&self) -> Point3<f64> {
        self.as_model().centre()
    }

    fn project_jacobian(&self, point: &Point3<f64>) -> Option<(Point2<f64>, Matrix2x3<f64>)> {
        self.as_model().project_jacobian(point)
    }
}

impl Movable for AnyCamera {
    fn moved(&self, pose: &Isometry3<f64>) -> Self {
        match self {
            Self::Cahv(m) => Self::Cahv(m.moved(pose)),
            Self::Cahvor(m) => Self::Cahvor(m.moved(pose)),
            Self::Cahvore(m) => Self::Cahvore(m.moved(pose)),
        }
    }
}
