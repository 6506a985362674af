//! The deliberative layer: the mission plan turned into commands for the reflexive layer.
//!
//! Paper 004 section 2: the deliberative layer "elaborates these action sequences into an
//! ordered list of commands that are performed by the reflexive layer. Individual commands are
//! presented to the RL for execution and continuously monitored. The DL decides on appropriate
//! parallel or subsequent actions based on the execution state reported by the reflexive software
//! (in process, success, failure, aborted, or cancelled)", and it "initiates and monitors the
//! execution of complementary tasks such as scooping, scientific measurements, or taking
//! panoramic views". Here the plan is a list of tasks: drive to each waypoint, drive to the goal,
//! then the mission's extra tasks; a task marked `parallel` starts together with the one before
//! it when they need different resources. Each start is one command with its own id; the
//! component executing it reports its state on `/executive/task_status`.
//!
//! The layer also applies the operator's commands (the command language of
//! [`crate::command_language`]) and runs fault protection ([`crate::fault_protection`]): on a
//! fault it stands every component down and ends the mission with `help_requested`.

mod approach;
mod commands;
mod direct;
mod plan;
mod science_summary;
mod science_watch;
mod tasks;
#[cfg(test)]
mod tests;
mod track_only;
mod vtt_telemetry;

pub use approach::{NAVIGATOR_LEG_MIN_M, TRACK_STANDOFF_M};
pub use direct::stop_cause;
pub use science_summary::{EventSummary, ImageSummary, WatchSummary};
pub use science_watch::{MAX_INTERVAL_S, Watch, WatchKind, WatchSpec};
pub use tasks::{Designation, Resource, Role, Task, TaskKind, TaskSpec, validate_plan};
pub use vtt_telemetry::{MatchMsg, TemplateMsg, VttTrace, VttTrackMsg};

use crate::components::{JausState, Port};
use crate::fault_protection::{Diagnosis, FaultProtection, FaultProtectionConfig};
use crate::messages::{
    ComponentStatusMsg, ControlAction, ControlMsg, EstimateMsg, FrameMsg, TaskState, TaskStatusMsg, topics,
};
use rovernav_bus::{Bus, BusError, Subscriber};
use rovernav_core::{Goal, Outcome, Point2, RoverConfig};
use std::collections::BTreeMap;

/// The mission's state as the operator sees it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MissionState {
    /// Executing the plan.
    Running,
    /// Holding after the current command (`mission pause`).
    Paused,
    /// Emergency stop (`stop`).
    Stopped,
    /// Over.
    Finished,
}

/// Settings of the deliberative layer.
#[derive(Clone, Debug)]
pub struct DeliberativeConfig {
    /// Mission time budget (s).
    pub time_limit_s: f64,
    /// Command budget.
    pub max_cycles: u64,
    /// Keep-out zones every drive honours.
    pub keep_out: Vec<Vec<Point2>>,
    /// Arrival tolerance of drives the operator adds (m).
    pub tolerance: f64,
    /// Useful range of the mast cameras (m).
    pub mast_range_m: f64,
    /// Fault-protection thresholds.
    pub fault_protection: FaultProtectionConfig,
}

