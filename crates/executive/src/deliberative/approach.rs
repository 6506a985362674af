//! The `approach_target` task and the `track` commands: visual target tracking (paper 003
//! section 3; [`rovernav_vision::tracking::approach`]) elaborated into commands for the
//! reflexive layer.
//!
//! Each cycle of an approach is one command at a time, each with its own id on the task:
//! a Navcam pair pointed at the target (`Sense`), then a turn to face it, then a drive of at
//! most 10 % of the remaining distance (the last one to the stand-off). While the target is
//! more than [`NAVIGATOR_LEG_MIN_M`] beyond the stand-off, the drive is a leg of the mission's
//! navigator (hazard avoidance on the way); closer in, where the target itself is the nearest
//! obstacle, the move is blind (turn in place, drive straight). The next step waits for the
//! pose estimate of the command's frame, so every image is placed with the estimate of the pose
//! it was taken from. A lost target or a missing range fails the task with the tracker's
//! reason: the mission stops and asks for help.
//!
//! `track ROW COL` designates a pixel of the last left Navcam image the rover took; `track X Y
//! Z` a site point. Both add an approach task after the current step and drive the rover there.

use super::vtt_telemetry::VttTrackMsg;
use super::{Deliberative, TaskKind};
use crate::messages::{
    CommandMsg, DriveToMsg, FrameMsg, ImageMsg, MotionRequest, Origin, SenseMsg, TaskState, TaskStatusMsg,
    topics,
};
use rovernav_bus::{Bus, BusError};
use rovernav_core::{Goal, Point2, Pose3};
use rovernav_vision::image::GreyF32;
use rovernav_vision::tracking::approach::grey_f32;
use rovernav_vision::tracking::{Approach, ApproachParams, Decision, Designation, NavcamPair, Observation};

/// Remaining distance beyond the stand-off below which moves are blind (m).
pub const NAVIGATOR_LEG_MIN_M: f64 = 2.0;
/// Stand-off of the operator's `track` commands (m).
pub const TRACK_STANDOFF_M: f64 = 1.0;

/// What an approach waits for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Phase {
    /// The Navcam pair of the current command.
    Imaging,
    /// A turn, after which the rover drives `distance` (m).
    Turning {
        /// The drive after the turn (m).
        distance: f64,
    },
    /// A drive or a navigator leg.
    Driving,
}

/// One approach in progress.
pub(super) struct ApproachRun {
    /// The tracker and its approach logic.
    pub(super) approach: Approach,
    phase: Phase,
    /// The current command finished; with the frame that ended it, if the platform sent one.
    done: Option<Option<u64>>,
    /// The frame of the current Navcam pair.
    images_seq: u64,
    /// The Navcam pair of the current imaging command.
    images: Vec<ImageMsg>,
    /// Every image's observation, in order (the target's estimates along the way).
    pub(super) observations: Vec<Observation>,
}

/// The last Navcam pair the rover took, with the estimate it was taken from.
#[derive(Clone, Debug)]
pub(super) struct LastNavcam {
    pub(super) images: Vec<ImageMsg>,
    pub(super) frame_seq: u64,
}

/// The left and right Navcam images of a frame, as the tracker's images, with pan and tilt: the
/// frame's last pair (a ride-along pair comes after the images of the navigator's own sensing,
/// which with stereo ranging include a Navcam left image of its own).
pub(super) fn pair_of(images: &[ImageMsg]) -> Option<(GreyF32, GreyF32, f64, f64)> {
    let get = |name: &str| images.iter().rfind(|i| i.camera == name);
    let (l, r) = (get("navcam_left")?, get("navcam_right")?);
    Some((grey_f32(l.width, l.height, &l.pixels)?, grey_f32(r.width, r.height, &r.pixels)?, l.pan, l.tilt))
}

impl Deliberative {
    /// Starts approach task `i` as command `cmd`.
    pub(super) fn start_approach(&mut self, bus: &mut Bus, i: usize, cmd: u64) -> Result<(), BusError> {
        let TaskKind::ApproachTarget { designation, standoff } = self.tasks[i].kind else { return Ok(()) };
        let params = ApproachParams { standoff_m: standoff, ..ApproachParams::default() };
        let approach = match Approach::new(&self.rover, self.navcam_width, designation, params) {
            Ok(a) => a,
            Err(e) => return self.fail_now(i, format!("approach: {e}")),
        };
        let id = self.tasks[i].id;
        let run = ApproachRun {
            approach,
            phase: Phase::Imaging,
            done: None,
            images_seq: 0,
            images: Vec::new(),
            observations: Vec::new(),
        };
        self.approaches.insert(id, run);
        match designation {
            Designation::Pixel { .. } => {
                // The operator designated a pixel of the last pair: designate on it at once.
                let Some(last) = self.last_navcam.clone() else {
                    return self.fail_now(i, "no Navcam image to designate a pixel on".into());
                };
                let run = self.approaches.get_mut(&id).expect("just inserted");
                run.images = last.images;
                run.images_seq = last.frame_seq;
                run.done = Some(Some(last.frame_seq));
                Ok(())
            }
            Designation::Site { .. } => self.approach_image(bus, i, cmd),
        }
    }

