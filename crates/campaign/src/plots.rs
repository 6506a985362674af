//! SVG charts of a campaign, drawn with plotters (through `rovernav-viz`, in its embedded font):
//! success against rock abundance with 95 % Wilson intervals, and the path-ratio distribution per
//! navigator with the median and p95 that `summary.md` gives ([`crate::summary::median`] and
//! [`crate::summary::percentile`], read from the summary itself).
//!
//! Labels under the x axis are laid out from their measured text extents ([`label_rows`]): a
//! label that would overlap its neighbour moves to the next row, so none collide.

use crate::row::Row;
use crate::summary::{Summary, Z95, wilson};
use rovernav_viz::font;
use rovernav_viz::plotters::coord::Shift;
use rovernav_viz::plotters::prelude::*;
use rovernav_viz::plotters::style::text_anchor::{HPos, Pos, VPos};

/// Chart size (px).
const SIZE: (u32, u32) = (900, 500);
/// Width of the legend column on the right (px).
const LEGEND_W: u32 = 250;
/// Plot margins: left (y labels), top (title), bottom (x labels).
const LEFT: u32 = 70;
const TOP: u32 = 44;
const BOTTOM: u32 = 96;

/// Distinguishable colours (Okabe-Ito, then greys) for up to ten navigators.
const PALETTE: [RGBColor; 10] = [
    RGBColor(0x00, 0x72, 0xB2),
    RGBColor(0xE6, 0x9F, 0x00),
    RGBColor(0x00, 0x9E, 0x73),
    RGBColor(0xCC, 0x79, 0xA7),
    RGBColor(0xD5, 0x5E, 0x00),
    RGBColor(0x56, 0xB4, 0xE9),
    RGBColor(0x00, 0x00, 0x00),
    RGBColor(0xF0, 0xE4, 0x42),
    RGBColor(0x99, 0x99, 0x99),
    RGBColor(0x7F, 0x3C, 0x8D),
];

fn colour(i: usize) -> RGBColor {
    PALETTE[i % PALETTE.len()]
}

fn text(size: f64) -> TextStyle<'static> {
    FontDesc::new(font::family(), size, FontStyle::Normal).color(&BLACK)
}

/// Text width in `style`'s font (px).
fn width_of(s: &str, size: f64) -> f64 {
    FontDesc::new(font::family(), size, FontStyle::Normal)
        .box_size(s)
        .map_or(7.0 * s.len() as f64, |(w, _)| w as f64)
}

/// Rows for labels centred at `centres` (px) with `widths` (px): each label takes the first row
/// in which it clears every label already placed there by `gap` px.
pub fn label_rows(centres: &[f64], widths: &[f64], gap: f64) -> Vec<usize> {
    let mut rows: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut out = Vec::with_capacity(centres.len());
    for (&c, &w) in centres.iter().zip(widths) {
        let (a, b) = (c - w / 2.0, c + w / 2.0);
        let free = |row: &Vec<(f64, f64)>| row.iter().all(|&(x0, x1)| b + gap <= x0 || a >= x1 + gap);
        let k = rows.iter().position(free).unwrap_or(rows.len());
        if k == rows.len() {
            rows.push(Vec::new());
        }
        rows[k].push((a, b));
        out.push(k);
    }
    out
}

type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;
type Drawn = Result<(), DrawingAreaErrorKind<std::io::Error>>;

/// Draws labels centred at `centres` under the plot, stacked by [`label_rows`]; each label is
/// one or more lines.
fn x_labels(area: &Area<'_>, centres: &[f64], labels: &[Vec<String>], y: i32) -> Drawn {
    const SIZE: f64 = 12.0;
    const LINE: i32 = 15;
    let widths: Vec<f64> =
        labels.iter().map(|l| l.iter().map(|s| width_of(s, SIZE)).fold(0.0, f64::max)).collect();
    let rows = label_rows(centres, &widths, 6.0);
    let height = labels.iter().map(|l| l.len() as i32).max().unwrap_or(1) * LINE + 4;
    for ((c, lines), row) in centres.iter().zip(labels).zip(rows) {
        for (k, line) in lines.iter().enumerate() {
            let pos = (*c as i32, y + row as i32 * height + k as i32 * LINE);
            let style = text(SIZE).pos(Pos::new(HPos::Center, VPos::Top));
            area.draw(&Text::new(
                line.clone(),
                pos,
                if k == 0 { style } else { style.color(&RGBColor(90, 90, 90)) },
            ))?;
        }
    }
    Ok(())
}

