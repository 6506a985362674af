//! The operator command language: plain-text commands in the spirit of SR2's operator interface
//! (paper 001 section 6), typed at `rovernav run --interactive` or sent over the bus.
//!
//! Units on the wire are the operator's: metres and degrees; the typed commands carry metres and
//! radians (ROS conventions: x east/forward, y north/left, angles counter-clockwise).
//!
//! Grammar (one command a line, whitespace-separated tokens, keywords case-insensitive):
//!
//! ```text
//! goto X Y                     waypoint add X Y | waypoint clear | waypoint list
//! mission start | pause | abort  stop   status   help [COMMAND]
//! drive D                      turn A              set position X Y [YAW]
//! ```
//!
//! A `#` starts a comment running to the end of the line; blank and comment-only lines parse to
//! `Ok(None)`. Numbers are decimal (`2`, `-0.5`, `1e3`) and must be finite. Distances may carry
//! the suffix `m` (`2m`); angles are degrees unless suffixed: `deg` or `°` (degrees) or `rad`
//! (radians), e.g. `90deg`, `1.5708rad`. No other units are accepted, so a distance typed as
//! `3deg` is an error rather than a silent misreading. Every error names the offending token by
//! its 1-based index and text (`end of line` when a token is missing).
//!
//! `Display` prints the canonical form, which parses back to the identical command (bit-exact
//! numbers): metres without a suffix, angles as the shortest decimal degree value that converts
//! back to exactly the same radians, or in `rad` when no decimal degree value does. The round
//! trip holds for every command `parse_command` can produce; a hand-built command with a
//! non-finite number or an unknown help topic prints, but does not parse back.

use std::fmt;

/// One operator command, parsed.
#[derive(Clone, Debug, PartialEq)]
pub enum OperatorCommand {
    /// `goto X Y`: replace the goal (local frame, m) and drive there.
    Goto {
        /// East (m).
        x: f64,
        /// North (m).
        y: f64,
    },
    /// `waypoint add X Y`: append a waypoint to visit before the goal.
    WaypointAdd {
        /// East (m).
        x: f64,
        /// North (m).
        y: f64,
    },
    /// `waypoint clear`: forget all waypoints.
    WaypointClear,
    /// `waypoint list`: print the waypoints.
    WaypointList,
    /// `mission start`: start (or resume) the mission plan.
    MissionStart,
    /// `mission pause`: stop after the current command and hold.
    MissionPause,
    /// `mission abort`: end the mission with outcome `aborted`.
    MissionAbort,
    /// `stop`: emergency stop; every component goes to Emergency.
    Stop,
    /// `drive D`: drive straight D metres (negative backwards), outside the mission plan.
    Drive {
        /// Signed distance (m).
        distance: f64,
    },
    /// `turn A`: turn in place by A degrees (positive counter-clockwise).
    Turn {
        /// Signed angle (rad).
        angle: f64,
    },
    /// `set position X Y [YAW]`: an authoritative external position fix (MRPTA's reset).
    SetPosition {
        /// East (m).
        x: f64,
        /// North (m).
        y: f64,
        /// Heading (rad); keeps the current estimate's heading when absent.
        yaw: Option<f64>,
    },
    /// `status`: print the rover's state.
    Status,
    /// `help [COMMAND]`: list the commands, or describe one.
    Help {
        /// The command asked about; `parse_command` stores it lower-case, one of [`COMMAND_NAMES`].
        topic: Option<String>,
    },
}

/// Every command's first keyword, in the order `help` lists them (for completion and help topics).
pub const COMMAND_NAMES: &[&str] =
    &["goto", "waypoint", "mission", "stop", "drive", "turn", "set", "status", "help"];

/// A malformed command line or unknown help topic: which token was wrong and what was expected.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("token {index} {}: expected {expected}", shown_token(.token))]
pub struct CommandError {
    /// 1-based position of the offending token on the line.
    pub index: usize,
    /// The offending token as typed; `None` when the line ended where a token was needed.
    pub token: Option<String>,
    /// What the grammar wanted at that position, naming the argument and the usage it belongs to.
    pub expected: String,
}

