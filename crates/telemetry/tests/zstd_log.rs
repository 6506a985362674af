//! A log compressed with zstd (what the Python and Rust `mcap` writers produce by default)
//! reads and replays as the same run as the lz4 log it was re-encoded from (issue 44).

use rovernav_executive::{Run, RunSettings, long_yard_world};
use rovernav_telemetry::{FlushPolicy, TelemetryRecorder, TelemetryWriter, mcap, parse_log};
use std::io::Cursor;
use std::time::Duration;

#[test]
fn a_zstd_compressed_log_replays_as_the_lz4_log_it_was_reencoded_from() {
    let dir = std::env::temp_dir().join(format!("rovernav-telemetry-zstd-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("telemetry.mcap");
    let policy = FlushPolicy { max_interval: Duration::from_secs(3600), max_chunk_bytes: 64 * 1024 };
    let mut recorder = TelemetryRecorder::new(TelemetryWriter::create(&path, policy).unwrap()).unwrap();
    let settings = RunSettings {
        navigator: "astar-grid".into(),
        localizer: "dead-reckoning".into(),
        seed: 3,
        time_limit_s: 3600.0,
        max_cycles: 400,
        name: "zstd-yard".into(),
        navigator_params: Default::default(),
    };
    Run::new(long_yard_world(3, 5.0, 4.0, 1.0), settings).observer(&mut recorder).execute().unwrap();
    recorder.finish().unwrap();
    let lz4 = std::fs::read(&path).unwrap();
    let _ = std::fs::remove_dir_all(&dir);

    // Every message re-written, in order, into zstd chunks.
    let mut zstd = Cursor::new(Vec::new());
    {
        let mut writer =
            mcap::WriteOptions::new().compression(Some(mcap::Compression::Zstd)).create(&mut zstd).unwrap();
        for message in mcap::MessageStream::new(&lz4).unwrap() {
            writer.write(&message.unwrap()).unwrap();
        }
        writer.finish().unwrap();
    }
    let zstd = zstd.into_inner();
    assert_ne!(zstd, lz4);

    let original = parse_log(&lz4, "lz4.mcap".as_ref()).unwrap();
    let recoded = parse_log(&zstd, "zstd.mcap".as_ref()).unwrap();
    assert!(recoded.end.truncated.is_none(), "{:?}", recoded.end.truncated);
    assert_eq!(recoded.end.messages, original.end.messages);
    assert!(recoded.end.messages > 100, "{} messages", recoded.end.messages);
    let (a, b) = (original.replay().unwrap(), recoded.replay().unwrap());
    assert!(b.complete);
    assert_eq!(serde_json::to_string(&b.report).unwrap(), serde_json::to_string(&a.report).unwrap());
}
