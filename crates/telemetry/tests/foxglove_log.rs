//! The log as Foxglove reads it (issue 45 item 2): each sensor frame once, the rover's frames
//! every cycle agreeing with the logged estimate and truth, the belief map on every cycle that
//! brought range data and agreeing with the true terrain, the plan in the scene as announced.

use rovernav_executive::{Run, RunSettings};
use rovernav_harness::{JudgedRun, long_yard_world};
use rovernav_telemetry::foxglove::{FrameTransformMsg, GridMsg, SceneUpdateMsg, topics as fox};
use rovernav_telemetry::messages::topics;
use rovernav_telemetry::{FlushPolicy, TelemetryRecorder, TelemetryWriter, mcap, parse_log};
use serde_json::Value;
use std::collections::BTreeMap;
use std::time::Duration;

/// Messages by topic: `(log time, JSON)`.
type ByTopic = BTreeMap<String, Vec<(u64, Value)>>;

/// The small yard's log and its messages by topic.
fn logged() -> (Vec<u8>, ByTopic) {
    let path = std::env::temp_dir().join(format!("rovernav-foxglove-{}.mcap", std::process::id()));
    let policy = FlushPolicy { max_interval: Duration::from_secs(3600), max_chunk_bytes: 1 << 20 };
    let mut recorder = TelemetryRecorder::new(TelemetryWriter::create(&path, policy).unwrap()).unwrap();
    let settings = RunSettings {
        navigator: "astar-grid".into(),
        localizer: "dead-reckoning".into(),
        seed: 5,
        time_limit_s: 3600.0,
        max_cycles: 400,
        name: "foxglove-yard".into(),
        navigator_params: Default::default(),
    };
    let out = Run::new(long_yard_world(5, 6.0, 4.0, 1.0), settings)
        .judged()
        .observer(&mut recorder)
        .execute()
        .unwrap();
    recorder.finish().unwrap();
    assert_eq!(out.report.outcome, "reached");
    let bytes = std::fs::read(&path).unwrap();
    let _ = std::fs::remove_file(&path);
    let mut by_topic = ByTopic::new();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        by_topic
            .entry(m.channel.topic.clone())
            .or_default()
            .push((m.log_time, serde_json::from_slice(&m.data).unwrap()));
    }
    (bytes, by_topic)
}

fn of<T: serde::de::DeserializeOwned>(v: &Value) -> T {
    serde_json::from_value(v.clone()).unwrap()
}

