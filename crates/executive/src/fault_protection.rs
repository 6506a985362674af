//! Fault protection: decides, from what the components report and from the sensor-derived
//! estimate, when the rover must stop and ask the operators for help.
//!
//! Flight rovers stop at the first sign of trouble and wait for the ground (paper 001 asks for
//! help when diverted too far; paper 004's deliberative layer monitors every command's state).
//! The diagnosis uses sensor data only: a sensor server or the pose estimator going to Failure
//! (they judge their own data), or no progress of the estimate toward the current drive target
//! over many commands. The reaction (stop every component, end the mission with
//! `help_requested`) belongs to the deliberative layer.

use crate::components::JausState;
use crate::messages::ComponentStatusMsg;
use rovernav_core::Point2;
use serde::{Deserialize, Serialize};

/// What went wrong, as fault protection classifies it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FaultKind {
    /// A sensor stopped giving usable data (silent camera, NaN compass).
    SensorFault,
    /// A wheel does not turn.
    StuckWheel,
    /// The pose estimate is unusable.
    LocalizationFailure,
    /// The rover does not get closer to where it is driving.
    NoProgress,
    /// The body keeps meeting the terrain (the navigator drives into what it does not see).
    HazardContact,
    /// Any other component failed.
    ComponentFailure,
}

impl FaultKind {
    /// A stable lower-case name.
    pub fn as_str(self) -> &'static str {
        match self {
            FaultKind::SensorFault => "sensor_fault",
            FaultKind::StuckWheel => "stuck_wheel",
            FaultKind::LocalizationFailure => "localization_failure",
            FaultKind::NoProgress => "no_progress",
            FaultKind::HazardContact => "hazard_contact",
            FaultKind::ComponentFailure => "component_failure",
        }
    }
}

/// A fault and where it was seen.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Diagnosis {
    /// Class.
    pub kind: FaultKind,
    /// The component that reported it, if one did.
    pub component: Option<String>,
    /// What was seen, in words.
    pub message: String,
}

/// Thresholds of fault protection.
#[derive(Clone, Debug, PartialEq)]
pub struct FaultProtectionConfig {
    /// Commands without the estimate getting `progress_m` closer to the drive target before
    /// declaring no progress.
    pub no_progress_commands: u64,
    /// Improvement of the best distance to the target that counts as progress (m).
    pub progress_m: f64,
}

impl Default for FaultProtectionConfig {
    fn default() -> Self {
        // On the default yard (seeds 1-3) the longest stretch without getting half a metre
        // closer that still ended at the goal was 267 commands (the MRPTA navigator detouring);
        // 400 leaves every healthy navigator alone and still stops a rover going nowhere.
        Self { no_progress_commands: 400, progress_m: 0.5 }
    }
}

/// The fault monitor.
#[derive(Clone, Debug)]
pub struct FaultProtection {
    config: FaultProtectionConfig,
    target: Option<Point2>,
    best: f64,
    since_best: u64,
}

impl FaultProtection {
    /// A monitor with no drive target.
    pub fn new(config: FaultProtectionConfig) -> Self {
        Self { config, target: None, best: f64::INFINITY, since_best: 0 }
    }

    /// The kind of fault a component's failure means.
    pub fn kind_of(component: &str) -> FaultKind {
        match component {
            "range-sensors" | "inertial-sensors" => FaultKind::SensorFault,
            "wheel-odometry" => FaultKind::StuckWheel,
            "contact-monitor" => FaultKind::HazardContact,
            "pose-estimator" => FaultKind::LocalizationFailure,
            _ => FaultKind::ComponentFailure,
        }
    }

    /// Judges a component's status.
    pub fn on_status(&mut self, status: &ComponentStatusMsg) -> Option<Diagnosis> {
        (status.state == JausState::Failure).then(|| Diagnosis {
            kind: Self::kind_of(&status.component),
            component: Some(status.component.clone()),
            message: format!("{} failed: {}", status.component, status.message),
        })
    }

    /// Starts watching progress toward a new drive target (`None` when not driving).
    pub fn set_target(&mut self, target: Option<Point2>) {
        if target != self.target {
            self.target = target;
            self.best = f64::INFINITY;
            self.since_best = 0;
        }
    }

