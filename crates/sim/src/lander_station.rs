//! A lander that watches the rover (paper 002 section 2, approach (a)): when the rover turns
//! in place within its range, the lander's stereo pair on its pan/tilt mast, aimed at the
//! rover's approximate position, takes the left image before the turn and both images after
//! it; its computer finds the rover in the difference (`rovernav_vision::lander::detect_rover`:
//! threshold, binarise, close, largest region, correlate in the right image, triangulate) and
//! sends the triangulated point with its uncertainty to the rover
//! ([`rovernav_core::SensorFrame::lander`]).
//!
//! The lander knows where it stands (a mission places it), so the point is in the world frame.
//! What the point means for the rover's position (a point of its visible surface, not its
//! centre) is the rover's business (`rovernav_localization::lander`).
//!
//! Departures from the paper, with reasons:
//! - The paper's rover turns 0.3 rad on purpose for each sighting; here the lander watches
//!   every in-place turn of at least `min_turn_rad` the navigator makes anyway (a turn of any
//!   size changes the rover's silhouette about its centre; the turns cost the traverse nothing).
//! - The mast aims at the true position plus `aim_sigma_m` of Gaussian error per axis, standing
//!   in for the rover's estimate radioed to the lander (the simulator does not see the
//!   estimate); the aim only centres the rover in the images and sizes the closing element and
//!   the disparity search.
//! - The lander is not an obstacle: it is not in the terrain, and the mission places it off the
//!   rover's route.

use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rovernav_core::{LanderSighting, Pose3, RoverConfig};
use rovernav_terrain::Terrain;
use rovernav_vision::lander::{DetectParams, detect_rover};
use rovernav_vision::stereo::StereoRig;
use rovernav_vision::tracking::approach::grey_f32;

use crate::raycast::HeightField;
use crate::render::Rig;
use crate::scenes::lander::LanderTurn;
use crate::sensors::gaussian;

/// A lander on the terrain and its stereo pair.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LanderStation {
    /// The mast's foot, world x and y (m); it stands on the terrain there.
    pub position: [f64; 2],
    /// Height of the left camera above the foot (m; Pathfinder's IMP stood 1.5 m high).
    pub mast_height_m: f64,
    /// Stereo baseline (m).
    pub baseline_m: f64,
    /// Horizontal field of view (rad).
    pub fov: f64,
    /// Image size (pixels, square).
    pub image_size: usize,
    /// Closest horizontal range at which the lander watches (m).
    pub min_range_m: f64,
    /// Farthest horizontal range at which the lander watches (m).
    pub max_range_m: f64,
    /// Smallest in-place turn watched (rad).
    pub min_turn_rad: f64,
    /// Aim error per axis (m).
    pub aim_sigma_m: f64,
    /// Standard deviation of the detected image position (px; where on the body the region
    /// falls is the rover's `LanderFixParams::box_sigma_m`).
    pub pixel_sigma_px: f64,
}

impl LanderStation {
    /// A lander with its foot at world (x, y) and the evaluated rig of
    /// `docs/results/2026-11-28-lander.md` (1.8 m mast, 15 cm baseline, 40 deg, 512 px), watching
    /// turns of at least 0.2 rad at 2-10 m.
    pub fn at(x: f64, y: f64) -> Self {
        Self {
            position: [x, y],
            mast_height_m: 1.8,
            baseline_m: 0.15,
            fov: 40f64.to_radians(),
            image_size: 512,
            min_range_m: 2.0,
            max_range_m: 10.0,
            min_turn_rad: 0.2,
            aim_sigma_m: 0.2,
            pixel_sigma_px: 1.0,
        }
    }

