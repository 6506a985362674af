//! Tests of the deliberative layer: plan order, parallel steps, arm aiming, failures, budgets,
//! operator errors.

use super::*;
use crate::fault_protection::FaultProtectionConfig;
use crate::messages::{CommandMsg, Origin, PoseMsg};

fn spec(kind: TaskKind, parallel: bool) -> TaskSpec {
    TaskSpec { kind, parallel }
}

#[test]
fn parallel_tasks_must_not_share_a_resource() {
    let p = Point2::new(1.0, 1.0);
    let drive = TaskKind::DriveTo { target: p, tolerance: 0.5 };
    assert!(
        validate_plan(&[spec(TaskKind::Panorama, false), spec(TaskKind::Scoop { target: p }, true)]).is_ok()
    );
    let (i, why) =
        validate_plan(&[spec(drive, false), spec(TaskKind::ScienceImage { target: p }, true)]).unwrap_err();
    assert_eq!(i, 1);
    assert!(why.contains("Mast"), "{why}");
    let (i, _) = validate_plan(&[
        spec(TaskKind::Panorama, false),
        spec(TaskKind::PlaceInstrument { target: p }, true),
        spec(TaskKind::Scoop { target: p }, true),
    ])
    .unwrap_err();
    assert_eq!(i, 2, "the arm is taken by task 1");
    assert_eq!(validate_plan(&[spec(TaskKind::Panorama, true)]).unwrap_err().0, 0);
    // A sequential task starts a new group.
    assert!(
        validate_plan(&[spec(drive, false), spec(drive, false), spec(TaskKind::Panorama, false)]).is_ok()
    );
}

fn layer(bus: &mut Bus, extra: &[TaskSpec]) -> Deliberative {
    let goal = Goal {
        position: Point2::new(10.0, 0.0),
        tolerance: 0.5,
        waypoints: vec![Point2::new(5.0, 5.0)],
        keep_out: vec![],
    };
    let config = DeliberativeConfig {
        time_limit_s: 100.0,
        max_cycles: 50,
        keep_out: vec![],
        tolerance: 0.5,
        mast_range_m: 5.0,
        fault_protection: FaultProtectionConfig::default(),
    };
    Deliberative::new(bus, &goal, extra, config).unwrap()
}

fn status(bus: &mut Bus, task: u64, state: TaskState, outcome: Option<&str>) {
    let msg = TaskStatusMsg {
        task,
        component: "navigator".into(),
        state,
        outcome: outcome.map(str::to_string),
        message: format!("{state:?}"),
    };
    bus.publish(topics::TASK_STATUS, msg).unwrap();
}

#[test]
fn drives_are_presented_one_after_the_other_and_parallel_tasks_together() {
    let mut bus = Bus::in_process();
    let drive_to = bus.subscribe(topics::EXECUTIVE_DRIVE_TO).unwrap();
    let motion = bus.subscribe(topics::EXECUTIVE_MOTION).unwrap();
    let arm = bus.subscribe(topics::ARM_COMMAND).unwrap();
    let extra =
        [spec(TaskKind::Panorama, false), spec(TaskKind::Scoop { target: Point2::new(11.0, 0.0) }, true)];
    let mut dl = layer(&mut bus, &extra);
    dl.step(&mut bus).unwrap();
    let first = bus.take(&drive_to).unwrap();
    assert_eq!(first.len(), 1);
    assert_eq!(first[0].goal.position, Point2::new(5.0, 5.0), "the waypoint comes first");
    // Nothing new while the waypoint drive is in process.
    status(&mut bus, first[0].task, TaskState::InProcess, None);
    dl.step(&mut bus).unwrap();
    assert!(bus.take(&drive_to).unwrap().is_empty());
    status(&mut bus, first[0].task, TaskState::Success, Some("reached"));
    dl.step(&mut bus).unwrap();
    let second = bus.take(&drive_to).unwrap();
    assert_eq!(second[0].goal.position, Point2::new(10.0, 0.0));
    assert!(bus.take(&motion).unwrap().is_empty(), "the panorama waits for the goal");
    status(&mut bus, second[0].task, TaskState::Success, Some("reached"));
    let at_goal = EstimateMsg { pose: PoseMsg { x: 10.0, ..Default::default() }, ..Default::default() };
    bus.publish(topics::LOCALIZATION_ESTIMATE, at_goal).unwrap();
    dl.step(&mut bus).unwrap();
    let pano = bus.take(&motion).unwrap();
    let scoop = bus.take(&arm).unwrap();
    assert_eq!((pano.len(), scoop.len()), (1, 1), "parallel tasks start in the same cycle");
    assert_eq!(scoop[0].target, [11.0, 0.0], "facing the target already: the arm deploys at once");
    assert_eq!(dl.tasks().iter().filter(|t| t.state == TaskState::InProcess).count(), 2);
    let Origin::Task(pano_id) = pano[0].origin else { panic!("task origin") };
    status(&mut bus, pano_id, TaskState::Success, None);
    dl.step(&mut bus).unwrap();
    assert!(dl.end().is_none(), "the step waits for the scoop too");
    status(&mut bus, scoop[0].task, TaskState::Success, None);
    dl.step(&mut bus).unwrap();
    let (outcome, why) = dl.end().unwrap();
    assert_eq!(*outcome, Outcome::Reached);
    assert!(why.contains("4 tasks succeeded"), "{why}");
}

