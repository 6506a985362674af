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
//! track ROW COL | track X Y Z   place X Y           navcam [PAN [TILT]]
//! motor left D | motor right D
//! ```
//!
//! A `#` starts a comment running to the end of the line; blank and comment-only lines parse to
//! `Ok(None)`. Numbers are decimal (`2`, `-0.5`, `1e3`) and must be finite. Distances may carry
//! the suffix `m` (`2m`); magnitudes are bounded ([`MAX_DRIVE_M`], [`MAX_ANGLE_DEG`],
//! [`MAX_COORDINATE_M`], [`MAX_PIXEL`]); angles are degrees unless suffixed: `deg` or `°` (degrees) or `rad`
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
    /// `track ROW COL`: approach the target at a pixel of the current left Navcam image
    /// (visual target tracking).
    TrackPixel {
        /// Image row (line, px).
        row: f64,
        /// Image column (sample, px).
        col: f64,
    },
    /// `track X Y Z`: approach the site-frame point (X, Y, Z) by visual target tracking.
    TrackSite {
        /// East (m).
        x: f64,
        /// North (m).
        y: f64,
        /// Up (m).
        z: f64,
    },
    /// `place X Y`: place the instrument on the site-frame point (X, Y) with AutoPlace (a
    /// `place_instrument` task queued next).
    Place {
        /// East (m).
        x: f64,
        /// North (m).
        y: f64,
    },
    /// `navcam [PAN [TILT]]`: take a Navcam stereo pair with the mast head at PAN, TILT (body
    /// frame; defaults 0 and [`DEFAULT_NAVCAM_TILT_DEG`]), outside the mission plan.
    Navcam {
        /// Pan, counter-clockwise from forward (rad).
        pan: f64,
        /// Tilt, positive up (rad), within +-90 degrees.
        tilt: f64,
    },
    /// `motor left D` / `motor right D`: run one side's drive motor for D metres of wheel travel
    /// (negative backwards) with the other side held, outside the mission plan (SR2's manual
    /// control of each motor, paper 001 section 6): the rover pivots about the held wheels.
    Motor {
        /// Which side's motor runs.
        side: MotorSide,
        /// Signed wheel travel of that side (m).
        distance: f64,
    },
    /// `status`: print the rover's state.
    Status,
    /// `help [COMMAND]`: list the commands, or describe one.
    Help {
        /// The command asked about; `parse_command` stores it lower-case, one of [`COMMAND_NAMES`].
        topic: Option<String>,
    },
}

/// One side's drive motor (SR2 has one per side).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MotorSide {
    /// The left wheels.
    Left,
    /// The right wheels.
    Right,
}

impl MotorSide {
    /// `left` or `right`.
    pub fn name(self) -> &'static str {
        match self {
            MotorSide::Left => "left",
            MotorSide::Right => "right",
        }
    }
}

/// Largest magnitude of a `turn` angle or a `set position` yaw (degrees: 100 turns).
pub const MAX_ANGLE_DEG: f64 = 36_000.0;
/// Largest magnitude of a `drive` distance (m).
pub const MAX_DRIVE_M: f64 = 1_000.0;
/// Largest magnitude of a coordinate (m), as in mission files.
pub const MAX_COORDINATE_M: f64 = crate::mission::check::MAX_COORDINATE_M;
/// Largest image row or column (px).
pub const MAX_PIXEL: f64 = 100_000.0;
/// The Navcam tilt of a `navcam` command without TILT (degrees): the ground about 4 m ahead of
/// a mast head 1.5 m up.
pub const DEFAULT_NAVCAM_TILT_DEG: f64 = -20.0;

