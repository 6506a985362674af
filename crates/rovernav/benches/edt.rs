//! Distance transforms in ns per cell at 1024x1024 and 4096x4096 (throughput = cells): rovernav's
//! exact EDT (`rovernav_localization::matching::distance_transform`) against the straightforward
//! Felzenszwalb-Huttenlocher transform and a two-pass 3-4 chamfer (the baselines of `rovernav
//! bench report`, `src/bench/edt.rs`), on a 2 % occupied grid. The memory-bandwidth floor is
//! about 1.4 ns per cell here. Run: `cargo bench -p rovernav --bench edt`.

#[allow(dead_code)] // the bench uses the baselines, not every helper
#[path = "../src/bench/edt.rs"]
mod edt;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use rovernav_localization::matching::distance_transform::squared_distance_3d;
use std::hint::black_box;
use std::time::Instant;

fn transforms(c: &mut Criterion) {
    for side in [1024usize, 4096] {
        let occ = edt::random_occupancy(side, side, 0.02, 43);
        let cells = (side * side) as f64;
        let ns = |f: &dyn Fn()| {
            let t0 = Instant::now();
            f();
            t0.elapsed().as_secs_f64() * 1e9 / cells
        };
        let ours = ns(&|| drop(black_box(squared_distance_3d(&occ, side, side, 1, u16::MAX))));
        let fh = ns(&|| drop(black_box(edt::felzenszwalb_huttenlocher(&occ, side, side))));
        let chamfer = ns(&|| drop(black_box(edt::chamfer_3_4(&occ, side, side))));
        eprintln!(
            "EDT {side}x{side}: rovernav exact {ours:.1} ns/cell, Felzenszwalb-Huttenlocher {fh:.1} ({:.2}x), \
             3-4 chamfer {chamfer:.1} ({:.2}x)",
            fh / ours,
            chamfer / ours,
        );
        let mut group = c.benchmark_group(format!("edt {side}x{side}"));
        group.sample_size(10).throughput(Throughput::Elements(side as u64 * side as u64));
        group.bench_function("rovernav exact", |b| {
            b.iter(|| squared_distance_3d(&occ, side, side, 1, u16::MAX))
        });
        group.bench_function("felzenszwalb-huttenlocher", |b| {
            b.iter(|| edt::felzenszwalb_huttenlocher(&occ, side, side))
        });
        group.bench_function("chamfer 3-4", |b| b.iter(|| edt::chamfer_3_4(&occ, side, side)));
        group.finish();
    }
}

criterion_group!(benches, transforms);
criterion_main!(benches);
