//! `rovernav stereo LEFT RIGHT`: correlates a rectified pair of image files and, given a
//! ground-truth disparity image, scores the result as the Middlebury benchmark does.
//!
//! The figures, over the pixels whose true disparity is known (all pixels without a truth):
//! - `valid_fraction`: the pixels the matcher measured (its filters reject the others);
//! - `mean_abs_error_px`: the mean error of the measured pixels;
//! - `measured_bad_pixel_fraction`: the measured map scored with every invalid pixel bad;
//! - `bad_pixel_fraction`: the benchmark's figure, where every pixel is scored: the invalid
//!   pixels are first filled from the background side (Hirschmüller 2008, section 4.4, as in
//!   the SGM figures Middlebury publishes), and a pixel still invalid after it counts as bad.
//!   Only the score is filled: the written disparity and the range the navigation uses keep
//!   their invalid pixels, since a filled range invents terrain. Unfilled, Cones could not meet
//!   the 15 % target at all: 7 % of its known pixels see past the right image's left edge and
//!   4 % are occluded, and no measurement exists there.

use anyhow::Context;
use rovernav_vision::image::{Grey16, Rgb8};
use rovernav_vision::stereo::{self, Disparity, INVALID_DISPARITY, StereoParams};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Options of `rovernav stereo`.
#[derive(clap::Args, Debug)]
pub struct StereoArgs {
    /// Left (reference) image of a rectified pair: PNG, PPM, PGM or JPEG (colour is converted to grey).
    left: PathBuf,
    /// Right image, the same size.
    right: PathBuf,
    /// Largest disparity searched (pixels): disparities 0..=D.
    #[arg(long, value_name = "D", default_value_t = 64)]
    max_disparity: usize,
    /// Ground-truth disparity of the left image (pixel value / S = disparity; 0 = unknown).
    #[arg(long, value_name = "DISP")]
    truth: Option<PathBuf>,
    /// Scale S of the ground-truth image's pixel values (16 for Tsukuba, 4 for Cones).
    #[arg(long, value_name = "S")]
    truth_scale: Option<f64>,
    /// Write disparity.png (16-bit, disparity x 16, 0 = invalid) and disparity_colour.png here.
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Print the figures as a JSON object.
    #[arg(long)]
    json: bool,
}

/// Runs `rovernav stereo`.
pub fn run(args: StereoArgs) -> anyhow::Result<()> {
    let truth_scale = match (&args.truth, args.truth_scale) {
        (Some(_), None) => anyhow::bail!("--truth-scale: required with --truth"),
        (None, Some(_)) => anyhow::bail!("--truth-scale: given without --truth"),
        (_, Some(s)) if !(s.is_finite() && s > 0.0) => {
            anyhow::bail!("--truth-scale {s}: must be a positive number")
        }
        (_, s) => s.unwrap_or(1.0),
    };
    let left = read_grey(&args.left)?;
    let right = read_grey(&args.right)?;
    if left.dimensions() != right.dimensions() {
        anyhow::bail!(
            "{}: the right image is {}x{} but the left image {} is {}x{}",
            args.right.display(),
            right.width(),
            right.height(),
            args.left.display(),
            left.width(),
            left.height()
        );
    }
    let truth = match &args.truth {
        Some(path) => Some(read_truth(path, truth_scale, left.dimensions())?),
        None => None,
    };
    let params = StereoParams { max_disparity: args.max_disparity, ..StereoParams::default() };
    let started = Instant::now();
    let disp = stereo::compute_disparity(&left, &right, &params).map_err(|e| match e {
        stereo::StereoError::BadParameter { name: "max_disparity", message } => {
            anyhow::anyhow!("--max-disparity {}: {message}", args.max_disparity)
        }
        e => anyhow::anyhow!("{}: {e}", args.left.display()),
    })?;
    let seconds = started.elapsed().as_secs_f64();
    if let Some(dir) = &args.out {
        write_outputs(dir, &disp, args.max_disparity)?;
    }
    let mut figures = serde_json::json!({
        "left": args.left.display().to_string(),
        "right": args.right.display().to_string(),
        "width": disp.width,
        "height": disp.height,
        "max_disparity": args.max_disparity,
        "seconds": seconds,
        "valid_fraction": disp.valid_fraction(),
    });
    if let Some(truth) = &truth {
        // The measured map: its valid fraction and error, invalid pixels counted bad.
        let measured = stereo::score_against_truth(&disp, truth, 1.0).expect("sizes checked on reading");
        // The benchmark's figure scores every pixel: the invalid ones filled from the background.
        let mut filled = disp.clone();
        stereo::filters::fill_from_background(&mut filled.data, filled.width);
        let scored = stereo::score_against_truth(&filled, truth, 1.0).expect("same size");
        figures["known_pixels"] = measured.known_pixels.into();
        figures["bad_pixel_fraction"] = scored.bad_pixel_fraction.into();
        figures["valid_fraction"] = measured.valid_fraction.into();
        figures["mean_abs_error_px"] = measured.mean_abs_error_px.into();
        figures["measured_bad_pixel_fraction"] = measured.bad_pixel_fraction.into();
        figures["bad_threshold_px"] = measured.bad_threshold_px.into();
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&figures)?);
    } else {
        println!(
            "{}: {}x{}, disparities 0..={}, {:.3} s",
            args.left.display(),
            disp.width,
            disp.height,
            args.max_disparity,
            seconds
        );
        let keys = [
            "known_pixels",
            "bad_pixel_fraction",
            "valid_fraction",
            "mean_abs_error_px",
            "measured_bad_pixel_fraction",
        ];
        for k in keys.into_iter().filter(|k| !figures[*k].is_null()) {
            println!("{k}: {}", figures[k]);
        }
        if let Some(dir) = &args.out {
            println!("outputs in {}", dir.display());
        }
    }
    Ok(())
}

