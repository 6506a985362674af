//! One console WebSocket connection: the run's telemetry and the console's notices out, the
//! client's commands in.
//!
//! Messages out are JSON objects with a `type`: `hello` (the client's id, the authority holder,
//! the phase, the `help` text for completion, the replay's span), `channel` (a topic), `msg` (one
//! logged message: `ch`, `t` in ns, `data` as logged), `lagged`, `command`, `reply`, `error`,
//! `authority`, `phase`, and in replay `reset` and `time`. Messages in: `command` (`line`),
//! `take_control`, `release`, `plan` (`goal`, `waypoints`, `keep_out`), and in replay `seek`
//! (`t_ns`), `play` (`speed`), `pause`. A message that is not one of these, larger than 64 KiB,
//! binary, or beyond the rate limit closes that connection and only that one.

use crate::hub::{Channel, Event, Message};
use crate::operator::{Notice, Phase, Plan};
use crate::replay::ReplayLog;
use crate::server::AppState;
use crate::server_history::shown;
use axum::extract::ws::{CloseFrame, Message as WsMessage, WebSocket, close_code};
use serde::Deserialize;
use serde_json::json;
use std::sync::Arc;
use std::time::{Duration, Instant};
use tokio::sync::broadcast::error::RecvError;

/// Messages a client may send per second, sustained.
pub const RATE_PER_S: f64 = 20.0;
/// Messages a client may send in a burst.
pub const BURST: f64 = 40.0;

/// A message from a client.
#[derive(Debug, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
enum ClientMsg {
    Command { line: String },
    TakeControl,
    Release,
    Plan(Plan),
    Seek { t_ns: u64 },
    Play { speed: f64 },
    Pause,
}

/// A token bucket: `BURST` messages at once, `RATE_PER_S` sustained.
struct RateLimit {
    tokens: f64,
    at: Instant,
}

impl RateLimit {
    fn allow(&mut self) -> bool {
        let now = Instant::now();
        self.tokens = (self.tokens + (now - self.at).as_secs_f64() * RATE_PER_S).min(BURST);
        self.at = now;
        self.tokens -= 1.0;
        self.tokens >= 0.0
    }
}

fn channel_json(c: &Channel) -> String {
    json!({"type": "channel", "id": c.id, "topic": c.topic, "schema_name": c.schema_name}).to_string()
}

/// A logged message as sent: its JSON is spliced in as logged, never parsed again.
fn message_json(m: &Message) -> String {
    let data = std::str::from_utf8(&m.json).unwrap_or("null");
    format!("{{\"type\":\"msg\",\"ch\":{},\"t\":{},\"data\":{data}}}", m.channel, m.time_ns)
}

fn phase_json(phase: &Phase) -> serde_json::Value {
    let outcome = if let Phase::Done(o) = phase { Some(o.as_str()) } else { None };
    json!({"type": "phase", "phase": phase.name(), "outcome": outcome})
}

/// A notice as sent to `client`, or nothing when it is for someone else.
fn notice_json(notice: &Notice, client: u64) -> Option<String> {
    Some(
        match notice {
            Notice::Command { client: from, line } => {
                json!({"type": "command", "client": from, "line": line})
            }
            Notice::Reply(text) => json!({"type": "reply", "text": text}),
            Notice::Error { client: to, text } if *to == client => json!({"type": "error", "text": text}),
            Notice::Error { .. } => return None,
            Notice::Authority(holder) => json!({"type": "authority", "holder": holder}),
            Notice::Phase(phase) => phase_json(phase),
        }
        .to_string(),
    )
}

/// The outgoing side of a connection; a send fails once the client is gone.
struct Peer {
    socket: WebSocket,
    /// Shown channel ids (index id - 1).
    shown: Vec<bool>,
}

impl Peer {
    async fn send(&mut self, text: String) -> Result<(), ()> {
        self.socket.send(WsMessage::Text(text.into())).await.map_err(|_| ())
    }

    async fn channel(&mut self, c: &Channel) -> Result<(), ()> {
        let index = c.id as usize - 1;
        if self.shown.len() <= index {
            self.shown.resize(index + 1, false);
        }
        self.shown[index] = shown(&c.topic);
        if self.shown[index] { self.send(channel_json(c)).await } else { Ok(()) }
    }

    async fn message(&mut self, m: &Message) -> Result<(), ()> {
        if self.shown.get(m.channel as usize - 1).copied().unwrap_or(false) {
            self.send(message_json(m)).await
        } else {
            Ok(())
        }
    }

    /// Forwards one hub event (a skip is reported as `lagged`).
    async fn event(&mut self, event: Result<Event, RecvError>) -> Result<(), ()> {
        match event {
            Ok(Event::Channel(c)) => self.channel(&c).await,
            Ok(Event::Message(m)) => self.message(&m).await,
            Err(RecvError::Lagged(skipped)) => {
                self.send(json!({"type": "lagged", "skipped": skipped}).to_string()).await
            }
            Err(RecvError::Closed) => Ok(()),
        }
    }

