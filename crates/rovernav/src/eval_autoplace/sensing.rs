//! What AutoPlace sees of a scene: stereo pairs rendered by the simulator's renderer and
//! correlated by `rovernav_manipulation::sensing` (the code the executive's tooling arm runs),
//! nothing else (the simulator's truth only scores).
//!
//! Three pairs, all body cameras of the rig (`rovernav_vision::rig`):
//! - the "ultimate" front Hazcam pair at the final position: target selection and terrain;
//! - the "penultimate" front Hazcam pair taken 0.30 m before (the last step), which sees the
//!   ground the rover now stands over and the volume in front of the body (paper 003 4.1); its
//!   points and camera centres move into the final body frame by the step, known from odometry;
//! - the Navcam pair pointed at the arm's workspace (pan 0, tilt -52 deg), terrain only.
//!   Departure: the paper builds the terrain model from the Hazcams alone; here the Hazcams
//!   sit 0.35 m high (`RoverConfig::body_camera_height`, MER's are about 0.5 m) and no line of
//!   sight from them crosses the space above their own height, where the elbow passes, so the
//!   Navcam's lines of sight verify that space.
//!
//! The rover's body is not drawn (as in `rovernav_sim::stereo_range`); the Navcam's points whose
//! line of sight would cross the rover's body are dropped, as flight software masks the rover's
//! pixels. The stowed arm is not drawn either.
//!
//! A [`Hole`] makes every pixel whose true surface point lies in it a flat grey in both images
//! of every pair, as deep shadow or glare does: the correlator's texture test rejects them.

use super::scene::{Hole, Scene};
use nalgebra::{Isometry3, Point2, Translation3};
use rovernav_core::RoverConfig;
use rovernav_manipulation::geometry::Aabb;
use rovernav_manipulation::sensing::{Correlation, correlate, mask_rover};
use rovernav_sim::HeightField;
use rovernav_sim::render::{self, Atmosphere, RenderSettings, Rig, Sun};
use rovernav_terrain::Terrain;
use rovernav_vision::camera::Movable;
use rovernav_vision::{Cahv, CameraModel};

pub use rovernav_manipulation::sensing::Pair;

/// Imaging settings.
#[derive(Clone, Debug)]
pub struct Imaging {
    /// Image width and height (pixels).
    pub width: usize,
    /// The last step's length (m).
    pub step_m: f64,
    /// Navcam tilt (rad).
    pub navcam_tilt: f64,
    /// Points beyond this range are dropped (m).
    pub max_range: f64,
}

impl Default for Imaging {
    fn default() -> Self {
        Self { width: 512, step_m: 0.30, navcam_tilt: (-52f64).to_radians(), max_range: 3.0 }
    }
}

/// Renders one pair from the body pose `body_to_world`, blanks the holes, correlates, and
/// returns points and centres moved by `to_final` (capture body frame -> final body frame).
#[allow(clippy::too_many_arguments)]
fn capture(
    name: &'static str,
    scene: &render::Scene,
    left: &Cahv,
    right: &Cahv,
    body_to_world: &Isometry3<f64>,
    to_final: &Isometry3<f64>,
    holes: &[Hole],
    imaging: &Imaging,
    seed: u64,
) -> Pair {
    let settings = RenderSettings::default();
    let images = [left, right].map(|cam| {
        let world = cam.moved(body_to_world);
        let mut out = render::render(scene, &world, name, &settings, seed);
        let w = out.width();
        if !holes.is_empty() {
            for (i, px) in out.image.pixels_mut().enumerate() {
                let range = out.range[i] as f64;
                if !range.is_finite() {
                    continue;
                }
                let ray = world.unproject(&Point2::new((i % w) as f64, (i / w) as f64));
                let p = ray.origin + ray.direction.into_inner() * range;
                if holes.iter().any(|h| (p.x - h.centre[0]).hypot(p.y - h.centre[1]) < h.radius) {
                    px.0[0] = 400;
                }
            }
        }
        out
    });
    let [l, r] = &images;
    let settings = Correlation { max_range: imaging.max_range, ..Correlation::default() };
    correlate(name, left, right, &l.image, &r.image, to_final, &settings).expect("rig pairs are rectified")
}

/// The three pairs of a scene: ultimate Hazcam (first), penultimate Hazcam, Navcam.
pub fn sense(
    scene: &Scene,
    terrain: &Terrain,
    rover: &RoverConfig,
    rover_boxes: &[Aabb],
    imaging: &Imaging,
) -> Vec<Pair> {
    let field = HeightField::new(&terrain.dem);
    let sun = Sun::on_mars(scene.local_time_h, -4.6, 0.0);
    let render_scene = render::Scene::new(terrain, &field, &sun, Atmosphere::default());
    let rig = Rig::new(rover).with_size(imaging.width);
    let model = |name: &str, tilt: f64| rig.camera(name, 0.0, tilt).expect("rig camera").model;
    let here = Isometry3::identity();
    let back = Isometry3::from_parts(Translation3::new(-imaging.step_m, 0.0, 0.0), Default::default());
    let seed = scene.seed.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    let (hl, hr) = (model("hazcam_front_left", 0.0), model("hazcam_front_right", 0.0));
    let (nl, nr) = (model("navcam_left", imaging.navcam_tilt), model("navcam_right", imaging.navcam_tilt));
    let ultimate =
        capture("hazcam_ultimate", &render_scene, &hl, &hr, &here, &here, &scene.holes, imaging, seed);
    let penultimate =
        capture("hazcam_penultimate", &render_scene, &hl, &hr, &back, &back, &scene.holes, imaging, seed ^ 1);
    let mut navcam =
        capture("navcam", &render_scene, &nl, &nr, &here, &here, &scene.holes, imaging, seed ^ 2);
    mask_rover(&mut navcam, rover_boxes);
    vec![ultimate, penultimate, navcam]
}
