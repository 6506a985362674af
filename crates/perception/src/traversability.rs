//! MRPTA traversability (paper 004 section 3.3): slope S, roughness R and neighbourhood N
//! combined as `T = min(S + R/2, N)` on a 1..14 scale (higher better, 7 neutral, <= 2 not
//! traversable); 0 marks an unsensed cell in the output layer.
//!
//! The paper gives the combination and the scale but not how S, R and N are put on it; this
//! module does it so that each hazard alone can make a cell non-traversable and so that a flat,
//! smooth, level cell scores the best value:
//!
//! * **S** (slope score) = `14 - 12 * slope / max_slope`, the slope being the tilt of the
//!   least-squares plane through the cell's points. A level cell scores 14 and a cell at the
//!   rover's maximum tilt scores 2 (not traversable), linearly in between. With
//!   `slope_block = 1` (the terrain evaluator's default) the plane is fitted through the points
//!   of the 3x3 cells around the cell: on a level plane imaged with 1 cm range noise the
//!   0.15 m cells' own planes tilt 2 to 17 degrees at random (few points, often in one or two
//!   range lines), while the 0.45 m patch is steady to a fraction of a degree.
//! * **R** (roughness score) = `-24 * sigma / max_roughness`, a penalty, where sigma is the RMS
//!   of the point heights about that plane (the variance of the elevations once the cell's own
//!   tilt is removed, so slope is not counted twice), less the expected sensor noise. It is
//!   scaled so that `R/2` takes a level cell down by the same 12 points at `max_roughness`
//!   that S loses at `max_slope`. Hence `S + R/2 = 14 - 12 * (slope/max_slope +
//!   sigma/max_roughness)`: the two normalised hazards add, and reach "not traversable" when
//!   they sum to 1.
//! * **N** (neighbourhood score) = `14 - 12 * |N(i, j)| / max_step`, where `N(i, j)` is the
//!   paper's height difference between the cell and the weighted heights of its three
//!   neighbours on the side of the grid centre (the rover): the step met when travelling from
//!   the cell towards the rover. A step of the rover's belly clearance scores 2. The weights are
//!   `c1 = |i|/C, c2 = |j|/C, c3 = 1 - c1 - c2` with `C = |i| + |j| + (|i| + |j|)/sqrt(2)`,
//!   applied to the neighbours `(i - si, j)`, `(i - si, j - sj)` and `(i, j - sj)` (si, sj the
//!   signs of i and j, 0 on an axis): the first-quadrant formula mirrored into the other
//!   quadrants. Unsensed neighbours are left out and the remaining weights renormalised; the
//!   centre cell and cells with no sensed neighbour towards it have no neighbourhood limit.
//!
//! The result is rounded and clamped to 1..14.

use crate::cell::CellStats;
use crate::footprint::fit_planes;

/// Best traversability value.
pub const TRAVERSABILITY_MAX: u8 = 14;
/// Value at or below which a cell is not traversable.
pub const TRAVERSABILITY_BLOCKED: u8 = 2;
/// Neutral value (what planners assume for unsensed cells).
pub const TRAVERSABILITY_NEUTRAL: u8 = 7;
/// Output value of an unsensed cell.
pub const TRAVERSABILITY_UNSENSED: u8 = 0;

/// Limits that put slope, roughness and neighbourhood on the traversability scale.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TraversabilityParams {
    /// Slope that scores "not traversable" (rad): the rover's maximum tilt.
    pub max_slope: f64,
    /// Roughness (RMS about the cell plane) that scores "not traversable" (m).
    pub max_roughness: f64,
    /// Step towards the rover that scores "not traversable" (m): the belly clearance.
    pub max_step: f64,
    /// Standard deviation of range noise in height (m), removed from the roughness.
    pub sensor_noise: f64,
    /// Half-size in cells of the block whose points the slope plane is fitted through (0: the
    /// cell alone, as in the paper).
    pub slope_block: usize,
}

/// The slope score S for a plane tilt (rad).
pub fn slope_score(slope: f64, p: &TraversabilityParams) -> f64 {
    14.0 - 12.0 * slope / p.max_slope
}

