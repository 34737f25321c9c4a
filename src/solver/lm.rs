//! The Levenberg–Marquardt / guided-projection iteration, its options and reports.

use super::assembly::{evaluate, weighted_energy, EvalBuffers, System};
use super::ordering::Ordering;
use super::problem::Problem;
use crate::progress::{Cancelled, Clock};
use serde::{Deserialize, Serialize};

/// Solver settings. All tolerances are absolute unless stated.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(default)]
pub struct SolverOptions {
    /// Maximal number of iterations (each one factorization, accepted or not).
    pub max_iterations: usize,
    /// Initial regularization ε (the system is JᵀWJ + ε²I).
    pub initial_epsilon: f64,
    /// Lower bound of ε.
    pub min_epsilon: f64,
    /// Upper bound of ε; reaching it ends the run (`Termination::DampingLimit`).
    pub max_epsilon: f64,
    /// Stop when |Δ| ≤ step_tolerance·(|x_free| + step_tolerance).
    pub step_tolerance: f64,
    /// Stop when the energy is ≤ this.
    pub energy_tolerance: f64,
    /// Stop when |JᵀWr|∞ ≤ this.
    pub gradient_tolerance: f64,
    /// Stop when an accepted step lowers the energy by ≤ this fraction of it, or with a
    /// `decrease_window` above 1, when that many iterations together do.
    pub relative_decrease_tolerance: f64,
    /// The iterations over which `relative_decrease_tolerance` is measured (1: each accepted
    /// step alone). A slow, steady descent whose every step counts stops on a window.
    pub decrease_window: usize,
    /// The caller's clock (e.g. `performance.now()` in the browser); with one, every iteration
    /// is timed (`IterationReport::ms`, `SolveReport::iteration_ms`).
    #[serde(skip)]
    pub clock: Clock,
    /// Fill-reducing ordering of the normal matrix (computed once per sparsity pattern).
    pub ordering: Ordering,
    /// Always factorize supernodally; otherwise faer chooses by flops per factor entry. An
    /// arrow-shaped normal matrix (small blocks and a dense border, as in the SQ line-congruence
    /// step) runs faster supernodal although faer's heuristic picks simplicial.
    #[serde(default)]
    pub supernodal: bool,
}

impl Default for SolverOptions {
    fn default() -> Self {
        Self {
            max_iterations: 100,
            initial_epsilon: 1e-3,
            min_epsilon: 1e-8,
            max_epsilon: 1e8,
            step_tolerance: 1e-14,
            energy_tolerance: 0.0,
            gradient_tolerance: 0.0,
            relative_decrease_tolerance: 1e-14,
            decrease_window: 1,
            clock: Clock::default(),
            ordering: Ordering::BlockAmd,
            supernodal: false,
        }
    }
}

/// Residual statistics of one term at the current point.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TermStats {
    pub name: String,
    pub weight: f64,
    pub residuals: usize,
    /// Residuals not switched off (one-sided terms).
    pub active: usize,
    /// Mean |r| over all residuals (inactive ones count as 0), unweighted.
    pub mean_abs: f64,
    /// Max |r|, unweighted.
    pub max_abs: f64,
    /// weight · Σ r².
    pub energy: f64,
}

/// Passed to the hook after every iteration.
#[derive(Debug, Serialize)]
pub struct IterationReport<'a> {
    /// 1-based.
    pub iteration: usize,
    /// Total weighted energy at the current (accepted) point.
    pub energy: f64,
    pub terms: &'a [TermStats],
    /// ε used for this iteration's step.
    pub epsilon: f64,
    /// |Δ| of this iteration's step (0 if the factorization failed).
    pub step_norm: f64,
    /// Whether the step was taken.
    pub accepted: bool,
    /// |JᵀWr|∞ at the current point.
    pub gradient_norm: f64,
    /// Duration of this iteration (when `SolverOptions::clock` is set).
    pub ms: Option<f64>,
    /// The current (accepted) variables, for snapshots.
    #[serde(skip)]
    pub x: &'a [f64],
}

