//! Driving: encoders against the slip model, turns, hazards and guards.

mod common;

use common::{add_ramp, add_rock, add_step, flat, plane};
use rovernav_core::{DriveGuard, NavCommand, Pose2, RoverConfig, SensorFrame, angle_diff};
use rovernav_sim::{SensorModel, Simulator, SlipModel};
use rovernav_terrain::{Rock, Terrain};

fn no_random_slip(base: f64) -> SensorModel {
    SensorModel {
        slip: SlipModel { base, per_command_sigma: 0.0, lateral_gain: 0.0, ..SlipModel::default() },
        ..SensorModel::default()
    }
}

fn drive(sim: &mut Simulator, distance: f64) -> SensorFrame {
    sim.execute(&NavCommand::Drive { distance, curvature: 0.0, guard: DriveGuard::default() })
}

/// Encoder distance (m) of the last sample: mean of both sides.
fn encoder_distance(f: &SensorFrame, rover: &RoverConfig) -> f64 {
    let o = f.odometry.last().expect("odometry");
    0.5 * (o.left_counts + o.right_counts) as f64 / (100.0 * rover.encoder_counts_per_cm)
}

#[test]
fn on_level_ground_without_slip_encoders_match_the_true_distance() {
    let rover = RoverConfig::default();
    let mut sim =
        Simulator::new(flat(10.0, 0.05), rover.clone(), no_random_slip(0.0), Pose2::new(2.0, 5.0, 0.0), 1);
    let f = drive(&mut sim, 2.0);
    assert!(f.motion_stopped.is_none());
    let quantum = 1.0 / (100.0 * rover.encoder_counts_per_cm);
    assert!((sim.distance_driven() - 2.0).abs() < 1e-9);
    assert!((encoder_distance(&f, &rover) - sim.distance_driven()).abs() <= quantum);
    assert!((sim.truth().x - 4.0).abs() < 1e-9 && (sim.truth().y - 5.0).abs() < 1e-9);
    // 2 m at 0.1 m/s: 20 s of motion and one 0.1 s rest sample, samples at 10 Hz.
    assert!((sim.time() - 20.1).abs() < 1e-9);
    assert_eq!(f.imu.len(), 201);
    assert!(f.odometry.windows(2).all(|w| w[1].left_counts >= w[0].left_counts));
}

#[test]
fn on_slopes_encoders_over_read_by_the_slip_model() {
    let rover = RoverConfig::default();
    let angle = 10f64.to_radians();
    let quantum = 1.0 / (100.0 * rover.encoder_counts_per_cm);
    // Uphill (east on a plane rising east): slip = 0.02 + 1.0 * sin(10 deg).
    let mut sim = Simulator::new(
        plane(10.0, 0.05, angle.tan(), 0.0),
        rover.clone(),
        no_random_slip(0.02),
        Pose2::new(3.0, 5.0, 0.0),
        1,
    );
    let f = drive(&mut sim, 2.0);
    let slip_up = 0.02 + angle.sin();
    assert!((encoder_distance(&f, &rover) - 2.0).abs() <= quantum);
    assert!((sim.distance_driven() - 2.0 * (1.0 - slip_up)).abs() < 1e-4, "{}", sim.distance_driven());
    // The planar advance is the surface travel times cos(10 deg).
    assert!((sim.truth().x - 3.0 - 2.0 * (1.0 - slip_up) * angle.cos()).abs() < 1e-4);
    // Downhill (west): slip = 0.02 + 0.2 * sin(10 deg).
    let mut sim = Simulator::new(
        plane(10.0, 0.05, angle.tan(), 0.0),
        rover.clone(),
        no_random_slip(0.02),
        Pose2::new(7.0, 5.0, std::f64::consts::PI),
        1,
    );
    let f = drive(&mut sim, 2.0);
    let slip_down = 0.02 + 0.2 * angle.sin();
    let ratio = encoder_distance(&f, &rover) / sim.distance_driven();
    assert!((ratio - 1.0 / (1.0 - slip_down)).abs() < 1e-3, "{ratio}");
}

