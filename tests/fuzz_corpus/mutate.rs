//! Seed corpus and mutations shared by the fuzz targets (issue 44): each target's seeds are the
//! files of `tests/fuzz_corpus/<target>/`, and an input is a seed with a few byte edits and
//! dictionary splices. Included by the fuzz tests with `#[path]`.

// Each fuzz test uses part of this support.
#![allow(dead_code)]

use proptest::prelude::*;
use std::path::{Path, PathBuf};

/// Tokens that broke or nearly broke the parsers: spliced in place of a number or a word.
pub const DICTIONARY: &[&str] = &[
    "nan",
    "inf",
    "-inf",
    "1e308",
    "-1e308",
    "0",
    "-0",
    "-1",
    "1e-300",
    "18446744073709551615",
    "4294967296",
    "\"../x\"",
    "\"/tmp/x\"",
    "\"\"",
    "[]",
    "[[]]",
    "{}",
    "\u{ff}",
    "999999999",
    "\n",
];

pub fn corpus(target: &str) -> Vec<(PathBuf, Vec<u8>)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/fuzz_corpus").join(target);
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    files.into_iter().map(|p| (p.clone(), std::fs::read(&p).unwrap())).collect()
}

/// One edit of a seed: overwrite, insert or delete a byte, truncate, or splice a dictionary
/// token over the run of digits (or letters) at a position.
#[derive(Clone, Debug)]
pub enum Edit {
    Set(usize, u8),
    Insert(usize, u8),
    Delete(usize),
    Truncate(usize),
    Splice(usize, usize),
}

pub fn edits() -> impl Strategy<Value = Vec<Edit>> {
    let edit = prop_oneof![
        (any::<usize>(), any::<u8>()).prop_map(|(p, b)| Edit::Set(p, b)),
        (any::<usize>(), any::<u8>()).prop_map(|(p, b)| Edit::Insert(p, b)),
        any::<usize>().prop_map(Edit::Delete),
        any::<usize>().prop_map(Edit::Truncate),
        (any::<usize>(), 0..DICTIONARY.len()).prop_map(|(p, d)| Edit::Splice(p, d)),
        (any::<usize>(), 0..DICTIONARY.len()).prop_map(|(p, d)| Edit::Splice(p, d)),
    ];
    proptest::collection::vec(edit, 0..6)
}

pub fn mutate(seed: &[u8], edits: &[Edit]) -> Vec<u8> {
    let mut b = seed.to_vec();
    for e in edits {
        let at = |p: usize, len: usize| if len == 0 { 0 } else { p % len };
        match *e {
            Edit::Set(p, v) if !b.is_empty() => {
                let i = at(p, b.len());
                b[i] = v;
            }
            Edit::Insert(p, v) => b.insert(at(p, b.len() + 1), v),
            Edit::Delete(p) if !b.is_empty() => {
                b.remove(at(p, b.len()));
            }
            Edit::Truncate(p) => b.truncate(at(p, b.len() + 1)),
            Edit::Splice(p, d) if !b.is_empty() => {
                let i = at(p, b.len());
                let word = |c: u8| c.is_ascii_alphanumeric() || b".-+".contains(&c);
                let (mut s, mut t) = (i, i);
                while s > 0 && word(b[s - 1]) {
                    s -= 1;
                }
                while t < b.len() && word(b[t]) {
                    t += 1;
                }
                b.splice(s..t, DICTIONARY[d].bytes());
            }
            _ => {}
        }
    }
    b
}

/// A seed of `target` and edits to apply to it.
pub fn input(target: &'static str) -> impl Strategy<Value = (PathBuf, Vec<u8>)> {
    let seeds = corpus(target);
    (0..seeds.len(), edits()).prop_map(move |(i, e)| (seeds[i].0.clone(), mutate(&seeds[i].1, &e)))
}
