//! The search machinery shared by the maximum-likelihood and Hausdorff matchers (paper 000
//! sections 4.2-4.3, paper 002 section 3.2).
//!
//! The global map becomes a 3D occupancy grid (z discretised at the grid scale, optionally
//! finer) and its exact Euclidean distance transform; the local map becomes a list of occupied
//! cells. A pose's score is a sum over local cells of a non-increasing function of the distance
//! from the transformed cell to the nearest global occupied voxel. The pose space is
//! discretised so that neighbouring poses move the local map by one grid cell (translation
//! step = resolution, heading step = resolution / farthest local cell). Branch and bound: the
//! dead-reckoned pose is scored first; then rectilinear cells of pose space are bounded by
//! scoring every local cell at the cell's centre pose with its distance reduced by the largest
//! displacement any pose of the cell can cause, `D_i^C = max(D_i^c - Delta_C, 0)`; cells that
//! cannot beat the best pose are pruned, the others are split. The best discrete pose is
//! refined with a quadratic fit of the log-score around it (subpixel estimate and covariance),
//! and searches outside the peak find competing poses, from which the probability that the
//! match picked the wrong place follows.
//!
//! Beyond the paper, measured to matter on rover-like data:
//! - [`BoundKind::MinPool`] bounds the translation part of a cell exactly with min-filtered
//!   distance transforms (never looser than the paper's bound, which stays available as
//!   [`BoundKind::Distance`]); [`SplitRule::HeadingFirst`] cuts heading before translation,
//!   because cells spanning headings pay a voxel-rounding slack.
//! - Local cells over unknown parts of the global map score a neutral constant instead of the
//!   outlier density: the paper's choice biases matches towards maximum overlap (measured: 10-20
//!   cm downrange bias between consecutive stereo views).
//! - That neutral score can be each local cell's own background, its mean score at misaligned
//!   poses ([`Scorer::use_background_neutral`]): smooth ground, which scores well anywhere,
//!   then counts for nothing, and only cells that discriminate poses pull the match.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use nalgebra::{Matrix3, SMatrix, SVector, Vector3};
use rovernav_core::{Grid2, Pose2, wrap_angle};

use super::distance_transform::{squared_distance_3d, squared_distances};
use super::elevation::occupied_cells;
use super::{MatchError, MatchResult, SearchWindow};

/// Largest voxel grid the matcher builds (cells), to bound memory on bad input.
const MAX_VOXELS: usize = 400_000_000;

/// A non-increasing score of the distance (m) between a local cell and the global surface.
pub trait DistanceScore {
    /// Contribution of one local cell at this distance.
    fn score(&self, distance: f64) -> f64;
}

/// The global map as a distance-transformed 3D occupancy grid.
#[derive(Clone, Debug)]
pub struct VoxelMap {
    cols: usize,
    rows: usize,
    layers: usize,
    resolution: f64,
    /// World x of the western edge of voxel column 0 (the grid is padded around the map).
    origin_x: f64,
    /// World y of the southern edge of voxel row 0.
    origin_y: f64,
    /// Height of one voxel layer (m): the resolution, or less with vertical exaggeration.
    layer_height: f64,
    /// Absolute height layer (floor(z / layer_height)) of voxel layer 0.
    layer0: i64,
    /// Capped squared distances (voxels^2) to the nearest occupied voxel.
    squared: Vec<u16>,
    /// `pooled[l]`: for each voxel, the smallest squared distance over the voxels of its layer
    /// within a square of half-side `2^l` (a min-filter of `squared`), for bounding distances
    /// over whole boxes of translations.
    pooled: Vec<Vec<u16>>,
    /// Per column: whether the global map has a height there.
    known: Vec<bool>,
    /// Per column: capped squared distance (cells^2) to the nearest unknown column.
    to_unknown: Vec<u16>,
    cap: u16,
}

