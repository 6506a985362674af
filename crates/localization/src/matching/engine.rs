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
//! - [`BoundKind::MinPool`] bounds the translation part of a box exactly: boxes are
//!   power-of-two blocks of lattice translations, and a sliding-window min-pyramid of the
//!   distance transform (level `t` = two shifted copies of level `t - 1`) gives each local
//!   cell's smallest distance over a block in one lookup, so the bound is the sum of the
//!   per-cell maxima (never looser than the paper's bound, which stays available as
//!   [`BoundKind::Distance`]); [`SplitRule::HeadingFirst`] cuts heading before translation,
//!   because boxes spanning headings pay a voxel-rounding slack. A box is dropped as soon as
//!   its partial bound falls to the best score; which cells are looked up, and in what order,
//!   is below. The work is counted in lookups (see [`SearchOutcome::evaluations`]).
//! - Per-cell bounds are tight at fine blocks only: at 4 x 8 cells and more, ground cells find
//!   their height layer somewhere in nearly every block, so coarse boxes rarely prune and the
//!   work is in bounding the fine ones. Four things cut it (lattice poses per evaluation on
//!   the 100 `rovernav eval localization` cases, 23.2 before): a box's per-cell bounds are
//!   kept and its sub-boxes start from them, looking up only cells that can still tighten
//!   (26.2); every box taken from the queue starts a greedy dive to a single pose, so that a
//!   good score to prune against comes early (31.0 on 30 cases, 31.6 with the optimum known
//!   in advance); each pyramid level learns which cells' lookups tighten its bounds and looks
//!   up only those, best first (`CellPlan`, 44.8 on 30 cases); and a box of one heading looks
//!   up first the cells that tightened the same block at the neighbouring heading, where every
//!   cell lands within a voxel of where it lands here (59.3 on 30 cases). Single poses are
//!   bounded on the distance transform before they are scored, and scored only if they may
//!   win. Exactness is untouched: every bound is a sum of per-cell upper bounds, whichever
//!   cells were looked up (62.5 on the 100 cases, all exact).
//! - Wall time (issue 43; profiled with `perf record` on `benchmark::localisation_workload`,
//!   39 000 local cells): the box bounds' lookups cost about 20 ns each against 4 ns for
//!   exhaustive search's, the pyramid load being the hottest instruction (cache misses: the
//!   learnt order visits cells anywhere in the voxel arrays), and sorts (cell plans, hints)
//!   took a fifth of the time. Cells are now looked up in tiers of expected decrease, index
//!   order within a tier (`ORDER_TIERS`), plans are re-sorted less often and built when a
//!   level is first reached, hints keep their lookup order, the bound store's memory is
//!   reused across the searches of a match, and the local cells are rotated once per heading
//!   (`Scorer::rotated`): the search makes more lookups (59.8 lattice poses per evaluation on
//!   the exactness test's 100 cases) in less time.
//! - Local cells over unknown parts of the global map score a neutral constant instead of the
//!   outlier density: the paper's choice biases matches towards maximum overlap (measured: 10-20
//!   cm downrange bias between consecutive stereo views).
//! - That neutral score can be each local cell's own background, its mean score at misaligned
//!   poses ([`Scorer::use_background_neutral`]): smooth ground, which scores well anywhere,
//!   then counts for nothing, and only cells that discriminate poses pull the match.

use std::cmp::Ordering;
use std::collections::{BinaryHeap, HashMap};

use nalgebra::{DMatrix, DVector, Matrix3, Vector3};
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
    /// `pyramid[t - 1]` (level `t` >= 1): for each voxel, the smallest squared distance (capped
    /// at 255) over the block of its layer that starts at it and spans [`block_size`]`(t)`
    /// voxels along x and y: a sliding-window min-pyramid of `squared` whose level `t` is two
    /// shifted copies of level `t - 1`, so that a box of translations at one heading is
    /// bounded exactly by one lookup per local cell.
    pyramid: Vec<Vec<u8>>,
    /// `unknown_pyramid[t]`: per column, whether the block of [`block_size`]`(t)` columns
    /// starting at it holds a column where the global map is unknown or leaves the grid.
    unknown_pyramid: Vec<Vec<bool>>,
    /// `nonzero_fraction[t][layer]`: over the known columns, the fraction whose level-`t`
    /// block at that layer holds no occupied voxel (minimum distance above zero). A local cell
    /// in a layer where this is small nearly always gets the best score's bound at that level:
    /// the prior order of each level's `CellPlan` looks such cells up last.
    nonzero_fraction: Vec<Vec<f32>>,
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
    /// `pool_levels` pyramid levels are kept for [`BoundKind::MinPool`] (blocks of 1x2, 2x2,
    /// 2x4, 4x4, ... voxels); zero keeps none.
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
                let layer = height_layer(f64::from(h), layer_height);
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
                    let z = (height_layer(f64::from(h), layer_height) - layer0) as usize;
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
        let pyramid = min_pyramid(&squared, cols, rows, layers, pool_levels);
        let unknown_pyramid = unknown_pyramid(&known, cols, rows, pool_levels);
        let nonzero_fraction = nonzero_fractions(&squared, &pyramid, &known, cols, rows, layers);
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
            pyramid,
            unknown_pyramid,
            nonzero_fraction,
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
        let layer = height_layer(z, self.layer_height) - self.layer0;
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

/// The height layer of a (high-passed) height, `floor(z / layer_height)`.
///
/// Layer edges at multiples of the layer height put one edge at zero, where high-passed ground
/// lies, so ground cells split between two layers (measured: 52 % and 59 % of a synthetic
/// map's ground columns hold a voxel in each). Centring the layers on zero instead was
/// measured worse on the simulator's mast-stereo sequence (6.1 / 5.9 cm mean downrange /
/// crossrange error against 4.2 / 4.6 cm), so the edge stays.
#[inline]
fn height_layer(z: f64, layer_height: f64) -> i64 {
    (z / layer_height).floor() as i64
}

/// `floor` for grid coordinates without a libm call: exact for |v| < 2^20, and any value
/// below that range maps below -2^20 (outside every grid) as floor would.
#[inline]
fn fast_floor(v: f64) -> i64 {
    const OFFSET: f64 = 1_048_576.0;
    if v > -OFFSET { (v + OFFSET) as i64 - OFFSET as i64 } else { i64::MIN / 2 }
}

/// Voxels spanned along (x, y) by a block of pyramid level `t`: `(2^(t/2), 2^((t+1)/2))`, so
/// level `t` is level `t - 1` doubled along y (odd `t`) or along x (even `t`).
pub fn block_size(t: u32) -> (usize, usize) {
    (1 << (t / 2), 1 << t.div_ceil(2))
}

/// Offset (voxels along x for even `t`, along y for odd `t`) of the second copy of level
/// `t - 1` that level `t` takes the minimum with.
fn level_shift(t: u32) -> usize {
    1 << ((t - 1) / 2)
}

/// The sliding-window min-pyramid of a voxel array (levels 1..=`levels`, see
/// `VoxelMap::pyramid`); voxels beyond the grid's edge count as far (they do not lower a
/// block's minimum: a pose that moves a local cell off the grid is covered by the unknown
/// pyramid instead).
fn min_pyramid(squared: &[u16], cols: usize, rows: usize, layers: usize, levels: usize) -> Vec<Vec<u8>> {
    let mut out: Vec<Vec<u8>> = Vec::with_capacity(levels);
    let first: Vec<u8> = squared.iter().map(|&v| v.min(255) as u8).collect();
    for t in 1..=levels as u32 {
        let shift = level_shift(t);
        let previous = out.last().unwrap_or(&first);
        let mut level = previous.clone();
        for z in 0..layers {
            for r in 0..rows {
                let base = (z * rows + r) * cols;
                if t % 2 == 1 {
                    if r + shift < rows {
                        let other = base + shift * cols;
                        for c in 0..cols {
                            level[base + c] = level[base + c].min(previous[other + c]);
                        }
                    }
                } else {
                    for c in 0..cols.saturating_sub(shift) {
                        level[base + c] = level[base + c].min(previous[base + c + shift]);
                    }
                }
            }
        }
        out.push(level);
    }
    out
}

