//! `rovernav eval localization`: how well the localisation layer works (issue 5).
//!
//! Three parts:
//! - branch-and-bound efficiency and exactness of the maximum-likelihood matcher against
//!   exhaustive search on rover-sized synthetic cases
//!   ([`rovernav_localization::evaluation::bnb_efficiency`]);
//! - matching accuracy with the simulator's stereo model: paper 002's protocol, 12 views one
//!   metre apart in a straight line, each matched against the previous one
//!   ([`rovernav_localization::evaluation::sequence_accuracy`]);
//! - closed loop: a long procedural traverse driven by a navigator through the simulator with
//!   the "ekf-ml" localiser and with dead reckoning on the same seeds, reporting the final
//!   position error as a percentage of the distance driven, and, with `--orbital`, with the
//!   "orbital-map" localiser (ekf-ml plus fixes against the yard's 1 m orbital map every
//!   `--fix-interval` metres). Each localiser's covariance is checked against the truth: the
//!   final position NEES of every run, its mean against the 95 % chi-square bounds of the
//!   mean of that many runs, and the runs above the 99.9 % bound of one run (13.8); the
//!   largest NEES along each run is reported too. Unless `--no-look-back` is given,
//!   the navigator is wrapped in the look-back decorator (`NAME+look-back`,
//!   `rovernav_navigation::look_back`), as `rovernav run` does for map-matching localisers: one
//!   mast wedge looking backwards before each forward look after at least 1 m of driving.

use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use anyhow::Context;
use rovernav_core::{Localizer, NavCommand, NavInput, Pose2, Pose3, RoverConfig, SenseRequest};
use rovernav_executive::World;
use rovernav_localization::consistency::{chi_square_quantile, mean_nees_bounds, position_nees};
use rovernav_localization::evaluation::{BnbSetup, SequenceSetup, bnb_efficiency, sequence_accuracy};
use rovernav_localization::{DeadReckoning, EkfMl, EkfMlParams, OrbitalMapLocalizer, OrbitalMapParams};
use rovernav_navigation::look_back::LOOK_BACK_SUFFIX;
use rovernav_sim::{SensorModel, Simulator};
use rovernav_terrain::procedural::{ClearPad, generate};
use rovernav_terrain::{MarsYardParams, RockFieldParams, Terrain};

/// Options of `rovernav eval localization`.
#[derive(clap::Args, Debug)]
pub struct EvalLocalizationArgs {
    /// Print the figures as JSON.
    #[arg(long)]
    json: bool,
    /// Number of closed-loop seeds, from `--first-seed` on (the protocol: seeds 1..=20
    /// of a 200 m traverse, about 3 min of CPU per seed with both localisers in release).
    #[arg(long, default_value_t = 20)]
    seeds: u64,
    /// First closed-loop seed.
    #[arg(long, default_value_t = 1)]
    first_seed: u64,
    /// Closed-loop traverse length (m, straight line from start to goal).
    #[arg(long, default_value_t = 200.0)]
    length: f64,
    /// Branch-and-bound cases.
    #[arg(long, default_value_t = 100)]
    bnb_cases: u64,
    /// Yards of the stereo sequence protocol (12 views 1 m apart in each).
    #[arg(long, default_value_t = 10)]
    sequence_yards: u64,
    /// Worker threads.
    #[arg(long, default_value_t = 2)]
    threads: usize,
    /// Do not add the look-back mast wedge before each forward look (use only what the
    /// navigator senses).
    #[arg(long)]
    no_look_back: bool,
    /// Navigator of the closed loop (registry name).
    #[arg(long, default_value = "astar-grid")]
    navigator: String,
    /// Point the look-back at the localisation target the map predicts best (paper 000
    /// section 4.4; the "ekf-ml-targets" localiser) instead of straight back.
    #[arg(long)]
    localization_targets: bool,
    /// Also drive each seed with the "orbital-map" localiser.
    #[arg(long)]
    orbital: bool,
    /// Drive only the "orbital-map" localiser (with `--orbital`; `ekf-ml` and dead reckoning
    /// are skipped and report zeros).
    #[arg(long)]
    orbital_only: bool,
    /// Travel between orbital fixes of the "orbital-map" localiser (m).
    #[arg(long, default_value_t = 100.0)]
    fix_interval: f64,
}

