//! Reusable accuracy evaluations of the terrain matcher (paper 002 section 3.3).
//!
//! Paper 002 tested its matcher on a sequence of 12 stereo views taken one metre apart in a
//! straight line, matching consecutive views and measuring the downrange and crossrange errors
//! against positions measured by hand: mean absolute errors of 3.17 cm and 3.66 cm, with the
//! rover's orientation known from other sensors (section 3.1). [`sequence_accuracy`] runs that
//! protocol with any range sensor, so the same evaluation serves synthetic stereo here and the
//! simulator's stereo model elsewhere.
//!
//! Which of two views is distance-transformed matters. With a view 1 m further from the
//! terrain as the reference, the score rewards poses that put the other view's cells where the
//! reference's samples are dense, i.e. nearer its camera: the mast stereo sequence measured a
//! 4 cm downrange bias towards the earlier view, which vanished (within 0.1 step in every
//! range band of the likelihood profile) when the reference view was resampled densely, while
//! a dense scored view changed nothing. So the reference is the view that sampled the overlap
//! more densely: the later, nearer one ([`ReferenceView::Later`]).

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use rovernav_core::{GridGeometry, Pose2, Pose3, angle_diff};

use crate::matching::elevation::bin_points;
use crate::matching::{MatchError, MlMatcher, MlParams, SearchWindow};

/// Which view of a consecutive pair is the reference (distance-transformed, world-frame) map.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ReferenceView {
    /// The earlier view is the global map, the later one is matched against it.
    Earlier,
    /// The later view (nearer the terrain both see, so sampling it more densely) is the global
    /// map; the earlier one is matched against it and the pair's offset inverted.
    Later,
}

/// How each step of a sequence is mapped and matched.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SequenceSetup {
    /// Map cell size (m).
    pub resolution: f64,
    /// Range of the maps around the rover (m): local maps span x in [-1, range] and y in
    /// [-range, range]; global maps a square of half-side range + 1 around the view point.
    pub range: f64,
    /// Dead-reckoning position error of the prior for each step (m, one sigma).
    pub prior_sigma_xy: f64,
    /// Heading error of the prior (rad, one sigma).
    pub prior_sigma_yaw: f64,
    /// Half-width of the search window in position (m).
    pub window_xy: f64,
    /// Half-width of the search window in heading (rad); 0 takes the prior's heading as known
    /// and searches translation only, as paper 002 does.
    pub window_yaw: f64,
    /// Which view of each pair is distance-transformed.
    pub reference: ReferenceView,
    /// Matcher parameters.
    pub params: MlParams,
}

impl Default for SequenceSetup {
    fn default() -> Self {
        Self {
            resolution: 0.05,
            range: 5.0,
            prior_sigma_xy: 0.05,
            // Paper 002 takes the heading from the sun sensor and gyros and matches translation
            // only. Between two views one metre apart the gyro's relative heading error is
            // about 1 mrad (10 deg/h bias over a ~20 s drive, plus its angle random walk).
            prior_sigma_yaw: 0.001,
            window_xy: 0.25,
            window_yaw: 0.0,
            reference: ReferenceView::Later,
            params: MlParams::default(),
        }
    }
}

/// The error of one matching step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepError {
    /// Error along the direction of motion (m).
    pub downrange: f64,
    /// Error across it (m, positive left).
    pub crossrange: f64,
    /// Heading error (rad).
    pub yaw: f64,
    /// Standard deviations the matcher reported for those three (for a heading not searched,
    /// the prior's).
    pub sigma: [f64; 3],
    /// Whether the match estimated the heading (else it held the prior's).
    pub heading_estimated: bool,
    /// The matcher's failure probability.
    pub failure_probability: f64,
    /// Cells and poses the search scored.
    pub poses_evaluated: u64,
}

/// The outcome of a sequence.
#[derive(Clone, Debug, PartialEq)]
pub struct SequenceReport {
    /// One entry per consecutive pair of views.
    pub steps: Vec<StepError>,
    /// Mean absolute downrange error (m).
    pub mean_abs_downrange: f64,
    /// Mean absolute crossrange error (m).
    pub mean_abs_crossrange: f64,
    /// Fraction of the estimated quantities' errors (downrange, crossrange, and the heading
    /// when the match estimated it) within three reported sigmas.
    pub within_three_sigma: f64,
}

