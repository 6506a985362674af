//! What a run publishes on the Foxglove topics, cycle by cycle: the recorder hands it what the
//! loop reports and writes what it returns.
//!
//! Per cycle: both rover frames, the scene (the body always; the plan, the wedges and the
//! navigator's drawings when they changed), the belief grids when new range data changed them,
//! a log line for the command. Truth goes only to the truth topics (`/sim/tf`, `/sim/scene`).

use super::grid::BeliefMap;
use super::scene::{
    LinePrimitive, SceneEntity, SceneUpdateMsg, colors, goal_entity, overlay_entities, rock_entity,
    rover_body, wedge_entity,
};
use super::{FrameTransformMsg, LogMsg, PoseMsg, Vector3, level, topics};
use rovernav_bus::Record;
use rovernav_core::{NavCommand, Overlay, Point2, Pose3, PoseEstimate, RoverConfig};
use rovernav_executive::messages::{ComponentStatusMsg, TaskStatusMsg};
use rovernav_executive::{CycleRecord, Report, RunSettings, Trace, World};
use serde::Serialize;

/// One message for a Foxglove topic, already JSON.
#[derive(Clone, Debug, PartialEq)]
pub struct Out {
    /// The topic ([`topics`]).
    pub topic: &'static str,
    /// The message.
    pub json: Vec<u8>,
}

fn out<T: Serialize>(topic: &'static str, msg: &T) -> Out {
    // The messages are plain structs of numbers and strings: serializing cannot fail.
    Out { topic, json: serde_json::to_vec(msg).unwrap_or_default() }
}

/// The state the Foxglove topics are published from (see the module documentation).
pub struct FoxglovePublisher {
    rover: RoverConfig,
    belief: BeliefMap,
    last_plan: Vec<Point2>,
    last_overlays: Option<Vec<Overlay>>,
    hazards: u32,
}

impl FoxglovePublisher {
    /// Starts publishing a run: the messages of its start (frames, bodies, goal, rocks, a log
    /// line naming the mission).
    pub fn start(
        world: &World,
        settings: &RunSettings,
        t: f64,
        estimate: &PoseEstimate,
        truth: &Pose3,
    ) -> (Self, Vec<Out>) {
        let publisher = Self {
            rover: world.rover.clone(),
            belief: BeliefMap::new(world),
            last_plan: Vec::new(),
            last_overlays: None,
            hazards: 0,
        };
        let z = estimate.pose.z;
        let mut scene = vec![
            rover_body(t, topics::ROVER_FRAME, &world.rover, colors::ROVER),
            goal_entity(t, topics::MAP_FRAME, world.goal.position, world.goal.tolerance, z),
        ];
        let keep_out =
            world.goal.keep_out.iter().map(|p| LinePrimitive::through(p, z, true, 0.06, colors::HAZARD));
        scene.push(SceneEntity {
            lines: keep_out.collect(),
            ..SceneEntity::new(t, topics::MAP_FRAME, "keep_out")
        });
        let dem = &world.terrain.dem;
        let ground = |x: f64, y: f64| dem.height(x, y).filter(|h| h.is_finite()).unwrap_or(0.0);
        let truth_scene = vec![
            rover_body(t, topics::TRUTH_FRAME, &world.rover, colors::TRUTH),
            rock_entity(t, topics::MAP_FRAME, &world.terrain.rocks, ground),
        ];
        let line = format!(
            "mission {}: navigator {}, localizer {}, seed {}; goal ({:.2}, {:.2}) within {:.2} m",
            settings.name,
            settings.navigator,
            settings.localizer,
            settings.seed,
            world.goal.position.x,
            world.goal.position.y,
            world.goal.tolerance
        );
        let outs = vec![
            out(topics::TF, &FrameTransformMsg::of_pose(t, topics::ROVER_FRAME, &estimate.pose)),
            out(topics::TRUTH_TF, &FrameTransformMsg::of_pose(t, topics::TRUTH_FRAME, truth)),
            out(topics::SCENE, &SceneUpdateMsg { deletions: Vec::new(), entities: scene }),
            out(topics::TRUTH_SCENE, &SceneUpdateMsg { deletions: Vec::new(), entities: truth_scene }),
            out(topics::LOG, &LogMsg::new(t, level::INFO, "executive", line)),
        ];
        (publisher, outs)
    }

    /// The messages of one cycle.
    pub fn cycle(&mut self, r: &CycleRecord<'_>) -> Vec<Out> {
        let t = r.sim_time_s;
        let mut outs = vec![
            out(topics::TF, &FrameTransformMsg::of_pose(t, topics::ROVER_FRAME, &r.estimate.pose)),
            out(topics::TRUTH_TF, &FrameTransformMsg::of_pose(t, topics::TRUTH_FRAME, r.truth)),
        ];
        let z = r.estimate.pose.z + 0.02;
        let mut entities = vec![rover_body(t, topics::ROVER_FRAME, &self.rover, colors::ROVER)];
        if r.plan != self.last_plan.as_slice() {
            self.last_plan = r.plan.to_vec();
            let line = LinePrimitive::through(r.plan, z, false, 0.05, colors::PLAN);
            entities
                .push(SceneEntity { lines: vec![line], ..SceneEntity::new(t, topics::MAP_FRAME, "plan") });
        }
        if !r.frame.clouds.is_empty() {
            entities.push(wedge_entity(t, topics::ROVER_FRAME, &r.frame.clouds));
        }
        entities.extend(self.overlays_if_changed(t, r.overlays, z));
        outs.push(out(topics::SCENE, &SceneUpdateMsg { deletions: Vec::new(), entities }));
        let mut truth_entities = vec![rover_body(t, topics::TRUTH_FRAME, &self.rover, colors::TRUTH)];
        if r.hazard_contacts > self.hazards {
            self.hazards = r.hazard_contacts;
            truth_entities.push(hazard_marker(t, r.hazard_contacts, r.truth));
        }
        outs.push(out(
            topics::TRUTH_SCENE,
            &SceneUpdateMsg { deletions: Vec::new(), entities: truth_entities },
        ));
        if self.belief.ingest(&r.frame.clouds, r.estimate)
            && let Some((elevation, traversability)) = self.belief.grids(t, topics::MAP_FRAME)
        {
            outs.push(out(topics::BELIEF_GRID, &elevation));
            outs.push(out(topics::TRAVERSABILITY_GRID, &traversability));
        }
        let line = format!("cycle {}: {}", r.cycle, describe(r.command));
        outs.push(out(topics::LOG, &LogMsg::new(t, level::INFO, "navigator", line)));
        if let Some(why) = &r.frame.motion_stopped {
            outs.push(out(
                topics::LOG,
                &LogMsg::new(t, level::WARNING, "platform", format!("motion stopped: {why}")),
            ));
        }
        outs
    }

