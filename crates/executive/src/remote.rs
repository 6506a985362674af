//! The platform across a link: the simulator in one process, the autonomy in another.
//!
//! The rover process hosts [`RemotePlatform`] where a single-process run hosts
//! [`SimPlatform`]: the same name, ports and JAUS life. Each time the runtime runs it, it takes
//! the motion requests and holds queued for the platform, sends them with the call (initialize,
//! step or idle, at the runtime's time) over a [`PlatformLink`], and publishes on its local bus
//! the frames and task statuses that came back, in the order the simulator published them.
//!
//! The simulator process answers with a [`PlatformServer`]: a real [`SimPlatform`] (with the
//! mission's scheduled faults) on a private in-process bus, driven call for call as the rover
//! process's runtime drives its stand-in, so a two-process run is the single-process run exactly
//! (messages cross as JSON, whose floats round-trip bit for bit).
//!
//! Truth stays with the server and its judge ([`crate::judge::Judge`], the harness's; the
//! harness's `platform_server` builds a judged server). The rover process learns the simulated
//! clock (which the platform's frames carry anyway) and, once the mission has ended, the scoring:
//! the rover sends [`PlatformCall::Finish`] with the goal the mission ended with and its final
//! estimate; the server answers with a [`Scoring`] its judge computed from truth (goal and localisation errors, distance
//! driven, hazard contacts and events, optimal length, the true track and sensed cells for the
//! picture), which the run's loop merges with what the rover side knows (outcome, cycles,
//! components, tasks, fault) into the usual [`crate::report::Report`].
//!
//! The link is transport-agnostic: the CLI fills it with zenoh (`rovernav sim` / `rovernav
//! rover`); [`LocalLink`] fills it in process, through JSON, for tests.

use crate::components::{Component, ComponentFault, Ctx, JausState, Port, Ports};
use crate::judge::Judge;
use crate::messages::{FrameMsg, HoldMsg, MotionRequest, PoseMsg, RideAlongMsg, TaskStatusMsg, topics};
use crate::platform::{ScheduledFault, SimPlatform};
use crate::report::HazardEvent;
use crate::world::World;
use rovernav_bus::{Bus, BusError, Subscriber, TapId, Topic, decode, encode};
use rovernav_core::{Point2, Pose3};
use rovernav_sim::Simulator;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// The rover process's platform requests (what crosses the network, not the rover's local bus).
pub const PLATFORM_REQUEST: Topic<PlatformRequest> = Topic::new("/platform/request");
/// The simulator process's answers.
pub const PLATFORM_REPLY: Topic<PlatformReply> = Topic::new("/platform/reply");

/// What the runtime asked of the platform.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum PlatformCall {
    /// Initialization; names the mission and seed so that mismatched processes are refused.
    Initialize {
        /// Mission name.
        mission: String,
        /// Seed of the rover process.
        seed: u64,
    },
    /// One step while Ready.
    Step,
    /// One cycle while Standby or Emergency.
    Idle(JausState),
    /// The mission has ended: score it against truth.
    Finish {
        /// The goal the mission ended with (an operator may have moved it) [x, y] (m).
        goal: [f64; 2],
        /// The rover's final pose estimate.
        estimate: PoseMsg,
    },
}

/// One call of the platform with the inputs queued for it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct PlatformRequest {
    /// Request number (1 for the first); the reply repeats it.
    pub seq: u64,
    /// The runtime's time for the call (s).
    pub time_s: f64,
    /// The call.
    pub call: PlatformCall,
    /// Motion requests queued on `/platform/command`, oldest first.
    pub commands: Vec<MotionRequest>,
    /// Holds queued on `/platform/hold`, oldest first.
    pub holds: Vec<HoldMsg>,
    /// Ride-along requests queued on `/platform/ride_along`, oldest first.
    #[serde(default)]
    pub ride_along: Vec<RideAlongMsg>,
}

/// A message the platform published during a call.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum PlatformOutput {
    /// On `/platform/frame`.
    Frame(FrameMsg),
    /// On `/executive/task_status`.
    Status(TaskStatusMsg),
}

