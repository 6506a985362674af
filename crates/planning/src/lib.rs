//! rovernav planning layer: global grid planners, their cost grid, benchmark loaders and the
//! segment driver.
//!
//! - [`CostGrid`]: per-cell traversal cost per unit length with a sensed flag (MRPTA, paper 004
//!   section 3.5: unsensed cells are costed neutral but stay tagged).
//! - [`GlobalPlanner`]: the planner plugin interface, with [`planner_by_name`] as its registry:
//!   `"astar"` (octile A* on cell centres), `"astar-corners"` (octile A* on the corner-node graph
//!   of Field D*), `"dstar-lite"` (Koenig and Likhachev's D* Lite on cell centres) and
//!   `"field-dstar"` (Ferguson and Stentz's interpolated Field D* on cell corners, the planner MER
//!   flies, paper 003 section 2).
//! - [`movingai`] and [`pgm`]: parsers for the benchmark maps (text in, no file I/O).
//! - [`segment_driver`]: cuts a planned path into straight segments and in-situ rotations
//!   (paper 004 section 3.5).
//! - [`benchmark`]: the logic behind `rovernav bench`; [`baseline`]: A*'s graph as a successor
//!   function for general-purpose search libraries (the benchmarks' baseline).
//!
//! Grid coordinates: a [`Cell`] is (row, col) in the cost grid's own indexing. Continuous path
//! points are [`Point2`]s in *grid units*: `x` runs along columns and `y` along rows, cell
//! (row, col) covers `[col, col+1] x [row, row+1]` and its centre is `(col + 0.5, row + 0.5)`;
//! [`CostGrid::grid_to_world`] maps them to the world frame.

pub mod astar;
pub mod baseline;
pub mod benchmark;
pub mod cost_grid;
pub mod dstar_lite;
pub mod field_dstar;
mod heap;
mod incremental;
mod lattice;
pub mod movingai;
pub mod pgm;
pub mod segment_driver;

pub use astar::AStar;
pub use cost_grid::{CellChange, CostGrid, CostGridError};
pub use dstar_lite::DStarLite;
pub use field_dstar::FieldDStar;
use rovernav_core::Point2;
pub use segment_driver::{Segment, SegmentDriverConfig, SegmentPlan, segment_path};

/// A grid cell, (row, col) in the cost grid's indexing.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Cell {
    /// Row index.
    pub row: usize,
    /// Column index.
    pub col: usize,
}

impl Cell {
    /// Builds a cell.
    pub const fn new(row: usize, col: usize) -> Self {
        Self { row, col }
    }
    /// The cell's centre in grid units (x along columns, y along rows).
    pub fn center(self) -> Point2 {
        Point2::new(self.col as f64 + 0.5, self.row as f64 + 0.5)
    }
    /// The cell's minimum-row, minimum-column corner in grid units: the corner node Field D*
    /// starts from and aims at for this cell.
    pub fn corner(self) -> Point2 {
        Point2::new(self.col as f64, self.row as f64)
    }
    /// The cell containing a point in grid units (floor of both coordinates), if non-negative.
    pub fn containing(p: Point2) -> Option<Cell> {
        if p.x.is_finite() && p.y.is_finite() && p.x >= 0.0 && p.y >= 0.0 {
            Some(Cell::new(p.y.floor() as usize, p.x.floor() as usize))
        } else {
            None
        }
    }
}

/// Which graph a planner searches.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GraphKind {
    /// Nodes at cell centres, 8-connected (octile A*, D* Lite).
    CellCentres,
    /// Nodes at cell corners (Field D*, and A* in its corner-graph mode).
    CornerNodes,
}

impl GraphKind {
    /// The name reported by benchmarks: `"cell-centres"` or `"corner-nodes"`.
    pub fn label(self) -> &'static str {
        match self {
            GraphKind::CellCentres => "cell-centres",
            GraphKind::CornerNodes => "corner-nodes",
        }
    }
}

/// A planned path.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    /// Cost of the returned path measured on the grid: the sum of its edge costs on graph
    /// planners; for Field D*, the cost of its interpolated polyline (each piece at the cost of
    /// the cell it crosses, or of the cheaper cell beside the cell edge it runs along).
    pub cost: f64,
    /// The planner's own cost-to-goal value at the start (its g-value). Equals `cost` on graph
    /// planners; Field D*'s interpolated value is a slight overestimate of its path's cost.
    pub value: f64,
    /// The path in grid units, start first: cell centres for cell-centre planners, corners and
    /// edge crossings for corner planners.
    pub points: Vec<Point2>,
    /// Nodes expanded (popped from the open list and processed) by this call.
    pub expansions: usize,
}

