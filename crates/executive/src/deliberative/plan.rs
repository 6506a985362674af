//! Presenting the plan's tasks to the reflexive layer: one command per task (two for an arm
//! task that first turns the rover), and withdrawing them.

use super::{Deliberative, TaskKind};
use crate::messages::{
    ArmAction, ArmTaskMsg, CancelMsg, CommandMsg, DriveToMsg, MotionRequest, Origin, SenseMsg, TaskState,
    topics,
};
use rovernav_bus::{Bus, BusError};
use rovernav_core::{Goal, Point2, angle_diff, wrap_angle};

/// Mast pans of a panorama (rad): eight 45 deg wedges all around.
const PANORAMA_PANS: usize = 8;
/// Nearest target the mast can image (m).
const MAST_MIN_RANGE_M: f64 = 0.5;
/// Bearing of an arm target beyond which the rover first turns to face it (rad).
const ARM_AIM_TOLERANCE: f64 = 0.17;

impl Deliberative {
    /// Presents task `i` to the reflexive layer.
    pub(super) fn start(&mut self, bus: &mut Bus, i: usize) -> Result<(), BusError> {
        let cmd = self.command_id();
        let kind = self.tasks[i].kind;
        self.tasks[i].command = Some(cmd);
        self.tasks[i].aiming = false;
        self.tasks[i].state = TaskState::InProcess;
        self.tasks[i].outcome = None;
        self.tasks[i].message = "started".into();
        match kind {
            TaskKind::DriveTo { target, tolerance } => {
                self.fp.set_target(Some(target));
                let goal = Goal {
                    position: target,
                    tolerance,
                    waypoints: Vec::new(),
                    keep_out: self.config.keep_out.clone(),
                };
                bus.publish(topics::EXECUTIVE_DRIVE_TO, DriveToMsg { task: cmd, goal })?;
            }
            TaskKind::CloudWatch(_) | TaskKind::DustDevilWatch(_) => return self.start_watch(bus, i, cmd),
            TaskKind::Panorama => {
                let requests = (0..PANORAMA_PANS)
                    .map(|k| SenseMsg::Mast {
                        pan: wrap_angle(k as f64 * std::f64::consts::TAU / PANORAMA_PANS as f64),
                    })
                    .collect();
                let request = MotionRequest {
                    id: cmd,
                    origin: Origin::Task(cmd),
                    command: CommandMsg::Sense(requests),
                };
                bus.publish(topics::EXECUTIVE_MOTION, request)?;
            }
            TaskKind::ScienceImage { target } => {
                let Some(e) = self.estimate else {
                    return self.fail_now(i, "no pose estimate to aim the mast".into());
                };
                let offset = target.sub(Point2::new(e.pose.x, e.pose.y));
                let range = offset.norm();
                if !(MAST_MIN_RANGE_M..=self.config.mast_range_m).contains(&range) {
                    let why = format!(
                        "target {range:.2} m away, outside the mast's {MAST_MIN_RANGE_M:.1}-{:.1} m range",
                        self.config.mast_range_m
                    );
                    return self.fail_now(i, why);
                }
                let pan = angle_diff(offset.angle(), e.pose.yaw);
                let request = MotionRequest {
                    id: cmd,
                    origin: Origin::Task(cmd),
                    command: CommandMsg::Sense(vec![SenseMsg::Mast { pan }]),
                };
                bus.publish(topics::EXECUTIVE_MOTION, request)?;
            }
            TaskKind::PlaceInstrument { target } | TaskKind::Scoop { target } => {
                let Some(e) = self.estimate else {
                    return self.fail_now(i, "no pose estimate to face the target".into());
                };
                let bearing = angle_diff(target.sub(Point2::new(e.pose.x, e.pose.y)).angle(), e.pose.yaw);
                if bearing.abs() <= ARM_AIM_TOLERANCE {
                    return self.deploy_arm(bus, i);
                }
                // Elaborate: face the target first, then deploy the arm.
                self.tasks[i].aiming = true;
                self.tasks[i].message = format!("turning {:.0} deg to face the target", bearing.to_degrees());
                let request = MotionRequest {
                    id: cmd,
                    origin: Origin::Task(cmd),
                    command: CommandMsg::Turn { angle: bearing },
                };
                bus.publish(topics::EXECUTIVE_MOTION, request)?;
            }
            TaskKind::ApproachTarget { .. } => return self.start_approach(bus, i, cmd),
            TaskKind::TrackTarget { .. } => return self.start_track(i),
        }
        Ok(())
    }

    /// Presents an arm task's operation to the tooling arm as a new command.
    pub(super) fn deploy_arm(&mut self, bus: &mut Bus, i: usize) -> Result<(), BusError> {
        let (action, target) = match self.tasks[i].kind {
            TaskKind::Scoop { target } => (ArmAction::Scoop, target),
            TaskKind::PlaceInstrument { target } => (ArmAction::PlaceInstrument, target),
            _ => return Ok(()),
        };
        let cmd = self.command_id();
        self.tasks[i].command = Some(cmd);
        self.tasks[i].message = "deploying the arm".into();
        bus.publish(topics::ARM_COMMAND, ArmTaskMsg { task: cmd, action, target: [target.x, target.y] })
    }

    pub(super) fn fail_now(&mut self, i: usize, why: String) -> Result<(), BusError> {
        self.tasks[i].state = TaskState::Failure;
        self.tasks[i].message = why;
        Ok(())
    }

    /// Withdraws a task's command from the reflexive layer; the task becomes `to`.
    pub(super) fn withdraw(
        &mut self,
        bus: &mut Bus,
        i: usize,
        to: TaskState,
        why: &str,
    ) -> Result<(), BusError> {
        if let Some(cmd) = self.tasks[i].command.take()
            && self.tasks[i].state == TaskState::InProcess
        {
            bus.publish(topics::EXECUTIVE_CANCEL, CancelMsg { task: cmd })?;
        }
        self.tasks[i].state = to;
        self.tasks[i].message = why.to_string();
        Ok(())
    }
}