/// The roughness penalty R for an RMS height deviation about the cell plane (m).
pub fn roughness_score(sigma: f64, p: &TraversabilityParams) -> f64 {
    let excess = (sigma * sigma - p.sensor_noise * p.sensor_noise).max(0.0).sqrt();
    -24.0 * excess / p.max_roughness
}

/// The neighbourhood score for a neighbourhood estimate N (m); `None` means no limit.
pub fn neighbourhood_score(n: Option<f64>, p: &TraversabilityParams) -> f64 {
    n.map_or(f64::INFINITY, |n| 14.0 - 12.0 * n.abs() / p.max_step)
}

/// Combines the three scores into the 1..14 scale: `min(S + R/2, N)`, rounded and clamped.
pub fn combine(s: f64, r: f64, n: f64) -> u8 {
    let t = (s + 0.5 * r).min(n);
    if t.is_nan() {
        return TRAVERSABILITY_BLOCKED;
    }
    t.round().clamp(1.0, 14.0) as u8
}

/// The paper's neighbourhood estimate N for a cell `di` rows and `dj` columns from the grid
/// centre, given a height lookup (NaN or `None` = unsensed) relative to that cell.
pub fn neighbourhood_estimate(di: i64, dj: i64, height: impl Fn(i64, i64) -> Option<f64>) -> Option<f64> {
    if di == 0 && dj == 0 {
        return None;
    }
    let h = height(0, 0)?;
    let (ai, aj) = (di.abs() as f64, dj.abs() as f64);
    let big_c = ai + aj + (ai + aj) / std::f64::consts::SQRT_2;
    let c1 = ai / big_c;
    let c2 = aj / big_c;
    let c3 = 1.0 - c1 - c2;
    let (si, sj) = (di.signum(), dj.signum());
    let neighbours = [(c1, -si, 0), (c2, -si, -sj), (c3, 0, -sj)];
    let (mut weight, mut sum) = (0.0, 0.0);
    for (c, oi, oj) in neighbours {
        if c <= 0.0 {
            continue;
        }
        if let Some(hn) = height(oi, oj) {
            weight += c;
            sum += c * hn;
        }
    }
    (weight > 0.0).then(|| h - sum / weight)
}

/// Slope (rad, NaN when no plane fits) and RMS roughness (m) of cell `(col, row)`.
///
/// The plane is the least-squares plane through the points of the `(2*block + 1)^2` cells
/// centred on the cell (`block = 0`: the cell's own points, as the paper states); the roughness
/// is the RMS of the cell's *own* point heights about that plane. Without a plane (fewer than
/// three points, or all on one line) the slope is unknown and the roughness is the plain spread.
pub fn cell_slope_and_roughness(
    cells: &[CellStats],
    cols: usize,
    rows: usize,
    resolution: f64,
    (col, row): (usize, usize),
    block: usize,
) -> (f32, f32) {
    let cell = &cells[row * cols + col];
    let mut patch = *cell;
    for rr in row.saturating_sub(block)..(row + block + 1).min(rows) {
        for cc in col.saturating_sub(block)..(col + block + 1).min(cols) {
            if (rr, cc) != (row, col) {
                let dx = (cc as f64 - col as f64) * resolution;
                let dy = (rr as f64 - row as f64) * resolution;
                patch.merge_offset(&cells[rr * cols + cc], dx, dy);
            }
        }
    }
    match patch.plane_fit() {
        Some(fit) => {
            let ms = cell.mean_square_residual(&fit, patch.reference_height()).unwrap_or(0.0);
            (fit.slope() as f32, ms.sqrt() as f32)
        }
        None => (f32::NAN, cell.variance().unwrap_or(0.0).sqrt() as f32),
    }
}

