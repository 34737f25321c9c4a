//! Fewer moulds (Sec. 4 with the fabrication's moulds, [`crate::panels::moulds`]): a face
//! sphere passes through its triangle's three vertices and is orthogonal to Ω, so a new radius
//! moves the vertices. [`project_to_curvatures`] solves, from the exact mesh, for vertices and
//! spheres with every vertex on its faces' spheres, every sphere orthogonal to Ω and of its
//! mould's curvature: per face five equations (three incidences, orthogonality, curvature) on
//! four unknowns of its sphere, one more on the vertices, of which there are about 3F/2: an
//! underdetermined system that Gauss–Newton solves near the start, the vertices held near the
//! reference first (point and tangent distance), then the equations alone. The spheres are then made again from the moved vertices and Ω (step 2), so
//! the result is exact by construction and its node axes pass through m (Sec. 4). A round
//! counts when it stays exact ([`EXACT`], or no worse than the method's own) and its panels within [`DISTANCE_GROWTH`] × the
//! method's distance to the reference.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::guarantees::EXACT;
use super::metrics::StSupportMetrics;
use crate::geometry::absolute_sphere::AbsoluteSphere;
use crate::geometry::mesh::TriMesh;
use crate::geometry::sphere::Sphere;
use crate::panels::moulds::{MouldOutcome, MouldRoundFigures};
use crate::progress::{Cancelled, Clock};
use crate::reference::proximity::ReferenceProximity;
use crate::reference::Reference;
use crate::solver::{Anchor, InversiveProductFixed, PointOnSphere, Problem, Proximal, Solver, SolverOptions, Termination, UnitLength};

/// The panels' largest distance to the reference may grow by this factor.
pub const DISTANCE_GROWTH: f64 = 1.2;
/// Weight of the damping against the equations in the first pass.
const DAMPING_WEIGHT: f64 = 1e-3;
/// Gauss–Newton iterations per pass.
pub const ITERATIONS: usize = 30;

/// One round toward fewer moulds: the figures of the mesh it made.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct StSupportMouldRound {
    pub coarsening: f64,
    /// Moulds at δ of the moved panels.
    pub moulds: usize,
    pub max_vertex_sphere_residual: f64,
    pub max_orthogonality_residual: f64,
    pub max_node_axis_offset: f64,
    /// The panels' largest distance to the reference, relative to the diagonal.
    pub max_distance_to_reference: f64,
    pub kept: bool,
}

/// What the rounds did.
pub type StSupportMouldOutcome = MouldOutcome<StSupportMouldRound>;

impl MouldRoundFigures for StSupportMouldRound {
    fn moulds(&self) -> usize {
        self.moulds
    }
    fn distance_to_reference(&self) -> f64 {
        self.max_distance_to_reference
    }
    fn kept(&self) -> bool {
        self.kept
    }
}

/// Whether `moved` keeps the method's exactness against `start`'s, its panels at
/// `distance` (relative) against the method's `start_distance`.
pub fn holds(start: &StSupportMetrics, moved: &StSupportMetrics, start_distance: f64, distance: f64) -> bool {
    let exact = |before: f64, after: f64| after <= EXACT.max(before);
    exact(start.max_vertex_sphere_residual, moved.max_vertex_sphere_residual)
        && exact(start.max_orthogonality_residual, moved.max_orthogonality_residual)
        && exact(start.max_center_plane_residual, moved.max_center_plane_residual)
        && exact(start.max_node_axis_offset, moved.max_node_axis_offset)
        && moved.degenerate_faces <= start.degenerate_faces
        && distance <= DISTANCE_GROWTH * start_distance
}

