//! The step/slope hazard model over the rover footprint (paper 000 section 2; paper 003 section 2).
//!
//! For every cell a square window of `(2k+1) x (2k+1)` cells, the size of the rover footprint,
//! is centred on it and a plane is fitted by least squares to the mean heights of the sensed
//! cells in the window (sums come from integral images, so each window costs O(1)). From the fit:
//!
//! * **slope**: the tilt of the plane; the rover standing there would tilt that much.
//! * **roughness**: RMS of the cell heights about the plane.
//! * **step**: the largest height difference within the window *after removing the plane*
//!   (max residual minus min residual). Measuring the step about the plane means a uniform slope
//!   the rover can climb is not mistaken for a step (slope is tested on its own), while a rock
//!   or a ledge of height h on any slope still shows a difference of about h.
//!
//! A window is hazardous when step > the rover's belly clearance or slope > its maximum tilt.
//! Obstacle *cells* (the "obstacle pixels" of paper 000, from which convex hulls are built) are
//! the cells that cause the hazard: in a window whose step exceeds the clearance, the cells more
//! than the clearance above or below the window's ground plane (refitted without them: rocks,
//! pits, the far side of a ledge); and the centre cell of a window whose ground is too steep.

/// Plane fitted over one window: `z = z_ref + a + b*col + c*row` in cell units.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WindowPlane {
    /// Whether the window had enough sensed cells, not all on one line.
    pub valid: bool,
    /// Offset (m, relative to the analysis reference height).
    pub a: f64,
    /// Height change per column (m per cell).
    pub b: f64,
    /// Height change per row (m per cell).
    pub c: f64,
    /// Plane tilt from horizontal (rad).
    pub slope: f64,
    /// RMS of the cell heights about the plane (m).
    pub roughness: f64,
    /// Sensed cells in the window.
    pub cells: u32,
}

/// Parameters of the footprint hazard model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FootprintParams {
    /// Half-width `k` of the square window, in cells.
    pub half_window: usize,
    /// Minimum sensed cells for a window to be assessed.
    pub min_cells: usize,
    /// Step height above which a window is hazardous (m): the belly clearance.
    pub step_limit: f64,
    /// Plane tilt above which a window is hazardous (rad).
    pub slope_limit: f64,
    /// How a hazardous window's ground is refitted, and where a cell below it is a pit.
    pub ground: GroundRefit,
}

/// How the step model refits the ground of a hazardous footprint window, and in which windows
/// a cell below that ground counts as a pit.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum GroundRefit {
    /// The refit from the whole-window plane only, and a low cell is a pit in any window: the
    /// grid navigators' model (on top heights the robust refit cost `astar-grid` contacts, its
    /// margins having been set on this one).
    #[default]
    WholeWindow,
    /// The refit holding the most cells, from the whole-window plane or from level planes at
    /// the lower and upper quartile heights (see `window_ground`); a low cell is a pit in any
    /// window. Beside a rock wider than the window the whole-window plane stays tilted between
    /// rock and ground; this one finds the ground. RoverBug's safety layer (top heights).
    Robust,
    /// [`GroundRefit::Robust`], and a low cell is a pit only in the window centred on it: a
    /// rock filling most of a window can be that window's refitted "ground", and the open
    /// ground next to it then reads as a pit, while a real pit is low in its own window.
    /// RoverBug's C-obstacle model (cell means).
    RobustOwnPits,
}

impl GroundRefit {
    /// Whether the ground is also refitted from level planes at the quartile heights.
    pub fn robust(self) -> bool {
        self != GroundRefit::WholeWindow
    }

    /// Whether a low cell is a pit only in the window centred on it.
    pub fn pits_in_own_window(self) -> bool {
        self == GroundRefit::RobustOwnPits
    }
}

/// Per-cell results of the footprint analysis, row-major, NaN where not assessed.
#[derive(Clone, Debug, PartialEq)]
pub struct FootprintLayers {
    /// Step within the window centred on each cell (m).
    pub step: Vec<f32>,
    /// Slope of the window's plane (rad).
    pub slope: Vec<f32>,
    /// Roughness about the window's plane (m).
    pub roughness: Vec<f32>,
    /// Cells that are obstacles (cause a step or slope hazard).
    pub obstacle: Vec<bool>,
    /// Obstacle cells that reach the step limit only within their height tolerance: their
    /// measured height stays under it (all false without tolerances).
    pub uncertain: Vec<bool>,
}

