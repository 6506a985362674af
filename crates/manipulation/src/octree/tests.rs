//! The octree against a brute-force voxel grid: every cell tested against every line of sight
//! with a slab test, on random scenes.

use super::*;
use proptest::prelude::*;

/// Whether the segment `c`-`q` shortened by `margin` crosses the box grown by `grow`.
fn crosses(c: &V3, q: &V3, margin: f64, lo: &V3, hi: &V3, grow: f64) -> bool {
    let v = q - c;
    let len = v.norm();
    let t_end = len - margin;
    if t_end <= 0.0 {
        return false;
    }
    let d = v / len;
    let (mut t0, mut t1) = (0.0f64, t_end);
    for k in 0..3 {
        let (a, b) = (lo[k] - grow, hi[k] + grow);
        if d[k].abs() < 1e-15 {
            if c[k] < a || c[k] > b {
                return false;
            }
        } else {
            let (s, t) = ((a - c[k]) / d[k], (b - c[k]) / d[k]);
            t0 = t0.max(s.min(t));
            t1 = t1.min(s.max(t));
        }
    }
    t0 <= t1
}

fn v3() -> impl Strategy<Value = [f64; 3]> {
    [-0.3f64..1.9, -0.3f64..1.9, -0.3f64..1.9]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn octree_agrees_with_a_brute_force_grid(
        cameras in prop::collection::vec(v3(), 1..3),
        points in prop::collection::vec(v3(), 1..25),
        margin in 0.0f64..0.2,
        probes in prop::collection::vec((v3(), 0.0f64..0.3), 20),
    ) {
        let params = OctreeParams { min: [0.0, 0.0, 0.0], leaf: 0.1, depth: 4, surface_margin: margin };
        let cams: Vec<V3> = cameras.iter().map(|c| V3::from(*c)).collect();
        let pts: Vec<[f32; 3]> = points.iter().map(|p| p.map(|x| x as f32)).collect();
        let tree = Octree::build(params.clone(), &[View { cameras: &cams, points: &pts }]);
        let n = 16usize;
        let mut brute = vec![Cell::Unknown; n * n * n];
        let mut counts = [0u64; 3];
        for i in 0..n {
            for j in 0..n {
                for k in 0..n {
                    let lo = V3::new(i as f64, j as f64, k as f64) * 0.1;
                    let hi = lo + V3::repeat(0.1);
                    let holds = pts.iter().any(|p| {
                        (0..3).all(|a| ((p[a] as f64 / 0.1).floor() as i64) == [i, j, k][a] as i64)
                    });
                    let got = tree.leaf([i, j, k]);
                    let expect = if holds {
                        Cell::Occupied
                    } else {
                        let sure = pts.iter().any(|p| cams.iter().any(|c| {
                            crosses(c, &V3::new(p[0] as f64, p[1] as f64, p[2] as f64), margin, &lo, &hi, -1e-9)
                        }));
                        let maybe = pts.iter().any(|p| cams.iter().any(|c| {
                            crosses(c, &V3::new(p[0] as f64, p[1] as f64, p[2] as f64), margin, &lo, &hi, 1e-9)
                        }));
                        if sure { Cell::Free } else if !maybe { Cell::Unknown } else { got }
                    };
                    prop_assert_eq!(got, expect, "cell {:?}", [i, j, k]);
                    brute[i + n * (j + n * k)] = got;
                    counts[match got { Cell::Occupied => 0, Cell::Free => 1, Cell::Unknown => 2 }] += 1;
                }
            }
        }
        prop_assert_eq!(tree.counts(), counts);
        // The stored leaves tile the cube, each agreeing with every grid cell it covers.
        let mut covered = 0u64;
        for (state, min, side) in tree.leaves() {
            let m = (side / 0.1).round() as usize;
            let at = min.map(|x| (x / 0.1).round() as usize);
            covered += (m * m * m) as u64;
            for c in 0..m * m * m {
                let (i, j, k) = (at.x + c % m, at.y + (c / m) % m, at.z + c / (m * m));
                prop_assert_eq!(brute[i + n * (j + n * k)], state);
            }
        }
        prop_assert_eq!(covered, (n * n * n) as u64);
        let dense = DenseGrid::build(&params, &[View { cameras: &cams, points: &pts }]);
        prop_assert_eq!(&dense.cells, &brute);
        // `blocked` against a scan of every cell.
        for (q, r) in probes {
            let q = V3::from(q);
            let outside = (0..3).any(|k| q[k] - r < 0.0 || q[k] + r > 1.6);
            let near = (0..n * n * n).any(|c| {
                let (i, j, k) = (c % n, (c / n) % n, c / (n * n));
                let lo = V3::new(i as f64, j as f64, k as f64) * 0.1;
                let b = Aabb { min: lo, max: lo + V3::repeat(0.1) };
                brute[c] != Cell::Free && b.distance(&q) < r
            });
            prop_assert_eq!(tree.blocked(&q, r), outside || near, "probe {:?} r {}", q, r);
        }
    }
}

#[test]
fn clear_box_frees_only_cells_inside() {
    let params = OctreeParams { min: [0.0, 0.0, 0.0], leaf: 0.1, depth: 3, surface_margin: 0.0 };
    let mut tree = Octree::unknown(params);
    tree.clear_box(&Aabb::new([0.05, 0.0, 0.0], [0.31, 0.2, 0.1]));
    // x cells 1 and 2 lie inside, cell 0 and 3 only partly.
    assert_eq!(tree.leaf([0, 0, 0]), Cell::Unknown);
    assert_eq!(tree.leaf([1, 0, 0]), Cell::Free);
    assert_eq!(tree.leaf([2, 1, 0]), Cell::Free);
    assert_eq!(tree.leaf([3, 0, 0]), Cell::Unknown);
    assert_eq!(tree.counts(), [0, 4, 512 - 4]);
    assert_eq!(tree.at(&V3::new(-1.0, 0.0, 0.0)), Cell::Unknown);
}
