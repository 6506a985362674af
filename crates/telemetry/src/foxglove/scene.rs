//! `foxglove.SceneUpdate`: the 3D panel's entities (rover bodies, plans, wedges, the navigator's
//! drawings, rocks), each a set of primitives under an id that a later update replaces.

use super::{PoseMsg, Quaternion, TimeMsg, Vector3};
use rovernav_core::{Overlay, OverlayKind, Point2, PointCloud, RoverConfig};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// `foxglove.Color` (components 0..1).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct ColorMsg {
    /// Red.
    pub r: f64,
    /// Green.
    pub g: f64,
    /// Blue.
    pub b: f64,
    /// Opacity.
    pub a: f64,
}

/// The colours of the scene, as the traverse picture draws the same things.
pub mod colors {
    use super::ColorMsg;
    /// The estimated rover body.
    pub const ROVER: ColorMsg = ColorMsg { r: 0.2, g: 0.5, b: 1.0, a: 0.8 };
    /// The true rover body.
    pub const TRUTH: ColorMsg = ColorMsg { r: 1.0, g: 1.0, b: 1.0, a: 0.5 };
    /// Planned paths.
    pub const PLAN: ColorMsg = ColorMsg { r: 0.1, g: 0.9, b: 0.2, a: 1.0 };
    /// C-obstacles and other obstacles.
    pub const C_OBSTACLE: ColorMsg = ColorMsg { r: 1.0, g: 0.3, b: 0.1, a: 1.0 };
    /// Sensed wedges.
    pub const WEDGE: ColorMsg = ColorMsg { r: 1.0, g: 0.85, b: 0.1, a: 0.8 };
    /// Other drawings (arcs, subgoals).
    pub const OTHER: ColorMsg = ColorMsg { r: 0.8, g: 0.3, b: 1.0, a: 1.0 };
    /// The goal.
    pub const GOAL: ColorMsg = ColorMsg { r: 0.1, g: 1.0, b: 1.0, a: 0.7 };
    /// Rocks (truth).
    pub const ROCK: ColorMsg = ColorMsg { r: 0.55, g: 0.4, b: 0.3, a: 1.0 };
    /// Hazard contacts (truth).
    pub const HAZARD: ColorMsg = ColorMsg { r: 1.0, g: 0.0, b: 0.0, a: 0.9 };
}

/// `foxglove.Point3`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct Point3 {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
}

/// A coordinate rounded to the millimetre: the scene is for display, and shorter numbers keep
/// the log small (the exact values are on the rovernav topics).
pub fn mm(v: f64) -> f64 {
    if v.is_finite() { (v * 1000.0).round() / 1000.0 } else { 0.0 }
}

/// `duration`: a lifetime (zero: until replaced).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
pub struct DurationMsg {
    /// Seconds.
    pub sec: i32,
    /// Nanoseconds.
    pub nsec: u32,
}

/// `foxglove.LinePrimitive`: `type` 0 line strip, 1 line loop, 2 line list.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct LinePrimitive {
    /// 0 strip, 1 loop, 2 list.
    #[serde(rename = "type")]
    pub kind: u8,
    /// Origin of the points.
    pub pose: PoseMsg,
    /// Width (m, or pixels when `scale_invariant`).
    pub thickness: f64,
    /// Whether `thickness` is in pixels.
    pub scale_invariant: bool,
    /// The points.
    pub points: Vec<Point3>,
    /// Colour of the whole line.
    pub color: ColorMsg,
    /// Per-point colours (none).
    pub colors: Vec<ColorMsg>,
    /// Point indices (none: in order).
    pub indices: Vec<u32>,
}

/// `foxglove.CubePrimitive`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct CubePrimitive {
    /// Centre and orientation.
    pub pose: PoseMsg,
    /// Size along each axis.
    pub size: Vector3,
    /// Colour.
    pub color: ColorMsg,
}

