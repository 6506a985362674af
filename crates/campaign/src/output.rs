//! The output folder of a campaign (or of one shard) and the merge of shard folders.
//!
//! A folder holds `campaign.json` (the resolved campaign and the shard), `rows.csv`,
//! `rows.jsonl`, `summary.json`, `summary.md`, `plots/*.svg` and `failures/` (a traverse
//! picture per failed run and a mission file per failed yard trial). Every file is written to a
//! temporary name and renamed, so a reader never sees half a file, except `rows.jsonl` while the
//! campaign runs: [`RowLog`] appends each row as its run ends (so a killed campaign keeps every
//! finished run), and the end of the campaign rewrites it sorted. A final line without its line
//! break is an append cut short and is left out when the folder is read.

use crate::plan::{Plan, Shard, TrialInfo};
use crate::row::{Row, from_jsonl, to_csv, to_jsonl};
use crate::spec::CampaignSpec;
use crate::summary::{MachineSummary, Summary, summarise};
use crate::{CampaignError, plots};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// `campaign.json`: what a folder's rows belong to, so that merge can check its inputs.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CampaignMeta {
    /// The spec with command-line overrides applied.
    pub spec: CampaignSpec,
    /// Navigator names, in table order.
    pub navigators: Vec<String>,
    /// Every trial of the whole campaign.
    pub trials: Vec<TrialInfo>,
    /// DEM missions left out.
    pub skipped: Vec<String>,
    /// The slice this folder holds, or `None` for the whole campaign.
    pub shard: Option<Shard>,
    /// Jobs of the whole campaign (trials x navigators).
    pub jobs: usize,
}

impl CampaignMeta {
    /// The meta of a plan run as `shard`.
    pub fn of(plan: &Plan, shard: Option<Shard>) -> Self {
        Self {
            spec: plan.spec.clone(),
            navigators: plan.navigators.clone(),
            trials: plan.trials.clone(),
            skipped: plan.skipped.clone(),
            shard,
            jobs: plan.trials.len() * plan.navigators.len(),
        }
    }

    /// The flat job index of a row, if its trial and navigator belong to this campaign.
    fn job_of(&self, row: &Row) -> Option<usize> {
        let nav = self.navigators.iter().position(|n| *n == row.navigator)?;
        (row.trial < self.trials.len()).then(|| row.trial * self.navigators.len() + nav)
    }
}

/// The JSON of `summary.json`: the deterministic summary and, apart, the wall-clock figures.
#[derive(Serialize, Deserialize)]
struct SummaryFile {
    summary: Summary,
    machine_dependent: MachineSummary,
}

/// Writes `path` through a temporary file and a rename.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), CampaignError> {
    let name = path.file_name().map(|n| n.to_string_lossy().to_string()).unwrap_or_default();
    // Unique per process and call: runs on several threads may write the same name at once.
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let tmp = path.with_file_name(format!(".{name}.{}-{n}.tmp", std::process::id()));
    std::fs::write(&tmp, bytes).map_err(|e| CampaignError::io(&tmp, e))?;
    std::fs::rename(&tmp, path).map_err(|e| CampaignError::io(path, e))
}

/// Creates `dir` and its `failures/` folder, removing pictures and mission files a previous
/// campaign left in `failures/` so the gallery only shows this campaign's failures.
pub fn prepare_dir(dir: &Path) -> Result<PathBuf, CampaignError> {
    let failures = dir.join("failures");
    std::fs::create_dir_all(&failures).map_err(|e| CampaignError::io(&failures, e))?;
    let entries = std::fs::read_dir(&failures).map_err(|e| CampaignError::io(&failures, e))?;
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().to_string();
        if name.starts_with("trial-") && (name.ends_with(".png") || name.ends_with(".toml")) {
            std::fs::remove_file(entry.path()).map_err(|e| CampaignError::io(&entry.path(), e))?;
        }
    }
    Ok(failures)
}

/// `rows.jsonl` while a campaign runs: `campaign.json` is written first, then each row is
/// appended (one `write` of one whole line) as its run ends.
pub struct RowLog {
    path: PathBuf,
    file: std::sync::Mutex<std::fs::File>,
    error: std::sync::Mutex<Option<CampaignError>>,
}

