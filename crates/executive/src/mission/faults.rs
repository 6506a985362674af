//! The mission file's `[[faults]]`: what the simulator makes fail, and when.

use super::Mission;
use serde::{Deserialize, Serialize};

/// The kinds of `[[faults]]` entry.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum FaultKindName {
    /// A range sensor returns images without points (`sensor` names it).
    SilentSensor,
    /// The wheels of one side stop turning (`side` names it).
    StalledWheel,
    /// The compass reads NaN.
    CompassNan,
    /// A range sensor's points are NaN (`sensor` names it).
    NanRange,
    /// The gyro's bias jumps by `rate_deg_s` (default [`DEFAULT_GYRO_JUMP_DEG_S`]).
    GyroBiasJump,
    /// A component of the graph crashes (`component` names it: `rovernav graph` lists them).
    ComponentCrash,
}

/// A gyro bias jump's default size (deg/s): 720 deg/h, 70 times the gyro's bias stability.
pub const DEFAULT_GYRO_JUMP_DEG_S: f64 = 0.2;

/// Range sensors a fault can silence.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
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
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum Side {
    /// Left.
    Left,
    /// Right.
    Right,
}

/// One `[[faults]]` entry: what fails and when (default: from the start).
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FaultSpec {
    /// What fails.
    pub kind: FaultKindName,
    /// For `silent_sensor`: which sensor.
    pub sensor: Option<SensorName>,
    /// For `stalled_wheel`: which side.
    pub side: Option<Side>,
    /// For `gyro_bias_jump`: the jump (deg/s).
    pub rate_deg_s: Option<f64>,
    /// For `component_crash`: the component's name.
    pub component: Option<String>,
    /// Fail before this command (commands count from 1; 0 is before the first frame).
    pub at_cycle: Option<u64>,
    /// Fail at the first action starting at or after this simulated time (s).
    pub at_time_s: Option<f64>,
}

/// The first `[[faults]]` entry that does not make sense, as (field, why): `faults[i].name`.
pub fn check(faults: &[FaultSpec]) -> Result<(), (String, &'static str)> {
    for (i, f) in faults.iter().enumerate() {
        let field = |name: &str| format!("faults[{i}].{name}");
        let names_sensor = matches!(f.kind, FaultKindName::SilentSensor | FaultKindName::NanRange);
        match (f.kind, f.sensor, f.side) {
            (_, None, _) if names_sensor => {
                return Err((
                    field("sensor"),
                    "silent_sensor and nan_range need `sensor` (mast, body_front, body_rear, lidar)",
                ));
            }
            (FaultKindName::StalledWheel, _, None) => {
                return Err((field("side"), "stalled_wheel needs `side` (left or right)"));
            }
            (_, Some(_), _) if !names_sensor => {
                return Err((field("sensor"), "only silent_sensor and nan_range name a sensor"));
            }
            (k, _, Some(_)) if k != FaultKindName::StalledWheel => {
                return Err((field("side"), "only stalled_wheel names a side"));
            }
            _ => {}
        }
        let crash = f.kind == FaultKindName::ComponentCrash;
        match &f.component {
            None if crash => {
                return Err((field("component"), "component_crash needs `component` (see `rovernav graph`)"));
            }
            Some(_) if !crash => return Err((field("component"), "only component_crash names a component")),
            Some(c) if !crate::graph::NODES.iter().any(|n| n.name == c.as_str()) => {
                return Err((field("component"), "not a component of the graph (see `rovernav graph`)"));
            }
            _ => {}
        }
        match f.rate_deg_s {
            Some(_) if f.kind != FaultKindName::GyroBiasJump => {
                return Err((field("rate_deg_s"), "only gyro_bias_jump has a rate"));
            }
            Some(r) if !(r.is_finite() && r.abs() <= 100.0) => {
                return Err((field("rate_deg_s"), "must be a number of deg/s within +-100"));
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
        use crate::platform::ScheduledFault;
        use rovernav_core::CameraKind;
        use rovernav_sim::Fault;
        let camera = |sensor: Option<SensorName>| match sensor {
            Some(SensorName::BodyFront) => CameraKind::BodyFront,
            Some(SensorName::BodyRear) => CameraKind::BodyRear,
            Some(SensorName::Lidar) => CameraKind::Lidar,
            Some(SensorName::Mast) | None => CameraKind::Mast,
        };
        self.faults
            .iter()
            .filter_map(|f| {
                let fault = match f.kind {
                    FaultKindName::SilentSensor => Fault::SilentSensor(camera(f.sensor)),
                    FaultKindName::NanRange => Fault::NanRange(camera(f.sensor)),
                    FaultKindName::StalledWheel => Fault::StalledWheel { left: f.side != Some(Side::Right) },
                    FaultKindName::CompassNan => Fault::CompassNaN,
                    FaultKindName::GyroBiasJump => {
                        Fault::GyroBiasJump(f.rate_deg_s.unwrap_or(DEFAULT_GYRO_JUMP_DEG_S).to_radians())
                    }
                    FaultKindName::ComponentCrash => return None,
                };
                Some(ScheduledFault { fault, at: f.trigger() })
            })
            .collect()
    }

    /// The `[[faults]]` that crash a component, as (component, trigger).
    pub fn crash_schedule(&self) -> Vec<crate::platform::ScheduledCrash> {
        self.faults
            .iter()
            .filter(|f| f.kind == FaultKindName::ComponentCrash)
            .filter_map(|f| {
                let component = f.component.clone()?;
                Some(crate::platform::ScheduledCrash { component, at: f.trigger() })
            })
            .collect()
    }
}

impl FaultSpec {
    /// When the fault comes (default: before the first frame).
    pub fn trigger(&self) -> crate::platform::FaultTrigger {
        use crate::platform::FaultTrigger;
        match (self.at_cycle, self.at_time_s) {
            (_, Some(t)) => FaultTrigger::Time(t),
            (c, None) => FaultTrigger::Cycle(c.unwrap_or(0)),
        }
    }

    /// The kind with what it names, e.g. `silent_sensor:mast`, `component_crash:navigator`,
    /// `stalled_wheel:left`, `gyro_bias_jump:0.2` (deg/s).
    pub fn label(&self) -> String {
        let what = match (self.sensor, self.side, &self.component) {
            (Some(s), _, _) => format!("{s:?}"),
            (_, Some(side), _) => format!("{side:?}"),
            (_, _, Some(c)) => c.clone(),
            _ if self.kind == FaultKindName::GyroBiasJump => {
                format!("{}", self.rate_deg_s.unwrap_or(DEFAULT_GYRO_JUMP_DEG_S))
            }
            _ => return self.kind_name().to_string(),
        };
        format!("{}:{}", self.kind_name(), toml_case(&what))
    }

    /// The kind's name in mission files (`silent_sensor`, `component_crash`...).
    pub fn kind_name(&self) -> &'static str {
        match self.kind {
            FaultKindName::SilentSensor => "silent_sensor",
            FaultKindName::StalledWheel => "stalled_wheel",
            FaultKindName::CompassNan => "compass_nan",
            FaultKindName::NanRange => "nan_range",
            FaultKindName::GyroBiasJump => "gyro_bias_jump",
            FaultKindName::ComponentCrash => "component_crash",
        }
    }
}

/// `BodyFront` as mission files spell it: `body_front`.
fn toml_case(debug: &str) -> String {
    let mut out = String::new();
    for (i, c) in debug.chars().enumerate() {
        if c.is_ascii_uppercase() {
            if i > 0 {
                out.push('_');
            }
            out.push(c.to_ascii_lowercase());
        } else {
            out.push(c);
        }
    }
    out
}
