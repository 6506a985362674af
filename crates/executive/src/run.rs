//! A run: the world and the mission's components wired on a bus, stepped until the deliberative
//! layer ends the mission, and scored against simulator truth.
//!
//! The loop itself holds no autonomy: the deliberative layer ([`crate::deliberative`]) presents
//! the plan to the reflexive components ([`crate::reflexive`], [`crate::sensor_servers`]) and the
//! platform ([`crate::platform`]), which the runtime ([`crate::runtime`]) steps on simulated
//! time. What the loop does is watch: it reads truth from the platform for the report, the
//! traverse picture and observers, and relays operator lines and answers.

use crate::components::Port;
use crate::deliberative::{Deliberative, DeliberativeConfig, TaskSpec};
use crate::fault_protection::FaultProtectionConfig;
use crate::messages::{ControlAction, topics};
use crate::mission::Mission;
use crate::operator::OperatorLink;
use crate::platform::{ArmConfig, ScheduledFault, SimPlatform, ToolingArm};
use crate::reflexive::{MotionController, NavigatorComponent, PoseEstimatorComponent, PoseEstimatorConfig};
use crate::report::{ComponentReport, FaultReport, HazardEvent, Report, StageTimes, TaskReport};
use crate::runtime::{Runtime, RuntimeError};
use crate::sensor_servers::{
    ContactMonitor, InertialSensors, MAX_BODY_CONTACTS, RangeSensors, WheelOdometry,
};
use crate::world::{World, WorldError, build_world};
use rovernav_bus::{Bus, BusError, InProcessTransport, Record, Subscriber, TapId};
use rovernav_core::{
    Grid2, GridGeometry, NavCommand, Navigator, Overlay, Point2, Pose3, PoseEstimate, SensorFrame,
};
use rovernav_sim::Simulator;
use std::time::Instant;

