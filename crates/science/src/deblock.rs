//! Block-compression artefacts: finding an 8x8 transform-coding grid in an image and removing
//! its block edges before the detectors look for variance or motion.
//!
//! A block codec (JPEG, the renderer's DCT quantiser) codes each 8x8 block on its own; at the
//! qualities used for downlink most of a smooth sky's AC coefficients quantise to zero, so the
//! sky comes back as a staircase of flat blocks whose steps (one DC quantisation step, about
//! 0.5 % of a 12-bit sky at quality 75) sit exactly on the grid. Those steps are what the
//! detectors' band-pass and frame differences would read as cloud variance or dust-devil motion.
//!
//! Detection: in every run of 8 neighbour differences along a row (column), the phase (column
//! or row modulo 8) of the largest one gets a vote; a grid shows as one phase with
//! [`GRID_RATIO`] times the other seven's median votes or more, in both directions. Votes
//! rather than summed differences, so a textured ground's large differences at every phase do
//! not drown the sky's small steps on the grid (Wang, Bovik and Evans, "Blind measurement of
//! blocking artifacts in images", ICIP 2000, measure blockiness from the same periodic peaks of
//! the difference signal).
//!
//! Removal: what survives a coarse quantiser reliably is each block's mean (its DC
//! coefficient); the image is replaced by the bilinear interpolation of the block means between
//! block centres, a smooth surface through the staircase. Departure from deblocking filters
//! (which keep detail inside blocks): the detectors need only structure larger than a block, and
//! the interpolated surface has no edge at the grid at all. The block means keep a
//! quantisation noise of about `step / sqrt(12)`, measured by the detectors from differences
//! one block apart.

use image::Luma;
use rovernav_vision::image::GreyF32;

use crate::plane::Plane;

/// Side of a transform-coding block (JPEG, the renderer's quantiser).
pub const BLOCK: usize = 8;

/// Smallest ratio of the grid phase's votes to the other phases' median that counts as a block
/// grid.
pub const GRID_RATIO: f32 = 1.5;

/// An 8x8 block grid found in an image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlockGrid {
    /// Column of the first block boundary (0..8): blocks start at columns `offset_x + 8 k`.
    pub offset_x: usize,
    /// Row of the first block boundary (0..8).
    pub offset_y: usize,
    /// The weaker direction's ratio of grid-phase votes to the other phases' median.
    pub strength: f32,
}

/// The 8x8 block grid of a block-compressed image, or `None` for an image without one.
pub fn find_block_grid(image: &GreyF32) -> Option<BlockGrid> {
    let (w, h) = (image.width() as usize, image.height() as usize);
    if w < 4 * BLOCK || h < 4 * BLOCK {
        return None;
    }
    let raw = image.as_raw();
    let at = |x: usize, y: usize| {
        let v = raw[y * w + x];
        if v.is_finite() { v } else { 0.0 }
    };
    // Votes: in each run of 8 neighbour differences along a row (column), the phase of the
    // strictly largest one.
    let (mut vx, mut vy) = ([0u64; BLOCK], [0u64; BLOCK]);
    let vote = |d: &[f32; BLOCK], votes: &mut [u64; BLOCK]| {
        let best = (0..BLOCK).max_by(|&a, &b| d[a].total_cmp(&d[b])).unwrap_or(0);
        if (0..BLOCK).all(|p| p == best || d[p] < d[best]) {
            votes[best] += 1;
        }
    };
    for y in 0..h {
        for k in 0..(w - 1) / BLOCK {
            let mut by_phase = [0f32; BLOCK];
            for i in 0..BLOCK {
                let x = 1 + k * BLOCK + i;
                by_phase[x % BLOCK] = (at(x, y) - at(x - 1, y)).abs();
            }
            vote(&by_phase, &mut vx);
        }
    }
    for x in 0..w {
        for k in 0..(h - 1) / BLOCK {
            let mut by_phase = [0f32; BLOCK];
            for i in 0..BLOCK {
                let y = 1 + k * BLOCK + i;
                by_phase[y % BLOCK] = (at(x, y) - at(x, y - 1)).abs();
            }
            vote(&by_phase, &mut vy);
        }
    }
    let phase = |votes: [u64; BLOCK]| -> (usize, f32) {
        let best = (0..BLOCK).max_by_key(|&p| votes[p]).unwrap_or(0);
        let mut others: Vec<u64> = (0..BLOCK).filter(|&p| p != best).map(|p| votes[p]).collect();
        others.sort_unstable();
        let median = others[others.len() / 2] as f32;
        (best, votes[best] as f32 / median.max(1.0))
    };
    let ((ox, rx), (oy, ry)) = (phase(vx), phase(vy));
    let strength = rx.min(ry);
    (strength >= GRID_RATIO).then_some(BlockGrid { offset_x: ox, offset_y: oy, strength })
}

