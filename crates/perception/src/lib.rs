//! rovernav perception layer: range data into terrain assessments.
//!
//! * [`elevation`]: range points into an elevation map (paper 002 section 3.1).
//! * [`footprint`]: the step/slope hazard model over the rover footprint (paper 000 section 2).
//! * [`hull`] and [`cobstacle`]: convex hulls of obstacle regions grown into labelled
//!   C-obstacles for RoverBug (paper 000 section 2).
//! * [`traversability`]: MRPTA slope/roughness/neighbourhood traversability 1..14 (paper 004
//!   section 3.3).
//! * [`goodness`]: GESTALT goodness 0..1 (paper 003 section 2).
//! * [`evaluator`]: the MRPTA terrain evaluator on a robot-centred toroidal grid, with requests
//!   for more data when the point density in front of the rover is low (paper 004 section 3.3).
//! * [`evaluation`]: figures of merit against ground truth for `rovernav eval terrain`.
//!
//! Points are placed in the world with the autonomy's pose estimate, never with ground truth.

pub mod cell;
pub mod cobstacle;
pub mod config;
pub mod elevation;
pub mod error;
pub mod evaluation;
pub mod evaluator;
pub mod footprint;
pub mod goodness;
pub mod hull;
pub mod traversability;

pub use cell::{CellStats, PlaneFit};
pub use cobstacle::{
    CObstacle, SensedWedge, VertexLabel, build_c_obstacles, grow_convex_polygon, label_c_obstacles,
    obstacle_regions, segment_intersection, segments_intersect,
};
pub use config::{DensityConfig, HazardHeight, RangeNoise, SensorNoise, TerrainConfig};
pub use elevation::{ElevationMap, world_points};
pub use error::PerceptionError;
pub use evaluation::{TerrainEvalFigures, TrueRock, evaluate_terrain};
pub use evaluator::{MoreDataRequest, TerrainEvaluator, TerrainLayers, assess_cells};
pub use footprint::GroundRefit;
pub use hull::convex_hull;
