//! Dust-devil detection in a sequence from a fixed camera (paper 003 section 5.2): "a
//! preprocessing step to reduce image noise followed by an image averaging. The difference
//! between the average image and the input or test image is then computed. Noise effects are
//! removed from the difference image and blob detection is performed on the remaining
//! differences. A buffered bounding box is formed around each detection to ensure that the
//! full dust devil is captured."
//!
//! The steps, each as the paper orders them (the parameters are rovernav's):
//! 1. Noise reduction: block means to the working size, a 3x3 median (dead and hot pixels),
//!    then a 3x3 box mean. A block-compressed sequence ([`crate::deblock`] finds the 8x8 grid
//!    in its first frame) is worked on one pixel per codec block instead: the blocks' trimmed
//!    means, what the quantiser keeps, so the block edges are no motion; its differences are
//!    mostly exactly 0, so their noise is a trimmed RMS, not a median absolute value, and its
//!    blobs need `block_min_score` (fewer, larger pixels).
//! 2. Average image: the per-pixel median of the frames, after each frame is scaled to the
//!    sequence's median brightness. Departures: the median instead of the mean, because a dust
//!    devil present in many frames leaves a ghost in the mean that every frame without it then
//!    shows as a difference (on rendered sets this cut false positives by about half); the
//!    scaling, so an exposure change between frames is not an event.
//! 3. Differences: each frame minus the average.
//! 4. Noise removal: the differences in units of the local noise sd (a robust sd per block of
//!    the image over all frames, so the bright sky and the dark ground each get theirs); pixels
//!    above `low_sigma` that are connected to one above `high_sigma` are kept (hysteresis);
//!    blobs smaller than `min_area` working pixels, or larger than `max_area_fraction` of the
//!    image (a global change, not a dust devil), are dropped.
//! 5. Blob detection: 8-connected components (imageproc); a blob's score is its summed
//!    significance over the square root of its area (the matched-filter signal-to-noise ratio).
//! 6. Buffered bounding box: the blob's box grown by `buffer` of its size on each side (at least
//!    `min_buffer_px` full-resolution pixels) and clipped; overlapping boxes of a frame merge.

use image::{GrayImage, Luma};
use imageproc::region_labelling::{Connectivity, connected_components};
use rayon::prelude::*;
use rovernav_vision::image::GreyF32;
use serde::Serialize;

use crate::ScienceError;
use crate::deblock::{BLOCK, block_means, find_block_grid};
use crate::plane::{Plane, factor_for, quantile, robust_sigma};

/// Parameters of the dust-devil detector.
#[derive(Clone, Debug, PartialEq)]
pub struct DustDevilParams {
    /// Longer side of the working image (pixels).
    pub max_side: usize,
    /// Seed threshold of a blob (noise sds).
    pub high_sigma: f32,
    /// Growing threshold of a blob (noise sds).
    pub low_sigma: f32,
    /// Smallest blob (working pixels).
    pub min_area: usize,
    /// Largest blob as a fraction of the image.
    pub max_area_fraction: f32,
    /// Smallest score kept.
    pub min_score: f32,
    /// Smallest score kept in a block-compressed sequence (worked on one pixel per block).
    pub block_min_score: f32,
    /// Box growth on each side, as a fraction of the blob's width or height.
    pub buffer: f32,
    /// Smallest box growth (full-resolution pixels).
    pub min_buffer_px: u32,
    /// Brightness bins of the noise model.
    pub noise_bins: usize,
}

impl Default for DustDevilParams {
    fn default() -> Self {
        Self {
            max_side: 384,
            high_sigma: 5.0,
            low_sigma: 2.5,
            min_area: 4,
            max_area_fraction: 0.2,
            min_score: 24.0,
            block_min_score: 12.0,
            buffer: 0.5,
            min_buffer_px: 8,
            noise_bins: 16,
        }
    }
}

/// One buffered bounding box (full-resolution pixels) with its score.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct DustDevilBox {
    /// Left column.
    pub x: u32,
    /// Top row.
    pub y: u32,
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// Matched-filter signal-to-noise ratio of the blob.
    pub score: f32,
}

