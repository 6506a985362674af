//! NaT, navigation templates (paper 001 section 4, after Slack's thesis): the rover's
//! instantaneous heading and speed come from the composition of spun potential fields placed
//! on every sensed obstacle plus an attraction to the goal.
//!
//! A plain repulsive field around an obstacle cancels the goal attraction in front of it (a
//! local minimum). NaT spins each obstacle's field: near the obstacle the push turns into a
//! flow around it, clockwise or counter-clockwise. The spin of each obstacle is chosen once,
//! when the obstacle is first met, so that the flow passes it on the side nearer the line to
//! the goal, and neighbouring obstacle cells inherit the spin of the cluster they join, so that
//! a whole cluster is circled one way instead of trapping the rover between opposed flows.
//!
//! Obstacles come from the stereo range data (the cells of the terrain model that are hazards
//! grown by the rover size) and from keep-out zones. The commanded motion is checked against
//! the map before it is driven; a heading that would enter a hazard or unsensed ground is
//! rotated further in the spin direction until safe.

use crate::gestalt::{arc_pose, keep_out_distance};
use crate::params::{Field, Param, Unit, map_params, turn_threshold_param};
use crate::registry::{NavigatorEntry, param_info};
use crate::terrain_model::TerrainModel;
use rovernav_core::{
    DriveGuard, GridGeometry, NavCommand, NavInput, Navigator, NavigatorStats, Outcome, Overlay, Point2,
    Pose2, RoverConfig, SenseRequest, angle_diff,
};
use std::collections::HashMap;

/// Tunable parameters of NaT.
#[derive(Clone, Debug)]
pub struct NatConfig {
    /// Longest distance driven per cycle (m).
    pub step: f64,
    /// Distance within which an obstacle's field acts (m).
    pub influence: f64,
    /// Strength of the obstacle fields relative to the unit goal attraction.
    pub gain: f64,
    /// Distance at which an obstacle's field is fully spun (tangential) (m).
    pub spin_distance: f64,
    /// Cells of the same spin cluster lie within this distance (m).
    pub cluster_distance: f64,
    /// Heading error beyond which the rover turns in place first (rad).
    pub turn_threshold: f64,
    /// Map cell size (m).
    pub map_resolution: f64,
    /// Map margin around the start-goal box (m).
    pub map_margin: f64,
    /// Extra clearance added to the rover radius when growing hazards (m).
    pub safety_buffer: f64,
    /// Mast pan angles (rad, body frame).
    pub mast_fan: Vec<f64>,
    /// Cycles without getting 0.25 m closer to the goal before asking for help.
    pub patience: u32,
}

impl NatConfig {
    /// The parameters a mission file may set (`[navigator_params]`).
    pub fn params() -> Vec<Param<Self>> {
        use Unit::*;
        let mut params: Vec<Param<Self>> = vec![
            Param {
                name: "step_m",
                doc: "longest distance driven per cycle",
                unit: PositiveMetres,
                field: |c| Field::Real(&mut c.step),
            },
            Param {
                name: "influence_m",
                doc: "distance within which an obstacle's field acts",
                unit: Metres,
                field: |c| Field::Real(&mut c.influence),
            },
            Param {
                name: "gain",
                doc: "strength of the obstacle fields relative to the unit goal attraction",
                unit: Weight,
                field: |c| Field::Real(&mut c.gain),
            },
            Param {
                name: "spin_distance_m",
                doc: "distance at which an obstacle's field is fully spun (tangential)",
                unit: Metres,
                field: |c| Field::Real(&mut c.spin_distance),
            },
            Param {
                name: "cluster_distance_m",
                doc: "cells of the same spin cluster lie within this distance",
                unit: Metres,
                field: |c| Field::Real(&mut c.cluster_distance),
            },
            turn_threshold_param(|c| Field::Real(&mut c.turn_threshold)),
            Param {
                name: "patience",
                doc: "cycles without getting 0.25 m closer to the goal before asking for help",
                unit: Count,
                field: |c| Field::U32(&mut c.patience),
            },
        ];
        params.extend(map_params::<Self>(
            |c| Field::Real(&mut c.map_resolution),
            |c| Field::Real(&mut c.map_margin),
            |c| Field::Real(&mut c.safety_buffer),
        ));
        params
    }
}
impl Default for NatConfig {
    fn default() -> Self {
        Self {
            step: 0.6,
            influence: 1.5,
            gain: 1.5,
            spin_distance: 0.5,
            cluster_distance: 0.6,
            turn_threshold: 20f64.to_radians(),
            map_resolution: 0.1,
            map_margin: 10.0,
            safety_buffer: 0.05,
            mast_fan: vec![-0.7, 0.0, 0.7],
            patience: 80,
        }
    }
}

