//! Every operator command answered (issue 45 item 3): a direct `drive` with its completion or
//! the guard that stopped it and how far it went, the same answers on `/operator/reply` in the
//! log, and commands after the mission's end answered "mission over" instead of dropped.
//!
//! Truth: the simulator's true pose before and after each executed command (the run's
//! observer), against which the distance the answer states (judged from the estimate) is checked.

use rovernav_core::{NavCommand, Pose3};
use rovernav_executive::{CycleRecord, Mission, Run, RunObserver, RunOptions, RunSettings, ScriptedOperator};
use rovernav_harness::{JudgedRun, build_world};

/// A flat 8 m yard without rocks, the rover at (2, 2) facing east (+x), the goal far away;
/// `extra` is appended to the mission text.
fn mission(extra: &str) -> Mission {
    let text = format!(
        "name = \"operator-replies\"\nseed = 4\n[terrain]\nkind = \"procedural\"\nsize_m = 8.0\n\
         resolution_m = 0.02\nrock_abundance = 0.0\nrelief_m = 0.03\n[start]\nx = 2.0\ny = 2.0\n\
         yaw_deg = 0.0\n[goal]\nx = 6.5\ny = 6.5\n{extra}"
    );
    Mission::from_toml(&text, "operator-replies").expect("valid mission")
}

/// Every executed command with the true pose after it, and the operator's answers on the bus.
#[derive(Default)]
struct Log {
    cycles: Vec<(NavCommand, Pose3)>,
    replies: Vec<String>,
}

impl RunObserver for Log {
    fn wants_bus(&self) -> bool {
        true
    }
    fn on_bus(&mut self, records: &[rovernav_bus::Record]) {
        for r in records.iter().filter(|r| r.topic == "/operator/reply") {
            let text: String = serde_json::from_slice(&r.payload).expect("a reply is a JSON string");
            if !text.is_empty() {
                self.replies.push(text);
            }
        }
    }
    fn on_cycle(&mut self, r: &CycleRecord<'_>) {
        self.cycles.push((r.command.clone(), *r.truth));
    }
}

/// Runs the mission with a 0.3 m rock of radius `rock_radius` centred at `rock` (if any).
fn run(rock: Option<[f64; 2]>, script: &[(u64, &str)]) -> (ScriptedOperator, Log, Pose3, String) {
    run_mission(&mission(""), rock, script)
}

/// [`run`] on mission `m`.
fn run_mission(
    m: &Mission,
    rock: Option<[f64; 2]>,
    script: &[(u64, &str)],
) -> (ScriptedOperator, Log, Pose3, String) {
    let mut world = build_world(m, "test").unwrap();
    if let Some([cx, cy]) = rock {
        let dem = &mut world.terrain.dem;
        let g = *dem.geometry();
        for r in 0..g.rows {
            for c in 0..g.cols {
                let x = g.origin_x + (c as f64 + 0.5) * g.resolution;
                let y = g.origin_y + (r as f64 + 0.5) * g.resolution;
                if (x - cx).hypot(y - cy) < 0.2 {
                    *dem.heights.get_mut(c, r) += 0.3;
                }
            }
        }
    }
    let start = world.start;
    let options = RunOptions::of(m, &world);
    let mut op = ScriptedOperator::new(script);
    let mut log = Log::default();
    let out = Run::new(world, RunSettings::of(m))
        .judged()
        .options(options)
        .observer(&mut log)
        .operator(&mut op)
        .execute()
        .unwrap();
    let start = Pose3 { x: start.x, y: start.y, yaw: start.yaw, ..Default::default() };
    (op, log, start, out.report.outcome)
}

/// The true distance driven by the `n`th executed command (0-based).
fn true_step(log: &Log, start: Pose3, n: usize) -> f64 {
    let before = if n == 0 { start } else { log.cycles[n - 1].1 };
    let after = log.cycles[n].1;
    (after.x - before.x).hypot(after.y - before.y)
}

/// The number of metres after `after` in `text` ("... after 0.31 m ...").
fn metres_after(text: &str, after: &str) -> f64 {
    let rest = &text[text.find(after).unwrap_or_else(|| panic!("`{after}` in {text}")) + after.len()..];
    rest.split_whitespace().next().unwrap().parse().unwrap_or_else(|e| panic!("{e}: {text}"))
}

