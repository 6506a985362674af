//! Same seed and commands give identical frames; another seed gives other noise.

mod common;

use common::{add_rock, flat};
use rovernav_core::{DriveGuard, NavCommand, Pose2, RoverConfig, SenseRequest, SensorFrame};
use rovernav_sim::{SensorModel, Simulator};
use rovernav_terrain::Rock;

fn run(seed: u64) -> (Vec<SensorFrame>, f64, [f64; 3]) {
    let mut t = flat(12.0, 0.05);
    add_rock(&mut t, Rock { x: 7.0, y: 6.5, diameter: 0.4, height: 0.3 });
    let mut sim =
        Simulator::new(t, RoverConfig::default(), SensorModel::default(), Pose2::new(4.0, 6.0, 0.1), seed);
    let commands = [
        NavCommand::Sense(vec![
            SenseRequest::Mast { pan: 0.2 },
            SenseRequest::BodyFront,
            SenseRequest::Lidar { pan: -0.3 },
        ]),
        NavCommand::Drive {
            distance: 1.2,
            curvature: 0.3,
            guard: DriveGuard { proximity: true, max_tilt: Some(0.3) },
        },
        NavCommand::Turn { angle: -0.6 },
        NavCommand::Drive { distance: -0.4, curvature: 0.0, guard: DriveGuard::default() },
        NavCommand::Sense(vec![SenseRequest::BodyRear]),
        NavCommand::Finish(rovernav_core::Outcome::Reached, String::new()),
    ];
    let mut frames = vec![sim.initial_frame()];
    frames.extend(commands.iter().map(|c| sim.execute(c)));
    let truth = sim.truth();
    (frames, sim.time(), [truth.x, truth.y, truth.yaw])
}

#[test]
fn same_seed_same_frames() {
    let a = run(42);
    let b = run(42);
    assert_eq!(a, b);
    assert!(a.0.iter().map(|f| f.clouds.len()).sum::<usize>() == 4);
}

#[test]
fn different_seed_different_noise() {
    let a = run(42);
    let b = run(43);
    assert_ne!(a.0[1].clouds[0].points, b.0[1].clouds[0].points);
    assert_ne!(a.0[0].imu, b.0[0].imu);
}
