//! The terrain evaluator (paper 004 section 3.3): range data into a robot-centred toroidal grid
//! (T-grid), assessed into elevation, hazard, traversability and goodness layers, with requests
//! for more data when the point density in front of the rover is too low.
//!
//! Each update recentres the T-grid on the pose estimate (cells falling off the grid are cleared,
//! nothing is copied), bins the new points into the cells' running sums, and reassesses the
//! whole window with flat arrays: per-cell statistics, the footprint step/slope model, MRPTA
//! traversability and GESTALT goodness. With a per-sensor range-noise model each point carries
//! the height noise its range implies (stereo error grows with range squared), and a raised cell
//! within that noise (beyond what the hazard margin covers) of the step limit becomes an
//! uncertain hazard: a few far points on a rock's near face read its crest low.

use crate::PerceptionError;
use crate::cell::CellStats;
use crate::cobstacle::{CObstacle, SensedWedge, build_c_obstacles, label_c_obstacles};
use crate::config::{HazardHeight, RangeNoise, TerrainConfig};
use crate::elevation::world_points;
use crate::footprint::analyse_footprints_with_tolerance;
use crate::goodness::goodness_layer;
use crate::traversability::traversability_layer;
use rovernav_core::{
    CameraKind, Grid2, GridGeometry, Point2, PointCloud, Pose2, Pose3, PoseEstimate, SenseRequest, angle_diff,
};
use rovernav_mapping::{LocalMap, RollingGrid};

/// The assessed layers of one window, all on the same world-aligned geometry.
#[derive(Clone, Debug, PartialEq)]
pub struct TerrainLayers {
    /// Elevation, variance, point count, traversability and goodness: what the map manager fuses.
    pub map: LocalMap,
    /// Obstacle cells of the step/slope model (the hazard classification).
    pub hazard: Grid2<bool>,
    /// Hazard cells whose measured height stays under the step limit but whose height noise
    /// (see [`TerrainConfig::hazard_confidence`]) leaves room for a step over it; a closer look
    /// settles them.
    pub uncertain_hazard: Grid2<bool>,
    /// Step within the footprint window centred on each cell (m; NaN not assessed).
    pub step: Grid2<f32>,
    /// Slope of the footprint plane centred on each cell (rad; NaN not assessed).
    pub slope: Grid2<f32>,
    /// Roughness about the footprint plane centred on each cell (m; NaN not assessed).
    pub roughness: Grid2<f32>,
}

impl TerrainLayers {
    /// Placement of the layers.
    pub fn geometry(&self) -> GridGeometry {
        self.map.elevation.geometry
    }

    /// Layers of a window where nothing is sensed.
    pub fn unknown(geometry: GridGeometry, reference: Pose2) -> Self {
        Self {
            map: LocalMap {
                reference,
                elevation: Grid2::filled(geometry, f32::NAN),
                variance: Grid2::filled(geometry, f32::NAN),
                point_count: Grid2::filled(geometry, 0),
                traversability: Grid2::filled(geometry, 0),
                goodness: Grid2::filled(geometry, f32::NAN),
            },
            hazard: Grid2::filled(geometry, false),
            uncertain_hazard: Grid2::filled(geometry, false),
            step: Grid2::filled(geometry, f32::NAN),
            slope: Grid2::filled(geometry, f32::NAN),
            roughness: Grid2::filled(geometry, f32::NAN),
        }
    }

    /// C-obstacles of the hazard cells, grown by rover radius + safety buffer and labelled.
    pub fn c_obstacles(
        &self,
        config: &TerrainConfig,
        sensed: &[SensedWedge],
        goal: Option<Point2>,
    ) -> Vec<CObstacle> {
        let mut obstacles = build_c_obstacles(&self.hazard, config.growth(), config.max_arc_step);
        label_c_obstacles(&mut obstacles, sensed, goal);
        obstacles
    }
}

