//! Telemetry end to end through the command line: `rovernav run` writes `telemetry.mcap`, an
//! independent MCAP reader finds every topic in it, `rovernav replay` rebuilds the run's
//! report.json and traverse.png from it, and a run killed mid-way leaves a log that replays to
//! a partial report.

use rovernav_telemetry::mcap;
use rovernav_telemetry::messages::topics;
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

fn rovernav() -> Command {
    Command::new(env!("CARGO_BIN_EXE_rovernav"))
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("rovernav-cli-telemetry-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn write_mission(dir: &Path, body: &str) -> PathBuf {
    let path = dir.join("mission.toml");
    std::fs::write(&path, body).unwrap();
    path
}

fn read_json(path: &Path) -> Value {
    serde_json::from_slice(&std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())))
        .unwrap()
}

const QUICK_MISSION: &str = "name = \"telemetry-quick\"\nseed = 3\n\n[terrain]\nkind = \"procedural\"\n\
                             size_m = 12.0\n\n[start]\nx = 3.0\ny = 3.0\n\n[goal]\nx = 9.0\ny = 9.0\n";

/// Runs a mission file through the command line; returns its output folder.
fn run_mission(name: &str, mission: &str) -> PathBuf {
    let dir = temp_dir(name);
    let mission = write_mission(&dir, mission);
    let out = dir.join("out");
    let status = rovernav().arg("run").arg(&mission).arg("--out").arg(&out).arg("--json").output().unwrap();
    assert!(status.status.success(), "run failed: {}", String::from_utf8_lossy(&status.stderr));
    out
}

/// The quick mission's output folder, run once for every test that reads it.
fn quick_run() -> &'static Path {
    static RUN: OnceLock<PathBuf> = OnceLock::new();
    RUN.get_or_init(|| run_mission("quick", QUICK_MISSION))
}

/// Messages per topic as the `mcap` crate's own reader sees them, checking order and schemas.
fn topic_counts(log: &Path) -> BTreeMap<String, u64> {
    let bytes = std::fs::read(log).unwrap();
    let mut counts = BTreeMap::new();
    let mut last = 0;
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        let schema = m.channel.schema.as_ref().unwrap_or_else(|| panic!("{}: no schema", m.channel.topic));
        assert_eq!(schema.encoding, "jsonschema");
        assert_eq!(m.channel.message_encoding, "json");
        serde_json::from_slice::<Value>(&schema.data).expect("the schema is JSON");
        serde_json::from_slice::<Value>(&m.data).expect("the message is JSON");
        assert!(m.log_time >= last, "{}: timestamps must not go back", m.channel.topic);
        assert_eq!(m.publish_time, m.log_time);
        last = m.log_time;
        *counts.entry(m.channel.topic.clone()).or_insert(0u64) += 1;
    }
    counts
}

