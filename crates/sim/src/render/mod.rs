//! Images of the true world: a ray-tracing renderer for the simulator's cameras.
//!
//! One primary ray per pixel (optionally a grid of sub-pixel rays) is cast through any
//! [`CameraModel`] in the world frame against the scene ([`Scene`]: the terrain's exact
//! height field with its rocks, the rover's body, the level ground to the horizon and the sky),
//! shaded with the sun, cast shadows, diffuse sky light, the dust's aerial perspective and the
//! transparent volumes in the air ([`shade`], [`shapes`]), then exposed, made noisy, quantised to
//! 12 bits and optionally compressed by the camera's sensor ([`sensor`]). Rows run in parallel
//! (rayon). Besides the image the renderer returns the ground truth every pixel saw: the true
//! range along the pixel's ray, the label of the surface, and the noise-free radiance.
//!
//! The rover's cameras are in [`rig`]: `Rig::camera(name, pan, tilt)` gives a body- or
//! site-frame model, [`RigCamera::in_world`] moves it with the true pose.

/// The rover's camera calibration (in the vision crate: the autonomy knows it too).
pub use rovernav_vision::rig;
pub mod scene;
pub mod sensor;
pub mod shade;
pub mod shapes;
pub mod sun;

pub use rig::{CAMERA_NAMES, Mount, Rig, RigCamera, pose_isometry};
pub use scene::{Label, Sample, Scene};
pub use sensor::{Exposure, Sensor};
pub use shade::{Atmosphere, Lighting};
pub use shapes::{Primitive, RoverBody, Volume, VolumeShape};
pub use sun::Sun;

use nalgebra::Point2;
use rayon::prelude::*;
use rovernav_vision::CameraModel;
use rovernav_vision::image::Grey16;

/// How to render.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    /// Sub-pixel rays per side (1: one ray per pixel; 2: a 2x2 grid, 4x the time).
    pub supersample: usize,
    /// Whether to cast shadow rays.
    pub shadows: bool,
    /// The camera's detector.
    pub sensor: Sensor,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self { supersample: 1, shadows: true, sensor: Sensor::default() }
    }
}

/// A rendered image and the truth behind it.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderedImage {
    /// The 12-bit image (DN in the low 12 bits).
    pub image: Grey16,
    /// True range (m) along each pixel's centre ray, row-major; infinite for sky.
    pub range: Vec<f32>,
    /// What each pixel's centre ray met first, row-major.
    pub labels: Vec<Label>,
    /// Noise-free radiance factor I/F of each pixel, row-major.
    pub radiance: Vec<f32>,
    /// Exposure used (DN per unit I/F).
    pub exposure: f64,
}

impl RenderedImage {
    /// Width in pixels.
    pub fn width(&self) -> usize {
        self.image.width() as usize
    }

    /// The 8-bit version of the image for people (12-bit DN / 16, rounded).
    pub fn to_8bit(&self) -> rovernav_vision::image::Grey8 {
        let (w, h) = self.image.dimensions();
        rovernav_vision::image::Grey8::from_fn(w, h, |x, y| {
            image::Luma([((self.image.get_pixel(x, y).0[0] as u32 + 8) / 16).min(255) as u8])
        })
    }
}

/// Renders what `camera` (world frame) sees of `scene`; the noise is deterministic for `seed`
/// and the camera's `name`.
pub fn render(
    scene: &Scene,
    camera: &dyn CameraModel,
    name: &str,
    settings: &RenderSettings,
    seed: u64,
) -> RenderedImage {
    let (w, h) = (camera.width(), camera.height());
    let pixel_angle = pixel_angle(camera);
    let ss = settings.supersample.max(1);
    let mut radiance = vec![0f32; w * h];
    let mut range = vec![f32::INFINITY; w * h];
    let mut labels = vec![Label::Sky; w * h];
    radiance
        .par_chunks_mut(w.max(1))
        .zip(range.par_chunks_mut(w.max(1)))
        .zip(labels.par_chunks_mut(w.max(1)))
        .enumerate()
        .for_each(|(row, ((rad, rng), lab))| {
            for col in 0..w {
                let trace = |x: f64, y: f64| {
                    let ray = camera.unproject(&Point2::new(x, y));
                    let d = ray.direction.into_inner();
                    scene.trace(ray.origin.coords.into(), d.into(), pixel_angle / ss as f64, settings.shadows)
                };
                let centre = trace(col as f64, row as f64);
                let mut l = centre.radiance;
                if ss > 1 {
                    l = 0.0;
                    for j in 0..ss {
                        for i in 0..ss {
                            let off = |k: usize| (k as f64 + 0.5) / ss as f64 - 0.5;
                            l += trace(col as f64 + off(i), row as f64 + off(j)).radiance;
                        }
                    }
                    l /= (ss * ss) as f64;
                }
                rad[col] = l as f32;
                rng[col] = centre.range as f32;
                lab[col] = centre.label;
            }
        });
    let exposure = settings.sensor.exposure_for(&radiance);
    let dn = settings.sensor.expose(&radiance, w, exposure, seed, name);
    let image = Grey16::from_raw(w as u32, h as u32, dn).expect("buffer of width x height");
    RenderedImage { image, range, labels, radiance, exposure }
}

/// Angle between the rays of two neighbouring pixels at the image centre (rad).
fn pixel_angle(camera: &dyn CameraModel) -> f64 {
    let (cx, cy) = (0.5 * camera.width() as f64, 0.5 * camera.height() as f64);
    let a = camera.unproject(&Point2::new(cx, cy)).direction;
    let b = camera.unproject(&Point2::new(cx + 1.0, cy)).direction;
    a.dot(&b).clamp(-1.0, 1.0).acos().max(1e-6)
}
