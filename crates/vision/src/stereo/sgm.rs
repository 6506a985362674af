//! Semi-global cost aggregation and winner-take-all (Hirschmüller, PAMI 30(2), 2008,
//! sections 3.3 and 3.4).
//!
//! Along each path direction r the aggregated cost is (equation 13)
//! L_r(p, d) = C(p, d) + min(L_r(p-r, d), L_r(p-r, d±1) + P1, min_i L_r(p-r, i) + P2)
//!             - min_i L_r(p-r, i),
//! which stays below C_max + P2, so `u16` holds the sum S(p, d) of the 8 paths. The paths run
//! as two sweeps: one from the top-left corner row by row (paths from the left, top-left, top
//! and top-right) and its mirror from the bottom-right corner (the 4 opposite paths), one rayon
//! task each.
//!
//! The right image's disparities for the consistency check are aggregated from the same
//! matching costs re-indexed to the right image ([`right_costs`]). The paper's cheaper
//! alternative, the minimum of the left image's aggregated costs along the diagonal
//! x_left = x_right + d, compares sums of different left pixels whose cost levels differ; on
//! Tsukuba it disagreed with a correct left disparity by more than 1 px at 4 % of the pixels,
//! which the check then rejected (the aggregation's time doubles instead).

use rayon::prelude::*;

use super::census::MAX_COST;
use super::{INVALID_DISPARITY, StereoParams};

/// The aggregated costs of the two sweeps; S(p, d) is the sum of both at `(y * w + x) * nd + d`.
pub struct Aggregated {
    /// Sum of the 4 paths coming from above and the left.
    pub forward: Vec<u16>,
    /// Sum of the 4 paths coming from below and the right.
    pub backward: Vec<u16>,
}

/// Padding value around each path vector: larger than any L, small enough that + P1 fits.
const SENTINEL: i16 = 0x3fff;

/// Aggregates the cost volume along 8 paths.
pub fn aggregate(
    costs: &[u8],
    img: &[f32],
    w: usize,
    h: usize,
    nd: usize,
    params: &StereoParams,
) -> Aggregated {
    let (forward, backward) = rayon::join(
        || sweep(costs, img, w, h, nd, params, false),
        || sweep(costs, img, w, h, nd, params, true),
    );
    Aggregated { forward, backward }
}

/// P2 after adaptation to the intensity step between a pixel and its predecessor on a path.
fn adapted_p2(params: &StereoParams, a: f32, b: f32) -> i16 {
    let g = params.p2_gradient_scale;
    let p2 = f32::from(params.p2) * g / (g + (a - b).abs());
    (p2 as i16).max(params.p1 as i16)
}

/// One step of equation 13: `out` (padded, nd + 2 entries) from the predecessor's padded
/// vector `prev` and its minimum. Returns the minimum of the new vector. The path costs are
/// `i16` (they stay below 0x3fff + P1) because SSE2 has a packed minimum for signed 16-bit
/// values only, and this loop is the matcher's inner loop.
#[inline]
fn step(c: &[u8], prev: &[i16], prev_min: i16, p1: i16, p2: i16, out: &mut [i16]) -> i16 {
    let nd = c.len();
    let jump = prev_min + p2;
    let (lower, same, upper) = (&prev[..nd], &prev[1..nd + 1], &prev[2..nd + 2]);
    let out = &mut out[1..nd + 1];
    for ((((o, &c), &a), &b), &e) in out.iter_mut().zip(c).zip(lower).zip(same).zip(upper) {
        let best = b.min(a + p1).min(e + p1).min(jump);
        *o = i16::from(c) + best - prev_min;
    }
    out.iter().copied().fold(i16::MAX, i16::min)
}

/// A path's first pixel: L = C.
#[inline]
fn start(c: &[u8], out: &mut [i16]) -> i16 {
    let mut m = i16::MAX;
    for (o, &v) in out[1..=c.len()].iter_mut().zip(c) {
        *o = i16::from(v);
        m = m.min(*o);
    }
    m
}

