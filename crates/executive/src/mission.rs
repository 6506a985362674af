//! The mission file: terrain, rover, sensors, start, goal, navigator, limits and seed (TOML).
//!
//! Unknown fields are rejected so that a misspelt key is an error naming the key and its line,
//! not a silently ignored setting.

use serde::Deserialize;
use std::path::{Path, PathBuf};

/// The built-in default mission (`missions/default.toml`).
pub const DEFAULT_MISSION_TOML: &str = include_str!("../../../missions/default.toml");

/// A complete mission description.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Mission {
    /// Human-readable name.
    #[serde(default = "default_name")]
    pub name: String,
    /// Seed for terrain generation and every sensor's noise.
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// Registry name of the navigator.
    #[serde(default = "default_navigator")]
    pub navigator: String,
    /// Parameters of the navigator (`[navigator_params]`, names and units as `rovernav
    /// navigators` lists them); unset ones keep the navigator's defaults.
    #[serde(default)]
    pub navigator_params: rovernav_navigation::NavigatorParams,
    /// Registry name of the localiser.
    #[serde(default = "default_localizer")]
    pub localizer: String,
    /// Mission time budget (s); exceeding it ends the run with `timeout`.
    #[serde(default = "default_time_limit")]
    pub time_limit_s: f64,
    /// Upper bound on navigator cycles; exceeding it ends the run with `timeout`.
    #[serde(default = "default_max_cycles")]
    pub max_cycles: u64,
    /// The world.
    pub terrain: TerrainSpec,
    /// Optional rover overrides.
    #[serde(default)]
    pub rover: RoverSpec,
    /// Optional sensor overrides.
    #[serde(default)]
    pub sensors: SensorSpec,
    /// Start pose.
    pub start: PoseSpec,
    /// Goal.
    pub goal: GoalSpec,
    /// Tasks after reaching the goal (`[[tasks]]`), in order; the plan always first drives to
    /// each waypoint and then the goal.
    #[serde(default)]
    pub tasks: Vec<TaskSpecToml>,
    /// Faults the simulator injects (`[[faults]]`), for fault-protection tests and drills.
    #[serde(default)]
    pub faults: Vec<FaultSpec>,
    /// Folder the mission file was read from (relative DEM paths resolve against it first).
    #[serde(skip)]
    pub base_dir: Option<PathBuf>,
}

fn default_name() -> String {
    "mission".into()
}
fn default_seed() -> u64 {
    1
}
fn default_navigator() -> String {
    "astar-grid".into()
}
fn default_localizer() -> String {
    "dead-reckoning".into()
}
fn default_time_limit() -> f64 {
    3600.0
}
fn default_max_cycles() -> u64 {
    5000
}

/// Where the terrain comes from.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(tag = "kind", rename_all = "lowercase", deny_unknown_fields)]
pub enum TerrainSpec {
    /// A procedural Mars yard.
    Procedural {
        /// Side of the square yard (m).
        #[serde(default = "default_size")]
        size_m: f64,
        /// Height-grid resolution (m).
        #[serde(default = "default_resolution")]
        resolution_m: f64,
        /// Golombek-Rapp rock abundance k (cumulative fractional area of rocks).
        #[serde(default = "default_rock_abundance")]
        rock_abundance: f64,
        /// Amplitude of the fractal relief (m).
        #[serde(default = "default_relief")]
        relief_m: f64,
        /// Regional slope (deg).
        #[serde(default)]
        slope_deg: f64,
        /// Craters per 100 m x 100 m with diameter at least 1 m.
        #[serde(default)]
        craters_per_hectare: Option<f64>,
    },
    /// A real elevation model.
    Dem {
        /// File path: absolute, relative to the mission file, or relative to `ROVERNAV_DATA`.
        path: PathBuf,
        /// Region [min easting, min northing, max easting, max northing] in projected metres.
        region: Option<[f64; 4]>,
        /// Resampled resolution (m).
        #[serde(default = "default_dem_resolution")]
        resolution_m: f64,
        /// Rock abundance k of rocks added on top of the DEM (0 for none).
        #[serde(default)]
        rock_abundance: f64,
    },
}

fn default_size() -> f64 {
    30.0
}
fn default_resolution() -> f64 {
    0.05
}
fn default_rock_abundance() -> f64 {
    0.16
}
fn default_relief() -> f64 {
    0.25
}
fn default_dem_resolution() -> f64 {
    0.1
}

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