/// Assesses a window of cell statistics given in row-major order (row 0 south).
///
/// `centre` is the grid cell of the rover (the T-grid centre, for the neighbourhood estimate)
/// and `reference` the pose estimate the points were placed with.
pub fn assess_cells<'a>(
    geometry: GridGeometry,
    cells: impl Iterator<Item = &'a CellStats>,
    centre: (usize, usize),
    reference: Pose2,
    config: &TerrainConfig,
) -> TerrainLayers {
    let n = geometry.len();
    let min_points = config.min_points_per_cell.max(1);
    // Cells with too few points count as unsensed throughout.
    let mut stats: Vec<CellStats> =
        cells.take(n).map(|c| if c.count >= min_points { *c } else { CellStats::EMPTY }).collect();
    stats.resize(n, CellStats::EMPTY);
    let heights: Vec<f32> = stats.iter().map(|c| c.mean().map_or(f32::NAN, |m| m as f32)).collect();
    let variance: Vec<f32> = stats.iter().map(|c| c.variance().map_or(f32::NAN, |v| v as f32)).collect();
    let counts: Vec<u32> = stats.iter().map(|c| c.count).collect();

    let (cols, rows, res) = (geometry.cols, geometry.rows, geometry.resolution);
    let noise_var = config.sensor_noise * config.sensor_noise;
    let hazard_heights: Vec<f32> = match config.hazard_height {
        HazardHeight::Mean => heights.clone(),
        HazardHeight::Max => stats.iter().map(|c| if c.count > 0 { c.max_z } else { f32::NAN }).collect(),
        HazardHeight::Top => stats.iter().map(|c| top_height(c, noise_var)).collect(),
    };
    let tolerance: Vec<f32> = if config.hazard_confidence > 0.0 {
        stats.iter().map(|c| (config.hazard_confidence * excess_noise_sigma(c, noise_var)) as f32).collect()
    } else {
        Vec::new()
    };
    let footprint = analyse_footprints_with_tolerance(
        &hazard_heights,
        &tolerance,
        cols,
        rows,
        res,
        &config.footprint_params(),
    );
    let traversability =
        traversability_layer(&stats, &heights, cols, rows, res, centre, &config.traversability_params());
    let goodness = goodness_layer(&heights, &footprint, &config.goodness_params());
    let grid = |data| Grid2 { geometry, data };
    TerrainLayers {
        map: LocalMap {
            reference,
            elevation: grid(heights),
            variance: grid(variance),
            point_count: Grid2 { geometry, data: counts },
            traversability: Grid2 { geometry, data: traversability },
            goodness: grid(goodness),
        },
        hazard: Grid2 { geometry, data: footprint.obstacle },
        uncertain_hazard: Grid2 { geometry, data: footprint.uncertain },
        step: grid(footprint.step),
        slope: grid(footprint.slope),
        roughness: grid(footprint.roughness),
    }
}

/// [`HazardHeight::Top`] of one cell: the mean plus the spread of its points beyond the sensor
/// noise (variance `noise_var`), capped at the highest point; NaN when unsensed.
fn top_height(cell: &CellStats, noise_var: f64) -> f32 {
    // The mean as the elevation layer stores it (f32), so Top starts from that layer's value.
    let Some(mean) = cell.mean().map(|m| m as f32) else { return f32::NAN };
    match cell.variance() {
        Some(var) if cell.count > 1 => {
            (mean as f64 + (var - noise_var).max(0.0).sqrt()).min(cell.max_z as f64) as f32
        }
        _ => mean,
    }
}

/// Height noise of a cell's points beyond the configured `sensor_noise` (variance `noise_var`),
/// as a standard deviation (m): far-range stereo points scatter more than the hazard margin
/// was set for, and a cell holding only a few of them can miss a rock's crest by about that.
fn excess_noise_sigma(cell: &CellStats, noise_var: f64) -> f64 {
    cell.noise_variance().map_or(0.0, |v| (v - noise_var).max(0.0).sqrt())
}