/// Legend entries at the right: a swatch and a line of words per navigator, then any further
/// lines of that entry in grey.
fn legend(area: &Area<'_>, entries: &[(RGBColor, Vec<String>)], notes: &[&str]) -> Drawn {
    let x = (SIZE.0 - LEGEND_W + 16) as i32;
    let mut y = TOP as i32 + 4;
    for (c, lines) in entries {
        area.draw(&Rectangle::new([(x, y), (x + 14, y + 14)], c.filled()))?;
        for (k, words) in lines.iter().enumerate() {
            let style = if k == 0 { text(12.0) } else { text(11.0).color(&RGBColor(90, 90, 90)) };
            area.draw(&Text::new(words.clone(), (x + 22, y), style))?;
            y += 16;
        }
        y += 6;
    }
    for n in notes {
        y += 4;
        area.draw(&Text::new(n.to_string(), (x, y), text(11.0).color(&RGBColor(80, 80, 80))))?;
        y += 14;
    }
    Ok(())
}

fn render(draw: impl FnOnce(&Area<'_>) -> Drawn) -> String {
    font::ensure();
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
        // Drawing into a string cannot fail but for a missing font, which is embedded.
        let _ = root.fill(&WHITE).and_then(|_| draw(&root)).and_then(|_| root.present());
    }
    svg
}

fn title(area: &Area<'_>, words: &str) -> Drawn {
    let x = ((SIZE.0 - LEGEND_W) / 2) as i32;
    area.draw(&Text::new(words.to_string(), (x, 14), text(16.0).pos(Pos::new(HPos::Center, VPos::Top))))
}

fn plot_area<'a>(root: &Area<'a>) -> Area<'a> {
    let (plot, _) = root.split_horizontally(SIZE.0 - LEGEND_W);
    plot.margin(TOP, BOTTOM, 0, 12)
}

/// Success rate of each navigator against rock abundance with its 95 % Wilson interval, each
/// bin's run count under its centre, and each navigator's overall rate and interval in the legend.
pub fn success_vs_rock_abundance(summary: &Summary) -> String {
    render(|root| {
        title(root, &format!("Success against rock abundance — campaign {}", summary.campaign))?;
        let bins = &summary.by_rock_abundance;
        let centres: Vec<f64> = bins.iter().map(|b| (b.lo + b.hi) / 2.0).collect();
        let lo = centres.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = centres.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let (lo, hi) = if lo.is_finite() { (lo, hi) } else { (0.0, 0.2) };
        // Room for the navigators dodged sideways around the outer bins.
        let pad = if hi > lo { 0.2 * (hi - lo) } else { 0.02 };
        let area = plot_area(root);
        let mut chart = ChartBuilder::on(&area)
            .y_label_area_size(LEFT)
            .build_cartesian_2d(lo - pad..hi + pad, 0.0..1.0)?;
        let pct = |v: &f64| format!("{:.0} %", v * 100.0);
        chart
            .configure_mesh()
            .disable_x_mesh()
            .light_line_style(RGBColor(245, 245, 245))
            .x_labels(0)
            .y_labels(5)
            .y_label_formatter(&pct)
            .y_desc("success (reached, no hazard contact)")
            .label_style(text(12.0))
            .axis_desc_style(text(13.0))
            .draw()?;
        let count = summary.navigators.len().max(1) as f64;
        let spacing = if centres.len() > 1 { (hi - lo) / (centres.len() - 1) as f64 } else { 2.0 * pad };
        for i in 0..summary.navigators.len() {
            // Side by side within a bin so that equal rates and their intervals stay apart.
            let dodge = (i as f64 - (count - 1.0) / 2.0) * 0.5 * spacing / count;
            let c = colour(i);
            let mut pts = Vec::new();
            for (b, x) in bins.iter().zip(&centres) {
                let [n, s] = b.per_navigator[i];
                let Some([a, z]) = wilson(s, n, Z95) else { continue };
                let x = x + dodge;
                pts.push((x, s as f64 / n as f64));
                chart.draw_series(std::iter::once(PathElement::new(
                    vec![(x, a), (x, z)],
                    c.stroke_width(1),
                )))?;
                for end in [a, z] {
                    chart.draw_series(std::iter::once(
                        EmptyElement::at((x, end)) + PathElement::new(vec![(-4, 0), (4, 0)], c),
                    ))?;
                }
            }
            chart.draw_series(std::iter::once(PathElement::new(pts.clone(), c.stroke_width(2))))?;
            chart.draw_series(pts.into_iter().map(|p| Circle::new(p, 4, c.filled())))?;
        }
        let px: Vec<f64> = centres.iter().map(|&x| chart.backend_coord(&(x, 0.0)).0 as f64).collect();
        let y = chart.backend_coord(&(lo, 0.0)).1 + 8;
        let labels: Vec<Vec<String>> = bins
            .iter()
            .zip(&centres)
            .map(|(b, c)| vec![format!("{c:.3}"), format!("n={}", b.terrains)])
            .collect();
        x_labels(root, &px, &labels, y)?;
        let x_mid = ((SIZE.0 - LEGEND_W) / 2) as i32;
        root.draw(&Text::new(
            "rock abundance k (bin centre; n = terrains)",
            (x_mid, SIZE.1 as i32 - 20),
            text(13.0).pos(Pos::new(HPos::Center, VPos::Top)),
        ))?;
        let lines: Vec<(RGBColor, Vec<String>)> = summary
            .navigators
            .iter()
            .enumerate()
            .map(|(i, n)| {
                let rate = n.success_rate.map_or("–".into(), |r| format!("{:.0} %", 100.0 * r));
                let ci = n
                    .success_ci95
                    .map_or(String::new(), |[a, b]| format!(" [{:.0}, {:.0}]", 100.0 * a, 100.0 * b));
                (colour(i), vec![format!("{} {rate}{ci}", n.navigator)])
            })
            .collect();
        legend(root, &lines, &["bars: 95 % Wilson interval", "legend: overall rate [95 % CI]"])
    })
}