/// The cells of a grid along a side of `n` pixels: `[start, end)` of each; the first is the
/// partial block before `offset` when `offset > 0`.
pub fn cells(n: usize, offset: usize) -> Vec<(usize, usize)> {
    let mut edges = vec![0];
    let mut e = if offset == 0 { BLOCK } else { offset };
    while e < n {
        edges.push(e);
        e += BLOCK;
    }
    edges.push(n);
    edges.windows(2).map(|p| (p[0], p[1])).collect()
}

/// The trimmed mean of each grid cell (each block's lowest and highest sixteenth dropped: a
/// dead or hot pixel does not move its block), one working pixel per cell; non-finite pixels
/// count as 0.
pub fn block_means(image: &GreyF32, grid: &BlockGrid) -> Plane {
    let w = image.width() as usize;
    let (cx, cy) = (cells(w, grid.offset_x), cells(image.height() as usize, grid.offset_y));
    let raw = image.as_raw();
    let mut data = vec![0f32; cx.len() * cy.len()];
    for (j, &(y0, y1)) in cy.iter().enumerate() {
        for (i, &(x0, x1)) in cx.iter().enumerate() {
            let mut v: Vec<f32> = (y0..y1)
                .flat_map(|y| {
                    raw[y * w + x0..y * w + x1].iter().map(|&v| if v.is_finite() { v } else { 0.0 })
                })
                .collect();
            data[j * cx.len() + i] = trimmed_mean(&mut v);
        }
    }
    Plane { width: cx.len(), height: cy.len(), data }
}

/// The image replaced by the bilinear interpolation of its [`block_means`] between block
/// centres (constant beyond the outermost centres).
pub fn deblocked(image: &GreyF32, grid: &BlockGrid) -> GreyF32 {
    let (w, h) = (image.width() as usize, image.height() as usize);
    if w == 0 || h == 0 {
        return image.clone();
    }
    let (cx, cy) = (cells(w, grid.offset_x), cells(h, grid.offset_y));
    let means = block_means(image, grid).data;
    // For each pixel coordinate: the two cells around it and the weight of the second.
    let weights = |cells: &[(usize, usize)], n: usize| -> Vec<(usize, usize, f32)> {
        let centres: Vec<f32> = cells.iter().map(|&(a, b)| 0.5 * (a + b) as f32 - 0.5).collect();
        (0..n)
            .map(|p| {
                let p = p as f32;
                let k = centres.partition_point(|&c| c <= p);
                if k == 0 {
                    (0, 0, 0.0)
                } else if k == centres.len() {
                    (k - 1, k - 1, 0.0)
                } else {
                    let t = (p - centres[k - 1]) / (centres[k] - centres[k - 1]);
                    (k - 1, k, t)
                }
            })
            .collect()
    };
    let (wx, wy) = (weights(&cx, w), weights(&cy, h));
    let nx = cx.len();
    GreyF32::from_fn(w as u32, h as u32, |x, y| {
        let (i0, i1, tx) = wx[x as usize];
        let (j0, j1, ty) = wy[y as usize];
        let row = |j: usize| means[j * nx + i0] * (1.0 - tx) + means[j * nx + i1] * tx;
        Luma([row(j0) * (1.0 - ty) + row(j1) * ty])
    })
}