/// A pose in either local or projected coordinates.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PoseSpec {
    /// Local east (m).
    pub x: Option<f64>,
    /// Local north (m).
    pub y: Option<f64>,
    /// Projected easting (m), for DEM missions.
    pub easting: Option<f64>,
    /// Projected northing (m), for DEM missions.
    pub northing: Option<f64>,
    /// Heading, counter-clockwise from east (deg).
    #[serde(default)]
    pub yaw_deg: f64,
}

/// The goal, waypoints and keep-out zones.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct GoalSpec {
    /// Local east (m).
    pub x: Option<f64>,
    /// Local north (m).
    pub y: Option<f64>,
    /// Projected easting (m).
    pub easting: Option<f64>,
    /// Projected northing (m).
    pub northing: Option<f64>,
    /// Arrival tolerance (m).
    #[serde(default = "default_tolerance")]
    pub tolerance_m: f64,
    /// Waypoints to visit first, as [x, y] in the same frame as the goal.
    #[serde(default)]
    pub waypoints: Vec<[f64; 2]>,
    /// Keep-out polygons, each a list of [x, y] vertices in the same frame as the goal.
    #[serde(default)]
    pub keep_out: Vec<Vec<[f64; 2]>>,
}

fn default_tolerance() -> f64 {
    0.5
}

/// The kinds of `[[tasks]]` entry.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum TaskKindName {
    /// Drive to `x`, `y`.
    DriveTo,
    /// Image all around with the mast.
    Panorama,
    /// Image the target `x`, `y` with the mast.
    ScienceImage,
    /// Place an instrument on the target `x`, `y` (in the arm's reach).
    PlaceInstrument,
    /// Scoop a sample at the target `x`, `y` (in the arm's reach).
    Scoop,
}

/// One `[[tasks]]` entry.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TaskSpecToml {
    /// What to do.
    pub kind: TaskKindName,
    /// Target east (m), in the goal's frame; every kind but `panorama` needs one.
    pub x: Option<f64>,
    /// Target north (m), in the goal's frame.
    pub y: Option<f64>,
    /// Arrival tolerance of a `drive_to` (m; default: the goal's).
    pub tolerance_m: Option<f64>,
    /// Start together with the previous task (they must need different resources).
    #[serde(default)]
    pub parallel: bool,
}

/// The kinds of `[[faults]]` entry.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum FaultKindName {
    /// A range sensor returns images without points (`sensor` names it).
    SilentSensor,
    /// The wheels of one side stop turning (`side` names it).
    StalledWheel,
    /// The compass reads NaN.
    CompassNan,
}

/// Range sensors a fault can silence.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum SensorName {
    /// Mast stereo pair.
    Mast,
    /// Forward body stereo pair.
    BodyFront,
    /// Rear body stereo pair.
    BodyRear,
    /// Nodding LIDAR.
    Lidar,
}

/// A side of the rover.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum Side {
    /// Left.
    Left,
    /// Right.
    Right,
}

/// One `[[faults]]` entry: what fails and when (default: from the start).
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FaultSpec {
    /// What fails.
    pub kind: FaultKindName,
    /// For `silent_sensor`: which sensor.
    pub sensor: Option<SensorName>,
    /// For `stalled_wheel`: which side.
    pub side: Option<Side>,
    /// Fail before this command (commands count from 1; 0 is before the first frame).
    pub at_cycle: Option<u64>,
    /// Fail at the first action starting at or after this simulated time (s).
    pub at_time_s: Option<f64>,
}

/// A mission that could not be read or does not make sense.
#[derive(Debug, thiserror::Error)]
pub enum MissionError {
    /// The file could not be read.
    #[error("{path}: {source}")]
    Io {
        /// File.
        path: String,
        /// Cause.
        source: std::io::Error,
    },
    /// TOML syntax or schema error (the message carries line and field).
    #[error("{path}: {message}")]
    Parse {
        /// File.
        path: String,
        /// What toml said, flattened to one line.
        message: String,
    },
    /// A field has an invalid value.
    #[error("{path}: field `{field}`: {message}")]
    Invalid {
        /// File.
        path: String,
        /// Dotted field name.
        field: String,
        /// Why.
        message: String,
    },
}

