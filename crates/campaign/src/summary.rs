//! The per-navigator summary of a campaign's rows, as JSON and Markdown.
//!
//! Everything in [`Summary`] is a function of the rows' deterministic fields, summed in
//! (trial, navigator) order, so it is byte-identical across runs and across shard + merge.
//! Wall-clock figures live apart in [`MachineSummary`].

use crate::output::CampaignMeta;
use crate::row::Row;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fmt::Write;

/// The standard normal quantile for a two-sided 95 % interval.
pub const Z95: f64 = 1.959_963_984_540_054;

/// The Wilson score interval of `successes` out of `n` at normal quantile `z`; `None` when
/// `n` is 0. Unlike the normal approximation it stays inside [0, 1] and is sensible at 0 % and
/// 100 %, which small campaigns often hit.
pub fn wilson(successes: usize, n: usize, z: f64) -> Option<[f64; 2]> {
    if n == 0 {
        return None;
    }
    let n = n as f64;
    let p = successes as f64 / n;
    let z2 = z * z;
    let denom = 1.0 + z2 / n;
    let centre = (p + z2 / (2.0 * n)) / denom;
    let half = z / denom * (p * (1.0 - p) / n + z2 / (4.0 * n * n)).sqrt();
    Some([(centre - half).max(0.0), (centre + half).min(1.0)])
}

/// Free text as one Markdown table cell: `|` escaped, line breaks as spaces.
pub(crate) fn markdown_cell(text: &str) -> String {
    text.replace('|', "\\|").replace(['\n', '\r'], " ")
}

/// The nearest-rank percentile (`q` in (0, 1]): the smallest value with at least `q` of the
/// values at or below it; `None` for no values.
pub fn percentile(values: &[f64], q: f64) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let rank = (q * v.len() as f64).ceil().max(1.0) as usize;
    Some(v[rank.min(v.len()) - 1])
}

/// Median of `values` (the mean of the two middle values for an even count), if any.
pub fn median(values: &[f64]) -> Option<f64> {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    match n {
        0 => None,
        _ if n % 2 == 1 => Some(v[n / 2]),
        _ => Some(0.5 * (v[n / 2 - 1] + v[n / 2])),
    }
}

fn mean(values: impl Iterator<Item = f64>) -> Option<f64> {
    let (sum, n) = values.fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
    (n > 0).then(|| sum / n as f64)
}

/// The deterministic summary of a campaign (or of one shard's slice).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Summary {
    /// Campaign name.
    pub campaign: String,
    /// Campaign seed.
    pub seed: u64,
    /// First and last terrain seed of the procedural yards when the campaign file gives them
    /// (`first_terrain_seed`) rather than drawing them from the campaign seed.
    #[serde(default)]
    pub terrain_seeds: Option<[u64; 2]>,
    /// The slice these rows are, `i/n`, or `None` for a whole campaign.
    pub shard: Option<String>,
    /// Distinct trials (terrains) in the rows.
    pub terrains: usize,
    /// Runs (rows).
    pub runs: usize,
    /// One entry per navigator, in the campaign's order.
    pub navigators: Vec<NavigatorSummary>,
    /// Success by rock abundance.
    pub by_rock_abundance: Vec<RockBin>,
    /// Runs that did not succeed.
    pub failures: Vec<Failure>,
    /// DEM missions left out, one line each.
    pub skipped: Vec<String>,
    /// Fault drills by kind (campaigns with `[[faults]]`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub faults: Vec<FaultSummary>,
}

/// How fault protection met one kind of injected fault.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FaultSummary {
    /// The `[[faults]]` kind and what it names (`silent_sensor:mast`).
    pub kind: String,
    /// Runs planned with this fault.
    pub runs: usize,
    /// Runs where it struck (the others ended before its command).
    pub injected: usize,
    /// Of those, runs where fault protection acted after it.
    pub detected: usize,
    /// Of those, runs where the rover was stopped (`help_requested`).
    pub stopped_safely: usize,
    /// Hazard contacts after the fault, over all runs.
    pub contacts_after_fault: u64,
    /// Median simulated time from the fault to the stop (s).
    pub time_to_detect_median_s: Option<f64>,
    /// Longest time from the fault to the stop (s).
    pub time_to_detect_max_s: Option<f64>,
}

