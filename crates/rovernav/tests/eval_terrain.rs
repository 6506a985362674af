//! `rovernav eval terrain`: each navigator's hazard model scored against the simulator's rocks
//! and true terrain on the same full-circle views.

use std::process::Command;

/// The JSON figures of one model on seeds 1..5.
fn figures(model: &str) -> serde_json::Value {
    let args = ["eval", "terrain", "--json", "--seeds", "1..5", "--model", model];
    let out = Command::new(env!("CARGO_BIN_EXE_rovernav")).args(args).output().expect("run rovernav");
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

#[test]
fn a_parameter_the_model_does_not_take_is_named_in_the_error() {
    for (model, param, named) in [
        ("roverbug", "clearance_margn=0.9", "clearance_margn"),
        ("roverbug", "pits_in_own_window=1", "pits_in_own_window"),
        ("grid", "clearance_margin=0.9", "grid model takes no parameters"),
        ("roverbug", "clearance_margin", "NAME=VALUE"),
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