/// Number of running sums kept per integral-image entry.
const SUMS: usize = 10;

/// Integral images of n, x, y, z, xx, xy, yy, xz, yz, zz over the sensed cells.
struct Integral {
    stride: usize,
    data: Vec<[f64; SUMS]>,
}

impl Integral {
    fn new(heights: &[f32], cols: usize, rows: usize, z_ref: f64) -> Self {
        let stride = cols + 1;
        let mut data = vec![[0.0; SUMS]; stride * (rows + 1)];
        for r in 0..rows {
            let mut row_sum = [0.0; SUMS];
            for c in 0..cols {
                let h = heights[r * cols + c];
                if h.is_finite() {
                    let (x, y, z) = (c as f64, r as f64, h as f64 - z_ref);
                    let v = [1.0, x, y, z, x * x, x * y, y * y, x * z, y * z, z * z];
                    for k in 0..SUMS {
                        row_sum[k] += v[k];
                    }
                }
                let above = data[r * stride + c + 1];
                let out = &mut data[(r + 1) * stride + c + 1];
                for k in 0..SUMS {
                    out[k] = above[k] + row_sum[k];
                }
            }
        }
        Self { stride, data }
    }

    /// Sums over columns `c0..c1` and rows `r0..r1` (half-open).
    #[inline]
    fn sum(&self, c0: usize, r0: usize, c1: usize, r1: usize) -> [f64; SUMS] {
        let s = self.stride;
        let (a, b, c, d) = (
            &self.data[r1 * s + c1],
            &self.data[r0 * s + c1],
            &self.data[r1 * s + c0],
            &self.data[r0 * s + c0],
        );
        let mut out = [0.0; SUMS];
        for k in 0..SUMS {
            out[k] = a[k] - b[k] - c[k] + d[k];
        }
        out
    }
}

/// A reference height for the analysis: the first finite height (keeps sums small).
fn reference_height(heights: &[f32]) -> f64 {
    heights.iter().find(|h| h.is_finite()).map_or(0.0, |&h| h as f64)
}

/// Half-open window bounds of half-width `k` around `i` clipped to `0..n`.
#[inline]
fn window(i: usize, k: usize, n: usize) -> (usize, usize) {
    (i.saturating_sub(k), (i + k + 1).min(n))
}

/// Fits a plane over the `(2k+1)^2` window around every cell of a row-major height grid
/// (NaN = unsensed). Returns the planes and the reference height they are relative to.
pub fn fit_planes(
    heights: &[f32],
    cols: usize,
    rows: usize,
    resolution: f64,
    half_window: usize,
    min_cells: usize,
) -> (Vec<WindowPlane>, f64) {
    let z_ref = reference_height(heights);
    let integral = Integral::new(heights, cols, rows, z_ref);
    let min_cells = min_cells.max(3) as f64;
    let mut planes = vec![WindowPlane::default(); cols * rows];
    for r in 0..rows {
        let (r0, r1) = window(r, half_window, rows);
        for c in 0..cols {
            let (c0, c1) = window(c, half_window, cols);
            let s = integral.sum(c0, r0, c1, r1);
            let n = s[0];
            if n < min_cells {
                continue;
            }
            let (mx, my, mz) = (s[1] / n, s[2] / n, s[3] / n);
            let cxx = s[4] / n - mx * mx;
            let cxy = s[5] / n - mx * my;
            let cyy = s[6] / n - my * my;
            let cxz = s[7] / n - mx * mz;
            let cyz = s[8] / n - my * mz;
            let czz = s[9] / n - mz * mz;
            let det = cxx * cyy - cxy * cxy;
            // Cells on one line (in cell units, spreads are >= 1/4 when not degenerate).
            if det < 1e-6 {
                continue;
            }
            let b = (cyy * cxz - cxy * cyz) / det;
            let cc = (cxx * cyz - cxy * cxz) / det;
            let residual = (czz - b * cxz - cc * cyz).max(0.0);
            planes[r * cols + c] = WindowPlane {
                valid: true,
                a: mz - b * mx - cc * my,
                b,
                c: cc,
                slope: (b.hypot(cc) / resolution).atan(),
                roughness: residual.sqrt(),
                cells: n as u32,
            };
        }
    }
    (planes, z_ref)
}

