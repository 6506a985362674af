//! Tests of the traverse picture against what it must show: marks where the axes put them, a
//! legend naming each overlay kind present, the same bytes for the same run.

use super::legend::{HAZARD_ROCK, VTT_ESTIMATE, VTT_TARGET, overlay_colour};
use super::*;
use rovernav_core::{Grid2, GridGeometry, Overlay, OverlayKind, Pose3};
use rovernav_executive::HazardEvent;
use rovernav_executive::deliberative::VttTrace;
use rovernav_terrain::{Dem, Rock};

struct Fixture {
    terrain: Terrain,
    rover: RoverConfig,
    goal: Goal,
    trace: Trace,
    report: Report,
}

fn pose(x: f64, y: f64) -> Pose3 {
    Pose3 { x, y, yaw: 0.7, ..Pose3::default() }
}

/// A flat 20 m yard with one rock taller than the clearance at (14, 6), a run from (3, 3)
/// towards (16, 16) that stopped at (10, 10) and asked for help.
fn fixture(overlays: Vec<Overlay>) -> Fixture {
    let g = GridGeometry { cols: 200, rows: 200, resolution: 0.1, origin_x: 0.0, origin_y: 0.0 };
    let terrain = Terrain {
        dem: Dem::from_grid(Grid2::filled(g, 1.0f32)),
        rocks: vec![Rock { x: 14.0, y: 6.0, diameter: 0.6, height: 0.4 }],
    };
    let truth: Vec<Pose3> = (0..=14).map(|k| pose(3.0 + 0.5 * k as f64, 3.0 + 0.5 * k as f64)).collect();
    let estimate: Vec<Pose3> = truth.iter().map(|p| pose(p.x + 0.02 * p.x, p.y)).collect();
    let report = Report {
        outcome: "help_requested".into(),
        message: "no way around the rocks".into(),
        goal_error_m: Point2::new(10.0, 10.0).dist(Point2::new(16.0, 16.0)),
        hazard_events: vec![HazardEvent { x: 8.0, y: 8.0, cycle: 5, cause: "step".into() }],
        ..Report::default()
    };
    Fixture {
        terrain,
        rover: RoverConfig::default(),
        goal: Goal { position: Point2::new(16.0, 16.0), tolerance: 0.5, waypoints: vec![], keep_out: vec![] },
        trace: Trace {
            plans: vec![vec![Point2::new(3.0, 3.0), Point2::new(16.0, 16.0)]],
            overlays,
            truth,
            estimate,
            ..Trace::default()
        },
        report,
    }
}

fn scene(f: &Fixture) -> TraverseScene<'_> {
    TraverseScene {
        terrain: &f.terrain,
        rover: &f.rover,
        start: Point2::new(3.0, 3.0),
        goal: &f.goal,
        trace: &f.trace,
        report: &f.report,
    }
}

fn rgb_at(r: &Rendered, (x, y): (i32, i32)) -> [u8; 3] {
    let i = (y as usize * r.width as usize + x as usize) * 3;
    [r.rgb[i], r.rgb[i + 1], r.rgb[i + 2]]
}

fn colour(c: plotters::style::RGBColor) -> [u8; 3] {
    [c.0, c.1, c.2]
}

#[test]
fn a_rock_is_drawn_where_the_axes_put_its_position() {
    let f = fixture(vec![]);
    let r = render(&scene(&f)).unwrap();
    let rock = Point2::new(14.0, 6.0);
    assert_eq!(rgb_at(&r, r.map.pixel_of(rock)), colour(HAZARD_ROCK));
    // Open ground 1.5 m away is terrain, not rock.
    assert_ne!(rgb_at(&r, r.map.pixel_of(Point2::new(15.5, 6.0))), colour(HAZARD_ROCK));
    // The same scale on both axes (pixel y grows southwards).
    let m = &r.map;
    let sx = (m.x_px.1 - m.x_px.0) / m.frame.width();
    let sy = (m.y_px.0 - m.y_px.1) / m.frame.height();
    assert!((sx / sy - 1.0).abs() < 0.01, "{sx} {sy}");
}

#[test]
fn a_c_obstacle_is_drawn_in_its_colour_on_its_edge() {
    let square = vec![
        Point2::new(12.0, 12.0),
        Point2::new(13.0, 12.0),
        Point2::new(13.0, 13.0),
        Point2::new(12.0, 13.0),
    ];
    let f = fixture(vec![Overlay::Polygon(square, OverlayKind::CObstacle)]);
    let r = render(&scene(&f)).unwrap();
    // The middle of its south edge.
    assert_eq!(
        rgb_at(&r, r.map.pixel_of(Point2::new(12.5, 12.0))),
        colour(overlay_colour(OverlayKind::CObstacle))
    );
}

#[test]
fn the_legend_names_each_overlay_kind_present_and_no_other() {
    let cobstacle = Overlay::Polygon(
        vec![Point2::new(5.0, 5.0), Point2::new(6.0, 5.0), Point2::new(6.0, 6.0)],
        OverlayKind::CObstacle,
    );
    let wedge = Overlay::Polyline(vec![Point2::new(4.0, 4.0), Point2::new(6.0, 7.0)], OverlayKind::Wedge);
    let with = render(&scene(&fixture(vec![cobstacle, wedge]))).unwrap().legend;
    let without = render(&scene(&fixture(vec![]))).unwrap().legend;
    let has = |legend: &[String], words: &str| legend.iter().any(|l| l.contains(words));
    assert!(has(&with, "C-obstacle") && has(&with, "sensed wedge"), "{with:?}");
    assert!(!has(&with, "other navigator drawing"));
    assert!(!has(&without, "C-obstacle") && !has(&without, "sensed wedge"), "{without:?}");
    for words in [
        "rock taller than the belly clearance",
        "hazard contact",
        "driven path",
        "estimated end",
        "footprint",
    ] {
        assert!(has(&with, words), "{words}: {with:?}");
    }
    assert!(!has(&with, "keep-out") && !has(&with, "smaller rock"), "nothing absent is listed: {with:?}");
}

