//! Sky segmentation: the horizon and the sky above it (paper 003 section 5.1: "the algorithm
//! first locates the sky (equivalently, the horizon) in an image").
//!
//! The paper gives no more than that step; this is how rovernav does it:
//! 1. Reduce the image to a working size (block means, then a 3x3 median against dead and hot
//!    pixels: the noise-reduction step).
//! 2. Texture: the mean absolute difference between each pixel and its 3x3 median, over a 5x5
//!    window, relative to the local brightness. Mars' sky is smooth at the pixel scale (its
//!    brightness changes over tens of degrees), the ground is textured at every scale (grain,
//!    rocks, shadows), also when it is hazed or brighter than the sky. A median keeps straight
//!    steps, so the seam between two frames of a mosaic (or the skyline itself) is not texture.
//! 3. Groundness of each pixel: 0 below half the texture threshold, 1 above 1.5 times it. The
//!    threshold adapts to the image's noise (4 times its 5 % texture quantile) within fixed
//!    bounds (0.6 % to 1.5 % relative texture: skies measure 0.3 to 0.5 % in rendered,
//!    JPEG-mosaic and 12-bit Navcam images, the least textured real ground about 1 to 2 %), so
//!    an all-sky image stays sky and an image without sky gets none.
//! 4. The horizon is one row per column with sky above and ground below: the path that
//!    minimises the groundness above it plus `ground_weight` times the smoothness below it,
//!    plus `jump_cost` per row the horizon moves between neighbouring columns (dynamic
//!    programming over columns, an L1 min-convolution per column: O(width x height)). The
//!    horizon may lie at row 0 (no sky in that column) or at the bottom (all sky), and may
//!    slant (a tilted rover) or step (a rock on the skyline).
//! 5. Each column's horizon moves to the strongest brightness step within 4 rows (the texture
//!    window blurs the skyline by that much), then a 5-column running median removes spikes.
//!
//! Departure: one sky run per column (sky above ground), so sky seen through a gap below an
//! overhang counts as ground; Navcam views have none.

use rovernav_vision::image::{Grey8, GreyF32};

use crate::plane::{Plane, factor_for_area, quantile};

/// Parameters of the sky segmentation.
#[derive(Clone, Debug, PartialEq)]
pub struct SkyParams {
    /// Most pixels of the working image (a wide mosaic keeps its short side's detail).
    pub max_pixels: usize,
    /// Lower bound of the relative texture threshold.
    pub min_threshold: f32,
    /// Upper bound of the relative texture threshold.
    pub max_threshold: f32,
    /// Cost of a smooth pixel below the horizon relative to a textured one above it.
    pub ground_weight: f32,
    /// Cost per row of horizon movement between neighbouring columns.
    pub jump_cost: f32,
}

impl Default for SkyParams {
    fn default() -> Self {
        Self {
            max_pixels: 640 * 640,
            min_threshold: 0.006,
            max_threshold: 0.015,
            ground_weight: 0.3,
            jump_cost: 0.4,
        }
    }
}

/// The sky region of an image: per column, the rows above the horizon.
#[derive(Clone, Debug, PartialEq)]
pub struct SkyMask {
    /// Image width (pixels).
    pub width: u32,
    /// Image height (pixels).
    pub height: u32,
    /// Per column, the first row that is not sky (0: no sky; `height`: all sky).
    pub horizon: Vec<u32>,
    /// Per column, the first row with data (below a mosaic's black fill; usually 0).
    pub top: Vec<u32>,
    /// The relative texture threshold used.
    pub threshold: f32,
}

impl SkyMask {
    /// Whether pixel (x, y) is sky.
    pub fn is_sky(&self, x: u32, y: u32) -> bool {
        self.horizon.get(x as usize).is_some_and(|&h| y < h && y >= self.top[x as usize])
    }

    /// Fraction of the image that is sky.
    pub fn fraction(&self) -> f64 {
        let n = self.width as f64 * self.height as f64;
        let rows: f64 = self.horizon.iter().zip(&self.top).map(|(&h, &t)| h.saturating_sub(t) as f64).sum();
        if n == 0.0 { 0.0 } else { rows / n }
    }

