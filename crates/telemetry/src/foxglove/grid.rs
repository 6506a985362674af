//! `foxglove.Grid`: the belief map (elevation) and the traversability map as the rover's range
//! data builds them.
//!
//! The navigators do not hand out their maps, so the log rebuilds the one the grid navigators
//! keep: a [`TerrainModel`] over the same extent (start and goal with the grid navigator's
//! margin and resolution) fed with the same frames placed with the same pose estimates. That is
//! the autonomy's belief (no truth goes in); for `astar-grid` it is the navigator's own map,
//! for the other navigators the stack's shared terrain model of what they sensed.
//!
//! Departures: an extent of more than [`MAX_CELLS`] cells gets coarser cells (memory); the
//! grids are published at twice the map's cell size (of each 2 x 2 block the highest height
//! and the lowest traversability and goodness: the worst) and cropped to the sensed area, to
//! keep the log small; the planner's own resolution is in the navigator's parameters.

use super::{PoseMsg, TimeMsg};
use crate::base64;
use rovernav_core::{Grid2, GridGeometry, PointCloud, PoseEstimate};
use rovernav_executive::World;
use rovernav_navigation::{GridNavigatorConfig, TerrainModel};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// `foxglove.PackedElementField`: one field of each cell (`type` 1 UINT8, 7 FLOAT32).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct PackedElementField {
    /// Field name.
    pub name: String,
    /// Byte offset within a cell.
    pub offset: u32,
    /// Foxglove `NumericType`: 1 UINT8, 7 FLOAT32.
    #[serde(rename = "type")]
    pub kind: u8,
}

/// Foxglove's `NumericType` UINT8.
pub const UINT8: u8 = 1;
/// Foxglove's `NumericType` FLOAT32.
pub const FLOAT32: u8 = 7;

/// `foxglove.Vector2`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct Vector2 {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
}

/// `foxglove.Grid`: a row-major grid of packed cells, row 0 at `pose` (the south-west corner).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct GridMsg {
    /// Time.
    pub timestamp: TimeMsg,
    /// Frame of `pose`.
    pub frame_id: String,
    /// The grid's corner (cell 0, 0) in the frame.
    pub pose: PoseMsg,
    /// Columns.
    pub column_count: u32,
    /// Cell size (m).
    pub cell_size: Vector2,
    /// Bytes per row.
    pub row_stride: u32,
    /// Bytes per cell.
    pub cell_stride: u32,
    /// The fields of a cell.
    pub fields: Vec<PackedElementField>,
    /// The cells, base64.
    #[schemars(extend("contentEncoding" = "base64"))]
    pub data: String,
}

impl GridMsg {
    /// The cell bytes back (for tests and readers); the error names the field.
    pub fn bytes(&self) -> Result<Vec<u8>, String> {
        let raw = base64::decode(&self.data).map_err(|e| format!("field `data`: {e}"))?;
        if self.row_stride != self.column_count * self.cell_stride
            || raw.len() % self.row_stride.max(1) as usize != 0
        {
            return Err(format!("field `data`: {} bytes for rows of {} bytes", raw.len(), self.row_stride));
        }
        Ok(raw)
    }
}

/// Most cells of the rebuilt map (16 million: about 0.4 km square at the navigators' 0.1 m).
pub const MAX_CELLS: f64 = 16e6;

/// The belief map a run's frames build (see the module documentation).
pub struct BeliefMap {
    model: TerrainModel,
    /// Cells of the model per published cell along each axis.
    block: usize,
}

impl BeliefMap {
    /// An empty map over the extent a grid navigator would use for this world.
    pub fn new(world: &World) -> Self {
        let config = GridNavigatorConfig::default();
        let m = config.map_margin;
        let mut points = vec![world.start.position(), world.goal.position];
        points.extend(world.goal.waypoints.iter().copied());
        let x0 = points.iter().map(|p| p.x).fold(f64::INFINITY, f64::min) - m;
        let y0 = points.iter().map(|p| p.y).fold(f64::INFINITY, f64::min) - m;
        let x1 = points.iter().map(|p| p.x).fold(f64::NEG_INFINITY, f64::max) + m;
        let y1 = points.iter().map(|p| p.y).fold(f64::NEG_INFINITY, f64::max) + m;
        // A long traverse gets coarser cells rather than more than MAX_CELLS of them.
        let res = config.map_resolution.max(((x1 - x0) * (y1 - y0) / MAX_CELLS).sqrt());
        let cols = ((x1 - x0) / res).ceil().clamp(1.0, 20_000.0) as usize;
        let rows = ((y1 - y0) / res).ceil().clamp(1.0, 20_000.0) as usize;
        let geometry = GridGeometry { cols, rows, resolution: res, origin_x: x0, origin_y: y0 };
        Self { model: TerrainModel::new(&world.rover, geometry, config.safety_buffer), block: 2 }
    }

