//! Shared fixtures of the localisation scenario tests.

#![allow(dead_code)]

use rovernav_core::Grid2;
use rovernav_core::{GridGeometry, Pose2, Wedge};
use rovernav_localization::synthetic::{HeightField, TerrainParams, fractal_terrain, local_map_from_field};

/// A rocky synthetic terrain of `size` metres sampled every `resolution / 2`.
pub fn rocky_terrain(size: f64, resolution: f64, seed: u64) -> HeightField {
    fractal_terrain(
        &TerrainParams { size, resolution: resolution / 2.0, rocks_per_100m2: 120.0, ..Default::default() },
        seed,
    )
}

/// A square world-frame global map of `half` metres around the origin.
pub fn global_map(field: &HeightField, resolution: f64, half: f64) -> Grid2<f32> {
    let n = (2.0 * half / resolution).round() as usize;
    field.sample(GridGeometry { cols: n, rows: n, resolution, origin_x: -half, origin_y: -half })
}

/// How a forward wedge view is taken.
#[derive(Clone, Copy, Debug)]
pub struct WedgeView {
    /// Farthest range (m).
    pub range: f64,
    /// Half of the field of view (rad).
    pub half_angle: f64,
    /// Height noise (m, one sigma).
    pub noise: f64,
    /// Fraction of cells left unknown.
    pub holes: f64,
}

/// A forward wedge local map seen from `pose` (rover frame), with height noise and holes.
pub fn wedge_map(
    field: &HeightField,
    pose: &Pose2,
    resolution: f64,
    view: WedgeView,
    seed: u64,
) -> Grid2<f32> {
    let geometry = GridGeometry {
        cols: (view.range / resolution).ceil() as usize,
        rows: (2.0 * view.range / resolution).ceil() as usize,
        resolution,
        origin_x: 0.0,
        origin_y: -view.range,
    };
    let wedge = Wedge { bearing: 0.0, half_angle: view.half_angle, min_range: 0.8, max_range: view.range };
    local_map_from_field(field, pose, geometry, Some(&wedge), view.noise, view.holes, seed)
}
