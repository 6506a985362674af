//! The navigator's view of the terrain: the MRPTA terrain evaluator (robot-centred T-grid) fused
//! into a world map, plus a world-aligned hazard layer grown into configuration space for
//! planning (paper 000 section 2: obstacles grown by the rover size and a safety buffer).

use rovernav_core::{
    Grid2, GridGeometry, Overlay, OverlayKind, Point2, PointCloud, PoseEstimate, RoverConfig,
};
use rovernav_mapping::WorldMap;
use rovernav_perception::{TerrainConfig, TerrainEvaluator};
use rovernav_planning::{Cell, CostGrid};

/// Fraction of the rover's clearance and tilt limits at which terrain counts as a hazard.
pub const HAZARD_MARGIN: f64 = 0.8;

/// Cell size of the robot-centred grid (m): finer than MRPTA's 0.15 m so that rocks of a few
/// decimetres, which a Rocky 7-sized rover cannot straddle, span several cells.
pub const T_GRID_RESOLUTION: f64 = 0.1;

/// Cost per metre of leaving a grown hazard the rover finds itself in.
const ESCAPE_COST: f32 = 50.0;

/// Cost per metre of a cell MRPTA grades not traversable but the hazard model does not block.
const BLOCKED_GRADE_COST: f32 = 30.0;

/// How unknown and sensed cells are costed for the planner.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CostMode {
    /// Every cell outside grown hazards costs 1, sensed or not (freespace assumption).
    Optimistic,
    /// MRPTA traversability costs, unsensed cells neutral (paper 004 section 3.5).
    Traversability,
}

/// Sensed terrain in world coordinates.
pub struct TerrainModel {
    evaluator: TerrainEvaluator,
    world: WorldMap,
    /// Obstacle cells of the step/slope model, latest observation wins.
    hazard: Grid2<bool>,
    /// Cells whose hazard state has been assessed.
    assessed: Grid2<bool>,
    /// Hazards grown by the rover radius plus buffer (recomputed after each ingest).
    grown: Grid2<bool>,
    /// Cells where the rover centre would enter a keep-out zone (grown like hazards).
    keep_out: Grid2<bool>,
    growth: f64,
    config: TerrainConfig,
}

impl TerrainModel {
    /// An empty model over `geometry` for a rover.
    pub fn new(rover: &RoverConfig, geometry: GridGeometry, safety_buffer: f64) -> Self {
        let config = Self::perception_config(rover, safety_buffer);
        let (cx, cy) =
            (geometry.origin_x + geometry.width_m() / 2.0, geometry.origin_y + geometry.height_m() / 2.0);
        let evaluator = TerrainEvaluator::new(config.clone(), rovernav_core::Pose2::new(cx, cy, 0.0))
            .expect("terrain configuration derived from a valid rover");
        Self {
            evaluator,
            world: WorldMap::unknown(geometry).expect("non-empty navigation map"),
            hazard: Grid2::filled(geometry, false),
            assessed: Grid2::filled(geometry, false),
            grown: Grid2::filled(geometry, false),
            keep_out: Grid2::filled(geometry, false),
            growth: config.growth(),
            config,
        }
    }

    /// Marks the mission's keep-out polygons, grown by the rover radius and buffer, as cells
    /// the planner must never enter (paper 003's keep-out zones, honoured by every navigator).
    pub fn set_keep_out(&mut self, zones: &[Vec<Point2>]) {
        let g = self.keep_out.geometry;
        for r in 0..g.rows {
            for c in 0..g.cols {
                let (x, y) = g.center(c, r);
                *self.keep_out.get_mut(c, r) = distance_to_zones(zones, Point2::new(x, y)) <= self.growth;
            }
        }
    }

    /// The terrain-assessment settings navigators use for a rover.
    ///
    /// Hazard limits sit below the rover's true limits: range noise and the wheels settling into
    /// relief can turn a rock that measures exactly the clearance into belly contact.
    pub fn perception_config(rover: &RoverConfig, safety_buffer: f64) -> TerrainConfig {
        TerrainConfig {
            safety_buffer,
            clearance: rover.clearance * HAZARD_MARGIN,
            max_tilt: rover.max_tilt * HAZARD_MARGIN,
            resolution: T_GRID_RESOLUTION,
            ..TerrainConfig::for_rover(rover)
        }
    }

    /// The fused world map.
    pub fn world(&self) -> &WorldMap {
        &self.world
    }