/// One closed-loop traverse with one localiser.
#[derive(Clone, Copy, Debug, Default)]
pub struct LoopResult {
    /// Distance the true rover drove (m).
    pub distance_m: f64,
    /// Final |estimate - truth| in position (m).
    pub error_m: f64,
    /// Final position error squared over the estimate's position covariance (2 dof NEES).
    pub nees: f64,
    /// The largest position NEES along the traverse, after any frame.
    pub max_nees: f64,
    /// Distance driven when the largest NEES was reached (m).
    pub max_nees_at_m: f64,
    /// Fixes fused (ekf-ml only).
    pub fixes_used: u64,
    /// Fixes rejected (ekf-ml only).
    pub fixes_rejected: u64,
    /// Of the rejected fixes, those with a high failure probability (ekf-ml only).
    pub rejected_uncertain: u64,
    /// Of the rejected fixes, those on the search window's edge (ekf-ml only).
    pub rejected_on_edge: u64,
    /// Whether the navigator reached the goal.
    pub reached: bool,
    /// How the navigator ended the traverse (`None`: the step or time limit ran out first).
    pub outcome: Option<rovernav_core::Outcome>,
}

/// A long procedural yard with a start at its west end and a goal `length` metres east.
pub fn closed_loop_world(seed: u64, length: f64) -> World {
    rovernav_harness::long_yard_world(seed, length, 40.0, 10.0)
}

/// Drives a world with a navigator and a localiser through the simulator; returns the result
/// and the localiser (for its counters). With `look_back`, the navigator is wrapped in the
/// look-back decorator.
pub fn drive<L: Localizer>(
    world: &World,
    navigator: &str,
    localizer: L,
    seed: u64,
    look_back: bool,
) -> anyhow::Result<(LoopResult, L)> {
    drive_logged(world, navigator, localizer, seed, look_back).map(|(r, l, _)| (r, l))
}

/// [`drive`], also returning the true pose after each frame the localiser was given (the
/// initial frame first).
pub fn drive_logged<L: Localizer>(
    world: &World,
    navigator: &str,
    mut localizer: L,
    seed: u64,
    look_back: bool,
) -> anyhow::Result<(LoopResult, L, Vec<Pose3>)> {
    let name = if look_back && !navigator.ends_with(LOOK_BACK_SUFFIX) {
        format!("{navigator}{LOOK_BACK_SUFFIX}")
    } else {
        navigator.to_string()
    };
    let mut nav = rovernav_navigation::navigator_by_name(&name, &world.rover)
        .with_context(|| format!("unknown navigator `{navigator}`"))?;
    let mut sim = Simulator::new(
        world.terrain.clone(),
        world.rover.clone(),
        world.sensor_model.clone(),
        world.start,
        seed,
    );
    let mut frame = sim.initial_frame();
    localizer.update(&frame);
    let mut truths = vec![sim.truth()];
    let (mut max_nees, mut max_nees_at_m) = (0.0f64, 0.0);
    let mut reached = false;
    let mut finished = None;
    for _ in 0..20_000 {
        let input = NavInput {
            time: sim.time(),
            estimate: localizer.estimate(),
            goal: &world.goal,
            frame: &frame,
            localization_target: localizer.localization_target(),
        };
        let command = nav.step(&input);
        if let NavCommand::Finish(outcome, _) = &command {
            reached = matches!(outcome, rovernav_core::Outcome::Reached);
            finished = Some(*outcome);
            break;
        }
        frame = sim.execute(&command);
        localizer.update(&frame);
        let truth = sim.truth();
        if let Some(nees) = position_nees(&localizer.estimate(), &truth)
            && nees > max_nees
        {
            (max_nees, max_nees_at_m) = (nees, sim.distance_driven());
        }
        truths.push(truth);
        if sim.time() > 40_000.0 {
            break;
        }
    }
    let truth = sim.truth();
    let estimate = localizer.estimate();
    let (ex, ey) = (estimate.pose.x - truth.x, estimate.pose.y - truth.y);
    let nees = position_nees(&estimate, &truth).unwrap_or(f64::NAN);
    let stats = localizer.stats();
    Ok((
        LoopResult {
            distance_m: sim.distance_driven(),
            error_m: ex.hypot(ey),
            nees,
            max_nees,
            max_nees_at_m,
            reached,
            outcome: finished,
            fixes_used: stats.fixes_used,
            fixes_rejected: stats.fixes_rejected,
            rejected_uncertain: stats.rejected_uncertain,
            rejected_on_edge: stats.rejected_on_edge,
        },
        localizer,
        truths,
    ))
}

