//! `rovernav eval vtt`: approaches to a designated rock with visual target tracking and without
//! (paper 003 section 3; issue 35 item 4).
//!
//! Each trial is one generated Mars yard (the default mission's terrain at a seed). The
//! evaluation, acting as the operator, picks a rock of a suitable size with a clear corridor
//! `--distance` metres away, places the rover facing it, points the Navcam head at it and
//! designates the rock's pixel on the rendered first image (the projection of a point 60 % up
//! its side). Then, on the same yard and from the same start:
//! - with VTT ([`rovernav_vision::tracking::Approach`]): image, track, re-range, move at most
//!   10 % of the remaining distance, until the tracked residual to the stand-off is below 1 cm;
//! - without (the baseline): the target ranged once by point stereo on the designation image,
//!   then the same moves computed from the pose estimate alone.
//!
//! The autonomy sees only the rendered images and the dead-reckoning pose estimate; the truth
//! (the surface point under the designated pixel, the rover's final position) scores the trial:
//! the error is the horizontal distance from the rover's final position to the commanded
//! stand-off point, the point `standoff` short of the true target on the line from the true
//! start to it. Every `--occlude-every`-th trial a 0.8 m rock is put into the line of sight after
//! the fourth move (the images from then on are rendered with it): the tracker must report the
//! loss rather than lock onto the occluder. Motion is blind (turn in place, drive straight, no
//! proximity guard) along a corridor chosen clear of rocks taller than 10 cm, on 40 m yards with
//! rock abundance 0.05 (the default mission's 0.16 leaves no clear 10 m corridor).