impl VoxelMap {
    /// Builds the occupancy grid of a (high-passed) elevation map and its distance transform,
    /// with distances saturating at `cap_cells` cells. Heights are discretised in layers of
    /// `resolution / vertical_exaggeration` (1 = the grid scale, as in the papers).
    ///
    /// `pool_levels` min-filtered copies are kept for [`BoundKind::MinPool`] (half-sides 1, 2,
    /// 4, ...); zero keeps none.
    pub fn new(
        heights: &Grid2<f32>,
        cap_cells: u32,
        vertical_exaggeration: f64,
        pool_levels: usize,
    ) -> Result<Self, MatchError> {
        let r = heights.resolution();
        if !(r > 0.0 && r.is_finite()) {
            return Err(MatchError::BadResolution { map: "global", value: r });
        }
        if !(vertical_exaggeration > 0.0 && vertical_exaggeration.is_finite()) {
            return Err(MatchError::BadParameter {
                field: "vertical_exaggeration",
                value: vertical_exaggeration,
                expected: "> 0",
            });
        }
        let layer_height = r / vertical_exaggeration;
        let cap_cells = cap_cells.clamp(1, 255);
        let cap = (cap_cells * cap_cells) as u16;
        let pad = cap_cells as usize + 1;
        let (mut lo, mut hi) = (i64::MAX, i64::MIN);
        for &h in &heights.data {
            if h.is_finite() {
                let layer = (f64::from(h) / layer_height).floor() as i64;
                lo = lo.min(layer);
                hi = hi.max(layer);
            }
        }
        if lo > hi {
            return Err(MatchError::EmptyMap { map: "global" });
        }
        let cols = heights.cols() + 2 * pad;
        let rows = heights.rows() + 2 * pad;
        let layers = (hi - lo) as usize + 1 + 2 * pad;
        let total = cols.saturating_mul(rows).saturating_mul(layers);
        if total > MAX_VOXELS {
            return Err(MatchError::TooLarge { voxels: total });
        }
        let layer0 = lo - pad as i64;
        let mut occupied = vec![false; total];
        for row in 0..heights.rows() {
            for col in 0..heights.cols() {
                let h = *heights.get(col, row);
                if h.is_finite() {
                    let z = ((f64::from(h) / layer_height).floor() as i64 - layer0) as usize;
                    occupied[(z * rows + row + pad) * cols + col + pad] = true;
                }
            }
        }
        let (squared, _) = squared_distances(&occupied, cols, rows, layers, cap);
        let mut known = vec![false; cols * rows];
        for row in 0..heights.rows() {
            for col in 0..heights.cols() {
                known[(row + pad) * cols + col + pad] = heights.get(col, row).is_finite();
            }
        }
        let unknown: Vec<bool> = known.iter().map(|k| !k).collect();
        let to_unknown = squared_distance_3d(&unknown, cols, rows, 1, u16::MAX - 1);
        let pooled = min_pool_levels(&squared, cols, rows, layers, pool_levels);
        Ok(Self {
            cols,
            rows,
            layers,
            resolution: r,
            layer_height,
            origin_x: heights.geometry.origin_x - pad as f64 * r,
            origin_y: heights.geometry.origin_y - pad as f64 * r,
            layer0,
            squared,
            pooled,
            known,
            to_unknown,
            cap,
        })
    }

    /// Cell size (m).
    pub fn resolution(&self) -> f64 {
        self.resolution
    }

    /// Capped squared distance (voxels^2) of the voxel containing a world point.
    pub fn squared_distance_at(&self, x: f64, y: f64, z: f64) -> u16 {
        let inv = 1.0 / self.resolution;
        let col = ((x - self.origin_x) * inv).floor() as i64;
        let row = ((y - self.origin_y) * inv).floor() as i64;
        let layer = (z / self.layer_height).floor() as i64 - self.layer0;
        if col < 0
            || row < 0
            || layer < 0
            || col >= self.cols as i64
            || row >= self.rows as i64
            || layer >= self.layers as i64
        {
            return self.cap;
        }
        self.squared[(layer as usize * self.rows + row as usize) * self.cols + col as usize]
    }

    /// Squared distance (cells^2, capped) from the column containing a world point to the
    /// nearest column where the global map is unknown: 0 over unknown ground or off the map.
    pub fn squared_distance_to_unknown(&self, x: f64, y: f64) -> u16 {
        let inv = 1.0 / self.resolution;
        let col = ((x - self.origin_x) * inv).floor() as i64;
        let row = ((y - self.origin_y) * inv).floor() as i64;
        if col < 0 || row < 0 || col >= self.cols as i64 || row >= self.rows as i64 {
            return 0;
        }
        self.to_unknown[row as usize * self.cols + col as usize]
    }
}

/// `floor` for grid coordinates without a libm call: exact for |v| < 2^20, and any value
/// below that range maps below -2^20 (outside every grid) as floor would.
#[inline]
fn fast_floor(v: f64) -> i64 {
    const OFFSET: f64 = 1_048_576.0;
    if v > -OFFSET { (v + OFFSET) as i64 - OFFSET as i64 } else { i64::MIN / 2 }
}

