//! AutoPlace (paper 003, Hayati et al., section 4): autonomous instrument placement with a
//! 5-DOF IDD-like arm, a terrain octree that knows what the cameras have not seen, target
//! selection by surface normal and roughness, and collision-checked trajectories.
//!
//! Points and cameras in, a placement or a refusal out: no files, no middleware.
//! - [`geometry`]: capsules, boxes and their distances.
//! - [`arm`]: the arm's kinematics, limits, stowed pose, self- and rover collision.
//! - [`octree`]: occupied / free / unknown cells, free only where a line of sight verified it.
//! - [`targets`]: the closest sensed point, candidates around it, normal and roughness.
//! - [`feasibility`]: via-points from the stowed pose, swept-volume checks against the octree.
//! - [`autoplace`]: the whole decision: placed, or refused with its reason.
//! - [`sensing`]: a rectified stereo pair of images into body-frame points (the only input).
//! - [`motion`]: a placement in time: the joint states out, the dwell, and back.
//! - [`execution`]: a plan executed on a true terrain (scoring only, never the autonomy).

pub mod arm;
pub mod autoplace;
pub mod execution;
pub mod feasibility;
pub mod geometry;
pub mod motion;
pub mod octree;
pub mod sensing;
pub mod targets;

pub use arm::{Arm, ArmGeometry, Joints};
pub use autoplace::{AutoPlaceParams, Outcome, Reason, autoplace, place_with, terrain_model};
pub use octree::{Cell, Octree, OctreeParams, View};
