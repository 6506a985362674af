//! Hostile input at the command line (issue 44): operator input that is not UTF-8 or out of
//! bounds, missions that would escape the output folder or cannot be built, malformed benchmark
//! files. Each gives one line naming what is wrong, and nothing is lost or left behind.

mod common;

use std::path::PathBuf;
use std::process::Command;

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("rovernav-hostile-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Runs `rovernav run --interactive` on the small yard with `input` on standard input; returns
/// the report's outcome and standard output.
fn interactive(name: &str, input: &[u8]) -> (String, String) {
    let dir = temp_dir(name);
    let out = dir.join("out");
    let result = common::run_interactive(&dir, input);
    let stdout = String::from_utf8_lossy(&result.stdout).to_string();
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(result.status.success() && !stderr.contains("panicked"), "stdout: {stdout}\nstderr: {stderr}");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    (report["outcome"].as_str().unwrap().to_string(), stdout)
}

#[test]
fn a_non_utf8_line_is_an_error_and_later_commands_still_arrive() {
    let (outcome, stdout) = interactive("utf8", b"mission pause\n\xff\xfe status\nmission abort\n");
    assert!(stdout.contains("error: input line 2 is not UTF-8"), "{stdout}");
    assert_eq!(outcome, "aborted", "`mission abort` after the bad line must arrive: {stdout}");
}

#[test]
fn operator_numbers_out_of_bounds_are_refused_and_the_mission_goes_on() {
    let input =
        b"mission pause\nturn 1e308\ngoto 1e308 5\ngoto 3000 3000\nwaypoint add -500 2\nmission abort\n";
    let (outcome, stdout) = interactive("numbers", input);
    let errors: Vec<&str> = stdout.lines().filter(|l| l.starts_with("error:")).collect();
    assert_eq!(errors.len(), 4, "{stdout}");
    assert!(errors[0].contains("\"1e308\"") && errors[0].contains("at most 36000"), "{stdout}");
    assert!(errors[1].contains("\"1e308\"") && errors[1].contains("for X"), "{stdout}");
    assert!(
        errors[2].contains("outside the terrain") && errors[3].contains("outside the terrain"),
        "{stdout}"
    );
    assert_eq!(outcome, "aborted", "{stdout}");
}

#[test]
fn a_mission_that_cannot_be_built_leaves_no_telemetry_log() {
    let dir = temp_dir("nolog");
    let mission = dir.join("m.toml");
    // Valid as a file, refused by the world: the goal lies outside the 12 m yard.
    let text = common::SMALL_YARD.replace("[goal]\nx = 9.5", "[goal]\nx = 500.0");
    assert_ne!(text, common::SMALL_YARD);
    std::fs::write(&mission, &text).unwrap();
    let out = dir.join("out");
    let result = Command::new(env!("CARGO_BIN_EXE_rovernav"))
        .args(["run", mission.to_str().unwrap(), "--out", out.to_str().unwrap()])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(!result.status.success() && !stderr.contains("panicked"), "{stderr}");
    assert!(!out.join("telemetry.mcap").exists(), "a log was created before the world: {stderr}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_mission_named_with_a_path_writes_nothing_outside_the_output_folder() {
    let dir = temp_dir("name");
    let escaped = dir.join("escaped");
    let text =
        format!("name = \"{}\"\n{}", escaped.display(), common::SMALL_YARD.replacen("name =", "# name =", 1));
    let mission = dir.join("m.toml");
    std::fs::write(&mission, text).unwrap();
    let result = Command::new(env!("CARGO_BIN_EXE_rovernav"))
        .current_dir(&dir)
        .args(["run", "m.toml"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(!result.status.success() && stderr.contains("field `name`"), "{stderr}");
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    assert!(!escaped.exists() && !dir.join("out").exists(), "outputs were written: {stderr}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn benchmark_files_with_huge_headers_or_no_scenarios_are_refused() {
    let dir = temp_dir("bench");
    let map = dir.join("huge.map");
    std::fs::write(&map, "type octile\nheight 1000000\nwidth 1000000\nmap\n..\n").unwrap();
    let pgm = dir.join("big.pgm");
    let mut bytes = b"P5\n4294967296 4294967296\n255\n".to_vec();
    bytes.extend_from_slice(&[1; 16]);
    std::fs::write(&pgm, bytes).unwrap();
    let small = dir.join("small.map");
    std::fs::write(&small, "type octile\nheight 2\nwidth 3\nmap\n...\n...\n").unwrap();
    let empty = dir.join("empty.scen");
    std::fs::write(&empty, "version 1\n").unwrap();
    let nan = dir.join("nan.scen");
    std::fs::write(&nan, "version 1\n0\tsmall.map\t3\t2\t0\t0\t1\t0\tnan\n").unwrap();
    let cases: [(Vec<&str>, &str); 4] = [
        (vec!["bench", "grid", "--start", "0,0", "--goal", "1,1", map.to_str().unwrap()], "input holds"),
        (vec!["bench", "grid", "--start", "0,0", "--goal", "1,1", pgm.to_str().unwrap()], "overflows"),
        (vec!["bench", "movingai", small.to_str().unwrap(), empty.to_str().unwrap()], "no scenario"),
        (vec!["bench", "movingai", small.to_str().unwrap(), nan.to_str().unwrap()], "line 2"),
    ];
    for (args, expected) in cases {
        let result = Command::new(env!("CARGO_BIN_EXE_rovernav")).args(&args).output().unwrap();
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert!(!result.status.success(), "{args:?} succeeded: {stderr}");
        assert!(!stderr.contains("panicked") && stderr.contains(expected), "{args:?}: {stderr}");
        assert_eq!(stderr.trim().lines().count(), 1, "{args:?}: {stderr}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
