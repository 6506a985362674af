//! The tooling arm (paper 004 section 4: instrument placement and scooping) as a component.
//!
//! Placing an instrument runs AutoPlace (paper 003 section 4, [`placement`]). The arm asks the
//! platform (commands of its own, origin [`Origin::Arm`], so the task's state stays the arm's to
//! report) for the paper's imaging sequence: the rover backs up one step (0.30 m) and takes the
//! "penultimate" front Hazcam pair, drives the last step forward again and takes the "ultimate"
//! Hazcam pair and a Navcam pair pointed down at the work volume. The arm correlates them,
//! moves the penultimate points into the final body frame by the pose estimates, builds the
//! terrain octree, chooses the target nearest the commanded point and plans the motion. Placed: it publishes the placement on `/arm/placement`
//! (the joint states over time, the octree, the target), holds the platform still while the arm
//! moves out, dwells [`ArmConfig::place_s`] in contact and stows, and succeeds if the wheels did
//! not turn meanwhile. Refused: the placement message names the reason (`no_data`, `normal`,
//! `roughness`, `reach`, `collision`), the task fails with it, and nothing moves.
//!
//! Scooping has no mechanism in the simulator: the arm checks reach and tilt from the pose
//! estimate, holds the rover still for [`ArmConfig::scoop_s`] and succeeds if the wheels did
//! not turn.

pub mod placement;

use crate::components::{Component, ComponentFault, Ctx, JausState, Port, Ports};
use crate::messages::{
    ArmAction, ArmTaskMsg, CancelMsg, CommandMsg, EstimateMsg, FrameMsg, HoldMsg, ImageMsg, MotionRequest,
    Origin, SenseMsg, TaskState, TaskStatusMsg, topics,
};
pub use placement::PlacementMsg;
use rovernav_bus::{Bus, BusError, Subscriber};
use rovernav_core::{DriveGuard, Point2, Pose3, RoverConfig, angle_diff};
use rovernav_manipulation::motion::Timing;

/// Longest wait for the work-volume images (simulated s) before the task fails.
const IMAGING_TIMEOUT_S: f64 = 120.0;

/// Tooling-arm parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct ArmConfig {
    /// Nearest reachable target, ahead of the rover centre (m).
    pub reach_min_m: f64,
    /// Farthest reachable target (m).
    pub reach_max_m: f64,
    /// Largest bearing off the rover's forward axis (rad).
    pub max_bearing: f64,
    /// Steepest body tilt at which the arm may work (rad).
    pub max_tilt: f64,
    /// The instrument's time in contact once placed (s).
    pub place_s: f64,
    /// Time to scoop: open, lower, cut, close (s).
    pub scoop_s: f64,
}

impl Default for ArmConfig {
    fn default() -> Self {
        Self {
            reach_min_m: 0.4,
            reach_max_m: 1.2,
            max_bearing: 45f64.to_radians(),
            max_tilt: 15f64.to_radians(),
            place_s: 30.0,
            scoop_s: 60.0,
        }
    }
}

/// The last step of the imaging sequence (m): the penultimate pair is taken this far back.
pub const LAST_STEP_M: f64 = 0.30;

/// What the arm is doing for a task.
#[derive(Clone, Debug)]
enum Phase {
    /// Running the imaging sequence requested at `since_s` (its requests' ids start at
    /// `first_id`); the penultimate pair's images and the estimate it was taken at, once in.
    Imaging { target: [f64; 2], since_s: f64, first_id: u64, penultimate: Option<(Vec<ImageMsg>, Pose3)> },
    /// Deployed (moving or working) until `until_s`, with the wheel counts at the start.
    Deployed { until_s: f64, counts: Option<(i64, i64)> },
}

/// The operation under way.
#[derive(Clone, Debug)]
struct ArmWork {
    task: u64,
    action: ArmAction,
    phase: Phase,
}

