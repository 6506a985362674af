//! The `track_target` task: visual target tracking in "track only" mode (paper 003 section 3:
//! in the sol-992 checkout "VTT was instructed to only track the target without controlling the
//! rover's movement"; issue 35 item 2).
//!
//! The task runs in parallel with a drive (or any task that moves the rover) and sends no
//! command of its own. It asks the platform for a Navcam pair alongside each of the navigator's
//! sensing commands (`/platform/ride_along`), aimed at the target from the pose estimate; each
//! pair, once the estimate of its frame has come, is tracked and re-ranged as in an approach
//! ([`rovernav_vision::tracking::Approach::observe`], with the motion since the last pair as
//! the prediction's uncertainty). Every image goes to `/vtt/track`. The task ends when the
//! other tasks of its step have ended: success if every pair tracked, failure naming the loss
//! otherwise (a loss stops the tracking, never the drive).
//!
//! Departure: on a rover the pair would add its exposure time to each sensing step; the
//! simulator takes it in no time (and without drawing from its noise streams) so that the
//! drive is the same, pose for pose, as without the task: the property the checkout tests.

use super::approach::pair_of;
use super::vtt_telemetry::VttTrackMsg;
use super::{Deliberative, TaskKind};
use crate::messages::{FrameMsg, ImageMsg, Origin, RideAlongMsg, TaskState, topics};
use rovernav_bus::{Bus, BusError};
use rovernav_core::{Pose3, angle_diff};
use rovernav_vision::tracking::{
    Approach, ApproachParams, Designation, NavcamPair, Observation, TrackParams,
};

/// Template re-cut score of track-only mode: the view of the target swings as another plan
/// drives past it (the default mission's rock scored 0.91, 0.81, 0.75 on an unchanged template
/// over three pairs, then was lost as ambiguous at 0.74).
pub const TRACK_ONLY_RECUT_SCORE: f32 = 0.85;

/// The approach settings of track-only mode (only the tracking ones matter).
fn track_only_params() -> ApproachParams {
    let d = ApproachParams::default();
    ApproachParams { track: TrackParams { recut_score: TRACK_ONLY_RECUT_SCORE, ..d.track }, ..d }
}

/// One track-only task in progress.
pub(super) struct TrackRun {
    approach: Approach,
    /// A pair waiting for the estimate of its frame: (frame seq, images).
    pending: Option<(u64, Vec<ImageMsg>)>,
    /// The estimate the last pair was placed with.
    last_pose: Option<Pose3>,
    /// Every image's observation, in order.
    pub(super) observations: Vec<Observation>,
    /// Why tracking stopped, if it lost the target.
    lost: Option<String>,
}

impl Deliberative {
    /// Starts track-only task `i`: no command, the pictures ride along with the navigator's.
    pub(super) fn start_track(&mut self, i: usize) -> Result<(), BusError> {
        let TaskKind::TrackTarget { designation } = self.tasks[i].kind else { return Ok(()) };
        self.tasks[i].command = None;
        let approach = match Approach::new(&self.rover, self.navcam_width, designation, track_only_params()) {
            Ok(a) => a,
            Err(e) => return self.fail_now(i, format!("track only: {e}")),
        };
        let mut run =
            TrackRun { approach, pending: None, last_pose: None, observations: Vec::new(), lost: None };
        if matches!(designation, Designation::Pixel { .. }) {
            // The operator designated a pixel of the last pair: designate on it first.
            let Some(last) = self.last_navcam.clone() else {
                return self.fail_now(i, "no Navcam image to designate a pixel on".into());
            };
            run.pending = Some((last.frame_seq, last.images));
        }
        self.tasks[i].message = "tracking only: waiting for the navigator's sensing".into();
        self.tracks.insert(self.tasks[i].id, run);
        Ok(())
    }

    /// Keeps the pairs taken alongside the navigator's sensing for the track-only tasks.
    pub(super) fn track_frame(&mut self, f: &FrameMsg) {
        if !matches!(f.request().map(|r| r.origin), Some(Origin::Navigator)) || pair_of(&f.images).is_none() {
            return;
        }
        for run in self.tracks.values_mut().filter(|r| r.lost.is_none()) {
            run.pending = Some((f.seq, f.images.clone()));
        }
    }

