//! The MRPTA segment driver (paper 004, section 3.5): turns a planned path into motion
//! commands. It keeps only the prefix of the path that lies in sensed terrain, divides that
//! prefix into straight segments starting at the rover's actual position (the planned points are
//! cell centres, the rover is not), and where the direction of consecutive segments differs by
//! more than a threshold (10 degrees in the paper) inserts an in-situ rotation. Smaller
//! direction changes are left to the motion controller, which steers along each straight
//! segment towards its end waypoint.

use rovernav_core::{Point2, Pose2, angle_diff};

/// One motion-controller action.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Segment {
    /// Rotate in place by `angle` (rad, counter-clockwise positive).
    Turn {
        /// Signed rotation (rad).
        angle: f64,
    },
    /// Drive straight for `distance` metres (towards the matching entry of
    /// [`SegmentPlan::waypoints`]).
    Straight {
        /// Length (m).
        distance: f64,
    },
}

/// Segment driver parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SegmentDriverConfig {
    /// Direction changes above this get an in-situ rotation (rad; the paper's 10 degrees).
    pub turn_threshold: f64,
    /// Path points within this distance (m) of a straight chord are merged into it.
    pub collinear_tolerance: f64,
    /// Spacing (m) of the sensed-terrain checks between consecutive path points.
    pub sample_step: f64,
    /// Straight pieces shorter than this (m) are dropped.
    pub min_distance: f64,
}

impl Default for SegmentDriverConfig {
    /// The paper's 10 degree rule; tolerances sized for MRPTA's 0.15 m cells.
    fn default() -> Self {
        Self {
            turn_threshold: 10f64.to_radians(),
            collinear_tolerance: 0.075,
            sample_step: 0.05,
            min_distance: 0.01,
        }
    }
}

/// The driver's output.
#[derive(Clone, Debug, PartialEq)]
pub struct SegmentPlan {
    /// Actions in execution order.
    pub segments: Vec<Segment>,
    /// End point (world) of each `Straight`, in order.
    pub waypoints: Vec<Point2>,
    /// How many leading path points lie in sensed terrain and were used.
    pub sensed_points: usize,
    /// Whether the whole path was sensed (the last waypoint is the path's end).
    pub complete: bool,
}

/// Number of leading path points in sensed terrain, sampling between consecutive points too.
fn sensed_prefix(path: &[Point2], is_sensed: &impl Fn(Point2) -> bool, step: f64) -> usize {
    for (i, &p) in path.iter().enumerate() {
        if !is_sensed(p) {
            return i;
        }
        if i > 0 {
            let a = path[i - 1];
            let n = (a.dist(p) / step.max(1e-6)).ceil() as usize;
            let gap = (1..n).any(|k| !is_sensed(a.add(p.sub(a).scale(k as f64 / n as f64))));
            if gap {
                return i;
            }
        }
    }
    path.len()
}

/// Splits a polyline into maximal chords that every intermediate point lies within `tol` of.
fn straight_pieces(points: &[Point2], tol: f64) -> Vec<Point2> {
    let mut out = vec![points[0]];
    let mut anchor = 0;
    while anchor + 1 < points.len() {
        let mut end = anchor + 1;
        for j in anchor + 2..points.len() {
            let (a, b) = (points[anchor], points[j]);
            let chord = b.sub(a);
            let len = chord.norm();
            let fits = (anchor + 1..j).all(|m| {
                let rel = points[m].sub(a);
                let off = if len > 0.0 { chord.cross(rel).abs() / len } else { rel.norm() };
                // Also require the point to project inside the chord (no back-tracking).
                let along = if len > 0.0 { chord.dot(rel) / len } else { 0.0 };
                off <= tol && along >= -tol && along <= len + tol
            });
            if fits {
                end = j;
            } else {
                break;
            }
        }
        out.push(points[end]);
        anchor = end;
    }
    out
}