/// Per pyramid level (0 = the distance transform itself) and layer, the fraction of known
/// columns (every second row and column: a statistic) whose block holds no occupied voxel.
fn nonzero_fractions(
    squared: &[u16],
    pyramid: &[Vec<u8>],
    known: &[bool],
    cols: usize,
    rows: usize,
    layers: usize,
) -> Vec<Vec<f32>> {
    let sampled: Vec<usize> =
        (0..rows).step_by(2).flat_map(|r| (0..cols).step_by(2).map(move |c| r * cols + c)).collect();
    let sampled: Vec<usize> = sampled.into_iter().filter(|&i| known[i]).collect();
    let n = sampled.len().max(1) as f32;
    let plane = rows * cols;
    let mut out = vec![
        (0..layers)
            .map(|z| sampled.iter().filter(|&&i| squared[z * plane + i] > 0).count() as f32 / n)
            .collect::<Vec<f32>>(),
    ];
    for level in pyramid {
        out.push(
            (0..layers)
                .map(|z| sampled.iter().filter(|&&i| level[z * plane + i] > 0).count() as f32 / n)
                .collect(),
        );
    }
    out
}

/// Levels 0..=`levels` of "the block starting at this column holds an unknown column or
/// reaches beyond the grid" (level 0: the column is unknown).
fn unknown_pyramid(known: &[bool], cols: usize, rows: usize, levels: usize) -> Vec<Vec<bool>> {
    let mut out = vec![known.iter().map(|k| !k).collect::<Vec<bool>>()];
    for t in 1..=levels as u32 {
        let shift = level_shift(t);
        let previous = &out[out.len() - 1];
        let mut level = previous.clone();
        for r in 0..rows {
            for c in 0..cols {
                let (c2, r2) = if t % 2 == 1 { (c, r + shift) } else { (c + shift, r) };
                level[r * cols + c] |= c2 >= cols || r2 >= rows || previous[r2 * cols + c2];
            }
        }
        out.push(level);
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
            let layer = height_layer(z, voxels.layer_height) - voxels.layer0;
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
    /// Pyramid level of the translation block (its low corner is `lo`; `hi` clips it to the
    /// window).
    level: u32,
    bound: f64,
    /// Slot of the box's per-cell bounds in the search's store (`NO_SLOT`: none kept).
    slot: u32,
}

/// `PoseCell::slot` of a box without per-cell bounds.
const NO_SLOT: u32 = u32::MAX;

/// A box's per-cell bounds as its sub-boxes start from them: upper bounds rounded up to f32,
/// and their sum.
#[derive(Clone, Copy)]
struct Inherited<'b> {
    values: &'b [f32],
    sum: f64,
}

/// The per-cell bounds of the boxes in a search's queue, `n` per slot (slot `ROOT_SLOT`: the
/// trivial bounds), rounded up to f32 (still upper bounds, in half the memory of f64).
struct BoundStore {
    values: Vec<f32>,
    sums: Vec<f64>,
    free: Vec<u32>,
    n: usize,
}

/// The slot of the trivial bounds, which every box's bounds are tightened from.
const ROOT_SLOT: u32 = 0;

impl BoundStore {
    /// A store holding the trivial bounds.
    fn new(trivial: &[f64]) -> Self {
        let values: Vec<f32> = trivial.iter().map(|&t| round_up_f32(t)).collect();
        let sum = values.iter().map(|&v| f64::from(v)).sum();
        Self { values, sums: vec![sum], free: Vec::new(), n: trivial.len() }
    }

    /// Empties the store down to the trivial bounds, keeping its memory.
    fn reset(&mut self, trivial: &[f64]) {
        self.values.clear();
        self.values.extend(trivial.iter().map(|&t| round_up_f32(t)));
        self.sums.clear();
        self.sums.push(self.values.iter().map(|&v| f64::from(v)).sum());
        self.free.clear();
        self.n = trivial.len();
    }

    /// The bounds kept in `slot` (the trivial ones for `NO_SLOT`).
    fn get(&self, slot: u32) -> Inherited<'_> {
        let slot = if slot == NO_SLOT { ROOT_SLOT } else { slot };
        let at = slot as usize * self.n;
        Inherited { values: &self.values[at..at + self.n], sum: self.sums[slot as usize] }
    }

    /// Keeps the bounds of a box: its parent's (in `parent`) tightened by `changes`;
    /// `NO_SLOT` when the store is full.
    fn keep(&mut self, parent: u32, changes: &[(u32, f64)]) -> u32 {
        let parent = if parent == NO_SLOT { ROOT_SLOT } else { parent };
        let slot = match self.free.pop() {
            Some(slot) => slot,
            None if self.values.len() + self.n <= MAX_STORED_BOUNDS => {
                self.values.resize(self.values.len() + self.n, 0.0);
                self.sums.push(0.0);
                (self.sums.len() - 1) as u32
            }
            None => return NO_SLOT,
        };
        let (from, at) = (parent as usize * self.n, slot as usize * self.n);
        self.values.copy_within(from..from + self.n, at);
        let mut sum = self.sums[parent as usize];
        for &(i, bound) in changes {
            let kept = &mut self.values[at + i as usize];
            let tightened = round_up_f32(bound);
            sum += f64::from(tightened) - f64::from(*kept);
            *kept = tightened;
        }
        self.sums[slot as usize] = sum;
        slot
    }

    /// Frees a slot (`NO_SLOT` and `ROOT_SLOT` are ignored).
    fn release(&mut self, slot: u32) {
        if slot != NO_SLOT && slot != ROOT_SLOT {
            self.free.push(slot);
        }
    }
}

/// The smallest f32 not below `v`.
fn round_up_f32(v: f64) -> f32 {
    let f = v as f32;
    if f64::from(f) < v { f.next_up() } else { f }
}

impl PartialEq for PoseCell {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
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
    /// Work in pose evaluations: distance-transform lookups divided by the local cells, rounded
    /// up (a pose scored costs one; a box bounded costs the fraction of its local cells that
    /// needed a lookup, see `Scorer::bound_block`).
    pub evaluations: u64,
    /// Boxes bounded and poses scored, whatever their cost.
    pub boxes: u64,
    /// Of those, single poses (bounded on the distance transform, and scored explicitly when
    /// they might win).
    pub poses_tested: u64,
}

impl SearchOutcome {
    /// Counts one pose scored explicitly and keeps it if it beats the best so far.
    fn offer(&mut self, pose: [i32; 3], score: f64) {
        self.boxes += 1;
        self.poses_tested += 1;
        if score > self.score {
            self.score = score;
            self.best = Some(pose);
        }
    }
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
    /// Single poses the main search bounded or scored (`poses_evaluated` counts their lookups
    /// with those of the box bounds, in poses' worth).
    pub poses_tested: u64,
    /// Boxes bounded and poses scored by the main search.
    pub boxes: u64,
    /// Evaluations spent on the failure-probability search.
    pub failure_search_evaluations: u64,
    /// Number of local cells scored per pose.
    pub local_cells: usize,
    /// Whether the quadratic fit around the peak was a proper maximum.
    pub peak_fit_ok: bool,
}

/// The map from a local cell's body-frame position to its voxel column and row at one pose:
/// the rotation and the continuous offset, then a whole-voxel shift (lattice translations
/// are whole-voxel moves, which is what makes the pyramid bound exact).
#[derive(Clone, Copy, Debug)]
struct Placement {
    cs: f64,
    ss: f64,
    bx: f64,
    by: f64,
    shift: [i64; 2],
}

impl Placement {
    #[inline]
    fn voxel(&self, x: f64, y: f64) -> (i64, i64) {
        (
            fast_floor(self.bx + self.cs * x - self.ss * y) + self.shift[0],
            fast_floor(self.by + self.ss * x + self.cs * y) + self.shift[1],
        )
    }
}