/// Min-filters of a voxel array over squares of half-side 1, 2, 4, ... within each layer, by
/// doubling: a window of half-side 2e is the union of two of half-side e shifted by +-e.
fn min_pool_levels(squared: &[u16], cols: usize, rows: usize, layers: usize, levels: usize) -> Vec<Vec<u16>> {
    let mut out: Vec<Vec<u16>> = Vec::with_capacity(levels);
    let mut current = squared.to_vec();
    let mut scratch = vec![0u16; squared.len()];
    let mut half = 1usize;
    for level in 0..levels {
        // The previous level has half-side `half / 2` (or 0 for the raw array); combining its
        // values at offsets +-(half - previous) gives half-side `half`.
        let previous = if level == 0 { 0 } else { half / 2 };
        let shift = half - previous;
        for z in 0..layers {
            for r in 0..rows {
                let base = (z * rows + r) * cols;
                for c in 0..cols {
                    let lo = current[base + c.saturating_sub(shift)];
                    let hi = current[base + (c + shift).min(cols - 1)];
                    scratch[base + c] = lo.min(hi).min(current[base + c]);
                }
            }
        }
        for z in 0..layers {
            for r in 0..rows {
                let base = z * rows * cols;
                let (r_lo, r_hi) = (r.saturating_sub(shift), (r + shift).min(rows - 1));
                for c in 0..cols {
                    let v = scratch[base + r * cols + c]
                        .min(scratch[base + r_lo * cols + c])
                        .min(scratch[base + r_hi * cols + c]);
                    current[base + r * cols + c] = v;
                }
            }
        }
        out.push(current.clone());
        half *= 2;
    }
    out
}

/// How a cell of poses is bounded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BoundKind {
    /// Paper 000's bound: each local cell's distance at the cell's centre pose minus the
    /// largest displacement the cell allows, `max(D_i^c - Delta_C, 0)`.
    Distance,
    /// The same with the translation part taken exactly: the smallest distance over the box
    /// of translations (a min-filtered distance transform), minus only the displacement due
    /// to heading; never looser than [`BoundKind::Distance`].
    MinPool,
}

/// Which axis a cell of poses is split along.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SplitRule {
    /// The longest axis, measured in grid cells of local-map motion (paper 000).
    LongestAxis,
    /// Heading until single headings, then the longest translation axis: cells spanning
    /// headings pay a rounding slack in their bound, so they are cut first.
    HeadingFirst,
}

/// The occupied cells of a local map, relative to a voxel map's layers.
#[derive(Clone, Debug)]
pub struct LocalCells {
    /// Body-frame x (m).
    xs: Vec<f64>,
    /// Body-frame y (m).
    ys: Vec<f64>,
    /// Offset of the cell's height layer in the voxel array, or `None` outside the layers.
    layer_offset: Vec<Option<usize>>,
    /// Distance of each cell from the rover origin (voxels).
    radii: Vec<f64>,
    /// Distance of the farthest cell from the rover origin (m).
    radius: f64,
}

impl LocalCells {
    /// Lists the known cells of a (high-passed) rover-frame local map against a voxel map,
    /// keeping an even subsample of at most `max_cells` of them when given.
    pub fn new(local: &Grid2<f32>, voxels: &VoxelMap, max_cells: Option<usize>) -> Result<Self, MatchError> {
        let mut cells = occupied_cells(local);
        if let Some(max) = max_cells.filter(|&m| m > 0 && cells.len() > m) {
            // Every k-th cell in row order, with a fractional stride so exactly `max` remain.
            let stride = cells.len() as f64 / max as f64;
            cells = (0..max).map(|i| cells[(i as f64 * stride) as usize]).collect();
        }
        if cells.is_empty() {
            return Err(MatchError::EmptyMap { map: "local" });
        }
        let inv = 1.0 / voxels.resolution;
        let plane = voxels.rows * voxels.cols;
        let mut out = Self {
            xs: Vec::with_capacity(cells.len()),
            ys: Vec::with_capacity(cells.len()),
            layer_offset: Vec::with_capacity(cells.len()),
            radii: Vec::with_capacity(cells.len()),
            radius: 0.0,
        };
        for [x, y, z] in cells {
            let layer = (z / voxels.layer_height).floor() as i64 - voxels.layer0;
            out.xs.push(x);
            out.ys.push(y);
            out.layer_offset
                .push((layer >= 0 && layer < voxels.layers as i64).then(|| layer as usize * plane));
            out.radius = out.radius.max(x.hypot(y));
            out.radii.push(x.hypot(y) * inv);
        }
        out.radius = out.radius.max(voxels.resolution);
        Ok(out)
    }

    /// Number of local cells.
    pub fn len(&self) -> usize {
        self.xs.len()
    }

    /// Whether there are no local cells.
    pub fn is_empty(&self) -> bool {
        self.xs.is_empty()
    }
}

/// The discretised pose space: pose (i, j, k) = centre + (i step, j step, k yaw_step).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoseLattice {
    /// Pose of index (0, 0, 0) (the dead-reckoned pose).
    pub center: Pose2,
    /// Translation step (m): the grid resolution.
    pub step: f64,
    /// Heading step (rad): resolution over the farthest local cell's radius.
    pub yaw_step: f64,
    /// Largest |index| searched along x, y and heading.
    pub half: [i32; 3],
}

