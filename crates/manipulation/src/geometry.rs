//! The few geometric queries the arm's collision checks need: capsules (a segment with a
//! radius), axis-aligned boxes, segment-segment and point-box distances.
//!
//! Written here rather than taken from `parry3d-f64` 0.31: measured on this 2-core machine
//! (release, one job, machine busy) it adds 41 crates and 55 s of build, its math types are
//! glam's (every call would convert from nalgebra), and AutoPlace needs only these two closed-form
//! distances (Ericson, "Real-Time Collision Detection", 2005, sections 5.1.3 and 5.1.9).

use nalgebra::Vector3;

/// A point or direction in the rover body frame (m): x forward, y left, z up, origin on the
/// ground plane of the wheels.
pub type V3 = Vector3<f64>;

/// An axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Lower corner (m).
    pub min: V3,
    /// Upper corner (m).
    pub max: V3,
}

impl Aabb {
    /// The box between two corners given as arrays.
    pub fn new(min: [f64; 3], max: [f64; 3]) -> Self {
        Self { min: V3::from(min), max: V3::from(max) }
    }

    /// Distance from `p` to the box (0 inside).
    pub fn distance(&self, p: &V3) -> f64 {
        let d = V3::new(
            (self.min.x - p.x).max(p.x - self.max.x).max(0.0),
            (self.min.y - p.y).max(p.y - self.max.y).max(0.0),
            (self.min.z - p.z).max(p.z - self.max.z).max(0.0),
        );
        d.norm()
    }

    /// Whether `other` lies entirely inside this box.
    pub fn contains_box(&self, other: &Aabb) -> bool {
        (0..3).all(|k| other.min[k] >= self.min[k] && other.max[k] <= self.max[k])
    }
}

/// A capsule: every point within `radius` of the segment `a`-`b`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Capsule {
    /// First end of the axis (m).
    pub a: V3,
    /// Second end of the axis (m).
    pub b: V3,
    /// Radius (m).
    pub radius: f64,
}

impl Capsule {
    /// Centres of spheres of radius `radius + step / 2` that together cover the capsule: the
    /// axis sampled at most `step` apart (both ends included).
    pub fn cover(&self, step: f64) -> impl Iterator<Item = V3> + '_ {
        let len = (self.b - self.a).norm();
        let n = ((len / step.max(1e-6)).ceil() as usize).max(1);
        (0..=n).map(move |i| self.a + (self.b - self.a) * (i as f64 / n as f64))
    }

    /// Whether this capsule and `other` overlap.
    pub fn touches(&self, other: &Capsule) -> bool {
        segment_distance(&self.a, &self.b, &other.a, &other.b) < self.radius + other.radius
    }

    /// Whether this capsule overlaps the box (sampled at a tenth of the radius: conservative by
    /// at most that).
    pub fn touches_box(&self, b: &Aabb) -> bool {
        let r = V3::repeat(self.radius);
        let (lo, hi) = (self.a.inf(&self.b) - r, self.a.sup(&self.b) + r);
        if (0..3).any(|k| hi[k] < b.min[k] || lo[k] > b.max[k]) {
            return false;
        }
        let step = 0.1 * self.radius.max(0.005);
        self.cover(step).any(|p| b.distance(&p) < self.radius + 0.5 * step)
    }
}

/// Shortest distance between segments `p1`-`q1` and `p2`-`q2` (Ericson 5.1.9).
pub fn segment_distance(p1: &V3, q1: &V3, p2: &V3, q2: &V3) -> f64 {
    let d1 = q1 - p1;
    let d2 = q2 - p2;
    let r = p1 - p2;
    let a = d1.dot(&d1);
    let e = d2.dot(&d2);
    let f = d2.dot(&r);
    let eps = 1e-15;
    let (s, t) = if a <= eps && e <= eps {
        (0.0, 0.0)
    } else if a <= eps {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = d1.dot(&r);
        if e <= eps {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            let b = d1.dot(&d2);
            let denom = a * e - b * b;
            let mut s = if denom > eps { ((b * f - c * e) / denom).clamp(0.0, 1.0) } else { 0.0 };
            let mut t = (b * s + f) / e;
            if t < 0.0 {
                t = 0.0;
                s = (-c / a).clamp(0.0, 1.0);
            } else if t > 1.0 {
                t = 1.0;
                s = ((b - c) / a).clamp(0.0, 1.0);
            }
            (s, t)
        }
    };
    ((p1 + d1 * s) - (p2 + d2 * t)).norm()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute force: the minimum over a fine grid of parameter pairs.
    fn sampled(p1: &V3, q1: &V3, p2: &V3, q2: &V3) -> f64 {
        let n = 400;
        let mut best = f64::INFINITY;
        for i in 0..=n {
            let x = p1 + (q1 - p1) * (i as f64 / n as f64);
            for j in 0..=n {
                let y = p2 + (q2 - p2) * (j as f64 / n as f64);
                best = best.min((x - y).norm());
            }
        }
        best
    }

    #[test]
    fn segment_distance_matches_a_dense_search() {
        let cases = [
            ([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, 1.0, 0.2], [0.5, -1.0, 0.2]),
            ([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.5, 0.0], [3.0, 0.5, 0.0]),
            ([0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.3], [1.0, 2.0, 0.3]),
            ([0.2, 0.1, 0.0], [0.2, 0.1, 0.0], [-1.0, 0.0, 0.0], [1.0, 0.0, 0.5]),
        ];
        for (a, b, c, d) in cases {
            let (a, b, c, d) = (V3::from(a), V3::from(b), V3::from(c), V3::from(d));
            let exact = segment_distance(&a, &b, &c, &d);
            assert!((exact - sampled(&a, &b, &c, &d)).abs() < 5e-3, "{a:?}{b:?}{c:?}{d:?}");
        }
    }

    #[test]
    fn box_distance_is_zero_inside_and_euclidean_outside() {
        let b = Aabb::new([0.0, 0.0, 0.0], [1.0, 1.0, 1.0]);
        assert_eq!(b.distance(&V3::new(0.5, 0.5, 0.5)), 0.0);
        assert!((b.distance(&V3::new(2.0, 2.0, 0.5)) - 2f64.sqrt()).abs() < 1e-12);
        let c = Capsule { a: V3::new(-1.0, 0.5, 1.05), b: V3::new(2.0, 0.5, 1.05), radius: 0.1 };
        assert!(c.touches_box(&b));
        let c = Capsule { radius: 0.04, ..c };
        assert!(!c.touches_box(&b));
    }
}
