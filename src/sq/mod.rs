//! Sec. 5: SQ meshes with support structure: the congruence and its torsal cross field (5.1), the
//! quad mesh along it, the final sphere optimization, panels and support structure (5.2).
//!
//! The reference is a B-spline surface f(u, v) ([`crate::reference::bspline`]). The sphere
//! congruence has centres c = f + r n (Eq. 1) and radius r(u, v), a B-spline function (Eq. 8).
//!
//! 1. **Radius** ([`radius`]): sample f on the grid G; fit r to the central radii 1/H. Where H
//!    changes sign or nearly vanishes (Sec. 6.3) the central spheres do not exist, and the
//!    congruence is the constant start alone ([`start`]: the normal congruence, not optimized).
//! 2. **Line congruence** ([`optimization`], step 1): the lines l ∥ c_u × c_v (Sec. 2.1) become
//!    variables with the radius coefficients; E_LC keeps them in the congruence of r, E_LC_orth
//!    keeps them within θ of the normals.
//! 3. **Torsal directions** (step 2): per grid quad, two torsal directions whose planes meet at
//!    ≥ α (Fig. 20), recomputed every RS iterations.
//!
//! 4. **Quad mesh** ([`quad_mesh`], Sec. 5.2): the torsal cross field integrated to a quad mesh
//!    with about N faces, faired into Q′ by gliding over the reference.
//! 5. **Final optimization** ([`sphere_optimization`], Eq. 10): face spheres, vertices, node
//!    axes and torsal planes, then the projection to an exact SQ mesh with support structure.
//! 6. **Panels out** ([`sq_mesh`]): the exact mesh moved rigidly closest to the reference
//!    ([`crate::geometry::rigid_alignment`]; a rigid motion keeps it exact), then spherical quad
//!    panels, node axes and support elements, with the figures of exactness.
//!
//! [`compute`] runs as far as [`SqParams::until`] asks; [`compute_congruence`] runs steps 1–3.
//! With the `auto` start, [`compute`] runs from constant radii first and from the central
//! congruence only when that SQ mesh misses a guarantee, keeping the result that misses fewer;
//! from constant radii, a mesh that misses only the distance is optimized again with larger
//! radii on the same quad mesh.
//!
//! Everything is computed in the frame y = (x − t)/s of the bounding box (centre t, diagonal s),
//! so the weights are dimensionless; results are returned in model units.

pub mod congruence_file;
mod error;
pub mod guarantees;
pub mod metrics;
pub mod moulds;
pub mod optimization;
pub mod params;
pub mod quad_mesh;
pub mod radius;
pub mod report;
pub mod segments;
pub mod sphere_optimization;
pub mod sphere_terms;
pub mod sq_mesh;
pub mod start;
pub mod terms;

use glam::DVec3;

use crate::congruence::torsal::{parameter_pair, TorsalPair};
use crate::geometry::bspline::BSplineFunction;
use crate::geometry::bspline::BSplineSurface;
use crate::geometry::rigid_alignment::point_to_plane_motion;
use crate::panels::buildability::Buildability;
use crate::panels::deviation::panel_distances;
use crate::panels::exact_surface::ExactSurfaces;
use crate::panels::moulds::{per_face, Fabrication, MouldHook, RoundCount, RoundSchedule, EXACT_ROUNDS};
use crate::panels::panel::Panel;
use crate::progress::{Cancelled, Clock, Progress, Timings};
use crate::reference::assumptions::Warning;
use crate::reference::bspline::SplineReference;
use crate::reference::Reference;
use crate::remeshing::quad_remeshing::coverage;
use crate::solver::TermStats;
use crate::stats::median;
use crate::units::Units;

pub use self::error::SqError;
pub use self::guarantees::Delivered;
use self::metrics::{torsal_pairs, CongruenceFigures};
use self::moulds::{SqMouldOutcome, SqMouldRound, DISTANCE_GROWTH};
use self::optimization::{CongruenceProblem, SqStep};
use self::params::{RadiusBasis, RadiusStart, SqParams, Until, PROJECTION_MARGIN_DEG};
use self::quad_mesh::{quad_mesh, SqQuadMesh};
use self::radius::{check_mean_curvature, constant_radius_fit, fit_radius, mean_curvature_shares, RadiusFit, SamplingGrid};
use self::sphere_optimization::{on_grid, optimize_spheres, project_to_curvatures, QuadStars, SphereInput, SphereOutcome, SpherePhase};
use self::sq_mesh::{sq_mesh, SqMesh};
use self::start::{constant_function, constant_radius, spherical_reference};
use crate::geometry::mesh::PolyMesh;
use crate::geometry::sphere::Sphere;
use crate::guarantees::Verdict;
use crate::remeshing::quad_remeshing::edge_field_angles;

