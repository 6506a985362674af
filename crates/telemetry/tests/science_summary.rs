//! A cloud watch logged to MCAP (issue 34): the watch waits its interval on the simulated clock
//! (the simulator's, the power model's and the log's), and its summary is on
//! `/bus/science/summary`, read back with the reader, equal to the one in the report and
//! accounting for every image.

use rovernav_executive::deliberative::WatchSummary;
use rovernav_executive::{Mission, Run, RunOptions, RunSettings};
use rovernav_harness::{JudgedRun, build_world};
use rovernav_telemetry::messages::topics;
use rovernav_telemetry::schema::check;
use rovernav_telemetry::{TelemetryRecorder, read_log};

const FRAMES: usize = 3;
const INTERVAL_S: f64 = 20.0;

/// The example sky-watch mission with only a cloud watch of `FRAMES` images `INTERVAL_S` apart.
fn cloud_watch_mission() -> Mission {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../missions/sky-watch.toml");
    let text = std::fs::read_to_string(&path).expect("the example mission");
    let (head, rest) = text.split_at(text.find("[[tasks]]").expect("its tasks"));
    let sky = &rest[rest.find("[[sky]]").expect("its sky")..];
    // A budget of 40 %: a crop around the cloud (half the image wide) is about 10 % of the three
    // images' raw volume, and each image has one.
    let task = format!(
        "[[tasks]]\nkind = \"cloud_watch\"\nframes = {FRAMES}\ninterval_s = {INTERVAL_S}\ntilt_deg = 25.0\nbudget = 0.4\n"
    );
    Mission::from_toml(&format!("{head}{task}\n{sky}"), "cloud watch").expect("mission")
}

#[test]
fn a_cloud_watch_waits_its_interval_and_logs_a_summary_of_every_image() {
    let mission = cloud_watch_mission();
    let mut world = build_world(&mission, "cloud watch").expect("world");
    world.sensor_model.navcam.width = 256;
    let model = world.sensor_model.clone();
    let dir = std::env::temp_dir().join(format!("rovernav-science-summary-{}", std::process::id()));
    let path = dir.join("telemetry.mcap");
    let mut recorder = TelemetryRecorder::create(&path).expect("log");
    let options = RunOptions::of(&mission, &world);
    let out = Run::new(world, RunSettings::of(&mission))
        .judged()
        .options(options)
        .observer(&mut recorder)
        .execute();
    recorder.finish().expect("log finished");
    let out = out.expect("run");
    let log = read_log(&path).expect("log read back");
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(out.report.outcome, "reached", "{}", out.report.message);

    // The summary in the log is the one in the report's task message.
    assert_eq!(log.science.len(), 1, "one watch, one summary: {:?}", log.topic_counts);
    let s = &log.science[0];
    let task = out.report.tasks.iter().find(|t| t.kind == "cloud_watch").expect("the watch task");
    assert_eq!(Some(s), WatchSummary::from_message(&task.message).as_ref(), "{}", task.message);
    assert_eq!((s.task, s.kind.as_str(), s.interval_s), (task.id, "clouds", INTERVAL_S));

    // It accounts for every image: one record each, images with events sent in full or as
    // crops while the budget lasts, the others summarised, the bytes adding up within the budget.
    assert_eq!((s.images, s.records.len()), (FRAMES, FRAMES), "{s:?}");
    let ids: Vec<String> = (0..FRAMES).map(|k| format!("{k:03}")).collect();
    assert_eq!(s.records.iter().map(|r| r.id.clone()).collect::<Vec<_>>(), ids);
    for r in &s.records {
        let kept = s.kept_full.contains(&r.id) || s.kept_crops.contains(&r.id);
        assert_eq!(kept, r.product != "summary_only", "{r:?}");
        assert!(!(kept && r.events.is_empty()), "an image without events is never sent: {r:?}");
    }
    let summarised: usize =
        s.records.iter().filter(|r| r.product == "summary_only").map(|r| r.events.len()).sum();
    assert_eq!(summarised, s.events_summary_only);
    assert!(s.images_with_events >= 1, "the rendered cloud is found: {s:?}");
    assert_eq!(s.images_with_events, s.records.iter().filter(|r| !r.events.is_empty()).count());
    assert_eq!(s.events, s.records.iter().map(|r| r.events.len()).sum::<usize>());
    assert_eq!(s.events_summary_only, 0, "40 % of the raw volume sends every event: {s:?}");
    let products: u64 = s.records.iter().map(|r| r.bytes).sum();
    assert_eq!(products + s.summary_bytes, s.bytes_sent);
    assert!(s.bytes_sent <= s.budget_bytes, "{s:?}");

    // Images `INTERVAL_S` apart on the simulated clock, and the clock moved on by
    // (FRAMES - 1) intervals plus one capture cycle (the sensor model's Navcam capture time
    // and one rest sample) from the first image to the end of the mission.
    let times = s.times_s();
    for w in times.windows(2) {
        assert!((w[1] - w[0] - INTERVAL_S).abs() < 1e-6, "times {times:?}");
    }
    let cycle_s = model.navcam.capture_time_s + 1.0 / model.sample_rate;
    let advance = out.report.sim_time_s - times[0];
    let want = (FRAMES - 1) as f64 * INTERVAL_S + cycle_s;
    assert!((advance - want).abs() < 1e-6, "clock moved {advance} s over the watch, want {want} s");

    // The log's frames and power readings moved with it: each capture's frame (and the power
    // model's reading in it) ends one capture cycle after its image.
    let capture_frames: Vec<f64> = log
        .frames
        .iter()
        .filter(|f| f.frame.t > times[0])
        .map(|f| f.frame.power.as_ref().expect("a power reading").t)
        .collect();
    assert_eq!(capture_frames.len(), FRAMES, "{capture_frames:?}");
    for (t_image, t_power) in times.iter().zip(&capture_frames) {
        assert!((t_power - t_image - cycle_s).abs() < 1e-6, "image {t_image} s, reading {t_power} s");
    }

    // The logged message satisfies the topic's schema (the one the channel declares).
    let schema = rovernav_executive::messages::topics::SCIENCE_SUMMARY.schema();
    check(&schema, &serde_json::to_value(s).unwrap()).expect("the summary fits its schema");
    assert_eq!(log.topic_counts.get(topics::SCIENCE_SUMMARY), Some(&1));

    // Replay rebuilds the report, the summary in its task message included.
    let replay = log.replay().expect("replay");
    let replayed = replay.report.tasks.iter().find(|t| t.kind == "cloud_watch").expect("the watch task");
    assert_eq!(WatchSummary::from_message(&replayed.message).as_ref(), Some(s));
}
