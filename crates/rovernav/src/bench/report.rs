//! `rovernav bench report`: every hot path against the baseline a user would otherwise pick,
//! both timed in this process, alternating, best time of each kept (on a shared machine only
//! a ratio measured in one run means anything). The workloads are in [`super::workloads`];
//! this module holds the row type, the table and the file it writes.

use serde::Serialize;
use std::time::Instant;

/// One workload's comparison (the JSON contract of issue 43: `workload`, `rovernav_s`,
/// `baseline`, `baseline_s`, `speedup`, and where they apply `rovernav_cost`, `baseline_cost`).
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    /// Workload name (`astar-map1000`, ...).
    pub workload: &'static str,
    /// What rovernav runs.
    pub rovernav: String,
    /// rovernav's best wall time (s).
    pub rovernav_s: f64,
    /// What the baseline is.
    pub baseline: String,
    /// The baseline's best wall time (s), measured in the same run.
    pub baseline_s: f64,
    /// `baseline_s / rovernav_s`.
    pub speedup: f64,
    /// Path cost (planners) or score (matchers) rovernav found.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rovernav_cost: Option<f64>,
    /// The baseline's cost or score.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub baseline_cost: Option<f64>,
    /// What limits the figure.
    pub limits: String,
    /// Workload-specific figures (expansions, ns per cell, stages, ...).
    pub details: serde_json::Value,
}

impl Row {
    /// A row from the two times; costs and details empty.
    pub fn timed(
        workload: &'static str,
        rovernav: &str,
        baseline: &str,
        times: (f64, f64),
        limits: &str,
    ) -> Self {
        Self {
            workload,
            rovernav: rovernav.into(),
            rovernav_s: times.0,
            baseline: baseline.into(),
            baseline_s: times.1,
            speedup: times.1 / times.0.max(1e-12),
            rovernav_cost: None,
            baseline_cost: None,
            limits: limits.into(),
            details: serde_json::json!({}),
        }
    }

    /// Sets both costs.
    pub fn costs(mut self, rovernav: f64, baseline: f64) -> Self {
        self.rovernav_cost = Some(rovernav);
        self.baseline_cost = Some(baseline);
        self
    }

    /// Sets the details.
    pub fn details(mut self, details: serde_json::Value) -> Self {
        self.details = details;
        self
    }
}

/// Best wall times of `ours` and `base` over `reps` alternating runs, with each one's last
/// output.
pub fn alternate<A, B>(
    reps: usize,
    mut ours: impl FnMut() -> A,
    mut base: impl FnMut() -> B,
) -> ((f64, f64), A, B) {
    let (mut to, mut tb) = (f64::INFINITY, f64::INFINITY);
    let (mut a, mut b) = (None, None);
    for _ in 0..reps.max(1) {
        let t0 = Instant::now();
        a = Some(std::hint::black_box(ours()));
        to = to.min(t0.elapsed().as_secs_f64());
        let t0 = Instant::now();
        b = Some(std::hint::black_box(base()));
        tb = tb.min(t0.elapsed().as_secs_f64());
    }
    ((to, tb), a.expect("ran at least once"), b.expect("ran at least once"))
}

/// The whole report.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// The command line that produced it.
    pub command: String,
    /// `git describe --always --dirty` of the source tree the binary was built from, or
    /// `unknown`.
    pub revision: String,
    /// Whether the quick versions ran.
    pub quick: bool,
    /// The rows, in the contract's order.
    pub rows: Vec<Row>,
}

/// The revision of the source tree this binary was built from (`git describe --always
/// --dirty` in it), or `unknown` when that tree or git is gone.
pub fn git_revision() -> String {
    std::process::Command::new("git")
        .args(["-C", env!("CARGO_MANIFEST_DIR"), "describe", "--always", "--dirty", "--abbrev=10"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .and_then(|o| String::from_utf8(o.stdout).ok())
        .map(|s| s.trim().to_string())
        .filter(|s| !s.is_empty())
        .unwrap_or_else(|| "unknown".into())
}

fn seconds(s: f64) -> String {
    if s >= 1.0 {
        format!("{s:.2} s")
    } else if s >= 1e-3 {
        format!("{:.2} ms", s * 1e3)
    } else {
        format!("{:.1} us", s * 1e6)
    }
}

fn cost(c: Option<f64>) -> String {
    c.map_or_else(
        || "-".into(),
        |v| format!("{v:.6}").trim_end_matches('0').trim_end_matches('.').to_string(),
    )
}

/// The report as a Markdown document: command, revision, and the table.
pub fn markdown(report: &Report) -> String {
    let mut out = String::from("# Performance side by side\n\n");
    out += &format!(
        "Produced by `{}` at revision `{}` ({} versions). Each row times rovernav and its baseline \
         in the same process, alternating, and keeps each one's best time; speed-up = baseline time \
         / rovernav time. What each figure means and what limits it: docs/performance.md.\n\n",
        report.command,
        report.revision,
        if report.quick { "quick" } else { "full" }
    );
    out += "| workload | rovernav | time | baseline | time | speed-up | rovernav cost | baseline cost | limits |\n";
    out += "|---|---|---|---|---|---|---|---|---|\n";
    for r in &report.rows {
        out += &format!(
            "| {} | {} | {} | {} | {} | {:.2}x | {} | {} | {} |\n",
            r.workload,
            r.rovernav,
            seconds(r.rovernav_s),
            r.baseline,
            seconds(r.baseline_s),
            r.speedup,
            cost(r.rovernav_cost),
            cost(r.baseline_cost),
            r.limits
        );
    }
    if let Some(navigators) =
        report.rows.iter().find_map(|r| r.details.get("navigators")).and_then(|n| n.as_object())
    {
        out +=
            "\nCompute per cycle by stage on the default mission (ms; the report's `compute_per_cycle`):\n\n";
        out +=
            "| navigator | outcome | cycles | navigation | localisation | platform (simulator) | budget |\n";
        out += "|---|---|---|---|---|---|---|\n";
        for (name, v) in navigators {
            let ms = |k: &str| {
                v.get(k).and_then(|x| x.as_f64()).map_or_else(|| "-".into(), |x| format!("{:.2}", x * 1e3))
            };
            out += &format!(
                "| {name} | {} | {} | {} | {} | {} | {} |\n",
                v.get("outcome").and_then(|x| x.as_str()).unwrap_or("-"),
                v.get("cycles").map_or_else(|| "-".into(), |x| x.to_string()),
                ms("navigation_s"),
                ms("localization_s"),
                ms("platform_s"),
                ms("budget_s")
            );
        }
    }
    out += "\nDetails per row (JSON, as `--json` prints them):\n\n";
    for r in &report.rows {
        out += &format!("- `{}`: `{}`\n", r.workload, r.details);
    }
    out
}

/// The report as text for the terminal.
pub fn text(report: &Report) -> String {
    let mut out = format!("revision {}{}\n", report.revision, if report.quick { " (quick)" } else { "" });
    for r in &report.rows {
        out += &format!(
            "{:<26} rovernav {:>10}  {:<40} {:>10}  speed-up {:>7.2}x  costs {} / {}\n",
            r.workload,
            seconds(r.rovernav_s),
            r.baseline,
            seconds(r.baseline_s),
            r.speedup,
            cost(r.rovernav_cost),
            cost(r.baseline_cost)
        );
    }
    out
}
