//! Matcher workloads for benchmarks and `rovernav bench report` (issue 43): the inputs, and
//! one timed match by branch and bound against exhaustive search of the same poses in the same
//! process.
//!
//! - [`localisation_workload`]: what the map-matching localiser does, as in
//!   `benches/matching.rs`: a 10 m x 10 m local map at 5 cm (every known cell scored) against a
//!   20 m x 20 m global map, a window of +-0.5 m and +-0.05 rad, and the full match (search,
//!   peak fit, failure search, the overlap re-run) by [`MlMatcher::match_detailed`].
//! - [`scan_window_workload`]: what a scan-matcher user would recognise: 340 occupied points
//!   at 5 cm, a window of +-7 m and +-30 deg (Cartographer's constraint-builder defaults:
//!   `linear_search_window = 7`, `angular_search_window = 30 deg`), and the search alone
//!   ([`MlMatcher::search`]), as Cartographer's fast correlative matcher returns only the best
//!   pose and its score. The points are what a range scan returns from obstacles: on a flat
//!   rock field (40 rocks per 100 m^2), the cells of a 360 deg view to 5 m that stand at least
//!   [`SCAN_WINDOW_OBSTACLE_HEIGHT`] above the ground under the rover, an even subsample of
//!   340 of them, matched on raw heights. Why not every cell of a rough-terrain view (as the
//!   localisation workload): there, ground cells find their height layer in nearly every
//!   block of translations, so coarse boxes do not prune; measured on the same window with 340
//!   cells of a fractal-terrain view, the search bounded about a million boxes (2.3 s), as an
//!   occupancy-grid scan matcher would on a map without free space.

use std::time::Instant;

use rovernav_core::{Grid2, GridGeometry, Pose2, Wedge};

use crate::matching::{MatchError, MlMatcher, MlParams, SearchWindow};
use crate::synthetic::{TerrainParams, fractal_terrain, local_map_from_field};

/// The inputs of one matcher workload.
#[derive(Clone, Debug)]
pub struct MatcherWorkload {
    /// Short name (`localisation` or `scan-window`).
    pub name: &'static str,
    /// The world-frame global elevation map.
    pub global: Grid2<f32>,
    /// The prepared global map.
    pub matcher: MlMatcher,
    /// The rover-frame local map.
    pub local: Grid2<f32>,
    /// The search window.
    pub window: SearchWindow,
    /// The true pose the local map was taken from.
    pub truth: Pose2,
    /// Whether a match is the full match (peak fit, failure search) or the search alone.
    pub full_match: bool,
}

/// The localisation workload (see the module doc); deterministic.
pub fn localisation_workload() -> Result<MatcherWorkload, MatchError> {
    let resolution = 0.05;
    let field = fractal_terrain(&TerrainParams { size: 24.0, resolution: 0.025, ..Default::default() }, 1);
    let global =
        field.sample(GridGeometry { cols: 400, rows: 400, resolution, origin_x: -10.0, origin_y: -10.0 });
    let truth = Pose2::new(0.37, -0.21, 0.3);
    let local_geometry = GridGeometry { cols: 200, rows: 200, resolution, origin_x: -5.0, origin_y: -5.0 };
    let local = local_map_from_field(&field, &truth, local_geometry, None, 0.01, 0.2, 2);
    let matcher = MlMatcher::new(&global, MlParams::default())?;
    let window =
        SearchWindow { center: Pose2::new(0.3, -0.1, 0.28), half_x: 0.5, half_y: 0.5, half_yaw: 0.05 };
    Ok(MatcherWorkload { name: "localisation", global, matcher, local, window, truth, full_match: true })
}

/// Local cells scored in the scan-window workload.
pub const SCAN_WINDOW_CELLS: usize = 340;

/// The terrain of the scan-window workload.
pub fn scan_window_terrain() -> TerrainParams {
    TerrainParams { relief: 0.02, bumps_per_100m2: 0.0, rocks_per_100m2: 40.0, ..Default::default() }
}

/// Height above the ground under the rover (m) of the scan-window workload's local points.
pub const SCAN_WINDOW_OBSTACLE_HEIGHT: f64 = 0.1;

/// The scan-window workload (see the module doc); deterministic.
pub fn scan_window_workload() -> Result<MatcherWorkload, MatchError> {
    scan_window_workload_on(&scan_window_terrain(), 7, Some(SCAN_WINDOW_OBSTACLE_HEIGHT))
}

