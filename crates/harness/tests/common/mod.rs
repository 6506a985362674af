//! Fixtures shared by the harness's scenario tests (runs of the executive, judged).
// Each test file uses part of these fixtures.
#![allow(dead_code)]

/// The small yard's terrain and start tables (shared with the command-line tests).
pub const SMALL_YARD_TABLES: &str = include_str!("small_yard.toml");

/// The small yard's usual goal table, about 9.8 m from the start.
pub const SMALL_YARD_GOAL: &str = "[goal]\nx = 9.5\ny = 8.5\n";

/// Mission text of the small yard: `name` and `seed`, its tables, then `rest` (goal, faults...).
pub fn small_yard(name: &str, seed: u64, rest: &str) -> String {
    format!("name = \"{name}\"\nseed = {seed}\n{SMALL_YARD_TABLES}{rest}")
}
