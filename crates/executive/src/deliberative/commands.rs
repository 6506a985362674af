//! The operator's commands (the command language of [`crate::command_language`]) applied to the
//! plan, and the `status` answer.

use super::{Deliberative, MissionState, Role, TaskKind};
use crate::command_language::{MotorSide, OperatorCommand, help_text, parse_command};
use crate::messages::{
    CommandMsg, ControlAction, MotionRequest, Origin, PoseMsg, SenseMsg, TaskState, topics,
};
use rovernav_bus::{Bus, BusError};
use rovernav_core::{DriveGuard, Outcome, Point2};

impl Deliberative {
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
            let (outcome, why) = self.end.as_ref().map_or(("over", ""), |(o, why)| (o.as_str(), why));
            return Ok(format!("mission over: {outcome} ({why}); `{cmd}` not executed"));
        }
        let target = match &cmd {
            C::Goto { x, y }
            | C::WaypointAdd { x, y }
            | C::SetPosition { x, y, .. }
            | C::TrackSite { x, y, .. }
            | C::Place { x, y } => Some((*x, *y)),
            _ => None,
        };
        if let (Some([x0, y0, x1, y1]), Some((x, y))) = (self.area, target)
            && !((x0..=x1).contains(&x) && (y0..=y1).contains(&y))
        {
            return Ok(format!(
                "error: `{cmd}`: ({x:.2}, {y:.2}) is outside the terrain (x {x0:.1}..{x1:.1}, y {y0:.1}..{y1:.1} m)"
            ));
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
                self.abandon_direct(bus, "emergency stop")?;
                self.fp.set_target(None);
                self.state = MissionState::Stopped;
                "emergency stop: every component to Emergency; `mission start` clears it".into()
            }
            C::Drive { distance } => self.direct(
                bus,
                cmd.clone(),
                super::direct::Asked::Drive(distance),
                CommandMsg::Drive {
                    distance,
                    curvature: 0.0,
                    guard: DriveGuard { proximity: distance > 0.0, max_tilt: None },
                },
            )?,
            C::Turn { angle } => {
                self.direct(bus, cmd.clone(), super::direct::Asked::Turn(angle), CommandMsg::Turn { angle })?
            }
            C::SetPosition { x, y, yaw } => {
                let Some(e) = self.estimate else {
                    return Ok("error: `set position`: no pose estimate yet".into());
                };
                let pose = PoseMsg { x, y, yaw: yaw.unwrap_or(e.pose.yaw), ..e.pose };
                bus.publish(topics::LOCALIZATION_RESET, pose)?;
                format!("position set to ({x:.2}, {y:.2}), yaw {:.1} deg", pose.yaw.to_degrees())
            }
            C::TrackPixel { row, col } => self.track(super::Designation::Pixel { row, col }),
            C::TrackSite { x, y, z } => self.track(super::Designation::Site { x, y, z }),
            C::Place { x, y } => self.queue(TaskKind::PlaceInstrument { target: Point2::new(x, y) }),
            C::Motor { side, distance } => {
                // Skid steering with one side held: the centre runs on a circle of radius track / 2
                // about the held wheels, so half the wheel travel, at curvature 2 / track.
                let track = self.rover.track;
                // At most a half turn per command, so the answer can tell the turn made.
                if distance.abs() >= std::f64::consts::PI * track {
                    return Ok(format!(
                        "error: `{cmd}`: at most {:.2} m per command (half a turn on a {track:.2} m track)",
                        std::f64::consts::PI * track - 0.005
                    ));
                }
                let curvature = match side {
                    MotorSide::Left => -2.0 / track,
                    MotorSide::Right => 2.0 / track,
                };
                self.direct(
                    bus,
                    cmd.clone(),
                    super::direct::Asked::Motor { distance, track },
                    CommandMsg::Drive {
                        distance: distance / 2.0,
                        curvature,
                        guard: DriveGuard { proximity: distance > 0.0, max_tilt: None },
                    },
                )?
            }
            C::Navcam { pan, tilt } => self.direct(
                bus,
                cmd.clone(),
                super::direct::Asked::Pictures,
                CommandMsg::Sense(vec![SenseMsg::Navcam { pan, tilt }]),
            )?,
            C::Status => self.status_text(),
            C::Help { topic } => match help_text(topic.as_deref()) {
                Ok(text) => text.trim_end().to_string(),
                Err(e) => format!("error: {e}"),
            },
        })
    }

    /// Queues an operator's task to run next: at the cursor if the task there has not started,
    /// else right after it.
    pub(super) fn queue(&mut self, kind: TaskKind) -> String {
        let task = self.new_task(kind, false, Role::Extra);
        let id = task.id;
        let at = if self.tasks.get(self.cursor).is_some_and(|t| t.state == TaskState::Pending) {
            self.cursor
        } else {
            (self.cursor + 1).min(self.tasks.len())
        };
        self.tasks.insert(at, task);
        self.operator_tasks.push(id);
        format!("task {id} added: {}", kind.describe())
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
        asked: super::direct::Asked,
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
        self.follow_direct(id, cmd.to_string(), asked);
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
        if let Some(p) = self.sleep.last() {
            out.push_str(&format!(
                "\npower: battery {:.0} % ({:.1} Wh) · panel {:.1} W · computer {:.1} W, motors {:.1} W, cameras {:.1} W{}",
                100.0 * p.state_of_charge,
                p.battery_wh,
                p.panel_w,
                p.computer_w,
                p.motors_w,
                p.cameras_w,
                if self.sleep.asleep() { " · asleep, waiting for charge" } else { "" }
            ));
        }
        let states: Vec<String> = self.components.iter().map(|(n, (s, _))| format!("{n} {s}")).collect();
        out.push_str(&format!("\ncomponents: {}", states.join(", ")));
        out
    }
}
