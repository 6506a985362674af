//! Elevation from consecutive descent images (paper 002 section 4).
//!
//! Two nadir images of a descent sequence, the second taken after the camera moved `T_z` down
//! (half the altitude), see the same ground at a 2:1 scale. The lower image is averaged 2:1 so
//! that both show the ground at the upper image's resolution; interest points of the upper
//! image (the strongest smaller eigenvalue of the gradient structure tensor in each cell of a
//! grid, so that matches cover the image evenly) are found in it by normalised
//! cross-correlation around where a prior ground height puts them, to a subpixel by a parabola
//! through the correlation peak along each axis. The two pixels' rays are triangulated (the
//! midpoint of their closest approach). The camera poses come from the lander's navigation
//! (the paper: "how well the relative positions and orientations of the camera can be
//! estimated" is left open); this module takes them as known.
//!
//! The paper's precision of an elevation from one pair (section 4, figure 4 geometry, purely
//! vertical descent): `dZ = (Z - T_z)^2 dtheta / (T_z tan theta)`, where `Z` is the upper
//! camera's height above the ground point (along the optical axis), `T_z` the distance the
//! camera descended between the two images, `theta` the angle between the upper camera's
//! optical axis and its ray to the point, and `dtheta` the angular precision (rad) with which
//! the point is found in the lower image (the paper assumes 0.1 pixel). It follows from
//! `Z = T_z tan(theta_2) / (tan(theta_2) - tan(theta))` differentiated in `tan(theta_2)`, with
//! `sec^2(theta_2)` taken as 1. No elevation comes from the image centre (`theta -> 0`).
//!
//! Departure: the matcher searches the 2:1-averaged lower image at the upper image's ground
//! resolution, so its correlation works on one pixel of the upper image (two of the lower);
//! [`DescentMatch::lower_px`] is in the lower image's own pixels.

use nalgebra::{Point2, Point3};
use rayon::prelude::*;
use rovernav_core::{Grid2, GridGeometry};

use crate::camera::{CameraModel, Ray};

/// The paper's precision of an elevation from one image pair (m): `(Z - T_z)^2 dtheta /
/// (T_z tan theta)` for height `z_m` of the upper camera above the point, descent `tz_m`,
/// viewing angle `theta` (rad) and matching precision `dtheta` (rad); infinite at `theta = 0`.
pub fn predicted_sigma(z_m: f64, tz_m: f64, theta: f64, dtheta: f64) -> f64 {
    let t = theta.tan().abs();
    if t <= 0.0 || tz_m <= 0.0 { f64::INFINITY } else { (z_m - tz_m).powi(2) * dtheta / (tz_m * t) }
}

/// The midpoint of the closest approach of two rays; `None` when they are parallel.
pub fn triangulate(a: &Ray, b: &Ray) -> Option<Point3<f64>> {
    let (u, v) = (a.direction.into_inner(), b.direction.into_inner());
    let w = a.origin - b.origin;
    let (uv, uw, vw) = (u.dot(&v), u.dot(&w), v.dot(&w));
    let den = 1.0 - uv * uv;
    if den < 1e-15 {
        return None;
    }
    let s = (uv * vw - uw) / den;
    let t = (vw - uv * uw) / den;
    Some(Point3::from((a.at(s).coords + b.at(t).coords) * 0.5))
}

/// A grey image, row-major.
#[derive(Clone, Copy, Debug)]
pub struct View<'a> {
    /// Pixels, `width * height`.
    pub pixels: &'a [f32],
    /// Width (pixels).
    pub width: usize,
    /// Height (pixels).
    pub height: usize,
}

impl View<'_> {
    fn at(&self, x: usize, y: usize) -> f64 {
        self.pixels[y * self.width + x] as f64
    }
}

/// The image averaged over 2x2 blocks (its pixel (i, j) is centred on the original
/// (2i + 0.5, 2j + 0.5)).
pub fn downsample_2x(image: &View) -> (Vec<f32>, usize, usize) {
    let (w, h) = (image.width / 2, image.height / 2);
    let out = (0..w * h)
        .map(|i| {
            let (x, y) = (2 * (i % w), 2 * (i / w));
            0.25 * (image.at(x, y) + image.at(x + 1, y) + image.at(x, y + 1) + image.at(x + 1, y + 1)) as f32
        })
        .collect();
    (out, w, h)
}