    /// Tracks the pairs whose estimates have come, ends the tasks whose step is over, and keeps
    /// the platform's ride-along pointing on the target.
    pub(super) fn pump_tracks(&mut self, bus: &mut Bus) -> Result<(), BusError> {
        let step = self.step_range();
        let others_done = step
            .clone()
            .filter(|&j| !matches!(self.tasks[j].kind, TaskKind::TrackTarget { .. }))
            .all(|j| self.tasks[j].state.is_final());
        let mut aim = None;
        for i in step {
            if self.tasks[i].state != TaskState::InProcess {
                continue;
            }
            let id = self.tasks[i].id;
            let Some(run) = self.tracks.get_mut(&id) else { continue };
            if let (Some((seq, _)), Some(e)) = (&run.pending, self.estimate)
                && e.frame_seq >= *seq
            {
                let (seq, images) = run.pending.take().expect("checked");
                let message = track_pair(run, id, seq, &images, &super::approach::pose_of(&e.pose));
                bus.publish(topics::VTT_TRACK, message)?;
            }
            if others_done {
                let images = run.observations.len();
                let (state, message) = match &run.lost {
                    Some(why) => (TaskState::Failure, format!("track only: {why} (after {images} images)")),
                    None if images == 0 => {
                        (TaskState::Failure, "track only: no Navcam pair was taken".into())
                    }
                    None => {
                        let t = run.observations.last().expect("images > 0").target.site;
                        let m = format!(
                            "tracked over all {images} images; target at ({:.2}, {:.2}, {:.2})",
                            t.x, t.y, t.z
                        );
                        (TaskState::Success, m)
                    }
                };
                self.tasks[i].state = state;
                self.tasks[i].message = message;
                continue;
            }
            if run.lost.is_none()
                && aim.is_none()
                && let Some(e) = self.estimate
            {
                let pose = super::approach::pose_of(&e.pose);
                aim = run.approach.aim(&pose).map(|(pan, tilt)| [pan, tilt]);
            }
        }
        if aim != self.ride_along {
            self.ride_along = aim;
            bus.publish(topics::PLATFORM_RIDE_ALONG, RideAlongMsg { navcam: aim })?;
        }
        Ok(())
    }

    /// The target estimates of track-only task `id` along the way (site frame, m).
    pub fn tracked_estimates(&self, id: u64) -> Vec<[f64; 3]> {
        self.tracks
            .get(&id)
            .map(|r| {
                r.observations.iter().map(|o| [o.target.site.x, o.target.site.y, o.target.site.z]).collect()
            })
            .unwrap_or_default()
    }
}

/// Tracks one pair of frame `seq` placed with `pose`; the telemetry message of the image.
fn track_pair(run: &mut TrackRun, task: u64, seq: u64, images: &[ImageMsg], pose: &Pose3) -> VttTrackMsg {
    let left = images.iter().find(|i| i.camera == "navcam_left");
    let head = VttTrackMsg {
        task,
        mode: "track_only".into(),
        image_index: run.observations.len() + 1,
        frame_seq: seq,
        t: left.map_or(0.0, |i| i.t),
        pan: left.map_or(0.0, |i| i.pan),
        tilt: left.map_or(0.0, |i| i.tilt),
        ..VttTrackMsg::default()
    };
    if let Some(last) = run.last_pose {
        let moved = (pose.x - last.x).hypot(pose.y - last.y);
        run.approach.moved_by(moved, angle_diff(pose.yaw, last.yaw));
    }
    let Some((left, right, pan, tilt)) = pair_of(images) else {
        run.lost = Some("the frame has no Navcam pair".into());
        return VttTrackMsg { status: "lost: the frame has no Navcam pair".into(), ..head };
    };
    let pair = NavcamPair { left: &left, right: &right, pan, tilt };
    match run.approach.observe(&pair, pose) {
        Ok(o) => {
            let message = VttTrackMsg::observed(head, &o);
            run.observations.push(o);
            run.last_pose = Some(*pose);
            message
        }
        Err(e) => {
            let why = format!("image {}: {e}", head.image_index);
            run.lost = Some(why.clone());
            VttTrackMsg { status: format!("lost: {why}"), ..head }
        }
    }
}
