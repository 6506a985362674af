//! Analytic shapes: the rover's body (boxes and cylinders) and the transparent volumes in the
//! air (ellipsoids and vertical columns), with their ray intersections.
//!
//! The rover is drawn from simple primitives (a box body, a mast, a pan/tilt head and six
//! wheels), posed in the world with its true pose; rays are moved into the body frame and
//! intersected there (slab test for boxes, the quadratic for cylinders with flat caps). A ray
//! that starts inside a primitive ignores it, so a camera mounted inside its housing sees out.

use nalgebra::{Isometry3, Point3, Vector3};
use rovernav_core::{Pose3, RoverConfig};

use super::rig::pose_isometry;
use crate::vehicle::{WHEEL_HALF_WIDTH, WHEEL_RADIUS};

/// A solid primitive of the rover, in the body frame.
#[derive(Clone, Debug, PartialEq)]
pub enum Primitive {
    /// A box with its own yaw about body z.
    Box {
        /// Centre (m).
        centre: [f64; 3],
        /// Half extents along its own x, y, z (m).
        half: [f64; 3],
        /// Rotation about body z (rad).
        yaw: f64,
        /// Lambertian albedo.
        albedo: f64,
    },
    /// A cylinder with flat caps.
    Cylinder {
        /// Centre (m).
        centre: [f64; 3],
        /// Unit axis.
        axis: [f64; 3],
        /// Radius (m).
        radius: f64,
        /// Half length along the axis (m).
        half_length: f64,
        /// Lambertian albedo.
        albedo: f64,
    },
}

/// Where a ray met a solid: range, outward unit normal (world frame) and albedo.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolidHit {
    /// Distance along the ray (m).
    pub t: f64,
    /// Outward unit normal in the world frame.
    pub normal: [f64; 3],
    /// Lambertian albedo of the surface.
    pub albedo: f64,
}

/// The rover's body at its true pose.
#[derive(Clone, Debug)]
pub struct RoverBody {
    primitives: Vec<Primitive>,
    /// Groups of primitives with their body-frame bounding box (min, max).
    groups: Vec<(Aabb, std::ops::Range<usize>)>,
    to_world: Isometry3<f64>,
    to_body: Isometry3<f64>,
    /// Bounding sphere (body frame centre, radius) for culling.
    bound: ([f64; 3], f64),
}

/// Smallest accepted intersection distance (m): hits closer than this are the ray's own start.
const EPS: f64 = 1e-6;

impl RoverBody {
    /// The rover of `rover`'s dimensions at `pose`, its Navcam head panned to `pan` (rad).
    pub fn new(rover: &RoverConfig, pose: &Pose3, pan: f64) -> Self {
        let (l, w, c) = (rover.length, rover.width, rover.clearance);
        let deck_top = c + 0.22;
        let mast_base = deck_top;
        let head_z = rover.mast_height;
        let wheel_x = (0.5 * l - WHEEL_RADIUS).max(0.0);
        // Chassis first (body, deck, wheels), then the mast group: each group has a bounding
        // box, so rays from the mast head skip the chassis test unless they look at it.
        let mut primitives = vec![
            // Warm electronics box: light, dusty paint.
            Primitive::Box {
                centre: [0.0, 0.0, 0.5 * (c + deck_top)],
                half: [0.5 * l, 0.4 * w, 0.5 * (deck_top - c)],
                yaw: 0.0,
                albedo: 0.45,
            },
            // Solar deck: dark cells on a thin plate slightly wider than the body.
            Primitive::Box {
                centre: [0.0, 0.0, deck_top + 0.01],
                half: [0.5 * l + 0.02, 0.5 * w + 0.02, 0.01],
                yaw: 0.0,
                albedo: 0.12,
            },
        ];
        for x in [wheel_x, 0.0, -wheel_x] {
            for y in [0.5 * rover.track, -0.5 * rover.track] {
                primitives.push(Primitive::Cylinder {
                    centre: [x, y, WHEEL_RADIUS],
                    axis: [0.0, 1.0, 0.0],
                    radius: WHEEL_RADIUS,
                    half_length: WHEEL_HALF_WIDTH,
                    albedo: 0.3,
                });
            }
        }
        let chassis = primitives.len();
        primitives.extend([
            Primitive::Cylinder {
                centre: [0.0, 0.0, 0.5 * (mast_base + head_z - 0.06)],
                axis: [0.0, 0.0, 1.0],
                radius: 0.025,
                half_length: 0.5 * (head_z - 0.06 - mast_base).max(0.01),
                albedo: 0.55,
            },
            Primitive::Box { centre: [0.0, 0.0, head_z], half: [0.05, 0.16, 0.05], yaw: pan, albedo: 0.5 },
        ]);
        let groups = vec![
            (bounds(&primitives[..chassis]), 0..chassis),
            (bounds(&primitives[chassis..]), chassis..primitives.len()),
        ];
        let to_world = pose_isometry(pose);
        let bound_centre = [0.0, 0.0, 0.5 * head_z];
        let bound_radius = (0.5 * l + 0.05).hypot(0.5 * w + 0.05).hypot(0.5 * head_z + 0.1);
        Self {
            primitives,
            groups,
            to_world,
            to_body: to_world.inverse(),
            bound: (bound_centre, bound_radius),
        }
    }