/// Why a run could not start.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The world could not be built (missing or corrupt DEM, bad region...).
    #[error(transparent)]
    World(#[from] WorldError),
    /// The mission names a navigator that is not registered.
    #[error("{origin}: field `navigator`: unknown navigator `{name}` (known: {known})")]
    UnknownNavigator {
        /// Where the name came from (mission file or command line).
        origin: String,
        /// The name given.
        name: String,
        /// Registered names.
        known: String,
    },
    /// The mission's navigator parameters name an unknown parameter or an out-of-range value.
    #[error("{origin}: field `navigator_params`: {message}")]
    NavigatorParams {
        /// Where the parameters came from.
        origin: String,
        /// Which parameter and why.
        message: String,
    },
    /// The mission names a localiser that is not registered.
    #[error("{origin}: field `localizer`: unknown localizer `{name}` (known: {known})")]
    UnknownLocalizer {
        /// Where the name came from.
        origin: String,
        /// The name given.
        name: String,
        /// Registered names.
        known: String,
    },
    /// The components could not be assembled or stepped.
    #[error(transparent)]
    Runtime(#[from] RuntimeError),
    /// A bus operation of the deliberative layer or the loop failed.
    #[error(transparent)]
    Bus(#[from] BusError),
}

/// What the loop records for pictures and replay.
#[derive(Clone, Debug, Default)]
pub struct Trace {
    /// True pose after every command (and at the start).
    pub truth: Vec<Pose3>,
    /// Estimated pose after every command (and at the start).
    pub estimate: Vec<Pose3>,
    /// Every distinct plan the navigator announced (world frame).
    pub plans: Vec<Vec<Point2>>,
    /// The navigator's overlays at the end of the run.
    pub overlays: Vec<Overlay>,
    /// Cells covered by range data (placed with the true pose: this is for display only).
    pub sensed: Option<Grid2<bool>>,
}

/// Everything a run produces.
pub struct RunOutput {
    /// The summary.
    pub report: Report,
    /// The recorded traverse.
    pub trace: Trace,
    /// The world the run used.
    pub world: World,
}

/// Progress of a run, for a progress bar.
#[derive(Clone, Copy, Debug)]
pub struct Progress {
    /// Navigator cycles so far.
    pub cycles: u64,
    /// Simulated time (s).
    pub sim_time_s: f64,
    /// Fraction of the mission time budget used.
    pub time_fraction: f64,
    /// True distance to the goal (m).
    pub distance_to_goal_m: f64,
}

/// One navigator cycle as the loop saw it, for telemetry and other observers.
#[derive(Clone, Copy, Debug)]
pub struct CycleRecord<'a> {
    /// Cycle number (1 for the first command).
    pub cycle: u64,
    /// Simulated time after the command (s).
    pub sim_time_s: f64,
    /// The command the navigator issued.
    pub command: &'a NavCommand,
    /// What the platform reported after executing it.
    pub frame: &'a SensorFrame,
    /// The localiser's estimate after the frame.
    pub estimate: &'a PoseEstimate,
    /// Simulator truth after the command (scoring and logs only; never shown to the autonomy).
    pub truth: &'a Pose3,
    /// The navigator's current plan (world frame).
    pub plan: &'a [Point2],
    /// Hazard contacts so far.
    pub hazard_contacts: u32,
}

/// Watches a run from outside the loop (telemetry logs, live displays); never steers it.
pub trait RunObserver {
    /// Called once before the first command with the world, the settings and the first frame.
    fn on_start(
        &mut self,
        _world: &World,
        _settings: &RunSettings,
        _frame: &SensorFrame,
        _estimate: &PoseEstimate,
    ) {
    }
    /// Called after every executed command.
    fn on_cycle(&mut self, _record: &CycleRecord<'_>) {}
    /// Called once with the final report and trace.
    fn on_finish(&mut self, _report: &Report, _trace: &Trace) {}
    /// Whether to receive every bus message as JSON ([`RunObserver::on_bus`]); serializing
    /// every message costs time, so only observers that record the bus ask for it.
    fn wants_bus(&self) -> bool {
        false
    }
    /// Every message published on the bus since the last call, in publish order, stamped with
    /// simulated time (called after each cycle and once before `on_finish`).
    fn on_bus(&mut self, _records: &[Record]) {}
}

/// An observer that does nothing.
pub struct NoObserver;

impl RunObserver for NoObserver {}

/// The run settings a mission gives besides its world.
#[derive(Clone, Debug, PartialEq)]
pub struct RunSettings {
    /// Navigator registry name.
    pub navigator: String,
    /// Localiser registry name.
    pub localizer: String,
    /// Seed of every sensor's noise.
    pub seed: u64,
    /// Mission time budget (s).
    pub time_limit_s: f64,
    /// Navigator cycle budget.
    pub max_cycles: u64,
    /// Mission name for the report.
    pub name: String,
    /// Navigator parameters (the mission's `[navigator_params]`).
    pub navigator_params: rovernav_navigation::NavigatorParams,
}

impl RunSettings {
    /// The settings of a mission file.
    pub fn of(mission: &Mission) -> Self {
        Self {
            navigator: mission.navigator_spec(),
            localizer: mission.localizer_spec(),
            seed: mission.seed,
            time_limit_s: mission.time_limit_s,
            max_cycles: mission.max_cycles,
            name: mission.name.clone(),
            navigator_params: mission.navigator_params.clone(),
        }
    }
}

/// Which bus the components talk over.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BusKind {
    /// The deterministic in-process bus, without serialization (the default).
    #[default]
    InProcess,
    /// Every message serialized to JSON through the in-process transport, as a networked
    /// transport would carry it (gives the same run; proves the messages survive the wire).
    Serialized,
}

/// What a run does besides driving to the world's goal: the mission's extra tasks, scheduled
/// faults, the components' parameters and the bus.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Tasks after the goal (`[[tasks]]`).
    pub tasks: Vec<TaskSpec>,
    /// Faults the platform injects (`[[faults]]`).
    pub faults: Vec<ScheduledFault>,
    /// Fault-protection thresholds.
    pub fault_protection: FaultProtectionConfig,
    /// Pose-estimator thresholds.
    pub pose_estimator: PoseEstimatorConfig,
    /// Tooling-arm parameters.
    pub arm: ArmConfig,
    /// The bus.
    pub bus: BusKind,
}

impl RunOptions {
    /// The tasks and faults of a mission file (targets mapped into the world's local frame).
    pub fn of(mission: &Mission, world: &World) -> Self {
        let to_local = crate::world::goal_frame_to_local(mission, world);
        Self { tasks: mission.plan_tasks(&to_local), faults: mission.fault_schedule(), ..Self::default() }
    }
}

/// Runs a mission to completion. `origin` names the mission source in error messages.
pub fn run_mission(
    mission: &Mission,
    origin: &str,
    on_progress: &mut dyn FnMut(&Progress),
) -> Result<RunOutput, RunError> {
    run_mission_observed(mission, origin, on_progress, &mut NoObserver)
}

