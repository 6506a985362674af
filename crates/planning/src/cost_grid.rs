//! The planners' cost grid: traversal cost per unit length per cell, plus a sensed flag.
//!
//! Following MRPTA (paper 004, section 3.5) the planner treats cells that have not been sensed
//! as neutral terrain but keeps them tagged, so the segment driver only executes the sensed part
//! of a path. Costs are `>= 1` (1 = the best terrain, so Euclidean distance is an admissible
//! heuristic) and `f32::INFINITY` marks an obstacle.
//!
//! Mappings from the map layers' scales:
//! - occupancy: free -> 1, occupied -> obstacle.
//! - MRPTA traversability `t` in 1..=14 (paper 004 section 3.3: higher is better, 7 neutral,
//!   <= 2 not traversable): `cost = 15 - t`, so 14 -> 1, neutral 7 -> 8, 3 -> 12, `t <= 2` ->
//!   obstacle; `t = 0` (no data) -> the neutral cost 8, tagged unsensed; values above 14 are
//!   clamped to 14. Each grade below the best adds one unit of cost.
//! - GESTALT goodness `g` in 0..=1 (paper 003 section 2: high goodness = traversable, Field D*
//!   wants low cost): `cost = 1 + 14 (1 - g)`, the same scale as traversability with `t = 14 g`
//!   (1 -> 1, neutral 0.5 -> 8); `g <= 0` -> obstacle; NaN -> neutral 8, tagged unsensed; values
//!   above 1 are clamped to 1.

use crate::Cell;
use rovernav_core::{Grid2, GridGeometry, Point2};

/// The cost of neutral (flat, or not yet sensed) terrain on both map scales.
pub const NEUTRAL_COST: f32 = 8.0;
/// The traversability grade MRPTA calls neutral.
pub const NEUTRAL_TRAVERSABILITY: u8 = 7;
/// The highest (best) traversability grade.
pub const MAX_TRAVERSABILITY: u8 = 14;
/// Grades at or below this are not traversable.
pub const MAX_BLOCKED_TRAVERSABILITY: u8 = 2;

/// Invalid cost grid input.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CostGridError {
    /// The value vector does not have rows x cols entries.
    #[error("cost grid {rows}x{cols} needs {} values, got {got}", rows * cols)]
    WrongLength {
        /// Rows.
        rows: usize,
        /// Columns.
        cols: usize,
        /// Values given.
        got: usize,
    },
    /// A cost below 1 or NaN.
    #[error("cell (row {}, col {}) has invalid cost {cost} (costs are >= 1 or infinite)", cell.row, cell.col)]
    InvalidCost {
        /// The cell.
        cell: Cell,
        /// The cost given.
        cost: f32,
    },
    /// A cell outside the grid.
    #[error("cell (row {}, col {}) is outside the {rows}x{cols} grid", cell.row, cell.col)]
    OutOfBounds {
        /// The cell.
        cell: Cell,
        /// Rows.
        rows: usize,
        /// Columns.
        cols: usize,
    },
}

/// One cell's new cost (and sensed flag), for incremental planners.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CellChange {
    /// The cell.
    pub cell: Cell,
    /// New cost per unit length (>= 1, or infinity for an obstacle).
    pub cost: f32,
}

/// Per-cell traversal cost per unit length (row-major) with a sensed flag per cell.
#[derive(Clone, Debug, PartialEq)]
pub struct CostGrid {
    rows: usize,
    cols: usize,
    cost: Vec<f32>,
    sensed: Vec<bool>,
    geometry: GridGeometry,
}

/// Whether a cost is acceptable: finite and >= 1, or +infinity.
fn valid_cost(c: f32) -> bool {
    c >= 1.0
}

/// Traversability grade -> (cost, sensed). See the module doc for the mapping.
pub fn traversability_cost(t: u8) -> (f32, bool) {
    match t {
        0 => (NEUTRAL_COST, false),
        t if t <= MAX_BLOCKED_TRAVERSABILITY => (f32::INFINITY, true),
        t => ((15 - t.min(MAX_TRAVERSABILITY)) as f32, true),
    }
}