/// The mean of `values` without their lowest and highest sixteenth (a dead or hot pixel in a block does not
/// move its level; the renderer's and real detectors' defects come after compression).
fn trimmed_mean(values: &mut [f32]) -> f32 {
    values.sort_unstable_by(f32::total_cmp);
    let cut = values.len() / 16;
    let kept = &values[cut..values.len() - cut];
    if kept.is_empty() { 0.0 } else { kept.iter().map(|&v| v as f64).sum::<f64>() as f32 / kept.len() as f32 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use rand_distr::StandardNormal;

    /// A smooth ramp with 1 % noise; `blocky` flattens each 8x8 block (from `offset`) to its
    /// mean quantised to `step`, as a coarse block codec does.
    fn ramp(blocky: Option<(usize, usize, f32)>, seed: u64) -> GreyF32 {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let clean = |x: f32, y: f32| 2000.0 + 3.0 * x + 1.5 * y + 40.0 * (x / 30.0).sin();
        GreyF32::from_fn(128, 96, |x, y| {
            let v = match blocky {
                Some((ox, oy, step)) => {
                    let bx = (x as usize + BLOCK - ox) / BLOCK * BLOCK + ox;
                    let by = (y as usize + BLOCK - oy) / BLOCK * BLOCK + oy;
                    let m = clean(bx as f32 - 4.5, by as f32 - 4.5);
                    (m / step).round() * step
                }
                None => {
                    let z: f32 = rng.sample(StandardNormal);
                    clean(x as f32, y as f32) * (1.0 + 0.01 * z)
                }
            };
            Luma([v])
        })
    }

    #[test]
    fn finds_the_grid_of_blocky_images_only() {
        for seed in 0..3 {
            assert_eq!(find_block_grid(&ramp(None, seed)), None, "seed {seed}");
        }
        for (ox, oy) in [(0, 0), (3, 5), (7, 1)] {
            let g = find_block_grid(&ramp(Some((ox, oy, 16.0)), 0)).expect("a grid");
            assert_eq!((g.offset_x, g.offset_y), (ox, oy));
        }
    }

    #[test]
    fn deblocking_leaves_no_step_on_the_grid_and_keeps_the_smooth_image() {
        let img = ramp(Some((3, 5, 16.0)), 0);
        let g = find_block_grid(&img).unwrap();
        let d = deblocked(&img, &g);
        // No jump anywhere: neighbours differ by the ramp's slope (under 4.4 DN per pixel) plus
        // one quantisation step (16 DN) spread between block centres (5.5 px or more apart: the
        // partial edge blocks), under 10 DN, where the blocky input jumps by more than 30 DN.
        let jump = |im: &GreyF32| {
            (1..128u32)
                .flat_map(|x| (0..96u32).map(move |y| (x, y)))
                .fold(0f32, |m, (x, y)| m.max((im.get_pixel(x, y)[0] - im.get_pixel(x - 1, y)[0]).abs()))
        };
        assert!(jump(&img) > 30.0 && jump(&d) < 10.0, "{} -> {}", jump(&img), jump(&d));
        // Inside the outermost block centres the surface stays within a quantisation step and
        // the ramp's curvature of the clean image.
        for y in 12..84u32 {
            for x in 12..116u32 {
                let clean = 2000.0 + 3.0 * x as f32 + 1.5 * y as f32 + 40.0 * (x as f32 / 30.0).sin();
                let e = (d.get_pixel(x, y)[0] - clean).abs();
                assert!(e < 16.0, "({x}, {y}): {e}");
            }
        }
    }
}