#[test]
fn on_a_cross_slope_the_rover_creeps_downhill() {
    let rover = RoverConfig::default();
    let angle = 10f64.to_radians();
    let model = SensorModel {
        slip: SlipModel { base: 0.0, per_command_sigma: 0.0, lateral_gain: 0.1, ..SlipModel::default() },
        ..SensorModel::default()
    };
    // Facing north on a plane rising east: downhill is west, to the rover's left.
    let mut sim = Simulator::new(
        plane(10.0, 0.05, angle.tan(), 0.0),
        rover,
        model,
        Pose2::new(5.0, 3.0, std::f64::consts::FRAC_PI_2),
        1,
    );
    drive(&mut sim, 2.0);
    let travelled = sim.truth().y - 3.0;
    let creep = 5.0 - sim.truth().x;
    assert!((creep - 0.1 * angle.sin() * travelled).abs() < 2e-3, "creep {creep}");
}

#[test]
fn turning_in_place_scrubs_and_slips_as_modelled() {
    let rover = RoverConfig::default();
    let model = no_random_slip(0.02);
    let mut sim =
        Simulator::new(flat(10.0, 0.05), rover.clone(), model.clone(), Pose2::new(5.0, 5.0, 0.0), 1);
    let angle = std::f64::consts::FRAC_PI_2;
    let t0 = sim.time();
    let f = sim.execute(&NavCommand::Turn { angle });
    assert!((sim.truth().yaw - angle * (1.0 - 0.02)).abs() < 1e-9);
    assert!(sim.distance_driven() < 1e-9);
    let o = f.odometry.last().expect("odometry");
    let per_m = 100.0 * rover.encoder_counts_per_cm;
    let wheel = angle * rover.track / 2.0 * (1.0 + model.slip.turn_scrub) * per_m;
    assert!((o.right_counts as f64 - wheel).abs() <= 1.0 && (o.left_counts as f64 + wheel).abs() <= 1.0);
    // Gyro rates integrate to the true turn (bias and noise are small over 9 s).
    let mut previous = t0;
    let mut integrated = 0.0;
    for s in &f.imu {
        integrated += s.gyro_z * (s.t - previous);
        previous = s.t;
    }
    assert!(angle_diff(integrated, sim.truth().yaw).abs() < 0.01);
}

#[test]
fn driving_an_arc_follows_its_curvature() {
    let mut sim = Simulator::new(
        flat(10.0, 0.05),
        RoverConfig::default(),
        no_random_slip(0.0),
        Pose2::new(5.0, 3.0, 0.0),
        1,
    );
    // A quarter circle of radius 2 to the left ends 2 m ahead and 2 m left, facing north.
    let r = 2.0;
    sim.execute(&NavCommand::Drive {
        distance: std::f64::consts::FRAC_PI_2 * r,
        curvature: 1.0 / r,
        guard: DriveGuard::default(),
    });
    let t = sim.truth();
    assert!((t.x - 7.0).abs() < 1e-3 && (t.y - 5.0).abs() < 1e-3, "{t:?}");
    assert!((t.yaw - std::f64::consts::FRAC_PI_2).abs() < 1e-9);
}

fn run_into(terrain: Terrain, distance: f64) -> (Simulator, SensorFrame) {
    let mut sim =
        Simulator::new(terrain, RoverConfig::default(), no_random_slip(0.0), Pose2::new(3.0, 5.0, 0.0), 1);
    let f = drive(&mut sim, distance);
    (sim, f)
}

#[test]
fn a_rock_under_the_belly_is_one_contact_and_stops_the_rover() {
    let mut t = flat(12.0, 0.05);
    add_rock(&mut t, Rock { x: 6.0, y: 5.0, diameter: 0.3, height: 0.3 });
    let (mut sim, f) = run_into(t, 5.0);
    assert_eq!(sim.hazard_contacts(), 1);
    let why = f.motion_stopped.expect("stopped");
    assert!(why.contains("belly"), "{why}");
    // The dome is above the 0.18 m clearance within 0.12 m of its centre; the body front is
    // 0.4 m ahead of the centre (one cell of smear allowed).
    let x = sim.truth().x;
    assert!(x > 6.0 - 0.4 - 0.12 - 0.1 && x < 6.0 - 0.4 - 0.12 + 0.01, "stopped at {x}");
    // Backing away is free.
    drive(&mut sim, -1.0);
    assert_eq!(sim.hazard_contacts(), 1);
}

#[test]
fn a_small_rock_passes_under_the_belly() {
    let mut t = flat(12.0, 0.05);
    add_rock(&mut t, Rock { x: 6.0, y: 5.0, diameter: 0.3, height: 0.1 });
    let (sim, f) = run_into(t, 5.0);
    assert_eq!(sim.hazard_contacts(), 0);
    assert!(f.motion_stopped.is_none());
    assert!((sim.truth().x - 8.0).abs() < 1e-6);
}

