//! ST meshes with support structure (Sec. 4).
//!
//! Input: the reference's triangulation (or, with `remesh`, a remesh of it: uniform, or adaptive
//! with the sizing field of the local spheres orthogonal to the Ω estimated on the reference, Fig. 16
//! bottom) and its curvature field.
//! Each step is one file, and [`compute`] reads like this list.
//! 1. Ω is estimated ([`absolute_sphere`], Eq. 7). When m0 lay on the positive side the working
//!    orientation is flipped: the output mesh has every triangle's winding reversed, so that its
//!    normals point away from m (the support structure is on the negative side).
//! 2. [`face_spheres`]: each face sphere passes through its triangle's three vertices and is orthogonal to Ω
//!    ([`Sphere::through_points_orthogonal`]: the null vector of the 4 × 5 system, a plane where
//!    it must), oriented like the (working) face normal.
//! 3. Option `optimize_radius` (Fig. 16 right, [`optimize_radius`]::[`choose_omega`]): R² (or the plane offset d)
//!    minimizing the mean kink angle, the vertices and m (or a) fixed.
//! 4. Node axes ([`crate::congruence::support_structure::node_axes`], the one definition): the
//!    line through v and the second common point v̄ of the spheres around v, from those spheres,
//!    not assumed. Where a star does not determine it (fewer than 3 faces, or nearly coaxal
//!    spheres) the axis is the line v m (or parallel to a) and does not count in
//!    `max_node_axis_offset`.
//! 5. [`support_elements`]: per edge the arc circle
//!    ([`crate::congruence::support_structure::edge_circle`]: interior edges the intersection
//!    circle of the two face spheres, boundary edges the plane through the edge and m, or parallel
//!    to a), and the annulus sector between the node axes with the given depth
//!    ([`crate::congruence::support_structure::SupportElement`]), tessellated along the panels'
//!    own arcs for display and export.
//! 6. [`second_envelope`]: the mesh inverted in Ω (same triangles). Given for R² > 0 (Fig. 10),
//!    also for R² < 0 (anti-inversion: the spheres pass through the anti-inverted vertices too)
//!    and for a plane Ω (reflection); None for R² = 0 (it degenerates to m).
//! 7. [`metrics`], measured on the result, and the panels ([`crate::panels::build_panels`]), their support strips and the node axes as
//!    segments: what is exported and shown.

// Negated float comparisons are deliberate: they also reject NaN.

pub mod absolute_sphere;
pub mod face_spheres;
pub mod guarantees;
pub mod metrics;
pub mod moulds;
pub mod optimize_radius;
pub mod params;
pub mod report;
pub mod second_envelope;
pub mod support_elements;

use std::fmt;
use std::rc::Rc;

use glam::DVec3;

use crate::congruence::central_spheres::CurvatureField;
use crate::congruence::support_structure::{node_axes, support_strips, EdgePlane, SupportStructure};
use crate::geometry::absolute_sphere::AbsoluteSphere;
use crate::geometry::mesh::topology::Topology;
use crate::geometry::mesh::TriMesh;
use crate::geometry::sphere::Sphere;
use crate::panels::deviation::max_distance_to_reference;
use crate::panels::moulds::{per_face, Fabrication, MouldHook, RoundCount, RoundSchedule, EXACT_ROUNDS};
use crate::panels::panel::Panel;
use crate::panels::sphere_mesh::{BoundaryArcRule, SphereMesh};
use crate::panels::{build_panels, edge_arc_points, DEFAULT_CHORD_TOLERANCE};
use crate::progress::{Cancelled, Clock, OnProgress, Progress, Timings};
use crate::reference::assumptions::{kink_warning, method_warnings, Warning};
use crate::reference::{Reference, ReferenceError};
use crate::remeshing::{
    local_spheres_orthogonal, mean_edge_length, GuardedRemeshError, RemeshParams, RemeshRefused, Sizing, SizingBounds, TooManyFaces,
};
use absolute_sphere::{estimate_absolute_sphere, AbsoluteSphereError, AbsoluteSphereEstimate, AbsoluteSphereParams};
use face_spheres::face_spheres;
pub use metrics::StSupportMetrics;
use metrics::{metrics, Counts};
use moulds::{StSupportMouldOutcome, StSupportMouldRound};
use optimize_radius::choose_omega;
pub use params::{StSupportParams, LOCAL_SPHERE_POINTS};
use second_envelope::second_envelope;
use support_elements::support_elements;

