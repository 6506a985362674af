use super::*;
use crate::synthetic::{HeightField, StereoModel, TerrainParams, fractal_terrain, stereo_points};
use rovernav_core::{CameraKind, PointCloud, Wedge};

/// Eight fine mast wedges out to 12 m seen from `truth` on `terrain`.
fn panorama(terrain: &HeightField, truth: &Pose3) -> Vec<PointCloud> {
    (0..8)
        .map(|k| {
            let bearing = k as f64 * std::f64::consts::FRAC_PI_4;
            let model = StereoModel {
                bearing,
                fov: 50f64.to_radians(),
                max_range: 12.0,
                ray_spacing: 0.1,
                ..StereoModel::default()
            };
            PointCloud {
                camera: CameraKind::Mast,
                origin: [0.0, 0.0, 1.2],
                wedge: Wedge { bearing, half_angle: 25f64.to_radians(), min_range: 1.0, max_range: 12.0 },
                points: stereo_points(terrain, truth, &model, 100 + k),
            }
        })
        .collect()
}

fn terrain() -> HeightField {
    let params = TerrainParams { size: 50.0, resolution: 0.1, relief: 0.8, ..TerrainParams::default() };
    fractal_terrain(&params, 7)
}

/// A rover whose estimate is 1.4 m off: the first panorama matched against the terrain's 1 m
/// orbital map brings it within 0.5 m of the truth, with a fix counted as used whose
/// position error is within its (scaled) covariance's 99.9 % bound.
#[test]
fn a_panorama_pulls_a_wrong_estimate_to_the_truth() {
    let terrain = terrain();
    let truth = Pose3 { x: 1.0, y: -2.0, yaw: 0.4, ..Default::default() };
    let start = Pose3 { x: truth.x + 1.2, y: truth.y - 0.7, ..truth };
    let params = OrbitalMapParams::default();
    let mut loc = OrbitalMapLocalizer::new(&RoverConfig::default(), start, &terrain.heights, params);
    assert_eq!(loc.orbital_map().resolution(), 1.0, "the 0.1 m field degraded to 1 m");
    loc.reset_position(start.x, start.y, 1.5);
    loc.update(&SensorFrame { clouds: panorama(&terrain, &truth), ..SensorFrame::default() });
    let e = loc.estimate().pose;
    assert!((e.x - truth.x).hypot(e.y - truth.y) < 0.5, "estimate {e:?}, {:?}", loc.orbital_stats());
    assert_eq!(loc.orbital_stats().used, 1);
    let fix = loc.fixes()[0];
    let nees = fix.fix.position_nees(truth.x, truth.y).expect("a covariance");
    assert!(nees < 13.8, "fix NEES {nees}");
    // A frame without clouds leaves the estimate alone and tries nothing.
    loc.update(&SensorFrame::default());
    assert_eq!(loc.orbital_stats().attempted, 1);
}

/// A filter that believes itself within 0.1 m while 3 m off rejects the orbital fix (the
/// truth lies outside its window: the best pose is on the window's edge or fails the gate)
/// rather than fusing a wrong one.
#[test]
fn an_overconfident_estimate_far_off_rejects_the_fix() {
    let terrain = terrain();
    let truth = Pose3 { x: 1.0, y: -2.0, yaw: 0.4, ..Default::default() };
    let start = Pose3 { x: truth.x + 3.0, ..truth };
    let mut loc = OrbitalMapLocalizer::new(
        &RoverConfig::default(),
        start,
        &terrain.heights,
        OrbitalMapParams::default(),
    );
    loc.reset_position(start.x, start.y, 0.1);
    loc.update(&SensorFrame { clouds: panorama(&terrain, &truth), ..SensorFrame::default() });
    let s = loc.orbital_stats();
    assert_eq!((s.attempted, s.used), (1, 0), "{s:?}");
    assert_eq!(loc.estimate().pose.x, start.x);
}

/// The gate's statistic is the position innovation's Mahalanobis length against the summed
/// covariances: checked against the closed form for diagonal covariances.
#[test]
fn innovation_nees_is_the_mahalanobis_length_of_the_innovation() {
    let estimate = PoseEstimate {
        pose: Pose3 { x: 1.0, y: 2.0, ..Default::default() },
        covariance: [[0.5, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 0.1]],
    };
    let fix = MatchResult {
        pose: Pose2::new(2.0, 0.0, 0.0),
        covariance: [[0.5, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 0.1]],
        log_likelihood: 0.0,
        failure_probability: 0.0,
        poses_evaluated: 1,
    };
    let d = innovation_nees(&estimate, &fix).unwrap();
    assert!((d - (1.0 / 1.0 + 4.0 / 4.0)).abs() < 1e-12, "{d}");
    let singular = MatchResult { covariance: [[0.0; 3]; 3], ..fix };
    let flat = PoseEstimate { covariance: [[0.0; 3]; 3], ..estimate };
    assert!(innovation_nees(&flat, &singular).is_none());
}

/// Driving without fixes counts travel, and the look-backs turn sideways in the lead before a
/// fix is due.
#[test]
fn sideways_targets_are_offered_before_a_fix_is_due() {
    let terrain = terrain();
    let params = OrbitalMapParams { fix_interval_m: 10.0, fix_lead_m: 4.0, ..OrbitalMapParams::default() };
    let mut loc =
        OrbitalMapLocalizer::new(&RoverConfig::default(), Pose3::default(), &terrain.heights, params);
    assert_eq!(loc.localization_target(), None);
    loc.travel = 7.0;
    assert_eq!(loc.localization_target(), Some(SIDE_PANS[0]));
    loc.side_looks = 1;
    assert_eq!(loc.localization_target(), Some(SIDE_PANS[1]));
}
