//! Localisation target selection (paper 000 section 4.4).
//!
//! Before moving, the rover predicts, for each direction the mast could look after the move,
//! how well the view would localise it: it builds the map it expects to see from the planned
//! pose (the known cells of the current global map inside the wedge and in line of sight of the
//! mast) and matches that prediction against the global map around the planned pose. The
//! sharpness of the likelihood peak (the fitted covariance) and the strength of competing
//! peaks (failure probability) give the predicted uncertainty; the direction with the lowest
//! is the localisation target.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use rovernav_core::{Grid2, GridGeometry, Point2, Pose2, wrap_angle};

use crate::matching::{MatchError, MlMatcher, MlParams, SearchWindow};

/// How candidate views are generated and compared.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TargetParams {
    /// Number of candidate pan angles, evenly spread over a full turn.
    pub candidates: usize,
    /// Full horizontal field of view of one view (rad).
    pub fov: f64,
    /// Nearest range seen (m).
    pub min_range: f64,
    /// Farthest range used (m).
    pub max_range: f64,
    /// Camera height above the ground (m), for line of sight.
    pub mast_height: f64,
    /// Expected height error of the new view at 1 m (m); it grows with range^2 as stereo's.
    pub height_noise_at_1m: f64,
    /// Half-size of the search window around the planned pose (m).
    pub window_xy: f64,
    /// Half-size of the heading window (rad).
    pub window_yaw: f64,
    /// Matcher parameters.
    pub params: MlParams,
}

impl Default for TargetParams {
    fn default() -> Self {
        Self {
            candidates: 8,
            fov: 45f64.to_radians(),
            min_range: 1.0,
            max_range: 5.0,
            mast_height: 1.2,
            height_noise_at_1m: 0.002,
            window_xy: 0.25,
            window_yaw: 0.03,
            params: MlParams::default(),
        }
    }
}

/// The predicted quality of looking in one direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TargetCandidate {
    /// Mast pan angle in the body frame at the planned pose (rad, counter-clockwise).
    pub pan: f64,
    /// Known, visible cells the view would contain.
    pub cells: usize,
    /// Predicted position uncertainty: sqrt of the trace of the xy covariance (m).
    pub position_sigma: f64,
    /// Predicted failure probability.
    pub failure_probability: f64,
    /// Combined cost (lower is better): the expected position error (m), the predicted sigma if
    /// the match holds and the search window's half-diagonal if it fails.
    pub cost: f64,
}

/// The map expected from `pose` looking along body bearing `pan`: known global cells inside the
/// wedge whose line of sight from the mast clears the terrain, in the rover frame, with the
/// expected sensing error drawn from a generator seeded by `seed` (the prediction must not be
/// an exact copy of the global map, or any view, even of featureless ground, would match it).
pub fn predicted_view(
    global: &Grid2<f32>,
    pose: &Pose2,
    pan: f64,
    params: &TargetParams,
    seed: u64,
) -> Grid2<f32> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let unit = Normal::new(0.0, 1.0).expect("unit normal");
    let r = global.resolution();
    let range = params.max_range;
    let n = (2.0 * range / r).ceil() as usize;
    let geometry = GridGeometry { cols: n, rows: n, resolution: r, origin_x: -range, origin_y: -range };
    let mut out = Grid2::filled(geometry, f32::NAN);
    let height = |p: Point2| global.at_world(p.x, p.y).copied().filter(|h| h.is_finite());
    let Some(ground) = height(pose.position()) else {
        return out;
    };
    let eye = f64::from(ground) + params.mast_height;
    for row in 0..n {
        for col in 0..n {
            let (bx, by) = geometry.center(col, row);
            let d = bx.hypot(by);
            if d < params.min_range || d > range || wrap_angle(by.atan2(bx) - pan).abs() > 0.5 * params.fov {
                continue;
            }
            let target = pose.transform(Point2::new(bx, by));
            let Some(h) = height(target) else {
                continue;
            };
            // Line of sight: no terrain between the mast and the cell rises above the ray.
            let steps = (d / r).ceil() as usize;
            let visible = (1..steps).all(|k| {
                let t = k as f64 / steps as f64;
                let p = pose.transform(Point2::new(bx * t, by * t));
                let ray = eye + t * (f64::from(h) - eye);
                height(p).is_none_or(|g| f64::from(g) <= ray + 1e-3)
            });
            if visible {
                let noise = params.height_noise_at_1m * d * d * unit.sample(&mut rng);
                *out.get_mut(col, row) = (f64::from(h - ground) + noise) as f32;
            }
        }
    }
    out
}

/// Ranks the candidate pan angles for localising at `next_pose` against `global` (best first).
pub fn rank_targets(
    global: &Grid2<f32>,
    next_pose: &Pose2,
    params: &TargetParams,
) -> Result<Vec<TargetCandidate>, MatchError> {
    let count = params.candidates.max(1);
    let pans: Vec<f64> =
        (0..count).map(|i| wrap_angle(i as f64 * std::f64::consts::TAU / count as f64)).collect();
    rank_pans(global, next_pose, &pans, params)
}

