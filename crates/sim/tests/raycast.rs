//! A ray never passes through terrain: random bumpy terrains and random rays, checked against
//! `Dem::height` sampled densely along the ray.

mod common;

use proptest::prelude::*;
use rovernav_core::{Grid2, GridGeometry};
use rovernav_sim::HeightField;
use rovernav_terrain::Dem;

fn bumpy(cols: usize, rows: usize, res: f64, amplitude: f64, seed: u64) -> Dem {
    let geometry = GridGeometry { cols, rows, resolution: res, origin_x: 1.5, origin_y: -2.0 };
    let mut s = seed | 1;
    let data = (0..cols * rows)
        .map(|_| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            ((s % 10_000) as f64 / 10_000.0 * amplitude) as f32
        })
        .collect();
    Dem::from_grid(Grid2 { geometry, data })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn ray_hits_the_surface_and_stays_above_it_before(
        cols in 2usize..30, rows in 2usize..30, res in 0.02f64..0.4, amplitude in 0.0f64..1.5,
        seed in any::<u64>(),
        fx in 0.0f64..1.0, fy in 0.0f64..1.0, above in 0.0f64..2.0,
        azimuth in -3.2f64..3.2, elevation in -1.5f64..0.6, max_range in 0.05f64..12.0,
    ) {
        let dem = bumpy(cols, rows, res, amplitude, seed);
        let g = *dem.geometry();
        let x = g.origin_x + fx * g.width_m();
        let y = g.origin_y + fy * g.height_m();
        let z = dem.height(x, y).expect("origin inside") + above;
        let dir = [elevation.cos() * azimuth.cos(), elevation.cos() * azimuth.sin(), elevation.sin()];
        let field = HeightField::new(&dem);
        let hit = field.cast(&dem, [x, y, z], dir, max_range);
        let end = hit.map_or(max_range, |h| h.range);
        if let Some(h) = hit {
            prop_assert!(h.range >= 0.0 && h.range <= max_range + 1e-9);
            let surface = dem.height(h.point[0], h.point[1]);
            prop_assert!(surface.is_some(), "hit off the DEM");
            prop_assert!((h.point[2] - surface.unwrap()).abs() < 1e-6,
                "hit {:?} is {} off the surface", h.point, h.point[2] - surface.unwrap());
        }
        // Every sample before the hit (or along the whole ray on a miss) is above the surface.
        let samples = 2000;
        for k in 0..samples {
            let t = end * k as f64 / samples as f64;
            let p = [x + dir[0] * t, y + dir[1] * t, z + dir[2] * t];
            if let Some(h) = dem.height(p[0], p[1]) {
                prop_assert!(p[2] >= h - 1e-7, "sample at t={t} is {} below the surface (hit {:?})", h - p[2], hit);
            }
        }
        // A miss that ended inside the DEM must have run its full range.
        if hit.is_none() {
            let p = [x + dir[0] * max_range, y + dir[1] * max_range];
            if dem.height(p[0], p[1]).is_some() && dem.height(x, y).is_some() {
                let q = [x + dir[0] * max_range, y + dir[1] * max_range, z + dir[2] * max_range];
                prop_assert!(q[2] >= dem.height(q[0], q[1]).unwrap() - 1e-7);
            }
        }
    }
}
