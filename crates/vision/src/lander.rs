//! Rover detection in lander images (paper 002 section 2, approach (a)): the lander's stereo
//! pair, aimed at the rover's approximate position, takes one image before and one after the
//! rover turns in place; "the absolute difference of these images is thresholded and binarized,
//! then the center of the bounding box of the largest connected region in the binary image is
//! taken to be the image coordinates of the rover. Cross correlation of an image patch around
//! these coordinates gives the location of the rover in the other image of a stereo pair;
//! finally, the position of the rover relative to the lander is computed by stereo
//! triangulation."
//!
//! The steps are [`difference_mask`], [`largest_region`] and [`detect_rover`] (which runs both,
//! correlates the region along the rectified pair's rows and triangulates z = f b / d along
//! the ray of the region's box centre). What the triangulated point means (a point of the
//! rover's visible surface, not its centre) is the localisation crate's business
//! (`rovernav_localization::lander`).
//!
//! Departures from the paper, with reasons:
//! - The paper does not give its threshold. Here it is `threshold_sigmas` robust standard
//!   deviations of the difference image (1.4826 x its median absolute value: most pixels do not
//!   change, so the median measures the noise), never below `min_threshold_dn`; a threshold
//!   tied to the noise works at any exposure.
//! - The binary image is morphologically closed (`close_px`, a square element) before its
//!   eight-connected regions are labelled. An in-place turn changes the ends of the body and
//!   barely its middle, so the changed pixels fall into separate crescents; without closing, the
//!   largest of them is half the rover and its box centre is off by a quarter of the rover's
//!   length. The caller sizes `close_px` from the range it aimed at.
//! - The "image patch around these coordinates" is the region itself: only the region's pixels
//!   inside its box are correlated (zero-mean NCC over them, one score per integer disparity,
//!   a parabola through the best three). A square patch at the box centre sees mostly ground
//!   behind the rover wherever the mast makes the box tall (at 10 m a patch at the box centre
//!   lies beside the mast, on ground metres behind the rover); the changed pixels are the
//!   rover's by construction.

use image::Luma;
use imageproc::distance_transform::Norm;
use imageproc::region_labelling::{Connectivity, connected_components};
use nalgebra::{Point2, Point3};

use crate::camera::CameraModel;
use crate::image::{Grey8, GreyF32};
use crate::stereo::StereoRig;
use crate::tracking::ncc::parabola_vertex;

/// Why no rover was found.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum LanderError {
    /// The images differ in size or are empty.
    #[error("images: {0}")]
    Images(String),
    /// A parameter is out of range.
    #[error("parameter: {0}")]
    Parameter(String),
    /// Nothing changed between the two images (no region above the threshold).
    #[error("no changed region of at least {min_px} pixels (largest {largest_px})")]
    NoChange {
        /// Smallest accepted region (pixels).
        min_px: usize,
        /// The largest region found (pixels).
        largest_px: usize,
    },
    /// The region could not be found in the other image.
    #[error("stereo: {0}")]
    Stereo(String),
}

/// Disparity standard deviation of a correlated rover region (px): 0.1, from the downrange
/// RMS of `rovernav eval lander --first-seed 1001 --trials 150` (0.064, 0.078, 0.068 and
/// 0.104 m at 2-4, 4-6, 6-8 and 8-10 m: a constant of about 0.06 m, where on the body the
/// point falls, and Matthies' range sigma at 0.1 px for the 15 cm, 40 deg, 512 px pair, 0.08 m
/// at 9 m). The region correlates hundreds of pixels at once, so it is more precise than a
/// window's 0.25 px (`stereo::range::DEFAULT_SIGMA_D_PX`).
pub const LANDER_SIGMA_D_PX: f64 = 0.1;

/// Detection settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DetectParams {
    /// Threshold on the absolute difference, in robust standard deviations of the difference.
    pub threshold_sigmas: f32,
    /// Smallest threshold (DN), whatever the noise estimate.
    pub min_threshold_dn: f32,
    /// Radius (px) of the square element the binary image is closed with (0: no closing).
    pub close_px: u8,
    /// Smallest region taken for the rover (pixels).
    pub min_region_px: usize,
    /// Disparities searched (px, inclusive).
    pub disparity: (usize, usize),
    /// Lowest accepted correlation score.
    pub min_score: f32,
    /// Disparity standard deviation (px) for the range uncertainty.
    pub sigma_d_px: f64,
}

impl Default for DetectParams {
    fn default() -> Self {
        Self {
            threshold_sigmas: 6.0,
            min_threshold_dn: 8.0,
            close_px: 3,
            min_region_px: 20,
            disparity: (1, 200),
            min_score: 0.5,
            sigma_d_px: LANDER_SIGMA_D_PX,
        }
    }
}

