//! Configuration-space obstacles for RoverBug (paper 000 section 2).
//!
//! Obstacle cells found by the step/slope model are grouped into distinct obstacles (8-connected
//! regions), the convex hull of each region is computed, and the hull is grown by the rover
//! radius plus an empirical safety buffer to give the C-obstacle. Each C-obstacle vertex is
//! labelled when it lies inside another C-obstacle or outside the sensed wedge(s); if the goal
//! lies inside a C-obstacle, that obstacle's vertices are marked as goals (so an operator can
//! designate a rock as a target).
//!
//! **Growth approximation.** The exact C-obstacle of a convex hull P for a disc of radius r is
//! the Minkowski sum P + D(r), bounded by P's edges pushed out by r and circular arcs of radius
//! r around P's vertices. Here each arc is replaced by segments of the tangent lines to the
//! circle at evenly spaced directions no more than `max_arc_step` apart, so the polygon vertices
//! sit at `r / cos(delta/2)` from the hull vertex. Every edge of the result lies on a supporting
//! line of the exact sum, so the polygon is the intersection of half-planes that each contain
//! the exact sum: it *contains* the exact C-obstacle (conservative) and overshoots it by at most
//! `r * (1/cos(max_arc_step/2) - 1)` (3.5 % of r for 30 degree steps).
//!
//! Obstacle regions are hulled over the corners of their cells, so the hull covers the whole
//! area of every obstacle cell, not just the cell centres.

use crate::hull::convex_hull;
use rovernav_core::{Grid2, Point2, Pose2, Wedge};
use std::f64::consts::TAU;

/// Tolerance (m) for boundary tests.
const EPS: f64 = 1e-9;

/// Labels of one C-obstacle vertex (paper 000 section 2).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct VertexLabel {
    /// The vertex lies strictly inside another C-obstacle.
    pub inside_other: bool,
    /// The vertex lies outside every sensed wedge.
    pub outside_sensed: bool,
    /// The goal lies inside this C-obstacle, so the vertex is a goal.
    pub goal: bool,
}

/// A convex configuration-space obstacle.
#[derive(Clone, Debug, PartialEq)]
pub struct CObstacle {
    /// Convex hull of the obstacle cells (counter-clockwise, world frame).
    pub hull: Vec<Point2>,
    /// Vertices of the grown polygon (counter-clockwise, world frame).
    pub vertices: Vec<Point2>,
    /// One label per vertex.
    pub labels: Vec<VertexLabel>,
    /// Number of obstacle cells in the region.
    pub cells: usize,
    /// Growth distance used: rover radius plus safety buffer (m).
    pub growth: f64,
}

impl CObstacle {
    /// Builds a C-obstacle from an obstacle hull grown by `growth` metres.
    pub fn from_hull(hull: Vec<Point2>, growth: f64, max_arc_step: f64, cells: usize) -> Self {
        let vertices = grow_convex_polygon(&hull, growth, max_arc_step);
        Self { labels: vec![VertexLabel::default(); vertices.len()], hull, vertices, cells, growth }
    }

    /// Outward edge `i` from vertex `i` to vertex `i + 1`.
    fn edge(&self, i: usize) -> (Point2, Point2) {
        let n = self.vertices.len();
        (self.vertices[i], self.vertices[(i + 1) % n])
    }

    /// Whether `p` is inside or on the polygon.
    pub fn contains(&self, p: Point2) -> bool {
        self.signed_clearance(p) <= EPS
    }

    /// Whether `p` is strictly inside the polygon (not on its boundary).
    pub fn contains_strict(&self, p: Point2) -> bool {
        self.signed_clearance(p) < -EPS
    }

