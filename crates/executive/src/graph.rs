//! The component graph in one place: which components a run hosts, at what rate, in which order
//! a step visits them, and (gathered from each component's declared ports) which topics each
//! reads and publishes.
//!
//! [`NODES`] is the table the runtime is built from (as copper-rs keeps its task graph in one
//! file): every run, in process or against a remote platform, adds exactly these components in
//! this order at these rates, through [`assemble`]. The ports stay declared by each component next
//! to the code that subscribes and publishes (so the two cannot drift apart); [`Graph::of`] reads
//! them back from an assembled runtime, which is what `rovernav graph` prints (a text table,
//! Graphviz dot or JSON).

use crate::components::{Component, Port};
use crate::deliberative::Deliberative;
use crate::messages::topics;
use crate::platform::ToolingArm;
use crate::reflexive::{MotionController, NavigatorComponent, PoseEstimatorComponent};
use crate::run::{RunOptions, RunSettings};
use crate::runtime::{Runtime, RuntimeError};
use crate::sensor_servers::{
    ContactMonitor, InertialSensors, MAX_BODY_CONTACTS, RangeSensors, WheelOdometry,
};
use rovernav_core::{Localizer, Navigator, RoverConfig};
use serde::Serialize;
use std::fmt::Write as _;

/// What a graph entry's constructor may use: the mission's algorithms (taken once), settings,
/// rover and options, and the platform (the simulator or its stand-in across a link).
pub struct Parts<'a> {
    /// The navigator (taken by the `navigator` entry).
    pub navigator: Option<Box<dyn Navigator>>,
    /// The localiser (taken by the `pose-estimator` entry).
    pub localizer: Option<Box<dyn Localizer>>,
    /// The platform component (taken by the `platform` entry).
    pub platform: Option<Box<dyn Component>>,
    /// The run's settings.
    pub settings: &'a RunSettings,
    /// The rover.
    pub rover: &'a RoverConfig,
    /// The run's options.
    pub options: &'a RunOptions,
}

