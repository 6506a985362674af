//! Stereo correlation: a rectified pair of images to a disparity map, and disparity to range.
//!
//! The matcher is semi-global matching (H. Hirschmüller, "Stereo processing by semiglobal
//! matching and mutual information", IEEE PAMI 30(2), 2008) on a census matching cost
//! (R. Zabih and J. Woodfill, ECCV 1994; Hirschmüller and Scharstein, "Evaluation of stereo
//! matching costs on images with radiometric differences", PAMI 31(9), 2009, found census the
//! most robust cost for SGM). The steps, each in its own file:
//! 1. [`census`]: a 9x7 census transform of both images and the matching cost volume
//!    C(p, d) = Hamming distance (0..62), stored as `u8`.
//! 2. [`sgm`]: cost aggregation along 8 paths (section 3.3 of the paper, equation 13), P2
//!    adapted to the intensity step along the path; winner-take-all for the left image and, from
//!    the same matching costs aggregated for the right image, for the right one (section 3.4);
//!    a parabola through the aggregated costs at d-1, d, d+1 for the subpixel disparity; a
//!    uniqueness ratio.
//! 3. [`filters`]: the left-right consistency check (section 3.4), a texture filter, a 3x3 median of the valid disparities and speckle removal (section 4.3
//!    of the paper: small connected segments of similar disparity are outliers).
//! 4. [`range`]: disparity to 3-D points, range and Matthies' range uncertainty for a
//!    rectified linear (CAHV) pair, and conversion to the navigators' point cloud.
//!
//! Departures from the paper, with their reasons:
//! - Census instead of hierarchical mutual information: as robust to the radiometric
//!   differences between two cameras, and it needs no initial disparity (one pass, no pyramid).
//! - P2 = max(P1, P2' g / (g + |ΔI|)) instead of P2'/|ΔI|: the paper's form is unbounded at
//!   ΔI = 0 and halves at ΔI = 2 grey levels, which camera noise alone reaches; the gradient
//!   scale g sets the step that halves P2.
//! - Pixels are rejected, never guessed: invalidated pixels (occlusions, mismatches, low
//!   texture, speckles) stay invalid ([`INVALID_DISPARITY`]) and the paper's interpolation of
//!   invalid disparities (section 4.4) is not part of the matcher, because the navigators need
//!   only measured range, and an interpolated range across an occlusion invents terrain. A
//!   simpler fill ([`filters::fill_from_background`]) exists for benchmarks that score every
//!   pixel (`rovernav stereo --truth`).
//! - The right image's disparities come from its own aggregation of the same matching costs,
//!   not from the left image's aggregated costs along a diagonal (see [`sgm`] for why).
//! - Two rejections the paper does not have: a uniqueness ratio on the aggregated costs (a
//!   second minimum more than 1 px away nearly as low means an ambiguous match) and the JPL
//!   correlators' texture filter; both reject, neither guesses.
//! - Intensities are scaled so both images' 99.9th percentile is 255 before the P2
//!   adaptation and the texture filter, so their thresholds hold for 8- to 16-bit data.
//! - The aggregation runs as two sweeps (the 4 paths coming from above and the left, and the
//!   4 coming from below and the right), one per rayon task, each with its own `u16` sum
//!   volume; the cost volume and the per-pixel steps run in parallel across rows.

pub mod census;
pub mod filters;
pub mod range;
pub mod sgm;

mod score;

pub use range::{RangeImage, StereoRig};
pub use score::{DisparityScore, score_against_truth};

use crate::image::Grey16;

/// The marker of a pixel without a disparity (a rejected or unmatched pixel).
pub const INVALID_DISPARITY: f32 = -1.0;

/// Errors of stereo correlation and triangulation.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum StereoError {
    /// The two images differ in size.
    #[error("the left image is {left_w}x{left_h} but the right one is {right_w}x{right_h}")]
    SizeMismatch {
        /// Left width.
        left_w: u32,
        /// Left height.
        left_h: u32,
        /// Right width.
        right_w: u32,
        /// Right height.
        right_h: u32,
    },
    /// The cost volume would exceed the configured bound.
    #[error(
        "{width}x{height} pixels at {disparities} disparities is {cells} cost cells, over the limit of {limit}"
    )]
    TooLarge {
        /// Image width.
        width: u32,
        /// Image height.
        height: u32,
        /// Number of disparities searched.
        disparities: usize,
        /// width x height x disparities.
        cells: u64,
        /// [`StereoParams::max_volume_cells`].
        limit: u64,
    },
    /// A parameter is out of its range.
    #[error("stereo parameter {name}: {message}")]
    BadParameter {
        /// The parameter.
        name: &'static str,
        /// What is wrong with it.
        message: String,
    },
    /// A camera pair is not a rectified linear pair.
    #[error("stereo rig: {0}")]
    NotRectified(String),
}

