//! Figures of merit of terrain assessment against ground truth, for `rovernav eval terrain`.
//!
//! The truth is independent of the sensed data: rock positions and sizes, and the true height
//! function sampled over each cell. "Truly safe" uses the same step/slope model as the detector
//! ([`crate::footprint`]) applied to true cell heights: a cell is truly safe when the rover
//! footprint window centred on it has step <= clearance and slope <= max tilt. A hazard cell
//! next to a real rock is therefore not counted as false (the rover could not stand there
//! either), while a hazard cell in open, level terrain is.

use crate::PerceptionError;
use crate::config::TerrainConfig;
use crate::footprint::analyse_footprints;
use rovernav_core::{Grid2, GridGeometry, Point2};

/// A rock of the true world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrueRock {
    /// Centre east (m).
    pub x: f64,
    /// Centre north (m).
    pub y: f64,
    /// Diameter (m).
    pub diameter: f64,
    /// Height above the surrounding ground (m).
    pub height: f64,
}

/// Terrain-assessment figures; a ratio with an empty denominator is NaN.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TerrainEvalFigures {
    /// Fraction of hazard rocks (taller than the clearance) near the sensor and at least partly
    /// sensed that are covered by at least one hazard cell.
    pub hazard_recall: f64,
    /// Hazard cells that are truly safe over all truly safe sensed cells.
    pub false_hazard_rate: f64,
    /// RMS of sensed minus true cell height over sensed cells with a true height (m).
    pub elevation_rmse_m: f64,
    /// Hazard rocks counted for recall.
    pub hazard_rocks: usize,
    /// Of those, rocks covered by a hazard cell.
    pub hazard_rocks_detected: usize,
    /// Sensed cells.
    pub sensed_cells: usize,
    /// Sensed cells classified as hazard.
    pub hazard_cells: usize,
    /// Sensed cells that are truly safe.
    pub truly_safe_cells: usize,
    /// Hazard cells that are truly safe.
    pub false_hazard_cells: usize,
}

/// Distance from a rock centre within which rocks count for recall (m).
pub const RECALL_RADIUS_M: f64 = 5.0;

/// Subsamples per cell side when averaging the true height over a cell.
const SUBSAMPLES: usize = 3;

/// Mean of the true height over each cell (NaN where the truth has no value).
fn true_cell_heights(g: &GridGeometry, true_height: &impl Fn(f64, f64) -> Option<f64>) -> Vec<f32> {
    let mut out = Vec::with_capacity(g.len());
    for r in 0..g.rows {
        for c in 0..g.cols {
            let (mut sum, mut n) = (0.0, 0usize);
            for a in 0..SUBSAMPLES {
                for b in 0..SUBSAMPLES {
                    let x = g.origin_x + (c as f64 + (a as f64 + 0.5) / SUBSAMPLES as f64) * g.resolution;
                    let y = g.origin_y + (r as f64 + (b as f64 + 0.5) / SUBSAMPLES as f64) * g.resolution;
                    if let Some(z) = true_height(x, y).filter(|z| z.is_finite()) {
                        sum += z;
                        n += 1;
                    }
                }
            }
            out.push(if n > 0 { (sum / n as f64) as f32 } else { f32::NAN });
        }
    }
    out
}

/// Cells `(col, row)` whose square overlaps the disc of radius `radius` around `centre`.
fn cells_overlapping_disc(g: &GridGeometry, centre: Point2, radius: f64) -> Vec<(usize, usize)> {
    let to_index = |v: f64, origin: f64, n: usize| {
        (((v - origin) / g.resolution).floor()).clamp(0.0, n as f64 - 1.0) as usize
    };
    let (c0, c1) =
        (to_index(centre.x - radius, g.origin_x, g.cols), to_index(centre.x + radius, g.origin_x, g.cols));
    let (r0, r1) =
        (to_index(centre.y - radius, g.origin_y, g.rows), to_index(centre.y + radius, g.origin_y, g.rows));
    let mut out = Vec::new();
    for r in r0..=r1 {
        for c in c0..=c1 {
            let x0 = g.origin_x + c as f64 * g.resolution;
            let y0 = g.origin_y + r as f64 * g.resolution;
            let nearest =
                Point2::new(centre.x.clamp(x0, x0 + g.resolution), centre.y.clamp(y0, y0 + g.resolution));
            if nearest.dist(centre) <= radius {
                out.push((c, r));
            }
        }
    }
    out
}

