//! Synthetic range data from analytic terrain, for tests and benchmarks: a base surface (flat
//! or tilted plane) with box and hemisphere rocks, sampled by casting rays from a sensor and
//! adding Gaussian range noise from a seeded RNG.

#![allow(dead_code)]

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use rovernav_core::{CameraKind, PointCloud, Pose3, Wedge};

/// Shape of a synthetic rock.
#[derive(Clone, Copy, Debug)]
pub enum Shape {
    /// Square box of side `size`, axis-aligned.
    Box,
    /// Spherical cap of base diameter `size` and the given height.
    Dome,
}

/// A synthetic rock on the base surface.
#[derive(Clone, Copy, Debug)]
pub struct Rock {
    pub x: f64,
    pub y: f64,
    pub size: f64,
    pub height: f64,
    pub shape: Shape,
}

/// Analytic terrain: `z = z0 + gx*x + gy*y` plus rocks.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    pub z0: f64,
    pub gx: f64,
    pub gy: f64,
    pub rocks: Vec<Rock>,
}

impl Scene {
    /// Height of the terrain at (x, y).
    pub fn height(&self, x: f64, y: f64) -> f64 {
        let base = self.z0 + self.gx * x + self.gy * y;
        let mut top: f64 = 0.0;
        for r in &self.rocks {
            let (dx, dy) = (x - r.x, y - r.y);
            let h = match r.shape {
                Shape::Box => {
                    if dx.abs() <= 0.5 * r.size && dy.abs() <= 0.5 * r.size {
                        r.height
                    } else {
                        0.0
                    }
                }
                Shape::Dome => {
                    // Spherical cap through the base circle with the given height.
                    let a = 0.5 * r.size;
                    let radius = (a * a + r.height * r.height) / (2.0 * r.height);
                    let d2 = dx * dx + dy * dy;
                    if d2 >= a * a { 0.0 } else { (radius * radius - d2).sqrt() - (radius - r.height) }
                }
            };
            top = top.max(h);
        }
        base + top
    }
}

/// How a synthetic range image is taken.
#[derive(Clone, Copy, Debug)]
pub struct Shot {
    /// True rover pose.
    pub pose: Pose3,
    /// Visible wedge (body frame).
    pub wedge: Wedge,
    /// Sensor origin in the body frame.
    pub origin: [f64; 3],
    /// Rays across the wedge.
    pub azimuths: usize,
    /// Rays along range.
    pub ranges: usize,
    /// Range noise standard deviation (m).
    pub noise: f64,
    /// RNG seed.
    pub seed: u64,
}

impl Shot {
    /// A mast wedge straight ahead of `pose`: 45 deg wide, 0.5..5 m, sensor at 1.2 m.
    pub fn mast(pose: Pose3, azimuths: usize, ranges: usize, noise: f64, seed: u64) -> Self {
        Self {
            pose,
            wedge: Wedge { bearing: 0.0, half_angle: 22.5f64.to_radians(), min_range: 0.5, max_range: 5.0 },
            origin: [0.0, 0.0, 1.2],
            azimuths,
            ranges,
            noise,
            seed,
        }
    }
}

/// Casts the rays of a shot against the scene; returns the body-frame cloud.
pub fn cast(scene: &Scene, shot: &Shot) -> PointCloud {
    let mut rng = ChaCha8Rng::seed_from_u64(shot.seed);
    let noise = Normal::new(0.0, shot.noise.max(1e-12)).unwrap();
    let pose = shot.pose;
    let o = pose.transform(shot.origin);
    let w = shot.wedge;
    let mut points = Vec::with_capacity(shot.azimuths * shot.ranges);
    for ia in 0..shot.azimuths {
        let az = w.bearing - w.half_angle + 2.0 * w.half_angle * (ia as f64 + 0.5) / shot.azimuths as f64;
        for ir in 0..shot.ranges {
            // Aim at level ground at this horizontal range below the sensor.
            let r = w.min_range + (w.max_range - w.min_range) * (ir as f64 + 0.5) / shot.ranges as f64;
            let body_dir = [az.cos() * r, az.sin() * r, -shot.origin[2]];
            let tip = pose.transform([
                shot.origin[0] + body_dir[0],
                shot.origin[1] + body_dir[1],
                shot.origin[2] + body_dir[2],
            ]);
            let d = [tip[0] - o[0], tip[1] - o[1], tip[2] - o[2]];
            let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            let d = [d[0] / len, d[1] / len, d[2] / len];
            let above = |t: f64| o[2] + t * d[2] - scene.height(o[0] + t * d[0], o[1] + t * d[1]);
            let (mut t0, mut t1) = (0.0, f64::NAN);
            let step = 0.03;
            let mut t = step;
            while t < 2.0 * w.max_range + 3.0 {
                if above(t) <= 0.0 {
                    t1 = t;
                    break;
                }
                t0 = t;
                t += step;
            }
            if t1.is_nan() {
                continue;
            }
            for _ in 0..30 {
                let m = 0.5 * (t0 + t1);
                if above(m) > 0.0 { t0 = m } else { t1 = m }
            }
            let range = t1 + noise.sample(&mut rng);
            let p = [o[0] + range * d[0], o[1] + range * d[1], o[2] + range * d[2]];
            let b = pose.inverse_transform(p);
            points.push([b[0] as f32, b[1] as f32, b[2] as f32]);
        }
    }
    PointCloud { camera: CameraKind::Mast, origin: shot.origin, wedge: w, points }
}
