//! The optimal safe path: the shortest path the rover could drive with full knowledge of the
//! true terrain, the yardstick of a run's path ratio (`distance_driven_m / optimal_length_m`).
//!
//! Field D* (paper: Ferguson and Stentz, any-angle interpolated D*) through the cells where the
//! simulator's hazard model says the rover centre is safe in every heading. It reads simulation
//! truth on purpose and is never part of the autonomy.

use rovernav_core::Point2;
use rovernav_executive::World;
use rovernav_planning::{Cell, CostGrid, FieldDStar, GlobalPlanner};

/// Cell size of the ground-truth hazard grid used for the optimal path (m).
pub const OPTIMAL_PATH_RESOLUTION: f64 = 0.1;

/// Length of the shortest safe path with full knowledge of the true terrain (m), if one exists:
/// Field D* (any-angle) through the cells where the simulator's hazard model says the rover
/// centre is safe in every heading.
///
/// None on a tiled terrain: the world holds only its coarse overview, and a hazard grid of a
/// whole long route at rover scale would not fit in memory.
pub fn optimal_length(world: &World) -> Option<f64> {
    if world.terrain.dem.geo.crs == rovernav_terrain::tiled::TILED_CRS {
        return None;
    }
    optimal_length_on(world, &true_hazard(world))
}

/// The simulator's hazard truth the optimal length is planned on (cells where the rover
/// centre is unsafe in some heading, at [`OPTIMAL_PATH_RESOLUTION`]).
pub fn true_hazard(world: &World) -> rovernav_core::Grid2<bool> {
    rovernav_sim::true_hazard_grid(&world.terrain, &world.rover, OPTIMAL_PATH_RESOLUTION)
}

/// [`optimal_length`] through the safe cells of a hazard grid already computed by
/// [`true_hazard`].
pub fn optimal_length_on(world: &World, hazard: &rovernav_core::Grid2<bool>) -> Option<f64> {
    let g = hazard.geometry;
    let mut grid = CostGrid::from_occupancy(hazard);
    grid.set_geometry(g);
    let cell = |p: Point2| g.cell_of(p.x, p.y).map(|(c, r)| Cell::new(r, c));
    let (start, goal) = (cell(world.start.position())?, cell(world.goal.position)?);
    // The rover starts (and the goal lies) in a cleared pad; make sure rounding to a cell
    // never declares a pad's own centre unsafe.
    let _ = grid.set_cost(start, 1.0);
    let _ = grid.set_cost(goal, 1.0);
    let mut planner = FieldDStar::new();
    planner.set_grid(grid);
    let plan = planner.plan(start, goal).ok()?;
    // The planner runs between cell centres (or corners); add the offsets to the true points.
    let to_world = |p: Point2| Point2::new(g.origin_x + p.x * g.resolution, g.origin_y + p.y * g.resolution);
    let mut length = plan.cost * g.resolution;
    if let (Some(first), Some(last)) = (plan.points.first(), plan.points.last()) {
        length += to_world(*first).dist(world.start.position()) + to_world(*last).dist(world.goal.position);
    }
    Some(length)
}
