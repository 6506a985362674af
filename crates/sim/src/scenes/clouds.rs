//! Skies with and without clouds for the cloud detector (paper 003 section 5.1).
//!
//! Martian water-ice clouds are thin, textured and high (about 10 to 30 km): each cloud here is
//! a cluster of 12 to 40 flat ellipsoids (0.6 to 3 km long, 60 to 300 m thick) drifting at
//! 5 to 30 m/s, at 8 to 20 km altitude, placed along a line of sight inside the camera's field
//! of view. A case's optical depth sets its contrast: faint clouds (path optical depth of a
//! part 0.0006 to 0.0025: peaks of a few per cent against the sky where parts overlap) or
//! distinct ones (0.004 to 0.03: peaks of 10 % to 100 %). Negatives
//! vary everything else a cloud detector must ignore: dust optical depth 0.3 to 1.2 (a bright
//! dusty sky), the sun's position (glare near the field of view, the sun itself at least
//! 30 deg off the camera axis as sky observations are planned), the head's tilt (all sky to a
//! third of sky), the rover's roll and pitch (a tilted horizon) and the yard.
//!
//! Truth: a cloud is labelled present when at least [`MIN_CLOUD_PIXELS`] pixels differ from the
//! cloud-free sky by [`VISIBLE_CONTRAST`] or more; a high-contrast cloud peaks at
//! [`HIGH_CONTRAST`] or more.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::{Site, event_extent, science_settings, volume_contrast};
use crate::render::{Atmosphere, RenderedImage, Scene, Sun, Volume, VolumeShape, render};

/// Relative contrast at which a cloud pixel counts as visible.
pub const VISIBLE_CONTRAST: f32 = 0.02;
/// Fewest visible pixels of a labelled cloud.
pub const MIN_CLOUD_PIXELS: usize = 100;
/// Peak contrast of a high-contrast cloud.
pub const HIGH_CONTRAST: f32 = 0.10;

/// What a generated cloud case holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CloudClass {
    /// No cloud.
    Clear,
    /// A faint cloud.
    Faint,
    /// A clearly visible cloud.
    Distinct,
}

/// The truth of one cloud image.
#[derive(Clone, Debug, PartialEq)]
pub struct CloudTruth {
    /// The class the case was generated as.
    pub class: CloudClass,
    /// Whether a cloud is visible (the label).
    pub cloud: bool,
    /// Whether the visible cloud is high-contrast.
    pub high_contrast: bool,
    /// Peak relative contrast of the clouds against the sky.
    pub peak_contrast: f32,
    /// Pixels at or above [`VISIBLE_CONTRAST`].
    pub pixels: usize,
    /// Bounding box of those pixels `[x, y, width, height]`.
    pub bbox: Option<[u32; 4]>,
    /// Fraction of the image that is sky (renderer labels).
    pub sky_fraction: f32,
}

/// One rendered, labelled cloud image.
pub struct CloudImage {
    /// The rendered image and its per-pixel truth.
    pub rendered: RenderedImage,
    /// The label.
    pub truth: CloudTruth,
}

