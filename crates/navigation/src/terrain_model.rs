//! The navigator's view of the terrain: the MRPTA terrain evaluator (robot-centred T-grid) fused
//! into a world map, plus a world-aligned hazard layer grown into configuration space for
//! planning (paper 000 section 2: obstacles grown by the rover size and a safety buffer): a wall
//! at half the rover's width (it cannot pass there even driving straight), an expensive band
//! out to its half-diagonal (it could not turn in place there), and exact sweeps of the body
//! outline for the turns and drives a plan needs.

use rovernav_core::{
    Grid2, GridGeometry, Overlay, OverlayKind, Point2, PointCloud, Pose2, PoseEstimate, RoverConfig,
};
use rovernav_mapping::WorldMap;
use rovernav_perception::{HazardHeight, SensorNoise, TerrainConfig, TerrainEvaluator};
use rovernav_planning::{Cell, CostGrid};

/// Fraction of the rover's clearance and tilt limits at which terrain counts as a hazard when
/// cell heights are point means (which lose part of a small rock's height).
pub const HAZARD_MARGIN: f64 = 0.8;

/// Fraction of the rover's clearance at which a step counts as a hazard on the cells' top
/// heights ([`HazardHeight::Top`]): that estimate is not biased low, so the margin only has to
/// cover range noise and the wheels settling a few centimetres into the relief.
pub const TOP_HAZARD_MARGIN: f64 = 0.9;

/// Standard deviations of far-range height noise within which a raised cell on the cells' top
/// heights counts as reaching the step limit: a rock of about the clearance seen from 3-5 m has
/// only a few mast points on its near face, and its top cell reads a couple of centimetres low.
pub const HAZARD_CONFIDENCE: f64 = 1.0;

/// Cell size of the robot-centred grid (m): finer than MRPTA's 0.15 m so that rocks of a few
/// decimetres, which a Rocky 7-sized rover cannot straddle, span several cells.
pub const T_GRID_RESOLUTION: f64 = 0.1;

/// Cost per metre of leaving a grown hazard the rover finds itself in.
const ESCAPE_COST: f32 = 50.0;

/// Cost per metre of a cell MRPTA grades not traversable but the hazard model does not block.
const BLOCKED_GRADE_COST: f32 = 30.0;

/// Cost per metre of a cell where the rover fits driving straight but could not turn in place
/// (between the inscribed and the circumscribed growth): passable, but worth a detour.
const TIGHT_COST: f32 = 4.0;

/// Allowance added to the rover's half-width for driving straight (m): the arcs the motion
/// controller drives start up to 10 deg off the chord, which swings the front corners out by
/// about half the length times sin(10 deg).
const HEADING_ALLOWANCE: f64 = 0.07;

/// Radius around a path point whose cells must have been seen before the rover drives there
/// (m): between half the rover's width and half its length.
pub const FOOTPRINT_CHECK_M: f64 = 0.35;

/// Clearance kept between the body outline and a hazard cell's centre when turning in place (m).
const TURN_MARGIN: f64 = 0.08;

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
    /// Uncertain hazard cells (within far-range noise of the step limit), latest observation
    /// wins: not walls for the planner, but the rover does not drive over one before a closer
    /// look has settled it (see [`Self::footprint_seen`]).
    suspect: Grid2<bool>,
    /// Cells whose hazard state has been assessed.
    assessed: Grid2<bool>,
    /// Cells that hold range points themselves (a window can assess a cell it has no points in).
    observed: Grid2<bool>,
    /// Hazards grown by the rover radius plus buffer: where the rover cannot turn in place
    /// (recomputed after each ingest).
    grown: Grid2<bool>,
    /// Hazards grown by half the rover width plus buffer and heading allowance: where even
    /// driving straight would put the body over a hazard.
    core: Grid2<bool>,
    /// Cells where the rover centre would enter a keep-out zone (grown like hazards).
    keep_out: Grid2<bool>,
    growth: f64,
    core_growth: f64,
    rover: RoverConfig,
    config: TerrainConfig,
}

impl TerrainModel {
    /// An empty model over `geometry` for a rover, assessing hazards on the cells' top heights
    /// (the grid navigators' setting).
    pub fn new(rover: &RoverConfig, geometry: GridGeometry, safety_buffer: f64) -> Self {
        Self::with_hazard_height(rover, geometry, safety_buffer, HazardHeight::Top)
    }

