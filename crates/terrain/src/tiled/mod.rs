//! Terrain without edges: the procedural Mars yard (`procedural`, after paper 000's JPL MarsYard
//! with Golombek-Rapp rock fields) generated in square tiles on demand, so a traverse of any
//! length has ground under it while only the tiles around the rover are held.
//!
//! - Relief, ridges and the regional slope are coherent noise of world coordinates
//!   ([`Relief`], the yard's own model), sampled at the cell centres of one global lattice per
//!   level: a tile's cells are exactly the cells a single grid of the same resolution would hold,
//!   so the relief has no seam.
//! - Craters and rocks are drawn per tile from a generator seeded by a hash of (seed, tile),
//!   each belonging to the tile that holds its centre, with the yard's size-frequency laws. A
//!   tile's heights add the craters of every tile within one blanket radius and the rocks of
//!   its eight neighbours, so a rock or crater on a border shapes both sides.
//! - Level `L` has cells of `resolution * 2^L` over the same tile squares: level 0 is the yards'
//!   5 cm near the rover, coarser levels give the far field. Rocks show in the heights only at
//!   levels of cells up to [`ROCK_LEVEL_MAX_RESOLUTION`]; coarser levels are bare ground.
//! - Tiles live in a bounded least-recently-used cache ([`cache`]).
//!
//! Departures from the whole-yard generator, and why: craters and rocks are sampled per tile (a
//! whole-yard draw needs the whole yard), so a tiled terrain and a yard of the same seed share
//! their relief cell for cell but not their craters and rocks; the statistics are the same.

pub mod cache;
mod tile;

use std::sync::Arc;

use crate::dem::{Dem, GeoReference, Rock, Terrain};
use crate::ops::LocalRect;
use crate::procedural::{MarsYardParams, Relief};
use rovernav_core::{Grid2, GridGeometry};

pub use cache::{CacheStats, TileCache};
pub use tile::{TILED_CRS, Tile};

/// Coarsest level (cells of `resolution * 2^MAX_LEVEL`).
pub const MAX_LEVEL: u8 = 6;

/// Cells at most this size (m) show rocks in their heights.
pub const ROCK_LEVEL_MAX_RESOLUTION: f64 = 0.2;

/// Largest grid `fill` builds (cells).
pub const MAX_FILL_CELLS: usize = 16_000_000;

/// Index of a tile: its level of detail and its column (tx, ty) in the tile lattice.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct TileKey {
    /// Level of detail (0 finest).
    pub level: u8,
    /// Tile column east (tile `tx` spans x in [tx S, (tx + 1) S)).
    pub tx: i64,
    /// Tile row north.
    pub ty: i64,
}

/// Parameters of a tiled terrain.
#[derive(Clone, Debug, PartialEq)]
pub struct TiledParams {
    /// The yard model (its `width_m` and `height_m` are ignored; `resolution` is level 0's).
    pub yard: MarsYardParams,
    /// Cells along a tile's side at level 0 (a multiple of `2^MAX_LEVEL`).
    pub tile_cells: usize,
}

/// Why tiled parameters cannot be used.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum TiledError {
    /// A parameter out of range (names it).
    #[error("tiled terrain: {0}")]
    Invalid(String),
}

impl TiledParams {
    /// Tiles of `tile_cells` cells at the yard's resolution.
    pub fn new(yard: MarsYardParams, tile_cells: usize) -> Result<Self, TiledError> {
        let p = Self { yard, tile_cells };
        p.check()?;
        Ok(p)
    }

