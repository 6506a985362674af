//! Planner benchmarks, each against a baseline measured in the same run (the ratio is printed
//! before criterion's own figures; `rovernav bench report` gives the same comparisons as a table):
//!
//! - A* and Dijkstra on the weighted cost map map1000 and on the MovingAI maze512 against the
//!   `pathfinding` crate searching the identical graph ([`rovernav_planning::baseline`]), path
//!   costs asserted equal;
//! - Field D* on map1000, bin1000 and uni200: path cost against the data README's reference,
//!   time per expansion, replanning after the obstacle block and after the moved start
//!   ([`rovernav_planning::benchmark::run_grid_events`]) against planning from scratch;
//! - D* Lite and Field D* replanning after a 121x121 local map update near the rover on map1000
//!   against planning from scratch (and against A* from scratch).
//!
//! Data files missing -> the group is skipped. Run: `cargo bench -p rovernav-planning`.

use criterion::{BatchSize, Criterion, Throughput, criterion_group, criterion_main};
use rovernav_core::data_file_or_skip;
use rovernav_planning::baseline::pathfinding_cost;
use rovernav_planning::benchmark::{run_grid_events, window_update};
use rovernav_planning::movingai::{parse_map, parse_scenarios};
use rovernav_planning::pgm::parse_cost_map;
use rovernav_planning::{AStar, Cell, CostGrid, GlobalPlanner, GraphKind, planner_by_name};
use std::hint::black_box;
use std::time::Instant;

fn cost_map(name: &str) -> Option<CostGrid> {
    let path = data_file_or_skip(&format!("costmaps/{name}.pgm"))?;
    Some(parse_cost_map(&std::fs::read(path).expect("readable")).expect("valid"))
}

/// The data README's start and goal on an N x N cost map: (N/10, N/10) to (N-1-N/10, N-1-N/10).
fn readme_query(grid: &CostGrid) -> (Cell, Cell) {
    let n = grid.rows();
    (Cell::new(n / 10, n / 10), Cell::new(n - 1 - n / 10, n - 1 - n / 10))
}

