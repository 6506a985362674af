//! Absolute fixes for [`EkfMl`]: an external fix (an orbital-map match, a lander sighting)
//! moves the estimate, and the rover's own map, placed with the estimates before it, moves with
//! it; otherwise the next terrain match against that map would pull the estimate back to where
//! the map was placed.
//!
//! The map is re-anchored rigidly: every cell within [`KEEP_RADIUS_M`] of the rover is moved by
//! the transform that takes the estimate before the fix to the estimate after it (the map was
//! placed relative to the estimate, so it shares the estimate's error); cells farther away are
//! dropped (they are older than the match horizon and would not be matched again).

use rovernav_core::{Grid2, GridGeometry, Localizer, Point2, Pose2};

use super::{EkfMl, WorldElevation};
use crate::matching::MatchResult;

/// Radius around the rover of the map kept through a re-anchoring (m).
pub const KEEP_RADIUS_M: f64 = 40.0;

impl EkfMl {
    /// The mean heights of the rover's own map in a world-aligned square of half-side `half`
    /// (m) around `centre`, in cells of `cell` metres (at least the map's resolution): each
    /// cell the mean of the map cells whose centres fall in it, NaN where none do.
    pub fn map_heights(&self, centre: Point2, half: f64, cell: f64) -> Grid2<f32> {
        let res = self.params.resolution;
        let cell = cell.max(res);
        let n = (2.0 * half / cell).ceil().max(1.0) as usize;
        let origin = Point2::new(centre.x - half, centre.y - half);
        let geometry =
            GridGeometry { cols: n, rows: n, resolution: cell, origin_x: origin.x, origin_y: origin.y };
        let mut sum = vec![0.0f64; n * n];
        let mut count = vec![0u32; n * n];
        let (k0, l0) = WorldElevation::key(origin.x, origin.y, res);
        let span = (2.0 * half / res).ceil() as i32 + 1;
        for l in l0..l0 + span {
            for k in k0..k0 + span {
                let Some(c) = self.map.cells.get(&(k, l)) else { continue };
                let (x, y) = ((f64::from(k) + 0.5) * res, (f64::from(l) + 0.5) * res);
                if let Some((col, row)) = geometry.cell_of(x, y) {
                    sum[row * n + col] += f64::from(c.height_sum / f32::from(c.count));
                    count[row * n + col] += 1;
                }
            }
        }
        let data = sum
            .iter()
            .zip(&count)
            .map(|(&s, &m)| if m > 0 { (s / f64::from(m)) as f32 } else { f32::NAN })
            .collect();
        Grid2 { geometry, data }
    }

    /// Restarts at (x, y) with the current heading and a position standard deviation of
    /// `sigma` (m), the map cleared (e.g. a rover whose landing position is uncertain).
    pub fn reset_position(&mut self, x: f64, y: f64, sigma: f64) {
        let pose = self.ekf.estimate().pose;
        Localizer::reset(self, rovernav_core::Pose3 { x, y, ..pose });
        self.ekf.reset_position(x, y, sigma);
        self.map_covariance = self.ekf.estimate().covariance;
    }

    /// Fuses an absolute fix (independent of the rover's map) into the filter and moves the
    /// map with the estimate. Returns whether the fix was fused (see `Ekf::fuse_fix`).
    pub fn fuse_absolute_fix(&mut self, fix: &MatchResult) -> bool {
        let before = self.ekf.estimate().pose.pose2();
        if !self.ekf.fuse_fix(fix) {
            return false;
        }
        let estimate = self.ekf.estimate();
        let after = estimate.pose.pose2();
        self.reanchor(&before, &after);
        // The map now lies where the fixed estimate puts it, with its uncertainty.
        self.map_covariance = estimate.covariance;
        let moved = |p: Point2| after.transform(before.inverse_transform(p));
        self.last_match_position = self.last_match_position.map(moved);
        self.previous_position = after.position();
        self.travel_since_fix = 0.0;
        self.target = None;
        true
    }

    /// Fuses an absolute fix whose error may be correlated with the filter's by covariance
    /// intersection ([`crate::consistency::covariance_intersection_weight`]): the filter's
    /// position covariance is inflated by 1 / omega and the fix's by 1 / (1 - omega) before an
    /// ordinary update, so that the posterior is consistent whatever the correlation. A fix the
    /// intersection gives no weight (omega = 1) is accepted and leaves the filter as it was.
    /// Departure from full-state covariance intersection (which inflates the whole state): only
    /// the position rows and columns are inflated, since the fix measures position only and
    /// heading and gyro bias are not correlated with it through the map. Returns whether the
    /// fix was accepted (on a refusal the filter is left as it was).
    pub fn fuse_correlated_fix(&mut self, fix: &MatchResult) -> bool {
        let p = self.ekf.estimate().covariance;
        let block = |c: &[[f64; 3]; 3]| [[c[0][0], c[0][1]], [c[1][0], c[1][1]]];
        let Some(w) = crate::consistency::covariance_intersection_weight(&block(&p), &block(&fix.covariance))
        else {
            return false;
        };
        if w >= 1.0 {
            // The intersection is the filter's own estimate: the fix agrees and adds nothing.
            return true;
        }
        let mut inflated = *fix;
        for row in inflated.covariance.iter_mut().take(2) {
            for v in row.iter_mut().take(2) {
                *v /= 1.0 - w;
            }
        }
        self.ekf.scale_position_covariance(1.0 / w);
        if self.fuse_absolute_fix(&inflated) {
            true
        } else {
            self.ekf.scale_position_covariance(w);
            false
        }
    }

