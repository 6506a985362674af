//! Terrain-evaluation throughput: one full T-grid update (121 x 121 cells of 0.15 m) from one
//! wedge of range data, its parts, and a toroidal recentre against a copying one.

#[path = "../tests/common/mod.rs"]
mod common;

use common::{Rock, Scene, Shape, Shot, cast};
use criterion::{Criterion, criterion_group, criterion_main};
use rovernav_core::{Point2, Pose2, Pose3, PoseEstimate};
use rovernav_mapping::{CopyingGrid, RollingGrid};
use rovernav_perception::{CellStats, TerrainConfig, TerrainEvaluator};
use std::hint::black_box;
use std::time::Duration;

fn scene() -> Scene {
    let mut rocks = Vec::new();
    for k in 0..12 {
        let t = k as f64 * 0.37;
        rocks.push(Rock {
            x: 1.2 + 0.3 * k as f64,
            y: 1.5 * t.sin(),
            size: 0.3 + 0.05 * (k % 4) as f64,
            height: 0.1 + 0.04 * (k % 6) as f64,
            shape: if k % 2 == 0 { Shape::Box } else { Shape::Dome },
        });
    }
    Scene { gx: 0.05, gy: -0.03, rocks, ..Default::default() }
}

fn terrain_update(c: &mut Criterion) {
    let pose = Pose3::default();
    // 180 x 200 rays: about 36k points over the 45 degree, 0.5-5 m mast wedge.
    let cloud = cast(&scene(), &Shot::mast(pose, 180, 200, 0.01, 11));
    eprintln!("cloud: {} points", cloud.points.len());
    let estimate = PoseEstimate { pose, covariance: [[0.0; 3]; 3] };
    let fresh = TerrainEvaluator::new(TerrainConfig::default(), pose.pose2()).unwrap();
    let clouds = [cloud];

    let mut group = c.benchmark_group("terrain_evaluation_121x121");
    // The navigation loop keeps one evaluator: update it in place (each call bins the wedge
    // again, so the per-cell work stays the same from call to call).
    let mut ev = fresh.clone();
    group.bench_function("full_update_one_wedge", |b| {
        b.iter(|| {
            black_box(ev.update(black_box(&clouds), &estimate).hazard.data.len());
        })
    });
    group.bench_function("full_update_one_wedge_fresh_evaluator", |b| {
        b.iter_batched_ref(
            || fresh.clone(),
            |ev| {
                ev.update(black_box(&clouds), &estimate);
            },
            criterion::BatchSize::LargeInput,
        )
    });
    group.bench_function("bin_points_only", |b| {
        b.iter_batched_ref(
            || fresh.clone(),
            |ev| black_box(ev.insert_cloud(&clouds[0], &pose)),
            criterion::BatchSize::LargeInput,
        )
    });
    let mut filled = fresh.clone();
    filled.insert_cloud(&clouds[0], &pose);
    group.bench_function("assess_only", |b| {
        b.iter(|| {
            black_box(filled.assess(Pose2::default()).hazard.data.len());
        })
    });
    group.finish();
}

fn grid_shift(c: &mut Criterion) {
    let res = 0.15;
    let mut group = c.benchmark_group("t_grid_shift_one_cell_121x121");
    let mut torus = RollingGrid::new(121, 121, res, CellStats::EMPTY, Point2::default()).unwrap();
    let mut x = 0.0;
    group.bench_function("toroidal", |b| {
        b.iter(|| {
            x += res;
            torus.recenter(black_box(Point2::new(x, 0.3 * x)));
        })
    });
    let mut copy = CopyingGrid::new(121, 121, res, CellStats::EMPTY, Point2::default()).unwrap();
    let mut x = 0.0;
    group.bench_function("copying", |b| {
        b.iter(|| {
            x += res;
            copy.recenter(black_box(Point2::new(x, 0.3 * x)));
        })
    });
    group.finish();
}

fn config() -> Criterion {
    Criterion::default()
        .sample_size(20)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2))
}

criterion_group! {
    name = benches;
    config = config();
    targets = terrain_update, grid_shift
}
criterion_main!(benches);
