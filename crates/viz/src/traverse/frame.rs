//! The part of the world a traverse picture shows: the box around everything the run touched
//! (start, goal, waypoints, driven and estimated paths, plans, hazards), with a margin, widened to
//! a near-square shape and kept inside the DEM; and whether the world is so much larger that an
//! overview inset is drawn.

use rovernav_core::{GridGeometry, Point2};

/// An axis-aligned box in the world's local frame (m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// West edge.
    pub x0: f64,
    /// East edge.
    pub x1: f64,
    /// South edge.
    pub y0: f64,
    /// North edge.
    pub y1: f64,
}

/// Least margin around the route (m).
const MIN_MARGIN_M: f64 = 3.0;
/// Margin as a fraction of the route box's longer side.
const MARGIN_FRACTION: f64 = 0.12;
/// Widest aspect ratio (longer side over shorter) before the shorter side is widened.
const MAX_ASPECT: f64 = 1.5;
/// An inset is drawn when the frame covers less than this fraction of the world's area.
const INSET_BELOW: f64 = 0.5;

impl Frame {
    /// The whole grid.
    pub fn of_grid(g: &GridGeometry) -> Self {
        Self { x0: g.origin_x, x1: g.origin_x + g.width_m(), y0: g.origin_y, y1: g.origin_y + g.height_m() }
    }

    /// East-west extent (m).
    pub fn width(&self) -> f64 {
        self.x1 - self.x0
    }

    /// North-south extent (m).
    pub fn height(&self) -> f64 {
        self.y1 - self.y0
    }

    /// Whether the frame covers so little of `world` that an overview inset helps.
    pub fn wants_inset(&self, world: &Frame) -> bool {
        self.width() * self.height() < INSET_BELOW * world.width() * world.height()
    }

    /// The frame fitted to `points` inside `world` (the whole world when no point is finite).
    pub fn fit(points: impl IntoIterator<Item = Point2>, world: &Frame) -> Self {
        let (mut x0, mut x1, mut y0, mut y1) =
            (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
        for p in points.into_iter().filter(|p| p.x.is_finite() && p.y.is_finite()) {
            (x0, x1, y0, y1) = (x0.min(p.x), x1.max(p.x), y0.min(p.y), y1.max(p.y));
        }
        if x0 > x1 {
            return *world;
        }
        let margin = (MARGIN_FRACTION * (x1 - x0).max(y1 - y0)).max(MIN_MARGIN_M);
        let (mut w, mut h) = (x1 - x0 + 2.0 * margin, y1 - y0 + 2.0 * margin);
        w = w.max(h / MAX_ASPECT);
        h = h.max(w / MAX_ASPECT);
        let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
        let (x0, x1) = fit_span(cx, w, world.x0, world.x1);
        let (y0, y1) = fit_span(cy, h, world.y0, world.y1);
        Self { x0, x1, y0, y1 }
    }

    /// Pixel size of a map of this frame whose longer side is `longest` px (same scale on both
    /// axes).
    pub fn pixels(&self, longest: u32) -> (u32, u32) {
        let scale = longest as f64 / self.width().max(self.height()).max(1e-9);
        (((self.width() * scale).round() as u32).max(1), ((self.height() * scale).round() as u32).max(1))
    }
}

/// A span of `len` centred on `centre`, shifted to lie within [lo, hi], or [lo, hi] itself when
/// it is longer.
fn fit_span(centre: f64, len: f64, lo: f64, hi: f64) -> (f64, f64) {
    if len >= hi - lo {
        return (lo, hi);
    }
    let a = (centre - len / 2.0).clamp(lo, hi - len);
    (a, a + len)
}

#[cfg(test)]
mod tests {
    use super::*;

    const WORLD: Frame = Frame { x0: 0.0, x1: 100.0, y0: 0.0, y1: 100.0 };

    #[test]
    fn frame_holds_every_point_with_a_margin() {
        let pts = [Point2::new(40.0, 50.0), Point2::new(60.0, 55.0), Point2::new(f64::NAN, 0.0)];
        let f = Frame::fit(pts, &WORLD);
        for p in &pts[..2] {
            assert!(p.x - f.x0 >= MIN_MARGIN_M && f.x1 - p.x >= MIN_MARGIN_M, "{f:?}");
            assert!(p.y - f.y0 >= MIN_MARGIN_M && f.y1 - p.y >= MIN_MARGIN_M, "{f:?}");
        }
        // 20 m x 5 m of route: the short side is widened to 1 / 1.5 of the long one.
        assert!((f.width() / f.height() - MAX_ASPECT).abs() < 1e-9, "{f:?}");
        assert!(f.wants_inset(&WORLD));
    }

    #[test]
    fn frame_stays_inside_the_world() {
        let f = Frame::fit([Point2::new(1.0, 1.0), Point2::new(10.0, 12.0)], &WORLD);
        assert!(f.x0 >= 0.0 && f.y0 >= 0.0, "{f:?}");
        assert!(f.x1 >= 10.0 + MIN_MARGIN_M && f.y1 >= 12.0 + MIN_MARGIN_M, "{f:?}");
        let big = Frame::fit([Point2::new(-50.0, -50.0), Point2::new(150.0, 150.0)], &WORLD);
        assert_eq!(big, WORLD);
        assert!(!big.wants_inset(&WORLD));
        assert_eq!(Frame::fit([], &WORLD), WORLD);
    }

    #[test]
    fn pixels_keep_the_scale_equal_on_both_axes() {
        let f = Frame { x0: 0.0, x1: 30.0, y0: 0.0, y1: 20.0 };
        assert_eq!(f.pixels(600), (600, 400));
    }
}
