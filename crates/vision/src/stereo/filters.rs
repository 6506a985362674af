//! Post-processing of a disparity map: every filter here rejects pixels (sets them to
//! [`INVALID_DISPARITY`]) or smooths valid ones; none invents a disparity where there was none.
//!
//! - Left-right consistency (Hirschmüller 2008, section 3.4): the left disparity d at x must
//!   agree with the right image's disparity at x - d; occluded pixels and mismatches fail.
//! - Texture: a pixel whose matching window has almost no intensity variation has no reliable
//!   match (the JPL correlators' texture filter; Goldberg, Maimone and Matthies, "Stereo vision
//!   and rover navigation software for planetary exploration", IEEE Aerospace 2002).
//! - A 3x3 median of the valid disparities (Hirschmüller 2008, section 4.3).
//! - Speckle removal (section 4.3): 4-connected segments whose neighbouring disparities differ
//!   by at most a step, smaller than a size, are outliers.
//!
//! [`fill_from_background`] is the exception, kept apart from the matcher: it guesses the
//! invalid pixels for benchmarks that score every pixel (section 4.4 of the paper). It fills
//! each run of invalid pixels in a row with the smaller (background) of the two valid
//! disparities bounding it; the paper fills only occlusions that way and interpolates
//! mismatches from 16 directions, a refinement not done here.

use rayon::prelude::*;

use super::census::{HALF_H, HALF_W};
use super::{INVALID_DISPARITY, is_valid};

/// Keeps the left disparities that the right image's disparities confirm within `tolerance`
/// (the right disparity at the nearest pixel to x - d).
pub fn left_right_check(left: &[f32], right: &[f32], w: usize, tolerance: f32) -> Vec<f32> {
    let mut out = left.to_vec();
    out.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, d) in row.iter_mut().enumerate() {
            if !is_valid(*d) {
                continue;
            }
            let xr = (x as f32 - *d).round();
            let ok = xr >= 0.0 && {
                let dr = right[y * w + xr as usize];
                is_valid(dr) && (dr - *d).abs() <= tolerance
            };
            if !ok {
                *d = INVALID_DISPARITY;
            }
        }
    });
    out
}

/// Rejects pixels whose census window (clipped to the image) has an intensity standard
/// deviation below `min_std` (same scale as `img`).
pub fn reject_textureless(disp: &mut [f32], img: &[f32], w: usize, h: usize, min_std: f32) {
    // Integral images of I and I^2 with a zero first row and column.
    let (iw, ih) = (w + 1, h + 1);
    let mut s1 = vec![0f64; iw * ih];
    let mut s2 = vec![0f64; iw * ih];
    for y in 0..h {
        let (mut r1, mut r2) = (0f64, 0f64);
        for x in 0..w {
            let v = f64::from(img[y * w + x]);
            r1 += v;
            r2 += v * v;
            s1[(y + 1) * iw + x + 1] = s1[y * iw + x + 1] + r1;
            s2[(y + 1) * iw + x + 1] = s2[y * iw + x + 1] + r2;
        }
    }
    let box_sum = |s: &[f64], x0: usize, y0: usize, x1: usize, y1: usize| {
        s[y1 * iw + x1] - s[y0 * iw + x1] - s[y1 * iw + x0] + s[y0 * iw + x0]
    };
    let min_var = f64::from(min_std).powi(2);
    disp.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        let (y0, y1) = (y.saturating_sub(HALF_H), (y + HALF_H + 1).min(h));
        for (x, d) in row.iter_mut().enumerate() {
            let (x0, x1) = (x.saturating_sub(HALF_W), (x + HALF_W + 1).min(w));
            let n = ((x1 - x0) * (y1 - y0)) as f64;
            let mean = box_sum(&s1, x0, y0, x1, y1) / n;
            let var = box_sum(&s2, x0, y0, x1, y1) / n - mean * mean;
            if var < min_var {
                *d = INVALID_DISPARITY;
            }
        }
    });
}

/// The median of the valid disparities in each valid pixel's 3x3 neighbourhood (invalid
/// pixels stay invalid; an even count takes the mean of the two middle values).
pub fn median3(disp: &[f32], w: usize, h: usize) -> Vec<f32> {
    let mut out = disp.to_vec();
    out.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        let mut v = Vec::with_capacity(9);
        for (x, o) in row.iter_mut().enumerate() {
            if !is_valid(*o) {
                continue;
            }
            v.clear();
            for yy in y.saturating_sub(1)..(y + 2).min(h) {
                for xx in x.saturating_sub(1)..(x + 2).min(w) {
                    let d = disp[yy * w + xx];
                    if is_valid(d) {
                        v.push(d);
                    }
                }
            }
            v.sort_by(f32::total_cmp);
            let n = v.len();
            *o = if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) };
        }
    });
    out
}