    /// Moves every map cell within [`KEEP_RADIUS_M`] of `after` rigidly from `before`'s frame
    /// to `after`'s; cells landing in the same cell are merged.
    fn reanchor(&mut self, before: &Pose2, after: &Pose2) {
        let res = self.params.resolution;
        let mut moved = WorldElevation::default();
        for (&(k, l), c) in &self.map.cells {
            let p = Point2::new((f64::from(k) + 0.5) * res, (f64::from(l) + 0.5) * res);
            let q = after.transform(before.inverse_transform(p));
            if q.dist(after.position()) > KEEP_RADIUS_M {
                continue;
            }
            let cell = moved.cells.entry(WorldElevation::key(q.x, q.y, res)).or_default();
            let total = u32::from(cell.count) + u32::from(c.count);
            if total <= u32::from(u16::MAX) {
                cell.height_sum += c.height_sum;
                cell.vertical_variance_sum += c.vertical_variance_sum;
                cell.ground_variance_sum += c.ground_variance_sum;
                cell.count = total as u16;
            }
        }
        self.map = moved;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rovernav_core::{Pose3, RoverConfig};

    fn localizer_with_map() -> EkfMl {
        let mut loc = EkfMl::new(&RoverConfig::default(), Pose3::default());
        // A 2 m x 1 m block of map at height 1 (x in [1, 3), y in [0, 1)) and a far cell.
        let mut points = Vec::new();
        for i in 0..40 {
            for j in 0..20 {
                points.push([1.0 + 0.05 * f64::from(i) + 0.025, 0.05 * f64::from(j) + 0.025, 1.0, 0.0, 0.0]);
            }
        }
        points.push([80.0, 0.0, 5.0, 0.0, 0.0]);
        loc.map.add(&points, loc.params.resolution);
        loc
    }

    #[test]
    fn map_heights_average_the_fine_cells() {
        let loc = localizer_with_map();
        let g = loc.map_heights(Point2::new(2.0, 0.5), 2.0, 0.5);
        assert_eq!((g.cols(), g.rows()), (8, 8));
        // Cells inside the block hold its height; outside it, nothing.
        assert_eq!(g.at_world(2.1, 0.3).copied(), Some(1.0));
        assert!(g.at_world(0.5, 0.3).is_some_and(|h| h.is_nan()));
        assert!(g.at_world(2.1, 1.6).is_some_and(|h| h.is_nan()));
    }

    #[test]
    fn an_absolute_fix_moves_the_estimate_and_the_map_with_it() {
        let mut loc = localizer_with_map();
        let sigma = 0.01;
        // The fix says the rover is 1 m further east than believed (and certain of it).
        let fix = MatchResult {
            pose: Pose2::new(1.0, 0.0, 0.0),
            covariance: [[sigma * sigma, 0.0, 0.0], [0.0, sigma * sigma, 0.0], [0.0, 0.0, 1e-6]],
            log_likelihood: 0.0,
            failure_probability: 0.0,
            poses_evaluated: 1,
        };
        loc.ekf.reset_position(0.0, 0.0, 1.0);
        assert!(loc.fuse_absolute_fix(&fix));
        let e = loc.estimate();
        assert!((e.pose.x - 1.0).abs() < 1e-3, "x {}", e.pose.x);
        // The block moved by as much as the estimate: now x in [2, 4) (to the estimate's
        // 1e-3 m); the far cell is gone.
        let shift = e.pose.x;
        let g = loc.map_heights(Point2::new(3.0, 0.5), 2.0, 0.5);
        assert_eq!(g.at_world(1.0 + shift + 0.3, 0.3).copied(), Some(1.0));
        assert!(g.at_world(1.0 + shift - 0.3, 0.3).is_some_and(|h| h.is_nan()));
        assert!(loc.map.cells.len() <= 40 * 20 + 40, "far cells dropped: {}", loc.map.cells.len());
        assert!(loc.map_covariance[0][0] < 2.0 * sigma * sigma);
    }

    #[test]
    fn a_correlated_fix_is_fused_by_covariance_intersection() {
        // Prior diag(1, 9) at the origin, fix diag(4, 1) at (1, 1): omega = 0.3958 (see
        // consistency's test), information diag(w + (1-w)/4, w/9 + (1-w)) = diag(0.547, 0.648),
        // the mean P (w P^-1 x_p + (1-w) R^-1 x_r) = (0.276, 0.932).
        let mut loc = localizer_with_map();
        loc.ekf.reset_position(0.0, 0.0, 1.0);
        let heading = loc.estimate().covariance[2][2];
        loc.ekf.set_pose_covariance(&[[1.0, 0.0, 0.0], [0.0, 9.0, 0.0], [0.0, 0.0, heading]]);
        let fix = MatchResult {
            pose: Pose2::new(1.0, 1.0, loc.estimate().pose.yaw),
            covariance: [[4.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0; 3]],
            log_likelihood: 0.0,
            failure_probability: 0.0,
            poses_evaluated: 1,
        };
        assert!(loc.fuse_correlated_fix(&fix));
        let e = loc.estimate();
        let close = |a: f64, b: f64| (a - b).abs() < 0.02 * b;
        assert!(
            close(e.covariance[0][0], 1.0 / 0.547) && close(e.covariance[1][1], 1.0 / 0.648),
            "{:?}",
            e.covariance
        );
        assert!(close(e.pose.x, 0.276) && close(e.pose.y, 0.932), "{:?}", e.pose);
        // Twice the ordinary update's variances (diag(0.8, 0.9)): the price of not knowing the
        // correlation.
        assert!(e.covariance[0][0] > 2.0 * 0.8 && e.covariance[1][1] > 1.5 * 0.9);
    }
}
