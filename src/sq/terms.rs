//! The residual terms of the congruence optimization (Sec. 5.1) over the variable layout of
//! [`Layout`]: the radius coefficients r_kl (Eq. 8), a unit line direction l_ij per point of G,
//! and per grid quad its two torsal directions (μ0, μ1) and torsal-plane normals n*.
//!
//! - [`LineCongruence`] (E_LC): ⟨l, ĉ_u⟩ and ⟨l, ĉ_v⟩ with ĉ = c/|c| (c_u and c_v normalized, as
//!   the authors' code does), c_u = f_u + r_u n + r n_u.
//! - [`LineNormalAngle`] (E_LC_orth): ∠(l, n) ≤ θ as cos²θ − ⟨l, n⟩² ≤ 0 (hinge) or
//!   ⟨l, n⟩² − cos²θ − μ² (the paper's slack μ).
//! - [`TorsalDirection`] (E_torsal): ⟨l_t/|l_t|, n*⟩, ⟨l_c/|l_c|, n*⟩, ⟨t, n*⟩ and |t|² − 1, with
//!   t = μ0 d⁺ + μ1 d⁻ and l_t = μ0 l⁺ + μ1 l⁻ (Fig. 20, [`crate::congruence::torsal`]).
//! - [`TorsalAngle`] (E_angle): torsal planes meeting at ≥ α as ⟨n*₁, n*₂⟩² − cos²α ≤ 0 (hinge)
//!   or ⟨n*₁, n*₂⟩² − cos²α + ν² (slack ν).
//! - [`line_fairness`] (E_fair): second differences of the lines along both grid directions.
//!
//! Every term's Jacobian is checked against finite differences (`tests/sq_terms.rs`).

use std::ops::Range;

use glam::DVec3;

use crate::geometry::bspline::{FunctionRow, SurfaceFrame};
use crate::solver::terms::v3;
use crate::solver::{JacobianSink, Linear, Term};

/// Where the variables are: the radius coefficients, then 3 per line, then (slack form) one μ per
/// line, then per quad [μ0, μ1, n*(3)] for each of the two torsal directions and (slack form) ν.
#[derive(Clone, Debug, PartialEq)]
pub struct Layout {
    pub radius: Range<usize>,
    pub points: usize,
    pub lines: usize,
    /// Offset of the line slacks μ (slack form).
    pub line_slack: Option<usize>,
    pub quads: usize,
    pub quad_count: usize,
    /// Variables per quad: 10, or 11 with the angle slack ν.
    pub quad_block: usize,
}

impl Layout {
    pub fn new(coefficients: usize, points: usize, quad_count: usize, slack: bool) -> Self {
        let lines = coefficients;
        let after_lines = lines + 3 * points;
        let (line_slack, quads) = if slack { (Some(after_lines), after_lines + points) } else { (None, after_lines) };
        Self { radius: 0..coefficients, points, lines, line_slack, quads, quad_count, quad_block: if slack { 11 } else { 10 } }
    }

    /// Variables of the line-congruence step (a prefix of the torsal step's).
    pub(crate) fn line_variables(&self) -> usize {
        self.quads
    }

    /// Variables of the torsal step.
    pub fn all_variables(&self) -> usize {
        self.quads + self.quad_block * self.quad_count
    }

    pub fn line(&self, p: usize) -> usize {
        self.lines + 3 * p
    }

    /// (μ0, μ1) of torsal direction k of quad q.
    pub fn mu(&self, q: usize, k: usize) -> usize {
        self.quads + self.quad_block * q + 5 * k
    }

    /// n* of torsal direction k of quad q.
    pub fn plane_normal(&self, q: usize, k: usize) -> usize {
        self.mu(q, k) + 2
    }

    /// ν of quad q (slack form).
    pub(crate) fn angle_slack(&self, q: usize) -> Option<usize> {
        (self.quad_block == 11).then(|| self.quads + self.quad_block * q + 10)
    }
}

/// E_LC: two residuals per point of G.
pub struct LineCongruence<'a> {
    pub frames: &'a [SurfaceFrame],
    pub rows: &'a [FunctionRow],
    pub layout: &'a Layout,
}

