//! The operator console: a run's telemetry served live over WebSocket, to the browser console
//! (papers 001 and 004: SR2's engineering and mission panels, MRPTA's OCU) and to Foxglove.
//!
//! - [`hub::Hub`]: every topic and message the run's telemetry log writes, fanned out to any
//!   number of watchers without ever making the run wait for one.
//! - [`server`]: the browser console (`rovernav serve`): the page, its WebSocket
//!   ([`server_ws`], [`server_history`] for late joiners), the access token ([`auth`]), command authority ([`operator`]), the
//!   mission run behind it ([`live`]) and the replay of a finished run's log ([`replay`]).

#![warn(missing_docs)]

pub mod auth;
pub mod foxglove;
pub mod hub;
pub mod live;
pub mod operator;
pub mod replay;
pub mod server;
pub mod server_history;
pub mod server_ws;

pub use hub::{Channel, Event, Hub, Message};