impl PoseLattice {
    /// The lattice covering a search window for a local map of the given radius.
    pub fn new(window: &SearchWindow, resolution: f64, radius: f64) -> Self {
        let yaw_step = resolution / radius;
        let count = |h: f64, s: f64| ((h.max(0.0) / s).floor() as i32).min(10_000);
        Self {
            center: window.center,
            step: resolution,
            yaw_step,
            half: [
                count(window.half_x, resolution),
                count(window.half_y, resolution),
                count(window.half_yaw, yaw_step),
            ],
        }
    }

    /// The continuous pose at fractional lattice coordinates.
    pub fn pose(&self, u: [f64; 3]) -> Pose2 {
        Pose2::new(
            self.center.x + u[0] * self.step,
            self.center.y + u[1] * self.step,
            wrap_angle(self.center.yaw + u[2] * self.yaw_step),
        )
    }

    /// Number of discrete poses in the window.
    pub fn size(&self) -> u64 {
        self.half.iter().map(|&h| 2 * h as u64 + 1).product()
    }
}

/// A box of lattice indices (inclusive bounds) with the bound of its best score.
#[derive(Clone, Copy, Debug)]
struct PoseCell {
    lo: [i32; 3],
    hi: [i32; 3],
    bound: f64,
}

impl PartialEq for PoseCell {
    fn eq(&self, other: &Self) -> bool {
        self.bound.total_cmp(&other.bound) == Ordering::Equal
    }
}
impl Eq for PoseCell {}
impl PartialOrd for PoseCell {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for PoseCell {
    fn cmp(&self, other: &Self) -> Ordering {
        self.bound.total_cmp(&other.bound)
    }
}

/// Outcome of one search over the lattice.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SearchOutcome {
    /// Best discrete pose's indices, if any pose beat the initial threshold.
    pub best: Option<[i32; 3]>,
    /// Its score (or the initial threshold).
    pub score: f64,
    /// Cells and poses scored.
    pub evaluations: u64,
    /// Of those, single poses scored explicitly.
    pub poses_tested: u64,
}

/// Everything a matcher learnt about one match.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MatchDetails {
    /// The result handed to the pose estimator.
    pub result: MatchResult,
    /// Lattice indices of the best discrete pose.
    pub best_index: [i32; 3],
    /// The pose lattice searched.
    pub lattice: PoseLattice,
    /// Score of the best pose outside the peak, when one came within the failure margin.
    pub runner_up: Option<f64>,
    /// Single poses the main search scored explicitly (the rest of `poses_evaluated` are
    /// cell bounds, each as costly as one pose).
    pub poses_tested: u64,
    /// Evaluations spent on the failure-probability search.
    pub failure_search_evaluations: u64,
    /// Number of local cells scored per pose.
    pub local_cells: usize,
    /// Whether the quadratic fit around the peak was a proper maximum.
    pub peak_fit_ok: bool,
}

/// Sub-cell steps of the table that turns a lower bound on a distance into a score bound.
const BOUND_STEPS_PER_CELL: f64 = 16.0;

/// Scores poses of a local map against a voxel map with a distance score.
pub struct Scorer<'a, S: DistanceScore> {
    voxels: &'a VoxelMap,
    cells: &'a LocalCells,
    lattice: PoseLattice,
    /// Score of a local cell by its capped squared voxel distance.
    exact: Vec<f64>,
    /// Score by a lower bound on the distance, in 1/BOUND_STEPS_PER_CELL cell steps (rounded
    /// down, so the table never under-estimates).
    bound: Vec<f64>,
    /// Square roots of the squared distances 0..=cap.
    roots: Vec<f64>,
    /// Half-width (voxels) of the padding around the occupied part of the voxel map.
    pad: f64,
    /// Per local cell: its score over an unknown part of the global map.
    neutral: Vec<f64>,
    /// How cells are bounded.
    bound_kind: BoundKind,
    /// How cells are split.
    split: SplitRule,
    _score: std::marker::PhantomData<&'a S>,
}

impl<'a, S: DistanceScore> Scorer<'a, S> {
    /// A scorer over the lattice of a search window.
    pub fn new(
        voxels: &'a VoxelMap,
        cells: &'a LocalCells,
        score: &'a S,
        window: &SearchWindow,
        bound_kind: BoundKind,
        split: SplitRule,
        neutral_distance: f64,
    ) -> Self {
        let lattice = PoseLattice::new(window, voxels.resolution, cells.radius);
        let r = voxels.resolution;
        let roots: Vec<f64> = (0..=voxels.cap).map(|n| f64::from(n).sqrt()).collect();
        let exact = roots.iter().map(|&d| score.score(d * r)).collect();
        let cap_d = f64::from(voxels.cap).sqrt();
        let bound = (0..=(cap_d * BOUND_STEPS_PER_CELL).ceil() as usize)
            .map(|i| score.score(i as f64 / BOUND_STEPS_PER_CELL * r))
            .collect();
        Self {
            voxels,
            cells,
            lattice,
            exact,
            bound,
            roots,
            pad: cap_d.floor() + 1.0,
            neutral: vec![score.score(neutral_distance); cells.len()],
            bound_kind,
            split,
            _score: std::marker::PhantomData,
        }
    }