    /// Points the head at the target and takes a Navcam pair (command `cmd`).
    fn approach_image(&mut self, bus: &mut Bus, i: usize, cmd: u64) -> Result<(), BusError> {
        let id = self.tasks[i].id;
        let Some(e) = self.estimate else {
            return self.fail_now(i, "no pose estimate to aim the Navcams".into());
        };
        let pose = pose_of(&e.pose);
        let Some(run) = self.approaches.get_mut(&id) else { return Ok(()) };
        let Some((pan, tilt)) = run.approach.aim(&pose) else {
            return self.fail_now(i, "nothing to aim the Navcams at".into());
        };
        run.phase = Phase::Imaging;
        run.done = None;
        run.images.clear();
        self.tasks[i].command = Some(cmd);
        let request = MotionRequest {
            id: cmd,
            origin: Origin::Task(cmd),
            command: CommandMsg::Sense(vec![SenseMsg::Navcam { pan, tilt }]),
        };
        bus.publish(topics::EXECUTIVE_MOTION, request)
    }

    /// Keeps the frames the approaches need: Navcam pairs, and which frame ended a command.
    pub(super) fn approach_frame(&mut self, f: &FrameMsg) {
        if f.images.iter().any(|i| i.camera == "navcam_left")
            && f.images.iter().any(|i| i.camera == "navcam_right")
        {
            self.last_navcam = Some(LastNavcam { images: f.images.clone(), frame_seq: f.seq });
        }
        let Some(Origin::Task(cmd)) = f.request().map(|r| r.origin) else { return };
        let Some(task) = self.tasks.iter().find(|t| t.command == Some(cmd)) else { return };
        if let Some(run) = self.approaches.get_mut(&task.id) {
            run.images = f.images.clone();
            run.images_seq = f.seq;
            run.done = Some(Some(f.seq));
        }
    }

    /// A status of an approach's current command; `true` when it was one.
    pub(super) fn approach_status(&mut self, i: usize, s: &TaskStatusMsg) -> bool {
        let Some(run) = self.approaches.get_mut(&self.tasks[i].id) else { return false };
        match s.state {
            TaskState::Success => {
                // A navigator leg ends without a frame of its own: its estimate is current.
                if run.done.is_none() {
                    run.done = Some(None);
                }
            }
            TaskState::Pending | TaskState::InProcess => {}
            state => {
                self.tasks[i].state = state;
                self.tasks[i].message = format!("approach stopped: {}", s.message);
            }
        }
        true
    }

    /// Advances every approach whose command is done and whose estimate has caught up.
    pub(super) fn pump_approaches(&mut self, bus: &mut Bus) -> Result<(), BusError> {
        for i in 0..self.tasks.len() {
            if self.tasks[i].state != TaskState::InProcess {
                continue;
            }
            let id = self.tasks[i].id;
            let Some(run) = self.approaches.get(&id) else { continue };
            let Some(done) = run.done else { continue };
            let Some(e) = self.estimate else { continue };
            if done.is_some_and(|seq| e.frame_seq < seq) {
                continue;
            }
            self.approach_next(bus, i)?;
        }
        Ok(())
    }

