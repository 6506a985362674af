//! `rovernav eval stereo`: correlated stereo range against the simulator's truth on rendered
//! Mars-yard pairs.
//!
//! For each seed of the default Mars yard the rover stands at the mission start and images a
//! full circle with the mast pair (eight 45 deg wedges) and both body pairs, through the
//! simulator's `stereo` range source: both images rendered, correlated by semi-global matching,
//! triangulated. Every left-image pixel is compared with the renderer's true range along its
//! ray. The figures, pooled over all seeds:
//! - `valid_fraction`: of the pixels whose true range is within 5 m (what the ray caster sees
//!   within 5 m), those the correlator gave a range;
//! - `gross_error_fraction`: of the valid pixels, those wrong by more than 3 sigma of their own
//!   predicted uncertainty (Matthies' model, sigma_r = r^2 sigma_d / (f b) along the ray);
//! - `median_abs_range_error_m`, and per range bin the median error, the observed robust
//!   sigma (1.4826 x the median absolute deviation) and the predicted sigma, so the error's
//!   growth with range can be read against the model.

use nalgebra::{Point2, Point3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use rovernav_executive::Mission;
use rovernav_harness::build_world;
use rovernav_sim::render::{Label, pose_isometry};
use rovernav_sim::sensors::RangeGeometry;
use rovernav_sim::stereo_range::{self, StereoImaging};
use rovernav_sim::vehicle::settled_pose;
use rovernav_sim::{HeightField, SensorModel};
use rovernav_vision::camera::Movable;
use rovernav_vision::{Cahv, CameraModel};
use serde::Serialize;

use crate::eval_terrain::parse_seed_range;

/// Width of one range bin of the error table (m).
const BIN_M: f64 = 0.5;
/// The range within which pixels count for the valid fraction (m).
const SEEN_WITHIN_M: f64 = 5.0;

/// Options of `rovernav eval stereo`.
#[derive(clap::Args, Debug)]
pub struct EvalStereoArgs {
    /// Seeds of the default Mars yard, as FIRST..LAST (inclusive).
    #[arg(long, default_value = "1..5")]
    pub seeds: String,
    /// Print the figures as JSON.
    #[arg(long)]
    pub json: bool,
}

/// The error of the pixels in one range bin.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct RangeBin {
    /// Lower edge of the bin (true range, m).
    pub from_m: f64,
    /// Upper edge (m).
    pub to_m: f64,
    /// Pixels with a true range in the bin.
    pub pixels: usize,
    /// Of those, the ones with a valid stereo range.
    pub valid: usize,
    /// Median absolute range error of the valid ones (m).
    pub median_abs_error_m: f64,
    /// Robust standard deviation of the signed error, 1.4826 x MAD (m).
    pub observed_sigma_m: f64,
    /// Median predicted standard deviation (Matthies' model) (m).
    pub predicted_sigma_m: f64,
    /// Valid pixels wrong by more than 3 predicted sigma.
    pub gross_errors: usize,
}

/// The figures of `rovernav eval stereo`.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct StereoEvaluation {
    /// Seeds evaluated.
    pub seeds: Vec<u64>,
    /// Stereo pairs correlated.
    pub pairs: usize,
    /// Pixels whose true range is within 5 m and whose surface point both cameras see.
    pub pixels_within_5m: usize,
    /// Of those, the fraction with a valid stereo range.
    pub valid_fraction: f64,
    /// Left-image pixels whose true range is within 5 m, whether the right camera sees them or
    /// not (near the left edge a near point falls outside the right image).
    pub pixels_within_5m_left_image: usize,
    /// Of those, the fraction with a valid stereo range.
    pub valid_fraction_left_image: f64,
    /// Of all valid pixels, the fraction wrong by more than 3 predicted sigma.
    pub gross_error_fraction: f64,
    /// Median absolute range error of the valid pixels within 5 m (m).
    pub median_abs_range_error_m: f64,
    /// Subpixel disparity error the predicted sigma assumes (px).
    pub sigma_d_px: f64,
    /// The error against range.
    pub by_range: Vec<RangeBin>,
}

/// One valid or invalid pixel's comparison.
#[derive(Clone, Copy)]
struct PixelError {
    truth: f64,
    /// Whether the right camera sees the same surface point (inside its image, unoccluded).
    both: bool,
    /// Signed error and predicted sigma, when the correlator gave a range.
    measured: Option<(f64, f64)>,
}

