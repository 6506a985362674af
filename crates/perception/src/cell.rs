//! Per-cell accumulation of range points: the sufficient statistics of an elevation-map cell.
//!
//! Paper 002 section 3.1 bins range points into a grid over the xy-plane and takes the mean
//! height of each bin; paper 004 section 3.3 also needs the variance of the heights (roughness)
//! and the best-fit plane through the points of a cell (slope). Keeping running sums lets new
//! clouds be fused into a cell without revisiting old points. Sums are taken with x, y relative
//! to the cell centre and z relative to the first point's height, so that the second moments
//! stay well conditioned even at Mars datum heights (thousands of metres).

/// Running sums of the range points that fell in one cell.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CellStats {
    /// Number of points.
    pub count: u32,
    /// Lowest point height (m, world z).
    pub min_z: f32,
    /// Highest point height (m, world z).
    pub max_z: f32,
    z_ref: f64,
    sum_x: f64,
    sum_y: f64,
    sum_z: f64,
    sum_xx: f64,
    sum_xy: f64,
    sum_yy: f64,
    sum_xz: f64,
    sum_yz: f64,
    sum_zz: f64,
    /// Sum of the points' expected height-noise variances (m^2): zero for points added without
    /// a noise figure.
    sum_noise_var: f64,
}

impl Default for CellStats {
    fn default() -> Self {
        Self::EMPTY
    }
}

/// Least-squares plane `z = z0 + gx*x + gy*y` through the points of one cell.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlaneFit {
    /// Height gradient along world x (m/m).
    pub gx: f64,
    /// Height gradient along world y (m/m).
    pub gy: f64,
    /// Variance of the point heights about the plane (m^2).
    pub residual_variance: f64,
    /// Plane height at the cell centre relative to the cell's reference height (m).
    pub offset: f64,
}

impl PlaneFit {
    /// Tilt of the plane from horizontal (rad).
    pub fn slope(&self) -> f64 {
        self.gx.hypot(self.gy).atan()
    }
}

impl CellStats {
    /// A cell with no points.
    pub const EMPTY: CellStats = CellStats {
        count: 0,
        min_z: f32::INFINITY,
        max_z: f32::NEG_INFINITY,
        z_ref: 0.0,
        sum_x: 0.0,
        sum_y: 0.0,
        sum_z: 0.0,
        sum_xx: 0.0,
        sum_xy: 0.0,
        sum_yy: 0.0,
        sum_xz: 0.0,
        sum_yz: 0.0,
        sum_zz: 0.0,
        sum_noise_var: 0.0,
    };

    /// Whether any point fell in the cell.
    pub fn is_sensed(&self) -> bool {
        self.count > 0
    }

    /// Adds a point at offset `(dx, dy)` from the cell centre with world height `z`.
    #[inline]
    pub fn add(&mut self, dx: f64, dy: f64, z: f64) {
        self.add_with_noise(dx, dy, z, 0.0);
    }

    /// [`Self::add`] for a point whose height is known to carry noise of variance `noise_var`
    /// (m^2; negative or non-finite values count as zero).
    #[inline]
    pub fn add_with_noise(&mut self, dx: f64, dy: f64, z: f64, noise_var: f64) {
        if noise_var.is_finite() && noise_var > 0.0 {
            self.sum_noise_var += noise_var;
        }
        if self.count == 0 {
            self.z_ref = z;
        }
        let dz = z - self.z_ref;
        self.count += 1;
        self.min_z = self.min_z.min(z as f32);
        self.max_z = self.max_z.max(z as f32);
        self.sum_x += dx;
        self.sum_y += dy;
        self.sum_z += dz;
        self.sum_xx += dx * dx;
        self.sum_xy += dx * dy;
        self.sum_yy += dy * dy;
        self.sum_xz += dx * dz;
        self.sum_yz += dy * dz;
        self.sum_zz += dz * dz;
    }

    /// Mean point height (m), if sensed.
    pub fn mean(&self) -> Option<f64> {
        (self.count > 0).then(|| self.z_ref + self.sum_z / self.count as f64)
    }

    /// Mean expected height-noise variance of the points (m^2), if sensed: how much of
    /// [`Self::variance`] range noise alone would explain.
    pub fn noise_variance(&self) -> Option<f64> {
        (self.count > 0).then(|| self.sum_noise_var / self.count as f64)
    }

    /// Population variance of the point heights (m^2), if sensed.
    pub fn variance(&self) -> Option<f64> {
        if self.count == 0 {
            return None;
        }
        let n = self.count as f64;
        let m = self.sum_z / n;
        Some((self.sum_zz / n - m * m).max(0.0))
    }

