//! The rover localised against the descent DEM (paper 002 section 4: the descent DEM serves as
//! the reference map of the rover's map matcher).
//!
//! At each distance from the landing site (along a direction drawn for the seed), the true
//! terrain is [`DescentTerrain`] sampled at 0.1 m around the rover; the simulated rover builds
//! its levelled elevation map from a full circle of eight fine mast stereo wedges out to 12 m
//! (as `eval orbital` does) and the orbital-map matcher (`localization::orbital`) searches
//! +-4 m and +-10 deg around a dead-reckoned pose (truth + 1 m per axis, 3 deg). The reference
//! is the descent DEM: the triangulated points (every pair's, and a dense pass matching every
//! pixel of the lowest pair that sees the rover's surroundings) gridded by inverse variance at
//! the finest cell size (1, 2, 4, ... m) that fills 80 % of the cells within 20 m of the rover.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rovernav_core::{Grid2, GridGeometry, NavCommand, Pose2, RoverConfig, SenseRequest};
use rovernav_localization::SearchWindow;
use rovernav_localization::orbital::{OrbitalParams, match_orbital, panorama_map, reference_around};
use rovernav_sim::scenes::descent::DescentTerrain;
use rovernav_sim::{SensorModel, Simulator};
use rovernav_terrain::{Dem, Terrain};
use rovernav_vision::descent::elevation_grid;
use serde::Serialize;

/// Panorama range (m), search half-widths (m, deg), dead-reckoning errors (m, deg).
const RANGE_M: f64 = 12.0;
const WINDOW: (f64, f64) = (4.0, 10.0);
const DR_SIGMA: (f64, f64) = (1.0, 3.0);
/// Cell of the rover's and the matched maps (m).
const CELL_M: f64 = 0.5;

/// One fix against the descent DEM.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct DescentFix {
    /// Distance of the rover from the landing site (m).
    pub distance_m: f64,
    /// Cell size of the descent DEM used as the reference (m).
    pub reference_cell_m: f64,
    /// RMS error of the descent DEM's cells within 20 m of the rover against the true heights
    /// at their centres (m).
    pub reference_rms_m: f64,
    /// Position error of the match (m).
    pub error_m: Option<f64>,
    /// Position error of dead reckoning, the search's starting point (m).
    pub dead_reckoning_error_m: f64,
    /// Heading error of the match (deg).
    pub heading_error_deg: Option<f64>,
    /// The matcher's false-match probability.
    pub failure_probability: Option<f64>,
    /// The matcher's error, if any.
    pub failure: Option<String>,
}

/// The rover's true position at `distance` m from the landing site (direction drawn for the
/// seed), its true heading and its dead-reckoned pose.
pub fn position(distance: f64, seed: u64) -> ([f64; 2], f64, Pose2) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x0de5_f1c5 ^ distance.to_bits());
    let azimuth = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
    let (x, y) = (distance * azimuth.cos(), distance * azimuth.sin());
    let yaw = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
    let mut normal = || {
        let (u1, u2): (f64, f64) = (rng.random::<f64>().max(1e-300), rng.random());
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    };
    let dr = Pose2::new(
        x + DR_SIGMA.0 * normal(),
        y + DR_SIGMA.0 * normal(),
        yaw + DR_SIGMA.1.to_radians() * normal(),
    );
    ([x, y], yaw, dr)
}

/// Half-side of the descent DEM the matcher needs around the dead-reckoned position (m).
pub const REACH_M: f64 = RANGE_M + WINDOW.0 + 6.0;

