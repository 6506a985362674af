//! What a console client that joins late needs: the run so far.
//!
//! The hub keeps only the latest message of each topic; the map needs the whole driven path, the
//! ground sensed so far and every component's state. [`History`] keeps every message of those
//! cumulative topics and the latest of the others; [`LiveHistory`] fills one from the hub on its
//! own thread and passes each event on to the clients under the same lock, so that a client that
//! joins gets the history and then exactly the events after it.
//!
//! The kept messages are bounded in bytes ([`HISTORY_BUDGET_BYTES`]): past the budget, the topic
//! holding the most bytes (the sensor frames, on a long run) is thinned to every other message,
//! keeping its first and last, so a late joiner of a long traverse sees the whole route at a
//! coarser step rather than the server's memory growing with the distance driven.

use crate::hub::{Channel, Event, Hub, Message};
use std::collections::HashMap;
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};
use tokio::sync::broadcast;

/// Topics of which a client needs every message (a path, the sensed ground, component states);
/// of every other topic the latest is enough.
pub const CUMULATIVE: [&str; 8] = [
    "/sim/truth",
    "/localization/estimate",
    "/platform/sensor_frame",
    "/bus/platform/frame",
    "/log",
    "/sim/hazard_contacts",
    "/bus/system/status",
    "/bus/executive/task_status",
];

/// Bus topics shown besides the curated ones (the rest repeat them); `/platform/sensor_frame`
/// may name its frame by its number on `/bus/platform/frame`.
const SHOWN_BUS_TOPICS: [&str; 3] =
    ["/bus/system/status", "/bus/executive/task_status", "/bus/platform/frame"];

/// Whether a topic goes to the console's clients.
pub fn shown(topic: &str) -> bool {
    !topic.starts_with("/bus/") || SHOWN_BUS_TOPICS.contains(&topic)
}

/// At most this many bytes of cumulative messages are kept for late joiners.
pub const HISTORY_BUDGET_BYTES: usize = 256 << 20;

/// A cumulative topic's thinning: of its messages in arrival order, those whose number is a
/// multiple of `stride` are kept, and the newest besides.
#[derive(Debug, Default)]
struct Thinning {
    arrivals: u64,
    stride: u64,
    newest: Option<(u64, Arc<Message>)>,
}

/// Channels and the messages a client needs to show the run up to now.
#[derive(Debug)]
pub struct History {
    /// Every topic so far.
    pub channels: Vec<Arc<Channel>>,
    cumulative: Vec<bool>,
    /// Kept cumulative messages: (sequence, arrival number in its topic, message).
    kept: Vec<(u64, u64, Arc<Message>)>,
    kept_bytes: usize,
    budget_bytes: usize,
    thinning: HashMap<u32, Thinning>,
    latest: HashMap<u32, (u64, Arc<Message>)>,
    seq: u64,
}

impl Default for History {
    fn default() -> Self {
        Self::with_budget(HISTORY_BUDGET_BYTES)
    }
}

impl History {
    /// An empty history keeping at most `budget_bytes` of cumulative messages.
    pub fn with_budget(budget_bytes: usize) -> Self {
        Self {
            channels: Vec::new(),
            cumulative: Vec::new(),
            kept: Vec::new(),
            kept_bytes: 0,
            budget_bytes,
            thinning: HashMap::new(),
            latest: HashMap::new(),
            seq: 0,
        }
    }

    /// Bytes of the cumulative messages kept.
    pub fn kept_bytes(&self) -> usize {
        self.kept_bytes
    }

    /// Doubles the stride of the topic holding the most bytes (every other kept message of it
    /// goes); returns whether anything was dropped.
    fn thin(&mut self) -> bool {
        let mut bytes: HashMap<u32, (usize, usize)> = HashMap::new();
        for (_, _, m) in &self.kept {
            let entry = bytes.entry(m.channel).or_default();
            entry.0 += m.json.len();
            entry.1 += 1;
        }
        let heaviest = bytes.iter().max_by_key(|(id, (b, _))| (*b, std::cmp::Reverse(**id)));
        let Some((&channel, &(_, count))) = heaviest else { return false };
        if count < 2 {
            return false;
        }
        let thinning = self.thinning.entry(channel).or_default();
        thinning.stride = thinning.stride.max(1) * 2;
        let stride = thinning.stride;
        self.kept.retain(|(_, number, m)| m.channel != channel || number.is_multiple_of(stride));
        self.kept_bytes = self.kept.iter().map(|(_, _, m)| m.json.len()).sum();
        true
    }

    /// Adds a topic.
    pub fn channel(&mut self, c: Arc<Channel>) {
        let index = c.id as usize - 1;
        if self.cumulative.len() <= index {
            self.cumulative.resize(index + 1, false);
        }
        self.cumulative[index] = CUMULATIVE.contains(&c.topic.as_str());
        self.channels.push(c);
    }

    /// Adds a message (one of a topic not shown is dropped).
    pub fn message(&mut self, m: Arc<Message>) {
        let Some(channel) = self.channels.iter().find(|c| c.id == m.channel) else { return };
        if !shown(&channel.topic) {
            return;
        }
        self.seq += 1;
        if self.cumulative.get(m.channel as usize - 1).copied().unwrap_or(false) {
            let thinning = self.thinning.entry(m.channel).or_default();
            let number = thinning.arrivals;
            thinning.arrivals += 1;
            if !number.is_multiple_of(thinning.stride.max(1)) {
                thinning.newest = Some((self.seq, m));
                return;
            }
            thinning.newest = None;
            self.kept_bytes += m.json.len();
            self.kept.push((self.seq, number, m));
            while self.kept_bytes > self.budget_bytes && self.thin() {}
        } else {
            self.latest.insert(m.channel, (self.seq, m));
        }
    }

