//! RoverBug: sensor-based path planning on the local tangent graph (paper 000 section 2,
//! Laubach, Olson, Burdick and Hayati, after the WedgeBug algorithm).
//!
//! The rover keeps no global map: at every sensing position the C-obstacles are rebuilt from the
//! wedges sensed there (step/slope hazards, convex hulls grown by the rover radius plus a safety
//! buffer), and the local tangent graph (LTG) is built inside the visible region. Two modes:
//!
//! * **Motion-to-goal** (section 2.1): sense the mast wedge toward the goal, search the subgraph
//!   G1 of LTG nodes no farther from the goal than `min(d(x, T), d_LEAVE)` with A* for the
//!   locally shortest path to the goal, cut it at the wedge's far radius minus a buffer and drive
//!   it; a blocking obstacle switches to boundary following.
//! * **Boundary following** (section 2.2): "virtual" boundary following swings the mast at
//!   `2 k alpha_mast` alternately on both sides of the goal direction until the conglomerate
//!   wedge shows the obstacle's silhouette vertex in its interior (or halts as trapped once the
//!   scans overlap all around); "normal" boundary following then looks toward the goal
//!   (leaving when a reachable node beats `d_reach`, resetting `d_LEAVE`) and otherwise moves to
//!   the farthest visible boundary vertex in the positive sense, halting as unreachable when the
//!   loop point `V_loop` comes back.
//!
//! Departures from the paper, for the simulated platform:
//! * normal boundary following looks with the mast as well as the forward body pair (the body
//!   pair alone sees 1.5 m), and turns the gaze in steps of `2 alpha_mast`;
//! * the loop is detected when the rover returns within a metre of `V_loop` after leaving it
//!   by more than two metres;
//! * besides the recorded parameters (`d_LEAVE`, `d_reach`, `V_loop`), the C-obstacles of the
//!   last view within reach of the rover are carried to the next one (the mast is blind within
//!   a metre), unless they lie outside that blind zone and the new view has sensed their ground
//!   again: the nearer view supersedes them (stale copies, seen from farther, pile up and close
//!   the gaps of a rock field). Hazard contacts and stops at the edge of the terrain are
//!   recorded as small C-obstacles; after one the rover backs out along the ground it just
//!   crossed;
//! * when planning finds no way on without a proof that the goal is unreachable (the "trapped"
//!   and "no boundary vertex" halts: in clutter the local C-obstacles hem the rover in, closing
//!   gaps that nearer views open), the rover records the dead end as a small C-obstacle and
//!   drives back in reverse along its recorded trail (ground the body has crossed) before a new
//!   motion-to-goal segment, at most `max_retreats` times (so too when the safety check keeps
//!   refusing every motion from one place); a loop through `V_loop` around the goal still halts
//!   at once. A retreat whose turn in place the safety check refuses backs along an arc to its
//!   waypoint when that sweep is clear (within 45 degrees of the rear);
//! * before an escape or that retreat, motion-to-goal is tried once more (once per sensing
//!   position) on C-obstacles grown by the rover radius alone (a *squeeze*): the empirical
//!   safety buffer closes gaps of a rock field that the rover's disc fits through, while the
//!   safety layer below still checks every motion against the body outline for step hazards
//!   (slope hazards have only their C-obstacles; keep-out zones keep the buffer). When that
//!   finds a way on, the next view keeps the smaller growth (the rover then stands within
//!   the buffer of the gap's rocks, whose squeezed C-obstacles are carried as they are until
//!   a nearer view supersedes them); otherwise the buffered C-obstacles come back and the
//!   escape or retreat goes ahead. Escapes and retreats follow only a give-up, never the loop
//!   through `V_loop`, which is a proof;
//! * a rover that finds itself in a C-obstacle's grown margin (noise, a late detection) may
//!   leave across the margin but never across the obstacle's own hull; inside a hull itself
//!   (a crater rim around it) it has no free way out;
//! * when normal boundary following has turned the gaze all around without a boundary vertex
//!   in the interior of the conglomerate wedge (the paper aborts), it steps to the first
//!   directly reachable node not yet visited past the goal direction in the positive sense (a
//!   wall follower's step); when there is none, when boundary following has led it more than
//!   `wander_limit_m` farther from the goal than d_reach (then before the wall follower's
//!   step), or when virtual boundary following finds no silhouette (in clutter the
//!   C-obstacles hide each other's), it takes the LTG path to an unvisited node minimising
//!   path length plus distance to the goal (the TangentBug heuristic), and halts only when
//!   there is no step at all;
//! * the places where boundary following started (Bug's hit points) and where escapes
//!   started are remembered across the restarts this implementation adds (escapes, retreats),
//!   while `visited` holds one boundary-following segment only, and forgotten when the
//!   leaving condition fires or motion-to-goal plans a subpath ending nearer the goal than all
//!   of them (progress, as past Bug's hit points; a plan back to one is not): boundary
//!   following and its fallbacks do not target nodes near them, so the rover cannot shuttle
//!   between the same places of a pocket its own C-obstacles close (seed 4 of the default
//!   yard, where every restart forgot them); when every way on is near one, the best way on
//!   takes one anyway rather than halt. Only these restart points, not every position: a
//!   boundary around an enclosed goal must be followed past ground already crossed for the
//!   loop through `V_loop` to close;
//! * the loop around `V_loop` proves the goal unreachable only when the positions of the
//!   boundary-following segment wind around the goal (more than 3/4 of a turn): in clutter the
//!   rover can come back near `V_loop` around another obstacle;
//! * the step model's ground in each footprint window is the refit holding the most cells,
//!   from the whole-window plane or from level planes at the quartile heights, and a low cell
//!   is a pit only in the window centred on it (`robust_ground`, `pits_in_own_window`):
//!   beside a rock wider than the window the whole-window refit stays tilted between rock and
//!   ground or settles on the rock, and the open ground beside it read as a pit that widened
//!   the C-obstacle by up to a metre;
//! * cell means lose part of a small rock's height, so rocks just over the clearance can escape
//!   the step/slope model behind the C-obstacles. A second, bounded memory of hazard cells on
//!   top heights ([`HazardHeight::Top`], the grid navigators' setting) is kept in a 12 m
//!   robot-centred grid across steps (dead-reckoning drift over a few steps is small against
//!   the margins). Its cells that stand out from the ground around them become extra
//!   C-obstacles grown only by half the rover's width plus an allowance (grown like the others
//!   they would close the gaps of a rock field), and every turn in place and drive is checked
//!   against them, body outline plus margin, before it is commanded: the first leg of every
//!   plan when the LTG is built, later legs at execution (a refused one starts a new step);
//!   turns go the long way round when only that is clear, and a rover that cannot turn in place
//!   at all backs out straight before giving up;
//! * the goal is a region, as the mission gives it: points on a circle well inside the goal
//!   tolerance (0.8 of it, at most the tolerance less 0.15 m), sensed and outside every
//!   C-obstacle, are LTG nodes that end a path when the rover reaches them directly from where
//!   it stands by a free, sensed segment, at no further cost (like the vertices of a
//!   C-obstacle containing the goal).
//!
//! * every forward drive keeps the body over sensed ground (`unseen_looks`): the local
//!   tangent graph needs only the path's centre line in the wedge, so a subpath along a
//!   wedge's bounding ray, behind a rock or across the gaps between an image's far rows sweeps
//!   the body over ground no image covered. The seen part of the drive goes ahead; short of
//!   that the next step also looks at the unseen ground, and after two looks from one place
//!   the drive counts as refused;
//! * the mast sees over low rocks, so the blocking obstacle's far side is in view, which a
//!   Bug algorithm's planar sensor never shows. V_loop and (with `near_side_reach`) d_reach
//!   are taken on the near side, among the boundary vertices the rover sees across free
//!   space; the way to a node that beats d_reach must lie on sensed ground.
//!
//! Mission keep-out polygons are C-obstacles like sensed ones (their hulls, grown alike).

use crate::params::{Field, Param, Unit, turn_threshold_param};
use crate::terrain_model::{HAZARD_MARGIN, T_GRID_RESOLUTION, TOP_HAZARD_MARGIN};
use rovernav_core::{
    DriveGuard, Grid2, NavCommand, NavInput, Navigator, NavigatorStats, Outcome, Overlay, OverlayKind,
    Point2, Pose2, RoverConfig, SenseRequest, angle_diff,
};
use rovernav_perception::{CObstacle, HazardHeight, SensedWedge, TerrainConfig, TerrainEvaluator};
use std::collections::VecDeque;
use std::f64::consts::PI;

/// Fraction of the goal tolerance within which LTG nodes count as arrival: short of the
/// tolerance itself, so that drive error still ends the subpath within it.
const ARRIVAL_FRACTION: f64 = 0.8;
/// Points on the circle of arrival around the goal offered to the LTG as nodes.
const ARRIVAL_POINTS: usize = 16;
/// Shortest hop onto the circle of arrival from outside the tolerance (m): motion-to-goal
/// drops subpaths under 0.1 m.
const ARRIVAL_MIN_HOP: f64 = 0.15;
/// Look-ahead beyond the body's ends in the unseen-ground check (m): the wheel radius, over
/// which the simulator's step check looks ahead of each wheel.
const UNSEEN_LOOKAHEAD: f64 = 0.1;
/// Margin by which a drive held back from unseen ground stops short of it (m).
const UNSEEN_BACKOFF: f64 = 0.1;
/// Shortest drive toward unseen ground worth commanding before looking at it (m).
const UNSEEN_MIN_DRIVE: f64 = 0.3;
/// Spacing of the body poses recorded along a drive or a turn (m, and rad for turns).
const SWEPT_STEP: f64 = 0.05;

/// Tunable parameters of RoverBug.
#[derive(Clone, Debug)]
pub struct RoverBugConfig {
    /// Empirical safety buffer added to the rover radius when growing C-obstacles (m; paper 000
    /// section 2).
    pub safety_buffer: f64,
    /// Fraction of the rover's belly clearance at which the step model behind the C-obstacles
    /// (on cell means) marks a hazard. At [`HAZARD_MARGIN`], the usual margin for cell means,
    /// it flags window steps over hummocky relief, and grown by the rover radius plus the
    /// safety buffer those false C-obstacles close the gaps of a rock field; the safety layer
    /// (top heights at [`TOP_HAZARD_MARGIN`]) still checks every motion against the body
    /// outline. See README.md for what 0.9 against 0.8 measured on seeds 1..160.
    pub clearance_margin: f64,
    /// Fraction of the rover's belly clearance at which the safety layer (top heights) marks a
    /// step hazard: lower keeps the body farther from rocks near the clearance at the cost of
    /// arrivals (README.md: 0.8 against 0.9 on seeds 1..160).
    pub safety_clearance_margin: f64,
    /// Buffer left inside the wedge's far radius when a path is truncated (m).
    pub range_buffer: f64,
    /// Heading error above which the rover turns in place before driving (rad).
    pub turn_threshold: f64,
    /// How much closer than `d_reach` a node must be to leave boundary following (m); 0, the
    /// default, is the paper's leaving condition d(V, T) < d_reach (README.md, session 20: 0.1
    /// m measured no better).
    pub leave_margin: f64,
    /// Angular margin inside the conglomerate wedge's bounding rays for "interior" (rad).
    pub interior_angle: f64,
    /// Distance from the sensing position within which the ground counts as visible (m): the
    /// rover's own footprint, seen from the previous position.
    pub near_visible: f64,
    /// Carried C-obstacles whose hulls come within `near_visible` plus this margin of the new
    /// sensing position always stay (m): the mast cannot see that ground. Farther ones stay
    /// only where the new view has not sensed their ground again.
    pub carry_margin: f64,
    /// Distance driven back along the recorded trail when planning finds no way on (m).
    pub retreat_distance: f64,
    /// Retreats from dead ends before planning's give-up stands.
    pub max_retreats: u32,
    /// Steps (sense-plan-act cycles) before asking for help.
    pub max_steps: u32,
    /// Wedges sensed in all before asking for help.
    pub max_wedges: u64,
    /// Hazard contacts recorded around one place before asking for help.
    pub max_contacts_here: usize,
    /// Clearance kept between the body outline and a safety-layer hazard cell when a motion is
    /// checked before it is commanded (m).
    pub body_margin: f64,
    /// Motions refused by the safety check at one place before asking for help.
    pub max_refusals_here: u32,
    /// Added to half the rover's width to grow the safety layer's own C-obstacles (m): the
    /// body margin plus the swing of the body's corners on arcs that start up to the turn
    /// threshold off the chord.
    pub top_allowance: f64,
    /// Straight drive out of a position where safety-layer hazards forbid a full turn in place
    /// and planning gave up (m).
    pub escape_distance: f64,
    /// Fraction of the safety layer's step limit by which a hazard cell's own points must
    /// stand out from the ground around it to count (see `confirm_hazards`).
    pub confirm_fraction: f64,
    /// Sensing positions (this one included) at which the C-obstacles stay grown by the rover
    /// radius alone after a squeeze: motion-to-goal found a way on only without the safety
    /// buffer (0 disables squeezing).
    pub squeeze_views: u32,
    /// Looks at unseen ground from one place before a forward drive over it counts as refused
    /// (2, the default; 0 disables the check that the ground under the body of every forward
    /// drive has been sensed; see `first_unseen` and README.md for what it measured).
    pub unseen_looks: u32,
    /// Length of the latest driving (m) over whose swept body the safety layer's hazard cells
    /// are dropped: the body crossed that ground without a hazard stop, which no sensed height
    /// overrules. Kept short because dead-reckoning drift between the map and the recorded
    /// poses grows with distance driven. 0, the default, disables it (README.md, session 17:
    /// 3 m frees seed 19 but measured no gain on seeds 1..320).
    pub swept_memory: f64,
    /// Inset of the body outline within which swept ground clears hazard cells (m): room for
    /// the drift and slip between the recorded poses and the body's true ones.
    pub swept_inset: f64,
    /// Radius the C-obstacles are grown by before the safety buffer (m); 0, the default, takes
    /// the rover's circumscribed radius, as the paper's disc rover. Half the rover's width
    /// lets the rover's disc through narrower gaps and leaves turning to the safety layer's
    /// body-outline check (README.md, session 17: more arrivals, twice the contacts).
    pub growth_radius: f64,
    /// Boundary following on the near side of the boundary (1, the default): d_reach over the
    /// boundary vertices the rover sees across free space, a way to a leaving node only over
    /// sensed ground, and boundary following kept across an escape. 0: d_reach over every
    /// vertex of the blocking obstacle in view, far side included, and an escape restarts
    /// from motion-to-goal (README.md, session 19).
    pub near_side_reach: bool,
    /// How much farther from the goal than d_reach (m) boundary following may have led before
    /// its step, when the gaze has turned all around without a silhouette vertex, is the
    /// TangentBug way on (path length plus distance to the goal) rather than the wall
    /// follower's (0 disables: always the wall follower's; README.md, session 20).
    pub wander_limit: f64,
    /// Mast wedges at the cameras' full resolution (1) instead of the subsampled navigation
    /// image (0, the default): sixteen times the rays at the same range noise per ray, so a
    /// cell mean at 4-5 m averages many points instead of one or two noisy ones, at twice the
    /// capture time (README.md, session 21).
    pub fine_mast: bool,
    /// C-obstacle cells below the ground plane count as pits only in the window centred on
    /// them (1, the default) rather than in any window (0): beside a large rock the window's
    /// ground refits onto the rock and the open ground next to it reads as a pit, widening
    /// the C-obstacle by up to a metre (README.md, session 22).
    pub pits_in_own_window: bool,
    /// The same for the safety layer (0, the default: measured with it, more contacts).
    pub safety_pits_in_own_window: bool,
    /// The C-obstacle model's windows take as ground the refit holding the most cells, from
    /// the whole-window plane or from level planes at the quartile heights (1, the default),
    /// not only the refit from the whole-window plane, which beside a large rock stays tilted
    /// between rock and ground (0). Meant with `pits_in_own_window`: alone it takes a rock
    /// filling most of a window as the ground.
    pub robust_ground: bool,
    /// The same for the safety layer (1, the default: on top heights it raises recall and
    /// halves the false hazards without `safety_pits_in_own_window`).
    pub safety_robust_ground: bool,
}

impl Default for RoverBugConfig {
    fn default() -> Self {
        Self {
            safety_buffer: 0.1,
            clearance_margin: 0.9,
            safety_clearance_margin: TOP_HAZARD_MARGIN,
            range_buffer: 1.0,
            turn_threshold: 10f64.to_radians(),
            leave_margin: 0.0,
            interior_angle: 4f64.to_radians(),
            near_visible: 1.0,
            carry_margin: 0.2,
            retreat_distance: 1.5,
            max_retreats: 5,
            max_steps: 200,
            max_wedges: 300,
            max_contacts_here: 6,
            body_margin: 0.08,
            max_refusals_here: 4,
            top_allowance: 0.15,
            escape_distance: 0.4,
            confirm_fraction: 0.3,
            squeeze_views: 2,
            unseen_looks: 2,
            swept_memory: 0.0,
            swept_inset: 0.1,
            growth_radius: 0.0,
            near_side_reach: true,
            wander_limit: 2.0,
            fine_mast: false,
            pits_in_own_window: true,
            safety_pits_in_own_window: false,
            robust_ground: true,
            safety_robust_ground: true,
        }
    }
}

