//! Pictures of traverses: shaded terrain, rocks and hazards, sensed area, planned and driven
//! paths, start, goal and a scale bar, written as PNG; and of instrument placements
//! ([`placement`]).
//!
//! A tiny software rasteriser is enough here and keeps image crates (and their build time) out.

mod canvas;
pub mod placement;

pub use canvas::{Canvas, Rgb};

use rovernav_core::{Grid2, Overlay, OverlayKind, Point2, Pose3};
use rovernav_terrain::Terrain;
use std::io::Write;

/// Everything drawn in a traverse picture.
pub struct TraverseScene<'a> {
    /// The world.
    pub terrain: &'a Terrain,
    /// Rocks taller than this are drawn as hazards (m).
    pub hazard_height: f64,
    /// Cells covered by range data.
    pub sensed: Option<&'a Grid2<bool>>,
    /// Plans announced during the run (the last is drawn strongest).
    pub plans: &'a [Vec<Point2>],
    /// Navigator overlays (C-obstacles, wedges...).
    pub overlays: &'a [Overlay],
    /// True driven path.
    pub driven: &'a [Pose3],
    /// Estimated path.
    pub estimated: &'a [Pose3],
    /// Hazard contact locations.
    pub hazards: &'a [Point2],
    /// Start position.
    pub start: Point2,
    /// Goal position.
    pub goal: Point2,
    /// Keep-out polygons.
    pub keep_out: &'a [Vec<Point2>],
}

/// The traverse picture of a run (`traverse.png`): the same drawing for `rovernav run`, its
/// replay and a campaign's failure gallery.
pub fn run_traverse_png(
    report: &rovernav_executive::Report,
    world: &rovernav_executive::World,
    trace: &rovernav_executive::Trace,
) -> std::io::Result<Vec<u8>> {
    let hazards: Vec<Point2> = report.hazard_events.iter().map(|e| Point2::new(e.x, e.y)).collect();
    let scene = TraverseScene {
        terrain: &world.terrain,
        hazard_height: world.rover.clearance,
        sensed: trace.sensed.as_ref(),
        plans: &trace.plans,
        overlays: &trace.overlays,
        driven: &trace.truth,
        estimated: &trace.estimate,
        hazards: &hazards,
        start: world.start.position(),
        goal: world.goal.position,
        keep_out: &world.goal.keep_out,
    };
    let mut bytes = Vec::new();
    write_traverse_png(&scene, &mut bytes)?;
    Ok(bytes)
}

/// Longest image side in pixels.
const MAX_SIDE: usize = 1000;

/// Renders the scene into a canvas.
pub fn render_traverse(scene: &TraverseScene<'_>) -> Canvas {
    let g = *scene.terrain.dem.geometry();
    let scale = (MAX_SIDE as f64 / g.cols.max(g.rows) as f64).min(4.0);
    let width = ((g.cols as f64) * scale).round().max(1.0) as usize;
    let height = ((g.rows as f64) * scale).round().max(1.0) as usize;
    let mut canvas = Canvas::new(width, height);
    let px_per_m = scale / g.resolution;
    let to_px = |p: Point2| -> (f64, f64) {
        ((p.x - g.origin_x) * px_per_m, height as f64 - (p.y - g.origin_y) * px_per_m)
    };

    shade_terrain(&mut canvas, scene, scale);
    if let Some(sensed) = scene.sensed {
        tint_sensed(&mut canvas, sensed, &to_px, px_per_m);
    }
    for rock in &scene.terrain.rocks {
        let (cx, cy) = to_px(Point2::new(rock.x, rock.y));
        let r = (0.5 * rock.diameter * px_per_m).max(1.0);
        if rock.height > scene.hazard_height {
            canvas.fill_circle(cx, cy, r, Rgb(200, 40, 30), 0.85);
        } else if r >= 1.5 {
            canvas.stroke_circle(cx, cy, r, Rgb(90, 70, 50), 0.5);
        }
    }
    for zone in scene.keep_out {
        let pts: Vec<(f64, f64)> = zone.iter().map(|p| to_px(*p)).collect();
        canvas.fill_polygon(&pts, Rgb(255, 0, 255), 0.25);
        canvas.polyline(&pts, true, Rgb(255, 0, 255), 2.0);
    }
    for overlay in scene.overlays {
        let (pts, closed, kind) = match overlay {
            Overlay::Polygon(p, k) => (p, true, *k),
            Overlay::Polyline(p, k) => (p, false, *k),
        };
        let pts: Vec<(f64, f64)> = pts.iter().map(|p| to_px(*p)).collect();
        let (color, w) = match kind {
            OverlayKind::CObstacle => (Rgb(255, 140, 0), 1.5),
            OverlayKind::Wedge => (Rgb(0, 160, 255), 1.0),
            OverlayKind::Plan => (Rgb(40, 90, 255), 1.5),
            OverlayKind::Other => (Rgb(230, 230, 230), 1.0),
        };
        canvas.polyline(&pts, closed, color, w);
    }
    let n = scene.plans.len();
    for (i, plan) in scene.plans.iter().enumerate() {
        let pts: Vec<(f64, f64)> = plan.iter().map(|p| to_px(*p)).collect();
        let last = i + 1 == n;
        canvas.polyline(
            &pts,
            false,
            if last { Rgb(40, 90, 255) } else { Rgb(120, 150, 255) },
            if last { 2.0 } else { 1.0 },
        );
    }
    let est: Vec<(f64, f64)> = scene.estimated.iter().map(|p| to_px(Point2::new(p.x, p.y))).collect();
    canvas.polyline(&est, false, Rgb(255, 230, 0), 1.0);
    let driven: Vec<(f64, f64)> = scene.driven.iter().map(|p| to_px(Point2::new(p.x, p.y))).collect();
    canvas.polyline(&driven, false, Rgb(255, 255, 255), 2.5);
    for h in scene.hazards {
        let (x, y) = to_px(*h);
        canvas.cross(x, y, 8.0, Rgb(255, 0, 0), 3.0);
    }
    let (sx, sy) = to_px(scene.start);
    canvas.fill_circle(sx, sy, 6.0, Rgb(0, 200, 0), 1.0);
    let (gx, gy) = to_px(scene.goal);
    canvas.stroke_circle(gx, gy, 9.0, Rgb(255, 215, 0), 1.0);
    canvas.fill_circle(gx, gy, 4.0, Rgb(255, 215, 0), 1.0);
    draw_scale_bar(&mut canvas, px_per_m);
    canvas
}

