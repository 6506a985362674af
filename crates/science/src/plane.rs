//! The working image of the detectors: a float plane reduced to a working size, with the box
//! filters, masked (normalised) box filters and robust statistics the detectors share.
//!
//! Box filters are separable running sums, so their cost does not depend on the radius; near
//! the border (and outside a mask) a box averages only the pixels it covers (normalised
//! convolution, Knutsson and Westin 1993), so borders are not darkened.

use rovernav_vision::image::GreyF32;

/// A row-major float image.
#[derive(Clone, Debug, PartialEq)]
pub struct Plane {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Row-major values.
    pub data: Vec<f32>,
}

impl Plane {
    /// A plane of `width x height` filled with `value`.
    pub fn filled(width: usize, height: usize, value: f32) -> Self {
        Self { width, height, data: vec![value; width * height] }
    }

    /// The value at column `x`, row `y`.
    pub fn at(&self, x: usize, y: usize) -> f32 {
        self.data[y * self.width + x]
    }

    /// The image reduced by block means of `factor x factor` pixels (partial blocks at the right
    /// and bottom edges average what they hold); non-finite pixels count as 0.
    pub fn reduced(image: &GreyF32, factor: usize) -> Self {
        let f = factor.max(1);
        let (w, h) = (image.width() as usize, image.height() as usize);
        let (rw, rh) = (w.div_ceil(f), h.div_ceil(f));
        let mut sum = vec![0f64; rw * rh];
        let mut count = vec![0u32; rw * rh];
        let raw = image.as_raw();
        for y in 0..h {
            let row = &raw[y * w..(y + 1) * w];
            let base = (y / f) * rw;
            for (x, &v) in row.iter().enumerate() {
                let i = base + x / f;
                sum[i] += if v.is_finite() { v as f64 } else { 0.0 };
                count[i] += 1;
            }
        }
        let data = sum.iter().zip(&count).map(|(s, &c)| (s / c.max(1) as f64) as f32).collect();
        Self { width: rw, height: rh, data }
    }

    /// The image reduced by `factor` and cleared of impulse noise (dead and hot pixels) by a
    /// 3x3 median: the detectors' common noise-reduction step.
    pub fn prepared(image: &GreyF32, factor: usize) -> Self {
        Self::reduced(image, factor).median3()
    }

    /// 3x3 median (the window clipped at the borders).
    pub fn median3(&self) -> Self {
        let (w, h) = (self.width, self.height);
        let mut data = vec![0f32; w * h];
        let mut window = Vec::with_capacity(9);
        for y in 0..h {
            for x in 0..w {
                window.clear();
                for yy in y.saturating_sub(1)..(y + 2).min(h) {
                    for xx in x.saturating_sub(1)..(x + 2).min(w) {
                        window.push(self.data[yy * w + xx]);
                    }
                }
                let mid = window.len() / 2;
                let (_, m, _) = window.select_nth_unstable_by(mid, f32::total_cmp);
                data[y * w + x] = *m;
            }
        }
        Self { width: w, height: h, data }
    }

    /// Box mean of radius `r` (a `(2r+1)^2` window, clipped at the borders).
    pub fn box_mean(&self, r: usize) -> Self {
        let ones = vec![1f32; self.data.len()];
        self.masked_mean_with(&ones, r)
    }

    /// Box mean of radius `r` over the pixels whose `weight` is non-zero (normalised
    /// convolution); a window without weight gives 0.
    pub fn masked_mean_with(&self, weight: &[f32], r: usize) -> Self {
        let weighted: Vec<f32> = self.data.iter().zip(weight).map(|(v, w)| v * w).collect();
        let num = box_sum(&weighted, self.width, self.height, r);
        let den = box_sum(weight, self.width, self.height, r);
        let data = num.iter().zip(&den).map(|(n, d)| if *d > 1e-6 { (n / d) as f32 } else { 0.0 }).collect();
        Self { width: self.width, height: self.height, data }
    }

    /// Local plane fit of radius `r` over the pixels whose `weight` is non-zero, evaluated at
    /// each pixel (normalised convolution with a first-order basis): unlike a box mean it has
    /// no bias from a brightness gradient at the image border or the mask's edge. Falls back to
    /// the masked box mean where the window's pixels lie on a line.
    pub fn masked_plane_fit(&self, weight: &[f32], r: usize) -> Self {
        let (w, h) = (self.width, self.height);
        let (cx, cy) = (0.5 * w as f32, 0.5 * h as f32);
        let term = |f: &dyn Fn(usize, usize, f32, f32) -> f32| -> Vec<f64> {
            let v: Vec<f32> = (0..w * h)
                .map(|i| {
                    let (x, y) = (i % w, i / w);
                    weight[i] * f(x, y, self.data[i], 0.0)
                })
                .collect();
            box_sum(&v, w, h, r)
        };
        let dx = |x: usize| x as f32 - cx;
        let dy = |y: usize| y as f32 - cy;
        let s0 = term(&|_, _, _, _| 1.0);
        let sx = term(&|x, _, _, _| dx(x));
        let sy = term(&|_, y, _, _| dy(y));
        let sxx = term(&|x, _, _, _| dx(x) * dx(x));
        let syy = term(&|_, y, _, _| dy(y) * dy(y));
        let sxy = term(&|x, y, _, _| dx(x) * dy(y));
        let si = term(&|_, _, v, _| v);
        let sxi = term(&|x, _, v, _| dx(x) * v);
        let syi = term(&|_, y, v, _| dy(y) * v);
        let data = (0..w * h)
            .map(|i| {
                if s0[i] < 1e-6 {
                    return 0.0;
                }
                let m =
                    nalgebra::Matrix3::new(s0[i], sx[i], sy[i], sx[i], sxx[i], sxy[i], sy[i], sxy[i], syy[i]);
                let b = nalgebra::Vector3::new(si[i], sxi[i], syi[i]);
                let (x, y) = (dx(i % w) as f64, dy(i / w) as f64);
                let scale = m[(1, 1)] * m[(2, 2)];
                match m.try_inverse() {
                    Some(inv) if m.determinant().abs() > 1e-9 * s0[i] * scale => {
                        let c = inv * b;
                        (c[0] + c[1] * x + c[2] * y) as f32
                    }
                    _ => (si[i] / s0[i]) as f32,
                }
            })
            .collect();
        Self { width: w, height: h, data }
    }
}

