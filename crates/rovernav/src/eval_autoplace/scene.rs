//! Generated AutoPlace scenes: a patch of ground in front of the rover with rocks of different
//! sizes and tilts, a commanded target, the time of day (long shadows early and late), and
//! stereo dropouts (regions whose pixels carry no texture, as in deep shadow or glare).
//!
//! The rover stands at the world origin, level, facing +x: its body frame is the world frame
//! (the ground under it is at height 0; the body is not drawn, so its exact settling does not
//! matter).

use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rovernav_core::{Grid2, GridGeometry};
use rovernav_terrain::{Dem, Rock, Terrain};

/// What a scene tests.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, PartialOrd, Ord)]
#[serde(rename_all = "snake_case")]
pub enum Kind {
    /// The target is the top of a rock.
    Rock,
    /// The target is soil between rocks.
    Soil,
    /// The target is 0.70-0.86 m from the arm's azimuth axis (reach 0.785 m).
    EdgeOfReach,
    /// A stereo dropout covers the target.
    Dropout,
    /// A stereo dropout hides a rock in the arm's path to a visible target.
    HiddenRock,
}

impl Kind {
    /// The kind's name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Kind::Rock => "rock",
            Kind::Soil => "soil",
            Kind::EdgeOfReach => "edge_of_reach",
            Kind::Dropout => "dropout",
            Kind::HiddenRock => "hidden_rock",
        }
    }
}

/// A region whose pixels carry no texture in every image: every pixel whose surface point lies
/// within `radius` (horizontally) of `centre`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hole {
    /// Centre (world x, y, m).
    pub centre: [f64; 2],
    /// Radius (m).
    pub radius: f64,
}

/// One rock's shape: an elliptical footprint with a tilted flat top and a rounded rim.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Slab {
    /// Centre (m).
    pub centre: [f64; 2],
    /// Semi-axes (m).
    pub semi: [f64; 2],
    /// Orientation of the first semi-axis (rad).
    pub orientation: f64,
    /// Height of the top at the centre (m).
    pub height: f64,
    /// Top slope (rise per metre) along `tilt_dir`.
    pub slope: f64,
    /// Direction of the top's slope (rad).
    pub tilt_dir: f64,
}

impl Slab {
    /// Height the rock adds at (x, y).
    pub fn height_at(&self, x: f64, y: f64) -> f64 {
        let (dx, dy) = (x - self.centre[0], y - self.centre[1]);
        let (s, c) = self.orientation.sin_cos();
        let (u, v) = (c * dx + s * dy, -s * dx + c * dy);
        let rho = ((u / self.semi[0]).powi(2) + (v / self.semi[1]).powi(2)).sqrt();
        if rho >= 1.0 {
            return 0.0;
        }
        let (st, ct) = self.tilt_dir.sin_cos();
        let top = (self.height + self.slope * (ct * dx + st * dy)).max(0.01);
        if rho < 0.75 {
            top
        } else {
            let t = (1.0 - rho) / 0.25;
            top * t * t * (3.0 - 2.0 * t)
        }
    }
}

/// A generated scene.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Its seed.
    pub seed: u64,
    /// What it tests.
    pub kind: Kind,
    /// The ground without rocks, and the rocks.
    pub base: Dem,
    /// The rocks' shapes.
    pub slabs: Vec<Slab>,
    /// The commanded target (body frame, m).
    pub target: Vector3<f64>,
    /// Stereo dropouts.
    pub holes: Vec<Hole>,
    /// Local true solar time (h).
    pub local_time_h: f64,
}

/// Grid of the scene's DEM: 1 cm cells from 1 m behind to 3.5 m ahead, 1.5 m either side.
fn geometry() -> GridGeometry {
    GridGeometry { cols: 450, rows: 300, resolution: 0.01, origin_x: -1.0, origin_y: -1.5 }
}

impl Scene {
    /// The terrain (rocks added to the base).
    pub fn terrain(&self) -> Terrain {
        let mut dem = self.base.clone();
        let g = *dem.geometry();
        for r in 0..g.rows {
            for c in 0..g.cols {
                let (x, y) = (
                    g.origin_x + (c as f64 + 0.5) * g.resolution,
                    g.origin_y + (r as f64 + 0.5) * g.resolution,
                );
                let add: f64 = self.slabs.iter().map(|s| s.height_at(x, y)).fold(0.0, f64::max);
                if add > 0.0 {
                    *dem.heights.get_mut(c, r) += add as f32;
                }
            }
        }
        let rocks = self
            .slabs
            .iter()
            .map(|s| Rock {
                x: s.centre[0],
                y: s.centre[1],
                diameter: 2.0 * s.semi[0].max(s.semi[1]),
                height: s.height,
            })
            .collect();
        Terrain { dem, rocks }
    }

    /// Height of the base ground at (x, y).
    pub fn ground(&self, x: f64, y: f64) -> f64 {
        self.base.height(x, y).unwrap_or(0.0)
    }
}

/// A random rock centred at (x, y).
fn random_slab(rng: &mut ChaCha8Rng, x: f64, y: f64) -> Slab {
    let a = rng.random_range(0.06..0.16);
    Slab {
        centre: [x, y],
        semi: [a, a * rng.random_range(0.6..1.0)],
        orientation: rng.random_range(0.0..std::f64::consts::PI),
        height: rng.random_range(0.04..0.18),
        slope: rng.random_range(0.0f64..35.0).to_radians().tan(),
        tilt_dir: rng.random_range(-std::f64::consts::PI..std::f64::consts::PI),
    }
}

