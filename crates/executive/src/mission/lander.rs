//! The mission's lander (`[lander]`): a lander with a stereo pair on its mast that watches the
//! rover's in-place turns and radios its sightings (paper 002 section 2;
//! `rovernav_sim::LanderStation`). It is placed from the rover's start, as the `[[sky]]`
//! volumes are: an azimuth (counter-clockwise from the world x axis, as `start.yaw_deg`) and a
//! horizontal distance. Only the simulator sees the lander; the rover sees its sightings.

use rovernav_sim::LanderStation;
use serde::Deserialize;

/// Where the lander stands and how it watches.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LanderSpec {
    /// Direction of the lander's mast from the start, counter-clockwise from the world x axis
    /// (deg).
    pub azimuth_deg: f64,
    /// Horizontal distance from the start (m).
    pub distance_m: f64,
    /// Height of the left camera above the lander's foot (m; default 1.8).
    #[serde(default)]
    pub mast_height_m: Option<f64>,
    /// Farthest range at which it watches (m; default 10, the paper's trials reached 10).
    #[serde(default)]
    pub max_range_m: Option<f64>,
    /// Smallest in-place turn it watches (deg; default 11.5, i.e. 0.2 rad).
    #[serde(default)]
    pub min_turn_deg: Option<f64>,
    /// Image size (pixels, square; default 512).
    #[serde(default)]
    pub image_size: Option<usize>,
}

impl LanderSpec {
    /// The lander station for a start at world (x, y).
    pub fn station(&self, start_x: f64, start_y: f64) -> LanderStation {
        let (s, c) = self.azimuth_deg.to_radians().sin_cos();
        let d = LanderStation::at(start_x + c * self.distance_m, start_y + s * self.distance_m);
        LanderStation {
            mast_height_m: self.mast_height_m.unwrap_or(d.mast_height_m),
            max_range_m: self.max_range_m.unwrap_or(d.max_range_m),
            min_turn_rad: self.min_turn_deg.map_or(d.min_turn_rad, f64::to_radians),
            image_size: self.image_size.unwrap_or(d.image_size),
            ..d
        }
    }

    /// Checks the numbers: `Err((field, why))`.
    pub fn check(&self) -> Result<(), (&'static str, String)> {
        super::check::in_range(self.azimuth_deg, -360.0, 360.0, " deg")
            .map_err(|e| ("lander.azimuth_deg", e))?;
        super::check::in_range(self.distance_m, 0.0, 1000.0, " m").map_err(|e| ("lander.distance_m", e))?;
        self.station(0.0, 0.0).validate().map_err(|e| ("lander", e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_lander_stands_at_its_azimuth_and_distance_from_the_start() {
        let spec: LanderSpec = toml::from_str("azimuth_deg = 90\ndistance_m = 6\nmax_range_m = 12").unwrap();
        let s = spec.station(10.0, 20.0);
        assert!((s.position[0] - 10.0).abs() < 1e-9 && (s.position[1] - 26.0).abs() < 1e-9);
        assert_eq!((s.max_range_m, s.image_size), (12.0, 512));
        assert!(spec.check().is_ok());
        let far = LanderSpec { max_range_m: Some(500.0), ..spec.clone() };
        assert!(far.check().unwrap_err().1.contains("max_range_m"));
        let nan = LanderSpec { distance_m: f64::NAN, ..spec };
        assert_eq!(nan.check().unwrap_err().0, "lander.distance_m");
        assert!(toml::from_str::<LanderSpec>("azimuth_deg = 1\ndistance_m = 6\nrange = 3").is_err());
    }
}
