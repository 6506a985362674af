//! The seam between the executive and its judge: a run against the simulator in process is
//! judged by the judge it is given, told every executed command, and refuses to start without
//! one; the judgement crosses a link unchanged.

use rovernav_executive::judge::{Judge, Judgement};
use rovernav_executive::platform::Executed;
use rovernav_executive::{Mission, Run, RunError, RunSettings, World};
use rovernav_harness::{JudgedRun, Scorer, long_yard_world, optimal_length};
use rovernav_sim::Simulator;
use std::sync::{Arc, Mutex};

/// The default mission's settings, dead reckoning, at most 400 commands.
fn settings() -> RunSettings {
    let default = RunSettings::of(&Mission::default_mission());
    RunSettings { localizer: "dead-reckoning".into(), max_cycles: 400, name: "judge-yard".into(), ..default }
}

/// A judge that counts what it is told and leaves the figures to the harness's scorer.
struct Counting {
    inner: Scorer,
    seen: Arc<Mutex<(u32, u64, u32)>>,
}

impl Judge for Counting {
    fn start(&mut self, world: &World, start: rovernav_core::Pose3) {
        self.seen.lock().unwrap().0 += 1;
        self.inner.start(world, start);
    }
    fn record(&mut self, executed: &Executed) {
        self.seen.lock().unwrap().1 += 1;
        self.inner.record(executed);
    }
    fn judge(&mut self, world: &World, sim: &Simulator, estimate: rovernav_core::Pose3) -> Judgement {
        self.seen.lock().unwrap().2 += 1;
        self.inner.judge(world, sim, estimate)
    }
}

#[test]
fn an_in_process_run_without_a_judge_refuses_to_start_naming_its_origin() {
    let err = Run::new(long_yard_world(3, 5.0, 4.0, 1.0), settings()).origin("bare.toml").execute().err();
    let Some(err @ RunError::NoJudge { .. }) = err else { panic!("expected NoJudge, got {err:?}") };
    let text = err.to_string();
    assert!(text.starts_with("bare.toml: ") && !text.contains('\n'), "{text}");
}

#[test]
fn the_given_judge_is_told_every_executed_command_and_gives_the_report_its_figures() {
    let world = long_yard_world(3, 5.0, 4.0, 1.0);
    let expected_optimal = optimal_length(&world).expect("the long yard has a safe path");
    let seen = Arc::new(Mutex::new((0, 0, 0)));
    let judge = Counting { inner: Scorer::new(), seen: Arc::clone(&seen) };
    let out = Run::new(world.clone(), settings()).judge(Box::new(judge)).execute().unwrap();
    let (starts, records, judgements) = *seen.lock().unwrap();
    assert_eq!((starts, judgements), (1, 1));
    assert!(out.report.cycles > 0);
    assert_eq!(records, out.report.cycles, "one record per executed command");
    // One true pose at the start and one after every command.
    assert_eq!(out.trace.truth.len() as u64, out.report.cycles + 1);
    assert_eq!(out.report.optimal_length_m, Some(expected_optimal));
    // The harness's own constructor gives the same run.
    let judged = Run::new(world, settings()).judged().execute().unwrap();
    assert_eq!(judged.report.cycles, out.report.cycles);
    assert_eq!(judged.trace.truth, out.trace.truth);
    assert_eq!(judged.trace.sensed.as_ref().map(|s| s.data.clone()), out.trace.sensed.map(|s| s.data));
}

#[test]
fn a_judgement_crosses_a_link_unchanged() {
    let world = long_yard_world(3, 5.0, 4.0, 1.0);
    let out = Run::new(world.clone(), settings()).judged().execute().unwrap();
    let sensed = out.trace.sensed.clone().expect("an in-process run has sensed cells");
    assert!(sensed.data.iter().any(|&s| s), "the run sensed something");
    let judgement = Judgement {
        scoring: rovernav_executive::judge::Scoring {
            goal_error_m: out.report.goal_error_m,
            distance_driven_m: out.report.distance_driven_m,
            optimal_length_m: out.report.optimal_length_m,
            hazard_contacts: out.report.hazard_contacts,
            sim_time_s: out.report.sim_time_s,
            sensing_actions: out.report.sensing_actions,
            localization_error_m: out.report.localization_error_m,
            straight_line_m: out.report.straight_line_m,
            hazard_events: out.report.hazard_events.clone(),
            cycles: out.report.cycles,
            truth: Vec::new(),
            sensed: Vec::new(),
            injected_faults: Vec::new(),
        },
        truth: out.trace.truth.clone(),
        sensed: sensed.clone(),
    };
    let wire = judgement.into_scoring();
    assert_eq!(wire.sensed.len(), sensed.data.iter().filter(|&&s| s).count());
    let back = Judgement::received(&world, wire);
    assert_eq!(back.truth, out.trace.truth);
    assert_eq!(back.sensed.data, sensed.data);
    assert_eq!(back.sensed.geometry, sensed.geometry);
    assert_eq!(back.scoring.cycles, out.report.cycles);
}
