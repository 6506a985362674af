//! Matching crops of the real Gale crater DEM (HiRISE, 1 m/pixel) shifted and rotated by known
//! amounts, with noise and holes; and flagging featureless terrain.

mod common;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rovernav_core::{Grid2, GridGeometry, Pose2};
use rovernav_localization::matching::{MlMatcher, MlParams, SearchWindow};
use rovernav_localization::synthetic::{HeightField, local_map_from_field};

/// Parameters for 1 m DEM cells: an 8 m high-pass keeps the hills, and 5 cm height layers
/// (vertical exaggeration 20) let the 8 degree mean slope separate poses.
fn dem_params() -> MlParams {
    MlParams {
        high_pass_window: Some(8.0),
        vertical_exaggeration: 20.0,
        sigma_cells: 1.5,
        ..Default::default()
    }
}

/// The rover-frame local map of a square of half-side `half` around `pose`.
fn local_square(
    field: &HeightField,
    pose: &Pose2,
    half: f64,
    noise: f64,
    holes: f64,
    seed: u64,
) -> Grid2<f32> {
    let n = (2.0 * half) as usize;
    let geometry = GridGeometry { cols: n, rows: n, resolution: 1.0, origin_x: -half, origin_y: -half };
    local_map_from_field(field, pose, geometry, None, noise, holes, seed)
}

#[test]
fn shifted_and_rotated_dem_crops_are_recovered_within_one_cell() {
    let Some(path) = rovernav_core::data_file_or_skip("gale/missionDEM.tif") else {
        return;
    };
    let dem = rovernav_terrain::io::load_geotiff(&path).expect("Gale DEM");
    assert_eq!((dem.heights.cols(), dem.heights.rows()), (348, 337));
    let field = HeightField { heights: dem.heights.clone() };
    let g = dem.heights.geometry;
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let mut worst: f64 = 0.0;
    let mut confident = 0;
    for case in 0..6u64 {
        // A global crop of 100 m x 100 m somewhere in the DEM (world frame = DEM local frame).
        let x0 = g.origin_x + rng.random_range(30.0..g.width_m() - 130.0);
        let y0 = g.origin_y + rng.random_range(30.0..g.height_m() - 130.0);
        let global_geometry =
            GridGeometry { cols: 100, rows: 100, resolution: 1.0, origin_x: x0, origin_y: y0 };
        let global = field.sample(global_geometry);
        let truth = Pose2::new(
            x0 + 50.0 + rng.random_range(-5.0..5.0),
            y0 + 50.0 + rng.random_range(-5.0..5.0),
            rng.random_range(-3.1..3.1),
        );
        let local = local_square(&field, &truth, 20.0, 0.05, 0.2, case);
        let matcher = MlMatcher::new(&global, dem_params()).expect("global");
        let prior = Pose2::new(truth.x + 3.0, truth.y - 2.0, truth.yaw + 0.05);
        let window = SearchWindow { center: prior, half_x: 6.0, half_y: 6.0, half_yaw: 0.12 };
        let r = matcher.match_map(&local, &window).expect("match");
        let err = (r.pose.x - truth.x).hypot(r.pose.y - truth.y);
        eprintln!(
            "case {case}: error {err:.2} m, yaw {:+.4} rad, p_fail {:.3}, evaluated {}",
            r.pose.yaw - truth.yaw,
            r.failure_probability,
            r.poses_evaluated
        );
        assert!(err <= 1.0, "case {case}: error {err} m");
        confident += usize::from(r.failure_probability < 0.2);
        worst = worst.max(err);
    }
    eprintln!("worst position error {worst:.2} m (1 m cells)");
    // Real terrain has ambiguous patches; most crops must still be confident matches.
    assert!(confident >= 5, "only {confident} of 6 crops matched confidently");
}

#[test]
fn featureless_terrain_is_flagged_as_a_likely_failure() {
    // A plane with 2 cm noise (a flat plain at 1 m resolution): nothing to match.
    let geometry = GridGeometry { cols: 200, rows: 200, resolution: 1.0, origin_x: 0.0, origin_y: 0.0 };
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let mut heights = Grid2::filled(geometry, 0.0f32);
    for (i, h) in heights.data.iter_mut().enumerate() {
        let (c, r) = ((i % 200) as f32, (i / 200) as f32);
        *h = 0.02 * c + 0.01 * r + rng.random_range(-0.02..0.02);
    }
    let field = HeightField { heights };
    let global =
        field.sample(GridGeometry { cols: 100, rows: 100, resolution: 1.0, origin_x: 50.0, origin_y: 50.0 });
    let truth = Pose2::new(100.0, 100.0, 0.4);
    let local = local_square(&field, &truth, 20.0, 0.02, 0.2, 1);
    let matcher = MlMatcher::new(&global, dem_params()).expect("global");
    let window =
        SearchWindow { center: Pose2::new(102.0, 99.0, 0.42), half_x: 6.0, half_y: 6.0, half_yaw: 0.12 };
    let r = matcher.match_map(&local, &window).expect("match");
    eprintln!("flat plain: p_fail {:.3}, pose {:?}", r.failure_probability, r.pose);
    assert!(r.failure_probability > 0.5, "p_fail {}", r.failure_probability);
}