impl CommandError {
    /// The offending token's text, or `"end of line"` when it was missing.
    pub fn token_text(&self) -> &str {
        self.token.as_deref().unwrap_or("end of line")
    }
}

fn shown_token(token: &Option<String>) -> String {
    match token {
        // Debug quoting escapes control characters so the error stays on one line.
        Some(text) => format!("{text:?}"),
        None => "(end of line)".to_string(),
    }
}

const USAGE_GOTO: &str = "goto X Y";
const USAGE_WAYPOINT: &str = "waypoint add X Y | waypoint clear | waypoint list";
const USAGE_WAYPOINT_ADD: &str = "waypoint add X Y";
const USAGE_MISSION: &str = "mission start | mission pause | mission abort";
const USAGE_DRIVE: &str = "drive D";
const USAGE_TURN: &str = "turn A";
const USAGE_SET: &str = "set position X Y [YAW]";
const USAGE_HELP: &str = "help [COMMAND]";

/// One command's help: its usage forms with a summary each, and the details shown by `help NAME`.
struct HelpEntry {
    name: &'static str,
    forms: &'static [(&'static str, &'static str)],
    detail: &'static str,
}

const HELP: &[HelpEntry] = &[
    HelpEntry {
        name: "goto",
        forms: &[(USAGE_GOTO, "replace the goal with (X, Y) and drive there")],
        detail: "X east, Y north, in metres in the local frame.",
    },
    HelpEntry {
        name: "waypoint",
        forms: &[
            (USAGE_WAYPOINT_ADD, "append a waypoint to visit before the goal"),
            ("waypoint clear", "forget all waypoints"),
            ("waypoint list", "print the waypoints"),
        ],
        detail: "Waypoints are visited in the order added; X east, Y north, in metres.",
    },
    HelpEntry {
        name: "mission",
        forms: &[
            ("mission start", "start (or resume) the mission plan"),
            ("mission pause", "stop after the current command and hold"),
            ("mission abort", "end the mission with outcome `aborted`"),
        ],
        detail: "Pause holds the rover in place; start resumes where the plan left off.",
    },
    HelpEntry {
        name: "stop",
        forms: &[("stop", "emergency stop: every component goes to Emergency")],
        detail: "Takes effect at once, whatever the mission is doing.",
    },
    HelpEntry {
        name: "drive",
        forms: &[(USAGE_DRIVE, "drive straight D metres (negative backwards), outside the plan")],
        detail: "D in metres, optional suffix m (`drive 2m`).",
    },
    HelpEntry {
        name: "turn",
        forms: &[(USAGE_TURN, "turn in place by A degrees (positive counter-clockwise)")],
        detail: "A in degrees, or suffixed: `90deg`, `90°`, `1.5708rad`.",
    },
    HelpEntry {
        name: "set",
        forms: &[(USAGE_SET, "external position fix (MRPTA reset); YAW in degrees")],
        detail: "Authoritative fix: X east, Y north in metres; the heading is kept when YAW is absent.",
    },
    HelpEntry {
        name: "status",
        forms: &[("status", "print the rover's state")],
        detail: "Pose estimate, mission state, goal and waypoints.",
    },
    HelpEntry {
        name: "help",
        forms: &[(USAGE_HELP, "list the commands, or describe one")],
        detail: "COMMAND is a first keyword, e.g. `help waypoint`.",
    },
];

const UNITS_NOTE: &str =
    "Numbers are metres and degrees (suffixes m, deg, rad allowed); `#` starts a comment.";

