//! Exact Euclidean distance transform of a 3D occupancy grid.
//!
//! Paper 000 section 4.1 measures, for each occupied cell of the local map, the distance to the
//! closest occupied cell of the global map; the transform tabulates that distance for every
//! voxel of the global map once, so that scoring a pose is one lookup per local cell.
//! Squared distances are in voxel units and saturate at a cap: a capped value means "at least
//! the cap", which is all the likelihood needs (beyond it the inlier term is negligible).
//!
//! The algorithm is Meijster, Roerdink and Hesselink's separable exact transform ("A general
//! algorithm for computing distance transforms in linear time", 2000): per layer, the distance
//! to the nearest occupied cell of the same column (their first phase, two sweeps), then per
//! row the lower envelope of the parabolas `(x - i)^2 + g(i)^2` (their second phase), then the
//! same envelope along the layers. Departures, each for speed with identical outputs:
//! - the first phase sweeps row by row over all columns at once, so it reads and writes memory
//!   contiguously (the paper scans each column top to bottom), and its upward sweep is fused
//!   with the row envelopes so that each row is transformed while still in cache;
//! - the envelopes compare intersection points as exact integer fractions (cross-multiplied,
//!   as in Felzenszwalb and Huttenlocher's formulation, Theory of Computing 8, 2012, section
//!   2.1) instead of the paper's integer division `Sep`, so no cell pays for a division;
//! - values are capped early: column distances saturate at `ceil(sqrt(cap))` (stored as
//!   `u16`), and a parabola whose apex is already at the cap is left out of the envelope,
//!   since it can only produce values at or above the cap;
//! - the layer pass gathers blocks of [`LAYER_BLOCK`] neighbouring cells across all layers
//!   (contiguous runs of each layer) rather than one strided column at a time.

/// Cells per block of the layer pass: each layer is read and written in runs of this many.
const LAYER_BLOCK: usize = 256;

/// One parabola of a lower envelope.
#[derive(Clone, Copy, Default)]
struct Piece {
    /// Position of its apex.
    at: i64,
    /// Its apex value plus `at^2` (so that intersections need no squares).
    lifted: i64,
    /// Left end of its interval on the envelope, the fraction `num / den` (`den > 0`).
    num: i64,
    /// Denominator of `num`.
    den: i64,
}

/// One-dimensional lower envelope: `out[x] = min(cap, min_i f[i] + (x - i)^2)`, skipping
/// parabolas whose apex `f[i]` is at or above `cap`. `hull` is a reusable buffer.
fn envelope(f: &[u32], cap: u32, out: &mut [u16], hull: &mut Vec<Piece>) {
    hull.clear();
    for (q, &fq) in f.iter().enumerate() {
        if fq >= cap {
            continue;
        }
        let q = q as i64;
        let lifted = i64::from(fq) + q * q;
        let mut piece = Piece { at: q, lifted, num: 0, den: 1 };
        while let Some(last) = hull.last() {
            // Intersection with the last parabola: (lifted - last.lifted) / (2 (q - last.at)).
            piece.num = lifted - last.lifted;
            piece.den = 2 * (q - last.at);
            // At or before the left end of its interval, the last parabola is hidden.
            if hull.len() > 1 && piece.num * last.den <= last.num * piece.den {
                hull.pop();
            } else {
                break;
            }
        }
        hull.push(piece);
    }
    let Some(first) = hull.first() else {
        out.fill(cap as u16);
        return;
    };
    let mut current = *first;
    let mut next = hull[1..].iter();
    let mut upcoming = next.next();
    let cap = i64::from(cap);
    for (x, o) in out.iter_mut().enumerate() {
        let x = x as i64;
        while let Some(p) = upcoming.filter(|p| p.num < x * p.den) {
            current = *p;
            upcoming = next.next();
        }
        let v = current.lifted + x * (x - 2 * current.at);
        *o = v.min(cap) as u16;
    }
}

/// Squared Euclidean distance (voxels^2) from every voxel to the nearest occupied one, capped
/// at `cap`. `occupied` is indexed `(layer * rows + row) * cols + col`.
pub fn squared_distance_3d(occupied: &[bool], cols: usize, rows: usize, layers: usize, cap: u16) -> Vec<u16> {
    let planar = planar_distances(occupied, cols, rows, layers, cap);
    if layers <= 1 { planar } else { layer_pass(&planar, cols * rows, layers, cap) }
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
    let planar = planar_distances(occupied, cols, rows, layers, cap);
    let full = if layers <= 1 { planar.clone() } else { layer_pass(&planar, cols * rows, layers, cap) };
    (full, planar)
}

