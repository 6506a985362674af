//! How a process joins the zenoh network: its mode, the TCP endpoints it listens on and connects
//! to, and the zenoh settings that follow from them.
//!
//! This part needs no zenoh build, so a CLI can parse and check `--listen` / `--connect`
//! arguments in the default (light) workspace build and fail early with a one-line error.

use rovernav_bus::{BusError, TopicFilter, check_topic_name};
use std::fmt;
use std::net::{Ipv4Addr, Ipv6Addr};
use std::str::FromStr;

/// Why a zenoh configuration was refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ZenohConfigError {
    /// An endpoint that is not `tcp/HOST:PORT`.
    #[error("bad zenoh endpoint `{endpoint}`: {why}")]
    BadEndpoint {
        /// The text given, with control characters escaped so the message stays on one line.
        endpoint: String,
        /// What is wrong with it.
        why: String,
    },
    /// A mode that is not `peer`, `client` or `router`.
    #[error("bad zenoh mode `{0}`: expected `peer`, `client` or `router`")]
    BadMode(String),
    /// A combination of mode and endpoints that can never reach another process.
    #[error("zenoh {mode} configuration: {why}")]
    Unusable {
        /// The mode configured.
        mode: Mode,
        /// What is missing or not allowed.
        why: &'static str,
    },
}

/// The role of a process in the zenoh network.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Mode {
    /// Talks directly to the peers it is linked with; does not forward between two others, so
    /// peers either all link to each other or go through a router.
    #[default]
    Peer,
    /// Talks through exactly one router (or peer) it connects to; cannot listen.
    Client,
    /// Forwards samples between every session linked to it: the hub of a star of clients.
    Router,
}

impl Mode {
    /// The name zenoh's configuration uses.
    pub fn as_str(self) -> &'static str {
        match self {
            Mode::Peer => "peer",
            Mode::Client => "client",
            Mode::Router => "router",
        }
    }
}

impl fmt::Display for Mode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl FromStr for Mode {
    type Err = ZenohConfigError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "peer" => Ok(Mode::Peer),
            "client" => Ok(Mode::Client),
            "router" => Ok(Mode::Router),
            other => Err(ZenohConfigError::BadMode(other.escape_debug().to_string())),
        }
    }
}

/// A TCP endpoint, written `tcp/HOST:PORT` (`tcp/127.0.0.1:7447`, `tcp/[::1]:7447`,
/// `tcp/rover.local:7447`).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Endpoint {
    host: String,
    port: u16,
}

impl Endpoint {
    /// An endpoint on this host's IPv4 loopback address.
    pub fn loopback(port: u16) -> Result<Self, ZenohConfigError> {
        Self::tcp("127.0.0.1", port)
    }

    /// An endpoint from a host (IPv4 address, bracket-free IPv6 address or DNS name) and a port.
    pub fn tcp(host: &str, port: u16) -> Result<Self, ZenohConfigError> {
        let shown = if host.contains(':') { format!("[{host}]") } else { host.to_string() };
        format!("tcp/{shown}:{port}").parse()
    }

    /// The host part as written in the endpoint (IPv6 addresses keep their brackets).
    pub fn host(&self) -> &str {
        &self.host
    }

    /// The TCP port.
    pub fn port(&self) -> u16 {
        self.port
    }
}

impl fmt::Display for Endpoint {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "tcp/{}:{}", self.host, self.port)
    }
}

impl FromStr for Endpoint {
    type Err = ZenohConfigError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let bad = |why: &str| ZenohConfigError::BadEndpoint {
            endpoint: s.escape_debug().to_string(),
            why: why.to_string(),
        };
        let Some(address) = s.strip_prefix("tcp/") else {
            return Err(bad("expected `tcp/HOST:PORT` (only TCP is built in)"));
        };
        let Some((host, port)) = address.rsplit_once(':') else {
            return Err(bad("missing `:PORT`"));
        };
        let port: u16 = match port.parse() {
            Ok(0) => return Err(bad("port 0 is not allowed: peers must know the port to connect to")),
            Ok(port) => port,
            Err(_) => return Err(bad("the port must be a number from 1 to 65535")),
        };
        if let Some(inner) = host.strip_prefix('[') {
            let Some(inner) = inner.strip_suffix(']') else {
                return Err(bad("unclosed `[` around an IPv6 address"));
            };
            if inner.parse::<Ipv6Addr>().is_err() {
                return Err(bad("not an IPv6 address inside `[...]`"));
            }
        } else if host.contains(':') {
            return Err(bad("write an IPv6 address in brackets, as `tcp/[::1]:7447`"));
        } else if host.is_empty() {
            return Err(bad("missing host"));
        } else if host.split('.').all(|part| part.chars().all(|c| c.is_ascii_digit())) {
            // All-numeric hosts are meant as IPv4 addresses; a typo such as `127.0.0.256`
            // would otherwise go to a DNS lookup and fail much later.
            if host.parse::<Ipv4Addr>().is_err() {
                return Err(bad("not an IPv4 address"));
            }
        } else if !host.split('.').all(is_dns_label) {
            return Err(bad("the host must be an IP address or a DNS name of letters, digits, `-` and `.`"));
        }
        Ok(Endpoint { host: host.to_string(), port })
    }
}