#[test]
fn foxglove_topics_follow_the_run_and_frames_are_logged_once() {
    let (bytes, by_topic) = logged();
    let get = |t: &str| by_topic.get(t).cloned().unwrap_or_default();
    let cycles = get(topics::CYCLE);
    let n = cycles.len();
    assert!(n > 5, "{n} cycles");

    // Each frame once: the cycle's message points at the bus frame and holds nothing else.
    let frames = get(topics::SENSOR_FRAME);
    let bus_frames = get("/bus/platform/frame");
    assert_eq!(frames.len(), n);
    for (_, f) in &frames {
        assert!(f.get("frame").is_none() && f["bus_seq"].is_u64(), "{f}");
    }
    let seqs: Vec<u64> = frames.iter().map(|(_, f)| f["bus_seq"].as_u64().unwrap()).collect();
    assert!(seqs.iter().all(|s| bus_frames.iter().any(|(_, b)| b["seq"].as_u64() == Some(*s))));
    let run = parse_log(&bytes, "foxglove.mcap".as_ref()).unwrap();
    assert_eq!(run.frames.len(), n, "every cycle's frame resolved from the bus");

    // The frames every cycle, equal to the logged estimate and truth.
    let (tf, truth_tf) = (get(fox::TF), get(fox::TRUTH_TF));
    assert_eq!((tf.len(), truth_tf.len()), (n, n));
    for ((est, tr), ((_, e), (_, t))) in
        get(topics::ESTIMATE).iter().zip(get(topics::TRUTH).iter()).zip(tf.iter().zip(truth_tf.iter()))
    {
        let (e, t): (FrameTransformMsg, FrameTransformMsg) = (of(e), of(t));
        assert_eq!((e.parent_frame_id.as_str(), e.child_frame_id.as_str()), ("map", "rover"));
        assert_eq!(t.child_frame_id, "rover_truth");
        assert_eq!(
            (e.translation.x, e.translation.y),
            (est.1["pose"]["x"].as_f64().unwrap(), est.1["pose"]["y"].as_f64().unwrap())
        );
        assert_eq!(
            (t.translation.x, t.translation.y),
            (tr.1["pose"]["x"].as_f64().unwrap(), tr.1["pose"]["y"].as_f64().unwrap())
        );
        let q = e.rotation;
        let yaw = (2.0 * (q.w * q.z + q.x * q.y)).atan2(1.0 - 2.0 * (q.y * q.y + q.z * q.z));
        let logged_yaw = est.1["pose"]["yaw"].as_f64().unwrap();
        assert!(
            (yaw - logged_yaw).sin().abs() < 1e-9 && (yaw - logged_yaw).cos() > 0.0,
            "{yaw} {logged_yaw}"
        );
    }

    // A scene update and a log line every cycle; the log names each command.
    for t in [fox::SCENE, fox::TRUTH_SCENE] {
        let times: Vec<u64> = get(t).iter().map(|(time, _)| *time).collect();
        for (time, _) in &cycles {
            assert!(times.contains(time), "{t}: nothing at {time}");
        }
    }
    let log_lines: Vec<String> =
        get(fox::LOG).iter().map(|(_, l)| l["message"].as_str().unwrap().to_string()).collect();
    assert_eq!(log_lines.iter().filter(|l| l.starts_with("cycle ")).count(), n - 1);
    assert!(log_lines.last().unwrap().starts_with("reached"), "{log_lines:?}");

    // The plan entity as the navigator announced each plan (millimetres).
    let plans = get(topics::PLAN);
    let scene_plans: Vec<Vec<(f64, f64)>> = get(fox::SCENE)
        .iter()
        .flat_map(|(_, s)| of::<SceneUpdateMsg>(s).entities)
        .filter(|e| e.id == "plan")
        .map(|e| e.lines[0].points.iter().map(|p| (p.x, p.y)).collect())
        .collect();
    assert_eq!(scene_plans.len(), plans.len(), "one plan entity per announced plan");
    for (scene, (_, plan)) in scene_plans.iter().zip(&plans) {
        let pts = plan["points"].as_array().unwrap();
        assert_eq!(scene.len(), pts.len());
        for (s, p) in scene.iter().zip(pts) {
            assert!(
                (s.0 - p["x"].as_f64().unwrap()).abs() <= 5e-4
                    && (s.1 - p["y"].as_f64().unwrap()).abs() <= 5e-4
            );
        }
    }

    // The belief map after every cycle whose frame brought range data, and only then.
    let sensing: Vec<u64> =
        run.frames.iter().skip(1).filter(|f| !f.frame.clouds.is_empty()).map(|f| f.cycle).collect();
    assert!(!sensing.is_empty());
    let grid_times: Vec<u64> = get(fox::BELIEF_GRID).iter().map(|(t, _)| *t).collect();
    let sensing_times: Vec<u64> = sensing.iter().map(|&c| cycles[c as usize].0).collect();
    assert_eq!(grid_times, sensing_times);
    assert_eq!(get(fox::TRAVERSABILITY_GRID).len(), sensing.len());

    // The last belief map agrees with the true terrain where it knows a height.
    let world = run.replay().unwrap().world;
    let grid: GridMsg = of(&get(fox::BELIEF_GRID).last().unwrap().1);
    let cells = grid.bytes().unwrap();
    let cols = grid.column_count as usize;
    // Against the true height under each cell: the heights follow the terrain, much better than
    // they follow the true heights 1 m away (a misplaced map).
    let correlation = |dx: f64| {
        let mut pairs = Vec::new();
        for (i, b) in cells.chunks_exact(4).enumerate() {
            let h = f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
            let x = grid.pose.position.x + ((i % cols) as f64 + 0.5) * grid.cell_size.x + dx;
            let y = grid.pose.position.y + ((i / cols) as f64 + 0.5) * grid.cell_size.y;
            if let (true, Some(truth)) = (h.is_finite(), world.terrain.dem.height(x, y)) {
                pairs.push((f64::from(h), truth));
            }
        }
        assert!(pairs.len() > 100, "{} known cells", pairs.len());
        let n = pairs.len() as f64;
        let (ma, mb) =
            (pairs.iter().map(|p| p.0).sum::<f64>() / n, pairs.iter().map(|p| p.1).sum::<f64>() / n);
        let cov: f64 = pairs.iter().map(|p| (p.0 - ma) * (p.1 - mb)).sum();
        let va: f64 = pairs.iter().map(|p| (p.0 - ma).powi(2)).sum();
        let vb: f64 = pairs.iter().map(|p| (p.1 - mb).powi(2)).sum();
        cov / (va * vb).sqrt()
    };
    let (placed, misplaced) = (correlation(0.0), correlation(1.0));
    eprintln!("correlation of belief and true heights: {placed:.3}, 1 m off: {misplaced:.3}");
    // (1 - r: what the map leaves unexplained; the yard's slope alone correlates well.)
    assert!(placed > 0.9 && 1.0 - placed < (1.0 - misplaced) / 2.0, "{placed} (1 m off: {misplaced})");
}
