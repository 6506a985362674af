//! The true hazard map: where the rover centre cannot safely be, from full knowledge of the
//! terrain.
//!
//! This is the evaluation's independent truth (the `optimal_length_m` of the report is the
//! shortest path through its safe cells). A cell is unsafe when, with the rover centred on it at
//! any of 24 headings, the rover would leave the DEM, meet a hazard of [`crate::vehicle`] (belly
//! contact, tilt, or a step within one wheel radius of a wheel in any direction). It is therefore
//! conservative: a cell the simulator lets the rover cross in one heading may still be marked.
//!
//! Most cells are close enough to a plane to be decided without settling the rover. If the DEM
//! heights within the rover's reach deviate from a plane P by at most e, then, because the
//! wheel-plane fit is linear in the wheel heights and reproduces a plane exactly, the fitted
//! plane in every heading is P plus the fit of the deviations, whose gradient and belly offset
//! are bounded by multiples of 2e computed from the wheel layout. That bounds tilt, belly rise
//! and steps from above and below for all headings at once; only cells the bounds cannot decide
//! are checked heading by heading.

use rovernav_core::{Grid2, GridGeometry, Point2, Pose2, RoverConfig};
use rovernav_terrain::Terrain;

use crate::vehicle::{self, VehicleGeometry, WHEEL_RADIUS};

/// Headings tried per cell over a full turn.
const HEADINGS: usize = 24;

/// Cells where the rover centre is unsafe in any heading (conservative; independent truth for
/// optimal path length and evaluation). Covers the DEM's extent at `resolution` metres.
pub fn true_hazard_grid(terrain: &Terrain, rover: &RoverConfig, resolution: f64) -> Grid2<bool> {
    let dem = &terrain.dem;
    let g = *dem.geometry();
    let usable = resolution.is_finite() && resolution > 0.0 && g.cols > 0 && g.rows > 0;
    let geometry = GridGeometry {
        cols: if usable { (g.width_m() / resolution).floor() as usize } else { 0 },
        rows: if usable { (g.height_m() / resolution).floor() as usize } else { 0 },
        resolution: if usable { resolution } else { 1.0 },
        origin_x: g.origin_x,
        origin_y: g.origin_y,
    };
    let mut grid = Grid2::filled(geometry, true);
    if geometry.is_empty() {
        return grid;
    }
    let geom = VehicleGeometry::new(rover);
    let bounds = FlatnessBounds::new(&geom);
    let reach = geom.wheels.iter().chain(&geom.belly).map(|p| p.norm()).fold(0.0, f64::max) + WHEEL_RADIUS;
    // Cells whose bilinear patches can touch the footprint of a rover centred anywhere in the
    // DEM cell holding the output cell's centre.
    let half = (reach / g.resolution).ceil() as usize + 2;
    // Within this distance of the DEM's edge some heading puts part of the rover off the DEM.
    let footprint = geom.wheels.iter().chain(&geom.belly).map(|p| p.norm()).fold(0.0, f64::max);
    let (x_min, y_min) = (g.origin_x + footprint, g.origin_y + footprint);
    let (x_max, y_max) = (g.origin_x + g.width_m() - footprint, g.origin_y + g.height_m() - footprint);
    let sums = PlaneSums::new(&dem.heights);
    let checker = HeadingChecker::new(terrain, &geom);
    for row in 0..geometry.rows {
        for col in 0..geometry.cols {
            let (x, y) = geometry.center(col, row);
            let Some((c, r)) = g.cell_of(x, y) else { continue };
            if x < x_min || y < y_min || x > x_max || y > y_max {
                continue;
            }
            let decided =
                sums.local_plane(&dem.heights, c, r, half).and_then(|plane| bounds.decide(&plane, &geom));
            let safe = decided.unwrap_or_else(|| checker.safe_in_every_heading(x, y, (c, r)));
            *grid.get_mut(col, row) = !safe;
        }
    }
    grid
}

/// The heading-by-heading check, with cheap per-cell bounds that spare most exact belly and
/// step evaluations.
struct HeadingChecker<'a> {
    terrain: &'a Terrain,
    geom: &'a VehicleGeometry,
    /// Headings to try, in radians (half a turn when the layout is half-turn symmetric).
    headings: Vec<f64>,
    /// Per DEM cell: lowest and highest cell height within one wheel radius (and the bilinear
    /// corners) of any point of the cell.
    step_lo: Vec<f64>,
    step_hi: Vec<f64>,
    /// Per DEM cell: highest cell height under the belly of a rover centred in the cell, in any
    /// heading.
    belly_hi: Vec<f64>,
}