/// Runs a traverse in a given world (hand-built scenario terrains use this directly).
pub fn run_world(
    world: World,
    mission: &RunSettings,
    origin: &str,
    on_progress: &mut dyn FnMut(&Progress),
) -> Result<RunOutput, RunError> {
    run_world_observed(world, mission, origin, on_progress, &mut NoObserver)
}

/// Runs a mission with an observer watching every cycle.
pub fn run_mission_observed(
    mission: &Mission,
    origin: &str,
    on_progress: &mut dyn FnMut(&Progress),
    observer: &mut dyn RunObserver,
) -> Result<RunOutput, RunError> {
    run_mission_with(mission, origin, on_progress, observer, None)
}

/// [`run_mission_observed`] with an operator sending commands while the mission runs.
pub fn run_mission_with(
    mission: &Mission,
    origin: &str,
    on_progress: &mut dyn FnMut(&Progress),
    observer: &mut dyn RunObserver,
    operator: Option<&mut dyn OperatorLink>,
) -> Result<RunOutput, RunError> {
    let world = build_world(mission, origin)?;
    let options = RunOptions::of(mission, &world);
    run_world_with(world, &RunSettings::of(mission), &options, origin, on_progress, observer, operator)
}

/// Wires the deliberative layer onto a runtime whose components are added (local or remote
/// platform alike): checks every port is served, builds the deliberative layer from the world and
/// settings, subscribes to operator replies, taps the bus if the observer wants it, and
/// initialises the runtime.
pub(crate) fn wire_deliberative(
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
        .with_rover(world.rover.clone(), world.sensor_model.navcam.width);
    let replies = runtime.bus().subscribe(topics::OPERATOR_REPLY)?;
    let tap = if observer.wants_bus() { Some(runtime.bus().tap()?) } else { None };
    runtime.initialize(0.0)?;
    Ok((deliberative, replies, tap))
}

/// [`run_world`] with an observer watching every cycle.
pub fn run_world_observed(
    world: World,
    mission: &RunSettings,
    origin: &str,
    on_progress: &mut dyn FnMut(&Progress),
    observer: &mut dyn RunObserver,
) -> Result<RunOutput, RunError> {
    run_world_with(world, mission, &RunOptions::default(), origin, on_progress, observer, None)
}