/// `foxglove.CylinderPrimitive` (axis along z).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct CylinderPrimitive {
    /// Centre and orientation.
    pub pose: PoseMsg,
    /// Bounding box size.
    pub size: Vector3,
    /// Bottom face scale (1: a cylinder).
    pub bottom_scale: f64,
    /// Top face scale.
    pub top_scale: f64,
    /// Colour.
    pub color: ColorMsg,
}

/// `foxglove.TextPrimitive`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct TextPrimitive {
    /// Where.
    pub pose: PoseMsg,
    /// Whether the text faces the camera.
    pub billboard: bool,
    /// Font size.
    pub font_size: f64,
    /// Whether `font_size` is in pixels.
    pub scale_invariant: bool,
    /// Colour.
    pub color: ColorMsg,
    /// The text.
    pub text: String,
}

/// `foxglove.KeyValuePair`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct KeyValuePair {
    /// Key.
    pub key: String,
    /// Value.
    pub value: String,
}

/// `foxglove.SceneEntity`: primitives sharing a frame, replaced by the next entity of the same
/// `id` on the topic. Every primitive list is present (empty when unused), as Foxglove's own
/// writers send them.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct SceneEntity {
    /// Time.
    pub timestamp: TimeMsg,
    /// Frame of the primitives.
    pub frame_id: String,
    /// Identifier (a later entity with the same id replaces this one).
    pub id: String,
    /// Lifetime (zero: until replaced or deleted).
    pub lifetime: DurationMsg,
    /// Whether the entity moves with its frame (true) or stays where it was drawn.
    pub frame_locked: bool,
    /// Key-value metadata.
    pub metadata: Vec<KeyValuePair>,
    /// Arrows (none).
    pub arrows: Vec<serde_json::Value>,
    /// Cubes.
    pub cubes: Vec<CubePrimitive>,
    /// Spheres (none).
    pub spheres: Vec<serde_json::Value>,
    /// Cylinders.
    pub cylinders: Vec<CylinderPrimitive>,
    /// Lines.
    pub lines: Vec<LinePrimitive>,
    /// Triangles (none).
    pub triangles: Vec<serde_json::Value>,
    /// Texts.
    pub texts: Vec<TextPrimitive>,
    /// Models (none).
    pub models: Vec<serde_json::Value>,
}

/// `foxglove.SceneEntityDeletion`: `type` 0 deletes the entity `id`, 1 deletes all.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct SceneEntityDeletion {
    /// Time: entities older than this are deleted.
    pub timestamp: TimeMsg,
    /// 0 matching id, 1 all.
    #[serde(rename = "type")]
    pub kind: u8,
    /// The id (for type 0).
    pub id: String,
}

/// `foxglove.SceneUpdate`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct SceneUpdateMsg {
    /// Entities to delete first.
    pub deletions: Vec<SceneEntityDeletion>,
    /// Entities to add or replace.
    pub entities: Vec<SceneEntity>,
}

impl SceneEntity {
    /// An empty entity `id` in `frame_id` at simulated time `t`.
    pub fn new(t: f64, frame_id: &str, id: &str) -> Self {
        Self {
            timestamp: TimeMsg::of_seconds(t),
            frame_id: frame_id.into(),
            id: id.into(),
            ..Self::default()
        }
    }
}

impl LinePrimitive {
    /// A line through planar points at height `z`, closed into a loop or not.
    pub fn through(points: &[Point2], z: f64, closed: bool, thickness: f64, color: ColorMsg) -> Self {
        Self {
            kind: if closed { 1 } else { 0 },
            pose: PoseMsg::default(),
            thickness,
            scale_invariant: false,
            points: points.iter().map(|p| Point3 { x: mm(p.x), y: mm(p.y), z: mm(z) }).collect(),
            color,
            colors: Vec::new(),
            indices: Vec::new(),
        }
    }
}

