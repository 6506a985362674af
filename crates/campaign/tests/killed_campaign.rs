//! A campaign killed part way (issue 44): the rows of every finished run are in `rows.jsonl`
//! (appended as each run ends, a line cut short by the kill left out), and `merge --partial`
//! summarises them while saying which runs are missing; without `--partial` merge refuses.

use rovernav_campaign::{CampaignMeta, CampaignSpec, Plan, Row, RowLog, merge_dirs, read_dir};
use rovernav_executive::Report;
use std::io::Write;

#[test]
fn a_killed_campaign_keeps_every_finished_row_and_merges_partially() {
    let dir = std::env::temp_dir().join(format!("rovernav-killed-campaign-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let (killed, merged) = (dir.join("killed"), dir.join("merged"));
    std::fs::create_dir_all(&killed).unwrap();
    let spec = CampaignSpec::from_toml("trials = 2\nnavigators = [\"nat\", \"sr2\"]", "c.toml").unwrap();
    let plan = Plan::new(spec).unwrap();
    let meta = CampaignMeta::of(&plan, None);
    let log = RowLog::start(&killed, &meta).unwrap();
    let finished = [(0, "nat"), (1, "nat"), (0, "sr2")];
    for (trial, nav) in finished {
        let report = Report { outcome: "reached".into(), navigator: nav.into(), ..Default::default() };
        log.append(&Row::new(&plan.trials[trial], nav, &report));
    }
    log.finish().unwrap();
    // The kill lands in the middle of the fourth append.
    let mut rows = std::fs::OpenOptions::new().append(true).open(killed.join("rows.jsonl")).unwrap();
    rows.write_all(b"{\"trial\":1,\"navig").unwrap();
    drop(rows);

    let (_, kept) = read_dir(&killed).unwrap();
    let mut got: Vec<(usize, &str)> = kept.iter().map(|r| (r.trial, r.navigator.as_str())).collect();
    got.sort();
    assert_eq!(got, [(0, "nat"), (0, "sr2"), (1, "nat")]);

    let e = merge_dirs(std::slice::from_ref(&killed), &merged, false).unwrap_err().to_string();
    assert!(e.contains("1 of 4 runs are missing") && e.contains("--partial"), "{e}");
    let (_, all, notes) = merge_dirs(std::slice::from_ref(&killed), &merged, true).unwrap();
    assert_eq!(all.len(), 3);
    assert!(notes.iter().any(|n| n.contains("1 of 4 runs are missing: trial 1 / sr2")), "{notes:?}");
    let _ = std::fs::remove_dir_all(&dir);
}
