//! Logs shared by the telemetry tests: a short traverse logged as `rovernav run` logs it (zstd),
//! and the same messages re-encoded with lz4 (what earlier rovernav logs and other writers use).

use rovernav_executive::{Run, RunSettings};
use rovernav_harness::{JudgedRun, long_yard_world};
use rovernav_telemetry::{FlushPolicy, TelemetryRecorder, TelemetryWriter, mcap};
use std::io::Cursor;
use std::time::Duration;

/// The bytes of the small yard's log (`max_cycles` at most, chunks closed at `chunk_bytes`) and
/// of its lz4 re-encoding; `name` keeps concurrent tests' files apart.
pub fn zstd_and_lz4_logs(name: &str, max_cycles: u64, chunk_bytes: u64) -> (Vec<u8>, Vec<u8>) {
    let path = std::env::temp_dir().join(format!("rovernav-telemetry-{name}-{}.mcap", std::process::id()));
    let policy = FlushPolicy { max_interval: Duration::from_secs(3600), max_chunk_bytes: chunk_bytes };
    let mut recorder = TelemetryRecorder::new(TelemetryWriter::create(&path, policy).unwrap()).unwrap();
    let settings = RunSettings {
        navigator: "astar-grid".into(),
        localizer: "dead-reckoning".into(),
        seed: 3,
        time_limit_s: 3600.0,
        max_cycles,
        name: format!("{name}-yard"),
        navigator_params: Default::default(),
    };
    Run::new(long_yard_world(3, 5.0, 4.0, 1.0), settings).judged().observer(&mut recorder).execute().unwrap();
    recorder.finish().unwrap();
    let zstd = std::fs::read(&path).unwrap();
    let _ = std::fs::remove_file(&path);
    // Every message re-written, in order, into lz4 chunks.
    let mut lz4 = Cursor::new(Vec::new());
    let mut writer =
        mcap::WriteOptions::new().compression(Some(mcap::Compression::Lz4)).create(&mut lz4).unwrap();
    for message in mcap::MessageStream::new(&zstd).unwrap() {
        writer.write(&message.unwrap()).unwrap();
    }
    writer.finish().unwrap();
    drop(writer);
    (zstd, lz4.into_inner())
}
