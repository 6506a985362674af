//! Rectification: epipolar lines become rows (checked by projecting 3-D points), images warped
//! through a known distortion come back to the analytic texture, and a rectified pair of a
//! textured plane matches along rows at the disparity f b / depth.

use nalgebra::{Isometry3, Point2, Point3, Translation3, UnitQuaternion, Vector3};
use rovernav_terrain::io::Pds3Label;
use rovernav_vision::camera::{AnyCamera, Cahv, Cahvor, Cahvore, CahvoreType, CameraModel, Movable, read};
use rovernav_vision::image::{GreyF32, Luma};
use rovernav_vision::rectify::{RectifyError, RectifyMap, rectify_models, rectify_pair_f32};

/// A deterministic pseudo-random number in [0, 1) (SplitMix64).
fn uniform(state: &mut u64) -> f64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
}

/// A left/right pair of distorted cameras looking along +x and down, 0.42 m apart along y
/// (the right camera at -y, REP 103), the right one toed in, rolled and offset a little.
fn pair() -> (Cahvor, Cahvor) {
    let left_lin = Cahv::from_intrinsics(
        Vector3::new(0.0, 0.21, 1.9),
        Vector3::new(1.0, 0.0, -0.45),
        Vector3::new(0.0, -1.0, 0.0),
        600.0,
        601.0,
        322.0,
        236.0,
        640,
        480,
    );
    let right_lin = Cahv::from_intrinsics(
        Vector3::new(0.01, -0.21, 1.915),
        Vector3::new(1.0, 0.02, -0.44),
        Vector3::new(0.0, -1.0, 0.01),
        604.0,
        603.5,
        317.0,
        241.0,
        640,
        480,
    );
    let tilt = |a: Vector3<f64>| (a + Vector3::new(0.0, 0.004, 0.006)).normalize();
    (
        Cahvor::new(left_lin, tilt(left_lin.a), Vector3::new(0.0, -0.08, 0.03)),
        Cahvor::new(right_lin, tilt(right_lin.a), Vector3::new(0.001, -0.07, 0.02)),
    )
}

fn check_rows(left: &AnyCamera, right: &AnyCamera, seed: u64) -> f64 {
    let rect = rectify_models(left, right).unwrap();
    let (l, r) = (rect.left, rect.right);
    assert_eq!((l.a, l.h, l.v), (r.a, r.h, r.v), "common A, H, V");
    assert!((l.focal_h() - l.focal_v()).abs() < 1e-9);
    let mut state = seed;
    let mut worst: f64 = 0.0;
    for _ in 0..500 {
        // A point in the left camera's field, 0.5 to 60 m away.
        let px = Point2::new(uniform(&mut state) * 639.0, uniform(&mut state) * 479.0);
        let p = left.unproject(&px).at(0.5 + 60.0 * uniform(&mut state));
        let (Some(a), Some(b)) = (l.project(&p), r.project(&p)) else { continue };
        worst = worst.max((a.y - b.y).abs());
        // Disparity x_left - x_right = f b / depth along A.
        let depth = (p - l.centre()).dot(&l.a);
        let expected = rect.disparity_at_depth(depth);
        assert!(((a.x - b.x) - expected).abs() < 1e-9 * expected.max(1.0), "{} vs {expected}", a.x - b.x);
        assert!(a.x - b.x > 0.0);
    }
    worst
}

#[test]
fn epipolar_lines_are_rows() {
    let (l, r) = pair();
    let worst = check_rows(&l.into(), &r.into(), 1);
    eprintln!("worst row difference {worst:.2e} px");
    assert!(worst < 1e-6);
    // A CAHVORE fish-eye pair too.
    let fish = |m: &Cahvor| {
        Cahvore::new(
            m.linear(),
            m.o,
            Vector3::new(0.0, 0.03, -0.01),
            Vector3::new(0.01, 0.0, 0.0),
            CahvoreType::Fisheye,
        )
    };
    assert!(check_rows(&fish(&l).into(), &fish(&r).into(), 2) < 1e-6);
}

