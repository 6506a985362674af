//! A small traverse logged with the recorder, read back and replayed: the replay must rebuild
//! exactly what the loop produced, and a log cut anywhere must replay up to its last cycle.

use rovernav_executive::{Run, RunOutput, RunSettings};
use rovernav_harness::{JudgedRun, long_yard_world};
use rovernav_telemetry::messages::topics;
use rovernav_telemetry::schema::check;
use rovernav_telemetry::{FlushPolicy, TelemetryRecorder, TelemetryWriter, parse_log, read_log};
use std::path::PathBuf;
use std::time::Duration;

fn settings() -> RunSettings {
    RunSettings {
        navigator: "astar-grid".into(),
        localizer: "dead-reckoning".into(),
        seed: 3,
        time_limit_s: 3600.0,
        max_cycles: 400,
        name: "telemetry-yard".into(),
        navigator_params: Default::default(),
    }
}

/// A log file in a temporary folder of its own, removed when dropped.
struct TempLog {
    path: PathBuf,
}

impl Drop for TempLog {
    fn drop(&mut self) {
        if let Some(dir) = self.path.parent() {
            let _ = std::fs::remove_dir_all(dir);
        }
    }
}

fn temp_log(name: &str) -> TempLog {
    let dir = std::env::temp_dir().join(format!("rovernav-telemetry-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    TempLog { path: dir.join("telemetry.mcap") }
}

/// Runs the small yard with a recorder whose policy closes a chunk after every cycle.
fn logged_run(name: &str) -> (RunOutput, TempLog) {
    let log_file = temp_log(name);
    let path = &log_file.path;
    let policy = FlushPolicy { max_interval: Duration::from_secs(3600), max_chunk_bytes: 1 };
    let mut recorder = TelemetryRecorder::new(TelemetryWriter::create(path, policy).unwrap()).unwrap();
    let world = long_yard_world(3, 5.0, 4.0, 1.0);
    let output = Run::new(world, settings()).judged().observer(&mut recorder).execute().unwrap();
    recorder.finish().unwrap();
    (output, log_file)
}

#[test]
fn replay_of_a_complete_log_rebuilds_the_run_exactly() {
    let (out, log_file) = logged_run("complete");
    let path = log_file.path.clone();
    assert_eq!(out.report.outcome, "reached", "the small yard is a normal traverse");
    assert!(out.report.cycles >= 5, "{} cycles", out.report.cycles);
    let log = read_log(&path).unwrap();
    assert_eq!(log.end.truncated, None);
    let replay = log.replay().unwrap();
    assert!(replay.complete);
    assert_eq!(replay.report, out.report);
    assert_eq!(replay.trace.truth, out.trace.truth);
    assert_eq!(replay.trace.estimate, out.trace.estimate);
    assert_eq!(replay.trace.plans, out.trace.plans);
    assert!(!out.trace.plans.is_empty());
    assert_eq!(replay.trace.overlays, out.trace.overlays);
    let (sensed, expected) = (replay.trace.sensed.unwrap(), out.trace.sensed.unwrap());
    assert!(expected.data.iter().any(|&s| s), "the run sensed something");
    assert_eq!(sensed, expected, "sensed area recomputed from the logged clouds");
    assert_eq!(replay.world.terrain, out.world.terrain);
    assert_eq!(replay.world.rover, out.world.rover);
    assert_eq!(replay.world.sensor_model, out.world.sensor_model);
    assert_eq!(replay.world.goal, out.world.goal);
}

#[test]
fn every_message_fits_its_schema_every_topic_is_there_and_time_never_goes_back() {
    let (out, log_file) = logged_run("schemas");
    let path = log_file.path.clone();
    let bytes = std::fs::read(&path).unwrap();
    let summary = mcap::Summary::read(&bytes).unwrap().expect("a finished log has a summary");
    let mut seen = std::collections::BTreeMap::<String, u64>::new();
    let mut last_time = 0;
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        let schema = m.channel.schema.as_ref().expect("every channel has a schema");
        assert_eq!((schema.encoding.as_str(), m.channel.message_encoding.as_str()), ("jsonschema", "json"));
        let schema: serde_json::Value = serde_json::from_slice(&schema.data).unwrap();
        let value: serde_json::Value = serde_json::from_slice(&m.data).unwrap();
        check(&schema, &value).unwrap_or_else(|e| panic!("{}: {e}", m.channel.topic));
        assert!(m.log_time >= last_time, "{}: log time went back", m.channel.topic);
        last_time = m.log_time;
        *seen.entry(m.channel.topic.clone()).or_default() += 1;
    }
    let cycles = out.report.cycles;
    let count = |t: &str| seen.get(t).copied().unwrap_or(0);
    for t in [topics::WORLD, topics::SETTINGS, topics::REPORT, topics::OVERLAYS] {
        assert_eq!(count(t), 1, "{t}");
    }
    for t in [topics::SENSOR_FRAME, topics::ESTIMATE, topics::TRUTH, topics::CYCLE] {
        assert_eq!(count(t), cycles + 1, "{t}: one per cycle and one at the start");
    }
    assert_eq!(count(topics::COMMAND), cycles);
    assert_eq!(count(topics::POWER), cycles, "a power reading after every command");
    assert_eq!(count(topics::PLAN), out.trace.plans.len() as u64);
    assert_eq!(count(topics::HAZARD_CONTACTS), out.report.hazard_events.len() as u64);
    assert_eq!(last_time, (out.report.sim_time_s * 1e9).round() as u64);
    let stats = summary.stats.unwrap();
    assert_eq!(stats.message_count, seen.values().sum::<u64>());
    // Every declared topic is in the summary with a schema, whether or not it had messages.
    for t in topics::ALL {
        assert!(summary.channels.values().any(|c| c.topic == t && c.schema.is_some()), "{t}");
    }
    // The component-bus channels carry their message types' derived schemas, not an empty one.
    let frame =
        summary.channels.values().find(|c| c.topic == "/bus/platform/frame").expect("bus frames logged");
    let schema: serde_json::Value = serde_json::from_slice(&frame.schema.as_ref().unwrap().data).unwrap();
    assert_eq!(schema["title"], "FrameMsg");
    assert!(schema["properties"]["frame"].is_object(), "{schema}");
}

#[test]
fn recomputed_figures_agree_with_the_executive_report() {
    // The partial report of a cut-off log is recomputed from the logged cycles; on a whole log
    // the same computation must give the figures the executive measured.
    let (out, log_file) = logged_run("recompute");
    let path = log_file.path.clone();
    let log = read_log(&path).unwrap();
    let replay = log.replay().unwrap();
    let last = log.last_complete_cycle().unwrap();
    let r = log.recomputed_report(&replay.world, &replay.trace, last).unwrap();
    let e = &out.report;
    assert_eq!(r.cycles, e.cycles);
    assert_eq!(r.sim_time_s, e.sim_time_s);
    assert_eq!(r.goal_error_m, e.goal_error_m);
    assert_eq!(r.localization_error_m, e.localization_error_m);
    assert_eq!(r.hazard_contacts, e.hazard_contacts);
    assert_eq!(r.hazard_events, e.hazard_events);
    assert_eq!(r.sensing_actions, e.sensing_actions);
    assert_eq!(r.optimal_length_m, e.optimal_length_m);
    assert_eq!(r.straight_line_m, e.straight_line_m);
    assert_eq!((&r.localizer, r.seed, &r.mission), (&e.localizer, e.seed, &e.mission));
    // Straight segments between logged poses: a lower bound, close to the integrated length.
    assert!(r.distance_driven_m <= e.distance_driven_m + 1e-9);
    assert!(
        r.distance_driven_m >= 0.95 * e.distance_driven_m,
        "{} vs {}",
        r.distance_driven_m,
        e.distance_driven_m
    );
    assert!(r.wall_time_s > 0.0 && r.wall_time_s <= e.wall_time_s + 1.0);
}

#[test]
fn a_log_cut_anywhere_replays_up_to_its_last_complete_cycle() {
    let (out, log_file) = logged_run("cut");
    let path = log_file.path.clone();
    let bytes = std::fs::read(&path).unwrap();
    let full = parse_log(&bytes, &path).unwrap();
    let world_end = {
        // The first chunk holds the start (world included); cuts before its end hold no cycle.
        let mut n = 0;
        while parse_log(&bytes[..n], &path).map_or(true, |l| l.last_complete_cycle().is_none()) {
            n += (bytes.len() / 400).max(1);
        }
        n
    };
    let mut cycles_seen = std::collections::BTreeSet::new();
    for k in 0..=40 {
        let cut = world_end + (bytes.len() - world_end) * k / 40;
        let log = parse_log(&bytes[..cut], &path).unwrap();
        assert_eq!(log.end.truncated.is_none(), cut == bytes.len(), "cut at {cut}");
        let replay = log.replay().unwrap();
        let n = replay.report.cycles as usize;
        cycles_seen.insert(n);
        assert_eq!(replay.trace.truth, out.trace.truth[..=n], "cut at {cut}");
        assert_eq!(replay.trace.estimate, out.trace.estimate[..=n]);
        if replay.complete {
            assert_eq!(replay.report, out.report);
            continue;
        }
        assert_eq!(replay.report.outcome, "aborted");
        assert!(replay.report.message.contains(&format!("ends at cycle {n}")), "{}", replay.report.message);
        let t = out.trace.truth[n];
        assert_eq!(
            replay.report.goal_error_m,
            rovernav_core::Point2::new(t.x, t.y).dist(out.world.goal.position)
        );
        assert!(n as u64 <= full.last_complete_cycle().unwrap().cycle);
    }
    assert!(cycles_seen.len() >= 5, "cuts land in many different cycles: {cycles_seen:?}");
    assert!(parse_log(&bytes[..3], &path).unwrap_err().to_string().contains("not an MCAP"));
}

/// Forwards to the recorder and panics after a given cycle, as a crashing loop would.
struct PanicsAfter {
    recorder: TelemetryRecorder,
    cycle: u64,
}

impl rovernav_executive::RunObserver for PanicsAfter {
    fn on_start(
        &mut self,
        world: &rovernav_executive::World,
        settings: &RunSettings,
        frame: &rovernav_core::SensorFrame,
        estimate: &rovernav_core::PoseEstimate,
    ) {
        self.recorder.on_start(world, settings, frame, estimate);
    }
    fn on_cycle(&mut self, record: &rovernav_executive::CycleRecord<'_>) {
        self.recorder.on_cycle(record);
        assert!(record.cycle < self.cycle, "simulated crash in cycle {}", record.cycle);
    }
}

#[test]
fn a_run_that_panics_still_leaves_a_finished_log_of_every_cycle_it_ran() {
    let log_file = temp_log("panic");
    let path = log_file.path.clone();
    let policy = FlushPolicy { max_interval: Duration::from_secs(3600), max_chunk_bytes: 1 << 30 };
    let recorder = TelemetryRecorder::new(TelemetryWriter::create(&path, policy).unwrap()).unwrap();
    let crashed = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        // Owned by the closure: unwinding drops it, as a panic in `rovernav run` would.
        let mut observer = PanicsAfter { recorder, cycle: 4 };
        Run::new(long_yard_world(3, 5.0, 4.0, 1.0), settings())
            .judged()
            .observer(&mut observer)
            .execute()
            .map(|o| o.report.cycles)
    }));
    assert!(crashed.is_err(), "the observer panicked");
    let bytes = std::fs::read(&path).unwrap();
    assert!(mcap::Summary::read(&bytes).unwrap().is_some(), "the file was finished with its summary");
    let log = parse_log(&bytes, &path).unwrap();
    assert_eq!(log.end.truncated, None);
    assert_eq!(
        log.last_complete_cycle().map(|c| c.cycle),
        Some(4),
        "nothing logged before the crash is lost"
    );
    let replay = log.replay().unwrap();
    assert!(!replay.complete);
    assert_eq!((replay.report.outcome.as_str(), replay.report.cycles), ("aborted", 4));
}

