//! Normalised cross-correlation of a template over a search window, with a subpixel peak and
//! the peak's quality measures (paper 003 section 3: "normalized cross-correlation (NCC) with
//! template image magnification").
//!
//! The zero-mean score of a template T (n pixels, mean T̄) placed on an image window I (mean Ī)
//! is r = Σ (I - Ī)(T - T̄) / sqrt(Σ (I - Ī)² Σ (T - T̄)²), in [-1, 1] and unchanged by any gain
//! and offset of either image. The raw variant (no means removed) exists to check this code
//! against an independent implementation of the same formula (imageproc's
//! `CrossCorrelationNormalized`). The subpixel peak is the vertex of a parabola through the
//! best score and its two neighbours, fitted separately along x and y (the separable form of a
//! paraboloid fit); the parabola's second difference is the peak's sharpness.

use super::TrackError;
use crate::image::GreyF32;

/// Whether the correlation removes the window means (the tracker's score) or not.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Centring {
    /// Zero-mean NCC: invariant to gain and offset.
    ZeroMean,
    /// Raw normalised correlation: invariant to gain only.
    Raw,
}

/// A rectangle of template-centre positions (pixels, inclusive bounds) to search.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Window {
    /// Smallest centre column.
    pub x_min: i64,
    /// Largest centre column.
    pub x_max: i64,
    /// Smallest centre row.
    pub y_min: i64,
    /// Largest centre row.
    pub y_max: i64,
}

impl Window {
    /// The window of centres within `half_x`, `half_y` pixels of the pixel nearest (x, y).
    pub fn around(x: f64, y: f64, half_x: usize, half_y: usize) -> Self {
        let (cx, cy) = (x.round() as i64, y.round() as i64);
        let (hx, hy) = (half_x as i64, half_y as i64);
        Self { x_min: cx - hx, x_max: cx + hx, y_min: cy - hy, y_max: cy + hy }
    }

    /// The part of the window where a template of half-sizes (hx, hy) lies inside a w x h image.
    fn clipped(&self, w: usize, h: usize, hx: usize, hy: usize) -> Option<Self> {
        let (w, h, hx, hy) = (w as i64, h as i64, hx as i64, hy as i64);
        let c = Self {
            x_min: self.x_min.max(hx),
            x_max: self.x_max.min(w - 1 - hx),
            y_min: self.y_min.max(hy),
            y_max: self.y_max.min(h - 1 - hy),
        };
        (c.x_min <= c.x_max && c.y_min <= c.y_max).then_some(c)
    }
}

/// Scores over a window: `scores[(y - y0) * width + (x - x0)]` is the score with the template's
/// centre on pixel (x, y).
#[derive(Clone, Debug, PartialEq)]
pub struct ScoreMap {
    /// Column of the first score.
    pub x0: i64,
    /// Row of the first score.
    pub y0: i64,
    /// Number of columns.
    pub width: usize,
    /// Number of rows.
    pub height: usize,
    /// Row-major scores in [-1, 1].
    pub scores: Vec<f32>,
}

impl ScoreMap {
    /// The score with the template centred on pixel (x, y), if searched.
    pub fn get(&self, x: i64, y: i64) -> Option<f32> {
        let (i, j) = (x - self.x0, y - self.y0);
        (i >= 0 && j >= 0 && (i as usize) < self.width && (j as usize) < self.height)
            .then(|| self.scores[j as usize * self.width + i as usize])
    }
}

/// The best match in a score map and how trustworthy it is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Peak {
    /// Subpixel column of the template centre.
    pub x: f64,
    /// Subpixel row of the template centre.
    pub y: f64,
    /// The best score.
    pub score: f32,
    /// The best local maximum farther than the exclusion radius from the peak (-1 if none).
    pub second: f32,
    /// Distance (px) from the peak to that second local maximum (NaN if none).
    pub second_distance_px: f64,
    /// Sharpness: the smaller negated second difference of the scores across the peak (per
    /// px²) over the axes where both neighbours were searched; NaN if there were none.
    pub curvature: f32,
    /// Whether the best score lies on the window's border (the true peak may lie outside).
    pub on_edge: bool,
}