    /// Checks the settings; the error names the field.
    pub fn validate(&self) -> Result<(), String> {
        let positive = [
            ("mast_height_m", self.mast_height_m),
            ("baseline_m", self.baseline_m),
            ("pixel_sigma_px", self.pixel_sigma_px),
        ];
        for (name, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("{name}: {v} must be positive"));
            }
        }
        if !self.position.iter().all(|v| v.is_finite()) {
            return Err(format!("position: {:?} must be finite", self.position));
        }
        if !(self.fov > 0.0 && self.fov < 3.0) {
            return Err(format!("fov: {} rad must be in (0, 3)", self.fov));
        }
        if !(64..=2048).contains(&self.image_size) {
            return Err(format!("image_size: {} must be in 64..2048", self.image_size));
        }
        if !(self.min_range_m >= 0.5 && self.max_range_m > self.min_range_m && self.max_range_m <= 100.0) {
            return Err(format!(
                "min_range_m {} and max_range_m {}: need 0.5 <= min < max <= 100",
                self.min_range_m, self.max_range_m
            ));
        }
        if !(self.min_turn_rad > 0.0 && self.aim_sigma_m >= 0.0 && self.aim_sigma_m.is_finite()) {
            return Err(format!(
                "min_turn_rad {} must be positive and aim_sigma_m {} non-negative",
                self.min_turn_rad, self.aim_sigma_m
            ));
        }
        Ok(())
    }

    /// The render rig of the lander's pair.
    pub fn rig(&self, rover: &RoverConfig) -> Rig {
        let mut rig = Rig::new(rover);
        rig.lander_position = [0.0, 0.0, self.mast_height_m];
        rig.lander_fov = self.fov;
        rig.lander_size = self.image_size;
        rig.lander_baseline = self.baseline_m;
        rig
    }

    /// Whether a turn by `angle` from `before` is one the lander watches.
    pub fn watches(&self, before: &Pose3, angle: f64) -> bool {
        let range = (before.x - self.position[0]).hypot(before.y - self.position[1]);
        angle.abs() >= self.min_turn_rad && (self.min_range_m..=self.max_range_m).contains(&range)
    }

    /// The lander's sighting of the rover turning from `poses[0]` to `poses[1]` (true poses) on
    /// `terrain`, or `None` when it does not watch that turn or does not find the rover.
    pub fn watch(
        &self,
        terrain: &Terrain,
        field: &HeightField,
        rover: &RoverConfig,
        poses: [Pose3; 2],
        rng: &mut ChaCha8Rng,
    ) -> Option<LanderSighting> {
        let before = poses[0];
        if !self.watches(&before, rovernav_core::angle_diff(poses[1].yaw, before.yaw)) {
            return None;
        }
        let [fx, fy] = self.position;
        let foot = terrain.dem.height(fx, fy).unwrap_or(before.z);
        let site = Pose3 { x: fx, y: fy, z: foot, ..Default::default() };
        let aim = [
            before.x + gaussian(rng, self.aim_sigma_m) - fx,
            before.y + gaussian(rng, self.aim_sigma_m) - fy,
            before.z + 0.5 - foot,
        ];
        let rig = self.rig(rover);
        let turn = LanderTurn { terrain, field, rover, rig: &rig, site };
        let capture = turn.render(poses, aim, rng.random());
        let [left, right] = capture.cameras;
        let camera = [left.c.x, left.c.y, left.c.z];
        let focal = left.focal_h();
        let stereo = StereoRig::new(left, right).ok()?;
        let grey = |img: &crate::render::RenderedImage| {
            grey_f32(img.image.width(), img.image.height(), img.image.as_raw())
        };
        let aimed_range = aim[0].hypot(aim[1]);
        let params = DetectParams::aimed(focal, self.baseline_m, aimed_range);
        let detection = detect_rover(
            &stereo,
            &grey(&capture.before)?,
            &grey(&capture.after_left)?,
            &grey(&capture.after_right)?,
            &params,
        )
        .ok()?;
        Some(LanderSighting {
            camera,
            point: detection.point.coords.into(),
            range_sigma_m: detection.range_sigma_m,
            angle_sigma_rad: self.pixel_sigma_px / focal,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenes::Site;
    use crate::vehicle::settled_pose;
    use rand::SeedableRng;
    use rovernav_core::Pose2;

    #[test]
    fn settings_are_checked_and_the_watch_is_limited_to_range_and_turn() {
        let station = LanderStation::at(0.0, 0.0);
        assert!(station.validate().is_ok());
        assert!(
            LanderStation { max_range_m: 1.0, ..station }.validate().unwrap_err().contains("max_range_m")
        );
        assert!(
            LanderStation { baseline_m: f64::NAN, ..station }.validate().unwrap_err().contains("baseline_m")
        );
        let at = |x: f64| Pose3 { x, ..Default::default() };
        assert!(station.watches(&at(5.0), 0.3) && station.watches(&at(5.0), -0.3));
        assert!(
            !station.watches(&at(5.0), 0.1)
                && !station.watches(&at(1.0), 0.3)
                && !station.watches(&at(12.0), 0.3)
        );
    }

    /// The rover turning 6 m from the lander on a Mars yard: the sighting's point lies on the
    /// rover (within its half length of the true centre, at the height of its body) and its
    /// range sigma is the stereo range error at 6 m (a few centimetres).
    #[test]
    fn the_lander_sights_a_turning_rover_within_its_body() {
        let site = Site::new(7);
        let rover = RoverConfig::default();
        let g = site.terrain.dem.geometry();
        let (cx, cy) = (g.origin_x + 0.5 * g.width_m(), g.origin_y + 0.5 * g.height_m());
        let station = LanderStation { image_size: 320, ..LanderStation::at(cx - 6.0, cy) };
        let before = settled_pose(&site.terrain.dem, &rover, Pose2::new(cx, cy, 1.0));
        let after = settled_pose(&site.terrain.dem, &rover, Pose2::new(cx, cy, 1.3));
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let s =
            station.watch(&site.terrain, &site.field, &rover, [before, after], &mut rng).expect("sighted");
        let off = (s.point[0] - cx).hypot(s.point[1] - cy);
        assert!(off < 0.5 * rover.length, "point {:?} is {off:.2} m from the rover's centre", s.point);
        assert!((s.point[2] - after.z).abs() < 1.0, "point height {} against ground {}", s.point[2], after.z);
        assert!(s.range_sigma_m > 0.005 && s.range_sigma_m < 0.2, "{}", s.range_sigma_m);
        assert!((s.camera[0] - (cx - 6.0)).abs() < 1e-9 && (s.camera[2] - after.z).abs() < 3.0);
        // A turn too small to watch gives nothing, and draws nothing.
        assert!(station.watch(&site.terrain, &site.field, &rover, [before, before], &mut rng).is_none());
    }
}
