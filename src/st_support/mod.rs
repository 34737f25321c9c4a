//! ST meshes with support structure (Sec. 4).
//!
//! Input: the reference's triangulation (or, with `remesh`, a remesh of it: uniform, or adaptive
//! with the sizing field of the local spheres orthogonal to the Ω estimated on the reference, Fig. 16
//! bottom) and its curvature field.
//! 1. Ω is estimated ([`absolute_sphere`], Eq. 7). When m0 lay on the positive side the working
//!    orientation is flipped: the output mesh has every triangle's winding reversed, so that its
//!    normals point away from m (the support structure is on the negative side).
//! 2. Each face sphere passes through its triangle's three vertices and is orthogonal to Ω
//!    ([`Sphere::through_points_orthogonal`]: the null vector of the 4 × 5 system, a plane where
//!    it must), oriented like the (working) face normal.
//! 3. Option `optimize_radius` (Fig. 16 right, [`optimize_radius`]): R² (or the plane offset d)
//!    minimizing the mean kink angle, the vertices and m (or a) fixed.
//! 4. Node axes: the line through v and the second common point v̄ of the spheres around v, from
//!    those spheres ([`crate::congruence::support_structure::star_axis`]), not assumed. Where a star does not determine it (fewer than 3
//!    faces, or nearly coaxal spheres: condition below `STAR_AXIS_MIN_CONDITION`) the axis is the
//!    line v m (or parallel to a) and does not count in `max_node_axis_offset`.
//! 5. Support elements: per edge the arc circle (interior edges: the intersection circle of the
//!    two face spheres; boundary edges: the [`BoundaryArcRule`] plane through the edge and m, or
//!    parallel to a), and the annulus sector between the node axes with the given depth
//!    ([`crate::congruence::support_structure::SupportElement`]), tessellated along the panels'
//!    own arcs for display and export.
//! 6. The second envelope: the mesh inverted in Ω (same triangles). Given for R² > 0 (Fig. 10),
//!    also for R² < 0 (anti-inversion: the spheres pass through the anti-inverted vertices too)
//!    and for a plane Ω (reflection); None for R² = 0 (it degenerates to m).
//!
//! 7. The panels ([`crate::panels::build_panels`]), their support strips and the node axes as
//!    segments: what is exported and shown.

// Negated float comparisons are deliberate: they also reject NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod absolute_sphere;
pub mod edge_circles;
pub mod optimize_radius;

use std::fmt;
use std::rc::Rc;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::congruence::central_spheres::{CurvatureField, JetParams};
use crate::congruence::support_structure::{
    star_axis, support_element, support_strips, SupportElement, SupportGeometry, SupportStructure,
    STAR_AXIS_MIN_CONDITION,
};
use crate::geometry::absolute_sphere::AbsoluteSphere;
use crate::geometry::mesh::topology::Topology;
use crate::geometry::mesh::TriMesh;
use crate::geometry::sphere::Sphere;
use crate::panels::panel::Panel;
use crate::panels::sphere_mesh::{BoundaryArcRule, SphereMesh};
use crate::panels::{build_panels, edge_arc_points, DEFAULT_CHORD_TOLERANCE};
use crate::progress::{Cancelled, Clock, OnProgress, Progress, Timings};
use crate::reference::assumptions::{is_sliver, kink_warning, method_warnings, Warning};
use crate::reference::{Reference, ReferenceError};
use crate::remeshing::{
    local_spheres_orthogonal, mean_edge_length, pliant_remesh, RemeshError, RemeshParams,
    RemeshRefused, Sizing, SizingBounds, TooManyFaces, MAX_METHOD_FACES,
};
use crate::stats::mean;
use absolute_sphere::{
    estimate_absolute_sphere, AbsoluteSphereError, AbsoluteSphereEstimate, AbsoluteSphereParams,
};
use edge_circles::edge_circle;
use optimize_radius::{optimize_parameter, parameter_of, with_parameter};

/// Neighbours of a local sphere orthogonal to Ω (remeshing with `Sizing::Adaptive`).
pub const LOCAL_SPHERE_POINTS: usize = 16;

