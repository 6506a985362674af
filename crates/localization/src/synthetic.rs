//! Synthetic terrain and stereo-like range data for testing the matchers and estimators.
//!
//! Terrain: fractal relief (octaves of smoothly interpolated random lattices whose amplitude
//! halves with each doubling of frequency), Gaussian bumps, and rocks as half-ellipsoids with
//! many small and few large ones. Range data: rays cast from a mast camera over a field of view
//! onto the height field, with the range error growing with the square of the range, as for
//! stereo (disparity error is constant, so depth error grows as range^2 / (baseline * focal)).
//! Everything is deterministic for a seed.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use rovernav_core::{Grid2, GridGeometry, Pose3};

/// Shape parameters of a synthetic terrain.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TerrainParams {
    /// Side of the square terrain (m).
    pub size: f64,
    /// Cell size of the height field (m).
    pub resolution: f64,
    /// Amplitude of the coarsest relief octave (m).
    pub relief: f64,
    /// Wavelength of the coarsest relief octave (m).
    pub relief_wavelength: f64,
    /// Amplitude ratio between successive relief octaves (0.5: smooth, 0.7: rough).
    pub roughness: f64,
    /// Number of Gaussian bumps per 100 m^2.
    pub bumps_per_100m2: f64,
    /// Number of rocks per 100 m^2.
    pub rocks_per_100m2: f64,
    /// Largest rock diameter (m).
    pub max_rock_diameter: f64,
}

impl Default for TerrainParams {
    fn default() -> Self {
        Self {
            size: 30.0,
            resolution: 0.025,
            relief: 0.4,
            relief_wavelength: 8.0,
            roughness: 0.6,
            bumps_per_100m2: 10.0,
            rocks_per_100m2: 60.0,
            max_rock_diameter: 1.0,
        }
    }
}

/// A height field that can be sampled anywhere by bilinear interpolation.
#[derive(Clone, Debug, PartialEq)]
pub struct HeightField {
    /// Heights (m), row 0 south.
    pub heights: Grid2<f32>,
}

impl HeightField {
    /// Bilinear height at a world point (NaN outside).
    pub fn height(&self, x: f64, y: f64) -> f64 {
        let g = &self.heights.geometry;
        let u = (x - g.origin_x) / g.resolution - 0.5;
        let v = (y - g.origin_y) / g.resolution - 0.5;
        if !(u >= 0.0 && v >= 0.0) {
            return f64::NAN;
        }
        let (c, r) = (u.floor() as usize, v.floor() as usize);
        if c + 1 >= g.cols || r + 1 >= g.rows {
            return f64::NAN;
        }
        let (fu, fv) = (u - c as f64, v - r as f64);
        let h = |c, r| f64::from(*self.heights.get(c, r));
        (1.0 - fv) * ((1.0 - fu) * h(c, r) + fu * h(c + 1, r))
            + fv * ((1.0 - fu) * h(c, r + 1) + fu * h(c + 1, r + 1))
    }

    /// The height field resampled at cell centres of another geometry (NaN outside).
    pub fn sample(&self, geometry: GridGeometry) -> Grid2<f32> {
        let mut out = Grid2::filled(geometry, f32::NAN);
        for r in 0..geometry.rows {
            for c in 0..geometry.cols {
                let (x, y) = geometry.center(c, r);
                *out.get_mut(c, r) = self.height(x, y) as f32;
            }
        }
        out
    }
}

fn smoothstep(t: f64) -> f64 {
    t * t * (3.0 - 2.0 * t)
}

