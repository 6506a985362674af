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

/// High-pass filter: each known height minus the height, at that cell, of the least-squares
/// plane through the known heights within a square window of `window` metres (side); unknown
/// (NaN) cells stay unknown.
///
/// Paper 002 section 3.2 high-passes the maps so that matching needs no vertical search. A
/// plain local mean would do that in the interior of a map, but near the edge of the imaged
/// area (the near-range edge, occlusion shadows) the window is one-sided and the mean of a
/// sloping surface is biased by `slope * offset`; the local map and the global map have their
/// edges in different places, so that bias would pull the match along the slope (the downrange
/// bias of a rover climbing a gentle grade). The local plane removes any linear trend exactly,
/// wherever the known cells are; where they are too few or collinear it falls back to the mean.
pub fn high_pass(map: &Grid2<f32>, window: f64) -> Grid2<f32> {
    let (cols, rows) = (map.cols(), map.rows());
    let half = ((0.5 * window / map.resolution()).round() as usize).max(1);
    // Summed-area tables of the moments n, u, v, uu, uv, vv, z, uz, vz (u, v cell indices).
    const M: usize = 9;
    let stride = cols + 1;
    let mut table = vec![[0.0f64; M]; (rows + 1) * stride];
    for r in 0..rows {
        for c in 0..cols {
            let h = *map.get(c, r);
            let mut m = [0.0; M];
            if h.is_finite() {
                let (u, v, z) = (c as f64, r as f64, f64::from(h));
                m = [1.0, u, v, u * u, u * v, v * v, z, u * z, v * z];
            }
            let i = (r + 1) * stride + c + 1;
            for k in 0..M {
                table[i][k] = m[k] + table[i - 1][k] + table[i - stride][k] - table[i - stride - 1][k];
            }
        }
    }
    map_known_windows(map, half, |h, c, r, (c0, c1, r0, r1)| {
        let mut s = [0.0; M];
        for (k, sk) in s.iter_mut().enumerate() {
            *sk = table[r1 * stride + c1][k] - table[r0 * stride + c1][k] - table[r1 * stride + c0][k]
                + table[r0 * stride + c0][k];
        }
        h - plane_at(&s, c as f64, r as f64)
    })
}

/// The height at (u, v) of the least-squares plane z = a + b (u - u0) + d (v - v0) through
/// points with moments `s` = [n, u, v, uu, uv, vv, z, uz, vz]; the mean if the plane is not
/// determined.
fn plane_at(s: &[f64; 9], u0: f64, v0: f64) -> f64 {
    let n = s[0].max(1.0);
    // Centre the moments on the points' mean so the normal equations are well conditioned.
    let (mu, mv, mz) = (s[1] / n, s[2] / n, s[6] / n);
    let suu = s[3] - n * mu * mu;
    let suv = s[4] - n * mu * mv;
    let svv = s[5] - n * mv * mv;
    let suz = s[7] - n * mu * mz;
    let svz = s[8] - n * mv * mz;
    let det = suu * svv - suv * suv;
    // Fewer than three points, or all on one line: no plane, use the mean.
    if s[0] < 3.0 || det <= 1e-9 * (suu * svv).max(1e-12) {
        return mz;
    }
    let b = (svv * suz - suv * svz) / det;
    let d = (suu * svz - suv * suz) / det;
    mz + b * (u0 - mu) + d * (v0 - mv)
}

