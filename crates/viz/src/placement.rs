//! The picture of one instrument placement (`placement-<task>.png`): a side view and a top view
//! of the arm's work volume in the body frame at the placement (x forward, y left, z up).
//!
//! Side view (left panel, x to the right, z up): the slice within 6 cm of the target's y:
//! unknown octree cells grey, occupied cells brown, the sensed points in that slice white, the
//! arm drawn at its via-points and at contact (orange links), the instrument tip's path over the
//! whole motion (yellow), the target (green cross) and its sensed normal (green line, 10 cm).
//! Top view (right panel, x up, y to the left): the sensed points coloured by height (dark low,
//! light high), unknown cells lying above the target's height (grey: space no camera verified
//! where the arm could pass), the tip's path, the arm at contact, the target and its normal. A
//! refusal draws the model and the commanded point (red cross) without any arm motion.

use crate::canvas::{Canvas, Rgb};
use rovernav_executive::arm_server::PlacementMsg;
use rovernav_manipulation::Arm;
use rovernav_manipulation::geometry::V3;

/// Pixels per metre.
const SCALE: f64 = 400.0;
/// Side of each panel (px).
const PANEL: usize = 600;
/// Half-width of the side view's slice (m).
const SLICE: f64 = 0.06;

/// One view: which body axes run right and up, and the window's lower corner in them (m).
struct View {
    right: usize,
    up: usize,
    origin: (f64, f64),
    sign_right: f64,
    offset_px: f64,
}

impl View {
    fn px(&self, p: [f64; 3]) -> (f64, f64) {
        let r = self.sign_right * (p[self.right] - self.origin.0);
        let u = p[self.up] - self.origin.1;
        (self.offset_px + r * SCALE, PANEL as f64 - u * SCALE)
    }
}

fn arm_links(arm: &Arm, q: &[f64; 5]) -> [[f64; 3]; 5] {
    let f = arm.forward(q);
    [f.shoulder, f.elbow, f.wrist, f.turret, f.tip].map(Into::into)
}

/// Draws the placement.
pub fn render_placement(msg: &PlacementMsg, arm: &Arm) -> Canvas {
    let mut c = Canvas::new(2 * PANEL, PANEL);
    c.fill_rect(0.0, 0.0, (2 * PANEL) as f64, PANEL as f64, Rgb(20, 22, 28), 1.0);
    let o = msg.octree.min;
    let size = msg.octree.size.max(0.5);
    let side = View { right: 0, up: 2, origin: (o[0] - 0.1, o[2]), sign_right: 1.0, offset_px: 0.0 };
    // Top view: x up, y to the left (so the picture's left is the rover's left).
    let top = View {
        right: 1,
        up: 0,
        origin: (o[1] + size, o[0] - 0.1),
        sign_right: -1.0,
        offset_px: PANEL as f64,
    };
    let focus = msg.target.map_or(msg.commanded, |t| t.point);
    let grey = Rgb(95, 95, 105);
    // Side view: the slice's cells.
    for (cells, colour, alpha) in
        [(&msg.octree.unknown, grey, 0.55), (&msg.octree.occupied, Rgb(150, 100, 60), 0.9)]
    {
        for cell in cells {
            let h = 0.5 * cell[3] as f64;
            if (cell[1] as f64 - focus[1]).abs() > h + SLICE {
                continue;
            }
            let (x, y) = side.px([cell[0] as f64 - h, 0.0, cell[2] as f64 + h]);
            let s = cell[3] as f64 * SCALE;
            c.fill_rect(x, y, s, s, colour, alpha);
        }
    }
    for p in &msg.points {
        if (p[1] as f64 - focus[1]).abs() <= SLICE {
            let (x, y) = side.px([p[0] as f64, 0.0, p[2] as f64]);
            c.fill_rect(x, y, 1.5, 1.5, Rgb(235, 235, 235), 0.9);
        }
    }
    // Top view: the sensed surface by height, unknown space above the target's height.
    let (lo, hi) = (focus[2] - 0.15, focus[2] + 0.15);
    for p in &msg.points {
        let t = ((p[2] as f64 - lo) / (hi - lo)).clamp(0.0, 1.0);
        let v = (40.0 + 200.0 * t) as u8;
        let (x, y) = top.px([p[0] as f64, p[1] as f64, 0.0]);
        c.fill_rect(x, y, 2.0, 2.0, Rgb(v, v, (v as f64 * 0.8) as u8), 1.0);
    }
    for cell in &msg.octree.unknown {
        let h = 0.5 * cell[3] as f64;
        if (cell[2] as f64) - h > focus[2] + 0.02 && (cell[2] as f64) - h < 0.6 {
            let (x, y) = top.px([cell[0] as f64 + h, cell[1] as f64 + h, 0.0]);
            let s = cell[3] as f64 * SCALE;
            c.fill_rect(x, y, s, s, grey, 0.25);
        }
    }
    // The arm: links at the via-points and at contact, the tip's path.
    let orange = Rgb(255, 150, 40);
    for view in [&side, &top] {
        let poses = msg.via.iter().chain(msg.approach.last());
        for q in poses {
            let pts: Vec<(f64, f64)> = arm_links(arm, q).iter().map(|p| view.px(*p)).collect();
            c.polyline(&pts, false, orange, 2.0);
        }
        let path: Vec<(f64, f64)> =
            msg.joints.iter().map(|j| view.px(arm.forward(&j.q).tip.into())).collect();
        c.polyline(&path, false, Rgb(250, 220, 60), 1.5);
        let commanded = view.px(msg.commanded);
        match msg.target {
            Some(t) => {
                let (x, y) = view.px(t.point);
                c.cross(x, y, 6.0, Rgb(60, 220, 90), 2.0);
                let n = V3::from(t.point) + V3::from(t.normal) * 0.1;
                c.line((x, y), view.px(n.into()), Rgb(60, 220, 90), 2.0);
            }
            None if commanded.0.is_finite() && commanded.1.is_finite() => {
                c.cross(commanded.0, commanded.1, 8.0, Rgb(230, 50, 50), 3.0)
            }
            None => {}
        }
    }
    // The rover's front face and a 10 cm scale bar in each panel.
    for view in [&side, &top] {
        let (x0, y0) = view.px([0.5, 0.0, 0.0]);
        let (x1, y1) = view.px([0.6, 0.0, 0.0]);
        c.line((x0, y0), (x1, y1), Rgb(200, 200, 255), 3.0);
    }
    c.line((10.0, PANEL as f64 - 10.0), (10.0 + 0.1 * SCALE, PANEL as f64 - 10.0), Rgb(255, 255, 255), 2.0);
    c.text(12.0, PANEL as f64 - 24.0, "0.1m", Rgb(255, 255, 255), 2);
    c.line((PANEL as f64, 0.0), (PANEL as f64, PANEL as f64), Rgb(255, 255, 255), 1.0);
    c
}

