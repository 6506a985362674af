//! `rovernav eval science --kind clouds|dust-devils [--json]`: the onboard-science detectors
//! (paper 003 section 5) on rendered, labelled sets at least as large as the paper's (210 cloud
//! images; 385 dust-devil frames in 25 sequences of 6 to 20 frames), scored against the
//! renderer's truth, with the downlink a 10 % budget triage sends.

use anyhow::Context;
use rayon::prelude::*;
use rovernav_science::{
    CloudParams, DustDevilParams, Event, EventKind, ImageRecord, SkyParams, detect_clouds,
    detect_dust_devils, segment_sky, triage,
};
use rovernav_sim::scenes::{Site, clouds, dust_devils};
use rovernav_vision::image::GreyF32;
use serde::Serialize;
use std::path::PathBuf;

/// Options of `rovernav eval science`.
#[derive(clap::Args, Debug)]
pub struct EvalScienceArgs {
    /// Which detector: clouds or dust-devils.
    #[arg(long)]
    pub kind: String,
    /// Cloud images (clouds) or sequences (dust devils); default the paper's 210 / 25.
    #[arg(long)]
    pub count: Option<usize>,
    /// Image size (pixels, square).
    #[arg(long, default_value_t = 256)]
    pub size: usize,
    /// Seed of the set.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Block-compress every rendered image at this JPEG-like quality (1..100); the onboard
    /// detectors see raw frames, so the default is none.
    #[arg(long)]
    pub jpeg_quality: Option<u8>,
    /// Budget of the triage as a fraction of the raw volume.
    #[arg(long, default_value_t = 0.1)]
    pub budget: f64,
    /// Folder to write every rendered image into (8-bit PNG), for inspection.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Print the figures as JSON.
    #[arg(long)]
    pub json: bool,
    /// Print one line per image (truth and verdict) to stderr.
    #[arg(long)]
    pub list: bool,
}

/// The figures of `rovernav eval science`.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct ScienceReport {
    /// clouds or dust-devils.
    pub kind: String,
    /// Images (frames) scored.
    pub images: usize,
    /// Sequences (dust devils; 0 for clouds).
    pub sequences: usize,
    /// Fraction of images classified right (event found where it is, or nothing where none is).
    pub accuracy: f64,
    /// Of the images the detector flagged, the fraction with a true event where it said.
    pub precision: f64,
    /// Of the images with a true event, the fraction found where it is.
    pub recall: f64,
    /// Detections (regions or boxes) that cover no true event, per image.
    pub false_positives_per_image: f64,
    /// Bytes the triage sends (summary and products) over the raw volume of the set.
    pub downlink_fraction: f64,
    /// Images with a true event.
    pub positives: usize,
    /// True positives, false positives, false negatives, true negatives (images).
    pub confusion: [usize; 4],
    /// Recall on the faint events alone.
    pub faint_recall: f64,
    /// High-contrast events missed (clouds: peak contrast >= 10 %; dust devils: not faint).
    pub high_contrast_missed: usize,
    /// Detected events the triage could send only as summary.
    pub events_summary_only: usize,
    /// Wall time (s).
    pub seconds: f64,
}

/// One scored image: truth, verdict, faintness and false detections.
struct Scored {
    truth: bool,
    found: bool,
    flagged: bool,
    faint: bool,
    high: bool,
    false_detections: usize,
    events: Vec<Event>,
}

/// Runs `rovernav eval science`.
pub fn run(args: EvalScienceArgs) -> anyhow::Result<()> {
    let report = evaluate(&args)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        println!(
            "{}: {} images ({} sequences), accuracy {:.1} %, precision {:.3}, recall {:.3} (faint {:.3}), {:.3} false \
             positives per image, {} high-contrast missed; downlink {:.2} % of the raw volume; {:.1} s",
            report.kind,
            report.images,
            report.sequences,
            100.0 * report.accuracy,
            report.precision,
            report.recall,
            report.faint_recall,
            report.false_positives_per_image,
            report.high_contrast_missed,
            100.0 * report.downlink_fraction,
            report.seconds
        );
    }
    Ok(())
}

