//! The `rovernav bench` logic: the replanning event sequence on a cost map and the input
//! handling the CLI relies on.

use rovernav_core::data_file_or_skip;
use rovernav_planning::benchmark::{BenchError, parse_cell, parse_grid_file, run_grid_events, run_movingai};
use rovernav_planning::movingai::{parse_map, parse_scenarios};
use rovernav_planning::{Cell, planner_by_name};

#[test]
fn grid_events_replan_like_a_fresh_planner() {
    let Some(path) = data_file_or_skip("costmaps/map200.pgm") else {
        return;
    };
    let grid = parse_grid_file(&std::fs::read(path).expect("readable")).expect("valid map");
    for planner in ["astar", "dstar-lite", "field-dstar"] {
        let r = run_grid_events(&grid, Cell::new(20, 20), Cell::new(179, 179), planner).expect("events run");
        let names: Vec<&str> = r.events.iter().map(|e| e.name).collect();
        assert_eq!(names, ["initial", "obstacle", "move-start", "fresh"]);
        assert_eq!(r.obstacle.len(), 100);
        for e in &r.events {
            eprintln!(
                "{planner} ({}): {:<10} {:8.3} ms {:7} expansions cost {:.3} value {:.3}",
                r.graph, e.name, e.ms, e.expansions, e.cost, e.value
            );
        }
        let [initial, blocked, moved, fresh] = &r.events[..] else { unreachable!() };
        // Blocking cells can only raise the optimum.
        assert!(blocked.value >= initial.value - 1e-9);
        // The replanned search and a new instance agree on the changed map from the new start.
        assert_eq!(moved.start, fresh.start);
        assert!((moved.value - fresh.value).abs() <= 1e-9 * fresh.value, "{planner}");
        assert!((moved.cost - fresh.cost).abs() <= 1e-6 * fresh.cost, "{planner}");
        let expected_graph = if planner == "field-dstar" { "corner-nodes" } else { "cell-centres" };
        assert_eq!(r.graph, expected_graph);
    }
}

#[test]
fn grid_files_may_be_pgm_or_movingai_maps() {
    let pgm = b"P5\n2 1\n255\n\x03\xff";
    let g = parse_grid_file(pgm).expect("pgm");
    assert_eq!(g.cost(Cell::new(0, 0)), 3.0);
    let map = b"type octile\nheight 1\nwidth 2\nmap\n.@\n";
    let g = parse_grid_file(map).expect("map");
    assert!(g.is_blocked(Cell::new(0, 1)));
    let e = parse_grid_file(b"type octile\nheight x\n").unwrap_err();
    assert_eq!(e.in_file("maze.map").to_string(), "maze.map line 2: expected `height N`, got `height x`");
}

#[test]
fn cells_parse_as_row_comma_col() {
    assert_eq!(parse_cell("20,30"), Ok(Cell::new(20, 30)));
    assert_eq!(parse_cell(" 1 , 2 "), Ok(Cell::new(1, 2)));
    assert!(parse_cell("1;2").is_err());
    assert!(parse_cell("1,2,3").is_err());
    assert!(parse_cell("-1,2").is_err());
}

#[test]
fn movingai_runs_reject_unknown_planners_and_foreign_scenarios() {
    let map = parse_map("type octile\nheight 2\nwidth 2\nmap\n..\n..\n").expect("map");
    let scen = parse_scenarios("version 1\n0\tx.map\t2\t2\t0\t0\t1\t1\t1.41421356\n").expect("scen");
    assert!(matches!(run_movingai(&map, "m", &scen, "nope", 1), Err(BenchError::UnknownPlanner(_))));
    let r = run_movingai(&map, "m", &scen, "astar", 1).expect("runs");
    assert_eq!((r.scenarios, r.solved, r.mismatches), (1, 1, 0));
    let wrong = parse_scenarios("0\tx.map\t3\t3\t0\t0\t1\t1\t1.41421356\n").expect("scen");
    let e = run_movingai(&map, "m", &wrong, "astar", 1).unwrap_err();
    assert!(e.to_string().starts_with("line 1:"), "{e}");
    assert!(planner_by_name("field-dstar").is_some());
}
