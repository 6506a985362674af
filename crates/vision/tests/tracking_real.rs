//! Visual target tracking on a real Mars image (issue 35, "Done when"): templates from the MSL
//! Navcam EDR matched against copies resampled by known scale (0.8..1.25) and roll (±10 deg)
//! with added noise, using the tracker's own magnification and roll compensation; and the NCC
//! score map against imageproc's template matching as an independent implementation.

use image::Luma;
use imageproc::template_matching::{MatchTemplateMethod, match_template};
use nalgebra::Point2;
use rovernav_vision::codec;
use rovernav_vision::image::{Grey8, GreyF32};
use rovernav_vision::tracking::{
    Centring, Prediction, Target, TemplateWarp, TrackOutcome, TrackParams, Tracker, Window, score_map,
};

const NAVCAM: &str = "gale/navcam/NLA_399621413EDR_F0030308NCAM00405M1.IMG";

use rovernav_core::data_file_or_skip as data_file;

fn navcam() -> Option<GreyF32> {
    Some(codec::read_image(data_file(NAVCAM)?).unwrap().to_grey_f32())
}

/// A deterministic standard normal sequence (SplitMix64 and Box-Muller).
fn gaussian(seed: u64) -> impl FnMut() -> f64 {
    let mut s = seed;
    let mut next = move || {
        s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = s;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    };
    move || {
        let (u, v) = (next().max(1e-300), next());
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }
}

/// This test's own bilinear lookup (clamped at the border).
fn sample(img: &GreyF32, x: f64, y: f64) -> f64 {
    let (w, h) = (img.width() as i64, img.height() as i64);
    let (x0, y0) = (x.floor() as i64, y.floor() as i64);
    let (fx, fy) = (x - x0 as f64, y - y0 as f64);
    let at = |xx: i64, yy: i64| img.get_pixel(xx.clamp(0, w - 1) as u32, yy.clamp(0, h - 1) as u32)[0] as f64;
    (1.0 - fy) * ((1.0 - fx) * at(x0, y0) + fx * at(x0 + 1, y0))
        + fy * ((1.0 - fx) * at(x0, y0 + 1) + fx * at(x0 + 1, y0 + 1))
}

/// A size x size patch of `img` seen after the camera rolled by `roll` (rad) about its axis and
/// came closer by the magnification `scale`: the point `p` of `img` appears at `q` of the patch.
/// Image-plane rotation of the scene is -roll (x right, y down); noise of `sigma` DN is added.
#[allow(clippy::too_many_arguments)]
fn transformed_patch(
    img: &GreyF32,
    p: (f64, f64),
    q: (f64, f64),
    size: u32,
    scale: f64,
    roll: f64,
    sigma: f64,
    seed: u64,
) -> GreyF32 {
    let mut g = gaussian(seed);
    // Forward: d' = scale * Rot(-roll) d, so d = Rot(roll) d' / scale.
    let (s, c) = roll.sin_cos();
    GreyF32::from_fn(size, size, |i, j| {
        let (dx, dy) = (i as f64 - q.0, j as f64 - q.1);
        let (sx, sy) = ((c * dx - s * dy) / scale, (s * dx + c * dy) / scale);
        Luma([(sample(img, p.0 + sx, p.1 + sy) + sigma * g()) as f32])
    })
}

/// Textured template centres: the `count` 31x31 windows of highest grey standard deviation on a
/// 64-px grid over the ground (rows 512..960), at least 128 px apart.
fn textured_points(img: &GreyF32, count: usize) -> Vec<(f64, f64)> {
    let mut cands = Vec::new();
    for y in (512..960).step_by(64) {
        for x in (64..960).step_by(64) {
            let vals: Vec<f64> = (0..31)
                .flat_map(|j| (0..31).map(move |i| (i, j)))
                .map(|(i, j)| img.get_pixel(x - 15 + i, y - 15 + j)[0] as f64)
                .collect();
            let m = vals.iter().sum::<f64>() / vals.len() as f64;
            let sd = (vals.iter().map(|v| (v - m).powi(2)).sum::<f64>() / vals.len() as f64).sqrt();
            cands.push((sd, x as f64, y as f64));
        }
    }
    cands.sort_by(|a, b| b.0.total_cmp(&a.0));
    let mut out: Vec<(f64, f64)> = Vec::new();
    for (_, x, y) in cands {
        if out.iter().all(|p| (p.0 - x).hypot(p.1 - y) >= 128.0) {
            out.push((x, y));
        }
        if out.len() == count {
            break;
        }
    }
    out
}

