//! Sec. 5: SQ meshes with support structure, up to the torsal cross field (Sec. 5, 5.1).
//!
//! The reference is a B-spline surface f(u, v) ([`crate::reference::bspline`]). The sphere
//! congruence has centres c = f + r n (Eq. 1) and radius r(u, v), a B-spline function (Eq. 8).
//!
//! 1. **Radius** ([`radius`]): sample f on the grid G; refuse where H changes sign or nearly
//!    vanishes (Sec. 6.3); fit r to the central radii 1/H.
//! 2. **Line congruence** ([`optimization`], step 1): the lines l ∥ c_u × c_v (Sec. 2.1) become
//!    variables with the radius coefficients; E_LC keeps them in the congruence of r, E_LC_orth
//!    keeps them within θ of the normals.
//! 3. **Torsal directions** (step 2): per grid quad, two torsal directions whose planes meet at
//!    ≥ α (Fig. 20), recomputed every RS iterations.
//!
//! The result is the optimized congruence with its torsal cross field on G, and the figures of
//! Sec. 2.5 before and after ([`metrics`]). Quad remeshing along the cross field and the final
//! sphere optimization (Sec. 5.2) follow.
//!
//! Everything is computed in the frame y = (x − t)/s of the bounding box (centre t, diagonal s),
//! so the weights are dimensionless; results are returned in model units.

mod error;
pub mod metrics;
pub mod optimization;
pub mod params;
pub mod radius;
pub mod segments;
pub mod terms;

use glam::DVec3;

use crate::congruence::torsal::TorsalPair;
use crate::geometry::bspline::BSplineFunction;
use crate::progress::{Cancelled, Clock, Progress, Timings};
use crate::reference::Reference;
use crate::solver::TermStats;
use crate::stats::median;

pub use self::error::SqError;
use self::metrics::{torsal_pairs, CongruenceFigures};
use self::optimization::{CongruenceProblem, SqStep};
use self::params::{RadiusBasis, SqParams, ALPHA_RANGE, GRID_RANGE, RECOMPUTE_RANGE, THETA_RANGE};
use self::radius::{check_mean_curvature, fit_radius, SamplingGrid};

