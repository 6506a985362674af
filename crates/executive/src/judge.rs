//! The seam to the judge: what the run's loop tells whoever scores it, and what it gets back.
//!
//! The executive is what would fly; it does not judge itself. A [`Judge`] (the harness's
//! `rovernav_harness::Scorer`, given to a run with [`crate::Run::judge`]) watches the commands
//! the simulated platform executes and, once the mission has ended, returns a [`Judgement`]:
//! the truth-based figures ([`Scoring`]), the true track and the cells the range data covered.
//! In process the loop of [`crate::run_loop`] feeds the judge; in a two-process run the
//! simulator process's [`crate::remote::PlatformServer`] feeds its own judge and sends the
//! judgement across the link as a [`Scoring`] with the track and cells as lists
//! ([`Judgement::into_scoring`]), which the rover process decodes ([`Judgement::received`]).
//! The autonomy never sees any of it.

use crate::platform::Executed;
use crate::world::World;
use rovernav_core::{Grid2, GridGeometry, Pose3};
use rovernav_sim::Simulator;

pub use crate::remote::Scoring;

/// Judges a run against simulator truth: told every executed command, asked once at the end.
pub trait Judge: Send {
    /// The run begins in `world` with the rover truly at `start` (the simulator's first truth).
    fn start(&mut self, world: &World, start: Pose3);
    /// One command the simulated platform executed, with the truth after it.
    fn record(&mut self, executed: &Executed);
    /// The judgement of the ended run in a `world` whose goal is the one the mission ended with
    /// (an operator may have moved it), for the rover's final `estimate`.
    fn judge(&mut self, world: &World, sim: &Simulator, estimate: Pose3) -> Judgement;
}

/// What the judge saw of a run: the figures, the true track and the sensed cells.
pub struct Judgement {
    /// The truth-based figures (its `truth` and `sensed` lists are empty: the track and the
    /// grid are below, unconverted).
    pub scoring: Scoring,
    /// True pose at the start and after every command.
    pub truth: Vec<Pose3>,
    /// Cells covered by range data (placed with the true pose: display only), on
    /// [`sensed_grid`]'s geometry.
    pub sensed: Grid2<bool>,
}

impl Judgement {
    /// The scoring to send across a link: the figures with the track and sensed cells as lists.
    pub fn into_scoring(self) -> Scoring {
        let mut sensed = Vec::new();
        let g = self.sensed.geometry;
        for r in 0..g.rows {
            for c in 0..g.cols {
                if *self.sensed.get(c, r) {
                    sensed.push([c as u32, r as u32]);
                }
            }
        }
        Scoring { truth: self.truth, sensed, ..self.scoring }
    }

    /// The judgement a scoring received across a link carries (track and cells decoded).
    pub fn received(world: &World, mut scoring: Scoring) -> Self {
        let truth = std::mem::take(&mut scoring.truth);
        let mut sensed = sensed_grid(world);
        for [c, r] in &scoring.sensed {
            let (c, r) = (*c as usize, *r as usize);
            if c < sensed.geometry.cols && r < sensed.geometry.rows {
                *sensed.get_mut(c, r) = true;
            }
        }
        scoring.sensed.clear();
        Self { scoring, truth, sensed }
    }
}

/// The grid of cells the range data covered, empty: the DEM's extent at its resolution, 0.1 m at
/// finest (the shape both ends of a link and the telemetry reader agree on).
pub fn sensed_grid(world: &World) -> Grid2<bool> {
    let dem_geometry = *world.terrain.dem.geometry();
    let res = dem_geometry.resolution.max(0.1);
    let geometry = GridGeometry {
        cols: (dem_geometry.width_m() / res).ceil() as usize,
        rows: (dem_geometry.height_m() / res).ceil() as usize,
        resolution: res,
        ..dem_geometry
    };
    Grid2::filled(geometry, false)
}
