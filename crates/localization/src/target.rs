//! Localisation target selection (paper 000 section 4.4).
//!
//! Before the look that will localise it, the rover predicts for each direction the mast could
//! look how well that view would localise it. As in the paper the prediction is a *probability
//! map* of the terrain expected to be seen from the pose: every cell of the map made so far that
//! the mast would see (inside the wedge, in line of sight) is expected where the map puts it,
//! blurred by the two errors that separate the coming view from the map: the map's own (the
//! range error of the points that made each cell, at the range and along the ray they were
//! mapped from) and the new view's (the range error at the range it will be seen from, along
//! the new ray). Each error splits into a vertical part and a part across the ground; each
//! cell becomes weighted points over the height layers it may be seen in (exact normal
//! probabilities per layer) times a three-point Gauss-Hermite rule across the ground, the
//! weight being the probability that the voxel is seen occupied (see [`probability_points`]).
//! The probability map is then compared with the map by the matcher's own likelihood,
//! as an expectation over those probabilities, at every pose of a search lattice around the
//! planned pose. How widely the resulting likelihood spreads around the planned pose (which is
//! the truth of the prediction) is the predicted uncertainty: a view of rocks mapped from close
//! by gives a sharp peak; featureless ground, or terrain mapped from afar, a broad one or
//! competing peaks. The direction with the smallest spread is the localisation target.

use rovernav_core::{Grid2, GridGeometry, Point2, Pose2, RangeNoise, SensorNoise, wrap_angle};

use crate::matching::elevation::{fill_gaps, high_pass, occupied_cells};
use crate::matching::{MatchError, MlMatcher, MlParams, SearchWindow};

/// The map's own error per cell (m, one sigma; NaN where unknown), on the map's geometry.
#[derive(Clone, Debug)]
pub struct MapError {
    /// Vertical part.
    pub vertical: Grid2<f32>,
    /// Part across the ground (applied along the new view's ray: the mapping ray's bearing is
    /// not kept).
    pub ground: Grid2<f32>,
}

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
    /// Range error of the mast's view.
    pub range_noise: RangeNoise,
    /// Half-size of the search window around the planned pose (m).
    pub window_xy: f64,
    /// Half-size of the heading window (rad). Zero (the default) holds the planned heading:
    /// views are ranked by position error, and every heading step multiplies the work.
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
            range_noise: SensorNoise::default().mast,
            window_xy: 0.25,
            window_yaw: 0.0,
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
    /// Predicted position uncertainty of the likelihood peak at the planned pose: sqrt of the
    /// trace of the xy covariance of a normal fitted to it (m); a flat axis counts the search
    /// window's half-width.
    pub position_sigma: f64,
    /// Predicted failure probability: the likelihood's mass more than one lattice step from
    /// the planned pose.
    pub failure_probability: f64,
    /// Combined cost (lower is better): the predicted root-mean-square position error (m), the
    /// likelihood's spread around the planned pose over the search lattice, with the fitted
    /// peak's variance below one lattice step (where the lattice cannot resolve it).
    pub cost: f64,
}

/// The terrain the mast is expected to see from a pose.
#[derive(Clone, Debug)]
pub struct PredictedView {
    /// Map heights of the visible cells, rover frame, relative to the ground under the rover
    /// (NaN elsewhere).
    pub heights: Grid2<f32>,
    /// Each visible cell's expected vertical error (m, one sigma): the map's and the view's.
    pub sigma_up: Grid2<f32>,
    /// Each visible cell's expected error across the ground, along the ray (m, one sigma).
    pub sigma_ground: Grid2<f32>,
    /// Height of the mast's eye above the ground under the rover (m).
    pub eye_height: f64,
}