#[test]
fn the_flush_timer_gets_a_quiet_cycle_to_disk_without_another_call() {
    // A cycle followed by silence (a long planning step, or the figures computed after the last
    // cycle) must still reach the file: the recorder's timer closes the chunk once it is older
    // than the interval. Only eventual arrival is checked, not how soon.
    let log_file = temp_log("timer");
    let path = log_file.path.clone();
    let policy = FlushPolicy { max_interval: Duration::from_millis(200), max_chunk_bytes: 1 << 30 };
    let mut recorder = TelemetryRecorder::new(TelemetryWriter::create(&path, policy).unwrap()).unwrap();
    let world = long_yard_world(3, 2.0, 2.0, 0.5);
    let frame = rovernav_core::SensorFrame { t: 1.0, ..Default::default() };
    let estimate = rovernav_core::PoseEstimate::default();
    use rovernav_executive::RunObserver;
    recorder.on_start(&world, &settings(), &frame, &estimate);
    recorder.on_cycle(&rovernav_executive::CycleRecord {
        cycle: 1,
        sim_time_s: 2.0,
        command: &rovernav_core::NavCommand::Turn { angle: 0.1 },
        frame: &frame,
        estimate: &estimate,
        truth: &rovernav_core::Pose3::default(),
        plan: &[],
        hazard_contacts: 0,
        overlays: &[],
    });
    let waited = std::time::Instant::now();
    loop {
        let log = read_log(&path).unwrap();
        if log.last_complete_cycle().map(|c| c.cycle) == Some(1) {
            assert_eq!(log.commands.len(), 1);
            break;
        }
        assert!(waited.elapsed() < Duration::from_secs(20), "the timer never flushed the cycle");
        std::thread::sleep(Duration::from_millis(20));
    }
    recorder.finish().unwrap();
}