/// The NaT navigator (see the module documentation).
pub struct NatNavigator {
    rover: RoverConfig,
    config: NatConfig,
    terrain: Option<TerrainModel>,
    /// Spin (+1 counter-clockwise) chosen for each obstacle cell met.
    spins: HashMap<(i64, i64), f64>,
    need_sense: bool,
    best_distance: f64,
    cycles_without_progress: u32,
    backing_out: bool,
    /// Whether the last motion was a turn in place.
    turned: bool,
    stats: NavigatorStats,
}

impl NatNavigator {
    /// A navigator for a rover with the given parameters.
    pub fn new(rover: RoverConfig, config: NatConfig) -> Self {
        Self {
            rover,
            config,
            terrain: None,
            spins: HashMap::new(),
            need_sense: true,
            best_distance: f64::INFINITY,
            cycles_without_progress: 0,
            backing_out: false,
            turned: true,
            stats: NavigatorStats::default(),
        }
    }

    fn key(&self, p: Point2) -> (i64, i64) {
        let r = self.config.map_resolution;
        ((p.x / r).floor() as i64, (p.y / r).floor() as i64)
    }

    /// The spin of an obstacle cell: inherited from its cluster, or chosen so that the flow
    /// passes the obstacle on the side nearer the straight line to the goal.
    fn spin_of(&mut self, obstacle: Point2, here: Point2, goal: Point2) -> f64 {
        let key = self.key(obstacle);
        if let Some(&s) = self.spins.get(&key) {
            return s;
        }
        let reach = (self.config.cluster_distance / self.config.map_resolution).ceil() as i64;
        let mut inherited = None;
        'search: for dx in -reach..=reach {
            for dy in -reach..=reach {
                if let Some(&s) = self.spins.get(&(key.0 + dx, key.1 + dy)) {
                    inherited = Some(s);
                    break 'search;
                }
            }
        }
        let spin = inherited.unwrap_or_else(|| {
            // Obstacle left of the goal line: pass it on its right (goal-line) side, which is
            // circling it counter-clockwise.
            let side = goal.sub(here).cross(obstacle.sub(here));
            if side > 0.0 { 1.0 } else { -1.0 }
        });
        self.spins.insert(key, spin);
        spin
    }

    /// The field at the rover: goal attraction plus the spun obstacle fields. Returns the
    /// field vector and the dominant spin.
    fn field(&mut self, here: Point2, input: &NavInput<'_>) -> (Point2, f64) {
        let goal = input.goal.position;
        let to_goal = goal.sub(here);
        let mut total = to_goal.scale(1.0 / to_goal.norm().max(1e-9));
        let terrain = self.terrain.as_ref().expect("map initialised");
        let res = self.config.map_resolution;
        let reach = (self.config.influence / res).ceil() as i64;
        let mut obstacles = Vec::new();
        for i in -reach..=reach {
            for j in -reach..=reach {
                let p = Point2::new(here.x + i as f64 * res, here.y + j as f64 * res);
                let d = p.dist(here);
                if d > self.config.influence || d < 1e-6 {
                    continue;
                }
                if terrain.is_grown_hazard(p) || keep_out_distance(input.goal, p) < self.rover.radius() {
                    obstacles.push(p);
                }
            }
        }
        let weight_sum = obstacles.len().max(1) as f64;
        let mut dominant = (0.0, 1.0);
        for p in obstacles {
            let away = here.sub(p);
            let d = away.norm().max(0.05);
            let dir = away.scale(1.0 / d);
            // Strength falls to 0 at the edge of the influence zone.
            let strength = self.config.gain * (1.0 / d - 1.0 / self.config.influence).max(0.0);
            let spin = self.spin_of(p, here, goal);
            // Fully tangential within the spin distance, pure repulsion at the edge.
            let blend = ((self.config.influence - d) / (self.config.influence - self.config.spin_distance))
                .clamp(0.0, 1.0);
            let angle = spin * blend * std::f64::consts::FRAC_PI_2;
            let (s, c) = angle.sin_cos();
            let spun = Point2::new(c * dir.x - s * dir.y, s * dir.x + c * dir.y);
            // Normalise by the number of cells so large obstacles do not swamp the goal pull.
            total = total.add(spun.scale(strength * 10.0 / weight_sum.max(10.0)));
            if strength > dominant.0 {
                dominant = (strength, spin);
            }
        }
        (total, dominant.1)
    }

    /// Whether driving `distance` from `pose` at `curvature` stays in sensed, safe terrain.
    fn safe(&self, input: &NavInput<'_>, pose: Pose2, distance: f64, curvature: f64) -> bool {
        let terrain = self.terrain.as_ref().expect("map initialised");
        let here = pose.position();
        let n = (distance.abs() / 0.05).ceil().max(1.0) as usize;
        let blind = 0.5 * self.rover.length;
        // The cameras miss a band of ground just ahead of the body (see gestalt.rs).
        let unseen_band = blind + 0.3;
        (1..=n).all(|i| {
            let p = arc_pose(pose, curvature, distance * i as f64 / n as f64).position();
            let d = p.dist(here);
            (d < blind || !terrain.is_grown_hazard(p))
                && keep_out_distance(input.goal, p) >= self.rover.radius()
                && (d < unseen_band || terrain.world().is_sensed(p.x, p.y))
        })
    }

    /// Images the terrain: the front body pair and one mast wedge ahead after a drive, the
    /// whole mast fan after a turn (the view changed).
    fn sense(&mut self) -> NavCommand {
        let mut requests: Vec<SenseRequest> = if self.turned {
            self.config.mast_fan.iter().map(|&pan| SenseRequest::Mast { pan }).collect()
        } else {
            vec![SenseRequest::Mast { pan: 0.0 }]
        };
        requests.push(SenseRequest::BodyFront);
        self.stats.sensing_actions += requests.len() as u64;
        self.need_sense = false;
        NavCommand::Sense(requests)
    }
}