impl RoverBugConfig {
    /// The parameters a mission file may set (`[navigator_params]`).
    pub fn params() -> Vec<Param<Self>> {
        use Unit::*;
        vec![
            Param {
                name: "safety_buffer_m",
                doc: "safety buffer added to the rover radius when growing C-obstacles",
                unit: Metres,
                field: |c| Field::Real(&mut c.safety_buffer),
            },
            Param {
                name: "clearance_margin",
                doc: "fraction of the belly clearance at which the C-obstacles' step model (cell means) marks a hazard",
                unit: Fraction,
                field: |c| Field::Real(&mut c.clearance_margin),
            },
            Param {
                name: "safety_clearance_margin",
                doc: "fraction of the belly clearance at which the safety layer (cell tops) marks a step hazard",
                unit: Fraction,
                field: |c| Field::Real(&mut c.safety_clearance_margin),
            },
            Param {
                name: "range_buffer_m",
                doc: "buffer left inside the wedge's far radius when a subpath is cut",
                unit: Metres,
                field: |c| Field::Real(&mut c.range_buffer),
            },
            turn_threshold_param(|c| Field::Real(&mut c.turn_threshold)),
            Param {
                name: "leave_margin_m",
                doc: "how much closer than d_reach a node must be to leave boundary following",
                unit: Metres,
                field: |c| Field::Real(&mut c.leave_margin),
            },
            Param {
                name: "interior_angle_deg",
                doc: "angular margin inside the conglomerate wedge's bounding rays for \"interior\"",
                unit: Degrees,
                field: |c| Field::Real(&mut c.interior_angle),
            },
            Param {
                name: "near_visible_m",
                doc: "distance from the sensing position within which the ground counts as visible",
                unit: Metres,
                field: |c| Field::Real(&mut c.near_visible),
            },
            Param {
                name: "carry_margin_m",
                doc: "margin beyond near_visible_m within which the last view's C-obstacles always stay",
                unit: Metres,
                field: |c| Field::Real(&mut c.carry_margin),
            },
            Param {
                name: "retreat_distance_m",
                doc: "distance driven back along the trail when planning finds no way on",
                unit: Metres,
                field: |c| Field::Real(&mut c.retreat_distance),
            },
            Param {
                name: "max_retreats",
                doc: "retreats from dead ends before planning's give-up stands",
                unit: Count,
                field: |c| Field::U32(&mut c.max_retreats),
            },
            Param {
                name: "max_steps",
                doc: "sense-plan-act steps before asking for help",
                unit: Count,
                field: |c| Field::U32(&mut c.max_steps),
            },
            Param {
                name: "max_wedges",
                doc: "wedges sensed in all before asking for help",
                unit: Count,
                field: |c| Field::U64(&mut c.max_wedges),
            },
            Param {
                name: "max_contacts_here",
                doc: "hazard contacts recorded around one place before asking for help",
                unit: Count,
                field: |c| Field::Usize(&mut c.max_contacts_here),
            },
            Param {
                name: "body_margin_m",
                doc: "clearance kept between the body outline and a safety-layer hazard cell",
                unit: Metres,
                field: |c| Field::Real(&mut c.body_margin),
            },
            Param {
                name: "max_refusals_here",
                doc: "motions refused by the safety check at one place before asking for help",
                unit: Count,
                field: |c| Field::U32(&mut c.max_refusals_here),
            },
            Param {
                name: "top_allowance_m",
                doc: "added to half the rover's width to grow the safety layer's own C-obstacles",
                unit: Metres,
                field: |c| Field::Real(&mut c.top_allowance),
            },
            Param {
                name: "escape_distance_m",
                doc: "straight drive out of a place where safety-layer hazards forbid a full turn",
                unit: Metres,
                field: |c| Field::Real(&mut c.escape_distance),
            },
            Param {
                name: "confirm_fraction",
                doc: "fraction of the safety layer's step limit a hazard cell must stand out from the ground around it",
                unit: Fraction,
                field: |c| Field::Real(&mut c.confirm_fraction),
            },
            Param {
                name: "squeeze_views",
                doc: "sensing positions that keep C-obstacles without the safety buffer after a squeeze (0 disables)",
                unit: Count,
                field: |c| Field::U32(&mut c.squeeze_views),
            },
            Param {
                name: "unseen_looks",
                doc: "looks at unseen ground under a forward drive's body before the drive is refused (0: drives are not checked for unseen ground)",
                unit: Count,
                field: |c| Field::U32(&mut c.unseen_looks),
            },
            Param {
                name: "swept_memory_m",
                doc: "length of the latest driving over whose swept body safety-layer hazards are dropped (0 disables)",
                unit: Metres,
                field: |c| Field::Real(&mut c.swept_memory),
            },
            Param {
                name: "swept_inset_m",
                doc: "inset of the body outline within which swept ground clears safety-layer hazards",
                unit: Metres,
                field: |c| Field::Real(&mut c.swept_inset),
            },
            Param {
                name: "growth_radius_m",
                doc: "radius C-obstacles are grown by before the safety buffer (0: the rover's circumscribed radius)",
                unit: Metres,
                field: |c| Field::Real(&mut c.growth_radius),
            },
            Param {
                name: "near_side_reach",
                doc: "1: d_reach over the boundary vertices seen across free space, leaving only over sensed ground, boundary following kept across an escape; 0: d_reach over every boundary vertex in view",
                unit: Switch,
                field: |c| Field::Bool(&mut c.near_side_reach),
            },
            Param {
                name: "wander_limit_m",
                doc: "how much farther from the goal than d_reach boundary following may lead before its blocked step is the way on toward the goal rather than along the boundary (0 disables)",
                unit: Metres,
                field: |c| Field::Real(&mut c.wander_limit),
            },
            Param {
                name: "fine_mast",
                doc: "1: mast wedges at the cameras' full resolution (16x the rays, twice the capture time); 0: the subsampled navigation image",
                unit: Switch,
                field: |c| Field::Bool(&mut c.fine_mast),
            },
            Param {
                name: "pits_in_own_window",
                doc: "1: a C-obstacle cell below the ground plane is a pit only in the window centred on it (beside a large rock the ground refits onto the rock); 0: in any window",
                unit: Switch,
                field: |c| Field::Bool(&mut c.pits_in_own_window),
            },
            Param {
                name: "safety_pits_in_own_window",
                doc: "pits_in_own_window for the safety layer's hazard cells",
                unit: Switch,
                field: |c| Field::Bool(&mut c.safety_pits_in_own_window),
            },
            Param {
                name: "robust_ground",
                doc: "1: a C-obstacle window's ground is the refit holding the most cells (from the whole-window plane or level planes at the quartile heights); 0: the refit from the whole-window plane",
                unit: Switch,
                field: |c| Field::Bool(&mut c.robust_ground),
            },
            Param {
                name: "safety_robust_ground",
                doc: "robust_ground for the safety layer's hazard cells",
                unit: Switch,
                field: |c| Field::Bool(&mut c.safety_robust_ground),
            },
        ]
    }
}

/// Operational mode (paper 000 sections 2.1-2.2).
#[derive(Clone, Debug, PartialEq)]
enum Mode {
    /// Monotonic progress toward the goal.
    MotionToGoal,
    /// Mast scans at `2 k alpha_mast` from the goal direction; `scans` are the k already sensed.
    Virtual { sense: f64, scans: Vec<i32> },
    /// Circumnavigating the obstacle in the positive `sense` (+1 counter-clockwise).
    Normal { sense: f64, d_reach: f64, v_loop: Point2, left_loop: bool, scans: Vec<i32> },
}

/// Everything sensed at the current position (renewed at every step: no global map).
struct View {
    evaluator: TerrainEvaluator,
    wedges: Vec<SensedWedge>,
    origin: Point2,
}

/// A node of the local tangent graph.
#[derive(Clone, Copy, Debug)]
struct Node {
    p: Point2,
    /// (obstacle, vertex) for C-obstacle vertices.
    vertex: Option<(usize, usize)>,
    /// Reaching the node is arrival: a vertex of the C-obstacle containing the goal, or a point
    /// within the goal's tolerance.
    arrival: bool,
}

impl Node {
    /// A point of the circle of arrival around the goal (not an obstacle vertex).
    fn on_goal_circle(&self) -> bool {
        self.arrival && self.vertex.is_none()
    }
}

/// The local tangent graph LTG(S) within the sensed region S.
struct Ltg {
    nodes: Vec<Node>,
    adj: Vec<Vec<(usize, f64)>>,
}

/// The RoverBug navigator (see the module documentation).
pub struct RoverBug {
    rover: RoverConfig,
    config: RoverBugConfig,
    terrain: TerrainConfig,
    mode: Mode,
    d_leave: Option<f64>,
    view: Option<View>,
    obstacles: Vec<CObstacle>,
    carried: Vec<CObstacle>,
    /// C-obstacles around recorded hazard contacts.
    contacts: Vec<CObstacle>,
    /// The pose estimate the current plan starts from (its first leg is checked for safety).
    here: Option<Pose2>,
    /// How many of `obstacles` come from sensing (this view's and the carried ones).
    sensed_len: usize,
    /// Top-height hazard cells in a robot-centred grid kept across steps: the swept body of
    /// every turn and drive is checked against it before the motion is commanded.
    safety: Option<TerrainEvaluator>,
    /// The safety layer's hazard cells that stand out from the ground around them (see
    /// [`RoverBug::confirm_hazards`]).
    safety_hazard: Option<Grid2<bool>>,
    /// Motions refused by the safety check at this place (the count restarts 0.3 m away), and where.
    refusals: (u32, Point2),
    /// Escapes from a boxed-in position, and where the last one started.
    escapes: (u32, Point2),
    /// Looks at ground a drive would cover unseen, at this place (the count restarts 0.3 m
    /// away), and where.
    looks: (u32, Point2),
    /// Where the next step's sensing also looks: the first unseen ground of the drive that
    /// was held back.
    look_at: Option<Point2>,
    /// Sign of the last motion: 1 forward, -1 reverse, 2 turn in place.
    last_motion: Option<f64>,
    /// Where the last forward drive started (estimate).
    drive_from: Option<Point2>,
    /// Positions of the current boundary-following segment.
    visited: Vec<Point2>,
    /// Where boundary following started and escapes started since motion-to-goal last made
    /// progress: unlike `visited` they survive a restart, so boundary following cannot cycle
    /// between the same places.
    been: Vec<Point2>,
    /// Positions the rover has stood at (estimate), oldest first: ground its body has crossed.
    trail: Vec<Point2>,
    /// Body poses along the latest driving (estimate), oldest first, each with the distance
    /// driven up to it: ground the body covered without a hazard stop.
    swept: VecDeque<(Pose2, f64)>,
    /// Where planning found no way on: recorded as small C-obstacles so that no later subpath
    /// leads back into the same dead end.
    dead_ends: Vec<CObstacle>,
    /// Retreats from dead ends so far.
    retreats: u32,
    /// Whether the current subpath is driven in reverse (a retreat along the trail).
    reversing: bool,
    /// Whether the latest halt is planning's give-up (no way on) rather than a proof.
    stuck: bool,
    /// The step (sensing position) at which a squeeze was last tried, and whether it found a
    /// way on: then C-obstacles go without the safety buffer for `squeeze_views` steps.
    squeezed: Option<(u32, bool)>,
    /// Distance from the goal within which the rover has arrived (m; from the goal given).
    goal_tolerance: f64,
    waypoints: VecDeque<Point2>,
    subpath: Vec<Point2>,
    finish: Option<(Outcome, String)>,
    stats: NavigatorStats,
    steps: u32,
    backing_out: bool,
    drawn_wedges: Vec<Vec<Point2>>,
    drawn_obstacles: Vec<Vec<Point2>>,
    drawn_paths: Vec<Vec<Point2>>,
}

/// The step/slope model behind RoverBug's C-obstacles: cell means over one sensing position's
/// wedges, with hazard limits below the rover's true limits, as the grid navigators use.
pub fn c_obstacle_terrain(rover: &RoverConfig, config: &RoverBugConfig) -> TerrainConfig {
    TerrainConfig {
        cols: 81,
        rows: 81,
        clearance: rover.clearance * config.clearance_margin,
        max_tilt: rover.max_tilt * HAZARD_MARGIN,
        safety_buffer: config.safety_buffer,
        rover_radius: if config.growth_radius > 0.0 { config.growth_radius } else { rover.radius() },
        pits_in_own_window: config.pits_in_own_window,
        robust_ground: config.robust_ground,
        ..TerrainConfig::for_rover(rover)
    }
}

/// The safety layer's model, kept across steps: top heights, which do not lose a small rock's
/// height as cell means do, on the grid navigators' finer cells.
pub fn safety_terrain(rover: &RoverConfig, config: &RoverBugConfig) -> TerrainConfig {
    TerrainConfig {
        cols: 121,
        rows: 121,
        resolution: T_GRID_RESOLUTION,
        hazard_height: HazardHeight::Top,
        clearance: rover.clearance * config.safety_clearance_margin,
        pits_in_own_window: config.safety_pits_in_own_window,
        robust_ground: config.safety_robust_ground,
        ..c_obstacle_terrain(rover, config)
    }
}

impl RoverBug {
    /// A RoverBug navigator for a rover.
    pub fn new(rover: RoverConfig, config: RoverBugConfig) -> Self {
        let terrain = c_obstacle_terrain(&rover, &config);
        Self {
            rover,
            config,
            terrain,
            mode: Mode::MotionToGoal,
            d_leave: None,
            view: None,
            obstacles: Vec::new(),
            carried: Vec::new(),
            visited: Vec::new(),
            been: Vec::new(),
            trail: Vec::new(),
            swept: VecDeque::new(),
            dead_ends: Vec::new(),
            retreats: 0,
            reversing: false,
            stuck: false,
            squeezed: None,
            contacts: Vec::new(),
            here: None,
            sensed_len: 0,
            safety: None,
            safety_hazard: None,
            refusals: (0, Point2::new(f64::NAN, f64::NAN)),
            escapes: (0, Point2::new(f64::NAN, f64::NAN)),
            looks: (0, Point2::new(f64::NAN, f64::NAN)),
            look_at: None,
            last_motion: None,
            drive_from: None,
            goal_tolerance: 0.0,
            waypoints: VecDeque::new(),
            subpath: Vec::new(),
            finish: None,
            stats: NavigatorStats::default(),
            steps: 0,
            backing_out: false,
            drawn_wedges: Vec::new(),
            drawn_obstacles: Vec::new(),
            drawn_paths: Vec::new(),
        }
    }

    /// Half-angle of a mast wedge (rad).
    fn alpha_mast(&self) -> f64 {
        0.5 * self.rover.mast_fov
    }

    /// Far radius of a mast wedge (m).
    fn range(&self) -> f64 {
        self.rover.mast_range
    }

    /// Requests range images, counting every wedge (gaze control).
    fn sense(&mut self, requests: Vec<SenseRequest>) -> NavCommand {
        if self.stats.sensing_actions >= self.config.max_wedges {
            let why = format!("no arrival after {} wedges sensed", self.stats.sensing_actions);
            return self.finish_now(Outcome::HelpRequested, &why);
        }
        self.stats.sensing_actions += requests.len() as u64;
        NavCommand::Sense(requests)
    }

    /// The mast wedge (navigation or full-resolution image, per `fine_mast`) centred on the
    /// world bearing `bearing`.
    fn mast_at(&self, pose: Pose2, bearing: f64) -> SenseRequest {
        let pan = angle_diff(bearing, pose.yaw);
        if self.config.fine_mast { SenseRequest::MastFine { pan } } else { SenseRequest::Mast { pan } }
    }

    /// Whether a world point lies in the region sensed from the current position.
    fn visible(&self, p: Point2) -> bool {
        let Some(view) = &self.view else { return false };
        if p.dist(view.origin) <= self.config.near_visible {
            return true;
        }
        view.wedges.iter().any(|w| {
            let b = w.pose.inverse_transform(p);
            let r = b.x.hypot(b.y);
            r <= w.wedge.max_range && angle_diff(b.y.atan2(b.x), w.wedge.bearing).abs() <= w.wedge.half_angle
        })
    }