/// An invalid-field error with the line of the field's key in `text` when one line holds it.
fn with_line(error: MissionError, text: &str) -> MissionError {
    let MissionError::Invalid { path, field, message } = error else { return error };
    let key = field.rsplit('.').next().unwrap_or(&field).split('[').next().unwrap_or_default();
    let lines: Vec<usize> = text
        .lines()
        .enumerate()
        .filter(|(_, l)| {
            l.trim_start().strip_prefix(key).is_some_and(|rest| rest.trim_start().starts_with('='))
        })
        .map(|(i, _)| i + 1)
        .collect();
    let message = match lines.as_slice() {
        [line] if !key.is_empty() => format!("line {line}: {message}"),
        _ => message,
    };
    MissionError::Invalid { path, field, message }
}

impl Mission {
    /// Parses mission text; `origin` names the source in error messages.
    pub fn from_toml(text: &str, origin: &str) -> Result<Self, MissionError> {
        let mission: Mission = toml::from_str(text).map_err(|e| {
            let mut message = String::new();
            if let Some(span) = e.span() {
                let line = text[..span.start.min(text.len())].matches('\n').count() + 1;
                message.push_str(&format!("line {line}: "));
            }
            message.push_str(&e.message().replace('\n', " "));
            MissionError::Parse { path: origin.into(), message }
        })?;
        mission.validate(origin).map_err(|e| with_line(e, text))?;
        Ok(mission)
    }

    /// Reads and validates a mission file.
    pub fn from_file(path: &Path) -> Result<Self, MissionError> {
        let shown = path.display().to_string();
        let text = std::fs::read_to_string(path)
            .map_err(|source| MissionError::Io { path: shown.clone(), source })?;
        let mut m = Self::from_toml(&text, &shown)?;
        m.base_dir = path.parent().map(Path::to_path_buf);
        Ok(m)
    }

    /// The built-in default mission.
    pub fn default_mission() -> Self {
        Self::from_toml(DEFAULT_MISSION_TOML, "built-in default mission")
            .expect("the built-in mission is valid")
    }

