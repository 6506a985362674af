//! Telemetry: every topic of a run logged to an MCAP file (the log format of ROS 2 and
//! Foxglove), and the reader that rebuilds the run from the log alone.
//!
//! - [`TelemetryWriter`]: a generic MCAP writer (JSON messages with JSON Schemas derived from
//!   the message types, zstd chunks,
//!   a flush policy so a killed process loses at most about a second).
//! - [`foxglove`]: Foxglove's well-known schemas (frames, grids, scenes, log, images) so that
//!   Foxglove shows a run natively.
//! - [`TelemetryRecorder`]: a `RunObserver` that logs the world, settings, sensor frames,
//!   commands, plans, estimates, truth, hazard contacts, overlays and the report
//!   ([`messages::topics`]).
//! - [`read_log`]: reads a log linearly, tolerating a truncated file, and
//!   [`LoggedRun::replay`] rebuilds the world, trace and report from it.
//!
//! Log and publish times are simulated time in nanoseconds, so a seeded run logs the same
//! timestamps every time; wall time appears only in `/executive/cycle` and the report.

#![warn(missing_docs)]

pub mod base64;
pub mod foxglove;
pub mod messages;
pub mod reader;
pub mod recorder;
pub mod writer;

/// The MCAP library the log is written with, for callers that want its raw records or its
/// reader (the tests read logs with it, independently of [`read_log`]).
pub use mcap;
pub use messages::topic_table;
pub use reader::{LogEnd, LoggedRun, ReplayedRun, bounded_messages, parse_log, read_log};
pub use recorder::TelemetryRecorder;
/// The derived JSON Schemas and their checker (the bus crate's, shared by the log).
pub use rovernav_bus::schema;
pub use writer::{FlushPolicy, LiveSink, LogStats, TelemetryError, TelemetryWriter};
