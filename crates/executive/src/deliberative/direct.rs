//! The operator's direct commands (`drive`, `turn`, `motor`, `navcam`) followed to their end: each is answered once
//! the platform has executed it, with its completion or the reason it stopped (the guard that
//! tripped, a hazard contact, a stall) and how far it went, or with why it never ran (an
//! emergency stop, the mission's end). Tasks the operator queued (`place`, `track`) are answered
//! likewise when they end: their final state and its message.
//!
//! How far is judged from the pose estimate (before the command and after the estimator has
//! integrated the command's frame), never from the simulator's truth, which the autonomy does
//! not have.

use super::Deliberative;
use crate::messages::{FrameMsg, Origin, topics};
use rovernav_bus::{Bus, BusError};
use rovernav_core::{Pose3, wrap_angle};

/// A direct motion the operator asked for, until it is answered.
#[derive(Clone, Debug)]
pub(super) struct DirectMotion {
    /// The motion request's id.
    pub id: u64,
    /// The command as the operator would type it (`drive 1`).
    pub text: String,
    /// What was asked: a distance (m) or an angle (rad).
    pub asked: Asked,
    /// The estimate when the command was issued.
    pub start: Option<Pose3>,
    /// Once executed: the frame's number and why the motion stopped, if it did.
    pub executed: Option<(u64, Option<String>)>,
    /// The images the executed command returned (camera and size), for `navcam`.
    pub images: Vec<String>,
}

/// What a direct motion asked for.
#[derive(Clone, Copy, Debug)]
pub(super) enum Asked {
    /// Drive this far (m; negative backwards).
    Drive(f64),
    /// Turn by this angle (rad).
    Turn(f64),
    /// Run one side's motor, the other held: a pivot about the held wheels.
    Motor {
        /// The driven side's wheel travel asked (m; negative backwards).
        distance: f64,
        /// Track width: metres between the left and right wheels.
        track: f64,
    },
    /// Take pictures (no motion).
    Pictures,
}

/// The guard or event a platform's `motion_stopped` text names, in the operator's words.
pub fn stop_cause(why: &str) -> &'static str {
    if why.contains("proximity") {
        "the proximity guard tripped"
    } else if why.contains("tilt") {
        "the tilt guard tripped"
    } else if why.starts_with("stall") {
        "the wheels stalled"
    } else if why.contains("terrain model") {
        "the rover reached the edge of the terrain model"
    } else {
        "the rover met a hazard"
    }
}

impl Deliberative {
    /// Remembers a direct motion just requested, to answer it when it has run.
    pub(super) fn follow_direct(&mut self, id: u64, text: String, asked: Asked) {
        let start = self.estimate.as_ref().map(|e| e.pose);
        self.direct.push(DirectMotion { id, text, asked, start, executed: None, images: Vec::new() });
    }

    /// Notes a frame that executed a followed direct motion.
    pub(super) fn direct_frame(&mut self, f: &FrameMsg) {
        let Some(r) = f.request().filter(|r| r.origin == Origin::Operator) else { return };
        if let Some(d) = self.direct.iter_mut().find(|d| d.id == r.id && d.executed.is_none()) {
            let p = &f.proximity;
            let sides: Vec<&str> = [(p.left(), "left"), (p.middle(), "middle"), (p.right(), "right")]
                .into_iter()
                .filter_map(|(on, side)| on.then_some(side))
                .collect();
            // Where the proximity guard saw something: the sensor clusters that triggered.
            let why = f.motion_stopped.as_ref().map(|w| match w.contains("proximity") && !sides.is_empty() {
                true => format!("{w}, {} sensors", sides.join(" and ")),
                false => w.clone(),
            });
            d.executed = Some((f.seq, why));
            d.images = f.images.iter().map(|i| format!("{} {}x{}", i.camera, i.width, i.height)).collect();
        }
    }