/// Variance of a range point's height (m^2) under a range error along the ray from `sensor`
/// (world frame): the error's vertical share is the ray's steepness.
fn height_noise_variance(noise: &RangeNoise, sensor: [f64; 3], p: [f64; 3]) -> f64 {
    let d = [p[0] - sensor[0], p[1] - sensor[1], p[2] - sensor[2]];
    let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    if !(r.is_finite() && r > 0.0) {
        return 0.0;
    }
    (noise.sigma(r) * d[2].abs() / r).powi(2)
}

/// A request for more range data: the sparsest sector in front of the rover is below the
/// configured density.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MoreDataRequest {
    /// Bearing of the sector centre in the body frame (rad, counter-clockwise from forward).
    pub bearing: f64,
    /// The same bearing in the world frame (rad, counter-clockwise from east).
    pub world_bearing: f64,
    /// Measured density in the sector (points per m^2).
    pub density: f64,
    /// Configured minimum (points per m^2).
    pub required: f64,
}

impl MoreDataRequest {
    /// The sensing command that images this bearing with the given sensor.
    pub fn sense_request(&self, sensor: CameraKind) -> SenseRequest {
        match sensor {
            CameraKind::Mast => SenseRequest::Mast { pan: self.bearing },
            CameraKind::Lidar => SenseRequest::Lidar { pan: self.bearing },
            CameraKind::BodyFront => SenseRequest::BodyFront,
            CameraKind::BodyRear => SenseRequest::BodyRear,
        }
    }
}

/// The MRPTA terrain evaluator: a T-grid of cell statistics that follows the rover.
#[derive(Clone, Debug)]
pub struct TerrainEvaluator {
    config: TerrainConfig,
    grid: RollingGrid<CellStats>,
    layers: TerrainLayers,
}

impl TerrainEvaluator {
    /// An evaluator with an empty T-grid centred on `start`.
    pub fn new(config: TerrainConfig, start: Pose2) -> Result<Self, PerceptionError> {
        config.validate()?;
        let grid = RollingGrid::new(
            config.cols,
            config.rows,
            config.resolution,
            CellStats::EMPTY,
            start.position(),
        )?;
        let layers = TerrainLayers::unknown(grid.geometry(), start);
        Ok(Self { config, grid, layers })
    }

    /// The configuration.
    pub fn config(&self) -> &TerrainConfig {
        &self.config
    }

    /// The T-grid of cell statistics.
    pub fn grid(&self) -> &RollingGrid<CellStats> {
        &self.grid
    }

    /// The layers of the last assessment.
    pub fn layers(&self) -> &TerrainLayers {
        &self.layers
    }

    /// Moves the T-grid so the rover is in its central cell (cells falling off are cleared).
    pub fn recenter(&mut self, position: Point2) {
        self.grid.recenter(position);
    }

    /// Bins a body-frame cloud placed with the pose estimate `pose`; returns the points kept.
    pub fn insert_cloud(&mut self, cloud: &PointCloud, pose: &Pose3) -> usize {
        let noise = self.config.range_noise.map(|n| n.of(cloud.camera));
        let sensor = pose.transform(cloud.origin);
        let mut kept = 0;
        for p in world_points(cloud, pose) {
            if let Some((slot, centre)) = self.grid.locate(p[0], p[1]) {
                let noise_var = noise.map_or(0.0, |n| height_noise_variance(&n, sensor, p));
                self.grid.slot_mut(slot).add_with_noise(p[0] - centre.x, p[1] - centre.y, p[2], noise_var);
                kept += 1;
            }
        }
        kept
    }

    /// Reassesses the whole window; `reference` is the pose estimate the data was placed with.
    pub fn assess(&mut self, reference: Pose2) -> &TerrainLayers {
        let centre = (self.grid.cols() / 2, self.grid.rows() / 2);
        self.layers =
            assess_cells(self.grid.geometry(), self.grid.iter_window(), centre, reference, &self.config);
        &self.layers
    }

    /// One full update: recentre on the estimate, bin the clouds, reassess.
    pub fn update(&mut self, clouds: &[PointCloud], estimate: &PoseEstimate) -> &TerrainLayers {
        let pose = estimate.pose;
        self.recenter(Point2::new(pose.x, pose.y));
        for cloud in clouds {
            self.insert_cloud(cloud, &pose);
        }
        self.assess(pose.pose2())
    }

