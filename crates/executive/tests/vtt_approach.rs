//! The `approach_target` task through a whole mission run: Navcam pairs rendered by the
//! simulator, tracked by the deliberative layer, navigator legs far out and blind moves near
//! the target; the rover's true final position is checked against the stand-off from the
//! surface point under the designated pixel.

use rovernav_executive::{Mission, build_world, run_mission};
use rovernav_sim::HeightField;
use rovernav_vision::camera::CameraModel;
use rovernav_vision::rig::Rig;
use rovernav_vision::tracking::{Approach, ApproachParams, Designation};

fn mission_text(yaw_deg: f64, task: &str) -> String {
    format!(
        r#"
name = "vtt-approach"
seed = 7
time_limit_s = 3600.0

[terrain]
kind = "procedural"
size_m = 20.0
resolution_m = 0.05
rock_abundance = 0.03
relief_m = 0.1
slope_deg = 0.0

[start]
x = 10.0
y = 10.0
yaw_deg = {yaw_deg}

[goal]
x = 10.2
y = 10.0
tolerance_m = 0.5
{task}"#
    )
}

#[test]
#[ignore = "known failure: the approach arrives (18 moves, 19 images, 1.004 m from its target estimate) but the rover truly stopped 0.688 m from the surface point under the designated pixel; cause not found (docs/vtt.md)"]
fn approach_target_stops_at_the_standoff_of_a_designated_rock() {
    // A rock 5-7 m from the start with nothing taller than 10 cm in the way.
    let probe = Mission::from_toml(&mission_text(0.0, ""), "probe").expect("mission");
    let world = build_world(&probe, "probe").expect("world");
    let rocks = &world.terrain.rocks;
    let clear = |r: &rovernav_terrain::Rock| {
        let (dx, dy) = (r.x - 10.0, r.y - 10.0);
        let (d, (ux, uy)) = (dx.hypot(dy), (dx / dx.hypot(dy), dy / dx.hypot(dy)));
        rocks.iter().all(|o| {
            let (ox, oy) = (o.x - 10.0, o.y - 10.0);
            let along = ox * ux + oy * uy;
            o == r || o.height <= 0.1 || along < -1.0 || along > d - 0.5 || (ox * uy - oy * ux).abs() > 0.9
        })
    };
    let rock = rocks
        .iter()
        .find(|r| {
            let d = (r.x - 10.0).hypot(r.y - 10.0);
            (5.0..7.0).contains(&d)
                && (0.25..0.8).contains(&r.diameter)
                && (0.12..0.5).contains(&r.height)
                && clear(r)
        })
        .expect("a rock with a clear corridor");
    let (dx, dy) = (rock.x - 10.0, rock.y - 10.0);
    let u = (dx / dx.hypot(dy), dy / dx.hypot(dy));
    let ground = world.terrain.dem.height(rock.x, rock.y).expect("on the yard") - rock.height;
    let aim =
        [rock.x - 0.3 * rock.diameter * u.0, rock.y - 0.3 * rock.diameter * u.1, ground + 0.6 * rock.height];
    let task = format!(
        "\n[[tasks]]\nkind = \"approach_target\"\nx = {}\ny = {}\nz = {}\nstandoff_m = 1.0\n",
        aim[0], aim[1], aim[2]
    );
    let mission = Mission::from_toml(&mission_text(dy.atan2(dx).to_degrees(), &task), "vtt test mission")
        .expect("mission");
    let out = run_mission(&mission, "vtt test mission", &mut |_| {}).expect("run");
    let report = out.report.tasks.iter().find(|t| t.kind == "approach_target").expect("the task");
    assert_eq!(report.state, "success", "{}", report.message);
    assert_eq!(out.report.outcome, "reached");
    // The tracked point: the surface point under the projection of `aim` in the first image,
    // aimed (as the rover did) from the start pose.
    let start = out.trace.truth[0];
    let designation = Designation::Site { x: aim[0], y: aim[1], z: aim[2] };
    let approach =
        Approach::new(&out.world.rover, 512, designation, ApproachParams::default()).expect("approach");
    let (pan, tilt) = approach.aim(&start).expect("aim");
    let left = Rig::new(&out.world.rover)
        .with_size(512)
        .camera("navcam_left", pan, tilt)
        .expect("navcam")
        .in_world(&start, &start);
    let pixel = left.project(&nalgebra::Point3::from(aim)).expect("in view");
    let ray = left.unproject(&pixel);
    let (c, v) = (ray.origin, ray.direction);
    let field = HeightField::new(&out.world.terrain.dem);
    let hit = field.cast(&out.world.terrain.dem, [c.x, c.y, c.z], [v.x, v.y, v.z], 50.0).expect("the rock");
    let end = out.trace.truth.last().expect("a pose");
    let d = (end.x - hit.point[0]).hypot(end.y - hit.point[1]);
    assert!((d - 1.0).abs() < 0.05, "stopped {d:.3} m from the target: {}", report.message);
}
