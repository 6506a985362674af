//! Stereo correlation and triangulation on a synthetic scene with a known answer: a rectified
//! CAHV pair 1.5 m above a randomly textured ground plane, rendered by ray-plane intersection
//! (each pixel the mean of 4x4 rays over its area, 12-bit values with read noise). The
//! correlated range must match the true range within Matthies' predicted sigma.

use nalgebra::{Point2, Vector3};
use rovernav_core::CameraKind;
use rovernav_vision::image::Grey16;
use rovernav_vision::stereo::{self, StereoParams, StereoRig, range::DEFAULT_SIGMA_D_PX};
use rovernav_vision::{Cahv, CameraModel};

/// SplitMix64: a small deterministic generator for the texture and the noise.
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    fn uniform(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn gaussian(&mut self) -> f64 {
        let (u, v) = (self.uniform().max(1e-300), self.uniform());
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }
}

/// Albedo of the ground: two octaves of bilinearly interpolated random values.
struct Texture {
    n: usize,
    fine: Vec<f64>,
    coarse: Vec<f64>,
}

impl Texture {
    const CELL: f64 = 0.04;

    fn new(seed: u64) -> Self {
        let mut rng = SplitMix(seed);
        let n = 512;
        Self {
            n,
            fine: (0..n * n).map(|_| rng.uniform()).collect(),
            coarse: (0..n * n).map(|_| rng.uniform()).collect(),
        }
    }

    fn lerp(&self, grid: &[f64], u: f64, v: f64) -> f64 {
        let (fu, fv) = (u.floor(), v.floor());
        let (i, j) = (fu.rem_euclid(self.n as f64) as usize, fv.rem_euclid(self.n as f64) as usize);
        let (i1, j1) = ((i + 1) % self.n, (j + 1) % self.n);
        let (a, b) = (u - fu, v - fv);
        let at = |i: usize, j: usize| grid[j * self.n + i];
        (1.0 - a) * (1.0 - b) * at(i, j)
            + a * (1.0 - b) * at(i1, j)
            + (1.0 - a) * b * at(i, j1)
            + a * b * at(i1, j1)
    }

    fn albedo(&self, x: f64, y: f64) -> f64 {
        let (u, v) = (x / Self::CELL, y / Self::CELL);
        0.2 + 0.5 * self.lerp(&self.fine, u, v) + 0.3 * self.lerp(&self.coarse, u / 4.0, v / 4.0)
    }
}

/// The point where a pixel's ray meets the ground z = 0, if it does.
fn ground_hit(cam: &Cahv, x: f64, y: f64) -> Option<Vector3<f64>> {
    let ray = cam.unproject(&Point2::new(x, y));
    let dz = ray.direction.z;
    (dz < -1e-6).then(|| ray.at(-ray.origin.z / dz).coords)
}

/// The image of the ground through `cam`: 4x4 rays per pixel, 12 bits, read noise 2 DN.
fn render(cam: &Cahv, texture: &Texture, seed: u64) -> Grey16 {
    let mut rng = SplitMix(seed);
    Grey16::from_fn(cam.width as u32, cam.height as u32, |px, py| {
        let mut sum = 0.0;
        for k in 0..16 {
            let (sx, sy) = (
                f64::from(px) - 0.375 + 0.25 * (k % 4) as f64,
                f64::from(py) - 0.375 + 0.25 * (k / 4) as f64,
            );
            sum += ground_hit(cam, sx, sy).map_or(0.9, |p| texture.albedo(p.x, p.y));
        }
        let dn = 3500.0 * sum / 16.0 + 2.0 * rng.gaussian();
        image::Luma([dn.round().clamp(0.0, 4095.0) as u16])
    })
}

/// A Navcam-like pair in the body frame (x forward, y left, z up): 1.5 m high, pitched 30 deg
/// down, 0.2 m baseline, 320x240 pixels, focal length 300 px.
fn rig() -> StereoRig {
    let pitch = 30f64.to_radians();
    let axis = Vector3::new(pitch.cos(), 0.0, -pitch.sin());
    let right = Vector3::new(0.0, -1.0, 0.0);
    let left =
        Cahv::from_intrinsics(Vector3::new(0.0, 0.1, 1.5), axis, right, 300.0, 300.0, 159.5, 119.5, 320, 240);
    let right_cam = Cahv { c: left.c + left.h_axis() * 0.2, ..left };
    StereoRig::new(left, right_cam).unwrap()
}

