//! `rovernav run --interactive` with commands piped in: a new goal, a status query and a bad
//! command while a small mission runs.

mod common;

#[test]
fn piped_commands_change_the_goal_answer_status_and_name_the_bad_token() {
    let dir = std::env::temp_dir().join(format!("rovernav-interactive-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("out");
    let result = common::run_interactive(&dir, b"goto 3.5 9\nstatus\nwarp 9\n");
    let stdout = String::from_utf8_lossy(&result.stdout);
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(result.status.success(), "stdout: {stdout}\nstderr: {stderr}");
    assert!(stdout.contains("goal set to (3.50, 9.00)"), "{stdout}");
    assert!(stdout.contains("mission running") && stdout.contains("goal (3.50, 9.00)"), "{stdout}");
    let error = stdout.lines().find(|l| l.starts_with("error:")).expect("an error answer");
    assert!(error.contains("\"warp\""), "the error names the wrong token: {error}");
    // The report scores the run against the operator's goal.
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(report["outcome"], "reached", "{report}");
    assert!(report["goal_error_m"].as_f64().unwrap() < 1.0, "{report}");
    assert_eq!(report["tasks"][0]["target"], serde_json::json!([3.5, 9.0]));
}