/// Whether a DNS label is non-empty letters, digits and inner hyphens.
fn is_dns_label(label: &str) -> bool {
    !label.is_empty()
        && !label.starts_with('-')
        && !label.ends_with('-')
        && label.chars().all(|c| c.is_ascii_alphanumeric() || c == '-')
}

/// Everything a process needs to open a zenoh transport: mode and explicit endpoints.
///
/// Multicast scouting is always off (the network it runs on has no multicast, and a rover must
/// not join whatever zenoh session happens to be on the LAN): sessions find each other only
/// through the endpoints given here.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ZenohConfig {
    /// Role in the network.
    pub mode: Mode,
    /// Endpoints this process accepts links on.
    pub listen: Vec<Endpoint>,
    /// Endpoints this process links to; a peer keeps retrying in the background until the other
    /// side is up, a client fails at once.
    pub connect: Vec<Endpoint>,
}

impl ZenohConfig {
    /// A peer that listens on `endpoint` (the side started first, e.g. the simulator).
    pub fn listen(endpoint: Endpoint) -> Self {
        Self { mode: Mode::Peer, listen: vec![endpoint], connect: Vec::new() }
    }

    /// A peer that connects to `endpoint` (e.g. the rover stack linking to the simulator).
    pub fn connect(endpoint: Endpoint) -> Self {
        Self { mode: Mode::Peer, listen: Vec::new(), connect: vec![endpoint] }
    }

    /// The same endpoints in another mode.
    pub fn with_mode(mut self, mode: Mode) -> Self {
        self.mode = mode;
        self
    }

    /// Also listens on `endpoint`.
    pub fn and_listen(mut self, endpoint: Endpoint) -> Self {
        self.listen.push(endpoint);
        self
    }

    /// Also connects to `endpoint`.
    pub fn and_connect(mut self, endpoint: Endpoint) -> Self {
        self.connect.push(endpoint);
        self
    }

    /// Refuses configurations that could never reach another process.
    pub fn check(&self) -> Result<(), ZenohConfigError> {
        let unusable = |why| Err(ZenohConfigError::Unusable { mode: self.mode, why });
        match self.mode {
            Mode::Client if self.connect.is_empty() => unusable("a client needs an endpoint to connect to"),
            Mode::Client if !self.listen.is_empty() => unusable("a client cannot listen; use peer or router"),
            Mode::Peer | Mode::Router if self.listen.is_empty() && self.connect.is_empty() => {
                unusable("no endpoint to listen on or connect to, and scouting is off")
            }
            _ => Ok(()),
        }
    }

    /// The zenoh settings as `(path, JSON5 value)` pairs, for `zenoh::Config::insert_json5`.
    pub fn zenoh_settings(&self) -> Result<Vec<(&'static str, String)>, ZenohConfigError> {
        self.check()?;
        let list = |endpoints: &[Endpoint]| {
            let quoted: Vec<String> = endpoints.iter().map(|e| format!("\"{e}\"")).collect();
            format!("[{}]", quoted.join(", "))
        };
        Ok(vec![
            ("mode", format!("\"{}\"", self.mode)),
            // Written even when empty: a peer's default is to listen on every interface.
            ("listen/endpoints", list(&self.listen)),
            ("connect/endpoints", list(&self.connect)),
            ("scouting/multicast/enabled", "false".to_string()),
            // Retry quickly so a process started before its counterpart links within a fraction
            // of a second of the counterpart coming up (zenoh's default waits up to 4 s).
            ("connect/retry", "{ period_init_ms: 50, period_max_ms: 500, period_increase_factor: 2 }".into()),
        ])
    }
}

/// The zenoh key expression of a topic name: the name without its leading `/`.
pub fn topic_key(topic: &str) -> Result<String, BusError> {
    check_topic_name(topic)?;
    Ok(topic[1..].to_string())
}

/// The zenoh key expression a subscription filter selects (`**` for every topic).
pub fn filter_key(filter: &TopicFilter) -> Result<String, BusError> {
    match filter {
        TopicFilter::Exact(name) => topic_key(name),
        TopicFilter::All => Ok("**".to_string()),
    }
}