    /// Folds a frame's range data in, placed with the estimate; whether the map changed.
    pub fn ingest(&mut self, clouds: &[PointCloud], estimate: &PoseEstimate) -> bool {
        if clouds.is_empty() {
            return false;
        }
        self.model.ingest(clouds, estimate);
        true
    }

    /// The elevation grid and the traversability grid of the sensed area, or `None` before
    /// anything was sensed.
    pub fn grids(&self, t: f64, frame_id: &str) -> Option<(GridMsg, GridMsg)> {
        let world = self.model.world();
        let (c0, r0, c1, r1) = sensed_bounds(world.sensed())?;
        let k = self.block;
        let g = world.geometry();
        let (cols, rows) = ((c1 - c0) / k + 1, (r1 - r0) / k + 1);
        let mut elevation = Vec::with_capacity(cols * rows * 4);
        let mut traversability = Vec::with_capacity(cols * rows * 5);
        for br in 0..rows {
            for bc in 0..cols {
                let (mut z, mut trav, mut good) = (f32::NAN, 0u8, f32::NAN);
                for r in (r0 + br * k)..(r0 + br * k + k).min(g.rows) {
                    for c in (c0 + bc * k)..(c0 + bc * k + k).min(g.cols) {
                        if !*world.sensed().get(c, r) {
                            continue;
                        }
                        z = max_known(z, *world.elevation().get(c, r));
                        let tv = *world.traversability().get(c, r);
                        if tv != 0 {
                            trav = if trav == 0 { tv } else { trav.min(tv) };
                        }
                        good = min_known(good, *world.goodness().get(c, r));
                    }
                }
                elevation.extend_from_slice(&z.to_le_bytes());
                traversability.push(trav);
                traversability.extend_from_slice(&good.to_le_bytes());
            }
        }
        let (x, y) = (g.origin_x + c0 as f64 * g.resolution, g.origin_y + r0 as f64 * g.resolution);
        // The grids lie at the lowest known height, under the terrain they describe (a DEM's
        // heights may be far from zero).
        let lowest = elevation
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .filter(|h| h.is_finite())
            .fold(f32::INFINITY, f32::min);
        let z = if lowest.is_finite() { f64::from(lowest) } else { 0.0 };
        let cell = g.resolution * k as f64;
        let grid = |fields: Vec<PackedElementField>, stride: u32, data: &[u8]| GridMsg {
            timestamp: TimeMsg::of_seconds(t),
            frame_id: frame_id.into(),
            pose: PoseMsg::at(x, y, z),
            column_count: cols as u32,
            cell_size: Vector2 { x: cell, y: cell },
            row_stride: cols as u32 * stride,
            cell_stride: stride,
            fields,
            data: base64::encode(data),
        };
        let field = |name: &str, offset, kind| PackedElementField { name: name.into(), offset, kind };
        Some((
            grid(vec![field("elevation", 0, FLOAT32)], 4, &elevation),
            grid(vec![field("traversability", 0, UINT8), field("goodness", 1, FLOAT32)], 5, &traversability),
        ))
    }

    /// The underlying model (its full-resolution layers).
    pub fn model(&self) -> &TerrainModel {
        &self.model
    }
}

fn max_known(a: f32, b: f32) -> f32 {
    if a.is_nan() {
        b
    } else if b.is_nan() {
        a
    } else {
        a.max(b)
    }
}

fn min_known(a: f32, b: f32) -> f32 {
    if a.is_nan() {
        b
    } else if b.is_nan() {
        a
    } else {
        a.min(b)
    }
}

