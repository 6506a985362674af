//! The true hazard grid against hand-worked rover geometry.

mod common;

use common::{add_ramp, add_rock, flat};
use rovernav_core::{DriveGuard, NavCommand, Pose2, RoverConfig};
use rovernav_sim::{SensorModel, Simulator, true_hazard_grid};
use rovernav_terrain::Rock;

#[test]
fn tall_rocks_are_marked_around_and_small_rocks_are_not() {
    let mut t = flat(16.0, 0.05);
    add_rock(&mut t, Rock { x: 5.0, y: 8.0, diameter: 0.4, height: 0.4 });
    add_rock(&mut t, Rock { x: 11.0, y: 8.0, diameter: 0.3, height: 0.08 });
    let rover = RoverConfig::default();
    let grid = true_hazard_grid(&t, &rover, 0.1);
    assert_eq!((grid.cols(), grid.rows()), (160, 160));
    let at = |x: f64, y: f64| *grid.at_world(x, y).expect("inside");
    assert!(at(5.0, 8.0), "on the tall rock");
    // With its centre 0.35 m from the rock in any direction, some heading puts the rock under
    // the 0.8 x 0.6 m body.
    for a in 0..8 {
        let a = a as f64 * std::f64::consts::FRAC_PI_4;
        assert!(at(5.0 + 0.35 * a.cos(), 8.0 + 0.35 * a.sin()), "0.35 m from the tall rock at {a}");
    }
    // Beyond the body's half-diagonal (0.5 m) plus the rock radius, one wheel radius and a cell
    // of interpolation the rover cannot touch it.
    for a in 0..8 {
        let a = a as f64 * std::f64::consts::FRAC_PI_4;
        assert!(!at(5.0 + 1.0 * a.cos(), 8.0 + 1.0 * a.sin()), "1 m from the tall rock at {a}");
    }
    assert!(!at(11.0, 8.0), "small rock");
    assert!(!at(8.0, 4.0), "open ground");
    // Near the edge the footprint leaves the DEM.
    assert!(at(0.25, 8.0) && at(8.0, 15.8));
}

#[test]
fn steep_slopes_are_marked_and_gentle_ones_are_not() {
    let mut t = flat(16.0, 0.05);
    add_ramp(&mut t, 8.0, 30f64.to_radians());
    let grid = true_hazard_grid(&t, &RoverConfig::default(), 0.2);
    assert!(*grid.at_world(10.0, 8.0).expect("inside"), "30 deg slope");
    let mut t = flat(16.0, 0.05);
    add_ramp(&mut t, 8.0, 15f64.to_radians());
    let grid = true_hazard_grid(&t, &RoverConfig::default(), 0.2);
    assert!(!*grid.at_world(10.0, 8.0).expect("inside"), "15 deg slope");
}

#[test]
fn a_straight_drive_through_safe_cells_never_meets_a_hazard() {
    // A field of rocks of mixed sizes; every east-west lane whose cells are all safe along the
    // path of the rover centre must be drivable without contact.
    let mut t = flat(14.0, 0.05);
    let rocks = [
        (4.0, 3.0, 0.5, 0.35),
        (6.5, 5.2, 0.3, 0.25),
        (9.0, 7.5, 0.6, 0.3),
        (5.5, 9.6, 0.3, 0.1),
        (8.2, 11.0, 0.4, 0.3),
    ];
    for (x, y, d, h) in rocks {
        add_rock(&mut t, Rock { x, y, diameter: d, height: h });
    }
    let rover = RoverConfig::default();
    let grid = true_hazard_grid(&t, &rover, 0.1);
    let mut lanes_driven = 0;
    for lane in 0..40 {
        let y = 2.0 + 0.25 * lane as f64;
        let clear = (0..=80).all(|k| !*grid.at_world(2.0 + 0.1 * k as f64, y).expect("inside"));
        if !clear {
            continue;
        }
        let model = SensorModel {
            slip: rovernav_sim::SlipModel { lateral_gain: 0.0, ..Default::default() },
            ..Default::default()
        };
        let mut sim = Simulator::new(t.clone(), rover.clone(), model, Pose2::new(2.0, y, 0.0), 1);
        sim.execute(&NavCommand::Drive { distance: 7.5, curvature: 0.0, guard: DriveGuard::default() });
        assert_eq!(sim.hazard_contacts(), 0, "lane y={y}");
        lanes_driven += 1;
    }
    assert!(lanes_driven > 10 && lanes_driven < 40, "{lanes_driven} lanes");
}

#[test]
fn the_grid_agrees_with_settling_the_rover_in_every_heading() {
    // Rocks of all sizes on a ramp: the grid's plane bounds must never call a cell safe that
    // some heading makes unsafe, and away from the DEM edge must never mark a cell that every
    // heading finds safe.
    let mut t = flat(8.0, 0.05);
    common::add_ramp(&mut t, 4.0, 12f64.to_radians());
    for (x, y, d, h) in [
        (2.0, 2.0, 0.5, 0.35),
        (3.0, 5.5, 0.3, 0.15),
        (5.0, 3.0, 0.4, 0.22),
        (6.0, 6.0, 0.2, 0.08),
        (4.2, 4.0, 0.3, 0.19),
    ] {
        add_rock(&mut t, Rock { x, y, diameter: d, height: h });
    }
    let rover = RoverConfig::default();
    let grid = true_hazard_grid(&t, &rover, 0.2);
    let geom = rovernav_sim::VehicleGeometry::new(&rover);
    let (mut unsafe_cells, mut safe_cells) = (0, 0);
    for row in 0..grid.rows() {
        for col in 0..grid.cols() {
            let (x, y) = grid.geometry.center(col, row);
            let brute_unsafe = (0..24).any(|k| {
                let yaw = std::f64::consts::TAU * k as f64 / 24.0;
                match rovernav_sim::vehicle::settle(&t.dem, &geom, Pose2::new(x, y, yaw)) {
                    None => true,
                    Some(c) => rovernav_sim::vehicle::static_hazard(&t.dem, &geom, &c).is_some(),
                }
            });
            let marked = *grid.get(col, row);
            if brute_unsafe {
                assert!(marked, "cell ({x}, {y}) is unsafe in some heading but not marked");
                unsafe_cells += 1;
            } else {
                safe_cells += 1;
                let interior = x > 0.6 && y > 0.6 && x < 7.4 && y < 7.4;
                assert!(!interior || !marked, "cell ({x}, {y}) is safe in every heading but marked");
            }
        }
    }
    assert!(unsafe_cells > 100 && safe_cells > 500, "{unsafe_cells} unsafe, {safe_cells} safe");
}
