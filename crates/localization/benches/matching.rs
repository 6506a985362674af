//! The map matcher against exhaustive search of the same poses, in the same run (issue 43):
//!
//! - `matcher-localisation`: a 10 m x 10 m local map at 5 cm (every known cell) against a
//!   20 m x 20 m global map, the full match (see `rovernav_localization::benchmark`);
//! - `matcher-scan-window`: about 340 obstacle points at 5 cm in a window of +-7 m and +-30 deg
//!   (Cartographer's defaults), the search alone.
//!
//! Criterion times the branch and bound (and, on the localisation workload, exhaustive search
//! too); each group also times one exhaustive search with `benchmark::compare` and prints the
//! ratio, asserting that both find the same optimum (the scan window's exhaustive search takes
//! about 10 s, too long for criterion's ten samples).

use criterion::{Criterion, criterion_group, criterion_main};
use rovernav_localization::benchmark::{
    MatcherWorkload, compare, localisation_workload, scan_window_workload, time_match,
};
use rovernav_localization::matching::{MlMatcher, MlParams};

/// Prints branch and bound against one exhaustive search of the same workload.
fn print_ratio(workload: &MatcherWorkload) {
    let c = compare(workload, 3).expect("workload");
    let (b, e) = (&c.rovernav, &c.exhaustive);
    eprintln!(
        "{}: branch and bound {:.4} s, exhaustive {:.4} s: {:.1}x faster; {} lattice poses, {} poses' \
         worth of lookups, {} boxes; same optimum: {} ({:.6} vs {:.6}); error {:.3} m",
        workload.name,
        b.seconds,
        e.seconds,
        c.speedup(),
        b.lattice_poses,
        b.poses_evaluated,
        b.boxes,
        c.same_optimum(),
        b.score,
        e.score,
        b.error_m(&workload.truth)
    );
    assert!(c.same_optimum(), "{}: branch and bound missed the exhaustive optimum", workload.name);
}

fn localisation(c: &mut Criterion) {
    let w = localisation_workload().expect("workload");
    print_ratio(&w);
    let mut group = c.benchmark_group("matcher-localisation");
    group.sample_size(10);
    group.bench_function("prepare 20 m global map at 5 cm", |b| {
        b.iter(|| MlMatcher::new(&w.global, MlParams::default()).expect("global map"))
    });
    group
        .bench_function("match 10 m local map at 5 cm", |b| b.iter(|| time_match(&w, false).expect("match")));
    // The same match scoring every lattice pose: the baseline the branch and bound's speed-up
    // is read against, measured in the same run because the machine's speed varies.
    group.bench_function("match 10 m local map at 5 cm, exhaustive search", |b| {
        b.iter(|| time_match(&w, true).expect("match"))
    });
    group.finish();
}

fn scan_window(c: &mut Criterion) {
    let w = scan_window_workload().expect("workload");
    print_ratio(&w);
    let mut group = c.benchmark_group("matcher-scan-window");
    group.sample_size(10);
    group.bench_function("search 340 points, 7 m and 30 deg window", |b| {
        b.iter(|| time_match(&w, false).expect("match"))
    });
    group.finish();
}

criterion_group!(benches, localisation, scan_window);
criterion_main!(benches);