/// Reads an image file as 16-bit grey (8-bit data keeps its full range, x 257).
fn read_grey(path: &Path) -> anyhow::Result<Grey16> {
    Ok(decode(path)?.to_luma16())
}

fn decode(path: &Path) -> anyhow::Result<image::DynamicImage> {
    let reader = image::ImageReader::open(path)
        .with_context(|| format!("{}: cannot open", path.display()))?
        .with_guessed_format()
        .with_context(|| format!("{}: cannot read", path.display()))?;
    reader.decode().with_context(|| format!("{}: cannot decode the image", path.display()))
}

/// Reads a grey ground-truth disparity image: raw pixel value / scale, 0 = unknown.
fn read_truth(path: &Path, scale: f64, size: (u32, u32)) -> anyhow::Result<Vec<f32>> {
    let img = decode(path)?;
    if img.color().has_color() {
        anyhow::bail!("{}: a ground-truth disparity image must be grey", path.display());
    }
    if (img.width(), img.height()) != size {
        anyhow::bail!(
            "{}: the truth is {}x{} but the images are {}x{}",
            path.display(),
            img.width(),
            img.height(),
            size.0,
            size.1
        );
    }
    // 8-bit truth keeps its raw values (to_luma16 would scale them by 257).
    let raw: Vec<u16> = match &img {
        image::DynamicImage::ImageLuma8(_) | image::DynamicImage::ImageLumaA8(_) => {
            img.to_luma8().into_raw().into_iter().map(u16::from).collect()
        }
        _ => img.to_luma16().into_raw(),
    };
    Ok(raw
        .into_iter()
        .map(|v| if v == 0 { INVALID_DISPARITY } else { (f64::from(v) / scale) as f32 })
        .collect())
}

/// Writes the 16-bit disparity (x 16; 0 = invalid, valid disparities below 1/16 px written as
/// 1) and a colour-mapped picture (near = warm, far = cool, invalid = black).
fn write_outputs(dir: &Path, disp: &Disparity, max_disparity: usize) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir)
        .with_context(|| format!("{}: cannot create output folder", dir.display()))?;
    let (w, h) = (disp.width as u32, disp.height as u32);
    let raw: Vec<u16> = disp
        .data
        .iter()
        .map(|&d| if stereo::is_valid(d) { (d * 16.0).round().clamp(1.0, 65535.0) as u16 } else { 0 })
        .collect();
    let grey = Grey16::from_raw(w, h, raw).expect("buffer size");
    let path = dir.join("disparity.png");
    grey.save(&path).with_context(|| format!("{}: cannot write", path.display()))?;
    let mut colour = Rgb8::new(w, h);
    for (p, &d) in colour.pixels_mut().zip(&disp.data) {
        if stereo::is_valid(d) {
            p.0 = colour_map(d / max_disparity.max(1) as f32);
        }
    }
    let path = dir.join("disparity_colour.png");
    colour.save(&path).with_context(|| format!("{}: cannot write", path.display()))?;
    Ok(())
}

/// A blue (0) to red (1) colour ramp through cyan, green and yellow.
fn colour_map(t: f32) -> [u8; 3] {
    const STOPS: [[f32; 3]; 5] = [
        [48.0, 18.0, 160.0],
        [30.0, 160.0, 230.0],
        [60.0, 200.0, 80.0],
        [250.0, 220.0, 40.0],
        [220.0, 40.0, 30.0],
    ];
    let t = t.clamp(0.0, 1.0) * (STOPS.len() - 1) as f32;
    let i = (t.floor() as usize).min(STOPS.len() - 2);
    let f = t - i as f32;
    std::array::from_fn(|k| (STOPS[i][k] * (1.0 - f) + STOPS[i + 1][k] * f).round() as u8)
}
