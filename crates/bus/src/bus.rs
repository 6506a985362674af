//! The typed bus: publish and take messages through [`Topic`] handles over a backend.
//!
//! Two backends behave identically from a component's point of view:
//! - in process (the default): messages are shared as `Arc<T>` without serialization, queued per
//!   subscription at publish time, so a lockstep runtime steps deterministically;
//! - over a [`Transport`]: every message is encoded as JSON, handed to the transport and decoded
//!   on `take`. With [`crate::InProcessTransport`] this is the serialized twin of the in-process
//!   backend, used by tests to prove that every message survives the wire unchanged.
//!
//! A tap ([`Bus::tap`]) receives every message of every topic as JSON bytes with a global
//! sequence number and the bus clock, for telemetry recorders.

use crate::topic::{Message, Topic, check_topic_name, decode, encode};
use crate::transport::{BusError, SubscriptionId, TopicFilter, Transport};
use std::any::Any;
use std::collections::{BTreeMap, VecDeque};
use std::sync::Arc;

/// A typed subscription; take its messages with [`Bus::take`].
#[derive(Debug)]
pub struct Subscriber<T> {
    id: SubscriptionId,
    topic: Topic<T>,
}

impl<T> Subscriber<T> {
    /// The topic subscribed to.
    pub fn topic(&self) -> Topic<T> {
        self.topic
    }
}

/// A handle to a tap (see [`Bus::tap`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TapId(usize);

/// One message seen by a tap.
#[derive(Clone, Debug, PartialEq)]
pub struct Record {
    /// Order in which this tap saw the message (0 for the first).
    pub seq: u64,
    /// The bus clock when the message was published (s; simulated time in a simulation).
    pub time_s: f64,
    /// Topic name.
    pub topic: String,
    /// Message type name (empty when the publisher is not on this bus).
    pub type_name: String,
    /// The message as JSON.
    pub payload: Vec<u8>,
}

type Shared = Arc<dyn Any + Send + Sync>;

/// Where messages go.
enum Backend {
    /// Typed queues, one per subscription: `(topic, queue)`.
    Local(Vec<(&'static str, VecDeque<Shared>)>),
    /// A serializing transport; `taps` are the transport's `All` subscriptions with the number
    /// of records each has delivered.
    Wire { transport: Box<dyn Transport>, taps: Vec<(SubscriptionId, u64)> },
}

/// The typed message bus.
pub struct Bus {
    backend: Backend,
    /// In-process taps: records delivered so far and queued records (the wire backend taps
    /// through the transport).
    local_taps: Vec<(u64, VecDeque<Record>)>,
    /// Message type of each topic seen, for tap records.
    types: BTreeMap<String, &'static str>,
    seq: u64,
    clock: f64,
}

impl std::fmt::Debug for Bus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let kind = match self.backend {
            Backend::Local(_) => "in-process",
            Backend::Wire { .. } => "transport",
        };
        f.debug_struct("Bus").field("backend", &kind).field("published", &self.seq).finish()
    }
}

impl Default for Bus {
    fn default() -> Self {
        Self::in_process()
    }
}

impl Bus {
    /// The deterministic in-process bus (no serialization).
    pub fn in_process() -> Self {
        Self::with_backend(Backend::Local(Vec::new()))
    }

    /// A bus that serializes every message through `transport`.
    pub fn over(transport: Box<dyn Transport>) -> Self {
        Self::with_backend(Backend::Wire { transport, taps: Vec::new() })
    }

    fn with_backend(backend: Backend) -> Self {
        Self { backend, local_taps: Vec::new(), types: BTreeMap::new(), seq: 0, clock: 0.0 }
    }

    /// Whether a message published now can be taken before `publish` returns (always for the
    /// in-process backend; as the transport says otherwise).
    pub fn is_synchronous(&self) -> bool {
        match &self.backend {
            Backend::Local(_) => true,
            Backend::Wire { transport, .. } => transport.is_synchronous(),
        }
    }

    /// Sets the clock stamped on tap records (the runtime sets simulated time).
    pub fn set_time(&mut self, time_s: f64) {
        self.clock = time_s;
    }

    /// The clock stamped on tap records (s).
    pub fn time(&self) -> f64 {
        self.clock
    }

    /// Messages published so far.
    pub fn published(&self) -> u64 {
        self.seq
    }

