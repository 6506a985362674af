//! The harness: what only the simulation knows, and the judging of a run against it.
//!
//! The executive (`rovernav_executive`) is what would fly: it is given a world and drives the
//! simulated rover through the same interfaces a real one would have. The harness builds that
//! world from a mission file ([`world`]: the true terrain, rover, sensors, start and goal),
//! plans the optimal safe path with full knowledge of it ([`optimal`]), records the true track,
//! the sensed cells and the hazard contacts and scores the run ([`scoring`]: the [`Scorer`], the
//! executive's [`rovernav_executive::judge::Judge`]), and runs the sensing-horizon reference
//! ([`horizon`]). [`run`] gives the judged entry points: [`JudgedRun::mission`] (so
//! `Run::mission(&mission, origin)` keeps working with the trait in scope), [`JudgedRun::judged`]
//! and [`platform_server`] for the simulator process of a two-process run.
//!
//! The harness depends on the executive, never the other way round.

pub mod horizon;
pub mod optimal;
pub mod run;
pub mod scoring;
pub mod world;

pub use optimal::{OPTIMAL_PATH_RESOLUTION, optimal_length, optimal_length_on, true_hazard};
pub use rovernav_executive::{World, WorldError};
pub use run::{JudgedRun, mission_options, platform_server, run_mission};
pub use scoring::{Scorer, mark_sensed};
pub use world::{build_world, long_yard_world, rover_config, tiled_source, tiled_source_of};