#[test]
fn an_arm_task_first_turns_the_rover_to_face_its_target() {
    let mut bus = Bus::in_process();
    let drive_to = bus.subscribe(topics::EXECUTIVE_DRIVE_TO).unwrap();
    let motion = bus.subscribe(topics::EXECUTIVE_MOTION).unwrap();
    let arm = bus.subscribe(topics::ARM_COMMAND).unwrap();
    let mut dl =
        layer(&mut bus, &[spec(TaskKind::PlaceInstrument { target: Point2::new(10.0, 1.0) }, false)]);
    dl.step(&mut bus).unwrap();
    let wp = bus.take(&drive_to).unwrap()[0].task;
    status(&mut bus, wp, TaskState::Success, Some("reached"));
    dl.step(&mut bus).unwrap();
    let goal = bus.take(&drive_to).unwrap()[0].task;
    status(&mut bus, goal, TaskState::Success, Some("reached"));
    let at_goal = EstimateMsg { pose: PoseMsg { x: 10.0, ..Default::default() }, ..Default::default() };
    bus.publish(topics::LOCALIZATION_ESTIMATE, at_goal).unwrap();
    dl.step(&mut bus).unwrap();
    let turn = bus.take(&motion).unwrap();
    assert_eq!(turn.len(), 1);
    let CommandMsg::Turn { angle } = turn[0].command else { panic!("a turn first: {:?}", turn[0]) };
    assert!((angle - std::f64::consts::FRAC_PI_2).abs() < 1e-12, "target straight left: {angle}");
    assert!(bus.take(&arm).unwrap().is_empty(), "the arm waits for the turn");
    status(&mut bus, turn[0].id, TaskState::Success, None);
    dl.step(&mut bus).unwrap();
    let deploy = bus.take(&arm).unwrap();
    assert_eq!(deploy.len(), 1);
    assert_ne!(deploy[0].task, turn[0].id, "a new command for the second phase");
    assert_eq!(dl.tasks()[2].state, TaskState::InProcess);
    status(&mut bus, deploy[0].task, TaskState::Success, None);
    dl.step(&mut bus).unwrap();
    assert_eq!(dl.end().map(|e| e.0), Some(Outcome::Reached));
}

#[test]
fn a_failed_drive_ends_the_mission_with_the_navigators_outcome() {
    let mut bus = Bus::in_process();
    let drive_to = bus.subscribe(topics::EXECUTIVE_DRIVE_TO).unwrap();
    let mut dl = layer(&mut bus, &[]);
    dl.step(&mut bus).unwrap();
    let first = bus.take(&drive_to).unwrap();
    status(&mut bus, first[0].task, TaskState::Failure, Some("unreachable"));
    dl.step(&mut bus).unwrap();
    let (outcome, why) = dl.end().unwrap();
    assert_eq!(*outcome, Outcome::Unreachable);
    assert!(why.contains("drive_to (5.00, 5.00)") && why.contains("failure"), "{why}");
    assert_eq!(dl.tasks()[1].state, TaskState::Pending, "the goal never started");
}

