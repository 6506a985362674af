//! `report.json` carries the localiser's correction counters (issue 5 item 5: a failed or
//! uncertain match is reported, not used), and `--localizer` picks the localiser from the command
//! line.

mod common;

use serde_json::Value;
use std::path::PathBuf;
use std::process::Command;

/// Runs the small yard with a localiser; returns report.json as printed with `--json`.
fn run_small_yard(localizer: &str) -> Value {
    let dir = std::env::temp_dir().join(format!("rovernav-loc-report-{}-{localizer}", std::process::id()));
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
    let _ = std::fs::remove_dir_all(&dir);
    report
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