/// What the method reports while it runs.
pub enum SqEvent<'a> {
    Progress(Progress<'a>),
    /// Once, before the optimization: the points of G (model units) and the unit lines of the
    /// fitted central congruence.
    Started {
        points: &'a [DVec3],
        lines: &'a [DVec3],
    },
    /// After every solver iteration: the step, the iteration within it, the term statistics and
    /// the current unit lines of G.
    Iteration {
        step: SqStep,
        iteration: usize,
        terms: &'a [TermStats],
        lines: Vec<DVec3>,
    },
    /// The first start missed θ or α: the optimization starts again from `start`, with these
    /// unit lines.
    Restarted {
        start: RadiusStart,
        lines: &'a [DVec3],
    },
    /// Steps 1–3 are done.
    Congruence(&'a SqCongruence),
    /// The quad mesh as the remesh extracted it (before Q′).
    Remeshed {
        mesh: &'a PolyMesh,
    },
    /// After every fairing iteration of Q′: the term statistics and the vertices.
    Fairing {
        iteration: usize,
        terms: &'a [TermStats],
        positions: &'a [DVec3],
    },
    /// Q′ is done.
    QuadMesh(&'a SqQuadMesh),
    /// After every iteration of the final optimization: its phase, the iteration within the
    /// phase, the term statistics, the vertices and the face spheres (model units).
    Spheres {
        phase: SpherePhase,
        iteration: usize,
        terms: &'a [TermStats],
        positions: &'a [DVec3],
        spheres: &'a [Sphere],
    },
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
    /// The start the congruence kept, and every start tried with its figures.
    pub start: RadiusStart,
    pub attempts: Vec<CongruenceAttempt>,
    /// The reference is one sphere (centre, radius in model units): the trivial case.
    pub sphere: Option<(DVec3, f64)>,
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
    pub warnings: Vec<Warning>,
}

impl SqCongruence {
    pub fn lc_iteration_median_ms(&self) -> Option<f64> {
        median(&self.lc_iteration_ms)
    }

    pub fn torsal_iteration_median_ms(&self) -> Option<f64> {
        median(&self.torsal_iteration_ms)
    }
}

/// Checks the parameters' ranges ([`SqParams::check`]).
pub fn validate(params: &SqParams) -> Result<(), SqError> {
    params.check().map_err(SqError::Parameter)
}

/// One start of the congruence optimization and what it reached.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CongruenceAttempt {
    pub start: RadiusStart,
    /// Of the start's congruence, and of the optimized one (measured on the lines of r).
    pub initial_figures: CongruenceFigures,
    pub figures: CongruenceFigures,
    /// Grid points beyond θ, quads without real torsal directions and quads below α.
    pub misses: usize,
    /// The guarantees the SQ mesh from this start missed, when it was run to the end and
    /// another start's result was weighed against it ([`compute`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub final_misses: Option<Vec<String>>,
}

impl CongruenceAttempt {
    /// θ and α hold on all of G.
    pub fn meets_guarantees(&self) -> bool {
        self.misses == 0
    }
}

/// The optimized state of one start.
struct Optimized {
    x: Vec<f64>,
    lc_residual_step1: f64,
    lc: optimization::StepOutcome,
    torsal: optimization::StepOutcome,
}

/// Runs Sec. 5 and 5.1 on a B-spline reference (steps 1–3 of the module docs). With
/// [`RadiusStart::Auto`] it starts from the central congruence and, when the optimized
/// congruence misses θ or α on G, starts again from constant radii ([`start`]); it keeps the
/// first start that meets both, else the one with the fewest misses.
pub fn compute_congruence(
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
    let ((u0, u1), (v0, v1)) = spline.domain();
    let n = params.grid;
    let (du, dv) = ((u1 - u0) / (n - 1) as f64, (v1 - v0) / (n - 1) as f64);
    let model_points: Vec<DVec3> = grid.frames.iter().map(|f| t + s * f.point).collect();
    if let Some((centre, radius)) = spherical_reference(&grid) {
        let sphere = (t + s * centre, s * radius);
        return Ok(spherical_congruence(grid, model_points, sphere, params, [du, dv], spline.domain(), timings));
    }
    let StartingRadius { sign, fit, mut warnings, starts } = radius_start(&surface, &grid, (hi - lo).length() / s, params)?;
    let problem = CongruenceProblem::new(grid, &fit.function, params.inequality);
    let grid = &problem.grid;
    timings.lap("radius");

    let (attempts, kept) = optimize_starts(&problem, &fit.function, sign, starts, &model_points, params, clock, on_event)?;
    timings.lap("congruence");
    let Kept { chosen, optimized, initial_lines, lines, pairs } = kept;
    let figures = attempts[chosen].figures.clone();
    let x = optimized.x;
    let lc_residual = problem.lc_residual(&x);
    let coefficients: Vec<f64> = x[problem.layout.radius.clone()].iter().map(|c| c * s).collect();
    let torsal_uv = torsal_directions(&pairs, spline, n);
    let radius = BSplineFunction { coefficients, ..fit.function.clone() };
    let radii = grid.uv.iter().map(|p| radius.evaluate(p[0], p[1]).0).collect();
    timings.lap("metrics");
    warnings.extend(central_replaced(&attempts, chosen, params));
    let initial_figures = attempts[0].initial_figures.clone();
    Ok(SqCongruence {
        grid: n,
        uv: grid.uv.clone(),
        points: model_points,
        normals: grid.frames.iter().map(|f| f.normal).collect(),
        radii,
        radius,
        radius_basis: params.radius_basis,
        radius_fit_error: fit.relative_error,
        start: attempts[chosen].start,
        sphere: None,
        attempts,
        initial_lines,
        lines,
        torsal: pairs,
        torsal_uv,
        initial_figures,
        figures,
        lc_residual_step1: optimized.lc_residual_step1,
        lc_residual,
        lc_iterations: optimized.lc.iterations,
        torsal_iterations: optimized.torsal.iterations,
        lc_iteration_ms: optimized.lc.iteration_ms,
        torsal_iteration_ms: optimized.torsal.iteration_ms,
        timings_ms: timings.laps,
        warnings,
    })
}

/// The start kept by [`optimize_starts`]: its index among the attempts, the optimized
/// variables, the start's lines, the optimized lines and their torsal pairs.
struct Kept {
    chosen: usize,
    optimized: Optimized,
    initial_lines: Vec<DVec3>,
    lines: Vec<DVec3>,
    pairs: Vec<Option<TorsalPair>>,
}

/// Optimizes the congruence from each of `starts` in turn (H of sign `sign`); keeps the first
/// that meets θ and α, else the first with the fewest misses. The constant start is not
/// optimized, and its misses count the points of G where its radius cannot meet the guarantees
/// ([`start::constant_start_misses`]).
fn optimize_starts(
    problem: &CongruenceProblem,
    fitted: &BSplineFunction,
    sign: f64,
    starts: &[RadiusStart],
    model_points: &[DVec3],
    params: &SqParams,
    clock: Clock,
    on_event: &mut dyn FnMut(SqEvent) -> Result<(), Cancelled>,
) -> Result<(Vec<CongruenceAttempt>, Kept), SqError> {
    let grid = &problem.grid;
    let mut attempts: Vec<CongruenceAttempt> = Vec::new();
    // The kept start: the first that meets θ and α, else the first with the fewest misses.
    let mut best: Option<Kept> = None;
    for (k, &start) in starts.iter().enumerate() {
        let (function, collapsed) = match start {
            RadiusStart::Constant => {
                let (r, misses) = constant_radius(grid, sign, params.faces, params.max_distance)
                    .ok_or(SqError::MeanCurvatureNearZero { uv: grid.uv[0], h_diag: 0.0 })?;
                (constant_function(fitted, r), misses)
            }
            _ => (fitted.clone(), 0),
        };
        let initial_lines = match start {
            // The offset's lines are the normals (module docs of `start`).
            RadiusStart::Constant => grid.frames.iter().map(|f| f.normal).collect(),
            _ => problem.congruence_lines(&function.coefficients)?,
        };
        let initial_figures = CongruenceFigures::of(grid, &initial_lines, &torsal_pairs(grid, &initial_lines));
        if k == 0 {
            on_event(SqEvent::Started { points: model_points, lines: &initial_lines })?;
        } else {
            on_event(SqEvent::Restarted { start, lines: &initial_lines })?;
        }
        let optimized = match start {
            RadiusStart::Constant => Optimized::unchanged(problem, &function.coefficients, &initial_lines, params),
            _ => optimize(problem, &function.coefficients, &initial_lines, params, clock, on_event)?,
        };
        let lines = problem.measured_lines(&optimized.x);
        let pairs = torsal_pairs(grid, &lines);
        let figures = CongruenceFigures::of(grid, &lines, &pairs);
        let misses = metrics::misses(grid, &lines, &pairs, params.theta_deg, params.alpha_deg) + collapsed;
        attempts.push(CongruenceAttempt { start, initial_figures, figures, misses, final_misses: None });
        if best.as_ref().is_none_or(|b| misses < attempts[b.chosen].misses) {
            best = Some(Kept { chosen: k, optimized, initial_lines, lines, pairs });
        }
        if misses == 0 {
            break;
        }
    }
    Ok((attempts, best.expect("at least one start")))
}

/// A unit direction in parameters of (μ0, μ1) on a grid quad of spacing (Δu, Δv): d⁺ is
/// (Δu, Δv) and d⁻ is (Δu, −Δv) (Fig. 20).
fn parameter_direction([m0, m1]: [f64; 2], [du, dv]: [f64; 2]) -> [f64; 2] {
    let (a, b) = ((m0 + m1) * du, (m0 - m1) * dv);
    let len = a.hypot(b);
    [a / len, b / len]
}

impl Optimized {
    /// The start itself, as the optimization's state (no iterations).
    fn unchanged(problem: &CongruenceProblem, coefficients: &[f64], lines: &[DVec3], params: &SqParams) -> Self {
        let x = problem.extend_for_torsal(&problem.initial_point(coefficients, lines, params));
        let lc_residual_step1 = problem.lc_residual(&x);
        Self { x, lc_residual_step1, lc: Default::default(), torsal: Default::default() }
    }
}

/// The torsal directions of `pairs` as unit (du, dv) in the domain's units.
fn torsal_directions(pairs: &[Option<TorsalPair>], surface: &crate::geometry::bspline::BSplineSurface, n: usize) -> Vec<Option<[[f64; 2]; 2]>> {
    let ((u0, u1), (v0, v1)) = surface.domain();
    let spacing = [(u1 - u0) / (n - 1) as f64, (v1 - v0) / (n - 1) as f64];
    pairs.iter().map(|p| p.map(|p| p.mu.map(|m| parameter_direction(m, spacing)))).collect()
}

/// Steps 1 and 2 from radius coefficients and lines.
fn optimize(
    problem: &CongruenceProblem,
    coefficients: &[f64],
    lines: &[DVec3],
    params: &SqParams,
    clock: Clock,
    on_event: &mut dyn FnMut(SqEvent) -> Result<(), Cancelled>,
) -> Result<Optimized, SqError> {
    let mut hook = |step: SqStep, iteration: usize, terms: &[TermStats], x: &[f64]| {
        on_event(SqEvent::Iteration { step, iteration, terms, lines: problem.lines(x) })
    };
    let mut x = problem.initial_point(coefficients, lines, params);
    let lc = problem.line_congruence_step(&mut x, params, clock, &mut hook)?;
    let lc_residual_step1 = problem.lc_residual(&x);
    let mut x = problem.extend_for_torsal(&x);
    let torsal = problem.torsal_step(&mut x, params, clock, &mut hook)?;
    Ok(Optimized { x, lc_residual_step1, lc, torsal })
}

/// The trivial case: a sphere patch (see [`start`]). The lines are the normals, and every
/// direction being torsal, the cross field follows the parameter lines.
fn spherical_congruence(
    grid: SamplingGrid,
    points: Vec<DVec3>,
    sphere: (DVec3, f64),
    params: &SqParams,
    spacing: [f64; 2],
    domain: ((f64, f64), (f64, f64)),
    mut timings: Timings,
) -> SqCongruence {
    let lines: Vec<DVec3> = grid.frames.iter().map(|f| f.normal).collect();
    let pairs: Vec<Option<TorsalPair>> = (0..grid.quad_count())
        .map(|q| {
            let c = grid.quad(q);
            parameter_pair(c.map(|p| grid.frames[p].point), c.map(|p| lines[p]))
        })
        .collect();
    let figures = CongruenceFigures::of(&grid, &lines, &pairs);
    let torsal_uv = pairs.iter().map(|p| p.map(|p| p.mu.map(|m| parameter_direction(m, spacing)))).collect();
    let function = BSplineFunction::constant(sphere.1, domain);
    timings.lap("radius");
    let misses = metrics::misses(&grid, &lines, &pairs, params.theta_deg, params.alpha_deg);
    let attempt =
        CongruenceAttempt { start: RadiusStart::Central, initial_figures: figures.clone(), figures: figures.clone(), misses, final_misses: None };
    SqCongruence {
        grid: params.grid,
        uv: grid.uv.clone(),
        points,
        normals: lines.clone(),
        radii: vec![sphere.1; grid.point_count()],
        radius: function,
        radius_basis: params.radius_basis,
        radius_fit_error: 0.0,
        start: RadiusStart::Central,
        sphere: Some(sphere),
        attempts: vec![attempt],
        initial_lines: lines.clone(),
        lines,
        torsal: pairs,
        torsal_uv,
        initial_figures: figures.clone(),
        figures,
        lc_residual_step1: 0.0,
        lc_residual: 0.0,
        lc_iterations: 0,
        torsal_iterations: 0,
        lc_iteration_ms: Vec::new(),
        torsal_iteration_ms: Vec::new(),
        timings_ms: timings.laps,
        warnings: vec![Warning::OneSphere],
    }
}

/// The final SQ mesh (Sec. 5.2) with what the final optimization did.
#[derive(Clone, Debug)]
pub struct SqFinal {
    pub mesh: SqMesh,
    /// (u, v) of the final vertices (closest points).
    pub uv: Vec<[f64; 2]>,
    /// Angles (deg) between the final edges and the torsal directions.
    pub edge_angles_deg: Vec<f64>,
    pub outcome: SphereOutcome,
    /// The rounds toward fewer moulds (`optimize_moulds` on a result that met its guarantees).
    pub moulds: Option<SqMouldOutcome>,
    /// The panels' and support elements' exact surfaces (the CAD files hold these).
    pub exact: ExactSurfaces,
    /// What stops the panels from being built, measured on them.
    pub buildability: Buildability,
    /// The share of the patch's area the panels cover.
    pub coverage: f64,
}

impl SqFinal {
    /// The mesh, its panels and what was measured on them, for [`guarantees::verdict`].
    pub fn delivered(&self, params: &SqParams) -> Delivered<'_> {
        self.delivered_with(params, &self.buildability)
    }

    /// [`Self::delivered`] with `panels` measured on its panels.
    fn delivered_with<'a>(&'a self, params: &SqParams, panels: &'a Buildability) -> Delivered<'a> {
        Delivered::SqMesh {
            mesh: &self.mesh.sphere_mesh.mesh,
            figures: &self.mesh.figures,
            panels,
            max_distance: params.max_distance,
            coverage: self.coverage,
        }
    }

    /// The final mesh with its panels measured ([`measure_panels`]).
    fn new(reference: &Reference, mesh: SqMesh, uv: Vec<[f64; 2]>, edge_angles_deg: Vec<f64>, outcome: SphereOutcome) -> Self {
        let (exact, buildability, coverage) = measure_panels(reference, &mesh, &uv);
        SqFinal { mesh, uv, edge_angles_deg, outcome, moulds: None, exact, buildability, coverage }
    }
}