    /// The primitives in the body frame.
    pub fn primitives(&self) -> &[Primitive] {
        &self.primitives
    }

    /// Nearest intersection of a world-frame ray with the body within `(EPS, t_max)`.
    pub fn intersect(&self, origin: [f64; 3], dir: [f64; 3], t_max: f64) -> Option<SolidHit> {
        let o = self.to_body * Point3::from(origin);
        let d = self.to_body.rotation * Vector3::from(dir);
        let oc = o.coords - Vector3::from(self.bound.0);
        let b = oc.dot(&d);
        if oc.norm_squared() - b * b > self.bound.1 * self.bound.1 {
            return None;
        }
        let mut best: Option<(f64, Vector3<f64>, f64)> = None;
        let groups = self.groups.iter().filter(|(b, _)| slab(&o.coords, &d, b, t_max));
        for p in groups.flat_map(|(_, range)| &self.primitives[range.clone()]) {
            let limit = best.map_or(t_max, |b| b.0);
            if let Some((t, n)) = intersect_primitive(p, &o.coords, &d, limit) {
                let albedo = match p {
                    Primitive::Box { albedo, .. } | Primitive::Cylinder { albedo, .. } => *albedo,
                };
                best = Some((t, n, albedo));
            }
        }
        best.map(|(t, n, albedo)| {
            let n = self.to_world.rotation * n;
            SolidHit { t, normal: [n.x, n.y, n.z], albedo }
        })
    }
}

/// An axis-aligned box in the body frame: (min, max) corners.
type Aabb = ([f64; 3], [f64; 3]);

/// Whether a ray meets an axis-aligned box (min, max) for some `t` in `[0, limit)`.
fn slab(o: &Vector3<f64>, d: &Vector3<f64>, b: &Aabb, limit: f64) -> bool {
    let (mut t0, mut t1) = (0.0f64, limit);
    for k in 0..3 {
        if d[k] == 0.0 {
            if o[k] < b.0[k] || o[k] > b.1[k] {
                return false;
            }
            continue;
        }
        let (a, c) = ((b.0[k] - o[k]) / d[k], (b.1[k] - o[k]) / d[k]);
        t0 = t0.max(a.min(c));
        t1 = t1.min(a.max(c));
    }
    t0 <= t1
}

/// A body-frame box (min, max) enclosing primitives.
fn bounds(primitives: &[Primitive]) -> Aabb {
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for p in primitives {
        let (centre, extent) = match p {
            Primitive::Box { centre, half, yaw, .. } => {
                let (s, c) = (yaw.sin().abs(), yaw.cos().abs());
                (centre, [c * half[0] + s * half[1], s * half[0] + c * half[1], half[2]])
            }
            Primitive::Cylinder { centre, axis, radius, half_length, .. } => {
                (centre, [0, 1, 2].map(|k| radius + half_length * axis[k].abs()))
            }
        };
        for k in 0..3 {
            lo[k] = lo[k].min(centre[k] - extent[k]);
            hi[k] = hi[k].max(centre[k] + extent[k]);
        }
    }
    (lo, hi)
}