    /// Whether `p` is in the interior of the conglomerate wedge: sensed, and so are the points a
    /// few degrees to either side at the same range.
    fn interior(&self, p: Point2) -> bool {
        let Some(view) = &self.view else { return false };
        let v = p.sub(view.origin);
        // The far arc counts as interior (paper 000 section 2.2): only the bounding rays matter.
        let (r, a) = (v.norm().min(self.range() - 1e-6), v.angle());
        let m = self.config.interior_angle;
        [a - m, a, a + m]
            .iter()
            .all(|&t| self.visible(view.origin.add(Point2::new(t.cos(), t.sin()).scale(r))))
    }

    /// Whether a point is sensed or beyond the radius at which subpaths are cut (a vertex of a
    /// C-obstacle grown from sensed cells may lie there; the rover never drives that far).
    fn visible_or_beyond_cut(&self, p: Point2) -> bool {
        let Some(view) = &self.view else { return false };
        self.visible(p) || p.dist(view.origin) > self.cut_radius()
    }

    /// Distance from the sensing position at which subpaths are cut (m).
    fn cut_radius(&self) -> f64 {
        (self.range() - self.config.range_buffer).max(0.5)
    }

    /// Whether the ground just past `v` on the ray from `x` is sensed and outside every
    /// C-obstacle: the obstacle's silhouette ends at `v` within the view.
    fn free_past(&self, x: Point2, v: Point2) -> bool {
        let d = v.sub(x);
        let unit = d.scale(1.0 / d.norm().max(1e-9));
        [0.3, 0.6].iter().all(|&k| {
            let q = v.add(unit.scale(k));
            (self.visible(q) || q.dist(x) > self.range())
                && !self.obstacles.iter().any(|o| o.contains_strict(q))
        })
    }

    /// Whether the segment lies in the sensed region up to the cut radius.
    fn segment_visible(&self, a: Point2, b: Point2) -> bool {
        Self::along(a, b, |p| self.visible_or_beyond_cut(p))
    }

    /// Whether the segment lies in the sensed region, even beyond the cut radius.
    fn segment_sensed(&self, a: Point2, b: Point2) -> bool {
        Self::along(a, b, |p| self.visible(p))
    }

    /// Whether `holds` is true at points every 0.2 m (at most) along the segment, ends included.
    fn along(a: Point2, b: Point2, holds: impl Fn(Point2) -> bool) -> bool {
        let n = (a.dist(b) / 0.2).ceil().max(1.0) as usize;
        (0..=n).all(|i| holds(a.add(b.sub(a).scale(i as f64 / n as f64))))
    }

    /// Whether segment a-b is free of every C-obstacle interior. The rover at `x` may find
    /// itself in a C-obstacle's grown margin (range noise, a late detection): segments leaving
    /// `x` may then cross the margin but never the obstacle's own hull; from inside a recorded
    /// contact (no cells) they may move out or along, never deeper in. Inside a hull itself (a
    /// crater rim around the rover) every way out crosses the hazard, so none is free.
    fn segment_free(&self, a: Point2, b: Point2, x: Point2) -> bool {
        self.obstacles.iter().all(|o| {
            if !o.blocks_segment(a, b) {
                return true;
            }
            let along = |k: usize| a.add(b.sub(a).scale(k as f64 / 16.0));
            a == x
                && o.contains_strict(x)
                && !o.hull_contains_strict(x)
                && if o.cells > 0 {
                    (1..=16).all(|k| !o.hull_contains_strict(along(k)))
                } else {
                    let depth = -o.signed_clearance(x);
                    (1..=16).all(|k| -o.signed_clearance(along(k)) <= depth + 0.05)
                }
        })
    }

    /// Builds the local tangent graph from the rover at `x` toward the goal `goal`.
    fn build_ltg(&self, x: Point2, goal: Point2) -> Ltg {
        let mut nodes = vec![Node { p: x, vertex: None, arrival: false }];
        // T_g: toward the goal when nothing visible blocks the direct line.
        let to_goal = goal.sub(x);
        let dist = to_goal.norm();
        let goal_inside = self.obstacles.iter().any(|o| o.contains_strict(goal));
        if dist > 1e-9 && !goal_inside {
            let reach = dist.min(self.range());
            let tg = x.add(to_goal.scale(reach / dist));
            if self.segment_free(x, tg, x) && self.segment_visible(x, tg) {
                nodes.push(Node { p: tg, vertex: None, arrival: false });
            }
        }
        // The goal is a region: points well inside its tolerance are arrival too, so that a
        // rock beside the goal point does not send the rover round it (seed 17 of the default
        // yard gave up 1.04 m from the goal and drove on for 50 m). They join the rover only,
        // by a sensed segment: ground beyond the cut radius counts as free, and a path through
        // it must not reach them (a goal inside a ring of rocks).
        let arrive = (ARRIVAL_FRACTION * self.goal_tolerance).min(self.goal_tolerance - ARRIVAL_MIN_HOP);
        if arrive > 0.0 && dist > arrive && dist < self.cut_radius() + arrive {
            for k in 0..ARRIVAL_POINTS {
                let a = 2.0 * PI * k as f64 / ARRIVAL_POINTS as f64;
                let p = goal.add(Point2::new(a.cos(), a.sin()).scale(arrive));
                if self.visible(p) && !self.obstacles.iter().any(|o| o.contains(p)) {
                    nodes.push(Node { p, vertex: None, arrival: true });
                }
            }
        }
        for (k, o) in self.obstacles.iter().enumerate() {
            let around_goal = o.contains(goal);
            for (i, &v) in o.vertices.iter().enumerate() {
                let inside_other =
                    self.obstacles.iter().enumerate().any(|(j, q)| j != k && q.contains_strict(v));
                if !inside_other && self.visible_or_beyond_cut(v) {
                    nodes.push(Node { p: v, vertex: Some((k, i)), arrival: around_goal });
                }
            }
        }
        let n = nodes.len();
        let mut adj = vec![Vec::new(); n];
        for i in 0..n {
            for j in i + 1..n {
                let (a, b) = (nodes[i].p, nodes[j].p);
                if a.dist(b) < 1e-9 || !self.tangent(&nodes[i], b) || !self.tangent(&nodes[j], a) {
                    continue;
                }
                if (nodes[i].on_goal_circle() || nodes[j].on_goal_circle())
                    && (i != 0 || !self.segment_sensed(a, b))
                {
                    continue;
                }
                let (a, b) = if j == 0 { (b, a) } else { (a, b) };
                if self.segment_free(a, b, x)
                    && self.segment_visible(a, b)
                    && (i != 0 || self.leg_clear(nodes[j].p))
                {
                    let d = a.dist(b);
                    adj[i].push((j, d));
                    adj[j].push((i, d));
                }
            }
        }
        Ltg { nodes, adj }
    }

    /// Whether the line from `node` toward `other` is tangent to the node's C-obstacle at the
    /// node: the obstacle's interior lies on one side of the line near the vertex.
    fn tangent(&self, node: &Node, other: Point2) -> bool {
        let Some((k, i)) = node.vertex else { return true };
        let vs = &self.obstacles[k].vertices;
        let n = vs.len();
        let d = other.sub(node.p);
        let prev = d.cross(vs[(i + n - 1) % n].sub(node.p));
        let next = d.cross(vs[(i + 1) % n].sub(node.p));
        prev * next >= -1e-12
    }

    /// A* over the LTG from the rover (node 0) to the goal: `allowed` nodes may end a path
    /// with the straight-line remainder to the goal (zero from an arrival node). Returns the
    /// node sequence without the virtual goal.
    fn search(&self, ltg: &Ltg, goal: Point2, allowed: &dyn Fn(&Node) -> bool) -> Option<Vec<usize>> {
        let clear =
            |node: &Node| node.arrival || self.obstacles.iter().all(|o| !o.blocks_segment(node.p, goal));
        self.search_with(ltg, goal, &|_, node: &Node| {
            // Arrival ends the path: the rover stops once its estimate is within the tolerance
            // anyway, so a path onto the circle of arrival is no shorter in driving than one
            // toward the goal point (seeds 1..80 of the default yard: the same ratios within 0.02
            // either way, but for seed 17, 1.24 at zero cost against 3.33 with the remainder
            // charged).
            (allowed(node) && clear(node)).then(|| if node.arrival { 0.0 } else { node.p.dist(goal) })
        })
    }

    /// A* over the LTG from the rover (node 0) to a virtual sink: `terminal` gives the cost of
    /// ending a path at a node (None where a path may not end). Returns the node sequence.
    fn search_with(
        &self,
        ltg: &Ltg,
        goal: Point2,
        terminal: &dyn Fn(usize, &Node) -> Option<f64>,
    ) -> Option<Vec<usize>> {
        const SINK: usize = usize::MAX;
        let mm = |d: f64| (d * 1000.0).round() as u64;
        // The straight-line heuristic is admissible only when no path ends early at a cost below
        // the remaining distance; goal vertices and other targets end at zero.
        let admissible = !ltg
            .nodes
            .iter()
            .enumerate()
            .any(|(i, n)| terminal(i, n).is_some_and(|c| c < n.p.dist(goal) - 1e-9));
        let (path, _) = pathfinding::prelude::astar(
            &0usize,
            |&i| {
                let mut next: Vec<(usize, u64)> = ltg.adj[i].iter().map(|&(j, d)| (j, mm(d))).collect();
                if i != 0
                    && let Some(rest) = terminal(i, &ltg.nodes[i])
                {
                    next.push((SINK, mm(rest)));
                }
                next
            },
            |&i| {
                if i == SINK || !admissible { 0 } else { mm(ltg.nodes[i].p.dist(goal)).saturating_sub(1) }
            },
            |&i| i == SINK,
        )?;
        Some(path.into_iter().filter(|&i| i != SINK).collect())
    }

    /// Cuts a path from `x` at the far radius of the wedge minus the buffer.
    fn truncate(&self, path: &[Point2], x: Point2) -> Vec<Point2> {
        let limit = self.cut_radius();
        let mut out = vec![x];
        for w in path.windows(2) {
            let (a, b) = (w[0], w[1]);
            if b.dist(x) <= limit {
                out.push(b);
                continue;
            }
            // First point of a-b at distance `limit` from x.
            let d = b.sub(a);
            let f = a.sub(x);
            let (qa, qb, qc) = (d.dot(d), 2.0 * f.dot(d), f.dot(f) - limit * limit);
            let disc = (qb * qb - 4.0 * qa * qc).max(0.0);
            let t = ((-qb + disc.sqrt()) / (2.0 * qa)).clamp(0.0, 1.0);
            out.push(a.add(d.scale(t)));
            break;
        }
        out
    }

    /// Queues a subpath for execution and records it for display.
    fn execute(&mut self, path: Vec<Point2>) {
        self.stats.plans += 1;
        self.waypoints = path.iter().skip(1).copied().collect();
        self.drawn_paths.push(path.clone());
        self.subpath = path;
    }

    /// Connected groups of overlapping C-obstacles (the obstacles of the paper's "∂O").
    fn components(&self) -> Vec<Vec<usize>> {
        let n = self.obstacles.len();
        let mut group: Vec<usize> = (0..n).collect();
        fn root(g: &mut [usize], mut i: usize) -> usize {
            while g[i] != i {
                g[i] = g[g[i]];
                i = g[i];
            }
            i
        }
        for i in 0..n {
            for j in i + 1..n {
                let (a, b) = (&self.obstacles[i], &self.obstacles[j]);
                let touch = a.vertices.iter().any(|&v| b.contains(v))
                    || b.vertices.iter().any(|&v| a.contains(v))
                    || a.vertices
                        .iter()
                        .enumerate()
                        .any(|(k, &v)| b.clip_segment(v, a.vertices[(k + 1) % a.vertices.len()]).is_some());
                if touch {
                    let (ri, rj) = (root(&mut group, i), root(&mut group, j));
                    group[ri] = rj;
                }
            }
        }
        let mut out: Vec<Vec<usize>> = Vec::new();
        let mut index = vec![usize::MAX; n];
        for i in 0..n {
            let r = root(&mut group, i);
            if index[r] == usize::MAX {
                index[r] = out.len();
                out.push(Vec::new());
            }
            out[index[r]].push(i);
        }
        out
    }

    /// The component blocking the way from `x` toward the goal (first hit along the line),
    /// or else the one nearest to `x`.
    fn blocking_component(&self, x: Point2, goal: Point2) -> Option<Vec<usize>> {
        let comps = self.components();
        let dir = goal.sub(x);
        let far = x.add(dir.scale(self.range() / dir.norm().max(1e-9)));
        let hit = |c: &Vec<usize>| {
            c.iter()
                .filter_map(|&k| self.obstacles[k].clip_segment(x, far).map(|(t0, _)| t0))
                .fold(f64::INFINITY, f64::min)
        };
        let nearest = |c: &Vec<usize>| {
            c.iter().map(|&k| self.obstacles[k].signed_clearance(x)).fold(f64::INFINITY, f64::min)
        };
        let blocking = comps.iter().filter(|c| hit(c).is_finite()).min_by(|a, b| hit(a).total_cmp(&hit(b)));
        blocking.or_else(|| comps.iter().min_by(|a, b| nearest(a).total_cmp(&nearest(b)))).cloned()
    }

    /// Exterior vertices of a component as LTG node indices.
    fn boundary_nodes(ltg: &Ltg, comp: &[usize]) -> Vec<usize> {
        (0..ltg.nodes.len())
            .filter(|&i| ltg.nodes[i].vertex.is_some_and(|(k, _)| comp.contains(&k)))
            .collect()
    }

    /// Signed angle of `p` seen from `x`, relative to the direction `reference`.
    fn rel_angle(x: Point2, p: Point2, reference: f64) -> f64 {
        angle_diff(p.sub(x).angle(), reference)
    }

    /// Starts a new sense-plan-act step at the current position. The C-obstacles of the last
    /// view that lie within reach of the rover are recorded and carried over: the mast cannot
    /// see the ground within a metre of the rover.
    fn new_view(&mut self, pose: Pose2) {
        let x = pose.position();
        let reach = self.config.near_visible + 0.5;
        self.carried = std::mem::take(&mut self.obstacles);
        self.carried.truncate(self.sensed_len);
        self.carried.retain(|o| o.signed_clearance(x) < reach);
        if self.safety.is_none() {
            let config = safety_terrain(&self.rover, &self.config);
            self.safety = TerrainEvaluator::new(config, pose).ok();
        }
        self.view = match TerrainEvaluator::new(self.terrain.clone(), pose) {
            Ok(evaluator) => Some(View { evaluator, wedges: Vec::new(), origin: pose.position() }),
            Err(e) => {
                self.finish = Some((Outcome::Aborted, format!("terrain configuration of the rover: {e}")));
                None
            }
        };
        self.steps += 1;
    }

    /// Folds the clouds of the last frame into the current view and rebuilds the C-obstacles.
    fn ingest(&mut self, input: &NavInput<'_>) {
        let pose = input.estimate.pose.pose2();
        if self.view.is_none() {
            self.new_view(pose);
        }
        let Some(view) = self.view.as_mut() else { return };
        for cloud in &input.frame.clouds {
            view.wedges.push(SensedWedge { pose, wedge: cloud.wedge });
            self.drawn_wedges.push(wedge_polygon(pose, &cloud.wedge));
        }
        view.evaluator.update(&input.frame.clouds, &input.estimate);
        if let Some(safety) = self.safety.as_mut() {
            safety.update(&input.frame.clouds, &input.estimate);
        }
        self.supersede_carried();
        self.safety_hazard = self.confirm_hazards();
        self.rebuild_obstacles(pose, input.goal, true);
    }

    /// The terrain settings the C-obstacles are grown with: without the safety buffer while
    /// squeezing.
    fn growth_terrain(&self) -> TerrainConfig {
        let squeezing =
            self.squeezed.is_some_and(|(at, way_on)| way_on && self.steps < at + self.config.squeeze_views);
        if squeezing {
            TerrainConfig { safety_buffer: 0.0, ..self.terrain.clone() }
        } else {
            self.terrain.clone()
        }
    }

    /// Builds the C-obstacles of the current view (with the carried ones, the safety layer's,
    /// recorded contacts and dead ends, and keep-out zones), recording the sensed and safety
    /// layer ones for the picture when `draw`.
    fn rebuild_obstacles(&mut self, pose: Pose2, goal: &rovernav_core::Goal, draw: bool) {
        let Some(view) = self.view.as_ref() else { return };
        let terrain = self.growth_terrain();
        self.obstacles = view.evaluator.layers().c_obstacles(&terrain, &view.wedges, Some(goal.position));
        self.obstacles.retain(|o| o.vertices.len() >= 3);
        let fresh = self.obstacles.len();
        // Carried ones keep the growth they were built with: after a squeeze the rover stands
        // within the buffer of the gap's rocks, and grown back they would hem it in again
        // (seeds 1..20 of the default yard: mean ratio 1.40 as kept, 1.51 regrown both ways,
        // 1.44 shrunk during a squeeze only); a nearer view supersedes them.
        self.obstacles.extend(self.carried.iter().cloned());
        self.sensed_len = self.obstacles.len();
        let top = self.top_obstacles(pose);
        self.obstacles.extend(top);
        if draw {
            for o in self.obstacles[..fresh].iter().chain(&self.obstacles[self.sensed_len..]) {
                self.drawn_obstacles.push(o.vertices.clone());
            }
        }
        self.obstacles.extend(self.contacts.iter().cloned());
        self.obstacles.extend(self.dead_ends.iter().cloned());
        // Keep-out zones are C-obstacles like any sensed one (their convex hulls, grown by the
        // same margin: conservative for a non-convex zone). They keep the safety buffer while
        // squeezing: the safety layer knows nothing of them.
        for zone in &goal.keep_out {
            let hull = rovernav_perception::hull::convex_hull(zone);
            if hull.len() >= 3 {
                self.obstacles.push(CObstacle::from_hull(
                    hull,
                    self.terrain.growth(),
                    self.terrain.max_arc_step,
                    0,
                ));
            }
        }
    }