#[test]
fn real_navcam_templates_found_within_one_pixel_across_scale_and_roll() {
    let Some(img) = navcam() else { return };
    let points = textured_points(&img, 4);
    assert_eq!(points.len(), 4);
    let scales = [0.8, 0.9, 1.0, 1.1, 1.25];
    let rolls_deg = [-10.0, -5.0, 0.0, 5.0, 10.0];
    let params = TrackParams::default();
    let half_window = 8;
    let size = 2 * (params.template_half + half_window) as u32 + 7;
    // The known position: off the pixel grid.
    let q = (size as f64 / 2.0 + 0.3, size as f64 / 2.0 - 0.2);
    let (mut ok, mut ok_plain, mut total) = (0, 0, 0);
    let mut table = String::new();
    for &scale in &scales {
        for &roll_deg in &rolls_deg {
            let roll = f64::to_radians(roll_deg);
            let mut cell = 0;
            let mut cell_plain = 0;
            for (k, &p) in points.iter().enumerate() {
                let target = Target {
                    pixel: Point2::new(p.0, p.1),
                    site: nalgebra::Point3::origin(),
                    rover: nalgebra::Point3::origin(),
                    range_m: 10.0,
                    range_sigma_m: 0.1,
                };
                let tracker = Tracker::new(&img, target, 0.0, params).unwrap();
                let seed = 1000 * k as u64 + (scale * 100.0) as u64 + (roll_deg as i64 + 50) as u64 * 7;
                let patch = transformed_patch(&img, p, q, size, scale, roll, 8.0, seed);
                // The prediction is off by (1.5, -1) px, as a motion estimate would be.
                let prediction = Prediction {
                    x: q.0 + 1.5,
                    y: q.1 - 1.0,
                    range_m: 10.0 / scale,
                    sigma_px: 3.0,
                    half_window,
                };
                let found = |warp: &TemplateWarp| match tracker.match_template(&patch, &prediction, warp) {
                    TrackOutcome::Tracked(m) => (m.x - q.0).hypot(m.y - q.1) <= 1.0,
                    TrackOutcome::Lost { .. } => false,
                };
                cell += found(&TemplateWarp::from_range_and_roll(10.0, 10.0 / scale, 0.0, roll)) as usize;
                cell_plain += found(&TemplateWarp::IDENTITY) as usize;
            }
            ok += cell;
            ok_plain += cell_plain;
            total += points.len();
            table += &format!(
                "scale {scale:4.2} roll {roll_deg:+5.1} deg: {cell}/{n} compensated, {cell_plain}/{n} uncompensated\n",
                n = points.len()
            );
        }
    }
    eprintln!("template centres {points:?}\n{table}");
    eprintln!("within 1 px: {ok}/{total} with magnification + roll compensation, {ok_plain}/{total} without");
    assert_eq!(ok, total, "every compensated match within 1 px");
    assert!(
        ok_plain < total,
        "the uncompensated matcher should fail somewhere (else the test proves nothing)"
    );
}

/// A crop of the Navcam quantised to 0..=127 above its minimum, as 8-bit and float images:
/// with such values every sum imageproc forms over a 31x31 window is an integer below 2^24,
/// so its f32 accumulation is exact and differences are this crate's alone.
fn crop7(img: &GreyF32, x0: u32, y0: u32, w: u32, h: u32) -> (Grey8, GreyF32) {
    let vals =
        (0..h).flat_map(|j| (0..w).map(move |i| (i, j))).map(|(i, j)| img.get_pixel(x0 + i, y0 + j)[0]);
    let (min, max) = vals.fold((f32::MAX, f32::MIN), |(lo, hi), v| (lo.min(v), hi.max(v)));
    let step = ((max - min) / 127.0).max(1.0);
    let g8 = Grey8::from_fn(w, h, |i, j| {
        Luma([((img.get_pixel(x0 + i, y0 + j)[0] - min) / step).round().min(127.0) as u8])
    });
    let f = GreyF32::from_fn(w, h, |i, j| Luma([g8.get_pixel(i, j)[0] as f32]));
    (g8, f)
}