use nalgebra::{Point2, Point3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use rovernav_core::{CameraImage, DriveGuard, NavCommand, Pose2, Pose3, SenseRequest, SensorFrame};
use rovernav_executive::{Mission, World};
use rovernav_harness::build_world;
use rovernav_sim::{HeightField, Simulator, navcam};
use rovernav_terrain::Rock;
use rovernav_vision::camera::CameraModel;
use rovernav_vision::image::GreyF32;
use rovernav_vision::rig::Rig;
use rovernav_vision::tracking::approach::grey_f32;
use rovernav_vision::tracking::{Approach, ApproachParams, Decision, Designation, NavcamPair};
use serde::Serialize;

/// Rock abundance of the evaluation's yards (the default mission's is 0.16).
const YARD_ROCK_ABUNDANCE: f64 = 0.05;
/// Rocks up to this height may lie in the approach corridor (m).
const CLEAR_HEIGHT_M: f64 = 0.1;

/// Options of `rovernav eval vtt`.
#[derive(clap::Args, Debug)]
pub struct EvalVttArgs {
    /// Trials (yards).
    #[arg(long, default_value_t = 10)]
    pub trials: usize,
    /// Start distance to the target (m).
    #[arg(long, default_value_t = 10.0)]
    pub distance: f64,
    /// Yard seed of the first trial (each later trial takes the next seed with a usable rock).
    #[arg(long, default_value_t = 1000)]
    pub first_seed: u64,
    /// Stand-off distance (m, rover origin to target, horizontal).
    #[arg(long, default_value_t = 1.0)]
    pub standoff: f64,
    /// Navcam image size (pixels).
    #[arg(long, default_value_t = 512)]
    pub width: usize,
    /// Occlude the target in every N-th trial (0: never).
    #[arg(long, default_value_t = 4)]
    pub occlude_every: usize,
    /// Print the figures as JSON.
    #[arg(long)]
    pub json: bool,
}

/// One trial's outcome.
#[derive(Clone, Debug, Serialize)]
pub struct TrialResult {
    /// Yard seed.
    pub seed: u64,
    /// True horizontal start distance to the target (m).
    pub start_distance_m: f64,
    /// Target rock diameter (m).
    pub rock_diameter_m: f64,
    /// Whether the trial was to be occluded (after the fourth move).
    pub occlusion_trial: bool,
    /// Whether the occluder was in view when the approach ended (the approach got that far).
    pub occluded: bool,
    /// With VTT: how it ended (`arrived`, or the error).
    pub vtt_end: String,
    /// With VTT: error to the stand-off point (m).
    pub vtt_error_m: f64,
    /// With VTT: true horizontal distance to the target minus the stand-off (m).
    pub vtt_radial_error_m: f64,
    /// With VTT, on arrival: distance from the designated surface point to the one under the
    /// final tracked pixel (m; the tracker's drift on the target).
    pub vtt_point_drift_m: f64,
    /// With VTT: images tracked (after the designation).
    pub images_tracked: usize,
    /// With VTT: the run ended at the wrong target.
    pub wrong_target: bool,
    /// Without VTT: error to the stand-off point (m).
    pub baseline_error_m: f64,
}

/// The figures of `rovernav eval vtt`.
#[derive(Clone, Debug, Serialize)]
pub struct VttEvaluation {
    /// Trials run.
    pub trials: usize,
    /// Start distance (m).
    pub distance_m: f64,
    /// Stand-off (m).
    pub standoff_m: f64,
    /// Median error to the stand-off point with VTT, unoccluded trials (m).
    pub median_error_m: f64,
    /// 95th percentile of the same (m).
    pub p95_error_m: f64,
    /// Median error without VTT (the pose estimate alone), same unoccluded trials (m).
    pub baseline_median_error_m: f64,
    /// 95th percentile of the same (m).
    pub baseline_p95_error_m: f64,
    /// Trials whose target was hidden by an occluder (the approach reached the fourth move).
    pub losses_induced: usize,
    /// Of those, the ones where the rover stopped with a reported loss (the tracker's, or point
    /// stereo's "no range") instead of arriving.
    pub losses_detected: usize,
    /// Approaches that ended at another rock or point than the target.
    pub wrong_target: usize,
    /// Losses reported in trials without an occluder.
    pub unplanned_losses: usize,
    /// Images tracked in all trials.
    pub images_tracked: usize,
    /// Yard seeds skipped (no rock with a clear corridor at the distance).
    pub seeds_skipped: usize,
    /// Every trial.
    pub per_trial: Vec<TrialResult>,
}

/// Runs the evaluation and prints the figures.
pub fn run(args: EvalVttArgs) -> anyhow::Result<()> {
    crate::output::print_evaluation(args.json, &evaluate(&args)?, print_table)
}

/// The trial set-up chosen on a yard.
#[derive(Clone, Debug)]
struct Setup {
    world: World,
    start: Pose2,
    rock: Rock,
    /// The point the operator designates (60 % up the rock's side facing the rover).
    aim: Point3<f64>,
}

/// Runs the trials (yards in parallel) and pools them.
pub fn evaluate(args: &EvalVttArgs) -> anyhow::Result<VttEvaluation> {
    anyhow::ensure!(args.trials > 0, "--trials must be at least 1");
    anyhow::ensure!(
        args.distance.is_finite() && args.distance > args.standoff + 1.0,
        "--distance {} must exceed the stand-off by more than 1 m",
        args.distance
    );
    anyhow::ensure!((64..=2048).contains(&args.width), "--width {} must be 64..2048", args.width);
    let params = ApproachParams { standoff_m: args.standoff, ..ApproachParams::default() };
    params.validate().map_err(|e| anyhow::anyhow!("--standoff: {e}"))?;
    // Pick the yards first (cheap), then run them in parallel.
    let mut setups = Vec::new();
    let mut skipped = 0;
    let mut seed = args.first_seed;
    while setups.len() < args.trials {
        anyhow::ensure!(skipped <= 10 * args.trials + 20, "too many yards without a usable rock");
        match choose_setup(seed, args.distance, args.standoff)? {
            Some(s) => setups.push((seed, s)),
            None => skipped += 1,
        }
        seed += 1;
    }
    let results: Vec<anyhow::Result<TrialResult>> = setups
        .par_iter()
        .enumerate()
        .map(|(i, (seed, setup))| {
            let occlude = args.occlude_every > 0 && (i + 1) % args.occlude_every == 0;
            trial(*seed, setup, &params, args.width, occlude)
        })
        .collect();
    let per_trial = results.into_iter().collect::<anyhow::Result<Vec<_>>>()?;
    Ok(summarise(args, per_trial, skipped))
}

fn summarise(args: &EvalVttArgs, per_trial: Vec<TrialResult>, skipped: usize) -> VttEvaluation {
    let clear: Vec<&TrialResult> = per_trial.iter().filter(|t| !t.occlusion_trial).collect();
    let mut vtt: Vec<f64> = clear.iter().map(|t| t.vtt_error_m).collect();
    let mut base: Vec<f64> = clear.iter().map(|t| t.baseline_error_m).collect();
    let induced: Vec<&TrialResult> = per_trial.iter().filter(|t| t.occluded).collect();
    VttEvaluation {
        trials: per_trial.len(),
        distance_m: args.distance,
        standoff_m: args.standoff,
        median_error_m: percentile(&mut vtt, 0.5),
        p95_error_m: percentile(&mut vtt, 0.95),
        baseline_median_error_m: percentile(&mut base, 0.5),
        baseline_p95_error_m: percentile(&mut base, 0.95),
        losses_induced: induced.len(),
        losses_detected: induced.iter().filter(|t| t.vtt_end != "arrived").count(),
        wrong_target: per_trial.iter().filter(|t| t.wrong_target).count(),
        unplanned_losses: clear.iter().filter(|t| t.vtt_end != "arrived").count(),
        images_tracked: per_trial.iter().map(|t| t.images_tracked).sum(),
        seeds_skipped: skipped,
        per_trial,
    }
}

/// The nearest-rank percentile `q` of a list (NaN for an empty one).
fn percentile(values: &mut [f64], q: f64) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    values.sort_by(f64::total_cmp);
    let rank = ((q * values.len() as f64).ceil() as usize).clamp(1, values.len());
    values[rank - 1]
}

