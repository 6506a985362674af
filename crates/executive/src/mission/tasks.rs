//! The mission file's `[[tasks]]`: what to do after reaching the goal.

use super::Mission;
use serde::Deserialize;

/// The kinds of `[[tasks]]` entry.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum TaskKindName {
    /// Drive to `x`, `y`.
    DriveTo,
    /// Image all around with the mast.
    Panorama,
    /// Image the target `x`, `y` with the mast.
    ScienceImage,
    /// Place an instrument on the target `x`, `y` (in the arm's reach).
    PlaceInstrument,
    /// Scoop a sample at the target `x`, `y` (in the arm's reach).
    Scoop,
    /// Stop and watch the sky for clouds (`frames`, `interval_s`, `pan_deg`, `tilt_deg`, `budget`).
    CloudWatch,
    /// Stop and watch the horizon for dust devils (the same fields).
    DustDevilWatch,
    /// Drive to the target `x`, `y`, `z` by visual target tracking, stopping `standoff_m` short.
    ApproachTarget,
    /// Track the target `x`, `y`, `z` by visual target tracking while the task before it drives
    /// (`parallel = true`), without influencing the motion ("track only").
    TrackTarget,
}

/// One `[[tasks]]` entry.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TaskSpecToml {
    /// What to do.
    pub kind: TaskKindName,
    /// Target east (m), in the goal's frame; every kind but `panorama` needs one.
    pub x: Option<f64>,
    /// Target north (m), in the goal's frame.
    pub y: Option<f64>,
    /// Arrival tolerance of a `drive_to` (m; default: the goal's).
    pub tolerance_m: Option<f64>,
    /// Images of a watch (default: 4 for clouds, 10 for dust devils).
    pub frames: Option<u32>,
    /// Seconds asked between a watch's images.
    pub interval_s: Option<f64>,
    /// Mast pan of a watch (deg, counter-clockwise from forward; default 0).
    pub pan_deg: Option<f64>,
    /// Mast tilt of a watch (deg, up; default 20 for clouds, -2 for dust devils).
    pub tilt_deg: Option<f64>,
    /// Downlink budget of a watch (fraction of its raw volume; default 0.1).
    pub budget: Option<f64>,
    /// Target height of an `approach_target` or a `track_target` (m, site frame; default 0).
    pub z: Option<f64>,
    /// Stand-off of an `approach_target` (m; default 1).
    pub standoff_m: Option<f64>,
    /// Start together with the previous task (they must need different resources).
    #[serde(default)]
    pub parallel: bool,
}

/// The first `[[tasks]]` entry that does not make sense, as (field, why); parallel tasks must
/// need different resources.
pub(super) fn check(mission: &Mission) -> Result<(), (String, String)> {
    for (i, t) in mission.tasks.iter().enumerate() {
        let field = |name: &str| format!("tasks[{i}].{name}");
        let has_target = t.x.is_some() || t.y.is_some();
        let untargeted = matches!(
            t.kind,
            TaskKindName::Panorama | TaskKindName::CloudWatch | TaskKindName::DustDevilWatch
        );
        if untargeted && has_target {
            return Err((field("x"), "a panorama or a watch takes no target".into()));
        }
        if !(untargeted || t.x.is_some() && t.y.is_some()) {
            return Err((
                field(if t.x.is_none() { "x" } else { "y" }),
                "this task needs a target x and y".into(),
            ));
        }
        if [t.x, t.y].iter().flatten().any(|v| !v.is_finite()) {
            return Err((field("x"), "target coordinates must be finite numbers".into()));
        }
        let tracking = matches!(t.kind, TaskKindName::ApproachTarget | TaskKindName::TrackTarget);
        if (t.z.is_some() && !tracking) || (t.standoff_m.is_some() && t.kind != TaskKindName::ApproachTarget)
        {
            let name = if t.z.is_some() { "z" } else { "standoff_m" };
            return Err((field(name), "only an approach_target (and a track_target's z) takes it".into()));
        }
        if t.kind == TaskKindName::TrackTarget && !t.parallel {
            return Err((
                field("parallel"),
                "a track_target tracks while the task before it drives: set parallel = true".into(),
            ));
        }
        if t.z.is_some_and(|z| !z.is_finite()) {
            return Err((field("z"), "must be a finite number".into()));
        }
        if t.standoff_m.is_some_and(|d| !(d.is_finite() && d >= 0.0)) {
            return Err((field("standoff_m"), "must be a non-negative number of metres".into()));
        }
        if let Some(kind) = t.watch_kind() {
            if let Err((name, why)) = t.watch_spec(kind).check(kind) {
                return Err((field(name), why));
            }
        } else if t.frames.is_some()
            || [t.interval_s, t.pan_deg, t.tilt_deg, t.budget].iter().any(Option::is_some)
        {
            return Err((
                field("frames"),
                "frames, interval_s, pan_deg, tilt_deg and budget are a watch's".into(),
            ));
        }
        if let Some(tol) = t.tolerance_m {
            if t.kind != TaskKindName::DriveTo {
                return Err((field("tolerance_m"), "only a drive_to has an arrival tolerance".into()));
            }
            if let Err(why) = super::check::tolerance(tol) {
                return Err((field("tolerance_m"), why));
            }
        }
    }
    // Resource conflicts of parallel tasks; the plan's drives come before these tasks.
    let mut plan = vec![crate::deliberative::TaskSpec {
        kind: crate::deliberative::TaskKind::DriveTo {
            target: rovernav_core::Point2::new(0.0, 0.0),
            tolerance: 1.0,
        },
        parallel: false,
    }];
    plan.extend(mission.plan_tasks(&|x, y| rovernav_core::Point2::new(x, y)));
    if let Err((i, why)) = crate::deliberative::validate_plan(&plan) {
        return Err((format!("tasks[{}].parallel", i - 1), why));
    }
    Ok(())
}

