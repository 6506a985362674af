//! `rovernav eval descent`: elevation from consecutive descent images against the paper's
//! predicted precision (paper 002 section 4, figures 4 and 5).
//!
//! The sequence ([`rovernav_sim::scenes::descent`]) is rendered over the 1 m Gale DEM
//! (`gale/missionDEM.tif`, its centre the landing site) blended into fractal relief, or over
//! fractal relief alone with `--no-dem`. Each consecutive pair is matched and triangulated
//! ([`rovernav_vision::descent::match_pair`]) with the true camera poses (the lander's
//! navigation), searching around the previous pair's elevations (the first pair around the
//! landing site's height). Every triangulated point is scored against the true ground height
//! under it, and its lower-image match against the true point projected into the lower camera.
//! Per pair:
//! - `predicted_sigma_m`: RMS over the pair's points of the paper's
//!   `dZ = (Z - T_z)^2 dtheta / (T_z tan theta)` with the paper's 0.1-pixel matching
//!   precision (`--matching-precision`);
//! - `measured_sigma_m`: RMS of the same points' elevation errors;
//! - `matching_sigma_px`: RMS radial error of the matches in lower-image pixels (the component
//!   that carries elevation), and `predicted_at_matching_sigma_m`, the formula with it.
//!
//! Points closer to the image centre than `MIN_RADIUS` of the half-width are left out (the
//! formula's precision diverges there); outliers are points whose error exceeds five robust
//! standard deviations of the errors normalised by their predictions, counted apart. The
//! combined profile (figure 5) bins points by distance from the landing site and combines the
//! pairs by inverse variance, predicted and measured alike. `localisation`: the rover matched
//! against the descent DEM at `--fix-distances` ([`fix`]).

#[path = "eval_descent_fix.rs"]
mod fix;

use crate::output::median;
use anyhow::Context;
use rovernav_core::{Grid2, GridGeometry};
use rovernav_sim::scenes::descent::{
    DescentImage, DescentPlan, DescentTerrain, ground_point, render_sequence,
};
use rovernav_vision::CameraModel;
use rovernav_vision::descent::{
    DescentMatch, MatchParams, View, elevation_grid, match_pair, predicted_sigma,
};
use serde::Serialize;

/// Least image radius of a used point, as a fraction of the upper image's half-width.
const MIN_RADIUS: f64 = 0.1;
/// Outlier threshold on robust standard deviations of the normalised errors.
const OUTLIER_SIGMAS: f64 = 5.0;
/// Least points in a bin for a measured figure.
const MIN_BIN_POINTS: usize = 10;

/// Options of `rovernav eval descent`.
#[derive(clap::Args, Debug)]
pub struct EvalDescentArgs {
    /// Number of images (one per halving of altitude).
    #[arg(long, default_value_t = 10)]
    pub images: usize,
    /// Image side (pixels; the paper's camera has 1000).
    #[arg(long, default_value_t = 1000)]
    pub size: usize,
    /// Altitude of the first image (m).
    #[arg(long, default_value_t = 6750.0)]
    pub top_altitude: f64,
    /// Seed of the terrain, drift and noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Matching precision of the prediction (pixels; the paper's 0.1).
    #[arg(long, default_value_t = 0.1)]
    pub matching_precision: f64,
    /// Horizontal drift of each camera per axis as a fraction of its altitude (1 sigma; 0 is
    /// the paper's purely vertical descent).
    #[arg(long, default_value_t = 0.0)]
    pub drift: f64,
    /// Fractal terrain only, without the Gale DEM at the landing site.
    #[arg(long)]
    pub no_dem: bool,
    /// Distances from the landing site where the rover localises against the descent DEM (m).
    #[arg(long, value_delimiter = ',', default_value = "100,500,1000")]
    pub fix_distances: Vec<f64>,
    /// Print the figures as JSON.
    #[arg(long)]
    pub json: bool,
}

/// One image pair's figures.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct PairFigures {
    /// Altitudes of the upper and lower images (m).
    pub altitudes_m: [f64; 2],
    /// Ground pixel of the upper image below it (m).
    pub pixel_m: f64,
    /// Points matched and triangulated.
    pub matches: usize,
    /// Points used (far enough from the centre, not outliers).
    pub used: usize,
    /// Outliers left out.
    pub outliers: usize,
    /// RMS of the paper's predicted precision over the used points (m).
    pub predicted_sigma_m: f64,
    /// RMS elevation error of the used points against the truth (m).
    pub measured_sigma_m: f64,
    /// `measured_sigma_m / predicted_sigma_m`.
    pub ratio: f64,
    /// RMS radial matching error in the lower image against the truth (pixels).
    pub matching_sigma_px: f64,
    /// The paper's formula with `matching_sigma_px` instead of the assumed precision (m).
    pub predicted_at_matching_sigma_m: f64,
}

