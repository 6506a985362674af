//! ZenohTransport over real TCP links on the loopback interface: two sessions in this process,
//! and a chain of three processes (this one as router, two `zenoh_echo` example clients).

use rovernav_bus::{Bus, BusError, Sample, SubscriptionId, Topic, TopicFilter, Transport, decode, encode};
use rovernav_bus_zenoh::{Endpoint, Mode, ZenohConfig, ZenohTransport};
use std::net::TcpListener;
use std::process::{Child, Command};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Generous: a loaded 2-core machine can stall a thread for seconds; a healthy run takes
/// milliseconds.
const WAIT: Duration = Duration::from_secs(15);

/// A TCP port nobody listens on now (zenoh cannot listen on port 0 and report the port).
fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port()
}

/// A session listening on a free loopback port in `mode`, retrying if another process grabs
/// the port between the probe and zenoh's bind.
fn listener(mode: Mode) -> (ZenohTransport, Endpoint) {
    let mut last = None;
    for _ in 0..5 {
        let endpoint = Endpoint::loopback(free_port()).unwrap();
        match ZenohTransport::open(&ZenohConfig::listen(endpoint.clone()).with_mode(mode)) {
            Ok(transport) => return (transport, endpoint),
            Err(e) => last = Some(e),
        }
    }
    panic!("no free loopback port: {last:?}");
}

/// A listening peer and a peer connected to it.
fn pair() -> (ZenohTransport, ZenohTransport) {
    let (a, endpoint) = listener(Mode::Peer);
    let b = ZenohTransport::open(&ZenohConfig::connect(endpoint)).unwrap();
    (a, b)
}

/// Waits until `count` samples have arrived on a subscription (or fails naming what is missing).
fn collect(t: &mut ZenohTransport, sub: SubscriptionId, count: usize) -> Vec<Sample> {
    let mut samples = Vec::new();
    while samples.len() < count {
        match t.wait_for(sub, WAIT) {
            Ok(more) => samples.extend(more),
            Err(e) => panic!("{} of {count} samples arrived: {e}", samples.len()),
        }
    }
    samples
}

fn topics(samples: &[Sample]) -> Vec<&str> {
    samples.iter().map(|s| s.topic.as_str()).collect()
}

#[test]
fn exact_and_all_subscriptions_receive_only_what_they_select() {
    let (mut a, mut b) = pair();
    let frames = b.subscribe(TopicFilter::Exact("/platform/frame".into())).unwrap();
    let everything = b.subscribe(TopicFilter::All).unwrap();
    b.announce("/b").unwrap();
    a.wait_for_announcement("/b", WAIT).unwrap();
    assert!(a.linked_nodes() >= 1 && b.linked_nodes() >= 1);

    a.publish("/platform/frame", b"f1").unwrap();
    a.publish("/platform/command", b"c1").unwrap();
    a.publish("/other/topic", b"o1").unwrap();
    // The last frame comes after the unselected samples, so once it is in, they would be too.
    a.publish("/platform/frame", b"f2").unwrap();

    let got = collect(&mut b, frames, 2);
    assert_eq!(topics(&got), ["/platform/frame", "/platform/frame"]);
    assert_eq!(got.iter().map(|s| s.payload.as_slice()).collect::<Vec<_>>(), [b"f1", b"f2"]);
    let all = collect(&mut b, everything, 4);
    assert_eq!(topics(&all), ["/platform/frame", "/platform/command", "/other/topic", "/platform/frame"]);
    assert_eq!(all[1].payload, b"c1");
    assert!(b.receive(frames).unwrap().is_empty() && b.receive(everything).unwrap().is_empty());
    assert!(!a.is_synchronous());
}

