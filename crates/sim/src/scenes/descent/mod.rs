//! A simulated descent sequence (paper 002 section 4): nadir images from a lander's descent
//! camera, one at each halving of altitude, over [`terrain::DescentTerrain`].
//!
//! The camera is a CAHV pinhole ([`rovernav_vision::Cahv`]) looking straight down, image
//! samples along +x (east) and lines along -y (south), 73.4 deg across `size` pixels (the Mars
//! Surveyor'98 descent imager of the paper; 1000 pixels by default). Image k is taken at
//! `top_altitude_m / 2^k` above the landing site, straight above it by default (the paper's
//! ideal purely vertical descent) or horizontally displaced by a drift drawn for the seed
//! (`drift_fraction` of the altitude per axis, the parachute's wander); the lander's navigation
//! is assumed to know every camera pose, so the sequence carries its true cameras.
//!
//! Each pixel's ray is intersected with the ground by fixed-point iteration on the height
//! (`z <- h(x(z), y(z))`, which converges where the ground's slope along the ray is below the
//! ray's elevation, everywhere but on cliffs at the image's edge), and shaded with Lambert's law
//! under a sun 40 deg high plus 15 % diffuse sky, the normal taken from the heights half a
//! pixel either side. The ground is band-limited to two pixels of each image. Detector noise is
//! Gaussian, 1 % of the mean signal, deterministic for the seed.
//!
//! Departures: the renderer of [`crate::render`] ray-casts one height grid with shadows; no
//! grid spans the sequence's 1000:1 range of scales, so this module renders the terrain
//! function directly without cast shadows or occlusion (negligible looking down: a ray leaves
//! nadir by at most 36.7 deg); the camera points exactly down (attitude from the lander's
//! navigation would enter as a rotated CAHV, which the matcher and triangulation handle).

pub mod terrain;

use nalgebra::{Point2, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use rayon::prelude::*;
use rovernav_vision::{Cahv, CameraModel};

pub use terrain::DescentTerrain;

/// The descent imaging plan.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DescentPlan {
    /// Altitude of the first image above the landing site (m; the paper's 6750).
    pub top_altitude_m: f64,
    /// Number of images (the paper's 10).
    pub images: usize,
    /// Image side (pixels; the paper's 1000).
    pub size: usize,
    /// Full field of view across the image (deg; the paper's 73.4).
    pub fov_deg: f64,
    /// Horizontal drift of each camera per axis as a fraction of its altitude (1 sigma).
    pub drift_fraction: f64,
    /// Detector noise as a fraction of the image's mean signal (1 sigma).
    pub noise_fraction: f64,
    /// Sun elevation (deg) and azimuth (deg, counter-clockwise from east).
    pub sun_deg: [f64; 2],
}

impl Default for DescentPlan {
    fn default() -> Self {
        Self {
            top_altitude_m: 6750.0,
            images: 10,
            size: 1000,
            fov_deg: 73.4,
            drift_fraction: 0.0,
            noise_fraction: 0.01,
            sun_deg: [40.0, 120.0],
        }
    }
}

impl DescentPlan {
    /// Focal length in pixels.
    pub fn focal_px(&self) -> f64 {
        0.5 * self.size as f64 / (0.5 * self.fov_deg.to_radians()).tan()
    }
}

/// One descent image with its true camera.
#[derive(Clone, Debug)]
pub struct DescentImage {
    /// Altitude above the landing site (m).
    pub altitude_m: f64,
    /// The camera (world frame of the terrain).
    pub camera: Cahv,
    /// Radiance, row-major, `size * size` (unitless, mean near 0.3).
    pub pixels: Vec<f32>,
    /// Ground size of a pixel straight below the camera at z = 0 (m).
    pub pixel_m: f64,
}

