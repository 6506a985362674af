//! Disparity accuracy against a ground-truth disparity map, as the Middlebury benchmark
//! counts it (Scharstein and Szeliski, IJCV 47, 2002, section 5.1): a pixel is bad when its
//! error exceeds 1 px; here a pixel left invalid is bad too.

use super::{Disparity, is_valid};

/// Accuracy figures over the pixels whose true disparity is known.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct DisparityScore {
    /// Pixels with a known true disparity.
    pub known_pixels: usize,
    /// Among them, the fraction left invalid or wrong by more than `bad_threshold_px`.
    pub bad_pixel_fraction: f64,
    /// Among them, the fraction with a valid disparity.
    pub valid_fraction: f64,
    /// Mean absolute error (px) over the valid pixels with a known truth.
    pub mean_abs_error_px: f64,
    /// The error above which a valid pixel is bad (px).
    pub bad_threshold_px: f64,
}

/// Scores `disp` against `truth` (same size, row-major; a negative value marks an unknown
/// true disparity). `None` when the sizes differ.
pub fn score_against_truth(disp: &Disparity, truth: &[f32], bad_threshold_px: f64) -> Option<DisparityScore> {
    if truth.len() != disp.data.len() {
        return None;
    }
    let (mut known, mut bad, mut valid, mut abs_sum) = (0usize, 0usize, 0usize, 0f64);
    for (&d, &t) in disp.data.iter().zip(truth) {
        if t < 0.0 {
            continue;
        }
        known += 1;
        if is_valid(d) {
            valid += 1;
            let e = f64::from((d - t).abs());
            abs_sum += e;
            if e > bad_threshold_px {
                bad += 1;
            }
        } else {
            bad += 1;
        }
    }
    let frac = |n: usize| if known == 0 { 0.0 } else { n as f64 / known as f64 };
    Some(DisparityScore {
        known_pixels: known,
        bad_pixel_fraction: frac(bad),
        valid_fraction: frac(valid),
        mean_abs_error_px: if valid == 0 { 0.0 } else { abs_sum / valid as f64 },
        bad_threshold_px,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stereo::INVALID_DISPARITY;

    #[test]
    fn counts_invalid_and_far_pixels_as_bad() {
        let disp = Disparity { width: 5, height: 1, data: vec![1.0, 2.0, INVALID_DISPARITY, 7.5, 3.0] };
        let truth = [1.5, 4.0, 3.0, 7.0, -1.0];
        let s = score_against_truth(&disp, &truth, 1.0).unwrap();
        assert_eq!(s.known_pixels, 4);
        assert_eq!(s.bad_pixel_fraction, 0.5);
        assert_eq!(s.valid_fraction, 0.75);
        assert!((s.mean_abs_error_px - 1.0).abs() < 1e-12);
        assert!(score_against_truth(&disp, &truth[..3], 1.0).is_none());
    }
}