impl Term for LineCongruence<'_> {
    fn name(&self) -> &str {
        "line_congruence"
    }
    fn residual_count(&self) -> usize {
        2 * self.frames.len()
    }
    fn eval(&self, x: &[f64], r: &mut [f64], jac: &mut JacobianSink) {
        let r0 = self.layout.radius.start;
        let coefficients = &x[self.layout.radius.clone()];
        for (p, (f, row)) in self.frames.iter().zip(self.rows).enumerate() {
            let (radius, ru, rv) = row.apply(coefficients);
            let l = v3(x, self.layout.line(p));
            let n = f.normal;
            for (k, c, dn, d) in [(0, f.su + ru * n + radius * f.nu, f.nu, &row.du), (1, f.sv + rv * n + radius * f.nv, f.nv, &row.dv)] {
                let i = 2 * p + k;
                let len = c.length();
                let (ch, rho) = if len > 0.0 { (c / len, l.dot(c) / len) } else { (DVec3::ZERO, 0.0) };
                r[i] = rho;
                jac.add_block(i, self.layout.line(p), &ch.to_array());
                let inv = if len > 0.0 { 1.0 / len } else { 0.0 };
                // ∂ρ/∂c = (l − ρ ĉ)/|c|; ∂c/∂r_m = d_m n + value_m ∂n.
                let a = (l.dot(n) - rho * ch.dot(n)) * inv;
                let b = (l.dot(dn) - rho * ch.dot(dn)) * inv;
                for (m, &ci) in row.index.iter().enumerate() {
                    jac.add(i, r0 + ci, a * d[m] + b * row.value[m]);
                }
            }
        }
    }
}

/// E_LC_orth: one residual per line (see the module docs; wrap in [`crate::solver::Hinge`] for
/// the hinge form).
#[derive(Clone)]
pub struct LineNormalAngle<'a> {
    pub normals: Vec<DVec3>,
    pub cos2: f64,
    pub layout: &'a Layout,
}

impl Term for LineNormalAngle<'_> {
    fn name(&self) -> &str {
        "line_normal_angle"
    }
    fn residual_count(&self) -> usize {
        self.normals.len()
    }
    fn eval(&self, x: &[f64], r: &mut [f64], jac: &mut JacobianSink) {
        for (p, n) in self.normals.iter().enumerate() {
            let l = v3(x, self.layout.line(p));
            let c = l.dot(*n);
            match self.layout.line_slack {
                None => {
                    r[p] = self.cos2 - c * c;
                    jac.add_block(p, self.layout.line(p), &(-2.0 * c * *n).to_array());
                }
                Some(s) => {
                    let mu = x[s + p];
                    r[p] = c * c - self.cos2 - mu * mu;
                    jac.add_block(p, self.layout.line(p), &(2.0 * c * *n).to_array());
                    jac.add(p, s + p, -2.0 * mu);
                }
            }
        }
    }
}

/// E_torsal and |t| = 1: four residuals per quad and torsal direction.
pub struct TorsalDirection<'a> {
    pub quads: Vec<[usize; 4]>,
    /// d⁺ and d⁻ of every quad.
    pub diagonals: Vec<(DVec3, DVec3)>,
    pub layout: &'a Layout,
}

