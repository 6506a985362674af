//! The run observer that logs every topic of a run to MCAP.

use crate::foxglove::publisher::Out;
use crate::foxglove::topics as fox;
use crate::foxglove::{CompressedImageMsg, FoxglovePublisher, LogMsg, foxglove_topic_table, level};
use crate::messages::{
    CommandMsg, CycleMsg, EstimateMsg, HazardContactMsg, OverlaysMsg, PlanMsg, SensorFrameMsg, SettingsMsg,
    TruthMsg, WorldMsg, camera_topic, topic_table, topics, without_images,
};
use crate::writer::{FlushPolicy, LogStats, TelemetryError, TelemetryWriter};
use rovernav_bus::Record;
use rovernav_bus::schema::titled_schema_of;
use rovernav_core::{Point2, Pose3, PoseEstimate, SensorFrame};
use rovernav_executive::messages::FrameSource;
use rovernav_executive::messages::topics::{CAMERA_IMAGE, PLATFORM_FRAME};
use rovernav_executive::{CycleRecord, Report, RunObserver, RunSettings, Trace, World};
use serde::Serialize;
use std::collections::{BTreeMap, VecDeque};
use std::fs::File;
use std::io::{BufWriter, Seek, Write};
use std::path::Path;
use std::sync::{Arc, Mutex, MutexGuard, PoisonError, mpsc};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Prefix under which every message of the component bus is logged as published (`/bus/platform/frame`),
/// beside the curated topics above that replay reads; `/camera/image` excepted (the camera
/// server's copies of the frames' images, which the log holds already).
pub const BUS_PREFIX: &str = "/bus";

/// The writer and the first error, shared with the flusher thread.
struct Shared<W: Write + Seek> {
    writer: Option<TelemetryWriter<W>>,
    error: Option<TelemetryError>,
}

impl<W: Write + Seek> Shared<W> {
    /// Runs `f` on the writer unless an earlier write failed; keeps the first error.
    fn apply(&mut self, f: impl FnOnce(&mut TelemetryWriter<W>) -> Result<(), TelemetryError>) {
        if self.error.is_none()
            && let Some(w) = self.writer.as_mut()
            && let Err(e) = f(w)
        {
            self.error = Some(e);
        }
    }
}

fn lock<W: Write + Seek>(shared: &Mutex<Shared<W>>) -> MutexGuard<'_, Shared<W>> {
    // A panic elsewhere while the lock was held leaves the writer usable: finish the log anyway.
    shared.lock().unwrap_or_else(PoisonError::into_inner)
}

/// Logs a run: attach it to `run_mission_observed`, then call [`TelemetryRecorder::finish`].
///
/// The loop closes a chunk at the end of a cycle when the flush policy says so; a timer thread
/// also closes the open chunk once it is older than the policy's interval, so that slow cycles
/// or the work after the last cycle never hold more than that in memory. Observer callbacks
/// cannot fail, so the first write error is kept, logging stops, and `finish` returns it.
/// Dropping the recorder without `finish` (a panic) still finishes the file.
pub struct TelemetryRecorder<W: Write + Seek + Send + 'static = BufWriter<File>> {
    shared: Arc<Mutex<Shared<W>>>,
    flusher: Option<(mpsc::Sender<()>, JoinHandle<()>)>,
    opened: Instant,
    last_time_ns: u64,
    last_plan: Option<Vec<Point2>>,
    plans_logged: usize,
    last_hazards: u32,
    /// The derived schema of each bus topic of the stack.
    bus_schemas: BTreeMap<&'static str, serde_json::Value>,
    /// The start (cycle 0) until its frame is logged: on the bus, or here at the latest before
    /// the first cycle.
    pending_start: Option<(u64, f64, SensorFrame)>,
    /// `(seq, t)` of the bus's command frames not yet tied to a cycle, oldest first.
    bus_frames: VecDeque<(u64, f64)>,
    /// The Foxglove topics' state, from the start of the run.
    foxglove: Option<FoxglovePublisher>,
}

impl TelemetryRecorder<BufWriter<File>> {
    /// Opens a log file (its folder is created if needed) with the default flush policy.
    pub fn create(path: &Path) -> Result<Self, TelemetryError> {
        Self::new(TelemetryWriter::create(path, FlushPolicy::default())?)
    }

    /// Opens a log file as [`TelemetryRecorder::create`] does, and sends every topic and message
    /// it writes to `sink` as well (a live view of the run).
    pub fn create_with_tee(path: &Path, sink: Box<dyn crate::LiveSink>) -> Result<Self, TelemetryError> {
        let mut writer = TelemetryWriter::create(path, FlushPolicy::default())?;
        writer.set_tee(sink);
        Self::new(writer)
    }
}

