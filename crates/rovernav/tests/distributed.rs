//! `rovernav sim` and `rovernav rover` as two processes over zenoh on loopback, checked against a
//! single-process `rovernav run` of the same mission and seed; `rovernav send` as a third process
//! changing the goal; and the argument checks every build makes.

use std::process::{Command, Stdio};

fn rovernav() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_rovernav"));
    c.stdin(Stdio::null()).stdout(Stdio::piped()).stderr(Stdio::piped());
    c
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

#[cfg(feature = "zenoh")]
mod common;

#[cfg(feature = "zenoh")]
mod over_zenoh {
    use super::*;
    use std::path::{Path, PathBuf};
    use std::process::{Child, Output};
    use std::time::{Duration, Instant};

    /// Longest a process of these tests may run before it is killed (a healthy one takes seconds).
    const DEADLINE: Duration = Duration::from_secs(45);

    /// A fresh folder for one test, removed when the test ends (pass or fail).
    struct TempDir(PathBuf);

    impl TempDir {
        fn new(name: &str) -> Self {
            let dir =
                std::env::temp_dir().join(format!("rovernav-distributed-{name}-{}", std::process::id()));
            let _ = std::fs::remove_dir_all(&dir);
            std::fs::create_dir_all(&dir).unwrap();
            Self(dir)
        }

        fn mission(&self) -> PathBuf {
            let path = self.0.join("mission.toml");
            std::fs::write(&path, crate::common::SMALL_YARD).unwrap();
            path
        }
    }

    impl Drop for TempDir {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }

    /// A child process killed if the test ends before it exits by itself.
    struct Reaped(Option<Child>);

    impl Reaped {
        fn spawn(command: &mut Command) -> Self {
            Self(Some(command.spawn().expect("rovernav starts")))
        }

        /// Waits for the exit (killing the process at the deadline) and returns its output.
        fn finish(mut self, what: &str) -> Output {
            let mut child = self.0.take().unwrap();
            let start = Instant::now();
            while child.try_wait().unwrap().is_none() {
                if start.elapsed() > DEADLINE {
                    let _ = child.kill();
                    let out = child.wait_with_output().unwrap();
                    panic!("{what} did not exit within {DEADLINE:?}; stderr: {}", text(&out.stderr));
                }
                std::thread::sleep(Duration::from_millis(20));
            }
            child.wait_with_output().unwrap()
        }
    }

    impl Drop for Reaped {
        fn drop(&mut self) {
            if let Some(child) = &mut self.0 {
                let _ = child.kill();
                let _ = child.wait();
            }
        }
    }

    /// A report as JSON without its wall-clock figures.
    /// Messages per topic of a telemetry log, read with the mcap crate.
    fn bus_counts(path: &Path) -> std::collections::BTreeMap<String, u64> {
        let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let mut counts = std::collections::BTreeMap::new();
        for message in rovernav_telemetry::mcap::MessageStream::new(&bytes).unwrap() {
            *counts.entry(message.unwrap().channel.topic.clone()).or_insert(0) += 1;
        }
        counts
    }

    fn timeless_report(path: &Path) -> serde_json::Value {
        let mut report: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
        let fields = report.as_object_mut().unwrap();
        // Measurements of the process, not of the run: each process has its own.
        fields.remove("wall_time_s");
        fields.remove("compute_per_cycle");
        fields.remove("peak_rss_mb");
        report
    }

    /// A loopback endpoint on a port nobody listens on now.
    fn free_endpoint() -> String {
        let port = std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
        format!("tcp/127.0.0.1:{port}")
    }

    fn sim(mission: &Path, endpoint: &str) -> Reaped {
        Reaped::spawn(rovernav().arg("sim").arg(mission).args(["--listen", endpoint, "--timeout-s", "30"]))
    }

    fn rover(mission: &Path, endpoint: &str, out: &Path) -> Reaped {
        Reaped::spawn(
            rovernav()
                .arg("rover")
                .arg(mission)
                .args(["--connect", endpoint, "--timeout-s", "30"])
                .arg("--out")
                .arg(out),
        )
    }

    fn assert_success(out: &Output, what: &str) {
        assert!(
            out.status.success(),
            "{what} failed ({}): stdout: {}\nstderr: {}",
            out.status,
            text(&out.stdout),
            text(&out.stderr)
        );
    }

