//! The navigation loop: navigator <-> platform, with the localiser in between.

use crate::mission::Mission;
use crate::report::{HazardEvent, Report, StageTimes};
use crate::world::{World, WorldError, build_world};
use rovernav_core::{
    Goal, Grid2, GridGeometry, NavCommand, NavInput, Navigator, Outcome, Overlay, Point2, Pose3,
    PoseEstimate, SensorFrame,
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
}

impl RunSettings {
    /// The settings of a mission file.
    pub fn of(mission: &Mission) -> Self {
        Self {
            navigator: mission.navigator.clone(),
            localizer: mission.localizer.clone(),
            seed: mission.seed,
            time_limit_s: mission.time_limit_s,
            max_cycles: mission.max_cycles,
            name: mission.name.clone(),
        }
    }
}

/// Runs a mission to completion. `origin` names the mission source in error messages.
pub fn run_mission(
    mission: &Mission,
    origin: &str,
    on_progress: &mut dyn FnMut(&Progress),
) -> Result<RunOutput, RunError> {
    let world = build_world(mission, origin)?;
    run_world(world, &RunSettings::of(mission), origin, on_progress)
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
    let world = build_world(mission, origin)?;
    run_world_observed(world, &RunSettings::of(mission), origin, on_progress, observer)
}

/// [`run_world`] with an observer watching every cycle.
pub fn run_world_observed(
    world: World,
    mission: &RunSettings,
    origin: &str,
    on_progress: &mut dyn FnMut(&Progress),
    observer: &mut dyn RunObserver,
) -> Result<RunOutput, RunError> {
    let wall = Instant::now();
    let mut navigator: Box<dyn Navigator> =
        rovernav_navigation::navigator_by_name(&mission.navigator, &world.rover).ok_or_else(|| {
            RunError::UnknownNavigator {
                origin: origin.into(),
                name: mission.navigator.clone(),
                known: rovernav_navigation::NAVIGATOR_NAMES.join(", "),
            }
        })?;
    let initial = Pose3 { x: world.start.x, y: world.start.y, yaw: world.start.yaw, ..Default::default() };
    let mut localizer = rovernav_localization::localizer_by_name(&mission.localizer, &world.rover, initial)
        .ok_or_else(|| RunError::UnknownLocalizer {
        origin: origin.into(),
        name: mission.localizer.clone(),
        known: rovernav_localization::LOCALIZER_NAMES.join(", "),
    })?;

    let mut sim = Simulator::new(
        world.terrain.clone(),
        world.rover.clone(),
        world.sensor_model.clone(),
        world.start,
        mission.seed,
    );
    let goal: Goal = world.goal.clone();
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

    let mut frame: SensorFrame = sim.initial_frame();
    localizer.update(&frame);
    trace.truth.push(sim.truth());
    trace.estimate.push(localizer.estimate().pose);
    observer.on_start(&world, mission, &frame, &localizer.estimate());
    let mut cycles = 0u64;
    let mut spent = StageTimes::default();
    let mut last_hazards = 0;
    let mut hazard_events = Vec::new();
    let (outcome, message) = loop {
        if sim.time() >= mission.time_limit_s {
            break (Outcome::Timeout, format!("mission time limit of {} s reached", mission.time_limit_s));
        }
        if cycles >= mission.max_cycles {
            break (Outcome::Timeout, format!("cycle limit of {} reached", mission.max_cycles));
        }
        let input = NavInput { time: sim.time(), estimate: localizer.estimate(), goal: &goal, frame: &frame };
        let started = Instant::now();
        let command = navigator.step(&input);
        spent.navigation_s += started.elapsed().as_secs_f64();
        let plan = navigator.planned_path();
        if !plan.is_empty() && trace.plans.last() != Some(&plan) {
            trace.plans.push(plan.clone());
        }
        if let NavCommand::Finish(outcome, message) = command {
            break (outcome, message);
        }
        let started = Instant::now();
        frame = sim.execute(&command);
        spent.platform_s += started.elapsed().as_secs_f64();
        let started = Instant::now();
        localizer.update(&frame);
        spent.localization_s += started.elapsed().as_secs_f64();
        cycles += 1;
        let truth = sim.truth();
        for cloud in &frame.clouds {
            mark_sensed(&mut sensed, &truth, cloud);
        }
        if sim.hazard_contacts() > last_hazards {
            last_hazards = sim.hazard_contacts();
            hazard_events.push(HazardEvent {
                x: truth.x,
                y: truth.y,
                cycle: cycles,
                cause: frame.motion_stopped.clone().unwrap_or_default(),
            });
        }
        trace.truth.push(truth);
        let estimate = localizer.estimate();
        trace.estimate.push(estimate.pose);
        observer.on_cycle(&CycleRecord {
            cycle: cycles,
            sim_time_s: sim.time(),
            command: &command,
            frame: &frame,
            estimate: &estimate,
            truth: &truth,
            plan: &plan,
            hazard_contacts: sim.hazard_contacts(),
        });
        let truth_pos = Point2::new(truth.x, truth.y);
        on_progress(&Progress {
            cycles,
            sim_time_s: sim.time(),
            time_fraction: (sim.time() / mission.time_limit_s).min(1.0),
            distance_to_goal_m: truth_pos.dist(goal.position),
        });
    };
    trace.overlays = navigator.overlays();
    trace.sensed = Some(sensed);

    let truth = sim.truth();
    let estimate = localizer.estimate().pose;
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
        navigator: navigator.name().to_string(),
        localizer: mission.localizer.clone(),
        seed: mission.seed,
        mission: mission.name.clone(),
        straight_line_m: world.start.position().dist(goal.position),
        hazard_events,
        compute_per_cycle: per_cycle(spent, cycles),
    };
    observer.on_finish(&report, &trace);
    Ok(RunOutput { report, trace, world })
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

/// Marks the cells a cloud's points fall in (display only, so true placement is fine).
fn mark_sensed(sensed: &mut Grid2<bool>, truth: &Pose3, cloud: &rovernav_core::PointCloud) {
    for p in &cloud.points {
        let w = truth.transform([p[0] as f64, p[1] as f64, p[2] as f64]);
        if let Some((c, r)) = sensed.geometry.cell_of(w[0], w[1]) {
            *sensed.get_mut(c, r) = true;
        }
    }
}