impl<W: Write + Seek + Send + 'static> TelemetryRecorder<W> {
    /// Declares every topic on a writer and starts its flush timer.
    pub fn new(mut writer: TelemetryWriter<W>) -> Result<Self, TelemetryError> {
        for (topic, name, schema, truth) in topic_table().into_iter().chain(foxglove_topic_table()) {
            let mut metadata = BTreeMap::new();
            if truth {
                metadata.insert("simulation_truth".to_string(), "true".to_string());
            }
            writer.add_topic(topic, name, &schema, &metadata)?;
        }
        let tick = (writer.policy().max_interval / 4).max(Duration::from_millis(10));
        let path = writer.path().to_path_buf();
        let shared = Arc::new(Mutex::new(Shared { writer: Some(writer), error: None }));
        let (stop, stopped) = mpsc::channel::<()>();
        let timer_shared = Arc::clone(&shared);
        let handle = std::thread::Builder::new()
            .name("telemetry-flush".into())
            .spawn(move || {
                while let Err(mpsc::RecvTimeoutError::Timeout) = stopped.recv_timeout(tick) {
                    lock(&timer_shared).apply(|w| w.flush_if_stale_at(Instant::now()).map(|_| ()));
                }
            })
            .map_err(|error| TelemetryError::Io { path, error })?;
        Ok(Self {
            shared,
            flusher: Some((stop, handle)),
            opened: Instant::now(),
            last_time_ns: 0,
            last_plan: None,
            plans_logged: 0,
            last_hazards: 0,
            bus_schemas: bus_schemas(),
            pending_start: None,
            bus_frames: VecDeque::new(),
            foxglove: None,
        })
    }

    /// Log time of a simulated time: nanoseconds, never earlier than the previous message.
    fn stamp(&mut self, sim_time_s: f64) -> u64 {
        let ns =
            if sim_time_s.is_finite() && sim_time_s > 0.0 { (sim_time_s * 1e9).round() as u64 } else { 0 };
        self.last_time_ns = self.last_time_ns.max(ns);
        self.last_time_ns
    }

    fn put<T: Serialize>(&self, topic: &str, time_ns: u64, msg: &T) {
        lock(&self.shared).apply(|w| w.write(topic, time_ns, msg));
    }

    /// Logs a frame's camera images as PNG, each on its camera's topic (declared on first use).
    fn put_images(&self, time_ns: u64, frame: &SensorFrame) {
        for image in &frame.images {
            let topic = camera_topic(&image.camera);
            let msg = match CompressedImageMsg::of(image) {
                Ok(msg) => msg,
                Err(why) => {
                    let line =
                        LogMsg::new(image.t, level::WARNING, "telemetry", format!("image not logged: {why}"));
                    self.put(fox::LOG, time_ns, &line);
                    continue;
                }
            };
            lock(&self.shared).apply(|w| {
                if !w.has_topic(&topic) {
                    let schema = titled_schema_of::<CompressedImageMsg>(fox::COMPRESSED_IMAGE);
                    w.add_topic(&topic, fox::COMPRESSED_IMAGE, &schema, &BTreeMap::new())?;
                }
                w.write(&topic, time_ns, &msg)
            });
        }
    }

    /// Writes the Foxglove publisher's messages at `time_ns`.
    fn put_all(&self, time_ns: u64, outs: Vec<Out>) {
        let mut shared = lock(&self.shared);
        for o in outs {
            shared.apply(|w| w.write_json(o.topic, time_ns, &o.json));
        }
    }

    fn end_cycle(&self, cycle: u64, sim_time_s: f64, t: u64) {
        let wall_time_s = self.opened.elapsed().as_secs_f64();
        self.put(topics::CYCLE, t, &CycleMsg { cycle, sim_time_s, wall_time_s });
    }

    /// Logs a plan when it differs from the last one, by the loop's rule for `Trace::plans`.
    fn put_plan(&mut self, cycle: u64, sim_time_s: f64, t: u64, plan: &[Point2]) {
        if plan.is_empty() || self.last_plan.as_deref() == Some(plan) {
            return;
        }
        self.put(topics::PLAN, t, &PlanMsg { cycle, sim_time_s, points: plan.to_vec() });
        self.last_plan = Some(plan.to_vec());
        self.plans_logged += 1;
    }

    /// Logs cycle 0's frame (on the bus as message `bus_seq`, or here) and its end, once.
    fn log_start(&mut self, bus_seq: Option<u64>) {
        if let Some((t, sim_time_s, frame)) = self.pending_start.take() {
            let msg = match bus_seq {
                Some(seq) => SensorFrameMsg::on_bus(0, seq),
                None => SensorFrameMsg { cycle: 0, bus_seq: None, frame: Some(frame) },
            };
            self.put(topics::SENSOR_FRAME, t, &msg);
            self.end_cycle(0, sim_time_s, t);
        }
    }

    /// Stops the flush timer.
    fn stop_timer(&mut self) {
        if let Some((stop, handle)) = self.flusher.take() {
            drop(stop);
            // The timer only flushes; if it panicked, finishing below reports any write error.
            let _ = handle.join();
        }
    }

    /// Closes the last chunk and writes the summary; returns the first error of the run.
    pub fn finish(mut self) -> Result<LogStats, TelemetryError> {
        self.log_start(None);
        self.stop_timer();
        let mut shared = lock(&self.shared);
        let finished = match shared.writer.take() {
            Some(w) => w.finish(),
            None => Ok(LogStats::default()),
        };
        match shared.error.take() {
            Some(e) => Err(e),
            None => finished,
        }
    }
}

