//! The world truth a mission names: terrain, rover, sensors, start and goal in local metres.
//!
//! [`build_world`] turns a mission file's tables into the [`World`] the executive's simulator
//! drives on (a procedural yard, a region of a DEM with rocks added, or the overview of a tiled
//! terrain with [`tiled_source`] giving the simulator its fine window); [`long_yard_world`] is a
//! hand-made yard for traverse tests. The executive only receives a world; what is true in it is
//! the simulation's to know.

use rovernav_core::{Goal, Point2, Pose2, RoverConfig};
use rovernav_executive::mission::{GoalSpec, Mission, PoseSpec, RangeSourceSpec, TerrainSpec, TiledSpec};
use rovernav_executive::world::TiledSource;
use rovernav_executive::{World, WorldError};
use rovernav_sim::{RangeSource, SensorModel};
use rovernav_terrain::procedural::{ClearPad, RockyRegionParams, rocky_region};
use rovernav_terrain::tiled::{TiledParams, TiledTerrain};
use rovernav_terrain::{LocalRect, MarsYardParams, RockFieldParams, Terrain};
use std::path::PathBuf;

/// Resolves a data path: absolute, relative to the mission file, or relative to `ROVERNAV_DATA`.
fn resolve_data_path(mission: &Mission, path: &PathBuf) -> PathBuf {
    if path.is_absolute() {
        return path.clone();
    }
    if let Some(base) = &mission.base_dir {
        let p = base.join(path);
        if p.exists() {
            return p;
        }
    }
    rovernav_core::data_dir().join(path)
}

/// The rover configuration with the mission's overrides.
pub fn rover_config(mission: &Mission) -> RoverConfig {
    let r = &mission.rover;
    let d = RoverConfig::default();
    RoverConfig {
        length: r.length_m.unwrap_or(d.length),
        width: r.width_m.unwrap_or(d.width),
        clearance: r.clearance_m.unwrap_or(d.clearance),
        max_tilt: r.max_tilt_deg.map_or(d.max_tilt, f64::to_radians),
        max_speed: r.max_speed_mps.unwrap_or(d.max_speed),
        mast_range: r.mast_range_m.unwrap_or(d.mast_range),
        mast_fov: r.mast_fov_deg.map_or(d.mast_fov, f64::to_radians),
        ..d
    }
}