impl<'a> HeadingChecker<'a> {
    fn new(terrain: &'a Terrain, geom: &'a VehicleGeometry) -> Self {
        let heights = &terrain.dem.heights;
        let res = heights.resolution();
        let turn = if geom.is_half_turn_symmetric() { std::f64::consts::PI } else { std::f64::consts::TAU };
        let count = if geom.is_half_turn_symmetric() { HEADINGS / 2 } else { HEADINGS };
        let headings = (0..count).map(|k| turn * k as f64 / count as f64).collect();
        let (step_lo, step_hi) = window_extremes(heights, (WHEEL_RADIUS / res).ceil() as usize + 1);
        let belly_reach = geom.belly.iter().map(|p| p.norm()).fold(0.0, f64::max);
        let (_, belly_hi) = window_extremes(heights, (belly_reach / res).ceil() as usize + 2);
        Self { terrain, geom, headings, step_lo, step_hi, belly_hi }
    }

    /// Whether the rover centred at (x, y), inside DEM cell `cell`, is safe in every heading.
    fn safe_in_every_heading(&self, x: f64, y: f64, cell: (usize, usize)) -> bool {
        let dem = &self.terrain.dem;
        let g = dem.geometry();
        let belly_hi = self.belly_hi[cell.1 * g.cols + cell.0];
        self.headings.iter().all(|&yaw| {
            let Some(contact) = vehicle::settle(dem, self.geom, Pose2::new(x, y, yaw)) else {
                return false;
            };
            let lowest_plane = self
                .geom
                .belly_corners
                .iter()
                .map(|&p| contact.plane_height(p))
                .fold(f64::INFINITY, f64::min);
            let body_clear = contact.pose.tilt() <= self.geom.max_tilt
                && (belly_hi - lowest_plane <= self.geom.clearance
                    || vehicle::body_hazard(dem, self.geom, &contact).is_none());
            body_clear
                && (0..self.geom.wheels.len()).all(|i| {
                    let p = contact.wheel_positions[i];
                    let h = contact.wheel_heights[i];
                    let k = g.cell_of(p.x, p.y).map(|(c, r)| r * g.cols + c);
                    let bounded = k.is_some_and(|k| {
                        (self.step_hi[k] - h).max(h - self.step_lo[k]) <= self.geom.clearance
                    });
                    bounded
                        || (0..8).all(|d| {
                            let a = d as f64 * std::f64::consts::FRAC_PI_4;
                            vehicle::wheel_step(dem, self.geom, &contact, i, Point2::new(a.cos(), a.sin()))
                                .is_none()
                        })
                })
        })
    }
}

/// How much a unit spread of wheel heights can tilt the fitted plane or lower it under the belly.
struct FlatnessBounds {
    /// Bound of |plane gradient| per metre of height spread.
    slope_per_spread: f64,
    /// Bound of (belly terrain - plane) per metre of height spread.
    belly_per_spread: f64,
}

impl FlatnessBounds {
    fn new(geom: &VehicleGeometry) -> Self {
        // The fitted plane is linear in the wheel heights: plane = sum_i z_i * plane(e_i).
        let unit_planes: Vec<[f64; 3]> = (0..geom.wheels.len())
            .map(|i| {
                let z: Vec<f64> = (0..geom.wheels.len()).map(|k| (k == i) as u8 as f64).collect();
                vehicle::fit_plane(&geom.wheels, &z).unwrap_or([f64::NAN; 3])
            })
            .collect();
        // Gradient weights sum to zero, so a spread d moves them by at most d * sum|w| / 2.
        let b: f64 = unit_planes.iter().map(|p| p[1].abs()).sum::<f64>() / 2.0;
        let c: f64 = unit_planes.iter().map(|p| p[2].abs()).sum::<f64>() / 2.0;
        // Plane value weights at a belly point sum to one; the negative ones can push the plane
        // below the lowest wheel by d * (sum of their magnitudes).
        let belly = geom
            .belly
            .iter()
            .map(|&Point2 { x, y }| {
                unit_planes.iter().map(|p| (p[0] + p[1] * x + p[2] * y).min(0.0).abs()).sum::<f64>()
            })
            .fold(0.0, f64::max);
        Self { slope_per_spread: b.hypot(c), belly_per_spread: 1.0 + belly }
    }

    /// Safe (true) or unsafe (false) in every heading, when the plane bounds decide it.
    fn decide(&self, plane: &LocalPlane, geom: &VehicleGeometry) -> Option<bool> {
        let spread = 2.0 * plane.max_deviation;
        if !spread.is_finite() || !plane.gradient.is_finite() {
            return None;
        }
        let wobble = spread * self.slope_per_spread;
        if (plane.gradient - wobble).max(0.0).atan() > geom.max_tilt {
            return Some(false);
        }
        let safe = (plane.gradient + wobble).atan() <= geom.max_tilt
            && spread * self.belly_per_spread <= geom.clearance
            && spread + plane.gradient * WHEEL_RADIUS <= geom.clearance;
        safe.then_some(true)
    }
}

/// A plane fitted to a square window of cells and the largest deviation of the cells from it.
struct LocalPlane {
    /// Gradient magnitude of the plane (m/m).
    gradient: f64,
    /// Largest |height - plane| over the window's cells (m).
    max_deviation: f64,
}

/// Summed-area tables of h, column * h and row * h (nodata as 0) and of nodata counts, for
/// least-squares planes in O(1) per window.
struct PlaneSums {
    cols: usize,
    nodata: Vec<f64>,
    sum: Vec<f64>,
    sum_c: Vec<f64>,
    sum_r: Vec<f64>,
}

