//! The per-run timeline (`timeline.svg` and `timeline.png`): against simulated time, the true
//! and the estimated distance to the goal, the localisation error (estimate against truth) and
//! the wall-clock compute of every cycle, from the run's trace.

use crate::font;
use plotters::coord::Shift;
use plotters::prelude::*;
use rovernav_core::{Point2, Pose3};
use rovernav_executive::{Report, Trace};

/// Picture size (px).
const SIZE: (u32, u32) = (960, 760);

/// The series a timeline draws, one value per trace sample.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Series {
    /// Simulated time (s), or the cycle number when the trace has no times.
    pub t: Vec<f64>,
    /// Whether `t` is simulated time (else cycles).
    pub timed: bool,
    /// True distance to the goal (m).
    pub true_to_goal: Vec<f64>,
    /// Estimated distance to the goal (m).
    pub estimated_to_goal: Vec<f64>,
    /// |estimate - truth| in the plane (m).
    pub localisation_error: Vec<f64>,
    /// Wall-clock compute per cycle (ms; empty when not recorded).
    pub compute_ms: Vec<f64>,
}

fn planar(p: &Pose3) -> Point2 {
    Point2::new(p.x, p.y)
}

/// The series of a trace for a goal.
pub fn series(trace: &Trace, goal: Point2) -> Series {
    let n = trace.truth.len().min(trace.estimate.len());
    let timed = trace.sim_time_s.len() >= n && n > 0;
    let t = if timed { trace.sim_time_s[..n].to_vec() } else { (0..n).map(|k| k as f64).collect() };
    let truth = &trace.truth[..n];
    let est = &trace.estimate[..n];
    Series {
        t,
        timed,
        true_to_goal: truth.iter().map(|p| planar(p).dist(goal)).collect(),
        estimated_to_goal: est.iter().map(|p| planar(p).dist(goal)).collect(),
        localisation_error: truth.iter().zip(est).map(|(a, b)| planar(a).dist(planar(b))).collect(),
        compute_ms: if trace.compute_s.len() >= n {
            trace.compute_s[..n].iter().map(|s| s * 1e3).collect()
        } else {
            Vec::new()
        },
    }
}

fn style(size: f64, bold: bool) -> TextStyle<'static> {
    FontDesc::new(font::family(), size, if bold { FontStyle::Bold } else { FontStyle::Normal }).color(&BLACK)
}

/// One curve of a panel: values, colour, legend words.
type Curve<'a> = (&'a [f64], RGBColor, &'static str);

/// An axis value with as many decimals as a span of `span` needs.
fn tick(v: f64, span: f64) -> String {
    let digits = if span >= 20.0 {
        0
    } else if span >= 2.0 {
        1
    } else {
        2
    };
    format!("{v:.digits$}")
}

fn upper(values: &[f64], floor: f64) -> f64 {
    let m = values.iter().copied().filter(|v| v.is_finite()).fold(0.0f64, f64::max);
    (m * 1.08).max(floor)
}

/// Draws the timeline of `report`'s run into `root`.
pub fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    report: &Report,
    s: &Series,
    tolerance: f64,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let (head, body) = root.split_vertically(56);
    head.draw(&Text::new(
        format!(
            "{} · navigator {} · localiser {} · seed {}",
            report.mission, report.navigator, report.localizer, report.seed
        ),
        (12, 8),
        style(18.0, true),
    ))?;
    let (words, colour) = crate::traverse::caption::outcome_words(&report.outcome);
    head.draw(&Text::new(
        format!("{words} after {:.0} s, {} cycles", report.sim_time_s, report.cycles),
        (12, 32),
        style(14.0, false).color(&colour),
    ))?;
    let panels = body.split_evenly((3, 1));
    let t_max = s.t.last().copied().unwrap_or(1.0).max(1e-6);
    let x_desc = if s.timed { "simulated time (s)" } else { "cycle" };
    let mut lines: Vec<(&str, Vec<Curve<'_>>, f64)> = vec![
        (
            "distance to the goal (m)",
            vec![
                (s.true_to_goal.as_slice(), RGBColor(0, 90, 200), "truth"),
                (s.estimated_to_goal.as_slice(), RGBColor(230, 150, 0), "estimate"),
            ],
            upper(&s.true_to_goal, 1.0).max(upper(&s.estimated_to_goal, 1.0)),
        ),
        (
            "localisation error (m)",
            vec![(s.localisation_error.as_slice(), RGBColor(200, 30, 30), "|estimate - truth|")],
            upper(&s.localisation_error, 0.1),
        ),
    ];
    let compute_desc = if s.compute_ms.is_empty() {
        "compute per cycle (not recorded)"
    } else {
        "compute per cycle (ms, wall clock)"
    };
    lines.push((
        compute_desc,
        vec![(s.compute_ms.as_slice(), RGBColor(90, 90, 90), "cycle")],
        upper(&s.compute_ms, 1.0),
    ));
    for (i, (area, (desc, curves, y_max))) in panels.iter().zip(lines).enumerate() {
        let mut chart = ChartBuilder::on(area)
            .margin(8)
            .margin_right(24)
            .x_label_area_size(if i == 2 { 40 } else { 22 })
            .y_label_area_size(64)
            .build_cartesian_2d(0.0..t_max, 0.0..y_max)?;
        let x_fmt = |v: &f64| tick(*v, t_max);
        let y_fmt = |v: &f64| tick(*v, y_max);
        let mut mesh = chart.configure_mesh();
        mesh.x_label_formatter(&x_fmt)
            .y_label_formatter(&y_fmt)
            .y_desc(desc)
            .label_style(style(12.0, false))
            .axis_desc_style(style(13.0, false))
            .light_line_style(WHITE);
        if i == 2 {
            mesh.x_desc(x_desc);
        }
        mesh.draw()?;
        if i == 0 && tolerance > 0.0 {
            let dash = DashedLineSeries::new(
                vec![(0.0, tolerance), (t_max, tolerance)],
                6,
                4,
                RGBColor(0, 140, 60).into(),
            );
            chart
                .draw_series(dash)?
                .label(format!("goal tolerance {tolerance:.2} m"))
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], RGBColor(0, 140, 60)));
        }
        for (values, colour, label) in curves {
            let pts: Vec<(f64, f64)> =
                s.t.iter().copied().zip(values.iter().copied()).filter(|(_, v)| v.is_finite()).collect();
            if i == 2 {
                // Compute is per cycle, not a continuous quantity: one thin bar per cycle.
                chart.draw_series(
                    pts.iter()
                        .map(|&(t, v)| PathElement::new(vec![(t, 0.0), (t, v)], colour.stroke_width(1))),
                )?;
            } else {
                chart.draw_series(LineSeries::new(pts, colour.stroke_width(2)))?.label(label).legend(
                    move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], colour.stroke_width(2)),
                );
            }
        }
        if i < 2 {
            chart
                .configure_series_labels()
                .position(
                    // The distance falls and the error grows over a run: each legend where its
                    // curves usually leave room.
                    if i == 0 { SeriesLabelPosition::UpperRight } else { SeriesLabelPosition::UpperLeft },
                )
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK.mix(0.3))
                .label_font(style(12.0, false))
                .draw()?;
        }
    }
    Ok(())
}

