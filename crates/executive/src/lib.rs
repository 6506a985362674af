//! The executive: missions, MRPTA's three layers wired on a message bus, and the run report.
//!
//! Paper 004 section 2: a deliberative layer ([`deliberative`]: the mission plan, operator
//! commands, [`fault_protection`]) presents commands to a reflexive layer of JAUS components
//! ([`components`], hosted by the [`runtime`]: the navigator, pose estimator and motion
//! controller of [`reflexive`], the [`sensor_servers`]) above a platform layer ([`platform`]:
//! the simulated rover and its tooling arm). They exchange the [`messages`] on a
//! `rovernav_bus::Bus`; [`graph`] lists the components a run hosts and in which order a step
//! visits them, [`run`] configures a run ([`Run`]) and its loop drives it, in process or against
//! a [`remote`] platform, and [`scoring`] judges it against simulator truth. The autonomy only ever sees sensor
//! messages; ground truth stays inside the simulator and is used solely to score the run.

pub mod arm_server;
pub mod camera_server;
pub mod command_language;
pub mod components;
pub mod deliberative;
pub mod fault_protection;
pub mod graph;
pub mod horizon;
pub mod messages;
pub mod mission;
pub mod operator;
pub mod orbital_prior;
pub mod platform;
pub mod power;
pub mod reflexive;
pub mod remote;
pub mod report;
pub mod run;
mod run_loop;
pub mod runtime;
pub mod scoring;
pub mod sensor_servers;
pub mod shadow;
pub mod world;

pub use command_language::{CommandError, OperatorCommand, help_text, parse_command};
pub use components::{Component, ComponentFault, JausState};
pub use graph::Graph;
pub use mission::{Mission, MissionError};
pub use operator::{OperatorLink, ScriptedOperator};
pub use report::{
    ComponentReport, FaultReport, HazardEvent, LocalizationStats, PlacementReport, Report, StageTimes,
    TaskReport,
};
pub use run::{
    BusKind, CycleRecord, NoObserver, Progress, Run, RunError, RunObserver, RunOptions, RunOutput,
    RunSettings, Trace, run_mission,
};
pub use world::{World, WorldError, build_world, long_yard_world};