    /// Judges the estimate after one executed command.
    pub fn on_command(&mut self, estimate: Point2) -> Option<Diagnosis> {
        let target = self.target?;
        let d = estimate.dist(target);
        if !d.is_finite() {
            return Some(Diagnosis {
                kind: FaultKind::LocalizationFailure,
                component: None,
                message: "the pose estimate is not finite".into(),
            });
        }
        if d < self.best - self.config.progress_m || self.best.is_infinite() {
            self.best = d;
            self.since_best = 0;
            return None;
        }
        self.since_best += 1;
        (self.since_best >= self.config.no_progress_commands).then(|| Diagnosis {
            kind: FaultKind::NoProgress,
            component: None,
            message: format!(
                "no progress: {} commands without getting {:.1} m closer to ({:.2}, {:.2}); still {:.2} m away",
                self.since_best, self.config.progress_m, target.x, target.y, d
            ),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn status(component: &str, state: JausState, message: &str) -> ComponentStatusMsg {
        ComponentStatusMsg { component: component.into(), state, message: message.into(), time_s: 1.0 }
    }

    #[test]
    fn a_failed_component_is_classified_by_what_it_serves() {
        let mut fp = FaultProtection::new(FaultProtectionConfig::default());
        assert_eq!(fp.on_status(&status("range-sensors", JausState::Ready, "")), None);
        let d = fp.on_status(&status("wheel-odometry", JausState::Failure, "left stuck")).unwrap();
        assert_eq!(d.kind, FaultKind::StuckWheel);
        assert!(d.message.contains("wheel-odometry") && d.message.contains("left stuck"));
        for (c, k) in [
            ("inertial-sensors", FaultKind::SensorFault),
            ("range-sensors", FaultKind::SensorFault),
            ("pose-estimator", FaultKind::LocalizationFailure),
            ("navigator", FaultKind::ComponentFailure),
        ] {
            assert_eq!(fp.on_status(&status(c, JausState::Failure, "x")).unwrap().kind, k);
        }
    }

    #[test]
    fn no_progress_is_declared_after_the_configured_commands_and_progress_resets_it() {
        let config = FaultProtectionConfig { no_progress_commands: 5, progress_m: 0.5 };
        let mut fp = FaultProtection::new(config);
        assert_eq!(fp.on_command(Point2::new(0.0, 0.0)), None, "no target, no judgement");
        fp.set_target(Some(Point2::new(10.0, 0.0)));
        assert_eq!(fp.on_command(Point2::new(0.0, 0.0)), None);
        // Wandering sideways and creeping 0.1 m at a time is not progress.
        for k in 1..5 {
            assert_eq!(fp.on_command(Point2::new(0.1 * k as f64, 1.0)), None, "command {k}");
        }
        let d = fp.on_command(Point2::new(0.0, -1.0)).expect("fifth command without progress");
        assert_eq!(d.kind, FaultKind::NoProgress);
        assert!(d.message.contains("(10.00, 0.00)"), "{}", d.message);
        // Real progress resets the count; a new target restarts the watch.
        let mut fp = FaultProtection::new(FaultProtectionConfig { no_progress_commands: 3, progress_m: 0.5 });
        fp.set_target(Some(Point2::new(10.0, 0.0)));
        for x in [0.0, 1.0, 2.0, 3.0, 4.0, 5.0] {
            assert_eq!(fp.on_command(Point2::new(x, 0.0)), None);
        }
        assert_eq!(fp.on_command(Point2::new(5.0, 0.0)), None);
        assert_eq!(fp.on_command(Point2::new(5.0, 0.0)), None);
        fp.set_target(Some(Point2::new(0.0, 0.0)));
        assert_eq!(fp.on_command(Point2::new(5.0, 0.0)), None);
        assert_eq!(fp.on_command(Point2::new(5.0, 0.0)), None);
        assert_eq!(fp.on_command(Point2::new(5.0, 0.0)), None);
        assert!(fp.on_command(Point2::new(5.0, 0.0)).is_some());
    }

    #[test]
    fn a_non_finite_estimate_is_a_localization_failure() {
        let mut fp = FaultProtection::new(FaultProtectionConfig::default());
        fp.set_target(Some(Point2::new(1.0, 1.0)));
        assert_eq!(fp.on_command(Point2::new(f64::NAN, 0.0)).unwrap().kind, FaultKind::LocalizationFailure);
    }
}