/// One seed's traverses: `ekf-ml`, dead reckoning and, when asked, `orbital-map`, with the
/// position NEES of each orbital fix tried against the truth at that frame.
#[derive(Clone, Debug, Default)]
pub struct SeedResult {
    /// The seed.
    pub seed: u64,
    /// With `ekf-ml`.
    pub ml: LoopResult,
    /// With dead reckoning.
    pub dr: LoopResult,
    /// With `orbital-map`.
    pub orbital: Option<LoopResult>,
    /// NEES of each fused orbital fix against the truth.
    pub orbital_fix_nees: Vec<f64>,
    /// Orbital fixes tried.
    pub orbital_attempts: u64,
}

/// Drives one seed's world with the `orbital-map` localiser (its orbital map: the yard without
/// rocks averaged to 1 m): the result and the NEES of each fused fix against the truth.
pub fn orbital_seed(
    seed: u64,
    length: f64,
    navigator: &str,
    look_back: bool,
    fix_interval: f64,
) -> anyhow::Result<(LoopResult, Vec<f64>, u64)> {
    let world = closed_loop_world(seed, length);
    let initial = Pose3 { x: world.start.x, y: world.start.y, yaw: world.start.yaw, ..Default::default() };
    let map = rovernav_executive::orbital_prior::orbital_map(
        &world,
        rovernav_executive::orbital_prior::ORBITAL_MAP_RESOLUTION_M,
    );
    let params = OrbitalMapParams { fix_interval_m: fix_interval, ..Default::default() };
    let localizer = OrbitalMapLocalizer::new(&world.rover, initial, &map, params);
    let (result, localizer, truths) = drive_logged(&world, navigator, localizer, seed, look_back)?;
    let nees = localizer
        .fixes()
        .iter()
        .filter(|f| f.used)
        .filter_map(|f| {
            let truth = truths.get(usize::try_from(f.at_update).ok()?.checked_sub(1)?)?;
            f.fix.position_nees(truth.x, truth.y)
        })
        .collect();
    Ok((result, nees, localizer.fixes().len() as u64))
}

/// Runs both localisers on one seed's world.
pub fn closed_loop_seed(
    seed: u64,
    length: f64,
    navigator: &str,
    look_back: bool,
    localization_targets: bool,
) -> anyhow::Result<(LoopResult, LoopResult)> {
    let world = closed_loop_world(seed, length);
    let initial = Pose3 { x: world.start.x, y: world.start.y, yaw: world.start.yaw, ..Default::default() };
    let params = EkfMlParams { select_targets: localization_targets, ..Default::default() };
    let matcher = EkfMl::with_params(&world.rover, initial, params);
    let (ml, _) = drive(&world, navigator, matcher, seed, look_back)?;
    let (dr, _) = drive(&world, navigator, DeadReckoning::new(&world.rover, initial), seed, look_back)?;
    Ok((ml, dr))
}