fn fault_summaries(rows: &[&Row]) -> Vec<FaultSummary> {
    let mut kinds: Vec<&str> = rows.iter().filter_map(|r| r.fault.as_deref()).collect();
    kinds.sort_unstable();
    kinds.dedup();
    kinds
        .into_iter()
        .map(|kind| {
            let mine: Vec<&&Row> = rows.iter().filter(|r| r.fault.as_deref() == Some(kind)).collect();
            let times: Vec<f64> = mine.iter().filter_map(|r| r.time_to_detect_s).collect();
            FaultSummary {
                kind: kind.to_string(),
                runs: mine.len(),
                injected: mine.iter().filter(|r| r.fault_time_s.is_some()).count(),
                detected: mine.iter().filter(|r| r.fault_detected == Some(true)).count(),
                stopped_safely: mine.iter().filter(|r| r.stopped_safely == Some(true)).count(),
                contacts_after_fault: mine
                    .iter()
                    .map(|r| u64::from(r.contacts_after_fault.unwrap_or(0)))
                    .sum(),
                time_to_detect_median_s: median(&times),
                time_to_detect_max_s: times.iter().copied().reduce(f64::max),
            }
        })
        .collect()
}

/// One navigator's figures.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct NavigatorSummary {
    /// Registry name.
    pub navigator: String,
    /// Runs.
    pub runs: usize,
    /// Runs that reached the goal with no hazard contact.
    pub successes: usize,
    /// successes / runs.
    pub success_rate: Option<f64>,
    /// 95 % Wilson score interval of the success rate.
    pub success_ci95: Option<[f64; 2]>,
    /// Runs whose outcome is `reached` (hazard contacts or not).
    pub reached: usize,
    /// reached / runs.
    pub reached_rate: Option<f64>,
    /// Hazard contacts over all runs.
    pub hazard_contacts: u64,
    /// Runs with at least one hazard contact.
    pub runs_with_hazard_contact: usize,
    /// Runs per outcome.
    pub outcomes: BTreeMap<String, usize>,
    /// Runs with a path ratio (reached, with an optimal length).
    pub path_ratio_runs: usize,
    /// Mean of distance driven / optimal length.
    pub path_ratio_mean: Option<f64>,
    /// Median of the path ratio (the mean of the two middle values for an even count): a few
    /// long detours set the mean.
    pub path_ratio_median: Option<f64>,
    /// 95th percentile (nearest rank) of the path ratio.
    pub path_ratio_p95: Option<f64>,
    /// Range images per metre driven (totals over all runs).
    pub sensing_per_m: Option<f64>,
    /// Mean final distance to the goal (m).
    pub goal_error_mean_m: Option<f64>,
    /// Mean final localisation error (m).
    pub localization_error_mean_m: Option<f64>,
    /// Mean navigator cycles per run.
    pub cycles_mean: Option<f64>,
}

/// Success counts of the trials whose rock abundance lies in [lo, hi].
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RockBin {
    /// Lower bound of the bin (equal to `hi` for a single value).
    pub lo: f64,
    /// Upper bound.
    pub hi: f64,
    /// Trials in the bin.
    pub terrains: usize,
    /// (runs, successes) per navigator, in the campaign's order.
    pub per_navigator: Vec<[usize; 2]>,
}

/// A run that did not succeed.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Failure {
    /// Trial index.
    pub trial: usize,
    /// Navigator.
    pub navigator: String,
    /// Outcome.
    pub outcome: String,
    /// Hazard contacts.
    pub hazard_contacts: u32,
    /// `yard` or the DEM mission's name.
    pub terrain: String,
    /// Terrain seed.
    pub seed: u64,
    /// Rock abundance.
    pub rock_abundance: f64,
    /// Slope (deg), yards only.
    pub slope_deg: Option<f64>,
    /// Traverse picture, relative to the output folder.
    pub picture: String,
    /// Why it failed: the first hazard contact's description if there was one, else the
    /// report's message.
    #[serde(default)]
    pub why: String,
}

/// Wall-clock figures, which vary from machine to machine and run to run.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MachineSummary {
    /// Compute per cycle by stage for each navigator (total stage time over total cycles).
    pub compute_per_cycle: Vec<NavigatorCompute>,
    /// Sum of the runs' wall-clock times (s).
    pub run_wall_time_s: f64,
}