/// Parameters of the method ([`compute`]); lengths relative to the bbox diagonal. The defaults
/// are written here only.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct StSupportParams {
    /// Choose R² (or d) minimizing the mean kink angle instead of the mean of the R_i².
    pub optimize_radius: bool,
    /// Depth of the support elements. Default 0.02.
    pub support_depth: f64,
    /// Length of the displayed node-axis segments. Default 0.1.
    pub axis_length: f64,
    /// Radii closer than this count as one in the panel schedule. Default 1e-3.
    pub radius_tolerance: f64,
    /// Remesh first: adaptively with the sizing field of the local spheres orthogonal to Ω
    /// (Fig. 16, bottom; ε × diag), uniformly to about N faces, or not at all (the default).
    pub remesh: Sizing,
    pub jet: JetParams,
    pub absolute: AbsoluteSphereParams,
}

impl Default for StSupportParams {
    fn default() -> Self {
        Self {
            optimize_radius: false,
            support_depth: 0.02,
            axis_length: 0.1,
            radius_tolerance: 1e-3,
            remesh: Sizing::None,
            jet: JetParams::default(),
            absolute: AbsoluteSphereParams::default(),
        }
    }
}

/// The metrics of the method (lengths relative to the bbox diagonal, angles in degrees), without
/// `max_distance_to_reference` (measured on the tessellated panels against the original
/// reference when the schedule is built), plus counts that qualify them.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StSupportMetrics {
    /// max over faces and their corners of | |v − c| − |r| | (exact distance, also for planes).
    pub max_vertex_sphere_residual: f64,
    /// max over faces of | |c − m|² − r² − R² | / diag² (a plane face: the distance of m from it
    /// / diag); 0 when Ω is a plane (see `max_center_plane_residual`).
    pub max_orthogonality_residual: f64,
    /// Ω a plane: max over faces of |⟨c, a⟩ − d| / diag (centres in Ω); 0 otherwise.
    pub max_center_plane_residual: f64,
    /// max over the axes computed from their star's spheres of the distance from m to the axis /
    /// diag. Ω a plane: the sine of the angle between the axis and a.
    pub max_node_axis_offset: f64,
    /// Angle between the node axis (as a line) and the reference normal, over all vertices.
    pub mean_axis_normal_angle_deg: f64,
    pub max_axis_normal_angle_deg: f64,
    /// Kink angles over the interior edges (exactly two faces).
    pub mean_kink_angle_deg: f64,
    pub max_kink_angle_deg: f64,
    pub interior_edges: usize,
    /// Vertices whose axis comes from their star's spheres; the others use the line through m.
    pub axes_from_spheres: usize,
    /// Sliver faces (their sphere is unreliable) and faces whose sphere could not be made
    /// orthogonal to Ω (they keep their triangle's plane).
    pub degenerate_faces: usize,
    /// Edges without a support element (both face spheres planes, or no circle).
    pub edges_without_support: usize,
}

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
        }
    }
}

impl std::error::Error for StSupportError {}

impl From<Cancelled> for StSupportError {
    fn from(_: Cancelled) -> Self {
        StSupportError::Cancelled
    }
}