/// The image blurred by a Gaussian of `sigma` pixels (a copy when `sigma` is not positive).
fn blur(image: &View, sigma: f64) -> Vec<f32> {
    if sigma.is_nan() || sigma <= 0.0 {
        return image.pixels.to_vec();
    }
    let buffer = image::ImageBuffer::<image::Luma<f32>, Vec<f32>>::from_raw(
        image.width as u32,
        image.height as u32,
        image.pixels.to_vec(),
    );
    match buffer {
        Some(b) => imageproc::filter::gaussian_blur_f32(&b, sigma as f32).into_raw(),
        None => image.pixels.to_vec(),
    }
}

/// Options of [`match_pair`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MatchParams {
    /// Side of the grid cells that each give at most one interest point (upper pixels).
    pub cell_px: usize,
    /// Half side of the correlation window (pixels).
    pub half_window: usize,
    /// Half side of the search around the prior's prediction (pixels of the averaged image).
    pub search_px: usize,
    /// Standard deviation of the Gaussian blur applied to the upper and the averaged lower
    /// image before matching (pixels; 0 for none): it removes the content near the sampling
    /// limit, which the 2x2 average lets through from the lower image and the upper image
    /// never had.
    pub blur_px: f64,
    /// Least normalised cross-correlation of an accepted match.
    pub min_ncc: f64,
    /// Upper-image pixels to match, `[x0, y0, x1, y1]` (exclusive ends); `None` for all.
    pub region: Option<[usize; 4]>,
    /// Least smaller structure-tensor eigenvalue per window pixel, relative to the image's
    /// mean squared intensity (rejects textureless points).
    pub min_texture: f64,
}

impl Default for MatchParams {
    fn default() -> Self {
        Self {
            cell_px: 8,
            half_window: 7,
            search_px: 12,
            blur_px: 1.0,
            min_ncc: 0.8,
            region: None,
            min_texture: 1e-5,
        }
    }
}

/// One point found in both images, triangulated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DescentMatch {
    /// Pixel in the upper image (sample, line).
    pub upper_px: [f64; 2],
    /// Pixel in the lower image (its own full-resolution sample, line).
    pub lower_px: [f64; 2],
    /// Peak normalised cross-correlation.
    pub ncc: f64,
    /// Triangulated point (world frame, m).
    pub point: [f64; 3],
    /// Angle between the upper camera's axis and its ray to the point (rad).
    pub theta: f64,
    /// Height of the upper camera above the point along its axis (m): the paper's `Z`.
    pub z_m: f64,
    /// Descent between the two images along the upper camera's axis (m): the paper's `T_z`.
    pub tz_m: f64,
}

impl DescentMatch {
    /// The paper's precision of this point for a matching precision of `sigma_px` pixels of
    /// the lower image whose focal length is `focal_px` (m).
    pub fn predicted_sigma(&self, sigma_px: f64, focal_px: f64) -> f64 {
        predicted_sigma(self.z_m, self.tz_m, self.theta, sigma_px / focal_px)
    }
}