/// The tooling arm: places an instrument (AutoPlace) or scoops at a target in front of the rover.
pub struct ToolingArm {
    config: ArmConfig,
    rover: RoverConfig,
    commands: Option<Subscriber<ArmTaskMsg>>,
    cancels: Option<Subscriber<CancelMsg>>,
    estimates: Option<Subscriber<EstimateMsg>>,
    frames: Option<Subscriber<FrameMsg>>,
    estimate: Option<EstimateMsg>,
    counts: Option<(i64, i64)>,
    work: Option<ArmWork>,
    next_request: u64,
    placements: Vec<PlacementMsg>,
}

impl ToolingArm {
    /// An idle arm on the default rover.
    pub fn new(config: ArmConfig) -> Self {
        Self {
            config,
            rover: RoverConfig::default(),
            commands: None,
            cancels: None,
            estimates: None,
            frames: None,
            estimate: None,
            counts: None,
            work: None,
            next_request: 0,
            placements: Vec::new(),
        }
    }

    /// The arm on `rover` (its cameras and body).
    pub fn with_rover(mut self, rover: RoverConfig) -> Self {
        self.rover = rover;
        self
    }

    /// Every placement decided so far (placed or refused), in order.
    pub fn placements(&self) -> &[PlacementMsg] {
        &self.placements
    }

    fn status(&self, bus: &mut Bus, task: u64, state: TaskState, message: String) -> Result<(), BusError> {
        bus.publish(
            topics::TASK_STATUS,
            TaskStatusMsg { task, component: "tooling-arm".into(), state, outcome: None, message },
        )
    }

    /// Why the arm cannot work on `target` from the current estimate, if it cannot.
    fn unreachable(&self, target: Point2) -> Option<String> {
        let Some(est) = &self.estimate else {
            return Some("no pose estimate yet".into());
        };
        let pose = est.pose;
        let offset = target.sub(Point2::new(pose.x, pose.y));
        let range = offset.norm();
        let bearing = angle_diff(offset.angle(), pose.yaw);
        let c = &self.config;
        if !(c.reach_min_m..=c.reach_max_m).contains(&range) {
            return Some(format!(
                "target {range:.2} m from the rover, outside the arm's reach ({:.2}-{:.2} m)",
                c.reach_min_m, c.reach_max_m
            ));
        }
        if bearing.abs() > c.max_bearing {
            return Some(format!(
                "target {:.0} deg off the rover's heading, beyond the arm's {:.0} deg",
                bearing.to_degrees(),
                c.max_bearing.to_degrees()
            ));
        }
        let tilt = (pose.roll.cos() * pose.pitch.cos()).clamp(-1.0, 1.0).acos();
        if tilt > c.max_tilt {
            return Some(format!(
                "rover tilted {:.1} deg, beyond the arm's {:.0} deg",
                tilt.to_degrees(),
                c.max_tilt.to_degrees()
            ));
        }
        None
    }

    /// Deploys the arm for `duration` seconds from `now`: holds the platform still meanwhile.
    fn deploy(&mut self, bus: &mut Bus, task: u64, action: ArmAction, until_s: f64) -> Result<(), BusError> {
        self.work = Some(ArmWork { task, action, phase: Phase::Deployed { until_s, counts: self.counts } });
        bus.publish(topics::PLATFORM_HOLD, HoldMsg { until_s, sleep: false })
    }

    /// Asks the platform for the imaging sequence of a placement: back one step, the
    /// penultimate Hazcam pair, the last step forward, the ultimate Hazcam and Navcam pairs.
    fn request_images(&mut self, ctx: &mut Ctx<'_>, cmd: &ArmTaskMsg) -> Result<(), BusError> {
        let step =
            |distance: f64| CommandMsg::Drive { distance, curvature: 0.0, guard: DriveGuard::default() };
        let commands = [
            step(-LAST_STEP_M),
            CommandMsg::Sense(vec![SenseMsg::BodyPair { front: true }]),
            step(LAST_STEP_M),
            CommandMsg::Sense(vec![
                SenseMsg::BodyPair { front: true },
                SenseMsg::Navcam { pan: 0.0, tilt: placement::NAVCAM_TILT },
            ]),
        ];
        let first_id = self.next_request + 1;
        for command in commands {
            self.next_request += 1;
            let request = MotionRequest { id: self.next_request, origin: Origin::Arm(cmd.task), command };
            ctx.bus.publish(topics::EXECUTIVE_MOTION, request)?;
        }
        let phase = Phase::Imaging { target: cmd.target, since_s: ctx.time_s, first_id, penultimate: None };
        self.work = Some(ArmWork { task: cmd.task, action: cmd.action, phase });
        self.status(ctx.bus, cmd.task, TaskState::InProcess, "imaging the work volume".into())
    }

