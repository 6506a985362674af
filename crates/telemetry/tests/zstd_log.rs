//! The log is written with zstd chunks (what the Python and Rust `mcap` writers produce by
//! default, and a third smaller than lz4 here); the same messages re-encoded with lz4 (earlier
//! rovernav logs) read and replay as the same run (issue 44).

mod common;

use rovernav_telemetry::{mcap, parse_log};

#[test]
fn the_zstd_log_and_its_lz4_reencoding_replay_as_the_same_run() {
    let (zstd, lz4) = common::zstd_and_lz4_logs("zstd", 400, 64 * 1024);
    let summary = mcap::Summary::read(&zstd).unwrap().expect("a finished log has a summary");
    assert!(!summary.chunk_indexes.is_empty());
    assert!(summary.chunk_indexes.iter().all(|c| c.compression == "zstd"), "the log is written with zstd");
    let written = parse_log(&zstd, "zstd.mcap".as_ref()).unwrap();
    let recoded = parse_log(&lz4, "lz4.mcap".as_ref()).unwrap();
    assert!(recoded.end.truncated.is_none(), "{:?}", recoded.end.truncated);
    assert_eq!(recoded.end.messages, written.end.messages);
    assert!(recoded.end.messages > 100, "{} messages", recoded.end.messages);
    let (a, b) = (written.replay().unwrap(), recoded.replay().unwrap());
    assert!(b.complete);
    assert_eq!(serde_json::to_string(&b.report).unwrap(), serde_json::to_string(&a.report).unwrap());
}
