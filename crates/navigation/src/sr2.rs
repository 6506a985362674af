//! SR2's reactive navigation (paper 001 sections 5.1-5.2 and 7): no maps, only the compass and
//! odometry pose, ten forward proximity threshold sensors in three clusters and the
//! inclinometer.
//!
//! - The rover drives straight at the next waypoint (then the goal), turning only when its
//!   heading deviates from the target bearing by more than 10 deg.
//! - A proximity cluster that triggers (rocks, or holes and cliffs, which the sensors report the
//!   same way) starts an avoidance: back up, rotate away (counter-clockwise for the right
//!   cluster, clockwise for the left, longer for the set-back middle cluster, whose left and
//!   right halves choose the direction), then drive forward. The cycle repeats, rotating the
//!   same way, until the forward leg completes without a trigger.
//! - A tilt beyond 15 deg makes the rover turn until the slope is acceptable, drive a couple of
//!   metres, then turn back toward the waypoint: it tacks across ridges like a sailing boat.
//! - Diverted too far from course, or without progress for too long, it stops and asks for
//!   help.
//!
//! Keep-out zones are treated like obstacles seen by the middle cluster.
//!
//! Departure: the avoidance's back-up is cut to the distance driven straight forward since the
//! last turn, so the rover only reverses over ground its wheels have just crossed, along the
//! path it came by (a zero budget, as right after a rotation, skips the back-up and goes
//! straight to the rotation). The slope back-off keeps its full length: cut the same way, the
//! rover turned on the spot at a crater rim (a tilt trip right after each turn) until fault
//! protection stopped it. SR2 has no rear sensors
//! (section 5.2), and the paper's worst case is that the rover "would have to backtrack the way
//! it came" (section 5.2): backing blindly by a fixed distance after a turn put a rear wheel
//! onto a rock it had never driven over.

use crate::gestalt::keep_out_distance;
use crate::params::{Field, Param, Unit};
use crate::registry::{NavigatorEntry, param_info};
use rovernav_core::{
    DriveGuard, NavCommand, NavInput, Navigator, NavigatorStats, Outcome, Point2, ProximityReading,
    RoverConfig, angle_diff,
};

/// Tunable parameters of SR2.
#[derive(Clone, Debug)]
pub struct Sr2Config {
    /// Heading dead-band (rad): turn toward the target only beyond this.
    pub dead_band: f64,
    /// Longest straight leg between heading checks (m).
    pub leg: f64,
    /// Back-up distance of an avoidance (m).
    pub backup: f64,
    /// Rotation away from a side-cluster obstacle (rad).
    pub side_rotation: f64,
    /// Rotation away from a middle-cluster obstacle (rad).
    pub middle_rotation: f64,
    /// Forward leg that must complete without a trigger to end an avoidance (m).
    pub clear_leg: f64,
    /// Inclinometer tilt limit (rad).
    pub max_tilt: f64,
    /// How far below the limit the drive guard trips (rad).
    pub tilt_margin: f64,
    /// Back-up distance after a slope exception (m).
    pub slope_backup: f64,
    /// Heading change per slope correction (rad).
    pub slope_turn: f64,
    /// Distance driven across the slope before turning back toward the target (m).
    pub tack_leg: f64,
    /// Distance from the straight course beyond which the rover asks for help (m).
    pub max_diversion: f64,
    /// Distance driven without getting 0.5 m closer to the target before asking for help (m).
    pub patience_m: f64,
    /// Distance after an avoidance within which the next one keeps its rotation direction (m).
    pub avoid_memory: f64,
}

