//! RoverBug's parameters, grouped: the paper's own quantities and the model behind its
//! C-obstacles ([`PaperParams`]), the budgets after which it asks for help ([`Budgets`]), the
//! safety layer ([`SafetyParams`]) and the recovery behaviours ([`RecoveryParams`]). Each
//! parameter is written once, in [`param_group!`]: its field, default, mission-file name, unit
//! (which fixes its valid range) and doc. A mission sets them by name in `[navigator_params]`;
//! a misspelt name or an out-of-range value is an error naming both (see [`crate::params`]).

use crate::params::{Field, Param, Unit};
use crate::terrain_model::{HAZARD_MARGIN, T_GRID_RESOLUTION, TOP_HAZARD_MARGIN};
use rovernav_core::RoverConfig;
use rovernav_perception::{GroundRefit, HazardHeight, TerrainConfig};

/// Declares a group of parameters: the struct with each field's doc, its [`Default`], and the
/// group's rows of the mission table, each parameter written once as
/// `field: type = default, "mission_name", Unit, FieldKind, "one-line doc";`.
macro_rules! param_group {
    (
        $(#[$gmeta:meta])*
        $Group:ident in $group:ident {
            $(
                $(#[$meta:meta])*
                $field:ident: $ty:ty = $default:expr, $name:literal, $unit:ident, $kind:ident, $short:literal;
            )*
        }
    ) => {
        $(#[$gmeta])*
        #[derive(Clone, Debug)]
        pub struct $Group {
            $(
                $(#[$meta])*
                pub $field: $ty,
            )*
        }

        impl Default for $Group {
            fn default() -> Self {
                Self { $($field: $default,)* }
            }
        }

        impl $Group {
            /// The group's rows of the mission table.
            fn params() -> Vec<Param<RoverBugConfig>> {
                vec![$(Param {
                    name: $name,
                    doc: $short,
                    unit: Unit::$unit,
                    field: |c| Field::$kind(&mut c.$group.$field),
                },)*]
            }
        }
    };
}

param_group! {
    /// Paper 000 section 2's quantities, and the step/slope model behind the C-obstacles.
    PaperParams in paper {
        /// Empirical safety buffer added to the rover radius when growing C-obstacles (m; paper
        /// 000 section 2).
        safety_buffer: f64 = 0.1, "safety_buffer_m", Clearance, Real,
            "safety buffer added to the rover radius when growing C-obstacles";
        /// Fraction of the rover's belly clearance at which the step model behind the
        /// C-obstacles (on cell means) marks a hazard. At [`HAZARD_MARGIN`] (0.8), the usual
        /// margin for cell means, it flags window steps over hummocky relief, and grown by the
        /// rover radius plus the safety buffer those false C-obstacles close the gaps of a rock
        /// field; the safety layer still checks every motion against the body outline
        /// (docs/navigators/roverbug.md: 0.9 against 0.8 on seeds 1..160).
        clearance_margin: f64 = 0.9, "clearance_margin", Fraction, Real,
            "fraction of the belly clearance at which the C-obstacles' step model (cell means) marks a hazard";
        /// Buffer left inside the wedge's far radius when a path is truncated (m; paper 000
        /// section 2.1: the rover should not begin the next step right behind an unsensed
        /// obstacle).
        range_buffer: f64 = 1.0, "range_buffer_m", Metres, Real,
            "buffer left inside the wedge's far radius when a subpath is cut";
        /// Heading error above which the rover turns in place before driving (rad): the path
        /// execution of section 3 drives arcs only for small heading errors (20 deg measured
        /// more contacts: wider arcs swing the body off the subpath).
        turn_threshold: f64 = 10f64.to_radians(), "turn_threshold_deg", Degrees, Real,
            "heading error above which the rover turns in place before driving";
        /// Angular margin inside the conglomerate wedge's bounding rays for "interior" (rad;
        /// section 2.2's int(W)).
        interior_angle: f64 = 4f64.to_radians(), "interior_angle_deg", Degrees, Real,
            "angular margin inside the conglomerate wedge's bounding rays for \"interior\"";
        /// Distance from the sensing position within which the ground counts as visible (m): the
        /// rover's own footprint, seen from the previous position (the mast is blind within
        /// about a metre, section 2.2).
        near_visible: f64 = 1.0, "near_visible_m", Metres, Real,
            "distance from the sensing position within which the ground counts as visible";
        /// Carried C-obstacles whose hulls come within `near_visible` plus this margin of the new
        /// sensing position always stay (m): the mast cannot see that ground. Farther ones stay
        /// only where the new view has not sensed their ground again.
        carry_margin: f64 = 0.2, "carry_margin_m", Metres, Real,
            "margin beyond near_visible_m within which the last view's C-obstacles always stay";
    }
}

param_group! {
    /// The budgets after which RoverBug asks for help instead of going on.
    Budgets in budgets {
        /// Steps (sense-plan-act cycles) before asking for help: a traverse that has not arrived
        /// by then is lost in clutter, and asking beats the mission's time limit.
        max_steps: u32 = 200, "max_steps", Count, U32,
            "sense-plan-act steps before asking for help";
        /// Wedges sensed in all before asking for help (the paper's scarce resource: every wedge
        /// costs capture and stereo time).
        max_wedges: u64 = 300, "max_wedges", Count, U64,
            "wedges sensed in all before asking for help";
        /// Hazard contacts recorded around one place (within 0.6 m) before asking for help:
        /// fault protection would stop the rover at the third body contact anyway.
        max_contacts_here: usize = 6, "max_contacts_here", Count, Usize,
            "hazard contacts recorded around one place before asking for help";
        /// Motions refused by the safety check at one place (within 0.3 m) before the escape,
        /// the retreat or a call for help.
        max_refusals_here: u32 = 4, "max_refusals_here", Count, U32,
            "motions refused by the safety check at one place before asking for help";
    }
}

param_group! {
    /// The safety layer: top heights kept across steps, checked against every motion's swept
    /// body outline before it is commanded (see the `safety` and `unseen` modules).
    SafetyParams in safety {
        /// Fraction of the rover's belly clearance at which the safety layer (top heights) marks
        /// a step hazard: lower keeps the body farther from rocks near the clearance at the cost
        /// of arrivals (measured: 0.8 against 0.9 on seeds 1..160, fewer arrivals).
        safety_clearance_margin: f64 = TOP_HAZARD_MARGIN, "safety_clearance_margin", Fraction, Real,
            "fraction of the belly clearance at which the safety layer (cell tops) marks a step hazard";
        /// Clearance kept between the body outline and a safety-layer hazard cell when a motion
        /// is checked before it is commanded (m): room for the sensed map's error (elevation
        /// RMSE about 0.02 m) and the drift between steps (0.12 m measured fewer arrivals).
        body_margin: f64 = 0.08, "body_margin_m", Clearance, Real,
            "clearance kept between the body outline and a safety-layer hazard cell";
        /// Added to half the rover's width to grow the safety layer's own C-obstacles (m): the
        /// body margin plus the swing of the body's corners on arcs that start up to the turn
        /// threshold off the chord.
        top_allowance: f64 = 0.15, "top_allowance_m", Clearance, Real,
            "added to half the rover's width to grow the safety layer's own C-obstacles";
        /// Fraction of the safety layer's step limit by which a hazard cell's own points must
        /// stand out from the ground around it to count (see `confirm_hazards`): sparsely sensed
        /// windows mark ground-level cells that would pin the rover for nothing.
        confirm_fraction: f64 = 0.3, "confirm_fraction", Fraction, Real,
            "fraction of the safety layer's step limit a hazard cell must stand out from the ground around it";
        /// Looks at unseen ground from one place before a forward drive over it counts as
        /// refused (0 disables the check that the ground under the body of every forward drive
        /// has been sensed; see the `unseen` module for what it measured).
        unseen_looks: u32 = 2, "unseen_looks", Count, U32,
            "looks at unseen ground under a forward drive's body before the drive is refused (0: drives are not checked for unseen ground)";
    }
}

param_group! {
    /// The recovery behaviours that replace the paper's halts and aborts (see the `recovery`
    /// module).
    RecoveryParams in recovery {
        /// Sensing positions (this one included) at which the C-obstacles stay grown by the
        /// rover radius alone after a squeeze: motion-to-goal found a way on only without the
        /// safety buffer (0 disables squeezing).
        squeeze_views: u32 = 2, "squeeze_views", Count, U32,
            "sensing positions that keep C-obstacles without the safety buffer after a squeeze (0 disables)";
        /// Straight drive out of a position where safety-layer hazards forbid a full turn in
        /// place and planning gave up (m).
        escape_distance: f64 = 0.4, "escape_distance_m", Metres, Real,
            "straight drive out of a place where safety-layer hazards forbid a full turn";
        /// Distance driven back along the recorded trail when planning finds no way on (m): far
        /// enough that the next view sees the dead end from outside its C-obstacles' margins.
        retreat_distance: f64 = 1.5, "retreat_distance_m", Metres, Real,
            "distance driven back along the trail when planning finds no way on";
        /// Retreats from dead ends before planning's give-up stands: each records a dead end, and
        /// unbounded they would shuttle until the time limit.
        max_retreats: u32 = 5, "max_retreats", Count, U32,
            "retreats from dead ends before planning's give-up stands";
        /// How much farther from the goal than d_reach (m) boundary following may have led
        /// before its step, when the gaze has turned all around without a silhouette vertex, is
        /// the TangentBug way on (path length plus distance to the goal) rather than the wall
        /// follower's (0 disables: always the wall follower's; 1 m and 4 m measured no better).
        wander_limit: f64 = 2.0, "wander_limit_m", Metres, Real,
            "how much farther from the goal than d_reach boundary following may lead before its blocked step is the way on toward the goal rather than along the boundary (0 disables)";
    }
}

/// Tunable parameters of RoverBug, by group.
#[derive(Clone, Debug, Default)]
pub struct RoverBugConfig {
    /// The paper's quantities and the C-obstacles' step model.
    pub paper: PaperParams,
    /// When to ask for help.
    pub budgets: Budgets,
    /// The safety layer.
    pub safety: SafetyParams,
    /// The recovery behaviours.
    pub recovery: RecoveryParams,
}

impl RoverBugConfig {
    /// The parameters a mission file may set (`[navigator_params]`).
    pub fn params() -> Vec<Param<Self>> {
        let mut out = PaperParams::params();
        out.extend(Budgets::params());
        out.extend(SafetyParams::params());
        out.extend(RecoveryParams::params());
        out
    }
}

/// The step/slope model behind RoverBug's C-obstacles: cell means over one sensing position's
/// wedges, with hazard limits below the rover's true limits, grown by the rover's circumscribed
/// radius (the paper's disc rover) plus the safety buffer. A hazardous window's ground is
/// refitted robustly and low cells are pits only in their own window
/// ([`GroundRefit::RobustOwnPits`]): beside a rock wider than the window the whole-window
/// refit read the open ground as a pit, widening the C-obstacle by up to a metre (seeds
/// 161..320: 148 / 3 / 150 clean / with contacts / reached against 134 / 5 / 137).
pub fn c_obstacle_terrain(rover: &RoverConfig, config: &RoverBugConfig) -> TerrainConfig {
    let paper = &config.paper;
    TerrainConfig {
        cols: 81,
        rows: 81,
        clearance: rover.clearance * paper.clearance_margin,
        max_tilt: rover.max_tilt * HAZARD_MARGIN,
        safety_buffer: paper.safety_buffer,
        ground: GroundRefit::RobustOwnPits,
        ..TerrainConfig::for_rover(rover)
    }
}

/// The safety layer's model, kept across steps: top heights, which do not lose a small rock's
/// height as cell means do, on the grid navigators' finer cells, with the robust ground refit
/// ([`GroundRefit::Robust`]: it halves the layer's false hazards; with pits only in their own
/// window as well, seeds 1..20 gave 16 / 1 / 16 against 20 / 0 / 20).
pub fn safety_terrain(rover: &RoverConfig, config: &RoverBugConfig) -> TerrainConfig {
    TerrainConfig {
        cols: 121,
        rows: 121,
        resolution: T_GRID_RESOLUTION,
        hazard_height: HazardHeight::Top,
        clearance: rover.clearance * config.safety.safety_clearance_margin,
        ground: GroundRefit::Robust,
        ..c_obstacle_terrain(rover, config)
    }
}