#[test]
fn ncc_score_map_matches_imageproc() {
    let Some(img) = navcam() else { return };
    let (x0, y0) = textured_points(&img, 1)[0];
    let (x0, y0) = (x0 as u32 - 40, y0 as u32 - 40);
    let (image8, imagef) = crop7(&img, x0, y0, 81, 81);
    let (templ8, templf) = crop7(&img, x0 + 30, y0 + 27, 31, 31);
    let (tw, th) = (31i64, 31i64);
    let all = Window { x_min: tw / 2, x_max: 80 - tw / 2, y_min: th / 2, y_max: 80 - th / 2 };
    let n = (tw * th) as f64;
    // Raw normalised cross-correlation: imageproc's CrossCorrelationNormalized directly.
    let raw = score_map(&imagef, &templf, &all, Centring::Raw).unwrap();
    let theirs = match_template(&image8, &templ8, MatchTemplateMethod::CrossCorrelationNormalized);
    assert_eq!((theirs.width() as usize, theirs.height() as usize), (raw.width, raw.height));
    let mut worst_raw = 0.0f64;
    for (i, v) in raw.scores.iter().enumerate() {
        let t = theirs.get_pixel((i % raw.width) as u32, (i / raw.width) as u32)[0];
        worst_raw = worst_raw.max((*v as f64 - t as f64).abs());
    }
    // Zero-mean NCC from imageproc's sums: sum(I T), sum(I) (T = ones), sum(I^2) (SSE to zero).
    let zero = score_map(&imagef, &templf, &all, Centring::ZeroMean).unwrap();
    let s_it = match_template(&image8, &templ8, MatchTemplateMethod::CrossCorrelation);
    let s_i =
        match_template(&image8, &Grey8::from_pixel(31, 31, Luma([1])), MatchTemplateMethod::CrossCorrelation);
    let s_ii = match_template(
        &image8,
        &Grey8::from_pixel(31, 31, Luma([0])),
        MatchTemplateMethod::SumOfSquaredErrors,
    );
    let s_t: f64 = templ8.pixels().map(|p| p[0] as f64).sum();
    let s_tt: f64 = templ8.pixels().map(|p| (p[0] as f64).powi(2)).sum();
    let mut worst_zero = 0.0f64;
    for (i, v) in zero.scores.iter().enumerate() {
        let (x, y) = ((i % zero.width) as u32, (i / zero.width) as u32);
        let (a, b, c) =
            (s_it.get_pixel(x, y)[0] as f64, s_i.get_pixel(x, y)[0] as f64, s_ii.get_pixel(x, y)[0] as f64);
        let r = (a - b * s_t / n) / ((c - b * b / n) * (s_tt - s_t * s_t / n)).sqrt();
        worst_zero = worst_zero.max((*v as f64 - r).abs());
    }
    eprintln!("largest difference from imageproc: raw {worst_raw:.2e}, zero-mean {worst_zero:.2e}");
    assert!(worst_raw < 1e-4 && worst_zero < 1e-4);
    // The peak is where the template was cut.
    let best = zero.scores.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)).unwrap().0;
    assert_eq!((zero.x0 + (best % zero.width) as i64, zero.y0 + (best / zero.width) as i64), (45, 42));
}

const TSUKUBA: &str = "stereo/middlebury/tsukuba";

#[test]
fn point_stereo_on_middlebury_tsukuba_matches_ground_truth() {
    use rovernav_vision::Cahv;
    use rovernav_vision::stereo::StereoRig;
    use rovernav_vision::tracking::{PointStereoParams, point_stereo};
    let (Some(l), Some(r), Some(t)) = (
        data_file(&format!("{TSUKUBA}/im3.png")),
        data_file(&format!("{TSUKUBA}/im4.png")),
        data_file(&format!("{TSUKUBA}/disp3.pgm")),
    ) else {
        return;
    };
    let left = codec::read_image(l).unwrap().to_grey_f32();
    let right = codec::read_image(r).unwrap().to_grey_f32();
    let truth = codec::read_image(t).unwrap().to_grey_f32();
    let (w, h) = (left.width() as usize, left.height() as usize);
    // Any rectified rig will do: the disparity is what is checked. f = 600 px, b = 0.1 m.
    let cam = |x: f64| nalgebra::Vector3::new(0.0, -x, 0.0);
    let make = |c| {
        Cahv::from_intrinsics(
            cam(c),
            nalgebra::Vector3::x(),
            -nalgebra::Vector3::y(),
            600.0,
            600.0,
            192.0,
            144.0,
            w,
            h,
        )
    };
    let rig = StereoRig::new(make(0.0), make(0.1)).unwrap();
    let params = PointStereoParams { max_disparity: 20.0, ..PointStereoParams::default() };
    let (mut ok, mut ranged, mut tried, mut sq) = (0, 0, 0, 0.0f64);
    for y in (24..h - 24).step_by(12) {
        for x in (40..w - 24).step_by(12) {
            // Only where the truth is known and constant over the window (no depth edge).
            let d0 = truth.get_pixel(x as u32, y as u32)[0];
            let flat = (0..15u32)
                .all(|j| (0..15u32).all(|i| truth.get_pixel(x as u32 + i - 7, y as u32 + j - 7)[0] == d0));
            if d0 == 0.0 || !flat {
                continue;
            }
            tried += 1;
            let Ok(pr) = point_stereo(&rig, &left, &right, Point2::new(x as f64, y as f64), &params) else {
                continue;
            };
            ranged += 1;
            let err = pr.disparity - d0 as f64 / 16.0;
            sq += err * err;
            ok += (err.abs() <= 1.0) as usize;
            // The range follows the disparity: z = f b / d.
            assert!((pr.depth_m - 60.0 / pr.disparity).abs() < 1e-9);
        }
    }
    let rms = (sq / ranged.max(1) as f64).sqrt();
    eprintln!(
        "Tsukuba point stereo: {ranged}/{tried} ranged, {ok} within 1 px of the truth, rms {rms:.2} px"
    );
    assert!(tried >= 50, "{tried} test points");
    assert!(ranged as f64 >= 0.8 * tried as f64 && ok as f64 >= 0.95 * ranged as f64);
}
