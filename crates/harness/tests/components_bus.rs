//! The component/bus run against an independent reference: a minimal direct loop (navigator ->
//! simulator -> localiser) kept here gives the report the components must reproduce exactly; the
//! serialized bus gives the same run as the in-process one; JAUS states follow the commands; an
//! emergency stop reaches every component and stops all motion.

mod common;

use rovernav_bus::Bus;
use rovernav_core::{NavCommand, NavInput, Outcome, Point2, Pose3};
use rovernav_executive::components::JausState;
use rovernav_executive::messages::{CommandMsg, ControlAction, MotionRequest, Origin, topics};
use rovernav_executive::platform::{ArmConfig, SimPlatform, ToolingArm};
use rovernav_executive::reflexive::{MotionController, NavigatorComponent, PoseEstimatorComponent};
use rovernav_executive::runtime::Runtime;
use rovernav_executive::sensor_servers::{InertialSensors, MAX_BODY_CONTACTS, RangeSensors, WheelOdometry};
use rovernav_executive::{
    BusKind, Mission, Report, Run, RunOptions, RunOutput, RunSettings, ScriptedOperator, World,
};
use rovernav_harness::{JudgedRun, build_world};
use rovernav_sim::Simulator;

/// A 12 m yard, quick in a debug build.
fn small_mission(seed: u64) -> Mission {
    let text = common::small_yard("small-yard", seed, common::SMALL_YARD_GOAL);
    Mission::from_toml(&text, "small-yard").expect("valid mission")
}

/// The reference loop's message when the body-contact rule halts it.
const BODY_CONTACT_HALT: &str = "halted at the body-contact limit";

/// What the reference loop measures.
#[derive(Debug, PartialEq)]
struct Reference {
    outcome: String,
    message: String,
    cycles: u64,
    sim_time_s: f64,
    distance_driven_m: f64,
    hazard_contacts: u32,
    sensing_actions: u64,
    goal_error_m: f64,
    localization_error_m: f64,
    truth: Vec<Pose3>,
    estimate: Vec<Pose3>,
}

/// The navigation loop at its simplest, with no components and no bus: the independent truth.
fn direct_loop(world: &World, s: &RunSettings) -> Reference {
    // A map-matching localiser's navigator looks back over the terrain crossed ("+look-back").
    let name = rovernav_navigation::registry().decorated(&s.navigator, &s.localizer);
    let mut navigator = rovernav_navigation::navigator_by_name(&name, &world.rover).unwrap();
    let initial = Pose3 { x: world.start.x, y: world.start.y, yaw: world.start.yaw, ..Default::default() };
    let mut localizer = rovernav_navigation::localizer_by_name(&s.localizer, &world.rover, initial).unwrap();
    let mut sim = Simulator::new(
        world.terrain.clone(),
        world.rover.clone(),
        world.sensor_model.clone(),
        world.start,
        s.seed,
    );
    let mut frame = sim.initial_frame();
    localizer.update(&frame);
    let (mut truth, mut estimate) = (vec![sim.truth()], vec![localizer.estimate().pose]);
    let (mut cycles, mut contacts) = (0, 0u32);
    let (outcome, message) = loop {
        if sim.time() >= s.time_limit_s {
            break (Outcome::Timeout, format!("mission time limit of {} s reached", s.time_limit_s));
        }
        if cycles >= s.max_cycles {
            break (Outcome::Timeout, format!("cycle limit of {} reached", s.max_cycles));
        }
        let input = NavInput {
            time: sim.time(),
            estimate: localizer.estimate(),
            goal: &world.goal,
            frame: &frame,
            localization_target: localizer.localization_target(),
        };
        let command = navigator.step(&input);
        if let NavCommand::Finish(outcome, message) = command {
            break (outcome, message);
        }
        frame = sim.execute(&command);
        localizer.update(&frame);
        cycles += 1;
        truth.push(sim.truth());
        estimate.push(localizer.estimate().pose);
        // Fault protection's documented rule: the third motion stopped on the terrain halts.
        contacts += u32::from(frame.motion_stopped.as_deref().is_some_and(|w| w.starts_with("hazard")));
        if contacts >= MAX_BODY_CONTACTS {
            break (Outcome::HelpRequested, BODY_CONTACT_HALT.into());
        }
    };
    let t = sim.truth();
    let e = localizer.estimate().pose;
    let goal_error_m = Point2::new(t.x, t.y).dist(world.goal.position);
    Reference {
        outcome: outcome.as_str().into(),
        message: rovernav_executive::report::run_message(outcome, &message, goal_error_m),
        cycles,
        sim_time_s: sim.time(),
        distance_driven_m: sim.distance_driven(),
        hazard_contacts: sim.hazard_contacts(),
        sensing_actions: sim.sensing_actions(),
        goal_error_m,
        localization_error_m: (t.x - e.x).hypot(t.y - e.y),
        truth,
        estimate,
    }
}