impl Navigator for NatNavigator {
    fn name(&self) -> &str {
        "nat"
    }

    fn step(&mut self, input: &NavInput<'_>) -> NavCommand {
        let est = input.estimate.pose;
        let pose = est.pose2();
        let here = pose.position();
        let goal = input.goal.position;
        if self.terrain.is_none() {
            let m = self.config.map_margin;
            let res = self.config.map_resolution;
            let (x0, y0) = (here.x.min(goal.x) - m, here.y.min(goal.y) - m);
            let geometry = GridGeometry {
                cols: ((here.x.max(goal.x) + m - x0) / res).ceil() as usize,
                rows: ((here.y.max(goal.y) + m - y0) / res).ceil() as usize,
                resolution: res,
                origin_x: x0,
                origin_y: y0,
            };
            self.terrain = Some(TerrainModel::with_hazard_height(
                &self.rover,
                geometry,
                self.config.safety_buffer,
                // Its arc evaluation treats every grown hazard as a wall, so the denser map of
                // top heights (tuned for the grid planners' graded costs) boxes it in.
                rovernav_perception::HazardHeight::Mean,
            ));
        }
        let d = here.dist(goal);
        if d <= input.goal.tolerance {
            return NavCommand::Finish(Outcome::Reached, format!("estimate within {d:.2} m of the goal"));
        }
        if let Some(why) = &input.frame.motion_stopped
            && why.starts_with("hazard")
            && !self.backing_out
        {
            let ahead = pose.transform(Point2::new(0.5 * self.rover.length, 0.0));
            self.terrain.as_mut().expect("map").mark_contact(ahead);
            self.backing_out = true;
            self.need_sense = true;
            return NavCommand::Drive { distance: -0.3, curvature: 0.0, guard: DriveGuard::default() };
        }
        self.backing_out = false;
        if self.need_sense {
            return self.sense();
        }
        if !input.frame.clouds.is_empty() {
            self.terrain.as_mut().expect("map").ingest(&input.frame.clouds, &input.estimate);
        }
        if d < self.best_distance - 0.25 {
            self.best_distance = d;
            self.cycles_without_progress = 0;
        } else {
            self.cycles_without_progress += 1;
            if self.cycles_without_progress > self.config.patience {
                return NavCommand::Finish(
                    Outcome::HelpRequested,
                    format!("no progress toward the goal in {} cycles", self.config.patience),
                );
            }
        }
        self.need_sense = true;
        self.stats.plans += 1;
        let command = self.decide(input, pose, d);
        self.turned = !matches!(command, NavCommand::Drive { .. });
        command
    }

