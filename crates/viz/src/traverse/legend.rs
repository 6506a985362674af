//! What a traverse picture draws, in which colour, and the legend naming each kind that is
//! present in a given picture (and only those).

use super::frame::Frame;
use super::{TraverseScene, map_px_per_m};
use plotters::style::RGBColor;
use rovernav_core::{Overlay, OverlayKind};
use rovernav_terrain::Rock;

/// The driven (true) path.
pub const DRIVEN: RGBColor = RGBColor(255, 255, 255);
/// The estimated path.
pub const ESTIMATED: RGBColor = RGBColor(255, 225, 0);
/// The last plan.
pub const PLAN: RGBColor = RGBColor(30, 80, 255);
/// Earlier plans.
pub const OLD_PLAN: RGBColor = RGBColor(130, 160, 255);
/// Rocks taller than the belly clearance.
pub const HAZARD_ROCK: RGBColor = RGBColor(205, 30, 25);
/// Smaller rocks' outlines.
pub const ROCK: RGBColor = RGBColor(80, 60, 45);
/// C-obstacles.
pub const C_OBSTACLE: RGBColor = RGBColor(255, 140, 0);
/// Sensed wedges.
pub const WEDGE: RGBColor = RGBColor(0, 175, 255);
/// Other navigator drawings.
pub const OTHER: RGBColor = RGBColor(225, 225, 225);
/// Keep-out zones.
pub const KEEP_OUT: RGBColor = RGBColor(255, 0, 255);
/// Hazard contacts.
pub const CONTACT: RGBColor = RGBColor(255, 0, 0);
/// The start.
pub const START: RGBColor = RGBColor(0, 200, 0);
/// The goal and its tolerance.
pub const GOAL: RGBColor = RGBColor(255, 200, 0);
/// Waypoints.
pub const WAYPOINT: RGBColor = RGBColor(0, 230, 230);
/// The true end and the footprint there.
pub const TRUE_END: RGBColor = RGBColor(255, 255, 255);
/// A VTT target as designated.
pub const VTT_TARGET: RGBColor = RGBColor(255, 70, 160);
/// The estimates of a VTT target along the way.
pub const VTT_ESTIMATE: RGBColor = RGBColor(170, 110, 255);
/// Outlines that keep light marks visible on light ground.
pub const EDGE: RGBColor = RGBColor(0, 0, 0);

/// Legend swatches' background.
pub const SWATCH: RGBColor = RGBColor(150, 120, 95);

/// Every solid colour marks are drawn in: a PNG palette keeps these exactly.
pub const SOLID: [RGBColor; 21] = [
    DRIVEN,
    ESTIMATED,
    PLAN,
    OLD_PLAN,
    HAZARD_ROCK,
    ROCK,
    C_OBSTACLE,
    WEDGE,
    OTHER,
    KEEP_OUT,
    CONTACT,
    START,
    GOAL,
    WAYPOINT,
    EDGE,
    SWATCH,
    VTT_TARGET,
    VTT_ESTIMATE,
    RGBColor(255, 0, 0),
    RGBColor(30, 30, 30),
    RGBColor(60, 60, 60),
];

/// How a legend entry's sample is drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Mark {
    /// A line of a width (px).
    Line(RGBColor, u32),
    /// A translucent patch.
    Patch(RGBColor),
    /// A filled disc.
    Disc(RGBColor),
    /// A ring.
    Ring(RGBColor),
    /// An X.
    Cross(RGBColor),
    /// A diamond.
    Diamond(RGBColor),
    /// A rectangle outline.
    Outline(RGBColor),
    /// A + crosshair.
    Crosshair(RGBColor),
    /// Small dots joined by a line.
    Dots(RGBColor),
}

/// One legend line.
#[derive(Clone, Debug, PartialEq)]
pub struct Entry {
    /// Sample.
    pub mark: Mark,
    /// Words.
    pub label: String,
}

/// How the map draws a rock: a filled disc for one taller than the belly clearance (at least
/// 2 px across, so none is lost at any scale), an outline for a smaller one as wide as 1.5 px
/// or more, nothing for a smaller one under that.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RockMark {
    /// Taller than the belly clearance.
    Hazard,
    /// Smaller, wide enough to draw.
    Small,
}