/// Why the method gave no mesh.
#[derive(Clone, Debug, PartialEq)]
pub enum StSupportError {
    Cancelled,
    Reference(ReferenceError),
    AbsoluteSphere(AbsoluteSphereError),
    NoFaces,
    /// The remesh could not reach the asked face count; the reference's failed assumptions
    /// (folds, slivers) often say why.
    Remesh(RemeshRefused),
    /// More faces than the method handles.
    TooManyFaces(TooManyFaces),
    /// A parameter outside its range.
    Parameter(crate::params::ParamError),
}

impl fmt::Display for StSupportError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StSupportError::Cancelled => f.write_str("cancelled"),
            StSupportError::Reference(e) => e.fmt(f),
            StSupportError::AbsoluteSphere(e) => e.fmt(f),
            StSupportError::NoFaces => f.write_str("remeshing produced no faces"),
            StSupportError::Remesh(e) => e.fmt(f),
            StSupportError::TooManyFaces(e) => e.fmt(f),
            StSupportError::Parameter(e) => e.fmt(f),
        }
    }
}

impl std::error::Error for StSupportError {}

impl From<Cancelled> for StSupportError {
    fn from(_: Cancelled) -> Self {
        StSupportError::Cancelled
    }
}

impl From<GuardedRemeshError> for StSupportError {
    fn from(e: GuardedRemeshError) -> Self {
        match e {
            GuardedRemeshError::Cancelled => StSupportError::Cancelled,
            GuardedRemeshError::NoFaces => StSupportError::NoFaces,
            GuardedRemeshError::Refused(r) => StSupportError::Remesh(r),
            GuardedRemeshError::TooManyFaces(t) => StSupportError::TooManyFaces(t),
        }
    }
}

impl From<AbsoluteSphereError> for StSupportError {
    fn from(e: AbsoluteSphereError) -> Self {
        StSupportError::AbsoluteSphere(e)
    }
}

/// Everything [`compute`] produces.
#[derive(Clone, Debug)]
pub struct StSupportResult {
    /// The mesh (winding reversed when `absolute.flipped`), its face spheres and the boundary arc
    /// rule (through m, or parallel to a).
    pub sphere_mesh: SphereMesh,
    /// The panels, tessellated to [`DEFAULT_CHORD_TOLERANCE`] of the diagonal.
    pub panels: Vec<Panel>,
    /// Node axes (toward the support side), support elements and their strips.
    pub support: SupportStructure,
    /// The estimate of Sec. 4 with the histogram data (its `omega` is the mean-R² estimate).
    pub absolute: AbsoluteSphereEstimate,
    /// The Ω the face spheres are orthogonal to: the estimate, or the optimized R² / d.
    pub omega: AbsoluteSphere,
    /// The optimized R² (or d for a plane) when `optimize_radius`.
    pub optimized_parameter: Option<f64>,
    /// Mean kink angle (deg) with the mean-R² estimate (equals the metric unless optimized).
    pub mean_kink_estimate_deg: f64,
    pub second_envelope: Option<TriMesh>,
    /// The bounding-box diagonal of the mesh the method ran on (the remeshed one, if any).
    pub diag: f64,
    pub metrics: StSupportMetrics,
    /// (step, milliseconds) in execution order.
    pub timings_ms: Vec<(String, f64)>,
    /// The method's assumptions the reference fails (H of one sign, no folds, no slivers).
    pub warnings: Vec<Warning>,
    /// The rounds toward fewer moulds (`optimize_moulds`).
    pub moulds: Option<StSupportMouldOutcome>,
}

