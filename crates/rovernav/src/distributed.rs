//! `rovernav sim`, `rovernav rover` and `rovernav send`: one mission as separate processes over
//! zenoh (cargo feature `zenoh`, off by default; without it these subcommands exit with one line
//! saying how to rebuild).
//!
//! - `rovernav sim` is the platform: it builds the mission's world, listens as the zenoh router
//!   and answers the rover's platform requests with a `PlatformServer` (the simulator and the
//!   mission's scheduled faults). When the mission ends it scores the run against truth, sends
//!   the scoring to the rover and prints a one-line summary.
//! - `rovernav rover` is the autonomy: the same components as `rovernav run`, with a
//!   `RemotePlatform` in the platform's place, stepping in lockstep with the simulator (one
//!   request, one reply). It writes the output folder (report.json and traverse.png; no
//!   telemetry.mcap yet) and prints the report, which equals `rovernav run`'s for the same
//!   mission and seed, wall-clock figures aside. It never reads simulator truth while the mission
//!   runs: truth figures, the true track and the sensed cells arrive once, in the scoring, after
//!   the mission has ended; the world it builds from the mission file gives the rover's
//!   configuration, start and goal, and its terrain is used only to draw the picture.
//! - `rovernav send "goto 12 14"` checks the line with the command language, publishes it on
//!   `/operator/command`, and prints the rover's answer from `/operator/reply` (one sender at a
//!   time: answers are not addressed).
//!
//! Topology: the simulator listens as a zenoh router, the rover and senders connect as clients
//! (so a sender reaches the rover through the simulator). Each process subscribes before it
//! announces itself, and waits for the other's announcement before the first exchange, so no
//! message is lost.

use clap::Args;
use std::path::PathBuf;

/// Where `rovernav sim` listens and the others connect by default.
const DEFAULT_ENDPOINT: &str = "tcp/127.0.0.1:7447";

/// Options of `rovernav sim`.
#[derive(Args, Debug)]
pub struct SimArgs {
    /// Mission file (TOML); omit for the built-in default mission.
    mission: Option<PathBuf>,
    /// Endpoint to listen on (`tcp/HOST:PORT`).
    #[arg(long, default_value = DEFAULT_ENDPOINT)]
    listen: String,
    /// Override the mission's seed (must match the rover's).
    #[arg(long)]
    seed: Option<u64>,
    /// Longest wait for the rover to appear or to send its next request (s).
    #[arg(long, default_value_t = 120.0)]
    timeout_s: f64,
}

/// Options of `rovernav rover`.
#[derive(Args, Debug)]
pub struct RoverArgs {
    /// Mission file (TOML); omit for the built-in default mission.
    mission: Option<PathBuf>,
    /// The simulator's endpoint (`tcp/HOST:PORT`).
    #[arg(long, default_value = DEFAULT_ENDPOINT)]
    connect: String,
    /// Override the mission's seed (must match the simulator's).
    #[arg(long)]
    seed: Option<u64>,
    /// Override the mission's navigator (registry name).
    #[arg(long)]
    navigator: Option<String>,
    /// Print report.json to standard output.
    #[arg(long)]
    json: bool,
    /// Output folder (default: out/<mission name>).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Longest wait for the simulator to appear or to answer a request (s).
    #[arg(long, default_value_t = 120.0)]
    timeout_s: f64,
}

/// Options of `rovernav send`.
#[derive(Args, Debug)]
pub struct SendArgs {
    /// One operator command line (`goto 12 14`, `status`, `mission pause`...).
    line: String,
    /// The simulator's endpoint (`tcp/HOST:PORT`).
    #[arg(long, default_value = DEFAULT_ENDPOINT)]
    connect: String,
    /// Longest wait for the rover to appear and to answer (s).
    #[arg(long, default_value_t = 20.0)]
    timeout_s: f64,
}

/// The parts of the argument checks that need no zenoh build, so a bad argument fails the same
/// way with or without the feature.
mod checks {
    use anyhow::{Context, bail};
    use rovernav_bus_zenoh::Endpoint;
    use std::time::Duration;

    /// An endpoint argument, with the option named in the error.
    pub fn endpoint(option: &str, text: &str) -> anyhow::Result<Endpoint> {
        text.parse().with_context(|| format!("--{option}"))
    }

    /// A timeout argument.
    pub fn timeout(seconds: f64) -> anyhow::Result<Duration> {
        if !(seconds.is_finite() && seconds > 0.0 && seconds < 1e6) {
            bail!("--timeout-s: expected a positive number of seconds below 1e6, got {seconds}");
        }
        Ok(Duration::from_secs_f64(seconds))
    }

