//! Elevation-map preparation for matching (paper 002 section 3.1 and 3.2).
//!
//! Range points are binned into a grid over the xy-plane and each bin's height is the mean of
//! the heights of the points in it (paper 002 section 3.1); the maps are then high-pass
//! filtered so that matching needs no search in the vertical direction (section 3.2), and the
//! occupied cells of a map are listed as the points the matchers score.

use rovernav_core::{Grid2, GridGeometry, Pose3};

/// Bins body-frame range points into an elevation grid: each point is placed with `pose`
/// (use a pose with only roll and pitch for a levelled rover-frame map, the full pose for a
/// world-frame map) and each cell's height is the mean of its points' heights (NaN if none).
pub fn bin_points(points: &[[f32; 3]], pose: &Pose3, geometry: GridGeometry) -> Grid2<f32> {
    let mut sum = vec![0.0f64; geometry.len()];
    let mut count = vec![0u32; geometry.len()];
    for p in points {
        let w = pose.transform([f64::from(p[0]), f64::from(p[1]), f64::from(p[2])]);
        if !w.iter().all(|v| v.is_finite()) {
            continue;
        }
        if let Some((c, r)) = geometry.cell_of(w[0], w[1]) {
            let i = geometry.index(c, r);
            sum[i] += w[2];
            count[i] += 1;
        }
    }
    Grid2 {
        geometry,
        data: sum
            .iter()
            .zip(&count)
            .map(|(&s, &n)| if n > 0 { (s / f64::from(n)) as f32 } else { f32::NAN })
            .collect(),
    }
}

/// High-pass filter: each known height minus the mean of the known heights within a square
/// window of `window` metres (side); unknown (NaN) cells stay unknown.
pub fn high_pass(map: &Grid2<f32>, window: f64) -> Grid2<f32> {
    let (cols, rows) = (map.cols(), map.rows());
    let half = ((0.5 * window / map.resolution()).round() as usize).max(1);
    // Summed-area tables of heights and of known-cell counts.
    let stride = cols + 1;
    let mut sum = vec![0.0f64; (rows + 1) * stride];
    let mut count = vec![0i64; (rows + 1) * stride];
    for r in 0..rows {
        for c in 0..cols {
            let h = *map.get(c, r);
            let (v, n) = if h.is_finite() { (f64::from(h), 1) } else { (0.0, 0) };
            let i = (r + 1) * stride + c + 1;
            sum[i] = v + sum[i - 1] + sum[i - stride] - sum[i - stride - 1];
            count[i] = n + count[i - 1] + count[i - stride] - count[i - stride - 1];
        }
    }
    let mut out = map.clone();
    for r in 0..rows {
        for c in 0..cols {
            let h = *map.get(c, r);
            if !h.is_finite() {
                continue;
            }
            let (c0, c1) = (c.saturating_sub(half), (c + half + 1).min(cols));
            let (r0, r1) = (r.saturating_sub(half), (r + half + 1).min(rows));
            let s =
                sum[r1 * stride + c1] - sum[r0 * stride + c1] - sum[r1 * stride + c0] + sum[r0 * stride + c0];
            let n = count[r1 * stride + c1] - count[r0 * stride + c1] - count[r1 * stride + c0]
                + count[r0 * stride + c0];
            *out.get_mut(c, r) = (f64::from(h) - s / n.max(1) as f64) as f32;
        }
    }
    out
}

/// The known cells of a map as (x, y, height) at the cell centres, in the map's frame.
pub fn occupied_cells(map: &Grid2<f32>) -> Vec<[f64; 3]> {
    let mut out = Vec::new();
    for r in 0..map.rows() {
        for c in 0..map.cols() {
            let h = *map.get(c, r);
            if h.is_finite() {
                let (x, y) = map.geometry.center(c, r);
                out.push([x, y, f64::from(h)]);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn geometry(cols: usize, rows: usize) -> GridGeometry {
        GridGeometry { cols, rows, resolution: 0.1, origin_x: 0.0, origin_y: 0.0 }
    }

    #[test]
    fn binning_averages_points_per_cell_and_applies_the_pose() {
        let pose = Pose3 { x: 0.5, z: 1.0, ..Default::default() };
        let points = [[0.01f32, 0.01, 0.2], [0.04, 0.02, 0.4], [0.25, 0.05, -1.0]];
        let g = bin_points(&points, &pose, geometry(10, 10));
        assert!((g.get(5, 0) - 1.3).abs() < 1e-6);
        assert!((g.get(7, 0) - 0.0).abs() < 1e-6);
        assert!(g.get(0, 0).is_nan());
    }

    #[test]
    fn high_pass_removes_planes_in_the_interior_and_keeps_bumps() {
        let mut g = Grid2::filled(geometry(20, 20), 0.0f32);
        for r in 0..20 {
            for c in 0..20 {
                *g.get_mut(c, r) = 0.3 * c as f32 + 0.1 * r as f32;
            }
        }
        *g.get_mut(3, 3) = f32::NAN;
        let hp = high_pass(&g, 0.4);
        // A plane's mean over a symmetric window is its centre value.
        assert!(hp.get(10, 10).abs() < 1e-5);
        assert!(hp.get(3, 3).is_nan());
        *g.get_mut(10, 10) += 1.0;
        let hp = high_pass(&g, 0.4);
        // Window of 5x5 cells: the bump keeps 24/25 of its height.
        assert!((hp.get(10, 10) - 0.96).abs() < 1e-4);
    }
}
