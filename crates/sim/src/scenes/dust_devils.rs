//! Fixed-camera sequences with and without dust devils for the dust-devil detector (paper 003
//! section 5.2: "dust devils are high dust opacity features on a dusty background and often have
//! a faint signature in an image").
//!
//! A sequence is 6 to 20 frames 5 to 20 s apart from a Navcam looking at the horizon (tilt -8
//! to +2 deg) on a rover standing still (small roll and pitch). Dust devils (Gusev: tens to a
//! few hundred metres across, hundreds of metres high, moving at a few m/s; Greeley et al.
//! 2006) are vertical columns standing on the far ground 150 to 2500 m away, radius 4 to 40 m,
//! height 100 to 600 m, drifting at 1 to 6 m/s, alive for part of the sequence; faint ones have
//! a centre optical depth of 0.003 to 0.015 (peak contrast about 1 to 3 %), distinct ones 0.04
//! to 0.15. Half the sequences with dust devils have faint ones. A third of the sequences
//! have none.
//!
//! Truth per frame: a dust devil is present when at least [`MIN_DEVIL_PIXELS`] pixels differ
//! from the scene without it by [`VISIBLE_CONTRAST`] or more.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::{Site, event_extent, science_settings, volume_contrast};
use crate::render::{Atmosphere, RenderedImage, Scene, Sun, Volume, VolumeShape, render};

/// Relative contrast at which a dust-devil pixel counts as visible.
pub const VISIBLE_CONTRAST: f32 = 0.008;
/// Fewest visible pixels of a labelled dust devil.
pub const MIN_DEVIL_PIXELS: usize = 6;

/// The truth of one frame.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameTruth {
    /// Whether a dust devil is visible (the label).
    pub present: bool,
    /// Whether the sequence's dust devils were generated faint.
    pub faint: bool,
    /// Peak relative contrast.
    pub peak_contrast: f32,
    /// Visible pixels.
    pub pixels: usize,
    /// Bounding box of the visible pixels `[x, y, width, height]`.
    pub bbox: Option<[u32; 4]>,
}

/// One rendered, labelled sequence.
pub struct DustDevilSequence {
    /// The frames with their per-pixel truth.
    pub frames: Vec<RenderedImage>,
    /// One truth per frame.
    pub truth: Vec<FrameTruth>,
    /// Seconds between frames.
    pub interval_s: f64,
}

/// Renders sequence `index` of the set of `seed` at `size` pixels square, `frames` long, raw or
/// block-compressed at `quality` (deterministic).
pub fn dust_devil_sequence(
    site: &Site,
    index: usize,
    frames: usize,
    size: usize,
    seed: u64,
    quality: Option<u8>,
) -> DustDevilSequence {
    let mut rng = ChaCha8Rng::seed_from_u64(seed.wrapping_mul(0xD1B5_4A32).wrapping_add(index as u64));
    let with_devils = !index.is_multiple_of(3);
    let faint = rng.random_bool(0.5);
    let pose =
        site.pose(rng.random_range(-0.06..0.06), rng.random_range(-0.05..0.05), rng.random_range(-3.1..3.1));
    let pan = rng.random_range(-3.1..3.1);
    let tilt = rng.random_range(-8f64..2.0).to_radians();
    let camera = site.navcam(&pose, pan, tilt, size);
    let sun = Sun::on_mars(rng.random_range(10.0..15.5), -14.6, rng.random_range(180.0..330.0));
    let atmosphere = Atmosphere { tau: rng.random_range(0.3..1.0), ..Atmosphere::default() };
    let interval_s = rng.random_range(5.0..20.0);
    let start = rng.random_range(0.0..3600.0);
    // Each devil: a volume and its life (first and last frame alive).
    let mut devils: Vec<(Volume, usize, usize)> = Vec::new();
    if with_devils {
        let count = if rng.random_bool(0.25) { 2 } else { 1 };
        for _ in 0..count {
            devils.push(make_devil(&mut rng, &camera, site.ground_z, faint, frames, interval_s, start));
        }
    }
    let mut out = Vec::with_capacity(frames);
    let mut truth = Vec::with_capacity(frames);
    for k in 0..frames {
        let mut scene = Scene::new(&site.terrain, &site.field, &sun, atmosphere);
        scene.time = start + k as f64 * interval_s;
        scene.volumes = devils.iter().filter(|d| (d.1..=d.2).contains(&k)).map(|d| d.0).collect();
        let rendered = render(
            &scene,
            &camera,
            "navcam_left",
            &science_settings(quality),
            seed ^ (index * 64 + k) as u64,
        );
        let contrast = volume_contrast(&scene, &camera, &rendered.radiance, &rendered.range);
        let (bbox, pixels, peak) = event_extent(&contrast, size, VISIBLE_CONTRAST);
        let present = pixels >= MIN_DEVIL_PIXELS;
        truth.push(FrameTruth {
            present,
            faint,
            peak_contrast: peak,
            pixels,
            bbox: if present { bbox } else { None },
        });
        out.push(rendered);
    }
    DustDevilSequence { frames: out, truth, interval_s }
}

/// One dust devil crossing the camera's view during the sequence.
fn make_devil(
    rng: &mut ChaCha8Rng,
    camera: &rovernav_vision::Cahv,
    ground_z: f64,
    faint: bool,
    frames: usize,
    interval_s: f64,
    start: f64,
) -> (Volume, usize, usize) {
    let axis = nalgebra::Vector2::new(camera.a.x, camera.a.y).normalize();
    let side = nalgebra::Vector2::new(-axis.y, axis.x);
    let distance = rng.random_range(150.0f64..2500.0);
    let radius = rng.random_range(4.0..40.0) * (distance / 800.0).clamp(0.5, 1.5);
    let height = rng.random_range(100.0..600.0);
    let speed = rng.random_range(1.0..6.0);
    let heading = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
    let velocity = [speed * heading.cos(), speed * heading.sin(), 0.0];
    // Position at the middle of the sequence: within +-18 deg of the view axis.
    let off = rng.random_range(-0.33..0.33) * distance;
    let mid = nalgebra::Vector2::new(camera.c.x, camera.c.y) + axis * distance + side * off;
    let t_mid = start + 0.5 * frames as f64 * interval_s;
    let position = [mid.x - velocity[0] * t_mid, mid.y - velocity[1] * t_mid, ground_z - 2.0];
    let tau = if faint { rng.random_range(0.003..0.015) } else { rng.random_range(0.04..0.15) };
    let density = tau / (2.0 * radius);
    let first = rng.random_range(0..frames / 2);
    let last = rng.random_range((frames / 2).max(first)..frames);
    let volume =
        Volume { shape: VolumeShape::Column { radius, height }, position, velocity, density, albedo: 0.6 };
    (volume, first, last)
}
