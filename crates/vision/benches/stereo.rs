//! Stereo correlation speed per megapixel at 64 disparities (`cargo bench -p rovernav-vision
//! --bench stereo`). The baseline, measured in the same run, is a naive local correlation:
//! for every pixel and disparity the sum of absolute differences over a 9x7 window summed
//! from scratch, then winner-take-all (no running sums, no aggregation, no filters), rayon
//! across rows like the matcher. The ratio says what semi-global matching with its
//! consistency check and filters costs against brute-force window correlation.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use rayon::prelude::*;
use rovernav_vision::image::{Grey16, Luma};
use rovernav_vision::stereo::{self, StereoParams};

const W: u32 = 640;
const H: u32 = 480;
const DISPARITIES: usize = 64;

/// A random texture and its right view: a slanted plane, disparity 10 at the top to 50 at the
/// bottom, sampled with linear interpolation.
fn pair() -> (Grey16, Grey16) {
    let noise = |x: u32, y: u32| {
        let mut z = u64::from(x) << 32 | u64::from(y);
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) % 4096) as f64
    };
    let texture = |x: f64, y: u32| {
        let (i, f) = (x.floor(), x - x.floor());
        let i = i.max(0.0) as u32;
        // 2x2-pixel blocks of noise, interpolated along the row.
        let block = |i: u32| noise(i / 2, y / 2);
        (1.0 - f) * block(i) + f * block(i + 1)
    };
    let left = Grey16::from_fn(W, H, |x, y| Luma([texture(f64::from(x) + 60.0, y) as u16]));
    let right = Grey16::from_fn(W, H, |x, y| {
        let d = 10.0 + 40.0 * f64::from(y) / f64::from(H);
        Luma([texture(f64::from(x) + 60.0 + d, y) as u16])
    });
    (left, right)
}

/// Brute-force 9x7 SAD with winner-take-all: the disparity of every left pixel.
fn naive_sad(left: &Grey16, right: &Grey16, nd: usize) -> Vec<u8> {
    let (w, h) = (left.width() as usize, left.height() as usize);
    let (l, r) = (left.as_raw(), right.as_raw());
    let mut out = vec![0u8; w * h];
    out.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        if y < 3 || y + 3 >= h {
            return;
        }
        for (x, o) in row.iter_mut().enumerate().take(w - 4).skip(4) {
            let (mut best, mut best_d) = (u32::MAX, 0);
            for d in 0..nd.min(x - 3) {
                let mut sad = 0u32;
                for yy in y - 3..=y + 3 {
                    for xx in x - 4..=x + 4 {
                        sad += u32::from(l[yy * w + xx].abs_diff(r[yy * w + xx - d]));
                    }
                }
                if sad < best {
                    (best, best_d) = (sad, d);
                }
            }
            *o = best_d as u8;
        }
    });
    out
}

fn bench(c: &mut Criterion) {
    let (left, right) = pair();
    let params = StereoParams { max_disparity: DISPARITIES - 1, ..StereoParams::default() };
    let mut group = c.benchmark_group("stereo_640x480_64_disparities");
    group.sample_size(10);
    group.throughput(Throughput::Elements(u64::from(W * H)));
    group.bench_function("sgm_census_8_paths_lr_filters", |b| {
        b.iter(|| stereo::compute_disparity(&left, &right, &params).unwrap())
    });
    group.bench_function("baseline_naive_sad_9x7", |b| b.iter(|| naive_sad(&left, &right, DISPARITIES)));
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
