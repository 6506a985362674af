//! The Foxglove WebSocket server driven over loopback by a minimal client (std only, RFC 6455
//! framing with client masking): what a live client receives is what the MCAP log holds, byte
//! for byte, and valid against the advertised schema; no token, no subprotocol or a bad message
//! is refused without disturbing the other clients.

use rovernav_console::Hub;
use rovernav_console::foxglove::{SUBPROTOCOL, router};
use rovernav_console::server::Server;
use rovernav_executive::{Run, RunSettings};
use rovernav_harness::{JudgedRun, long_yard_world};
use rovernav_telemetry::schema::check;
use rovernav_telemetry::{TelemetryRecorder, mcap};
use serde_json::{Value, json};
use std::io::{BufRead, BufReader, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// The console tests' client, for its frame encoder.
mod console_client;

const TOKEN: &str = "fox-token_42";

/// A server frame.
#[derive(Debug)]
enum Frame {
    Text(Value),
    Binary(Vec<u8>),
    Close(u16),
}

/// A WebSocket client connection.
struct Client {
    stream: BufReader<TcpStream>,
}

/// Sends an upgrade request; gives the status line's code, the response headers and the stream.
fn handshake(addr: SocketAddr, path: &str, protocol: Option<&str>) -> (u16, String, BufReader<TcpStream>) {
    let mut stream = TcpStream::connect(addr).unwrap();
    stream.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
    let protocol = protocol.map(|p| format!("Sec-WebSocket-Protocol: {p}\r\n")).unwrap_or_default();
    let request = format!(
        "GET {path} HTTP/1.1\r\nHost: {addr}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n\
         Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n{protocol}\r\n"
    );
    stream.write_all(request.as_bytes()).unwrap();
    let mut reader = BufReader::new(stream);
    let mut headers = String::new();
    loop {
        let mut line = String::new();
        if reader.read_line(&mut line).unwrap() == 0 || line == "\r\n" {
            break;
        }
        headers.push_str(&line);
    }
    let code = headers.split_whitespace().nth(1).and_then(|c| c.parse().ok()).unwrap_or(0);
    (code, headers, reader)
}

impl Client {
    fn connect(addr: SocketAddr) -> Self {
        let (code, headers, stream) = handshake(addr, &format!("/?token={TOKEN}"), Some(SUBPROTOCOL));
        assert_eq!(code, 101, "{headers}");
        assert!(
            headers.to_ascii_lowercase().contains(&format!("sec-websocket-protocol: {SUBPROTOCOL}")),
            "{headers}"
        );
        Self { stream }
    }

    fn send_text(&mut self, text: &str) {
        let frame = console_client::masked_frame(1, text.as_bytes());
        self.stream.get_mut().write_all(&frame).unwrap();
    }

    fn send(&mut self, v: &Value) {
        self.send_text(&v.to_string());
    }

    fn recv(&mut self) -> Frame {
        loop {
            let mut head = [0u8; 2];
            self.stream.read_exact(&mut head).unwrap();
            let mut len = u64::from(head[1] & 0x7f);
            if len == 126 {
                let mut b = [0u8; 2];
                self.stream.read_exact(&mut b).unwrap();
                len = u64::from(u16::from_be_bytes(b));
            } else if len == 127 {
                let mut b = [0u8; 8];
                self.stream.read_exact(&mut b).unwrap();
                len = u64::from_be_bytes(b);
            }
            let mut payload = vec![0u8; len as usize];
            self.stream.read_exact(&mut payload).unwrap();
            match head[0] & 0x0f {
                1 => return Frame::Text(serde_json::from_slice(&payload).unwrap()),
                2 => return Frame::Binary(payload),
                8 => return Frame::Close(payload.get(..2).map_or(0, |b| u16::from_be_bytes([b[0], b[1]]))),
                _ => continue,
            }
        }
    }

    /// Text messages until one with `op`.
    fn until_op(&mut self, op: &str) -> Value {
        loop {
            if let Frame::Text(v) = self.recv()
                && v["op"] == op
            {
                return v;
            }
        }
    }
}

fn settings() -> RunSettings {
    RunSettings {
        navigator: "astar-grid".into(),
        localizer: "dead-reckoning".into(),
        seed: 2,
        time_limit_s: 3600.0,
        max_cycles: 400,
        name: "foxglove-live".into(),
        navigator_params: Default::default(),
    }
}

/// Decodes a message-data frame: (subscription, timestamp, payload).
fn data(frame: &[u8]) -> (u32, u64, &[u8]) {
    assert_eq!(frame[0], 0x01, "message data opcode");
    let sub = u32::from_le_bytes(frame[1..5].try_into().unwrap());
    let t = u64::from_le_bytes(frame[5..13].try_into().unwrap());
    (sub, t, &frame[13..])
}

#[test]
fn a_live_client_receives_what_the_log_holds_and_bad_clients_are_refused_alone() {
    let hub = Hub::new(1 << 16);
    let dir = std::env::temp_dir().join(format!("rovernav-foxglove-live-{}", std::process::id()));
    let log = dir.join("telemetry.mcap");
    let recorder = TelemetryRecorder::create_with_tee(&log, hub.sink()).unwrap();
    let server = Server::new().unwrap();
    let addr =
        server.serve("127.0.0.1:0".parse().unwrap(), router(Arc::clone(&hub), Arc::from(TOKEN))).unwrap();

    // Refusals: no token, a wrong token, no subprotocol.
    assert_eq!(handshake(addr, "/", Some(SUBPROTOCOL)).0, 401);
    assert_eq!(handshake(addr, "/?token=wrong", Some(SUBPROTOCOL)).0, 401);
    assert_eq!(handshake(addr, &format!("/?token={TOKEN}"), None).0, 400);

    // A watcher: server info, then the channels the recorder declared, with their schemas.
    let mut client = Client::connect(addr);
    let info = client.until_op("serverInfo");
    assert_eq!(info["name"], "rovernav");
    let ad = client.until_op("advertise");
    let channels = ad["channels"].as_array().unwrap();
    let tf = channels.iter().find(|c| c["topic"] == "/tf").expect("/tf advertised");
    assert_eq!((tf["encoding"].as_str(), tf["schemaEncoding"].as_str()), (Some("json"), Some("jsonschema")));
    assert_eq!(tf["schemaName"], "foxglove.FrameTransform");
    let tf_schema: Value = serde_json::from_str(tf["schema"].as_str().unwrap()).unwrap();
    client.send(&json!({"op": "subscribe", "subscriptions": [{"id": 9, "channelId": tf["id"]}]}));

    // A hostile client: malformed JSON closes it (1007), after a status error.
    let mut hostile = Client::connect(addr);
    hostile.until_op("advertise");
    hostile.send_text("{\"op\": \"subscribe\", \"subscriptions\": [oops");
    let status = hostile.until_op("status");
    assert_eq!(status["level"], 2);
    assert!(matches!(hostile.recv(), Frame::Close(1007)));

    // The run, logged with the hub as its tee.
    let mut recorder = recorder;
    let run = std::thread::spawn(move || {
        let out = Run::new(long_yard_world(2, 4.0, 3.0, 1.0), settings())
            .judged()
            .observer(&mut recorder)
            .execute();
        recorder.finish().unwrap();
        out.unwrap().report
    });
    let report = run.join().unwrap();
    let logged: Vec<Vec<u8>> = mcap::MessageStream::new(&std::fs::read(&log).unwrap())
        .unwrap()
        .map(Result::unwrap)
        .filter(|m| m.channel.topic == "/tf")
        .map(|m| m.data.into_owned())
        .collect();
    assert_eq!(logged.len() as u64, report.cycles + 1);
    let mut received = Vec::new();
    let mut last_t = 0;
    let deadline = Instant::now() + Duration::from_secs(30);
    while received.len() < logged.len() && Instant::now() < deadline {
        if let Frame::Binary(frame) = client.recv() {
            let (sub, t, payload) = data(&frame);
            assert_eq!(sub, 9);
            assert!(t >= last_t, "receive times in log order");
            last_t = t;
            check(&tf_schema, &serde_json::from_slice(payload).unwrap()).unwrap();
            received.push(payload.to_vec());
        }
    }
    assert_eq!(received, logged, "every /tf message, as the log holds it");

    // Unsubscribed: a later message on /tf is not sent; a new channel is advertised at once.
    client.send(&json!({"op": "unsubscribe", "subscriptionIds": [9]}));
    std::thread::sleep(Duration::from_millis(200));
    hub.publish("/tf", u64::MAX, b"{}");
    hub.declare("/late", "late.Topic", &json!({"type": "object", "title": "late.Topic"}));
    match client.recv() {
        Frame::Text(v) => {
            assert_eq!(v["op"], "advertise", "{v}");
            assert_eq!(v["channels"][0]["topic"], "/late");
        }
        other => panic!("expected the new channel's advertisement, got {other:?}"),
    }
    // A late subscriber gets the channel's latest message at once.
    let mut late = Client::connect(addr);
    let ad = late.until_op("advertise");
    let world =
        ad["channels"].as_array().unwrap().iter().find(|c| c["topic"] == "/sim/world").unwrap().clone();
    late.send(&json!({"op": "subscribe", "subscriptions": [{"id": 1, "channelId": world["id"]}]}));
    match late.recv() {
        Frame::Binary(frame) => {
            let (sub, _, payload) = data(&frame);
            assert_eq!(sub, 1);
            let schema: Value = serde_json::from_str(world["schema"].as_str().unwrap()).unwrap();
            check(&schema, &serde_json::from_slice(payload).unwrap()).unwrap();
        }
        other => panic!("expected the latest world, got {other:?}"),
    }
    let _ = std::fs::remove_dir_all(&dir);
}
