//! The Foxglove WebSocket protocol (`foxglove.websocket.v1`), the subset a viewer needs to
//! watch a run live: Foxglove or Lichtblick connects to `ws://HOST:PORT/?token=TOKEN` and shows
//! the topics and schemas of the MCAP log (docs/telemetry.md) as they are written.
//!
//! Protocol (<https://github.com/foxglove/ws-protocol>, spec v1): on connection the server
//! sends `serverInfo` and an `advertise` of every channel (`id`, `topic`, `encoding` "json",
//! `schemaName`, `schema` as a string, `schemaEncoding` "jsonschema"), and advertises each new
//! channel as the log declares it. The client sends `subscribe` (`subscriptions: [{id,
//! channelId}]`) and `unsubscribe` (`subscriptionIds`); each message of a subscribed channel
//! goes out as a binary frame: opcode `0x01`, the subscription id (u32 LE), the receive
//! timestamp (u64 LE, ns; here the log time, simulated) and the JSON payload. On subscribing,
//! the channel's latest message is sent at once (a late viewer still gets the world).
//!
//! Departures, each for the reason given: no capabilities are advertised (no client publish,
//! parameters, services or time: the run is watched, never driven, from here); a client that
//! falls behind skips messages (told by a `status` warning) rather than slowing the run; a
//! malformed, binary, oversized or unknown client message gets a `status` error and closes
//! that connection only (the spec only asks for the status; closing bounds what a hostile
//! client costs).

use crate::auth;
use crate::hub::{Channel, Event, Hub, Message};
use axum::Router;
use axum::extract::ws::{CloseFrame, Message as WsMessage, WebSocket, WebSocketUpgrade, close_code};
use axum::extract::{RawQuery, State};
use axum::http::{HeaderMap, StatusCode, header};
use axum::response::{IntoResponse, Response};
use axum::routing::get;
use serde::Deserialize;
use serde_json::{Value, json};
use std::collections::HashMap;
use std::sync::Arc;
use tokio::sync::broadcast::error::RecvError;

/// The WebSocket subprotocol.
pub const SUBPROTOCOL: &str = "foxglove.websocket.v1";
/// Largest client message accepted (bytes): subscriptions are small.
pub const MAX_CLIENT_MESSAGE: usize = 64 * 1024;
/// Most subscriptions one client may hold.
pub const MAX_SUBSCRIPTIONS: usize = 4096;
/// The opcode of a binary message-data frame.
pub const MESSAGE_DATA: u8 = 0x01;

struct Served {
    hub: Arc<Hub>,
    token: Arc<str>,
}

/// The Foxglove server's routes: the WebSocket upgrade at `/`, which needs the access token
/// (`?token=`, or `Authorization: Bearer`) and the `foxglove.websocket.v1` subprotocol; 401
/// without the token, 400 without the subprotocol.
pub fn router(hub: Arc<Hub>, token: Arc<str>) -> Router {
    Router::new().route("/", get(upgrade)).with_state(Arc::new(Served { hub, token }))
}

async fn upgrade(
    State(served): State<Arc<Served>>,
    headers: HeaderMap,
    RawQuery(query): RawQuery,
    ws: Result<WebSocketUpgrade, axum::extract::ws::rejection::WebSocketUpgradeRejection>,
) -> Response {
    let authorization = headers.get(header::AUTHORIZATION).and_then(|h| h.to_str().ok());
    let authorised = auth::presented_token(authorization, query.as_deref())
        .is_some_and(|t| auth::same_token(t, &served.token));
    if !authorised {
        return (StatusCode::UNAUTHORIZED, "401: the access token is missing or wrong (?token=)\n")
            .into_response();
    }
    let offered = headers
        .get_all(header::SEC_WEBSOCKET_PROTOCOL)
        .iter()
        .filter_map(|h| h.to_str().ok())
        .flat_map(|h| h.split(','))
        .any(|p| p.trim() == SUBPROTOCOL);
    if !offered {
        return (
            StatusCode::BAD_REQUEST,
            format!("400: the WebSocket subprotocol {SUBPROTOCOL} is required\n"),
        )
            .into_response();
    }
    match ws {
        Ok(ws) => {
            let hub = Arc::clone(&served.hub);
            ws.protocols([SUBPROTOCOL])
                .max_message_size(MAX_CLIENT_MESSAGE)
                .max_frame_size(MAX_CLIENT_MESSAGE)
                .on_upgrade(move |socket| serve(socket, hub))
        }
        Err(rejection) => rejection.into_response(),
    }
}

