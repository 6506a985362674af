//! Fuzz target of the MCAP reader (issue 44): a small run's log (lz4, as `rovernav run` writes
//! it, and re-encoded with zstd), mutated byte by byte, cut anywhere, or with a record length,
//! chunk size or grid size overwritten with a huge value, is read and replayed without a panic
//! or an abort. `PROPTEST_CASES` sets the cases.

use proptest::prelude::*;
use rovernav_executive::{Run, RunSettings, long_yard_world};
use rovernav_telemetry::{FlushPolicy, TelemetryRecorder, TelemetryWriter, mcap, parse_log};
use std::io::Cursor;
use std::sync::OnceLock;
use std::time::Duration;

/// The seed logs: one lz4 log of a short traverse and its zstd re-encoding.
fn seeds() -> &'static [Vec<u8>; 2] {
    static SEEDS: OnceLock<[Vec<u8>; 2]> = OnceLock::new();
    SEEDS.get_or_init(|| {
        let path = std::env::temp_dir().join(format!("rovernav-fuzz-log-{}.mcap", std::process::id()));
        let policy = FlushPolicy { max_interval: Duration::from_secs(3600), max_chunk_bytes: 16 * 1024 };
        let mut recorder = TelemetryRecorder::new(TelemetryWriter::create(&path, policy).unwrap()).unwrap();
        let settings = RunSettings {
            navigator: "astar-grid".into(),
            localizer: "dead-reckoning".into(),
            seed: 3,
            time_limit_s: 3600.0,
            max_cycles: 40,
            name: "fuzz-yard".into(),
            navigator_params: Default::default(),
        };
        Run::new(long_yard_world(3, 4.0, 3.0, 1.0), settings).observer(&mut recorder).execute().unwrap();
        recorder.finish().unwrap();
        let lz4 = std::fs::read(&path).unwrap();
        let _ = std::fs::remove_file(&path);
        let mut zstd = Cursor::new(Vec::new());
        let mut writer =
            mcap::WriteOptions::new().compression(Some(mcap::Compression::Zstd)).create(&mut zstd).unwrap();
        for message in mcap::MessageStream::new(&lz4).unwrap() {
            writer.write(&message.unwrap()).unwrap();
        }
        writer.finish().unwrap();
        drop(writer);
        [lz4, zstd.into_inner()]
    })
}

/// Edits: a byte set, a little-endian u64 or u32 written (huge lengths and sizes), a cut.
#[derive(Clone, Debug)]
enum Edit {
    Byte(usize, u8),
    U64(usize, u64),
    U32(usize, u32),
    Cut(usize),
}

fn edit() -> impl Strategy<Value = Edit> {
    let huge = prop_oneof![Just(u64::MAX), Just(1u64 << 40), Just(1u64 << 32), any::<u64>()];
    prop_oneof![
        (any::<usize>(), any::<u8>()).prop_map(|(p, b)| Edit::Byte(p, b)),
        (any::<usize>(), huge).prop_map(|(p, v)| Edit::U64(p, v)),
        (any::<usize>(), any::<u32>()).prop_map(|(p, v)| Edit::U32(p, v)),
        any::<usize>().prop_map(Edit::Cut),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn fuzz_mcap_reader_and_replay(which in 0..2usize, edits in proptest::collection::vec(edit(), 1..4)) {
        let mut b = seeds()[which].clone();
        for e in edits {
            let n = b.len().max(1);
            match e {
                Edit::Byte(p, v) => b[p % n] = v,
                Edit::U64(p, v) if b.len() >= 8 => {
                    let i = p % (b.len() - 7);
                    b[i..i + 8].copy_from_slice(&v.to_le_bytes());
                }
                Edit::U32(p, v) if b.len() >= 4 => {
                    let i = p % (b.len() - 3);
                    b[i..i + 4].copy_from_slice(&v.to_le_bytes());
                }
                Edit::Cut(p) => b.truncate(p % n),
                _ => {}
            }
        }
        if let Ok(log) = parse_log(&b, "fuzz.mcap".as_ref()) {
            let _ = log.replay();
        }
    }
}