    /// The step after a finished command of approach `i`.
    fn approach_next(&mut self, bus: &mut Bus, i: usize) -> Result<(), BusError> {
        let id = self.tasks[i].id;
        let pose = pose_of(&self.estimate.expect("checked by the caller").pose);
        let run = self.approaches.get_mut(&id).expect("checked by the caller");
        run.done = None;
        let cmd = self.next_command;
        self.next_command += 1;
        match run.phase {
            Phase::Imaging => {
                let Some((left, right, pan, tilt)) = pair_of(&run.images) else {
                    return self.fail_now(i, "approach: the frame has no Navcam pair".into());
                };
                let pair = NavcamPair { left: &left, right: &right, pan, tilt };
                let t = run.images.iter().find(|i| i.camera == "navcam_left").map_or(0.0, |i| i.t);
                let head = VttTrackMsg {
                    task: id,
                    mode: "approach".into(),
                    image_index: run.approach.images() + 1,
                    frame_seq: run.images_seq,
                    t,
                    pan,
                    tilt,
                    ..VttTrackMsg::default()
                };
                match run.approach.observe(&pair, &pose) {
                    Ok(o) => {
                        bus.publish(topics::VTT_TRACK, VttTrackMsg::observed(head, &o))?;
                        run.observations.push(o);
                    }
                    Err(e) => {
                        bus.publish(topics::VTT_TRACK, VttTrackMsg { status: format!("lost: {e}"), ..head })?;
                        let why = format!("{e}; rover stopped, asking for help");
                        return self.fail_now(i, why);
                    }
                }
                match run.approach.decide(&pose) {
                    Ok(Decision::Arrived { distance_m }) => {
                        self.tasks[i].state = TaskState::Success;
                        self.tasks[i].message = format!(
                            "at the target: {distance_m:.3} m away after {} moves and {} images",
                            run.approach.moves(),
                            run.approach.images()
                        );
                        Ok(())
                    }
                    Ok(Decision::Move { turn_rad, distance_m, .. }) => {
                        let target = run.approach.target().map(|t| t.site);
                        let standoff = run.approach.params().standoff_m;
                        let remaining =
                            target.map_or(0.0, |t| Point2::new(t.x - pose.x, t.y - pose.y).norm());
                        if remaining - distance_m > standoff + NAVIGATOR_LEG_MIN_M {
                            // A leg of the navigator to the step's end point, toward the target.
                            let t = target.expect("a move has a target");
                            let k = distance_m / remaining.max(1e-9);
                            let to = Point2::new(pose.x + k * (t.x - pose.x), pose.y + k * (t.y - pose.y));
                            run.phase = Phase::Driving;
                            self.tasks[i].command = Some(cmd);
                            self.tasks[i].message = format!("leg of {distance_m:.2} m toward the target");
                            let goal = Goal {
                                position: to,
                                tolerance: (0.2 * distance_m).max(0.05),
                                waypoints: Vec::new(),
                                keep_out: self.config.keep_out.clone(),
                            };
                            bus.publish(topics::EXECUTIVE_DRIVE_TO, DriveToMsg { task: cmd, goal })
                        } else if turn_rad != 0.0 {
                            run.phase = Phase::Turning { distance: distance_m };
                            self.motion(bus, i, cmd, CommandMsg::Turn { angle: turn_rad })
                        } else {
                            run.phase = Phase::Driving;
                            self.motion(bus, i, cmd, drive(distance_m))
                        }
                    }
                    Err(e) => self.fail_now(i, format!("{e}; rover stopped, asking for help")),
                }
            }
            Phase::Turning { distance } => {
                run.phase = Phase::Driving;
                self.motion(bus, i, cmd, drive(distance))
            }
            Phase::Driving => self.approach_image(bus, i, cmd),
        }
    }

    fn motion(&mut self, bus: &mut Bus, i: usize, cmd: u64, command: CommandMsg) -> Result<(), BusError> {
        self.tasks[i].command = Some(cmd);
        bus.publish(topics::EXECUTIVE_MOTION, MotionRequest { id: cmd, origin: Origin::Task(cmd), command })
    }

    /// `track ROW COL` / `track X Y Z`: an approach task after the current step.
    pub(super) fn track(&mut self, designation: Designation) -> String {
        if matches!(designation, Designation::Pixel { .. }) && self.last_navcam.is_none() {
            return "error: `track ROW COL`: the rover has taken no Navcam image yet".into();
        }
        self.queue(TaskKind::ApproachTarget { designation, standoff: TRACK_STANDOFF_M })
    }

    /// The target estimates of approach task `id` along the way (site frame, m).
    pub fn target_estimates(&self, id: u64) -> Vec<[f64; 3]> {
        self.approaches
            .get(&id)
            .map(|r| {
                r.observations.iter().map(|o| [o.target.site.x, o.target.site.y, o.target.site.z]).collect()
            })
            .unwrap_or_default()
    }

    /// What the traverse picture draws of every approach and track-only task so far: the
    /// designated target and its later estimates (the same as [`VttTrace::of_records`] of the
    /// logged `/vtt/track` records, so a replay draws the same picture).
    pub fn vtt_traces(&self) -> Vec<super::VttTrace> {
        let approaches = self.approaches.keys().map(|&id| (id, self.target_estimates(id)));
        let tracks = self.tracks.keys().map(|&id| (id, self.tracked_estimates(id)));
        super::VttTrace::of_sites(approaches.chain(tracks))
    }
}

fn drive(distance: f64) -> CommandMsg {
    CommandMsg::Drive { distance, curvature: 0.0, guard: Default::default() }
}

pub(super) fn pose_of(p: &crate::messages::PoseMsg) -> Pose3 {
    Pose3 { x: p.x, y: p.y, z: p.z, roll: p.roll, pitch: p.pitch, yaw: p.yaw }
}
