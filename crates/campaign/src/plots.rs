//! SVG charts of a campaign, written by hand (a few lines and circles do not need a plotting
//! crate): success against rock abundance, and the path-ratio distribution per navigator.

use crate::row::Row;
use crate::summary::{Summary, percentile};
use std::fmt::Write;

/// Chart size (px).
const WIDTH: f64 = 760.0;
const HEIGHT: f64 = 440.0;
/// Plot area (px).
const LEFT: f64 = 70.0;
const RIGHT: f64 = 560.0;
const TOP: f64 = 50.0;
const BOTTOM: f64 = 370.0;

/// Distinguishable colours (Okabe-Ito, then greys) for up to ten navigators.
const PALETTE: [&str; 10] = [
    "#0072B2", "#E69F00", "#009E73", "#CC79A7", "#D55E00", "#56B4E9", "#000000", "#F0E442", "#999999",
    "#7F3C8D",
];

fn colour(i: usize) -> &'static str {
    PALETTE[i % PALETTE.len()]
}

/// Escapes text for SVG.
fn esc(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

fn open(title: &str) -> String {
    format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{WIDTH}\" height=\"{HEIGHT}\" viewBox=\"0 0 {WIDTH} {HEIGHT}\" \
         font-family=\"sans-serif\" font-size=\"12\">\n\
         <rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n\
         <text x=\"{}\" y=\"24\" text-anchor=\"middle\" font-size=\"15\">{}</text>\n",
        (LEFT + RIGHT) / 2.0,
        esc(title)
    )
}

/// Horizontal grid lines and labels for `ticks` (value, label) on a y scale.
fn y_axis(s: &mut String, ticks: &[(f64, String)], y: impl Fn(f64) -> f64, label: &str) {
    for (v, text) in ticks {
        let py = y(*v);
        let _ = writeln!(
            s,
            "<line x1=\"{LEFT}\" y1=\"{py:.1}\" x2=\"{RIGHT}\" y2=\"{py:.1}\" stroke=\"#ddd\"/>\
             <text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">{}</text>",
            LEFT - 6.0,
            py + 4.0,
            esc(text)
        );
    }
    let _ = writeln!(
        s,
        "<rect x=\"{LEFT}\" y=\"{TOP}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"#333\"/>\n\
         <text transform=\"translate(18 {:.1}) rotate(-90)\" text-anchor=\"middle\">{}</text>",
        RIGHT - LEFT,
        BOTTOM - TOP,
        (TOP + BOTTOM) / 2.0,
        esc(label)
    );
}

fn legend(s: &mut String, names: &[&str]) {
    for (i, name) in names.iter().enumerate() {
        let y = TOP + 10.0 + 20.0 * i as f64;
        let _ = writeln!(
            s,
            "<rect x=\"{:.1}\" y=\"{:.1}\" width=\"14\" height=\"14\" fill=\"{}\"/>\
             <text x=\"{:.1}\" y=\"{:.1}\">{}</text>",
            RIGHT + 20.0,
            y - 11.0,
            colour(i),
            RIGHT + 40.0,
            y,
            esc(name)
        );
    }
}