/// One navigator's compute per cycle.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct NavigatorCompute {
    /// Registry name.
    pub navigator: String,
    /// Navigator step: perception, mapping and planning (s per cycle).
    pub navigation_s: f64,
    /// Localiser update (s per cycle).
    pub localization_s: f64,
    /// Platform (simulator) execution and sensing (s per cycle).
    pub platform_s: f64,
    /// Sum of the runs' wall-clock times (s).
    pub wall_time_s: f64,
}

/// Most distinct rock abundances shown one per bin; more are grouped into equal-width bins.
const MAX_VALUE_BINS: usize = 8;
/// Bins used when the rock abundances are too many to show one by one.
const RANGE_BINS: usize = 6;

/// Summarises rows (in any order) of the campaign `meta` describes.
pub fn summarise(meta: &CampaignMeta, rows: &[Row]) -> (Summary, MachineSummary) {
    let nav_pos = |name: &str| meta.navigators.iter().position(|n| n == name).unwrap_or(usize::MAX);
    let mut rows: Vec<&Row> = rows.iter().collect();
    rows.sort_by_key(|r| (r.trial, nav_pos(&r.navigator)));
    let mut navigators = Vec::new();
    let mut compute = Vec::new();
    for name in &meta.navigators {
        let mine: Vec<&Row> = rows.iter().copied().filter(|r| &r.navigator == name).collect();
        navigators.push(navigator_summary(name, &mine));
        compute.push(navigator_compute(name, &mine));
    }
    let mut terrains: Vec<usize> = rows.iter().map(|r| r.trial).collect();
    terrains.dedup();
    let failures = rows
        .iter()
        .filter(|r| r.failed())
        .map(|r| Failure {
            trial: r.trial,
            navigator: r.navigator.clone(),
            outcome: r.outcome.clone(),
            hazard_contacts: r.hazard_contacts,
            terrain: r.terrain.clone(),
            seed: r.seed,
            rock_abundance: r.rock_abundance,
            slope_deg: r.slope_deg,
            picture: format!("failures/{}", r.picture_name()),
            why: r.why(),
        })
        .collect();
    let summary = Summary {
        campaign: meta.spec.name.clone(),
        seed: meta.spec.seed,
        terrain_seeds: meta
            .spec
            .first_terrain_seed
            .filter(|_| meta.spec.trials > 0)
            .map(|first| [first, first + meta.spec.trials as u64 - 1]),
        shard: meta.shard.map(|s| s.to_string()),
        terrains: terrains.len(),
        runs: rows.len(),
        navigators,
        by_rock_abundance: rock_bins(&meta.navigators, &rows),
        failures,
        skipped: meta.skipped.clone(),
        faults: fault_summaries(&rows),
    };
    let machine = MachineSummary {
        run_wall_time_s: rows.iter().map(|r| r.wall_time_s).sum(),
        compute_per_cycle: compute,
    };
    (summary, machine)
}

fn navigator_summary(name: &str, rows: &[&Row]) -> NavigatorSummary {
    let runs = rows.len();
    let successes = rows.iter().filter(|r| r.success).count();
    let reached = rows.iter().filter(|r| r.outcome == "reached").count();
    let rate = |k: usize| (runs > 0).then(|| k as f64 / runs as f64);
    let mut outcomes = BTreeMap::new();
    for r in rows {
        *outcomes.entry(r.outcome.clone()).or_insert(0) += 1;
    }
    let ratios: Vec<f64> = rows.iter().filter_map(|r| r.path_ratio).collect();
    let driven: f64 = rows.iter().map(|r| r.distance_driven_m).sum();
    let sensed: u64 = rows.iter().map(|r| r.sensing_actions).sum();
    NavigatorSummary {
        navigator: name.into(),
        runs,
        successes,
        success_rate: rate(successes),
        success_ci95: wilson(successes, runs, Z95),
        reached,
        reached_rate: rate(reached),
        hazard_contacts: rows.iter().map(|r| u64::from(r.hazard_contacts)).sum(),
        runs_with_hazard_contact: rows.iter().filter(|r| r.hazard_contacts > 0).count(),
        outcomes,
        path_ratio_runs: ratios.len(),
        path_ratio_mean: mean(ratios.iter().copied()),
        path_ratio_median: median(&ratios),
        path_ratio_p95: percentile(&ratios, 0.95),
        sensing_per_m: (driven > 0.0).then(|| sensed as f64 / driven),
        goal_error_mean_m: mean(rows.iter().map(|r| r.goal_error_m)),
        localization_error_mean_m: mean(rows.iter().map(|r| r.localization_error_m)),
        cycles_mean: mean(rows.iter().map(|r| r.cycles as f64)),
    }
}

