//! Exact Euclidean distance transform of a 3D occupancy grid (Felzenszwalb and Huttenlocher's
//! lower envelope of parabolas, applied separably along each axis).
//!
//! Paper 000 section 4.1 measures, for each occupied cell of the local map, the distance to the
//! closest occupied cell of the global map; the transform tabulates that distance for every
//! voxel of the global map once, so that scoring a pose is one lookup per local cell.
//! Squared distances are in voxel units and saturate at a cap: a capped value means "at least
//! the cap", which is all the likelihood needs (beyond it the inlier term is negligible).

/// One-dimensional squared-distance transform of a sampled function: `out[q] = min_p f[p] +
/// (q - p)^2`. `hull` and `bounds` are scratch buffers of at least `f.len()` and `f.len() + 1`.
pub fn squared_distance_1d(f: &[f64], out: &mut [f64], hull: &mut [usize], bounds: &mut [f64]) {
    let n = f.len();
    if n == 0 {
        return;
    }
    let mut k = 0usize;
    hull[0] = 0;
    bounds[0] = f64::NEG_INFINITY;
    bounds[1] = f64::INFINITY;
    for q in 1..n {
        let fq = f[q] + (q * q) as f64;
        let mut s;
        loop {
            let p = hull[k];
            s = (fq - (f[p] + (p * p) as f64)) / (2.0 * (q - p) as f64);
            // bounds[0] is -inf, so this stops at k == 0 at the latest.
            if s <= bounds[k] {
                k -= 1;
            } else {
                break;
            }
        }
        k += 1;
        hull[k] = q;
        bounds[k] = s;
        bounds[k + 1] = f64::INFINITY;
    }
    k = 0;
    for (q, o) in out.iter_mut().enumerate().take(n) {
        while bounds[k + 1] < q as f64 {
            k += 1;
        }
        let p = hull[k];
        let d = q as f64 - p as f64;
        *o = d * d + f[p];
    }
}

/// Squared Euclidean distance (voxels^2) from every voxel to the nearest occupied one, capped
/// at `cap`. `occupied` is indexed `(layer * rows + row) * cols + col`.
pub fn squared_distance_3d(occupied: &[bool], cols: usize, rows: usize, layers: usize, cap: u16) -> Vec<u16> {
    squared_distances(occupied, cols, rows, layers, cap).0
}

/// Both the 3D squared distances and, per layer, the squared horizontal distance to the
/// nearest occupied voxel of the same layer (the transform before its vertical pass), capped.
pub fn squared_distances(
    occupied: &[bool],
    cols: usize,
    rows: usize,
    layers: usize,
    cap: u16,
) -> (Vec<u16>, Vec<u16>) {
    let cap_f = f64::from(cap);
    let mut field: Vec<f64> = occupied.iter().map(|&o| if o { 0.0 } else { cap_f }).collect();
    let longest = cols.max(rows).max(layers);
    let mut line = vec![0.0; longest];
    let mut out = vec![0.0; longest];
    let mut hull = vec![0usize; longest];
    let mut bounds = vec![0.0; longest + 1];
    // Along x.
    for start in (0..field.len()).step_by(cols.max(1)) {
        let seg = &mut field[start..start + cols];
        squared_distance_1d(seg, &mut out[..cols], &mut hull, &mut bounds);
        for (v, o) in seg.iter_mut().zip(&out[..cols]) {
            *v = o.min(cap_f);
        }
    }
    // Along y, then z: gather the strided line, transform, scatter back.
    let mut pass = |field: &mut [f64], stride: usize, len: usize, starts: &mut dyn Iterator<Item = usize>| {
        for start in starts {
            for (i, l) in line[..len].iter_mut().enumerate() {
                *l = field[start + i * stride];
            }
            squared_distance_1d(&line[..len], &mut out[..len], &mut hull, &mut bounds);
            for (i, o) in out[..len].iter().enumerate() {
                field[start + i * stride] = o.min(cap_f);
            }
        }
    };
    pass(&mut field, cols, rows, &mut (0..layers).flat_map(|z| (0..cols).map(move |c| z * rows * cols + c)));
    let planar: Vec<u16> = field.iter().map(|v| v.round() as u16).collect();
    pass(&mut field, rows * cols, layers, &mut (0..rows * cols));
    (field.into_iter().map(|v| v.round() as u16).collect(), planar)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn matches_brute_force_on_random_grids() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        for case in 0..20 {
            let (cols, rows, layers) =
                (rng.random_range(1..14), rng.random_range(1..14), rng.random_range(1..6));
            let density = if case % 4 == 0 { 0.0 } else { rng.random_range(0.01..0.3) };
            let occupied: Vec<bool> = (0..cols * rows * layers).map(|_| rng.random_bool(density)).collect();
            let cap = 40;
            let (dt, planar) = squared_distances(&occupied, cols, rows, layers, cap);
            for z in 0..layers {
                for r in 0..rows {
                    for c in 0..cols {
                        let mut best = u32::from(cap);
                        for z2 in 0..layers {
                            for r2 in 0..rows {
                                for c2 in 0..cols {
                                    if occupied[(z2 * rows + r2) * cols + c2] {
                                        let d = (c.abs_diff(c2).pow(2)
                                            + r.abs_diff(r2).pow(2)
                                            + z.abs_diff(z2).pow(2))
                                            as u32;
                                        best = best.min(d);
                                    }
                                }
                            }
                        }
                        assert_eq!(u32::from(dt[(z * rows + r) * cols + c]), best);
                        let mut best_planar = u32::from(cap);
                        for r2 in 0..rows {
                            for c2 in 0..cols {
                                if occupied[(z * rows + r2) * cols + c2] {
                                    let d = (c.abs_diff(c2).pow(2) + r.abs_diff(r2).pow(2)) as u32;
                                    best_planar = best_planar.min(d);
                                }
                            }
                        }
                        assert_eq!(u32::from(planar[(z * rows + r) * cols + c]), best_planar);
                    }
                }
            }
        }
    }
}
