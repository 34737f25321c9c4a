//! A scalar tensor-product B-spline function g(u, v) = Σ N_k(u) M_l(v) g_kl (Eq. 8's radius
//! function), its gradient, the linear map from coefficients to (g, g_u, g_v) at a parameter, and
//! the least-squares fit of samples.

// Negated float comparisons are deliberate: they also reject NaN.

use super::basis::{BSplineBasis, BasisValues};
use faer::prelude::SolveLstsq;
use faer::Mat;

/// The coefficients a parameter's value and first derivatives depend on: g = Σ value[k] c[index[k]],
/// g_u = Σ du[k] c[index[k]], g_v = Σ dv[k] c[index[k]].
#[derive(Clone, Debug, PartialEq)]
pub struct FunctionRow {
    pub index: Vec<usize>,
    pub value: Vec<f64>,
    pub du: Vec<f64>,
    pub dv: Vec<f64>,
}

impl FunctionRow {
    /// (g, g_u, g_v) for coefficients `c`.
    pub(crate) fn apply(&self, c: &[f64]) -> (f64, f64, f64) {
        let mut out = (0.0, 0.0, 0.0);
        for (k, &i) in self.index.iter().enumerate() {
            out.0 += self.value[k] * c[i];
            out.1 += self.du[k] * c[i];
            out.2 += self.dv[k] * c[i];
        }
        out
    }
}

/// A scalar B-spline function on two bases; coefficient (k, l), k along U, at k + n_u l.
#[derive(Clone, Debug, PartialEq)]
pub struct BSplineFunction {
    pub u: BSplineBasis,
    pub v: BSplineBasis,
    pub coefficients: Vec<f64>,
}

/// How well a least-squares fit matches its samples.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FitError {
    pub max: f64,
    pub rms: f64,
}

impl BSplineFunction {
    /// The constant function `value` on the domain (degree 1, a 2 × 2 grid of coefficients).
    pub fn constant(value: f64, (u, v): ((f64, f64), (f64, f64))) -> Self {
        let basis = |d| BSplineBasis::clamped_uniform(1, 2, d).expect("a linear basis on a domain");
        Self { u: basis(u), v: basis(v), coefficients: vec![value; 4] }
    }

    /// The function times `factor`.
    pub fn scaled(&self, factor: f64) -> Self {
        Self { coefficients: self.coefficients.iter().map(|c| c * factor).collect(), ..self.clone() }
    }

    /// The row of parameter (u, v) (clamped to the domain).
    pub fn row(u: &BSplineBasis, v: &BSplineBasis, s: f64, t: f64) -> FunctionRow {
        Self::row_with(u.count(), &u.evaluate(s), &v.evaluate(t))
    }

    fn row_with(nu: usize, bu: &BasisValues, bv: &BasisValues) -> FunctionRow {
        let n = bu.count * bv.count;
        let mut row =
            FunctionRow { index: Vec::with_capacity(n), value: Vec::with_capacity(n), du: Vec::with_capacity(n), dv: Vec::with_capacity(n) };
        for jb in 0..bv.count {
            for ib in 0..bu.count {
                row.index.push(bu.first + ib + nu * (bv.first + jb));
                row.value.push(bu.values[0][ib] * bv.values[0][jb]);
                row.du.push(bu.values[1][ib] * bv.values[0][jb]);
                row.dv.push(bu.values[0][ib] * bv.values[1][jb]);
            }
        }
        row
    }

    /// (g, g_u, g_v) at (s, t).
    pub fn evaluate(&self, s: f64, t: f64) -> (f64, f64, f64) {
        Self::row(&self.u, &self.v, s, t).apply(&self.coefficients)
    }

    /// The least-squares fit of `samples` ((u, v), value) on the bases; None when the samples do
    /// not determine the coefficients (too few, or none under some basis function).
    pub fn fit(u: BSplineBasis, v: BSplineBasis, samples: &[([f64; 2], f64)]) -> Option<(Self, FitError)> {
        let n = u.count() * v.count();
        let m = samples.len();
        if m < n || samples.iter().any(|(uv, g)| !(uv[0].is_finite() && uv[1].is_finite() && g.is_finite())) {
            return None;
        }
        let mut a = Mat::<f64>::zeros(m, n);
        let mut b = Mat::<f64>::zeros(m, 1);
        for (i, (uv, value)) in samples.iter().enumerate() {
            let row = Self::row(&u, &v, uv[0], uv[1]);
            for (k, &c) in row.index.iter().enumerate() {
                a[(i, c)] = row.value[k];
            }
            b[(i, 0)] = *value;
        }
        let qr = a.col_piv_qr();
        // Rank: |R_kk| relative to |R_00| (column pivoting sorts them).
        let r = qr.R();
        let r0 = r[(0, 0)].abs();
        if !(r0 > 0.0) || (0..n).any(|k| !(r[(k, k)].abs() > 1e-12 * r0)) {
            return None;
        }
        let x = qr.solve_lstsq(&b);
        let coefficients: Vec<f64> = (0..n).map(|k| x[(k, 0)]).collect();
        if coefficients.iter().any(|c| !c.is_finite()) {
            return None;
        }
        let f = Self { u, v, coefficients };
        let (mut max, mut sum) = (0.0f64, 0.0);
        for (uv, value) in samples {
            let e = (f.evaluate(uv[0], uv[1]).0 - value).abs();
            max = max.max(e);
            sum += e * e;
        }
        Some((f, FitError { max, rms: (sum / m as f64).sqrt() }))
    }
}