/// The detections of one frame.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FrameDetections {
    /// Index of the frame in the sequence.
    pub frame: usize,
    /// Buffered boxes, best score first.
    pub boxes: Vec<DustDevilBox>,
}

/// Fewest frames the average needs (the paper's sequences had 6 to 20).
pub const MIN_FRAMES: usize = 3;

/// Detects dust devils in a sequence of frames of one fixed camera.
pub fn detect_dust_devils(
    frames: &[GreyF32],
    params: &DustDevilParams,
) -> Result<Vec<FrameDetections>, ScienceError> {
    if frames.len() < MIN_FRAMES {
        return Err(ScienceError::TooFewFrames { frames: frames.len(), min: MIN_FRAMES });
    }
    let (w, h) = frames[0].dimensions();
    for (index, f) in frames.iter().enumerate() {
        let (fw, fh) = f.dimensions();
        if fw == 0 || fh == 0 {
            return Err(ScienceError::Empty { index, width: fw, height: fh });
        }
        if (fw, fh) != (w, h) {
            return Err(ScienceError::SizeMismatch { index, width: fw, height: fh, width0: w, height0: h });
        }
    }
    let factor = factor_for(w, h, params.max_side);
    // 1. Noise reduction. Block-compressed frames (one fixed camera's frames share the codec's
    //    grid, found in the first frame) are worked on one pixel per block: the blocks' trimmed
    //    means, what a coarse quantiser keeps.
    let grid = find_block_grid(&frames[0]);
    let (factor, shift) = match &grid {
        Some(g) => (BLOCK, ((BLOCK - g.offset_x) % BLOCK, (BLOCK - g.offset_y) % BLOCK)),
        None => (factor, (0, 0)),
    };
    let mut planes: Vec<Plane> = frames
        .par_iter()
        .map(|f| match &grid {
            Some(g) => block_means(f, g),
            None => Plane::prepared(f, factor).box_mean(1),
        })
        .collect();
    let (pw, ph) = (planes[0].width, planes[0].height);
    // 2. Brightness normalisation and the average image.
    let medians: Vec<f32> = planes.iter().map(|p| quantile(p.data.iter().copied(), 0.5)).collect();
    let reference = quantile(medians.iter().copied(), 0.5);
    for (p, m) in planes.iter_mut().zip(&medians) {
        if *m > 0.0 && reference > 0.0 {
            let s = reference / m;
            p.data.iter_mut().for_each(|v| *v *= s);
        }
    }
    let average: Vec<f32> = (0..pw * ph)
        .into_par_iter()
        .map(|i| {
            let mut v: Vec<f32> = planes.iter().map(|p| p.data[i]).collect();
            let mid = v.len() / 2;
            let (_, m, _) = v.select_nth_unstable_by(mid, f32::total_cmp);
            *m
        })
        .collect();
    // 3. Differences.
    let diffs: Vec<Vec<f32>> =
        planes.iter().map(|p| p.data.iter().zip(&average).map(|(a, b)| a - b).collect()).collect();
    // 4. Noise as a function of brightness (shot noise grows with the signal): robust sd of the
    //    differences of all frames in brightness bins of the average image.
    let sd_of = noise_by_level(&average, &diffs, params.noise_bins.max(1), grid.is_some());
    let min_score = if grid.is_some() { params.block_min_score } else { params.min_score };
    let max_area = (params.max_area_fraction * (pw * ph) as f32) as usize;
    let out = diffs
        .par_iter()
        .enumerate()
        .map(|(frame, d)| {
            let z: Vec<f32> = (0..pw * ph).map(|i| d[i].abs() / sd_of(average[i])).collect();
            let boxes = blobs(&z, pw, ph, params, min_score, max_area)
                .into_iter()
                .map(|(x0, y0, x1, y1, score)| buffered(x0, y0, x1, y1, score, factor, shift, w, h, params))
                .collect();
            FrameDetections { frame, boxes: merge(boxes) }
        })
        .collect();
    Ok(out)
}