/// The scan-window workload's window and view over another synthetic terrain (`size` and
/// `resolution` are set here). With `obstacles_above` (m), the local map keeps only the cells
/// that high above the ground under the rover (the points a range scan sees on obstacles), and
/// heights are matched raw (no high-pass filter: both maps are levelled on flat ground).
pub fn scan_window_workload_on(
    terrain: &TerrainParams,
    seed: u64,
    obstacles_above: Option<f64>,
) -> Result<MatcherWorkload, MatchError> {
    let resolution = 0.05;
    let (window_xy, window_yaw) = (7.0, 30f64.to_radians());
    let range = 5.0;
    // The global map covers every pose of the window with the whole view.
    let half = window_xy + range + 1.0;
    let field = fractal_terrain(
        &TerrainParams { size: 2.0 * half + 4.0, resolution: resolution / 2.0, ..*terrain },
        seed,
    );
    let n = (2.0 * half / resolution).round() as usize;
    let global =
        field.sample(GridGeometry { cols: n, rows: n, resolution, origin_x: -half, origin_y: -half });
    let truth = Pose2::new(0.42, -0.67, 0.5);
    let cells = (2.0 * range / resolution).ceil() as usize;
    let geometry = GridGeometry { cols: cells, rows: cells, resolution, origin_x: -range, origin_y: -range };
    let wedge = Wedge { bearing: 0.0, half_angle: std::f64::consts::PI, min_range: 0.8, max_range: range };
    let mut local = local_map_from_field(&field, &truth, geometry, Some(&wedge), 0.01, 0.1, 3);
    let mut params = MlParams { max_local_cells: Some(SCAN_WINDOW_CELLS), ..Default::default() };
    if let Some(above) = obstacles_above {
        for h in &mut local.data {
            if h.is_nan() || f64::from(*h) <= above {
                *h = f32::NAN;
            }
        }
        params.high_pass_window = None;
        params.overlap_margin_cells = None;
    }
    let matcher = MlMatcher::new(&global, params)?;
    // The prior is off the truth by a few metres and degrees, well inside the window.
    let window = SearchWindow {
        center: Pose2::new(truth.x - 2.3, truth.y + 1.6, truth.yaw - 0.2),
        half_x: window_xy,
        half_y: window_xy,
        half_yaw: window_yaw,
    };
    Ok(MatcherWorkload { name: "scan-window", global, matcher, local, window, truth, full_match: false })
}

/// One timed match.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimedMatch {
    /// Wall time (s).
    pub seconds: f64,
    /// The pose found (subpixel for a full match, the best lattice pose for a search).
    pub pose: Pose2,
    /// Score of the best lattice pose.
    pub score: f64,
    /// Lattice index of the best pose.
    pub best_index: [i32; 3],
    /// Distance-transform lookups in poses' worth (see [`crate::matching::engine::SearchOutcome`]).
    pub poses_evaluated: u64,
    /// Poses of the search lattice.
    pub lattice_poses: u64,
    /// Boxes bounded and poses scored by the main search (the lattice for exhaustive search).
    pub boxes: u64,
}

impl TimedMatch {
    /// Position error (m) to a true pose.
    pub fn error_m(&self, truth: &Pose2) -> f64 {
        (self.pose.x - truth.x).hypot(self.pose.y - truth.y)
    }
}

/// Times one match of a workload, by branch and bound or by exhaustive search.
pub fn time_match(workload: &MatcherWorkload, exhaustive: bool) -> Result<TimedMatch, MatchError> {
    let w = workload;
    let start = Instant::now();
    if w.full_match {
        let d = w.matcher.match_detailed(&w.local, &w.window, exhaustive)?;
        let seconds = start.elapsed().as_secs_f64();
        Ok(TimedMatch {
            seconds,
            pose: d.result.pose,
            score: d.result.log_likelihood,
            best_index: d.best_index,
            poses_evaluated: d.result.poses_evaluated,
            lattice_poses: d.lattice.size(),
            boxes: d.boxes,
        })
    } else {
        let (outcome, lattice) = w.matcher.search(&w.local, &w.window, exhaustive)?;
        let seconds = start.elapsed().as_secs_f64();
        let best_index = outcome.best.unwrap_or([0, 0, 0]);
        let u = best_index.map(f64::from);
        Ok(TimedMatch {
            seconds,
            pose: lattice.pose(u),
            score: outcome.score,
            best_index,
            poses_evaluated: outcome.evaluations,
            lattice_poses: lattice.size(),
            boxes: outcome.boxes,
        })
    }
}

/// Branch and bound against exhaustive search on one workload, in the same run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MatcherComparison {
    /// The branch-and-bound match (the fastest of the repeats).
    pub rovernav: TimedMatch,
    /// The exhaustive match (timed once: it is the slow one).
    pub exhaustive: TimedMatch,
}

impl MatcherComparison {
    /// Exhaustive time over branch-and-bound time.
    pub fn speedup(&self) -> f64 {
        self.exhaustive.seconds / self.rovernav.seconds.max(1e-12)
    }

    /// Whether both found the same best score (the optimum; ties may sit at other poses).
    pub fn same_optimum(&self) -> bool {
        self.rovernav.score == self.exhaustive.score
    }
}

/// Runs a workload by branch and bound `repeats` times (keeping the fastest) and once by
/// exhaustive search.
pub fn compare(workload: &MatcherWorkload, repeats: usize) -> Result<MatcherComparison, MatchError> {
    let mut best = time_match(workload, false)?;
    for _ in 1..repeats {
        let t = time_match(workload, false)?;
        if t.seconds < best.seconds {
            best = t;
        }
    }
    let exhaustive = time_match(workload, true)?;
    Ok(MatcherComparison { rovernav: best, exhaustive })
}
