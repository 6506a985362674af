//! The map manager's world model (paper 004 section 3.4).
//!
//! At start-up the model is either flat terrain (elevation 0, as MRPTA does), wholly unknown, or
//! read from an external elevation model (an orbital DEM given as `Grid2<f32>` heights; those
//! cells are tagged *prior*, never *sensed*). During operations local maps from the terrain
//! evaluator are registered with the rover pose estimate and fused in. Cells never sensed keep
//! their unknown tags (traversability 0, goodness NaN) so planners can treat them as neutral
//! while still knowing they are unsensed (paper 004 section 3.5).
//!
//! Fusion rule: a local map is itself an accumulation of every range point its cells received
//! while in the rolling window, so a world cell is *replaced* by the local estimate (not
//! averaged with it, which would count the same points twice) whenever the local estimate rests
//! on at least as many points as the one stored. A cell revisited with fewer points keeps its
//! better-supported value.

use crate::{LocalMap, MappingError};
use rovernav_core::{Grid2, GridGeometry, Point2, Pose2, PoseEstimate};

/// Traversability value of an unknown (unsensed) cell.
pub const TRAVERSABILITY_UNKNOWN: u8 = 0;
/// Traversability value planners assume for unsensed cells (paper 004 sections 3.3, 3.5).
pub const TRAVERSABILITY_NEUTRAL: u8 = 7;

/// Parameters of the world model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WorldMapConfig {
    /// Variance assigned to heights taken from an external DEM (m^2).
    pub prior_variance: f32,
}

impl Default for WorldMapConfig {
    fn default() -> Self {
        // Orbital DEMs (HiRISE class) carry roughly metre-level vertical error.
        Self { prior_variance: 1.0 }
    }
}

/// Everything the world model knows about one cell.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WorldCell {
    /// Height (m), if known from sensing, a prior or the flat assumption.
    pub elevation: Option<f32>,
    /// Height variance (m^2), if known.
    pub variance: Option<f32>,
    /// Traversability 1..14, or `None` when unknown.
    pub traversability: Option<u8>,
    /// Goodness 0..1, or `None` when unknown.
    pub goodness: Option<f32>,
    /// Whether range data has been fused into this cell.
    pub sensed: bool,
    /// Whether the elevation came from the external DEM.
    pub prior: bool,
    /// Number of range points behind the sensed values.
    pub point_count: u32,
}

/// What one fusion did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FuseStats {
    /// World cells whose values were replaced by the local map's.
    pub cells_updated: usize,
    /// World cells the local map touched but that kept their better-supported values.
    pub cells_kept: usize,
}

/// The world model: co-registered layers over one world grid.
#[derive(Clone, Debug, PartialEq)]
pub struct WorldMap {
    elevation: Grid2<f32>,
    variance: Grid2<f32>,
    traversability: Grid2<u8>,
    goodness: Grid2<f32>,
    sensed: Grid2<bool>,
    prior: Grid2<bool>,
    point_count: Grid2<u32>,
}

/// Running aggregate of the local cells that land in one world cell.
#[derive(Clone, Copy, Debug)]
struct CellAggregate {
    points: u64,
    weight: f64,
    sum_z: f64,
    sum_second_moment: f64,
    min_traversability: u8,
    min_goodness: f32,
}

impl Default for CellAggregate {
    fn default() -> Self {
        Self {
            points: 0,
            weight: 0.0,
            sum_z: 0.0,
            sum_second_moment: 0.0,
            min_traversability: u8::MAX,
            min_goodness: f32::INFINITY,
        }
    }
}