    /// Least-squares plane through the points, if there are at least three not on one line.
    pub fn plane_fit(&self) -> Option<PlaneFit> {
        if self.count < 3 {
            return None;
        }
        let n = self.count as f64;
        let (mx, my, mz) = (self.sum_x / n, self.sum_y / n, self.sum_z / n);
        let cxx = self.sum_xx / n - mx * mx;
        let cxy = self.sum_xy / n - mx * my;
        let cyy = self.sum_yy / n - my * my;
        let cxz = self.sum_xz / n - mx * mz;
        let cyz = self.sum_yz / n - my * mz;
        let czz = self.sum_zz / n - mz * mz;
        let det = cxx * cyy - cxy * cxy;
        // Points on (nearly) one line leave the cross-slope undetermined: relative threshold
        // against the squared spread, so it does not depend on the cell size.
        if det <= 1e-9 * (cxx + cyy).powi(2) || det <= 0.0 {
            return None;
        }
        let gx = (cyy * cxz - cxy * cyz) / det;
        let gy = (cxx * cyz - cxy * cxz) / det;
        let residual_variance = (czz - gx * cxz - gy * cyz).max(0.0);
        Some(PlaneFit { gx, gy, residual_variance, offset: mz - gx * mx - gy * my })
    }

    /// Fuses another cell's points into this one (both relative to the same cell centre).
    pub fn merge(&mut self, other: &CellStats) {
        self.merge_offset(other, 0.0, 0.0);
    }

    /// Fuses the points of a cell whose centre lies at `(dx, dy)` from this cell's centre, so
    /// that the result describes all the points relative to this cell's centre (used to fit a
    /// plane over a block of cells).
    pub fn merge_offset(&mut self, other: &CellStats, dx: f64, dy: f64) {
        if other.count == 0 {
            return;
        }
        let was_empty = self.count == 0;
        if was_empty {
            self.z_ref = other.z_ref;
        }
        let n = other.count as f64;
        // Heights re-expressed relative to this cell's reference.
        let shift = other.z_ref - self.z_ref;
        let sum_z = other.sum_z + n * shift;
        let sum_zz = other.sum_zz + 2.0 * shift * other.sum_z + n * shift * shift;
        let sum_xz = other.sum_xz + shift * other.sum_x;
        let sum_yz = other.sum_yz + shift * other.sum_y;
        // Positions re-expressed relative to this cell's centre.
        self.sum_xx += other.sum_xx + 2.0 * dx * other.sum_x + n * dx * dx;
        self.sum_yy += other.sum_yy + 2.0 * dy * other.sum_y + n * dy * dy;
        self.sum_xy += other.sum_xy + dx * other.sum_y + dy * other.sum_x + n * dx * dy;
        self.sum_xz += sum_xz + dx * sum_z;
        self.sum_yz += sum_yz + dy * sum_z;
        self.sum_x += other.sum_x + n * dx;
        self.sum_y += other.sum_y + n * dy;
        self.sum_z += sum_z;
        self.sum_zz += sum_zz;
        self.sum_noise_var += other.sum_noise_var;
        if was_empty {
            self.min_z = other.min_z;
            self.max_z = other.max_z;
        } else {
            self.min_z = self.min_z.min(other.min_z);
            self.max_z = self.max_z.max(other.max_z);
        }
        self.count += other.count;
    }

    /// Mean squared height of this cell's points about a plane fitted (possibly over a larger
    /// block) relative to this cell's centre and reference height (m^2).
    pub fn mean_square_residual(&self, fit: &PlaneFit, fit_reference: f64) -> Option<f64> {
        if self.count == 0 {
            return None;
        }
        let n = self.count as f64;
        // Plane height at the cell centre relative to this cell's reference.
        let z0 = fit.offset + fit_reference - self.z_ref;
        let (gx, gy) = (fit.gx, fit.gy);
        let s = self.sum_zz - 2.0 * z0 * self.sum_z - 2.0 * gx * self.sum_xz - 2.0 * gy * self.sum_yz
            + n * z0 * z0
            + 2.0 * z0 * gx * self.sum_x
            + 2.0 * z0 * gy * self.sum_y
            + gx * gx * self.sum_xx
            + 2.0 * gx * gy * self.sum_xy
            + gy * gy * self.sum_yy;
        Some((s / n).max(0.0))
    }