fn as_reference(out: &RunOutput) -> Reference {
    let r = &out.report;
    Reference {
        outcome: r.outcome.clone(),
        message: r.message.clone(),
        cycles: r.cycles,
        sim_time_s: r.sim_time_s,
        distance_driven_m: r.distance_driven_m,
        hazard_contacts: r.hazard_contacts,
        sensing_actions: r.sensing_actions,
        goal_error_m: r.goal_error_m,
        localization_error_m: r.localization_error_m,
        truth: out.trace.truth.clone(),
        estimate: out.trace.estimate.clone(),
    }
}

fn bus_run(mission: &Mission, bus: BusKind) -> RunOutput {
    let world = build_world(mission, "test").unwrap();
    let options = RunOptions { bus, ..RunOptions::of(mission, &world) };
    Run::new(world, RunSettings::of(mission)).judged().options(options).execute().unwrap()
}

/// The report without its wall-clock figures.
fn timeless(r: &Report) -> Report {
    Report { wall_time_s: 0.0, compute_per_cycle: Default::default(), ..r.clone() }
}

fn assert_matches_direct_loop(mission: &Mission) -> RunOutput {
    let world = build_world(mission, "test").unwrap();
    let reference = direct_loop(&world, &RunSettings::of(mission));
    let out = bus_run(mission, BusKind::InProcess);
    let mut reference = reference;
    if reference.message == BODY_CONTACT_HALT {
        // The wording is fault protection's; what must agree is that it halted here, and why.
        let fault = out.report.fault.as_ref().expect("fault protection acted");
        assert_eq!(fault.kind, "hazard_contact", "{fault:?}");
        reference.message = out.report.message.clone();
    }
    assert_eq!(as_reference(&out), reference, "the components reproduce the direct loop exactly");
    out
}

#[test]
fn components_on_the_bus_reproduce_the_direct_loop_on_a_small_yard() {
    let mission = small_mission(3);
    let out = assert_matches_direct_loop(&mission);
    assert_eq!(out.report.outcome, "reached", "{}", out.report.message);
    assert!(out.report.cycles > 10, "a real traverse: {} cycles", out.report.cycles);
    // A finished mission stands every component down.
    assert_eq!(out.report.components.len(), 10);
    assert!(out.report.components.iter().any(|c| c.name == "camera-server"));
    assert!(out.report.components.iter().all(|c| c.state == "Standby"), "{:?}", out.report.components);
    assert_eq!(out.report.tasks.len(), 1);
    assert_eq!(out.report.tasks[0].state, "success");
    assert_eq!(out.report.fault, None);
}

#[test]
fn bus_runs_are_deterministic_and_the_serialized_bus_gives_the_same_run() {
    let mission = small_mission(5);
    let a = bus_run(&mission, BusKind::InProcess);
    let b = bus_run(&mission, BusKind::InProcess);
    let wire = bus_run(&mission, BusKind::Serialized);
    assert_eq!(timeless(&a.report), timeless(&b.report));
    assert_eq!(a.trace.truth, b.trace.truth);
    assert_eq!(timeless(&a.report), timeless(&wire.report), "every message survives JSON unchanged");
    assert_eq!(a.trace.estimate, wire.trace.estimate);
    assert_eq!(a.trace.plans, wire.trace.plans);
}

#[test]
#[ignore = "release speed: cargo test --release -p rovernav-harness --test components_bus -- --ignored"]
fn default_mission_through_the_components_equals_the_direct_loop() {
    let out = assert_matches_direct_loop(&Mission::default_mission());
    assert_eq!(out.report.outcome, "reached");
}

#[test]
#[ignore = "release speed: cargo test --release -p rovernav-harness --test components_bus -- --ignored"]
fn every_navigator_on_three_default_yards_gives_the_direct_loops_run() {
    // Fault protection must never fire on a healthy rover: any navigator, same run as without it
    // (a navigator that keeps meeting the terrain is halted by the rule the reference applies).
    for seed in 1..=3 {
        for navigator in rovernav_navigation::navigator_names() {
            let mission = Mission {
                navigator: navigator.to_string(),
                seed,
                // Every navigator alone (the default mission itself runs map matching above).
                localizer: "dead-reckoning".into(),
                ..Mission::default_mission()
            };
            let out = assert_matches_direct_loop(&mission);
            let fault = out.report.fault.as_ref();
            assert!(fault.is_none_or(|f| f.kind == "hazard_contact"), "{navigator}, seed {seed}: {fault:?}");
        }
    }
}

