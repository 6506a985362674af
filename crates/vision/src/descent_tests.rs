//! Tests of [`super`]: the paper's formula against triangulation worked by hand, and the
//! matcher on a synthetic pair (a flat plane with a bump) against its known heights.

use nalgebra::{Point2, Point3, Vector3};

use super::*;
use crate::camera::Cahv;

/// A nadir camera at height `z` above (0, 0), `n` pixels square, focal `f` pixels.
fn nadir(z: f64, n: usize, f: f64) -> Cahv {
    let c = 0.5 * (n as f64 - 1.0);
    Cahv::from_intrinsics(
        Vector3::new(0.0, 0.0, z),
        Vector3::new(0.0, 0.0, -1.0),
        Vector3::new(1.0, 0.0, 0.0),
        f,
        f,
        c,
        c,
        n,
        n,
    )
}

#[test]
fn formula_matches_triangulation_worked_by_hand() {
    let f = 500.0;
    let (up, lo) = (nadir(100.0, 501, f), nadir(50.0, 501, f));
    for (r, h) in [(30.0, 0.0), (20.0, 3.0), (45.0, -2.0)] {
        let truth = Point3::new(r, 0.0, h);
        let (p1, p2) = (up.project(&truth).unwrap(), lo.project(&truth).unwrap());
        let exact = triangulate(&up.unproject(&p1), &lo.unproject(&p2)).unwrap();
        assert!((exact - truth).norm() < 1e-6, "{exact} vs {truth}");
        // Move the lower image's match 0.1 pixel outward along the radius and triangulate.
        let delta = 0.1;
        let moved = triangulate(&up.unproject(&p1), &lo.unproject(&Point2::new(p2.x + delta, p2.y))).unwrap();
        // By hand: Z = T_z t2 / (t2 - t1), tangents read off the pixels.
        let (t1, t2) = ((p1.x - 250.0) / f, (p2.x + delta - 250.0) / f);
        let by_hand = 100.0 - 50.0 * t2 / (t2 - t1);
        assert!((moved.z - by_hand).abs() < 1e-3 * (moved.z - h).abs(), "{} vs {by_hand}", moved.z);
        let predicted = predicted_sigma(100.0 - h, 50.0, (r / (100.0 - h)).atan(), delta / f);
        let err = (moved.z - h).abs();
        assert!(
            (err / predicted - 1.0).abs() < 0.03,
            "r {r} h {h}: error {err:.4} vs predicted {predicted:.4}"
        );
    }
    assert!(predicted_sigma(100.0, 50.0, 0.0, 1e-4).is_infinite());
}

/// Hashed value noise on a 0.6 m lattice, bilinear (the ground's albedo).
fn albedo(x: f64, y: f64) -> f64 {
    let (u, v) = (x / 0.6, y / 0.6);
    let (i, j) = (u.floor(), v.floor());
    let corner = |a: f64, b: f64| {
        let mut h = (a as i64 as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15)
            ^ (b as i64 as u64).wrapping_mul(0xc2b2_ae3d);
        h ^= h >> 29;
        h = h.wrapping_mul(0xbf58_476d_1ce4_e5b9);
        h ^= h >> 32;
        (h % 1000) as f64 / 1000.0
    };
    let (fx, fy) = (u - i, v - j);
    let top = corner(i, j) * (1.0 - fx) + corner(i + 1.0, j) * fx;
    let bottom = corner(i, j + 1.0) * (1.0 - fx) + corner(i + 1.0, j + 1.0) * fx;
    0.2 + 0.6 * (top * (1.0 - fy) + bottom * fy)
}

/// A flat plane with a 4 m Gaussian bump of 6 m radius at (8, 5).
fn ground(x: f64, y: f64) -> f64 {
    4.0 * (-((x - 8.0).powi(2) + (y - 5.0).powi(2)) / 36.0).exp()
}

/// Renders the textured ground seen by a camera (ray-ground by fixed point, 2x2 supersampled).
fn render(cam: &Cahv) -> Vec<f32> {
    let n = cam.width;
    (0..n * n)
        .map(|i| {
            let mut sum = 0.0;
            for (ox, oy) in [(-0.25, -0.25), (0.25, -0.25), (-0.25, 0.25), (0.25, 0.25)] {
                let ray = cam.unproject(&Point2::new((i % n) as f64 + ox, (i / n) as f64 + oy));
                let (o, d) = (ray.origin, ray.direction.into_inner());
                let mut z = 0.0;
                for _ in 0..30 {
                    let t = (z - o.z) / d.z;
                    z = ground(o.x + t * d.x, o.y + t * d.y);
                }
                let t = (z - o.z) / d.z;
                sum += albedo(o.x + t * d.x, o.y + t * d.y);
            }
            (0.25 * sum) as f32
        })
        .collect()
}

#[test]
fn matched_elevations_lie_within_their_predicted_precision_of_the_truth() {
    let (n, f) = (200, 140.0);
    let (up, lo) = (nadir(60.0, n, f), nadir(30.0, n, f));
    let (a, b) = (render(&up), render(&lo));
    let (va, vb) = (View { pixels: &a, width: n, height: n }, View { pixels: &b, width: n, height: n });
    let matches = match_pair(
        (&va, &up),
        (&vb, &lo),
        &|_, _| 0.0,
        &MatchParams { cell_px: 4, search_px: 7, ..Default::default() },
    );
    // Points far enough from the centre for the parallax to carry elevation.
    let usable: Vec<_> = matches.iter().filter(|m| m.theta.tan() > 0.15).collect();
    assert!(usable.len() > 60, "{} usable matches of {}", usable.len(), matches.len());
    // Each point's error against the known ground, in units of the paper's precision for a
    // matching precision of 0.25 pixel (a Gaussian error would put 90 % within 1.64 of them).
    let mut normalised: Vec<f64> = usable
        .iter()
        .map(|m| (m.point[2] - ground(m.point[0], m.point[1])) / m.predicted_sigma(0.25, f))
        .collect();
    normalised.sort_by(|a, b| a.abs().total_cmp(&b.abs()));
    let p90 = normalised[normalised.len() * 9 / 10].abs();
    eprintln!(
        "{} usable of {} matches; |error| / sigma(0.25 px): median {:.2}, p90 {p90:.2}",
        usable.len(),
        matches.len(),
        normalised[normalised.len() / 2].abs()
    );
    assert!(p90 < 2.0, "90th percentile of |error| / predicted sigma: {p90:.2}");
    // The bump is seen: points on it triangulate well above the plane.
    let on_bump = usable.iter().filter(|m| ground(m.point[0], m.point[1]) > 3.0).collect::<Vec<_>>();
    assert!(!on_bump.is_empty() && on_bump.iter().all(|m| m.point[2] > 1.5));
}

#[test]
fn grid_weights_points_by_inverse_variance() {
    let g = GridGeometry { cols: 2, rows: 1, resolution: 1.0, origin_x: 0.0, origin_y: 0.0 };
    let grid = elevation_grid(&[[0.5, 0.5, 1.0, 1.0], [0.2, 0.7, 4.0, 2.0], [5.0, 0.5, 9.0, 1.0]], g);
    assert!((grid.data[0] - 1.6).abs() < 1e-6, "{}", grid.data[0]);
    assert!(grid.data[1].is_nan());
    let (small, w, h) = downsample_2x(&View { pixels: &[1.0, 3.0, 5.0, 7.0], width: 2, height: 2 });
    assert_eq!((small, w, h), (vec![4.0], 1, 1));
}
