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
//! And what an exact transform costs when written for the cache, as a reference for
//! rovernav's own: [`meijster`], Meijster, Roerdink and Hesselink's separable exact EDT ("A
//! general algorithm for computing distance transforms in linear time", Mathematical
//! Morphology and its Applications to Image and Signal Processing, 2000), with its first
//! phase (distance along columns) swept row by row over all columns at once, so that both
//! phases read memory contiguously, and integer arithmetic throughout.
//!
//! rovernav's exact transform is `rovernav_localization::matching::distance_transform`; the
//! report asserts it, [`felzenszwalb_huttenlocher`] and [`meijster`] agree on every cell.

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

/// Exact squared Euclidean distances (cells^2) of a `cols` x `rows` occupancy grid (row-major)
/// by Meijster et al.'s algorithm (see the module doc); `u32::MAX` everywhere when nothing is
/// occupied.
pub fn meijster(occupied: &[bool], cols: usize, rows: usize) -> Vec<u32> {
    if !occupied.iter().any(|&o| o) {
        return vec![u32::MAX; cols * rows];
    }
    // Phase 1: distance to the nearest occupied cell in the same column, as rows sweep down
    // then up (all columns at once: contiguous rows). `far` exceeds any real distance.
    let far = (rows + cols) as u32;
    let mut g = vec![far; cols * rows];
    for (r, row) in occupied.chunks_exact(cols).enumerate() {
        for c in 0..cols {
            g[r * cols + c] = if row[c] {
                0
            } else if r > 0 {
                (g[(r - 1) * cols + c] + 1).min(far)
            } else {
                far
            };
        }
    }
    for r in (0..rows.saturating_sub(1)).rev() {
        let (upper, lower) = g.split_at_mut((r + 1) * cols);
        for (a, &b) in upper[r * cols..].iter_mut().zip(&lower[..cols]) {
            *a = (*a).min(b + 1);
        }
    }
    // Phase 2: per row, the lower envelope of (x - i)^2 + g(i)^2 with integer separators.
    let mut out = vec![0u32; cols * rows];
    let (mut s, mut t) = (vec![0usize; cols], vec![0i64; cols]);
    let mut g2 = vec![0i64; cols];
    for r in 0..rows {
        for (v, &d) in g2.iter_mut().zip(&g[r * cols..(r + 1) * cols]) {
            *v = i64::from(d) * i64::from(d);
        }
        let g2 = &g2;
        let f = |x: i64, i: usize| (x - i as i64) * (x - i as i64) + g2[i];
        let sep = |i: usize, u: usize| {
            let (i64_i, u2) = (i as i64, u as i64);
            (u2 * u2 - i64_i * i64_i + g2[u] - g2[i]).div_euclid(2 * (u2 - i64_i))
        };
        let mut q: isize = 0;
        s[0] = 0;
        t[0] = 0;
        for u in 1..cols {
            while q >= 0 && f(t[q as usize], s[q as usize]) > f(t[q as usize], u) {
                q -= 1;
            }
            if q < 0 {
                q = 0;
                s[0] = u;
            } else {
                let w = 1 + sep(s[q as usize], u);
                if w < cols as i64 {
                    q += 1;
                    s[q as usize] = u;
                    t[q as usize] = w;
                }
            }
        }
        let row = &mut out[r * cols..(r + 1) * cols];
        for u in (0..cols).rev() {
            row[u] = f(u as i64, s[q as usize]) as u32;
            if u as i64 == t[q as usize] {
                q -= 1;
            }
        }
    }
    out
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
            let fast: Vec<f64> = super::meijster(&occ, cols, rows)
                .iter()
                .map(|&d| if d == u32::MAX { f64::INFINITY } else { d as f64 })
                .collect();
            assert_eq!(fast, truth, "seed {seed}");
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