    /// The mask as an image: 255 for sky, 0 otherwise.
    pub fn to_image(&self) -> Grey8 {
        Grey8::from_fn(self.width, self.height, |x, y| image::Luma([if self.is_sky(x, y) { 255 } else { 0 }]))
    }
}

/// Finds the sky in `image` (any grey scale; non-finite pixels count as 0).
pub fn segment_sky(image: &GreyF32, params: &SkyParams) -> SkyMask {
    let (w, h) = image.dimensions();
    if w == 0 || h == 0 {
        return SkyMask {
            width: w,
            height: h,
            horizon: vec![0; w as usize],
            top: vec![0; w as usize],
            threshold: 0.0,
        };
    }
    let f = factor_for_area(w, h, params.max_pixels);
    let raw = Plane::reduced(image, f);
    let p = raw.median3();
    let (ground, threshold) = groundness(&raw, &p, params);
    let mut rows = horizon_path(&ground, p.width, p.height, params);
    refine_to_edge(&p, &mut rows);
    median_across_columns(&mut rows, 2);
    // Back to full resolution: each working column covers f image columns; linear between
    // column centres, so a slanted horizon stays a line.
    let horizon = (0..w as usize)
        .map(|x| {
            let u = ((x as f64 + 0.5) / f as f64 - 0.5).clamp(0.0, (p.width - 1) as f64);
            let (i, t) = (u.floor() as usize, u - u.floor());
            let j = (i + 1).min(p.width - 1);
            let r = rows[i] as f64 * (1.0 - t) + rows[j] as f64 * t;
            ((r * f as f64).round() as u32).min(h)
        })
        .collect();
    // Leading fill of each column: pixels below 20 % of the bright level (a mosaic's black
    // fill and its grid lines; a sky is never that dark next to its image's bright end). The
    // data start where a run of FILL_RUN data rows does (or the horizon comes first): the
    // labels printed in a mosaic's fill are bright but only a few rows tall. Then a 5-column
    // running median, as for the horizon.
    let bright = quantile(image.as_raw().iter().copied(), 0.99).max(1e-6);
    let mut top: Vec<usize> =
        (0..w).zip(&horizon).map(|(x, &hz)| data_start(image, x, hz, 0.2 * bright) as usize).collect();
    // A grid line drawn down through the fill is one column of data from row 0.
    median_across_columns(&mut top, 2);
    let top: Vec<u32> = top.iter().zip(&horizon).map(|(&t, &hz)| (t as u32).min(hz)).collect();
    SkyMask { width: w, height: h, horizon, top, threshold }
}

/// Consecutive data rows that mark the start of a column's data below a mosaic's fill.
const FILL_RUN: u32 = 16;

/// The first row of column `x` from which FILL_RUN rows (or all rows to `horizon`) are above
/// `level`; `horizon` when there is none.
fn data_start(image: &GreyF32, x: u32, horizon: u32, level: f32) -> u32 {
    let mut start = 0;
    for y in 0..horizon {
        if image.get_pixel(x, y)[0] <= level {
            start = y + 1;
        } else if y + 1 - start >= FILL_RUN {
            return start;
        }
    }
    start.min(horizon)
}

