//! rovernav's simulated platform: the world truth and the sensors the autonomy sees.
//!
//! A rover at Rocky 7 / SR2 scale (papers 000 and 001) drives on a 2.5D terrain with pitch and
//! roll from wheel contact, slope-dependent wheel slip and hazard detection ([`vehicle`]); it
//! images the terrain with stereo wedges and a nodding LIDAR by exact ray casting
//! ([`raycast`]), and reports proximity thresholds, compass, gyro, inclinometer, sun sensor and
//! wheel encoders with documented noise ([`sensors`], papers 001 and 004). Everything is
//! deterministic for a seed. [`true_hazard_grid`] gives the evaluation's ground-truth hazard map.

pub mod hazard;
pub mod lander_station;
pub mod navcam;
pub mod power;
pub mod raycast;
pub mod render;
pub mod scenes;
pub mod sensors;
pub mod simulator;
pub mod stereo_range;
pub mod terrain_window;
pub mod vehicle;

pub use hazard::true_hazard_grid;
pub use lander_station::LanderStation;
pub use navcam::NavcamImaging;
pub use power::{PowerConfig, PowerModel};
pub use raycast::{HeightField, RayHit};
pub use sensors::{LidarModel, ProximityModel, RangeImagerModel, SensorModel};
pub use simulator::{Fault, Simulator};
pub use stereo_range::{RangeSource, StereoImaging};
pub use terrain_window::TerrainWindow;
pub use vehicle::{Hazard, SlipModel, VehicleGeometry};
