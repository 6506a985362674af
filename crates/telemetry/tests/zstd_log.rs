//! A log compressed with zstd (what the Python and Rust `mcap` writers produce by default)
//! reads and replays as the same run as the lz4 log it was re-encoded from (issue 44).

mod common;

use rovernav_telemetry::parse_log;

#[test]
fn a_zstd_compressed_log_replays_as_the_lz4_log_it_was_reencoded_from() {
    let (lz4, zstd) = common::lz4_and_zstd_logs("zstd", 400, 64 * 1024);
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
