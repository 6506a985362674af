//! Sensor messages: what the autonomy receives from the (simulated or real) platform.
//!
//! Exteroceptive data is expressed in the rover body frame at the time of capture; the autonomy
//! places it in the world with its own pose estimate, never with ground truth.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Which camera pair (or range sensor) produced a point cloud.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum CameraKind {
    /// Stereo pair on the pan/tilt mast.
    Mast,
    /// Forward body stereo pair.
    BodyFront,
    /// Rear body stereo pair.
    BodyRear,
    /// Nodding LIDAR (MRPTA).
    Lidar,
}

impl CameraKind {
    /// A stable lower-case name.
    pub fn as_str(self) -> &'static str {
        match self {
            CameraKind::Mast => "mast",
            CameraKind::BodyFront => "body_front",
            CameraKind::BodyRear => "body_rear",
            CameraKind::Lidar => "lidar",
        }
    }
}

/// The visible region of one range image: a wedge in the body frame.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct Wedge {
    /// Bearing of the wedge centre in the body frame (rad, counter-clockwise from forward).
    pub bearing: f64,
    /// Half of the field of view (rad).
    pub half_angle: f64,
    /// Nearest range sensed (m).
    pub min_range: f64,
    /// Useful far range (m).
    pub max_range: f64,
}

impl Wedge {
    /// Whether a body-frame planar point lies inside the wedge.
    pub fn contains(&self, x: f64, y: f64) -> bool {
        let r = x.hypot(y);
        if r < self.min_range || r > self.max_range {
            return false;
        }
        crate::angle_diff(y.atan2(x), self.bearing).abs() <= self.half_angle
    }
}

/// A cloud of 3D points from one range image, in the body frame at capture time.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct PointCloud {
    /// Sensor that produced it.
    pub camera: CameraKind,
    /// Sensor origin in the body frame (m).
    pub origin: [f64; 3],
    /// The region it covers (planar, body frame).
    pub wedge: Wedge,
    /// Points (x forward, y left, z up) in metres, body frame (base64 of little-endian f32 on the wire).
    #[serde(with = "crate::wire::points_base64")]
    #[schemars(with = "String", extend("contentEncoding" = "base64"))]
    pub points: Vec<[f32; 3]>,
}

/// The ten forward proximity threshold sensors of SR2 (paper 001), grouped in clusters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(transparent)]
pub struct ProximityReading {
    /// Raw sensors, index 0 leftmost; true when something is closer than the threshold.
    pub raw: [bool; 10],
}

impl ProximityReading {
    /// Any of the left cluster (sensors 0..3) triggered.
    pub fn left(&self) -> bool {
        self.raw[0..3].iter().any(|&b| b)
    }
    /// Any of the middle cluster (sensors 3..7) triggered.
    pub fn middle(&self) -> bool {
        self.raw[3..7].iter().any(|&b| b)
    }
    /// Any of the right cluster (sensors 7..10) triggered.
    pub fn right(&self) -> bool {
        self.raw[7..10].iter().any(|&b| b)
    }
    /// Any sensor triggered.
    pub fn any(&self) -> bool {
        self.raw.iter().any(|&b| b)
    }
}

/// Inertial and attitude sensors sampled together.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct ImuSample {
    /// Time (s).
    pub t: f64,
    /// Yaw rate from the gyro (rad/s), including bias and noise.
    #[serde(deserialize_with = "crate::wire::nan_from_null")]
    #[schemars(with = "Option<f64>")]
    pub gyro_z: f64,
    /// Roll from the inclinometer (rad).
    #[serde(deserialize_with = "crate::wire::nan_from_null")]
    #[schemars(with = "Option<f64>")]
    pub incl_roll: f64,
    /// Pitch from the inclinometer (rad).
    #[serde(deserialize_with = "crate::wire::nan_from_null")]
    #[schemars(with = "Option<f64>")]
    pub incl_pitch: f64,
    /// Magnetic/compass heading (rad, counter-clockwise from east); NaN on a faulty sensor.
    #[serde(deserialize_with = "crate::wire::nan_from_null")]
    #[schemars(with = "Option<f64>")]
    pub compass_yaw: f64,
    /// Heading from the sun sensor (rad), when the sun is visible.
    pub sun_yaw: Option<f64>,
}

/// Cumulative wheel encoder counts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct OdometrySample {
    /// Time (s).
    pub t: f64,
    /// Left side cumulative counts.
    pub left_counts: i64,
    /// Right side cumulative counts.
    pub right_counts: i64,
}

