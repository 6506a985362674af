//! Progress for a person who cannot see a progress bar: when standard error is not a terminal
//! (piped, in CI), indicatif draws nothing, so long commands print a plain line every few
//! seconds instead.

use std::io::IsTerminal;
use std::time::{Duration, Instant};

/// Seconds between two plain progress lines.
pub const PLAIN_EVERY: Duration = Duration::from_secs(5);

/// Prints a progress line to standard error at most every [`PLAIN_EVERY`], only when standard
/// error is not a terminal (a terminal has the progress bar).
pub struct PlainProgress {
    enabled: bool,
    every: Duration,
    last: Instant,
}

impl PlainProgress {
    /// Lines only when standard error is not a terminal.
    pub fn for_stderr() -> Self {
        Self::new(!std::io::stderr().is_terminal(), PLAIN_EVERY)
    }

    /// Lines when `enabled`, at most one per `every`.
    pub fn new(enabled: bool, every: Duration) -> Self {
        Self { enabled, every, last: Instant::now() }
    }

    /// The line `text` makes, if one is due now (the closure runs only then).
    pub fn due(&mut self, text: impl FnOnce() -> String) -> Option<String> {
        if !self.enabled || self.last.elapsed() < self.every {
            return None;
        }
        self.last = Instant::now();
        Some(text())
    }

    /// Prints the line `text` makes to standard error, if one is due.
    pub fn tick(&mut self, text: impl FnOnce() -> String) {
        if let Some(line) = self.due(text) {
            eprintln!("{line}");
        }
    }
}

/// Time left to the end of the route at the mean rate of progress along it so far.
#[derive(Debug, Default)]
pub struct Eta {
    /// Route to go, simulated time and wall clock at the first update.
    first: Option<(f64, f64, Instant)>,
}

impl Eta {
    /// (simulated s, wall s) left with `to_go_m` metres of route to go at `sim_time_s`; None
    /// until the route has shortened.
    pub fn update(&mut self, to_go_m: f64, sim_time_s: f64) -> Option<(f64, f64)> {
        let (to_go0, t0, wall0) = *self.first.get_or_insert((to_go_m, sim_time_s, Instant::now()));
        let done = to_go0 - to_go_m;
        let (sim, wall) = (sim_time_s - t0, wall0.elapsed().as_secs_f64());
        (done > 0.0 && sim > 0.0).then(|| (to_go_m * sim / done, to_go_m * wall / done))
    }
}

/// A duration as `1h05m`, `4m07s` or `12s`.
pub fn duration(seconds: f64) -> String {
    let s = seconds.max(0.0).round() as u64;
    match s {
        0..60 => format!("{s}s"),
        60..3600 => format!("{}m{:02}s", s / 60, s % 60),
        _ => format!("{}h{:02}m", s / 3600, (s % 3600) / 60),
    }
}

/// A run's progress in words: cycles, distance driven and to go, simulated time, and the
/// estimated time to arrival (simulated, then wall clock) from the rate along the route so far.
pub fn long_run_line(p: &rovernav_executive::Progress, eta: Option<(f64, f64)>) -> String {
    let eta = match eta {
        Some((sim, wall)) => format!("ETA {} sim, {} wall", duration(sim), duration(wall)),
        None => "ETA --".into(),
    };
    format!(
        "cycle {} · driven {:.0} m · {:.0} m to go · sim {} · {eta}",
        p.cycles,
        p.distance_driven_m,
        p.route_to_go_m,
        duration(p.sim_time_s)
    )
}

/// A campaign's progress in words: runs done of all, wall time so far and left at the mean
/// rate so far, and the last run's outcome.
pub fn campaign_line(name: &str, done: usize, total: usize, elapsed_s: f64, last: &str) -> String {
    let left = if done > 0 { elapsed_s / done as f64 * total.saturating_sub(done) as f64 } else { f64::NAN };
    let eta = if left.is_finite() { duration(left) } else { "--".into() };
    format!("campaign {name}: {done}/{total} runs · {} elapsed · ETA {eta} · {last}", duration(elapsed_s))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_campaign_line_gives_the_runs_done_and_the_time_left_at_the_mean_rate() {
        // 25 runs in 100 s: 75 more take 300 s.
        let line = campaign_line("c", 25, 100, 100.0, "trial 24 astar-grid: reached");
        assert_eq!(
            line,
            "campaign c: 25/100 runs · 1m40s elapsed · ETA 5m00s · trial 24 astar-grid: reached"
        );
        assert!(campaign_line("c", 0, 4, 3.0, "").contains("ETA --"));
    }

    #[test]
    fn eta_is_the_time_left_at_the_mean_rate_so_far() {
        let mut eta = Eta::default();
        assert_eq!(eta.update(1000.0, 10.0), None, "no progress yet");
        // 100 m in 500 s: 900 m more take 4500 s.
        let (sim, wall) = eta.update(900.0, 510.0).unwrap();
        assert!((sim - 4500.0).abs() < 1e-9, "{sim}");
        assert!(wall >= 0.0);
        assert_eq!(duration(4500.0), "1h15m");
        assert_eq!(duration(247.0), "4m07s");
        assert_eq!(duration(12.4), "12s");
    }

    #[test]
    fn a_line_is_due_once_per_interval_and_never_when_disabled() {
        let mut off = PlainProgress::new(false, Duration::ZERO);
        assert_eq!(off.due(|| "x".into()), None);
        let mut hourly = PlainProgress::new(true, Duration::from_secs(3600));
        assert_eq!(hourly.due(|| unreachable!("not due for an hour")), None);
        let mut always = PlainProgress::new(true, Duration::ZERO);
        assert_eq!(always.due(|| "cycle 1".into()).as_deref(), Some("cycle 1"));
        assert_eq!(always.due(|| "cycle 2".into()).as_deref(), Some("cycle 2"));
    }
}