impl<W: Write + Seek + Send + 'static> Drop for TelemetryRecorder<W> {
    fn drop(&mut self) {
        self.log_start(None);
        self.stop_timer();
        // Without `finish` (a panic unwinding through the run): close the file properly anyway.
        if let Some(w) = lock(&self.shared).writer.take() {
            let _ = w.finish();
        }
    }
}

/// The derived schema of every bus topic of the stack: the components' and the remote
/// platform link's (a rover process logs its link to the simulator).
fn bus_schemas() -> BTreeMap<&'static str, serde_json::Value> {
    use rovernav_executive::remote::{PLATFORM_REPLY, PLATFORM_REQUEST};
    let mut all: BTreeMap<_, _> = rovernav_executive::messages::topics::all().into_iter().collect();
    all.insert(PLATFORM_REQUEST.name(), PLATFORM_REQUEST.schema());
    all.insert(PLATFORM_REPLY.name(), PLATFORM_REPLY.schema());
    all
}

/// The part of a `/platform/frame` bus message that ties it to a cycle.
#[derive(serde::Deserialize)]
struct FrameHead {
    seq: u64,
    source: FrameSource,
    frame: FrameTime,
}

/// A frame's time (the rest of the frame is skipped).
#[derive(serde::Deserialize)]
struct FrameTime {
    t: f64,
}

/// The true pose the simulator starts from: the rover settled on the terrain at the start
/// (the same rule as `Simulator::new`), or the bare start pose off the terrain.
fn initial_truth(world: &World) -> Pose3 {
    rovernav_sim::vehicle::settled_pose(&world.terrain.dem, &world.rover, world.start)
}

