//! Planar convex hulls by Andrew's monotone chain (paper 000 section 2: "the convex hulls of
//! distinct obstacles are computed").

use rovernav_core::Point2;

/// Convex hull of a point set, counter-clockwise, starting at the lowest-x (then lowest-y)
/// point, without collinear or repeated vertices. Non-finite points are ignored. Degenerate sets
/// give one point (all equal) or two (all on one line); an empty set gives none.
pub fn convex_hull(points: &[Point2]) -> Vec<Point2> {
    let mut pts: Vec<Point2> = points.iter().copied().filter(|p| p.is_finite()).collect();
    pts.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    pts.dedup();
    if pts.len() <= 2 {
        return pts;
    }
    // Turn of o->a->b: positive for a counter-clockwise (left) turn.
    let turn = |o: Point2, a: Point2, b: Point2| a.sub(o).cross(b.sub(o));
    let mut hull: Vec<Point2> = Vec::with_capacity(2 * pts.len());
    // Lower chain left to right, then upper chain right to left; pop non-left turns.
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &Point2>> =
            if pass == 0 { Box::new(pts.iter()) } else { Box::new(pts.iter().rev()) };
        for &p in iter {
            while hull.len() >= start + 2 && turn(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0 {
                hull.pop();
            }
            hull.push(p);
        }
        // The last point of each chain is the first of the other.
        hull.pop();
    }
    if hull.len() < 3 {
        // All points collinear: the two chains collapse to the two extremes.
        let first = pts[0];
        let last = pts[pts.len() - 1];
        return vec![first, last];
    }
    hull
}

/// Signed area of a polygon (positive when counter-clockwise).
pub fn polygon_area(poly: &[Point2]) -> f64 {
    let n = poly.len();
    (0..n).map(|i| poly[i].cross(poly[(i + 1) % n])).sum::<f64>() * 0.5
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn square_with_interior_and_edge_points() {
        let pts = [
            Point2::new(0.0, 0.0),
            Point2::new(1.0, 0.0),
            Point2::new(0.5, 0.0),
            Point2::new(1.0, 1.0),
            Point2::new(0.0, 1.0),
            Point2::new(0.5, 0.5),
            Point2::new(1.0, 1.0),
        ];
        let h = convex_hull(&pts);
        assert_eq!(
            h,
            vec![Point2::new(0.0, 0.0), Point2::new(1.0, 0.0), Point2::new(1.0, 1.0), Point2::new(0.0, 1.0)]
        );
        assert!((polygon_area(&h) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn degenerate_sets() {
        assert!(convex_hull(&[]).is_empty());
        let p = Point2::new(2.0, 3.0);
        assert_eq!(convex_hull(&[p, p]), vec![p]);
        let line: Vec<Point2> = (0..5).map(|k| Point2::new(k as f64, 2.0 * k as f64)).collect();
        assert_eq!(convex_hull(&line), vec![line[0], line[4]]);
    }

    proptest! {
        /// Every input point is inside or on the hull, and the hull turns left at every vertex.
        #[test]
        fn hull_contains_all_points_and_is_convex(
            pts in prop::collection::vec((-10.0..10.0f64, -10.0..10.0f64), 3..40)
        ) {
            let pts: Vec<Point2> = pts.into_iter().map(|(x, y)| Point2::new(x, y)).collect();
            let h = convex_hull(&pts);
            prop_assume!(h.len() >= 3);
            let n = h.len();
            for i in 0..n {
                let (a, b, c) = (h[i], h[(i + 1) % n], h[(i + 2) % n]);
                prop_assert!(b.sub(a).cross(c.sub(b)) > 0.0);
            }
            for p in &pts {
                for i in 0..n {
                    let (a, b) = (h[i], h[(i + 1) % n]);
                    prop_assert!(b.sub(a).cross(p.sub(a)) >= -1e-9);
                }
            }
        }
    }
}