/// The rover at `distance` m from the landing site matched against the descent DEM built from
/// `points` (`[x, y, z, sigma]`).
pub fn fix(terrain: &DescentTerrain, points: &[[f64; 4]], distance: f64, seed: u64) -> DescentFix {
    let ([x, y], yaw, dr) = position(distance, seed);
    // The reference: the finest cell size the points fill.
    let reach = REACH_M;
    let (mut coarse, mut cell) = (None, 1.0);
    while cell <= 64.0 {
        let n = (2.0 * (reach + 2.0 * cell) / cell).ceil() as usize;
        let origin = (dr.x - 0.5 * n as f64 * cell, dr.y - 0.5 * n as f64 * cell);
        let geometry =
            GridGeometry { cols: n, rows: n, resolution: cell, origin_x: origin.0, origin_y: origin.1 };
        let grid = elevation_grid(points, geometry);
        if filled_near(&grid, dr.x, dr.y, 20.0) >= 0.8 {
            coarse = Some(grid);
            break;
        }
        cell *= 2.0;
    }
    let base = DescentFix {
        distance_m: distance,
        reference_cell_m: cell,
        reference_rms_m: coarse.as_ref().map_or(f64::NAN, |g| rms_near(g, terrain, dr.x, dr.y, 20.0)),
        error_m: None,
        dead_reckoning_error_m: (dr.x - x).hypot(dr.y - y),
        heading_error_deg: None,
        failure_probability: None,
        failure: None,
    };
    let Some(coarse) = coarse else {
        return DescentFix { failure: Some("no descent elevations around the rover".into()), ..base };
    };
    // The true terrain around the rover at 0.1 m, in a frame whose origin is its corner.
    let half = RANGE_M + 3.0;
    let n = (2.0 * half / 0.1).round() as usize;
    let (ox, oy) = (x - half, y - half);
    let geometry = GridGeometry { cols: n, rows: n, resolution: 0.1, origin_x: 0.0, origin_y: 0.0 };
    let heights: Vec<f32> = (0..n * n)
        .map(|i| {
            let (cx, cy) = geometry.center(i % n, i / n);
            terrain.height(ox + cx, oy + cy, 0.2) as f32
        })
        .collect();
    let truth_terrain = Terrain { dem: Dem::from_grid(Grid2 { geometry, data: heights }), rocks: Vec::new() };
    let rover = RoverConfig { mast_range: RANGE_M, ..RoverConfig::default() };
    let mut sim =
        Simulator::new(truth_terrain, rover, SensorModel::default(), Pose2::new(half, half, yaw), seed);
    let t = sim.truth();
    let pans: Vec<SenseRequest> =
        (0..8).map(|k| SenseRequest::MastFine { pan: f64::from(k) * 0.25 * std::f64::consts::PI }).collect();
    let frame = sim.execute(&NavCommand::Sense(pans));
    let cloud: Vec<[f32; 3]> = frame.clouds.into_iter().flat_map(|c| c.points).collect();
    let local = panorama_map(&cloud, t.roll, t.pitch, RANGE_M, CELL_M);
    let reference = reference_around(&coarse, dr.x, dr.y, reach, CELL_M);
    let window =
        SearchWindow { center: dr, half_x: WINDOW.0, half_y: WINDOW.0, half_yaw: WINDOW.1.to_radians() };
    let (tx, ty) = (t.x + ox, t.y + oy);
    match match_orbital(&local, &reference, &window, &OrbitalParams::default()) {
        Ok(m) => DescentFix {
            error_m: Some((m.pose.x - tx).hypot(m.pose.y - ty)),
            heading_error_deg: Some(rovernav_core::wrap_angle(m.pose.yaw - t.yaw).to_degrees()),
            failure_probability: Some(m.failure_probability),
            ..base
        },
        Err(e) => DescentFix { failure: Some(e.to_string()), ..base },
    }
}

/// RMS difference between the grid's cells within `radius` of (x, y) and the true heights at
/// their centres, after removing the mean difference (the matcher ignores a height offset).
fn rms_near(grid: &Grid2<f32>, terrain: &DescentTerrain, x: f64, y: f64, radius: f64) -> f64 {
    let g = &grid.geometry;
    let mut d = Vec::new();
    for r in 0..g.rows {
        for c in 0..g.cols {
            let (cx, cy) = g.center(c, r);
            let v = *grid.get(c, r) as f64;
            if (cx - x).hypot(cy - y) <= radius && v.is_finite() {
                d.push(v - terrain.height(cx, cy, g.resolution));
            }
        }
    }
    let mean = d.iter().sum::<f64>() / d.len().max(1) as f64;
    (d.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / d.len().max(1) as f64).sqrt()
}

/// Fraction of the grid's cells within `radius` of (x, y) that hold a height.
fn filled_near(grid: &Grid2<f32>, x: f64, y: f64, radius: f64) -> f64 {
    let g = &grid.geometry;
    let (mut n, mut filled) = (0usize, 0usize);
    for r in 0..g.rows {
        for c in 0..g.cols {
            let (cx, cy) = g.center(c, r);
            if (cx - x).hypot(cy - y) <= radius {
                n += 1;
                filled += grid.get(c, r).is_finite() as usize;
            }
        }
    }
    if n == 0 { 0.0 } else { filled as f64 / n as f64 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_reference_of_true_heights_localises_the_rover() {
        let terrain = DescentTerrain::procedural(4);
        let ([x, y], _, _) = position(100.0, 3);
        // The true ground every 0.5 m around the rover, as if the descent DEM were perfect.
        let mut points = Vec::new();
        for i in -60..=60 {
            for j in -60..=60 {
                let (px, py) = (x + 0.5 * f64::from(i), y + 0.5 * f64::from(j));
                points.push([px, py, terrain.height(px, py, 1.0), 0.05]);
            }
        }
        let f = fix(&terrain, &points, 100.0, 3);
        assert_eq!(f.reference_cell_m, 1.0);
        let error = f.error_m.expect("a match");
        assert!(error < 0.5, "{f:?}");
    }
}