#[test]
fn the_navcam_pair_rectifies_to_rows() {
    let path = rovernav_core::data_dir().join("gale/navcam/NLA_399621413EDR_F0030308NCAM00405M1.IMG");
    if !path.is_file() {
        assert!(std::env::var("ROVERNAV_REQUIRE_DATA").as_deref() != Ok("1"), "{} missing", path.display());
        eprintln!("skipping: data file {} not found (set ROVERNAV_DATA)", path.display());
        return;
    }
    let left = read::from_pds3_label(&Pds3Label::open(&path).unwrap()).unwrap();
    // A right camera 0.424 m along the left one's H' axis (MSL's Navcam baseline), turned
    // 0.5 deg about its centre.
    let lin = left.linear();
    let c = Point3::from(lin.c);
    let turn = UnitQuaternion::from_euler_angles(0.004, -0.006, 0.009);
    let shift = lin.h_axis() * 0.424;
    let pose = Isometry3::from_parts(Translation3::from(c.coords + shift - turn * c.coords), turn);
    let right = left.moved(&pose);
    assert!((right.centre() - c - shift).norm() < 1e-12);
    let worst = check_rows(&left, &right, 3);
    assert!(worst < 1e-6);
    let rect = rectify_models(&left, &right).unwrap();
    assert!((rect.baseline() - 0.424).abs() < 1e-12);
    eprintln!("navcam rectified focal {:.2} px, centre {:?}", rect.focal(), rect.left.image_centre());
}

#[test]
fn degenerate_pairs_are_refused() {
    let (l, _) = pair();
    let err = rectify_models(&l.into(), &l.into()).unwrap_err();
    assert_eq!(err, RectifyError::ZeroBaseline(0.0));
    let ahead = Cahvor { c: l.c + l.a * 0.3, ..l };
    assert!(matches!(rectify_models(&l.into(), &ahead.into()), Err(RectifyError::BaselineAlongAxis(_))));
    let map = RectifyMap::new(&l, &l.linear(), 10.0);
    let err = map.apply_f32(&GreyF32::new(64, 48)).unwrap_err();
    assert_eq!(err.to_string(), "rectify: source image is 64x48, its camera model 640x480");
}

/// A smooth texture with wavelengths of 23 and 31 pixels times `scale`.
fn texture(x: f64, y: f64, scale: f64) -> f64 {
    use std::f64::consts::TAU;
    2000.0 + 700.0 * (TAU * x / (23.0 * scale)).sin() * (TAU * y / (31.0 * scale)).cos() + 0.4 * x - 0.3 * y
}

/// Renders what `camera` sees of a texture painted in `target`'s pixel coordinates (rays taken
/// at `range`), then rectifies it back; returns the mean and largest error against the texture
/// over pixels sampled at least one pixel inside the source image.
fn warp_back(camera: &dyn CameraModel, target: &Cahv, assumed: &dyn CameraModel, scale: f64) -> (f64, f64) {
    let (w, h) = (camera.width() as u32, camera.height() as u32);
    let image = GreyF32::from_fn(w, h, |x, y| {
        let ray = camera.unproject(&Point2::new(x as f64, y as f64));
        let q = target.project(&ray.at(10.0)).unwrap();
        Luma([texture(q.x, q.y, scale) as f32])
    });
    let map = RectifyMap::new(assumed, target, 10.0);
    let back = map.apply_f32(&image).unwrap();
    let (mut sum, mut worst, mut n) = (0.0, 0.0f64, 0usize);
    for y in 0..target.height {
        for x in 0..target.width {
            let [sx, sy] = map.source[y * target.width + x];
            if !(sx >= 1.0 && sy >= 1.0 && sx <= w as f32 - 2.0 && sy <= h as f32 - 2.0) {
                continue;
            }
            let err =
                (back.get_pixel(x as u32, y as u32)[0] as f64 - texture(x as f64, y as f64, scale)).abs();
            sum += err;
            worst = worst.max(err);
            n += 1;
        }
    }
    assert!(n > target.width * target.height / 2, "most of the output is covered ({n})");
    (sum / n as f64, worst)
}