/// Builds the world of a mission; `origin` names the mission in error messages.
pub fn build_world(mission: &Mission, origin: &str) -> Result<World, WorldError> {
    let rover = rover_config(mission);
    let mut sensor_model = SensorModel { power: mission.power.config(), ..SensorModel::default() };
    if let Some(s) = mission.sensors.compass_sigma_deg {
        sensor_model.compass_sigma = s.to_radians();
    }
    if let Some(p) = mission.sensors.stereo_dropout {
        sensor_model.mast.dropout = p;
        sensor_model.mast_fine.dropout = p;
        sensor_model.body.dropout = p;
    }
    if let Some(k) = mission.sensors.stereo_noise_scale {
        for imager in [&mut sensor_model.mast, &mut sensor_model.mast_fine, &mut sensor_model.body] {
            imager.sigma_constant *= k;
            imager.sigma_quadratic *= k;
        }
    }
    if let Some(source) = mission.sensors.range_source {
        sensor_model.range_source = match source {
            RangeSourceSpec::Raycast => RangeSource::Raycast,
            RangeSourceSpec::Stereo => RangeSource::Stereo,
        };
    }
    let invalid = |field: &str, message: String| WorldError::Invalid {
        origin: origin.into(),
        field: field.into(),
        message,
    };

    let (terrain, to_local): (Terrain, Box<ToLocal>) = match &mission.terrain {
        TerrainSpec::Procedural {
            size_m,
            resolution_m,
            rock_abundance,
            relief_m,
            slope_deg,
            craters_per_hectare,
        } => {
            let start = local_point(&pose_xy(&mission.start), &|e, n| (e, n));
            let goal = local_point(&goal_xy(&mission.goal), &|e, n| (e, n));
            let mut params = MarsYardParams {
                width_m: *size_m,
                height_m: *size_m,
                resolution: *resolution_m,
                seed: mission.seed,
                relief_amplitude_m: *relief_m,
                regional_slope_deg: *slope_deg,
                rocks: RockFieldParams { abundance: *rock_abundance, ..Default::default() },
                clear_pads: vec![pad(start), pad(goal)],
                ..Default::default()
            };
            if let Some(c) = craters_per_hectare {
                params.crater_density = c / 10_000.0;
            }
            (rovernav_terrain::procedural::generate(&params), Box::new(|e, n| (e, n)))
        }
        TerrainSpec::Dem { path, region, resolution_m, rock_abundance } => {
            let file = resolve_data_path(mission, path);
            // A FIFO, device or folder would block or fail obscurely in the reader.
            if let Ok(meta) = std::fs::metadata(&file)
                && !meta.is_file()
            {
                return Err(invalid("terrain.path", format!("{} is not a regular file", file.display())));
            }
            let dem = rovernav_terrain::io::load_geotiff(&file)
                .map_err(|e| WorldError::Dem { origin: origin.into(), message: e.to_string() })?;
            let g = *dem.geometry();
            let region = match region {
                Some([e0, n0, e1, n1]) => {
                    let (x0, y0) = dem.to_local(*e0, *n0);
                    let (x1, y1) = dem.to_local(*e1, *n1);
                    LocalRect { x_min: x0, y_min: y0, x_max: x1, y_max: y1 }
                }
                None => LocalRect::from_corner_size(g.origin_x, g.origin_y, g.width_m(), g.height_m()),
            };
            let source_geo = dem.geo.clone();
            let source_local = move |e: f64, n: f64| (e - source_geo.easting, n - source_geo.northing);
            let params = RockyRegionParams {
                region,
                resolution: *resolution_m,
                rocks: RockFieldParams { abundance: *rock_abundance, ..Default::default() },
                micro_relief_m: 0.03,
                seed: mission.seed,
                clear_pads: vec![
                    pad(local_point(&pose_xy(&mission.start), &source_local)),
                    pad(local_point(&goal_xy(&mission.goal), &source_local)),
                ],
            };
            let terrain =
                rocky_region(&dem, &params).map_err(|e| invalid("terrain.region", e.to_string()))?.rebased();
            let geo = terrain.dem.geo.clone();
            let to_local = move |e: f64, n: f64| (e - geo.easting, n - geo.northing);
            (terrain, Box::new(to_local))
        }
        TerrainSpec::Tiled(spec) => {
            let source = tiled_source_of(mission, spec).map_err(|e| invalid("terrain", e))?;
            (overview(&source, mission).map_err(|e| invalid("terrain", e))?, Box::new(|e, n| (e, n)))
        }
    };

    let start_xy = local_point(&pose_xy(&mission.start), &*to_local);
    let goal_xy = local_point(&goal_xy(&mission.goal), &*to_local);
    for (field, p) in [("start", start_xy), ("goal", goal_xy)] {
        if terrain.dem.height(p.x, p.y).is_none() {
            let g = terrain.dem.geometry();
            return Err(invalid(
                field,
                format!(
                    "({:.2}, {:.2}) is outside the terrain (local extent {:.1} x {:.1} m) or has no elevation data",
                    p.x,
                    p.y,
                    g.width_m(),
                    g.height_m()
                ),
            ));
        }
    }
    let spec_to_local = |v: &[f64; 2]| {
        let (x, y) = if mission.goal.easting.is_some() { to_local(v[0], v[1]) } else { (v[0], v[1]) };
        Point2::new(x, y)
    };
    let waypoints: Vec<Point2> = mission.goal.waypoints.iter().map(spec_to_local).collect();
    for (i, p) in waypoints.iter().enumerate() {
        if terrain.dem.height(p.x, p.y).is_none() {
            return Err(invalid(
                &format!("goal.waypoints[{i}]"),
                format!("({:.2}, {:.2}) is outside the terrain or has no elevation data", p.x, p.y),
            ));
        }
    }
    let goal = Goal {
        position: goal_xy,
        tolerance: mission.goal.tolerance_m,
        waypoints,
        keep_out: mission.goal.keep_out.iter().map(|z| z.iter().map(spec_to_local).collect()).collect(),
    };
    // The sky's clouds and dust devils, placed from the start on its ground.
    let ground_z = terrain.dem.height(start_xy.x, start_xy.y).unwrap_or(0.0);
    sensor_model.navcam.volumes =
        mission.sky.iter().map(|s| s.volume(start_xy.x, start_xy.y, ground_z)).collect();
    // The lander station, placed from the start; it must stand on the terrain.
    if let Some(lander) = &mission.lander {
        let station = lander.station(start_xy.x, start_xy.y);
        let [fx, fy] = station.position;
        if terrain.dem.height(fx, fy).is_none() {
            return Err(invalid(
                "lander.distance_m",
                format!("puts the lander at ({fx:.1}, {fy:.1}) m, off the terrain"),
            ));
        }
        sensor_model.lander = Some(station);
    }
    Ok(World {
        terrain,
        rover,
        sensor_model,
        start: Pose2::new(start_xy.x, start_xy.y, mission.start.yaw_deg.to_radians()),
        goal,
    })
}