/// The command list with one line per usage form, or the usage and details of one command.
pub fn help_text(topic: Option<&str>) -> Result<String, CommandError> {
    let Some(topic) = topic else {
        let mut text = String::from("Commands:\n");
        for form in HELP.iter().flat_map(|entry| entry.forms) {
            text.push_str(&format!("  {:<24} {}\n", form.0, form.1));
        }
        text.push_str(UNITS_NOTE);
        text.push('\n');
        return Ok(text);
    };
    let entry = HELP
        .iter()
        .find(|entry| entry.name.eq_ignore_ascii_case(topic.trim()))
        .ok_or_else(|| unknown_topic(2, topic))?;
    let mut text = String::new();
    for form in entry.forms {
        text.push_str(&format!("{}: {}\n", form.0, form.1));
    }
    text.push_str(entry.detail);
    text.push('\n');
    text.push_str(UNITS_NOTE);
    text.push('\n');
    Ok(text)
}

fn unknown_topic(index: usize, topic: &str) -> CommandError {
    CommandError {
        index,
        token: Some(topic.to_string()),
        expected: format!("a command name ({}) in \"{USAGE_HELP}\"", COMMAND_NAMES.join(", ")),
    }
}

/// Which unit a numeric argument is in, deciding the suffixes it accepts.
#[derive(Clone, Copy)]
enum Unit {
    Metres,
    Degrees,
}

/// The tokens of one line with the 1-based index of the next one.
struct Tokens<'a> {
    words: std::str::SplitWhitespace<'a>,
    index: usize,
}

impl<'a> Tokens<'a> {
    fn next(&mut self) -> (usize, Option<&'a str>) {
        self.index += 1;
        (self.index, self.words.next())
    }

    fn error(index: usize, token: Option<&str>, expected: String) -> CommandError {
        CommandError { index, token: token.map(str::to_string), expected }
    }

    /// The next token, which must be one of `choices` (case-insensitive); returns the canonical one.
    fn keyword(&mut self, choices: &[&'static str], usage: &str) -> Result<&'static str, CommandError> {
        let (index, token) = self.next();
        token
            .and_then(|word| choices.iter().copied().find(|choice| choice.eq_ignore_ascii_case(word)))
            .ok_or_else(|| Self::error(index, token, format!("{} in \"{usage}\"", one_of(choices))))
    }

    fn number(&mut self, unit: Unit, name: &str, usage: &str) -> Result<f64, CommandError> {
        let (index, token) = self.next();
        let unit_name = match unit {
            Unit::Metres => "metres",
            Unit::Degrees => "degrees",
        };
        let value = token.ok_or(()).and_then(|word| parse_quantity(word, unit));
        value.map_err(|()| {
            Self::error(index, token, format!("a number ({unit_name}) for {name} in \"{usage}\""))
        })
    }

    fn optional_number(&mut self, unit: Unit, name: &str, usage: &str) -> Result<Option<f64>, CommandError> {
        if self.words.clone().next().is_none() {
            return Ok(None);
        }
        self.number(unit, name, usage).map(Some)
    }

    fn end(&mut self, usage: &str) -> Result<(), CommandError> {
        match self.next() {
            (_, None) => Ok(()),
            (index, token) => Err(Self::error(index, token, format!("end of line after \"{usage}\""))),
        }
    }
}

fn one_of(choices: &[&str]) -> String {
    match choices {
        [only] => format!("\"{only}\""),
        [init @ .., last] => format!("{} or {last}", init.join(", ")),
        [] => "nothing".to_string(),
    }
}

/// `word` without `suffix` at its end (ASCII case-insensitive), if it ends so.
fn strip_suffix_ignore_case<'w>(word: &'w str, suffix: &str) -> Option<&'w str> {
    let split = word.len().checked_sub(suffix.len())?;
    // `get` rather than slicing: `split` may fall inside a multi-byte character of arbitrary input.
    let (head, tail) = (word.get(..split)?, word.get(split..)?);
    tail.eq_ignore_ascii_case(suffix).then_some(head)
}

