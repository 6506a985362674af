//! Fixtures shared by the command-line tests.

/// A small procedural yard (12 m, seed 3) whose traverse takes a few seconds in debug: the
/// executive tests' small yard with its usual goal.
pub const SMALL_YARD: &str = concat!(
    "name = \"small-yard\"\nseed = 3\n",
    include_str!("../../../harness/tests/common/small_yard.toml"),
    "[goal]\nx = 9.5\ny = 8.5\n"
);

/// Runs `rovernav run --interactive` on [`SMALL_YARD`] in `dir` (outputs in `dir/out`) with
/// `input` piped to standard input, and waits for it.
#[allow(dead_code)] // not every test file that shares these fixtures runs the binary interactively
pub fn run_interactive(dir: &std::path::Path, input: &[u8]) -> std::process::Output {
    run_interactive_with(dir, input, &[])
}

/// [`run_interactive`] with `extra` arguments after the usual ones (`--speed 20`).
#[allow(dead_code)]
pub fn run_interactive_with(dir: &std::path::Path, input: &[u8], extra: &[&str]) -> std::process::Output {
    use std::io::Write;
    let mission = dir.join("mission.toml");
    std::fs::write(&mission, SMALL_YARD).unwrap();
    let out = dir.join("out");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_rovernav"))
        .args(["run", mission.to_str().unwrap(), "--interactive", "--out", out.to_str().unwrap()])
        .args(extra)
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("binary runs");
    child.stdin.take().unwrap().write_all(input).unwrap();
    child.wait_with_output().unwrap()
}