/// Why a run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Termination {
    StepTolerance,
    EnergyTolerance,
    GradientTolerance,
    RelativeDecrease,
    MaxIterations,
    /// ε reached `max_epsilon` (no descent found).
    DampingLimit,
    /// The hook returned `Err(Cancelled)`.
    Cancelled,
    /// The energy at the starting point is not finite.
    NonFinite,
    /// Every variable is fixed (or there are none).
    NoFreeVariables,
}

impl Termination {
    /// Converged (as opposed to stopped by a limit, the hook or an error).
    pub fn converged(self) -> bool {
        matches!(self, Self::StepTolerance | Self::EnergyTolerance | Self::GradientTolerance | Self::RelativeDecrease | Self::NoFreeVariables)
    }
}

/// Summary of one [`Solver::solve`] call.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SolveReport {
    pub iterations: usize,
    pub accepted_steps: usize,
    pub initial_energy: f64,
    pub energy: f64,
    pub terms: Vec<TermStats>,
    pub termination: Termination,
    /// ε at the end.
    pub epsilon: f64,
    /// Symbolic analyses done during this call (0 when the cached one was reused).
    pub symbolic_analyses: usize,
    pub numeric_factorizations: usize,
    pub free_variables: usize,
    pub residuals: usize,
    /// Stored entries of the upper triangle of JᵀJ.
    pub normal_matrix_nnz: usize,
    /// Stored values of the Cholesky factor L.
    pub factor_nnz: usize,
    /// Whether faer chose the supernodal (else simplicial) factorization.
    pub supernodal: bool,
    /// The fill-reducing ordering in use (never `Auto`).
    pub ordering: Ordering,
    /// Σ c_j² over the columns of L: about the flops of one numeric factorization.
    pub factor_flops: f64,
    /// Per-iteration durations (when `SolverOptions::clock` is set).
    pub iteration_ms: Vec<f64>,
    /// Time per phase, summed over the call (when `SolverOptions::clock` is set).
    pub phase_ms: PhaseTimes,
}

/// Milliseconds spent per phase (zeros without a clock).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PhaseTimes {
    /// Pattern, maps and symbolic Cholesky analysis.
    pub symbolic: f64,
    /// `prepare` + `eval` of all terms.
    pub evaluate: f64,
    /// JᵀWJ and JᵀWr.
    pub assemble: f64,
    /// Numeric Cholesky and the triangular solves.
    pub factorize_solve: f64,
}

impl PhaseTimes {
    /// Adds another call's times.
    pub fn add(&mut self, other: &PhaseTimes) {
        self.symbolic += other.symbolic;
        self.evaluate += other.evaluate;
        self.assemble += other.assemble;
        self.factorize_solve += other.factorize_solve;
    }
}

/// Levenberg–Marquardt in the regularized guided-projection form of Tang et al. 2014.
///
/// Each iteration solves `(JᵀWJ + ε²I) Δ = −JᵀW r` over the free variables with a sparse
/// Cholesky factorization, then evaluates the energy at `x + Δ`:
///
/// - the gain ratio ρ = (E(x) − E(x+Δ)) / (L(0) − L(Δ)) compares the actual decrease with the
///   decrease predicted by the linearization, L(0) − L(Δ) = Δᵀ(ε²Δ − JᵀWr) > 0;
/// - the step is **accepted** iff E(x+Δ) < E(x); then ε² ← ε²·max(1/3, 1 − (2ρ − 1)³) and ν ← 2
///   (Nielsen's rule: a very good ratio lowers the damping by up to 3×, a poor but positive one
///   raises it by up to 2×);
/// - a **rejected** step (or a failed factorization) leaves x unchanged and sets ε² ← ν ε²,
///   ν ← 2ν (growing 2×, 4×, 8×, … on consecutive rejections);
/// - ε is kept within [`SolverOptions::min_epsilon`], [`SolverOptions::max_epsilon`].
///
/// The Jacobian evaluated at an accepted trial point is reused for the next iteration, so an
/// iteration costs one evaluation of all terms, one assembly and one numeric factorization.
///
/// The solver caches the sparsity pattern, the triplet → JᵀJ maps and the symbolic Cholesky
/// factorization across iterations *and* across calls (stages with new weights, new starting
/// points); they are rebuilt only when the structure emitted by the terms or the fixed mask
/// changes ([`Solver::symbolic_analyses`] counts them).
pub struct Solver {
    pub options: SolverOptions,
    system: Option<System>,
    cur: EvalBuffers,
    trial: EvalBuffers,
    x_trial: Vec<f64>,
    delta: Vec<f64>,
    stats: Vec<TermStats>,
    symbolic_analyses: usize,
    numeric_factorizations: usize,
}