    fn overlays(&self) -> Vec<Overlay> {
        self.terrain.as_ref().map(TerrainModel::overlays).unwrap_or_default()
    }

    fn stats(&self) -> NavigatorStats {
        self.stats.clone()
    }
}

impl NatNavigator {
    /// Heading and speed from the fields, checked against the map.
    fn decide(&mut self, input: &NavInput<'_>, pose: Pose2, d: f64) -> NavCommand {
        let here = pose.position();
        let (field, spin) = self.field(here, input);
        let magnitude = field.norm();
        // Speed follows the field magnitude: slow where fields oppose the goal pull.
        let distance = (self.config.step * magnitude.clamp(0.3, 1.0)).min(d);
        let desired = field.angle();
        // Try the field heading first, then headings rotated away from the obstacle (against
        // the direction the spun flow turns toward it).
        for k in 0..12 {
            let heading = desired - spin * k as f64 * 15f64.to_radians();
            let error = angle_diff(heading, pose.yaw);
            let turned = Pose2::new(pose.x, pose.y, heading);
            if !self.safe(input, turned, distance + 0.3, 0.0) {
                continue;
            }
            if error.abs() > self.config.turn_threshold {
                return NavCommand::Turn { angle: error };
            }
            // An arc that bends toward the heading over the step.
            let curvature = 2.0 * error.sin() / distance.max(0.1);
            if self.safe(input, pose, distance, curvature) {
                return NavCommand::Drive { distance, curvature, guard: DriveGuard::default() };
            }
            return NavCommand::Turn { angle: error };
        }
        // Boxed in by what is known: turn to look elsewhere.
        NavCommand::Turn { angle: -spin }
    }
}

/// Registry entry: navigation templates.
pub const ENTRY: NavigatorEntry = NavigatorEntry {
    name: "nat",
    doc: "NaT navigation templates: spun potential fields around sensed obstacles (paper 001 section 4)",
    global_planners: &[],
    params: || param_info(NatConfig::default(), NatConfig::params()),
    build: |b| {
        Ok(Box::new(NatNavigator::new(
            b.rover.clone(),
            b.configured(NatConfig::default(), &NatConfig::params())?,
        )))
    },
};

#[cfg(test)]
mod tests {
    use super::*;
    use rovernav_core::{Goal, Pose3, PoseEstimate, SensorFrame};

    #[test]
    fn free_field_points_at_the_goal_and_spin_sides_follow_the_goal_line() {
        let rover = RoverConfig::default();
        let mut nat = NatNavigator::new(rover, NatConfig::default());
        let goal =
            Goal { position: Point2::new(10.0, 0.0), tolerance: 0.5, waypoints: vec![], keep_out: vec![] };
        let frame = SensorFrame::default();
        let input = NavInput {
            time: 0.0,
            estimate: PoseEstimate { pose: Pose3::default(), covariance: [[0.0; 3]; 3] },
            goal: &goal,
            frame: &frame,
            localization_target: None,
        };
        // The first step builds the map and asks for range data.
        assert!(matches!(nat.step(&input), NavCommand::Sense(_)));
        let (f, _) = nat.field(Point2::new(0.0, 0.0), &input);
        assert!((f.angle()).abs() < 1e-9 && (f.norm() - 1.0).abs() < 1e-9);
        // An obstacle left of the line to the goal is circled counter-clockwise, one right of it
        // clockwise: both flows then pass between the obstacle and the goal line.
        let here = Point2::new(0.0, 0.0);
        assert_eq!(nat.spin_of(Point2::new(1.0, 0.5), here, goal.position), 1.0);
        assert_eq!(nat.spin_of(Point2::new(5.0, -3.0), here, goal.position), -1.0);
        // A neighbour of an obstacle already met inherits its spin.
        assert_eq!(nat.spin_of(Point2::new(1.0, 0.2), here, goal.position), 1.0);
    }
}