/// The noise sd of a difference as a function of the average brightness: equal-count bins of
/// the average, a robust sd of the differences in each (over every frame), monotone
/// non-decreasing with brightness (shot noise), floored at a quarter of the median bin's.
fn noise_by_level(average: &[f32], diffs: &[Vec<f32>], bins: usize, quantised: bool) -> impl Fn(f32) -> f32 {
    let mut order: Vec<usize> = (0..average.len()).collect();
    order.sort_by(|&a, &b| average[a].total_cmp(&average[b]));
    let per = order.len().div_ceil(bins).max(1);
    let mut edges = Vec::new();
    let mut sds = Vec::new();
    for chunk in order.chunks(per) {
        edges.push(average[*chunk.last().expect("chunks are not empty")]);
        let values = diffs.iter().flat_map(|d| chunk.iter().map(move |&i| d[i]));
        sds.push(if quantised { trimmed_rms(values) } else { robust_sigma(values) });
    }
    let median = quantile(sds.iter().copied(), 0.5);
    let floor = (0.25 * median).max(1e-6);
    let mut run = floor;
    for s in sds.iter_mut() {
        run = run.max(*s);
        *s = run;
    }
    move |level: f32| {
        let k = edges.partition_point(|&e| e < level).min(sds.len() - 1);
        sds[k]
    }
}

/// The root mean square of the values without their largest 2 % (events): the noise sd of
/// quantised differences, most of which are exactly 0 (their median absolute value is no
/// measure).
fn trimmed_rms(values: impl IntoIterator<Item = f32>) -> f32 {
    let mut sq: Vec<f32> = values.into_iter().filter(|v| v.is_finite()).map(|v| v * v).collect();
    if sq.is_empty() {
        return 0.0;
    }
    let keep = (sq.len() * 49).div_ceil(50);
    sq.select_nth_unstable_by(keep - 1, f32::total_cmp);
    (sq[..keep].iter().map(|&v| v as f64).sum::<f64>() / keep as f64).sqrt() as f32
}

/// Blobs of a significance image: (x0, y0, x1, y1) inclusive working pixels and the score.
fn blobs(
    z: &[f32],
    pw: usize,
    ph: usize,
    params: &DustDevilParams,
    min_score: f32,
    max_area: usize,
) -> Vec<(usize, usize, usize, usize, f32)> {
    let mask = GrayImage::from_fn(pw as u32, ph as u32, |x, y| {
        Luma([if z[y as usize * pw + x as usize] > params.low_sigma { 255 } else { 0 }])
    });
    let labels = connected_components(&mask, Connectivity::Eight, Luma([0u8]));
    #[derive(Clone, Copy)]
    struct Acc {
        x0: usize,
        y0: usize,
        x1: usize,
        y1: usize,
        area: usize,
        sum: f32,
        peak: f32,
    }
    let mut acc: Vec<Option<Acc>> = Vec::new();
    for (x, y, l) in labels.enumerate_pixels() {
        let l = l.0[0] as usize;
        if l == 0 {
            continue;
        }
        if acc.len() <= l {
            acc.resize(l + 1, None);
        }
        let (x, y) = (x as usize, y as usize);
        let v = z[y * pw + x];
        let a = acc[l].get_or_insert(Acc { x0: x, y0: y, x1: x, y1: y, area: 0, sum: 0.0, peak: 0.0 });
        (a.x0, a.y0, a.x1, a.y1) = (a.x0.min(x), a.y0.min(y), a.x1.max(x), a.y1.max(y));
        a.area += 1;
        a.sum += v;
        a.peak = a.peak.max(v);
    }
    acc.into_iter()
        .flatten()
        .filter(|a| a.peak >= params.high_sigma && a.area >= params.min_area && a.area <= max_area)
        .map(|a| (a.x0, a.y0, a.x1, a.y1, a.sum / (a.area as f32).sqrt()))
        .filter(|b| b.4 >= min_score)
        .collect()
}

