//! The congruence optimization of Sec. 5.1, in its two steps, with the sparse Levenberg–Marquardt
//! solver of [`crate::solver`] (Tang et al. 2014's form, Eq. 9):
//!
//! 1. **Line congruence**: E = w_LC E_LC + w_LC_orth E_LC_orth + |l| = 1 over the radius
//!    coefficients and the lines, from the central congruence; then the lines are flipped back
//!    to the side of n.
//! 2. **Torsal directions**: adds E_torsal, E_angle, E_fair and E_reg (on n*) over the per-quad
//!    unknowns. Every RS iterations the torsal directions and plane normals are recomputed exactly
//!    from the current lines ([`crate::congruence::torsal`]); a quad without real ones keeps its
//!    previous values (at the start: the two real directions nearest its complex pair). The last
//!    iterations run with w_angle = w_fair = 0.
//!
//! The per-quad unknowns couple only to their quad's four lines; the block AMD ordering
//! eliminates them first, which is the Schur complement the issue of keeping the solve small
//! asks for, done by the sparse Cholesky factorization.

use glam::DVec3;

use crate::congruence::line_congruence::centre_derivatives;
use crate::congruence::torsal::{quadratic_roots, torsal_quadratic};
use crate::geometry::bspline::{BSplineFunction, FunctionRow};
use crate::progress::{Cancelled, Clock};
use crate::solver::terms::v3;
use crate::solver::{Hinge, PhaseTimes, Problem, Proximal, Solver, SolverOptions, Term, TermStats, UnitLength};

use super::error::SqError;
use super::params::{Inequality, SqParams};
use super::radius::SamplingGrid;
use super::terms::{line_fairness, Layout, LineCongruence, LineNormalAngle, TorsalAngle, TorsalDirection};

/// The two steps, as reported to the hook.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SqStep {
    LineCongruence,
    Torsal,
}

impl SqStep {
    pub fn key(self) -> &'static str {
        match self {
            SqStep::LineCongruence => "line_congruence",
            SqStep::Torsal => "torsal",
        }
    }
}

/// Called after every solver iteration with the step, the iteration (1-based within the step),
/// the term statistics and the variables; `Err(Cancelled)` stops the step.
pub type IterationHook<'h> = dyn FnMut(SqStep, usize, &[TermStats], &[f64]) -> Result<(), Cancelled> + 'h;

/// What a step did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StepOutcome {
    pub iterations: usize,
    /// Per-iteration times (ms) with a clock.
    pub iteration_ms: Vec<f64>,
    /// Where the time went (with a clock).
    pub phase_ms: PhaseTimes,
}

/// The optimization's fixed data, in the normalized frame.
pub struct CongruenceProblem {
    pub grid: SamplingGrid,
    /// The radius function's row at every point of G.
    pub rows: Vec<FunctionRow>,
    pub layout: Layout,
    pub quads: Vec<[usize; 4]>,
    /// d⁺ and d⁻ of every quad.
    pub diagonals: Vec<(DVec3, DVec3)>,
}

impl CongruenceProblem {
    pub fn new(grid: SamplingGrid, radius: &BSplineFunction, inequality: Inequality) -> Self {
        let rows = grid.uv.iter().map(|p| BSplineFunction::row(&radius.u, &radius.v, p[0], p[1])).collect();
        let quads: Vec<[usize; 4]> = (0..grid.quad_count()).map(|q| grid.quad(q)).collect();
        let diagonals = quads
            .iter()
            .map(|c| {
                let f = c.map(|p| grid.frames[p].point);
                (f[2] - f[0], f[1] - f[3])
            })
            .collect();
        let layout = Layout::new(radius.coefficients.len(), grid.point_count(), quads.len(), inequality == Inequality::Slack);
        Self { grid, rows, layout, quads, diagonals }
    }

