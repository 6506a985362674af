//! The operator console: a run's telemetry served live over WebSocket, to the browser console
//! (papers 001 and 004: SR2's engineering and mission panels, MRPTA's OCU) and to Foxglove.
//!
//! - [`hub::Hub`]: every topic and message the run's telemetry log writes, fanned out to any
//!   number of watchers without ever making the run wait for one.

#![warn(missing_docs)]

pub mod hub;

pub use hub::{Channel, Event, Hub, Message};
