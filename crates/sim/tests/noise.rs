//! Sensor noise statistics match their stated standard deviations over many samples.

mod common;

use common::{flat, mean, plane, std_dev};
use rovernav_core::{NavCommand, Pose2, RoverConfig, SenseRequest, angle_diff};
use rovernav_sim::sensors::RangeGeometry;
use rovernav_sim::{SensorModel, Simulator};

fn within_ten_percent(measured: f64, sigma: f64, what: &str) {
    assert!((measured / sigma - 1.0).abs() < 0.1, "{what}: sample std {measured} vs sigma {sigma}");
}

#[test]
fn compass_inclinometer_sun_and_gyro_at_rest() {
    let model = SensorModel { initial_rest_samples: 3000, ..SensorModel::default() };
    // A plane rising to the north-east so that roll and pitch are both non-zero.
    let t = plane(10.0, 0.05, 0.1, 0.2);
    let mut sim = Simulator::new(t, RoverConfig::default(), model.clone(), Pose2::new(5.0, 5.0, 0.4), 11);
    let truth = sim.truth();
    assert!(truth.roll.abs() > 0.05 && truth.pitch.abs() > 0.05);
    let frame = sim.initial_frame();
    assert_eq!(frame.imu.len(), 3000);
    let compass: Vec<f64> = frame.imu.iter().map(|s| angle_diff(s.compass_yaw, truth.yaw)).collect();
    let roll: Vec<f64> = frame.imu.iter().map(|s| s.incl_roll - truth.roll).collect();
    let pitch: Vec<f64> = frame.imu.iter().map(|s| s.incl_pitch - truth.pitch).collect();
    let sun: Vec<f64> = frame.imu.iter().map(|s| angle_diff(s.sun_yaw.expect("sun"), truth.yaw)).collect();
    within_ten_percent(std_dev(&compass), model.compass_sigma, "compass");
    within_ten_percent(std_dev(&roll), model.inclinometer_sigma, "roll");
    within_ten_percent(std_dev(&pitch), model.inclinometer_sigma, "pitch");
    within_ten_percent(std_dev(&sun), model.sun_sigma, "sun");
    for (v, s) in [
        (&compass, model.compass_sigma),
        (&roll, model.inclinometer_sigma),
        (&pitch, model.inclinometer_sigma),
    ] {
        assert!(mean(v).abs() < 4.0 * s / (v.len() as f64).sqrt(), "unbiased");
    }
    // Gyro at rest: mean is the bias, spread is the white noise of one 0.1 s sample.
    let gyro: Vec<f64> = frame.imu.iter().map(|s| s.gyro_z).collect();
    let white = model.gyro_noise_density / (1.0 / model.sample_rate).sqrt();
    within_ten_percent(std_dev(&gyro), white, "gyro");
    assert!((mean(&gyro) - sim.gyro_bias()).abs() < 5.0 * white / (gyro.len() as f64).sqrt() + 1e-6);
    // Samples are 0.1 s apart.
    assert!((frame.imu[1].t - frame.imu[0].t - 0.1).abs() < 1e-9);
}

#[test]
fn stereo_range_error_grows_with_the_square_of_range() {
    let model = SensorModel {
        mast: rovernav_sim::RangeImagerModel { dropout: 0.0, ..SensorModel::default().mast },
        ..SensorModel::default()
    };
    let rover = RoverConfig::default();
    let mut sim =
        Simulator::new(flat(20.0, 0.1), rover.clone(), model.clone(), Pose2::new(10.0, 10.0, 0.3), 21);
    let k = model.mast.sigma_quadratic;
    let bins = [1.5, 3.0, 4.5];
    let mut errors: Vec<Vec<f64>> = vec![Vec::new(); bins.len()];
    for _ in 0..25 {
        let f = sim.execute(&NavCommand::Sense(vec![SenseRequest::Mast { pan: 0.0 }]));
        let c = &f.clouds[0];
        for p in &c.points {
            let d = [p[0] as f64 - c.origin[0], p[1] as f64 - c.origin[1], p[2] as f64 - c.origin[2]];
            let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            // Noise is along the ray, so the direction is exact: level ground at body z = 0
            // lies at range h / sin(depression) along it.
            let true_r = c.origin[2] / (-d[2] / r);
            for (b, centre) in bins.iter().enumerate() {
                if (true_r - centre).abs() < 0.25 {
                    errors[b].push((r - true_r) / (k * true_r * true_r));
                }
            }
        }
    }
    for (b, e) in errors.iter().enumerate() {
        assert!(e.len() > 500, "bin {} has {} samples", bins[b], e.len());
        within_ten_percent(std_dev(e), 1.0, &format!("normalised stereo error at {} m", bins[b]));
    }
}

#[test]
fn dropouts_remove_the_stated_fraction_of_returns() {
    let model = SensorModel::default();
    let rover = RoverConfig::default();
    let mut sim =
        Simulator::new(flat(20.0, 0.1), rover.clone(), model.clone(), Pose2::new(10.0, 10.0, 0.0), 5);
    // Rays that meet level ground within the wedge's range, counted from the geometry alone.
    let g = RangeGeometry::mast(&rover, &model, 0.0);
    let mut expected = 0usize;
    for row in 0..model.mast.rows {
        for col in 0..model.mast.cols {
            let d = g.ray(&model.mast, col, row);
            if d[2] < 0.0 && g.origin[2] / -d[2] * d[0].hypot(d[1]) <= rover.mast_range {
                expected += 1;
            }
        }
    }
    let images = 20;
    let mut got = 0usize;
    for _ in 0..images {
        got += sim.execute(&NavCommand::Sense(vec![SenseRequest::Mast { pan: 0.0 }])).clouds[0].points.len();
    }
    let n = (expected * images) as f64;
    let kept = got as f64 / n;
    let p = model.mast.dropout;
    assert!((kept - (1.0 - p)).abs() < 4.0 * (p * (1.0 - p) / n).sqrt() + 1e-3, "kept {kept}");
}

#[test]
fn lidar_range_error_is_constant() {
    let model = SensorModel::default();
    let mut sim = Simulator::new(
        flat(30.0, 0.1),
        RoverConfig::default(),
        model.clone(),
        Pose2::new(15.0, 15.0, 0.0),
        8,
    );
    let (mut near, mut far) = (Vec::new(), Vec::new());
    for _ in 0..3 {
        let f = sim.execute(&NavCommand::Sense(vec![SenseRequest::Lidar { pan: 0.0 }]));
        let c = &f.clouds[0];
        for p in &c.points {
            let d = [p[0] as f64 - c.origin[0], p[1] as f64 - c.origin[1], p[2] as f64 - c.origin[2]];
            let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            let true_r = c.origin[2] / (-d[2] / r);
            if true_r < 3.0 {
                near.push(r - true_r)
            } else if true_r > 5.0 {
                far.push(r - true_r)
            }
        }
    }
    within_ten_percent(std_dev(&near), model.lidar.imager.sigma_constant, "lidar near");
    within_ten_percent(std_dev(&far), model.lidar.imager.sigma_constant, "lidar far");
}
