//! `rovernav graph`: the component graph a mission's run steps, as a text table, Graphviz dot
//! text or JSON (the graph is [`rovernav_executive::graph`]'s, read back from an assembled run).

use rovernav_executive::remote::NoLink;
use rovernav_executive::{Mission, Run};
use rovernav_harness::JudgedRun;
use std::path::PathBuf;

/// Options of `rovernav graph`.
#[derive(clap::Args, Debug)]
pub struct GraphArgs {
    /// Mission file (TOML); omit for the built-in default mission.
    mission: Option<PathBuf>,
    /// The rover process's graph of a two-process run (its platform a stand-in across a link).
    #[arg(long)]
    remote: bool,
    /// Graphviz dot text (`rovernav graph --dot | dot -Tsvg > graph.svg`).
    #[arg(long, conflicts_with = "json")]
    dot: bool,
    /// JSON.
    #[arg(long)]
    json: bool,
}

/// Prints the graph.
pub fn run(args: GraphArgs) -> anyhow::Result<()> {
    let (mission, origin) = match &args.mission {
        Some(path) => (Mission::from_file(path)?, path.display().to_string()),
        None => (Mission::default_mission(), "built-in default mission".to_string()),
    };
    let mut run = Run::mission(&mission, &origin)?;
    if args.remote {
        run = run.remote(Box::new(NoLink));
    }
    let graph = run.graph()?;
    if args.dot {
        print!("{}", graph.dot());
    } else if args.json {
        println!("{}", serde_json::to_string_pretty(&graph)?);
    } else {
        print!("{}", graph.table());
    }
    Ok(())
}