/// What a client may send.
#[derive(Deserialize)]
#[serde(tag = "op", rename_all = "camelCase", deny_unknown_fields)]
enum ClientOp {
    Subscribe {
        subscriptions: Vec<Subscription>,
    },
    Unsubscribe {
        #[serde(rename = "subscriptionIds")]
        subscription_ids: Vec<u32>,
    },
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Subscription {
    id: u32,
    #[serde(rename = "channelId")]
    channel_id: u32,
}

/// An `advertise` of channels.
pub fn advertise(channels: &[Arc<Channel>]) -> String {
    let channels: Vec<Value> = channels
        .iter()
        .map(|c| {
            json!({
                "id": c.id,
                "topic": c.topic,
                "encoding": "json",
                "schemaName": c.schema_name,
                "schema": c.schema.to_string(),
                "schemaEncoding": "jsonschema",
            })
        })
        .collect();
    json!({"op": "advertise", "channels": channels}).to_string()
}

/// A binary message-data frame.
pub fn message_data(subscription: u32, message: &Message) -> Vec<u8> {
    let mut frame = Vec::with_capacity(13 + message.json.len());
    frame.push(MESSAGE_DATA);
    frame.extend_from_slice(&subscription.to_le_bytes());
    frame.extend_from_slice(&message.time_ns.to_le_bytes());
    frame.extend_from_slice(&message.json);
    frame
}

fn status(level: u8, message: &str) -> String {
    json!({"op": "status", "level": level, "message": message}).to_string()
}

/// One client's subscriptions: subscription id -> channel id.
#[derive(Default)]
struct Subscriptions {
    by_id: HashMap<u32, u32>,
}

impl Subscriptions {
    fn of_channel(&self, channel: u32) -> impl Iterator<Item = u32> + '_ {
        self.by_id.iter().filter(move |(_, c)| **c == channel).map(|(s, _)| *s)
    }
}

/// Why a connection ends.
enum End {
    /// The client left or the socket failed.
    Gone,
    /// The client misbehaved: close with this code and reason.
    Bad(u16, String),
}

/// Serves one client until it leaves or misbehaves.
async fn serve(mut socket: WebSocket, hub: Arc<Hub>) {
    if let End::Bad(code, why) = session(&mut socket, &hub).await {
        let _ = socket.send(WsMessage::Text(status(2, &why).into())).await;
        let frame = CloseFrame { code, reason: why.chars().take(100).collect::<String>().into() };
        let _ = socket.send(WsMessage::Close(Some(frame))).await;
    }
}

async fn send_text(socket: &mut WebSocket, text: String) -> Result<(), End> {
    socket.send(WsMessage::Text(text.into())).await.map_err(|_| End::Gone)
}

async fn session(socket: &mut WebSocket, hub: &Hub) -> End {
    let snapshot = hub.snapshot();
    let mut events = snapshot.events;
    let mut latest: HashMap<u32, Arc<Message>> =
        snapshot.latest.into_iter().map(|m| (m.channel, m)).collect();
    let mut subscriptions = Subscriptions::default();
    let info = json!({
        "op": "serverInfo",
        "name": "rovernav",
        "capabilities": [],
        "supportedEncodings": [],
        "metadata": {},
        "sessionId": format!("rovernav-{}", std::process::id()),
    });
    let opening = async {
        send_text(socket, info.to_string()).await?;
        if !snapshot.channels.is_empty() {
            send_text(socket, advertise(&snapshot.channels)).await?;
        }
        Ok::<(), End>(())
    };
    if let Err(end) = opening.await {
        return end;
    }
    loop {
        let step = tokio::select! {
            event = events.recv() => match event {
                Ok(Event::Channel(c)) => send_text(socket, advertise(&[c])).await,
                Ok(Event::Message(m)) => {
                    latest.insert(m.channel, Arc::clone(&m));
                    send_message(socket, &subscriptions, &m).await
                }
                Err(RecvError::Lagged(skipped)) => {
                    send_text(socket, status(1, &format!("fell behind: {skipped} messages skipped"))).await
                }
                // The run is over and the hub gone: keep the connection until the client leaves.
                Err(RecvError::Closed) => wait_for_close(socket).await,
            },
            incoming = socket.recv() => match incoming {
                None | Some(Err(_)) | Some(Ok(WsMessage::Close(_))) => Err(End::Gone),
                Some(Ok(WsMessage::Ping(_) | WsMessage::Pong(_))) => Ok(()),
                Some(Ok(WsMessage::Binary(_))) => Err(End::Bad(close_code::UNSUPPORTED, "binary client messages are not supported (no clientPublish capability)".into())),
                Some(Ok(WsMessage::Text(text))) => act(socket, text.as_str(), &mut subscriptions, &latest, hub).await,
            },
        };
        if let Err(end) = step {
            return end;
        }
    }
}