    /// The pose lattice.
    pub fn lattice(&self) -> PoseLattice {
        self.lattice
    }

    /// Largest displacement (voxels) of a local cell due to a heading extent, as a constant
    /// and a factor of the cell's radius (voxels): the chord swept, plus the rounding of both
    /// poses' positions to voxels (at a fixed heading lattice moves are whole-voxel shifts).
    fn rotation_bound(&self, heading_extent: i32) -> (f64, f64) {
        if heading_extent == 0 {
            return (0.0, 0.0);
        }
        let half_angle = 0.5 * f64::from(heading_extent) * self.lattice.yaw_step;
        (std::f64::consts::SQRT_2, 2.0 * half_angle.min(std::f64::consts::FRAC_PI_2).sin())
    }

    /// Visits each local cell's column (linear index in the padded grid) at lattice pose
    /// `index`, or `None` when outside the grid.
    #[inline]
    fn for_each_column(&self, index: [i32; 3], mut visit: impl FnMut(usize, Option<usize>)) {
        let v = self.voxels;
        let yaw = self.lattice.center.yaw + f64::from(index[2]) * self.lattice.yaw_step;
        let inv = 1.0 / v.resolution;
        let (s, c) = yaw.sin_cos();
        let (cs, ss) = (c * inv, s * inv);
        let bx = (self.lattice.center.x - v.origin_x) * inv;
        let by = (self.lattice.center.y - v.origin_y) * inv;
        let (cols, rows) = (v.cols as i64, v.rows as i64);
        let cells = self.cells;
        for (i, (&x, &y)) in cells.xs.iter().zip(&cells.ys).enumerate() {
            let col = fast_floor(bx + cs * x - ss * y) + i64::from(index[0]);
            let row = fast_floor(by + ss * x + cs * y) + i64::from(index[1]);
            let inside = col >= 0 && row >= 0 && col < cols && row < rows;
            visit(i, inside.then(|| row as usize * v.cols + col as usize));
        }
    }

    /// Exact score of local cell `i` landing in `column`: the distance score where the global
    /// map is known, the neutral score where it is not (no information either way).
    #[inline]
    fn exact_at(&self, i: usize, column: Option<usize>) -> f64 {
        let v = self.voxels;
        match column {
            Some(cell) if v.known[cell] => match self.cells.layer_offset[i] {
                Some(layer) => self.exact[v.squared[layer + cell] as usize],
                None => self.exact[v.cap as usize],
            },
            _ => self.neutral[i],
        }
    }

    /// Replaces each local cell's neutral score by its background score: the mean of its
    /// exact scores, over known global columns, at poses displaced from the window's centre
    /// by `radii` lattice steps in eight directions (keeping the constant neutral where it
    /// never lands on known ground).
    ///
    /// Why: a cell of smooth ground scores near the maximum wherever it is placed over known
    /// terrain, so with any constant neutral score the sum rewards overlap rather than
    /// alignment, and consecutive forward views are pulled towards each other (measured: 10-30
    /// cm downrange bias on the simulator's stereo). Scoring each cell against its own
    /// misaligned expectation makes the sum a log-likelihood ratio against a random placement:
    /// uninformative cells count about zero wherever they land, informative ones (rocks, edges)
    /// count for alignment. The search stays exact: bounds use the same per-cell neutral.
    pub fn use_background_neutral(&mut self, radii: &[i32]) {
        let n = self.cells.len();
        let mut sum = vec![0.0; n];
        let mut count = vec![0u32; n];
        let v = self.voxels;
        for &radius in radii {
            for (dx, dy) in [(1, 0), (1, 1), (0, 1), (-1, 1), (-1, 0), (-1, -1), (0, -1), (1, -1)] {
                let index = [dx * radius, dy * radius, 0];
                self.for_each_column(index, |i, column| {
                    if let Some(cell) = column.filter(|&c| v.known[c]) {
                        sum[i] += match self.cells.layer_offset[i] {
                            Some(layer) => self.exact[v.squared[layer + cell] as usize],
                            None => self.exact[v.cap as usize],
                        };
                        count[i] += 1;
                    }
                });
            }
        }
        for ((neutral, s), c) in self.neutral.iter_mut().zip(sum).zip(count) {
            if c > 0 {
                *neutral = s / f64::from(c);
            }
        }
    }

    /// The exact score of one lattice pose.
    pub fn score_pose(&mut self, index: [i32; 3]) -> f64 {
        let mut sum = 0.0;
        self.for_each_column(index, |i, column| sum += self.exact_at(i, column));
        sum
    }

