//! The `stereo` range source: range computed from pixels, as on a real rover.
//!
//! Instead of casting one ray per range sample ([`crate::sensors::capture`]), the simulator
//! renders both images of a rectified stereo pair ([`crate::render`]) and correlates them with
//! semi-global matching ([`rovernav_vision::stereo`]); the triangulated pixels become the point
//! cloud the navigators consume. The pair covers the same wedge as the ray grid it replaces:
//! pointed at the wedge's bearing, tilted to the middle of its elevation span, with the wedge's
//! horizontal field of view and enough lines to cover the span. Its range error is what the
//! correlator makes of the rendered pixels (noise, texture, occlusions, foreshortening), not a
//! drawn Gaussian.
//!
//! Departures from a flight stereo pipeline, with their reasons:
//! - The images are rendered already rectified (linear CAHV models with a common A, H, V): the
//!   simulated cameras have no lens distortion to remove, so rectification would be an identity
//!   resampling.
//! - The rover's own body is not drawn: flight stereo masks the rover's pixels out, and leaving
//!   the body out of the render is the same mask without the bookkeeping.
//! - Images are 256 pixels wide, as MER's navigation stereo ran on 256x256 subsampled Navcam
//!   and Hazcam images (Goldberg, Maimone and Matthies, "Stereo vision and rover navigation
//!   software for planetary exploration", IEEE Aerospace 2002).

use nalgebra::Vector3;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rovernav_core::{CameraKind, PointCloud, Pose3};
use rovernav_terrain::Terrain;
use rovernav_vision::stereo::{self, StereoParams, StereoRig};
use rovernav_vision::{Cahv, camera::Movable};

use crate::raycast::HeightField;
use crate::render::{self, Atmosphere, RenderSettings, RenderedImage, Scene, Sun, pose_isometry};
use crate::sensors::RangeGeometry;

/// Where the stereo pairs' range comes from.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum RangeSource {
    /// Rays cast against the true terrain with Gaussian range noise and dropouts.
    #[default]
    Raycast,
    /// Both images of the pair rendered and correlated.
    Stereo,
}

/// How the `stereo` range source images and correlates.
#[derive(Clone, Debug, PartialEq)]
pub struct StereoImaging {
    /// Image width (pixels); the height follows from the wedge's elevation span.
    pub width: usize,
    /// Mast pair baseline (m); MER's Navcams: 0.20 m.
    pub mast_baseline: f64,
    /// Body pair baseline (m); MER's Hazcams: 0.10 m.
    pub body_baseline: f64,
    /// Local true solar time of the traverse (hours), for the sun's direction.
    pub local_time_h: f64,
    /// Site latitude (deg).
    pub latitude_deg: f64,
    /// Areocentric solar longitude, the season (deg).
    pub ls_deg: f64,
    /// The atmosphere's dust.
    pub atmosphere: Atmosphere,
    /// Subpixel disparity error assumed for the points' range uncertainty (px).
    pub sigma_d_px: f64,
    /// Correlator settings (the disparity search is set per pair from its near range).
    pub correlator: StereoParams,
    /// One pixel in `point_stride` along each axis becomes a point of the navigators' cloud.
    pub point_stride: usize,
}

impl Default for StereoImaging {
    fn default() -> Self {
        Self {
            width: 256,
            mast_baseline: 0.20,
            body_baseline: 0.10,
            // Early afternoon, when rovers usually drive; Gale crater's latitude, northern spring.
            local_time_h: 13.0,
            latitude_deg: -4.6,
            ls_deg: 0.0,
            atmosphere: Atmosphere::default(),
            sigma_d_px: stereo::range::DEFAULT_SIGMA_D_PX,
            // A left-right tolerance of half a pixel: next to an occluding rock the census
            // window drags the rock's disparity onto the ground behind it, and a range blunder
            // there reads as an obstacle or hides one. `rovernav eval stereo` seeds 3..8: 0.8 %
            // of valid pixels beyond 3 sigma and 95.9 % of the pixels both cameras see ranged,
            // against 1.3 % and 99.0 % at the Middlebury-tuned 1 px (which counts rejected
            // pixels as errors, as a rover must not).
            correlator: StereoParams { lr_tolerance: 0.5, ..StereoParams::default() },
            // 256 / 4 = 64 points across, about the 60 rays of the ray-cast navigation image:
            // the navigators get the same density (and cost) from either source.
            point_stride: 4,
        }
    }
}