/// The view expected from `pose` looking along body bearing `pan`: the known cells of `global`
/// inside the wedge whose line of sight from the mast clears the terrain. `map_error` is on
/// `global`'s geometry; without it, or where it is unknown, the map is taken to be as good as
/// the coming view.
pub fn predicted_view(
    global: &Grid2<f32>,
    map_error: Option<&MapError>,
    pose: &Pose2,
    pan: f64,
    params: &TargetParams,
) -> PredictedView {
    let r = global.resolution();
    let range = params.max_range;
    let n = (2.0 * range / r).ceil() as usize;
    let geometry = GridGeometry { cols: n, rows: n, resolution: r, origin_x: -range, origin_y: -range };
    let mut view = PredictedView {
        heights: Grid2::filled(geometry, f32::NAN),
        sigma_up: Grid2::filled(geometry, f32::NAN),
        sigma_ground: Grid2::filled(geometry, f32::NAN),
        eye_height: params.mast_height,
    };
    let height = |p: Point2| global.at_world(p.x, p.y).copied().filter(|h| h.is_finite());
    let Some(ground) = height(pose.position()) else {
        return view;
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
                let rise = f64::from(h) - eye;
                let r = d.hypot(rise);
                let sigma = params.range_noise.sigma(r);
                let (view_up, view_ground) = (sigma * rise.abs() / r, sigma * d / r);
                let map = |grid: &Grid2<f32>| {
                    grid.at_world(target.x, target.y).copied().map(f64::from).filter(|s| s.is_finite())
                };
                let map_up = map_error.and_then(|e| map(&e.vertical)).unwrap_or(view_up);
                let map_ground = map_error.and_then(|e| map(&e.ground)).unwrap_or(view_ground);
                *view.heights.get_mut(col, row) = (f64::from(h) - f64::from(ground)) as f32;
                *view.sigma_up.get_mut(col, row) = view_up.hypot(map_up) as f32;
                *view.sigma_ground.get_mut(col, row) = view_ground.hypot(map_ground) as f32;
            }
        }
    }
    view
}

/// The probability map of a predicted view as the matcher sees it: the view filtered as a
/// local map is (gap filling, high pass), subsampled to the matcher's cell budget, and each
/// cell spread over the voxels its errors may put it in, as points `[x, y, z, probability]`:
/// exactly over the height layers for the vertical error, by a three-point Gauss-Hermite rule
/// (nodes 0 and +-sqrt(3) sigma) along the ray across the ground for the other. The two are
/// taken as independent (along one ray they are one range error; the map's and the view's
/// rays differ). A node rule in height would keep the map's own layer pattern at full weight
/// and predict a sharp peak on featureless ground, whose cells straddle a layer edge.
pub fn probability_points(view: &PredictedView, target: &TargetParams) -> Vec<[f64; 4]> {
    const RULE: [(f64, f64); 3] =
        [(0.0, 2.0 / 3.0), (-1.732_050_807_568_877_2, 1.0 / 6.0), (1.732_050_807_568_877_2, 1.0 / 6.0)];
    // Layers of smaller probability are left out: they change the expectation by less than
    // the quadrature does.
    const MIN_PROBABILITY: f64 = 1e-3;
    // At most this many layers each side of a cell's own (a wildly uncertain map cell would
    // otherwise spread over thousands).
    const MAX_LAYERS: i64 = 32;
    let params = &target.params;
    let layer = view.heights.resolution() / params.vertical_exaggeration;
    let filled = fill_gaps(&view.heights, params.fill_gaps_cells);
    let filtered = match params.high_pass_window {
        Some(w) => high_pass(&filled, w),
        None => filled.clone(),
    };
    let mut cells = occupied_cells(&filtered);
    if let Some(max) = params.max_local_cells.filter(|&m| m > 0 && cells.len() > m) {
        // The same even subsample the matcher takes of a real view.
        let stride = cells.len() as f64 / max as f64;
        cells = (0..max).map(|i| cells[(i as f64 * stride) as usize]).collect();
    }
    let cdf = |v: f64| 0.5 * (1.0 + libm::erf(v * std::f64::consts::FRAC_1_SQRT_2));
    let known = |grid: &Grid2<f32>, x: f64, y: f64| {
        grid.at_world(x, y).copied().map(f64::from).filter(|s| s.is_finite())
    };
    let mut out = Vec::with_capacity(12 * cells.len());
    for [x, y, z] in cells {
        let Some(h) = known(&filled, x, y) else {
            continue;
        };
        let rise = h - view.eye_height;
        let ground = x.hypot(y);
        if ground <= 0.0 {
            continue;
        }
        // Cells the gap filling added have no sigma of their own: the view's, and a map as
        // good.
        let r = ground.hypot(rise);
        let fallback = std::f64::consts::SQRT_2 * target.range_noise.sigma(r);
        let sigma_up = known(&view.sigma_up, x, y).unwrap_or(fallback * rise.abs() / r);
        let sigma_ground = known(&view.sigma_ground, x, y).unwrap_or(fallback * ground / r);
        let own = (z / layer).floor() as i64;
        let (lo, hi) = if sigma_up > 1e-9 {
            (
                (((z - 3.0 * sigma_up) / layer).floor() as i64).max(own - MAX_LAYERS),
                (((z + 3.0 * sigma_up) / layer).floor() as i64).min(own + MAX_LAYERS),
            )
        } else {
            (own, own)
        };
        for k in lo..=hi {
            let p = if lo == hi {
                1.0
            } else {
                let (bottom, top) = (k as f64 * layer, (k + 1) as f64 * layer);
                cdf((top - z) / sigma_up) - cdf((bottom - z) / sigma_up)
            };
            if p < MIN_PROBABILITY {
                continue;
            }
            let centre = (k as f64 + 0.5) * layer;
            for (node, weight) in RULE {
                // Never through the mast to the other side.
                let shift = (node * sigma_ground / ground).clamp(-0.9, 0.9);
                out.push([x + shift * x, y + shift * y, centre, weight * p]);
            }
        }
    }
    out
}

