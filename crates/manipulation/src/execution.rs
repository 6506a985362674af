//! Executing a placement on a true terrain, for scoring only (the autonomy never calls it):
//! the arm is moved along its plan (every joint-space segment sampled 5 mm apart), the straight
//! move stops when the instrument's contact face meets the true surface (the contact sensor),
//! and every executed pose is tested against the true height field (rocks included), the
//! rover's body and the arm itself. The contact angle error is the angle between the approach
//! and the true surface normal, a plane fitted to the true heights within 3 cm of the contact.
//!
//! The truth is a [`Ground`]: the true surface height at a point of the arm's (body) frame,
//! so that `rovernav eval autoplace` (whose body frame is the world frame) and a mission test
//! (the rover anywhere on a site) score the same way.

use crate::arm::{Arm, Joints};
use crate::feasibility::{Plan, interpolate, trimmed};
use crate::geometry::Capsule;
use nalgebra::{Matrix3, Vector3};

/// The true surface: its height (body z, m) at body (x, y), `None` off the known terrain.
pub trait Ground {
    /// Height of the surface at (x, y).
    fn height(&self, x: f64, y: f64) -> Option<f64>;
}

impl<F: Fn(f64, f64) -> Option<f64>> Ground for F {
    fn height(&self, x: f64, y: f64) -> Option<f64> {
        self(x, y)
    }
}

/// What executing a plan did in truth.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Execution {
    /// The part that met something first, if any: "terrain", "rover" or "self".
    pub collision: Option<&'static str>,
    /// Whether the contact face met the surface before the end of the straight move.
    pub contact: bool,
    /// Angle between the approach and the true surface normal at the contact (deg).
    pub normal_error_deg: f64,
    /// Where the contact face stopped (m).
    pub stop: [f64; 3],
}

/// Length of the instrument's end allowed to touch the surface on the straight move (m): the
/// overdrive plus the contact face's own thickness.
const CONTACT_ALLOWANCE: f64 = 0.03;

/// Whether a capsule meets the height field: some point within `radius` of its axis lies
/// below the surface (axis and disc sampled 5 mm apart).
pub fn capsule_hits_terrain(dem: &dyn Ground, c: &Capsule) -> bool {
    let r = c.radius;
    let n = (r / 0.005).ceil() as i32;
    c.cover(0.005).any(|p| {
        for i in -n..=n {
            for j in -n..=n {
                let (dx, dy) = (i as f64 * 0.005, j as f64 * 0.005);
                let d2 = dx * dx + dy * dy;
                if d2 > r * r {
                    continue;
                }
                if let Some(h) = dem.height(p.x + dx, p.y + dy)
                    && h > p.z - (r * r - d2).sqrt()
                {
                    return true;
                }
            }
        }
        false
    })
}

/// What the arm at `q` meets; the instrument's last `exempt` metres may touch the terrain.
fn pose_hits(arm: &Arm, dem: &dyn Ground, q: &Joints, exempt: f64) -> Option<&'static str> {
    if arm.self_collides(q) {
        return Some("self");
    }
    if arm.hits_rover(q) {
        return Some("rover");
    }
    let caps = arm.capsules(q);
    let hit = caps.iter().enumerate().any(|(i, c)| {
        let c = if i == 4 { trimmed(c, exempt) } else { Some(*c) };
        c.is_some_and(|c| capsule_hits_terrain(dem, &c))
    });
    hit.then_some("terrain")
}

/// The true surface normal at (x, y): least-squares plane through the heights within 3 cm (the
/// contact footprint, the patch AutoPlace estimates its normal from).
pub fn true_normal(dem: &dyn Ground, x: f64, y: f64) -> Vector3<f64> {
    let mut ata = Matrix3::zeros();
    let mut atb = Vector3::zeros();
    for i in -6..=6 {
        for j in -6..=6 {
            let (dx, dy) = (i as f64 * 0.005, j as f64 * 0.005);
            if dx * dx + dy * dy > 0.03 * 0.03 + 1e-12 {
                continue;
            }
            if let Some(h) = dem.height(x + dx, y + dy) {
                let row = Vector3::new(dx, dy, 1.0);
                ata += row * row.transpose();
                atb += row * h;
            }
        }
    }
    let sol = ata.lu().solve(&atb).unwrap_or_else(Vector3::zeros);
    Vector3::new(-sol.x, -sol.y, 1.0).normalize()
}

/// Executes `plan` on the true terrain.
pub fn execute(arm: &Arm, dem: &dyn Ground, plan: &Plan) -> Execution {
    let step = 0.005;
    for w in plan.via.windows(2) {
        for q in interpolate(arm, &w[0], &w[1], step) {
            if let Some(what) = pose_hits(arm, dem, &q, 0.0) {
                return Execution {
                    collision: Some(what),
                    contact: false,
                    normal_error_deg: f64::NAN,
                    stop: arm.forward(&q).tip.into(),
                };
            }
        }
    }
    let axis = Vector3::from(plan.axis);
    let mut last = plan.approach[0];
    for w in plan.approach.windows(2) {
        for q in interpolate(arm, &w[0], &w[1], step) {
            last = q;
            let tip = arm.forward(&q).tip;
            let touching = dem.height(tip.x, tip.y).is_some_and(|h| tip.z <= h);
            if let Some(what) = pose_hits(arm, dem, &q, CONTACT_ALLOWANCE) {
                return Execution {
                    collision: Some(what),
                    contact: touching,
                    normal_error_deg: f64::NAN,
                    stop: tip.into(),
                };
            }
            if touching {
                return Execution {
                    collision: None,
                    contact: true,
                    normal_error_deg: angle(dem, &tip, &axis),
                    stop: tip.into(),
                };
            }
        }
    }
    let tip = arm.forward(&last).tip;
    Execution { collision: None, contact: false, normal_error_deg: angle(dem, &tip, &axis), stop: tip.into() }
}

fn angle(dem: &dyn Ground, tip: &Vector3<f64>, axis: &Vector3<f64>) -> f64 {
    true_normal(dem, tip.x, tip.y).angle(&-axis).to_degrees()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn true_normal_of_a_tilted_plane_and_capsule_contact() {
        let dem = |x: f64, y: f64| ((0.0..1.0).contains(&x) && (0.0..1.0).contains(&y)).then_some(0.3 * x);
        let n = true_normal(&dem, 0.5, 0.5);
        assert!(n.angle(&Vector3::new(-0.3, 0.0, 1.0)) < 1e-4, "{n:?}");
        let z = 0.12;
        let above = Capsule {
            a: Vector3::new(0.4, 0.5, z + 0.05),
            b: Vector3::new(0.4, 0.6, z + 0.05),
            radius: 0.03,
        };
        assert!(!capsule_hits_terrain(&dem, &above));
        let low = Capsule {
            a: above.a - Vector3::new(0.0, 0.0, 0.06),
            b: above.b - Vector3::new(0.0, 0.0, 0.06),
            ..above
        };
        assert!(capsule_hits_terrain(&dem, &low));
    }
}