    /// The ultimate images came: AutoPlace decides; the arm deploys or the task fails.
    fn on_images(
        &mut self,
        bus: &mut Bus,
        w: ArmWork,
        target: [f64; 2],
        penultimate: Option<(Vec<ImageMsg>, Pose3)>,
        f: &FrameMsg,
    ) -> Result<(), BusError> {
        let Some(est) = self.estimate else {
            self.work = None;
            return self.status(bus, w.task, TaskState::Failure, "no pose estimate".into());
        };
        let timing = Timing { dwell_s: self.config.place_s.max(0.0), ..Timing::default() };
        let views = placement::Views {
            ultimate: &f.images,
            penultimate: penultimate.as_ref().map(|(i, p)| (&i[..], p)),
        };
        let msg = placement::place(w.task, f.t, &views, &est.pose, target, &self.rover, &timing);
        bus.publish(topics::ARM_PLACEMENT, msg.clone())?;
        let words = placement_words(&msg);
        let end_s = msg.end_s();
        let placed = msg.outcome == "placed";
        self.placements.push(msg);
        if !placed {
            self.work = None;
            return self.status(bus, w.task, TaskState::Failure, words);
        }
        self.deploy(bus, w.task, w.action, end_s)?;
        self.status(bus, w.task, TaskState::InProcess, format!("{words}; working until t = {end_s:.1} s"))
    }

    /// A frame: wheel counts, the images of a placement, the end of a deployment.
    fn on_frame(&mut self, bus: &mut Bus, f: &FrameMsg) -> Result<(), BusError> {
        if let Some(o) = f.odometry.last() {
            self.counts = Some((o.left_counts, o.right_counts));
        }
        let Some(w) = self.work.clone() else { return Ok(()) };
        match w.phase.clone() {
            Phase::Imaging { target, first_id, penultimate, since_s } => {
                let Some(r) = f.request().filter(|r| r.origin == Origin::Arm(w.task)) else { return Ok(()) };
                if r.id == first_id + 1 {
                    let pose = self.estimate.map(|e| e.pose).unwrap_or_default();
                    let penultimate = Some((f.images.clone(), pose));
                    let phase = Phase::Imaging { target, since_s, first_id, penultimate };
                    self.work = Some(ArmWork { phase, ..w });
                } else if r.id == first_id + 3 {
                    return self.on_images(bus, w, target, penultimate, f);
                }
            }
            Phase::Deployed { until_s, counts } if f.t + 1e-9 >= until_s => {
                self.work = None;
                let (state, message) = if counts == self.counts {
                    let what = match (w.action, self.placements.last()) {
                        (ArmAction::PlaceInstrument, Some(p)) if p.task == w.task => {
                            format!("instrument placed: {}", placement_words(p))
                        }
                        (ArmAction::PlaceInstrument, _) => "instrument placed".into(),
                        (ArmAction::Scoop, _) => "soil sample scooped".into(),
                    };
                    (TaskState::Success, what)
                } else {
                    (TaskState::Failure, "the wheels turned while the arm was deployed".to_string())
                };
                self.status(bus, w.task, state, message)?;
            }
            Phase::Deployed { .. } => {}
        }
        Ok(())
    }