    fn validate(&self, origin: &str) -> Result<(), MissionError> {
        let bad = |field: &str, message: &str| {
            Err(MissionError::Invalid { path: origin.into(), field: field.into(), message: message.into() })
        };
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if !positive(self.time_limit_s) {
            return bad("time_limit_s", "must be a positive number of seconds");
        }
        match &self.terrain {
            TerrainSpec::Procedural { size_m, resolution_m, rock_abundance, relief_m, slope_deg, .. } => {
                if !positive(*size_m) || *size_m > 2000.0 {
                    return bad("terrain.size_m", "must be in (0, 2000] m");
                }
                if !positive(*resolution_m) || *resolution_m > *size_m / 4.0 {
                    return bad("terrain.resolution_m", "must be positive and much smaller than the yard");
                }
                if (size_m / resolution_m).powi(2) > 1.0e8 {
                    return bad("terrain.resolution_m", "yard too large at this resolution (over 1e8 cells)");
                }
                if !(0.0..=0.5).contains(rock_abundance) {
                    return bad("terrain.rock_abundance", "must be in [0, 0.5]");
                }
                if !(relief_m.is_finite() && *relief_m >= 0.0) {
                    return bad("terrain.relief_m", "must be a non-negative number");
                }
                if !(slope_deg.is_finite() && slope_deg.abs() < 45.0) {
                    return bad("terrain.slope_deg", "must be within (-45, 45) deg");
                }
            }
            TerrainSpec::Dem { resolution_m, rock_abundance, region, .. } => {
                if !positive(*resolution_m) {
                    return bad("terrain.resolution_m", "must be positive");
                }
                if !(0.0..=0.5).contains(rock_abundance) {
                    return bad("terrain.rock_abundance", "must be in [0, 0.5]");
                }
                if let Some(r) = region
                    && !(r.iter().all(|v| v.is_finite()) && r[2] > r[0] && r[3] > r[1])
                {
                    return bad("terrain.region", "must be [min E, min N, max E, max N] with max > min");
                }
            }
        }
        for (name, spec) in [
            ("start", (&self.start.x, &self.start.y, &self.start.easting, &self.start.northing)),
            ("goal", (&self.goal.x, &self.goal.y, &self.goal.easting, &self.goal.northing)),
        ] {
            let (x, y, e, n) = spec;
            let local = x.is_some() && y.is_some();
            let projected = e.is_some() && n.is_some();
            if local == projected {
                return bad(
                    name,
                    "give either x and y (local metres) or easting and northing (projected metres)",
                );
            }
            if [x, y, e, n].iter().any(|v| v.is_some_and(|v| !v.is_finite())) {
                return bad(name, "coordinates must be finite numbers");
            }
        }
        if !self.start.yaw_deg.is_finite() {
            return bad("start.yaw_deg", "must be a finite number");
        }
        if let Err((field, why)) = self.sensors.check() {
            return bad(&format!("sensors.{field}"), why);
        }
        if !positive(self.goal.tolerance_m) {
            return bad("goal.tolerance_m", "must be positive");
        }
        // An unknown navigator name is the run's error (it lists the registered ones).
        if let Err(e) = rovernav_navigation::check_params(&self.navigator, &self.navigator_params) {
            let field = e.param().map_or("navigator_params".into(), |p| format!("navigator_params.{p}"));
            return bad(&field, &e.to_string());
        }
        for (i, zone) in self.goal.keep_out.iter().enumerate() {
            if zone.len() < 3 {
                return bad(&format!("goal.keep_out[{i}]"), "a polygon needs at least 3 vertices");
            }
        }
        for (i, t) in self.tasks.iter().enumerate() {
            let field = |name: &str| format!("tasks[{i}].{name}");
            let has_target = t.x.is_some() || t.y.is_some();
            if t.kind == TaskKindName::Panorama && has_target {
                return bad(&field("x"), "a panorama takes no target");
            }
            if t.kind != TaskKindName::Panorama && !(t.x.is_some() && t.y.is_some()) {
                return bad(
                    &field(if t.x.is_none() { "x" } else { "y" }),
                    "this task needs a target x and y",
                );
            }
            if [t.x, t.y].iter().flatten().any(|v| !v.is_finite()) {
                return bad(&field("x"), "target coordinates must be finite numbers");
            }
            if let Some(tol) = t.tolerance_m {
                if t.kind != TaskKindName::DriveTo {
                    return bad(&field("tolerance_m"), "only a drive_to has an arrival tolerance");
                }
                if !positive(tol) {
                    return bad(&field("tolerance_m"), "must be positive");
                }
            }
        }
        // Resource conflicts of parallel tasks; the plan's drives come before these tasks.
        let mut plan = vec![crate::deliberative::TaskSpec {
            kind: crate::deliberative::TaskKind::DriveTo {
                target: rovernav_core::Point2::new(0.0, 0.0),
                tolerance: 1.0,
            },
            parallel: false,
        }];
        plan.extend(self.plan_tasks(&|x, y| rovernav_core::Point2::new(x, y)));
        if let Err((i, why)) = crate::deliberative::validate_plan(&plan) {
            return bad(&format!("tasks[{}].parallel", i - 1), &why);
        }
        for (i, f) in self.faults.iter().enumerate() {
            let field = |name: &str| format!("faults[{i}].{name}");
            match (f.kind, f.sensor, f.side) {
                (FaultKindName::SilentSensor, None, _) => {
                    return bad(
                        &field("sensor"),
                        "silent_sensor needs `sensor` (mast, body_front, body_rear, lidar)",
                    );
                }
                (FaultKindName::StalledWheel, _, None) => {
                    return bad(&field("side"), "stalled_wheel needs `side` (left or right)");
                }
                (k, Some(_), _) if k != FaultKindName::SilentSensor => {
                    return bad(&field("sensor"), "only silent_sensor names a sensor");
                }
                (k, _, Some(_)) if k != FaultKindName::StalledWheel => {
                    return bad(&field("side"), "only stalled_wheel names a side");
                }
                _ => {}
            }
            if f.at_cycle.is_some() && f.at_time_s.is_some() {
                return bad(&field("at_time_s"), "give at_cycle or at_time_s, not both");
            }
            if f.at_time_s.is_some_and(|t| !(t.is_finite() && t >= 0.0)) {
                return bad(&field("at_time_s"), "must be a non-negative number of seconds");
            }
        }
        Ok(())
    }

    /// The `[[tasks]]` as plan entries, with targets mapped by `to_local` (goal frame to local).
    pub fn plan_tasks(
        &self,
        to_local: &dyn Fn(f64, f64) -> rovernav_core::Point2,
    ) -> Vec<crate::deliberative::TaskSpec> {
        use crate::deliberative::{TaskKind, TaskSpec};
        self.tasks
            .iter()
            .map(|t| {
                let target = to_local(t.x.unwrap_or(f64::NAN), t.y.unwrap_or(f64::NAN));
                let kind = match t.kind {
                    TaskKindName::DriveTo => TaskKind::DriveTo {
                        target,
                        tolerance: t.tolerance_m.unwrap_or(self.goal.tolerance_m),
                    },
                    TaskKindName::Panorama => TaskKind::Panorama,
                    TaskKindName::ScienceImage => TaskKind::ScienceImage { target },
                    TaskKindName::PlaceInstrument => TaskKind::PlaceInstrument { target },
                    TaskKindName::Scoop => TaskKind::Scoop { target },
                };
                TaskSpec { kind, parallel: t.parallel }
            })
            .collect()
    }

