//! Reflexive-layer components wrapping the autonomy: the navigator, the pose estimator and the
//! motion controller.
//!
//! The navigators of rovernav each bundle MRPTA's terrain evaluator, map manager, planner and
//! segment driver behind one `Navigator` trait (the algorithms stay in their crates), so one
//! `navigator` component hosts them; the pose estimator hosts a `Localizer`; the motion
//! controller is the single gate between command sources (navigator, operator, tasks) and the
//! platform, so an emergency stop that reaches it stops every motion.

use crate::components::{Component, ComponentFault, Ctx, JausState, Port, Ports};
use crate::messages::{
    CancelMsg, CommandMsg, DriveToMsg, EstimateMsg, FrameMsg, MotionRequest, Origin, PlanMsg, PoseMsg,
    TaskState, TaskStatusMsg, topics,
};
use crate::shadow::{ShadowNavigator, ShadowReport};
use rovernav_bus::{Bus, BusError, Subscriber};
use rovernav_core::{
    Goal, Localizer, NavCommand, NavInput, Navigator, Outcome, Overlay, Point2, PoseEstimate, RoverConfig,
    SensorFrame,
};

/// Takes every queued message of an optional subscription.
fn take_all<T: rovernav_bus::Message>(
    bus: &mut Bus,
    sub: &Option<Subscriber<T>>,
) -> Result<Vec<std::sync::Arc<T>>, BusError> {
    match sub {
        Some(s) => bus.take(s),
        None => Ok(Vec::new()),
    }
}

fn task_status(
    bus: &mut Bus,
    component: &str,
    task: u64,
    state: TaskState,
    outcome: Option<String>,
    message: String,
) -> Result<(), BusError> {
    bus.publish(
        topics::TASK_STATUS,
        TaskStatusMsg { task, component: component.into(), state, outcome, message },
    )
}

/// Appends a later frame to an earlier one: everything the platform reported since then.
fn merge_frames(into: &mut SensorFrame, later: SensorFrame) {
    into.t = later.t;
    into.clouds.extend(later.clouds);
    into.imu.extend(later.imu);
    into.odometry.extend(later.odometry);
    into.proximity = later.proximity;
    if into.motion_stopped.is_none() {
        into.motion_stopped = later.motion_stopped;
    }
}

/// The navigator component: drives one leg (a `DriveTo`) at a time with a registered navigator.
pub struct NavigatorComponent {
    registry_name: String,
    /// Parameters of every instance (the mission's `[navigator_params]`).
    params: rovernav_navigation::NavigatorParams,
    rover: RoverConfig,
    navigator: Box<dyn Navigator>,
    /// The navigator above has not driven a leg yet.
    unused: bool,
    leg: Option<(u64, Goal)>,
    leg_started: bool,
    /// Everything the platform reported since the last step.
    frame: Option<SensorFrame>,
    last_frame: SensorFrame,
    estimate: Option<PoseEstimate>,
    /// The localiser's latest localisation target (mast pan, rad).
    localization_target: Option<f64>,
    fresh: bool,
    next_id: u64,
    last_plan: Vec<Point2>,
    drive_to: Option<Subscriber<DriveToMsg>>,
    cancels: Option<Subscriber<CancelMsg>>,
    frames: Option<Subscriber<FrameMsg>>,
    estimates: Option<Subscriber<EstimateMsg>>,
    /// A navigator riding along in shadow (`shadow_navigator`), never obeyed.
    shadow: Option<ShadowNavigator>,
}

impl NavigatorComponent {
    /// Hosts `navigator` (registry name `registry_name`); later legs get fresh instances of the
    /// same name, since a navigator's map and progress belong to one start and goal.
    pub fn new(navigator: Box<dyn Navigator>, registry_name: &str, rover: RoverConfig) -> Self {
        Self {
            registry_name: registry_name.to_string(),
            params: Default::default(),
            rover,
            navigator,
            unused: true,
            leg: None,
            leg_started: false,
            frame: None,
            last_frame: SensorFrame::default(),
            estimate: None,
            localization_target: None,
            fresh: false,
            next_id: 0,
            last_plan: Vec::new(),
            drive_to: None,
            cancels: None,
            frames: None,
            estimates: None,
            shadow: None,
        }
    }