#[test]
fn correlated_range_matches_the_plane_within_matthies_sigma() {
    let rig = rig();
    let texture = Texture::new(7);
    let (left, right) = (render(&rig.left, &texture, 1), render(&rig.right, &texture, 2));
    let params = StereoParams { max_disparity: 48, ..StereoParams::default() };
    let disp = stereo::compute_disparity(&left, &right, &params).unwrap();
    let range = rig.range_image(&disp, DEFAULT_SIGMA_D_PX);

    // Truth per pixel: the range to the plane along the pixel's ray and its disparity f b / z.
    let (mut considered, mut valid, mut within, mut d_err2) = (0usize, 0usize, 0usize, 0f64);
    let mut abs_err = Vec::new();
    for y in 0..240 {
        for x in 48..320 {
            let Some(p) = ground_hit(&rig.left, x as f64, y as f64) else { continue };
            considered += 1;
            let i = y * 320 + x;
            if !range.range[i].is_finite() {
                continue;
            }
            valid += 1;
            let true_range = (p - rig.left.c).norm();
            let depth = (p - rig.left.c).dot(&rig.left.a);
            let e = f64::from(range.range[i]) - true_range;
            abs_err.push(e.abs() / f64::from(range.range_sigma[i]));
            within += usize::from(e.abs() <= 3.0 * f64::from(range.range_sigma[i]));
            d_err2 += (f64::from(disp.data[i]) - rig.focal_baseline() / depth).powi(2);
            // The 3-D point lies on the pixel's ray at the reported range.
            let q = Vector3::from(range.points[i].map(f64::from));
            assert!(((q - rig.left.c).norm() - f64::from(range.range[i])).abs() < 1e-3 * true_range);
        }
    }
    abs_err.sort_by(f64::total_cmp);
    let sigma_d = (d_err2 / valid as f64).sqrt();
    let median_in_sigmas = abs_err[abs_err.len() / 2];
    eprintln!(
        "valid {:.3}, within 3 sigma {:.4}, disparity rms error {sigma_d:.3} px, median |error| {median_in_sigmas:.2} sigma",
        valid as f64 / considered as f64,
        within as f64 / valid as f64
    );
    assert!(valid as f64 > 0.9 * considered as f64, "{valid} of {considered}");
    assert!(within as f64 > 0.99 * valid as f64, "{within} of {valid} within 3 sigma");
    // The documented sigma_d is not optimistic: the measured rms disparity error is below it,
    // and a Gaussian's median |error| of 0.67 sigma is not exceeded.
    assert!(sigma_d <= DEFAULT_SIGMA_D_PX, "rms disparity error {sigma_d} px");
    assert!(median_in_sigmas < 0.67, "median |error| {median_in_sigmas} sigma");
}

#[test]
fn the_point_cloud_holds_the_ground_in_the_body_frame() {
    let rig = rig();
    let texture = Texture::new(11);
    let (left, right) = (render(&rig.left, &texture, 3), render(&rig.right, &texture, 4));
    let params = StereoParams { max_disparity: 48, ..StereoParams::default() };
    let disp = stereo::compute_disparity(&left, &right, &params).unwrap();
    let range = rig.range_image(&disp, DEFAULT_SIGMA_D_PX);
    let cloud = rig.point_cloud(&range, CameraKind::Mast, 6.0);
    assert_eq!(cloud.camera, CameraKind::Mast);
    assert_eq!(cloud.origin, [0.0, 0.1, 1.5]);
    assert!(cloud.points.len() > 20_000, "{}", cloud.points.len());
    // Every point is on the ground (z = 0) within 5 sigma at its range, in front of the rover.
    for p in &cloud.points {
        let r = (Vector3::new(p[0], p[1], p[2]).cast::<f64>() - rig.left.c).norm();
        assert!(r <= 6.0 + 1e-3);
        let sigma_z = rig.depth_sigma(r, DEFAULT_SIGMA_D_PX);
        assert!(f64::from(p[2]).abs() < 5.0 * sigma_z + 0.01, "{p:?}");
        assert!(
            p[0] > 0.0 && cloud.wedge.contains(f64::from(p[0]), f64::from(p[1])),
            "{p:?} {:?}",
            cloud.wedge
        );
    }
    assert!((cloud.wedge.bearing).abs() < 1e-12);
    // The wedge is as wide as the widest bearing of the ground seen within 6 m (the bottom
    // corners of a camera pitched down look wider than its +-28 deg), counting the columns
    // the right camera also sees (x >= 48 at the largest disparity) for the lower bound.
    let widest = |x0: u32| {
        (0..240)
            .flat_map(|y| (x0..320).map(move |x| (x, y)))
            .filter_map(|(x, y)| ground_hit(&rig.left, f64::from(x), f64::from(y)))
            .filter(|p| (p - rig.left.c).norm() <= 6.0)
            .map(|p| p.y.atan2(p.x).abs())
            .fold(0.0, f64::max)
    };
    let (outer, matched) = (widest(0), widest(48));
    assert!(cloud.wedge.half_angle <= outer + 1e-3, "{:?} against {outer}", cloud.wedge);
    assert!(cloud.wedge.half_angle > matched - 0.02, "{:?} against {matched}", cloud.wedge);
    assert!(cloud.wedge.min_range > 1.0 && cloud.wedge.max_range < 6.0, "{:?}", cloud.wedge);
}

#[test]
fn a_pair_that_is_not_rectified_is_refused() {
    let r = rig();
    let turned = Cahv { a: (r.left.a + Vector3::new(0.0, 0.01, 0.0)).normalize(), ..r.right };
    assert!(StereoRig::new(r.left, turned).is_err());
    let vertical = Cahv { c: r.left.c + r.left.v_axis() * 0.2, ..r.left };
    assert!(StereoRig::new(r.left, vertical).is_err());
    assert!(StereoRig::new(r.right, r.left).is_err(), "the right camera on the left");
}
