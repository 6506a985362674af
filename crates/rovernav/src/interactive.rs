//! `rovernav run --interactive`: operator commands from standard input while the mission runs.
//!
//! A reader thread feeds standard-input lines into a channel that the run polls once per cycle,
//! taking one line a cycle; each line goes to the deliberative layer on the `/operator/command` topic and its answer comes
//! back on `/operator/reply`, printed on standard output (errors name the wrong token). The
//! mission starts at once, which suits scripts (`printf 'goto 8 3\n' | rovernav run
//! --interactive`); `mission pause` holds it and `mission start` resumes. While the mission
//! waits for the operator the run waits for input in wall-clock time, so a paused rover does not
//! burn through its simulated time budget; when input ends, a running mission carries on and a
//! waiting one is aborted. Banner and progress go to standard error.
//!
//! The simulation runs as fast as it can unless `--speed X` (X simulated seconds per wall-clock
//! second) or `--realtime` (`--speed 1`) paces it: after each executed command the run sleeps
//! until the wall clock has caught up with simulated time, so a `drive 1` answers when the drive
//! would have ended. Every direct motion is answered when it has run (completed, or the guard
//! that stopped it and how far it went), and lines typed after the end are answered
//! `mission over: <outcome>` before the run exits.

use crate::RunArgs;
use rovernav_executive::{OperatorLink, Run};
use rovernav_harness::JudgedRun;
use std::io::{BufRead, Write};
use std::sync::mpsc::{Receiver, RecvTimeoutError, TryRecvError, channel};
use std::time::Duration;

/// How long a waiting mission waits for a line per cycle (wall clock).
const WAIT_FOR_INPUT: Duration = Duration::from_millis(100);

/// Standard input and output as the operator's link.
struct StdinLink {
    /// Each line of input, or why it is not a command (a line that is not UTF-8).
    lines: Receiver<Result<String, String>>,
    closed: bool,
}

impl StdinLink {
    /// Starts the reader thread.
    fn spawn() -> Self {
        let (send, lines) = channel();
        std::thread::spawn(move || {
            let mut stdin = std::io::stdin().lock();
            for number in 1.. {
                // Bytes, not `lines()`: one line that is not UTF-8 is an error on that line rather
                // than the end of input (which would drop every later command, `mission abort`
                // included).
                let mut bytes = Vec::new();
                match stdin.read_until(b'\n', &mut bytes) {
                    Ok(0) | Err(_) => break,
                    Ok(_) => {}
                }
                let line = strip_line_end(bytes);
                let item = String::from_utf8(line).map_err(|e| {
                    format!(
                        "error: input line {number} is not UTF-8 text (byte {})",
                        e.utf8_error().valid_up_to() + 1
                    )
                });
                if send.send(item).is_err() {
                    break;
                }
            }
        });
        Self { lines, closed: false }
    }
}

impl OperatorLink for StdinLink {
    /// One line per cycle, so that each line sees what the one before did (a `status` after
    /// `drive 1` shows the rover moved), as typed commands would.
    fn poll(&mut self, _cycles: u64, waiting: bool) -> Vec<String> {
        if self.closed {
            return Vec::new();
        }
        let next = if waiting {
            self.lines.recv_timeout(WAIT_FOR_INPUT).map_err(|e| e == RecvTimeoutError::Disconnected)
        } else {
            self.lines.try_recv().map_err(|e| e == TryRecvError::Disconnected)
        };
        match next {
            Ok(Ok(line)) => vec![line],
            Ok(Err(why)) => {
                self.reply(&why);
                Vec::new()
            }
            Err(disconnected) => {
                self.closed = disconnected;
                Vec::new()
            }
        }
    }

    fn reply(&mut self, text: &str) {
        let mut stdout = std::io::stdout().lock();
        // A closed standard output (the operator went away) must not stop the mission.
        let _ = writeln!(stdout, "{text}");
        let _ = stdout.flush();
    }

    fn closed(&self) -> bool {
        self.closed
    }
}

/// Parses `--speed`: a finite number of simulated seconds per second above zero.
pub fn parse_speed(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
        Ok(_) => Err(format!("`{text}` is not a speed above zero")),
        Err(e) => Err(format!("`{text}` is not a number: {e}")),
    }
}

/// A line's bytes without its `\n` or `\r\n` ending.
fn strip_line_end(mut bytes: Vec<u8>) -> Vec<u8> {
    if bytes.last() == Some(&b'\n') {
        bytes.pop();
        if bytes.last() == Some(&b'\r') {
            bytes.pop();
        }
    }
    bytes
}

/// Runs a mission with operator commands from standard input.
pub fn run(args: RunArgs) -> anyhow::Result<()> {
    let crate::MissionToRun { mission, origin_of_navigator, out_dir } = crate::MissionToRun::of(&args)?;
    let speed = args.speed.or(args.realtime.then_some(1.0));
    let pacing = speed.map_or("as fast as possible".to_string(), |x| format!("at {x} x real time"));
    eprintln!(
        "rovernav: mission `{}` running {pacing} with operator input; `help` lists the commands, `mission pause` holds the rover",
        mission.name
    );
    let mut link = StdinLink::spawn();
    // The world first: a mission that cannot be built leaves no telemetry.mcap.
    let run = Run::mission(&mission, &origin_of_navigator)?;
    let mut log = crate::output::RunLog::open(&out_dir)?;
    let mut pacer = speed.map(rovernav_console::live::Pacer::new);
    let mut pace = |p: &rovernav_executive::Progress| {
        if let Some(pacer) = pacer.as_mut() {
            pacer.pace(p.sim_time_s);
        }
    };
    let output = run.observer(&mut log.recorder).operator(&mut link).progress(&mut pace).execute();
    log.close(output.is_ok())?;
    let output = output?;
    crate::output::write_run_outputs(&out_dir, &output)?;
    let r = &output.report;
    if args.json {
        println!("{}", serde_json::to_string_pretty(r)?);
    } else {
        println!(
            "{}: {} ({}) · {} · goal error {:.2} m · driven {:.1} m · {} cycles · {:.0} s simulated",
            r.mission,
            r.outcome,
            r.navigator,
            r.message,
            r.goal_error_m,
            r.distance_driven_m,
            r.cycles,
            r.sim_time_s,
        );
        println!("outputs in {}", out_dir.display());
    }
    Ok(())
}
