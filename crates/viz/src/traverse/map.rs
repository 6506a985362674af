//! The map of a traverse picture: plotters axes in metres over the shaded terrain, then the
//! marks in the legend's order (rocks, keep-out zones, navigator overlays, plans, paths, hazard
//! contacts, start, goal, waypoints, VTT target estimates and targets, the rover's footprint and the two end points).

use super::legend::*;
use super::{MapPixels, TraverseScene, frame::Frame, raster};
use crate::font;
use plotters::coord::Shift;
use plotters::prelude::*;
use rovernav_core::{Overlay, Point2};

type Area<DB> = DrawingArea<DB, Shift>;

/// Draws the map into `area`; returns where the frame landed in pixels.
pub(super) fn draw<DB: DrawingBackend>(
    area: &Area<DB>,
    scene: &TraverseScene<'_>,
    frame: Frame,
    range: (f64, f64),
    (mw, mh): (u32, u32),
    (y_labels, x_labels, gap): (u32, u32, u32),
) -> Result<MapPixels, DrawingAreaErrorKind<DB::ErrorType>> {
    let geo = &scene.terrain.dem.geo;
    // Procedural and hand-built worlds have a local frame ("local", "local (procedural ...)").
    let georeferenced = !geo.crs.starts_with("local");
    let (east, north) = (geo.easting, geo.northing);
    let (x_desc, y_desc) = if georeferenced {
        (format!("easting (m, {})", geo.crs), "northing (m)".to_string())
    } else {
        ("east (m)".to_string(), "north (m)".to_string())
    };
    let mut chart = ChartBuilder::on(area)
        .x_label_area_size(x_labels)
        .y_label_area_size(y_labels)
        .margin_right(gap)
        .build_cartesian_2d(frame.x0..frame.x1, frame.y0..frame.y1)?;
    let label = FontDesc::new(font::family(), 13.0, FontStyle::Normal);
    let x_fmt = move |v: &f64| format!("{:.0}", v + east);
    let y_fmt = move |v: &f64| format!("{:.0}", v + north);
    let fine = frame.width().max(frame.height()) < 12.0;
    let x_fine = move |v: &f64| format!("{:.1}", v + east);
    let y_fine = move |v: &f64| format!("{:.1}", v + north);
    let raster = raster::shade(
        &scene.terrain.dem,
        scene.trace.sensed.as_ref(),
        &frame,
        range,
        mw as usize,
        mh as usize,
    );
    if let Some(bitmap) = BitMapElement::with_owned_buffer((frame.x0, frame.y1), (mw, mh), raster) {
        chart.draw_series(std::iter::once(bitmap))?;
    }
    let mut mesh = chart.configure_mesh();
    mesh.x_desc(x_desc)
        .y_desc(y_desc)
        .x_labels(7)
        .y_labels(7)
        .label_style(label.clone())
        .axis_desc_style(label)
        .light_line_style(TRANSPARENT)
        .bold_line_style(WHITE.mix(0.25));
    if fine {
        mesh.x_label_formatter(&x_fine).y_label_formatter(&y_fine).draw()?;
    } else {
        mesh.x_label_formatter(&x_fmt).y_label_formatter(&y_fmt).draw()?;
    }

    let px_per_m = mw as f64 / frame.width();
    for rock in &scene.terrain.rocks {
        let r = 0.5 * rock.diameter * px_per_m;
        match rock_mark(rock, scene.rover.clearance, &frame, px_per_m) {
            Some(RockMark::Hazard) => {
                chart.draw_series(std::iter::once(Circle::new(
                    (rock.x, rock.y),
                    r.max(2.0),
                    HAZARD_ROCK.filled(),
                )))?;
            }
            Some(RockMark::Small) => {
                chart.draw_series(std::iter::once(Circle::new((rock.x, rock.y), r, ROCK.mix(0.6))))?;
            }
            None => {}
        }
    }
    for zone in &scene.goal.keep_out {
        let pts = xy(zone);
        chart.draw_series(std::iter::once(Polygon::new(pts.clone(), KEEP_OUT.mix(0.25))))?;
        chart.draw_series(segments(closed(pts), KEEP_OUT.stroke_width(2)))?;
    }
    for overlay in &scene.trace.overlays {
        let (pts, kind, is_closed) = match overlay {
            Overlay::Polygon(p, k) => (xy(p), *k, true),
            Overlay::Polyline(p, k) => (xy(p), *k, false),
        };
        let pts = if is_closed { closed(pts) } else { pts };
        chart.draw_series(segments(pts, overlay_colour(kind).stroke_width(2)))?;
    }
    let plans = &scene.trace.plans;
    for (i, plan) in plans.iter().enumerate() {
        let style =
            if i + 1 == plans.len() { PLAN.stroke_width(2) } else { OLD_PLAN.mix(0.7).stroke_width(1) };
        chart.draw_series(segments(xy(plan), style))?;
    }
    let poses = |p: &[rovernav_core::Pose3]| -> Vec<(f64, f64)> { p.iter().map(|q| (q.x, q.y)).collect() };
    chart.draw_series(segments(poses(&scene.trace.estimate), ESTIMATED.stroke_width(1)))?;
    chart.draw_series(segments(poses(&scene.trace.truth), EDGE.mix(0.5).stroke_width(5)))?;
    chart.draw_series(segments(poses(&scene.trace.truth), DRIVEN.stroke_width(3)))?;
    for h in &scene.report.hazard_events {
        chart.draw_series(std::iter::once(Cross::new((h.x, h.y), 8, CONTACT.stroke_width(3))))?;
    }
    let at = |p: Point2| EmptyElement::at((p.x, p.y));
    let diamond = |p: Point2, r: i32, colour: RGBColor| {
        let pts = vec![(0, -r), (r, 0), (0, r), (-r, 0), (0, -r)];
        at(p) + Polygon::new(pts.clone(), colour.filled()) + PathElement::new(pts, EDGE.stroke_width(1))
    };
    chart.draw_series(std::iter::once(at(scene.start) + Circle::new((0, 0), 7, START.filled())))?;
    chart.draw_series(std::iter::once(at(scene.start) + Circle::new((0, 0), 7, EDGE.stroke_width(1))))?;
    let goal = scene.goal.position;
    let tol_px = (scene.goal.tolerance * px_per_m).max(6.0);
    chart.draw_series(std::iter::once(at(goal) + Circle::new((0, 0), tol_px, GOAL.stroke_width(2))))?;
    chart.draw_series(std::iter::once(at(goal) + Circle::new((0, 0), 4, GOAL.filled())))?;
    for w in &scene.goal.waypoints {
        chart.draw_series(std::iter::once(diamond(*w, 6, WAYPOINT)))?;
    }
    for vtt in &scene.trace.vtt {
        let pts: Vec<(f64, f64)> = vtt.estimates.iter().map(|e| (e[0], e[1])).collect();
        chart.draw_series(segments(pts.clone(), VTT_ESTIMATE.stroke_width(1)))?;
        chart.draw_series(pts.iter().map(|&p| Circle::new(p, 3, VTT_ESTIMATE.filled())))?;
    }
    for vtt in &scene.trace.vtt {
        let t = Point2::new(vtt.target[0], vtt.target[1]);
        for style in [EDGE.stroke_width(5), VTT_TARGET.stroke_width(3)] {
            let (h, v) = (vec![(-9, 0), (9, 0)], vec![(0, -9), (0, 9)]);
            chart.draw_series(std::iter::once(at(t) + PathElement::new(h, style)))?;
            chart.draw_series(std::iter::once(at(t) + PathElement::new(v, style)))?;
        }
    }
    if let Some(end) = scene.trace.truth.last() {
        let (c, s) = (end.yaw.cos(), end.yaw.sin());
        let (hl, hw) = (scene.rover.length / 2.0, scene.rover.width / 2.0);
        let corners: Vec<(f64, f64)> = [(hl, hw), (hl, -hw), (-hl, -hw), (-hl, hw), (hl, hw)]
            .iter()
            .map(|(a, b)| (end.x + c * a - s * b, end.y + s * a + c * b))
            .collect();
        let nose = vec![(end.x, end.y), (end.x + c * hl, end.y + s * hl)];
        chart.draw_series(segments(corners.clone(), EDGE.stroke_width(4)))?;
        chart.draw_series(segments(corners, TRUE_END.stroke_width(2)))?;
        chart.draw_series(segments(nose, TRUE_END.stroke_width(2)))?;
    }
    if let Some(est) = scene.trace.estimate.last() {
        chart.draw_series(std::iter::once(diamond(Point2::new(est.x, est.y), 7, ESTIMATED)))?;
    }
    let (x0, y0) = chart.backend_coord(&(frame.x0, frame.y0));
    let (x1, y1) = chart.backend_coord(&(frame.x1, frame.y1));
    Ok(MapPixels { frame, x_px: (x0 as f64, x1 as f64), y_px: (y0 as f64, y1 as f64) })
}

fn xy(points: &[Point2]) -> Vec<(f64, f64)> {
    points.iter().map(|p| (p.x, p.y)).collect()
}

/// A polyline as separate two-point segments (repeated points dropped): plotters joins a wide
/// polyline's segments with mitres, which grow into long spikes where the path turns back on
/// itself (a rover turning in place and backing up).
pub(super) fn segments(mut pts: Vec<(f64, f64)>, style: ShapeStyle) -> Vec<PathElement<(f64, f64)>> {
    pts.dedup();
    pts.windows(2).map(|w| PathElement::new(vec![w[0], w[1]], style)).collect()
}

fn closed(mut pts: Vec<(f64, f64)>) -> Vec<(f64, f64)> {
    if let Some(&first) = pts.first() {
        pts.push(first);
    }
    pts
}
