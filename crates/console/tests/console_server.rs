//! The console server over loopback with a real mission run: the token guards every route, one
//! client commands and the others watch, hostile clients are cut off alone, and ten watchers do
//! not change the run.

mod console_client;

use console_client::{Closed, Served, TOKEN, Ws, get, replay, without_wall_time};
use serde_json::{Value, json};
use std::time::Duration;

const WAIT: Duration = Duration::from_secs(120);

fn is(kind: &str) -> impl Fn(&Value) -> bool + '_ {
    move |v| v["type"] == kind
}

#[test]
fn every_route_but_the_login_page_needs_the_token() {
    let served = Served::start("routes", true, None);
    let addr = served.addr;
    let bearer = format!("Bearer {TOKEN}");
    assert_eq!(get(addr, "/", &[]).0, 401);
    assert_eq!(get(addr, "/?token=wrong", &[]).0, 401);
    assert_eq!(get(addr, "/", &[("Authorization", "Bearer wrong")]).0, 401);
    assert_eq!(get(addr, "/anything", &[]).0, 401);
    assert_eq!(get(addr, "/ws", &[]).0, 401);
    let (status, login) = get(addr, "/login", &[]);
    assert_eq!(status, 200);
    assert!(login.contains("Access token") && !login.contains(TOKEN));
    let (status, page) = get(addr, &format!("/?token={TOKEN}"), &[]);
    assert_eq!(status, 200);
    assert!(page.contains("<canvas id=\"map\"") && page.contains("new WebSocket"), "the page is whole");
    assert!(!page.contains("http://") && !page.contains("https://"), "the page loads nothing from elsewhere");
    assert_eq!(get(addr, "/", &[("Authorization", &bearer)]).0, 200);
    assert_eq!(get(addr, "/anything", &[("Authorization", &bearer)]).0, 404);
    let refused = Ws::connect(addr, "/ws").err().expect("no upgrade without the token");
    assert!(refused.contains("401"), "{refused}");
    assert!(Ws::connect(addr, "/ws?token=nope").err().unwrap().contains("401"));
    let mut ws = Ws::connect(addr, &format!("/ws?token={TOKEN}")).expect("upgrade with the token");
    let hello = ws.recv().unwrap();
    assert_eq!(hello["type"], "hello");
    assert_eq!(hello["phase"]["phase"], "waiting");
    assert!(hello["help"].as_str().unwrap().contains("mission pause"));
    ws.until(WAIT, |v| v["type"] == "channel" && v["topic"] == "/sim/world");
}

#[test]
fn the_holder_commands_a_watcher_cannot_and_status_is_answered() {
    // Paced, so the mission is still running while the clients talk to it.
    let mut served = Served::start("authority", false, Some(2.0));
    let mut holder = served.client();
    let hello = holder.until(WAIT, is("hello"));
    assert_eq!(hello["holder"], hello["client"], "the first client holds command authority");
    let mut watcher = served.client();
    let hello = watcher.until(WAIT, is("hello"));
    assert_ne!(hello["holder"], hello["client"], "the second client watches");
    holder.until(WAIT, |v| v["type"] == "msg");
    holder.send(&json!({"type": "command", "line": "status"})).unwrap();
    let reply = holder.until(WAIT, is("reply"));
    assert!(reply["text"].as_str().unwrap().starts_with("mission running"), "{reply}");
    watcher.send(&json!({"type": "command", "line": "mission abort"})).unwrap();
    let refused = watcher.until(WAIT, is("error"));
    assert!(refused["text"].as_str().unwrap().contains("holds command authority"), "{refused}");
    watcher.send(&json!({"type": "plan", "goal": [3.0, 3.0]})).unwrap();
    assert!(watcher.until(WAIT, is("error"))["text"].as_str().unwrap().contains("watching"));
    holder.send(&json!({"type": "command", "line": "mission abort"})).unwrap();
    let done = watcher.until(WAIT, is("phase"));
    assert_eq!((done["phase"].as_str(), done["outcome"].as_str()), (Some("done"), Some("aborted")));
    let report = served.report();
    assert_eq!(report["outcome"], "aborted", "only the holder's abort ended the mission");
}

