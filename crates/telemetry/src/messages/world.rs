//! `/sim/world`: the simulated world of a run, complete enough to rebuild it bit for bit.

use crate::base64;
use rovernav_core::{Goal, GridGeometry, Pose2, RoverConfig};
use rovernav_executive::World;
use rovernav_sim::{
    LidarModel, ProximityModel, RangeImagerModel, RangeSource, SensorModel, SlipModel, StereoImaging,
};
use rovernav_terrain::{Dem, GeoReference, Rock, Terrain};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Placement of a grid (row 0 south, column 0 west).
pub type GridMsg = GridGeometry;

/// A rock body on the terrain.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct RockMsg {
    /// Centre east (m).
    pub x: f64,
    /// Centre north (m).
    pub y: f64,
    /// Diameter (m).
    pub diameter: f64,
    /// Height above the ground (m).
    pub height: f64,
}

/// The true terrain: elevation grid and rocks.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct TerrainMsg {
    /// Grid placement.
    pub grid: GridMsg,
    /// Heights (m) as little-endian f32, row-major from the south-west corner, NaN for no data.
    pub heights_f32le: String,
    /// The source file's nodata value, if any.
    pub nodata: Option<f32>,
    /// Coordinate reference system of the projected frame.
    pub crs: String,
    /// Projected easting of local (0, 0) (m).
    pub easting: f64,
    /// Projected northing of local (0, 0) (m).
    pub northing: f64,
    /// The rocks.
    pub rocks: Vec<RockMsg>,
}

/// The rover's physical and sensing parameters.
pub type RoverMsg = RoverConfig;

/// One range imager's ray grid and noise.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct ImagerMsg {
    /// Rays across.
    pub cols: u64,
    /// Rays down.
    pub rows: u64,
    /// Ground range of the bottom row (m).
    pub near_range: f64,
    /// Elevation margin of the top row (rad).
    pub up_margin: f64,
    /// Constant range error sigma (m).
    pub sigma_constant: f64,
    /// Range error sigma per squared metre (1/m).
    pub sigma_quadratic: f64,
    /// Ray dropout probability.
    pub dropout: f64,
    /// Capture time (s).
    pub capture_time: f64,
}

/// The nodding LIDAR.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct LidarMsg {
    /// Ray grid and noise.
    pub imager: ImagerMsg,
    /// Horizontal field of view (rad).
    pub fov: f64,
    /// Maximum planar range (m).
    pub range: f64,
    /// Mounting height (m).
    pub height: f64,
    /// Mounting offset along body x (m).
    pub x_offset: f64,
}

/// The proximity threshold sensors.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct ProximityModelMsg {
    /// Mounting height (m).
    pub height: f64,
    /// Beam bearings, index 0 leftmost (rad).
    pub bearings: Vec<f64>,
    /// Setback behind the body front (m).
    pub setback: Vec<f64>,
    /// Level-ground return as a multiple of the threshold.
    pub ground_return_ratio: f64,
    /// Missing-ground margin (m).
    pub drop_margin: f64,
    /// Range noise sigma (m).
    pub range_sigma: f64,
}

/// Wheel slip.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct SlipMsg {
    /// Level-ground slip ratio.
    pub base: f64,
    /// Uphill gain.
    pub uphill_gain: f64,
    /// Downhill gain.
    pub downhill_gain: f64,
    /// Slip ratio bound.
    pub max: f64,
    /// Sideways creep gain.
    pub lateral_gain: f64,
    /// Turn scrub fraction.
    pub turn_scrub: f64,
    /// Per-command slip sigma.
    pub per_command_sigma: f64,
}

/// Every noise and mounting parameter of the simulated platform (`SensorModel`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct SensorModelMsg {
    /// Mast stereo.
    pub mast: ImagerMsg,
    /// Full-resolution mast stereo (absent in logs written before it existed: the default).
    #[serde(default)]
    pub mast_fine: Option<ImagerMsg>,
    /// Body stereo.
    pub body: ImagerMsg,
    /// LIDAR.
    pub lidar: LidarMsg,
    /// Proximity sensors.
    pub proximity: ProximityModelMsg,
    /// Compass sigma (rad).
    pub compass_sigma: f64,
    /// Inclinometer sigma (rad).
    pub inclinometer_sigma: f64,
    /// Sun sensor sigma (rad).
    pub sun_sigma: f64,
    /// Whether the sun is visible.
    pub sun_visible: bool,
    /// Gyro turn-on bias sigma (rad/s).
    pub gyro_bias_sigma: f64,
    /// Gyro bias random walk (rad/s/sqrt(s)).
    pub gyro_bias_walk: f64,
    /// Gyro rate noise density (rad/s/sqrt(Hz)).
    pub gyro_noise_density: f64,
    /// Proprioceptive sample rate (Hz).
    pub sample_rate: f64,
    /// Samples at rest in the first frame.
    pub initial_rest_samples: u64,
    /// Wheel slip.
    pub slip: SlipMsg,
    /// Source of the stereo pairs' range (`raycast` or `stereo`); absent in older logs.
    #[serde(default)]
    pub range_source: Option<String>,
}