/// Traversability of every cell of a row-major window of cell statistics whose grid centre
/// (the rover) is cell `centre = (col, row)`; `heights` are the cells' mean heights (NaN where
/// unsensed). Output: 1..14, 0 for unsensed cells.
pub fn traversability_layer(
    cells: &[CellStats],
    heights: &[f32],
    cols: usize,
    rows: usize,
    resolution: f64,
    centre: (usize, usize),
    p: &TraversabilityParams,
) -> Vec<u8> {
    // Cells whose points fit no plane take the slope of the 3x3 neighbourhood of cell means.
    let (fallback, _) = fit_planes(heights, cols, rows, resolution, 1, 3);
    let mut out = vec![TRAVERSABILITY_UNSENSED; cols * rows];
    for r in 0..rows {
        for c in 0..cols {
            let i = r * cols + c;
            if cells[i].count == 0 || !heights[i].is_finite() {
                continue;
            }
            let (cell_slope, sigma) =
                cell_slope_and_roughness(cells, cols, rows, resolution, (c, r), p.slope_block);
            let slope = if cell_slope.is_finite() {
                cell_slope as f64
            } else if fallback[i].valid {
                fallback[i].slope
            } else {
                0.0
            };
            let di = r as i64 - centre.1 as i64;
            let dj = c as i64 - centre.0 as i64;
            let n = neighbourhood_estimate(di, dj, |oi, oj| {
                let (rr, cc) = (r as i64 + oi, c as i64 + oj);
                if rr < 0 || cc < 0 || rr >= rows as i64 || cc >= cols as i64 {
                    return None;
                }
                let h = heights[rr as usize * cols + cc as usize];
                h.is_finite().then_some(h as f64)
            });
            out[i] = combine(
                slope_score(slope, p),
                roughness_score(sigma.max(0.0) as f64, p),
                neighbourhood_score(n, p),
            );
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> TraversabilityParams {
        TraversabilityParams {
            max_slope: 25f64.to_radians(),
            max_roughness: 0.06,
            max_step: 0.18,
            sensor_noise: 0.0,
            slope_block: 0,
        }
    }

    /// A 3x3 window with the rover at the centre cell (1, 1); the cell under test is (2, 2)
    /// (first quadrant, i = j = 1). `surface(x, y, k)` gives the height of the point at
    /// (x, y) with index parity k (a 4x4 pattern of points per cell).
    fn build(surface: impl Fn(f64, f64, usize) -> f64) -> (Vec<CellStats>, Vec<f32>) {
        let res = 0.15;
        let mut cells = vec![CellStats::EMPTY; 9];
        for r in 0..3 {
            for c in 0..3 {
                let (cx, cy) = ((c as f64 + 0.5) * res, (r as f64 + 0.5) * res);
                for a in 0..4 {
                    for b in 0..4 {
                        let (dx, dy) = ((a as f64 - 1.5) * 0.03, (b as f64 - 1.5) * 0.03);
                        cells[r * 3 + c].add(dx, dy, surface(cx + dx, cy + dy, (a + b) % 2));
                    }
                }
            }
        }
        let heights = cells.iter().map(|c| c.mean().unwrap() as f32).collect();
        (cells, heights)
    }

    fn layer(cells: &[CellStats], heights: &[f32]) -> Vec<u8> {
        traversability_layer(cells, heights, 3, 3, 0.15, (1, 1), &params())
    }

    fn t_at_corner(cells: &[CellStats], heights: &[f32]) -> u8 {
        layer(cells, heights)[8]
    }

    #[test]
    fn weights_match_the_paper_on_the_diagonal_and_axes() {
        // i = j = 1: C = 2 + 2/sqrt(2) = 3.4142; c1 = c2 = 0.2929, c3 = 0.4142.
        // Neighbour heights 1, 2, 3 for (i-1, j), (i-1, j-1), (i, j-1); cell height 10.
        let n = neighbourhood_estimate(1, 1, |oi, oj| match (oi, oj) {
            (0, 0) => Some(10.0),
            (-1, 0) => Some(1.0),
            (-1, -1) => Some(2.0),
            (0, -1) => Some(3.0),
            _ => None,
        })
        .unwrap();
        let expected = 10.0 - 0.292_893_2 * 1.0 - 0.292_893_2 * 2.0 - 0.414_213_6 * 3.0;
        assert!((n - expected).abs() < 1e-6, "{n} vs {expected}");
        // On the column axis (i = 0, j = 2) all weight falls on (0, j-1).
        let n = neighbourhood_estimate(0, 2, |oi, oj| match (oi, oj) {
            (0, 0) => Some(1.0),
            (0, -1) => Some(0.25),
            _ => Some(100.0),
        })
        .unwrap();
        assert!((n - 0.75).abs() < 1e-12);
        // Third quadrant mirrors: neighbours towards the centre are (+1, 0), (+1, +1), (0, +1).
        let n = neighbourhood_estimate(-3, -3, |oi, oj| {
            Some(if (oi, oj) == (0, 0) {
                5.0
            } else if oi >= 0 && oj >= 0 {
                4.0
            } else {
                -50.0
            })
        })
        .unwrap();
        assert!((n - 1.0).abs() < 1e-12);
        assert_eq!(neighbourhood_estimate(0, 0, |_, _| Some(1.0)), None);
    }

    #[test]
    fn flat_smooth_cell_scores_fourteen() {
        let (cells, h) = build(|_, _, _| 2.0);
        assert_eq!(t_at_corner(&cells, &h), 14);
    }

    #[test]
    fn tilted_plane_scores_by_slope_and_neighbourhood() {
        // Plane tilted 12.5 deg (half the max tilt) along x: S = 14 - 6 = 8, R = 0.
        // N: cell (2,2) height minus 0.2929*h(1,2) + 0.2929*h(1,1) + 0.4142*h(2,1), where the
        // columns-1 neighbours sit 0.15 m lower: N = (0.2929 + 0.4142) * 0.15 * tan(12.5 deg)
        // = 0.02351 m, score 14 - 12 * 0.02351 / 0.18 = 12.43. T = min(8, 12.43) = 8.
        let g = 12.5f64.to_radians().tan();
        let (cells, h) = build(|x, _, _| g * x);
        assert_eq!(t_at_corner(&cells, &h), 8);
    }

    #[test]
    fn block_plane_keeps_the_slope_of_a_uniform_plane() {
        let g = 12.5f64.to_radians().tan();
        let (cells, _) = build(|x, y, _| g * x - 0.3 * g * y);
        for block in [0, 1, 2] {
            let (slope, sigma) = cell_slope_and_roughness(&cells, 3, 3, 0.15, (1, 1), block);
            let expected = (g.hypot(0.3 * g)).atan();
            assert!((slope as f64 - expected).abs() < 1e-5, "block {block}: {slope}");
            assert!(sigma < 1e-6);
        }
    }

    #[test]
    fn rough_cell_is_penalised_by_half_its_roughness_score() {
        // Points alternate +-0.03 m about a level plane in a 4x4 checkerboard, which has no
        // correlation with x or y: the plane stays level, sigma = 0.03 m,
        // R = -24 * 0.03 / 0.06 = -12, S = 14, S + R/2 = 8; all cells share mean 0 so N = 0.
        let (cells, h) = build(|_, _, k| if k == 0 { 0.03 } else { -0.03 });
        let fit = cells[8].plane_fit().unwrap();
        assert!(fit.slope() < 1e-9);
        assert!((fit.residual_variance.sqrt() - 0.03).abs() < 1e-9);
        assert_eq!(t_at_corner(&cells, &h), 8);
    }

    #[test]
    fn step_towards_the_rover_is_not_traversable() {
        // Cell (2, 2) is a level 0.18 m block on level ground: N = 0.18, N score = 2.
        let (cells, h) = build(|x, y, _| if x > 0.3 && y > 0.3 { 0.18 } else { 0.0 });
        assert_eq!(t_at_corner(&cells, &h), 2);
        // A 0.09 m block: N score 14 - 6 = 8.
        let (cells, h) = build(|x, y, _| if x > 0.3 && y > 0.3 { 0.09 } else { 0.0 });
        assert_eq!(t_at_corner(&cells, &h), 8);
    }

    #[test]
    fn unsensed_cells_are_zero_and_max_tilt_is_blocked() {
        let (mut cells, mut h) = build(|x, _, _| 25f64.to_radians().tan() * x);
        cells[0] = CellStats::EMPTY;
        h[0] = f32::NAN;
        let t = layer(&cells, &h);
        assert_eq!(t[0], TRAVERSABILITY_UNSENSED);
        assert_eq!(t[8], TRAVERSABILITY_BLOCKED);
        assert_eq!(combine(14.0, 0.0, f64::INFINITY), 14);
        assert_eq!(combine(-30.0, -5.0, 3.0), 1);
    }
}
