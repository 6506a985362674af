//! The platform layer as components: the simulated rover and its tooling arm.
//!
//! The simulator stands where MRPTA's platform control layer and sensor hardware stand (paper
//! 004 section 2): it executes the commands the motion controller passes on, rests (sampling)
//! when asked or when the runtime's clock has moved on without it, and publishes what its sensors
//! reported as a frame. Faults scheduled by the mission file
//! are injected here, on the truth side; nothing downstream learns of them except through the
//! sensor data. The tooling arm is its own component ([`crate::arm_server`], re-exported here).

pub use crate::arm_server::{ArmConfig, ToolingArm};
use crate::components::{Component, ComponentFault, Ctx, JausState, Port, Ports};
use crate::messages::{
    FrameMsg, FrameSource, HoldMsg, MotionRequest, Origin, RideAlongMsg, TaskState, TaskStatusMsg, topics,
};
use rovernav_bus::{Bus, BusError, Subscriber};
use rovernav_core::{NavCommand, Pose3, SensorFrame};
use rovernav_sim::{Fault, Simulator};

/// Longest hold the platform executes in one step (s), so a bad hold time cannot spin forever.
const MAX_HOLD_S: f64 = 3600.0;
/// Seed stream of the pictures taken alongside the navigator's sensing (xor the frame number).
const RIDE_ALONG_SEED: u64 = 0x7674_7472_6163_6b00;

/// When a scheduled fault starts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FaultTrigger {
    /// Before the n-th command executes (commands count from 1; 0 is before the initial frame).
    Cycle(u64),
    /// Before the first action that starts at or after this simulated time (s).
    Time(f64),
}

/// A component crash the run loop injects when its trigger comes (a software fault: the
/// simulator has no part in it).
#[derive(Clone, Debug, PartialEq)]
pub struct ScheduledCrash {
    /// The component's name in the graph.
    pub component: String,
    /// When.
    pub at: FaultTrigger,
}

/// A fault as it was injected: what, when, and the hazard contacts before it (truth, for
/// scoring fault drills).
#[derive(Clone, Debug, PartialEq)]
pub struct InjectedFault {
    /// The mission file's kind name (`silent_sensor`, `component_crash`...).
    pub kind: &'static str,
    /// The crashed component, for a crash.
    pub component: Option<String>,
    /// Simulated time of the injection (s).
    pub time_s: f64,
    /// Hazard contacts before the injection.
    pub hazard_contacts_before: u32,
}

/// The mission file's kind name of a simulator fault.
pub fn fault_kind_name(fault: &Fault) -> &'static str {
    match fault {
        Fault::SilentSensor(_) => "silent_sensor",
        Fault::NanRange(_) => "nan_range",
        Fault::GyroBiasJump(_) => "gyro_bias_jump",
        Fault::StalledWheel { .. } => "stalled_wheel",
        Fault::CompassNaN => "compass_nan",
    }
}

/// A fault the platform injects into the simulator when its trigger comes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScheduledFault {
    /// The fault.
    pub fault: Fault,
    /// When.
    pub at: FaultTrigger,
}

/// One command the platform executed, with the truth after it (for scoring and logs only).
#[derive(Clone, Debug)]
pub struct Executed {
    /// The request.
    pub request: MotionRequest,
    /// The command as the simulator ran it.
    pub command: NavCommand,
    /// What the sensors reported.
    pub frame: SensorFrame,
    /// Simulator truth afterwards.
    pub truth: Pose3,
    /// Hazard contacts so far.
    pub hazard_contacts: u32,
}

/// The simulated rover: the platform layer.
pub struct SimPlatform {
    sim: Simulator,
    faults: Vec<ScheduledFault>,
    injected: Vec<InjectedFault>,
    commands: Option<Subscriber<MotionRequest>>,
    holds: Option<Subscriber<HoldMsg>>,
    ride_along: Option<Subscriber<RideAlongMsg>>,
    /// The Navcam pointing (pan, tilt) of the pairs taken alongside the navigator's sensing.
    ride_navcam: Option<[f64; 2]>,
    seq: u64,
    executed_count: u64,
    executed: Vec<Executed>,
    initial_frame: SensorFrame,
}

impl SimPlatform {
    /// Wraps a simulator; `faults` are injected when their triggers come.
    pub fn new(sim: Simulator, faults: Vec<ScheduledFault>) -> Self {
        Self {
            sim,
            faults,
            injected: Vec::new(),
            commands: None,
            holds: None,
            ride_along: None,
            ride_navcam: None,
            seq: 0,
            executed_count: 0,
            executed: Vec::new(),
            initial_frame: SensorFrame::default(),
        }
    }

