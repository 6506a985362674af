//! Navigator and localiser parameters from the mission file's `[navigator_params]` and
//! `[localizer_params]` tables (as Nav2 gives each plugin its parameters): every navigator publishes a table of the settings a mission may
//! change, with units and valid ranges, and a misspelt name or an out-of-range value is an
//! error naming the navigator and the parameter rather than a silently ignored setting.

use std::collections::BTreeMap;
use std::fmt;

/// Numeric parameters by mission-file name (of a navigator or a localiser).
pub type NavigatorParams = BTreeMap<String, f64>;

/// What a parameter's value means, which fixes its valid range and its conversion.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Unit {
    /// A length or distance, zero or more, at most [`MAX_METRES`] (m).
    Metres,
    /// A length that must be positive, at most [`MAX_METRES`] (m).
    PositiveMetres,
    /// A map cell size, from 2 cm to 1 m (finer maps would not fit in memory).
    CellSize,
    /// A clearance hazards are grown by, from 0 to [`MAX_CLEARANCE`] (m): the growing kernel's
    /// cost rises with its square, so a huge one would stall the navigator.
    Clearance,
    /// An angle from 0 to 180 degrees, stored in radians.
    Degrees,
    /// A fraction in (0, 1].
    Fraction,
    /// A whole number, zero or more, at most [`MAX_COUNT`].
    Count,
    /// A weight or gain, zero or more.
    Weight,
    /// On (1) or off (0).
    Switch,
}

impl Unit {
    /// How the unit reads in a parameter listing.
    pub fn label(self) -> &'static str {
        match self {
            Unit::Metres => "m, 0..100",
            Unit::PositiveMetres => "m, > 0, <= 100",
            Unit::CellSize => "m, 0.02..1",
            Unit::Clearance => "m, 0..2",
            Unit::Degrees => "deg, 0..180",
            Unit::Fraction => "fraction, (0, 1]",
            Unit::Count => "count, whole, 0..100000",
            Unit::Weight => ">= 0",
            Unit::Switch => "0 (off) or 1 (on)",
        }
    }
}

/// Largest length parameter (m): beyond any rover's map, so that `map_margin_m = 1e9` is an error
/// rather than a map sized from it (issue 44: it overflowed a grid allocation).
pub const MAX_METRES: f64 = 100.0;

/// Largest clearance hazards are grown by (m): `safety_buffer_m = 100` took over two minutes.
pub const MAX_CLEARANCE: f64 = 2.0;

/// Largest count parameter (cycles, samples, arcs...).
pub const MAX_COUNT: f64 = 100_000.0;