/// The simulator's mast stereo from a true pose: a small yard, one forward mast wedge imaged at
/// full resolution (the terrain-matching image) with the default stereo noise.
fn sim_sequence(seed: u64) -> anyhow::Result<rovernav_localization::evaluation::SequenceReport> {
    let params = MarsYardParams {
        width_m: 30.0,
        height_m: 30.0,
        resolution: 0.05,
        seed,
        rocks: RockFieldParams { abundance: 0.1, ..Default::default() },
        clear_pads: vec![ClearPad { x: 8.0, y: 15.0, radius: 1.0 }],
        ..Default::default()
    };
    let terrain: Terrain = generate(&params);
    let rover = RoverConfig::default();
    let model = SensorModel::default();
    let truth: Vec<Pose3> = (0..12)
        .map(|i| {
            let start = Pose2::new(8.0 + f64::from(i), 15.0, 0.0);
            Simulator::new(terrain.clone(), rover.clone(), model.clone(), start, seed).truth()
        })
        .collect();
    let sense = |pose: &Pose3, s: u64| {
        let mut sim = Simulator::new(terrain.clone(), rover.clone(), model.clone(), pose.pose2(), s);
        let frame = sim.execute(&NavCommand::Sense(vec![SenseRequest::MastFine { pan: 0.0 }]));
        frame.clouds.into_iter().flat_map(|c| c.points).collect::<Vec<_>>()
    };
    Ok(sequence_accuracy(sense, &truth, &SequenceSetup::default(), seed, 2)?)
}