    /// Runs registered navigator `name` in shadow beside the hosted one (see [`crate::shadow`]).
    pub fn with_shadow(mut self, name: Option<&str>) -> Result<Self, String> {
        self.shadow = name.map(|n| ShadowNavigator::new(n, &self.rover)).transpose()?;
        Ok(self)
    }

    /// The shadow navigator's record, if one rides along.
    pub fn shadow_report(&self) -> Option<ShadowReport> {
        self.shadow.as_ref().map(|s| s.report().clone())
    }

    /// Later legs' instances take these parameters (those the first instance was built with).
    pub fn with_params(mut self, params: rovernav_navigation::NavigatorParams) -> Self {
        self.params = params;
        self
    }

    /// The hosted navigator's name.
    pub fn navigator_name(&self) -> &str {
        self.navigator.name()
    }

    /// The current plan (world frame).
    pub fn planned_path(&self) -> Vec<Point2> {
        self.navigator.planned_path()
    }

    /// The navigator's drawings.
    pub fn overlays(&self) -> Vec<Overlay> {
        self.navigator.overlays()
    }

    /// Reads commands and sensor data (in every live state).
    fn absorb(&mut self, bus: &mut Bus) -> Result<(), ComponentFault> {
        for c in take_all(bus, &self.cancels)? {
            if self.leg.as_ref().is_some_and(|(task, _)| *task == c.task) {
                self.leg = None;
                task_status(bus, self.name(), c.task, TaskState::Cancelled, None, "cancelled".into())?;
            }
        }
        for d in take_all(bus, &self.drive_to)? {
            if let Some((old, _)) = self.leg.take() {
                task_status(
                    bus,
                    self.name(),
                    old,
                    TaskState::Cancelled,
                    None,
                    format!("replaced by task {}", d.task),
                )?;
            }
            if !self.unused {
                self.navigator = rovernav_navigation::navigator_with_params(
                    &self.registry_name,
                    &self.rover,
                    &self.params,
                )
                .map_err(|e| ComponentFault(e.to_string()))?;
            }
            self.unused = false;
            if let Some(shadow) = self.shadow.as_mut() {
                shadow.new_leg().map_err(ComponentFault)?;
            }
            self.leg = Some((d.task, d.goal.clone()));
            self.leg_started = false;
        }
        for f in take_all(bus, &self.frames)? {
            let frame = f.frame();
            match &mut self.frame {
                Some(pending) => merge_frames(pending, frame),
                None => self.frame = Some(frame),
            }
        }
        if let Some(e) = take_all(bus, &self.estimates)?.pop() {
            self.estimate = Some(e.estimate());
            self.localization_target = e.localization_target;
            self.fresh = true;
        }
        Ok(())
    }

    fn abort_leg(&mut self, bus: &mut Bus, why: String) -> Result<(), BusError> {
        if let Some((task, _)) = self.leg.take() {
            task_status(bus, self.name(), task, TaskState::Aborted, None, why)?;
        }
        Ok(())
    }
}

