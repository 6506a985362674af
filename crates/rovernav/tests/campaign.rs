//! `rovernav campaign`: a campaign split into four shards and merged gives the summary of the
//! unsharded campaign, byte for byte; bad input ends with one line naming what is wrong.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Job-array variables the tests must not inherit from a cluster they might run on.
const ARRAY_VARS: [&str; 6] = [
    "SLURM_ARRAY_TASK_ID",
    "SLURM_ARRAY_TASK_COUNT",
    "SLURM_ARRAY_TASK_MIN",
    "SLURM_ARRAY_TASK_STEP",
    "JOB_COMPLETION_INDEX",
    "ROVERNAV_SHARD_COUNT",
];

fn rovernav_with_env(args: &[&str], env: &[(&str, &str)]) -> (bool, String, String) {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_rovernav"));
    for v in ARRAY_VARS {
        cmd.env_remove(v);
    }
    cmd.envs(env.iter().copied());
    let out = cmd.args(args).output().expect("binary runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).to_string(),
        String::from_utf8_lossy(&out.stderr).trim().to_string(),
    )
}

fn rovernav(args: &[&str]) -> (bool, String, String) {
    rovernav_with_env(args, &[])
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("rovernav-campaign-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A fresh folder holding the tiny campaign file, and the file's path.
fn tiny_campaign(name: &str) -> (PathBuf, PathBuf) {
    let dir = temp_dir(name);
    let spec = dir.join("tiny.toml");
    std::fs::write(&spec, TINY).unwrap();
    (dir, spec)
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Small yards and a short cycle budget keep the debug build fast; the budget also makes some
/// runs fail (timeout) so the failure gallery is exercised.
const TINY: &str = r#"
name = "tiny"
seed = 11
trials = 4
navigators = ["astar-grid", "roverbug"]
max_cycles = 6

[yard]
size_m = 12.0
rock_abundance = [0.02, 0.06]
slope_deg = { min = 0.0, max = 3.0 }
relief_m = 0.1
"#;

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// The deterministic part of summary.json (everything before the machine-dependent block).
fn deterministic_json(dir: &Path) -> String {
    let text = read(&dir.join("summary.json"));
    let cut = text.find("\"machine_dependent\"").expect("machine_dependent block");
    text[..cut].to_string()
}

/// The deterministic part of summary.md.
fn deterministic_md(dir: &Path) -> String {
    let text = read(&dir.join("summary.md"));
    let cut = text.find("## Compute per cycle (machine-dependent)").expect("compute section");
    text[..cut].to_string()
}

/// rows.jsonl without the wall-clock fields.
fn deterministic_rows(dir: &Path) -> Vec<Value> {
    read(&dir.join("rows.jsonl"))
        .lines()
        .map(|l| {
            let mut v: Value = serde_json::from_str(l).unwrap();
            let o = v.as_object_mut().unwrap();
            o.remove("compute_per_cycle").expect("compute_per_cycle");
            o.remove("wall_time_s").expect("wall_time_s");
            v
        })
        .collect()
}

#[test]
fn four_shards_merged_equal_the_unsharded_campaign() {
    let (dir, spec) = tiny_campaign("shards");
    let whole = dir.join("whole");
    let (ok, stdout, err) = rovernav(&["campaign", s(&spec), "--out", s(&whole), "--json"]);
    assert!(ok, "{err}");
    let printed: Value = serde_json::from_str(&stdout).expect("--json prints summary.json");
    assert_eq!(printed, serde_json::from_str::<Value>(&read(&whole.join("summary.json"))).unwrap());

    // Shard 2 comes from a Slurm array's environment (task ids 0..3), the others from --shard.
    let mut shard_dirs = Vec::new();
    for i in 1..=4 {
        let out = dir.join(format!("shard{i}"));
        let (ok, _, err) = if i == 2 {
            rovernav_with_env(
                &["campaign", s(&spec), "--out", s(&out)],
                &[("SLURM_ARRAY_TASK_ID", "1"), ("SLURM_ARRAY_TASK_COUNT", "4")],
            )
        } else {
            rovernav(&["campaign", s(&spec), "--out", s(&out), "--shard", &format!("{i}/4")])
        };
        assert!(ok, "shard {i}: {err}");
        let shard: Value = serde_json::from_str(&read(&out.join("campaign.json"))).unwrap();
        assert_eq!(shard["shard"]["index"], i, "shard {i}");
        shard_dirs.push(out);
    }
    let merged = dir.join("merged");
    let mut args = vec!["campaign", "merge"];
    args.extend(shard_dirs.iter().rev().map(|d| s(d)));
    args.extend(["--out", s(&merged)]);
    let (ok, stdout, err) = rovernav(&args);
    assert!(ok, "{err}");
    assert!(stdout.contains("| astar-grid |") && stdout.contains("(machine-dependent)"), "{stdout}");

    assert_eq!(deterministic_json(&merged), deterministic_json(&whole));
    assert_eq!(deterministic_md(&merged), deterministic_md(&whole));
    assert_eq!(deterministic_rows(&merged), deterministic_rows(&whole));
    for plot in ["plots/success_vs_rock_abundance.svg", "plots/path_ratio.svg"] {
        assert_eq!(read(&merged.join(plot)), read(&whole.join(plot)), "{plot}");
    }

    // The rows hold every (trial, navigator) once, and the summary counts what they say.
    let rows = deterministic_rows(&whole);
    assert_eq!(rows.len(), 8);
    let mut keys: Vec<(u64, String)> = rows
        .iter()
        .map(|r| (r["trial"].as_u64().unwrap(), r["navigator"].as_str().unwrap().into()))
        .collect();
    keys.dedup();
    assert_eq!(keys.len(), 8);
    assert!(rows.iter().all(|r| r["cycles"].as_u64().unwrap() <= 6));
    let summary: Value = serde_json::from_str(&read(&whole.join("summary.json"))).unwrap();
    for nav in summary["summary"]["navigators"].as_array().unwrap() {
        let name = nav["navigator"].as_str().unwrap();
        let mine: Vec<&Value> = rows.iter().filter(|r| r["navigator"] == name).collect();
        let ok = mine.iter().filter(|r| r["outcome"] == "reached" && r["hazard_contacts"] == 0).count();
        assert_eq!((nav["runs"].as_u64(), nav["successes"].as_u64()), (Some(4), Some(ok as u64)), "{name}");
    }
    // Every failed run has its traverse picture in the merged gallery.
    let failed: Vec<&Value> =
        rows.iter().filter(|r| !(r["outcome"] == "reached" && r["hazard_contacts"] == 0)).collect();
    assert!(!failed.is_empty(), "six cycles are too few to reach a goal 8.5 m away every time");
    for r in failed {
        let png = merged.join(format!(
            "failures/trial-{:04}-{}.png",
            r["trial"].as_u64().unwrap(),
            r["navigator"].as_str().unwrap()
        ));
        let bytes = std::fs::read(&png).unwrap_or_else(|e| panic!("{}: {e}", png.display()));
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "{}", png.display());
    }

    // Overlapping, incomplete and foreign shards are refused with one line.
    let (ok, _, err) =
        rovernav(&["campaign", "merge", s(&shard_dirs[0]), s(&shard_dirs[0]), "--out", s(&dir.join("m2"))]);
    assert_one_line_error(ok, &err, &["merge", "trial 0", "shard1"]);
    let (ok, _, err) =
        rovernav(&["campaign", "merge", s(&shard_dirs[0]), s(&shard_dirs[1]), "--out", s(&dir.join("m3"))]);
    assert_one_line_error(ok, &err, &["merge", "missing"]);
    let other = dir.join("other");
    let (ok, _, err) = rovernav(&[
        "campaign",
        s(&spec),
        "--seed",
        "12",
        "--trials",
        "1",
        "--out",
        s(&other),
        "--shard",
        "3/4",
    ]);
    assert!(ok, "{err}");
    let m4 = dir.join("m4");
    let mut args = vec!["campaign", "merge"];
    args.extend(shard_dirs.iter().map(|d| s(d)));
    args.extend([s(&other), "--out", s(&m4)]);
    let (ok, _, err) = rovernav(&args);
    assert_one_line_error(ok, &err, &["merge", "not slices of the same campaign"]);
    let (ok, _, err) = rovernav(&["campaign", "merge", s(&shard_dirs[0]), "--out", s(&shard_dirs[0])]);
    assert_one_line_error(ok, &err, &["merge", "one of the inputs"]);
}

fn assert_one_line_error(ok: bool, stderr: &str, must_contain: &[&str]) {
    assert!(!ok, "expected failure, stderr: {stderr}");
    assert!(!stderr.contains("panicked"), "panic: {stderr}");
    assert_eq!(stderr.lines().count(), 1, "not one line: {stderr}");
    for part in must_contain {
        assert!(stderr.contains(part), "`{part}` missing from: {stderr}");
    }
}

#[test]
fn bad_input_is_one_line_naming_what_is_wrong() {
    let dir = temp_dir("bad");
    let out = dir.join("out");
    let (ok, _, err) = rovernav(&["campaign", "--navigators", "astar-grid,warp-drive", "--out", s(&out)]);
    assert_one_line_error(ok, &err, &["--navigators", "warp-drive"]);

    let spec = dir.join("bad.toml");
    std::fs::write(&spec, TINY.replace("seed = 11", "seed = = 11")).unwrap();
    let (ok, _, err) = rovernav(&["campaign", s(&spec), "--out", s(&out)]);
    assert_one_line_error(ok, &err, &["bad.toml", "line 3"]);

    std::fs::write(&spec, TINY.replace("relief_m = 0.1", "relief = 0.1")).unwrap();
    let (ok, _, err) = rovernav(&["campaign", s(&spec), "--out", s(&out)]);
    assert_one_line_error(ok, &err, &["bad.toml", "relief"]);

    std::fs::write(&spec, TINY.replace("rock_abundance = [0.02, 0.06]", "rock_abundance = [0.02, 0.9]"))
        .unwrap();
    let (ok, _, err) = rovernav(&["campaign", s(&spec), "--out", s(&out)]);
    assert_one_line_error(ok, &err, &["bad.toml", "yard.rock_abundance", "0.9"]);

    let (ok, _, err) = rovernav(&["campaign", "/nonexistent/campaign.toml"]);
    assert_one_line_error(ok, &err, &["/nonexistent/campaign.toml"]);

    for shard in ["0/4", "5/4", "x", "1/0"] {
        let (ok, _, err) = rovernav(&["campaign", "--shard", shard, "--out", s(&out)]);
        assert_one_line_error(ok, &err, &["--shard", shard]);
    }
    let (ok, _, err) = rovernav_with_env(&["campaign", "--out", s(&out)], &[("JOB_COMPLETION_INDEX", "0")]);
    assert_one_line_error(ok, &err, &["JOB_COMPLETION_INDEX", "--shard-count"]);
    let (ok, _, err) = rovernav(&["campaign", "--shard-count", "4", "--out", s(&out)]);
    assert_one_line_error(ok, &err, &["--shard-count"]);

    let (ok, _, err) = rovernav(&["campaign", "merge", s(&dir.join("absent")), "--out", s(&out)]);
    assert_one_line_error(ok, &err, &["absent", "campaign.json"]);
    assert!(!out.exists(), "no output folder on bad input");
}

#[test]
fn compare_pairs_two_navigators_of_one_campaign_terrain_by_terrain() {
    let (dir, spec) = tiny_campaign("compare");
    let out = dir.join("out");
    let (ok, _, err) = rovernav(&["campaign", s(&spec), "--out", s(&out)]);
    assert!(ok, "{err}");
    let (ok, stdout, err) = rovernav(&[
        "campaign",
        "compare",
        s(&out),
        "--against",
        s(&out),
        "--a-navigator",
        "astar-grid",
        "--b-navigator",
        "roverbug",
        "--json",
    ]);
    assert!(ok, "{err}");
    let c: Value = serde_json::from_str(&stdout).expect("--json prints the comparison");
    // The independent truth: each navigator's rows in rows.jsonl, paired by terrain seed.
    let rows = deterministic_rows(&out);
    let clean = |nav: &str, seed: &Value| {
        rows.iter().any(|r| {
            r["navigator"] == nav
                && r["seed"] == *seed
                && r["outcome"] == "reached"
                && r["hazard_contacts"] == 0
        })
    };
    let seeds: Vec<Value> =
        rows.iter().filter(|r| r["navigator"] == "roverbug").map(|r| r["seed"].clone()).collect();
    assert_eq!(c["paired"], seeds.len());
    let a_only = seeds.iter().filter(|sd| clean("astar-grid", sd) && !clean("roverbug", sd)).count();
    let b_only = seeds.iter().filter(|sd| !clean("astar-grid", sd) && clean("roverbug", sd)).count();
    assert_eq!(c["clean_arrivals"]["a_only"], a_only);
    assert_eq!(c["clean_arrivals"]["b_only"], b_only);
    assert_eq!(c["a"]["navigator"], "astar-grid");
    assert_eq!(c["discordant"].as_array().unwrap().len(), a_only + b_only);
    // Without naming the navigators the mixed folder is refused in one line.
    let (ok, _, err) = rovernav(&["campaign", "compare", s(&out), "--against", s(&out)]);
    assert_one_line_error(ok, &err, &["compare", "--a-navigator", "astar-grid, roverbug"]);
}