/// Predicts how well a probability map would localise the rover at `window.center` (the
/// planned pose, the prediction's truth): its expected log-likelihood over the window's pose
/// lattice, turned into a distribution over poses at the matcher's temperature.
pub fn predict_uncertainty(
    matcher: &MlMatcher,
    points: &[[f64; 4]],
    window: &SearchWindow,
) -> Result<(f64, f64, f64), MatchError> {
    let (lattice, scores) = matcher.expected_log_likelihoods(points, window)?;
    let [hx, hy, hk] = lattice.half;
    let (nx, ny) = (2 * hx + 1, 2 * hy + 1);
    let index = |i: i32, j: i32, k: i32| (((k + hk) * ny + j + hy) * nx + i + hx) as usize;
    let t = matcher.params().temperature;
    let best = scores.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let (mut mass, mut squared, mut far) = (0.0, 0.0, 0.0);
    for k in -hk..=hk {
        for j in -hy..=hy {
            for i in -hx..=hx {
                let p = ((scores[index(i, j, k)] - best) / t).exp();
                mass += p;
                squared += p * f64::from(i * i + j * j);
                if i.abs().max(j.abs()) > 1 {
                    far += p;
                }
            }
        }
    }
    let step = lattice.step;
    let spread = squared / mass * step * step;
    // Variance of a normal fitted to the peak along each axis (log-likelihood curvature at the
    // planned pose); a flat or concave axis counts as one step^2.
    // A flat or concave axis, or one the window does not search, is as uncertain as the window.
    let fitted = |di: i32, dj: i32, half: i32, width: f64| {
        let flat = width * width;
        if half == 0 {
            return flat;
        }
        let c = 2.0 * scores[index(0, 0, 0)] - scores[index(di, dj, 0)] - scores[index(-di, -dj, 0)];
        if c > 0.0 { (t * step * step / c).min(flat) } else { flat }
    };
    let (vx, vy) = (fitted(1, 0, hx, window.half_x.max(step)), fitted(0, 1, hy, window.half_y.max(step)));
    let sigma = (vx + vy).sqrt();
    let cost = (spread + vx.min(step * step) + vy.min(step * step)).sqrt();
    Ok((sigma, far / mass, cost))
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
    rank_pans(global, None, next_pose, &pans, params)
}

