//! Running a campaign's jobs in parallel across cores.
//!
//! Each worker of a rayon pool pulls the next job from a shared counter, so the expensive DEM
//! runs, queued first, start first and the cheap yard runs fill in behind them. Results come
//! back in completion order; rows are sorted by (trial, navigator) before they are summarised,
//! so the order never shows in the outputs.

use crate::CampaignError;
use crate::output::write_atomic;
use crate::plan::{Job, Plan, TerrainKind};
use crate::row::Row;
use rovernav_executive::{Run, RunOutput};
use rovernav_harness::JudgedRun;
use std::path::Path;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// Runs `jobs` of `plan` on `threads` workers (at least one). `on_done` is called from the
/// workers after every run (for a progress bar). When `failures_dir` is given, every run that
/// did not succeed leaves its traverse picture there, and a failed yard trial its mission file.
/// Stops at the first run that cannot start and returns its error.
pub fn run_jobs(
    plan: &Plan,
    jobs: &[Job],
    threads: usize,
    failures_dir: Option<&Path>,
    on_done: &(dyn Fn(&Row) + Sync),
) -> Result<Vec<Row>, CampaignError> {
    let mut order: Vec<&Job> = jobs.iter().collect();
    order.sort_by_key(|j| (plan.trials[j.trial].terrain_kind != TerrainKind::Dem, j.index));
    let next = AtomicUsize::new(0);
    let stop = AtomicBool::new(false);
    let rows = Mutex::new(Vec::with_capacity(jobs.len()));
    let error = Mutex::new(None);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads.max(1))
        .build()
        .map_err(|e| CampaignError::Run { trial: 0, navigator: String::new(), message: e.to_string() })?;
    pool.broadcast(|_| {
        while !stop.load(Ordering::Relaxed) {
            let Some(job) = order.get(next.fetch_add(1, Ordering::Relaxed)) else { break };
            match run_one(plan, job, failures_dir) {
                Ok(row) => {
                    on_done(&row);
                    rows.lock().expect("no worker panics holding the lock").push(row);
                }
                Err(e) => {
                    stop.store(true, Ordering::Relaxed);
                    error.lock().expect("no worker panics holding the lock").get_or_insert(e);
                }
            }
        }
    });
    if let Some(e) = error.into_inner().expect("workers have finished") {
        return Err(e);
    }
    Ok(rows.into_inner().expect("workers have finished"))
}

/// One run. A navigator that panics is reported as an error naming the trial, so the crash
/// can be rerun alone, rather than taking the whole campaign down without context.
fn run_one(plan: &Plan, job: &Job, failures_dir: Option<&Path>) -> Result<Row, CampaignError> {
    let (mission, origin) = plan.mission(job);
    let run_error = |message: String| CampaignError::Run {
        trial: job.trial,
        navigator: mission.navigator.clone(),
        message,
    };
    let output =
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| Run::mission(&mission, origin)?.execute()))
            .map_err(|panic| {
                let what = panic
                    .downcast_ref::<&str>()
                    .map(|s| s.to_string())
                    .or_else(|| panic.downcast_ref::<String>().cloned())
                    .unwrap_or_default();
                run_error(format!("the run panicked (seed {}): {what}", mission.seed))
            })?
            .map_err(|e| run_error(e.to_string()))?;
    let row = Row::new(&plan.trials[job.trial], &mission.navigator, &output.report);
    if row.failed()
        && let Some(dir) = failures_dir
    {
        write_atomic(&dir.join(row.picture_name()), &traverse_png(&output)?)?;
        if let Some(text) = plan.mission_toml(job.trial) {
            write_atomic(&dir.join(format!("trial-{:04}.toml", job.trial)), text.as_bytes())?;
        }
    }
    Ok(row)
}

/// The traverse picture of a run, drawn as `rovernav run` draws `traverse.png`.
pub fn traverse_png(output: &RunOutput) -> Result<Vec<u8>, CampaignError> {
    rovernav_viz::run_traverse_png(&output.report, &output.world, &output.trace)
        .map_err(|e| CampaignError::Io { path: "traverse picture".into(), message: e.to_string() })
}
