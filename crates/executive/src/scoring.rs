//! Judging a run against simulator truth: the true track, the cells the range data covered,
//! the hazard events and the report's truth-based figures.
//!
//! One [`Scorer`] watches the commands the simulated platform executes, wherever that platform
//! runs: inside the run's own process (the loop of [`crate::run_loop`] feeds it) or in the
//! simulator process of a two-process run (the [`crate::remote::PlatformServer`] feeds it and
//! sends the resulting [`Scoring`] across the link). The autonomy never sees any of it.

use crate::platform::Executed;
use crate::report::HazardEvent;
use crate::world::World;
use rovernav_core::{Grid2, GridGeometry, Point2, Pose3};
use rovernav_sim::Simulator;

pub use crate::remote::Scoring;

/// What the judge saw of a run: the figures, the true track and the sensed cells.
pub struct Judgement {
    /// The truth-based figures (its `truth` and `sensed` lists are empty in process: the track
    /// and the grid are below, unconverted).
    pub scoring: Scoring,
    /// True pose at the start and after every command.
    pub truth: Vec<Pose3>,
    /// Cells covered by range data (placed with the true pose: display only).
    pub sensed: Grid2<bool>,
}

/// Records truth as commands execute and scores the run at its end.
pub struct Scorer {
    truth: Vec<Pose3>,
    sensed: Grid2<bool>,
    hazard_events: Vec<HazardEvent>,
    last_hazards: u32,
    cycles: u64,
}

impl Scorer {
    /// A scorer for a world whose rover truly starts at `start` (the simulator's first truth).
    pub fn new(world: &World, start: Pose3) -> Self {
        Self {
            truth: vec![start],
            sensed: sensed_grid(world),
            hazard_events: Vec::new(),
            last_hazards: 0,
            cycles: 0,
        }
    }

    /// Records one executed command: the sensed cells, a new hazard contact, the true pose.
    pub fn record(&mut self, e: &Executed) {
        self.cycles += 1;
        for cloud in &e.frame.clouds {
            mark_sensed(&mut self.sensed, &e.truth, cloud);
        }
        if e.hazard_contacts > self.last_hazards {
            self.last_hazards = e.hazard_contacts;
            self.hazard_events.push(HazardEvent {
                x: e.truth.x,
                y: e.truth.y,
                cycle: self.cycles,
                cause: e.frame.motion_stopped.clone().unwrap_or_default(),
            });
        }
        self.truth.push(e.truth);
    }

    /// Commands recorded so far.
    pub fn cycles(&self) -> u64 {
        self.cycles
    }

    /// The figures of the ended run in a `world` whose goal is the one the mission ended with (an
    /// operator may have moved it), for the rover's final `estimate`; the track and sensed lists
    /// are left empty.
    pub fn figures(&self, world: &World, sim: &Simulator, estimate: Pose3) -> Scoring {
        let truth = sim.truth();
        let goal = world.goal.position;
        Scoring {
            goal_error_m: Point2::new(truth.x, truth.y).dist(goal),
            distance_driven_m: sim.distance_driven(),
            optimal_length_m: crate::world::optimal_length(world),
            hazard_contacts: sim.hazard_contacts(),
            sim_time_s: sim.time(),
            sensing_actions: sim.sensing_actions(),
            localization_error_m: (truth.x - estimate.x).hypot(truth.y - estimate.y),
            straight_line_m: world.start.position().dist(goal),
            hazard_events: self.hazard_events.clone(),
            cycles: self.cycles,
            truth: Vec::new(),
            sensed: Vec::new(),
            injected_faults: Vec::new(),
        }
    }

    /// The judgement in process: the figures with the track and grid as recorded.
    pub fn judge(self, world: &World, sim: &Simulator, estimate: Pose3) -> Judgement {
        let scoring = self.figures(world, sim, estimate);
        Judgement { scoring, truth: self.truth, sensed: self.sensed }
    }

    /// The scoring to send across a link: the figures with the track and sensed cells as lists.
    pub fn scoring(&self, world: &World, sim: &Simulator, estimate: Pose3) -> Scoring {
        let mut sensed = Vec::new();
        let g = self.sensed.geometry;
        for r in 0..g.rows {
            for c in 0..g.cols {
                if *self.sensed.get(c, r) {
                    sensed.push([c as u32, r as u32]);
                }
            }
        }
        Scoring { truth: self.truth.clone(), sensed, ..self.figures(world, sim, estimate) }
    }
}

impl Judgement {
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

/// The grid of cells the range data covered, at the DEM's resolution (at least 0.1 m).
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

/// Marks the cells a cloud's points fall in (display only, so true placement is fine).
pub fn mark_sensed(sensed: &mut Grid2<bool>, truth: &Pose3, cloud: &rovernav_core::PointCloud) {
    for p in &cloud.points {
        let w = truth.transform([p[0] as f64, p[1] as f64, p[2] as f64]);
        if let Some((c, r)) = sensed.geometry.cell_of(w[0], w[1]) {
            *sensed.get_mut(c, r) = true;
        }
    }
}