impl Component for NavigatorComponent {
    fn name(&self) -> &'static str {
        "navigator"
    }

    fn ports(&self) -> Ports {
        Ports {
            inputs: vec![
                Port::of(topics::EXECUTIVE_DRIVE_TO),
                Port::of(topics::EXECUTIVE_CANCEL),
                Port::of(topics::PLATFORM_FRAME),
                Port::of(topics::LOCALIZATION_ESTIMATE),
            ],
            outputs: vec![
                Port::of(topics::NAVIGATION_COMMAND),
                Port::of(topics::NAVIGATION_PLAN),
                Port::of(topics::NAVIGATION_SHADOW),
                Port::of(topics::TASK_STATUS),
            ],
        }
    }

    fn connect(&mut self, bus: &mut Bus) -> Result<(), BusError> {
        self.drive_to = Some(bus.subscribe(topics::EXECUTIVE_DRIVE_TO)?);
        self.cancels = Some(bus.subscribe(topics::EXECUTIVE_CANCEL)?);
        self.frames = Some(bus.subscribe(topics::PLATFORM_FRAME)?);
        self.estimates = Some(bus.subscribe(topics::LOCALIZATION_ESTIMATE)?);
        Ok(())
    }

    fn step(&mut self, ctx: &mut Ctx<'_>) -> Result<(), ComponentFault> {
        self.absorb(ctx.bus)?;
        let Some((task, goal)) = self.leg.clone() else { return Ok(()) };
        // Step once per new estimate (the result of the last command), or at once on a new leg.
        if !self.fresh && self.leg_started {
            return Ok(());
        }
        let Some(estimate) = self.estimate else { return Ok(()) };
        if let Some(f) = self.frame.take() {
            self.last_frame = f;
        }
        let input = NavInput {
            time: self.last_frame.t,
            estimate,
            goal: &goal,
            frame: &self.last_frame,
            localization_target: self.localization_target,
        };
        let command = self.navigator.step(&input);
        if let Some(msg) = self.shadow.as_mut().and_then(|s| s.step(task, &input, &command)) {
            ctx.bus.publish(topics::NAVIGATION_SHADOW, msg)?;
        }
        self.fresh = false;
        let plan = self.navigator.planned_path();
        if plan != self.last_plan {
            let points = plan.iter().map(|p| [p.x, p.y]).collect();
            ctx.bus.publish(topics::NAVIGATION_PLAN, PlanMsg { task, points })?;
            self.last_plan = plan;
        }
        if let NavCommand::Finish(outcome, message) = &command {
            self.leg = None;
            let state = if *outcome == Outcome::Reached { TaskState::Success } else { TaskState::Failure };
            task_status(ctx.bus, self.name(), task, state, Some(outcome.as_str().into()), message.clone())?;
            return Ok(());
        }
        if !self.leg_started {
            self.leg_started = true;
            let message = format!("driving to ({:.2}, {:.2})", goal.position.x, goal.position.y);
            task_status(ctx.bus, self.name(), task, TaskState::InProcess, None, message)?;
        }
        self.next_id += 1;
        let request = MotionRequest { id: self.next_id, origin: Origin::Navigator, command };
        ctx.bus.publish(topics::NAVIGATION_COMMAND, request)?;
        Ok(())
    }

    /// Standing by (mission paused) the navigator keeps its leg and its inputs, and steps on
    /// resume with everything that arrived meanwhile.
    fn idle(&mut self, ctx: &mut Ctx<'_>, _state: JausState) -> Result<(), ComponentFault> {
        self.absorb(ctx.bus)
    }

    fn on_transition(
        &mut self,
        ctx: &mut Ctx<'_>,
        _from: JausState,
        to: JausState,
    ) -> Result<(), ComponentFault> {
        if matches!(to, JausState::Emergency | JausState::Failure | JausState::Shutdown) {
            self.abort_leg(ctx.bus, format!("navigator in {to}"))?;
        }
        Ok(())
    }
}

/// Pose-estimator parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct PoseEstimatorConfig {
    /// Position standard deviation beyond which localisation has failed (m).
    pub max_position_sigma_m: f64,
}

impl Default for PoseEstimatorConfig {
    fn default() -> Self {
        // Dead reckoning grows 2-2.5 % of the distance (papers 001, 004): 50 m is a 2 km drive,
        // far beyond any mission budget here, so only a diverging estimator reaches it.
        Self { max_position_sigma_m: 50.0 }
    }
}

/// The pose estimator component: a registered localiser fed with every frame.
pub struct PoseEstimatorComponent {
    localizer: Box<dyn Localizer>,
    config: PoseEstimatorConfig,
    frames: Option<Subscriber<FrameMsg>>,
    resets: Option<Subscriber<PoseMsg>>,
    last: EstimateMsg,
}

