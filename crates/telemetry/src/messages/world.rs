//! `/sim/world`: the simulated world of a run, complete enough to rebuild it bit for bit.
//!
//! The rover, the sensor models, the rocks, the start and the goal are the simulator's and the
//! core's own types (they derive their serde and schema); only the height grid has a form of its
//! own here, byte planes of little-endian f32 in base64 (exact, NaN for no data included).

use crate::base64;
use rovernav_core::{Goal, GridGeometry, Pose2, RoverConfig};
use rovernav_executive::World;
use rovernav_sim::SensorModel;
use rovernav_terrain::{Dem, GeoReference, Rock, Terrain};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// The true terrain: elevation grid and rocks.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct TerrainMsg {
    /// Grid placement (row 0 south, column 0 west).
    pub grid: GridGeometry,
    /// Heights (m) as f32, row-major from the south-west corner, NaN for no data: their
    /// little-endian bytes in four planes (every first byte, then every second...), base64.
    #[schemars(extend("contentEncoding" = "base64"))]
    pub heights_f32_planes: String,
    /// The source file's nodata value, if any.
    pub nodata: Option<f32>,
    /// Georeference of the local frame.
    pub geo: GeoReference,
    /// The rocks.
    pub rocks: Vec<Rock>,
}

/// `/sim/world`: everything needed to rebuild the run's world and draw it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct WorldMsg {
    /// Always true: this is the simulator's ground truth, never shown to the autonomy.
    pub simulation_truth: bool,
    /// The terrain.
    pub terrain: TerrainMsg,
    /// The rover.
    pub rover: RoverConfig,
    /// The sensor models (the renderer's settings are not logged: a replay draws no images).
    pub sensor_model: SensorModel,
    /// True start pose.
    pub start: Pose2,
    /// The goal.
    pub goal: Goal,
}

impl WorldMsg {
    /// The message of a world.
    pub fn of(world: &World) -> Self {
        let dem = &world.terrain.dem;
        Self {
            simulation_truth: true,
            terrain: TerrainMsg {
                grid: *dem.geometry(),
                heights_f32_planes: base64::encode_f32_planes(&dem.heights.data),
                nodata: dem.nodata,
                geo: dem.geo.clone(),
                rocks: world.terrain.rocks.clone(),
            },
            rover: world.rover.clone(),
            sensor_model: world.sensor_model.clone(),
            start: world.start,
            goal: world.goal.clone(),
        }
    }

    /// Rebuilds the world; the error names the field that does not fit.
    pub fn to_world(&self) -> Result<World, String> {
        let t = &self.terrain;
        let geometry = t.grid;
        // The declared size is checked (its product may wrap) before anything that size is
        // allocated: the heights here, the replay's sensed grid later.
        let cells =
            rovernav_core::limits::checked_elements(&[geometry.rows as u64, geometry.cols as u64], 4, None)
                .map_err(|why| format!("field `terrain.grid`: {why}"))?;
        if !(geometry.origin_x.is_finite() && geometry.origin_y.is_finite()) {
            return Err("field `terrain.grid`: origin is not finite".into());
        }
        let heights = base64::decode_f32_planes(&t.heights_f32_planes)
            .map_err(|e| format!("field `terrain.heights_f32_planes`: {e}"))?;
        if heights.len() != cells || cells == 0 {
            return Err(format!(
                "field `terrain.heights_f32_planes`: {} heights for a {} x {} grid",
                heights.len(),
                geometry.cols,
                geometry.rows
            ));
        }
        if !(geometry.resolution.is_finite() && geometry.resolution > 0.0) {
            return Err(format!(
                "field `terrain.grid.resolution`: {} is not a positive size",
                geometry.resolution
            ));
        }
        Ok(World {
            terrain: Terrain {
                dem: Dem {
                    heights: rovernav_core::Grid2 { geometry, data: heights },
                    nodata: t.nodata,
                    geo: t.geo.clone(),
                },
                rocks: t.rocks.clone(),
            },
            rover: self.rover.clone(),
            sensor_model: self.sensor_model.clone(),
            start: self.start,
            goal: self.goal.clone(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::messages::tests::through_json;
    use rovernav_core::Point2;

    fn small_world() -> World {
        let mut w = rovernav_harness::long_yard_world(7, 3.0, 2.0, 0.5);
        w.terrain.dem.heights.data[5] = f32::NAN;
        w.terrain.dem.nodata = Some(-32768.0);
        w.terrain.dem.geo = GeoReference { crs: "Mars2000".into(), easting: 1234.5, northing: -0.1 };
        w.goal.waypoints = vec![Point2::new(1.0, 1.0)];
        w.goal.keep_out =
            vec![vec![Point2::new(0.1, 0.2), Point2::new(0.3, 0.2), Point2::new(0.2, 1.0 / 3.0)]];
        w.sensor_model.compass_sigma = 0.1f64.sqrt();
        w
    }

    #[test]
    fn world_round_trips_bit_exactly_and_fits_its_schema() {
        let world = small_world();
        assert!(!world.terrain.rocks.is_empty(), "the yard has rocks to carry");
        let back = through_json(&WorldMsg::of(&world)).to_world().unwrap();
        let bits = |d: &Dem| d.heights.data.iter().map(|h| h.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&back.terrain.dem), bits(&world.terrain.dem));
        assert_eq!(back.terrain.dem.heights.geometry, world.terrain.dem.heights.geometry);
        assert_eq!(back.terrain.dem.nodata, world.terrain.dem.nodata);
        assert_eq!(back.terrain.dem.geo, world.terrain.dem.geo);
        assert_eq!(back.terrain.rocks, world.terrain.rocks);
        assert_eq!(back.rover, world.rover);
        assert_eq!(back.sensor_model, world.sensor_model);
        assert_eq!(
            (back.start.x, back.start.y, back.start.yaw),
            (world.start.x, world.start.y, world.start.yaw)
        );
        assert_eq!(back.goal, world.goal);
    }

    #[test]
    fn world_declaring_a_huge_grid_is_refused_before_allocating() {
        let mut msg = WorldMsg::of(&small_world());
        let n = msg.terrain.grid.len();
        // A size whose product wraps to the true count, and one past the memory ceiling.
        msg.terrain.grid.cols = (1usize << 63) + n / 2;
        msg.terrain.grid.rows = 2;
        let e = msg.to_world().unwrap_err();
        assert!(e.contains("terrain.grid") && e.contains("overflows"), "{e}");
        msg.terrain.grid.cols = 1 << 20;
        msg.terrain.grid.rows = 1 << 20;
        let e = msg.to_world().unwrap_err();
        assert!(e.contains("terrain.grid") && e.contains("memory ceiling"), "{e}");
    }

    #[test]
    fn world_with_a_wrong_height_count_is_an_error_naming_the_field() {
        let mut msg = WorldMsg::of(&small_world());
        msg.terrain.grid.cols += 1;
        let err = msg.to_world().unwrap_err();
        assert!(err.contains("terrain.heights_f32_planes"), "{err}");
        let mut value = serde_json::to_value(WorldMsg::of(&small_world())).unwrap();
        value["sensor_model"]["proximity"]["bearings"].as_array_mut().unwrap().pop();
        let err = serde_json::from_value::<WorldMsg>(value).unwrap_err().to_string();
        assert!(err.contains("length 9"), "{err}");
    }
}