/// Goal, waypoints and keep-out zones.
pub type GoalMsg = Goal;

/// `/sim/world`: everything needed to rebuild the run's world and draw it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct WorldMsg {
    /// Always true: this is the simulator's ground truth, never shown to the autonomy.
    pub simulation_truth: bool,
    /// The terrain.
    pub terrain: TerrainMsg,
    /// The rover.
    pub rover: RoverMsg,
    /// The sensor models.
    pub sensor_model: SensorModelMsg,
    /// True start pose.
    pub start: Pose2,
    /// The goal.
    pub goal: GoalMsg,
}

fn imager_msg(m: &RangeImagerModel) -> ImagerMsg {
    ImagerMsg {
        cols: m.cols as u64,
        rows: m.rows as u64,
        near_range: m.near_range,
        up_margin: m.up_margin,
        sigma_constant: m.sigma_constant,
        sigma_quadratic: m.sigma_quadratic,
        dropout: m.dropout,
        capture_time: m.capture_time,
    }
}

fn imager_model(m: &ImagerMsg) -> RangeImagerModel {
    RangeImagerModel {
        cols: m.cols as usize,
        rows: m.rows as usize,
        near_range: m.near_range,
        up_margin: m.up_margin,
        sigma_constant: m.sigma_constant,
        sigma_quadratic: m.sigma_quadratic,
        dropout: m.dropout,
        capture_time: m.capture_time,
    }
}

fn ten(values: &[f64], field: &str) -> Result<[f64; 10], String> {
    values.try_into().map_err(|_| format!("field `{field}`: expected 10 values, found {}", values.len()))
}

impl WorldMsg {
    /// The message of a world.
    pub fn of(world: &World) -> Self {
        let dem = &world.terrain.dem;
        let g = dem.geometry();
        let r = &world.rover;
        let s = &world.sensor_model;
        Self {
            simulation_truth: true,
            terrain: TerrainMsg {
                grid: *g,
                heights_f32le: base64::encode_f32s(dem.heights.data.iter().copied()),
                nodata: dem.nodata,
                crs: dem.geo.crs.clone(),
                easting: dem.geo.easting,
                northing: dem.geo.northing,
                rocks: world
                    .terrain
                    .rocks
                    .iter()
                    .map(|k| RockMsg { x: k.x, y: k.y, diameter: k.diameter, height: k.height })
                    .collect(),
            },
            rover: r.clone(),
            sensor_model: SensorModelMsg {
                mast: imager_msg(&s.mast),
                mast_fine: Some(imager_msg(&s.mast_fine)),
                body: imager_msg(&s.body),
                lidar: LidarMsg {
                    imager: imager_msg(&s.lidar.imager),
                    fov: s.lidar.fov,
                    range: s.lidar.range,
                    height: s.lidar.height,
                    x_offset: s.lidar.x_offset,
                },
                proximity: ProximityModelMsg {
                    height: s.proximity.height,
                    bearings: s.proximity.bearings.to_vec(),
                    setback: s.proximity.setback.to_vec(),
                    ground_return_ratio: s.proximity.ground_return_ratio,
                    drop_margin: s.proximity.drop_margin,
                    range_sigma: s.proximity.range_sigma,
                },
                compass_sigma: s.compass_sigma,
                inclinometer_sigma: s.inclinometer_sigma,
                sun_sigma: s.sun_sigma,
                sun_visible: s.sun_visible,
                gyro_bias_sigma: s.gyro_bias_sigma,
                gyro_bias_walk: s.gyro_bias_walk,
                gyro_noise_density: s.gyro_noise_density,
                sample_rate: s.sample_rate,
                initial_rest_samples: s.initial_rest_samples as u64,
                slip: SlipMsg {
                    base: s.slip.base,
                    uphill_gain: s.slip.uphill_gain,
                    downhill_gain: s.slip.downhill_gain,
                    max: s.slip.max,
                    lateral_gain: s.slip.lateral_gain,
                    turn_scrub: s.slip.turn_scrub,
                    per_command_sigma: s.slip.per_command_sigma,
                },
                range_source: Some(
                    match s.range_source {
                        RangeSource::Raycast => "raycast",
                        RangeSource::Stereo => "stereo",
                    }
                    .into(),
                ),
            },
            start: world.start,
            goal: world.goal.clone(),
        }
    }

