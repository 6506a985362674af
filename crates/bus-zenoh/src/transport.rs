//! [`ZenohTransport`]: the bus's [`Transport`] over a zenoh session, through zenoh's blocking API
//! (zenoh runs its own threads; rovernav code needs no async runtime).

use crate::config::{ZenohConfig, filter_key, key_topic, topic_key};
use rovernav_bus::{BusError, Sample, SubscriptionId, TopicFilter, Transport, check_topic_name};
use std::collections::HashMap;
use std::fmt;
use std::sync::mpsc;
use std::time::Duration;
use zenoh::Wait;
use zenoh::liveliness::LivelinessToken;
use zenoh::pubsub::{Publisher, Subscriber};
use zenoh::qos::CongestionControl;
use zenoh::sample::{Locality, SampleKind};

/// Key prefix of the liveliness tokens behind [`ZenohTransport::announce`]; tokens live apart
/// from published samples, so a `**` subscription never sees them.
const READY_PREFIX: &str = "rovernav/ready";

/// One subscription: its filter and the queue its zenoh callback fills.
struct Subscription {
    filter: TopicFilter,
    queue: mpsc::Receiver<Sample>,
    /// Held for its lifetime: dropping a zenoh subscriber undeclares it.
    _subscriber: Subscriber<()>,
}

/// A [`Transport`] over a zenoh session: topic `/platform/frame` is zenoh key `platform/frame`
/// and [`TopicFilter::All`] is `**`.
///
/// Samples arrive on zenoh's threads and wait in one queue per subscription, so `receive` never
/// blocks; [`ZenohTransport::wait_for`] blocks when a process must (lockstep over the network).
/// Publishing blocks rather than drops under congestion and every link is TCP, so each
/// subscriber gets every sample of a publisher once and in publish order, provided the
/// publisher already knew of the subscription ([`ZenohTransport::wait_for_subscriber`],
/// [`ZenohTransport::wait_for_announcement`]). A session also receives its own samples, as the
/// in-process transport does. Dropping the transport closes the session and frees its ports.
pub struct ZenohTransport {
    session: zenoh::Session,
    publishers: HashMap<String, Publisher<'static>>,
    subscriptions: Vec<Subscription>,
    tokens: Vec<LivelinessToken>,
}

impl fmt::Debug for ZenohTransport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("ZenohTransport")
            .field("zid", &self.session.zid().to_string())
            .field("publishers", &self.publishers.len())
            .field("subscriptions", &self.subscriptions.len())
            .finish()
    }
}

/// A zenoh failure as the bus's one-line transport error.
fn failure(action: &str, error: impl fmt::Display) -> BusError {
    BusError::Transport(one_line(&format!("zenoh: {action}: {error}")))
}

/// A message on one line, without the ` at /path/file.rs:LINE` source locations zenoh appends
/// (they name zenoh's code, not the user's problem).
fn one_line(message: &str) -> String {
    let mut words: Vec<String> = Vec::new();
    let mut tokens = message.split_whitespace().peekable();
    while let Some(token) = tokens.next() {
        if token == "at"
            && let Some(location) = tokens.peek().and_then(|next| next.split_once(".rs:"))
        {
            tokens.next();
            // Keep what closes after the line number (`]`), not the sentence's full stop.
            let rest = location.1.trim_start_matches(|c: char| c.is_ascii_digit()).trim_start_matches('.');
            match words.last_mut() {
                Some(last) => last.push_str(rest),
                None => words.push(rest.to_string()),
            }
            continue;
        }
        words.push(token.to_string());
    }
    words.join(" ")
}

