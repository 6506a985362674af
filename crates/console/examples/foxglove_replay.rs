//! Serves a finished run's telemetry log over the Foxglove WebSocket protocol, replayed in log
//! order once a client has connected, over and over until killed (or once with `--once`):
//!
//! `cargo run --release -p rovernav-console --example foxglove_replay -- LOG.mcap
//! [--listen 127.0.0.1:8765] [--token TOKEN] [--rate MESSAGES_PER_S] [--once]`
//!
//! The first line of standard output is the URL to connect to (`ws://ADDR/?token=TOKEN`). It
//! is what `tests/foxglove/ws_client.py` runs against; `rovernav serve --foxglove` serves a live
//! run through the same router.

use rovernav_console::Hub;
use rovernav_console::foxglove::router;
use rovernav_console::server::Server;
use std::io::Write;
use std::net::SocketAddr;
use std::sync::Arc;
use std::time::Duration;

struct Args {
    log: String,
    listen: SocketAddr,
    token: String,
    rate: f64,
    once: bool,
}

fn args() -> Result<Args, String> {
    let mut it = std::env::args().skip(1);
    let mut args = Args {
        log: String::new(),
        listen: "127.0.0.1:0".parse().map_err(|e| format!("{e}"))?,
        token: rovernav_console::auth::generate_token()?,
        rate: 2000.0,
        once: false,
    };
    while let Some(a) = it.next() {
        let mut value = |name: &str| it.next().ok_or(format!("{name} needs a value"));
        match a.as_str() {
            "--listen" => args.listen = value("--listen")?.parse().map_err(|e| format!("--listen: {e}"))?,
            "--token" => args.token = value("--token")?,
            "--rate" => {
                args.rate = value("--rate")?.parse().map_err(|e| format!("--rate: {e}"))?;
                if !(args.rate.is_finite() && args.rate > 0.0) {
                    return Err("--rate: a positive number of messages per second".into());
                }
            }
            "--once" => args.once = true,
            _ if args.log.is_empty() && !a.starts_with('-') => args.log = a,
            _ => return Err(format!("unknown argument `{a}`")),
        }
    }
    if args.log.is_empty() {
        return Err("usage: foxglove_replay LOG.mcap [--listen ADDR] [--token T] [--rate N] [--once]".into());
    }
    Ok(args)
}

fn main() {
    if let Err(e) = run() {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), String> {
    let args = args()?;
    let bytes = std::fs::read(&args.log).map_err(|e| format!("{}: {e}", args.log))?;
    let messages: Vec<_> = rovernav_telemetry::mcap::MessageStream::new(&bytes)
        .map_err(|e| format!("{}: {e}", args.log))?
        .collect::<Result<_, _>>()
        .map_err(|e| format!("{}: {e}", args.log))?;
    let hub = Hub::new(1 << 16);
    for m in &messages {
        let schema = m.channel.schema.as_ref();
        let name = schema.map_or("json", |s| s.name.as_str());
        let value = schema.and_then(|s| serde_json::from_slice(&s.data).ok()).unwrap_or_default();
        hub.declare(&m.channel.topic, name, &value);
    }
    let server = Server::new()?;
    let addr = server.serve(args.listen, router(Arc::clone(&hub), Arc::from(args.token.as_str())))?;
    println!("ws://{addr}/?token={}", args.token);
    std::io::stdout().flush().map_err(|e| e.to_string())?;
    let pause = Duration::from_secs_f64(1.0 / args.rate);
    loop {
        while hub.watchers() == 0 {
            std::thread::sleep(Duration::from_millis(20));
        }
        for m in &messages {
            hub.publish(&m.channel.topic, m.log_time, &m.data);
            std::thread::sleep(pause);
        }
        if args.once {
            return Ok(());
        }
    }
}
