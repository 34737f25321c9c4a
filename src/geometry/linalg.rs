//! Small dense linear algebra in f64: Householder least squares (column-major, m × n with
//! n ≤ [`MAX_COLS`], no allocation) for the jet fit, a closed-form symmetric 2×2 and a cyclic
//! Jacobi symmetric 3×3 eigen-decomposition, and a one-sided Jacobi SVD ([`Svd`]) of m × N
//! matrices (N ≤ 5 in practice) for the null vectors of the sphere systems, to high relative
//! accuracy.

// Negated float comparisons are deliberate: they also reject NaN.

use glam::DVec3;

/// Most unknowns of [`lstsq_householder`] (a degree-4 jet has 15).
pub const MAX_COLS: usize = 15;

/// Least squares min ‖A x − b‖ by Householder QR, in place.
///
/// `a` is column-major m × n (column j is `a[j*m..(j+1)*m]`), `b` has m entries, the solution goes to
/// `x[..n]`. Returns false (and leaves `x` unspecified) when m < n, n > [`MAX_COLS`], or A is
/// numerically rank deficient: a diagonal entry of R below `rank_tol` times the norm of its original
/// column (so the test is invariant to column scaling). Never produces NaN from finite input: on
/// false the caller must not use `x`.
pub fn lstsq_householder(a: &mut [f64], m: usize, n: usize, b: &mut [f64], x: &mut [f64], rank_tol: f64) -> bool {
    if n == 0 || m < n || n > MAX_COLS || a.len() < m * n || b.len() < m || x.len() < n {
        return false;
    }
    let mut col_norm = [0.0f64; MAX_COLS];
    for (j, cn) in col_norm.iter_mut().enumerate().take(n) {
        *cn = dot(&a[j * m..(j + 1) * m], &a[j * m..(j + 1) * m]).sqrt();
    }
    let mut diag = [0.0f64; MAX_COLS];
    for k in 0..n {
        // Householder vector for column k, rows k..m, stored in place (v has v[k] = x_k − α).
        let (head, tail) = a.split_at_mut((k + 1) * m);
        let col = &mut head[k * m..];
        let sigma = dot(&col[k..m], &col[k..m]).sqrt();
        if !(sigma > rank_tol * col_norm[k]) || sigma == 0.0 {
            return false;
        }
        let alpha = if col[k] > 0.0 { -sigma } else { sigma };
        col[k] -= alpha;
        // vᵀv = 2σ(σ + |x_k|) > 0: no cancellation since α has the opposite sign of x_k.
        let vtv = 2.0 * sigma * (sigma + (col[k] + alpha).abs());
        if !(vtv > 0.0) {
            return false;
        }
        diag[k] = alpha;
        // Apply H = I − 2 v vᵀ / vᵀv to the remaining columns and to b.
        for j in k + 1..n {
            let cj = &mut tail[(j - k - 1) * m..(j - k) * m];
            let s = 2.0 * dot(&col[k..m], &cj[k..m]) / vtv;
            axpy(-s, &col[k..m], &mut cj[k..m]);
        }
        let s = 2.0 * dot(&col[k..m], &b[k..m]) / vtv;
        axpy(-s, &col[k..m], &mut b[k..m]);
    }
    // Back substitution R x = Qᵀ b (R's diagonal in `diag`, above it in `a`).
    for k in (0..n).rev() {
        let mut s = b[k];
        for j in k + 1..n {
            s -= a[j * m + k] * x[j];
        }
        x[k] = s / diag[k];
    }
    x[..n].iter().all(|v| v.is_finite())
}

/// Dot product with four accumulators (vectorizes; the inputs are preconditioned, O(1) values, so
/// no overflow scaling is needed: a non-finite result fails the rank test).
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut acc = [0.0f64; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for k in 0..4 {
            acc[k] += x[k] * y[k];
        }
    }
    let mut s = (acc[0] + acc[1]) + (acc[2] + acc[3]);
    for (x, y) in ra.iter().zip(rb) {
        s += x * y;
    }
    s
}

/// y += s x.
fn axpy(s: f64, x: &[f64], y: &mut [f64]) {
    for (yi, xi) in y.iter_mut().zip(x) {
        *yi += s * xi;
    }
}

/// Eigen-decomposition of the symmetric 2×2 matrix [[p, q], [q, r]]: (λ1, λ2, (c, s)) with
/// λ1 ≥ λ2 and (c, s) the unit eigenvector of λ1 ((−s, c) belongs to λ2). Umbilic (λ1 = λ2) gives
/// (1, 0).
pub(crate) fn sym2_eigen(p: f64, q: f64, r: f64) -> (f64, f64, (f64, f64)) {
    let mean = 0.5 * (p + r);
    let half_diff = 0.5 * (p - r);
    let d = half_diff.hypot(q);
    let theta = 0.5 * q.atan2(half_diff);
    (mean + d, mean - d, (theta.cos(), theta.sin()))
}