impl PoseEstimatorComponent {
    /// Hosts a localiser.
    pub fn new(localizer: Box<dyn Localizer>, config: PoseEstimatorConfig) -> Self {
        Self { localizer, config, frames: None, resets: None, last: EstimateMsg::default() }
    }

    /// The current estimate.
    pub fn estimate(&self) -> PoseEstimate {
        self.localizer.estimate()
    }

    /// The localiser's correction counters.
    pub fn localizer_stats(&self) -> rovernav_core::LocalizerStats {
        self.localizer.stats()
    }

    /// Integrates new frames and resets, publishing an estimate after each frame. The estimator
    /// keeps tracking in Standby and Emergency: the rover can still be moved, and the gyro and
    /// encoder streams must not have gaps.
    fn track(&mut self, bus: &mut Bus) -> Result<(), ComponentFault> {
        for pose in take_all(bus, &self.resets)? {
            self.localizer.reset(*pose);
            self.publish(bus, self.last.frame_seq, self.last.t)?;
        }
        for f in take_all(bus, &self.frames)? {
            self.localizer.update(&f.frame());
            self.publish(bus, f.seq, f.t)?;
        }
        Ok(())
    }

    fn publish(&mut self, bus: &mut Bus, frame_seq: u64, t: f64) -> Result<(), ComponentFault> {
        let e = self.localizer.estimate();
        self.last = EstimateMsg {
            frame_seq,
            t,
            pose: e.pose,
            covariance: e.covariance,
            localization_target: self.localizer.localization_target(),
        };
        bus.publish(topics::LOCALIZATION_ESTIMATE, self.last)?;
        let p = e.pose;
        if ![p.x, p.y, p.z, p.roll, p.pitch, p.yaw].iter().all(|v| v.is_finite()) {
            return Err(ComponentFault(format!(
                "localisation failed: the estimate is not finite (x {}, y {}, yaw {})",
                p.x, p.y, p.yaw
            )));
        }
        if e.covariance.iter().flatten().any(|v| !v.is_finite()) {
            return Err(ComponentFault("localisation failed: the covariance is not finite".into()));
        }
        let sigma = (e.covariance[0][0] + e.covariance[1][1]).max(0.0).sqrt();
        if sigma.is_nan() || sigma > self.config.max_position_sigma_m {
            return Err(ComponentFault(format!(
                "localisation failed: position uncertainty {sigma:.2} m beyond {:.2} m",
                self.config.max_position_sigma_m
            )));
        }
        Ok(())
    }
}

impl Component for PoseEstimatorComponent {
    fn name(&self) -> &'static str {
        "pose-estimator"
    }

    fn ports(&self) -> Ports {
        Ports {
            inputs: vec![Port::of(topics::PLATFORM_FRAME), Port::of(topics::LOCALIZATION_RESET)],
            outputs: vec![Port::of(topics::LOCALIZATION_ESTIMATE)],
        }
    }

    fn connect(&mut self, bus: &mut Bus) -> Result<(), BusError> {
        self.frames = Some(bus.subscribe(topics::PLATFORM_FRAME)?);
        self.resets = Some(bus.subscribe(topics::LOCALIZATION_RESET)?);
        Ok(())
    }

    /// Integrates the frame the platform, initialized earlier, took at rest.
    fn initialize(&mut self, ctx: &mut Ctx<'_>) -> Result<(), ComponentFault> {
        self.track(ctx.bus)
    }

    fn step(&mut self, ctx: &mut Ctx<'_>) -> Result<(), ComponentFault> {
        self.track(ctx.bus)
    }

    fn idle(&mut self, ctx: &mut Ctx<'_>, _state: JausState) -> Result<(), ComponentFault> {
        self.track(ctx.bus)
    }
}

