//! Exact ray casting against the bilinear height field of a [`Dem`].
//!
//! Every range sensor of the simulator (stereo pairs, nodding LIDAR, proximity sensors; papers
//! 000 section 2, 001 section 3, 004 section 3.1) is a ray cast with occlusion. `Dem::height`
//! interpolates bilinearly between cell centres, so the surface is a mesh of bilinear patches
//! whose corners are adjacent cell centres. Along a straight ray the height inside one patch is a
//! quadratic in the ray parameter, and so is the ray's clearance above the surface. The caster
//! marches the ray patch by patch (a grid traversal, so no patch is ever skipped however thin),
//! finds the first patch where the clearance quadratic reaches zero (end points and the vertex of
//! the parabola bound it exactly) and solves that quadratic for the crossing in closed form
//! (bisection only when rounding puts no root inside the bracket). A ray therefore never passes
//! through terrain. A coarse grid of per-block maximum heights lets the march skip blocks the
//! ray flies over, and a grid of per-patch maxima makes a patch it clears cost one load.

use rovernav_terrain::Dem;

/// Patches per side of one culling block.
const BLOCK: usize = 8;
/// Bisection stops when the bracket is shorter than this (m).
const BISECTION_TOLERANCE: f64 = 1e-10;

/// Where a ray met the terrain.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayHit {
    /// Distance from the ray origin along the unit direction (m).
    pub range: f64,
    /// World point of the crossing (m).
    pub point: [f64; 3],
}

/// Acceleration structure for ray casting: per-block maximum heights of a DEM.
#[derive(Clone, Debug)]
pub struct HeightField {
    block_cols: usize,
    block_rows: usize,
    /// Maximum corner height of each block (+inf when a block holds nodata).
    block_max: Vec<f64>,
    /// Patches per row: patch `i` in `-1..=cols - 1` is column `i + 1`.
    patch_cols: usize,
    /// Maximum corner height of each patch (+inf when a corner is nodata), so a patch the ray
    /// clears costs one load.
    patch_max: Vec<f32>,
}

/// A ray in patch-lattice coordinates: `u = (x - origin_x) / res - 0.5`, same for `v`, so
/// patch `i` spans `u` in `[i, i + 1]` between the centres of columns `i` and `i + 1`.
struct LatticeRay {
    u0: f64,
    v0: f64,
    du: f64,
    dv: f64,
    z0: f64,
    dz: f64,
}

impl LatticeRay {
    fn z(&self, t: f64) -> f64 {
        self.z0 + self.dz * t
    }
}

/// Outcome of examining one patch.
enum PatchResult {
    Clear,
    Hit(f64),
    NoData,
}

impl HeightField {
    /// Builds the block maxima of a DEM.
    pub fn new(dem: &Dem) -> Self {
        let g = dem.geometry();
        // Patch indices run from -1 (clamped western edge) to cols - 1 (clamped eastern edge).
        let block_cols = (g.cols + 1).div_ceil(BLOCK).max(1);
        let block_rows = (g.rows + 1).div_ceil(BLOCK).max(1);
        let mut block_max = vec![f64::NEG_INFINITY; block_cols * block_rows];
        if g.cols > 0 && g.rows > 0 {
            for (br, row_of_blocks) in block_max.chunks_mut(block_cols).enumerate() {
                for (bc, slot) in row_of_blocks.iter_mut().enumerate() {
                    *slot = block_corner_max(dem, bc, br);
                }
            }
        }
        let (patch_cols, patch_rows) = (g.cols + 1, g.rows + 1);
        let mut patch_max = vec![f32::INFINITY; patch_cols * patch_rows];
        if g.cols > 0 && g.rows > 0 {
            let h = |c: usize, r: usize| *dem.heights.get(c.min(g.cols - 1), r.min(g.rows - 1));
            for (pr, row) in patch_max.chunks_mut(patch_cols).enumerate() {
                // Patch (pc - 1, pr - 1) has corners at cells pc - 1 ..= pc, clamped.
                let (r0, r1) = (pr.saturating_sub(1), pr);
                for (pc, slot) in row.iter_mut().enumerate() {
                    let (c0, c1) = (pc.saturating_sub(1), pc);
                    let corners = [h(c0, r0), h(c1, r0), h(c0, r1), h(c1, r1)];
                    *slot = if corners.iter().any(|v| v.is_nan()) {
                        f32::INFINITY
                    } else {
                        corners.into_iter().fold(f32::NEG_INFINITY, f32::max)
                    };
                }
            }
        }
        Self { block_cols, block_rows, block_max, patch_cols, patch_max }
    }

