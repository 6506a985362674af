//! Terrain builders shared by the scenario tests: a flat DEM with rocks, steps and ramps added
//! to its heights.
#![allow(dead_code)]

use rovernav_core::{Grid2, GridGeometry};
use rovernav_terrain::{Dem, Rock, Terrain};

/// A flat terrain at height 0 of `size_m` square with cells of `res` metres.
pub fn flat(size_m: f64, res: f64) -> Terrain {
    let n = (size_m / res).round() as usize;
    Terrain { dem: Dem::flat(n, n, res, 0.0), rocks: Vec::new() }
}

/// Adds a dome-shaped rock (half-ellipsoid of the given diameter and height) to the heights.
pub fn add_rock(t: &mut Terrain, rock: Rock) {
    map_heights(&mut t.dem, |x, y, h| {
        let d = (x - rock.x).hypot(y - rock.y);
        let q = 2.0 * d / rock.diameter;
        if q < 1.0 { h + rock.height * (1.0 - q * q).sqrt() } else { h }
    });
    t.rocks.push(rock);
}

/// Raises everything east of `x0` by `height` (a vertical step, smeared over one cell by the
/// bilinear interpolation).
pub fn add_step(t: &mut Terrain, x0: f64, height: f64) {
    map_heights(&mut t.dem, |x, _, h| if x >= x0 { h + height } else { h });
}

/// A ramp rising to the east of `x0` at `angle` radians.
pub fn add_ramp(t: &mut Terrain, x0: f64, angle: f64) {
    map_heights(&mut t.dem, |x, _, h| h + (x - x0).max(0.0) * angle.tan());
}

/// A terrain that is a plane through the origin with the given gradient.
pub fn plane(size_m: f64, res: f64, gx: f64, gy: f64) -> Terrain {
    let mut t = flat(size_m, res);
    map_heights(&mut t.dem, |x, y, h| h + gx * x + gy * y);
    t
}

/// Applies `f(x, y, h)` at every cell centre.
pub fn map_heights(dem: &mut Dem, f: impl Fn(f64, f64, f64) -> f64) {
    let g: GridGeometry = *dem.geometry();
    let heights: &mut Grid2<f32> = &mut dem.heights;
    for r in 0..g.rows {
        for c in 0..g.cols {
            let (x, y) = g.center(c, r);
            let h = heights.get_mut(c, r);
            *h = f(x, y, *h as f64) as f32;
        }
    }
}

/// Sample standard deviation.
pub fn std_dev(v: &[f64]) -> f64 {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
}

/// Mean.
pub fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}