    /// The `[[faults]]` as the platform's schedule.
    pub fn fault_schedule(&self) -> Vec<crate::platform::ScheduledFault> {
        use crate::platform::{FaultTrigger, ScheduledFault};
        use rovernav_core::CameraKind;
        use rovernav_sim::Fault;
        self.faults
            .iter()
            .map(|f| {
                let fault = match (f.kind, f.sensor, f.side) {
                    (FaultKindName::SilentSensor, sensor, _) => Fault::SilentSensor(match sensor {
                        Some(SensorName::BodyFront) => CameraKind::BodyFront,
                        Some(SensorName::BodyRear) => CameraKind::BodyRear,
                        Some(SensorName::Lidar) => CameraKind::Lidar,
                        Some(SensorName::Mast) | None => CameraKind::Mast,
                    }),
                    (FaultKindName::StalledWheel, _, side) => {
                        Fault::StalledWheel { left: side != Some(Side::Right) }
                    }
                    (FaultKindName::CompassNan, _, _) => Fault::CompassNaN,
                };
                let at = match (f.at_cycle, f.at_time_s) {
                    (_, Some(t)) => FaultTrigger::Time(t),
                    (c, None) => FaultTrigger::Cycle(c.unwrap_or(0)),
                };
                ScheduledFault { fault, at }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_mission_parses() {
        let m = Mission::default_mission();
        assert_eq!(m.navigator, "astar-grid");
        assert!(matches!(m.terrain, TerrainSpec::Procedural { .. }));
    }

    #[test]
    fn misspelt_field_is_named_with_its_line() {
        let text = DEFAULT_MISSION_TOML.replace("navigator =", "navigatr =");
        let err = Mission::from_toml(&text, "m.toml").unwrap_err().to_string();
        assert!(err.contains("m.toml") && err.contains("navigatr") && err.contains("line "), "{err}");
    }

    #[test]
    fn sensor_overrides_out_of_range_name_their_field() {
        for (line, field) in [
            ("stereo_dropout = 1.5", "sensors.stereo_dropout"),
            ("stereo_noise_scale = -1.0", "sensors.stereo_noise_scale"),
            ("compass_sigma_deg = nan", "sensors.compass_sigma_deg"),
            ("range_source = \"lidar\"", "expected `raycast` or `stereo`"),
        ] {
            let text = format!("{DEFAULT_MISSION_TOML}\n[sensors]\n{line}\n");
            let err = Mission::from_toml(&text, "m.toml").unwrap_err().to_string();
            assert!(err.contains("m.toml") && err.contains(field), "{line}: {err}");
        }
        let text = format!(
            "{DEFAULT_MISSION_TOML}\n[sensors]\nstereo_noise_scale = 0.0\nstereo_dropout = 0.1\nrange_source = \"stereo\"\n"
        );
        let m = Mission::from_toml(&text, "m.toml").unwrap();
        // The mission file table written back parses to the same overrides.
        let again =
            Mission::from_toml(&format!("{DEFAULT_MISSION_TOML}{}", m.sensors.toml_table()), "m.toml")
                .unwrap();
        assert_eq!(again.sensors, m.sensors);
        assert_eq!(m.sensors.stereo_noise_scale, Some(0.0));
        assert_eq!(m.sensors.range_source, Some(RangeSourceSpec::Stereo));
    }

    #[test]
    fn a_sensor_override_takes_the_place_of_the_given_field_only() {
        let own =
            SensorSpec { compass_sigma_deg: Some(2.0), stereo_dropout: Some(0.2), ..Default::default() };
        let over =
            SensorSpec { stereo_dropout: Some(0.0), stereo_noise_scale: Some(0.5), ..Default::default() };
        let merged = own.overridden_by(&over);
        assert_eq!(merged.compass_sigma_deg, Some(2.0));
        assert_eq!(merged.stereo_dropout, Some(0.0));
        assert_eq!(merged.stereo_noise_scale, Some(0.5));
        assert_eq!(own.overridden_by(&SensorSpec::default()), own);
    }

    #[test]
    fn invalid_value_names_the_field() {
        let text = DEFAULT_MISSION_TOML.replace("rock_abundance = 0.16", "rock_abundance = 3.0");
        let err = Mission::from_toml(&text, "m.toml").unwrap_err().to_string();
        assert!(err.contains("terrain.rock_abundance"), "{err}");
    }

    #[test]
    fn tasks_and_faults_are_read_and_checked() {
        let text = format!(
            "{DEFAULT_MISSION_TOML}\n[[tasks]]\nkind = \"panorama\"\n[[tasks]]\nkind = \"scoop\"\nx = 20.5\ny = 20.0\nparallel = true\n\
             [[faults]]\nkind = \"stalled_wheel\"\nside = \"right\"\nat_cycle = 4\n"
        );
        let m = Mission::from_toml(&text, "m.toml").unwrap();
        assert_eq!(m.tasks.len(), 2);
        let plan = m.plan_tasks(&|x, y| rovernav_core::Point2::new(x, y));
        assert_eq!(
            plan[1].kind,
            crate::deliberative::TaskKind::Scoop { target: rovernav_core::Point2::new(20.5, 20.0) }
        );
        assert!(plan[1].parallel);
        let schedule = m.fault_schedule();
        assert_eq!(schedule[0].fault, rovernav_sim::Fault::StalledWheel { left: false });
        assert_eq!(schedule[0].at, crate::platform::FaultTrigger::Cycle(4));
        for (bad, field) in [
            ("[[tasks]]\nkind = \"scoop\"\nx = 1.0\n", "tasks[0].y"),
            ("[[tasks]]\nkind = \"panorama\"\nx = 1.0\n", "tasks[0].x"),
            (
                "[[tasks]]\nkind = \"panorama\"\n[[tasks]]\nkind = \"science_image\"\nx = 1.0\ny = 1.0\nparallel = true\n",
                "tasks[1].parallel",
            ),
            ("[[tasks]]\nkind = \"panorama\"\nparallel = true\n", "tasks[0].parallel"),
            ("[[faults]]\nkind = \"silent_sensor\"\n", "faults[0].sensor"),
            ("[[faults]]\nkind = \"compass_nan\"\nside = \"left\"\n", "faults[0].side"),
            ("[[faults]]\nkind = \"compass_nan\"\nat_cycle = 1\nat_time_s = 2.0\n", "faults[0].at_time_s"),
        ] {
            let err = Mission::from_toml(&format!("{DEFAULT_MISSION_TOML}\n{bad}"), "m.toml")
                .unwrap_err()
                .to_string();
            assert!(err.contains(field), "{field}: {err}");
        }
        let err =
            Mission::from_toml(&format!("{DEFAULT_MISSION_TOML}\n[[faults]]\nkind = \"meteor\"\n"), "m.toml")
                .unwrap_err()
                .to_string();
        assert!(err.contains("meteor") && err.contains("line "), "{err}");
    }

    #[test]
    fn navigator_params_are_read_and_checked_against_the_navigator() {
        let text = DEFAULT_MISSION_TOML.replace("\"astar-grid\"", "\"roverbug\"");
        let m = Mission::from_toml(
            &format!("{text}\n[navigator_params]\nsafety_buffer_m = 0.2\nmax_wedges = 40\n"),
            "m.toml",
        )
        .unwrap();
        assert_eq!(m.navigator_params.get("max_wedges"), Some(&40.0));
        for (bad, field) in [
            ("wedge_budget = 40", "navigator_params.wedge_budget"),
            ("clearance_margin = 1.5", "navigator_params.clearance_margin"),
            ("max_wedges = 2.5", "navigator_params.max_wedges"),
        ] {
            let full = format!("{text}\n[navigator_params]\n{bad}\n");
            let line = full.lines().count();
            let err = Mission::from_toml(&full, "m.toml").unwrap_err().to_string();
            assert!(err.contains("m.toml") && err.contains(field), "{field}: {err}");
            assert!(err.contains(&format!("line {line}:")), "{field}: {err}");
        }
        // Parameters are the named navigator's: astar-grid has no wedge budget.
        let err = Mission::from_toml(
            &format!("{DEFAULT_MISSION_TOML}\n[navigator_params]\nmax_wedges = 40\n"),
            "m.toml",
        )
        .unwrap_err()
        .to_string();
        assert!(err.contains("astar-grid") && err.contains("max_wedges"), "{err}");
    }

    #[test]
    fn start_needs_one_coordinate_frame() {
        let text = DEFAULT_MISSION_TOML.replace("x = 5.0\n", "");
        let err = Mission::from_toml(&text, "m.toml").unwrap_err().to_string();
        assert!(err.contains("`start`"), "{err}");
    }
}
