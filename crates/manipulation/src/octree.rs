//! The terrain model of AutoPlace (paper 003 section 4.2): an octree whose cells are occupied,
//! free or unknown, where a cell is free only if a camera's line of sight to a sensed point
//! crossed it ("visibility analysis ... tracing the line of sight from one or both cameras to 3D
//! points sensed by the stereo vision system, and marking cells ... as verifiably free"), and
//! every cell not verified free counts as an obstacle ("the negation of this volume is added to
//! the obstacle octree").
//!
//! Cells holding a sensed point are occupied; each segment from a camera centre to a sensed
//! point, shortened by a surface margin so the surface's own cell is not freed, frees every cell
//! it crosses (a 3D digital differential analyser, Amanatides and Woo 1987); a cell both crossed
//! and holding a point stays occupied. Uniform octants collapse into one node.
//!
//! Departure: the paper keeps two octrees (obstacles, and verified-free space) and adds the
//! complement of the second to the first; here one tree holds the three states, which answers
//! the same question ("is this volume confirmed free?") with one descent.

use crate::geometry::{Aabb, V3};

/// The state of a cell.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Cell {
    /// No line of sight crossed it and no point fell in it: an obstacle for planning.
    Unknown,
    /// A line of sight crossed it and no point fell in it.
    Free,
    /// A sensed point fell in it.
    Occupied,
}

/// Where the octree sits and how fine it is.
#[derive(Clone, Debug, PartialEq)]
pub struct OctreeParams {
    /// Lower corner of the cube (body frame, m).
    pub min: [f64; 3],
    /// Leaf cell size (m).
    pub leaf: f64,
    /// Levels below the root: the cube has 2^depth leaves per side.
    pub depth: u32,
    /// A line of sight frees cells only up to this distance before its point (m).
    pub surface_margin: f64,
}

impl Default for OctreeParams {
    fn default() -> Self {
        // 2 cm leaves over a 1.28 m cube from just ahead of the body front down below the
        // wheels' plane: the arm's whole work volume.
        Self { min: [0.36, -0.64, -0.40], leaf: 0.02, depth: 6, surface_margin: 0.02 }
    }
}

/// One stereo view: the camera centres its lines of sight start from and the points it sensed
/// (body frame).
#[derive(Clone, Copy, Debug)]
pub struct View<'a> {
    /// Camera centres (m): both cameras of a pair, or one.
    pub cameras: &'a [V3],
    /// Sensed points (m).
    pub points: &'a [[f32; 3]],
}

/// A node as stored: 0, 1, 2 are leaves (unknown, free, occupied), `3 + i` a branch whose
/// children start at index `i` (four bytes a node).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Packed(u32);

impl From<Node> for Packed {
    fn from(n: Node) -> Self {
        Packed(match n {
            Node::Leaf(Cell::Unknown) => 0,
            Node::Leaf(Cell::Free) => 1,
            Node::Leaf(Cell::Occupied) => 2,
            Node::Branch(first) => first + 3,
        })
    }
}