/// One sweep of 4 paths; `reverse` mirrors both axes (the 4 opposite paths).
fn sweep(
    costs: &[u8],
    img: &[f32],
    w: usize,
    h: usize,
    nd: usize,
    params: &StereoParams,
    reverse: bool,
) -> Vec<u16> {
    let stride = nd + 2;
    let p1 = params.p1 as i16;
    let new_row = || vec![SENTINEL; w * stride];
    // Previous and current rows for the 3 paths from the row above: diagonal from the
    // preceding column, vertical, diagonal from the following column (in sweep order).
    let mut prev: [Vec<i16>; 3] = [new_row(), new_row(), new_row()];
    let mut cur: [Vec<i16>; 3] = [new_row(), new_row(), new_row()];
    let mut prev_min = [vec![0i16; w], vec![0i16; w], vec![0i16; w]];
    let mut cur_min = prev_min.clone();
    let mut along = vec![SENTINEL; stride];
    let mut along_next = vec![SENTINEL; stride];
    let mut out = vec![0u16; w * h * nd];
    let real = |i: usize, n: usize| if reverse { n - 1 - i } else { i };
    for yi in 0..h {
        let y = real(yi, h);
        let mut along_min = 0i16;
        for xi in 0..w {
            let x = real(xi, w);
            let p = y * w + x;
            let c = &costs[p * nd..(p + 1) * nd];
            let i = img[p];
            // Path along the row.
            along_min = if xi == 0 {
                start(c, &mut along_next)
            } else {
                let q = img[y * w + real(xi - 1, w)];
                step(c, &along, along_min, p1, adapted_p2(params, i, q), &mut along_next)
            };
            std::mem::swap(&mut along, &mut along_next);
            // Paths from the row above (in sweep order): columns xi - 1, xi, xi + 1.
            for (k, dx) in [-1isize, 0, 1].into_iter().enumerate() {
                let pred = xi as isize + dx;
                let o = &mut cur[k][xi * stride..(xi + 1) * stride];
                cur_min[k][xi] = if yi == 0 || pred < 0 || pred >= w as isize {
                    start(c, o)
                } else {
                    let pred = pred as usize;
                    let q = img[real(yi - 1, h) * w + real(pred, w)];
                    let pv = &prev[k][pred * stride..(pred + 1) * stride];
                    step(c, pv, prev_min[k][pred], p1, adapted_p2(params, i, q), o)
                };
            }
            let s = &mut out[p * nd..(p + 1) * nd];
            let r = xi * stride + 1..xi * stride + 1 + nd;
            let (a, b, cc) = (&cur[0][r.clone()], &cur[1][r.clone()], &cur[2][r]);
            for ((((s, &l), &a), &b), &cc) in s.iter_mut().zip(&along[1..nd + 1]).zip(a).zip(b).zip(cc) {
                // Each term is below 62 + 1000 (P2 <= 1000), so the sum fits.
                *s = (l + a + b + cc) as u16;
            }
        }
        std::mem::swap(&mut prev, &mut cur);
        std::mem::swap(&mut prev_min, &mut cur_min);
    }
    out
}

/// Which image a cost volume takes as reference.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reference {
    /// Left pixel x matches right pixel x - d.
    Left,
    /// Right pixel x matches left pixel x + d.
    Right,
}

/// The right image's cost volume from the left one, C_R(x, d) = C(x + d, d): the same
/// matching costs, re-indexed; [`MAX_COST`] where x + d leaves the image.
pub fn right_costs(costs: &[u8], w: usize, h: usize, nd: usize) -> Vec<u8> {
    let mut out = vec![MAX_COST; w * h * nd];
    out.par_chunks_mut(w * nd).enumerate().for_each(|(y, row)| {
        for (x, cell) in row.chunks_exact_mut(nd).enumerate() {
            for (d, c) in cell.iter_mut().enumerate().take(w - x) {
                *c = costs[(y * w + x + d) * nd + d];
            }
        }
    });
    out
}

