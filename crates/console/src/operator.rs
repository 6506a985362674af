//! Command authority and the operator's link from the browser into the run.
//!
//! Every client watches; one at a time holds command authority (the first to connect, or the
//! last to press "take control"). The holder's command lines go, one per cycle, through the same
//! [`OperatorLink`] path as `rovernav run --interactive`'s standard input, so the deliberative
//! layer validates them exactly as it does typed lines; its answers, the lines sent and changes
//! of authority and phase reach every client as [`Notice`]s.

use rovernav_executive::OperatorLink;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError, Sender, TryRecvError, channel};
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};
use std::time::Duration;
use tokio::sync::broadcast;

/// How long a waiting mission waits for a line per cycle (wall clock), as on standard input.
const WAIT_FOR_INPUT: Duration = Duration::from_millis(100);

/// Longest command line accepted (the whole message is capped at 64 KiB anyway).
pub const MAX_LINE: usize = 4096;

/// Most waypoints, keep-out polygons and vertices per polygon a plan may hold.
pub const MAX_PLAN_ITEMS: usize = 100;

/// Where the console's run is.
#[derive(Clone, Debug, PartialEq)]
pub enum Phase {
    /// The world is shown and the mission waits for a plan from the mission planner.
    Waiting,
    /// The mission runs.
    Running,
    /// The mission ended with this outcome.
    Done(String),
    /// A finished run's log is being replayed: there is no rover to command.
    Replay,
}

impl Phase {
    /// Its name for clients (`waiting`, `running`, `done`, `replay`).
    pub fn name(&self) -> &'static str {
        match self {
            Phase::Waiting => "waiting",
            Phase::Running => "running",
            Phase::Done(_) => "done",
            Phase::Replay => "replay",
        }
    }
}

/// A mission drawn in the mission planner (local frame, metres).
#[derive(Clone, Debug, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Plan {
    /// The goal, [x east, y north].
    pub goal: [f64; 2],
    /// Waypoints to visit first, in order.
    #[serde(default)]
    pub waypoints: Vec<[f64; 2]>,
    /// Keep-out polygons, each at least 3 vertices.
    #[serde(default)]
    pub keep_out: Vec<Vec<[f64; 2]>>,
}

impl Plan {
    /// Checks sizes and that every coordinate is finite and within `area` ([x0, y0, x1, y1]).
    pub fn check(&self, area: [f64; 4]) -> Result<(), String> {
        if self.waypoints.len() > MAX_PLAN_ITEMS || self.keep_out.len() > MAX_PLAN_ITEMS {
            return Err(format!("a plan holds at most {MAX_PLAN_ITEMS} waypoints and keep-out zones"));
        }
        let inside = |p: &[f64; 2]| {
            p.iter().all(|v| v.is_finite())
                && (area[0]..=area[2]).contains(&p[0])
                && (area[1]..=area[3]).contains(&p[1])
        };
        let outside = |what: String, p: &[f64; 2]| {
            format!(
                "{what} ({}, {}) is outside the terrain (x {:.1}..{:.1}, y {:.1}..{:.1} m)",
                p[0], p[1], area[0], area[2], area[1], area[3]
            )
        };
        if !inside(&self.goal) {
            return Err(outside("the goal".into(), &self.goal));
        }
        for (i, w) in self.waypoints.iter().enumerate() {
            if !inside(w) {
                return Err(outside(format!("waypoint {}", i + 1), w));
            }
        }
        for (i, zone) in self.keep_out.iter().enumerate() {
            if zone.len() < 3 || zone.len() > MAX_PLAN_ITEMS {
                return Err(format!("keep-out zone {}: 3 to {MAX_PLAN_ITEMS} vertices", i + 1));
            }
            if let Some(v) = zone.iter().find(|v| !inside(v)) {
                return Err(outside(format!("keep-out zone {} vertex", i + 1), v));
            }
        }
        Ok(())
    }

    /// The command lines that give a running mission this goal and these waypoints.
    pub fn command_lines(&self) -> Vec<String> {
        let mut lines = vec!["waypoint clear".to_string(), format!("goto {} {}", self.goal[0], self.goal[1])];
        lines.extend(self.waypoints.iter().map(|w| format!("waypoint add {} {}", w[0], w[1])));
        lines
    }
}

/// What the console tells clients besides the telemetry.
#[derive(Clone, Debug, PartialEq)]
pub enum Notice {
    /// A client sent a command line.
    Command {
        /// The client.
        client: u64,
        /// The line.
        line: String,
    },
    /// An answer of the deliberative layer (or of the console when no mission runs).
    Reply(String),
    /// One client's own error (a command refused before it reached the rover).
    Error {
        /// The client it is for.
        client: u64,
        /// What went wrong.
        text: String,
    },
    /// Who holds command authority now.
    Authority(Option<u64>),
    /// The run's phase changed.
    Phase(Phase),
}

#[derive(Default)]
struct Shared {
    holder: Option<u64>,
    phase: Option<Phase>,
    plans: Option<Sender<Plan>>,
}

