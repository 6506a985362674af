//! The transport interface: moving serialized messages by topic name.
//!
//! A [`Transport`] knows nothing of message types: it carries opaque payloads (the bus encodes
//! them as JSON) under ROS-style topic names (`/platform/frame`). The in-process
//! [`InProcessTransport`] delivers synchronously and in publish order, which the lockstep
//! component runtime relies on; a networked transport (zenoh) implements the same four methods,
//! mapping topic names to its own key space (zenoh key expressions drop the leading `/`) and the
//! [`TopicFilter::All`] filter to its `**` wildcard.

use std::collections::VecDeque;

/// Why a bus operation failed.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum BusError {
    /// A topic name that is not `/`-separated lower-case words.
    #[error("bad topic name `{name}`: {why}")]
    BadTopic {
        /// The name given.
        name: String,
        /// What is wrong with it.
        why: &'static str,
    },
    /// A payload could not be encoded or decoded as the topic's type.
    #[error("topic `{topic}`: cannot {action} `{type_name}`: {message}")]
    Codec {
        /// Topic name.
        topic: String,
        /// `encode` or `decode`.
        action: &'static str,
        /// The message type.
        type_name: String,
        /// What the codec said.
        message: String,
    },
    /// A subscription handle this transport never issued.
    #[error("unknown subscription {0}")]
    UnknownSubscription(u64),
    /// The transport itself failed (connection lost, session closed...).
    #[error("transport: {0}")]
    Transport(String),
}

/// Which topics a subscription receives.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum TopicFilter {
    /// One topic, by exact name.
    Exact(String),
    /// Every topic (telemetry recorders, bridges).
    All,
}

impl TopicFilter {
    /// Whether a topic name passes the filter.
    pub fn matches(&self, topic: &str) -> bool {
        match self {
            TopicFilter::Exact(name) => name == topic,
            TopicFilter::All => true,
        }
    }
}

/// A handle to one subscription of a transport.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct SubscriptionId(pub u64);

/// One serialized message as a transport delivers it.
#[derive(Clone, Debug, PartialEq)]
pub struct Sample {
    /// Topic name.
    pub topic: String,
    /// Serialized message (JSON for the bus's codec).
    pub payload: Vec<u8>,
}

/// Moves serialized messages by topic name (the seam a networked transport such as zenoh fills).
///
/// Contract, which [`InProcessTransport`] meets and the bus's tests check: a sample published
/// after `subscribe` returns is delivered to that subscription exactly once, samples of one
/// publisher arrive in publish order, and `receive` never blocks (it drains what has arrived).
pub trait Transport: Send {
    /// Publishes one serialized message on a topic.
    fn publish(&mut self, topic: &str, payload: &[u8]) -> Result<(), BusError>;
    /// Starts receiving the topics a filter selects; messages published earlier are not replayed.
    fn subscribe(&mut self, filter: TopicFilter) -> Result<SubscriptionId, BusError>;
    /// Takes every message that has arrived for a subscription, oldest first.
    fn receive(&mut self, subscription: SubscriptionId) -> Result<Vec<Sample>, BusError>;
    /// Whether a message published now is receivable before `publish` returns; the lockstep
    /// component runtime needs this (a networked transport answers false and is used to bridge
    /// or record rather than to step components).
    fn is_synchronous(&self) -> bool;
}

/// The deterministic in-process transport: one FIFO queue per subscription, filled at publish.
#[derive(Debug, Default)]
pub struct InProcessTransport {
    subscriptions: Vec<(TopicFilter, VecDeque<Sample>)>,
}

impl InProcessTransport {
    /// An empty transport.
    pub fn new() -> Self {
        Self::default()
    }
}

impl Transport for InProcessTransport {
    fn publish(&mut self, topic: &str, payload: &[u8]) -> Result<(), BusError> {
        crate::topic::check_topic_name(topic)?;
        for (filter, queue) in &mut self.subscriptions {
            if filter.matches(topic) {
                queue.push_back(Sample { topic: topic.to_string(), payload: payload.to_vec() });
            }
        }
        Ok(())
    }

    fn subscribe(&mut self, filter: TopicFilter) -> Result<SubscriptionId, BusError> {
        if let TopicFilter::Exact(name) = &filter {
            crate::topic::check_topic_name(name)?;
        }
        self.subscriptions.push((filter, VecDeque::new()));
        Ok(SubscriptionId(self.subscriptions.len() as u64 - 1))
    }

    fn receive(&mut self, subscription: SubscriptionId) -> Result<Vec<Sample>, BusError> {
        let (_, queue) = self
            .subscriptions
            .get_mut(subscription.0 as usize)
            .ok_or(BusError::UnknownSubscription(subscription.0))?;
        Ok(queue.drain(..).collect())
    }

    fn is_synchronous(&self) -> bool {
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn delivers_each_sample_once_in_order_to_matching_subscriptions() {
        let mut t = InProcessTransport::new();
        t.publish("/a", b"before").unwrap();
        let a = t.subscribe(TopicFilter::Exact("/a".into())).unwrap();
        let all = t.subscribe(TopicFilter::All).unwrap();
        t.publish("/a", b"1").unwrap();
        t.publish("/b", b"2").unwrap();
        t.publish("/a", b"3").unwrap();
        let got: Vec<Vec<u8>> = t.receive(a).unwrap().into_iter().map(|s| s.payload).collect();
        assert_eq!(got, vec![b"1".to_vec(), b"3".to_vec()], "no replay of `before`, publish order kept");
        let topics: Vec<String> = t.receive(all).unwrap().into_iter().map(|s| s.topic).collect();
        assert_eq!(topics, ["/a", "/b", "/a"]);
        assert!(t.receive(a).unwrap().is_empty(), "each sample delivered once");
    }

    #[test]
    fn rejects_bad_names_and_unknown_subscriptions() {
        let mut t = InProcessTransport::new();
        assert!(matches!(t.publish("no-slash", b""), Err(BusError::BadTopic { .. })));
        assert!(matches!(t.subscribe(TopicFilter::Exact("/A b".into())), Err(BusError::BadTopic { .. })));
        assert_eq!(t.receive(SubscriptionId(7)), Err(BusError::UnknownSubscription(7)));
    }
}
