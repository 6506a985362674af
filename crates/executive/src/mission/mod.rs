//! The mission file: terrain, rover, sensors, start, goal, navigator, limits and seed (TOML).
//!
//! Unknown fields are rejected so that a misspelt key is an error naming the key and its line,
//! not a silently ignored setting.

pub mod check;
mod faults;
mod lander;
mod power;
mod route;
mod sensors;
mod sky;
mod tasks;
mod terrain;

pub use faults::{
    DEFAULT_GYRO_JUMP_DEG_S, FaultKindName, FaultSpec, SensorName, Side, check as check_faults,
};
pub use lander::LanderSpec;
pub use power::PowerSpec;
pub use route::{GoalSpec, PoseSpec};
pub use sensors::{RangeSourceSpec, RoverSpec, SensorSpec};
pub use sky::{SkyKind, SkySpec};
pub use tasks::{TaskKindName, TaskSpecToml};
pub use terrain::{TerrainSpec, TiledSpec};

use serde::Deserialize;
use std::path::{Path, PathBuf};

/// The built-in default mission (`missions/default.toml`).
pub const DEFAULT_MISSION_TOML: &str = include_str!("../../../../missions/default.toml");

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
    /// Registry name of the navigator (`rovernav navigators` lists them; old combined names
    /// such as `gestalt+field-dstar` are aliases).
    #[serde(default = "default_navigator")]
    pub navigator: String,
    /// The global planner the navigator runs under, among those `rovernav navigators` lists
    /// for it (default: its first).
    #[serde(default)]
    pub global_planner: Option<String>,
    /// Parameters of the navigator (`[navigator_params]`, names and units as `rovernav
    /// navigators` lists them); unset ones keep the navigator's defaults.
    #[serde(default)]
    pub navigator_params: rovernav_navigation::NavigatorParams,
    /// A registered navigator to run in shadow beside the driving one: stepped on the same
    /// inputs, its commands and plans logged on `/navigation/shadow`, never obeyed (paper 003
    /// section 6's "no update" checkout).
    #[serde(default)]
    pub shadow_navigator: Option<String>,
    /// Registry name of the localiser.
    #[serde(default = "default_localizer")]
    pub localizer: String,
    /// Parameters of the localiser (`[localizer_params]`, as `rovernav navigators` lists them).
    #[serde(default)]
    pub localizer_params: rovernav_navigation::NavigatorParams,
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
    /// Clouds and dust devils in the simulated sky (`[[sky]]`).
    #[serde(default)]
    pub sky: Vec<SkySpec>,
    /// The solar panel, battery, loads and sleep thresholds (`[power]`; defaults: a small rover).
    #[serde(default)]
    pub power: PowerSpec,
    /// A lander watching the rover's in-place turns (`[lander]`; none by default).
    #[serde(default)]
    pub lander: Option<LanderSpec>,
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
    let message = match check::line_of(text, &field) {
        Some(line) => format!("line {line}: {message}"),
        None => message,
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

    /// The navigator as one registry name (an alias's label, e.g. `gestalt+field-dstar` for
    /// `gestalt` under `field-dstar`); the name as given when it is not registered.
    pub fn navigator_spec(&self) -> String {
        let registry = rovernav_navigation::registry();
        match registry.navigator(&self.navigator, self.global_planner.as_deref()) {
            Ok(choice) => choice.spec(),
            Err(_) => self.navigator.clone(),
        }
    }

    /// The shadow navigator as one registry name (see [`Mission::navigator_spec`]), if any.
    pub fn shadow_navigator_spec(&self) -> Option<String> {
        let registry = rovernav_navigation::registry();
        self.shadow_navigator.as_ref().map(|name| match registry.navigator(name, None) {
            Ok(choice) => choice.spec(),
            Err(_) => name.clone(),
        })
    }

    /// The localiser as one registry name (an alias, or `name(k=v,...)` with its parameters);
    /// the name as given when it is not registered.
    pub fn localizer_spec(&self) -> String {
        let registry = rovernav_navigation::registry();
        match registry.localizer(&self.localizer, &self.localizer_params) {
            Ok(choice) => registry.localizer_spec(&choice),
            Err(_) => self.localizer.clone(),
        }
    }

    /// Checks the navigator's global planner and parameters (an unknown name passes).
    fn check_navigator(&self) -> Result<(), rovernav_navigation::NavigatorError> {
        use rovernav_navigation::NavigatorError;
        let registry = rovernav_navigation::registry();
        match registry.navigator(&self.navigator, self.global_planner.as_deref()) {
            Ok(choice) => rovernav_navigation::check_params(&choice.spec(), &self.navigator_params),
            Err(NavigatorError::UnknownNavigator { .. }) => Ok(()),
            Err(e) => Err(e),
        }
    }

    fn validate(&self, origin: &str) -> Result<(), MissionError> {
        let bad = |field: &str, message: &str| {
            Err(MissionError::Invalid { path: origin.into(), field: field.into(), message: message.into() })
        };
        if let Err(why) = check::output_name(&self.name) {
            return bad("name", &why);
        }
        if let Some(Err((field, why))) = self.lander.as_ref().map(LanderSpec::check) {
            return bad(field, &why);
        }
        if let Err(why) = check::positive_up_to(self.time_limit_s, 1.0e7, " s") {
            return bad("time_limit_s", &why);
        }
        if !(1..=10_000_000).contains(&self.max_cycles) {
            return bad("max_cycles", "must be in [1, 10000000]");
        }
        if let Err((field, why)) = self.terrain.check() {
            return bad(field, why);
        }
        if let TerrainSpec::Procedural { craters_per_hectare: Some(c), size_m, .. } = &self.terrain
            && let Err(why) = check::craters_per_hectare(*c, *size_m)
        {
            return bad("terrain.craters_per_hectare", &why);
        }
        if let Err((field, why)) = self.rover.check() {
            return bad(&format!("rover.{field}"), &why);
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
            if let Some(why) = [x, y, e, n].iter().find_map(|v| v.and_then(|v| check::coordinate(v).err())) {
                return bad(name, &format!("coordinates {why}"));
            }
        }
        if !self.start.yaw_deg.is_finite() {
            return bad("start.yaw_deg", "must be a finite number");
        }
        if let Err((field, why)) = self.sensors.check() {
            return bad(&format!("sensors.{field}"), why);
        }
        if let Err(why) = check::tolerance(self.goal.tolerance_m) {
            return bad("goal.tolerance_m", &why);
        }
        for (i, w) in self.goal.waypoints.iter().enumerate() {
            if let Some(why) = w.iter().find_map(|v| check::coordinate(*v).err()) {
                return bad(&format!("goal.waypoints[{i}]"), &format!("coordinates {why}"));
            }
        }
        // An unknown navigator or localiser name is the run's error (it lists the registered
        // ones).
        if let Err(e) = self.check_navigator() {
            let field = match e.param() {
                _ if e.is_about_global_planner() => "global_planner".into(),
                Some(p) => format!("navigator_params.{p}"),
                None => "navigator_params".into(),
            };
            return bad(&field, &e.to_string());
        }
        let registry = rovernav_navigation::registry();
        if let Some(name) = &self.shadow_navigator
            && let Err(e) = registry.navigator(name, None)
        {
            return bad("shadow_navigator", &e.to_string());
        }
        if let Err(e) = registry.check_localizer(&self.localizer, &self.localizer_params)
            && !matches!(e, rovernav_navigation::NavigatorError::UnknownLocalizer { .. })
        {
            let field = e.param().map_or("localizer_params".into(), |p| format!("localizer_params.{p}"));
            return bad(&field, &e.to_string());
        }
        for (i, zone) in self.goal.keep_out.iter().enumerate() {
            if zone.len() < 3 {
                return bad(&format!("goal.keep_out[{i}]"), "a polygon needs at least 3 vertices");
            }
            if let Some(why) = zone.iter().flatten().find_map(|v| check::coordinate(*v).err()) {
                return bad(&format!("goal.keep_out[{i}]"), &format!("vertex coordinates {why}"));
            }
        }
        if let Err((field, why)) = tasks::check(self) {
            return bad(&field, &why);
        }
        if let Err((field, why)) = faults::check(&self.faults) {
            return bad(&field, why);
        }
        if let Err((field, why)) = sky::check(&self.sky) {
            return bad(&field, why);
        }
        if let Err((field, why)) = self.power.check() {
            return bad(&format!("power.{field}"), &why);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests;