/// The exact surfaces of an SQ mesh's panels and support elements, what stops them from being
/// built (with each panel's distance to the reference) and the share of the patch they cover
/// (vertices at their closest points `uv`).
/// Lengths in the default unit: [`SqResult::verdict_in`] gives them in the design's.
pub fn measure_panels(reference: &Reference, mesh: &SqMesh, uv: &[[f64; 2]]) -> (ExactSurfaces, Buildability, f64) {
    let exact = ExactSurfaces::of(&mesh.panels, &mesh.support.elements);
    let distances = panel_distances(&mesh.panels, reference);
    let buildability = Buildability::measure(&exact, &distances, true, reference.diagonal(), Units::default());
    let coverage = reference.spline().map_or(f64::NAN, |s| coverage(s, &mesh.sphere_mesh.mesh.faces, uv));
    (exact, buildability, coverage)
}

/// What [`compute`] produced, as far as [`SqParams::until`] asked.
#[derive(Clone, Debug)]
pub struct SqResult {
    pub congruence: SqCongruence,
    pub quad_mesh: Option<SqQuadMesh>,
    pub sq_mesh: Option<SqFinal>,
    /// Step timings (ms) after the congruence: remesh (with Q′), spheres, panels.
    pub timings_ms: Vec<(String, f64)>,
    pub warnings: Vec<Warning>,
    /// The guarantees of what the run delivers ([`guarantees`]), measured on it.
    pub verdict: Verdict,
}

