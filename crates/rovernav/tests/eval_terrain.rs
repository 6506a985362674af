//! `rovernav eval terrain`: each navigator's hazard model scored against the simulator's rocks
//! and true terrain on the same full-circle views.

use std::process::Command;

/// The JSON figures of one model on seeds 1..5.
fn figures(model: &str) -> serde_json::Value {
    figures_with(model, &[])
}

/// [`figures`] with `--param` options.
fn figures_with(model: &str, params: &[&str]) -> serde_json::Value {
    let mut args = vec!["eval", "terrain", "--json", "--seeds", "1..5", "--model", model];
    for p in params {
        args.extend(["--param", p]);
    }
    let out = Command::new(env!("CARGO_BIN_EXE_rovernav")).args(&args).output().expect("run rovernav");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&out.stdout).expect("JSON figures")
}

fn get(figures: &serde_json::Value, key: &str) -> f64 {
    figures[key].as_f64().unwrap_or_else(|| panic!("field `{key}` missing: {figures}"))
}

#[test]
fn roverbug_safety_layer_finds_the_rocks_its_cell_means_lose() {
    let means = figures("roverbug");
    let tops = figures("roverbug-safety");
    assert_eq!(means["model"], "roverbug");
    assert_eq!(tops["model"], "roverbug-safety");
    let (recall_means, recall_tops) = (get(&means, "hazard_recall"), get(&tops, "hazard_recall"));
    eprintln!("hazard recall: cell means {recall_means:.3}, safety layer {recall_tops:.3}");
    // Cell means average a small rock with the ground around it (paper 000's C-obstacles are
    // built from them); the safety layer's top heights exist to catch what they lose.
    assert!(recall_tops > recall_means, "tops {recall_tops} vs means {recall_means}");
    assert!(recall_tops >= 0.95, "safety layer recall {recall_tops}");
    for f in [&means, &tops] {
        assert!(get(f, "hazard_rocks") >= 50.0, "too few hazard rocks in view to compare: {f}");
        assert!(get(f, "false_hazard_rate") < 0.02, "{f}");
    }
}

#[test]
fn an_unknown_hazard_model_is_named_in_the_error() {
    let out = Command::new(env!("CARGO_BIN_EXE_rovernav"))
        .args(["eval", "terrain", "--model", "lidar-magic"])
        .output()
        .expect("run rovernav");
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("lidar-magic") && stderr.contains("roverbug-safety"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}

/// The step models before session 22: every window's ground refitted from the whole-window
/// plane only, low cells pits in any window.
const WHOLE_WINDOW_GROUND: [&str; 3] = ["pits_in_own_window=0", "robust_ground=0", "safety_robust_ground=0"];

#[test]
fn pits_in_their_own_window_only_drop_false_hazards_beside_large_rocks() {
    // The same views and truth: the option only removes low cells some other window marked.
    let plain = figures_with("roverbug", &WHOLE_WINDOW_GROUND);
    let own = figures_with("roverbug", &["pits_in_own_window=1", "robust_ground=0"]);
    let (f0, f1) = (get(&plain, "false_hazard_cells"), get(&own, "false_hazard_cells"));
    let (r0, r1) = (get(&plain, "hazard_rocks_detected"), get(&own, "hazard_rocks_detected"));
    eprintln!("false hazard cells {f0} -> {f1}, rocks detected {r0} -> {r1}");
    assert!(f1 < 0.9 * f0, "false hazard cells {f0} -> {f1}");
    assert!(get(&own, "hazard_cells") < get(&plain, "hazard_cells"));
    assert!(r1 <= r0 && r1 >= 0.9 * r0, "rocks detected {r0} -> {r1}");
    assert_eq!(get(&plain, "sensed_cells"), get(&own, "sensed_cells"));
}

#[test]
fn the_robust_ground_refit_cuts_both_models_false_hazards_and_keeps_their_recall() {
    // RoverBug's defaults (pits in their own window and the robust refit for its C-obstacle
    // model, the robust refit for its safety layer) against the step models before them, on
    // the same views and truth.
    for model in ["roverbug", "roverbug-safety"] {
        let before = figures_with(model, &WHOLE_WINDOW_GROUND);
        let now = figures(model);
        let (f0, f1) = (get(&before, "false_hazard_cells"), get(&now, "false_hazard_cells"));
        let (r0, r1) = (get(&before, "hazard_recall"), get(&now, "hazard_recall"));
        eprintln!("{model}: false hazard cells {f0} -> {f1}, recall {r0:.3} -> {r1:.3}");
        assert!(f1 < 0.6 * f0, "{model}: false hazard cells {f0} -> {f1}");
        assert!(r1 >= r0 - 0.05, "{model}: recall {r0} -> {r1}");
    }
}

#[test]
fn a_parameter_the_model_does_not_take_is_named_in_the_error() {
    for (model, param, named) in [
        ("roverbug", "pits_in_own_windw=1", "pits_in_own_windw"),
        ("grid", "pits_in_own_window=1", "grid model takes no parameters"),
        ("roverbug", "pits_in_own_window", "NAME=VALUE"),
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_rovernav"))
            .args(["eval", "terrain", "--seeds", "1", "--model", model, "--param", param])
            .output()
            .expect("run rovernav");
        assert!(!out.status.success(), "{model} {param}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(stderr.contains(named) && !stderr.contains("panicked"), "{stderr}");
    }
}
