//! MovingAI benchmark scenarios (Sturtevant 2012) against their published optimal 8-connected
//! lengths: octile A* and D* Lite must match exactly; Field D* must never beat the straight
//! line, never be more than 1 % above the optimum, and be shorter on average.

use rovernav_core::data_file_or_skip;
use rovernav_planning::benchmark::{MovingAiReport, run_movingai};
use rovernav_planning::movingai::{MovingAiMap, Scenario, parse_map, parse_scenarios};

/// (map file, scenario file, stride): maze512 has 8010 scenarios, so the debug-profile suite
/// runs every 80th (the full set runs through `rovernav bench movingai`).
const MAPS: [(&str, &str, usize); 3] = [
    ("movingai/arena.map", "movingai/arena.map.scen", 1),
    ("movingai/maze512-32-9.map", "movingai/maze512-32-9.map.scen", 80),
    ("movingai/random-32-32-20.map", "movingai/random-32-32-20-random-1.scen", 1),
];

fn load(map: &str, scen: &str) -> Option<(MovingAiMap, Vec<Scenario>)> {
    let map_path = data_file_or_skip(map)?;
    let scen_path = data_file_or_skip(scen)?;
    let m = parse_map(&std::fs::read_to_string(map_path).expect("readable")).expect("valid map");
    let s = parse_scenarios(&std::fs::read_to_string(scen_path).expect("readable")).expect("valid scenarios");
    Some((m, s))
}

fn run(planner: &str) -> Vec<MovingAiReport> {
    let mut reports = Vec::new();
    for (map, scen, stride) in MAPS {
        let Some((m, s)) = load(map, scen) else {
            continue;
        };
        let r = run_movingai(&m, map, &s, planner, stride).expect("benchmark runs");
        eprintln!(
            "{planner} on {map}: {} scenarios, {} solved, {} mismatches, mean ratio {:.5}, max ratio {:.5}, min cost/straight {:.5}, {:.0} us/query",
            r.scenarios,
            r.solved,
            r.mismatches,
            r.mean_cost_ratio,
            r.max_cost_ratio,
            r.min_straight_ratio,
            r.mean_us_per_query
        );
        assert!(r.scenarios > 0);
        reports.push(r);
    }
    reports
}

#[test]
fn astar_matches_published_optimal_lengths() {
    for r in run("astar") {
        assert_eq!(r.solved, r.scenarios, "{}", r.map);
        assert_eq!(r.mismatches, 0, "{}", r.map);
    }
}

#[test]
fn dstar_lite_matches_published_optimal_lengths() {
    for r in run("dstar-lite") {
        assert_eq!(r.solved, r.scenarios, "{}", r.map);
        assert_eq!(r.mismatches, 0, "{}", r.map);
    }
}

#[test]
fn field_dstar_is_any_angle_and_never_much_worse() {
    for r in run("field-dstar") {
        assert_eq!(r.solved, r.scenarios, "{}", r.map);
        assert_eq!(r.mismatches, 0, "{}", r.map);
        assert!(r.min_straight_ratio >= 1.0 - 1e-12, "{}", r.map);
        assert!(r.max_cost_ratio <= 1.01, "{}", r.map);
        assert!(r.mean_cost_ratio < 1.0, "{}", r.map);
    }
}