    /// Upper bound of the score over a box of lattice poses (exact for a single pose).
    ///
    /// Each local cell's distance at the box's centre pose is reduced by the largest
    /// displacement `Delta` any pose of the box can cause (paper 000: `max(D - Delta, 0)`),
    /// and the reduced distances go through the score. With [`BoundKind::MinPool`] the
    /// translation part of the box is handled exactly by a min-filtered distance transform
    /// (the distance can be no smaller than the smallest one over the box of translations),
    /// leaving `Delta` only the heading part.
    pub fn bound_cell(&mut self, lo: [i32; 3], hi: [i32; 3]) -> f64 {
        let mut center = [0; 3];
        let mut extent = [0; 3];
        for a in 0..3 {
            center[a] = lo[a] + (hi[a] - lo[a]) / 2;
            extent[a] = (center[a] - lo[a]).max(hi[a] - center[a]);
        }
        if extent == [0, 0, 0] {
            return self.score_pose(center);
        }
        let v = self.voxels;
        // Pick the widest min-filter that fits inside the translation box; the rest of the
        // box is covered by the Lipschitz step (distances change by at most the move).
        let widest = extent[0].max(extent[1]) as usize;
        let level = match self.bound_kind {
            BoundKind::MinPool if widest > 0 && !v.pooled.is_empty() => {
                Some((usize::BITS - 1 - widest.leading_zeros()) as usize).map(|l| l.min(v.pooled.len() - 1))
            }
            _ => None,
        };
        let pooled_half = level.map_or(0, |l| 1i32 << l);
        let residual =
            f64::from((extent[0] - pooled_half).max(0)).hypot(f64::from((extent[1] - pooled_half).max(0)));
        let (rotation_fixed, rotation_per_radius) = self.rotation_bound(extent[2]);
        // A hair of slack keeps the bound above the exact score despite rounding.
        let delta_fixed = residual + rotation_fixed + 1e-9;
        let distances = level.map_or(&v.squared, |l| &v.pooled[l]);
        let translation_reach = f64::from(extent[0]).hypot(f64::from(extent[1]));
        let capped = self.exact[v.cap as usize];
        let mut sum = 0.0;
        self.for_each_column(center, |i, column| {
            let radius = self.cells.radii[i];
            let delta = delta_fixed + rotation_per_radius * radius;
            let Some(cell) = column else {
                // Outside the padded grid: unknown here, and occupied voxels lie at least
                // `pad` voxels inside the grid's edges.
                let d = self.pad - f64::from(pooled_half) - delta;
                let step = (d.max(0.0) * BOUND_STEPS_PER_CELL) as usize;
                sum += self.bound[step.min(self.bound.len() - 1)].max(self.neutral[i]);
                return;
            };
            let known_bound = match self.cells.layer_offset[i] {
                Some(layer) => {
                    let d = self.roots[distances[layer + cell] as usize] - delta;
                    let step = (d.max(0.0) * BOUND_STEPS_PER_CELL) as usize;
                    self.bound[step.min(self.bound.len() - 1)]
                }
                // Outside the height layers the distance is capped wherever the cell moves.
                None => capped,
            };
            // Any pose of the box that puts the cell over an unknown column scores neutral.
            let reach = translation_reach + rotation_fixed + rotation_per_radius * radius;
            let may_be_unknown = !v.known[cell] || f64::from(v.to_unknown[cell]) <= reach * reach + 1e-9;
            sum += if may_be_unknown { known_bound.max(self.neutral[i]) } else { known_bound };
        });
        sum
    }

