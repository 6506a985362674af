//! The scene: the true terrain and its rocks, the rover at its true pose, the volumes in the
//! air, the sun and the atmosphere; and the tracing of one ray through it.
//!
//! Primary and shadow rays against the terrain use the exact height-field caster
//! ([`crate::raycast`]). Beyond the DEM the ground continues as a level plane at the DEM's mean
//! height out to the horizon of a sphere of Mars' radius (`sqrt(2 R h)` for a camera `h` above
//! the plane), so the yard does not float in the sky; that plane is textured and hazed but casts
//! no shadows.

use rovernav_core::{Pose3, RoverConfig};
use rovernav_terrain::{Dem, Terrain};

use super::shade::Atmosphere;
use super::shade::{Lighting, rock_albedo, rock_roughness, soil_albedo};
use super::shapes::{RoverBody, Volume};
use super::sun::Sun;
use crate::raycast::HeightField;

/// Mars' mean radius (m).
const MARS_RADIUS_M: f64 = 3_389_500.0;
/// Side of a rock-index bucket (m).
const BUCKET: f64 = 0.5;

/// What a pixel shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[repr(u8)]
pub enum Label {
    /// Sky (no surface along the ray).
    #[default]
    Sky = 0,
    /// Soil of the DEM.
    Ground = 1,
    /// A rock of the terrain's rock list.
    Rock = 2,
    /// The rover's body.
    Rover = 3,
    /// The level ground beyond the DEM.
    FarGround = 4,
}

/// Everything the renderer draws.
#[derive(Clone, Debug)]
pub struct Scene<'a> {
    /// The true terrain (rocks are in its heights; the rock list gives their albedo).
    pub terrain: &'a Terrain,
    /// The ray-casting acceleration structure of `terrain.dem`.
    pub field: &'a HeightField,
    /// The rover's body, when it is to be drawn (and cast shadows).
    pub rover: Option<RoverBody>,
    /// Transparent volumes in the air.
    pub volumes: Vec<Volume>,
    /// Scene time for the moving volumes (s).
    pub time: f64,
    /// Sun and atmosphere.
    pub lighting: Lighting,
    rocks: RockIndex,
    far_z: f64,
    top_z: f64,
}

/// The result of tracing one ray: radiance factor, range and label.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Radiance factor I/F seen along the ray.
    pub radiance: f64,
    /// Distance to the first surface (m); infinite for sky.
    pub range: f64,
    /// What the ray met first.
    pub label: Label,
}

impl<'a> Scene<'a> {
    /// A scene of the terrain under the sun through the atmosphere, without rover or volumes.
    pub fn new(terrain: &'a Terrain, field: &'a HeightField, sun: &Sun, atmosphere: Atmosphere) -> Self {
        let h = &terrain.dem.heights.data;
        let finite: Vec<f64> = h.iter().filter(|v| v.is_finite()).map(|&v| v as f64).collect();
        let far_z = if finite.is_empty() { 0.0 } else { finite.iter().sum::<f64>() / finite.len() as f64 };
        let top_z = finite.iter().fold(f64::NEG_INFINITY, |m, &v| m.max(v));
        Self {
            terrain,
            field,
            rover: None,
            volumes: Vec::new(),
            time: 0.0,
            lighting: Lighting::new(sun, atmosphere),
            rocks: RockIndex::new(terrain),
            far_z,
            top_z,
        }
    }

    /// Adds the rover's body at its true `pose`, Navcam head panned to `pan` (rad).
    pub fn with_rover(mut self, rover: &RoverConfig, pose: &Pose3, pan: f64) -> Self {
        self.rover = Some(RoverBody::new(rover, pose, pan));
        self
    }

    /// Traces one ray; `pixel_angle` (rad) sets the texture's band limit.
    pub fn trace(&self, origin: [f64; 3], dir: [f64; 3], pixel_angle: f64, shadows: bool) -> Sample {
        let dem = &self.terrain.dem;
        let terrain = self.field.cast(dem, origin, dir, self.reach(origin, dir, 1e5));
        let t_terrain = terrain.map_or(f64::INFINITY, |h| h.range);
        let body = self.rover.as_ref().and_then(|b| b.intersect(origin, dir, t_terrain));
        let lit = &self.lighting;
        let (surface, range, label) = if let Some(b) = body {
            let p = along(origin, dir, b.t);
            let shadowed = shadows && self.in_shadow(p, b.normal);
            (lit.surface(b.albedo, b.normal, shadowed), b.t, Label::Rover)
        } else if let Some(hit) = terrain {
            let p = hit.point;
            let mut n = dem_normal(dem, p[0], p[1]);
            let footprint = footprint(hit.range, pixel_angle, dir, n);
            let (albedo, label) = match self.rocks.find(&self.terrain.rocks, p[0], p[1]) {
                Some(i) => {
                    let (gx, gy) = rock_roughness(i, p[0], p[1], footprint);
                    let m = [n[0] - gx, n[1] - gy, n[2]];
                    let len = (m[0] * m[0] + m[1] * m[1] + m[2] * m[2]).sqrt();
                    n = [m[0] / len, m[1] / len, m[2] / len];
                    (rock_albedo(&self.terrain.rocks[i], i, p[0], p[1], footprint), Label::Rock)
                }
                None => (soil_albedo(p[0], p[1], footprint), Label::Ground),
            };
            let shadowed = shadows && self.in_shadow(p, n);
            (lit.surface(albedo, n, shadowed), hit.range, label)
        } else if let Some(t) = self.far_ground(origin, dir) {
            let p = along(origin, dir, t);
            let n = [0.0, 0.0, 1.0];
            let albedo = soil_albedo(p[0], p[1], footprint(t, pixel_angle, dir, n));
            (lit.surface(albedo, n, false), t, Label::FarGround)
        } else {
            (lit.sky(dir), f64::INFINITY, Label::Sky)
        };
        let mut radiance = if range.is_finite() { lit.aerial(surface, range, dir) } else { surface };
        radiance = self.composite_volumes(radiance, origin, dir, range);
        Sample { radiance, range, label }
    }

