//! The operator command language: plain-text commands in the spirit of SR2's operator interface
//! (paper 001 section 6), typed at `rovernav run --interactive` or sent over the bus.
//!
//! Units on the wire are the operator's: metres and degrees; the typed commands carry metres and
//! radians (ROS conventions: x east/forward, y north/left, angles counter-clockwise).

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
        /// The command asked about.
        topic: Option<String>,
    },
}