/// How the box bounds of one pyramid level choose and order the local cells they look up.
///
/// Any subset of cells gives a valid bound (the others keep their parent box's bound), so the
/// choice only trades lookups against pruning. Each lookup's decrease of its cell's bound is
/// recorded, and cells are looked up in order of their mean decrease per lookup (shrunk
/// towards a prior from the cell's layer), skipping cells whose expected decrease is below
/// the level's [`min_rate_units`]. Why: whether a cell's lookup tightens a bound depends on
/// where it lands (a ground cell whose landing region holds its height layer everywhere never
/// does), which the layer statistics alone cannot tell and a few hundred lookups reveal.
#[derive(Clone, Debug, Default)]
struct CellPlan {
    /// All local cells, highest expected decrease first.
    order: Vec<usize>,
    /// How many cells at the front of `order` are looked up.
    active: usize,
    /// Per cell: lookups made at this level and the summed decrease of its bound they brought
    /// (side by side: the search touches both at once).
    tally: Vec<[f32; 2]>,
    /// Per cell: prior decrease per lookup (its layer's fraction of blocks without an
    /// occupied voxel times the loss of a one-voxel miss).
    prior: Vec<f32>,
    /// Lookups made at this level since `order` was sorted.
    since_sort: usize,
    /// Smallest expected decrease per lookup worth a lookup.
    min_rate: f32,
}

/// Weight of a cell's prior decrease, in lookups.
const PRIOR_LOOKUPS: f32 = 4.0;

/// Lookups, in local cells' worth, between re-sorts of a level's cell order. Measured on 30
/// of the `rovernav eval localization` cases: 57.8 lattice poses per evaluation at 2, 57.1 at
/// 4, 54.4 at 16; at 2 the sorts took 13 % of the bench's match time (39 000 local cells). In
/// wall time on the localisation workload (`benchmark::localisation_workload`, CPU seconds
/// per match with `ORDER_TIERS` = 4): 0.30 s at 16, 0.25 s at 64, with the same lookups.
const RESORT_EVERY: usize = 64;

/// Tiers of a level's cell order (by expected decrease) within which cells are looked up in
/// index order. Lookups in the learnt order land anywhere in the voxel arrays (tens of MB)
/// and miss the cache: the pyramid load was the hottest instruction of the profile. Measured
/// on the localisation workload (CPU s per match, lookups in poses' worth): learnt order 0.32
/// s (177), one tier 0.26 s (217), four tiers 0.25 s (200).
const ORDER_TIERS: usize = 4;

impl CellPlan {
    /// Expected decrease per lookup of cell `i`.
    fn rate(&self, i: usize) -> f32 {
        let [lookups, decrease] = self.tally[i];
        (decrease + self.prior[i] * PRIOR_LOOKUPS) / (lookups + PRIOR_LOOKUPS)
    }

    /// Sorts the cells by expected decrease (ties in a fixed scattered order, so that equal
    /// cells are not taken row by row) and sets how many are worth a lookup.
    fn sort(&mut self) {
        let rates: Vec<f32> = (0..self.order.len()).map(|i| self.rate(i)).collect();
        // One integer key per cell, sorted in a flat array (a sort of tens of thousands of
        // cells runs often): the rate's bits in descending total order, then the spread, a
        // bijection of the index, so that the keys are distinct and the order determined.
        let descending = |r: f32| {
            let bits = r.to_bits();
            !(if bits >> 31 == 1 { !bits } else { bits | 1 << 31 })
        };
        let mut keys: Vec<(u64, u32)> = rates
            .iter()
            .enumerate()
            .map(|(i, &r)| {
                let spread = (i as u32).wrapping_mul(2_654_435_761);
                ((u64::from(descending(r)) << 32) | u64::from(spread), i as u32)
            })
            .collect();
        keys.sort_unstable_by_key(|&(key, _)| key);
        for (slot, &(_, i)) in self.order.iter_mut().zip(&keys) {
            *slot = i as usize;
        }
        self.active = self.order.iter().take_while(|&&i| rates[i] >= self.min_rate).count();
        // Within each tier of expected decrease, cells in index order (the local map's row
        // order), so that consecutive lookups land near each other in the voxel arrays.
        let tier = self.active.div_ceil(ORDER_TIERS).max(1);
        for chunk in self.order[..self.active].chunks_mut(tier) {
            chunk.sort_unstable();
        }
        self.since_sort = 0;
    }
}

/// Smallest expected decrease per lookup (in units of the loss of a one-voxel miss) for which
/// a level's box bounds look a cell up.
///
/// Measured on 30 of the `rovernav eval localization` cases (lattice poses per evaluation):
/// coarse blocks (level >= 5, 4 x 8 cells and more) rarely prune, so only cells that nearly
/// always tighten them are looked up there (0.1: 37.8, 0.15: 39.1, 0.25: 42.8, 0.4: 43.7,
/// 0.6: 44.8); fine blocks need most cells to prune (level 4 at 0.15: 36.4, 0.07: 38.9,
/// 0.04: best; levels 1-3 at 0.03: 40.4, 0.05: best, 0.08: equal). Single poses take every
/// cell: a pose that is not pruned is scored in full anyway.
fn min_rate_units(level: usize) -> f64 {
    match level {
        0 => 0.0,
        1..=3 => 0.05,
        4 => 0.04,
        _ => 0.6,
    }
}

/// Pyramid levels whose box bounds take their cell order from the same block at a
/// neighbouring heading (see `Scorer::bound_block`); measured: levels 1-4 give 59.3 lattice
/// poses per evaluation, 1-2 give 46.4, 1-6 give 58.9 (the learnt order alone: 45.7).
const NEIGHBOUR_HINT_LEVELS: std::ops::RangeInclusive<u32> = 1..=4;

/// Most per-cell bounds (f32) the search keeps for the boxes in its queue (64 MB); beyond it
/// boxes keep none and their children start from the trivial bounds.
const MAX_STORED_BOUNDS: usize = 1 << 24;

/// Most cells the neighbouring-heading hints hold at once (32 MB).
const MAX_HINT_ENTRIES: usize = 1 << 22;

/// A box is pruned when its bound is below the best score by at least this (or the rounding
/// error of a sum of the local map's cells, when larger): slack against the rounding of sums
/// taken in different orders.
const PRUNE_MARGIN: f64 = 1e-9;

/// What a box bound reads of one local cell, side by side: the bounds visit cells in an
/// order of their own, and one cache line per cell keeps that cheap on large local maps.
#[derive(Clone, Copy, Debug)]
struct HotCell {
    x: f64,
    y: f64,
    /// Offset of the cell's height layer in the voxel array, `None` outside the layers.
    layer: Option<usize>,
    /// Distance from the rover origin (voxels).
    radius: f64,
    neutral: f64,
    trivial: f64,
}

/// Most cached rotated cell positions (`Scorer::rotated`, 8 bytes each: 64 MB).
const MAX_ROTATED: usize = 1 << 23;