#[test]
fn a_thousand_samples_arrive_once_each_in_publish_order() {
    let (mut a, mut b) = pair();
    let seq = b.subscribe(TopicFilter::Exact("/test/seq".into())).unwrap();
    let every = b.subscribe(TopicFilter::All).unwrap();
    b.announce("/b").unwrap();
    a.wait_for_announcement("/b", WAIT).unwrap();
    // Two topics interleaved: the order holds per publisher across topics, not just per topic.
    for i in 0u32..1000 {
        let topic = if i % 3 == 0 { "/test/tick" } else { "/test/seq" };
        a.publish(topic, &i.to_le_bytes()).unwrap();
    }
    a.publish("/test/seq", b"end").unwrap();

    let index = |s: &Sample| u32::from_le_bytes(s.payload.as_slice().try_into().unwrap());
    let expected: Vec<u32> = (0..1000).filter(|i| i % 3 != 0).collect();
    let got = collect(&mut b, seq, expected.len() + 1);
    assert_eq!(got.last().unwrap().payload, b"end");
    assert_eq!(got[..got.len() - 1].iter().map(index).collect::<Vec<_>>(), expected);
    let all = collect(&mut b, every, 1001);
    assert_eq!(all[..1000].iter().map(index).collect::<Vec<_>>(), (0..1000).collect::<Vec<_>>());
    assert!(
        all[..1000].iter().all(|s| s.topic == if index(s) % 3 == 0 { "/test/tick" } else { "/test/seq" })
    );
    // Exactly once: nothing beyond the marker is left over.
    assert!(b.receive(seq).unwrap().is_empty() && b.receive(every).unwrap().is_empty());
}

#[test]
fn a_one_megabyte_point_cloud_arrives_intact() {
    let (mut a, mut b) = pair();
    let cloud = b.subscribe(TopicFilter::Exact("/sensors/points".into())).unwrap();
    b.announce("/b").unwrap();
    a.wait_for_announcement("/b", WAIT).unwrap();
    // 87,382 points of three f32: 1,048,584 bytes of varied content (splitmix64), so a dropped,
    // repeated or reordered fragment changes the bytes.
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = || {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    };
    let payload: Vec<u8> =
        (0..87_382 * 3).flat_map(|_| ((next() >> 40) as f32 / 1000.0).to_le_bytes()).collect();
    assert!(payload.len() > 1 << 20);
    a.publish("/sensors/points", &payload).unwrap();
    a.publish("/sensors/points", b"small after large").unwrap();
    let got = collect(&mut b, cloud, 2);
    assert_eq!(got[0].payload.len(), payload.len());
    assert!(got[0].payload == payload, "payload changed in transit");
    assert_eq!(got[1].payload, b"small after large");
}

#[test]
fn a_bus_over_zenoh_delivers_typed_messages_between_sessions() {
    const READINGS: Topic<Vec<f64>> = Topic::new("/test/readings");
    let (a, b) = pair();
    let mut reader = Bus::over(Box::new(b));
    let sub = reader.subscribe(READINGS).unwrap();
    let mut a = a;
    a.wait_for_subscriber("/test/readings", WAIT).unwrap();
    let mut writer = Bus::over(Box::new(a));
    let values = vec![0.1, 1.0 / 3.0, -2.5e-300, 5e-324];
    writer.publish(READINGS, values.clone()).unwrap();
    let start = Instant::now();
    let got: Vec<Arc<Vec<f64>>> = loop {
        // The bus has no blocking take: poll until the message is in (typically under 1 ms).
        let got = reader.take(&sub).unwrap();
        if !got.is_empty() || start.elapsed() > WAIT {
            break got;
        }
        std::thread::sleep(Duration::from_millis(1));
    };
    assert_eq!(got.len(), 1, "one message expected");
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&got[0]), bits(&values), "floats must survive the wire bit for bit");
    assert!(!reader.is_synchronous());
}

