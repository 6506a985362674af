//! `rovernav`: run autonomous rover traverses, benchmarks and evaluations from the command line.

mod bench;
mod campaign;
mod distributed;
mod eval_autoplace;
mod eval_descent;
mod eval_horizon;
mod eval_lander;
mod eval_localization;
mod eval_orbital;
mod eval_science;
mod eval_stereo;
mod eval_terrain;
mod eval_vtt;
mod graph_cmd;
mod interactive;
mod output;
mod progress;
mod render_cmd;
mod replay;
mod science_cmd;
mod serve_cmd;
mod stereo_cmd;

use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use rovernav_executive::{Mission, Run};
use rovernav_harness::JudgedRun;
use std::path::PathBuf;
use std::process::ExitCode;

/// Autonomous navigation for planetary rovers.
#[derive(Parser, Debug)]
#[command(name = "rovernav", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Run a mission (the built-in default mission when no file is given).
    Run(RunArgs),
    /// Rebuild a run's report.json and traverse.png from its telemetry log alone.
    Replay(replay::ReplayArgs),
    /// The operator console in the browser: run a mission (or replay a log) and serve it live.
    Serve(serve_cmd::ServeArgs),
    /// Planner benchmarks on MovingAI maps and PGM cost maps.
    #[command(subcommand)]
    Bench(bench::BenchCommand),
    /// Evaluations against simulator truth.
    #[command(subcommand)]
    Eval(EvalCommand),
    /// The registry: navigators (global planners, `[navigator_params]`) and localisers (`[localizer_params]`).
    Navigators(NavigatorsArgs),
    /// Campaigns: every navigator on the same generated terrains, with a results table and plots.
    Campaign(campaign::CampaignArgs),
    /// The component graph a mission's run steps: components, rates, topics, step order (--dot, --json).
    Graph(graph_cmd::GraphArgs),
    /// The simulator as its own process, serving a rover over zenoh (feature `zenoh`).
    Sim(distributed::SimArgs),
    /// The autonomy as its own process, driving a simulator over zenoh (feature `zenoh`).
    Rover(distributed::RoverArgs),
    /// Send one operator command to a running `rovernav rover` over zenoh (feature `zenoh`).
    Send(distributed::SendArgs),
    /// Correlate a rectified stereo pair of image files; score it against a true disparity.
    Stereo(stereo_cmd::StereoArgs),
    /// Write what one of the rover's cameras sees of the mission's world (DIR/NAME.png).
    Render(render_cmd::RenderArgs),
    /// Onboard science (paper 003 section 5): sky masks, cloud and dust-devil detection on image files.
    #[command(subcommand)]
    Science(science_cmd::ScienceCommand),
}

#[derive(Subcommand, Debug)]
enum EvalCommand {
    /// Terrain assessment: hazard recall, false hazards and elevation error on the default yard.
    Terrain(eval_terrain::EvalTerrainArgs),
    /// Localisation: branch-and-bound exactness, match accuracy and closed-loop drift.
    Localization(eval_localization::EvalLocalizationArgs),
    /// The sensing-horizon reference: the path ratio of an ideal rover that knows only what lies within its sensing range.
    Horizon(eval_horizon::EvalHorizonArgs),
    /// Stereo: correlated range against the true range on rendered Mars-yard pairs.
    Stereo(eval_stereo::EvalStereoArgs),
    /// Onboard science: cloud or dust-devil detection on rendered labelled sets.
    Science(eval_science::EvalScienceArgs),
    /// Visual target tracking: approaches to a designated rock with and without VTT.
    Vtt(eval_vtt::EvalVttArgs),
    /// AutoPlace: instrument placements on generated scenes, scored against the truth.
    Autoplace(eval_autoplace::EvalAutoplaceArgs),
    /// Rover detection in lander images: downrange and cross-range errors at 2-10 m.
    Lander(eval_lander::EvalLanderArgs),
    /// Orbital-map localisation: the mast panorama's map matched against the Gale DEM at an orbital resolution.
    Orbital(eval_orbital::EvalOrbitalArgs),
    /// Descent imagery: elevations from consecutive descent images against the paper's predicted precision.
    Descent(eval_descent::EvalDescentArgs),
}