/// The vertices of `mesh` moved so that every face sphere orthogonal to `omega` through them has
/// the signed curvature `curvatures[f]` (model units, along the face's normal; NaN: free), from
/// the exact `spheres`; `reference` is the surface they stay near. Solved in the frame of the
/// reference's bounding box. None when a vertex is not finite. What it reached is measured on
/// the spheres made again from the vertices, not here.
pub fn project_to_curvatures(
    reference: &Reference,
    mesh: &TriMesh,
    spheres: &[Sphere],
    omega: &AbsoluteSphere,
    curvatures: &[f64],
    clock: Clock,
    on_iteration: &mut dyn FnMut(&[DVec3]) -> Result<(), Cancelled>,
) -> Result<Option<Vec<DVec3>>, Cancelled> {
    let (lo, hi) = reference.mesh().bbox();
    let (t, s) = (0.5 * (lo + hi), reference.diagonal());
    let framed = reference.in_frame(t, s);
    let (nf, nv) = (mesh.face_count(), mesh.positions.len());
    let sphere = |f: usize| 5 * f;
    let vertex = |v: usize| 5 * nf + 3 * v;
    let mut x = vec![0.0; 5 * nf + 3 * nv];
    for (f, sp) in spheres.iter().enumerate() {
        x[sphere(f)..sphere(f) + 5].copy_from_slice(&sp.in_frame(t, s).normalized().to_array());
    }
    for (v, p) in mesh.positions.iter().enumerate() {
        x[vertex(v)..vertex(v) + 3].copy_from_slice(&((*p - t) / s).to_array());
    }
    // Ω in the frame, scaled to a unit coefficient vector (the product's target is 0).
    let o = omega.coefficients().in_frame(t, s).to_array();
    let norm = o.iter().map(|c| c * c).sum::<f64>().sqrt().max(f64::MIN_POSITIVE);
    let o = o.map(|c| c / norm);
    let orthogonal: Vec<usize> = (0..nf)
        .filter(|&f| {
            let sp = &x[sphere(f)..sphere(f) + 5];
            let product = o[1] * sp[1] + o[2] * sp[2] + o[3] * sp[3] - 2.0 * (sp[0] * o[4] + o[0] * sp[4]);
            product.abs() <= 1e-6
        })
        .map(sphere)
        .collect();
    let mut problem = Problem::new(x.len());
    let pairs: Vec<(usize, usize)> =
        mesh.triangles.iter().enumerate().flat_map(|(f, tri)| tri.iter().map(move |&v| (vertex(v as usize), sphere(f)))).collect();
    problem.add_term(PointOnSphere::new(pairs).with_name("sphere"), 1.0);
    problem.add_term(UnitLength::spheres((0..nf).map(sphere).collect()).with_name("sphere_unit"), 1.0);
    problem.add_term(InversiveProductFixed::new(orthogonal, o, 0.0), 1.0);
    // A normalized sphere's curvature along its normal is 2a: hold a at |κ|/2 (frame: |κ| s)
    // with the sign of the start's a, so that no panel is asked to turn over.
    let (held, halves): (Vec<usize>, Vec<f64>) =
        curvatures.iter().enumerate().filter(|(_, k)| k.is_finite()).map(|(f, &k)| (sphere(f), (0.5 * k.abs() * s).copysign(x[sphere(f)]))).unzip();
    problem.add_term(Anchor::new(held, halves).with_name("mould_curvature"), 1.0);
    let vertices: Vec<usize> = (0..nv).map(vertex).collect();
    let glide = problem.add_term(ReferenceProximity::tangent(&framed, vertices.clone()).with_name("vertex_proximity"), 1.0);
    let near = problem.add_term(ReferenceProximity::point(&framed, vertices.clone(), vec![1.0; nv]).with_name("vertex_point_proximity"), 1.0);
    let damping = problem.add_term(Proximal::new(vertices).with_name("regularization_vertices"), DAMPING_WEIGHT);
    for f in 0..nf {
        problem.group_variables(sphere(f)..sphere(f) + 5);
    }
    for v in 0..nv {
        problem.group_variables(vertex(v)..vertex(v) + 3);
    }
    let mut solver = Solver::new(SolverOptions {
        clock,
        max_iterations: ITERATIONS,
        min_epsilon: 1e-7,
        energy_tolerance: 1e-27,
        relative_decrease_tolerance: 0.0,
        step_tolerance: 1e-16,
        ..SolverOptions::default()
    });
    let mut hook = |x: &[f64]| on_iteration(&(0..nv).map(|v| t + s * DVec3::from_slice(&x[vertex(v)..vertex(v) + 3])).collect::<Vec<_>>());
    // The vertices near the reference while the spheres reach their curvatures, then the
    // equations alone.
    for pass in 0..2 {
        if pass == 1 {
            problem.set_weight(glide, 0.0);
            problem.set_weight(near, 0.0);
            problem.set_weight(damping, 0.0);
        }
        let report = solver.solve(&mut problem, &mut x, |it| hook(it.x));
        if report.termination == Termination::Cancelled {
            return Err(Cancelled);
        }
    }
    let moved: Vec<DVec3> = (0..nv).map(|v| t + s * DVec3::from_slice(&x[vertex(v)..vertex(v) + 3])).collect();
    Ok(moved.iter().all(|p| p.is_finite()).then_some(moved))
}
