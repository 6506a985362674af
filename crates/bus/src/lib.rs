//! rovernav's message bus: typed topics over a transport that moves serialized messages by
//! topic name (paper 004 section 2: JAUS components "collaborate by exchanging well-defined
//! messages").
//!
//! - [`Topic`]: a topic name bound to its message type (any serde type; [`Topic::schema`] for one with a JSON Schema).
//! - [`schema`]: the message types' derived JSON Schemas and a checker for them.
//! - [`Transport`]: the byte-level seam a networked transport (zenoh) implements.
//! - [`InProcessTransport`]: the deterministic in-process transport.
//! - [`Bus`]: the typed front the components use; in process it skips serialization, over a
//!   transport it encodes JSON, and both deliver the same messages in the same order.
//!
//! Names follow ROS conventions (`/layer/what`); message frames and units follow REP 103
//! (x forward, y left, z up; metres, radians). The crate knows nothing of rovernav's types, so
//! an adapter (a telemetry recorder, a zenoh bridge) can depend on it alone.

pub mod bus;
pub mod schema;
pub mod topic;
pub mod transport;

pub use bus::{Bus, Record, Subscriber, TapId};
pub use topic::{Message, Topic, check_topic_name, decode, encode};
pub use transport::{BusError, InProcessTransport, Sample, SubscriptionId, TopicFilter, Transport};
