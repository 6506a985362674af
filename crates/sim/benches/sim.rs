//! Simulator speed: one mast wedge (2400 rays), one LIDAR sweep, 1 m of driving, and the true
//! hazard grid of a 30 m square.

use criterion::{Criterion, criterion_group, criterion_main};
use rovernav_core::{DriveGuard, Grid2, GridGeometry, NavCommand, Pose2, RoverConfig, SenseRequest};
use rovernav_sim::{SensorModel, Simulator, true_hazard_grid};
use rovernav_terrain::{Dem, Rock, Terrain};

/// A 30 m square at 5 cm cells: gentle undulation and a grid of dome rocks.
fn rocky_terrain() -> Terrain {
    let geometry = GridGeometry { cols: 600, rows: 600, resolution: 0.05, origin_x: 0.0, origin_y: 0.0 };
    let mut rocks = Vec::new();
    for i in 0..12 {
        for j in 0..12 {
            let k = (i * 12 + j) as f64;
            rocks.push(Rock {
                x: 1.5 + 2.4 * i as f64 + 0.7 * (k * 1.7).sin(),
                y: 1.5 + 2.4 * j as f64 + 0.7 * (k * 2.3).cos(),
                diameter: 0.2 + 0.3 * (0.5 + 0.5 * (k * 0.9).sin()),
                height: 0.05 + 0.3 * (0.5 + 0.5 * (k * 1.3).cos()),
            });
        }
    }
    let mut grid = Grid2::filled(geometry, 0.0f32);
    for r in 0..geometry.rows {
        for c in 0..geometry.cols {
            let (x, y) = geometry.center(c, r);
            let mut h = 0.3 * (x * 0.3).sin() * (y * 0.25).cos();
            for rock in &rocks {
                let q = 2.0 * (x - rock.x).hypot(y - rock.y) / rock.diameter;
                if q < 1.0 {
                    h += rock.height * (1.0 - q * q).sqrt();
                }
            }
            *grid.get_mut(c, r) = h as f32;
        }
    }
    Terrain { dem: Dem::from_grid(grid), rocks }
}

fn benches(c: &mut Criterion) {
    let terrain = rocky_terrain();
    let rover = RoverConfig::default();
    let start = Pose2::new(15.2, 15.1, 0.3);
    let mut sim = Simulator::new(terrain.clone(), rover.clone(), SensorModel::default(), start, 1);
    let mast = NavCommand::Sense(vec![SenseRequest::Mast { pan: 0.0 }]);
    c.bench_function("mast wedge 60x40 rays", |b| b.iter(|| sim.execute(&mast)));
    let lidar = NavCommand::Sense(vec![SenseRequest::Lidar { pan: 0.0 }]);
    c.bench_function("lidar sweep 121x40 rays", |b| b.iter(|| sim.execute(&lidar)));
    let forward = NavCommand::Drive {
        distance: 0.5,
        curvature: 0.2,
        guard: DriveGuard { proximity: true, max_tilt: Some(0.4) },
    };
    let back = NavCommand::Drive { distance: -0.5, curvature: 0.2, guard: DriveGuard::default() };
    c.bench_function("drive 1 m (0.5 m out and back, guarded)", |b| {
        b.iter(|| {
            sim.execute(&forward);
            sim.execute(&back)
        })
    });
    let mut group = c.benchmark_group("hazard grid");
    group.sample_size(10);
    group.bench_function("true_hazard_grid 30 m at 0.1 m", |b| {
        b.iter(|| true_hazard_grid(&terrain, &rover, 0.1))
    });
    group.finish();
}

criterion_group!(sim_benches, benches);
criterion_main!(sim_benches);
