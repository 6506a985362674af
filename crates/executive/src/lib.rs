//! The executive: missions, MRPTA's three layers wired on a message bus, and the run report.
//!
//! Paper 004 section 2: a deliberative layer ([`deliberative`]: the mission plan, operator
//! commands, [`fault_protection`]) presents commands to a reflexive layer of JAUS components
//! ([`components`], hosted by the [`runtime`]: the navigator, pose estimator and motion
//! controller of [`reflexive`], the [`sensor_servers`]) above a platform layer ([`platform`]:
//! the simulated rover and its tooling arm). They exchange the [`messages`] on a
//! `rovernav_bus::Bus`; [`run`] assembles a run and scores it. The autonomy only ever sees sensor
//! messages; ground truth stays inside the simulator and is used solely to score the run.

pub mod camera_server;
pub mod command_language;
pub mod components;
pub mod deliberative;
pub mod fault_protection;
pub mod horizon;
pub mod messages;
pub mod mission;
pub mod operator;
pub mod platform;
pub mod reflexive;
pub mod remote;
pub mod report;
pub mod run;
pub mod runtime;
pub mod sensor_servers;
pub mod world;

pub use command_language::{CommandError, OperatorCommand, help_text, parse_command};
pub use components::{Component, ComponentFault, JausState};
pub use mission::{Mission, MissionError};
pub use operator::{OperatorLink, ScriptedOperator};
pub use report::{
    ComponentReport, FaultReport, HazardEvent, LocalizationStats, Report, StageTimes, TaskReport,
};
pub use run::{
    BusKind, CycleRecord, NoObserver, Progress, RunError, RunObserver, RunOptions, RunOutput, RunSettings,
    Trace, run_mission, run_mission_observed, run_mission_with, run_world, run_world_observed,
    run_world_with,
};
pub use world::{World, WorldError, build_world, long_yard_world};
