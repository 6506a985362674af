//! rovernav's message bus over zenoh, so the rover stack, the simulator and a ground station can
//! run as separate processes on separate hosts.
//!
//! - [`ZenohConfig`], [`Endpoint`], [`Mode`]: how a process joins the network (explicit TCP
//!   endpoints, multicast scouting off); always built, so CLIs can check their arguments.
//! - `ZenohTransport` (cargo feature `zenoh`, off by default because zenoh adds about 240
//!   crates): a [`rovernav_bus::Transport`] that maps topic `/platform/frame` to zenoh key
//!   `platform/frame`, plus the blocking helpers a lockstep exchange between processes needs.

pub mod config;
#[cfg(feature = "zenoh")]
pub mod transport;

pub use config::{Endpoint, Mode, ZenohConfig, ZenohConfigError, filter_key, key_topic, topic_key};
#[cfg(feature = "zenoh")]
pub use transport::ZenohTransport;