impl Default for Solver {
    fn default() -> Self {
        Self::new(SolverOptions::default())
    }
}

impl Solver {
    pub fn new(options: SolverOptions) -> Self {
        Self {
            options,
            system: None,
            cur: EvalBuffers::default(),
            trial: EvalBuffers::default(),
            x_trial: Vec::new(),
            delta: Vec::new(),
            stats: Vec::new(),
            symbolic_analyses: 0,
            numeric_factorizations: 0,
        }
    }

    /// Symbolic analyses (sparsity pattern + fill-reducing ordering + symbolic Cholesky) done by
    /// this solver so far.
    pub fn symbolic_analyses(&self) -> usize {
        self.symbolic_analyses
    }

    /// Numeric factorizations done by this solver so far.
    pub fn numeric_factorizations(&self) -> usize {
        self.numeric_factorizations
    }

    /// Minimizes the problem's energy starting from `x` (updated in place to the last accepted
    /// point). `hook` is called after every iteration; `Err(Cancelled)` ends the run at once
    /// (`Termination::Cancelled`).
    pub fn solve<F>(&mut self, problem: &mut Problem, x: &mut [f64], mut hook: F) -> SolveReport
    where
        F: FnMut(&IterationReport) -> Result<(), Cancelled>,
    {
        let n = problem.num_variables();
        assert_eq!(x.len(), n, "variable vector has the wrong length");
        let opts = self.options.clone();
        let clock = opts.clock.0;
        let tick = || clock.map_or(0.0, |c| c());
        let sym0 = self.symbolic_analyses;
        let fac0 = self.numeric_factorizations;
        let mut phase = PhaseTimes::default();

        let t = tick();
        problem.prepare(x);
        evaluate(problem, x, &mut self.cur);
        phase.evaluate += tick() - t;
        let mut energy = weighted_energy(problem, &self.cur);
        self.stats = empty_stats(problem);
        fill_stats(problem, &self.cur, &mut self.stats);

        let mut report = SolveReport {
            iterations: 0,
            accepted_steps: 0,
            initial_energy: energy,
            energy,
            terms: Vec::new(),
            termination: Termination::MaxIterations,
            epsilon: opts.initial_epsilon,
            symbolic_analyses: 0,
            numeric_factorizations: 0,
            free_variables: 0,
            residuals: self.cur.r.len(),
            normal_matrix_nnz: 0,
            factor_nnz: 0,
            supernodal: false,
            ordering: opts.ordering,
            factor_flops: 0.0,
            iteration_ms: Vec::with_capacity(if clock.is_some() { opts.max_iterations } else { 0 }),
            phase_ms: PhaseTimes::default(),
        };
        if !energy.is_finite() {
            report.termination = Termination::NonFinite;
            report.terms = self.stats.clone();
            return report;
        }
        if !self.system.as_ref().is_some_and(|s| s.matches(problem, &self.cur)) {
            let t = tick();
            self.system = None; // free the old pattern first
            self.system = Some(System::build(problem, &self.cur, opts.ordering, opts.supernodal));
            self.symbolic_analyses += 1;
            phase.symbolic += tick() - t;
        }
        let sys = self.system.as_mut().unwrap();
        let t = tick();
        sys.assemble(problem, &self.cur);
        phase.assemble += tick() - t;
        let nf = sys.n_free();
        self.delta.clear();
        self.delta.resize(nf, 0.0);
        self.x_trial.clear();
        self.x_trial.extend_from_slice(x);

        let finish = |mut report: SolveReport, this: &Self, energy: f64, mu: f64, phase: PhaseTimes, t: Termination| {
            let sys = this.system.as_ref().unwrap();
            report.termination = t;
            report.energy = energy;
            report.terms = this.stats.clone();
            report.epsilon = mu.sqrt();
            report.symbolic_analyses = this.symbolic_analyses - sym0;
            report.numeric_factorizations = this.numeric_factorizations - fac0;
            report.free_variables = sys.n_free();
            report.normal_matrix_nnz = sys.nnz();
            report.factor_nnz = sys.factor_nnz();
            report.supernodal = sys.is_supernodal();
            report.ordering = sys.ordering;
            report.factor_flops = sys.factor_flops();
            report.phase_ms = phase;
            report
        };

        let mu_min = opts.min_epsilon * opts.min_epsilon;
        let mu_max = opts.max_epsilon * opts.max_epsilon;
        let mut mu = (opts.initial_epsilon * opts.initial_epsilon).clamp(mu_min, mu_max);
        let mut nu = 2.0;
        if nf == 0 {
            return finish(report, self, energy, mu, phase, Termination::NoFreeVariables);
        }
        if energy <= opts.energy_tolerance {
            return finish(report, self, energy, mu, phase, Termination::EnergyTolerance);
        }
        if sys.gradient_inf_norm() <= opts.gradient_tolerance {
            return finish(report, self, energy, mu, phase, Termination::GradientTolerance);
        }

        // The energy after each iteration, for a decrease measured over `decrease_window`.
        let mut energies: Vec<f64> = vec![energy];
        for it in 1..=opts.max_iterations {
            let t0 = clock.map(|c| c());
            let sys = self.system.as_mut().unwrap();
            let mu_used = mu;
            let t = tick();
            let solved = sys.factor_solve(mu, &mut self.delta);
            phase.factorize_solve += tick() - t;
            self.numeric_factorizations += 1;
            let mut accepted = false;
            let mut step_norm = 0.0;
            let mut small_decrease = false;
            if solved {
                step_norm = self.delta.iter().map(|d| d * d).sum::<f64>().sqrt();
                let mut pred = 0.0;
                for (d, g) in self.delta.iter().zip(&sys.g) {
                    pred += d * (mu * d - g);
                }
                self.x_trial.copy_from_slice(x);
                for (&v, &d) in sys.free_to_var.iter().zip(&self.delta) {
                    self.x_trial[v as usize] += d;
                }
                let t = tick();
                problem.prepare(&self.x_trial);
                evaluate(problem, &self.x_trial, &mut self.trial);
                phase.evaluate += tick() - t;
                let e_trial = weighted_energy(problem, &self.trial);
                if e_trial.is_finite() && e_trial < energy && problem.is_admissible(&self.x_trial) {
                    accepted = true;
                    let rho = if pred > 0.0 { (energy - e_trial) / pred } else { 1.0 };
                    small_decrease = opts.decrease_window <= 1 && energy - e_trial <= opts.relative_decrease_tolerance * energy;
                    energy = e_trial;
                    x.copy_from_slice(&self.x_trial);
                    std::mem::swap(&mut self.cur, &mut self.trial);
                    if !sys.matches_structure(&self.cur) {
                        // A term changed its structure: new pattern, new symbolic analysis.
                        let t = tick();
                        self.system = None;
                        self.system = Some(System::build(problem, &self.cur, opts.ordering, opts.supernodal));
                        self.symbolic_analyses += 1;
                        phase.symbolic += tick() - t;
                    }
                    let t = tick();
                    self.system.as_mut().unwrap().assemble(problem, &self.cur);
                    phase.assemble += tick() - t;
                    fill_stats(problem, &self.cur, &mut self.stats);
                    report.accepted_steps += 1;
                    let t = 2.0 * rho - 1.0;
                    mu *= (1.0 - t * t * t).max(1.0 / 3.0);
                    nu = 2.0;
                }
            }
            if !accepted {
                mu *= nu;
                nu *= 2.0;
            }
            energies.push(energy);
            if opts.decrease_window > 1 && it >= opts.decrease_window {
                let before = energies[it - opts.decrease_window];
                small_decrease = before - energy <= opts.relative_decrease_tolerance * before;
            }
            let hit_max = !accepted && mu >= mu_max;
            mu = mu.clamp(mu_min, mu_max);
            let sys = self.system.as_ref().unwrap();
            let gnorm = sys.gradient_inf_norm();
            let ms = match t0 {
                Some(t0) => {
                    let ms = tick() - t0;
                    report.iteration_ms.push(ms);
                    Some(ms)
                }
                _ => None,
            };
            report.iterations = it;
            let ir = IterationReport {
                iteration: it,
                energy,
                terms: &self.stats,
                epsilon: mu_used.sqrt(),
                step_norm,
                accepted,
                gradient_norm: gnorm,
                ms,
                x,
            };
            if hook(&ir).is_err() {
                return finish(report, self, energy, mu, phase, Termination::Cancelled);
            }
            let x_norm = sys.free_to_var.iter().map(|&v| x[v as usize] * x[v as usize]).sum::<f64>().sqrt();
            let t = if energy <= opts.energy_tolerance {
                Some(Termination::EnergyTolerance)
            } else if accepted && gnorm <= opts.gradient_tolerance {
                Some(Termination::GradientTolerance)
            } else if solved && step_norm <= opts.step_tolerance * (x_norm + opts.step_tolerance) {
                Some(Termination::StepTolerance)
            } else if small_decrease {
                Some(Termination::RelativeDecrease)
            } else if hit_max {
                Some(Termination::DampingLimit)
            } else {
                None
            };
            if let Some(t) = t {
                return finish(report, self, energy, mu, phase, t);
            }
        }
        finish(report, self, energy, mu, phase, Termination::MaxIterations)
    }
}