/// The answer to one [`PlatformRequest`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct PlatformReply {
    /// The request's number.
    pub seq: u64,
    /// The simulated clock after the call (s).
    pub sim_time_s: f64,
    /// What the platform published, in publish order.
    pub outputs: Vec<PlatformOutput>,
    /// The platform's fault, if the call raised one (the component then goes to Failure).
    pub fault: Option<String>,
    /// The scoring, in answer to [`PlatformCall::Finish`].
    pub scoring: Option<Scoring>,
}

/// The figures of a run that need simulator truth, computed by the simulator process.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct Scoring {
    /// True final position to the final goal (m).
    pub goal_error_m: f64,
    /// True path length driven (m).
    pub distance_driven_m: f64,
    /// Shortest safe path with full knowledge of the terrain (m).
    pub optimal_length_m: Option<f64>,
    /// Times the true rover entered a hazard.
    pub hazard_contacts: u32,
    /// Simulated mission time (s).
    pub sim_time_s: f64,
    /// Range images taken.
    pub sensing_actions: u64,
    /// Final |estimate - truth| in the plane (m).
    pub localization_error_m: f64,
    /// Start to final goal (m).
    pub straight_line_m: f64,
    /// Where and why the true rover met a hazard.
    pub hazard_events: Vec<HazardEvent>,
    /// Commands the simulator executed (the rover side's cycle count must agree).
    pub cycles: u64,
    /// True pose at the start and after every command (for the picture only).
    pub truth: Vec<PoseMsg>,
    /// Cells of the sensed-area grid covered by range data, as `[col, row]` (picture only).
    pub sensed: Vec<[u32; 2]>,
    /// The faults the simulator injected (`[[faults]]`), with the true contacts after each.
    #[serde(default)]
    pub injected_faults: Vec<crate::report::InjectedFaultReport>,
}

/// Why a link exchange failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("platform link: {0}")]
pub struct LinkError(pub String);

impl From<BusError> for LinkError {
    fn from(e: BusError) -> Self {
        LinkError(e.to_string())
    }
}

/// The rover process's end of the link: sends a request and blocks for its reply.
pub trait PlatformLink: Send {
    /// One request and its reply.
    fn exchange(&mut self, request: &PlatformRequest) -> Result<PlatformReply, LinkError>;
}

/// The simulator process's side: a [`SimPlatform`] on a private bus, answering requests.
pub struct PlatformServer {
    world: World,
    mission: String,
    seed: u64,
    bus: Bus,
    platform: SimPlatform,
    tap: TapId,
    judge: Box<dyn Judge>,
    cycles: u64,
    finished: bool,
}

impl PlatformServer {
    /// A server for a mission's world, seed and scheduled faults, judged by `judge`.
    pub fn new(
        world: World,
        mission: &str,
        seed: u64,
        faults: Vec<ScheduledFault>,
        mut judge: Box<dyn Judge>,
    ) -> Result<Self, BusError> {
        let sim = Simulator::new(
            world.terrain.clone(),
            world.rover.clone(),
            world.sensor_model.clone(),
            world.start,
            seed,
        );
        let mut platform = SimPlatform::new(sim, faults);
        let mut bus = Bus::in_process();
        platform.connect(&mut bus)?;
        let tap = bus.tap()?;
        judge.start(&world, platform.sim().truth());
        let mission = mission.to_string();
        Ok(Self { world, mission, seed, bus, platform, tap, judge, cycles: 0, finished: false })
    }

    /// Whether a [`PlatformCall::Finish`] has been answered (the serving loop may stop).
    pub fn finished(&self) -> bool {
        self.finished
    }

    /// Commands executed so far.
    pub fn cycles(&self) -> u64 {
        self.cycles
    }

    /// The simulator (truth: for the simulator process's own log lines).
    pub fn sim(&self) -> &Simulator {
        self.platform.sim()
    }

    /// Answers one request: the call runs on the simulator exactly as in a single-process run.
    pub fn handle(&mut self, request: &PlatformRequest) -> PlatformReply {
        let mut reply = PlatformReply {
            seq: request.seq,
            sim_time_s: self.platform.sim().time(),
            outputs: Vec::new(),
            fault: None,
            scoring: None,
        };
        if let PlatformCall::Finish { goal, estimate } = &request.call {
            reply.scoring = Some(self.score(Point2::new(goal[0], goal[1]), *estimate));
            self.finished = true;
            return reply;
        }
        match self.call(request) {
            Ok(outputs) => reply.outputs = outputs,
            Err(ComponentFault(why)) => reply.fault = Some(why),
        }
        reply.sim_time_s = self.platform.sim().time();
        reply
    }