/// A finite number in metres or radians from a token with an optional unit suffix.
fn parse_quantity(word: &str, unit: Unit) -> Result<f64, ()> {
    let (digits, to_internal): (&str, fn(f64) -> f64) = match unit {
        Unit::Metres => (strip_suffix_ignore_case(word, "m").unwrap_or(word), |v| v),
        Unit::Degrees => {
            if let Some(digits) = strip_suffix_ignore_case(word, "rad") {
                (digits, |v| v)
            } else {
                let digits =
                    strip_suffix_ignore_case(word, "deg").or_else(|| word.strip_suffix('°')).unwrap_or(word);
                (digits, f64::to_radians)
            }
        }
    };
    let value: f64 = digits.parse().map_err(|_| ())?;
    let value = to_internal(value);
    if value.is_finite() { Ok(value) } else { Err(()) }
}

/// Parses one line; `Ok(None)` for a blank or comment-only line.
pub fn parse_command(line: &str) -> Result<Option<OperatorCommand>, CommandError> {
    let code = line.split_once('#').map_or(line, |(before, _comment)| before);
    let mut tokens = Tokens { words: code.split_whitespace(), index: 0 };
    if tokens.words.clone().next().is_none() {
        return Ok(None);
    }
    let (index, first) = tokens.next();
    let first = first.unwrap_or_default();
    let name =
        COMMAND_NAMES.iter().copied().find(|name| name.eq_ignore_ascii_case(first)).ok_or_else(|| {
            Tokens::error(index, Some(first), format!("a command ({})", COMMAND_NAMES.join(", ")))
        })?;
    let command = match name {
        "goto" => {
            let x = tokens.number(Unit::Metres, "X", USAGE_GOTO)?;
            let y = tokens.number(Unit::Metres, "Y", USAGE_GOTO)?;
            tokens.end(USAGE_GOTO)?;
            OperatorCommand::Goto { x, y }
        }
        "waypoint" => match tokens.keyword(&["add", "clear", "list"], USAGE_WAYPOINT)? {
            "add" => {
                let x = tokens.number(Unit::Metres, "X", USAGE_WAYPOINT_ADD)?;
                let y = tokens.number(Unit::Metres, "Y", USAGE_WAYPOINT_ADD)?;
                tokens.end(USAGE_WAYPOINT_ADD)?;
                OperatorCommand::WaypointAdd { x, y }
            }
            "clear" => {
                tokens.end("waypoint clear")?;
                OperatorCommand::WaypointClear
            }
            _ => {
                tokens.end("waypoint list")?;
                OperatorCommand::WaypointList
            }
        },
        "mission" => {
            let (usage, command) = match tokens.keyword(&["start", "pause", "abort"], USAGE_MISSION)? {
                "start" => ("mission start", OperatorCommand::MissionStart),
                "pause" => ("mission pause", OperatorCommand::MissionPause),
                _ => ("mission abort", OperatorCommand::MissionAbort),
            };
            tokens.end(usage)?;
            command
        }
        "stop" => {
            tokens.end("stop")?;
            OperatorCommand::Stop
        }
        "drive" => {
            let distance = tokens.number(Unit::Metres, "D", USAGE_DRIVE)?;
            tokens.end(USAGE_DRIVE)?;
            OperatorCommand::Drive { distance }
        }
        "turn" => {
            let angle = tokens.number(Unit::Degrees, "A", USAGE_TURN)?;
            tokens.end(USAGE_TURN)?;
            OperatorCommand::Turn { angle }
        }
        "set" => {
            tokens.keyword(&["position"], USAGE_SET)?;
            let x = tokens.number(Unit::Metres, "X", USAGE_SET)?;
            let y = tokens.number(Unit::Metres, "Y", USAGE_SET)?;
            let yaw = tokens.optional_number(Unit::Degrees, "YAW", USAGE_SET)?;
            tokens.end(USAGE_SET)?;
            OperatorCommand::SetPosition { x, y, yaw }
        }
        "status" => {
            tokens.end("status")?;
            OperatorCommand::Status
        }
        _ => {
            let topic = match tokens.next() {
                (_, None) => None,
                (index, Some(word)) => Some(
                    COMMAND_NAMES
                        .iter()
                        .find(|name| name.eq_ignore_ascii_case(word))
                        .ok_or_else(|| unknown_topic(index, word))?
                        .to_string(),
                ),
            };
            if topic.is_some() {
                tokens.end(USAGE_HELP)?;
            }
            OperatorCommand::Help { topic }
        }
    };
    Ok(Some(command))
}