/// The topic name of a zenoh key, or `None` for keys no rovernav topic maps to (other zenoh
/// applications sharing the network).
pub fn key_topic(key: &str) -> Option<String> {
    let topic = format!("/{key}");
    check_topic_name(&topic).is_ok().then_some(topic)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn endpoint_error(text: &str) -> String {
        text.parse::<Endpoint>().unwrap_err().to_string()
    }

    #[test]
    fn endpoints_parse_and_print_back() {
        for text in ["tcp/127.0.0.1:7447", "tcp/[::1]:1", "tcp/rover-1.local:65535", "tcp/localhost:80"] {
            let endpoint: Endpoint = text.parse().unwrap();
            assert_eq!(endpoint.to_string(), text);
        }
        let e: Endpoint = "tcp/10.0.0.2:7448".parse().unwrap();
        assert_eq!((e.host(), e.port()), ("10.0.0.2", 7448));
        assert_eq!(Endpoint::loopback(9000).unwrap().to_string(), "tcp/127.0.0.1:9000");
        assert_eq!(Endpoint::tcp("::1", 9000).unwrap().to_string(), "tcp/[::1]:9000");
    }

    #[test]
    fn bad_endpoints_get_a_one_line_error_naming_them() {
        let cases = [
            ("udp/127.0.0.1:7447", "tcp/HOST:PORT"),
            ("127.0.0.1:7447", "tcp/HOST:PORT"),
            ("tcp/127.0.0.1", "missing `:PORT`"),
            ("tcp/127.0.0.1:0", "port 0"),
            ("tcp/127.0.0.1:65536", "1 to 65535"),
            ("tcp/127.0.0.1:http", "1 to 65535"),
            ("tcp/:7447", "missing host"),
            ("tcp/::1:7447", "brackets"),
            ("tcp/[::1:7447", "unclosed"),
            ("tcp/[zz]:7447", "IPv6"),
            ("tcp/127.0.0.256:7447", "IPv4"),
            ("tcp/ro ver:7447", "DNS name"),
            ("tcp/rover..local:7447", "DNS name"),
            ("tcp/rover\n:7447", "DNS name"),
        ];
        for (text, why) in cases {
            let message = endpoint_error(text);
            assert!(message.contains(why), "{text:?}: {message}");
            assert!(message.contains(&text.escape_debug().to_string()), "{text:?}: {message}");
            assert!(!message.contains('\n'), "{text:?}: {message}");
        }
        assert!(Endpoint::loopback(0).is_err());
    }

    #[test]
    fn modes_parse_by_their_zenoh_names() {
        for mode in [Mode::Peer, Mode::Client, Mode::Router] {
            assert_eq!(mode.as_str().parse::<Mode>().unwrap(), mode);
        }
        assert!("Peer".parse::<Mode>().unwrap_err().to_string().contains("`Peer`"));
    }

    #[test]
    fn configurations_that_cannot_reach_anyone_are_refused() {
        let e = Endpoint::loopback(7447).unwrap();
        assert!(ZenohConfig::listen(e.clone()).check().is_ok());
        assert!(ZenohConfig::connect(e.clone()).with_mode(Mode::Client).check().is_ok());
        assert!(ZenohConfig::listen(e.clone()).with_mode(Mode::Router).check().is_ok());
        let refused = [
            ZenohConfig::default(),
            ZenohConfig::default().with_mode(Mode::Router),
            ZenohConfig::listen(e.clone()).with_mode(Mode::Client),
            ZenohConfig::connect(e.clone()).and_listen(e.clone()).with_mode(Mode::Client),
        ];
        for config in refused {
            let message = config.check().unwrap_err().to_string();
            assert!(message.starts_with(&format!("zenoh {} configuration", config.mode)), "{message}");
            assert!(config.zenoh_settings().is_err());
        }
    }

    #[test]
    fn settings_turn_scouting_off_and_name_every_endpoint() {
        let config = ZenohConfig::listen(Endpoint::loopback(7447).unwrap())
            .and_connect("tcp/[::1]:7448".parse().unwrap())
            .and_connect("tcp/sim.local:7449".parse().unwrap());
        let settings = config.zenoh_settings().unwrap();
        let get = |path: &str| settings.iter().find(|(p, _)| *p == path).map(|(_, v)| v.as_str());
        assert_eq!(get("mode"), Some("\"peer\""));
        assert_eq!(get("scouting/multicast/enabled"), Some("false"));
        assert_eq!(get("listen/endpoints"), Some("[\"tcp/127.0.0.1:7447\"]"));
        assert_eq!(get("connect/endpoints"), Some("[\"tcp/[::1]:7448\", \"tcp/sim.local:7449\"]"));
        let client = ZenohConfig::connect(Endpoint::loopback(1).unwrap()).with_mode(Mode::Client);
        let settings = client.zenoh_settings().unwrap();
        assert!(settings.contains(&("listen/endpoints", "[]".to_string())), "{settings:?}");
    }

    #[test]
    fn topics_map_to_keys_without_the_leading_slash() {
        assert_eq!(topic_key("/platform/frame").unwrap(), "platform/frame");
        assert_eq!(filter_key(&TopicFilter::Exact("/platform/command".into())).unwrap(), "platform/command");
        assert_eq!(filter_key(&TopicFilter::All).unwrap(), "**");
        assert!(matches!(topic_key("platform/frame"), Err(BusError::BadTopic { .. })));
        assert!(matches!(filter_key(&TopicFilter::Exact("/a/*".into())), Err(BusError::BadTopic { .. })));
        assert_eq!(key_topic("platform/frame").as_deref(), Some("/platform/frame"));
        for foreign in ["Other/App", "a//b", "", "demo/**"] {
            assert_eq!(key_topic(foreign), None, "{foreign:?}");
        }
    }
}
