//! Times the matcher workloads once each (for profiling with `perf record`):
//! `cargo run --release -p rovernav-localization --example matcher_profile -- [localisation|scan-window] [bb|ex|both] [repeats]`.

use rovernav_localization::benchmark::{localisation_workload, scan_window_workload, time_match};

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
            match time_match(&workload, exhaustive) {
                Ok(t) => println!(
                    "{} {}: {:.4} s, score {:.6}, best {:?}, error {:.3} m, {} poses' worth of lookups of {} lattice poses, {} boxes",
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