fn navigator_compute(name: &str, rows: &[&Row]) -> NavigatorCompute {
    let cycles: f64 = rows.iter().map(|r| r.cycles as f64).sum::<f64>().max(1.0);
    let total = |f: fn(&Row) -> f64| rows.iter().map(|r| f(r) * r.cycles as f64).sum::<f64>() / cycles;
    NavigatorCompute {
        navigator: name.into(),
        navigation_s: total(|r| r.compute_per_cycle.navigation_s),
        localization_s: total(|r| r.compute_per_cycle.localization_s),
        platform_s: total(|r| r.compute_per_cycle.platform_s),
        wall_time_s: rows.iter().map(|r| r.wall_time_s).sum(),
    }
}

/// Bins of rock abundance: one per distinct value when there are few, else equal-width bins.
fn rock_bins(navigators: &[String], rows: &[&Row]) -> Vec<RockBin> {
    let mut values: Vec<f64> = rows.iter().map(|r| r.rock_abundance).collect();
    values.sort_by(f64::total_cmp);
    values.dedup();
    let bounds: Vec<(f64, f64)> = if values.len() <= MAX_VALUE_BINS {
        values.iter().map(|v| (*v, *v)).collect()
    } else {
        let (lo, hi) = (values[0], values[values.len() - 1]);
        let w = (hi - lo) / RANGE_BINS as f64;
        (0..RANGE_BINS)
            .map(|i| (lo + w * i as f64, if i + 1 == RANGE_BINS { hi } else { lo + w * (i + 1) as f64 }))
            .collect()
    };
    let last = bounds.len().saturating_sub(1);
    let in_bin = |i: usize, v: f64| {
        let (lo, hi) = bounds[i];
        v >= lo && (v < hi || (i == last && v <= hi) || lo == hi && v == hi)
    };
    (0..bounds.len())
        .map(|i| {
            let inside: Vec<&&Row> = rows.iter().filter(|r| in_bin(i, r.rock_abundance)).collect();
            let mut trials: Vec<usize> = inside.iter().map(|r| r.trial).collect();
            trials.sort_unstable();
            trials.dedup();
            let per_navigator = navigators
                .iter()
                .map(|n| {
                    let mine = inside.iter().filter(|r| &r.navigator == n);
                    [mine.clone().count(), mine.filter(|r| r.success).count()]
                })
                .collect();
            RockBin { lo: bounds[i].0, hi: bounds[i].1, terrains: trials.len(), per_navigator }
        })
        .collect()
}

/// The heading that starts the machine-dependent part of `summary.md`.
pub const MACHINE_HEADING: &str = "## Compute per cycle (machine-dependent)";

fn pct(v: Option<f64>) -> String {
    v.map_or("–".into(), |v| format!("{:.1} %", 100.0 * v))
}

fn num(v: Option<f64>, digits: usize) -> String {
    v.map_or("–".into(), |v| format!("{v:.digits$}"))
}

impl Summary {
    /// The main table, one row per navigator (deterministic).
    pub fn main_table(&self) -> String {
        let mut s = String::from(
            "| navigator | runs | success (95 % CI) | reached | hazard contacts | path ratio mean | path ratio median | path ratio p95 | sensing / m | goal error mean (m) | loc. error mean (m) | cycles mean | outcomes |\n\
             |---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|\n",
        );
        for n in &self.navigators {
            let ci =
                n.success_ci95.map_or("–".into(), |[a, b]| format!("{:.0}–{:.0} %", 100.0 * a, 100.0 * b));
            let outcomes: Vec<String> = n.outcomes.iter().map(|(k, v)| format!("{k} {v}")).collect();
            let _ = writeln!(
                s,
                "| {} | {} | {} ({}) | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                n.navigator,
                n.runs,
                pct(n.success_rate),
                ci,
                pct(n.reached_rate),
                n.hazard_contacts,
                num(n.path_ratio_mean, 3),
                num(n.path_ratio_median, 3),
                num(n.path_ratio_p95, 3),
                num(n.sensing_per_m, 2),
                num(n.goal_error_mean_m, 2),
                num(n.localization_error_mean_m, 2),
                num(n.cycles_mean, 1),
                outcomes.join(", "),
            );
        }
        s
    }

