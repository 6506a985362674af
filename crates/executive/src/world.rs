//! The world a run is given, in the terrain's local frame: the true terrain the simulator drives
//! on, the rover, its sensors' noise, the true start and the goal.
//!
//! The executive only receives a world; building one from a mission file (procedural yards,
//! DEM regions, tiled terrain) is the harness's business (`rovernav_harness::build_world`), as is
//! everything judged against its truth. [`goal_frame_to_local`] places a mission's task targets
//! in the world's frame; [`TiledSource`] is the simulator's window onto a tiled terrain.

use crate::mission::{Mission, TerrainSpec};
use rovernav_core::{Goal, Point2, Pose2, RoverConfig};
use rovernav_sim::{SensorModel, TerrainWindow};
use rovernav_terrain::Terrain;
use rovernav_terrain::tiled::{TiledParams, TiledTerrain};

/// The world of one run, in the terrain's local frame.
#[derive(Clone, Debug)]
pub struct World {
    /// Ground truth terrain (the simulator's; the autonomy never reads it).
    pub terrain: Terrain,
    /// The rover.
    pub rover: RoverConfig,
    /// Sensor noise models.
    pub sensor_model: SensorModel,
    /// True start pose.
    pub start: Pose2,
    /// Goal, waypoints and keep-out zones.
    pub goal: Goal,
}

/// Why the world could not be built.
#[derive(Debug, thiserror::Error)]
pub enum WorldError {
    /// The DEM file is missing or unreadable.
    #[error("{origin}: field `terrain.path`: {message}")]
    Dem {
        /// Mission source.
        origin: String,
        /// Loader message (names the file).
        message: String,
    },
    /// A field's value does not fit the terrain.
    #[error("{origin}: field `{field}`: {message}")]
    Invalid {
        /// Mission source.
        origin: String,
        /// Dotted field name.
        field: String,
        /// Why.
        message: String,
    },
}

/// Maps a point given in the mission's goal frame (local metres, or projected metres when the
/// goal is given as easting and northing) to the world's local frame.
pub fn goal_frame_to_local(mission: &Mission, world: &World) -> impl Fn(f64, f64) -> Point2 + use<> {
    let projected = matches!(mission.terrain, TerrainSpec::Dem { .. }) && mission.goal.easting.is_some();
    let (e0, n0) = (world.terrain.dem.geo.easting, world.terrain.dem.geo.northing);
    move |x, y| if projected { Point2::new(x - e0, y - n0) } else { Point2::new(x, y) }
}

/// A tiled terrain's generator and the simulator's window onto it (`kind = "tiled"`).
#[derive(Clone, Debug, PartialEq)]
pub struct TiledSource {
    /// The tiles' parameters (seed, yard model, clear pads at the start, waypoints and goal).
    pub params: TiledParams,
    /// Side of the simulator's window of finest cells (m).
    pub window_m: f64,
}

impl TiledSource {
    /// The simulator's window onto these tiles.
    pub fn window(&self) -> TerrainWindow {
        let cache = TiledTerrain::new(self.params.clone(), window_cache_tiles(self))
            .expect("parameters checked when the source was made");
        TerrainWindow::new(cache, 0.5 * self.window_m, rovernav_sim::terrain_window::DEFAULT_MARGIN_M)
    }
}

/// Tiles the window's cache holds: those a window covers, twice over (a re-centred window and
/// the last one).
fn window_cache_tiles(source: &TiledSource) -> usize {
    let per_side = (source.window_m / source.params.tile_size_m()).ceil() as usize + 1;
    2 * per_side * per_side
}