/// Goodness in 0..=1 -> (cost, sensed). See the module doc for the mapping.
pub fn goodness_cost(g: f32) -> (f32, bool) {
    if g.is_nan() {
        (NEUTRAL_COST, false)
    } else if g <= 0.0 {
        (f32::INFINITY, true)
    } else {
        (1.0 + 14.0 * (1.0 - g.min(1.0)), true)
    }
}

impl CostGrid {
    /// A grid with every cell at one cost, all sensed, at 1 m resolution with origin (0, 0).
    pub fn uniform(rows: usize, cols: usize, cost: f32) -> Result<Self, CostGridError> {
        Self::from_costs(rows, cols, vec![cost; rows * cols])
    }

    /// A grid from row-major costs (all sensed, 1 m cells, origin (0, 0)).
    pub fn from_costs(rows: usize, cols: usize, cost: Vec<f32>) -> Result<Self, CostGridError> {
        if cost.len() != rows * cols {
            return Err(CostGridError::WrongLength { rows, cols, got: cost.len() });
        }
        if let Some(i) = cost.iter().position(|&c| !valid_cost(c)) {
            return Err(CostGridError::InvalidCost { cell: Cell::new(i / cols, i % cols), cost: cost[i] });
        }
        Ok(Self {
            rows,
            cols,
            sensed: vec![true; cost.len()],
            cost,
            geometry: GridGeometry { cols, rows, resolution: 1.0, origin_x: 0.0, origin_y: 0.0 },
        })
    }

    /// A grid from row-major blocked flags: free cells cost 1, blocked ones are obstacles.
    pub fn from_blocked(rows: usize, cols: usize, blocked: &[bool]) -> Result<Self, CostGridError> {
        let cost = blocked.iter().map(|&b| if b { f32::INFINITY } else { 1.0 }).collect();
        Self::from_costs(rows, cols, cost)
    }

    /// A grid from an occupancy layer (`true` = occupied), keeping its geometry.
    pub fn from_occupancy(occupied: &Grid2<bool>) -> Self {
        Self::from_layer(occupied, |&o| (if o { f32::INFINITY } else { 1.0 }, true))
    }

    /// A grid from an MRPTA traversability layer (1..=14, 0 = unsensed), keeping its geometry.
    pub fn from_traversability(layer: &Grid2<u8>) -> Self {
        Self::from_layer(layer, |&t| traversability_cost(t))
    }

    /// A grid from a GESTALT goodness layer (0..=1, NaN = unknown), keeping its geometry.
    pub fn from_goodness(layer: &Grid2<f32>) -> Self {
        Self::from_layer(layer, |&g| goodness_cost(g))
    }

    fn from_layer<T>(layer: &Grid2<T>, map: impl Fn(&T) -> (f32, bool)) -> Self {
        let (cost, sensed) = layer.data.iter().map(map).unzip();
        Self { rows: layer.rows(), cols: layer.cols(), cost, sensed, geometry: layer.geometry }
    }

