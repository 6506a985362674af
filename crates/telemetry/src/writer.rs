//! A generic MCAP writer: one channel per topic, JSON messages with JSON Schemas (what Foxglove
//! and the MCAP tools read), zstd-compressed chunks, and a flush policy that bounds what a killed
//! process loses.
//!
//! MCAP keeps messages in chunks that a reader can only use once they are complete, so a crash
//! loses the open chunk. The writer therefore closes the chunk and flushes the file whenever a
//! second of wall time has passed since the last flush or the chunk has grown past a size
//! limit; callers apply the policy at points where the log is consistent (the recorder does so
//! at the end of a cycle), so a chunk never ends in the middle of one.

use mcap::records::MessageHeader;
use mcap::{Compression, WriteOptions, Writer};
use serde::Serialize;
use serde_json::Value;
use std::collections::{BTreeMap, HashMap};
use std::fs::File;
use std::io::{BufWriter, Seek, Write};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Why the log could not be written or read.
#[derive(Debug, thiserror::Error)]
pub enum TelemetryError {
    /// The file could not be created, written or read.
    #[error("{path}: {error}")]
    Io {
        /// The log file.
        path: PathBuf,
        /// The cause (in the message, not a chained source, so it is said once).
        error: std::io::Error,
    },
    /// The MCAP library refused a record.
    #[error("{path}: MCAP: {error}")]
    Mcap {
        /// The log file.
        path: PathBuf,
        /// The cause.
        error: mcap::McapError,
    },
    /// A message could not be encoded or a topic was misused.
    #[error("{path}: topic `{topic}`: {message}")]
    Topic {
        /// The log file.
        path: PathBuf,
        /// The topic.
        topic: String,
        /// What went wrong.
        message: String,
    },
    /// The log does not hold what a run logs.
    #[error("{path}: {message}")]
    Content {
        /// The log file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
}

/// When to close the open chunk and flush the file.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlushPolicy {
    /// Longest wall time between flushes: the most a killed process loses.
    pub max_interval: Duration,
    /// Uncompressed bytes after which the open chunk is closed regardless of time.
    pub max_chunk_bytes: u64,
}

impl Default for FlushPolicy {
    fn default() -> Self {
        Self { max_interval: Duration::from_secs(1), max_chunk_bytes: 1 << 20 }
    }
}

impl FlushPolicy {
    /// Whether a chunk opened at `last_flush` holding `chunk_bytes` must be closed at `now`.
    pub fn due(&self, last_flush: Instant, now: Instant, chunk_bytes: u64) -> bool {
        chunk_bytes > 0
            && (chunk_bytes >= self.max_chunk_bytes
                || now.saturating_duration_since(last_flush) >= self.max_interval)
    }
}

/// Counts of a finished log.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LogStats {
    /// Messages written.
    pub messages: u64,
    /// Chunks closed.
    pub chunks: u64,
    /// Uncompressed message bytes.
    pub message_bytes: u64,
}

struct ChannelState {
    id: u16,
    sequence: u32,
}

/// A live consumer of everything a log writes (the web console, the Foxglove server): told of
/// each topic as it is declared and of each message as it is written, so that what is shown
/// live is exactly what the log holds.
pub trait LiveSink: Send {
    /// A topic was declared with its schema name and JSON Schema.
    fn topic(&mut self, topic: &str, schema_name: &str, schema: &Value);
    /// A message (JSON) was written on a declared topic at `time_ns` (simulated time).
    fn message(&mut self, topic: &str, time_ns: u64, json: &[u8]);
}

/// Writes JSON messages on named topics to an MCAP file.
pub struct TelemetryWriter<W: Write + Seek = BufWriter<File>> {
    writer: Writer<W>,
    tee: Option<Box<dyn LiveSink>>,
    path: PathBuf,
    channels: HashMap<String, ChannelState>,
    policy: FlushPolicy,
    last_flush: Instant,
    chunk_bytes: u64,
    stats: LogStats,
}

/// The zstd level of the chunks: the default mission's log is 4.20 MB at the default level 3,
/// 4.07 MB at 9, for no measurable difference in the run's wall time (2.4 s).
const ZSTD_LEVEL: u32 = 9;

/// The MCAP profile: none of the well-known ones (ROS 1/2) fits JSON messages.
const PROFILE: &str = "";

