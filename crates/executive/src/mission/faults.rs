//! The mission file's `[[faults]]`: what the simulator makes fail, and when.

use super::Mission;
use serde::Deserialize;

/// The kinds of `[[faults]]` entry.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum FaultKindName {
    /// A range sensor returns images without points (`sensor` names it).
    SilentSensor,
    /// The wheels of one side stop turning (`side` names it).
    StalledWheel,
    /// The compass reads NaN.
    CompassNan,
}

/// Range sensors a fault can silence.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum SensorName {
    /// Mast stereo pair.
    Mast,
    /// Forward body stereo pair.
    BodyFront,
    /// Rear body stereo pair.
    BodyRear,
    /// Nodding LIDAR.
    Lidar,
}

/// A side of the rover.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum Side {
    /// Left.
    Left,
    /// Right.
    Right,
}

/// One `[[faults]]` entry: what fails and when (default: from the start).
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FaultSpec {
    /// What fails.
    pub kind: FaultKindName,
    /// For `silent_sensor`: which sensor.
    pub sensor: Option<SensorName>,
    /// For `stalled_wheel`: which side.
    pub side: Option<Side>,
    /// Fail before this command (commands count from 1; 0 is before the first frame).
    pub at_cycle: Option<u64>,
    /// Fail at the first action starting at or after this simulated time (s).
    pub at_time_s: Option<f64>,
}

/// The first `[[faults]]` entry that does not make sense, as (field, why).
pub(super) fn check(faults: &[FaultSpec]) -> Result<(), (String, &'static str)> {
    for (i, f) in faults.iter().enumerate() {
        let field = |name: &str| format!("faults[{i}].{name}");
        match (f.kind, f.sensor, f.side) {
            (FaultKindName::SilentSensor, None, _) => {
                return Err((
                    field("sensor"),
                    "silent_sensor needs `sensor` (mast, body_front, body_rear, lidar)",
                ));
            }
            (FaultKindName::StalledWheel, _, None) => {
                return Err((field("side"), "stalled_wheel needs `side` (left or right)"));
            }
            (k, Some(_), _) if k != FaultKindName::SilentSensor => {
                return Err((field("sensor"), "only silent_sensor names a sensor"));
            }
            (k, _, Some(_)) if k != FaultKindName::StalledWheel => {
                return Err((field("side"), "only stalled_wheel names a side"));
            }
            _ => {}
        }
        if f.at_cycle.is_some() && f.at_time_s.is_some() {
            return Err((field("at_time_s"), "give at_cycle or at_time_s, not both"));
        }
        if f.at_time_s.is_some_and(|t| !(t.is_finite() && t >= 0.0)) {
            return Err((field("at_time_s"), "must be a non-negative number of seconds"));
        }
    }
    Ok(())
}

impl Mission {
    /// The `[[faults]]` as the platform's schedule.
    pub fn fault_schedule(&self) -> Vec<crate::platform::ScheduledFault> {
        use crate::platform::{FaultTrigger, ScheduledFault};
        use rovernav_core::CameraKind;
        use rovernav_sim::Fault;
        self.faults
            .iter()
            .map(|f| {
                let fault = match (f.kind, f.sensor, f.side) {
                    (FaultKindName::SilentSensor, sensor, _) => Fault::SilentSensor(match sensor {
                        Some(SensorName::BodyFront) => CameraKind::BodyFront,
                        Some(SensorName::BodyRear) => CameraKind::BodyRear,
                        Some(SensorName::Lidar) => CameraKind::Lidar,
                        Some(SensorName::Mast) | None => CameraKind::Mast,
                    }),
                    (FaultKindName::StalledWheel, _, side) => {
                        Fault::StalledWheel { left: side != Some(Side::Right) }
                    }
                    (FaultKindName::CompassNan, _, _) => Fault::CompassNaN,
                };
                let at = match (f.at_cycle, f.at_time_s) {
                    (_, Some(t)) => FaultTrigger::Time(t),
                    (c, None) => FaultTrigger::Cycle(c.unwrap_or(0)),
                };
                ScheduledFault { fault, at }
            })
            .collect()
    }
}