    /// Largest signed distance from `p` to the supporting lines of the edges: negative inside
    /// (minus the distance to the nearest edge line), positive outside.
    pub fn signed_clearance(&self, p: Point2) -> f64 {
        let n = self.vertices.len();
        if n < 3 {
            return f64::INFINITY;
        }
        (0..n)
            .map(|i| {
                let (a, b) = self.edge(i);
                let d = b.sub(a);
                // Counter-clockwise polygon: outside is to the right of each edge.
                -d.cross(p.sub(a)) / d.norm()
            })
            .fold(f64::NEG_INFINITY, f64::max)
    }

    /// The part of segment `a -> b` inside or on the polygon, as the parameter interval
    /// `[t0, t1]` of `a + t (b - a)`, `0 <= t0 <= t1 <= 1` (Cyrus-Beck clipping).
    pub fn clip_segment(&self, a: Point2, b: Point2) -> Option<(f64, f64)> {
        let n = self.vertices.len();
        if n < 3 {
            return None;
        }
        let d = b.sub(a);
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        for i in 0..n {
            let (v, w) = self.edge(i);
            let e = w.sub(v);
            let len = e.norm();
            // Outward normal of a counter-clockwise edge.
            let normal = Point2::new(e.y / len, -e.x / len);
            let num = normal.dot(a.sub(v));
            let den = normal.dot(d);
            if den.abs() < 1e-15 {
                if num > EPS {
                    return None;
                }
                continue;
            }
            // Inside this edge's half-plane (with tolerance): normal . (a + t d - v) <= EPS.
            let t = (EPS - num) / den;
            if den > 0.0 {
                t1 = t1.min(t);
            } else {
                t0 = t0.max(t);
            }
            if t0 > t1 {
                return None;
            }
        }
        Some((t0.max(0.0), t1.min(1.0)))
    }

    /// Whether segment `a -> b` passes through the polygon's interior. Grazing a vertex or
    /// running along an edge (the tangent segments of a tangent graph) does not count.
    pub fn blocks_segment(&self, a: Point2, b: Point2) -> bool {
        match self.clip_segment(a, b) {
            Some((t0, t1)) if t1 > t0 => {
                let d = b.sub(a);
                let mid = a.add(d.scale(0.5 * (t0 + t1)));
                self.contains_strict(mid)
            }
            _ => false,
        }
    }

    /// Whether `p` lies strictly inside the obstacle's own convex hull (not just in the margin
    /// it was grown by). A hull of fewer than three points has no inside.
    pub fn hull_contains_strict(&self, p: Point2) -> bool {
        let n = self.hull.len();
        n >= 3
            && (0..n).all(|i| {
                let (a, b) = (self.hull[i], self.hull[(i + 1) % n]);
                b.sub(a).cross(p.sub(a)) > EPS
            })
    }

    /// Whether the goal vertex labels are set (the goal lies inside this obstacle).
    pub fn is_goal_obstacle(&self) -> bool {
        self.labels.first().is_some_and(|l| l.goal)
    }
}

/// Grows a convex counter-clockwise polygon by `r` (conservative Minkowski sum with a disc; see
/// the module documentation). One point grows into a regular polygon circumscribing the circle;
/// two points into a stadium.
pub fn grow_convex_polygon(hull: &[Point2], r: f64, max_arc_step: f64) -> Vec<Point2> {
    let step = if max_arc_step.is_finite() && max_arc_step > 1e-3 {
        max_arc_step.min(std::f64::consts::FRAC_PI_2)
    } else {
        std::f64::consts::FRAC_PI_6
    };
    let r = r.max(0.0);
    let n = hull.len();
    let mut out = Vec::new();
    match n {
        0 => {}
        1 => {
            let m = (TAU / step).ceil() as usize;
            let delta = TAU / m as f64;
            let dist = r / (0.5 * delta).cos();
            for k in 0..m {
                let theta = (k as f64 + 0.5) * delta;
                out.push(hull[0].add(Point2::new(theta.cos(), theta.sin()).scale(dist)));
            }
        }
        _ => {
            // Outward normal direction (angle) of edge i -> i+1 of a counter-clockwise polygon.
            let normal_angle = |i: usize| {
                let d = hull[(i + 1) % n].sub(hull[i]);
                (-d.x).atan2(d.y)
            };
            for (i, &vertex) in hull.iter().enumerate() {
                let theta_in = normal_angle((i + n - 1) % n);
                let theta_out = normal_angle(i);
                let mut turn = (theta_out - theta_in).rem_euclid(TAU);
                if n == 2 {
                    turn = std::f64::consts::PI;
                }
                if turn < 1e-12 {
                    continue;
                }
                let m = (turn / step).ceil().max(1.0) as usize;
                let delta = turn / m as f64;
                let dist = r / (0.5 * delta).cos();
                for k in 0..m {
                    let theta = theta_in + (k as f64 + 0.5) * delta;
                    out.push(vertex.add(Point2::new(theta.cos(), theta.sin()).scale(dist)));
                }
            }
        }
    }
    out
}

