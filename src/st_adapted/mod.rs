//! ST meshes with adapted face size (Sec. 3): the angle-minimizing ST mesh (Sec. 3 end, Sec. 5.2).
//!
//! Steps ([`compute`]): jet fit of the reference → refusal when the central spheres are
//! unusable (H ≈ 0, minimal surfaces) → sizing field (influence zones of the central spheres, or
//! a uniform field for a face count) → pliant remeshing → the remesh's central spheres (jets
//! on the remeshed mesh) → initialization → staged optimization
//! with [`crate::solver`] → boundary arcs along the reference boundary → metrics and warnings.
//!
//! **Initialization.** Every face sphere is the member of the pencil through its three vertices
//! ([`Sphere::through_points_family`], orthonormal basis s₀ (plane), s₁) closest to the face's
//! central sphere C (the normalized mean of its vertices' central spheres): maximizing ⟨s, C⟩
//! over cos θ s₀ + sin θ s₁ gives θ = atan2(⟨s₁, C⟩, ⟨s₀, C⟩). It is oriented like the face
//! (cos θ ≥ 0; else negated).
//!
//! **Optimization** (in a frame centred at the reference's bounding box and scaled by its
//! diagonal, so weights are dimensionless). Variables: one pencil angle θ_f per face (first) and
//! the vertices (3-blocks, after). Face f's sphere is the member s_f = cos θ_f s₀ + sin θ_f s₁ of
//! the pencil through its three vertices ([`crate::geometry::pencil`]): it passes through them
//! wherever they move, so E_sphere and E_unit of the paper hold exactly and a sphere costs one
//! unknown, not five. Terms ([`terms::build_problem`]):
//! - `angle`: ⟨s_f, s_g⟩ − 1 for every interior edge (⟨s_f, s_g⟩ is the cosine of the kink angle
//!   for spheres oriented alike), through the chain rule to θ and the four vertices;
//! - `tangent_distance`: n_v·(v − q_v), q_v the closest reference point, n_v the reference normal
//!   there (barycentric vertex normals), updated in `Term::prepare` (vertices glide, Sec. 5.2);
//! - `point_distance`: v − q_v (small weight; ×[`terms::BOUNDARY_POINT_FACTOR`] on boundary vertices so
//!   the boundary does not slide off);
//! - `face_distance`: ψ_f(r_f) with r_f the reference point closest to face f's centroid
//!   ([`crate::reference::proximity::CentroidTargets`], same weight schedule as the proximity terms):
//!   keeps the panels, not only the vertices, near the reference;
//! - `fairness`: uniform Laplacian v − mean(neighbours) at interior vertices (small weight);
//! - `edge_circle` (variant (a) only): the sideways bulge of every interior edge's arc, zero when
//!   the intersection circle is orthogonal to the reference (Sec. 6.1, Fig. 12 left) — see
//!   [`terms::EdgeCircle`]; without it, two nearly tangent spheres of different radii meet in a
//!   small circle whose arc overhangs the surface;
//! - `sagitta_match` (variant (a) only, with a tolerance ε): the two panels of an interior edge
//!   bulge alike over it, within τ ([`terms::SagittaMatch`] in a [`crate::solver::Band`] of the
//!   tolerance band's weight): near the boundary of a surface whose H changes sign, a nearly flat
//!   sphere beside a small one meets it in a circle whose arc overhangs the boundary, which the
//!   edge-circle term's small-arc estimate underrates (conical1 at ε = 2e-3: 4.1ε → 1.8ε);
//! - `orientation`: each face keeps an oriented area of at least 0.2 × its initial one (a hinge
//!   barrier, [`terms::FaceOrientation`]), so gliding vertices never fold a face;
//! - `vertex_tolerance`, `face_tolerance`: the tangent distance and the face distance beyond τ,
//!   ε/2 or the reference's facet sagitta if that is larger
//!   ([`params::StAdaptedParams::tolerance_band`]), in a [`crate::solver::Band`] with a large
//!   weight (zero inside, a logarithmic wall outside): the proximity terms pull everything toward
//!   the reference, the band keeps the outliers within the user's tolerance, so the panels stay
//!   near 2ε of it, not only on average.
//!
//! The stages ([`params::OptimizationStage`]) scale the proximity weights (larger first, then
//! relaxed). No projection is needed at the end: the spheres pass through their vertices to
//! rounding.
//!
//! **Variant (b)** (Fig. 12 bottom): the same spheres, but each interior edge arc is cut from
//! each face sphere by the *bisecting plane* of the two face planes (the plane through the edge
//! containing n_f + n_g). Both cut curves pass through the edge's vertices but differ in between.
//! The panels and exports of variant (b) cut each sphere the same way
//! ([`EdgeArcs::BisectingPlanes`]); the gap between the two arcs of an edge is measured on the
//! panels' own arcs ([`crate::panels::gaps::arc_gaps`]).
//!
//! **Boundary arcs** ([`boundary_arcs`]): each boundary edge is cut by the plane whose arc passes
//! nearest the reference boundary. Where the reference has no boundary near the edge, the rule
//! [`BoundaryArcRule::Parallel`]`(0)` holds: the plane through the edge and the face sphere's
//! centre (a great-circle arc; straight for planes). The initial mesh and the live snapshots
//! use that rule throughout.