/// One distance bin of the combined profile (figure 5).
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct ProfileBin {
    /// Distance range from the landing site (m).
    pub distance_m: [f64; 2],
    /// Pairs combined (predicted: those that see the bin's centre distance).
    pub pairs: usize,
    /// Combined predicted precision at the bin's geometric centre (m).
    pub predicted_sigma_m: f64,
    /// Combined measured precision (m; NaN without enough points).
    pub measured_sigma_m: f64,
    /// Used points in the bin.
    pub points: usize,
}

/// The figures of `rovernav eval descent`.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct DescentEvaluation {
    /// Image side (pixels) and focal length (pixels).
    pub size: usize,
    /// Focal length (pixels).
    pub focal_px: f64,
    /// Whether the Gale DEM lies under the landing site.
    pub gale_dem: bool,
    /// Assumed matching precision of the predictions (pixels).
    pub matching_precision_px: f64,
    /// Per image pair, top down.
    pub pairs: Vec<PairFigures>,
    /// Median over pairs of `measured / predicted`: the factor by which they agree.
    pub agreement_factor: f64,
    /// Median over pairs of `measured / predicted at the measured matching precision`.
    pub agreement_at_matching_sigma: f64,
    /// Combined precision against distance from the landing site.
    pub profile: Vec<ProfileBin>,
    /// The rover localised against the descent DEM.
    pub localisation: Vec<fix::DescentFix>,
}

/// A used point: distance from the landing site, error, predicted sigma, pair index.
#[derive(Clone, Copy, Debug)]
struct Scored {
    distance: f64,
    error: f64,
    predicted: f64,
    pair: usize,
}

/// Runs the evaluation and prints the figures.
pub fn run(args: EvalDescentArgs) -> anyhow::Result<()> {
    anyhow::ensure!((2..=12).contains(&args.images), "--images: {} is outside 2..12", args.images);
    anyhow::ensure!((64..=2000).contains(&args.size), "--size: {} is outside 64..2000", args.size);
    anyhow::ensure!(
        args.top_altitude.is_finite() && (50.0..=50_000.0).contains(&args.top_altitude),
        "--top-altitude: {} is outside 50..50000 m",
        args.top_altitude
    );
    anyhow::ensure!(
        args.fix_distances.iter().all(|d| d.is_finite() && (0.0..=5000.0).contains(d)),
        "--fix-distances: {:?} must lie within 0..5000 m",
        args.fix_distances
    );
    anyhow::ensure!(
        args.drift.is_finite() && (0.0..=0.2).contains(&args.drift),
        "--drift: {} is outside 0..0.2",
        args.drift
    );
    anyhow::ensure!(
        args.matching_precision.is_finite() && args.matching_precision > 0.0,
        "--matching-precision: {} must be positive",
        args.matching_precision
    );
    let terrain = if args.no_dem {
        DescentTerrain::procedural(args.seed as u32)
    } else {
        let path = rovernav_core::data_dir().join("gale/missionDEM.tif");
        let dem = rovernav_terrain::io::load_geotiff(&path).with_context(|| format!("{}", path.display()))?;
        DescentTerrain::with_dem(dem, args.seed as u32)
            .with_context(|| format!("{}: no height at the DEM's centre", path.display()))?
    };
    let plan = DescentPlan {
        top_altitude_m: args.top_altitude,
        images: args.images,
        size: args.size,
        drift_fraction: args.drift,
        ..Default::default()
    };
    let evaluation =
        evaluate(&terrain, &plan, args.seed, args.matching_precision, !args.no_dem, &args.fix_distances);
    crate::output::print_evaluation(args.json, &evaluation, print_table)
}

