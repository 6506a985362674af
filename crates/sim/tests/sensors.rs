//! Range images, proximity sensors and faults on hand-built terrains.

mod common;

use common::{add_rock, add_step, flat};
use rovernav_core::{CameraKind, NavCommand, Pose2, RoverConfig, SenseRequest};
use rovernav_sim::{Fault, SensorModel, Simulator};
use rovernav_terrain::Rock;

fn exact_model() -> SensorModel {
    let mut m = SensorModel::default();
    for imager in [&mut m.mast, &mut m.body, &mut m.lidar.imager] {
        imager.sigma_constant = 0.0;
        imager.sigma_quadratic = 0.0;
        imager.dropout = 0.0;
    }
    m
}

fn sense(sim: &mut Simulator, req: SenseRequest) -> rovernav_core::PointCloud {
    let mut f = sim.execute(&NavCommand::Sense(vec![req]));
    assert_eq!(f.clouds.len(), 1);
    f.clouds.remove(0)
}

#[test]
fn mast_wedge_on_flat_ground_covers_one_to_five_metres() {
    let rover = RoverConfig::default();
    let mut sim =
        Simulator::new(flat(20.0, 0.1), rover.clone(), exact_model(), Pose2::new(10.0, 10.0, 0.7), 1);
    let pan = 0.4;
    let cloud = sense(&mut sim, SenseRequest::Mast { pan });
    assert_eq!(cloud.camera, CameraKind::Mast);
    assert!((cloud.wedge.bearing - pan).abs() < 1e-12);
    assert!((cloud.wedge.half_angle - rover.mast_fov / 2.0).abs() < 1e-12);
    assert!(cloud.points.len() > 1500, "{} points", cloud.points.len());
    let (mut near, mut far) = (f64::INFINITY, 0.0f64);
    for p in &cloud.points {
        let (x, y, z) = (p[0] as f64, p[1] as f64, p[2] as f64);
        assert!(z.abs() < 1e-5, "flat ground point at z={z}");
        let r = x.hypot(y);
        near = near.min(r);
        far = far.max(r);
        assert!((y.atan2(x) - pan).abs() <= rover.mast_fov / 2.0 + 1e-6);
        assert!(cloud.wedge.contains(x, y) || r < cloud.wedge.min_range);
    }
    assert!(near > 0.9 && near < 1.2, "near edge {near}");
    assert!(far > 4.7 && far <= 5.0 + 1e-6, "far edge {far}");
    assert_eq!(sim.sensing_actions(), 1);
}

#[test]
fn a_tall_rock_hides_the_ground_behind_it() {
    let mut t = flat(20.0, 0.05);
    add_rock(&mut t, Rock { x: 13.0, y: 10.0, diameter: 1.0, height: 1.0 });
    let mut sim = Simulator::new(t, RoverConfig::default(), exact_model(), Pose2::new(10.0, 10.0, 0.0), 1);
    let cloud = sense(&mut sim, SenseRequest::Mast { pan: 0.0 });
    let on_rock = cloud.points.iter().filter(|p| p[2] > 0.3).count();
    assert!(on_rock > 20, "the rock face is seen ({on_rock} points)");
    // The rock subtends +-9.5 deg at 3 m; behind it the 1.2 m camera cannot see the ground.
    let shadowed = cloud
        .points
        .iter()
        .filter(|p| (p[0] as f64) > 3.6 && (p[1] as f64).atan2(p[0] as f64).abs() < 3f64.to_radians())
        .count();
    assert_eq!(shadowed, 0);
}

#[test]
fn body_cameras_look_fore_and_aft_within_their_range() {
    let rover = RoverConfig::default();
    let mut sim =
        Simulator::new(flat(10.0, 0.05), rover.clone(), exact_model(), Pose2::new(5.0, 5.0, 0.0), 3);
    let front = sense(&mut sim, SenseRequest::BodyFront);
    let rear = sense(&mut sim, SenseRequest::BodyRear);
    assert!(!front.points.is_empty() && !rear.points.is_empty());
    for p in &front.points {
        let d = (p[0] as f64 - front.origin[0]).hypot(p[1] as f64 - front.origin[1]);
        assert!(p[0] as f64 > rover.length / 2.0 && d <= rover.body_range + 1e-6);
    }
    assert!(rear.points.iter().all(|p| (p[0] as f64) < -rover.length / 2.0));
    assert!((rear.wedge.bearing.abs() - std::f64::consts::PI).abs() < 1e-12);
}

#[test]
fn lidar_sees_farther_and_wider_than_the_mast() {
    let model = exact_model();
    let mut sim = Simulator::new(
        flat(30.0, 0.1),
        RoverConfig::default(),
        model.clone(),
        Pose2::new(15.0, 15.0, 0.0),
        3,
    );
    let cloud = sense(&mut sim, SenseRequest::Lidar { pan: 0.0 });
    let far = cloud.points.iter().map(|p| (p[0] as f64).hypot(p[1] as f64)).fold(0.0, f64::max);
    let widest = cloud.points.iter().map(|p| (p[1] as f64).atan2(p[0] as f64).abs()).fold(0.0, f64::max);
    assert!(far > 7.5, "far {far}");
    assert!(widest > 50f64.to_radians(), "widest {widest}");
    assert_eq!(cloud.camera, CameraKind::Lidar);
}