    /// Answers every executed direct motion whose frame the estimate has integrated.
    pub(super) fn answer_direct(&mut self, bus: &mut Bus) -> Result<(), BusError> {
        let Some(now) = self.estimate.as_ref().map(|e| (e.frame_seq, e.pose)) else { return Ok(()) };
        let (ready, waiting): (Vec<_>, Vec<_>) = std::mem::take(&mut self.direct)
            .into_iter()
            .partition(|d| d.executed.as_ref().is_some_and(|(seq, _)| *seq <= now.0));
        self.direct = waiting;
        for d in ready {
            bus.publish(topics::OPERATOR_REPLY, outcome_text(&d, &now.1))?;
        }
        Ok(())
    }

    /// Answers every direct motion still waiting: it will not run (or not be judged) because
    /// of `why`.
    pub(super) fn abandon_direct(&mut self, bus: &mut Bus, why: &str) -> Result<(), BusError> {
        for d in std::mem::take(&mut self.direct) {
            let text = match (&d.executed, self.estimate.as_ref()) {
                (Some(_), Some(e)) => format!("{}; then {why}", outcome_text(&d, &e.pose)),
                _ => format!("`{}` not executed: {why}", d.text),
            };
            bus.publish(topics::OPERATOR_REPLY, text)?;
        }
        Ok(())
    }

    /// Answers every task the operator queued that has ended; with `over` (the mission's end),
    /// every other one too, as not done.
    pub(super) fn answer_tasks(&mut self, bus: &mut Bus, over: Option<&str>) -> Result<(), BusError> {
        let mut waiting = Vec::new();
        for id in std::mem::take(&mut self.operator_tasks) {
            let Some(t) = self.tasks.iter().find(|t| t.id == id) else { continue };
            let text = if t.state.is_final() {
                let message = if t.message.is_empty() { String::new() } else { format!(": {}", t.message) };
                format!("task {id} ({}) {}{message}", t.kind.describe(), t.state.as_str())
            } else if let Some(why) = over {
                format!("task {id} ({}) not done: {why}", t.kind.describe())
            } else {
                waiting.push(id);
                continue;
            };
            bus.publish(topics::OPERATOR_REPLY, text)?;
        }
        self.operator_tasks = waiting;
        Ok(())
    }
}

/// The answer to an executed direct motion, the estimate `end` after it.
fn outcome_text(d: &DirectMotion, end: &Pose3) -> String {
    let stopped = d.executed.as_ref().and_then(|(_, why)| why.as_deref());
    let (done, asked) = match (d.asked, d.start) {
        (Asked::Pictures, _) => {
            return match (stopped, d.images.len()) {
                (Some(why), _) => format!("`{}` failed: {why}", d.text),
                (None, 0) => format!("`{}` completed, but no image came back", d.text),
                (None, n) => {
                    format!("`{}` completed: {n} images ({}) on /camera/image", d.text, d.images.join(", "))
                }
            };
        }
        (_, None) => {
            return match stopped {
                Some(why) => format!("`{}` stopped: {} ({why})", d.text, stop_cause(why)),
                None => format!("`{}` completed", d.text),
            };
        }
        (Asked::Drive(m), Some(start)) => {
            (format!("{:.2} m", (end.x - start.x).hypot(end.y - start.y)), format!("{:.2} m", m.abs()))
        }
        (Asked::Turn(a), Some(start)) => (
            format!("{:.1} deg", wrap_angle(end.yaw - start.yaw).to_degrees()),
            format!("{:.1} deg", a.to_degrees()),
        ),
        (Asked::Motor { distance, track }, Some(start)) => {
            // The driven side's travel is the turn times the track (the held side stays put).
            let turned = wrap_angle(end.yaw - start.yaw);
            (
                format!(
                    "{:.2} m of wheel travel (turned {:.1} deg)",
                    turned.abs() * track,
                    turned.to_degrees()
                ),
                format!("{:.2} m", distance.abs()),
            )
        }
    };
    match stopped {
        Some(why) => {
            format!(
                "`{}` stopped after {done} of {asked}: {} ({why}; by the pose estimate)",
                d.text,
                stop_cause(why)
            )
        }
        None => format!("`{}` completed: {done} by the pose estimate", d.text),
    }
}
