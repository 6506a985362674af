//! Distance-transform baselines for `rovernav bench report`'s `edt-4096` row, written the way
//! a user would write them without rovernav:
//!
//! - [`chamfer_3_4`]: Borgefors' two-pass 3-4 chamfer distance ("Distance transformations in
//!   digital images", CVGIP 34, 1986): a forward and a backward raster pass with the 3x3 mask,
//!   an approximation of the Euclidean distance (in units of 1/3 cell);
//! - [`felzenszwalb_huttenlocher`]: the exact squared Euclidean transform of Felzenszwalb and
//!   Huttenlocher ("Distance transforms of sampled functions", Theory of Computing 8, 2012,
//!   section 2.1), straightforwardly: one 1D lower envelope of parabolas per column, then per row,
//!   on `f64` values with a fresh envelope buffer per line.
//!
//! rovernav's exact transform is `rovernav_localization::matching::distance_transform`
//! (Meijster, Roerdink and Hesselink's algorithm, written for the cache); the report asserts it
//! and [`felzenszwalb_huttenlocher`] agree on every cell.

/// Two-pass 3-4 chamfer distances (1/3 cell units) of a `cols` x `rows` occupancy grid
/// (row-major); cells farther than any occupied one get `u32::MAX / 2`.
pub fn chamfer_3_4(occupied: &[bool], cols: usize, rows: usize) -> Vec<u32> {
    const FAR: u32 = u32::MAX / 2;
    let mut d: Vec<u32> = occupied.iter().map(|&o| if o { 0 } else { FAR }).collect();
    for r in 0..rows {
        for c in 0..cols {
            let i = r * cols + c;
            let mut v = d[i];
            if c > 0 {
                v = v.min(d[i - 1] + 3);
            }
            if r > 0 {
                let up = i - cols;
                v = v.min(d[up] + 3);
                if c > 0 {
                    v = v.min(d[up - 1] + 4);
                }
                if c + 1 < cols {
                    v = v.min(d[up + 1] + 4);
                }
            }
            d[i] = v;
        }
    }
    for r in (0..rows).rev() {
        for c in (0..cols).rev() {
            let i = r * cols + c;
            let mut v = d[i];
            if c + 1 < cols {
                v = v.min(d[i + 1] + 3);
            }
            if r + 1 < rows {
                let down = i + cols;
                v = v.min(d[down] + 3);
                if c + 1 < cols {
                    v = v.min(d[down + 1] + 4);
                }
                if c > 0 {
                    v = v.min(d[down - 1] + 4);
                }
            }
            d[i] = v;
        }
    }
    d
}

/// One-dimensional lower envelope of the parabolas `f[p] + (q - p)^2` (their algorithm DT(f)).
fn envelope_1d(f: &[f64]) -> Vec<f64> {
    let n = f.len();
    let mut v = vec![0usize; n];
    let mut z = vec![0.0f64; n + 1];
    let mut out = vec![0.0; n];
    if n == 0 {
        return out;
    }
    let mut k = 0;
    z[0] = f64::NEG_INFINITY;
    z[1] = f64::INFINITY;
    for q in 1..n {
        if f[q].is_infinite() {
            continue;
        }
        if f[v[k]].is_infinite() {
            v[k] = q;
            continue;
        }
        let intersect = |p: usize| ((f[q] + (q * q) as f64) - (f[p] + (p * p) as f64)) / (2 * (q - p)) as f64;
        let mut s = intersect(v[k]);
        while k > 0 && s <= z[k] {
            k -= 1;
            s = intersect(v[k]);
        }
        k += 1;
        v[k] = q;
        z[k] = s;
        z[k + 1] = f64::INFINITY;
    }
    let mut k = 0;
    for (q, o) in out.iter_mut().enumerate() {
        while z[k + 1] < q as f64 {
            k += 1;
        }
        let d = q as f64 - v[k] as f64;
        *o = d * d + f[v[k]];
    }
    out
}

/// Exact squared Euclidean distances (cells^2) of a `cols` x `rows` occupancy grid (row-major);
/// infinite where nothing is occupied.
pub fn felzenszwalb_huttenlocher(occupied: &[bool], cols: usize, rows: usize) -> Vec<f64> {
    let mut d: Vec<f64> = occupied.iter().map(|&o| if o { 0.0 } else { f64::INFINITY }).collect();
    for c in 0..cols {
        let column: Vec<f64> = (0..rows).map(|r| d[r * cols + c]).collect();
        for (r, v) in envelope_1d(&column).into_iter().enumerate() {
            d[r * cols + c] = v;
        }
    }
    for r in 0..rows {
        let row = envelope_1d(&d[r * cols..(r + 1) * cols]);
        d[r * cols..(r + 1) * cols].copy_from_slice(&row);
    }
    d
}

/// A reproducible occupancy grid: each cell occupied with probability `density` (xorshift from
/// `seed`).
pub fn random_occupancy(cols: usize, rows: usize, density: f64, seed: u64) -> Vec<bool> {
    let mut state = seed | 1;
    let threshold = (density.clamp(0.0, 1.0) * u64::MAX as f64) as u64;
    (0..cols * rows)
        .map(|_| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state < threshold
        })
        .collect()
}

#[cfg(test)]
mod tests {
    // Paths instead of `use`: the EDT bench includes this file, and its harness drops tests.

    /// Brute force over every occupied cell: the independent truth.
    fn brute(occupied: &[bool], cols: usize, rows: usize) -> Vec<f64> {
        let pts: Vec<(usize, usize)> =
            (0..rows * cols).filter(|&i| occupied[i]).map(|i| (i / cols, i % cols)).collect();
        (0..rows * cols)
            .map(|i| {
                let (r, c) = (i / cols, i % cols);
                pts.iter()
                    .map(|&(pr, pc)| (r.abs_diff(pr).pow(2) + c.abs_diff(pc).pow(2)) as f64)
                    .fold(f64::INFINITY, f64::min)
            })
            .collect()
    }

    #[test]
    fn exact_baseline_matches_brute_force_and_chamfer_is_close() {
        for (seed, density, cols, rows) in
            [(1, 0.02, 37, 23), (2, 0.2, 16, 41), (3, 0.0, 5, 4), (4, 0.005, 64, 64)]
        {
            let occ = super::random_occupancy(cols, rows, density, seed);
            let truth = brute(&occ, cols, rows);
            assert_eq!(super::felzenszwalb_huttenlocher(&occ, cols, rows), truth, "seed {seed}");
            let chamfer = super::chamfer_3_4(&occ, cols, rows);
            for (i, (&ch, &t)) in chamfer.iter().zip(&truth).enumerate() {
                if t.is_finite() {
                    // 3-4 chamfer is within about 8 % of the Euclidean distance (Borgefors).
                    let e = t.sqrt();
                    let a = ch as f64 / 3.0;
                    assert!((a - e).abs() <= 0.09 * e + 1e-9, "seed {seed} cell {i}: {a} vs {e}");
                } else {
                    assert_eq!(ch, u32::MAX / 2);
                }
            }
        }
    }
}
