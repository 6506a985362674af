//! Judging a run against simulator truth: the true track, the cells the range data covered,
//! the hazard contacts and the report's truth-based figures.
//!
//! A [`Scorer`] is the harness's [`Judge`]: the executive's run loop feeds it every command the
//! simulated platform executes, in process ([`crate::JudgedRun::judged`]) or in the simulator
//! process of a two-process run ([`crate::platform_server`]), and asks it for the
//! [`Judgement`] once the mission has ended. The autonomy never sees any of it.

use rovernav_core::{Grid2, Point2, Pose3};
use rovernav_executive::judge::{Judge, Judgement, Scoring, sensed_grid};
use rovernav_executive::platform::Executed;
use rovernav_executive::{HazardEvent, World};
use rovernav_sim::Simulator;

/// Records truth as commands execute and scores the run at its end.
#[derive(Default)]
pub struct Scorer {
    truth: Vec<Pose3>,
    sensed: Option<Grid2<bool>>,
    hazard_events: Vec<HazardEvent>,
    last_hazards: u32,
    cycles: u64,
}

impl Scorer {
    /// A scorer waiting for its run to start.
    pub fn new() -> Self {
        Self::default()
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
            optimal_length_m: crate::optimal::optimal_length(world),
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
}

impl Judge for Scorer {
    fn start(&mut self, world: &World, start: Pose3) {
        *self = Self { truth: vec![start], sensed: Some(sensed_grid(world)), ..Self::default() };
    }

    fn record(&mut self, e: &Executed) {
        self.cycles += 1;
        if let Some(sensed) = self.sensed.as_mut() {
            for cloud in &e.frame.clouds {
                mark_sensed(sensed, &e.truth, cloud);
            }
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

    fn judge(&mut self, world: &World, sim: &Simulator, estimate: Pose3) -> Judgement {
        let scoring = self.figures(world, sim, estimate);
        let sensed = self.sensed.take().unwrap_or_else(|| sensed_grid(world));
        Judgement { scoring, truth: std::mem::take(&mut self.truth), sensed }
    }
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
