//! Template magnification and roll compensation as one affine resampling (paper 003 section 3:
//! "NCC with template image magnification" and improvement 1, "template image roll
//! compensation (the MER mast does not provide roll control)").
//!
//! Between two images the target's neighbourhood appears, to first order, scaled by
//! s = r_old / r_new (its range shrinks as the rover approaches, so it grows in the image) and
//! rotated in the image plane by θ = -Δφ, where Δφ is the change of the camera's rotation about
//! its own pointing axis (for a forward-looking Navcam, the change of rover roll). A camera
//! rolled by +Δφ about its axis (x right, y down, z forward) sees a fixed point rotated by -Δφ,
//! so with R(θ) = [[cos θ, -sin θ], [sin θ, cos θ]] in (sample, line) coordinates an image
//! offset d from the target becomes s R(θ) d. The template for the next image is therefore
//! sampled from the reference image at c + (1/s) R(-θ) d for each template offset d, bilinearly.
//! Departure: no low-pass filter before shrinking (s < 1); at the 10 % steps the paper drives
//! (s >= 0.9 when backing off, s <= 1.25 approaching) the aliasing is negligible.

use image::Luma;
use nalgebra::Point2;

use super::TrackError;
use crate::image::GreyF32;

/// The similarity transform the next image applies about the target: magnification and
/// in-plane rotation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TemplateWarp {
    /// Magnification s = r_old / r_new (> 1 when the target comes closer).
    pub scale: f64,
    /// Image-plane rotation θ (rad) of the scene, in (sample, line) coordinates.
    pub rotation_rad: f64,
}

impl TemplateWarp {
    /// No change.
    pub const IDENTITY: Self = Self { scale: 1.0, rotation_rad: 0.0 };

    /// The warp for a target seen at range `range_old` (m) with camera roll `roll_old` (rad,
    /// about the pointing axis) and next at `range_new` with `roll_new`: s = r_old / r_new,
    /// θ = -(roll_new - roll_old).
    pub fn from_range_and_roll(range_old: f64, range_new: f64, roll_old: f64, roll_new: f64) -> Self {
        Self { scale: range_old / range_new, rotation_rad: -(roll_new - roll_old) }
    }

    /// Where a point at offset (dx, dy) from the target in the next image appears, as an offset
    /// in the reference image: (1/s) R(-θ) d.
    pub fn source_offset(&self, dx: f64, dy: f64) -> (f64, f64) {
        let (sin, cos) = self.rotation_rad.sin_cos();
        ((cos * dx + sin * dy) / self.scale, (-sin * dx + cos * dy) / self.scale)
    }

    /// Where a reference-image offset appears in the next image: s R(θ) d.
    pub fn forward_offset(&self, dx: f64, dy: f64) -> (f64, f64) {
        let (sin, cos) = self.rotation_rad.sin_cos();
        (self.scale * (cos * dx - sin * dy), self.scale * (sin * dx + cos * dy))
    }
}

/// The bilinear interpolation of `img` at (x, y) (pixel centres at integers); `None` outside.
pub fn bilinear(img: &GreyF32, x: f64, y: f64) -> Option<f32> {
    let (w, h) = (img.width() as usize, img.height() as usize);
    if !(x >= 0.0 && y >= 0.0 && x <= (w - 1) as f64 && y <= (h - 1) as f64) {
        return None;
    }
    let (x0, y0) =
        ((x.floor() as usize).min(w.saturating_sub(2)), (y.floor() as usize).min(h.saturating_sub(2)));
    let (fx, fy) = (x - x0 as f64, y - y0 as f64);
    let raw = img.as_raw();
    let at = |xx: usize, yy: usize| raw[yy.min(h - 1) * w + xx.min(w - 1)] as f64;
    let top = at(x0, y0) * (1.0 - fx) + at(x0 + 1, y0) * fx;
    let bottom = at(x0, y0 + 1) * (1.0 - fx) + at(x0 + 1, y0 + 1) * fx;
    Some((top * (1.0 - fy) + bottom * fy) as f32)
}

