//! The simulated sky (`[[sky]]`): clouds and dust devils for the Navcam to photograph, so a
//! mission's `cloud_watch` and `dust_devil_watch` (paper 003 section 5) have something to find.
//! Each entry is placed from the rover's start: an azimuth (counter-clockwise from the world x
//! axis, as `start.yaw_deg`), a horizontal distance and an altitude above the start's ground,
//! at simulation time 0; from then on it drifts with its velocity.
//! Only the simulator sees these volumes; the autonomy sees their pixels.

use rovernav_sim::render::{Volume, VolumeShape};
use serde::Deserialize;

/// What a `[[sky]]` entry is.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum SkyKind {
    /// A flattened ellipsoid of ice or dust high in the air.
    Cloud,
    /// A vertical dust column standing on the ground.
    DustDevil,
}

/// One volume in the simulated sky.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SkySpec {
    /// `cloud` or `dust_devil`.
    pub kind: SkyKind,
    /// Direction from the start, counter-clockwise from the world x axis (deg).
    pub azimuth_deg: f64,
    /// Horizontal distance from the start (m).
    pub distance_m: f64,
    /// Height above the start's ground (m): a cloud's centre, a dust devil's base (default 0).
    #[serde(default)]
    pub altitude_m: f64,
    /// A cloud's horizontal radius, a dust devil's column radius (m).
    pub radius_m: f64,
    /// A cloud's vertical half-thickness, a dust devil's height (m).
    pub height_m: f64,
    /// Optical depth through the middle (vertically for a cloud, across for a dust devil).
    pub optical_depth: f64,
    /// Drift velocity, x and y (m/s; default still).
    #[serde(default)]
    pub velocity_mps: [f64; 2],
}

impl SkySpec {
    /// The volume in the world frame, the start at `(x, y)` on ground `ground_z`.
    pub fn volume(&self, x: f64, y: f64, ground_z: f64) -> Volume {
        let (s, c) = self.azimuth_deg.to_radians().sin_cos();
        let position = [x + c * self.distance_m, y + s * self.distance_m, ground_z + self.altitude_m];
        let (shape, path, albedo) = match self.kind {
            SkyKind::Cloud => (
                VolumeShape::Ellipsoid { radii: [self.radius_m, self.radius_m, self.height_m] },
                2.0 * self.height_m,
                0.9,
            ),
            SkyKind::DustDevil => (
                VolumeShape::Column { radius: self.radius_m, height: self.height_m },
                2.0 * self.radius_m,
                0.6,
            ),
        };
        Volume {
            shape,
            position,
            velocity: [self.velocity_mps[0], self.velocity_mps[1], 0.0],
            density: self.optical_depth / path,
            albedo,
        }
    }
}

/// Checks every entry; the error names the field.
pub(super) fn check(sky: &[SkySpec]) -> Result<(), (String, &'static str)> {
    for (i, s) in sky.iter().enumerate() {
        let field = |name: &str| format!("sky[{i}].{name}");
        let finite = [s.azimuth_deg, s.distance_m, s.altitude_m, s.velocity_mps[0], s.velocity_mps[1]];
        if finite.iter().any(|v| !v.is_finite()) {
            return Err((field("azimuth_deg"), "position and velocity must be finite numbers"));
        }
        if !(0.0..=1.0e6).contains(&s.distance_m) {
            return Err((field("distance_m"), "must be 0 to 1000 km"));
        }
        if !(-1.0e4..=1.0e5).contains(&s.altitude_m) {
            return Err((field("altitude_m"), "must be -10 to 100 km"));
        }
        for (name, v) in [("radius_m", s.radius_m), ("height_m", s.height_m)] {
            if !(v.is_finite() && v > 0.0 && v <= 1.0e5) {
                return Err((field(name), "must be positive, at most 100 km"));
            }
        }
        if !(s.optical_depth.is_finite() && s.optical_depth > 0.0 && s.optical_depth <= 10.0) {
            return Err((field("optical_depth"), "must be positive, at most 10"));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cloud() -> SkySpec {
        SkySpec {
            kind: SkyKind::Cloud,
            azimuth_deg: 90.0,
            distance_m: 1000.0,
            altitude_m: 8000.0,
            radius_m: 2000.0,
            height_m: 150.0,
            optical_depth: 0.03,
            velocity_mps: [10.0, 0.0],
        }
    }

    #[test]
    fn a_cloud_sits_where_its_azimuth_distance_and_altitude_put_it_with_the_asked_optical_depth() {
        let v = cloud().volume(5.0, -2.0, -4500.0);
        assert!((v.position[0] - 5.0).abs() < 1e-9 && (v.position[1] - 998.0).abs() < 1e-9);
        assert!((v.position[2] - 3500.0).abs() < 1e-9);
        // A vertical ray through the centre crosses 2 x 150 m of density: the optical depth.
        let (t0, t1) = v.chord([5.0, 998.0, 0.0], [0.0, 0.0, 1.0], 0.0).expect("the ray crosses it");
        assert!(((t1 - t0) * v.density - 0.03).abs() < 1e-9);
        // It drifts with its velocity.
        let (a, _) = v.chord([1005.0, 998.0, 0.0], [0.0, 0.0, 1.0], 100.0).expect("drifted over");
        assert!(a > 0.0);
    }

    #[test]
    fn a_dust_devil_stands_on_the_ground_and_bad_fields_are_named() {
        let devil = SkySpec {
            kind: SkyKind::DustDevil,
            altitude_m: 0.0,
            radius_m: 20.0,
            height_m: 400.0,
            optical_depth: 0.1,
            ..cloud()
        };
        let v = devil.volume(0.0, 0.0, 10.0);
        assert_eq!(v.position[2], 10.0);
        assert!((v.density * 40.0 - 0.1).abs() < 1e-12);
        assert_eq!(check(&[cloud(), devil.clone()]), Ok(()));
        let bad = SkySpec { optical_depth: f64::NAN, ..devil.clone() };
        assert_eq!(check(&[cloud(), bad]).unwrap_err().0, "sky[1].optical_depth");
        let bad = SkySpec { radius_m: 0.0, ..devil };
        assert_eq!(check(&[bad]).unwrap_err().0, "sky[0].radius_m");
    }
}
