//! Navigators: complete sense-plan-act algorithms behind the `Navigator` trait, chosen by name in
//! the mission file (as Nav2 chooses planner plugins).
//!
//! Each navigator composes the perception, mapping, planning and localisation layers; it sees
//! only the `NavInput` the executive gives it (pose estimate and sensor frames), never ground
//! truth. A new navigator is one module plus one line in [`navigator_by_name`].

pub mod gestalt;
pub mod grid_nav;
pub mod look_back;
pub mod nat;
pub mod params;
pub mod roverbug;
pub mod sr2;
pub mod terrain_model;

pub use grid_nav::{GridNavigator, GridNavigatorConfig};
pub use params::{NavigatorError, NavigatorParams};
pub use terrain_model::TerrainModel;

use params::{Param, configured};
use rovernav_core::{Navigator, RoverConfig};

/// Registered navigator names.
pub const NAVIGATOR_NAMES: [&str; 7] =
    ["astar-grid", "mrpta", "gestalt", "gestalt+field-dstar", "sr2", "nat", "roverbug"];

/// A fresh navigator by registry name with its default parameters, or `None` if the name is
/// unknown.
///
/// Any name followed by [`look_back::LOOK_BACK_SUFFIX`] ("+look-back") is that navigator
/// wrapped in [`look_back::LookBack`].
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
    if let Some(base) = name.strip_suffix(look_back::LOOK_BACK_SUFFIX) {
        let inner = navigator_with_params(base, rover, params)?;
        return Ok(Box::new(look_back::LookBack::new(inner, Default::default())));
    }
    let grid = |planner: &'static str| {
        let config = GridNavigatorConfig { planner, ..Default::default() };
        configured(name, config, &GridNavigatorConfig::params(), params)
    };
    let gestalt = |field_dstar: bool| {
        let config = gestalt::GestaltConfig { field_dstar, ..Default::default() };
        configured(name, config, &gestalt::GestaltConfig::params(), params)
    };
    Ok(match name {
        "astar-grid" => Box::new(GridNavigator::new("astar-grid", rover.clone(), grid("astar")?)),
        "mrpta" => Box::new(GridNavigator::new("mrpta", rover.clone(), grid("dstar-lite")?)),
        "gestalt" => Box::new(gestalt::GestaltNavigator::new("gestalt", rover.clone(), gestalt(false)?)),
        "gestalt+field-dstar" => {
            Box::new(gestalt::GestaltNavigator::new("gestalt+field-dstar", rover.clone(), gestalt(true)?))
        }
        "sr2" => {
            let config = configured(name, sr2::Sr2Config::default(), &sr2::Sr2Config::params(), params)?;
            Box::new(sr2::Sr2Navigator::new(rover.clone(), config))
        }
        "nat" => {
            let config = configured(name, nat::NatConfig::default(), &nat::NatConfig::params(), params)?;
            Box::new(nat::NatNavigator::new(rover.clone(), config))
        }
        "roverbug" => {
            let table = roverbug::RoverBugConfig::params();
            let config = configured(name, roverbug::RoverBugConfig::default(), &table, params)?;
            Box::new(roverbug::RoverBug::new(rover.clone(), config))
        }
        _ => return Err(NavigatorError::UnknownNavigator { name: name.to_string() }),
    })
}

/// Checks a navigator's parameters (names and ranges) for a mission or campaign file. An
/// unknown navigator passes: callers report unknown names with their own list of names.
pub fn check_params(name: &str, params: &NavigatorParams) -> Result<(), NavigatorError> {
    match navigator_with_params(name, &RoverConfig::default(), params) {
        Ok(_) | Err(NavigatorError::UnknownNavigator { .. }) => Ok(()),
        Err(e) => Err(e),
    }
}

/// One parameter a navigator takes in the mission file's `[navigator_params]` table.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamInfo {
    /// Name in the mission file.
    pub name: &'static str,
    /// Unit and valid range.
    pub unit: &'static str,
    /// One-line meaning.
    pub doc: &'static str,
    /// The value the navigator uses when the mission does not set it (in the parameter's unit).
    pub default: f64,
}

/// The parameters a registered navigator takes, or `None` if the name is unknown.
pub fn navigator_params(name: &str) -> Option<Vec<ParamInfo>> {
    fn info<C>(mut defaults: C, table: Vec<Param<C>>) -> Vec<ParamInfo> {
        table
            .iter()
            .map(|p| {
                let default = params::value(&mut defaults, p);
                ParamInfo { name: p.name, unit: p.unit.label(), doc: p.doc, default }
            })
            .collect()
    }
    let base = name.strip_suffix(look_back::LOOK_BACK_SUFFIX).unwrap_or(name);
    Some(match base {
        "astar-grid" | "mrpta" => info(GridNavigatorConfig::default(), GridNavigatorConfig::params()),
        "gestalt" | "gestalt+field-dstar" => {
            info(gestalt::GestaltConfig::default(), gestalt::GestaltConfig::params())
        }
        "sr2" => info(sr2::Sr2Config::default(), sr2::Sr2Config::params()),
        "nat" => info(nat::NatConfig::default(), nat::NatConfig::params()),
        "roverbug" => info(roverbug::RoverBugConfig::default(), roverbug::RoverBugConfig::params()),
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_navigator_lists_distinct_parameters_that_take_their_defaults_back() {
        let rover = RoverConfig::default();
        for name in NAVIGATOR_NAMES {
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
    }

    #[test]
    fn unknown_names_and_values_are_errors_naming_them() {
        let rover = RoverConfig::default();
        let err = navigator_with_params("warp-drive", &rover, &NavigatorParams::new()).err().unwrap();
        assert_eq!(err, NavigatorError::UnknownNavigator { name: "warp-drive".into() });
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
