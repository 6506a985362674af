//! Terrain assessment on synthetic range data from analytic terrain with known truth.

mod common;

use common::{Rock, Scene, Shape, Shot, cast};
use rovernav_core::{GridGeometry, Point2, Pose2, Pose3, PoseEstimate, Wedge};
use rovernav_mapping::WorldMap;
use rovernav_perception::{
    ElevationMap, HazardHeight, SensedWedge, SensorNoise, TerrainConfig, TerrainEvaluator, TrueRock,
    evaluate_terrain,
};

fn estimate(pose: Pose3) -> PoseEstimate {
    PoseEstimate { pose, covariance: [[0.0; 3]; 3] }
}

fn rocky_scene() -> Scene {
    Scene {
        rocks: vec![
            // Hazards: a 0.3 m box and a 0.3 m dome, 2.5-4 m ahead.
            Rock { x: 2.6, y: 0.5, size: 0.4, height: 0.3, shape: Shape::Box },
            Rock { x: 3.8, y: -0.7, size: 0.6, height: 0.3, shape: Shape::Dome },
            // A pebble well below the 0.18 m clearance.
            Rock { x: 2.0, y: -0.6, size: 0.3, height: 0.07, shape: Shape::Dome },
        ],
        ..Default::default()
    }
}

fn true_rocks(scene: &Scene) -> Vec<TrueRock> {
    scene.rocks.iter().map(|r| TrueRock { x: r.x, y: r.y, diameter: r.size, height: r.height }).collect()
}

#[test]
fn flat_plane_has_no_hazards_and_top_traversability() {
    let scene = Scene { z0: -2.0, ..Default::default() };
    let pose = Pose3 { z: -2.0, ..Default::default() };
    let cloud = cast(&scene, &Shot::mast(pose, 120, 120, 0.01, 1));
    let mut ev = TerrainEvaluator::new(TerrainConfig::default(), pose.pose2()).unwrap();
    let layers = ev.update(&[cloud], &estimate(pose)).clone();
    let sensed: Vec<usize> =
        (0..layers.geometry().len()).filter(|&i| layers.map.point_count.data[i] > 0).collect();
    assert!(sensed.len() > 300, "{} sensed cells", sensed.len());
    assert!(layers.hazard.data.iter().all(|&h| !h));
    let good = sensed.iter().filter(|&&i| layers.map.traversability.data[i] >= 12).count();
    assert!(good as f64 >= 0.95 * sensed.len() as f64, "{good} of {}", sensed.len());
    for &i in &sensed {
        assert!((layers.map.elevation.data[i] + 2.0).abs() < 0.02);
    }
    let mean_goodness: f32 = sensed
        .iter()
        .filter_map(|&i| Some(layers.map.goodness.data[i]).filter(|g| g.is_finite()))
        .sum::<f32>()
        / sensed.len() as f32;
    assert!(mean_goodness > 0.8, "mean goodness {mean_goodness}");
}

#[test]
fn tilted_planes_are_assessed_by_their_slope() {
    for (deg, hazardous) in [(10.0f64, false), (32.0, true)] {
        let g = deg.to_radians().tan();
        let scene = Scene { gx: g, ..Default::default() };
        // Rover on the slope facing uphill: nose up is negative pitch.
        let pose = Pose3 { pitch: -deg.to_radians(), ..Default::default() };
        let cloud = cast(&scene, &Shot::mast(pose, 100, 100, 0.005, 2));
        let mut ev = TerrainEvaluator::new(TerrainConfig::default(), pose.pose2()).unwrap();
        let layers = ev.update(&[cloud], &estimate(pose)).clone();
        let assessed: Vec<usize> = (0..layers.geometry().len())
            .filter(|&i| layers.slope.data[i].is_finite() && layers.map.point_count.data[i] > 0)
            .collect();
        assert!(assessed.len() > 100);
        let mean_slope =
            assessed.iter().map(|&i| layers.slope.data[i] as f64).sum::<f64>() / assessed.len() as f64;
        assert!((mean_slope.to_degrees() - deg).abs() < 1.0, "{deg}: mean slope {}", mean_slope.to_degrees());
        let hazard =
            assessed.iter().filter(|&&i| layers.hazard.data[i]).count() as f64 / assessed.len() as f64;
        if hazardous {
            assert!(hazard > 0.95, "{deg} deg: hazard fraction {hazard}");
        } else {
            assert_eq!(hazard, 0.0, "{deg} deg");
        }
    }
}

