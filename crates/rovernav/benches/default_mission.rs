//! Simulated metres per wall-clock second on the default mission (release: `cargo bench -p rovernav`).
//!
//! Criterion times one complete traverse; the throughput is the distance the rover drove, so the
//! report reads in metres per second of wall time. The run's own figures are printed too.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use rovernav_executive::{Mission, Run};
use rovernav_harness::JudgedRun;

fn default_mission(c: &mut Criterion) {
    let mission = Mission::default_mission();
    let run = || Run::mission(&mission, "default").and_then(Run::execute).expect("default mission runs");
    let probe = run();
    let metres = probe.report.distance_driven_m;
    println!(
        "default mission: {} after {:.1} m driven, {:.0} s simulated, {:.2} s wall ({:.1} simulated m per wall s)",
        probe.report.outcome,
        metres,
        probe.report.sim_time_s,
        probe.report.wall_time_s,
        metres / probe.report.wall_time_s
    );
    let mut group = c.benchmark_group("traverse");
    group.sample_size(10);
    group.throughput(Throughput::Elements(metres.round().max(1.0) as u64));
    group.bench_function("default_mission_metres", |b| b.iter(run));
    group.finish();
}

criterion_group!(benches, default_mission);
criterion_main!(benches);
