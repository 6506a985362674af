//! The mission file's `[rover]` and `[sensors]` overrides.

use serde::Deserialize;

/// Optional overrides of the rover's dimensions and sensors (defaults: `RoverConfig::default`).
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RoverSpec {
    /// Body length (m).
    pub length_m: Option<f64>,
    /// Body width (m).
    pub width_m: Option<f64>,
    /// Belly clearance (m).
    pub clearance_m: Option<f64>,
    /// Tilt limit (deg).
    pub max_tilt_deg: Option<f64>,
    /// Top speed (m/s).
    pub max_speed_mps: Option<f64>,
    /// Mast stereo useful range (m).
    pub mast_range_m: Option<f64>,
    /// Mast stereo field of view (deg).
    pub mast_fov_deg: Option<f64>,
}

/// Optional overrides of the sensor noise (defaults: the simulator's `SensorModel::default`).
#[derive(Clone, Debug, Default, Deserialize, serde::Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SensorSpec {
    /// Compass noise sigma (deg).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub compass_sigma_deg: Option<f64>,
    /// Probability that a stereo pixel gives no range.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stereo_dropout: Option<f64>,
    /// Multiplier on the stereo pairs' range noise (mast, full-resolution mast and body
    /// pairs): 0 is noise-free stereo, 2 twice the default sigma.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stereo_noise_scale: Option<f64>,
    /// Where the stereo pairs' range comes from: `raycast` (rays cast against the true terrain
    /// with a noise model, the default) or `stereo` (both cameras' images rendered and
    /// correlated, as on a real rover).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub range_source: Option<RangeSourceSpec>,
}

/// The simulator's source of stereo range, as a mission file names it.
#[derive(Clone, Copy, Debug, Deserialize, serde::Serialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum RangeSourceSpec {
    /// Rays cast against the true terrain, with Gaussian range noise and dropouts.
    Raycast,
    /// Rendered stereo images, correlated by semi-global matching.
    Stereo,
}

impl SensorSpec {
    /// Whether no override is given.
    pub fn is_empty(&self) -> bool {
        *self == Self::default()
    }

    /// These overrides with `over`'s set fields taking their place.
    pub fn overridden_by(&self, over: &SensorSpec) -> SensorSpec {
        SensorSpec {
            compass_sigma_deg: over.compass_sigma_deg.or(self.compass_sigma_deg),
            stereo_dropout: over.stereo_dropout.or(self.stereo_dropout),
            stereo_noise_scale: over.stereo_noise_scale.or(self.stereo_noise_scale),
            range_source: over.range_source.or(self.range_source),
        }
    }

    /// The overrides as the lines of a mission file's `[sensors]` table (empty without any).
    pub fn toml_table(&self) -> String {
        if self.is_empty() {
            return String::new();
        }
        let lines = toml::to_string(self).expect("a table of optional numbers serialises");
        format!("\n[sensors]\n{lines}")
    }

    /// The first override out of range, as (field under `sensors.`, why).
    pub fn check(&self) -> Result<(), (&'static str, &'static str)> {
        if self.compass_sigma_deg.is_some_and(|v| !(v.is_finite() && v >= 0.0)) {
            return Err(("compass_sigma_deg", "must be a number of degrees >= 0"));
        }
        if self.stereo_dropout.is_some_and(|v| !(0.0..1.0).contains(&v)) {
            return Err(("stereo_dropout", "must be a probability in [0, 1)"));
        }
        if self.stereo_noise_scale.is_some_and(|v| !(v.is_finite() && v >= 0.0)) {
            return Err(("stereo_noise_scale", "must be a finite number >= 0"));
        }
        Ok(())
    }
}