    /// Reference height the sums are relative to (m).
    pub fn reference_height(&self) -> f64 {
        self.z_ref
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_variance_is_the_mean_of_the_points_and_survives_merging() {
        let mut a = CellStats::EMPTY;
        assert_eq!(a.noise_variance(), None);
        a.add_with_noise(0.0, 0.0, 1.0, 4e-4);
        a.add(0.01, 0.0, 1.1);
        assert!((a.noise_variance().unwrap() - 2e-4).abs() < 1e-12);
        let mut b = CellStats::EMPTY;
        b.add_with_noise(0.0, 0.01, 0.9, 1e-4);
        b.add_with_noise(0.0, 0.0, 0.9, f64::NAN);
        a.merge(&b);
        // (4e-4 + 0 + 1e-4 + 0) over four points; the unusable figure counts as zero.
        assert!((a.noise_variance().unwrap() - 1.25e-4).abs() < 1e-12);
        assert_eq!(a.count, 4);
    }

    #[test]
    fn mean_variance_and_extremes_match_hand_values() {
        let mut c = CellStats::EMPTY;
        for z in [1000.0, 1000.2, 1000.4, 1000.6] {
            c.add(0.0, 0.0, z);
        }
        assert!((c.mean().unwrap() - 1000.3).abs() < 1e-9);
        // Heights 0, 0.2, 0.4, 0.6 about their mean: variance (0.09+0.01+0.01+0.09)/4 = 0.05.
        assert!((c.variance().unwrap() - 0.05).abs() < 1e-9);
        assert_eq!((c.min_z, c.max_z), (1000.0, 1000.6));
        assert!(CellStats::EMPTY.mean().is_none());
    }

    #[test]
    fn plane_fit_recovers_a_tilted_plane_exactly() {
        let mut c = CellStats::EMPTY;
        let (gx, gy) = (0.3, -0.1);
        for i in 0..5 {
            for j in 0..5 {
                let (x, y) = (i as f64 * 0.03 - 0.06, j as f64 * 0.03 - 0.06);
                c.add(x, y, -4500.0 + gx * x + gy * y);
            }
        }
        let p = c.plane_fit().unwrap();
        assert!((p.gx - gx).abs() < 1e-6 && (p.gy - gy).abs() < 1e-6);
        assert!(p.residual_variance < 1e-9);
        assert!((p.slope() - (0.1f64.hypot(0.3)).atan()).abs() < 1e-6);
    }

    #[test]
    fn collinear_points_give_no_plane() {
        let mut c = CellStats::EMPTY;
        for i in 0..5 {
            c.add(i as f64 * 0.01, 0.0, i as f64);
        }
        assert!(c.plane_fit().is_none());
    }

    #[test]
    fn offset_merge_fits_a_plane_across_cells_and_measures_residuals() {
        // Two cells 0.15 m apart along x on the plane z = 7 + 0.2 x (world x).
        let (mut a, mut b) = (CellStats::EMPTY, CellStats::EMPTY);
        for (i, j) in [(-1.0, -1.0), (1.0, -1.0), (0.0, 1.0), (1.0, 1.0)] {
            let (dx, dy) = (0.03 * i, 0.03 * j);
            a.add(dx, dy, 7.0 + 0.2 * dx);
            b.add(dx, dy, 7.0 + 0.2 * (0.15 + dx) + if i > 0.0 { 0.01 } else { -0.01 });
        }
        let mut block = a;
        block.merge_offset(&b, 0.15, 0.0);
        assert_eq!(block.count, 8);
        let fit = block.plane_fit().unwrap();
        assert!((fit.gx - 0.2).abs() < 0.2 && fit.gy.abs() < 0.5);
        // Against the exact plane, cell b's points deviate by exactly +-0.01 m.
        let exact = PlaneFit { gx: 0.2, gy: 0.0, residual_variance: 0.0, offset: 0.0 };
        let b_ref = b.reference_height();
        let at_b = PlaneFit { offset: 7.0 + 0.2 * 0.15 - b_ref, ..exact };
        assert!((b.mean_square_residual(&at_b, b_ref).unwrap() - 1e-4).abs() < 1e-12);
        let at_a = PlaneFit { offset: 7.0 - a.reference_height(), ..exact };
        assert!(a.mean_square_residual(&at_a, a.reference_height()).unwrap() < 1e-12);
    }

    #[test]
    fn merge_equals_adding_all_points_to_one_cell() {
        let pts =
            [(0.01, 0.02, 5.0), (-0.03, 0.05, 5.3), (0.04, -0.06, 4.8), (0.0, 0.0, 9.0), (0.02, 0.07, 7.5)];
        let mut all = CellStats::EMPTY;
        let (mut a, mut b) = (CellStats::EMPTY, CellStats::EMPTY);
        for (k, &(x, y, z)) in pts.iter().enumerate() {
            all.add(x, y, z);
            if k < 2 { a.add(x, y, z) } else { b.add(x, y, z) }
        }
        a.merge(&b);
        assert_eq!(a.count, all.count);
        assert!((a.mean().unwrap() - all.mean().unwrap()).abs() < 1e-12);
        assert!((a.variance().unwrap() - all.variance().unwrap()).abs() < 1e-9);
        let (pa, pb) = (a.plane_fit().unwrap(), all.plane_fit().unwrap());
        assert!((pa.gx - pb.gx).abs() < 1e-9 && (pa.gy - pb.gy).abs() < 1e-9);
    }
}
