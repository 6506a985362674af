//! A minimal HTTP and WebSocket client for the console tests (std only: RFC 6455 framing with
//! client masking), and a console serving a small mission on loopback.

#![allow(dead_code)]

use rovernav_console::live::{self, LiveRun};
use rovernav_console::operator::{Console, Phase};
use rovernav_console::server::{AppState, Server, router};
use rovernav_console::{Hub, hub::DEFAULT_QUEUE};
use rovernav_executive::{Mission, RunOutput};
use serde_json::Value;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::path::PathBuf;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// A 12 m yard with a goal 9 m away: quick in a debug build.
pub const MISSION: &str = r#"
name = "console-test"
seed = 3
navigator = "astar-grid"
localizer = "dead-reckoning"
time_limit_s = 1200.0
[terrain]
kind = "procedural"
size_m = 12.0
resolution_m = 0.05
rock_abundance = 0.08
relief_m = 0.1
slope_deg = 1.0
[start]
x = 2.0
y = 2.0
yaw_deg = 45.0
[goal]
x = 8.5
y = 8.0
tolerance_m = 0.5
"#;

/// The access token the tests use.
pub const TOKEN: &str = "test-token_0123";

/// A console serving a mission run on its own thread.
pub struct Served {
    /// Where it listens.
    pub addr: SocketAddr,
    /// The run: joins with its output.
    pub run: Option<JoinHandle<Result<RunOutput, String>>>,
    _server: Server,
    dir: PathBuf,
}