#[test]
fn rocks_taller_than_clearance_are_found_and_become_c_obstacles() {
    let scene = rocky_scene();
    let pose = Pose3::default();
    let shot = Shot::mast(pose, 160, 180, 0.01, 3);
    let cloud = cast(&scene, &shot);
    assert!(cloud.points.len() > 20_000);
    let config = TerrainConfig::default();
    let mut ev = TerrainEvaluator::new(config.clone(), pose.pose2()).unwrap();
    let layers = ev.update(&[cloud], &estimate(pose)).clone();

    let figures = evaluate_terrain(
        &true_rocks(&scene),
        |x, y| Some(scene.height(x, y)),
        &layers.map.elevation,
        &layers.hazard,
        Point2::new(0.0, 0.0),
        &config,
    )
    .unwrap();
    assert_eq!(figures.hazard_rocks, 2);
    assert_eq!(figures.hazard_recall, 1.0);
    assert!(figures.false_hazard_rate < 0.01, "{figures:?}");
    assert!(figures.elevation_rmse_m < 0.05, "{figures:?}");

    let wedge = SensedWedge { pose: pose.pose2(), wedge: shot.wedge };
    let goal = Point2::new(3.8, -0.7);
    let obstacles = layers.c_obstacles(&config, &[wedge], Some(goal));
    // Each hazard rock's C-obstacle contains the rock's visible half grown by the rover radius
    // (the far half is in the rock's range shadow, unsensed).
    for r in &scene.rocks[..2] {
        let o =
            obstacles.iter().find(|o| o.contains(Point2::new(r.x, r.y))).expect("rock inside a C-obstacle");
        let towards_sensor = (-r.y).atan2(-r.x);
        for k in -4..=4 {
            let t = towards_sensor + k as f64 * 15f64.to_radians();
            let edge = Point2::new(r.x + 0.4 * r.size * t.cos(), r.y + 0.4 * r.size * t.sin());
            assert!(o.contains(edge.add(Point2::new(t.cos(), t.sin()).scale(config.rover_radius))));
        }
    }
    // The goal sits on the dome: that C-obstacle's vertices are goals, the other's are not.
    let dome = obstacles.iter().find(|o| o.contains(goal)).unwrap();
    assert!(dome.labels.iter().all(|l| l.goal));
    let boxed = obstacles.iter().find(|o| o.contains(Point2::new(2.6, 0.5))).unwrap();
    assert!(boxed.labels.iter().all(|l| !l.goal));
    // The pebble is not an obstacle: no hull covers it.
    assert!(!obstacles.iter().any(|o| inside_hull(&o.hull, Point2::new(2.0, -0.6))));
}

fn inside_hull(hull: &[Point2], p: Point2) -> bool {
    let n = hull.len();
    n >= 3 && (0..n).all(|i| hull[(i + 1) % n].sub(hull[i]).cross(p.sub(hull[i])) >= 0.0)
}

#[test]
fn points_are_placed_with_the_estimate_on_a_tilted_rover() {
    // Rover rolled and pitched on a cross-slope, heading north-east, 100 m from the origin.
    let (gx, gy) = (0.12, -0.08);
    let scene = Scene { z0: 10.0, gx, gy, ..Default::default() };
    let (x, y) = (100.0, 50.0);
    let yaw = 0.7f64;
    // Align the body with the plane: slope along the heading and across it.
    let along = gx * yaw.cos() + gy * yaw.sin();
    let across = -gx * yaw.sin() + gy * yaw.cos();
    let pose = Pose3 { x, y, z: scene.height(x, y), roll: across.atan(), pitch: -(along.atan()), yaw };
    let cloud = cast(&scene, &Shot::mast(pose, 80, 80, 0.005, 4));
    let geometry =
        GridGeometry { cols: 80, rows: 80, resolution: 0.15, origin_x: x - 6.0, origin_y: y - 6.0 };
    let mut map = ElevationMap::new(geometry).unwrap();
    map.insert_cloud(&cloud, &pose);
    let h = map.mean_heights();
    let mut n = 0;
    for r in 0..geometry.rows {
        for c in 0..geometry.cols {
            let z = *h.get(c, r);
            if z.is_finite() {
                let (cx, cy) = geometry.center(c, r);
                assert!((z as f64 - scene.height(cx, cy)).abs() < 0.03);
                n += 1;
            }
        }
    }
    assert!(n > 200);
}