    /// When planning found no way on without a proof, tries motion-to-goal once more on
    /// C-obstacles grown by the rover radius alone: the empirical safety buffer closes gaps of
    /// a rock field that the rover's disc fits through. The first leg of the plan is still
    /// checked against the safety layer's step hazards (body outline plus margin), later legs
    /// at execution; slope hazards (crater walls) have only their C-obstacles. On success the
    /// next `squeeze_views` views keep the smaller growth (the rover is then within the buffer
    /// of the gap's rocks); otherwise the buffered C-obstacles come back. Tried at most once
    /// per sensing position.
    fn squeeze(&mut self, pose: Pose2, goal: &rovernav_core::Goal) -> bool {
        if self.config.squeeze_views == 0 || self.squeezed.is_some_and(|(at, _)| at == self.steps) {
            return false;
        }
        self.squeezed = Some((self.steps, true));
        self.rebuild_obstacles(pose, goal, false);
        self.waypoints.clear();
        if self.motion_to_goal(pose.position(), goal.position) {
            // Drawn as planned on.
            self.rebuild_obstacles(pose, goal, true);
            self.finish = None;
            self.mode = Mode::MotionToGoal;
            return true;
        }
        self.squeezed = Some((self.steps, false));
        self.rebuild_obstacles(pose, goal, false);
        false
    }

    /// Drops the carried C-obstacles that the current view supersedes: those outside the
    /// mast's blind zone around the sensing position whose ground this view has sensed again
    /// (the centre and at least half the hull's vertices in sensed cells). The fresh ones are
    /// seen from nearer, so more accurately; stale copies would pile up and close gaps the
    /// nearer view shows open. Within the blind zone, or where this view has not looked, the
    /// carried ones stay.
    fn supersede_carried(&mut self) {
        let Some(view) = &self.view else { return };
        let sensed = |p: Point2| view.evaluator.grid().at_world(p.x, p.y).is_some_and(|c| c.count > 0);
        let blind = self.config.near_visible + self.config.carry_margin;
        self.carried.retain(|o| {
            if o.hull.is_empty() || hull_distance(o, view.origin) < blind {
                return true;
            }
            let seen = o.hull.iter().filter(|&&p| sensed(p)).count();
            let centre =
                o.hull.iter().fold(Point2::new(0.0, 0.0), |a, &p| a.add(p)).scale(1.0 / o.hull.len() as f64);
            !(sensed(centre) && 2 * seen >= o.hull.len())
        });
    }

    /// C-obstacles of the safety layer's hazard cells that the view's C-obstacles miss (rocks
    /// whose cell means read below the step limit), grown only by half the rover's width plus
    /// an allowance: grown like the others they would close the gaps of a rock field, and the
    /// turns and drives near them are checked against the cells themselves. Cells under the
    /// body at `pose` are left out: the rover stands there without contact.
    fn top_obstacles(&self, pose: Pose2) -> Vec<CObstacle> {
        let Some(mut mask) = self.safety_hazard.clone() else { return Vec::new() };
        let growth = 0.5 * self.rover.width + self.config.top_allowance;
        let g = mask.geometry;
        let (half_l, half_w) = (0.5 * self.rover.length, 0.5 * self.rover.width);
        for r in 0..g.rows {
            for c in 0..g.cols {
                if !*mask.get(c, r) {
                    continue;
                }
                let (cx, cy) = g.center(c, r);
                let q = Point2::new(cx, cy);
                let b = pose.inverse_transform(q);
                let under_body = b.x.abs() <= half_l && b.y.abs() <= half_w;
                let covered =
                    self.obstacles[..self.sensed_len].iter().any(|o| o.signed_clearance(q) <= -growth);
                if under_body || covered {
                    *mask.get_mut(c, r) = false;
                }
            }
        }
        let mut out = rovernav_perception::build_c_obstacles(&mask, growth, self.terrain.max_arc_step);
        out.retain(|o| o.vertices.len() >= 3);
        out
    }

    /// Motion-to-goal planning on the current view; false when a blocking obstacle stops it.
    fn motion_to_goal(&mut self, x: Point2, goal: Point2) -> bool {
        let ltg = self.build_ltg(x, goal);
        let bound = x.dist(goal).min(self.d_leave.unwrap_or(f64::INFINITY));
        let Some(path) = self.search(&ltg, goal, &|n: &Node| n.arrival || n.p.dist(goal) <= bound + 1e-9)
        else {
            return false;
        };
        let points: Vec<Point2> = path.iter().map(|&i| ltg.nodes[i].p).collect();
        let sub = self.truncate(&points, x);
        let length: f64 = sub.windows(2).map(|w| w[0].dist(w[1])).sum();
        if length < 0.1 {
            return false;
        }
        // Motion-to-goal drives on toward a node of G1; its restart points are forgotten only
        // when that is progress past all of them (as Bug's hit points: a subpath back toward
        // a place boundary following started from is not).
        let end = *sub.last().expect("a subpath of positive length");
        if self.been.iter().all(|b| end.dist(goal) < b.dist(goal) - 0.3) {
            self.been.clear();
        }
        self.execute(sub);
        true
    }

    /// Enters virtual boundary following: positive sense by the shorter side around the
    /// blocking obstacle.
    fn start_boundary_following(&mut self, x: Point2, goal: Point2) {
        let ltg = self.build_ltg(x, goal);
        let reference = goal.sub(x).angle();
        let mut sense = 1.0;
        if let Some(comp) = self.blocking_component(x, goal) {
            let side = |s: f64| {
                Self::boundary_nodes(&ltg, &comp)
                    .into_iter()
                    .map(|i| ltg.nodes[i].p)
                    .max_by(|a, b| {
                        (s * Self::rel_angle(x, *a, reference))
                            .total_cmp(&(s * Self::rel_angle(x, *b, reference)))
                    })
                    .map_or(f64::INFINITY, |v| x.dist(v) + v.dist(goal))
            };
            if side(-1.0) < side(1.0) {
                sense = -1.0;
            }
        }
        self.mode = Mode::Virtual { sense, scans: vec![0] };
        self.visited = vec![x];
        self.remember(x);
    }

    /// The silhouette vertex of the obstacle blocking the way to the goal in the sense `s`
    /// (+1 counter-clockwise from the goal direction): the most extreme boundary node the rover
    /// reaches by a free tangent segment, lying in the interior of the conglomerate wedge with
    /// sensed free ground past it. Returns the subpath to it, the boundary nodes' closest
    /// distance to the goal and the extreme node in the other sense.
    fn silhouette(
        &self,
        x: Point2,
        goal: Point2,
        s: f64,
        virtual_mode: bool,
    ) -> Option<(Vec<Point2>, f64, Point2)> {
        let ltg = self.build_ltg(x, goal);
        let reference = goal.sub(x).angle();
        let comp = self.blocking_component(x, goal)?;
        let nodes = Self::boundary_nodes(&ltg, &comp);
        let key = |i: usize| s * Self::rel_angle(x, ltg.nodes[i].p, reference);
        // The near side of the boundary: the vertices the rover sees across free space. Over
        // low rocks the mast also sees the far side, which a planar sensor never shows.
        let near: Vec<usize> =
            nodes.iter().copied().filter(|&i| ltg.adj[0].iter().any(|&(j, _)| j == i)).collect();
        let direct: Vec<usize> = near
            .iter()
            .copied()
            .filter(|&i| ltg.nodes[i].p.dist(x) > 0.1)
            // Never back to where this segment has been, nor to a restart point.
            .filter(|&i| self.away_from_visits(ltg.nodes[i].p, 0.3))
            // Onward in the positive sense: on that side of the goal direction.
            .filter(|&i| virtual_mode || key(i) > -0.05)
            .collect();
        let v = direct.iter().copied().max_by(|&a, &b| key(a).total_cmp(&key(b)))?;
        let target = ltg.nodes[v].p;
        // Virtual boundary following also needs free ground past the silhouette (the obstacle
        // ends there); following the boundary, the next vertex of a curved boundary hides the
        // rest of it, as the paper's farthest visible boundary vertex does.
        if !self.interior(target) || (virtual_mode && !self.free_past(x, target)) {
            return None;
        }
        // d_reach, "the closest distance to T encountered so far on ∂O": on the near side too
        // (`near_side_reach`). Over every boundary vertex in view, far side included, it can
        // be metres nearer the goal than any boundary the rover follows in a rock field, so
        // that the rover never leaves.
        let reach_pool = if self.config.near_side_reach { &near } else { &nodes };
        let d_reach = reach_pool.iter().map(|&i| ltg.nodes[i].p.dist(goal)).fold(x.dist(goal), f64::min);
        // V_loop lies on the near side of the boundary (paper 000 section 2.2): the most extreme
        // near vertex in the negative sense. Taken among all, it can lie on the far side of an
        // encircling obstacle, which the rover following the near side never comes back to.
        // `near` holds the target, so it is not empty.
        let other =
            near.iter().copied().min_by(|&a, &b| key(a).total_cmp(&key(b))).map_or(x, |i| ltg.nodes[i].p);
        // The target is a sensed node joined to the rover by a sensed free segment: no cut.
        Some((vec![x, target], d_reach, other))
    }

    /// The step of boundary following when the gaze has turned all around without a silhouette
    /// vertex: the first node past the goal direction in the positive sense `s` joined to the
    /// rover by a free tangent segment, away from every position of this boundary-following
    /// segment and every restart point; the most extreme such node in the sense when none lies
    /// on the positive side. Turning from the goal direction only as far as the way is blocked
    /// keeps the obstacle at hand, as a wall follower does: the most extreme node, up to half a
    /// turn from the goal, led the rover away from it (seed 10 of the default yard: 8 m south
    /// of a goal to the north-east and back).
    fn fallback_step(&self, ltg: &Ltg, x: Point2, goal: Point2, s: f64) -> Option<Vec<Point2>> {
        let reference = goal.sub(x).angle();
        let key = |p: &Point2| s * Self::rel_angle(x, *p, reference);
        let candidates: Vec<Point2> = ltg.adj[0]
            .iter()
            .map(|&(j, _)| ltg.nodes[j].p)
            .filter(|&p| p.dist(x) > 0.2 && self.away_from_visits(p, 0.5))
            .collect();
        candidates
            .iter()
            .filter(|p| key(p) > -0.05)
            .min_by(|a, b| key(a).total_cmp(&key(b)))
            .or_else(|| candidates.iter().max_by(|a, b| key(a).total_cmp(&key(b))))
            .map(|&p| vec![x, p])
    }

    /// Boundary following's step when the gaze has turned all around without a silhouette
    /// vertex: the wall follower's step, then the locally best way on; in the other order once
    /// the rover is more than `wander_limit` farther from the goal than d_reach. Following a
    /// boundary away from the goal through clutter, the wall follower's step keeps leading
    /// away (seed 19 of the default yard wandered until the time limit).
    fn blocked_step(
        &self,
        ltg: &Ltg,
        x: Point2,
        goal: Point2,
        sense: f64,
        d_reach: f64,
    ) -> Option<Vec<Point2>> {
        let limit = self.config.wander_limit;
        if limit > 0.0 && x.dist(goal) > d_reach + limit {
            self.best_exit(ltg, x, goal).or_else(|| self.fallback_step(ltg, x, goal, sense))
        } else {
            self.fallback_step(ltg, x, goal, sense).or_else(|| self.best_exit(ltg, x, goal))
        }
    }

    /// Whether `p` lies farther than `radius` from every position of this boundary-following
    /// segment and from every restart point since motion-to-goal last made progress.
    fn away_from_visits(&self, p: Point2, radius: f64) -> bool {
        self.visited.iter().chain(&self.been).all(|q| q.dist(p) > radius)
    }

    /// Remembers a restart point (see `been`).
    fn remember(&mut self, x: Point2) {
        if self.been.last().is_none_or(|q| q.dist(x) > 1e-9) {
            self.been.push(x);
        }
    }

    /// The locally best way on (TangentBug's heuristic): the LTG path from the rover to a node
    /// away from every position of this boundary-following segment and every restart point that
    /// minimises its length plus the node's distance to the goal, cut at the wedge radius. `ltg`
    /// is the local tangent graph from `x`.
    fn best_exit(&self, ltg: &Ltg, x: Point2, goal: Point2) -> Option<Vec<Point2>> {
        // The restart points are a preference: with every way on near one, one near a restart
        // point beats halting.
        self.best_exit_avoiding(ltg, x, goal, &self.been)
            .or_else(|| self.best_exit_avoiding(ltg, x, goal, &[]))
    }

    /// [`Self::best_exit`] avoiding this segment's positions and the points `avoid`.
    fn best_exit_avoiding(
        &self,
        ltg: &Ltg,
        x: Point2,
        goal: Point2,
        avoid: &[Point2],
    ) -> Option<Vec<Point2>> {
        let fresh = |p: Point2| p.dist(x) > 0.2 && self.visited.iter().chain(avoid).all(|q| q.dist(p) > 0.5);
        let path =
            self.search_with(ltg, goal, &|i, n: &Node| (i != 0 && fresh(n.p)).then(|| n.p.dist(goal)))?;
        let points: Vec<Point2> = path.iter().map(|&i| ltg.nodes[i].p).collect();
        let sub = self.truncate(&points, x);
        (sub.len() >= 2).then_some(sub)
    }

    /// Whether the positions of this boundary-following segment (and `next`) wind around the
    /// goal: a loop around an obstacle proves the goal unreachable only when the obstacle
    /// encloses the goal; in clutter the rover can come back near `V_loop` around another one.
    fn encircles_goal(&self, goal: Point2, next: Option<Point2>) -> bool {
        let pts: Vec<Point2> = self.visited.iter().copied().chain(next).collect();
        let winding: f64 =
            pts.windows(2).map(|w| angle_diff(w[1].sub(goal).angle(), w[0].sub(goal).angle())).sum();
        winding.abs() > 1.5 * PI
    }

    /// The next mast wedge of a scan that alternates sides, k = 1, -1, 2, -2, ... in units of
    /// 2 alpha_mast from the goal direction; None once the scans overlap all around.
    fn next_scan(&self, scans: &[i32], sense: f64) -> Option<(i32, f64)> {
        let last = *scans.last().unwrap_or(&0);
        let next = if last <= 0 { -last + 1 } else { -last };
        let angle = 2.0 * self.alpha_mast() * next as f64 * sense;
        (angle.abs() - self.alpha_mast() <= PI + 1e-9 && scans.len() <= 16).then_some((next, angle))
    }

    /// Virtual boundary following on the conglomerate wedge: move to an interior silhouette
    /// vertex, or ask for the next mast wedge, or halt as trapped.
    fn virtual_step(&mut self, pose: Pose2, goal: Point2) -> Option<NavCommand> {
        let x = pose.position();
        let Mode::Virtual { sense, scans } = self.mode.clone() else { return None };
        if self.motion_to_goal_clear(x, goal) {
            self.mode = Mode::MotionToGoal;
            return None;
        }
        for s in [sense, -sense] {
            if let Some((path, d_reach, v_loop)) = self.silhouette(x, goal, s, true) {
                self.mode = Mode::Normal { sense: s, d_reach, v_loop, left_loop: false, scans: vec![0] };
                self.execute(path);
                return None;
            }
        }
        let Some((next, angle)) = self.next_scan(&scans, sense) else {
            // No silhouette vertex in the interior of the conglomerate wedge: in clutter the
            // blocking C-obstacles hide each other's silhouettes. Follow the best way on the
            // local tangent graph instead; halt as trapped only when there is none.
            if let Some(path) = self.best_exit(&self.build_ltg(x, goal), x, goal) {
                let d_reach = x.dist(goal);
                self.mode = Mode::Normal { sense, d_reach, v_loop: x, left_loop: false, scans: vec![0] };
                self.execute(path);
                return None;
            }
            self.stuck = true;
            return self.halt(
                Outcome::Unreachable,
                "trapped: the mast scans overlap all around and no boundary vertex leads out",
            );
        };
        let mut scans = scans;
        scans.push(next);
        self.mode = Mode::Virtual { sense, scans };
        Some(self.sense(vec![self.mast_at(pose, goal.sub(x).angle() + angle)]))
    }