    /// Folds range data into the maps, placed with the pose estimate.
    pub fn ingest(&mut self, clouds: &[PointCloud], estimate: &PoseEstimate) {
        let layers = self.evaluator.update(clouds, estimate);
        // A fusion error can only come from inconsistent layer sizes, which the evaluator
        // never produces; skipping the fusion keeps the navigator running on older data.
        let _ = self.world.fuse(&layers.map, estimate);
        let lg = layers.geometry();
        let wg = self.hazard.geometry;
        // Sample the local assessment under every world cell it covers.
        let x0 = lg.origin_x.max(wg.origin_x);
        let y0 = lg.origin_y.max(wg.origin_y);
        let x1 = (lg.origin_x + lg.width_m()).min(wg.origin_x + wg.width_m());
        let y1 = (lg.origin_y + lg.height_m()).min(wg.origin_y + wg.height_m());
        if x1 <= x0 || y1 <= y0 {
            return;
        }
        let (Some((c0, r0)), Some((c1, r1))) = (wg.cell_of(x0, y0), wg.cell_of(x1 - 1e-9, y1 - 1e-9)) else {
            return;
        };
        for r in r0..=r1 {
            for c in c0..=c1 {
                let (x, y) = wg.center(c, r);
                let Some((lc, lr)) = lg.cell_of(x, y) else { continue };
                let i = lg.index(lc, lr);
                if layers.step.data[i].is_finite() || layers.hazard.data[i] {
                    *self.assessed.get_mut(c, r) = true;
                    *self.hazard.get_mut(c, r) = layers.hazard.data[i];
                }
            }
        }
        self.grow_hazards();
    }

    fn grow_hazards(&mut self) {
        let g = self.hazard.geometry;
        let reach = (self.growth / g.resolution).ceil() as isize;
        let r2 = (self.growth / g.resolution).powi(2);
        let offsets: Vec<(isize, isize)> = (-reach..=reach)
            .flat_map(|dr| (-reach..=reach).map(move |dc| (dr, dc)))
            .filter(|&(dr, dc)| ((dr * dr + dc * dc) as f64) <= r2 + 0.5)
            .collect();
        self.grown.data.iter_mut().for_each(|v| *v = false);
        for r in 0..g.rows {
            for c in 0..g.cols {
                if !*self.hazard.get(c, r) {
                    continue;
                }
                for &(dr, dc) in &offsets {
                    let (rr, cc) = (r as isize + dr, c as isize + dc);
                    if rr >= 0 && cc >= 0 && (rr as usize) < g.rows && (cc as usize) < g.cols {
                        *self.grown.get_mut(cc as usize, rr as usize) = true;
                    }
                }
            }
        }
    }

    /// Growth of hazards into configuration space (rover radius plus safety buffer, m).
    pub fn growth(&self) -> f64 {
        self.growth
    }

    /// Regrows the hazards with another safety buffer (the rover radius always stays).
    pub fn set_safety_buffer(&mut self, buffer: f64) {
        self.growth = self.config.rover_radius + buffer.max(0.0);
        self.grow_hazards();
    }

    /// Records an obstacle the body met but perception missed (a hazard contact), so the
    /// planner never drives into it again.
    pub fn mark_contact(&mut self, p: Point2) {
        let g = self.hazard.geometry;
        let reach = 0.25;
        let steps = (reach / g.resolution).ceil() as isize;
        for dr in -steps..=steps {
            for dc in -steps..=steps {
                let q = Point2::new(p.x + dc as f64 * g.resolution, p.y + dr as f64 * g.resolution);
                if q.dist(p) <= reach
                    && let Some((c, r)) = g.cell_of(q.x, q.y)
                {
                    *self.hazard.get_mut(c, r) = true;
                    *self.assessed.get_mut(c, r) = true;
                }
            }
        }
        self.grow_hazards();
    }

    /// Whether the hazard state of the cell containing a point has been assessed from range data.
    pub fn is_assessed(&self, p: Point2) -> bool {
        self.hazard.geometry.cell_of(p.x, p.y).is_some_and(|(c, r)| *self.assessed.get(c, r))
    }

    /// Whether a point lies in a grown hazard.
    pub fn is_grown_hazard(&self, p: Point2) -> bool {
        self.hazard.geometry.cell_of(p.x, p.y).is_some_and(|(c, r)| *self.grown.get(c, r))
    }