/// The reference remeshed as `params.remesh` asks, or None. The adaptive sizing field uses local
/// least-squares spheres orthogonal to the Ω estimated on the reference (Sec. 3, Fig. 16
/// bottom); faces are never finer than the reference's mean edge length, where spheres through
/// sub-facet faces would fit the facets' creases, not the surface.
fn remeshed_reference(
    reference: &Reference,
    field: &CurvatureField,
    params: &StSupportParams,
    progress: &mut OnProgress,
) -> Result<Option<Reference>, StSupportError> {
    let (mesh, topo) = (reference.mesh(), reference.topology());
    let mut bounds = SizingBounds::for_mesh(mesh, topo);
    let spheres = match params.remesh {
        Sizing::Adaptive { .. } => {
            progress(Progress::new("sizing", 0, 1))?;
            let estimate = estimate_absolute_sphere(mesh, field, &AbsoluteSphereParams::default())?;
            bounds.g_min = mean_edge_length(mesh, topo).min(bounds.g_max);
            local_spheres_orthogonal(mesh, topo, &estimate.omega, LOCAL_SPHERE_POINTS)
        }
        _ => Vec::new(),
    };
    let sphere_of = |i: usize| spheres.get(i).copied().unwrap_or_else(|| Sphere::plane(mesh.positions[i], DVec3::Z));
    let Some(sizing) = params.remesh.guarded_field(mesh, topo, &sphere_of, bounds, progress)? else {
        return Ok(None);
    };
    let warnings = || method_warnings(reference, field, None);
    let remeshed = params.remesh.remesh_to(mesh, &sizing, &RemeshParams::default(), &warnings, progress)?;
    Ok(Some(Reference::from_triangles(remeshed)))
}

/// The method on `reference` (see the module documentation): optionally remeshed first, then the
/// steps on the working mesh, and the warnings of the reference and the result.
pub fn compute(
    reference: &Reference,
    params: &StSupportParams,
    fabrication: &Fabrication,
    clock: Clock,
    progress: &mut OnProgress,
) -> Result<StSupportResult, StSupportError> {
    params.check().map_err(StSupportError::Parameter)?;
    reference.validate().map_err(StSupportError::Reference)?;
    let field = reference.curvature(&params.jet, progress)?;
    let mut timings = Timings::start(clock);
    let remeshed = remeshed_reference(reference, &field, params, progress)?;
    let mut warnings = method_warnings(reference, &field, remeshed.as_ref().map(|r| r.mesh()));
    let (work, field): (&Reference, Rc<CurvatureField>) = match &remeshed {
        Some(r) => {
            timings.lap("remesh");
            let field = r.curvature(&params.jet, progress)?;
            timings.skip();
            (r, field)
        }
        None => (reference, field),
    };
    let mut steps = steps(work.mesh(), work.topology(), &field, params, &mut timings, progress)?;
    if params.optimize_moulds {
        timings.skip();
        steps = fewer_moulds(reference, work, steps, params, fabrication, clock, progress)?;
        timings.lap("fewer_moulds");
    }
    warnings.extend(kink_warning(&steps.sphere_mesh.kink_angles_deg(), work));
    Ok(StSupportResult { timings_ms: timings.laps, warnings, ..steps })
}

/// The method's part in the rounds toward fewer moulds ([`crate::panels::moulds::fewer_moulds`]):
/// [`moulds::project_to_curvatures`] moves the vertices so that every face sphere, still through
/// its vertices and orthogonal to Ω, has its mould's curvature; steps 2 and 4 to 7 then make the
/// structure again on the moved mesh, exact by construction.
struct Moulds<'a, 'p> {
    /// The reference the panels are measured against, and the one the method ran on.
    reference: &'a Reference,
    work: &'a Reference,
    params: &'a StSupportParams,
    start_metrics: StSupportMetrics,
    start_distance: f64,
    clock: Clock,
    progress: &'a mut OnProgress<'p>,
}

impl Moulds<'_, '_> {
    fn distance(&self, panels: &[Panel]) -> f64 {
        max_distance_to_reference(panels, self.reference, self.reference.diagonal())
    }
}

impl MouldHook for Moulds<'_, '_> {
    type Result = StSupportResult;
    type Round = StSupportMouldRound;
    type Error = StSupportError;

    fn schedule(&self) -> RoundSchedule {
        EXACT_ROUNDS
    }

