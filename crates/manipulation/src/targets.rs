//! Target selection (paper 003 section 4.2): "finding the closest point on the terrain to the
//! commanded target. Once the closest surface point is identified, it and other points at a
//! regular spatial sampling in a list are candidate targets ... The first step in evaluating a
//! candidate target is to compute its surface normal, since AutoPlace must approach the surface
//! within 10 degrees of the local surface normal ... Surface roughness (maximum variation in
//! surface height relative to the normal) is also computed at this point."
//!
//! Candidates: the closest sensed point, then the sensed points nearest to the nodes of a square
//! grid around it (spacing [`TargetParams::spacing`]), nearest nodes first. For each, a plane is
//! fitted by least squares (principal axes) to the sensed points within the instrument's
//! footprint radius; its normal, oriented up, is the surface normal.
//!
//! Departures, with their reasons:
//! - Roughness is the maximum minus the minimum of the mean heights above the fitted plane in
//!   1 cm cells of the plane (cells with two points or more), not of the raw points: the
//!   Hazcams' range noise at 0.5-1 m (a few millimetres, with rare centimetre blunders) would
//!   otherwise decide the maximum alone; relief larger than a cell (a rim, a step) still shows.
//! - Curvature: the normal of a wider patch ([`TargetParams::curvature_radius`]) must agree with
//!   the patch's within [`TargetParams::max_bend_deg`], else the candidate counts as rough. The
//!   paper's roughness is a height span; on a rock's rounded rim the span over 3 cm stays small
//!   while the contact plate would rock, and the stereo normal there was off by more than 10 deg.
//! - A patch must hold points in each eighth of its outer half: a candidate on a rock's rim
//!   whose far side the cameras cannot see would otherwise fit the visible top alone.
//! - A candidate is refused for its normal when no direction within 10 deg of the normal comes
//!   within the arm's approach cone (instruments point at most [`TargetParams::max_tilt_deg`],
//!   25 deg, from straight down): the arm works from above, and on steeper faces (rocks' sides
//!   facing the Hazcams) the stereo normal of a 3 cm patch was off by more than 10 deg in
//!   `rovernav eval autoplace` (4 of 51 placements at 35 deg).
//! - A second view (the Navcam pair in the evaluation) may check a candidate: its own plane
//!   through the same patch must agree within [`TargetParams::max_disagreement_deg`] (else
//!   the candidate's normal is refused), and a patch it did not sense is missing data.

use crate::geometry::V3;
use nalgebra::{Matrix3, SymmetricEigen};

/// Target selection settings.
#[derive(Clone, Debug, PartialEq)]
pub struct TargetParams {
    /// The closest sensed point must be within this distance of the commanded target (m).
    pub max_offset: f64,
    /// Candidate grid spacing (m).
    pub spacing: f64,
    /// Candidates lie within this distance of the closest point (m).
    pub search_radius: f64,
    /// Radius of the patch the normal and roughness are computed from: the instrument's
    /// contact footprint (m).
    pub patch_radius: f64,
    /// Fewest sensed points in a patch.
    pub min_points: usize,
    /// Largest roughness accepted (m).
    pub max_roughness: f64,
    /// Radius of the wider patch the curvature test fits (m).
    pub curvature_radius: f64,
    /// Largest angle between the patch's normal and the wider patch's (deg).
    pub max_bend_deg: f64,
    /// Largest angle between the normal and a second view's normal of the same patch (deg).
    pub max_disagreement_deg: f64,
    /// Largest angle between an approach and straight down the arm can use (deg).
    pub max_tilt_deg: f64,
    /// Largest angle between the approach and the surface normal (deg): the contact sensors'.
    pub approach_tolerance_deg: f64,
}

impl Default for TargetParams {
    fn default() -> Self {
        Self {
            max_offset: 0.10,
            spacing: 0.02,
            search_radius: 0.06,
            patch_radius: 0.03,
            min_points: 15,
            max_roughness: 0.015,
            curvature_radius: 0.05,
            max_bend_deg: 6.0,
            max_disagreement_deg: 6.0,
            max_tilt_deg: 25.0,
            approach_tolerance_deg: 10.0,
        }
    }
}