/// Intersection of a body-frame ray with one primitive in `(EPS, limit)`: distance and outward
/// normal (body frame). A ray starting inside the primitive misses it.
fn intersect_primitive(
    p: &Primitive,
    o: &Vector3<f64>,
    d: &Vector3<f64>,
    limit: f64,
) -> Option<(f64, Vector3<f64>)> {
    match p {
        Primitive::Box { centre, half, yaw, .. } => {
            let (s, c) = if *yaw == 0.0 { (0.0, 1.0) } else { yaw.sin_cos() };
            let rel = o - Vector3::from(*centre);
            // Into the box's own axes (rotation by -yaw).
            let lo = Vector3::new(c * rel.x + s * rel.y, -s * rel.x + c * rel.y, rel.z);
            let ld = Vector3::new(c * d.x + s * d.y, -s * d.x + c * d.y, d.z);
            let (mut t_in, mut t_out, mut axis) = (f64::NEG_INFINITY, f64::INFINITY, 0);
            for k in 0..3 {
                if ld[k] == 0.0 {
                    if lo[k].abs() > half[k] {
                        return None;
                    }
                    continue;
                }
                let (a, b) = ((-half[k] - lo[k]) / ld[k], (half[k] - lo[k]) / ld[k]);
                let (near, far) = if a < b { (a, b) } else { (b, a) };
                if near > t_in {
                    t_in = near;
                    axis = k;
                }
                t_out = t_out.min(far);
            }
            if t_in > t_out || t_in <= EPS || t_in >= limit {
                return None;
            }
            let mut n = Vector3::zeros();
            n[axis] = -ld[axis].signum();
            // Back to the body axes (rotation by +yaw).
            Some((t_in, Vector3::new(c * n.x - s * n.y, s * n.x + c * n.y, n.z)))
        }
        Primitive::Cylinder { centre, axis, radius, half_length, .. } => {
            let a = Vector3::from(*axis);
            let rel = o - Vector3::from(*centre);
            let (oa, da) = (rel.dot(&a), d.dot(&a));
            let (op, dp) = (rel - a * oa, d - a * da);
            let inside = op.norm_squared() <= radius * radius && oa.abs() <= *half_length;
            if inside {
                return None;
            }
            let mut best: Option<(f64, Vector3<f64>)> = None;
            let mut consider = |t: f64, n: Vector3<f64>| {
                if t > EPS && t < limit && best.is_none_or(|b| t < b.0) {
                    best = Some((t, n));
                }
            };
            // Side: |op + dp t| = r.
            let qa = dp.norm_squared();
            if qa > 0.0 {
                let qb = op.dot(&dp);
                let qc = op.norm_squared() - radius * radius;
                let disc = qb * qb - qa * qc;
                if disc >= 0.0 {
                    let t = (-qb - disc.sqrt()) / qa;
                    if (oa + da * t).abs() <= *half_length {
                        consider(t, (op + dp * t) / *radius);
                    }
                }
            }
            // Caps.
            if da != 0.0 {
                for sign in [-1.0, 1.0] {
                    let t = (sign * half_length - oa) / da;
                    if (op + dp * t).norm_squared() <= radius * radius && sign * da < 0.0 {
                        consider(t, a * sign);
                    }
                }
            }
            best
        }
    }
}

/// The shape of a transparent volume.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum VolumeShape {
    /// An axis-aligned ellipsoid with these semi-axes (m): a cloud, a dust puff.
    Ellipsoid {
        /// Semi-axes along x, y, z (m).
        radii: [f64; 3],
    },
    /// A vertical column standing on its centre point: a dust devil.
    Column {
        /// Radius (m).
        radius: f64,
        /// Height above its base (m).
        height: f64,
    },
}

