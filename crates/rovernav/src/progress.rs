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

#[cfg(test)]
mod tests {
    use super::*;

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