/// The motion controller: passes one command per cycle to the platform, in arrival order,
/// refuses malformed commands and, out of Ready, every command.
#[derive(Default)]
pub struct MotionController {
    navigation: Option<Subscriber<MotionRequest>>,
    executive: Option<Subscriber<MotionRequest>>,
    queue: std::collections::VecDeque<MotionRequest>,
    forwarded: u64,
}

impl MotionController {
    /// A controller with nothing forwarded yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Commands passed to the platform so far.
    pub fn forwarded(&self) -> u64 {
        self.forwarded
    }

    fn refuse(bus: &mut Bus, request: &MotionRequest, why: String) -> Result<(), BusError> {
        if let Origin::Task(task) = request.origin {
            task_status(bus, "motion-controller", task, TaskState::Aborted, None, why)?;
        }
        Ok(())
    }
}

/// Why a command must not reach the wheels, if it must not.
fn malformed(command: &CommandMsg) -> Option<String> {
    let finite = |v: f64| v.is_finite();
    match command {
        CommandMsg::Drive { distance, curvature, guard } => {
            (!finite(*distance) || !finite(*curvature) || guard.max_tilt.is_some_and(|t| !finite(t)))
                .then(|| format!("drive with non-finite distance {distance} or curvature {curvature}"))
        }
        CommandMsg::Turn { angle } => (!finite(*angle)).then(|| format!("turn by non-finite angle {angle}")),
        CommandMsg::Sense(_) => None,
        CommandMsg::Finish(..) => Some("`finish` is not a platform command".into()),
    }
}

