//! The example navigator (`examples/straight_line_navigator`) registered at run time drives a
//! mission and a campaign by its name.

#[path = "../examples/straight_line_navigator/navigator.rs"]
mod navigator;

use rovernav_campaign::{CampaignSpec, Plan};
use rovernav_executive::{Mission, Run};
use rovernav_harness::JudgedRun;
use rovernav_navigation::{Registry, registry};

#[test]
fn the_example_navigator_registers_with_one_line_and_runs_a_mission_and_a_campaign() {
    registry::install(Registry::builtin().with(navigator::ENTRY)).expect("first use of the registry");
    // A rock-free yard, goal in sight: driving straight at it must arrive.
    let text = rovernav_executive::mission::DEFAULT_MISSION_TOML
        .replace("navigator = \"astar-grid\"", "navigator = \"straight-line\"")
        .replace("rock_abundance = 0.16", "rock_abundance = 0.0");
    let mission = Mission::from_toml(&text, "straight-line mission").unwrap();
    let out = Run::mission(&mission, "straight-line mission").and_then(Run::execute).unwrap();
    assert_eq!(out.report.navigator, "straight-line");
    assert_eq!(out.report.outcome, "reached", "{}", out.report.message);
    // It drove straight from (5, 5) toward (20, 20): its true path is no shorter than the line
    // less the final error (triangle inequality) and hardly longer than the line plus it, and
    // it ended within dead reckoning's drift (under 10 % of the distance) of the goal.
    let line = (15.0f64 * 15.0 * 2.0).sqrt();
    let r = &out.report;
    assert!(r.distance_driven_m >= line - r.goal_error_m - 1e-6, "{r:?}");
    assert!(r.distance_driven_m <= line + r.goal_error_m + 0.5, "{r:?}");
    assert!(r.goal_error_m < 0.1 * line, "{r:?}");
    assert_eq!(r.sensing_actions, 0, "it never senses");
    // Its parameters are checked like a built-in navigator's.
    let bad: rovernav_navigation::NavigatorParams = [("step_m".to_string(), -1.0)].into();
    assert!(rovernav_navigation::check_params("straight-line", &bad).is_err());

    // A campaign names it like any other navigator; its row carries the name.
    let spec = CampaignSpec::from_toml(
        "trials = 1\nnavigators = [\"straight-line\"]\n[yard]\nsize_m = 12.0\n",
        "c.toml",
    )
    .unwrap();
    let plan = Plan::new(spec).unwrap();
    let rows = rovernav_campaign::run_jobs(&plan, &plan.jobs(), 1, None, &|_| {}).unwrap();
    assert_eq!(rows.len(), 1);
    assert_eq!(rows[0].navigator, "straight-line");
}