    /// Publishes a message.
    pub fn publish<T: Message>(&mut self, topic: Topic<T>, message: T) -> Result<(), BusError> {
        check_topic_name(topic.name())?;
        self.types.insert(topic.name().to_string(), topic.type_name());
        self.seq += 1;
        match &mut self.backend {
            Backend::Local(subscriptions) => {
                if !self.local_taps.is_empty() {
                    let record = Record {
                        seq: 0,
                        time_s: self.clock,
                        topic: topic.name().to_string(),
                        type_name: topic.type_name().to_string(),
                        payload: encode(&topic, &message)?,
                    };
                    for (count, queue) in &mut self.local_taps {
                        queue.push_back(Record { seq: *count, ..record.clone() });
                        *count += 1;
                    }
                }
                let shared: Shared = Arc::new(message);
                for (name, queue) in subscriptions.iter_mut() {
                    if *name == topic.name() {
                        queue.push_back(Arc::clone(&shared));
                    }
                }
                Ok(())
            }
            Backend::Wire { transport, .. } => transport.publish(topic.name(), &encode(&topic, &message)?),
        }
    }

    /// Subscribes to a topic; messages published from now on are queued for the subscriber.
    pub fn subscribe<T: Message>(&mut self, topic: Topic<T>) -> Result<Subscriber<T>, BusError> {
        check_topic_name(topic.name())?;
        self.types.insert(topic.name().to_string(), topic.type_name());
        let id = match &mut self.backend {
            Backend::Local(subscriptions) => {
                subscriptions.push((topic.name(), VecDeque::new()));
                SubscriptionId(subscriptions.len() as u64 - 1)
            }
            Backend::Wire { transport, .. } => {
                transport.subscribe(TopicFilter::Exact(topic.name().to_string()))?
            }
        };
        Ok(Subscriber { id, topic })
    }

    /// Takes every message queued for a subscriber, oldest first.
    pub fn take<T: Message>(&mut self, subscriber: &Subscriber<T>) -> Result<Vec<Arc<T>>, BusError> {
        match &mut self.backend {
            Backend::Local(subscriptions) => {
                let (_, queue) = subscriptions
                    .get_mut(subscriber.id.0 as usize)
                    .ok_or(BusError::UnknownSubscription(subscriber.id.0))?;
                queue
                    .drain(..)
                    .map(|shared| {
                        shared.downcast::<T>().map_err(|_| BusError::Codec {
                            topic: subscriber.topic.name().to_string(),
                            action: "decode",
                            type_name: subscriber.topic.type_name().to_string(),
                            message: "a message of another type was published on this topic".into(),
                        })
                    })
                    .collect()
            }
            Backend::Wire { transport, .. } => transport
                .receive(subscriber.id)?
                .into_iter()
                .map(|sample| decode(&subscriber.topic, &sample.payload).map(Arc::new))
                .collect(),
        }
    }

    /// The newest message queued for a subscriber (older ones are dropped), if any.
    pub fn latest<T: Message>(&mut self, subscriber: &Subscriber<T>) -> Result<Option<Arc<T>>, BusError> {
        Ok(self.take(subscriber)?.pop())
    }

    /// Starts receiving every message of every topic as JSON (telemetry, bridges).
    pub fn tap(&mut self) -> Result<TapId, BusError> {
        match &mut self.backend {
            Backend::Local(_) => {
                self.local_taps.push((0, VecDeque::new()));
                Ok(TapId(self.local_taps.len() - 1))
            }
            Backend::Wire { transport, taps } => {
                taps.push((transport.subscribe(TopicFilter::All)?, 0));
                Ok(TapId(taps.len() - 1))
            }
        }
    }

