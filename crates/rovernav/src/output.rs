//! Writing a run's output folder: `report.json`, `traverse.png` and the timeline
//! (`timeline.svg`, `timeline.png`), each written to a temporary file and renamed, so a reader
//! never sees a half-written output.

use anyhow::Context;
use rovernav_executive::{Report, RunOutput, Trace, World};
use rovernav_telemetry::TelemetryRecorder;
use std::path::{Path, PathBuf};

/// Writes `path` atomically from a closure that produces the bytes.
pub fn write_atomic(
    path: &Path,
    write: impl FnOnce(&mut Vec<u8>) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let mut bytes = Vec::new();
    write(&mut bytes)?;
    let tmp = path.with_extension("tmp");
    std::fs::write(&tmp, &bytes).with_context(|| format!("{}: cannot write", tmp.display()))?;
    std::fs::rename(&tmp, path).with_context(|| format!("{}: cannot write", path.display()))?;
    Ok(())
}

/// Writes report.json, traverse.png and the timeline into `dir` (created if needed).
pub fn write_run_outputs(dir: &Path, output: &RunOutput) -> anyhow::Result<()> {
    write_outputs(dir, &output.report, &output.world, &output.trace)
}

/// Writes report.json, traverse.png and the timeline from a run's pieces (a replay rebuilds them
/// from a log).
pub fn write_outputs(dir: &Path, report: &Report, world: &World, trace: &Trace) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir)
        .with_context(|| format!("{}: cannot create output folder", dir.display()))?;
    write_atomic(&dir.join("report.json"), |b| {
        serde_json::to_writer_pretty(&mut *b, report)?;
        b.push(b'\n');
        Ok(())
    })?;
    let picture = rovernav_viz::run_traverse_png(report, world, trace)?;
    write_atomic(&dir.join("traverse.png"), |b| {
        b.extend_from_slice(&picture);
        Ok(())
    })?;
    let (svg, png) = rovernav_viz::run_timeline(report, world, trace)?;
    write_atomic(&dir.join("timeline.svg"), |b| {
        b.extend_from_slice(svg.as_bytes());
        Ok(())
    })?;
    write_atomic(&dir.join("timeline.png"), |b| {
        b.extend_from_slice(&png);
        Ok(())
    })
}

/// Writes `placement-<task>.png` into `dir` for every instrument placement (AutoPlace) of a run,
/// read back from its telemetry log (`rovernav run` and `rovernav replay` draw the same).
pub fn write_placement_pictures(
    dir: &Path,
    placements: &[rovernav_executive::arm_server::PlacementMsg],
    rover: &rovernav_core::RoverConfig,
) -> anyhow::Result<()> {
    let arm = rovernav_manipulation::Arm::new(rover);
    for p in placements {
        let png = rovernav_viz::placement::placement_png(p, &arm)?;
        write_atomic(&dir.join(format!("placement-{}.png", p.task)), |b| {
            b.extend_from_slice(&png);
            Ok(())
        })?;
    }
    Ok(())
}

/// A run's `telemetry.mcap`, opened before the run so every cycle is logged as it happens.
///
/// A run that fails before logging anything (an unknown navigator, a missing DEM) leaves no
/// output behind: the log and any folders opening it created are removed again.
pub struct RunLog {
    path: PathBuf,
    created: Vec<PathBuf>,
    /// The observer to hand to the run.
    pub recorder: TelemetryRecorder,
}

impl RunLog {
    /// Opens `<dir>/telemetry.mcap`, creating `dir` if needed.
    pub fn open(dir: &Path) -> anyhow::Result<Self> {
        let created: Vec<PathBuf> = dir
            .ancestors()
            .filter(|a| !a.as_os_str().is_empty() && !a.exists())
            .map(Path::to_path_buf)
            .collect();
        let path = dir.join("telemetry.mcap");
        let recorder = TelemetryRecorder::create(&path)?;
        Ok(Self { path, created, recorder })
    }

    /// Finishes the log; when the run failed without logging a message, removes it again.
    pub fn close(self, run_succeeded: bool) -> anyhow::Result<()> {
        let stats = self.recorder.finish();
        if !run_succeeded && stats.as_ref().is_ok_and(|s| s.messages == 0) {
            let _ = std::fs::remove_file(&self.path);
            // Innermost first; `remove_dir` leaves any folder that is not empty.
            for dir in &self.created {
                let _ = std::fs::remove_dir(dir);
            }
        }
        stats.with_context(|| format!("{}: telemetry log", self.path.display()))?;
        Ok(())
    }
}

/// Prints an evaluation's figures: pretty JSON with `--json`, else the evaluation's table.
pub fn print_evaluation<T: serde::Serialize>(
    json: bool,
    evaluation: &T,
    table: fn(&T),
) -> anyhow::Result<()> {
    if json {
        println!("{}", serde_json::to_string_pretty(evaluation)?);
    } else {
        table(evaluation);
    }
    Ok(())
}

/// Median of `values` (the mean of the two middle values for an even count; NaN when empty):
/// the campaign summary's definition, so every figure uses one.
pub fn median(values: &[f64]) -> f64 {
    rovernav_campaign::summary::median(values).unwrap_or(f64::NAN)
}

#[cfg(test)]
mod median_tests {
    use super::median;

    #[test]
    fn median_of_odd_and_even() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), 2.5);
        assert!(median(&[]).is_nan());
    }
}