/// A number as the shortest text that parses back to the same `f64`, exponent form when long.
fn number_text(value: f64) -> String {
    let magnitude = value.abs();
    if magnitude == 0.0 || (1e-4..1e15).contains(&magnitude) {
        format!("{value}")
    } else {
        format!("{value:e}")
    }
}

/// An angle (rad) as the degree text that converts back to exactly `radians`, else in `rad`.
fn angle_text(radians: f64) -> String {
    let degrees = radians.to_degrees();
    if degrees.is_finite() {
        // Fewest significant digits first, so an angle typed as `turn 90` prints as `90`.
        for digits in 0..17 {
            if let Ok(candidate) = format!("{degrees:.digits$e}").parse::<f64>()
                && candidate.to_radians() == radians
            {
                return number_text(candidate);
            }
        }
        // `to_degrees` may land a few ulps off a value whose conversion back is exact.
        let (mut up, mut down) = (degrees, degrees);
        for _ in 0..4 {
            (up, down) = (up.next_up(), down.next_down());
            for candidate in [up, down] {
                if candidate.is_finite() && candidate.to_radians() == radians {
                    return number_text(candidate);
                }
            }
        }
    }
    // Multiplying by pi/180 skips some doubles, so some radian values have no exact degree form.
    format!("{}rad", number_text(radians))
}

impl fmt::Display for OperatorCommand {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Goto { x, y } => write!(f, "goto {} {}", number_text(*x), number_text(*y)),
            Self::WaypointAdd { x, y } => write!(f, "waypoint add {} {}", number_text(*x), number_text(*y)),
            Self::WaypointClear => f.write_str("waypoint clear"),
            Self::WaypointList => f.write_str("waypoint list"),
            Self::MissionStart => f.write_str("mission start"),
            Self::MissionPause => f.write_str("mission pause"),
            Self::MissionAbort => f.write_str("mission abort"),
            Self::Stop => f.write_str("stop"),
            Self::Drive { distance } => write!(f, "drive {}", number_text(*distance)),
            Self::Turn { angle } => write!(f, "turn {}", angle_text(*angle)),
            Self::SetPosition { x, y, yaw } => {
                write!(f, "set position {} {}", number_text(*x), number_text(*y))?;
                match yaw {
                    Some(yaw) => write!(f, " {}", angle_text(*yaw)),
                    None => Ok(()),
                }
            }
            Self::Status => f.write_str("status"),
            Self::Help { topic: None } => f.write_str("help"),
            Self::Help { topic: Some(topic) } => write!(f, "help {topic}"),
        }
    }
}

#[cfg(test)]
mod tests {
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
    fn help_lists_every_command_and_describes_each() {
        let list = help_text(None).expect("full list");
        for name in COMMAND_NAMES {
            assert!(list.lines().any(|line| line.trim_start().starts_with(name)), "{name} missing:\n{list}");
            let one = help_text(Some(name)).expect("known topic");
            assert!(one.starts_with(name), "{one}");
            assert_eq!(help_text(Some(&name.to_uppercase())), Ok(one));
            // Each command word is one the parser accepts as a first keyword and as a help topic.
            assert!(parse_command(name).map_or_else(|e| e.index > 1, |_| true), "{name}");
            assert_eq!(
                parsed(&format!("help {name}")),
                OperatorCommand::Help { topic: Some(name.to_string()) }
            );
        }
        assert_eq!(COMMAND_NAMES.len(), HELP.len());
        // One line per usage form: every form in the list is a usage the parser documents.
        for form in
            ["goto X Y", "waypoint add X Y", "waypoint clear", "mission abort", "set position X Y [YAW]"]
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
            any::<f64>().prop_filter("finite", |v| v.is_finite()),
            (-100_000i64..100_000).prop_map(|v| v as f64 / 100.0),
            -1e3..1e3f64,
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
}