/// One sensed cell of a window: position (cell units), height relative to the reference, and
/// whether it is currently taken to stand off the ground plane (raised or sunken).
#[derive(Clone, Copy, Debug)]
struct WindowCell {
    col: usize,
    row: usize,
    z: f64,
    off_ground: bool,
}

/// Least-squares plane `(a, b, c)` through the cells on the ground, if determined.
fn fit_ground(cells: &[WindowCell]) -> Option<(f64, f64, f64)> {
    let (mut n, mut sx, mut sy, mut sz) = (0.0, 0.0, 0.0, 0.0);
    let (mut sxx, mut sxy, mut syy, mut sxz, mut syz) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for w in cells.iter().filter(|w| !w.off_ground) {
        let (x, y) = (w.col as f64, w.row as f64);
        n += 1.0;
        sx += x;
        sy += y;
        sz += w.z;
        sxx += x * x;
        sxy += x * y;
        syy += y * y;
        sxz += x * w.z;
        syz += y * w.z;
    }
    if n < 3.0 {
        return None;
    }
    let (mx, my, mz) = (sx / n, sy / n, sz / n);
    let cxx = sxx / n - mx * mx;
    let cxy = sxy / n - mx * my;
    let cyy = syy / n - my * my;
    let det = cxx * cyy - cxy * cxy;
    if det < 1e-6 {
        return None;
    }
    let cxz = sxz / n - mx * mz;
    let cyz = syz / n - my * mz;
    let b = (cyy * cxz - cxy * cyz) / det;
    let c = (cxx * cyz - cxy * cxz) / det;
    Some((mz - b * mx - c * my, b, c))
}

/// Residual of a window cell about the plane `(a, b, c)`.
#[inline]
fn residual(w: &WindowCell, (a, b, c): (f64, f64, f64)) -> f64 {
    w.z - (a + b * w.col as f64 + c * w.row as f64)
}

/// Refits the ground from `start`: the cells within `band` of the current plane, until that
/// set stops changing. Returns the plane and how many cells lie on it.
fn refit_ground(cells: &mut [WindowCell], start: (f64, f64, f64), band: f64) -> ((f64, f64, f64), usize) {
    let mut plane = start;
    for w in cells.iter_mut() {
        w.off_ground = false;
    }
    for _round in 0..6 {
        let mut changed = false;
        for w in cells.iter_mut() {
            let off = residual(w, plane).abs() > band;
            changed |= off != w.off_ground;
            w.off_ground = off;
        }
        if !changed {
            break;
        }
        match fit_ground(cells) {
            Some(p) => plane = p,
            None => break,
        }
    }
    (plane, cells.iter().filter(|w| residual(w, plane).abs() <= band).count())
}

/// The ground of a window: refitted from the whole-window plane and, with `robust`, also from
/// level planes at the lower and upper quartile cell heights, keeping the fit that holds the
/// most cells (the whole-window refit on a tie). Beside a rock filling much of the window the
/// whole-window plane is tilted between rock and ground with few cells near it, and a refit
/// from it cannot leave it.
fn window_ground(
    cells: &mut [WindowCell],
    whole: (f64, f64, f64),
    band: f64,
    robust: bool,
) -> (f64, f64, f64) {
    let mut best = refit_ground(cells, whole, band);
    if robust {
        // Level planes at the lower and upper quartile heights: one of them lies in the ground
        // however much of the window a rock fills, and the refit tilts it onto the ground.
        // The cells' order does not matter past the whole-window refit: select in place.
        let n = cells.len();
        if n > 0 {
            let by_height = |a: &WindowCell, b: &WindowCell| a.z.total_cmp(&b.z);
            let lower = cells.select_nth_unstable_by(n / 4, by_height).1.z;
            let upper = cells.select_nth_unstable_by(3 * n / 4, by_height).1.z;
            for q in [lower, upper] {
                let fit = refit_ground(cells, (q, 0.0, 0.0), band);
                if fit.1 > best.1 {
                    best = fit;
                }
            }
        }
    }
    best.0
}

