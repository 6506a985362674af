//! Visual target tracking in track-only mode (issue 35 item 2, paper 003 section 3's sol-992
//! checkout): a `track_target` task beside the default mission's drive tracks a rock in the
//! Navcam pairs taken alongside the navigator's sensing. The drive must be the same, pose for
//! pose, as the same mission without the task, and every tracked image must agree with the
//! simulator's truth: the tracked pixel with the projection of the true surface point into the
//! true camera, the range and the rover-frame position with that point's.

use nalgebra::Point3;
use rovernav_executive::{Mission, Run, RunObserver, World};
use rovernav_harness::JudgedRun;
use rovernav_sim::HeightField;
use rovernav_vision::camera::CameraModel;
use rovernav_vision::rig::{Rig, pose_isometry};

/// The `/vtt/track` messages a run published.
#[derive(Default)]
struct VttLog(Vec<rovernav_executive::deliberative::VttTrackMsg>);

impl RunObserver for VttLog {
    fn wants_bus(&self) -> bool {
        true
    }
    fn on_bus(&mut self, records: &[rovernav_bus::Record]) {
        for r in records.iter().filter(|r| r.topic == "/vtt/track") {
            self.0.push(serde_json::from_slice(&r.payload).expect("a /vtt/track message"));
        }
    }
}

/// The default mission with its goal at `goal` and, if given, a `track_target` of site point
/// `track` beside the drive.
fn mission(goal: [f64; 2], track: Option<Point3<f64>>) -> Mission {
    let text = rovernav_executive::mission::DEFAULT_MISSION_TOML;
    let mut text =
        text.replace("[goal]\nx = 20.0\ny = 20.0", &format!("[goal]\nx = {}\ny = {}", goal[0], goal[1]));
    assert_ne!(text, rovernav_executive::mission::DEFAULT_MISSION_TOML, "the goal is replaced");
    if let Some(p) = track {
        text += &format!(
            "\n[[tasks]]\nkind = \"track_target\"\nx = {}\ny = {}\nz = {}\nparallel = true\n",
            p.x, p.y, p.z
        );
    }
    Mission::from_toml(&text, "track only").expect("valid mission")
}

/// The true surface point the left Navcam at `truth`, head at `pan`, `tilt`, sees at pixel `px`.
fn surface_at(
    world: &World,
    field: &HeightField,
    truth: &rovernav_core::Pose3,
    pan: f64,
    tilt: f64,
    px: [f64; 2],
) -> Option<Point3<f64>> {
    let rig = Rig::new(&world.rover).with_size(world.sensor_model.navcam.width);
    let cam = rig.camera("navcam_left", pan, tilt)?.in_world(truth, truth);
    let ray = cam.unproject(&nalgebra::Point2::new(px[0], px[1]));
    let (c, d) = (ray.origin, ray.direction);
    let hit = field.cast(&world.terrain.dem, [c.x, c.y, c.z], [d.x, d.y, d.z], 100.0)?;
    Some(Point3::from(hit.point))
}

/// A rock 6-9 m from the start, within 30 deg of its heading, 0.25-0.6 m tall and 0.5-1 m
/// across, whose facing side is in sight from the start: the point 60 % up that side, and a
/// goal 2.5 m short of the rock on the line from the start (the drive heads towards the target,
/// as with the sol-992 checkout's blind drive, so the view turns little between pairs).
fn target(world: &World, field: &HeightField) -> (Point3<f64>, [f64; 2]) {
    let start = rovernav_sim::vehicle::settled_pose(&world.terrain.dem, &world.rover, world.start);
    let mut rocks: Vec<_> = world
        .terrain
        .rocks
        .iter()
        .filter(|r| (0.25..=0.6).contains(&r.height) && (0.5..=1.0).contains(&r.diameter))
        .filter(|r| {
            let (dx, dy) = (r.x - start.x, r.y - start.y);
            let bearing = rovernav_core::angle_diff(dy.atan2(dx), start.yaw);
            (6.0..=9.0).contains(&dx.hypot(dy)) && bearing.abs() < 30f64.to_radians()
        })
        .collect();
    rocks.sort_by(|a, b| {
        (a.x - start.x).hypot(a.y - start.y).total_cmp(&(b.x - start.x).hypot(b.y - start.y))
    });
    let rig = Rig::new(&world.rover);
    for rock in rocks {
        let (dx, dy) = (rock.x - start.x, rock.y - start.y);
        let n = dx.hypot(dy);
        let ground = world.terrain.dem.height(rock.x, rock.y).unwrap_or(0.0) - rock.height;
        let aim = Point3::new(
            rock.x - 0.3 * rock.diameter * dx / n,
            rock.y - 0.3 * rock.diameter * dy / n,
            ground + 0.6 * rock.height,
        );
        // In sight: the ray from the mast head towards it meets the rock first.
        let head = pose_isometry(&start) * Point3::new(0.0, 0.0, rig.mast_height);
        let d = (aim - head).normalize();
        let Some(hit) = field.cast(&world.terrain.dem, [head.x, head.y, head.z], [d.x, d.y, d.z], 100.0)
        else {
            continue;
        };
        if (Point3::from(hit.point) - aim).norm() < 0.1 {
            let goal = [rock.x - 2.5 * dx / n, rock.y - 2.5 * dy / n];
            return (aim, goal);
        }
    }
    panic!("the default yard has no rock in sight ahead");
}