/// The deliberative layer.
pub struct Deliberative {
    config: DeliberativeConfig,
    tasks: Vec<Task>,
    /// First task of the current step.
    cursor: usize,
    next_task: u64,
    next_command: u64,
    state: MissionState,
    end: Option<(Outcome, String)>,
    diagnosis: Option<(Diagnosis, u64, f64)>,
    pending_diagnosis: Option<Diagnosis>,
    fp: FaultProtection,
    components: BTreeMap<String, (JausState, String)>,
    estimate: Option<EstimateMsg>,
    time_s: f64,
    cycles: u64,
    input_closed: bool,
    frames: Subscriber<FrameMsg>,
    estimates: Subscriber<EstimateMsg>,
    statuses: Subscriber<TaskStatusMsg>,
    components_sub: Subscriber<ComponentStatusMsg>,
    operator: Subscriber<String>,
    /// Science watches in progress, by task id.
    watches: BTreeMap<u64, science_watch::WatchRun>,
    /// The rover (its Navcam calibration, for target tracking).
    rover: RoverConfig,
    /// Navcam image size (px).
    navcam_width: usize,
    /// Approaches in progress, by task id.
    approaches: BTreeMap<u64, approach::ApproachRun>,
    /// Track-only tasks in progress, by task id.
    tracks: BTreeMap<u64, track_only::TrackRun>,
    /// The Navcam pointing last asked of the platform alongside the navigator's sensing.
    ride_along: Option<[f64; 2]>,
    /// The last Navcam pair taken (what `track ROW COL` designates on).
    last_navcam: Option<approach::LastNavcam>,
    /// The terrain's extent [x min, y min, x max, y max] (m): operator targets outside it are
    /// refused before a map is sized from them.
    area: Option<[f64; 4]>,
    /// The operator's direct motions not answered yet.
    direct: Vec<direct::DirectMotion>,
    /// Tasks the operator queued whose end has not been answered yet.
    operator_tasks: Vec<u64>,
    /// Sleep and wake on the battery's charge.
    sleep: crate::power::SleepMonitor,
}

impl Deliberative {
    /// The topics the layer publishes (for the runtime's wiring check).
    pub fn ports() -> Vec<Port> {
        vec![
            Port::of(topics::EXECUTIVE_DRIVE_TO),
            Port::of(topics::EXECUTIVE_CANCEL),
            Port::of(topics::EXECUTIVE_MOTION),
            Port::of(topics::ARM_COMMAND),
            Port::of(topics::LOCALIZATION_RESET),
            Port::of(topics::SYSTEM_CONTROL),
            Port::of(topics::OPERATOR_REPLY),
            Port::of(topics::PLATFORM_HOLD),
            Port::of(topics::SCIENCE_SUMMARY),
            Port::of(topics::PLATFORM_RIDE_ALONG),
            Port::of(topics::VTT_TRACK),
        ]
    }

    /// A layer for a goal (its waypoints become drives before it) and extra tasks after it;
    /// subscribes at once so that it sees the platform's first frame.
    pub fn new(
        bus: &mut Bus,
        goal: &Goal,
        extra: &[TaskSpec],
        config: DeliberativeConfig,
    ) -> Result<Self, BusError> {
        let mut me = Self {
            fp: FaultProtection::new(config.fault_protection.clone()),
            config,
            tasks: Vec::new(),
            cursor: 0,
            next_task: 1,
            next_command: 1,
            state: MissionState::Running,
            end: None,
            diagnosis: None,
            pending_diagnosis: None,
            components: BTreeMap::new(),
            estimate: None,
            time_s: 0.0,
            cycles: 0,
            input_closed: false,
            frames: bus.subscribe(topics::PLATFORM_FRAME)?,
            estimates: bus.subscribe(topics::LOCALIZATION_ESTIMATE)?,
            statuses: bus.subscribe(topics::TASK_STATUS)?,
            components_sub: bus.subscribe(topics::SYSTEM_STATUS)?,
            operator: bus.subscribe(topics::OPERATOR_COMMAND)?,
            watches: BTreeMap::new(),
            rover: RoverConfig::default(),
            navcam_width: 512,
            approaches: BTreeMap::new(),
            tracks: BTreeMap::new(),
            ride_along: None,
            last_navcam: None,
            area: None,
            direct: Vec::new(),
            operator_tasks: Vec::new(),
            sleep: crate::power::SleepMonitor::new(crate::power::PowerPolicy::default()),
        };
        for w in &goal.waypoints {
            me.push(TaskKind::DriveTo { target: *w, tolerance: goal.tolerance }, false, Role::Waypoint);
        }
        me.push(TaskKind::DriveTo { target: goal.position, tolerance: goal.tolerance }, false, Role::Goal);
        for t in extra {
            me.push(t.kind, t.parallel, Role::Extra);
        }
        Ok(me)
    }