impl SqResult {
    /// The verdict of what the run delivers ([`guarantees::verdict`], as far as it ran): the one
    /// measurement the report, the CLI and the app read, lengths in `units` beside their share of
    /// the diagonal. [`Self::verdict`] is the same measurement in the default unit, which the
    /// method weighs its starts by.
    pub fn verdict_in(&self, params: &SqParams, units: Units) -> Verdict {
        let (c, theta, alpha) = (&self.congruence.figures, params.theta_deg, params.alpha_deg);
        match (&self.sq_mesh, &self.quad_mesh) {
            (Some(f), _) => {
                let panels = Buildability { units, ..f.buildability.clone() };
                guarantees::verdict(c, f.delivered_with(params, &panels), theta, alpha)
            }
            (None, Some(q)) => guarantees::verdict(c, Delivered::QuadMesh(&q.mesh, q.coverage), theta, alpha),
            (None, None) => guarantees::verdict(c, Delivered::Congruence, theta, alpha),
        }
    }

    /// Median time of a full-optimization iteration (ms).
    pub fn final_iteration_median_ms(&self) -> Option<f64> {
        self.sq_mesh.as_ref().and_then(|f| median(&f.outcome.iteration_ms))
    }
}

/// Runs the SQ method as far as `params.until` (see the module docs). With
/// [`RadiusStart::Auto`] to the final mesh: from constant radii, and when that SQ mesh misses a
/// guarantee, again from the central congruence where it exists and where its optimized
/// congruence misses θ or α on no more of G than the constant one (a congruence that misses more
/// has never led to a better SQ mesh: in none of the 80 runs of the corpora and the hard set
/// where both starts ran to the end was the central one kept); the result that misses fewer
/// guarantees is kept (constant radii among equals), with both starts among its attempts.
pub fn compute(
    reference: &Reference,
    params: &SqParams,
    fabrication: &Fabrication,
    clock: Clock,
    on_event: &mut dyn FnMut(SqEvent) -> Result<(), Cancelled>,
) -> Result<SqResult, SqError> {
    if params.start != RadiusStart::Auto || params.until != Until::Final {
        return compute_from(reference, params, fabrication, clock, on_event);
    }
    let mut constant = compute_from(reference, &SqParams { start: RadiusStart::Constant, ..params.clone() }, fabrication, clock, on_event)?;
    if constant.verdict.holds() {
        return Ok(constant);
    }
    // The second start's first event is a restart.
    let mut restarted = |e: SqEvent| match e {
        SqEvent::Started { lines, .. } => on_event(SqEvent::Restarted { start: RadiusStart::Central, lines }),
        e => on_event(e),
    };
    let central_params = SqParams { start: RadiusStart::Central, ..params.clone() };
    let central = match compute_congruence(reference, &central_params, clock, &mut restarted) {
        Ok(central) => central,
        Err(SqError::Cancelled) => return Err(SqError::Cancelled),
        // No central congruence (H changes sign or vanishes), or none that runs to the end.
        Err(_) => return Ok(constant),
    };
    let missed = |r: &SqResult| r.verdict.failures().map(|g| g.name.clone()).collect::<Vec<_>>();
    let weigh = |result: &mut SqResult, misses: Vec<String>| {
        let chosen = result.congruence.start;
        if let Some(a) = result.congruence.attempts.iter_mut().rev().find(|a| a.start == chosen) {
            a.final_misses = Some(misses);
        }
    };
    let misses_on_grid = |c: &SqCongruence| c.attempts.iter().find(|a| a.start == c.start).map_or(usize::MAX, |a| a.misses);
    if misses_on_grid(&central) > misses_on_grid(&constant.congruence) {
        let ms = central.timings_ms.iter().map(|(_, ms)| ms).sum();
        constant.timings_ms.push(("start_not_kept".into(), ms));
        let c = missed(&constant);
        weigh(&mut constant, c);
        constant.congruence.attempts.extend(central.attempts.into_iter().filter(|a| a.start == RadiusStart::Central));
        return Ok(constant);
    }
    let mut central = finish_from(reference, &central_params, central, fabrication, clock, &mut restarted)?;
    let (c, k) = (missed(&constant), missed(&central));
    let keep_central = k.len() < c.len();
    weigh(&mut constant, c);
    weigh(&mut central, k);
    let (mut kept, other) = if keep_central { (central, constant) } else { (constant, central) };
    let other_ms = other.congruence.timings_ms.iter().chain(&other.timings_ms).map(|(_, ms)| ms).sum();
    kept.timings_ms.push(("start_not_kept".into(), other_ms));
    let mut attempts = other.congruence.attempts;
    attempts.retain(|a| a.final_misses.is_some());
    if keep_central {
        attempts.append(&mut kept.congruence.attempts);
        kept.congruence.attempts = attempts;
    } else {
        kept.congruence.attempts.append(&mut attempts);
    }
    Ok(kept)
}

