//! Octile A* (Hart, Nilsson and Raphael 1968), the non-incremental baseline, on either graph:
//!
//! - cell centres ([`GraphKind::CellCentres`], registry name `"astar"`): 8-connected, a step
//!   costs the mean of the two cells' costs times its length (1 or sqrt 2), and a diagonal step
//!   needs both cells it passes between to be traversable (no corner cutting). With all free
//!   costs 1 this is exactly the MovingAI benchmark's metric.
//! - corner nodes ([`GraphKind::CornerNodes`], `"astar-corners"`): Ferguson and Stentz's graph
//!   under Field D* with plain 8-connected edges (a diagonal crosses one cell at its cost times
//!   sqrt 2, an axis edge runs between two cells at the cheaper one's cost); the optimum Field D*
//!   improves on. Start and goal cells map to their minimum corner ([`Cell::corner`]).
//!
//! The heuristic is the octile distance (costs are >= 1, so it is consistent); [`AStar::dijkstra`]
//! searches without it (Dijkstra's algorithm, the same search with h = 0). Search arrays are
//! flat and reused between queries; only the entries a search touched are reset.

use crate::heap::IndexedHeap;
use crate::lattice::Lattice;
use crate::{Cell, CellChange, CostGrid, GlobalPlanner, GraphKind, Plan, PlanError};

const NO_PARENT: u8 = u8::MAX;

/// Row and column steps of the lattice's 8 directions (E, NE, N, NW, W, SW, S, SE).
const STEP_RC: [(isize, isize); 8] = [(0, 1), (1, 1), (1, 0), (1, -1), (0, -1), (-1, -1), (-1, 0), (-1, 1)];

/// The A* planner.
#[derive(Clone, Debug)]
pub struct AStar {
    graph: GraphKind,
    heuristic: bool,
    grid: Option<CostGrid>,
    lat: Option<Lattice>,
    g: Vec<f64>,
    /// Expanded in this search, or not a node of the graph at all (set once per grid).
    closed: Vec<bool>,
    parent: Vec<u8>,
    touched: Vec<u32>,
    heap: IndexedHeap,
    start: Option<Cell>,
    goal: Option<Cell>,
}

impl AStar {
    /// A planner on the given graph, without a grid.
    pub fn new(graph: GraphKind) -> Self {
        Self {
            graph,
            heuristic: true,
            grid: None,
            lat: None,
            g: Vec::new(),
            closed: Vec::new(),
            parent: Vec::new(),
            touched: Vec::new(),
            heap: IndexedHeap::new(0),
            start: None,
            goal: None,
        }
    }

    /// Dijkstra's algorithm on the given graph: the same search without the heuristic (not in
    /// the registry; the benchmarks' uninformed search).
    pub fn dijkstra(graph: GraphKind) -> Self {
        Self { heuristic: false, ..Self::new(graph) }
    }

    fn check(&self, what: &'static str, cell: Cell) -> Result<(), PlanError> {
        let grid = self.grid.as_ref().ok_or(PlanError::NoGrid)?;
        if grid.contains(cell) {
            Ok(())
        } else {
            Err(PlanError::OutOfBounds { what, cell, rows: grid.rows(), cols: grid.cols() })
        }
    }