impl DetectParams {
    /// Settings for a rover aimed at from `range_m` (m) by a pair of focal length `focal_px` and
    /// baseline `baseline_m`: the closing bridges gaps of 6 cm at that range, the disparity
    /// search covers a third to three times the range.
    pub fn aimed(focal_px: f64, baseline_m: f64, range_m: f64) -> Self {
        let range_m = range_m.max(0.1);
        let px_per_m = focal_px / range_m;
        let d = focal_px * baseline_m / range_m;
        Self {
            close_px: (0.06 * px_per_m).round().clamp(1.0, 40.0) as u8,
            disparity: ((d / 3.0).floor().max(1.0) as usize, (3.0 * d).ceil().max(4.0) as usize),
            ..Self::default()
        }
    }
}

/// A connected region of the binary image: its bounding box (inclusive) and pixels.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Region {
    /// Smallest column.
    pub x_min: u32,
    /// Largest column.
    pub x_max: u32,
    /// Smallest row.
    pub y_min: u32,
    /// Largest row.
    pub y_max: u32,
    /// The region's pixels (column, row), in row-major order.
    pub pixels: Vec<(u32, u32)>,
}

impl Region {
    /// The centre of the bounding box (pixel coordinates, sample then line).
    pub fn centre(&self) -> Point2<f64> {
        Point2::new(0.5 * (self.x_min + self.x_max) as f64, 0.5 * (self.y_min + self.y_max) as f64)
    }

    /// Width and height of the bounding box (pixels).
    pub fn size(&self) -> (u32, u32) {
        (self.x_max - self.x_min + 1, self.y_max - self.y_min + 1)
    }
}

/// The rover found in the lander's images.
#[derive(Clone, Debug, PartialEq)]
pub struct RoverDetection {
    /// The largest changed region of the left camera's (closed) difference image.
    pub region: Region,
    /// The rover's image position in the left (after) image: the region's box centre.
    pub pixel: Point2<f64>,
    /// The difference threshold used (DN).
    pub threshold_dn: f32,
    /// Subpixel disparity of the region (px).
    pub disparity: f64,
    /// Correlation score of the best disparity.
    pub score: f32,
    /// Depth along the left camera's axis (m).
    pub depth_m: f64,
    /// Range from the left camera centre along `pixel`'s ray (m).
    pub range_m: f64,
    /// Matthies' standard deviation of that range (m).
    pub range_sigma_m: f64,
    /// The triangulated point on `pixel`'s ray, in the frame of the rig's camera models.
    pub point: Point3<f64>,
}

/// The threshold for `before` against `after`: `threshold_sigmas` robust standard deviations of
/// their difference (1.4826 x median |difference|), at least `min_threshold_dn`.
pub fn difference_threshold(
    before: &GreyF32,
    after: &GreyF32,
    params: &DetectParams,
) -> Result<f32, LanderError> {
    same_size(before, after)?;
    let mut d: Vec<f32> = before.pixels().zip(after.pixels()).map(|(a, b)| (a.0[0] - b.0[0]).abs()).collect();
    let mid = d.len() / 2;
    let (_, median, _) = d.select_nth_unstable_by(mid, f32::total_cmp);
    Ok((params.threshold_sigmas * 1.4826 * *median).max(params.min_threshold_dn))
}

/// The binary image of |after - before| > `threshold` (255 where changed, 0 elsewhere).
pub fn difference_mask(before: &GreyF32, after: &GreyF32, threshold: f32) -> Result<Grey8, LanderError> {
    same_size(before, after)?;
    let (w, h) = before.dimensions();
    Ok(Grey8::from_fn(w, h, |x, y| {
        let d = (after.get_pixel(x, y).0[0] - before.get_pixel(x, y).0[0]).abs();
        Luma([if d > threshold { 255 } else { 0 }])
    }))
}

/// The largest eight-connected region of the non-zero pixels of `mask` (the first one in
/// label order on a tie); `None` when `mask` is all zero.
pub fn largest_region(mask: &Grey8) -> Option<Region> {
    let labels = connected_components(mask, Connectivity::Eight, Luma([0u8]));
    let mut counts: Vec<usize> = Vec::new();
    for l in labels.pixels() {
        let l = l.0[0] as usize;
        if l > 0 {
            if counts.len() < l {
                counts.resize(l, 0);
            }
            counts[l - 1] += 1;
        }
    }
    let best =
        counts.iter().enumerate().rev().max_by_key(|(_, n)| **n).filter(|(_, n)| **n > 0)?.0 as u32 + 1;
    let pixels: Vec<(u32, u32)> =
        labels.enumerate_pixels().filter(|(_, _, l)| l.0[0] == best).map(|(x, y, _)| (x, y)).collect();
    let fold = |f: fn(u32, u32) -> u32, init: u32, pick: fn(&(u32, u32)) -> u32| {
        pixels.iter().map(pick).fold(init, f)
    };
    Some(Region {
        x_min: fold(u32::min, u32::MAX, |p| p.0),
        x_max: fold(u32::max, 0, |p| p.0),
        y_min: fold(u32::min, u32::MAX, |p| p.1),
        y_max: fold(u32::max, 0, |p| p.1),
        pixels,
    })
}

