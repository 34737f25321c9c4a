//! The staged optimization (Sec. 3 end) in its normalized frame.

use glam::DVec3;

use super::params::StAdaptedParams;
use super::params::StAdaptedWeights;
use super::terms::{boundary_vertices, build_problem, pack, unpack, vertex_offset, StAdaptedTerms};
use crate::geometry::mesh::topology::Topology;
use crate::geometry::mesh::TriMesh;
use crate::geometry::sphere::Sphere;
use crate::progress::Cancelled;
use crate::reference::Reference;
use crate::solver::{IterationReport, PhaseTimes, Problem, SolveReport, Solver, Termination};

/// What [`run_stages`] did.
#[derive(Clone, Debug, Default)]
pub struct StageRun {
    /// Solver iterations over all stages.
    pub iterations: usize,
    /// Per-iteration times (ms) when the solver has a clock.
    pub iteration_ms: Vec<f64>,
    /// Phase times summed over the stages (when the solver has a clock).
    pub phase_ms: PhaseTimes,
    /// Numeric factorizations over all stages.
    pub numeric_factorizations: usize,
    /// The last stage's report.
    pub last: Option<SolveReport>,
}

/// What the stages call after every solver iteration, with the stage's name.
pub type StageHook<'h> = dyn FnMut(&str, &IterationReport) -> Result<(), Cancelled> + 'h;

/// Runs the optimization stages of `params` on a problem from [`build_problem`] (weights set per
/// stage, ε carried from stage to stage), starting at `x` (updated). `hook(stage, report)` is
/// called after every iteration; `Err(Cancelled)` stops the run and is returned.
pub fn run_stages(
    problem: &mut Problem,
    ids: &StAdaptedTerms,
    x: &mut [f64],
    params: &StAdaptedParams,
    solver: &mut Solver,
    hook: &mut StageHook,
) -> Result<StageRun, Cancelled> {
    let mut run = StageRun::default();
    let mut epsilon = params.initial_epsilon;
    let w = &params.weights;
    for stage in &params.stages {
        if stage.iterations == 0 {
            continue;
        }
        problem.set_weight(ids.tangent_distance, w.tangent_distance * stage.proximity_scale);
        problem.set_weight(ids.point_distance, w.point_distance * stage.proximity_scale);
        problem.set_weight(ids.face_distance, w.face_distance * stage.proximity_scale);
        solver.options.max_iterations = stage.iterations;
        solver.options.initial_epsilon = epsilon;
        let name = stage.name.as_str();
        let report = solver.solve(problem, x, |rep| hook(name, rep));
        run.iterations += report.iterations;
        run.iteration_ms.extend_from_slice(&report.iteration_ms);
        run.numeric_factorizations += report.numeric_factorizations;
        run.phase_ms.add(&report.phase_ms);
        epsilon = report.epsilon.max(1e-6);
        if report.termination == Termination::Cancelled {
            return Err(Cancelled);
        }
        run.last = Some(report);
    }
    Ok(run)
}

/// The optimization in its normalized frame: the reference and the remeshed mesh moved by the
/// reference's bbox centre `t` and scaled to diagonal 1, the initial point and the vertices
/// `params` hard-fixes (boundary, feature curves).
pub struct OptimizationFrame {
    pub t: DVec3,
    pub diag: f64,
    pub reference: Reference,
    pub mesh: TriMesh,
    pub topology: Topology,
    /// The initial point ([`pack`]).
    pub x0: Vec<f64>,
    /// Hard-fixed vertices.
    pub fixed: Vec<usize>,
    /// The tolerance band's half-width: [`StAdaptedParams::tolerance_band`], at least the reference's
    /// [`Reference::facet_sagitta`] (a coarse reference's facets are that far from any smooth
    /// panel); the frame's diagonal is 1.
    pub tolerance: Option<f64>,
}

impl OptimizationFrame {
    /// `init`: one face sphere per face of `remeshed`, model coordinates.
    pub fn new(reference: &Reference, remeshed: &TriMesh, init: &[Sphere], params: &StAdaptedParams) -> Self {
        let diag = reference.diagonal();
        let (lo, hi) = reference.mesh().bbox();
        let t = 0.5 * (lo + hi);
        let nref = reference.in_frame(t, diag);
        let inv = 1.0 / diag;
        let mesh = TriMesh::new(remeshed.positions.iter().map(|&p| (p - t) * inv).collect(), remeshed.triangles.clone());
        let topology = Topology::new(&mesh);
        let boundary = boundary_vertices(&topology);
        let spheres: Vec<Sphere> = init.iter().map(|s| s.in_frame(t, diag).normalized()).collect();
        let x0 = pack(&mesh, &spheres);
        let nv = mesh.vertex_count();
        let mut fixed = vec![false; nv];
        if params.fix_boundary {
            for v in 0..nv {
                fixed[v] |= boundary[v];
            }
        }
        if params.fix_features {
            let cos_max = params.remesh.feature_angle_deg.to_radians().cos();
            for (e, f, g) in topology.interior_edges() {
                let [a, b] = topology.edges()[e];
                let (f, g) = (f as usize, g as usize);
                let (nf, ng) = (mesh.face_area_vector(f).normalize_or_zero(), mesh.face_area_vector(g).normalize_or_zero());
                if nf.dot(ng) < cos_max {
                    fixed[a as usize] = true;
                    fixed[b as usize] = true;
                }
            }
        }
        let fixed = (0..nv).filter(|&v| fixed[v]).collect();
        Self { t, diag, reference: nref, mesh, topology, x0, fixed, tolerance: params.tolerance_band().map(|t| t.max(reference.facet_sagitta())) }
    }

    /// [`build_problem`] at the initial point, with the fixed vertices fixed.
    pub fn problem(&self, weights: &StAdaptedWeights) -> (Problem<'_>, StAdaptedTerms) {
        let (mut problem, ids) = build_problem(&self.mesh, &self.topology, &self.reference, weights, self.tolerance, &self.x0);
        let nf = self.mesh.face_count();
        for &v in &self.fixed {
            let o = vertex_offset(nf, v);
            problem.fix_range(o..o + 3);
        }
        (problem, ids)
    }

    /// Vertices and face spheres of `x`, in model coordinates.
    pub(crate) fn to_model(&self, x: &[f64]) -> (Vec<DVec3>, Vec<Sphere>) {
        let (verts, sph) = unpack(x, &self.mesh.triangles, self.mesh.vertex_count());
        let verts = verts.iter().map(|&p| self.t + p * self.diag).collect();
        let sph = sph.iter().map(|s| s.from_frame(self.t, self.diag).normalized()).collect();
        (verts, sph)
    }
}