/// The rectified body-frame pair imaging the wedge of `geometry` with images `width` wide.
pub fn pair_for(geometry: &RangeGeometry, width: usize, baseline: f64) -> StereoRig {
    let tilt = 0.5 * (geometry.elevation_min + geometry.elevation_max);
    let span = (geometry.elevation_max - geometry.elevation_min).max(1e-3);
    let (sb, cb) = geometry.bearing.sin_cos();
    let (st, ct) = tilt.sin_cos();
    let axis = Vector3::new(ct * cb, ct * sb, st);
    // Samples grow to the camera's right: the body's -y side when looking forward.
    let right = Vector3::new(sb, -cb, 0.0);
    let focal = 0.5 * width as f64 / (0.5 * geometry.fov).tan();
    let height = ((2.0 * focal * (0.5 * span).tan()).ceil() as usize).max(8);
    let o = Vector3::from(geometry.origin);
    let camera = |centre: Vector3<f64>| {
        Cahv::from_intrinsics(
            centre,
            axis,
            right,
            focal,
            focal,
            0.5 * (width as f64 - 1.0),
            0.5 * (height as f64 - 1.0),
            width,
            height,
        )
    };
    let left = camera(o - right * (0.5 * baseline));
    let right_cam = camera(o + right * (0.5 * baseline));
    StereoRig::new(left, right_cam).expect("a pair built with a common A, H, V is rectified")
}

/// One stereo capture: both rendered images and the point cloud correlated from them.
#[derive(Clone, Debug)]
pub struct StereoCapture {
    /// The body-frame pair.
    pub rig: StereoRig,
    /// The left (reference) image and the truth behind it.
    pub left: RenderedImage,
    /// The right image.
    pub right: RenderedImage,
    /// Per-pixel triangulated range of the left image.
    pub range: stereo::RangeImage,
    /// The valid points within the wedge's range, body frame.
    pub cloud: PointCloud,
}

/// Renders the pair of `geometry` at the true pose and correlates it.
pub fn capture(
    terrain: &Terrain,
    field: &HeightField,
    truth: &Pose3,
    geometry: &RangeGeometry,
    imaging: &StereoImaging,
    rng: &mut ChaCha8Rng,
) -> StereoCapture {
    let baseline = match geometry.camera {
        CameraKind::Mast => imaging.mast_baseline,
        _ => imaging.body_baseline,
    };
    let rig = pair_for(geometry, imaging.width, baseline);
    let sun = Sun::on_mars(imaging.local_time_h, imaging.latitude_deg, imaging.ls_deg);
    let scene = Scene::new(terrain, field, &sun, imaging.atmosphere);
    let pose = pose_isometry(truth);
    let settings = RenderSettings::default();
    // One draw per capture keeps the noise stream independent of the scene.
    let seed: u64 = rng.random();
    let left = render::render(&scene, &rig.left.moved(&pose), "stereo_left", &settings, seed);
    let right = render::render(&scene, &rig.right.moved(&pose), "stereo_right", &settings, seed);
    // Search down to the nearest range the wedge images (with 20 % margin for relief).
    let near = nearest_slant_range(geometry);
    let max_disparity = ((rig.focal_baseline() / near) * 1.2).ceil() as usize;
    let params = StereoParams { max_disparity: max_disparity.clamp(16, 128), ..imaging.correlator.clone() };
    let disparity = stereo::compute_disparity(&left.image, &right.image, &params)
        .expect("the pair's images share one size within the volume bound");
    let range = rig.range_image(&disparity, imaging.sigma_d_px);
    let cloud = rig.point_cloud(&thinned(&range, imaging.point_stride), geometry.camera, geometry.max_range);
    StereoCapture { rig, left, right, range, cloud }
}

/// The range image with only every `stride`-th pixel of every `stride`-th line kept (the
/// centre of each stride x stride block); the others become NaN.
fn thinned(range: &stereo::RangeImage, stride: usize) -> stereo::RangeImage {
    let s = stride.max(1);
    let mut out = range.clone();
    for y in 0..range.height {
        for x in 0..range.width {
            if x % s != s / 2 || y % s != s / 2 {
                let i = y * range.width + x;
                out.points[i] = [f32::NAN; 3];
                out.range[i] = f32::NAN;
                out.range_sigma[i] = f32::NAN;
            }
        }
    }
    out
}

/// The name of the left camera of a pair (`navcam_left`, `hazcam_front_left`, ...).
pub fn left_camera_name(camera: CameraKind) -> &'static str {
    match camera {
        CameraKind::Mast => "navcam_left",
        CameraKind::BodyFront => "hazcam_front_left",
        CameraKind::BodyRear => "hazcam_rear_left",
        CameraKind::Lidar => "lidar",
    }
}

/// Slant range from the sensor to level ground at the wedge's bottom row (m).
fn nearest_slant_range(geometry: &RangeGeometry) -> f64 {
    let h = geometry.origin[2].max(0.05);
    h / (-geometry.elevation_min).sin().max(0.05)
}
