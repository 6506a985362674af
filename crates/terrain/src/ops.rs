//! Queries and transforms of a `Dem`: gradient, slope and normal, min/max, cropping and
//! resampling.
//!
//! Local frame throughout: metres, x east, y north. Cropping keeps local coordinates (the crop's
//! grid origin is where the rectangle starts), so `to_projected` stays correct without touching
//! the georeference; `rebased` moves the grid origin back to local (0, 0) and shifts the
//! georeference to match.

use rovernav_core::{Grid2, GridGeometry};
use thiserror::Error;

use crate::dem::Dem;

/// An axis-aligned rectangle in a DEM's local frame (m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalRect {
    /// Western edge (m).
    pub x_min: f64,
    /// Southern edge (m).
    pub y_min: f64,
    /// Eastern edge (m).
    pub x_max: f64,
    /// Northern edge (m).
    pub y_max: f64,
}

impl LocalRect {
    /// A rectangle from its south-west corner and its size.
    pub fn from_corner_size(x_min: f64, y_min: f64, width: f64, height: f64) -> Self {
        Self { x_min, y_min, x_max: x_min + width, y_max: y_min + height }
    }

    /// A square of half-size `half` centred on (x, y).
    pub fn centered(x: f64, y: f64, half: f64) -> Self {
        Self { x_min: x - half, y_min: y - half, x_max: x + half, y_max: y + half }
    }
}

/// Why a DEM transform could not be done.
#[derive(Debug, Error, PartialEq)]
pub enum DemError {
    /// The requested rectangle does not overlap the DEM.
    #[error("region {0:?} does not overlap the DEM")]
    EmptyRegion(LocalRect),
    /// A resolution that is not a positive finite number.
    #[error("invalid resolution {0} m (must be positive and finite)")]
    InvalidResolution(f64),
    /// The result would have more cells than allowed.
    #[error("resampling to {cols}x{rows} cells exceeds the limit of {limit}")]
    TooLarge {
        /// Requested columns.
        cols: usize,
        /// Requested rows.
        rows: usize,
        /// Maximum cell count.
        limit: usize,
    },
}

/// Largest grid `resample` will build (cells), so a typo in a resolution cannot exhaust memory.
pub const MAX_RESAMPLE_CELLS: usize = 200_000_000;

impl Dem {
    /// Surface gradient (dz/dx, dz/dy) at a local point, by central differences of the bilinear
    /// surface one cell apart (one-sided at the edges); `None` where there is no height.
    pub fn gradient(&self, x: f64, y: f64) -> Option<(f64, f64)> {
        let g = &self.heights.geometry;
        let h = g.resolution;
        let centre = self.height(x, y)?;
        // The bilinear surface is flat beyond the outermost cell centres, so differences are
        // taken between points clamped to the hull of the centres, over the distance covered.
        let span = |v: f64, origin: f64, n: usize| {
            let (lo, hi) = (origin + 0.5 * h, origin + (n as f64 - 0.5) * h);
            ((v - h).clamp(lo, hi), (v + h).clamp(lo, hi))
        };
        let diff = |v: f64, (lo, hi): (f64, f64), at: &dyn Fn(f64) -> Option<f64>| {
            if hi - lo < 1e-9 * h {
                return Some(0.0); // a single row or column: no slope measurable
            }
            match (at(lo), at(hi)) {
                (Some(m), Some(p)) => Some((p - m) / (hi - lo)),
                (None, Some(p)) if hi > v => Some((p - centre) / (hi - v)),
                (Some(m), None) if v > lo => Some((centre - m) / (v - lo)),
                _ => None,
            }
        };
        let gx = diff(x, span(x, g.origin_x, g.cols), &|xs| self.height(xs, y))?;
        let gy = diff(y, span(y, g.origin_y, g.rows), &|ys| self.height(x, ys))?;
        Some((gx, gy))
    }

    /// Slope angle (rad, 0 = level) at a local point.
    pub fn slope(&self, x: f64, y: f64) -> Option<f64> {
        self.gradient(x, y).map(|(gx, gy)| gx.hypot(gy).atan())
    }

    /// Upward unit surface normal [nx, ny, nz] at a local point.
    pub fn normal(&self, x: f64, y: f64) -> Option<[f64; 3]> {
        self.gradient(x, y).map(|(gx, gy)| {
            let n = (gx * gx + gy * gy + 1.0).sqrt();
            [-gx / n, -gy / n, 1.0 / n]
        })
    }

    /// Cell size (m).
    pub fn resolution(&self) -> f64 {
        self.heights.geometry.resolution
    }

    /// Smallest and largest height, ignoring NaN; `None` when there is no data at all.
    pub fn min_max(&self) -> Option<(f32, f32)> {
        min_max_ignoring_nan(&self.heights.data)
    }