/// Runs the paper 002 protocol: for each consecutive pair of true poses, the reference view
/// (see [`SequenceSetup::reference`]; placed in the world with its true pose) is the global map
/// and the other (in its rover frame, levelled) is the local map; the search starts from the
/// other view's true pose perturbed by the setup's prior errors. Errors are those of the later
/// pose relative to the earlier. `sense(pose, seed)` returns the body-frame range points
/// seen from a pose. Steps run on up to `threads` threads.
pub fn sequence_accuracy<F>(
    sense: F,
    truth: &[Pose3],
    setup: &SequenceSetup,
    seed: u64,
    threads: usize,
) -> Result<SequenceReport, MatchError>
where
    F: Fn(&Pose3, u64) -> Vec<[f32; 3]> + Sync,
{
    let pairs: Vec<usize> = (0..truth.len().saturating_sub(1)).collect();
    let threads = threads.clamp(1, pairs.len().max(1));
    let chunk = pairs.len().div_ceil(threads).max(1);
    let results: Vec<Result<StepError, MatchError>> = std::thread::scope(|scope| {
        let handles: Vec<_> = pairs
            .chunks(chunk)
            .map(|steps| {
                let sense = &sense;
                scope.spawn(move || {
                    steps
                        .iter()
                        .map(|&i| match_step(sense, &truth[i], &truth[i + 1], setup, seed, i))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        handles.into_iter().flat_map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e))).collect()
    });
    let steps = results.into_iter().collect::<Result<Vec<_>, _>>()?;
    let n = steps.len().max(1) as f64;
    let (mut within, mut checked) = (0usize, 0usize);
    for step in &steps {
        let axes = if step.heading_estimated { 3 } else { 2 };
        let errors = [step.downrange, step.crossrange, step.yaw];
        within += (0..axes).filter(|&a| errors[a].abs() <= 3.0 * step.sigma[a]).count();
        checked += axes;
    }
    Ok(SequenceReport {
        mean_abs_downrange: steps.iter().map(|s| s.downrange.abs()).sum::<f64>() / n,
        mean_abs_crossrange: steps.iter().map(|s| s.crossrange.abs()).sum::<f64>() / n,
        within_three_sigma: within as f64 / checked.max(1) as f64,
        steps,
    })
}

/// Matches one view against the previous one and measures the error.
fn match_step<F>(
    sense: &F,
    previous: &Pose3,
    current: &Pose3,
    setup: &SequenceSetup,
    seed: u64,
    index: usize,
) -> Result<StepError, MatchError>
where
    F: Fn(&Pose3, u64) -> Vec<[f32; 3]>,
{
    let step_seed = seed.wrapping_mul(1_000_003).wrapping_add(index as u64 * 7919);
    // Each view keeps its own noise seed whichever role it plays.
    let (reference, matched, reference_seed, matched_seed, sign) = match setup.reference {
        ReferenceView::Earlier => (previous, current, step_seed, step_seed + 1, 1.0),
        ReferenceView::Later => (current, previous, step_seed + 1, step_seed, -1.0),
    };
    let r = setup.resolution;
    let cells = |m: f64| (m / r).round() as usize;
    let half = setup.range + 1.0;
    let global_geometry = GridGeometry {
        cols: cells(2.0 * half),
        rows: cells(2.0 * half),
        resolution: r,
        origin_x: reference.x - half,
        origin_y: reference.y - half,
    };
    let global = bin_points(&sense(reference, reference_seed), reference, global_geometry);
    let local_geometry = GridGeometry {
        cols: cells(setup.range + 1.0),
        rows: cells(2.0 * setup.range),
        resolution: r,
        origin_x: -1.0,
        origin_y: -setup.range,
    };
    let level = Pose3 { roll: matched.roll, pitch: matched.pitch, ..Default::default() };
    let local = bin_points(&sense(matched, matched_seed), &level, local_geometry);
    let mut rng = ChaCha8Rng::seed_from_u64(step_seed + 2);
    let unit = Normal::new(0.0, 1.0).expect("unit normal");
    let prior = Pose2::new(
        matched.x + setup.prior_sigma_xy * unit.sample(&mut rng),
        matched.y + setup.prior_sigma_xy * unit.sample(&mut rng),
        matched.yaw + setup.prior_sigma_yaw * unit.sample(&mut rng),
    );
    let matcher = MlMatcher::new(&global, setup.params)?;
    let window = SearchWindow {
        center: prior,
        half_x: setup.window_xy,
        half_y: setup.window_xy,
        half_yaw: setup.window_yaw,
    };
    let result = matcher.match_map(&local, &window)?;
    // Downrange is the direction of travel between the two views.
    let travel = (current.y - previous.y).atan2(current.x - previous.x);
    let (s, c) = travel.sin_cos();
    // An error in the earlier view's estimated position is the opposite error in the later
    // view's position relative to it.
    let (ex, ey) = (sign * (result.pose.x - matched.x), sign * (result.pose.y - matched.y));
    let cov = result.covariance;
    // The matcher reports a heading variance of 0 for a heading its window held fixed.
    let heading_estimated = cov[2][2] > 0.0;
    let project = |u: [f64; 2]| {
        (u[0] * u[0] * cov[0][0] + 2.0 * u[0] * u[1] * cov[0][1] + u[1] * u[1] * cov[1][1]).max(0.0).sqrt()
    };
    Ok(StepError {
        downrange: c * ex + s * ey,
        crossrange: -s * ex + c * ey,
        yaw: sign * angle_diff(result.pose.yaw, matched.yaw),
        sigma: [
            project([c, s]),
            project([-s, c]),
            if heading_estimated { cov[2][2].sqrt() } else { setup.prior_sigma_yaw },
        ],
        heading_estimated,
        failure_probability: result.failure_probability,
        poses_evaluated: result.poses_evaluated,
    })
}

/// How the branch-and-bound efficiency cases are drawn: rover-sized maps and a search window
/// from a realistic dead-reckoning uncertainty.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BnbSetup {
    /// Map cell size (m).
    pub resolution: f64,
    /// Half-side of the square global map (m).
    pub global_half: f64,
    /// Range of the local view (m).
    pub view_range: f64,
    /// Half field of view of the local view (rad): three 45 degree mast wedges side by side.
    pub view_half_angle: f64,
    /// Dead-reckoning position error (m, one sigma); the window is 3 sigma wide.
    pub prior_sigma_xy: f64,
    /// Dead-reckoning heading error (rad, one sigma); the window is 3 sigma wide.
    pub prior_sigma_yaw: f64,
    /// Local cells scored per pose (even subsample), see [`MlParams::max_local_cells`].
    pub max_local_cells: usize,
    /// Rocks per 100 m^2 of the synthetic terrain.
    pub rocks_per_100m2: f64,
}