    /// Whether point `p` on a surface of normal `n` is in the shadow of the terrain or rover.
    fn in_shadow(&self, p: [f64; 3], n: [f64; 3]) -> bool {
        let s = self.lighting.sun;
        if s[2] <= 0.0 || n[0] * s[0] + n[1] * s[1] + n[2] * s[2] <= 0.0 {
            return false;
        }
        // Start a little off the surface so the ray does not find its own start.
        let o = [p[0] + n[0] * 2e-3, p[1] + n[1] * 2e-3, p[2] + n[2] * 2e-3];
        self.field.cast(&self.terrain.dem, o, s, self.reach(o, s, 1e4)).is_some()
            || self.rover.as_ref().is_some_and(|b| b.intersect(o, s, f64::INFINITY).is_some())
    }

    /// How far along a ray the terrain can still be met: a rising ray is above every cell
    /// once it passes the DEM's highest point.
    fn reach(&self, o: [f64; 3], d: [f64; 3], limit: f64) -> f64 {
        if d[2] > 0.0 { ((self.top_z - o[2]) / d[2]).clamp(0.0, limit) } else { limit }
    }

    /// The distance to the level ground beyond the DEM, if the ray meets it before the horizon.
    fn far_ground(&self, o: [f64; 3], d: [f64; 3]) -> Option<f64> {
        let h = o[2] - self.far_z;
        if d[2] >= 0.0 || h <= 0.0 {
            return None;
        }
        let g = self.terrain.dem.geometry();
        let (x1, y1) = (g.origin_x + g.cols as f64 * g.resolution, g.origin_y + g.rows as f64 * g.resolution);
        let t_plane = -h / d[2];
        // Leave the DEM's rectangle first: inside it the DEM is the ground.
        let mut t_exit = f64::INFINITY;
        for (p, dp, lo, hi) in [(o[0], d[0], g.origin_x, x1), (o[1], d[1], g.origin_y, y1)] {
            if dp != 0.0 {
                t_exit = t_exit.min(if dp > 0.0 { (hi - p) / dp } else { (lo - p) / dp });
            }
        }
        let t_exit = if t_exit.is_finite() { t_exit.max(0.0) } else { 0.0 };
        let t = t_plane.max(t_exit);
        let horizontal = t * d[0].hypot(d[1]);
        (horizontal <= (2.0 * MARS_RADIUS_M * h).sqrt()).then_some(t)
    }

    /// Composites the volumes between the camera and the surface over `behind`.
    fn composite_volumes(&self, behind: f64, o: [f64; 3], d: [f64; 3], range: f64) -> f64 {
        if self.volumes.is_empty() {
            return behind;
        }
        let mut chords: Vec<(f64, f64, &Volume)> = self
            .volumes
            .iter()
            .filter_map(|v| v.chord(o, d, self.time).map(|(a, b)| (a, b.min(range), v)))
            .filter(|(a, b, _)| b > a)
            .collect();
        // Far to near, each over what lies behind it (single scattering, isotropic phase).
        chords.sort_by(|a, b| b.0.total_cmp(&a.0));
        let lit = &self.lighting;
        let mut l = behind;
        for (a, b, v) in chords {
            let transmission = (-v.density * (b - a)).exp();
            let source = v.albedo * (lit.direct * lit.sun[2].max(0.0).sqrt() + lit.diffuse);
            l = l * transmission + source * (1.0 - transmission);
        }
        l
    }
}

fn along(o: [f64; 3], d: [f64; 3], t: f64) -> [f64; 3] {
    [o[0] + d[0] * t, o[1] + d[1] * t, o[2] + d[2] * t]
}

/// Ground footprint of a pixel (m): range times pixel angle, stretched by the obliquity.
fn footprint(range: f64, pixel_angle: f64, d: [f64; 3], n: [f64; 3]) -> f64 {
    let cos = (d[0] * n[0] + d[1] * n[1] + d[2] * n[2]).abs().max(0.1);
    range * pixel_angle / cos
}