    /// The lines of the congruence with radius coefficients `coefficients`; an error where the
    /// centre surface is singular.
    pub fn congruence_lines(&self, coefficients: &[f64]) -> Result<Vec<DVec3>, SqError> {
        let mut singular = 0;
        let lines: Vec<DVec3> = self
            .grid
            .frames
            .iter()
            .zip(&self.rows)
            .map(|(f, row)| {
                let c = centre_derivatives(f, row.apply(coefficients));
                c.line(f.normal, f.su.length() * f.sv.length()).unwrap_or_else(|| {
                    singular += 1;
                    f.normal
                })
            })
            .collect();
        if singular > 0 {
            return Err(SqError::SingularCentreSurface { points: singular, total: lines.len() });
        }
        Ok(lines)
    }

    /// The starting point of step 1: coefficients, lines and (slack form) line slacks.
    pub fn initial_point(&self, coefficients: &[f64], lines: &[DVec3], params: &SqParams) -> Vec<f64> {
        let lay = &self.layout;
        let mut x = vec![0.0; lay.line_variables()];
        x[lay.radius.clone()].copy_from_slice(coefficients);
        for (p, l) in lines.iter().enumerate() {
            x[lay.line(p)..lay.line(p) + 3].copy_from_slice(&l.to_array());
        }
        if let Some(s) = lay.line_slack {
            let cos2 = params.target_theta_deg().to_radians().cos().powi(2);
            for (p, (l, f)) in lines.iter().zip(&self.grid.frames).enumerate() {
                x[s + p] = (l.dot(f.normal).powi(2) - cos2).max(0.0).sqrt();
            }
        }
        x
    }

    /// The lines of the congruence of `x`'s radius function, c_u × c_v (Sec. 2.1), unit and on
    /// the side of the normals: what the guarantees are measured on, not the optimizer's line
    /// variables. Where the centre surface is singular (a focal point of a constant radius),
    /// the line variable stands in.
    pub(crate) fn measured_lines(&self, x: &[f64]) -> Vec<DVec3> {
        let coefficients = &x[self.layout.radius.clone()];
        let variables = self.lines(x);
        self.grid
            .frames
            .iter()
            .zip(&self.rows)
            .zip(variables)
            .map(|((f, row), l)| centre_derivatives(f, row.apply(coefficients)).line(f.normal, f.su.length() * f.sv.length()).unwrap_or(l))
            .collect()
    }

    /// The unit lines of `x`, on the side of the normals.
    pub fn lines(&self, x: &[f64]) -> Vec<DVec3> {
        (0..self.layout.points)
            .map(|p| {
                let l = v3(x, self.layout.line(p)).normalize_or_zero();
                if l.dot(self.grid.frames[p].normal) < 0.0 {
                    -l
                } else {
                    l
                }
            })
            .collect()
    }

    /// E_LC per term: the mean of its squared residuals at `x`.
    pub fn lc_residual(&self, x: &[f64]) -> f64 {
        let r = crate::solver::residuals(&self.line_congruence(), x);
        r.iter().map(|v| v * v).sum::<f64>() / r.len().max(1) as f64
    }