    /// The simulator (truth: for scoring, logs and pictures only).
    pub fn sim(&self) -> &Simulator {
        &self.sim
    }

    /// The frame taken at rest before the first command.
    pub fn initial_frame(&self) -> &SensorFrame {
        &self.initial_frame
    }

    /// Takes the commands executed since the last call, in order.
    pub fn take_executed(&mut self) -> Vec<Executed> {
        std::mem::take(&mut self.executed)
    }

    /// Faults injected so far.
    pub fn injected_faults(&self) -> &[InjectedFault] {
        &self.injected
    }

    /// Injects the faults whose trigger has come, given the number of the next command.
    fn inject_due(&mut self, next_command: u64) {
        let time = self.sim.time();
        let (due, later): (Vec<ScheduledFault>, Vec<ScheduledFault>) =
            self.faults.iter().partition(|f| match f.at {
                FaultTrigger::Cycle(n) => n <= next_command,
                FaultTrigger::Time(t) => t <= time,
            });
        for f in &due {
            self.sim.inject_fault(f.fault);
            self.injected.push(InjectedFault {
                kind: fault_kind_name(&f.fault),
                component: None,
                time_s: time,
                hazard_contacts_before: self.sim.hazard_contacts(),
            });
        }
        self.faults = later;
    }

    fn publish_frame(
        &mut self,
        bus: &mut Bus,
        source: FrameSource,
        frame: &SensorFrame,
    ) -> Result<(), BusError> {
        self.seq += 1;
        bus.publish(topics::PLATFORM_FRAME, FrameMsg::new(self.seq, source, frame))
    }

    /// Rests, sampling, until `until_s` (one frame for the whole hold; nothing if the clock is
    /// there already), or sleeps without sampling when `sleep` is set. The runtime's clock
    /// moving past the platform's is a hold too.
    fn hold(&mut self, bus: &mut Bus, until_s: f64, sleep: bool) -> Result<(), BusError> {
        let until = until_s.min(self.sim.time() + MAX_HOLD_S);
        if until.is_nan() || until <= self.sim.time() {
            return Ok(());
        }
        self.inject_due(self.executed_count + 1);
        if sleep {
            let frame = self.sim.sleep(until);
            return self.publish_frame(bus, FrameSource::Hold, &frame);
        }
        let mut frame = SensorFrame::default();
        while self.sim.time() < until - 1e-9 {
            // An empty sense request is one sample period at rest.
            let rest = self.sim.execute(&NavCommand::Sense(Vec::new()));
            frame.imu.extend(rest.imu);
            frame.odometry.extend(rest.odometry);
            frame.proximity = rest.proximity;
            frame.power = rest.power;
            frame.t = rest.t;
        }
        self.publish_frame(bus, FrameSource::Hold, &frame)
    }

    /// Executes one request.
    fn execute(&mut self, bus: &mut Bus, request: MotionRequest) -> Result<(), BusError> {
        let command = request.command.clone();
        if matches!(command, NavCommand::Finish(..)) {
            return Ok(());
        }
        self.inject_due(self.executed_count + 1);
        let mut frame = self.sim.execute(&command);
        if let (Origin::Navigator, NavCommand::Sense(_), Some([pan, tilt])) =
            (request.origin, &command, self.ride_navcam)
        {
            // Exposed while the navigator's own sensing holds the rover still: the pair changes
            // nothing the run does (no time, energy or draws of the simulator's noise streams).
            let seed = RIDE_ALONG_SEED ^ (self.seq + 1);
            let pair = rovernav_sim::navcam::Pair::Navcam { pan, tilt };
            frame.images.extend(self.sim.pictures_alongside(pair, seed));
        }
        self.executed_count += 1;
        if let Origin::Task(task) = request.origin {
            let empty: Vec<&str> =
                frame.clouds.iter().filter(|c| c.points.is_empty()).map(|c| c.camera.as_str()).collect();
            let (state, message) = match (&frame.motion_stopped, empty.is_empty()) {
                (Some(why), _) => (TaskState::Failure, format!("motion stopped: {why}")),
                (None, false) => (TaskState::Failure, format!("no range data from {}", empty.join(", "))),
                (None, true) if frame.clouds.is_empty() => (TaskState::Success, "done".to_string()),
                (None, true) => (TaskState::Success, format!("{} images taken", frame.clouds.len())),
            };
            bus.publish(
                topics::TASK_STATUS,
                TaskStatusMsg { task, component: self.name().into(), state, outcome: None, message },
            )?;
        }
        self.publish_frame(bus, FrameSource::Command(request.clone()), &frame)?;
        self.executed.push(Executed {
            request,
            command,
            truth: self.sim.truth(),
            hazard_contacts: self.sim.hazard_contacts(),
            frame,
        });
        Ok(())
    }

