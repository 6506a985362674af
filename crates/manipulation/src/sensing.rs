//! AutoPlace's eyes: a rectified stereo pair of images correlated into body-frame points and
//! the camera centres their lines of sight start from (paper 003 section 4.1: the terrain model
//! is built from the body cameras' stereo range). Images in, points out: the same code serves
//! the executive's tooling arm and `rovernav eval autoplace`.
//!
//! Semi-global matching (`rovernav_vision::stereo`) with a disparity search that reaches 0.35 m
//! (the nearest ground a Hazcam sees), a 0.5 px left-right check, and points beyond
//! [`Correlation::max_range`] dropped. [`mask_rover`] drops the points whose line of sight
//! crosses the rover's body (as flight software masks the rover's own pixels).

use crate::geometry::{Aabb, V3};
use nalgebra::{Isometry3, Point3};
use rovernav_vision::Cahv;
use rovernav_vision::image::Grey16;
use rovernav_vision::stereo::{self, StereoParams, StereoRig};

/// One correlated pair in the body frame AutoPlace works in.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Pair {
    /// Which pair.
    pub name: String,
    /// Camera centres (m).
    pub cameras: Vec<V3>,
    /// Sensed points (m).
    pub points: Vec<[f32; 3]>,
}

/// Correlation settings.
#[derive(Clone, Debug, PartialEq)]
pub struct Correlation {
    /// Nearest range the disparity search covers (m).
    pub near: f64,
    /// Points beyond this range are dropped (m).
    pub max_range: f64,
}

impl Default for Correlation {
    fn default() -> Self {
        Self { near: 0.35, max_range: 3.0 }
    }
}

/// Correlates a rectified pair (`left`, `right`: the cameras' models in the capture's body
/// frame) and moves its points and camera centres by `to_final` (capture body frame -> the
/// frame AutoPlace plans in; the identity for a pair taken where the arm works).
#[allow(clippy::too_many_arguments)]
pub fn correlate(
    name: &str,
    left: &Cahv,
    right: &Cahv,
    left_image: &Grey16,
    right_image: &Grey16,
    to_final: &Isometry3<f64>,
    settings: &Correlation,
) -> Result<Pair, String> {
    let rig = StereoRig::new(*left, *right).map_err(|e| format!("{name}: not a rectified pair: {e}"))?;
    let max_disparity = ((rig.focal_baseline() / settings.near) * 1.2).ceil() as usize;
    let params = StereoParams {
        max_disparity: max_disparity.clamp(16, 128),
        lr_tolerance: 0.5,
        ..StereoParams::default()
    };
    let disparity = stereo::compute_disparity(left_image, right_image, &params)
        .map_err(|e| format!("{name}: stereo correlation: {e}"))?;
    let range = rig.range_image(&disparity, stereo::range::DEFAULT_SIGMA_D_PX);
    let mut points = Vec::new();
    for (p, rg) in range.points.iter().zip(&range.range) {
        if rg.is_finite() && (*rg as f64) < settings.max_range && p.iter().all(|v| v.is_finite()) {
            let q = to_final * Point3::new(p[0] as f64, p[1] as f64, p[2] as f64);
            points.push([q.x as f32, q.y as f32, q.z as f32]);
        }
    }
    let cameras = [left.c, right.c].iter().map(|c| (to_final * Point3::from(*c)).coords).collect();
    Ok(Pair { name: name.to_string(), cameras, points })
}

/// Whether the segment `a`-`b` crosses the box (slab test).
pub fn segment_hits_box(a: &V3, b: &V3, bx: &Aabb) -> bool {
    let d = b - a;
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for k in 0..3 {
        if d[k].abs() < 1e-12 {
            if a[k] < bx.min[k] || a[k] > bx.max[k] {
                return false;
            }
        } else {
            let (s, t) = ((bx.min[k] - a[k]) / d[k], (bx.max[k] - a[k]) / d[k]);
            t0 = t0.max(s.min(t));
            t1 = t1.min(s.max(t));
        }
    }
    t0 <= t1
}

/// Drops the pair's points whose line of sight from either camera crosses one of `boxes`.
pub fn mask_rover(pair: &mut Pair, boxes: &[Aabb]) {
    let cams = pair.cameras.clone();
    pair.points.retain(|p| {
        let q = V3::new(p[0] as f64, p[1] as f64, p[2] as f64);
        !cams.iter().any(|c| boxes.iter().any(|b| segment_hits_box(c, &q, b)))
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_segment_meets_a_box_only_when_it_crosses_it() {
        let b = Aabb::new([0.0, 0.0, 0.0], [1.0, 1.0, 1.0]);
        let o = V3::new(-1.0, 0.5, 0.5);
        assert!(segment_hits_box(&o, &V3::new(2.0, 0.5, 0.5), &b));
        assert!(!segment_hits_box(&o, &V3::new(-0.1, 0.5, 0.5), &b), "stops short");
        assert!(!segment_hits_box(&o, &V3::new(2.0, 2.5, 0.5), &b), "passes beside");
        let mut pair = Pair {
            name: "t".into(),
            cameras: vec![o],
            points: vec![[2.0, 0.5, 0.5], [-0.5, 0.5, 0.5], [2.0, 3.0, 0.5]],
        };
        mask_rover(&mut pair, &[b]);
        assert_eq!(pair.points, vec![[-0.5, 0.5, 0.5], [2.0, 3.0, 0.5]]);
    }
}