    /// An empty model that runs the hazard model on the given cell height.
    pub fn with_hazard_height(
        rover: &RoverConfig,
        geometry: GridGeometry,
        safety_buffer: f64,
        hazard_height: HazardHeight,
    ) -> Self {
        let config = Self::perception_config_for(rover, safety_buffer, hazard_height);
        let (cx, cy) =
            (geometry.origin_x + geometry.width_m() / 2.0, geometry.origin_y + geometry.height_m() / 2.0);
        let evaluator = TerrainEvaluator::new(config.clone(), rovernav_core::Pose2::new(cx, cy, 0.0))
            .expect("terrain configuration derived from a valid rover");
        Self {
            evaluator,
            world: WorldMap::unknown(geometry).expect("non-empty navigation map"),
            hazard: Grid2::filled(geometry, false),
            suspect: Grid2::filled(geometry, false),
            assessed: Grid2::filled(geometry, false),
            observed: Grid2::filled(geometry, false),
            grown: Grid2::filled(geometry, false),
            core: Grid2::filled(geometry, false),
            keep_out: Grid2::filled(geometry, false),
            growth: config.growth(),
            core_growth: core_growth(rover, safety_buffer),
            rover: rover.clone(),
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
        Self::perception_config_for(rover, safety_buffer, HazardHeight::Top)
    }

    /// [`Self::perception_config`] on a chosen cell height; the margin below the clearance
    /// follows the height's bias ([`HAZARD_MARGIN`] for means, [`TOP_HAZARD_MARGIN`] otherwise).
    pub fn perception_config_for(
        rover: &RoverConfig,
        safety_buffer: f64,
        hazard_height: HazardHeight,
    ) -> TerrainConfig {
        let mean = hazard_height == HazardHeight::Mean;
        let margin = if mean { HAZARD_MARGIN } else { TOP_HAZARD_MARGIN };
        TerrainConfig {
            safety_buffer,
            hazard_height,
            // The mean's wider margin already covers far-range noise.
            range_noise: (!mean).then(SensorNoise::default),
            hazard_confidence: if mean { 0.0 } else { HAZARD_CONFIDENCE },
            clearance: rover.clearance * margin,
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
                if layers.map.point_count.data[i] > 0 {
                    *self.observed.get_mut(c, r) = true;
                }
                if layers.step.data[i].is_finite() || layers.hazard.data[i] {
                    let uncertain = layers.uncertain_hazard.data[i];
                    *self.assessed.get_mut(c, r) = true;
                    *self.hazard.get_mut(c, r) = layers.hazard.data[i] && !uncertain;
                    *self.suspect.get_mut(c, r) = uncertain;
                }
            }
        }
        self.grow_hazards();
    }

    fn grow_hazards(&mut self) {
        self.hazard.dilate_into(self.growth, &mut self.grown);
        self.hazard.dilate_into(self.core_growth, &mut self.core);
    }

    /// Growth of hazards into configuration space (rover radius plus safety buffer, m).
    pub fn growth(&self) -> f64 {
        self.growth
    }

    /// Regrows the hazards with another safety buffer (the rover radius always stays).
    pub fn set_safety_buffer(&mut self, buffer: f64) {
        self.growth = self.config.rover_radius + buffer.max(0.0);
        self.core_growth = core_growth(&self.rover, buffer);
        self.grow_hazards();
    }

    /// Whether the rover could turn in place all the way round at `p`: no hazard cell within
    /// the body's half-diagonal plus a margin.
    pub fn can_turn_freely(&self, p: Point2) -> bool {
        let g = self.hazard.geometry;
        let reach = (0.5 * self.rover.length + TURN_MARGIN).hypot(0.5 * self.rover.width + TURN_MARGIN);
        let steps = (reach / g.resolution).ceil() as isize;
        let Some((c, r)) = g.cell_of(p.x, p.y) else { return true };
        for dr in -steps..=steps {
            for dc in -steps..=steps {
                let (rr, cc) = (r as isize + dr, c as isize + dc);
                if rr < 0 || cc < 0 || rr as usize >= g.rows || cc as usize >= g.cols {
                    continue;
                }
                let (x, y) = g.center(cc as usize, rr as usize);
                if *self.hazard.get(cc as usize, rr as usize) && Point2::new(x, y).dist(p) <= reach {
                    return false;
                }
            }
        }
        true
    }

