//! The safety layer (a departure from paper 000: the paper has no map kept across steps).
//! Cell means lose part of a small rock's height, so rocks just over the clearance can escape
//! the step/slope model behind the C-obstacles. A second, bounded memory of hazard cells on top
//! heights ([`HazardHeight::Top`](rovernav_perception::HazardHeight::Top), the grid navigators' setting) is kept in a 12 m
//! robot-centred grid across steps (dead-reckoning drift over a few steps is small against the
//! margins):
//! * its cells that stand out from the ground around them ([`RoverBug::confirm_hazards`])
//!   become extra C-obstacles grown only by half the rover's width plus an allowance
//!   ([`RoverBug::top_obstacles`]; grown like the others they would close the gaps of a rock
//!   field);
//! * every turn in place and drive is checked against them, body outline plus margin, before
//!   it is commanded ([`RoverBug::motion_hazards`], [`RoverBug::leg_clear`]): the first leg of
//!   every plan when the tangent graph is built, later legs at execution; a refused one starts
//!   a new step (`recovery::refuse`).
//!
//! Measured (`rovernav eval terrain --seeds 1..20`): the C-obstacle model's cell means find
//! 83 % of the rocks over the clearance, the safety layer's top heights 98 %; see
//! docs/navigators/roverbug.md.

use super::{CObstacle, Grid2, Point2, Pose2, RoverBug, angle_diff};
use std::f64::consts::PI;

impl RoverBug {
    /// The safety layer's hazard cells whose own points rise above (or fall below) the median
    /// height of the sensed cells within the footprint radius by a fraction of the layer's step
    /// limit. The step/slope model also marks ground-level cells of a window it finds hazardous
    /// when the window is sparsely sensed (single points, planes tilted by a nearby rock);
    /// those would pin the rover in place for nothing. The fraction stays well below one: the
    /// wheels may stand lower than the median ground, so a rock that reads a little under the
    /// limit above it can still touch the belly. Slope hazards are left to the C-obstacles.
    pub(super) fn confirm_hazards(&self) -> Option<Grid2<bool>> {
        let safety = self.safety.as_ref()?;
        let layers = safety.layers();
        let mut out = layers.hazard.clone();
        let g = out.geometry;
        let limit = self.config.safety.confirm_fraction * safety.config().clearance;
        let k = (safety.config().footprint_radius / g.resolution).round() as isize;
        for r in 0..g.rows {
            for c in 0..g.cols {
                if !*out.get(c, r) {
                    continue;
                }
                let (x, y) = g.center(c, r);
                let Some(cell) = safety.grid().at_world(x, y).filter(|cell| cell.count > 0) else {
                    *out.get_mut(c, r) = false;
                    continue;
                };
                let mut around: Vec<f64> = Vec::new();
                for dr in -k..=k {
                    for dc in -k..=k {
                        let (qx, qy) = (x + dc as f64 * g.resolution, y + dr as f64 * g.resolution);
                        if (dc * dc + dr * dr) as f64 <= (k * k) as f64
                            && let Some(m) = safety.grid().at_world(qx, qy).and_then(|q| q.mean())
                        {
                            around.push(m);
                        }
                    }
                }
                around.sort_by(f64::total_cmp);
                let ground = around.get(around.len() / 2).copied().unwrap_or(f64::NAN);
                let stands_out = cell.max_z as f64 - ground > limit || ground - cell.min_z as f64 > limit;
                *out.get_mut(c, r) = stands_out;
            }
        }
        Some(out)
    }

    /// C-obstacles of the safety layer's hazard cells that the view's C-obstacles miss (rocks
    /// whose cell means read below the step limit), grown only by half the rover's width plus
    /// an allowance: grown like the others they would close the gaps of a rock field, and the
    /// turns and drives near them are checked against the cells themselves. Cells under the
    /// body at `pose` are left out: the rover stands there without contact.
    pub(super) fn top_obstacles(&self, pose: Pose2) -> Vec<CObstacle> {
        let Some(mut mask) = self.safety_hazard.clone() else { return Vec::new() };
        let growth = 0.5 * self.rover.width + self.config.safety.top_allowance;
        let g = mask.geometry;
        let (half_l, half_w) = (0.5 * self.rover.length, 0.5 * self.rover.width);
        for r in 0..g.rows {
            for c in 0..g.cols {
                if !*mask.get(c, r) {
                    continue;
                }
                let (cx, cy) = g.center(c, r);
                let q = Point2::new(cx, cy);
                let b = pose.inverse_transform(q);
                let under_body = b.x.abs() <= half_l && b.y.abs() <= half_w;
                let covered =
                    self.obstacles[..self.sensed_len].iter().any(|o| o.signed_clearance(q) <= -growth);
                if under_body || covered {
                    *mask.get_mut(c, r) = false;
                }
            }
        }
        let mut out = rovernav_perception::build_c_obstacles(&mask, growth, self.terrain.max_arc_step);
        out.retain(|o| o.vertices.len() >= 3);
        out
    }

