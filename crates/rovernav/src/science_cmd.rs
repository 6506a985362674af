//! `rovernav science sky IMAGE --out MASK.png [--json]` and `rovernav science detect --kind
//! clouds|dust-devils FILES... [--json]`: the onboard-science detectors (paper 003 section 5)
//! on image files (PNG, JPEG, PGM/PPM, PDS3 IMG, animated GIF frames).

use anyhow::Context;
use image::AnimationDecoder;
use rovernav_science::{
    CloudParams, DustDevilParams, SkyParams, detect_clouds, detect_dust_devils, segment_sky,
};
use rovernav_vision::codec::{read_image, write_png_grey8, write_png_rgb8};
use rovernav_vision::image::{GreyF32, Rgb8};
use serde_json::json;
use std::path::{Path, PathBuf};

/// `rovernav science` subcommands.
#[derive(clap::Subcommand, Debug)]
pub enum ScienceCommand {
    /// The sky mask (white = sky) of one image.
    Sky(SkyArgs),
    /// Run a detector on image files and print the detections.
    Detect(DetectArgs),
}

/// Options of `rovernav science sky`.
#[derive(clap::Args, Debug)]
pub struct SkyArgs {
    /// Image file.
    pub image: PathBuf,
    /// Where to write the mask (PNG, 255 = sky).
    #[arg(long)]
    pub out: PathBuf,
    /// Also write a picture of the image (reduced to `--overlay-width`) with the sky tinted
    /// blue and the horizon in red.
    #[arg(long)]
    pub overlay: Option<PathBuf>,
    /// Width of the overlay picture (pixels).
    #[arg(long, default_value_t = 1200)]
    pub overlay_width: u32,
    /// Print the result as JSON.
    #[arg(long)]
    pub json: bool,
}

/// Options of `rovernav science detect`.
#[derive(clap::Args, Debug)]
pub struct DetectArgs {
    /// clouds (one record per image) or dust-devils (the files, or the frames of one animated
    /// GIF, are one sequence: one record per frame).
    #[arg(long)]
    pub kind: String,
    /// Image files.
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
    /// Print the detections as JSON.
    #[arg(long)]
    pub json: bool,
}

/// Writes the science watches' summaries (`/science/summary`) to `science.json` in `out_dir`,
/// one JSON array; nothing when the run had no watch. `rovernav run` writes it from the report's
/// task messages, `rovernav replay` from the telemetry log: the two files are the same.
pub fn write_watch_summaries(
    out_dir: &Path,
    summaries: &[rovernav_executive::deliberative::WatchSummary],
) -> anyhow::Result<()> {
    if summaries.is_empty() {
        return Ok(());
    }
    let path = out_dir.join("science.json");
    crate::output::write_atomic(&path, |bytes| {
        serde_json::to_writer_pretty(&mut *bytes, summaries)?;
        bytes.push(b'\n');
        Ok(())
    })
}

/// Runs `rovernav science`.
pub fn run(command: ScienceCommand) -> anyhow::Result<()> {
    match command {
        ScienceCommand::Sky(args) => sky(args),
        ScienceCommand::Detect(args) => detect(args),
    }
}

fn sky(args: SkyArgs) -> anyhow::Result<()> {
    let image = read_grey(&args.image)?;
    let mask = segment_sky(&image, &SkyParams::default());
    write_png_grey8(&args.out, &mask.to_image())
        .with_context(|| format!("{}: cannot write", args.out.display()))?;
    if let Some(path) = &args.overlay {
        let picture = overlay(&image, &mask, args.overlay_width.clamp(16, 8192));
        write_png_rgb8(path, &picture).with_context(|| format!("{}: cannot write", path.display()))?;
    }
    let mut rows: Vec<u32> = mask.horizon.clone();
    rows.sort_unstable();
    let pick = |q: f64| rows.get(((rows.len().max(1) - 1) as f64 * q) as usize).copied().unwrap_or(0);
    let record = json!({
        "file": args.image.display().to_string(),
        "width": mask.width,
        "height": mask.height,
        "sky_fraction": mask.fraction(),
        "horizon_row_min": pick(0.0),
        "horizon_row_median": pick(0.5),
        "horizon_row_max": pick(1.0),
        "texture_threshold": mask.threshold,
        "mask": args.out.display().to_string(),
    });
    if args.json {
        println!("{}", serde_json::to_string_pretty(&record)?);
    } else {
        println!(
            "{}: {}x{}, sky {:.1} %, horizon rows {}..{} (median {}) -> {}",
            args.image.display(),
            mask.width,
            mask.height,
            100.0 * mask.fraction(),
            pick(0.0),
            pick(1.0),
            pick(0.5),
            args.out.display()
        );
    }
    Ok(())
}

fn detect(args: DetectArgs) -> anyhow::Result<()> {
    let records: Vec<serde_json::Value> = match args.kind.as_str() {
        "clouds" => {
            let mut out = Vec::new();
            for file in &args.files {
                let image = read_grey(file)?;
                let sky = segment_sky(&image, &SkyParams::default());
                let d = detect_clouds(&image, &sky, &CloudParams::default());
                out.push(json!({
                    "file": file.display().to_string(),
                    "cloud": d.cloud,
                    "confidence": d.confidence,
                    "regions": d.regions,
                    "sky_fraction": sky.fraction(),
                }));
            }
            out
        }
        "dust-devils" => {
            let (frames, names) = read_sequence(&args.files)?;
            let detections = detect_dust_devils(&frames, &DustDevilParams::default())
                .map_err(|e| anyhow::anyhow!("{}: {e}", args.files[0].display()))?;
            detections
                .iter()
                .zip(&names)
                .map(|(d, name)| {
                    let boxes: Vec<[f64; 5]> = d
                        .boxes
                        .iter()
                        .map(|b| [b.x as f64, b.y as f64, b.width as f64, b.height as f64, b.score as f64])
                        .collect();
                    json!({ "frame": d.frame, "file": name, "boxes": boxes })
                })
                .collect()
        }
        other => anyhow::bail!("--kind `{other}`: expected clouds or dust-devils"),
    };
    if args.json {
        println!("{}", serde_json::to_string_pretty(&records)?);
    } else {
        for r in &records {
            println!("{r}");
        }
    }
    Ok(())
}

