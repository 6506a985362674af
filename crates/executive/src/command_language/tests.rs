//! Tests of the command language: typed values, errors naming tokens, help, round trips.

use super::help::HELP;
use super::*;
use proptest::prelude::*;
use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

fn parsed(line: &str) -> OperatorCommand {
    match parse_command(line) {
        Ok(Some(command)) => command,
        other => panic!("{line:?} gave {other:?}"),
    }
}

fn error(line: &str) -> CommandError {
    match parse_command(line) {
        Err(error) => error,
        other => panic!("{line:?} should fail, gave {other:?}"),
    }
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * b.abs().max(1.0)
}

#[test]
fn operator_numbers_out_of_bounds_are_refused_naming_the_token() {
    fails_at("turn 1e308", 2, Some("1e308"), "a number (degrees) of magnitude at most 36000 for A");
    fails_at("turn -36001", 2, Some("-36001"), "at most 36000");
    fails_at("drive 1e6", 2, Some("1e6"), "at most 1000 for D");
    fails_at("set position 1 2 1e9rad", 5, Some("1e9rad"), "for YAW");
    fails_at("track 1e9 3", 2, Some("1e9"), "for ROW");
    fails_at("waypoint add 3 -2e7", 4, Some("-2e7"), "for Y");
    assert_eq!(parsed("turn 36000"), OperatorCommand::Turn { angle: 36_000f64.to_radians() });
    assert_eq!(parsed("drive -1000m"), OperatorCommand::Drive { distance: -1000.0 });
}

#[test]
fn every_command_parses_to_its_typed_values() {
    use OperatorCommand as C;
    assert_eq!(parsed("goto 12.5 -3"), C::Goto { x: 12.5, y: -3.0 });
    assert_eq!(parsed("waypoint add 4 5e1"), C::WaypointAdd { x: 4.0, y: 50.0 });
    assert_eq!(parsed("waypoint clear"), C::WaypointClear);
    assert_eq!(parsed("waypoint list"), C::WaypointList);
    assert_eq!(parsed("mission start"), C::MissionStart);
    assert_eq!(parsed("mission pause"), C::MissionPause);
    assert_eq!(parsed("mission abort"), C::MissionAbort);
    assert_eq!(parsed("stop"), C::Stop);
    assert_eq!(parsed("drive -1.25"), C::Drive { distance: -1.25 });
    assert_eq!(parsed("status"), C::Status);
    assert_eq!(parsed("navcam"), C::Navcam { pan: 0.0, tilt: (-20f64).to_radians() });
    assert_eq!(parsed("navcam 30"), C::Navcam { pan: 30f64.to_radians(), tilt: (-20f64).to_radians() });
    assert_eq!(parsed("NAVCAM -45deg 0.5rad"), C::Navcam { pan: (-45f64).to_radians(), tilt: 0.5 });
    assert_eq!(parsed("motor left 0.3"), C::Motor { side: MotorSide::Left, distance: 0.3 });
    assert_eq!(parsed("MOTOR Right -2m"), C::Motor { side: MotorSide::Right, distance: -2.0 });
    assert_eq!(parse_command("motor up 1").unwrap_err().index, 2);
    assert_eq!(parse_command("motor left 1 2").unwrap_err().index, 4);
    assert_eq!(parsed("help"), C::Help { topic: None });
    assert_eq!(parsed("help waypoint"), C::Help { topic: Some("waypoint".into()) });
    let C::Turn { angle } = parsed("turn 90") else { panic!("not a turn") };
    assert!(close(angle, FRAC_PI_2), "{angle}");
    let C::Turn { angle } = parsed("turn -180") else { panic!("not a turn") };
    assert!(close(angle, -PI), "{angle}");
    let C::SetPosition { x, y, yaw } = parsed("set position 1 2 45") else { panic!("not a fix") };
    assert_eq!((x, y), (1.0, 2.0));
    assert!(close(yaw.expect("yaw given"), FRAC_PI_4));
    assert_eq!(parsed("set position -7 0.5"), C::SetPosition { x: -7.0, y: 0.5, yaw: None });
}

#[test]
fn keywords_ignore_case_and_spacing_and_comments_are_skipped() {
    assert_eq!(parsed("  GoTo\t1   2 "), OperatorCommand::Goto { x: 1.0, y: 2.0 });
    assert_eq!(parsed("WAYPOINT Add 1 2"), OperatorCommand::WaypointAdd { x: 1.0, y: 2.0 });
    assert_eq!(parsed("Help SET"), OperatorCommand::Help { topic: Some("set".into()) });
    assert_eq!(parsed("stop # now!"), OperatorCommand::Stop);
    assert_eq!(parse_command(""), Ok(None));
    assert_eq!(parse_command("   \t "), Ok(None));
    assert_eq!(parse_command("# goto 1 2"), Ok(None));
    assert_eq!(parse_command("   # indented comment"), Ok(None));
}