impl Sr2Config {
    /// The parameters a mission file may set (`[navigator_params]`).
    pub fn params() -> Vec<Param<Self>> {
        use Unit::*;
        vec![
            Param {
                name: "dead_band_deg",
                doc: "heading dead-band: turn toward the target only beyond this",
                unit: Degrees,
                field: |c| Field::Real(&mut c.dead_band),
            },
            Param {
                name: "leg_m",
                doc: "longest straight leg between heading checks",
                unit: PositiveMetres,
                field: |c| Field::Real(&mut c.leg),
            },
            Param {
                name: "backup_m",
                doc: "back-up distance of an avoidance",
                unit: Metres,
                field: |c| Field::Real(&mut c.backup),
            },
            Param {
                name: "side_rotation_deg",
                doc: "rotation away from a side-cluster obstacle",
                unit: Degrees,
                field: |c| Field::Real(&mut c.side_rotation),
            },
            Param {
                name: "middle_rotation_deg",
                doc: "rotation away from a middle-cluster obstacle",
                unit: Degrees,
                field: |c| Field::Real(&mut c.middle_rotation),
            },
            Param {
                name: "clear_leg_m",
                doc: "forward leg that must complete without a trigger to end an avoidance",
                unit: Metres,
                field: |c| Field::Real(&mut c.clear_leg),
            },
            Param {
                name: "max_tilt_deg",
                doc: "inclinometer tilt limit",
                unit: Degrees,
                field: |c| Field::Real(&mut c.max_tilt),
            },
            Param {
                name: "tilt_margin_deg",
                doc: "how far below the limit the drive guard trips",
                unit: Degrees,
                field: |c| Field::Real(&mut c.tilt_margin),
            },
            Param {
                name: "slope_backup_m",
                doc: "back-up distance after a slope exception",
                unit: Metres,
                field: |c| Field::Real(&mut c.slope_backup),
            },
            Param {
                name: "slope_turn_deg",
                doc: "heading change per slope correction",
                unit: Degrees,
                field: |c| Field::Real(&mut c.slope_turn),
            },
            Param {
                name: "tack_leg_m",
                doc: "distance driven across the slope before turning back toward the target",
                unit: Metres,
                field: |c| Field::Real(&mut c.tack_leg),
            },
            Param {
                name: "max_diversion_m",
                doc: "distance from the straight course beyond which the rover asks for help",
                unit: Metres,
                field: |c| Field::Real(&mut c.max_diversion),
            },
            Param {
                name: "patience_m",
                doc: "distance driven without getting 0.5 m closer to the target before asking for help",
                unit: Metres,
                field: |c| Field::Real(&mut c.patience_m),
            },
            Param {
                name: "avoid_memory_m",
                doc: "distance after an avoidance within which the next one keeps its rotation direction",
                unit: Metres,
                field: |c| Field::Real(&mut c.avoid_memory),
            },
        ]
    }
}
impl Default for Sr2Config {
    fn default() -> Self {
        Self {
            dead_band: 10f64.to_radians(),
            leg: 1.0,
            backup: 0.3,
            side_rotation: 30f64.to_radians(),
            middle_rotation: 60f64.to_radians(),
            clear_leg: 1.5,
            max_tilt: 15f64.to_radians(),
            tilt_margin: 1f64.to_radians(),
            slope_backup: 0.6,
            slope_turn: 45f64.to_radians(),
            tack_leg: 2.0,
            max_diversion: 12.0,
            patience_m: 60.0,
            avoid_memory: 3.0,
        }
    }
}

/// What SR2 is doing.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Mode {
    /// Heading for the target.
    Cruise,
    /// Avoiding an obstacle, rotating in the given direction (+1 counter-clockwise).
    Avoid { phase: AvoidPhase, dir: f64, middle: bool },
    /// Crossing a slope, turning `dir` (+1 counter-clockwise) on each slope exception.
    Tack { dir: f64, stage: TackStage },
}

/// The phases of an avoidance.
#[derive(Clone, Copy, Debug, PartialEq)]
enum AvoidPhase {
    BackUp,
    Rotate,
    Forward,
}

/// The stages of a slope correction.
#[derive(Clone, Copy, Debug, PartialEq)]
enum TackStage {
    /// Backed off the slope; the turn comes next.
    BackedOff,
    /// Turned across the slope; the leg comes next.
    Turned,
    /// Driving the leg across the slope.
    Crossing,
}

/// The SR2 navigator (see the module documentation).
pub struct Sr2Navigator {
    rover: RoverConfig,
    config: Sr2Config,
    target_index: usize,
    leg_start: Option<Point2>,
    mode: Mode,
    best_distance: f64,
    driven_since_progress: f64,
    last_position: Option<Point2>,
    tack_dir: Option<f64>,
    odometer: f64,
    /// The rotation direction of the last avoidance and the odometer when it ended.
    last_avoid: Option<(f64, f64)>,
    /// Distance driven straight forward since the last turn, less what was reversed since (m):
    /// the most a back-up may cover.
    retrace: f64,
    /// The sign of the last drive command (+1 forward, -1 reverse, 0 a turn or nothing).
    last_motion: f64,
    stats: NavigatorStats,
}

