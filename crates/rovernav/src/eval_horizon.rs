//! `rovernav eval horizon`: the sensing-horizon reference on the default Mars yard (or on a
//! mission file's terrain).
//!
//! For each seed, the idealised rover of [`rovernav_harness::horizon`] (true hazards sensed
//! without noise or occlusion within the range, everything sensed remembered, unsensed ground
//! free, shortest path replanned) drives from the start to the goal. Its distance over the
//! optimal length is the path ratio that sensing horizon allows; a navigator's excess over it is
//! what its sensing (field of view, noise, hazard margins, memory) and its planner cost.
//! `--against` puts a campaign's runs on the same yards beside it, seed by seed.

use crate::eval_terrain::parse_seed_range;
use anyhow::Context;
use rayon::prelude::*;
use rovernav_campaign::{Row, TerrainKind};
use rovernav_executive::Mission;
use rovernav_harness::build_world;
use rovernav_harness::horizon::{HorizonConfig, HorizonRun, horizon_reference};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Options of `rovernav eval horizon`.
#[derive(clap::Args, Debug)]
pub struct EvalHorizonArgs {
    /// Seeds of the mission (the terrain of a procedural one, the rocks of a DEM one), as
    /// FIRST..LAST (inclusive).
    #[arg(long, default_value = "1..20")]
    pub seeds: String,
    /// A mission file instead of the built-in default mission.
    #[arg(long)]
    pub mission: Option<PathBuf>,
    /// Sensing radius (m).
    #[arg(long, default_value_t = 5.0)]
    pub range: f64,
    /// Field of view about the direction of travel (deg; 360: all around).
    #[arg(long, default_value_t = 360.0)]
    pub fov: f64,
    /// Distance driven between two sensings (m).
    #[arg(long, default_value_t = 1.0)]
    pub step: f64,
    /// Margin the true hazard cells are grown by (m).
    #[arg(long, default_value_t = 0.0)]
    pub margin: f64,
    /// Fraction of the belly clearance at which the truth marks a hazard.
    #[arg(long, default_value_t = 1.0)]
    pub clearance_fraction: f64,
    /// A campaign folder (`rovernav campaign --out DIR`) run on these yards: its navigators'
    /// path ratios beside the reference's, seed by seed.
    #[arg(long)]
    pub against: Option<PathBuf>,
    /// Print the figures as JSON.
    #[arg(long)]
    pub json: bool,
}

/// One seed's reference run.
struct SeedRow {
    seed: u64,
    run: HorizonRun,
}

impl SeedRow {
    /// Distance driven over the optimal length, when reached.
    fn ratio(&self) -> Option<f64> {
        self.run.optimal_m.filter(|_| self.run.reached).map(|o| self.run.driven_m / o)
    }
}

/// Mean and median of some values (NaN when empty).
fn mean_median(values: &[f64]) -> (f64, f64) {
    let mean = values.iter().sum::<f64>() / values.len() as f64;
    (mean, rovernav_campaign::summary::median(values).unwrap_or(f64::NAN))
}

/// Runs the reference on every seed (in parallel) and returns the rows in seed order.
fn reference_rows(
    template: &Mission,
    origin: &str,
    seeds: &[u64],
    config: &HorizonConfig,
) -> anyhow::Result<Vec<SeedRow>> {
    let one = |seed: u64| -> anyhow::Result<SeedRow> {
        let mut mission = template.clone();
        mission.seed = seed;
        let world = build_world(&mission, origin)?;
        Ok(SeedRow { seed, run: horizon_reference(&world, config)? })
    };
    seeds.par_iter().map(|&seed| one(seed)).collect()
}

/// The campaign's runs on these terrains (its yards for a procedural mission, its trials of
/// the mission for a DEM one), by navigator and seed, checked to be the same terrains.
fn campaign_runs(
    dir: &Path,
    mission: &Mission,
    rows: &[SeedRow],
) -> anyhow::Result<BTreeMap<String, BTreeMap<u64, Row>>> {
    let procedural = matches!(mission.terrain, rovernav_executive::mission::TerrainSpec::Procedural { .. });
    let (_, runs) =
        rovernav_campaign::read_dir(dir).with_context(|| format!("--against {}", dir.display()))?;
    let mut by_nav: BTreeMap<String, BTreeMap<u64, Row>> = BTreeMap::new();
    for run in runs {
        let Some(reference) = rows.iter().find(|r| r.seed == run.seed) else { continue };
        let same_kind = match run.terrain_kind {
            TerrainKind::Procedural => procedural,
            TerrainKind::Dem => !procedural && run.terrain == mission.name,
        };
        if !same_kind {
            continue;
        }
        // The same seed of a differently generated yard would compare unlike terrains: the
        // optimal lengths tell.
        if let (Some(a), Some(b)) = (run.optimal_length_m, reference.run.optimal_m)
            && (a - b).abs() > 1e-6 * b.max(1.0)
        {
            anyhow::bail!(
                "--against {}: trial {} (seed {}) has optimal length {a:.3} m, the mission's terrain of that seed {b:.3} m: not this mission's terrains",
                dir.display(),
                run.trial,
                run.seed
            );
        }
        by_nav.entry(run.navigator.clone()).or_default().insert(run.seed, run);
    }
    anyhow::ensure!(
        !by_nav.is_empty(),
        "--against {}: no runs of this mission's terrains on seeds of this range",
        dir.display()
    );
    Ok(by_nav)
}

