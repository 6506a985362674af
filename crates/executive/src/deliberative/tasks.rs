//! The plan's tasks: what each does, the resources it occupies, and its execution state.

use crate::messages::TaskState;
use rovernav_core::Point2;
pub use rovernav_vision::tracking::Designation;

/// What a task does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TaskKind {
    /// Drive to a point (a waypoint or the goal).
    DriveTo {
        /// Where (world frame, m).
        target: Point2,
        /// Arrival tolerance (m).
        tolerance: f64,
    },
    /// Stop and watch the sky for clouds: Navcam images, the cloud detector, the triage.
    CloudWatch(crate::deliberative::WatchSpec),
    /// Stop and watch the horizon for dust devils: a Navcam sequence, the dust-devil detector,
    /// the triage.
    DustDevilWatch(crate::deliberative::WatchSpec),
    /// Image all around with the mast.
    Panorama,
    /// Image a target with the mast.
    ScienceImage {
        /// Target (world frame, m).
        target: Point2,
    },
    /// Place an instrument on a target in front of the rover.
    PlaceInstrument {
        /// Target (world frame, m).
        target: Point2,
    },
    /// Scoop a soil sample at a target in front of the rover.
    Scoop {
        /// Target (world frame, m).
        target: Point2,
    },
    /// Drive to a designated target by visual target tracking and stop at a stand-off.
    ApproachTarget {
        /// The target: a Navcam pixel or a site-frame point.
        designation: Designation,
        /// Horizontal stand-off from the rover's origin to the target (m).
        standoff: f64,
    },
    /// Track a designated target by visual target tracking while the tasks it runs in parallel
    /// with drive ("track only", paper 003 section 3's sol-992 checkout): the Navcam pairs ride
    /// along with the navigator's own sensing, and nothing it does changes the motion.
    TrackTarget {
        /// The target: a Navcam pixel or a site-frame point.
        designation: Designation,
    },
}

/// Something a task occupies while it runs; parallel tasks must not share one.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Resource {
    /// The wheels (driving moves them, arm work needs them still).
    Wheels,
    /// The mast cameras (navigators sense with them too).
    Mast,
    /// The tooling arm.
    Arm,
}

impl TaskKind {
    /// A stable lower-case name (the mission file's `kind`).
    pub fn name(&self) -> &'static str {
        match self {
            TaskKind::DriveTo { .. } => "drive_to",
            TaskKind::CloudWatch(_) => "cloud_watch",
            TaskKind::DustDevilWatch(_) => "dust_devil_watch",
            TaskKind::Panorama => "panorama",
            TaskKind::ScienceImage { .. } => "science_image",
            TaskKind::PlaceInstrument { .. } => "place_instrument",
            TaskKind::Scoop { .. } => "scoop",
            TaskKind::ApproachTarget { .. } => "approach_target",
            TaskKind::TrackTarget { .. } => "track_target",
        }
    }

    /// The task's target, if it has one.
    pub fn target(&self) -> Option<Point2> {
        match *self {
            TaskKind::CloudWatch(_) | TaskKind::DustDevilWatch(_) => None,
            TaskKind::DriveTo { target, .. }
            | TaskKind::ScienceImage { target }
            | TaskKind::PlaceInstrument { target }
            | TaskKind::Scoop { target } => Some(target),
            TaskKind::ApproachTarget { designation: Designation::Site { x, y, .. }, .. }
            | TaskKind::TrackTarget { designation: Designation::Site { x, y, .. } } => {
                Some(Point2::new(x, y))
            }
            TaskKind::Panorama | TaskKind::ApproachTarget { .. } | TaskKind::TrackTarget { .. } => None,
        }
    }

    /// What the task occupies.
    pub fn resources(&self) -> &'static [Resource] {
        match self {
            TaskKind::DriveTo { .. } | TaskKind::ApproachTarget { .. } => &[Resource::Wheels, Resource::Mast],
            // The rover stands still while it watches.
            TaskKind::CloudWatch(_) | TaskKind::DustDevilWatch(_) => &[Resource::Wheels, Resource::Mast],
            TaskKind::Panorama | TaskKind::ScienceImage { .. } => &[Resource::Mast],
            TaskKind::PlaceInstrument { .. } | TaskKind::Scoop { .. } => &[Resource::Arm, Resource::Wheels],
            // Its pictures ride along with the navigator's sensing: it occupies nothing.
            TaskKind::TrackTarget { .. } => &[],
        }
    }

    pub(super) fn describe(&self) -> String {
        if let TaskKind::ApproachTarget { designation: Designation::Pixel { row, col }, .. }
        | TaskKind::TrackTarget { designation: Designation::Pixel { row, col } } = self
        {
            return format!("{} (pixel row {row:.1}, col {col:.1})", self.name());
        }
        match self.target() {
            Some(t) => format!("{} ({:.2}, {:.2})", self.name(), t.x, t.y),
            None => self.name().to_string(),
        }
    }
}

/// One entry of a mission plan.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TaskSpec {
    /// What to do.
    pub kind: TaskKind,
    /// Start together with the previous task.
    pub parallel: bool,
}

/// Checks that parallel tasks do not share a resource; the error gives the offending task's
/// index and why.
pub fn validate_plan(tasks: &[TaskSpec]) -> Result<(), (usize, String)> {
    let mut group_start = 0;
    for (i, t) in tasks.iter().enumerate() {
        if !t.parallel {
            group_start = i;
            continue;
        }
        if i == 0 {
            return Err((0, "the first task has no task before it to run in parallel with".into()));
        }
        for other in &tasks[group_start..i] {
            if let Some(r) = t.kind.resources().iter().find(|r| other.kind.resources().contains(r)) {
                return Err((
                    i,
                    format!(
                        "cannot run in parallel with the {} before it: both need the {r:?}",
                        other.kind.name()
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// Where a task came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    /// A waypoint before the goal.
    Waypoint,
    /// The goal.
    Goal,
    /// An extra task of the mission file.
    Extra,
}

/// A task of the plan with its execution state.
#[derive(Clone, Debug, PartialEq)]
pub struct Task {
    /// Plan id (stable).
    pub id: u64,
    /// What it does.
    pub kind: TaskKind,
    /// Starts together with the previous task.
    pub parallel: bool,
    /// Where it came from.
    pub role: Role,
    /// Execution state.
    pub state: TaskState,
    /// The last word on it.
    pub message: String,
    /// For a finished drive: the navigator's outcome name.
    pub outcome: Option<String>,
    /// Id of the command currently standing for this task in the reflexive layer.
    pub(super) command: Option<u64>,
    /// An arm task is turning the rover to face its target before deploying the arm.
    pub(super) aiming: bool,
}

impl Task {
    /// Id of the command standing (or last standing) for this task in the reflexive layer.
    pub fn command(&self) -> Option<u64> {
        self.command
    }
}
