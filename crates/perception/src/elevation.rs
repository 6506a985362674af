//! Elevation maps from range data (paper 002 section 3.1).
//!
//! Range points arrive in the rover body frame at capture. They are first rotated and translated
//! into the world frame with the autonomy's pose estimate (the paper assumes orientation from
//! non-visual sensors: sun sensor, accelerometers, gyro; here the estimate carries roll, pitch
//! and yaw), then binned into a grid over the xy-plane, the terrain being taken as a single-valued
//! function z = f(x, y). Each cell keeps running sums ([`CellStats`]) so its mean height, height
//! variance, extremes and best-fit plane are available and later clouds fuse in without
//! re-reading earlier ones.

use crate::PerceptionError;
use crate::cell::CellStats;
use crate::config::TerrainConfig;
use crate::evaluator::{TerrainLayers, assess_cells};
use rovernav_core::{Grid2, GridGeometry, PointCloud, Pose2, Pose3};

/// Body-frame points of a cloud placed in the world with `pose`; non-finite points are dropped.
pub fn world_points<'a>(cloud: &'a PointCloud, pose: &Pose3) -> impl Iterator<Item = [f64; 3]> + 'a {
    let r = pose.rotation();
    let t = [pose.x, pose.y, pose.z];
    cloud.points.iter().filter_map(move |p| {
        let (x, y, z) = (p[0] as f64, p[1] as f64, p[2] as f64);
        if !(x.is_finite() && y.is_finite() && z.is_finite()) {
            return None;
        }
        Some([
            t[0] + r[0][0] * x + r[0][1] * y + r[0][2] * z,
            t[1] + r[1][0] * x + r[1][1] * y + r[1][2] * z,
            t[2] + r[2][0] * x + r[2][1] * y + r[2][2] * z,
        ])
    })
}

/// A fixed, world-aligned elevation map built by binning range points.
#[derive(Clone, Debug, PartialEq)]
pub struct ElevationMap {
    cells: Grid2<CellStats>,
}

impl ElevationMap {
    /// An empty map over `geometry`.
    pub fn new(geometry: GridGeometry) -> Result<Self, PerceptionError> {
        if geometry.is_empty() || !(geometry.resolution.is_finite() && geometry.resolution > 0.0) {
            return Err(PerceptionError::InvalidConfig {
                field: "geometry",
                reason: format!(
                    "needs at least one cell and a positive resolution, got {}x{} at {}",
                    geometry.cols, geometry.rows, geometry.resolution
                ),
            });
        }
        Ok(Self { cells: Grid2::filled(geometry, CellStats::EMPTY) })
    }

    /// Placement of the map.
    pub fn geometry(&self) -> GridGeometry {
        self.cells.geometry
    }

    /// The per-cell statistics.
    pub fn cells(&self) -> &Grid2<CellStats> {
        &self.cells
    }

    /// Adds one world point; returns whether it fell inside the map.
    #[inline]
    pub fn insert_world_point(&mut self, p: [f64; 3]) -> bool {
        let g = self.cells.geometry;
        match g.cell_of(p[0], p[1]) {
            Some((c, r)) => {
                let (cx, cy) = g.center(c, r);
                self.cells.get_mut(c, r).add(p[0] - cx, p[1] - cy, p[2]);
                true
            }
            None => false,
        }
    }

    /// Bins a body-frame cloud placed with the pose estimate `pose`; returns the points kept.
    pub fn insert_cloud(&mut self, cloud: &PointCloud, pose: &Pose3) -> usize {
        let mut kept = 0;
        for p in world_points(cloud, pose) {
            kept += usize::from(self.insert_world_point(p));
        }
        kept
    }

    /// Fuses another map of the same geometry into this one.
    pub fn merge(&mut self, other: &ElevationMap) -> Result<(), PerceptionError> {
        if other.geometry() != self.geometry() {
            return Err(PerceptionError::InvalidConfig {
                field: "other.geometry",
                reason: "maps to merge must share one geometry".into(),
            });
        }
        for (a, b) in self.cells.data.iter_mut().zip(&other.cells.data) {
            a.merge(b);
        }
        Ok(())
    }