/// One component of the graph.
pub struct NodeSpec {
    /// The component's name (the built component must carry it).
    pub name: &'static str,
    /// Its layer (paper 004 section 2): `reflexive`, `platform` or `sensor server`.
    pub layer: &'static str,
    /// How often the runtime steps it (Hz, simulated time).
    pub rate_hz: f64,
    /// What it does, in a few words.
    pub does: &'static str,
    /// Builds it from the run's parts.
    pub build: fn(&mut Parts<'_>) -> Result<Box<dyn Component>, RuntimeError>,
}

/// A part an entry takes, or an error naming it when another entry took it already.
fn take<T>(part: &mut Option<T>, name: &'static str) -> Result<T, RuntimeError> {
    part.take().ok_or(RuntimeError::Duplicate(name))
}

/// The components of every run, in the order a step visits them (the data-flow order: the
/// navigator's command reaches the platform and the estimator integrates the frame within the
/// tick). Rates: paper 004 section 2's default of 10 Hz for every component.
pub const NODES: &[NodeSpec] = &[
    NodeSpec {
        name: "navigator",
        layer: "reflexive",
        rate_hz: 10.0,
        does: "plans toward the drive target on the frames and estimates; issues motion",
        build: |p| {
            let navigator = take(&mut p.navigator, "navigator")?;
            Ok(Box::new(
                NavigatorComponent::new(
                    navigator,
                    &crate::run_loop::registry_name(p.settings),
                    p.rover.clone(),
                )
                .with_params(p.settings.navigator_params.clone())
                .with_shadow(p.options.shadow_navigator.as_deref())
                .map_err(|message| RuntimeError::Build { entry: "navigator", message })?,
            ))
        },
    },
    NodeSpec {
        name: "tooling-arm",
        layer: "platform",
        rate_hz: 10.0,
        does: "places the instrument by AutoPlace (images, octree, safe motion) or refuses; holds the platform while it works",
        build: |p| Ok(Box::new(ToolingArm::new(p.options.arm.clone()).with_rover(p.rover.clone()))),
    },
    NodeSpec {
        name: "motion-controller",
        layer: "reflexive",
        rate_hz: 10.0,
        does: "passes the navigator's or the executive's motion to the platform",
        build: |_| Ok(Box::new(MotionController::new())),
    },
    NodeSpec {
        name: "platform",
        layer: "platform",
        rate_hz: 10.0,
        does: "executes motion and publishes the sensor frames (simulator or remote stand-in)",
        build: |p| take(&mut p.platform, "platform"),
    },
    NodeSpec {
        name: "range-sensors",
        layer: "sensor server",
        rate_hz: 10.0,
        does: "watches the range cameras: fails on a silent one",
        build: |_| Ok(Box::new(RangeSensors::new())),
    },
    NodeSpec {
        name: "camera-server",
        layer: "sensor server",
        rate_hz: 10.0,
        does: "publishes each frame's camera images; fails on a blind camera",
        build: |_| Ok(Box::new(crate::camera_server::CameraServer::new())),
    },
    NodeSpec {
        name: "inertial-sensors",
        layer: "sensor server",
        rate_hz: 10.0,
        does: "watches gyro, inclinometer and compass: fails on a bad reading",
        build: |_| Ok(Box::new(InertialSensors::new())),
    },
    NodeSpec {
        name: "wheel-odometry",
        layer: "sensor server",
        rate_hz: 10.0,
        does: "watches encoders and motor currents: fails on a stuck wheel",
        build: |p| Ok(Box::new(WheelOdometry::new(p.rover.encoder_counts_per_cm, p.rover.track))),
    },
    NodeSpec {
        name: "contact-monitor",
        layer: "sensor server",
        rate_hz: 10.0,
        does: "counts body contacts: fails when a navigator keeps hitting terrain",
        build: |_| Ok(Box::new(ContactMonitor::new(MAX_BODY_CONTACTS))),
    },
    NodeSpec {
        name: "pose-estimator",
        layer: "reflexive",
        rate_hz: 10.0,
        does: "integrates each frame into the pose estimate",
        build: |p| {
            let localizer = take(&mut p.localizer, "pose-estimator")?;
            Ok(Box::new(PoseEstimatorComponent::new(localizer, p.options.pose_estimator.clone())))
        },
    },
];

/// Adds the graph's components to a runtime, in [`NODES`] order at [`NODES`] rates.
pub fn assemble(runtime: &mut Runtime, mut parts: Parts<'_>) -> Result<(), RuntimeError> {
    for node in NODES {
        let component = (node.build)(&mut parts)?;
        if component.name() != node.name {
            return Err(RuntimeError::Misnamed { entry: node.name, built: component.name() });
        }
        runtime.add_at(component, node.rate_hz)?;
    }
    Ok(())
}

/// The topics the deliberative layer reads (it is stepped by the loop, not by the runtime).
pub fn deliberative_inputs() -> Vec<Port> {
    vec![
        Port::of(topics::PLATFORM_FRAME),
        Port::of(topics::LOCALIZATION_ESTIMATE),
        Port::of(topics::TASK_STATUS),
        Port::of(topics::SYSTEM_STATUS),
        Port::of(topics::OPERATOR_COMMAND),
    ]
}

/// One topic end of a node.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TopicRef {
    /// Topic name.
    pub topic: &'static str,
    /// Message type.
    pub message: &'static str,
}

impl From<Port> for TopicRef {
    fn from(p: Port) -> Self {
        let message = p.type_name.rsplit("::").next().unwrap_or(p.type_name);
        Self { topic: p.topic, message }
    }
}

/// One node of a printed graph.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct GraphNode {
    /// Step order (1 for the first component; 0 for the layers outside the runtime).
    pub order: usize,
    /// Component name.
    pub name: &'static str,
    /// Layer.
    pub layer: &'static str,
    /// Rate (Hz); 0 for the layers the loop steps once per tick.
    pub rate_hz: f64,
    /// What it does.
    pub does: &'static str,
    /// Topics it reads.
    pub subscribes: Vec<TopicRef>,
    /// Topics it publishes.
    pub publishes: Vec<TopicRef>,
}

/// A run's component graph as assembled: the runtime's components plus the deliberative layer
/// and the operator, which the loop steps outside the runtime, and the runtime's own state
/// topics.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Graph {
    /// Mission name.
    pub mission: String,
    /// `simulator in process` or `remote over the bus`.
    pub platform: &'static str,
    /// The components in step order, then the deliberative layer, the operator and the runtime.
    pub nodes: Vec<GraphNode>,
}

