//! The operator's line into a running mission: command-language lines in, answers out.
//!
//! The run loop polls an [`OperatorLink`] once per cycle and publishes what it gives on
//! `/operator/command`; the deliberative layer answers on `/operator/reply`, which the loop hands
//! back to the link. `rovernav run --interactive` links standard input and output; tests use
//! [`ScriptedOperator`], which sends each line at a given command count, so a run with operator
//! commands is as deterministic as one without.

/// Where operator commands come from and answers go.
pub trait OperatorLink {
    /// The lines typed since the last call. `waiting` says the mission is holding for the
    /// operator (paused or emergency-stopped): a live link may then wait a little for input
    /// instead of letting simulated time race ahead. Once the mission is over the loop polls
    /// with `cycles` = `u64::MAX` and `waiting` set until a call gives nothing, answering each
    /// line `mission over: <outcome>` (or `status`, `help`) instead of dropping it.
    fn poll(&mut self, cycles: u64, waiting: bool) -> Vec<String>;
    /// One answer of the deliberative layer (may span several lines).
    fn reply(&mut self, text: &str);
    /// Whether input has ended for good (a waiting mission is then aborted).
    fn closed(&self) -> bool {
        false
    }
}

/// Lines sent at given command counts, at most one per poll (so each line sees the effect of
/// the one before: a `status` after a `stop` finds the components stopped); every answer is kept.
#[derive(Clone, Debug, Default)]
pub struct ScriptedOperator {
    script: Vec<(u64, String)>,
    sent: usize,
    /// Every answer, in order.
    pub replies: Vec<String>,
}

impl ScriptedOperator {
    /// A script of `(command count, line)`: each line is sent once the run has executed that
    /// many commands (0 sends it before the first), one line per cycle, in script order.
    pub fn new(script: &[(u64, &str)]) -> Self {
        let mut script: Vec<(u64, String)> = script.iter().map(|(c, l)| (*c, l.to_string())).collect();
        // Stable: lines due at the same count keep their order.
        script.sort_by_key(|(c, _)| *c);
        Self { script, sent: 0, replies: Vec::new() }
    }

    /// The first answer containing `needle`.
    pub fn reply_containing(&self, needle: &str) -> Option<&str> {
        self.replies.iter().map(String::as_str).find(|r| r.contains(needle))
    }
}

impl OperatorLink for ScriptedOperator {
    fn poll(&mut self, cycles: u64, _waiting: bool) -> Vec<String> {
        match self.script.get(self.sent) {
            Some((due, line)) if *due <= cycles => {
                self.sent += 1;
                vec![line.clone()]
            }
            _ => Vec::new(),
        }
    }

    fn reply(&mut self, text: &str) {
        self.replies.push(text.to_string());
    }

    fn closed(&self) -> bool {
        self.sent == self.script.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scripted_lines_are_sent_once_at_their_command_count() {
        let mut op = ScriptedOperator::new(&[(3, "status"), (0, "goto 1 2"), (3, "help")]);
        assert_eq!(op.poll(0, false), ["goto 1 2"]);
        assert!(op.poll(0, false).is_empty());
        assert!(op.poll(2, false).is_empty());
        assert!(!op.closed());
        assert_eq!(op.poll(5, false), ["status"]);
        assert_eq!(op.poll(5, false), ["help"]);
        assert!(op.poll(9, false).is_empty());
        assert!(op.closed());
    }
}
