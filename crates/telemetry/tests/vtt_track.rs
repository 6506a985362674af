//! Visual target tracking's telemetry (issue 35 item 3): a track-only run logged to MCAP holds
//! one `/bus/vtt/track` record per image the task saw (the task's report counts them), each
//! with its template, match and score and fitting the topic's derived schema, and replay
//! rebuilds the report with the task's message and the run's traverse picture byte for byte
//! (the designated target and its estimates included).

use rovernav_executive::{Mission, Run};
use rovernav_harness::JudgedRun;
use rovernav_telemetry::messages::topics;
use rovernav_telemetry::schema::check;
use rovernav_telemetry::{TelemetryRecorder, read_log};

/// The default mission with its goal short of a rock 6.7 m ahead of the start and a
/// `track_target` of that rock's facing side beside the drive (the point and goal that
/// `rovernav-executive`'s `vtt_track_only` test picks on this yard).
fn mission() -> Mission {
    let text = rovernav_executive::mission::DEFAULT_MISSION_TOML
        .replace("[goal]\nx = 20.0\ny = 20.0", "[goal]\nx = 9.564\ny = 5.782");
    let task = "[[tasks]]\nkind = \"track_target\"\nx = 11.874\ny = 6.178\nz = 0.353\nparallel = true\n";
    Mission::from_toml(&format!("{text}\n{task}"), "track only").expect("mission")
}

#[test]
fn a_track_only_run_logs_one_record_per_image_and_replays() {
    let dir = std::env::temp_dir().join(format!("rovernav-vtt-track-{}", std::process::id()));
    let path = dir.join("telemetry.mcap");
    let mut recorder = TelemetryRecorder::create(&path).expect("log");
    let out = Run::mission(&mission(), "track only").expect("builds").observer(&mut recorder).execute();
    recorder.finish().expect("log finished");
    let out = out.expect("run");
    let log = read_log(&path).expect("log read back");
    let _ = std::fs::remove_dir_all(&dir);

    let task = out.report.tasks.iter().find(|t| t.kind == "track_target").expect("the task");
    assert_eq!(task.state, "success", "{}", task.message);
    let images: usize = task
        .message
        .split("all ")
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("image count in {}", task.message));
    assert!(images >= 2, "{}", task.message);
    // One record per image, in order, equal to what the bus carried.
    assert_eq!(log.vtt.len(), images, "{:?}", log.topic_counts);
    assert_eq!(log.topic_counts.get(topics::VTT_TRACK), Some(&(images as u64)));
    let schema = rovernav_executive::messages::topics::VTT_TRACK.schema();
    for (k, m) in log.vtt.iter().enumerate() {
        assert_eq!((m.image_index, m.task, m.mode.as_str()), (k + 1, task.id, "track_only"));
        check(&schema, &serde_json::to_value(m).unwrap()).expect("the record fits its schema");
        let t = m.template.as_ref().expect("a template");
        assert_eq!(t.pixels.len(), (t.width * t.height) as usize);
        if k == 0 {
            assert_eq!((m.status.as_str(), m.matched), ("designated", None));
        } else {
            let s = m.matched.expect("a match");
            assert_eq!(m.status, "tracked");
            assert!(s.score >= 0.6 && s.score <= 1.0 && s.second < s.score, "{s:?}");
            assert_eq!(m.pixel, Some([s.x, s.y]));
        }
    }
    // Replay rebuilds the report, the task's message included.
    let replay = log.replay().expect("replay");
    let replayed = replay.report.tasks.iter().find(|t| t.kind == "track_target").expect("the task");
    assert_eq!(replayed.message, task.message);
    // The picture marks the designation and one estimate per later image, from the run's
    // deliberative layer and from the log alike, and the two pictures are the same bytes.
    assert_eq!(out.trace.vtt.len(), 1, "{:?}", out.trace.vtt);
    let site = |k: usize| log.vtt[k].site.expect("a site position");
    assert_eq!(out.trace.vtt[0].target, site(0));
    assert_eq!(out.trace.vtt[0].estimates, (1..images).map(site).collect::<Vec<_>>());
    assert_eq!(replay.trace.vtt, out.trace.vtt);
    let run_png = rovernav_viz::run_traverse_png(&out.report, &out.world, &out.trace).expect("png");
    let replay_png =
        rovernav_viz::run_traverse_png(&replay.report, &replay.world, &replay.trace).expect("png");
    assert!(run_png == replay_png, "replay draws the run's traverse.png");
}