/// Eigen-decomposition of a symmetric 3×3 matrix by cyclic Jacobi rotations: eigenvalues ascending
/// and the matching orthonormal eigenvectors.
pub(crate) fn sym3_eigen(m: [[f64; 3]; 3]) -> ([f64; 3], [DVec3; 3]) {
    let mut a = m;
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _sweep in 0..32 {
        let off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
        let diag = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
        if !(off > 1e-30 * diag) {
            break;
        }
        for (p, q) in [(0usize, 1usize), (0, 2), (1, 2)] {
            if a[p][q] == 0.0 {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            // A ← Jᵀ A J with J the rotation in the (p, q) plane.
            for k in 0..3 {
                let (akp, akq) = (a[k][p], a[k][q]);
                a[k][p] = c * akp - s * akq;
                a[k][q] = s * akp + c * akq;
            }
            for k in 0..3 {
                let (apk, aqk) = (a[p][k], a[q][k]);
                a[p][k] = c * apk - s * aqk;
                a[q][k] = s * apk + c * aqk;
            }
            for row in &mut v {
                let (vp, vq) = (row[p], row[q]);
                row[p] = c * vp - s * vq;
                row[q] = s * vp + c * vq;
            }
        }
    }
    let mut idx = [0usize, 1, 2];
    idx.sort_by(|&i, &j| a[i][i].total_cmp(&a[j][j]));
    let vals = idx.map(|i| a[i][i]);
    let vecs = idx.map(|i| DVec3::new(v[0][i], v[1][i], v[2][i]));
    (vals, vecs)
}

/// Singular values (descending) and matching right singular vectors `v[j]` of an m × N
/// matrix given by rows (m may be smaller than N: the missing singular values are 0).
#[derive(Clone, Debug)]
pub struct Svd<const N: usize> {
    pub sigma: [f64; N],
    pub v: [[f64; N]; N],
}

impl<const N: usize> Svd<N> {
    /// One-sided (Hestenes) Jacobi: rotate column pairs of A until all are orthogonal to
    /// `f64::EPSILON` relative; the column norms are the singular values and the accumulated
    /// rotations the right singular vectors.
    pub fn new(rows: &[[f64; N]]) -> Self {
        let mut a: Vec<[f64; N]> = rows.to_vec();
        let mut v = [[0.0; N]; N];
        for (i, row) in v.iter_mut().enumerate() {
            row[i] = 1.0;
        }
        // v is stored by columns: v[j] is column j (a right singular vector).
        // A column at the rounding level of A is a null direction: rotating it against another
        // column would only move the null vector by O(ε) (and never terminates: the rounding
        // noise stays parallel to the other column), so such pairs are skipped.
        let norm2: f64 = a.iter().flat_map(|r| r.iter()).map(|x| x * x).sum();
        let negligible = (8.0 * f64::EPSILON) * (8.0 * f64::EPSILON) * norm2;
        for _sweep in 0..60 {
            let mut rotated = false;
            for p in 0..N {
                for q in p + 1..N {
                    let (mut alpha, mut beta, mut gamma) = (0.0, 0.0, 0.0);
                    for r in &a {
                        alpha += r[p] * r[p];
                        beta += r[q] * r[q];
                        gamma += r[p] * r[q];
                    }
                    if gamma == 0.0 || gamma.abs() <= 8.0 * f64::EPSILON * (alpha * beta).sqrt() || alpha.min(beta) <= negligible {
                        continue;
                    }
                    rotated = true;
                    let zeta = (beta - alpha) / (2.0 * gamma);
                    let t = zeta.signum() / (zeta.abs() + (1.0 + zeta * zeta).sqrt());
                    let c = 1.0 / (1.0 + t * t).sqrt();
                    let s = c * t;
                    for r in a.iter_mut() {
                        let (x, y) = (r[p], r[q]);
                        r[p] = c * x - s * y;
                        r[q] = s * x + c * y;
                    }
                    let (vp, vq) = (v[p], v[q]);
                    for k in 0..N {
                        v[p][k] = c * vp[k] - s * vq[k];
                        v[q][k] = s * vp[k] + c * vq[k];
                    }
                }
            }
            if !rotated {
                break;
            }
        }
        let mut sigma = [0.0; N];
        for (j, s) in sigma.iter_mut().enumerate() {
            *s = a.iter().map(|r| r[j] * r[j]).sum::<f64>().sqrt();
        }
        let mut order: [usize; N] = [0; N];
        for (i, o) in order.iter_mut().enumerate() {
            *o = i;
        }
        order.sort_by(|&i, &j| sigma[j].partial_cmp(&sigma[i]).unwrap_or(std::cmp::Ordering::Equal));
        Svd { sigma: order.map(|i| sigma[i]), v: order.map(|i| v[i]) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn householder_solves_overdetermined_system() {
        // Fit y = 1 + 2x − 3x² exactly from 7 samples, with a huge column scale difference.
        let xs = [-3.0, -2.0, -1.0, 0.0, 0.5, 1.0, 2.5];
        let m = xs.len();
        let mut a = vec![0.0; m * 3];
        let mut b = vec![0.0; m];
        for (i, &x) in xs.iter().enumerate() {
            a[i] = 1.0;
            a[m + i] = 1e6 * x;
            a[2 * m + i] = x * x;
            b[i] = 1.0 + 2.0 * x - 3.0 * x * x;
        }
        let mut sol = [0.0; 3];
        assert!(lstsq_householder(&mut a, m, 3, &mut b, &mut sol, 1e-12));
        assert!((sol[0] - 1.0).abs() < 1e-12 && (sol[1] * 1e6 - 2.0).abs() < 1e-12 && (sol[2] + 3.0).abs() < 1e-12);
    }

    #[test]
    fn householder_least_squares_matches_normal_equations() {
        // Line fit through 4 points: known closed form.
        let pts = [(0.0, 1.0), (1.0, 2.0), (2.0, 2.0), (3.0, 4.0)];
        let m = pts.len();
        let mut a = vec![0.0; m * 2];
        let mut b = vec![0.0; m];
        for (i, &(x, y)) in pts.iter().enumerate() {
            a[i] = 1.0;
            a[m + i] = x;
            b[i] = y;
        }
        let mut sol = [0.0; 2];
        assert!(lstsq_householder(&mut a, m, 2, &mut b, &mut sol, 1e-12));
        // slope = cov/var = (Σxy − n x̄ ȳ)/(Σx² − n x̄²) = (19 − 4·1.5·2.25)/(14 − 9) = 0.9
        assert!((sol[1] - 0.9).abs() < 1e-14 && (sol[0] - (2.25 - 0.9 * 1.5)).abs() < 1e-14);
    }

    #[test]
    fn householder_detects_rank_deficiency() {
        let m = 5;
        let mut a = vec![0.0; m * 3];
        let mut b = vec![1.0; m];
        for i in 0..m {
            a[i] = 1.0;
            a[m + i] = i as f64;
            a[2 * m + i] = 2.0 * i as f64 - 1.0; // = 2·col1 − col0
        }
        let mut sol = [0.0; 3];
        assert!(!lstsq_householder(&mut a, m, 3, &mut b, &mut sol, 1e-10));
        let mut a = vec![0.0; 6];
        assert!(!lstsq_householder(&mut a, 3, 2, &mut [0.0; 3], &mut sol, 1e-10));
        assert!(!lstsq_householder(&mut [1.0; 2], 1, 2, &mut [0.0; 1], &mut sol, 1e-10));
    }

    #[test]
    fn sym2() {
        let (l1, l2, (c, s)) = sym2_eigen(2.0, 1.0, 2.0);
        assert!((l1 - 3.0).abs() < 1e-15 && (l2 - 1.0).abs() < 1e-15);
        assert!((c - s).abs() < 1e-15 && (c * c + s * s - 1.0).abs() < 1e-15);
        let (l1, l2, (c, s)) = sym2_eigen(-1.0, 0.0, 4.0);
        assert_eq!((l1, l2), (4.0, -1.0));
        assert!(c.abs() < 1e-15 && (s.abs() - 1.0).abs() < 1e-15);
        let (l1, l2, (c, _)) = sym2_eigen(0.5, 0.0, 0.5);
        assert_eq!((l1, l2, c), (0.5, 0.5, 1.0));
        // Generic: A v = λ v.
        let (p, q, r) = (0.3, -1.7, 2.2);
        let (l1, l2, (c, s)) = sym2_eigen(p, q, r);
        assert!((p * c + q * s - l1 * c).abs() < 1e-14 && (q * c + r * s - l1 * s).abs() < 1e-14);
        assert!((-p * s + q * c + l2 * s).abs() < 1e-14 && (-q * s + r * c - l2 * c).abs() < 1e-14);
    }

    #[test]
    fn sym3() {
        let m = [[4.0, 1.0, -2.0], [1.0, 2.0, 0.5], [-2.0, 0.5, 3.0]];
        let (vals, vecs) = sym3_eigen(m);
        assert!(vals[0] <= vals[1] && vals[1] <= vals[2]);
        for k in 0..3 {
            let v = vecs[k];
            let mv = DVec3::new(
                m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z,
                m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
                m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z,
            );
            assert!((mv - vals[k] * v).length() < 1e-12);
            assert!((v.length() - 1.0).abs() < 1e-12);
        }
        assert!((vals.iter().sum::<f64>() - 9.0).abs() < 1e-12);
        let (vals, _) = sym3_eigen([[0.0; 3]; 3]);
        assert_eq!(vals, [0.0; 3]);
    }
}