/// Cuts a planned path (world points, start first; the first point is taken to be the rover's
/// cell and replaced by the rover's position) into straight segments and in-situ rotations,
/// keeping only the prefix that `is_sensed` accepts.
pub fn segment_path(
    rover: Pose2,
    path: &[Point2],
    is_sensed: impl Fn(Point2) -> bool,
    config: &SegmentDriverConfig,
) -> SegmentPlan {
    let kept = sensed_prefix(path, &is_sensed, config.sample_step);
    let mut polyline = vec![rover.position()];
    polyline
        .extend(path.iter().take(kept).skip(1).filter(|p| p.dist(rover.position()) > config.min_distance));
    let mut plan = SegmentPlan {
        segments: Vec::new(),
        waypoints: Vec::new(),
        sensed_points: kept,
        complete: kept == path.len(),
    };
    if polyline.len() < 2 {
        return plan;
    }
    let corners = straight_pieces(&polyline, config.collinear_tolerance);
    let mut heading = rover.yaw;
    for w in corners.windows(2) {
        let d = w[1].sub(w[0]);
        let distance = d.norm();
        if distance < config.min_distance {
            continue;
        }
        let direction = d.angle();
        let turn = angle_diff(direction, heading);
        if turn.abs() > config.turn_threshold {
            plan.segments.push(Segment::Turn { angle: turn });
        }
        plan.segments.push(Segment::Straight { distance });
        plan.waypoints.push(w[1]);
        heading = direction;
    }
    plan
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    fn cells_along(from: Point2, step: Point2, n: usize) -> Vec<Point2> {
        (0..n).map(|k| from.add(step.scale(k as f64))).collect()
    }

    #[test]
    fn l_shaped_path_gets_one_rotation() {
        let mut path = cells_along(Point2::new(0.0, 0.0), Point2::new(1.0, 0.0), 6);
        path.extend(cells_along(Point2::new(5.0, 1.0), Point2::new(0.0, 1.0), 5));
        let plan = segment_path(Pose2::new(0.0, 0.0, 0.0), &path, |_| true, &SegmentDriverConfig::default());
        assert_eq!(plan.segments.len(), 3);
        assert!(matches!(plan.segments[0], Segment::Straight { distance } if (distance - 5.0).abs() < 1e-9));
        assert!(matches!(plan.segments[1], Segment::Turn { angle } if (angle - FRAC_PI_2).abs() < 1e-9));
        assert!(matches!(plan.segments[2], Segment::Straight { distance } if (distance - 5.0).abs() < 1e-9));
        assert!(plan.complete);
        assert_eq!(plan.waypoints.last(), Some(&Point2::new(5.0, 5.0)));
    }

    #[test]
    fn small_bends_need_no_rotation_and_initial_heading_is_checked() {
        // Two legs 6 degrees apart, each longer than the tolerance can absorb.
        let a = 6f64.to_radians();
        let mut path = cells_along(Point2::new(0.0, 0.0), Point2::new(1.0, 0.0), 11);
        let bend = Point2::new(a.cos(), a.sin());
        path.extend(cells_along(Point2::new(10.0, 0.0).add(bend), bend, 10));
        // Rover faces north: a -90 degree rotation first, then no rotation at the 6 degree bend.
        let plan =
            segment_path(Pose2::new(0.0, 0.0, FRAC_PI_2), &path, |_| true, &SegmentDriverConfig::default());
        let turns: Vec<f64> = plan
            .segments
            .iter()
            .filter_map(|s| match s {
                Segment::Turn { angle } => Some(*angle),
                _ => None,
            })
            .collect();
        assert_eq!(turns.len(), 1);
        assert!((turns[0] + FRAC_PI_2).abs() < 1e-9);
        let straights = plan.segments.iter().filter(|s| matches!(s, Segment::Straight { .. })).count();
        assert_eq!(straights, 2);
    }

    #[test]
    fn nearly_collinear_points_merge_and_rover_offset_starts_the_segment() {
        // Cell centres wobbling by 2 cm around the x axis; rover 5 cm off the first centre.
        let path: Vec<Point2> =
            (0..20).map(|k| Point2::new(0.15 * k as f64, if k % 2 == 0 { 0.02 } else { -0.02 })).collect();
        let plan = segment_path(Pose2::new(0.0, 0.05, 0.0), &path, |_| true, &SegmentDriverConfig::default());
        assert_eq!(plan.segments.len(), 1);
        let Segment::Straight { distance } = plan.segments[0] else {
            panic!("expected a straight segment");
        };
        let expected = Point2::new(0.0, 0.05).dist(path[19]);
        assert!((distance - expected).abs() < 1e-12);
    }

    #[test]
    fn stops_at_the_first_unsensed_point() {
        let path = cells_along(Point2::new(0.0, 0.0), Point2::new(0.15, 0.0), 40);
        let sensed = |p: Point2| p.x < 2.0;
        let plan = segment_path(Pose2::new(0.0, 0.0, 0.0), &path, sensed, &SegmentDriverConfig::default());
        assert!(!plan.complete);
        // Points at x = 0, 0.15, ..., 1.95 are sensed: 14 of them.
        assert_eq!(plan.sensed_points, 14);
        let total: f64 = plan
            .segments
            .iter()
            .map(|s| match s {
                Segment::Straight { distance } => *distance,
                Segment::Turn { .. } => 0.0,
            })
            .sum();
        assert!((total - 1.95).abs() < 1e-9);
        // A gap between two sensed points also cuts the path.
        let gap = |p: Point2| !(0.5..0.55).contains(&p.x);
        let plan = segment_path(Pose2::new(0.0, 0.0, 0.0), &path, gap, &SegmentDriverConfig::default());
        assert_eq!(plan.sensed_points, 4);
    }
}