/// 8-connected regions of `true` cells, each a list of `(col, row)`.
pub fn obstacle_regions(mask: &Grid2<bool>) -> Vec<Vec<(usize, usize)>> {
    let (cols, rows) = (mask.cols(), mask.rows());
    let mut seen = vec![false; cols * rows];
    let mut regions = Vec::new();
    let mut stack = Vec::new();
    for start in 0..cols * rows {
        if !mask.data[start] || seen[start] {
            continue;
        }
        seen[start] = true;
        stack.push(start);
        let mut region = Vec::new();
        while let Some(i) = stack.pop() {
            let (c, r) = (i % cols, i / cols);
            region.push((c, r));
            for dr in -1i64..=1 {
                for dc in -1i64..=1 {
                    let (nc, nr) = (c as i64 + dc, r as i64 + dr);
                    if nc < 0 || nr < 0 || nc >= cols as i64 || nr >= rows as i64 {
                        continue;
                    }
                    let j = nr as usize * cols + nc as usize;
                    if mask.data[j] && !seen[j] {
                        seen[j] = true;
                        stack.push(j);
                    }
                }
            }
        }
        regions.push(region);
    }
    regions
}

/// C-obstacles of every obstacle region of `mask`, grown by `growth` metres (rover radius plus
/// safety buffer), arcs approximated in steps of at most `max_arc_step` radians. Labels are
/// left unset: call [`label_c_obstacles`].
pub fn build_c_obstacles(mask: &Grid2<bool>, growth: f64, max_arc_step: f64) -> Vec<CObstacle> {
    let g = mask.geometry;
    obstacle_regions(mask)
        .into_iter()
        .map(|region| {
            let mut corners = Vec::with_capacity(4 * region.len());
            for &(c, r) in &region {
                let x0 = g.origin_x + c as f64 * g.resolution;
                let y0 = g.origin_y + r as f64 * g.resolution;
                corners.push(Point2::new(x0, y0));
                corners.push(Point2::new(x0 + g.resolution, y0));
                corners.push(Point2::new(x0, y0 + g.resolution));
                corners.push(Point2::new(x0 + g.resolution, y0 + g.resolution));
            }
            CObstacle::from_hull(convex_hull(&corners), growth, max_arc_step, region.len())
        })
        .collect()
}

/// A sensed wedge placed in the world: the wedge of a range image and the pose estimate of the
/// rover when it was captured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SensedWedge {
    /// Rover pose estimate at capture.
    pub pose: Pose2,
    /// Visible region in that pose's body frame.
    pub wedge: Wedge,
}

impl SensedWedge {
    /// Whether a world point lies inside the wedge.
    pub fn contains(&self, p: Point2) -> bool {
        let b = self.pose.inverse_transform(p);
        self.wedge.contains(b.x, b.y)
    }
}