#[test]
fn proximity_clusters_see_rocks_and_drop_offs() {
    let rover = RoverConfig::default();
    let start = Pose2::new(5.0, 5.0, 0.0);
    let mut sim = Simulator::new(flat(10.0, 0.05), rover.clone(), SensorModel::default(), start, 5);
    assert!(!sim.execute(&NavCommand::Sense(vec![])).proximity.any(), "level ground is clear");

    // A rock straight ahead, 0.3 m in front of the body.
    let mut t = flat(10.0, 0.05);
    add_rock(&mut t, Rock { x: 5.0 + 0.4 + 0.3, y: 5.0, diameter: 0.3, height: 0.3 });
    let mut sim = Simulator::new(t, rover.clone(), SensorModel::default(), start, 5);
    let p = sim.execute(&NavCommand::Sense(vec![])).proximity;
    assert!(p.middle() && !p.left() && !p.right(), "{p:?}");

    // A rock ahead-left of the left front corner.
    let mut t = flat(10.0, 0.05);
    add_rock(&mut t, Rock { x: 5.0 + 0.4 + 0.35, y: 5.0 + 0.3 + 0.35, diameter: 0.4, height: 0.3 });
    let mut sim = Simulator::new(t, rover.clone(), SensorModel::default(), start, 5);
    let p = sim.execute(&NavCommand::Sense(vec![])).proximity;
    assert!(p.left() && !p.right(), "{p:?}");

    // The ground drops 0.5 m just ahead: no ground return where expected.
    let mut t = flat(10.0, 0.05);
    add_step(&mut t, 5.0 + 0.4 + 0.3, -0.5);
    let mut sim = Simulator::new(t, rover, SensorModel::default(), start, 5);
    let p = sim.execute(&NavCommand::Sense(vec![])).proximity;
    assert!(p.left() && p.middle() && p.right(), "{p:?}");
}

#[test]
fn injected_faults_silence_sensors_stall_wheels_and_blank_the_compass() {
    let mut sim = Simulator::new(
        flat(10.0, 0.05),
        RoverConfig::default(),
        SensorModel::default(),
        Pose2::new(5.0, 5.0, 0.0),
        9,
    );
    sim.inject_fault(Fault::SilentSensor(CameraKind::Mast));
    let f = sim.execute(&NavCommand::Sense(vec![SenseRequest::Mast { pan: 0.0 }, SenseRequest::BodyFront]));
    assert!(f.clouds[0].points.is_empty());
    assert!(!f.clouds[1].points.is_empty());

    sim.inject_fault(Fault::CompassNaN);
    let f = sim.execute(&NavCommand::Sense(vec![]));
    assert!(f.imu.iter().all(|s| s.compass_yaw.is_nan()));

    sim.inject_fault(Fault::StalledWheel { left: true });
    let f = sim.execute(&NavCommand::Drive { distance: 1.0, curvature: 0.0, guard: Default::default() });
    let why = f.motion_stopped.expect("stall reported");
    assert!(why.contains("stall"), "{why}");
    let last = f.odometry.last().expect("samples");
    assert_eq!(last.left_counts, 0);
    assert!(last.right_counts > 0);
    // Pivoting about the stalled left wheels turns the rover left (counter-clockwise).
    assert!(sim.truth().yaw > 0.0);
    assert!(sim.distance_driven() < 0.1);
}

#[test]
fn proximity_guard_passes_rocks_under_the_clearance_and_stops_at_taller_ones() {
    // The truth is the hazard model: a rock lower than the belly clearance is driven over without
    // a hazard contact, so the guard must not stop for one well under the beams' aim; a rock
    // taller than the clearance, even by a centimetre, must stop the rover before it touches it.
    let rover = RoverConfig::default();
    let aim = SensorModel::default().proximity.aim_fraction;
    let low = [0.4, 0.9 * aim].map(|f| (f * rover.clearance, false));
    let tall = [1.05, 1.25, 1.6, 2.5].map(|f| (f * rover.clearance, true));
    for (seed, (height, stops)) in low.into_iter().chain(tall).enumerate() {
        let mut t = flat(12.0, 0.05);
        add_rock(&mut t, Rock { x: 6.0, y: 5.0, diameter: 0.35, height });
        let start = Pose2::new(3.0, 5.0, 0.0);
        let mut sim = Simulator::new(t, rover.clone(), SensorModel::default(), start, seed as u64);
        let guard = rovernav_core::DriveGuard { proximity: true, max_tilt: None };
        let f = sim.execute(&NavCommand::Drive { distance: 5.0, curvature: 0.0, guard });
        if stops {
            let why = f.motion_stopped.expect("stopped");
            assert!(why.contains("proximity"), "{height} m rock: {why}");
            assert_eq!(sim.hazard_contacts(), 0, "{height} m rock: stopped before touching it");
            assert!(sim.truth().x < 6.0 - 0.4, "{height} m rock: stopped short of it");
        } else {
            assert!(f.motion_stopped.is_none(), "{height} m rock: {:?}", f.motion_stopped);
            assert!(sim.truth().x > 7.5, "{height} m rock: drove over it");
            assert_eq!(sim.hazard_contacts(), 0, "{height} m rock is under the clearance");
        }
    }
}
