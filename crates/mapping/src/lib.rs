//! rovernav mapping layer: the robot-centred rolling (toroidal) grid and the world map manager.
//!
//! * [`rolling::RollingGrid`] is the MRPTA T-grid store (paper 004 section 3.3): a fixed-size
//!   window of cells that follows the rover; moving it shifts an index offset and clears only
//!   the cells that fall off, never copying.
//! * [`local::LocalMap`] is the set of per-cell layers a terrain evaluator hands over.
//! * [`world::WorldMap`] is the map manager's world model (paper 004 section 3.4): elevation,
//!   variance, traversability, goodness and sensed layers, initialised flat/unknown or from an
//!   orbital DEM, fused with local maps using the pose estimate.
//!
//! This crate depends only on `rovernav-core`: heights come in as `Grid2<f32>`, never through the
//! terrain or simulator crates.

pub mod error;
pub mod local;
pub mod rolling;
pub mod world;

pub use error::MappingError;
pub use local::LocalMap;
pub use rolling::{CopyingGrid, RollingGrid};
pub use world::{
    FuseStats, TRAVERSABILITY_NEUTRAL, TRAVERSABILITY_UNKNOWN, WorldCell, WorldMap, WorldMapConfig,
};
