//! Tiled terrain: deterministic whatever the order tiles are generated in, seamless across tile
//! borders, the same relief as a whole yard, and a bounded cache.

use proptest::prelude::*;
use rovernav_terrain::procedural::{self, MarsYardParams, RockFieldParams};
use rovernav_terrain::tiled::{TileKey, TiledParams, TiledTerrain};
use rovernav_terrain::{Dem, LocalRect};

/// Small tiles (3.2 m at 5 cm) so that a debug test crosses many borders quickly.
fn small_params(seed: u64) -> TiledParams {
    let yard = MarsYardParams {
        seed,
        crater_density: 0.02,
        crater_max_diameter_m: 4.0,
        rocks: RockFieldParams { abundance: 0.2, ..Default::default() },
        ..MarsYardParams::default()
    };
    TiledParams::new(yard, 64).unwrap()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// Heights and rocks at a point are the same whichever order the tiles around it were
    /// generated in, with a cold cache or a warm one that has evicted and regenerated tiles.
    #[test]
    fn heights_and_rocks_do_not_depend_on_generation_order(
        seed in 0u64..1000,
        x in -20.0f64..20.0,
        y in -20.0f64..20.0,
        order in proptest::collection::vec((-4i64..4, -4i64..4), 1..12),
    ) {
        let params = small_params(seed);
        let mut cold = TiledTerrain::new(params.clone(), 4).unwrap();
        let mut warm = TiledTerrain::new(params, 3).unwrap();
        for &(tx, ty) in &order {
            let _ = warm.tile(TileKey { level: 0, tx, ty });
        }
        let area = LocalRect::centered(x, y, 0.6);
        let a = cold.fill(area, 0).unwrap();
        let _ = warm.tile(TileKey { level: 0, tx: 9, ty: 9 });
        let b = warm.fill(area, 0).unwrap();
        prop_assert_eq!(a.dem.heights.geometry, b.dem.heights.geometry);
        prop_assert!(a.dem.heights.data.iter().zip(&b.dem.heights.data).all(|(p, q)| p.to_bits() == q.to_bits()));
        prop_assert_eq!(&a.rocks, &b.rocks);
        prop_assert_eq!(cold.height(x, y, 0).map(f64::to_bits), warm.height(x, y, 0).map(f64::to_bits));
        prop_assert!(warm.cache_stats().held <= 3);
    }
}

#[test]
fn relief_is_the_whole_yards_cell_for_cell() {
    // Without craters and rocks a tiled terrain and a yard of the same seed sample the same
    // relief function at the same cell centres.
    let yard = MarsYardParams {
        width_m: 9.6,
        height_m: 6.4,
        seed: 5,
        crater_density: 0.0,
        rocks: RockFieldParams { abundance: 0.0, ..Default::default() },
        ..MarsYardParams::default()
    };
    let whole = procedural::generate_ground(&yard);
    let mut tiled = TiledTerrain::new(TiledParams::new(yard, 64).unwrap(), 16).unwrap();
    let filled = tiled.fill(LocalRect::from_corner_size(0.0, 0.0, 9.6, 6.4), 0).unwrap();
    assert_eq!(filled.dem.heights.geometry, whole.heights.geometry);
    assert_eq!(filled.dem.heights.data, whole.heights.data);
}

#[test]
fn rocks_belong_to_the_tile_of_their_centre_and_shape_both_sides_of_a_border() {
    let params = small_params(3);
    let s = params.tile_size_m();
    let mut t = TiledTerrain::new(params, 32).unwrap();
    let area = LocalRect::from_corner_size(-2.0 * s, -2.0 * s, 4.0 * s, 4.0 * s);
    let terrain = t.fill(area, 0).unwrap();
    let ground = t.params().yard.clone();
    let bare = {
        let no_rocks =
            MarsYardParams { rocks: RockFieldParams { abundance: 0.0, ..Default::default() }, ..ground };
        let mut b = TiledTerrain::new(TiledParams::new(no_rocks, 64).unwrap(), 32).unwrap();
        b.fill(area, 0).unwrap().dem
    };
    let mut straddling = 0;
    for rock in &terrain.rocks {
        let key = t.tile_of(rock.x, rock.y);
        assert!(t.tile(TileKey { level: 0, tx: key.0, ty: key.1 }).rocks.contains(rock));
        // A rock across a vertical border raises the ground on both sides of it.
        let border = (rock.x / s).round() * s;
        let r = 0.5 * rock.diameter;
        if rock.diameter > 0.25
            && (rock.x - border).abs() < 0.5 * r
            && rock.y.abs() < 2.0 * s - r
            && rock.x.abs() < 2.0 * s - r
        {
            straddling += 1;
            for side in [-1.0, 1.0] {
                let x = border + side * 0.05;
                let raise = terrain.dem.height(x, rock.y).unwrap() - bare.height(x, rock.y).unwrap();
                let dome = rock.height * (1.0 - ((x - rock.x) / r).powi(2)).max(0.0).sqrt();
                assert!(raise >= 0.8 * dome - 0.01, "rock {rock:?}: {raise} m raised at x {x}, dome {dome}");
            }
        }
    }
    assert!(straddling > 0, "no rock straddles a border: choose another seed");
}