/// Tolerance of cell `i` (m): zero when missing, negative or not finite.
#[inline]
fn tolerance_at(tolerance: &[f32], i: usize) -> f64 {
    tolerance.get(i).map_or(0.0, |&t| if t.is_finite() { t.max(0.0) as f64 } else { 0.0 })
}

/// Marks the cells of a hazardous window that stand more than `limit` above or below the
/// ground.
///
/// The plane fitted over the whole window is pulled and tilted by the obstacle itself (a rock
/// in one corner, a pit, one side of a ledge), which can make open ground look raised. So the
/// ground plane is refitted without the cells lying more than `limit / 2` off it, until that set
/// stops changing: what remains is the surface the wheels rest on. Cells more than `limit` off
/// that plane are obstacles: rocks, pits, and the far side of a ledge; cells that reach `limit`
/// above it only with their `tolerance` added go to `uncertain`. Returns the ground plane's
/// gradient `(b, c)` (m per cell).
#[allow(clippy::too_many_arguments)]
fn mark_off_ground_cells(
    heights: &[f32],
    tolerance: &[f32],
    cols: usize,
    (c0, c1, r0, r1): (usize, usize, usize, usize),
    z_ref: f64,
    plane: WindowPlane,
    limit: f64,
    scratch: &mut Vec<WindowCell>,
    obstacle: &mut [bool],
    uncertain: &mut [bool],
    (centre, pits_in_own_window, robust_ground): (usize, bool, bool),
) -> (f64, f64) {
    scratch.clear();
    for rr in r0..r1 {
        for cc in c0..c1 {
            let h = heights[rr * cols + cc];
            if h.is_finite() {
                scratch.push(WindowCell { col: cc, row: rr, z: h as f64 - z_ref, off_ground: false });
            }
        }
    }
    let (a, b, c) = window_ground(scratch, (plane.a, plane.b, plane.c), 0.5 * limit, robust_ground);
    for w in scratch.iter() {
        let i = w.row * cols + w.col;
        let t = tolerance_at(tolerance, i);
        let off = residual(w, (a, b, c));
        // A cell low only in another window's ground may be open ground beside a rock.
        let own = i == centre || !pits_in_own_window;
        if off > limit || (own && -off > limit) {
            obstacle[i] = true;
        } else if off + t > limit {
            // Only upwards: a sparse cell's top misses the crest of a rock seen from one side,
            // while a low cell is already set apart by its own measured depth.
            uncertain[i] = true;
        }
    }
    (b, c)
}

/// Runs the step/slope model over every footprint window of a row-major height grid.
pub fn analyse_footprints(
    heights: &[f32],
    cols: usize,
    rows: usize,
    resolution: f64,
    params: &FootprintParams,
) -> FootprintLayers {
    analyse_footprints_with_tolerance(heights, &[], cols, rows, resolution, params)
}

