//! Filter consistency checks: the normalised estimation error squared (NEES) of a position
//! estimate against the truth and the chi-square bounds an honest covariance keeps it within
//! (Bar-Shalom, Li and Kirubarajan, "Estimation with Applications to Tracking and
//! Navigation", section 5.4: the mean NEES of N independent runs of an n-dimensional state is
//! chi-square with N n degrees of freedom, divided by N).
//!
//! Quantiles use the Wilson-Hilferty cube-root approximation with the normal quantile of
//! Abramowitz and Stegun 26.2.23 (error below 4.5e-4 in z): within 0.1 % of the tables for
//! the degrees of freedom used here (2 to a few hundred); exact for 2 degrees of freedom.

use rovernav_core::{Pose3, PoseEstimate};

/// The position NEES of `estimate` against the true position of `truth`: e^T P^-1 e with the
/// covariance's (x, y) block (2 on average for an honest covariance); `None` when that block
/// is singular.
pub fn position_nees(estimate: &PoseEstimate, truth: &Pose3) -> Option<f64> {
    let c = &estimate.covariance;
    let block = [[c[0][0], c[0][1]], [c[1][0], c[1][1]]];
    let det = c[0][0] * c[1][1] - c[0][1] * c[1][0];
    squared_mahalanobis_2d(estimate.pose.x - truth.x, estimate.pose.y - truth.y, &block)
        .filter(|_| det.is_finite())
}

/// e^T S^-1 e for a 2-vector `(ex, ey)` and a 2x2 covariance `s`; `None` when `s` is singular
/// or not positive definite by its determinant.
pub fn squared_mahalanobis_2d(ex: f64, ey: f64, s: &[[f64; 2]; 2]) -> Option<f64> {
    let det = s[0][0] * s[1][1] - s[0][1] * s[1][0];
    (det > 0.0).then(|| (s[1][1] * ex * ex - (s[0][1] + s[1][0]) * ex * ey + s[0][0] * ey * ey) / det)
}

/// The covariance intersection weight of two 2x2 position covariances `p` (the filter's) and
/// `r` (a fix's) whose errors may be correlated in any way (Julier and Uhlmann, "A
/// non-divergent estimation algorithm in the presence of unknown correlations", 1997): the
/// omega in [0.01, 1] that minimises the determinant of (omega p^-1 + (1 - omega) r^-1)^-1.
/// Fusing with `p / omega` and `r / (1 - omega)` as if independent gives that intersection;
/// omega = 1 means the fix adds nothing (fusing it would only inflate the filter). The grid
/// stops at 0.01 rather than 0 because `p / omega` must stay finite.
/// `None` when either matrix is singular.
pub fn covariance_intersection_weight(p: &[[f64; 2]; 2], r: &[[f64; 2]; 2]) -> Option<f64> {
    let inverse = |m: &[[f64; 2]; 2]| {
        let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
        (det > 0.0 && det.is_finite())
            .then(|| [[m[1][1] / det, -m[0][1] / det], [-m[1][0] / det, m[0][0] / det]])
    };
    let (a, b) = (inverse(p)?, inverse(r)?);
    // det(omega a + (1 - omega) b) is a quadratic in omega: the best of a fine grid.
    let information = |w: f64| {
        let m = |i: usize, j: usize| w * a[i][j] + (1.0 - w) * b[i][j];
        m(0, 0) * m(1, 1) - m(0, 1) * m(1, 0)
    };
    (1..=100).map(|k| f64::from(k) / 100.0).max_by(|x, y| information(*x).total_cmp(&information(*y)))
}

/// The standard normal quantile at `p` in (0, 1) (Abramowitz and Stegun 26.2.23).
pub fn normal_quantile(p: f64) -> f64 {
    let p = p.clamp(1e-300, 1.0 - 1e-16);
    let tail = |q: f64| {
        let t = (-2.0 * q.ln()).sqrt();
        t - (2.515517 + 0.802853 * t + 0.010328 * t * t)
            / (1.0 + 1.432788 * t + 0.189269 * t * t + 0.001308 * t.powi(3))
    };
    if p < 0.5 { -tail(p) } else { tail(1.0 - p) }
}

