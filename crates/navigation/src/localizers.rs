//! The built-in localisers' registry entries (the localisers themselves are in
//! `rovernav_localization`) and the parameters a mission's `[localizer_params]` may set.

use crate::params::NavigatorError;
use crate::params::{Field, Param, Unit};
use crate::registry::{LocalizerAlias, LocalizerEntry, param_info};
use rovernav_localization::{
    DeadReckoning, Ekf, EkfMl, EkfMlParams, LanderLocalizer, LanderLocalizerParams, OrbitalMapLocalizer,
    OrbitalMapParams,
};

/// The built-in localisers.
pub const BUILTIN_LOCALIZERS: &[LocalizerEntry] = &[
    LocalizerEntry {
        name: "dead-reckoning",
        doc: "compass heading and wheel odometry (paper 001)",
        matches_terrain: false,
        needs_prior_map: false,
        params: Vec::new,
        build: |b| Ok(Box::new(DeadReckoning::new(b.rover, b.initial))),
    },
    LocalizerEntry {
        name: "ekf",
        doc: "gyro, inclinometer and odometry EKF with zero-velocity updates (paper 004 section 3.2)",
        matches_terrain: false,
        needs_prior_map: false,
        params: Vec::new,
        build: |b| Ok(Box::new(Ekf::new(b.rover, b.initial))),
    },
    LocalizerEntry {
        name: "ekf-ml",
        doc: "the EKF with terrain-map matching fixes against its own map (paper 000 section 4)",
        matches_terrain: true,
        needs_prior_map: false,
        params: || param_info(EkfMlParams::default(), ekf_ml_params()),
        build: |b| {
            let params = b.configured(EkfMlParams::default(), &ekf_ml_params())?;
            Ok(Box::new(EkfMl::with_params(b.rover, b.initial, params)))
        },
    },
    LocalizerEntry {
        name: "orbital-map",
        doc: "ekf-ml with fixes against the terrain's orbital map, given before the traverse (paper 002 section 5)",
        matches_terrain: true,
        needs_prior_map: true,
        params: || param_info(OrbitalMapParams::default(), orbital_map_params()),
        build: |b| {
            let params = b.configured(OrbitalMapParams::default(), &orbital_map_params())?;
            let map =
                b.prior_map.ok_or_else(|| NavigatorError::MissingPriorMap { localizer: b.name.into() })?;
            Ok(Box::new(OrbitalMapLocalizer::new(b.rover, b.initial, map, params)))
        },
    },
    LocalizerEntry {
        name: "lander",
        doc: "ekf-ml with fixes from a lander's stereo sightings of the rover turning near it (paper 002 section 2)",
        matches_terrain: true,
        needs_prior_map: false,
        params: || param_info(LanderLocalizerParams::default(), lander_params()),
        build: |b| {
            let params = b.configured(LanderLocalizerParams::default(), &lander_params())?;
            Ok(Box::new(LanderLocalizer::new(b.rover, b.initial, params)))
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

/// The parameters of `orbital-map` a mission may set (its map matcher between fixes keeps
/// `ekf-ml`'s defaults).
pub fn orbital_map_params() -> Vec<Param<OrbitalMapParams>> {
    vec![
        Param {
            name: "fix_interval_m",
            doc: "estimated travel between orbital fixes",
            unit: Unit::PositiveMetres,
            field: |c| Field::Real(&mut c.fix_interval_m),
        },
        Param {
            name: "orbital_resolution_m",
            doc: "resolution the orbital map is averaged to (1 m: HiRISE-class; 6, 20, 100 m: CTX, HRSC, MOLA)",
            unit: Unit::PositiveMetres,
            field: |c| Field::Real(&mut c.orbital_resolution_m),
        },
        Param {
            name: "range_m",
            doc: "half-side of the rover's own map matched against the orbital map",
            unit: Unit::PositiveMetres,
            field: |c| Field::Real(&mut c.range_m),
        },
        Param {
            name: "max_window_m",
            doc: "largest search half-width of an orbital match",
            unit: Unit::PositiveMetres,
            field: |c| Field::Real(&mut c.max_window_m),
        },
        Param {
            name: "max_failure_probability",
            doc: "orbital fixes more likely than this to be wrong are rejected",
            unit: Unit::Fraction,
            field: |c| Field::Real(&mut c.max_failure_probability),
        },
        Param {
            name: "covariance_scale",
            doc: "factor on an orbital match's covariance before it is fused",
            unit: Unit::Weight,
            field: |c| Field::Real(&mut c.covariance_scale),
        },
    ]
}

/// The parameters of `lander` a mission may set (its map matcher keeps `ekf-ml`'s defaults).
pub fn lander_params() -> Vec<Param<LanderLocalizerParams>> {
    vec![
        Param {
            name: "map_matching",
            doc: "match the rover's own map between lander fixes (ekf-ml); off: the EKF with lander fixes only",
            unit: Unit::Switch,
            field: |c| Field::Bool(&mut c.map_matching),
        },
        Param {
            name: "covariance_scale",
            doc: "factor on a lander fix's covariance before it is fused",
            unit: Unit::Weight,
            field: |c| Field::Real(&mut c.covariance_scale),
        },
        Param {
            name: "independent_after_m",
            doc: "sightings closer than this to the last fused one are fused by covariance intersection",
            unit: Unit::PositiveMetres,
            field: |c| Field::Real(&mut c.independent_after_m),
        },
    ]
}
