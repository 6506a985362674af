//! Building the terrain octree from one stereo pair, against the dense voxel grid with the same
//! marking rules (the baseline, measured in the same run): time per build, and the memory of
//! each printed once.
//!
//! The pair: a Hazcam-like pair (0.10 m baseline, 0.35 m high) that sensed 256 x 256 points
//! of ground with two rocks in front of the rover, 0.4-2.0 m ahead.

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rovernav_manipulation::octree::{DenseGrid, Octree, OctreeParams, View};
use std::hint::black_box;

fn pair() -> (Vec<Vector3<f64>>, Vec<[f32; 3]>) {
    let cameras = vec![Vector3::new(0.43, 0.05, 0.35), Vector3::new(0.43, -0.05, 0.35)];
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let rock = |x: f64, y: f64| {
        let a = 0.15 - ((x - 0.9).powi(2) + (y - 0.1).powi(2)).sqrt();
        let b = 0.10 - ((x - 1.2).powi(2) + (y + 0.25).powi(2)).sqrt();
        a.max(b).max(0.0)
    };
    let mut points = Vec::with_capacity(256 * 256);
    for i in 0..256 {
        for j in 0..256 {
            let x = 0.4 + 1.6 * i as f64 / 255.0;
            let y = -0.8 + 1.6 * j as f64 / 255.0;
            let z = rock(x, y) + rng.random_range(-0.004..0.004);
            points.push([x as f32, y as f32, z as f32]);
        }
    }
    (cameras, points)
}

fn bench(c: &mut Criterion) {
    let (cameras, points) = pair();
    let params = OctreeParams::default();
    let views = [View { cameras: &cameras, points: &points }];
    let tree = Octree::build(params.clone(), &views);
    let grid = DenseGrid::build(&params, &views);
    println!(
        "memory: octree {} nodes, {} bytes; dense grid {} bytes (ratio {:.3}); cells [occupied, free, unknown] {:?}",
        tree.node_count(),
        tree.memory_bytes(),
        grid.memory_bytes(),
        tree.memory_bytes() as f64 / grid.memory_bytes() as f64,
        tree.counts()
    );
    let mut group = c.benchmark_group("octree_build_one_pair");
    group.sample_size(10);
    group
        .bench_function("octree", |b| b.iter(|| black_box(Octree::build(params.clone(), black_box(&views)))));
    group.bench_function("dense_grid_baseline", |b| {
        b.iter(|| black_box(DenseGrid::build(&params, black_box(&views))))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