/// The radius function to start from (Eq. 8), the sign of H it follows, the warnings, and the
/// starts that exist.
struct StartingRadius {
    sign: f64,
    fit: RadiusFit,
    warnings: Vec<Warning>,
    starts: &'static [RadiusStart],
}

/// The radius function to start from (Eq. 8), the sign of H it follows, the warnings, and the
/// starts that exist: where H changes sign or vanishes, the central spheres pass through planes
/// and only the constant start exists (Sec. 6.3). `extent`: the frame's bounding-box diagonal.
fn radius_start(surface: &BSplineSurface, grid: &SamplingGrid, extent: f64, params: &SqParams) -> Result<StartingRadius, SqError> {
    match check_mean_curvature(surface, grid, extent, params.faces) {
        Ok(signs) => Ok(StartingRadius {
            sign: signs.sign,
            fit: fit_radius(surface, grid, params.radius_basis, &signs.excluded)?,
            warnings: signs.warnings,
            starts: params.start.starts(),
        }),
        Err(refusal @ (SqError::MeanCurvatureSignChange { .. } | SqError::MeanCurvatureNearZero { .. })) => {
            let [positive_share, negative_share] = mean_curvature_shares(surface);
            let sign = if positive_share >= negative_share { 1.0 } else { -1.0 };
            let r = match (params.start, constant_radius(grid, sign, params.faces, params.max_distance)) {
                (RadiusStart::Auto | RadiusStart::Constant, Some((r, _))) => r,
                _ => return Err(refusal),
            };
            let warning = Warning::CentralCongruenceUnbounded { positive_share, negative_share };
            let fit = constant_radius_fit(surface, params.radius_basis, r)?;
            Ok(StartingRadius { sign, fit, warnings: vec![warning], starts: &[RadiusStart::Constant] })
        }
        Err(e) => Err(e),
    }
}

/// The warning that the central congruence was tried and another start kept, with its figures.
fn central_replaced(attempts: &[CongruenceAttempt], chosen: usize, params: &SqParams) -> Option<Warning> {
    let central = attempts.iter().find(|a| a.start == RadiusStart::Central && a.start != attempts[chosen].start)?;
    let a = &central.figures;
    Some(Warning::CentralCongruenceReplaced {
        max_line_normal_angle_deg: a.max_line_normal_angle_deg,
        theta_deg: params.theta_deg,
        quads_without_real_torsal_directions: a.quads_without_real_torsal_directions,
        min_torsal_plane_angle_deg: a.min_torsal_plane_angle_deg,
        alpha_deg: params.alpha_deg,
    })
}

/// Rounds of the rigid alignment of the final mesh onto the reference.
const ALIGNMENT_ROUNDS: usize = 3;

/// The largest factor the constant start's radius grows by when its SQ mesh misses only the
/// distance to the reference.
const MAX_RADIUS_SCALE: f64 = 4.0;

/// The verdict misses the distance to the reference and nothing else.
fn only_distance_missed(verdict: &Verdict) -> bool {
    let missed: Vec<&str> = verdict.failures().map(|g| g.name.as_str()).collect();
    missed == [crate::panels::buildability::MAX_DISTANCE]
}

/// `tried` meets every guarantee, or misses only the distance, by less than `before` does.
fn closer(tried: &Verdict, before: &Verdict) -> bool {
    let distance =
        |v: &Verdict| v.guarantees.iter().find(|g| g.name == crate::panels::buildability::MAX_DISTANCE).map_or(f64::INFINITY, |g| g.measured);
    tried.holds() || (only_distance_missed(tried) && distance(tried) < distance(before))
}

/// [`compute`] from `params.start`'s starts, the one kept by their congruences' misses.
fn compute_from(
    reference: &Reference,
    params: &SqParams,
    fabrication: &Fabrication,
    clock: Clock,
    on_event: &mut dyn FnMut(SqEvent) -> Result<(), Cancelled>,
) -> Result<SqResult, SqError> {
    let congruence = compute_congruence(reference, params, clock, on_event)?;
    finish_from(reference, params, congruence, fabrication, clock, on_event)
}