#[test]
fn track_only_leaves_the_drive_pose_for_pose_and_tracks_the_true_rock() {
    let world = rovernav_harness::build_world(&Mission::default_mission(), "default").expect("world");
    let field = HeightField::new(&world.terrain.dem);
    let (aim, goal) = target(&world, &field);
    let alone = Run::mission(&mission(goal, None), "alone").and_then(Run::execute).expect("runs");
    assert_eq!(alone.report.outcome, "reached", "{}", alone.report.message);
    // The site frame is the localiser's: it starts at z = 0 where the rover stands, so the
    // operator gives heights above the rover's start.
    let site = aim - nalgebra::Vector3::new(0.0, 0.0, alone.trace.truth[0].z);
    eprintln!("goal {goal:?}, designated site point {site}");
    let mut log = VttLog::default();
    let tracked = Run::mission(&mission(goal, Some(site)), "track only")
        .expect("builds")
        .observer(&mut log)
        .execute()
        .expect("runs");
    // The drive: the same true and estimated path, pose for pose.
    assert_eq!(alone.trace.truth, tracked.trace.truth, "tracking changed the drive");
    assert_eq!(alone.trace.estimate, tracked.trace.estimate);
    let task = tracked.report.tasks.iter().find(|t| t.kind == "track_target").expect("the task");
    eprintln!("{}: {}", task.state, task.message);
    // The tracking: one message per pair, all tracked, each against the truth.
    let msgs = &log.0;
    let first = &msgs[0];
    assert_eq!(first.status, "designated");
    let truth_at = |t: f64| {
        let i = tracked.trace.sim_time_s.iter().position(|&s| s == t).expect("a pose at the image's time");
        tracked.trace.truth[i]
    };
    let rig = Rig::new(&world.rover).with_size(world.sensor_model.navcam.width);
    let p = surface_at(&world, &field, &truth_at(first.t), first.pan, first.tilt, first.pixel.unwrap())
        .expect("the designated pixel sees the ground");
    assert!((p - aim).norm() < 0.3, "designated {p} for {aim}");
    let mut worst_px: f64 = 0.0;
    for m in msgs {
        if m.pixel.is_none() {
            continue;
        }
        let truth = truth_at(m.t);
        let cam = rig.camera("navcam_left", m.pan, m.tilt).unwrap().in_world(&truth, &truth);
        let true_px = cam.project(&p).expect("in front of the camera");
        let [x, y] = m.pixel.unwrap();
        let px_err = (true_px.x - x).hypot(true_px.y - y);
        worst_px = worst_px.max(px_err);
        let [range, sigma] = m.range_m.unwrap();
        let true_range = (p - Point3::from(cam.c)).norm();
        let in_rover = pose_isometry(&truth).inverse_transform_point(&p);
        let r = m.rover.unwrap();
        let rover_err = (in_rover - Point3::new(r[0], r[1], r[2])).norm();
        eprintln!(
            "image {}: {px_err:.2} px, range {range:.3} vs {true_range:.3} (sigma {sigma:.3}), rover-frame {rover_err:.3} m",
            m.image_index
        );
        assert!(px_err < 2.0, "image {}: {px_err:.2} px from the true projection", m.image_index);
        assert!(
            (range - true_range).abs() < 3.0 * sigma + 0.05,
            "image {}: range {range} vs {true_range}",
            m.image_index
        );
        assert!(rover_err < 3.0 * sigma + 0.1, "image {}: {rover_err} m", m.image_index);
        assert!(m.template.as_ref().is_some_and(|t| t.width == 31 && t.pixels.len() == 31 * 31));
        if m.image_index > 1 {
            let s = m.matched.unwrap();
            assert!(s.score >= 0.6 && (s.x, s.y) == (x, y), "{s:?}");
        }
    }
    eprintln!("worst {worst_px:.2} px over {} images", msgs.len());
    assert!(msgs.len() >= 4, "{} images", msgs.len());
    assert!(msgs.iter().skip(1).all(|m| m.status == "tracked"), "every pair tracked");
    assert_eq!(task.state, "success", "{}", task.message);
    assert_eq!(alone.report.outcome, tracked.report.outcome);
}
