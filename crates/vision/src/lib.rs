//! Cameras and images: the camera models NASA rovers use (CAHV, CAHVOR, CAHVORE), image types
//! and their decoding, stereo rectification and stereo correlation.
//!
//! Like the map crates, this crate knows no middleware: images and camera models in, images,
//! disparities and point clouds out. Frames follow the rest of rovernav (REP 103); a camera
//! model lives in whatever frame its vectors are expressed in (the rover body frame for a
//! mounted camera, the world frame once moved by a pose).

pub mod camera;
pub mod codec;
pub mod descent;
pub mod image;
pub mod lander;
pub mod rectify;
pub mod rig;
pub mod stereo;
pub mod tracking;

pub use camera::{Cahv, CameraModel, Ray};