/// A candidate that passed the normal and roughness checks.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Candidate {
    /// The sensed surface point (body frame, m).
    pub point: [f64; 3],
    /// Unit surface normal (up).
    pub normal: [f64; 3],
    /// Roughness (m).
    pub roughness: f64,
    /// Sensed points in the patch.
    pub support: usize,
}

/// Why a candidate was rejected.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Rejection {
    /// Too few sensed points around it.
    NoData,
    /// Its normal cannot be approached within the tolerance.
    Normal,
    /// Too rough.
    Roughness,
}

/// The sensed points of the targeting view, with a coarse horizontal bucket index.
#[derive(Clone, Debug)]
pub struct Surface {
    points: Vec<V3>,
    bucket: f64,
    buckets: std::collections::HashMap<(i64, i64), Vec<u32>>,
}

impl Surface {
    /// Indexes the finite points of a cloud (body frame).
    pub fn new(points: &[[f32; 3]]) -> Self {
        let bucket = 0.05;
        let points: Vec<V3> = points
            .iter()
            .filter(|p| p.iter().all(|x| x.is_finite()))
            .map(|p| V3::new(p[0] as f64, p[1] as f64, p[2] as f64))
            .collect();
        let mut buckets: std::collections::HashMap<(i64, i64), Vec<u32>> = Default::default();
        for (i, p) in points.iter().enumerate() {
            buckets.entry(key(p, bucket)).or_default().push(i as u32);
        }
        Self { points, bucket, buckets }
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether there are no points.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Points whose horizontal distance to `q` is below `r` (indices).
    fn near(&self, q: &V3, r: f64) -> Vec<usize> {
        let (c0, r0) = key(&(q - V3::new(r, r, 0.0)), self.bucket);
        let (c1, r1) = key(&(q + V3::new(r, r, 0.0)), self.bucket);
        let mut out = Vec::new();
        for c in c0..=c1 {
            for rr in r0..=r1 {
                if let Some(ids) = self.buckets.get(&(c, rr)) {
                    out.extend(
                        ids.iter().map(|&i| i as usize).filter(|&i| (self.points[i] - q).xy().norm() < r),
                    );
                }
            }
        }
        out
    }

    /// The sensed point closest (in 3D) to `q` within `max` (m).
    pub fn closest(&self, q: &V3, max: f64) -> Option<V3> {
        self.near(q, max)
            .into_iter()
            .map(|i| self.points[i])
            .filter(|p| (p - q).norm() <= max)
            .min_by(|a, b| (a - q).norm().total_cmp(&(b - q).norm()))
    }

    /// Candidate points: the closest point to `target`, then grid nodes around it, nearest
    /// first, each replaced by the sensed point nearest to it horizontally. `None` when no point
    /// lies within `max_offset` of the target.
    pub fn candidates(&self, target: &V3, params: &TargetParams) -> Option<Vec<V3>> {
        let first = self.closest(target, params.max_offset)?;
        let k = (params.search_radius / params.spacing).floor() as i64;
        let mut nodes: Vec<(f64, V3)> = Vec::new();
        for i in -k..=k {
            for j in -k..=k {
                let off = V3::new(i as f64, j as f64, 0.0) * params.spacing;
                if off.norm() <= params.search_radius + 1e-9 {
                    nodes.push((off.norm(), first + off));
                }
            }
        }
        nodes.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut out: Vec<V3> = Vec::new();
        for (_, node) in nodes {
            let best = self
                .near(&node, 0.5 * params.spacing)
                .into_iter()
                .map(|i| self.points[i])
                .min_by(|a, b| (a - node).xy().norm().total_cmp(&(b - node).xy().norm()));
            if let Some(p) = best
                && !out.iter().any(|q| (q - p).norm() < 1e-9)
            {
                out.push(p);
            }
        }
        Some(out)
    }

    /// The normal and roughness of the patch around `p`.
    pub fn evaluate(&self, p: &V3, params: &TargetParams) -> Result<Candidate, Rejection> {
        let ids: Vec<usize> = self
            .near(p, params.patch_radius)
            .into_iter()
            .filter(|&i| (self.points[i] - p).norm() < params.patch_radius)
            .collect();
        if ids.len() < params.min_points {
            return Err(Rejection::NoData);
        }
        let (mean, normal) = self.plane(&ids);
        let (e1, e2) = {
            let helper = if normal.x.abs() < 0.9 { V3::x() } else { V3::y() };
            let e1 = normal.cross(&helper).normalize();
            (e1, normal.cross(&e1))
        };
        // Roughness: the span of the mean heights above the plane in 1 cm cells of the plane.
        let mut cells: std::collections::HashMap<(i64, i64), (f64, usize)> = Default::default();
        for &i in &ids {
            let d = self.points[i] - mean;
            let key = ((d.dot(&e1) / 0.01).floor() as i64, (d.dot(&e2) / 0.01).floor() as i64);
            let e = cells.entry(key).or_default();
            e.0 += d.dot(&normal);
            e.1 += 1;
        }
        let means: Vec<f64> = cells.values().filter(|(_, n)| *n >= 2).map(|(s, n)| s / *n as f64).collect();
        let roughness = if means.len() >= 3 {
            means.iter().copied().fold(f64::MIN, f64::max) - means.iter().copied().fold(f64::MAX, f64::min)
        } else {
            let h: Vec<f64> = ids.iter().map(|&i| (self.points[i] - mean).dot(&normal)).collect();
            h.iter().copied().fold(f64::MIN, f64::max) - h.iter().copied().fold(f64::MAX, f64::min)
        };
        // A point on the plane under p (the sensed point itself carries its noise).
        let point = p - normal * (p - mean).dot(&normal);
        let candidate =
            Candidate { point: point.into(), normal: normal.into(), roughness, support: ids.len() };
        // Every eighth of the patch's outer half must hold a point: a patch seen only in part
        // (the far side of a rock's rim, a dropout) is missing data, not a smooth surface.
        let mut sectors = [false; 8];
        for &i in &ids {
            let d = self.points[i] - p;
            let (u, v) = (d.dot(&e1), d.dot(&e2));
            if u.hypot(v) > 0.5 * params.patch_radius {
                let k = ((v.atan2(u) + std::f64::consts::PI) / std::f64::consts::FRAC_PI_4) as usize;
                sectors[k.min(7)] = true;
            }
        }
        if !sectors.iter().all(|s| *s) {
            return Err(Rejection::NoData);
        }
        // A curved surface (a rock's rim or a small rock's whole top) fits a different plane at
        // a larger scale: the contact plate would not sit flat. Counted as roughness.
        let wide: Vec<usize> = self
            .near(p, params.curvature_radius)
            .into_iter()
            .filter(|&i| (self.points[i] - p).norm() < params.curvature_radius)
            .collect();
        let (_, wide_normal) = self.plane(&wide);
        let bend = wide_normal.angle(&normal).to_degrees();
        let tilt = normal.z.clamp(-1.0, 1.0).acos().to_degrees();
        if tilt - params.approach_tolerance_deg > params.max_tilt_deg {
            return Err(Rejection::Normal);
        }
        if roughness > params.max_roughness || bend > params.max_bend_deg {
            return Err(Rejection::Roughness);
        }
        Ok(candidate)
    }
}

impl Surface {
    /// The normal of this surface's points within the patch radius of `p` (a second view's
    /// opinion of a candidate), `None` with too few points.
    pub fn normal_at(&self, p: &V3, params: &TargetParams) -> Option<V3> {
        let ids: Vec<usize> = self
            .near(p, params.patch_radius)
            .into_iter()
            .filter(|&i| (self.points[i] - p).norm() < params.patch_radius)
            .collect();
        (ids.len() >= params.min_points).then(|| self.plane(&ids).1)
    }