/// A mutable reference to the config field a parameter sets.
pub enum Field<'a> {
    /// A real-valued field (radians for [`Unit::Degrees`]).
    Real(&'a mut f64),
    /// A 32-bit count.
    U32(&'a mut u32),
    /// A 64-bit count.
    U64(&'a mut u64),
    /// A size count.
    Usize(&'a mut usize),
    /// An on/off setting ([`Unit::Switch`]).
    Bool(&'a mut bool),
}

/// One parameter of a navigator's config type `C`.
pub struct Param<C> {
    /// Name in the mission file.
    pub name: &'static str,
    /// One-line meaning.
    pub doc: &'static str,
    /// Unit and valid range.
    pub unit: Unit,
    /// The field it sets.
    pub field: fn(&mut C) -> Field<'_>,
}

/// Why a navigator or a localiser could not be built from a name and parameters.
#[derive(Clone, Debug, PartialEq)]
pub enum NavigatorError {
    /// No navigator of that name is registered.
    UnknownNavigator {
        /// The name asked for.
        name: String,
        /// The names a mission may give.
        known: Vec<&'static str>,
    },
    /// No localiser of that name is registered.
    UnknownLocalizer {
        /// The name asked for.
        name: String,
        /// The names a mission may give.
        known: Vec<&'static str>,
    },
    /// The navigator cannot run under that global planner.
    UnknownGlobalPlanner {
        /// Navigator registry name.
        navigator: String,
        /// The planner asked for.
        planner: String,
        /// The planners it can run under.
        known: Vec<&'static str>,
    },
    /// A name that fixes the global planner was given another one.
    ConflictingGlobalPlanner {
        /// The name given.
        navigator: String,
        /// The planner asked for.
        planner: String,
        /// The planner the name stands for.
        implied: &'static str,
    },
    /// The navigator (or localiser) has no parameter of that name.
    UnknownParam {
        /// What it is: "navigator" or "localizer".
        kind: &'static str,
        /// Registry name.
        navigator: String,
        /// The parameter asked for.
        param: String,
        /// The parameters it has.
        known: Vec<&'static str>,
    },
    /// The value is outside the parameter's range.
    InvalidParam {
        /// What it is: "navigator" or "localizer".
        kind: &'static str,
        /// Registry name.
        navigator: String,
        /// The parameter.
        param: String,
        /// The value given.
        value: f64,
        /// The valid range.
        expected: &'static str,
    },
    /// The localiser needs a prior map (an orbital map) that the run does not give.
    MissingPriorMap {
        /// Registry name.
        localizer: String,
    },
}

impl fmt::Display for NavigatorError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            NavigatorError::UnknownNavigator { name, known } => {
                write!(f, "unknown navigator `{name}` (known: {})", known.join(", "))
            }
            NavigatorError::UnknownLocalizer { name, known } => {
                write!(f, "unknown localizer `{name}` (known: {})", known.join(", "))
            }
            NavigatorError::UnknownGlobalPlanner { navigator, planner, known } if known.is_empty() => {
                write!(f, "navigator `{navigator}` takes no global planner (given `{planner}`)")
            }
            NavigatorError::UnknownGlobalPlanner { navigator, planner, known } => write!(
                f,
                "navigator `{navigator}` has no global planner `{planner}` (it has: {})",
                known.join(", ")
            ),
            NavigatorError::ConflictingGlobalPlanner { navigator, planner, implied } => write!(
                f,
                "navigator `{navigator}` runs under global planner `{implied}`, not `{planner}` (name the entry to choose)"
            ),
            NavigatorError::UnknownParam { kind, navigator, param, known } if known.is_empty() => {
                write!(f, "{kind} `{navigator}` takes no parameters (given `{param}`)")
            }
            NavigatorError::UnknownParam { kind, navigator, param, known } => {
                write!(f, "{kind} `{navigator}` has no parameter `{param}` (it has: {})", known.join(", "))
            }
            NavigatorError::InvalidParam { kind, navigator, param, value, expected } => {
                write!(f, "parameter `{param}` of {kind} `{navigator}` is {value}, expected {expected}")
            }
            NavigatorError::MissingPriorMap { localizer } => write!(
                f,
                "localizer `{localizer}` needs an orbital map of the terrain, which this run does not give"
            ),
        }
    }
}

impl std::error::Error for NavigatorError {}

impl NavigatorError {
    /// The parameter the error is about, if any.
    pub fn param(&self) -> Option<&str> {
        match self {
            NavigatorError::UnknownParam { param, .. } | NavigatorError::InvalidParam { param, .. } => {
                Some(param)
            }
            _ => None,
        }
    }

    /// Whether the error is about the global planner.
    pub fn is_about_global_planner(&self) -> bool {
        matches!(
            self,
            NavigatorError::UnknownGlobalPlanner { .. } | NavigatorError::ConflictingGlobalPlanner { .. }
        )
    }

    /// The same error said of a localiser.
    pub fn of_localizer(self) -> Self {
        match self {
            NavigatorError::UnknownParam { navigator, param, known, .. } => {
                NavigatorError::UnknownParam { kind: "localizer", navigator, param, known }
            }
            NavigatorError::InvalidParam { navigator, param, value, expected, .. } => {
                NavigatorError::InvalidParam { kind: "localizer", navigator, param, value, expected }
            }
            other => other,
        }
    }
}

/// Sets every parameter of `params` on `config` from the navigator's `table`; the config is
/// left unchanged when any name or value is wrong.
pub fn apply<C: Clone>(
    navigator: &str,
    config: &mut C,
    table: &[Param<C>],
    params: &NavigatorParams,
) -> Result<(), NavigatorError> {
    let mut out = config.clone();
    for (name, &value) in params {
        let Some(param) = table.iter().find(|p| p.name == name) else {
            return Err(NavigatorError::UnknownParam {
                kind: "navigator",
                navigator: navigator.to_string(),
                param: name.clone(),
                known: table.iter().map(|p| p.name).collect(),
            });
        };
        let invalid = || NavigatorError::InvalidParam {
            kind: "navigator",
            navigator: navigator.to_string(),
            param: name.clone(),
            value,
            expected: param.unit.label(),
        };
        let ok = value.is_finite()
            && match param.unit {
                Unit::Metres => (0.0..=MAX_METRES).contains(&value),
                Unit::Weight => value >= 0.0,
                Unit::Count => (0.0..=MAX_COUNT).contains(&value),
                Unit::PositiveMetres => value > 0.0 && value <= MAX_METRES,
                Unit::CellSize => (0.02..=1.0).contains(&value),
                Unit::Clearance => (0.0..=MAX_CLEARANCE).contains(&value),
                Unit::Degrees => (0.0..=180.0).contains(&value),
                Unit::Fraction => value > 0.0 && value <= 1.0,
                Unit::Switch => value == 0.0 || value == 1.0,
            };
        if !ok {
            return Err(invalid());
        }
        let whole = value.fract() == 0.0;
        match (param.field)(&mut out) {
            Field::Real(f) if param.unit == Unit::Degrees => *f = value.to_radians(),
            Field::Real(f) => *f = value,
            Field::U32(f) if whole && value <= u32::MAX as f64 => *f = value as u32,
            Field::U64(f) if whole && value <= u64::MAX as f64 => *f = value as u64,
            Field::Usize(f) if whole && value <= usize::MAX as f64 => *f = value as usize,
            Field::Bool(f) if value == 0.0 || value == 1.0 => *f = value == 1.0,
            _ => return Err(invalid()),
        }
    }
    *config = out;
    Ok(())
}

/// The map settings the grid-map navigators share: cell size, margin around the start-goal
/// box, and the safety buffer their hazards are grown by.
pub fn map_params<C>(
    resolution: fn(&mut C) -> Field<'_>,
    margin: fn(&mut C) -> Field<'_>,
    buffer: fn(&mut C) -> Field<'_>,
) -> [Param<C>; 3] {
    [
        Param { name: "map_resolution_m", doc: "map cell size", unit: Unit::CellSize, field: resolution },
        Param {
            name: "map_margin_m",
            doc: "margin of the world map around the start-goal box",
            unit: Unit::Metres,
            field: margin,
        },
        Param {
            name: "safety_buffer_m",
            doc: "extra clearance added to the rover radius when growing hazards",
            unit: Unit::Clearance,
            field: buffer,
        },
    ]
}

/// The heading error above which a navigator turns in place before driving.
pub fn turn_threshold_param<C>(field: fn(&mut C) -> Field<'_>) -> Param<C> {
    Param {
        name: "turn_threshold_deg",
        doc: "heading error above which the rover turns in place before driving",
        unit: Unit::Degrees,
        field,
    }
}

/// The value of `param` in `config`, in the parameter's unit (degrees for angles).
pub fn value<C>(config: &mut C, param: &Param<C>) -> f64 {
    match (param.field)(config) {
        Field::Real(f) if param.unit == Unit::Degrees => f.to_degrees(),
        Field::Real(f) => *f,
        Field::U32(f) => *f as f64,
        Field::U64(f) => *f as f64,
        Field::Usize(f) => *f as f64,
        Field::Bool(f) => f64::from(u8::from(*f)),
    }
}

/// `config` with `params` applied (see [`apply`]).
pub fn configured<C: Clone>(
    navigator: &str,
    mut config: C,
    table: &[Param<C>],
    params: &NavigatorParams,
) -> Result<C, NavigatorError> {
    apply(navigator, &mut config, table, params)?;
    Ok(config)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Clone, Debug, PartialEq)]
    struct Demo {
        buffer: f64,
        angle: f64,
        steps: u32,
        on: bool,
    }

    fn table() -> Vec<Param<Demo>> {
        vec![
            Param {
                name: "buffer_m",
                doc: "buffer",
                unit: Unit::Metres,
                field: |c| Field::Real(&mut c.buffer),
            },
            Param {
                name: "angle_deg",
                doc: "angle",
                unit: Unit::Degrees,
                field: |c| Field::Real(&mut c.angle),
            },
            Param { name: "steps", doc: "steps", unit: Unit::Count, field: |c| Field::U32(&mut c.steps) },
            Param { name: "on", doc: "switch", unit: Unit::Switch, field: |c| Field::Bool(&mut c.on) },
        ]
    }

    fn params(pairs: &[(&str, f64)]) -> NavigatorParams {
        pairs.iter().map(|(k, v)| (k.to_string(), *v)).collect()
    }

    #[test]
    fn values_convert_to_the_fields_units() {
        let mut c = Demo { buffer: 0.1, angle: 0.0, steps: 1, on: true };
        let given = params(&[("buffer_m", 0.3), ("angle_deg", 90.0), ("steps", 7.0), ("on", 0.0)]);
        apply("demo", &mut c, &table(), &given).unwrap();
        assert_eq!(c.buffer, 0.3);
        assert!((c.angle - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        assert_eq!(c.steps, 7);
        assert!(!c.on);
        assert_eq!(value(&mut c, &table()[3]), 0.0);
        apply("demo", &mut c, &table(), &params(&[("on", 1.0)])).unwrap();
        assert!(c.on);
        assert_eq!(value(&mut c, &table()[3]), 1.0);
    }

    #[test]
    fn a_wrong_name_or_value_names_it_and_changes_nothing() {
        let before = Demo { buffer: 0.1, angle: 0.0, steps: 1, on: false };
        let mut c = before.clone();
        let err = apply("demo", &mut c, &table(), &params(&[("bufer_m", 0.3)])).unwrap_err();
        assert!(err.to_string().contains("no parameter `bufer_m`"), "{err}");
        assert!(err.to_string().contains("buffer_m, angle_deg, steps, on"), "{err}");
        for bad in [
            ("buffer_m", -0.1),
            ("buffer_m", f64::NAN),
            ("angle_deg", 200.0),
            ("steps", 2.5),
            ("on", 2.0),
            ("on", 0.5),
        ] {
            // The valid "angle_deg" is applied first where the bad entry is another one, so a
            // partial update would show.
            let err = apply("demo", &mut c, &table(), &params(&[("angle_deg", 10.0), bad])).unwrap_err();
            assert!(matches!(err, NavigatorError::InvalidParam { .. }), "{bad:?}: {err}");
            assert!(err.to_string().contains(bad.0), "{err}");
            assert_eq!(c, before, "{bad:?}");
        }
    }
}
