//! Reading a run's log back, and rebuilding the run (world, trace, report) from it alone.
//!
//! The log is read linearly, so a file cut short by a killed process yields every message up to
//! its last complete chunk; [`LogEnd`] says how far it got and why it stopped.

use crate::messages::{
    CommandMsg, CycleMsg, EstimateMsg, HazardContactMsg, OverlaysMsg, PlanMsg, SensorFrameMsg, SettingsMsg,
    TruthMsg, WorldMsg, topics, without_images,
};
use crate::writer::TelemetryError;
use rovernav_core::{Point2, Pose3, SensorFrame};
use rovernav_executive::deliberative::VttTrace;
use rovernav_executive::judge::sensed_grid;
use rovernav_executive::{HazardEvent, Report, StageTimes, Trace, World};
use rovernav_harness::mark_sensed;
use serde::Deserialize;
use serde::de::DeserializeOwned;
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

/// How far a log could be read.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LogEnd {
    /// Messages read.
    pub messages: u64,
    /// Log time of the last message read (ns).
    pub last_log_time_ns: u64,
    /// Why reading stopped before the end of a well-formed file (a truncated or damaged log).
    pub truncated: Option<String>,
}

/// Every message of a run's log, by topic, in log order.
#[derive(Clone, Debug, Default)]
pub struct LoggedRun {
    /// The log file.
    pub path: PathBuf,
    /// `/sim/world`.
    pub world: Option<WorldMsg>,
    /// `/executive/settings`.
    pub settings: Option<SettingsMsg>,
    /// `/platform/sensor_frame`, each frame resolved (from `/bus/platform/frame` when the
    /// cycle's message points there).
    pub frames: Vec<LoggedFrame>,
    /// `/navigation/command`.
    pub commands: Vec<CommandMsg>,
    /// `/localization/estimate`.
    pub estimates: Vec<EstimateMsg>,
    /// `/sim/truth`.
    pub truths: Vec<TruthMsg>,
    /// `/navigation/plan`.
    pub plans: Vec<PlanMsg>,
    /// `/sim/hazard_contacts`.
    pub hazards: Vec<HazardContactMsg>,
    /// `/executive/cycle`.
    pub cycles: Vec<CycleMsg>,
    /// `/navigation/overlays`.
    pub overlays: Option<OverlaysMsg>,
    /// `/executive/report`.
    pub report: Option<Report>,
    /// `/bus/arm/placement`: every instrument placement the tooling arm decided.
    pub placements: Vec<rovernav_executive::arm_server::PlacementMsg>,
    /// `/bus/science/summary`: every science watch's summary, in the order the watches ended.
    pub science: Vec<rovernav_executive::deliberative::WatchSummary>,
    /// `/bus/vtt/track`: every image visual target tracking saw, in order.
    pub vtt: Vec<rovernav_executive::deliberative::VttTrackMsg>,
    /// Messages per topic (unknown topics included: they are counted and skipped).
    pub topic_counts: BTreeMap<String, u64>,
    /// How far reading got.
    pub end: LogEnd,
}

/// One cycle's sensor frame.
#[derive(Clone, Debug, PartialEq)]
pub struct LoggedFrame {
    /// Cycle (0: the frame before the first command).
    pub cycle: u64,
    /// The frame (without camera images).
    pub frame: SensorFrame,
}

/// The part of a `/bus/platform/frame` message the reader keeps.
#[derive(Deserialize)]
struct BusFrame {
    seq: u64,
    frame: SensorFrame,
}

/// Reads a log; a truncated file is not an error (see [`LogEnd::truncated`]), a message that
/// does not decode is.
pub fn read_log(path: &Path) -> Result<LoggedRun, TelemetryError> {
    let bytes =
        std::fs::read(path).map_err(|error| TelemetryError::Io { path: path.to_path_buf(), error })?;
    parse_log(&bytes, path)
}

