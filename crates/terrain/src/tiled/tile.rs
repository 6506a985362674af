//! Generating one tile: everything in it is a function of the seed and the tile's index alone.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rovernav_core::{Grid2, GridGeometry};

use super::{TileKey, TiledParams};
use crate::dem::{Dem, GeoReference, Rock};
use crate::ops::LocalRect;
use crate::procedural::{
    Crater, PAD_CRATER_CLEARANCE, Relief, add_craters, add_rocks, sample_craters, sample_rocks,
};

/// Generator stream of a tile's craters.
const STREAM_CRATERS: u64 = 1;
/// Generator stream of a tile's rocks.
const STREAM_ROCKS: u64 = 2;

/// The splitmix64 finaliser.
fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// The generator of one purpose in one tile column (tx, ty): seeded from a hash of the terrain
/// seed and the index, so that no tile's draws depend on another's.
pub(crate) fn tile_rng(seed: u64, tx: i64, ty: i64, purpose: u64) -> ChaCha8Rng {
    let h = mix(seed ^ mix((tx as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ mix(ty as u64 ^ 0x632b_e59b)));
    let mut rng = ChaCha8Rng::seed_from_u64(h);
    rng.set_stream(purpose);
    rng
}

/// The rectangle of tile column (tx, ty) (m).
pub(crate) fn tile_rect(params: &TiledParams, tx: i64, ty: i64) -> LocalRect {
    let s = params.tile_size_m();
    LocalRect::from_corner_size(tx as f64 * s, ty as f64 * s, s, s)
}

/// The craters whose centres lie in tile column (tx, ty), those overlapping a clear pad dropped.
pub(crate) fn tile_craters(params: &TiledParams, tx: i64, ty: i64) -> Vec<Crater> {
    let yard = &params.yard;
    let rect = tile_rect(params, tx, ty);
    // `sample_craters` places centres up to one blanket radius outside the area it is given;
    // shrinking the area by that margin makes the centres fall in the tile itself.
    let margin = 2.5 * 0.5 * yard.crater_max_diameter_m;
    let inner = LocalRect {
        x_min: rect.x_min + margin,
        y_min: rect.y_min + margin,
        x_max: rect.x_max - margin,
        y_max: rect.y_max - margin,
    };
    let mut craters = sample_craters(yard, inner, &mut tile_rng(yard.seed, tx, ty, STREAM_CRATERS));
    craters.retain(|c| {
        yard.clear_pads
            .iter()
            .all(|p| (c.x - p.x).hypot(c.y - p.y) >= p.radius + PAD_CRATER_CLEARANCE * 0.5 * c.diameter)
    });
    craters
}

/// The rocks whose centres lie in tile column (tx, ty), those reaching into a clear pad dropped.
pub(crate) fn tile_rocks(params: &TiledParams, tx: i64, ty: i64) -> Vec<Rock> {
    let yard = &params.yard;
    let rect = tile_rect(params, tx, ty);
    let mut rng = tile_rng(yard.seed, tx, ty, STREAM_ROCKS);
    sample_rocks(&yard.rocks, rect, &yard.clear_pads, &mut rng)
}

/// A generated tile: its heights at its level's resolution (ground, craters and, at the levels
/// fine enough to show them, rocks) and the rocks whose centres it holds.
#[derive(Clone, Debug)]
pub struct Tile {
    /// Which tile.
    pub key: TileKey,
    /// Heights; the grid's origin is the tile's south-west corner in the terrain's frame.
    pub dem: Dem,
    /// Rocks whose centres lie in the tile (empty at levels too coarse for rocks).
    pub rocks: Vec<Rock>,
}

/// Generates a tile: relief sampled at the cell centres of the global lattice, plus the craters
/// and rocks of every tile close enough to reach into it, in a fixed order of tiles.
pub(crate) fn generate(params: &TiledParams, relief: &Relief, key: TileKey) -> Tile {
    let n = params.cells_per_side(key.level);
    let res = params.resolution(key.level);
    let (gx0, gy0) = (key.tx * n as i64, key.ty * n as i64);
    let geometry = GridGeometry {
        cols: n,
        rows: n,
        resolution: res,
        origin_x: gx0 as f64 * res,
        origin_y: gy0 as f64 * res,
    };
    let mut data = Vec::with_capacity(n * n);
    for r in 0..n {
        let y = ((gy0 + r as i64) as f64 + 0.5) * res;
        for c in 0..n {
            let x = ((gx0 + c as i64) as f64 + 0.5) * res;
            data.push(relief.height(x, y) as f32);
        }
    }
    let mut dem = Dem {
        heights: Grid2 { geometry, data },
        nodata: None,
        geo: GeoReference { crs: TILED_CRS.into(), easting: 0.0, northing: 0.0 },
    };
    let ring = params.crater_ring();
    let mut craters = Vec::new();
    for ty in key.ty - ring..=key.ty + ring {
        for tx in key.tx - ring..=key.tx + ring {
            craters.extend(tile_craters(params, tx, ty));
        }
    }
    add_craters(&mut dem, &craters);
    let mut rocks = Vec::new();
    if params.shows_rocks(key.level) {
        let mut near = Vec::new();
        for ty in key.ty - 1..=key.ty + 1 {
            for tx in key.tx - 1..=key.tx + 1 {
                let these = tile_rocks(params, tx, ty);
                if (tx, ty) == (key.tx, key.ty) {
                    rocks = these.clone();
                }
                near.extend(these);
            }
        }
        add_rocks(&mut dem, &near);
    }
    Tile { key, dem, rocks }
}

/// Coordinate reference text of tiled terrain.
pub const TILED_CRS: &str = "local (procedural tiled terrain)";
