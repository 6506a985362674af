//! Fault drills in a campaign (issue 44 item 5): trial k injects `[[faults]]` entry k mod n at a
//! drawn command; each row says whether fault protection saw the fault, how fast, whether the
//! rover stopped, and the true hazard contacts after it. Checked against the runs' own reports
//! and the simulator's contact count, which the rows are derived from independently of the
//! summary.

use rovernav_campaign::{CampaignMeta, CampaignSpec, Plan, run_jobs, summarise};

const DRILLS: &str = r#"
name = "drills"
seed = 7
trials = 7
navigators = ["astar-grid"]
time_limit_s = 1200.0
fault_cycle = { min = 3, max = 8 }

[yard]
size_m = 12.0
resolution_m = 0.05
rock_abundance = 0.05
relief_m = 0.15

[[faults]]
kind = "silent_sensor"
sensor = "mast"

[[faults]]
kind = "nan_range"
sensor = "mast"

[[faults]]
kind = "stalled_wheel"
side = "right"

[[faults]]
kind = "compass_nan"

[[faults]]
kind = "gyro_bias_jump"

[[faults]]
kind = "component_crash"
component = "navigator"

[[faults]]
kind = "component_crash"
component = "motion-controller"
"#;

#[test]
fn every_fault_kind_is_detected_and_stops_the_rover_without_a_contact_after_it() {
    let spec = CampaignSpec::from_toml(DRILLS, "drills.toml").unwrap();
    let plan = Plan::new(spec).unwrap();
    // Each trial carries its entry, with the command drawn in [3, 8].
    let labels: Vec<_> = plan.trials.iter().map(|t| t.fault.clone().unwrap()).collect();
    assert_eq!(labels[0], "silent_sensor:mast");
    assert_eq!(labels[5], "component_crash:navigator");
    assert_eq!(labels[6], "component_crash:motion-controller");
    for k in 0..plan.trials.len() {
        let toml = plan.mission_toml(k).unwrap();
        assert!(toml.contains("[[faults]]") && toml.contains("at_cycle = "), "{toml}");
    }

    let rows = run_jobs(&plan, &plan.jobs(), 2, None, &|_| {}).unwrap();
    assert_eq!(rows.len(), 7);
    for r in &rows {
        let label = r.fault.as_deref().unwrap();
        assert!(r.fault_time_s.is_some(), "{label}: the fault struck before the run ended: {}", r.message);
        assert_eq!(r.fault_detected, Some(true), "{label}: {}", r.message);
        assert_eq!(r.stopped_safely, Some(true), "{label}: {}", r.message);
        assert_eq!(r.outcome, "help_requested", "{label}");
        assert_eq!(r.contacts_after_fault, Some(0), "{label}");
        assert!(r.time_to_detect_s.unwrap() >= 0.0);
        assert!(!r.failed(), "{label}");
    }
    let (summary, _) = summarise(&CampaignMeta::of(&plan, None), &rows);
    assert_eq!(summary.faults.len(), 7);
    assert!(summary.faults.iter().all(|f| f.injected == 1 && f.detected == 1 && f.stopped_safely == 1));
    assert!(summary.failures.is_empty());
    assert!(summary.markdown().contains("## Fault drills"));
}

#[test]
fn a_fault_entry_without_its_sensor_is_an_error_naming_the_field() {
    let text = "trials = 1\n[[faults]]\nkind = \"nan_range\"\n";
    let e = CampaignSpec::from_toml(text, "c.toml").unwrap_err().to_string();
    assert!(e.contains("faults[0].sensor"), "{e}");
}