    /// Takes the records a tap has seen, in publish order.
    pub fn take_tap(&mut self, tap: TapId) -> Result<Vec<Record>, BusError> {
        match &mut self.backend {
            Backend::Local(_) => {
                let (_, queue) =
                    self.local_taps.get_mut(tap.0).ok_or(BusError::UnknownSubscription(tap.0 as u64))?;
                Ok(queue.drain(..).collect())
            }
            Backend::Wire { transport, taps } => {
                let (id, count) = taps.get_mut(tap.0).ok_or(BusError::UnknownSubscription(tap.0 as u64))?;
                let samples = transport.receive(*id)?;
                let first = *count;
                *count += samples.len() as u64;
                // A transport sample carries no time: stamp it with the clock at arrival.
                Ok(samples
                    .into_iter()
                    .enumerate()
                    .map(|(i, s)| Record {
                        seq: first + i as u64,
                        time_s: self.clock,
                        type_name: self.types.get(&s.topic).copied().unwrap_or_default().to_string(),
                        topic: s.topic,
                        payload: s.payload,
                    })
                    .collect())
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::InProcessTransport;
    use serde::{Deserialize, Serialize};

    #[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
    struct Reading {
        t: f64,
        values: Vec<f32>,
        note: Option<String>,
    }

    const READINGS: Topic<Reading> = Topic::new("/test/readings");
    const WORDS: Topic<String> = Topic::new("/test/words");

    /// What a backend delivered: readings, words, and (seq, topic, type) of the tap records.
    type Delivered = (Vec<Reading>, Vec<String>, Vec<(u64, String, String)>);

    fn exercise(bus: &mut Bus) -> Delivered {
        let tap = bus.tap().unwrap();
        let readings = bus.subscribe(READINGS).unwrap();
        let words = bus.subscribe(WORDS).unwrap();
        bus.set_time(1.5);
        bus.publish(READINGS, Reading { t: 0.1, values: vec![1.0 / 3.0, -0.0, 7e-39], note: None }).unwrap();
        bus.publish(WORDS, "stop".to_string()).unwrap();
        bus.publish(READINGS, Reading { t: 0.2, values: vec![], note: Some("é\n\"q\"".into()) }).unwrap();
        let r = bus.take(&readings).unwrap().iter().map(|r| (**r).clone()).collect();
        let w = bus.take(&words).unwrap().iter().map(|w| (**w).clone()).collect();
        assert!(bus.take(&readings).unwrap().is_empty());
        let t =
            bus.take_tap(tap).unwrap().into_iter().map(|rec| (rec.seq, rec.topic, rec.type_name)).collect();
        (r, w, t)
    }

    #[test]
    fn in_process_and_serialized_backends_deliver_the_same_messages() {
        let local = exercise(&mut Bus::in_process());
        let wire = exercise(&mut Bus::over(Box::new(InProcessTransport::new())));
        assert_eq!(local, wire);
        assert_eq!(local.0.len(), 2);
        assert_eq!(local.0[0].values[0].to_bits(), (1.0f32 / 3.0).to_bits());
        assert_eq!(local.1, ["stop"]);
        let topics: Vec<&str> = local.2.iter().map(|(_, t, _)| t.as_str()).collect();
        assert_eq!(topics, ["/test/readings", "/test/words", "/test/readings"]);
        assert_eq!(local.2.iter().map(|r| r.0).collect::<Vec<_>>(), [0, 1, 2]);
        assert_eq!(local.2[0].2, "Reading");
    }

    #[test]
    fn tap_payload_is_the_json_of_the_message() {
        let mut bus = Bus::in_process();
        let tap = bus.tap().unwrap();
        bus.set_time(4.0);
        bus.publish(WORDS, "hello".to_string()).unwrap();
        let rec = bus.take_tap(tap).unwrap().remove(0);
        assert_eq!(rec.payload, b"\"hello\"");
        assert_eq!(rec.time_s, 4.0);
    }

    #[test]
    fn latest_keeps_only_the_newest() {
        let mut bus = Bus::in_process();
        let words = bus.subscribe(WORDS).unwrap();
        for w in ["a", "b", "c"] {
            bus.publish(WORDS, w.to_string()).unwrap();
        }
        assert_eq!(bus.latest(&words).unwrap().as_deref().map(String::as_str), Some("c"));
        assert_eq!(bus.latest(&words).unwrap(), None);
    }

    #[test]
    fn a_type_mismatch_on_one_topic_name_is_an_error_not_a_panic() {
        let mut bus = Bus::in_process();
        let as_words = bus.subscribe(WORDS).unwrap();
        let as_numbers: Topic<u32> = Topic::new("/test/words");
        bus.publish(as_numbers, 3).unwrap();
        let err = bus.take(&as_words).unwrap_err().to_string();
        assert!(err.contains("/test/words"), "{err}");
    }
}