/// The lockstep pattern of a simulator and a rover in two processes (threads here): each
/// subscribes, announces itself and waits for the other; then the simulator publishes frame k
/// and blocks for command k, and the rover answers every frame with one command.
#[test]
fn simulator_and_rover_step_in_lockstep() {
    const FRAME: Topic<(u32, f64)> = Topic::new("/platform/frame");
    const COMMAND: Topic<(u32, f64)> = Topic::new("/platform/command");
    const STEPS: u32 = 200;
    let (mut sim, sim_endpoint) = listener(Mode::Peer);
    let rover = std::thread::spawn(move || -> Result<Vec<u32>, BusError> {
        let mut rover = ZenohTransport::open(&ZenohConfig::connect(sim_endpoint))?;
        let frames = rover.subscribe(TopicFilter::Exact(FRAME.name().into()))?;
        rover.announce("/rover")?;
        rover.wait_for_announcement("/sim", WAIT)?;
        let mut seen = Vec::new();
        while seen.len() < STEPS as usize {
            for sample in rover.wait_for(frames, WAIT)? {
                let (k, x) = decode(&FRAME, &sample.payload)?;
                seen.push(k);
                rover.publish(COMMAND.name(), &encode(&COMMAND, &(k, -x))?)?;
            }
        }
        Ok(seen)
    });
    let commands = sim.subscribe(TopicFilter::Exact(COMMAND.name().into())).unwrap();
    sim.announce("/sim").unwrap();
    sim.wait_for_announcement("/rover", WAIT).unwrap();
    for k in 0..STEPS {
        let x = f64::from(k) * 0.25;
        sim.publish(FRAME.name(), &encode(&FRAME, &(k, x)).unwrap()).unwrap();
        let replies = sim.wait_for(commands, WAIT).unwrap();
        // Lockstep: exactly one command per frame, answering this frame.
        assert_eq!(replies.len(), 1, "step {k}");
        assert_eq!(decode(&COMMAND, &replies[0].payload).unwrap(), (k, -x));
    }
    assert_eq!(rover.join().unwrap().unwrap(), (0..STEPS).collect::<Vec<_>>());
}

#[test]
fn a_peer_started_before_its_counterpart_links_when_it_comes_up() {
    let endpoint = Endpoint::loopback(free_port()).unwrap();
    // The rover may start before the simulator: a connecting peer opens anyway and retries.
    let mut early = ZenohTransport::open(&ZenohConfig::connect(endpoint.clone())).unwrap();
    assert_eq!(early.linked_nodes(), 0);
    let late_config = ZenohConfig::listen(endpoint);
    let mut late = ZenohTransport::open(&late_config).unwrap();
    let greetings = late.subscribe(TopicFilter::Exact("/test/hello".into())).unwrap();
    late.announce("/late").unwrap();
    early.wait_for_announcement("/late", WAIT).unwrap();
    early.publish("/test/hello", b"hi").unwrap();
    assert_eq!(late.wait_for(greetings, WAIT).unwrap()[0].payload, b"hi");

    // Dropping a transport closes its session and frees its port for the next run.
    drop(late);
    ZenohTransport::open(&late_config).expect("the port is free again after drop");
}