/// Renders the sequence, matches every consecutive pair and scores it.
pub fn evaluate(
    terrain: &DescentTerrain,
    plan: &DescentPlan,
    seed: u64,
    precision_px: f64,
    gale_dem: bool,
    fix_distances: &[f64],
) -> DescentEvaluation {
    let images = render_sequence(terrain, plan, seed);
    let f = plan.focal_px();
    let mut prior: Option<(Grid2<f32>, f64)> = None;
    let mut pairs = Vec::new();
    let mut scored = Vec::new();
    // Every triangulated point with the formula's precision at its pair's matching error.
    let mut dem_points: Vec<[f64; 4]> = Vec::new();
    let mut priors = Vec::new();
    for (k, w) in images.windows(2).enumerate() {
        let (va, vb) = (view(&w[0], plan.size), view(&w[1], plan.size));
        let height = |x: f64, y: f64| match &prior {
            Some((grid, fallback)) => {
                grid.at_world(x, y).map(|&v| v as f64).filter(|v| v.is_finite()).unwrap_or(*fallback)
            }
            None => 0.0,
        };
        let matches = match_pair((&va, &w[0].camera), (&vb, &w[1].camera), &height, &MatchParams::default());
        priors.push(prior.clone());
        let (figures, points) = score_pair(terrain, &w[0], &w[1], &matches, f, precision_px, plan.size, k);
        // The next pair searches around this pair's elevations.
        let cell = 16.0 * w[0].pixel_m;
        let half = 0.5 * plan.size as f64 * w[0].pixel_m;
        let (cx, cy) = (w[0].camera.c.x, w[0].camera.c.y);
        let cols = (2.0 * half / cell).ceil() as usize;
        let geometry =
            GridGeometry { cols, rows: cols, resolution: cell, origin_x: cx - half, origin_y: cy - half };
        let cloud: Vec<[f64; 4]> =
            matches.iter().map(|m| [m.point[0], m.point[1], m.point[2], 1.0]).collect();
        let zs: Vec<f64> = matches.iter().map(|m| m.point[2]).collect();
        let level = median(&zs);
        prior = level.is_finite().then(|| (elevation_grid(&cloud, geometry), level));
        dem_points.extend(matches.iter().map(|m| {
            let [x, y, z] = m.point;
            [x, y, z, m.predicted_sigma(figures.matching_sigma_px, f)]
        }));
        pairs.push(figures);
        scored.extend(points);
    }
    let ratios: Vec<f64> = pairs.iter().map(|p| p.ratio).filter(|r| r.is_finite()).collect();
    let at_matching: Vec<f64> = pairs
        .iter()
        .map(|p| p.measured_sigma_m / p.predicted_at_matching_sigma_m)
        .filter(|r| r.is_finite())
        .collect();
    let localisation = fix_distances
        .iter()
        .map(|&d| {
            let mut points = dem_points.clone();
            points.extend(dense_points(&images, &priors, &pairs, d, seed, f));
            fix::fix(terrain, &points, d, seed)
        })
        .collect();
    DescentEvaluation {
        size: plan.size,
        focal_px: f,
        gale_dem,
        matching_precision_px: precision_px,
        profile: profile(&images, &scored, f, precision_px, plan),
        pairs,
        agreement_factor: median(&ratios),
        agreement_at_matching_sigma: median(&at_matching),
        localisation,
    }
}

/// Every upper pixel matched around the rover's dead-reckoned position at `distance`, in the
/// lowest pair whose lower image sees the matcher's whole reach (`[x, y, z, sigma]`, sigma from
/// the formula at the pair's measured matching error); empty when no pair does.
fn dense_points(
    images: &[DescentImage],
    priors: &[Option<(Grid2<f32>, f64)>],
    pairs: &[PairFigures],
    distance: f64,
    seed: u64,
    f: f64,
) -> Vec<[f64; 4]> {
    let (_, _, dr) = fix::position(distance, seed);
    let r = fix::REACH_M + 2.0;
    let corners = [(-r, -r), (r, -r), (r, r), (-r, r)];
    let sees = |cam: &rovernav_vision::Cahv| {
        corners.iter().all(|&(dx, dy)| {
            cam.project(&nalgebra::Point3::new(dr.x + dx, dr.y + dy, 0.0)).is_some_and(|p| {
                let m = 0.1 * cam.width as f64;
                p.x > m && p.y > m && p.x < cam.width as f64 - m && p.y < cam.height as f64 - m
            })
        })
    };
    let Some(k) = (0..images.len().saturating_sub(1)).rev().find(|&k| sees(&images[k + 1].camera)) else {
        return Vec::new();
    };
    let (up, lo) = (&images[k], &images[k + 1]);
    let pixels: Vec<_> = corners
        .iter()
        .filter_map(|&(dx, dy)| up.camera.project(&nalgebra::Point3::new(dr.x + dx, dr.y + dy, 0.0)))
        .collect();
    let bound = |v: f64| v.max(0.0) as usize;
    let region = [
        bound(pixels.iter().map(|p| p.x).fold(f64::INFINITY, f64::min)),
        bound(pixels.iter().map(|p| p.y).fold(f64::INFINITY, f64::min)),
        bound(pixels.iter().map(|p| p.x).fold(0.0, f64::max).ceil()),
        bound(pixels.iter().map(|p| p.y).fold(0.0, f64::max).ceil()),
    ];
    let height = |x: f64, y: f64| match &priors[k] {
        Some((grid, fallback)) => {
            grid.at_world(x, y).map(|&v| v as f64).filter(|v| v.is_finite()).unwrap_or(*fallback)
        }
        None => 0.0,
    };
    let size = up.camera.width;
    let params = MatchParams { cell_px: 1, region: Some(region), ..Default::default() };
    let matches = match_pair((&view(up, size), &up.camera), (&view(lo, size), &lo.camera), &height, &params);
    matches
        .iter()
        .map(|m| {
            let [x, y, z] = m.point;
            [x, y, z, m.predicted_sigma(pairs[k].matching_sigma_px, f)]
        })
        .collect()
}