/// Per working pixel, how much it looks like ground (0..1, `None` where there is no data: a
/// mosaic's black fill), and the texture threshold. Means are taken over data pixels only, so
/// the edge of the fill is not texture.
fn groundness(raw: &Plane, p: &Plane, params: &SkyParams) -> (Vec<Option<f32>>, f32) {
    let bright = quantile(p.data.iter().copied(), 0.99).max(1e-6);
    let floor = 0.01 * bright;
    // Data pixels whose 3x3 neighbourhood is all data (a working pixel next to the fill
    // averages fill and image).
    let (w, h) = (p.width, p.height);
    let valid: Vec<f32> = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let all = (y.saturating_sub(1)..(y + 2).min(h))
                .all(|yy| (x.saturating_sub(1)..(x + 2).min(w)).all(|xx| p.at(xx, yy) > floor));
            if all { 1.0 } else { 0.0 }
        })
        .collect();
    let detail = Plane {
        width: p.width,
        height: p.height,
        data: raw.data.iter().zip(&p.data).map(|(a, b)| (a - b).abs()).collect(),
    };
    let texture = detail.masked_mean_with(&valid, 2);
    let level = p.masked_mean_with(&valid, 2);
    let relative: Vec<f32> = texture.data.iter().zip(&level.data).map(|(t, l)| t / l.max(floor)).collect();
    let data_texture = relative.iter().zip(&valid).filter(|(_, v)| **v > 0.0).map(|(r, _)| *r);
    let threshold = (4.0 * quantile(data_texture, 0.05)).clamp(params.min_threshold, params.max_threshold);
    let ground = relative
        .iter()
        .zip(&valid)
        .map(|(&t, &v)| (v > 0.0).then(|| (t / threshold - 0.5).clamp(0.0, 1.0)))
        .collect();
    (ground, threshold)
}

/// Moves each column's horizon to the strongest brightness step (mean over 3 columns) within
/// the texture window's reach (4 rows), since the texture measure blurs the skyline by that
/// much; a column without sky, or all sky, stays as it is.
fn refine_to_edge(p: &Plane, rows: &mut [usize]) {
    let (w, h) = (p.width, p.height);
    let step = |x: usize, y: usize| -> f32 {
        let cols = x.saturating_sub(1)..(x + 2).min(w);
        let n = cols.len() as f32;
        cols.map(|c| (p.at(c, y) - p.at(c, y - 1)).abs()).sum::<f32>() / n
    };
    for (x, r) in rows.iter_mut().enumerate() {
        if *r == 0 || *r >= h {
            continue;
        }
        let (lo, hi) = ((*r).saturating_sub(4).max(1), (*r + 4).min(h - 1));
        if let Some(best) = (lo..=hi).max_by(|&a, &b| step(x, a).total_cmp(&step(x, b))) {
            *r = best;
        }
    }
}

/// A running median of radius `r` along the columns: removes one- and two-column spikes left
/// by the per-column refinement, keeps steps wider than that (a rock on the skyline).
fn median_across_columns(rows: &mut [usize], r: usize) {
    let src = rows.to_vec();
    for (x, out) in rows.iter_mut().enumerate() {
        let mut w: Vec<usize> = src[x.saturating_sub(r)..(x + r + 1).min(src.len())].to_vec();
        let mid = w.len() / 2;
        *out = *w.select_nth_unstable(mid).1;
    }
}