/// The image reduced to `width` (block means, stretched between its 1st and 99th percentiles)
/// with the sky tinted blue and the horizon drawn in red.
fn overlay(image: &GreyF32, mask: &rovernav_science::SkyMask, width: u32) -> Rgb8 {
    let (w, h) = image.dimensions();
    let f = (w.div_ceil(width.max(1))).max(1);
    let (ow, oh) = (w.div_ceil(f), h.div_ceil(f));
    let mut values: Vec<f32> = image.pixels().step_by(7).map(|p| p[0]).collect();
    values.sort_by(f32::total_cmp);
    let at = |q: f64| values.get(((values.len().max(1) - 1) as f64 * q) as usize).copied().unwrap_or(0.0);
    let (lo, hi) = (at(0.01), at(0.99).max(at(0.01) + 1e-6));
    Rgb8::from_fn(ow, oh, |x, y| {
        let (mut sum, mut n, mut sky) = (0f32, 0f32, 0u32);
        for yy in y * f..((y + 1) * f).min(h) {
            for xx in x * f..((x + 1) * f).min(w) {
                sum += image.get_pixel(xx, yy)[0];
                n += 1.0;
                sky += mask.is_sky(xx, yy) as u32;
            }
        }
        let g = ((sum / n.max(1.0) - lo) / (hi - lo) * 255.0).clamp(0.0, 255.0);
        let col = (x * f + f / 2).min(w - 1) as usize;
        let line = mask.horizon[col] / f;
        if mask.horizon[col] > mask.top[col] && mask.horizon[col] < h && (line == y || line + 1 == y) {
            return image::Rgb([255, 0, 0]);
        }
        if 2 * sky >= n as u32 {
            image::Rgb([(0.6 * g) as u8, (0.7 * g) as u8, (0.5 * g + 120.0).min(255.0) as u8])
        } else {
            let v = g as u8;
            image::Rgb([v, v, v])
        }
    })
}

/// An image file as grey floats; a GIF's first frame.
fn read_grey(path: &Path) -> anyhow::Result<GreyF32> {
    if is_gif(path) {
        let frames = gif_frames(path)?;
        return frames.into_iter().next().with_context(|| format!("{}: GIF without frames", path.display()));
    }
    Ok(read_image(path).map_err(|e| anyhow::anyhow!("{e}"))?.to_grey_f32())
}

/// The sequence of `files`: the frames of one animated GIF, or one frame per file.
fn read_sequence(files: &[PathBuf]) -> anyhow::Result<(Vec<GreyF32>, Vec<String>)> {
    if let [one] = files
        && is_gif(one)
    {
        let frames = gif_frames(one)?;
        let names = (0..frames.len()).map(|k| format!("{}#{k}", one.display())).collect();
        return Ok((frames, names));
    }
    let frames = files.iter().map(|f| read_grey(f)).collect::<anyhow::Result<Vec<_>>>()?;
    Ok((frames, files.iter().map(|f| f.display().to_string()).collect()))
}

fn is_gif(path: &Path) -> bool {
    path.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case("gif"))
}

/// Every frame of an animated GIF as grey floats (Rec. 601 luma).
fn gif_frames(path: &Path) -> anyhow::Result<Vec<GreyF32>> {
    let file = std::fs::File::open(path).with_context(|| format!("{}: cannot open", path.display()))?;
    let decoder = image::codecs::gif::GifDecoder::new(std::io::BufReader::new(file))
        .with_context(|| format!("{}: not a readable GIF", path.display()))?;
    let frames = decoder
        .into_frames()
        .collect_frames()
        .with_context(|| format!("{}: bad GIF frame", path.display()))?;
    Ok(frames
        .into_iter()
        .map(|f| {
            let buf = f.into_buffer();
            GreyF32::from_fn(buf.width(), buf.height(), |x, y| {
                let [r, g, b, _] = buf.get_pixel(x, y).0;
                image::Luma([0.299 * r as f32 + 0.587 * g as f32 + 0.114 * b as f32])
            })
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn animated_gif_frames_are_one_sequence() {
        use image::codecs::gif::GifEncoder;
        use image::{Delay, Frame, RgbaImage};
        let dir = std::env::temp_dir().join(format!("rovernav-science-gif-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("seq.gif");
        {
            let mut enc = GifEncoder::new(std::fs::File::create(&path).unwrap());
            for k in 0..4u8 {
                let img = RgbaImage::from_fn(16, 12, |x, _| image::Rgba([x as u8 * 10 + k, 50, 50, 255]));
                enc.encode_frame(Frame::from_parts(img, 0, 0, Delay::from_numer_denom_ms(100, 1))).unwrap();
            }
        }
        let (frames, names) = read_sequence(std::slice::from_ref(&path)).unwrap();
        assert_eq!(frames.len(), 4);
        assert_eq!((frames[0].width(), frames[0].height()), (16, 12));
        assert!(names[3].ends_with("#3"));
        let missing = read_grey(&dir.join("nope.png")).unwrap_err().to_string();
        assert!(missing.contains("nope.png"), "{missing}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