#[test]
fn the_same_run_draws_the_same_bytes() {
    let f = fixture(vec![]);
    let a = traverse_png(&scene(&f)).unwrap();
    let b = traverse_png(&scene(&f)).unwrap();
    assert!(a == b);
    // The 256-colour file still shows the rock in its colour where the axes put it.
    let mut decoder = png::Decoder::new(std::io::Cursor::new(a));
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let r = render(&scene(&f)).unwrap();
    assert_eq!((info.width, info.height), (r.width, r.height));
    let (x, y) = r.map.pixel_of(Point2::new(14.0, 6.0));
    let i = (y as usize * info.width as usize + x as usize) * 3;
    let rock = colour(HAZARD_ROCK);
    assert_eq!(buf[i..i + 3], rock, "the palette keeps mark colours exactly");
}

#[test]
fn the_frame_fits_the_route_not_the_whole_world() {
    let mut f = fixture(vec![]);
    // The same run in a world ten times larger.
    let g = GridGeometry { cols: 2000, rows: 2000, resolution: 0.1, origin_x: -90.0, origin_y: -90.0 };
    f.terrain.dem = Dem::from_grid(Grid2::filled(g, 1.0f32));
    let s = scene(&f);
    let frame = s.frame();
    assert!(frame.x0 <= 3.0 && frame.x1 >= 16.5 && frame.y0 <= 3.0 && frame.y1 >= 16.5, "{frame:?}");
    assert!(frame.width() < 30.0 && frame.height() < 30.0, "{frame:?}");
    assert!(frame.wants_inset(&frame::Frame::of_grid(&g)));
}

/// The legend lists a smaller rock exactly when the map draws one: at this 20 m frame (720 px
/// across a 20-odd metre frame, about 35 px per metre) a 2 cm pebble is under 1.5 px and left
/// out of both, a 0.3 m stone is drawn and listed.
#[test]
fn the_legend_lists_a_smaller_rock_only_when_the_map_draws_it() {
    let small = |diameter: f64| {
        let mut f = fixture(vec![]);
        f.terrain.rocks.push(Rock { x: 6.0, y: 12.0, diameter, height: 0.05 });
        f
    };
    let has_small =
        |f: &Fixture| render(&scene(f)).unwrap().legend.iter().any(|l| l.contains("smaller rock"));
    let pebble = small(0.02);
    let stone = small(0.3);
    let px_per_m = super::map_px_per_m(&scene(&stone).frame());
    assert!(0.5 * 0.02 * px_per_m < 1.5 && 0.5 * 0.3 * px_per_m >= 1.5, "{px_per_m} px/m");
    assert!(!has_small(&pebble), "a pebble the map leaves out is not listed");
    assert!(has_small(&stone), "a stone the map outlines is listed");
    // The stone's outline is in the picture, one radius east of its centre.
    let r = render(&scene(&stone)).unwrap();
    let (cx, cy) = r.map.pixel_of(Point2::new(6.0, 12.0));
    let radius = (0.15 * px_per_m).round() as i32;
    let near_outline = (-1..=1).any(|d| {
        rgb_at(&r, (cx + radius + d, cy)) != rgb_at(&render(&scene(&pebble)).unwrap(), (cx + radius + d, cy))
    });
    assert!(near_outline, "the outline changes the pixels at its radius");
}

/// A VTT target designated at (12, 5) and estimated along the way: its crosshair's centre, an
/// estimate's dot away from it, each where the axes put them in their own colour; the legend
/// lists "VTT target" and "target estimates" with them and neither without.
#[test]
fn a_vtt_target_and_its_estimates_are_drawn_where_the_axes_put_them_and_listed_only_then() {
    let mut f = fixture(vec![]);
    let plain = render(&scene(&f)).unwrap();
    f.trace.vtt = vec![VttTrace {
        task: 1,
        target: [12.0, 5.0, 0.1],
        estimates: vec![[10.0, 4.0, 0.1], [11.0, 4.6, 0.1], [11.9, 5.0, 0.1]],
    }];
    let r = render(&scene(&f)).unwrap();
    assert_eq!(rgb_at(&r, r.map.pixel_of(Point2::new(12.0, 5.0))), colour(VTT_TARGET));
    assert_eq!(rgb_at(&r, r.map.pixel_of(Point2::new(10.0, 4.0))), colour(VTT_ESTIMATE));
    // Open ground 1 m south of the target is neither.
    let ground = rgb_at(&r, r.map.pixel_of(Point2::new(12.0, 4.0)));
    assert!(ground != colour(VTT_TARGET) && ground != colour(VTT_ESTIMATE), "{ground:?}");
    assert_eq!(plain.map, r.map, "the marks lie inside the same frame");
    let has = |legend: &[String], words: &str| legend.iter().any(|l| l == words);
    assert!(has(&r.legend, "VTT target") && has(&r.legend, "target estimates"), "{:?}", r.legend);
    assert!(!has(&plain.legend, "VTT target") && !has(&plain.legend, "target estimates"));
    // The designation alone: the target is listed, no estimates.
    f.trace.vtt[0].estimates.clear();
    let alone = render(&scene(&f)).unwrap().legend;
    assert!(has(&alone, "VTT target") && !has(&alone, "target estimates"), "{alone:?}");
}