    fn call(&mut self, request: &PlatformRequest) -> Result<Vec<PlatformOutput>, ComponentFault> {
        for c in &request.commands {
            self.bus.publish(topics::PLATFORM_COMMAND, c.clone())?;
        }
        for h in &request.holds {
            self.bus.publish(topics::PLATFORM_HOLD, *h)?;
        }
        for r in &request.ride_along {
            self.bus.publish(topics::PLATFORM_RIDE_ALONG, *r)?;
        }
        let mut ctx = Ctx { bus: &mut self.bus, time_s: request.time_s };
        match &request.call {
            PlatformCall::Initialize { mission, seed } => {
                if (mission.as_str(), *seed) != (self.mission.as_str(), self.seed) {
                    return Err(ComponentFault(format!(
                        "the simulator runs mission `{}` with seed {}, the rover `{mission}` with seed {seed}",
                        self.mission, self.seed
                    )));
                }
                self.platform.initialize(&mut ctx)?;
            }
            PlatformCall::Step => self.platform.step(&mut ctx)?,
            PlatformCall::Idle(state) => self.platform.idle(&mut ctx, *state)?,
            PlatformCall::Finish { .. } => {}
        }
        for e in self.platform.take_executed() {
            self.cycles += 1;
            self.judge.record(&e);
        }
        let mut outputs = Vec::new();
        for record in self.bus.take_tap(self.tap)? {
            if record.topic == topics::PLATFORM_FRAME.name() {
                outputs.push(PlatformOutput::Frame(decode(&topics::PLATFORM_FRAME, &record.payload)?));
            } else if record.topic == topics::TASK_STATUS.name() {
                outputs.push(PlatformOutput::Status(decode(&topics::TASK_STATUS, &record.payload)?));
            }
        }
        Ok(outputs)
    }

    fn score(&mut self, goal: Point2, estimate: Pose3) -> Scoring {
        self.world.goal.position = goal;
        let mut scoring = self.judge.judge(&self.world, self.platform.sim(), estimate).into_scoring();
        scoring.injected_faults =
            crate::run_loop::fault_reports(self.platform.injected_faults(), scoring.hazard_contacts);
        scoring
    }
}

/// A link to a server in the same process, through JSON as a network link would carry it.
pub struct LocalLink {
    server: PlatformServer,
}

impl LocalLink {
    /// Wraps a server.
    pub fn new(server: PlatformServer) -> Self {
        Self { server }
    }
}

impl PlatformLink for LocalLink {
    fn exchange(&mut self, request: &PlatformRequest) -> Result<PlatformReply, LinkError> {
        let request = decode(&PLATFORM_REQUEST, &encode(&PLATFORM_REQUEST, request)?)?;
        let reply = self.server.handle(&request);
        Ok(decode(&PLATFORM_REPLY, &encode(&PLATFORM_REPLY, &reply)?)?)
    }
}

/// A link to no simulator: every exchange fails. For assembling a remote run that never steps
/// (printing its component graph).
pub struct NoLink;

impl PlatformLink for NoLink {
    fn exchange(&mut self, _request: &PlatformRequest) -> Result<PlatformReply, LinkError> {
        Err(LinkError("no simulator is connected".into()))
    }
}

/// The platform's stand-in in the rover process: forwards every call over a [`PlatformLink`].
pub struct RemotePlatform {
    link: Box<dyn PlatformLink>,
    mission: String,
    seed: u64,
    commands: Option<Subscriber<MotionRequest>>,
    holds: Option<Subscriber<HoldMsg>>,
    ride_along: Option<Subscriber<RideAlongMsg>>,
    /// Ride-along requests taken from the bus, not sent yet.
    ride_queue: Vec<RideAlongMsg>,
    seq: u64,
    sim_time_s: f64,
    initialized: bool,
    executed: Vec<FrameMsg>,
}

