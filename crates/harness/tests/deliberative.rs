//! The deliberative layer in closed loop: the plan's tasks in sequence and in parallel, each
//! command's state, and operator commands changing the mission while it runs.

mod common;

use rovernav_core::{NavCommand, Point2, Pose3};
use rovernav_executive::{
    CycleRecord, Mission, NoObserver, Report, Run, RunObserver, RunOptions, RunOutput, RunSettings,
    ScriptedOperator,
};
use rovernav_harness::{JudgedRun, build_world};

/// A 12 m yard; `extra` is appended to the mission text.
fn mission(extra: &str) -> Mission {
    let text = common::small_yard("task-yard", 3, &format!("{extra}\n"));
    Mission::from_toml(&text, "task-yard").expect("valid mission")
}

const GOAL: &str = "[goal]\nx = 9.5\ny = 8.5\ntolerance_m = 0.25\n";

/// Every executed command with the truth after it.
#[derive(Default)]
struct Commands(Vec<(NavCommand, Pose3, f64)>);

impl RunObserver for Commands {
    fn on_cycle(&mut self, r: &CycleRecord<'_>) {
        self.0.push((r.command.clone(), *r.truth, r.sim_time_s));
    }
}

fn run(m: &Mission, script: &[(u64, &str)], observer: &mut dyn RunObserver) -> (RunOutput, ScriptedOperator) {
    let world = build_world(m, "test").unwrap();
    let options = RunOptions::of(m, &world);
    let mut op = ScriptedOperator::new(script);
    let out = Run::new(world, RunSettings::of(m))
        .judged()
        .options(options)
        .observer(observer)
        .operator(&mut op)
        .execute()
        .unwrap();
    (out, op)
}

fn states(r: &Report) -> Vec<(&str, &str)> {
    r.tasks.iter().map(|t| (t.kind.as_str(), t.state.as_str())).collect()
}

/// A scoop 0.8 m east of the goal and a panorama, parallel or one after the other.
fn task_mission(parallel: bool) -> Mission {
    mission(&format!(
        "{GOAL}[[tasks]]\nkind = \"scoop\"\nx = 10.3\ny = 8.5\n[[tasks]]\nkind = \"panorama\"\nparallel = {parallel}\n"
    ))
}

#[test]
fn parallel_tasks_overlap_and_sequential_tasks_add_up() {
    let drive_only = run(&mission(GOAL), &[], &mut NoObserver).0.report;
    let sequential = run(&task_mission(false), &[], &mut NoObserver).0.report;
    let parallel = run(&task_mission(true), &[], &mut NoObserver).0.report;
    for r in [&sequential, &parallel] {
        assert_eq!(r.outcome, "reached", "{}", r.message);
        assert_eq!(states(r), [("drive_to", "success"), ("scoop", "success"), ("panorama", "success")]);
        assert!(r.message.contains("3 tasks succeeded"), "{}", r.message);
    }
    // One panorama, and a turn to face the scoop target unless the rover already does.
    assert!(
        (1..=2).contains(&(sequential.cycles - drive_only.cycles)),
        "{} vs {}",
        sequential.cycles,
        drive_only.cycles
    );
    assert_eq!(parallel.cycles, sequential.cycles);
    let seq = sequential.sim_time_s - drive_only.sim_time_s;
    let par = parallel.sim_time_s - drive_only.sim_time_s;
    // A panorama is 8 mast images (10 s each); a scoop keeps the arm out 60 s. In sequence they
    // add up; in parallel the arm works while the mast images.
    assert!(seq >= 140.0, "sequential tasks took {seq:.1} s");
    assert!((80.0..seq - 55.0).contains(&par), "parallel tasks took {par:.1} s, sequential {seq:.1} s");
    assert_eq!(parallel.sensing_actions, drive_only.sensing_actions + 8);
}

#[test]
fn a_task_that_cannot_be_done_fails_and_the_rover_asks_for_help() {
    let m = mission(&format!("{GOAL}[[tasks]]\nkind = \"science_image\"\nx = 2.0\ny = 2.0\n"));
    let r = run(&m, &[], &mut NoObserver).0.report;
    assert_eq!(r.outcome, "help_requested", "{}", r.message);
    assert_eq!(states(&r), [("drive_to", "success"), ("science_image", "failure")]);
    assert!(r.message.contains("outside the mast's"), "{}", r.message);
}