/// The point where a camera's pixel ray meets the ground band-limited at `min_wavelength_m`
/// (fixed-point iteration on the height); `None` if the ray does not point down.
pub fn ground_point(
    terrain: &DescentTerrain,
    camera: &dyn CameraModel,
    pixel: &Point2<f64>,
    min_wavelength_m: f64,
) -> Option<[f64; 3]> {
    let ray = camera.unproject(pixel);
    let d = ray.direction.into_inner();
    if d.z > -1e-6 {
        return None;
    }
    let o = ray.origin;
    let (mut z, mut last) = (0.0, f64::INFINITY);
    let (mut x, mut y) = (o.x, o.y);
    for _ in 0..40 {
        let t = (z - o.z) / d.z;
        (x, y) = (o.x + t * d.x, o.y + t * d.y);
        let h = terrain.height(x, y, min_wavelength_m);
        let step = h - z;
        // Damped once the iteration starts to oscillate (steep ground along the ray).
        z += if step.abs() > last { 0.5 * step } else { step };
        last = step.abs();
        if last < 1e-4 * min_wavelength_m {
            break;
        }
    }
    Some([x, y, z])
}

/// Renders the plan's images over `terrain`, deterministic for `seed` (drift and noise).
pub fn render_sequence(terrain: &DescentTerrain, plan: &DescentPlan, seed: u64) -> Vec<DescentImage> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x0de5_ce47);
    let unit = Normal::new(0.0, 1.0).expect("unit normal");
    let f = plan.focal_px();
    let c = 0.5 * (plan.size as f64 - 1.0);
    (0..plan.images)
        .map(|k| {
            let altitude = plan.top_altitude_m / 2f64.powi(k as i32);
            let drift = plan.drift_fraction * altitude;
            let centre = Vector3::new(drift * unit.sample(&mut rng), drift * unit.sample(&mut rng), altitude);
            let camera = Cahv::from_intrinsics(
                centre,
                Vector3::new(0.0, 0.0, -1.0),
                Vector3::new(1.0, 0.0, 0.0),
                f,
                f,
                c,
                c,
                plan.size,
                plan.size,
            );
            let noise_seed: u64 = rng.random();
            render_image(terrain, plan, camera, altitude, noise_seed)
        })
        .collect()
}

/// Renders one nadir image.
fn render_image(
    terrain: &DescentTerrain,
    plan: &DescentPlan,
    camera: Cahv,
    altitude: f64,
    seed: u64,
) -> DescentImage {
    let n = plan.size;
    let pixel_m = altitude / plan.focal_px();
    let band = 2.0 * pixel_m;
    let (el, az) = (plan.sun_deg[0].to_radians(), plan.sun_deg[1].to_radians());
    let sun = Vector3::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin());
    let mut pixels: Vec<f32> = (0..n * n)
        .into_par_iter()
        .map(|i| {
            let pixel = Point2::new((i % n) as f64, (i / n) as f64);
            let Some([x, y, z]) = ground_point(terrain, &camera, &pixel, band) else { return 0.0 };
            // Ground size of this pixel (grows off-nadir with range).
            let h = 0.5 * pixel_m * (altitude - z).max(1e-3) / altitude;
            let gx = (terrain.height(x + h, y, band) - terrain.height(x - h, y, band)) / (2.0 * h);
            let gy = (terrain.height(x, y + h, band) - terrain.height(x, y - h, band)) / (2.0 * h);
            let normal = Vector3::new(-gx, -gy, 1.0).normalize();
            let light = normal.dot(&sun).max(0.0) + 0.15;
            (terrain.albedo(x, y, band) * light) as f32
        })
        .collect();
    let mean = pixels.iter().map(|&p| p as f64).sum::<f64>() / pixels.len().max(1) as f64;
    let noise = Normal::new(0.0, plan.noise_fraction.max(0.0) * mean).expect("finite noise");
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    for p in &mut pixels {
        *p += noise.sample(&mut rng) as f32;
    }
    DescentImage { altitude_m: altitude, camera, pixels, pixel_m }
}