/// A transparent, moving volume in the air (paper 003: clouds and dust devils).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Volume {
    /// Its shape.
    pub shape: VolumeShape,
    /// Position at time 0 (world frame, m): the ellipsoid's centre or the column's base.
    pub position: [f64; 3],
    /// Drift velocity (world frame, m/s).
    pub velocity: [f64; 3],
    /// Extinction coefficient (1/m): optical depth per metre of path.
    pub density: f64,
    /// Single-scattering albedo of its particles.
    pub albedo: f64,
}

impl Volume {
    /// The interval `(t_enter, t_exit)` of a world ray inside the volume at time `time` (s),
    /// clipped to `t >= 0`.
    pub fn chord(&self, origin: [f64; 3], dir: [f64; 3], time: f64) -> Option<(f64, f64)> {
        let p = Vector3::from(self.position) + Vector3::from(self.velocity) * time;
        let o = Vector3::from(origin) - p;
        let d = Vector3::from(dir);
        let (t0, t1) = match self.shape {
            VolumeShape::Ellipsoid { radii } => {
                let (os, ds) =
                    (o.component_div(&Vector3::from(radii)), d.component_div(&Vector3::from(radii)));
                let (a, b, c) = (ds.norm_squared(), os.dot(&ds), os.norm_squared() - 1.0);
                let disc = b * b - a * c;
                if a == 0.0 || disc < 0.0 {
                    return None;
                }
                ((-b - disc.sqrt()) / a, (-b + disc.sqrt()) / a)
            }
            VolumeShape::Column { radius, height } => {
                let (a, b, c) =
                    (d.x * d.x + d.y * d.y, o.x * d.x + o.y * d.y, o.x * o.x + o.y * o.y - radius * radius);
                let (mut t0, mut t1) = if a == 0.0 {
                    if c > 0.0 {
                        return None;
                    }
                    (f64::NEG_INFINITY, f64::INFINITY)
                } else {
                    let disc = b * b - a * c;
                    if disc < 0.0 {
                        return None;
                    }
                    ((-b - disc.sqrt()) / a, (-b + disc.sqrt()) / a)
                };
                if d.z == 0.0 {
                    if o.z < 0.0 || o.z > height {
                        return None;
                    }
                } else {
                    let (za, zb) = (-o.z / d.z, (height - o.z) / d.z);
                    t0 = t0.max(za.min(zb));
                    t1 = t1.min(za.max(zb));
                }
                (t0, t1)
            }
        };
        let t0 = t0.max(0.0);
        (t1 > t0).then_some((t0, t1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn culled_intersection_equals_testing_every_primitive() {
        let pose = Pose3 { x: 2.0, y: -1.0, z: 0.3, roll: 0.05, pitch: -0.1, yaw: 0.7 };
        let body = RoverBody::new(&RoverConfig::default(), &pose, 0.4);
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut hits = 0;
        for _ in 0..5000 {
            let o = [0, 1, 2].map(|k| [2.0, -1.0, 0.8][k] + rng.random_range(-2.0..2.0));
            // Aim at a random point of the rover's bounding volume, so most rays come close.
            let aim = pose.transform([
                rng.random_range(-0.5..0.5),
                rng.random_range(-0.4..0.4),
                rng.random_range(0.0..1.3),
            ]);
            let d = (Vector3::from(aim) - Vector3::from(o)).normalize();
            let got = body.intersect(o, [d.x, d.y, d.z], f64::INFINITY).map(|h| h.t);
            let (ob, db) = (body.to_body * Point3::from(o), body.to_body.rotation * d);
            let brute = body
                .primitives
                .iter()
                .filter_map(|p| intersect_primitive(p, &ob.coords, &db, f64::INFINITY).map(|h| h.0))
                .min_by(f64::total_cmp);
            assert_eq!(got.is_some(), brute.is_some());
            if let (Some(a), Some(b)) = (got, brute) {
                assert!((a - b).abs() < 1e-12);
                hits += 1;
            }
        }
        assert!(hits > 1500, "{hits}");
    }
}
