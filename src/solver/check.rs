//! Finite-difference check of a term's Jacobian.

use super::assembly::eval_term;
use super::Term;
use serde::{Deserialize, Serialize};

/// Worst disagreement between the analytic Jacobian and central differences.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct JacobianCheck {
    /// max over entries of |J − J_fd| / max(1, |J_fd|).
    pub max_error: f64,
    /// Where it occurs (local row, variable).
    pub row: usize,
    pub col: usize,
    pub analytic: f64,
    pub numeric: f64,
}

/// Max relative error of the term's Jacobian at `x` against central differences with step `h`:
/// max over all (row, variable) of |J − J_fd| / max(1, |J_fd|) (relative for entries above 1,
/// absolute below). Every variable is perturbed, so a missing Jacobian column is caught too.
/// Inactive residuals count as 0 with a zero Jacobian row, as in the solver; choose `x` away from
/// the kinks of one-sided terms.
pub fn check_jacobian(term: &dyn Term, x: &[f64], h: f64) -> f64 {
    check_jacobian_report(term, x, h).max_error
}

/// [`check_jacobian`] with the location of the worst entry.
pub fn check_jacobian_report(term: &dyn Term, x: &[f64], h: f64) -> JacobianCheck {
    let m = term.residual_count();
    let n = x.len();
    let mut r = vec![0.0; m];
    let mut active = vec![true; m];
    let (mut rows, mut cols, mut vals) = (Vec::new(), Vec::new(), Vec::new());
    eval_term(term, x, &mut r, &mut active, &mut rows, &mut cols, &mut vals, 0);
    let mut dense = vec![0.0; m * n];
    for ((&i, &j), &v) in rows.iter().zip(&cols).zip(&vals) {
        let (i, j) = (i as usize, j as usize);
        assert!(i < m && j < n, "Jacobian entry ({i}, {j}) out of range");
        if active[i] {
            dense[j * m + i] += v;
        }
    }
    let mut xp = x.to_vec();
    let (mut rp, mut rm) = (vec![0.0; m], vec![0.0; m]);
    let mut best = JacobianCheck::default();
    for j in 0..n {
        xp[j] = x[j] + h;
        rows.clear();
        cols.clear();
        vals.clear();
        eval_term(term, &xp, &mut rp, &mut active, &mut rows, &mut cols, &mut vals, 0);
        xp[j] = x[j] - h;
        rows.clear();
        cols.clear();
        vals.clear();
        eval_term(term, &xp, &mut rm, &mut active, &mut rows, &mut cols, &mut vals, 0);
        xp[j] = x[j];
        let dh = (x[j] + h) - (x[j] - h);
        for i in 0..m {
            let fd = (rp[i] - rm[i]) / dh;
            let an = dense[j * m + i];
            let err = (an - fd).abs() / fd.abs().max(1.0);
            if err > best.max_error || !err.is_finite() {
                best = JacobianCheck { max_error: err, row: i, col: j, analytic: an, numeric: fd };
                if !err.is_finite() {
                    best.max_error = f64::INFINITY;
                    return best;
                }
            }
        }
    }
    best
}