/// An image as the matcher's view.
fn view(image: &DescentImage, size: usize) -> View<'_> {
    View { pixels: &image.pixels, width: size, height: size }
}

/// One pair's figures and its used points.
#[allow(clippy::too_many_arguments)]
fn score_pair(
    terrain: &DescentTerrain,
    upper: &DescentImage,
    lower: &DescentImage,
    matches: &[DescentMatch],
    f: f64,
    precision_px: f64,
    size: usize,
    pair: usize,
) -> (PairFigures, Vec<Scored>) {
    let band = 2.0 * lower.pixel_m;
    let c = 0.5 * (size as f64 - 1.0);
    let min_radius = MIN_RADIUS * 0.5 * size as f64;
    // (distance, error, predicted, radial matching error)
    let rows: Vec<[f64; 4]> = matches
        .iter()
        .filter(|m| (m.upper_px[0] - c).hypot(m.upper_px[1] - c) >= min_radius)
        .filter_map(|m| {
            let [x, y, z] = m.point;
            let error = z - terrain.height(x, y, band);
            let p1 = nalgebra::Point2::new(m.upper_px[0], m.upper_px[1]);
            let truth = ground_point(terrain, &upper.camera, &p1, band)?;
            let p2 = lower.camera.project(&nalgebra::Point3::from(truth))?;
            let (rx, ry) = (p2.x - c, p2.y - c);
            let norm = rx.hypot(ry).max(1e-9);
            let radial = ((m.lower_px[0] - p2.x) * rx + (m.lower_px[1] - p2.y) * ry) / norm;
            Some([x.hypot(y), error, m.predicted_sigma(precision_px, f), radial])
        })
        .collect();
    let mut normalised: Vec<f64> = rows.iter().map(|r| r[1] / r[2]).collect();
    let centre = median(&normalised);
    let deviations: Vec<f64> = normalised.iter_mut().map(|v| (*v - centre).abs()).collect();
    let scale = 1.4826 * median(&deviations);
    let used: Vec<&[f64; 4]> =
        rows.iter().filter(|r| (r[1] / r[2] - centre).abs() <= OUTLIER_SIGMAS * scale.max(1e-9)).collect();
    let rms = |k: usize| (used.iter().map(|r| r[k] * r[k]).sum::<f64>() / used.len().max(1) as f64).sqrt();
    let (predicted, measured, matching) = (rms(2), rms(1), rms(3));
    let figures = PairFigures {
        altitudes_m: [upper.altitude_m, lower.altitude_m],
        pixel_m: upper.pixel_m,
        matches: matches.len(),
        used: used.len(),
        outliers: rows.len() - used.len(),
        predicted_sigma_m: predicted,
        measured_sigma_m: measured,
        ratio: measured / predicted,
        matching_sigma_px: matching,
        predicted_at_matching_sigma_m: predicted * matching / precision_px,
    };
    let points = used.iter().map(|r| Scored { distance: r[0], error: r[1], predicted: r[2], pair }).collect();
    (figures, points)
}