/// Best of five wall times of `f` (seconds).
fn best_of_5<T>(mut f: impl FnMut() -> T) -> f64 {
    (0..5)
        .map(|_| {
            let t0 = Instant::now();
            black_box(f());
            t0.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}

/// Best wall times of `a` and `b` over seven alternating runs (seconds): on a shared machine
/// alternating keeps both under the same load.
fn best_of_alternating<A, B>(mut a: impl FnMut() -> A, mut b: impl FnMut() -> B) -> (f64, f64) {
    let (mut ta, mut tb) = (f64::INFINITY, f64::INFINITY);
    for _ in 0..7 {
        ta = ta.min(best_of_1(&mut a));
        tb = tb.min(best_of_1(&mut b));
    }
    (ta, tb)
}

fn best_of_1<T>(f: &mut impl FnMut() -> T) -> f64 {
    let t0 = Instant::now();
    black_box(f());
    t0.elapsed().as_secs_f64()
}

fn print_ratio(what: &str, ours: f64, baseline_name: &str, baseline: f64) {
    eprintln!(
        "{what}: rovernav {:.3} ms, {baseline_name} {:.3} ms, speed-up {:.2}x",
        ours * 1e3,
        baseline * 1e3,
        baseline / ours
    );
}

/// A* and Dijkstra against `pathfinding` on one graph and a list of queries.
fn versus_pathfinding(c: &mut Criterion, label: &str, grid: &CostGrid, queries: &[(Cell, Cell)]) {
    let mut group = c.benchmark_group(format!("{label} vs pathfinding"));
    group.sample_size(10);
    for informed in [true, false] {
        let mut ours = if informed {
            AStar::new(GraphKind::CellCentres)
        } else {
            AStar::dijkstra(GraphKind::CellCentres)
        };
        ours.set_grid(grid.clone());
        let theirs = |s: Cell, g: Cell| pathfinding_cost(grid, s, g, informed).unwrap_or(f64::INFINITY);
        let mut expansions = 0;
        for &(s, g) in queries {
            let plan = ours.plan(s, g).expect("solvable");
            expansions += plan.expansions;
            let base = theirs(s, g);
            assert!((plan.cost - base).abs() <= 1e-9 * base, "{label} {s:?}->{g:?}: {} vs {base}", plan.cost);
        }
        let name = if informed { "astar" } else { "dijkstra" };
        let (t_ours, t_theirs) = best_of_alternating(
            || queries.iter().map(|&(s, g)| ours.plan(s, g).map_or(0.0, |p| p.cost)).sum::<f64>(),
            || queries.iter().map(|&(s, g)| theirs(s, g)).sum::<f64>(),
        );
        print_ratio(&format!("{label} {name} ({expansions} expansions)"), t_ours, "pathfinding", t_theirs);
        group.throughput(Throughput::Elements(expansions as u64));
        group.bench_function(format!("{name} rovernav (throughput = expansions)"), |b| {
            b.iter(|| {
                queries.iter().map(|&(s, g)| black_box(ours.plan(s, g).expect("solvable").cost)).sum::<f64>()
            })
        });
        group.bench_function(format!("{name} pathfinding"), |b| {
            b.iter(|| queries.iter().map(|&(s, g)| black_box(theirs(s, g))).sum::<f64>())
        });
    }
    group.finish();
}

fn graph_search(c: &mut Criterion) {
    if let Some(grid) = cost_map("map1000") {
        versus_pathfinding(c, "map1000", &grid, &[readme_query(&grid)]);
    }
    let (Some(map), Some(scen)) =
        (data_file_or_skip("movingai/maze512-32-9.map"), data_file_or_skip("movingai/maze512-32-9.map.scen"))
    else {
        return;
    };
    let map = parse_map(&std::fs::read_to_string(map).expect("readable")).expect("valid");
    let scen = parse_scenarios(&std::fs::read_to_string(scen).expect("readable")).expect("valid");
    // Every 400th scenario: 21 queries spread over all difficulty buckets.
    let queries: Vec<_> = scen.iter().step_by(400).map(|s| (s.start, s.goal)).collect();
    versus_pathfinding(c, "maze512", &map.cost_grid(), &queries);
}

/// Field D* path cost against the README reference, expansions, and replanning against scratch.
fn field_dstar(c: &mut Criterion) {
    // (map, goal override, reference Field D* cost from the data README)
    let cases = [
        ("map1000", None, 24145.3),
        ("bin1000", None, 1135.3),
        ("uni200", Some(Cell::new(179, 85)), 171.783),
    ];
    let mut group = c.benchmark_group("field-dstar");
    group.sample_size(10);
    for (name, goal, reference) in cases {
        let Some(grid) = cost_map(name) else { continue };
        let (start, readme_goal) = readme_query(&grid);
        let goal = goal.unwrap_or(readme_goal);
        let events = run_grid_events(&grid, start, goal, "field-dstar").expect("path");
        let initial = &events.events[0];
        eprintln!(
            "field-dstar {name}: cost {:.1} (reference {reference}, {:+.3} %), {} expansions, {:.3} us per expansion",
            initial.cost,
            100.0 * (initial.cost / reference - 1.0),
            initial.expansions,
            initial.ms * 1e3 / initial.expansions.max(1) as f64
        );
        let fresh = &events.events[3];
        for e in &events.events[1..3] {
            eprintln!(
                "field-dstar {name} {}: replan {:.3} ms, from scratch {:.3} ms on the final map, speed-up {:.1}x",
                e.name,
                e.ms,
                fresh.ms,
                fresh.ms / e.ms.max(1e-9)
            );
        }
        group.throughput(Throughput::Elements(initial.expansions as u64));
        group.bench_function(format!("{name} plan (throughput = expansions)"), |b| {
            b.iter_batched(
                || {
                    let mut p = planner_by_name("field-dstar").expect("registered");
                    p.set_grid(grid.clone());
                    p
                },
                |mut p| black_box(p.plan(start, goal).expect("path")),
                BatchSize::LargeInput,
            )
        });
    }
    group.finish();
}

fn local_update(c: &mut Criterion) {
    let Some(grid) = cost_map("map1000") else { return };
    let (start, goal) = (Cell::new(100, 100), Cell::new(899, 899));
    let mut group = c.benchmark_group("map1000 121x121 update near the rover");
    group.sample_size(10);
    let updates = [window_update(&grid, start, true), window_update(&grid, start, false)];
    let mut changed = grid.clone();
    changed.apply(&updates[0]).expect("valid");
    let mut astar = AStar::new(GraphKind::CellCentres);
    astar.set_grid(changed.clone());
    let t_astar = best_of_5(|| astar.plan(start, goal).expect("path").cost);
    for name in ["dstar-lite", "field-dstar"] {
        let mut planner = planner_by_name(name).expect("registered");
        planner.set_grid(grid.clone());
        planner.plan(start, goal).expect("path");
        let mut which = 0;
        let mut replan = || {
            planner.update_cells(&updates[which]).expect("valid");
            which ^= 1;
            planner.replan().expect("path")
        };
        // Each update is timed from the unchanged map's search (the undo runs untimed).
        let t_replan = (0..5)
            .map(|_| {
                let t0 = Instant::now();
                black_box(replan());
                let t = t0.elapsed().as_secs_f64();
                replan();
                t
            })
            .fold(f64::INFINITY, f64::min);
        let scratch = || {
            let mut p = planner_by_name(name).expect("registered");
            p.set_grid(changed.clone());
            let t0 = Instant::now();
            black_box(p.plan(start, goal).expect("path"));
            t0.elapsed().as_secs_f64()
        };
        let t_scratch = (0..3).map(|_| scratch()).fold(f64::INFINITY, f64::min);
        print_ratio(&format!("{name} replan"), t_replan, &format!("{name} from scratch"), t_scratch);
        if name == "dstar-lite" {
            print_ratio("dstar-lite replan", t_replan, "astar from scratch", t_astar);
        }
        group.bench_function(format!("{name} replan (update and undo)"), |b| b.iter(|| black_box(replan())));
    }
    group.bench_function("astar from scratch", |b| {
        b.iter(|| black_box(astar.plan(start, goal).expect("path")))
    });
    group.finish();
}

criterion_group!(benches, graph_search, field_dstar, local_update);
criterion_main!(benches);
