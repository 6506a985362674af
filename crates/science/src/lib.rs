//! Onboard science (paper 003, Hayati et al., section 5): find the sky in a Navcam image, detect
//! clouds in it, detect dust devils in a short sequence from a fixed camera, and choose what to
//! downlink within a data-volume budget.
//!
//! Images in, detections out: no files, no middleware. Every detector works on a grey float
//! image ([`rovernav_vision::image::GreyF32`]) on the image's own scale (12-bit DN, 8-bit
//! values, ...), reduced first to a working size of at most a few hundred pixels a side (the
//! paper's flight code ran on the rovers' 20 MHz processor on subsampled images; here the
//! reduction is the first noise-reduction step too). Results are in full-resolution pixels.
//!
//! - [`sky`]: the horizon and the sky region (section 5.1's first step).
//! - [`cloud`]: high-variance regions inside the sky (section 5.1).
//! - [`dust_devil`]: noise reduction, average image, differences, noise removal, blobs and
//!   buffered bounding boxes (section 5.2).
//! - [`triage`]: the images or crops to send within a budget and the compact summary of the rest
//!   (section 5, introduction).

pub mod cloud;
pub mod deblock;
pub mod dust_devil;
pub mod plane;
pub mod sky;
pub mod triage;

pub use cloud::{CloudDetection, CloudParams, CloudRegion, detect_clouds};
pub use dust_devil::{DustDevilBox, DustDevilParams, FrameDetections, detect_dust_devils};
/// The detectors' image type (grey, float, on the image's own scale).
pub use rovernav_vision::image::GreyF32;
pub use sky::{SkyMask, SkyParams, segment_sky};
pub use triage::{Event, EventKind, ImageRecord, Product, TriagePlan, triage};

/// Errors of the detectors (bad input, never a panic).
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ScienceError {
    /// An image with no pixels.
    #[error("image {index}: empty image ({width}x{height})")]
    Empty {
        /// Index of the image in its sequence.
        index: usize,
        /// Width in pixels.
        width: u32,
        /// Height in pixels.
        height: u32,
    },
    /// A sequence too short for differencing.
    #[error("sequence of {frames} frames: at least {min} are needed")]
    TooFewFrames {
        /// Frames given.
        frames: usize,
        /// Frames needed.
        min: usize,
    },
    /// A frame whose size differs from the first frame's.
    #[error("frame {index}: {width}x{height}, but frame 0 is {width0}x{height0} (a fixed camera's sequence)")]
    SizeMismatch {
        /// Index of the frame.
        index: usize,
        /// Its width.
        width: u32,
        /// Its height.
        height: u32,
        /// Width of frame 0.
        width0: u32,
        /// Height of frame 0.
        height0: u32,
    },
}