/// Why a planner could not produce a path.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PlanError {
    /// No grid was given before planning.
    #[error("no cost grid set")]
    NoGrid,
    /// A cell outside the grid was named.
    #[error("{what} cell (row {}, col {}) is outside the {rows}x{cols} grid", cell.row, cell.col)]
    OutOfBounds {
        /// Which cell ("start", "goal", "changed").
        what: &'static str,
        /// The offending cell.
        cell: Cell,
        /// Grid rows.
        rows: usize,
        /// Grid columns.
        cols: usize,
    },
    /// Start and goal are not connected through finite-cost cells.
    #[error("no path from (row {}, col {}) to (row {}, col {})", start.row, start.col, goal.row, goal.col)]
    NoPath {
        /// Start cell.
        start: Cell,
        /// Goal cell.
        goal: Cell,
    },
    /// A change names a cost below 1 or NaN.
    #[error("invalid cost {cost} for cell (row {}, col {}) (costs are >= 1 or infinite)", cell.row, cell.col)]
    InvalidCost {
        /// The cell.
        cell: Cell,
        /// The cost given.
        cost: f32,
    },
    /// `replan`/`move_start` before any `plan`.
    #[error("no previous plan to update")]
    NoPreviousPlan,
}

/// A global grid planner plugin (pure interface; the registry is [`planner_by_name`]).
///
/// A planner owns a copy of its cost grid. `plan` searches from start to goal; incremental
/// planners reuse their previous search when the goal is unchanged, so the usual loop is
/// `set_grid`, `plan`, then any number of `update_cells` / `move_start` followed by `replan`.
pub trait GlobalPlanner: Send {
    /// The registry name.
    fn name(&self) -> &'static str;
    /// The graph this planner searches.
    fn graph(&self) -> GraphKind;
    /// Replaces the cost grid; the next `plan` searches from scratch.
    fn set_grid(&mut self, grid: CostGrid);
    /// The planner's current cost grid.
    fn grid(&self) -> Option<&CostGrid>;
    /// Plans from `start` to `goal` (cells; corner planners use each cell's [`Cell::corner`]).
    fn plan(&mut self, start: Cell, goal: Cell) -> Result<Plan, PlanError>;
    /// Applies a batch of cell cost changes to the planner's grid.
    fn update_cells(&mut self, changes: &[CellChange]) -> Result<(), PlanError>;
    /// Moves the start (the rover) without changing the goal.
    fn move_start(&mut self, start: Cell) -> Result<(), PlanError>;
    /// Plans again from the current start to the current goal after updates.
    fn replan(&mut self) -> Result<Plan, PlanError>;
}

/// The registered planner names.
pub const PLANNER_NAMES: [&str; 4] = ["astar", "astar-corners", "dstar-lite", "field-dstar"];

/// A fresh planner by registry name, or `None` for an unknown name.
pub fn planner_by_name(name: &str) -> Option<Box<dyn GlobalPlanner>> {
    match name {
        "astar" => Some(Box::new(AStar::new(GraphKind::CellCentres))),
        "astar-corners" => Some(Box::new(AStar::new(GraphKind::CornerNodes))),
        "dstar-lite" => Some(Box::new(DStarLite::new())),
        "field-dstar" => Some(Box::new(FieldDStar::new())),
        _ => None,
    }
}

/// Octile distance between two lattice points (axis steps 1, diagonal steps sqrt 2).
pub fn octile_distance(dr: usize, dc: usize) -> f64 {
    let (lo, hi) = if dr < dc { (dr, dc) } else { (dc, dr) };
    (hi - lo) as f64 + lo as f64 * std::f64::consts::SQRT_2
}

/// A parse error in a benchmark file, naming the file (when known) and the line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ParseError {
    /// The file's name, empty until [`ParseError::in_file`] sets it.
    pub file: String,
    /// 1-based line number, when the error belongs to one line.
    pub line: Option<usize>,
    /// What was wrong.
    pub message: String,
}

impl ParseError {
    /// An error at a line.
    pub fn at_line(line: usize, message: impl Into<String>) -> Self {
        Self { file: String::new(), line: Some(line), message: message.into() }
    }
    /// An error about the whole input.
    pub fn whole(message: impl Into<String>) -> Self {
        Self { file: String::new(), line: None, message: message.into() }
    }
    /// Names the file the error came from.
    pub fn in_file(mut self, file: impl Into<String>) -> Self {
        self.file = file.into();
        self
    }
}

impl std::fmt::Display for ParseError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match (self.file.is_empty(), self.line) {
            (false, Some(l)) => write!(f, "{} line {l}: {}", self.file, self.message),
            (false, None) => write!(f, "{}: {}", self.file, self.message),
            (true, Some(l)) => write!(f, "line {l}: {}", self.message),
            (true, None) => write!(f, "{}", self.message),
        }
    }
}

impl std::error::Error for ParseError {}