/// Labels every vertex: inside another C-obstacle, outside all `sensed` wedges, and goal when
/// `goal` lies inside its own C-obstacle (paper 000 section 2).
pub fn label_c_obstacles(obstacles: &mut [CObstacle], sensed: &[SensedWedge], goal: Option<Point2>) {
    for k in 0..obstacles.len() {
        let is_goal = goal.is_some_and(|g| obstacles[k].contains(g));
        let labels: Vec<VertexLabel> = obstacles[k]
            .vertices
            .iter()
            .map(|&v| VertexLabel {
                inside_other: obstacles.iter().enumerate().any(|(j, o)| j != k && o.contains_strict(v)),
                outside_sensed: !sensed.iter().any(|w| w.contains(v)),
                goal: is_goal,
            })
            .collect();
        obstacles[k].labels = labels;
    }
}

/// Intersection point of segments `a-b` and `c-d`, if they cross or touch (collinear overlaps
/// return the first shared point along `a-b`).
pub fn segment_intersection(a: Point2, b: Point2, c: Point2, d: Point2) -> Option<Point2> {
    let r = b.sub(a);
    let s = d.sub(c);
    let denom = r.cross(s);
    let ac = c.sub(a);
    let scale = r.norm().max(s.norm()).max(1.0);
    if denom.abs() <= 1e-12 * scale * scale {
        // Parallel: intersect only when collinear and overlapping.
        if ac.cross(r).abs() > 1e-12 * scale * scale {
            return None;
        }
        let rr = r.dot(r);
        if rr == 0.0 {
            return (a.dist(c) <= EPS || segments_intersect(c, d, a, a)).then_some(a);
        }
        let t0 = ac.dot(r) / rr;
        let t1 = d.sub(a).dot(r) / rr;
        let (lo, hi) = (t0.min(t1).max(0.0), t0.max(t1).min(1.0));
        return (lo <= hi).then(|| a.add(r.scale(lo)));
    }
    let t = ac.cross(s) / denom;
    let u = ac.cross(r) / denom;
    let tol = 1e-12;
    ((-tol..=1.0 + tol).contains(&t) && (-tol..=1.0 + tol).contains(&u)).then(|| a.add(r.scale(t)))
}