    fn panels<'r>(&self, result: &'r StSupportResult) -> &'r [Panel] {
        &result.panels
    }

    fn pull(&mut self, from: &StSupportResult, per_panel: &[f64]) -> Result<Option<(StSupportResult, bool)>, StSupportError> {
        let curvatures = per_face(&from.panels, per_panel, from.sphere_mesh.mesh.face_count(), 1.0);
        let sm = &from.sphere_mesh;
        let triangles = sm.mesh.triangulated();
        let mut iteration = 0;
        let progress = &mut *self.progress;
        let mut on_iteration = |_: &[DVec3]| {
            iteration += 1;
            progress(Progress::new("project_to_moulds", iteration, 2 * moulds::ITERATIONS))
        };
        let Some(moved) =
            moulds::project_to_curvatures(self.work, &triangles, &sm.face_spheres, &from.omega, &curvatures, self.clock, &mut on_iteration)?
        else {
            return Ok(None);
        };
        let chosen =
            Chosen { omega: from.omega, mean_kink_estimate_deg: Some(from.mean_kink_estimate_deg), optimized_parameter: from.optimized_parameter };
        let mesh = TriMesh::new(moved, triangles.triangles);
        let mut scratch = Timings::start(self.clock);
        let moved = structure(mesh, self.work.topology(), chosen, from.absolute.clone(), self.params, from.diag, &mut scratch, self.progress)?;
        let holds = moulds::holds(&self.start_metrics, &moved.metrics, self.start_distance, self.distance(&moved.panels));
        Ok(Some((moved, holds)))
    }

    fn round(&self, moved: &StSupportResult, count: RoundCount) -> StSupportMouldRound {
        let m = &moved.metrics;
        StSupportMouldRound {
            coarsening: count.coarsening,
            moulds: count.moulds,
            max_vertex_sphere_residual: m.max_vertex_sphere_residual,
            max_orthogonality_residual: m.max_orthogonality_residual.max(m.max_center_plane_residual),
            max_node_axis_offset: m.max_node_axis_offset,
            max_distance_to_reference: self.distance(&moved.panels),
            kept: count.kept,
        }
    }

    fn distance_limit(&self) -> f64 {
        moulds::DISTANCE_GROWTH * self.start_distance
    }

    fn progress(&mut self, p: Progress) -> Result<(), Cancelled> {
        (self.progress)(p)
    }
}

/// The rounds toward fewer moulds from the method's result `start` on `work` (the reference it
/// ran on), its panels measured against `reference`.
fn fewer_moulds(
    reference: &Reference,
    work: &Reference,
    start: StSupportResult,
    params: &StSupportParams,
    fabrication: &Fabrication,
    clock: Clock,
    progress: &mut OnProgress,
) -> Result<StSupportResult, StSupportError> {
    let start_distance = max_distance_to_reference(&start.panels, reference, reference.diagonal());
    let mut hook = Moulds { reference, work, params, start_metrics: start.metrics.clone(), start_distance, clock, progress };
    let run = crate::panels::moulds::fewer_moulds(&mut hook, &start, reference.diagonal(), fabrication)?;
    let mut result = run.best.unwrap_or(start);
    result.moulds = Some(run.outcome);
    Ok(result)
}

/// Steps 1 to 7 on a triangle mesh with its topology and curvature; the warnings are the
/// caller's.
fn steps(
    mesh: &TriMesh,
    topo: &Topology,
    field: &CurvatureField,
    params: &StSupportParams,
    timings: &mut Timings,
    progress: &mut OnProgress,
) -> Result<StSupportResult, StSupportError> {
    let diag = mesh.bbox_diagonal();
    progress(Progress::new("absolute_sphere", 0, 1))?;
    let absolute = estimate_absolute_sphere(mesh, field, &params.absolute)?;
    progress(Progress::new("absolute_sphere", 1, 1))?;
    timings.lap("absolute_sphere");
    let work = working_orientation(mesh, absolute.flipped);
    let interior: Vec<[u32; 2]> = topo.interior_edges().map(|(_, f, g)| [f, g]).collect();
    let chosen = choose_omega(&work, &absolute, &interior, params.optimize_radius, progress)?;
    if params.optimize_radius {
        timings.lap("optimize_radius");
    }
    let chosen =
        Chosen { omega: chosen.omega, mean_kink_estimate_deg: chosen.mean_kink_estimate_deg, optimized_parameter: chosen.optimized_parameter };
    structure(work, topo, chosen, absolute, params, diag, timings, progress)
}