    /// Success by rock abundance, one column per navigator (deterministic).
    pub fn rock_table(&self) -> String {
        let mut s = String::from("| rock abundance | terrains |");
        for n in &self.navigators {
            let _ = write!(s, " {} |", n.navigator);
        }
        s.push_str("\n|---|---:|");
        s.push_str(&"---:|".repeat(self.navigators.len()));
        s.push('\n');
        for b in &self.by_rock_abundance {
            let label =
                if b.lo == b.hi { format!("{:.3}", b.lo) } else { format!("{:.3}–{:.3}", b.lo, b.hi) };
            let _ = write!(s, "| {label} | {} |", b.terrains);
            for [runs, ok] in &b.per_navigator {
                let _ = write!(s, " {ok}/{runs} |");
            }
            s.push('\n');
        }
        s
    }

    /// The fault drills' table: for each kind, how often fault protection saw it and stopped
    /// the rover, how fast, and the hazard contacts after it.
    pub fn fault_table(&self) -> String {
        let mut s = String::from(
            "\n## Fault drills\n\nA drill fails when the fault struck and the rover was not stopped (`help_requested`) \
             or met a hazard after it. Time to detect: simulated seconds from the fault to fault protection's stop.\n\n\
             | fault | runs | struck | detected | stopped safely | contacts after | time to detect, median (s) | max (s) |\n\
             |---|---:|---:|---:|---:|---:|---:|---:|\n",
        );
        let share = |k: usize, n: usize| {
            if n == 0 { "-".to_string() } else { format!("{k} ({:.0} %)", 100.0 * k as f64 / n as f64) }
        };
        for f in &self.faults {
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {} | {} | {} |",
                f.kind,
                f.runs,
                f.injected,
                share(f.detected, f.injected),
                share(f.stopped_safely, f.injected),
                f.contacts_after_fault,
                num(f.time_to_detect_median_s, 1),
                num(f.time_to_detect_max_s, 1)
            );
        }
        s
    }

    /// The deterministic part of `summary.md`.
    pub fn markdown(&self) -> String {
        let mut s = format!(
            "# Campaign `{}` (seed {}{}{})\n\n{} terrains, {} runs. Success: outcome `reached` with 0 hazard contacts; \
             95 % interval: Wilson score. Path ratio: distance driven / optimal length (Field D* on the true \
             terrain), over reached runs. Sensing / m: range images per metre driven.\n\n",
            self.campaign,
            self.seed,
            self.terrain_seeds.map_or(String::new(), |[a, b]| format!(", terrain seeds {a}-{b}")),
            self.shard.as_ref().map_or(String::new(), |s| format!(", shard {s}")),
            self.terrains,
            self.runs,
        );
        s.push_str(&self.main_table());
        s.push_str("\n## Success by rock abundance\n\n");
        s.push_str(&self.rock_table());
        s.push_str("\nPlots: [success against rock abundance](plots/success_vs_rock_abundance.svg), ");
        s.push_str("[path ratio distribution](plots/path_ratio.svg).\n");
        if !self.faults.is_empty() {
            s.push_str(&self.fault_table());
        }
        if !self.skipped.is_empty() {
            s.push_str("\n## Skipped\n\n");
            for line in &self.skipped {
                let _ = writeln!(s, "- {line}");
            }
        }
        if !self.failures.is_empty() {
            s.push_str("\n## Failed runs\n\nRerun a yard trial with `rovernav run failures/trial-NNNN.toml --navigator NAME`.\n\n");
            s.push_str("| trial | navigator | outcome | hazard contacts | terrain | seed | rock abundance | slope (deg) | picture | why |\n");
            s.push_str("|---:|---|---|---:|---|---:|---:|---:|---|---|\n");
            for f in &self.failures {
                let _ = writeln!(
                    s,
                    "| {} | {} | {} | {} | {} | {} | {:.3} | {} | [png]({}) | {} |",
                    f.trial,
                    f.navigator,
                    f.outcome,
                    f.hazard_contacts,
                    f.terrain,
                    f.seed,
                    f.rock_abundance,
                    num(f.slope_deg, 1),
                    f.picture,
                    markdown_cell(&f.why)
                );
            }
        }
        s
    }
}