impl ZenohTransport {
    /// Opens a zenoh session as `config` says. A listening session fails at once if its port is
    /// taken; a connecting peer returns without waiting and keeps retrying in the background
    /// (see [`ZenohTransport::wait_for_announcement`]); a connecting client fails at once if
    /// nothing listens.
    pub fn open(config: &ZenohConfig) -> Result<Self, BusError> {
        let settings = config.zenoh_settings().map_err(|e| BusError::Transport(e.to_string()))?;
        let mut zenoh_config = zenoh::Config::default();
        for (path, value) in &settings {
            zenoh_config
                .insert_json5(path, value)
                .map_err(|e| failure(&format!("setting `{path}` to `{value}`"), e))?;
        }
        let endpoints: Vec<String> =
            config.listen.iter().chain(&config.connect).map(ToString::to_string).collect();
        let session = zenoh::open(zenoh_config).wait().map_err(|e| {
            failure(&format!("opening a {} session on {}", config.mode, endpoints.join(", ")), e)
        })?;
        Ok(Self { session, publishers: HashMap::new(), subscriptions: Vec::new(), tokens: Vec::new() })
    }

    /// This session's zenoh id (for logs).
    pub fn id(&self) -> String {
        self.session.zid().to_string()
    }

    /// How many peers and routers this session is linked with now (clients linked to a router
    /// are not counted: zenoh does not report them).
    pub fn linked_nodes(&self) -> usize {
        let info = self.session.info();
        info.peers_zid().wait().count() + info.routers_zid().wait().count()
    }

    fn subscription(&self, id: SubscriptionId) -> Result<&Subscription, BusError> {
        self.subscriptions.get(id.0 as usize).ok_or(BusError::UnknownSubscription(id.0))
    }

    /// Blocks until at least one sample has arrived for a subscription, then takes every sample
    /// that has arrived, oldest first; an error names the subscription if none came in time.
    pub fn wait_for(&mut self, id: SubscriptionId, timeout: Duration) -> Result<Vec<Sample>, BusError> {
        let subscription = self.subscription(id)?;
        let first = subscription.queue.recv_timeout(timeout).map_err(|_| {
            let what = match &subscription.filter {
                TopicFilter::Exact(name) => format!("`{name}`"),
                TopicFilter::All => "every topic".to_string(),
            };
            BusError::Transport(format!(
                "zenoh: no sample on subscription {} ({what}) within {:.3} s",
                id.0,
                timeout.as_secs_f64()
            ))
        })?;
        let mut samples = vec![first];
        samples.extend(subscription.queue.try_iter());
        Ok(samples)
    }

    /// Blocks until another session has a subscription that receives `topic` (an exact one or
    /// an `All`), so that what is published next reaches it. With several remote subscribers
    /// this returns at the first; use [`ZenohTransport::wait_for_announcement`] to wait for a
    /// particular process.
    pub fn wait_for_subscriber(&mut self, topic: &str, timeout: Duration) -> Result<(), BusError> {
        let key = topic_key(topic)?;
        let action = format!("waiting for a subscriber of `{topic}`");
        // A probe that only sees other sessions: the transport's own subscriptions must not
        // count as a remote reader.
        let probe = self
            .session
            .declare_publisher(key)
            .allowed_destination(Locality::Remote)
            .wait()
            .map_err(|e| failure(&action, e))?;
        let (tx, rx) = mpsc::channel();
        let _listener = probe
            .matching_listener()
            .callback(move |status| {
                if status.matching() {
                    // The receiver is gone only once this wait is over.
                    let _ = tx.send(());
                }
            })
            .wait()
            .map_err(|e| failure(&action, e))?;
        // Checked after the listener exists, so a subscriber appearing in between is not missed.
        if probe.matching_status().wait().map_err(|e| failure(&action, e))?.matching() {
            return Ok(());
        }
        rx.recv_timeout(timeout).map_err(|_| {
            BusError::Transport(format!(
                "zenoh: no other session subscribed to `{topic}` within {:.3} s",
                timeout.as_secs_f64()
            ))
        })
    }

    /// Tells every linked session that this process is ready under a node name (`/rover`,
    /// `/sim`): call it after subscribing, so a process that sees the announcement knows those
    /// subscriptions too. It lasts until the transport is dropped or the process dies.
    pub fn announce(&mut self, node: &str) -> Result<(), BusError> {
        let key = format!("{READY_PREFIX}/{}", topic_key(node)?);
        let token = self
            .session
            .liveliness()
            .declare_token(key)
            .wait()
            .map_err(|e| failure(&format!("announcing `{node}`"), e))?;
        self.tokens.push(token);
        Ok(())
    }