/// Options of `rovernav navigators`.
#[derive(clap::Args, Debug)]
struct NavigatorsArgs {
    /// Only this navigator or localiser (registry name or alias).
    name: Option<String>,
}

/// Options of `rovernav run`.
#[derive(clap::Args, Debug, Default)]
struct RunArgs {
    /// Mission file (TOML); omit for the built-in default mission.
    mission: Option<PathBuf>,
    /// Override the mission's seed.
    #[arg(long)]
    seed: Option<u64>,
    /// Override the mission's navigator (registry name).
    #[arg(long)]
    navigator: Option<String>,
    /// Override the navigator's global planner (`rovernav navigators` lists each one's).
    #[arg(long)]
    global_planner: Option<String>,
    /// Override the mission's localiser (registry name: dead-reckoning, ekf, ekf-ml, ...).
    #[arg(long)]
    localizer: Option<String>,
    /// Set a localiser parameter, NAME=VALUE (repeatable; over the mission's
    /// `[localizer_params]`).
    #[arg(long = "localizer-param", value_name = "NAME=VALUE")]
    localizer_params: Vec<String>,
    /// Set a navigator parameter, NAME=VALUE (repeatable; over the mission's
    /// `[navigator_params]`; `rovernav navigators` lists them).
    #[arg(long = "param", value_name = "NAME=VALUE")]
    params: Vec<String>,
    /// Print report.json to standard output.
    #[arg(long)]
    json: bool,
    /// Output folder (default: out/<mission name>).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Read operator commands (`help` lists them) from standard input while the mission runs;
    /// the mission starts at once (`mission pause` holds it) and answers go to standard output.
    #[arg(long)]
    interactive: bool,
    /// With --interactive: pace the simulation against the wall clock, X simulated seconds per
    /// second (default: as fast as possible).
    #[arg(long, value_name = "X", requires = "interactive", value_parser = interactive::parse_speed)]
    speed: Option<f64>,
    /// With --interactive: run in real time (--speed 1).
    #[arg(long, requires = "interactive", conflicts_with = "speed")]
    realtime: bool,
}

/// The mission a `rovernav run` names, with its command-line overrides applied.
struct MissionToRun {
    mission: Mission,
    /// Where the navigator's name came from, for error messages.
    origin_of_navigator: String,
    out_dir: PathBuf,
}

impl MissionToRun {
    fn of(args: &RunArgs) -> anyhow::Result<Self> {
        let (mut mission, origin) = match &args.mission {
            Some(path) => (Mission::from_file(path)?, path.display().to_string()),
            None => (Mission::default_mission(), "built-in default mission".to_string()),
        };
        let mut origin_of_navigator = origin.clone();
        if let Some(seed) = args.seed {
            mission.seed = seed;
        }
        if let Some(nav) = &args.navigator {
            if *nav != mission.navigator {
                // The mission's parameters belong to the navigator it names.
                mission.navigator_params.clear();
            }
            mission.navigator = nav.clone();
            mission.global_planner = None;
            origin_of_navigator = "--navigator".into();
        }
        if let Some(planner) = &args.global_planner {
            mission.global_planner = Some(planner.clone());
        }
        let registry = rovernav_navigation::registry();
        if let Err(e) = registry.navigator(&mission.navigator, mission.global_planner.as_deref())
            && e.is_about_global_planner()
        {
            anyhow::bail!("--global-planner: {e}");
        }
        for param in &args.params {
            let (name, value) = parse_param(param)?;
            mission.navigator_params.insert(name, value);
        }
        if let Err(e) =
            rovernav_navigation::check_params(&mission.navigator_spec(), &mission.navigator_params)
        {
            anyhow::bail!("--param: {e}");
        }
        if let Some(name) = &args.localizer {
            if *name != mission.localizer {
                // The mission's parameters belong to the localiser it names.
                mission.localizer_params.clear();
            }
            if let Err(e) = registry.localizer(name, &Default::default()) {
                anyhow::bail!("--localizer: {e}");
            }
            mission.localizer = name.clone();
        }
        for param in &args.localizer_params {
            let (name, value) = parse_param(param)?;
            mission.localizer_params.insert(name, value);
        }
        if let Err(e) = registry.check_localizer(&mission.localizer, &mission.localizer_params) {
            anyhow::bail!("--localizer-param: {e}");
        }
        let out_dir = args.out.clone().unwrap_or_else(|| PathBuf::from("out").join(&mission.name));
        Ok(Self { mission, origin_of_navigator, out_dir })
    }
}