#[test]
fn a_step_taller_than_the_clearance_stops_the_wheels() {
    let mut t = flat(12.0, 0.05);
    add_step(&mut t, 6.0, 0.3);
    let (sim, f) = run_into(t, 5.0);
    assert_eq!(sim.hazard_contacts(), 1);
    let why = f.motion_stopped.expect("stopped");
    assert!(why.contains("step"), "{why}");
    // Front wheels 0.3 m ahead of the centre look one wheel radius (0.1 m) ahead.
    let x = sim.truth().x;
    assert!(x > 6.0 - 0.3 - 0.1 - 0.06 && x < 6.0 - 0.3, "stopped at {x}");
}

#[test]
fn a_low_step_is_climbed() {
    let mut t = flat(12.0, 0.05);
    add_step(&mut t, 6.0, 0.1);
    let (sim, f) = run_into(t, 5.0);
    assert_eq!(sim.hazard_contacts(), 0, "{:?}", f.motion_stopped);
    assert!((sim.truth().z - 0.1).abs() < 1e-6);
}

#[test]
fn tilting_beyond_the_limit_is_one_contact() {
    let mut t = flat(14.0, 0.05);
    add_ramp(&mut t, 6.0, 30f64.to_radians());
    let (sim, f) = run_into(t, 6.0);
    assert_eq!(sim.hazard_contacts(), 1);
    let why = f.motion_stopped.expect("stopped");
    assert!(why.contains("tilt"), "{why}");
    let limit = RoverConfig::default().max_tilt;
    assert!(sim.truth().tilt() <= limit && sim.truth().tilt() > limit - 3f64.to_radians());
}

#[test]
fn guards_stop_before_hazards() {
    // Tilt guard at 15 deg on a 20 deg ramp: no hazard, a guard stop.
    let mut t = flat(14.0, 0.05);
    add_ramp(&mut t, 6.0, 20f64.to_radians());
    let mut sim =
        Simulator::new(t, RoverConfig::default(), SensorModel::default(), Pose2::new(3.0, 5.0, 0.0), 1);
    let guard = DriveGuard { proximity: false, max_tilt: Some(15f64.to_radians()) };
    let f = sim.execute(&NavCommand::Drive { distance: 6.0, curvature: 0.0, guard });
    assert!(f.motion_stopped.expect("stopped").contains("tilt"));
    assert_eq!(sim.hazard_contacts(), 0);
    assert!(sim.truth().tilt() < 17f64.to_radians());

    // Proximity guard in front of a tall rock.
    let mut t = flat(12.0, 0.05);
    add_rock(&mut t, Rock { x: 6.0, y: 5.0, diameter: 0.4, height: 0.4 });
    let mut sim =
        Simulator::new(t, RoverConfig::default(), SensorModel::default(), Pose2::new(3.0, 5.0, 0.0), 1);
    let guard = DriveGuard { proximity: true, max_tilt: None };
    let f = sim.execute(&NavCommand::Drive { distance: 5.0, curvature: 0.0, guard });
    assert!(f.motion_stopped.expect("stopped").contains("proximity"));
    assert!(f.proximity.middle(), "{:?}", f.proximity);
    assert_eq!(sim.hazard_contacts(), 0);
    // Driving on under the guard gains at most a few centimetres and never touches the rock;
    // backing up is not guarded by the forward sensors.
    let before = sim.truth().x;
    sim.execute(&NavCommand::Drive { distance: 1.0, curvature: 0.0, guard });
    assert!(sim.truth().x < before + 0.05);
    assert_eq!(sim.hazard_contacts(), 0);
    let before = sim.truth().x;
    sim.execute(&NavCommand::Drive { distance: -0.5, curvature: 0.0, guard });
    assert!(sim.truth().x < before - 0.4);
}

#[test]
fn the_rover_stops_at_the_edge_of_the_terrain_model() {
    let mut sim = Simulator::new(
        flat(6.0, 0.05),
        RoverConfig::default(),
        SensorModel::default(),
        Pose2::new(3.0, 3.0, 0.0),
        1,
    );
    let f = drive(&mut sim, 5.0);
    assert!(f.motion_stopped.expect("stopped").contains("terrain"));
    assert_eq!(sim.hazard_contacts(), 0);
    let x = sim.truth().x;
    // The front of the body (0.4 m) reaches the DEM edge at x = 6.
    assert!(x > 5.5 && x <= 5.6, "{x}");
}