/// Runs a traverse through the components and the bus: the deliberative layer presents the plan
/// to the reflexive layer, the runtime steps the components, and this loop only watches (truth
/// for scoring and pictures, observer callbacks, operator input and answers).
pub fn run_world_with(
    mut world: World,
    mission: &RunSettings,
    options: &RunOptions,
    origin: &str,
    on_progress: &mut dyn FnMut(&Progress),
    observer: &mut dyn RunObserver,
    mut operator: Option<&mut dyn OperatorLink>,
) -> Result<RunOutput, RunError> {
    let wall = Instant::now();
    let (navigator, localizer) = algorithms(&world, mission, origin)?;
    let sim = Simulator::new(
        world.terrain.clone(),
        world.rover.clone(),
        world.sensor_model.clone(),
        world.start,
        mission.seed,
    );

    let bus = match options.bus {
        BusKind::InProcess => Bus::in_process(),
        BusKind::Serialized => Bus::over(Box::new(InProcessTransport::new())),
    };
    let mut runtime = Runtime::new(bus)?;
    let sim_platform = Box::new(SimPlatform::new(sim, options.faults.clone()));
    add_components(&mut runtime, navigator, localizer, mission, &world.rover, options, sim_platform)?;
    let (mut deliberative, replies, tap) =
        wire_deliberative(&mut runtime, &world, mission, options, observer)?;

    let mut trace = Trace::default();
    let dem_geometry = *world.terrain.dem.geometry();
    let sensed_res = dem_geometry.resolution.max(0.1);
    let sensed_geometry = GridGeometry {
        cols: (dem_geometry.width_m() / sensed_res).ceil() as usize,
        rows: (dem_geometry.height_m() / sensed_res).ceil() as usize,
        resolution: sensed_res,
        ..dem_geometry
    };
    let mut sensed = Grid2::filled(sensed_geometry, false);
    let first_frame = platform(&runtime).initial_frame().clone();
    trace.truth.push(platform(&runtime).sim().truth());
    trace.estimate.push(estimator(&runtime).estimate().pose);
    observer.on_start(&world, mission, &first_frame, &estimator(&runtime).estimate());
    runtime.command(None, ControlAction::Resume)?;
    runtime.settle(runtime.clock())?;

    let mut cycles = 0u64;
    let mut last_hazards = 0;
    let mut hazard_events = Vec::new();
    let (outcome, message) = loop {
        let now = platform(&runtime).sim().time();
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
        let executed = platform_mut(&mut runtime).take_executed();
        let plan = navigator_of(&runtime).planned_path();
        if !plan.is_empty() && trace.plans.last() != Some(&plan) {
            trace.plans.push(plan.clone());
        }
        let estimate = estimator(&runtime).estimate();
        for e in executed {
            cycles += 1;
            for cloud in &e.frame.clouds {
                mark_sensed(&mut sensed, &e.truth, cloud);
            }
            if e.hazard_contacts > last_hazards {
                last_hazards = e.hazard_contacts;
                hazard_events.push(HazardEvent {
                    x: e.truth.x,
                    y: e.truth.y,
                    cycle: cycles,
                    cause: e.frame.motion_stopped.clone().unwrap_or_default(),
                });
            }
            trace.truth.push(e.truth);
            trace.estimate.push(estimate.pose);
            let sim_time_s = e.frame.t;
            observer.on_cycle(&CycleRecord {
                cycle: cycles,
                sim_time_s,
                command: &e.command,
                frame: &e.frame,
                estimate: &estimate,
                truth: &e.truth,
                plan: &plan,
                hazard_contacts: e.hazard_contacts,
            });
            let goal = deliberative.goal().unwrap_or(world.goal.position);
            on_progress(&Progress {
                cycles,
                sim_time_s,
                time_fraction: (sim_time_s / mission.time_limit_s).min(1.0),
                distance_to_goal_m: Point2::new(e.truth.x, e.truth.y).dist(goal),
            });
        }
    };
    // The deliberative layer's last state commands (stand down) take effect.
    runtime.settle(runtime.clock())?;
    forward_replies(runtime.bus(), &replies, operator)?;
    if let Some(tap) = tap {
        observer.on_bus(&runtime.bus().take_tap(tap)?);
    }
    trace.overlays = navigator_of(&runtime).overlays();
    trace.sensed = Some(sensed);

    // Operators may have moved the goal: score against the goal the mission ended with.
    if let Some(goal) = deliberative.goal() {
        world.goal.position = goal;
    }
    let goal = world.goal.clone();
    let sim = platform(&runtime).sim();
    let truth = sim.truth();
    let estimate = estimator(&runtime).estimate().pose;
    let spent = StageTimes {
        navigation_s: runtime.busy_s("navigator"),
        localization_s: runtime.busy_s("pose-estimator"),
        platform_s: runtime.busy_s("platform"),
    };
    let report = Report {
        outcome: outcome.as_str().into(),
        message,
        goal_error_m: Point2::new(truth.x, truth.y).dist(goal.position),
        distance_driven_m: sim.distance_driven(),
        optimal_length_m: crate::world::optimal_length(&world),
        hazard_contacts: sim.hazard_contacts(),
        sim_time_s: sim.time(),
        wall_time_s: wall.elapsed().as_secs_f64(),
        cycles,
        sensing_actions: sim.sensing_actions(),
        localization_error_m: (truth.x - estimate.x).hypot(truth.y - estimate.y),
        navigator: navigator_of(&runtime).navigator_name().to_string(),
        localizer: mission.localizer.clone(),
        seed: mission.seed,
        mission: mission.name.clone(),
        straight_line_m: world.start.position().dist(goal.position),
        hazard_events,
        compute_per_cycle: per_cycle(spent, cycles),
        localization_stats: Some(estimator(&runtime).localizer_stats().into()),
        ..executive_outcome(&runtime, &deliberative)
    };
    observer.on_finish(&report, &trace);
    Ok(RunOutput { report, trace, world })
}

/// A localiser chosen by name.
type BoxedLocalizer = Box<dyn rovernav_core::Localizer>;