/// The horizon row of each column (0..=height) by dynamic programming over columns.
fn horizon_path(ground: &[Option<f32>], w: usize, h: usize, params: &SkyParams) -> Vec<usize> {
    let n = h + 1;
    // cost[r]: horizon at row r = groundness of rows < r + weight * smoothness of rows >= r.
    // A pixel without data costs nothing on either side.
    let column_cost = |x: usize| -> Vec<f32> {
        let smooth = |y: usize| ground[y * w + x].map_or(0.0, |g| 1.0 - g);
        let total_smooth: f32 = (0..h).map(smooth).sum();
        let mut c = Vec::with_capacity(n);
        let (mut above, mut smooth_above) = (0f32, 0f32);
        for r in 0..n {
            c.push(above + params.ground_weight * (total_smooth - smooth_above));
            if r < h {
                above += ground[r * w + x].unwrap_or(0.0);
                smooth_above += smooth(r);
            }
        }
        c
    };
    let mut back = vec![0u32; w * n];
    let mut acc = column_cost(0);
    let lambda = params.jump_cost;
    for x in 1..w {
        // L1 min-convolution of acc: forward and backward passes with the argmin.
        let mut best: Vec<(f32, u32)> = acc.iter().enumerate().map(|(r, &v)| (v, r as u32)).collect();
        for r in 1..n {
            if best[r - 1].0 + lambda < best[r].0 {
                best[r] = (best[r - 1].0 + lambda, best[r - 1].1);
            }
        }
        for r in (0..n - 1).rev() {
            if best[r + 1].0 + lambda < best[r].0 {
                best[r] = (best[r + 1].0 + lambda, best[r + 1].1);
            }
        }
        let c = column_cost(x);
        for r in 0..n {
            acc[r] = best[r].0 + c[r];
            back[x * n + r] = best[r].1;
        }
    }
    let mut rows = vec![0usize; w];
    let mut r = acc.iter().enumerate().min_by(|a, b| a.1.total_cmp(b.1)).map_or(0, |(i, _)| i);
    for x in (0..w).rev() {
        rows[x] = r;
        if x > 0 {
            r = back[x * n + r] as usize;
        }
    }
    rows
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::Luma;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use rand_distr::StandardNormal;

    /// A hand-built scene: sky (smooth, brighter towards the horizon) above the line
    /// `y = y0 + slope x`, textured ground below; shot-like noise of `noise` relative sd.
    pub(crate) fn scene(
        w: u32,
        h: u32,
        y0: f64,
        slope: f64,
        sky_level: f32,
        noise: f32,
        seed: u64,
    ) -> GreyF32 {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut texture = ChaCha8Rng::seed_from_u64(seed ^ 77);
        GreyF32::from_fn(w, h, |x, y| {
            let line = y0 + slope * x as f64;
            let base = if (y as f64) < line {
                sky_level * (1.0 + 0.3 * (-(line - y as f64) / h as f64 * 3.0).exp() as f32)
            } else {
                // Grain and rocks: +-25 % albedo texture, darker on average.
                let blob = ((x / 6 + y / 5) % 7) as f32 / 7.0 - 0.5;
                0.8 * sky_level * (1.0 + 0.25 * texture.random_range(-1.0f32..1.0) + 0.2 * blob)
            };
            let z: f32 = rng.sample(StandardNormal);
            Luma([base * (1.0 + noise * z)])
        })
    }

    fn horizon_error(mask: &SkyMask, y0: f64, slope: f64) -> f64 {
        let h = mask.height as f64;
        let errors: Vec<f64> = (0..mask.width)
            .map(|x| (mask.horizon[x as usize] as f64 - (y0 + slope * x as f64).clamp(0.0, h)).abs())
            .collect();
        errors.iter().sum::<f64>() / errors.len() as f64
    }

    #[test]
    fn finds_a_known_level_and_a_tilted_horizon() {
        for (y0, slope) in [(90.0, 0.0), (40.0, 0.35), (170.0, -0.3)] {
            let img = scene(320, 240, y0, slope, 2000.0, 0.006, 3);
            let mask = segment_sky(&img, &SkyParams::default());
            let e = horizon_error(&mask, y0, slope);
            assert!(e < 2.5, "horizon y0 {y0} slope {slope}: mean error {e} px");
        }
    }

    #[test]
    fn all_sky_and_no_sky_images() {
        // Terrain-free: the whole image is sky (also a bright, dusty, noisier one).
        let sky = scene(200, 150, 1e9, 0.0, 3500.0, 0.01, 5);
        assert!(segment_sky(&sky, &SkyParams::default()).fraction() > 0.99);
        // Pointed at the ground: no sky.
        let ground = scene(200, 150, -1.0, 0.0, 2000.0, 0.006, 6);
        let m = segment_sky(&ground, &SkyParams::default());
        assert!(m.fraction() < 0.02, "{} {}", m.fraction(), m.threshold);
    }

    #[test]
    fn bright_dusty_sky_over_hazed_ground() {
        // The ground is as bright as the sky near the horizon: only its texture tells it apart.
        let base = scene(256, 256, 100.0, 0.0, 3000.0, 0.008, 9);
        let img = GreyF32::from_fn(256, 256, |x, y| {
            let v = base.get_pixel(x, y)[0];
            Luma([if y >= 100 { v * 1.25 } else { v }])
        });
        let mask = segment_sky(&img, &SkyParams::default());
        assert!(horizon_error(&mask, 100.0, 0.0) < 2.5);
    }

    #[test]
    fn empty_image_has_no_sky() {
        let m = segment_sky(&GreyF32::new(0, 0), &SkyParams::default());
        assert_eq!(m.fraction(), 0.0);
    }
}