/// A rock 0.25-0.8 m across and 0.12-0.5 m tall about `distance` away, with a start point
/// inside the yard whose corridor to the stand-off is clear of rocks taller than 8 cm and
/// from which the designated point is in sight; `None` when the yard has none.
fn choose_setup(seed: u64, distance: f64, standoff: f64) -> anyhow::Result<Option<Setup>> {
    let mut mission = Mission::default_mission();
    mission.seed = seed;
    // A 40 m yard with a sparser rock field than the default, so that clear 10-20 m corridors
    // exist on most seeds.
    if let rovernav_executive::mission::TerrainSpec::Procedural { size_m, rock_abundance, .. } =
        &mut mission.terrain
    {
        *size_m = 40.0;
        *rock_abundance = YARD_ROCK_ABUNDANCE;
    }
    let world = build_world(&mission, "built-in default mission, 40 m yard")?;
    let g = world.terrain.dem.geometry();
    let (x0, y0) = (g.origin_x + 1.5, g.origin_y + 1.5);
    let (x1, y1) =
        (g.origin_x + g.cols as f64 * g.resolution - 1.5, g.origin_y + g.rows as f64 * g.resolution - 1.5);
    let field = HeightField::new(&world.terrain.dem);
    let rig = Rig::new(&world.rover);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let turn0: f64 = rng.random_range(0.0..std::f64::consts::TAU);
    let rocks = world.terrain.rocks.clone();
    for rock in rocks.iter().filter(|r| (0.25..=0.8).contains(&r.diameter)) {
        if !(0.12..=0.5).contains(&rock.height) {
            continue;
        }
        for k in 0..24 {
            let theta = turn0 + f64::from(k) * std::f64::consts::TAU / 24.0;
            let (sx, sy) = (rock.x - distance * theta.cos(), rock.y - distance * theta.sin());
            if !(x0..=x1).contains(&sx) || !(y0..=y1).contains(&sy) {
                continue;
            }
            let (ux, uy) = (theta.cos(), theta.sin());
            let corridor_end = distance - standoff;
            let blocked = rocks.iter().any(|o| {
                if o == rock || o.height <= CLEAR_HEIGHT_M {
                    return false;
                }
                let (dx, dy) = (o.x - sx, o.y - sy);
                let along = dx * ux + dy * uy;
                let across = (dx * uy - dy * ux).abs();
                along > -1.0
                    && along < corridor_end + 0.5
                    && across < 0.5 * world.rover.width + 0.3 + 0.5 * o.diameter
            });
            if blocked {
                continue;
            }
            let start = Pose2::new(sx, sy, theta);
            let truth = rovernav_sim::vehicle::settled_pose(&world.terrain.dem, &world.rover, start);
            // The designated point: on the rock's side facing the rover, 60 % of its height up.
            let ground = world.terrain.dem.height(rock.x, rock.y).unwrap_or(0.0) - rock.height;
            let aim = Point3::new(
                rock.x - 0.3 * rock.diameter * ux,
                rock.y - 0.3 * rock.diameter * uy,
                ground + 0.6 * rock.height,
            );
            let Some(hit) = designated_surface(&rig, &world, &field, &truth, &aim) else { continue };
            if (Point2::new(hit.x, hit.y) - Point2::new(rock.x, rock.y)).norm() > 0.6 * rock.diameter {
                continue;
            }
            let rock = *rock;
            return Ok(Some(Setup { world, start, rock, aim }));
        }
    }
    Ok(None)
}