    /// Rebuilds the world; the error names the field that does not fit.
    pub fn to_world(&self) -> Result<World, String> {
        let t = &self.terrain;
        let geometry = t.grid;
        let heights = base64::decode_f32s(&t.heights_f32le)
            .map_err(|e| format!("field `terrain.heights_f32le`: {e}"))?;
        if heights.len() != geometry.len() || geometry.is_empty() {
            return Err(format!(
                "field `terrain.heights_f32le`: {} heights for a {} x {} grid",
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
        let s = &self.sensor_model;
        let p = &s.proximity;
        Ok(World {
            terrain: Terrain {
                dem: Dem {
                    heights: rovernav_core::Grid2 { geometry, data: heights },
                    nodata: t.nodata,
                    geo: GeoReference { crs: t.crs.clone(), easting: t.easting, northing: t.northing },
                },
                rocks: t
                    .rocks
                    .iter()
                    .map(|k| Rock { x: k.x, y: k.y, diameter: k.diameter, height: k.height })
                    .collect(),
            },
            rover: self.rover.clone(),
            sensor_model: SensorModel {
                mast: imager_model(&s.mast),
                mast_fine: s
                    .mast_fine
                    .as_ref()
                    .map(imager_model)
                    .unwrap_or_else(|| SensorModel::default().mast_fine),
                body: imager_model(&s.body),
                lidar: LidarModel {
                    imager: imager_model(&s.lidar.imager),
                    fov: s.lidar.fov,
                    range: s.lidar.range,
                    height: s.lidar.height,
                    x_offset: s.lidar.x_offset,
                },
                proximity: ProximityModel {
                    height: p.height,
                    bearings: ten(&p.bearings, "sensor_model.proximity.bearings")?,
                    setback: ten(&p.setback, "sensor_model.proximity.setback")?,
                    ground_return_ratio: p.ground_return_ratio,
                    drop_margin: p.drop_margin,
                    range_sigma: p.range_sigma,
                },
                compass_sigma: s.compass_sigma,
                inclinometer_sigma: s.inclinometer_sigma,
                sun_sigma: s.sun_sigma,
                sun_visible: s.sun_visible,
                gyro_bias_sigma: s.gyro_bias_sigma,
                gyro_bias_walk: s.gyro_bias_walk,
                gyro_noise_density: s.gyro_noise_density,
                sample_rate: s.sample_rate,
                initial_rest_samples: s.initial_rest_samples as usize,
                slip: SlipModel {
                    base: s.slip.base,
                    uphill_gain: s.slip.uphill_gain,
                    downhill_gain: s.slip.downhill_gain,
                    max: s.slip.max,
                    lateral_gain: s.slip.lateral_gain,
                    turn_scrub: s.slip.turn_scrub,
                    per_command_sigma: s.slip.per_command_sigma,
                },
                range_source: match s.range_source.as_deref() {
                    None | Some("raycast") => RangeSource::Raycast,
                    Some("stereo") => RangeSource::Stereo,
                    Some(other) => {
                        return Err(format!(
                            "sensor_model.range_source: unknown range source {other:?} (raycast or stereo)"
                        ));
                    }
                },
                stereo: StereoImaging::default(),
                // The pictures are logged themselves (`/camera/*`); their settings take the defaults.
                navcam: rovernav_sim::NavcamImaging::default(),
            },
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
        let mut w = rovernav_executive::long_yard_world(7, 3.0, 2.0, 0.5);
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
    fn world_with_a_wrong_height_count_is_an_error_naming_the_field() {
        let mut msg = WorldMsg::of(&small_world());
        msg.terrain.grid.cols += 1;
        let err = msg.to_world().unwrap_err();
        assert!(err.contains("terrain.heights_f32le"), "{err}");
        let mut msg = WorldMsg::of(&small_world());
        msg.sensor_model.proximity.bearings.pop();
        assert!(msg.to_world().unwrap_err().contains("sensor_model.proximity.bearings"));
    }
}
