//! Bad input ends with a non-zero exit and one line naming the file and field, never a panic.

use std::path::{Path, PathBuf};
use std::process::Command;

fn rovernav(args: &[&str]) -> (bool, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_rovernav")).args(args).output().expect("binary runs");
    (out.status.success(), String::from_utf8_lossy(&out.stderr).trim().to_string())
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("rovernav-cli-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn assert_one_line_error(ok: bool, stderr: &str, must_contain: &[&str]) {
    assert!(!ok, "expected failure, stderr: {stderr}");
    assert!(!stderr.contains("panicked"), "panic: {stderr}");
    assert_eq!(stderr.lines().count(), 1, "not one line: {stderr}");
    for s in must_contain {
        assert!(stderr.contains(s), "`{s}` missing from: {stderr}");
    }
}

fn write_mission(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.display().to_string()
}

const DEFAULT: &str = include_str!("../../../missions/default.toml");

#[test]
fn missing_mission_file_is_named() {
    let (ok, err) = rovernav(&["run", "/nonexistent/mission.toml"]);
    assert_one_line_error(ok, &err, &["/nonexistent/mission.toml"]);
}

#[test]
fn invalid_toml_names_file_and_line() {
    let dir = temp_dir("toml");
    let path = write_mission(&dir, "bad.toml", &DEFAULT.replace("seed = 1", "seed = = 1"));
    let (ok, err) = rovernav(&["run", &path, "--out", dir.join("out").to_str().unwrap()]);
    assert_one_line_error(ok, &err, &["bad.toml", "line "]);
    assert!(!dir.join("out/report.json").exists(), "no output on bad input");
}

#[test]
fn unknown_navigator_names_the_field() {
    let dir = temp_dir("nav");
    let path = write_mission(&dir, "nav.toml", &DEFAULT.replace("\"astar-grid\"", "\"warp-drive\""));
    let (ok, err) = rovernav(&["run", &path]);
    assert_one_line_error(ok, &err, &["nav.toml", "navigator", "warp-drive"]);
    let (ok, err) = rovernav(&["run", "--navigator", "warp-drive"]);
    assert_one_line_error(ok, &err, &["--navigator", "warp-drive"]);
    let (ok, err) = rovernav(&["run", "--localizer", "star-tracker"]);
    assert_one_line_error(ok, &err, &["--localizer", "star-tracker", "ekf-ml"]);
}

#[test]
fn a_run_that_cannot_start_leaves_no_output_folder() {
    let dir = temp_dir("no-output");
    let out = dir.join("nested/out");
    let (ok, err) = rovernav(&["run", "--navigator", "warp-drive", "--out", out.to_str().unwrap()]);
    assert_one_line_error(ok, &err, &["warp-drive"]);
    assert!(!dir.join("nested").exists(), "the telemetry log and its folders are removed again");
}

#[test]
fn missing_dem_names_the_file_and_field() {
    let dir = temp_dir("dem");
    let text = "name = \"m\"\n[terrain]\nkind = \"dem\"\npath = \"/nonexistent/dem.tif\"\n[start]\nx = 1.0\ny = 1.0\n[goal]\nx = 5.0\ny = 5.0\n";
    let path = write_mission(&dir, "dem.toml", text);
    let (ok, err) = rovernav(&["run", &path]);
    assert_one_line_error(ok, &err, &["dem.toml", "terrain.path", "/nonexistent/dem.tif"]);
}

#[test]
fn corrupt_geotiff_names_the_file() {
    let dir = temp_dir("tif");
    let tif = dir.join("corrupt.tif");
    let mut bytes = b"II*\0\x08\0\0\0".to_vec();
    bytes.extend((0..500u32).map(|i| (i * 37 % 251) as u8));
    std::fs::write(&tif, bytes).unwrap();
    let text = format!(
        "name = \"m\"\n[terrain]\nkind = \"dem\"\npath = \"{}\"\n[start]\nx = 1.0\ny = 1.0\n[goal]\nx = 5.0\ny = 5.0\n",
        tif.display()
    );
    let path = write_mission(&dir, "tif.toml", &text);
    let (ok, err) = rovernav(&["run", &path]);
    assert_one_line_error(ok, &err, &["tif.toml", "corrupt.tif"]);
}

#[test]
fn unknown_command_fails() {
    let out = Command::new(env!("CARGO_BIN_EXE_rovernav")).arg("fly").output().unwrap();
    assert!(!out.status.success());
    assert!(!String::from_utf8_lossy(&out.stderr).contains("panicked"));
}

#[cfg(unix)]
#[test]
fn broken_pipe_on_stdout_panicked_in_println() {
    use std::os::unix::process::ExitStatusExt;
    use std::process::Stdio;
    // The reader is gone before the child starts (`rovernav ... | head -0`), so its first line
    // meets a closed pipe whatever the timing.
    let (reader, writer) = std::io::pipe().expect("a pipe");
    drop(reader);
    let out = Command::new(env!("CARGO_BIN_EXE_rovernav"))
        .args(["eval", "terrain", "--seeds", "1"])
        .stdout(Stdio::from(writer))
        .stderr(Stdio::piped())
        .output()
        .expect("binary runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "panic: {stderr}");
    assert!(out.status.success() || out.status.signal() == Some(libc::SIGPIPE), "{:?}: {stderr}", out.status);
}

#[test]
fn bad_navigator_params_name_the_file_line_and_parameter() {
    let dir = temp_dir("params");
    let text = format!("{}\n[navigator_params]\nsafety_bufer_m = 0.2\n", DEFAULT);
    let line = text.lines().count();
    let path = write_mission(&dir, "params.toml", &text);
    let out = dir.join("out");
    let (ok, err) = rovernav(&["run", &path, "--out", out.to_str().unwrap()]);
    assert_one_line_error(
        ok,
        &err,
        &["params.toml", "navigator_params.safety_bufer_m", &format!("line {line}")],
    );
    assert!(!out.join("report.json").exists(), "no output on bad input");
    for (param, names) in [
        ("max_wedges=3", vec!["--param", "astar-grid", "max_wedges"]),
        ("safety_buffer_m", vec!["--param", "NAME=VALUE"]),
        ("safety_buffer_m=wide", vec!["--param", "not a number"]),
        ("safety_buffer_m=-1", vec!["--param", "safety_buffer_m", "0..2"]),
    ] {
        let (ok, err) = rovernav(&["run", "--param", param, "--out", out.to_str().unwrap()]);
        assert_one_line_error(ok, &err, &names);
    }
    let (ok, err) = rovernav(&["navigators", "warp-drive"]);
    assert_one_line_error(ok, &err, &["warp-drive", "roverbug"]);
    let listing =
        Command::new(env!("CARGO_BIN_EXE_rovernav")).args(["navigators", "roverbug"]).output().unwrap();
    let listing = String::from_utf8_lossy(&listing.stdout);
    assert!(listing.contains("safety_clearance_margin = 0.9"), "{listing}");
}