    /// The planning grid. Cells within the rover's own footprint are never blocked, so a rover
    /// that finds itself inside a grown hazard (noise, or a late detection) can still plan out.
    pub fn cost_grid(&self, mode: CostMode, rover: Point2, goal: Point2) -> CostGrid {
        let g = self.hazard.geometry;
        let mut grid = match mode {
            CostMode::Optimistic => CostGrid::uniform(g.rows, g.cols, 1.0).expect("non-empty grid"),
            CostMode::Traversability => CostGrid::from_traversability(self.world.traversability()),
        };
        grid.set_geometry(g);
        // A rover that finds itself inside grown hazards (noise, or a late detection) may leave
        // through them at a high cost, but never through an obstacle cell itself; likewise a
        // goal that a nearby rock's grown margin covers stays reachable.
        let escape_radius = self.growth + g.resolution;
        let in_grown = |p: Point2| g.cell_of(p.x, p.y).is_some_and(|(c, r)| *self.grown.get(c, r));
        let (rover_trapped, goal_covered) = (in_grown(rover), in_grown(goal));
        for r in 0..g.rows {
            for c in 0..g.cols {
                let cell = Cell::new(r, c);
                if *self.grown.get(c, r) {
                    let (x, y) = g.center(c, r);
                    let p = Point2::new(x, y);
                    let escapable = !*self.hazard.get(c, r)
                        && ((rover_trapped && p.dist(rover) <= escape_radius)
                            || (goal_covered && p.dist(goal) <= escape_radius));
                    let _ = grid.set_cost(cell, if escapable { ESCAPE_COST } else { f32::INFINITY });
                }
                if *self.keep_out.get(c, r) {
                    let _ = grid.set_cost(cell, f32::INFINITY);
                    continue;
                }
                if mode == CostMode::Traversability && !*self.grown.get(c, r) && grid.is_blocked(cell) {
                    // MRPTA grades cells "not traversable" from roughness and neighbourhood
                    // too; only the step/slope hazards (grown) are walls, the rest is just
                    // the most expensive terrain, so noise cannot wall the rover in.
                    let _ = grid.set_cost(cell, BLOCKED_GRADE_COST);
                }
                if mode == CostMode::Optimistic {
                    grid.set_sensed(cell, *self.assessed.get(c, r));
                }
            }
        }
        grid
    }

    /// The grown hazards as C-obstacle overlays for the traverse picture.
    pub fn overlays(&self) -> Vec<Overlay> {
        self.hazard_outlines().into_iter().map(|p| Overlay::Polygon(p, OverlayKind::CObstacle)).collect()
    }

    /// Outlines of the grown hazards, as convex C-obstacles, for display.
    pub fn hazard_outlines(&self) -> Vec<Vec<Point2>> {
        rovernav_perception::cobstacle::build_c_obstacles(&self.hazard, self.growth, self.config.max_arc_step)
            .into_iter()
            .map(|o| o.vertices)
            .collect()
    }
}

/// Distance from a point to the nearest of some polygons (0 inside one; infinity without any).
pub fn distance_to_zones(zones: &[Vec<Point2>], p: Point2) -> f64 {
    let mut best = f64::INFINITY;
    for zone in zones.iter().filter(|z| z.len() >= 3) {
        let mut inside = false;
        for i in 0..zone.len() {
            let (a, b) = (zone[i], zone[(i + 1) % zone.len()]);
            if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x) {
                inside = !inside;
            }
            let ab = b.sub(a);
            let t = (p.sub(a).dot(ab) / ab.dot(ab).max(1e-12)).clamp(0.0, 1.0);
            best = best.min(p.dist(a.add(ab.scale(t))));
        }
        if inside {
            return 0.0;
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zone_distance_is_zero_inside_and_euclidean_outside() {
        let square = vec![vec![
            Point2::new(0.0, 0.0),
            Point2::new(2.0, 0.0),
            Point2::new(2.0, 2.0),
            Point2::new(0.0, 2.0),
        ]];
        assert_eq!(distance_to_zones(&square, Point2::new(1.0, 1.0)), 0.0);
        assert!((distance_to_zones(&square, Point2::new(3.0, 1.0)) - 1.0).abs() < 1e-12);
        assert!((distance_to_zones(&square, Point2::new(3.0, 3.0)) - 2f64.sqrt()).abs() < 1e-12);
        assert_eq!(distance_to_zones(&[], Point2::new(0.0, 0.0)), f64::INFINITY);
    }
}