/// Checks a finished run's log with the `mcap` crate's reader, replays it, and compares the
/// replay's report.json and traverse.png with the run's.
fn check_log_and_replay(out: &Path) -> Value {
    let report = read_json(&out.join("report.json"));
    let cycles = report["cycles"].as_u64().unwrap();
    let log = out.join("telemetry.mcap");
    let bytes = std::fs::read(&log).unwrap();
    let summary = mcap::Summary::read(&bytes).unwrap().expect("a finished log has a summary");
    for t in topics::ALL {
        assert!(
            summary.channels.values().any(|c| c.topic == t && c.schema.is_some()),
            "{t} declared with a schema"
        );
    }
    let counts = topic_counts(&log);
    let count = |t: &str| counts.get(t).copied().unwrap_or(0);
    for t in [topics::SENSOR_FRAME, topics::ESTIMATE, topics::TRUTH, topics::CYCLE] {
        assert_eq!(count(t), cycles + 1, "{t}: one per cycle and one at the start");
    }
    assert_eq!(count(topics::COMMAND), cycles);
    // Every message of the component bus, as published: a frame at the start and after each
    // command, one platform command per cycle, the components' status.
    assert_eq!(count("/bus/platform/frame"), cycles + 1);
    assert_eq!(count("/bus/platform/command"), cycles);
    assert!(count("/bus/system/status") > 0 && count("/bus/localization/estimate") > cycles);
    assert!(count(topics::PLAN) >= 1);
    assert_eq!(count(topics::HAZARD_CONTACTS), report["hazard_events"].as_array().unwrap().len() as u64);
    for t in [topics::WORLD, topics::SETTINGS, topics::OVERLAYS, topics::REPORT] {
        assert_eq!(count(t), 1, "{t}");
    }
    assert_eq!(summary.stats.unwrap().message_count, counts.values().sum::<u64>());

    let replay_dir = out.parent().unwrap().join("replayed");
    let replayed =
        rovernav().arg("replay").arg(&log).arg("--out").arg(&replay_dir).arg("--json").output().unwrap();
    assert!(replayed.status.success(), "replay failed: {}", String::from_utf8_lossy(&replayed.stderr));
    assert!(replayed.stderr.is_empty(), "a whole log replays without warnings");
    // Wall time and compute times included: they come from the log, not from the replay.
    assert_eq!(read_json(&replay_dir.join("report.json")), report);
    assert_eq!(serde_json::from_slice::<Value>(&replayed.stdout).unwrap(), report);
    let png = |dir: &Path| std::fs::read(dir.join("traverse.png")).unwrap();
    assert!(png(&replay_dir) == png(out), "the replayed picture is byte-identical");
    // Both write the timeline, with its three panels, as SVG and PNG.
    for dir in [out, replay_dir.as_path()] {
        let svg = std::fs::read_to_string(dir.join("timeline.svg")).expect("timeline.svg written");
        for panel in ["distance to the goal (m)", "localisation error (m)", "compute per cycle"] {
            assert!(svg.contains(panel), "{}: no `{panel}` panel", dir.display());
        }
        let timeline_png = std::fs::read(dir.join("timeline.png")).expect("timeline.png written");
        assert!(timeline_png.starts_with(b"\x89PNG\r\n\x1a\n"), "{}", dir.display());
    }
    report
}

#[test]
fn a_run_logs_every_topic_and_replay_reproduces_its_report_and_picture() {
    let report = check_log_and_replay(quick_run());
    assert!(report["cycles"].as_u64().unwrap() > 5, "a real traverse: {report}");
}

#[test]
fn a_run_that_ends_on_a_fault_loses_nothing_from_its_log() {
    // The compass reads NaN from cycle 5: fault protection stops the rover; the log must hold
    // every cycle (NaN readings included) and a report that replays exactly, fault and all.
    let mission = format!("{QUICK_MISSION}\n[[faults]]\nkind = \"compass_nan\"\nat_cycle = 5\n");
    let out = run_mission("fault", &mission);
    let report = check_log_and_replay(&out);
    assert!(!report["fault"].is_null(), "the run ended on the fault: {report}");
    let log = rovernav_telemetry::read_log(&out.join("telemetry.mcap")).unwrap();
    let nan_compass = log.frames.iter().flat_map(|f| &f.frame.imu).filter(|s| s.compass_yaw.is_nan()).count();
    assert!(nan_compass > 0, "the faulty compass readings are logged (as null)");
    let _ = std::fs::remove_dir_all(out.parent().unwrap());
}

#[test]
fn the_log_reads_with_the_python_mcap_package_when_it_is_installed() {
    let probe = Command::new("python3").args(["-c", "import mcap, lz4"]).stderr(Stdio::null()).status();
    if !probe.is_ok_and(|s| s.success()) {
        eprintln!("skipping: python3 with the `mcap` package is not available (pip install mcap)");
        return;
    }
    let log = quick_run().join("telemetry.mcap");
    let script = r#"
import json, sys
from collections import Counter
from mcap.reader import make_reader
counts = Counter()
with open(sys.argv[1], "rb") as f:
    reader = make_reader(f)
    for schema, channel, message in reader.iter_messages():
        assert schema.encoding == "jsonschema" and channel.message_encoding == "json"
        json.loads(schema.data)
        json.loads(message.data)
        counts[channel.topic] += 1
print(json.dumps(counts))
"#;
    let out = Command::new("python3").args(["-c", script]).arg(&log).output().unwrap();
    assert!(out.status.success(), "python mcap reader failed: {}", String::from_utf8_lossy(&out.stderr));
    let python: BTreeMap<String, u64> = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(python, topic_counts(&log));
}