    fn check(&self) -> Result<(), TiledError> {
        let bad = |why: &str| Err(TiledError::Invalid(why.into()));
        let step = 1usize << MAX_LEVEL;
        if self.tile_cells == 0 || !self.tile_cells.is_multiple_of(step) || self.tile_cells > 4096 {
            return bad("tile_cells must be a positive multiple of 64 up to 4096");
        }
        let res = self.yard.resolution;
        if !(res.is_finite() && (0.005..=1.0).contains(&res)) {
            return bad("resolution must be in [0.005, 1] m");
        }
        let max_rock = self.yard.rocks.max_diameter_m;
        if max_rock.is_nan() || self.tile_size_m() < max_rock {
            return bad("a tile must be at least as wide as the largest rock");
        }
        let c = &self.yard;
        if !(c.crater_max_diameter_m.is_finite() && c.crater_max_diameter_m <= 8.0 * self.tile_size_m()) {
            return bad("crater_max_diameter_m must be finite and at most 8 tiles");
        }
        Ok(())
    }

    /// Side of a tile (m), the same at every level.
    pub fn tile_size_m(&self) -> f64 {
        self.tile_cells as f64 * self.yard.resolution
    }

    /// Cell size at a level (m).
    pub fn resolution(&self, level: u8) -> f64 {
        self.yard.resolution * f64::from(1u32 << level.min(MAX_LEVEL))
    }

    /// Cells along a tile's side at a level.
    pub fn cells_per_side(&self, level: u8) -> usize {
        self.tile_cells >> level.min(MAX_LEVEL)
    }

    /// Whether a level's cells are fine enough to show rocks.
    pub fn shows_rocks(&self, level: u8) -> bool {
        self.resolution(level) <= ROCK_LEVEL_MAX_RESOLUTION + 1e-12
    }

    /// Tiles around a tile whose craters may reach into it.
    pub(crate) fn crater_ring(&self) -> i64 {
        let reach = 2.5 * 0.5 * self.yard.crater_max_diameter_m.max(0.0);
        (reach / self.tile_size_m()).ceil() as i64
    }

    /// The finest level whose cells are at least `resolution` (m).
    pub fn level_for(&self, resolution: f64) -> u8 {
        (0..=MAX_LEVEL).find(|&l| self.resolution(l) >= resolution - 1e-12).unwrap_or(MAX_LEVEL)
    }
}

/// A tiled terrain: the generator and its cache of tiles.
#[derive(Clone, Debug)]
pub struct TiledTerrain {
    params: TiledParams,
    relief: Relief,
    cache: TileCache,
}

impl TiledTerrain {
    /// A tiled terrain holding at most `cache_tiles` tiles.
    pub fn new(params: TiledParams, cache_tiles: usize) -> Result<Self, TiledError> {
        params.check()?;
        let relief = Relief::new(&params.yard);
        Ok(Self { params, relief, cache: TileCache::new(cache_tiles) })
    }

    /// The parameters.
    pub fn params(&self) -> &TiledParams {
        &self.params
    }

    /// The tile of a key, generated unless cached.
    pub fn tile(&mut self, key: TileKey) -> Arc<Tile> {
        let key = TileKey { level: key.level.min(MAX_LEVEL), ..key };
        let (params, relief) = (&self.params, &self.relief);
        self.cache.get_or_insert_with(key, || tile::generate(params, relief, key))
    }

    /// Cache counters.
    pub fn cache_stats(&self) -> CacheStats {
        self.cache.stats()
    }

    /// The tile column (tx, ty) holding a point.
    pub fn tile_of(&self, x: f64, y: f64) -> (i64, i64) {
        let s = self.params.tile_size_m();
        ((x / s).floor() as i64, (y / s).floor() as i64)
    }

    /// Height at a point at a level (bilinear between cell centres, as `Dem::height`).
    pub fn height(&mut self, x: f64, y: f64, level: u8) -> Option<f64> {
        let res = self.params.resolution(level);
        let rect = LocalRect::centered(x, y, res);
        self.fill(rect, level).ok()?.dem.height(x, y)
    }