#[test]
fn hostile_clients_are_cut_off_alone_and_ten_watchers_leave_the_run_unchanged() {
    let mut quiet = Served::start("quiet", false, None);
    let alone = without_wall_time(quiet.report());

    let mut served = Served::start("watched", true, None);
    let mut holder = served.client();
    holder.until(WAIT, is("hello"));
    let mut watchers: Vec<Ws> = (0..10).map(|_| served.client()).collect();
    for w in &mut watchers {
        w.until(WAIT, |v| v["type"] == "msg");
    }
    let mut malformed = served.client();
    malformed.send_frame(1, b"{\"type\": \"command\", \"line\": ").unwrap();
    assert_eq!(malformed.closed(), Closed::Code(1007), "malformed JSON closes the connection");
    let mut unknown = served.client();
    unknown.send(&json!({"type": "launch_missiles"})).unwrap();
    assert_eq!(unknown.closed(), Closed::Code(1007));
    let mut binary = served.client();
    binary.send_frame(2, &[0, 1, 2]).unwrap();
    assert_eq!(binary.closed(), Closed::Code(1003));
    let mut huge = served.client();
    let _ = huge.send_frame(1, &vec![b' '; 1 << 20]);
    assert!(matches!(huge.closed(), Closed::Code(1009) | Closed::Dropped), "a megabyte message closes it");
    let mut flood = served.client();
    for _ in 0..1000 {
        if flood.send(&json!({"type": "command", "line": "mission abort"})).is_err() {
            break;
        }
    }
    assert_eq!(flood.closed(), Closed::Code(1008), "a flood closes the connection");
    // The rover's run starts only now, with the mission's own goal, and ends with everyone
    // still connected.
    holder.send(&json!({"type": "plan", "goal": [8.5, 8.0]})).unwrap();
    for w in &mut watchers {
        let done = w.until(WAIT, |v| v["type"] == "phase" && v["phase"] == "done");
        assert_eq!(done["outcome"], "reached");
    }
    let watched = without_wall_time(served.report());
    assert_eq!(watched, alone, "the watched run's report equals the run without clients");
}

#[test]
fn a_replay_scrubs_through_the_logged_run() {
    let mut served = Served::start("replayed", false, None);
    let report = served.report();
    let (_server, addr) = replay(&served.log());
    let mut ws = Ws::connect(addr, &format!("/ws?token={TOKEN}")).unwrap();
    let hello = ws.until(WAIT, is("hello"));
    assert_eq!(hello["phase"]["phase"], "replay");
    let (start, end) =
        (hello["replay"]["start_ns"].as_u64().unwrap(), hello["replay"]["end_ns"].as_u64().unwrap());
    assert!(end > start);
    // At first the whole run: one truth per cycle (and the start), the final report.
    let mut topics = std::collections::HashMap::new();
    let mut truths = 0;
    let mut logged_report = Value::Null;
    loop {
        let m = ws.recv().unwrap();
        match m["type"].as_str() {
            Some("channel") => {
                topics.insert(m["id"].as_u64().unwrap(), m["topic"].as_str().unwrap().to_string());
            }
            Some("msg") => match topics[&m["ch"].as_u64().unwrap()].as_str() {
                "/sim/truth" => truths += 1,
                "/executive/report" => logged_report = m["data"].clone(),
                _ => {}
            },
            Some("time") => {
                assert_eq!(m["t_ns"].as_u64(), Some(end));
                break;
            }
            _ => {}
        }
    }
    assert_eq!(truths, report["cycles"].as_u64().unwrap() + 1);
    assert_eq!(logged_report, report);
    // Halfway: a reset, then the path up to there only.
    ws.send(&json!({"type": "seek", "t_ns": (start + end) / 2})).unwrap();
    ws.until(WAIT, is("reset"));
    let mut half = 0;
    loop {
        let m = ws.recv().unwrap();
        if m["type"] == "time" {
            break;
        }
        if m["type"] == "msg" && topics[&m["ch"].as_u64().unwrap()] == "/sim/truth" {
            assert!(m["t"].as_u64().unwrap() <= (start + end) / 2);
            half += 1;
        }
    }
    assert!(half > 1 && half < truths, "{half} of {truths}");
    // Playing moves the head forward; a command has no rover to go to.
    ws.send(&json!({"type": "play", "speed": 1000.0})).unwrap();
    let later = ws.until(WAIT, |m| m["type"] == "time" && m["t_ns"].as_u64() > Some((start + end) / 2));
    assert_eq!(later["playing"], true);
    ws.send(&json!({"type": "command", "line": "mission abort"})).unwrap();
    assert!(ws.until(WAIT, is("error"))["text"].as_str().unwrap().contains("replay"));
}