    /// Sends a close frame, then reads (and drops) what the client still sends until it closes
    /// too or a second has passed: closing a socket with unread data would reset the connection
    /// and could lose the close frame that says why.
    async fn close(&mut self, code: u16, why: &'static str) {
        let frame = CloseFrame { code, reason: why.into() };
        if self.socket.send(WsMessage::Close(Some(frame))).await.is_err() {
            return;
        }
        let drain = async {
            while let Some(Ok(msg)) = self.socket.recv().await {
                if matches!(msg, WsMessage::Close(_)) {
                    break;
                }
            }
        };
        let _ = tokio::time::timeout(Duration::from_secs(1), drain).await;
    }
}

/// What reading the client gave.
enum Incoming {
    Msg(ClientMsg),
    /// Nothing to act on (a ping, a pong).
    Nothing,
    /// The client left.
    Gone,
    /// Close the connection with this code and reason.
    Bad(u16, &'static str),
}

fn read(item: Option<Result<WsMessage, axum::Error>>, limit: &mut RateLimit) -> Incoming {
    let text = match item {
        None | Some(Err(_)) | Some(Ok(WsMessage::Close(_))) => return Incoming::Gone,
        Some(Ok(WsMessage::Ping(_) | WsMessage::Pong(_))) => return Incoming::Nothing,
        Some(Ok(WsMessage::Binary(_))) => return Incoming::Bad(close_code::UNSUPPORTED, "binary message"),
        Some(Ok(WsMessage::Text(text))) => text,
    };
    if !limit.allow() {
        return Incoming::Bad(close_code::POLICY, "too many messages");
    }
    if text.len() > crate::server::MAX_CLIENT_MESSAGE {
        return Incoming::Bad(close_code::SIZE, "message too large");
    }
    match serde_json::from_str(text.as_str()) {
        Ok(msg) => Incoming::Msg(msg),
        Err(_) => Incoming::Bad(close_code::INVALID, "malformed message"),
    }
}

/// Serves one client until it leaves or misbehaves.
pub async fn client(socket: WebSocket, state: Arc<AppState>) {
    let console = Arc::clone(&state.console);
    let mut notices = console.subscribe();
    let id = console.connect();
    let mut peer = Peer { socket, shown: Vec::new() };
    let replay = state.replay.clone();
    let hello = json!({
        "type": "hello",
        "client": id,
        "holder": console.holder(),
        "phase": phase_json(&console.phase()),
        "help": rovernav_executive::help_text(None).unwrap_or_default(),
        "replay": replay.as_ref().map(|r| json!({"start_ns": r.start_ns(), "end_ns": r.end_ns()})),
        "rate_per_s": RATE_PER_S,
    });
    if peer.send(hello.to_string()).await.is_ok() {
        let end = match replay {
            Some(log) => serve_replay(&mut peer, &log, &mut notices, id, &state).await,
            None => serve_live(&mut peer, &mut notices, id, &state).await,
        };
        if let Some((code, why)) = end {
            peer.close(code, why).await;
        }
    }
    console.disconnect(id);
}

/// Acts on a client's message (replay's own messages are handled by the replay loop).
fn act(msg: ClientMsg, id: u64, state: &AppState) {
    match msg {
        ClientMsg::Command { line } => state.console.command(id, &line),
        ClientMsg::TakeControl => state.console.take_control(id),
        ClientMsg::Release => state.console.release(id),
        ClientMsg::Plan(plan) => state.console.plan(id, plan),
        ClientMsg::Seek { .. } | ClientMsg::Play { .. } | ClientMsg::Pause => {
            state.console.refuse(id, "seek, play and pause are for a replay")
        }
    }
}

type Notices = tokio::sync::broadcast::Receiver<Notice>;

/// The live run: the run so far, then everything the hub publishes; `None` when the client left.
async fn serve_live(
    peer: &mut Peer,
    notices: &mut Notices,
    id: u64,
    state: &AppState,
) -> Option<(u16, &'static str)> {
    let (channels, messages, mut events) = state.history.join();
    for c in &channels {
        peer.channel(c).await.ok()?;
    }
    for m in &messages {
        peer.message(m).await.ok()?;
    }
    let mut limit = RateLimit { tokens: BURST, at: Instant::now() };
    loop {
        let sent = tokio::select! {
            event = events.recv() => match event {
                Err(RecvError::Closed) => return None,
                event => peer.event(event).await,
            },
            notice = notices.recv() => match notice {
                Ok(n) => {
                    if matches!(n, Notice::Phase(_)) {
                        // The run's last messages before the news that it ended.
                        while let Ok(event) = events.try_recv() {
                            peer.event(Ok(event)).await.ok()?;
                        }
                    }
                    match notice_json(&n, id) { Some(text) => peer.send(text).await, None => Ok(()) }
                }
                Err(RecvError::Lagged(_)) => Ok(()),
                Err(RecvError::Closed) => return None,
            },
            incoming = peer.socket.recv() => match read(incoming, &mut limit) {
                Incoming::Msg(msg) => { act(msg, id, state); Ok(()) }
                Incoming::Nothing => Ok(()),
                Incoming::Gone => return None,
                Incoming::Bad(code, why) => return Some((code, why)),
            },
        };
        sent.ok()?;
    }
}

/// A replay: the log's state at the play head, moved by `seek` and `play`.
async fn serve_replay(
    peer: &mut Peer,
    log: &ReplayLog,
    notices: &mut Notices,
    id: u64,
    state: &AppState,
) -> Option<(u16, &'static str)> {
    for c in &log.channels {
        peer.channel(c).await.ok()?;
    }
    let (start, end) = (log.start_ns(), log.end_ns());
    let mut head = end;
    let mut playing: Option<f64> = None;
    let time = |head: u64, playing: Option<f64>| {
        json!({"type": "time", "t_ns": head, "playing": playing.is_some(), "speed": playing}).to_string()
    };
    for m in log.state_at(head) {
        peer.message(&m).await.ok()?;
    }
    peer.send(time(head, playing)).await.ok()?;
    let mut limit = RateLimit { tokens: BURST, at: Instant::now() };
    let tick = Duration::from_millis(100);
    let mut ticker = tokio::time::interval(tick);
    loop {
        let sent = tokio::select! {
            _ = ticker.tick(), if playing.is_some() => {
                let speed = playing.unwrap_or(1.0);
                let next = (head as f64 + speed * tick.as_secs_f64() * 1e9).min(end as f64) as u64;
                for m in &log.messages[log.count_upto(head)..log.count_upto(next)] {
                    peer.message(m).await.ok()?;
                }
                head = next;
                if head >= end {
                    playing = None;
                }
                peer.send(time(head, playing)).await
            },
            notice = notices.recv() => match notice {
                Ok(n) => match notice_json(&n, id) { Some(text) => peer.send(text).await, None => Ok(()) },
                Err(_) => Ok(()),
            },
            incoming = peer.socket.recv() => match read(incoming, &mut limit) {
                Incoming::Msg(ClientMsg::Seek { t_ns }) => {
                    head = t_ns.clamp(start, end);
                    peer.send(json!({"type": "reset"}).to_string()).await.ok()?;
                    for m in log.state_at(head) {
                        peer.message(&m).await.ok()?;
                    }
                    peer.send(time(head, playing)).await
                }
                Incoming::Msg(ClientMsg::Play { speed }) if speed.is_finite() && speed > 0.0 => {
                    if head >= end {
                        head = start;
                        peer.send(json!({"type": "reset"}).to_string()).await.ok()?;
                        for m in log.state_at(head) {
                            peer.message(&m).await.ok()?;
                        }
                    }
                    playing = Some(speed.min(1000.0));
                    peer.send(time(head, playing)).await
                }
                Incoming::Msg(ClientMsg::Pause) => {
                    playing = None;
                    peer.send(time(head, playing)).await
                }
                Incoming::Msg(msg) => { act(msg, id, state); Ok(()) }
                Incoming::Nothing => Ok(()),
                Incoming::Gone => return None,
                Incoming::Bad(code, why) => return Some((code, why)),
            },
        };
        sent.ok()?;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn client_messages_parse_strictly() {
        let ok = |s: &str| serde_json::from_str::<ClientMsg>(s).is_ok();
        assert!(ok(r#"{"type":"command","line":"status"}"#));
        assert!(ok(r#"{"type":"take_control"}"#));
        assert!(ok(r#"{"type":"plan","goal":[1,2],"waypoints":[[3,4]]}"#));
        assert!(ok(r#"{"type":"seek","t_ns":5}"#));
        assert!(!ok(r#"{"type":"command","line":"status","extra":1}"#));
        assert!(!ok(r#"{"type":"launch"}"#));
        assert!(!ok(r#"{"type":"command"}"#));
        assert!(!ok(r#"{"type":"plan","goal":[1]}"#));
        assert!(!ok(r#"[1,2]"#));
        assert!(!ok("not json"));
    }

    #[test]
    fn the_rate_limit_allows_a_burst_then_the_sustained_rate() {
        let mut limit = RateLimit { tokens: BURST, at: Instant::now() };
        let allowed = (0..1000).filter(|_| limit.allow()).count();
        assert!((BURST as usize..BURST as usize + 2).contains(&allowed), "{allowed}");
    }

    #[test]
    fn logged_json_is_spliced_in_unchanged() {
        let m = Message { channel: 3, time_ns: 7, json: Arc::from(&b"{\"x\":1.5}"[..]) };
        let v: serde_json::Value = serde_json::from_str(&message_json(&m)).unwrap();
        assert_eq!(v, json!({"type": "msg", "ch": 3, "t": 7, "data": {"x": 1.5}}));
        assert!(shown("/sim/truth") && shown("/bus/system/status") && !shown("/bus/navigation/plan"));
    }
}
