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

#[test]
fn a_paced_run_takes_its_simulated_time_over_the_speed_and_answers_every_command() {
    let dir = std::env::temp_dir().join(format!("rovernav-paced-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let speed = 20.0;
    // Turns and drives of the paused rover (about 20 s simulated), then a line after the end.
    let input = b"mission pause\nturn 90\ndrive 1\nturn -45\ndrive 1\nmission abort\ndrive 1\n";
    let wall = std::time::Instant::now();
    let result = common::run_interactive_with(&dir, input, &["--speed", "20"]);
    let wall = wall.elapsed().as_secs_f64();
    let stdout = String::from_utf8_lossy(&result.stdout);
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(result.status.success(), "stdout: {stdout}\nstderr: {stderr}");
    assert!(stderr.contains("at 20 x real time"), "{stderr}");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("out/report.json")).unwrap()).unwrap();
    assert_eq!(report["outcome"], "aborted", "{report}");
    // A lower bound only: the wall clock kept up with simulated time over the speed.
    let sim = report["sim_time_s"].as_f64().unwrap();
    assert!(sim > 10.0, "the motions took simulated time: {report}");
    assert!(wall >= sim / speed, "{sim:.1} s simulated in {wall:.2} s of wall time at --speed {speed}");
    // The drive is answered with what it did, the line after the end with the outcome.
    assert!(stdout.contains("`turn 90` completed: "), "{stdout}");
    assert!(
        stdout.contains("`drive 1` completed: ") || stdout.contains("`drive 1` stopped after "),
        "{stdout}"
    );
    assert!(
        stdout.contains("mission over: aborted (mission aborted by the operator); `drive 1` not executed"),
        "{stdout}"
    );
    // The log holds the same answers: seven lines answered at once, four motions when they ran.
    let bytes = std::fs::read(dir.join("out/telemetry.mcap")).unwrap();
    let logged: Vec<String> = rovernav_telemetry::mcap::MessageStream::new(&bytes)
        .unwrap()
        .map(|m| m.unwrap())
        .filter(|m| m.channel.topic == "/bus/operator/reply")
        .map(|m| serde_json::from_slice(&m.data).unwrap())
        .collect();
    assert_eq!(logged.len(), 11, "{logged:?}");
    assert!(logged.iter().all(|r| stdout.contains(r.as_str())), "{logged:?}\n{stdout}");
    assert!(logged.last().unwrap().starts_with("mission over: aborted"), "{logged:?}");
}

#[test]
fn speed_needs_interactive_and_a_positive_number() {
    let run = |args: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_rovernav")).arg("run").args(args).output().unwrap()
    };
    for (args, needle) in [
        (&["--speed", "2"][..], "--interactive"),
        (&["--interactive", "--speed", "0"][..], "not a speed above zero"),
        (&["--interactive", "--speed", "fast"][..], "not a number"),
        (&["--interactive", "--speed", "2", "--realtime"][..], "cannot be used with"),
    ] {
        let out = run(args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && stderr.contains(needle), "{args:?}: {stderr}");
    }
}