/// Height differences between horizontally adjacent cells (m per cell): the pairs that straddle
/// a tile border, and the pairs a few cells to either side inside the tiles (the same rows and
/// nearly the same large-scale relief, so only a seam can tell them apart).
fn slopes(dem: &Dem, tile_cells: usize) -> (Vec<f64>, Vec<f64>) {
    let g = dem.heights.geometry;
    let first = (g.origin_x / g.resolution).round() as i64;
    let (mut border, mut inside) = (Vec::new(), Vec::new());
    for r in 0..g.rows {
        for c in 0..g.cols - 1 {
            let d = (*dem.heights.get(c + 1, r) - *dem.heights.get(c, r)).abs() as f64;
            match (first + c as i64 + 1).rem_euclid(tile_cells as i64) {
                0 => border.push(d),
                3 | 6 | 9 => inside.push(d),
                k if k == tile_cells as i64 - 3
                    || k == tile_cells as i64 - 6
                    || k == tile_cells as i64 - 9 =>
                {
                    inside.push(d)
                }
                _ => {}
            }
        }
    }
    (border, inside)
}

/// Two-sample Kolmogorov-Smirnov statistic.
fn ks(mut a: Vec<f64>, mut b: Vec<f64>) -> f64 {
    a.sort_by(f64::total_cmp);
    b.sort_by(f64::total_cmp);
    let (mut i, mut j, mut d) = (0, 0, 0.0f64);
    while i < a.len() && j < b.len() {
        let v = a[i].min(b[j]);
        while i < a.len() && a[i] <= v {
            i += 1;
        }
        while j < b.len() && b[j] <= v {
            j += 1;
        }
        d = d.max((i as f64 / a.len() as f64 - j as f64 / b.len() as f64).abs());
    }
    d
}

/// The KS critical value at significance 0.001 for samples of sizes n and m.
fn ks_critical(n: usize, m: usize) -> f64 {
    let (n, m) = (n as f64, m as f64);
    1.949 * ((n + m) / (n * m)).sqrt()
}

#[test]
fn the_slope_across_a_tile_border_is_distributed_like_the_slope_inside() {
    let params = small_params(11);
    let s = params.tile_size_m();
    let mut t = TiledTerrain::new(params, 64).unwrap();
    let terrain = t.fill(LocalRect::from_corner_size(-4.0 * s, -3.0 * s, 8.0 * s, 6.0 * s), 0).unwrap();
    let (border, inside) = slopes(&terrain.dem, 64);
    let (n, m) = (border.len(), inside.len());
    let d = ks(border, inside);
    eprintln!("tiled: KS {d:.4}, critical {:.4} (n {n}, m {m})", ks_critical(n, m));
    assert!(d < ks_critical(n, m), "KS {d:.4} >= {:.4} (n {n}, m {m})", ks_critical(n, m));

    // The test sees a seam: tiles each generated as an independent yard (what a tiler that
    // ignores its neighbours would make) differ across borders.
    let yard = t.params().yard.clone();
    let mut seamed = terrain.dem.clone();
    for ty in -3..3i64 {
        for tx in -4..4i64 {
            let own = procedural::generate(&MarsYardParams {
                width_m: s,
                height_m: s,
                seed: (ty * 100 + tx) as u64,
                ..yard.clone()
            });
            let (c0, r0) = (((tx + 4) * 64) as usize, ((ty + 3) * 64) as usize);
            for r in 0..64 {
                for c in 0..64 {
                    *seamed.heights.get_mut(c0 + c, r0 + r) = *own.dem.heights.get(c, r);
                }
            }
        }
    }
    let (border, inside) = slopes(&seamed, 64);
    let (n, m) = (border.len(), inside.len());
    let d = ks(border, inside);
    eprintln!("seamed: KS {d:.4}, critical {:.4} (n {n}, m {m})", ks_critical(n, m));
    assert!(d > ks_critical(n, m), "the seamed terrain passes: KS {d:.4} (n {n}, m {m})");
}

#[test]
fn coarse_levels_sample_the_same_ground_and_drop_rocks() {
    let params = small_params(2);
    let mut t = TiledTerrain::new(params, 32).unwrap();
    let area = LocalRect::from_corner_size(-6.4, -6.4, 12.8, 12.8);
    let fine = t.fill(area, 0).unwrap();
    let coarse = t.fill(area, 3).unwrap();
    assert!((coarse.dem.heights.geometry.resolution - 0.4).abs() < 1e-12);
    assert!(coarse.rocks.is_empty() && !fine.rocks.is_empty());
    // Away from rocks a coarse cell centre's height is the fine terrain's there (same
    // function, bilinear in between): compare at coarse centres clear of every rock.
    let g = coarse.dem.heights.geometry;
    let mut compared = 0;
    for r in 1..g.rows - 1 {
        for c in 1..g.cols - 1 {
            let (x, y) = g.center(c, r);
            if fine.rocks.iter().any(|k| (k.x - x).hypot(k.y - y) < 0.5 * k.diameter + 0.1) {
                continue;
            }
            let (a, b) = (*coarse.dem.heights.get(c, r) as f64, fine.dem.height(x, y).unwrap());
            assert!((a - b).abs() < 0.01, "({x}, {y}): coarse {a} fine {b}");
            compared += 1;
        }
    }
    assert!(compared > 200, "{compared}");
}

#[test]
fn bad_parameters_are_refused_with_the_reason() {
    let yard = MarsYardParams::default();
    let e = TiledParams::new(yard.clone(), 100).unwrap_err().to_string();
    assert!(e.contains("tile_cells"), "{e}");
    let e = TiledParams::new(MarsYardParams { resolution: f64::NAN, ..yard }, 64).unwrap_err().to_string();
    assert!(e.contains("resolution"), "{e}");
    let mut t = TiledTerrain::new(small_params(1), 4).unwrap();
    assert!(t.fill(LocalRect::from_corner_size(0.0, 0.0, f64::NAN, 1.0), 0).is_err());
    assert!(t.fill(LocalRect::from_corner_size(0.0, 0.0, 1e6, 1e6), 0).is_err());
}