/// Head pan and tilt (rad) that look from the true pose at `p`.
fn pointing(rig: &Rig, truth: &Pose3, p: &Point3<f64>) -> (f64, f64) {
    let head = rovernav_vision::rig::pose_isometry(truth) * Point3::new(0.0, 0.0, rig.mast_height);
    let d = p - head;
    (rovernav_core::angle_diff(d.y.atan2(d.x), truth.yaw), d.z.atan2(d.x.hypot(d.y)))
}

/// The true surface point seen at the designated pixel (the projection of `aim` in the true
/// left Navcam pointed at it), or `None` if the ray meets nothing.
fn designated_surface(
    rig: &Rig,
    world: &World,
    field: &HeightField,
    truth: &Pose3,
    aim: &Point3<f64>,
) -> Option<Point3<f64>> {
    let (pan, tilt) = pointing(rig, truth, aim);
    let left = rig.camera("navcam_left", pan, tilt)?.in_world(truth, truth);
    let px = left.project(aim)?;
    let ray = left.unproject(&px);
    let c = ray.origin;
    let d = ray.direction;
    let hit = field.cast(&world.terrain.dem, [c.x, c.y, c.z], [d.x, d.y, d.z], 100.0)?;
    Some(Point3::from(hit.point))
}

/// The left and right Navcam images of a frame.
fn pair_of(images: &[CameraImage]) -> Option<(GreyF32, GreyF32, f64, f64)> {
    let get = |name: &str| images.iter().find(|i| i.camera == name);
    let (l, r) = (get("navcam_left")?, get("navcam_right")?);
    Some((grey_f32(l.width, l.height, &l.pixels)?, grey_f32(r.width, r.height, &r.pixels)?, l.pan, l.tilt))
}

/// One approach's end: the rover's true final pose, how it ended, images tracked.
struct RunEnd {
    truth: Pose3,
    end: String,
    tracked: usize,
    /// The occluder was in the world for the last image.
    occluded: bool,
    /// How far the surface point under the final tracked pixel is from the designated one (m).
    drift_m: f64,
}

