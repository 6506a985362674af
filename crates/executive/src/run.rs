//! A run: what it is given ([`RunSettings`], [`RunOptions`], an observer, an operator, a remote
//! platform), what it produces ([`RunOutput`]) and the one builder every caller goes through
//! ([`Run`]).
//!
//! The loop itself ([`crate::run_loop`]) holds no autonomy: the deliberative layer presents the
//! plan to the components of the graph ([`crate::graph`]), which the runtime steps on simulated
//! time; the loop watches (observer callbacks, operator lines and answers) and asks the run's
//! judge ([`crate::judge`], supplied by the harness) for the truth-based figures and pictures.
//!
//! A run is given its world; building one from a mission file is the harness's
//! (`rovernav_harness`: `Run::mission` with its `JudgedRun` trait in scope).

use crate::deliberative::TaskSpec;
use crate::fault_protection::FaultProtectionConfig;
use crate::judge::Judge;
use crate::mission::Mission;
use crate::operator::OperatorLink;
use crate::platform::{ArmConfig, ScheduledFault};
use crate::reflexive::PoseEstimatorConfig;
use crate::remote::PlatformLink;
use crate::report::Report;
use crate::runtime::RuntimeError;
use crate::world::{World, WorldError};
use rovernav_bus::{BusError, Record};
use rovernav_core::{Grid2, NavCommand, Overlay, Point2, Pose3, PoseEstimate, SensorFrame};

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
    /// A run against the simulator in process was given no judge.
    #[error(
        "{origin}: a run against the simulator in process needs a judge (rovernav_harness: Run::mission or .judged())"
    )]
    NoJudge {
        /// The run's mission source.
        origin: String,
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
    /// Simulated time of every pose in `estimate` (s; the start, then after every command).
    pub sim_time_s: Vec<f64>,
    /// Wall-clock time the loop spent on each cycle, from the previous command's end to this
    /// one's (s; 0 for the start), for the same samples; empty when unknown.
    pub compute_s: Vec<f64>,
    /// Every VTT task's designated target and its estimates (site frame), by task id.
    pub vtt: Vec<crate::deliberative::VttTrace>,
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
    /// Distance driven so far (m, planar, between cycles; by the estimate across a link).
    pub distance_driven_m: f64,
    /// Distance still to go along the route: to the next waypoint, then leg by leg to the goal
    /// (m, straight lines).
    pub route_to_go_m: f64,
}

/// The length of the route from `at` through `points` in order (m, straight legs).
pub fn route_to_go(at: Point2, points: &[Point2]) -> f64 {
    let mut length = 0.0;
    let mut from = at;
    for &p in points {
        length += from.dist(p);
        from = p;
    }
    length
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
    /// The navigator's drawings after the command (world frame); empty unless the observer
    /// asks for them ([`RunObserver::wants_overlays`]).
    pub overlays: &'a [Overlay],
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
    /// Whether [`CycleRecord::overlays`] should hold the navigator's drawings every cycle;
    /// drawing them costs time, so only observers that show them ask.
    fn wants_overlays(&self) -> bool {
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
    /// Component crashes the loop injects (`[[faults]]` of kind `component_crash`).
    pub crashes: Vec<crate::platform::ScheduledCrash>,
    /// Fault-protection thresholds.
    pub fault_protection: FaultProtectionConfig,
    /// Pose-estimator thresholds.
    pub pose_estimator: PoseEstimatorConfig,
    /// Tooling-arm parameters.
    pub arm: ArmConfig,
    /// The bus.
    pub bus: BusKind,
    /// The tiled terrain the simulator drives on through a window (`kind = "tiled"`; none for a
    /// fixed terrain; the harness's `mission_options` fills it from a mission).
    pub tiles: Option<crate::world::TiledSource>,
    /// Whether the report gives the process's peak resident memory (`peak_rss_mb`).
    pub measure_peak_rss: bool,
    /// Sleep and wake thresholds on the battery's charge (`[power]`).
    pub power: crate::power::PowerPolicy,
    /// A navigator to run in shadow beside the driving one (`shadow_navigator`; paper 003
    /// section 6's "no update" checkout).
    pub shadow_navigator: Option<String>,
}

impl RunOptions {
    /// The tasks and faults of a mission file (targets mapped into the world's local frame);
    /// the simulator's tiles are the harness's to build (`rovernav_harness::mission_options`).
    pub fn of(mission: &Mission, world: &World) -> Self {
        let to_local = crate::world::goal_frame_to_local(mission, world);
        Self {
            tasks: mission.plan_tasks(&to_local),
            faults: mission.fault_schedule(),
            crashes: mission.crash_schedule(),
            power: mission.power.policy(),
            shadow_navigator: mission.shadow_navigator_spec(),
            ..Self::default()
        }
    }
}

/// A run, configured step by step and then executed: the one entry point of every run, in
/// process or against a remote platform.
///
/// A mission file's run comes from the harness, which builds the world and supplies the
/// judge: `Run::mission(&mission, "built-in default mission")?.execute()?` with
/// `rovernav_harness::JudgedRun` in scope; a hand-built world's run is
/// `Run::new(world, settings).judge(judge)`.
pub struct Run<'a> {
    pub(crate) world: World,
    pub(crate) settings: RunSettings,
    pub(crate) options: RunOptions,
    pub(crate) origin: String,
    pub(crate) link: Option<Box<dyn PlatformLink>>,
    pub(crate) judge: Option<Box<dyn Judge>>,
    pub(crate) observer: Option<&'a mut dyn RunObserver>,
    pub(crate) operator: Option<&'a mut dyn OperatorLink>,
    pub(crate) progress: Option<&'a mut dyn FnMut(&Progress)>,
}