    /// Safety-layer hazard cells (centres) that come within the body margin of the body
    /// outline at any of `poses`, closer than they are at `start`. Cells under the bare body at
    /// `start` are left out: the rover stands there without contact, so those are noise or too
    /// low to matter, and counting them would forbid every motion; a cell already within the
    /// margin beside the body only counts if the motion brings the body nearer.
    fn motion_hazards(&self, start: Pose2, poses: &[Pose2]) -> Vec<Point2> {
        let Some(hazard) = &self.safety_hazard else { return Vec::new() };
        let g = hazard.geometry;
        let (half_l, half_w) = (0.5 * self.rover.length, 0.5 * self.rover.width);
        let m = self.config.body_margin;
        let reach = (half_l + m).hypot(half_w + m);
        // Chebyshev-style distance from the body rectangle (negative under the body).
        let outside = |pose: &Pose2, q: Point2| {
            let b = pose.inverse_transform(q);
            (b.x.abs() - half_l).max(b.y.abs() - half_w)
        };
        let mut out: Vec<Point2> = Vec::new();
        for pose in poses {
            let (cols, rows) = cells_around(&g, pose.position(), reach);
            for r in rows {
                for c in cols.clone() {
                    if !*hazard.get(c, r) {
                        continue;
                    }
                    let (cx, cy) = g.center(c, r);
                    let q = Point2::new(cx, cy);
                    let before = outside(&start, q);
                    let now = outside(pose, q);
                    if before > 0.0
                        && now <= m
                        && now < before - 0.01
                        && !out.iter().any(|o| o.dist(q) < 1e-9)
                    {
                        out.push(q);
                    }
                }
            }
        }
        out
    }

    /// The first of `poses` at which the body outline (with a wheel radius of look-ahead at
    /// either end) covers ground the safety layer has not sensed (see [`first_unseen_pose`]).
    /// The wedge geometry alone does not say this: a subpath along a wedge's edge takes half
    /// the body outside it, and the ground behind a rock is in the wedge but hidden. Cells
    /// under the body at `start` are left out (the rover stands there), and so is the mast's
    /// blind zone around the sensing position, as for the local tangent graph (`near_visible`:
    /// the rover's footprint, seen from the previous position).
    fn first_unseen(&self, start: Pose2, poses: &[Pose2]) -> Option<usize> {
        let safety = self.safety.as_ref()?;
        let grid = safety.grid();
        let origin = self.view.as_ref().map_or(start.position(), |v| v.origin);
        let (half_l, half_w) = (0.5 * self.rover.length, 0.5 * self.rover.width);
        let exempt = |q: Point2| {
            let b = start.inverse_transform(q);
            (b.x.abs() <= half_l && b.y.abs() <= half_w) || q.dist(origin) <= self.config.near_visible
        };
        first_unseen_pose(
            poses,
            (half_l + UNSEEN_LOOKAHEAD, half_w),
            safety.config().resolution,
            exempt,
            |q| grid.at_world(q.x, q.y).is_some_and(|c| c.count > 0),
        )
    }

    /// Records the body poses from the last recorded one to `pose`, interpolated
    /// [`SWEPT_STEP`] apart, and forgets those more than `swept_memory` of driving back.
    fn record_swept(&mut self, pose: Pose2) {
        if self.config.swept_memory <= 0.0 {
            return;
        }
        let Some(&(last, driven)) = self.swept.back() else {
            self.swept.push_back((pose, 0.0));
            return;
        };
        let distance = last.position().dist(pose.position());
        let turn = angle_diff(pose.yaw, last.yaw);
        let n = (distance.max(turn.abs()) / SWEPT_STEP).ceil() as usize;
        for k in 1..=n {
            let t = k as f64 / n as f64;
            let p = last.position().add(pose.position().sub(last.position()).scale(t));
            self.swept.push_back((Pose2::new(p.x, p.y, last.yaw + t * turn), driven + t * distance));
        }
        let latest = driven + distance;
        while self.swept.front().is_some_and(|&(_, d)| d < latest - self.config.swept_memory) {
            self.swept.pop_front();
        }
    }

    /// Clears the hazard cells of `mask` whose centres the body, inset by `swept_inset`, has
    /// covered along the recorded poses.
    fn clear_swept(&self, mask: &mut Grid2<bool>) {
        let g = mask.geometry;
        let half_l = 0.5 * self.rover.length - self.config.swept_inset;
        let half_w = 0.5 * self.rover.width - self.config.swept_inset;
        if half_l <= 0.0 || half_w <= 0.0 {
            return;
        }
        let reach = half_l.hypot(half_w);
        for &(pose, _) in &self.swept {
            let (cols, rows) = cells_around(&g, pose.position(), reach);
            for r in rows {
                for c in cols.clone() {
                    let (cx, cy) = g.center(c, r);
                    let b = pose.inverse_transform(Point2::new(cx, cy));
                    if b.x.abs() <= half_l && b.y.abs() <= half_w {
                        *mask.get_mut(c, r) = false;
                    }
                }
            }
        }
    }

    /// The safety layer's hazard cells whose own points rise above (or fall below) the median
    /// height of the sensed cells within the footprint radius by a fraction of the layer's step
    /// limit. The step/slope model also marks ground-level cells of a window it finds hazardous
    /// when the window is sparsely sensed (single points, planes tilted by a nearby rock);
    /// those would pin the rover in place for nothing. The fraction stays well below one: the
    /// wheels may stand lower than the median ground, so a rock that reads a little under the
    /// limit above it can still touch the belly. Slope hazards are left to the C-obstacles.
    /// Ground the body has just crossed without a hazard stop is cleared (see `clear_swept`).
    fn confirm_hazards(&self) -> Option<Grid2<bool>> {
        let safety = self.safety.as_ref()?;
        let layers = safety.layers();
        let mut out = layers.hazard.clone();
        let g = out.geometry;
        let limit = self.config.confirm_fraction * safety.config().clearance;
        let k = (safety.config().footprint_radius / g.resolution).round() as isize;
        for r in 0..g.rows {
            for c in 0..g.cols {
                if !*out.get(c, r) {
                    continue;
                }
                let (x, y) = g.center(c, r);
                let Some(cell) = safety.grid().at_world(x, y).filter(|cell| cell.count > 0) else {
                    *out.get_mut(c, r) = false;
                    continue;
                };
                let mut around: Vec<f64> = Vec::new();
                for dr in -k..=k {
                    for dc in -k..=k {
                        let (qx, qy) = (x + dc as f64 * g.resolution, y + dr as f64 * g.resolution);
                        if (dc * dc + dr * dr) as f64 <= (k * k) as f64
                            && let Some(m) = safety.grid().at_world(qx, qy).and_then(|q| q.mean())
                        {
                            around.push(m);
                        }
                    }
                }
                around.sort_by(f64::total_cmp);
                let ground = around.get(around.len() / 2).copied().unwrap_or(f64::NAN);
                let stands_out = cell.max_z as f64 - ground > limit || ground - cell.min_z as f64 > limit;
                *out.get_mut(c, r) = stands_out;
            }
        }
        self.clear_swept(&mut out);
        Some(out)
    }

    /// Whether the rover can turn in place toward `target` (either way round) and drive
    /// straight to it without its body sweeping over a safety-layer hazard.
    fn leg_clear(&self, target: Point2) -> bool {
        let Some(pose) = self.here else { return true };
        let d = target.sub(pose.position());
        let error = angle_diff(d.angle(), pose.yaw);
        if error.abs() <= self.config.turn_threshold {
            // No turn: the drive is the arc the executor commands.
            let (distance, curvature) = Self::arc_to(d.norm(), error);
            return self.motion_hazards(pose, &Self::arc_poses(pose, distance, curvature)).is_empty();
        }
        let turned = Pose2::new(pose.x, pose.y, pose.yaw + error);
        let turn_ok = self.motion_hazards(pose, &Self::turn_poses(pose, error)).is_empty()
            || self
                .motion_hazards(pose, &Self::turn_poses(pose, error - error.signum() * 2.0 * PI))
                .is_empty();
        turn_ok && self.motion_hazards(pose, &Self::arc_poses(turned, d.norm(), 0.0)).is_empty()
    }

    /// When planning gave up with the rover pinned by safety-layer hazards (it cannot turn
    /// all the way round in place), a short straight drive out, backwards first (the way the
    /// rover came), replaces the halt: the hazards restrict its turns, not the C-obstacles its
    /// way. At most twice in one place.
    fn escape(&mut self, pose: Pose2) -> Option<NavCommand> {
        if self.stats.sensing_actions >= self.config.max_wedges {
            return None;
        }
        let pinned = !self.motion_hazards(pose, &Self::turn_poses(pose, 2.0 * PI)).is_empty();
        let x = pose.position();
        let (count, at) = self.escapes;
        let count = if at.dist(x) < 0.5 { count + 1 } else { 1 };
        if !pinned || count > 2 {
            return None;
        }
        let distance = [-self.config.escape_distance, self.config.escape_distance]
            .into_iter()
            .find(|&d| self.motion_hazards(pose, &Self::arc_poses(pose, d, 0.0)).is_empty())?;
        self.escapes = (count, x);
        self.remember(x);
        self.finish = None;
        // The short drive out is a motion, not a decision of the planner: boundary following
        // goes on in the same sense toward the same V_loop (a restart would choose the sense
        // afresh, and inside a U-shaped trap the shorter side flips from place to place).
        if !self.config.near_side_reach || !matches!(self.mode, Mode::Normal { .. }) {
            self.mode = Mode::MotionToGoal;
        }
        self.last_motion = Some(distance.signum());
        self.drive_from = Some(x);
        Some(NavCommand::Drive { distance, curvature: 0.0, guard: DriveGuard::default() })
    }

    /// Length and curvature of the arc that starts along the current heading and ends at a
    /// point `chord` metres away, `error` radians off the heading.
    fn arc_to(chord: f64, error: f64) -> (f64, f64) {
        let curvature = if chord > 1e-6 { 2.0 * error.sin() / chord } else { 0.0 };
        let distance = if error.abs() > 1e-6 { chord * error / error.sin() } else { chord };
        (distance, curvature)
    }

    /// Poses along a turn in place by `angle` from `pose`, a few degrees apart.
    fn turn_poses(pose: Pose2, angle: f64) -> Vec<Pose2> {
        let n = (angle.abs() / 4f64.to_radians()).ceil().max(1.0) as usize;
        (1..=n).map(|k| Pose2::new(pose.x, pose.y, pose.yaw + angle * k as f64 / n as f64)).collect()
    }

    /// Poses along an arc of signed length `distance` and `curvature` from `pose`, 5 cm apart.
    fn arc_poses(pose: Pose2, distance: f64, curvature: f64) -> Vec<Pose2> {
        let n = (distance.abs() / 0.05).ceil().max(1.0) as usize;
        (1..=n)
            .map(|k| {
                let s = distance * k as f64 / n as f64;
                let yaw = pose.yaw + curvature * s;
                if curvature.abs() < 1e-9 {
                    Pose2::new(pose.x + s * pose.yaw.cos(), pose.y + s * pose.yaw.sin(), pose.yaw)
                } else {
                    Pose2::new(
                        pose.x + (yaw.sin() - pose.yaw.sin()) / curvature,
                        pose.y - (yaw.cos() - pose.yaw.cos()) / curvature,
                        yaw,
                    )
                }
            })
            .collect()
    }

    /// When planning finds no way on without a proof that the goal is unreachable (the local
    /// C-obstacles hem the rover in: in clutter they close gaps a nearer view may open), drives
    /// back in reverse along the recorded trail, over ground the body has already crossed, and
    /// records the dead end as a small C-obstacle so that the next motion-to-goal segment
    /// plans around it. At most `max_retreats` times; false when there is no trail to retrace.
    fn retreat(&mut self, x: Point2, goal: Point2) -> bool {
        if self.retreats >= self.config.max_retreats
            || self.stats.sensing_actions >= self.config.max_wedges
            || self.steps >= self.config.max_steps
        {
            return false;
        }
        let mut trail = self.trail.clone();
        let mut path = vec![x];
        let mut length = 0.0;
        while let Some(p) = trail.pop() {
            let last = *path.last().unwrap_or(&x);
            if p.dist(last) < 0.05 {
                continue;
            }
            length += p.dist(last);
            path.push(p);
            if length >= self.config.retreat_distance {
                break;
            }
        }
        if length < 0.3 {
            return false;
        }
        // The retreat's end stays on the trail; the retraced part is left behind.
        trail.push(*path.last().unwrap_or(&x));
        self.trail = trail;
        self.retreats += 1;
        let growth = self.terrain.growth();
        // Never around the goal: a goal inside a C-obstacle turns its vertices into goals.
        if x.dist(goal) > growth {
            self.dead_ends.push(CObstacle::from_hull(vec![x], growth, self.terrain.max_arc_step, 0));
        }
        self.finish = None;
        self.mode = Mode::MotionToGoal;
        self.visited.clear();
        self.reversing = true;
        self.execute(path);
        true
    }

    /// Drives the queued subpath: a turn in place toward the next waypoint (the rear of the
    /// rover when reversing) or an arc to it, each checked for safety first; a new step once
    /// the subpath is done.
    fn drive_waypoints(&mut self, pose: Pose2, goal: Point2) -> NavCommand {
        let x = pose.position();
        while let Some(&next) = self.waypoints.front() {
            if next.dist(x) < 0.05 {
                self.waypoints.pop_front();
                continue;
            }
            // Reversing, the rear leads: the heading error is taken from the reversed heading.
            let sign = if self.reversing { -1.0 } else { 1.0 };
            let lead = if self.reversing { pose.yaw + PI } else { pose.yaw };
            let error = angle_diff(next.sub(x).angle(), lead);
            if error.abs() > self.config.turn_threshold {
                // The shorter way round, else the longer one, if the body's sweep is clear.
                let long = error - error.signum() * 2.0 * PI;
                let short_cells = self.motion_hazards(pose, &Self::turn_poses(pose, error));
                let angle = if short_cells.is_empty() {
                    error
                } else if self.motion_hazards(pose, &Self::turn_poses(pose, long)).is_empty() {
                    long
                } else if let Some(arc) = self.reverse_arc(pose, next, error) {
                    return arc;
                } else {
                    return self.refuse(pose, goal);
                };
                self.last_motion = Some(2.0);
                return NavCommand::Turn { angle };
            }
            let (distance, curvature) = Self::arc_to(x.dist(next), error);
            // Backwards along an arc the yaw turns the other way for the same bend.
            let (distance, curvature) = (sign * distance, sign * curvature);
            let poses = Self::arc_poses(pose, distance, curvature);
            let cells = self.motion_hazards(pose, &poses);
            if !cells.is_empty() {
                return self.refuse(pose, goal);
            }
            // Forward, the body covers only sensed ground: the seen part of the arc is driven
            // (the waypoint stays), and short of that the next step looks at the unseen part.
            // Reversing retraces the trail.
            let checked = self.config.unseen_looks > 0 && !self.reversing;
            if let Some(j) = checked.then(|| self.first_unseen(pose, &poses)).flatten() {
                let seen = distance * j as f64 / poses.len() as f64 - UNSEEN_BACKOFF;
                if seen >= UNSEEN_MIN_DRIVE {
                    self.last_motion = Some(sign);
                    self.drive_from = Some(x);
                    return NavCommand::Drive { distance: seen, curvature, guard: DriveGuard::default() };
                }
                let (count, at) = self.looks;
                let count = if at.dist(x) < 0.3 { count + 1 } else { 1 };
                self.looks = (count, x);
                if count > self.config.unseen_looks {
                    return self.refuse(pose, goal);
                }
                self.look_at = Some(poses[j].position());
                self.waypoints.clear();
                return self.open_step(pose, goal);
            }
            self.waypoints.pop_front();
            self.last_motion = Some(sign);
            self.drive_from = Some(x);
            return NavCommand::Drive { distance, curvature, guard: DriveGuard::default() };
        }
        // Subpath done: a goal vertex reached, or a new step.
        if self
            .obstacles
            .iter()
            .any(|o| o.contains_strict(goal) && o.vertices.iter().any(|v| v.dist(x) < 0.3))
        {
            return NavCommand::Finish(Outcome::Reached, "at a vertex of the goal's C-obstacle".into());
        }
        self.open_step(pose, goal)
    }

