//! The contact monitor end to end: a navigator that never senses (the example straight-line
//! navigator, registered at run time) is sent at a boulder lying across its line to the goal.
//! The platform stops each drive on the rock; the body-contact monitor must fail at its limit
//! (`MAX_BODY_CONTACTS`) and fault protection must stop the rover there, asking for help,
//! instead of letting it ram the rock until its step budget runs out.

#[path = "../examples/straight_line_navigator/navigator.rs"]
mod navigator;

use rovernav_core::SensorFrame;
use rovernav_executive::sensor_servers::MAX_BODY_CONTACTS;
use rovernav_executive::{CycleRecord, Mission, Run, RunObserver, RunOptions, RunSettings};
use rovernav_harness::{JudgedRun, build_world};
use rovernav_navigation::{Registry, registry};
use rovernav_terrain::Rock;
use rovernav_terrain::procedural::add_rocks;

/// The motion-stop reports of every executed cycle, kept apart from the report.
#[derive(Default)]
struct Frames(Vec<SensorFrame>);

impl RunObserver for Frames {
    fn on_cycle(&mut self, record: &CycleRecord<'_>) {
        self.0.push(record.frame.clone());
    }
}

#[test]
fn a_rover_ramming_a_boulder_is_stopped_by_the_contact_monitor_at_its_limit() {
    registry::install(Registry::builtin().with(navigator::ENTRY)).expect("first use of the registry");
    // A rock-free yard; the straight line from (5, 5) to (20, 20) is then blocked by one boulder
    // 0.5 m high (far above the 0.18 m belly clearance) at its middle.
    let text = rovernav_executive::mission::DEFAULT_MISSION_TOML
        .replace("navigator = \"astar-grid\"", "navigator = \"straight-line\"")
        .replace("rock_abundance = 0.16", "rock_abundance = 0.0");
    let mission = Mission::from_toml(&text, "rammer").expect("valid mission");
    let mut world = build_world(&mission, "rammer").expect("world");
    let (start, goal) = (world.start.position(), world.goal.position);
    let boulder =
        Rock { x: (start.x + goal.x) / 2.0, y: (start.y + goal.y) / 2.0, diameter: 1.2, height: 0.5 };
    add_rocks(&mut world.terrain.dem, &[boulder]);
    world.terrain.rocks.push(boulder);

    let options = RunOptions::of(&mission, &world);
    let mut frames = Frames::default();
    let out = Run::new(world, RunSettings::of(&mission))
        .judged()
        .options(options)
        .origin("rammer")
        .observer(&mut frames)
        .execute()
        .expect("runs");
    let r = &out.report;
    assert_eq!(r.outcome, "help_requested", "{}", r.message);
    let fault = r.fault.as_ref().expect("fault protection acted");
    assert_eq!(
        (fault.kind.as_str(), fault.component.as_deref()),
        ("hazard_contact", Some("contact-monitor"))
    );
    assert_eq!(r.hazard_contacts, MAX_BODY_CONTACTS, "stopped at the limit: {}", r.message);
    // Independent of the monitor and the report: the simulator's own motion-stop reports.
    let stops =
        frames.0.iter().filter(|f| f.motion_stopped.as_deref().is_some_and(|w| w.starts_with("hazard")));
    assert_eq!(stops.count(), MAX_BODY_CONTACTS as usize);
    // No command after the one that revealed the fault, and the rover (truth) is still on the
    // start's side of the boulder: it never got past or over it.
    assert_eq!(fault.cycle, r.cycles);
    let end = out.trace.truth.last().expect("a truth trace");
    let along = |x: f64, y: f64| {
        ((x - start.x) * (goal.x - start.x) + (y - start.y) * (goal.y - start.y)) / start.dist(goal)
    };
    assert!(
        along(end.x, end.y) < along(boulder.x, boulder.y),
        "the rover ended {:.2} m along the line, the boulder is at {:.2} m",
        along(end.x, end.y),
        along(boulder.x, boulder.y)
    );
}
