//! The component runtime: owns the components' JAUS states and steps them on simulated time.
//!
//! The runtime keeps the clock of the reflexive layer: a tick happens at the platform's time or,
//! when the platform has not acted since the last tick, one base period (the fastest component's)
//! later; the platform then rests, sampling, until that time. Simulated time thus always moves
//! (a paused mission still sees its sensors sampled at the component rate) without adding a
//! single rest sample to a run whose platform acts every tick.
//!
//! One [`Runtime::tick`] visits the components in the order they were added (the data-flow order:
//! navigator, motion controller, platform, sensor servers, pose estimator...). Before each
//! component it applies the state commands that have arrived on `/system/control`, so an
//! emergency stop published by the deliberative layer reaches every component before any of them
//! acts again; then it steps the component if its period has elapsed. Messages are delivered as
//! they are published, so a command issued by the navigator is executed by the platform and
//! integrated by the pose estimator within the same tick, as in the stop-and-go loop of a
//! planetary rover. Nothing here depends on wall-clock time: a run is deterministic for a seed.

use crate::components::{Component, ComponentFault, Ctx, DEFAULT_RATE_HZ, JausState, Port, Ports};
use crate::messages::{ComponentStatusMsg, ControlAction, ControlMsg, topics};
use rovernav_bus::{Bus, BusError, Subscriber};
use std::any::Any;
use std::collections::BTreeSet;
use std::time::{Duration, Instant};

/// Tolerance on the due time, so that float sums of sample periods never skip a step (s).
const DUE_EPSILON_S: f64 = 1e-9;

/// Why the runtime could not be assembled or run.
#[derive(Debug, thiserror::Error)]
pub enum RuntimeError {
    /// Two components with one name.
    #[error("component `{0}` added twice")]
    Duplicate(&'static str),
    /// An input nobody publishes.
    #[error("component `{component}` reads `{topic}` ({type_name}) but nothing publishes it")]
    Unconnected {
        /// Reader.
        component: &'static str,
        /// Topic.
        topic: &'static str,
        /// Type.
        type_name: &'static str,
    },
    /// One topic declared with two types.
    #[error("topic `{topic}` is declared as both {a} and {b}")]
    TypeClash {
        /// Topic.
        topic: &'static str,
        /// One type.
        a: &'static str,
        /// The other.
        b: &'static str,
    },
    /// A graph entry built a component with another name.
    #[error("the graph's entry `{entry}` built a component named `{built}`")]
    Misnamed {
        /// The entry's name.
        entry: &'static str,
        /// The built component's name.
        built: &'static str,
    },
    /// A graph entry could not build its component.
    #[error("component `{entry}`: {message}")]
    Build {
        /// The entry's name.
        entry: &'static str,
        /// Why.
        message: String,
    },
    /// The bus cannot deliver within a tick.
    #[error("the lockstep runtime needs a synchronous transport")]
    Asynchronous,
    /// A bus operation of the runtime itself failed.
    #[error(transparent)]
    Bus(#[from] BusError),
}

/// A component with the state the runtime keeps for it.
struct Slot {
    component: Box<dyn Component>,
    rate_hz: f64,
    state: JausState,
    message: String,
    next_due: f64,
    busy: Duration,
    /// A crash injected for a fault drill: the component's next run panics.
    crash_pending: bool,
}

/// A component's name, state and the reason of its last change.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ComponentState {
    /// Name.
    pub name: &'static str,
    /// JAUS state.
    pub state: JausState,
    /// Reason of the last change (the fault, for Failure).
    pub message: String,
}

/// The scheduler and state keeper of the reflexive and platform layers.
pub struct Runtime {
    bus: Bus,
    slots: Vec<Slot>,
    control: Subscriber<ControlMsg>,
    clock: f64,
}

impl Runtime {
    /// A runtime over a bus; the bus must deliver synchronously.
    pub fn new(mut bus: Bus) -> Result<Self, RuntimeError> {
        if !bus.is_synchronous() {
            return Err(RuntimeError::Asynchronous);
        }
        let control = bus.subscribe(topics::SYSTEM_CONTROL)?;
        Ok(Self { bus, slots: Vec::new(), control, clock: f64::NEG_INFINITY })
    }