    /// The rover whose Navcams target tracking uses, and their image size (px); the default
    /// rover and 512 px otherwise.
    pub fn with_rover(mut self, rover: RoverConfig, navcam_width: usize) -> Self {
        self.rover = rover;
        self.navcam_width = navcam_width;
        self
    }

    /// The terrain's extent [x min, y min, x max, y max] (m), outside which `goto`, `waypoint
    /// add`, `set position` and `track X Y Z` are refused.
    pub fn with_area(mut self, area: [f64; 4]) -> Self {
        self.area = Some(area);
        self
    }

    /// Sleep and wake thresholds on the battery's charge (default [`crate::power::PowerPolicy`]).
    pub fn with_power(mut self, policy: crate::power::PowerPolicy) -> Self {
        self.sleep = crate::power::SleepMonitor::new(policy);
        self
    }

    /// The report's power figures (none when the platform gave no reading).
    pub fn power_report(&self) -> Option<crate::power::PowerReport> {
        self.sleep.report(self.time_s)
    }

    fn push(&mut self, kind: TaskKind, parallel: bool, role: Role) {
        let task = self.new_task(kind, parallel, role);
        self.tasks.push(task);
    }

    fn new_task(&mut self, kind: TaskKind, parallel: bool, role: Role) -> Task {
        self.next_task += 1;
        Task {
            id: self.next_task - 1,
            kind,
            parallel,
            role,
            state: TaskState::Pending,
            message: String::new(),
            outcome: None,
            command: None,
            aiming: false,
        }
    }

    /// The plan's tasks.
    pub fn tasks(&self) -> &[Task] {
        &self.tasks
    }

    /// The mission state.
    pub fn state(&self) -> MissionState {
        self.state
    }

    /// Whether the mission waits for the operator (paused or emergency-stopped).
    pub fn waiting(&self) -> bool {
        matches!(self.state, MissionState::Paused | MissionState::Stopped)
    }

    /// The outcome, once the mission is over.
    pub fn end(&self) -> Option<&(Outcome, String)> {
        self.end.as_ref()
    }

    /// The fault that stopped the mission, with the command count and time it was acted on.
    pub fn diagnosis(&self) -> Option<&(Diagnosis, u64, f64)> {
        self.diagnosis.as_ref()
    }

    /// The goal's current target (operators may have moved it).
    pub fn goal(&self) -> Option<Point2> {
        self.tasks.iter().find(|t| t.role == Role::Goal).and_then(|t| t.kind.target())
    }

    /// Commands executed so far.
    pub fn cycles(&self) -> u64 {
        self.cycles
    }

    /// Tells the layer that operator input has ended: a waiting mission cannot resume.
    pub fn close_input(&mut self) {
        self.input_closed = true;
    }

    /// One deliberative cycle: read what the reflexive layer reported, apply operator commands,
    /// run fault protection, check the budgets and advance the plan.
    pub fn step(&mut self, bus: &mut Bus) -> Result<(), BusError> {
        self.read(bus)?;
        for line in bus.take(&self.operator)? {
            let reply = self.apply_line(bus, &line)?;
            bus.publish(topics::OPERATOR_REPLY, reply)?;
        }
        if self.state == MissionState::Finished {
            return Ok(());
        }
        if let Some(d) = self.pending_diagnosis.take() {
            return self.fault_stop(bus, d);
        }
        if self.time_s >= self.config.time_limit_s {
            let why = format!("mission time limit of {} s reached", self.config.time_limit_s);
            return self.finish(bus, Outcome::Timeout, why);
        }
        if self.cycles >= self.config.max_cycles {
            return self.finish(
                bus,
                Outcome::Timeout,
                format!("cycle limit of {} reached", self.config.max_cycles),
            );
        }
        if self.input_closed && self.waiting() {
            let why = "operator input ended while the mission was waiting for the operator".to_string();
            return self.finish(bus, Outcome::Aborted, why);
        }
        if self.state == MissionState::Running && self.power_step(bus)? {
            return Ok(());
        }
        if self.state == MissionState::Running {
            self.pump_watches(bus)?;
            self.pump_approaches(bus)?;
            self.pump_tracks(bus)?;
            self.advance(bus)?;
        }
        Ok(())
    }

