//! The live hub: what the telemetry log writes, fanned out to watchers.
//!
//! The run's [`TelemetryRecorder`](rovernav_telemetry::TelemetryRecorder) writes through a
//! [`LiveSink`]; [`Hub::sink`] is one, so the console and the Foxglove server show exactly the
//! topics, schemas and messages of the MCAP log. Publishing never blocks: each watcher reads a
//! bounded broadcast queue, and one that falls behind skips messages (it learns how many) rather
//! than slowing the rover. The latest message of each topic is kept so that a watcher who joins
//! late still gets the world, the settings and the last camera image.

use rovernav_telemetry::LiveSink;
use serde_json::Value;
use std::collections::HashMap;
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};
use tokio::sync::broadcast;

/// How many events a watcher may fall behind before it skips some.
pub const DEFAULT_QUEUE: usize = 4096;

/// A declared topic.
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    /// Its number, in declaration order from 1 (Foxglove's channel id).
    pub id: u32,
    /// The topic (`/rover/estimate`).
    pub topic: String,
    /// The schema's name (`foxglove.CompressedImage`, `rovernav.Estimate`).
    pub schema_name: String,
    /// The JSON Schema of its messages.
    pub schema: Value,
}

/// One message on a channel.
#[derive(Clone, Debug, PartialEq)]
pub struct Message {
    /// The channel's id.
    pub channel: u32,
    /// Simulated time, nanoseconds (the log time).
    pub time_ns: u64,
    /// The message, JSON.
    pub json: Arc<[u8]>,
}

/// What a watcher receives, in the order the log wrote it.
#[derive(Clone, Debug, PartialEq)]
pub enum Event {
    /// A topic was declared.
    Channel(Arc<Channel>),
    /// A message was written.
    Message(Arc<Message>),
}

#[derive(Default)]
struct State {
    channels: Vec<Arc<Channel>>,
    by_topic: HashMap<String, u32>,
    latest: HashMap<u32, Arc<Message>>,
}

/// The live fan-out of a run's telemetry.
pub struct Hub {
    state: Mutex<State>,
    events: broadcast::Sender<Event>,
}

/// What a watcher starts from: the topics so far, the latest message of each, and the stream of
/// everything after them.
pub struct Snapshot {
    /// Every topic declared so far, in declaration order.
    pub channels: Vec<Arc<Channel>>,
    /// The latest message of each topic that has one, in channel order.
    pub latest: Vec<Arc<Message>>,
    /// Everything published after the snapshot.
    pub events: broadcast::Receiver<Event>,
}

impl Hub {
    /// An empty hub whose watchers may each fall `queue` events behind.
    pub fn new(queue: usize) -> Arc<Self> {
        let (events, _) = broadcast::channel(queue.max(1));
        Arc::new(Self { state: Mutex::new(State::default()), events })
    }

    fn lock(&self) -> MutexGuard<'_, State> {
        self.state.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Declares a topic (again: keeps the first declaration) and returns its id.
    pub fn declare(&self, topic: &str, schema_name: &str, schema: &Value) -> u32 {
        let mut state = self.lock();
        if let Some(&id) = state.by_topic.get(topic) {
            return id;
        }
        let id = state.channels.len() as u32 + 1;
        let channel = Arc::new(Channel {
            id,
            topic: topic.to_string(),
            schema_name: schema_name.to_string(),
            schema: schema.clone(),
        });
        state.channels.push(Arc::clone(&channel));
        state.by_topic.insert(topic.to_string(), id);
        // No watcher is not an error: the event is simply not seen.
        let _ = self.events.send(Event::Channel(channel));
        id
    }

    /// Publishes a message on a declared topic; a message on an undeclared topic is dropped
    /// (the log refuses it too).
    pub fn publish(&self, topic: &str, time_ns: u64, json: &[u8]) {
        let mut state = self.lock();
        let Some(&channel) = state.by_topic.get(topic) else { return };
        let message = Arc::new(Message { channel, time_ns, json: Arc::from(json) });
        state.latest.insert(channel, Arc::clone(&message));
        let _ = self.events.send(Event::Message(message));
    }

    /// The channels, the latest messages and a receiver for what follows, taken together so
    /// that nothing is missed or seen twice.
    pub fn snapshot(&self) -> Snapshot {
        let state = self.lock();
        let mut latest: Vec<Arc<Message>> = state.latest.values().cloned().collect();
        latest.sort_by_key(|m| m.channel);
        Snapshot { channels: state.channels.clone(), latest, events: self.events.subscribe() }
    }

