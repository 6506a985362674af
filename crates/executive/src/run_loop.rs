//! The one loop of every run: the deliberative layer presents the plan to the components of the
//! graph ([`crate::graph`]), the runtime steps them on simulated time, and the loop only watches.
//!
//! One cycle, as a newcomer would follow it: the operator's lines go on the bus; the deliberative
//! layer ([`crate::deliberative`]) reads the bus and publishes drives, cancels and state commands;
//! the runtime ([`crate::runtime`]) ticks, visiting the navigator (plans, publishes a motion), the
//! motion controller, the platform (executes it and publishes the sensor frame), the sensor
//! servers and the pose estimator (integrates the frame) in [`crate::graph::NODES`] order. The
//! loop then records what the platform executed for the trace, the observers and the progress
//! bar, and ends when the deliberative layer says the mission is over.
//!
//! The platform is either the simulator in process or a stand-in across a link
//! ([`crate::remote::RemotePlatform`]); the loop is the same. What differs is who holds the truth:
//! in process the run's [`Judge`] (the harness's) is told every executed command here; across a
//! link the simulator process's judge is, and its [`crate::judge::Scoring`] comes back when the
//! mission has ended.

use crate::components::{Component, Port};
use crate::deliberative::{Deliberative, DeliberativeConfig};
use crate::graph::{Parts, assemble as assemble_graph};
use crate::judge::{Judge, Judgement};
use crate::messages::{ControlAction, topics};
use crate::operator::OperatorLink;
use crate::platform::{FaultTrigger, InjectedFault, ScheduledCrash, SimPlatform};
use crate::reflexive::{NavigatorComponent, PoseEstimatorComponent};
use crate::remote::{PlatformLink, RemotePlatform};
use crate::report::{ComponentReport, FaultReport, InjectedFaultReport, Report, StageTimes, TaskReport};
use crate::run::{
    BusKind, CycleRecord, NoObserver, Progress, Run, RunError, RunObserver, RunOptions, RunOutput,
    RunSettings, Trace,
};
use crate::runtime::Runtime;
use crate::world::World;
use rovernav_bus::{Bus, BusError, InProcessTransport, Subscriber, TapId};
use rovernav_core::{Navigator, Point2, Pose3};
use rovernav_sim::Simulator;
use std::time::Instant;

/// Builds a run's runtime from the graph around its platform: the simulator in process, or a
/// stand-in forwarding to `link`.
pub(crate) fn assemble(
    world: &World,
    settings: &RunSettings,
    options: &RunOptions,
    origin: &str,
    link: Option<Box<dyn PlatformLink>>,
) -> Result<(Runtime, bool), RunError> {
    let (navigator, localizer) = algorithms(world, settings, origin)?;
    let remote = link.is_some();
    let platform: Box<dyn Component> = match link {
        None => {
            let sim = Simulator::new(
                world.terrain.clone(),
                world.rover.clone(),
                world.sensor_model.clone(),
                world.start,
                settings.seed,
            );
            let sim = match &options.tiles {
                Some(tiles) => sim.with_window(tiles.window()),
                None => sim,
            };
            Box::new(SimPlatform::new(sim, options.faults.clone()))
        }
        Some(link) => Box::new(RemotePlatform::new(link, &settings.name, settings.seed)),
    };
    let bus = match options.bus {
        BusKind::InProcess => Bus::in_process(),
        BusKind::Serialized => Bus::over(Box::new(InProcessTransport::new())),
    };
    let mut runtime = Runtime::new(bus)?;
    let parts = Parts {
        navigator: Some(navigator),
        localizer: Some(localizer),
        platform: Some(platform),
        settings,
        rover: &world.rover,
        options,
    };
    assemble_graph(&mut runtime, parts)?;
    Ok((runtime, remote))
}

/// Records a cycle's estimate, simulated time and the wall-clock time since the last one.
fn record_sample(trace: &mut Trace, estimate: Pose3, t: f64, clock: &mut Instant) {
    trace.estimate.push(estimate);
    trace.sim_time_s.push(t);
    trace.compute_s.push(clock.elapsed().as_secs_f64());
    *clock = Instant::now();
}