impl Component for MotionController {
    fn name(&self) -> &'static str {
        "motion-controller"
    }

    fn ports(&self) -> Ports {
        Ports {
            inputs: vec![Port::of(topics::NAVIGATION_COMMAND), Port::of(topics::EXECUTIVE_MOTION)],
            outputs: vec![Port::of(topics::PLATFORM_COMMAND), Port::of(topics::TASK_STATUS)],
        }
    }

    fn connect(&mut self, bus: &mut Bus) -> Result<(), BusError> {
        self.navigation = Some(bus.subscribe(topics::NAVIGATION_COMMAND)?);
        self.executive = Some(bus.subscribe(topics::EXECUTIVE_MOTION)?);
        Ok(())
    }

    /// One command per cycle keeps the platform's actions one at a time, so that work which
    /// needs no platform action (the tooling arm) overlaps with the next command.
    fn step(&mut self, ctx: &mut Ctx<'_>) -> Result<(), ComponentFault> {
        let mut requests = take_all(ctx.bus, &self.executive)?;
        requests.extend(take_all(ctx.bus, &self.navigation)?);
        for r in requests {
            match malformed(&r.command) {
                Some(why) => Self::refuse(ctx.bus, &r, format!("refused: {why}"))?,
                None => self.queue.push_back((*r).clone()),
            }
        }
        if let Some(r) = self.queue.pop_front() {
            self.forwarded += 1;
            ctx.bus.publish(topics::PLATFORM_COMMAND, r)?;
        }
        Ok(())
    }

    /// Out of Ready every queued command is dropped, so nothing stale moves the rover on resume.
    fn idle(&mut self, ctx: &mut Ctx<'_>, state: JausState) -> Result<(), ComponentFault> {
        let mut requests: Vec<MotionRequest> = self.queue.drain(..).collect();
        requests.extend(take_all(ctx.bus, &self.executive)?.iter().map(|r| (**r).clone()));
        requests.extend(take_all(ctx.bus, &self.navigation)?.iter().map(|r| (**r).clone()));
        for r in requests {
            Self::refuse(ctx.bus, &r, format!("motion controller in {state}"))?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::messages::{FrameSource, SenseMsg};
    use rovernav_core::Pose3;

    /// A localiser that diverges to NaN on its second update.
    struct Diverging(u32);

    impl Localizer for Diverging {
        fn name(&self) -> &str {
            "diverging"
        }
        fn reset(&mut self, _pose: Pose3) {
            self.0 = 0;
        }
        fn update(&mut self, _frame: &SensorFrame) {
            self.0 += 1;
        }
        fn estimate(&self) -> PoseEstimate {
            let x = if self.0 >= 2 { f64::NAN } else { 1.0 };
            PoseEstimate { pose: Pose3 { x, ..Default::default() }, covariance: [[0.0; 3]; 3] }
        }
    }

    fn hold_frame(seq: u64) -> FrameMsg {
        FrameMsg::new(seq, FrameSource::Hold, &SensorFrame::default())
    }

    #[test]
    fn a_non_finite_estimate_is_a_localisation_failure_and_a_reset_is_applied_first() {
        let mut bus = Bus::in_process();
        let mut pe = PoseEstimatorComponent::new(Box::new(Diverging(0)), PoseEstimatorConfig::default());
        pe.connect(&mut bus).unwrap();
        let estimates = bus.subscribe(topics::LOCALIZATION_ESTIMATE).unwrap();
        bus.publish(topics::PLATFORM_FRAME, hold_frame(1)).unwrap();
        pe.step(&mut Ctx { bus: &mut bus, time_s: 0.0 }).unwrap();
        assert_eq!(bus.take(&estimates).unwrap()[0].frame_seq, 1);
        // A reset and a frame in one cycle: the reset comes first, so the frame is integrated
        // from the reset pose (here: the counter restarts and no divergence yet).
        bus.publish(topics::LOCALIZATION_RESET, PoseMsg::default()).unwrap();
        bus.publish(topics::PLATFORM_FRAME, hold_frame(2)).unwrap();
        pe.step(&mut Ctx { bus: &mut bus, time_s: 0.0 }).unwrap();
        bus.publish(topics::PLATFORM_FRAME, hold_frame(3)).unwrap();
        let err = pe.step(&mut Ctx { bus: &mut bus, time_s: 0.0 }).unwrap_err();
        assert!(err.0.contains("localisation failed") && err.0.contains("not finite"), "{err}");
    }

    #[test]
    fn the_motion_controller_forwards_one_command_per_cycle_and_refuses_bad_ones() {
        let mut bus = Bus::in_process();
        let mut mc = MotionController::new();
        mc.connect(&mut bus).unwrap();
        let platform = bus.subscribe(topics::PLATFORM_COMMAND).unwrap();
        let status = bus.subscribe(topics::TASK_STATUS).unwrap();
        let sense = CommandMsg::Sense(vec![SenseMsg::BodyFront]);
        let bad = CommandMsg::Turn { angle: f64::NAN };
        for (id, command) in [(1, sense.clone()), (2, bad), (3, sense)] {
            bus.publish(topics::EXECUTIVE_MOTION, MotionRequest { id, origin: Origin::Task(id), command })
                .unwrap();
        }
        mc.step(&mut Ctx { bus: &mut bus, time_s: 0.0 }).unwrap();
        let first: Vec<u64> = bus.take(&platform).unwrap().iter().map(|r| r.id).collect();
        assert_eq!(first, [1]);
        let refused = bus.take(&status).unwrap();
        assert_eq!((refused[0].task, refused[0].state), (2, TaskState::Aborted));
        mc.step(&mut Ctx { bus: &mut bus, time_s: 0.0 }).unwrap();
        assert_eq!(bus.take(&platform).unwrap()[0].id, 3);
        // Queued commands do not survive a stop.
        bus.publish(
            topics::NAVIGATION_COMMAND,
            MotionRequest { id: 4, origin: Origin::Navigator, command: CommandMsg::Turn { angle: 0.1 } },
        )
        .unwrap();
        mc.idle(&mut Ctx { bus: &mut bus, time_s: 0.0 }, JausState::Emergency).unwrap();
        mc.step(&mut Ctx { bus: &mut bus, time_s: 0.0 }).unwrap();
        assert!(bus.take(&platform).unwrap().is_empty());
        assert_eq!(mc.forwarded(), 2);
    }
}
