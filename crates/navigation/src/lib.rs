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
pub mod roverbug;
pub mod sr2;
pub mod terrain_model;

pub use grid_nav::{GridNavigator, GridNavigatorConfig};
pub use terrain_model::TerrainModel;

use rovernav_core::{Navigator, RoverConfig};

/// Registered navigator names.
pub const NAVIGATOR_NAMES: [&str; 7] =
    ["astar-grid", "mrpta", "gestalt", "gestalt+field-dstar", "sr2", "nat", "roverbug"];

/// A fresh navigator by registry name, or `None` if the name is unknown.
///
/// Any name followed by [`look_back::LOOK_BACK_SUFFIX`] ("+look-back") is that navigator
/// wrapped in [`look_back::LookBack`].
pub fn navigator_by_name(name: &str, rover: &RoverConfig) -> Option<Box<dyn Navigator>> {
    if let Some(base) = name.strip_suffix(look_back::LOOK_BACK_SUFFIX) {
        let inner = navigator_by_name(base, rover)?;
        return Some(Box::new(look_back::LookBack::new(inner, Default::default())));
    }
    match name {
        "astar-grid" => Some(Box::new(GridNavigator::new(
            "astar-grid",
            rover.clone(),
            GridNavigatorConfig { planner: "astar", ..Default::default() },
        ))),
        "mrpta" => Some(Box::new(GridNavigator::new(
            "mrpta",
            rover.clone(),
            GridNavigatorConfig { planner: "dstar-lite", ..Default::default() },
        ))),
        "gestalt" => Some(Box::new(gestalt::GestaltNavigator::new(
            "gestalt",
            rover.clone(),
            gestalt::GestaltConfig::default(),
        ))),
        "gestalt+field-dstar" => Some(Box::new(gestalt::GestaltNavigator::new(
            "gestalt+field-dstar",
            rover.clone(),
            gestalt::GestaltConfig { field_dstar: true, ..Default::default() },
        ))),
        "sr2" => Some(Box::new(sr2::Sr2Navigator::new(rover.clone(), sr2::Sr2Config::default()))),
        "nat" => Some(Box::new(nat::NatNavigator::new(rover.clone(), nat::NatConfig::default()))),
        "roverbug" => Some(Box::new(roverbug::RoverBug::new(rover.clone(), Default::default()))),
        _ => None,
    }
}