#[test]
fn stale_statuses_of_withdrawn_commands_are_ignored() {
    let mut bus = Bus::in_process();
    let drive_to = bus.subscribe(topics::EXECUTIVE_DRIVE_TO).unwrap();
    let cancel = bus.subscribe(topics::EXECUTIVE_CANCEL).unwrap();
    let mut dl = layer(&mut bus, &[]);
    dl.step(&mut bus).unwrap();
    let old = bus.take(&drive_to).unwrap()[0].task;
    let reply = dl.apply_line(&mut bus, "waypoint clear").unwrap();
    assert!(reply.contains("1 waypoints cleared"), "{reply}");
    assert_eq!(bus.take(&cancel).unwrap()[0].task, old);
    dl.step(&mut bus).unwrap();
    let goal = bus.take(&drive_to).unwrap();
    assert_eq!(goal[0].goal.position, Point2::new(10.0, 0.0));
    // The navigator confirms the cancel of the old command afterwards: no effect on the goal.
    status(&mut bus, old, TaskState::Cancelled, None);
    dl.step(&mut bus).unwrap();
    assert_eq!(dl.tasks()[1].state, TaskState::InProcess);
    assert!(dl.end().is_none());
}

#[test]
fn budgets_end_the_mission_with_timeout() {
    let mut bus = Bus::in_process();
    let mut dl = layer(&mut bus, &[]);
    dl.time_s = 100.0;
    dl.step(&mut bus).unwrap();
    let (outcome, why) = dl.end().unwrap();
    assert_eq!(*outcome, Outcome::Timeout);
    assert_eq!(why, "mission time limit of 100 s reached");
}

#[test]
fn operator_errors_name_the_token_and_misplaced_commands_are_refused() {
    let mut bus = Bus::in_process();
    let mut dl = layer(&mut bus, &[]);
    let reply = dl.apply_line(&mut bus, "goto 3 north").unwrap();
    assert!(reply.starts_with("error:") && reply.contains("\"north\""), "{reply}");
    let reply = dl.apply_line(&mut bus, "drive 2").unwrap();
    assert!(reply.contains("mission pause"), "{reply}");
    assert!(dl.apply_line(&mut bus, "mission pause").unwrap().contains("paused"));
    assert!(dl.waiting());
    assert!(dl.apply_line(&mut bus, "drive 2").unwrap().contains("executing"));
    assert_eq!(dl.apply_line(&mut bus, "# just a comment").unwrap(), "");
    assert!(dl.apply_line(&mut bus, "help goto").unwrap().contains("goto X Y"));
}

#[test]
fn a_task_the_operator_queued_is_answered_when_it_ends() {
    let mut bus = Bus::in_process();
    let drive_to = bus.subscribe(topics::EXECUTIVE_DRIVE_TO).unwrap();
    let motion = bus.subscribe(topics::EXECUTIVE_MOTION).unwrap();
    let arm = bus.subscribe(topics::ARM_COMMAND).unwrap();
    let replies = bus.subscribe(topics::OPERATOR_REPLY).unwrap();
    let mut dl = layer(&mut bus, &[]);
    dl.step(&mut bus).unwrap();
    let wp = bus.take(&drive_to).unwrap()[0].task;
    let added = dl.apply_line(&mut bus, "place 5 6").unwrap();
    assert!(added.starts_with("task 3 added"), "{added}");
    status(&mut bus, wp, TaskState::Success, Some("reached"));
    let at_wp = EstimateMsg { pose: PoseMsg { x: 5.0, y: 5.0, ..Default::default() }, ..Default::default() };
    bus.publish(topics::LOCALIZATION_ESTIMATE, at_wp).unwrap();
    dl.step(&mut bus).unwrap();
    let turn = bus.take(&motion).unwrap();
    status(&mut bus, turn[0].id, TaskState::Success, None);
    dl.step(&mut bus).unwrap();
    let deploy = bus.take(&arm).unwrap();
    assert!(bus.take(&replies).unwrap().is_empty(), "nothing to answer while the arm works");
    status(&mut bus, deploy[0].task, TaskState::Failure, None);
    dl.step(&mut bus).unwrap();
    let answers: Vec<String> = bus.take(&replies).unwrap().iter().map(|r| r.to_string()).collect();
    assert_eq!(answers, ["task 3 (place_instrument (5.00, 6.00)) failure: Failure"]);
    assert_eq!(dl.end().map(|e| e.0), Some(Outcome::HelpRequested), "and the failure ends the mission");
}
