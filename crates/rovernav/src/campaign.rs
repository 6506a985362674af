//! `rovernav campaign`: every navigator on the same generated terrains, Monte Carlo, with a
//! results table and plots (issue 9). A thin command-line layer over [`rovernav_campaign`]:
//! argument parsing, the progress bar and printing.
//!
//! Job arrays: `--shard i/n` runs the i-th of n disjoint slices. Without `--shard`, a Slurm
//! array task takes its slice from `SLURM_ARRAY_TASK_ID` (less `SLURM_ARRAY_TASK_MIN`, over
//! `SLURM_ARRAY_TASK_STEP`) of `SLURM_ARRAY_TASK_COUNT`, and a Kubernetes indexed job from
//! `JOB_COMPLETION_INDEX` (0-based) of `--shard-count` or `ROVERNAV_SHARD_COUNT`.
//! `rovernav campaign merge DIRS...` joins the slices' folders into one.
//! `rovernav campaign compare DIRS... --against DIRS...` pairs two sets of runs terrain by
//! terrain (McNemar's exact test on clean arrivals and on runs with contacts).

use anyhow::{Context, bail};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rovernav_campaign::output::{prepare_dir, summary_json};
use rovernav_campaign::{CampaignMeta, CampaignSpec, MachineSummary, Plan, Shard, Summary};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

/// Options of `rovernav campaign`.
#[derive(clap::Args, Debug)]
#[command(args_conflicts_with_subcommands = true)]
pub struct CampaignArgs {
    #[command(subcommand)]
    command: Option<CampaignCommand>,
    #[command(flatten)]
    run: RunArgs,
}

/// Subcommands of `rovernav campaign`.
#[derive(clap::Subcommand, Debug)]
enum CampaignCommand {
    /// Join shard folders into one campaign folder whose summary equals an unsharded run's.
    Merge(MergeArgs),
    /// Compare two sets of runs terrain by terrain: a variant against its baseline, or one
    /// navigator against another, with McNemar's exact test on the terrains they disagree on.
    Compare(CompareArgs),
}

/// Options of `rovernav campaign compare`.
#[derive(clap::Args, Debug)]
struct CompareArgs {
    /// Side A: output folders of one or more campaigns (their runs are pooled).
    #[arg(required = true)]
    dirs: Vec<PathBuf>,
    /// Side B: output folders to compare against.
    #[arg(long, required = true, num_args = 1..)]
    against: Vec<PathBuf>,
    /// Side A's navigator, when its folders hold several.
    #[arg(long)]
    a_navigator: Option<String>,
    /// Side B's navigator, when its folders hold several.
    #[arg(long)]
    b_navigator: Option<String>,
    /// Print the comparison as JSON.
    #[arg(long)]
    json: bool,
}

/// Options of a campaign run.
#[derive(clap::Args, Debug)]
struct RunArgs {
    /// Campaign file (TOML); omit for the built-in campaign (campaigns/default.toml).
    file: Option<PathBuf>,
    /// Number of procedural yards (overrides the file's `trials`; DEM missions come on top).
    #[arg(long)]
    trials: Option<usize>,
    /// Navigators, comma-separated registry names, or `all` (overrides the file's list).
    #[arg(long, value_delimiter = ',')]
    navigators: Option<Vec<String>>,
    /// Campaign seed (overrides the file's): every trial's draws, and its terrain seed unless the
    /// file gives `first_terrain_seed`, derive from it.
    #[arg(long)]
    seed: Option<u64>,
    /// Run only slice i of n (1-based, e.g. 2/4) of the (trial, navigator) jobs.
    #[arg(long, conflicts_with = "shard_count")]
    shard: Option<String>,
    /// Slice count for a JOB_COMPLETION_INDEX job array (or to override Slurm's count).
    #[arg(long)]
    shard_count: Option<usize>,
    /// Output folder (default: out/campaign-<name>, with -shard-<i>-of-<n> for a slice).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Print summary.json to standard output instead of the tables.
    #[arg(long)]
    json: bool,
    /// Worker threads (default: one per core).
    #[arg(long)]
    threads: Option<usize>,
}

/// Options of `rovernav campaign merge`.
#[derive(clap::Args, Debug)]
struct MergeArgs {
    /// Output folders of the shards.
    #[arg(required = true)]
    dirs: Vec<PathBuf>,
    /// Output folder of the merged campaign (default: out/campaign-<name>).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Print summary.json to standard output instead of the tables.
    #[arg(long)]
    json: bool,
    /// Merge even when runs are missing (a campaign killed part way): say which, summarise the rest.
    #[arg(long)]
    partial: bool,
}

/// Runs `rovernav campaign` or `rovernav campaign merge`.
pub fn run(args: CampaignArgs) -> anyhow::Result<()> {
    match args.command {
        Some(CampaignCommand::Merge(m)) => merge(m),
        Some(CampaignCommand::Compare(c)) => compare(c),
        None => run_campaign(args.run),
    }
}