/// Parses log bytes; `path` names the log in errors.
pub fn parse_log(bytes: &[u8], path: &Path) -> Result<LoggedRun, TelemetryError> {
    let content = |message: String| TelemetryError::Content { path: path.to_path_buf(), message };
    if !bytes.starts_with(mcap::MAGIC) {
        let what = if bytes.is_empty() { "empty file" } else { "no MCAP magic at the start" };
        return Err(content(format!("not an MCAP log ({what})")));
    }
    let mut run = LoggedRun { path: path.to_path_buf(), ..Default::default() };
    // Bus frames by number, until a cycle's message claims them.
    let mut bus_frames: HashMap<u64, SensorFrame> = HashMap::new();
    for item in bounded_messages(bytes) {
        let msg = match item {
            Ok(m) => m,
            Err(e) => {
                run.end.truncated = Some(e.to_string());
                break;
            }
        };
        let topic = msg.channel.topic.as_str();
        *run.topic_counts.entry(topic.to_string()).or_default() += 1;
        run.end.messages += 1;
        run.end.last_log_time_ns = msg.log_time;
        let data: &[u8] = &msg.data;
        let decode_err = |e: String| content(format!("topic `{topic}` message {}: {e}", msg.sequence));
        match topic {
            topics::WORLD => run.world = Some(decode(data).map_err(decode_err)?),
            topics::SETTINGS => run.settings = Some(decode(data).map_err(decode_err)?),
            topics::SENSOR_FRAME => {
                let m: SensorFrameMsg = decode(data).map_err(decode_err)?;
                let frame = match (m.frame, m.bus_seq) {
                    (Some(frame), _) => frame,
                    (None, Some(seq)) => bus_frames.remove(&seq).ok_or_else(|| {
                        decode_err(format!("field `bus_seq`: no `{BUS_FRAME}` message {seq} before it"))
                    })?,
                    (None, None) => return Err(decode_err("neither `frame` nor `bus_seq`".into())),
                };
                run.frames.push(LoggedFrame { cycle: m.cycle, frame: without_images(&frame) });
            }
            BUS_FRAME => {
                let m: BusFrame = decode(data).map_err(decode_err)?;
                bus_frames.insert(m.seq, m.frame);
            }
            topics::COMMAND => run.commands.push(decode(data).map_err(decode_err)?),
            topics::ESTIMATE => run.estimates.push(decode(data).map_err(decode_err)?),
            topics::TRUTH => run.truths.push(decode(data).map_err(decode_err)?),
            topics::PLAN => run.plans.push(decode(data).map_err(decode_err)?),
            topics::HAZARD_CONTACTS => run.hazards.push(decode(data).map_err(decode_err)?),
            topics::CYCLE => run.cycles.push(decode(data).map_err(decode_err)?),
            topics::OVERLAYS => run.overlays = Some(decode(data).map_err(decode_err)?),
            topics::REPORT => run.report = Some(decode(data).map_err(decode_err)?),
            topics::ARM_PLACEMENT => run.placements.push(decode(data).map_err(decode_err)?),
            topics::SCIENCE_SUMMARY => run.science.push(decode(data).map_err(decode_err)?),
            topics::VTT_TRACK => run.vtt.push(decode(data).map_err(decode_err)?),
            _ => {}
        }
    }
    Ok(run)
}

/// Where the recorder logs the platform's frames as the bus carried them.
const BUS_FRAME: &str = "/bus/platform/frame";

/// The log's messages in file order, each record at most 64 times the log's length (64 MiB at
/// least: a chunk decompresses to more than it takes) and within the memory ceiling
/// (`rovernav_core::limits`): `mcap::MessageStream` applies no limit inside chunks, so a corrupt
/// record length there made it try to allocate petabytes (found by tests/fuzz_log.rs).
pub fn bounded_messages(
    bytes: &[u8],
) -> impl Iterator<Item = Result<mcap::Message<'static>, mcap::McapError>> + '_ {
    use mcap::sans_io::{LinearReaderOptions, MessageReadEvent, MessageReader};
    let ceiling = usize::try_from(rovernav_core::limits::max_alloc_bytes()).unwrap_or(usize::MAX);
    let limit = bytes.len().saturating_mul(64).max(64 << 20).min(ceiling);
    let mut reader =
        MessageReader::new_with_options(LinearReaderOptions::default().with_record_length_limit(limit));
    let mut rest = bytes;
    std::iter::from_fn(move || {
        loop {
            match reader.next_event()? {
                Ok(MessageReadEvent::ReadRequest(need)) => {
                    let n = need.min(rest.len());
                    reader.insert(n).copy_from_slice(&rest[..n]);
                    reader.notify_read(n);
                    rest = &rest[n..];
                }
                Ok(MessageReadEvent::Message(message)) => return Some(Ok(message)),
                Err(e) => return Some(Err(e)),
            }
        }
    })
}

