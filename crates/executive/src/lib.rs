//! The executive: missions, MRPTA's three layers wired on a message bus, and the run report.
//!
//! Paper 004 section 2: a deliberative layer ([`deliberative`]: the mission plan, operator
//! commands, [`fault_protection`]) presents commands to a reflexive layer of JAUS components
//! ([`components`], hosted by the [`runtime`]: the navigator, pose estimator and motion
//! controller of [`reflexive`], the [`sensor_servers`]) above a platform layer ([`platform`]:
//! the simulated rover and its tooling arm). They exchange the [`messages`] on a
//! `rovernav_bus::Bus`; [`graph`] lists the components a run hosts and in which order a step
//! visits them, [`run`] configures a run ([`Run`]) in a [`world`] it is given and its loop drives
//! it, in process or against a [`remote`] platform. The executive is what would fly: it does
//! not judge itself. Building the world from a mission file and judging the run against
//! simulator truth are the harness's (`rovernav_harness`), which the loop sees through the small
//! [`judge::Judge`] trait. The autonomy only ever sees sensor messages; ground truth stays inside
//! the simulator and is used solely to score the run.

pub mod arm_server;
pub mod camera_server;
pub mod command_language;
pub mod components;
pub mod deliberative;
pub mod fault_protection;
pub mod graph;
pub mod judge;
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
    RunSettings, Trace,
};
pub use world::{World, WorldError};
