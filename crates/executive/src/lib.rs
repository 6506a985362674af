//! The executive: missions, the navigation loop that ties the autonomy to the platform, and the
//! run report.
//!
//! The loop is the deliberative layer's simplest form (paper 004 section 2): it builds the world
//! the mission names, starts the chosen navigator and localiser, and relays commands and sensor
//! frames between them and the platform until the navigator finishes or a limit is hit. The
//! autonomy only ever sees `SensorFrame`s; ground truth stays inside the simulator and is used
//! here solely to score the run.

pub mod command_language;
pub mod mission;
pub mod report;
pub mod run;
pub mod world;

pub use command_language::OperatorCommand;
pub use mission::{Mission, MissionError};
pub use report::{HazardEvent, Report, StageTimes};
pub use run::{
    CycleRecord, NoObserver, Progress, RunError, RunObserver, RunOutput, RunSettings, Trace, run_mission,
    run_mission_observed, run_world, run_world_observed,
};
pub use world::{World, WorldError, build_world, long_yard_world};