/// Generates a terrain centred on the world origin.
pub fn fractal_terrain(params: &TerrainParams, seed: u64) -> HeightField {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let n = (params.size / params.resolution).round().max(2.0) as usize;
    let geometry = GridGeometry {
        cols: n,
        rows: n,
        resolution: params.resolution,
        origin_x: -0.5 * params.size,
        origin_y: -0.5 * params.size,
    };
    let mut heights = vec![0.0f64; n * n];
    // Relief: octaves of value noise.
    let mut wavelength = params.relief_wavelength;
    let mut amplitude = params.relief;
    while wavelength > 4.0 * params.resolution && amplitude > 1e-3 {
        let lattice_n = (params.size / wavelength).ceil() as usize + 2;
        let lattice: Vec<f64> = (0..lattice_n * lattice_n).map(|_| rng.random_range(-1.0..1.0)).collect();
        for r in 0..n {
            for c in 0..n {
                let (x, y) = geometry.center(c, r);
                let u = (x - geometry.origin_x) / wavelength;
                let v = (y - geometry.origin_y) / wavelength;
                let (i, j) = (u.floor() as usize, v.floor() as usize);
                let (fu, fv) = (smoothstep(u - i as f64), smoothstep(v - j as f64));
                let l = |a: usize, b: usize| lattice[b * lattice_n + a];
                let h = (1.0 - fv) * ((1.0 - fu) * l(i, j) + fu * l(i + 1, j))
                    + fv * ((1.0 - fu) * l(i, j + 1) + fu * l(i + 1, j + 1));
                heights[r * n + c] += amplitude * h;
            }
        }
        wavelength *= 0.5;
        amplitude *= params.roughness;
    }
    let area_factor = params.size * params.size / 100.0;
    let add_blob = |heights: &mut Vec<f64>, cx: f64, cy: f64, radius: f64, f: &dyn Fn(f64) -> f64| {
        let reach = (radius / params.resolution).ceil() as i64 + 1;
        let (c0, r0) = (
            ((cx - geometry.origin_x) / params.resolution) as i64,
            ((cy - geometry.origin_y) / params.resolution) as i64,
        );
        for r in (r0 - reach).max(0)..(r0 + reach).min(n as i64) {
            for c in (c0 - reach).max(0)..(c0 + reach).min(n as i64) {
                let (x, y) = geometry.center(c as usize, r as usize);
                let d = (x - cx).hypot(y - cy) / radius;
                let i = r as usize * n + c as usize;
                heights[i] += f(d);
            }
        }
    };
    // Gaussian bumps.
    let bumps = (params.bumps_per_100m2 * area_factor).round() as usize;
    for _ in 0..bumps {
        let cx = rng.random_range(geometry.origin_x..-geometry.origin_x);
        let cy = rng.random_range(geometry.origin_y..-geometry.origin_y);
        let radius = rng.random_range(0.5..1.5);
        let height = rng.random_range(-0.15..0.25);
        add_blob(&mut heights, cx, cy, 2.0 * radius, &|d: f64| height * (-2.0 * d * d * 4.0).exp());
    }
    // Rocks: diameters from a power law (many small, few large), half-ellipsoids.
    let rocks = (params.rocks_per_100m2 * area_factor).round() as usize;
    for _ in 0..rocks {
        let cx = rng.random_range(geometry.origin_x..-geometry.origin_x);
        let cy = rng.random_range(geometry.origin_y..-geometry.origin_y);
        let u: f64 = rng.random_range(0.0..1.0);
        let diameter = (0.1 * (params.max_rock_diameter / 0.1).powf(u * u)).min(params.max_rock_diameter);
        let height = diameter * rng.random_range(0.3..0.6);
        add_blob(&mut heights, cx, cy, 0.5 * diameter, &|d: f64| {
            if d < 1.0 { height * (1.0 - d * d).sqrt() } else { 0.0 }
        });
    }
    HeightField { heights: Grid2 { geometry, data: heights.into_iter().map(|h| h as f32).collect() } }
}

/// A stereo-like range sensor on a mast.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StereoModel {
    /// Camera height above the ground under the rover (m).
    pub mast_height: f64,
    /// Viewing direction in the body frame (rad).
    pub bearing: f64,
    /// Full horizontal field of view (rad).
    pub fov: f64,
    /// Nearest ground range imaged (m).
    pub min_range: f64,
    /// Farthest range kept (m).
    pub max_range: f64,
    /// Range standard deviation at 1 m (m); it grows with range^2.
    pub range_noise_at_1m: f64,
    /// Spacing of the rays on the ground, roughly (m).
    pub ray_spacing: f64,
}

impl Default for StereoModel {
    fn default() -> Self {
        Self {
            mast_height: 1.2,
            bearing: 0.0,
            fov: 90f64.to_radians(),
            min_range: 1.0,
            max_range: 5.0,
            range_noise_at_1m: 0.001,
            ray_spacing: 0.05,
        }
    }
}