    /// Number of rows.
    pub fn rows(&self) -> usize {
        self.rows
    }
    /// Number of columns.
    pub fn cols(&self) -> usize {
        self.cols
    }
    /// Row-major costs.
    pub fn costs(&self) -> &[f32] {
        &self.cost
    }
    /// Row-major sensed flags.
    pub fn sensed_flags(&self) -> &[bool] {
        &self.sensed
    }
    /// The world placement (row 0 at `origin_y`; image loaders keep image rows, see [`crate::pgm`]).
    pub fn geometry(&self) -> GridGeometry {
        self.geometry
    }
    /// Sets the world placement (its rows/cols must match; others are ignored).
    pub fn set_geometry(&mut self, geometry: GridGeometry) {
        self.geometry = GridGeometry { rows: self.rows, cols: self.cols, ..geometry };
    }
    /// Whether the cell lies inside the grid.
    pub fn contains(&self, cell: Cell) -> bool {
        cell.row < self.rows && cell.col < self.cols
    }
    /// The cost of a cell (panics outside the grid, like slice indexing).
    pub fn cost(&self, cell: Cell) -> f32 {
        self.cost[cell.row * self.cols + cell.col]
    }
    /// Whether a cell is an obstacle.
    pub fn is_blocked(&self, cell: Cell) -> bool {
        self.cost(cell).is_infinite()
    }
    /// Whether a cell has been sensed.
    pub fn is_sensed(&self, cell: Cell) -> bool {
        self.sensed[cell.row * self.cols + cell.col]
    }
    /// Sets a cell's cost (>= 1 or infinity) and marks it sensed.
    pub fn set_cost(&mut self, cell: Cell, cost: f32) -> Result<(), CostGridError> {
        if !self.contains(cell) {
            return Err(CostGridError::OutOfBounds { cell, rows: self.rows, cols: self.cols });
        }
        if !valid_cost(cost) {
            return Err(CostGridError::InvalidCost { cell, cost });
        }
        let i = cell.row * self.cols + cell.col;
        self.cost[i] = cost;
        self.sensed[i] = true;
        Ok(())
    }
    /// Sets a cell's sensed flag.
    pub fn set_sensed(&mut self, cell: Cell, sensed: bool) {
        self.sensed[cell.row * self.cols + cell.col] = sensed;
    }
    /// Applies a batch of changes, stopping at the first invalid one.
    pub fn apply(&mut self, changes: &[CellChange]) -> Result<(), CostGridError> {
        changes.iter().try_for_each(|c| self.set_cost(c.cell, c.cost))
    }
    /// The cost of the cell containing a grid-unit point, infinity outside the grid.
    pub fn cost_at_point(&self, p: Point2) -> f32 {
        match Cell::containing(p) {
            Some(c) if self.contains(c) => self.cost(c),
            _ => f32::INFINITY,
        }
    }
    /// Whether the cell containing a grid-unit point is sensed (false outside).
    pub fn is_sensed_at_point(&self, p: Point2) -> bool {
        matches!(Cell::containing(p), Some(c) if self.contains(c) && self.is_sensed(c))
    }
    /// Grid units -> world coordinates.
    pub fn grid_to_world(&self, p: Point2) -> Point2 {
        let g = &self.geometry;
        Point2::new(g.origin_x + p.x * g.resolution, g.origin_y + p.y * g.resolution)
    }
    /// World coordinates -> grid units.
    pub fn world_to_grid(&self, p: Point2) -> Point2 {
        let g = &self.geometry;
        Point2::new((p.x - g.origin_x) / g.resolution, (p.y - g.origin_y) / g.resolution)
    }

    /// Cost of a polyline in grid units measured on this grid, the model Field D* uses: a piece
    /// inside a cell costs that cell's cost times its length, a piece along a cell edge the
    /// cheaper adjacent cell's. Each piece is split where it crosses grid lines.
    pub fn polyline_cost(&self, points: &[Point2]) -> f64 {
        points.windows(2).map(|w| self.segment_cost(w[0], w[1])).sum()
    }

    /// Cost of one straight piece (see [`CostGrid::polyline_cost`]).
    pub fn segment_cost(&self, a: Point2, b: Point2) -> f64 {
        let d = b.sub(a);
        let len = d.norm();
        if len == 0.0 {
            return 0.0;
        }
        // Parameters where the segment crosses vertical or horizontal grid lines.
        let mut ts = vec![0.0, 1.0];
        for (p0, dp) in [(a.x, d.x), (a.y, d.y)] {
            if dp.abs() > 1e-12 {
                let (lo, hi) = if dp > 0.0 { (p0, p0 + dp) } else { (p0 + dp, p0) };
                let mut k = lo.ceil();
                while k <= hi.floor() {
                    ts.push((k - p0) / dp);
                    k += 1.0;
                }
            }
        }
        ts.sort_by(f64::total_cmp);
        let mut total = 0.0;
        for w in ts.windows(2) {
            let piece = (w[1] - w[0]) * len;
            if piece <= 1e-12 {
                continue;
            }
            let mid = a.add(d.scale(0.5 * (w[0] + w[1])));
            total += piece * self.piece_cost(mid, d) as f64;
        }
        total
    }

