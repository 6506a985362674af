//! Telemetry of visual target tracking (issue 35 item 3): one `/vtt/track` message per image an
//! approach or a track-only task saw, with the template matched, the match and its score, and
//! the target's estimate in the site and rover frames (paper 003 section 3: "target position in
//! rover and site frames").

use rovernav_vision::image::GreyF32;
use rovernav_vision::tracking::Observation;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// A small grey image (a tracking template), row-major.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct TemplateMsg {
    /// Columns.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Grey values (the camera's DN), row by row.
    pub pixels: Vec<f32>,
}

impl TemplateMsg {
    /// The template of an image.
    pub fn of(image: &GreyF32) -> Self {
        Self { width: image.width(), height: image.height(), pixels: image.as_raw().clone() }
    }
}

/// The correlation peak of a match.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct MatchMsg {
    /// Subpixel column (sample) of the target in the image.
    pub x: f64,
    /// Subpixel row (line).
    pub y: f64,
    /// Normalised cross-correlation at the peak.
    pub score: f32,
    /// Best separate second peak.
    pub second: f32,
    /// Peak sharpness (negated second difference, per px²).
    pub curvature: f32,
    /// Predicted column and row searched around.
    pub predicted: [f64; 2],
    /// Half-size of the search window (px).
    pub search_half_px: usize,
    /// Template magnification applied (old range / new range).
    pub scale: f64,
    /// Template rotation (rad).
    pub rotation_rad: f64,
}

/// One image visual target tracking saw.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct VttTrackMsg {
    /// The plan task (an `approach_target` or a `track_target`).
    pub task: u64,
    /// `approach` (VTT drives) or `track_only` (another plan drives).
    pub mode: String,
    /// Images seen by this task so far, this one included (1: the designation).
    pub image_index: usize,
    /// The platform frame that holds the image.
    pub frame_seq: u64,
    /// Simulated time of the image (s).
    pub t: f64,
    /// Navcam head pan and tilt (rad, body frame).
    pub pan: f64,
    /// Head tilt (rad).
    pub tilt: f64,
    /// `designated`, `tracked`, or `lost: WHY`.
    pub status: String,
    /// The match (absent for the designation and a loss).
    pub matched: Option<MatchMsg>,
    /// The template matched (the designation's own for the first image).
    pub template: Option<TemplateMsg>,
    /// Pixel (column, row) of the target in this image.
    pub pixel: Option<[f64; 2]>,
    /// The target's site-frame position after this image (m).
    pub site: Option<[f64; 3]>,
    /// The target's position in the rover frame at this image (m).
    pub rover: Option<[f64; 3]>,
    /// Range from the camera (m) and its standard deviation (m).
    pub range_m: Option<[f64; 2]>,
}

impl VttTrackMsg {
    /// The message of an image that gave `o`.
    pub fn observed(head: VttTrackMsg, o: &Observation) -> Self {
        let t = &o.target;
        let matched = o.matched.map(|m| MatchMsg {
            x: m.x,
            y: m.y,
            score: m.peak.score,
            second: m.peak.second,
            curvature: m.peak.curvature,
            predicted: [m.prediction.x, m.prediction.y],
            search_half_px: m.prediction.half_window,
            scale: m.warp.scale,
            rotation_rad: m.warp.rotation_rad,
        });
        Self {
            image_index: o.image_index,
            status: if matched.is_some() { "tracked" } else { "designated" }.into(),
            matched,
            template: Some(TemplateMsg::of(&o.template)),
            pixel: Some([t.pixel.x, t.pixel.y]),
            site: Some([t.site.x, t.site.y, t.site.z]),
            rover: Some([t.rover.x, t.rover.y, t.rover.z]),
            range_m: Some([t.range_m, t.range_sigma_m]),
            ..head
        }
    }
}

/// What the traverse picture draws of one VTT task: the designated target and the site-frame
/// estimates of it from the images tracked after the designation, in order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct VttTrace {
    /// The plan task.
    pub task: u64,
    /// The target's site position at the designation (m).
    pub target: [f64; 3],
    /// The target's site position after each later image tracked (m).
    pub estimates: Vec<[f64; 3]>,
}

impl VttTrace {
    /// One trace per task (by task id) from the site positions of its images in order, the
    /// designation first; a task with no position is left out.
    pub fn of_sites(tasks: impl IntoIterator<Item = (u64, Vec<[f64; 3]>)>) -> Vec<Self> {
        let mut out: Vec<Self> = tasks
            .into_iter()
            .filter_map(|(task, sites)| {
                let (&target, rest) = sites.split_first()?;
                Some(Self { task, target, estimates: rest.to_vec() })
            })
            .collect();
        out.sort_by_key(|t| t.task);
        out
    }

    /// The traces of logged `/vtt/track` records (those with a site position, grouped by task).
    pub fn of_records<'a>(records: impl IntoIterator<Item = &'a VttTrackMsg>) -> Vec<Self> {
        let mut by_task: std::collections::BTreeMap<u64, Vec<[f64; 3]>> = Default::default();
        for r in records {
            if let Some(site) = r.site {
                by_task.entry(r.task).or_default().push(site);
            }
        }
        Self::of_sites(by_task)
    }
}