#[test]
fn unit_suffixes_convert_to_metres_and_radians() {
    assert_eq!(parsed("drive 2m"), OperatorCommand::Drive { distance: 2.0 });
    assert_eq!(parsed("drive 2M"), OperatorCommand::Drive { distance: 2.0 });
    assert_eq!(parsed("goto 1m -2m"), OperatorCommand::Goto { x: 1.0, y: -2.0 });
    for line in ["turn 90deg", "turn 90DEG", "turn 90°", "turn 1.5707963267948966rad"] {
        let OperatorCommand::Turn { angle } = parsed(line) else { panic!("{line} not a turn") };
        assert!(close(angle, FRAC_PI_2), "{line}: {angle}");
    }
    let OperatorCommand::SetPosition { yaw, .. } = parsed("set position 0 0 -0.5rad") else {
        panic!("not a fix")
    };
    assert_eq!(yaw, Some(-0.5));
}

/// Asserts that `line` fails at token `index` whose text is `token` (`None`: end of line),
/// and that the message names both.
fn fails_at(line: &str, index: usize, token: Option<&str>, expected_part: &str) {
    let error = error(line);
    assert_eq!(error.index, index, "{line:?}: {error}");
    assert_eq!(error.token.as_deref(), token, "{line:?}: {error}");
    assert!(error.expected.contains(expected_part), "{line:?}: {error}");
    let message = error.to_string();
    assert!(message.starts_with(&format!("token {index} ")), "{message}");
    match token {
        Some(text) => assert!(message.contains(&format!("{text:?}")), "{message}"),
        None => assert!(message.contains("end of line"), "{message}"),
    }
    assert!(!message.contains('\n'), "{message}");
}

#[test]
fn each_error_names_the_wrong_token() {
    fails_at("gogo 1 2", 1, Some("gogo"), "a command (goto,");
    fails_at("goto 1 abc", 3, Some("abc"), "a number (metres) for Y in \"goto X Y\"");
    fails_at("goto 1", 3, None, "for Y in \"goto X Y\"");
    fails_at("goto", 2, None, "for X in \"goto X Y\"");
    fails_at("goto 1 2 3", 4, Some("3"), "end of line after \"goto X Y\"");
    fails_at("goto NaN 2", 2, Some("NaN"), "a number (metres) for X");
    fails_at("goto 1 inf", 3, Some("inf"), "for Y");
    fails_at("goto 1e999 0", 2, Some("1e999"), "for X");
    fails_at("goto 1e308 0", 2, Some("1e308"), "of magnitude at most 10000000 for X");
    fails_at("drive 3deg", 2, Some("3deg"), "a number (metres) for D");
    fails_at("drive 3mm", 2, Some("3mm"), "for D");
    fails_at("drive", 2, None, "for D in \"drive D\"");
    fails_at("turn left", 2, Some("left"), "a number (degrees) for A in \"turn A\"");
    fails_at("turn 90m", 2, Some("90m"), "(degrees)");
    fails_at("turn -infinity", 2, Some("-infinity"), "(degrees)");
    fails_at("waypoint", 2, None, "add, clear or list");
    fails_at("waypoint remove 1", 2, Some("remove"), "add, clear or list");
    fails_at("waypoint add 1", 4, None, "for Y in \"waypoint add X Y\"");
    fails_at("waypoint clear all", 3, Some("all"), "end of line after \"waypoint clear\"");
    fails_at("waypoint list 2", 3, Some("2"), "after \"waypoint list\"");
    fails_at("mission go", 2, Some("go"), "start, pause or abort");
    fails_at("mission", 2, None, "start, pause or abort");
    fails_at("mission abort now", 3, Some("now"), "after \"mission abort\"");
    fails_at("stop please", 2, Some("please"), "after \"stop\"");
    fails_at("status x", 2, Some("x"), "after \"status\"");
    fails_at("set pos 1 2", 2, Some("pos"), "\"position\" in \"set position X Y [YAW]\"");
    fails_at("set", 2, None, "\"position\"");
    fails_at("set position 1", 4, None, "for Y");
    fails_at("set position 1 2 north", 5, Some("north"), "a number (degrees) for YAW");
    fails_at("set position 1 2 3 4", 6, Some("4"), "end of line after \"set position X Y [YAW]\"");
    fails_at("help fly", 2, Some("fly"), "a command name (goto,");
    fails_at("help goto now", 3, Some("now"), "after \"help [COMMAND]\"");
    fails_at("goto 1 x # comment", 3, Some("x"), "for Y");
}

