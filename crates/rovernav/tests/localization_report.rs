//! `report.json` carries the localiser's correction counters (issue 5 item 5: a failed or
//! uncertain match is reported, not used), and `--localizer` picks the localiser from the command
//! line.

mod common;

use rovernav_telemetry::mcap;
use rovernav_telemetry::messages::topics;
use serde_json::Value;
use std::path::PathBuf;
use std::process::Command;

/// Runs the small yard with a localiser; returns report.json as printed with `--json`.
fn run_small_yard(localizer: &str) -> Value {
    run_small_yard_logging(localizer).0
}

/// Same as [`run_small_yard`], also returning the pans of every full-resolution mast image the
/// run's telemetry log records.
fn run_small_yard_logging(localizer: &str) -> (Value, Vec<f64>) {
    // Tests run in parallel and may run the same localiser: every run gets its own folder.
    static RUNS: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
    let run = RUNS.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
    let dir =
        std::env::temp_dir().join(format!("rovernav-loc-report-{}-{run}-{localizer}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let mission: PathBuf = dir.join("mission.toml");
    std::fs::write(&mission, common::SMALL_YARD).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_rovernav"))
        .arg("run")
        .arg(&mission)
        .args(["--localizer", localizer, "--json", "--out"])
        .arg(dir.join("out"))
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let report: Value = serde_json::from_slice(&out.stdout).unwrap();
    let log = std::fs::read(dir.join("out").join("telemetry.mcap")).unwrap();
    let mut pans = Vec::new();
    for m in mcap::MessageStream::new(&log).unwrap() {
        let m = m.unwrap();
        if m.channel.topic == topics::COMMAND {
            fine_pans(&serde_json::from_slice(&m.data).unwrap(), &mut pans);
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    (report, pans)
}

/// Collects the pans of the `mast_fine` sense requests anywhere in a message.
fn fine_pans(v: &Value, out: &mut Vec<f64>) {
    match v {
        Value::Object(o) => {
            if o.get("sensor").and_then(Value::as_str) == Some("mast_fine") {
                out.extend(o.get("pan").and_then(Value::as_f64));
            }
            o.values().for_each(|x| fine_pans(x, out));
        }
        Value::Array(a) => a.iter().for_each(|x| fine_pans(x, out)),
        _ => {}
    }
}

fn count(stats: &Value, field: &str) -> u64 {
    stats[field].as_u64().unwrap_or_else(|| panic!("localization_stats.{field} missing: {stats}"))
}

#[test]
fn terrain_matching_run_reports_its_fixes_and_dead_reckoning_reports_none() {
    let matched = run_small_yard("ekf-ml");
    assert_eq!(matched["localizer"], "ekf-ml");
    let stats = &matched["localization_stats"];
    let attempted = count(stats, "matches_attempted");
    // The localiser matches after every min_travel metre of a several-metre traverse.
    let driven = matched["distance_driven_m"].as_f64().unwrap();
    assert!(driven > 5.0 && attempted >= 2, "{driven} m driven, {attempted} matches: {stats}");
    // Every attempt is either fused or rejected; the rejections split by reason.
    let (used, rejected) = (count(stats, "fixes_used"), count(stats, "fixes_rejected"));
    assert_eq!(used + rejected, attempted, "{stats}");
    assert!(count(stats, "rejected_uncertain") + count(stats, "rejected_on_edge") <= rejected, "{stats}");
    assert!(used >= 1, "a textured yard gives usable fixes: {stats}");
    // The filter underneath still integrates the gyro: the rover stands still while it senses.
    assert!(count(stats, "zero_velocity_updates") > 0, "{stats}");

    let reckoned = run_small_yard("dead-reckoning");
    assert_eq!(reckoned["localizer"], "dead-reckoning");
    let stats = &reckoned["localization_stats"];
    for field in
        ["matches_attempted", "fixes_used", "fixes_rejected", "zero_velocity_updates", "slip_corrections"]
    {
        assert_eq!(count(stats, field), 0, "dead reckoning makes no corrections: {stats}");
    }
}

#[test]
fn target_selection_points_the_look_back_at_the_chosen_rearward_view() {
    let pi = std::f64::consts::PI;
    let wrap = |a: f64| (a + pi).rem_euclid(2.0 * pi) - pi;
    let (plain, straight) = run_small_yard_logging("ekf-ml");
    assert_eq!(plain["localizer"], "ekf-ml");
    assert!(!straight.is_empty(), "the look-back images the crossed terrain");
    assert!(
        straight.iter().all(|p| wrap(p - pi).abs() < 1e-9),
        "without targets it looks straight back: {straight:?}"
    );

    let (targeted, pans) = run_small_yard_logging("ekf-ml-targets");
    assert_eq!(targeted["localizer"], "ekf-ml-targets");
    assert!(count(&targeted["localization_stats"], "fixes_used") >= 1, "{targeted}");
    // Every look-back is one of the three rearward candidates, and the prediction turns the mast
    // off the straight-back axis at least once on this rocky yard.
    let candidate = |p: f64| [pi, pi - pi / 4.0, pi + pi / 4.0].iter().any(|c| wrap(p - c).abs() < 1e-9);
    assert!(pans.iter().all(|&p| candidate(p)), "{pans:?}");
    assert!(pans.iter().any(|&p| wrap(p - pi).abs() > 0.1), "{pans:?}");
}