/// Writes a traverse picture as PNG.
pub fn write_traverse_png(scene: &TraverseScene<'_>, out: impl Write) -> std::io::Result<()> {
    render_traverse(scene).write_png(out)
}

/// Hillshade (sun from the north-west, 45 deg up) mapped to a Mars-like ochre palette.
fn shade_terrain(canvas: &mut Canvas, scene: &TraverseScene<'_>, scale: f64) {
    let dem = &scene.terrain.dem;
    let g = *dem.geometry();
    let (lo, hi) = dem
        .heights
        .data
        .iter()
        .filter(|v| v.is_finite())
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
    let span = ((hi - lo) as f64).max(1e-6);
    let sun = {
        let az = 135f64.to_radians();
        let el = 45f64.to_radians();
        [az.cos() * el.cos(), az.sin() * el.cos(), el.sin()]
    };
    let h = |c: isize, r: isize| -> f64 {
        let c = c.clamp(0, g.cols as isize - 1);
        let r = r.clamp(0, g.rows as isize - 1);
        *dem.heights.get(c as usize, r as usize) as f64
    };
    for py in 0..canvas.height {
        let r = ((canvas.height - 1 - py) as f64 / scale) as isize;
        for px in 0..canvas.width {
            let c = (px as f64 / scale) as isize;
            let z = h(c, r);
            if !z.is_finite() {
                canvas.set(px, py, Rgb(20, 20, 30));
                continue;
            }
            let dzdx = (h(c + 1, r) - h(c - 1, r)) / (2.0 * g.resolution);
            let dzdy = (h(c, r + 1) - h(c, r - 1)) / (2.0 * g.resolution);
            let n = [-dzdx, -dzdy, 1.0];
            let len = (n[0] * n[0] + n[1] * n[1] + 1.0).sqrt();
            let shade = if dzdx.is_finite() && dzdy.is_finite() {
                ((n[0] * sun[0] + n[1] * sun[1] + n[2] * sun[2]) / len).clamp(0.0, 1.0)
            } else {
                0.7
            };
            let t = (z - lo as f64) / span;
            let base = [150.0 + 70.0 * t, 95.0 + 50.0 * t, 60.0 + 30.0 * t];
            let k = 0.35 + 0.75 * shade;
            canvas.set(
                px,
                py,
                Rgb(
                    (base[0] * k).min(255.0) as u8,
                    (base[1] * k).min(255.0) as u8,
                    (base[2] * k).min(255.0) as u8,
                ),
            );
        }
    }
}

fn tint_sensed(
    canvas: &mut Canvas,
    sensed: &Grid2<bool>,
    to_px: &dyn Fn(Point2) -> (f64, f64),
    px_per_m: f64,
) {
    let g = sensed.geometry;
    let size = (g.resolution * px_per_m).max(1.0);
    for r in 0..g.rows {
        for c in 0..g.cols {
            if *sensed.get(c, r) {
                let (x, y) = g.center(c, r);
                let (px, py) = to_px(Point2::new(x, y));
                canvas.fill_rect(px - size / 2.0, py - size / 2.0, size, size, Rgb(60, 200, 255), 0.18);
            }
        }
    }
}

fn draw_scale_bar(canvas: &mut Canvas, px_per_m: f64) {
    let target_px = canvas.width as f64 / 5.0;
    let raw = target_px / px_per_m;
    let magnitude = 10f64.powf(raw.log10().floor());
    let metres =
        [1.0, 2.0, 5.0, 10.0].iter().map(|k| k * magnitude).rfind(|m| *m <= raw).unwrap_or(magnitude);
    let len = metres * px_per_m;
    let x0 = 15.0;
    let y0 = canvas.height as f64 - 20.0;
    canvas.fill_rect(x0 - 6.0, y0 - 22.0, len + 60.0, 32.0, Rgb(0, 0, 0), 0.45);
    canvas.fill_rect(x0, y0 - 3.0, len, 6.0, Rgb(255, 255, 255), 1.0);
    canvas.fill_rect(x0, y0 - 9.0, 2.0, 12.0, Rgb(255, 255, 255), 1.0);
    canvas.fill_rect(x0 + len - 2.0, y0 - 9.0, 2.0, 12.0, Rgb(255, 255, 255), 1.0);
    let label = if metres >= 1.0 { format!("{}m", metres as u64) } else { format!("{metres}m") };
    canvas.text(x0 + len + 6.0, y0 - 8.0, &label, Rgb(255, 255, 255), 2);
}