/// `(c0, r0, c1, r1)` of the sensed cells, inclusive.
fn sensed_bounds(sensed: &Grid2<bool>) -> Option<(usize, usize, usize, usize)> {
    let g = sensed.geometry;
    let mut b: Option<(usize, usize, usize, usize)> = None;
    for r in 0..g.rows {
        for c in 0..g.cols {
            if *sensed.get(c, r) {
                b = Some(match b {
                    None => (c, r, c, r),
                    Some((c0, r0, c1, r1)) => (c0.min(c), r0.min(r), c1.max(c), r1.max(r)),
                });
            }
        }
    }
    b
}

#[cfg(test)]
mod tests {
    use super::*;
    use rovernav_core::{CameraKind, Pose3, Wedge};

    #[test]
    fn a_sensed_patch_is_published_where_it_lies_with_its_heights() {
        let world = rovernav_harness::long_yard_world(1, 5.0, 4.0, 1.0);
        let mut map = BeliefMap::new(&world);
        assert!(map.grids(0.0, "map").is_none(), "nothing sensed yet");
        // A flat patch 0.3 m high, 2..3 m ahead of a rover at the start.
        let start = world.start;
        let pose = Pose3 { x: start.x, y: start.y, z: 0.0, roll: 0.0, pitch: 0.0, yaw: start.yaw };
        let points: Vec<[f32; 3]> = (0..40)
            .flat_map(|i| (0..40).map(move |j| [2.0 + i as f32 * 0.025, -0.5 + j as f32 * 0.025, 0.3]))
            .collect();
        let cloud = PointCloud {
            camera: CameraKind::Mast,
            origin: [0.0, 0.0, 1.0],
            wedge: Wedge { bearing: 0.0, half_angle: 0.5, min_range: 1.0, max_range: 4.0 },
            points,
        };
        let estimate = PoseEstimate { pose, covariance: [[0.0; 3]; 3] };
        assert!(!map.ingest(&[], &estimate));
        assert!(map.ingest(&[cloud], &estimate));
        let (elevation, trav) = map.grids(5.0, "map").expect("sensed");
        let cells = elevation.bytes().unwrap();
        let heights: Vec<f32> =
            cells.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect();
        let known: Vec<f32> = heights.iter().copied().filter(|h| h.is_finite()).collect();
        assert!(!known.is_empty());
        assert!(known.iter().all(|h| (h - 0.3).abs() < 0.05), "{known:?}");
        // The known cells lie where the points were: 2..3 m ahead of the start along its heading.
        let cols = elevation.column_count as usize;
        let cell = elevation.cell_size.x;
        let (hx, hy) = (start.yaw.cos(), start.yaw.sin());
        for (i, h) in heights.iter().enumerate() {
            if h.is_finite() {
                let x = elevation.pose.position.x + ((i % cols) as f64 + 0.5) * cell - start.x;
                let y = elevation.pose.position.y + ((i / cols) as f64 + 0.5) * cell - start.y;
                let ahead = x * hx + y * hy;
                assert!((1.6..=3.4).contains(&ahead), "cell {i} {ahead} m ahead");
            }
        }
        assert_eq!(elevation.pose.position.z, f64::from(known.iter().copied().fold(f32::INFINITY, f32::min)));
        assert_eq!(trav.cell_stride, 5);
        assert_eq!(trav.bytes().unwrap().len(), heights.len() * 5);
    }

    #[test]
    fn a_long_traverse_gets_coarser_cells_not_more_of_them() {
        let mut world = rovernav_harness::long_yard_world(1, 5.0, 4.0, 1.0);
        let near = BeliefMap::new(&world).model().world().geometry();
        assert_eq!(near.resolution, GridNavigatorConfig::default().map_resolution);
        world.goal.position = rovernav_core::Point2::new(3000.0, 2000.0);
        let far = BeliefMap::new(&world).model().world().geometry();
        assert!((far.cols * far.rows) as f64 <= MAX_CELLS * 1.01, "{} x {}", far.cols, far.rows);
        assert!(
            far.width_m() >= 3000.0 && far.height_m() >= 2000.0,
            "the extent still covers start and goal"
        );
    }
}