/// Whether segments `a-b` and `c-d` cross or touch.
pub fn segments_intersect(a: Point2, b: Point2, c: Point2, d: Point2) -> bool {
    if a == b {
        // Degenerate first segment: a point on c-d?
        let s = d.sub(c);
        let len2 = s.dot(s);
        if len2 == 0.0 {
            return a.dist(c) <= EPS;
        }
        let t = (a.sub(c).dot(s) / len2).clamp(0.0, 1.0);
        return c.add(s.scale(t)).dist(a) <= EPS;
    }
    segment_intersection(a, b, c, d).is_some()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hull::polygon_area;
    use proptest::prelude::*;
    use rovernav_core::GridGeometry;

    fn square() -> Vec<Point2> {
        vec![Point2::new(0.0, 0.0), Point2::new(1.0, 0.0), Point2::new(1.0, 1.0), Point2::new(0.0, 1.0)]
    }

    #[test]
    fn grown_square_area_is_between_exact_sum_and_its_bound() {
        let r = 0.5;
        let step = 30f64.to_radians();
        let grown = grow_convex_polygon(&square(), r, step);
        // Each corner turns 90 degrees in 3 steps of 30: 3 vertices per corner.
        assert_eq!(grown.len(), 12);
        let exact = 1.0 + 4.0 * r + std::f64::consts::PI * r * r;
        // Outer bound: the same shape with radius r / cos(15 deg).
        let ro = r / 15f64.to_radians().cos();
        let outer = 1.0 + 4.0 * r + 12.0 * ro * ro * 15f64.to_radians().tan();
        let a = polygon_area(&grown);
        assert!(a >= exact && a <= outer + 1e-9, "{exact} <= {a} <= {outer}");
    }

    #[test]
    fn point_and_segment_grow_into_discs_and_stadiums() {
        let p = Point2::new(3.0, 4.0);
        let grown = grow_convex_polygon(&[p], 1.0, 30f64.to_radians());
        assert_eq!(grown.len(), 12);
        for v in &grown {
            assert!((v.dist(p) - 1.0 / 15f64.to_radians().cos()).abs() < 1e-12);
        }
        let seg =
            grow_convex_polygon(&[Point2::new(0.0, 0.0), Point2::new(2.0, 0.0)], 1.0, 30f64.to_radians());
        let o = CObstacle {
            hull: vec![],
            labels: vec![VertexLabel::default(); seg.len()],
            vertices: seg,
            cells: 0,
            growth: 1.0,
        };
        assert!(o.contains(Point2::new(1.0, 0.999)) && o.contains(Point2::new(-0.99, 0.0)));
        assert!(!o.contains(Point2::new(1.0, 1.01)));
    }

    #[test]
    fn clip_and_block_distinguish_crossing_from_grazing() {
        let o = CObstacle::from_hull(square(), 0.0, 0.5, 1);
        // Square grown by 0 is the square itself (corner vertices coincide).
        assert!(o.contains(Point2::new(0.5, 0.5)) && o.contains(Point2::new(1.0, 0.5)));
        assert!(!o.contains_strict(Point2::new(1.0, 0.5)));
        let (t0, t1) = o.clip_segment(Point2::new(-1.0, 0.5), Point2::new(3.0, 0.5)).unwrap();
        assert!((t0 - 0.25).abs() < 1e-6 && (t1 - 0.5).abs() < 1e-6);
        assert!(o.blocks_segment(Point2::new(-1.0, 0.5), Point2::new(3.0, 0.5)));
        // Along the top edge: touches but does not enter.
        assert!(!o.blocks_segment(Point2::new(-1.0, 1.0), Point2::new(3.0, 1.0)));
        // Through a corner only.
        assert!(!o.blocks_segment(Point2::new(-1.0, 1.0), Point2::new(1.0, -1.0)));
        // Along the diagonal: crosses.
        assert!(o.blocks_segment(Point2::new(-1.0, 2.0), Point2::new(2.0, -1.0)));
        assert!(o.clip_segment(Point2::new(-1.0, 3.0), Point2::new(3.0, 3.0)).is_none());
    }

    #[test]
    fn hull_containment_excludes_the_grown_margin() {
        let o = CObstacle::from_hull(square(), 0.5, 30f64.to_radians(), 1);
        // Inside the unit square, on its edge, and in the 0.5 m margin around it.
        assert!(o.hull_contains_strict(Point2::new(0.5, 0.5)));
        assert!(!o.hull_contains_strict(Point2::new(1.0, 0.5)));
        assert!(!o.hull_contains_strict(Point2::new(1.3, 0.5)) && o.contains(Point2::new(1.3, 0.5)));
        let point = CObstacle::from_hull(vec![Point2::new(0.0, 0.0)], 0.5, 30f64.to_radians(), 0);
        assert!(!point.hull_contains_strict(Point2::new(0.0, 0.0)));
    }

    #[test]
    fn segment_helpers_find_crossings() {
        let x = segment_intersection(
            Point2::new(0.0, 0.0),
            Point2::new(2.0, 2.0),
            Point2::new(0.0, 2.0),
            Point2::new(2.0, 0.0),
        )
        .unwrap();
        assert!(x.dist(Point2::new(1.0, 1.0)) < 1e-12);
        assert!(!segments_intersect(
            Point2::new(0.0, 0.0),
            Point2::new(1.0, 0.0),
            Point2::new(0.0, 1.0),
            Point2::new(1.0, 1.0)
        ));
        assert!(segments_intersect(
            Point2::new(0.0, 0.0),
            Point2::new(2.0, 0.0),
            Point2::new(1.0, 0.0),
            Point2::new(3.0, 0.0)
        ));
    }

    #[test]
    fn labels_mark_overlaps_wedge_and_goal() {
        let g = GridGeometry { cols: 20, rows: 20, resolution: 0.5, origin_x: 0.0, origin_y: 0.0 };
        let mut mask = Grid2::filled(g, false);
        *mask.get_mut(4, 10) = true;
        *mask.get_mut(6, 10) = true; // separate region, grown C-obstacles overlap
        *mask.get_mut(15, 10) = true;
        let mut obs = build_c_obstacles(&mask, 0.6, 30f64.to_radians());
        assert_eq!(obs.len(), 3);
        // A wedge from (0, 5) looking east, 6 m deep, +-30 degrees.
        let wedge = SensedWedge {
            pose: Pose2::new(0.0, 5.25, 0.0),
            wedge: Wedge { bearing: 0.0, half_angle: 30f64.to_radians(), min_range: 0.0, max_range: 6.0 },
        };
        let goal = Point2::new(7.75, 5.25);
        label_c_obstacles(&mut obs, &[wedge], Some(goal));
        let by_cell = |x: f64| obs.iter().find(|o| o.contains(Point2::new(x, 5.25))).unwrap();
        let left = by_cell(2.25);
        let right = by_cell(3.25);
        assert!(left.labels.iter().any(|l| l.inside_other));
        assert!(right.labels.iter().any(|l| l.inside_other));
        let far = by_cell(7.75);
        assert!(far.is_goal_obstacle() && far.labels.iter().all(|l| l.goal && l.outside_sensed));
        assert!(left.labels.iter().all(|l| !l.goal && !l.outside_sensed));
    }

    proptest! {
        /// Every point of the obstacle cells dilated by the growth radius lies in a C-obstacle.
        #[test]
        fn c_obstacles_contain_obstacles_grown_by_radius(
            cells in prop::collection::vec(any::<bool>(), 64),
            radius in 0.05..1.0f64,
            step_deg in 5.0..90.0f64,
            samples in prop::collection::vec((0usize..64, 0.0..1.0f64, 0.0..1.0f64, 0.0..TAU, 0.0..1.0f64), 40),
        ) {
            let g = GridGeometry { cols: 8, rows: 8, resolution: 0.15, origin_x: -0.3, origin_y: 1.1 };
            let mask = Grid2 { geometry: g, data: cells.clone() };
            let obs = build_c_obstacles(&mask, radius, step_deg.to_radians());
            for (k, u, v, theta, d) in samples {
                // Pick an obstacle cell (the k-th, cycling), a point in it, and an offset <= r.
                let occupied: Vec<usize> = (0..64).filter(|&i| cells[i]).collect();
                prop_assume!(!occupied.is_empty());
                let i = occupied[k % occupied.len()];
                let (c, r) = (i % 8, i / 8);
                let base = Point2::new(
                    g.origin_x + (c as f64 + u) * g.resolution,
                    g.origin_y + (r as f64 + v) * g.resolution,
                );
                let p = base.add(Point2::new(theta.cos(), theta.sin()).scale(d * radius));
                prop_assert!(obs.iter().any(|o| o.contains(p)), "{p:?} not covered");
            }
            // Cell corners pushed out by exactly the radius, in 16 directions.
            for i in (0..64).filter(|&i| cells[i]) {
                let (c, r) = (i % 8, i / 8);
                for (du, dv) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)] {
                    let corner = Point2::new(
                        g.origin_x + (c as f64 + du) * g.resolution,
                        g.origin_y + (r as f64 + dv) * g.resolution,
                    );
                    for k in 0..16 {
                        let t = k as f64 * TAU / 16.0;
                        let p = corner.add(Point2::new(t.cos(), t.sin()).scale(radius));
                        prop_assert!(obs.iter().any(|o| o.contains(p)), "{p:?} not covered");
                    }
                }
            }
        }
    }
}