fn decode<T: DeserializeOwned>(data: &[u8]) -> Result<T, String> {
    serde_json::from_slice(data).map_err(|e| e.to_string())
}

/// A run rebuilt from its log.
pub struct ReplayedRun {
    /// The world.
    pub world: World,
    /// The traverse, with the sensed area recomputed from the logged clouds.
    pub trace: Trace,
    /// The logged report, or for a cut-off log one recomputed from the logged cycles.
    pub report: Report,
    /// Whether the log holds the whole run (its final report).
    pub complete: bool,
}

impl LoggedRun {
    /// The last cycle whose messages are all in the log (its `/executive/cycle` marker is).
    pub fn last_complete_cycle(&self) -> Option<CycleMsg> {
        self.cycles.last().copied()
    }

    fn content_err(&self, message: String) -> TelemetryError {
        TelemetryError::Content { path: self.path.clone(), message }
    }

    /// Rebuilds the run: the whole run when the log holds its report, else everything up to the
    /// last complete cycle with a report recomputed from it (outcome `aborted`).
    pub fn replay(&self) -> Result<ReplayedRun, TelemetryError> {
        let world_msg = self.world.as_ref().ok_or_else(|| {
            self.content_err(format!(
                "no `{}` message: the log ends before the run started ({} messages read)",
                topics::WORLD,
                self.end.messages
            ))
        })?;
        let world =
            world_msg.to_world().map_err(|e| self.content_err(format!("topic `{}`: {e}", topics::WORLD)))?;
        let last = self.last_complete_cycle().ok_or_else(|| {
            self.content_err(format!("no `{}` message: the log ends before the first cycle", topics::CYCLE))
        })?;
        let upto = self.report.as_ref().map_or(last.cycle, |r| r.cycles);
        let trace = self.trace(&world, upto)?;
        let (report, complete) = match &self.report {
            Some(r) => (r.clone(), true),
            None => (self.recomputed_report(&world, &trace, last)?, false),
        };
        Ok(ReplayedRun { world, trace, report, complete })
    }

