//! Paper 002 section 3.3's test: twelve stereo views one metre apart in a line, each matched
//! against the previous one (there: mean absolute errors 3.17 cm downrange, 3.66 cm
//! crossrange), here on synthetic rocky terrain with stereo-like range noise growing with the
//! square of the range.

use rovernav_core::Pose3;
use rovernav_localization::evaluation::{SequenceSetup, sequence_accuracy};
use rovernav_localization::synthetic::{StereoModel, TerrainParams, fractal_terrain, stereo_points};

#[test]
fn twelve_views_one_metre_apart_localise_within_three_centimetres() {
    let field = fractal_terrain(&TerrainParams { size: 24.0, resolution: 0.025, ..Default::default() }, 0);
    // 2 mm range noise at 1 m, 5 cm at 5 m.
    let model = StereoModel { fov: 150f64.to_radians(), range_noise_at_1m: 0.002, ..Default::default() };
    let truth: Vec<Pose3> = (0..12)
        .map(|i| Pose3 {
            x: -5.5 + i as f64,
            y: 0.1 * (i as f64 * 0.7).sin(),
            yaw: 0.02 * (i as f64).cos(),
            ..Default::default()
        })
        .collect();
    let setup = SequenceSetup::default();
    let report =
        sequence_accuracy(|pose, seed| stereo_points(&field, pose, &model, seed), &truth, &setup, 1, 2)
            .expect("sequence");
    for s in &report.steps {
        eprintln!(
            "downrange {:+.3} crossrange {:+.3} yaw {:+.4} (sigma {:.3} {:.3} {:.4}) p_fail {:.3}",
            s.downrange, s.crossrange, s.yaw, s.sigma[0], s.sigma[1], s.sigma[2], s.failure_probability
        );
    }
    eprintln!(
        "mean |downrange| {:.4} m, mean |crossrange| {:.4} m, within 3 sigma {:.3}",
        report.mean_abs_downrange, report.mean_abs_crossrange, report.within_three_sigma
    );
    assert_eq!(report.steps.len(), 11);
    assert!(report.mean_abs_downrange <= 0.03);
    assert!(report.mean_abs_crossrange <= 0.03);
    assert!(report.within_three_sigma >= 0.97);
    assert!(report.steps.iter().all(|s| s.failure_probability < 0.2));
}