#[test]
fn failures_are_one_line_errors_naming_their_cause() {
    let one_line = |e: BusError| {
        let message = e.to_string();
        assert!(!message.contains('\n'), "{message}");
        message
    };
    // A port taken by someone else.
    let taken = TcpListener::bind("127.0.0.1:0").unwrap();
    let endpoint = Endpoint::loopback(taken.local_addr().unwrap().port()).unwrap();
    let message = one_line(ZenohTransport::open(&ZenohConfig::listen(endpoint.clone())).unwrap_err());
    assert!(message.contains(&endpoint.to_string()), "{message}");
    // A client whose router is not there fails at once rather than hanging.
    let nobody = Endpoint::loopback(free_port()).unwrap();
    let client = ZenohConfig::connect(nobody.clone()).with_mode(Mode::Client);
    let message = one_line(ZenohTransport::open(&client).unwrap_err());
    assert!(message.contains(&nobody.to_string()), "{message}");
    // A configuration that cannot reach anyone.
    let message = one_line(ZenohTransport::open(&ZenohConfig::default()).unwrap_err());
    assert!(message.contains("scouting is off"), "{message}");
    drop(taken);

    let (mut a, _b) = pair();
    assert!(matches!(a.publish("platform/frame", b""), Err(BusError::BadTopic { .. })));
    assert!(matches!(a.subscribe(TopicFilter::Exact("/a/**".into())), Err(BusError::BadTopic { .. })));
    assert_eq!(a.receive(SubscriptionId(9)), Err(BusError::UnknownSubscription(9)));
    let quiet = a.subscribe(TopicFilter::Exact("/nobody/talks".into())).unwrap();
    let message = one_line(a.wait_for(quiet, Duration::from_millis(50)).unwrap_err());
    assert!(message.contains("/nobody/talks"), "{message}");
    let message = one_line(a.wait_for_announcement("/ghost", Duration::from_millis(50)).unwrap_err());
    assert!(message.contains("/ghost"), "{message}");
    assert!(matches!(a.announce("ghost"), Err(BusError::BadTopic { .. })));
}

/// Kills a child process if the test fails before it exits by itself.
struct Reaped(Child);

impl Drop for Reaped {
    fn drop(&mut self) {
        if matches!(self.0.try_wait(), Ok(None)) {
            let _ = self.0.kill();
            let _ = self.0.wait();
        }
    }
}

/// The `zenoh_echo` example, which `cargo test` builds beside this test binary.
fn echo_binary() -> std::path::PathBuf {
    let exe = std::env::current_exe().unwrap();
    let profile_dir = exe.parent().and_then(|deps| deps.parent()).unwrap();
    let path = profile_dir.join("examples").join(format!("zenoh_echo{}", std::env::consts::EXE_SUFFIX));
    assert!(
        path.exists(),
        "{} is missing: run `cargo test -p rovernav-bus-zenoh --features zenoh` (it builds the examples)",
        path.display()
    );
    path
}

#[test]
fn three_processes_relay_through_a_router() {
    let (mut hub, endpoint) = listener(Mode::Router);
    let out = hub.subscribe(TopicFilter::Exact("/chain/c".into())).unwrap();
    let spawn = |from: &str, to: &str, name: &str| {
        let child = Command::new(echo_binary())
            .args(["--mode", "client", "--connect", &endpoint.to_string()])
            .args(["--from", from, "--to", to, "--name", name, "--quit", "/chain/quit", "--idle-s", "20"])
            .spawn()
            .unwrap();
        Reaped(child)
    };
    // Started out of order on purpose: each relay waits for a reader of its output.
    let mut second = spawn("/chain/b", "/chain/c", "/echo_2");
    let mut first = spawn("/chain/a", "/chain/b", "/echo_1");
    hub.wait_for_announcement("/echo_1", WAIT).unwrap();
    hub.wait_for_announcement("/echo_2", WAIT).unwrap();
    for i in 0u32..300 {
        hub.publish("/chain/a", &i.to_le_bytes()).unwrap();
    }
    let got = collect(&mut hub, out, 300);
    let order: Vec<u32> =
        got.iter().map(|s| u32::from_le_bytes(s.payload.as_slice().try_into().unwrap())).collect();
    assert_eq!(order, (0..300).collect::<Vec<_>>(), "two hops and back, in order, once each");

    hub.publish("/chain/quit", b"").unwrap();
    for relay in [&mut first, &mut second] {
        let start = Instant::now();
        let status = loop {
            if let Some(status) = relay.0.try_wait().unwrap() {
                break status;
            }
            assert!(start.elapsed() < WAIT, "a relay did not quit");
            std::thread::sleep(Duration::from_millis(10));
        };
        assert!(status.success(), "relay exit status {status}");
    }
}