fn main() -> ExitCode {
    // A reader that closes the pipe early (`rovernav run | head -1`) ends the output, as it does
    // for any command-line tool, instead of a panic in `println!`. The run's files are written
    // before anything is printed.
    #[cfg(unix)]
    // SAFETY: sets the default disposition of one signal before any other thread exists.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = Cli::parse();
    let result = match cli.command {
        None => run(RunArgs::default()),
        Some(Command::Run(args)) if args.interactive => interactive::run(args),
        Some(Command::Run(args)) => run(args),
        Some(Command::Replay(args)) => replay::run(args),
        Some(Command::Serve(args)) => serve_cmd::run(args),
        Some(Command::Bench(cmd)) => bench::run(cmd),
        Some(Command::Eval(EvalCommand::Terrain(args))) => eval_terrain::run(args),
        Some(Command::Eval(EvalCommand::Localization(args))) => eval_localization::run(args),
        Some(Command::Eval(EvalCommand::Horizon(args))) => eval_horizon::run(args),
        Some(Command::Eval(EvalCommand::Stereo(args))) => eval_stereo::run(args),
        Some(Command::Eval(EvalCommand::Science(args))) => eval_science::run(args),
        Some(Command::Eval(EvalCommand::Vtt(args))) => eval_vtt::run(args),
        Some(Command::Eval(EvalCommand::Autoplace(args))) => eval_autoplace::run(args),
        Some(Command::Eval(EvalCommand::Lander(args))) => eval_lander::run(args),
        Some(Command::Eval(EvalCommand::Orbital(args))) => eval_orbital::run(args),
        Some(Command::Eval(EvalCommand::Descent(args))) => eval_descent::run(args),
        Some(Command::Navigators(args)) => navigators(args),
        Some(Command::Graph(args)) => graph_cmd::run(args),
        Some(Command::Campaign(args)) => campaign::run(args),
        Some(Command::Sim(args)) => distributed::sim(args),
        Some(Command::Rover(args)) => distributed::rover(args),
        Some(Command::Send(args)) => distributed::send(args),
        Some(Command::Stereo(args)) => stereo_cmd::run(args),
        Some(Command::Render(args)) => render_cmd::run(args),
        Some(Command::Science(cmd)) => science_cmd::run(cmd),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", format!("{e:#}").replace('\n', " "));
            ExitCode::FAILURE
        }
    }
}

fn navigators(args: NavigatorsArgs) -> anyhow::Result<()> {
    let registry = rovernav_navigation::registry();
    let print_params = |params: Vec<rovernav_navigation::ParamInfo>| {
        for p in params {
            println!("  {} = {} ({}): {}", p.name, p.default, p.unit, p.doc);
        }
    };
    let navigator = args.name.as_deref().map(|name| registry.navigator(name, None));
    let localizer = args.name.as_deref().map(|name| registry.localizer(name, &Default::default()));
    if let (Some(Err(e)), Some(Err(_))) = (&navigator, &localizer) {
        anyhow::bail!("{e}; localizers: {}", registry.localizer_names().join(", "));
    }
    for entry in registry.navigators() {
        if navigator.as_ref().is_some_and(|c| c.as_ref().map_or(true, |c| c.entry.name != entry.name)) {
            continue;
        }
        println!("{}: {}", entry.name, entry.doc);
        if !entry.global_planners.is_empty() {
            let variants: Vec<String> = entry
                .global_planners
                .iter()
                .map(|v| format!("{} (`{}`)", v.global_planner, v.label))
                .collect();
            println!("  global_planner: {}", variants.join(", "));
        }
        print_params((entry.params)());
    }
    for entry in registry.localizers() {
        if localizer.as_ref().is_some_and(|c| c.as_ref().map_or(true, |c| c.entry.name != entry.name)) {
            continue;
        }
        println!("localizer {}: {}", entry.name, entry.doc);
        for alias in registry.localizer_aliases().iter().filter(|a| a.localizer == entry.name) {
            let set: Vec<String> = alias.params.iter().map(|(k, v)| format!("{k} = {v}")).collect();
            println!("  alias `{}`: {}", alias.name, set.join(", "));
        }
        print_params((entry.params)());
    }
    Ok(())
}

