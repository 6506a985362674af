//! The census transform and the matching cost volume.
//!
//! The census transform (Zabih and Woodfill, "Non-parametric local transforms for computing
//! visual correspondence", ECCV 1994) encodes each pixel by which of its neighbours in a window
//! are darker than it; the matching cost of two pixels is the Hamming distance of their codes.
//! It depends only on the order of intensities, so a gain or offset between the two cameras
//! does not change it. The window here is 9 wide by 7 high (62 bits, one `u64`), the size
//! Hirschmüller and Scharstein (PAMI 31(9), 2009) evaluated for SGM.

use rayon::prelude::*;

use crate::image::Grey16;

/// Half-width of the census window (9 columns).
pub const HALF_W: usize = 4;
/// Half-height of the census window (7 rows).
pub const HALF_H: usize = 3;
/// The largest census cost: the number of neighbours compared.
pub const MAX_COST: u8 = ((2 * HALF_W + 1) * (2 * HALF_H + 1) - 1) as u8;

/// Both images as `f32` on a common scale where the 99.9th percentile of both images' pixels
/// maps to 255, so intensity thresholds mean the same for 8-, 12- and 16-bit data and a few
/// hot pixels do not compress the scale (brighter pixels go above 255; the census and the
/// thresholds need no clamping).
pub fn normalise_pair(left: &Grey16, right: &Grey16) -> (Vec<f32>, Vec<f32>) {
    let mut histogram = vec![0usize; 1 << 16];
    for &v in left.as_raw().iter().chain(right.as_raw()) {
        histogram[usize::from(v)] += 1;
    }
    let total: usize = histogram.iter().sum();
    let mut below = 0usize;
    let mut high = 1usize;
    for (v, &n) in histogram.iter().enumerate() {
        below += n;
        if below as f64 >= 0.999 * total as f64 {
            high = v.max(1);
            break;
        }
    }
    let scale = 255.0 / high as f32;
    let conv = |img: &Grey16| img.as_raw().iter().map(|&v| f32::from(v) * scale).collect();
    (conv(left), conv(right))
}

/// The census code of every pixel (row-major); the window is clamped at the image borders.
/// Each window row is copied once into a buffer padded by replicating its end pixels, so the
/// comparisons for one offset run over contiguous slices (a loop the compiler vectorises).
pub fn census(img: &[f32], w: usize, h: usize) -> Vec<u64> {
    let mut out = vec![0u64; w * h];
    out.par_chunks_mut(w).enumerate().for_each(|(y, codes)| {
        let centre = &img[y * w..(y + 1) * w];
        let mut padded = vec![0f32; w + 2 * HALF_W];
        for k in 0..=2 * HALF_H {
            let yy = (y + k).saturating_sub(HALF_H).min(h - 1);
            let row = &img[yy * w..(yy + 1) * w];
            padded[..HALF_W].fill(row[0]);
            padded[HALF_W..HALF_W + w].copy_from_slice(row);
            padded[HALF_W + w..].fill(row[w - 1]);
            for j in 0..=2 * HALF_W {
                if k == HALF_H && j == HALF_W {
                    continue;
                }
                for ((code, &c), &n) in codes.iter_mut().zip(centre).zip(&padded[j..j + w]) {
                    *code = (*code << 1) | u64::from(n < c);
                }
            }
        }
    });
    out
}

