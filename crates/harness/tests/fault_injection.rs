//! Fault injection from the mission file: a sensor that goes silent or returns NaN, a wheel that
//! stalls, a compass that reads NaN, a gyro whose bias jumps and a component that crashes each
//! stop the rover with `help_requested`, the failed component in Failure, a message naming the
//! fault, the injection in the report, and every executed command in the log.

mod common;

use rovernav_core::{NavCommand, SensorFrame};
use rovernav_executive::{
    CycleRecord, Mission, Report, Run, RunObserver, RunOptions, RunSettings, Trace, World,
};
use rovernav_harness::{JudgedRun, build_world};
use rovernav_terrain::MarsYardParams;
use rovernav_terrain::procedural::{add_craters, yard_craters};

/// A 12 m yard with one `[[faults]]` entry.
fn mission_with_fault(fault: &str) -> Mission {
    let text =
        common::small_yard("fault-yard", 3, &format!("{}[[faults]]\n{fault}\n", common::SMALL_YARD_GOAL));
    Mission::from_toml(&text, "fault-yard").expect("valid mission")
}

/// Keeps everything the run hands to observers.
#[derive(Default)]
struct Log {
    started: bool,
    cycles: Vec<u64>,
    commands: Vec<NavCommand>,
    frames: Vec<SensorFrame>,
    finished: Option<(Report, usize)>,
}

impl RunObserver for Log {
    fn on_start(
        &mut self,
        _world: &World,
        _settings: &rovernav_executive::RunSettings,
        _frame: &SensorFrame,
        _estimate: &rovernav_core::PoseEstimate,
    ) {
        self.started = true;
    }
    fn on_cycle(&mut self, record: &CycleRecord<'_>) {
        self.cycles.push(record.cycle);
        self.commands.push(record.command.clone());
        self.frames.push(record.frame.clone());
    }
    fn on_finish(&mut self, report: &Report, trace: &Trace) {
        self.finished = Some((report.clone(), trace.truth.len()));
    }
}

/// Runs the mission and checks what every fault must give; returns the report and the log.
fn run_and_check_stop(fault: &str, component: &str, kind: &str) -> (Report, Log) {
    let mut log = Log::default();
    let out =
        Run::mission(&mission_with_fault(fault), "fault-yard").unwrap().observer(&mut log).execute().unwrap();
    let r = out.report.clone();
    assert_eq!(r.outcome, "help_requested", "{}", r.message);
    let fault_report = r.fault.clone().expect("fault protection acted");
    assert_eq!(fault_report.kind, kind);
    assert_eq!(fault_report.component.as_deref(), Some(component));
    assert!(r.message.contains("asking for help") && r.message.contains(component), "{}", r.message);
    // The faulty component is in Failure; fault protection stood every other one down.
    for c in &r.components {
        let expected = if c.name == component { "Failure" } else { "Standby" };
        assert_eq!(c.state, expected, "{}: {}", c.name, c.message);
    }
    // Stopped at once: no command after the one that revealed the fault.
    assert_eq!(fault_report.cycle, r.cycles, "no command after fault protection acted");
    assert_eq!(r.tasks[0].state, "aborted");
    // Nothing lost: every executed command reached the observer, in order, and the trace.
    assert!(log.started);
    assert_eq!(log.cycles, (1..=r.cycles).collect::<Vec<_>>());
    assert_eq!(out.trace.truth.len() as u64, r.cycles + 1);
    let (finished, truth_len) = log.finished.as_ref().expect("on_finish called");
    assert_eq!(finished, &r);
    assert_eq!(*truth_len, out.trace.truth.len());
    (r, log)
}

#[test]
fn a_mast_camera_that_goes_silent_stops_the_rover_with_a_sensor_fault() {
    let (r, log) = run_and_check_stop(
        "kind = \"silent_sensor\"\nsensor = \"mast\"\nat_cycle = 4",
        "range-sensors",
        "sensor_fault",
    );
    let message = &r.fault.as_ref().unwrap().message;
    assert!(message.contains("mast stereo") && message.contains("no range points"), "{message}");
    // Independent check on the logged data: the command that revealed the fault returned empty
    // mast images, and every mast image before the fault had points.
    let last = log.frames.last().unwrap();
    assert!(last.clouds.iter().any(|c| c.points.is_empty()));
    let before: Vec<&SensorFrame> = log.frames[..3].iter().collect();
    assert!(before.iter().flat_map(|f| &f.clouds).all(|c| !c.points.is_empty()));
    assert!(r.cycles >= 4, "the fault starts at command 4");
}