/// What the method reports while it runs.
pub enum SqEvent<'a> {
    Progress(Progress<'a>),
    /// Once, before the optimization: the points of G (model units) and the unit lines of the
    /// fitted central congruence.
    Started { points: &'a [DVec3], lines: &'a [DVec3] },
    /// After every solver iteration: the step, the iteration within it, the term statistics and
    /// the current unit lines of G.
    Iteration { step: SqStep, iteration: usize, terms: &'a [TermStats], lines: Vec<DVec3> },
}

/// The optimized congruence on G, in model units.
#[derive(Clone, Debug)]
pub struct SqCongruence {
    /// Points per direction of G; point (i, j) at i + n j.
    pub grid: usize,
    pub uv: Vec<[f64; 2]>,
    pub points: Vec<DVec3>,
    pub normals: Vec<DVec3>,
    /// r at the points of G, final.
    pub radii: Vec<f64>,
    /// The radius function r(u, v), final (model units).
    pub radius: BSplineFunction,
    pub radius_basis: RadiusBasis,
    /// Largest |r − 1/H| of the fit over G, relative to the mean |1/H|.
    pub radius_fit_error: f64,
    /// Unit lines, on the side of the normals: of the fitted central congruence, and final.
    pub initial_lines: Vec<DVec3>,
    pub lines: Vec<DVec3>,
    /// Per quad of G (i + (n − 1) j): the final torsal directions.
    pub torsal: Vec<Option<TorsalPair>>,
    /// The final torsal directions in parameters (unit (du, dv) in the domain's units).
    pub torsal_uv: Vec<Option<[[f64; 2]; 2]>>,
    pub initial_figures: CongruenceFigures,
    pub figures: CongruenceFigures,
    /// E_LC per term: of the central congruence (with lines c_u × c_v: 0 up to rounding), after
    /// step 1 and after step 2.
    pub lc_residual_step1: f64,
    pub lc_residual: f64,
    /// Solver iterations of the two steps.
    pub lc_iterations: usize,
    pub torsal_iterations: usize,
    pub lc_iteration_ms: Vec<f64>,
    pub torsal_iteration_ms: Vec<f64>,
    /// Step timings (ms): radius, line_congruence, torsal, metrics.
    pub timings_ms: Vec<(String, f64)>,
    pub warnings: Vec<String>,
}

impl SqCongruence {
    pub fn lc_iteration_median_ms(&self) -> Option<f64> {
        median(&self.lc_iteration_ms)
    }

    pub fn torsal_iteration_median_ms(&self) -> Option<f64> {
        median(&self.torsal_iteration_ms)
    }
}

/// Checks the parameters' ranges.
pub fn validate(params: &SqParams) -> Result<(), SqError> {
    let bad = |what: &str, v: String, lo: String, hi: String| Err(SqError::Parameter(format!("{what} {v} is outside [{lo}, {hi}]")));
    if !(GRID_RANGE.0..=GRID_RANGE.1).contains(&params.grid) {
        return bad("grid", params.grid.to_string(), GRID_RANGE.0.to_string(), GRID_RANGE.1.to_string());
    }
    if !(THETA_RANGE.0..=THETA_RANGE.1).contains(&params.theta_deg) {
        return bad("θ", params.theta_deg.to_string(), THETA_RANGE.0.to_string(), THETA_RANGE.1.to_string());
    }
    if !(ALPHA_RANGE.0..=ALPHA_RANGE.1).contains(&params.alpha_deg) {
        return bad("α", params.alpha_deg.to_string(), ALPHA_RANGE.0.to_string(), ALPHA_RANGE.1.to_string());
    }
    if !(RECOMPUTE_RANGE.0..=RECOMPUTE_RANGE.1).contains(&params.recompute_every) {
        return bad("RS", params.recompute_every.to_string(), RECOMPUTE_RANGE.0.to_string(), RECOMPUTE_RANGE.1.to_string());
    }
    let b = params.radius_basis;
    if !(1..=15).contains(&b.degree) || b.controls <= b.degree || b.controls > 40 {
        return Err(SqError::Parameter(format!(
            "radius basis: degree {} with {} coefficients per direction (degree 1..=15, more coefficients than the degree, at most 40)",
            b.degree, b.controls
        )));
    }
    Ok(())
}

/// Runs Sec. 5 and 5.1 on a B-spline reference (see the module docs).
pub fn compute(
    reference: &Reference,
    params: &SqParams,
    clock: Clock,
    on_event: &mut dyn FnMut(SqEvent) -> Result<(), Cancelled>,
) -> Result<SqCongruence, SqError> {
    validate(params)?;
    let spline = reference.spline().ok_or(SqError::NotBSpline)?;
    let mut timings = Timings::start(clock);
    on_event(SqEvent::Progress(Progress::new("radius", 0, 1)))?;
    let (lo, hi) = reference.mesh().bbox();
    let (t, s) = (0.5 * (lo + hi), reference.diagonal());
    let surface = spline.in_frame(t, s);
    let grid = SamplingGrid::new(&surface, params.grid)?;
    let signs = check_mean_curvature(&surface, &grid, (hi - lo).length() / s)?;
    let fit = fit_radius(&surface, &grid, params.radius_basis, &signs.excluded)?;
    let problem = CongruenceProblem::new(grid, &fit.function, params.inequality);
    let initial_lines = problem.congruence_lines(&fit.function.coefficients)?;
    let grid = &problem.grid;
    let initial_torsal = torsal_pairs(grid, &initial_lines);
    let initial_figures = CongruenceFigures::of(grid, &initial_lines, &initial_torsal);
    timings.lap("radius");
    let model_points: Vec<DVec3> = grid.frames.iter().map(|f| t + s * f.point).collect();
    on_event(SqEvent::Started { points: &model_points, lines: &initial_lines })?;

    let mut hook = |step: SqStep, iteration: usize, terms: &[TermStats], x: &[f64]| {
        on_event(SqEvent::Iteration { step, iteration, terms, lines: problem.lines(x) }).is_ok()
    };
    let mut x = problem.initial_point(&fit.function.coefficients, &initial_lines, params);
    let lc = problem.line_congruence_step(&mut x, params, clock, &mut hook);
    if lc.cancelled {
        return Err(SqError::Cancelled);
    }
    let lc_residual_step1 = problem.lc_residual(&x);
    timings.lap("line_congruence");
    let mut x = problem.extend_for_torsal(&x);
    let torsal = problem.torsal_step(&mut x, params, clock, &mut hook);
    if torsal.cancelled {
        return Err(SqError::Cancelled);
    }
    timings.lap("torsal");

    let lines = problem.lines(&x);
    let pairs = torsal_pairs(grid, &lines);
    let figures = CongruenceFigures::of(grid, &lines, &pairs);
    let lc_residual = problem.lc_residual(&x);
    let coefficients: Vec<f64> = x[problem.layout.radius.clone()].iter().map(|c| c * s).collect();
    let ((u0, u1), (v0, v1)) = spline.domain();
    let n = params.grid;
    let (du, dv) = ((u1 - u0) / (n - 1) as f64, (v1 - v0) / (n - 1) as f64);
    let torsal_uv = pairs
        .iter()
        .map(|p| {
            p.map(|p| {
                p.mu.map(|[m0, m1]| {
                    let (a, b) = ((m0 + m1) * du, (m0 - m1) * dv);
                    let len = a.hypot(b);
                    [a / len, b / len]
                })
            })
        })
        .collect();
    let radius = BSplineFunction { coefficients, ..fit.function.clone() };
    let radii = grid.uv.iter().map(|p| radius.evaluate(p[0], p[1]).0).collect();
    timings.lap("metrics");
    let mut warnings = Vec::new();
    warnings.extend(signs.warning);
    Ok(SqCongruence {
        grid: n,
        uv: grid.uv.clone(),
        points: model_points,
        normals: grid.frames.iter().map(|f| f.normal).collect(),
        radii,
        radius,
        radius_basis: params.radius_basis,
        radius_fit_error: fit.relative_error,
        initial_lines,
        lines,
        torsal: pairs,
        torsal_uv,
        initial_figures,
        figures,
        lc_residual_step1,
        lc_residual,
        lc_iterations: lc.iterations,
        torsal_iterations: torsal.iterations,
        lc_iteration_ms: lc.iteration_ms,
        torsal_iteration_ms: torsal.iteration_ms,
        timings_ms: timings.laps,
        warnings,
    })
}