/// [`compute_from`] after the congruence: the quad mesh and the final mesh from `congruence`.
fn finish_from(
    reference: &Reference,
    params: &SqParams,
    congruence: SqCongruence,
    fabrication: &Fabrication,
    clock: Clock,
    on_event: &mut dyn FnMut(SqEvent) -> Result<(), Cancelled>,
) -> Result<SqResult, SqError> {
    on_event(SqEvent::Congruence(&congruence))?;
    let mut warnings = congruence.warnings.clone();
    let (theta, alpha) = (params.theta_deg, params.alpha_deg);
    let verdict = guarantees::verdict(&congruence.figures, Delivered::Congruence, theta, alpha);
    let mut result = SqResult { congruence, quad_mesh: None, sq_mesh: None, timings_ms: Vec::new(), warnings: Vec::new(), verdict };
    if params.until == Until::Congruence {
        result.warnings = warnings;
        return Ok(result);
    }
    let mut timings = Timings::start(clock);
    on_event(SqEvent::Progress(Progress::new("remesh", 0, 1)))?;
    let quad = quad_mesh(reference, result.congruence.grid, &result.congruence.torsal_uv, params, clock, &mut |iteration, terms, positions| {
        on_event(SqEvent::Fairing { iteration, terms, positions })
    });
    let quad = match quad {
        Err(SqError::Cancelled) => return Err(SqError::Cancelled),
        other => other?,
    };
    on_event(SqEvent::Remeshed { mesh: &quad.remesh })?;
    on_event(SqEvent::QuadMesh(&quad))?;
    timings.lap("remesh");
    warnings.extend(quad.warnings.iter().cloned());
    if params.until == Until::Remesh {
        result.verdict = guarantees::verdict(&result.congruence.figures, Delivered::QuadMesh(&quad.mesh, quad.coverage), theta, alpha);
        result.quad_mesh = Some(quad);
        result.timings_ms = timings.laps;
        result.warnings = warnings;
        return Ok(result);
    }
    let mut done = final_mesh(reference, &result.congruence, &quad, params, fabrication, clock, &mut timings, on_event)?;
    let verdict = |f: &SqFinal| guarantees::verdict(&result.congruence.figures, f.delivered(params), theta, alpha);
    result.verdict = verdict(&done);
    if result.congruence.start == RadiusStart::Constant && result.congruence.sphere.is_none() {
        // Larger constant radii, when the mesh misses only the distance (see `start`).
        let (mut scale, mut kept_scale) = (1.0, 1.0);
        let retry = only_distance_missed(&result.verdict);
        while retry && scale < MAX_RADIUS_SCALE && !result.verdict.holds() {
            scale *= 2.0;
            let wider = SqCongruence { radius: result.congruence.radius.scaled(scale), ..result.congruence.clone() };
            let tried = final_mesh(reference, &wider, &quad, params, fabrication, clock, &mut timings, on_event)?;
            let v = verdict(&tried);
            if closer(&v, &result.verdict) {
                (done, result.verdict, kept_scale) = (tried, v, scale);
            }
        }
        result.congruence.radii.iter_mut().for_each(|r| *r *= kept_scale);
        result.congruence.radius = result.congruence.radius.scaled(kept_scale);
    }
    result.quad_mesh = Some(quad);
    result.sq_mesh = Some(done);
    result.timings_ms = timings.laps;
    result.warnings = warnings;
    Ok(result)
}

/// The trivial case: on one sphere every quad mesh is exact (see [`start`]): each vertex of Q′
/// on the sphere, every face sphere the sphere itself.
fn spherical_mesh(
    reference: &Reference,
    quad: &SqQuadMesh,
    stars: &QuadStars,
    centre: DVec3,
    r: f64,
    params: &SqParams,
    timings: &mut Timings,
) -> SqFinal {
    let diag = reference.diagonal();
    let positions: Vec<DVec3> = quad.mesh.positions.iter().map(|p| centre + r * (*p - centre).normalize_or(DVec3::Z)).collect();
    let normals: Vec<DVec3> = positions.iter().map(|p| (centre - *p) / r).collect();
    let sphere = Sphere::from_center_radius(centre, r).normalized();
    let mesh = PolyMesh::new(positions, quad.mesh.faces.clone());
    let spheres = vec![sphere; mesh.face_count()];
    let mut out = sq_mesh(mesh, spheres, &normals, stars, diag, params.support_depth * diag, params.axis_length * diag);
    let distance = out.sphere_mesh.mesh.positions.iter().map(|p| (p.distance(centre) - r).abs()).fold(0.0, f64::max);
    out.figures.max_vertex_distance_to_reference = distance / diag;
    let done = SqFinal::new(reference, out, quad.uv.clone(), quad.edge_angles_deg.clone(), SphereOutcome::default());
    timings.lap("panels");
    done
}

/// What the final optimization of Q′ works on (Sec. 5.2): the frame (lengths relative to the
/// diagonal about the bounding box's centre), Q′ in it with the congruence's radii, lines and
/// the normals at its vertices, and the stars of its vertices.
struct FinalSetup<'a> {
    reference: &'a Reference,
    surface: &'a BSplineSurface,
    spline: &'a SplineReference,
    quad: &'a SqQuadMesh,
    params: &'a SqParams,
    /// The frame: x ↦ (x − t) / s.
    t: DVec3,
    s: f64,
    framed: Reference,
    frame_mesh: PolyMesh,
    radii: Vec<f64>,
    lines: Vec<DVec3>,
    normals: Vec<DVec3>,
    stars: QuadStars,
}

impl<'a> FinalSetup<'a> {
    fn new(reference: &'a Reference, congruence: &SqCongruence, quad: &'a SqQuadMesh, params: &'a SqParams) -> Result<Self, SqError> {
        let surface = reference.spline().ok_or(SqError::NotBSpline)?;
        let spline = reference.spline_reference().ok_or(SqError::NotBSpline)?;
        let (lo, hi) = reference.mesh().bbox();
        let (t, s) = (0.5 * (lo + hi), reference.diagonal());
        let mesh = &quad.mesh;
        let frame_mesh = PolyMesh::new(mesh.positions.iter().map(|p| (*p - t) / s).collect(), mesh.faces.clone());
        let radii: Vec<f64> = quad.uv.iter().map(|uv| congruence.radius.evaluate(uv[0], uv[1]).0 / s).collect();
        let normals: Vec<DVec3> = quad.uv.iter().map(|uv| surface.derivatives(uv[0], uv[1]).normal().unwrap_or(DVec3::Z)).collect();
        let lines: Vec<DVec3> = quad
            .uv
            .iter()
            .zip(&normals)
            .map(|(uv, n)| {
                let l = on_grid(surface, congruence.grid, &congruence.lines, *uv).normalize_or_zero();
                if l.dot(*n) < 0.0 {
                    -l
                } else {
                    l
                }
            })
            .collect();
        let stars = QuadStars::new(mesh);
        Ok(Self { reference, surface, spline, quad, params, t, s, framed: reference.in_frame(t, s), frame_mesh, radii, lines, normals, stars })
    }