impl RowLog {
    /// Writes `dir/campaign.json` and starts an empty `dir/rows.jsonl`.
    pub fn start(dir: &Path, meta: &CampaignMeta) -> Result<Self, CampaignError> {
        write_atomic(&dir.join("campaign.json"), &pretty(meta))?;
        // A previous campaign's summary in this folder would describe other rows.
        for name in ["summary.json", "summary.md", "rows.csv"] {
            let _ = std::fs::remove_file(dir.join(name));
        }
        let path = dir.join("rows.jsonl");
        let file = std::fs::File::create(&path).map_err(|e| CampaignError::io(&path, e))?;
        Ok(Self { path, file: std::sync::Mutex::new(file), error: std::sync::Mutex::new(None) })
    }

    /// Appends one row (from any worker); the first failure is kept for [`RowLog::finish`].
    pub fn append(&self, row: &Row) {
        use std::io::Write;
        let mut line = serde_json::to_vec(row).expect("rows serialise");
        line.push(b'\n');
        let written = self.file.lock().expect("no append panics holding the lock").write_all(&line);
        if let Err(e) = written {
            self.error
                .lock()
                .expect("no append panics holding the lock")
                .get_or_insert(CampaignError::io(&self.path, e));
        }
    }

    /// The first append that failed, if any.
    pub fn finish(self) -> Result<(), CampaignError> {
        match self.error.into_inner().expect("appends have finished") {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }
}

/// Writes every file of the folder but `failures/` (the runner fills it) and returns the summary.
pub fn write_dir(
    dir: &Path,
    meta: &CampaignMeta,
    rows: &[Row],
) -> Result<(Summary, MachineSummary), CampaignError> {
    let plots_dir = dir.join("plots");
    std::fs::create_dir_all(&plots_dir).map_err(|e| CampaignError::io(&plots_dir, e))?;
    let mut rows = rows.to_vec();
    rows.sort_by_key(|r| meta.job_of(r));
    let (summary, machine) = summarise(meta, &rows);
    write_atomic(&dir.join("campaign.json"), &pretty(meta))?;
    write_atomic(&dir.join("rows.csv"), to_csv(&rows).as_bytes())?;
    write_atomic(&dir.join("rows.jsonl"), to_jsonl(&rows).as_bytes())?;
    let file = SummaryFile { summary, machine_dependent: machine };
    write_atomic(&dir.join("summary.json"), &pretty(&file))?;
    let md = format!("{}\n{}", file.summary.markdown(), file.machine_dependent.markdown());
    write_atomic(&dir.join("summary.md"), md.as_bytes())?;
    write_atomic(
        &plots_dir.join("success_vs_rock_abundance.svg"),
        plots::success_vs_rock_abundance(&file.summary).as_bytes(),
    )?;
    write_atomic(&plots_dir.join("path_ratio.svg"), plots::path_ratio(&file.summary, &rows).as_bytes())?;
    Ok((file.summary, file.machine_dependent))
}

/// `summary.json` as written.
pub fn summary_json(summary: &Summary, machine: &MachineSummary) -> String {
    let file = SummaryFile { summary: summary.clone(), machine_dependent: machine.clone() };
    String::from_utf8(pretty(&file)).expect("JSON is UTF-8")
}

/// Pretty JSON with a final line break.
fn pretty<T: Serialize>(value: &T) -> Vec<u8> {
    let mut bytes = serde_json::to_vec_pretty(value).expect("campaign outputs serialise");
    bytes.push(b'\n');
    bytes
}

/// Reads a folder's `campaign.json` and `rows.jsonl`, checking every row belongs to the folder's
/// campaign and slice and matches its trial's descriptors.
pub fn read_dir(dir: &Path) -> Result<(CampaignMeta, Vec<Row>), CampaignError> {
    let read = |name: &str| {
        let p = dir.join(name);
        std::fs::read_to_string(&p).map_err(|e| CampaignError::io(&p, e)).map(|t| (p, t))
    };
    let (meta_path, text) = read("campaign.json")?;
    let meta: CampaignMeta = serde_json::from_str(&text).map_err(|e| CampaignError::Parse {
        path: meta_path.display().to_string(),
        message: e.to_string(),
    })?;
    let (rows_path, text) = read("rows.jsonl")?;
    let shown = rows_path.display().to_string();
    // A last line without its line break is an append cut short by a kill: left out.
    let whole = if text.ends_with('\n') { &text[..] } else { &text[..text.rfind('\n').map_or(0, |i| i + 1)] };
    let rows = from_jsonl(whole, &shown)?;
    for (i, r) in rows.iter().enumerate() {
        let bad = |why: &str| CampaignError::Invalid {
            path: shown.clone(),
            field: format!("line {}", i + 1),
            message: format!("trial {} / {}: {why}", r.trial, r.navigator),
        };
        let job = meta.job_of(r).ok_or_else(|| bad("not a run of this campaign"))?;
        if meta.shard.is_some_and(|s| !s.contains(job)) {
            return Err(bad("not in this folder's shard"));
        }
        if r.trial_info() != meta.trials[r.trial] {
            return Err(bad("terrain descriptors differ from campaign.json"));
        }
    }
    Ok((meta, rows))
}

/// Joins shard folders into one campaign: checks they are slices of the same campaign, that no
/// run appears twice and that none is missing (with `partial`, missing runs, as a killed
/// campaign leaves, are a note saying which instead), copies their failure galleries into `out`,
/// and returns the whole campaign's meta and rows (to write with [`write_dir`]). Files it could
/// not copy are reported as notes.
pub fn merge_dirs(
    dirs: &[PathBuf],
    out: &Path,
    partial: bool,
) -> Result<(CampaignMeta, Vec<Row>, Vec<String>), CampaignError> {
    let Some(first_dir) = dirs.first() else {
        return Err(CampaignError::Merge("no folders given".into()));
    };
    let out_abs = std::path::absolute(out).map_err(|e| CampaignError::io(out, e))?;
    let mut parts = Vec::new();
    for d in dirs {
        if std::path::absolute(d).map_err(|e| CampaignError::io(d, e))? == out_abs {
            return Err(CampaignError::Merge(format!(
                "the output folder {} is one of the inputs; choose another --out",
                d.display()
            )));
        }
        parts.push(read_dir(d)?);
    }
    let (first, _) = &parts[0];
    let mut seen: BTreeMap<usize, &Path> = BTreeMap::new();
    for ((meta, rows), dir) in parts.iter().zip(dirs) {
        let differs = if meta.spec != first.spec {
            Some("campaign spec")
        } else if meta.navigators != first.navigators {
            Some("navigators")
        } else if meta.trials != first.trials {
            Some("trials")
        } else if meta.skipped != first.skipped {
            Some("skipped DEM missions")
        } else {
            None
        };
        if let Some(what) = differs {
            return Err(CampaignError::Merge(format!(
                "{} and {} are not slices of the same campaign ({what} differ)",
                first_dir.display(),
                dir.display()
            )));
        }
        for r in rows {
            let job = meta.job_of(r).expect("read_dir checked the row");
            if let Some(other) = seen.insert(job, dir) {
                return Err(CampaignError::Merge(format!(
                    "trial {} / {} is in both {} and {} (overlapping or repeated shards)",
                    r.trial,
                    r.navigator,
                    other.display(),
                    dir.display()
                )));
            }
        }
    }
    let mut notes = Vec::new();
    if seen.len() != first.jobs {
        let missing: Vec<usize> = (0..first.jobs).filter(|j| !seen.contains_key(j)).collect();
        let n = first.navigators.len().max(1);
        let run = |j: usize| {
            format!("trial {} / {}", j / n, first.navigators.get(j % n).map_or("?", String::as_str))
        };
        let count = format!("{} of {} runs are missing", missing.len(), first.jobs);
        if !partial {
            return Err(CampaignError::Merge(format!(
                "{count} (first: {}); give every shard's folder, or --partial to merge what there is",
                run(missing[0])
            )));
        }
        let listed: Vec<String> = missing.iter().take(10).map(|&j| run(j)).collect();
        let more = if missing.len() > 10 { ", ..." } else { "" };
        notes.push(format!("{count}: {}{more}", listed.join(", ")));
    }
    let failures = prepare_dir(out)?;
    let mut meta = first.clone();
    meta.shard = None;
    let mut all = Vec::new();
    for ((_, rows), dir) in parts.into_iter().zip(dirs) {
        for r in &rows {
            if !r.failed() {
                continue;
            }
            let mut names = vec![r.picture_name()];
            if r.terrain_kind == crate::TerrainKind::Procedural {
                names.push(format!("trial-{:04}.toml", r.trial));
            }
            for name in names {
                let from = dir.join("failures").join(&name);
                let to = failures.join(&name);
                if to.exists() {
                    continue;
                }
                match std::fs::read(&from) {
                    Ok(bytes) => write_atomic(&to, &bytes)?,
                    Err(e) => notes.push(format!("picture not copied: {}: {e}", from.display())),
                }
            }
        }
        all.extend(rows);
    }
    Ok((meta, all, notes))
}