    fn search(&mut self, start: Cell, goal: Cell) -> Result<Plan, PlanError> {
        let lat = self.lat.as_ref().ok_or(PlanError::NoGrid)?;
        for &n in &self.touched {
            let n = n as usize;
            self.g[n] = f64::INFINITY;
            self.closed[n] = false;
            self.parent[n] = NO_PARENT;
        }
        self.touched.clear();
        self.heap.clear();
        let (s, t) = (lat.index(start), lat.index(goal));
        let blocked_endpoint =
            self.graph == GraphKind::CellCentres && (lat.cost[s].is_infinite() || lat.cost[t].is_infinite());
        let no_path = PlanError::NoPath { start, goal };
        if blocked_endpoint {
            return Err(no_path);
        }
        self.g[s] = 0.0;
        self.touched.push(s as u32);
        let heuristic = self.heuristic;
        let w = lat.w;
        let (tr, tc) = (t / w, t % w);
        // Octile distance to the goal from a node's padded row and column (no division).
        let h = |r: usize, c: usize| {
            if heuristic { crate::octile_distance(r.abs_diff(tr), c.abs_diff(tc)) } else { 0.0 }
        };
        self.heap.push_or_update(s, [h(s / w, s % w), 0.0]);
        let centres = self.graph == GraphKind::CellCentres;
        let mut expansions = 0;
        while let Some((_, u)) = self.heap.pop() {
            if u == t {
                break;
            }
            self.closed[u] = true;
            expansions += 1;
            let gu = self.g[u];
            let (ur, uc) = (u / w, u % w);
            let cu = lat.cost[u] as f64;
            for (k, &(dr, dc)) in STEP_RC.iter().enumerate() {
                let v = lat.step(u, k);
                if self.closed[v] {
                    continue;
                }
                // The cell-centre edge written out (as `Lattice::edge`, same arithmetic).
                let e = if centres {
                    let cv = lat.cost[v] as f64;
                    if k % 2 == 0 {
                        0.5 * (cu + cv)
                    } else if lat.cost[lat.step(u, k - 1)].is_infinite()
                        || lat.cost[lat.step(u, (k + 1) % 8)].is_infinite()
                    {
                        continue;
                    } else {
                        0.5 * (cu + cv) * std::f64::consts::SQRT_2
                    }
                } else {
                    lat.edge(u, k)
                };
                if !e.is_finite() {
                    continue;
                }
                let gv = gu + e;
                if gv < self.g[v] {
                    if self.g[v].is_infinite() {
                        self.touched.push(v as u32);
                    }
                    self.g[v] = gv;
                    self.parent[v] = ((k + 4) % 8) as u8;
                    let hv = h(ur.wrapping_add_signed(dr), uc.wrapping_add_signed(dc));
                    self.heap.push_or_update(v, [gv + hv, hv]);
                }
            }
        }
        let cost = self.g[t];
        if !cost.is_finite() {
            return Err(no_path);
        }
        let mut points = vec![lat.point(t)];
        let mut n = t;
        while n != s {
            n = lat.step(n, self.parent[n] as usize);
            points.push(lat.point(n));
        }
        points.reverse();
        Ok(Plan { cost, value: cost, points, expansions })
    }
}

impl GlobalPlanner for AStar {
    fn name(&self) -> &'static str {
        match (self.graph, self.heuristic) {
            (GraphKind::CellCentres, true) => "astar",
            (GraphKind::CornerNodes, true) => "astar-corners",
            (GraphKind::CellCentres, false) => "dijkstra",
            (GraphKind::CornerNodes, false) => "dijkstra-corners",
        }
    }
    fn graph(&self) -> GraphKind {
        self.graph
    }
    fn set_grid(&mut self, grid: CostGrid) {
        let lat = Lattice::new(&grid, self.graph);
        let n = lat.len();
        self.g = vec![f64::INFINITY; n];
        self.closed = lat.valid.iter().map(|&v| !v).collect();
        self.parent = vec![NO_PARENT; n];
        self.touched.clear();
        self.heap = IndexedHeap::new(n);
        self.lat = Some(lat);
        self.grid = Some(grid);
    }
    fn grid(&self) -> Option<&CostGrid> {
        self.grid.as_ref()
    }
    fn plan(&mut self, start: Cell, goal: Cell) -> Result<Plan, PlanError> {
        self.check("start", start)?;
        self.check("goal", goal)?;
        self.start = Some(start);
        self.goal = Some(goal);
        self.search(start, goal)
    }
    fn update_cells(&mut self, changes: &[CellChange]) -> Result<(), PlanError> {
        for c in changes {
            self.check("changed", c.cell)?;
            if c.cost.is_nan() || c.cost < 1.0 {
                return Err(PlanError::InvalidCost { cell: c.cell, cost: c.cost });
            }
        }
        let grid = self.grid.as_mut().ok_or(PlanError::NoGrid)?;
        let lat = self.lat.as_mut().ok_or(PlanError::NoGrid)?;
        for c in changes {
            if grid.set_cost(c.cell, c.cost).is_err() {
                return Err(PlanError::InvalidCost { cell: c.cell, cost: c.cost });
            }
            lat.set_cost(c.cell, c.cost);
        }
        Ok(())
    }
    fn move_start(&mut self, start: Cell) -> Result<(), PlanError> {
        self.check("start", start)?;
        self.start = Some(start);
        Ok(())
    }
    fn replan(&mut self) -> Result<Plan, PlanError> {
        match (self.start, self.goal) {
            (Some(s), Some(t)) => self.search(s, t),
            _ => Err(PlanError::NoPreviousPlan),
        }
    }
}