/// The rover's body as a box in its own frame (`frame_locked`, so it moves with the frame).
pub fn rover_body(t: f64, frame_id: &str, rover: &RoverConfig, color: ColorMsg) -> SceneEntity {
    let height = (rover.mast_height * 0.4).clamp(0.1, 1.0);
    let cube = CubePrimitive {
        pose: PoseMsg::at(0.0, 0.0, rover.clearance + height / 2.0),
        size: Vector3 { x: rover.length, y: rover.width, z: height },
        color,
    };
    SceneEntity { frame_locked: true, cubes: vec![cube], ..SceneEntity::new(t, frame_id, "body") }
}

/// The colour and id of an overlay kind.
fn overlay_style(kind: OverlayKind) -> (ColorMsg, &'static str) {
    match kind {
        OverlayKind::Plan => (colors::PLAN, "overlays/plan"),
        OverlayKind::CObstacle => (colors::C_OBSTACLE, "overlays/c_obstacle"),
        OverlayKind::Wedge => (colors::WEDGE, "overlays/wedge"),
        OverlayKind::Other => (colors::OTHER, "overlays/other"),
    }
}

/// The navigator's drawings as one entity per kind (in `map`, at height `z`); every kind is
/// present, so a kind whose drawings vanished is replaced by an empty entity.
pub fn overlay_entities(t: f64, frame_id: &str, overlays: &[Overlay], z: f64) -> Vec<SceneEntity> {
    let kinds = [OverlayKind::Plan, OverlayKind::CObstacle, OverlayKind::Wedge, OverlayKind::Other];
    kinds
        .iter()
        .map(|&kind| {
            let (color, id) = overlay_style(kind);
            let lines = overlays
                .iter()
                .filter_map(|o| match o {
                    Overlay::Polygon(p, k) if *k == kind => {
                        Some(LinePrimitive::through(p, z, true, 0.04, color))
                    }
                    Overlay::Polyline(p, k) if *k == kind => {
                        Some(LinePrimitive::through(p, z, false, 0.04, color))
                    }
                    _ => None,
                })
                .collect();
            SceneEntity { lines, ..SceneEntity::new(t, frame_id, id) }
        })
        .collect()
}

/// The wedges of a frame's range data, in the rover frame where they were taken (not frame
/// locked: they stay where the rover looked).
pub fn wedge_entity(t: f64, frame_id: &str, clouds: &[PointCloud]) -> SceneEntity {
    let lines = clouds
        .iter()
        .map(|c| {
            let w = &c.wedge;
            let (ox, oy) = (c.origin[0], c.origin[1]);
            let steps = 12;
            let arc = |r: f64| -> Vec<Point2> {
                (0..=steps)
                    .map(|i| {
                        let a =
                            w.bearing - w.half_angle + 2.0 * w.half_angle * f64::from(i) / f64::from(steps);
                        Point2::new(ox + r * a.cos(), oy + r * a.sin())
                    })
                    .collect()
            };
            let mut outline = arc(w.max_range.min(50.0));
            outline.extend(arc(w.min_range.max(0.0)).into_iter().rev());
            LinePrimitive::through(&outline, 0.05, true, 0.03, colors::WEDGE)
        })
        .collect();
    SceneEntity { lines, ..SceneEntity::new(t, frame_id, "wedges") }
}

/// The goal: a ring of its tolerance and a label.
pub fn goal_entity(t: f64, frame_id: &str, goal: Point2, tolerance: f64, z: f64) -> SceneEntity {
    let r = tolerance.max(0.1);
    let ring: Vec<Point2> = (0..32)
        .map(|i| {
            let a = f64::from(i) * std::f64::consts::TAU / 32.0;
            Point2::new(goal.x + r * a.cos(), goal.y + r * a.sin())
        })
        .collect();
    let text = TextPrimitive {
        pose: PoseMsg::at(goal.x, goal.y, z + 0.5),
        billboard: true,
        font_size: 14.0,
        scale_invariant: true,
        color: colors::GOAL,
        text: "goal".into(),
    };
    SceneEntity {
        lines: vec![LinePrimitive::through(&ring, z, true, 0.05, colors::GOAL)],
        texts: vec![text],
        ..SceneEntity::new(t, frame_id, "goal")
    }
}