impl Sr2Navigator {
    /// A navigator for a rover with the given parameters.
    pub fn new(rover: RoverConfig, config: Sr2Config) -> Self {
        Self {
            rover,
            config,
            target_index: 0,
            leg_start: None,
            mode: Mode::Cruise,
            best_distance: f64::INFINITY,
            driven_since_progress: 0.0,
            last_position: None,
            tack_dir: None,
            odometer: 0.0,
            last_avoid: None,
            retrace: 0.0,
            last_motion: 0.0,
            stats: NavigatorStats::default(),
        }
    }

    fn guard(&self) -> DriveGuard {
        // The guard trips a little below the limit: the inclinometer is noisy and the motion
        // stops one sample after the trip.
        DriveGuard { proximity: true, max_tilt: Some(self.config.max_tilt - self.config.tilt_margin) }
    }

    fn drive(&mut self, distance: f64) -> NavCommand {
        self.last_motion = distance.signum();
        let guard = if distance > 0.0 { self.guard() } else { DriveGuard::default() };
        NavCommand::Drive { distance, curvature: 0.0, guard }
    }

    fn turn(&mut self, angle: f64) -> NavCommand {
        self.last_motion = 0.0;
        self.retrace = 0.0;
        NavCommand::Turn { angle }
    }

    /// A reverse leg of up to `distance`, cut to the ground just driven over; `None` when there
    /// is none to reverse over.
    fn reverse(&mut self, distance: f64) -> Option<NavCommand> {
        let distance = distance.min(self.retrace);
        (distance > 0.01).then(|| self.drive(-distance))
    }

    /// Starts an avoidance for a proximity reading (or a virtual middle obstacle).
    fn start_avoid(&mut self, reading: &ProximityReading, keep_dir: Option<f64>) -> NavCommand {
        let middle = reading.middle() || !(reading.left() || reading.right());
        let dir = keep_dir.unwrap_or_else(|| {
            if reading.right() && !reading.left() {
                1.0
            } else if reading.left() && !reading.right() {
                -1.0
            } else {
                // The middle cluster is split in halves to choose the rotation.
                let left_half = reading.raw[3..5].iter().filter(|&&b| b).count();
                let right_half = reading.raw[5..7].iter().filter(|&&b| b).count();
                if left_half > right_half { -1.0 } else { 1.0 }
            }
        });
        self.mode = Mode::Avoid { phase: AvoidPhase::BackUp, dir, middle };
        match self.reverse(self.config.backup) {
            Some(command) => command,
            None => self.avoid_rotate(dir, middle),
        }
    }

    /// The rotation of an avoidance.
    fn avoid_rotate(&mut self, dir: f64, middle: bool) -> NavCommand {
        self.mode = Mode::Avoid { phase: AvoidPhase::Rotate, dir, middle };
        let angle = if middle { self.config.middle_rotation } else { self.config.side_rotation };
        self.turn(dir * angle)
    }

    /// Whether driving `distance` straight ahead from the pose would enter a keep-out zone.
    fn keep_out_ahead(&self, input: &NavInput<'_>, distance: f64) -> bool {
        let pose = input.estimate.pose.pose2();
        let n = (distance / 0.1).ceil() as usize;
        (0..=n).any(|i| {
            let p = pose.transform(Point2::new(distance * i as f64 / n.max(1) as f64, 0.0));
            keep_out_distance(input.goal, p) < self.rover.radius()
        })
    }

    fn cruise(&mut self, input: &NavInput<'_>, here: Point2, target: Point2) -> NavCommand {
        self.mode = Mode::Cruise;
        let bearing = target.sub(here).angle();
        let error = angle_diff(bearing, input.estimate.pose.yaw);
        if error.abs() > self.config.dead_band {
            return self.turn(error);
        }
        let distance = here.dist(target).min(self.config.leg);
        if self.keep_out_ahead(input, distance + 0.5 * self.rover.length) {
            return self.start_avoid(&ProximityReading { raw: [false; 10] }, None);
        }
        self.drive(distance)
    }
}

impl Navigator for Sr2Navigator {
    fn name(&self) -> &str {
        "sr2"
    }

