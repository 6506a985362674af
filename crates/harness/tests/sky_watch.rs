//! The sky watches end to end (issue 34 item 3): the example mission's `[[sky]]` puts a cloud
//! and a dust devil where its `cloud_watch` and `dust_devil_watch` look; the rendered Navcam
//! images alone must make the watches keep images with events, and the same mission under an
//! empty sky must keep none (the simulator's volumes are the independent truth).

use rovernav_executive::Mission;
use rovernav_executive::run::Run;
use rovernav_harness::JudgedRun;

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

/// The example mission with one watch task and one `[[sky]]` entry in place of its own, its
/// Navcams at `width` pixels.
fn one_watch(task: &str, sky: &str, width: usize) -> (Mission, rovernav_executive::World) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../missions/sky-watch.toml");
    let text = std::fs::read_to_string(&path).expect("the example mission");
    let head = &text[..text.find("[[tasks]]").expect("its tasks")];
    let mission = Mission::from_toml(&format!("{head}{task}\n{sky}"), "one watch").expect("mission");
    let mut world = rovernav_harness::build_world(&mission, "one watch").expect("world");
    world.sensor_model.navcam.width = width;
    (mission, world)
}

/// Runs a mission in `world` and returns the report and the watch's summary.
fn run_watch(
    mission: &Mission,
    world: rovernav_executive::World,
) -> (rovernav_executive::RunOutput, rovernav_executive::deliberative::WatchSummary) {
    use rovernav_executive::{RunOptions, RunSettings};
    let options = RunOptions::of(mission, &world);
    let out = Run::new(world, RunSettings::of(mission)).judged().options(options).execute().expect("run");
    assert_eq!(out.report.outcome, "reached", "{}", out.report.message);
    let task = out.report.tasks.iter().find(|t| t.kind.ends_with("_watch")).expect("the watch task");
    assert_eq!(task.state, "success", "{}", task.message);
    let summary = rovernav_executive::deliberative::WatchSummary::from_message(&task.message)
        .unwrap_or_else(|| panic!("no summary in {}", task.message));
    (out, summary)
}

#[test]
fn a_dust_devil_watch_sees_the_column_where_it_stands_at_each_image_time() {
    use rovernav_vision::CameraModel;
    // A dust devil 800 m away, 16 m wide, drifting north at 2.5 m/s: it crosses the view from
    // right to left (the watch starts about 130 s into the mission, the column then 6 deg right
    // of the view's centre), more than its width between images (a motion detector's median
    // background holds a column that overlaps itself from image to image, and its box then
    // spans both).
    let sky = "[[sky]]\nkind = \"dust_devil\"\nazimuth_deg = -30.0\ndistance_m = 800.0\nradius_m = 8.0\n\
               height_m = 400.0\noptical_depth = 0.1\nvelocity_mps = [0.0, 2.5]\n";
    let mut slopes = Vec::new();
    for interval in [8.0, 24.0] {
        let task = format!(
            "[[tasks]]\nkind = \"dust_devil_watch\"\nframes = 6\ninterval_s = {interval}\ntilt_deg = -2.0\n"
        );
        let (mission, world) = one_watch(&task, sky, 256);
        let volume = world.sensor_model.navcam.volumes[0];
        let (out, s) = run_watch(&mission, world);
        // The images are the interval apart on the simulated clock.
        let times = s.times_s();
        assert_eq!(times.len(), 6, "{s:?}");
        for w in times.windows(2) {
            assert!((w[1] - w[0] - interval).abs() < 1e-6, "interval {interval}: times {times:?}");
        }
        // Truth: the column's axis at each image's time, seen by the left Navcam from the
        // rover's true pose (it stands still through the watch).
        let truth = *out.trace.truth.last().expect("the true pose");
        let rig = rovernav_vision::rig::Rig::new(&out.world.rover).with_size(256);
        let camera = rig.camera("navcam_left", 0.0, -2f64.to_radians()).unwrap().in_world(&truth, &truth);
        let column_x = |t: f64| {
            let [x, y, _] = volume.position;
            let at =
                nalgebra::Point3::new(x + volume.velocity[0] * t, y + volume.velocity[1] * t, truth.z + 1.5);
            camera.project(&at).expect("in front of the camera").x
        };
        // The strongest box of each image holds the column as it stood at the image's time.
        let mut seen = Vec::new();
        for r in &s.records {
            let want = column_x(r.time_s);
            let Some(e) = r.events.iter().max_by(|a, b| a.score.total_cmp(&b.score)) else { continue };
            let [x, _, w, _] = e.bbox;
            if (x as f64 - 2.0..=(x + w) as f64 + 2.0).contains(&want) {
                seen.push((r.time_s, x as f64 + 0.5 * w as f64));
            }
        }
        assert!(
            seen.len() >= 5,
            "interval {interval}: the column is boxed in {} of 6 images: {s:?}",
            seen.len()
        );
        // The boxes move at the column's rate across the image (pixels per second).
        let n = seen.len() as f64;
        let (mt, mx) = (seen.iter().map(|p| p.0).sum::<f64>() / n, seen.iter().map(|p| p.1).sum::<f64>() / n);
        let slope = seen.iter().map(|p| (p.0 - mt) * (p.1 - mx)).sum::<f64>()
            / seen.iter().map(|p| (p.0 - mt).powi(2)).sum::<f64>();
        let want = (column_x(times[5]) - column_x(times[0])) / (times[5] - times[0]);
        assert!(
            (slope - want).abs() <= 0.1 * want.abs(),
            "interval {interval}: boxes move {slope:.3} px/s, the column {want:.3} px/s; seen {seen:?}; column {:?}; {s:?}",
            times.iter().map(|&t| column_x(t)).collect::<Vec<_>>()
        );
        slopes.push((slope, want));
    }
    eprintln!("box and column rates (px/s) at 8 s and 24 s: {slopes:?}");
}