    /// A retreat whose turn in place the safety check refuses backs along an arc to the
    /// waypoint instead, if that sweep is clear and the waypoint lies within 45 degrees of the
    /// rear (the arc then strays from the chord by at most about a fifth of its length): pinned where
    /// it stands, the rover otherwise spends every retreat on the spot and, each one recording
    /// a dead end there, boxes itself in (seed 14 of the default yard).
    fn reverse_arc(&mut self, pose: Pose2, next: Point2, error: f64) -> Option<NavCommand> {
        if !self.reversing || error.abs() > 0.25 * PI {
            return None;
        }
        let x = pose.position();
        let (distance, curvature) = Self::arc_to(x.dist(next), error);
        let (distance, curvature) = (-distance, -curvature);
        if !self.motion_hazards(pose, &Self::arc_poses(pose, distance, curvature)).is_empty() {
            return None;
        }
        self.waypoints.pop_front();
        self.last_motion = Some(-1.0);
        self.drive_from = Some(x);
        Some(NavCommand::Drive { distance, curvature, guard: DriveGuard::default() })
    }

    /// The new step to command instead of a motion the safety check refused (a later leg of
    /// the subpath: the first leg of every plan is checked); after repeated refusals here,
    /// backs out if it can (see [`Self::escape`]), else retreats along the trail (see
    /// [`Self::retreat`]), else asks for help.
    fn refuse(&mut self, pose: Pose2, goal: Point2) -> NavCommand {
        let x = pose.position();
        self.waypoints.clear();
        let (count, at) = self.refusals;
        let count = if at.dist(x) < 0.3 { count + 1 } else { 1 };
        self.refusals = (count, x);
        if count > self.config.max_refusals_here {
            if let Some(escape) = self.escape(pose) {
                return escape;
            }
            // Every plan from here is refused: back out over the ground the body came by.
            if self.retreat(x, goal) {
                self.refusals = (0, x);
                return self.drive_waypoints(pose, goal);
            }
            return self.finish_now(
                Outcome::HelpRequested,
                "every motion from here sweeps the body over a sensed hazard",
            );
        }
        // Replan on fresh sensing: the new plan's first leg is checked.
        self.open_step(pose, goal)
    }

    /// Records a final outcome and returns the command that reports it.
    fn finish_now(&mut self, outcome: Outcome, why: &str) -> NavCommand {
        self.finish = Some((outcome, why.to_string()));
        NavCommand::Finish(outcome, why.to_string())
    }

    /// [`Self::finish_now`] for the planning functions that may return a command.
    fn halt(&mut self, outcome: Outcome, why: &str) -> Option<NavCommand> {
        Some(self.finish_now(outcome, why))
    }

    /// Whether the direct line toward the goal is free within the view (T_g exists).
    fn motion_to_goal_clear(&self, x: Point2, goal: Point2) -> bool {
        let d = goal.sub(x);
        let tg = x.add(d.scale(d.norm().min(self.range()) / d.norm().max(1e-9)));
        !self.obstacles.iter().any(|o| o.contains_strict(goal) && o.contains(tg))
            && self.segment_free(x, tg, x)
            && self.segment_visible(x, tg)
            && tg.dist(goal) <= self.d_leave.unwrap_or(f64::INFINITY) + 1e-9
            && self.leg_clear(tg)
    }

    /// Normal boundary following: leave when a reachable node beats `d_reach`, halt when the
    /// loop point comes back, else move to the next silhouette vertex in the positive sense
    /// (turning the gaze when none is in view).
    fn normal_step(&mut self, pose: Pose2, goal: Point2) -> Option<NavCommand> {
        let x = pose.position();
        let Mode::Normal { sense, d_reach, v_loop, mut left_loop, scans } = self.mode.clone() else {
            return None;
        };
        let ltg = self.build_ltg(x, goal);
        // Leaving condition: a reachable node of G1 closer to the goal than d_reach.
        let bound = x.dist(goal).min(self.d_leave.unwrap_or(f64::INFINITY));
        let limit = d_reach - self.config.leave_margin;
        let leave = self.search(&ltg, goal, &|n: &Node| {
            n.arrival || (n.p.dist(goal) <= bound + 1e-9 && n.p.dist(goal) < limit)
        });
        // The way to a node that beats d_reach must lie on sensed ground: beyond the cut radius
        // the tangent graph also crosses ground no image covered, where an encircling
        // obstacle's rocks have no C-obstacles, and a leave through it would restart boundary
        // following (with a new V_loop) each time the rover drives up to it.
        let leave = leave.filter(|path| {
            !self.config.near_side_reach
                || path.windows(2).all(|w| self.segment_sensed(ltg.nodes[w[0]].p, ltg.nodes[w[1]].p))
        });
        if let Some(path) = leave {
            let end = ltg.nodes[*path.last().expect("non-empty path")];
            self.d_leave = Some(end.p.dist(goal));
            self.been.clear();
            self.mode = Mode::MotionToGoal;
            let points: Vec<Point2> = path.iter().map(|&i| ltg.nodes[i].p).collect();
            let sub = self.truncate(&points, x);
            self.execute(sub);
            return None;
        }
        self.visited.push(x);
        left_loop |= x.dist(v_loop) > 2.0;
        if left_loop && x.dist(v_loop) < 1.0 && self.encircles_goal(goal, None) {
            return self.halt(
                Outcome::Unreachable,
                "boundary following completed a loop around the obstacle (V_loop): the goal is unreachable",
            );
        }
        if let Some((path, seen_reach, _)) = self.silhouette(x, goal, sense, false) {
            let target = *path.last().expect("non-empty subpath");
            if left_loop && target.dist(v_loop) < 1.0 && self.encircles_goal(goal, Some(target)) {
                return self.halt(
                    Outcome::Unreachable,
                    "boundary following reached V_loop again: the goal is unreachable",
                );
            }
            let d_reach = d_reach.min(seen_reach);
            self.mode = Mode::Normal { sense, d_reach, v_loop, left_loop, scans: vec![0] };
            self.execute(path);
            return None;
        }
        let Some((next, angle)) = self.next_scan(&scans, sense) else {
            // The gaze has turned all around without a silhouette vertex in the interior of the
            // conglomerate wedge (paper: abort). In clutter, step on instead (along the boundary,
            // or toward the goal once it has led too far away); abort only when there is none.
            // The graph built for the leaving condition: nothing it depends on has changed.
            if let Some(path) = self.blocked_step(&ltg, x, goal, sense, d_reach) {
                self.mode = Mode::Normal { sense, d_reach, v_loop, left_loop, scans: vec![0] };
                self.execute(path);
                return None;
            }
            self.stuck = true;
            return self.halt(
                Outcome::HelpRequested,
                "boundary following: the scans overlap all around and no boundary vertex leads on",
            );
        };
        let mut scans = scans;
        scans.push(next);
        self.mode = Mode::Normal { sense, d_reach, v_loop, left_loop, scans };
        Some(self.sense(vec![self.mast_at(pose, goal.sub(x).angle() + angle)]))
    }

    /// The sensing that opens a step in the current mode.
    fn open_step(&mut self, pose: Pose2, goal: Point2) -> NavCommand {
        self.view = None;
        self.reversing = false;
        self.new_view(pose);
        if let Some((outcome, why)) = self.finish.clone() {
            return NavCommand::Finish(outcome, why);
        }
        if self.steps > self.config.max_steps {
            let why = format!("no arrival in {} steps", self.config.max_steps);
            return self.finish_now(Outcome::HelpRequested, &why);
        }
        let toward_goal = goal.sub(pose.position()).angle();
        let mut requests = vec![self.mast_at(pose, toward_goal)];
        if let Mode::Normal { sense, .. } = self.mode {
            // Also along the boundary, a quarter turn from the goal direction.
            requests.push(self.mast_at(pose, pose.yaw + sense * self.alpha_mast()));
        }
        if let Some(target) = self.look_at.take()
            && target.dist(pose.position()) > self.config.near_visible
        {
            // Gaze control: the ground a drive was held back from, beyond the mast's blind
            // zone, unless the wedge toward the goal covers it.
            let bearing = target.sub(pose.position()).angle();
            if angle_diff(bearing, toward_goal).abs() > 0.5 * self.alpha_mast() {
                requests.push(self.mast_at(pose, bearing));
            }
        }
        requests.push(SenseRequest::BodyFront);
        if let Mode::Virtual { .. } = self.mode {
            self.mode = Mode::MotionToGoal;
        }
        self.sense(requests)
    }

    /// Plans after new sensing; returns a command when the mode asks for more data or halts.
    fn plan(&mut self, pose: Pose2, goal: Point2) -> Option<NavCommand> {
        let x = pose.position();
        for _ in 0..3 {
            match self.mode {
                Mode::MotionToGoal => {
                    if self.d_leave.is_none() {
                        self.d_leave = Some(x.dist(goal));
                    }
                    if self.motion_to_goal(x, goal) {
                        return None;
                    }
                    self.start_boundary_following(x, goal);
                }
                Mode::Virtual { .. } => {
                    let cmd = self.virtual_step(pose, goal);
                    if cmd.is_some() || !self.waypoints.is_empty() {
                        return cmd;
                    }
                }
                Mode::Normal { .. } => {
                    let cmd = self.normal_step(pose, goal);
                    if cmd.is_some() || !self.waypoints.is_empty() {
                        return cmd;
                    }
                }
            }
        }
        None
    }
}

/// The first of `poses` at which a body outline of half-extents `half` (m, along and across
/// the heading) covers unseen ground: a cell centre of the `resolution` lattice (cells
/// `[i r, (i + 1) r)`, as the map's) inside the outline, not `exempt`, that is not `sensed`
/// and is no one-cell gap among sensed cells (at least five of its eight neighbours sensed:
/// the spacing of a range image's far rows).
fn first_unseen_pose(
    poses: &[Pose2],
    half: (f64, f64),
    resolution: f64,
    exempt: impl Fn(Point2) -> bool,
    sensed: impl Fn(Point2) -> bool,
) -> Option<usize> {
    let n = (half.0.hypot(half.1) / resolution).ceil() as i64;
    let lattice = |x: f64, y: f64| Point2::new((x + 0.5) * resolution, (y + 0.5) * resolution);
    poses.iter().position(|pose| {
        let (cx, cy) = ((pose.x / resolution).floor(), (pose.y / resolution).floor());
        (-n..=n).any(|dr| {
            (-n..=n).any(|dc| {
                let (i, j) = (cx + dc as f64, cy + dr as f64);
                let q = lattice(i, j);
                let b = pose.inverse_transform(q);
                if b.x.abs() > half.0 || b.y.abs() > half.1 || exempt(q) || sensed(q) {
                    return false;
                }
                let around = [(-1, -1), (0, -1), (1, -1), (-1, 0), (1, 0), (-1, 1), (0, 1), (1, 1)]
                    .iter()
                    .filter(|&&(a, c)| sensed(lattice(i + a as f64, j + c as f64)))
                    .count();
                around < 5
            })
        })
    })
}

/// The column and row ranges of the cells of grid `g` within the square of half-side `reach`
/// around `p`, clipped to the grid.
fn cells_around(
    g: &rovernav_core::GridGeometry,
    p: Point2,
    reach: f64,
) -> (std::ops::Range<usize>, std::ops::Range<usize>) {
    let index = |v: f64, origin: f64| ((v - origin) / g.resolution).max(0.0);
    let c0 = index(p.x - reach, g.origin_x).floor() as usize;
    let r0 = index(p.y - reach, g.origin_y).floor() as usize;
    let c1 = (index(p.x + reach, g.origin_x).ceil() as usize).min(g.cols);
    let r1 = (index(p.y + reach, g.origin_y).ceil() as usize).min(g.rows);
    (c0..c1, r0..r1)
}

/// Euclidean distance from `p` to a C-obstacle's hull (the hazard cells' convex hull, before
/// growth); 0 inside it.
fn hull_distance(o: &CObstacle, p: Point2) -> f64 {
    let n = o.hull.len();
    if n == 0 {
        return f64::INFINITY;
    }
    if n >= 3 && o.hull_contains_strict(p) {
        return 0.0;
    }
    (0..n)
        .map(|i| {
            let (a, b) = (o.hull[i], o.hull[(i + 1) % n]);
            let d = b.sub(a);
            let t = if d.dot(d) > 1e-18 { (p.sub(a).dot(d) / d.dot(d)).clamp(0.0, 1.0) } else { 0.0 };
            p.dist(a.add(d.scale(t)))
        })
        .fold(f64::INFINITY, f64::min)
}

/// The outline of a sensed wedge in the world, for display.
fn wedge_polygon(pose: Pose2, wedge: &rovernav_core::Wedge) -> Vec<Point2> {
    let n = 8;
    let mut out = Vec::with_capacity(2 * n + 2);
    for i in 0..=n {
        let a = wedge.bearing - wedge.half_angle + 2.0 * wedge.half_angle * i as f64 / n as f64;
        out.push(pose.transform(Point2::new(a.cos(), a.sin()).scale(wedge.max_range)));
    }
    for i in (0..=n).rev() {
        let a = wedge.bearing - wedge.half_angle + 2.0 * wedge.half_angle * i as f64 / n as f64;
        out.push(pose.transform(Point2::new(a.cos(), a.sin()).scale(wedge.min_range)));
    }
    out
}

impl Navigator for RoverBug {
    fn name(&self) -> &str {
        "roverbug"
    }

    fn step(&mut self, input: &NavInput<'_>) -> NavCommand {
        let pose = input.estimate.pose.pose2();
        let x = pose.position();
        let goal = input.goal.position;
        if let Some((outcome, why)) = self.finish.clone() {
            return NavCommand::Finish(outcome, why);
        }
        self.goal_tolerance = input.goal.tolerance;
        if x.dist(goal) <= input.goal.tolerance {
            return NavCommand::Finish(Outcome::Reached, format!("within {:.2} m of the goal", x.dist(goal)));
        }
        if let Some(why) = &input.frame.motion_stopped {
            self.waypoints.clear();
            // The edge of the terrain stops the wheels like a hazard does: both are recorded.
            let blocked = why.starts_with("hazard") || why.starts_with("left the terrain");
            if blocked {
                // The ground of a stopped motion is no evidence of safe ground.
                self.swept.clear();
            }
            if blocked && !self.backing_out {
                // Record where the body met the terrain (paper: explicitly recorded points may
                // pass between steps), so no later subpath leads there again.
                let half = 0.5 * self.rover.length;
                let touched: Vec<Point2> = match self.last_motion {
                    Some(sign) if sign.abs() < 2.0 => vec![pose.transform(Point2::new(sign * half, 0.0))],
                    _ => vec![
                        pose.transform(Point2::new(half, 0.5 * self.rover.width)),
                        pose.transform(Point2::new(half, -0.5 * self.rover.width)),
                    ],
                };
                for p in touched {
                    let growth = self.terrain.growth();
                    self.contacts.push(CObstacle::from_hull(vec![p], growth, self.terrain.max_arc_step, 0));
                }
                let here = self.contacts.iter().filter(|o| o.hull.iter().any(|h| h.dist(x) < 0.6)).count();
                if here >= self.config.max_contacts_here {
                    return self.finish_now(
                        Outcome::HelpRequested,
                        "repeated hazard contacts or terrain-edge stops at the same place",
                    );
                }
                // Back out along the ground the wheels just crossed: reversing farther than the
                // drive went (after a turn in place, hardly at all) leads onto ground the body
                // has not covered.
                let back = match (self.last_motion, self.drive_from) {
                    (Some(sign), Some(from)) if sign.abs() < 2.0 => x.dist(from).clamp(0.1, 0.3),
                    _ => 0.3,
                };
                // Out the way the wheels came: forward after a contact driving in reverse.
                let dir = if self.last_motion.is_some_and(|s| s < 0.0) { 1.0 } else { -1.0 };
                self.backing_out = true;
                self.reversing = false;
                self.last_motion = Some(dir);
                return NavCommand::Drive {
                    distance: dir * back,
                    curvature: 0.0,
                    guard: DriveGuard::default(),
                };
            }
        }
        self.backing_out = false;
        self.record_swept(pose);
        if !self.reversing && self.trail.last().is_none_or(|p| p.dist(x) > 0.05) {
            self.trail.push(x);
        }
        if !input.frame.clouds.is_empty() {
            self.here = Some(pose);
            self.ingest(input);
            if let Some((outcome, why)) = self.finish.clone() {
                return NavCommand::Finish(outcome, why);
            }
            let mut cmd = self.plan(pose, goal);
            // Resting at a vertex of the goal's C-obstacle is arrival, not a reason to back out.
            let at_goal_vertex = cmd.is_none()
                && self.waypoints.is_empty()
                && self.obstacles.iter().any(|o| o.contains_strict(goal))
                && self
                    .obstacles
                    .iter()
                    .any(|o| o.contains(goal) && o.vertices.iter().any(|v| v.dist(x) < 0.3));
            let gave_up = match &self.finish {
                Some((outcome, _)) => *outcome != Outcome::Reached,
                None => cmd.is_none() && self.waypoints.is_empty() && !at_goal_vertex,
            };
            let stuck = gave_up && (self.finish.is_none() || self.stuck);
            self.stuck = false;
            // Only a give-up is squeezed, escaped or retreated from: a loop through V_loop is a
            // proof.
            if stuck && self.squeeze(pose, input.goal) {
                cmd = None;
            } else if stuck {
                if let Some(escape) = self.escape(pose) {
                    return escape;
                }
                if self.retreat(x, goal) {
                    return self.drive_waypoints(pose, goal);
                }
            }
            if let Some(cmd) = cmd {
                return cmd;
            }
            if let Some((outcome, why)) = self.finish.clone() {
                return NavCommand::Finish(outcome, why);
            }
            if self.waypoints.is_empty() {
                // Nothing to do from here: the goal vertex was reached, or no plan exists.
                if at_goal_vertex {
                    return NavCommand::Finish(
                        Outcome::Reached,
                        "at a vertex of the goal's C-obstacle".into(),
                    );
                }
                self.finish = Some((Outcome::HelpRequested, "no subpath from the current view".into()));
                return NavCommand::Finish(Outcome::HelpRequested, "no subpath from the current view".into());
            }
        }
        self.drive_waypoints(pose, goal)
    }

