//! `/sim/world`: the simulated world of a run, complete enough to rebuild it bit for bit.

use super::{Point2Msg, Pose2Msg, point_schema, points_schema, pose2_schema};
use crate::base64;
use crate::schema::{
    array, boolean, bytes, enumeration, fixed_array, integer, message, nullable, number, object, string,
};
use rovernav_core::{Goal, GridGeometry, Pose2, RoverConfig};
use rovernav_executive::World;
use rovernav_sim::{
    LidarModel, ProximityModel, RangeImagerModel, RangeSource, SensorModel, SlipModel, StereoImaging,
};
use rovernav_terrain::{Dem, GeoReference, Rock, Terrain};
use serde::{Deserialize, Serialize};
use serde_json::Value;

/// Placement of a grid (row 0 south, column 0 west).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct GridMsg {
    /// Columns (along x).
    pub cols: u64,
    /// Rows (along y).
    pub rows: u64,
    /// Cell size (m).
    pub resolution: f64,
    /// World x of the western edge (m).
    pub origin_x: f64,
    /// World y of the southern edge (m).
    pub origin_y: f64,
}

/// A rock body on the terrain.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
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
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
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

/// The rover's physical and sensing parameters (`RoverConfig`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RoverMsg {
    /// Body length (m).
    pub length: f64,
    /// Body width (m).
    pub width: f64,
    /// Wheel track (m).
    pub track: f64,
    /// Belly clearance (m).
    pub clearance: f64,
    /// Hazardous tilt (rad).
    pub max_tilt: f64,
    /// Top speed (m/s).
    pub max_speed: f64,
    /// In-place turn rate (rad/s).
    pub turn_rate: f64,
    /// Encoder counts per cm of wheel travel.
    pub encoder_counts_per_cm: f64,
    /// Mast camera height (m).
    pub mast_height: f64,
    /// Mast field of view (rad).
    pub mast_fov: f64,
    /// Mast useful range (m).
    pub mast_range: f64,
    /// Body camera height (m).
    pub body_camera_height: f64,
    /// Body field of view (rad).
    pub body_fov: f64,
    /// Body useful range (m).
    pub body_range: f64,
    /// Proximity sensor range (m).
    pub proximity_range: f64,
}

/// One range imager's ray grid and noise.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
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
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
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
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
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
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
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
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
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
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GoalMsg {
    /// Goal position.
    pub position: Point2Msg,
    /// Reach tolerance (m).
    pub tolerance: f64,
    /// Waypoints in order.
    pub waypoints: Vec<Point2Msg>,
    /// Keep-out polygons.
    pub keep_out: Vec<Vec<Point2Msg>>,
}