    /// `(body bearing, points per m^2)` of each sector in front of `pose`, from the right-most
    /// sector (most negative bearing) to the left-most.
    pub fn sector_densities(&self, pose: Pose2) -> Vec<(f64, f64)> {
        let d = &self.config.density;
        let sectors = d.sectors.max(1);
        let width = 2.0 * d.half_angle / sectors as f64;
        let mut points = vec![0u64; sectors];
        let mut cells = vec![0u64; sectors];
        let res = self.grid.resolution();
        let reach = (d.far / res).ceil() as i64 + 1;
        let Some((cc, cr)) = self.grid.cell_of(pose.x, pose.y) else {
            return Vec::new();
        };
        let (cols, rows) = (self.grid.cols() as i64, self.grid.rows() as i64);
        for r in (cr as i64 - reach).max(0)..(cr as i64 + reach + 1).min(rows) {
            for c in (cc as i64 - reach).max(0)..(cc as i64 + reach + 1).min(cols) {
                let p = self.grid.center(c as usize, r as usize);
                let v = p.sub(pose.position());
                let dist = v.norm();
                if dist < d.near || dist > d.far {
                    continue;
                }
                let rel = angle_diff(v.angle(), pose.yaw);
                if rel.abs() > d.half_angle {
                    continue;
                }
                let k = (((rel + d.half_angle) / width) as usize).min(sectors - 1);
                cells[k] += 1;
                points[k] += self.grid.get(c as usize, r as usize).count as u64;
            }
        }
        (0..sectors)
            .map(|k| {
                let bearing = -d.half_angle + (k as f64 + 0.5) * width;
                let area = cells[k] as f64 * res * res;
                let density = if area > 0.0 { points[k] as f64 / area } else { 0.0 };
                (bearing, density)
            })
            .collect()
    }