impl CellAggregate {
    /// Adds local cell `i` of `local` (which must be sensed).
    fn add(&mut self, local: &LocalMap, i: usize) {
        let n = local.point_count.data[i];
        let z = local.elevation.data[i] as f64;
        let var = local.variance.data[i];
        let var = if var.is_finite() { var as f64 } else { 0.0 };
        let w = n as f64;
        self.points += n as u64;
        self.weight += w;
        self.sum_z += w * z;
        self.sum_second_moment += w * (var + z * z);
        let t = local.traversability.data[i];
        if t != TRAVERSABILITY_UNKNOWN {
            self.min_traversability = self.min_traversability.min(t);
        }
        let g = local.goodness.data[i];
        if g.is_finite() {
            self.min_goodness = self.min_goodness.min(g);
        }
    }
}

impl WorldMap {
    /// A model with every layer unknown and elevation `initial_height` (NaN for unknown).
    fn with_height(geometry: GridGeometry, initial_height: f32) -> Result<Self, MappingError> {
        if geometry.is_empty() {
            return Err(MappingError::InvalidParameter {
                field: "geometry",
                reason: "the world grid must have at least one cell".into(),
            });
        }
        if !(geometry.resolution.is_finite() && geometry.resolution > 0.0) {
            return Err(MappingError::InvalidParameter {
                field: "geometry.resolution",
                reason: format!("must be a positive finite length, got {}", geometry.resolution),
            });
        }
        Ok(Self {
            elevation: Grid2::filled(geometry, initial_height),
            variance: Grid2::filled(geometry, f32::NAN),
            traversability: Grid2::filled(geometry, TRAVERSABILITY_UNKNOWN),
            goodness: Grid2::filled(geometry, f32::NAN),
            sensed: Grid2::filled(geometry, false),
            prior: Grid2::filled(geometry, false),
            point_count: Grid2::filled(geometry, 0),
        })
    }

    /// A flat world (elevation 0 everywhere, as MRPTA starts) with every cell unsensed.
    pub fn flat(geometry: GridGeometry) -> Result<Self, MappingError> {
        Self::with_height(geometry, 0.0)
    }

    /// A world with no height information at all.
    pub fn unknown(geometry: GridGeometry) -> Result<Self, MappingError> {
        Self::with_height(geometry, f32::NAN)
    }

    /// A world initialised from an external DEM (the orbital prior). Finite heights are tagged
    /// prior with `config.prior_variance`; non-finite heights stay unknown. Nothing is sensed.
    pub fn from_dem(dem: &Grid2<f32>, config: WorldMapConfig) -> Result<Self, MappingError> {
        if dem.data.len() != dem.geometry.len() {
            return Err(MappingError::LayerSize {
                layer: "dem",
                expected: dem.geometry.len(),
                got: dem.data.len(),
            });
        }
        if !(config.prior_variance.is_finite() && config.prior_variance >= 0.0) {
            return Err(MappingError::InvalidParameter {
                field: "prior_variance",
                reason: format!("must be finite and >= 0, got {}", config.prior_variance),
            });
        }
        let mut map = Self::with_height(dem.geometry, f32::NAN)?;
        for (i, &h) in dem.data.iter().enumerate() {
            if h.is_finite() {
                map.elevation.data[i] = h;
                map.variance.data[i] = config.prior_variance;
                map.prior.data[i] = true;
            }
        }
        Ok(map)
    }

    /// Placement of the world grid.
    pub fn geometry(&self) -> GridGeometry {
        self.elevation.geometry
    }
    /// Elevation layer (m; NaN unknown).
    pub fn elevation(&self) -> &Grid2<f32> {
        &self.elevation
    }
    /// Height variance layer (m^2; NaN unknown).
    pub fn variance(&self) -> &Grid2<f32> {
        &self.variance
    }
    /// Traversability layer (1..14; 0 unknown).
    pub fn traversability(&self) -> &Grid2<u8> {
        &self.traversability
    }
    /// Goodness layer (0..1; NaN unknown).
    pub fn goodness(&self) -> &Grid2<f32> {
        &self.goodness
    }
    /// Sensed layer: true where range data was fused.
    pub fn sensed(&self) -> &Grid2<bool> {
        &self.sensed
    }
    /// Prior layer: true where the elevation came from the external DEM.
    pub fn prior(&self) -> &Grid2<bool> {
        &self.prior
    }
    /// Number of range points behind each sensed cell.
    pub fn point_count(&self) -> &Grid2<u32> {
        &self.point_count
    }