    fn line_congruence(&self) -> LineCongruence<'_> {
        LineCongruence { frames: &self.grid.frames, rows: &self.rows, layout: &self.layout }
    }

    fn line_normal_angle(&self, params: &SqParams) -> Box<dyn Term + '_> {
        let term = LineNormalAngle {
            normals: self.grid.frames.iter().map(|f| f.normal).collect(),
            cos2: params.target_theta_deg().to_radians().cos().powi(2),
            layout: &self.layout,
        };
        match params.inequality {
            Inequality::Hinge => Box::new(Hinge::new(term).with_name("line_normal_angle")),
            Inequality::Slack => Box::new(term),
        }
    }

    fn line_offsets(&self) -> Vec<usize> {
        (0..self.layout.points).map(|p| self.layout.line(p)).collect()
    }

    fn group_blocks(&self, problem: &mut Problem) {
        let lay = &self.layout;
        for p in 0..lay.points {
            problem.group_variables(lay.line(p)..lay.line(p) + 3);
        }
        if problem.num_variables() == lay.all_variables() {
            for q in 0..lay.quad_count {
                for k in 0..2 {
                    problem.group_variables(lay.mu(q, k)..lay.mu(q, k) + 2);
                    problem.group_variables(lay.plane_normal(q, k)..lay.plane_normal(q, k) + 3);
                }
            }
        }
    }

    /// Step 1 (see the module docs); `x` from [`Self::initial_point`].
    pub fn line_congruence_step(&self, x: &mut [f64], params: &SqParams, clock: Clock, hook: &mut IterationHook) -> Result<StepOutcome, Cancelled> {
        let w = params.lc_weights;
        let mut problem = Problem::new(self.layout.line_variables());
        problem.add_term(self.line_congruence(), w.lc);
        problem.add_boxed(self.line_normal_angle(params), w.lc_orth);
        problem.add_term(UnitLength::vectors(self.line_offsets()), w.unit);
        self.group_blocks(&mut problem);
        // Lines in 3 × 3 blocks with the radius coefficients as a dense border: supernodal is faster.
        let mut solver = Solver::new(SolverOptions { max_iterations: params.lc_iterations, clock, supernodal: true, ..SolverOptions::default() });
        let report = solver.solve(&mut problem, x, |it| hook(SqStep::LineCongruence, it.iteration, it.terms, it.x));
        // Back to unit lines on the side of n.
        for (p, l) in self.lines(x).into_iter().enumerate() {
            x[self.layout.line(p)..self.layout.line(p) + 3].copy_from_slice(&l.to_array());
        }
        if report.termination == crate::solver::Termination::Cancelled {
            return Err(Cancelled);
        }
        Ok(StepOutcome { iterations: report.iterations, iteration_ms: report.iteration_ms, phase_ms: report.phase_ms })
    }

    /// Extends step 1's variables with the per-quad unknowns of the torsal directions.
    pub fn extend_for_torsal(&self, x: &[f64]) -> Vec<f64> {
        let mut out = x.to_vec();
        out.resize(self.layout.all_variables(), 0.0);
        self.recompute_torsal(&mut out, None, 0.0);
        out
    }

    /// Sets every quad's (μ0, μ1) and n* from the exact torsal directions of the current lines.
    /// A quad without real ones keeps `previous` values, or (none yet) takes the real directions
    /// nearest its complex pair. In the slack form ν is set to make E_angle's residual vanish
    /// where it can (`cos2_alpha`).
    fn recompute_torsal(&self, x: &mut [f64], previous: Option<&[f64]>, cos2_alpha: f64) {
        let lay = &self.layout;
        let lines: Vec<DVec3> = (0..lay.points).map(|p| v3(x, lay.line(p))).collect();
        for (q, corners) in self.quads.iter().enumerate() {
            let f = corners.map(|p| self.grid.frames[p].point);
            let l = corners.map(|p| lines[p]);
            let [a, b, c] = torsal_quadratic(f, l);
            let roots = quadratic_roots([a, b, c]).or_else(|| match previous {
                Some(_) => None,
                // Complex pair x = (−b ± i√−disc)/2a: take (−b ± √−disc)/2a.
                None if a != 0.0 => {
                    let s = (4.0 * a * c - b * b).max(0.0).sqrt();
                    Some([[(-b + s) / (2.0 * a), 1.0], [(-b - s) / (2.0 * a), 1.0]])
                }
                None => Some([[1.0, 0.0], [0.0, 1.0]]),
            });
            let (dp, dm) = self.diagonals[q];
            let lc = 0.25 * (l[0] + l[1] + l[2] + l[3]);
            let fresh = roots.and_then(|roots| {
                let mut values = [[0.0; 5]; 2];
                for k in 0..2 {
                    let t = roots[k][0] * dp + roots[k][1] * dm;
                    let len = t.length();
                    let n = lc.cross(t / len).try_normalize()?;
                    values[k] = [roots[k][0] / len, roots[k][1] / len, n.x, n.y, n.z];
                }
                Some(values)
            });
            match (fresh, previous) {
                (Some(mut values), prev) => {
                    // Keep each direction's slot: swap when that matches the previous ones better.
                    if let Some(prev) = prev {
                        let t_of = |v: &[f64]| v[0] * dp + v[1] * dm;
                        let old0 = t_of(&prev[lay.mu(q, 0)..]);
                        if t_of(&values[1]).dot(old0).abs() > t_of(&values[0]).dot(old0).abs() {
                            values.swap(0, 1);
                        }
                    }
                    for (k, v) in values.iter().enumerate() {
                        x[lay.mu(q, k)..lay.mu(q, k) + 5].copy_from_slice(v);
                    }
                }
                (None, Some(prev)) => {
                    let (o, e) = (lay.mu(q, 0), lay.mu(q, 0) + 10);
                    x[o..e].copy_from_slice(&prev[o..e]);
                }
                (None, None) => {}
            }
            if let Some(s) = lay.angle_slack(q) {
                let (n1, n2) = (v3(x, lay.plane_normal(q, 0)), v3(x, lay.plane_normal(q, 1)));
                x[s] = (cos2_alpha - n1.dot(n2).powi(2)).max(0.0).sqrt();
            }
        }
    }

    /// Step 2 (see the module docs); `x` from [`Self::extend_for_torsal`].
    pub fn torsal_step(&self, x: &mut [f64], params: &SqParams, clock: Clock, hook: &mut IterationHook) -> Result<StepOutcome, Cancelled> {
        let w = params.torsal_weights;
        let lay = &self.layout;
        let cos2_alpha = params.target_alpha_deg().to_radians().cos().powi(2);
        let mut problem = Problem::new(lay.all_variables());
        problem.add_term(self.line_congruence(), w.lc);
        problem.add_boxed(self.line_normal_angle(params), w.lc_orth);
        problem.add_term(UnitLength::vectors(self.line_offsets()), w.unit);
        let normals: Vec<usize> = (0..lay.quad_count).flat_map(|q| [lay.plane_normal(q, 0), lay.plane_normal(q, 1)]).collect();
        problem.add_term(UnitLength::vectors(normals.clone()).with_name("plane_normal_unit"), w.unit);
        problem.add_term(TorsalDirection { quads: self.quads.clone(), diagonals: self.diagonals.clone(), layout: lay }, w.torsal);
        let angle = TorsalAngle { cos2: cos2_alpha, layout: lay };
        let angle_id = match params.inequality {
            Inequality::Hinge => problem.add_term(Hinge::new(angle).with_name("torsal_angle"), w.angle),
            Inequality::Slack => problem.add_term(angle, w.angle),
        };
        let fair_id = problem.add_term(line_fairness(self.grid.n, lay).with_name("line_fairness"), w.fair);
        let reg: Vec<usize> = normals.iter().flat_map(|&o| o..o + 3).collect();
        problem.add_term(Proximal::new(reg), w.reg);
        self.group_blocks(&mut problem);

        let total = params.torsal_iterations;
        let final_from = total.saturating_sub(params.final_iterations);
        let every = params.recompute_every.max(1);
        let mut solver = Solver::new(SolverOptions { clock, ..SolverOptions::default() });
        let mut outcome = StepOutcome::default();
        let mut done = 0;
        while done < total {
            if done > 0 {
                let previous = x.to_vec();
                self.recompute_torsal(x, Some(&previous), cos2_alpha);
            }
            if done >= final_from {
                problem.set_weight(angle_id, 0.0);
                problem.set_weight(fair_id, 0.0);
            }
            // A round ends at the next recomputation or where the final iterations begin.
            let mut end = (done + every).min(total);
            if done < final_from && end > final_from {
                end = final_from;
            }
            solver.options.max_iterations = end - done;
            let offset = done;
            let report = solver.solve(&mut problem, x, |it| hook(SqStep::Torsal, offset + it.iteration, it.terms, it.x));
            outcome.iteration_ms.extend_from_slice(&report.iteration_ms);
            outcome.phase_ms.add(&report.phase_ms);
            if report.termination == crate::solver::Termination::Cancelled {
                return Err(Cancelled);
            }
            // A converged round still counts as its iterations: the recomputation moves on.
            done = end;
        }
        outcome.iterations = done;
        Ok(outcome)
    }
}