/// The placement picture as PNG bytes.
pub fn placement_png(msg: &PlacementMsg, arm: &Arm) -> std::io::Result<Vec<u8>> {
    let mut bytes = Vec::new();
    render_placement(msg, arm).write_png(&mut bytes)?;
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rovernav_core::{Pose3, RoverConfig};
    use rovernav_executive::arm_server::placement::{OctreeMsg, TargetMsg};

    fn message(target: Option<TargetMsg>) -> PlacementMsg {
        PlacementMsg {
            task: 3,
            t: 0.0,
            outcome: if target.is_some() { "placed" } else { "refused" }.into(),
            reason: None,
            examined: 1,
            pose: Pose3::default(),
            commanded: [1.0, -0.12, 0.05],
            target,
            axis: None,
            contact_angle_deg: None,
            via: Vec::new(),
            approach: Vec::new(),
            joints: Vec::new(),
            octree: OctreeMsg {
                min: [0.36, -0.64, -0.40],
                size: 1.28,
                leaf: 0.02,
                occupied: vec![[1.2, -0.12, 0.0, 0.04]],
                unknown: vec![[0.8, -0.12, 0.3, 0.08]],
            },
            points: Vec::new(),
            sensed: Default::default(),
        }
    }

    /// Where the side view draws a body-frame (x, z).
    fn side(x: f64, z: f64) -> (usize, usize) {
        ((((x - 0.26) * SCALE).round()) as usize, (PANEL as f64 - (z + 0.40) * SCALE).round() as usize)
    }

    #[test]
    fn the_side_view_shows_cells_where_they_are_and_the_target_or_the_refused_point() {
        let arm = Arm::new(&RoverConfig::default());
        let target = TargetMsg { point: [1.0, -0.12, 0.05], normal: [0.0, 0.0, 1.0], roughness: 0.0 };
        let c = render_placement(&message(Some(target)), &arm);
        let bg = Rgb(20, 22, 28);
        let (ux, uy) = side(0.8, 0.3);
        assert_ne!(c.get(ux, uy), bg, "unknown cell drawn");
        let (ox, oy) = side(1.2, 0.0);
        let o = c.get(ox, oy);
        assert!(o.0 > o.2, "occupied cell brown: {o:?}");
        let (tx, ty) = side(1.0, 0.05);
        assert_eq!(c.get(tx, ty), Rgb(60, 220, 90), "target cross");
        // The normal rises 10 cm straight up from the target.
        let (nx, ny) = side(1.0, 0.12);
        assert_eq!(c.get(nx, ny), Rgb(60, 220, 90), "normal");
        let refused = render_placement(&message(None), &arm);
        assert_eq!(refused.get(tx, ty), Rgb(230, 50, 50), "refused: the commanded point in red");
        assert_eq!(refused.get(nx, ny), bg, "no normal drawn");
    }
}