impl TaskSpecToml {
    /// The watch this entry asks for, if it is one.
    fn watch_kind(&self) -> Option<crate::deliberative::WatchKind> {
        use crate::deliberative::WatchKind;
        match self.kind {
            TaskKindName::CloudWatch => Some(WatchKind::Clouds),
            TaskKindName::DustDevilWatch => Some(WatchKind::DustDevils),
            _ => None,
        }
    }

    /// A watch's settings: the entry's fields over the defaults of `kind`.
    fn watch_spec(&self, kind: crate::deliberative::WatchKind) -> crate::deliberative::WatchSpec {
        let d = crate::deliberative::WatchSpec::default_for(kind);
        crate::deliberative::WatchSpec {
            frames: self.frames.unwrap_or(d.frames),
            interval_s: self.interval_s.unwrap_or(d.interval_s),
            pan: self.pan_deg.map_or(d.pan, f64::to_radians),
            tilt: self.tilt_deg.map_or(d.tilt, f64::to_radians),
            budget: self.budget.unwrap_or(d.budget),
        }
    }
}

impl Mission {
    /// The `[[tasks]]` as plan entries, with targets mapped by `to_local` (goal frame to local).
    pub fn plan_tasks(
        &self,
        to_local: &dyn Fn(f64, f64) -> rovernav_core::Point2,
    ) -> Vec<crate::deliberative::TaskSpec> {
        use crate::deliberative::{TaskKind, TaskSpec, WatchKind};
        self.tasks
            .iter()
            .map(|t| {
                let target = to_local(t.x.unwrap_or(f64::NAN), t.y.unwrap_or(f64::NAN));
                let kind = match t.kind {
                    TaskKindName::DriveTo => TaskKind::DriveTo {
                        target,
                        tolerance: t.tolerance_m.unwrap_or(self.goal.tolerance_m),
                    },
                    TaskKindName::Panorama => TaskKind::Panorama,
                    TaskKindName::ScienceImage => TaskKind::ScienceImage { target },
                    TaskKindName::PlaceInstrument => TaskKind::PlaceInstrument { target },
                    TaskKindName::Scoop => TaskKind::Scoop { target },
                    TaskKindName::CloudWatch => TaskKind::CloudWatch(t.watch_spec(WatchKind::Clouds)),
                    TaskKindName::DustDevilWatch => {
                        TaskKind::DustDevilWatch(t.watch_spec(WatchKind::DustDevils))
                    }
                    TaskKindName::ApproachTarget => TaskKind::ApproachTarget {
                        designation: crate::deliberative::Designation::Site {
                            x: target.x,
                            y: target.y,
                            z: t.z.unwrap_or(0.0),
                        },
                        standoff: t.standoff_m.unwrap_or(crate::deliberative::TRACK_STANDOFF_M),
                    },
                    TaskKindName::TrackTarget => TaskKind::TrackTarget {
                        designation: crate::deliberative::Designation::Site {
                            x: target.x,
                            y: target.y,
                            z: t.z.unwrap_or(0.0),
                        },
                    },
                };
                TaskSpec { kind, parallel: t.parallel }
            })
            .collect()
    }
}