    /// Adds a component (in Initialization) after those already added and connects it; it
    /// steps at its own rate ([`Component::rate_hz`]).
    pub fn add(&mut self, component: Box<dyn Component>) -> Result<(), RuntimeError> {
        let rate_hz = component.rate_hz();
        self.add_at(component, rate_hz)
    }

    /// [`Runtime::add`] at a given rate (Hz): the component graph's ([`crate::graph`]).
    pub fn add_at(&mut self, mut component: Box<dyn Component>, rate_hz: f64) -> Result<(), RuntimeError> {
        let name = component.name();
        if self.slots.iter().any(|s| s.component.name() == name) {
            return Err(RuntimeError::Duplicate(name));
        }
        component.connect(&mut self.bus)?;
        self.slots.push(Slot {
            component,
            rate_hz,
            state: JausState::Initialization,
            message: "created".into(),
            next_due: f64::NEG_INFINITY,
            busy: Duration::ZERO,
            crash_pending: false,
        });
        Ok(())
    }

    /// Checks the wiring: every input is published by a component or by `external` (the
    /// deliberative layer, the operator), and no topic has two types.
    pub fn validate(&self, external: &[Port]) -> Result<(), RuntimeError> {
        let mut published: BTreeSet<Port> = external.iter().copied().collect();
        for slot in &self.slots {
            published.extend(slot.component.ports().outputs);
        }
        let mut all: Vec<Port> = published.iter().copied().collect();
        for slot in &self.slots {
            all.extend(slot.component.ports().inputs);
        }
        for a in &all {
            if let Some(b) = all.iter().find(|b| b.topic == a.topic && b.type_name != a.type_name) {
                return Err(RuntimeError::TypeClash { topic: a.topic, a: a.type_name, b: b.type_name });
            }
        }
        for slot in &self.slots {
            for input in slot.component.ports().inputs {
                if !published.contains(&input) {
                    return Err(RuntimeError::Unconnected {
                        component: slot.component.name(),
                        topic: input.topic,
                        type_name: input.type_name,
                    });
                }
            }
        }
        Ok(())
    }

    /// The bus.
    pub fn bus(&mut self) -> &mut Bus {
        &mut self.bus
    }

    /// Publishes a state command for one component (`Some(name)`) or all (`None`); it takes
    /// effect at the next component the runtime visits.
    pub fn command(&mut self, target: Option<&str>, action: ControlAction) -> Result<(), BusError> {
        self.bus.publish(topics::SYSTEM_CONTROL, ControlMsg { target: target.map(str::to_string), action })
    }

    /// Initializes every component in Initialization, in order (a component may read what an
    /// earlier one published while initializing, as the pose estimator reads the initial frame).
    pub fn initialize(&mut self, time_s: f64) -> Result<(), RuntimeError> {
        self.clock = time_s;
        self.bus.set_time(time_s);
        for i in 0..self.slots.len() {
            self.apply_control(time_s)?;
            if self.slots[i].state == JausState::Initialization {
                self.run(i, time_s)?;
            }
        }
        self.apply_control(time_s)
    }

    /// Applies the state commands that have arrived without stepping anyone (the last word of
    /// a finished mission).
    pub fn settle(&mut self, time_s: f64) -> Result<(), RuntimeError> {
        self.apply_control(time_s)
    }

    /// The time of the last tick (s).
    pub fn clock(&self) -> f64 {
        self.clock
    }

    /// The shortest component period (s): how far the clock moves in a tick where the platform
    /// did not act.
    pub fn base_period(&self) -> f64 {
        let fastest = self.slots.iter().map(|s| s.rate_hz).fold(DEFAULT_RATE_HZ, f64::max);
        1.0 / fastest
    }