/// Matches the upper image's interest points in the lower image and triangulates them.
/// `prior(x, y)` is a ground height (m) near which to search.
pub fn match_pair<C: CameraModel>(
    upper: (&View, &C),
    lower: (&View, &C),
    prior: &(dyn Fn(f64, f64) -> f64 + Sync),
    params: &MatchParams,
) -> Vec<DescentMatch> {
    let (up, up_cam) = upper;
    let (lo, lo_cam) = lower;
    let (small, sw, sh) = downsample_2x(lo);
    let small = blur(&View { pixels: &small, width: sw, height: sh }, params.blur_px);
    let small = View { pixels: &small, width: sw, height: sh };
    let up_blurred = blur(up, params.blur_px);
    let up = &View { pixels: &up_blurred, ..*up };
    let score = min_eigenvalue(up, params.half_window);
    let mean_sq = up.pixels.iter().map(|&p| (p as f64).powi(2)).sum::<f64>() / up.pixels.len().max(1) as f64;
    let min_score = params.min_texture * mean_sq * ((2 * params.half_window + 1) as f64).powi(2);
    let hw = params.half_window;
    let cell = params.cell_px.max(1);
    let centre = Point2::new(0.5 * (up.width as f64 - 1.0), 0.5 * (up.height as f64 - 1.0));
    let axis = up_cam.unproject(&centre).direction.into_inner();
    let [x0, y0, x1, y1] = params.region.unwrap_or([0, 0, up.width, up.height]);
    let (x1, y1) = (x1.min(up.width), y1.min(up.height));
    let cells: Vec<(usize, usize)> =
        (y0 / cell..y1 / cell).flat_map(|cy| (x0 / cell..x1 / cell).map(move |cx| (cx, cy))).collect();
    cells
        .par_iter()
        .filter_map(|&(cx, cy)| {
            // The cell's strongest interest point.
            let (mut best, mut at) = (min_score, None);
            for y in cy * cell..(cy + 1) * cell {
                for x in cx * cell..(cx + 1) * cell {
                    if x >= hw
                        && y >= hw
                        && x + hw < up.width
                        && y + hw < up.height
                        && score[y * up.width + x] > best
                    {
                        (best, at) = (score[y * up.width + x], Some((x, y)));
                    }
                }
            }
            let (x, y) = at?;
            let p1 = Point2::new(x as f64, y as f64);
            let ray1 = up_cam.unproject(&p1);
            let guess = on_prior(&ray1, prior)?;
            let predicted = lo_cam.project(&guess)?;
            // Averaged-image coordinates of the prediction.
            let (gx, gy) = ((predicted.x - 0.5) / 2.0, (predicted.y - 0.5) / 2.0);
            let (sx, sy, ncc) = search(up, (x, y), &small, (gx, gy), params)?;
            let p2 = Point2::new(2.0 * sx + 0.5, 2.0 * sy + 0.5);
            let ray2 = lo_cam.unproject(&p2);
            let point = triangulate(&ray1, &ray2)?;
            let theta = ray1.direction.into_inner().dot(&axis).clamp(-1.0, 1.0).acos();
            let z_m = (point - up_cam.centre()).dot(&axis);
            let tz_m = (lo_cam.centre() - up_cam.centre()).dot(&axis);
            Some(DescentMatch {
                upper_px: [p1.x, p1.y],
                lower_px: [p2.x, p2.y],
                ncc,
                point: [point.x, point.y, point.z],
                theta,
                z_m,
                tz_m,
            })
        })
        .collect()
}

/// Where a ray meets the prior ground (fixed-point iteration on the height).
fn on_prior(ray: &Ray, prior: &(dyn Fn(f64, f64) -> f64 + Sync)) -> Option<Point3<f64>> {
    let (o, d) = (ray.origin, ray.direction.into_inner());
    if d.z > -1e-6 {
        return None;
    }
    let mut z = prior(o.x, o.y);
    for _ in 0..10 {
        let t = (z - o.z) / d.z;
        z = prior(o.x + t * d.x, o.y + t * d.y);
    }
    let t = (z - o.z) / d.z;
    z.is_finite().then(|| ray.at(t))
}

/// Normalised cross-correlation search of the upper window at `p` in the averaged lower
/// image around `guess`: the subpixel peak and its score, or `None` below `min_ncc`, at the
/// search's border or outside the image.
fn search(
    up: &View,
    p: (usize, usize),
    small: &View,
    guess: (f64, f64),
    params: &MatchParams,
) -> Option<(f64, f64, f64)> {
    let hw = params.half_window as isize;
    let r = params.search_px as isize;
    let n = ((2 * hw + 1) * (2 * hw + 1)) as f64;
    let template: Vec<f64> = (-hw..=hw)
        .flat_map(|dy| (-hw..=hw).map(move |dx| (dx, dy)))
        .map(|(dx, dy)| up.at((p.0 as isize + dx) as usize, (p.1 as isize + dy) as usize))
        .collect();
    let tm = template.iter().sum::<f64>() / n;
    let tv: Vec<f64> = template.iter().map(|v| v - tm).collect();
    let tn = tv.iter().map(|v| v * v).sum::<f64>().sqrt();
    let (gx, gy) = (guess.0.round() as isize, guess.1.round() as isize);
    if gx - r - hw < 0
        || gy - r - hw < 0
        || gx + r + hw >= small.width as isize
        || gy + r + hw >= small.height as isize
    {
        return None;
    }
    let side = (2 * r + 1) as usize;
    let mut scores = vec![-1.0; side * side];
    for oy in -r..=r {
        for ox in -r..=r {
            let (cx, cy) = (gx + ox, gy + oy);
            let (mut s, mut s2, mut st) = (0.0, 0.0, 0.0);
            let mut k = 0;
            for dy in -hw..=hw {
                for dx in -hw..=hw {
                    let v = small.at((cx + dx) as usize, (cy + dy) as usize);
                    s += v;
                    s2 += v * v;
                    st += v * tv[k];
                    k += 1;
                }
            }
            let var = s2 - s * s / n;
            if var > 0.0 && tn > 0.0 {
                scores[((oy + r) as usize) * side + (ox + r) as usize] = st / (var.sqrt() * tn);
            }
        }
    }
    let (best, &peak) = scores.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1))?;
    let (bx, by) = (best % side, best / side);
    if peak < params.min_ncc || bx == 0 || by == 0 || bx + 1 == side || by + 1 == side {
        return None;
    }
    let parabola = |a: f64, b: f64, c: f64| {
        let den = a - 2.0 * b + c;
        if den < 0.0 { (0.5 * (a - c) / den).clamp(-0.5, 0.5) } else { 0.0 }
    };
    let at = |x: usize, y: usize| scores[y * side + x];
    let fx = parabola(at(bx - 1, by), peak, at(bx + 1, by));
    let fy = parabola(at(bx, by - 1), peak, at(bx, by + 1));
    Some(((gx - r) as f64 + bx as f64 + fx, (gy - r) as f64 + by as f64 + fy, peak))
}

