//! The sky watches end to end (issue 34 item 3): the example mission's `[[sky]]` puts a cloud
//! and a dust devil where its `cloud_watch` and `dust_devil_watch` look; the rendered Navcam
//! images alone must make the watches keep images with events, and the same mission under an
//! empty sky must keep none (the simulator's volumes are the independent truth).

use rovernav_executive::Mission;
use rovernav_executive::run::Run;

/// Images with events and images kept, from a watch task's summary line.
fn watch(report: &rovernav_executive::Report, kind: &str) -> (u32, u32, String) {
    let task = report.tasks.iter().find(|t| t.kind == kind).expect("the watch task");
    assert_eq!(task.state, "success", "{}", task.message);
    let number_before = |text: &str, what: &str| -> u32 {
        let end = text.find(what).unwrap_or_else(|| panic!("`{what}` in {text}"));
        text[..end].trim_end().rsplit(' ').next().unwrap().parse().unwrap()
    };
    let kept = task.message.split("kept ").nth(1).expect("kept count");
    let kept: u32 = kept.split(' ').next().unwrap().parse().unwrap();
    (number_before(&task.message, "with events"), kept, task.message.clone())
}

#[test]
fn the_watches_keep_the_cloud_and_the_dust_devil_and_nothing_under_an_empty_sky() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../missions/sky-watch.toml");
    let mission = Mission::from_file(&path).expect("the example mission");
    assert_eq!(mission.sky.len(), 2, "a cloud and a dust devil");
    let out = Run::mission(&mission, "sky-watch").and_then(Run::execute).expect("run");
    assert_eq!(out.report.outcome, "reached");
    let (events, kept, message) = watch(&out.report, "cloud_watch");
    assert!(events >= 1 && kept >= 1, "the cloud is seen and kept: {message}");
    let (events, kept, message) = watch(&out.report, "dust_devil_watch");
    assert!(events >= 1 && kept >= 1, "the dust devil is seen and kept: {message}");

    let clear = Mission { sky: Vec::new(), ..mission };
    let out = Run::mission(&clear, "sky-watch, empty sky").and_then(Run::execute).expect("run");
    for kind in ["cloud_watch", "dust_devil_watch"] {
        let (events, kept, message) = watch(&out.report, kind);
        assert_eq!((events, kept), (0, 0), "an empty sky gives nothing to keep: {message}");
    }
}
