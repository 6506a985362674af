//! AutoPlace in a mission (issue 36 item 5): a `place_instrument` task on a rock stamped into the
//! generated terrain, scored against the simulator's truth, and one whose path runs through a
//! rock the cameras cannot see (a data hole behind a boulder), which must be refused.
//!
//! Truth: the terrain the simulator rendered the images from and the rover's true pose. The
//! planned motion is executed on the true surface by `rovernav_manipulation::execution` (every
//! pose 5 mm apart against the true heights, the rover and the arm; the contact angle against a
//! plane fitted to the true heights under the contact).

mod common;

use rovernav_core::Pose3;
use rovernav_executive::arm_server::PlacementMsg;
use rovernav_executive::{Mission, Run, RunObserver, RunOptions, RunOutput, RunSettings, ScriptedOperator};
use rovernav_harness::{JudgedRun, build_world};
use rovernav_manipulation::Arm;
use rovernav_manipulation::execution::execute;
use rovernav_manipulation::feasibility::Plan;
use rovernav_terrain::Dem;

/// Start (2, 2) facing east; the goal is the start, so the plan goes straight to its task.
fn mission(seed: u64, target: [f64; 2]) -> Mission {
    let text = format!(
        "name = \"autoplace\"\nseed = {seed}\n[terrain]\nkind = \"procedural\"\nsize_m = 8.0\n\
         resolution_m = 0.01\nrock_abundance = 0.0\nrelief_m = 0.03\n[start]\nx = 2.0\ny = 2.0\nyaw_deg = 0.0\n\
         [goal]\nx = 2.0\ny = 2.0\ntolerance_m = 0.5\n[[tasks]]\nkind = \"place_instrument\"\nx = {}\ny = {}\n",
        target[0], target[1]
    );
    Mission::from_toml(&text, "autoplace").expect("valid mission")
}

/// A rock with a flat top descending `slope_deg` towards the world direction `tilt_dir` (rad),
/// rounded at its rim.
#[derive(Clone, Copy)]
struct Slab {
    centre: [f64; 2],
    radius: f64,
    height: f64,
    slope_deg: f64,
    tilt_dir: f64,
}

impl Slab {
    fn add(&self, dem: &mut Dem) {
        let g = *dem.geometry();
        for r in 0..g.rows {
            for c in 0..g.cols {
                let x = g.origin_x + (c as f64 + 0.5) * g.resolution;
                let y = g.origin_y + (r as f64 + 0.5) * g.resolution;
                let (dx, dy) = (x - self.centre[0], y - self.centre[1]);
                let rho = dx.hypot(dy) / self.radius;
                if rho >= 1.0 {
                    continue;
                }
                let (s, co) = self.tilt_dir.sin_cos();
                let top = self.height - self.slope_deg.to_radians().tan() * (co * dx + s * dy);
                let add = if rho < 0.75 {
                    top
                } else {
                    let t = (1.0 - rho) / 0.25;
                    top * t * t * (3.0 - 2.0 * t)
                };
                *dem.heights.get_mut(c, r) += add.max(0.0) as f32;
            }
        }
    }
}

/// Collects the placements published on the bus.
#[derive(Default)]
struct Placements(Vec<PlacementMsg>);

impl RunObserver for Placements {
    fn wants_bus(&self) -> bool {
        true
    }
    fn on_bus(&mut self, records: &[rovernav_bus::Record]) {
        for r in records.iter().filter(|r| r.topic == "/arm/placement") {
            self.0.push(serde_json::from_slice(&r.payload).expect("a placement message"));
        }
    }
}

/// Runs the mission with `slabs` stamped into its terrain.
fn run(m: &Mission, slabs: &[Slab]) -> (RunOutput, Vec<PlacementMsg>) {
    let mut world = build_world(m, "test").unwrap();
    for s in slabs {
        s.add(&mut world.terrain.dem);
    }
    let options = RunOptions::of(m, &world);
    let mut seen = Placements::default();
    let out =
        Run::new(world, RunSettings::of(m)).judged().options(options).observer(&mut seen).execute().unwrap();
    (out, seen.0)
}

/// The true surface in the rover's body frame at `pose`: the body z of the surface under body
/// (x, y) (a few fixed-point steps along body z).
fn body_ground<'a>(dem: &'a Dem, pose: &'a Pose3) -> impl Fn(f64, f64) -> Option<f64> + 'a {
    let r = pose.rotation();
    move |x, y| {
        let mut z = 0.0;
        for _ in 0..4 {
            let w = pose.transform([x, y, z]);
            z += (dem.height(w[0], w[1])? - w[2]) / r[2][2];
        }
        Some(z)
    }
}

