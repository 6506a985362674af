//! Navigators: complete sense-plan-act algorithms behind the `Navigator` trait, chosen by name in
//! the mission file (as Nav2 chooses planner plugins).
//!
//! Each navigator composes the perception, mapping, planning and localisation layers; it sees
//! only the `NavInput` the executive gives it (pose estimate and sensor frames), never ground
//! truth. A new navigator is one module exporting an `ENTRY` plus one line in
//! [`registry::BUILTIN_NAVIGATORS`] (or, outside this crate, `Registry::builtin().with(ENTRY)`
//! installed with [`registry::install`]); the localisers are registered beside them
//! ([`localizers`]). The functions here build from the installed [`registry()`].

pub mod gestalt;
pub mod grid_nav;
pub mod localizers;
pub mod look_back;
pub mod nat;
pub mod params;
pub mod registry;
pub mod roverbug;
pub mod sr2;
pub mod terrain_model;

pub use grid_nav::{GridNavigator, GridNavigatorConfig};
pub use params::{NavigatorError, NavigatorParams};
pub use registry::{ParamInfo, Registry, registry};
pub use terrain_model::TerrainModel;

use rovernav_core::{Localizer, Navigator, Pose3, RoverConfig};

/// Every navigator combination's name (what a campaign's `all` runs), from the registry.
pub fn navigator_names() -> Vec<&'static str> {
    registry().navigator_names()
}

/// Every localiser name a mission may give, aliases included, from the registry.
pub fn localizer_names() -> Vec<&'static str> {
    registry().localizer_names()
}

/// A fresh navigator by registry name with its default parameters, or `None` if the name is
/// unknown. Any name followed by [`look_back::LOOK_BACK_SUFFIX`] ("+look-back") is that
/// navigator wrapped in [`look_back::LookBack`].
pub fn navigator_by_name(name: &str, rover: &RoverConfig) -> Option<Box<dyn Navigator>> {
    navigator_with_params(name, rover, &NavigatorParams::new()).ok()
}

/// A fresh navigator by registry name with the mission's parameters set (names and units as
/// [`navigator_params`] lists them); a "+look-back" name passes them to the wrapped navigator.
pub fn navigator_with_params(
    name: &str,
    rover: &RoverConfig,
    params: &NavigatorParams,
) -> Result<Box<dyn Navigator>, NavigatorError> {
    registry().build_navigator(name, rover, params)
}

/// A localiser by registry name (an alias, or `name(k=v,...)`) with its default parameters,
/// starting at `initial`; `None` if the name is unknown.
pub fn localizer_by_name(name: &str, rover: &RoverConfig, initial: Pose3) -> Option<Box<dyn Localizer>> {
    registry().build_localizer(name, rover, initial, &NavigatorParams::new()).ok()
}

/// Checks a navigator's parameters (names and ranges) for a mission or campaign file. An
/// unknown navigator passes: callers report unknown names with their own list of names.
pub fn check_params(name: &str, params: &NavigatorParams) -> Result<(), NavigatorError> {
    match registry().check_navigator(name, params) {
        Ok(()) | Err(NavigatorError::UnknownNavigator { .. }) => Ok(()),
        Err(e) => Err(e),
    }
}