impl Default for BnbSetup {
    fn default() -> Self {
        Self {
            resolution: 0.05,
            global_half: 10.0,
            view_range: 5.0,
            view_half_angle: 1.18,
            prior_sigma_xy: 0.33,
            prior_sigma_yaw: 0.033,
            max_local_cells: 400,
            rocks_per_100m2: 40.0,
        }
    }
}

/// Totals of branch and bound against exhaustive search over a batch of cases.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BnbReport {
    /// Cases run.
    pub cases: u64,
    /// Cases where branch and bound found the exhaustive optimum's score.
    pub exact: u64,
    /// Poses of the lattices (what exhaustive search scores).
    pub lattice_poses: u64,
    /// Evaluations branch and bound made, in poses scored: its distance-transform lookups over
    /// the local cells per pose (a pose scored counts one; a box bounded counts the fraction
    /// of the local cells it looked up, see [`crate::matching::engine::SearchOutcome`]).
    pub evaluations: u64,
    /// Boxes bounded and poses scored, whatever their cost.
    pub boxes: u64,
    /// Of those, single poses scored.
    pub poses_tested: u64,
}

impl BnbReport {
    /// Lattice poses per branch-and-bound evaluation (the speed-up in scoring work).
    pub fn evaluation_ratio(&self) -> f64 {
        self.lattice_poses as f64 / self.evaluations.max(1) as f64
    }

    /// Whether every case found the exhaustive optimum.
    pub fn all_exact(&self) -> bool {
        self.exact == self.cases
    }

