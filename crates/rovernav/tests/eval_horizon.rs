//! `rovernav eval horizon`: the sensing-horizon reference against the optimal length it must
//! come close to, and beside a campaign's runs on the same yards.

use std::path::PathBuf;
use std::process::Command;

/// Runs rovernav; returns success, stdout and stderr.
fn rovernav(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_rovernav")).args(args).output().expect("run rovernav");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("rovernav-horizon-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn num(v: &serde_json::Value, key: &str) -> f64 {
    v[key].as_f64().unwrap_or_else(|| panic!("field `{key}` missing: {v}"))
}

#[test]
fn the_reference_drives_no_shorter_than_the_optimal_path_allows_and_close_to_it() {
    let (ok, out, err) = rovernav(&["eval", "horizon", "--seeds", "1..2", "--json"]);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("JSON figures");
    let runs = v["runs_per_seed"].as_array().expect("runs_per_seed");
    assert_eq!(runs.len(), 2);
    // The default mission's goal tolerance.
    let tolerance = rovernav_executive::Mission::default_mission().goal.tolerance_m;
    for r in runs {
        assert_eq!(r["reached"], true, "{r}");
        let (driven, optimal) = (num(r, "driven_m"), num(r, "optimal_length_m"));
        // No safe path to the tolerance circle is shorter than the optimal path less the
        // tolerance (both planned on the same 0.1 m truth; 1 % for Field D*'s interpolation).
        assert!(driven >= 0.99 * (optimal - tolerance), "{r}");
        // Sensing all around 5 m ahead on a yard whose rocks leave gaps, it hardly detours.
        assert!(driven <= 1.1 * optimal, "{r}");
        assert!((num(r, "path_ratio") - driven / optimal).abs() < 1e-9);
    }
    assert!(num(&v, "path_ratio_mean") <= 1.1);
}

#[test]
fn a_mission_file_gives_its_own_terrain() {
    let mission = concat!(env!("CARGO_MANIFEST_DIR"), "/../../missions/roverbug-marsyard.toml");
    let (ok, out, err) = rovernav(&["eval", "horizon", "--mission", mission, "--seeds", "1", "--json"]);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("JSON figures");
    assert_eq!(v["mission"], "roverbug-marsyard");
    let run = &v["runs_per_seed"][0];
    assert_eq!(run["reached"], true, "{run}");
    // The mission's own terrain: its optimal length, not the default yard's of seed 1.
    let (ok, default, _) = rovernav(&["eval", "horizon", "--seeds", "1", "--json"]);
    assert!(ok);
    let default: serde_json::Value = serde_json::from_str(&default).unwrap();
    assert_ne!(run["optimal_length_m"], default["runs_per_seed"][0]["optimal_length_m"]);
    let (ok, _, err) = rovernav(&["eval", "horizon", "--mission", "no-such-mission.toml"]);
    assert!(!ok && err.contains("no-such-mission.toml") && !err.contains("panicked"), "{err}");
}

#[test]
fn a_campaign_of_other_yards_is_refused_and_bad_settings_are_named() {
    let (ok, _, err) = rovernav(&["eval", "horizon", "--fov", "400"]);
    assert!(!ok && err.contains("field of view 400"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    let (ok, _, err) = rovernav(&["eval", "horizon", "--seeds", "3..1"]);
    assert!(!ok && err.contains("--seeds"), "{err}");
    let dir = temp_dir("missing");
    let (ok, _, err) = rovernav(&["eval", "horizon", "--seeds", "1", "--against", dir.to_str().unwrap()]);
    assert!(!ok && err.contains("campaign.json"), "{err}");
}

/// Release speed: one RoverBug run on the default yard of seed 1.
#[test]
#[ignore]
fn against_a_campaign_the_navigator_ratio_stands_beside_the_reference() {
    let dir = temp_dir("against");
    let out = dir.join("campaign");
    let spec = concat!(env!("CARGO_MANIFEST_DIR"), "/../../campaigns/roverbug-yard.toml");
    let (ok, _, err) = rovernav(&["campaign", spec, "--trials", "1", "--out", out.to_str().unwrap()]);
    assert!(ok, "{err}");
    let (ok, text, err) =
        rovernav(&["eval", "horizon", "--seeds", "1", "--against", out.to_str().unwrap(), "--json"]);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(&text).expect("JSON figures");
    let seed = &v["runs_per_seed"][0];
    let bug = &seed["navigators"]["roverbug"];
    assert!(bug["outcome"].is_string(), "{v}");
    let rows = std::fs::read_to_string(out.join("rows.jsonl")).unwrap();
    let row: serde_json::Value = serde_json::from_str(rows.lines().next().unwrap()).unwrap();
    assert_eq!(bug["path_ratio"], row["path_ratio"]);
    // The campaign's optimal length is the reference's own: the same yard.
    assert!((num(&row, "optimal_length_m") - num(seed, "optimal_length_m")).abs() < 1e-6);
    // Seed 1 of a campaign's smaller yard is not the default yard of seed 1.
    let other = dir.join("other.toml");
    std::fs::write(
        &other,
        "name = \"other\"\nfirst_terrain_seed = 1\ntrials = 1\nnavigators = [\"astar-grid\"]\n[yard]\nsize_m = 12.0\n",
    )
    .unwrap();
    let other_out = dir.join("other");
    let (ok, _, err) = rovernav(&["campaign", other.to_str().unwrap(), "--out", other_out.to_str().unwrap()]);
    assert!(ok, "{err}");
    let (ok, _, err) =
        rovernav(&["eval", "horizon", "--seeds", "1", "--against", other_out.to_str().unwrap()]);
    assert!(!ok && err.contains("not this mission's terrains"), "{err}");
    // A seed range the campaign has no run on is refused too.
    let (ok, _, err) =
        rovernav(&["eval", "horizon", "--seeds", "2", "--against", other_out.to_str().unwrap()]);
    assert!(!ok && err.contains("no runs of this mission's terrains"), "{err}");
}
