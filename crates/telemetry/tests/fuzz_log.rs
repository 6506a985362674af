//! Fuzz target of the MCAP reader (issue 44): a small run's log (zstd, as `rovernav run` writes
//! it, and re-encoded with lz4), mutated byte by byte, cut anywhere, or with a record length,
//! chunk size or grid size overwritten with a huge value, is read and replayed without a panic
//! or an abort. `PROPTEST_CASES` sets the cases.

mod common;

use proptest::prelude::*;
use rovernav_telemetry::parse_log;
use std::sync::OnceLock;

/// The seed logs: one zstd log of a short traverse and its lz4 re-encoding.
fn seeds() -> &'static [Vec<u8>; 2] {
    static SEEDS: OnceLock<[Vec<u8>; 2]> = OnceLock::new();
    SEEDS.get_or_init(|| {
        let (zstd, lz4) = common::zstd_and_lz4_logs("fuzz", 40, 16 * 1024);
        [zstd, lz4]
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
