//! The traverse picture of a run (`traverse.png`), drawn with plotters: a header with the title
//! (mission, navigator, localiser, seed), the outcome and its reason and the run's figures; a map
//! of the frame fitted to the route with axes in metres (eastings and northings on a
//! georeferenced DEM) over the shaded terrain ([`raster`]); and a side panel with the elevation
//! colour bar, the end points' errors (truth beside estimate), the legend of every kind of mark
//! drawn ([`legend`]) and, when the world is much larger than the frame, an overview inset.

pub mod caption;
pub mod frame;
pub mod legend;
mod map;
pub mod raster;
mod side;

use crate::font;
use frame::Frame;
use plotters::coord::Shift;
use plotters::prelude::*;
use rovernav_core::{Goal, Point2, RoverConfig};
use rovernav_executive::{Report, Trace};
use rovernav_terrain::Terrain;

/// Everything a traverse picture shows.
pub struct TraverseScene<'a> {
    /// The world's terrain (heights with rocks, and the rocks).
    pub terrain: &'a Terrain,
    /// The rover (belly clearance for hazard rocks, size for the footprint).
    pub rover: &'a RoverConfig,
    /// True start position.
    pub start: Point2,
    /// Goal (tolerance, waypoints, keep-out zones) as the run ended with it.
    pub goal: &'a Goal,
    /// The recorded traverse.
    pub trace: &'a Trace,
    /// The run's report (title, outcome, reason, figures).
    pub report: &'a Report,
}

/// Longest side of the map (px).
const MAP_PX: u32 = 720;
/// Width of the y-axis label area (px).
const Y_LABELS: u32 = 78;
/// Height of the x-axis label area (px).
const X_LABELS: u32 = 48;
/// Gap between the map and the side panel (px).
const GAP: u32 = 24;
/// Side panel width (px).
const SIDE: u32 = 320;
/// Header line heights (px).
const TITLE_LINE: u32 = 28;
const TEXT_LINE: u32 = 19;

/// Where the map lies in a rendered picture.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MapPixels {
    /// The world frame shown.
    pub frame: Frame,
    /// Pixel x of the frame's west and east edges (plotters' mapping).
    pub x_px: (f64, f64),
    /// Pixel y of the frame's south and north edges (plotters' mapping).
    pub y_px: (f64, f64),
}

impl MapPixels {
    /// The pixel where a world point is drawn.
    pub fn pixel_of(&self, p: Point2) -> (i32, i32) {
        let f = &self.frame;
        let x = self.x_px.0 + (p.x - f.x0) / f.width() * (self.x_px.1 - self.x_px.0);
        let y = self.y_px.0 + (p.y - f.y0) / f.height() * (self.y_px.1 - self.y_px.0);
        (x.round() as i32, y.round() as i32)
    }
}

/// A rendered picture: RGB pixels, row 0 at the top.
pub struct Rendered {
    /// Width (px).
    pub width: u32,
    /// Height (px).
    pub height: u32,
    /// Row-major RGB bytes.
    pub rgb: Vec<u8>,
    /// Where the map lies.
    pub map: MapPixels,
    /// The legend's labels, in order.
    pub legend: Vec<String>,
}

impl TraverseScene<'_> {
    /// The frame the map shows: fitted to everything the run touched.
    pub fn frame(&self) -> Frame {
        let world = Frame::of_grid(self.terrain.dem.geometry());
        let t = self.trace;
        let poses = t.truth.iter().chain(&t.estimate).map(|p| Point2::new(p.x, p.y));
        let plans = t.plans.iter().flatten().copied();
        let hazards = self.report.hazard_events.iter().map(|h| Point2::new(h.x, h.y));
        let vtt = t.vtt.iter().flat_map(|v| std::iter::once(&v.target).chain(&v.estimates));
        let vtt = vtt.map(|p| Point2::new(p[0], p[1]));
        let tol = self.goal.tolerance.max(0.0);
        let goal_box =
            [-1.0, 1.0].map(|s| Point2::new(self.goal.position.x + s * tol, self.goal.position.y + s * tol));
        let points = [self.start]
            .into_iter()
            .chain(goal_box)
            .chain(self.goal.waypoints.iter().copied())
            .chain(poses)
            .chain(plans)
            .chain(hazards)
            .chain(vtt);
        Frame::fit(points, &world)
    }
}

/// Map pixels per metre of a picture framed by `frame` (the map's width over the frame's).
fn map_px_per_m(frame: &Frame) -> f64 {
    frame.pixels(MAP_PX).0 as f64 / frame.width()
}

/// Renders the picture into RGB pixels.
pub fn render(scene: &TraverseScene<'_>) -> std::io::Result<Rendered> {
    font::ensure();
    let frame = scene.frame();
    let (mw, mh) = frame.pixels(MAP_PX);
    let cap = caption::caption(scene.report);
    let body_font = FontDesc::new(font::family(), 15.0, FontStyle::Normal);
    let width = Y_LABELS + mw + GAP + SIDE;
    let reason = caption::wrap(&format!("{}: {}", cap.outcome, cap.reason), &body_font, width - 24, 4);
    let header = 10 + TITLE_LINE + TEXT_LINE * (reason.len() as u32 + 1) + 10;
    let entries = legend::entries(scene, &frame);
    let world = Frame::of_grid(scene.terrain.dem.geometry());
    let inset = frame.wants_inset(&world);
    let side_h = side::height(entries.len(), inset);
    let height = header + (mh + X_LABELS).max(side_h);
    let mut rgb = vec![255u8; (width * height * 3) as usize];
    let map = {
        let root = BitMapBackend::with_buffer(&mut rgb, (width, height)).into_drawing_area();
        let map = draw(&root, scene, &cap, &reason, header, frame, &entries, inset)
            .map_err(std::io::Error::other)?;
        root.present().map_err(std::io::Error::other)?;
        map
    };
    let legend = entries.into_iter().map(|e| e.label).collect();
    Ok(Rendered { width, height, rgb, map, legend })
}