    fn read(&mut self, bus: &mut Bus) -> Result<(), BusError> {
        let frames = bus.take(&self.frames)?;
        if let Some(e) = bus.take(&self.estimates)?.pop() {
            self.estimate = Some(*e);
        }
        for f in &frames {
            self.direct_frame(f);
            self.watch_frame(f);
            self.approach_frame(f);
            self.track_frame(f);
            self.time_s = f.t;
            if let Some(p) = &f.power {
                self.sleep.on_reading(p);
            }
            if f.request().is_some() {
                self.cycles += 1;
                if let Some(e) = &self.estimate
                    && self.pending_diagnosis.is_none()
                {
                    self.pending_diagnosis = self.fp.on_command(Point2::new(e.pose.x, e.pose.y));
                }
            }
        }
        self.answer_direct(bus)?;
        for s in bus.take(&self.components_sub)? {
            self.components.insert(s.component.clone(), (s.state, s.message.clone()));
            if self.pending_diagnosis.is_none() && self.state != MissionState::Finished {
                self.pending_diagnosis = self.fp.on_status(&s);
            }
        }
        for s in bus.take(&self.statuses)? {
            let Some(i) = self.tasks.iter().position(|t| t.command == Some(s.task)) else { continue };
            if self.watch_status(i, &s) {
                continue;
            }
            let task = &mut self.tasks[i];
            if task.state.is_final() {
                continue;
            }
            if matches!(task.kind, TaskKind::ApproachTarget { .. }) {
                self.approach_status(i, &s);
                continue;
            }
            if task.aiming && s.state == TaskState::Success {
                // Facing the target now: the second command of an arm task.
                task.aiming = false;
                self.deploy_arm(bus, i)?;
                continue;
            }
            task.state = s.state;
            task.message = s.message.clone();
            task.outcome = s.outcome.clone();
        }
        self.answer_tasks(bus, None)
    }

    /// The tasks of the current step: the cursor's and those parallel to it.
    fn step_range(&self) -> std::ops::Range<usize> {
        let end = (self.cursor + 1..self.tasks.len())
            .find(|&i| !self.tasks[i].parallel)
            .unwrap_or(self.tasks.len());
        self.cursor..end.max(self.cursor)
    }

    fn advance(&mut self, bus: &mut Bus) -> Result<(), BusError> {
        loop {
            if self.cursor >= self.tasks.len() {
                return self.complete(bus);
            }
            let range = self.step_range();
            for i in range.clone() {
                if self.tasks[i].state == TaskState::Pending {
                    self.start(bus, i)?;
                }
            }
            let step = &self.tasks[range.clone()];
            if !step.iter().all(|t| t.state.is_final()) {
                return Ok(());
            }
            if let Some(bad) =
                step.iter().find(|t| matches!(t.state, TaskState::Failure | TaskState::Aborted))
            {
                let (outcome, why) = self.failure_of(bad);
                return self.finish(bus, outcome, why);
            }
            self.cursor = range.end;
        }
    }

    /// The mission outcome a failed or aborted task means.
    fn failure_of(&self, task: &Task) -> (Outcome, String) {
        let single = self.tasks.len() == 1;
        let outcome = match (task.state, &task.kind) {
            (TaskState::Aborted, _) => Outcome::Aborted,
            (_, TaskKind::DriveTo { .. }) => {
                task.outcome.as_deref().and_then(Outcome::parse).unwrap_or(Outcome::HelpRequested)
            }
            _ => Outcome::HelpRequested,
        };
        let why = if single && matches!(task.kind, TaskKind::DriveTo { .. }) {
            task.message.clone()
        } else {
            format!("task {} ({}) {}: {}", task.id, task.kind.describe(), task.state.as_str(), task.message)
        };
        (outcome, why)
    }