#[test]
fn a_known_distortion_warped_and_rectified_back_matches() {
    let (l, r) = pair();
    let rect = rectify_models(&l.into(), &r.into()).unwrap();
    let (mean, worst) = warp_back(&l, &rect.left, &l, 1.0);
    // Bilinear interpolation of this texture errs by at most 700 ((2 pi / 23)^2 +
    // (2 pi / 31)^2) / 8 = 10 DN times the square of the source pixel spacing (in output
    // pixels; about 1 here, up to 1.2 where the distortion compresses the field).
    eprintln!("CAHVOR warped back: mean {mean:.2} DN, worst {worst:.2} DN");
    assert!(mean < 3.0 && worst < 15.0);
    // Ignoring the distortion (resampling as if the camera were its linear part) fails.
    let (mean_lin, _) = warp_back(&l, &rect.left, &l.linear(), 1.0);
    eprintln!("same image resampled without the R terms: mean {mean_lin:.1} DN");
    assert!(mean_lin > 10.0 * mean);
    // A fish-eye CAHVORE (about 120 deg across) into a 95 deg linear view.
    let fish = Cahvore::new(
        Cahv::from_intrinsics(l.c, l.a, Vector3::new(0.0, -1.0, 0.0), 260.0, 260.0, 321.0, 238.0, 640, 480),
        l.o,
        Vector3::new(0.0, 0.02, -0.005),
        Vector3::new(0.01, -0.005, 0.0),
        CahvoreType::Fisheye,
    );
    let target =
        Cahv::from_intrinsics(l.c, l.a, Vector3::new(0.0, -1.0, 0.0), 300.0, 300.0, 319.5, 239.5, 640, 480);
    // Towards the edges of the linear view one fish-eye pixel spans up to 2.5 output pixels,
    // so the texture is three times coarser here (bound 10 / 9 x 2.5^2 = 7 DN).
    let (mean, worst) = warp_back(&fish, &target, &fish, 3.0);
    eprintln!("CAHVORE warped back: mean {mean:.2} DN, worst {worst:.2} DN");
    assert!(mean < 3.0 && worst < 15.0);
}

#[test]
fn a_rectified_pair_of_a_plane_matches_along_rows() {
    let (l, r) = pair();
    let (la, ra): (AnyCamera, AnyCamera) = (l.into(), r.into());
    // A wall 6 m ahead (x = 6), textured in metres.
    let wall = |p: &Point3<f64>| {
        2000.0 + 600.0 * (p.y * 23.0).sin() * (p.z * 19.0).cos() + 300.0 * (p.y * 7.0 + p.z * 11.0).sin()
    };
    let hit = |cam: &dyn CameraModel, x: f64, y: f64| {
        let ray = cam.unproject(&Point2::new(x, y));
        let t = (6.0 - ray.origin.x) / ray.direction.x;
        ray.at(t)
    };
    let render = |cam: &AnyCamera| {
        GreyF32::from_fn(640, 480, |x, y| Luma([wall(&hit(cam, x as f64, y as f64)) as f32]))
    };
    let pair = rectify_pair_f32(&render(&la), &la, &render(&ra), &ra, 6.0).unwrap();
    let m = pair.models;
    let bilinear = |img: &GreyF32, x: f64, y: f64| {
        let (x0, y0) = (x.floor() as u32, y.floor() as u32);
        let (fx, fy) = ((x - x0 as f64) as f32, (y - y0 as f64) as f32);
        let g = |dx, dy| img.get_pixel(x0 + dx, y0 + dy)[0];
        ((g(0, 0) * (1.0 - fx) + g(1, 0) * fx) * (1.0 - fy) + (g(0, 1) * (1.0 - fx) + g(1, 1) * fx) * fy)
            as f64
    };
    let (mut same_row, mut off_row, mut n) = (0.0, 0.0, 0usize);
    for y in (40..440).step_by(7) {
        for x in (40..600).step_by(7) {
            let p = hit(&m.left, x as f64, y as f64);
            let d = m.disparity_at_depth((p - m.left.centre()).dot(&m.left.a));
            let xr = x as f64 - d;
            if !(2.0..636.0).contains(&xr) {
                continue;
            }
            let left = pair.left.get_pixel(x, y)[0] as f64;
            same_row += (left - bilinear(&pair.right, xr, y as f64)).abs();
            off_row += (left - bilinear(&pair.right, xr, y as f64 + 1.0)).abs();
            n += 1;
        }
    }
    let (same_row, off_row) = (same_row / n as f64, off_row / n as f64);
    eprintln!(
        "plane pair: mean difference on the same row {same_row:.2} DN, one row off {off_row:.1} DN ({n} px)"
    );
    assert!(n > 3000);
    assert!(same_row < 5.0 && off_row > 10.0 * same_row);
}
