//! `rovernav serve --replay LOG.mcap`: a finished run's log served to the same panels, which
//! scrub through it (each client has its own play head).
//!
//! The log is read once, linearly, with a bound on every record's length (the telemetry crate's
//! `bounded_messages`: a corrupt length must not make the reader allocate without limit), so a
//! log cut short by a killed run replays up to its last complete chunk.

use crate::hub::{Channel, Hub, Message};
use crate::server_history::CUMULATIVE;
use rovernav_telemetry::mcap;
use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

/// A run's log in memory: its channels and messages in log order.
#[derive(Debug)]
pub struct ReplayLog {
    /// Every topic, numbered from 1 in order of first appearance.
    pub channels: Vec<Arc<Channel>>,
    /// Every message, in file order (log times never decrease in a run's log).
    pub messages: Vec<Arc<Message>>,
    /// Why reading stopped early, for a log cut short.
    pub truncated: Option<String>,
    cumulative: Vec<bool>,
}

impl ReplayLog {
    /// Reads a log file.
    pub fn read(path: &Path) -> Result<Self, String> {
        let shown = path.display();
        let bytes = std::fs::read(path).map_err(|e| format!("{shown}: cannot read: {e}"))?;
        Self::parse(&bytes).map_err(|e| format!("{shown}: {e}"))
    }

    /// Parses log bytes; an empty log or one that is not MCAP is an error, a cut-off one is not.
    pub fn parse(bytes: &[u8]) -> Result<Self, String> {
        if !bytes.starts_with(mcap::MAGIC) {
            return Err("not an MCAP log (no MCAP magic at the start)".into());
        }
        let mut log =
            Self { channels: Vec::new(), messages: Vec::new(), truncated: None, cumulative: Vec::new() };
        let mut ids: HashMap<String, u32> = HashMap::new();
        for item in rovernav_telemetry::bounded_messages(bytes) {
            match item {
                Err(e) => {
                    log.truncated = Some(e.to_string());
                    break;
                }
                Ok(m) => {
                    let topic = &m.channel.topic;
                    let channel = match ids.get(topic) {
                        Some(&id) => id,
                        None => {
                            let id = log.channels.len() as u32 + 1;
                            let (schema_name, schema) = match &m.channel.schema {
                                Some(s) => {
                                    (s.name.clone(), serde_json::from_slice(&s.data).unwrap_or_default())
                                }
                                None => (String::new(), serde_json::Value::Null),
                            };
                            log.channels.push(Arc::new(Channel {
                                id,
                                topic: topic.clone(),
                                schema_name,
                                schema,
                            }));
                            log.cumulative.push(CUMULATIVE.contains(&topic.as_str()));
                            ids.insert(topic.clone(), id);
                            id
                        }
                    };
                    let json: Arc<[u8]> = Arc::from(&*m.data);
                    log.messages.push(Arc::new(Message { channel, time_ns: m.log_time, json }));
                }
            }
        }
        if log.messages.is_empty() {
            return Err(log.truncated.map_or("the log holds no message".into(), |why| {
                format!("no message could be read ({why})")
            }));
        }
        Ok(log)
    }

    /// Log time of the first message (ns).
    pub fn start_ns(&self) -> u64 {
        self.messages.first().map_or(0, |m| m.time_ns)
    }

    /// Log time of the last message (ns).
    pub fn end_ns(&self) -> u64 {
        self.messages.last().map_or(0, |m| m.time_ns)
    }

    /// How many messages were logged at or before `t_ns`.
    pub fn count_upto(&self, t_ns: u64) -> usize {
        self.messages.partition_point(|m| m.time_ns <= t_ns)
    }

    /// What a client needs to show the run at `t_ns`: every message of the cumulative topics up
    /// to it and the latest of each other topic, in log order.
    pub fn state_at(&self, t_ns: u64) -> Vec<Arc<Message>> {
        let upto = &self.messages[..self.count_upto(t_ns)];
        let mut latest: HashMap<u32, usize> = HashMap::new();
        for (i, m) in upto.iter().enumerate() {
            if !self.is_cumulative(m.channel) {
                latest.insert(m.channel, i);
            }
        }
        upto.iter()
            .enumerate()
            .filter(|(i, m)| self.is_cumulative(m.channel) || latest.get(&m.channel) == Some(i))
            .map(|(_, m)| Arc::clone(m))
            .collect()
    }