/// Success rate of each navigator against rock abundance, with each bin's run count.
pub fn success_vs_rock_abundance(summary: &Summary) -> String {
    let mut s = open(&format!("Success against rock abundance — campaign {}", summary.campaign));
    let bins = &summary.by_rock_abundance;
    let centres: Vec<f64> = bins.iter().map(|b| (b.lo + b.hi) / 2.0).collect();
    let (mut x0, mut x1) = (
        centres.iter().copied().fold(f64::INFINITY, f64::min),
        centres.iter().copied().fold(f64::NEG_INFINITY, f64::max),
    );
    if !x0.is_finite() {
        (x0, x1) = (0.0, 0.2);
    }
    let pad = if x1 > x0 { 0.08 * (x1 - x0) } else { 0.02 };
    let (x0, x1) = ((x0 - pad).max(0.0), x1 + pad);
    let x = |v: f64| LEFT + (v - x0) / (x1 - x0) * (RIGHT - LEFT);
    let y = |v: f64| BOTTOM - v * (BOTTOM - TOP);
    let ticks: Vec<(f64, String)> = (0..=4).map(|i| (i as f64 / 4.0, format!("{} %", 25 * i))).collect();
    y_axis(&mut s, &ticks, y, "success (reached, no hazard contact)");
    for (b, c) in bins.iter().zip(&centres) {
        let px = x(*c);
        let _ = writeln!(
            s,
            "<line x1=\"{px:.1}\" y1=\"{BOTTOM}\" x2=\"{px:.1}\" y2=\"{:.1}\" stroke=\"#333\"/>\
             <text x=\"{px:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{c:.3}</text>\
             <text x=\"{px:.1}\" y=\"{:.1}\" text-anchor=\"middle\" fill=\"#777\" font-size=\"10\">n={}</text>",
            BOTTOM + 5.0,
            BOTTOM + 18.0,
            BOTTOM + 31.0,
            b.terrains
        );
    }
    let _ = writeln!(
        s,
        "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\">rock abundance k (bin centre; n = terrains)</text>",
        (LEFT + RIGHT) / 2.0,
        BOTTOM + 52.0
    );
    let count = summary.navigators.len() as f64;
    for (i, nav) in summary.navigators.iter().enumerate() {
        // Navigators with equal rates would hide each other: shift each a few pixels sideways.
        let dodge = (i as f64 - (count - 1.0) / 2.0) * 3.0;
        let pts: Vec<(f64, f64)> = bins
            .iter()
            .zip(&centres)
            .filter(|(b, _)| b.per_navigator[i][0] > 0)
            .map(|(b, c)| (x(*c) + dodge, y(b.per_navigator[i][1] as f64 / b.per_navigator[i][0] as f64)))
            .collect();
        let path: Vec<String> = pts.iter().map(|(a, b)| format!("{a:.1},{b:.1}")).collect();
        let _ = writeln!(
            s,
            "<polyline points=\"{}\" fill=\"none\" stroke=\"{}\" stroke-width=\"2\"><title>{}</title></polyline>",
            path.join(" "),
            colour(i),
            esc(&nav.navigator)
        );
        for (a, b) in pts {
            let _ = writeln!(s, "<circle cx=\"{a:.1}\" cy=\"{b:.1}\" r=\"3.5\" fill=\"{}\"/>", colour(i));
        }
    }
    let names: Vec<&str> = summary.navigators.iter().map(|n| n.navigator.as_str()).collect();
    legend(&mut s, &names);
    s.push_str("</svg>\n");
    s
}