/// Casts the sensor's rays from a rover pose (level, standing on the terrain) and returns the
/// noisy hits as body-frame points (z relative to the ground under the rover).
pub fn stereo_points(terrain: &HeightField, pose: &Pose3, model: &StereoModel, seed: u64) -> Vec<[f32; 3]> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let unit = Normal::new(0.0, 1.0).expect("unit normal");
    let ground = terrain.height(pose.x, pose.y);
    if !ground.is_finite() {
        return Vec::new();
    }
    let eye = [pose.x, pose.y, ground + model.mast_height];
    let az_step = model.ray_spacing / model.max_range;
    let n_az = (model.fov / az_step).ceil() as usize + 1;
    let mut points = Vec::new();
    let march = terrain.heights.resolution();
    for a in 0..n_az {
        let azimuth = model.bearing - 0.5 * model.fov + a as f64 * model.fov / (n_az - 1).max(1) as f64;
        let heading = pose.yaw + azimuth;
        let (sh, ch) = heading.sin_cos();
        let mut ground_range = model.min_range;
        while ground_range <= model.max_range {
            // A ray aimed at the flat-ground point at this range.
            let depression = (model.mast_height / ground_range).atan();
            let (sd, cd) = depression.sin_cos();
            let dir = [cd * ch, cd * sh, -sd];
            let mut t = 0.0;
            let mut hit = None;
            let limit = 1.5 * model.max_range;
            while t < limit {
                let p = [eye[0] + t * dir[0], eye[1] + t * dir[1], eye[2] + t * dir[2]];
                let h = terrain.height(p[0], p[1]);
                if !h.is_finite() {
                    break;
                }
                if p[2] <= h {
                    // Refine the crossing by bisection.
                    let (mut lo, mut hi) = ((t - march).max(0.0), t);
                    for _ in 0..12 {
                        let m = 0.5 * (lo + hi);
                        let q = [eye[0] + m * dir[0], eye[1] + m * dir[1], eye[2] + m * dir[2]];
                        if q[2] <= terrain.height(q[0], q[1]) {
                            hi = m;
                        } else {
                            lo = m;
                        }
                    }
                    hit = Some(0.5 * (lo + hi));
                    break;
                }
                t += march;
            }
            if let Some(range) = hit
                && range <= model.max_range
            {
                let noisy = range + model.range_noise_at_1m * range * range * unit.sample(&mut rng);
                let w = [eye[0] + noisy * dir[0], eye[1] + noisy * dir[1], eye[2] + noisy * dir[2]];
                let body = Pose3 { z: ground, ..*pose }.inverse_transform(w);
                points.push([body[0] as f32, body[1] as f32, body[2] as f32]);
            }
            ground_range += model.ray_spacing * (ground_range / model.max_range).max(0.5);
        }
    }
    points
}

/// Samples a rover-frame local elevation map straight from a height field: each cell centre
/// (body frame, rover at `pose`) is looked up in the world, heights are relative to the ground
/// under the rover, cells outside `wedge` (when given) or hit by the `hole_fraction` lottery
/// are unknown, and `noise` (m, one sigma) is added to each height.
pub fn local_map_from_field(
    field: &HeightField,
    pose: &rovernav_core::Pose2,
    geometry: GridGeometry,
    wedge: Option<&rovernav_core::Wedge>,
    noise: f64,
    hole_fraction: f64,
    seed: u64,
) -> Grid2<f32> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let unit = Normal::new(0.0, 1.0).expect("unit normal");
    let ground = field.height(pose.x, pose.y);
    let ground = if ground.is_finite() { ground } else { 0.0 };
    let mut out = Grid2::filled(geometry, f32::NAN);
    for r in 0..geometry.rows {
        for c in 0..geometry.cols {
            let (bx, by) = geometry.center(c, r);
            if wedge.is_some_and(|w| !w.contains(bx, by)) {
                continue;
            }
            let noise_draw = noise * unit.sample(&mut rng);
            if rng.random_bool(hole_fraction.clamp(0.0, 1.0)) {
                continue;
            }
            let w = pose.transform(rovernav_core::Point2::new(bx, by));
            let h = field.height(w.x, w.y);
            if h.is_finite() {
                *out.get_mut(c, r) = (h - ground + noise_draw) as f32;
            }
        }
    }
    out
}
