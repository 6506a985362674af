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

use crate::command_language::{OperatorCommand, help_text, parse_command};
use crate::components::{JausState, Port};
use crate::fault_protection::{Diagnosis, FaultProtection, FaultProtectionConfig};
use crate::messages::{
    ArmAction, ArmTaskMsg, CancelMsg, CommandMsg, ComponentStatusMsg, ControlAction, ControlMsg, DriveToMsg,
    EstimateMsg, FrameMsg, GoalMsg, MotionRequest, Origin, PoseMsg, SenseMsg, TaskState, TaskStatusMsg,
    topics,
};
use rovernav_bus::{Bus, BusError, Subscriber};
use rovernav_core::{Goal, Outcome, Point2, angle_diff, wrap_angle};
use std::collections::BTreeMap;

/// Mast pans of a panorama (rad): eight 45 deg wedges all around.
const PANORAMA_PANS: usize = 8;
/// Nearest target the mast can image (m).
const MAST_MIN_RANGE_M: f64 = 0.5;
/// Bearing of an arm target beyond which the rover first turns to face it (rad).
const ARM_AIM_TOLERANCE: f64 = 0.17;

/// What a task does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TaskKind {
    /// Drive to a point (a waypoint or the goal).
    DriveTo {
        /// Where (world frame, m).
        target: Point2,
        /// Arrival tolerance (m).
        tolerance: f64,
    },
    /// Image all around with the mast.
    Panorama,
    /// Image a target with the mast.
    ScienceImage {
        /// Target (world frame, m).
        target: Point2,
    },
    /// Place an instrument on a target in front of the rover.
    PlaceInstrument {
        /// Target (world frame, m).
        target: Point2,
    },
    /// Scoop a soil sample at a target in front of the rover.
    Scoop {
        /// Target (world frame, m).
        target: Point2,
    },
}

/// Something a task occupies while it runs; parallel tasks must not share one.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Resource {
    /// The wheels (driving moves them, arm work needs them still).
    Wheels,
    /// The mast cameras (navigators sense with them too).
    Mast,
    /// The tooling arm.
    Arm,
}

impl TaskKind {
    /// A stable lower-case name (the mission file's `kind`).
    pub fn name(&self) -> &'static str {
        match self {
            TaskKind::DriveTo { .. } => "drive_to",
            TaskKind::Panorama => "panorama",
            TaskKind::ScienceImage { .. } => "science_image",
            TaskKind::PlaceInstrument { .. } => "place_instrument",
            TaskKind::Scoop { .. } => "scoop",
        }
    }

    /// The task's target, if it has one.
    pub fn target(&self) -> Option<Point2> {
        match *self {
            TaskKind::DriveTo { target, .. }
            | TaskKind::ScienceImage { target }
            | TaskKind::PlaceInstrument { target }
            | TaskKind::Scoop { target } => Some(target),
            TaskKind::Panorama => None,
        }
    }

    /// What the task occupies.
    pub fn resources(&self) -> &'static [Resource] {
        match self {
            TaskKind::DriveTo { .. } => &[Resource::Wheels, Resource::Mast],
            TaskKind::Panorama | TaskKind::ScienceImage { .. } => &[Resource::Mast],
            TaskKind::PlaceInstrument { .. } | TaskKind::Scoop { .. } => &[Resource::Arm, Resource::Wheels],
        }
    }

    fn describe(&self) -> String {
        match self.target() {
            Some(t) => format!("{} ({:.2}, {:.2})", self.name(), t.x, t.y),
            None => self.name().to_string(),
        }
    }
}

/// One entry of a mission plan.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TaskSpec {
    /// What to do.
    pub kind: TaskKind,
    /// Start together with the previous task.
    pub parallel: bool,
}