/// Generates the scene of `seed`; `arm_base` is the arm's azimuth axis (x, y).
pub fn generate(seed: u64, arm_base: [f64; 2]) -> Scene {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0xA17E_91AC_E000_0000);
    let kind = match rng.random_range(0..20) {
        0..7 => Kind::Rock,
        7..10 => Kind::Soil,
        10..14 => Kind::EdgeOfReach,
        14..17 => Kind::Dropout,
        _ => Kind::HiddenRock,
    };
    let g = geometry();
    let (sx, sy) = (rng.random_range(-0.05..0.05), rng.random_range(-0.05..0.05));
    let (amp, kx, ky, p1, p2) = (
        rng.random_range(0.0..0.02),
        rng.random_range(4.0..10.0),
        rng.random_range(4.0..10.0),
        rng.random_range(0.0..6.3),
        rng.random_range(0.0..6.3),
    );
    let wave = |x: f64, y: f64| sx * x + sy * y + amp * (kx * x + p1).sin() * (ky * y + p2).sin();
    let z0 = wave(0.0, 0.0);
    let mut heights = Grid2::filled(g, 0f32);
    for r in 0..g.rows {
        for c in 0..g.cols {
            let (x, y) =
                (g.origin_x + (c as f64 + 0.5) * g.resolution, g.origin_y + (r as f64 + 0.5) * g.resolution);
            *heights.get_mut(c, r) = (wave(x, y) - z0) as f32;
        }
    }
    let base = Dem::from_grid(heights);
    let mut slabs: Vec<Slab> = Vec::new();
    for _ in 0..rng.random_range(1..=4) {
        for _ in 0..20 {
            let (x, y) = (rng.random_range(0.7..1.4), rng.random_range(-0.5..0.4));
            let s = random_slab(&mut rng, x, y);
            let clear = slabs.iter().all(|o| {
                let d = (o.centre[0] - s.centre[0]).hypot(o.centre[1] - s.centre[1]);
                d > o.semi[0].max(o.semi[1]) + s.semi[0].max(s.semi[1]) + 0.05
            });
            if clear {
                slabs.push(s);
                break;
            }
        }
    }
    let local_time_h = rng.random_range(8.0..17.0);
    let on_rock = |rng: &mut ChaCha8Rng, slabs: &[Slab]| {
        let s = slabs[rng.random_range(0..slabs.len())];
        [s.centre[0] + rng.random_range(-0.02..0.02), s.centre[1] + rng.random_range(-0.02..0.02)]
    };
    let on_soil = |rng: &mut ChaCha8Rng, slabs: &[Slab], xr: std::ops::Range<f64>| {
        for _ in 0..50 {
            let p = [rng.random_range(xr.clone()), rng.random_range(-0.4..0.3)];
            if slabs
                .iter()
                .all(|s| (s.centre[0] - p[0]).hypot(s.centre[1] - p[1]) > s.semi[0].max(s.semi[1]) + 0.08)
            {
                return p;
            }
        }
        [xr.start, -0.45]
    };
    let mut holes = Vec::new();
    let xy = match kind {
        Kind::Rock => on_rock(&mut rng, &slabs),
        Kind::Soil => on_soil(&mut rng, &slabs, 0.75..1.15),
        Kind::EdgeOfReach => {
            let r = rng.random_range(0.70..0.86);
            let az = rng.random_range(-35f64..35.0).to_radians();
            [arm_base[0] + r * az.cos(), arm_base[1] + r * az.sin()]
        }
        Kind::Dropout => {
            let p = if rng.random_bool(0.5) {
                on_rock(&mut rng, &slabs)
            } else {
                on_soil(&mut rng, &slabs, 0.75..1.15)
            };
            holes.push(Hole { centre: p, radius: rng.random_range(0.13..0.2) });
            p
        }
        // The hidden rock and its hole are placed once the arm's path is known.
        Kind::HiddenRock => on_soil(&mut rng, &slabs, 0.95..1.2),
    };
    let mut scene = Scene { seed, kind, base, slabs, target: Vector3::zeros(), holes, local_time_h };
    let terrain = scene.terrain();
    let z = terrain.dem.height(xy[0], xy[1]).unwrap_or(0.0) + rng.random_range(-0.01..0.01);
    scene.target = Vector3::new(xy[0], xy[1], z);
    scene
}

/// Hides a rock under the point `p` of the arm's path (x, y, and the arm's lowest point there,
/// z): a rock rising `above` metres higher than that point, inside a dropout wide enough that no
/// camera sees any of it.
pub fn hide_rock(scene: &mut Scene, p: [f64; 3], above: f64) {
    let ground = scene.ground(p[0], p[1]);
    let height = (p[2] - ground + above).clamp(0.05, 0.45);
    scene.slabs.retain(|s| (s.centre[0] - p[0]).hypot(s.centre[1] - p[1]) > s.semi[0].max(s.semi[1]) + 0.1);
    scene.slabs.push(Slab {
        centre: [p[0], p[1]],
        semi: [0.06, 0.06],
        orientation: 0.0,
        height,
        slope: 0.0,
        tilt_dir: 0.0,
    });
    scene.holes.push(Hole { centre: [p[0], p[1]], radius: 0.12 });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scenes_are_deterministic_and_every_kind_occurs() {
        let a = generate(5, [0.5, -0.12]);
        let b = generate(5, [0.5, -0.12]);
        assert_eq!(a.target, b.target);
        assert_eq!(a.slabs, b.slabs);
        let kinds: std::collections::HashSet<Kind> =
            (0..60).map(|s| generate(s, [0.5, -0.12]).kind).collect();
        assert_eq!(kinds.len(), 5);
        // A slab's top at its centre is its height; outside the footprint it adds nothing.
        let s = a.slabs[0];
        assert!((s.height_at(s.centre[0], s.centre[1]) - s.height.max(0.01)).abs() < 1e-12);
        assert_eq!(s.height_at(s.centre[0] + 0.5, s.centre[1]), 0.0);
    }
}