/// Runs the evaluation and prints the figures.
pub fn run(args: EvalStereoArgs) -> anyhow::Result<()> {
    let seeds: Vec<u64> = parse_seed_range(&args.seeds)?.collect();
    crate::output::print_evaluation(args.json, &evaluate(&seeds)?, print_table)
}

/// Images every seed's start position and pools the pixel errors.
pub fn evaluate(seeds: &[u64]) -> anyhow::Result<StereoEvaluation> {
    let imaging = StereoImaging::default();
    let per_seed: Vec<anyhow::Result<(usize, Vec<PixelError>)>> =
        seeds.par_iter().map(|&seed| seed_errors(seed, &imaging)).collect();
    let mut pairs = 0;
    let mut errors = Vec::new();
    for r in per_seed {
        let (n, e) = r?;
        pairs += n;
        errors.extend(e);
    }
    Ok(summarise(seeds.to_vec(), pairs, &errors, imaging.sigma_d_px))
}

/// The pixel errors of one seed's circle of mast wedges and its two body pairs.
fn seed_errors(seed: u64, imaging: &StereoImaging) -> anyhow::Result<(usize, Vec<PixelError>)> {
    let mut mission = Mission::default_mission();
    mission.seed = seed;
    let world = build_world(&mission, "built-in default mission")?;
    let model = SensorModel::default();
    let truth = settled_pose(&world.terrain.dem, &world.rover, world.start);
    let field = HeightField::new(&world.terrain.dem);
    let mut geometries: Vec<RangeGeometry> = (0..8)
        .map(|k| RangeGeometry::mast(&world.rover, &model, f64::from(k) * std::f64::consts::FRAC_PI_4))
        .collect();
    geometries.push(RangeGeometry::body(&world.rover, &model, true));
    geometries.push(RangeGeometry::body(&world.rover, &model, false));
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut errors = Vec::new();
    let pose = pose_isometry(&truth);
    for geometry in &geometries {
        let capture = stereo_range::capture(&world.terrain, &field, &truth, geometry, imaging, &mut rng);
        let (left, right) = (capture.rig.left.moved(&pose), capture.rig.right.moved(&pose));
        let width = capture.left.width();
        for (i, &truth_range) in capture.left.range.iter().enumerate() {
            // The ray caster sees the DEM only: sky and the level ground the renderer draws
            // beyond the DEM's edge are not part of the yard.
            if !truth_range.is_finite() || matches!(capture.left.labels[i], Label::Sky | Label::FarGround) {
                continue;
            }
            let pixel = Point2::new((i % width) as f64, (i / width) as f64);
            let point = left.unproject(&pixel).at(f64::from(truth_range));
            let both = seen_by(&right, &capture.right.range, &point);
            let measured = capture.range.range[i];
            let sigma = capture.range.range_sigma[i];
            errors.push(PixelError {
                truth: f64::from(truth_range),
                both,
                measured: measured
                    .is_finite()
                    .then(|| (f64::from(measured) - f64::from(truth_range), f64::from(sigma))),
            });
        }
    }
    Ok((geometries.len(), errors))
}

/// Whether a camera whose true range image is `range` sees `point` (inside its image and not
/// hidden behind a nearer surface: its pixel's true range within 2 % + 2 cm of the distance).
fn seen_by(camera: &Cahv, range: &[f32], point: &Point3<f64>) -> bool {
    let Some(px) = camera.project(point) else { return false };
    if !camera.contains(&px) {
        return false;
    }
    let (x, y) = (px.x.round() as usize, px.y.round() as usize);
    let Some(&r) = range.get(y * camera.width + x) else { return false };
    let d = (point - camera.centre()).norm();
    r.is_finite() && (f64::from(r) - d).abs() <= 0.02 * d + 0.02
}