#[test]
fn error_message_matches_the_documented_shape() {
    assert_eq!(
        error("goto 1 abc").to_string(),
        "token 3 \"abc\": expected a number (metres) for Y in \"goto X Y\""
    );
    assert_eq!(
        error("goto 1").to_string(),
        "token 3 (end of line): expected a number (metres) for Y in \"goto X Y\""
    );
    assert_eq!(error("goto 1").token_text(), "end of line");
    assert_eq!(error("goto 1 abc").token_text(), "abc");
}

#[test]
fn track_takes_a_pixel_or_a_site_point() {
    assert_eq!(parsed("track 240 256.5"), OperatorCommand::TrackPixel { row: 240.0, col: 256.5 });
    assert_eq!(parsed("TRACK 240px 12px"), OperatorCommand::TrackPixel { row: 240.0, col: 12.0 });
    assert_eq!(parsed("track 10 2.5m -0.3"), OperatorCommand::TrackSite { x: 10.0, y: 2.5, z: -0.3 });
    assert_eq!(error("track 1px 2 3").index, 2, "a site point is in metres");
    assert_eq!(error("track 1").index, 3);
    assert_eq!(error("track 1 2 3 4").index, 5);
    assert_eq!(error("track a b").token.as_deref(), Some("a"));
}

#[test]
fn place_takes_a_site_point_in_metres_strictly() {
    assert_eq!(parsed("place 10.3 -2"), OperatorCommand::Place { x: 10.3, y: -2.0 });
    assert_eq!(parsed("PLACE 1m 2.5M # on the rock"), OperatorCommand::Place { x: 1.0, y: 2.5 });
    assert_eq!(parsed("place 10.3 -2").to_string(), "place 10.3 -2");
    fails_at("place 1", 3, None, "a number (metres) for Y in \"place X Y\"");
    fails_at("place NaN 2", 2, Some("NaN"), "for X");
    fails_at("place 1 inf", 3, Some("inf"), "for Y");
    fails_at("place 1deg 2", 2, Some("1deg"), "metres");
    fails_at("place 1 2 3", 4, Some("3"), "end of line after \"place X Y\"");
    let limit = MAX_COORDINATE_M;
    fails_at(&format!("place {} 0", 2.0 * limit), 2, Some(&format!("{}", 2.0 * limit)), "magnitude at most");
    assert_eq!(parsed(&format!("place {limit} -{limit}")), OperatorCommand::Place { x: limit, y: -limit });
    let help = help_text(Some("place")).expect("place has help");
    assert!(help.starts_with("place X Y: ") && help.contains("collision"), "{help}");
}

#[test]
fn help_lists_every_command_and_describes_each() {
    let list = help_text(None).expect("full list");
    for name in COMMAND_NAMES {
        assert!(list.lines().any(|line| line.trim_start().starts_with(name)), "{name} missing:\n{list}");
        let one = help_text(Some(name)).expect("known topic");
        assert!(one.starts_with(name), "{one}");
        assert_eq!(help_text(Some(&name.to_uppercase())), Ok(one));
        // Each command word is one the parser accepts as a first keyword and as a help topic.
        assert!(parse_command(name).map_or_else(|e| e.index > 1, |_| true), "{name}");
        assert_eq!(parsed(&format!("help {name}")), OperatorCommand::Help { topic: Some(name.to_string()) });
    }
    assert_eq!(COMMAND_NAMES.len(), HELP.len());
    // One line per usage form: every form in the list is a usage the parser documents.
    for form in ["goto X Y", "waypoint add X Y", "waypoint clear", "mission abort", "set position X Y [YAW]"]
    {
        assert!(list.contains(form), "{form} missing:\n{list}");
    }
    let unknown = help_text(Some("fly")).expect_err("unknown topic");
    assert_eq!((unknown.index, unknown.token.as_deref()), (2, Some("fly")));
    assert!(unknown.to_string().contains("\"fly\""));
}

#[test]
fn angles_typed_in_degrees_print_back_as_typed() {
    for degrees in ["90", "-45.5", "0.1", "359.99", "1e-7", "12345.678"] {
        let value: f64 = degrees.parse().expect("literal");
        let turn = OperatorCommand::Turn { angle: value.to_radians() };
        assert_eq!(turn.to_string(), format!("turn {degrees}"));
    }
    assert_eq!(OperatorCommand::Goto { x: 1.5, y: -2.0 }.to_string(), "goto 1.5 -2");
}

