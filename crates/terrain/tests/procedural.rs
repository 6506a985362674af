//! Procedural terrain scenarios: rock statistics against Golombek-Rapp, determinism, rocks as
//! bodies in the DEM, clear pads, regional slope, and rocks on the real Gale DEM.

use std::f64::consts::PI;

use rovernav_core::data_file_or_skip;
use rovernav_terrain::procedural::{
    self, ClearPad, MarsYardParams, RockFieldParams, RockyRegionParams, generate_ground, sample_rocks_seeded,
};
use rovernav_terrain::{LocalRect, Rock, Terrain, io};

/// Integral of f over [a, b] by the midpoint rule.
fn integrate(a: f64, b: f64, f: impl Fn(f64) -> f64) -> f64 {
    let n = 20_000;
    let h = (b - a) / n as f64;
    (0..n).map(|i| f(a + (i as f64 + 0.5) * h)).sum::<f64>() * h
}

#[test]
fn rock_fractional_area_follows_golombek_rapp() {
    let params = RockFieldParams::default();
    let (k, d_max) = (params.abundance, params.max_diameter_m);
    let q = 1.79 + 0.152 / k;
    let side = 200.0;
    let area = side * side;
    let rocks = sample_rocks_seeded(&params, LocalRect::from_corner_size(0.0, 0.0, side, side), &[], 2024);
    for d in [0.3, 0.5, 1.0] {
        let covered: f64 =
            rocks.iter().filter(|r| r.diameter >= d).map(|r| PI * r.diameter * r.diameter / 4.0).sum::<f64>()
                / area;
        // F(D) = k exp(-q D), less what lies beyond the largest diameter modelled.
        let expected = k * ((-q * d).exp() - (-q * d_max).exp());
        // A compound Poisson sum: its variance is the integral of dN/dD times the squared area
        // of a rock, divided by the area twice.
        let variance = integrate(d, d_max, |x| k * q * (-q * x).exp() * PI * x * x / 4.0) / area;
        let sigma = variance.sqrt();
        assert!(
            (covered - expected).abs() < 4.0 * sigma,
            "D >= {d}: {covered:.5} vs {expected:.5} (sigma {sigma:.5})"
        );
        assert!(sigma < 0.1 * expected, "test too weak at D >= {d}");
    }
    // The count is Poisson with the integral of dN/dD as its mean.
    let mean =
        area * integrate(params.min_diameter_m, d_max, |x| k * q * (-q * x).exp() / (PI * x * x / 4.0));
    assert!(
        (rocks.len() as f64 - mean).abs() < 4.0 * mean.sqrt(),
        "{} rocks, expected {mean:.0}",
        rocks.len()
    );
    for r in &rocks {
        assert!((0.1..=2.0).contains(&r.diameter));
        assert!((0.4 * r.diameter..=0.6 * r.diameter).contains(&r.height));
    }
}

#[test]
fn generation_is_deterministic_per_seed() {
    let params = MarsYardParams { width_m: 8.0, height_m: 6.0, ..MarsYardParams::with_seed(42) };
    let a = procedural::generate(&params);
    let b = procedural::generate(&params);
    assert_eq!(a, b);
    let c = procedural::generate(&MarsYardParams { seed: 43, ..params });
    assert_ne!(a.dem.heights.data, c.dem.heights.data);
    assert_ne!(a.rocks, c.rocks);
}

/// Rocks whose top (8 cm around the centre) no other rock reaches.
fn isolated(rocks: &[Rock], min_diameter: f64) -> Vec<Rock> {
    rocks
        .iter()
        .filter(|r| r.diameter >= min_diameter)
        .filter(|r| {
            rocks
                .iter()
                .all(|o| std::ptr::eq(*r, o) || (r.x - o.x).hypot(r.y - o.y) > 0.5 * o.diameter + 0.08)
        })
        .copied()
        .collect()
}

#[test]
fn rocks_stand_on_the_ground_in_the_dem() {
    let params = MarsYardParams { width_m: 20.0, height_m: 20.0, ..MarsYardParams::with_seed(7) };
    let terrain = procedural::generate(&params);
    let ground = generate_ground(&params);
    assert_eq!(terrain.dem.geometry(), ground.geometry());
    let g = terrain.dem.geometry();
    let inside = |r: &Rock| r.x > 0.5 && r.y > 0.5 && r.x < g.width_m() - 0.5 && r.y < g.height_m() - 0.5;
    let rocks: Vec<Rock> = isolated(&terrain.rocks, 0.4).into_iter().filter(inside).collect();
    assert!(rocks.len() >= 30, "only {} isolated rocks", rocks.len());
    for r in &rocks {
        let top = terrain.dem.height(r.x, r.y).unwrap() - ground.height(r.x, r.y).unwrap();
        // Cell centres lie within 3.6 cm of the rock centre; the dome drops by under 7 %
        // there for D >= 0.4 m.
        assert!(top <= r.height * 1.001 && top > 0.92 * r.height, "rock {r:?}: {top}");
    }
}

#[test]
fn clear_pads_have_bare_ground() {
    let params = MarsYardParams::with_seed(9).clear_around(3.0, 3.0, 1.0).clear_around(27.0, 27.0, 1.0);
    let terrain = procedural::generate(&params);
    let ground = generate_ground(&params);
    for pad in &params.clear_pads {
        for r in &terrain.rocks {
            assert!((r.x - pad.x).hypot(r.y - pad.y) >= pad.radius + 0.5 * r.diameter);
        }
        let g = terrain.dem.geometry();
        for row in 0..g.rows {
            for col in 0..g.cols {
                let (x, y) = g.center(col, row);
                if (x - pad.x).hypot(y - pad.y) < pad.radius {
                    assert_eq!(terrain.dem.heights.get(col, row), ground.heights.get(col, row));
                }
            }
        }
    }
    // The default yard: 30 m at 5 cm, rocks everywhere else.
    assert_eq!((terrain.dem.geometry().cols, terrain.dem.geometry().rows), (600, 600));
    let expected = RockFieldParams::default().expected_density() * 900.0;
    assert!((terrain.rocks.len() as f64 - expected).abs() < 0.1 * expected);
}

