//! Adding a navigator: the straight-line example navigator registered with one line and run
//! in a campaign beside `astar-grid` on the built-in campaign's yards.
//!
//! ```text
//! cargo run --release -p rovernav-campaign --example straight_line_navigator -- --trials 4
//! ```
//!
//! Options: `--trials N` (default 4), `--out DIR` (default `out/campaign-straight-line`).

mod navigator;

use rovernav_campaign::output::prepare_dir;
use rovernav_campaign::{CampaignMeta, CampaignSpec, Plan};
use rovernav_navigation::Registry;
use std::path::PathBuf;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // The one line that adds the navigator to every run of this process.
    rovernav_navigation::registry::install(Registry::builtin().with(navigator::ENTRY))
        .map_err(|_| "a registry was already in use")?;

    let mut trials = 4;
    let mut out = PathBuf::from("out/campaign-straight-line");
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        match (arg.as_str(), args.next()) {
            ("--trials", Some(n)) => {
                trials = n.parse().map_err(|_| format!("--trials: `{n}` is not a count"))?
            }
            ("--out", Some(dir)) => out = PathBuf::from(dir),
            _ => {
                return Err(
                    format!("unknown or incomplete option `{arg}` (use --trials N, --out DIR)").into()
                );
            }
        }
    }
    let mut spec = CampaignSpec::builtin();
    spec.name = "straight-line".into();
    spec.trials = trials;
    spec.navigators = vec![navigator::ENTRY.name.into(), "astar-grid".into()];
    spec.validate("example campaign")?;
    let plan = Plan::new(spec)?;
    let failures = prepare_dir(&out)?;
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let rows = rovernav_campaign::run_jobs(&plan, &plan.jobs(), threads, Some(&failures), &|row| {
        eprintln!("trial {} {}: {}", row.trial, row.navigator, row.outcome);
    })?;
    let (summary, _) = rovernav_campaign::write_dir(&out, &CampaignMeta::of(&plan, None), &rows)?;
    println!("{}", summary.main_table());
    println!("results in {}", out.display());
    Ok(())
}
