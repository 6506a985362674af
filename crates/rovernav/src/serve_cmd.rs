//! `rovernav serve`: the operator console in the browser (issue 41), live or replaying a log.
//!
//! The first line of standard output is the console's address with its access token
//! (`http://127.0.0.1:8080/?token=...`); everything else goes to standard error. The mission runs
//! on this thread, the server on its own threads; after the mission the console keeps serving
//! (the final state, answers `mission over`) until Ctrl-C, or exits with `--exit-when-done`.

use crate::{MissionToRun, RunArgs};
use anyhow::Context;
use rovernav_console::live::{self, LiveRun};
use rovernav_console::operator::{Console, Phase};
use rovernav_console::replay::ReplayLog;
use rovernav_console::server::{AppState, Server, router};
use rovernav_console::{Hub, auth};
use std::io::Write;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

/// Options of `rovernav serve`.
#[derive(clap::Args, Debug)]
pub struct ServeArgs {
    /// Mission file (TOML); omit for the built-in default mission's world, held until the
    /// mission planner sends a plan.
    mission: Option<PathBuf>,
    /// Address to serve the console on (loopback unless told otherwise).
    #[arg(long, default_value = "127.0.0.1:8080")]
    listen: SocketAddr,
    /// Read the access token from this file (first line) instead of generating one.
    #[arg(long, value_name = "FILE")]
    token_file: Option<PathBuf>,
    /// Also serve the run over the Foxglove WebSocket protocol on this address (same token, as
    /// `?token=`).
    #[arg(long, value_name = "HOST:PORT")]
    foxglove: Option<SocketAddr>,
    /// Replay a finished run's telemetry log instead of running a mission.
    #[arg(long, value_name = "LOG.mcap", conflicts_with = "mission")]
    replay: Option<PathBuf>,
    /// Simulated seconds per wall-clock second, or `max` for as fast as possible.
    #[arg(long, value_name = "X|max", default_value = "1", value_parser = parse_speed)]
    speed: Speed,
    /// Hold a mission file's mission until the mission planner sends a plan.
    #[arg(long)]
    wait: bool,
    /// Exit once the mission has ended and its outputs are written (for scripts and tests).
    #[arg(long)]
    exit_when_done: bool,
    /// Override the mission's seed.
    #[arg(long)]
    seed: Option<u64>,
    /// Override the mission's navigator (registry name).
    #[arg(long)]
    navigator: Option<String>,
    /// Output folder (default: out/<mission name>).
    #[arg(long)]
    out: Option<PathBuf>,
}

/// `--speed`: a pace, or none.
#[derive(Clone, Copy, Debug)]
struct Speed(Option<f64>);

fn parse_speed(text: &str) -> Result<Speed, String> {
    if text.trim().eq_ignore_ascii_case("max") {
        return Ok(Speed(None));
    }
    crate::interactive::parse_speed(text).map(|x| Speed(Some(x)))
}

/// Serves the console until Ctrl-C (or the mission's end with `--exit-when-done`).
pub fn run(args: ServeArgs) -> anyhow::Result<()> {
    let token: Arc<str> = match &args.token_file {
        Some(file) => auth::read_token_file(file),
        None => auth::generate_token(),
    }
    .map_err(anyhow::Error::msg)?
    .into();
    let replay = match &args.replay {
        Some(path) => Some(Arc::new(ReplayLog::read(path).map_err(anyhow::Error::msg)?)),
        None => None,
    };
    let live = match &replay {
        Some(_) => None,
        None => Some(MissionToRun::of(&RunArgs {
            mission: args.mission.clone(),
            seed: args.seed,
            navigator: args.navigator.clone(),
            out: args.out.clone(),
            ..RunArgs::default()
        })?),
    };
    let hub = Hub::new(rovernav_console::hub::DEFAULT_QUEUE);
    let (console, link) = Console::new(if replay.is_some() { Phase::Replay } else { Phase::Waiting });
    let replay_log = replay.clone();
    let state = AppState::new(Arc::clone(&token), Arc::clone(&hub), console, replay);
    let server = Server::new().map_err(anyhow::Error::msg)?;
    let addr = server.serve(args.listen, router(state)).map_err(anyhow::Error::msg)?;
    if let Some(foxglove) = args.foxglove {
        let router = rovernav_console::foxglove::router(Arc::clone(&hub), Arc::clone(&token));
        let bound = server.serve(foxglove, router).map_err(anyhow::Error::msg)?;
        eprintln!("rovernav: Foxglove WebSocket server on ws://{bound}/?token=<the token>");
        if let Some(log) = replay_log.clone() {
            let (hub, speed) = (Arc::clone(&hub), args.speed.0);
            std::thread::spawn(move || log.play_into(&hub, speed));
        }
    }
    let mut stdout = std::io::stdout().lock();
    writeln!(stdout, "http://{addr}/?token={token}")?;
    stdout.flush()?;
    drop(stdout);
    if !addr.ip().is_loopback() {
        eprintln!(
            "rovernav: warning: the console listens on {addr}, beyond this machine; anyone with the token commands the rover"
        );
    }
    let Some(MissionToRun { mission, origin_of_navigator, out_dir }) = live else {
        let log = args.replay.as_deref().map(|p| p.display().to_string()).unwrap_or_default();
        eprintln!("rovernav: replaying {log}; Ctrl-C stops");
        serve_forever();
    };
    let hold = args.wait || args.mission.is_none();
    let pacing = args.speed.0.map_or("as fast as possible".into(), |x| format!("at {x} x real time"));
    eprintln!(
        "rovernav: mission `{}` {} {pacing}; open the address above",
        mission.name,
        if hold { "waits for a plan from the console, then runs" } else { "runs" }
    );
    std::fs::create_dir_all(&out_dir).with_context(|| format!("{}: cannot create", out_dir.display()))?;
    let config = LiveRun {
        mission,
        origin: origin_of_navigator,
        hold,
        speed: args.speed.0,
        log: out_dir.join("telemetry.mcap"),
    };
    let output = live::run(&config, &hub, link).map_err(anyhow::Error::msg)?;
    crate::output::write_run_outputs(&out_dir, &output)?;
    let r = &output.report;
    eprintln!(
        "rovernav: {}: {} ({}) · goal error {:.2} m · driven {:.1} m · {} cycles; outputs in {}",
        r.mission,
        r.outcome,
        r.message,
        r.goal_error_m,
        r.distance_driven_m,
        r.cycles,
        out_dir.display()
    );
    if args.exit_when_done {
        // Time for the clients to receive the last messages.
        std::thread::sleep(Duration::from_millis(500));
        return Ok(());
    }
    eprintln!("rovernav: the console keeps serving the finished run; Ctrl-C stops");
    serve_forever()
}

/// Blocks while the server's threads serve (Ctrl-C ends the process).
fn serve_forever() -> ! {
    loop {
        std::thread::park();
    }
}