    /// An operator line the command language accepts.
    pub fn command(line: &str) -> anyhow::Result<()> {
        match rovernav_executive::parse_command(line) {
            Ok(Some(_)) => Ok(()),
            Ok(None) => bail!("command `{}`: empty: give one operator command", line.escape_debug()),
            Err(e) => bail!("command `{}`: {e}", line.escape_debug()),
        }
    }
}

#[cfg(not(feature = "zenoh"))]
mod without {
    use super::{RoverArgs, SendArgs, SimArgs, checks};

    /// The one line every distributed subcommand gives in a build without zenoh.
    fn unavailable() -> anyhow::Error {
        anyhow::anyhow!("built without the `zenoh` feature: rebuild with `cargo build --features zenoh`")
    }

    /// `rovernav sim` without zenoh.
    pub fn sim(args: SimArgs) -> anyhow::Result<()> {
        checks::endpoint("listen", &args.listen)?;
        checks::timeout(args.timeout_s)?;
        Err(unavailable())
    }

    /// `rovernav rover` without zenoh.
    pub fn rover(args: RoverArgs) -> anyhow::Result<()> {
        checks::endpoint("connect", &args.connect)?;
        checks::timeout(args.timeout_s)?;
        Err(unavailable())
    }

    /// `rovernav send` without zenoh.
    pub fn send(args: SendArgs) -> anyhow::Result<()> {
        checks::command(&args.line)?;
        checks::endpoint("connect", &args.connect)?;
        checks::timeout(args.timeout_s)?;
        Err(unavailable())
    }
}

#[cfg(not(feature = "zenoh"))]
pub use without::{rover, send, sim};

#[cfg(feature = "zenoh")]
mod with {
    use super::{RoverArgs, SendArgs, SimArgs, checks};
    use anyhow::{Context, bail};
    use rovernav_bus::{SubscriptionId, Topic, TopicFilter, Transport, decode, encode};
    use rovernav_bus_zenoh::{Endpoint, Mode, ZenohConfig, ZenohTransport};
    use rovernav_executive::messages::topics;
    use rovernav_executive::remote::{
        LinkError, PLATFORM_REPLY, PLATFORM_REQUEST, PlatformLink, PlatformReply, PlatformRequest,
    };
    use rovernav_executive::{Mission, OperatorLink, Run, RunOptions, RunSettings};
    use rovernav_harness::{build_world, platform_server};
    use std::collections::VecDeque;
    use std::path::PathBuf;
    use std::sync::{Arc, Mutex, MutexGuard};
    use std::time::{Duration, Instant};

    /// The rover's last word: it has the scoring, the simulator may close.
    const PLATFORM_DONE: Topic<u64> = Topic::new("/platform/done");
    /// How long a paused mission waits for an operator line per cycle (wall clock).
    const WAIT_FOR_INPUT: Duration = Duration::from_millis(100);
    /// How long the simulator waits for the rover's last word before closing anyway.
    const DONE_WAIT: Duration = Duration::from_secs(10);

    /// A mission file (or the default mission) with the seed and navigator overrides.
    fn load(
        mission: &Option<PathBuf>,
        seed: Option<u64>,
        navigator: Option<&String>,
    ) -> anyhow::Result<(Mission, String)> {
        let (mut m, origin) = match mission {
            Some(path) => (Mission::from_file(path)?, path.display().to_string()),
            None => (Mission::default_mission(), "built-in default mission".to_string()),
        };
        if let Some(seed) = seed {
            m.seed = seed;
        }
        if let Some(nav) = navigator {
            m.navigator = nav.clone();
        }
        Ok((m, origin))
    }

    /// A client session to `endpoint`, retried until `timeout` (the simulator may start later).
    fn connect(endpoint: &Endpoint, timeout: Duration) -> anyhow::Result<ZenohTransport> {
        let config = ZenohConfig::connect(endpoint.clone()).with_mode(Mode::Client);
        let start = Instant::now();
        loop {
            match ZenohTransport::open(&config) {
                Ok(t) => return Ok(t),
                Err(e) if start.elapsed() >= timeout => {
                    return Err(e).with_context(|| format!("no simulator at {endpoint}"));
                }
                Err(_) => std::thread::sleep(Duration::from_millis(100)),
            }
        }
    }

    /// A session shared by the platform link and the operator link of the rover process.
    type Shared = Arc<Mutex<ZenohTransport>>;

    fn lock(t: &Shared) -> MutexGuard<'_, ZenohTransport> {
        // A panic elsewhere cannot leave the transport half-updated: recover the guard.
        t.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// The platform link over zenoh: publish a request, block for its reply.
    struct ZenohPlatformLink {
        transport: Shared,
        replies: SubscriptionId,
        timeout: Duration,
        early: VecDeque<PlatformReply>,
    }

