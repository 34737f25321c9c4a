//! Finite-difference check of a term's Jacobian.

use super::assembly::eval_term;
use super::problem::Term;
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

/// The residuals of a term at `x` (inactive ones 0; no `prepare`).
pub fn residuals(term: &dyn Term, x: &[f64]) -> Vec<f64> {
    let m = term.residual_count();
    let mut r = vec![0.0; m];
    let mut active = vec![true; m];
    let (mut rows, mut cols, mut vals) = (Vec::new(), Vec::new(), Vec::new());
    eval_term(term, x, &mut r, &mut active, &mut rows, &mut cols, &mut vals, 0);
    r
}

/// The analytic and the central-difference Jacobian of a term at `x`, dense and column-major
/// (entry (i, j) at `j * m + i`, m = `term.residual_count()`). With `moving`, the term is
/// prepared at every perturbed point (its targets move with the variables, as between two
/// solver iterations) and again at `x` after; without it the targets stay those of `x`.
/// Inactive residuals count as 0 with a zero Jacobian row.
pub fn jacobians(term: &mut dyn Term, x: &[f64], h: f64, moving: bool) -> (Vec<f64>, Vec<f64>) {
    let m = term.residual_count();
    let n = x.len();
    let mut r = vec![0.0; m];
    let mut active = vec![true; m];
    let (mut rows, mut cols, mut vals) = (Vec::new(), Vec::new(), Vec::new());
    term.prepare(x);
    eval_term(&*term, x, &mut r, &mut active, &mut rows, &mut cols, &mut vals, 0);
    let mut analytic = vec![0.0; m * n];
    for ((&i, &j), &v) in rows.iter().zip(&cols).zip(&vals) {
        if active[i as usize] {
            analytic[j as usize * m + i as usize] += v;
        }
    }
    let mut numeric = vec![0.0; m * n];
    let mut xp = x.to_vec();
    let (mut rp, mut rm) = (vec![0.0; m], vec![0.0; m]);
    for j in 0..n {
        for (sign, out) in [(1.0, &mut rp), (-1.0, &mut rm)] {
            xp[j] = x[j] + sign * h;
            if moving {
                term.prepare(&xp);
            }
            rows.clear();
            cols.clear();
            vals.clear();
            eval_term(&*term, &xp, out, &mut active, &mut rows, &mut cols, &mut vals, 0);
        }
        xp[j] = x[j];
        let dh = (x[j] + h) - (x[j] - h);
        for i in 0..m {
            numeric[j * m + i] = (rp[i] - rm[i]) / dh;
        }
    }
    if moving {
        term.prepare(x);
    }
    (analytic, numeric)
}
