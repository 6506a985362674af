//! Stereo rectification: two CAHV, CAHVOR or CAHVORE models warped to a pair of linear CAHV
//! models that share A, H and V (so epipolar lines are image rows and a point's disparity is
//! f b / depth), with the images resampled through the pair.
//!
//! The common model follows JPL's practice (the model warping of Gennery's calibration work,
//! as used by the MER/MSL ground and flight stereo): each output camera keeps its own centre C;
//! H' (the unit horizontal image axis) lies along the baseline C_right - C_left, signed to agree
//! with the input H' axes; A is the mean of the input axes made perpendicular to the baseline;
//! V' = A x H' (signed to agree with the input V' axes); both cameras get the same focal length
//! and image centre. Departures: the focal length is the mean of the four input focal lengths
//! and the image centre the mean of the two input centres (JPL's library offers several
//! choices; these keep the input resolution and framing); the output image has the left input's
//! size.
//!
//! Resampling maps each output pixel through the output model's ray to the input model's pixel
//! (for CAHVORE, whose entrance pupil moves, at a nominal range along the ray) and interpolates
//! bilinearly; output pixels whose source falls outside the input image are 0.

use nalgebra::{Point2, Vector3};
use rayon::prelude::*;
use thiserror::Error;

use crate::camera::{AnyCamera, Cahv, CameraModel};
use crate::image::{Grey16, GreyF32};

/// Why a pair cannot be rectified or an image resampled.
#[derive(Debug, Error, PartialEq)]
pub enum RectifyError {
    /// The two camera centres coincide.
    #[error("rectify: the camera centres coincide (baseline {0} m)")]
    ZeroBaseline(f64),
    /// The baseline points along the cameras' axis: no image plane contains it.
    #[error("rectify: the baseline is within {0:.1} deg of the pointing axis")]
    BaselineAlongAxis(f64),
    /// An image does not match its camera model's size.
    #[error("rectify: {which} image is {got_w}x{got_h}, its camera model {want_w}x{want_h}")]
    SizeMismatch {
        /// Which image ("left", "right" or "source").
        which: &'static str,
        /// Image width.
        got_w: u32,
        /// Image height.
        got_h: u32,
        /// Model width.
        want_w: usize,
        /// Model height.
        want_h: usize,
    },
}

/// The common linear models of a rectified pair.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RectifiedModels {
    /// Left output model.
    pub left: Cahv,
    /// Right output model.
    pub right: Cahv,
}

impl RectifiedModels {
    /// Focal length in pixels (the same in both directions and both cameras).
    pub fn focal(&self) -> f64 {
        self.left.focal_h()
    }

    /// Baseline length |C_right - C_left|.
    pub fn baseline(&self) -> f64 {
        (self.right.c - self.left.c).norm()
    }

    /// The disparity x_left - x_right of a point at `depth` along A: f b / depth.
    pub fn disparity_at_depth(&self, depth: f64) -> f64 {
        self.focal() * self.baseline() / depth
    }
}

/// The rectified linear pair of two camera models (see the module documentation).
pub fn rectify_models(left: &AnyCamera, right: &AnyCamera) -> Result<RectifiedModels, RectifyError> {
    let (l, r) = (left.linear(), right.linear());
    let baseline = r.c - l.c;
    let b = baseline.norm();
    if b < 1e-9 {
        return Err(RectifyError::ZeroBaseline(b));
    }
    let mut hs = baseline / b;
    if hs.dot(&(l.h_axis() + r.h_axis())) < 0.0 {
        hs = -hs;
    }
    let mean_axis = (l.a + r.a).normalize();
    let along = mean_axis.dot(&hs);
    let a = mean_axis - hs * along;
    if a.norm() < 0.1 {
        return Err(RectifyError::BaselineAlongAxis(along.abs().min(1.0).acos().to_degrees()));
    }
    let a = a.normalize();
    let mut vs = a.cross(&hs);
    if vs.dot(&(l.v_axis() + r.v_axis())) < 0.0 {
        vs = -vs;
    }
    let f = (l.focal_h() + l.focal_v() + r.focal_h() + r.focal_v()) / 4.0;
    let ((lh, lv), (rh, rv)) = (l.image_centre(), r.image_centre());
    let (hc, vc) = ((lh + rh) / 2.0, (lv + rv) / 2.0);
    let model = |c: Vector3<f64>| Cahv {
        c,
        a,
        h: hs * f + a * hc,
        v: vs * f + a * vc,
        width: l.width,
        height: l.height,
    };
    Ok(RectifiedModels { left: model(l.c), right: model(r.c) })
}

/// For each pixel of an output (rectified) image, where to sample the input image.
#[derive(Clone, Debug, PartialEq)]
pub struct RectifyMap {
    /// Output width.
    pub width: usize,
    /// Output height.
    pub height: usize,
    /// Input image size the map samples (width, height).
    pub source_size: (usize, usize),
    /// Input (sample, line) per output pixel, row-major; NaN where the ray does not project.
    pub source: Vec<[f32; 2]>,
}

impl RectifyMap {
    /// The map from `source` (the camera that took the image) to the linear model `target`,
    /// sampling each output ray at `range` (only CAHVORE's moving pupil makes it matter).
    pub fn new(source: &dyn CameraModel, target: &Cahv, range: f64) -> Self {
        let (w, h) = (target.width, target.height);
        let mut map = vec![[f32::NAN; 2]; w * h];
        map.par_chunks_mut(w.max(1)).enumerate().for_each(|(y, row)| {
            for (x, out) in row.iter_mut().enumerate() {
                let ray = target.unproject(&Point2::new(x as f64, y as f64));
                if let Some(p) = source.project(&ray.at(range)) {
                    *out = [p.x as f32, p.y as f32];
                }
            }
        });
        Self { width: w, height: h, source_size: (source.width(), source.height()), source: map }
    }