impl TelemetryWriter<BufWriter<File>> {
    /// Creates (or truncates) the log file, creating its folder if needed.
    pub fn create(path: &Path, policy: FlushPolicy) -> Result<Self, TelemetryError> {
        let io = |error| TelemetryError::Io { path: path.to_path_buf(), error };
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(io)?;
        }
        let file = File::create(path).map_err(io)?;
        Self::new(BufWriter::new(file), path, policy)
    }
}

impl<W: Write + Seek> TelemetryWriter<W> {
    /// Starts a log on any seekable stream; `path` names it in errors.
    pub fn new(stream: W, path: &Path, policy: FlushPolicy) -> Result<Self, TelemetryError> {
        let options = WriteOptions::new()
            .compression(Some(Compression::Zstd))
            .compression_level(ZSTD_LEVEL)
            .profile(PROFILE)
            .library(concat!("rovernav-telemetry ", env!("CARGO_PKG_VERSION")))
            // Chunks are closed by the flush policy only, at consistent points.
            .chunk_size(None);
        let writer = options
            .create(stream)
            .map_err(|error| TelemetryError::Mcap { path: path.to_path_buf(), error })?;
        Ok(Self {
            writer,
            tee: None,
            path: path.to_path_buf(),
            channels: HashMap::new(),
            policy,
            last_flush: Instant::now(),
            chunk_bytes: 0,
            stats: LogStats::default(),
        })
    }

    /// Sends every topic declared from now on, and every message, to `sink` as well.
    pub fn set_tee(&mut self, sink: Box<dyn LiveSink>) {
        self.tee = Some(sink);
    }