/// Generates the set and scores the detector.
pub fn evaluate(args: &EvalScienceArgs) -> anyhow::Result<ScienceReport> {
    if !(32..=2048).contains(&args.size) {
        anyhow::bail!("--size {}: must be 32 to 2048 pixels", args.size);
    }
    if args.jpeg_quality.is_some_and(|q| !(1..=100).contains(&q)) {
        anyhow::bail!("--jpeg-quality: must be 1 to 100");
    }
    if !(args.budget.is_finite() && args.budget > 0.0 && args.budget <= 1.0) {
        anyhow::bail!("--budget {}: must be a fraction in (0, 1]", args.budget);
    }
    if let Some(dir) = &args.out {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("--out {}: cannot create the folder", dir.display()))?;
    }
    let start = std::time::Instant::now();
    let sites: Vec<Site> = (0..4).map(|k| Site::new(args.seed.wrapping_mul(31).wrapping_add(k))).collect();
    let (scored, sequences) = match args.kind.as_str() {
        "clouds" => (score_clouds(args, &sites)?, 0),
        "dust-devils" => {
            let n = args.count.unwrap_or(25);
            (score_dust_devils(args, &sites, n)?, n)
        }
        other => anyhow::bail!("--kind `{other}`: expected clouds or dust-devils"),
    };
    let n = scored.len();
    let tp = scored.iter().filter(|s| s.truth && s.found).count();
    let flagged = scored.iter().filter(|s| s.flagged).count();
    let positives = scored.iter().filter(|s| s.truth).count();
    let correct = scored.iter().filter(|s| if s.truth { s.found } else { !s.flagged }).count();
    let fp = scored.iter().filter(|s| s.flagged && !(s.truth && s.found)).count();
    let fneg = positives - tp;
    let faint: Vec<&Scored> = scored.iter().filter(|s| s.truth && s.faint).collect();
    let ratio = |a: usize, b: usize| if b == 0 { 1.0 } else { a as f64 / b as f64 };
    let records: Vec<ImageRecord> = scored
        .iter()
        .enumerate()
        .map(|(i, s)| ImageRecord {
            id: format!("{i:04}"),
            time_s: i as f64,
            width: args.size as u32,
            height: args.size as u32,
            bytes_per_pixel: 1.5,
            events: s.events.clone(),
        })
        .collect();
    let raw: u64 = records.iter().map(ImageRecord::full_bytes).sum();
    let plan = triage(&records, (args.budget * raw as f64) as u64);
    Ok(ScienceReport {
        kind: args.kind.clone(),
        images: n,
        sequences,
        accuracy: ratio(correct, n),
        precision: ratio(tp, flagged),
        recall: ratio(tp, positives),
        false_positives_per_image: scored.iter().map(|s| s.false_detections).sum::<usize>() as f64
            / n.max(1) as f64,
        downlink_fraction: plan.bytes_used as f64 / raw.max(1) as f64,
        positives,
        confusion: [tp, fp, fneg, n - tp - fp - fneg],
        faint_recall: ratio(faint.iter().filter(|s| s.found).count(), faint.len()),
        high_contrast_missed: scored.iter().filter(|s| s.truth && s.high && !s.found).count(),
        events_summary_only: plan.events_summary_only,
        seconds: start.elapsed().as_secs_f64(),
    })
}

fn grey(image: &rovernav_vision::image::Grey16) -> GreyF32 {
    GreyF32::from_fn(image.width(), image.height(), |x, y| image::Luma([image.get_pixel(x, y)[0] as f32]))
}

/// Whether boxes `[x, y, w, h]` intersect.
fn overlaps(a: [u32; 4], b: [u32; 4]) -> bool {
    a[0] < b[0] + b[2] && b[0] < a[0] + a[2] && a[1] < b[1] + b[3] && b[1] < a[1] + a[3]
}

