//! rovernav localisation layer: proprioceptive pose estimation and map-matching fixes.
//!
//! - [`dead_reckoning`]: compass + encoder dead reckoning (paper 001).
//! - [`ekf`]: gyro/inclinometer/odometry pose estimator with zero-velocity update, slip
//!   correction and map-matching fixes (paper 004 section 3.2).
//! - [`ekf_ml`]: the EKF with terrain-matching fixes against the rover's own map ("ekf-ml").
//! - [`matching`]: terrain map matching: maximum likelihood with branch and bound (paper 000
//!   section 4) and partial Hausdorff (paper 002 section 3).
//! - [`target`]: choosing where to look for the next match (paper 000 section 4.4).
//! - [`evaluation`]: the paper 002 sequence-accuracy protocol, reusable with any range sensor.
//! - [`synthetic`]: seeded synthetic terrain and stereo-like range data for tests and benches.
//!
//! Localisers are chosen by name through [`localizer_by_name`]. A typical cycle: feed each
//! command's [`rovernav_core::SensorFrame`] to the localiser; after a move, build the local
//! elevation map, match it with [`MlMatcher::match_map`] in a [`SearchWindow`] from the
//! estimate, and fuse the result with [`Ekf::fuse_fix`].

pub mod dead_reckoning;
pub mod ekf;
pub mod ekf_ml;
pub mod evaluation;
pub mod matching;
pub mod synthetic;
pub mod target;

pub use dead_reckoning::{DeadReckoning, DeadReckoningParams};
pub use ekf::{Ekf, EkfParams, EkfStats};
pub use ekf_ml::{EkfMl, EkfMlParams, EkfMlStats};
pub use matching::{
    HausdorffMatcher, HausdorffParams, MatchError, MatchResult, MlMatcher, MlParams, SearchWindow,
};
pub use target::{TargetParams, select_target};

use rovernav_core::{Localizer, Pose3, RoverConfig};

/// Names accepted by [`localizer_by_name`].
pub const LOCALIZER_NAMES: &[&str] = &["dead-reckoning", "ekf", "ekf-ml", "ekf-ml-targets"];

/// Whether the named localiser corrects its pose by terrain-map matching (and so wants the
/// navigator to look back over the terrain it crossed).
pub fn matches_terrain(name: &str) -> bool {
    matches!(name, "ekf-ml" | "ekf-ml-targets")
}

/// Builds a localiser by registry name, or `None` for an unknown name.
pub fn localizer_by_name(name: &str, config: &RoverConfig, initial: Pose3) -> Option<Box<dyn Localizer>> {
    match name {
        "dead-reckoning" => Some(Box::new(DeadReckoning::new(config, initial))),
        "ekf" => Some(Box::new(Ekf::new(config, initial))),
        "ekf-ml" => Some(Box::new(EkfMl::new(config, initial))),
        // Localisation target selection (paper 000 section 4.4) on: the look-back points where
        // the map predicts the best fix.
        "ekf-ml-targets" => Some(Box::new(EkfMl::with_params(
            config,
            initial,
            EkfMlParams { select_targets: true, ..Default::default() },
        ))),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn registry_builds_every_listed_name_and_rejects_others() {
        for name in LOCALIZER_NAMES {
            let l = localizer_by_name(name, &RoverConfig::default(), Pose3::default());
            assert_eq!(l.map(|l| l.name().to_string()).as_deref(), Some(*name));
        }
        assert!(localizer_by_name("nope", &RoverConfig::default(), Pose3::default()).is_none());
    }
}