/// Every component of a run, on a bus, for state tests.
fn runtime(mission: &Mission) -> Runtime {
    let world = build_world(mission, "test").unwrap();
    let rover = world.rover.clone();
    let nav = rovernav_navigation::navigator_by_name("astar-grid", &rover).unwrap();
    let start = Pose3 { x: world.start.x, y: world.start.y, yaw: world.start.yaw, ..Default::default() };
    let loc = rovernav_navigation::localizer_by_name("dead-reckoning", &rover, start).unwrap();
    let sim = Simulator::new(world.terrain, rover.clone(), world.sensor_model, world.start, mission.seed);
    let mut rt = Runtime::new(Bus::in_process()).unwrap();
    rt.add(Box::new(NavigatorComponent::new(nav, "astar-grid", rover.clone()))).unwrap();
    rt.add(Box::new(ToolingArm::new(ArmConfig::default()))).unwrap();
    rt.add(Box::new(MotionController::new())).unwrap();
    rt.add(Box::new(SimPlatform::new(sim, vec![]))).unwrap();
    rt.add(Box::new(RangeSensors::new())).unwrap();
    rt.add(Box::new(InertialSensors::new())).unwrap();
    rt.add(Box::new(WheelOdometry::new(rover.encoder_counts_per_cm, rover.track))).unwrap();
    rt.add(Box::new(PoseEstimatorComponent::new(loc, Default::default()))).unwrap();
    rt
}

fn states(rt: &Runtime) -> Vec<JausState> {
    rt.states().iter().map(|s| s.state).collect()
}

fn drive(rt: &mut Runtime, id: u64) {
    let command = CommandMsg::Drive { distance: 0.5, curvature: 0.0, guard: Default::default() };
    rt.bus()
        .publish(topics::EXECUTIVE_MOTION, MotionRequest { id, origin: Origin::Operator, command })
        .unwrap();
}

#[test]
fn jaus_states_follow_the_commands_and_an_emergency_stop_reaches_every_component() {
    let mut rt = runtime(&small_mission(3));
    let status = rt.bus().subscribe(topics::SYSTEM_STATUS).unwrap();
    assert!(states(&rt).iter().all(|s| *s == JausState::Initialization));
    rt.initialize(0.0).unwrap();
    assert!(states(&rt).iter().all(|s| *s == JausState::Standby), "{:?}", rt.states());
    let time = |rt: &Runtime| rt.get::<SimPlatform>().unwrap().sim().time();

    // Standing by, the motion controller drops a command instead of keeping it for later.
    drive(&mut rt, 1);
    rt.tick(time(&rt)).unwrap();
    rt.command(None, ControlAction::Resume).unwrap();
    rt.tick(time(&rt)).unwrap();
    assert!(states(&rt).iter().all(|s| *s == JausState::Ready));
    assert_eq!(rt.get::<SimPlatform>().unwrap().sim().distance_driven(), 0.0, "no stale command executed");

    // Ready, a command reaches the wheels within the tick.
    drive(&mut rt, 2);
    rt.tick(time(&rt)).unwrap();
    let driven = rt.get::<SimPlatform>().unwrap().sim().distance_driven();
    assert!(driven > 0.3, "drove {driven} m");

    // One component can stand by alone.
    rt.command(Some("navigator"), ControlAction::Standby).unwrap();
    rt.tick(time(&rt)).unwrap();
    assert_eq!(rt.state("navigator"), Some(JausState::Standby));
    assert_eq!(rt.state("platform"), Some(JausState::Ready));

    // An emergency stop reaches every component, whatever its state, before any acts again.
    drive(&mut rt, 3);
    rt.command(None, ControlAction::EmergencyStop).unwrap();
    rt.tick(time(&rt)).unwrap();
    assert!(states(&rt).iter().all(|s| *s == JausState::Emergency), "{:?}", rt.states());
    assert_eq!(rt.get::<SimPlatform>().unwrap().sim().distance_driven(), driven, "no motion after the stop");
    let announced: Vec<String> = rt
        .bus()
        .take(&status)
        .unwrap()
        .iter()
        .filter(|s| s.state == JausState::Emergency)
        .map(|s| s.component.clone())
        .collect();
    assert_eq!(announced.len(), 8, "every component announces Emergency on the bus: {announced:?}");

    // Resume is refused until the emergency is cleared; clearing leads to Standby, then Ready.
    rt.command(None, ControlAction::Resume).unwrap();
    rt.tick(time(&rt)).unwrap();
    assert!(states(&rt).iter().all(|s| *s == JausState::Emergency));
    rt.command(None, ControlAction::ClearEmergency).unwrap();
    rt.tick(time(&rt)).unwrap();
    assert!(states(&rt).iter().all(|s| *s == JausState::Standby));
    rt.command(None, ControlAction::Resume).unwrap();
    rt.tick(time(&rt)).unwrap();
    assert!(states(&rt).iter().all(|s| *s == JausState::Ready));
    assert_eq!(
        rt.get::<SimPlatform>().unwrap().sim().distance_driven(),
        driven,
        "the stopped command is gone"
    );
}