/// Smooth surface normal at (x, y): bilinear interpolation of the cell normals (central
/// differences), so rocks shade smoothly across the 5 cm cells.
pub fn dem_normal(dem: &Dem, x: f64, y: f64) -> [f64; 3] {
    let g = dem.geometry();
    if g.cols < 2 || g.rows < 2 {
        return [0.0, 0.0, 1.0];
    }
    let fx = ((x - g.origin_x) / g.resolution - 0.5).clamp(0.0, (g.cols - 1) as f64);
    let fy = ((y - g.origin_y) / g.resolution - 0.5).clamp(0.0, (g.rows - 1) as f64);
    let c0 = (fx.floor() as usize).min(g.cols - 2);
    let r0 = (fy.floor() as usize).min(g.rows - 2);
    let (tx, ty) = (fx - c0 as f64, fy - r0 as f64);
    let h = |c: usize, r: usize| {
        let v = *dem.heights.get(c.min(g.cols - 1), r.min(g.rows - 1)) as f64;
        if v.is_finite() { v } else { 0.0 }
    };
    let grad = |c: usize, r: usize| {
        let (cl, cr) = (c.saturating_sub(1), (c + 1).min(g.cols - 1));
        let (rl, rh) = (r.saturating_sub(1), (r + 1).min(g.rows - 1));
        (
            (h(cr, r) - h(cl, r)) / ((cr - cl) as f64 * g.resolution),
            (h(c, rh) - h(c, rl)) / ((rh - rl) as f64 * g.resolution),
        )
    };
    let (g00, g10, g01, g11) = (grad(c0, r0), grad(c0 + 1, r0), grad(c0, r0 + 1), grad(c0 + 1, r0 + 1));
    let lerp = |a: f64, b: f64, c: f64, d: f64| {
        (a * (1.0 - tx) + b * tx) * (1.0 - ty) + (c * (1.0 - tx) + d * tx) * ty
    };
    let gx = lerp(g00.0, g10.0, g01.0, g11.0);
    let gy = lerp(g00.1, g10.1, g01.1, g11.1);
    let n = (gx * gx + gy * gy + 1.0).sqrt();
    [-gx / n, -gy / n, 1.0 / n]
}

/// Buckets of rock indices for finding the rock under a point.
#[derive(Clone, Debug)]
struct RockIndex {
    origin: (f64, f64),
    cols: usize,
    rows: usize,
    buckets: Vec<Vec<u32>>,
    /// How far beyond its radius a rock's surface reaches: the DEM interpolates one cell
    /// outward from the last cell inside the rock.
    margin: f64,
}

impl RockIndex {
    fn new(terrain: &Terrain) -> Self {
        let g = terrain.dem.geometry();
        let cols = ((g.cols as f64 * g.resolution) / BUCKET).ceil().max(1.0) as usize;
        let rows = ((g.rows as f64 * g.resolution) / BUCKET).ceil().max(1.0) as usize;
        let mut buckets = vec![Vec::new(); cols * rows];
        let origin = (g.origin_x, g.origin_y);
        for (i, rock) in terrain.rocks.iter().enumerate() {
            let r = 0.5 * rock.diameter + g.resolution;
            let span = |lo: f64, o: f64, n: usize| (((lo - o) / BUCKET).floor().max(0.0) as usize).min(n - 1);
            let (c0, c1) = (span(rock.x - r, origin.0, cols), span(rock.x + r, origin.0, cols));
            let (r0, r1) = (span(rock.y - r, origin.1, rows), span(rock.y + r, origin.1, rows));
            for row in r0..=r1 {
                for col in c0..=c1 {
                    buckets[row * cols + col].push(i as u32);
                }
            }
        }
        Self { origin, cols, rows, buckets, margin: g.resolution }
    }

    /// The rock whose footprint holds (x, y); where rocks overlap (their heights add up in the
    /// DEM), the one that adds the most height there.
    fn find(&self, rocks: &[rovernav_terrain::Rock], x: f64, y: f64) -> Option<usize> {
        let (c, r) = ((x - self.origin.0) / BUCKET, (y - self.origin.1) / BUCKET);
        if c < 0.0 || r < 0.0 || c >= self.cols as f64 || r >= self.rows as f64 {
            return None;
        }
        self.buckets[r as usize * self.cols + c as usize]
            .iter()
            .map(|&i| i as usize)
            .filter(|&i| (x - rocks[i].x).hypot(y - rocks[i].y) <= 0.5 * rocks[i].diameter + self.margin)
            .max_by(|&a, &b| dome(&rocks[a], x, y).total_cmp(&dome(&rocks[b], x, y)))
    }
}

/// Height a rock's dome adds at (x, y) (negative outside it: minus the distance beyond its rim).
fn dome(rock: &rovernav_terrain::Rock, x: f64, y: f64) -> f64 {
    let r = 0.5 * rock.diameter;
    let d = (x - rock.x).hypot(y - rock.y);
    if d < r { rock.height * (1.0 - (d / r).powi(2)).sqrt() } else { r - d }
}