/// The console's state shared by every connection: authority, phase, and the way into the run.
pub struct Console {
    shared: Mutex<Shared>,
    lines: Mutex<Sender<String>>,
    next_client: AtomicU64,
    notices: broadcast::Sender<Notice>,
}

/// The run's end of the console: command lines in, plans in, answers out.
pub struct ConsoleLink {
    lines: Receiver<String>,
    /// Plans sent while the mission waits for one.
    pub plans: Receiver<Plan>,
    console: Arc<Console>,
}

impl Console {
    /// A console in `phase` and the link its run reads.
    pub fn new(phase: Phase) -> (Arc<Self>, ConsoleLink) {
        let (line_tx, lines) = channel();
        let (plan_tx, plans) = channel();
        let (notices, _) = broadcast::channel(1024);
        let console = Arc::new(Self {
            shared: Mutex::new(Shared { holder: None, phase: Some(phase), plans: Some(plan_tx) }),
            lines: Mutex::new(line_tx),
            next_client: AtomicU64::new(1),
            notices,
        });
        let link = ConsoleLink { lines, plans, console: Arc::clone(&console) };
        (console, link)
    }

    fn lock(&self) -> MutexGuard<'_, Shared> {
        self.shared.lock().unwrap_or_else(PoisonError::into_inner)
    }

    fn notify(&self, notice: Notice) {
        // Nobody listening is not an error.
        let _ = self.notices.send(notice);
    }

    /// Notices from now on.
    pub fn subscribe(&self) -> broadcast::Receiver<Notice> {
        self.notices.subscribe()
    }

    /// A new client's id; it takes command authority when nobody holds it.
    pub fn connect(&self) -> u64 {
        let id = self.next_client.fetch_add(1, Ordering::Relaxed);
        let mut shared = self.lock();
        if shared.holder.is_none() && shared.phase != Some(Phase::Replay) {
            shared.holder = Some(id);
            drop(shared);
            self.notify(Notice::Authority(Some(id)));
        }
        id
    }

    /// A client left: its authority, if it held it, is free.
    pub fn disconnect(&self, client: u64) {
        let mut shared = self.lock();
        if shared.holder == Some(client) {
            shared.holder = None;
            drop(shared);
            self.notify(Notice::Authority(None));
        }
    }

    /// `client` takes command authority (from whoever held it).
    pub fn take_control(&self, client: u64) {
        let mut shared = self.lock();
        if shared.phase == Some(Phase::Replay) {
            drop(shared);
            self.refuse(client, "a replay has no rover to command");
            return;
        }
        shared.holder = Some(client);
        drop(shared);
        self.notify(Notice::Authority(Some(client)));
    }

    /// `client` gives command authority up.
    pub fn release(&self, client: u64) {
        self.disconnect(client);
    }

    /// Who holds command authority.
    pub fn holder(&self) -> Option<u64> {
        self.lock().holder
    }

    /// The phase.
    pub fn phase(&self) -> Phase {
        self.lock().phase.clone().unwrap_or(Phase::Waiting)
    }

    /// Moves to `phase` and tells every client.
    pub fn set_phase(&self, phase: Phase) {
        self.lock().phase = Some(phase.clone());
        self.notify(Notice::Phase(phase));
    }

    /// Tells one client why its message was refused.
    pub fn refuse(&self, client: u64, text: &str) {
        self.notify(Notice::Error { client, text: text.to_string() });
    }

    /// Whether `client` may command; tells it why not.
    fn authorised(&self, client: u64) -> bool {
        let holder = self.holder();
        if holder == Some(client) {
            return true;
        }
        let why = match (self.phase(), holder) {
            (Phase::Replay, _) => "a replay has no rover to command".to_string(),
            (_, Some(h)) => format!("watching: client {h} holds command authority (press Take control)"),
            (_, None) => "watching: nobody holds command authority (press Take control)".to_string(),
        };
        self.refuse(client, &why);
        false
    }

    /// A command line from `client`: sent to the run when it holds authority and the line is
    /// one line of text; answered here when no mission runs.
    pub fn command(&self, client: u64, line: &str) {
        if !self.authorised(client) {
            return;
        }
        if line.len() > MAX_LINE || line.chars().any(char::is_control) {
            self.refuse(client, &format!("a command is one line of at most {MAX_LINE} bytes"));
            return;
        }
        self.notify(Notice::Command { client, line: line.to_string() });
        match self.phase() {
            Phase::Running => {
                // A run that has just ended drops the line; the Done notice follows.
                let _ = self.lines.lock().unwrap_or_else(PoisonError::into_inner).send(line.to_string());
            }
            phase => self.notify(Notice::Reply(answer_without_run(&phase, line))),
        }
    }

    /// A plan from the mission planner: starts a waiting mission, or becomes commands for a
    /// running one (keep-out zones only apply to a mission not yet started).
    pub fn plan(&self, client: u64, plan: Plan) {
        if !self.authorised(client) {
            return;
        }
        match self.phase() {
            Phase::Waiting => {
                let sent = self.lock().plans.as_ref().is_some_and(|p| p.send(plan).is_ok());
                if !sent {
                    self.refuse(client, "the mission no longer takes a plan");
                }
            }
            Phase::Running => {
                if !plan.keep_out.is_empty() {
                    self.refuse(
                        client,
                        "keep-out zones apply to a mission not yet started; sent the goal and waypoints",
                    );
                }
                for line in plan.command_lines() {
                    self.command(client, &line);
                }
            }
            phase => self.refuse(client, &answer_without_run(&phase, "plan")),
        }
    }
}

