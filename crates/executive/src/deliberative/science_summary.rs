//! The compact summary a science watch ends with (paper 003 section 5: "compact summary
//! statistics on the number and type of events can be still be down-linked"): counts and kinds
//! of events, each image's time, its events' positions in the image and what was sent of it
//! (in full, as crops, or only its summary record), and the bytes sent against the budget.
//!
//! The deliberative layer publishes it on `/science/summary` when a watch ends (the telemetry log
//! keeps it as `/bus/science/summary`) and puts it, as JSON after `summary `, at the end of the
//! task's message in `report.json`.

use rovernav_science::{ImageRecord, TriagePlan};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// One detected event of an image.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct EventSummary {
    /// `cloud` or `dust_devil`.
    pub kind: String,
    /// Box in the full image: left, top, width, height (pixels).
    pub bbox: [u32; 4],
    /// Detector score (higher is stronger).
    pub score: f32,
}

/// One image of a watch: when it was taken, what was found and what is sent of it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct ImageSummary {
    /// Image id within the watch (`000`, `001`, ...).
    pub id: String,
    /// Simulated time the image was taken (s).
    pub time_s: f64,
    /// What is sent: `full`, `crops` (one per event box) or `summary_only`.
    pub product: String,
    /// Bytes sent of it beyond its summary record.
    pub bytes: u64,
    /// Its detections.
    pub events: Vec<EventSummary>,
}

/// The outcome of a watch: what the detector found and what the triage sends.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct WatchSummary {
    /// The watch task's id in the mission plan.
    pub task: u64,
    /// `clouds` or `dust_devils`.
    pub kind: String,
    /// Seconds asked between images.
    pub interval_s: f64,
    /// Images taken.
    pub images: usize,
    /// Images with at least one detection.
    pub images_with_events: usize,
    /// Detections over all images.
    pub events: usize,
    /// Detections by kind.
    pub events_by_kind: BTreeMap<String, usize>,
    /// Ids of the images sent in full.
    pub kept_full: Vec<String>,
    /// Ids of the images sent as crops around their detections.
    pub kept_crops: Vec<String>,
    /// Detections only in the summary (over budget).
    pub events_summary_only: usize,
    /// Bytes of the summary records.
    pub summary_bytes: u64,
    /// Bytes sent (summary and products).
    pub bytes_sent: u64,
    /// The budget (bytes).
    pub budget_bytes: u64,
    /// Bytes of sending every image in full.
    pub raw_bytes: u64,
    /// Every image, in the order taken.
    pub records: Vec<ImageSummary>,
}

impl WatchSummary {
    /// The summary of task `task`'s watch of `kind` from its images and their triage.
    pub fn of(task: u64, kind: &str, interval_s: f64, images: &[ImageRecord], plan: &TriagePlan) -> Self {
        let ids = |product: &str| -> Vec<String> {
            plan.decisions.iter().filter(|d| d.product.name() == product).map(|d| d.id.clone()).collect()
        };
        let records: Vec<ImageSummary> = images
            .iter()
            .zip(&plan.decisions)
            .map(|(image, decision)| ImageSummary {
                id: image.id.clone(),
                time_s: image.time_s,
                product: decision.product.name().into(),
                bytes: decision.bytes,
                events: image
                    .events
                    .iter()
                    .map(|e| EventSummary { kind: e.kind.name().into(), bbox: e.bbox, score: e.score })
                    .collect(),
            })
            .collect();
        Self {
            task,
            kind: kind.into(),
            interval_s,
            images: plan.images,
            images_with_events: plan.images_with_events,
            events: images.iter().map(|r| r.events.len()).sum(),
            events_by_kind: plan.events_by_kind.iter().map(|&(k, n)| (k.name().to_string(), n)).collect(),
            kept_full: ids("full"),
            kept_crops: ids("crops"),
            events_summary_only: plan.events_summary_only,
            summary_bytes: plan.summary_bytes,
            bytes_sent: plan.bytes_used,
            budget_bytes: plan.budget_bytes,
            raw_bytes: plan.raw_bytes,
            records,
        }
    }

    /// Images sent in full or as crops.
    pub fn kept(&self) -> usize {
        self.kept_full.len() + self.kept_crops.len()
    }

    /// The images' times (s), in the order taken.
    pub fn times_s(&self) -> Vec<f64> {
        self.records.iter().map(|r| r.time_s).collect()
    }

    /// One line for the task's message, the summary as JSON at its end.
    pub fn line(&self) -> String {
        format!(
            "{} watch: {} images, {} with events ({} detections); kept {} (full {:?}, crops {:?}), {} detections \
             summary-only; {} of {} bytes sent (budget {}); summary {}",
            self.kind,
            self.images,
            self.images_with_events,
            self.events,
            self.kept(),
            self.kept_full,
            self.kept_crops,
            self.events_summary_only,
            self.bytes_sent,
            self.raw_bytes,
            self.budget_bytes,
            serde_json::to_string(self).unwrap_or_default()
        )
    }

    /// The summary at the end of a watch task's message ([`WatchSummary::line`]); `None` when
    /// the message holds none (a watch that failed).
    pub fn from_message(message: &str) -> Option<Self> {
        let (_, json) = message.rsplit_once("; summary ")?;
        serde_json::from_str(json).ok()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rovernav_science::{Event, EventKind, triage};

    #[test]
    fn the_summary_accounts_for_every_image_and_reads_back_from_the_line() {
        let images: Vec<ImageRecord> = (0..5)
            .map(|i| ImageRecord {
                id: format!("{i:03}"),
                time_s: 100.0 + 15.0 * i as f64,
                width: 256,
                height: 256,
                bytes_per_pixel: 1.5,
                events: if i == 2 {
                    vec![Event { kind: EventKind::DustDevil, bbox: [10, 20, 30, 40], score: 33.5 }]
                } else {
                    Vec::new()
                },
            })
            .collect();
        let raw: u64 = images.iter().map(ImageRecord::full_bytes).sum();
        let plan = triage(&images, raw / 10);
        let s = WatchSummary::of(7, "dust_devils", 15.0, &images, &plan);
        assert_eq!((s.images, s.images_with_events, s.events, s.kept()), (5, 1, 1, 1));
        assert_eq!(s.records.len(), 5);
        assert_eq!(s.times_s(), vec![100.0, 115.0, 130.0, 145.0, 160.0]);
        assert_eq!(s.records[2].events[0].bbox, [10, 20, 30, 40]);
        assert_eq!(s.events_by_kind.get("dust_devil"), Some(&1));
        // Everything else is summary-only, and the bytes add up to what was sent.
        assert!(
            s.records.iter().filter(|r| r.id != "002").all(|r| r.product == "summary_only" && r.bytes == 0)
        );
        let products: u64 = s.records.iter().map(|r| r.bytes).sum();
        assert_eq!(products + s.summary_bytes, s.bytes_sent);
        assert!(s.bytes_sent <= s.budget_bytes && s.budget_bytes == raw / 10);
        assert_eq!(WatchSummary::from_message(&s.line()), Some(s));
        assert_eq!(WatchSummary::from_message("watch stopped: no frame"), None);
    }
}
