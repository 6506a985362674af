//! Runs the harness judges: a mission file's run ([`JudgedRun::mission`]), any run given the
//! harness's judge ([`JudgedRun::judged`]) and the simulator process of a two-process run
//! ([`platform_server`]).
//!
//! The executive's [`Run`] builds and drives a run in a world it is given and asks a
//! [`rovernav_executive::judge::Judge`] for the figures; these entry points build the world
//! from the mission ([`crate::world`]) and give it the [`Scorer`].

use crate::scoring::Scorer;
use crate::world::{build_world, tiled_source};
use rovernav_bus::BusError;
use rovernav_executive::platform::ScheduledFault;
use rovernav_executive::remote::PlatformServer;
use rovernav_executive::{Mission, Progress, Run, RunError, RunOptions, RunOutput, RunSettings, World};

/// The harness's constructors on [`Run`]: `use rovernav_harness::JudgedRun;` and
/// `Run::mission(&mission, origin)?.execute()` runs a mission file, judged.
pub trait JudgedRun<'a>: Sized {
    /// A mission file's run: its world (with the mission's lander station, if any), settings,
    /// tasks and scheduled faults, judged by a [`Scorer`]. `origin` names the mission source in error messages.
    fn mission(mission: &Mission, origin: &str) -> Result<Run<'a>, RunError>;
    /// The same run, judged by a [`Scorer`] (in process; a remote run's judge is the
    /// simulator process's).
    fn judged(self) -> Self;
}

impl<'a> JudgedRun<'a> for Run<'a> {
    fn mission(mission: &Mission, origin: &str) -> Result<Run<'a>, RunError> {
        let world = build_world(mission, origin)?;
        let options = mission_options(mission, &world);
        Ok(Run::new(world, RunSettings::of(mission)).options(options).origin(origin).judged())
    }

    fn judged(self) -> Self {
        self.judge(Box::new(Scorer::new()))
    }
}

/// The tasks, faults and tiled terrain of a mission file in its `world`: the executive's
/// [`RunOptions::of`] plus the simulator's window onto a tiled terrain.
pub fn mission_options(mission: &Mission, world: &World) -> RunOptions {
    RunOptions { tiles: tiled_source(mission), ..RunOptions::of(mission, world) }
}

/// Runs a mission to completion with a progress callback: `Run::mission(mission, origin)`,
/// `.progress(on_progress).execute()`.
pub fn run_mission(
    mission: &Mission,
    origin: &str,
    on_progress: &mut dyn FnMut(&Progress),
) -> Result<RunOutput, RunError> {
    Run::mission(mission, origin)?.progress(on_progress).execute()
}

/// The simulator process's side of a two-process run: a platform server for `world` with the
/// mission's name, seed and scheduled faults, judged by a [`Scorer`].
pub fn platform_server(
    world: World,
    mission: &str,
    seed: u64,
    faults: Vec<ScheduledFault>,
) -> Result<PlatformServer, BusError> {
    PlatformServer::new(world, mission, seed, faults, Box::new(Scorer::new()))
}