impl<'a> Run<'a> {
    /// A traverse of `settings` in a given world, without extra tasks or faults, against the
    /// simulator in process (which needs a [`Run::judge`]).
    pub fn new(world: World, settings: RunSettings) -> Self {
        Self {
            world,
            settings,
            options: RunOptions::default(),
            origin: "run".into(),
            link: None,
            judge: None,
            observer: None,
            operator: None,
            progress: None,
        }
    }

    /// Replaces the tasks, faults, component parameters and bus.
    pub fn options(mut self, options: RunOptions) -> Self {
        self.options = options;
        self
    }

    /// Gives the process's peak resident memory in the report (`peak_rss_mb`).
    pub fn measure_peak_rss(mut self) -> Self {
        self.options.measure_peak_rss = true;
        self
    }

    /// Names the mission source in error messages.
    pub fn origin(mut self, origin: &str) -> Self {
        self.origin = origin.to_string();
        self
    }

    /// An observer watching every cycle (telemetry logs, live displays).
    pub fn observer(mut self, observer: &'a mut dyn RunObserver) -> Self {
        self.observer = Some(observer);
        self
    }

    /// An operator sending commands while the mission runs.
    pub fn operator(mut self, operator: &'a mut dyn OperatorLink) -> Self {
        self.operator = Some(operator);
        self
    }

    /// A progress callback, called after every executed command.
    pub fn progress(mut self, on_progress: &'a mut dyn FnMut(&Progress)) -> Self {
        self.progress = Some(on_progress);
        self
    }

    /// The judge of a run against the simulator in process (the harness's `Scorer`): told every
    /// executed command, it gives the truth-based figures, the true track and the sensed cells.
    pub fn judge(mut self, judge: Box<dyn Judge>) -> Self {
        self.judge = Some(judge);
        self
    }

    /// Drives a platform across `link` instead of the simulator in process (the rover process's
    /// half of a two-process run): the world then gives only the rover's configuration, start,
    /// goal and keep-out zones, scheduled faults are the simulator process's business, and the
    /// truth-based figures come back from the simulator process's judge at the end (a judge
    /// given to this side is not used). Observers get the bus and the
    /// final report, not per-cycle records (they carry truth this side lacks).
    pub fn remote(mut self, link: Box<dyn PlatformLink>) -> Self {
        self.link = Some(link);
        self
    }

    /// Runs to the end of the mission and scores the run.
    pub fn execute(self) -> Result<RunOutput, RunError> {
        crate::run_loop::drive(self)
    }

    /// The component graph this run would step (nothing runs).
    pub fn graph(self) -> Result<crate::graph::Graph, RunError> {
        let remote = self.link.is_some();
        let (runtime, _) =
            crate::run_loop::assemble(&self.world, &self.settings, &self.options, &self.origin, self.link)?;
        Ok(crate::graph::Graph::of(&runtime, &self.settings.name, remote))
    }
}