// Negated float comparisons are deliberate: they also reject NaN.

pub mod boundary_arcs;
pub mod events;
pub mod guarantees;
pub mod initialization;
pub mod metrics;
pub mod moulds;
pub mod optimization;
pub mod params;
pub mod report;
pub mod terms;
pub mod warm_up;

use std::fmt;

use glam::DVec3;

use crate::congruence::central_spheres::{CurvatureField, UnusableCentralSpheres};
use crate::geometry::mesh::TriMesh;
use crate::geometry::sphere::Sphere;
use crate::panels::edge_arcs::EdgeArcs;
use crate::panels::moulds::Fabrication;
use crate::panels::panel::Panel;
use crate::panels::sphere_mesh::{BoundaryArcRule, SphereMesh};
use crate::progress::{Cancelled, Clock, Progress, Timings};
use crate::reference::assumptions::{coarseness_warning, kink_warning, method_warnings, Warning};
use crate::reference::{Reference, ReferenceError};
use crate::remeshing::{GuardedRemeshError, RemeshRefused, SizingBounds, TooManyFaces};
use crate::solver::{IterationReport, Solver, SolverOptions, TermStats};
use crate::stats::median;
pub use events::{OnEvent, StAdaptedEvent};
use initialization::initial_spheres;
use metrics::{metrics, shape, StAdaptedMetrics, StAdaptedShape};
use moulds::{fewer_moulds_of, Moved, StAdaptedMouldOutcome};
use optimization::{run_stages, OptimizationFrame};
use params::StAdaptedParams;

/// Why the method gave no mesh.
#[derive(Clone, Debug, PartialEq)]
pub enum StAdaptedError {
    Cancelled,
    Reference(ReferenceError),
    /// H ≈ 0 on most of the surface: no central spheres to start from or to size faces by.
    NoCentralSpheres(UnusableCentralSpheres),
    NoFaces,
    /// The remesh could not reach the asked face count; the reference's failed assumptions
    /// (folds, slivers) often say why.
    Remesh(RemeshRefused),
    /// More faces than the method handles.
    TooManyFaces(TooManyFaces),
    /// A parameter outside its range.
    Parameter(crate::params::ParamError),
}

impl fmt::Display for StAdaptedError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StAdaptedError::Cancelled => f.write_str("cancelled"),
            StAdaptedError::Reference(e) => e.fmt(f),
            StAdaptedError::NoCentralSpheres(e) => write!(
                f,
                "{e}; the angle-minimizing ST method initializes its face spheres from central spheres and its face \
                 size from their influence zones"
            ),
            StAdaptedError::NoFaces => f.write_str("remeshing produced no faces"),
            StAdaptedError::Remesh(e) => e.fmt(f),
            StAdaptedError::TooManyFaces(e) => e.fmt(f),
            StAdaptedError::Parameter(e) => e.fmt(f),
        }
    }
}

impl std::error::Error for StAdaptedError {}

impl From<Cancelled> for StAdaptedError {
    fn from(_: Cancelled) -> Self {
        StAdaptedError::Cancelled
    }
}

impl From<GuardedRemeshError> for StAdaptedError {
    fn from(e: GuardedRemeshError) -> Self {
        match e {
            GuardedRemeshError::Cancelled => StAdaptedError::Cancelled,
            GuardedRemeshError::NoFaces => StAdaptedError::NoFaces,
            GuardedRemeshError::Refused(r) => StAdaptedError::Remesh(r),
            GuardedRemeshError::TooManyFaces(t) => StAdaptedError::TooManyFaces(t),
        }
    }
}

