//! The platform across a link (in process, through JSON): the rover side's run must be the
//! single-process run exactly, faults and operator commands included, with truth computed only
//! by the server.

mod common;

use rovernav_executive::remote::LocalLink;
use rovernav_executive::{Mission, Report, Run, RunOptions, RunOutput, RunSettings, ScriptedOperator};
use rovernav_harness::{JudgedRun, build_world};

/// A 12 m yard, quick in a debug build, with optional extra TOML (faults).
fn mission(seed: u64, extra: &str) -> Mission {
    let text = common::small_yard("remote-yard", seed, &format!("{}{extra}\n", common::SMALL_YARD_GOAL));
    Mission::from_toml(&text, "remote-yard").expect("valid mission")
}

/// The report without its wall-clock figures.
fn timeless(r: &Report) -> Report {
    Report { wall_time_s: 0.0, compute_per_cycle: Default::default(), ..r.clone() }
}

fn single(m: &Mission, operator: Option<&mut ScriptedOperator>) -> RunOutput {
    let world = build_world(m, "test").unwrap();
    let options = RunOptions::of(m, &world);
    let run = Run::new(world, RunSettings::of(m)).judged().options(options);
    match operator {
        Some(op) => run.operator(op),
        None => run,
    }
    .execute()
    .unwrap()
}

fn remote(m: &Mission, operator: Option<&mut ScriptedOperator>) -> RunOutput {
    // Each side builds its own world from the mission, as two processes would.
    let sim_world = build_world(m, "test").unwrap();
    let faults = RunOptions::of(m, &sim_world).faults;
    let server = rovernav_harness::platform_server(sim_world, &m.name, m.seed, faults).unwrap();
    let world = build_world(m, "test").unwrap();
    let mut options = RunOptions::of(m, &world);
    // The rover side never injects faults: prove the server's schedule alone does it.
    options.faults.clear();
    let run = Run::new(world, RunSettings::of(m)).options(options).remote(Box::new(LocalLink::new(server)));
    match operator {
        Some(op) => run.operator(op),
        None => run,
    }
    .execute()
    .unwrap()
}

#[test]
fn a_run_across_the_link_is_the_single_process_run() {
    let m = mission(3, "");
    let (a, b) = (single(&m, None), remote(&m, None));
    assert_eq!(a.report.outcome, "reached", "{}", a.report.message);
    assert_eq!(timeless(&a.report), timeless(&b.report));
    assert_eq!(a.trace.truth, b.trace.truth, "the server's true track is the single run's");
    assert_eq!(a.trace.estimate, b.trace.estimate);
    assert_eq!(a.trace.plans, b.trace.plans);
    assert_eq!(a.trace.sensed.as_ref().map(|g| &g.data), b.trace.sensed.as_ref().map(|g| &g.data));
}

#[test]
fn a_fault_scheduled_on_the_server_stops_the_rover_as_in_one_process() {
    let m = mission(3, "[[faults]]\nkind = \"stalled_wheel\"\nside = \"left\"\nat_cycle = 3");
    let (a, b) = (single(&m, None), remote(&m, None));
    assert_eq!(a.report.outcome, "help_requested", "{}", a.report.message);
    assert_eq!(a.report.fault.as_ref().unwrap().kind, "stuck_wheel");
    assert_eq!(timeless(&a.report), timeless(&b.report));
}

#[test]
fn an_operator_goal_change_is_scored_against_the_new_goal_on_both_sides() {
    let m = mission(3, "");
    let mut op_a = ScriptedOperator::new(&[(2, "goto 3.5 9")]);
    let mut op_b = ScriptedOperator::new(&[(2, "goto 3.5 9")]);
    let (a, b) = (single(&m, Some(&mut op_a)), remote(&m, Some(&mut op_b)));
    assert_eq!(timeless(&a.report), timeless(&b.report));
    assert_eq!(op_a.replies, op_b.replies);
    assert_eq!(b.report.outcome, "reached", "{}", b.report.message);
    // Independent of the code under test: start (2, 2) to the operator's goal (3.5, 9).
    assert!((b.report.straight_line_m - (1.5f64).hypot(7.0)).abs() < 1e-9, "{}", b.report.straight_line_m);
    let last = b.trace.truth.last().unwrap();
    assert!((last.x - 3.5).hypot(last.y - 9.0) < 1.0, "ended at ({}, {})", last.x, last.y);
}

#[test]
fn a_simulator_running_another_seed_is_refused_at_initialization() {
    let m = mission(3, "");
    let world = build_world(&m, "test").unwrap();
    let server = rovernav_harness::platform_server(world.clone(), &m.name, 4, Vec::new()).unwrap();
    let options = RunOptions::of(&m, &world);
    let out = Run::new(world, RunSettings::of(&m))
        .options(options)
        .remote(Box::new(LocalLink::new(server)))
        .execute()
        .unwrap();
    let platform = out.report.components.iter().find(|c| c.name == "platform").unwrap();
    assert_eq!(platform.state, "Failure", "{platform:?}");
    assert!(platform.message.contains("seed 4") && platform.message.contains("seed 3"), "{platform:?}");
    assert_ne!(out.report.outcome, "reached");
    assert_eq!(out.report.distance_driven_m, 0.0);
}
