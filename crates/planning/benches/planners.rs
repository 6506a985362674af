//! Planner benchmarks: A* / D* Lite / Field D* query time on maze512, D* Lite replanning after
//! a 121x121 local map update near the rover on a 1000x1000 map against planning from scratch,
//! and Field D* time per node expansion on map1000. Data files missing -> the bench is skipped.
//!
//! Run: `cargo bench -p rovernav-planning -- --quick`

use criterion::{BatchSize, Criterion, Throughput, criterion_group, criterion_main};
use rovernav_core::data_file_or_skip;
use rovernav_planning::movingai::{parse_map, parse_scenarios};
use rovernav_planning::pgm::parse_cost_map;
use rovernav_planning::{Cell, CellChange, CostGrid, GlobalPlanner, planner_by_name};
use std::hint::black_box;

/// MRPTA's local terrain grid side (paper 004 section 3.3).
const WINDOW: usize = 121;

fn maze_queries(c: &mut Criterion) {
    let (Some(map), Some(scen)) =
        (data_file_or_skip("movingai/maze512-32-9.map"), data_file_or_skip("movingai/maze512-32-9.map.scen"))
    else {
        return;
    };
    let map = parse_map(&std::fs::read_to_string(map).expect("readable")).expect("valid");
    let scen = parse_scenarios(&std::fs::read_to_string(scen).expect("readable")).expect("valid");
    // Every 400th scenario: 21 queries spread over all difficulty buckets.
    let queries: Vec<_> = scen.iter().step_by(400).map(|s| (s.start, s.goal)).collect();
    let mut group = c.benchmark_group("maze512");
    group.sample_size(10);
    group.throughput(Throughput::Elements(queries.len() as u64));
    for name in ["astar", "dstar-lite", "field-dstar"] {
        let mut planner = planner_by_name(name).expect("registered");
        planner.set_grid(map.cost_grid());
        group.bench_function(format!("{name} per query"), |b| {
            b.iter(|| {
                for &(s, g) in &queries {
                    black_box(planner.plan(s, g).expect("solvable"));
                }
            })
        });
    }
    group.finish();
}

fn map1000() -> Option<CostGrid> {
    let path = data_file_or_skip("costmaps/map1000.pgm")?;
    Some(parse_cost_map(&std::fs::read(path).expect("readable")).expect("valid"))
}

/// The window of newly sensed terrain: centred 40 cells ahead of the rover, costs doubled and a
/// band of obstacles across the direction of travel (`scale` 1 restores the original map).
fn window_update(grid: &CostGrid, rover: Cell, doubled: bool) -> Vec<CellChange> {
    let centre = rover.row + 40;
    let r0 = centre - WINDOW / 2;
    let c0 = rover.col + 40 - WINDOW / 2;
    let mut changes = Vec::with_capacity(WINDOW * WINDOW);
    for row in r0..r0 + WINDOW {
        for col in c0..c0 + WINDOW {
            let cell = Cell::new(row, col);
            let base = grid.cost(cell);
            let cost = if !doubled {
                base
            } else if row == centre && (col - c0) % 30 < 25 {
                f32::INFINITY
            } else {
                base * 2.0
            };
            changes.push(CellChange { cell, cost });
        }
    }
    changes
}

fn dstar_lite_local_update(c: &mut Criterion) {
    let Some(grid) = map1000() else { return };
    let (start, goal) = (Cell::new(100, 100), Cell::new(899, 899));
    let mut group = c.benchmark_group("map1000 121x121 update near the rover");
    group.sample_size(10);
    for name in ["dstar-lite", "field-dstar"] {
        let mut planner = planner_by_name(name).expect("registered");
        planner.set_grid(grid.clone());
        planner.plan(start, goal).expect("path");
        let updates = [window_update(&grid, start, true), window_update(&grid, start, false)];
        let mut which = 0;
        group.bench_function(format!("{name} replan"), |b| {
            b.iter(|| {
                planner.update_cells(&updates[which]).expect("valid");
                which ^= 1;
                black_box(planner.replan().expect("path"))
            })
        });
        let mut changed = grid.clone();
        changed.apply(&updates[0]).expect("valid");
        group.bench_function(format!("{name} from scratch"), |b| {
            b.iter_batched(
                || {
                    let mut p: Box<dyn GlobalPlanner> = planner_by_name(name).expect("registered");
                    p.set_grid(changed.clone());
                    p
                },
                |mut p| black_box(p.plan(start, goal).expect("path")),
                BatchSize::LargeInput,
            )
        });
    }
    group.finish();
}

fn field_dstar_expansions(c: &mut Criterion) {
    let Some(grid) = map1000() else { return };
    let (start, goal) = (Cell::new(100, 100), Cell::new(899, 899));
    let mut probe = planner_by_name("field-dstar").expect("registered");
    probe.set_grid(grid.clone());
    let expansions = probe.plan(start, goal).expect("path").expansions;
    eprintln!("field-dstar map1000: {expansions} expansions per plan");
    let mut group = c.benchmark_group("field-dstar map1000");
    group.sample_size(10);
    group.throughput(Throughput::Elements(expansions as u64));
    group.bench_function("plan (throughput = expansions)", |b| {
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
    group.finish();
}

criterion_group!(benches, maze_queries, dstar_lite_local_update, field_dstar_expansions);
criterion_main!(benches);