/// Zero-mean normalised cross-correlation of the left image's `pixels` against the right image
/// shifted by `d` columns (NaN when a shifted pixel leaves the image or either side is flat).
fn region_score(left: &GreyF32, right: &GreyF32, pixels: &[(u32, u32)], d: usize) -> f32 {
    let n = pixels.len() as f64;
    let (mut sl, mut sr, mut sll, mut srr, mut slr) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for &(x, y) in pixels {
        let Some(xr) = x.checked_sub(d as u32) else { return f32::NAN };
        let a = left.get_pixel(x, y).0[0] as f64;
        let b = right.get_pixel(xr, y).0[0] as f64;
        sl += a;
        sr += b;
        sll += a * a;
        srr += b * b;
        slr += a * b;
    }
    let cov = slr - sl * sr / n;
    let (vl, vr) = (sll - sl * sl / n, srr - sr * sr / n);
    if vl <= 0.0 || vr <= 0.0 {
        return f32::NAN;
    }
    (cov / (vl * vr).sqrt()) as f32
}

/// Finds the rover: `before` and `after_left` are the left camera's images before and after
/// the rover's turn, `after_right` the right camera's after the turn, `rig` the pair (as
/// calibrated: a calibration error here is an error of the result).
pub fn detect_rover(
    rig: &StereoRig,
    before: &GreyF32,
    after_left: &GreyF32,
    after_right: &GreyF32,
    params: &DetectParams,
) -> Result<RoverDetection, LanderError> {
    let (d_lo, d_hi) = params.disparity;
    if !(params.threshold_sigmas > 0.0 && params.min_threshold_dn >= 0.0 && d_lo >= 1 && d_hi > d_lo + 1) {
        return Err(LanderError::Parameter(format!(
            "threshold_sigmas {} must be positive, min_threshold_dn {} non-negative, disparities {d_lo}..{d_hi} at least 1 and three wide",
            params.threshold_sigmas, params.min_threshold_dn
        )));
    }
    same_size(after_left, after_right)?;
    let threshold_dn = difference_threshold(before, after_left, params)?;
    let mut mask = difference_mask(before, after_left, threshold_dn)?;
    if params.close_px > 0 {
        mask = imageproc::morphology::close(&mask, Norm::LInf, params.close_px);
    }
    let largest = largest_region(&mask);
    let largest_px = largest.as_ref().map_or(0, |r| r.pixels.len());
    let region = largest
        .filter(|r| r.pixels.len() >= params.min_region_px)
        .ok_or(LanderError::NoChange { min_px: params.min_region_px, largest_px })?;
    let pixel = region.centre();
    let scores: Vec<f32> =
        (d_lo..=d_hi).map(|d| region_score(after_left, after_right, &region.pixels, d)).collect();
    let (best, &score) = scores
        .iter()
        .enumerate()
        .filter(|(_, s)| s.is_finite())
        .max_by(|a, b| a.1.total_cmp(b.1))
        .ok_or_else(|| LanderError::Stereo("no disparity keeps the region inside the right image".into()))?;
    if score < params.min_score {
        return Err(LanderError::Stereo(format!("best score {score:.3} < {}", params.min_score)));
    }
    if best == 0 || best + 1 == scores.len() || !scores[best - 1].is_finite() || !scores[best + 1].is_finite()
    {
        return Err(LanderError::Stereo("best match on the edge of the disparity range".into()));
    }
    let (offset, _) = parabola_vertex(scores[best - 1], score, scores[best + 1]);
    let disparity = (d_lo + best) as f64 + offset;
    let depth_m = rig.depth(disparity);
    let ray = rig.left.unproject(&pixel);
    let cos = ray.direction.dot(&rig.left.a);
    let range_m = depth_m / cos;
    let range_sigma_m = rig.depth_sigma(depth_m, params.sigma_d_px) / cos;
    Ok(RoverDetection {
        region,
        pixel,
        threshold_dn,
        disparity,
        score,
        depth_m,
        range_m,
        range_sigma_m,
        point: ray.at(range_m),
    })
}

