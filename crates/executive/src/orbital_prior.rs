//! The orbital map a rover is given before its traverse (paper 002 section 5): prior data
//! derived once from the world's terrain description, never per-cycle truth.
//!
//! An orbital DEM such as HiRISE's resolves the ground's relief at about a metre and none of
//! the rocks a rover has to avoid. The map here is the world's terrain with every rock's
//! footprint left out, averaged over square cells of the orbital resolution (1 m by default);
//! a cell whose ground is all rock keeps the mean of its heights, rocks included. For a tiled
//! terrain the world holds a coarse overview of the route whose cells show bare ground
//! (`docs/long-range.md`), which is averaged the same way.
//!
//! Departure from a real orbital map: this one is registered to the simulation frame exactly
//! and has no height noise (a HiRISE DEM carries metres of registration error and decimetres
//! of height noise), so fixes against it are unbiased by construction and the figures of
//! `docs/results/2026-11-28-localization-scales.md` are best cases.

use crate::World;
use rovernav_core::{Grid2, GridGeometry};

/// Resolution of the orbital map derived for a run (m): HiRISE-class.
pub const ORBITAL_MAP_RESOLUTION_M: f64 = 1.0;

/// The orbital map of `world`'s terrain at `resolution` metres (NaN where the terrain has no
/// data): its heights without the rocks' footprints, averaged over each cell.
pub fn orbital_map(world: &World, resolution: f64) -> Grid2<f32> {
    let dem = &world.terrain.dem;
    let g = *dem.geometry();
    let resolution = resolution.max(g.resolution);
    let cols = ((g.width_m() / resolution).ceil() as usize).max(1);
    let rows = ((g.height_m() / resolution).ceil() as usize).max(1);
    let out = GridGeometry { cols, rows, resolution, origin_x: g.origin_x, origin_y: g.origin_y };
    // Cells under a rock (its footprint grown by half a cell).
    let mut rock = vec![false; g.len()];
    for r in &world.terrain.rocks {
        let radius = 0.5 * r.diameter + 0.5 * g.resolution;
        let cell = |v: f64, o: f64| ((v - o) / g.resolution).floor();
        let (c0, c1) = (cell(r.x - radius, g.origin_x).max(0.0), cell(r.x + radius, g.origin_x));
        let (r0, r1) = (cell(r.y - radius, g.origin_y).max(0.0), cell(r.y + radius, g.origin_y));
        if !(c1 >= 0.0 && r1 >= 0.0) {
            continue;
        }
        let (c1, r1) = ((c1 as usize).min(g.cols - 1), (r1 as usize).min(g.rows - 1));
        for row in r0 as usize..=r1 {
            for col in c0 as usize..=c1 {
                let (x, y) = g.center(col, row);
                if (x - r.x).hypot(y - r.y) <= radius {
                    rock[g.index(col, row)] = true;
                }
            }
        }
    }
    // Sums over (bare ground, all ground) per output cell.
    let mut bare = vec![(0.0f64, 0u32); out.len()];
    let mut all = vec![(0.0f64, 0u32); out.len()];
    let nodata = dem.nodata;
    for row in 0..g.rows {
        for col in 0..g.cols {
            let h = *dem.heights.get(col, row);
            if !h.is_finite() || nodata == Some(h) {
                continue;
            }
            let (x, y) = g.center(col, row);
            let Some((oc, or)) = out.cell_of(x, y) else { continue };
            let i = out.index(oc, or);
            all[i].0 += f64::from(h);
            all[i].1 += 1;
            if !rock[g.index(col, row)] {
                bare[i].0 += f64::from(h);
                bare[i].1 += 1;
            }
        }
    }
    let mean = |(s, n): (f64, u32)| (n > 0).then(|| (s / f64::from(n)) as f32);
    let data = bare.iter().zip(&all).map(|(&b, &a)| mean(b).or(mean(a)).unwrap_or(f32::NAN)).collect();
    Grid2 { geometry: out, data }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rovernav_core::{Goal, Point2, Pose2, RoverConfig};
    use rovernav_sim::SensorModel;
    use rovernav_terrain::{Dem, Rock, Terrain};

    fn world(dem: Dem, rocks: Vec<Rock>) -> World {
        World {
            terrain: Terrain { dem, rocks },
            rover: RoverConfig::default(),
            sensor_model: SensorModel::default(),
            start: Pose2::new(1.0, 1.0, 0.0),
            goal: Goal {
                position: Point2::new(2.0, 2.0),
                tolerance: 0.5,
                waypoints: vec![],
                keep_out: vec![],
            },
        }
    }

    /// A tilted plane with a rock on it: the map is the plane's mean over each metre (its value
    /// at the cell's centre), the rock's bump left out.
    #[test]
    fn the_map_is_the_ground_without_its_rocks_averaged_over_each_cell() {
        let geometry = GridGeometry { cols: 60, rows: 40, resolution: 0.05, origin_x: 0.0, origin_y: 0.0 };
        let plane = |x: f64, y: f64| 0.2 * x - 0.1 * y;
        let mut dem = Dem::flat(60, 40, 0.05, 0.0);
        for row in 0..geometry.rows {
            for col in 0..geometry.cols {
                let (x, y) = geometry.center(col, row);
                let bump = if (x - 1.5).hypot(y - 0.5) < 0.2 { 0.3 } else { 0.0 };
                *dem.heights.get_mut(col, row) = (plane(x, y) + bump) as f32;
            }
        }
        let rock = Rock { x: 1.5, y: 0.5, diameter: 0.4, height: 0.3 };
        let map = orbital_map(&world(dem.clone(), vec![rock]), 1.0);
        assert_eq!((map.cols(), map.rows(), map.resolution()), (3, 2, 1.0));
        for row in 0..2 {
            for col in 0..3 {
                let (x, y) = map.geometry.center(col, row);
                let h = f64::from(*map.get(col, row));
                // The rock's cell loses a symmetric disc of the plane: its mean stays the plane's.
                assert!((h - plane(x, y)).abs() < 2e-3, "cell ({col}, {row}): {h} against {}", plane(x, y));
            }
        }
        // Without the rock list the bump stays in (what leaving rocks in would give).
        let with_rock = orbital_map(&world(dem, vec![]), 1.0);
        assert!(f64::from(*with_rock.get(1, 0)) > plane(1.5, 0.5) + 0.02);
    }
}
