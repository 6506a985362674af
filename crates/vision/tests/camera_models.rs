//! CAHV, CAHVOR and CAHVORE: analytic Jacobians against finite differences, CAHVORE against
//! CAHVOR where they coincide, round trips on random models, rigid motion, and the readers.

use nalgebra::{Isometry3, Matrix2x3, Point2, Point3, Translation3, UnitQuaternion, Vector3};
use proptest::prelude::*;
use rovernav_terrain::io::Pds3Label;
use rovernav_vision::camera::{
    AnyCamera, Cahv, Cahvor, Cahvore, CahvoreType, CameraModel, CameraReadError, Movable, read,
};

fn linear(f: f64, size: usize, tilt: f64) -> Cahv {
    let half = (size as f64 - 1.0) / 2.0;
    Cahv::from_intrinsics(
        Vector3::new(0.2, -0.1, 1.3),
        Vector3::new(1.0, tilt, -0.4),
        Vector3::new(0.1, -1.0, 0.0),
        f,
        f * 1.002,
        half + 3.0,
        half - 2.0,
        size,
        size,
    )
}

/// A unit vector within about `deg` degrees of `axis`.
fn tilted(axis: &Vector3<f64>, deg: f64, phase: f64) -> Vector3<f64> {
    let side = axis.cross(&Vector3::z()).normalize();
    let up = side.cross(axis).normalize();
    let t = deg.to_radians();
    (axis + (side * phase.cos() + up * phase.sin()) * t.tan()).normalize()
}

fn cahvor(f: f64, r: [f64; 3]) -> Cahvor {
    let lin = linear(f, 1024, 0.05);
    Cahvor::new(lin, tilted(&lin.a, 0.7, 0.4), Vector3::from(r))
}

fn cahvore(f: f64, r: [f64; 3], e: [f64; 3], kind: CahvoreType) -> Cahvore {
    let lin = linear(f, 1024, 0.05);
    Cahvore::new(lin, tilted(&lin.a, 0.7, 0.4), Vector3::from(r), Vector3::from(e), kind)
}

/// Central differences of `project`, step 1e-6 of the range.
fn numeric_jacobian(cam: &dyn CameraModel, p: &Point3<f64>) -> Matrix2x3<f64> {
    let step = 1e-6 * (p - cam.centre()).norm();
    let mut jac = Matrix2x3::zeros();
    for k in 0..3 {
        let mut dp = Vector3::zeros();
        dp[k] = step;
        let d = cam.project(&(p + dp)).unwrap() - cam.project(&(p - dp)).unwrap();
        jac.set_column(k, &(d / (2.0 * step)));
    }
    jac
}

fn sample_points(cam: &dyn CameraModel) -> Vec<Point3<f64>> {
    let mut out = Vec::new();
    for &(x, y) in
        &[(0.0, 0.0), (1023.0, 0.0), (512.0, 500.0), (100.0, 900.0), (1023.0, 1023.0), (700.0, 30.0)]
    {
        let ray = cam.unproject(&Point2::new(x, y));
        for t in [0.7, 4.0, 30.0] {
            out.push(ray.at(t));
        }
    }
    out
}

#[test]
fn analytic_jacobians_match_finite_differences() {
    let models: Vec<AnyCamera> = vec![
        linear(1200.0, 1024, 0.05).into(),
        cahvor(1236.0, [0.000274, -0.004951, 0.021485]).into(),
        cahvor(600.0, [0.01, -0.2, 0.1]).into(),
        cahvore(1236.0, [0.000274, -0.004951, 0.021485], [0.002, -0.01, 0.005], CahvoreType::Perspective)
            .into(),
        cahvore(300.0, [0.0, 0.04, -0.01], [0.003, 0.01, -0.02], CahvoreType::Fisheye).into(),
        cahvore(400.0, [0.0, 0.02, -0.005], [-0.004, 0.02, 0.0], CahvoreType::General(0.6)).into(),
        cahvore(350.0, [0.0, 0.02, -0.005], [0.004, 0.0, 0.01], CahvoreType::General(-0.3)).into(),
    ];
    for cam in &models {
        for p in sample_points(cam) {
            let (px, analytic) = cam.project_jacobian(&p).expect("in front");
            assert_eq!(Some(px), cam.project(&p));
            let numeric = numeric_jacobian(cam, &p);
            let scale = numeric.abs().max().max(1e-3);
            let err = (analytic - numeric).abs().max() / scale;
            assert!(err < 1e-6, "{}: relative Jacobian error {err:.2e} at {p}", cam.type_name());
        }
    }
}