/// A box of one heading by (pyramid level, block corner x, y, heading).
type HintKey = (u32, i32, i32, i32);

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
    /// Per local cell: its trivial bound, the best of the best score and its neutral score.
    trivial: Vec<f64>,
    /// The sum of `trivial`.
    trivial_all: f64,
    /// Per local cell: what box bounds read of it.
    hot: Vec<HotCell>,
    /// Per heading (`k + half[2]`): each local cell's voxel column and row at translation
    /// (0, 0), rotated once when a box bound first needs the heading (`None`: not yet, or
    /// beyond `MAX_ROTATED` or `i32`); lattice translations add whole voxels to it.
    rotated: Vec<Option<Vec<[i32; 2]>>>,
    /// Entries held in `rotated`.
    rotated_entries: usize,
    /// How cells are bounded.
    bound_kind: BoundKind,
    /// How cells are split.
    split: SplitRule,
    /// Per pyramid level: which cells its box bounds look up, in which order.
    plans: Vec<CellPlan>,
    /// Per (level, block corner x, y, heading) of single-heading boxes bounded at
    /// [`NEIGHBOUR_HINT_LEVELS`]: the cells looked up and their decrease from the trivial
    /// bound, a guide (never a bound) for the same block at the next heading.
    hints: HashMap<HintKey, Vec<(u32, f32)>>,
    /// Cells held in `hints`, all boxes together.
    hint_entries: usize,
    /// Per local cell: the `hint_generation` of the last hint that held it.
    in_hint: Vec<u32>,
    /// Counter of box bounds, to mark hint membership without clearing `in_hint`.
    hint_generation: u32,
    /// Distance-transform lookups made so far (one per local cell per pose scored or box
    /// bounded; none for a cell whose bound is inherited or trivial).
    lookups: u64,
    /// The per-cell bound store of the last search, kept so that the next search (the failure
    /// search runs several) reuses its memory instead of faulting in fresh pages.
    spare_store: Option<BoundStore>,
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
        let mut scorer = Self {
            voxels,
            cells,
            lattice,
            exact,
            bound,
            roots,
            pad: cap_d.floor() + 1.0,
            neutral: vec![score.score(neutral_distance); cells.len()],
            trivial: Vec::new(),
            trivial_all: 0.0,
            hot: Vec::new(),
            rotated: Vec::new(),
            rotated_entries: 0,
            bound_kind,
            split,
            plans: Vec::new(),
            hints: HashMap::new(),
            hint_entries: 0,
            in_hint: vec![0; cells.len()],
            hint_generation: 0,
            lookups: 0,
            spare_store: None,
            _score: std::marker::PhantomData,
        };
        scorer.plan_cells();
        scorer
    }

    /// Sets the trivial bounds from the current neutral scores and forgets the cell plans
    /// learnt (they restart from their priors at the next box bound).
    fn plan_cells(&mut self) {
        let best_anywhere = self.exact[0];
        self.trivial = self.neutral.iter().map(|n| best_anywhere.max(*n)).collect();
        self.trivial_all = self.trivial.iter().sum();
        self.hot = (0..self.cells.len())
            .map(|i| HotCell {
                x: self.cells.xs[i],
                y: self.cells.ys[i],
                layer: self.cells.layer_offset[i],
                radius: self.cells.radii[i],
                neutral: self.neutral[i],
                trivial: self.trivial[i],
            })
            .collect();
        self.plans.clear();
        self.hints.clear();
        self.hint_entries = 0;
    }

    /// Starts each level's cell plan from its prior, when the first box is bounded (a
    /// scorer's neutral scores may change before).
    fn build_plans(&mut self) {
        self.plans = vec![CellPlan::default(); self.voxels.nonzero_fraction.len()];
    }

    /// The cell plan of one pyramid level, from its prior.
    fn build_plan(&self, level: usize) -> CellPlan {
        let v = self.voxels;
        let plane = v.rows * v.cols;
        let best_anywhere = self.exact[0];
        let miss = best_anywhere - self.exact[1.min(self.exact.len() - 1)];
        let n = self.cells.len();
        let fractions = &v.nonzero_fraction[level];
        let prior = (0..n)
            .map(|i| {
                let f = self.cells.layer_offset[i].map_or(1.0, |offset| fractions[offset / plane]);
                (f64::from(f) * miss) as f32
            })
            .collect();
        let mut plan = CellPlan {
            order: (0..n).collect(),
            active: 0,
            tally: vec![[0.0; 2]; n],
            prior,
            since_sort: 0,
            min_rate: (min_rate_units(level) * miss) as f32,
        };
        plan.sort();
        plan
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
        let (cols, rows) = (v.cols as i64, v.rows as i64);
        self.for_each_voxel(index, |i, col, row| {
            let inside = col >= 0 && row >= 0 && col < cols && row < rows;
            visit(i, inside.then(|| row as usize * v.cols + col as usize));
        });
    }

    /// Visits each local cell's voxel column and row at lattice pose `index` (possibly off
    /// the grid).
    #[inline]
    fn for_each_voxel(&self, index: [i32; 3], mut visit: impl FnMut(usize, i64, i64)) {
        let place = self.placement(index);
        for (i, (&x, &y)) in self.cells.xs.iter().zip(&self.cells.ys).enumerate() {
            let (col, row) = place.voxel(x, y);
            visit(i, col, row);
        }
    }

    /// Where local cells land in the voxel grid at lattice pose `index`.
    #[inline]
    fn placement(&self, index: [i32; 3]) -> Placement {
        let v = self.voxels;
        let yaw = self.lattice.center.yaw + f64::from(index[2]) * self.lattice.yaw_step;
        let inv = 1.0 / v.resolution;
        let (s, c) = yaw.sin_cos();
        Placement {
            cs: c * inv,
            ss: s * inv,
            bx: (self.lattice.center.x - v.origin_x) * inv,
            by: (self.lattice.center.y - v.origin_y) * inv,
            shift: [i64::from(index[0]), i64::from(index[1])],
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
        self.plan_cells();
    }

    /// The exact score of one lattice pose.
    pub fn score_pose(&mut self, index: [i32; 3]) -> f64 {
        self.lookups += self.cells.len() as u64;
        let mut sum = 0.0;
        self.for_each_column(index, |i, column| sum += self.exact_at(i, column));
        sum
    }

    /// Upper bound of the score over a box of lattice poses (inclusive bounds; exact for a
    /// single pose).
    ///
    /// With [`BoundKind::Distance`], paper 000's bound: each local cell's distance at the
    /// box's centre pose reduced by the largest displacement `Delta` any pose of the box can
    /// cause, `max(D - Delta, 0)`. With [`BoundKind::MinPool`], the translation part of the
    /// box is taken exactly from the min-pyramid (see `Scorer::bound_block`), over the
    /// smallest pyramid block that covers it.
    pub fn bound_cell(&mut self, lo: [i32; 3], hi: [i32; 3]) -> f64 {
        if lo == hi {
            return self.score_pose(lo);
        }
        match self.bound_kind {
            BoundKind::Distance => self.bound_distance(lo, hi),
            BoundKind::MinPool => {
                let span = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(0) as u32 + 1;
                // Square block of side 2^a >= span: level 2a.
                let a = span.next_power_of_two().trailing_zeros();
                let store = BoundStore::new(&self.trivial);
                self.bound_block(
                    lo,
                    2 * a,
                    lo[2],
                    hi[2],
                    f64::NEG_INFINITY,
                    store.get(ROOT_SLOT),
                    &mut Vec::new(),
                )
            }
        }
    }

    /// Paper 000's bound over a box (see [`Scorer::bound_cell`]).
    fn bound_distance(&mut self, lo: [i32; 3], hi: [i32; 3]) -> f64 {
        self.lookups += self.cells.len() as u64;
        let mut center = [0; 3];
        let mut extent = [0; 3];
        for a in 0..3 {
            center[a] = lo[a] + (hi[a] - lo[a]) / 2;
            extent[a] = (center[a] - lo[a]).max(hi[a] - center[a]);
        }
        let v = self.voxels;
        let (rotation_fixed, rotation_per_radius) = self.rotation_bound(extent[2]);
        let translation_reach = f64::from(extent[0]).hypot(f64::from(extent[1]));
        // A hair of slack keeps the bound above the exact score despite rounding.
        let delta_fixed = translation_reach + rotation_fixed + 1e-9;
        let capped = self.exact[v.cap as usize];
        let mut sum = 0.0;
        self.for_each_column(center, |i, column| {
            let delta = delta_fixed + rotation_per_radius * self.cells.radii[i];
            let Some(cell) = column else {
                // Outside the padded grid: unknown here, and occupied voxels lie at least
                // `pad` voxels inside the grid's edges.
                let d = self.pad - delta;
                let step = (d.max(0.0) * BOUND_STEPS_PER_CELL) as usize;
                sum += self.bound[step.min(self.bound.len() - 1)].max(self.neutral[i]);
                return;
            };
            let known_bound = match self.cells.layer_offset[i] {
                Some(layer) => {
                    let d = self.roots[v.squared[layer + cell] as usize] - delta;
                    let step = (d.max(0.0) * BOUND_STEPS_PER_CELL) as usize;
                    self.bound[step.min(self.bound.len() - 1)]
                }
                // Outside the height layers the distance is capped wherever the cell moves.
                None => capped,
            };
            // Any pose of the box that puts the cell over an unknown column scores neutral.
            let may_be_unknown = !v.known[cell] || f64::from(v.to_unknown[cell]) <= delta * delta + 1e-9;
            sum += if may_be_unknown { known_bound.max(self.neutral[i]) } else { known_bound };
        });
        sum
    }

    /// Upper bound of the score over the poses with headings `k_lo..=k_hi` and translations
    /// in the pyramid block of level `level` whose low corner is `lo` (x, y indices).
    ///
    /// At one heading, lattice translations shift every local cell by whole voxels, so the
    /// smallest distance a cell reaches over the block of translations is one pyramid lookup
    /// at its voxel for the block's low corner: the bound is the sum of the per-cell maxima,
    /// the tightest bound that treats cells separately. Over several headings each cell's
    /// distance is reduced by its largest displacement from the centre heading (the chord
    /// swept at its radius plus the rounding of both poses to voxels), as in paper 000's
    /// `max(D_i^c - Delta_C, 0)` with `D_i^c` the block's minimum. A cell scores at least its
    /// neutral score when some pose of the box can put it over unknown ground or off the grid.
    ///
    /// Each cell starts from its bound for the parent box (`parent`, rounded up to f32; the
    /// trivial bounds without one), which holds for every sub-box, and only the cells of the
    /// level's [`CellPlan`] are looked up, in its order (or, at [`NEIGHBOUR_HINT_LEVELS`], in
    /// the order of the decreases the same block brought at a neighbouring heading, whose
    /// cells land within a voxel of where they land here). The per-cell bounds that tightened
    /// are pushed to `changes`; the partial sum is a bound too, so the box is dropped as soon as
    /// it falls to `threshold`.
    #[allow(clippy::too_many_arguments)]
    fn bound_block(
        &mut self,
        lo: [i32; 3],
        level: u32,
        k_lo: i32,
        k_hi: i32,
        threshold: f64,
        parent: Inherited<'_>,
        changes: &mut Vec<(u32, f64)>,
    ) -> f64 {
        let v = self.voxels;
        let capped = self.exact[v.cap as usize];
        let n = self.cells.len();
        let mut sum = parent.sum;
        if level as usize > v.pyramid.len() {
            // No pyramid level this coarse: only the parent's bound.
            return sum;
        }
        if self.plans.is_empty() {
            self.build_plans();
        }
        let mut plan = std::mem::take(&mut self.plans[level as usize]);
        if plan.order.len() != n {
            // Each level's plan is built when the search first reaches the level.
            plan = self.build_plan(level as usize);
        }
        if plan.since_sort >= RESORT_EVERY * n {
            plan.sort();
        }
        let k_center = k_lo + (k_hi - k_lo) / 2;
        let cached = self.rotated_cells(k_center);
        let hinted = k_lo == k_hi && NEIGHBOUR_HINT_LEVELS.contains(&level);
        // The hint's cells that were worth their lookup at the neighbouring heading, in the
        // order it looked them up (by tiers of expected decrease, index order within a tier;
        // sorting them by their decrease there cost more time than its earlier exits saved),
        // then the plan's cells the hint did not look up (the others were not worth it there).
        let mut tightened: Vec<(u32, f32)> = Vec::new();
        self.hint_generation = self.hint_generation.wrapping_add(1);
        let generation = self.hint_generation;
        let mut use_hint = false;
        if hinted {
            let key = |k: i32| (level, lo[0], lo[1], k);
            if let Some(hint) =
                self.hints.get(&key(k_center - 1)).or_else(|| self.hints.get(&key(k_center + 1)))
            {
                use_hint = true;
                tightened.extend(hint.iter().copied().filter(|&(_, decrease)| decrease >= plan.min_rate));
                for &(i, _) in hint {
                    self.in_hint[i as usize] = generation;
                }
            }
        }
        let in_hint = &self.in_hint;
        let planned = plan.order[..plan.active].iter().copied();
        let cells = tightened
            .iter()
            .map(|&(i, _)| i as usize)
            .chain(planned.filter(|&i| !use_hint || in_hint[i] != generation));
        let mut record = Vec::new();
        let (wx, wy) = block_size(level);
        let distances: &[u8] = if level == 0 { &[] } else { &v.pyramid[level as usize - 1] };
        let distance_at = |index: usize| -> usize {
            if level == 0 { usize::from(v.squared[index].min(255)) } else { usize::from(distances[index]) }
        };
        let unknown = &v.unknown_pyramid[level as usize];
        let k_extent = (k_center - k_lo).max(k_hi - k_center);
        let (rotation_fixed, rotation_per_radius) = self.rotation_bound(k_extent);
        let (cols, rows) = (v.cols as i64, v.rows as i64);
        let half_diagonal = 0.5 * (wx as f64).hypot(wy as f64);
        let place = self.placement([lo[0], lo[1], k_center]);
        let rotated =
            cached.then(|| self.rotated[(k_center + self.lattice.half[2]) as usize].as_deref()).flatten();
        let shift = [i64::from(lo[0]), i64::from(lo[1])];
        let mut looked = 0u64;
        for i in cells {
            if sum <= threshold {
                break;
            }
            let before = f64::from(parent.values[i]);
            let c = &self.hot[i];
            if before <= capped.min(c.neutral) {
                // Already as low as any pose can make it.
                continue;
            }
            looked += 1;
            plan.tally[i][0] += 1.0;
            let (col, row) = match rotated {
                Some(r) => (i64::from(r[i][0]) + shift[0], i64::from(r[i][1]) + shift[1]),
                None => place.voxel(c.x, c.y),
            };
            let inside = col >= 0 && row >= 0 && col + wx as i64 <= cols && row + wy as i64 <= rows;
            if !inside {
                continue;
            }
            let cell = row as usize * v.cols + col as usize;
            let (known_bound, may_be_unknown) = if k_extent == 0 {
                let known_bound = match c.layer {
                    Some(layer) => self.exact[distance_at(layer + cell).min(v.cap as usize)],
                    None => capped,
                };
                (known_bound, unknown[cell])
            } else {
                // A hair of slack keeps the bound above the exact score despite rounding.
                let delta = rotation_fixed + rotation_per_radius * c.radius + 1e-9;
                let known_bound = match c.layer {
                    Some(layer) => {
                        let d = self.roots[distance_at(layer + cell).min(v.cap as usize)] - delta;
                        let step = (d.max(0.0) * BOUND_STEPS_PER_CELL) as usize;
                        self.bound[step.min(self.bound.len() - 1)]
                    }
                    None => capped,
                };
                // Unknown ground within reach of the block's centre column, which is
                // inside the grid; leaving the grid means crossing its unknown padding.
                let centre = (row as usize + wy / 2) * v.cols + col as usize + wx / 2;
                let reach = half_diagonal + delta + 1.0;
                (known_bound, unknown[cell] || f64::from(v.to_unknown[centre]) <= reach * reach)
            };
            let bound = if may_be_unknown { known_bound.max(c.neutral) } else { known_bound };
            plan.tally[i][1] += (before - bound).max(0.0) as f32;
            if hinted {
                record.push((i as u32, (c.trivial - bound).max(0.0) as f32));
            }
            if bound < before {
                changes.push((i as u32, bound));
                sum -= before - bound;
            }
        }
        self.lookups += looked;
        plan.since_sort += looked as usize;
        self.plans[level as usize] = plan;
        if hinted {
            if self.hint_entries + record.len() > MAX_HINT_ENTRIES {
                // Hints only guide the order: forgetting them keeps the memory bounded on
                // large local maps.
                self.hints.clear();
                self.hint_entries = 0;
            }
            self.hint_entries += record.len();
            if let Some(old) = self.hints.insert((level, lo[0], lo[1], k_center), record) {
                self.hint_entries -= old.len();
            }
        }
        sum
    }

    /// Rotates the local cells to heading `k` once (see `Scorer::rotated`); whether they are
    /// cached.
    fn rotated_cells(&mut self, k: i32) -> bool {
        let headings = 2 * self.lattice.half[2] as usize + 1;
        if self.rotated.len() != headings {
            self.rotated = vec![None; headings];
            self.rotated_entries = 0;
        }
        let slot = (k + self.lattice.half[2]) as usize;
        if self.rotated[slot].is_some() {
            return true;
        }
        let n = self.cells.len();
        if self.rotated_entries + n > MAX_ROTATED {
            return false;
        }
        let place = self.placement([0, 0, k]);
        let fits = |v: i64| i32::try_from(v).ok();
        let cells: Option<Vec<[i32; 2]>> = self
            .hot
            .iter()
            .map(|c| {
                let (col, row) = place.voxel(c.x, c.y);
                Some([fits(col)?, fits(row)?])
            })
            .collect();
        let Some(cells) = cells else { return false };
        self.rotated_entries += n;
        self.rotated[slot] = Some(cells);
        true
    }

    /// Bound of one box of the search tree from its parent's per-cell bounds, pushing the
    /// cells it tightened to `changes`; a single pose's exact score when it may beat
    /// `threshold`.
    fn bound_search_cell(
        &mut self,
        cell: &PoseCell,
        threshold: f64,
        parent: Inherited<'_>,
        changes: &mut Vec<(u32, f64)>,
    ) -> f64 {
        if cell.lo == cell.hi {
            if self.bound_kind == BoundKind::MinPool {
                // Level 0 of the pyramid is the distance transform itself: the pose's partial
                // sum often shows it cannot win before every cell is looked up.
                let partial =
                    self.bound_block(cell.lo, 0, cell.lo[2], cell.hi[2], threshold, parent, changes);
                if partial <= threshold {
                    return partial;
                }
            }
            return self.score_pose(cell.lo);
        }
        match self.bound_kind {
            BoundKind::Distance => self.bound_distance(cell.lo, cell.hi),
            BoundKind::MinPool => {
                self.bound_block(cell.lo, cell.level, cell.lo[2], cell.hi[2], threshold, parent, changes)
            }
        }
    }

    /// Branch-and-bound search for the best lattice pose scoring above `threshold`, skipping
    /// poses inside any of the `exclude` boxes (inclusive index bounds), starting from the
    /// `seed` pose if given.
    ///
    /// The translation part of every box is a pyramid block (2^a x 2^a or 2^a x 2^(a+1)
    /// lattice steps, clipped to the window), so that [`BoundKind::MinPool`] bounds it with
    /// one lookup per local cell; boxes are split in two along heading or along the block's
    /// longer side as the [`SplitRule`] says. Each box taken from the queue (best bound
    /// first) starts a dive: its better child (ties towards the window's centre, the prior
    /// pose) is split next and the other queued, down to a single pose, so that a good score
    /// to prune against is found after a few dozen boxes rather than after the best-first
    /// order has bounded every coarse box (measured on 30 of the `rovernav eval localization`
    /// cases with inherited bounds: 24.5 lattice poses per evaluation without dives, 31.0 with
    /// them, 31.6 when the optimum is known in advance). Children start from their parent's
    /// per-cell bounds. The work is counted in distance-transform lookups divided by the
    /// number of local cells (a pose scored costs one; a box bound costs the lookups it made
    /// before it was decided), and the boxes bounded are counted separately.
    pub fn branch_and_bound(
        &mut self,
        threshold: f64,
        seed: Option<[i32; 3]>,
        exclude: &[([i32; 3], [i32; 3])],
    ) -> SearchOutcome {
        let half = self.lattice.half;
        let n = self.cells.len();
        let mut out =
            SearchOutcome { best: None, score: threshold, evaluations: 0, boxes: 0, poses_tested: 0 };
        let lookups_before = self.lookups;
        // A bound sums n per-cell terms in another order than the exact score: each addition
        // may round by an ulp of the running sum, at most n times the largest term.
        let largest = self.exact.iter().chain(&self.neutral).fold(0.0f64, |m, v| m.max(v.abs()));
        let margin = PRUNE_MARGIN.max(4.0 * f64::EPSILON * (n * n) as f64 * largest);
        let inside = |p: [i32; 3], b: &([i32; 3], [i32; 3])| (0..3).all(|a| p[a] >= b.0[a] && p[a] <= b.1[a]);
        if let Some(p) = seed.filter(|p| !exclude.iter().any(|b| inside(*p, b))) {
            out.offer(p, self.score_pose(p));
        }
        let root_lo = [-half[0], -half[1], -half[2]];
        let span = (2 * half[0].max(half[1]) + 1) as u32;
        let root_level = 2 * span.next_power_of_two().trailing_zeros();
        let mut heap: BinaryHeap<PoseCell> = BinaryHeap::new();
        // Per-cell bounds of the queued boxes, `n` per slot, and the free slots.
        let mut store = match self.spare_store.take() {
            Some(mut store) => {
                store.reset(&self.trivial);
                store
            }
            None => BoundStore::new(&self.trivial),
        };
        let mut changes = Vec::new();
        let mut next: Option<PoseCell> = None;
        if root_lo != half {
            // A bound of +inf: the root is split without a lookup (its bound would not prune).
            next = Some(PoseCell {
                lo: root_lo,
                hi: half,
                level: root_level,
                bound: f64::INFINITY,
                slot: ROOT_SLOT,
            });
        } else if Some(root_lo) != seed && !exclude.iter().any(|b| inside(root_lo, b)) {
            // A window of one pose.
            out.offer(root_lo, self.score_pose(root_lo));
        }
        loop {
            let cell = match next.take() {
                Some(cell) if cell.bound > out.score - margin => cell,
                Some(cell) => {
                    store.release(cell.slot);
                    continue;
                }
                None => match heap.pop() {
                    Some(cell) if cell.bound > out.score - margin => cell,
                    _ => break,
                },
            };
            let mut kept: [Option<PoseCell>; 2] = [None, None];
            for (entry, child) in kept.iter_mut().zip(self.split_cell(&cell)) {
                let Some(child) = child else { continue };
                if exclude.iter().any(|b| (0..3).all(|a| child.lo[a] >= b.0[a] && child.hi[a] <= b.1[a])) {
                    continue;
                }
                let single = child.lo == child.hi;
                if single && Some(child.lo) == seed {
                    continue;
                }
                changes.clear();
                let bound =
                    self.bound_search_cell(&child, out.score - margin, store.get(cell.slot), &mut changes);
                out.boxes += 1;
                out.poses_tested += u64::from(single);
                if single {
                    // An exact score (or a bound that cannot win): strictly better to win,
                    // as in the exhaustive search.
                    if bound > out.score {
                        out.score = bound;
                        out.best = Some(child.lo);
                    }
                } else if bound > out.score - margin {
                    let slot = match self.bound_kind {
                        BoundKind::MinPool => store.keep(cell.slot, &changes),
                        BoundKind::Distance => NO_SLOT,
                    };
                    *entry = Some(PoseCell { bound, slot, ..child });
                }
            }
            store.release(cell.slot);
            // Dive into the better child; queue the other.
            let [a, b] = kept;
            let (dive, other) = match (a, b) {
                (Some(a), Some(b)) => {
                    let offset = |c: &PoseCell| (0..3).map(|x| (c.lo[x] + c.hi[x]).abs()).sum::<i32>();
                    let a_first = a.bound > b.bound || (a.bound == b.bound && offset(&a) <= offset(&b));
                    if a_first { (Some(a), Some(b)) } else { (Some(b), Some(a)) }
                }
                (a, b) => (a.or(b), None),
            };
            next = dive;
            if let Some(other) = other {
                heap.push(other);
            }
        }
        self.spare_store = Some(store);
        out.evaluations = (self.lookups - lookups_before).div_ceil(n.max(1) as u64);
        out
    }

    /// The two halves of a box (`None` for a half outside the window).
    fn split_cell(&self, cell: &PoseCell) -> [Option<PoseCell>; 2] {
        let (lo, hi) = (cell.lo, cell.hi);
        let heading_span = hi[2] - lo[2];
        let (bx, by) = block_size(cell.level);
        let block_side = bx.max(by) as i32;
        // Heading steps move the farthest local cell by about one grid cell each, like
        // translation steps, so the extents compare directly.
        let split_heading = heading_span > 0
            && match self.split {
                SplitRule::HeadingFirst => true,
                SplitRule::LongestAxis => heading_span + 1 >= block_side || cell.level == 0,
            };
        let (axis, cut) = if split_heading {
            (2, lo[2] + heading_span / 2 + 1)
        } else {
            let axis = if by > bx { 1 } else { 0 };
            (axis, lo[axis] + level_shift(cell.level) as i32)
        };
        let level = if split_heading { cell.level } else { cell.level - 1 };
        let mut first = PoseCell { level, ..*cell };
        first.hi[axis] = hi[axis].min(cut - 1);
        let mut second = PoseCell { level, ..*cell };
        second.lo[axis] = cut;
        [Some(first), (cut <= hi[axis]).then_some(second)]
    }

    /// Scores every lattice pose (the reference the branch and bound must agree with).
    pub fn exhaustive(&mut self) -> SearchOutcome {
        let half = self.lattice.half;
        let mut out =
            SearchOutcome { best: None, score: f64::NEG_INFINITY, evaluations: 0, boxes: 0, poses_tested: 0 };
        for k in -half[2]..=half[2] {
            for j in -half[1]..=half[1] {
                for i in -half[0]..=half[0] {
                    let sum = self.score_pose([i, j, k]);
                    out.evaluations += 1;
                    out.boxes += 1;
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
    ///
    /// Axes the window does not search (half-width 0, e.g. a heading known from other sensors,
    /// as paper 002 section 3 assumes) are neither fitted nor moved: their offset and variance
    /// are 0, so the estimate stays on the given value.
    pub fn fit_peak(
        &mut self,
        best: [i32; 3],
        radius: i32,
        temperature: f64,
    ) -> Option<([f64; 3], Matrix3<f64>)> {
        let active: Vec<usize> = (0..3).filter(|&a| self.lattice.half[a] > 0).collect();
        let n = active.len();
        if n == 0 {
            return Some(([0.0; 3], Matrix3::zeros()));
        }
        // Features: 1, the active coordinates, their squares and their pairwise products.
        let pairs: Vec<(usize, usize)> = (0..n).flat_map(|i| (i + 1..n).map(move |j| (i, j))).collect();
        let m = 1 + 2 * n + pairs.len();
        let mut ata = DMatrix::<f64>::zeros(m, m);
        let mut atb = DVector::<f64>::zeros(m);
        let center = self.score_pose(best);
        let span = |a: usize| if self.lattice.half[a] > 0 { radius } else { 0 };
        let (s0, s1, s2) = (span(0), span(1), span(2));
        for dk in -s2..=s2 {
            for dj in -s1..=s1 {
                for di in -s0..=s0 {
                    let s = if (di, dj, dk) == (0, 0, 0) {
                        center
                    } else {
                        self.score_pose([best[0] + di, best[1] + dj, best[2] + dk])
                    } - center;
                    let d = [f64::from(di), f64::from(dj), f64::from(dk)];
                    let u: Vec<f64> = active.iter().map(|&a| d[a]).collect();
                    let mut f = DVector::<f64>::zeros(m);
                    f[0] = 1.0;
                    for i in 0..n {
                        f[1 + i] = u[i];
                        f[1 + n + i] = u[i] * u[i];
                    }
                    for (k, &(i, j)) in pairs.iter().enumerate() {
                        f[1 + 2 * n + k] = u[i] * u[j];
                    }
                    ata += &f * f.transpose();
                    atb += &f * s;
                }
            }
        }
        let beta = ata.lu().solve(&atb)?;
        let g = DVector::from_iterator(n, (0..n).map(|i| beta[1 + i]));
        let mut h = DMatrix::<f64>::zeros(n, n);
        for i in 0..n {
            h[(i, i)] = 2.0 * beta[1 + n + i];
        }
        for (k, &(i, j)) in pairs.iter().enumerate() {
            h[(i, j)] = beta[1 + 2 * n + k];
            h[(j, i)] = beta[1 + 2 * n + k];
        }
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
        let clamped = eigen.eigenvalues.map(|e| 1.0 / e.max(floor));
        let inv = &eigen.eigenvectors * DMatrix::from_diagonal(&clamped) * eigen.eigenvectors.transpose();
        let step = &inv * g;
        let mut offset = [0.0; 3];
        let mut covariance = Matrix3::zeros();
        for (i, &a) in active.iter().enumerate() {
            offset[a] = step[i].clamp(-1.0, 1.0);
            for (j, &b) in active.iter().enumerate() {
                covariance[(a, b)] = inv[(i, j)] * temperature;
            }
        }
        Some((offset, covariance))
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
    let peak = find_peak(scorer, analysis, exhaustive);
    finish_match(scorer, analysis, &peak)
}

/// The main search and the peak fit of a match, before its failure search.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Peak {
    /// The main search's outcome.
    pub main: SearchOutcome,
    /// Lattice index of the best pose.
    pub best: [i32; 3],
    /// The lattice searched.
    pub lattice: PoseLattice,
    /// Subpixel offset of the fitted peak (lattice units).
    pub offset: [f64; 3],
    /// Covariance of the fit (lattice units).
    pub cov_lattice: Matrix3<f64>,
    /// Whether the fit was a proper maximum.
    pub peak_fit_ok: bool,
}

impl Peak {
    /// The estimated (subpixel) pose.
    pub fn pose(&self) -> Pose2 {
        self.lattice.pose([0, 1, 2].map(|a| f64::from(self.best[a]) + self.offset[a]))
    }
}

/// Runs the main search (branch and bound from the dead-reckoned pose, or exhaustive) and fits
/// the peak; [`finish_match`] adds the failure search.
pub fn find_peak<S: DistanceScore>(
    scorer: &mut Scorer<'_, S>,
    analysis: &PeakAnalysis,
    exhaustive: bool,
) -> Peak {
    let main = if exhaustive {
        scorer.exhaustive()
    } else {
        scorer.branch_and_bound(f64::NEG_INFINITY, Some([0, 0, 0]), &[])
    };
    let best = main.best.unwrap_or([0, 0, 0]);
    let lattice = scorer.lattice();
    let temperature = analysis.temperature.max(1e-12);
    let fit = scorer.fit_peak(best, analysis.fit_radius, temperature);
    let (offset, cov_lattice, peak_fit_ok) = match fit {
        Some((o, c)) => (o, c, true),
        None => {
            // No proper peak: report the whole window as the uncertainty.
            let w = [0, 1, 2].map(|a| f64::from(lattice.half[a]).powi(2));
            ([0.0; 3], Matrix3::from_diagonal(&Vector3::new(w[0], w[1], w[2])), false)
        }
    };
    Peak { main, best, lattice, offset, cov_lattice, peak_fit_ok }
}

/// Completes a match from its peak: the covariance, and the failure search for competing
/// peaks.
pub fn finish_match<S: DistanceScore>(
    scorer: &mut Scorer<'_, S>,
    analysis: &PeakAnalysis,
    peak: &Peak,
) -> MatchDetails {
    let Peak { main, best, lattice, cov_lattice, peak_fit_ok, .. } = *peak;
    let temperature = analysis.temperature.max(1e-12);
    let steps = [lattice.step, lattice.step, lattice.yaw_step];
    let mut covariance = [[0.0; 3]; 3];
    for (r, row) in covariance.iter_mut().enumerate() {
        for (c, v) in row.iter_mut().enumerate() {
            *v = cov_lattice[(r, c)] * steps[r] * steps[c];
        }
        // The lattice itself cannot resolve better than a uniform error over one step (an
        // axis the window fixes is not estimated at all).
        if lattice.half[r] > 0 {
            row[r] += steps[r] * steps[r] / 12.0;
        }
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
        let last = peaks[peaks.len() - 1];
        excluded.push(([0, 1, 2].map(|a| last[a] - exclusion[a]), [0, 1, 2].map(|a| last[a] + exclusion[a])));
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
    MatchDetails {
        result: MatchResult {
            pose: peak.pose(),
            covariance,
            log_likelihood: main.score,
            failure_probability,
            poses_evaluated: main.evaluations,
        },
        best_index: best,
        lattice,
        runner_up,
        poses_tested: main.poses_tested,
        boxes: main.boxes,
        failure_search_evaluations,
        local_cells: scorer.cells.len(),
        peak_fit_ok,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A mixture-like score: the shape of the ML matcher's (see `ml::MixtureLikelihood`).
    struct Mixture;

    impl DistanceScore for Mixture {
        fn score(&self, d: f64) -> f64 {
            let z = d / 0.05;
            (0.5 * (-0.5 * z * z).exp() + 0.025).ln()
        }
    }

    /// Rough ground with rocks, 5 cm cells.
    fn terrain(x: f64, y: f64) -> f64 {
        let mut h = 0.02 * (7.0 * x).sin() * (5.0 * y).cos() + 0.01 * (23.0 * x + 17.0 * y).sin();
        for (cx, cy, r) in [(0.4, 0.3, 0.15), (-0.6, 0.8, 0.2), (1.1, -0.5, 0.12), (0.2, -1.0, 0.25)] {
            let d2 = (x - cx) * (x - cx) + (y - cy) * (y - cy);
            h += 2.0 * r * (-d2 / (r * r)).exp();
        }
        h
    }

    /// Boxes bounded from their parent's per-cell bounds (rounded up to f32), with the cell
    /// subsets and orders the search learnt and the neighbouring-heading hints, early
    /// termination included, never undercut any pose's exact score in the box, cell by cell
    /// and in sum: the property that keeps the branch and bound exact. Checked against every
    /// pose of random boxes of one to three headings, after a search has trained the plans.
    #[test]
    fn inherited_and_learnt_bounds_never_undercut_exact_scores() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let r = 0.05;
        let mut global = Grid2::filled(
            rovernav_core::GridGeometry { cols: 80, rows: 80, resolution: r, origin_x: -2.0, origin_y: -2.0 },
            f32::NAN,
        );
        for row in 0..80 {
            for col in 0..80 {
                let (x, y) = global.geometry.center(col, row);
                // An unknown patch, so that neutral scores enter the bounds.
                if !(x > 0.9 && y > 0.9) {
                    *global.get_mut(col, row) = (terrain(x, y) + rng.random_range(-0.005..0.005)) as f32;
                }
            }
        }
        let truth = Pose2::new(0.12, -0.08, 0.04);
        let mut local = Grid2::filled(
            rovernav_core::GridGeometry { cols: 30, rows: 40, resolution: r, origin_x: 0.0, origin_y: -1.0 },
            f32::NAN,
        );
        for row in 0..40 {
            for col in 0..30 {
                let (x, y) = local.geometry.center(col, row);
                let w = truth.transform(rovernav_core::Point2::new(x, y));
                if rng.random_bool(0.9) {
                    *local.get_mut(col, row) = (terrain(w.x, w.y) + rng.random_range(-0.01..0.01)) as f32;
                }
            }
        }
        let voxels = VoxelMap::new(&global, 5, 1.0, 12).expect("voxels");
        let cells = LocalCells::new(&local, &voxels, Some(250)).expect("cells");
        let window =
            SearchWindow { center: Pose2::new(0.0, 0.0, 0.0), half_x: 0.6, half_y: 0.6, half_yaw: 0.08 };
        let score = Mixture;
        let mut scorer =
            Scorer::new(&voxels, &cells, &score, &window, BoundKind::MinPool, SplitRule::HeadingFirst, 0.05);
        scorer.use_background_neutral(&[3, 6]);
        scorer.branch_and_bound(f64::NEG_INFINITY, Some([0, 0, 0]), &[]);
        let half = scorer.lattice().half;
        let n = cells.len();
        let root = BoundStore::new(&scorer.trivial);
        let mut changes = Vec::new();
        for trial in 0..60 {
            let level = rng.random_range(0..6u32);
            let headings = rng.random_range(1..4);
            let k_lo = rng.random_range(-half[2]..=half[2] - headings + 1);
            let k_hi = k_lo + headings - 1;
            let lo = [rng.random_range(-half[0]..=half[0]), rng.random_range(-half[1]..=half[1]), k_lo];
            // The parent: the next level's block from the same corner, up to one more heading
            // on each side, tightened from the trivial bounds and kept as the search keeps it.
            let (pk_lo, pk_hi) = ((k_lo - rng.random_range(0..2)).max(-half[2]), (k_hi + 1).min(half[2]));
            changes.clear();
            scorer.bound_block(
                lo,
                level + 1,
                pk_lo,
                pk_hi,
                f64::NEG_INFINITY,
                root.get(ROOT_SLOT),
                &mut changes,
            );
            let mut store = BoundStore::new(&scorer.trivial);
            let slot = store.keep(ROOT_SLOT, &changes);
            let mut exact = vec![0.0; n];
            let mut best = f64::NEG_INFINITY;
            let (wx, wy) = block_size(level);
            let mut poses = Vec::new();
            for k in k_lo..=k_hi {
                for j in lo[1]..lo[1] + wy as i32 {
                    for i in lo[0]..lo[0] + wx as i32 {
                        poses.push([i, j, k]);
                    }
                }
            }
            let mut cell_best = vec![f64::NEG_INFINITY; n];
            for &p in &poses {
                scorer.for_each_column(p, |c, column| exact[c] = scorer.exact_at(c, column));
                for (b, e) in cell_best.iter_mut().zip(&exact) {
                    *b = b.max(*e);
                }
                best = best.max(exact.iter().sum());
            }
            // Sometimes a threshold near the best, so that the bound stops early.
            let threshold =
                if trial % 2 == 0 { f64::NEG_INFINITY } else { best + rng.random_range(-2.0..2.0) };
            changes.clear();
            let bound = scorer.bound_block(lo, level, k_lo, k_hi, threshold, store.get(slot), &mut changes);
            let mut values: Vec<f64> = store.get(slot).values.iter().map(|&v| f64::from(v)).collect();
            for &(c, b) in &changes {
                values[c as usize] = b;
            }
            assert!(
                bound >= best - 1e-9,
                "trial {trial}: level {level} box {lo:?}..{k_hi}: {bound} < {best}"
            );
            for c in 0..n {
                assert!(
                    values[c] >= cell_best[c] - 1e-9,
                    "trial {trial}: cell {c}: {} < {}",
                    values[c],
                    cell_best[c]
                );
            }
        }
    }

    #[test]
    fn bounds_kept_as_f32_are_rounded_up() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for _ in 0..10_000 {
            let v: f64 = rng.random_range(-1e3..1e3);
            let f = round_up_f32(v);
            assert!(f64::from(f) >= v && f64::from(f.next_down()) < v, "{v} -> {f}");
        }
    }

    #[test]
    fn pyramid_levels_are_block_minima_and_unknown_flags() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let (cols, rows, layers) = (13, 11, 3);
        let squared: Vec<u16> = (0..cols * rows * layers).map(|_| rng.random_range(0..300)).collect();
        let known: Vec<bool> = (0..cols * rows).map(|_| rng.random_bool(0.9)).collect();
        let levels = 7;
        let pyramid = min_pyramid(&squared, cols, rows, layers, levels);
        let unknown = unknown_pyramid(&known, cols, rows, levels);
        for t in 0..=levels as u32 {
            let (wx, wy) = block_size(t);
            for z in 0..layers {
                for r in 0..rows {
                    for c in 0..cols {
                        // Brute force over the block, clipped to the grid.
                        let mut min = u16::MAX;
                        let mut any_unknown = c + wx > cols || r + wy > rows;
                        for rr in r..(r + wy).min(rows) {
                            for cc in c..(c + wx).min(cols) {
                                min = min.min(squared[(z * rows + rr) * cols + cc]);
                                any_unknown |= !known[rr * cols + cc];
                            }
                        }
                        let i = (z * rows + r) * cols + c;
                        let got =
                            if t == 0 { squared[i].min(255) } else { u16::from(pyramid[t as usize - 1][i]) };
                        assert_eq!(got, min.min(255), "level {t} at ({c}, {r}, {z})");
                        if z == 0 {
                            assert_eq!(
                                unknown[t as usize][r * cols + c],
                                any_unknown,
                                "level {t} at ({c}, {r})"
                            );
                        }
                    }
                }
            }
        }
    }
}
