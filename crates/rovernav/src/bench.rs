//! `rovernav bench`: planner benchmarks on the MovingAI scenarios and on cost maps. A thin
//! command-line layer (file reading, argument parsing, printing) over
//! [`rovernav_planning::benchmark`], where the logic lives and is tested.

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