    /// The final optimization's input with Q′ (or a mesh of its faces) `frame_mesh` in the frame.
    fn input<'m>(&'m self, frame_mesh: &'m PolyMesh) -> SphereInput<'m> {
        let params = self.params;
        SphereInput {
            mesh: frame_mesh,
            radii: &self.radii,
            lines: &self.lines,
            normals: &self.normals,
            polylines: &self.quad.polylines,
            on_boundary: &self.quad.on_boundary,
            reference: &self.framed,
            cos2_theta: params.target_theta_deg().to_radians().cos().powi(2),
            cos2_alpha: params.target_alpha_deg().to_radians().cos().powi(2),
            limits: [params.theta_deg - PROJECTION_MARGIN_DEG, (params.alpha_deg + PROJECTION_MARGIN_DEG).min(90.0)],
        }
    }

    /// The optimizer's vertices and spheres, in the frame, back in model units.
    fn to_model(&self, v: &[DVec3], sp: &[Sphere]) -> (Vec<DVec3>, Vec<Sphere>) {
        (v.iter().map(|p| self.t + self.s * *p).collect(), sp.iter().map(|x| x.from_frame(self.t, self.s).normalized()).collect())
    }

    /// The SQ mesh of the optimized vertices and spheres (frame units): moved rigidly closest to
    /// the reference ([`Self::aligned`]), with its panels, support structure and node axes.
    fn finish(
        &self,
        vertices: &[DVec3],
        spheres: &[Sphere],
        outcome: SphereOutcome,
        on_event: &mut dyn FnMut(SqEvent) -> Result<(), Cancelled>,
    ) -> Result<SqFinal, SqError> {
        let (positions, spheres) = self.to_model(vertices, spheres);
        if positions.iter().any(|p| !p.is_finite()) || spheres.iter().any(|x| !x.is_finite()) {
            return Err(SqError::FinalOptimization("a vertex or a face sphere is not finite; try fewer faces or a smaller θ".into()));
        }
        on_event(SqEvent::Progress(Progress::new("panels", 0, 1)))?;
        let (positions, spheres) = self.aligned(positions, spheres);
        // The reference's closest points: (u, v), normals and the vertices' distance.
        let mut uv = Vec::with_capacity(positions.len());
        let mut final_normals = Vec::with_capacity(positions.len());
        let mut distance: f64 = 0.0;
        for (p, start) in positions.iter().zip(&self.quad.uv) {
            let (w, q, n) = self.spline.closest_point(*p, *start);
            uv.push(w);
            final_normals.push(n.unwrap_or(DVec3::Z));
            distance = distance.max(p.distance(q));
        }
        let (reference, params, quad) = (self.reference, self.params, self.quad);
        let diag = reference.diagonal();
        let mesh = PolyMesh::new(positions, quad.mesh.faces.clone());
        let edge_angles_deg = edge_field_angles(self.surface, &quad.torsal, &mesh, &uv, &quad.on_boundary);
        let mut out = sq_mesh(mesh, spheres, &final_normals, &self.stars, diag, params.support_depth * diag, params.axis_length * diag);
        out.figures.max_vertex_distance_to_reference = distance / diag;
        on_event(SqEvent::Progress(Progress::new("panels", 1, 1)))?;
        Ok(SqFinal::new(reference, out, uv, edge_angles_deg, outcome))
    }

    /// The rigid motion that brings the panels closest to the reference (their corners and the
    /// points of their spheres over their centres) keeps the mesh exact: applied when it brings
    /// the farthest point closer without sliding the panels off the patch (below what they
    /// covered, or below the guarantee).
    fn aligned(&self, positions: Vec<DVec3>, spheres: Vec<Sphere>) -> (Vec<DVec3>, Vec<Sphere>) {
        let (quad, spline) = (self.quad, self.spline);
        let faces = &quad.mesh.faces;
        let centre_uv: Vec<[f64; 2]> = faces
            .iter()
            .map(|f| {
                let k = f.corners().len() as f64;
                f.corners().iter().fold([0.0, 0.0], |a, &v| [a[0] + quad.uv[v as usize][0] / k, a[1] + quad.uv[v as usize][1] / k])
            })
            .collect();
        let centres = faces.iter().zip(&spheres).map(|(f, x)| {
            let m = f.corners().iter().map(|&v| positions[v as usize]).sum::<DVec3>() / f.corners().len() as f64;
            x.closest_point(m)
        });
        let before: Vec<DVec3> = positions.iter().copied().chain(centres).collect();
        let start_uv = |i: usize| if i < quad.uv.len() { quad.uv[i] } else { centre_uv[i - quad.uv.len()] };
        // One closest-point pass per set of points: the farthest of them, and the share of the
        // patch the panels cover with their corners at the closest points.
        let nv = positions.len();
        let measure = |points: &[DVec3]| -> (f64, f64) {
            let closest: Vec<([f64; 2], DVec3)> = points
                .iter()
                .enumerate()
                .map(|(i, p)| {
                    let (w, q, _) = spline.closest_point(*p, start_uv(i));
                    (w, q)
                })
                .collect();
            let farthest = closest.iter().zip(points).map(|((_, q), p)| q.distance(*p)).fold(0.0, f64::max);
            let uv: Vec<[f64; 2]> = closest[..nv].iter().map(|c| c.0).collect();
            (farthest, coverage(self.surface, faces, &uv))
        };
        let (rotation, shift) = point_to_plane_motion(&before, ALIGNMENT_ROUNDS, &mut |i, p| {
            let (_, q, n) = spline.closest_point(p, start_uv(i));
            Some((q, n?))
        });
        let after: Vec<DVec3> = before.iter().map(|p| rotation * *p + shift).collect();
        let ((far_before, covered_before), (far_after, covered_after)) = (measure(&before), measure(&after));
        if far_after < far_before && covered_after >= covered_before.min(guarantees::MIN_COVERAGE) {
            (after[..nv].to_vec(), spheres.iter().map(|x| x.moved(rotation, shift)).collect())
        } else {
            (positions, spheres)
        }
    }
}