    /// Assesses the map with the terrain evaluator's pipeline (step/slope hazards,
    /// traversability, goodness); `rover` is the pose estimate, whose cell is the grid centre for
    /// the neighbourhood estimate (the map's central cell when the rover is outside it).
    pub fn assess(&self, config: &TerrainConfig, rover: Pose2) -> TerrainLayers {
        let g = self.geometry();
        let centre = g.cell_of(rover.x, rover.y).unwrap_or((g.cols / 2, g.rows / 2));
        assess_cells(g, self.cells.data.iter(), centre, rover, config)
    }

    /// Mean height per cell (m); NaN where unsensed.
    pub fn mean_heights(&self) -> Grid2<f32> {
        self.map_cells(|c| c.mean().map_or(f32::NAN, |m| m as f32))
    }

    /// Height variance per cell (m^2); NaN where unsensed.
    pub fn variances(&self) -> Grid2<f32> {
        self.map_cells(|c| c.variance().map_or(f32::NAN, |v| v as f32))
    }

    /// Points per cell.
    pub fn counts(&self) -> Grid2<u32> {
        self.map_cells(|c| c.count)
    }

    /// Whether each cell holds any point.
    pub fn sensed(&self) -> Grid2<bool> {
        self.map_cells(|c| c.is_sensed())
    }

    fn map_cells<T>(&self, f: impl Fn(&CellStats) -> T) -> Grid2<T> {
        Grid2 { geometry: self.cells.geometry, data: self.cells.data.iter().map(f).collect() }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rovernav_core::{CameraKind, Wedge};

    fn cloud(points: Vec<[f32; 3]>) -> PointCloud {
        PointCloud {
            camera: CameraKind::Mast,
            origin: [0.0, 0.0, 1.2],
            wedge: Wedge { bearing: 0.0, half_angle: 0.4, min_range: 0.5, max_range: 5.0 },
            points,
        }
    }

    #[test]
    fn points_are_placed_with_the_pose_and_averaged_per_bin() {
        let g = GridGeometry { cols: 10, rows: 10, resolution: 1.0, origin_x: 0.0, origin_y: 0.0 };
        let mut m = ElevationMap::new(g).unwrap();
        // Rover at (5, 5, 2) facing north: body forward (1, 0) maps to world (5, 6).
        let pose = Pose3 { x: 5.0, y: 5.0, z: 2.0, yaw: std::f64::consts::FRAC_PI_2, ..Default::default() };
        let kept =
            m.insert_cloud(&cloud(vec![[1.2, 0.1, -1.0], [1.4, -0.2, -2.0], [f32::NAN, 0.0, 0.0]]), &pose);
        assert_eq!(kept, 2);
        let h = m.mean_heights();
        // Both points land in world cell (4, 6) or (5, 6): x = 5 - 0.1 = 4.9 and 5 + 0.2 = 5.2.
        assert!((h.get(4, 6) - 1.0).abs() < 1e-6);
        assert!((h.get(5, 6) - 0.0).abs() < 1e-6);
        assert!(h.get(5, 5).is_nan());
        assert_eq!(*m.counts().get(4, 6), 1);
    }

    #[test]
    fn a_pitched_rover_sees_level_ground_as_level() {
        let g = GridGeometry { cols: 20, rows: 20, resolution: 0.5, origin_x: -5.0, origin_y: -5.0 };
        let mut m = ElevationMap::new(g).unwrap();
        let pose = Pose3 { z: 1.0, pitch: 0.2, ..Default::default() };
        // Body-frame points of the world plane z = 0 seen from this pose.
        let pts: Vec<[f32; 3]> = (0..40)
            .map(|k| {
                let w = [0.5 + 0.1 * k as f64, 0.3, 0.0];
                let b = pose.inverse_transform(w);
                [b[0] as f32, b[1] as f32, b[2] as f32]
            })
            .collect();
        m.insert_cloud(&cloud(pts), &pose);
        for h in m.mean_heights().data.iter().filter(|h| h.is_finite()) {
            assert!(h.abs() < 1e-5, "height {h}");
        }
    }

    #[test]
    fn empty_geometry_is_rejected() {
        let g = GridGeometry { cols: 0, rows: 3, resolution: 1.0, origin_x: 0.0, origin_y: 0.0 };
        assert!(ElevationMap::new(g).is_err());
    }
}
