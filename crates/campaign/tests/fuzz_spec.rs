//! Fuzz target of the campaign file parser (issue 44): the shipped campaigns and the hostile
//! cases of `tests/fuzz_corpus/campaign/`, mutated, parse to a plan or to a one-line error
//! naming the file, and never panic. `PROPTEST_CASES` sets the cases.

use proptest::prelude::*;
use rovernav_campaign::{CampaignSpec, Plan};

#[path = "../../../tests/fuzz_corpus/mutate.rs"]
mod mutate;

proptest! {
    #![proptest_config(ProptestConfig { failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn fuzz_campaign_parser_and_plan((path, bytes) in mutate::input("campaign")) {
        let text = String::from_utf8_lossy(&bytes);
        match CampaignSpec::from_toml(&text, "fuzz.toml") {
            Err(e) => {
                let e = e.to_string();
                prop_assert!(e.starts_with("fuzz.toml") && !e.contains('\n'), "{}: {e}", path.display());
            }
            Ok(spec) if spec.trials <= 1000 => {
                if let Ok(plan) = Plan::new(spec) {
                    let _ = plan.jobs();
                }
            }
            Ok(_) => {}
        }
    }
}