impl From<RemeshError> for StSupportError {
    fn from(e: RemeshError) -> Self {
        match e {
            RemeshError::Cancelled => StSupportError::Cancelled,
            RemeshError::NoFaces => StSupportError::NoFaces,
            error @ RemeshError::TargetMissed { .. } => StSupportError::Remesh(RemeshRefused {
                error,
                warnings: Vec::new(),
            }),
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
    /// Node axes (vertex, unit direction toward the support side) and the absolute depth.
    pub support: SupportStructure,
    pub support_elements: Vec<SupportElement>,
    /// The support elements as strips along the panels' arcs.
    pub support_geometry: SupportGeometry,
    /// The estimate of Sec. 4 with the histogram data (its `omega` is the mean-R² estimate).
    pub absolute: AbsoluteSphereEstimate,
    /// The Ω the face spheres are orthogonal to: the estimate, or the optimized R² / d.
    pub omega: AbsoluteSphere,
    /// The optimized R² (or d for a plane) when `optimize_radius`.
    pub optimized_parameter: Option<f64>,
    /// Mean kink angle (deg) with the mean-R² estimate (equals the metric unless optimized).
    pub mean_kink_estimate_deg: f64,
    pub second_envelope: Option<TriMesh>,
    /// Per vertex: v̄ computed from the star's spheres (None where not determined).
    pub second_points: Vec<Option<DVec3>>,
    /// Per vertex: whether its node axis comes from its star's spheres.
    pub axis_from_spheres: Vec<bool>,
    /// Length of the displayed axis segments (absolute).
    pub axis_length: f64,
    /// The bounding-box diagonal of the mesh the method ran on (the remeshed one, if any).
    pub diag: f64,
    pub metrics: StSupportMetrics,
    /// (step, milliseconds) in execution order.
    pub timings_ms: Vec<(String, f64)>,
    /// The method's assumptions the reference fails (H of one sign, no folds, no slivers).
    pub warnings: Vec<Warning>,
}

impl StSupportResult {
    /// The node axes as display segments (v, v + axis_length · direction), toward the support
    /// side.
    pub fn node_axis_segments(&self) -> Vec<(DVec3, DVec3)> {
        self.support.axis_segments(self.axis_length)
    }
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
    let sizing = match params.remesh {
        Sizing::None => {
            params
                .remesh
                .check_size(mesh, None, MAX_METHOD_FACES)
                .map_err(StSupportError::TooManyFaces)?;
            return Ok(None);
        }
        Sizing::UniformFaces(_) => params.remesh.field(
            mesh,
            topo,
            &|i| Sphere::plane(mesh.positions[i], DVec3::Z),
            SizingBounds::for_mesh(mesh, topo),
            progress,
        )?,
        Sizing::Adaptive { .. } => {
            progress(Progress::new("sizing", 0, 1))?;
            let estimate = estimate_absolute_sphere(mesh, field, &AbsoluteSphereParams::default())?;
            let spheres =
                local_spheres_orthogonal(mesh, topo, &estimate.omega, LOCAL_SPHERE_POINTS);
            let mut bounds = SizingBounds::for_mesh(mesh, topo);
            bounds.g_min = mean_edge_length(mesh, topo).min(bounds.g_max);
            params
                .remesh
                .field(mesh, topo, &|i| spheres[i], bounds, progress)?
        }
    };
    let Some(sizing) = sizing else {
        return Ok(None);
    };
    params
        .remesh
        .check_size(mesh, Some(&sizing), MAX_METHOD_FACES)
        .map_err(StSupportError::TooManyFaces)?;
    let remeshed = pliant_remesh(mesh, &sizing, &RemeshParams::default(), progress)?;
    params
        .remesh
        .check_reached(remeshed.face_count())
        .map_err(|error| {
            StSupportError::Remesh(RemeshRefused {
                error,
                warnings: method_warnings(reference, field, None),
            })
        })?;
    Ok(Some(Reference::from_triangles(remeshed)))
}

/// The method on `reference` (see the module documentation): optionally remeshed first, then Ω,
/// face spheres, node axes, support elements, panels and their support strips.
pub fn compute(
    reference: &Reference,
    params: &StSupportParams,
    clock: Clock,
    progress: &mut OnProgress,
) -> Result<StSupportResult, StSupportError> {
    reference.validate().map_err(StSupportError::Reference)?;
    let field = reference.curvature(&params.jet, progress)?;
    let mut timings = Timings::start(clock);
    let remeshed = remeshed_reference(reference, &field, params, progress)?;
    let warnings = method_warnings(reference, &field, remeshed.as_ref().map(|r| r.mesh()));
    let (work, field): (&Reference, Rc<CurvatureField>) = match &remeshed {
        Some(r) => {
            timings.lap("remesh");
            (r, r.curvature(&params.jet, progress)?)
        }
        None => (reference, field),
    };
    let mut result = on_mesh(
        work.mesh(),
        work.topology(),
        &field,
        params,
        clock,
        progress,
    )?;
    result.warnings = warnings;
    result
        .warnings
        .extend(kink_warning(&result.sphere_mesh.kink_angles_deg(), work));
    if remeshed.is_some() {
        result.timings_ms.insert(0, timings.laps.remove(0));
    }

    let mut timings = Timings::start(clock);
    progress(Progress::new("panels", 0, 1))?;
    let diag = result.diag;
    result.panels = build_panels(&result.sphere_mesh, DEFAULT_CHORD_TOLERANCE * diag);
    let (sm, panels) = (&result.sphere_mesh, &result.panels);
    result.support_geometry = support_strips(&result.support_elements, |el| {
        edge_arc_points(sm, panels, el.edge)
    });
    progress(Progress::new("panels", 1, 1))?;
    timings.lap("panels");
    result.timings_ms.extend(timings.laps);
    Ok(result)
}

/// Ω, face spheres, node axes and support elements on a triangle mesh with its topology and
/// curvature (panels are left empty).
fn on_mesh(
    mesh: &TriMesh,
    topo: &Topology,
    field: &CurvatureField,
    params: &StSupportParams,
    clock: Clock,
    progress: &mut OnProgress,
) -> Result<StSupportResult, StSupportError> {
    let nv = mesh.vertex_count();
    let nf = mesh.face_count();
    let diag = mesh.bbox_diagonal();
    let mut timer = Timings::start(clock);

    // --- Ω ---
    progress(Progress::new("absolute_sphere", 0, 1))?;
    let absolute = estimate_absolute_sphere(mesh, field, &params.absolute)?;
    progress(Progress::new("absolute_sphere", 1, 1))?;
    timer.lap("absolute_sphere");
    let triangles: Vec<[u32; 3]> = if absolute.flipped {
        mesh.triangles.iter().map(|t| [t[0], t[2], t[1]]).collect()
    } else {
        mesh.triangles.clone()
    };
    let work = TriMesh::new(mesh.positions.clone(), triangles);
    let normals = &absolute.normals;
    let interior: Vec<[u32; 2]> = topo.interior_edges().map(|(_, f, g)| [f, g]).collect();

    // --- Optimize R² (or d) ---
    let mut omega = absolute.omega;
    let mut optimized_parameter = None;
    let families: Option<Vec<[Sphere; 2]>> = params.optimize_radius.then(|| {
        (0..nf)
            .map(|f| Sphere::through_points_family(work.face_points(f)))
            .collect()
    });
    let mean_kink_estimate_deg;
    if let Some(families) = &families {
        progress(Progress::new("optimize_radius", 0, 1))?;
        let (best, value, initial) =
            optimize_parameter(&work, &absolute, families, &interior, progress)?;
        mean_kink_estimate_deg = initial;
        if value < initial {
            omega = with_parameter(&absolute.omega, best);
            optimized_parameter = Some(best);
        } else {
            optimized_parameter = Some(parameter_of(&absolute.omega));
        }
        progress(Progress::new("optimize_radius", 1, 1))?;
        timer.lap("optimize_radius");
    } else {
        mean_kink_estimate_deg = f64::NAN;
    }

    // --- Face spheres ---
    let omega_coefficients = omega.coefficients();
    let mut face_spheres = Vec::with_capacity(nf);
    let mut degenerate_faces = 0;
    for f in 0..nf {
        if f % 1024 == 0 {
            progress(Progress::new("face_spheres", f, nf))?;
        }
        let p = work.face_points(f);
        if is_sliver(p) {
            degenerate_faces += 1;
        }
        let s = match Sphere::through_points_orthogonal(p, &omega_coefficients) {
            Some(s) if s.is_finite() => s,
            _ => {
                degenerate_faces += !is_sliver(p) as usize;
                Sphere::through_points_family(p)[0]
            }
        };
        face_spheres.push(s);
    }
    progress(Progress::new("face_spheres", nf, nf))?;
    timer.lap("face_spheres");
    let kinks: Vec<f64> = interior
        .iter()
        .map(|[f, g]| {
            face_spheres[*f as usize]
                .kink_angle(&face_spheres[*g as usize])
                .to_degrees()
        })
        .collect();
    let mean_kink_estimate_deg = if mean_kink_estimate_deg.is_nan() {
        mean(&kinks)
    } else {
        mean_kink_estimate_deg
    };
    // --- Node axes ---
    let m = omega.center();
    let support_dir = |v: DVec3, n: DVec3| -> DVec3 {
        match omega {
            AbsoluteSphere::Sphere { center, .. } => (center - v).try_normalize().unwrap_or(-n),
            AbsoluteSphere::Plane { axis, .. } => -axis,
        }
    };
    let mut node_axes = Vec::with_capacity(nv);
    let mut second_points = vec![None; nv];
    let mut axis_from_spheres = vec![false; nv];
    let mut star = Vec::new();
    for v in 0..nv {
        if v % 1024 == 0 {
            progress(Progress::new("node_axes", v, nv))?;
        }
        let p = work.positions[v];
        let toward = support_dir(p, normals[v]);
        star.clear();
        star.extend(
            topo.vertex_faces(v)
                .iter()
                .map(|&f| face_spheres[f as usize]),
        );
        let mut dir = toward;
        if let Some(axis) = star_axis(&star, p).filter(|a| a.condition >= STAR_AXIS_MIN_CONDITION) {
            dir = if axis.direction.dot(toward) < 0.0 {
                -axis.direction
            } else {
                axis.direction
            };
            second_points[v] = axis.second_point;
            axis_from_spheres[v] = true;
        }
        node_axes.push((p, dir));
    }
    progress(Progress::new("node_axes", nv, nv))?;
    timer.lap("node_axes");

    // --- Support elements ---
    let depth = params.support_depth * diag;
    let rule = match omega {
        AbsoluteSphere::Sphere { center, .. } => BoundaryArcRule::Through(center),
        AbsoluteSphere::Plane { axis, .. } => BoundaryArcRule::Parallel(axis),
    };
    let mut support_elements = Vec::with_capacity(topo.edges().len());
    let mut edges_without_support = 0;
    for (e, edge) in topo.edges().iter().enumerate() {
        if e % 1024 == 0 {
            progress(Progress::new("support_elements", e, topo.edges().len()))?;
        }
        let faces: Vec<u32> = topo.edge_faces(e).iter().map(|&(f, _)| f).collect();
        let (u, w) = (
            work.positions[edge[0] as usize],
            work.positions[edge[1] as usize],
        );
        let circle = faces.first().and_then(|&f1| {
            let s2 = (faces.len() == 2).then(|| &face_spheres[faces[1] as usize]);
            edge_circle(&face_spheres[f1 as usize], s2, u, w, &rule)
        });
        let element = circle.and_then(|c| {
            support_element(
                *edge,
                c,
                [u, w],
                [node_axes[edge[0] as usize].1, node_axes[edge[1] as usize].1],
                depth,
            )
        });
        match element {
            Some(el) => support_elements.push(el),
            None => edges_without_support += 1,
        }
    }
    progress(Progress::new(
        "support_elements",
        topo.edges().len(),
        topo.edges().len(),
    ))?;
    timer.lap("support_elements");

    // --- Second envelope ---
    let second_envelope = match omega {
        AbsoluteSphere::Sphere { r2: 0.0, .. } => None,
        _ => work
            .positions
            .iter()
            .map(|p| omega.invert(*p))
            .collect::<Option<Vec<_>>>()
            .map(|pos| TriMesh::new(pos, work.triangles.clone())),
    };
    timer.lap("second_envelope");

    // --- Metrics ---
    progress(Progress::new("metrics", 0, 1))?;
    let mut metrics = StSupportMetrics {
        degenerate_faces,
        edges_without_support,
        interior_edges: interior.len(),
        ..Default::default()
    };
    for (f, s) in face_spheres.iter().enumerate() {
        for p in work.face_points(f) {
            metrics.max_vertex_sphere_residual =
                metrics.max_vertex_sphere_residual.max(s.distance(p) / diag);
        }
        let defect = omega.orthogonality_defect(s);
        match omega {
            AbsoluteSphere::Sphere { .. } => {
                let rel = if s.a.abs() > 1e-300 {
                    defect / (diag * diag)
                } else {
                    defect / diag
                };
                metrics.max_orthogonality_residual = metrics.max_orthogonality_residual.max(rel);
            }
            AbsoluteSphere::Plane { .. } => {
                metrics.max_center_plane_residual =
                    metrics.max_center_plane_residual.max(defect / diag);
            }
        }
    }
    let mut angle_sum = 0.0;
    for v in 0..nv {
        let (p, d) = node_axes[v];
        let a = d
            .cross(normals[v])
            .length()
            .atan2(d.dot(normals[v]).abs())
            .to_degrees();
        angle_sum += a;
        metrics.max_axis_normal_angle_deg = metrics.max_axis_normal_angle_deg.max(a);
        if axis_from_spheres[v] {
            metrics.axes_from_spheres += 1;
            let offset = match (m, omega) {
                (Some(m), _) => (m - p).cross(d).length() / diag,
                (None, AbsoluteSphere::Plane { axis, .. }) => d.cross(axis).length(),
                _ => 0.0,
            };
            metrics.max_node_axis_offset = metrics.max_node_axis_offset.max(offset);
        }
    }
    metrics.mean_axis_normal_angle_deg = angle_sum / nv as f64;
    metrics.mean_kink_angle_deg = mean(&kinks);
    metrics.max_kink_angle_deg = kinks.iter().copied().fold(0.0, f64::max);
    progress(Progress::new("metrics", 1, 1))?;
    timer.lap("metrics");

    let sphere_mesh = SphereMesh::new(work, face_spheres, rule);
    Ok(StSupportResult {
        sphere_mesh,
        panels: Vec::new(),
        support: SupportStructure { node_axes, depth },
        support_elements,
        support_geometry: SupportGeometry::default(),
        absolute,
        omega,
        optimized_parameter,
        mean_kink_estimate_deg,
        second_envelope,
        second_points,
        axis_from_spheres,
        axis_length: params.axis_length * diag,
        diag,
        metrics,
        timings_ms: timer.laps,
        warnings: Vec::new(),
    })
}