    /// Safety-layer hazard cells (centres) that come within the body margin of the body
    /// outline at any of `poses`, closer than they are at `start`. Cells under the bare body at
    /// `start` are left out: the rover stands there without contact, so those are noise or too
    /// low to matter, and counting them would forbid every motion; a cell already within the
    /// margin beside the body only counts if the motion brings the body nearer.
    pub(super) fn motion_hazards(&self, start: Pose2, poses: &[Pose2]) -> Vec<Point2> {
        let Some(hazard) = &self.safety_hazard else { return Vec::new() };
        let g = hazard.geometry;
        let (half_l, half_w) = (0.5 * self.rover.length, 0.5 * self.rover.width);
        let m = self.config.safety.body_margin;
        let reach = (half_l + m).hypot(half_w + m);
        // Chebyshev-style distance from the body rectangle (negative under the body).
        let outside = |pose: &Pose2, q: Point2| {
            let b = pose.inverse_transform(q);
            (b.x.abs() - half_l).max(b.y.abs() - half_w)
        };
        let mut out: Vec<Point2> = Vec::new();
        for pose in poses {
            let (cols, rows) = cells_around(&g, pose.position(), reach);
            for r in rows {
                for c in cols.clone() {
                    if !*hazard.get(c, r) {
                        continue;
                    }
                    let (cx, cy) = g.center(c, r);
                    let q = Point2::new(cx, cy);
                    let before = outside(&start, q);
                    let now = outside(pose, q);
                    if before > 0.0
                        && now <= m
                        && now < before - 0.01
                        && !out.iter().any(|o| o.dist(q) < 1e-9)
                    {
                        out.push(q);
                    }
                }
            }
        }
        out
    }

    /// Whether the rover can turn in place toward `target` (either way round) and drive
    /// straight to it without its body sweeping over a safety-layer hazard.
    pub(super) fn leg_clear(&self, target: Point2) -> bool {
        let Some(pose) = self.here else { return true };
        let d = target.sub(pose.position());
        let error = angle_diff(d.angle(), pose.yaw);
        if error.abs() <= self.config.paper.turn_threshold {
            // No turn: the drive is the arc the executor commands.
            let (distance, curvature) = Self::arc_to(d.norm(), error);
            return self.motion_hazards(pose, &Self::arc_poses(pose, distance, curvature)).is_empty();
        }
        let turned = Pose2::new(pose.x, pose.y, pose.yaw + error);
        let turn_ok = self.motion_hazards(pose, &Self::turn_poses(pose, error)).is_empty()
            || self
                .motion_hazards(pose, &Self::turn_poses(pose, error - error.signum() * 2.0 * PI))
                .is_empty();
        turn_ok && self.motion_hazards(pose, &Self::arc_poses(turned, d.norm(), 0.0)).is_empty()
    }
}

/// The column and row ranges of the cells of grid `g` within the square of half-side `reach`
/// around `p`, clipped to the grid.
pub(super) fn cells_around(
    g: &rovernav_core::GridGeometry,
    p: Point2,
    reach: f64,
) -> (std::ops::Range<usize>, std::ops::Range<usize>) {
    let index = |v: f64, origin: f64| ((v - origin) / g.resolution).max(0.0);
    let c0 = index(p.x - reach, g.origin_x).floor() as usize;
    let r0 = index(p.y - reach, g.origin_y).floor() as usize;
    let c1 = (index(p.x + reach, g.origin_x).ceil() as usize).min(g.cols);
    let r1 = (index(p.y + reach, g.origin_y).ceil() as usize).min(g.rows);
    (c0..c1, r0..r1)
}