/// Runs the evaluation and prints the figures.
pub fn run(args: EvalHorizonArgs) -> anyhow::Result<()> {
    let range = parse_seed_range(&args.seeds)?;
    let seeds: Vec<u64> = range.clone().collect();
    let config = HorizonConfig {
        range_m: args.range,
        fov_deg: args.fov,
        step_m: args.step,
        margin_m: args.margin,
        clearance_fraction: args.clearance_fraction,
        ..Default::default()
    };
    // Settings are checked before any terrain is built.
    config.validate()?;
    let (mission, origin) = match &args.mission {
        Some(path) => (Mission::from_file(path)?, path.display().to_string()),
        None => (Mission::default_mission(), "built-in default mission".to_string()),
    };
    let rows = reference_rows(&mission, &origin, &seeds, &config)?;
    let navs =
        args.against.as_ref().map(|d| campaign_runs(d, &mission, &rows)).transpose()?.unwrap_or_default();

    let ratios: Vec<f64> = rows.iter().filter_map(SeedRow::ratio).collect();
    let (mean, median) = mean_median(&ratios);
    let reached = rows.iter().filter(|r| r.run.reached).count();
    // Per navigator: its mean ratio and the reference's over the seeds both reached.
    let paired: Vec<(String, usize, f64, f64)> = navs
        .iter()
        .map(|(nav, runs)| {
            let pairs: Vec<(f64, f64)> =
                rows.iter().filter_map(|r| Some((runs.get(&r.seed)?.path_ratio?, r.ratio()?))).collect();
            let n = pairs.len();
            let m = |f: fn(&(f64, f64)) -> f64| pairs.iter().map(f).sum::<f64>() / n.max(1) as f64;
            (nav.clone(), n, m(|p| p.0), m(|p| p.1))
        })
        .collect();
    if args.json {
        let per_seed: Vec<_> = rows
            .iter()
            .map(|r| {
                let mut v = serde_json::json!({
                    "seed": r.seed,
                    "reached": r.run.reached,
                    "driven_m": r.run.driven_m,
                    "optimal_length_m": r.run.optimal_m,
                    "path_ratio": r.ratio(),
                    "plans": r.run.plans,
                });
                if !navs.is_empty() {
                    v["navigators"] = navs
                        .iter()
                        .filter_map(|(nav, runs)| {
                            let run = runs.get(&r.seed)?;
                            Some((
                                nav.clone(),
                                serde_json::json!({"outcome": run.outcome, "hazard_contacts": run.hazard_contacts, "path_ratio": run.path_ratio}),
                            ))
                        })
                        .collect::<serde_json::Map<_, _>>()
                        .into();
                }
                v
            })
            .collect();
        let against: Vec<_> = paired
            .iter()
            .map(|(nav, n, nav_mean, ref_mean)| {
                serde_json::json!({"navigator": nav, "seeds_both_reached": n, "path_ratio_mean": nav_mean, "reference_path_ratio_mean": ref_mean})
            })
            .collect();
        let v = serde_json::json!({
            "mission": mission.name,
            "seeds": format!("{}..{}", range.start(), range.end()),
            "range_m": args.range,
            "fov_deg": args.fov,
            "step_m": args.step,
            "margin_m": args.margin,
            "clearance_fraction": args.clearance_fraction,
            "reached": reached,
            "runs": rows.len(),
            "path_ratio_mean": mean,
            "path_ratio_median": median,
            "runs_per_seed": per_seed,
            "against": against,
        });
        println!("{}", serde_json::to_string_pretty(&v)?);
        return Ok(());
    }
    let nav_head: String = navs.keys().map(|n| format!("  {n:>12}")).collect();
    println!("seed  reached  driven (m)  optimal (m)  ratio  plans{nav_head}");
    for r in &rows {
        let nav_cols: String = navs
            .values()
            .map(|runs| {
                let cell = runs.get(&r.seed).map_or("-".to_string(), |run| match run.path_ratio {
                    Some(x) if run.hazard_contacts == 0 => format!("{x:.3}"),
                    Some(x) => format!("{x:.3} c{}", run.hazard_contacts),
                    None => run.outcome.clone(),
                });
                format!("  {cell:>12}")
            })
            .collect();
        println!(
            "{:>4}  {:>7}  {:>10.2}  {:>11}  {:>5}  {:>5}{nav_cols}",
            r.seed,
            if r.run.reached { "yes" } else { "no" },
            r.run.driven_m,
            r.run.optimal_m.map_or("-".into(), |o| format!("{o:.2}")),
            r.ratio().map_or("-".into(), |x| format!("{x:.3}")),
            r.run.plans
        );
    }
    println!(
        "{}, seeds {}..{}: sensing-horizon reference ({} m, {} deg, every {} m, margin {} m, clearance x {}): {reached}/{} reached, path ratio mean {mean:.3} (median {median:.3})",
        mission.name,
        range.start(),
        range.end(),
        args.range,
        args.fov,
        args.step,
        args.margin,
        args.clearance_fraction,
        rows.len()
    );
    for (nav, n, nav_mean, ref_mean) in &paired {
        println!(
            "{nav}: path ratio mean {nav_mean:.3} against the reference's {ref_mean:.3} over the {n} seeds both reached"
        );
    }
    Ok(())
}