fn score_clouds(args: &EvalScienceArgs, sites: &[Site]) -> anyhow::Result<Vec<Scored>> {
    let n = args.count.unwrap_or(210);
    let (sky_params, cloud_params) = (SkyParams::default(), CloudParams::default());
    (0..n)
        .into_par_iter()
        .map(|i| {
            let case =
                clouds::cloud_image(&sites[i % sites.len()], i, args.size, args.seed, args.jpeg_quality);
            if let Some(dir) = &args.out {
                let path = dir
                    .join(format!("cloud_{i:03}_{}.png", if case.truth.cloud { "cloud" } else { "clear" }));
                case.rendered
                    .to_8bit()
                    .save(&path)
                    .with_context(|| format!("{}: cannot write", path.display()))?;
            }
            let img = grey(&case.rendered.image);
            let sky = segment_sky(&img, &sky_params);
            let d = detect_clouds(&img, &sky, &cloud_params);
            let boxes: Vec<[u32; 4]> = d.regions.iter().map(|r| [r.x, r.y, r.width, r.height]).collect();
            let hit = case.truth.bbox.is_some_and(|t| boxes.iter().any(|b| overlaps(*b, t)));
            let false_detections = if d.cloud {
                boxes.iter().filter(|b| !case.truth.bbox.is_some_and(|t| overlaps(**b, t))).count()
            } else {
                0
            };
            if args.list {
                eprintln!(
                    "cloud {i:03}: truth {} peak {:.3} px {} sky {:.2} | found {} conf {:.2} best {:?}",
                    case.truth.cloud,
                    case.truth.peak_contrast,
                    case.truth.pixels,
                    case.truth.sky_fraction,
                    d.cloud,
                    d.confidence,
                    d.regions.first().map(|r| (r.strength, r.contrast, r.x, r.y))
                );
            }
            let events = d.events();
            Ok(Scored {
                truth: case.truth.cloud,
                found: d.cloud && hit,
                flagged: d.cloud,
                faint: case.truth.peak_contrast < clouds::HIGH_CONTRAST,
                high: case.truth.high_contrast,
                false_detections,
                events,
            })
        })
        .collect()
}

/// Sequence lengths: 6 to 20 frames, summing to 385 for the paper's 25 sequences.
pub fn sequence_lengths(n: usize) -> Vec<usize> {
    let mut lengths: Vec<usize> = (0..n).map(|i| 6 + (i * 7) % 15).collect();
    if n == 25 {
        let mut total: usize = lengths.iter().sum();
        let mut i = 0;
        while total != 385 {
            if total < 385 && lengths[i % n] < 20 {
                lengths[i % n] += 1;
                total += 1;
            } else if total > 385 && lengths[i % n] > 6 {
                lengths[i % n] -= 1;
                total -= 1;
            }
            i += 1;
        }
    }
    lengths
}