impl Graph {
    /// The graph of an assembled runtime (`remote`: its platform is a stand-in across a link).
    pub fn of(runtime: &Runtime, mission: &str, remote: bool) -> Self {
        let mut nodes: Vec<GraphNode> = runtime
            .nodes()
            .into_iter()
            .enumerate()
            .map(|(i, (name, rate_hz, ports))| {
                let spec = NODES.iter().find(|n| n.name == name);
                GraphNode {
                    order: i + 1,
                    name,
                    layer: spec.map_or("", |s| s.layer),
                    rate_hz,
                    does: spec.map_or("", |s| s.does),
                    subscribes: ports.inputs.into_iter().map(TopicRef::from).collect(),
                    publishes: ports.outputs.into_iter().map(TopicRef::from).collect(),
                }
            })
            .collect();
        nodes.push(GraphNode {
            order: 0,
            name: "deliberative",
            layer: "deliberative",
            rate_hz: 0.0,
            does: "mission plan, operator commands and fault protection; once per tick, before it",
            subscribes: deliberative_inputs().into_iter().map(TopicRef::from).collect(),
            publishes: Deliberative::ports().into_iter().map(TopicRef::from).collect(),
        });
        nodes.push(GraphNode {
            order: 0,
            name: "operator",
            layer: "ground",
            rate_hz: 0.0,
            does: "command lines in, answers out (console, script or zenoh)",
            subscribes: vec![Port::of(topics::OPERATOR_REPLY).into()],
            publishes: vec![Port::of(topics::OPERATOR_COMMAND).into()],
        });
        nodes.push(GraphNode {
            order: 0,
            name: "runtime",
            layer: "runtime",
            rate_hz: 0.0,
            does: "applies state commands before each component; reports every state change",
            subscribes: vec![Port::of(topics::SYSTEM_CONTROL).into()],
            publishes: vec![Port::of(topics::SYSTEM_STATUS).into()],
        });
        let platform = if remote { "remote over the bus" } else { "simulator in process" };
        Self { mission: mission.to_string(), platform, nodes }
    }

    /// A text table: one row per node in step order, its topics listed under it.
    pub fn table(&self) -> String {
        let mut out = format!(
            "component graph of mission `{}` (platform: {}); a step visits 1..{} in order,\n\
             the deliberative layer runs before each step\n\n",
            self.mission,
            self.platform,
            self.nodes.iter().filter(|n| n.order > 0).count()
        );
        let _ = writeln!(out, "{:>2}  {:<18} {:<14} {:>7}  does", "#", "component", "layer", "rate");
        for n in &self.nodes {
            let order = if n.order > 0 { n.order.to_string() } else { "-".into() };
            let rate = if n.rate_hz > 0.0 { format!("{} Hz", n.rate_hz) } else { "tick".into() };
            let _ = writeln!(out, "{order:>2}  {:<18} {:<14} {rate:>7}  {}", n.name, n.layer, n.does);
            for t in &n.subscribes {
                let _ = writeln!(out, "{:>24}<- {} ({})", "", t.topic, t.message);
            }
            for t in &n.publishes {
                let _ = writeln!(out, "{:>24}-> {} ({})", "", t.topic, t.message);
            }
        }
        out
    }

    /// Graphviz dot text: components as boxes (labelled with step order and rate), topics as
    /// ellipses, an edge from each publisher to the topic and from the topic to each reader.
    pub fn dot(&self) -> String {
        let mut out = String::from("digraph rovernav {\n  rankdir=LR;\n  node [fontname=\"Helvetica\"];\n");
        let _ = writeln!(out, "  label=\"{} ({})\";", self.mission, self.platform);
        let mut topics: Vec<&TopicRef> =
            self.nodes.iter().flat_map(|n| n.subscribes.iter().chain(&n.publishes)).collect();
        topics.sort_by_key(|t| t.topic);
        topics.dedup_by_key(|t| t.topic);
        for n in &self.nodes {
            let label = if n.order > 0 {
                format!("{}. {}\\n{} Hz", n.order, n.name, n.rate_hz)
            } else {
                format!("{}\\n(each tick)", n.name)
            };
            let style = if n.order > 0 { "box" } else { "box, style=rounded" };
            let _ = writeln!(out, "  \"{}\" [shape={style}, label=\"{label}\"];", n.name);
        }
        for t in &topics {
            let _ = writeln!(
                out,
                "  \"{}\" [shape=ellipse, fontsize=10, label=\"{}\\n{}\"];",
                t.topic, t.topic, t.message
            );
        }
        for n in &self.nodes {
            for t in &n.publishes {
                let _ = writeln!(out, "  \"{}\" -> \"{}\";", n.name, t.topic);
            }
            for t in &n.subscribes {
                let _ = writeln!(out, "  \"{}\" -> \"{}\";", t.topic, n.name);
            }
        }
        out.push_str("}\n");
        out
    }
}
