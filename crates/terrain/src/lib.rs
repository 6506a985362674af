//! Terrain: elevation models, their loaders and procedural Mars terrain.
//!
//! `Dem` is the one elevation type of rovernav: a `Grid2<f32>` of heights (NaN where there is no
//! data) with a georeference that maps its local metric frame to projected map coordinates.
//! `ops` adds its queries (gradient, slope, normal, min/max) and transforms (crop, resample);
//! `io` loads GeoTIFF, PDS3 and `.npy` files (the only module that touches files);
//! `procedural` builds seeded Mars yards and puts rock fields on real DEMs;
//! `tiled` generates the yard model in tiles on demand, for terrain without edges.

#![warn(missing_docs)]

pub mod dem;
pub mod io;
pub mod ops;
pub mod procedural;
pub mod tiled;

pub use dem::{Dem, GeoReference, Rock, Terrain};
pub use io::LoadError;
pub use ops::{DemError, LocalRect};
pub use procedural::{MarsYardParams, RockFieldParams, generate};