    /// The navigator's drawings when they differ from the last ones published.
    fn overlays_if_changed(&mut self, t: f64, overlays: &[Overlay], z: f64) -> Vec<SceneEntity> {
        if self.last_overlays.as_deref() == Some(overlays) {
            return Vec::new();
        }
        self.last_overlays = Some(overlays.to_vec());
        overlay_entities(t, topics::MAP_FRAME, overlays, z)
    }

    /// Log lines for the bus messages an operator wants to read: operator lines and answers,
    /// component states, task states.
    pub fn bus(&mut self, record: &Record) -> Option<Out> {
        let t = record.time_s;
        let line = match record.topic.as_str() {
            "/operator/command" => {
                let text: String = serde_json::from_slice(&record.payload).ok()?;
                LogMsg::new(t, level::INFO, "operator", format!("> {text}"))
            }
            "/operator/reply" => {
                let text: String = serde_json::from_slice(&record.payload).ok()?;
                LogMsg::new(t, level::INFO, "executive", text)
            }
            "/system/status" => {
                let s: ComponentStatusMsg = serde_json::from_slice(&record.payload).ok()?;
                let bad = matches!(
                    s.state,
                    rovernav_executive::JausState::Failure | rovernav_executive::JausState::Emergency
                );
                let lvl = if bad { level::ERROR } else { level::DEBUG };
                LogMsg::new(t, lvl, &s.component, format!("{:?}: {}", s.state, s.message))
            }
            "/executive/task_status" => {
                let s: TaskStatusMsg = serde_json::from_slice(&record.payload).ok()?;
                let outcome = s.outcome.map(|o| format!(" ({o})")).unwrap_or_default();
                LogMsg::new(
                    t,
                    level::INFO,
                    &s.component,
                    format!("task {} {:?}{outcome}: {}", s.task, s.state, s.message),
                )
            }
            _ => return None,
        };
        Some(out(topics::LOG, &line))
    }

    /// The messages of the end: the navigator's final drawings (when they changed) and the
    /// outcome.
    pub fn finish(&mut self, report: &Report, trace: &Trace) -> Vec<Out> {
        let t = report.sim_time_s;
        let z = trace.estimate.last().map_or(0.0, |p| p.z) + 0.02;
        let mut outs = Vec::new();
        let entities = self.overlays_if_changed(t, &trace.overlays, z);
        if !entities.is_empty() {
            outs.push(out(topics::SCENE, &SceneUpdateMsg { deletions: Vec::new(), entities }));
        }
        let lvl = if report.outcome == "reached" { level::INFO } else { level::ERROR };
        let line = format!("{}: {}", report.outcome, report.message);
        outs.push(out(topics::LOG, &LogMsg::new(t, lvl, "executive", line)));
        outs
    }
}

/// A hazard contact of the true rover: a red column where it happened (truth).
fn hazard_marker(t: f64, n: u32, truth: &Pose3) -> SceneEntity {
    let cube = super::scene::CubePrimitive {
        pose: PoseMsg::at(truth.x, truth.y, truth.z + 0.5),
        size: Vector3 { x: 0.2, y: 0.2, z: 1.0 },
        color: colors::HAZARD,
    };
    SceneEntity { cubes: vec![cube], ..SceneEntity::new(t, topics::MAP_FRAME, &format!("hazard/{n}")) }
}

/// A command in words.
pub fn describe(c: &NavCommand) -> String {
    match c {
        NavCommand::Sense(views) => format!("sense ({} views)", views.len()),
        NavCommand::Drive { distance, curvature, .. } => {
            format!("drive {distance:.2} m at curvature {curvature:.3} 1/m")
        }
        NavCommand::Turn { angle } => format!("turn {:.1} deg", angle.to_degrees()),
        NavCommand::Finish(outcome, why) => format!("finish: {} ({why})", outcome.as_str()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rovernav_core::{DriveGuard, Outcome};

    #[test]
    fn commands_read_as_words() {
        let drive = NavCommand::Drive { distance: 0.5, curvature: 0.0, guard: DriveGuard::default() };
        assert_eq!(describe(&drive), "drive 0.50 m at curvature 0.000 1/m");
        assert_eq!(describe(&NavCommand::Turn { angle: -std::f64::consts::FRAC_PI_2 }), "turn -90.0 deg");
        assert_eq!(describe(&NavCommand::Finish(Outcome::Reached, "ok".into())), "finish: reached (ok)");
    }
}