    /// Asks for more data at the bearing of the sparsest sector in front of the rover when its
    /// point density is below the configured minimum; `None` when coverage is sufficient.
    pub fn density_request(&self, pose: Pose2) -> Option<MoreDataRequest> {
        let required = self.config.density.min_points_per_m2;
        self.sector_densities(pose)
            .into_iter()
            .filter(|&(_, density)| density < required)
            // Sparsest first; among equals, the one nearest straight ahead.
            .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.abs().total_cmp(&b.0.abs())))
            .map(|(bearing, density)| MoreDataRequest {
                bearing,
                world_bearing: rovernav_core::wrap_angle(pose.yaw + bearing),
                density,
                required,
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 15 x 15 grid of 0.1 m cells of flat ground at z = 0, sampled by 16 points per cell with
    /// +-`noise` alternating, and one cell at (7, 7) whose points are half on a rock top at
    /// `rock` m and half on the ground (a cell straddling a small rock's edge).
    fn straddled_rock(rock: f64, noise: f64) -> Vec<CellStats> {
        let mut cells = vec![CellStats::EMPTY; 15 * 15];
        for (i, cell) in cells.iter_mut().enumerate() {
            for k in 0..16 {
                let (dx, dy) = (-0.04 + 0.025 * (k % 4) as f64, -0.04 + 0.025 * (k / 4) as f64);
                let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
                let z = if i == 7 * 15 + 7 && k >= 8 { rock } else { sign * noise };
                cell.add(dx, dy, z);
            }
        }
        cells
    }

    fn hazard_at_rock(height: HazardHeight, rock: f64, noise: f64) -> bool {
        let geometry = GridGeometry { cols: 15, rows: 15, resolution: 0.1, origin_x: 0.0, origin_y: 0.0 };
        let config = TerrainConfig {
            resolution: 0.1,
            clearance: 0.15,
            footprint_radius: 0.5,
            sensor_noise: 0.01,
            hazard_height: height,
            ..TerrainConfig::default()
        };
        let cells = straddled_rock(rock, noise);
        let layers = assess_cells(geometry, cells.iter(), (7, 7), Pose2::new(0.75, 0.75, 0.0), &config);
        layers.hazard.data.iter().any(|&h| h)
    }

    #[test]
    fn height_noise_is_the_vertical_share_of_the_range_error() {
        let mast = RangeNoise { constant: 0.0, quadratic: 0.004 };
        // Sensor 1.2 m up, ground point 1.6 m out: range 2 m, sigma_r = 0.016 m, of which the
        // share 1.2 / 2 is vertical.
        let (sensor, p) = ([0.0, 0.0, 1.2], [1.6, 0.0, 0.0]);
        let expected = (0.016f64 * 0.6).powi(2);
        assert!((height_noise_variance(&mast, sensor, p) - expected).abs() < 1e-12);
        // A level ray carries no height error; a point at the sensor none at all.
        assert_eq!(height_noise_variance(&mast, [0.0, 0.0, 0.0], [3.0, 4.0, 0.0]), 0.0);
        assert_eq!(height_noise_variance(&mast, sensor, sensor), 0.0);
    }

    #[test]
    fn far_points_raise_a_cell_within_tolerance_near_points_do_not() {
        // A cell of four points whose expected noise is 2.2 cm (mast at ~4.5 m) and one whose
        // noise is 5 mm (close range), against the 1 cm the hazard margin covers.
        let cell = |sigma: f64| {
            let mut c = CellStats::EMPTY;
            (0..4).for_each(|k| c.add_with_noise(0.0, 0.0, 0.01 * k as f64, sigma * sigma));
            c
        };
        let noise_var = 1e-4;
        let far = excess_noise_sigma(&cell(0.022), noise_var);
        assert!((far - (0.022f64.powi(2) - 1e-4).sqrt()).abs() < 1e-9);
        assert_eq!(excess_noise_sigma(&cell(0.005), noise_var), 0.0);
        assert_eq!(excess_noise_sigma(&CellStats::EMPTY, noise_var), 0.0);
    }

    #[test]
    fn top_height_sees_a_rock_the_cell_mean_halves() {
        // A 0.17 m rock over a 0.15 m clearance: the mixed cell's mean reads 0.085 m, its top
        // (mean + spread) reads the rock's 0.17 m.
        assert!(!hazard_at_rock(HazardHeight::Mean, 0.17, 0.0));
        assert!(hazard_at_rock(HazardHeight::Top, 0.17, 0.0));
        assert!(hazard_at_rock(HazardHeight::Max, 0.17, 0.0));
        // A 0.13 m rock is below the clearance whatever the estimate.
        assert!(!hazard_at_rock(HazardHeight::Top, 0.13, 0.0));
    }

    #[test]
    fn top_height_is_the_rock_on_a_straddling_cell_and_the_mean_on_noisy_ground() {
        let cell = |zs: &[f64]| {
            let mut c = CellStats::EMPTY;
            zs.iter().for_each(|&z| c.add(0.0, 0.0, z));
            c
        };
        // Half the points on a 0.17 m rock top: mean 0.085, spread 0.085.
        let straddling = cell(&[0.0, 0.0, 0.0, 0.0, 0.17, 0.17, 0.17, 0.17]);
        assert!((top_height(&straddling, 0.0) - 0.17).abs() < 1e-6);
        // Flat ground sampled with +-1 cm noise, the configured noise: the spread is all noise.
        let noisy = cell(&[0.01, -0.01, 0.01, -0.01]);
        assert!(top_height(&noisy, 1e-4).abs() < 1e-6);
        assert!((top_height(&noisy, 0.0) - 0.01).abs() < 1e-6, "without the discount it reads 1 cm high");
        assert!(top_height(&CellStats::EMPTY, 1e-4).is_nan());
    }

    #[test]
    fn top_height_discounts_noise_on_flat_ground() {
        // Flat ground with +-1 cm noise (the configured sensor noise) and a rock below the
        // clearance: the spread is all noise, so the top stays near the mean.
        assert!(!hazard_at_rock(HazardHeight::Top, 0.13, 0.01));
        assert!(hazard_at_rock(HazardHeight::Top, 0.17, 0.01));
    }
}