    /// Casts a ray from `origin` along the unit vector `dir` up to `max_range` (m).
    ///
    /// Returns the first crossing of the terrain surface, or `None` when the ray reaches its
    /// range, leaves the DEM, or meets a cell without data first. An origin at or below the
    /// surface hits at range 0.
    pub fn cast(&self, dem: &Dem, origin: [f64; 3], dir: [f64; 3], max_range: f64) -> Option<RayHit> {
        self.cast_with::<false>(dem, origin, dir, max_range)
    }

    /// The same cast as [`HeightField::cast`] done the plain way: every visited patch's four
    /// corners loaded and its crossing found by bisection alone. A second implementation for
    /// the tests and the baseline of the render benchmark; ranges agree within 1e-9 m.
    pub fn cast_reference(
        &self,
        dem: &Dem,
        origin: [f64; 3],
        dir: [f64; 3],
        max_range: f64,
    ) -> Option<RayHit> {
        self.cast_with::<true>(dem, origin, dir, max_range)
    }

    fn cast_with<const REFERENCE: bool>(
        &self,
        dem: &Dem,
        origin: [f64; 3],
        dir: [f64; 3],
        max_range: f64,
    ) -> Option<RayHit> {
        let g = dem.geometry();
        if g.cols == 0 || g.rows == 0 || max_range.is_nan() || max_range <= 0.0 {
            return None;
        }
        let ray = LatticeRay {
            u0: (origin[0] - g.origin_x) / g.resolution - 0.5,
            v0: (origin[1] - g.origin_y) / g.resolution - 0.5,
            du: dir[0] / g.resolution,
            dv: dir[1] / g.resolution,
            z0: origin[2],
            dz: dir[2],
        };
        if !(ray.u0.is_finite() && ray.v0.is_finite() && ray.du.is_finite() && ray.dv.is_finite()) {
            return None;
        }
        // Clip to the domain where Dem::height is defined.
        let (mut t_in, mut t_out) = (0.0, max_range);
        for (p0, dp, hi) in [(ray.u0, ray.du, g.cols as f64 - 0.5), (ray.v0, ray.dv, g.rows as f64 - 0.5)] {
            if dp == 0.0 {
                if p0 < -0.5 || p0 > hi {
                    return None;
                }
            } else {
                let (a, b) = ((-0.5 - p0) / dp, (hi - p0) / dp);
                t_in = f64::max(t_in, a.min(b));
                t_out = f64::min(t_out, a.max(b));
            }
        }
        if t_in > t_out {
            return None;
        }
        let mut outcome = None;
        walk_cells(&ray, t_in, t_out, BLOCK as f64, -1.0, |bc, br, ta, tb| {
            if self.block_is_below(bc, br, ray.z(ta).min(ray.z(tb))) {
                return false;
            }
            walk_cells(&ray, ta, tb, 1.0, 0.0, |i, j, t0, t1| {
                match self.examine_patch::<REFERENCE>(dem, &ray, i, j, t0, t1) {
                    PatchResult::Clear => false,
                    // A ray from outside the DEM entering beneath its surface crosses no modelled
                    // surface: no return.
                    PatchResult::Hit(t) if t_in > 0.0 && t <= t_in => {
                        outcome = Some(f64::NAN);
                        true
                    }
                    PatchResult::Hit(t) => {
                        outcome = Some(t);
                        true
                    }
                    PatchResult::NoData => {
                        outcome = Some(f64::NAN);
                        true
                    }
                }
            })
        });
        let t = outcome.filter(|t| t.is_finite())?;
        Some(RayHit {
            range: t,
            point: [origin[0] + dir[0] * t, origin[1] + dir[1] * t, origin[2] + dir[2] * t],
        })
    }