/// Executes a configured run.
pub(crate) fn drive(run: Run<'_>) -> Result<RunOutput, RunError> {
    let Run { mut world, settings, options, origin, link, judge, observer, mut operator, progress } = run;
    // In process the truth is judged here; across a link, by the simulator process.
    let mut judge: Option<Box<dyn Judge>> = match (&link, judge) {
        (Some(_), _) => None,
        (None, Some(judge)) => Some(judge),
        (None, None) => return Err(RunError::NoJudge { origin }),
    };
    let mut no_observer = NoObserver;
    let observer: &mut dyn RunObserver = match observer {
        Some(o) => o,
        None => &mut no_observer,
    };
    let mut no_progress = |_: &Progress| {};
    let on_progress: &mut dyn FnMut(&Progress) = match progress {
        Some(p) => p,
        None => &mut no_progress,
    };
    let wall = Instant::now();
    let (mut runtime, remote) = assemble(&world, &settings, &options, &origin, link)?;
    let (mut deliberative, replies, tap) =
        wire_deliberative(&mut runtime, &world, &settings, &options, observer)?;

    let mut trace = Trace::default();
    if let Some(judge) = judge.as_mut() {
        let platform = sim_platform(&runtime);
        judge.start(&world, platform.sim().truth());
        let first_frame = platform.initial_frame().clone();
        trace.estimate.push(estimator(&runtime).estimate().pose);
        trace.sim_time_s.push(first_frame.t);
        observer.on_start(&world, &settings, &first_frame, &estimator(&runtime).estimate());
    } else {
        trace.estimate.push(estimator(&runtime).estimate().pose);
        trace.sim_time_s.push(0.0);
    }
    trace.compute_s.push(0.0);
    let mut cycle_clock = Instant::now();
    runtime.command(None, ControlAction::Resume)?;
    runtime.settle(runtime.clock())?;

    let mut cycles = 0u64;
    // Planar distance between successive positions, for the progress bar.
    let (mut driven, mut last_at) = (0.0, None);
    let mut crashes = options.crashes.clone();
    let mut crashed = Vec::new();
    let (outcome, message) = loop {
        let now = match judge {
            Some(_) => sim_platform(&runtime).sim().time(),
            None => remote_platform(&mut runtime).sim_time(),
        };
        inject_due_crashes(&mut runtime, &mut crashes, &mut crashed, cycles, now, judge.is_some());
        if let Some(link) = operator.as_deref_mut() {
            for line in link.poll(cycles, deliberative.waiting()) {
                runtime.bus().publish(topics::OPERATOR_COMMAND, line)?;
            }
            if link.closed() {
                deliberative.close_input();
            }
        }
        deliberative.step(runtime.bus())?;
        forward_replies(runtime.bus(), &replies, operator.as_deref_mut())?;
        if let Some((outcome, message)) = deliberative.end() {
            break (*outcome, message.clone());
        }
        runtime.tick(now)?;
        if let Some(tap) = tap {
            observer.on_bus(&runtime.bus().take_tap(tap)?);
        }
        let plan = navigator_of(&runtime).planned_path();
        if !plan.is_empty() && trace.plans.last() != Some(&plan) {
            trace.plans.push(plan.clone());
        }
        let estimate = estimator(&runtime).estimate();
        let overlays = if observer.wants_overlays() { navigator_of(&runtime).overlays() } else { Vec::new() };
        let goal = deliberative.goal().unwrap_or(world.goal.position);
        let route = route_ahead(&deliberative);
        let mut progress = |cycles: u64, t: f64, at: Point2| {
            driven += last_at.map_or(0.0, |p: Point2| p.dist(at));
            last_at = Some(at);
            Progress {
                cycles,
                sim_time_s: t,
                time_fraction: (t / settings.time_limit_s).min(1.0),
                distance_to_goal_m: at.dist(goal),
                distance_driven_m: driven,
                route_to_go_m: crate::run::route_to_go(at, &route),
            }
        };
        match judge.as_mut() {
            Some(judge) => {
                for e in sim_platform_mut(&mut runtime).take_executed() {
                    cycles += 1;
                    judge.record(&e);
                    record_sample(&mut trace, estimate.pose, e.frame.t, &mut cycle_clock);
                    observer.on_cycle(&CycleRecord {
                        cycle: cycles,
                        sim_time_s: e.frame.t,
                        command: &e.command,
                        frame: &e.frame,
                        estimate: &estimate,
                        truth: &e.truth,
                        plan: &plan,
                        hazard_contacts: e.hazard_contacts,
                        overlays: &overlays,
                    });
                    on_progress(&progress(cycles, e.frame.t, Point2::new(e.truth.x, e.truth.y)));
                }
            }
            None => {
                for frame in remote_platform(&mut runtime).take_executed() {
                    cycles += 1;
                    record_sample(&mut trace, estimate.pose, frame.t, &mut cycle_clock);
                    // The rover process knows no truth: progress shows the estimated distance to go.
                    on_progress(&progress(cycles, frame.t, Point2::new(estimate.pose.x, estimate.pose.y)));
                }
            }
        }
    };
    // The deliberative layer's last state commands (stand down) take effect.
    runtime.settle(runtime.clock())?;
    forward_replies(runtime.bus(), &replies, operator.as_deref_mut())?;
    answer_after_end(runtime.bus(), &mut deliberative, &replies, operator)?;
    if let Some(tap) = tap {
        observer.on_bus(&runtime.bus().take_tap(tap)?);
    }
    trace.overlays = navigator_of(&runtime).overlays();
    trace.vtt = deliberative.vtt_traces();

    // Operators may have moved the goal: score against the goal the mission ended with.
    if let Some(goal) = deliberative.goal() {
        world.goal.position = goal;
    }
    let estimate = estimator(&runtime).estimate().pose;
    let judgement = match judge.as_mut() {
        Some(judge) => judge.judge(&world, sim_platform(&runtime).sim(), estimate),
        None => {
            let scoring = remote_platform(&mut runtime)
                .finish(world.goal.position, estimate)
                .map_err(|e| RunError::Bus(BusError::Transport(e.to_string())))?;
            if scoring.cycles != cycles {
                return Err(RunError::Bus(BusError::Transport(format!(
                    "the simulator executed {} commands, the rover counted {cycles}",
                    scoring.cycles
                ))));
            }
            Judgement::received(&world, scoring)
        }
    };
    trace.truth = judgement.truth;
    trace.sensed = Some(judgement.sensed);
    let scoring = judgement.scoring;
    let spent = StageTimes {
        navigation_s: runtime.busy_s("navigator"),
        localization_s: runtime.busy_s("pose-estimator"),
        platform_s: runtime.busy_s("platform"),
    };
    let message = crate::report::run_message(outcome, &message, scoring.goal_error_m);
    let message = crate::power::with_sleep(message, deliberative.power_report().as_ref());
    let injected = injected_faults(&runtime, &crashed, &scoring, remote);
    let report = Report {
        outcome: outcome.as_str().into(),
        message,
        goal_error_m: scoring.goal_error_m,
        distance_driven_m: scoring.distance_driven_m,
        optimal_length_m: scoring.optimal_length_m,
        hazard_contacts: scoring.hazard_contacts,
        sim_time_s: scoring.sim_time_s,
        wall_time_s: wall.elapsed().as_secs_f64(),
        cycles,
        sensing_actions: scoring.sensing_actions,
        localization_error_m: scoring.localization_error_m,
        navigator: navigator_of(&runtime).navigator_name().to_string(),
        localizer: settings.localizer.clone(),
        seed: settings.seed,
        mission: settings.name.clone(),
        straight_line_m: scoring.straight_line_m,
        hazard_events: scoring.hazard_events,
        compute_per_cycle: per_cycle(spent, cycles),
        localization_stats: Some(estimator(&runtime).localizer_stats().into()),
        injected_faults: injected,
        ..executive_outcome(&runtime, &deliberative)
    }
    .with_route_and_memory(world.goal.waypoints.len(), options.measure_peak_rss);
    observer.on_finish(&report, &trace);
    Ok(RunOutput { report, trace, world })
}