    fn absorb(&mut self, ctx: &mut Ctx<'_>, state: JausState) -> Result<(), ComponentFault> {
        if let Some(s) = &self.estimates
            && let Some(e) = ctx.bus.latest(s)?
        {
            self.estimate = Some(*e);
        }
        let frames = match &self.frames {
            Some(s) => ctx.bus.take(s)?,
            None => Vec::new(),
        };
        let cancels = match &self.cancels {
            Some(s) => ctx.bus.take(s)?,
            None => Vec::new(),
        };
        for c in cancels {
            if let Some(w) = self.work.clone()
                && w.task == c.task
            {
                self.work = None;
                self.status(ctx.bus, w.task, TaskState::Cancelled, "cancelled".into())?;
            }
        }
        for f in &frames {
            self.on_frame(ctx.bus, f)?;
        }
        if let Some(ArmWork { task, phase: Phase::Imaging { since_s, .. }, .. }) = self.work.clone()
            && ctx.time_s > since_s + IMAGING_TIMEOUT_S
        {
            self.work = None;
            let why = format!("no work-volume images within {IMAGING_TIMEOUT_S:.0} s; nothing moved");
            self.status(ctx.bus, task, TaskState::Failure, why)?;
        }
        let commands = match &self.commands {
            Some(s) => ctx.bus.take(s)?,
            None => Vec::new(),
        };
        for cmd in commands {
            if state != JausState::Ready {
                self.status(ctx.bus, cmd.task, TaskState::Aborted, format!("tooling arm in {state}"))?;
                continue;
            }
            if let Some(w) = &self.work {
                let why = format!("arm busy with task {}", w.task);
                self.status(ctx.bus, cmd.task, TaskState::Failure, why)?;
                continue;
            }
            if let Some(why) = self.unreachable(Point2::new(cmd.target[0], cmd.target[1])) {
                self.status(ctx.bus, cmd.task, TaskState::Failure, why)?;
                continue;
            }
            match cmd.action {
                ArmAction::PlaceInstrument => self.request_images(ctx, &cmd)?,
                ArmAction::Scoop => {
                    let until_s = ctx.time_s + self.config.scoop_s;
                    self.deploy(ctx.bus, cmd.task, cmd.action, until_s)?;
                    let why = format!("working until t = {until_s:.1} s");
                    self.status(ctx.bus, cmd.task, TaskState::InProcess, why)?;
                }
            }
        }
        Ok(())
    }
}

/// A placement in words: the target and contact angle, or the refusal and its reason.
pub fn placement_words(p: &PlacementMsg) -> String {
    match (&p.target, p.contact_angle_deg, &p.reason) {
        (Some(t), Some(a), _) => {
            let w = p.to_world(t.point);
            format!(
                "AutoPlace placed at ({:.2}, {:.2}, {:.2}), contact angle {a:.1} deg from the sensed normal",
                w[0], w[1], w[2]
            )
        }
        (_, _, reason) => format!(
            "AutoPlace refused: {} ({} candidates examined); nothing moved",
            reason.as_deref().unwrap_or("no_data"),
            p.examined
        ),
    }
}

