//! Rover detection in lander images (paper 002 section 2) on rendered scenes, against the
//! renderer's truth: the detected image position against the box of the pixels whose rover
//! label changed, the stereo range against the renderer's true range along that pixel's ray.

use nalgebra::Point2;
use rovernav_core::RoverConfig;
use rovernav_sim::render::{Label, Rig};
use rovernav_sim::scenes::Site;
use rovernav_sim::scenes::lander::{LanderCapture, LanderSetup};
use rovernav_vision::CameraModel;
use rovernav_vision::image::GreyF32;
use rovernav_vision::lander::{DetectParams, detect_rover};
use rovernav_vision::stereo::StereoRig;
use rovernav_vision::tracking::approach::grey_f32;

fn grey(img: &rovernav_sim::render::RenderedImage) -> GreyF32 {
    grey_f32(img.image.width(), img.image.height(), img.image.as_raw()).expect("sized buffer")
}

fn rig() -> Rig {
    let mut rig = Rig::new(&RoverConfig::default());
    rig.lander_position = [0.0, 0.0, 1.8];
    rig.lander_fov = 40f64.to_radians();
    rig.lander_size = 320;
    rig
}

/// At 3, 6 and 9 m the detected rover position is within a few pixels of the centre of the
/// rover's box (chassis and mast head) at both poses, projected from the true poses (the
/// detector also sees the rover's shadow change, the truth box does not), and the triangulated
/// depth is within half the 10-90 % span of the true depths of the region's rover pixels, plus
/// two predicted sigmas, of their median (the region also holds the rover's changed shadow on
/// the ground behind it).
#[test]
fn the_detection_finds_the_rover_where_the_truth_puts_it() {
    let rover = RoverConfig::default();
    let rig = rig();
    for (k, range) in [3.0, 6.0, 9.0].into_iter().enumerate() {
        let seed = 11 + k as u64;
        let site = Site::new(seed);
        let setup = LanderSetup { range_m: range, ..LanderSetup::random(seed, (2.0, 10.0), 0.2) };
        let cap = LanderCapture::render(&site, &rover, &rig, &setup, seed);
        let stereo = StereoRig::new(cap.cameras[0], cap.cameras[1]).unwrap();
        let d = detect_rover(
            &stereo,
            &grey(&cap.before),
            &grey(&cap.after_left),
            &grey(&cap.after_right),
            &DetectParams::aimed(cap.cameras[0].focal_h(), rig.lander_baseline, range),
        )
        .unwrap_or_else(|e| panic!("range {range}: {e}"));
        assert!(cap.changed_rover_pixels() > 50);
        let (x0, x1, y0, y1) = cap.true_rover_box(&rover).expect("the rover is in front of the lander");
        let truth = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
        let err = (d.pixel.x - truth.0).hypot(d.pixel.y - truth.1);
        // A few pixels, or a tenth of the rover box where the rover's changing shadow widens
        // the changed region.
        let allowed = 4f64.max(0.1 * (x1 - x0).max(y1 - y0));
        assert!(
            err <= allowed,
            "range {range}: detected {:?}, truth {truth:?} ({err:.1} px > {allowed:.1})",
            d.pixel
        );
        // The true depths (along the camera axis) of the region's pixels that show the rover,
        // from the renderer: the correlated depth lies within their spread, near their median.
        let cam = &cap.cameras[0];
        let w = cap.after_left.width();
        let mut depths: Vec<f64> = d
            .region
            .pixels
            .iter()
            .filter(|&&(x, y)| cap.after_left.labels[y as usize * w + x as usize] == Label::Rover)
            .map(|&(x, y)| {
                let ray = cam.unproject(&Point2::new(x as f64, y as f64));
                cap.after_left.range[y as usize * w + x as usize] as f64 * ray.direction.dot(&cam.a)
            })
            .collect();
        depths.sort_by(f64::total_cmp);
        let q = |f: f64| depths[((depths.len() - 1) as f64 * f).round() as usize];
        let (p10, median, p90) = (q(0.1), q(0.5), q(0.9));
        println!(
            "range {range}: pixel error {err:.1} px, depth {:.3} m, rover depths {p10:.3} / {median:.3} / {p90:.3} m",
            d.depth_m
        );
        // Matthies' depth sigma at the stereo's own disparity precision.
        let sigma = d.range_sigma_m * d.depth_m / d.range_m;
        let allowed = 0.5 * (p90 - p10) + 2.0 * sigma;
        assert!(
            (d.depth_m - median).abs() <= allowed,
            "range {range}: stereo depth {:.3} m, rover depths 10/50/90 % {p10:.3} / {median:.3} / {p90:.3} m, allowed {allowed:.3}",
            d.depth_m
        );
    }
}