    fn step(&mut self, input: &NavInput<'_>) -> NavCommand {
        let est = input.estimate.pose;
        let here = Point2::new(est.x, est.y);
        let goal = input.goal;
        let targets: Vec<Point2> = goal.waypoints.iter().copied().chain([goal.position]).collect();
        let leg_start = *self.leg_start.get_or_insert(here);
        if let Some(last) = self.last_position {
            self.driven_since_progress += last.dist(here);
            self.odometer += last.dist(here);
            self.retrace = (self.retrace + self.last_motion * last.dist(here)).max(0.0);
        }
        self.last_position = Some(here);

        // Advance through the waypoints.
        while self.target_index < targets.len() && here.dist(targets[self.target_index]) <= goal.tolerance {
            if self.target_index + 1 == targets.len() {
                return NavCommand::Finish(
                    Outcome::Reached,
                    format!("estimate within {:.2} m of the goal", here.dist(goal.position)),
                );
            }
            self.target_index += 1;
            self.leg_start = Some(here);
            self.best_distance = f64::INFINITY;
            self.tack_dir = None;
            self.mode = Mode::Cruise;
        }
        let target = targets[self.target_index];
        let from = if self.target_index == 0 { leg_start } else { self.leg_start.unwrap_or(here) };

        // Asking for help: diverted too far from the straight course, or no progress.
        let course = target.sub(from);
        let diversion =
            if course.norm() > 1e-9 { course.cross(here.sub(from)).abs() / course.norm() } else { 0.0 };
        if diversion > self.config.max_diversion {
            return NavCommand::Finish(
                Outcome::HelpRequested,
                format!("diverted {diversion:.1} m from the course to the next waypoint"),
            );
        }
        let d = here.dist(target);
        if d < self.best_distance - 0.5 {
            self.best_distance = d;
            self.driven_since_progress = 0.0;
        } else if self.driven_since_progress > self.config.patience_m {
            return NavCommand::Finish(
                Outcome::HelpRequested,
                format!("no progress in {:.0} m of driving", self.config.patience_m),
            );
        }

        let stopped = input.frame.motion_stopped.as_deref();
        let tilt_stop = stopped.is_some_and(|w| w.contains("tilt"));
        let proximity_stop = stopped.is_some_and(|w| w.contains("proximity") || w.starts_with("hazard"));

        if proximity_stop {
            // Keep rotating the same way while one avoidance is under way.
            // Keep rotating the same way while one avoidance is under way, and for a while
            // after it: alternating directions would lead back into a half-enclosure.
            let keep = match self.mode {
                Mode::Avoid { dir, .. } => Some(dir),
                _ => self
                    .last_avoid
                    .filter(|&(_, at)| self.odometer - at < self.config.avoid_memory)
                    .map(|(dir, _)| dir),
            };
            return self.start_avoid(&input.frame.proximity, keep);
        }
        if tilt_stop {
            // Too steep: turn off the fall line and cross the slope for a while.
            let dir = match self.tack_dir {
                Some(dir) => dir,
                None => {
                    // Turn toward the side that is lower under the rover (roll > 0 lifts the
                    // left side), which leads along the slope rather than up it.
                    let roll = input.frame.imu.last().map_or(0.0, |s| s.incl_roll);
                    if roll > 0.0 { -1.0 } else { 1.0 }
                }
            };
            // Keep tacking the same way along this ridge, as a sailing boat keeps its tack.
            self.tack_dir = Some(dir);
            self.mode = Mode::Tack { dir, stage: TackStage::BackedOff };
            self.stats.plans += 1;
            return self.drive(-self.config.slope_backup);
        }

        match self.mode {
            Mode::Avoid { phase: AvoidPhase::BackUp, dir, middle } => self.avoid_rotate(dir, middle),
            Mode::Avoid { phase: AvoidPhase::Rotate, dir, middle } => {
                if self.keep_out_ahead(input, self.config.clear_leg + 0.5 * self.rover.length) {
                    self.mode = Mode::Avoid { phase: AvoidPhase::BackUp, dir, middle };
                    return self.turn(dir * self.config.side_rotation);
                }
                self.mode = Mode::Avoid { phase: AvoidPhase::Forward, dir, middle };
                self.drive(self.config.clear_leg)
            }
            Mode::Avoid { phase: AvoidPhase::Forward, dir, .. } => {
                self.last_avoid = Some((dir, self.odometer));
                self.cruise(input, here, target)
            }
            Mode::Tack { stage: TackStage::Crossing, .. } => {
                // The forward leg completed without a trigger: recompute the course.
                self.cruise(input, here, target)
            }
            Mode::Tack { dir, stage: TackStage::BackedOff } => {
                self.mode = Mode::Tack { dir, stage: TackStage::Turned };
                self.turn(dir * self.config.slope_turn)
            }
            Mode::Tack { dir, stage: TackStage::Turned } => {
                if self.keep_out_ahead(input, self.config.tack_leg + 0.5 * self.rover.length) {
                    return self.start_avoid(&ProximityReading::default(), Some(dir));
                }
                self.mode = Mode::Tack { dir, stage: TackStage::Crossing };
                self.drive(self.config.tack_leg)
            }
            Mode::Cruise => self.cruise(input, here, target),
        }
    }