#[test]
fn radians_without_an_exact_degree_form_fall_back_to_rad() {
    // A double just above pi/2 whose degree image sits in a binade where x*pi/180 skips values.
    let mut angle = FRAC_PI_2;
    let mut found = None;
    for _ in 0..10_000 {
        angle = angle.next_up();
        let text = OperatorCommand::Turn { angle }.to_string();
        if text.ends_with("rad") {
            found = Some((angle, text));
            break;
        }
    }
    let (angle, text) = found.expect("some double near pi/2 has no exact degree form");
    // The fallback is taken only when truly no degree value nearby maps back exactly.
    let degrees = angle.to_degrees();
    let mut probe = degrees;
    for _ in 0..4 {
        probe = probe.next_down();
    }
    for _ in 0..9 {
        assert_ne!(probe.to_radians(), angle);
        probe = probe.next_up();
    }
    assert_eq!(parsed(&text), OperatorCommand::Turn { angle });
}

fn finite() -> impl Strategy<Value = f64> {
    prop_oneof![
        // Every bit pattern's value folded into the smallest bound (60 rad < 36000 deg).
        any::<f64>().prop_filter("finite", |v| v.is_finite()).prop_map(|v| v % 60.0),
        (-6_000i64..6_000).prop_map(|v| v as f64 / 100.0),
        -60.0..60.0f64,
    ]
}

fn command() -> impl Strategy<Value = OperatorCommand> {
    use OperatorCommand as C;
    prop_oneof![
        (finite(), finite()).prop_map(|(x, y)| C::Goto { x, y }),
        (finite(), finite()).prop_map(|(x, y)| C::WaypointAdd { x, y }),
        Just(C::WaypointClear),
        Just(C::WaypointList),
        Just(C::MissionStart),
        Just(C::MissionPause),
        Just(C::MissionAbort),
        Just(C::Stop),
        finite().prop_map(|distance| C::Drive { distance }),
        finite().prop_map(|angle| C::Turn { angle }),
        (finite(), finite(), proptest::option::of(finite())).prop_map(|(x, y, yaw)| C::SetPosition {
            x,
            y,
            yaw
        }),
        (finite(), finite()).prop_map(|(row, col)| C::TrackPixel { row, col }),
        (finite(), finite(), finite()).prop_map(|(x, y, z)| C::TrackSite { x, y, z }),
        (finite(), finite()).prop_map(|(x, y)| C::Place { x, y }),
        (finite(), -90.0..=90.0f64).prop_map(|(pan, tilt)| C::Navcam { pan, tilt: tilt.to_radians() }),
        (any::<bool>(), finite()).prop_map(|(left, distance)| C::Motor {
            side: if left { MotorSide::Left } else { MotorSide::Right },
            distance
        }),
        Just(C::Status),
        proptest::option::of(proptest::sample::select(COMMAND_NAMES))
            .prop_map(|topic| C::Help { topic: topic.map(str::to_string) }),
    ]
}

/// Lines built from the grammar's own words, so the fuzzing reaches past the first token.
fn near_miss_line() -> impl Strategy<Value = String> {
    let word = prop_oneof![
        proptest::sample::select(vec![
            "goto", "waypoint", "add", "clear", "list", "mission", "start", "pause", "abort", "stop",
            "drive", "turn", "set", "position", "status", "help", "#", "nan", "inf", "1e999", "°", "m",
            "deg", "rad", "-0", "1.5", "é",
        ])
        .prop_map(str::to_string),
        "\\PC{0,6}",
    ];
    proptest::collection::vec(word, 0..7).prop_map(|words| words.join(" "))
}

proptest! {
    #[test]
    fn parse_never_panics_on_arbitrary_text(line in "\\PC*") {
        let _ = parse_command(&line);
    }

    #[test]
    fn parse_errors_point_at_a_real_token(line in near_miss_line()) {
        if let Err(error) = parse_command(&line) {
            let code = line.split_once('#').map_or(line.as_str(), |(before, _)| before);
            let words: Vec<&str> = code.split_whitespace().collect();
            prop_assert!(error.index >= 1);
            prop_assert_eq!(error.token.as_deref(), words.get(error.index - 1).copied());
            prop_assert!(!error.to_string().contains('\n'));
        }
    }

    #[test]
    fn display_parses_back_to_the_same_command(command in command()) {
        let text = command.to_string();
        prop_assert_eq!(parse_command(&text), Ok(Some(command.clone())), "text {:?}", text);
    }
}

#[test]
fn a_navcam_tilt_beyond_straight_up_or_down_names_its_token() {
    let e = parse_command("navcam 10 95").unwrap_err();
    assert_eq!((e.index, e.token_text()), (3, "95"));
    assert!(e.expected.contains("-90..90") && e.expected.contains("navcam [PAN [TILT]]"), "{}", e.expected);
    assert!(parse_command("navcam 10 -90").is_ok(), "straight down is allowed");
    let e = parse_command("navcam 1 2 3").unwrap_err();
    assert_eq!((e.index, e.token_text()), (4, "3"));
}