/// The chi-square quantile at probability `p` with `dof` degrees of freedom.
pub fn chi_square_quantile(p: f64, dof: f64) -> f64 {
    if dof == 2.0 {
        return -2.0 * (1.0 - p).ln();
    }
    let a = 2.0 / (9.0 * dof);
    dof * (1.0 - a + normal_quantile(p) * a.sqrt()).powi(3).max(0.0)
}

/// The two-sided `confidence` bounds (e.g. 0.95) of the mean NEES of `runs` independent runs
/// of a `dim`-dimensional error.
pub fn mean_nees_bounds(runs: usize, dim: usize, confidence: f64) -> (f64, f64) {
    let n = runs.max(1) as f64;
    let dof = n * dim as f64;
    let tail = 0.5 * (1.0 - confidence);
    (chi_square_quantile(tail, dof) / n, chi_square_quantile(1.0 - tail, dof) / n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_match_the_tables() {
        // Tables (e.g. NIST/SEMATECH e-Handbook 1.3.6.7.4).
        for (p, dof, table) in [
            (0.975, 40.0, 59.342),
            (0.025, 40.0, 24.433),
            (0.999, 2.0, 13.816),
            (0.95, 10.0, 18.307),
            (0.05, 100.0, 77.929),
            (0.975, 4.0, 11.143),
        ] {
            let q = chi_square_quantile(p, dof);
            assert!((q - table).abs() < 2e-3 * table, "chi2({dof}) at {p}: {q} against {table}");
        }
        assert!((normal_quantile(0.975) - 1.95996).abs() < 5e-4);
        assert!((normal_quantile(0.5)).abs() < 1e-3);
        let (lo, hi) = mean_nees_bounds(20, 2, 0.95);
        assert!((lo - 24.433 / 20.0).abs() < 0.01 && (hi - 59.342 / 20.0).abs() < 0.01, "{lo} {hi}");
    }

    #[test]
    fn the_intersection_weight_maximises_the_fused_information() {
        // Diagonal p = diag(1, 9), r = diag(4, 1): det((w/p1 + (1-w)/r1)(w/p2 + (1-w)/r2)) is a
        // downward parabola in w with its vertex at -(c1 d2 + c2 d1) / (2 d1 d2), c = 1/r,
        // d = 1/p - 1/r: 0.3958.
        let w = covariance_intersection_weight(&[[1.0, 0.0], [0.0, 9.0]], &[[4.0, 0.0], [0.0, 1.0]]).unwrap();
        assert!((w - 0.3958).abs() < 0.006, "{w}");
        // Mirror images weigh half; a fix worse in every direction weighs (almost) nothing.
        let w = covariance_intersection_weight(&[[1.0, 0.0], [0.0, 4.0]], &[[4.0, 0.0], [0.0, 1.0]]).unwrap();
        assert!((w - 0.5).abs() < 1e-9, "{w}");
        let tight = [[0.01, 0.0], [0.0, 0.01]];
        assert_eq!(
            covariance_intersection_weight(&tight, &[[1.0, 0.0], [0.0, 1.0]]),
            Some(1.0),
            "a fix far wider than the filter adds nothing"
        );
        assert!(covariance_intersection_weight(&tight, &[[0.0; 2]; 2]).is_none());
    }

    #[test]
    fn nees_is_the_mahalanobis_length_of_the_error() {
        let estimate = PoseEstimate {
            pose: Pose3 { x: 1.0, y: 2.0, ..Default::default() },
            covariance: [[4.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        };
        let truth = Pose3 { x: 3.0, y: 1.0, ..Default::default() };
        assert!((position_nees(&estimate, &truth).unwrap() - (4.0 / 4.0 + 1.0 / 1.0)).abs() < 1e-12);
        let flat = PoseEstimate { covariance: [[0.0; 3]; 3], ..estimate };
        assert!(position_nees(&flat, &truth).is_none());
    }
}