/// Scores `template` (odd width and height) at every centre of `window` inside `image`.
pub fn score_map(
    image: &GreyF32,
    template: &GreyF32,
    window: &Window,
    centring: Centring,
) -> Result<ScoreMap, TrackError> {
    let (tw, th) = (template.width() as usize, template.height() as usize);
    if tw % 2 == 0 || th % 2 == 0 {
        return Err(TrackError::Template(format!("size {tw}x{th} is not odd")));
    }
    let (iw, ih) = (image.width() as usize, image.height() as usize);
    let win = window.clipped(iw, ih, tw / 2, th / 2).ok_or(TrackError::OutOfView)?;
    let n = (tw * th) as f64;
    let t = template.as_raw();
    let t_mean = match centring {
        Centring::ZeroMean => t.iter().map(|&v| v as f64).sum::<f64>() / n,
        Centring::Raw => 0.0,
    };
    let tc: Vec<f64> = t.iter().map(|&v| v as f64 - t_mean).collect();
    let t_norm: f64 = tc.iter().map(|v| v * v).sum();
    if t_norm <= 1e-12 * n {
        return Err(TrackError::Textureless);
    }
    let img = image.as_raw();
    let width = (win.x_max - win.x_min + 1) as usize;
    let height = (win.y_max - win.y_min + 1) as usize;
    let mut scores = Vec::with_capacity(width * height);
    for cy in win.y_min..=win.y_max {
        for cx in win.x_min..=win.x_max {
            let (x0, y0) = ((cx as usize) - tw / 2, (cy as usize) - th / 2);
            let (mut s_it, mut s_i, mut s_ii) = (0.0f64, 0.0f64, 0.0f64);
            for r in 0..th {
                let row = &img[(y0 + r) * iw + x0..(y0 + r) * iw + x0 + tw];
                let trow = &tc[r * tw..(r + 1) * tw];
                for (&iv, &tv) in row.iter().zip(trow) {
                    let iv = iv as f64;
                    s_it += iv * tv;
                    s_i += iv;
                    s_ii += iv * iv;
                }
            }
            let i_var = match centring {
                Centring::ZeroMean => s_ii - s_i * s_i / n,
                Centring::Raw => s_ii,
            };
            let denom = (i_var.max(0.0) * t_norm).sqrt();
            let r = if denom > 1e-12 { (s_it / denom).clamp(-1.0, 1.0) } else { 0.0 };
            scores.push(r as f32);
        }
    }
    Ok(ScoreMap { x0: win.x_min, y0: win.y_min, width, height, scores })
}

/// Whether the scores on the segment from `a` to `b` (nearest map cells, one sample per px) fall
/// below `level` somewhere.
fn separated(map: &ScoreMap, a: (usize, usize), b: (usize, usize), level: f32) -> bool {
    let (dx, dy) = (b.0 as f64 - a.0 as f64, b.1 as f64 - a.1 as f64);
    let n = dx.abs().max(dy.abs()).ceil() as usize;
    (1..n).any(|k| {
        let t = k as f64 / n as f64;
        let x = (a.0 as f64 + t * dx).round() as usize;
        let y = (a.1 as f64 + t * dy).round() as usize;
        map.scores[y * map.width + x] < level
    })
}

/// Vertex offset (clamped to ±0.5) and negated second difference of a parabola through three
/// equally spaced samples with the middle one the largest.
pub fn parabola_vertex(minus: f32, centre: f32, plus: f32) -> (f64, f64) {
    let (m, c, p) = (minus as f64, centre as f64, plus as f64);
    let second = m - 2.0 * c + p;
    if second >= 0.0 {
        return (0.0, 0.0);
    }
    ((0.5 * (m - p) / second).clamp(-0.5, 0.5), -second)
}

/// Least fall (in correlation) between two local maxima for them to count as separate peaks:
/// a maximum joined to the best by a ridge that never drops this far below it is a bump on the
/// best peak's lobe, not a second place the template fits.
pub const SEPARATING_DIP: f32 = 0.1;