/// The median of a non-empty list (0 for an empty one).
fn median(values: &mut [f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n % 2 == 1 { values[n / 2] } else { 0.5 * (values[n / 2 - 1] + values[n / 2]) }
}

/// Pools the pixel errors into the figures.
fn summarise(seeds: Vec<u64>, pairs: usize, errors: &[PixelError], sigma_d_px: f64) -> StereoEvaluation {
    let whole: Vec<&PixelError> = errors.iter().filter(|e| e.truth <= SEEN_WITHIN_M).collect();
    let valid_whole = whole.iter().filter(|e| e.measured.is_some()).count();
    let within: Vec<&PixelError> = whole.iter().copied().filter(|e| e.both).collect();
    let valid_within: Vec<(f64, f64)> = within.iter().filter_map(|e| e.measured).collect();
    let all_valid: Vec<(f64, f64)> = errors.iter().filter_map(|e| e.measured).collect();
    let gross = |v: &[(f64, f64)]| v.iter().filter(|(err, sigma)| err.abs() > 3.0 * sigma).count();
    let mut abs_within: Vec<f64> = valid_within.iter().map(|(e, _)| e.abs()).collect();
    let bins = (SEEN_WITHIN_M / BIN_M).ceil() as usize + 2;
    let by_range = (0..bins)
        .filter_map(|b| {
            let (from, to) = (b as f64 * BIN_M, (b + 1) as f64 * BIN_M);
            let in_bin: Vec<&PixelError> =
                errors.iter().filter(|e| e.truth >= from && e.truth < to).collect();
            if in_bin.is_empty() {
                return None;
            }
            let valid: Vec<(f64, f64)> = in_bin.iter().filter_map(|e| e.measured).collect();
            let mut abs: Vec<f64> = valid.iter().map(|(e, _)| e.abs()).collect();
            let mut signed: Vec<f64> = valid.iter().map(|(e, _)| *e).collect();
            let centre = median(&mut signed);
            let mut deviations: Vec<f64> = valid.iter().map(|(e, _)| (e - centre).abs()).collect();
            let mut predicted: Vec<f64> = valid.iter().map(|(_, s)| *s).collect();
            Some(RangeBin {
                from_m: from,
                to_m: to,
                pixels: in_bin.len(),
                valid: valid.len(),
                median_abs_error_m: median(&mut abs),
                observed_sigma_m: 1.4826 * median(&mut deviations),
                predicted_sigma_m: median(&mut predicted),
                gross_errors: gross(&valid),
            })
        })
        .collect();
    let fraction = |a: usize, b: usize| if b == 0 { 0.0 } else { a as f64 / b as f64 };
    StereoEvaluation {
        seeds,
        pairs,
        pixels_within_5m: within.len(),
        valid_fraction: fraction(valid_within.len(), within.len()),
        pixels_within_5m_left_image: whole.len(),
        valid_fraction_left_image: fraction(valid_whole, whole.len()),
        gross_error_fraction: fraction(gross(&all_valid), all_valid.len()),
        median_abs_range_error_m: median(&mut abs_within),
        sigma_d_px,
        by_range,
    }
}

/// Prints the figures for a person.
fn print_table(e: &StereoEvaluation) {
    println!(
        "stereo on {} pairs of {} seeds: valid_fraction {:.4} (of {} pixels within 5 m both cameras see; {:.4} of all {} left-image pixels within 5 m), gross_error_fraction {:.4}, median_abs_range_error_m {:.4}",
        e.pairs,
        e.seeds.len(),
        e.valid_fraction,
        e.pixels_within_5m,
        e.valid_fraction_left_image,
        e.pixels_within_5m_left_image,
        e.gross_error_fraction,
        e.median_abs_range_error_m
    );
    println!("range (m)   pixels   valid  median|err| (m)  observed sigma (m)  predicted sigma (m)  gross");
    for b in &e.by_range {
        println!(
            "{:4.1}-{:<4.1} {:8} {:7.3} {:16.4} {:19.4} {:20.4} {:6}",
            b.from_m,
            b.to_m,
            b.pixels,
            if b.pixels == 0 { 0.0 } else { b.valid as f64 / b.pixels as f64 },
            b.median_abs_error_m,
            b.observed_sigma_m,
            b.predicted_sigma_m,
            b.gross_errors
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn summary_counts_valid_gross_and_bins() {
        let px = |truth: f64, m: Option<(f64, f64)>| PixelError { truth, both: true, measured: m };
        let errors = [
            px(1.2, Some((0.01, 0.01))),
            px(1.3, Some((-0.05, 0.01))), // gross: 5 sigma
            px(1.4, None),
            px(6.0, Some((0.2, 0.1))), // beyond 5 m: not in the valid fraction
        ];
        let e = summarise(vec![1], 1, &errors, 0.25);
        assert_eq!(e.pixels_within_5m, 3);
        assert!((e.valid_fraction - 2.0 / 3.0).abs() < 1e-12);
        assert!((e.gross_error_fraction - 1.0 / 3.0).abs() < 1e-12);
        assert!((e.median_abs_range_error_m - 0.03).abs() < 1e-12);
        let bin = e.by_range.iter().find(|b| b.from_m == 1.0).unwrap();
        assert_eq!((bin.pixels, bin.valid, bin.gross_errors), (3, 2, 1));
    }
}