/// A camera image as the platform reports it: grey, row-major, up to 16 bits per pixel.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct CameraImage {
    /// The camera's name (`navcam_left`, `hazcam_front_left`, ...).
    pub camera: String,
    /// Time of exposure (s).
    pub t: f64,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Bits per pixel used (12 for the rover's cameras).
    pub bits: u8,
    /// Pixel values, row-major, `width * height` of them (base64 of little-endian u16 on the wire).
    #[serde(with = "crate::wire::pixels_base64")]
    #[schemars(with = "String", extend("contentEncoding" = "base64"))]
    pub pixels: Vec<u16>,
    /// Mast pan when taken, counter-clockwise from forward (rad; 0 for body-fixed cameras).
    #[serde(default)]
    pub pan: f64,
    /// Mast tilt when taken, positive up (rad; 0 for body-fixed cameras).
    #[serde(default)]
    pub tilt: f64,
}

/// Everything the platform reports after executing one command.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct SensorFrame {
    /// Time at the end of the command (s).
    pub t: f64,
    /// Range data requested by the command (empty for motion).
    pub clouds: Vec<PointCloud>,
    /// Proprioceptive samples during the command, in time order.
    pub imu: Vec<ImuSample>,
    /// Encoder samples during the command, in time order.
    pub odometry: Vec<OdometrySample>,
    /// Proximity reading at the end of the command.
    pub proximity: ProximityReading,
    /// Whether a motion stopped early (guard, hazard or stall), and why.
    pub motion_stopped: Option<String>,
    /// Camera images taken during the command (the left image of each correlated stereo pair).
    pub images: Vec<CameraImage>,
    /// The power system's reading at the end of the command (absent from platforms without one).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub power: Option<PowerReading>,
    /// A lander's stereo sighting of the rover, when a lander watched this command (paper 002
    /// section 2: the rover turned in place in its view).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lander: Option<Box<LanderSighting>>,
}

/// A lander's sighting of the rover (paper 002 section 2), in the world frame: the lander knows
/// where it stands, so its triangulated point is an absolute measurement.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct LanderSighting {
    /// The lander's (left) camera centre (m).
    pub camera: [f64; 3],
    /// The triangulated point of the rover's visible surface (m).
    pub point: [f64; 3],
    /// Standard deviation of the range along the line of sight (m).
    pub range_sigma_m: f64,
    /// Standard deviation of the image position, as an angle (rad).
    pub angle_sigma_rad: f64,
}

/// The power system's telemetry (SR2's current and voltage sensors on the solar panel and the
/// system, paper 001 section 3): all the autonomy knows of its energy.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct PowerReading {
    /// Time of the reading (s).
    pub t: f64,
    /// Battery state of charge (0 empty .. 1 full).
    pub state_of_charge: f64,
    /// Energy in the battery (Wh).
    pub battery_wh: f64,
    /// Solar panel output at the reading (W).
    pub panel_w: f64,
    /// Computer load, mean over the command (W).
    pub computer_w: f64,
    /// Drive motors' load, mean over the command (W).
    pub motors_w: f64,
    /// Cameras' load, mean over the command (W).
    pub cameras_w: f64,
}

/// Range error of one range sensor: standard deviation `constant + quadratic * r^2` at range `r`
/// (stereo depth error grows with the square of range, a time-of-flight LIDAR's hardly at all).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RangeNoise {
    /// Range-independent part of the standard deviation (m).
    pub constant: f64,
    /// Standard deviation per squared metre of range (1/m).
    pub quadratic: f64,
}

impl RangeNoise {
    /// Standard deviation of the range error at range `r` (m).
    pub fn sigma(&self, r: f64) -> f64 {
        self.constant + self.quadratic * r * r
    }
}

/// The calibrated range error of each of the rover's range sensors.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SensorNoise {
    /// Mast stereo pair.
    pub mast: RangeNoise,
    /// Front and rear body stereo pairs.
    pub body: RangeNoise,
    /// Nodding LIDAR.
    pub lidar: RangeNoise,
}

impl Default for SensorNoise {
    /// Stereo error `r^2 sigma_d / (f b)` of the rover's pairs (mast: ~0.2 m baseline, ~2 mrad
    /// pixels, 0.4 px matching error; body pairs: wider field, shorter baseline, 2.5 times
    /// that) and a 1.5 cm time-of-flight LIDAR.
    fn default() -> Self {
        Self {
            mast: RangeNoise { constant: 0.0, quadratic: 0.004 },
            body: RangeNoise { constant: 0.0, quadratic: 0.01 },
            lidar: RangeNoise { constant: 0.015, quadratic: 0.0 },
        }
    }
}

impl SensorNoise {
    /// The model of one sensor.
    pub fn of(&self, camera: CameraKind) -> RangeNoise {
        match camera {
            CameraKind::Mast => self.mast,
            CameraKind::BodyFront | CameraKind::BodyRear => self.body,
            CameraKind::Lidar => self.lidar,
        }
    }
}