impl PlaneSums {
    fn new(heights: &Grid2<f32>) -> Self {
        let (cols, rows) = (heights.cols(), heights.rows());
        let n = (cols + 1) * (rows + 1);
        let (mut sum, mut sum_c, mut sum_r) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        let mut nodata = vec![0.0; n];
        for r in 0..rows {
            for c in 0..cols {
                let raw = *heights.get(c, r) as f64;
                let h = if raw.is_finite() { raw } else { 0.0 };
                let k = (r + 1) * (cols + 1) + c + 1;
                let (up, left, diag) = (k - (cols + 1), k - 1, k - (cols + 1) - 1);
                nodata[k] = (!raw.is_finite()) as u8 as f64 + nodata[up] + nodata[left] - nodata[diag];
                sum[k] = h + sum[up] + sum[left] - sum[diag];
                sum_c[k] = c as f64 * h + sum_c[up] + sum_c[left] - sum_c[diag];
                sum_r[k] = r as f64 * h + sum_r[up] + sum_r[left] - sum_r[diag];
            }
        }
        Self { cols, nodata, sum, sum_c, sum_r }
    }

    /// Sum of a table over cells c0..c1, r0..r1 (exclusive ends).
    fn window(&self, table: &[f64], c0: usize, c1: usize, r0: usize, r1: usize) -> f64 {
        let w = self.cols + 1;
        table[r1 * w + c1] - table[r0 * w + c1] - table[r1 * w + c0] + table[r0 * w + c0]
    }

    /// The least-squares plane of the cells within `half` cells of cell (c, r), clipped to the
    /// grid.
    fn local_plane(&self, heights: &Grid2<f32>, c: usize, r: usize, half: usize) -> Option<LocalPlane> {
        let (c0, c1) = (c.saturating_sub(half), (c + half + 1).min(heights.cols()));
        let (r0, r1) = (r.saturating_sub(half), (r + half + 1).min(heights.rows()));
        if self.window(&self.nodata, c0, c1, r0, r1) > 0.5 {
            return None;
        }
        let (wc, wr) = ((c1 - c0) as f64, (r1 - r0) as f64);
        let n = wc * wr;
        // Offsets from the rectangle's own centre are uncorrelated, so the fit decouples.
        let (mc, mr) = (0.5 * (c0 + c1 - 1) as f64, 0.5 * (r0 + r1 - 1) as f64);
        let s = self.window(&self.sum, c0, c1, r0, r1);
        let sc = self.window(&self.sum_c, c0, c1, r0, r1) - mc * s;
        let sr = self.window(&self.sum_r, c0, c1, r0, r1) - mr * s;
        let sxx = wr * wc * (wc * wc - 1.0) / 12.0;
        let syy = wc * wr * (wr * wr - 1.0) / 12.0;
        let mean = s / n;
        let gx = if sxx > 0.0 { sc / sxx } else { 0.0 };
        let gy = if syy > 0.0 { sr / syy } else { 0.0 };
        let mut max_deviation = 0.0f64;
        for rr in r0..r1 {
            for cc in c0..c1 {
                let plane = mean + gx * (cc as f64 - mc) + gy * (rr as f64 - mr);
                max_deviation = max_deviation.max((*heights.get(cc, rr) as f64 - plane).abs());
            }
        }
        let res = heights.resolution();
        Some(LocalPlane { gradient: gx.hypot(gy) / res, max_deviation })
    }
}

/// Minimum and maximum of the cell values in the (2 half + 1)-square window around each cell
/// (NaN counts as -inf for the minimum and +inf for the maximum).
fn window_extremes(heights: &Grid2<f32>, half: usize) -> (Vec<f64>, Vec<f64>) {
    let (cols, rows) = (heights.cols(), heights.rows());
    let lo0: Vec<f64> =
        heights.data.iter().map(|&h| if h.is_nan() { f64::NEG_INFINITY } else { h as f64 }).collect();
    let hi0: Vec<f64> =
        heights.data.iter().map(|&h| if h.is_nan() { f64::INFINITY } else { h as f64 }).collect();
    let pass = |src: &[f64], along_rows: bool, pick: fn(f64, f64) -> f64| -> Vec<f64> {
        let mut out = vec![0.0; src.len()];
        for r in 0..rows {
            for c in 0..cols {
                let (k, n) = if along_rows { (c, cols) } else { (r, rows) };
                let (a, b) = (k.saturating_sub(half), (k + half).min(n - 1));
                let mut m = src[r * cols + c];
                for j in a..=b {
                    let v = if along_rows { src[r * cols + j] } else { src[j * cols + c] };
                    m = pick(m, v);
                }
                out[r * cols + c] = m;
            }
        }
        out
    };
    let lo = pass(&pass(&lo0, true, f64::min), false, f64::min);
    let hi = pass(&pass(&hi0, true, f64::max), false, f64::max);
    (lo, hi)
}