    /// Whether every surface point of block (bc, br) lies strictly below `z`.
    fn block_is_below(&self, bc: i64, br: i64, z: f64) -> bool {
        let (bc, br) = (
            bc.clamp(0, self.block_cols as i64 - 1) as usize,
            br.clamp(0, self.block_rows as i64 - 1) as usize,
        );
        z > self.block_max[br * self.block_cols + bc]
    }

    /// Looks for the first crossing of the ray with bilinear patch (i, j) for `t` in `[t0, t1]`.
    /// With `REFERENCE`, the plain way: corners loaded first, crossing by bisection.
    fn examine_patch<const REFERENCE: bool>(
        &self,
        dem: &Dem,
        ray: &LatticeRay,
        i: i64,
        j: i64,
        t0: f64,
        t1: f64,
    ) -> PatchResult {
        let g = dem.geometry();
        let col = |k: i64| k.clamp(0, g.cols as i64 - 1) as usize;
        let row = |k: i64| k.clamp(0, g.rows as i64 - 1) as usize;
        // A bilinear patch never rises above its highest corner.
        let (pc, pr) = ((i + 1).clamp(0, g.cols as i64) as usize, (j + 1).clamp(0, g.rows as i64) as usize);
        if !REFERENCE && ray.z(t0).min(ray.z(t1)) > self.patch_max[pr * self.patch_cols + pc] as f64 {
            return PatchResult::Clear;
        }
        let h00 = *dem.heights.get(col(i), row(j)) as f64;
        let h10 = *dem.heights.get(col(i + 1), row(j)) as f64;
        let h01 = *dem.heights.get(col(i), row(j + 1)) as f64;
        let h11 = *dem.heights.get(col(i + 1), row(j + 1)) as f64;
        if !(h00.is_finite() && h10.is_finite() && h01.is_finite() && h11.is_finite()) {
            return PatchResult::NoData;
        }
        if REFERENCE && ray.z(t0).min(ray.z(t1)) > h00.max(h10).max(h01).max(h11) {
            return PatchResult::Clear;
        }
        patch_crossing::<REFERENCE>(ray, [h00, h10, h01, h11], i, j, t0, t1)
    }
}

/// Maximum of the cell heights that are corners of the patches of block (bc, br).
fn block_corner_max(dem: &Dem, bc: usize, br: usize) -> f64 {
    let g = dem.geometry();
    // Block b holds patches b*BLOCK - 1 ..= b*BLOCK + BLOCK - 2, whose corners are cells
    // b*BLOCK - 1 ..= b*BLOCK + BLOCK - 1 (clamped to the grid).
    let span = |b: usize, n: usize| {
        let lo = (b * BLOCK).saturating_sub(1).min(n - 1);
        let hi = (b * BLOCK + BLOCK - 1).min(n - 1);
        lo..=hi
    };
    let mut m = f64::NEG_INFINITY;
    for r in span(br, g.rows) {
        for c in span(bc, g.cols) {
            let h = *dem.heights.get(c, r) as f64;
            m = if h.is_nan() { f64::INFINITY } else { m.max(h) };
            if m == f64::INFINITY {
                return m;
            }
        }
    }
    m
}