    impl PlatformLink for ZenohPlatformLink {
        fn exchange(&mut self, request: &PlatformRequest) -> Result<PlatformReply, LinkError> {
            let mut t = lock(&self.transport);
            t.publish(PLATFORM_REQUEST.name(), &encode(&PLATFORM_REQUEST, request)?)?;
            loop {
                if let Some(reply) = self.early.pop_front() {
                    if reply.seq == request.seq {
                        return Ok(reply);
                    }
                    return Err(LinkError(format!(
                        "the simulator answered request {} while request {} was due",
                        reply.seq, request.seq
                    )));
                }
                for sample in t.wait_for(self.replies, self.timeout).map_err(|e| {
                    LinkError(format!("no answer from the simulator to request {}: {e}", request.seq))
                })? {
                    self.early.push_back(decode(&PLATFORM_REPLY, &sample.payload)?);
                }
            }
        }
    }

    /// Operator lines from `/operator/command`, answers to `/operator/reply`.
    struct ZenohOperator {
        transport: Shared,
        commands: SubscriptionId,
        pending: VecDeque<String>,
    }

    impl ZenohOperator {
        fn absorb(&mut self, samples: Vec<rovernav_bus::Sample>) {
            for sample in samples {
                match decode(&topics::OPERATOR_COMMAND, &sample.payload) {
                    Ok(line) => self.pending.push_back(line),
                    // A stranger's message must not stop the mission: say so and go on.
                    Err(e) => eprintln!("rover: ignored an operator message: {e}"),
                }
            }
        }
    }

    impl OperatorLink for ZenohOperator {
        /// One line per cycle, as `rovernav run --interactive` takes them.
        fn poll(&mut self, _cycles: u64, waiting: bool) -> Vec<String> {
            if self.pending.is_empty() {
                let transport = Arc::clone(&self.transport);
                let mut t = lock(&transport);
                let samples = if waiting {
                    t.wait_for(self.commands, WAIT_FOR_INPUT).unwrap_or_default()
                } else {
                    t.receive(self.commands).unwrap_or_default()
                };
                drop(t);
                self.absorb(samples);
            }
            self.pending.pop_front().into_iter().collect()
        }

        fn reply(&mut self, text: &str) {
            let sent = encode(&topics::OPERATOR_REPLY, &text.to_string())
                .and_then(|payload| lock(&self.transport).publish(topics::OPERATOR_REPLY.name(), &payload));
            if let Err(e) = sent {
                eprintln!("rover: cannot send an operator answer: {e}");
            }
        }
    }

    /// `rovernav sim`: the platform process.
    pub fn sim(args: SimArgs) -> anyhow::Result<()> {
        let endpoint = checks::endpoint("listen", &args.listen)?;
        let timeout = checks::timeout(args.timeout_s)?;
        let (mission, origin) = load(&args.mission, args.seed, None)?;
        let world = build_world(&mission, &origin)?;
        let faults = RunOptions::of(&mission, &world).faults;
        let mut server = platform_server(world, &mission.name, mission.seed, faults)?;

        let mut t = ZenohTransport::open(&ZenohConfig::listen(endpoint.clone()).with_mode(Mode::Router))?;
        let requests = t.subscribe(TopicFilter::Exact(PLATFORM_REQUEST.name().into()))?;
        let done = t.subscribe(TopicFilter::Exact(PLATFORM_DONE.name().into()))?;
        t.announce("/sim")?;
        eprintln!(
            "sim: mission `{}` (seed {}) listening on {endpoint}; waiting for the rover",
            mission.name, mission.seed
        );
        t.wait_for_announcement("/rover", timeout).context("waiting for `rovernav rover`")?;
        let mut scoring = None;
        while scoring.is_none() {
            let samples = t
                .wait_for(requests, timeout)
                .with_context(|| format!("the rover went quiet after {} commands", server.cycles()))?;
            for sample in samples {
                let request = decode(&PLATFORM_REQUEST, &sample.payload)?;
                let reply = server.handle(&request);
                t.publish(PLATFORM_REPLY.name(), &encode(&PLATFORM_REPLY, &reply)?)?;
                if reply.scoring.is_some() {
                    scoring = reply.scoring;
                }
            }
        }
        // Closing before the rover has its scoring could cut the last reply off.
        if t.wait_for(done, DONE_WAIT).is_err() {
            eprintln!("sim: the rover did not confirm the scoring within {} s", DONE_WAIT.as_secs());
        }
        let s = scoring.expect("the loop ends with a scoring");
        println!(
            "sim: {} commands · goal error {:.2} m · driven {:.1} m · hazard contacts {} · localization error {:.2} m · {:.0} s simulated",
            s.cycles,
            s.goal_error_m,
            s.distance_driven_m,
            s.hazard_contacts,
            s.localization_error_m,
            s.sim_time_s
        );
        Ok(())
    }