#[test]
fn a_stalled_wheel_stops_the_rover_with_a_stuck_wheel_fault() {
    let (r, log) = run_and_check_stop(
        "kind = \"stalled_wheel\"\nside = \"left\"\nat_cycle = 3",
        "wheel-odometry",
        "stuck_wheel",
    );
    let message = &r.fault.as_ref().unwrap().message;
    assert!(message.contains("stuck wheel") && message.contains("left"), "{message}");
    // It was the first motion at or after command 3 that revealed it.
    let first_motion = log
        .commands
        .iter()
        .zip(&log.cycles)
        .find(|(c, n)| **n >= 3 && matches!(c, NavCommand::Drive { .. } | NavCommand::Turn { .. }))
        .map(|(_, n)| *n)
        .expect("the rover tried to move");
    assert_eq!(r.cycles, first_motion);
}

#[test]
fn a_compass_reading_nan_stops_the_rover_with_a_sensor_fault() {
    let (r, log) =
        run_and_check_stop("kind = \"compass_nan\"\nat_time_s = 30.0", "inertial-sensors", "sensor_fault");
    let message = &r.fault.as_ref().unwrap().message;
    assert!(message.contains("compass") && message.contains("NaN"), "{message}");
    // The logged samples show the NaN: the last frame has one, no earlier frame does.
    let has_nan = |f: &SensorFrame| f.imu.iter().any(|s| s.compass_yaw.is_nan());
    assert!(has_nan(log.frames.last().unwrap()));
    assert!(log.frames[..log.frames.len() - 1].iter().all(|f| !has_nan(f)));
    assert!(log.frames.last().unwrap().t >= 30.0);
}

#[test]
fn a_mast_camera_returning_nan_points_stops_the_rover_before_they_reach_the_map() {
    let (r, log) = run_and_check_stop(
        "kind = \"nan_range\"\nsensor = \"mast\"\nat_cycle = 4",
        "range-sensors",
        "sensor_fault",
    );
    let message = &r.fault.as_ref().unwrap().message;
    assert!(message.contains("mast stereo") && message.contains("non-finite"), "{message}");
    // The logged data: the last frame's mast cloud is NaN, no earlier frame has a NaN point.
    let nan_points = |f: &SensorFrame| f.clouds.iter().flat_map(|c| &c.points).any(|p| p[0].is_nan());
    assert!(nan_points(log.frames.last().unwrap()));
    assert!(log.frames[..log.frames.len() - 1].iter().all(|f| !nan_points(f)));
    let injected = &r.injected_faults[0];
    assert_eq!(injected.kind, "nan_range");
    assert!(injected.time_s <= r.fault.as_ref().unwrap().time_s);
}

#[test]
fn a_gyro_bias_jump_is_seen_at_rest_and_stops_the_rover() {
    let (r, log) = run_and_check_stop(
        "kind = \"gyro_bias_jump\"\nrate_deg_s = 0.3\nat_time_s = 20.0",
        "inertial-sensors",
        "sensor_fault",
    );
    let message = &r.fault.as_ref().unwrap().message;
    assert!(message.contains("gyro") && message.contains("wheels still"), "{message}");
    // Independent check on the logged samples: before the jump every sample with the wheels
    // still read under 0.05 deg/s; the stop came within two commands of the jump.
    let injected = &r.injected_faults[0];
    assert_eq!(injected.kind, "gyro_bias_jump");
    let mut last = None;
    for f in &log.frames {
        for (o, s) in f.odometry.iter().zip(&f.imu) {
            let counts = (o.left_counts, o.right_counts);
            if last == Some(counts) && s.t < injected.time_s {
                assert!(s.gyro_z.abs().to_degrees() < 0.05, "at rest before the jump: {}", s.gyro_z);
            }
            last = Some(counts);
        }
    }
    let after = log.frames.iter().filter(|f| f.t >= injected.time_s).count();
    assert!((1..=3).contains(&after), "{after} commands between the jump and the stop");
}