    fn add(&mut self, o: &BnbReport) {
        self.cases += o.cases;
        self.exact += o.exact;
        self.lattice_poses += o.lattice_poses;
        self.evaluations += o.evaluations;
        self.boxes += o.boxes;
        self.poses_tested += o.poses_tested;
    }
}

/// One branch-and-bound case: a synthetic rocky terrain (one per five cases), a global map of
/// it, a forward local view from a random true pose, and a window around a prior drawn from
/// the dead-reckoning errors (clamped inside the window).
pub fn bnb_case(setup: &BnbSetup, case: u64) -> (MlMatcher, rovernav_core::Grid2<f32>, SearchWindow) {
    use rand::Rng;
    let mut rng = ChaCha8Rng::seed_from_u64(case);
    let r = setup.resolution;
    let field = crate::synthetic::fractal_terrain(
        &crate::synthetic::TerrainParams {
            size: 2.0 * setup.global_half + 2.0 * setup.view_range + 4.0,
            resolution: r / 2.0,
            rocks_per_100m2: setup.rocks_per_100m2,
            ..Default::default()
        },
        case / 5,
    );
    let n = (2.0 * setup.global_half / r).round() as usize;
    let half = setup.global_half;
    let global =
        field.sample(GridGeometry { cols: n, rows: n, resolution: r, origin_x: -half, origin_y: -half });
    let span = half - setup.view_range - 1.0;
    let truth = Pose2::new(
        rng.random_range(-span..span),
        rng.random_range(-span..span),
        rng.random_range(-std::f64::consts::PI..std::f64::consts::PI),
    );
    let range = setup.view_range;
    let geometry = GridGeometry {
        cols: (range / r).ceil() as usize,
        rows: (2.0 * range / r).ceil() as usize,
        resolution: r,
        origin_x: 0.0,
        origin_y: -range,
    };
    let wedge = rovernav_core::Wedge {
        bearing: 0.0,
        half_angle: setup.view_half_angle,
        min_range: 0.8,
        max_range: range,
    };
    let local =
        crate::synthetic::local_map_from_field(&field, &truth, geometry, Some(&wedge), 0.01, 0.1, case);
    let unit = Normal::new(0.0, 1.0).expect("unit normal");
    let (wx, wy) = (3.0 * setup.prior_sigma_xy, 3.0 * setup.prior_sigma_yaw);
    let error = |s: f64, w: f64, rng: &mut ChaCha8Rng| (s * unit.sample(rng)).clamp(-0.9 * w, 0.9 * w);
    let window = SearchWindow {
        center: Pose2::new(
            truth.x + error(setup.prior_sigma_xy, wx, &mut rng),
            truth.y + error(setup.prior_sigma_xy, wx, &mut rng),
            truth.yaw + error(setup.prior_sigma_yaw, wy, &mut rng),
        ),
        half_x: wx,
        half_y: wx,
        half_yaw: wy,
    };
    let params = MlParams { max_local_cells: Some(setup.max_local_cells), ..Default::default() };
    let matcher = MlMatcher::new(&global, params).expect("synthetic global map is valid");
    (matcher, local, window)
}

/// Runs cases `first..first + count` of [`bnb_case`] with branch and bound and with exhaustive
/// search (the independent reference), on up to `threads` threads.
pub fn bnb_efficiency(
    setup: &BnbSetup,
    first: u64,
    count: u64,
    threads: usize,
) -> Result<BnbReport, MatchError> {
    let threads = threads.clamp(1, count.max(1) as usize) as u64;
    let results: Vec<Result<BnbReport, MatchError>> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..threads)
            .map(|t| {
                scope.spawn(move || {
                    let mut report = BnbReport::default();
                    for case in (first..first + count).filter(|c| c % threads == t) {
                        let (matcher, local, window) = bnb_case(setup, case);
                        let (bb, lattice) = matcher.search(&local, &window, false)?;
                        let (ex, _) = matcher.search(&local, &window, true)?;
                        report.add(&BnbReport {
                            cases: 1,
                            exact: u64::from(bb.score == ex.score),
                            lattice_poses: lattice.size(),
                            evaluations: bb.evaluations,
                            boxes: bb.boxes,
                            poses_tested: bb.poses_tested,
                        });
                    }
                    Ok(report)
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e))).collect()
    });
    let mut total = BnbReport::default();
    for r in results {
        total.add(&r?);
    }
    Ok(total)
}