#[allow(clippy::too_many_arguments)]
fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    scene: &TraverseScene<'_>,
    cap: &caption::Caption,
    reason: &[String],
    header: u32,
    frame: Frame,
    entries: &[legend::Entry],
    inset: bool,
) -> Result<MapPixels, DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let (head, body) = root.split_vertically(header);
    let title = FontDesc::new(font::family(), 21.0, FontStyle::Bold).color(&BLACK);
    head.draw(&Text::new(cap.title.clone(), (12, 10), title))?;
    let mut y = 10 + TITLE_LINE as i32;
    for (i, line) in reason.iter().enumerate() {
        let colour = if i == 0 { cap.colour } else { RGBColor(30, 30, 30) };
        let style =
            FontDesc::new(font::family(), 15.0, if i == 0 { FontStyle::Bold } else { FontStyle::Normal });
        head.draw(&Text::new(line.clone(), (12, y), style.color(&colour)))?;
        y += TEXT_LINE as i32;
    }
    let figures = FontDesc::new(font::family(), 15.0, FontStyle::Normal).color(&RGBColor(60, 60, 60));
    head.draw(&Text::new(cap.figures.clone(), (12, y), figures))?;
    let (mw, mh) = frame.pixels(MAP_PX);
    let (map_area, side_area) = body.split_horizontally(Y_LABELS + mw + GAP);
    let (map_area, _) = map_area.split_vertically(mh + X_LABELS);
    let range = raster::elevation_range(&scene.terrain.dem, &frame);
    let map = map::draw(&map_area, scene, frame, range, (mw, mh), (Y_LABELS, X_LABELS, GAP))?;
    side::draw(&side_area, scene, frame, range, entries, inset)?;
    Ok(map)
}

/// Encodes RGB pixels as a PNG (best compression: pictures go into docs and galleries).
pub fn encode_png(width: u32, height: u32, rgb: &[u8]) -> std::io::Result<Vec<u8>> {
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_compression(png::Compression::High);
    let mut writer = encoder.write_header().map_err(std::io::Error::other)?;
    writer.write_image_data(rgb).map_err(std::io::Error::other)?;
    writer.finish().map_err(std::io::Error::other)?;
    Ok(out)
}

/// Encodes RGB pixels as a 256-colour PNG: the marks' solid colours ([`legend::SOLID`], the
/// outcome colours, black and white) exactly, the rest (shaded terrain, blends, text edges) by a
/// NeuQuant palette, the same for the same pixels. A shaded terrain in full colour makes PNGs
/// several times larger.
pub fn encode_png_256(width: u32, height: u32, rgb: &[u8]) -> std::io::Result<Vec<u8>> {
    let outcomes = ["reached", "help_requested", "timeout", "unreachable", "aborted", ""];
    let fixed: Vec<[u8; 3]> = legend::SOLID
        .iter()
        .copied()
        .chain(outcomes.iter().map(|o| caption::outcome_words(o).1))
        .chain([BLACK, WHITE])
        .map(|c| [c.0, c.1, c.2])
        .fold(Vec::new(), |mut v, c| {
            if !v.contains(&c) {
                v.push(c);
            }
            v
        });
    let index_of_fixed: std::collections::HashMap<[u8; 3], u8> =
        fixed.iter().enumerate().map(|(i, c)| (*c, i as u8)).collect();
    let rgba: Vec<u8> = rgb.chunks_exact(3).flat_map(|p| [p[0], p[1], p[2], 255]).collect();
    let quant = color_quant::NeuQuant::new(10, 256 - fixed.len(), &rgba);
    let indices: Vec<u8> = rgba
        .chunks_exact(4)
        .map(|p| match index_of_fixed.get(&[p[0], p[1], p[2]]) {
            Some(&i) => i,
            None => (fixed.len() + quant.index_of(p)) as u8,
        })
        .collect();
    let mut palette: Vec<u8> = fixed.concat();
    palette.extend(quant.color_map_rgb());
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, width, height);
    encoder.set_color(png::ColorType::Indexed);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_palette(palette);
    encoder.set_compression(png::Compression::High);
    let mut writer = encoder.write_header().map_err(std::io::Error::other)?;
    writer.write_image_data(&indices).map_err(std::io::Error::other)?;
    writer.finish().map_err(std::io::Error::other)?;
    Ok(out)
}

/// The traverse picture as PNG bytes.
pub fn traverse_png(scene: &TraverseScene<'_>) -> std::io::Result<Vec<u8>> {
    let r = render(scene)?;
    encode_png_256(r.width, r.height, &r.rgb)
}

#[cfg(test)]
mod tests;