    /// Branch-and-bound search for the best lattice pose scoring above `threshold`, skipping
    /// poses inside any of the `exclude` boxes (inclusive index bounds), starting from the
    /// `seed` pose if given.
    pub fn branch_and_bound(
        &mut self,
        threshold: f64,
        seed: Option<[i32; 3]>,
        exclude: &[([i32; 3], [i32; 3])],
    ) -> SearchOutcome {
        let half = self.lattice.half;
        let mut out = SearchOutcome { best: None, score: threshold, evaluations: 0, poses_tested: 0 };
        let inside = |p: [i32; 3], b: &([i32; 3], [i32; 3])| (0..3).all(|a| p[a] >= b.0[a] && p[a] <= b.1[a]);
        if let Some(p) = seed.filter(|p| !exclude.iter().any(|b| inside(*p, b))) {
            let s = self.score_pose(p);
            out.evaluations += 1;
            out.poses_tested += 1;
            if s > out.score {
                out.score = s;
                out.best = Some(p);
            }
        }
        let root_lo = [-half[0], -half[1], -half[2]];
        let mut heap = BinaryHeap::new();
        let root_bound = self.bound_cell(root_lo, half);
        out.evaluations += 1;
        heap.push(PoseCell { lo: root_lo, hi: half, bound: root_bound });
        while let Some(cell) = heap.pop() {
            if cell.bound <= out.score {
                break;
            }
            // Split along the longest axis; all axes move local cells by about one grid
            // cell per index, so index extents compare directly.
            let sizes = [0, 1, 2].map(|a| cell.hi[a] - cell.lo[a]);
            let axis = match self.split {
                SplitRule::HeadingFirst if sizes[2] > 0 => 2,
                _ => (0..3).max_by_key(|&a| (sizes[a], 3 - a)).unwrap_or(0),
            };
            let mid = cell.lo[axis] + sizes[axis] / 2;
            let mut first_hi = cell.hi;
            first_hi[axis] = mid;
            let mut second_lo = cell.lo;
            second_lo[axis] = mid + 1;
            for (lo, hi) in [(cell.lo, first_hi), (second_lo, cell.hi)] {
                if exclude.iter().any(|b| (0..3).all(|a| lo[a] >= b.0[a] && hi[a] <= b.1[a])) {
                    continue;
                }
                let single = lo == hi;
                if single && Some(lo) == seed {
                    continue;
                }
                let bound = self.bound_cell(lo, hi);
                out.evaluations += 1;
                out.poses_tested += u64::from(single);
                if bound <= out.score {
                    continue;
                }
                if single {
                    out.score = bound;
                    out.best = Some(lo);
                } else {
                    heap.push(PoseCell { lo, hi, bound });
                }
            }
        }
        out
    }

    /// Scores every lattice pose (the reference the branch and bound must agree with).
    pub fn exhaustive(&mut self) -> SearchOutcome {
        let half = self.lattice.half;
        let mut out = SearchOutcome { best: None, score: f64::NEG_INFINITY, evaluations: 0, poses_tested: 0 };
        for k in -half[2]..=half[2] {
            for j in -half[1]..=half[1] {
                for i in -half[0]..=half[0] {
                    let sum = self.score_pose([i, j, k]);
                    out.evaluations += 1;
                    out.poses_tested += 1;
                    if sum > out.score {
                        out.score = sum;
                        out.best = Some([i, j, k]);
                    }
                }
            }
        }
        out
    }

    /// Fits `score ~ a + g.u + u'Hu/2` by least squares to the lattice poses within
    /// `radius` steps of `best` (a normal surface in log space); returns the subpixel offset
    /// (lattice units) and the covariance (lattice units) of the normal whose log is the fitted
    /// surface divided by `temperature`, or `None` without a maximum.
    pub fn fit_peak(
        &mut self,
        best: [i32; 3],
        radius: i32,
        temperature: f64,
    ) -> Option<([f64; 3], Matrix3<f64>)> {
        let mut ata = SMatrix::<f64, 10, 10>::zeros();
        let mut atb = SVector::<f64, 10>::zeros();
        let center = self.score_pose(best);
        for dk in -radius..=radius {
            for dj in -radius..=radius {
                for di in -radius..=radius {
                    let s = if (di, dj, dk) == (0, 0, 0) {
                        center
                    } else {
                        self.score_pose([best[0] + di, best[1] + dj, best[2] + dk])
                    } - center;
                    let (a, b, c) = (f64::from(di), f64::from(dj), f64::from(dk));
                    let f =
                        SVector::<f64, 10>::from([1.0, a, b, c, a * a, b * b, c * c, a * b, a * c, b * c]);
                    ata += f * f.transpose();
                    atb += f * s;
                }
            }
        }
        let beta = ata.lu().solve(&atb)?;
        let g = Vector3::new(beta[1], beta[2], beta[3]);
        let h = Matrix3::new(
            2.0 * beta[4],
            beta[7],
            beta[8],
            beta[7],
            2.0 * beta[5],
            beta[9],
            beta[8],
            beta[9],
            2.0 * beta[6],
        );
        // A proper maximum has a positive-definite negative Hessian. A ridge (a direction
        // the map does not constrain) gives a tiny or negative curvature along it: floor the
        // eigenvalues so that direction gets a large variance instead of breaking the fit.
        let eigen = (-h).symmetric_eigen();
        let largest = eigen.eigenvalues.max();
        if largest.is_nan() || largest <= 0.0 {
            return None;
        }
        // Curvature floor: no direction gets a variance beyond the search window's size.
        let window = f64::from(self.lattice.half.iter().copied().max().unwrap_or(1).max(1));
        let floor = (temperature / (window * window)).min(largest);
        let clamped = eigen.eigenvalues.map(|e| e.max(floor));
        let inv = eigen.eigenvectors
            * Matrix3::from_diagonal(&clamped.map(|e| 1.0 / e))
            * eigen.eigenvectors.transpose();
        let offset = inv * g;
        let offset = [0, 1, 2].map(|a| offset[a].clamp(-1.0, 1.0));
        Some((offset, inv * temperature))
    }
}