/// Wires the deliberative layer onto an assembled runtime: checks every port is served, builds
/// the deliberative layer from the world and settings, subscribes to operator replies, taps the
/// bus if the observer wants it, and initialises the runtime.
fn wire_deliberative(
    runtime: &mut Runtime,
    world: &World,
    mission: &RunSettings,
    options: &RunOptions,
    observer: &dyn RunObserver,
) -> Result<(Deliberative, Subscriber<String>, Option<TapId>), RunError> {
    let mut external = Deliberative::ports();
    external.push(Port::of(topics::OPERATOR_COMMAND));
    runtime.validate(&external)?;
    let config = DeliberativeConfig {
        time_limit_s: mission.time_limit_s,
        max_cycles: mission.max_cycles,
        keep_out: world.goal.keep_out.clone(),
        tolerance: world.goal.tolerance,
        mast_range_m: world.rover.mast_range,
        fault_protection: options.fault_protection.clone(),
    };
    let deliberative = Deliberative::new(runtime.bus(), &world.goal, &options.tasks, config)?
        .with_rover(world.rover.clone(), world.sensor_model.navcam.width)
        .with_power(options.power)
        .with_area({
            let g = world.terrain.dem.geometry();
            [g.origin_x, g.origin_y, g.origin_x + g.width_m(), g.origin_y + g.height_m()]
        });
    let replies = runtime.bus().subscribe(topics::OPERATOR_REPLY)?;
    let tap = if observer.wants_bus() { Some(runtime.bus().tap()?) } else { None };
    runtime.initialize(0.0)?;
    Ok((deliberative, replies, tap))
}

