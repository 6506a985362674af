//! The CAHVOR model of a real MSL Navcam EDR label (sol 24, left camera), checked against the
//! instrument (a 45 deg field of view over 1024 pixels) and against the label's own derived
//! pointing and field of view, which JPL's ground software computed independently.

use nalgebra::{Point2, Vector3};
use rovernav_terrain::io::Pds3Label;
use rovernav_vision::camera::{AnyCamera, Cahvor, CameraModel, read};

const NAVCAM: &str = "gale/navcam/NLA_399621413EDR_F0030308NCAM00405M1.IMG";

use rovernav_core::data_file_or_skip as data_file;

fn navcam() -> Option<(Pds3Label, Cahvor)> {
    let label = Pds3Label::open(data_file(NAVCAM)?).expect("label parses");
    match read::from_pds3_label(&label).expect("camera model reads") {
        AnyCamera::Cahvor(m) => Some((label, m)),
        other => panic!("expected CAHVOR, got {}", other.type_name()),
    }
}

/// Azimuth (clockwise from +x towards +y) and elevation (up, with z down) in degrees, the
/// conventions of MSL's ROVER_NAV_FRAME.
fn az_el(d: &Vector3<f64>) -> (f64, f64) {
    (d.y.atan2(d.x).to_degrees(), (-d.z).atan2(d.x.hypot(d.y)).to_degrees())
}

/// The angle between two vectors (atan2 of the cross and dot products: acos loses half the
/// digits near zero).
fn angle_deg(a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    a.cross(b).norm().atan2(a.dot(b)).to_degrees()
}

#[test]
fn focal_lengths_and_centre_match_a_45_degree_field_over_1024_pixels() {
    let Some((_, cam)) = navcam() else { return };
    assert_eq!((cam.width, cam.height), (1024, 1024));
    assert!((cam.a.norm() - 1.0).abs() < 1e-12 && (cam.o.norm() - 1.0).abs() < 1e-12, "A, O normalised");
    // The distortion axis O lies within a degree of A.
    assert!(angle_deg(&cam.a, &cam.o) < 1.0, "O is {} deg from A", angle_deg(&cam.a, &cam.o));
    // 45 deg over 1024 pixels: f = 512 / tan(22.5 deg) = 1236.1 px. "45 deg" is the nominal
    // field rounded to the degree; a field between 44 and 46 deg gives f between 1208 and
    // 1265 px, so the tolerance is 30 px (2.4 %).
    let nominal = 512.0 / 22.5f64.to_radians().tan();
    let (fh, fv) = (cam.focal_h(), cam.focal_v());
    eprintln!("focal lengths {fh:.2} {fv:.2} px (nominal {nominal:.1})");
    assert!((fh - nominal).abs() < 30.0 && (fv - nominal).abs() < 30.0);
    // Square pixels: the two focal lengths agree to 0.5 %.
    assert!((fh / fv - 1.0).abs() < 5e-3);
    // The image centre lies within 2 % of the frame (20 px) of the middle of the detector.
    let (hc, vc) = cam.image_centre();
    eprintln!("image centre {hc:.2} {vc:.2}");
    assert!((hc - 511.5).abs() < 20.0 && (vc - 511.5).abs() < 20.0);
}

#[test]
fn field_of_view_through_the_full_model_matches_the_label() {
    let Some((label, cam)) = navcam() else { return };
    let parms = label.block("INSTRUMENT_STATE_PARMS").expect("INSTRUMENT_STATE_PARMS");
    let az_fov = parms.get_f64("AZIMUTH_FOV").expect("AZIMUTH_FOV");
    let el_fov = parms.get_f64("ELEVATION_FOV").expect("ELEVATION_FOV");
    // Edge to edge of the detector (outer borders of the first and last pixels), through the
    // middle row and column.
    let ray = |x: f64, y: f64| cam.unproject(&Point2::new(x, y)).direction.into_inner();
    let h = angle_deg(&ray(-0.5, 511.5), &ray(1023.5, 511.5));
    let v = angle_deg(&ray(511.5, -0.5), &ray(511.5, 1023.5));
    eprintln!("field of view {h:.4} x {v:.4} deg; label {az_fov} x {el_fov}");
    assert!((h - 45.0).abs() < 1.0 && (v - 45.0).abs() < 1.0, "nominal 45 deg within 1 deg");
    // The label's own field of view (JPL's, from the same model) agrees to its four printed
    // decimals (5e-4 deg measured).
    assert!((h - az_fov).abs() < 2e-3 && (v - el_fov).abs() < 2e-3, "label's field within 2e-3 deg");
}