/// Parameters of the matcher. [`StereoParams::default`] is tuned on Middlebury's Tsukuba and
/// Cones (see docs/vision.md) and suits 8- to 12-bit images.
#[derive(Clone, Debug, PartialEq)]
pub struct StereoParams {
    /// Largest disparity searched (pixels); disparities 0..=max_disparity are tried.
    pub max_disparity: usize,
    /// SGM penalty for a disparity change of one pixel between neighbours (cost units, 0..62).
    pub p1: u16,
    /// SGM penalty for a larger disparity change, before its adaptation to the intensity step.
    pub p2: u16,
    /// Intensity step (grey levels on a 0..255 scale) that halves P2.
    pub p2_gradient_scale: f32,
    /// A pixel whose best aggregated cost is not at least this fraction below the best cost at
    /// a disparity more than one pixel away is rejected (0 disables).
    pub uniqueness: f32,
    /// Largest difference (pixels) between the left disparity and the right image's disparity
    /// at the matching pixel; more is an occlusion or a mismatch.
    pub lr_tolerance: f32,
    /// Pixels whose census window has an intensity standard deviation below this (grey levels
    /// on a 0..255 scale) are rejected as textureless (0 disables).
    pub min_texture: f32,
    /// Connected regions (4-neighbours differing by at most `speckle_step`) smaller than this
    /// many pixels are rejected (0 disables).
    pub speckle_size: usize,
    /// Largest disparity step (pixels) inside one speckle region.
    pub speckle_step: f32,
    /// Apply a 3x3 median to the valid disparities.
    pub median: bool,
    /// Bound on width x height x disparities: the matcher holds up to 6 bytes per cell (the
    /// default, 10^8, is 600 MB: a 1024x1024 image at up to 95 disparities).
    pub max_volume_cells: u64,
}

impl Default for StereoParams {
    fn default() -> Self {
        Self {
            max_disparity: 63,
            p1: 20,
            p2: 150,
            p2_gradient_scale: 8.0,
            uniqueness: 0.05,
            lr_tolerance: 1.0,
            min_texture: 1.0,
            speckle_size: 60,
            speckle_step: 1.0,
            median: true,
            max_volume_cells: 100_000_000,
        }
    }
}

impl StereoParams {
    /// Checks the parameters' ranges.
    pub fn validate(&self) -> Result<(), StereoError> {
        let bad = |name, message: &str| Err(StereoError::BadParameter { name, message: message.into() });
        if self.max_disparity == 0 || self.max_disparity > 1024 {
            return bad("max_disparity", "must be 1..=1024");
        }
        if self.p1 == 0 || self.p2 < self.p1 || self.p2 > 1000 {
            return bad("p1/p2", "need 0 < p1 <= p2 <= 1000");
        }
        if !(self.p2_gradient_scale.is_finite() && self.p2_gradient_scale > 0.0) {
            return bad("p2_gradient_scale", "must be positive");
        }
        if !(0.0..1.0).contains(&self.uniqueness) {
            return bad("uniqueness", "must be in [0, 1)");
        }
        let non_negative = |v: f32| v.is_finite() && v >= 0.0;
        if ![self.lr_tolerance, self.speckle_step, self.min_texture].into_iter().all(non_negative) {
            return bad("lr_tolerance/speckle_step/min_texture", "must be non-negative numbers");
        }
        Ok(())
    }

    /// Number of disparities searched.
    pub fn disparities(&self) -> usize {
        self.max_disparity + 1
    }
}

/// A disparity map of the left image: `data[y * width + x]` is the disparity in pixels of the
/// left pixel (x, y) (its match in the right image is at x - d), or [`INVALID_DISPARITY`].
#[derive(Clone, Debug, PartialEq)]
pub struct Disparity {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Row-major disparities.
    pub data: Vec<f32>,
}

impl Disparity {
    /// The disparity at (x, y), `None` when invalid.
    pub fn get(&self, x: usize, y: usize) -> Option<f32> {
        let d = self.data[y * self.width + x];
        is_valid(d).then_some(d)
    }

    /// Fraction of the pixels with a valid disparity.
    pub fn valid_fraction(&self) -> f64 {
        if self.data.is_empty() {
            return 0.0;
        }
        self.data.iter().filter(|&&d| is_valid(d)).count() as f64 / self.data.len() as f64
    }
}

/// Whether a disparity value is valid (not [`INVALID_DISPARITY`]).
pub fn is_valid(d: f32) -> bool {
    d >= 0.0
}