/// [`analyse_footprints`] where a cell also counts as an obstacle once it stands within its
/// `tolerance` (m, row-major; missing or non-finite entries count as zero) of the step limit
/// above the ground: a cell whose height is uncertain by about that much may hide a step above
/// the limit. Such cells are flagged in [`FootprintLayers::uncertain`]; the step layer stays the
/// measured one.
pub fn analyse_footprints_with_tolerance(
    heights: &[f32],
    tolerance: &[f32],
    cols: usize,
    rows: usize,
    resolution: f64,
    params: &FootprintParams,
) -> FootprintLayers {
    let k = params.half_window;
    let (planes, z_ref) = fit_planes(heights, cols, rows, resolution, k, params.min_cells);
    let n = cols * rows;
    let mut out = FootprintLayers {
        step: vec![f32::NAN; n],
        slope: vec![f32::NAN; n],
        roughness: vec![f32::NAN; n],
        obstacle: vec![false; n],
        uncertain: vec![false; n],
    };
    // Cells some window finds within tolerance of the limit; those another window finds over it
    // on their measured height are plain obstacles.
    let mut uncertain = vec![false; n];
    let mut scratch = Vec::with_capacity((2 * k + 1) * (2 * k + 1));
    for r in 0..rows {
        let (r0, r1) = window(r, k, rows);
        for c in 0..cols {
            let i = r * cols + c;
            let p = planes[i];
            if !p.valid {
                continue;
            }
            let (c0, c1) = window(c, k, cols);
            let residual = |cc: usize, rr: usize| -> Option<f64> {
                let h = heights[rr * cols + cc];
                h.is_finite().then_some(h as f64 - z_ref - (p.a + p.b * cc as f64 + p.c * rr as f64))
            };
            let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
            // The highest residual raised by its cell's tolerance: whether the window may hold a
            // step above the limit.
            let mut hi_tol = f64::NEG_INFINITY;
            for rr in r0..r1 {
                for cc in c0..c1 {
                    if let Some(e) = residual(cc, rr) {
                        lo = lo.min(e);
                        hi = hi.max(e);
                        hi_tol = hi_tol.max(e + tolerance_at(tolerance, rr * cols + cc));
                    }
                }
            }
            let step = hi - lo;
            out.step[i] = step as f32;
            out.slope[i] = p.slope as f32;
            out.roughness[i] = p.roughness as f32;
            // The slope the rover would stand on: the whole-window plane, or, when something
            // protrudes, the ground plane under it (a rock at the window's edge tilts the
            // whole-window plane without making the ground steep).
            let mut ground_slope = p.slope;
            if step > params.step_limit || hi_tol - lo > params.step_limit {
                let (gb, gc) = mark_off_ground_cells(
                    heights,
                    tolerance,
                    cols,
                    (c0, c1, r0, r1),
                    z_ref,
                    p,
                    params.step_limit,
                    &mut scratch,
                    &mut out.obstacle,
                    &mut uncertain,
                    (i, params.ground.pits_in_own_window(), params.ground.robust()),
                );
                ground_slope = (gb.hypot(gc) / resolution).atan();
            }
            if ground_slope > params.slope_limit && heights[i].is_finite() {
                out.obstacle[i] = true;
            }
        }
    }
    for ((o, u), &maybe) in out.obstacle.iter_mut().zip(out.uncertain.iter_mut()).zip(&uncertain) {
        *u = maybe && !*o;
        *o |= maybe;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> FootprintParams {
        FootprintParams {
            half_window: 3,
            min_cells: 12,
            step_limit: 0.18,
            slope_limit: 25f64.to_radians(),
            ground: GroundRefit::WholeWindow,
        }
    }

    fn grid(cols: usize, rows: usize, f: impl Fn(f64, f64) -> f64) -> Vec<f32> {
        let res = 0.15;
        let mut v = Vec::with_capacity(cols * rows);
        for r in 0..rows {
            for c in 0..cols {
                v.push(f((c as f64 + 0.5) * res, (r as f64 + 0.5) * res) as f32);
            }
        }
        v
    }

    #[test]
    fn uniform_climbable_slope_is_neither_step_nor_slope_hazard() {
        let g = 20f64.to_radians().tan();
        let h = grid(30, 30, |x, y| 3000.0 + g * (0.6 * x + 0.8 * y));
        let out = analyse_footprints(&h, 30, 30, 0.15, &params());
        assert!(out.obstacle.iter().all(|&o| !o));
        let robust = FootprintParams { ground: GroundRefit::RobustOwnPits, ..params() };
        assert_eq!(analyse_footprints(&h, 30, 30, 0.15, &robust), out);
        let centre = 15 * 30 + 15;
        assert!((out.slope[centre] as f64 - 20f64.to_radians()).abs() < 1e-3);
        assert!(out.step[centre] < 1e-3 && out.roughness[centre] < 1e-3);
    }

    #[test]
    fn too_steep_slope_marks_every_sensed_cell() {
        let g = 30f64.to_radians().tan();
        let h = grid(20, 20, |x, _| g * x);
        let out = analyse_footprints(&h, 20, 20, 0.15, &params());
        assert!(out.obstacle.iter().all(|&o| o));
    }

    #[test]
    fn box_rock_taller_than_clearance_marks_exactly_its_cells() {
        // A 0.25 m high box over cells 10..13 x 10..13 on flat ground.
        let mut h = grid(25, 25, |_, _| 0.0);
        for r in 10..13 {
            for c in 10..13 {
                h[r * 25 + c] = 0.25;
            }
        }
        let robust = FootprintParams { ground: GroundRefit::RobustOwnPits, ..params() };
        for p in [params(), robust] {
            let out = analyse_footprints(&h, 25, 25, 0.15, &p);
            for r in 0..25 {
                for c in 0..25 {
                    let rock = (10..13).contains(&r) && (10..13).contains(&c);
                    assert_eq!(out.obstacle[r * 25 + c], rock, "cell ({c}, {r}) {p:?}");
                }
            }
        }
        let out = analyse_footprints(&h, 25, 25, 0.15, &params());
        // The window centred on the rock sees the full 0.25 m step about its plane.
        assert!((out.step[11 * 25 + 11] - 0.25).abs() < 1e-5);
    }

    #[test]
    fn a_tolerance_flags_a_cell_just_under_the_limit_as_uncertain_and_only_upwards() {
        // Flat ground with a 0.17 m bump at (10, 10) and a 0.17 m pit at (5, 5), limit 0.18.
        let mut h = grid(25, 25, |_, _| 0.0);
        h[10 * 25 + 10] = 0.17;
        h[5 * 25 + 5] = -0.17;
        let plain = analyse_footprints(&h, 25, 25, 0.15, &params());
        assert!(plain.obstacle.iter().all(|&o| !o), "both stay under the limit as measured");
        // 2 cm of tolerance everywhere: the bump may reach 0.19 m, the pit is no rock.
        let tol = vec![0.02f32; 25 * 25];
        let out = analyse_footprints_with_tolerance(&h, &tol, 25, 25, 0.15, &params());
        for i in 0..25 * 25 {
            assert_eq!(out.obstacle[i], i == 10 * 25 + 10, "cell {i}");
            assert_eq!(out.uncertain[i], out.obstacle[i], "cell {i}");
        }
        // 5 mm is not enough to reach the limit.
        let small = vec![0.005f32; 25 * 25];
        let out = analyse_footprints_with_tolerance(&h, &small, 25, 25, 0.15, &params());
        assert!(out.obstacle.iter().all(|&o| !o));
        // A bump over the limit is a plain obstacle, whatever its tolerance.
        h[10 * 25 + 10] = 0.25;
        let out = analyse_footprints_with_tolerance(&h, &tol, 25, 25, 0.15, &params());
        assert!(out.obstacle[10 * 25 + 10] && !out.uncertain[10 * 25 + 10]);
        assert_eq!(out.step, analyse_footprints(&h, 25, 25, 0.15, &params()).step);
    }

    #[test]
    fn ledge_marks_a_band_along_one_side_of_its_edge() {
        // A 0.3 m ledge: ground rises from 0 to 0.3 m between columns 11 and 12.
        let mut h = grid(25, 25, |_, _| 0.0);
        for r in 0..25 {
            for c in 12..25 {
                h[r * 25 + c] = 0.3;
            }
        }
        let out = analyse_footprints(&h, 25, 25, 0.15, &params());
        for r in 0..25 {
            // Every row has a cell at the edge marked, and only cells within one footprint
            // half-width (3 cells) of the edge are marked.
            assert!(out.obstacle[r * 25 + 11] || out.obstacle[r * 25 + 12], "row {r}");
            for c in 0..25 {
                if out.obstacle[r * 25 + c] {
                    assert!((8..=15).contains(&c), "cell ({c}, {r})");
                }
            }
        }
    }

    /// A 0.5 m block over cells 11..20 x 11..20 of a 31 x 31 flat grid: wider than a window.
    fn large_block() -> Vec<f32> {
        let mut h = grid(31, 31, |_, _| 0.0);
        for r in 11..20 {
            for c in 11..20 {
                h[r * 31 + c] = 0.5;
            }
        }
        h
    }

    #[test]
    fn beside_a_block_wider_than_a_window_only_the_robust_refit_with_own_window_pits_marks_no_ground() {
        let h = large_block();
        let block = |i: usize| (11..20).contains(&(i / 31)) && (11..20).contains(&(i % 31));
        let with = |ground: GroundRefit| {
            analyse_footprints(&h, 31, 31, 0.15, &FootprintParams { ground, ..params() })
        };
        let ground =
            |o: &FootprintLayers| (0..31 * 31).filter(|&i| o.obstacle[i] && !block(i)).collect::<Vec<_>>();
        // Windows centred on the block's edge keep a plane tilted between block and ground (or
        // refit onto the block), and the open ground beside it reads as a pit.
        let whole = ground(&with(GroundRefit::WholeWindow));
        assert!(whole.len() >= 10, "{} ground cells marked", whole.len());
        // The robust refit alone takes the block as the ground of the windows on it: more
        // ground cells read low.
        assert!(ground(&with(GroundRefit::Robust)).len() > whole.len());
        // With pits only in their own window too, the ground beside the block is found in every
        // window and only the block stands out, its rim all round.
        let out = with(GroundRefit::RobustOwnPits);
        assert!(ground(&out).is_empty(), "ground cells marked: {:?}", ground(&out));
        for k in 11..20 {
            assert!(out.obstacle[11 * 31 + k] && out.obstacle[19 * 31 + k], "rim at column {k}");
            assert!(out.obstacle[k * 31 + 11] && out.obstacle[k * 31 + 19], "rim at row {k}");
        }
        // A real pit is low in its own window, whichever refit.
        let mut pit = grid(25, 25, |_, _| 0.0);
        for r in 11..14 {
            for c in 11..14 {
                pit[r * 25 + c] = -0.3;
            }
        }
        for g in [GroundRefit::WholeWindow, GroundRefit::Robust, GroundRefit::RobustOwnPits] {
            let out = analyse_footprints(&pit, 25, 25, 0.15, &FootprintParams { ground: g, ..params() });
            for r in 0..25 {
                for c in 0..25 {
                    let inside = (11..14).contains(&r) && (11..14).contains(&c);
                    assert_eq!(out.obstacle[r * 25 + c], inside, "cell ({c}, {r}) {g:?}");
                }
            }
        }
    }

    #[test]
    fn pit_deeper_than_clearance_marks_exactly_its_cells() {
        let mut h = grid(25, 25, |_, _| 0.0);
        for r in 11..14 {
            for c in 11..14 {
                h[r * 25 + c] = -0.3;
            }
        }
        let out = analyse_footprints(&h, 25, 25, 0.15, &params());
        for r in 0..25 {
            for c in 0..25 {
                let pit = (11..14).contains(&r) && (11..14).contains(&c);
                assert_eq!(out.obstacle[r * 25 + c], pit, "cell ({c}, {r})");
            }
        }
    }

    #[test]
    fn low_rock_is_not_an_obstacle_and_sparse_windows_are_not_assessed() {
        let mut h = grid(20, 20, |_, _| 0.0);
        h[10 * 20 + 10] = 0.15;
        let out = analyse_footprints(&h, 20, 20, 0.15, &params());
        assert!(out.obstacle.iter().all(|&o| !o));
        let mut sparse = vec![f32::NAN; 400];
        sparse[..5].fill(0.0);
        let out = analyse_footprints(&sparse, 20, 20, 0.15, &params());
        assert!(out.step.iter().all(|s| s.is_nan()));
    }

    #[test]
    fn integral_window_sums_match_direct_sums() {
        let h = grid(9, 7, |x, y| (3.0 * x).sin() + y * y);
        let integral = Integral::new(&h, 9, 7, 0.0);
        let s = integral.sum(2, 1, 6, 5);
        let mut direct = 0.0;
        for r in 1..5 {
            for c in 2..6 {
                direct += h[r * 9 + c] as f64 * c as f64;
            }
        }
        assert!((s[7] - direct).abs() < 1e-9);
        assert_eq!(s[0], 16.0);
    }
}