/// The cost volume `C[(y * w + x) * nd + d]`: the Hamming distance between the census codes of
/// left pixel (x, y) and right pixel (x - d, y); [`MAX_COST`] where x - d leaves the image.
pub fn cost_volume(left: &[f32], right: &[f32], w: usize, h: usize, nd: usize) -> Vec<u8> {
    let (cl, cr) = rayon::join(|| census(left, w, h), || census(right, w, h));
    let mut costs = vec![MAX_COST; w * h * nd];
    costs.par_chunks_mut(w * nd).enumerate().for_each(|(y, row)| {
        let (l, r) = (&cl[y * w..(y + 1) * w], &cr[y * w..(y + 1) * w]);
        for (x, cell) in row.chunks_exact_mut(nd).enumerate() {
            for (d, c) in cell.iter_mut().enumerate().take(x + 1) {
                *c = (l[x] ^ r[x - d]).count_ones() as u8;
            }
        }
    });
    costs
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hot_pixels_do_not_set_the_scale() {
        // A 12-bit image up to 1000 DN with 0.05 % of its pixels saturated at 4095.
        let img = Grey16::from_fn(100, 100, |x, y| {
            image::Luma([if (x, y) == (3, 4) || (x, y) == (50, 60) {
                4095
            } else {
                ((x * 7 + y * 3) % 1001) as u16
            }])
        });
        let (a, _) = normalise_pair(&img, &img);
        let p = |x: usize, y: usize| a[y * 100 + x];
        assert!((p(0, 0) - 0.0).abs() < 1e-6);
        assert!(p(3, 4) > 1000.0, "the hot pixel stays above the scale");
        let hot = [4 * 100 + 3, 60 * 100 + 50];
        let max_normal = (0..100 * 100).filter(|i| !hot.contains(i)).map(|i| a[i]).fold(0.0, f32::max);
        assert!((250.0..=265.0).contains(&max_normal), "{max_normal}");
    }

    /// The census code of one pixel computed literally, bit by bit, with clamped coordinates.
    fn census_at(img: &[f32], w: usize, h: usize, x: usize, y: usize) -> u64 {
        let mut c = 0u64;
        for dy in -(HALF_H as isize)..=HALF_H as isize {
            for dx in -(HALF_W as isize)..=HALF_W as isize {
                if (dx, dy) == (0, 0) {
                    continue;
                }
                let xx = (x as isize + dx).clamp(0, w as isize - 1) as usize;
                let yy = (y as isize + dy).clamp(0, h as isize - 1) as usize;
                c = (c << 1) | u64::from(img[yy * w + xx] < img[y * w + x]);
            }
        }
        c
    }

    #[test]
    fn census_matches_the_definition_at_every_pixel() {
        for (w, h) in [(23, 17), (3, 2), (1, 1)] {
            let img: Vec<f32> = (0..w * h).map(|i| ((i * 7919 + 13) % 101) as f32).collect();
            let codes = census(&img, w, h);
            for y in 0..h {
                for x in 0..w {
                    assert_eq!(codes[y * w + x], census_at(&img, w, h, x, y), "({x},{y}) in {w}x{h}");
                }
            }
        }
    }

    #[test]
    fn census_is_invariant_to_gain_and_offset() {
        let (w, h) = (20, 12);
        let img: Vec<f32> = (0..w * h).map(|i| ((i * 7919) % 97) as f32).collect();
        let brighter: Vec<f32> = img.iter().map(|v| 3.0 * v + 11.0).collect();
        assert_eq!(census(&img, w, h), census(&brighter, w, h));
    }

    #[test]
    fn the_true_shift_has_zero_cost() {
        // Right image = left image shifted by 5 pixels: C(x, 5) = 0 wherever the windows agree.
        let (w, h, shift) = (40, 10, 5);
        let left: Vec<f32> = (0..w * h).map(|i| ((i * 2654435761usize) % 251) as f32).collect();
        let right: Vec<f32> = (0..w * h).map(|i| left[(i / w) * w + ((i % w) + shift).min(w - 1)]).collect();
        let costs = cost_volume(&left, &right, w, h, 8);
        for y in 0..h {
            for x in shift + HALF_W..w - HALF_W - shift {
                let cell = &costs[(y * w + x) * 8..(y * w + x + 1) * 8];
                assert_eq!(cell[shift], 0, "({x},{y})");
                assert!(cell.iter().enumerate().all(|(d, &c)| d == shift || c > 0), "({x},{y}) {cell:?}");
            }
        }
    }
}