/// The best score of a map, refined to subpixel, with the best separate local maximum farther
/// than `exclusion_px` from it (separate: the scores on the straight line between the two fall
/// at least [`SEPARATING_DIP`] below the lower one); `None` for an empty map.
pub fn find_peak(map: &ScoreMap, exclusion_px: f64) -> Option<Peak> {
    let (w, h) = (map.width, map.height);
    let best = (0..w * h).max_by(|&a, &b| map.scores[a].total_cmp(&map.scores[b]))?;
    let (bx, by) = (best % w, best / w);
    let s = |x: usize, y: usize| map.scores[y * w + x];
    let score = s(bx, by);
    let mut curvature = f64::INFINITY;
    let (mut dx, mut dy) = (0.0, 0.0);
    if bx > 0 && bx + 1 < w {
        let (d, c) = parabola_vertex(s(bx - 1, by), score, s(bx + 1, by));
        dx = d;
        curvature = curvature.min(c);
    }
    if by > 0 && by + 1 < h {
        let (d, c) = parabola_vertex(s(bx, by - 1), score, s(bx, by + 1));
        dy = d;
        curvature = curvature.min(c);
    }
    let curvature = if curvature.is_finite() { curvature as f32 } else { f32::NAN };
    let on_edge = (w > 1 && (bx == 0 || bx + 1 == w)) || (h > 1 && (by == 0 || by + 1 == h));
    let mut second = -1.0f32;
    let mut second_distance_px = f64::NAN;
    let ex2 = exclusion_px * exclusion_px;
    for y in 0..h {
        for x in 0..w {
            let v = s(x, y);
            let d2 = (x as f64 - bx as f64).powi(2) + (y as f64 - by as f64).powi(2);
            if v <= second || d2 <= ex2 {
                continue;
            }
            let local_max = (y.saturating_sub(1)..(y + 2).min(h))
                .all(|yy| (x.saturating_sub(1)..(x + 2).min(w)).all(|xx| s(xx, yy) <= v));
            if local_max && separated(map, (bx, by), (x, y), v - SEPARATING_DIP) {
                second = v;
                second_distance_px = d2.sqrt();
            }
        }
    }
    Some(Peak {
        x: (map.x0 + bx as i64) as f64 + dx,
        y: (map.y0 + by as i64) as f64 + dy,
        score,
        second,
        second_distance_px,
        curvature,
        on_edge,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::Luma;

    #[test]
    fn parabola_vertex_of_a_sampled_parabola() {
        // f(x) = 1 - 0.1 (x - 0.3)^2 sampled at -1, 0, 1: vertex at 0.3, f'' = -0.2.
        let f = |x: f64| (1.0 - 0.1 * (x - 0.3) * (x - 0.3)) as f32;
        let (d, c) = parabola_vertex(f(-1.0), f(0.0), f(1.0));
        assert!((d - 0.3).abs() < 1e-6, "{d}");
        assert!((c - 0.2).abs() < 1e-6, "{c}");
    }

    #[test]
    fn exact_copy_scores_one_and_gain_offset_do_not_matter() {
        let img =
            GreyF32::from_fn(40, 30, |x, y| Luma([((x * 7 + y * 13) % 17) as f32 + (x * y % 5) as f32]));
        let tmpl = GreyF32::from_fn(7, 5, |x, y| Luma([3.0 * img.get_pixel(x + 20, y + 10)[0] + 100.0]));
        let map = score_map(&img, &tmpl, &Window::around(23.0, 12.0, 6, 6), Centring::ZeroMean).unwrap();
        let peak = find_peak(&map, 3.0).unwrap();
        assert_eq!((peak.x.round(), peak.y.round()), (23.0, 12.0));
        assert!((peak.score - 1.0).abs() < 1e-5);
        assert!(peak.second < peak.score);
    }

    #[test]
    fn a_bump_on_the_ridge_of_the_best_peak_is_not_a_second_peak() {
        // Scores along one row: the best peak at 2, a shoulder at 8 joined to it by a ridge
        // that never falls 0.1 below the shoulder, and a separate peak at 14 behind a valley.
        let row = [0.2, 0.6, 0.95, 0.9, 0.88, 0.86, 0.85, 0.86, 0.87, 0.8, 0.5, 0.2, 0.4, 0.7, 0.8, 0.6, 0.3];
        let map = ScoreMap { x0: 0, y0: 0, width: row.len(), height: 1, scores: row.to_vec() };
        let peak = find_peak(&map, 3.0).unwrap();
        assert_eq!(peak.second, 0.8);
        assert_eq!(peak.second_distance_px, 12.0);
        // Without the valley, the shoulder (0.87) would have been the second peak.
        let mut ridge = row;
        ridge[10..14].copy_from_slice(&[0.79, 0.78, 0.79, 0.76]);
        let map = ScoreMap { x0: 0, y0: 0, width: ridge.len(), height: 1, scores: ridge.to_vec() };
        assert_eq!(find_peak(&map, 3.0).unwrap().second, -1.0);
    }

    #[test]
    fn flat_template_is_an_error_and_even_size_too() {
        let img = GreyF32::from_fn(20, 20, |x, _| Luma([x as f32]));
        let flat = GreyF32::from_pixel(5, 5, Luma([2.0]));
        let w = Window::around(10.0, 10.0, 2, 2);
        assert_eq!(score_map(&img, &flat, &w, Centring::ZeroMean), Err(TrackError::Textureless));
        let even = GreyF32::from_fn(4, 5, |x, _| Luma([x as f32]));
        assert!(matches!(score_map(&img, &even, &w, Centring::ZeroMean), Err(TrackError::Template(_))));
        let off = Window::around(100.0, 10.0, 2, 2);
        let tmpl = GreyF32::from_fn(5, 5, |x, _| Luma([x as f32]));
        assert_eq!(score_map(&img, &tmpl, &off, Centring::ZeroMean), Err(TrackError::OutOfView));
    }
}