/// A (2 half + 1)² template for the next image, resampled from `source` about the target's
/// pixel `centre` by `warp`; an error if its footprint leaves the source image.
pub fn resample_template(
    source: &GreyF32,
    centre: Point2<f64>,
    half: usize,
    warp: &TemplateWarp,
) -> Result<GreyF32, TrackError> {
    if !(warp.scale.is_finite() && warp.scale > 0.0 && warp.rotation_rad.is_finite()) {
        return Err(TrackError::Template(format!(
            "warp scale {} rotation {} is not usable",
            warp.scale, warp.rotation_rad
        )));
    }
    let size = 2 * half + 1;
    let mut out = GreyF32::new(size as u32, size as u32);
    for j in 0..size {
        for i in 0..size {
            let (ox, oy) = warp.source_offset(i as f64 - half as f64, j as f64 - half as f64);
            let v = bilinear(source, centre.x + ox, centre.y + oy).ok_or(TrackError::OutOfView)?;
            out.put_pixel(i as u32, j as u32, Luma([v]));
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    fn close(a: (f64, f64), b: (f64, f64)) -> bool {
        (a.0 - b.0).abs() < 1e-12 && (a.1 - b.1).abs() < 1e-12
    }

    #[test]
    fn magnification_hand_worked() {
        // 10 m -> 8 m: the target looks 1.25 times bigger; a point 5 px right of the target in
        // the next image is 4 px right of it in the reference image.
        let w = TemplateWarp::from_range_and_roll(10.0, 8.0, 0.0, 0.0);
        assert_eq!(w.scale, 1.25);
        assert!(close(w.source_offset(5.0, 0.0), (4.0, 0.0)));
        assert!(close(w.source_offset(0.0, -2.5), (0.0, -2.0)));
        assert!(close(w.forward_offset(4.0, 0.0), (5.0, 0.0)));
    }

    #[test]
    fn roll_hand_worked() {
        // The camera rolls +90 deg about its axis: a point that was 1 px right of the target
        // (camera x) is now along camera -y, i.e. 1 px above it (lines grow downwards).
        let w = TemplateWarp::from_range_and_roll(5.0, 5.0, 0.1, 0.1 + FRAC_PI_2);
        assert!(close(w.forward_offset(1.0, 0.0), (0.0, -1.0)));
        assert!(close(w.source_offset(0.0, -1.0), (1.0, 0.0)));
        // Scale and roll together: 2x closer and rolled +90 deg.
        let w = TemplateWarp::from_range_and_roll(10.0, 5.0, 0.0, FRAC_PI_2);
        assert!(close(w.forward_offset(1.0, 0.0), (0.0, -2.0)));
        assert!(close(w.source_offset(0.0, -2.0), (1.0, 0.0)));
    }

    #[test]
    fn warp_agrees_with_cahv_cameras_that_approach_and_roll() {
        // A camera looking along +x at a wall point 10 m away, then 8 m away and rolled by
        // +7 deg about its axis: wall points near the target must move as the warp says.
        use crate::camera::{Cahv, CameraModel};
        use nalgebra::{Point3, Rotation3, Vector3};
        let cam = |x: f64, roll: f64| {
            let right = Rotation3::from_axis_angle(&Vector3::x_axis(), roll) * -Vector3::y();
            Cahv::from_intrinsics(
                Vector3::new(x, 0.0, 0.0),
                Vector3::x(),
                right,
                500.0,
                500.0,
                255.5,
                255.5,
                512,
                512,
            )
        };
        let roll = 7f64.to_radians();
        let (before, after) = (cam(0.0, 0.0), cam(2.0, roll));
        let target = Point3::new(10.0, 0.0, 0.0);
        let warp = TemplateWarp::from_range_and_roll(10.0, 8.0, 0.0, roll);
        let (c0, c1) = (before.project(&target).unwrap(), after.project(&target).unwrap());
        for (dy, dz) in [(0.1, 0.0), (0.0, 0.1), (-0.07, 0.04)] {
            let p = Point3::new(10.0, dy, dz);
            let (q0, q1) = (before.project(&p).unwrap(), after.project(&p).unwrap());
            let predicted = warp.forward_offset(q0.x - c0.x, q0.y - c0.y);
            assert!((predicted.0 - (q1.x - c1.x)).abs() < 1e-9 && (predicted.1 - (q1.y - c1.y)).abs() < 1e-9);
        }
    }

    #[test]
    fn resampling_a_linear_ramp_is_exact() {
        // Bilinear interpolation reproduces a linear image: I = 2x + 3y.
        let img = GreyF32::from_fn(50, 50, |x, y| Luma([2.0 * x as f32 + 3.0 * y as f32]));
        let warp = TemplateWarp { scale: 0.8, rotation_rad: 0.3 };
        let t = resample_template(&img, Point2::new(24.3, 25.6), 4, &warp).unwrap();
        for j in 0..9u32 {
            for i in 0..9u32 {
                let (ox, oy) = warp.source_offset(i as f64 - 4.0, j as f64 - 4.0);
                let want = 2.0 * (24.3 + ox) + 3.0 * (25.6 + oy);
                assert!((t.get_pixel(i, j)[0] as f64 - want).abs() < 1e-3);
            }
        }
        assert_eq!(resample_template(&img, Point2::new(2.0, 25.0), 4, &warp), Err(TrackError::OutOfView));
        assert!(bilinear(&img, 49.0, 49.0).is_some() && bilinear(&img, 49.01, 3.0).is_none());
    }
}