    /// One message per cycle 0..=upto, in cycle order, or an error naming the first gap.
    fn per_cycle<'a, T>(
        &self,
        items: &'a [T],
        cycle: impl Fn(&T) -> u64,
        topic: &str,
        upto: u64,
    ) -> Result<Vec<&'a T>, TelemetryError> {
        let picked: Vec<&T> = items.iter().filter(|m| cycle(m) <= upto).collect();
        for (k, m) in picked.iter().enumerate() {
            if cycle(m) != k as u64 {
                return Err(self
                    .content_err(format!("topic `{topic}`: expected cycle {k}, found cycle {}", cycle(m))));
            }
        }
        if picked.len() as u64 != upto + 1 {
            return Err(
                self.content_err(format!("topic `{topic}`: {} messages for cycles 0..={upto}", picked.len()))
            );
        }
        Ok(picked)
    }

    /// The traverse up to cycle `upto`.
    pub fn trace(&self, world: &World, upto: u64) -> Result<Trace, TelemetryError> {
        let truths = self.per_cycle(&self.truths, |m| m.cycle, topics::TRUTH, upto)?;
        let estimates = self.per_cycle(&self.estimates, |m| m.cycle, topics::ESTIMATE, upto)?;
        let frames = self.per_cycle(&self.frames, |m| m.cycle, topics::SENSOR_FRAME, upto)?;
        let cycles = self.per_cycle(&self.cycles, |m| m.cycle, topics::CYCLE, upto)?;
        let truth: Vec<Pose3> = truths.iter().map(|m| m.pose).collect();
        let mut sensed = sensed_grid(world);
        // The loop marks the clouds of executed commands only, placed with the true pose.
        for (frame, pose) in frames.iter().zip(&truth).skip(1) {
            for cloud in &frame.frame.clouds {
                mark_sensed(&mut sensed, pose, cloud);
            }
        }
        let overlays = match (&self.overlays, &self.report) {
            (Some(o), Some(_)) => o.overlays.clone(),
            _ => Vec::new(),
        };
        Ok(Trace {
            truth,
            estimate: estimates.iter().map(|m| m.estimate.pose).collect(),
            plans: self.plans.iter().filter(|p| p.cycle <= upto).map(|p| p.points.clone()).collect(),
            overlays,
            // A whole run: every image; a cut: the images taken up to its last cycle's time.
            vtt: VttTrace::of_records(self.vtt.iter().filter(|r| {
                cycles.len() >= self.cycles.len() || cycles.last().is_none_or(|c| r.t <= c.sim_time_s)
            })),
            sensed: Some(sensed),
            sim_time_s: cycles.iter().map(|m| m.sim_time_s).collect(),
            // The logging run's wall clock between cycle markers: the loop's time per cycle.
            compute_s: std::iter::once(0.0)
                .chain(cycles.windows(2).map(|w| (w[1].wall_time_s - w[0].wall_time_s).max(0.0)))
                .collect(),
        })
    }

    /// The report of a run cut off after cycle `last`, recomputed from the logged cycles.
    ///
    /// Exact for every figure but two: `distance_driven_m` sums straight segments between the
    /// logged poses (a lower bound of the simulator's integrated path), and `compute_per_cycle`
    /// is not logged (zero).
    // Report fields added later (not logged per cycle) take their defaults: the struct update
    // stays, and is needless only while every field is listed.
    #[allow(clippy::needless_update)]
    pub fn recomputed_report(
        &self,
        world: &World,
        trace: &Trace,
        last: CycleMsg,
    ) -> Result<Report, TelemetryError> {
        let settings = self
            .settings
            .as_ref()
            .ok_or_else(|| self.content_err(format!("no `{}` message", topics::SETTINGS)))?;
        let truths = self.per_cycle(&self.truths, |m| m.cycle, topics::TRUTH, last.cycle)?;
        let frames = self.per_cycle(&self.frames, |m| m.cycle, topics::SENSOR_FRAME, last.cycle)?;
        let (Some(truth), Some(estimate), Some(final_truth)) =
            (trace.truth.last(), trace.estimate.last(), truths.last())
        else {
            return Err(self.content_err("no logged pose".into()));
        };
        let goal = world.goal.position;
        let distance: f64 = trace
            .truth
            .windows(2)
            .map(|w| {
                ((w[1].x - w[0].x).powi(2) + (w[1].y - w[0].y).powi(2) + (w[1].z - w[0].z).powi(2)).sqrt()
            })
            .sum();
        Ok(Report {
            outcome: "aborted".into(),
            message: format!(
                "telemetry log ends at cycle {} (sim time {:.1} s): the run was cut off; figures recomputed from the logged cycles",
                last.cycle, last.sim_time_s
            ),
            goal_error_m: Point2::new(truth.x, truth.y).dist(goal),
            distance_driven_m: distance,
            optimal_length_m: rovernav_harness::optimal_length(world),
            hazard_contacts: final_truth.hazard_contacts,
            sim_time_s: last.sim_time_s,
            wall_time_s: last.wall_time_s,
            cycles: last.cycle,
            sensing_actions: frames.iter().skip(1).map(|f| f.frame.clouds.len() as u64).sum(),
            localization_error_m: (truth.x - estimate.x).hypot(truth.y - estimate.y),
            navigator: settings.navigator.clone(),
            localizer: settings.localizer.clone(),
            seed: settings.seed,
            mission: settings.name.clone(),
            straight_line_m: world.start.position().dist(goal),
            hazard_events: self
                .hazards
                .iter()
                .filter(|h| h.cycle <= last.cycle)
                .map(|h| HazardEvent { x: h.x, y: h.y, cycle: h.cycle, cause: h.cause.clone() })
                .collect(),
            compute_per_cycle: StageTimes::default(),
            ..Report::default()
        })
    }
}