impl<W: Write + Seek + Send + 'static> RunObserver for TelemetryRecorder<W> {
    fn on_start(
        &mut self,
        world: &World,
        settings: &RunSettings,
        frame: &SensorFrame,
        estimate: &PoseEstimate,
    ) {
        let t = self.stamp(frame.t);
        self.put(topics::WORLD, t, &WorldMsg::of(world));
        self.put(topics::SETTINGS, t, &SettingsMsg::of(settings));
        self.put(topics::ESTIMATE, t, &EstimateMsg::of(0, frame.t, estimate));
        let truth = TruthMsg {
            simulation_truth: true,
            cycle: 0,
            sim_time_s: frame.t,
            pose: initial_truth(world),
            hazard_contacts: 0,
        };
        self.put(topics::TRUTH, t, &truth);
        let (foxglove, outs) = FoxglovePublisher::start(world, settings, frame.t, estimate, &truth.pose);
        self.foxglove = Some(foxglove);
        self.put_all(t, outs);
        // The frame and the end of cycle 0 follow with the bus's initial frame (`on_bus`).
        self.pending_start = Some((t, frame.t, without_images(frame)));
        // The world is the largest message and everything replay needs: get it to disk now.
        lock(&self.shared).apply(|w| w.flush());
    }

    fn on_cycle(&mut self, r: &CycleRecord<'_>) {
        self.log_start(None);
        let t = self.stamp(r.sim_time_s);
        self.put(topics::COMMAND, t, &CommandMsg::of(r.cycle, r.sim_time_s, r.command));
        // The bus's next command frame is this cycle's when their times agree bit for bit.
        let frame_msg = match self.bus_frames.pop_front() {
            Some((seq, bus_t)) if bus_t.to_bits() == r.frame.t.to_bits() => {
                SensorFrameMsg::on_bus(r.cycle, seq)
            }
            _ => {
                self.bus_frames.clear();
                SensorFrameMsg::of(r.cycle, r.frame)
            }
        };
        self.put(topics::SENSOR_FRAME, t, &frame_msg);
        if let Some(power) = &r.frame.power {
            self.put(topics::POWER, t, power);
        }
        self.put_images(t, r.frame);
        self.put(topics::ESTIMATE, t, &EstimateMsg::of(r.cycle, r.sim_time_s, r.estimate));
        let truth = TruthMsg {
            simulation_truth: true,
            cycle: r.cycle,
            sim_time_s: r.sim_time_s,
            pose: *r.truth,
            hazard_contacts: r.hazard_contacts,
        };
        self.put(topics::TRUTH, t, &truth);
        self.put_plan(r.cycle, r.sim_time_s, t, r.plan);
        // The loop's rule for a report's hazard event: the count went up this cycle.
        if r.hazard_contacts > self.last_hazards {
            self.last_hazards = r.hazard_contacts;
            let contact = HazardContactMsg {
                simulation_truth: true,
                cycle: r.cycle,
                sim_time_s: r.sim_time_s,
                x: r.truth.x,
                y: r.truth.y,
                contacts: r.hazard_contacts,
                cause: r.frame.motion_stopped.clone().unwrap_or_default(),
            };
            self.put(topics::HAZARD_CONTACTS, t, &contact);
        }
        if let Some(foxglove) = self.foxglove.as_mut() {
            let outs = foxglove.cycle(r);
            self.put_all(t, outs);
        }
        self.end_cycle(r.cycle, r.sim_time_s, t);
        lock(&self.shared).apply(|w| w.maybe_flush().map(|_| ()));
    }

    fn wants_bus(&self) -> bool {
        true
    }

    fn wants_overlays(&self) -> bool {
        true
    }

    fn on_bus(&mut self, records: &[Record]) {
        for record in records {
            // The camera server republishes the images of the platform's frames, which the log
            // holds already (in `/bus/platform/frame`, and as PNG on `/camera/NAME`).
            if record.topic == CAMERA_IMAGE.name() {
                continue;
            }
            let topic = format!("{BUS_PREFIX}{}", record.topic);
            let t = self.stamp(record.time_s);
            let bus_schemas = &self.bus_schemas;
            lock(&self.shared).apply(|w| {
                if !w.has_topic(&topic) {
                    // The stack's topics carry the message types' derived schemas; a topic
                    // outside that table (a test's) is any JSON, said so in a schema that is
                    // still a schema (titled and described), never an empty one.
                    let metadata = BTreeMap::from([("bus_topic".to_string(), record.topic.clone())]);
                    let name = if record.type_name.is_empty() { "json" } else { &record.type_name };
                    let schema = bus_schemas.get(record.topic.as_str()).cloned().unwrap_or_else(|| {
                        serde_json::json!({
                            "$schema": "https://json-schema.org/draft/2020-12/schema",
                            "title": name,
                            "description": format!("`{}` as published on the bus: a message type outside the stack's topic table, any JSON", record.topic),
                        })
                    });
                    w.add_topic(&topic, name, &schema, &metadata)?;
                }
                w.write_json(&topic, t, &record.payload)
            });
            if let Some(line) = self.foxglove.as_mut().and_then(|f| f.bus(record)) {
                self.put_all(t, vec![line]);
            }
            if record.topic == PLATFORM_FRAME.name()
                && let Ok(head) = serde_json::from_slice::<FrameHead>(&record.payload)
            {
                match head.source {
                    FrameSource::Initial => self.log_start(Some(head.seq)),
                    FrameSource::Command(_) => self.bus_frames.push_back((head.seq, head.frame.t)),
                    FrameSource::Hold => {}
                }
            }
        }
    }

    fn on_finish(&mut self, report: &Report, trace: &Trace) {
        self.log_start(None);
        let t = self.stamp(report.sim_time_s);
        // The plan of the finishing step is announced without a cycle of its own.
        let unlogged: Vec<Vec<Point2>> = trace.plans.iter().skip(self.plans_logged).cloned().collect();
        for plan in unlogged {
            self.put_plan(report.cycles, report.sim_time_s, t, &plan);
        }
        self.put(
            topics::OVERLAYS,
            t,
            &OverlaysMsg { sim_time_s: report.sim_time_s, overlays: trace.overlays.clone() },
        );
        if let Some(foxglove) = self.foxglove.as_mut() {
            let outs = foxglove.finish(report, trace);
            self.put_all(t, outs);
        }
        self.put(topics::REPORT, t, report);
        lock(&self.shared).apply(|w| w.flush());
    }
}