fn run(args: RunArgs) -> anyhow::Result<()> {
    let MissionToRun { mission, origin_of_navigator, out_dir } = MissionToRun::of(&args)?;

    let bar = ProgressBar::new(1000);
    bar.set_style(
        ProgressStyle::with_template("{spinner} {msg} [{bar:30}] {percent}% of time budget")
            .expect("static template")
            .progress_chars("=> "),
    );
    bar.set_message(format!("{} / {}", mission.name, mission.navigator));
    let mut plain = progress::PlainProgress::for_stderr();
    let mut eta = progress::Eta::default();
    let mut on_progress = |p: &rovernav_executive::Progress| {
        bar.set_position((p.time_fraction * 1000.0) as u64);
        let line = progress::long_run_line(p, eta.update(p.route_to_go_m, p.sim_time_s));
        bar.set_message(line.clone());
        plain.tick(|| {
            format!("{}: {line} · {:.0} % of the time budget", mission.name, 100.0 * p.time_fraction)
        });
    };
    // The world is built before telemetry.mcap is created, so a mission that cannot be built
    // leaves no log; every topic of the run goes to the log, finished even when the run fails.
    let run = Run::mission(&mission, &origin_of_navigator)
        .inspect_err(|_| bar.finish_and_clear())?
        .measure_peak_rss();
    let mut log = output::RunLog::open(&out_dir)?;
    let output = run.progress(&mut on_progress).observer(&mut log.recorder).execute();
    bar.finish_and_clear();
    log.close(output.is_ok())?;
    let output = output?;
    output::write_run_outputs(&out_dir, &output)?;
    if output.report.tasks.iter().any(|t| t.placement.is_some()) {
        let placements = rovernav_telemetry::read_log(&out_dir.join("telemetry.mcap"))?.placements;
        output::write_placement_pictures(&out_dir, &placements, &output.world.rover)?;
    }
    let summaries: Vec<_> = output
        .report
        .tasks
        .iter()
        .filter_map(|t| rovernav_executive::deliberative::WatchSummary::from_message(&t.message))
        .collect();
    science_cmd::write_watch_summaries(&out_dir, &summaries)?;
    let report = &output.report;
    if args.json {
        println!("{}", serde_json::to_string_pretty(report)?);
    } else {
        println!(
            "{}: {} ({}; {}, {}) · goal error {:.2} m · driven {:.1} m (optimal {}) · hazard contacts {} · {} cycles · {:.0} s simulated · {:.1} s wall",
            report.mission,
            report.outcome,
            report.message,
            report.navigator,
            report.localizer,
            report.goal_error_m,
            report.distance_driven_m,
            report.optimal_length_m.map_or("n/a".to_string(), |v| format!("{v:.1} m")),
            report.hazard_contacts,
            report.cycles,
            report.sim_time_s,
            report.wall_time_s,
        );
        println!("outputs in {}", out_dir.display());
    }
    Ok(())
}

/// One `--param NAME=VALUE` option, its name trimmed.
pub(crate) fn parse_param(param: &str) -> anyhow::Result<(String, f64)> {
    let Some((name, value)) = param.split_once('=') else {
        anyhow::bail!("--param `{param}`: expected NAME=VALUE");
    };
    let value: f64 =
        value.trim().parse().map_err(|_| anyhow::anyhow!("--param `{param}`: the value is not a number"))?;
    Ok((name.trim().to_string(), value))
}