/// The parameters a registered navigator takes, or `None` if the name is unknown.
pub fn navigator_params(name: &str) -> Option<Vec<ParamInfo>> {
    registry().navigator(name, None).ok().map(|choice| (choice.entry.params)())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::{Param, configured};

    #[test]
    fn every_navigator_lists_distinct_parameters_that_take_their_defaults_back() {
        let rover = RoverConfig::default();
        for name in navigator_names() {
            let params = navigator_params(name).expect("registered navigators list parameters");
            assert!(!params.is_empty(), "{name}");
            for (i, p) in params.iter().enumerate() {
                assert!(params[..i].iter().all(|q| q.name != p.name), "{name}: {} twice", p.name);
                let one: NavigatorParams = [(p.name.to_string(), p.default)].into();
                assert!(
                    navigator_with_params(name, &rover, &one).is_ok(),
                    "{name}: {} = {}",
                    p.name,
                    p.default
                );
            }
            let look_back = format!("{name}{}", look_back::LOOK_BACK_SUFFIX);
            assert_eq!(navigator_params(&look_back), Some(params), "{look_back}");
        }
    }

    /// Sets each parameter of `table` alone to a valid value other than its default and checks
    /// that it, and no other parameter, reads it back: a row pointing at another row's field
    /// (or converting wrongly) fails.
    fn each_parameter_sets_its_own_field<C: Clone>(defaults: C, table: Vec<Param<C>>) {
        let read = |config: &C| {
            let mut c = config.clone();
            table.iter().map(|p| params::value(&mut c, p)).collect::<Vec<f64>>()
        };
        let before = read(&defaults);
        for (i, p) in table.iter().enumerate() {
            let value = match p.unit {
                params::Unit::Fraction | params::Unit::CellSize if before[i] == 0.5 => 0.25,
                params::Unit::Fraction | params::Unit::CellSize => 0.5,
                params::Unit::Degrees if before[i] == 30.0 => 45.0,
                params::Unit::Degrees => 30.0,
                params::Unit::Switch => 1.0 - before[i],
                _ => before[i] + 1.0,
            };
            let one: NavigatorParams = [(p.name.to_string(), value)].into();
            let config = configured("test", defaults.clone(), &table, &one).expect("a valid value");
            let mut expected = before.clone();
            expected[i] = value;
            let after = read(&config);
            for (k, (a, e)) in after.iter().zip(&expected).enumerate() {
                assert!(
                    (a - e).abs() < 1e-9,
                    "setting {} changed {} to {a} (expected {e})",
                    p.name,
                    table[k].name
                );
            }
        }
    }

    #[test]
    fn every_parameter_sets_its_own_field() {
        each_parameter_sets_its_own_field(GridNavigatorConfig::default(), GridNavigatorConfig::params());
        each_parameter_sets_its_own_field(
            gestalt::GestaltConfig::default(),
            gestalt::GestaltConfig::params(),
        );
        each_parameter_sets_its_own_field(sr2::Sr2Config::default(), sr2::Sr2Config::params());
        each_parameter_sets_its_own_field(nat::NatConfig::default(), nat::NatConfig::params());
        each_parameter_sets_its_own_field(
            roverbug::RoverBugConfig::default(),
            roverbug::RoverBugConfig::params(),
        );
        each_parameter_sets_its_own_field(
            rovernav_localization::EkfMlParams::default(),
            localizers::ekf_ml_params(),
        );
    }

    #[test]
    fn unknown_names_and_values_are_errors_naming_them() {
        let rover = RoverConfig::default();
        let err = navigator_with_params("warp-drive", &rover, &NavigatorParams::new()).err().unwrap();
        assert!(
            matches!(&err, NavigatorError::UnknownNavigator { name, .. } if name == "warp-drive"),
            "{err}"
        );
        let bogus: NavigatorParams = [("wedge_count".to_string(), 3.0)].into();
        let err = navigator_with_params("roverbug+look-back", &rover, &bogus).err().unwrap();
        assert!(err.to_string().contains("no parameter `wedge_count`"), "{err}");
        let tiny: NavigatorParams = [("map_resolution_m".to_string(), 1e-6)].into();
        let err = navigator_with_params("astar-grid", &rover, &tiny).err().unwrap();
        assert!(matches!(err, NavigatorError::InvalidParam { .. }), "{err}");
        assert!(navigator_by_name("roverbug", &rover).is_some());
        // Checking leaves unknown navigator names to the caller, and names the parameter.
        assert!(check_params("warp-drive", &bogus).is_ok());
        assert_eq!(check_params("roverbug", &bogus).unwrap_err().param(), Some("wedge_count"));
    }
}