impl Served {
    /// Serves [`MISSION`]: held for a plan or started at once, paced at `speed` (None: max).
    pub fn start(name: &str, hold: bool, speed: Option<f64>) -> Self {
        let dir = std::env::temp_dir().join(format!("rovernav-console-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let hub = Hub::new(DEFAULT_QUEUE);
        let (console, link) = Console::new(Phase::Waiting);
        let state = AppState::new(TOKEN.into(), hub.clone(), console, None);
        let server = Server::new().unwrap();
        let addr = server.serve("127.0.0.1:0".parse().unwrap(), router(state)).unwrap();
        let config = LiveRun {
            mission: Mission::from_toml(MISSION, "test mission").unwrap(),
            origin: "test mission".into(),
            hold,
            speed,
            log: dir.join("telemetry.mcap"),
        };
        let run = std::thread::spawn(move || live::run(&config, &hub, link));
        Self { addr, run: Some(run), _server: server, dir }
    }

    /// Waits for the run's end and gives its report as JSON.
    pub fn report(&mut self) -> Value {
        let output = self.run.take().unwrap().join().unwrap().unwrap();
        serde_json::to_value(&output.report).unwrap()
    }

    /// The run's telemetry log.
    pub fn log(&self) -> PathBuf {
        self.dir.join("telemetry.mcap")
    }

    /// Connects a WebSocket client with the token.
    pub fn client(&self) -> Ws {
        Ws::connect(self.addr, &format!("/ws?token={TOKEN}")).unwrap()
    }
}

impl Drop for Served {
    fn drop(&mut self) {
        std::fs::remove_dir_all(&self.dir).ok();
    }
}

/// A console replaying a log.
pub fn replay(log: &std::path::Path) -> (Server, SocketAddr) {
    let replay = rovernav_console::replay::ReplayLog::read(log).unwrap();
    let (console, _link) = Console::new(Phase::Replay);
    let state =
        AppState::new(TOKEN.into(), Hub::new(DEFAULT_QUEUE), console, Some(std::sync::Arc::new(replay)));
    let server = Server::new().unwrap();
    let addr = server.serve("127.0.0.1:0".parse().unwrap(), router(state)).unwrap();
    (server, addr)
}

/// The report without the fields that measure wall-clock time (as `cmp` of a run and its replay
/// would also differ there between two runs).
pub fn without_wall_time(mut report: Value) -> Value {
    if let Some(map) = report.as_object_mut() {
        map.remove("wall_time_s");
        map.remove("compute_per_cycle");
    }
    report
}

/// An HTTP GET: the status code and body.
pub fn get(addr: SocketAddr, path: &str, headers: &[(&str, &str)]) -> (u16, String) {
    let mut stream = TcpStream::connect(addr).unwrap();
    let mut request = format!("GET {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n");
    for (name, value) in headers {
        request.push_str(&format!("{name}: {value}\r\n"));
    }
    request.push_str("\r\n");
    stream.write_all(request.as_bytes()).unwrap();
    let mut response = String::new();
    stream.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
    let _ = stream.read_to_string(&mut response);
    let status = response.split_whitespace().nth(1).and_then(|s| s.parse().ok()).unwrap_or(0);
    let body = response.split_once("\r\n\r\n").map_or("", |(_, b)| b).to_string();
    (status, body)
}

/// How a connection ended.
#[derive(Debug, PartialEq)]
pub enum Closed {
    /// A close frame with this code.
    Code(u16),
    /// The server dropped the connection without a close frame.
    Dropped,
}

/// A WebSocket client.
pub struct Ws {
    reader: BufReader<TcpStream>,
    writer: TcpStream,
}

impl Ws {
    /// Opens `path` with the upgrade handshake; the error holds the HTTP status line.
    pub fn connect(addr: SocketAddr, path: &str) -> Result<Self, String> {
        let mut writer = TcpStream::connect(addr).map_err(|e| e.to_string())?;
        let request = format!(
            "GET {path} HTTP/1.1\r\nHost: {addr}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n\
             Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n"
        );
        writer.write_all(request.as_bytes()).map_err(|e| e.to_string())?;
        writer.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
        let mut reader = BufReader::new(writer.try_clone().map_err(|e| e.to_string())?);
        let mut status = String::new();
        reader.read_line(&mut status).map_err(|e| e.to_string())?;
        loop {
            let mut line = String::new();
            reader.read_line(&mut line).map_err(|e| e.to_string())?;
            if line == "\r\n" || line.is_empty() {
                break;
            }
        }
        if !status.contains(" 101 ") {
            return Err(status.trim().to_string());
        }
        Ok(Self { reader, writer })
    }

    /// Sends one frame (masked, as clients must).
    pub fn send_frame(&mut self, opcode: u8, payload: &[u8]) -> std::io::Result<()> {
        self.writer.write_all(&masked_frame(opcode, payload))
    }

    /// Sends a JSON message.
    pub fn send(&mut self, msg: &Value) -> std::io::Result<()> {
        self.send_frame(1, msg.to_string().as_bytes())
    }

    /// The next text message as JSON, or how the connection ended.
    pub fn recv(&mut self) -> Result<Value, Closed> {
        loop {
            let mut head = [0u8; 2];
            self.reader.read_exact(&mut head).map_err(|_| Closed::Dropped)?;
            let len = match head[1] & 0x7f {
                126 => {
                    let mut b = [0u8; 2];
                    self.reader.read_exact(&mut b).map_err(|_| Closed::Dropped)?;
                    u16::from_be_bytes(b) as usize
                }
                127 => {
                    let mut b = [0u8; 8];
                    self.reader.read_exact(&mut b).map_err(|_| Closed::Dropped)?;
                    u64::from_be_bytes(b) as usize
                }
                n => n as usize,
            };
            let mut payload = vec![0u8; len];
            self.reader.read_exact(&mut payload).map_err(|_| Closed::Dropped)?;
            match head[0] & 0x0f {
                1 => return Ok(serde_json::from_slice(&payload).expect("the server sends JSON")),
                8 => {
                    let code = payload.get(..2).map_or(1005, |b| u16::from_be_bytes([b[0], b[1]]));
                    return Err(Closed::Code(code));
                }
                _ => {}
            }
        }
    }

    /// Messages until one satisfies `pred` (returned), or panics after `timeout`.
    pub fn until(&mut self, timeout: Duration, mut pred: impl FnMut(&Value) -> bool) -> Value {
        let deadline = Instant::now() + timeout;
        while Instant::now() < deadline {
            match self.recv() {
                Ok(v) if pred(&v) => return v,
                Ok(_) => {}
                Err(e) => panic!("connection ended while waiting: {e:?}"),
            }
        }
        panic!("nothing matched within {timeout:?}");
    }

    /// Reads until the server ends the connection; how it ended.
    pub fn closed(&mut self) -> Closed {
        loop {
            if let Err(end) = self.recv() {
                return end;
            }
        }
    }
}

/// One final WebSocket frame of `opcode` carrying `payload`, masked as a client must (RFC 6455
/// section 5.2).
pub fn masked_frame(opcode: u8, payload: &[u8]) -> Vec<u8> {
    let mut frame = vec![0x80 | opcode];
    match payload.len() {
        n if n < 126 => frame.push(0x80 | n as u8),
        n if n < 65536 => {
            frame.push(0x80 | 126);
            frame.extend_from_slice(&(n as u16).to_be_bytes());
        }
        n => {
            frame.push(0x80 | 127);
            frame.extend_from_slice(&(n as u64).to_be_bytes());
        }
    }
    let mask = [0x37, 0xfa, 0x21, 0x3d];
    frame.extend_from_slice(&mask);
    frame.extend(payload.iter().enumerate().map(|(i, b)| b ^ mask[i % 4]));
    frame
}