/// Renders cloud case `index` of the set of `seed` at `size` pixels square (deterministic),
/// raw or block-compressed at `quality`. Classes cycle so that 45 % are clear, 25 % faint and
/// 30 % distinct.
pub fn cloud_image(site: &Site, index: usize, size: usize, seed: u64, quality: Option<u8>) -> CloudImage {
    let mut rng = ChaCha8Rng::seed_from_u64(seed.wrapping_mul(0x9E37_79B9).wrapping_add(index as u64));
    let class = match index % 20 {
        0..=8 => CloudClass::Clear,
        9..=13 => CloudClass::Faint,
        _ => CloudClass::Distinct,
    };
    let pose =
        site.pose(rng.random_range(-0.12..0.12), rng.random_range(-0.08..0.08), rng.random_range(-3.1..3.1));
    let pan = rng.random_range(-3.1..3.1);
    let tilt = rng.random_range(5f64..35.0).to_radians();
    let camera = site.navcam(&pose, pan, tilt, size);
    // Sky observations point away from the sun (a flight rule keeps it 30 deg or more off the
    // camera axis, so glare reaches the image edges at most).
    let axis = camera.a;
    let mut sun = Sun::on_mars(rng.random_range(8.5..16.5), -14.6, rng.random_range(0.0..360.0));
    for _ in 0..20 {
        let d = sun.direction();
        if d[0] * axis.x + d[1] * axis.y + d[2] * axis.z < 30f64.to_radians().cos() {
            break;
        }
        sun = Sun::on_mars(rng.random_range(8.5..16.5), -14.6, rng.random_range(0.0..360.0));
    }
    let atmosphere = Atmosphere { tau: rng.random_range(0.3..1.2), ..Atmosphere::default() };
    let mut scene = Scene::new(&site.terrain, &site.field, &sun, atmosphere);
    scene.time = rng.random_range(0.0..600.0);
    if class != CloudClass::Clear {
        let clouds = if rng.random_bool(0.3) { 2 } else { 1 };
        for _ in 0..clouds {
            add_cloud(&mut scene.volumes, &mut rng, &camera, class, scene.time);
        }
    }
    let rendered = render(&scene, &camera, "navcam_left", &science_settings(quality), seed ^ index as u64);
    let contrast = volume_contrast(&scene, &camera, &rendered.radiance, &rendered.range);
    let (bbox, pixels, peak) = event_extent(&contrast, size, VISIBLE_CONTRAST);
    let sky = rendered.labels.iter().filter(|l| **l == crate::render::Label::Sky).count();
    let cloud = pixels >= MIN_CLOUD_PIXELS;
    let truth = CloudTruth {
        class,
        cloud,
        high_contrast: cloud && peak >= HIGH_CONTRAST,
        peak_contrast: peak,
        pixels,
        bbox: if cloud { bbox } else { None },
        sky_fraction: sky as f32 / (size * size) as f32,
    };
    CloudImage { rendered, truth }
}

/// Adds one textured cloud seen by `camera` (world frame) at time `time`.
fn add_cloud(
    volumes: &mut Vec<Volume>,
    rng: &mut ChaCha8Rng,
    camera: &rovernav_vision::Cahv,
    class: CloudClass,
    time: f64,
) {
    use rovernav_vision::CameraModel;
    // A line of sight inside the image, at least 4 deg above the horizon.
    let (w, h) = (camera.width() as f64, camera.height() as f64);
    let mut dir = nalgebra::Vector3::new(0.0, 0.0, 1.0);
    for _ in 0..50 {
        let p = nalgebra::Point2::new(rng.random_range(0.1..0.9) * w, rng.random_range(0.05..0.8) * h);
        let d = camera.unproject(&p).direction.into_inner();
        dir = d;
        if d.z > 4f64.to_radians().sin() {
            break;
        }
    }
    if dir.z <= 0.02 {
        return;
    }
    let altitude = rng.random_range(8_000.0..20_000.0);
    let reach = (altitude - camera.c.z) / dir.z;
    let centre = camera.c + dir * reach;
    let spread = rng.random_range(2_500.0..10_000.0) * (reach / 40_000.0).clamp(0.3, 2.0);
    let velocity = {
        let (s, c) = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI).sin_cos();
        let v = rng.random_range(5.0..30.0);
        [v * c, v * s, 0.0]
    };
    let path_tau = match class {
        CloudClass::Faint => rng.random_range(0.0006..0.0025),
        _ => rng.random_range(0.004..0.03),
    };
    let albedo = 0.9;
    let parts = rng.random_range(12..40);
    // Streaks along one direction (wave clouds and cirrus-like bands).
    let (sa, ca) = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI).sin_cos();
    for _ in 0..parts {
        let along = rng.random_range(-1.0..1.0) * spread;
        let across = rng.random_range(-0.35..0.35) * spread;
        let long: f64 = rng.random_range(600.0..3_000.0);
        let short = long * rng.random_range(0.25..0.6);
        let (rx, ry) = if ca.abs() > sa.abs() { (long, short) } else { (short, long) };
        let rz = rng.random_range(60.0..300.0);
        // Optical depth along the slanted line of sight through the part's middle.
        let path = (2.0 * rz / dir.z).min(2.0 * rx.max(ry) / (1.0 - dir.z * dir.z).sqrt().max(1e-3));
        let density = path_tau / path * rng.random_range(0.4..1.6);
        let p = [
            centre.x + along * ca - across * sa - velocity[0] * time,
            centre.y + along * sa + across * ca - velocity[1] * time,
            centre.z + rng.random_range(-300.0..300.0),
        ];
        volumes.push(Volume {
            shape: VolumeShape::Ellipsoid { radii: [rx, ry, rz] },
            position: p,
            velocity,
            density,
            albedo,
        });
    }
}