/// Runs both approaches on one yard and scores them.
fn trial(
    seed: u64,
    setup: &Setup,
    params: &ApproachParams,
    width: usize,
    occlude: bool,
) -> anyhow::Result<TrialResult> {
    let field = HeightField::new(&setup.world.terrain.dem);
    let rig = Rig::new(&setup.world.rover).with_size(width);
    let start_truth =
        rovernav_sim::vehicle::settled_pose(&setup.world.terrain.dem, &setup.world.rover, setup.start);
    let target = designated_surface(&rig, &setup.world, &field, &start_truth, &setup.aim)
        .ok_or_else(|| anyhow::anyhow!("seed {seed}: the designated point left the view"))?;
    let vtt = approach(seed, setup, params, width, true, occlude)?;
    let base = approach(seed, setup, params, width, false, false)?;
    let t = Point2::new(target.x, target.y);
    let s = Point2::new(start_truth.x, start_truth.y);
    let standoff_point = t - (t - s).normalize() * params.standoff_m;
    let error = |p: &Pose3| (Point2::new(p.x, p.y) - standoff_point).norm();
    let to_target = (Point2::new(vtt.truth.x, vtt.truth.y) - t).norm();
    Ok(TrialResult {
        seed,
        start_distance_m: (t - s).norm(),
        rock_diameter_m: setup.rock.diameter,
        occlusion_trial: occlude,
        occluded: vtt.occluded,
        vtt_radial_error_m: to_target - params.standoff_m,
        vtt_point_drift_m: vtt.drift_m,
        wrong_target: vtt.end == "arrived" && (to_target - params.standoff_m).abs() > 0.25,
        vtt_error_m: error(&vtt.truth),
        vtt_end: vtt.end,
        images_tracked: vtt.tracked,
        baseline_error_m: error(&base.truth),
    })
}

/// One approach on the yard: with VTT (`track`) or from the designation alone.
fn approach(
    seed: u64,
    setup: &Setup,
    params: &ApproachParams,
    width: usize,
    track: bool,
    occlude: bool,
) -> anyhow::Result<RunEnd> {
    let world = &setup.world;
    let mut model = world.sensor_model.clone();
    model.navcam.width = width;
    let mut sim =
        Simulator::new(world.terrain.clone(), world.rover.clone(), model.clone(), setup.start, seed);
    let initial = sim.truth();
    let mut localizer = rovernav_localization::localizer_by_name("dead-reckoning", &world.rover, initial)
        .ok_or_else(|| anyhow::anyhow!("no dead-reckoning localizer"))?;
    localizer.update(&sim.initial_frame());
    let rig = Rig::new(&world.rover).with_size(width);
    // The operator points the head at the rock and designates it on the first image.
    let (pan, tilt) = pointing(&rig, &sim.truth(), &setup.aim);
    let left_true = rig
        .camera("navcam_left", pan, tilt)
        .ok_or_else(|| anyhow::anyhow!("no navcam"))?
        .in_world(&sim.truth(), &sim.truth());
    let px = left_true.project(&setup.aim).ok_or_else(|| anyhow::anyhow!("seed {seed}: rock behind"))?;
    let designation = Designation::Pixel { row: px.y, col: px.x };
    let mut vtt = Approach::new(&world.rover, width, designation, *params)?;
    let mut occluded: Option<(rovernav_terrain::Terrain, HeightField)> = None;
    let mut image_seed = ChaCha8Rng::seed_from_u64(seed ^ 0x5eed);
    let mut take = |sim: &mut Simulator,
                    loc: &mut Box<dyn rovernav_core::Localizer>,
                    occ: &Option<(rovernav_terrain::Terrain, HeightField)>,
                    pan: f64,
                    tilt: f64|
     -> anyhow::Result<(GreyF32, GreyF32, f64, f64)> {
        let frame = sim.execute(&NavCommand::Sense(vec![SenseRequest::Navcam { pan, tilt }]));
        loc.update(&frame);
        let images = match occ {
            // The world with the occluder: the same picture rendered with it.
            Some((terrain, field)) => navcam::capture_pair(
                terrain,
                field,
                &world.rover,
                &sim.truth(),
                &model.stereo,
                &model.navcam,
                navcam::Pair::Navcam { pan, tilt },
                sim.time(),
                image_seed.random(),
            )
            .to_vec(),
            None => frame.images,
        };
        pair_of(&images).ok_or_else(|| anyhow::anyhow!("seed {seed}: the Navcam pair is missing"))
    };
    let (l, r, p, t) = take(&mut sim, &mut localizer, &occluded, pan, tilt)?;
    let pair = NavcamPair { left: &l, right: &r, pan: p, tilt: t };
    if let Err(e) = vtt.observe(&pair, &localizer.estimate().pose) {
        return Ok(RunEnd {
            truth: sim.truth(),
            end: format!("designation: {e}"),
            tracked: 0,
            occluded: false,
            drift_m: f64::NAN,
        });
    }
    let mut tracked = 0;
    let mut last_pointing = Some((p, t));
    let base_field = HeightField::new(&world.terrain.dem);
    let designated =
        designated_surface(&rig, world, &base_field, &sim.truth(), &setup.aim).unwrap_or(setup.aim);
    loop {
        let estimate = localizer.estimate().pose;
        // An approach that stops before arriving: where the rover is and why.
        let stopped = |sim: &Simulator, why: String, tracked, occluded: bool| RunEnd {
            truth: sim.truth(),
            end: why,
            tracked,
            occluded,
            drift_m: f64::NAN,
        };
        let decision = match vtt.decide(&estimate) {
            Ok(d) => d,
            Err(e) => return Ok(stopped(&sim, e.to_string(), tracked, occluded.is_some())),
        };
        let Decision::Move { turn_rad, distance_m, .. } = decision else {
            let drift = vtt.target().zip(last_pointing).and_then(|(t, (pan, tilt))| {
                let cam = rig.camera("navcam_left", pan, tilt)?.in_world(&sim.truth(), &sim.truth());
                let ray = cam.unproject(&t.pixel);
                let (c, d) = (ray.origin, ray.direction);
                let field = occluded.as_ref().map_or(&base_field, |o| &o.1);
                let hit = field.cast(&world.terrain.dem, [c.x, c.y, c.z], [d.x, d.y, d.z], 100.0)?;
                Some((Point3::from(hit.point) - designated).norm())
            });
            return Ok(RunEnd {
                drift_m: drift.unwrap_or(f64::NAN),
                truth: sim.truth(),
                end: "arrived".into(),
                tracked,
                occluded: occluded.is_some(),
            });
        };
        execute(&mut sim, &mut localizer, turn_rad, distance_m);
        if occlude && occluded.is_none() && vtt.moves() == 4 {
            occluded = Some(occluder(world, &sim.truth(), vtt.target().map(|t| t.site)));
        }
        if !track {
            continue;
        }
        let estimate = localizer.estimate().pose;
        let Some((pan, tilt)) = vtt.aim(&estimate) else { continue };
        let (l, r, p, t) = take(&mut sim, &mut localizer, &occluded, pan, tilt)?;
        last_pointing = Some((p, t));
        let pair = NavcamPair { left: &l, right: &r, pan: p, tilt: t };
        match vtt.observe(&pair, &localizer.estimate().pose) {
            Ok(_) => tracked += 1,
            Err(e) => return Ok(stopped(&sim, e.to_string(), tracked, occluded.is_some())),
        }
    }
}

