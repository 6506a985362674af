//! Departure: every forward drive keeps the body over sensed ground (`unseen_looks`). The
//! local tangent graph needs only the path's centre line in the wedge, so a subpath along a
//! wedge's bounding ray, behind a rock or across the gaps between an image's far rows sweeps
//! the body over ground no image covered (seeds 11 and 49 of the default yard met rocks just
//! outside the mast wedge that way). The seen part of the drive goes ahead; short of that the
//! next step also looks at the unseen ground (see `view`), and after `unseen_looks` looks from
//! one place the drive counts as refused.
//!
//! Measured when it became the default (with near-side boundary following): seeds 1..160,
//! 136 / 8 / 139 clean / with contacts / reached against 126 / 11 / 129; seeds 161..320,
//! 126 / 4 / 128 against 106 / 23 / 119 (contacts on 2 terrains against 21, McNemar
//! p < 0.001). See docs/navigators/roverbug.md.

use super::{Point2, Pose2, RoverBug};

/// Look-ahead beyond the body's ends in the unseen-ground check (m): the wheel radius, over
/// which the simulator's step check looks ahead of each wheel.
const UNSEEN_LOOKAHEAD: f64 = 0.1;

impl RoverBug {
    /// The first of `poses` at which the body outline (with a wheel radius of look-ahead at
    /// either end) covers ground the safety layer has not sensed (see [`first_unseen_pose`]).
    /// The wedge geometry alone does not say this: a subpath along a wedge's edge takes half
    /// the body outside it, and the ground behind a rock is in the wedge but hidden. Cells
    /// under the body at `start` are left out (the rover stands there), and so is the mast's
    /// blind zone around the sensing position, as for the local tangent graph (`near_visible`:
    /// the rover's footprint, seen from the previous position).
    pub(super) fn first_unseen(&self, start: Pose2, poses: &[Pose2]) -> Option<usize> {
        let safety = self.safety.as_ref()?;
        let grid = safety.grid();
        let origin = self.view.as_ref().map_or(start.position(), |v| v.origin);
        let (half_l, half_w) = (0.5 * self.rover.length, 0.5 * self.rover.width);
        let exempt = |q: Point2| {
            let b = start.inverse_transform(q);
            (b.x.abs() <= half_l && b.y.abs() <= half_w) || q.dist(origin) <= self.config.paper.near_visible
        };
        first_unseen_pose(
            poses,
            (half_l + UNSEEN_LOOKAHEAD, half_w),
            safety.config().resolution,
            exempt,
            |q| grid.at_world(q.x, q.y).is_some_and(|c| c.count > 0),
        )
    }
}

/// The first of `poses` at which a body outline of half-extents `half` (m, along and across
/// the heading) covers unseen ground: a cell centre of the `resolution` lattice (cells
/// `[i r, (i + 1) r)`, as the map's) inside the outline, not `exempt`, that is not `sensed`
/// and is no one-cell gap among sensed cells (at least five of its eight neighbours sensed:
/// the spacing of a range image's far rows).
pub(super) fn first_unseen_pose(
    poses: &[Pose2],
    half: (f64, f64),
    resolution: f64,
    exempt: impl Fn(Point2) -> bool,
    sensed: impl Fn(Point2) -> bool,
) -> Option<usize> {
    let n = (half.0.hypot(half.1) / resolution).ceil() as i64;
    let lattice = |x: f64, y: f64| Point2::new((x + 0.5) * resolution, (y + 0.5) * resolution);
    poses.iter().position(|pose| {
        let (cx, cy) = ((pose.x / resolution).floor(), (pose.y / resolution).floor());
        (-n..=n).any(|dr| {
            (-n..=n).any(|dc| {
                let (i, j) = (cx + dc as f64, cy + dr as f64);
                let q = lattice(i, j);
                let b = pose.inverse_transform(q);
                if b.x.abs() > half.0 || b.y.abs() > half.1 || exempt(q) || sensed(q) {
                    return false;
                }
                let around = [(-1, -1), (0, -1), (1, -1), (-1, 0), (1, 0), (-1, 1), (0, 1), (1, 1)]
                    .iter()
                    .filter(|&&(a, c)| sensed(lattice(i + a as f64, j + c as f64)))
                    .count();
                around < 5
            })
        })
    })
}