pub(crate) fn empty_stats(problem: &Problem) -> Vec<TermStats> {
    problem
        .terms
        .iter()
        .map(|t| TermStats { name: t.term.name().to_string(), weight: t.weight, residuals: t.term.residual_count(), ..Default::default() })
        .collect()
}

pub(crate) fn fill_stats(problem: &Problem, buf: &EvalBuffers, stats: &mut [TermStats]) {
    for (ti, (t, s)) in problem.terms.iter().zip(stats.iter_mut()).enumerate() {
        let (r0, r1) = (buf.term_rows[ti], buf.term_rows[ti + 1]);
        let (mut sum, mut max, mut sq) = (0.0f64, 0.0f64, 0.0f64);
        for &r in &buf.r[r0..r1] {
            sum += r.abs();
            max = max.max(r.abs());
            sq += r * r;
        }
        let n = r1 - r0;
        s.weight = t.weight;
        s.residuals = n;
        s.active = buf.active[r0..r1].iter().filter(|&&a| a).count();
        s.mean_abs = if n > 0 { sum / n as f64 } else { 0.0 };
        s.max_abs = max;
        s.energy = t.weight * sq;
    }
}

impl Problem<'_> {
    /// Per-term statistics at `x` (does not call `prepare`).
    pub fn term_stats(&self, x: &[f64]) -> Vec<TermStats> {
        let mut buf = EvalBuffers::default();
        evaluate(self, x, &mut buf);
        let mut stats = empty_stats(self);
        fill_stats(self, &buf, &mut stats);
        stats
    }

    /// Total weighted energy Σ w Σ r² at `x` (does not call `prepare`).
    pub fn energy(&self, x: &[f64]) -> f64 {
        self.term_stats(x).iter().map(|s| s.energy).sum()
    }
}