    /// The channel with this id.
    pub fn channel(&self, id: u32) -> Option<Arc<Channel>> {
        self.lock().channels.get((id as usize).checked_sub(1)?).cloned()
    }

    /// How many watchers are subscribed now.
    pub fn watchers(&self) -> usize {
        self.events.receiver_count()
    }

    /// A sink for the telemetry writer that publishes into this hub.
    pub fn sink(self: &Arc<Self>) -> Box<dyn LiveSink> {
        Box::new(HubSink(Arc::clone(self)))
    }
}

/// The telemetry writer's tee into a hub.
struct HubSink(Arc<Hub>);

impl LiveSink for HubSink {
    fn topic(&mut self, topic: &str, schema_name: &str, schema: &Value) {
        self.0.declare(topic, schema_name, schema);
    }

    fn message(&mut self, topic: &str, time_ns: u64, json: &[u8]) {
        self.0.publish(topic, time_ns, json);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn a_late_watcher_gets_the_channels_and_latest_messages_then_the_rest_in_order() {
        let hub = Hub::new(16);
        hub.declare("/a", "A", &json!({"type": "object"}));
        hub.publish("/a", 1, b"{\"n\":1}");
        hub.publish("/a", 2, b"{\"n\":2}");
        hub.publish("/undeclared", 3, b"{}");
        let mut snap = hub.snapshot();
        assert_eq!(snap.channels.len(), 1);
        assert_eq!(snap.latest.len(), 1);
        assert_eq!(&*snap.latest[0].json, b"{\"n\":2}");
        assert_eq!(hub.declare("/a", "other", &json!({})), 1, "a second declaration keeps the first");
        let b = hub.declare("/b", "B", &json!({}));
        hub.publish("/b", 4, b"{}");
        match snap.events.try_recv().unwrap() {
            Event::Channel(c) => assert_eq!((c.id, c.topic.as_str()), (b, "/b")),
            other => panic!("expected the new channel, got {other:?}"),
        }
        match snap.events.try_recv().unwrap() {
            Event::Message(m) => assert_eq!((m.channel, m.time_ns), (b, 4)),
            other => panic!("expected the message, got {other:?}"),
        }
        assert!(snap.events.try_recv().is_err(), "nothing else was published");
    }

    #[test]
    fn a_slow_watcher_skips_messages_and_never_blocks_the_publisher() {
        let hub = Hub::new(4);
        hub.declare("/a", "A", &json!({}));
        let mut snap = hub.snapshot();
        for i in 0..100u64 {
            hub.publish("/a", i, b"{}");
        }
        match snap.events.try_recv() {
            Err(broadcast::error::TryRecvError::Lagged(skipped)) => assert_eq!(skipped, 96),
            other => panic!("expected a lag of 96, got {other:?}"),
        }
        let rest: Vec<u64> = std::iter::from_fn(|| match snap.events.try_recv() {
            Ok(Event::Message(m)) => Some(m.time_ns),
            _ => None,
        })
        .collect();
        assert_eq!(rest, vec![96, 97, 98, 99], "the newest messages are kept");
    }

    #[test]
    fn the_telemetry_writer_tee_publishes_what_the_log_holds() {
        let hub = Hub::new(64);
        let dir = std::env::temp_dir().join(format!("rovernav-hub-tee-{}", std::process::id()));
        let path = dir.join("t.mcap");
        let mut writer =
            rovernav_telemetry::TelemetryWriter::create(&path, rovernav_telemetry::FlushPolicy::default())
                .unwrap();
        writer.set_tee(hub.sink());
        writer.add_topic("/x", "X", &json!({"type": "object"}), &Default::default()).unwrap();
        writer.write("/x", 7, &json!({"v": 1.5})).unwrap();
        writer.finish().unwrap();
        let logged = rovernav_telemetry::mcap::MessageStream::new(&std::fs::read(&path).unwrap())
            .unwrap()
            .map(|m| m.unwrap().data.into_owned())
            .collect::<Vec<_>>();
        std::fs::remove_dir_all(&dir).ok();
        let snap = hub.snapshot();
        assert_eq!(snap.channels[0].schema_name, "X");
        assert_eq!(logged.len(), 1);
        assert_eq!(&*snap.latest[0].json, logged[0].as_slice(), "the live message is the logged bytes");
    }
}