impl Term for TorsalDirection<'_> {
    fn name(&self) -> &str {
        "torsal_direction"
    }
    fn residual_count(&self) -> usize {
        8 * self.quads.len()
    }
    fn eval(&self, x: &[f64], r: &mut [f64], jac: &mut JacobianSink) {
        let lay = self.layout;
        for (q, (corners, &(dp, dm))) in self.quads.iter().zip(&self.diagonals).enumerate() {
            let l = corners.map(|p| v3(x, lay.line(p)));
            let (lp, lm) = (l[2] - l[0], l[1] - l[3]);
            let lc = 0.25 * (l[0] + l[1] + l[2] + l[3]);
            let lc_len = lc.length();
            let lc_hat = if lc_len > 0.0 { lc / lc_len } else { DVec3::ZERO };
            for k in 0..2 {
                let (om, on) = (lay.mu(q, k), lay.plane_normal(q, k));
                let (m0, m1) = (x[om], x[om + 1]);
                let ns = v3(x, on);
                let t = m0 * dp + m1 * dm;
                let lt = m0 * lp + m1 * lm;
                let lt_len = lt.length();
                let lt_hat = if lt_len > 0.0 { lt / lt_len } else { DVec3::ZERO };
                let i = 8 * q + 4 * k;
                // ρ1 = ⟨l_t/|l_t|, n*⟩: ∂/∂l_t = (n* − ρ1 l̂_t)/|l_t|.
                let rho1 = lt_hat.dot(ns);
                r[i] = rho1;
                let g1 = if lt_len > 0.0 { (ns - rho1 * lt_hat) / lt_len } else { DVec3::ZERO };
                for (corner, coef) in [(corners[2], m0), (corners[0], -m0), (corners[1], m1), (corners[3], -m1)] {
                    jac.add_block(i, lay.line(corner), &(coef * g1).to_array());
                }
                jac.add(i, om, g1.dot(lp));
                jac.add(i, om + 1, g1.dot(lm));
                jac.add_block(i, on, &lt_hat.to_array());
                // ρ2 = ⟨l_c/|l_c|, n*⟩.
                let rho2 = lc_hat.dot(ns);
                r[i + 1] = rho2;
                let g2 = if lc_len > 0.0 { 0.25 * (ns - rho2 * lc_hat) / lc_len } else { DVec3::ZERO };
                for &corner in corners {
                    jac.add_block(i + 1, lay.line(corner), &g2.to_array());
                }
                jac.add_block(i + 1, on, &lc_hat.to_array());
                // ρ3 = ⟨t, n*⟩.
                r[i + 2] = t.dot(ns);
                jac.add(i + 2, om, dp.dot(ns));
                jac.add(i + 2, om + 1, dm.dot(ns));
                jac.add_block(i + 2, on, &t.to_array());
                // |t|² − 1.
                r[i + 3] = t.length_squared() - 1.0;
                jac.add(i + 3, om, 2.0 * t.dot(dp));
                jac.add(i + 3, om + 1, 2.0 * t.dot(dm));
            }
        }
    }
}

/// E_angle: one residual per quad (see the module docs; wrap in [`crate::solver::Hinge`] for the
/// hinge form).
#[derive(Clone)]
pub struct TorsalAngle<'a> {
    pub cos2: f64,
    pub layout: &'a Layout,
}

impl Term for TorsalAngle<'_> {
    fn name(&self) -> &str {
        "torsal_angle"
    }
    fn residual_count(&self) -> usize {
        self.layout.quad_count
    }
    fn eval(&self, x: &[f64], r: &mut [f64], jac: &mut JacobianSink) {
        let lay = self.layout;
        for (q, rq) in r.iter_mut().enumerate().take(lay.quad_count) {
            let (o1, o2) = (lay.plane_normal(q, 0), lay.plane_normal(q, 1));
            let (n1, n2) = (v3(x, o1), v3(x, o2));
            let c = n1.dot(n2);
            *rq = c * c - self.cos2;
            jac.add_block(q, o1, &(2.0 * c * n2).to_array());
            jac.add_block(q, o2, &(2.0 * c * n1).to_array());
            if let Some(s) = lay.angle_slack(q) {
                *rq += x[s] * x[s];
                jac.add(q, s, 2.0 * x[s]);
            }
        }
    }
}

/// E_fair: l(i−1) − 2 l(i) + l(i+1) along both directions of the n × n grid, per coordinate.
pub fn line_fairness(n: usize, layout: &Layout) -> Linear {
    let mut fair = Linear::new();
    for j in 0..n {
        for i in 0..n {
            let p = i + n * j;
            for (step, interior) in [(1, i > 0 && i + 1 < n), (n, j > 0 && j + 1 < n)] {
                if !interior {
                    continue;
                }
                for c in 0..3 {
                    fair.push_row(&[(layout.line(p - step) + c, 1.0), (layout.line(p) + c, -2.0), (layout.line(p + step) + c, 1.0)], 0.0);
                }
            }
        }
    }
    fair
}