    /// Cost rate at a piece's midpoint: inside a cell its cost, on a grid line (piece running
    /// along it) the cheaper of the two cells beside it.
    fn piece_cost(&self, mid: Point2, dir: Point2) -> f32 {
        const ON_LINE: f64 = 1e-9;
        let on_vertical = dir.x.abs() <= 1e-12 && (mid.x - mid.x.round()).abs() < ON_LINE;
        let on_horizontal = dir.y.abs() <= 1e-12 && (mid.y - mid.y.round()).abs() < ON_LINE;
        if on_vertical {
            let x = mid.x.round();
            let l = self.cost_at_point(Point2::new(x - 0.5, mid.y));
            let r = self.cost_at_point(Point2::new(x + 0.5, mid.y));
            l.min(r)
        } else if on_horizontal {
            let y = mid.y.round();
            let l = self.cost_at_point(Point2::new(mid.x, y - 0.5));
            let r = self.cost_at_point(Point2::new(mid.x, y + 0.5));
            l.min(r)
        } else {
            self.cost_at_point(mid)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn traversability_scale_maps_to_documented_costs() {
        assert_eq!(traversability_cost(14), (1.0, true));
        assert_eq!(traversability_cost(7), (NEUTRAL_COST, true));
        assert_eq!(traversability_cost(3), (12.0, true));
        assert!(traversability_cost(2).0.is_infinite());
        assert!(traversability_cost(1).0.is_infinite());
        assert_eq!(traversability_cost(0), (NEUTRAL_COST, false));
    }

    #[test]
    fn goodness_scale_agrees_with_traversability() {
        assert_eq!(goodness_cost(1.0), (1.0, true));
        assert_eq!(goodness_cost(0.5), (NEUTRAL_COST, true));
        assert!(goodness_cost(0.0).0.is_infinite());
        assert_eq!(goodness_cost(f32::NAN), (NEUTRAL_COST, false));
        // g = t / 14 gives the same cost as grade t.
        for t in 3..=14u8 {
            let (c, _) = goodness_cost(t as f32 / 14.0);
            assert!((c - traversability_cost(t).0).abs() < 1e-4);
        }
    }

    #[test]
    fn layer_constructors_keep_geometry_and_sensed_tags() {
        let geometry = GridGeometry { cols: 3, rows: 2, resolution: 0.15, origin_x: -1.0, origin_y: 2.0 };
        let layer = Grid2 { geometry, data: vec![0, 1, 7, 14, 3, 2] };
        let g = CostGrid::from_traversability(&layer);
        assert_eq!(g.geometry(), geometry);
        assert!(!g.is_sensed(Cell::new(0, 0)));
        assert_eq!(g.cost(Cell::new(0, 0)), NEUTRAL_COST);
        assert!(g.is_blocked(Cell::new(0, 1)));
        assert_eq!(g.cost(Cell::new(1, 0)), 1.0);
        let w = g.grid_to_world(Point2::new(1.0, 1.0));
        assert!((w.x + 0.85).abs() < 1e-12 && (w.y - 2.15).abs() < 1e-12);
    }

    #[test]
    fn invalid_costs_are_rejected() {
        assert!(CostGrid::from_costs(1, 2, vec![1.0, 0.5]).is_err());
        assert!(CostGrid::from_costs(1, 2, vec![1.0, f32::NAN]).is_err());
        assert!(CostGrid::from_costs(1, 2, vec![1.0]).is_err());
        let mut g = CostGrid::uniform(2, 2, 1.0).unwrap();
        assert!(g.set_cost(Cell::new(2, 0), 1.0).is_err());
    }

    #[test]
    fn segment_cost_splits_at_grid_lines() {
        // Row 0: costs 1, 3; row 1: 2, 4.
        let g = CostGrid::from_costs(2, 2, vec![1.0, 3.0, 2.0, 4.0]).unwrap();
        // Horizontal through the middle of row 0: half of cell 1 and half of cell 3.
        let c = g.segment_cost(Point2::new(0.5, 0.5), Point2::new(1.5, 0.5));
        assert!((c - 2.0).abs() < 1e-12);
        // Along the line y = 1 between rows 0 and 1: min(1,2) then min(3,4).
        let c = g.segment_cost(Point2::new(0.0, 1.0), Point2::new(2.0, 1.0));
        assert!((c - 4.0).abs() < 1e-12);
        // Diagonal of cell (1, 1): 4 sqrt 2.
        let c = g.segment_cost(Point2::new(1.0, 1.0), Point2::new(2.0, 2.0));
        assert!((c - 4.0 * std::f64::consts::SQRT_2).abs() < 1e-12);
    }
}
