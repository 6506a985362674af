//! A goal walled in by a ring of rock (the grid navigators, `crates/navigation/src/grid_nav/`):
//! the goal counts as reached anywhere within its tolerance, so when the rock's grown margin
//! closes every way to the goal cell itself the navigator plans to the nearest reachable cell
//! inside the tolerance instead of declaring the goal unreachable.
//!
//! Truth: the simulator's true final pose against the goal and the ring, and the report's
//! hazard contacts.

use rovernav_core::Point2;
use rovernav_executive::{Mission, Run, RunOptions, RunSettings};
use rovernav_harness::{JudgedRun, build_world};

/// A flat 12 m yard without rocks, the rover at (2, 6) facing east, the goal at (8, 6) with
/// the given tolerance, driven by `navigator`.
fn mission(navigator: &str, tolerance_m: f64) -> Mission {
    let text = format!(
        "name = \"walled-goal\"\nseed = 3\nnavigator = \"{navigator}\"\nlocalizer = \"dead-reckoning\"\n\
         time_limit_s = 1800.0\n[terrain]\nkind = \"procedural\"\nsize_m = 12.0\nresolution_m = 0.02\n\
         rock_abundance = 0.0\nrelief_m = 0.02\n[start]\nx = 2.0\ny = 6.0\nyaw_deg = 0.0\n\
         [goal]\nx = 8.0\ny = 6.0\ntolerance_m = {tolerance_m}\n"
    );
    Mission::from_toml(&text, "walled-goal").expect("valid mission")
}

/// Ring of rock around the goal: 0.35 m high between 0.45 and 0.6 m from it.
const RING: (f64, f64, f64) = (0.45, 0.6, 0.35);

fn run(navigator: &str, tolerance_m: f64) -> (String, String, Point2, u32) {
    let m = mission(navigator, tolerance_m);
    let mut world = build_world(&m, "test").unwrap();
    let goal = world.goal.position;
    let dem = &mut world.terrain.dem;
    let g = *dem.geometry();
    for r in 0..g.rows {
        for c in 0..g.cols {
            let p = Point2::new(
                g.origin_x + (c as f64 + 0.5) * g.resolution,
                g.origin_y + (r as f64 + 0.5) * g.resolution,
            );
            if (RING.0..=RING.1).contains(&p.dist(goal)) {
                *dem.heights.get_mut(c, r) += RING.2 as f32;
            }
        }
    }
    let options = RunOptions::of(&m, &world);
    let out = Run::new(world, RunSettings::of(&m)).judged().options(options).execute().unwrap();
    let end = out.trace.truth.last().expect("a traverse");
    (
        out.report.outcome.clone(),
        out.report.message.clone(),
        Point2::new(end.x, end.y),
        out.report.hazard_contacts,
    )
}

#[test]
fn a_goal_inside_a_ring_of_rock_is_reached_within_its_tolerance_from_outside_the_ring() {
    for navigator in ["astar-grid", "mrpta"] {
        let (outcome, message, end, contacts) = run(navigator, 2.0);
        let d = end.dist(Point2::new(8.0, 6.0));
        assert_eq!(outcome, "reached", "{navigator}: {message}");
        assert!(d <= 2.0 + 0.3, "{navigator}: true end {d:.2} m from the goal");
        assert!(d > RING.1, "{navigator}: the rover ended outside the ring ({d:.2} m from the goal)");
        assert_eq!(contacts, 0, "{navigator}: never touched the ring");
    }
}