/// Invalidates the 4-connected segments (neighbours differing by at most `step`) of fewer
/// than `min_size` valid pixels.
pub fn remove_speckles(disp: &mut [f32], w: usize, h: usize, min_size: usize, step: f32) {
    let mut seen = vec![false; w * h];
    let mut stack = Vec::new();
    let mut segment = Vec::new();
    for start in 0..w * h {
        if seen[start] || !is_valid(disp[start]) {
            continue;
        }
        seen[start] = true;
        stack.push(start);
        segment.clear();
        while let Some(p) = stack.pop() {
            segment.push(p);
            let (x, y) = (p % w, p / w);
            let neighbours = [
                (x > 0).then(|| p - 1),
                (x + 1 < w).then(|| p + 1),
                (y > 0).then(|| p - w),
                (y + 1 < h).then(|| p + w),
            ];
            for q in neighbours.into_iter().flatten() {
                if !seen[q] && is_valid(disp[q]) && (disp[q] - disp[p]).abs() <= step {
                    seen[q] = true;
                    stack.push(q);
                }
            }
        }
        if segment.len() < min_size {
            for &p in &segment {
                disp[p] = INVALID_DISPARITY;
            }
        }
    }
}

/// Fills every run of invalid pixels in a row with the smaller of the valid disparities at its
/// two ends (the one end inside the image at a border); rows without a valid pixel stay invalid.
pub fn fill_from_background(disp: &mut [f32], w: usize) {
    disp.par_chunks_mut(w).for_each(|row| {
        let mut x = 0;
        while x < row.len() {
            if is_valid(row[x]) {
                x += 1;
                continue;
            }
            let start = x;
            while x < row.len() && !is_valid(row[x]) {
                x += 1;
            }
            let before = start.checked_sub(1).map(|i| row[i]);
            let after = row.get(x).copied();
            let fill = match (before, after) {
                (Some(a), Some(b)) => a.min(b),
                (Some(v), None) | (None, Some(v)) => v,
                (None, None) => INVALID_DISPARITY,
            };
            row[start..x].fill(fill);
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    const X: f32 = INVALID_DISPARITY;

    #[test]
    fn left_right_check_rejects_disagreement() {
        // Left pixel 3 at d = 2 matches right pixel 1 (d = 2: kept); left pixel 4 at d = 1
        // matches right pixel 3 (d = 3: rejected); left pixel 0 at d = 1 leaves the image.
        let left = [1.0, 1.0, 0.0, 2.0, 1.0];
        let right = [1.0, 2.0, 0.0, 3.0, 0.0];
        assert_eq!(left_right_check(&left, &right, 5, 1.0), vec![X, 1.0, 0.0, 2.0, X]);
    }

    #[test]
    fn speckles_below_the_size_go_and_larger_segments_stay() {
        // A 2-pixel island at 9 inside a 5x3 plane at 1: removed at size 3, kept at size 2.
        let mut d = vec![1.0; 15];
        d[6] = 9.0;
        d[7] = 9.2;
        let mut a = d.clone();
        remove_speckles(&mut a, 5, 3, 3, 1.0);
        assert_eq!((a[6], a[7], a[0]), (X, X, 1.0));
        let mut b = d.clone();
        remove_speckles(&mut b, 5, 3, 2, 1.0);
        assert_eq!(b, d);
    }

    #[test]
    fn fill_takes_the_background_side() {
        let mut d = vec![X, 3.0, X, X, 8.0, 9.0, X, X, X, X, X];
        fill_from_background(&mut d[..8], 8);
        assert_eq!(&d[..8], &[3.0, 3.0, 3.0, 3.0, 8.0, 9.0, 9.0, 9.0]);
        fill_from_background(&mut d[8..], 3);
        assert_eq!(&d[8..], &[X, X, X]);
    }

    #[test]
    fn median_removes_a_lone_outlier_and_keeps_holes() {
        let mut d = vec![4.0; 9];
        d[4] = 40.0;
        d[0] = X;
        let m = median3(&d, 3, 3);
        assert_eq!(m[4], 4.0);
        assert_eq!(m[0], X);
    }

    #[test]
    fn flat_windows_are_rejected_and_textured_ones_kept() {
        let (w, h) = (30, 10);
        // Left half flat, right half a checkerboard of amplitude 10.
        let img: Vec<f32> = (0..w * h)
            .map(|i| if i % w < 15 { 50.0 } else { 50.0 + 10.0 * ((i % w + i / w) % 2) as f32 })
            .collect();
        let mut d = vec![5.0; w * h];
        reject_textureless(&mut d, &img, w, h, 1.0);
        assert_eq!(d[5 * w + 3], X);
        assert_eq!(d[5 * w + 25], 5.0);
    }
}
