//! Matching with the heading known from other sensors (paper 002 section 3: a sun sensor and
//! gyros give the orientation, the terrain match gives the position): a search window of zero
//! heading half-width searches translation only, and neither the search nor the peak fit may
//! move the heading.

use rovernav_core::{GridGeometry, Pose2, Wedge};
use rovernav_localization::matching::{MlMatcher, MlParams, SearchWindow};
use rovernav_localization::synthetic::{TerrainParams, fractal_terrain, local_map_from_field};

#[test]
fn a_window_without_heading_width_keeps_the_given_heading_and_finds_the_position() {
    let r = 0.05;
    let field = fractal_terrain(
        &TerrainParams { size: 16.0, resolution: r / 2.0, rocks_per_100m2: 30.0, ..Default::default() },
        3,
    );
    let global =
        field.sample(GridGeometry { cols: 200, rows: 200, resolution: r, origin_x: -5.0, origin_y: -5.0 });
    let matcher = MlMatcher::new(&global, MlParams::default()).expect("global map");
    let truth = Pose2::new(0.3, -0.2, 0.4);
    let geometry = GridGeometry { cols: 80, rows: 120, resolution: r, origin_x: 0.0, origin_y: -3.0 };
    let wedge = Wedge { bearing: 0.0, half_angle: 0.6, min_range: 0.8, max_range: 4.0 };
    let local = local_map_from_field(&field, &truth, geometry, Some(&wedge), 0.005, 0.05, 7);
    for (k, heading_error) in [0.0, 0.002, -0.003].into_iter().enumerate() {
        let center = Pose2::new(truth.x - 0.12, truth.y + 0.08, truth.yaw + heading_error);
        let window = SearchWindow { center, half_x: 0.3, half_y: 0.3, half_yaw: 0.0 };
        let fast = matcher.match_detailed(&local, &window, false).expect("branch and bound");
        let exhaustive = matcher.match_detailed(&local, &window, true).expect("exhaustive");
        let m = fast.result;
        assert_eq!(m.pose.yaw, center.yaw, "case {k}: the heading moved");
        assert_eq!(m.covariance[2][2], 0.0, "case {k}: a fixed heading has no variance");
        assert_eq!(fast.best_index, exhaustive.best_index, "case {k}: not the exhaustive optimum");
        assert_eq!(fast.best_index[2], 0, "case {k}");
        let error = (m.pose.x - truth.x).hypot(m.pose.y - truth.y);
        eprintln!("case {k}: heading error {heading_error:+.3} rad, position error {error:.3} m");
        // A heading error of e rotates cells ~2 m out by 2e: the position stays within a cell.
        assert!(error <= r, "case {k}: position error {error:.3} m");
        assert!(m.covariance[0][0] > 0.0 && m.covariance[1][1] > 0.0, "case {k}");
    }
}