    fn mcap_err(&self) -> impl Fn(mcap::McapError) -> TelemetryError + '_ {
        |error| TelemetryError::Mcap { path: self.path.clone(), error }
    }

    /// Declares a topic with its schema (encoding `jsonschema`, messages `json`).
    pub fn add_topic(
        &mut self,
        topic: &str,
        schema_name: &str,
        schema: &Value,
        metadata: &BTreeMap<String, String>,
    ) -> Result<(), TelemetryError> {
        if self.channels.contains_key(topic) {
            return Err(self.topic_err(topic, "declared twice"));
        }
        let data = serde_json::to_vec(schema).map_err(|e| self.topic_err(topic, &e.to_string()))?;
        let schema_id = self.writer.add_schema(schema_name, "jsonschema", &data).map_err(self.mcap_err())?;
        let id = self.writer.add_channel(schema_id, topic, "json", metadata).map_err(self.mcap_err())?;
        self.channels.insert(topic.to_string(), ChannelState { id, sequence: 0 });
        if let Some(tee) = self.tee.as_mut() {
            tee.topic(topic, schema_name, schema);
        }
        Ok(())
    }

    fn topic_err(&self, topic: &str, message: &str) -> TelemetryError {
        TelemetryError::Topic { path: self.path.clone(), topic: topic.into(), message: message.into() }
    }

    /// Writes one message; `time_ns` is both its log and publish time.
    pub fn write<T: Serialize>(
        &mut self,
        topic: &str,
        time_ns: u64,
        message: &T,
    ) -> Result<(), TelemetryError> {
        let data = serde_json::to_vec(message).map_err(|e| self.topic_err(topic, &e.to_string()))?;
        self.write_json(topic, time_ns, &data)
    }

    /// Whether a topic has been declared.
    pub fn has_topic(&self, topic: &str) -> bool {
        self.channels.contains_key(topic)
    }

    /// Logs a message that is already JSON (a bus record) on a declared topic.
    pub fn write_json(&mut self, topic: &str, time_ns: u64, data: &[u8]) -> Result<(), TelemetryError> {
        let Some(channel) = self.channels.get_mut(topic) else {
            return Err(self.topic_err(topic, "not declared"));
        };
        channel.sequence = channel.sequence.wrapping_add(1);
        let header = MessageHeader {
            channel_id: channel.id,
            sequence: channel.sequence,
            log_time: time_ns,
            publish_time: time_ns,
        };
        self.writer.write_to_known_channel(&header, data).map_err(self.mcap_err())?;
        if let Some(tee) = self.tee.as_mut() {
            tee.message(topic, time_ns, data);
        }
        self.chunk_bytes += data.len() as u64;
        self.stats.messages += 1;
        self.stats.message_bytes += data.len() as u64;
        Ok(())
    }

    /// Applies the flush policy at `now`; returns whether a chunk was closed.
    pub fn maybe_flush_at(&mut self, now: Instant) -> Result<bool, TelemetryError> {
        if self.policy.due(self.last_flush, now, self.chunk_bytes) {
            self.flush_at(now)?;
            return Ok(true);
        }
        Ok(false)
    }

    /// Applies the flush policy now.
    pub fn maybe_flush(&mut self) -> Result<bool, TelemetryError> {
        self.maybe_flush_at(Instant::now())
    }

    /// Closes the open chunk if it is older than the policy's interval (the time rule alone,
    /// for a timer that may fire in the middle of a caller's group of messages).
    pub fn flush_if_stale_at(&mut self, now: Instant) -> Result<bool, TelemetryError> {
        let stale = now.saturating_duration_since(self.last_flush) >= self.policy.max_interval;
        if self.chunk_bytes > 0 && stale {
            self.flush_at(now)?;
            return Ok(true);
        }
        Ok(false)
    }

    /// The flush policy.
    pub fn policy(&self) -> FlushPolicy {
        self.policy
    }

    /// The log file (as named in errors).
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Closes the open chunk (if any) and flushes the file.
    pub fn flush(&mut self) -> Result<(), TelemetryError> {
        self.flush_at(Instant::now())
    }

    fn flush_at(&mut self, now: Instant) -> Result<(), TelemetryError> {
        if self.chunk_bytes > 0 {
            self.stats.chunks += 1;
        }
        self.writer.flush().map_err(self.mcap_err())?;
        self.chunk_bytes = 0;
        self.last_flush = now;
        Ok(())
    }

    /// Closes the last chunk and writes the summary and footer.
    pub fn finish(mut self) -> Result<LogStats, TelemetryError> {
        if self.chunk_bytes > 0 {
            self.stats.chunks += 1;
        }
        self.writer.finish().map_err(self.mcap_err())?;
        let stats = self.stats;
        let mut stream = self.writer.into_inner();
        stream.flush().map_err(|error| TelemetryError::Io { path: self.path.clone(), error })?;
        Ok(stats)
    }

    /// Counts so far.
    pub fn stats(&self) -> LogStats {
        self.stats
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Cursor;

    #[test]
    fn policy_flushes_on_time_or_size_and_never_an_empty_chunk() {
        let p = FlushPolicy { max_interval: Duration::from_secs(1), max_chunk_bytes: 1000 };
        let t0 = Instant::now();
        assert!(!p.due(t0, t0 + Duration::from_millis(999), 999));
        assert!(p.due(t0, t0 + Duration::from_secs(1), 1));
        assert!(p.due(t0, t0, 1000));
        assert!(!p.due(t0, t0 + Duration::from_secs(10), 0), "nothing to flush");
    }

    fn open(policy: FlushPolicy) -> TelemetryWriter<Cursor<Vec<u8>>> {
        let mut w = TelemetryWriter::new(Cursor::new(Vec::new()), Path::new("mem.mcap"), policy).unwrap();
        let schema = serde_json::json!({"type": "object"});
        w.add_topic("/a", "test.A", &schema, &BTreeMap::new()).unwrap();
        w.add_topic("/b", "test.B", &schema, &BTreeMap::from([("k".into(), "v".into())])).unwrap();
        w
    }

    #[test]
    fn messages_schemas_and_metadata_read_back_with_the_mcap_reader() {
        let mut w = open(FlushPolicy::default());
        for i in 0..5u64 {
            w.write("/a", i * 10, &serde_json::json!({ "i": i })).unwrap();
            w.write("/b", i * 10 + 1, &serde_json::json!({ "j": i })).unwrap();
        }
        let stats = w.stats();
        assert_eq!(stats.messages, 10);
        w.writer.finish().unwrap();
        let bytes = w.writer.into_inner().into_inner();
        let summary = mcap::Summary::read(&bytes).unwrap().expect("summary");
        assert_eq!(summary.stats.as_ref().unwrap().message_count, 10);
        let msgs: Vec<_> = mcap::MessageStream::new(&bytes).unwrap().map(Result::unwrap).collect();
        assert_eq!(msgs.len(), 10);
        for (k, m) in msgs.iter().enumerate() {
            let schema = m.channel.schema.as_ref().unwrap();
            assert_eq!(schema.encoding, "jsonschema");
            assert_eq!(m.channel.message_encoding, "json");
            assert_eq!(m.log_time, m.publish_time);
            assert_eq!(m.sequence as usize, k / 2 + 1, "per-channel sequence numbers");
            let v: Value = serde_json::from_slice(&m.data).unwrap();
            assert_eq!(v.as_object().unwrap().values().next().unwrap().as_u64(), Some(k as u64 / 2));
        }
        assert_eq!(msgs[1].channel.metadata.get("k").map(String::as_str), Some("v"));
    }

    #[test]
    fn the_timer_rule_flushes_only_an_old_nonempty_chunk() {
        let policy = FlushPolicy { max_interval: Duration::from_secs(1), max_chunk_bytes: 1 };
        let mut w = open(policy);
        let t0 = w.last_flush;
        assert!(!w.flush_if_stale_at(t0 + Duration::from_secs(5)).unwrap(), "nothing written yet");
        w.write("/a", 0, &1).unwrap();
        assert!(!w.flush_if_stale_at(t0 + Duration::from_millis(500)).unwrap(), "size alone does not count");
        assert!(w.flush_if_stale_at(t0 + Duration::from_secs(1)).unwrap());
        assert_eq!(w.stats().chunks, 1);
    }

    #[test]
    fn undeclared_topic_and_duplicate_declaration_are_errors() {
        let mut w = open(FlushPolicy::default());
        let err = w.write("/nope", 0, &1).unwrap_err().to_string();
        assert!(err.contains("mem.mcap") && err.contains("/nope") && err.contains("not declared"), "{err}");
        let err = w.add_topic("/a", "x", &Value::Null, &BTreeMap::new()).unwrap_err().to_string();
        assert!(err.contains("declared twice"), "{err}");
    }

    /// An in-memory stream the test can snapshot while the writer still owns it, as a file on
    /// disk can be read while a process writes it.
    #[derive(Clone, Default)]
    struct SharedBuf(std::rc::Rc<std::cell::RefCell<Cursor<Vec<u8>>>>);

    impl Write for SharedBuf {
        fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
            self.0.borrow_mut().write(buf)
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    impl Seek for SharedBuf {
        fn seek(&mut self, pos: std::io::SeekFrom) -> std::io::Result<u64> {
            self.0.borrow_mut().seek(pos)
        }
    }

    #[test]
    fn a_stream_cut_after_a_flush_still_yields_every_flushed_message() {
        // Size-triggered flushes close a chunk every few messages; cutting the stream anywhere
        // after a flush (inside the next, unfinished chunk) must leave every message of the
        // closed chunks readable, and none of the open one.
        let buf = SharedBuf::default();
        let policy = FlushPolicy { max_interval: Duration::from_secs(3600), max_chunk_bytes: 64 };
        let mut w = TelemetryWriter::new(buf.clone(), Path::new("mem.mcap"), policy).unwrap();
        w.add_topic("/a", "test.A", &serde_json::json!({"type": "object"}), &BTreeMap::new()).unwrap();
        let mut flushes = Vec::new();
        for i in 0..40u64 {
            w.write("/a", i, &serde_json::json!({ "payload": "x".repeat(20), "i": i })).unwrap();
            let now = w.last_flush;
            if w.maybe_flush_at(now).unwrap() {
                flushes.push((i + 1, buf.0.borrow().get_ref().len()));
            }
        }
        assert!(flushes.len() >= 10, "the size limit closes chunks: {flushes:?}");
        w.write("/a", 99, &serde_json::json!({ "payload": "in the open chunk" })).unwrap();
        let full = buf.0.borrow().get_ref().clone();
        for &(count, end) in &flushes {
            for cut in [end, (end + 7).min(full.len()), full.len()] {
                let read: Vec<_> =
                    mcap::MessageStream::new(&full[..cut]).unwrap().map_while(Result::ok).collect();
                let expect = if cut == full.len() { flushes.last().unwrap().0 } else { count };
                assert_eq!(read.len() as u64, expect, "cut at byte {cut} of {}", full.len());
                assert!(read.iter().enumerate().all(|(k, m)| m.log_time == k as u64));
            }
        }
        let stats = w.finish().unwrap();
        assert_eq!(stats.messages, 41);
        let done = buf.0.borrow().get_ref().clone();
        assert_eq!(mcap::MessageStream::new(&done).unwrap().map(Result::unwrap).count(), 41);
    }
}