/// Fills unknown cells that have known cells on at least two opposite sides within `radius`
/// cells (left and right, or below and above) with the mean of the known heights in the
/// `(2 radius + 1)^2` square around them; other unknown cells stay unknown.
///
/// Why: a sparse range image (a few thousand rays) leaves gaps between the rays' footprints
/// at long range, so that most known cells of a single view border unknown ones. Filling gaps
/// that lie between measurements (and not beyond their edge) lets the matcher tell sampling
/// gaps from real shadows, which stay unknown.
pub fn fill_gaps(map: &Grid2<f32>, radius: usize) -> Grid2<f32> {
    if radius == 0 {
        return map.clone();
    }
    let (cols, rows) = (map.cols(), map.rows());
    let known = |c: usize, r: usize| map.get(c, r).is_finite();
    let mut out = map.clone();
    for r in 0..rows {
        for c in 0..cols {
            if known(c, r) {
                continue;
            }
            let left = (1..=radius.min(c)).any(|d| known(c - d, r));
            let right = (1..=radius).take_while(|d| c + d < cols).any(|d| known(c + d, r));
            let below = (1..=radius.min(r)).any(|d| known(c, r - d));
            let above = (1..=radius).take_while(|d| r + d < rows).any(|d| known(c, r + d));
            if !((left && right) || (below && above)) {
                continue;
            }
            let (mut sum, mut n) = (0.0f64, 0u32);
            for rr in r.saturating_sub(radius)..(r + radius + 1).min(rows) {
                for cc in c.saturating_sub(radius)..(c + radius + 1).min(cols) {
                    let h = *map.get(cc, rr);
                    if h.is_finite() {
                        sum += f64::from(h);
                        n += 1;
                    }
                }
            }
            *out.get_mut(c, r) = (sum / f64::from(n.max(1))) as f32;
        }
    }
    out
}

/// Paper 002's high-pass filter: each known height minus the mean of the known heights within
/// a square window of `window` metres (side); unknown (NaN) cells stay unknown. Used by the
/// Hausdorff matcher as in the paper; [`high_pass`] removes slopes without the edge bias.
pub fn high_pass_mean(map: &Grid2<f32>, window: f64) -> Grid2<f32> {
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
    map_known_windows(map, half, |h, _, _, (c0, c1, r0, r1)| {
        let s = sum[r1 * stride + c1] - sum[r0 * stride + c1] - sum[r1 * stride + c0] + sum[r0 * stride + c0];
        let n = count[r1 * stride + c1] - count[r0 * stride + c1] - count[r1 * stride + c0]
            + count[r0 * stride + c0];
        h - s / n.max(1) as f64
    })
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

/// Maps every known cell to `f(height, col, row, window)`, the window being the cell's
/// `(2 half + 1)^2` neighbourhood clipped to the map as half-open `(c0, c1, r0, r1)`; unknown
/// cells stay unknown.
fn map_known_windows(
    map: &Grid2<f32>,
    half: usize,
    f: impl Fn(f64, usize, usize, (usize, usize, usize, usize)) -> f64,
) -> Grid2<f32> {
    let (cols, rows) = (map.geometry.cols, map.geometry.rows);
    let mut out = map.clone();
    for r in 0..rows {
        for c in 0..cols {
            let h = *map.get(c, r);
            if !h.is_finite() {
                continue;
            }
            let window = (
                c.saturating_sub(half),
                (c + half + 1).min(cols),
                r.saturating_sub(half),
                (r + half + 1).min(rows),
            );
            *out.get_mut(c, r) = f(f64::from(h), c, r, window) as f32;
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
    fn gaps_between_measurements_are_filled_and_edges_are_not() {
        let mut g = Grid2::filled(geometry(10, 10), f32::NAN);
        *g.get_mut(2, 5) = 1.0;
        *g.get_mut(4, 5) = 3.0;
        let f = fill_gaps(&g, 2);
        // Between two measurements: their mean.
        assert!((f.get(3, 5) - 2.0).abs() < 1e-6);
        // Beyond the last measurement, or off to one side: still unknown.
        assert!(f.get(6, 5).is_nan());
        assert!(f.get(3, 7).is_nan());
        assert!(fill_gaps(&g, 0).get(3, 5).is_nan());
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
        // A plane is removed everywhere, also at the edges and next to unknown cells.
        for (c, r) in [(10, 10), (0, 0), (19, 5), (2, 3), (4, 4)] {
            assert!(hp.get(c, r).abs() < 1e-4, "({c}, {r}): {}", hp.get(c, r));
        }
        assert!(hp.get(3, 3).is_nan());
        *g.get_mut(10, 10) += 1.0;
        let hp = high_pass(&g, 0.4);
        // Window of 5x5 cells: the bump keeps 24/25 of its height.
        assert!((hp.get(10, 10) - 0.96).abs() < 1e-4);
    }
}
