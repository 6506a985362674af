//! Matches per second: a 10 m x 10 m local map at 5 cm against a 20 m x 20 m global map, by
//! branch and bound and by exhaustive search (the baseline for the branch and bound's speed-up).

use criterion::{Criterion, criterion_group, criterion_main};
use rovernav_core::{GridGeometry, Pose2};
use rovernav_localization::matching::{MlMatcher, MlParams, SearchWindow};
use rovernav_localization::synthetic::{TerrainParams, fractal_terrain, local_map_from_field};

fn matching(c: &mut Criterion) {
    let resolution = 0.05;
    let field = fractal_terrain(&TerrainParams { size: 24.0, resolution: 0.025, ..Default::default() }, 1);
    let global =
        field.sample(GridGeometry { cols: 400, rows: 400, resolution, origin_x: -10.0, origin_y: -10.0 });
    let truth = Pose2::new(0.37, -0.21, 0.3);
    let local_geometry = GridGeometry { cols: 200, rows: 200, resolution, origin_x: -5.0, origin_y: -5.0 };
    let local = local_map_from_field(&field, &truth, local_geometry, None, 0.01, 0.2, 2);
    let matcher = MlMatcher::new(&global, MlParams::default()).expect("global map");
    let window =
        SearchWindow { center: Pose2::new(0.3, -0.1, 0.28), half_x: 0.5, half_y: 0.5, half_yaw: 0.05 };
    let d = matcher.match_detailed(&local, &window, false).expect("match");
    eprintln!(
        "lattice {} poses, {} local cells, {} scored ({} single poses), failure search {}; error {:.3} m",
        d.lattice.size(),
        d.local_cells,
        d.result.poses_evaluated,
        d.poses_tested,
        d.failure_search_evaluations,
        (d.result.pose.x - truth.x).hypot(d.result.pose.y - truth.y)
    );
    let mut group = c.benchmark_group("ml_matching");
    group.sample_size(10);
    group.bench_function("prepare 20 m global map at 5 cm", |b| {
        b.iter(|| MlMatcher::new(&global, MlParams::default()).expect("global map"))
    });
    group.bench_function("match 10 m local map at 5 cm", |b| {
        b.iter(|| matcher.match_map(&local, &window).expect("match"))
    });
    // The same match scoring every lattice pose: the baseline the branch and bound's speed-up
    // is read against, measured in the same run because the machine's speed varies.
    group.bench_function("match 10 m local map at 5 cm, exhaustive search", |b| {
        b.iter(|| matcher.exhaustive_search(&local, &window).expect("match"))
    });
    group.finish();
}

criterion_group!(benches, matching);
criterion_main!(benches);
