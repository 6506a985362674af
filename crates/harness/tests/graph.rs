//! The component graph: the run's runtime holds exactly the table's components in its order,
//! the wiring is closed, a remote run steps the same graph, and the printed forms carry every
//! edge.

mod common;

use rovernav_executive::graph::{Graph, NODES};
use rovernav_executive::remote::NoLink;
use rovernav_executive::{Mission, Run};
use rovernav_harness::JudgedRun;
use std::collections::BTreeSet;

fn small_mission() -> Mission {
    Mission::from_toml(&common::small_yard("graph-yard", 1, common::SMALL_YARD_GOAL), "graph-yard").unwrap()
}

fn graph(remote: bool) -> Graph {
    let run = Run::mission(&small_mission(), "graph-yard").unwrap();
    let run = if remote { run.remote(Box::new(NoLink)) } else { run };
    run.graph().unwrap()
}

#[test]
fn the_runtime_steps_the_tables_components_in_its_order_and_at_its_rates() {
    let g = graph(false);
    let stepped: Vec<_> = g.nodes.iter().filter(|n| n.order > 0).collect();
    assert_eq!(stepped.len(), NODES.len());
    for (i, (node, spec)) in stepped.iter().zip(NODES).enumerate() {
        assert_eq!((node.order, node.name, node.rate_hz), (i + 1, spec.name, spec.rate_hz));
    }
    // A run's report lists the same components in the same order.
    let report = Run::mission(&small_mission(), "graph-yard").unwrap().execute().unwrap().report;
    let names: Vec<&str> = report.components.iter().map(|c| c.name.as_str()).collect();
    let table: Vec<&str> = NODES.iter().map(|n| n.name).collect();
    assert_eq!(names, table);
}

#[test]
fn every_topic_read_is_published_and_data_flows_forward_within_a_step() {
    let g = graph(false);
    let published: BTreeSet<&str> =
        g.nodes.iter().flat_map(|n| n.publishes.iter().map(|t| t.topic)).collect();
    for n in &g.nodes {
        for t in &n.subscribes {
            assert!(published.contains(t.topic), "{} reads {} which nobody publishes", n.name, t.topic);
        }
    }
    // The stop-and-go cycle within one tick: the navigator's command reaches the platform through
    // the motion controller, and the estimator integrates the platform's frame.
    let order = |name: &str| g.nodes.iter().find(|n| n.name == name).unwrap().order;
    let feeds = |from: &str, to: &str| {
        let a = g.nodes.iter().find(|n| n.name == from).unwrap();
        let b = g.nodes.iter().find(|n| n.name == to).unwrap();
        a.publishes.iter().any(|t| b.subscribes.iter().any(|s| s.topic == t.topic))
    };
    for (from, to) in [
        ("navigator", "motion-controller"),
        ("motion-controller", "platform"),
        ("platform", "pose-estimator"),
    ] {
        assert!(feeds(from, to), "{from} feeds {to}");
        assert!(order(from) < order(to), "{from} steps before {to}");
    }
}

#[test]
fn a_remote_run_steps_the_same_graph() {
    let (local, remote) = (graph(false), graph(true));
    assert_eq!(local.nodes, remote.nodes);
    assert_ne!(local.platform, remote.platform);
}

#[test]
fn the_dot_text_has_one_edge_per_port_and_the_table_one_line_per_port() {
    let g = graph(false);
    let ports: usize = g.nodes.iter().map(|n| n.subscribes.len() + n.publishes.len()).sum();
    let dot = g.dot();
    assert!(dot.starts_with("digraph") && dot.trim_end().ends_with('}'));
    assert_eq!(dot.lines().filter(|l| l.contains("\" -> \"")).count(), ports);
    let table = g.table();
    assert_eq!(table.lines().filter(|l| l.contains("<- ") || l.contains("-> ")).count(), ports);
    let json: serde_json::Value = serde_json::to_value(&g).unwrap();
    assert_eq!(json["nodes"].as_array().unwrap().len(), g.nodes.len());
}