    /// Least-squares plane (principal axes) of the points `ids`: centroid and upward normal.
    fn plane(&self, ids: &[usize]) -> (V3, V3) {
        let n = ids.len().max(1) as f64;
        let mean = ids.iter().fold(V3::zeros(), |a, &i| a + self.points[i]) / n;
        let mut cov = Matrix3::zeros();
        for &i in ids {
            let d = self.points[i] - mean;
            cov += d * d.transpose();
        }
        let eig = SymmetricEigen::new(cov / n);
        let mut normal: V3 = eig.eigenvectors.column(eig.eigenvalues.imin()).into();
        if normal.z < 0.0 {
            normal = -normal;
        }
        (mean, normal)
    }
}

fn key(p: &V3, bucket: f64) -> (i64, i64) {
    ((p.x / bucket).floor() as i64, (p.y / bucket).floor() as i64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Points on a plane z = a x + b y + c with uniform noise, on a 5 mm grid.
    fn plane(a: f64, b: f64, noise: f64, seed: u64) -> Vec<[f32; 3]> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut out = Vec::new();
        for i in 0..60 {
            for j in 0..60 {
                let (x, y) = (0.6 + i as f64 * 0.005, -0.15 + j as f64 * 0.005);
                let z = a * x + b * y + 0.02 + rng.random_range(-noise..=noise);
                out.push([x as f32, y as f32, z as f32]);
            }
        }
        out
    }

    #[test]
    fn the_normal_of_a_tilted_plane_is_its_analytic_normal() {
        for (a, b) in [(0.0, 0.0), (0.3, -0.1), (-0.2, 0.4)] {
            let s = Surface::new(&plane(a, b, 0.001, 1));
            let at = s.closest(&V3::new(0.75, 0.0, 0.75 * a + 0.02), 0.1).unwrap();
            let c = s.evaluate(&at, &TargetParams::default()).unwrap();
            let truth = V3::new(-a, -b, 1.0).normalize();
            let err = V3::from(c.normal).angle(&truth).to_degrees();
            assert!(err < 0.5, "normal error {err} deg");
            assert!(c.roughness <= 0.002 + 1e-6 && c.roughness > 0.001, "{}", c.roughness);
        }
    }

    #[test]
    fn steep_rough_and_empty_patches_are_rejected_with_their_reason() {
        let p = TargetParams::default();
        // 50 deg tilt: beyond 25 + 10.
        let steep = Surface::new(&plane(1.2, 0.0, 0.0, 2));
        let on = steep.closest(&V3::new(0.75, 0.0, 1.2 * 0.75 + 0.02), 0.1).unwrap();
        assert_eq!(steep.evaluate(&on, &p), Err(Rejection::Normal));
        let at = V3::new(0.75, 0.0, 0.02);
        let rough = Surface::new(&plane(0.0, 0.0, 0.02, 3));
        assert_eq!(rough.evaluate(&at, &p), Err(Rejection::Roughness));
        // Half a patch: the edge of the sensed area.
        let half: Vec<[f32; 3]> = plane(0.0, 0.0, 0.0, 5).into_iter().filter(|p| p[0] < 0.75).collect();
        let edge = Surface::new(&half);
        let on = edge.closest(&V3::new(0.745, 0.0, 0.02), 0.1).unwrap();
        assert_eq!(edge.evaluate(&on, &p), Err(Rejection::NoData));
        let far = V3::new(2.0, 0.0, 0.0);
        assert_eq!(rough.evaluate(&far, &p), Err(Rejection::NoData));
        assert!(rough.candidates(&far, &p).is_none());
    }

    #[test]
    fn candidates_start_at_the_closest_point_and_follow_a_regular_grid() {
        let s = Surface::new(&plane(0.0, 0.0, 0.0, 4));
        let p = TargetParams::default();
        let target = V3::new(0.7512, 0.0031, 0.05);
        let c = s.candidates(&target, &p).unwrap();
        // The closest point in 3D is the grid point under the target.
        assert!((c[0] - V3::new(0.75, 0.005, 0.02)).norm() < 1e-6, "{:?}", c[0]);
        // Spacing 2 cm within 6 cm: 29 nodes of the disc.
        assert_eq!(c.len(), 29);
        let dist: Vec<f64> = c.iter().map(|q| (q - c[0]).xy().norm()).collect();
        assert!(dist.windows(2).all(|w| w[0] <= w[1] + 0.006), "nearest first: {dist:?}");
    }
}