    #[test]
    fn simulator_and_rover_in_two_processes_give_the_single_process_report() {
        let dir = TempDir::new("two");
        let mission = dir.mission();
        let endpoint = free_endpoint();
        // The rover starts first on purpose: it must wait for the simulator.
        let rover_process = rover(&mission, &endpoint, &dir.0.join("two"));
        let sim_process = sim(&mission, &endpoint);

        // The independent truth: the same mission and seed in one process.
        let single =
            rovernav().arg("run").arg(&mission).arg("--out").arg(dir.0.join("one")).output().unwrap();
        assert_success(&single, "rovernav run");

        let rover_out = rover_process.finish("rovernav rover");
        let sim_out = sim_process.finish("rovernav sim");
        assert_success(&rover_out, "rovernav rover");
        assert_success(&sim_out, "rovernav sim");
        let one = timeless_report(&dir.0.join("one/report.json"));
        let two = timeless_report(&dir.0.join("two/report.json"));
        assert_eq!(one["outcome"], "reached", "{one}");
        assert_eq!(one, two, "the two-process run must be the single-process run");
        assert!(dir.0.join("two/traverse.png").exists());
        // The rover process logs its own bus: the same platform frames and commands as the
        // single-process run's log, and the same report.
        let (one_log, two_log) =
            (bus_counts(&dir.0.join("one/telemetry.mcap")), bus_counts(&dir.0.join("two/telemetry.mcap")));
        for topic in ["/bus/platform/frame", "/bus/platform/command", "/executive/report"] {
            assert!(two_log.get(topic).copied().unwrap_or(0) > 0, "{topic} in the rover's log: {two_log:?}");
            assert_eq!(one_log.get(topic), two_log.get(topic), "{topic}");
        }
        // The simulator's own summary agrees with the report the rover wrote.
        let summary = text(&sim_out.stdout);
        assert!(summary.contains(&format!("{} commands", two["cycles"])), "{summary}");
    }

    #[test]
    fn a_third_process_changes_the_goal_and_the_rover_reaches_it() {
        let dir = TempDir::new("send");
        let mission = dir.mission();
        let endpoint = free_endpoint();
        let sim_process = sim(&mission, &endpoint);
        // The sender waits for the rover to announce itself, so its command arrives as the
        // mission starts, long before the rover could reach the mission's own goal.
        let sender = Reaped::spawn(rovernav().args(["send", "goto 3.5 9", "--connect", &endpoint]));
        let rover_process = rover(&mission, &endpoint, &dir.0.join("out"));
        let sent = sender.finish("rovernav send");
        let rover_out = rover_process.finish("rovernav rover");
        let sim_out = sim_process.finish("rovernav sim");
        assert_success(&sent, "rovernav send");
        assert_success(&rover_out, "rovernav rover");
        assert_success(&sim_out, "rovernav sim");
        assert!(text(&sent.stdout).contains("goal set to (3.50, 9.00)"), "{}", text(&sent.stdout));

        let report = timeless_report(&dir.0.join("out/report.json"));
        assert_eq!(report["outcome"], "reached", "{report}");
        // Measured against the new goal: the straight line from the start (2, 2) to (3.5, 9),
        // computed here, and a goal error within the mission's 1 m tolerance.
        let straight = report["straight_line_m"].as_f64().unwrap();
        assert!((straight - 1.5f64.hypot(7.0)).abs() < 1e-9, "{report}");
        assert!(report["goal_error_m"].as_f64().unwrap() < 1.0, "{report}");
        assert_eq!(report["tasks"][0]["target"], serde_json::json!([3.5, 9.0]));
    }

    #[test]
    fn a_sender_with_no_simulator_gives_up_with_one_line_naming_the_endpoint() {
        let endpoint = free_endpoint();
        let out = rovernav()
            .args(["send", "status", "--connect", &endpoint, "--timeout-s", "0.5"])
            .output()
            .unwrap();
        assert!(!out.status.success());
        let stderr = text(&out.stderr);
        assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
        assert!(stderr.contains(&endpoint), "{stderr}");
    }
}

#[test]
fn a_bad_command_is_refused_before_sending_naming_the_token() {
    let out = rovernav().args(["send", "warp 9", "--connect", "tcp/127.0.0.1:1"]).output().unwrap();
    assert!(!out.status.success());
    let stderr = text(&out.stderr);
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(stderr.contains("\"warp\""), "{stderr}");
}

#[test]
fn a_bad_endpoint_is_named() {
    let out = rovernav().args(["sim", "--listen", "udp/127.0.0.1:7447"]).output().unwrap();
    assert!(!out.status.success());
    let stderr = text(&out.stderr);
    assert!(stderr.contains("--listen") && stderr.contains("udp/127.0.0.1:7447"), "{stderr}");
}

#[cfg(not(feature = "zenoh"))]
#[test]
fn without_the_feature_each_subcommand_says_how_to_rebuild() {
    for args in [&["sim"][..], &["rover"], &["send", "status"]] {
        let out = rovernav().args(args).output().unwrap();
        assert!(!out.status.success(), "{args:?}");
        let stderr = text(&out.stderr);
        assert_eq!(
            stderr.trim_end(),
            "error: built without the `zenoh` feature: rebuild with `cargo build --features zenoh`",
            "{args:?}"
        );
    }
}