/// Parameters of the peak analysis shared by the matchers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PeakAnalysis {
    /// Divisor turning score differences into log-probability differences (accounts for the
    /// correlation between neighbouring local cells, which the score treats as independent).
    pub temperature: f64,
    /// The failure search only looks for competitors within this many temperature units of
    /// the best score (smaller gaps are reported as a failure probability of about e^-margin).
    pub failure_margin: f64,
    /// Smallest half-size of the region around the peak excluded from the failure search
    /// (lattice steps).
    pub min_exclusion: i32,
    /// Half-size of the neighbourhood of the peak the normal surface is fitted to (steps).
    pub fit_radius: i32,
    /// Most competing peaks searched for the failure probability.
    pub max_competitors: usize,
}

/// Runs a full match: branch and bound from the dead-reckoned pose, peak fit, failure search.
pub fn run_match<S: DistanceScore>(
    scorer: &mut Scorer<'_, S>,
    analysis: &PeakAnalysis,
    exhaustive: bool,
) -> MatchDetails {
    let main = if exhaustive {
        scorer.exhaustive()
    } else {
        scorer.branch_and_bound(f64::NEG_INFINITY, Some([0, 0, 0]), &[])
    };
    let best = main.best.unwrap_or([0, 0, 0]);
    let lattice = scorer.lattice();
    let temperature = analysis.temperature.max(1e-12);
    let fit = scorer.fit_peak(best, analysis.fit_radius, temperature);
    let steps = [lattice.step, lattice.step, lattice.yaw_step];
    let (offset, cov_lattice, peak_fit_ok) = match fit {
        Some((o, c)) => (o, c, true),
        None => {
            // No proper peak: report the whole window as the uncertainty.
            let w = [0, 1, 2].map(|a| f64::from(lattice.half[a].max(1)).powi(2));
            ([0.0; 3], Matrix3::from_diagonal(&Vector3::new(w[0], w[1], w[2])), false)
        }
    };
    let mut covariance = [[0.0; 3]; 3];
    for (r, row) in covariance.iter_mut().enumerate() {
        for (c, v) in row.iter_mut().enumerate() {
            *v = cov_lattice[(r, c)] * steps[r] * steps[c];
        }
        // The lattice itself cannot resolve better than a uniform error over one step.
        row[r] += steps[r] * steps[r] / 12.0;
    }
    // Failure search: the best pose away from the peak.
    let exclusion = [0, 1, 2].map(|a| {
        let sigma = cov_lattice[(a, a)].max(0.0).sqrt();
        let e = (2.5 * sigma).ceil() as i32;
        e.clamp(analysis.min_exclusion, (lattice.half[a] / 2).max(analysis.min_exclusion))
    });
    // Competing peaks: repeatedly the best pose outside the peaks found so far, while one
    // comes within the failure margin. The match fails if the true pose is at any of them:
    // P = sum_j w_j / (1 + sum_j w_j), w_j = exp((score_j - best) / temperature).
    let threshold = main.score - analysis.failure_margin * temperature;
    let mut peaks = vec![best];
    let mut excluded = Vec::new();
    let mut competitor_weight = 0.0;
    let mut runner_up = None;
    let mut failure_search_evaluations = 0;
    while peaks.len() <= analysis.max_competitors {
        let peak = peaks[peaks.len() - 1];
        excluded.push(([0, 1, 2].map(|a| peak[a] - exclusion[a]), [0, 1, 2].map(|a| peak[a] + exclusion[a])));
        let competitor = scorer.branch_and_bound(threshold, None, &excluded);
        failure_search_evaluations += competitor.evaluations;
        let Some(found) = competitor.best else {
            break;
        };
        runner_up = runner_up.or(Some(competitor.score));
        competitor_weight += ((competitor.score - main.score) / temperature).exp();
        peaks.push(found);
    }
    if runner_up.is_none() {
        // Nothing within the margin: the failure probability is below e^-margin.
        competitor_weight = (-analysis.failure_margin).exp();
    }
    let mut failure_probability = competitor_weight / (1.0 + competitor_weight);
    if !peak_fit_ok {
        failure_probability = failure_probability.max(0.5);
    }
    let u = [0, 1, 2].map(|a| f64::from(best[a]) + offset[a]);
    MatchDetails {
        result: MatchResult {
            pose: lattice.pose(u),
            covariance,
            log_likelihood: main.score,
            failure_probability,
            poses_evaluated: main.evaluations,
        },
        best_index: best,
        lattice,
        runner_up,
        poses_tested: main.poses_tested,
        failure_search_evaluations,
        local_cells: scorer.cells.len(),
        peak_fit_ok,
    }
}