    fn planned_path(&self) -> Vec<Point2> {
        Vec::new()
    }

    fn stats(&self) -> NavigatorStats {
        self.stats.clone()
    }
}

/// Registry entry: SR2's reactive navigation.
pub const ENTRY: NavigatorEntry = NavigatorEntry {
    name: "sr2",
    doc: "SR2 reactive navigation on proximity sensors, no maps (paper 001 sections 5.1-5.2)",
    global_planners: &[],
    params: || param_info(Sr2Config::default(), Sr2Config::params()),
    build: |b| {
        Ok(Box::new(Sr2Navigator::new(
            b.rover.clone(),
            b.configured(Sr2Config::default(), &Sr2Config::params())?,
        )))
    },
};

#[cfg(test)]
mod tests {
    use super::*;
    use rovernav_core::{Goal, Pose3, PoseEstimate, SensorFrame};

    /// Distance from `p` to the segment `a`-`b`.
    fn to_segment(p: Point2, a: Point2, b: Point2) -> f64 {
        let ab = b.sub(a);
        let t = if ab.norm() > 1e-12 { (p.sub(a).dot(ab) / ab.dot(ab)).clamp(0.0, 1.0) } else { 0.0 };
        p.dist(Point2::new(a.x + t * ab.x, a.y + t * ab.y))
    }

    #[test]
    fn every_back_up_stays_on_ground_driven_forward() {
        let mut nav = Sr2Navigator::new(RoverConfig::default(), Sr2Config::default());
        let goal =
            Goal { position: Point2::new(40.0, 5.0), tolerance: 0.5, waypoints: vec![], keep_out: vec![] };
        // The truth: an exact kinematic rover and the forward segments it drove.
        let (mut x, mut y, mut yaw) = (0.0f64, 0.0f64, 0.0f64);
        let mut forward: Vec<(Point2, Point2)> = Vec::new();
        let mut frame = SensorFrame::default();
        // Forward drives are cut short by a trigger in a fixed pattern, some right after a turn.
        let cuts = [None, Some(0.1), Some(0.6), None, Some(0.05), Some(0.9), None, Some(0.3)];
        let (mut drives, mut reverses, mut skipped) = (0usize, 0usize, 0usize);
        let mut turned = false;
        for _ in 0..400 {
            let estimate =
                PoseEstimate { pose: Pose3 { x, y, yaw, ..Default::default() }, ..Default::default() };
            let input =
                NavInput { time: 0.0, estimate, goal: &goal, frame: &frame, localization_target: None };
            let command = nav.step(&input);
            frame = SensorFrame::default();
            let from = Point2::new(x, y);
            match command {
                NavCommand::Turn { angle } => {
                    yaw += angle;
                    turned = true;
                }
                NavCommand::Drive { distance, .. } if distance > 0.0 => {
                    let cut = cuts[drives % cuts.len()];
                    drives += 1;
                    let d = cut.map_or(distance, |f| f * distance);
                    (x, y) = (x + d * yaw.cos(), y + d * yaw.sin());
                    forward.push((from, Point2::new(x, y)));
                    if cut.is_some() {
                        frame.motion_stopped = Some("proximity".into());
                        frame.proximity.raw[drives % 10] = true;
                    }
                }
                NavCommand::Drive { distance, .. } => {
                    (x, y) = (x + distance * yaw.cos(), y + distance * yaw.sin());
                    let to = Point2::new(x, y);
                    // Every point of the reverse leg lies on a forward segment driven before.
                    let on_trail = |p: Point2| forward.iter().any(|&(a, b)| to_segment(p, a, b) < 1e-9);
                    assert!(
                        (0..=20).all(|i| {
                            let t = f64::from(i) / 20.0;
                            on_trail(Point2::new(from.x + t * (to.x - from.x), from.y + t * (to.y - from.y)))
                        }),
                        "reversed from {from:?} to {to:?} off the ground driven forward"
                    );
                    reverses += 1;
                }
                NavCommand::Finish(..) => break,
                _ => {}
            }
            if turned && matches!(command, NavCommand::Turn { .. }) {
                skipped += usize::from(nav.retrace == 0.0);
            }
        }
        // The pattern exercised both a cut-down back-up and a skipped one.
        assert!(reverses > 5 && skipped > 5, "reverses {reverses}, skipped {skipped}");
    }
}