    /// Resamples a 16-bit image (rounded to the nearest DN).
    pub fn apply_grey16(&self, image: &Grey16) -> Result<Grey16, RectifyError> {
        self.check(image.width(), image.height())?;
        let out = self.warp(image.as_raw(), |v| v as f32, |v| v.round().clamp(0.0, 65535.0) as u16);
        Ok(Grey16::from_raw(self.width as u32, self.height as u32, out).expect("size matches"))
    }

    /// Resamples a float image.
    pub fn apply_f32(&self, image: &GreyF32) -> Result<GreyF32, RectifyError> {
        self.check(image.width(), image.height())?;
        let out = self.warp(image.as_raw(), |v| v, |v| v);
        Ok(GreyF32::from_raw(self.width as u32, self.height as u32, out).expect("size matches"))
    }

    /// Whether output pixel (x, y) samples inside the input image.
    pub fn valid(&self, x: usize, y: usize) -> bool {
        x < self.width && y < self.height && self.sample_weights(self.source[y * self.width + x]).is_some()
    }

    fn check(&self, w: u32, h: u32) -> Result<(), RectifyError> {
        if (w as usize, h as usize) == self.source_size {
            Ok(())
        } else {
            Err(RectifyError::SizeMismatch {
                which: "source",
                got_w: w,
                got_h: h,
                want_w: self.source_size.0,
                want_h: self.source_size.1,
            })
        }
    }

    /// The top-left integer pixel and the bilinear fractions of a source position; positions
    /// within the half-pixel border are clamped to the edge pixels.
    fn sample_weights(&self, p: [f32; 2]) -> Option<(usize, usize, f32, f32)> {
        let (sw, sh) = (self.source_size.0 as f32, self.source_size.1 as f32);
        let [x, y] = p;
        if !(x >= -0.5 && y >= -0.5 && x <= sw - 0.5 && y <= sh - 0.5) {
            return None;
        }
        let x = x.clamp(0.0, sw - 1.0);
        let y = y.clamp(0.0, sh - 1.0);
        let (x0, y0) = (
            (x.floor() as usize).min(self.source_size.0.saturating_sub(2)),
            (y.floor() as usize).min(self.source_size.1.saturating_sub(2)),
        );
        Some((x0, y0, x - x0 as f32, y - y0 as f32))
    }

    fn warp<T: Copy + Default + Send + Sync>(
        &self,
        src: &[T],
        to_f: fn(T) -> f32,
        from_f: fn(f32) -> T,
    ) -> Vec<T> {
        let sw = self.source_size.0;
        let single_column = self.source_size.0 < 2 || self.source_size.1 < 2;
        let mut out = vec![T::default(); self.width * self.height];
        out.par_chunks_mut(self.width.max(1)).enumerate().for_each(|(y, row)| {
            for (x, o) in row.iter_mut().enumerate() {
                let Some((x0, y0, fx, fy)) = self.sample_weights(self.source[y * self.width + x]) else {
                    continue;
                };
                if single_column {
                    *o = src[y0.min(self.source_size.1 - 1) * sw + x0.min(sw - 1)];
                    continue;
                }
                let k = y0 * sw + x0;
                let top = to_f(src[k]) * (1.0 - fx) + to_f(src[k + 1]) * fx;
                let bottom = to_f(src[k + sw]) * (1.0 - fx) + to_f(src[k + sw + 1]) * fx;
                *o = from_f(top * (1.0 - fy) + bottom * fy);
            }
        });
        out
    }
}

/// A rectified image pair with its linear models.
#[derive(Clone, Debug, PartialEq)]
pub struct RectifiedPair<I> {
    /// Left rectified image.
    pub left: I,
    /// Right rectified image.
    pub right: I,
    /// The output models.
    pub models: RectifiedModels,
}

fn check_size(which: &'static str, w: u32, h: u32, model: &AnyCamera) -> Result<(), RectifyError> {
    if (w as usize, h as usize) == (model.width(), model.height()) {
        Ok(())
    } else {
        Err(RectifyError::SizeMismatch {
            which,
            got_w: w,
            got_h: h,
            want_w: model.width(),
            want_h: model.height(),
        })
    }
}

/// Rectifies a 16-bit pair: the common models, and both images resampled through them
/// (`range` as in [`RectifyMap::new`]).
pub fn rectify_pair_grey16(
    left: &Grey16,
    left_model: &AnyCamera,
    right: &Grey16,
    right_model: &AnyCamera,
    range: f64,
) -> Result<RectifiedPair<Grey16>, RectifyError> {
    check_size("left", left.width(), left.height(), left_model)?;
    check_size("right", right.width(), right.height(), right_model)?;
    let models = rectify_models(left_model, right_model)?;
    let l = RectifyMap::new(left_model, &models.left, range).apply_grey16(left)?;
    let r = RectifyMap::new(right_model, &models.right, range).apply_grey16(right)?;
    Ok(RectifiedPair { left: l, right: r, models })
}

/// Rectifies a float pair (see [`rectify_pair_grey16`]).
pub fn rectify_pair_f32(
    left: &GreyF32,
    left_model: &AnyCamera,
    right: &GreyF32,
    right_model: &AnyCamera,
    range: f64,
) -> Result<RectifiedPair<GreyF32>, RectifyError> {
    check_size("left", left.width(), left.height(), left_model)?;
    check_size("right", right.width(), right.height(), right_model)?;
    let models = rectify_models(left_model, right_model)?;
    let l = RectifyMap::new(left_model, &models.left, range).apply_f32(left)?;
    let r = RectifyMap::new(right_model, &models.right, range).apply_f32(right)?;
    Ok(RectifiedPair { left: l, right: r, models })
}