/// Turns then drives blind, feeding the estimator.
fn execute(sim: &mut Simulator, loc: &mut Box<dyn rovernav_core::Localizer>, turn: f64, distance: f64) {
    let mut frames: Vec<SensorFrame> = Vec::new();
    if turn != 0.0 {
        frames.push(sim.execute(&NavCommand::Turn { angle: turn }));
    }
    let guard = DriveGuard { proximity: false, max_tilt: None };
    frames.push(sim.execute(&NavCommand::Drive { distance, curvature: 0.0, guard }));
    for f in &frames {
        loc.update(f);
    }
}

/// The yard with an occluding rock (0.8 m across, 0.75 m tall) on the line of sight, 70 % of
/// the way from the rover to the tracked target (`None`: straight ahead 3 m).
fn occluder(
    world: &World,
    truth: &Pose3,
    target: Option<Point3<f64>>,
) -> (rovernav_terrain::Terrain, HeightField) {
    let (tx, ty) =
        target.map_or((truth.x + 3.0 * truth.yaw.cos(), truth.y + 3.0 * truth.yaw.sin()), |t| (t.x, t.y));
    let rock = Rock {
        x: truth.x + 0.7 * (tx - truth.x),
        y: truth.y + 0.7 * (ty - truth.y),
        diameter: 0.8,
        height: 0.75,
    };
    let mut terrain = world.terrain.clone();
    rovernav_terrain::procedural::rocks::add_rocks(&mut terrain.dem, &[rock]);
    terrain.rocks.push(rock);
    let field = HeightField::new(&terrain.dem);
    (terrain, field)
}