    fn complete(&mut self, bus: &mut Bus) -> Result<(), BusError> {
        let done: Vec<&Task> = self.tasks.iter().filter(|t| t.state == TaskState::Success).collect();
        let last_drive = self.tasks.iter().rev().find(|t| matches!(t.kind, TaskKind::DriveTo { .. }));
        let why = match (self.tasks.len(), last_drive) {
            (1, Some(d)) => d.message.clone(),
            (_, Some(d)) => {
                format!("mission plan complete: {} tasks succeeded; goal: {}", done.len(), d.message)
            }
            (_, None) => format!("mission plan complete: {} tasks succeeded", done.len()),
        };
        self.finish(bus, Outcome::Reached, why)
    }

    fn command_id(&mut self) -> u64 {
        self.next_command += 1;
        self.next_command - 1
    }

    /// Ends the mission: withdraws what runs and stands the reflexive layer down.
    fn finish(&mut self, bus: &mut Bus, outcome: Outcome, why: String) -> Result<(), BusError> {
        for i in 0..self.tasks.len() {
            if self.tasks[i].state == TaskState::InProcess {
                self.withdraw(bus, i, TaskState::Cancelled, "mission over")?;
            }
        }
        self.fp.set_target(None);
        self.control(bus, None, ControlAction::Standby)?;
        self.state = MissionState::Finished;
        let over = format!("mission over: {} ({why})", outcome.as_str());
        self.abandon_direct(bus, &over)?;
        self.answer_tasks(bus, Some(&over))?;
        self.end = Some((outcome, why));
        Ok(())
    }

    /// Fault protection's reaction: stop everything and ask for help.
    fn fault_stop(&mut self, bus: &mut Bus, d: Diagnosis) -> Result<(), BusError> {
        for i in 0..self.tasks.len() {
            if self.tasks[i].state == TaskState::InProcess {
                self.withdraw(bus, i, TaskState::Aborted, "stopped by fault protection")?;
            }
        }
        let why =
            format!("fault protection ({}): {}; rover stopped, asking for help", d.kind.as_str(), d.message);
        self.diagnosis = Some((d, self.cycles, self.time_s));
        self.finish(bus, Outcome::HelpRequested, why)
    }

    /// Sleeps below the low threshold of charge and wakes at the high one (SR2's SLEEP mode):
    /// asleep, the navigator stands by and the platform holds in its sleep mode. Whether the
    /// rover is (still) asleep.
    fn power_step(&mut self, bus: &mut Bus) -> Result<bool, BusError> {
        use crate::messages::HoldMsg;
        use crate::power::SleepAction;
        match self.sleep.decide(self.time_s) {
            SleepAction::Awake => Ok(false),
            SleepAction::Sleep(until_s) => {
                self.control(bus, Some("navigator"), ControlAction::Standby)?;
                self.fp.set_target(None);
                bus.publish(topics::PLATFORM_HOLD, HoldMsg { until_s, sleep: true })?;
                Ok(true)
            }
            SleepAction::StayAsleep(until_s) => {
                // Still standing by, even if the operator resumed the mission meanwhile.
                self.control(bus, Some("navigator"), ControlAction::Standby)?;
                bus.publish(topics::PLATFORM_HOLD, HoldMsg { until_s, sleep: true })?;
                Ok(true)
            }
            SleepAction::Wake => {
                self.control(bus, Some("navigator"), ControlAction::Resume)?;
                Ok(false)
            }
        }
    }

    fn control(
        &mut self,
        bus: &mut Bus,
        target: Option<&str>,
        action: ControlAction,
    ) -> Result<(), BusError> {
        bus.publish(topics::SYSTEM_CONTROL, ControlMsg { target: target.map(str::to_string), action })
    }
}