impl Component for ToolingArm {
    fn name(&self) -> &'static str {
        "tooling-arm"
    }

    fn ports(&self) -> Ports {
        Ports {
            inputs: vec![
                Port::of(topics::ARM_COMMAND),
                Port::of(topics::EXECUTIVE_CANCEL),
                Port::of(topics::LOCALIZATION_ESTIMATE),
                Port::of(topics::PLATFORM_FRAME),
            ],
            outputs: vec![
                Port::of(topics::PLATFORM_HOLD),
                Port::of(topics::EXECUTIVE_MOTION),
                Port::of(topics::ARM_PLACEMENT),
                Port::of(topics::TASK_STATUS),
            ],
        }
    }

    fn connect(&mut self, bus: &mut Bus) -> Result<(), BusError> {
        self.commands = Some(bus.subscribe(topics::ARM_COMMAND)?);
        self.cancels = Some(bus.subscribe(topics::EXECUTIVE_CANCEL)?);
        self.estimates = Some(bus.subscribe(topics::LOCALIZATION_ESTIMATE)?);
        self.frames = Some(bus.subscribe(topics::PLATFORM_FRAME)?);
        Ok(())
    }

    fn step(&mut self, ctx: &mut Ctx<'_>) -> Result<(), ComponentFault> {
        self.absorb(ctx, JausState::Ready)
    }

    fn idle(&mut self, ctx: &mut Ctx<'_>, state: JausState) -> Result<(), ComponentFault> {
        self.absorb(ctx, state)
    }

    fn on_transition(
        &mut self,
        ctx: &mut Ctx<'_>,
        _from: JausState,
        to: JausState,
    ) -> Result<(), ComponentFault> {
        if matches!(to, JausState::Emergency | JausState::Failure | JausState::Shutdown)
            && let Some(w) = self.work.take()
        {
            self.status(ctx.bus, w.task, TaskState::Aborted, format!("arm stowed: {to}"))?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::messages::FrameSource;
    use rovernav_core::SensorFrame;

    #[test]
    fn a_placement_images_first_and_a_refusal_holds_nothing_and_fails_the_task() {
        let mut bus = Bus::in_process();
        let mut arm = ToolingArm::new(ArmConfig::default());
        arm.connect(&mut bus).unwrap();
        let motion = bus.subscribe(topics::EXECUTIVE_MOTION).unwrap();
        let holds = bus.subscribe(topics::PLATFORM_HOLD).unwrap();
        let status = bus.subscribe(topics::TASK_STATUS).unwrap();
        let placements = bus.subscribe(topics::ARM_PLACEMENT).unwrap();
        bus.publish(topics::LOCALIZATION_ESTIMATE, EstimateMsg::default()).unwrap();
        let cmd = ArmTaskMsg { task: 7, action: ArmAction::PlaceInstrument, target: [1.0, 0.0] };
        bus.publish(topics::ARM_COMMAND, cmd).unwrap();
        arm.step(&mut Ctx { bus: &mut bus, time_s: 0.0 }).unwrap();
        // The imaging sequence: back a step, a pair, the step, the pairs; all the arm's own.
        let requests = bus.take(&motion).unwrap();
        assert_eq!(requests.len(), 4);
        assert!(requests.iter().all(|r| r.origin == Origin::Arm(7)));
        assert!(
            matches!(requests[0].command, CommandMsg::Drive { distance, .. } if distance == -LAST_STEP_M)
        );
        assert!(matches!(requests[2].command, CommandMsg::Drive { distance, .. } if distance == LAST_STEP_M));
        assert_eq!(bus.take(&status).unwrap()[0].state, TaskState::InProcess);
        // The frames come back without images: AutoPlace refuses for no data.
        for (seq, r) in requests.iter().enumerate() {
            let frame =
                FrameMsg::new(seq as u64 + 1, FrameSource::Command((**r).clone()), &SensorFrame::default());
            bus.publish(topics::PLATFORM_FRAME, frame).unwrap();
            arm.step(&mut Ctx { bus: &mut bus, time_s: 1.0 + seq as f64 }).unwrap();
        }
        let done = bus.take(&status).unwrap();
        assert_eq!(done.len(), 1);
        assert_eq!(done[0].state, TaskState::Failure);
        assert!(done[0].message.contains("refused: no_data") && done[0].message.contains("nothing moved"));
        assert!(bus.take(&holds).unwrap().is_empty(), "nothing moves on a refusal");
        let p = bus.take(&placements).unwrap();
        assert_eq!((p.len(), p[0].reason.as_deref()), (1, Some("no_data")));
        assert_eq!(arm.placements().len(), 1);
        // The arm is free again.
        bus.publish(topics::ARM_COMMAND, ArmTaskMsg { task: 8, ..cmd }).unwrap();
        arm.step(&mut Ctx { bus: &mut bus, time_s: 9.0 }).unwrap();
        assert_eq!(bus.take(&motion).unwrap().len(), 4);
    }
}