fn same_size(a: &GreyF32, b: &GreyF32) -> Result<(), LanderError> {
    if a.dimensions() != b.dimensions() || a.width() == 0 || a.height() == 0 {
        return Err(LanderError::Images(format!(
            "the images must be the same non-empty size ({:?} against {:?})",
            a.dimensions(),
            b.dimensions()
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Cahv;
    use nalgebra::{Point3, Vector3};

    /// A textured image: a hash of the pixel, smooth enough to correlate.
    fn texture(w: u32, h: u32, shift: f64) -> GreyF32 {
        GreyF32::from_fn(w, h, |x, y| {
            let u = x as f64 + shift;
            let v = y as f64;
            Luma([
                (1000.0 + 300.0 * (0.31 * u).sin() * (0.23 * v).cos() + 200.0 * (0.17 * u + 0.11 * v).sin())
                    as f32,
            ])
        })
    }

    fn pair(size: usize, baseline: f64) -> StereoRig {
        let f = 400.0;
        let c = 0.5 * (size as f64 - 1.0);
        let make = |x: f64| {
            Cahv::from_intrinsics(
                Vector3::new(x, 0.0, 0.0),
                Vector3::z(),
                Vector3::x(),
                f,
                f,
                c,
                c,
                size,
                size,
            )
        };
        StereoRig::new(make(0.0), make(baseline)).unwrap()
    }

    #[test]
    fn the_largest_region_and_its_box_centre() {
        let mut mask = Grey8::new(40, 30);
        // A 3-pixel blob, a 12-pixel L shape (8-connected through a diagonal), one lone pixel.
        for (x, y) in [(1, 1), (2, 1), (1, 2)] {
            mask.put_pixel(x, y, Luma([255]));
        }
        for (x, y) in [
            (10, 10),
            (11, 10),
            (12, 10),
            (13, 10),
            (14, 11),
            (15, 12),
            (15, 13),
            (15, 14),
            (15, 15),
            (15, 16),
            (15, 17),
            (15, 18),
        ] {
            mask.put_pixel(x, y, Luma([255]));
        }
        mask.put_pixel(30, 25, Luma([255]));
        let r = largest_region(&mask).unwrap();
        assert_eq!((r.x_min, r.x_max, r.y_min, r.y_max, r.pixels.len()), (10, 15, 10, 18, 12));
        assert!(r.pixels.contains(&(14, 11)) && !r.pixels.contains(&(1, 1)));
        assert_eq!(r.centre(), Point2::new(12.5, 14.0));
        assert!(largest_region(&Grey8::new(5, 5)).is_none());
    }

    #[test]
    fn a_moved_patch_is_found_and_triangulated_by_the_formula() {
        let (size, baseline, disparity) = (160usize, 0.2, 12.0);
        let rig = pair(size, baseline);
        // The "rover": a bright square that moves between the left images; the right image is
        // the left one shifted by a known disparity.
        let before = texture(size as u32, size as u32, 0.0);
        let mut after_left = before.clone();
        let mut after_right = texture(size as u32, size as u32, disparity);
        for y in 60..90u32 {
            for x in 70..110u32 {
                let v = 2500.0 + 8.0 * ((x * x * 7 + y * 13 + x * y * 5) % 97) as f32;
                after_left.put_pixel(x, y, Luma([v]));
                after_right.put_pixel(x - disparity as u32, y, Luma([v]));
            }
        }
        let d = detect_rover(&rig, &before, &after_left, &after_right, &DetectParams::default()).unwrap();
        assert_eq!((d.region.x_min, d.region.x_max, d.region.y_min, d.region.y_max), (70, 109, 60, 89));
        assert!((d.disparity - disparity).abs() < 0.05, "{}", d.disparity);
        // z = f b / d, and the point lies on the pixel's ray at that depth.
        let z = 400.0 * baseline / disparity;
        assert!((d.depth_m - z).abs() < 0.01 * z);
        let c = 0.5 * (size as f64 - 1.0);
        let expected = Point3::new((d.pixel.x - c) * z / 400.0, (d.pixel.y - c) * z / 400.0, z);
        assert!((d.point - expected).norm() < 0.01 * z, "{:?} against {expected:?}", d.point);
    }

    #[test]
    fn no_change_and_bad_input_are_errors() {
        let rig = pair(64, 0.2);
        let a = texture(64, 64, 0.0);
        let p = DetectParams::default();
        assert!(matches!(detect_rover(&rig, &a, &a, &a, &p), Err(LanderError::NoChange { .. })));
        let small = texture(32, 64, 0.0);
        assert!(matches!(detect_rover(&rig, &a, &small, &a, &p), Err(LanderError::Images(_))));
        let bad = DetectParams { threshold_sigmas: 0.0, ..p };
        assert!(matches!(detect_rover(&rig, &a, &a, &a, &bad), Err(LanderError::Parameter(_))));
    }
}
