//! `rovernav replay LOG.mcap`: rebuilds a run's `report.json` and `traverse.png` from its
//! telemetry log alone. A log cut short (a killed run) gives a partial report up to its last
//! complete cycle, and says so on standard error.

use crate::output;
use rovernav_telemetry::read_log;
use std::path::{Path, PathBuf};

/// Options of `rovernav replay`.
#[derive(clap::Args, Debug)]
pub struct ReplayArgs {
    /// Telemetry log of a run (`telemetry.mcap` in its output folder).
    log: PathBuf,
    /// Output folder (default: `replay` beside the log).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Print report.json to standard output.
    #[arg(long)]
    json: bool,
}

/// Replays a log into an output folder.
pub fn run(args: ReplayArgs) -> anyhow::Result<()> {
    let log = read_log(&args.log)?;
    let replay = log.replay()?;
    let out_dir =
        args.out.clone().unwrap_or_else(|| args.log.parent().unwrap_or(Path::new(".")).join("replay"));
    output::write_outputs(&out_dir, &replay.report, &replay.world, &replay.trace)?;
    output::write_placement_pictures(&out_dir, &log.placements, &replay.world.rover)?;
    crate::science_cmd::write_watch_summaries(&out_dir, &log.science)?;
    let shown = args.log.display();
    if !replay.complete {
        let why = log.end.truncated.as_deref().unwrap_or("the log has no final report");
        eprintln!(
            "warning: {shown}: the run was cut off ({why}); partial report up to cycle {} (sim time {:.1} s) from {} messages",
            replay.report.cycles, replay.report.sim_time_s, log.end.messages
        );
    } else if let Some(why) = &log.end.truncated {
        eprintln!("warning: {shown}: the log's end is damaged ({why}), but it holds the whole run");
    }
    let report = &replay.report;
    if args.json {
        println!("{}", serde_json::to_string_pretty(report)?);
    } else {
        println!(
            "{}: {} ({}) · goal error {:.2} m · driven {:.1} m · hazard contacts {} · {} cycles · {:.0} s simulated · replayed from {}",
            report.mission,
            report.outcome,
            report.navigator,
            report.goal_error_m,
            report.distance_driven_m,
            report.hazard_contacts,
            report.cycles,
            report.sim_time_s,
            shown,
        );
        println!("outputs in {}", out_dir.display());
    }
    Ok(())
}