    /// Everything known about the cell containing world point `(x, y)`; `None` outside the map.
    pub fn cell_at(&self, x: f64, y: f64) -> Option<WorldCell> {
        let (c, r) = self.geometry().cell_of(x, y)?;
        let i = self.geometry().index(c, r);
        let finite = |v: f32| v.is_finite().then_some(v);
        let t = self.traversability.data[i];
        Some(WorldCell {
            elevation: finite(self.elevation.data[i]),
            variance: finite(self.variance.data[i]),
            traversability: (t != TRAVERSABILITY_UNKNOWN).then_some(t),
            goodness: finite(self.goodness.data[i]),
            sensed: self.sensed.data[i],
            prior: self.prior.data[i],
            point_count: self.point_count.data[i],
        })
    }

    /// Height at a world point, if known.
    pub fn elevation_at(&self, x: f64, y: f64) -> Option<f32> {
        self.cell_at(x, y)?.elevation
    }

    /// Traversability at a world point, `None` when unknown or outside the map.
    pub fn traversability_at(&self, x: f64, y: f64) -> Option<u8> {
        self.cell_at(x, y)?.traversability
    }

    /// Traversability a planner should use: unknown cells inside the map count as neutral (7);
    /// `None` outside the map.
    pub fn planning_traversability_at(&self, x: f64, y: f64) -> Option<u8> {
        let cell = self.cell_at(x, y)?;
        Some(cell.traversability.unwrap_or(TRAVERSABILITY_NEUTRAL))
    }

    /// Whether the cell containing a world point has been sensed.
    pub fn is_sensed(&self, x: f64, y: f64) -> bool {
        self.cell_at(x, y).is_some_and(|c| c.sensed)
    }