/// The final optimization on Q′ and the SQ mesh out of it (Sec. 5.2); with `optimize_moulds`,
/// when it meets the method's guarantees, the rounds toward fewer moulds.
fn final_mesh(
    reference: &Reference,
    congruence: &SqCongruence,
    quad: &SqQuadMesh,
    params: &SqParams,
    fabrication: &Fabrication,
    clock: Clock,
    timings: &mut Timings,
    on_event: &mut dyn FnMut(SqEvent) -> Result<(), Cancelled>,
) -> Result<SqFinal, SqError> {
    let setup = FinalSetup::new(reference, congruence, quad, params)?;
    if let Some((centre, r)) = congruence.sphere {
        return Ok(spherical_mesh(reference, quad, &setup.stars, centre, r, params, timings));
    }
    // The Spheres event carries the phase and iteration: it is the progress of this step.
    let mut hook = |phase, iteration, terms: &[TermStats], v: &[DVec3], sp: &[Sphere]| {
        let (positions, spheres) = setup.to_model(v, sp);
        on_event(SqEvent::Spheres { phase, iteration, terms, positions: &positions, spheres: &spheres })
    };
    let (vertices, spheres, outcome) = optimize_spheres(&setup.input(&setup.frame_mesh), &setup.stars, params, clock, &mut hook)?;
    timings.lap("spheres");
    let done = setup.finish(&vertices, &spheres, outcome, on_event)?;
    timings.lap("panels");
    if !params.optimize_moulds || !setup.meets(congruence, &done) {
        return Ok(done);
    }
    let distance_limit = DISTANCE_GROWTH * done.mesh.figures.max_vertex_distance_to_reference;
    let mut moulds = Moulds { setup: &setup, congruence, clock, on_event, distance_limit };
    let run = crate::panels::moulds::fewer_moulds(&mut moulds, &done, reference.diagonal(), fabrication)?;
    timings.lap("fewer_moulds");
    let mut out = run.best.unwrap_or(done);
    out.moulds = Some(run.outcome);
    Ok(out)
}

impl FinalSetup<'_> {
    /// Whether `done` meets the method's guarantees (the verdict with the congruence's figures).
    fn meets(&self, congruence: &SqCongruence, done: &SqFinal) -> bool {
        let p = self.params;
        guarantees::verdict(&congruence.figures, done.delivered(p), p.theta_deg, p.alpha_deg).holds()
    }
}

/// SQ's part in the rounds toward fewer moulds ([`crate::panels::moulds::fewer_moulds`]): the
/// projection to exactness again from the exact mesh, every face held at its mould's curvature
/// ([`project_to_curvatures`]), landing on a nearby exact SQ mesh. A round counts when that mesh
/// meets the method's guarantees (exact, θ, α) and its vertices stay within
/// [`DISTANCE_GROWTH`] × the method's distance to the reference.
struct Moulds<'a, 'e> {
    setup: &'a FinalSetup<'a>,
    congruence: &'a SqCongruence,
    clock: Clock,
    on_event: &'a mut (dyn FnMut(SqEvent) -> Result<(), Cancelled> + 'e),
    distance_limit: f64,
}

impl MouldHook for Moulds<'_, '_> {
    type Result = SqFinal;
    type Round = SqMouldRound;
    type Error = SqError;

    fn schedule(&self) -> RoundSchedule {
        EXACT_ROUNDS
    }

    fn panels<'r>(&self, result: &'r SqFinal) -> &'r [Panel] {
        &result.mesh.panels
    }

    fn pull(&mut self, from: &SqFinal, per_panel: &[f64]) -> Result<Option<(SqFinal, bool)>, SqError> {
        let (setup, s, t) = (self.setup, self.setup.s, self.setup.t);
        let sm = &from.mesh.sphere_mesh;
        let curvatures = per_face(&from.mesh.panels, per_panel, sm.mesh.face_count(), s);
        let frame_mesh = PolyMesh::new(sm.mesh.positions.iter().map(|p| (*p - t) / s).collect(), sm.mesh.faces.clone());
        let spheres: Vec<Sphere> = sm.face_spheres.iter().map(|x| x.in_frame(t, s).normalized()).collect();
        let on_event = &mut *self.on_event;
        let mut hook = |phase, iteration, terms: &[TermStats], v: &[DVec3], sp: &[Sphere]| {
            let (positions, spheres) = setup.to_model(v, sp);
            on_event(SqEvent::Spheres { phase, iteration, terms, positions: &positions, spheres: &spheres })
        };
        let input = setup.input(&frame_mesh);
        let (v, sp, iterations) = project_to_curvatures(&input, &setup.stars, &spheres, &curvatures, setup.params, self.clock, &mut hook)?;
        let outcome = SphereOutcome { projection_iterations: iterations, ..from.outcome.clone() };
        let moved = match setup.finish(&v, &sp, outcome, self.on_event) {
            Err(SqError::Cancelled) => return Err(SqError::Cancelled),
            Err(_) => return Ok(None),
            Ok(m) => m,
        };
        let holds = setup.meets(self.congruence, &moved) && moved.mesh.figures.max_vertex_distance_to_reference <= self.distance_limit;
        Ok(Some((moved, holds)))
    }

    fn round(&self, moved: &SqFinal, count: RoundCount) -> SqMouldRound {
        let f = &moved.mesh.figures;
        SqMouldRound {
            coarsening: count.coarsening,
            moulds: count.moulds,
            max_vertex_sphere_residual: f.max_vertex_sphere_residual,
            max_centre_face_planarity: f.max_centre_face_planarity,
            max_axis_normal_angle_deg: f.max_axis_normal_angle_deg,
            min_support_plane_angle_deg: f.min_torsal_plane_angle_deg,
            max_vertex_distance_to_reference: f.max_vertex_distance_to_reference,
            kept: count.kept,
        }
    }

    fn distance_limit(&self) -> f64 {
        self.distance_limit
    }

    fn progress(&mut self, p: Progress) -> Result<(), Cancelled> {
        (self.on_event)(SqEvent::Progress(p))
    }
}