/// What the method makes.
#[derive(Clone, Debug)]
pub struct StAdaptedResult {
    pub sphere_mesh: SphereMesh,
    /// The panels of `sphere_mesh` for the variant, tessellated to
    /// [`crate::panels::DEFAULT_CHORD_TOLERANCE`] of the diagonal.
    pub panels: Vec<Panel>,
    /// Each panel's largest distance to the reference ([`crate::panels::deviation::max_deviation`],
    /// absolute), measured once for the metrics and the schedule.
    pub panel_deviations: Vec<f64>,
    pub initial_sphere_mesh: SphereMesh,
    pub remeshed: TriMesh,
    /// min / max of the sizing field g (absolute), when the reference was remeshed to it.
    pub sizing_range: Option<(f64, f64)>,
    /// The initial sphere mesh's shape (it gets no panels).
    pub initial_shape: StAdaptedShape,
    pub metrics: StAdaptedMetrics,
    /// Solver iterations over all stages.
    pub iterations: usize,
    /// Per-iteration times (ms) when a clock was given.
    pub iteration_ms: Vec<f64>,
    /// Median of `iteration_ms`.
    pub angle_iteration_median_ms: Option<f64>,
    /// Whether the sparse Cholesky factorization was supernodal (else simplicial).
    pub supernodal: bool,
    /// Step timings (ms) when a clock was given: jet_fit, sizing, remesh, init, optimize, metrics.
    pub timings_ms: Vec<(String, f64)>,
    pub diag: f64,
    pub variant: EdgeArcs,
    /// Final term statistics.
    pub terms: Vec<TermStats>,
    /// The rounds toward fewer moulds and the snap to their radii (`optimize_moulds`).
    pub moulds: Option<StAdaptedMouldOutcome>,
    /// The method's assumptions the reference fails (H of one sign, no folds, no slivers, not
    /// coarser than ε) and the kinks over the warning angle.
    pub warnings: Vec<Warning>,
}

/// Announces a step (0 of 0).
fn step(on_event: &mut OnEvent, name: &str) -> Result<(), Cancelled> {
    on_event(StAdaptedEvent::Progress(Progress::new(name, 0, 0)))
}

/// The angle-minimizing ST method end to end (see the module docs): the curvature and its
/// refusal, sizing and remeshing, the initial spheres, the optimization, the metrics.
pub fn compute(
    reference: &Reference,
    params: &StAdaptedParams,
    fabrication: &Fabrication,
    clock: Clock,
    on_event: &mut OnEvent,
) -> Result<StAdaptedResult, StAdaptedError> {
    params.check().map_err(StAdaptedError::Parameter)?;
    reference.validate().map_err(StAdaptedError::Reference)?;
    let mut timings = Timings::start(clock);
    step(on_event, "jet_fit")?;
    timings.skip();
    let field = reference.curvature(&params.jet, &mut |p| on_event(StAdaptedEvent::Progress(p)))?;
    field
        .usable_central_spheres(reference.mesh().vertex_count(), reference.diagonal(), params.min_curvature_ratio, params.min_usable_fraction)
        .map_err(StAdaptedError::NoCentralSpheres)?;
    timings.lap("jet_fit");
    let (remeshed, sizing_range) = remesh(reference, &field, params, &mut timings, on_event)?;
    let remeshed_by_sizing = sizing_range.is_some();
    step(on_event, "init")?;
    timings.skip();
    // The remesh's own central spheres, as ST with support structure takes them: jets on the
    // mesh the face spheres pass through (examples/remesh_central_spheres.rs measures both ways).
    let central_spheres = match remeshed_by_sizing {
        true => Reference::from_triangles(remeshed.clone())
            .curvature(&params.jet, &mut |p| on_event(StAdaptedEvent::Progress(p)))?
            .central_spheres
            .clone(),
        false => field.central_spheres.clone(),
    };
    let init = initial_spheres(&remeshed, &central_spheres);
    let initial_sphere_mesh = SphereMesh::new(&remeshed, init.clone(), BoundaryArcRule::Parallel(DVec3::ZERO));
    timings.lap("init");
    on_event(StAdaptedEvent::Initialized { sphere_mesh: &initial_sphere_mesh })?;
    step(on_event, "optimize")?;
    timings.skip();
    let optimized = optimize(reference, &remeshed, &init, params, clock, on_event)?;
    timings.lap("optimize");
    step(on_event, "metrics")?;
    timings.skip();
    let initial_shape = shape(&initial_sphere_mesh, reference);
    let mut sphere_mesh = optimized.sphere_mesh;
    let (mut final_metrics, mut panels, mut panel_deviations) = metrics(&sphere_mesh, reference, params.variant);
    timings.lap("metrics");
    let mut moulds = None;
    if params.optimize_moulds {
        step(on_event, "fewer_moulds")?;
        timings.skip();
        let start = Moved { sphere_mesh, panels, deviations: panel_deviations, metrics: final_metrics };
        let (moved, outcome) = fewer_moulds_of(reference, start, params, fabrication, clock, &mut timings, on_event)?;
        (sphere_mesh, panels, panel_deviations, final_metrics) = (moved.sphere_mesh, moved.panels, moved.deviations, moved.metrics);
        moulds = Some(outcome);
    }
    let mut warnings = method_warnings(reference, &field, remeshed_by_sizing.then_some(&remeshed));
    warnings.extend(kink_warning(&sphere_mesh.kink_angles_deg(), reference));
    if let Some(epsilon) = params.epsilon() {
        warnings.extend(coarseness_warning(reference, epsilon));
    }
    Ok(StAdaptedResult {
        sphere_mesh,
        panels,
        panel_deviations,
        initial_sphere_mesh,
        remeshed,
        sizing_range,
        initial_shape,
        metrics: final_metrics,
        iterations: optimized.iterations,
        angle_iteration_median_ms: median(&optimized.iteration_ms),
        iteration_ms: optimized.iteration_ms,
        supernodal: optimized.supernodal,
        timings_ms: if clock.0.is_some() { timings.laps } else { Vec::new() },
        diag: reference.diagonal(),
        variant: params.variant,
        terms: optimized.terms,
        moulds,
        warnings,
    })
}

