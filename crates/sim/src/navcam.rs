//! Navcam pictures on request (`SenseRequest::Navcam`): both images of the mast's rectified
//! Navcam pair rendered from the rover's true pose, for target tracking, onboard science and
//! the operator. The range sensors are elsewhere ([`crate::sensors`], [`crate::stereo_range`]);
//! these images carry no range: whoever needs range correlates them.

use crate::raycast::HeightField;
use crate::render::{self, RenderSettings, Scene, Sun, Volume};
use crate::stereo_range::StereoImaging;
use rovernav_core::{CameraImage, Pose3, RoverConfig};
use rovernav_terrain::Terrain;
use rovernav_vision::rig::Rig;

/// How the Navcam pair images on request.
#[derive(Clone, Debug, PartialEq)]
pub struct NavcamImaging {
    /// Image width and height (pixels; MER's Navcams: 1024, here 512 by default to keep an
    /// image pair near half a second of rendering).
    pub width: usize,
    /// Pointing the mast and exposing both cameras (s).
    pub capture_time_s: f64,
    /// Clouds and dust devils in the simulated sky (scene time is the simulation clock).
    pub volumes: Vec<Volume>,
}

impl Default for NavcamImaging {
    fn default() -> Self {
        Self { width: 512, capture_time_s: 5.0, volumes: Vec::new() }
    }
}

/// Which stereo pair to render.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Pair {
    /// The Navcams, with the head at body-frame `pan` and `tilt` (rad).
    Navcam {
        /// Head pan (rad).
        pan: f64,
        /// Head tilt (rad).
        tilt: f64,
    },
    /// A body (Hazcam) pair, front or rear, at the Navcams' image size (the mast head stays
    /// forward): pictures for the tooling arm's terrain model.
    Body {
        /// Front pair when true, rear otherwise.
        front: bool,
    },
}

impl Pair {
    /// The rig's camera names (left, right) and the head's pan and tilt.
    fn cameras(self) -> ([&'static str; 2], f64, f64) {
        match self {
            Pair::Navcam { pan, tilt } => (["navcam_left", "navcam_right"], pan, tilt),
            Pair::Body { front: true } => (["hazcam_front_left", "hazcam_front_right"], 0.0, 0.0),
            Pair::Body { front: false } => (["hazcam_rear_left", "hazcam_rear_right"], 0.0, 0.0),
        }
    }
}

/// Renders a stereo pair (left, right) from the rover's true pose at simulation time `time`;
/// `seed` draws the sensor noise.
#[allow(clippy::too_many_arguments)]
pub fn capture_pair(
    terrain: &Terrain,
    field: &HeightField,
    rover: &RoverConfig,
    truth: &Pose3,
    lighting: &StereoImaging,
    navcam: &NavcamImaging,
    pair: Pair,
    time: f64,
    seed: u64,
) -> [CameraImage; 2] {
    let shot = Shot { terrain, field, rover, truth, lighting, navcam, time, seed };
    let (names, pan, tilt) = pair.cameras();
    shot.render(names, pan, tilt)
}

/// What one rendered pair shares: the world, the pose, the light and the time.
struct Shot<'a> {
    terrain: &'a Terrain,
    field: &'a HeightField,
    rover: &'a RoverConfig,
    truth: &'a Pose3,
    lighting: &'a StereoImaging,
    navcam: &'a NavcamImaging,
    time: f64,
    seed: u64,
}

impl Shot<'_> {
    /// Renders the two rig cameras `names` (the mast head at `pan`, `tilt`).
    fn render(&self, names: [&str; 2], pan: f64, tilt: f64) -> [CameraImage; 2] {
        let l = self.lighting;
        let sun = Sun::on_mars(l.local_time_h, l.latitude_deg, l.ls_deg);
        let mut scene =
            Scene::new(self.terrain, self.field, &sun, l.atmosphere).with_rover(self.rover, self.truth, pan);
        scene.volumes = self.navcam.volumes.clone();
        scene.time = self.time;
        let rig = Rig::new(self.rover).with_size(self.navcam.width.max(16));
        let settings = RenderSettings::default();
        names.map(|name| {
            let camera = rig.camera(name, pan, tilt).expect("the rig has every body and mast camera");
            // Body-mounted cameras ignore the site pose.
            let model = camera.in_world(self.truth, self.truth);
            let image = render::render(&scene, &model, name, &settings, self.seed).image;
            CameraImage {
                camera: name.into(),
                t: self.time,
                width: image.width(),
                height: image.height(),
                bits: 12,
                pixels: image.into_raw(),
                pan,
                tilt,
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_pair_is_two_textured_images_and_the_right_one_sees_the_left_one_shifted() {
        let site = crate::scenes::Site::new(3);
        let (terrain, field) = (&site.terrain, &site.field);
        let truth = site.pose(0.0, 0.0, 0.0);
        let rover = RoverConfig::default();
        let navcam = NavcamImaging { width: 64, ..NavcamImaging::default() };
        let [left, right] = capture_pair(
            terrain,
            field,
            &rover,
            &truth,
            &StereoImaging::default(),
            &navcam,
            Pair::Navcam { pan: 0.0, tilt: -0.4 },
            10.0,
            7,
        );
        assert_eq!((left.camera.as_str(), right.camera.as_str()), ("navcam_left", "navcam_right"));
        assert_eq!((left.width, left.height, left.pixels.len()), (64, 64, 64 * 64));
        assert_eq!((left.pan, left.tilt, left.t), (0.0, -0.4, 10.0));
        let spread = |p: &[u16]| p.iter().max().unwrap() - p.iter().min().unwrap();
        assert!(spread(&left.pixels) > 100 && spread(&right.pixels) > 100, "textured ground");
        assert_ne!(left.pixels, right.pixels, "0.20 m apart, the two cameras see different images");
    }
}
