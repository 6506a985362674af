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
    let (report, looks, _) = run_logging(common::SMALL_YARD, localizer);
    (report, looks.into_iter().map(|(pan, _)| pan).collect())
}

/// Runs a mission text with a localiser; returns report.json, the pose estimates (x, y) the
/// telemetry log records in order, and for every full-resolution mast image it records, its
/// pan and the index of the latest estimate when it was commanded.
fn run_logging(mission_text: &str, localizer: &str) -> (Value, Vec<(f64, usize)>, Vec<[f64; 2]>) {
    // Tests run in parallel and may run the same localiser: every run gets its own folder.
    static RUNS: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
    let run = RUNS.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
    let dir =
        std::env::temp_dir().join(format!("rovernav-loc-report-{}-{run}-{localizer}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let mission: PathBuf = dir.join("mission.toml");
    std::fs::write(&mission, mission_text).unwrap();
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
    let (mut looks, mut track) = (Vec::new(), Vec::new());
    for m in mcap::MessageStream::new(&log).unwrap() {
        let m = m.unwrap();
        if m.channel.topic == topics::ESTIMATE {
            let v: Value = serde_json::from_slice(&m.data).unwrap();
            track.push([v["pose"]["x"].as_f64().unwrap(), v["pose"]["y"].as_f64().unwrap()]);
        }
        if m.channel.topic == topics::COMMAND {
            let mut pans = Vec::new();
            fine_pans(&serde_json::from_slice(&m.data).unwrap(), &mut pans);
            looks.extend(pans.into_iter().map(|p| (p, track.len().saturating_sub(1))));
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    (report, looks, track)
}

/// Collects the pans of the `mast_fine` sense requests anywhere in a message.
fn fine_pans(v: &Value, out: &mut Vec<f64>) {
    match v {
        Value::Object(o) => {
            out.extend(o.get("mast_fine").and_then(|r| r["pan"].as_f64()));
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

#[test]
fn later_task_legs_keep_the_look_back_wrapper() {
    // A waypoint makes two legs; the navigator component builds a fresh navigator for the
    // second, which used to lose the look-back wrapper (and with it every pose fix after the
    // first leg).
    let waypoint = [5.0, 6.0];
    let mission = common::SMALL_YARD.replace("[goal]\n", "[goal]\nwaypoints = [[5.0, 6.0]]\n");
    assert_ne!(mission, common::SMALL_YARD);
    let (report, looks, track) = run_logging(&mission, "ekf-ml");
    assert_eq!(report["outcome"], "reached", "{report}");
    let tasks = report["tasks"].as_array().unwrap();
    assert!(tasks.len() >= 2 && tasks.iter().all(|t| t["state"] == "success"), "{report}");
    // The first leg ends when the estimate comes within the 0.5 m tolerance of the waypoint.
    let reached = track
        .iter()
        .position(|p| (p[0] - waypoint[0]).hypot(p[1] - waypoint[1]) <= 0.5)
        .expect("the estimate reaches the waypoint");
    let (first, second) = (
        looks.iter().filter(|&&(_, i)| i < reached).count(),
        looks.iter().filter(|&&(_, i)| i > reached).count(),
    );
    let rest: f64 = track[reached..].windows(2).map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1])).sum();
    // One look back per metre driven (the decorator's min_travel), on both legs.
    assert!(first >= 1 && second >= 1, "{first} looks on the first leg, {second} on the {rest:.1} m second");
}
