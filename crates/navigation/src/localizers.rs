//! The built-in localisers' registry entries (the localisers themselves are in
//! `rovernav_localization`) and the parameters a mission's `[localizer_params]` may set.

use crate::params::{Field, Param, Unit};
use crate::registry::{LocalizerAlias, LocalizerEntry, param_info};
use rovernav_localization::{DeadReckoning, Ekf, EkfMl, EkfMlParams};

/// The built-in localisers.
pub const BUILTIN_LOCALIZERS: &[LocalizerEntry] = &[
    LocalizerEntry {
        name: "dead-reckoning",
        doc: "compass heading and wheel odometry (paper 001)",
        matches_terrain: false,
        params: Vec::new,
        build: |b| Ok(Box::new(DeadReckoning::new(b.rover, b.initial))),
    },
    LocalizerEntry {
        name: "ekf",
        doc: "gyro, inclinometer and odometry EKF with zero-velocity updates (paper 004 section 3.2)",
        matches_terrain: false,
        params: Vec::new,
        build: |b| Ok(Box::new(Ekf::new(b.rover, b.initial))),
    },
    LocalizerEntry {
        name: "ekf-ml",
        doc: "the EKF with terrain-map matching fixes against its own map (paper 000 section 4)",
        matches_terrain: true,
        params: || param_info(EkfMlParams::default(), ekf_ml_params()),
        build: |b| {
            let params = b.configured(EkfMlParams::default(), &ekf_ml_params())?;
            Ok(Box::new(EkfMl::with_params(b.rover, b.initial, params)))
        },
    },
];

/// Old localiser names and the parameters they stand for.
pub const LOCALIZER_ALIASES: &[LocalizerAlias] = &[
    // Localisation target selection (paper 000 section 4.4) on: the look-back points where the
    // map predicts the best fix.
    LocalizerAlias { name: "ekf-ml-targets", localizer: "ekf-ml", params: &[("select_targets", 1.0)] },
];

/// The parameters of `ekf-ml` a mission may set.
pub fn ekf_ml_params() -> Vec<Param<EkfMlParams>> {
    vec![
        Param {
            name: "select_targets",
            doc: "choose where to look back by predicting the best fix (paper 000 section 4.4)",
            unit: Unit::Switch,
            field: |c| Field::Bool(&mut c.select_targets),
        },
        Param {
            name: "resolution_m",
            doc: "cell size of the rover's maps",
            unit: Unit::CellSize,
            field: |c| Field::Real(&mut c.resolution),
        },
        Param {
            name: "min_travel_m",
            doc: "travel since the last match before a new view is matched",
            unit: Unit::PositiveMetres,
            field: |c| Field::Real(&mut c.min_travel),
        },
        Param {
            name: "window_sigmas",
            doc: "search window half-width in EKF standard deviations",
            unit: Unit::Weight,
            field: |c| Field::Real(&mut c.window_sigmas),
        },
        Param {
            name: "max_failure_probability",
            doc: "fixes more likely than this to be wrong are rejected",
            unit: Unit::Fraction,
            field: |c| Field::Real(&mut c.max_failure_probability),
        },
        Param {
            name: "max_fix_sigma_m",
            doc: "fixes with a larger position standard deviation are rejected",
            unit: Unit::PositiveMetres,
            field: |c| Field::Real(&mut c.max_fix_sigma),
        },
    ]
}