async fn wait_for_close(socket: &mut WebSocket) -> Result<(), End> {
    loop {
        match socket.recv().await {
            None | Some(Err(_)) | Some(Ok(WsMessage::Close(_))) => return Err(End::Gone),
            _ => {}
        }
    }
}

async fn send_message(socket: &mut WebSocket, subscriptions: &Subscriptions, m: &Message) -> Result<(), End> {
    let ids: Vec<u32> = subscriptions.of_channel(m.channel).collect();
    for id in ids {
        socket.send(WsMessage::Binary(message_data(id, m).into())).await.map_err(|_| End::Gone)?;
    }
    Ok(())
}

/// Acts on one client text message.
async fn act(
    socket: &mut WebSocket,
    text: &str,
    subscriptions: &mut Subscriptions,
    latest: &HashMap<u32, Arc<Message>>,
    hub: &Hub,
) -> Result<(), End> {
    let op: ClientOp = serde_json::from_str(text).map_err(|e| {
        let shown: String = e.to_string().chars().take(80).collect();
        End::Bad(close_code::INVALID, format!("malformed or unsupported client message: {shown}"))
    })?;
    match op {
        ClientOp::Subscribe { subscriptions: new } => {
            if subscriptions.by_id.len() + new.len() > MAX_SUBSCRIPTIONS {
                return Err(End::Bad(
                    close_code::POLICY,
                    format!("more than {MAX_SUBSCRIPTIONS} subscriptions"),
                ));
            }
            for s in new {
                if subscriptions.by_id.contains_key(&s.id) {
                    send_text(socket, status(2, &format!("subscription {} already exists", s.id))).await?;
                    continue;
                }
                if hub.channel(s.channel_id).is_none() {
                    send_text(socket, status(1, &format!("channel {} is not advertised", s.channel_id)))
                        .await?;
                    continue;
                }
                subscriptions.by_id.insert(s.id, s.channel_id);
                if let Some(m) = latest.get(&s.channel_id) {
                    socket
                        .send(WsMessage::Binary(message_data(s.id, m).into()))
                        .await
                        .map_err(|_| End::Gone)?;
                }
            }
            Ok(())
        }
        ClientOp::Unsubscribe { subscription_ids } => {
            for id in subscription_ids {
                subscriptions.by_id.remove(&id);
            }
            Ok(())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_and_advertisements_follow_the_spec_layout() {
        let m = Message { channel: 3, time_ns: 0x0102_0304_0506_0708, json: Arc::from(&b"{\"a\":1}"[..]) };
        let frame = message_data(0xA0B0_C0D0, &m);
        assert_eq!(frame[0], 0x01);
        assert_eq!(&frame[1..5], &[0xD0, 0xC0, 0xB0, 0xA0], "subscription id, little-endian");
        assert_eq!(&frame[5..13], &[8, 7, 6, 5, 4, 3, 2, 1], "timestamp, little-endian");
        assert_eq!(&frame[13..], b"{\"a\":1}");
        let channel = Arc::new(Channel {
            id: 7,
            topic: "/tf".into(),
            schema_name: "foxglove.FrameTransform".into(),
            schema: json!({"type": "object", "title": "foxglove.FrameTransform"}),
        });
        let ad: Value = serde_json::from_str(&advertise(&[channel])).unwrap();
        assert_eq!(ad["op"], "advertise");
        let c = &ad["channels"][0];
        assert_eq!(
            (c["id"].as_u64(), c["encoding"].as_str(), c["schemaEncoding"].as_str()),
            (Some(7), Some("json"), Some("jsonschema"))
        );
        let schema: Value =
            serde_json::from_str(c["schema"].as_str().expect("the schema is a string")).unwrap();
        assert_eq!(schema["title"], "foxglove.FrameTransform");
    }

    #[test]
    fn client_messages_parse_strictly() {
        let ok: ClientOp =
            serde_json::from_str(r#"{"op":"subscribe","subscriptions":[{"id":1,"channelId":2}]}"#).unwrap();
        assert!(matches!(ok, ClientOp::Subscribe { subscriptions } if subscriptions[0].channel_id == 2));
        let un: ClientOp = serde_json::from_str(r#"{"op":"unsubscribe","subscriptionIds":[1,2]}"#).unwrap();
        assert!(matches!(un, ClientOp::Unsubscribe { subscription_ids } if subscription_ids == [1, 2]));
        for bad in [
            r#"{"op":"advertise","channels":[]}"#,
            r#"{"op":"subscribe","subscriptions":[{"id":-1,"channelId":2}]}"#,
            r#"{"op":"subscribe"}"#,
            r#"{"subscriptions":[]}"#,
            "not json",
        ] {
            assert!(serde_json::from_str::<ClientOp>(bad).is_err(), "{bad}");
        }
    }
}
