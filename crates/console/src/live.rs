//! The console's run: a mission executed on the calling thread, its telemetry log teed into the
//! hub, its operator the console, paced against the wall clock.
//!
//! A mission held for the operator (`rovernav serve` without a mission file, or `--wait`) shows
//! its world first and starts when the mission planner sends a plan (goal, waypoints, keep-out
//! zones); otherwise it starts at once.

use crate::hub::Hub;
use crate::operator::{ConsoleLink, Phase, Plan};
use rovernav_core::Point2;
use rovernav_executive::{Mission, Progress, Run, RunOutput, RunSettings, World};
use rovernav_harness::{JudgedRun, build_world, mission_options};
use rovernav_telemetry::TelemetryRecorder;
use rovernav_telemetry::messages::{WorldMsg, topics};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// How a console run goes.
#[derive(Clone, Debug)]
pub struct LiveRun {
    /// The mission (its goal is replaced by the operator's plan when held).
    pub mission: Mission,
    /// Where the mission came from, for error messages.
    pub origin: String,
    /// Wait for a plan from the mission planner before starting.
    pub hold: bool,
    /// Simulated seconds per wall-clock second; `None` runs as fast as possible.
    pub speed: Option<f64>,
    /// The telemetry log to write (`telemetry.mcap`).
    pub log: PathBuf,
}

/// Paces simulated time against the wall clock.
pub struct Pacer {
    speed: f64,
    /// A wall-clock instant and the simulated time it stands for.
    anchor: (Instant, f64),
}

/// How far the wall clock may run ahead of paced simulated time (a pause, slow computing) before
/// pacing restarts from now instead of letting the simulation catch up in a burst.
const PACE_SLACK: Duration = Duration::from_millis(250);

impl Pacer {
    /// Pacing `speed` simulated seconds per wall-clock second from now, at simulated time 0.
    pub fn new(speed: f64) -> Self {
        Self { speed, anchor: (Instant::now(), 0.0) }
    }

    /// Sleeps until the wall clock reaches simulated time `t`.
    pub fn pace(&mut self, t: f64) {
        let (wall, sim) = self.anchor;
        let due = wall + Duration::from_secs_f64(((t - sim) / self.speed).clamp(0.0, 1e6));
        let now = Instant::now();
        if now > due + PACE_SLACK {
            self.anchor = (now, t);
        } else if due > now {
            std::thread::sleep(due - now);
        }
    }
}

/// The terrain's extent, [x0, y0, x1, y1] in the local frame.
pub fn terrain_area(world: &World) -> [f64; 4] {
    let g = world.terrain.dem.geometry();
    [g.origin_x, g.origin_y, g.origin_x + g.width_m(), g.origin_y + g.height_m()]
}

/// Shows the world in the hub and waits for a plan that fits it; gives the world with that goal.
fn wait_for_plan(mut world: World, hub: &Hub, link: &ConsoleLink) -> World {
    let (_, name, schema, _) = rovernav_telemetry::topic_table()
        .into_iter()
        .find(|row| row.0 == topics::WORLD)
        .expect("the world topic is in the table");
    hub.declare(topics::WORLD, name, &schema);
    if let Ok(json) = serde_json::to_vec(&WorldMsg::of(&world)) {
        hub.publish(topics::WORLD, 0, &json);
    }
    let console = link.console();
    console.set_phase(Phase::Waiting);
    let area = terrain_area(&world);
    loop {
        let Ok(plan) = link.plans.recv() else { return world };
        match plan.check(area) {
            Ok(()) => {
                apply_plan(&mut world, &plan);
                return world;
            }
            Err(why) => {
                if let Some(holder) = console.holder() {
                    console.refuse(holder, &format!("plan refused: {why}"));
                }
            }
        }
    }
}

/// The world with the plan's goal, waypoints and keep-out zones.
fn apply_plan(world: &mut World, plan: &Plan) {
    fn point(p: &[f64; 2]) -> Point2 {
        Point2::new(p[0], p[1])
    }
    world.goal.position = point(&plan.goal);
    world.goal.waypoints = plan.waypoints.iter().map(point).collect();
    world.goal.keep_out = plan.keep_out.iter().map(|z| z.iter().map(point).collect()).collect();
}

/// Runs the mission with the console as its operator and the hub watching its log; returns what
/// the run produced (the caller writes the report and pictures). The console's phase ends
/// `Done(outcome)`, or `Done("failed")` when the run could not run.
pub fn run(config: &LiveRun, hub: &Arc<Hub>, mut link: ConsoleLink) -> Result<RunOutput, String> {
    let console = Arc::clone(link.console());
    let result = run_inner(config, hub, &mut link);
    let outcome = match &result {
        Ok(output) => output.report.outcome.clone(),
        Err(_) => "failed".to_string(),
    };
    console.set_phase(Phase::Done(outcome));
    result
}

fn run_inner(config: &LiveRun, hub: &Arc<Hub>, link: &mut ConsoleLink) -> Result<RunOutput, String> {
    let mission = &config.mission;
    let mut world = build_world(mission, &config.origin).map_err(|e| e.to_string())?;
    if config.hold {
        world = wait_for_plan(world, hub, link);
    }
    let options = mission_options(mission, &world);
    let run = Run::new(world, RunSettings::of(mission)).judged().options(options).origin(&config.origin);
    let mut recorder =
        TelemetryRecorder::create_with_tee(&config.log, hub.sink()).map_err(|e| e.to_string())?;
    link.console().set_phase(Phase::Running);
    let mut pacer = config.speed.map(Pacer::new);
    let mut pace = |p: &Progress| {
        if let Some(pacer) = pacer.as_mut() {
            pacer.pace(p.sim_time_s);
        }
    };
    let output = run.observer(&mut recorder).operator(link).progress(&mut pace).execute();
    let logged = recorder.finish();
    let output = output.map_err(|e| e.to_string())?;
    logged.map_err(|e| format!("{}: telemetry log: {e}", config.log.display()))?;
    Ok(output)
}
