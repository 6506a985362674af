//! Fixtures shared by the command-line tests.

/// A small procedural yard (12 m, seed 3) whose traverse takes a few seconds in debug: the
/// executive tests' small yard with its usual goal.
pub const SMALL_YARD: &str = concat!(
    "name = \"small-yard\"\nseed = 3\n",
    include_str!("../../../executive/tests/common/small_yard.toml"),
    "[goal]\nx = 9.5\ny = 8.5\n"
);
