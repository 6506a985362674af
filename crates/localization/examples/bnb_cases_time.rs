//! Times the `rovernav eval localization` branch-and-bound cases (search only), branch and
//! bound against exhaustive search, in CPU seconds of this thread:
//! `cargo run --release -p rovernav-localization --example bnb_cases_time -- [cases]`.

use rovernav_localization::evaluation::{BnbSetup, bnb_case};

fn cpu_seconds() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next().and_then(|v| v.parse::<f64>().ok()))
        .map_or(0.0, |ns| ns * 1e-9)
}

fn main() {
    let cases: u64 = std::env::args().nth(1).and_then(|s| s.parse().ok()).unwrap_or(20);
    let setup = BnbSetup::default();
    let (mut bb_s, mut ex_s, mut exact) = (0.0, 0.0, 0);
    for case in 0..cases {
        let (matcher, local, window) = bnb_case(&setup, case);
        let t = cpu_seconds();
        let Ok((bb, _)) = matcher.search(&local, &window, false) else { continue };
        bb_s += cpu_seconds() - t;
        let t = cpu_seconds();
        let Ok((ex, _)) = matcher.search(&local, &window, true) else { continue };
        ex_s += cpu_seconds() - t;
        exact += u64::from(bb.score == ex.score);
    }
    println!(
        "{cases} cases: branch and bound {bb_s:.3} s, exhaustive {ex_s:.3} s ({:.1}x), {exact} exact",
        ex_s / bb_s
    );
}