#[test]
fn mission_waypoints_are_driven_in_order_before_the_goal() {
    let m = mission("[goal]\nx = 9.5\ny = 8.5\nwaypoints = [[8.0, 3.0], [4.0, 7.0]]\n");
    let mut log = Commands::default();
    let r = run(&m, &[], &mut log).0.report;
    assert_eq!(r.outcome, "reached", "{}", r.message);
    assert_eq!(states(&r), [("drive_to", "success"); 3]);
    // Truth passes near each waypoint, in order.
    let first_near = |p: Point2| log.0.iter().position(|(_, t, _)| Point2::new(t.x, t.y).dist(p) < 1.2);
    let (a, b) = (first_near(Point2::new(8.0, 3.0)), first_near(Point2::new(4.0, 7.0)));
    assert!(a.is_some() && b.is_some() && a < b, "visits: {a:?} then {b:?}");
}

#[test]
fn goto_mid_run_replaces_the_goal_and_the_rover_reaches_the_new_one() {
    let (out, op) = run(&mission(GOAL), &[(6, "goto 3.5 9"), (6, "status")], &mut NoObserver);
    let r = &out.report;
    assert!(op.reply_containing("goal set to (3.50, 9.00)").is_some(), "{:?}", op.replies);
    assert!(
        op.reply_containing("goal (3.50, 9.00)").is_some(),
        "status shows the new goal: {:?}",
        op.replies
    );
    assert_eq!(r.outcome, "reached", "{}", r.message);
    assert!(r.goal_error_m < 1.0, "true error to the new goal {} m", r.goal_error_m);
    assert_eq!(out.world.goal.position, Point2::new(3.5, 9.0), "scored against the new goal");
    assert_eq!(r.tasks[0].target, Some([3.5, 9.0]));
}

#[test]
fn a_waypoint_added_mid_run_is_visited_before_the_goal() {
    let mut log = Commands::default();
    let script = [(4, "waypoint add 9 3"), (4, "waypoint list")];
    let (out, op) = run(&mission(GOAL), &script, &mut log);
    let r = &out.report;
    assert!(op.reply_containing("waypoint 2 (9.00, 3.00) in_process").is_some(), "{:?}", op.replies);
    assert_eq!(r.outcome, "reached", "{}", r.message);
    assert_eq!(states(r), [("drive_to", "success"), ("drive_to", "success")]);
    let near = log.0.iter().position(|(_, t, _)| Point2::new(t.x, t.y).dist(Point2::new(9.0, 3.0)) < 1.2);
    let at_goal = log.0.iter().position(|(_, t, _)| Point2::new(t.x, t.y).dist(Point2::new(9.5, 8.5)) < 1.0);
    assert!(near.is_some() && near < at_goal, "waypoint at {near:?}, goal at {at_goal:?}");
}

#[test]
fn paused_the_rover_takes_direct_motion_commands_only_and_resumes_on_start() {
    let mut log = Commands::default();
    let script = [(5, "mission pause"), (5, "drive 0.4"), (6, "turn -30"), (7, "mission start")];
    let (out, op) = run(&mission(GOAL), &script, &mut log);
    assert!(op.reply_containing("mission paused").is_some(), "{:?}", op.replies);
    assert!(op.reply_containing("mission resumed").is_some(), "{:?}", op.replies);
    assert_eq!(out.report.outcome, "reached", "{}", out.report.message);
    // Commands 6 and 7 are exactly the operator's.
    assert_eq!(
        log.0[5].0,
        NavCommand::Drive {
            distance: 0.4,
            curvature: 0.0,
            guard: rovernav_core::DriveGuard { proximity: true, max_tilt: None },
        }
    );
    assert_eq!(log.0[6].0, NavCommand::Turn { angle: (-30f64).to_radians() });
}

#[test]
fn set_position_resets_the_localiser() {
    let script = [(3, "mission pause"), (3, "set position 3 3"), (3, "status"), (3, "mission start")];
    let (out, op) = run(&mission(GOAL), &script, &mut NoObserver);
    assert!(op.reply_containing("position set to (3.00, 3.00)").is_some(), "{:?}", op.replies);
    assert!(op.reply_containing("estimate (3.00, 3.00)").is_some(), "{:?}", op.replies);
    let plain = run(&mission(GOAL), &[], &mut NoObserver).0.report;
    // The fix moved the estimate about 1 m from the truth: the error stays with the run.
    assert!(
        out.report.localization_error_m > plain.localization_error_m + 0.5,
        "{} vs {}",
        out.report.localization_error_m,
        plain.localization_error_m
    );
}