    /// Fuses a local map, re-registered with the current pose estimate.
    ///
    /// The local map's data was placed in the world with `local.reference`; if localisation has
    /// since corrected the estimate, the whole local map is moved rigidly by
    /// `estimate o reference^-1` before fusion. Local cells are aggregated into coarser world
    /// cells (count-weighted mean height, pooled variance, minimum traversability and goodness:
    /// the most cautious assessment wins); a world grid finer than the local one samples the
    /// local cell under each world cell centre.
    pub fn fuse(&mut self, local: &LocalMap, estimate: &PoseEstimate) -> Result<FuseStats, MappingError> {
        local.validate()?;
        let correction = Correction::new(local.reference, estimate.pose.pose2());
        let lg = local.elevation.geometry;
        let wg = self.geometry();
        // World-cell window touched by the moved local map.
        let corners = [
            (lg.origin_x, lg.origin_y),
            (lg.origin_x + lg.width_m(), lg.origin_y),
            (lg.origin_x, lg.origin_y + lg.height_m()),
            (lg.origin_x + lg.width_m(), lg.origin_y + lg.height_m()),
        ]
        .map(|(x, y)| correction.forward(Point2::new(x, y)));
        let min_x = corners.iter().map(|p| p.x).fold(f64::INFINITY, f64::min);
        let max_x = corners.iter().map(|p| p.x).fold(f64::NEG_INFINITY, f64::max);
        let min_y = corners.iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
        let max_y = corners.iter().map(|p| p.y).fold(f64::NEG_INFINITY, f64::max);
        let col_range = |v: f64| ((v - wg.origin_x) / wg.resolution).floor();
        let row_range = |v: f64| ((v - wg.origin_y) / wg.resolution).floor();
        let c0 = col_range(min_x).max(0.0);
        let c1 = col_range(max_x).min(wg.cols as f64 - 1.0);
        let r0 = row_range(min_y).max(0.0);
        let r1 = row_range(max_y).min(wg.rows as f64 - 1.0);
        if !(c0 <= c1 && r0 <= r1) {
            return Ok(FuseStats::default());
        }
        let (c0, c1, r0, r1) = (c0 as usize, c1 as usize, r0 as usize, r1 as usize);
        let win_cols = c1 - c0 + 1;
        let mut aggregates = vec![CellAggregate::default(); win_cols * (r1 - r0 + 1)];

        if wg.resolution >= lg.resolution {
            for row in 0..lg.rows {
                for col in 0..lg.cols {
                    let i = lg.index(col, row);
                    if local.point_count.data[i] == 0 || !local.elevation.data[i].is_finite() {
                        continue;
                    }
                    let (x, y) = lg.center(col, row);
                    let p = correction.forward(Point2::new(x, y));
                    if let Some((wc, wr)) = wg.cell_of(p.x, p.y)
                        && (c0..=c1).contains(&wc)
                        && (r0..=r1).contains(&wr)
                    {
                        aggregates[(wr - r0) * win_cols + (wc - c0)].add(local, i);
                    }
                }
            }
        } else {
            for wr in r0..=r1 {
                for wc in c0..=c1 {
                    let (x, y) = wg.center(wc, wr);
                    let p = correction.inverse(Point2::new(x, y));
                    if let Some((lc, lr)) = lg.cell_of(p.x, p.y) {
                        let i = lg.index(lc, lr);
                        if local.point_count.data[i] > 0 && local.elevation.data[i].is_finite() {
                            aggregates[(wr - r0) * win_cols + (wc - c0)].add(local, i);
                        }
                    }
                }
            }
        }

        let mut stats = FuseStats::default();
        for (k, agg) in aggregates.iter().enumerate() {
            if agg.weight <= 0.0 {
                continue;
            }
            let wc = c0 + k % win_cols;
            let wr = r0 + k / win_cols;
            let i = wg.index(wc, wr);
            let points = agg.points.min(u32::MAX as u64) as u32;
            if self.sensed.data[i] && points < self.point_count.data[i] {
                stats.cells_kept += 1;
                continue;
            }
            let mean = agg.sum_z / agg.weight;
            let variance = (agg.sum_second_moment / agg.weight - mean * mean).max(0.0);
            self.elevation.data[i] = mean as f32;
            self.variance.data[i] = variance as f32;
            self.traversability.data[i] = if agg.min_traversability == u8::MAX {
                TRAVERSABILITY_UNKNOWN
            } else {
                agg.min_traversability
            };
            self.goodness.data[i] = if agg.min_goodness.is_finite() { agg.min_goodness } else { f32::NAN };
            self.sensed.data[i] = true;
            self.point_count.data[i] = points;
            stats.cells_updated += 1;
        }
        Ok(stats)
    }
}

/// The rigid planar motion `estimate o reference^-1` that re-registers a local map.
struct Correction {
    reference: Pose2,
    estimate: Pose2,
}