/// `/sim/world`: everything needed to rebuild the run's world and draw it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
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
    pub start: Pose2Msg,
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
                grid: GridMsg {
                    cols: g.cols as u64,
                    rows: g.rows as u64,
                    resolution: g.resolution,
                    origin_x: g.origin_x,
                    origin_y: g.origin_y,
                },
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
            rover: RoverMsg {
                length: r.length,
                width: r.width,
                track: r.track,
                clearance: r.clearance,
                max_tilt: r.max_tilt,
                max_speed: r.max_speed,
                turn_rate: r.turn_rate,
                encoder_counts_per_cm: r.encoder_counts_per_cm,
                mast_height: r.mast_height,
                mast_fov: r.mast_fov,
                mast_range: r.mast_range,
                body_camera_height: r.body_camera_height,
                body_fov: r.body_fov,
                body_range: r.body_range,
                proximity_range: r.proximity_range,
            },
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
            start: Pose2Msg { x: world.start.x, y: world.start.y, yaw: world.start.yaw },
            goal: GoalMsg {
                position: world.goal.position.into(),
                tolerance: world.goal.tolerance,
                waypoints: world.goal.waypoints.iter().map(|&p| p.into()).collect(),
                keep_out: world.goal.keep_out.iter().map(|z| z.iter().map(|&p| p.into()).collect()).collect(),
            },
        }
    }

    /// Rebuilds the world; the error names the field that does not fit.
    pub fn to_world(&self) -> Result<World, String> {
        let t = &self.terrain;
        let geometry = GridGeometry {
            cols: t.grid.cols as usize,
            rows: t.grid.rows as usize,
            resolution: t.grid.resolution,
            origin_x: t.grid.origin_x,
            origin_y: t.grid.origin_y,
        };
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
        let r = &self.rover;
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
            rover: RoverConfig {
                length: r.length,
                width: r.width,
                track: r.track,
                clearance: r.clearance,
                max_tilt: r.max_tilt,
                max_speed: r.max_speed,
                turn_rate: r.turn_rate,
                encoder_counts_per_cm: r.encoder_counts_per_cm,
                mast_height: r.mast_height,
                mast_fov: r.mast_fov,
                mast_range: r.mast_range,
                body_camera_height: r.body_camera_height,
                body_fov: r.body_fov,
                body_range: r.body_range,
                proximity_range: r.proximity_range,
            },
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
            start: Pose2::new(self.start.x, self.start.y, self.start.yaw),
            goal: Goal {
                position: self.goal.position.into(),
                tolerance: self.goal.tolerance,
                waypoints: self.goal.waypoints.iter().map(|&p| p.into()).collect(),
                keep_out: self.goal.keep_out.iter().map(|z| z.iter().map(|&p| p.into()).collect()).collect(),
            },
        })
    }

    /// The JSON Schema.
    pub fn schema() -> Value {
        let imager = || {
            object(
                "range imager ray grid and noise",
                &[
                    ("cols", integer("rays across")),
                    ("rows", integer("rays down")),
                    ("near_range", number("ground range of the bottom row (m)")),
                    ("up_margin", number("elevation margin of the top row (rad)")),
                    ("sigma_constant", number("constant range error sigma (m)")),
                    ("sigma_quadratic", number("range error sigma per squared metre (1/m)")),
                    ("dropout", number("ray dropout probability")),
                    ("capture_time", number("capture time (s)")),
                ],
            )
        };
        message(
            "rovernav.World",
            "The simulated world of a run (simulation truth: the autonomy never sees it)",
            &[
                ("simulation_truth", boolean("always true: ground truth, logged for scoring and pictures")),
                (
                    "terrain",
                    object(
                        "true terrain",
                        &[
                            (
                                "grid",
                                object(
                                    "elevation grid placement (row 0 south, column 0 west)",
                                    &[
                                        ("cols", integer("columns (along x)")),
                                        ("rows", integer("rows (along y)")),
                                        ("resolution", number("cell size (m)")),
                                        ("origin_x", number("world x of the western edge (m)")),
                                        ("origin_y", number("world y of the southern edge (m)")),
                                    ],
                                ),
                            ),
                            (
                                "heights_f32le",
                                bytes(
                                    "heights (m), little-endian f32, row-major from the south-west, NaN = no data",
                                ),
                            ),
                            ("nodata", nullable(number("the source file's nodata value"))),
                            ("crs", string("coordinate reference system of the projected frame")),
                            ("easting", number("projected easting of local (0, 0) (m)")),
                            ("northing", number("projected northing of local (0, 0) (m)")),
                            (
                                "rocks",
                                array(
                                    "rock bodies",
                                    object(
                                        "rock",
                                        &[
                                            ("x", number("centre east (m)")),
                                            ("y", number("centre north (m)")),
                                            ("diameter", number("diameter (m)")),
                                            ("height", number("height above the ground (m)")),
                                        ],
                                    ),
                                ),
                            ),
                        ],
                    ),
                ),
                (
                    "rover",
                    object(
                        "rover parameters",
                        &[
                            ("length", number("body length (m)")),
                            ("width", number("body width (m)")),
                            ("track", number("wheel track (m)")),
                            ("clearance", number("belly clearance (m)")),
                            ("max_tilt", number("hazardous tilt (rad)")),
                            ("max_speed", number("top speed (m/s)")),
                            ("turn_rate", number("in-place turn rate (rad/s)")),
                            ("encoder_counts_per_cm", number("encoder counts per cm of wheel travel")),
                            ("mast_height", number("mast camera height (m)")),
                            ("mast_fov", number("mast field of view (rad)")),
                            ("mast_range", number("mast useful range (m)")),
                            ("body_camera_height", number("body camera height (m)")),
                            ("body_fov", number("body field of view (rad)")),
                            ("body_range", number("body useful range (m)")),
                            ("proximity_range", number("proximity sensor range (m)")),
                        ],
                    ),
                ),
                (
                    "sensor_model",
                    object(
                        "sensor noise and mounting",
                        &[
                            ("mast", imager()),
                            ("mast_fine", nullable(imager())),
                            ("body", imager()),
                            (
                                "lidar",
                                object(
                                    "nodding LIDAR",
                                    &[
                                        ("imager", imager()),
                                        ("fov", number("horizontal field of view (rad)")),
                                        ("range", number("maximum planar range (m)")),
                                        ("height", number("mounting height (m)")),
                                        ("x_offset", number("mounting offset along body x (m)")),
                                    ],
                                ),
                            ),
                            (
                                "proximity",
                                object(
                                    "proximity threshold sensors",
                                    &[
                                        ("height", number("mounting height (m)")),
                                        ("bearings", fixed_array("beam bearings (rad)", number("rad"), 10)),
                                        (
                                            "setback",
                                            fixed_array("setback behind the front (m)", number("m"), 10),
                                        ),
                                        ("ground_return_ratio", number("level-ground return / threshold")),
                                        ("drop_margin", number("missing-ground margin (m)")),
                                        ("range_sigma", number("range noise sigma (m)")),
                                    ],
                                ),
                            ),
                            ("compass_sigma", number("compass sigma (rad)")),
                            ("inclinometer_sigma", number("inclinometer sigma (rad)")),
                            ("sun_sigma", number("sun sensor sigma (rad)")),
                            ("sun_visible", boolean("whether the sun is visible")),
                            ("gyro_bias_sigma", number("gyro turn-on bias sigma (rad/s)")),
                            ("gyro_bias_walk", number("gyro bias random walk (rad/s/sqrt(s))")),
                            ("gyro_noise_density", number("gyro rate noise density (rad/s/sqrt(Hz))")),
                            ("sample_rate", number("proprioceptive sample rate (Hz)")),
                            ("initial_rest_samples", integer("samples at rest in the first frame")),
                            (
                                "slip",
                                object(
                                    "wheel slip",
                                    &[
                                        ("base", number("level-ground slip ratio")),
                                        ("uphill_gain", number("uphill gain")),
                                        ("downhill_gain", number("downhill gain")),
                                        ("max", number("slip ratio bound")),
                                        ("lateral_gain", number("sideways creep gain")),
                                        ("turn_scrub", number("turn scrub fraction")),
                                        ("per_command_sigma", number("per-command slip sigma")),
                                    ],
                                ),
                            ),
                            (
                                "range_source",
                                nullable(enumeration("source of the stereo range", &["raycast", "stereo"])),
                            ),
                        ],
                    ),
                ),
                ("start", pose2_schema("true start pose")),
                (
                    "goal",
                    object(
                        "goal and constraints",
                        &[
                            ("position", point_schema()),
                            ("tolerance", number("reach tolerance (m)")),
                            ("waypoints", points_schema("waypoints in order")),
                            ("keep_out", array("keep-out polygons", points_schema("polygon vertices"))),
                        ],
                    ),
                ),
            ],
        )
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
        let back = through_json(&WorldMsg::of(&world), &WorldMsg::schema()).to_world().unwrap();
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