fn score_dust_devils(args: &EvalScienceArgs, sites: &[Site], n: usize) -> anyhow::Result<Vec<Scored>> {
    let lengths = sequence_lengths(n);
    let params = DustDevilParams::default();
    let per_sequence: Vec<anyhow::Result<Vec<Scored>>> = (0..n)
        .into_par_iter()
        .map(|s| {
            let seq = dust_devils::dust_devil_sequence(
                &sites[s % sites.len()],
                s,
                lengths[s],
                args.size,
                args.seed,
                args.jpeg_quality,
            );
            if let Some(dir) = &args.out {
                for (k, f) in seq.frames.iter().enumerate() {
                    let tag = if seq.truth[k].present { "devil" } else { "none" };
                    let path = dir.join(format!("devil_{s:02}_{k:02}_{tag}.png"));
                    f.to_8bit().save(&path).with_context(|| format!("{}: cannot write", path.display()))?;
                }
            }
            let frames: Vec<GreyF32> = seq.frames.iter().map(|f| grey(&f.image)).collect();
            let det = detect_dust_devils(&frames, &params)?;
            if args.list {
                for (d, t) in det.iter().zip(&seq.truth) {
                    eprintln!(
                        "devil {s:02}/{:02}: truth {} faint {} peak {:.3} px {} bbox {:?} | boxes {:?}",
                        d.frame,
                        t.present,
                        t.faint,
                        t.peak_contrast,
                        t.pixels,
                        t.bbox,
                        d.boxes
                            .iter()
                            .map(|b| (b.x, b.y, b.width, b.height, b.score as u32))
                            .collect::<Vec<_>>()
                    );
                }
            }
            Ok(det
                .iter()
                .zip(&seq.truth)
                .map(|(d, t)| {
                    let boxes: Vec<[u32; 4]> =
                        d.boxes.iter().map(|b| [b.x, b.y, b.width, b.height]).collect();
                    let hit = t.bbox.is_some_and(|tb| boxes.iter().any(|b| overlaps(*b, tb)));
                    Scored {
                        truth: t.present,
                        found: hit,
                        flagged: !boxes.is_empty(),
                        faint: t.faint,
                        high: !t.faint,
                        false_detections: boxes
                            .iter()
                            .filter(|b| !t.bbox.is_some_and(|tb| overlaps(**b, tb)))
                            .count(),
                        events: d
                            .boxes
                            .iter()
                            .map(|b| Event {
                                kind: EventKind::DustDevil,
                                bbox: [b.x, b.y, b.width, b.height],
                                score: b.score,
                            })
                            .collect(),
                    }
                })
                .collect())
        })
        .collect();
    let mut out = Vec::new();
    for s in per_sequence {
        out.extend(s?);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(kind: &str, count: usize, size: usize) -> EvalScienceArgs {
        EvalScienceArgs {
            kind: kind.into(),
            count: Some(count),
            size,
            seed: 1,
            jpeg_quality: None,
            budget: 0.1,
            out: None,
            json: false,
            list: false,
        }
    }

    #[test]
    fn sky_mask_agrees_with_the_renderer_labels() {
        let site = Site::new(5);
        for index in [0, 1, 2, 3, 20, 21] {
            let case = clouds::cloud_image(&site, index, 128, 3, None);
            let mask = segment_sky(&grey(&case.rendered.image), &SkyParams::default());
            let agree = (0..128 * 128)
                .filter(|&i| {
                    let truth = case.rendered.labels[i] == rovernav_sim::render::Label::Sky;
                    truth == mask.is_sky((i % 128) as u32, (i / 128) as u32)
                })
                .count();
            assert!(
                agree as f64 > 0.95 * 128.0 * 128.0,
                "case {index}: {agree} of {} pixels agree",
                128 * 128
            );
        }
    }

    #[test]
    fn small_rendered_sets_are_mostly_right() {
        let clouds = evaluate(&args("clouds", 20, 128)).unwrap();
        assert_eq!(clouds.images, 20);
        assert!(clouds.accuracy >= 0.85, "{clouds:?}");
        let devils = evaluate(&args("dust-devils", 3, 128)).unwrap();
        assert!(devils.accuracy >= 0.8, "{devils:?}");
        assert!(devils.downlink_fraction <= 0.1 + 1e-9);
        assert!(evaluate(&args("rainbows", 1, 128)).unwrap_err().to_string().contains("--kind"));
    }

    /// The paper-size sets (`cargo test --release -p rovernav -- --ignored science_targets`).
    #[test]
    #[ignore]
    fn science_targets_on_paper_size_sets() {
        let clouds = evaluate(&args("clouds", 210, 256)).unwrap();
        assert!(clouds.accuracy >= 0.93 && clouds.high_contrast_missed == 0, "{clouds:?}");
        let devils = evaluate(&args("dust-devils", 25, 256)).unwrap();
        assert_eq!(devils.images, 385);
        assert!(devils.accuracy >= 0.85, "{devils:?}");
        // Block-compressed at quality 75 (the detectors deblock first): 95.2 % and 96.9 % at
        // seed 1, 48.6 % and 35.8 % before they did.
        let compressed = |kind: &str, count: usize| {
            evaluate(&EvalScienceArgs { jpeg_quality: Some(75), ..args(kind, count, 256) }).unwrap()
        };
        let clouds = compressed("clouds", 210);
        assert!(clouds.accuracy >= 0.93 && clouds.high_contrast_missed == 0, "{clouds:?}");
        let devils = compressed("dust-devils", 25);
        assert!(devils.accuracy >= 0.85, "{devils:?}");
    }

    #[test]
    fn sequence_lengths_match_the_paper() {
        let l = sequence_lengths(25);
        assert_eq!(l.iter().sum::<usize>(), 385);
        assert!(l.iter().all(|&n| (6..=20).contains(&n)));
    }
}
