//! The side panel of a traverse picture: the elevation colour bar (plotters axis), the end
//! points' goal errors (truth beside estimate), the legend, and the overview inset when the world
//! is much larger than the map's frame.

use super::legend::{self, EDGE, Entry, Mark};
use super::{TraverseScene, frame::Frame, raster};
use crate::font;
use plotters::coord::Shift;
use plotters::prelude::*;
use rovernav_core::Point2;

type Area<DB> = DrawingArea<DB, Shift>;
type DrawResult<DB> = Result<(), DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>>;

const BAR_BLOCK: u32 = 200;
const ENDS_BLOCK: u32 = 104;
const LINE: u32 = 19;
const INSET_PX: u32 = 230;
const INSET_BLOCK: u32 = INSET_PX + 58;

/// The panel's height for `entries` legend lines and an optional inset (px).
pub(super) fn height(entries: usize, inset: bool) -> u32 {
    BAR_BLOCK + ENDS_BLOCK + 28 + LINE * entries as u32 + 12 + if inset { INSET_BLOCK } else { 0 }
}

fn text_style(size: f64, bold: bool) -> TextStyle<'static> {
    FontDesc::new(font::family(), size, if bold { FontStyle::Bold } else { FontStyle::Normal }).color(&BLACK)
}

/// Draws the panel.
pub(super) fn draw<DB: DrawingBackend>(
    area: &Area<DB>,
    scene: &TraverseScene<'_>,
    frame: Frame,
    range: (f64, f64),
    entries: &[Entry],
    inset: bool,
) -> DrawResult<DB> {
    let (bar, rest) = area.split_vertically(BAR_BLOCK);
    colour_bar(&bar, range)?;
    let (ends, rest) = rest.split_vertically(ENDS_BLOCK);
    end_points(&ends, scene)?;
    let (legend_area, rest) = rest.split_vertically(28 + LINE * entries.len() as u32 + 12);
    draw_legend(&legend_area, entries)?;
    if inset {
        overview(&rest, scene, frame)?;
    }
    Ok(())
}

fn colour_bar<DB: DrawingBackend>(area: &Area<DB>, (lo, hi): (f64, f64)) -> DrawResult<DB> {
    area.draw(&Text::new("Elevation (m), fitted to the map", (0, 4), text_style(15.0, true)))?;
    let (_, below) = area.split_vertically(26);
    let (bar_area, note) = below.split_horizontally(150);
    let mut chart = ChartBuilder::on(&bar_area)
        .y_label_area_size(80)
        .margin_top(8)
        .margin_bottom(8)
        .build_cartesian_2d(0.0..1.0, lo..hi)?;
    let steps = 120;
    chart.draw_series((0..steps).map(|k| {
        let (a, b) = (k as f64 / steps as f64, (k + 1) as f64 / steps as f64);
        let c = raster::ramp((a + b) / 2.0);
        Rectangle::new(
            [(0.0, lo + a * (hi - lo)), (1.0, lo + b * (hi - lo))],
            RGBColor(c[0], c[1], c[2]).filled(),
        )
    }))?;
    let digits = if hi - lo < 2.0 {
        2
    } else if hi - lo < 20.0 {
        1
    } else {
        0
    };
    let fmt = move |v: &f64| format!("{v:.digits$}");
    chart
        .configure_mesh()
        .disable_x_mesh()
        .disable_y_mesh()
        .disable_x_axis()
        .y_labels(6)
        .y_label_formatter(&fmt)
        .label_style(text_style(13.0, false))
        .draw()?;
    let lines =
        ["light: facing the sun", "(north-west, 45° up);", "cyan tint: ground the", "range sensors saw"];
    for (i, l) in lines.iter().enumerate() {
        note.draw(&Text::new(*l, (4, 20 + i as i32 * 18), text_style(13.0, false)))?;
    }
    Ok(())
}

fn end_points<DB: DrawingBackend>(area: &Area<DB>, scene: &TraverseScene<'_>) -> DrawResult<DB> {
    let goal = scene.goal.position;
    area.draw(&Text::new(
        format!("End points (goal tolerance {:.2} m)", scene.goal.tolerance),
        (0, 4),
        text_style(15.0, true),
    ))?;
    let mut lines = vec![format!("true end: {:.2} m from the goal", scene.report.goal_error_m)];
    if let Some(est) = scene.trace.estimate.last() {
        let d = Point2::new(est.x, est.y).dist(goal);
        lines.push(format!("estimated end: {d:.2} m from the goal"));
    }
    lines.push(format!("localisation error at the end: {:.2} m", scene.report.localization_error_m));
    for (i, l) in lines.iter().enumerate() {
        area.draw(&Text::new(l.clone(), (4, 28 + i as i32 * LINE as i32), text_style(14.0, false)))?;
    }
    Ok(())
}