/// The navigator and localiser a mission names, the localiser starting at the world's start.
pub(crate) fn algorithms(
    world: &World,
    mission: &RunSettings,
    origin: &str,
) -> Result<(Box<dyn Navigator>, BoxedLocalizer), RunError> {
    let registry = rovernav_navigation::registry();
    let navigator: Box<dyn Navigator> =
        registry.build_navigator(&registry_name(mission), &world.rover, &mission.navigator_params).map_err(
            |e| match e {
                rovernav_navigation::NavigatorError::UnknownNavigator { name, known } => {
                    RunError::UnknownNavigator { origin: origin.into(), name, known: known.join(", ") }
                }
                other => RunError::NavigatorParams { origin: origin.into(), message: other.to_string() },
            },
        )?;
    let initial = Pose3 { x: world.start.x, y: world.start.y, yaw: world.start.yaw, ..Default::default() };
    let no_params = rovernav_navigation::NavigatorParams::new();
    let localizer =
        registry.build_localizer(&mission.localizer, &world.rover, initial, &no_params).map_err(|e| match e {
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
fn registry_name(mission: &RunSettings) -> String {
    rovernav_navigation::registry().decorated(&mission.navigator, &mission.localizer)
}

/// The report's executive part: final component states, the diagnosed fault and each task's
/// state (the same for a local and a remote run).
pub(crate) fn executive_outcome(runtime: &Runtime, deliberative: &Deliberative) -> Report {
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
            })
            .collect(),
        ..Report::default()
    }
}

/// Adds a run's components in stepping order around a platform (the simulator in process, or
/// its stand-in across a link): one list, so a remote run steps exactly as a local one.
pub(crate) fn add_components(
    runtime: &mut Runtime,
    navigator: Box<dyn Navigator>,
    localizer: Box<dyn rovernav_core::Localizer>,
    mission: &RunSettings,
    rover: &rovernav_core::RoverConfig,
    options: &RunOptions,
    platform: Box<dyn crate::components::Component>,
) -> Result<(), RuntimeError> {
    runtime.add(Box::new(
        NavigatorComponent::new(navigator, &registry_name(mission), rover.clone())
            .with_params(mission.navigator_params.clone()),
    ))?;
    runtime.add(Box::new(ToolingArm::new(options.arm.clone())))?;
    runtime.add(Box::new(MotionController::new()))?;
    runtime.add(platform)?;
    runtime.add(Box::new(RangeSensors::new()))?;
    runtime.add(Box::new(crate::camera_server::CameraServer::new()))?;
    runtime.add(Box::new(InertialSensors::new()))?;
    runtime.add(Box::new(WheelOdometry::new(rover.encoder_counts_per_cm, rover.track)))?;
    runtime.add(Box::new(ContactMonitor::new(MAX_BODY_CONTACTS)))?;
    runtime.add(Box::new(PoseEstimatorComponent::new(localizer, options.pose_estimator.clone())))?;
    Ok(())
}

/// Hands the deliberative layer's answers to the operator.
pub(crate) fn forward_replies<'a>(
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

// Every run adds these components (above), so the look-ups cannot fail.
fn platform(rt: &Runtime) -> &SimPlatform {
    rt.get::<SimPlatform>().expect("every run has a platform")
}
fn platform_mut(rt: &mut Runtime) -> &mut SimPlatform {
    rt.get_mut::<SimPlatform>().expect("every run has a platform")
}
pub(crate) fn estimator(rt: &Runtime) -> &PoseEstimatorComponent {
    rt.get::<PoseEstimatorComponent>().expect("every run has a pose estimator")
}
pub(crate) fn navigator_of(rt: &Runtime) -> &NavigatorComponent {
    rt.get::<NavigatorComponent>().expect("every run has a navigator")
}

/// Totals divided by the cycle count (zero when no command ran).
pub(crate) fn per_cycle(total: StageTimes, cycles: u64) -> StageTimes {
    let n = cycles.max(1) as f64;
    StageTimes {
        navigation_s: total.navigation_s / n,
        localization_s: total.localization_s / n,
        platform_s: total.platform_s / n,
    }
}

/// Marks the cells a cloud's points fall in (display only, so true placement is fine).
pub(crate) fn mark_sensed(sensed: &mut Grid2<bool>, truth: &Pose3, cloud: &rovernav_core::PointCloud) {
    for p in &cloud.points {
        let w = truth.transform([p[0] as f64, p[1] as f64, p[2] as f64]);
        if let Some((c, r)) = sensed.geometry.cell_of(w[0], w[1]) {
            *sensed.get_mut(c, r) = true;
        }
    }
}