/// Path ratio (distance driven / optimal) of every reached run, one column per navigator, with
/// the median (bar) and the 95th percentile (tick).
pub fn path_ratio(summary: &Summary, rows: &[Row]) -> String {
    let mut s = open(&format!("Path ratio of reached runs — campaign {}", summary.campaign));
    let per_nav: Vec<Vec<f64>> = summary
        .navigators
        .iter()
        .map(|n| rows.iter().filter(|r| r.navigator == n.navigator).filter_map(|r| r.path_ratio).collect())
        .collect();
    let all = per_nav.iter().flatten().copied();
    let lo = all.clone().fold(1.0f64, f64::min);
    let hi = all.fold(1.2f64, f64::max);
    let (y0, y1) = ((lo - 0.05).max(0.0), hi + 0.05 * (hi - lo).max(0.2));
    let y = |v: f64| BOTTOM - (v - y0) / (y1 - y0) * (BOTTOM - TOP);
    let step = nice_step((y1 - y0) / 6.0);
    let ticks: Vec<(f64, String)> = (0..)
        .map(|k| (y0 / step).ceil() * step + k as f64 * step)
        .take_while(|v| *v <= y1)
        .map(|v| (v, format!("{v:.2}")))
        .collect();
    y_axis(&mut s, &ticks, y, "distance driven / optimal length");
    let _ = writeln!(
        s,
        "<line x1=\"{LEFT}\" y1=\"{0:.1}\" x2=\"{RIGHT}\" y2=\"{0:.1}\" stroke=\"#333\" stroke-dasharray=\"5 4\"/>\
         <text x=\"{1:.1}\" y=\"{2:.1}\" text-anchor=\"end\" fill=\"#333\" font-size=\"10\">optimal</text>",
        y(1.0),
        RIGHT - 4.0,
        y(1.0) - 4.0
    );
    let n = per_nav.len().max(1) as f64;
    let band = (RIGHT - LEFT) / n;
    for (i, (nav, ratios)) in summary.navigators.iter().zip(&per_nav).enumerate() {
        let cx = LEFT + band * (i as f64 + 0.5);
        // Alternate label rows so that long names in narrow columns do not run together.
        let row = 14.0 * (i % 2) as f64;
        let _ = writeln!(
            s,
            "<text x=\"{cx:.1}\" y=\"{:.1}\" text-anchor=\"middle\" font-size=\"11\">{} <tspan fill=\"#777\" font-size=\"10\">n={}</tspan></text>",
            BOTTOM + 16.0 + row,
            esc(&nav.navigator),
            ratios.len()
        );
        for (k, r) in ratios.iter().enumerate() {
            // Golden-ratio jitter: spreads the dots evenly and is the same on every run.
            let dx = ((k as f64 * 0.618_034).fract() - 0.5) * band * 0.5;
            let _ = writeln!(
                s,
                "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"2.5\" fill=\"{}\" fill-opacity=\"0.6\"/>",
                cx + dx,
                y(*r),
                colour(i)
            );
        }
        for (q, w, label) in [(0.5, 0.35, "median"), (0.95, 0.2, "p95")] {
            if let Some(v) = percentile(ratios, q) {
                let half = band * w;
                let _ = writeln!(
                    s,
                    "<line x1=\"{a:.1}\" y1=\"{py:.1}\" x2=\"{b:.1}\" y2=\"{py:.1}\" stroke=\"#000\" stroke-width=\"2\"><title>{label} {v:.3}</title></line>",
                    a = cx - half,
                    py = y(v),
                    b = cx + half
                );
            }
        }
    }
    let _ = writeln!(
        s,
        "<text x=\"{:.1}\" y=\"{:.1}\">long bar: median</text><text x=\"{0:.1}\" y=\"{:.1}\">short bar: p95</text>",
        RIGHT + 20.0,
        TOP + 10.0,
        TOP + 28.0
    );
    s.push_str("</svg>\n");
    s
}

/// A round tick step (1, 2 or 5 times a power of ten) near `raw`.
fn nice_step(raw: f64) -> f64 {
    let p = 10f64.powf(raw.max(1e-9).log10().floor());
    let m = raw / p;
    p * if m < 1.5 {
        1.0
    } else if m < 3.5 {
        2.0
    } else if m < 7.5 {
        5.0
    } else {
        10.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::CampaignMeta;
    use crate::row::tests::row;
    use crate::spec::CampaignSpec;
    use crate::summary::summarise;

    fn summary_and_rows() -> (Summary, Vec<Row>) {
        let spec = CampaignSpec::from_toml("name = \"p\"", "t").unwrap();
        let meta = CampaignMeta {
            spec,
            navigators: vec!["nat".into(), "a<b".into()],
            trials: vec![],
            skipped: vec![],
            shard: None,
            jobs: 0,
        };
        let mut rows = Vec::new();
        for t in 0..6 {
            rows.push(row(t, "nat", "reached", 0, 10.0 + t as f64));
            rows.push(row(t, "a<b", if t < 3 { "reached" } else { "timeout" }, 0, 12.0));
        }
        (summarise(&meta, &rows).0, rows)
    }

    #[test]
    fn success_plot_has_a_line_and_a_point_per_bin_for_each_navigator() {
        let (s, _) = summary_and_rows();
        let svg = success_vs_rock_abundance(&s);
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        assert_eq!(svg.matches("<polyline").count(), 2);
        assert_eq!(svg.matches("<circle").count(), 2 * 3);
        assert!(svg.contains("a&lt;b") && !svg.contains("a<b"), "names are escaped");
    }

    #[test]
    fn path_ratio_plot_has_a_dot_per_reached_run() {
        let (s, rows) = summary_and_rows();
        let svg = path_ratio(&s, &rows);
        assert_eq!(svg.matches("<circle").count(), 6 + 3);
        assert_eq!(svg.matches("<title>median").count(), 2);
    }

    #[test]
    fn tick_steps_are_round() {
        assert_eq!(nice_step(0.13), 0.1);
        assert_eq!(nice_step(0.3), 0.2);
        assert_eq!(nice_step(0.04), 0.05);
        assert_eq!(nice_step(8.0), 10.0);
    }
}