    fn planned_path(&self) -> Vec<Point2> {
        self.subpath.clone()
    }

    fn overlays(&self) -> Vec<Overlay> {
        let wedges = self.drawn_wedges.iter().map(|w| Overlay::Polygon(w.clone(), OverlayKind::Wedge));
        let obstacles =
            self.drawn_obstacles.iter().map(|o| Overlay::Polygon(o.clone(), OverlayKind::CObstacle));
        let paths = self.drawn_paths.iter().map(|p| Overlay::Polyline(p.clone(), OverlayKind::Plan));
        wedges.chain(obstacles).chain(paths).collect()
    }

    fn stats(&self) -> NavigatorStats {
        self.stats.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(cx: f64, cy: f64, h: f64) -> CObstacle {
        let hull = vec![
            Point2::new(cx - h, cy - h),
            Point2::new(cx + h, cy - h),
            Point2::new(cx + h, cy + h),
            Point2::new(cx - h, cy + h),
        ];
        CObstacle::from_hull(hull, 0.0, 0.5, 1)
    }

    /// [`square`] with each corner once: a zero growth repeats the corners, whose zero-length
    /// edges then pass any line as tangent.
    fn corner_square(cx: f64, cy: f64, h: f64) -> CObstacle {
        let mut o = square(cx, cy, h);
        o.vertices = o.hull.clone();
        o.labels.truncate(o.vertices.len());
        o
    }

    fn bug_with(obstacles: Vec<CObstacle>) -> RoverBug {
        let mut bug = RoverBug::new(RoverConfig::default(), RoverBugConfig::default());
        bug.new_view(Pose2::new(0.0, 0.0, 0.0));
        let wedge = rovernav_core::Wedge { bearing: 0.0, half_angle: 1.2, min_range: 0.0, max_range: 5.0 };
        bug.view.as_mut().unwrap().wedges.push(SensedWedge { pose: Pose2::new(0.0, 0.0, 0.0), wedge });
        bug.obstacles = obstacles;
        bug
    }

    #[test]
    fn ltg_path_around_a_square_is_the_hand_computed_tangent_path() {
        // Square [2,3]x[-0.5,0.5] between rover (0,0) and goal (4,0): the shortest path hugs one
        // side: 0 -> (2,±0.5) -> (3,±0.5) -> goal, by hand |(2,0.5)| + 1 + |(1,0.5)| = 4.1796.
        let bug = bug_with(vec![square(2.5, 0.0, 0.5)]);
        let goal = Point2::new(4.0, 0.0);
        let ltg = bug.build_ltg(Point2::new(0.0, 0.0), goal);
        let path = bug.search(&ltg, goal, &|_| true).expect("path");
        let pts: Vec<Point2> = path.iter().map(|&i| ltg.nodes[i].p).collect();
        let len: f64 = pts.windows(2).map(|w| w[0].dist(w[1])).sum::<f64>() + pts.last().unwrap().dist(goal);
        let expect = 2.0f64.hypot(0.5) + 1.0 + 1.0f64.hypot(0.5);
        assert!((len - expect).abs() < 1e-3, "{len} vs {expect}: {pts:?}");
    }

    #[test]
    fn d_reach_on_the_near_side_leaves_out_the_vertices_seen_over_the_obstacle() {
        // Square [2,3]x[-0.5,0.5] between the rover (0,0) and the goal (4,0). Its near corners
        // (2,±0.5) are seen across free space, 2.0616 m from the goal; its far corners (3,±0.5)
        // are in view too (a mast sees over low rocks) but only past the square, 1.1180 m from
        // the goal. V_loop, the extreme vertex in the negative sense, is the near corner
        // (2,-0.5) whichever vertices it is taken among here; the ring scenario
        // `ring_with_unseen_looks_v_loop_on_the_far_side_never_closed_the_loop` is the one that
        // tells the near side from all of them.
        let goal = Point2::new(4.0, 0.0);
        let x = Point2::new(0.0, 0.0);
        let mut bug = bug_with(vec![square(2.5, 0.0, 0.5)]);
        bug.config.near_side_reach = false;
        let (path, d_reach, v_loop) = bug.silhouette(x, goal, 1.0, false).expect("a boundary vertex");
        assert!(path.last().unwrap().dist(Point2::new(2.0, 0.5)) < 1e-9, "{path:?}");
        assert!((d_reach - 1.0f64.hypot(0.5)).abs() < 1e-9, "{d_reach}");
        assert!(v_loop.dist(Point2::new(2.0, -0.5)) < 1e-9, "{v_loop:?}");
        bug.config.near_side_reach = true;
        let (_, d_reach, v_loop) = bug.silhouette(x, goal, 1.0, false).expect("a boundary vertex");
        assert!((d_reach - 2.0f64.hypot(0.5)).abs() < 1e-9, "{d_reach}");
        assert!(v_loop.dist(Point2::new(2.0, -0.5)) < 1e-9, "{v_loop:?}");
    }

    #[test]
    fn a_goal_ringed_by_rocks_is_reached_within_its_tolerance() {
        // Eight squares of half-side 0.2 m centred 0.4 m around the goal (3, 0) overlap into a
        // closed ring: no path reaches the goal point. With a 1 m tolerance the circle of
        // arrival (0.8 m) lies outside the ring; the nearest point, (2.2, 0), is 2.2 m
        // straight ahead of the rover at the origin.
        let goal = Point2::new(3.0, 0.0);
        let ring: Vec<CObstacle> = (0..8)
            .map(|k| {
                let a = k as f64 * PI / 4.0;
                square(goal.x + 0.4 * a.cos(), goal.y + 0.4 * a.sin(), 0.2)
            })
            .collect();
        let mut bug = bug_with(ring);
        let x = Point2::new(0.0, 0.0);
        let plan = |bug: &RoverBug| {
            let ltg = bug.build_ltg(x, goal);
            bug.search(&ltg, goal, &|_| true)
                .map(|path| path.iter().map(|&i| ltg.nodes[i]).collect::<Vec<_>>())
        };
        assert!(plan(&bug).is_none(), "the goal point is out of reach");
        bug.goal_tolerance = 1.0;
        let path = plan(&bug).expect("a path onto the circle of arrival");
        let end = path.last().unwrap();
        assert!(end.on_goal_circle());
        let length: f64 = path.windows(2).map(|w| w[0].p.dist(w[1].p)).sum();
        assert!((length - 2.2).abs() < 1e-9 && (end.p.dist(goal) - 0.8).abs() < 1e-9, "{path:?}");
        // In open ground the path runs straight toward the goal, onto the circle.
        let mut open = bug_with(vec![]);
        open.goal_tolerance = 1.0;
        let ltg = open.build_ltg(x, goal);
        let path = open.search(&ltg, goal, &|_| true).expect("path");
        assert_eq!(path.len(), 2);
        assert!(ltg.nodes[path[1]].p.dist(Point2::new(2.2, 0.0)) < 1e-9);
        // A small tolerance keeps the hop onto its circle above the shortest subpath.
        open.goal_tolerance = 0.3;
        let ltg = open.build_ltg(Point2::new(2.69, 0.0), goal);
        let circle: Vec<_> = ltg.nodes.iter().filter(|n| n.on_goal_circle()).collect();
        assert!(!circle.is_empty() && circle.iter().all(|n| (n.p.dist(goal) - 0.15).abs() < 1e-9));
    }

    #[test]
    fn from_a_margin_the_rover_may_cross_the_margin_but_not_the_hull() {
        // Hull [1,2]x[-0.5,0.5] grown by 0.6: the rover at (0.6, 0) is 0.4 m from the hull, in
        // the margin. Sideways or back it never crosses the hull; straight on it does.
        let hull = vec![
            Point2::new(1.0, -0.5),
            Point2::new(2.0, -0.5),
            Point2::new(2.0, 0.5),
            Point2::new(1.0, 0.5),
        ];
        let bug = bug_with(vec![CObstacle::from_hull(hull, 0.6, 30f64.to_radians(), 4)]);
        let x = Point2::new(0.6, 0.0);
        assert!(bug.obstacles[0].contains_strict(x));
        assert!(bug.segment_free(x, Point2::new(-1.0, 0.0), x));
        assert!(bug.segment_free(x, Point2::new(0.6, -3.0), x));
        assert!(!bug.segment_free(x, Point2::new(3.0, 0.0), x));
        // The same segments from anywhere but the rover's position are blocked.
        assert!(!bug.segment_free(x, Point2::new(0.6, -3.0), Point2::new(-1.0, 0.0)));
        // Inside the hull itself every way out crosses the hazard.
        let inside = Point2::new(1.5, 0.0);
        assert!(!bug.segment_free(inside, Point2::new(1.5, -3.0), inside));
        assert!(!bug.segment_free(inside, Point2::new(-1.0, 0.0), inside));
    }

    #[test]
    fn from_a_recorded_contact_the_rover_may_not_go_deeper() {
        // A contact at the origin grown by 0.6; the rover 0.3 m east of it backs away freely but
        // may not drive across the contact point.
        let contact = CObstacle::from_hull(vec![Point2::new(0.0, 0.0)], 0.6, 30f64.to_radians(), 0);
        let bug = bug_with(vec![contact]);
        let x = Point2::new(0.3, 0.0);
        assert!(bug.segment_free(x, Point2::new(2.0, 0.0), x));
        assert!(!bug.segment_free(x, Point2::new(-2.0, 0.0), x));
    }

    #[test]
    fn t_g_is_added_only_when_the_line_to_the_goal_is_free() {
        let goal = Point2::new(4.0, 0.0);
        let free = bug_with(vec![square(2.5, 2.0, 0.5)]);
        assert!(free.build_ltg(Point2::new(0.0, 0.0), goal).nodes.iter().any(|n| n.p.dist(goal) < 1e-9));
        let blocked = bug_with(vec![square(2.5, 0.0, 0.5)]);
        assert!(!blocked.build_ltg(Point2::new(0.0, 0.0), goal).nodes.iter().any(|n| n.p.dist(goal) < 1e-9));
    }

    #[test]
    fn truncation_stops_at_the_far_radius_minus_buffer() {
        let bug = bug_with(vec![]);
        let x = Point2::new(0.0, 0.0);
        let cut = bug.truncate(&[x, Point2::new(3.0, 0.0), Point2::new(3.0, 10.0)], x);
        let last = *cut.last().unwrap();
        assert!((last.dist(x) - 4.0).abs() < 1e-9);
        assert!((last.x - 3.0).abs() < 1e-9 && (last.y - 7f64.sqrt()).abs() < 1e-9);
    }

    #[test]
    fn arc_poses_follow_the_circle_of_the_curvature() {
        // Curvature 0.5 (radius 2) driven for half the circumference from the origin heading
        // +x ends 4 m to the left, heading -x; a straight drive ends on the heading line.
        let start = Pose2::new(0.0, 0.0, 0.0);
        let end = *RoverBug::arc_poses(start, PI * 2.0, 0.5).last().unwrap();
        assert!(end.x.abs() < 1e-9 && (end.y - 4.0).abs() < 1e-9, "{end:?}");
        assert!(angle_diff(end.yaw, PI).abs() < 1e-9);
        let back = *RoverBug::arc_poses(Pose2::new(1.0, 1.0, 0.5 * PI), -2.0, 0.0).last().unwrap();
        assert!((back.x - 1.0).abs() < 1e-9 && (back.y + 1.0).abs() < 1e-9, "{back:?}");
    }

    /// A navigator at the origin heading +x whose safety layer holds the given hazard cells.
    fn bug_with_hazards(cells: &[(f64, f64)]) -> RoverBug {
        let mut bug = bug_with(vec![]);
        let geometry = rovernav_core::GridGeometry {
            cols: 60,
            rows: 60,
            resolution: 0.1,
            origin_x: -3.0,
            origin_y: -3.0,
        };
        let mut grid = Grid2::filled(geometry, false);
        for &(x, y) in cells {
            let (c, r) = geometry.cell_of(x, y).unwrap();
            *grid.get_mut(c, r) = true;
        }
        bug.safety_hazard = Some(grid);
        bug
    }

    #[test]
    fn motion_check_follows_the_body_outline() {
        // Default body 0.8 x 0.6 m, margin 0.08 m. A cell 0.45 m to the left of the centre is
        // 0.15 m from the body's side: driving straight keeps it there, a quarter turn brings
        // the front end to 0.05 m of it.
        let start = Pose2::new(0.0, 0.0, 0.0);
        let beside = bug_with_hazards(&[(0.05, 0.45)]);
        assert!(beside.motion_hazards(start, &RoverBug::arc_poses(start, 1.0, 0.0)).is_empty());
        assert!(beside.motion_hazards(start, &RoverBug::arc_poses(start, -1.0, 0.0)).is_empty());
        assert_eq!(beside.motion_hazards(start, &RoverBug::turn_poses(start, 0.5 * PI)).len(), 1);
        // A cell 0.95 m ahead is met driving 1 m forward, not backward.
        let ahead = bug_with_hazards(&[(0.95, 0.05)]);
        assert_eq!(ahead.motion_hazards(start, &RoverBug::arc_poses(start, 1.0, 0.0)).len(), 1);
        assert!(ahead.motion_hazards(start, &RoverBug::arc_poses(start, -1.0, 0.0)).is_empty());
        // A cell under the body where the rover stands never counts.
        let under = bug_with_hazards(&[(0.15, 0.05)]);
        assert!(under.motion_hazards(start, &RoverBug::turn_poses(start, PI)).is_empty());
        assert!(under.motion_hazards(start, &RoverBug::arc_poses(start, 1.0, 0.0)).is_empty());
    }

    #[test]
    fn ground_the_body_just_crossed_clears_hazard_cells_inside_the_inset_outline_only() {
        // Body 0.8 x 0.6 m inset by 0.1 m: 0.3 m ahead and behind, 0.2 m to either side of each
        // recorded pose. The rover drove from x = -1 to x = 1 along y = 0.
        let cells = [(0.05, 0.05), (0.05, 0.35), (1.45, 0.05), (-1.25, 0.05)];
        let mut bug = bug_with_hazards(&cells);
        bug.config.swept_memory = 3.0;
        bug.record_swept(Pose2::new(-1.0, 0.0, 0.0));
        bug.record_swept(Pose2::new(1.0, 0.0, 0.0));
        let mut mask = bug.safety_hazard.clone().unwrap();
        bug.clear_swept(&mut mask);
        let hazard = |x: f64, y: f64| {
            let (c, r) = mask.geometry.cell_of(x, y).unwrap();
            *mask.get(c, r)
        };
        assert!(!hazard(0.05, 0.05), "on the track, under the body");
        assert!(hazard(0.05, 0.35), "beside the inset outline");
        assert!(hazard(1.45, 0.05), "ahead of the body's last pose");
        assert!(!hazard(-1.25, 0.05), "under the body's first pose");
        // Only the latest `swept_memory` of driving counts: 3 m more forgets the start.
        bug.record_swept(Pose2::new(4.0, 0.0, 0.0));
        let mut mask = bug.safety_hazard.clone().unwrap();
        bug.clear_swept(&mut mask);
        let (c, r) = mask.geometry.cell_of(-1.25, 0.05).unwrap();
        assert!(*mask.get(c, r), "forgotten ground keeps its hazard");
    }

    #[test]
    fn growth_radius_replaces_the_circumscribed_radius_and_keeps_the_safety_buffer() {
        let rover = RoverConfig::default();
        let paper = c_obstacle_terrain(&rover, &RoverBugConfig::default());
        // The 0.8 x 0.6 m body's circumscribed radius is 0.5 m.
        assert!((paper.growth() - (0.5 * 0.8f64.hypot(0.6) + 0.1)).abs() < 1e-12);
        let config = RoverBugConfig { growth_radius: 0.3, ..RoverBugConfig::default() };
        assert!((c_obstacle_terrain(&rover, &config).growth() - 0.4).abs() < 1e-12);
    }

    /// A 45-degree mast wedge along +x from the origin, sensed from 1 to 5 m.
    fn wedge_sensed(q: Point2) -> bool {
        (1.0..=5.0).contains(&q.norm()) && q.y.atan2(q.x).abs() <= 22.5f64.to_radians()
    }

    #[test]
    fn a_drive_along_the_wedge_edge_meets_unseen_ground_within_a_metre_and_one_along_its_axis_none() {
        let (half, blind) = ((0.5, 0.3), |q: Point2| q.norm() <= 1.0);
        let axis = RoverBug::arc_poses(Pose2::new(0.0, 0.0, 0.0), 4.0, 0.0);
        assert_eq!(first_unseen_pose(&axis, half, 0.1, blind, wedge_sensed), None);
        // 2.5 degrees inside the edge, the body's left side leaves the wedge as soon as it is
        // out of the blind zone (seed 49 of the default yard met a 0.38 m rock there).
        let edge = RoverBug::arc_poses(Pose2::new(0.0, 0.0, 20f64.to_radians()), 4.0, 0.0);
        let k = first_unseen_pose(&edge, half, 0.1, blind, wedge_sensed).expect("the body leaves the wedge");
        assert!(edge[k].position().norm() < 1.0, "met at {:?}", edge[k]);
    }

    #[test]
    fn a_one_row_gap_in_the_sensed_ground_passes_and_a_two_row_gap_stops_the_body_front() {
        let axis = RoverBug::arc_poses(Pose2::new(0.0, 0.0, 0.0), 3.0, 0.0);
        let column = |q: Point2| (q.x / 0.1).floor() as i64;
        let one = |q: Point2| column(q) != 20;
        assert_eq!(first_unseen_pose(&axis, (0.5, 0.3), 0.1, |_| false, one), None);
        let two = |q: Point2| !matches!(column(q), 20 | 21);
        let k = first_unseen_pose(&axis, (0.5, 0.3), 0.1, |_| false, two).expect("a two-row gap is unseen");
        // The outline's front (0.5 m ahead of the centre) reaches the gap's first cell centres
        // (x = 2.05 m); the poses are 5 cm apart.
        assert!((1.55..=1.6).contains(&axis[k].x), "met at {:?}", axis[k]);
        // Exempt ground (in the navigator: under the body where it stands) never counts.
        assert_eq!(first_unseen_pose(&axis, (0.5, 0.3), 0.1, |q| q.x > 1.9, two), None);
    }

    #[test]
    fn hull_distance_is_the_euclidean_distance_to_the_hull() {
        let o = square(0.0, 0.0, 1.0);
        assert_eq!(hull_distance(&o, Point2::new(0.2, -0.3)), 0.0);
        assert!((hull_distance(&o, Point2::new(3.0, 0.5)) - 2.0).abs() < 1e-9);
        // Off a corner the distance is to the corner, not to the edge's line.
        assert!((hull_distance(&o, Point2::new(4.0, 5.0)) - 5.0).abs() < 1e-9);
        let point = CObstacle::from_hull(vec![Point2::new(1.0, 1.0)], 0.6, 30f64.to_radians(), 0);
        assert!((hull_distance(&point, Point2::new(4.0, 5.0)) - 5.0).abs() < 1e-9);
    }

    #[test]
    fn carried_obstacles_give_way_only_where_the_new_view_sensed_their_ground_again() {
        use rovernav_core::{CameraKind, PointCloud, Pose3, PoseEstimate, Wedge};
        let mut bug = bug_with(vec![]);
        // Flat ground sensed from the origin over x in [0.5, 4], y in [-1, 1].
        let points: Vec<[f32; 3]> = (0..70)
            .flat_map(|i| (0..40).map(move |j| [0.5 + 0.05 * i as f32, -1.0 + 0.05 * j as f32, 0.0]))
            .collect();
        let wedge = Wedge { bearing: 0.0, half_angle: 0.6, min_range: 0.5, max_range: 5.0 };
        let cloud = PointCloud { camera: CameraKind::Mast, origin: [0.0; 3], wedge, points };
        let estimate = PoseEstimate { pose: Pose3::default(), covariance: [[0.0; 3]; 3] };
        bug.view.as_mut().unwrap().evaluator.update(&[cloud], &estimate);
        // Sensed again beyond the blind zone; sensed but within the blind zone (1.2 m); never
        // looked at.
        bug.carried = vec![square(3.0, 0.0, 0.2), square(0.9, 0.0, 0.2), square(3.0, 3.0, 0.2)];
        bug.supersede_carried();
        let centres: Vec<Point2> = bug
            .carried
            .iter()
            .map(|o| o.hull.iter().fold(Point2::new(0.0, 0.0), |a, &p| a.add(p)).scale(0.25))
            .collect();
        assert_eq!(centres.len(), 2, "{centres:?}");
        assert!(centres[0].dist(Point2::new(0.9, 0.0)) < 1e-9);
        assert!(centres[1].dist(Point2::new(3.0, 3.0)) < 1e-9);
    }

    #[test]
    fn a_retreat_retraces_the_trail_and_records_the_dead_end() {
        let mut bug = bug_with(vec![]);
        // An L-shaped trail: 1 m east, then 2 m north to the rover at (1, 2).
        bug.trail = vec![Point2::new(0.0, 0.0), Point2::new(1.0, 0.0), Point2::new(1.0, 1.0)];
        let x = Point2::new(1.0, 2.0);
        assert!(bug.retreat(x, Point2::new(9.0, 9.0)));
        // Back through (1, 1) to (1, 0): 2 m, the first trail point at least 1.5 m back.
        let wp: Vec<Point2> = bug.waypoints.iter().copied().collect();
        assert_eq!(wp, vec![Point2::new(1.0, 1.0), Point2::new(1.0, 0.0)]);
        assert!(bug.reversing);
        assert_eq!(bug.mode, Mode::MotionToGoal);
        assert!(bug.dead_ends.len() == 1 && bug.dead_ends[0].contains_strict(x));
        // The retraced part leaves the trail; its end stays.
        assert_eq!(bug.trail, vec![Point2::new(0.0, 0.0), Point2::new(1.0, 0.0)]);
        // Reversing, the executor drives the rear to the waypoint along an arc.
        bug.waypoints = VecDeque::from(vec![Point2::new(-1.0, 0.1)]);
        let pose = Pose2::new(0.0, 0.0, 0.0);
        let NavCommand::Drive { distance, curvature, .. } = bug.drive_waypoints(pose, Point2::new(9.0, 9.0))
        else {
            panic!("a reverse drive expected");
        };
        assert!(distance < 0.0);
        let end = *RoverBug::arc_poses(pose, distance, curvature).last().unwrap();
        assert!(end.position().dist(Point2::new(-1.0, 0.1)) < 1e-9, "{end:?}");
        // Too short a trail, or the retreats used up: no retreat.
        let mut short = bug_with(vec![]);
        short.trail = vec![Point2::new(0.0, 0.1)];
        assert!(!short.retreat(Point2::new(0.0, 0.0), Point2::new(9.0, 9.0)));
        bug.retreats = bug.config.max_retreats;
        bug.trail = vec![Point2::new(0.0, 0.0), Point2::new(5.0, 0.0)];
        assert!(!bug.retreat(Point2::new(5.0, 3.0), Point2::new(9.0, 9.0)));
    }

    /// Smallest distance of a point from the body outline over the poses (Chebyshev-style, as
    /// the safety check measures it; negative under the body), computed here independently.
    fn body_clearance(rover: &RoverConfig, poses: &[Pose2], q: Point2) -> f64 {
        poses
            .iter()
            .map(|p| {
                let b = p.inverse_transform(q);
                (b.x.abs() - 0.5 * rover.length).max(b.y.abs() - 0.5 * rover.width)
            })
            .fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn seed_14_a_retreat_pinned_against_turning_backs_along_an_arc() {
        // Hazard cells (at their grid centres) 0.45 m either side of the rover's centre: 0.15 m
        // off its sides, but a turn in place of 30 degrees either way brings a corner within
        // the 0.08 m margin.
        let cells = [(0.05, 0.45), (0.05, -0.45)];
        let mut bug = bug_with_hazards(&cells);
        let rover = bug.rover.clone();
        let m = bug.config.body_margin;
        let pose = Pose2::new(0.0, 0.0, 0.0);
        // The retreat's waypoint 2 m away, 30 degrees off the rear.
        let a = 150f64.to_radians();
        let wp = Point2::new(2.0 * a.cos(), 2.0 * a.sin());
        let near = |poses: &[Pose2]| {
            cells
                .iter()
                .map(|&(x, y)| body_clearance(&rover, poses, Point2::new(x, y)))
                .fold(f64::INFINITY, f64::min)
        };
        // Truth: both turns in place toward it pass the cells within the margin.
        let turn = -30f64.to_radians();
        assert!(near(&RoverBug::turn_poses(pose, turn)) < m);
        assert!(near(&RoverBug::turn_poses(pose, turn + 2.0 * PI)) < m);
        bug.reversing = true;
        bug.waypoints = VecDeque::from(vec![wp]);
        let NavCommand::Drive { distance, curvature, .. } = bug.drive_waypoints(pose, Point2::new(9.0, 9.0))
        else {
            panic!("a reverse arc expected, not a refusal");
        };
        assert!(distance < 0.0);
        let poses = RoverBug::arc_poses(pose, distance, curvature);
        let end = *poses.last().unwrap();
        assert!(end.position().dist(wp) < 1e-9, "{end:?}");
        // The rear leads all the way: the end heading points the front away from the start.
        assert!(angle_diff(end.yaw, wp.angle() + PI).abs() < 0.55, "{end:?}");
        assert!(near(&poses) >= m, "the arc sweeps within {} m of a cell", near(&poses));
        // Driving forward, the same refusal stands (only retreats back along an arc).
        bug.reversing = false;
        bug.waypoints = VecDeque::from(vec![Point2::new(2.0 * 30f64.to_radians().cos(), -1.0)]);
        assert!(!matches!(bug.drive_waypoints(pose, Point2::new(9.0, 9.0)), NavCommand::Drive { .. }));
    }

    /// The first waypoint of the best way on from the origin toward `goal`.
    fn first_exit_waypoint(bug: &RoverBug, goal: Point2) -> Point2 {
        let x = Point2::new(0.0, 0.0);
        let path = bug.best_exit(&bug.build_ltg(x, goal), x, goal).expect("a way on");
        path[1]
    }

    #[test]
    fn seed_4_boundary_following_memory_survives_a_restart() {
        // Square [2,3]x[-0.5,0.5] across the line to a goal a little left of the axis: by hand
        // the way on passes the upper corners (path plus remaining distance 6.07 m against
        // 6.12 m by the lower ones). Once boundary following has restarted at both upper
        // corners (escapes from there), a new restart must not lead back to them: the only
        // nodes left are the lower corners.
        let goal = Point2::new(6.0, 0.2);
        let x = Point2::new(0.0, 0.0);
        let mut bug = bug_with(vec![square(2.5, 0.0, 0.5)]);
        assert!(first_exit_waypoint(&bug, goal).y > 0.0);
        bug.start_boundary_following(x, goal);
        bug.remember(Point2::new(2.0, 0.5));
        bug.remember(Point2::new(3.0, 0.5));
        bug.start_boundary_following(x, goal);
        assert_eq!(bug.visited, vec![x], "a restart begins a new segment");
        let wp = first_exit_waypoint(&bug, goal);
        assert!(wp.y < 0.0 && (wp.x - 2.0).abs() < 1e-6, "{wp:?}");
        // With the lower corners remembered too, every way on is near a restart point: one
        // near them still beats halting.
        bug.remember(Point2::new(2.0, -0.5));
        bug.remember(Point2::new(3.0, -0.5));
        let ltg = bug.build_ltg(x, goal);
        assert!(bug.best_exit_avoiding(&ltg, x, goal, &bug.been).is_none());
        assert!(bug.best_exit(&ltg, x, goal).is_some());
        // Motion to goal from the start plans round the upper corners again: not progress
        // past the restart points, which stay remembered.
        let remembered = bug.been.len();
        assert!(bug.motion_to_goal(x, goal));
        assert_eq!(bug.been.len(), remembered);
        // From beyond the square its subpath ends nearer the goal than every restart point:
        // they are forgotten, and the upper side is open again.
        assert!(bug.motion_to_goal(Point2::new(4.0, 0.0), goal));
        assert!(bug.been.is_empty());
        bug.visited.clear();
        assert!(first_exit_waypoint(&bug, goal).y > 0.0);
    }

    #[test]
    fn seed_10_boundary_following_fallback_turned_away_from_the_goal() {
        // Square [2,3]x[-0.5,0.5] across the line to the goal (6,0), and a square
        // [1.2,1.8]x[1.7,2.3] off to the left. By hand, the nodes joined to the rover are the
        // near corners (2,±0.5) at ±14.0 degrees from the goal direction and the left square's
        // silhouette corners (1.8,1.7) at 43.4 and (1.2,2.3) at 62.4 degrees. Counter-clockwise
        // the fallback hugs the blocking square at (2,0.5); turning as far as possible it took
        // (1.2,2.3), away from the goal.
        let goal = Point2::new(6.0, 0.0);
        let x = Point2::new(0.0, 0.0);
        let mut bug = bug_with(vec![corner_square(2.5, 0.0, 0.5), corner_square(1.5, 2.0, 0.3)]);
        let step = |bug: &RoverBug, s: f64| {
            bug.fallback_step(&bug.build_ltg(x, goal), x, goal, s).expect("a step")[1]
        };
        let near = |a: Point2, b: Point2| a.dist(b) < 1e-6;
        assert!(near(step(&bug, 1.0), Point2::new(2.0, 0.5)), "{:?}", step(&bug, 1.0));
        assert!(near(step(&bug, -1.0), Point2::new(2.0, -0.5)), "{:?}", step(&bug, -1.0));
        // With that corner visited, the next one round in the positive sense.
        bug.visited = vec![x, Point2::new(2.0, 0.5)];
        assert!(near(step(&bug, 1.0), Point2::new(1.8, 1.7)), "{:?}", step(&bug, 1.0));
        // Nothing left on the positive side: a node on the other.
        bug.visited.extend([Point2::new(1.8, 1.7), Point2::new(1.2, 2.3)]);
        assert!(near(step(&bug, 1.0), Point2::new(2.0, -0.5)), "{:?}", step(&bug, 1.0));
    }

    #[test]
    fn seed_19_far_from_d_reach_the_blocked_step_heads_for_the_goal() {
        // Square [2,3]x[-0.5,0.5] across the line to the goal (6,-0.2). By hand, the way on by
        // the lower corners (path plus remaining distance 2.062 + 1 + 3.015 = 6.077 m) beats
        // the upper ones (6.142 m); counter-clockwise, the wall follower's step is the upper
        // corner (2,0.5), the first past the goal direction.
        let goal = Point2::new(6.0, -0.2);
        let x = Point2::new(0.0, 0.0);
        let scene = || bug_with(vec![corner_square(2.5, 0.0, 0.5)]);
        let bug = scene();
        let d = x.dist(goal);
        let ltg = bug.build_ltg(x, goal);
        let step = |d_reach: f64| bug.blocked_step(&ltg, x, goal, 1.0, d_reach).expect("a step")[1];
        let near = |a: Point2, b: Point2| a.dist(b) < 1e-6;
        // Within the limit of d_reach: along the boundary.
        assert!(near(step(d - 1.0), Point2::new(2.0, 0.5)), "{:?}", step(d - 1.0));
        // Led farther than the limit (2 m) from it: toward the goal.
        assert!(near(step(d - 2.5), Point2::new(2.0, -0.5)), "{:?}", step(d - 2.5));
        // Disabled, along the boundary however far.
        let mut off = scene();
        off.config.wander_limit = 0.0;
        assert!(near(
            off.blocked_step(&ltg, x, goal, 1.0, d - 2.5).expect("a step")[1],
            Point2::new(2.0, 0.5)
        ));
    }

    #[test]
    fn a_loop_proves_unreachable_only_around_the_goal() {
        let goal = Point2::new(0.0, 0.0);
        let circle = |c: Point2, r: f64, turn: f64| -> Vec<Point2> {
            (0..=24)
                .map(|k| k as f64 * turn / 24.0)
                .map(|t| c.add(Point2::new(t.cos(), t.sin()).scale(r)))
                .collect()
        };
        let mut bug = bug_with(vec![]);
        // 330 degrees around the goal.
        bug.visited = circle(goal, 3.0, 330f64.to_radians());
        assert!(bug.encircles_goal(goal, None));
        // Half a turn around it is no loop yet.
        bug.visited = circle(goal, 3.0, PI);
        assert!(!bug.encircles_goal(goal, None));
        // A full loop around a point 5 m away leaves the goal outside.
        bug.visited = circle(Point2::new(5.0, 0.0), 2.0, 2.0 * PI);
        assert!(!bug.encircles_goal(goal, None));
    }
}