impl Correction {
    fn new(reference: Pose2, estimate: Pose2) -> Self {
        Self { reference, estimate }
    }
    /// Local-map world coordinates to corrected world coordinates.
    fn forward(&self, p: Point2) -> Point2 {
        self.estimate.transform(self.reference.inverse_transform(p))
    }
    /// Corrected world coordinates back to local-map world coordinates.
    fn inverse(&self, p: Point2) -> Point2 {
        self.reference.transform(self.estimate.inverse_transform(p))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rovernav_core::Pose3;

    fn geometry(cols: usize, rows: usize, res: f64, ox: f64, oy: f64) -> GridGeometry {
        GridGeometry { cols, rows, resolution: res, origin_x: ox, origin_y: oy }
    }

    /// A local map whose sensed cells hold height = x + 2y (cell centre), variance 0.01,
    /// `points` points, traversability 9 and goodness 0.5.
    fn local_ramp(
        g: GridGeometry,
        reference: Pose2,
        points: u32,
        sensed: impl Fn(usize, usize) -> bool,
    ) -> LocalMap {
        let mut m = LocalMap {
            reference,
            elevation: Grid2::filled(g, f32::NAN),
            variance: Grid2::filled(g, f32::NAN),
            point_count: Grid2::filled(g, 0),
            traversability: Grid2::filled(g, 0),
            goodness: Grid2::filled(g, f32::NAN),
        };
        for r in 0..g.rows {
            for c in 0..g.cols {
                if sensed(c, r) {
                    let (x, y) = g.center(c, r);
                    let i = g.index(c, r);
                    m.elevation.data[i] = (x + 2.0 * y) as f32;
                    m.variance.data[i] = 0.01;
                    m.point_count.data[i] = points;
                    m.traversability.data[i] = 9;
                    m.goodness.data[i] = 0.5;
                }
            }
        }
        m
    }

    fn estimate_at(p: Pose2) -> PoseEstimate {
        PoseEstimate {
            pose: Pose3 { x: p.x, y: p.y, yaw: p.yaw, ..Default::default() },
            covariance: [[0.0; 3]; 3],
        }
    }

    #[test]
    fn flat_world_is_height_zero_and_unsensed() {
        let w = WorldMap::flat(geometry(10, 10, 1.0, 0.0, 0.0)).unwrap();
        let c = w.cell_at(3.5, 3.5).unwrap();
        assert_eq!(c.elevation, Some(0.0));
        assert!(!c.sensed && !c.prior);
        assert_eq!(c.traversability, None);
        assert_eq!(w.planning_traversability_at(3.5, 3.5), Some(TRAVERSABILITY_NEUTRAL));
        assert!(w.cell_at(-0.5, 3.0).is_none());
        assert!(WorldMap::unknown(geometry(0, 10, 1.0, 0.0, 0.0)).is_err());
    }

    #[test]
    fn dem_prior_is_tagged_prior_not_sensed() {
        let g = geometry(3, 2, 1.0, 0.0, 0.0);
        let dem = Grid2 { geometry: g, data: vec![1.0, 2.0, f32::NAN, 4.0, 5.0, 6.0] };
        let w = WorldMap::from_dem(&dem, WorldMapConfig::default()).unwrap();
        let c = w.cell_at(1.5, 0.5).unwrap();
        assert_eq!(c.elevation, Some(2.0));
        assert!(c.prior && !c.sensed);
        assert_eq!(c.variance, Some(1.0));
        let unknown = w.cell_at(2.5, 0.5).unwrap();
        assert!(unknown.elevation.is_none() && !unknown.prior);
        let bad = Grid2 { geometry: g, data: vec![0.0; 5] };
        assert!(matches!(
            WorldMap::from_dem(&bad, WorldMapConfig::default()),
            Err(MappingError::LayerSize { layer: "dem", expected: 6, got: 5 })
        ));
    }

    #[test]
    fn fusion_at_same_resolution_copies_sensed_cells_and_keeps_unknowns() {
        let lg = geometry(4, 4, 0.5, 1.0, 1.0);
        let reference = Pose2::new(2.0, 2.0, 0.3);
        let local = local_ramp(lg, reference, 10, |c, _| c < 2);
        let mut w = WorldMap::flat(geometry(20, 20, 0.5, 0.0, 0.0)).unwrap();
        let stats = w.fuse(&local, &estimate_at(reference)).unwrap();
        assert_eq!(stats.cells_updated, 8);
        // Cell centred (1.25, 1.75): height 1.25 + 3.5.
        let c = w.cell_at(1.25, 1.75).unwrap();
        assert!((c.elevation.unwrap() - 4.75).abs() < 1e-6);
        assert!(c.sensed && c.traversability == Some(9) && c.point_count == 10);
        // Unsensed local cells leave the world cell untouched and tagged unknown.
        let u = w.cell_at(2.75, 1.75).unwrap();
        assert!(!u.sensed && u.traversability.is_none() && u.elevation == Some(0.0));
    }

    #[test]
    fn coarser_world_cells_take_count_weighted_mean_and_pooled_variance() {
        let lg = geometry(2, 2, 0.5, 0.0, 0.0);
        let reference = Pose2::new(0.5, 0.5, 0.0);
        let mut local = local_ramp(lg, reference, 1, |_, _| true);
        // Heights 0.75, 1.25 (row 0) and 1.75, 2.25 (row 1); give the last cell 3 points.
        local.point_count.data[3] = 3;
        local.traversability.data[2] = 4;
        let mut w = WorldMap::unknown(geometry(1, 1, 1.0, 0.0, 0.0)).unwrap();
        w.fuse(&local, &estimate_at(reference)).unwrap();
        let c = w.cell_at(0.5, 0.5).unwrap();
        let mean = (0.75 + 1.25 + 1.75 + 3.0 * 2.25) / 6.0;
        assert!((c.elevation.unwrap() as f64 - mean).abs() < 1e-6);
        let second =
            (0.75f64.powi(2) + 1.25f64.powi(2) + 1.75f64.powi(2) + 3.0 * 2.25f64.powi(2)) / 6.0 + 0.01;
        assert!((c.variance.unwrap() as f64 - (second - mean * mean)).abs() < 1e-5);
        assert_eq!(c.traversability, Some(4));
        assert_eq!(c.point_count, 6);
    }

    #[test]
    fn corrected_estimate_moves_the_local_map_rigidly() {
        let lg = geometry(2, 2, 0.5, 0.0, 0.0);
        let reference = Pose2::new(0.5, 0.5, 0.0);
        let local = local_ramp(lg, reference, 5, |c, r| c == 0 && r == 0);
        let mut w = WorldMap::unknown(geometry(40, 40, 0.5, -10.0, -10.0)).unwrap();
        // The estimate now says the rover was 3 m further east and turned by 90 degrees.
        let corrected = Pose2::new(3.5, 0.5, std::f64::consts::FRAC_PI_2);
        w.fuse(&local, &estimate_at(corrected)).unwrap();
        // Local cell centre (0.25, 0.25) is (-0.25, -0.25) from the reference; rotated by 90
        // degrees that is (0.25, -0.25) from the corrected pose: world (3.75, 0.25).
        let c = w.cell_at(3.75, 0.25).unwrap();
        assert!(c.sensed);
        assert!((c.elevation.unwrap() - 0.75).abs() < 1e-6);
        assert!(!w.is_sensed(0.25, 0.25));
    }

    #[test]
    fn better_supported_cells_are_kept_and_finer_world_samples_local_cells() {
        let lg = geometry(2, 2, 1.0, 0.0, 0.0);
        let reference = Pose2::new(1.0, 1.0, 0.0);
        let rich = local_ramp(lg, reference, 50, |_, _| true);
        let mut poor = local_ramp(lg, reference, 2, |_, _| true);
        poor.elevation.data.iter_mut().for_each(|z| *z = 100.0);
        let mut w = WorldMap::unknown(geometry(8, 8, 0.25, 0.0, 0.0)).unwrap();
        let s1 = w.fuse(&rich, &estimate_at(reference)).unwrap();
        assert_eq!(s1.cells_updated, 64);
        let s2 = w.fuse(&poor, &estimate_at(reference)).unwrap();
        assert_eq!(s2.cells_kept, 64);
        // World cell (0.125, 0.125) lies in local cell (0, 0): height 0.5 + 1.0.
        assert!((w.elevation_at(0.125, 0.125).unwrap() - 1.5).abs() < 1e-6);
    }

    #[test]
    fn mismatched_local_layers_are_rejected() {
        let lg = geometry(2, 2, 1.0, 0.0, 0.0);
        let mut local = local_ramp(lg, Pose2::default(), 1, |_, _| true);
        local.goodness.data.pop();
        let mut w = WorldMap::unknown(lg).unwrap();
        assert!(matches!(
            w.fuse(&local, &PoseEstimate::default()),
            Err(MappingError::LayerSize { layer: "goodness", .. })
        ));
    }
}