    /// Publishes the log into `hub` in log order, paced at `speed` simulated seconds per second
    /// (`None`: all at once), for the watchers that follow a hub (the Foxglove server).
    pub fn play_into(&self, hub: &Hub, speed: Option<f64>) {
        for c in &self.channels {
            hub.declare(&c.topic, &c.schema_name, &c.schema);
        }
        let started = std::time::Instant::now();
        for m in &self.messages {
            if let Some(speed) = speed {
                let due = (m.time_ns - self.start_ns()) as f64 / 1e9 / speed;
                let now = started.elapsed().as_secs_f64();
                if due > now {
                    std::thread::sleep(std::time::Duration::from_secs_f64(due - now));
                }
            }
            hub.publish(&self.channels[m.channel as usize - 1].topic, m.time_ns, &m.json);
        }
    }

    fn is_cumulative(&self, channel: u32) -> bool {
        self.cumulative.get(channel as usize - 1).copied().unwrap_or(false)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn log_bytes(name: &str) -> Vec<u8> {
        let dir = std::env::temp_dir().join(format!("rovernav-replay-{}-{name}", std::process::id()));
        let path = dir.join("t.mcap");
        let mut w = rovernav_telemetry::TelemetryWriter::create(&path, Default::default()).unwrap();
        w.add_topic("/sim/truth", "T", &json!({"type": "object"}), &Default::default()).unwrap();
        w.add_topic("/camera/a", "I", &json!({}), &Default::default()).unwrap();
        for i in 0..10u64 {
            w.write("/sim/truth", i * 10, &json!({"i": i})).unwrap();
            w.write("/camera/a", i * 10 + 5, &json!({"i": i})).unwrap();
            w.flush().unwrap();
        }
        w.finish().unwrap();
        let bytes = std::fs::read(&path).unwrap();
        std::fs::remove_dir_all(&dir).ok();
        bytes
    }

    #[test]
    fn the_state_at_a_time_keeps_paths_whole_and_images_latest() {
        let log = ReplayLog::parse(&log_bytes("state")).unwrap();
        assert!(log.truncated.is_none());
        assert_eq!((log.start_ns(), log.end_ns(), log.messages.len()), (0, 95, 20));
        let state = log.state_at(42);
        let truth: Vec<u64> = state.iter().filter(|m| m.channel == 1).map(|m| m.time_ns).collect();
        let images: Vec<u64> = state.iter().filter(|m| m.channel == 2).map(|m| m.time_ns).collect();
        assert_eq!(truth, [0, 10, 20, 30, 40]);
        assert_eq!(images, [35], "only the latest image up to the time");
    }

    #[test]
    fn played_into_a_hub_the_log_is_the_hubs_latest() {
        let log = ReplayLog::parse(&log_bytes("hub")).unwrap();
        let hub = Hub::new(64);
        log.play_into(&hub, None);
        let snap = hub.snapshot();
        assert_eq!(snap.channels.len(), 2);
        let times: Vec<u64> = snap.latest.iter().map(|m| m.time_ns).collect();
        assert_eq!(times, [90, 95]);
    }

    #[test]
    fn a_cut_log_replays_its_complete_chunks_and_garbage_is_refused() {
        let whole = log_bytes("cut");
        let cut = ReplayLog::parse(&whole[..whole.len() / 3]).unwrap();
        assert!(cut.truncated.is_some());
        assert!(cut.messages.len() >= 2 && cut.messages.len() < 20, "{}", cut.messages.len());
        assert!(ReplayLog::parse(b"hello").unwrap_err().contains("not an MCAP log"));
        assert!(ReplayLog::parse(&whole[..12]).is_err());
    }
}