    /// Whether turning in place by `angle` (rad, signed) from `pose` keeps the body outline,
    /// plus a margin, clear of every hazard cell over the whole sweep. Cells already under the
    /// body at `pose` are not counted: the rover stands there without contact, so they are
    /// either noise or too low to matter, and counting them would forbid every motion.
    pub fn turn_is_clear(&self, pose: Pose2, angle: f64) -> bool {
        // Body-frame angles of the sweep, a few degrees apart so no cell slips between samples.
        let samples = (angle.abs() / 4f64.to_radians()).ceil().max(1.0) as usize;
        let poses =
            (1..=samples).map(|k| Pose2::new(pose.x, pose.y, pose.yaw + angle * k as f64 / samples as f64));
        self.motion_is_clear(pose, poses)
    }

    /// Whether driving straight by `distance` (m, negative backwards) from `pose` keeps the body
    /// outline, plus a margin, clear of every hazard cell not already under it.
    pub fn drive_is_clear(&self, pose: Pose2, distance: f64) -> bool {
        let samples = (distance.abs() / 0.05).ceil().max(1.0) as usize;
        let (s, c) = pose.yaw.sin_cos();
        let poses = (1..=samples).map(|k| {
            let d = distance * k as f64 / samples as f64;
            Pose2::new(pose.x + d * c, pose.y + d * s, pose.yaw)
        });
        self.motion_is_clear(pose, poses)
    }

    /// Whether the body outline at each of `poses`, grown by a margin, covers no hazard cell
    /// centre that is not already under the bare body at `start`.
    fn motion_is_clear(&self, start: Pose2, poses: impl Iterator<Item = Pose2>) -> bool {
        let g = self.hazard.geometry;
        let (half_l, half_w) = (0.5 * self.rover.length + TURN_MARGIN, 0.5 * self.rover.width + TURN_MARGIN);
        let reach = half_l.hypot(half_w);
        let inside = |pose: Pose2, x: f64, y: f64, margin: f64| {
            let (s, co) = pose.yaw.sin_cos();
            let (dx, dy) = (x - pose.x, y - pose.y);
            let (bx, by) = (co * dx + s * dy, -s * dx + co * dy);
            bx.abs() <= 0.5 * self.rover.length + margin && by.abs() <= 0.5 * self.rover.width + margin
        };
        let covers = |pose: Pose2, x: f64, y: f64| inside(pose, x, y, TURN_MARGIN);
        let under_body = |pose: Pose2, x: f64, y: f64| inside(pose, x, y, 0.0);
        let clamp_x = |x: f64| x.clamp(g.origin_x, g.origin_x + g.width_m() - 1e-9);
        let clamp_y = |y: f64| y.clamp(g.origin_y, g.origin_y + g.height_m() - 1e-9);
        for pose in poses {
            let (Some((c0, r0)), Some((c1, r1))) = (
                g.cell_of(clamp_x(pose.x - reach), clamp_y(pose.y - reach)),
                g.cell_of(clamp_x(pose.x + reach), clamp_y(pose.y + reach)),
            ) else {
                continue;
            };
            for r in r0..=r1 {
                for c in c0..=c1 {
                    if !*self.hazard.get(c, r) {
                        continue;
                    }
                    let (x, y) = g.center(c, r);
                    if covers(pose, x, y) && !under_body(start, x, y) {
                        return false;
                    }
                }
            }
        }
        true
    }

    /// Records an obstacle the body met but perception missed (a hazard contact), so the
    /// planner never drives into it again.
    pub fn mark_contact(&mut self, p: Point2) {
        for (c, r) in cells_in_disc(&self.hazard.geometry, p, 0.25) {
            *self.hazard.get_mut(c, r) = true;
            *self.assessed.get_mut(c, r) = true;
        }
        self.grow_hazards();
    }