/// The Ω of step 3 with what choosing it found.
#[derive(Clone, Copy, Debug)]
struct Chosen {
    omega: AbsoluteSphere,
    mean_kink_estimate_deg: Option<f64>,
    optimized_parameter: Option<f64>,
}

/// Steps 2 and 4 to 7 on the working mesh `work` with Ω chosen, the estimate of step 1 (its
/// normals at the vertices) and the diagonal `diag` the lengths are relative to.
fn structure(
    work: TriMesh,
    topo: &Topology,
    chosen: Chosen,
    absolute: AbsoluteSphereEstimate,
    params: &StSupportParams,
    diag: f64,
    timings: &mut Timings,
    progress: &mut OnProgress,
) -> Result<StSupportResult, StSupportError> {
    let omega = chosen.omega;
    let normals = &absolute.normals;
    let (spheres, degenerate_faces) = face_spheres(&work, &omega, progress)?;
    timings.lap("face_spheres");
    let toward = |v: usize| match omega {
        AbsoluteSphere::Sphere { center, .. } => (center - work.positions[v]).try_normalize().unwrap_or(-normals[v]),
        AbsoluteSphere::Plane { axis, .. } => -axis,
    };
    let plane = |_: [DVec3; 2]| edge_plane(&omega);
    let axes = node_axes(&work.positions, topo, &spheres, &toward, &plane, progress)?;
    timings.lap("node_axes");
    let depth = params.support_depth * diag;
    let rule = boundary_arc_rule(&omega);
    let (elements, edges_without_support) = support_elements(&work, topo, &spheres, &axes.axes, edge_plane(&omega), depth, progress)?;
    timings.lap("support_elements");
    let second_envelope = second_envelope(&work, &omega);
    timings.lap("second_envelope");
    progress(Progress::new("metrics", 0, 1))?;
    let sphere_mesh = SphereMesh::new(work, spheres, rule);
    let counts = Counts { degenerate_faces, edges_without_support };
    let metrics = metrics(&sphere_mesh, &omega, &axes, normals, diag, counts);
    progress(Progress::new("metrics", 1, 1))?;
    timings.lap("metrics");
    progress(Progress::new("panels", 0, 1))?;
    let panels = build_panels(&sphere_mesh, DEFAULT_CHORD_TOLERANCE * diag);
    let support_geometry = support_strips(&elements, |el| edge_arc_points(&sphere_mesh, &panels, el.edge));
    progress(Progress::new("panels", 1, 1))?;
    timings.lap("panels");
    Ok(StSupportResult {
        mean_kink_estimate_deg: chosen.mean_kink_estimate_deg.unwrap_or(metrics.mean_kink_angle_deg),
        sphere_mesh,
        panels,
        support: SupportStructure { node_axes: axes, depth, elements, geometry: support_geometry, axis_length: params.axis_length * diag },
        absolute,
        omega,
        optimized_parameter: chosen.optimized_parameter,
        second_envelope,
        diag,
        metrics,
        timings_ms: Vec::new(),
        warnings: Vec::new(),
        moulds: None,
    })
}

/// The mesh in the working orientation of step 1: every triangle's winding reversed when m0
/// lay on the positive side, so that the normals point away from m.
fn working_orientation(mesh: &TriMesh, flipped: bool) -> TriMesh {
    let triangles = if flipped { mesh.triangles.iter().map(|t| [t[0], t[2], t[1]]).collect() } else { mesh.triangles.clone() };
    TriMesh::new(mesh.positions.clone(), triangles)
}

/// The plane through an edge beside its radical plane: through m, or parallel to a (step 5).
fn edge_plane(omega: &AbsoluteSphere) -> EdgePlane {
    match *omega {
        AbsoluteSphere::Sphere { center, .. } => EdgePlane::Through(center),
        AbsoluteSphere::Plane { axis, .. } => EdgePlane::Parallel(axis),
    }
}

/// The plane of a boundary edge's arc: through m, or parallel to a (step 5).
fn boundary_arc_rule(omega: &AbsoluteSphere) -> BoundaryArcRule {
    match *omega {
        AbsoluteSphere::Sphere { center, .. } => BoundaryArcRule::Through(center),
        AbsoluteSphere::Plane { axis, .. } => BoundaryArcRule::Parallel(axis),
    }
}