/// Rocks as cylinders standing on the ground (`ground(x, y)`), truth.
pub fn rock_entity(
    t: f64,
    frame_id: &str,
    rocks: &[rovernav_terrain::Rock],
    ground: impl Fn(f64, f64) -> f64,
) -> SceneEntity {
    let cylinders = rocks
        .iter()
        .map(|r| CylinderPrimitive {
            pose: PoseMsg {
                position: Vector3 { x: mm(r.x), y: mm(r.y), z: mm(ground(r.x, r.y) + r.height / 2.0) },
                orientation: Quaternion::default(),
            },
            size: Vector3 { x: mm(r.diameter), y: mm(r.diameter), z: mm(r.height) },
            bottom_scale: 1.0,
            top_scale: 0.6,
            color: colors::ROCK,
        })
        .collect();
    SceneEntity { cylinders, ..SceneEntity::new(t, frame_id, "rocks") }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rovernav_bus::schema::{check, titled_schema_of};
    use rovernav_core::Wedge;

    #[test]
    fn overlays_become_one_entity_per_kind_with_their_points() {
        let square = vec![Point2::new(0.0, 0.0), Point2::new(1.0, 0.0), Point2::new(1.0, 1.0)];
        let overlays = vec![
            Overlay::Polygon(square.clone(), OverlayKind::CObstacle),
            Overlay::Polyline(square.clone(), OverlayKind::Plan),
            Overlay::Polygon(square.clone(), OverlayKind::CObstacle),
        ];
        let entities = overlay_entities(2.0, "map", &overlays, 0.5);
        assert_eq!(entities.len(), 4, "every kind, so a vanished kind is cleared");
        let c = entities.iter().find(|e| e.id == "overlays/c_obstacle").unwrap();
        assert_eq!(c.lines.len(), 2);
        assert_eq!(c.lines[0].kind, 1, "a polygon is a closed loop");
        assert_eq!(c.lines[0].points[2], Point3 { x: 1.0, y: 1.0, z: 0.5 });
        let plan = entities.iter().find(|e| e.id == "overlays/plan").unwrap();
        assert_eq!(plan.lines[0].kind, 0, "a polyline stays open");
        assert!(entities.iter().find(|e| e.id == "overlays/wedge").unwrap().lines.is_empty());
        let update = SceneUpdateMsg { deletions: Vec::new(), entities };
        let schema = titled_schema_of::<SceneUpdateMsg>("foxglove.SceneUpdate");
        check(&schema, &serde_json::to_value(&update).unwrap()).unwrap();
    }

    #[test]
    fn a_wedge_outline_spans_its_bearing_and_ranges() {
        let cloud = PointCloud {
            origin: [0.5, 0.0, 1.0],
            wedge: Wedge { bearing: 0.0, half_angle: 0.5, min_range: 1.0, max_range: 4.0 },
            camera: rovernav_core::CameraKind::Mast,
            points: Vec::new(),
        };
        let e = wedge_entity(1.0, "rover", &[cloud]);
        let pts = &e.lines[0].points;
        let far = pts.iter().map(|p| (p.x - 0.5).hypot(p.y)).fold(0.0, f64::max);
        let near = pts.iter().map(|p| (p.x - 0.5).hypot(p.y)).fold(f64::INFINITY, f64::min);
        // Points are rounded to the millimetre.
        assert!((far - 4.0).abs() < 2e-3 && (near - 1.0).abs() < 2e-3, "{near} {far}");
        let max_bearing = pts.iter().map(|p| p.y.atan2(p.x - 0.5).abs()).fold(0.0, f64::max);
        assert!((max_bearing - 0.5).abs() < 2e-3, "{max_bearing}");
    }
}