/// Per layer, capped squared distances to the nearest occupied cell of the same layer.
fn planar_distances(occupied: &[bool], cols: usize, rows: usize, layers: usize, cap: u16) -> Vec<u16> {
    let plane = cols * rows;
    let cap32 = u32::from(cap);
    let mut planar = vec![0u16; plane * layers];
    if plane == 0 {
        return planar;
    }
    // Column distances at or beyond `far` square to at least the cap.
    let mut far = f64::from(cap).sqrt() as u32;
    while far * far < cap32 {
        far += 1;
    }
    let far = far as u16;
    let mut hull = Vec::with_capacity(cols);
    let mut squares = vec![0u32; cols];
    let mut below = vec![0u16; cols];
    for (occ, g) in occupied[..plane * layers].chunks_exact(plane).zip(planar.chunks_exact_mut(plane)) {
        // Phase 1, down: distance to the nearest occupied cell above in the same column.
        for (o, v) in occ[..cols].iter().zip(&mut g[..cols]) {
            *v = far * u16::from(!*o);
        }
        for r in 1..rows {
            let (done, rest) = g.split_at_mut(r * cols);
            let above = &done[(r - 1) * cols..];
            for ((o, v), &u) in occ[r * cols..(r + 1) * cols].iter().zip(&mut rest[..cols]).zip(above) {
                *v = (u + 1).min(far) * u16::from(!*o);
            }
        }
        // Up (or below), fused with phase 2 while the row is in cache: per row, the envelope
        // of the squared column distances. `below` keeps the row under it before its envelope
        // overwrites it.
        for (r, row) in g.chunks_exact_mut(cols).enumerate().rev() {
            if r + 1 < rows {
                for (v, &b) in row.iter_mut().zip(&below) {
                    *v = (*v).min(b + 1);
                }
            }
            below.copy_from_slice(row);
            for (s, &d) in squares.iter_mut().zip(row.iter()) {
                *s = (u32::from(d) * u32::from(d)).min(cap32);
            }
            envelope(&squares, cap32, row, &mut hull);
        }
    }
    planar
}

/// The envelope along the layers of `planar` (`layers` planes of `plane` cells), in blocks of
/// neighbouring cells gathered across all layers.
fn layer_pass(planar: &[u16], plane: usize, layers: usize, cap: u16) -> Vec<u16> {
    let cap32 = u32::from(cap);
    let mut full = vec![0u16; plane * layers];
    let mut hull = Vec::with_capacity(layers);
    let mut block_in = vec![0u32; layers * LAYER_BLOCK];
    let mut block_out = vec![0u16; layers * LAYER_BLOCK];
    for base in (0..plane).step_by(LAYER_BLOCK) {
        let width = LAYER_BLOCK.min(plane - base);
        for z in 0..layers {
            let src = &planar[z * plane + base..z * plane + base + width];
            for (j, &v) in src.iter().enumerate() {
                block_in[j * layers + z] = u32::from(v);
            }
        }
        for (f, out) in block_in.chunks_exact(layers).zip(block_out.chunks_exact_mut(layers)).take(width) {
            envelope(f, cap32, out, &mut hull);
        }
        for z in 0..layers {
            let dst = &mut full[z * plane + base..z * plane + base + width];
            for (j, v) in dst.iter_mut().enumerate() {
                *v = block_out[j * layers + z];
            }
        }
    }
    full
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

    /// Brute force over every occupied voxel, uncapped: (3D, planar) squared distances, or
    /// `u32::MAX` where nothing is occupied.
    fn brute(occupied: &[bool], cols: usize, rows: usize) -> (Vec<u32>, Vec<u32>) {
        let index = |i: usize| (i % cols, (i / cols) % rows, i / (cols * rows));
        let sites: Vec<_> = (0..occupied.len()).filter(|&i| occupied[i]).map(index).collect();
        let (mut full, mut planar) = (vec![u32::MAX; occupied.len()], vec![u32::MAX; occupied.len()]);
        for i in 0..occupied.len() {
            let (c, r, z) = index(i);
            for &(c2, r2, z2) in &sites {
                let flat = (c.abs_diff(c2).pow(2) + r.abs_diff(r2).pow(2)) as u32;
                full[i] = full[i].min(flat + z.abs_diff(z2).pow(2) as u32);
                if z == z2 {
                    planar[i] = planar[i].min(flat);
                }
            }
        }
        (full, planar)
    }

    #[test]
    fn matches_brute_force_on_edge_grids_and_caps() {
        let mut rng = ChaCha8Rng::seed_from_u64(43);
        let mut shapes = vec![(0, 5, 2), (5, 0, 2), (4, 4, 0), (1, 1, 1), (1, 30, 3), (30, 1, 3), (1, 1, 40)];
        for _ in 0..40 {
            shapes.push((rng.random_range(1..24), rng.random_range(1..24), rng.random_range(1..6)));
        }
        for (case, &(cols, rows, layers)) in shapes.iter().enumerate() {
            let density = match case % 5 {
                0 => 0.0,
                1 => 1.0,
                _ => rng.random_range(0.001..0.2),
            };
            let occupied: Vec<bool> = (0..cols * rows * layers).map(|_| rng.random_bool(density)).collect();
            let (full, planar) = brute(&occupied, cols, rows);
            for cap in [0u16, 1, 2, 5, 40, 300, u16::MAX - 1, u16::MAX] {
                let capped = |v: &[u32]| v.iter().map(|&d| d.min(u32::from(cap)) as u16).collect::<Vec<_>>();
                let what = format!("case {case} ({cols}x{rows}x{layers}, density {density:.3}) cap {cap}");
                let (new_full, new_planar) = squared_distances(&occupied, cols, rows, layers, cap);
                assert_eq!(new_full, capped(&full), "{what}");
                assert_eq!(new_planar, capped(&planar), "{what}");
                assert_eq!(squared_distance_3d(&occupied, cols, rows, layers, cap), new_full, "{what}");
            }
        }
    }
}