/// Computes hazard recall, false hazard rate and elevation RMSE of sensed maps against truth.
///
/// `elevation` holds sensed mean heights (NaN unsensed) and `hazard` the hazard classification
/// on the same geometry; `sensor` is the true sensor position; the step/slope limits and
/// footprint come from `config`.
pub fn evaluate_terrain(
    rocks: &[TrueRock],
    true_height: impl Fn(f64, f64) -> Option<f64>,
    elevation: &Grid2<f32>,
    hazard: &Grid2<bool>,
    sensor: Point2,
    config: &TerrainConfig,
) -> Result<TerrainEvalFigures, PerceptionError> {
    config.validate()?;
    let g = elevation.geometry;
    if hazard.geometry != g || hazard.data.len() != g.len() {
        return Err(PerceptionError::GeometryMismatch { what: "hazard" });
    }
    if elevation.data.len() != g.len() {
        return Err(PerceptionError::GeometryMismatch { what: "elevation" });
    }
    let truth = true_cell_heights(&g, &true_height);
    let params = config.footprint_params();
    let true_fp = analyse_footprints(&truth, g.cols, g.rows, g.resolution, &params);

    let (mut sensed, mut hazards, mut safe, mut false_hazards) = (0usize, 0usize, 0usize, 0usize);
    let (mut sq_err, mut n_err) = (0.0f64, 0usize);
    for (i, (&h, &true_h)) in elevation.data.iter().zip(&truth).enumerate() {
        if !h.is_finite() {
            continue;
        }
        sensed += 1;
        hazards += usize::from(hazard.data[i]);
        if true_h.is_finite() {
            let e = h as f64 - true_h as f64;
            sq_err += e * e;
            n_err += 1;
        }
        let step = true_fp.step[i] as f64;
        let slope = true_fp.slope[i] as f64;
        let truly_safe =
            step.is_finite() && slope.is_finite() && step <= params.step_limit && slope <= params.slope_limit;
        if truly_safe {
            safe += 1;
            false_hazards += usize::from(hazard.data[i]);
        }
    }

    let (mut eligible, mut detected) = (0usize, 0usize);
    for rock in rocks {
        let centre = Point2::new(rock.x, rock.y);
        if rock.height <= config.clearance || centre.dist(sensor) > RECALL_RADIUS_M {
            continue;
        }
        let cells = cells_overlapping_disc(&g, centre, 0.5 * rock.diameter);
        let seen = cells.iter().any(|&(c, r)| elevation.get(c, r).is_finite());
        if !seen {
            continue;
        }
        eligible += 1;
        detected += usize::from(cells.iter().any(|&(c, r)| *hazard.get(c, r)));
    }

    let ratio = |a: usize, b: usize| if b > 0 { a as f64 / b as f64 } else { f64::NAN };
    Ok(TerrainEvalFigures {
        hazard_recall: ratio(detected, eligible),
        false_hazard_rate: ratio(false_hazards, safe),
        elevation_rmse_m: if n_err > 0 { (sq_err / n_err as f64).sqrt() } else { f64::NAN },
        hazard_rocks: eligible,
        hazard_rocks_detected: detected,
        sensed_cells: sensed,
        hazard_cells: hazards,
        truly_safe_cells: safe,
        false_hazard_cells: false_hazards,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn geometry() -> GridGeometry {
        GridGeometry { cols: 40, rows: 40, resolution: 0.15, origin_x: 0.0, origin_y: 0.0 }
    }

    fn box_rock(x: f64, y: f64) -> impl Fn(f64, f64) -> Option<f64> {
        move |px, py| Some(if (px - x).abs() < 0.2 && (py - y).abs() < 0.2 { 0.3 } else { 0.0 })
    }

    #[test]
    fn perfect_sensing_scores_full_recall_no_false_hazards_and_zero_error() {
        let g = geometry();
        let truth = box_rock(3.0, 3.0);
        let heights = Grid2 { geometry: g, data: true_cell_heights(&g, &truth) };
        let cfg = TerrainConfig::default();
        let fp = analyse_footprints(&heights.data, g.cols, g.rows, g.resolution, &cfg.footprint_params());
        let hazard = Grid2 { geometry: g, data: fp.obstacle };
        let rocks = [TrueRock { x: 3.0, y: 3.0, diameter: 0.4, height: 0.3 }];
        let f = evaluate_terrain(&rocks, &truth, &heights, &hazard, Point2::new(1.0, 1.0), &cfg).unwrap();
        assert_eq!((f.hazard_rocks, f.hazard_rocks_detected), (1, 1));
        assert_eq!(f.hazard_recall, 1.0);
        assert_eq!(f.false_hazard_rate, 0.0);
        assert!(f.elevation_rmse_m < 1e-6);
        assert_eq!(f.sensed_cells, 1600);
    }

    #[test]
    fn a_missed_rock_and_a_phantom_hazard_are_counted() {
        let g = geometry();
        let truth = box_rock(3.0, 3.0);
        // Sensed map: flat ground biased by +0.1 m, rock missed, one hazard in open ground.
        let heights = Grid2::filled(g, 0.1f32);
        let mut hazard = Grid2::filled(g, false);
        *hazard.get_mut(5, 5) = true;
        let rocks = [
            TrueRock { x: 3.0, y: 3.0, diameter: 0.4, height: 0.3 },
            // Too low to be a hazard, and too far: neither counts.
            TrueRock { x: 1.0, y: 1.0, diameter: 0.4, height: 0.1 },
            TrueRock { x: 5.9, y: 5.9, diameter: 0.4, height: 0.5 },
        ];
        let cfg = TerrainConfig::default();
        let f = evaluate_terrain(&rocks, &truth, &heights, &hazard, Point2::new(0.0, 0.0), &cfg).unwrap();
        assert_eq!((f.hazard_rocks, f.hazard_rocks_detected), (1, 0));
        assert_eq!(f.hazard_recall, 0.0);
        assert_eq!(f.false_hazard_cells, 1);
        assert!((f.false_hazard_rate - 1.0 / f.truly_safe_cells as f64).abs() < 1e-12);
        assert!(f.truly_safe_cells < 1600);
        assert!(f.elevation_rmse_m > 0.1);
    }

    #[test]
    fn mismatched_hazard_grid_is_an_error() {
        let g = geometry();
        let heights = Grid2::filled(g, 0.0f32);
        let hazard = Grid2::filled(GridGeometry { cols: 3, ..g }, false);
        let r = evaluate_terrain(
            &[],
            |_, _| Some(0.0),
            &heights,
            &hazard,
            Point2::default(),
            &TerrainConfig::default(),
        );
        assert_eq!(r, Err(PerceptionError::GeometryMismatch { what: "hazard" }));
    }
}