/// The smaller eigenvalue of the gradient structure tensor summed over each pixel's
/// `(2 hw + 1)^2` window (central differences; 0 near the border).
fn min_eigenvalue(image: &View, hw: usize) -> Vec<f64> {
    let (w, h) = (image.width, image.height);
    let mut sums = vec![[0.0f64; 3]; (w + 1) * (h + 1)];
    for y in 0..h {
        let mut row = [0.0; 3];
        for x in 0..w {
            let (gx, gy) = if x > 0 && y > 0 && x + 1 < w && y + 1 < h {
                (
                    0.5 * (image.at(x + 1, y) - image.at(x - 1, y)),
                    0.5 * (image.at(x, y + 1) - image.at(x, y - 1)),
                )
            } else {
                (0.0, 0.0)
            };
            row[0] += gx * gx;
            row[1] += gy * gy;
            row[2] += gx * gy;
            let above = sums[y * (w + 1) + x + 1];
            sums[(y + 1) * (w + 1) + x + 1] = [above[0] + row[0], above[1] + row[1], above[2] + row[2]];
        }
    }
    let mut out = vec![0.0; w * h];
    for y in hw + 1..h.saturating_sub(hw + 1) {
        for x in hw + 1..w.saturating_sub(hw + 1) {
            let (x0, y0, x1, y1) = (x - hw, y - hw, x + hw + 1, y + hw + 1);
            let s = |k: usize| {
                sums[y1 * (w + 1) + x1][k] - sums[y0 * (w + 1) + x1][k] - sums[y1 * (w + 1) + x0][k]
                    + sums[y0 * (w + 1) + x0][k]
            };
            let (a, b, c) = (s(0), s(1), s(2));
            out[y * w + x] = 0.5 * (a + b) - (0.25 * (a - b).powi(2) + c * c).sqrt();
        }
    }
    out
}

/// The inverse-variance weighted mean height of the points `[x, y, z, sigma]` in each cell of
/// `geometry` (NaN where no point falls; points with a non-positive or non-finite sigma are
/// left out).
pub fn elevation_grid(points: &[[f64; 4]], geometry: GridGeometry) -> Grid2<f32> {
    let mut sums = vec![[0.0f64; 2]; geometry.len()];
    for &[x, y, z, sigma] in points {
        if !(sigma > 0.0 && sigma.is_finite() && z.is_finite()) {
            continue;
        }
        if let Some((c, r)) = geometry.cell_of(x, y) {
            let w = sigma.powi(-2);
            let s = &mut sums[geometry.index(c, r)];
            s[0] += w * z;
            s[1] += w;
        }
    }
    let data = sums.iter().map(|s| if s[1] > 0.0 { (s[0] / s[1]) as f32 } else { f32::NAN }).collect();
    Grid2 { geometry, data }
}

#[cfg(test)]
#[path = "descent_tests.rs"]
mod tests;