/// Visits the cells of a square lattice (cell size `size`, boundaries at `offset + k * size`)
/// that the ray crosses between `t_start` and `t_end`, in order, with the sub-interval inside
/// each. Stops early when `visit` returns true; returns whether it did.
fn walk_cells(
    ray: &LatticeRay,
    t_start: f64,
    t_end: f64,
    size: f64,
    offset: f64,
    mut visit: impl FnMut(i64, i64, f64, f64) -> bool,
) -> bool {
    let axis = |p0: f64, dp: f64| {
        let p = p0 + dp * t_start;
        let cell = ((p - offset) / size).floor();
        if dp > 0.0 {
            (cell as i64, 1, t_start + ((cell + 1.0) * size + offset - p) / dp, size / dp)
        } else if dp < 0.0 {
            (cell as i64, -1, t_start + (cell * size + offset - p) / dp, -size / dp)
        } else {
            (cell as i64, 0, f64::INFINITY, f64::INFINITY)
        }
    };
    let (mut cu, step_u, mut next_u, delta_u) = axis(ray.u0, ray.du);
    let (mut cv, step_v, mut next_v, delta_v) = axis(ray.v0, ray.dv);
    let mut t = t_start;
    loop {
        let t_next = next_u.min(next_v).min(t_end);
        if visit(cu, cv, t, t_next) {
            return true;
        }
        if t_next >= t_end {
            return false;
        }
        if next_u < next_v {
            cu += step_u;
            t = next_u;
            next_u += delta_u;
        } else {
            cv += step_v;
            t = next_v;
            next_v += delta_v;
        }
    }
}

/// The first crossing of the ray with the bilinear patch (i, j) of corner heights `[h00, h10,
/// h01, h11]` for `t` in `[t0, t1]`, the ray below the patch's highest corner somewhere there.
fn patch_crossing<const REFERENCE: bool>(
    ray: &LatticeRay,
    [h00, h10, h01, h11]: [f64; 4],
    i: i64,
    j: i64,
    t0: f64,
    t1: f64,
) -> PatchResult {
    // Clearance f(s) = z(t0 + s) - h(t0 + s) = q2 s^2 + q1 s + q0 on s in [0, len].
    let a0 = ray.u0 + ray.du * t0 - i as f64;
    let b0 = ray.v0 + ray.dv * t0 - j as f64;
    let (a1, b1) = (ray.du, ray.dv);
    let (ca, cb, cab) = (h10 - h00, h01 - h00, h00 - h10 - h01 + h11);
    let q0 = ray.z(t0) - (h00 + ca * a0 + cb * b0 + cab * a0 * b0);
    let q1 = ray.dz - (ca * a1 + cb * b1 + cab * (a0 * b1 + a1 * b0));
    let q2 = -cab * a1 * b1;
    let f = |s: f64| (q2 * s + q1) * s + q0;
    let len = t1 - t0;
    if q0 <= 0.0 {
        return PatchResult::Hit(t0);
    }
    let bracket_end = if f(len) <= 0.0 {
        len
    } else if q2 > 0.0 {
        let vertex = -q1 / (2.0 * q2);
        if vertex > 0.0 && vertex < len && f(vertex) <= 0.0 {
            vertex
        } else {
            return PatchResult::Clear;
        }
    } else {
        return PatchResult::Clear;
    };
    let s = if REFERENCE { bisect(q2, q1, q0, bracket_end) } else { first_root(q2, q1, q0, bracket_end) };
    PatchResult::Hit(t0 + s)
}

/// The root of `f(s) = q2 s^2 + q1 s + q0` in `(0, end]`, given `f(0) > 0 >= f(end)` and a
/// single crossing there: in closed form (the cancellation-free pair `q / q2`, `q0 / q` with
/// `q = -(q1 + sign(q1) sqrt(q1^2 - 4 q2 q0)) / 2`, Numerical Recipes 5.6), falling back to
/// bisection when rounding puts neither root inside the bracket.
fn first_root(q2: f64, q1: f64, q0: f64, end: f64) -> f64 {
    let disc = (q1 * q1 - 4.0 * q2 * q0).max(0.0);
    let q = -0.5 * (q1 + disc.sqrt().copysign(q1));
    let inside = |s: f64| (0.0..=end).contains(&s);
    let (r1, r2) = (q / q2, q0 / q);
    match (inside(r1), inside(r2)) {
        (true, true) => r1.min(r2),
        (true, false) => r1,
        (false, true) => r2,
        (false, false) => bisect(q2, q1, q0, end),
    }
}