/// Correlates a rectified pair (left image as reference): the disparity of every left pixel,
/// invalid where a filter rejected it.
pub fn compute_disparity(
    left: &Grey16,
    right: &Grey16,
    params: &StereoParams,
) -> Result<Disparity, StereoError> {
    params.validate()?;
    if left.dimensions() != right.dimensions() {
        return Err(StereoError::SizeMismatch {
            left_w: left.width(),
            left_h: left.height(),
            right_w: right.width(),
            right_h: right.height(),
        });
    }
    let (w, h) = (left.width() as usize, left.height() as usize);
    let nd = params.disparities();
    let cells = w as u64 * h as u64 * nd as u64;
    if cells > params.max_volume_cells {
        return Err(StereoError::TooLarge {
            width: left.width(),
            height: left.height(),
            disparities: nd,
            cells,
            limit: params.max_volume_cells,
        });
    }
    if w == 0 || h == 0 {
        return Ok(Disparity { width: w, height: h, data: Vec::new() });
    }
    let (left8, right8) = census::normalise_pair(left, right);
    let costs = census::cost_volume(&left8, &right8, w, h, nd);
    let left_disp = {
        let sums = sgm::aggregate(&costs, &left8, w, h, nd, params);
        sgm::winner_take_all(&sums, w, h, nd, params.uniqueness, sgm::Reference::Left)
    };
    let right_disp = {
        let costs = sgm::right_costs(&costs, w, h, nd);
        let sums = sgm::aggregate(&costs, &right8, w, h, nd, params);
        sgm::winner_take_all(&sums, w, h, nd, 0.0, sgm::Reference::Right)
    };
    drop(costs);
    let mut data = filters::left_right_check(&left_disp, &right_disp, w, params.lr_tolerance);
    if params.min_texture > 0.0 {
        filters::reject_textureless(&mut data, &left8, w, h, params.min_texture);
    }
    if params.median {
        data = filters::median3(&data, w, h);
    }
    if params.speckle_size > 0 {
        filters::remove_speckles(&mut data, w, h, params.speckle_size, params.speckle_step);
    }
    Ok(Disparity { width: w, height: h, data })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A random-texture image and its copy shifted left by `shift` pixels (the right view of a
    /// fronto-parallel plane at disparity `shift`).
    fn shifted_pair(w: u32, h: u32, shift: u32) -> (Grey16, Grey16) {
        let value = |x: u32, y: u32| ((x.wrapping_mul(2654435761) ^ y.wrapping_mul(40503)) % 4096) as u16;
        let left = Grey16::from_fn(w, h, |x, y| image::Luma([value(x / 2, y / 2)]));
        let right = Grey16::from_fn(w, h, |x, y| image::Luma([value((x + shift) / 2, y / 2)]));
        (left, right)
    }

    #[test]
    fn a_shifted_texture_gives_its_shift() {
        let (left, right) = shifted_pair(80, 40, 8);
        let params = StereoParams { max_disparity: 20, ..StereoParams::default() };
        let disp = compute_disparity(&left, &right, &params).unwrap();
        let interior: Vec<f32> =
            (0..40).flat_map(|y| (12..76).map(move |x| (x, y))).map(|(x, y)| disp.data[y * 80 + x]).collect();
        let valid: Vec<f32> = interior.iter().copied().filter(|&d| is_valid(d)).collect();
        assert!(valid.len() as f64 > 0.95 * interior.len() as f64, "{} of {}", valid.len(), interior.len());
        assert!(valid.iter().all(|&d| (d - 8.0).abs() < 0.5), "{valid:?}");
    }

    #[test]
    fn images_smaller_than_the_window_do_not_panic() {
        for (w, h) in [(1, 1), (2, 1), (1, 5), (5, 3), (0, 0)] {
            let (left, right) = shifted_pair(w, h, 1);
            let disp = compute_disparity(&left, &right, &StereoParams::default()).unwrap();
            assert_eq!(disp.data.len(), (w * h) as usize);
            assert!(disp.data.iter().all(|&d| d == INVALID_DISPARITY || (0.0..=63.0).contains(&d)));
        }
    }

    #[test]
    fn bad_sizes_are_refused_before_allocating() {
        let (left, right) = shifted_pair(40, 30, 2);
        let small = Grey16::new(40, 29);
        assert!(matches!(
            compute_disparity(&left, &small, &StereoParams::default()),
            Err(StereoError::SizeMismatch { right_h: 29, .. })
        ));
        let params = StereoParams { max_volume_cells: 40 * 30 * 63, ..StereoParams::default() };
        let err = compute_disparity(&left, &right, &params).unwrap_err();
        assert!(matches!(err, StereoError::TooLarge { cells: 76800, .. }), "{err}");
        let zero = StereoParams { max_disparity: 0, ..StereoParams::default() };
        assert!(matches!(compute_disparity(&left, &right, &zero), Err(StereoError::BadParameter { .. })));
    }
}