fn print_table(e: &VttEvaluation) {
    println!(
        "VTT approaches from {:.1} m to a {:.2} m stand-off: {} trials ({} yards skipped)",
        e.distance_m, e.standoff_m, e.trials, e.seeds_skipped
    );
    println!(
        "error to the stand-off point, with VTT: median {:.4} m, p95 {:.4} m",
        e.median_error_m, e.p95_error_m
    );
    println!(
        "pose estimate alone:                   median {:.4} m, p95 {:.4} m",
        e.baseline_median_error_m, e.baseline_p95_error_m
    );
    println!(
        "losses induced {}, detected {}; wrong target {}; unplanned losses {}; images tracked {}",
        e.losses_induced, e.losses_detected, e.wrong_target, e.unplanned_losses, e.images_tracked
    );
    for t in &e.per_trial {
        println!(
            "  seed {:5} {:5.2} m rock {:.2} m{} vtt {:.4} m (radial {:+.4}, drift {:.4}; {}; {} images) baseline {:.4} m",
            t.seed,
            t.start_distance_m,
            t.rock_diameter_m,
            if t.occluded {
                " occluded"
            } else if t.occlusion_trial {
                " (occlusion trial)"
            } else {
                ""
            },
            t.vtt_error_m,
            t.vtt_radial_error_m,
            t.vtt_point_drift_m,
            t.vtt_end,
            t.images_tracked,
            t.baseline_error_m
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(trials: usize, distance: f64) -> EvalVttArgs {
        EvalVttArgs {
            trials,
            distance,
            first_seed: 1000,
            standoff: 1.0,
            width: 512,
            occlude_every: 4,
            json: true,
        }
    }

    #[test]
    fn percentiles_are_nearest_rank() {
        let mut v = vec![5.0, 1.0, 4.0, 2.0, 3.0];
        assert_eq!(percentile(&mut v, 0.5), 3.0);
        assert_eq!(percentile(&mut v, 0.95), 5.0);
        assert_eq!(percentile(&mut v, 0.2), 1.0);
        assert!(percentile(&mut [], 0.5).is_nan());
    }

    #[test]
    fn bad_arguments_are_refused_before_any_yard_is_built() {
        assert!(evaluate(&args(0, 10.0)).is_err());
        assert!(evaluate(&args(1, 1.5)).is_err(), "the distance must exceed the stand-off by 1 m");
        assert!(evaluate(&EvalVttArgs { width: 8, ..args(1, 10.0) }).is_err());
    }

    /// On eight yards from 10 m: every unoccluded approach arrives and ends closer to the
    /// stand-off point than the same approach on the pose estimate alone, every induced loss is
    /// reported and no approach ends at a wrong target. (Issue 35's median <= 2 cm and p95 <= 5
    /// cm are measured on 50 yards by `rovernav eval vtt`, docs/results/; not met yet.)
    #[test]
    #[ignore = "renders about 150 Navcam pairs: run in release (.ci/run does)"]
    fn vtt_beats_the_estimate_alone_and_reports_every_induced_loss_from_10_m() {
        let e = evaluate(&args(8, 10.0)).expect("evaluation");
        for t in e.per_trial.iter().filter(|t| !t.occlusion_trial) {
            assert_eq!(t.vtt_end, "arrived", "seed {}", t.seed);
            assert!(t.vtt_error_m < t.baseline_error_m, "seed {}: {t:?}", t.seed);
        }
        assert!(e.losses_induced > 0, "the occlusion trials hid the target: {e:?}");
        assert_eq!(e.losses_detected, e.losses_induced);
        assert_eq!(e.wrong_target, 0);
    }
}
