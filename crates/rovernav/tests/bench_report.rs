//! `rovernav bench report`: the JSON contract of issue 43 and the agreement checks behind its
//! figures (no figure is asserted: only fields, costs and optima).

use std::path::PathBuf;
use std::process::Command;

const WORKLOADS: [&str; 9] = [
    "astar-map1000",
    "dijkstra-map1000",
    "field-dstar-map1000",
    "dstar-lite-replan-map1000",
    "matcher-localisation",
    "edt-4096",
    "matcher-scan-window",
    "cycle-default",
    "sim-default",
];

fn temp_file(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("rovernav-bench-report-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

#[test]
fn a_missing_data_directory_is_a_one_line_error_naming_the_file() {
    let out = Command::new(env!("CARGO_BIN_EXE_rovernav"))
        .args(["bench", "report", "--quick", "--no-write"])
        .env("ROVERNAV_DATA", "/nonexistent-rovernav-data")
        .output()
        .unwrap();
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    let error: Vec<&str> = stderr.lines().filter(|l| !l.starts_with("bench report:")).collect();
    assert_eq!(error.len(), 1, "{stderr}");
    assert!(error[0].contains("/nonexistent-rovernav-data/costmaps/map1000.pgm"), "{stderr}");
}

#[test]
#[ignore = "release speed (about a minute): cargo test --release -p rovernav --test bench_report -- --ignored"]
fn quick_report_keeps_the_contract_and_its_costs_agree() {
    if rovernav_core::data_file_or_skip("costmaps/map1000.pgm").is_none() {
        return;
    }
    let table = temp_file("performance.md");
    let out = Command::new(env!("CARGO_BIN_EXE_rovernav"))
        .args(["bench", "report", "--quick", "--json", "--write", table.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    let rows = v["rows"].as_array().expect("rows");
    let names: Vec<&str> = rows.iter().map(|r| r["workload"].as_str().unwrap()).collect();
    assert_eq!(names, WORKLOADS);
    for r in rows {
        for field in ["rovernav_s", "baseline_s", "speedup"] {
            let x = r[field].as_f64().unwrap_or_else(|| panic!("{}: {field}", r["workload"]));
            assert!(x.is_finite() && x > 0.0, "{}: {field} = {x}", r["workload"]);
        }
        assert!(r["baseline"].as_str().is_some_and(|b| !b.is_empty()));
        assert!(r["limits"].as_str().is_some_and(|b| !b.is_empty()));
        let ratio = r["baseline_s"].as_f64().unwrap() / r["rovernav_s"].as_f64().unwrap();
        assert!((r["speedup"].as_f64().unwrap() - ratio).abs() <= 1e-9 * ratio);
    }
    let row = |name: &str| rows.iter().find(|r| r["workload"] == name).unwrap();
    let costs = |name: &str| {
        (row(name)["rovernav_cost"].as_f64().unwrap(), row(name)["baseline_cost"].as_f64().unwrap())
    };
    // A* and Dijkstra find the pathfinding crate's optimum on the identical graph; D* Lite's
    // repaired path costs what A* from scratch finds on the changed map.
    for name in ["astar-map1000", "dijkstra-map1000", "dstar-lite-replan-map1000"] {
        let (ours, base) = costs(name);
        assert!((ours - base).abs() <= 1e-9 * base, "{name}: {ours} vs {base}");
    }
    // Field D* within 0.1 % of the data README's reference, below the corner graph's optimum.
    let (field, corner) = costs("field-dstar-map1000");
    assert!((field / 24145.3 - 1.0).abs() <= 1e-3, "Field D* {field}");
    assert!(field < corner);
    // The matchers find exhaustive search's optimum.
    for name in ["matcher-localisation", "matcher-scan-window"] {
        let (ours, base) = costs(name);
        assert_eq!(ours, base, "{name}");
        assert_eq!(row(name)["details"]["optimum_identical"], true, "{name}");
    }
    let written = std::fs::read_to_string(&table).unwrap();
    assert!(written.contains(&format!("at revision `{}`", v["revision"].as_str().unwrap())));
    for name in WORKLOADS {
        assert!(written.contains(&format!("| {name} |")), "{name} missing from the table");
    }
}