#[test]
fn a_drive_toward_a_rock_is_answered_with_the_proximity_stop_and_how_far_it_went() {
    // A 0.3 m rock 1.4 m ahead of the rover's centre: within a metre's drive, beyond the
    // proximity sensors' 0.6 m at the start.
    let script = [
        (0, "mission pause"),
        (0, "drive 1"),
        (1, "place 3.4 2.0"),
        (1, "mission abort"),
        (1, "drive 1"),
        (1, "status"),
    ];
    let (op, log, start, outcome) = run(Some([3.4, 2.0]), &script);
    assert_eq!(outcome, "aborted");
    assert!(matches!(log.cycles[0].0, NavCommand::Drive { .. }), "{:?}", log.cycles[0].0);
    let answer = op.reply_containing("`drive 1` stopped").unwrap_or_else(|| panic!("{:?}", op.replies));
    assert!(answer.contains("the proximity guard tripped"), "{answer}");
    assert!(answer.contains("middle sensors"), "the rock is straight ahead: {answer}");
    let said = metres_after(answer, "stopped after ");
    let truth = true_step(&log, start, 0);
    assert!(truth > 0.05 && truth < 0.9, "the guard stopped the rover after {truth:.3} m in truth");
    assert!((said - truth).abs() < 0.05, "answered {said} m, true {truth:.3} m: {answer}");
    eprintln!("{answer} (true {truth:.3} m)");
    // The queued placement never ran (the mission was paused): its end says so.
    let task = op.reply_containing("not done").unwrap_or_else(|| panic!("{:?}", op.replies));
    assert!(
        task.starts_with("task 2 (place")
            && task.ends_with("not done: mission over: aborted (mission aborted by the operator)"),
        "{task}"
    );
    // Commands after the end are answered, not dropped; `status` still works.
    let over: Vec<&String> = op.replies.iter().filter(|r| r.starts_with("mission over: aborted")).collect();
    assert_eq!(over.len(), 1, "{:?}", op.replies);
    assert_eq!(over[0], "mission over: aborted (mission aborted by the operator); `drive 1` not executed");
    assert!(op.replies.last().unwrap().starts_with("mission over · "), "{:?}", op.replies);
    // The log carries the same answers, in the same order.
    assert_eq!(log.replies, op.replies);
}

#[test]
fn an_unobstructed_drive_and_a_turn_are_answered_completed_with_what_they_did() {
    let script = [(0, "mission pause"), (0, "drive 1"), (1, "turn 90"), (2, "mission abort")];
    let (op, log, start, _) = run(None, &script);
    let answer = op.reply_containing("`drive 1` completed").unwrap_or_else(|| panic!("{:?}", op.replies));
    let said = metres_after(answer, "completed: ");
    let truth = true_step(&log, start, 0);
    assert!((said - 1.0).abs() < 0.02, "the estimate drove {said} m of 1 m: {answer}");
    assert!((said - truth).abs() < 0.1, "answered {said} m, true {truth:.3} m: {answer}");
    let turn = op.reply_containing("`turn 90` completed").unwrap_or_else(|| panic!("{:?}", op.replies));
    let turned = log.cycles[1].1.yaw - log.cycles[0].1.yaw;
    let said =
        turn.split("completed: ").nth(1).and_then(|r| r.split(' ').next()).and_then(|n| n.parse().ok());
    let said: f64 = said.unwrap_or_else(|| panic!("{:?}", op.replies));
    assert!(
        (said - turned.to_degrees()).abs() < 5.0,
        "answered {said} deg, true {:.1}: {turn}",
        turned.to_degrees()
    );
    assert_eq!(log.replies, op.replies);
}

#[test]
fn a_stall_during_a_drive_is_answered_with_the_stall_and_the_fault_that_ended_the_mission() {
    let m = mission("[[faults]]\nkind = \"stalled_wheel\"\nside = \"left\"\nat_cycle = 1\n");
    let script = [(0, "mission pause"), (0, "drive 1"), (1, "drive 1")];
    let (op, log, start, outcome) = run_mission(&m, None, &script);
    assert_eq!(outcome, "help_requested", "{:?}", op.replies);
    let answer = op.reply_containing("`drive 1` stopped").unwrap_or_else(|| panic!("{:?}", op.replies));
    assert!(answer.contains("the wheels stalled (stall: left wheels"), "{answer}");
    let (said, truth) = (metres_after(answer, "stopped after "), true_step(&log, start, 0));
    assert!(truth < 0.9 && (said - truth).abs() < 0.1, "answered {said} m, true {truth:.3} m: {answer}");
    // The second drive, accepted as the fault was diagnosed, is answered with the fault.
    let over = op.reply_containing("not executed").unwrap_or_else(|| panic!("{:?}", op.replies));
    assert!(over.contains("mission over: help_requested (fault protection (stuck_wheel)"), "{over}");
    assert_eq!(log.cycles.len(), 1, "the second drive never ran");
}