    /// Blocks until a session (this one or another) has announced `node` with
    /// [`ZenohTransport::announce`]: the handshake before a lockstep exchange.
    pub fn wait_for_announcement(&mut self, node: &str, timeout: Duration) -> Result<(), BusError> {
        let key = format!("{READY_PREFIX}/{}", topic_key(node)?);
        let action = format!("waiting for `{node}`");
        let (tx, rx) = mpsc::channel();
        // `history` replays tokens already alive, so an announcement made before this call counts.
        let _watch = self
            .session
            .liveliness()
            .declare_subscriber(key)
            .history(true)
            .callback(move |sample| {
                if sample.kind() == SampleKind::Put {
                    // The receiver is gone only once this wait is over.
                    let _ = tx.send(());
                }
            })
            .wait()
            .map_err(|e| failure(&action, e))?;
        rx.recv_timeout(timeout).map_err(|_| {
            BusError::Transport(format!(
                "zenoh: `{node}` did not announce itself within {:.3} s",
                timeout.as_secs_f64()
            ))
        })
    }

    /// The cached publisher of a topic, declared on first use.
    fn publisher(&mut self, topic: &str) -> Result<&Publisher<'static>, BusError> {
        if !self.publishers.contains_key(topic) {
            let publisher = self
                .session
                .declare_publisher(topic_key(topic)?)
                // Lockstep needs every message: wait for room instead of dropping the sample.
                .congestion_control(CongestionControl::Block)
                .wait()
                .map_err(|e| failure(&format!("declaring a publisher of `{topic}`"), e))?;
            self.publishers.insert(topic.to_string(), publisher);
        }
        Ok(&self.publishers[topic])
    }
}

impl Transport for ZenohTransport {
    fn publish(&mut self, topic: &str, payload: &[u8]) -> Result<(), BusError> {
        check_topic_name(topic)?;
        self.publisher(topic)?
            .put(payload.to_vec())
            .wait()
            .map_err(|e| failure(&format!("publishing on `{topic}`"), e))
    }

    fn subscribe(&mut self, filter: TopicFilter) -> Result<SubscriptionId, BusError> {
        let key = filter_key(&filter)?;
        let (tx, queue) = mpsc::channel();
        let subscriber = self
            .session
            .declare_subscriber(key)
            .callback(move |sample| {
                if sample.kind() != SampleKind::Put {
                    return;
                }
                // Keys of other zenoh applications sharing the network are not rovernav topics.
                if let Some(topic) = key_topic(sample.key_expr().as_str()) {
                    let payload = sample.payload().to_bytes().into_owned();
                    // The receiver is gone only while the transport is being dropped.
                    let _ = tx.send(Sample { topic, payload });
                }
            })
            .wait()
            .map_err(|e| failure("declaring a subscriber", e))?;
        self.subscriptions.push(Subscription { filter, queue, _subscriber: subscriber });
        Ok(SubscriptionId(self.subscriptions.len() as u64 - 1))
    }

    fn receive(&mut self, id: SubscriptionId) -> Result<Vec<Sample>, BusError> {
        Ok(self.subscription(id)?.queue.try_iter().collect())
    }

    fn is_synchronous(&self) -> bool {
        false
    }
}

#[cfg(test)]
mod tests {
    use super::one_line;

    #[test]
    fn zenoh_source_locations_are_dropped_from_messages() {
        let raw = "bind tcp/127.0.0.1:1: [127.0.0.1:1: Address already in use (os error 98) at \
                   /r/zenoh-link-commons/src/tcp.rs:61.] at /r/zenoh-link-tcp/src/unicast.rs:338.";
        assert_eq!(
            one_line(raw),
            "bind tcp/127.0.0.1:1: [127.0.0.1:1: Address already in use (os error 98)]"
        );
        assert_eq!(one_line("look at\nthe port"), "look at the port");
    }
}