#[test]
fn cahvore_perspective_without_pupil_motion_is_cahvor() {
    let r = [0.001, -0.03, 0.05];
    let a = cahvor(900.0, r);
    let b = cahvore(900.0, r, [0.0; 3], CahvoreType::Perspective);
    for p in sample_points(&a) {
        let (pa, pb) = (a.project(&p).unwrap(), b.project(&p).unwrap());
        assert!((pa - pb).norm() < 1e-9, "{pa} vs {pb}");
    }
    for &(x, y) in &[(0.0, 0.0), (1023.0, 511.0), (321.5, 987.25)] {
        let pixel = Point2::new(x, y);
        let (ra, rb) = (a.unproject(&pixel), b.unproject(&pixel));
        assert!((ra.direction.into_inner() - rb.direction.into_inner()).norm() < 1e-12);
        assert!((ra.origin - rb.origin).norm() < 1e-15);
    }
}

#[test]
fn fisheye_sees_beyond_ninety_degrees_and_the_pupil_moves() {
    // A 1024-px fish-eye with f = 250 px covers theta = 511.5 / 250 = 117 deg at the edge.
    let cam = cahvore(250.0, [0.0, 0.0, 0.0], [0.01, 0.02, 0.0], CahvoreType::Fisheye);
    let (hc, _) = cam.image_centre();
    let ray = cam.unproject(&Point2::new(hc + 480.0, 509.5));
    let theta = ray.direction.dot(&cam.o).acos();
    assert!(theta > 90f64.to_radians(), "edge ray at {} deg", theta.to_degrees());
    // The pupil has moved forward along O by s(theta) > 0 for positive E.
    let s = (ray.origin - cam.centre()).dot(&cam.o);
    assert!((s - cam.pupil_shift(theta)).abs() < 1e-12 && s > 0.01);
    let back = cam.project(&ray.at(2.0)).unwrap();
    assert!((back - Point2::new(hc + 480.0, 509.5)).norm() < 1e-6);
}

#[test]
fn moved_models_project_moved_points_to_the_same_pixel() {
    let pose = Isometry3::from_parts(
        Translation3::new(3.0, -2.0, 0.5),
        UnitQuaternion::from_euler_angles(0.1, -0.2, 1.1),
    );
    let models: Vec<AnyCamera> = vec![
        linear(800.0, 1024, 0.0).into(),
        cahvor(800.0, [0.0, -0.02, 0.01]).into(),
        cahvore(500.0, [0.0, 0.01, 0.0], [0.01, 0.0, 0.0], CahvoreType::General(0.5)).into(),
    ];
    for cam in &models {
        let moved = cam.moved(&pose);
        for p in sample_points(cam) {
            let (a, b) = (cam.project(&p).unwrap(), moved.project(&(pose * p)).unwrap());
            assert!((a - b).norm() < 1e-8, "{}: {a} vs {b}", cam.type_name());
        }
    }
}

/// Checks both round trips on one model over a grid of pixels including the corners.
fn check_round_trips(cam: &dyn CameraModel) -> Result<(), TestCaseError> {
    let (w, h) = (cam.width() as f64, cam.height() as f64);
    let mut pixels = vec![(-0.5, -0.5), (w - 0.5, -0.5), (-0.5, h - 0.5), (w - 0.5, h - 0.5)];
    for i in 0..=8 {
        for j in 0..=8 {
            pixels.push(((w - 1.0) * i as f64 / 8.0, (h - 1.0) * j as f64 / 8.0));
        }
    }
    for (x, y) in pixels {
        let pixel = Point2::new(x, y);
        let ray = cam.unproject(&pixel);
        for t in [0.3, 3.0, 300.0] {
            let p = ray.at(t);
            let back = cam.project(&p);
            prop_assert!(back.is_some(), "({x}, {y}) at {t}: not projected");
            let back = back.unwrap();
            prop_assert!((back - pixel).norm() < 1e-6, "({x}, {y}) at {t}: back at {back}");
            let again = cam.unproject(&back);
            let err = again.direction.into_inner().cross(&(p - again.origin).normalize()).norm();
            prop_assert!(err < 1e-9, "({x}, {y}) at {t}: direction off by {err}");
        }
    }
    Ok(())
}

/// Whether the radial polynomial (1 + r0) chi + r1 chi^3 + r2 chi^5 rises steadily out to beyond
/// the image corner (`chi_corner` of the linear model): calibrated models do over their image,
/// random ones need not.
fn radial_monotone(r: &Vector3<f64>, chi_corner: f64) -> bool {
    (0..=100).all(|k| {
        let x = 1.5 * chi_corner * k as f64 / 100.0;
        (1.0 + r[0]) + 3.0 * r[1] * x * x + 5.0 * r[2] * x.powi(4) > 0.2
    })
}

