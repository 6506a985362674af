//! The lander watching the rover turn (paper 002 section 2): a lander on a Mars yard with its
//! stereo pair on a pan/tilt mast aimed at the rover's approximate position, the rover turning
//! in place, and the three images the detector needs (left before the turn, left and right
//! after) with the truth behind them.
//!
//! The lander's cameras share one fixed exposure, set by the first image: an automatic exposure
//! per image would change the whole difference image when the rover's turn changes the scene's
//! brightest pixels, which no lander operator differencing images would allow.

use nalgebra::Point3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use rovernav_core::{Pose2, Pose3, RoverConfig};
use rovernav_vision::{Cahv, CameraModel};

use super::Site;
use crate::raycast::HeightField;
use crate::render::{Exposure, Label, RenderSettings, RenderedImage, Rig, Scene, Sun, render};
use crate::stereo_range::StereoImaging;
use crate::vehicle::settled_pose;
use rovernav_terrain::Terrain;

/// Where the rover stands relative to the lander and how the lander aims.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LanderSetup {
    /// Horizontal distance from the lander's mast to the rover (m).
    pub range_m: f64,
    /// Direction of the rover from the lander (rad, world frame).
    pub azimuth: f64,
    /// The rover's heading before the turn (rad).
    pub heading: f64,
    /// The in-place turn (rad; the paper's 0.3).
    pub turn: f64,
    /// Error of the rover position the lander aims at, per axis (m).
    pub aim_error: [f64; 2],
}

impl LanderSetup {
    /// A setup drawn for `seed`: range uniform in `ranges` (m), azimuth within 35 deg of the
    /// yard's +x axis, any heading, a 0.3 rad turn, and an aim error of `aim_sigma_m` per axis.
    pub fn random(seed: u64, ranges: (f64, f64), aim_sigma_m: f64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x001a_4de7);
        let range_m = rng.random_range(ranges.0..=ranges.1);
        let azimuth = rng.random_range(-35f64.to_radians()..=35f64.to_radians());
        let heading = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
        let normal = Normal::new(0.0, aim_sigma_m.max(0.0)).expect("a finite non-negative sigma");
        let aim_error = [normal.sample(&mut rng), normal.sample(&mut rng)];
        Self { range_m, azimuth, heading, turn: 0.3, aim_error }
    }
}

/// One trial's geometry and images.
#[derive(Clone, Debug)]
pub struct LanderCapture {
    /// The lander's site pose (mast foot on the ground, world frame).
    pub site: Pose3,
    /// The rig (lander mast position, baseline, field of view, image size).
    pub rig: Rig,
    /// Mast pan and tilt used (rad, site frame).
    pub pan_tilt: (f64, f64),
    /// The rover before and after the turn (true poses).
    pub poses: [Pose3; 2],
    /// The true left and right camera models (world frame).
    pub cameras: [Cahv; 2],
    /// Left image before the turn.
    pub before: RenderedImage,
    /// Left image after the turn.
    pub after_left: RenderedImage,
    /// Right image after the turn.
    pub after_right: RenderedImage,
}

/// A lander watching a rover turn on some terrain: what [`LanderTurn::render`] needs.
#[derive(Clone, Copy, Debug)]
pub struct LanderTurn<'a> {
    /// The terrain (its rocks are rendered).
    pub terrain: &'a Terrain,
    /// Its height field.
    pub field: &'a HeightField,
    /// The rover's body.
    pub rover: &'a RoverConfig,
    /// The rig (lander mast position above its foot, baseline, field of view, image size).
    pub rig: &'a Rig,
    /// The lander's site pose (mast foot on the ground, world frame).
    pub site: Pose3,
}