/// Checks that parallel tasks do not share a resource; the error gives the offending task's
/// index and why.
pub fn validate_plan(tasks: &[TaskSpec]) -> Result<(), (usize, String)> {
    let mut group_start = 0;
    for (i, t) in tasks.iter().enumerate() {
        if !t.parallel {
            group_start = i;
            continue;
        }
        if i == 0 {
            return Err((0, "the first task has no task before it to run in parallel with".into()));
        }
        for other in &tasks[group_start..i] {
            if let Some(r) = t.kind.resources().iter().find(|r| other.kind.resources().contains(r)) {
                return Err((
                    i,
                    format!(
                        "cannot run in parallel with the {} before it: both need the {r:?}",
                        other.kind.name()
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// Where a task came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    /// A waypoint before the goal.
    Waypoint,
    /// The goal.
    Goal,
    /// An extra task of the mission file.
    Extra,
}

/// A task of the plan with its execution state.
#[derive(Clone, Debug, PartialEq)]
pub struct Task {
    /// Plan id (stable).
    pub id: u64,
    /// What it does.
    pub kind: TaskKind,
    /// Starts together with the previous task.
    pub parallel: bool,
    /// Where it came from.
    pub role: Role,
    /// Execution state.
    pub state: TaskState,
    /// The last word on it.
    pub message: String,
    /// For a finished drive: the navigator's outcome name.
    pub outcome: Option<String>,
    /// Id of the command currently standing for this task in the reflexive layer.
    command: Option<u64>,
    /// An arm task is turning the rover to face its target before deploying the arm.
    aiming: bool,
}

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
        if self.state == MissionState::Running {
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
            self.time_s = f.t;
            if f.request().is_some() {
                self.cycles += 1;
                if let Some(e) = &self.estimate
                    && self.pending_diagnosis.is_none()
                {
                    self.pending_diagnosis = self.fp.on_command(Point2::new(e.pose.x, e.pose.y));
                }
            }
        }
        for s in bus.take(&self.components_sub)? {
            self.components.insert(s.component.clone(), (s.state, s.message.clone()));
            if self.pending_diagnosis.is_none() && self.state != MissionState::Finished {
                self.pending_diagnosis = self.fp.on_status(&s);
            }
        }
        for s in bus.take(&self.statuses)? {
            let Some(i) = self.tasks.iter().position(|t| t.command == Some(s.task)) else { continue };
            let task = &mut self.tasks[i];
            if task.state.is_final() {
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
        Ok(())
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

    /// Presents task `i` to the reflexive layer.
    fn start(&mut self, bus: &mut Bus, i: usize) -> Result<(), BusError> {
        let cmd = self.command_id();
        let kind = self.tasks[i].kind;
        self.tasks[i].command = Some(cmd);
        self.tasks[i].aiming = false;
        self.tasks[i].state = TaskState::InProcess;
        self.tasks[i].outcome = None;
        self.tasks[i].message = "started".into();
        match kind {
            TaskKind::DriveTo { target, tolerance } => {
                self.fp.set_target(Some(target));
                let goal = Goal {
                    position: target,
                    tolerance,
                    waypoints: Vec::new(),
                    keep_out: self.config.keep_out.clone(),
                };
                bus.publish(
                    topics::EXECUTIVE_DRIVE_TO,
                    DriveToMsg { task: cmd, goal: GoalMsg::from(&goal) },
                )?;
            }
            TaskKind::Panorama => {
                let requests = (0..PANORAMA_PANS)
                    .map(|k| SenseMsg::Mast {
                        pan: wrap_angle(k as f64 * std::f64::consts::TAU / PANORAMA_PANS as f64),
                    })
                    .collect();
                let request = MotionRequest {
                    id: cmd,
                    origin: Origin::Task(cmd),
                    command: CommandMsg::Sense { requests },
                };
                bus.publish(topics::EXECUTIVE_MOTION, request)?;
            }
            TaskKind::ScienceImage { target } => {
                let Some(e) = self.estimate else {
                    return self.fail_now(i, "no pose estimate to aim the mast".into());
                };
                let offset = target.sub(Point2::new(e.pose.x, e.pose.y));
                let range = offset.norm();
                if !(MAST_MIN_RANGE_M..=self.config.mast_range_m).contains(&range) {
                    let why = format!(
                        "target {range:.2} m away, outside the mast's {MAST_MIN_RANGE_M:.1}-{:.1} m range",
                        self.config.mast_range_m
                    );
                    return self.fail_now(i, why);
                }
                let pan = angle_diff(offset.angle(), e.pose.yaw);
                let request = MotionRequest {
                    id: cmd,
                    origin: Origin::Task(cmd),
                    command: CommandMsg::Sense { requests: vec![SenseMsg::Mast { pan }] },
                };
                bus.publish(topics::EXECUTIVE_MOTION, request)?;
            }
            TaskKind::PlaceInstrument { target } | TaskKind::Scoop { target } => {
                let Some(e) = self.estimate else {
                    return self.fail_now(i, "no pose estimate to face the target".into());
                };
                let bearing = angle_diff(target.sub(Point2::new(e.pose.x, e.pose.y)).angle(), e.pose.yaw);
                if bearing.abs() <= ARM_AIM_TOLERANCE {
                    return self.deploy_arm(bus, i);
                }
                // Elaborate: face the target first, then deploy the arm.
                self.tasks[i].aiming = true;
                self.tasks[i].message = format!("turning {:.0} deg to face the target", bearing.to_degrees());
                let request = MotionRequest {
                    id: cmd,
                    origin: Origin::Task(cmd),
                    command: CommandMsg::Turn { angle: bearing },
                };
                bus.publish(topics::EXECUTIVE_MOTION, request)?;
            }
        }
        Ok(())
    }

    /// Presents an arm task's operation to the tooling arm as a new command.
    fn deploy_arm(&mut self, bus: &mut Bus, i: usize) -> Result<(), BusError> {
        let (action, target) = match self.tasks[i].kind {
            TaskKind::Scoop { target } => (ArmAction::Scoop, target),
            TaskKind::PlaceInstrument { target } => (ArmAction::PlaceInstrument, target),
            _ => return Ok(()),
        };
        let cmd = self.command_id();
        self.tasks[i].command = Some(cmd);
        self.tasks[i].message = "deploying the arm".into();
        bus.publish(topics::ARM_COMMAND, ArmTaskMsg { task: cmd, action, target: [target.x, target.y] })
    }

    fn fail_now(&mut self, i: usize, why: String) -> Result<(), BusError> {
        self.tasks[i].state = TaskState::Failure;
        self.tasks[i].message = why;
        Ok(())
    }

    /// Withdraws a task's command from the reflexive layer; the task becomes `to`.
    fn withdraw(&mut self, bus: &mut Bus, i: usize, to: TaskState, why: &str) -> Result<(), BusError> {
        if let Some(cmd) = self.tasks[i].command.take()
            && self.tasks[i].state == TaskState::InProcess
        {
            bus.publish(topics::EXECUTIVE_CANCEL, CancelMsg { task: cmd })?;
        }
        self.tasks[i].state = to;
        self.tasks[i].message = why.to_string();
        Ok(())
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

    fn control(
        &mut self,
        bus: &mut Bus,
        target: Option<&str>,
        action: ControlAction,
    ) -> Result<(), BusError> {
        bus.publish(topics::SYSTEM_CONTROL, ControlMsg { target: target.map(str::to_string), action })
    }

    /// Parses and applies one operator line; returns the answer.
    pub fn apply_line(&mut self, bus: &mut Bus, line: &str) -> Result<String, BusError> {
        match parse_command(line) {
            Ok(None) => Ok(String::new()),
            Ok(Some(cmd)) => self.apply(bus, cmd),
            Err(e) => Ok(format!("error: {e}")),
        }
    }

    /// Applies one operator command; returns the answer.
    pub fn apply(&mut self, bus: &mut Bus, cmd: OperatorCommand) -> Result<String, BusError> {
        use OperatorCommand as C;
        if self.state == MissionState::Finished
            && !matches!(cmd, C::Status | C::Help { .. } | C::WaypointList)
        {
            let outcome = self.end.as_ref().map_or("over", |(o, _)| o.as_str());
            return Ok(format!("error: `{cmd}`: the mission is over ({outcome})"));
        }
        Ok(match cmd {
            C::Goto { x, y } => self.goto(bus, Point2::new(x, y))?,
            C::WaypointAdd { x, y } => self.add_waypoint(bus, Point2::new(x, y))?,
            C::WaypointClear => self.clear_waypoints(bus)?,
            C::WaypointList => self.waypoint_list(),
            C::MissionStart => self.mission_start(bus)?,
            C::MissionPause => match self.state {
                MissionState::Running => {
                    self.control(bus, Some("navigator"), ControlAction::Standby)?;
                    self.fp.set_target(None);
                    self.state = MissionState::Paused;
                    "mission paused; `mission start` resumes".into()
                }
                _ => format!("error: `mission pause`: the mission is {}", self.state_name()),
            },
            C::MissionAbort => {
                self.finish(bus, Outcome::Aborted, "mission aborted by the operator".into())?;
                "mission aborted".into()
            }
            C::Stop => {
                self.control(bus, None, ControlAction::EmergencyStop)?;
                self.fp.set_target(None);
                self.state = MissionState::Stopped;
                "emergency stop: every component to Emergency; `mission start` clears it".into()
            }
            C::Drive { distance } => self.direct(
                bus,
                cmd.clone(),
                CommandMsg::Drive {
                    distance,
                    curvature: 0.0,
                    proximity_guard: distance > 0.0,
                    max_tilt: None,
                },
            )?,
            C::Turn { angle } => self.direct(bus, cmd.clone(), CommandMsg::Turn { angle })?,
            C::SetPosition { x, y, yaw } => {
                let Some(e) = self.estimate else {
                    return Ok("error: `set position`: no pose estimate yet".into());
                };
                let pose = PoseMsg { x, y, yaw: yaw.unwrap_or(e.pose.yaw), ..e.pose };
                bus.publish(topics::LOCALIZATION_RESET, pose)?;
                format!("position set to ({x:.2}, {y:.2}), yaw {:.1} deg", pose.yaw.to_degrees())
            }
            C::Status => self.status_text(),
            C::Help { topic } => match help_text(topic.as_deref()) {
                Ok(text) => text.trim_end().to_string(),
                Err(e) => format!("error: {e}"),
            },
        })
    }

    fn state_name(&self) -> &'static str {
        match self.state {
            MissionState::Running => "running",
            MissionState::Paused => "paused",
            MissionState::Stopped => "emergency-stopped",
            MissionState::Finished => "over",
        }
    }

    fn goal_index(&self) -> Option<usize> {
        self.tasks.iter().position(|t| t.role == Role::Goal)
    }

    /// `goto`: the goal moves; a drive under way to it restarts, a reached goal is driven to
    /// again (and the tasks after it run again there). Pending waypoints are still visited first.
    fn goto(&mut self, bus: &mut Bus, target: Point2) -> Result<String, BusError> {
        let Some(g) = self.goal_index() else { return Ok("error: `goto`: the plan has no goal".into()) };
        let tolerance = match self.tasks[g].kind {
            TaskKind::DriveTo { tolerance, .. } => tolerance,
            _ => self.config.tolerance,
        };
        let rewind = g < self.cursor || self.tasks[g].state.is_final();
        let last = if rewind { self.tasks.len() } else { g + 1 };
        for i in g..last {
            if self.tasks[i].state == TaskState::InProcess {
                self.withdraw(bus, i, TaskState::Pending, "goal moved")?;
            }
            self.tasks[i].state = TaskState::Pending;
            self.tasks[i].command = None;
            self.tasks[i].message = "goal moved".into();
        }
        self.tasks[g].kind = TaskKind::DriveTo { target, tolerance };
        self.cursor = self.cursor.min(g);
        Ok(format!("goal set to ({:.2}, {:.2})", target.x, target.y))
    }

    fn add_waypoint(&mut self, bus: &mut Bus, at: Point2) -> Result<String, BusError> {
        let Some(g) = self.goal_index() else {
            return Ok("error: `waypoint add`: the plan has no goal".into());
        };
        if self.tasks[g].state.is_final() {
            return Ok("error: `waypoint add`: the goal is already reached; use `goto`".into());
        }
        if self.tasks[g].state == TaskState::InProcess {
            self.withdraw(bus, g, TaskState::Pending, "waypoint added")?;
        }
        let task = self.new_task(
            TaskKind::DriveTo { target: at, tolerance: self.config.tolerance },
            false,
            Role::Waypoint,
        );
        let id = task.id;
        self.tasks.insert(g, task);
        let n = self.tasks.iter().filter(|t| t.role == Role::Waypoint && !t.state.is_final()).count();
        Ok(format!("waypoint {id} added at ({:.2}, {:.2}); {n} to visit before the goal", at.x, at.y))
    }

    fn clear_waypoints(&mut self, bus: &mut Bus) -> Result<String, BusError> {
        let mut cleared = 0;
        for i in 0..self.tasks.len() {
            if self.tasks[i].role == Role::Waypoint && !self.tasks[i].state.is_final() {
                self.withdraw(bus, i, TaskState::Cancelled, "cleared by the operator")?;
                cleared += 1;
            }
        }
        Ok(format!("{cleared} waypoints cleared"))
    }

    fn waypoint_list(&self) -> String {
        let lines: Vec<String> = self
            .tasks
            .iter()
            .filter(|t| t.role == Role::Waypoint)
            .map(|t| {
                let p = t.kind.target().unwrap_or(Point2::new(f64::NAN, f64::NAN));
                format!("  waypoint {} ({:.2}, {:.2}) {}", t.id, p.x, p.y, t.state.as_str())
            })
            .collect();
        if lines.is_empty() { "no waypoints".into() } else { format!("waypoints:\n{}", lines.join("\n")) }
    }

    fn mission_start(&mut self, bus: &mut Bus) -> Result<String, BusError> {
        Ok(match self.state {
            MissionState::Running => "mission already running".into(),
            MissionState::Paused => {
                self.control(bus, Some("navigator"), ControlAction::Resume)?;
                self.state = MissionState::Running;
                "mission resumed".into()
            }
            MissionState::Stopped => {
                self.control(bus, None, ControlAction::ClearEmergency)?;
                self.control(bus, None, ControlAction::Resume)?;
                // What the stop aborted starts again.
                for t in &mut self.tasks {
                    if matches!(t.state, TaskState::Aborted | TaskState::InProcess) {
                        t.state = TaskState::Pending;
                        t.command = None;
                        t.message = "restarted after an emergency stop".into();
                    }
                }
                self.state = MissionState::Running;
                "emergency cleared; mission resumed".into()
            }
            MissionState::Finished => "error: `mission start`: the mission is over".into(),
        })
    }

    /// `drive` and `turn`: direct motion while the mission is paused.
    fn direct(
        &mut self,
        bus: &mut Bus,
        cmd: OperatorCommand,
        command: CommandMsg,
    ) -> Result<String, BusError> {
        if self.state != MissionState::Paused {
            return Ok(format!(
                "error: `{cmd}`: direct motion needs the mission paused (`mission pause`); it is {}",
                self.state_name()
            ));
        }
        let id = self.command_id();
        bus.publish(topics::EXECUTIVE_MOTION, MotionRequest { id, origin: Origin::Operator, command })?;
        Ok(format!("executing `{cmd}`"))
    }

    /// The `status` answer.
    pub fn status_text(&self) -> String {
        let mut out =
            format!("mission {} · t {:.1} s · {} commands", self.state_name(), self.time_s, self.cycles);
        if let Some((o, why)) = &self.end {
            out.push_str(&format!(" · outcome {}: {why}", o.as_str()));
        }
        if let Some(e) = &self.estimate {
            out.push_str(&format!(
                "\nestimate ({:.2}, {:.2}) yaw {:.1} deg",
                e.pose.x,
                e.pose.y,
                e.pose.yaw.to_degrees()
            ));
        }
        if let Some(g) = self.goal() {
            out.push_str(&format!(" · goal ({:.2}, {:.2})", g.x, g.y));
            if let Some(e) = &self.estimate {
                out.push_str(&format!(" · {:.2} m to go", Point2::new(e.pose.x, e.pose.y).dist(g)));
            }
        }
        for t in &self.tasks {
            out.push_str(&format!("\ntask {} {} {}", t.id, t.kind.describe(), t.state.as_str()));
            if !t.message.is_empty() {
                out.push_str(&format!(": {}", t.message));
            }
        }
        let states: Vec<String> = self.components.iter().map(|(n, (s, _))| format!("{n} {s}")).collect();
        out.push_str(&format!("\ncomponents: {}", states.join(", ")));
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(kind: TaskKind, parallel: bool) -> TaskSpec {
        TaskSpec { kind, parallel }
    }

    #[test]
    fn parallel_tasks_must_not_share_a_resource() {
        let p = Point2::new(1.0, 1.0);
        let drive = TaskKind::DriveTo { target: p, tolerance: 0.5 };
        assert!(
            validate_plan(&[spec(TaskKind::Panorama, false), spec(TaskKind::Scoop { target: p }, true)])
                .is_ok()
        );
        let (i, why) = validate_plan(&[spec(drive, false), spec(TaskKind::ScienceImage { target: p }, true)])
            .unwrap_err();
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
        assert_eq!(first[0].goal.position, [5.0, 5.0], "the waypoint comes first");
        // Nothing new while the waypoint drive is in process.
        status(&mut bus, first[0].task, TaskState::InProcess, None);
        dl.step(&mut bus).unwrap();
        assert!(bus.take(&drive_to).unwrap().is_empty());
        status(&mut bus, first[0].task, TaskState::Success, Some("reached"));
        dl.step(&mut bus).unwrap();
        let second = bus.take(&drive_to).unwrap();
        assert_eq!(second[0].goal.position, [10.0, 0.0]);
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
        assert_eq!(goal[0].goal.position, [10.0, 0.0]);
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
}