/// The buffered full-resolution box of a blob.
#[allow(clippy::too_many_arguments)]
fn buffered(
    x0: usize,
    y0: usize,
    x1: usize,
    y1: usize,
    score: f32,
    factor: usize,
    shift: (usize, usize),
    w: u32,
    h: u32,
    params: &DustDevilParams,
) -> DustDevilBox {
    let f = factor as f32;
    let (sx, sy) = (shift.0 as f32, shift.1 as f32);
    let (ax, ay) = ((x0 as f32 * f - sx).max(0.0), (y0 as f32 * f - sy).max(0.0));
    let (bx, by) = (((x1 + 1) as f32 * f - sx).min(w as f32), ((y1 + 1) as f32 * f - sy).min(h as f32));
    let grow = |size: f32| (params.buffer * size).max(params.min_buffer_px as f32);
    let (gx, gy) = (grow(bx - ax), grow(by - ay));
    let (px, py) = ((ax - gx).max(0.0) as u32, (ay - gy).max(0.0) as u32);
    let (qx, qy) = (((bx + gx) as u32).min(w), ((by + gy) as u32).min(h));
    DustDevilBox { x: px, y: py, width: qx - px, height: qy - py, score }
}

/// Merges overlapping boxes (the merged box covers both; its score is the larger); best first.
fn merge(mut boxes: Vec<DustDevilBox>) -> Vec<DustDevilBox> {
    let overlaps = |a: &DustDevilBox, b: &DustDevilBox| {
        a.x < b.x + b.width && b.x < a.x + a.width && a.y < b.y + b.height && b.y < a.y + a.height
    };
    let mut changed = true;
    while changed {
        changed = false;
        'outer: for i in 0..boxes.len() {
            for j in i + 1..boxes.len() {
                if overlaps(&boxes[i], &boxes[j]) {
                    let (a, b) = (boxes[i], boxes.swap_remove(j));
                    let (x, y) = (a.x.min(b.x), a.y.min(b.y));
                    let (qx, qy) = ((a.x + a.width).max(b.x + b.width), (a.y + a.height).max(b.y + b.height));
                    boxes[i] =
                        DustDevilBox { x, y, width: qx - x, height: qy - y, score: a.score.max(b.score) };
                    changed = true;
                    break 'outer;
                }
            }
        }
    }
    boxes.sort_by(|a, b| b.score.total_cmp(&a.score));
    boxes
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use rand_distr::StandardNormal;

    /// A fixed textured scene with 1 % noise; in frames listed in `devil`, a faint column of
    /// optical depth `c` (source 3000 DN) at x, rows `top..80`, half-width 3 px.
    fn sequence(frames: usize, devil: &[(usize, f32, f32)], c: f32, seed: u64) -> Vec<GreyF32> {
        let mut tex = ChaCha8Rng::seed_from_u64(99);
        let base: Vec<f32> = (0..240 * 180)
            .map(
                |i| if i / 240 < 70 { 2000.0 } else { 1200.0 * (1.0 + 0.3 * tex.random_range(-1.0f32..1.0)) },
            )
            .collect();
        (0..frames)
            .map(|k| {
                let mut rng = ChaCha8Rng::seed_from_u64(seed * 1000 + k as u64);
                GreyF32::from_fn(240, 180, |x, y| {
                    let mut v = base[(y * 240 + x) as usize];
                    for &(f, cx, top) in devil {
                        if f == k && (x as f32 - cx).abs() <= 3.0 && (y as f32) >= top && y < 80 {
                            v = v * (1.0 - c) + 3000.0 * c;
                        }
                    }
                    let z: f32 = rng.sample(StandardNormal);
                    image::Luma([v * (1.0 + 0.01 * z)])
                })
            })
            .collect()
    }

    #[test]
    fn a_sequence_without_events_gives_no_detection() {
        for seed in 0..3 {
            let seq = sequence(10, &[], 0.0, seed);
            let d = detect_dust_devils(&seq, &DustDevilParams::default()).unwrap();
            let total: usize = d.iter().map(|f| f.boxes.len()).sum();
            assert_eq!(total, 0, "seed {seed}: {d:?}");
        }
    }

    #[test]
    fn a_moving_faint_column_is_boxed_in_its_frames_only() {
        // Moves 12 px per frame through frames 2..6, 4 % contrast against the sky.
        let devil: Vec<(usize, f32, f32)> = (2..6).map(|k| (k, 40.0 + 12.0 * k as f32, 50.0)).collect();
        let seq = sequence(10, &devil, 0.04, 4);
        let d = detect_dust_devils(&seq, &DustDevilParams::default()).unwrap();
        for f in &d {
            let truth = devil.iter().find(|t| t.0 == f.frame);
            match truth {
                Some(&(_, cx, top)) => {
                    assert!(!f.boxes.is_empty(), "frame {} missed", f.frame);
                    let b = f.boxes[0];
                    assert!(b.x as f32 <= cx - 3.0 && (b.x + b.width) as f32 >= cx + 3.0, "{b:?} vs x {cx}");
                    assert!(b.y as f32 <= top && b.y + b.height >= 80, "{b:?} vs rows {top}..80");
                }
                None => assert!(f.boxes.is_empty(), "frame {}: {:?}", f.frame, f.boxes),
            }
        }
    }

    /// Each frame through the renderer's block codec at `quality`.
    fn compressed(seq: &[GreyF32], quality: u8) -> Vec<GreyF32> {
        seq.iter()
            .map(|f| {
                let mut dn: Vec<u16> =
                    f.as_raw().iter().map(|v| v.round().clamp(0.0, 4095.0) as u16).collect();
                rovernav_sim::render::sensor::compress(&mut dn, f.width() as usize, quality);
                GreyF32::from_fn(f.width(), f.height(), |x, y| {
                    image::Luma([dn[(y * f.width() + x) as usize] as f32])
                })
            })
            .collect()
    }

    #[test]
    fn block_compressed_sequences_keep_their_verdicts() {
        // Quality 75: block flips between frames are no event; a 10 % column still is.
        for seed in 0..3 {
            let seq = compressed(&sequence(10, &[], 0.0, seed), 75);
            let d = detect_dust_devils(&seq, &DustDevilParams::default()).unwrap();
            assert!(d.iter().all(|f| f.boxes.is_empty()), "seed {seed}: {d:?}");
        }
        let devil: Vec<(usize, f32, f32)> = (2..6).map(|k| (k, 40.0 + 24.0 * k as f32, 30.0)).collect();
        let seq = compressed(&sequence(10, &devil, 0.1, 4), 75);
        let d = detect_dust_devils(&seq, &DustDevilParams::default()).unwrap();
        for f in &d {
            match devil.iter().find(|t| t.0 == f.frame) {
                Some(&(_, cx, _)) => {
                    let b = f.boxes.first().unwrap_or_else(|| panic!("frame {} missed", f.frame));
                    assert!(b.x as f32 <= cx && (b.x + b.width) as f32 >= cx, "{b:?} vs x {cx}");
                }
                None => assert!(f.boxes.is_empty(), "frame {}: {:?}", f.frame, f.boxes),
            }
        }
    }

    #[test]
    fn exposure_changes_are_not_events_and_bad_input_is_an_error() {
        let mut seq = sequence(8, &[], 0.0, 7);
        for (k, f) in seq.iter_mut().enumerate() {
            let s = 1.0 + 0.05 * k as f32;
            f.pixels_mut().for_each(|p| p.0[0] *= s);
        }
        let d = detect_dust_devils(&seq, &DustDevilParams::default()).unwrap();
        assert!(d.iter().all(|f| f.boxes.is_empty()));
        assert!(matches!(
            detect_dust_devils(&seq[..2], &DustDevilParams::default()),
            Err(ScienceError::TooFewFrames { .. })
        ));
        seq[3] = GreyF32::new(10, 10);
        assert!(matches!(
            detect_dust_devils(&seq, &DustDevilParams::default()),
            Err(ScienceError::SizeMismatch { index: 3, .. })
        ));
    }
}