    /// `rovernav rover`: the autonomy process.
    pub fn rover(args: RoverArgs) -> anyhow::Result<()> {
        let endpoint = checks::endpoint("connect", &args.connect)?;
        let timeout = checks::timeout(args.timeout_s)?;
        let (mission, origin) = load(&args.mission, args.seed, args.navigator.as_ref())?;
        let origin_of_navigator =
            if args.navigator.is_some() { "--navigator".to_string() } else { origin.clone() };
        let out_dir = args.out.clone().unwrap_or_else(|| PathBuf::from("out").join(&mission.name));
        let world = build_world(&mission, &origin)?;
        let mut options = RunOptions::of(&mission, &world);
        // Faults are injected on the simulator's side only.
        options.faults.clear();

        let mut t = connect(&endpoint, timeout)?;
        let replies = t.subscribe(TopicFilter::Exact(PLATFORM_REPLY.name().into()))?;
        let commands = t.subscribe(TopicFilter::Exact(topics::OPERATOR_COMMAND.name().into()))?;
        t.announce("/rover")?;
        t.wait_for_announcement("/sim", timeout).context("waiting for `rovernav sim`")?;
        eprintln!(
            "rover: mission `{}` (seed {}) linked to the simulator at {endpoint}",
            mission.name, mission.seed
        );
        let shared: Shared = Arc::new(Mutex::new(t));
        let link =
            ZenohPlatformLink { transport: Arc::clone(&shared), replies, timeout, early: VecDeque::new() };
        let mut operator =
            ZenohOperator { transport: Arc::clone(&shared), commands, pending: VecDeque::new() };
        // The rover process logs its own bus (no truth lives here) and the final report.
        let mut log = crate::output::RunLog::open(&out_dir)?;
        let output = Run::new(world, RunSettings::of(&mission))
            .options(options)
            .origin(&origin_of_navigator)
            .remote(Box::new(link))
            .operator(&mut operator)
            .observer(&mut log.recorder)
            .measure_peak_rss()
            .execute();
        log.close(output.is_ok())?;
        let output = output?;
        lock(&shared).publish(PLATFORM_DONE.name(), &encode(&PLATFORM_DONE, &output.report.cycles)?)?;
        crate::output::write_run_outputs(&out_dir, &output)?;
        let r = &output.report;
        if args.json {
            println!("{}", serde_json::to_string_pretty(r)?);
        } else {
            println!(
                "{}: {} ({}) · goal error {:.2} m · driven {:.1} m (optimal {}) · hazard contacts {} · {} cycles · {:.0} s simulated · {:.1} s wall",
                r.mission,
                r.outcome,
                r.navigator,
                r.goal_error_m,
                r.distance_driven_m,
                r.optimal_length_m.map_or("n/a".to_string(), |v| format!("{v:.1} m")),
                r.hazard_contacts,
                r.cycles,
                r.sim_time_s,
                r.wall_time_s,
            );
            println!("outputs in {}", out_dir.display());
        }
        Ok(())
    }

    /// `rovernav send`: one operator line to the running rover, and its answer.
    pub fn send(args: SendArgs) -> anyhow::Result<()> {
        checks::command(&args.line)?;
        let endpoint = checks::endpoint("connect", &args.connect)?;
        let timeout = checks::timeout(args.timeout_s)?;
        let mut t = connect(&endpoint, timeout)?;
        // Subscribed before the command goes out, so the answer cannot pass us by.
        let answers = t.subscribe(TopicFilter::Exact(topics::OPERATOR_REPLY.name().into()))?;
        t.wait_for_announcement("/rover", timeout).context("waiting for `rovernav rover`")?;
        t.publish(topics::OPERATOR_COMMAND.name(), &encode(&topics::OPERATOR_COMMAND, &args.line)?)?;
        let samples = t.wait_for(answers, timeout).context("waiting for the rover's answer")?;
        let Some(first) = samples.first() else { bail!("the rover sent no answer") };
        let answer = decode(&topics::OPERATOR_REPLY, &first.payload)?;
        println!("{answer}");
        if answer.starts_with("error:") {
            bail!("the rover refused `{}`", args.line.escape_debug());
        }
        Ok(())
    }
}

#[cfg(feature = "zenoh")]
pub use with::{rover, send, sim};