/// chi of the linear model at the image corner farthest from the image centre.
fn corner_chi(lin: &Cahv) -> f64 {
    let (hc, vc) = lin.image_centre();
    let dx = hc.max(lin.width as f64 - hc) / lin.focal_h();
    let dy = vc.max(lin.height as f64 - vc) / lin.focal_v();
    dx.hypot(dy)
}

fn kind_strategy() -> impl Strategy<Value = CahvoreType> {
    prop_oneof![
        Just(CahvoreType::Perspective),
        Just(CahvoreType::Fisheye),
        (-0.5..1.0f64).prop_map(CahvoreType::General),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn random_cahvor_models_round_trip(
        half_fov in 15.0..50.0f64,
        size in 64usize..1600,
        tilt in -0.3..0.3f64,
        o_deg in 0.0..2.0f64,
        phase in 0.0..6.3f64,
        r0 in -0.01..0.01f64,
        r1 in -0.05..0.05f64,
        r2 in -0.01..0.03f64,
    ) {
        let f = (size as f64 / 2.0) / half_fov.to_radians().tan();
        let lin = linear(f, size, tilt);
        let cam = Cahvor::new(lin, tilted(&lin.a, o_deg, phase), Vector3::new(r0, r1, r2));
        prop_assume!(radial_monotone(&cam.r, corner_chi(&lin)));
        check_round_trips(&cam)?;
    }

    #[test]
    fn random_cahvore_models_round_trip(
        half_fov in 15.0..55.0f64,
        size in 64usize..1600,
        tilt in -0.3..0.3f64,
        o_deg in 0.0..2.0f64,
        phase in 0.0..6.3f64,
        r1 in -0.03..0.03f64,
        r2 in -0.01..0.02f64,
        e in prop::array::uniform3(-0.01..0.01f64),
        kind in kind_strategy(),
    ) {
        // The focal length that puts the edge of the field at `half_fov` from the axis.
        let l = kind.linearity();
        let t = half_fov.to_radians() * std::f64::consts::SQRT_2;
        let chi = if l > 1e-9 { (l * t).tan() / l } else if l < -1e-9 { (l * t).sin() / l } else { t };
        let f = (size as f64 / 2.0) * std::f64::consts::SQRT_2 / chi;
        let lin = linear(f, size, tilt);
        let cam = Cahvore::new(lin, tilted(&lin.a, o_deg, phase), Vector3::new(0.0, r1, r2), Vector3::from(e), kind);
        prop_assume!(radial_monotone(&cam.r, corner_chi(&lin)));
        check_round_trips(&cam)?;
    }
}

const CAHVORE_LABEL: &str = "PDS_VERSION_ID = PDS3
OBJECT = IMAGE
  LINES = 960
  LINE_SAMPLES = 1280
END_OBJECT = IMAGE
GROUP = GEOMETRIC_CAMERA_MODEL
  MODEL_TYPE = CAHVORE
  MODEL_COMPONENT_1 = (0.563572,0.473888,-1.90136)
  MODEL_COMPONENT_2 = (-0.199471,-0.828431,0.523382)
  MODEL_COMPONENT_3 = (589.435,-711.664,337.385)
  MODEL_COMPONENT_4 = (-3.98773,-26.3001,884.12)
  MODEL_COMPONENT_5 = (-0.198073,-0.828704,0.52348)
  MODEL_COMPONENT_6 = (2e-06,0.049535,-0.015973)
  MODEL_COMPONENT_7 = (-0.003612,0.013016,-0.023961)
  MODEL_COMPONENT_8 = 3.0
  MODEL_COMPONENT_9 = 0.25
END_GROUP = GEOMETRIC_CAMERA_MODEL
END
";

#[test]
fn reads_a_cahvore_pds3_label_and_names_missing_fields() {
    let label = Pds3Label::parse(std::path::Path::new("hazcam.lbl"), CAHVORE_LABEL).unwrap();
    let AnyCamera::Cahvore(cam) = read::from_pds3_label(&label).unwrap() else { panic!("not CAHVORE") };
    assert_eq!((cam.width, cam.height), (1280, 960));
    assert_eq!(cam.kind, CahvoreType::General(0.25));
    assert_eq!(cam.e, Vector3::new(-0.003612, 0.013016, -0.023961));
    let broken = CAHVORE_LABEL.replace("  MODEL_COMPONENT_7 = (-0.003612,0.013016,-0.023961)\n", "");
    let label = Pds3Label::parse(std::path::Path::new("hazcam.lbl"), &broken).unwrap();
    let err = read::from_pds3_label(&label).unwrap_err();
    assert_eq!(err.to_string(), "hazcam.lbl: field GEOMETRIC_CAMERA_MODEL.MODEL_COMPONENT_7 missing");
    let bad_type = CAHVORE_LABEL.replace("MODEL_COMPONENT_8 = 3.0", "MODEL_COMPONENT_8 = 7.0");
    let label = Pds3Label::parse(std::path::Path::new("hazcam.lbl"), &bad_type).unwrap();
    let err = read::from_pds3_label(&label).unwrap_err().to_string();
    assert!(err.contains("MODEL_COMPONENT_8") && err.contains("not 1, 2 or 3"), "{err}");
    let no_size = CAHVORE_LABEL.replace("  LINES = 960\n", "");
    let label = Pds3Label::parse(std::path::Path::new("hazcam.lbl"), &no_size).unwrap();
    assert_eq!(
        read::from_pds3_label(&label).unwrap_err().to_string(),
        "hazcam.lbl: field IMAGE.LINES missing"
    );
}

/// A hand-made record in the format of the Mars 2020 raw-images API (the model of a Navcam
/// image of sol 14, as the API publishes it; the other fields trimmed).
const M2020_RECORD: &str = r#"{
  "imageid": "NLF_0014_0668192307_846ECM_N0030110NCAM02014_01_285J",
  "sol": 14,
  "camera": {
    "instrument": "NAVCAM_LEFT",
    "camera_vector": "(-0.199471,-0.828431,0.523382)",
    "camera_position": "(0.563572,0.473888,-1.90136)",
    "camera_model_type": "CAHVORE",
    "camera_model_component_list": "(0.563572,0.473888,-1.90136);(-0.199471,-0.828431,0.523382);(589.435,-711.664,337.385);(-3.98773,-26.3001,884.12);(-0.198073,-0.828704,0.52348);(2e-06,0.049535,-0.015973);(-0.003612,0.013016,-0.023961);2.0;0.0"
  },
  "extended": { "dimension": "(1280,960)", "subframeRect": "(1,1,5120,3840)", "scaleFactor": "4" }
}"#;