impl MachineSummary {
    /// The compute table, clearly labelled as machine-dependent.
    pub fn markdown(&self) -> String {
        let mut s = format!(
            "{MACHINE_HEADING}\n\nWall-clock milliseconds per navigator cycle by stage; varies with the machine and its load.\n\n\
             | navigator | navigation (ms) | localisation (ms) | platform (ms) | run wall time (s) |\n|---|---:|---:|---:|---:|\n"
        );
        for c in &self.compute_per_cycle {
            let _ = writeln!(
                s,
                "| {} | {:.2} | {:.3} | {:.2} | {:.1} |",
                c.navigator,
                1e3 * c.navigation_s,
                1e3 * c.localization_s,
                1e3 * c.platform_s,
                c.wall_time_s
            );
        }
        let _ = writeln!(s, "\nSum of run wall times: {:.1} s.", self.run_wall_time_s);
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::row::tests::row;
    use crate::spec::CampaignSpec;

    #[test]
    fn wilson_matches_the_formula_worked_by_hand() {
        // 8 of 10, z = 1.96: centre (0.8 + 0.19208) / 1.38416 = 0.716737;
        // half 1.96 / 1.38416 * sqrt(0.016 + 0.009604) = 0.226581; the textbook [0.4902, 0.9433].
        let [lo, hi] = wilson(8, 10, 1.96).unwrap();
        assert!((lo - 0.490156).abs() < 1e-5 && (hi - 0.943318).abs() < 1e-5, "{lo} {hi}");
        // 0 of 10: lower bound 0, upper z^2 / (n + z^2) = 3.8416 / 13.8416.
        let [lo, hi] = wilson(0, 10, 1.96).unwrap();
        assert!(lo.abs() < 1e-12 && (hi - 3.8416 / 13.8416).abs() < 1e-12);
        // All successes mirror no successes.
        let [lo, hi] = wilson(10, 10, 1.96).unwrap();
        assert!((lo - 10.0 / 13.8416).abs() < 1e-12 && (hi - 1.0).abs() < 1e-12);
        assert!(wilson(0, 0, Z95).is_none());
        // Large n approaches the normal interval p +- z sqrt(p(1-p)/n).
        let [lo, hi] = wilson(50_000, 100_000, Z95).unwrap();
        let half = Z95 * (0.25f64 / 100_000.0).sqrt();
        assert!((lo - (0.5 - half)).abs() < 1e-5 && (hi - (0.5 + half)).abs() < 1e-5);
    }

    #[test]
    fn p95_is_the_nearest_rank() {
        let v: Vec<f64> = (1..=20).rev().map(f64::from).collect();
        // ceil(0.95 * 20) = 19th smallest.
        assert_eq!(percentile(&v, 0.95), Some(19.0));
        assert_eq!(percentile(&[3.0, 1.0, 2.0], 0.95), Some(3.0));
        assert_eq!(percentile(&[5.0], 0.95), Some(5.0));
        assert_eq!(percentile(&[4.0, 1.0, 3.0, 2.0], 0.5), Some(2.0));
        assert_eq!(percentile(&[], 0.95), None);
    }

    fn meta(navs: &[&str]) -> CampaignMeta {
        let spec = CampaignSpec::from_toml("name = \"t\"\nseed = 4", "t").unwrap();
        CampaignMeta {
            spec,
            navigators: navs.iter().map(|s| s.to_string()).collect(),
            trials: vec![],
            skipped: vec![],
            shard: None,
            jobs: 0,
        }
    }

    fn sample_rows() -> Vec<Row> {
        let mut rows = Vec::new();
        for t in 0..9 {
            rows.push(row(
                t,
                "nat",
                if t % 4 == 3 { "timeout" } else { "reached" },
                (t == 5) as u32,
                10.0 + t as f64,
            ));
            rows.push(row(
                t,
                "sr2",
                if t % 3 == 0 { "help_requested" } else { "reached" },
                0,
                11.0 + 0.37 * t as f64,
            ));
        }
        rows
    }

    #[test]
    fn navigator_figures_follow_their_definitions() {
        let (s, _) = summarise(&meta(&["nat", "sr2"]), &sample_rows());
        let nat = &s.navigators[0];
        // Trials 3 and 7 time out; trial 5 reaches with a hazard contact.
        assert_eq!((nat.runs, nat.reached, nat.successes, nat.hazard_contacts), (9, 7, 6, 1));
        assert_eq!(nat.success_ci95, wilson(6, 9, Z95));
        assert_eq!(nat.outcomes.get("timeout"), Some(&2));
        // Ratios of the reached trials 0,1,2,4,5,6,8: (10 + t) / 10.
        let ratios = [1.0, 1.1, 1.2, 1.4, 1.5, 1.6, 1.8];
        assert!((nat.path_ratio_mean.unwrap() - ratios.iter().sum::<f64>() / 7.0).abs() < 1e-12);
        assert!((nat.path_ratio_p95.unwrap() - 1.8).abs() < 1e-12);
        assert!((nat.path_ratio_median.unwrap() - 1.4).abs() < 1e-12);
        let cells: Vec<usize> = s.main_table().lines().map(|l| l.matches('|').count()).collect();
        assert!(cells.iter().all(|&c| c == cells[0]) && cells.len() == 4, "{cells:?}");
        // An even count takes the mean of the two middle values.
        assert_eq!(median(&[1.6, 1.0, 1.2, 3.0]), Some(1.4));
        assert_eq!(median(&[]), None);
        // 7 range images per run over 90 + 36 m.
        assert!((nat.sensing_per_m.unwrap() - 63.0 / 126.0).abs() < 1e-12);
        assert_eq!(s.failures.len(), 3 + 3);
        // Why each failed: the first contact, else the run's own message.
        let why =
            |trial: usize| &s.failures.iter().find(|f| f.navigator == "nat" && f.trial == trial).unwrap().why;
        assert_eq!(why(5), "hazard: step of 0.180 m at wheel 0");
        assert_eq!(why(3), "timeout, after all");
        assert_eq!(s.terrains, 9);
        // Three rock values (0.05, 0.1, 0.2), three trials each.
        assert_eq!(s.by_rock_abundance.len(), 3);
        assert!(s.by_rock_abundance.iter().all(|b| b.terrains == 3 && b.per_navigator[0][0] == 3));
    }

    #[test]
    fn shuffled_rows_give_the_same_summary() {
        let rows = sample_rows();
        let m = meta(&["nat", "sr2"]);
        let (a, _) = summarise(&m, &rows);
        let mut shuffled = rows.clone();
        // A fixed permutation that moves every row (17 is coprime to 18).
        shuffled = (0..rows.len()).map(|i| shuffled[(i * 17 + 5) % rows.len()].clone()).collect();
        assert_ne!(shuffled, rows);
        let (b, _) = summarise(&m, &shuffled);
        assert_eq!(serde_json::to_string(&a).unwrap(), serde_json::to_string(&b).unwrap());
        assert_eq!(a.markdown(), b.markdown());
    }

    #[test]
    fn many_rock_values_are_binned_by_range() {
        let rows: Vec<Row> = (0..30)
            .map(|t| {
                let mut r = row(t, "nat", "reached", 0, 10.0);
                r.rock_abundance = 0.01 * t as f64;
                r
            })
            .collect();
        let (s, _) = summarise(&meta(&["nat"]), &rows);
        assert_eq!(s.by_rock_abundance.len(), RANGE_BINS);
        assert_eq!(s.by_rock_abundance.iter().map(|b| b.terrains).sum::<usize>(), 30);
    }

    #[test]
    fn compute_is_total_time_over_total_cycles() {
        let mut rows = vec![row(0, "nat", "reached", 0, 10.0), row(1, "nat", "reached", 0, 10.0)];
        rows[0].cycles = 10;
        rows[0].compute_per_cycle.navigation_s = 0.1;
        rows[1].cycles = 30;
        rows[1].compute_per_cycle.navigation_s = 0.3;
        let (_, m) = summarise(&meta(&["nat"]), &rows);
        assert!((m.compute_per_cycle[0].navigation_s - (1.0 + 9.0) / 40.0).abs() < 1e-12);
    }

    #[test]
    fn the_failed_runs_table_keeps_its_columns_whatever_the_message() {
        let mut rows = vec![row(0, "nat", "timeout", 0, 10.0), row(1, "nat", "reached", 0, 10.0)];
        rows[0].message = "stuck | twice\nat (3, 4)".into();
        let (s, _) = summarise(&meta(&["nat"]), &rows);
        let md = s.markdown();
        let table: Vec<&str> = md
            .lines()
            .skip_while(|l| !l.starts_with("## Failed runs"))
            .filter(|l| l.starts_with('|'))
            .collect();
        assert_eq!(table.len(), 3, "{md}");
        let cells = |l: &str| l.replace("\\|", "").matches('|').count();
        assert!(table.iter().all(|l| cells(l) == cells(table[0])), "{table:?}");
        assert!(table[2].contains("stuck \\| twice at (3, 4)"), "{}", table[2]);
    }
}