/// Every command's first keyword, in the order `help` lists them (for completion and help topics).
pub const COMMAND_NAMES: &[&str] = &[
    "goto", "waypoint", "mission", "stop", "drive", "turn", "set", "track", "place", "navcam", "motor",
    "status", "help",
];

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
const USAGE_TRACK: &str = "track ROW COL | track X Y Z";
const USAGE_PLACE: &str = "place X Y";
const USAGE_NAVCAM: &str = "navcam [PAN [TILT]]";
const USAGE_MOTOR: &str = "motor left D | motor right D";

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
    Pixels,
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
            Unit::Pixels => "pixels",
        };
        let value = token.ok_or(()).and_then(|word| parse_quantity(word, unit));
        let value = value.map_err(|()| {
            Self::error(index, token, format!("a number ({unit_name}) for {name} in \"{usage}\""))
        })?;
        // Magnitudes are bounded here, at the edge, so that `turn 1e308` is a typing error rather
        // than a turn that never ends (angles are compared in radians, as parsed).
        let (limit, shown) = match (unit, name) {
            (Unit::Degrees, _) => (MAX_ANGLE_DEG.to_radians(), MAX_ANGLE_DEG),
            (Unit::Pixels, _) => (MAX_PIXEL, MAX_PIXEL),
            (Unit::Metres, "D") => (MAX_DRIVE_M, MAX_DRIVE_M),
            (Unit::Metres, _) => (MAX_COORDINATE_M, MAX_COORDINATE_M),
        };
        if value.abs() > limit {
            return Err(Self::error(
                index,
                token,
                format!("a number ({unit_name}) of magnitude at most {shown} for {name} in \"{usage}\""),
            ));
        }
        Ok(value)
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
        Unit::Pixels => (strip_suffix_ignore_case(word, "px").unwrap_or(word), |v| v),
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
        "track" => {
            // Two numbers are a pixel, three a site point.
            let count = tokens.words.clone().count();
            if count == 2 {
                let row = tokens.number(Unit::Pixels, "ROW", "track ROW COL")?;
                let col = tokens.number(Unit::Pixels, "COL", "track ROW COL")?;
                OperatorCommand::TrackPixel { row, col }
            } else {
                let x = tokens.number(Unit::Metres, "X", USAGE_TRACK)?;
                let y = tokens.number(Unit::Metres, "Y", USAGE_TRACK)?;
                let z = tokens.number(Unit::Metres, "Z", "track X Y Z")?;
                tokens.end("track X Y Z")?;
                OperatorCommand::TrackSite { x, y, z }
            }
        }
        "place" => {
            let x = tokens.number(Unit::Metres, "X", USAGE_PLACE)?;
            let y = tokens.number(Unit::Metres, "Y", USAGE_PLACE)?;
            tokens.end(USAGE_PLACE)?;
            OperatorCommand::Place { x, y }
        }
        "navcam" => {
            let pan = tokens.optional_number(Unit::Degrees, "PAN", USAGE_NAVCAM)?.unwrap_or(0.0);
            let (tilt_index, tilt_token) = (tokens.index + 1, tokens.words.clone().next());
            let tilt = tokens
                .optional_number(Unit::Degrees, "TILT", USAGE_NAVCAM)?
                .unwrap_or(DEFAULT_NAVCAM_TILT_DEG.to_radians());
            if tilt.abs() > 90f64.to_radians() {
                return Err(Tokens::error(
                    tilt_index,
                    tilt_token,
                    format!("a tilt (degrees) within -90..90 for TILT in \"{USAGE_NAVCAM}\""),
                ));
            }
            tokens.end(USAGE_NAVCAM)?;
            OperatorCommand::Navcam { pan, tilt }
        }
        "motor" => {
            let side = match tokens.keyword(&["left", "right"], USAGE_MOTOR)? {
                "left" => MotorSide::Left,
                _ => MotorSide::Right,
            };
            let usage = if side == MotorSide::Left { "motor left D" } else { "motor right D" };
            let distance = tokens.number(Unit::Metres, "D", usage)?;
            tokens.end(usage)?;
            OperatorCommand::Motor { side, distance }
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
            Self::TrackPixel { row, col } => write!(f, "track {} {}", number_text(*row), number_text(*col)),
            Self::TrackSite { x, y, z } => {
                write!(f, "track {} {} {}", number_text(*x), number_text(*y), number_text(*z))
            }
            Self::Place { x, y } => write!(f, "place {} {}", number_text(*x), number_text(*y)),
            Self::Navcam { pan, tilt } => write!(f, "navcam {} {}", angle_text(*pan), angle_text(*tilt)),
            Self::Motor { side, distance } => write!(f, "motor {} {}", side.name(), number_text(*distance)),
            Self::Status => f.write_str("status"),
            Self::Help { topic: None } => f.write_str("help"),
            Self::Help { topic: Some(topic) } => write!(f, "help {topic}"),
        }
    }
}

mod help;
#[cfg(test)]
mod tests;

pub use help::help_text;
