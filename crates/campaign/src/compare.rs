//! Paired comparison of two sets of runs on the same terrains: a navigator against another, or
//! one navigator's variant against its baseline.
//!
//! Runs are paired by terrain (kind, name and seed), so each terrain's difficulty cancels out:
//! only terrains where the two sides disagree say anything. Whether they disagree more one way
//! than the other by chance is McNemar's exact test (a two-sided binomial test on the discordant
//! pairs at p = 1/2), for clean arrivals and for runs with hazard contacts.

use crate::CampaignError;
use crate::row::Row;
use crate::summary::markdown_cell;
use serde::Serialize;
use std::collections::BTreeMap;

/// One side's figures over the paired terrains.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SideFigures {
    /// Navigator registry name.
    pub navigator: String,
    /// Runs that reached the goal with no hazard contact.
    pub clean_arrivals: usize,
    /// Runs that reached the goal.
    pub reached: usize,
    /// Runs with at least one hazard contact.
    pub runs_with_contacts: usize,
    /// Runs with contacts per kilometre driven over all paired runs.
    pub contact_runs_per_km: f64,
    /// Mean driven / optimal length over the terrains both sides reached.
    pub mean_path_ratio_both_reached: Option<f64>,
    /// Range images per metre driven over all paired runs.
    pub sensing_per_m: f64,
    /// Runs per outcome.
    pub outcomes: BTreeMap<String, usize>,
}

/// A yes/no figure compared terrain by terrain.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PairedCount {
    /// Terrains where only side A has it.
    pub a_only: usize,
    /// Terrains where only side B has it.
    pub b_only: usize,
    /// McNemar's exact two-sided p-value: the chance of a split at least this uneven if either
    /// side were as likely to have it on a discordant terrain.
    pub p_value: f64,
}

/// The comparison of two sets of runs.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Comparison {
    /// Terrains both sides ran.
    pub paired: usize,
    /// Terrains only one side ran (left out).
    pub unpaired: usize,
    /// Side A.
    pub a: SideFigures,
    /// Side B.
    pub b: SideFigures,
    /// Clean arrivals, terrain by terrain.
    pub clean_arrivals: PairedCount,
    /// Runs with hazard contacts, terrain by terrain.
    pub runs_with_contacts: PairedCount,
    /// Terrains where one side failed to arrive cleanly and the other did not, A's failures
    /// first.
    pub discordant: Vec<DiscordantRun>,
}

/// A terrain where one side arrived cleanly and the other did not.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DiscordantRun {
    /// Terrain seed.
    pub seed: u64,
    /// `a` or `b`: the side that failed.
    pub failed: String,
    /// The failed run's outcome.
    pub outcome: String,
    /// Its first hazard contact, else its closing message.
    pub why: String,
}

/// McNemar's exact two-sided p-value for `b` and `c` discordant pairs: twice the binomial tail
/// of the smaller count at p = 1/2, at most 1.
pub fn mcnemar_exact(b: usize, c: usize) -> f64 {
    let n = b + c;
    if n == 0 {
        return 1.0;
    }
    let k = b.min(c);
    // ln C(n, i) accumulated term by term keeps large n finite.
    let mut ln_choose = 0.0;
    let mut tail = 0.0;
    for i in 0..=k {
        if i > 0 {
            ln_choose += ((n - i + 1) as f64).ln() - (i as f64).ln();
        }
        tail += (ln_choose - n as f64 * std::f64::consts::LN_2).exp();
    }
    (2.0 * tail).min(1.0)
}

