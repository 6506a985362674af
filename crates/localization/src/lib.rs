//! rovernav localisation layer: proprioceptive pose estimation and map-matching fixes.
//!
//! - [`dead_reckoning`]: compass + encoder dead reckoning (paper 001).
//! - [`ekf`]: gyro/inclinometer/odometry pose estimator with zero-velocity update, slip
//!   correction and map-matching fixes (paper 004 section 3.2).
//! - [`ekf_ml`]: the EKF with terrain-matching fixes against the rover's own map ("ekf-ml").
//! - [`matching`]: terrain map matching: maximum likelihood with branch and bound (paper 000
//!   section 4) and partial Hausdorff (paper 002 section 3).
//! - [`lander`]: the rover's position from the lander's stereo sighting (paper 002 section 2).
//! - [`lander_localizer`]: the `lander` localiser, `ekf-ml` with fixes from lander sightings.
//! - [`orbital`]: matching the rover's panorama map against an orbital DEM (paper 002 section 5).
//! - [`orbital_map`]: the `orbital-map` localiser, `ekf-ml` with fixes against an orbital map
//!   given before the traverse.
//! - [`target`]: choosing where to look for the next match (paper 000 section 4.4).
//! - [`consistency`]: NEES and its chi-square bounds (is a filter's covariance honest?).
//! - [`evaluation`]: the paper 002 sequence-accuracy protocol, reusable with any range sensor.
//! - [`synthetic`]: seeded synthetic terrain and stereo-like range data for tests and benches.
//! - [`benchmark`]: the matcher workloads of the benches and `rovernav bench report`.
//!
//! Localisers are chosen by name through the registry (`rovernav_navigation::registry`, which
//! lists them with their `[localizer_params]`; [`localizer_by_name`] builds the built-in ones
//! without parameters). A typical cycle: feed each
//! command's [`rovernav_core::SensorFrame`] to the localiser; after a move, build the local
//! elevation map, match it with [`MlMatcher::match_map`] in a [`SearchWindow`] from the
//! estimate, and fuse the result with [`Ekf::fuse_fix`].

pub mod benchmark;
pub mod consistency;
pub mod dead_reckoning;
pub mod ekf;
pub mod ekf_ml;
pub mod evaluation;
pub mod lander;
pub mod lander_localizer;
pub mod matching;
pub mod orbital;
pub mod orbital_map;
pub mod synthetic;
pub mod target;

pub use dead_reckoning::{DeadReckoning, DeadReckoningParams};
pub use ekf::{Ekf, EkfParams, EkfStats};
pub use ekf_ml::{EkfMl, EkfMlParams, EkfMlStats};
pub use lander_localizer::{LanderLocalizer, LanderLocalizerParams};
pub use matching::{
    HausdorffMatcher, HausdorffParams, MatchError, MatchResult, MlMatcher, MlParams, SearchWindow,
};
pub use orbital_map::{OrbitalMapLocalizer, OrbitalMapParams};
pub use target::{TargetParams, select_target};

use rovernav_core::{Localizer, Pose3, RoverConfig};

/// A built-in localiser by name with its default parameters (`ekf-ml-targets` is `ekf-ml` with
/// target selection), or `None` for another name. Missions choose localisers through the
/// registry (`rovernav_navigation::registry`), which also takes `[localizer_params]`; a test
/// there checks that both build the same localiser for every built-in name.
pub fn localizer_by_name(name: &str, config: &RoverConfig, initial: Pose3) -> Option<Box<dyn Localizer>> {
    let targets = EkfMlParams { select_targets: true, ..Default::default() };
    match name {
        "dead-reckoning" => Some(Box::new(DeadReckoning::new(config, initial))),
        "ekf" => Some(Box::new(Ekf::new(config, initial))),
        "ekf-ml" => Some(Box::new(EkfMl::new(config, initial))),
        "ekf-ml-targets" => Some(Box::new(EkfMl::with_params(config, initial, targets))),
        "lander" => Some(Box::new(LanderLocalizer::new(config, initial, Default::default()))),
        _ => None,
    }
}