/// The timeline as SVG text and PNG bytes.
pub fn timeline(
    report: &Report,
    trace: &Trace,
    goal: Point2,
    tolerance: f64,
) -> std::io::Result<(String, Vec<u8>)> {
    font::ensure();
    let s = series(trace, goal);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
        draw(&root, report, &s, tolerance).map_err(std::io::Error::other)?;
        root.present().map_err(std::io::Error::other)?;
    }
    let mut rgb = vec![255u8; (SIZE.0 * SIZE.1 * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, SIZE).into_drawing_area();
        draw(&root, report, &s, tolerance).map_err(std::io::Error::other)?;
        root.present().map_err(std::io::Error::other)?;
    }
    Ok((svg, crate::traverse::encode_png(SIZE.0, SIZE.1, &rgb)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pose(x: f64, y: f64) -> Pose3 {
        Pose3 { x, y, ..Pose3::default() }
    }

    #[test]
    fn series_measure_distances_to_the_goal_and_between_the_paths() {
        let trace = Trace {
            truth: vec![pose(0.0, 0.0), pose(3.0, 0.0)],
            estimate: vec![pose(0.0, 0.0), pose(3.0, 4.0)],
            sim_time_s: vec![0.0, 2.5],
            compute_s: vec![0.0, 0.004],
            ..Trace::default()
        };
        let s = series(&trace, Point2::new(3.0, 4.0));
        assert!(s.timed);
        assert_eq!(s.t, vec![0.0, 2.5]);
        assert_eq!(s.true_to_goal, vec![5.0, 4.0]);
        assert_eq!(s.estimated_to_goal, vec![5.0, 0.0]);
        assert_eq!(s.localisation_error, vec![0.0, 4.0]);
        assert_eq!(s.compute_ms, vec![0.0, 4.0]);
        let untimed =
            series(&Trace { sim_time_s: vec![], compute_s: vec![], ..trace }, Point2::new(0.0, 0.0));
        assert!(!untimed.timed && untimed.compute_ms.is_empty());
        assert_eq!(untimed.t, vec![0.0, 1.0]);
    }

    #[test]
    fn timeline_svg_names_its_three_panels() {
        let trace = Trace {
            truth: vec![pose(0.0, 0.0), pose(1.0, 0.0), pose(2.0, 0.0)],
            estimate: vec![pose(0.0, 0.0), pose(1.0, 0.1), pose(2.0, 0.3)],
            sim_time_s: vec![0.0, 1.0, 2.0],
            compute_s: vec![0.0, 0.002, 0.003],
            ..Trace::default()
        };
        let report = Report { outcome: "reached".into(), mission: "m".into(), ..Report::default() };
        let (svg, png) = timeline(&report, &trace, Point2::new(2.0, 0.0), 0.5).unwrap();
        for words in [
            "distance to the goal (m)",
            "localisation error (m)",
            "compute per cycle (ms, wall clock)",
            "simulated time (s)",
            "goal tolerance 0.50 m",
        ] {
            assert!(svg.contains(words), "{words}");
        }
        assert!(png.starts_with(b"\x89PNG"));
    }
}