    /// Steps every due component once, in order, at the platform's time `platform_time_s` or
    /// one base period after the last tick, whichever is later; returns the tick's time.
    pub fn tick(&mut self, platform_time_s: f64) -> Result<f64, RuntimeError> {
        let earliest = self.clock + self.base_period();
        let time_s = if platform_time_s + DUE_EPSILON_S >= earliest || !earliest.is_finite() {
            platform_time_s
        } else {
            earliest
        };
        self.clock = time_s;
        self.bus.set_time(time_s);
        for i in 0..self.slots.len() {
            self.apply_control(time_s)?;
            let slot = &mut self.slots[i];
            if time_s + DUE_EPSILON_S < slot.next_due {
                continue;
            }
            slot.next_due = time_s + 1.0 / slot.rate_hz.max(1e-6);
            self.run(i, time_s)?;
        }
        self.apply_control(time_s)?;
        Ok(time_s)
    }

    /// Runs component `i` once according to its state.
    fn run(&mut self, i: usize, time_s: f64) -> Result<(), RuntimeError> {
        let slot = &mut self.slots[i];
        let mut ctx = Ctx { bus: &mut self.bus, time_s };
        let started = Instant::now();
        let (state, crash) = (slot.state, std::mem::take(&mut slot.crash_pending));
        let live = !matches!(state, JausState::Failure | JausState::Shutdown);
        let component = &mut slot.component;
        // A component that panics has crashed: it goes to Failure like one that reports a
        // fault, and the rest of the rover carries on (fault protection then stops it safely).
        let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            if crash && live {
                // `resume_unwind` unwinds without the panic hook's message: a drill, not a bug.
                std::panic::resume_unwind(Box::new("injected crash"));
            }
            match state {
                JausState::Initialization => component.initialize(&mut ctx).map(|()| true),
                JausState::Ready => component.step(&mut ctx).map(|()| false),
                JausState::Standby | JausState::Emergency => component.idle(&mut ctx, state).map(|()| false),
                JausState::Failure | JausState::Shutdown => Ok(false),
            }
        }))
        .unwrap_or_else(|panic| {
            let what = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".into());
            Err(ComponentFault(format!("crashed: {what}")))
        });
        slot.busy += started.elapsed();
        match result {
            Ok(true) => self.set_state(i, JausState::Standby, "initialized".into(), time_s),
            Ok(false) => Ok(()),
            Err(ComponentFault(why)) => self.set_state(i, JausState::Failure, why, time_s),
        }
    }

    /// Applies the state commands that have arrived.
    fn apply_control(&mut self, time_s: f64) -> Result<(), RuntimeError> {
        for msg in self.bus.take(&self.control)? {
            for i in 0..self.slots.len() {
                let slot = &self.slots[i];
                if msg.target.as_deref().is_some_and(|t| t != slot.component.name()) {
                    continue;
                }
                if let Some(next) = slot.state.after(msg.action) {
                    self.set_state(i, next, format!("{:?} command", msg.action), time_s)?;
                }
            }
        }
        Ok(())
    }

    /// Changes a component's state, tells the component and publishes the new status.
    fn set_state(&mut self, i: usize, to: JausState, why: String, time_s: f64) -> Result<(), RuntimeError> {
        let slot = &mut self.slots[i];
        let from = slot.state;
        slot.state = to;
        slot.message = why;
        if to == JausState::Initialization {
            slot.next_due = f64::NEG_INFINITY;
        }
        let mut ctx = Ctx { bus: &mut self.bus, time_s };
        if let Err(ComponentFault(fault)) = slot.component.on_transition(&mut ctx, from, to)
            && to != JausState::Failure
        {
            slot.state = JausState::Failure;
            slot.message = fault;
        }
        let status = ComponentStatusMsg {
            component: slot.component.name().to_string(),
            state: slot.state,
            message: slot.message.clone(),
            time_s,
        };
        self.bus.publish(topics::SYSTEM_STATUS, status)?;
        Ok(())
    }

    /// Makes the named component crash (panic) the next time it runs, for fault drills; false
    /// when no component has that name.
    pub fn inject_crash(&mut self, name: &str) -> bool {
        match self.slots.iter_mut().find(|s| s.component.name() == name) {
            Some(slot) => {
                slot.crash_pending = true;
                true
            }
            None => false,
        }
    }

    /// Every component's state, in stepping order.
    pub fn states(&self) -> Vec<ComponentState> {
        self.slots
            .iter()
            .map(|s| ComponentState { name: s.component.name(), state: s.state, message: s.message.clone() })
            .collect()
    }

    /// Every component's name, rate (Hz) and declared ports, in stepping order.
    pub fn nodes(&self) -> Vec<(&'static str, f64, Ports)> {
        self.slots.iter().map(|s| (s.component.name(), s.rate_hz, s.component.ports())).collect()
    }

    /// One component's state.
    pub fn state(&self, name: &str) -> Option<JausState> {
        self.slots.iter().find(|s| s.component.name() == name).map(|s| s.state)
    }

    /// Wall-clock time spent in one component so far (s).
    pub fn busy_s(&self, name: &str) -> f64 {
        self.slots.iter().filter(|s| s.component.name() == name).map(|s| s.busy.as_secs_f64()).sum()
    }

    /// The first component of a concrete type.
    pub fn get<T: Component>(&self) -> Option<&T> {
        self.slots.iter().find_map(|s| (&*s.component as &dyn Any).downcast_ref::<T>())
    }

    /// The first component of a concrete type, mutably.
    pub fn get_mut<T: Component>(&mut self) -> Option<&mut T> {
        self.slots.iter_mut().find_map(|s| (&mut *s.component as &mut dyn Any).downcast_mut::<T>())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rovernav_bus::Topic;

    const NUMBERS: Topic<u64> = Topic::new("/test/numbers");

    /// Publishes a counter on every step.
    struct Source {
        rate: f64,
        next: u64,
    }

    impl Component for Source {
        fn name(&self) -> &'static str {
            "source"
        }
        fn rate_hz(&self) -> f64 {
            self.rate
        }
        fn ports(&self) -> Ports {
            Ports { inputs: vec![], outputs: vec![Port::of(NUMBERS)] }
        }
        fn connect(&mut self, _bus: &mut Bus) -> Result<(), BusError> {
            Ok(())
        }
        fn step(&mut self, ctx: &mut Ctx<'_>) -> Result<(), ComponentFault> {
            self.next += 1;
            Ok(ctx.bus.publish(NUMBERS, self.next)?)
        }
    }

    /// Records what it reads; fails on the number it is told to.
    struct Sink {
        input: Option<Subscriber<u64>>,
        seen: Vec<u64>,
        fail_on: u64,
        idled: usize,
    }

    impl Component for Sink {
        fn name(&self) -> &'static str {
            "sink"
        }
        fn ports(&self) -> Ports {
            Ports { inputs: vec![Port::of(NUMBERS)], outputs: vec![] }
        }
        fn connect(&mut self, bus: &mut Bus) -> Result<(), BusError> {
            self.input = Some(bus.subscribe(NUMBERS)?);
            Ok(())
        }
        fn step(&mut self, ctx: &mut Ctx<'_>) -> Result<(), ComponentFault> {
            let input = self.input.as_ref().ok_or_else(|| ComponentFault("not initialized".into()))?;
            for n in ctx.bus.take(input)? {
                self.seen.push(*n);
                if *n == self.fail_on {
                    return Err(ComponentFault(format!("read the bad number {n}")));
                }
            }
            Ok(())
        }
        fn idle(&mut self, _ctx: &mut Ctx<'_>, _state: JausState) -> Result<(), ComponentFault> {
            self.idled += 1;
            Ok(())
        }
    }

    fn runtime(rate: f64, fail_on: u64) -> Runtime {
        let mut rt = Runtime::new(Bus::in_process()).unwrap();
        rt.add(Box::new(Source { rate, next: 0 })).unwrap();
        rt.add(Box::new(Sink { input: None, seen: vec![], fail_on, idled: 0 })).unwrap();
        rt
    }

    #[test]
    fn components_initialize_to_standby_and_step_only_when_ready() {
        let mut rt = runtime(10.0, 0);
        rt.initialize(0.0).unwrap();
        assert!(rt.states().iter().all(|s| s.state == JausState::Standby));
        rt.tick(0.1).unwrap();
        assert!(rt.get::<Sink>().unwrap().seen.is_empty(), "standby components do not step");
        assert_eq!(rt.get::<Sink>().unwrap().idled, 1);
        rt.command(None, ControlAction::Resume).unwrap();
        rt.tick(0.2).unwrap();
        assert_eq!(rt.get::<Sink>().unwrap().seen, [1], "delivered within the tick it was published");
    }

    #[test]
    fn a_component_steps_at_its_rate_on_simulated_time() {
        let mut rt = runtime(2.0, 0);
        rt.initialize(0.0).unwrap();
        rt.command(None, ControlAction::Resume).unwrap();
        // Ticks every 0.1 s for 2 s: a 2 Hz source steps at 0, 0.5, 1.0 and 1.5 s.
        for k in 0..20 {
            rt.tick(k as f64 * 0.1).unwrap();
        }
        assert_eq!(rt.get::<Sink>().unwrap().seen, [1, 2, 3, 4]);
    }

    #[test]
    fn a_fault_moves_the_component_to_failure_with_its_message_on_the_bus() {
        let mut rt = runtime(10.0, 2);
        let status = rt.bus().subscribe(topics::SYSTEM_STATUS).unwrap();
        rt.initialize(0.0).unwrap();
        rt.command(None, ControlAction::Resume).unwrap();
        for k in 1..=4 {
            rt.tick(k as f64 * 0.1).unwrap();
        }
        assert_eq!(rt.state("sink"), Some(JausState::Failure));
        assert_eq!(rt.state("source"), Some(JausState::Ready));
        assert_eq!(rt.get::<Sink>().unwrap().seen, [1, 2], "a failed component stops stepping");
        let failure = rt.bus().take(&status).unwrap().into_iter().find(|s| s.state == JausState::Failure);
        let failure = failure.expect("failure status published");
        assert_eq!(failure.component, "sink");
        assert!(failure.message.contains("bad number 2"), "{}", failure.message);
        // An emergency stop does not hide the failure; a reset re-initializes.
        rt.command(None, ControlAction::EmergencyStop).unwrap();
        rt.tick(0.5).unwrap();
        assert_eq!(rt.state("sink"), Some(JausState::Failure));
        assert_eq!(rt.state("source"), Some(JausState::Emergency));
        rt.command(Some("sink"), ControlAction::Reset).unwrap();
        rt.tick(0.6).unwrap();
        assert_eq!(rt.state("sink"), Some(JausState::Standby));
    }

    #[test]
    fn wiring_is_validated() {
        let mut rt = Runtime::new(Bus::in_process()).unwrap();
        rt.add(Box::new(Sink { input: None, seen: vec![], fail_on: 0, idled: 0 })).unwrap();
        let err = rt.validate(&[]).unwrap_err().to_string();
        assert!(err.contains("sink") && err.contains("/test/numbers"), "{err}");
        assert!(rt.validate(&[Port::of(NUMBERS)]).is_ok());
        let clash: Topic<String> = Topic::new("/test/numbers");
        assert!(matches!(
            rt.validate(&[Port::of(NUMBERS), Port::of(clash)]),
            Err(RuntimeError::TypeClash { .. })
        ));
        assert!(matches!(
            rt.add(Box::new(Sink { input: None, seen: vec![], fail_on: 0, idled: 0 })),
            Err(RuntimeError::Duplicate("sink"))
        ));
    }
}