fn draw_legend<DB: DrawingBackend>(area: &Area<DB>, entries: &[Entry]) -> DrawResult<DB> {
    area.draw(&Text::new("Legend", (0, 4), text_style(15.0, true)))?;
    // Samples sit on a mid-grey swatch so that white and yellow marks show.
    for (i, e) in entries.iter().enumerate() {
        let y = 28 + i as i32 * LINE as i32;
        let c = (16, y + 8);
        area.draw(&Rectangle::new([(0, y), (32, y + 16)], legend::SWATCH.filled()))?;
        match e.mark {
            Mark::Line(colour, w) => {
                area.draw(&PathElement::new(vec![(3, c.1), (29, c.1)], colour.stroke_width(w)))?;
            }
            Mark::Patch(colour) => {
                area.draw(&Rectangle::new([(3, y + 3), (29, y + 13)], colour.mix(0.6).filled()))?
            }
            Mark::Disc(colour) => area.draw(&Circle::new(c, 6, colour.filled()))?,
            Mark::Ring(colour) => area.draw(&Circle::new(c, 6, colour.stroke_width(2)))?,
            Mark::Cross(colour) => area.draw(&Cross::new(c, 5, colour.stroke_width(3)))?,
            Mark::Diamond(colour) => {
                let pts =
                    vec![(c.0, c.1 - 7), (c.0 + 7, c.1), (c.0, c.1 + 7), (c.0 - 7, c.1), (c.0, c.1 - 7)];
                area.draw(&Polygon::new(pts.clone(), colour.filled()))?;
                area.draw(&PathElement::new(pts, EDGE.stroke_width(1)))?;
            }
            Mark::Outline(colour) => {
                area.draw(&Rectangle::new([(6, y + 3), (26, y + 13)], colour.stroke_width(2)))?;
            }
            Mark::Crosshair(colour) => {
                for style in [EDGE.stroke_width(5), colour.stroke_width(3)] {
                    area.draw(&PathElement::new(vec![(c.0 - 8, c.1), (c.0 + 8, c.1)], style))?;
                    area.draw(&PathElement::new(vec![(c.0, c.1 - 8), (c.0, c.1 + 8)], style))?;
                }
            }
            Mark::Dots(colour) => {
                area.draw(&PathElement::new(vec![(5, c.1), (27, c.1)], colour.stroke_width(1)))?;
                for x in [6, 16, 26] {
                    area.draw(&Circle::new((x, c.1), 3, colour.filled()))?;
                }
            }
        }
        area.draw(&Text::new(e.label.clone(), (40, y), text_style(14.0, false)))?;
    }
    Ok(())
}

fn overview<DB: DrawingBackend>(area: &Area<DB>, scene: &TraverseScene<'_>, frame: Frame) -> DrawResult<DB> {
    let dem = &scene.terrain.dem;
    let world = Frame::of_grid(dem.geometry());
    area.draw(&Text::new(
        format!("Overview: the whole map, {:.0} m x {:.0} m", world.width(), world.height()),
        (0, 4),
        text_style(15.0, true),
    ))?;
    let (w, h) = world.pixels(INSET_PX);
    let (_, below) = area.split_vertically(28);
    let (inset, _) = below.split_horizontally(w + 2);
    let (inset, _) = inset.split_vertically(h + 2);
    let mut chart =
        ChartBuilder::on(&inset).margin(1).build_cartesian_2d(world.x0..world.x1, world.y0..world.y1)?;
    let range = raster::elevation_range(dem, &world);
    let pixels = raster::shade(dem, None, &world, range, w as usize, h as usize);
    if let Some(bitmap) = BitMapElement::with_owned_buffer((world.x0, world.y1), (w, h), pixels) {
        chart.draw_series(std::iter::once(bitmap))?;
    }
    let truth: Vec<(f64, f64)> = scene.trace.truth.iter().map(|p| (p.x, p.y)).collect();
    chart.draw_series(super::map::segments(truth, legend::DRIVEN.stroke_width(2)))?;
    let outline = vec![
        (frame.x0, frame.y0),
        (frame.x1, frame.y0),
        (frame.x1, frame.y1),
        (frame.x0, frame.y1),
        (frame.x0, frame.y0),
    ];
    chart.draw_series(super::map::segments(outline, RED.stroke_width(2)))?;
    inset.draw(&Rectangle::new([(0, 0), (w as i32 + 1, h as i32 + 1)], BLACK.stroke_width(1)))?;
    let note = "red box: the map; white: the driven path";
    area.draw(&Text::new(note, (0, 34 + h as i32), text_style(13.0, false)))?;
    Ok(())
}
