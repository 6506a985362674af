//! GESTALT goodness (paper 003 section 2): the local goodness grid map that MER AutoNav builds
//! from stereo range data, where high goodness means highly traversable terrain.
//!
//! Each cell's goodness rates the rover standing centred on that cell: the step, slope and
//! roughness of the rover-footprint window around it ([`crate::footprint`]) are each mapped to
//! `1 - value / limit` (1 for ideal terrain, 0 at the limit), and the cell takes the worst of
//! the three, clamped to 0..1. A value of 0 is an obstacle for the rover there. Cells that are
//! unsensed, or whose window has too few sensed cells for a plane fit, are unknown (NaN).

use crate::footprint::FootprintLayers;

/// Limits at which each hazard drives goodness to 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GoodnessParams {
    /// Step height (m): the belly clearance.
    pub max_step: f64,
    /// Plane tilt (rad): the maximum safe tilt.
    pub max_slope: f64,
    /// RMS height about the footprint plane (m).
    pub max_roughness: f64,
}

/// Goodness of one footprint from its step (m), slope (rad) and roughness (m); NaN in, NaN out.
pub fn goodness(step: f64, slope: f64, roughness: f64, p: &GoodnessParams) -> f32 {
    if !(step.is_finite() && slope.is_finite() && roughness.is_finite()) {
        return f32::NAN;
    }
    let g = (1.0 - step / p.max_step).min(1.0 - slope / p.max_slope).min(1.0 - roughness / p.max_roughness);
    g.clamp(0.0, 1.0) as f32
}

/// Goodness of every cell of a row-major window (NaN where unknown).
pub fn goodness_layer(heights: &[f32], footprint: &FootprintLayers, p: &GoodnessParams) -> Vec<f32> {
    heights
        .iter()
        .enumerate()
        .map(|(i, h)| {
            if !h.is_finite() {
                return f32::NAN;
            }
            goodness(footprint.step[i] as f64, footprint.slope[i] as f64, footprint.roughness[i] as f64, p)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p() -> GoodnessParams {
        GoodnessParams { max_step: 0.18, max_slope: 25f64.to_radians(), max_roughness: 0.09 }
    }

    #[test]
    fn goodness_takes_the_worst_hazard() {
        assert_eq!(goodness(0.0, 0.0, 0.0, &p()), 1.0);
        // Step 0.09 of 0.18 -> 0.5; slope 5 of 25 deg -> 0.8; roughness 0.009 of 0.09 -> 0.9.
        assert!((goodness(0.09, 5f64.to_radians(), 0.009, &p()) - 0.5).abs() < 1e-6);
        assert!((goodness(0.0, 20f64.to_radians(), 0.0, &p()) - 0.2).abs() < 1e-6);
        assert_eq!(goodness(0.3, 0.0, 0.0, &p()), 0.0);
        assert!(goodness(f64::NAN, 0.0, 0.0, &p()).is_nan());
    }

    #[test]
    fn unsensed_centres_are_unknown() {
        let fp = FootprintLayers {
            step: vec![0.0, 0.0],
            slope: vec![0.0, 0.0],
            roughness: vec![0.0, 0.0],
            obstacle: vec![false, false],
            uncertain: vec![false, false],
        };
        let g = goodness_layer(&[0.0, f32::NAN], &fp, &p());
        assert_eq!(g[0], 1.0);
        assert!(g[1].is_nan());
    }
}