/// A localiser chosen by name.
type BoxedLocalizer = Box<dyn rovernav_core::Localizer>;

/// The navigator and localiser a mission names, the localiser starting at the world's start.
fn algorithms(
    world: &World,
    mission: &RunSettings,
    origin: &str,
) -> Result<(Box<dyn Navigator>, BoxedLocalizer), RunError> {
    let registry = rovernav_navigation::registry();
    let navigator: Box<dyn Navigator> = registry
        .build_navigator(&registry_name(mission), &world.rover, &mission.navigator_params)
        .map_err(|e| match e {
            rovernav_navigation::NavigatorError::UnknownNavigator { name, known } => {
                RunError::UnknownNavigator { origin: origin.into(), name, known: known.join(", ") }
            }
            other => RunError::NavigatorParams { origin: origin.into(), message: other.to_string() },
        })?;
    let initial = Pose3 { x: world.start.x, y: world.start.y, yaw: world.start.yaw, ..Default::default() };
    let no_params = rovernav_navigation::NavigatorParams::new();
    // A localiser matching against an orbital map is given one derived from the terrain.
    let prior = registry
        .localizer_needs_prior_map(&mission.localizer)
        .then(|| crate::orbital_prior::orbital_map(world, crate::orbital_prior::ORBITAL_MAP_RESOLUTION_M));
    let localizer = registry
        .build_localizer_with_prior(&mission.localizer, &world.rover, initial, &no_params, prior.as_ref())
        .map_err(|e| match e {
            rovernav_navigation::NavigatorError::UnknownLocalizer { name, known } => {
                RunError::UnknownLocalizer { origin: origin.into(), name, known: known.join(", ") }
            }
            other => RunError::NavigatorParams { origin: origin.into(), message: other.to_string() },
        })?;
    Ok((navigator, localizer))
}

/// The registry name every leg's navigator is built from: the mission's, wrapped in the
/// look-back decorator ("+look-back") when a map-matching localiser needs views back over the
/// terrain crossed (issue 5 item 5) and the name does not ask for it already. One name for
/// the first leg and the later ones, which the navigator component builds afresh.
pub(crate) fn registry_name(mission: &RunSettings) -> String {
    rovernav_navigation::registry().decorated(&mission.navigator, &mission.localizer)
}

/// The route's points still to reach: the targets of the drive tasks not yet ended, in order.
fn route_ahead(deliberative: &Deliberative) -> Vec<Point2> {
    use crate::messages::TaskState;
    deliberative
        .tasks()
        .iter()
        .filter(|t| {
            t.kind.name() == "drive_to" && matches!(t.state, TaskState::Pending | TaskState::InProcess)
        })
        .filter_map(|t| t.kind.target())
        .collect()
}

/// The report's executive part: final component states, the diagnosed fault and each task's
/// state (the same for a local and a remote run).
fn executive_outcome(runtime: &Runtime, deliberative: &Deliberative) -> Report {
    let placements = runtime.get::<crate::arm_server::ToolingArm>().map_or(&[][..], |a| a.placements());
    Report {
        components: runtime
            .states()
            .into_iter()
            .map(|c| ComponentReport {
                name: c.name.into(),
                state: c.state.as_str().into(),
                message: c.message,
            })
            .collect(),
        fault: deliberative.diagnosis().map(|(d, cycle, time_s)| FaultReport {
            kind: d.kind.as_str().into(),
            component: d.component.clone(),
            message: d.message.clone(),
            cycle: *cycle,
            time_s: *time_s,
        }),
        tasks: deliberative
            .tasks()
            .iter()
            .map(|t| TaskReport {
                id: t.id,
                kind: t.kind.name().into(),
                target: t.kind.target().map(|p| [p.x, p.y]),
                state: t.state.as_str().into(),
                message: t.message.clone(),
                placement: placements
                    .iter()
                    .rev()
                    .find(|p| Some(p.task) == t.command())
                    .filter(|_| matches!(t.kind, crate::deliberative::TaskKind::PlaceInstrument { .. }))
                    .map(|p| p.report()),
            })
            .collect(),
        power: deliberative.power_report(),
        shadow: navigator_of(runtime).shadow_report(),
        ..Report::default()
    }
}

