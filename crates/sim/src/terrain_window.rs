//! A window of a tiled terrain around the rover: the simulator keeps one ordinary [`Terrain`]
//! (what the ray caster, the renderer, the sensors and the vehicle model read) filled from the
//! tiles of a [`TiledTerrain`], and re-fills it around the rover when the rover comes within a
//! margin of its edge. A fixed terrain has no window and stays as it is.

use rovernav_terrain::tiled::{CacheStats, TiledTerrain};
use rovernav_terrain::{LocalRect, Terrain};

/// Default half-size of the window (m): an 80 m square at the finest level.
pub const DEFAULT_HALF_SIZE_M: f64 = 40.0;

/// Default margin (m): the window is re-centred when the rover comes this close to its edge,
/// leaving room for the longest sensor reach the navigators use (the mast's 20 m at most) and
/// for a whole drive command.
pub const DEFAULT_MARGIN_M: f64 = 25.0;

/// The rover's window onto a tiled terrain.
#[derive(Clone, Debug)]
pub struct TerrainWindow {
    source: TiledTerrain,
    half_size: f64,
    margin: f64,
    level: u8,
    /// The window's extent now (the cells' outer edges).
    extent: Option<LocalRect>,
    refills: u64,
}

impl TerrainWindow {
    /// A window of `half_size` metres around the rover at the source's finest level, re-centred
    /// within `margin` of its edge (clamped to less than the half-size).
    pub fn new(source: TiledTerrain, half_size: f64, margin: f64) -> Self {
        let half_size =
            if half_size.is_finite() && half_size > 1.0 { half_size } else { DEFAULT_HALF_SIZE_M };
        let margin = margin.clamp(0.0, 0.9 * half_size);
        Self { source, half_size, margin, level: 0, extent: None, refills: 0 }
    }

    /// Whether the rover at (x, y) is within the margin of the window's edge (or there is no
    /// window yet).
    pub fn needs_refill(&self, x: f64, y: f64) -> bool {
        match self.extent {
            None => true,
            Some(e) => {
                x - e.x_min < self.margin
                    || e.x_max - x < self.margin
                    || y - e.y_min < self.margin
                    || e.y_max - y < self.margin
            }
        }
    }

    /// The terrain of the window centred on (x, y).
    pub fn fill_around(&mut self, x: f64, y: f64) -> Terrain {
        let rect = LocalRect::centered(x, y, self.half_size);
        let terrain = match self.source.fill(rect, self.level) {
            Ok(t) => t,
            // Only a non-finite position gets here: an empty window, which the vehicle model
            // reports as the rover having left the terrain.
            Err(_) => Terrain { dem: rovernav_terrain::Dem::flat(0, 0, 1.0, 0.0), rocks: Vec::new() },
        };
        let g = terrain.dem.geometry();
        self.extent = Some(LocalRect::from_corner_size(g.origin_x, g.origin_y, g.width_m(), g.height_m()));
        self.refills += 1;
        terrain
    }

    /// Times the window was filled.
    pub fn refills(&self) -> u64 {
        self.refills
    }

    /// The tile cache's counters.
    pub fn cache_stats(&self) -> CacheStats {
        self.source.cache_stats()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rovernav_terrain::MarsYardParams;
    use rovernav_terrain::tiled::TiledParams;

    fn window() -> TerrainWindow {
        let params = TiledParams::new(MarsYardParams::with_seed(4), 64).unwrap();
        TerrainWindow::new(TiledTerrain::new(params, 16).unwrap(), 4.0, 1.5)
    }

    #[test]
    fn the_window_refills_only_near_its_edge_and_agrees_with_the_last_one() {
        let mut w = window();
        assert!(w.needs_refill(0.0, 0.0));
        let first = w.fill_around(0.0, 0.0);
        assert!(!w.needs_refill(2.0, -2.0));
        assert!(w.needs_refill(2.7, 0.0));
        let second = w.fill_around(2.7, 0.0);
        assert_eq!(w.refills(), 2);
        // The overlap of two windows holds the same cells (bilinear heights between them round
        // differently in the last bits: the grids start at different cells).
        for (x, y) in [(0.013, 0.017), (1.312, -2.226), (3.911, 3.104)] {
            let cell = |t: &Terrain| t.dem.heights.at_world(x, y).map(|v| v.to_bits());
            assert_eq!(cell(&first), cell(&second), "({x}, {y})");
            let (a, b) = (first.dem.height(x, y).unwrap(), second.dem.height(x, y).unwrap());
            assert!((a - b).abs() < 1e-9, "({x}, {y}): {a} vs {b}");
        }
        assert!(second.dem.height(6.5, 0.0).is_some() && first.dem.height(6.5, 0.0).is_none());
    }
}
