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
    /// Start together with the previous task (they must need different resources).
    #[serde(default)]
    pub parallel: bool,
}

/// The first `[[tasks]]` entry that does not make sense, as (field, why); parallel tasks must
/// need different resources.
pub(super) fn check(mission: &Mission) -> Result<(), (String, String)> {
    let positive = |v: f64| v.is_finite() && v > 0.0;
    for (i, t) in mission.tasks.iter().enumerate() {
        let field = |name: &str| format!("tasks[{i}].{name}");
        let has_target = t.x.is_some() || t.y.is_some();
        if t.kind == TaskKindName::Panorama && has_target {
            return Err((field("x"), "a panorama takes no target".into()));
        }
        if t.kind != TaskKindName::Panorama && !(t.x.is_some() && t.y.is_some()) {
            return Err((
                field(if t.x.is_none() { "x" } else { "y" }),
                "this task needs a target x and y".into(),
            ));
        }
        if [t.x, t.y].iter().flatten().any(|v| !v.is_finite()) {
            return Err((field("x"), "target coordinates must be finite numbers".into()));
        }
        if let Some(tol) = t.tolerance_m {
            if t.kind != TaskKindName::DriveTo {
                return Err((field("tolerance_m"), "only a drive_to has an arrival tolerance".into()));
            }
            if !positive(tol) {
                return Err((field("tolerance_m"), "must be positive".into()));
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

impl Mission {
    /// The `[[tasks]]` as plan entries, with targets mapped by `to_local` (goal frame to local).
    pub fn plan_tasks(
        &self,
        to_local: &dyn Fn(f64, f64) -> rovernav_core::Point2,
    ) -> Vec<crate::deliberative::TaskSpec> {
        use crate::deliberative::{TaskKind, TaskSpec};
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
                };
                TaskSpec { kind, parallel: t.parallel }
            })
            .collect()
    }
}