#[test]
fn reads_a_mars_2020_raw_image_record() {
    let cam = read::from_m2020_json_str(M2020_RECORD, "record.json").unwrap();
    let AnyCamera::Cahvore(m) = cam else { panic!("not CAHVORE") };
    assert_eq!(m.kind, CahvoreType::Fisheye);
    assert_eq!((m.width, m.height), (1280, 960));
    assert_eq!(m.r, Vector3::new(2e-06, 0.049535, -0.015973));
    // The model suits the returned image: its centre is near the middle of 1280 x 960.
    let (hc, vc) = m.image_centre();
    assert!((hc - 639.5).abs() < 40.0 && (vc - 479.5).abs() < 40.0, "centre {hc} {vc}");
    // camera_vector is the pointing axis.
    let axis = m.unproject(&Point2::new(hc, vc)).direction;
    assert!(axis.dot(&m.a) > (0.5f64).to_radians().cos());
    check_round_trips(&m).unwrap();
    // Older records carry the camera fields at the top level.
    let mut record: serde_json::Value = serde_json::from_str(M2020_RECORD).unwrap();
    let camera = record["camera"].take();
    record["camera_model_type"] = camera["camera_model_type"].clone();
    record["camera_model_component_list"] = camera["camera_model_component_list"].clone();
    assert_eq!(read::from_m2020_json(&record, "flat.json").unwrap(), cam);
}

#[test]
fn mars_2020_errors_name_the_field() {
    let cases = [
        (M2020_RECORD.replace("\"dimension\": \"(1280,960)\", ", ""), "field extended.dimension missing"),
        (M2020_RECORD.replace("(1280,960)", "(1280;960)"), "field extended.dimension: \"(1280;960)\""),
        (M2020_RECORD.replace("CAHVORE\"", "CAHVOR2\""), "field camera.camera_model_type: unsupported"),
        (M2020_RECORD.replace(";2.0;0.0", ""), "field camera.camera_model_component_list[7] missing"),
        (
            M2020_RECORD.replace("(2e-06,0.049535,-0.015973)", "(2e-06,x,-0.015973)"),
            "component_list[5]: expected",
        ),
        (
            M2020_RECORD.replace("(-0.199471,-0.828431,0.523382);", "(-0.9,-0.8,0.5);"),
            "component_list[1]: expected a unit",
        ),
        ("{ \"camera\": 3 ".to_string(), "record.json: not JSON"),
    ];
    for (text, expected) in cases {
        let err = read::from_m2020_json_str(&text, "record.json").unwrap_err();
        assert!(matches!(
            err,
            CameraReadError::Missing { .. } | CameraReadError::Invalid { .. } | CameraReadError::Json { .. }
        ));
        let message = err.to_string();
        assert!(
            message.starts_with("record.json: ") && message.contains(expected),
            "{message} lacks {expected}"
        );
    }
}