    /// The messages kept, in the order they came.
    pub fn messages(&self) -> Vec<Arc<Message>> {
        let kept = self.kept.iter().map(|(seq, _, m)| (*seq, m));
        let newest = self.thinning.values().filter_map(|t| t.newest.as_ref().map(|(seq, m)| (*seq, m)));
        let latest = self.latest.values().map(|(seq, m)| (*seq, m));
        let mut all: Vec<(u64, &Arc<Message>)> = kept.chain(newest).chain(latest).collect();
        all.sort_by_key(|(seq, _)| *seq);
        all.into_iter().map(|(_, m)| Arc::clone(m)).collect()
    }
}

/// A history kept up to date from a hub, and the events after it.
pub struct LiveHistory {
    history: Mutex<History>,
    events: broadcast::Sender<Event>,
}

impl LiveHistory {
    /// Starts following `hub` on a thread of its own (for the life of the process).
    pub fn follow(hub: &Arc<Hub>) -> Arc<Self> {
        let (events, _) = broadcast::channel(crate::hub::DEFAULT_QUEUE);
        let live = Arc::new(Self { history: Mutex::new(History::default()), events });
        let mut snap = hub.snapshot();
        {
            let mut history = live.lock();
            snap.channels.into_iter().for_each(|c| history.channel(c));
            snap.latest.into_iter().for_each(|m| history.message(m));
        }
        let follower = Arc::clone(&live);
        std::thread::Builder::new()
            .name("console-history".into())
            .spawn(move || {
                loop {
                    let event = match snap.events.blocking_recv() {
                        Ok(event) => event,
                        Err(broadcast::error::RecvError::Lagged(_)) => continue,
                        Err(broadcast::error::RecvError::Closed) => break,
                    };
                    let mut history = follower.lock();
                    match &event {
                        Event::Channel(c) => history.channel(Arc::clone(c)),
                        Event::Message(m) => history.message(Arc::clone(m)),
                    }
                    let _ = follower.events.send(event);
                }
            })
            .expect("a thread can be spawned at start");
        live
    }

    fn lock(&self) -> MutexGuard<'_, History> {
        self.history.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// The channels, the messages so far, and the events after them.
    pub fn join(&self) -> (Vec<Arc<Channel>>, Vec<Arc<Message>>, broadcast::Receiver<Event>) {
        let history = self.lock();
        (history.channels.clone(), history.messages(), self.events.subscribe())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;
    use std::time::{Duration, Instant};

    #[test]
    fn a_late_client_gets_the_whole_path_the_latest_of_the_rest_then_what_follows() {
        let hub = Hub::new(64);
        hub.declare("/sim/truth", "T", &json!({}));
        hub.declare("/camera/a", "I", &json!({}));
        hub.declare("/bus/navigation/plan", "F", &json!({}));
        let live = LiveHistory::follow(&hub);
        for i in 0..5u64 {
            hub.publish("/sim/truth", i, b"{}");
            hub.publish("/camera/a", i, b"{}");
            hub.publish("/bus/navigation/plan", i, b"{}");
        }
        let deadline = Instant::now() + Duration::from_secs(5);
        let (channels, messages, mut rest) = loop {
            let joined = live.join();
            if joined.1.len() == 6 || Instant::now() > deadline {
                break joined;
            }
            std::thread::sleep(Duration::from_millis(5));
        };
        assert_eq!(channels.len(), 3);
        let seen: Vec<(u32, u64)> = messages.iter().map(|m| (m.channel, m.time_ns)).collect();
        assert_eq!(seen, [(1, 0), (1, 1), (1, 2), (1, 3), (1, 4), (2, 4)], "the bus plan is not shown");
        hub.publish("/sim/truth", 9, b"{}");
        let next = rest.blocking_recv().unwrap();
        assert!(matches!(next, Event::Message(m) if m.time_ns == 9));
    }

    #[test]
    fn a_long_run_is_thinned_within_the_budget_keeping_the_route_ends_and_the_small_topics() {
        let mut history = History::with_budget(100_000);
        history.channel(Arc::new(Channel {
            id: 1,
            topic: "/bus/platform/frame".into(),
            schema_name: "F".into(),
            schema: json!({}),
        }));
        history.channel(Arc::new(Channel {
            id: 2,
            topic: "/log".into(),
            schema_name: "L".into(),
            schema: json!({}),
        }));
        let frame: Arc<[u8]> = Arc::from(vec![b' '; 1000]);
        for t in 0..10_000u64 {
            history.message(Arc::new(Message { channel: 1, time_ns: t, json: Arc::clone(&frame) }));
            if t % 100 == 0 {
                history.message(Arc::new(Message { channel: 2, time_ns: t, json: Arc::from(&b"{}"[..]) }));
            }
        }
        assert!(history.kept_bytes() <= 100_000, "{} bytes kept", history.kept_bytes());
        let frames: Vec<u64> =
            history.messages().iter().filter(|m| m.channel == 1).map(|m| m.time_ns).collect();
        assert_eq!((frames[0], *frames.last().unwrap()), (0, 9_999), "the route's ends are kept");
        assert!(frames.len() > 25, "the route is kept at a coarser step: {} frames", frames.len());
        let steps: Vec<u64> = frames.windows(2).map(|w| w[1] - w[0]).collect();
        let widest = *steps.iter().max().unwrap();
        let mean = 9_999 / (frames.len() as u64 - 1);
        assert!(widest <= 2 * mean, "thinned evenly: a gap of {widest} against a mean of {mean}");
        let logs = history.messages().iter().filter(|m| m.channel == 2).count();
        assert_eq!(logs, 100, "a small topic is not thinned");
    }
}