    /// The rocks whose footprints reach into a rectangle, tile by tile (row-major from the
    /// south-west), each tile's in its drawing order.
    pub fn rocks_in(&self, rect: LocalRect) -> Vec<Rock> {
        let r = 0.5 * self.params.yard.rocks.max_diameter_m;
        let (tx0, ty0) = self.tile_of(rect.x_min - r, rect.y_min - r);
        let (tx1, ty1) = self.tile_of(rect.x_max + r, rect.y_max + r);
        let mut rocks = Vec::new();
        for ty in ty0..=ty1 {
            for tx in tx0..=tx1 {
                rocks.extend(tile::tile_rocks(&self.params, tx, ty).into_iter().filter(|k| {
                    let h = 0.5 * k.diameter;
                    k.x + h > rect.x_min
                        && k.x - h < rect.x_max
                        && k.y + h > rect.y_min
                        && k.y - h < rect.y_max
                }));
            }
        }
        rocks
    }

    /// A terrain covering `rect` at a level: the cells of the level's lattice that overlap it,
    /// copied from the tiles, and the rocks reaching into it (none at levels too coarse for
    /// rocks). Its frame is the tiled terrain's (the grid origin is where the cells start).
    pub fn fill(&mut self, rect: LocalRect, level: u8) -> Result<Terrain, TiledError> {
        let level = level.min(MAX_LEVEL);
        let res = self.params.resolution(level);
        let finite = [rect.x_min, rect.y_min, rect.x_max, rect.y_max].iter().all(|v| v.is_finite());
        if !finite || rect.x_max <= rect.x_min || rect.y_max <= rect.y_min {
            return Err(TiledError::Invalid(format!("fill: empty or non-finite rectangle {rect:?}")));
        }
        let (c0, r0) = ((rect.x_min / res).floor() as i64, (rect.y_min / res).floor() as i64);
        let (c1, r1) = ((rect.x_max / res).ceil() as i64, (rect.y_max / res).ceil() as i64);
        let (cols, rows) = ((c1 - c0).max(1) as usize, (r1 - r0).max(1) as usize);
        if cols.saturating_mul(rows) > MAX_FILL_CELLS {
            return Err(TiledError::Invalid(format!(
                "fill: {cols} x {rows} cells at level {level} exceed {MAX_FILL_CELLS}"
            )));
        }
        let geometry = GridGeometry {
            cols,
            rows,
            resolution: res,
            origin_x: c0 as f64 * res,
            origin_y: r0 as f64 * res,
        };
        let mut data = vec![0.0f32; cols * rows];
        let n = self.params.cells_per_side(level) as i64;
        for ty in r0.div_euclid(n)..=(r0 + rows as i64 - 1).div_euclid(n) {
            for tx in c0.div_euclid(n)..=(c0 + cols as i64 - 1).div_euclid(n) {
                let tile = self.tile(TileKey { level, tx, ty });
                // The overlap of the tile's cells and the fill's, in global cell indices.
                let (gc0, gc1) = ((tx * n).max(c0), ((tx + 1) * n).min(c0 + cols as i64));
                let (gr0, gr1) = ((ty * n).max(r0), ((ty + 1) * n).min(r0 + rows as i64));
                let width = (gc1 - gc0) as usize;
                for gr in gr0..gr1 {
                    let src = ((gr - ty * n) * n + (gc0 - tx * n)) as usize;
                    let dst = (gr - r0) as usize * cols + (gc0 - c0) as usize;
                    data[dst..dst + width].copy_from_slice(&tile.dem.heights.data[src..src + width]);
                }
            }
        }
        let dem = Dem {
            heights: Grid2 { geometry, data },
            nodata: None,
            geo: GeoReference { crs: TILED_CRS.into(), easting: 0.0, northing: 0.0 },
        };
        let rocks = if self.params.shows_rocks(level) {
            self.rocks_in(LocalRect::from_corner_size(
                geometry.origin_x,
                geometry.origin_y,
                geometry.width_m(),
                geometry.height_m(),
            ))
        } else {
            Vec::new()
        };
        Ok(Terrain { dem, rocks })
    }
}