    /// Whether the body could stand at `p` on terrain it has seen: every cell within
    /// [`FOOTPRINT_CHECK_M`] of `p` is assessed, is no uncertain hazard (a rock seen only from
    /// afar whose top may reach the clearance: walling it off would box the rover in among the
    /// many rocks just under the limit, driving over it unchecked may meet one above it), and
    /// either holds range points or is a one-cell gap among cells that do. A footprint window
    /// assesses cells it has no points in, and a rock in an occlusion shadow is such a hole:
    /// driving over it on the strength of its neighbours is how a rover meets a rock it never
    /// saw. Cells within `exempt_radius` of `exempt` (the ground under the rover, which its
    /// cameras cannot see) are not checked.
    pub fn footprint_seen(&self, p: Point2, exempt: Point2, exempt_radius: f64) -> bool {
        let g = self.hazard.geometry;
        let Some((c0, r0)) = g.cell_of(p.x, p.y) else { return false };
        let steps = (FOOTPRINT_CHECK_M / g.resolution).ceil() as isize;
        let observed = |c: isize, r: isize| {
            c >= 0
                && r >= 0
                && (c as usize) < g.cols
                && (r as usize) < g.rows
                && *self.observed.get(c as usize, r as usize)
        };
        for dr in -steps..=steps {
            for dc in -steps..=steps {
                let (c, r) = (c0 as isize + dc, r0 as isize + dr);
                if c < 0 || r < 0 || c as usize >= g.cols || r as usize >= g.rows {
                    return false;
                }
                let (x, y) = g.center(c as usize, r as usize);
                let q = Point2::new(x, y);
                if q.dist(p) > FOOTPRINT_CHECK_M || q.dist(exempt) <= exempt_radius {
                    continue;
                }
                if !*self.assessed.get(c as usize, r as usize) || *self.suspect.get(c as usize, r as usize) {
                    return false;
                }
                if observed(c, r) {
                    continue;
                }
                let seen_around = (-1..=1)
                    .flat_map(|a| (-1..=1).map(move |b| (a, b)))
                    .filter(|&(a, b)| (a, b) != (0, 0) && observed(c + a, r + b))
                    .count();
                if seen_around < 5 {
                    return false;
                }
            }
        }
        true
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
        let escape_radius = self.core_growth + g.resolution;
        let in_core = |p: Point2| g.cell_of(p.x, p.y).is_some_and(|(c, r)| *self.core.get(c, r));
        let (rover_trapped, goal_covered) = (in_core(rover), in_core(goal));
        for r in 0..g.rows {
            for c in 0..g.cols {
                let cell = Cell::new(r, c);
                if *self.core.get(c, r) {
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
                if mode == CostMode::Traversability && !*self.core.get(c, r) && grid.is_blocked(cell) {
                    // MRPTA grades cells "not traversable" from roughness and neighbourhood
                    // too; only the step/slope hazards (grown) are walls, the rest is just
                    // the most expensive terrain, so noise cannot wall the rover in.
                    let _ = grid.set_cost(cell, BLOCKED_GRADE_COST);
                }
                if !*self.core.get(c, r) && *self.grown.get(c, r) {
                    let base = grid.cost(cell);
                    let _ = grid.set_cost(cell, base.max(1.0) * TIGHT_COST);
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

/// The cells under the points `p + (dc, dr) * resolution` that lie within `radius` of `p`: a
/// disc of cells around `p`, clipped to the grid.
pub fn cells_in_disc(g: &GridGeometry, p: Point2, radius: f64) -> Vec<(usize, usize)> {
    let steps = (radius / g.resolution).ceil() as isize;
    let mut out = Vec::new();
    for dr in -steps..=steps {
        for dc in -steps..=steps {
            let q = Point2::new(p.x + dc as f64 * g.resolution, p.y + dr as f64 * g.resolution);
            if q.dist(p) <= radius
                && let Some(cell) = g.cell_of(q.x, q.y)
            {
                out.push(cell);
            }
        }
    }
    out
}

/// Growth that keeps a rover driving straight (half its width plus the heading allowance and the
/// safety buffer) off a hazard.
fn core_growth(rover: &RoverConfig, safety_buffer: f64) -> f64 {
    0.5 * rover.width + HEADING_ALLOWANCE + safety_buffer.max(0.0)
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

    /// A 6 m x 6 m model at 0.1 m around the origin with every cell seen and assessed, and
    /// hazard cells at the given world points.
    fn model_with_hazards(points: &[Point2]) -> TerrainModel {
        let geometry = GridGeometry { cols: 60, rows: 60, resolution: 0.1, origin_x: -3.0, origin_y: -3.0 };
        let mut m = TerrainModel::new(&RoverConfig::default(), geometry, 0.1);
        m.assessed.data.iter_mut().for_each(|v| *v = true);
        m.observed.data.iter_mut().for_each(|v| *v = true);
        for p in points {
            let (c, r) = geometry.cell_of(p.x, p.y).unwrap();
            *m.hazard.get_mut(c, r) = true;
        }
        m.grow_hazards();
        m
    }

    #[test]
    fn turning_sweeps_the_body_outline() {
        // A 0.8 m x 0.6 m rover at the origin facing east. A hazard 0.45 m to its left is clear
        // of the body (half-width 0.3 + margin) but inside the half-length (0.4 + margin) once
        // the rover has turned a quarter turn either way.
        let rover = RoverConfig::default();
        assert_eq!((rover.length, rover.width), (0.8, 0.6));
        let m = model_with_hazards(&[Point2::new(0.05, 0.45)]);
        let pose = Pose2::new(0.0, 0.0, 0.0);
        assert!(m.turn_is_clear(pose, 0.1), "a small turn keeps the side clear");
        assert!(!m.turn_is_clear(pose, std::f64::consts::FRAC_PI_2));
        assert!(!m.turn_is_clear(pose, -std::f64::consts::FRAC_PI_2));
        assert!(!m.can_turn_freely(Point2::new(0.0, 0.0)), "0.45 m is inside the 0.57 m half-diagonal");
        assert!(m.can_turn_freely(Point2::new(0.0, -0.3)), "0.75 m away the rover turns freely");
        // Driving east passes it; driving north into it does not.
        assert!(m.drive_is_clear(pose, 1.0));
        assert!(!m.drive_is_clear(Pose2::new(0.0, -0.5, std::f64::consts::FRAC_PI_2), 0.6));
        assert!(m.drive_is_clear(Pose2::new(0.0, -0.5, std::f64::consts::FRAC_PI_2), 0.2));
    }

    #[test]
    fn cells_already_under_the_body_do_not_forbid_motion() {
        // The rover stands over a detection without touching anything: it must still be able
        // to move off it, or one noisy cell would trap it.
        let m = model_with_hazards(&[Point2::new(0.1, 0.0)]);
        let pose = Pose2::new(0.0, 0.0, 0.0);
        assert!(m.turn_is_clear(pose, 1.0));
        assert!(m.drive_is_clear(pose, -0.5));
    }

    #[test]
    fn the_grid_walls_off_half_the_width_and_charges_the_turning_band() {
        let m = model_with_hazards(&[Point2::new(0.05, 0.05)]);
        let grid = m.cost_grid(CostMode::Optimistic, Point2::new(-2.5, -2.5), Point2::new(2.5, 2.5));
        let cost_at = |x: f64| grid.cost_at_point(grid.world_to_grid(Point2::new(x, 0.05)));
        // Wall: half-width 0.3 + heading allowance 0.07 + buffer 0.1 = 0.47 m.
        assert!(cost_at(0.05 + 0.4).is_infinite());
        // Band: out to the radius 0.5 + buffer 0.1 = 0.6 m.
        assert_eq!(cost_at(0.05 + 0.55), TIGHT_COST);
        assert_eq!(cost_at(0.05 + 0.8), 1.0);
    }

    #[test]
    fn the_footprint_must_have_been_seen() {
        let mut m = model_with_hazards(&[]);
        let g = m.observed.geometry;
        let p = Point2::new(1.0, 1.0);
        let (c, r) = g.cell_of(p.x, p.y).unwrap();
        // A one-cell gap in the points is sampling, not a hiding place for a rock.
        *m.observed.get_mut(c, r) = false;
        assert!(m.footprint_seen(p, Point2::new(-2.0, -2.0), 0.4));
        // A 3 x 3 hole (0.3 m) can hide a rock the rover cannot straddle.
        for dr in 0..3 {
            for dc in 0..3 {
                *m.observed.get_mut(c + dc - 1, r + dr - 1) = false;
            }
        }
        assert!(!m.footprint_seen(p, Point2::new(-2.0, -2.0), 0.4));
        // ... unless it lies under the rover, which its cameras cannot see.
        assert!(m.footprint_seen(p, p, 0.4));
        // A hole 0.5 m away is outside the footprint check.
        assert!(m.footprint_seen(Point2::new(1.5, 1.0), Point2::new(-2.0, -2.0), 0.4));
        // An uncertain hazard 0.3 m away must be looked at again before the rover stands there,
        // but it is no wall for the planner.
        let q = Point2::new(-1.0, -1.0);
        assert!(m.footprint_seen(q, Point2::new(-2.0, -2.0), 0.4));
        let (c, r) = g.cell_of(q.x + 0.3, q.y).unwrap();
        *m.suspect.get_mut(c, r) = true;
        m.grow_hazards();
        assert!(!m.footprint_seen(q, Point2::new(-2.0, -2.0), 0.4));
        let grid = m.cost_grid(CostMode::Optimistic, Point2::new(-2.5, -2.5), Point2::new(2.5, 2.5));
        assert_eq!(grid.cost_at_point(grid.world_to_grid(q)), 1.0);
    }

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