/// Crashes the components whose drill is due before the next command (`cycles` executed so
/// far, simulated time `now`), recording each injection.
fn inject_due_crashes(
    runtime: &mut Runtime,
    pending: &mut Vec<ScheduledCrash>,
    crashed: &mut Vec<InjectedFault>,
    cycles: u64,
    now: f64,
    in_process: bool,
) {
    let (due, later): (Vec<_>, Vec<_>) = pending.drain(..).partition(|c| match c.at {
        FaultTrigger::Cycle(n) => n <= cycles + 1,
        FaultTrigger::Time(t) => t <= now,
    });
    *pending = later;
    for c in due {
        if runtime.inject_crash(&c.component) {
            let before = if in_process { sim_platform(runtime).sim().hazard_contacts() } else { 0 };
            crashed.push(InjectedFault {
                kind: "component_crash",
                component: Some(c.component),
                time_s: now,
                hazard_contacts_before: before,
            });
        }
    }
}

/// The report's list of injected faults (platform faults and crashes, in time order) with the
/// true hazard contacts after each.
fn injected_faults(
    runtime: &Runtime,
    crashed: &[InjectedFault],
    scoring: &crate::judge::Scoring,
    remote: bool,
) -> Vec<InjectedFaultReport> {
    let mut all = fault_reports(crashed, scoring.hazard_contacts);
    if remote {
        // The simulator process injected the platform's faults and reports them.
        all.extend(scoring.injected_faults.iter().cloned());
    } else {
        all.extend(fault_reports(sim_platform(runtime).injected_faults(), scoring.hazard_contacts));
    }
    all.sort_by(|a, b| a.time_s.total_cmp(&b.time_s));
    all
}

/// Injected faults as the report gives them, with the true hazard contacts after each (of
/// `contacts` at the end).
pub(crate) fn fault_reports(faults: &[InjectedFault], contacts: u32) -> Vec<InjectedFaultReport> {
    faults
        .iter()
        .map(|f| InjectedFaultReport {
            kind: f.kind.into(),
            component: f.component.clone(),
            time_s: f.time_s,
            hazard_contacts_after: contacts.saturating_sub(f.hazard_contacts_before),
        })
        .collect()
}

/// Answers the operator's lines still to come once the mission is over ("mission over:
/// <outcome>" for a command, the answer for `status` or `help`) instead of dropping them: every
/// line the link still gives, until it gives none.
fn answer_after_end<'a>(
    bus: &mut Bus,
    deliberative: &mut Deliberative,
    replies: &Subscriber<String>,
    operator: Option<&mut (dyn OperatorLink + 'a)>,
) -> Result<(), BusError> {
    let Some(link) = operator else { return Ok(()) };
    loop {
        let lines = link.poll(u64::MAX, true);
        if lines.is_empty() {
            return Ok(());
        }
        for line in lines {
            bus.publish(topics::OPERATOR_COMMAND, line)?;
        }
        deliberative.step(bus)?;
        forward_replies(bus, replies, Some(&mut *link))?;
    }
}

/// Hands the deliberative layer's answers to the operator.
fn forward_replies<'a>(
    bus: &mut Bus,
    replies: &Subscriber<String>,
    operator: Option<&mut (dyn OperatorLink + 'a)>,
) -> Result<(), BusError> {
    let answers = bus.take(replies)?;
    if let Some(link) = operator {
        for a in answers.iter().filter(|a| !a.is_empty()) {
            link.reply(a);
        }
    }
    Ok(())
}

// Every run adds these components ([`crate::graph::NODES`]), so the look-ups cannot fail.
fn sim_platform(rt: &Runtime) -> &SimPlatform {
    rt.get::<SimPlatform>().expect("an in-process run has a simulated platform")
}
fn sim_platform_mut(rt: &mut Runtime) -> &mut SimPlatform {
    rt.get_mut::<SimPlatform>().expect("an in-process run has a simulated platform")
}
fn remote_platform(rt: &mut Runtime) -> &mut RemotePlatform {
    rt.get_mut::<RemotePlatform>().expect("a remote run has a remote platform")
}
fn estimator(rt: &Runtime) -> &PoseEstimatorComponent {
    rt.get::<PoseEstimatorComponent>().expect("every run has a pose estimator")
}
fn navigator_of(rt: &Runtime) -> &NavigatorComponent {
    rt.get::<NavigatorComponent>().expect("every run has a navigator")
}

/// Totals divided by the cycle count (zero when no command ran).
fn per_cycle(total: StageTimes, cycles: u64) -> StageTimes {
    let n = cycles.max(1) as f64;
    StageTimes {
        navigation_s: total.navigation_s / n,
        localization_s: total.localization_s / n,
        platform_s: total.platform_s / n,
    }
}
