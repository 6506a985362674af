//! A relay process: republishes every sample of one topic on another, over zenoh.
//!
//! ```text
//! cargo run -p rovernav-bus-zenoh --features zenoh --example zenoh_echo -- \
//!     --connect tcp/127.0.0.1:7447 --mode client --from /chain/a --to /chain/b --name /echo_1
//! ```
//!
//! It subscribes to `--from` and `--quit` (default `/echo/quit`), waits until some other process
//! subscribes to `--to`, announces itself as `--name`, then relays until a sample arrives on the
//! quit topic (exit 0) or nothing arrives for `--idle-s` seconds (exit 1), so it never outlives
//! the run that started it. The three-process test in `tests/loopback.rs` chains two of them.

use rovernav_bus::{TopicFilter, Transport};
use rovernav_bus_zenoh::{Endpoint, Mode, ZenohConfig, ZenohTransport};
use std::process::ExitCode;
use std::time::Duration;

/// Parsed command line.
struct Args {
    config: ZenohConfig,
    from: String,
    to: String,
    quit: String,
    name: String,
    idle: Duration,
}

const USAGE: &str = "usage: zenoh_echo [--mode peer|client|router] [--listen tcp/HOST:PORT]... \
[--connect tcp/HOST:PORT]... --from TOPIC --to TOPIC --name NODE [--quit TOPIC] [--idle-s SECONDS]";

fn parse_args(mut args: impl Iterator<Item = String>) -> Result<Args, String> {
    let mut config = ZenohConfig::default();
    let (mut from, mut to, mut name) = (None, None, None);
    let mut quit = "/echo/quit".to_string();
    let mut idle = Duration::from_secs(20);
    while let Some(flag) = args.next() {
        let value = args.next().ok_or_else(|| format!("`{flag}` needs a value; {USAGE}"))?;
        match flag.as_str() {
            "--mode" => config.mode = value.parse::<Mode>().map_err(|e| e.to_string())?,
            "--listen" => config.listen.push(value.parse::<Endpoint>().map_err(|e| e.to_string())?),
            "--connect" => config.connect.push(value.parse::<Endpoint>().map_err(|e| e.to_string())?),
            "--from" => from = Some(value),
            "--to" => to = Some(value),
            "--name" => name = Some(value),
            "--quit" => quit = value,
            "--idle-s" => {
                let seconds: f64 = value.parse().map_err(|_| format!("`--idle-s {value}`: not a number"))?;
                idle = Duration::try_from_secs_f64(seconds)
                    .map_err(|_| format!("`--idle-s {value}`: not a duration in seconds"))?;
            }
            other => return Err(format!("unknown argument `{other}`; {USAGE}")),
        }
    }
    let missing = |what: &str| format!("missing `{what}`; {USAGE}");
    Ok(Args {
        config,
        from: from.ok_or_else(|| missing("--from"))?,
        to: to.ok_or_else(|| missing("--to"))?,
        name: name.ok_or_else(|| missing("--name"))?,
        quit,
        idle,
    })
}

fn run(args: Args) -> Result<(), String> {
    let mut transport = ZenohTransport::open(&args.config).map_err(|e| e.to_string())?;
    // One subscription for both topics, so one blocking wait serves the relay and the quit signal.
    let all = transport.subscribe(TopicFilter::All).map_err(|e| e.to_string())?;
    transport.wait_for_subscriber(&args.to, Duration::from_secs(10)).map_err(|e| e.to_string())?;
    transport.announce(&args.name).map_err(|e| e.to_string())?;
    loop {
        for sample in transport.wait_for(all, args.idle).map_err(|e| e.to_string())? {
            if sample.topic == args.quit {
                return Ok(());
            }
            if sample.topic == args.from {
                transport.publish(&args.to, &sample.payload).map_err(|e| e.to_string())?;
            }
        }
    }
}

fn main() -> ExitCode {
    match parse_args(std::env::args().skip(1)).and_then(run) {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("zenoh_echo: {message}");
            ExitCode::FAILURE
        }
    }
}