#[test]
fn pointing_matches_the_labels_derived_azimuth_and_elevation() {
    let Some((label, cam)) = navcam() else { return };
    let derived = label.block("ROVER_DERIVED_GEOMETRY_PARMS").expect("ROVER_DERIVED_GEOMETRY_PARMS");
    let az = derived.get_f64("INSTRUMENT_AZIMUTH").expect("INSTRUMENT_AZIMUTH");
    let el = derived.get_f64("INSTRUMENT_ELEVATION").expect("INSTRUMENT_ELEVATION");
    // The label's pointing is that of the middle pixel's ray (the image centre (H.A, V.A) is
    // 8 px from the middle, 0.4 deg): the model's ray there agrees to the label's four printed
    // decimals (2e-4 deg measured).
    let mid = cam.unproject(&Point2::new(511.5, 511.5)).direction.into_inner();
    let (maz, mel) = az_el(&mid);
    eprintln!("middle ray az {maz:.4} el {mel:.4}; label {az} {el}");
    assert!((maz - az).abs() < 1e-3 && (mel - el).abs() < 1e-3);
    // The pointing axis A itself is within a degree of it.
    let (aaz, ael) = az_el(&cam.a);
    assert!((aaz - az).abs() < 1.0 && (ael - el).abs() < 1.0);
}

#[test]
fn unproject_then_project_returns_the_pixel_across_the_image() {
    let Some((_, cam)) = navcam() else { return };
    let mut worst: f64 = 0.0;
    let mut pixels: Vec<(f64, f64)> = vec![(-0.5, -0.5), (1023.5, -0.5), (-0.5, 1023.5), (1023.5, 1023.5)];
    for i in 0..=32 {
        for j in 0..=32 {
            pixels.push((i as f64 * 1023.0 / 32.0, j as f64 * 1023.0 / 32.0 + 0.37));
        }
    }
    for &(x, y) in &pixels {
        let ray = cam.unproject(&Point2::new(x, y));
        for t in [0.5, 5.0, 50.0, 5000.0] {
            let back = cam.project(&ray.at(t)).expect("in front");
            worst = worst.max((back.x - x).hypot(back.y - y));
        }
    }
    eprintln!("worst unproject-project error {worst:.3e} px");
    assert!(worst < 1e-6);
    // The R terms matter at the corners: the linear part alone puts the corner ray 0.9 px
    // away (the Navcam's lens is nearly distortion-free), 1e5 times the tolerance above.
    let corner = cam.unproject(&Point2::new(-0.5, -0.5));
    let linear = cam.linear().project(&corner.at(10.0)).unwrap();
    let shift = (linear.x + 0.5).hypot(linear.y + 0.5);
    eprintln!("corner distortion {shift:.2} px");
    assert!(shift > 0.5, "the corner is {shift} px from its linear position");
}

#[test]
fn project_then_unproject_returns_the_direction() {
    let Some((_, cam)) = navcam() else { return };
    let mut worst: f64 = 0.0;
    for i in 0..=20 {
        for j in 0..=20 {
            // Directions filling the field: through the linear model's pixels, then projected
            // through the full model.
            let lin = cam.linear().unproject(&Point2::new(i as f64 * 51.15, j as f64 * 51.15));
            let p = lin.at(3.0 + i as f64);
            let px = cam.project(&p).expect("in front");
            let ray = cam.unproject(&px);
            worst = worst.max(angle_deg(&ray.direction, &(p - ray.origin)));
        }
    }
    eprintln!("worst direction error {worst:.3e} deg");
    assert!(worst < 1e-9);
}

#[test]
fn the_terrain_crates_model_projects_identically() {
    let Some((label, cam)) = navcam() else { return };
    let terrain = label.cahvor().expect("terrain reads CAHVOR");
    let converted = Cahvor::from_terrain(&terrain, 1024, 1024);
    for (x, y) in [(converted.c, cam.c), (converted.a, cam.a), (converted.h, cam.h), (converted.v, cam.v)]
        .into_iter()
        .chain([(converted.o, cam.o), (converted.r, cam.r)])
    {
        assert!((x - y).norm() < 1e-12, "{x:?} vs {y:?}");
    }
    // The terrain crate projects with A and O as printed (not normalised, |A| and |O| differ
    // from 1 by up to 1e-5): the two agree to 0.02 px (8e-3 px measured).
    let mut worst: f64 = 0.0;
    for k in 0..50 {
        let t = k as f64;
        let p = cam.c + Vector3::new(0.3 * (t * 0.7).sin(), 1.0 + 0.2 * t, 0.5 + 0.3 * (t * 1.3).cos());
        let ours = cam.project(&p.into()).expect("in front");
        let theirs = terrain.project([p.x, p.y, p.z]).expect("in front");
        worst = worst.max((ours.x - theirs.0).hypot(ours.y - theirs.1));
    }
    eprintln!("worst difference from the terrain crate's projection {worst:.2e} px");
    assert!(worst < 0.02);
}
