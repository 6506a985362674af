//! `rovernav bench`: planner benchmarks on the MovingAI scenarios and on cost maps, a thin
//! command-line layer (file reading, argument parsing, printing) over
//! [`rovernav_planning::benchmark`], where the logic lives and is tested; and `bench report`,
//! every hot path against a baseline timed in the same process ([`report`], [`workloads`]).

mod edt;
mod report;
mod workloads;

use anyhow::{Context, anyhow};
use rovernav_planning::benchmark::{
    GridReport, MovingAiReport, parse_cell, parse_grid_file, run_grid_events, run_movingai,
};
use rovernav_planning::movingai::{parse_map, parse_scenarios};
use std::path::{Path, PathBuf};

/// The `bench` subcommands.
#[derive(clap::Subcommand, Debug)]
pub enum BenchCommand {
    /// Run every scenario of a MovingAI `.scen` file on a `.map` and check the published optimal
    /// lengths (the map named inside the `.scen` is ignored: MAP is used).
    Movingai {
        /// The MovingAI `.map` file.
        map: PathBuf,
        /// The `.scen` scenario file.
        scen: PathBuf,
        /// Planner: astar, astar-corners, dstar-lite or field-dstar.
        #[arg(long, default_value = "astar")]
        planner: String,
        /// Print one JSON object instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Plan on a cost map (binary PGM or MovingAI `.map`), then replan after an obstacle block
    /// lands on the path and after the start moves, and plan afresh on the changed map.
    Grid {
        /// The map file.
        map: PathBuf,
        /// Start cell as ROW,COL (image row and column).
        #[arg(long)]
        start: String,
        /// Goal cell as ROW,COL.
        #[arg(long)]
        goal: String,
        /// Planner: astar, astar-corners, dstar-lite or field-dstar.
        #[arg(long, default_value = "field-dstar")]
        planner: String,
        /// Print one JSON object instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Time every hot path against the baseline a user would otherwise pick, both in this
    /// process (A*/Dijkstra vs the pathfinding crate, Field D*, D* Lite replanning, the map
    /// matcher vs exhaustive search, the EDT, the navigation cycle, the simulator), and write
    /// the table with the command and git revision (to docs/results/performance.md unless
    /// --write says where, or --no-write). Needs the data directory (ROVERNAV_DATA).
    Report {
        /// The quick versions (fewer repetitions and cases; about a minute in release).
        #[arg(long)]
        quick: bool,
        /// Print the rows as one JSON object instead of text.
        #[arg(long)]
        json: bool,
        /// Where to write the Markdown table.
        #[arg(long, default_value = "docs/results/performance.md")]
        write: PathBuf,
        /// Do not write the table anywhere.
        #[arg(long)]
        no_write: bool,
    },
}

/// Runs a bench subcommand, printing its results to stdout.
pub fn run(cmd: BenchCommand) -> anyhow::Result<()> {
    match cmd {
        BenchCommand::Movingai { map, scen, planner, json } => {
            let map_text = read_text(&map)?;
            let scen_text = read_text(&scen)?;
            let parsed_map = parse_map(&map_text).map_err(|e| anyhow!(e.in_file(label(&map))))?;
            let scenarios = parse_scenarios(&scen_text).map_err(|e| anyhow!(e.in_file(label(&scen))))?;
            let report = run_movingai(&parsed_map, &label(&map), &scenarios, &planner, 1)
                .map_err(|e| anyhow!("{}: {e}", label(&scen)))?;
            print_movingai(&report, json);
        }
        BenchCommand::Grid { map, start, goal, planner, json } => {
            let start = parse_cell(&start).map_err(|e| anyhow!("--start: {e}"))?;
            let goal = parse_cell(&goal).map_err(|e| anyhow!("--goal: {e}"))?;
            let bytes = std::fs::read(&map).with_context(|| format!("{}: cannot read", label(&map)))?;
            let grid = parse_grid_file(&bytes).map_err(|e| anyhow!(e.in_file(label(&map))))?;
            for (what, cell) in [("--start", start), ("--goal", goal)] {
                if !grid.contains(cell) {
                    return Err(anyhow!(
                        "{what}: cell ({}, {}) is outside the {}x{} map {}",
                        cell.row,
                        cell.col,
                        grid.rows(),
                        grid.cols(),
                        label(&map)
                    ));
                }
            }
            let report =
                run_grid_events(&grid, start, goal, &planner).map_err(|e| anyhow!("{}: {e}", label(&map)))?;
            print_grid(&report, &label(&map), json);
        }
        BenchCommand::Report { quick, json, write, no_write } => {
            run_report(quick, json, (!no_write).then_some(write))?
        }
    }
    Ok(())
}

/// Runs every workload of `bench report` (progress on stderr), prints and writes the table.
fn run_report(quick: bool, json: bool, write: Option<PathBuf>) -> anyhow::Result<()> {
    let reps = if quick { 2 } else { 5 };
    let mut rows = Vec::new();
    let step = |name: &str| eprintln!("bench report: {name}");
    step("map1000 planners");
    let map1000 = workloads::cost_map("map1000")?;
    rows.extend(workloads::graph_search(&map1000, reps)?);
    rows.push(workloads::field_dstar(&map1000, if quick { 1 } else { 3 })?);
    rows.push(workloads::dstar_lite_replan(&map1000, reps)?);
    step("matcher, localisation workload");
    rows.push(workloads::matcher_localisation(quick)?);
    step("distance transforms");
    rows.push(workloads::edt(quick)?);
    step("matcher, scan-matcher window");
    rows.push(workloads::matcher_scan_window(quick)?);
    step("default mission");
    rows.extend(workloads::mission_rows(quick)?);
    let command =
        std::iter::once("rovernav".to_string()).chain(std::env::args().skip(1)).collect::<Vec<_>>().join(" ");
    let report = report::Report { command, revision: report::git_revision(), quick, rows };
    if let Some(path) = write {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create", dir.display()))?;
        }
        std::fs::write(&path, report::markdown(&report))
            .with_context(|| format!("{}: cannot write", label(&path)))?;
        eprintln!("bench report: table written to {}", label(&path));
    }
    if json {
        println!("{}", serde_json::to_string(&report)?);
    } else {
        print!("{}", report::text(&report));
    }
    Ok(())
}

fn label(path: &Path) -> String {
    path.display().to_string()
}

fn read_text(path: &Path) -> anyhow::Result<String> {
    std::fs::read_to_string(path).with_context(|| format!("{}: cannot read", label(path)))
}

fn print_movingai(r: &MovingAiReport, json: bool) {
    if json {
        let v = serde_json::json!({
            "planner": r.planner,
            "map": r.map,
            "graph": r.graph,
            "scenarios": r.scenarios,
            "solved": r.solved,
            "mismatches": r.mismatches,
            "mean_cost_ratio": r.mean_cost_ratio,
            "mean_us_per_query": r.mean_us_per_query,
        });
        println!("{v}");
    } else {
        println!("planner           {}", r.planner);
        println!("map               {}", r.map);
        println!("graph             {}", r.graph);
        println!("scenarios         {}", r.scenarios);
        println!("solved            {}", r.solved);
        println!("mismatches        {}", r.mismatches);
        println!("mean_cost_ratio   {:.6}", r.mean_cost_ratio);
        println!("mean_us_per_query {:.1}", r.mean_us_per_query);
    }
}

fn print_grid(r: &GridReport, map: &str, json: bool) {
    if json {
        let events: Vec<_> = r
            .events
            .iter()
            .map(|e| {
                serde_json::json!({
                    "event": e.name,
                    "ms": e.ms,
                    "expansions": e.expansions,
                    "cost": e.cost,
                    "value": e.value,
                    "start": [e.start.row, e.start.col],
                })
            })
            .collect();
        let v = serde_json::json!({
            "planner": r.planner,
            "map": map,
            "graph": r.graph,
            "obstacle_cells": r.obstacle.len(),
            "events": events,
        });
        println!("{v}");
    } else {
        println!("planner {}  map {map}  graph {}", r.planner, r.graph);
        for e in &r.events {
            println!(
                "{:<10} {:9.3} ms {:9} expansions  cost {:.3}  (start {},{})",
                e.name, e.ms, e.expansions, e.cost, e.start.row, e.start.col
            );
        }
    }
}