/// Path ratio (distance driven / optimal) of every reached run, one column per navigator, with
/// the median (long bar) and the p95 (short bar) as `summary.md` gives them.
pub fn path_ratio(summary: &Summary, rows: &[Row]) -> String {
    render(|root| {
        title(root, &format!("Path ratio of reached runs — campaign {}", summary.campaign))?;
        let per_nav: Vec<Vec<f64>> = summary
            .navigators
            .iter()
            .map(|n| {
                rows.iter().filter(|r| r.navigator == n.navigator).filter_map(|r| r.path_ratio).collect()
            })
            .collect();
        let all = per_nav.iter().flatten().copied();
        let lo = all.clone().fold(1.0f64, f64::min);
        let hi = all.fold(1.2f64, f64::max);
        let (y0, y1) = ((lo - 0.05).max(0.0), hi + 0.05 * (hi - lo).max(0.2));
        let n = per_nav.len().max(1);
        let area = plot_area(root);
        let mut chart =
            ChartBuilder::on(&area).y_label_area_size(LEFT).build_cartesian_2d(0.0..n as f64, y0..y1)?;
        let fmt = |v: &f64| format!("{v:.2}");
        chart
            .configure_mesh()
            .disable_x_mesh()
            .light_line_style(RGBColor(245, 245, 245))
            .x_labels(0)
            .y_labels(7)
            .y_label_formatter(&fmt)
            .y_desc("distance driven / optimal length")
            .label_style(text(12.0))
            .axis_desc_style(text(13.0))
            .draw()?;
        let dash = DashedLineSeries::new(vec![(0.0, 1.0), (n as f64, 1.0)], 5, 4, BLACK.into());
        chart.draw_series(dash)?;
        let mut entries = Vec::new();
        for (i, (nav, ratios)) in summary.navigators.iter().zip(&per_nav).enumerate() {
            let cx = i as f64 + 0.5;
            for (k, r) in ratios.iter().enumerate() {
                // Golden-ratio jitter: spreads the dots evenly and is the same on every run.
                let dx = ((k as f64 * 0.618_034).fract() - 0.5) * 0.5;
                chart.draw_series(std::iter::once(Circle::new(
                    (cx + dx, *r),
                    3,
                    colour(i).mix(0.6).filled(),
                )))?;
            }
            for (v, half) in [(nav.path_ratio_median, 0.35), (nav.path_ratio_p95, 0.2)] {
                if let Some(v) = v {
                    chart.draw_series(std::iter::once(PathElement::new(
                        vec![(cx - half, v), (cx + half, v)],
                        BLACK.stroke_width(2),
                    )))?;
                }
            }
            let stats = match (nav.path_ratio_median, nav.path_ratio_p95) {
                (Some(m), Some(p)) => format!("n={} · median {m:.3} · p95 {p:.3}", ratios.len()),
                _ => "no reached run".to_string(),
            };
            entries.push((colour(i), vec![nav.navigator.clone(), stats]));
        }
        let px: Vec<f64> = (0..n).map(|i| chart.backend_coord(&(i as f64 + 0.5, y0)).0 as f64).collect();
        let y = chart.backend_coord(&(0.0, y0)).1 + 8;
        let labels: Vec<Vec<String>> = summary.navigators.iter().map(|n| vec![n.navigator.clone()]).collect();
        x_labels(root, &px, &labels, y)?;
        legend(
            root,
            &entries,
            &["long bar: median (as summary.md)", "short bar: p95 (nearest rank)", "dashed: optimal (1.0)"],
        )
    })
}

#[cfg(test)]
#[path = "plots_tests.rs"]
mod tests;