fn run_campaign(args: RunArgs) -> anyhow::Result<()> {
    let (mut spec, origin) = match &args.file {
        Some(path) => (CampaignSpec::from_file(path)?, path.display().to_string()),
        None => (CampaignSpec::builtin(), "built-in campaign".to_string()),
    };
    if let Some(navs) = &args.navigators {
        let registry = rovernav_navigation::registry();
        for name in navs.iter().filter(|n| *n != "all") {
            if let Err(e) = registry.navigator(name, None) {
                bail!("--navigators: {}", e.to_string().replace("(known: ", "(known: all, "));
            }
        }
        spec.navigators = navs.clone();
        // Parameters of navigators the override leaves out have no runs to go to.
        let names = spec.navigator_names();
        spec.navigator_params.retain(|name, _| names.contains(name));
    }
    if let Some(t) = args.trials {
        spec.trials = t;
    }
    if let Some(s) = args.seed {
        spec.seed = s;
    }
    spec.validate(&format!("{origin} with command-line overrides"))?;
    let shard = match &args.shard {
        Some(text) => Some(Shard::parse(text)?),
        None => {
            let s = Shard::from_env(|k| std::env::var(k).ok(), args.shard_count)?;
            if s.is_none() && args.shard_count.is_some() {
                bail!(
                    "--shard-count: neither JOB_COMPLETION_INDEX nor SLURM_ARRAY_TASK_ID is set (use --shard i/n)"
                );
            }
            s
        }
    };
    let plan = Plan::new(spec)?;
    for note in &plan.skipped {
        eprintln!("note: {note}");
    }
    let jobs: Vec<_> =
        plan.jobs().into_iter().filter(|j| shard.is_none_or(|s| s.contains(j.index))).collect();
    let out_dir = args.out.clone().unwrap_or_else(|| {
        let mut name = format!("campaign-{}", plan.spec.name);
        if let Some(s) = shard {
            name.push_str(&format!("-shard-{}-of-{}", s.index, s.count));
        }
        PathBuf::from("out").join(name)
    });
    let failures = prepare_dir(&out_dir)?;
    let threads = args.threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    if threads == 0 {
        bail!("--threads: must be at least 1");
    }

    let bar = ProgressBar::new(jobs.len() as u64);
    if !std::io::stderr().is_terminal() {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    }
    bar.set_style(
        ProgressStyle::with_template(
            "{spinner} {prefix} [{bar:30}] {pos}/{len} runs · {elapsed} (eta {eta}) {msg}",
        )
        .expect("static template")
        .progress_chars("=> "),
    );
    bar.set_prefix(format!(
        "campaign {}{}",
        plan.spec.name,
        shard.map_or(String::new(), |s| format!(" shard {s}"))
    ));
    bar.enable_steady_tick(std::time::Duration::from_millis(250));
    // campaign.json first, then each row appended as its run ends: a killed campaign keeps every
    // finished run (`campaign merge --partial` summarises them).
    let meta = CampaignMeta::of(&plan, shard);
    let row_log = rovernav_campaign::RowLog::start(&out_dir, &meta)?;
    // Without a terminal the bar draws nothing: a plain line every few seconds instead.
    let plain = std::sync::Mutex::new(crate::progress::PlainProgress::for_stderr());
    let on_done = |row: &rovernav_campaign::Row| {
        row_log.append(row);
        bar.inc(1);
        let last = format!("trial {} {}: {}", row.trial, row.navigator, row.outcome);
        if let Ok(mut plain) = plain.lock() {
            let (done, total, elapsed) = (bar.position() as usize, jobs.len(), bar.elapsed().as_secs_f64());
            plain.tick(|| crate::progress::campaign_line(&plan.spec.name, done, total, elapsed, &last));
        }
        bar.set_message(last);
    };
    let rows = rovernav_campaign::run_jobs(&plan, &jobs, threads, Some(&failures), &on_done);
    bar.finish_and_clear();
    let rows = rows?;
    row_log.finish()?;
    let (summary, machine) = rovernav_campaign::write_dir(&out_dir, &meta, &rows)?;
    print_summary(&summary, &machine, &out_dir, args.json);
    Ok(())
}

fn merge(args: MergeArgs) -> anyhow::Result<()> {
    let out_dir = match &args.out {
        Some(d) => d.clone(),
        None => {
            let (meta, _) = rovernav_campaign::read_dir(&args.dirs[0])?;
            PathBuf::from("out").join(format!("campaign-{}", meta.spec.name))
        }
    };
    let (meta, rows, notes) = rovernav_campaign::merge_dirs(&args.dirs, &out_dir, args.partial)?;
    for note in notes {
        eprintln!("note: {note}");
    }
    let (summary, machine) = rovernav_campaign::write_dir(&out_dir, &meta, &rows)
        .with_context(|| format!("{}: cannot write the merged campaign", out_dir.display()))?;
    print_summary(&summary, &machine, &out_dir, args.json);
    Ok(())
}

fn compare(args: CompareArgs) -> anyhow::Result<()> {
    let read = |dirs: &[PathBuf]| -> anyhow::Result<Vec<rovernav_campaign::Row>> {
        let mut rows = Vec::new();
        for d in dirs {
            rows.extend(rovernav_campaign::read_dir(d)?.1);
        }
        Ok(rows)
    };
    let (a, b) = (read(&args.dirs)?, read(&args.against)?);
    let c = rovernav_campaign::compare(&a, args.a_navigator.as_deref(), &b, args.b_navigator.as_deref())?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&c)?);
    } else {
        let label =
            |dirs: &[PathBuf]| dirs.iter().map(|d| d.display().to_string()).collect::<Vec<_>>().join(" + ");
        println!("{}", c.markdown(&label(&args.dirs), &label(&args.against)));
    }
    Ok(())
}

fn print_summary(summary: &Summary, machine: &MachineSummary, out_dir: &Path, json: bool) {
    if json {
        print!("{}", summary_json(summary, machine));
        return;
    }
    let shard = summary.shard.as_ref().map_or(String::new(), |s| format!(", shard {s}"));
    println!(
        "campaign {} (seed {}{shard}): {} terrains, {} runs, {} failed\n",
        summary.campaign,
        summary.seed,
        summary.terrains,
        summary.runs,
        summary.failures.len()
    );
    println!("{}", summary.main_table());
    println!("Success by rock abundance:\n\n{}", summary.rock_table());
    println!("{}", machine.markdown());
    println!("outputs in {}", out_dir.display());
}
