//! Core types shared by every rovernav layer: geometry, grids, sensor messages, rover
//! configuration and the navigator interface.
//!
//! Frames follow ROS conventions (REP 103): the world frame is x east, y north, z up; the rover
//! body frame is x forward, y left, z up; angles in radians, lengths in metres. This crate does no
//! I/O and knows no middleware, so every algorithm crate can use it; its message types derive
//! `Serialize`, `Deserialize` and `schemars::JsonSchema` once, and the bus and the MCAP log carry
//! them as they are ([`wire`] says how a few fields travel).

pub mod geometry;
pub mod grid;
pub mod limits;
pub mod nav;
pub mod rover;
pub mod sensors;
pub mod wire;

pub use geometry::{Point2, Pose2, Pose3, angle_diff, wrap_angle};
pub use grid::{Grid2, GridGeometry};
pub use nav::{
    DriveGuard, Goal, Localizer, LocalizerStats, NavCommand, NavInput, Navigator, NavigatorStats, Outcome,
    Overlay, OverlayKind, PoseEstimate, SenseRequest,
};
pub use rover::RoverConfig;
pub use sensors::{
    CameraImage, CameraKind, ImuSample, LanderSighting, OdometrySample, PointCloud, PowerReading,
    ProximityReading, RangeNoise, SensorFrame, SensorNoise, Wedge,
};

/// The folder holding rovernav's real data sets (`ROVERNAV_DATA`, default `../shared/data`).
///
/// The default is tried relative to the working directory (the project root, for the command
/// line) and then relative to this workspace's checkout (for `cargo test`, which runs in each
/// crate's folder).
pub fn data_dir() -> std::path::PathBuf {
    if let Some(dir) = std::env::var_os("ROVERNAV_DATA") {
        return dir.into();
    }
    let cwd_default = std::path::PathBuf::from("../shared/data");
    if cwd_default.is_dir() {
        return cwd_default;
    }
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data")
}

/// The path of a data file, or `None` after printing one line saying why the caller skips.
pub fn data_file_or_skip(relative: &str) -> Option<std::path::PathBuf> {
    let p = data_dir().join(relative);
    if p.is_file() {
        return Some(p);
    }
    assert!(
        std::env::var("ROVERNAV_REQUIRE_DATA").as_deref() != Ok("1"),
        "data file {} missing and ROVERNAV_REQUIRE_DATA=1",
        p.display()
    );
    eprintln!("skipping: data file {} not found (set ROVERNAV_DATA)", p.display());
    None
}