#[test]
fn sparse_front_triggers_a_request_for_more_data() {
    let scene = Scene::default();
    let pose = Pose3::default();
    let mut ev = TerrainEvaluator::new(TerrainConfig::default(), pose.pose2()).unwrap();
    // Nothing sensed yet: the whole front is empty, ask straight ahead.
    let req = ev.density_request(pose.pose2()).unwrap();
    assert_eq!(req.density, 0.0);
    assert!(req.bearing.abs() < 1e-9);
    // Image only the left: the right-hand sector stays empty and is asked for.
    let mut shot = Shot::mast(pose, 100, 100, 0.005, 5);
    shot.wedge =
        Wedge { bearing: 35f64.to_radians(), half_angle: 25f64.to_radians(), min_range: 0.3, max_range: 5.0 };
    ev.update(&[cast(&scene, &shot)], &estimate(pose));
    let req = ev.density_request(pose.pose2()).unwrap();
    assert!(req.bearing < -0.2, "bearing {}", req.bearing);
    // Image the right too: coverage is complete.
    shot.wedge.bearing = -35f64.to_radians();
    shot.seed = 6;
    ev.update(&[cast(&scene, &shot)], &estimate(pose));
    assert_eq!(ev.density_request(pose.pose2()), None);
}

#[test]
fn map_manager_fuses_evaluator_output_and_data_survives_driving() {
    let scene = rocky_scene();
    let pose = Pose3::default();
    let config = TerrainConfig::default();
    let mut ev = TerrainEvaluator::new(config, pose.pose2()).unwrap();
    ev.update(&[cast(&scene, &Shot::mast(pose, 100, 100, 0.01, 7))], &estimate(pose));
    // Drive 1.5 m forward: the rock seen before is still in the rolling grid.
    let moved = Pose3 { x: 1.5, ..pose };
    let layers = ev.update(&[], &estimate(moved)).clone();
    let z = layers.map.elevation.at_world(2.6, 0.5).copied().unwrap();
    assert!((z - 0.3).abs() < 0.05, "box top {z}");
    assert!(layers.hazard.at_world(2.6, 0.5).copied().unwrap());

    let world_geometry =
        GridGeometry { cols: 200, rows: 200, resolution: 0.3, origin_x: -30.0, origin_y: -30.0 };
    let mut world = WorldMap::flat(world_geometry).unwrap();
    world.fuse(&layers.map, &estimate(moved)).unwrap();
    let cell = world.cell_at(3.0, 0.0).unwrap();
    assert!(cell.sensed && cell.traversability.is_some());
    assert!((cell.elevation.unwrap() as f64 - scene.height(3.0, 0.0)).abs() < 0.05);
    let behind = world.cell_at(-5.0, 0.0).unwrap();
    assert!(!behind.sensed && behind.traversability.is_none());
    assert_eq!(world.planning_traversability_at(-5.0, 0.0), Some(7));
    let _ = Pose2::default();
}

/// Hazard cells of one sparse, noisy mast wedge over flat ground with a dome of `height` 3.8 m
/// ahead, assessed on top heights at `clearance` with the given height-noise confidence.
fn far_dome_hazards(height: f64, confidence: f64, seed: u64) -> (Vec<(Point2, bool)>, Point2) {
    let rock = Rock { x: 3.8, y: 0.2, size: 0.38, height, shape: Shape::Dome };
    let scene = Scene { rocks: vec![rock], ..Default::default() };
    let pose = Pose3::default();
    // One or two points per 0.1 m cell at 3.8 m, as the mast delivers there.
    let cloud = cast(&scene, &Shot::mast(pose, 40, 45, 0.02, seed));
    let config = TerrainConfig {
        resolution: 0.1,
        clearance: 0.162,
        hazard_height: HazardHeight::Top,
        range_noise: Some(SensorNoise::default()),
        hazard_confidence: confidence,
        ..TerrainConfig::default()
    };
    let mut ev = TerrainEvaluator::new(config, pose.pose2()).unwrap();
    let layers = ev.update(&[cloud], &estimate(pose)).clone();
    let g = layers.geometry();
    let mut cells = Vec::new();
    for r in 0..g.rows {
        for c in 0..g.cols {
            let i = g.index(c, r);
            if layers.hazard.data[i] {
                let (x, y) = g.center(c, r);
                cells.push((Point2::new(x, y), layers.uncertain_hazard.data[i]));
            }
        }
    }
    (cells, Point2::new(rock.x, rock.y))
}

#[test]
fn the_far_range_noise_allowance_keeps_open_ground_and_low_rocks_clear() {
    for seed in 1..=4 {
        // A 0.19 m dome (over the 0.18 m true clearance) is found, as an uncertain hazard or a
        // measured one, and every hazard cell lies on or next to it.
        let (cells, rock) = far_dome_hazards(0.19, 1.0, seed);
        assert!(cells.iter().any(|(p, _)| p.dist(rock) <= 0.25), "seed {seed}: rock missed");
        assert!(cells.iter().all(|(p, _)| p.dist(rock) <= 0.4), "seed {seed}: {cells:?}");
        // A 0.1 m dome is well under the limit even with the noise allowance.
        let (cells, _) = far_dome_hazards(0.1, 1.0, seed);
        assert!(cells.is_empty(), "seed {seed}: {cells:?}");
    }
}