#[test]
fn clear_pads_are_outside_crater_bowls_and_rims() {
    // With craters switched off the ground is the same relief; under a pad, craters may add
    // only distant ejecta (at most ~1 % of the largest diameter), never a bowl (-0.2 D).
    let largest = MarsYardParams::default().crater_max_diameter_m;
    for seed in 1..=40 {
        let params = MarsYardParams { crater_density: 0.02, ..MarsYardParams::with_seed(seed) }
            .clear_around(4.0, 4.0, 1.0)
            .clear_around(19.0, 19.0, 1.0);
        let with = generate_ground(&params);
        let without = generate_ground(&MarsYardParams { crater_density: 0.0, ..params.clone() });
        let g = with.geometry();
        for pad in &params.clear_pads {
            for row in 0..g.rows {
                for col in 0..g.cols {
                    let (x, y) = g.center(col, row);
                    if (x - pad.x).hypot(y - pad.y) < pad.radius {
                        let dz = (with.heights.get(col, row) - without.heights.get(col, row)).abs() as f64;
                        assert!(
                            dz <= 0.0106 * largest,
                            "seed {seed} pad {pad:?}: crater changes height by {dz}"
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn regional_slope_is_the_fitted_plane() {
    let params = MarsYardParams {
        width_m: 20.0,
        height_m: 20.0,
        resolution: 0.1,
        relief_amplitude_m: 0.02,
        ridge_amplitude_m: 0.0,
        crater_density: 0.0,
        regional_slope_deg: 5.0,
        slope_azimuth_deg: 90.0, // uphill to the north
        rocks: RockFieldParams { abundance: 0.0, ..RockFieldParams::default() },
        ..MarsYardParams::with_seed(1)
    };
    let terrain = procedural::generate(&params);
    assert!(terrain.rocks.is_empty());
    // Least-squares plane z = a + b x + c y over all cells (normal equations on centred data).
    let g = terrain.dem.geometry();
    let (mut n, mut sx, mut sy, mut sz) = (0.0, 0.0, 0.0, 0.0);
    for row in 0..g.rows {
        for col in 0..g.cols {
            let (x, y) = g.center(col, row);
            n += 1.0;
            sx += x;
            sy += y;
            sz += *terrain.dem.heights.get(col, row) as f64;
        }
    }
    let (mx, my, mz) = (sx / n, sy / n, sz / n);
    let (mut sxx, mut syy, mut sxz, mut syz) = (0.0, 0.0, 0.0, 0.0);
    for row in 0..g.rows {
        for col in 0..g.cols {
            let (x, y) = g.center(col, row);
            let z = *terrain.dem.heights.get(col, row) as f64 - mz;
            sxx += (x - mx) * (x - mx);
            syy += (y - my) * (y - my);
            sxz += (x - mx) * z;
            syz += (y - my) * z;
        }
    }
    // The grid is symmetric, so x and y decouple.
    let (b, c) = (sxz / sxx, syz / syy);
    assert!(b.abs() < 0.005, "east gradient {b}");
    assert!((c - 5f64.to_radians().tan()).abs() < 0.005, "north gradient {c}");
}

#[test]
fn rocks_on_the_gale_dem() {
    let Some(path) = data_file_or_skip("gale/missionDEM.tif") else { return };
    let gale = io::load_geotiff(&path).unwrap();
    let (x, y) = gale.to_local(8_142_579.427, -276_693.318); // Curiosity on sol 1051
    let mut params = RockyRegionParams::around(x, y, 10.0, 5);
    params.clear_pads.push(ClearPad { x, y, radius: 1.5 });
    let terrain = procedural::rocky_region(&gale, &params).unwrap();
    let g = terrain.dem.geometry();
    // 1 m cells snapped outwards from a 20 m square: 21 m (or 20 m) at 5 cm.
    assert!((400..=420).contains(&g.cols) && (400..=420).contains(&g.rows), "{g:?}");
    assert_eq!(g.resolution, 0.05);
    // The rover's spot is rock-free: the DEM there is the Gale surface plus micro-relief.
    let z = terrain.dem.height(x, y).unwrap();
    assert!((z - gale.height(x, y).unwrap()).abs() <= params.micro_relief_m + 0.01, "{z}");
    assert!(terrain.rocks.iter().all(|r| (r.x - x).hypot(r.y - y) >= 1.5 + 0.5 * r.diameter));
    let covered: f64 = terrain.rocks.iter().map(|r| PI * r.diameter * r.diameter / 4.0).sum::<f64>();
    let fraction = covered / (g.width_m() * g.height_m());
    assert!((0.05..0.25).contains(&fraction), "rock cover {fraction}");
    // Rebasing keeps every rock on the same projected spot.
    let projected: Vec<(f64, f64)> =
        terrain.rocks.iter().map(|r| terrain.dem.to_projected(r.x, r.y)).collect();
    let rebased: Terrain = terrain.rebased();
    assert_eq!(rebased.dem.geometry().origin_x, 0.0);
    for (r, (e, n)) in rebased.rocks.iter().zip(projected) {
        let (pe, pn) = rebased.dem.to_projected(r.x, r.y);
        assert!((pe - e).abs() < 1e-6 && (pn - n).abs() < 1e-6);
    }
}
