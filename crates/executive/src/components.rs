//! Reflexive-layer components: the JAUS state machine and the one trait every component meets.
//!
//! Paper 004 section 2: every module of the reflexive layer is a JAUS component, "a state machine
//! with 6 standard JAUS states: Initialization, Standby, Ready, Emergency, Failure and
//! Shutdown", that "operates at a specified frequency (the default is 10 Hz)"; "state transitions
//! are initiated by internal logic or by external messages", and components "collaborate by
//! exchanging well-defined messages". Here a component declares its typed input and output
//! topics, the runtime ([`crate::runtime`]) owns its state and steps it at its rate on simulated
//! time, and the state commands travel on the bus as [`ControlMsg`](crate::messages::ControlMsg).

use crate::messages::ControlAction;
use rovernav_bus::{Bus, BusError, Topic};
use serde::{Deserialize, Serialize};
use std::any::Any;

/// The default component rate (Hz), paper 004 section 2.
pub const DEFAULT_RATE_HZ: f64 = 10.0;

/// The six JAUS component states.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, schemars::JsonSchema)]
pub enum JausState {
    /// Starting up: subscribing, loading, taking first data.
    Initialization,
    /// Initialized and idle: not acting until resumed.
    Standby,
    /// Working.
    Ready,
    /// Emergency stop: no actuation until the emergency is cleared.
    Emergency,
    /// An internal fault: the component cannot do its job until reset.
    Failure,
    /// Shut down for good.
    Shutdown,
}

impl JausState {
    /// The state after a control command, or `None` when the command does not apply here (a
    /// failed or shut-down component ignores an emergency stop: it is already not acting).
    pub fn after(self, action: ControlAction) -> Option<JausState> {
        use ControlAction as A;
        use JausState as S;
        match (self, action) {
            (S::Shutdown, _) => None,
            (_, A::Shutdown) => Some(S::Shutdown),
            (S::Failure, A::Reset) => Some(S::Initialization),
            (S::Failure, _) => None,
            (_, A::EmergencyStop) if self != S::Emergency => Some(S::Emergency),
            (S::Emergency, A::ClearEmergency) => Some(S::Standby),
            (S::Standby, A::Resume) => Some(S::Ready),
            (S::Ready, A::Standby) => Some(S::Standby),
            _ => None,
        }
    }

    /// A stable name.
    pub fn as_str(self) -> &'static str {
        match self {
            JausState::Initialization => "Initialization",
            JausState::Standby => "Standby",
            JausState::Ready => "Ready",
            JausState::Emergency => "Emergency",
            JausState::Failure => "Failure",
            JausState::Shutdown => "Shutdown",
        }
    }
}

impl std::fmt::Display for JausState {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// One typed port of a component: a topic name and its message type.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Port {
    /// Topic name.
    pub topic: &'static str,
    /// Message type name.
    pub type_name: &'static str,
}

impl Port {
    /// The port of a typed topic.
    pub fn of<T>(topic: Topic<T>) -> Self {
        Self { topic: topic.name(), type_name: topic.type_name() }
    }
}

/// A component's declared inputs and outputs.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Ports {
    /// Topics it reads.
    pub inputs: Vec<Port>,
    /// Topics it publishes.
    pub outputs: Vec<Port>,
}

/// A fault a component found in itself or in its data; the runtime moves it to Failure.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct ComponentFault(pub String);

impl From<BusError> for ComponentFault {
    fn from(e: BusError) -> Self {
        ComponentFault(format!("bus: {e}"))
    }
}

/// What a component sees when it runs.
pub struct Ctx<'a> {
    /// The message bus.
    pub bus: &'a mut Bus,
    /// Simulated time at the start of the runtime tick (s).
    pub time_s: f64,
}

/// A reflexive-layer (or platform-layer) component.
///
/// The runtime calls `connect` when the component is added (subscribe there, so that no message
/// published later is missed), `initialize` in Initialization (Ok moves the component to Standby,
/// an error to Failure), `step` at the component's rate while Ready, and `idle` at the same rate
/// in Standby and Emergency so that a standing-by component drops or keeps its inputs
/// deliberately rather than finding them stale on resume. A returned fault moves it to Failure.
pub trait Component: Any + Send {
    /// Unique name (`platform`, `pose-estimator`...).
    fn name(&self) -> &'static str;
    /// Stepping rate (Hz).
    fn rate_hz(&self) -> f64 {
        DEFAULT_RATE_HZ
    }
    /// Declared typed inputs and outputs.
    fn ports(&self) -> Ports;
    /// Subscribes to the inputs.
    fn connect(&mut self, bus: &mut Bus) -> Result<(), BusError>;
    /// Prepares; may publish first data (the platform's initial frame).
    fn initialize(&mut self, _ctx: &mut Ctx<'_>) -> Result<(), ComponentFault> {
        Ok(())
    }
    /// One cycle of work while Ready.
    fn step(&mut self, ctx: &mut Ctx<'_>) -> Result<(), ComponentFault>;
    /// One cycle while Standby or Emergency (default: nothing; queued inputs wait).
    fn idle(&mut self, _ctx: &mut Ctx<'_>, _state: JausState) -> Result<(), ComponentFault> {
        Ok(())
    }
    /// Called after every state change, with the bus to report what the change did.
    fn on_transition(
        &mut self,
        _ctx: &mut Ctx<'_>,
        _from: JausState,
        _to: JausState,
    ) -> Result<(), ComponentFault> {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ControlAction as A;
    use JausState as S;

    const STATES: [JausState; 6] =
        [S::Initialization, S::Standby, S::Ready, S::Emergency, S::Failure, S::Shutdown];
    const ACTIONS: [ControlAction; 6] =
        [A::Resume, A::Standby, A::EmergencyStop, A::ClearEmergency, A::Reset, A::Shutdown];

    /// The JAUS reference architecture's transitions, written out as a table.
    fn expected(s: JausState, a: ControlAction) -> Option<JausState> {
        let table: &[(JausState, ControlAction, JausState)] = &[
            (S::Initialization, A::EmergencyStop, S::Emergency),
            (S::Initialization, A::Shutdown, S::Shutdown),
            (S::Standby, A::Resume, S::Ready),
            (S::Standby, A::EmergencyStop, S::Emergency),
            (S::Standby, A::Shutdown, S::Shutdown),
            (S::Ready, A::Standby, S::Standby),
            (S::Ready, A::EmergencyStop, S::Emergency),
            (S::Ready, A::Shutdown, S::Shutdown),
            (S::Emergency, A::ClearEmergency, S::Standby),
            (S::Emergency, A::Shutdown, S::Shutdown),
            (S::Failure, A::Reset, S::Initialization),
            (S::Failure, A::Shutdown, S::Shutdown),
        ];
        table.iter().find(|(from, action, _)| *from == s && *action == a).map(|t| t.2)
    }

    #[test]
    fn transitions_match_the_jaus_table_for_every_pair() {
        for s in STATES {
            for a in ACTIONS {
                assert_eq!(s.after(a), expected(s, a), "{s:?} + {a:?}");
            }
        }
    }

    #[test]
    fn emergency_reaches_every_live_state_and_ready_needs_standby_first() {
        for s in [S::Initialization, S::Standby, S::Ready] {
            assert_eq!(s.after(A::EmergencyStop), Some(S::Emergency));
        }
        assert_eq!(S::Emergency.after(A::Resume), None, "clear the emergency before resuming");
        assert_eq!(S::Emergency.after(A::ClearEmergency).and_then(|s| s.after(A::Resume)), Some(S::Ready));
    }
}