/// The console's own answer to a line when no mission runs.
fn answer_without_run(phase: &Phase, line: &str) -> String {
    let word = line.split_whitespace().next().unwrap_or("");
    if word.eq_ignore_ascii_case("help") {
        let topic = line.split_whitespace().nth(1);
        return match rovernav_executive::help_text(topic) {
            Ok(text) => text.trim_end().to_string(),
            Err(e) => format!("error: {e}"),
        };
    }
    match phase {
        Phase::Waiting => format!(
            "no mission yet: draw a goal in the mission planner and press Send; `{line}` not executed"
        ),
        Phase::Done(outcome) => format!("mission over: {outcome}; `{line}` not executed"),
        Phase::Replay => format!("a replay has no rover to command; `{line}` not executed"),
        Phase::Running => String::new(),
    }
}

impl ConsoleLink {
    /// The console this link belongs to.
    pub fn console(&self) -> &Arc<Console> {
        &self.console
    }
}

impl OperatorLink for ConsoleLink {
    /// One line per cycle, as standard input gives them; a waiting mission waits up to 100 ms.
    fn poll(&mut self, _cycles: u64, waiting: bool) -> Vec<String> {
        let next = if waiting {
            self.lines.recv_timeout(WAIT_FOR_INPUT).map_err(|e| e == RecvTimeoutError::Disconnected)
        } else {
            self.lines.try_recv().map_err(|e| e == TryRecvError::Disconnected)
        };
        next.map(|line| vec![line]).unwrap_or_default()
    }

    fn reply(&mut self, text: &str) {
        self.console.notify(Notice::Reply(text.to_string()));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_holder_commands_and_authority_moves_on_request() {
        let (console, mut link) = Console::new(Phase::Running);
        let mut notices = console.subscribe();
        let a = console.connect();
        let b = console.connect();
        assert_eq!(console.holder(), Some(a), "first come holds authority");
        console.command(b, "mission abort");
        console.command(a, "status");
        assert_eq!(link.poll(0, false), ["status"], "the watcher's line never reached the run");
        assert!(link.poll(0, false).is_empty());
        let seen: Vec<Notice> = std::iter::from_fn(|| notices.try_recv().ok()).collect();
        assert!(seen.iter().any(
            |n| matches!(n, Notice::Error { client, text } if *client == b && text.contains("watching"))
        ));
        console.take_control(b);
        console.command(b, "mission pause");
        assert_eq!(link.poll(0, false), ["mission pause"]);
        console.disconnect(b);
        assert_eq!(console.holder(), None);
    }

    #[test]
    fn multi_line_and_control_characters_are_refused() {
        let (console, mut link) = Console::new(Phase::Running);
        let a = console.connect();
        console.command(a, "status\nmission abort");
        console.command(a, &"x".repeat(MAX_LINE + 1));
        assert!(link.poll(0, false).is_empty());
    }

    #[test]
    fn plans_are_checked_against_the_terrain() {
        let area = [0.0, 0.0, 30.0, 30.0];
        let ok = Plan { goal: [20.0, 20.0], waypoints: vec![[5.0, 10.0]], keep_out: vec![] };
        assert!(ok.check(area).is_ok());
        let outside = Plan { goal: [31.0, 2.0], ..ok.clone() };
        assert!(outside.check(area).unwrap_err().contains("the goal (31, 2) is outside"));
        let nan = Plan { waypoints: vec![[f64::NAN, 1.0]], ..ok.clone() };
        assert!(nan.check(area).unwrap_err().contains("waypoint 1"));
        let thin = Plan { keep_out: vec![vec![[1.0, 1.0], [2.0, 2.0]]], ..ok.clone() };
        assert!(thin.check(area).unwrap_err().contains("keep-out zone 1"));
        assert_eq!(ok.command_lines(), ["waypoint clear", "goto 20 20", "waypoint add 5 10"]);
    }

    #[test]
    fn without_a_run_the_console_answers() {
        let (console, _link) = Console::new(Phase::Waiting);
        let mut notices = console.subscribe();
        let a = console.connect();
        console.command(a, "help");
        console.command(a, "status");
        let replies: Vec<String> = std::iter::from_fn(|| notices.try_recv().ok())
            .filter_map(|n| if let Notice::Reply(t) = n { Some(t) } else { None })
            .collect();
        assert!(replies[0].starts_with("Commands:"), "{replies:?}");
        assert!(replies[1].contains("no mission yet"), "{replies:?}");
    }
}