/// The crossing of `f(s) = q2 s^2 + q1 s + q0` in `(0, end]` by bisection to
/// `BISECTION_TOLERANCE`, given `f(0) > 0 >= f(end)`.
fn bisect(q2: f64, q1: f64, q0: f64, end: f64) -> f64 {
    let f = |s: f64| (q2 * s + q1) * s + q0;
    // f(lo) > 0 >= f(hi), and f has no root before lo in this patch.
    let (mut lo, mut hi) = (0.0, end);
    while hi - lo > BISECTION_TOLERANCE {
        let mid = 0.5 * (lo + hi);
        if f(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rovernav_core::{Grid2, GridGeometry};

    fn bumpy(cols: usize, rows: usize, res: f64, seed: u64) -> Dem {
        let geometry = GridGeometry { cols, rows, resolution: res, origin_x: -1.0, origin_y: 2.0 };
        let mut s = seed;
        let data = (0..cols * rows)
            .map(|_| {
                s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                ((s >> 33) as f64 / (1u64 << 31) as f64 * 0.5) as f32
            })
            .collect();
        Dem::from_grid(Grid2 { geometry, data })
    }

    #[test]
    fn vertical_ray_hits_the_interpolated_height() {
        let dem = bumpy(12, 9, 0.1, 3);
        let hf = HeightField::new(&dem);
        for (x, y) in [(-0.93, 2.07), (-0.5, 2.4), (0.12, 2.83), (-0.02, 2.55)] {
            let hit = hf.cast(&dem, [x, y, 5.0], [0.0, 0.0, -1.0], 10.0).expect("hit");
            let h = dem.height(x, y).expect("inside");
            assert!((hit.point[2] - h).abs() < 1e-7, "{} vs {h}", hit.point[2]);
            assert!((hit.range - (5.0 - h)).abs() < 1e-7);
        }
    }

    #[test]
    fn flat_ground_range_matches_the_triangle() {
        let dem = Dem::flat(100, 100, 0.05, 0.0);
        let hf = HeightField::new(&dem);
        // Camera 1.2 m up looking 20 deg below the horizon: range h / sin(20 deg).
        let d = 20f64.to_radians();
        let dir = [d.cos() * 0.6, d.cos() * 0.8, -d.sin()];
        let hit = hf.cast(&dem, [0.3, 0.3, 1.2], dir, 10.0).expect("hit");
        assert!((hit.range - 1.2 / d.sin()).abs() < 1e-9);
    }

    #[test]
    fn rays_leaving_the_dem_or_pointing_up_return_nothing() {
        let dem = Dem::flat(10, 10, 0.1, 0.0);
        let hf = HeightField::new(&dem);
        assert!(hf.cast(&dem, [0.5, 0.5, 1.0], [1.0, 0.0, 0.0], 100.0).is_none());
        assert!(hf.cast(&dem, [0.5, 0.5, 1.0], [0.6, 0.0, 0.8], 100.0).is_none());
        assert!(hf.cast(&dem, [0.5, 0.5, 1.0], [0.0, 0.0, -1.0], 0.5).is_none());
        let under = hf.cast(&dem, [0.5, 0.5, -0.2], [1.0, 0.0, 0.0], 1.0).expect("inside");
        assert_eq!(under.range, 0.0);
    }

    #[test]
    fn rays_from_outside_hit_when_they_enter_above_the_surface() {
        let dem = Dem::flat(10, 10, 0.1, 0.0);
        let hf = HeightField::new(&dem);
        // From 1 m west of the DEM, 1 m up, 30 deg down: enters at z = 1 - tan(30) * 1 > 0.
        let d = 30f64.to_radians();
        let hit = hf.cast(&dem, [-1.0, 0.5, 1.0], [d.cos(), 0.0, -d.sin()], 10.0).expect("hit");
        assert!((hit.point[0] - (-1.0 + 1.0 / d.tan())).abs() < 1e-9 && hit.point[2].abs() < 1e-9);
        // From below the DEM's level outside it: passes under the model, no return.
        assert!(hf.cast(&dem, [-1.0, 0.5, -0.1], [1.0, 0.0, 0.0], 10.0).is_none());
    }

    /// Uniform draws in [0, 1) from a xorshift stream (`seed` non-zero).
    fn uniform(seed: u64) -> impl FnMut() -> f64 {
        let mut s = seed;
        move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    #[test]
    fn closed_form_root_equals_bisection() {
        // Random parabolas through a crossing at a known root r: f(s) = (s - r) (q2' s + k)
        // with f(0) > 0 >= f(end); bisection is the second implementation.
        let mut next = uniform(0x9e37_79b9_7f4a_7c15);
        let mut checked = 0;
        for _ in 0..20_000 {
            let end = 0.01 + next() * 0.2;
            let r = next() * end;
            let (a, k) = ((next() - 0.5) * 400.0, -(0.05 + next() * 3.0));
            let (q2, q1, q0) = (a, k - a * r, -k * r);
            let f = |x: f64| (q2 * x + q1) * x + q0;
            if !(q0 > 0.0 && f(end) <= 0.0) {
                continue;
            }
            let (fast, slow) = (first_root(q2, q1, q0, end), bisect(q2, q1, q0, end));
            assert!((fast - slow).abs() < 1e-9, "q = ({q2}, {q1}, {q0}) end {end}: {fast} vs {slow}");
            assert!((fast - r).abs() < 1e-9, "root {r} found at {fast}");
            checked += 1;
        }
        assert!(checked > 5_000, "only {checked} brackets");
        // A straight line (q2 = 0) and a double root at the bracket's end.
        assert!((first_root(0.0, -2.0, 0.1, 0.2) - 0.05).abs() < 1e-15);
        assert!((first_root(1.0, -0.2, 0.01, 0.1) - 0.1).abs() < 1e-7);
    }

    #[test]
    fn cast_equals_the_reference_cast() {
        // Bumpy DEMs with nodata holes, rays from above, below, outside and grazing: the fast
        // cast (patch maxima, closed-form crossing) against the plain one (corners, bisection).
        let mut hits = 0;
        for seed in 1..40u64 {
            let mut dem = bumpy(37, 23, 0.05, seed);
            if seed % 3 == 0 {
                *dem.heights.get_mut((seed % 37) as usize, 11) = f32::NAN;
            }
            let hf = HeightField::new(&dem);
            let mut next = uniform(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1);
            for _ in 0..500 {
                let o = [-1.3 + next() * 2.4, 1.7 + next() * 1.8, -0.2 + next() * 1.4];
                let (az, el) = (next() * 6.3, -1.5 + next() * 1.9);
                let d = [el.cos() * az.cos(), el.cos() * az.sin(), el.sin()];
                let fast = hf.cast(&dem, o, d, 4.0);
                let plain = hf.cast_reference(&dem, o, d, 4.0);
                match (fast, plain) {
                    (Some(a), Some(b)) => {
                        assert!((a.range - b.range).abs() < 1e-9, "{o:?} {d:?}: {} vs {}", a.range, b.range);
                        hits += 1;
                    }
                    (None, None) => {}
                    _ => panic!("{o:?} {d:?}: {fast:?} vs {plain:?}"),
                }
            }
        }
        assert!(hits > 5_000, "only {hits} hits");
    }

    #[test]
    fn nodata_stops_the_ray() {
        let mut dem = Dem::flat(20, 3, 0.1, 0.0);
        *dem.heights.get_mut(10, 1) = f32::NAN;
        let hf = HeightField::new(&dem);
        // Grazing ray from the west that would reach the ground east of the hole.
        let dir: [f64; 3] = [0.999, 0.0, -0.0447];
        let n = dir[0] * dir[0] + dir[2] * dir[2];
        let dir = [dir[0] / n.sqrt(), 0.0, dir[2] / n.sqrt()];
        assert!(hf.cast(&dem, [0.05, 0.15, 0.07], dir, 5.0).is_none());
    }
}