/// Tiles along a side at the finest level.
const TILE_CELLS: usize = 512;

/// Largest overview grid (cells).
const OVERVIEW_MAX_CELLS: usize = 1_000_000;

/// Margin of the overview around the route (m).
const OVERVIEW_MARGIN_M: f64 = 60.0;

/// The source of a mission's tiled terrain; the error says which value does not fit.
pub fn tiled_source_of(mission: &Mission, spec: &TiledSpec) -> Result<TiledSource, String> {
    // Octaves down to the yard's finest relief wavelength (0.375 m for its 12 m, 6 octaves).
    let octaves = 1 + (spec.relief_wavelength_m / 0.375).log2().floor().clamp(0.0, 15.0) as u32;
    let pads = route_points(mission).into_iter().map(pad).collect();
    let yard = MarsYardParams {
        resolution: spec.resolution_m,
        seed: mission.seed,
        relief_amplitude_m: spec.relief_m,
        relief_wavelength_m: spec.relief_wavelength_m,
        relief_octaves: octaves,
        roughness: spec.roughness,
        crater_density: spec.craters_per_hectare / 10_000.0,
        crater_max_diameter_m: spec.crater_max_diameter_m,
        ridge_amplitude_m: spec.ridge_m,
        ridge_wavelength_m: spec.ridge_wavelength_m,
        ridge_azimuth_deg: spec.ridge_azimuth_deg,
        regional_slope_deg: spec.slope_deg,
        rocks: RockFieldParams { abundance: spec.rock_abundance, ..Default::default() },
        clear_pads: pads,
        ..MarsYardParams::default()
    };
    let params = TiledParams::new(yard, TILE_CELLS).map_err(|e| e.to_string())?;
    Ok(TiledSource { params, window_m: spec.window_m })
}

/// The world's terrain: a coarse overview of the route and its surroundings (bare ground at
/// the finest level of at most [`OVERVIEW_MAX_CELLS`] cells), for drawing, the operator's
/// area and the sensed-cell grid; the simulator drives on its fine window.
fn overview(source: &TiledSource, mission: &Mission) -> Result<Terrain, String> {
    let points = route_points(mission);
    let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
    for p in &points {
        (x0, y0, x1, y1) = (x0.min(p.x), y0.min(p.y), x1.max(p.x), y1.max(p.y));
    }
    if !points.iter().all(|p| p.x.is_finite() && p.y.is_finite()) {
        return Err("start, goal and waypoints need x and y (local metres) on a tiled terrain".into());
    }
    let m = OVERVIEW_MARGIN_M;
    let rect = LocalRect { x_min: x0 - m, y_min: y0 - m, x_max: x1 + m, y_max: y1 + m };
    let area = (rect.x_max - rect.x_min) * (rect.y_max - rect.y_min);
    let level = source.params.level_for((area / OVERVIEW_MAX_CELLS as f64).sqrt());
    let mut tiles = TiledTerrain::new(source.params.clone(), 64).map_err(|e| e.to_string())?;
    tiles.fill(rect, level).map_err(|e| e.to_string())
}

/// The source of a mission's tiled terrain, if it has one.
pub fn tiled_source(mission: &Mission) -> Option<TiledSource> {
    match &mission.terrain {
        TerrainSpec::Tiled(spec) => tiled_source_of(mission, spec).ok(),
        _ => None,
    }
}

/// Start, waypoints and goal of a mission in local metres (NaN where given as projected).
fn route_points(mission: &Mission) -> Vec<Point2> {
    let mut points = vec![local_point(&pose_xy(&mission.start), &|e, n| (e, n))];
    points.extend(mission.goal.waypoints.iter().map(|w| Point2::new(w[0], w[1])));
    points.push(local_point(&goal_xy(&mission.goal), &|e, n| (e, n)));
    points
}

/// Maps projected (easting, northing) to the terrain's local frame.
type ToLocal = dyn Fn(f64, f64) -> (f64, f64);

/// A rock-free pad around a mission's start or goal, larger than the rover.
fn pad(p: Point2) -> ClearPad {
    ClearPad { x: p.x, y: p.y, radius: 1.0 }
}