fn scripted_run(mission: &Mission, script: &[(u64, &str)]) -> (RunOutput, ScriptedOperator) {
    let world = build_world(mission, "test").unwrap();
    let options = RunOptions::of(mission, &world);
    let mut operator = ScriptedOperator::new(script);
    let out = Run::new(world, RunSettings::of(mission))
        .judged()
        .options(options)
        .operator(&mut operator)
        .execute()
        .unwrap();
    (out, operator)
}

#[test]
fn an_operator_stop_puts_every_component_in_emergency_and_holds_the_rover() {
    let (out, op) =
        scripted_run(&small_mission(3), &[(3, "stop"), (3, "status"), (3, "drive 1"), (3, "mission abort")]);
    let r = &out.report;
    assert_eq!(r.outcome, "aborted", "{}", r.message);
    assert_eq!(r.cycles, 3, "nothing executed after the stop");
    assert!(r.components.iter().all(|c| c.state == "Emergency"), "{:?}", r.components);
    let status = op.reply_containing("components:").expect("status answered");
    let components = status.lines().find(|l| l.starts_with("components:")).unwrap();
    assert_eq!(components.matches("Emergency").count(), r.components.len(), "{status}");
    assert!(op.reply_containing("direct motion needs the mission paused").is_some(), "{:?}", op.replies);
    assert_eq!(r.tasks[0].state, "aborted", "the stop aborted the drive: {:?}", r.tasks);
}

#[test]
fn clearing_an_emergency_resumes_the_mission_to_the_goal() {
    let mission = small_mission(3);
    let (out, op) = scripted_run(&mission, &[(4, "stop"), (4, "mission start")]);
    assert!(op.reply_containing("emergency cleared").is_some(), "{:?}", op.replies);
    assert_eq!(out.report.outcome, "reached", "{}", out.report.message);
    assert!(out.report.goal_error_m < 1.5);
}

/// Records the bus.
#[derive(Default)]
struct BusLog(Vec<rovernav_bus::Record>);

impl rovernav_executive::RunObserver for BusLog {
    fn wants_bus(&self) -> bool {
        true
    }
    fn on_bus(&mut self, records: &[rovernav_bus::Record]) {
        self.0.extend_from_slice(records);
    }
}

#[test]
fn an_observer_can_record_every_bus_message_as_json() {
    let mission = small_mission(3);
    let world = build_world(&mission, "test").unwrap();
    let mut log = BusLog::default();
    let options = RunOptions::of(&mission, &world);
    let out = Run::new(world, RunSettings::of(&mission))
        .judged()
        .options(options)
        .observer(&mut log)
        .execute()
        .unwrap();
    let on = |topic: &str| log.0.iter().filter(|r| r.topic == topic).count() as u64;
    // The initial frame, one frame per command, and the stand-down of every component at the end.
    assert_eq!(on("/platform/frame"), out.report.cycles + 1);
    assert_eq!(on("/platform/command"), out.report.cycles);
    assert!(log.0.windows(2).all(|w| w[0].seq + 1 == w[1].seq && w[0].time_s <= w[1].time_s));
    let last_frame = log.0.iter().rev().find(|r| r.topic == "/platform/frame").unwrap();
    let frame: rovernav_executive::messages::FrameMsg =
        rovernav_bus::decode(&topics::PLATFORM_FRAME, &last_frame.payload).unwrap();
    assert_eq!(frame.t, out.report.sim_time_s);
    let standby = log
        .0
        .iter()
        .filter(|r| r.topic == "/system/status" && r.payload.windows(9).any(|w| w == b"\"Standby\""));
    assert!(standby.count() >= 16, "every component went to Standby twice (initialized, mission over)");
}