#[test]
fn a_placement_on_a_rock_meets_its_true_normal_and_nothing_else() {
    // A 10 cm rock 1.0 m ahead on the arm's side, its top rising 10 deg away from the rover
    // (facing the cameras).
    let rock = Slab {
        centre: [3.0, 1.88],
        radius: 0.14,
        height: 0.10,
        slope_deg: 10.0,
        tilt_dir: std::f64::consts::PI,
    };
    let m = mission(5, rock.centre);
    let (out, placements) = run(&m, &[rock]);
    let task = &out.report.tasks.last().unwrap();
    assert_eq!(task.kind, "place_instrument");
    let summary = task.placement.as_ref().expect("the report says what AutoPlace did");
    assert_eq!((task.state.as_str(), summary.outcome.as_str()), ("success", "placed"), "{}", task.message);
    assert!(task.message.contains("contact angle"), "{}", task.message);
    assert_eq!(placements.len(), 1);
    let p = &placements[0];
    // Truth: the plan executed on the true terrain at the true pose.
    let truth = *out.trace.truth.last().unwrap();
    let arm = Arm::new(&out.world.rover);
    let plan = Plan {
        via: p.via.clone(),
        approach: p.approach.clone(),
        axis: p.axis.unwrap(),
        contact: p.target.unwrap().point,
    };
    let e = execute(&arm, &body_ground(&out.world.terrain.dem, &truth), &plan);
    assert_eq!(e.collision, None, "{e:?}");
    assert!(e.contact, "the contact face met the rock: {e:?}");
    assert!(e.normal_error_deg < 10.0, "contact angle {:.1} deg from the true normal", e.normal_error_deg);
    // On the rock's top, not beside it.
    let stop = truth.transform(e.stop);
    assert!((stop[0] - rock.centre[0]).hypot(stop[1] - rock.centre[1]) < 0.75 * rock.radius, "{stop:?}");
    // The arm's joint states cover the move out, the dwell and the return, in time.
    assert!(p.joints.windows(2).all(|w| w[1].t > w[0].t));
    assert_eq!(p.joints.first().unwrap().q, arm.stowed());
    assert_eq!(p.joints.last().unwrap().q, arm.stowed());
    assert!(!p.octree.occupied.is_empty() && !p.octree.unknown.is_empty());
    assert!(out.report.sim_time_s >= p.end_s() - 1e-6, "the mission waited for the arm");
}

#[test]
fn a_rock_hidden_behind_a_boulder_in_the_arms_path_is_refused_and_nothing_moves() {
    // A 30 cm boulder 0.85 m ahead hides the ground behind it from the Hazcams; a 12 cm rock
    // sits in that shadow on the way to a target beyond it.
    let boulder = Slab { centre: [2.85, 1.88], radius: 0.12, height: 0.30, slope_deg: 0.0, tilt_dir: 0.0 };
    let hidden = Slab { centre: [3.02, 1.88], radius: 0.06, height: 0.12, slope_deg: 0.0, tilt_dir: 0.0 };
    let target = [3.15, 1.88];
    let m = mission(6, target);
    let (out, placements) = run(&m, &[boulder, hidden]);
    let task = &out.report.tasks.last().unwrap();
    let summary = task.placement.as_ref().expect("the report says what AutoPlace did");
    assert_eq!((task.state.as_str(), summary.outcome.as_str()), ("failure", "refused"), "{}", task.message);
    let reason = summary.reason.as_deref().unwrap();
    assert!(["collision", "no_data"].contains(&reason), "{reason}: {}", task.message);
    assert!(task.message.contains("nothing moved"), "{}", task.message);
    let p = &placements[0];
    assert!(p.joints.is_empty() && p.via.is_empty(), "nothing moves on a refusal");
    // The hidden rock was a data hole: no sensed point lies on its top.
    let truth = *out.trace.truth.last().unwrap();
    let on_top = p.points.iter().filter(|q| {
        let w = truth.transform([q[0] as f64, q[1] as f64, q[2] as f64]);
        (w[0] - hidden.centre[0]).hypot(w[1] - hidden.centre[1]) < 0.05
    });
    assert_eq!(on_top.count(), 0);
    // ... and the octree keeps it as unknown space (an obstacle), not free.
    let top = [
        hidden.centre[0],
        hidden.centre[1],
        out.world.terrain.dem.height(hidden.centre[0], hidden.centre[1]).unwrap(),
    ];
    let r = truth.rotation();
    let d = [0, 1, 2].map(|k| top[k] - [truth.x, truth.y, truth.z][k]);
    let body = [0, 1, 2].map(|j| (0..3).map(|i| r[i][j] * d[i]).sum::<f64>());
    let inside = |c: &[f32; 4]| (0..3).all(|k| (body[k] - c[k] as f64).abs() <= 0.5 * c[3] as f64);
    assert!(p.octree.unknown.iter().any(inside), "the hidden rock's top {body:?} is unknown");
    assert!(!p.octree.occupied.iter().any(inside));
}

#[test]
fn the_operators_place_command_queues_a_placement_that_runs_end_to_end() {
    // The example mission without its task: the operator asks for the placement instead.
    let file = include_str!("../../../missions/place_instrument.toml");
    let text = file.split("[[tasks]]").next().unwrap();
    let m = Mission::from_toml(text, "place_instrument.toml").expect("the example mission parses");
    let world = build_world(&m, "test").unwrap();
    let options = RunOptions::of(&m, &world);
    let mut op = ScriptedOperator::new(&[(0, "place 7.61 3.68"), (0, "place 7.61 nan")]);
    let out =
        Run::new(world, RunSettings::of(&m)).judged().options(options).operator(&mut op).execute().unwrap();
    assert!(op.reply_containing("task 2 added: place_instrument (7.61, 3.68)").is_some());
    assert!(op.reply_containing("error: token 3 \"nan\"").is_some(), "a NaN is refused at the edge");
    let place = out.report.tasks.iter().find(|t| t.kind == "place_instrument").expect("queued");
    let summary = place.placement.as_ref().expect("AutoPlace ran");
    assert_eq!((place.state.as_str(), summary.outcome.as_str()), ("success", "placed"), "{}", place.message);
    // On the rock's top: the rock (26 cm across) rises above the ground around it.
    let t = summary.target.unwrap();
    assert!((t[0] - 7.61).hypot(t[1] - 3.68) < 0.1, "{t:?}");
    let dem = &out.world.terrain.dem;
    assert!(dem.height(t[0], t[1]).unwrap() > dem.height(7.61 - 0.3, 3.68).unwrap() + 0.05);
    assert_eq!(out.report.outcome, "reached", "{}", out.report.message);
}
