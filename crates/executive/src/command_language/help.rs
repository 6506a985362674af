//! The command language's help: one entry per command, its usage forms and details.

use super::{
    CommandError, USAGE_DRIVE, USAGE_GOTO, USAGE_HELP, USAGE_NAVCAM, USAGE_PLACE, USAGE_SET, USAGE_TURN,
    USAGE_WAYPOINT_ADD, unknown_topic,
};

/// One command's help: its usage forms with a summary each, and the details shown by `help NAME`.
pub(super) struct HelpEntry {
    name: &'static str,
    forms: &'static [(&'static str, &'static str)],
    detail: &'static str,
}

pub(super) const HELP: &[HelpEntry] = &[
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
        name: "track",
        forms: &[
            ("track ROW COL", "approach the target at a pixel of the current left Navcam image"),
            ("track X Y Z", "approach the site-frame point (X, Y, Z) by visual target tracking"),
        ],
        detail: "The rover re-finds the target after each step of at most 10 % of the distance and stops 1 m \
                 short of it; a lost target stops it and asks for help. ROW and COL in pixels (suffix px).",
    },
    HelpEntry {
        name: "place",
        forms: &[(USAGE_PLACE, "place the instrument on (X, Y) with AutoPlace, or refuse with the reason")],
        detail: "X east, Y north in metres, within the arm's reach in front of the rover (0.4-1.2 m, 45 deg either \
                 side). The rover turns to face the point if needed, images it with the front Hazcams and the \
                 Navcams, and places on the safe target nearest it; a refusal (no_data, normal, roughness, \
                 reach, collision) moves nothing.",
    },
    HelpEntry {
        name: "navcam",
        forms: &[(USAGE_NAVCAM, "take a Navcam stereo pair with the mast head at PAN, TILT degrees")],
        detail: "Needs the mission paused, like `drive` and `turn`. PAN counter-clockwise from forward (default 0), \
                 TILT up from level within -90..90 (default -20: the ground about 4 m ahead). The pair goes on \
                 /camera/image: the console's camera panel, the log and `track ROW COL` use it.",
    },
    HelpEntry {
        name: "motor",
        forms: &[
            ("motor left D", "run the left motor D metres (negative backwards), the right wheels held"),
            ("motor right D", "run the right motor D metres (negative backwards), the left wheels held"),
        ],
        detail: "Needs the mission paused. The rover pivots about the held side's wheels: D metres of wheel \
                 travel turn it by D / track radians (clockwise for the left motor forward). D in metres, optional suffix m.",
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