type TerrainKey = (&'static str, String, u64);

fn key(row: &Row) -> TerrainKey {
    (row.terrain_kind.as_str(), row.terrain.clone(), row.seed)
}

/// The rows of one navigator, by terrain: `navigator` when given, else the only one there is.
fn by_terrain(
    rows: &[Row],
    navigator: Option<&str>,
    side: &str,
) -> Result<(String, BTreeMap<TerrainKey, Row>), CampaignError> {
    let mut names: Vec<&str> = rows.iter().map(|r| r.navigator.as_str()).collect();
    names.sort_unstable();
    names.dedup();
    let name = match navigator {
        Some(n) if names.contains(&n) => n.to_string(),
        Some(n) => {
            return Err(CampaignError::Compare(format!(
                "side {side}: no runs of navigator `{n}` (it has: {})",
                names.join(", ")
            )));
        }
        None if names.len() == 1 => names[0].to_string(),
        None => {
            return Err(CampaignError::Compare(format!(
                "side {side} holds several navigators ({}): choose one with --{side}-navigator",
                names.join(", ")
            )));
        }
    };
    let mut out = BTreeMap::new();
    for r in rows.iter().filter(|r| r.navigator == name) {
        if out.insert(key(r), r.clone()).is_some() {
            return Err(CampaignError::Compare(format!(
                "side {side}: terrain {} seed {} appears twice for `{name}`",
                r.terrain, r.seed
            )));
        }
    }
    Ok((name, out))
}

/// One side's figures over its paired `runs`; `ratios` are its path ratios on the terrains
/// both sides reached.
fn side_figures(navigator: String, runs: &[&Row], ratios: &[f64]) -> SideFigures {
    let km: f64 = runs.iter().map(|r| r.distance_driven_m).sum::<f64>() / 1000.0;
    let contacts = runs.iter().filter(|r| r.hazard_contacts > 0).count();
    let mut outcomes = BTreeMap::new();
    for r in runs {
        *outcomes.entry(r.outcome.clone()).or_insert(0) += 1;
    }
    let images: u64 = runs.iter().map(|r| r.sensing_actions).sum();
    SideFigures {
        navigator,
        clean_arrivals: runs.iter().filter(|r| r.success).count(),
        reached: runs.iter().filter(|r| r.outcome == "reached").count(),
        runs_with_contacts: contacts,
        contact_runs_per_km: if km > 0.0 { contacts as f64 / km } else { 0.0 },
        mean_path_ratio_both_reached: (!ratios.is_empty())
            .then(|| ratios.iter().sum::<f64>() / ratios.len() as f64),
        sensing_per_m: if km > 0.0 { images as f64 / (km * 1000.0) } else { 0.0 },
        outcomes,
    }
}

fn paired_count(pairs: &[(&Row, &Row)], has: impl Fn(&Row) -> bool) -> PairedCount {
    let a_only = pairs.iter().filter(|(a, b)| has(a) && !has(b)).count();
    let b_only = pairs.iter().filter(|(a, b)| !has(a) && has(b)).count();
    PairedCount { a_only, b_only, p_value: mcnemar_exact(a_only, b_only) }
}

/// Compares side A's runs of `a_navigator` (or its only navigator) with side B's, terrain by
/// terrain.
pub fn compare(
    a_rows: &[Row],
    a_navigator: Option<&str>,
    b_rows: &[Row],
    b_navigator: Option<&str>,
) -> Result<Comparison, CampaignError> {
    let (a_name, a) = by_terrain(a_rows, a_navigator, "a")?;
    let (b_name, b) = by_terrain(b_rows, b_navigator, "b")?;
    let pairs: Vec<(&Row, &Row)> = a.iter().filter_map(|(k, ra)| b.get(k).map(|rb| (ra, rb))).collect();
    if pairs.is_empty() {
        return Err(CampaignError::Compare("the two sides share no terrain".into()));
    }
    let unpaired = a.len() + b.len() - 2 * pairs.len();
    let (a_ratios, b_ratios): (Vec<f64>, Vec<f64>) =
        pairs.iter().filter_map(|(ra, rb)| Some((ra.path_ratio?, rb.path_ratio?))).unzip();
    let a_runs: Vec<&Row> = pairs.iter().map(|(ra, _)| *ra).collect();
    let b_runs: Vec<&Row> = pairs.iter().map(|(_, rb)| *rb).collect();
    let mut discordant = Vec::new();
    for (side, failed, other) in [("a", 0, 1), ("b", 1, 0)] {
        for pair in &pairs {
            let runs = [pair.0, pair.1];
            if !runs[failed].success && runs[other].success {
                discordant.push(DiscordantRun {
                    seed: runs[failed].seed,
                    failed: side.to_string(),
                    outcome: runs[failed].outcome.clone(),
                    why: runs[failed].why(),
                });
            }
        }
    }
    Ok(Comparison {
        paired: pairs.len(),
        unpaired,
        a: side_figures(a_name, &a_runs, &a_ratios),
        b: side_figures(b_name, &b_runs, &b_ratios),
        clean_arrivals: paired_count(&pairs, |r| r.success),
        runs_with_contacts: paired_count(&pairs, |r| r.hazard_contacts > 0),
        discordant,
    })
}

impl Comparison {
    /// The comparison as a Markdown table and the discordant terrains.
    pub fn markdown(&self, a_label: &str, b_label: &str) -> String {
        let mut s = format!(
            "{} terrains paired{}\n\n| | A: {} ({a_label}) | B: {} ({b_label}) |\n|---|---|---|\n",
            self.paired,
            if self.unpaired > 0 {
                format!(" ({} run on one side only, left out)", self.unpaired)
            } else {
                String::new()
            },
            self.a.navigator,
            self.b.navigator,
        );
        let ratio = |r: Option<f64>| r.map_or("-".to_string(), |v| format!("{v:.3}"));
        let rows: [(&str, String, String); 6] = [
            ("clean arrivals", self.a.clean_arrivals.to_string(), self.b.clean_arrivals.to_string()),
            ("reached", self.a.reached.to_string(), self.b.reached.to_string()),
            (
                "runs with contacts",
                self.a.runs_with_contacts.to_string(),
                self.b.runs_with_contacts.to_string(),
            ),
            (
                "runs with contacts per km",
                format!("{:.2}", self.a.contact_runs_per_km),
                format!("{:.2}", self.b.contact_runs_per_km),
            ),
            (
                "mean path ratio (both reached)",
                ratio(self.a.mean_path_ratio_both_reached),
                ratio(self.b.mean_path_ratio_both_reached),
            ),
            (
                "range images per m",
                format!("{:.2}", self.a.sensing_per_m),
                format!("{:.2}", self.b.sensing_per_m),
            ),
        ];
        for (name, a, b) in rows {
            s.push_str(&format!("| {name} | {a} | {b} |\n"));
        }
        for (name, c) in
            [("clean arrivals", &self.clean_arrivals), ("runs with contacts", &self.runs_with_contacts)]
        {
            s.push_str(&format!(
                "\n{name}: A only on {}, B only on {} terrains; McNemar exact p = {:.3}",
                c.a_only, c.b_only, c.p_value
            ));
        }
        s.push_str("\n\nTerrains where one side failed and the other arrived cleanly:\n\n");
        s.push_str("| seed | failed | outcome | why |\n|---|---|---|---|\n");
        for d in &self.discordant {
            s.push_str(&format!(
                "| {} | {} | {} | {} |\n",
                d.seed,
                d.failed.to_uppercase(),
                d.outcome,
                markdown_cell(&d.why)
            ));
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::row::tests::row;

    #[test]
    fn mcnemar_matches_the_binomial_tail() {
        // Six to none: 2 / 2^6.
        assert!((mcnemar_exact(0, 6) - 0.03125).abs() < 1e-12);
        assert!((mcnemar_exact(6, 0) - 0.03125).abs() < 1e-12);
        // One to nine: 2 (1 + 10) / 2^10.
        assert!((mcnemar_exact(1, 9) - 22.0 / 1024.0).abs() < 1e-12);
        // An even split, or nothing to split, says nothing.
        assert_eq!(mcnemar_exact(5, 5), 1.0);
        assert_eq!(mcnemar_exact(0, 0), 1.0);
        // Large counts stay finite: 200 vs 260 is about p = 0.006 (normal approximation).
        let p = mcnemar_exact(200, 260);
        assert!(p > 0.003 && p < 0.01, "{p}");
    }

    #[test]
    fn runs_pair_by_terrain_and_only_disagreements_count() {
        // Side A: terrains 0..6, clean except 1 (timeout) and 2 (contact). Side B: terrains
        // 1..7 (0 missing, 7 extra), clean except 4 (help requested).
        let a: Vec<Row> = (0..6)
            .map(|t| match t {
                1 => row(t, "roverbug", "timeout", 0, 50.0),
                2 => row(t, "roverbug", "reached", 1, 20.0),
                _ => row(t, "roverbug", "reached", 0, 12.0),
            })
            .collect();
        let b: Vec<Row> = (1..8)
            .map(|t| {
                if t == 4 {
                    row(t, "astar-grid", "help_requested", 0, 9.0)
                } else {
                    row(t, "astar-grid", "reached", 0, 15.0)
                }
            })
            .collect();
        let c = compare(&a, None, &b, None).unwrap();
        assert_eq!((c.paired, c.unpaired), (5, 3));
        assert_eq!((c.a.navigator.as_str(), c.b.navigator.as_str()), ("roverbug", "astar-grid"));
        // Terrains 1..5: A clean on 3, 4, 5; B clean on 1, 2, 3, 5.
        assert_eq!((c.a.clean_arrivals, c.b.clean_arrivals), (3, 4));
        assert_eq!((c.clean_arrivals.a_only, c.clean_arrivals.b_only), (1, 2));
        assert_eq!((c.runs_with_contacts.a_only, c.runs_with_contacts.b_only), (1, 0));
        assert_eq!(c.clean_arrivals.p_value, 1.0);
        let seeds: Vec<(u64, &str)> = c.discordant.iter().map(|d| (d.seed, d.failed.as_str())).collect();
        assert_eq!(seeds, vec![(101, "a"), (102, "a"), (104, "b")]);
        assert!(c.discordant[1].why.contains("step of 0.180 m"), "{:?}", c.discordant[1]);
        // Path ratio over the terrains both reached (2, 3, 5): A 20 / 10 and 12 / 10 twice.
        let a_ratio = c.a.mean_path_ratio_both_reached.unwrap();
        assert!((a_ratio - (2.0 + 1.2 + 1.2) / 3.0).abs() < 1e-9, "{a_ratio}");
        assert!((c.b.mean_path_ratio_both_reached.unwrap() - 1.5).abs() < 1e-9);
        // One contact run over 50 + 20 + 3 x 12 m = 106 m.
        assert!((c.a.contact_runs_per_km - 1.0 / 0.106).abs() < 1e-9);
        let table = c.markdown("left", "right");
        assert!(table.contains("| clean arrivals | 3 | 4 |"), "{table}");
        assert!(table.contains("| 104 | B | help_requested |"), "{table}");
    }

    #[test]
    fn a_side_with_several_navigators_must_name_one() {
        let rows = vec![row(0, "nat", "reached", 0, 10.0), row(0, "sr2", "reached", 0, 10.0)];
        let err = compare(&rows, None, &rows, Some("nat")).unwrap_err().to_string();
        assert!(err.contains("--a-navigator") && err.contains("nat, sr2"), "{err}");
        let err = compare(&rows, Some("gestalt"), &rows, Some("nat")).unwrap_err().to_string();
        assert!(err.contains("`gestalt`"), "{err}");
        let c = compare(&rows, Some("sr2"), &rows, Some("nat")).unwrap();
        assert_eq!(c.paired, 1);
        let other = vec![row(5, "nat", "reached", 0, 10.0)];
        assert!(compare(&rows, Some("nat"), &other, None).unwrap_err().to_string().contains("no terrain"));
    }
}