    /// Slope (rad) of every cell by Horn's 3x3 weighted differences (the method of common GIS
    /// tools), NaN on the border and next to missing data.
    pub fn slope_grid(&self) -> Grid2<f32> {
        let g = self.heights.geometry;
        let mut out = Grid2::filled(g, f32::NAN);
        if g.cols < 3 || g.rows < 3 {
            return out;
        }
        let z = &self.heights.data;
        let w = g.cols;
        let eight_h = 8.0 * g.resolution;
        for r in 1..g.rows - 1 {
            for c in 1..g.cols - 1 {
                let at = |dc: isize, dr: isize| {
                    z[(r as isize + dr) as usize * w + (c as isize + dc) as usize] as f64
                };
                let dzdx = ((at(1, 1) + 2.0 * at(1, 0) + at(1, -1))
                    - (at(-1, 1) + 2.0 * at(-1, 0) + at(-1, -1)))
                    / eight_h;
                let dzdy = ((at(-1, 1) + 2.0 * at(0, 1) + at(1, 1))
                    - (at(-1, -1) + 2.0 * at(0, -1) + at(1, -1)))
                    / eight_h;
                out.data[r * w + c] = dzdx.hypot(dzdy).atan() as f32;
            }
        }
        out
    }

    /// The cells overlapping a local rectangle, as a new DEM in the same local frame (same
    /// georeference; the grid origin snaps outwards to the source cell edges).
    pub fn crop(&self, rect: LocalRect) -> Result<Dem, DemError> {
        let g = &self.heights.geometry;
        let to_col = |x: f64| (x - g.origin_x) / g.resolution;
        let to_row = |y: f64| (y - g.origin_y) / g.resolution;
        let c0 = to_col(rect.x_min).floor().max(0.0);
        let r0 = to_row(rect.y_min).floor().max(0.0);
        let c1 = to_col(rect.x_max).ceil().min(g.cols as f64);
        let r1 = to_row(rect.y_max).ceil().min(g.rows as f64);
        if !(c1 > c0 && r1 > r0) {
            return Err(DemError::EmptyRegion(rect));
        }
        let (c0, r0, c1, r1) = (c0 as usize, r0 as usize, c1 as usize, r1 as usize);
        let geometry = GridGeometry {
            cols: c1 - c0,
            rows: r1 - r0,
            resolution: g.resolution,
            origin_x: g.origin_x + c0 as f64 * g.resolution,
            origin_y: g.origin_y + r0 as f64 * g.resolution,
        };
        let mut data = Vec::with_capacity(geometry.len());
        for r in r0..r1 {
            data.extend_from_slice(&self.heights.data[r * g.cols + c0..r * g.cols + c1]);
        }
        Ok(Dem { heights: Grid2 { geometry, data }, nodata: self.nodata, geo: self.geo.clone() })
    }

    /// The same DEM with its grid origin moved to local (0, 0) and the georeference shifted so
    /// every cell keeps its projected position.
    pub fn rebased(mut self) -> Dem {
        let g = &mut self.heights.geometry;
        self.geo.easting += g.origin_x;
        self.geo.northing += g.origin_y;
        g.origin_x = 0.0;
        g.origin_y = 0.0;
        self
    }

    /// The DEM resampled to a new cell size over the same extent (bilinear between the source
    /// cell centres; NaN where the source has no data). The cell count per axis is the extent
    /// divided by the resolution, rounded, at least 1.
    pub fn resample(&self, resolution: f64) -> Result<Dem, DemError> {
        if !(resolution.is_finite() && resolution > 0.0) {
            return Err(DemError::InvalidResolution(resolution));
        }
        let g = &self.heights.geometry;
        let cols = ((g.width_m() / resolution).round() as usize).max(1);
        let rows = ((g.height_m() / resolution).round() as usize).max(1);
        if cols.saturating_mul(rows) > MAX_RESAMPLE_CELLS {
            return Err(DemError::TooLarge { cols, rows, limit: MAX_RESAMPLE_CELLS });
        }
        let geometry = GridGeometry { cols, rows, resolution, origin_x: g.origin_x, origin_y: g.origin_y };
        let mut data = Vec::with_capacity(geometry.len());
        for r in 0..rows {
            let y = g.origin_y + (r as f64 + 0.5) * resolution;
            for c in 0..cols {
                let x = g.origin_x + (c as f64 + 0.5) * resolution;
                data.push(self.height(x, y).map_or(f32::NAN, |h| h as f32));
            }
        }
        Ok(Dem { heights: Grid2 { geometry, data }, nodata: self.nodata, geo: self.geo.clone() })
    }
}

