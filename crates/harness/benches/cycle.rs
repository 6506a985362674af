//! Compute per navigation cycle on the default mission (release: `cargo bench -p
//! rovernav-harness --bench cycle`).
//!
//! First, every registered navigator's compute per cycle by stage (navigation, localisation,
//! platform) against the flight-like budget (10 ms, RoverBug 30 ms; issue 43).
//!
//! `components`: one cycle of the full run (the deliberative layer, the runtime stepping the
//! component graph on the bus, the loop's trace), timed by an observer from the start of the
//! loop to the last executed command of whole traverses (so without assembling the run and
//! scoring it against truth afterwards) and divided by their cycles. `direct`: the baseline measured in the same run, the bare loop
//! (navigator -> simulator -> localiser, no components, no bus) on the same mission and seed,
//! which issues the same commands. Their ratio is the cost of the executive around the
//! algorithms; save a baseline (`-- --save-baseline NAME`) to compare revisions.

use criterion::{Criterion, criterion_group, criterion_main};
use rovernav_core::{NavCommand, NavInput, Pose3, PoseEstimate, SensorFrame};
use rovernav_executive::{CycleRecord, Mission, Run, RunObserver, RunOptions, RunSettings, World};
use rovernav_harness::{JudgedRun, build_world};
use rovernav_sim::Simulator;
use std::time::{Duration, Instant};

/// The bare loop on a world (navigator, simulator and localiser only): the time of its cycles
/// and their number.
fn direct_cycles(world: &World, mission: &Mission) -> (Duration, u64) {
    // A map-matching localiser's navigator looks back over the terrain crossed, as in a run.
    let name = rovernav_navigation::registry().decorated(&mission.navigator, &mission.localizer);
    let mut navigator = rovernav_navigation::navigator_by_name(&name, &world.rover).expect("registered");
    let initial = Pose3 { x: world.start.x, y: world.start.y, yaw: world.start.yaw, ..Default::default() };
    let mut localizer = rovernav_navigation::localizer_by_name(&mission.localizer, &world.rover, initial)
        .expect("registered");
    let mut sim = Simulator::new(
        world.terrain.clone(),
        world.rover.clone(),
        world.sensor_model.clone(),
        world.start,
        mission.seed,
    );
    let mut frame = sim.initial_frame();
    localizer.update(&frame);
    let started = Instant::now();
    let mut cycles = 0;
    while sim.time() < mission.time_limit_s && cycles < mission.max_cycles {
        let input = NavInput {
            time: sim.time(),
            estimate: localizer.estimate(),
            goal: &world.goal,
            frame: &frame,
            localization_target: localizer.localization_target(),
        };
        let command = navigator.step(&input);
        if matches!(command, NavCommand::Finish(..)) {
            break;
        }
        frame = sim.execute(&command);
        localizer.update(&frame);
        cycles += 1;
    }
    (started.elapsed(), cycles)
}

/// Wall time from the loop's start to its last executed command.
#[derive(Default)]
struct Stopwatch {
    start: Option<Instant>,
    last: Option<Instant>,
}

impl RunObserver for Stopwatch {
    fn on_start(&mut self, _: &World, _: &RunSettings, _: &SensorFrame, _: &PoseEstimate) {
        self.start = Some(Instant::now());
    }
    fn on_cycle(&mut self, _: &CycleRecord<'_>) {
        self.last = Some(Instant::now());
    }
}

/// Time per cycle over as many whole traverses as `iters` cycles need; `traverse` returns the
/// time it spent in its cycles and their number.
fn per_cycle(iters: u64, mut traverse: impl FnMut() -> (Duration, u64)) -> Duration {
    let (mut spent, mut cycles) = (Duration::ZERO, 0u64);
    while cycles < iters.max(1) {
        let (time, n) = traverse();
        spent += time;
        cycles += n.max(1);
    }
    spent.mul_f64(iters as f64 / cycles as f64)
}

/// Compute per cycle by stage for every registered navigator on the default mission, against
/// the flight-like budget (10 ms; RoverBug 30 ms), from each run's `compute_per_cycle`.
fn print_stages() {
    for name in rovernav_navigation::navigator_names() {
        let mut mission = Mission::default_mission();
        mission.navigator = name.into();
        let Ok(run) = Run::mission(&mission, "default").and_then(Run::execute) else {
            eprintln!("{name:<22} did not run");
            continue;
        };
        let t = &run.report.compute_per_cycle;
        let budget = if name == "roverbug" { 30.0 } else { 10.0 };
        eprintln!(
            "{name:<22} {:>4} cycles  navigation {:7.3} ms  localisation {:6.3} ms  platform {:6.3} ms  \
             (budget {budget} ms: {:.1}x margin)",
            run.report.cycles,
            t.navigation_s * 1e3,
            t.localization_s * 1e3,
            t.platform_s * 1e3,
            budget / ((t.navigation_s + t.localization_s) * 1e3).max(1e-9)
        );
    }
}

fn cycle(c: &mut Criterion) {
    print_stages();
    let mission = Mission::default_mission();
    let world = build_world(&mission, "default").expect("the default world builds");
    let options = RunOptions::of(&mission, &world);
    let mut group = c.benchmark_group("navigation_cycle");
    group.sample_size(10).measurement_time(Duration::from_secs(30));
    group.bench_function("components", |b| {
        b.iter_custom(|iters| {
            per_cycle(iters, || {
                let mut watch = Stopwatch::default();
                let run =
                    Run::new(world.clone(), RunSettings::of(&mission)).judged().options(options.clone());
                let cycles =
                    run.observer(&mut watch).execute().expect("the default mission runs").report.cycles;
                let time = watch.last.zip(watch.start).map_or(Duration::ZERO, |(l, s)| l - s);
                (time, cycles)
            })
        })
    });
    group.bench_function("direct", |b| {
        b.iter_custom(|iters| per_cycle(iters, || direct_cycles(&world, &mission)))
    });
    group.finish();
}

criterion_group!(benches, cycle);
criterion_main!(benches);