impl LanderTurn<'_> {
    /// Renders the three images of a turn from `poses[0]` to `poses[1]` (true poses), the mast
    /// aimed at the site-frame point `aim`, images noisy for `seed`.
    pub fn render(&self, poses: [Pose3; 2], aim: [f64; 3], seed: u64) -> LanderCapture {
        let (rig, lander) = (self.rig, self.site);
        let (pan, tilt) = rig.lander_aim(aim);
        let cameras = ["lander", "lander_right"].map(|name| {
            rig.lander_camera(name, pan, tilt).expect("both lander cameras exist").in_world(&lander, &lander)
        });
        let imaging = StereoImaging::default();
        let sun = Sun::on_mars(imaging.local_time_h, imaging.latitude_deg, imaging.ls_deg);
        let scene = |pose: &Pose3| {
            Scene::new(self.terrain, self.field, &sun, imaging.atmosphere).with_rover(self.rover, pose, 0.0)
        };
        let auto = RenderSettings::default();
        let before_img = render(&scene(&poses[0]), &cameras[0], "lander", &auto, seed.wrapping_mul(2));
        let fixed = RenderSettings {
            sensor: crate::render::Sensor {
                exposure: Exposure::Fixed(before_img.exposure),
                ..auto.sensor.clone()
            },
            ..auto.clone()
        };
        let after_scene = scene(&poses[1]);
        let noise = seed.wrapping_mul(2).wrapping_add(1);
        let after_left = render(&after_scene, &cameras[0], "lander", &fixed, noise);
        let after_right = render(&after_scene, &cameras[1], "lander_right", &fixed, noise);
        LanderCapture {
            site: lander,
            rig: rig.clone(),
            pan_tilt: (pan, tilt),
            poses,
            cameras,
            before: before_img,
            after_left,
            after_right,
        }
    }
}

impl LanderCapture {
    /// Renders a trial on `site`: the lander 7 m behind the yard's centre along -x, its mast
    /// `rig.lander_position` above its foot, the rover at `setup`, images noisy for `seed`.
    pub fn render(site: &Site, rover: &RoverConfig, rig: &Rig, setup: &LanderSetup, seed: u64) -> Self {
        let g = site.terrain.dem.geometry();
        let (fx, fy) = (g.origin_x + 0.5 * g.width_m() - 7.0, g.origin_y + 0.5 * g.height_m());
        let foot = site.terrain.dem.height(fx, fy).unwrap_or(site.ground_z);
        let lander = Pose3 { x: fx, y: fy, z: foot, ..Default::default() };
        let (mx, my) = (fx + rig.lander_position[0], fy + rig.lander_position[1]);
        let (rx, ry) = (mx + setup.range_m * setup.azimuth.cos(), my + setup.range_m * setup.azimuth.sin());
        let dem = &site.terrain.dem;
        let before = settled_pose(dem, rover, Pose2::new(rx, ry, setup.heading));
        let after = settled_pose(dem, rover, Pose2::new(rx, ry, setup.heading + setup.turn));
        // Aim at the dead-reckoned position, half a metre above the ground there.
        let aim = [rx + setup.aim_error[0] - fx, ry + setup.aim_error[1] - fy, before.z + 0.5 - foot];
        let turn = LanderTurn { terrain: &site.terrain, field: &site.field, rover, rig, site: lander };
        turn.render([before, after], aim, seed)
    }

    /// The truth the detector seeks: the left-image bounding box (x_min, x_max, y_min, y_max)
    /// of the rover (chassis from the ground to the solar deck, and the mast head) at both
    /// poses, projected from the true poses; `None` if a corner is behind the camera.
    pub fn true_rover_box(&self, rover: &RoverConfig) -> Option<(f64, f64, f64, f64)> {
        let (hx, hy, top) = (0.5 * rover.length + 0.02, 0.5 * rover.width + 0.02, rover.clearance + 0.24);
        let head = rover.mast_height;
        let corners = |x0: f64, y0: f64, z0: f64, z1: f64| {
            [-x0, x0].into_iter().flat_map(move |x| {
                [-y0, y0].into_iter().flat_map(move |y| [z0, z1].into_iter().map(move |z| [x, y, z]))
            })
        };
        let mut bounds = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
        for pose in &self.poses {
            // The head box of the renderer's rover (0.1 x 0.32 x 0.1 m at mast height).
            for p in corners(hx, hy, 0.0, top).chain(corners(0.05, 0.16, head - 0.05, head + 0.05)) {
                let (u, v) = self.project_left(pose.transform(p))?;
                bounds = (bounds.0.min(u), bounds.1.max(u), bounds.2.min(v), bounds.3.max(v));
            }
        }
        Some(bounds)
    }

    /// The number of left-image pixels whose rover label changed between the two images.
    pub fn changed_rover_pixels(&self) -> usize {
        let rover = |l: &Label| *l == Label::Rover;
        self.before.labels.iter().zip(&self.after_left.labels).filter(|(a, b)| rover(a) != rover(b)).count()
    }

    /// The left-image pixel of a world point, if in front of the camera.
    pub fn project_left(&self, p: [f64; 3]) -> Option<(f64, f64)> {
        self.cameras[0].project(&Point3::from(p)).map(|q| (q.x, q.y))
    }
}