/// The sizing field g and the pliant remesh to it (Sec. 3) behind the shared guards; the mesh
/// as is without a sizing. The range of g when it was remeshed to it.
fn remesh(
    reference: &Reference,
    field: &CurvatureField,
    params: &StAdaptedParams,
    timings: &mut Timings,
    on_event: &mut OnEvent,
) -> Result<(TriMesh, Option<(f64, f64)>), StAdaptedError> {
    step(on_event, "remesh")?;
    timings.skip();
    let (mesh, topo) = (reference.mesh(), reference.topology());
    let sphere_of = |i: usize| field.central_spheres.get(i).copied().unwrap_or_else(|| Sphere::plane(mesh.positions[i], DVec3::Z));
    let bounds = SizingBounds::for_mesh(mesh, topo);
    let sizing = params.sizing.guarded_field(mesh, topo, &sphere_of, bounds, &mut |p| on_event(StAdaptedEvent::Progress(p)))?;
    timings.lap("sizing");
    let remeshed = match &sizing {
        Some(sizing) => {
            on_event(StAdaptedEvent::Sizing { values: sizing.values() })?;
            timings.skip();
            let warnings = || method_warnings(reference, field, None);
            params.sizing.remesh_to(mesh, sizing, &params.remesh, &warnings, &mut |p| on_event(StAdaptedEvent::Progress(p)))?
        }
        None => mesh.clone(),
    };
    timings.lap("remesh");
    on_event(StAdaptedEvent::Remeshed { mesh: &remeshed })?;
    let range = sizing.map(|g| g.values().iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &g| (lo.min(g), hi.max(g))));
    Ok((remeshed, range))
}

/// What the optimization made.
struct Optimized {
    sphere_mesh: SphereMesh,
    terms: Vec<TermStats>,
    iterations: usize,
    iteration_ms: Vec<f64>,
    supernodal: bool,
}

/// The optimization in the normalized frame, its stages one after the other; the boundary arcs
/// cut along the reference boundary.
fn optimize(
    reference: &Reference,
    remeshed: &TriMesh,
    init: &[Sphere],
    params: &StAdaptedParams,
    clock: Clock,
    on_event: &mut OnEvent,
) -> Result<Optimized, StAdaptedError> {
    let frame = OptimizationFrame::new(reference, remeshed, init, params);
    let mut x = frame.x0.clone();
    let (mut problem, ids) = frame.problem(&params.variant_weights());
    let mut solver = Solver::new(SolverOptions { clock, ..SolverOptions::default() });
    let total = params.total_iterations();
    let mut iteration = 0usize;
    let mut hook = |name: &str, rep: &IterationReport| {
        iteration += 1;
        let (vertices, spheres) = frame.to_model(rep.x);
        on_event(StAdaptedEvent::Iteration {
            progress: Progress::new(name, iteration, total),
            energy: rep.energy,
            terms: rep.terms,
            vertices: &vertices,
            spheres: &spheres,
        })
    };
    let run = run_stages(&mut problem, &ids, &mut x, params, &mut solver, &mut hook).map_err(|Cancelled| StAdaptedError::Cancelled)?;
    let model = |x: &[f64]| {
        let (verts, sph) = frame.to_model(x);
        let sphere_mesh = SphereMesh::new(TriMesh::new(verts, remeshed.triangles.clone()), sph, BoundaryArcRule::Parallel(DVec3::ZERO));
        boundary_arcs::delivered_arcs(sphere_mesh, reference, params.variant)
    };
    problem.prepare_all(&x);
    let terms = problem.term_stats(&x);
    Ok(Optimized {
        sphere_mesh: model(&x),
        terms,
        iterations: iteration,
        supernodal: run.last.as_ref().is_some_and(|r| r.supernodal),
        iteration_ms: run.iteration_ms,
    })
}