/// Ranks the given pan angles (body frame, rad) for localising at `next_pose` against
/// `global` (best first); `map_error` is the map's own error (see [`predicted_view`]).
pub fn rank_pans(
    global: &Grid2<f32>,
    map_error: Option<&MapError>,
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
    for &pan in pans {
        let view = predicted_view(global, map_error, next_pose, pan, params);
        let cells = view.heights.data.iter().filter(|h| h.is_finite()).count();
        let points = probability_points(&view, params);
        let candidate = match predict_uncertainty(&matcher, &points, &window) {
            Ok((position_sigma, failure_probability, cost)) => {
                TargetCandidate { pan, cells, position_sigma, failure_probability, cost }
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
        terrain_with_rocky_sectors(&[sector_bearing])
    }

    /// Flat ground with faint noise everywhere, and rocks only in the given sectors.
    fn terrain_with_rocky_sectors(sector_bearings: &[f64]) -> Grid2<f32> {
        let geometry =
            GridGeometry { cols: 240, rows: 240, resolution: 0.05, origin_x: -6.0, origin_y: -6.0 };
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let mut g = Grid2::filled(geometry, 0.0f32);
        for h in &mut g.data {
            *h = rng.random_range(-0.003..0.003);
        }
        for _ in 0..40 * sector_bearings.len() {
            let sector_bearing = sector_bearings[rng.random_range(0..sector_bearings.len())];
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
        // The localiser's cell budget (as in its fixes).
        let params = TargetParams {
            params: MlParams { max_local_cells: Some(2000), ..Default::default() },
            ..Default::default()
        };
        let ranked = rank_targets(&global, &next, &params).expect("ranking");
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
        let ranked = rank_pans(&global, None, &rover, &pans, &TargetParams::default()).expect("ranking");
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
    fn prefers_rocks_mapped_from_close_range_to_rocks_mapped_from_afar() {
        // Rocks to the left and to the right of a rover facing east; the map of one side was
        // made from close by (1 cm range error), of the other from afar (10 cm): the view of
        // the well-mapped side must be chosen, whichever side it is.
        let global = terrain_with_rocky_sectors(&[std::f64::consts::FRAC_PI_2, -std::f64::consts::FRAC_PI_2]);
        let params = TargetParams {
            params: MlParams { max_local_cells: Some(2000), ..Default::default() },
            ..Default::default()
        };
        let next = Pose2::new(0.0, 0.0, 0.0);
        let pans = [std::f64::consts::FRAC_PI_2, -std::f64::consts::FRAC_PI_2];
        for well_mapped_left in [true, false] {
            // Range errors of the mast stereo seen from 1.5 m and from 5 m (1.2 m mast): mostly
            // across the ground.
            let mut error = MapError {
                vertical: Grid2::filled(global.geometry, 0.006f32),
                ground: Grid2::filled(global.geometry, 0.007f32),
            };
            for row in 0..global.rows() {
                for col in 0..global.cols() {
                    let (_, y) = global.geometry.center(col, row);
                    if (y > 0.0) != well_mapped_left {
                        *error.vertical.get_mut(col, row) = 0.023;
                        *error.ground.get_mut(col, row) = 0.097;
                    }
                }
            }
            let ranked = rank_pans(&global, Some(&error), &next, &pans, &params).expect("ranking");
            let expected = if well_mapped_left { pans[0] } else { pans[1] };
            assert!((ranked[0].pan - expected).abs() < 1e-9, "{ranked:?}");
            assert!(ranked[1].cost > ranked[0].cost);
        }
    }

    #[test]
    fn probability_points_carry_a_cells_errors_as_their_moments() {
        // One visible cell 3 m ahead on flat ground, 3 cm vertical and 8 cm across-ground error.
        let geometry =
            GridGeometry { cols: 200, rows: 200, resolution: 0.05, origin_x: -5.0, origin_y: -5.0 };
        let (sigma_up, sigma_ground) = (0.03, 0.08);
        let mut view = PredictedView {
            heights: Grid2::filled(geometry, f32::NAN),
            sigma_up: Grid2::filled(geometry, f32::NAN),
            sigma_ground: Grid2::filled(geometry, f32::NAN),
            eye_height: 1.2,
        };
        let (col, row) = geometry.cell_of(3.0, 0.0).expect("cell");
        let (cx, cy) = geometry.center(col, row);
        *view.heights.get_mut(col, row) = 0.0;
        *view.sigma_up.get_mut(col, row) = sigma_up as f32;
        *view.sigma_ground.get_mut(col, row) = sigma_ground as f32;
        let params = TargetParams::default();
        let points = probability_points(&view, &params);
        let total: f64 = points.iter().map(|p| p[3]).sum();
        assert!((0.99..=1.0 + 1e-9).contains(&total), "probabilities sum to {total}");
        let mean = |f: &dyn Fn(&[f64; 4]) -> f64| points.iter().map(|p| p[3] * f(p)).sum::<f64>() / total;
        // Across the ground the spread runs along the ray (radially from the mast) with the
        // cell's sigma, and nothing sideways.
        let (mx, my) = (mean(&|p| p[0]), mean(&|p| p[1]));
        assert!((mx - cx).abs() < 1e-9 && (my - cy).abs() < 1e-9, "centred: {mx} {my}");
        let (ux, uy) = (cx / cx.hypot(cy), cy / cx.hypot(cy));
        let radial = mean(&|p| ((p[0] - cx) * ux + (p[1] - cy) * uy).powi(2)).sqrt();
        assert!((radial - sigma_ground).abs() < 0.002, "radial sigma {radial}");
        assert!(mean(&|p| ((p[1] - cy) * ux - (p[0] - cx) * uy).powi(2)) < 1e-12, "nothing sideways");
        // Up and down over the layers with the cell's sigma, up to the layers' own width.
        let layer = geometry.resolution / params.params.vertical_exaggeration;
        let vertical = (mean(&|p| p[2].powi(2)) - mean(&|p| p[2]).powi(2) - layer * layer / 12.0).sqrt();
        assert!((vertical - sigma_up).abs() < 0.1 * sigma_up, "vertical sigma {vertical}");
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
        let params = TargetParams::default();
        let view = predicted_view(&g, None, &Pose2::new(0.0, 0.0, 0.0), 0.0, &params);
        let known = |x: f64, y: f64| view.heights.at_world(x, y).is_some_and(|h| h.is_finite());
        assert!(known(1.5, 0.0));
        assert!(known(2.02, 0.0));
        assert!(!known(3.5, 0.0));
    }
}