    /// Takes the latest ride-along request, if any came.
    fn take_ride_along(&mut self, bus: &mut Bus) -> Result<(), BusError> {
        if let Some(sub) = &self.ride_along
            && let Some(last) = bus.take(sub)?.pop()
        {
            self.ride_navcam = last.navcam;
        }
        Ok(())
    }

    /// The latest time the holds asked for, and whether any asked to sleep.
    fn take_holds(&mut self, bus: &mut Bus) -> Result<Option<(f64, bool)>, BusError> {
        let Some(holds) = &self.holds else { return Ok(None) };
        let holds = bus.take(holds)?;
        let sleep = holds.iter().any(|h| h.sleep);
        Ok(holds.iter().map(|h| h.until_s).filter(|t| t.is_finite()).reduce(f64::max).map(|t| (t, sleep)))
    }
}

impl Component for SimPlatform {
    fn name(&self) -> &'static str {
        "platform"
    }

    fn ports(&self) -> Ports {
        Ports {
            inputs: vec![
                Port::of(topics::PLATFORM_COMMAND),
                Port::of(topics::PLATFORM_HOLD),
                Port::of(topics::PLATFORM_RIDE_ALONG),
            ],
            outputs: vec![Port::of(topics::PLATFORM_FRAME), Port::of(topics::TASK_STATUS)],
        }
    }

    fn connect(&mut self, bus: &mut Bus) -> Result<(), BusError> {
        self.commands = Some(bus.subscribe(topics::PLATFORM_COMMAND)?);
        self.holds = Some(bus.subscribe(topics::PLATFORM_HOLD)?);
        self.ride_along = Some(bus.subscribe(topics::PLATFORM_RIDE_ALONG)?);
        Ok(())
    }

    /// Samples at rest before the first command (lets the pose estimator find the gyro bias).
    fn initialize(&mut self, ctx: &mut Ctx<'_>) -> Result<(), ComponentFault> {
        if self.seq == 0 {
            self.inject_due(0);
            self.initial_frame = self.sim.initial_frame();
            let frame = self.initial_frame.clone();
            ctx.bus.publish(topics::PLATFORM_FRAME, FrameMsg::new(0, FrameSource::Initial, &frame))?;
        }
        Ok(())
    }

    fn step(&mut self, ctx: &mut Ctx<'_>) -> Result<(), ComponentFault> {
        self.hold(ctx.bus, ctx.time_s, false)?;
        self.take_ride_along(ctx.bus)?;
        let commands = match &self.commands {
            Some(s) => ctx.bus.take(s)?,
            None => Vec::new(),
        };
        for request in commands {
            self.execute(ctx.bus, (*request).clone())?;
        }
        if let Some((until, sleep)) = self.take_holds(ctx.bus)? {
            self.hold(ctx.bus, until, sleep)?;
        }
        Ok(())
    }

    /// Standing by or stopped, the wheels stay locked (commands are refused) but the sensors
    /// keep sampling through holds.
    fn idle(&mut self, ctx: &mut Ctx<'_>, state: JausState) -> Result<(), ComponentFault> {
        self.hold(ctx.bus, ctx.time_s, false)?;
        self.take_ride_along(ctx.bus)?;
        let commands = match &self.commands {
            Some(s) => ctx.bus.take(s)?,
            None => Vec::new(),
        };
        for request in commands {
            if let Origin::Task(task) = request.origin {
                let message = format!("platform in {state}: command refused");
                ctx.bus.publish(
                    topics::TASK_STATUS,
                    TaskStatusMsg {
                        task,
                        component: self.name().into(),
                        state: TaskState::Aborted,
                        outcome: None,
                        message,
                    },
                )?;
            }
        }
        if let Some((until, sleep)) = self.take_holds(ctx.bus)? {
            self.hold(ctx.bus, until, sleep)?;
        }
        Ok(())
    }
}
