//! Vehicle and sensor-suite parameters shared by the simulator and the autonomy.
//!
//! Defaults are Rocky 7 / SR2 scale (paper 000 section 1: Sojourner-sized, 1.2 m deployable mast
//! with a 30-45 deg stereo pair, body stereo pairs fore and aft with 80-100 deg; paper 001: SR2
//! with ten forward proximity sensors; paper 004 section 3.2: gyro, inclinometer, odometry).

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Physical and sensing parameters of the rover.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct RoverConfig {
    /// Body length (m).
    pub length: f64,
    /// Body width (m).
    pub width: f64,
    /// Distance between left and right wheel centres (m).
    pub track: f64,
    /// Belly clearance above the ground plane of the wheels (m).
    pub clearance: f64,
    /// Tilt beyond which the rover is in hazard (rad).
    pub max_tilt: f64,
    /// Top speed (m/s).
    pub max_speed: f64,
    /// In-place turn rate (rad/s).
    pub turn_rate: f64,
    /// Wheel encoder resolution (counts per cm of wheel travel).
    pub encoder_counts_per_cm: f64,
    /// Mast camera height above the ground (m).
    pub mast_height: f64,
    /// Mast stereo field of view (rad, full angle).
    pub mast_fov: f64,
    /// Mast stereo useful range (m).
    pub mast_range: f64,
    /// Body camera height above the ground (m).
    pub body_camera_height: f64,
    /// Body stereo field of view (rad, full angle).
    pub body_fov: f64,
    /// Body stereo useful range (m).
    pub body_range: f64,
    /// Range of the forward proximity sensors (m).
    pub proximity_range: f64,
}

impl Default for RoverConfig {
    fn default() -> Self {
        Self {
            length: 0.8,
            width: 0.6,
            track: 0.5,
            clearance: 0.18,
            max_tilt: 25f64.to_radians(),
            max_speed: 0.1,
            turn_rate: 10f64.to_radians(),
            encoder_counts_per_cm: 20.0,
            mast_height: 1.2,
            mast_fov: 45f64.to_radians(),
            mast_range: 5.0,
            body_camera_height: 0.35,
            body_fov: 90f64.to_radians(),
            body_range: 1.5,
            proximity_range: 0.6,
        }
    }
}

impl RoverConfig {
    /// Radius of the circle that encloses the body footprint (m), used to grow obstacles.
    pub fn radius(&self) -> f64 {
        0.5 * self.length.hypot(self.width)
    }
}