/// Smallest and largest value of a slice, ignoring NaN.
pub fn min_max_ignoring_nan(values: &[f32]) -> Option<(f32, f32)> {
    values.iter().filter(|v| !v.is_nan()).fold(None, |acc, &v| match acc {
        None => Some((v, v)),
        Some((lo, hi)) => Some((lo.min(v), hi.max(v))),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A DEM sampling z = a + b x + c y + d x y at cell centres: bilinear interpolation
    /// reproduces such a surface exactly, so every query has a closed-form answer.
    fn bilinear_dem(cols: usize, rows: usize, res: f64, k: [f64; 4]) -> Dem {
        let mut dem = Dem::flat(cols, rows, res, 0.0);
        for r in 0..rows {
            for c in 0..cols {
                let (x, y) = dem.geometry().center(c, r);
                *dem.heights.get_mut(c, r) = (k[0] + k[1] * x + k[2] * y + k[3] * x * y) as f32;
            }
        }
        dem
    }

    #[test]
    fn plane_slope_and_normal_match_the_formula() {
        let (b, c) = (0.3, -0.4);
        let dem = bilinear_dem(20, 15, 0.5, [10.0, b, c, 0.0]);
        let expected = (0.5f64).atan(); // hypot(0.3, 0.4) = 0.5
        for &(x, y) in &[(5.0, 3.0), (0.3, 0.3), (9.9, 7.4), (2.2, 6.1)] {
            let (gx, gy) = dem.gradient(x, y).unwrap();
            assert!((gx - b).abs() < 1e-5 && (gy - c).abs() < 1e-5, "{gx} {gy}");
            assert!((dem.slope(x, y).unwrap() - expected).abs() < 1e-5);
            let n = dem.normal(x, y).unwrap();
            let len = (1.0f64 + 0.25).sqrt();
            assert!((n[0] + b / len).abs() < 1e-5 && (n[1] + c / len).abs() < 1e-5);
            assert!((n[2] - 1.0 / len).abs() < 1e-5);
        }
        assert_eq!(dem.gradient(-1.0, 3.0), None);
        let slopes = dem.slope_grid();
        let inner = *slopes.get(5, 5) as f64;
        assert!((inner - expected).abs() < 1e-5);
        assert!(slopes.get(0, 5).is_nan());
    }

    #[test]
    fn min_max_ignores_nan_and_empty_is_none() {
        let mut dem = bilinear_dem(4, 4, 1.0, [0.0, 1.0, 10.0, 0.0]);
        *dem.heights.get_mut(3, 3) = f32::NAN; // would be the maximum, 3.5 + 35
        assert_eq!(dem.min_max(), Some((0.5 + 5.0, 2.5 + 35.0)));
        assert_eq!(min_max_ignoring_nan(&[f32::NAN, f32::NAN]), None);
    }

    #[test]
    fn crop_keeps_heights_and_projected_positions() {
        let mut dem = bilinear_dem(40, 30, 0.5, [1.0, 0.2, -0.1, 0.01]);
        dem.geo.easting = 1000.0;
        dem.geo.northing = -500.0;
        let crop = dem.crop(LocalRect { x_min: 3.2, y_min: 4.9, x_max: 11.0, y_max: 9.1 }).unwrap();
        // Outward snapping: 3.2 -> 3.0, 4.9 -> 4.5, 11.0 -> 11.0, 9.1 -> 9.5.
        assert_eq!(crop.geometry().origin_x, 3.0);
        assert_eq!(crop.geometry().origin_y, 4.5);
        assert_eq!((crop.geometry().cols, crop.geometry().rows), (16, 10));
        for &(x, y) in &[(3.3, 4.8), (7.0, 7.0), (10.7, 9.2)] {
            assert_eq!(crop.height(x, y), dem.height(x, y));
        }
        let rebased = crop.clone().rebased();
        assert_eq!(rebased.geometry().origin_x, 0.0);
        // The same projected point has the same height in both.
        let (e, n) = crop.to_projected(7.0, 7.0);
        let (lx, ly) = rebased.to_local(e, n);
        assert!((lx - 4.0).abs() < 1e-12 && (ly - 2.5).abs() < 1e-12);
        assert_eq!(rebased.height(lx, ly), crop.height(7.0, 7.0));
        let outside = LocalRect { x_min: 30.0, y_min: 0.0, x_max: 40.0, y_max: 5.0 };
        assert_eq!(dem.crop(outside), Err(DemError::EmptyRegion(outside)));
    }

    #[test]
    fn resample_reproduces_a_bilinear_surface() {
        let k = [2.0, 0.3, 0.2, -0.05];
        let dem = bilinear_dem(12, 10, 1.0, k);
        for res in [0.25, 2.0] {
            let fine = dem.resample(res).unwrap();
            assert_eq!(fine.geometry().cols, (12.0 / res) as usize);
            for r in 0..fine.geometry().rows {
                for c in 0..fine.geometry().cols {
                    let (x, y) = fine.geometry().center(c, r);
                    // Only inside the hull of the source cell centres is bilinear exact.
                    if (0.5..=11.5).contains(&x) && (0.5..=9.5).contains(&y) {
                        let truth = k[0] + k[1] * x + k[2] * y + k[3] * x * y;
                        assert!((*fine.heights.get(c, r) as f64 - truth).abs() < 1e-4);
                    }
                }
            }
        }
        assert_eq!(dem.resample(0.0), Err(DemError::InvalidResolution(0.0)));
    }
}