/// Sums over a `(2r+1)^2` box clipped at the borders (separable running sums, f64).
pub fn box_sum(values: &[f32], w: usize, h: usize, r: usize) -> Vec<f64> {
    let mut rows = vec![0f64; w * h];
    let mut prefix = vec![0f64; w.max(h) + 1];
    for y in 0..h {
        for x in 0..w {
            prefix[x + 1] = prefix[x] + values[y * w + x] as f64;
        }
        for x in 0..w {
            let (a, b) = (x.saturating_sub(r), (x + r + 1).min(w));
            rows[y * w + x] = prefix[b] - prefix[a];
        }
    }
    let mut out = vec![0f64; w * h];
    for x in 0..w {
        for y in 0..h {
            prefix[y + 1] = prefix[y] + rows[y * w + x];
        }
        for y in 0..h {
            let (a, b) = (y.saturating_sub(r), (y + r + 1).min(h));
            out[y * w + x] = prefix[b] - prefix[a];
        }
    }
    out
}

/// The `q` quantile (0..1) of the finite values (0 for none).
pub fn quantile(values: impl IntoIterator<Item = f32>, q: f64) -> f32 {
    let mut v: Vec<f32> = values.into_iter().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return 0.0;
    }
    let i = ((v.len() - 1) as f64 * q.clamp(0.0, 1.0)).round() as usize;
    let (_, x, _) = v.select_nth_unstable_by(i, f32::total_cmp);
    *x
}

/// Robust standard deviation of zero-mean noise: 1.4826 x the median absolute value.
pub fn robust_sigma(values: impl IntoIterator<Item = f32>) -> f32 {
    1.4826 * quantile(values.into_iter().map(f32::abs), 0.5)
}

/// The reduction factor that brings the longer side to at most `max_side` pixels.
pub fn factor_for(width: u32, height: u32, max_side: usize) -> usize {
    (width.max(height) as usize).div_ceil(max_side.max(1)).max(1)
}

/// The reduction factor that brings the image to at most `max_pixels` pixels.
pub fn factor_for_area(width: u32, height: u32, max_pixels: usize) -> usize {
    let ratio = width as f64 * height as f64 / max_pixels.max(1) as f64;
    (ratio.sqrt().ceil() as usize).max(1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::Luma;

    #[test]
    fn box_mean_equals_brute_force_and_keeps_constants() {
        let (w, h) = (13, 9);
        let p = Plane { width: w, height: h, data: (0..w * h).map(|i| ((i * 37) % 11) as f32).collect() };
        let m = p.box_mean(2);
        for y in 0..h {
            for x in 0..w {
                let (mut s, mut n) = (0.0, 0.0);
                for yy in y.saturating_sub(2)..(y + 3).min(h) {
                    for xx in x.saturating_sub(2)..(x + 3).min(w) {
                        s += p.at(xx, yy);
                        n += 1.0;
                    }
                }
                assert!((m.at(x, y) - s / n).abs() < 1e-4);
            }
        }
        // A plane fit reproduces a linear ramp exactly, also at borders and mask edges.
        let ramp = Plane {
            width: w,
            height: h,
            data: (0..w * h).map(|i| (i % w) as f32 * 2.0 + (i / w) as f32).collect(),
        };
        let weight: Vec<f32> = (0..w * h).map(|i| if i / w < 6 { 1.0 } else { 0.0 }).collect();
        let fit = ramp.masked_plane_fit(&weight, 3);
        for i in 0..w * 6 {
            assert!((fit.data[i] - ramp.data[i]).abs() < 1e-3, "{i}: {} vs {}", fit.data[i], ramp.data[i]);
        }
        let c = Plane::filled(7, 5, 3.5).box_mean(10);
        assert!(c.data.iter().all(|v| (v - 3.5).abs() < 1e-6));
    }

    #[test]
    fn reduction_averages_blocks() {
        let img = GreyF32::from_fn(5, 3, |x, y| Luma([(x + 10 * y) as f32]));
        let r = Plane::reduced(&img, 2);
        assert_eq!((r.width, r.height), (3, 2));
        assert_eq!(r.at(0, 0), (0.0 + 1.0 + 10.0 + 11.0) / 4.0);
        assert_eq!(r.at(2, 1), 24.0);
        assert_eq!(factor_for(7696, 1800, 512), 16);
        assert_eq!(factor_for_area(7696, 1800, 640 * 640), 6);
        assert_eq!(factor_for_area(100, 100, 640 * 640), 1);
        assert_eq!(robust_sigma([1.0, -1.0, 1.0]), 1.4826);
        // A dead pixel in a flat image disappears.
        let mut flat = GreyF32::from_pixel(6, 6, Luma([100.0]));
        flat.put_pixel(3, 2, Luma([0.0]));
        assert!(Plane::prepared(&flat, 1).data.iter().all(|&v| v == 100.0));
    }
}