#[test]
fn a_killed_run_leaves_a_log_that_replays_to_a_partial_report() {
    let dir = temp_dir("killed");
    // A traverse of about 20 m: over a hundred cycles, then the optimal-path figure; killed a
    // few chunks in, it is either still driving or computing that figure, never done.
    let mission = write_mission(
        &dir,
        "name = \"telemetry-long\"\nseed = 2\n\n[terrain]\nkind = \"procedural\"\nsize_m = 20.0\nresolution_m = 0.1\n\n\
         [start]\nx = 3.0\ny = 3.0\n\n[goal]\nx = 17.0\ny = 17.0\n",
    );
    let out = dir.join("out");
    let log = out.join("telemetry.mcap");
    let started = Instant::now();
    let mut child = rovernav()
        .arg("run")
        .arg(&mission)
        .arg("--out")
        .arg(&out)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    // Wait until the log holds the start chunk and two chunks of cycles after it.
    let mut chunk_ends = std::collections::BTreeSet::new();
    while chunk_ends.len() < 3 {
        assert!(started.elapsed() < Duration::from_secs(90), "the log never grew: {chunk_ends:?}");
        assert!(child.try_wait().unwrap().is_none(), "the run ended before it could be killed");
        if let Ok(l) = rovernav_telemetry::read_log(&log)
            && let Some(c) = l.last_complete_cycle()
        {
            chunk_ends.insert(c.cycle);
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    child.kill().unwrap();
    let killed_at = started.elapsed().as_secs_f64();
    eprintln!("killed after {killed_at:.1} s, {} chunks of cycles seen", chunk_ends.len() - 1);
    child.wait().unwrap();

    let logged = rovernav_telemetry::read_log(&log).expect("a killed run's log still reads");
    assert!(logged.end.truncated.is_some(), "no footer: the log was cut");
    assert!(logged.report.is_none());
    assert!(logged.world.is_some() && logged.end.messages > 0);
    let last = logged.last_complete_cycle().unwrap();
    assert!(
        last.cycle >= *chunk_ends.last().unwrap(),
        "everything seen on disk before the kill is still there"
    );
    assert!(last.wall_time_s <= killed_at);

    let replay_dir = dir.join("replayed");
    let replayed = rovernav().arg("replay").arg(&log).arg("--out").arg(&replay_dir).output().unwrap();
    let stderr = String::from_utf8_lossy(&replayed.stderr);
    assert!(replayed.status.success(), "replay failed: {stderr}");
    assert!(stderr.contains("cut off") && stderr.contains(&format!("cycle {}", last.cycle)), "{stderr}");
    let report = read_json(&replay_dir.join("report.json"));
    assert_eq!(report["outcome"], "aborted");
    assert_eq!(report["cycles"].as_u64(), Some(last.cycle));
    assert!(report["message"].as_str().unwrap().contains(&format!("ends at cycle {}", last.cycle)));
    assert_eq!(report["mission"], "telemetry-long");
    assert!(replay_dir.join("traverse.png").is_file());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn replay_of_a_missing_or_foreign_file_fails_with_one_line_naming_it() {
    let dir = temp_dir("bad");
    let not_mcap = dir.join("notes.mcap");
    std::fs::write(&not_mcap, "not a log\n").unwrap();
    for (path, expected) in [(dir.join("absent.mcap"), "absent.mcap"), (not_mcap, "not an MCAP log")] {
        let out = rovernav().arg("replay").arg(&path).output().unwrap();
        assert!(!out.status.success());
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
        assert!(stderr.contains(&path.display().to_string()) && stderr.contains(expected), "{stderr}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