/// Ranks the given pan angles (body frame, rad) for localising at `next_pose` against
/// `global` (best first).
pub fn rank_pans(
    global: &Grid2<f32>,
    next_pose: &Pose2,
    pans: &[f64],
    params: &TargetParams,
) -> Result<Vec<TargetCandidate>, MatchError> {
    let matcher = MlMatcher::new(global, params.params)?;
    let window = SearchWindow {
        center: *next_pose,
        half_x: params.window_xy,
        half_y: params.window_xy,
        half_yaw: params.window_yaw,
    };
    let mut out = Vec::with_capacity(pans.len());
    for (i, &pan) in pans.iter().enumerate() {
        let view = predicted_view(global, next_pose, pan, params, i as u64);
        let cells = view.data.iter().filter(|h| h.is_finite()).count();
        let candidate = match matcher.match_detailed(&view, &window, false) {
            Ok(d) => {
                let c = d.result.covariance;
                let sigma = (c[0][0] + c[1][1]).max(0.0).sqrt();
                let p = d.result.failure_probability;
                TargetCandidate {
                    pan,
                    cells,
                    position_sigma: sigma,
                    failure_probability: p,
                    // A failed match lands anywhere in the window: an error of the order of
                    // its half-diagonal. (Dividing the sigma by 1 - p instead let a featureless
                    // view with a one-in-four failure risk beat a rocky one.)
                    cost: (1.0 - p) * sigma + p * params.window_xy * std::f64::consts::SQRT_2,
                }
            }
            Err(MatchError::EmptyMap { .. }) => TargetCandidate {
                pan,
                cells,
                position_sigma: f64::INFINITY,
                failure_probability: 1.0,
                cost: f64::INFINITY,
            },
            Err(e) => return Err(e),
        };
        out.push(candidate);
    }
    out.sort_by(|a, b| a.cost.total_cmp(&b.cost));
    Ok(out)
}

/// The mast pan angle (body frame at `next_pose`) predicted to localise best.
pub fn select_target(
    global: &Grid2<f32>,
    next_pose: &Pose2,
    params: &TargetParams,
) -> Result<f64, MatchError> {
    Ok(rank_targets(global, next_pose, params)?.first().map_or(0.0, |c| c.pan))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Flat ground with faint noise everywhere, and rocks only in one sector.
    fn terrain_with_rocky_sector(sector_bearing: f64) -> Grid2<f32> {
        let geometry =
            GridGeometry { cols: 240, rows: 240, resolution: 0.05, origin_x: -6.0, origin_y: -6.0 };
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let mut g = Grid2::filled(geometry, 0.0f32);
        for h in &mut g.data {
            *h = rng.random_range(-0.003..0.003);
        }
        for _ in 0..40 {
            let bearing = sector_bearing + rng.random_range(-0.4..0.4);
            let d = rng.random_range(1.5..4.5);
            let (cx, cy) = (d * bearing.cos(), d * bearing.sin());
            let radius = rng.random_range(0.1..0.3);
            for row in 0..240 {
                for col in 0..240 {
                    let (x, y) = geometry.center(col, row);
                    let q = ((x - cx).powi(2) + (y - cy).powi(2)) / (radius * radius);
                    if q < 1.0 {
                        *g.get_mut(col, row) += (0.6 * radius * (1.0 - q).sqrt()) as f32;
                    }
                }
            }
        }
        g
    }

    #[test]
    fn picks_the_direction_of_the_distinctive_terrain() {
        // Rocks to the north; the rover will face east, so the mast should pan left (+pi/2).
        let global = terrain_with_rocky_sector(std::f64::consts::FRAC_PI_2);
        let next = Pose2::new(0.0, 0.0, 0.0);
        let ranked = rank_targets(&global, &next, &TargetParams::default()).expect("ranking");
        let best = ranked[0];
        assert!(wrap_angle(best.pan - std::f64::consts::FRAC_PI_2).abs() < 0.4, "picked {best:?}");
        // Looking at featureless ground predicts a worse (or failed) localisation.
        let south = ranked
            .iter()
            .find(|c| wrap_angle(c.pan + std::f64::consts::FRAC_PI_2).abs() < 0.1)
            .expect("south candidate");
        assert!(south.cost > best.cost);
    }

    #[test]
    fn among_rearward_pans_picks_the_one_facing_the_rocks() {
        // A rover facing +y with rocks at world bearing -3pi/4: behind it and to its left, body
        // pan 3pi/4 = pi - pi/4.
        let rover = Pose2::new(0.0, 0.0, std::f64::consts::FRAC_PI_2);
        let rocks = -3.0 * std::f64::consts::FRAC_PI_4;
        let global = terrain_with_rocky_sector(rocks);
        let pi = std::f64::consts::PI;
        let pans = [pi, pi - std::f64::consts::FRAC_PI_4, pi + std::f64::consts::FRAC_PI_4];
        let ranked = rank_pans(&global, &rover, &pans, &TargetParams::default()).expect("ranking");
        assert_eq!(ranked.len(), 3);
        let facing = wrap_angle(rocks - rover.yaw);
        assert!(
            wrap_angle(ranked[0].pan - facing).abs() < 1e-9,
            "picked {:?}, rocks at pan {facing}",
            ranked[0]
        );
        assert!(ranked[1].cost >= ranked[0].cost && ranked[2].cost >= ranked[1].cost);
    }

    #[test]
    fn predicted_view_hides_cells_behind_a_wall() {
        let geometry =
            GridGeometry { cols: 200, rows: 200, resolution: 0.05, origin_x: -5.0, origin_y: -5.0 };
        let mut g = Grid2::filled(geometry, 0.0f32);
        // A 2 m high wall 2 m ahead blocks the ground behind it from a 1.2 m mast.
        for row in 0..200 {
            for col in 140..142 {
                *g.get_mut(col, row) = 2.0;
            }
        }
        let params = TargetParams { height_noise_at_1m: 0.0, ..Default::default() };
        let view = predicted_view(&g, &Pose2::new(0.0, 0.0, 0.0), 0.0, &params, 0);
        let known = |x: f64, y: f64| view.at_world(x, y).is_some_and(|h| h.is_finite());
        assert!(known(1.5, 0.0));
        assert!(known(2.02, 0.0));
        assert!(!known(3.5, 0.0));
    }
}