impl RemotePlatform {
    /// A stand-in for the platform of a mission (name and seed are checked by the server).
    pub fn new(link: Box<dyn PlatformLink>, mission: &str, seed: u64) -> Self {
        Self {
            link,
            mission: mission.to_string(),
            seed,
            commands: None,
            holds: None,
            ride_along: None,
            ride_queue: Vec::new(),
            seq: 0,
            sim_time_s: 0.0,
            initialized: false,
            executed: Vec::new(),
        }
    }

    /// The simulated clock as of the last reply (s).
    pub fn sim_time(&self) -> f64 {
        self.sim_time_s
    }

    /// Takes the frames of the commands executed since the last call, in order.
    pub fn take_executed(&mut self) -> Vec<FrameMsg> {
        std::mem::take(&mut self.executed)
    }

    /// Asks the server to score the ended mission.
    pub fn finish(&mut self, goal: Point2, estimate: Pose3) -> Result<Scoring, LinkError> {
        let call = PlatformCall::Finish { goal: [goal.x, goal.y], estimate };
        let reply = self.exchange(call, self.sim_time_s, Vec::new(), Vec::new())?;
        reply.scoring.ok_or_else(|| LinkError("the simulator answered `finish` without a scoring".into()))
    }

    fn exchange(
        &mut self,
        call: PlatformCall,
        time_s: f64,
        commands: Vec<MotionRequest>,
        holds: Vec<HoldMsg>,
    ) -> Result<PlatformReply, LinkError> {
        self.seq += 1;
        let ride_along = std::mem::take(&mut self.ride_queue);
        let request = PlatformRequest { seq: self.seq, time_s, call, commands, holds, ride_along };
        let reply = self.link.exchange(&request)?;
        if reply.seq != request.seq {
            return Err(LinkError(format!("reply {} to request {}", reply.seq, request.seq)));
        }
        self.sim_time_s = reply.sim_time_s;
        Ok(reply)
    }

    /// Forwards one call with the queued inputs and publishes what the simulator published.
    fn forward(&mut self, ctx: &mut Ctx<'_>, call: PlatformCall) -> Result<(), ComponentFault> {
        let commands: Vec<MotionRequest> = match &self.commands {
            Some(s) => ctx.bus.take(s)?.iter().map(|c| (**c).clone()).collect(),
            None => Vec::new(),
        };
        let holds: Vec<HoldMsg> = match &self.holds {
            Some(s) => ctx.bus.take(s)?.iter().map(|h| **h).collect(),
            None => Vec::new(),
        };
        if let Some(s) = &self.ride_along {
            self.ride_queue.extend(ctx.bus.take(s)?.iter().map(|r| **r));
        }
        // With nothing queued and the clock not past the simulator's, the platform would do
        // nothing (no hold, no command): spare the round trip.
        let nothing_to_do = commands.is_empty()
            && holds.is_empty()
            && self.ride_queue.is_empty()
            && ctx.time_s <= self.sim_time_s;
        if self.initialized && !matches!(call, PlatformCall::Initialize { .. }) && nothing_to_do {
            return Ok(());
        }
        let reply =
            self.exchange(call, ctx.time_s, commands, holds).map_err(|e| ComponentFault(e.to_string()))?;
        for output in reply.outputs {
            match output {
                PlatformOutput::Frame(frame) => {
                    if frame.request().is_some() {
                        self.executed.push(frame.clone());
                    }
                    ctx.bus.publish(topics::PLATFORM_FRAME, frame)?;
                }
                PlatformOutput::Status(status) => ctx.bus.publish(topics::TASK_STATUS, status)?,
            }
        }
        match reply.fault {
            Some(why) => Err(ComponentFault(why)),
            None => Ok(()),
        }
    }
}

impl Component for RemotePlatform {
    /// The platform's name, so reports and fault protection see the same component.
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

    fn initialize(&mut self, ctx: &mut Ctx<'_>) -> Result<(), ComponentFault> {
        let call = PlatformCall::Initialize { mission: self.mission.clone(), seed: self.seed };
        self.forward(ctx, call)?;
        self.initialized = true;
        Ok(())
    }

    fn step(&mut self, ctx: &mut Ctx<'_>) -> Result<(), ComponentFault> {
        self.forward(ctx, PlatformCall::Step)
    }

    fn idle(&mut self, ctx: &mut Ctx<'_>, state: JausState) -> Result<(), ComponentFault> {
        self.forward(ctx, PlatformCall::Idle(state))
    }
}