/// The mark of `rock` on a map of `px_per_m` framed by `frame` (`None`: not drawn), the one rule
/// the map and the legend share.
pub fn rock_mark(rock: &Rock, clearance: f64, frame: &Frame, px_per_m: f64) -> Option<RockMark> {
    let reach = rock.diameter;
    let overlaps = rock.x + reach >= frame.x0
        && rock.x - reach <= frame.x1
        && rock.y + reach >= frame.y0
        && rock.y - reach <= frame.y1;
    if !overlaps {
        None
    } else if rock.height > clearance {
        Some(RockMark::Hazard)
    } else if 0.5 * rock.diameter * px_per_m >= 1.5 {
        Some(RockMark::Small)
    } else {
        None
    }
}

fn entry(mark: Mark, label: &str) -> Entry {
    Entry { mark, label: label.to_string() }
}

/// The legend of a scene drawn in `frame`: one entry per kind of mark present, in drawing order.
pub fn entries(scene: &TraverseScene<'_>, frame: &Frame) -> Vec<Entry> {
    let mut out = Vec::new();
    let trace = scene.trace;
    if trace.sensed.as_ref().is_some_and(|s| s.data.iter().any(|&v| v)) {
        out.push(entry(Mark::Patch(RGBColor(60, 200, 255)), "ground seen by range sensors"));
    }
    let px_per_m = map_px_per_m(frame);
    let (mut tall, mut small) = (false, false);
    for r in &scene.terrain.rocks {
        match rock_mark(r, scene.rover.clearance, frame, px_per_m) {
            Some(RockMark::Hazard) => tall = true,
            Some(RockMark::Small) => small = true,
            None => {}
        }
    }
    if tall {
        out.push(entry(Mark::Disc(HAZARD_ROCK), "rock taller than the belly clearance"));
    }
    if small {
        out.push(entry(Mark::Ring(ROCK), "smaller rock"));
    }
    if !scene.goal.keep_out.is_empty() {
        out.push(entry(Mark::Patch(KEEP_OUT), "keep-out zone"));
    }
    let has = |kind: OverlayKind| {
        trace
            .overlays
            .iter()
            .any(|o| matches!(o, Overlay::Polygon(_, k) | Overlay::Polyline(_, k) if *k == kind))
    };
    for (kind, label) in [
        (OverlayKind::CObstacle, "C-obstacle (obstacle grown by the rover's size)"),
        (OverlayKind::Wedge, "sensed wedge"),
        (OverlayKind::Plan, "navigator's path drawing"),
        (OverlayKind::Other, "other navigator drawing"),
    ] {
        if has(kind) {
            out.push(entry(Mark::Line(overlay_colour(kind), 2), label));
        }
    }
    if trace.plans.len() > 1 {
        out.push(entry(Mark::Line(OLD_PLAN, 1), "earlier plans"));
    }
    if !trace.plans.is_empty() {
        out.push(entry(Mark::Line(PLAN, 2), "last plan"));
    }
    if trace.estimate.len() > 1 {
        out.push(entry(Mark::Line(ESTIMATED, 1), "estimated path"));
    }
    if trace.truth.len() > 1 {
        out.push(entry(Mark::Line(DRIVEN, 3), "driven path (truth)"));
    }
    if !scene.report.hazard_events.is_empty() {
        out.push(entry(Mark::Cross(CONTACT), "hazard contact"));
    }
    out.push(entry(Mark::Disc(START), "start"));
    out.push(entry(Mark::Ring(GOAL), "goal and its tolerance"));
    if !scene.goal.waypoints.is_empty() {
        out.push(entry(Mark::Diamond(WAYPOINT), "waypoint"));
    }
    if trace.vtt.iter().any(|v| !v.estimates.is_empty()) {
        out.push(entry(Mark::Dots(VTT_ESTIMATE), "target estimates"));
    }
    if !trace.vtt.is_empty() {
        out.push(entry(Mark::Crosshair(VTT_TARGET), "VTT target"));
    }
    if !trace.truth.is_empty() {
        out.push(entry(Mark::Outline(TRUE_END), "rover footprint at the end (truth)"));
    }
    if !trace.estimate.is_empty() {
        out.push(entry(Mark::Diamond(ESTIMATED), "estimated end"));
    }
    out
}

/// The colour of a navigator overlay kind.
pub fn overlay_colour(kind: OverlayKind) -> RGBColor {
    match kind {
        OverlayKind::CObstacle => C_OBSTACLE,
        OverlayKind::Wedge => WEDGE,
        OverlayKind::Plan => PLAN,
        OverlayKind::Other => OTHER,
    }
}