impl From<Packed> for Node {
    fn from(p: Packed) -> Self {
        match p.0 {
            0 => Node::Leaf(Cell::Unknown),
            1 => Node::Leaf(Cell::Free),
            2 => Node::Leaf(Cell::Occupied),
            i => Node::Branch(i - 3),
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Node {
    Leaf(Cell),
    /// Index of the first of eight consecutive children.
    Branch(u32),
}

/// The three-state terrain octree.
#[derive(Clone, Debug)]
pub struct Octree {
    params: OctreeParams,
    nodes: Vec<Packed>,
}

/// Leaf index of a point along one axis (may be out of range).
fn index_of(x: f64, min: f64, leaf: f64) -> i64 {
    ((x - min) / leaf).floor() as i64
}

/// Calls `visit` with every leaf cell (i, j, k) the segment `c + t d`, t in `[0, t_end]`,
/// crosses inside the cube of `n` leaves per side (Amanatides and Woo's traversal after
/// clipping the segment to the cube).
pub fn trace_segment(p: &OctreeParams, c: &V3, d: &V3, t_end: f64, mut visit: impl FnMut([usize; 3])) {
    let n = 1usize << p.depth;
    let size = p.leaf * n as f64;
    let (mut t0, mut t1) = (0.0f64, t_end);
    for k in 0..3 {
        let lo = p.min[k];
        let hi = lo + size;
        if d[k].abs() < 1e-15 {
            if c[k] < lo || c[k] > hi {
                return;
            }
        } else {
            let (a, b) = ((lo - c[k]) / d[k], (hi - c[k]) / d[k]);
            t0 = t0.max(a.min(b));
            t1 = t1.min(a.max(b));
        }
    }
    if t0 > t1 {
        return;
    }
    let start = c + d * t0;
    let mut cell = [0i64; 3];
    let mut step = [0i64; 3];
    let mut t_max = [f64::INFINITY; 3];
    let mut t_delta = [f64::INFINITY; 3];
    for k in 0..3 {
        cell[k] = index_of(start[k], p.min[k], p.leaf).clamp(0, n as i64 - 1);
        if d[k] > 1e-15 {
            step[k] = 1;
            t_max[k] = (p.min[k] + (cell[k] + 1) as f64 * p.leaf - c[k]) / d[k];
            t_delta[k] = p.leaf / d[k];
        } else if d[k] < -1e-15 {
            step[k] = -1;
            t_max[k] = (p.min[k] + cell[k] as f64 * p.leaf - c[k]) / d[k];
            t_delta[k] = -p.leaf / d[k];
        }
    }
    loop {
        visit([cell[0] as usize, cell[1] as usize, cell[2] as usize]);
        let k = if t_max[0] < t_max[1] {
            if t_max[0] < t_max[2] { 0 } else { 2 }
        } else if t_max[1] < t_max[2] {
            1
        } else {
            2
        };
        if t_max[k] > t1 {
            return;
        }
        cell[k] += step[k];
        if cell[k] < 0 || cell[k] >= n as i64 {
            return;
        }
        t_max[k] += t_delta[k];
    }
}

/// Every leaf a view's lines of sight free and every leaf its points occupy.
fn for_each_mark(
    p: &OctreeParams,
    views: &[View],
    mut free: impl FnMut([usize; 3]),
    mut occupied: impl FnMut([usize; 3]),
) {
    let n = 1i64 << p.depth;
    for view in views {
        for q in view.points {
            let q = V3::new(q[0] as f64, q[1] as f64, q[2] as f64);
            if !(q.x.is_finite() && q.y.is_finite() && q.z.is_finite()) {
                continue;
            }
            for c in view.cameras {
                let v = q - c;
                let len = v.norm();
                let t_end = len - p.surface_margin;
                if t_end > 0.0 {
                    trace_segment(p, c, &(v / len), t_end, &mut free);
                }
            }
            let ijk = [0, 1, 2].map(|k| index_of(q[k], p.min[k], p.leaf));
            if ijk.iter().all(|&i| (0..n).contains(&i)) {
                occupied(ijk.map(|i| i as usize));
            }
        }
    }
}

impl Octree {
    /// An octree with every cell unknown.
    pub fn unknown(params: OctreeParams) -> Self {
        Self { params, nodes: vec![Node::Leaf(Cell::Unknown).into()] }
    }

    /// Builds the terrain model from stereo views: lines of sight free, points occupy.
    pub fn build(params: OctreeParams, views: &[View]) -> Self {
        let mut tree = Self::unknown(params);
        let p = tree.params.clone();
        let mut occupied = Vec::new();
        for_each_mark(&p, views, |ijk| tree.set(ijk, Cell::Free, false), |ijk| occupied.push(ijk));
        for ijk in occupied {
            tree.set(ijk, Cell::Occupied, true);
        }
        tree.compact();
        tree
    }

    /// The parameters it was built with.
    pub fn params(&self) -> &OctreeParams {
        &self.params
    }

    /// Leaves per side.
    pub fn side(&self) -> usize {
        1 << self.params.depth
    }

    /// Sets one leaf; a free mark never overwrites an occupied one unless `force`.
    fn set(&mut self, ijk: [usize; 3], state: Cell, force: bool) {
        let mut node = 0usize;
        for level in (0..self.params.depth).rev() {
            if let Node::Leaf(s) = Node::from(self.nodes[node]) {
                if s == state || (!force && s == Cell::Occupied) {
                    return;
                }
                let first = self.nodes.len() as u32;
                self.nodes.extend([Packed::from(Node::Leaf(s)); 8]);
                self.nodes[node] = Node::Branch(first).into();
            }
            let Node::Branch(first) = Node::from(self.nodes[node]) else { unreachable!("split above") };
            let octant =
                ((ijk[0] >> level) & 1) | (((ijk[1] >> level) & 1) << 1) | (((ijk[2] >> level) & 1) << 2);
            node = first as usize + octant;
        }
        match Node::from(self.nodes[node]) {
            Node::Leaf(Cell::Occupied) if !force => {}
            _ => self.nodes[node] = Node::Leaf(state).into(),
        }
    }

    /// Merges uniform octants and drops unreachable nodes.
    fn compact(&mut self) {
        fn copy(src: &[Packed], node: usize, out: &mut Vec<Packed>, at: usize) {
            match Node::from(src[node]) {
                Node::Leaf(s) => out[at] = Node::Leaf(s).into(),
                Node::Branch(first) => {
                    let base = out.len();
                    out.extend([Packed::from(Node::Leaf(Cell::Unknown)); 8]);
                    for i in 0..8 {
                        copy(src, first as usize + i, out, base + i);
                    }
                    let kids = &out[base..base + 8];
                    if let Node::Leaf(s) = Node::from(kids[0])
                        && kids.iter().all(|k| *k == kids[0])
                    {
                        out.truncate(base);
                        out[at] = Node::Leaf(s).into();
                    } else {
                        out[at] = Node::Branch(base as u32).into();
                    }
                }
            }
        }
        let mut out = vec![Packed::from(Node::Leaf(Cell::Unknown))];
        copy(&self.nodes, 0, &mut out, 0);
        self.nodes = out;
    }

    /// Marks every leaf lying entirely inside `b` free, whatever it held: volumes known to hold
    /// no terrain (the rover's body, the stowed arm).
    pub fn clear_box(&mut self, b: &Aabb) {
        let p = self.params.clone();
        let n = self.side() as i64;
        let lo = |k: usize| (((b.min[k] - p.min[k]) / p.leaf).ceil() as i64).clamp(0, n);
        let hi = |k: usize| (((b.max[k] - p.min[k]) / p.leaf).floor() as i64).clamp(0, n);
        for i in lo(0)..hi(0) {
            for j in lo(1)..hi(1) {
                for k in lo(2)..hi(2) {
                    self.set([i as usize, j as usize, k as usize], Cell::Free, true);
                }
            }
        }
        self.compact();
    }

    /// The same model with every unknown cell taken as free: what a planner that treats missing
    /// data as empty space would use (for evaluation only; AutoPlace never does).
    pub fn unknown_as_free(&self) -> Octree {
        let nodes = self
            .nodes
            .iter()
            .map(|n| match Node::from(*n) {
                Node::Leaf(Cell::Unknown) => Node::Leaf(Cell::Free).into(),
                _ => *n,
            })
            .collect();
        Octree { params: self.params.clone(), nodes }
    }

    /// The state of leaf (i, j, k).
    pub fn leaf(&self, ijk: [usize; 3]) -> Cell {
        let mut node = 0usize;
        let mut level = self.params.depth;
        loop {
            match Node::from(self.nodes[node]) {
                Node::Leaf(s) => return s,
                Node::Branch(first) => {
                    level -= 1;
                    let o = ((ijk[0] >> level) & 1)
                        | (((ijk[1] >> level) & 1) << 1)
                        | (((ijk[2] >> level) & 1) << 2);
                    node = first as usize + o;
                }
            }
        }
    }

    /// The state at a point; outside the cube everything is unknown.
    pub fn at(&self, q: &V3) -> Cell {
        let n = self.side() as i64;
        let ijk = [0, 1, 2].map(|k| index_of(q[k], self.params.min[k], self.params.leaf));
        if ijk.iter().any(|&i| !(0..n).contains(&i)) {
            return Cell::Unknown;
        }
        self.leaf(ijk.map(|i| i as usize))
    }

    /// Whether any cell not verified free (occupied or unknown, or outside the cube) lies within
    /// `radius` of `q`.
    pub fn blocked(&self, q: &V3, radius: f64) -> bool {
        let p = &self.params;
        let size = p.leaf * self.side() as f64;
        let cube = Aabb { min: V3::from(p.min), max: V3::from(p.min) + V3::repeat(size) };
        if (0..3).any(|k| q[k] - radius < cube.min[k] || q[k] + radius > cube.max[k]) {
            return true;
        }
        self.blocked_in(0, &cube, q, radius)
    }

    fn blocked_in(&self, node: usize, b: &Aabb, q: &V3, radius: f64) -> bool {
        if b.distance(q) >= radius {
            return false;
        }
        match Node::from(self.nodes[node]) {
            Node::Leaf(Cell::Free) => false,
            Node::Leaf(_) => true,
            Node::Branch(first) => {
                let h = (b.max - b.min) * 0.5;
                (0..8).any(|o| {
                    let off = V3::new(
                        (o & 1) as f64 * h.x,
                        ((o >> 1) & 1) as f64 * h.y,
                        ((o >> 2) & 1) as f64 * h.z,
                    );
                    let child = Aabb { min: b.min + off, max: b.min + off + h };
                    self.blocked_in(first as usize + o, &child, q, radius)
                })
            }
        }
    }

    /// Leaf-equivalent counts of (occupied, free, unknown) cells.
    pub fn counts(&self) -> [u64; 3] {
        let mut out = [0u64; 3];
        let mut stack = vec![(0usize, self.params.depth)];
        while let Some((node, level)) = stack.pop() {
            match Node::from(self.nodes[node]) {
                Node::Leaf(s) => {
                    let i = match s {
                        Cell::Occupied => 0,
                        Cell::Free => 1,
                        Cell::Unknown => 2,
                    };
                    out[i] += 1u64 << (3 * level);
                }
                Node::Branch(first) => stack.extend((0..8).map(|o| (first as usize + o, level - 1))),
            }
        }
        out
    }

    /// Every leaf as stored (a merged octant whole): its state, lower corner (m) and side (m),
    /// in depth-first order. The compact form of the model for logs and pictures.
    pub fn leaves(&self) -> Vec<(Cell, V3, f64)> {
        let mut out = Vec::new();
        let size = self.params.leaf * self.side() as f64;
        let mut stack = vec![(0usize, V3::from(self.params.min), size)];
        while let Some((node, min, side)) = stack.pop() {
            match Node::from(self.nodes[node]) {
                Node::Leaf(s) => out.push((s, min, side)),
                Node::Branch(first) => {
                    let h = 0.5 * side;
                    for o in (0..8).rev() {
                        let off = V3::new((o & 1) as f64, ((o >> 1) & 1) as f64, ((o >> 2) & 1) as f64) * h;
                        stack.push((first as usize + o, min + off, h));
                    }
                }
            }
        }
        out
    }

    /// Nodes held (leaves and branches).
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Bytes held by the nodes.
    pub fn memory_bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<Packed>()
    }
}

/// The same model as a dense voxel grid (one byte per leaf): the baseline the octree's memory
/// and build time are measured against.
#[derive(Clone, Debug)]
pub struct DenseGrid {
    /// Leaves per side.
    pub side: usize,
    /// Cell states, x fastest.
    pub cells: Vec<Cell>,
}

impl DenseGrid {
    /// Builds the grid with the octree's marking rules.
    pub fn build(params: &OctreeParams, views: &[View]) -> Self {
        let side = 1usize << params.depth;
        let mut cells = vec![Cell::Unknown; side * side * side];
        let at = |ijk: [usize; 3]| ijk[0] + side * (ijk[1] + side * ijk[2]);
        let mut occupied = Vec::new();
        for_each_mark(
            params,
            views,
            |ijk| {
                let c = &mut cells[at(ijk)];
                if *c == Cell::Unknown {
                    *c = Cell::Free;
                }
            },
            |ijk| occupied.push(ijk),
        );
        for ijk in occupied {
            cells[at(ijk)] = Cell::Occupied;
        }
        Self { side, cells }
    }

    /// Bytes held.
    pub fn memory_bytes(&self) -> usize {
        self.cells.len() * std::mem::size_of::<Cell>()
    }
}

#[cfg(test)]
mod tests;