#[test]
fn a_navcam_command_takes_a_stereo_pair_where_it_points_and_answers_with_the_images() {
    let script = [(0, "navcam 0 -20"), (0, "mission pause"), (0, "navcam 30 -20"), (1, "mission abort")];
    let (op, log, start, outcome) = run(None, &script);
    assert_eq!(outcome, "aborted");
    // While the mission runs, the mast is the navigator's: refused like a drive.
    let refused = op.reply_containing("`navcam 0 -20`").unwrap_or_else(|| panic!("{:?}", op.replies));
    assert!(refused.contains("needs the mission paused"), "{refused}");
    // The command the platform executed is the pair at the asked pan and tilt, and no motion.
    let executed: Vec<_> = log
        .cycles
        .iter()
        .filter_map(|(c, _)| match c {
            NavCommand::Sense(requests) => Some(requests.clone()),
            _ => None,
        })
        .collect();
    let pair = [rovernav_core::SenseRequest::Navcam { pan: 30f64.to_radians(), tilt: (-20f64).to_radians() }];
    assert!(executed.iter().any(|r| r[..] == pair[..]), "{executed:?}");
    let last = log.cycles.last().expect("a cycle").1;
    assert!((last.x - start.x).hypot(last.y - start.y) < 0.02, "pictures do not move the rover");
    // The answer names both images, which the camera server put on /camera/image.
    let answer =
        op.reply_containing("`navcam 30 -20` completed").unwrap_or_else(|| panic!("{:?}", op.replies));
    assert!(answer.contains("2 images (navcam_left ") && answer.contains("navcam_right "), "{answer}");
    assert_eq!(log.replies, op.replies);
}

#[test]
fn one_motor_pivots_the_rover_about_the_held_wheels_and_is_answered_with_its_travel() {
    let script = [
        (0, "mission pause"),
        (0, "motor left 0.3"),
        (1, "motor right 0.3"),
        (2, "motor left 5"),
        (2, "mission abort"),
    ];
    let (op, log, start, outcome) = run(None, &script);
    assert_eq!(outcome, "aborted");
    let track = rovernav_core::RoverConfig::default().track;
    // Truth: the left motor forward turns the rover clockwise by travel / track about the right
    // wheels, whose contact point stays put; the right motor then turns it back about the left.
    let after_left = log.cycles[0].1;
    let turned = rovernav_core::wrap_angle(after_left.yaw - start.yaw);
    assert!((turned + 0.3 / track).abs() < 0.03, "turned {:.3} rad, expected {:.3}", turned, -0.3 / track);
    let held = |p: &Pose3| (p.x + (track / 2.0) * p.yaw.sin(), p.y - (track / 2.0) * p.yaw.cos());
    let (before, after) = (held(&start), held(&after_left));
    assert!((before.0 - after.0).hypot(before.1 - after.1) < 0.02, "the right wheels stayed put");
    let back = rovernav_core::wrap_angle(log.cycles[1].1.yaw - start.yaw);
    assert!(back.abs() < 0.03, "the right motor turned it back: {back:.3} rad");
    // The answers state the driven side's travel, judged from the estimate.
    let answer =
        op.reply_containing("`motor left 0.3` completed").unwrap_or_else(|| panic!("{:?}", op.replies));
    let said = metres_after(answer, "completed: ");
    assert!((said - 0.3).abs() < 0.03, "{answer}");
    assert!(op.reply_containing("`motor right 0.3` completed").is_some(), "{:?}", op.replies);
    // More than half a turn in one command is refused (the answer could not tell the turn).
    let refused = op.reply_containing("`motor left 5`").unwrap_or_else(|| panic!("{:?}", op.replies));
    assert!(refused.starts_with("error:") && refused.contains("at most 1.57 m"), "{refused}");
}