#[test]
fn a_navigator_that_crashes_goes_to_failure_and_the_rover_stops() {
    let (r, _) = run_and_check_stop(
        "kind = \"component_crash\"\ncomponent = \"navigator\"\nat_cycle = 5",
        "navigator",
        "component_failure",
    );
    let fault = r.fault.as_ref().unwrap();
    assert!(fault.message.contains("crashed"), "{}", fault.message);
    assert_eq!(r.injected_faults.len(), 1);
    assert_eq!(r.injected_faults[0].component.as_deref(), Some("navigator"));
    assert_eq!(r.hazard_contacts, 0);
}

#[test]
fn a_fault_naming_an_unknown_component_is_a_one_line_error() {
    let text = common::small_yard(
        "fault-yard",
        3,
        &format!(
            "{}[[faults]]\nkind = \"component_crash\"\ncomponent = \"flux-capacitor\"\n",
            common::SMALL_YARD_GOAL
        ),
    );
    let e = Mission::from_toml(&text, "fault-yard").unwrap_err().to_string();
    assert!(e.contains("faults[0].component") && !e.contains('\n'), "{e}");
}

/// Campaign `full`, trial 5: SR2 drove into a tilt hazard and kept commanding the same motion,
/// logging 4995 hazard contacts before its cycle budget ran out. The contact monitor then stopped
/// it at the third contact (its limit: `sensor_servers`' unit test). Since SR2 backs up only over
/// ground it has just driven over (`navigation::sr2`), after a stop right behind a turn it
/// rotates again instead of backing blindly and re-entering: it now gets past the crater.
#[test]
fn regression_sr2_rammed_the_terrain_4995_times_in_campaign_full_trial_5() {
    let text = r#"
name = "full-trial-0005"
seed = 443230342
navigator = "sr2"
[terrain]
kind = "procedural"
size_m = 30.0
resolution_m = 0.05
rock_abundance = 0.04
relief_m = 0.3254641454057985
slope_deg = 2.26523504172323
[start]
x = 5.0
y = 5.0
yaw_deg = 30.0
[goal]
x = 20.0
y = 20.0
"#;
    let mission = Mission::from_toml(text, "trial-5").expect("valid mission");
    // The yard generator now keeps craters off the start and goal pads; the tilt hazard SR2
    // rammed was such a crater, so the world of the campaign trial is rebuilt with it put back.
    let mut world = build_world(&mission, "trial-5").expect("world");
    let params = MarsYardParams {
        width_m: 30.0,
        height_m: 30.0,
        resolution: 0.05,
        seed: mission.seed,
        ..MarsYardParams::default()
    };
    let pads = [(5.0, 5.0), (20.0, 20.0)];
    let dropped: Vec<_> = yard_craters(&params)
        .into_iter()
        .filter(|c| pads.iter().any(|&(x, y)| (c.x - x).hypot(c.y - y) < 1.0 + 0.75 * c.diameter))
        .collect();
    assert!(!dropped.is_empty(), "the trial's world had a crater at a pad");
    add_craters(&mut world.terrain.dem, &dropped);
    let options = RunOptions::of(&mission, &world);
    let mut log = Log::default();
    let r = Run::new(world, RunSettings::of(&mission))
        .judged()
        .options(options)
        .origin("trial-5")
        .observer(&mut log)
        .execute()
        .expect("runs")
        .report;
    assert_eq!(r.outcome, "reached", "{}", r.message);
    assert!(r.hazard_contacts < 3, "under the monitor's limit: {}", r.hazard_contacts);
    assert!(r.fault.is_none(), "no fault: {:?}", r.fault);
    // Independent of the report: the logged frames show as many motions stopped on the terrain.
    let stops =
        log.frames.iter().filter(|f| f.motion_stopped.as_deref().is_some_and(|w| w.starts_with("hazard")));
    assert_eq!(stops.count(), r.hazard_contacts as usize);
}