/// A pose or goal's coordinates: `(value, projected?)`.
type SpecXy = ((f64, f64), bool);

fn local_point(spec: &SpecXy, to_local: &dyn Fn(f64, f64) -> (f64, f64)) -> Point2 {
    let ((a, b), projected) = *spec;
    let (x, y) = if projected { to_local(a, b) } else { (a, b) };
    Point2::new(x, y)
}

fn pose_xy(p: &PoseSpec) -> SpecXy {
    match (p.x, p.y, p.easting, p.northing) {
        (Some(x), Some(y), _, _) => ((x, y), false),
        (_, _, Some(e), Some(n)) => ((e, n), true),
        _ => ((f64::NAN, f64::NAN), false),
    }
}

fn goal_xy(g: &GoalSpec) -> SpecXy {
    match (g.x, g.y, g.easting, g.northing) {
        (Some(x), Some(y), _, _) => ((x, y), false),
        (_, _, Some(e), Some(n)) => ((e, n), true),
        _ => ((f64::NAN, f64::NAN), false),
    }
}

/// A long procedural yard for traverse tests: `length` m from a start `end_margin` m inside its
/// west end to a goal `end_margin` m inside its east end, `height` m wide, rock abundance 0.1.
pub fn long_yard_world(seed: u64, length: f64, height: f64, end_margin: f64) -> World {
    let start = Point2::new(end_margin, height / 2.0);
    let goal = Point2::new(end_margin + length, height / 2.0);
    let params = MarsYardParams {
        width_m: length + 2.0 * end_margin,
        height_m: height,
        resolution: 0.05,
        seed,
        rocks: RockFieldParams { abundance: 0.1, ..Default::default() },
        clear_pads: vec![pad(start), pad(goal)],
        ..Default::default()
    };
    World {
        terrain: rovernav_terrain::generate(&params),
        rover: RoverConfig::default(),
        sensor_model: SensorModel::default(),
        start: Pose2::new(start.x, start.y, 0.0),
        goal: Goal { position: goal, tolerance: 1.0, waypoints: vec![], keep_out: vec![] },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rovernav_core::{NavCommand, SenseRequest};

    /// The mast points of one image from the start, with the sensors' noise drawn from `seed`.
    fn mast_points(mission: &Mission, seed: u64) -> Vec<[f32; 3]> {
        let world = build_world(mission, "test").unwrap();
        let mut sim =
            rovernav_sim::Simulator::new(world.terrain, world.rover, world.sensor_model, world.start, seed);
        let _ = sim.initial_frame();
        let frame = sim.execute(&NavCommand::Sense(vec![SenseRequest::Mast { pan: 0.0 }]));
        frame.clouds.into_iter().flat_map(|c| c.points).collect()
    }

    #[test]
    fn noise_free_stereo_gives_the_same_points_whatever_the_noise_seed() {
        let mut mission = Mission::default_mission();
        mission.sensors.stereo_dropout = Some(0.0);
        let noisy = (mast_points(&mission, 1), mast_points(&mission, 2));
        assert!(!noisy.0.is_empty());
        assert_ne!(noisy.0, noisy.1, "the default stereo noise differs between noise seeds");
        mission.sensors.stereo_noise_scale = Some(0.0);
        let clean = (mast_points(&mission, 1), mast_points(&mission, 2));
        assert!(!clean.0.is_empty());
        assert_eq!(clean.0, clean.1);
    }

    /// A lander placed where the terrain has no height is refused with the field that put it
    /// there; one on the terrain stands where the mission says, from the start.
    #[test]
    fn a_lander_off_the_terrain_is_refused_and_one_on_it_is_placed_from_the_start() {
        let lander = |d: f64| {
            let mut m = Mission::default_mission();
            m.lander = Some(rovernav_executive::mission::LanderSpec {
                azimuth_deg: 0.0,
                distance_m: d,
                mast_height_m: None,
                max_range_m: None,
                min_turn_deg: None,
                image_size: None,
            });
            m
        };
        let world = build_world(&lander(6.0), "test").unwrap();
        let station = world.sensor_model.lander.expect("the mission's lander");
        assert!((station.position[0] - (world.start.x + 6.0)).abs() < 1e-9);
        assert!((station.position[1] - world.start.y).abs() < 1e-9);
        let err = build_world(&lander(100.0), "test").unwrap_err().to_string();
        assert!(err.contains("lander.distance_m") && err.contains("off the terrain"), "{err}");
    }
}