/// Runs the evaluation and prints its figures.
pub fn run(args: EvalLocalizationArgs) -> anyhow::Result<()> {
    let started = Instant::now();
    let bnb = bnb_efficiency(&BnbSetup::default(), 0, args.bnb_cases, args.threads)?;
    let bnb_s = started.elapsed().as_secs_f64();

    let t = Instant::now();
    let mut downrange = 0.0;
    let mut crossrange = 0.0;
    let mut within = 0.0;
    let sequences = args.sequence_yards;
    for seed in 1..=sequences {
        let r = sim_sequence(seed)?;
        downrange += r.mean_abs_downrange / sequences as f64;
        crossrange += r.mean_abs_crossrange / sequences as f64;
        within += r.within_three_sigma / sequences as f64;
    }
    let sequence_s = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let next = AtomicU64::new(args.first_seed);
    let results: Mutex<Vec<SeedResult>> = Mutex::new(Vec::new());
    let failure: Mutex<Option<anyhow::Error>> = Mutex::new(None);
    let look_back = !args.no_look_back;
    std::thread::scope(|s| {
        for _ in 0..args.threads.max(1) {
            s.spawn(|| {
                loop {
                    let seed = next.fetch_add(1, Ordering::SeqCst);
                    if seed >= args.first_seed.saturating_add(args.seeds) {
                        break;
                    }
                    let one = || -> anyhow::Result<SeedResult> {
                        let (ml, dr) = if args.orbital_only {
                            Default::default()
                        } else {
                            closed_loop_seed(
                                seed,
                                args.length,
                                &args.navigator,
                                look_back,
                                args.localization_targets,
                            )?
                        };
                        let mut r = SeedResult { seed, ml, dr, ..Default::default() };
                        if args.orbital {
                            let (o, fix_nees, attempts) = orbital_seed(
                                seed,
                                args.length,
                                &args.navigator,
                                look_back,
                                args.fix_interval,
                            )?;
                            (r.orbital, r.orbital_fix_nees, r.orbital_attempts) =
                                (Some(o), fix_nees, attempts);
                        }
                        Ok(r)
                    };
                    match one() {
                        Ok(r) => results.lock().expect("results").push(r),
                        Err(e) => *failure.lock().expect("failure") = Some(e),
                    }
                }
            });
        }
    });
    if let Some(e) = failure.into_inner().expect("failure") {
        return Err(e);
    }
    let mut results = results.into_inner().expect("results");
    results.sort_by_key(|r| r.seed);
    let loop_s = t.elapsed().as_secs_f64();
    // An empty float sum is -0.0; adding 0.0 prints figures of no runs as 0.
    let pct = |f: &dyn Fn(&SeedResult) -> &LoopResult| {
        let n = results.len().max(1) as f64;
        results.iter().map(|r| 100.0 * f(r).error_m / f(r).distance_m.max(1e-9)).sum::<f64>() / n + 0.0
    };
    let ml_pct = pct(&|r| &r.ml);
    let dr_pct = pct(&|r| &r.dr);
    let n = results.len().max(1) as f64;
    let nees = results.iter().map(|r| r.ml.nees).filter(|v| v.is_finite()).sum::<f64>() / n + 0.0;
    let within_3sigma = results.iter().filter(|r| r.ml.nees <= 11.8).count() as f64 / n;
    let fixes_used: u64 = results.iter().map(|r| r.ml.fixes_used).sum();
    let fixes_rejected: u64 = results.iter().map(|r| r.ml.fixes_rejected).sum();
    let distance = results.iter().map(|r| r.ml.distance_m).sum::<f64>() / n + 0.0;
    let reached = results.iter().filter(|r| r.ml.reached).count();
    let orbital: Vec<&LoopResult> = results.iter().filter_map(|r| r.orbital.as_ref()).collect();
    let orbital_pct = if orbital.is_empty() {
        f64::NAN
    } else {
        orbital.iter().map(|o| 100.0 * o.error_m / o.distance_m.max(1e-9)).sum::<f64>() / orbital.len() as f64
    };
    let fix_nees: Vec<f64> = results.iter().flat_map(|r| r.orbital_fix_nees.iter().copied()).collect();
    let mut consistency = serde_json::Map::new();
    let mut lines = Vec::new();
    let mut check = |name: &str, runs: Vec<f64>| {
        let (json, line) = nees_summary(&runs);
        consistency.insert(name.to_string(), json);
        lines.push(format!("{name}: {line}"));
    };
    check("ekf-ml", results.iter().map(|r| r.ml.nees).collect());
    check("dead-reckoning", results.iter().map(|r| r.dr.nees).collect());
    if !orbital.is_empty() {
        check("orbital-map", orbital.iter().map(|o| o.nees).collect());
        check("orbital-fixes", fix_nees.clone());
    }
    let runs: Vec<serde_json::Value> = results
        .iter()
        .map(|r| {
            let (ml, dr) = (&r.ml, &r.dr);
            let mut run = serde_json::json!({
                "seed": r.seed,
                "distance_m": ml.distance_m,
                "reached": ml.reached,
                "outcome": ml.outcome.map_or("limit", |o| o.as_str()),
                "err_pct": 100.0 * ml.error_m / ml.distance_m.max(1e-9),
                "dead_reckoning_err_pct": 100.0 * dr.error_m / dr.distance_m.max(1e-9),
                "nees": ml.nees,
                "max_nees": ml.max_nees,
                "max_nees_at_m": ml.max_nees_at_m,
                "dead_reckoning_nees": dr.nees,
                "fixes_used": ml.fixes_used,
                "fixes_rejected": ml.fixes_rejected,
            });
            if let Some(o) = &r.orbital {
                run["orbital_map"] = serde_json::json!({
                    "distance_m": o.distance_m,
                    "reached": o.reached,
                    "err_pct": 100.0 * o.error_m / o.distance_m.max(1e-9),
                    "nees": o.nees,
                    "max_nees": o.max_nees,
                    "orbital_fixes_tried": r.orbital_attempts,
                    "orbital_fix_nees": r.orbital_fix_nees,
                    "fixes_used": o.fixes_used,
                });
            }
            run
        })
        .collect();
    let localizer = if args.localization_targets { "ekf-ml-targets" } else { "ekf-ml" };

    let figures = serde_json::json!({
        "bnb_cases": bnb.cases,
        "bnb_exact": bnb.all_exact(),
        "bnb_exact_cases": bnb.exact,
        "bnb_eval_ratio": bnb.evaluation_ratio(),
        "bnb_pose_ratio": bnb.lattice_poses as f64 / bnb.poses_tested.max(1) as f64,
        "bnb_lattice_poses": bnb.lattice_poses,
        "bnb_evaluations": bnb.evaluations,
        "bnb_boxes_bounded": bnb.boxes,
        "bnb_poses_tested": bnb.poses_tested,
        "mean_abs_err_downrange_m": downrange,
        "mean_abs_err_crossrange_m": crossrange,
        "sequence_within_three_sigma": within,
        "sequence_yards": sequences,
        "closed_loop_seeds": results.len(),
        "closed_loop_reached": reached,
        "closed_loop_mean_distance_m": distance,
        "closed_loop_err_pct": ml_pct,
        "dead_reckoning_err_pct": dr_pct,
        "covariance_consistency": nees,
        "closed_loop_within_3_sigma": within_3sigma,
        "fixes_used": fixes_used,
        "fixes_rejected": fixes_rejected,
        "closed_loop_localizer": localizer,
        "closed_loop_runs": runs,
        "orbital_map_err_pct": if orbital.is_empty() { serde_json::Value::Null } else { orbital_pct.into() },
        "nees_consistency": consistency,
        "wall_time_s": { "bnb": bnb_s, "sequence": sequence_s, "closed_loop": loop_s },
    });
    if args.json {
        println!("{}", serde_json::to_string_pretty(&figures)?);
    } else {
        println!(
            "branch and bound: {}/{} cases exact; {:.1}x fewer evaluations (distance-transform lookups in \
             poses, {} boxes bounded) and {:.1}x fewer single poses than exhaustive search ({} lattice poses) \
             [{bnb_s:.1} s]",
            bnb.exact,
            bnb.cases,
            bnb.evaluation_ratio(),
            bnb.boxes,
            bnb.lattice_poses as f64 / bnb.poses_tested.max(1) as f64,
            bnb.lattice_poses
        );
        println!(
            "sim stereo sequence (12 views 1 m apart, {sequences} yards): mean |error| downrange {:.1} cm, \
             crossrange {:.1} cm; {:.0}% within 3 sigma [{sequence_s:.1} s]",
            100.0 * downrange,
            100.0 * crossrange,
            100.0 * within
        );
        println!(
            "closed loop ({} seeds, {:.0} m yard, {}, {reached} reached, {distance:.0} m driven on average): \
             {localizer} {ml_pct:.2}% of distance, dead reckoning {dr_pct:.2}%; fixes used {fixes_used}, rejected \
             {fixes_rejected}; mean final NEES {nees:.2} (2 expected) [{loop_s:.1} s]",
            results.len(),
            args.length,
            args.navigator
        );
        println!("final position NEES against chi-square bounds (per localiser):");
        for line in &lines {
            println!("  {line}");
        }
        if !orbital.is_empty() {
            println!("orbital-map: {orbital_pct:.2}% of distance (fix every {} m)", args.fix_interval);
        }
        for SeedResult { seed, ml, dr, .. } in &results {
            println!(
                "  seed {seed}: driven {:.1} m, ekf-ml {:.3} m ({} fixes, {} rejected: {} uncertain, {} on the \
                 window edge), dead reckoning {:.3} m",
                ml.distance_m,
                ml.error_m,
                ml.fixes_used,
                ml.fixes_rejected,
                ml.rejected_uncertain,
                ml.rejected_on_edge,
                dr.error_m
            );
        }
    }
    Ok(())
}

/// The consistency summary of one localiser's NEES values (one per run or fix): the mean
/// against the 95 % chi-square bounds of the mean of that many, the count above the 99.9 %
/// bound of one, and the largest; as JSON and as one line.
fn nees_summary(values: &[f64]) -> (serde_json::Value, String) {
    let finite: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    let n = finite.len();
    let mean = finite.iter().sum::<f64>() / n.max(1) as f64 + 0.0;
    let (lo, hi) = mean_nees_bounds(n, 2, 0.95);
    let limit = chi_square_quantile(0.999, 2.0);
    let above = finite.iter().filter(|&&v| v > limit).count();
    let max = finite.iter().copied().fold(0.0, f64::max);
    let within = n > 0 && (lo..=hi).contains(&mean) && above == 0;
    let json = serde_json::json!({
        "n": n,
        "mean_nees": mean,
        "bounds_95": [lo, hi],
        "above_99_9": above,
        "limit_99_9": limit,
        "max_nees": max,
        "consistent": within,
    });
    let line = format!(
        "mean NEES {mean:.2} over {n} (95 % bounds {lo:.2}-{hi:.2}), {above} above {limit:.1}, largest {max:.2}: {}",
        if within { "consistent" } else { "NOT consistent" }
    );
    (json, line)
}
