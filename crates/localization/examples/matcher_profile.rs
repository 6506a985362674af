//! Times the matcher workloads once each (for profiling with `perf record`):
//! `cargo run --release -p rovernav-localization --example matcher_profile -- [localisation|scan-window] [bb|ex|both] [repeats]`.

use rovernav_localization::benchmark::{localisation_workload, scan_window_workload, time_match};

/// This thread's CPU time (s), from Linux's schedstat (0 elsewhere): wall time is unreliable
/// on a shared machine.
fn cpu_seconds() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next().and_then(|v| v.parse::<f64>().ok()))
        .map_or(0.0, |ns| ns * 1e-9)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let which = args.get(1).map_or("localisation", String::as_str);
    let mode = args.get(2).map_or("both", String::as_str);
    let repeats: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(1);
    let start = std::time::Instant::now();
    let workload = match which {
        "scan-window" => scan_window_workload(),
        _ => localisation_workload(),
    };
    let workload = match workload {
        Ok(w) => w,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    };
    eprintln!("local known cells {}", workload.local.data.iter().filter(|h| h.is_finite()).count());
    eprintln!("prepared {} in {:.3} s", workload.name, start.elapsed().as_secs_f64());
    for exhaustive in [false, true] {
        if (exhaustive && mode == "bb") || (!exhaustive && mode == "ex") {
            continue;
        }
        for _ in 0..repeats {
            let cpu = cpu_seconds();
            let result = time_match(&workload, exhaustive);
            let cpu = cpu_seconds() - cpu;
            match result {
                Ok(t) => println!(
                    "cpu {:.4} s; {} {}: {:.4} s, score {:.6}, best {:?}, error {:.3} m, {} poses' worth of lookups of {} lattice poses, {} boxes",
                    cpu,
                    workload.name,
                    if exhaustive { "exhaustive" } else { "branch and bound" },
                    t.seconds,
                    t.score,
                    t.best_index,
                    t.error_m(&workload.truth),
                    t.poses_evaluated,
                    t.lattice_poses,
                    t.boxes
                ),
                Err(e) => eprintln!("error: {e}"),
            }
        }
    }
}