/// The combined profile: doubling distance bins from 5 m, predicted at each bin's centre for
/// every pair whose lower image sees it, measured from the used points; pairs combined by
/// inverse variance.
fn profile(
    images: &[DescentImage],
    scored: &[Scored],
    f: f64,
    precision_px: f64,
    plan: &DescentPlan,
) -> Vec<ProfileBin> {
    let half_tan = 0.5 * plan.size as f64 / f;
    let far = images.first().map_or(0.0, |im| 0.5 * im.altitude_m * half_tan);
    let mut bins = Vec::new();
    let mut lo = 5.0;
    while lo < far {
        let hi = 2.0 * lo;
        let d = (lo * hi).sqrt();
        let mut info = 0.0;
        let mut pairs = 0;
        for w in images.windows(2) {
            let (z, tz) = (w[0].altitude_m, w[0].altitude_m - w[1].altitude_m);
            let tan = d / z;
            if d <= (z - tz) * half_tan && tan >= MIN_RADIUS * half_tan {
                info += predicted_sigma(z, tz, tan.atan(), precision_px / f).powi(-2);
                pairs += 1;
            }
        }
        let in_bin: Vec<&Scored> = scored.iter().filter(|s| s.distance >= lo && s.distance < hi).collect();
        let mut measured_info = 0.0;
        for k in 0..images.len().saturating_sub(1) {
            let errors: Vec<f64> = in_bin.iter().filter(|s| s.pair == k).map(|s| s.error).collect();
            if errors.len() >= MIN_BIN_POINTS {
                measured_info += errors.len() as f64 / errors.iter().map(|e| e * e).sum::<f64>();
            }
        }
        bins.push(ProfileBin {
            distance_m: [lo, hi],
            pairs,
            predicted_sigma_m: if info > 0.0 { info.powf(-0.5) } else { f64::NAN },
            measured_sigma_m: if measured_info > 0.0 { measured_info.powf(-0.5) } else { f64::NAN },
            points: in_bin.len(),
        });
        debug_assert!(in_bin.iter().all(|s| s.predicted > 0.0));
        lo = hi;
    }
    bins
}

/// Prints the per-pair table and the profile.
fn print_table(e: &DescentEvaluation) {
    println!(
        "descent imagery: {} px, focal {:.1} px, {}; prediction at {} px matching",
        e.size,
        e.focal_px,
        if e.gale_dem { "Gale DEM at the landing site" } else { "fractal terrain" },
        e.matching_precision_px
    );
    println!("  altitudes (m)      pixel (m)  matches  used  predicted (m)  measured (m)  ratio  match (px)");
    for p in &e.pairs {
        println!(
            "  {:>8.1} -> {:>7.1}  {:>9.4}  {:>7}  {:>4}  {:>13.4}  {:>12.4}  {:>5.2}  {:>10.3}",
            p.altitudes_m[0],
            p.altitudes_m[1],
            p.pixel_m,
            p.matches,
            p.used,
            p.predicted_sigma_m,
            p.measured_sigma_m,
            p.ratio,
            p.matching_sigma_px
        );
    }
    println!(
        "  agreement: measured / predicted {:.2} (median); at the measured matching precision {:.2}",
        e.agreement_factor, e.agreement_at_matching_sigma
    );
    println!("  distance (m)     pairs  predicted (m)  measured (m)  points");
    for b in &e.profile {
        println!(
            "  {:>6.0} - {:>6.0}  {:>5}  {:>13.4}  {:>12.4}  {:>6}",
            b.distance_m[0], b.distance_m[1], b.pairs, b.predicted_sigma_m, b.measured_sigma_m, b.points
        );
    }
    println!(
        "  rover against the descent DEM: distance (m)  DEM cell (m)  DEM RMS (m)  error (m)  dead reckoning (m)  P(false)"
    );
    for x in &e.localisation {
        let opt = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.3}"));
        println!(
            "  {:>10.0}  {:>12.0}  {:>11.3}  {:>9}  {:>18.3}  {:>8}  {}",
            x.distance_m,
            x.reference_cell_m,
            x.reference_rms_m,
            opt(x.error_m),
            x.dead_reckoning_error_m,
            opt(x.failure_probability),
            x.failure.as_deref().unwrap_or("")
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn measured_precision_follows_the_formula_at_the_measured_matching_precision() {
        let plan = DescentPlan { top_altitude_m: 400.0, images: 3, size: 200, ..Default::default() };
        let e = evaluate(&DescentTerrain::procedural(5), &plan, 5, 0.1, false, &[]);
        assert_eq!(e.pairs.len(), 2);
        for p in &e.pairs {
            assert!(p.used >= 50, "{p:?}");
            let r = p.measured_sigma_m / p.predicted_at_matching_sigma_m;
            assert!(
                (0.5..2.0).contains(&r),
                "measured {} vs formula at measured matching {}",
                p.measured_sigma_m,
                p.predicted_at_matching_sigma_m
            );
        }
        assert!(!e.profile.is_empty() && e.profile.iter().any(|b| b.measured_sigma_m.is_finite()));
    }
}