/// Winner-take-all on S = forward + backward with the parabola subpixel fit and the
/// uniqueness test; only disparities whose match lies inside the other image compete.
pub fn winner_take_all(
    agg: &Aggregated,
    w: usize,
    h: usize,
    nd: usize,
    uniqueness: f32,
    reference: Reference,
) -> Vec<f32> {
    let mut disp = vec![INVALID_DISPARITY; w * h];
    disp.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        let mut s = vec![0u16; nd];
        for (x, out) in row.iter_mut().enumerate() {
            let p = (y * w + x) * nd;
            for ((v, &a), &b) in s.iter_mut().zip(&agg.forward[p..p + nd]).zip(&agg.backward[p..p + nd]) {
                *v = a + b;
            }
            let n = match reference {
                Reference::Left => nd.min(x + 1),
                Reference::Right => nd.min(w - x),
            };
            *out = best_disparity(&s[..n], uniqueness);
        }
    });
    disp
}

/// The subpixel minimum of one pixel's aggregated costs, or invalid when not unique.
fn best_disparity(s: &[u16], uniqueness: f32) -> f32 {
    let (mut best, mut d) = (u16::MAX, 0);
    for (k, &v) in s.iter().enumerate() {
        if v < best {
            (best, d) = (v, k);
        }
    }
    if uniqueness > 0.0 {
        let second = s.iter().enumerate().filter(|(k, _)| k.abs_diff(d) > 1).map(|(_, &v)| v).min();
        if let Some(second) = second
            && f32::from(best) > (1.0 - uniqueness) * f32::from(second)
        {
            return INVALID_DISPARITY;
        }
    }
    let mut sub = d as f32;
    if d > 0 && d + 1 < s.len() {
        let (a, b, c) = (f32::from(s[d - 1]), f32::from(best), f32::from(s[d + 1]));
        let denom = a - 2.0 * b + c;
        if denom > 0.0 {
            sub += ((a - c) / (2.0 * denom)).clamp(-0.5, 0.5);
        }
    }
    sub
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Equation 13 evaluated literally along one path, for comparison.
    fn reference_path(costs: &[Vec<u8>], p1: i16, p2: i16) -> Vec<Vec<i16>> {
        let mut out: Vec<Vec<i16>> = Vec::new();
        for (i, c) in costs.iter().enumerate() {
            if i == 0 {
                out.push(c.iter().map(|&v| i16::from(v)).collect());
                continue;
            }
            let prev = &out[i - 1];
            let m = *prev.iter().min().unwrap();
            let l: Vec<i16> = (0..c.len())
                .map(|d| {
                    let mut best = prev[d].min(m + p2);
                    if d > 0 {
                        best = best.min(prev[d - 1] + p1);
                    }
                    if d + 1 < c.len() {
                        best = best.min(prev[d + 1] + p1);
                    }
                    i16::from(c[d]) + best - m
                })
                .collect();
            out.push(l);
        }
        out
    }

    #[test]
    fn step_matches_equation_13() {
        let nd = 9;
        let costs: Vec<Vec<u8>> =
            (0..30).map(|i| (0..nd).map(|d| ((i * 31 + d * 17) % 63) as u8).collect()).collect();
        let want = reference_path(&costs, 7, 40);
        let mut prev = vec![SENTINEL; nd + 2];
        let mut cur = vec![SENTINEL; nd + 2];
        let mut m = start(&costs[0], &mut prev);
        for (i, c) in costs.iter().enumerate().skip(1) {
            m = step(c, &prev, m, 7, 40, &mut cur);
            assert_eq!(&cur[1..=nd], &want[i][..], "pixel {i}");
            assert_eq!(m, *want[i].iter().min().unwrap());
            std::mem::swap(&mut prev, &mut cur);
        }
    }

    #[test]
    fn subpixel_parabola_recovers_the_vertex() {
        // Costs sampled from 10 (d - 3.3)^2 + 5: the vertex is at 3.3.
        let s: Vec<u16> = (0..8).map(|d| (10.0 * (d as f32 - 3.3).powi(2) + 5.0).round() as u16).collect();
        let d = best_disparity(&s, 0.0);
        assert!((d - 3.3).abs() < 0.05, "{d}");
    }
}
