//! The final sphere-congruence optimization (Sec. 5.2, Eq. 10, Fig. 24) on the quad mesh Q′, and
//! the projection to an exact SQ mesh with support structure.
//!
//! **Variables** (in the frame of the bounding box, like Sec. 5.1): per face its sphere (A, B, C);
//! the vertices of Q′; per inner vertex n_cq, the normal of the face of the mesh of centres (the
//! node axis); per edge n_uw, the normal of its discrete torsal plane.
//!
//! **Initialization** (Fig. 24 left): c_ij = q_ij + r(u_i, v_j) n_ij; each face's sphere has the
//! mean of its corners' centres and radii. n_cq starts as the congruence's line at the vertex,
//! n_uw as the unit (u − w) × (l_u + l_w).
//!
//! **Energy** (Eq. 10, Table 3's weights): E_sphere ([`PointOnSphere`]), E_unit
//! ([`UnitLength::spheres`]), E_supp ([`CentrePlanarity`]), E_torsal plane ([`TorsalPlane`]),
//! E_prox for the vertices (the glide terms of [`crate::reference::proximity`]: tangent distance
//! plus ε times point distance) and for the centres ([`CentreProximity`]), quad fairness (second
//! differences along the mesh polylines) and E_reg ([`Proximal`] on spheres and normals); and two
//! hinges that hold the support planes at ≥ α and the node axes within θ of the normals
//! ([`CentreQuadAngle`], [`AxisNormalAngle`]).
//!
//! **Phases**: a warm-up moves only the spheres (and n_cq) under E_sphere, E_unit and a small
//! E_supp; then the full optimization, until [`SqParams::sphere_decrease_window`] iterations
//! together lower its energy by at most [`SqParams::sphere_decrease_tolerance`]. Per-edge and
//! per-star normals couple only to their own edge or star, so the block ordering eliminates them
//! first (a Schur complement inside the sparse Cholesky factorization).
//!
//! **Projection to exactness.** At an inner vertex four spheres meet; when their centres are
//! coplanar, the reflection of the vertex in that plane lies on all four, so the spheres share a
//! second point and the node axis is the line through both, orthogonal to the plane. Then the
//! circle of every inner edge contains both end vertices and both second points, so neighbouring
//! node axes are coplanar: the support structure is torsion free. Exactness therefore needs only
//! (i) every vertex on its faces' spheres and (ii) coplanar centres at inner vertices. The last
//! phase walks there by a quadratic penalty (these equations at growing weights against the
//! hinges and the proximity to the reference), then solves the equations (with the unit
//! normalizations) by Gauss–Newton with a tiny damping, first with the hinges at θ and α, then
//! with the hinges faint (they steer within the exact family, the equations win; each of these
//! two passes ends where it stalls), then alone, until exact or stagnant: it converges
//! quadratically to a nearby exact solution (an underdetermined system: 4F + 4S equations,
//! 5F + 3V + 3S unknowns), after a slow, steady approach on fine meshes.

use glam::DVec3;

use crate::geometry::bspline::BSplineSurface;
use crate::geometry::mesh::PolyMesh;
use crate::geometry::sphere::Sphere;
use crate::progress::{Cancelled, Clock};
use crate::reference::proximity::{BoundaryProximity, CentroidTargets, ReferenceProximity};
use crate::reference::Reference;
use crate::solver::terms::v3;
use crate::solver::{Anchor, Hinge, PhaseTimes, PointOnSphere, Problem, Proximal, Solver, SolverOptions, TermId, TermStats, Termination, UnitLength};

use super::params::{SphereWeights, SqParams};
use super::quad_mesh::polyline_fairness;
use super::sphere_terms::{
    AxisNormalAngle, CentrePlanarity, CentreProximity, CentreQuadAngle, CentreSeparation, FanAxisAngle, NodeAxis, PanelProximity, TorsalPlane,
    VertexNormals,
};

/// Neighbouring face centres keep at least this share of their initial distance.
pub(crate) const CENTRE_SEPARATION: f64 = 0.25;

/// The weights of the equations of exactness, relative to the hinges and the proximity, in the
/// stages of the quadratic penalty that opens the projection to exactness.
const PENALTY_WEIGHTS: [f64; 4] = [1e1, 1e2, 1e3, 1e4];

/// Iterations per penalty stage (at most the projection's own).
const PENALTY_ITERATIONS: usize = 10;

/// The projection has reached exactness where its energy is at most this per equation of
/// exactness: a root mean square residual of 1e-14 (frame units), the rounding floor of the
/// sphere equations, so that no pass spends iterations on rounding however many faces there
/// are (the largest residual is then below 1e-12 even on 10⁴ equations).
const EXACT_ENERGY_PER_EQUATION: f64 = 1e-28;

/// The projection's last pass (the equations alone) may run this many times the projection's
/// iterations.
const LAST_PASS_ITERATIONS: usize = 4;
/// The last pass has stagnated when [`STAGNATION_WINDOW`] iterations together lower its energy
/// by at most this fraction (less than halve it).
const STAGNATION_DECREASE: f64 = 0.5;
const STAGNATION_WINDOW: usize = 20;

/// The hinges' weight in the projection's third pass, against the equations of exactness at 1.
const FAINT_HINGES: f64 = 1e-3;
/// A projection pass with hinges has stalled when [`STALL_WINDOW`] iterations together lower its
/// energy by at most this fraction (less than an order of magnitude).
const STALL_DECREASE: f64 = 0.9;
const STALL_WINDOW: usize = 10;

/// The phases, as reported to the hook.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SpherePhase {
    WarmUp,
    Full,
    Projection,
    /// The projection with every face at its mould's curvature ([`super::moulds`]).
    Moulds,
}

impl SpherePhase {
    pub fn key(self) -> &'static str {
        match self {
            SpherePhase::WarmUp => "warm_up",
            SpherePhase::Full => "spheres",
            SpherePhase::Projection => "projection",
            SpherePhase::Moulds => "moulds",
        }
    }
}

/// Called after every iteration with the phase, the iteration within it, the term statistics,
/// the vertices and the spheres (frame units); false cancels.
pub type SphereHook<'h> = dyn FnMut(SpherePhase, usize, &[TermStats], &[DVec3], &[Sphere]) -> Result<(), Cancelled> + 'h;

/// The combinatorics the optimization needs.
#[derive(Clone, Debug)]
pub struct QuadStars {
    /// Per inner vertex (four faces in a closed cycle, or three or five at a singular vertex,
    /// Sec. 5.2):
    /// the vertex and its faces in order.
    pub stars: Vec<(u32, Vec<u32>)>,
    /// Per vertex: its star index, if inner.
    pub star_of: Vec<Option<usize>>,
    /// Per vertex with three faces: the vertex and its faces.
    pub fans: Vec<(u32, [u32; 3])>,
    /// Every edge (lo, hi).
    pub edges: Vec<[u32; 2]>,
}

impl QuadStars {
    pub fn new(mesh: &PolyMesh) -> Self {
        let nv = mesh.vertex_count();
        let mut incident: Vec<Vec<u32>> = vec![Vec::new(); nv];
        for (f, face) in mesh.faces.iter().enumerate() {
            for &v in face.corners() {
                incident[v as usize].push(f as u32);
            }
        }
        let corner = |f: u32, v: u32| mesh.faces[f as usize].corners().iter().position(|&c| c == v);
        let mut stars = Vec::new();
        let mut star_of = vec![None; nv];
        let mut fans = Vec::new();
        for v in 0..nv as u32 {
            let faces = &incident[v as usize];
            if let &[f, g, h] = faces.as_slice() {
                fans.push((v, [f, g, h]));
            }
            let m = faces.len();
            if !(3..=5).contains(&m) {
                continue;
            }
            // Walk around v: from face f, the next face contains v and f's corner after v.
            let mut order = vec![faces[0]; m];
            let mut closed = true;
            for k in 1..=m {
                let f = order[k - 1];
                let c = mesh.faces[f as usize].corners();
                let next = c[(corner(f, v).unwrap() + 1) % c.len()];
                let g = faces.iter().copied().find(|&g| g != f && corner(g, next).is_some());
                match (k == m, g) {
                    (true, Some(g)) => closed &= g == order[0],
                    (false, Some(g)) => order[k] = g,
                    (_, None) => closed = false,
                }
                if !closed {
                    break;
                }
            }
            let mut distinct = order.clone();
            distinct.sort_unstable();
            distinct.dedup();
            if closed && distinct.len() == m {
                star_of[v as usize] = Some(stars.len());
                stars.push((v, order));
            }
        }
        let topo = crate::geometry::mesh::topology::Topology::new(mesh);
        Self { stars, star_of, fans, edges: topo.edges().to_vec() }
    }
}

/// Where the variables are.
#[derive(Clone, Copy, Debug)]
pub struct SphereLayout {
    pub faces: usize,
    pub vertices: usize,
    pub stars: usize,
    pub edges: usize,
}

impl SphereLayout {
    pub fn sphere(&self, f: usize) -> usize {
        5 * f
    }
    pub fn vertex(&self, v: usize) -> usize {
        5 * self.faces + 3 * v
    }
    pub(crate) fn star_normal(&self, s: usize) -> usize {
        5 * self.faces + 3 * self.vertices + 3 * s
    }
    pub(crate) fn edge_normal(&self, e: usize) -> usize {
        5 * self.faces + 3 * self.vertices + 3 * self.stars + 3 * e
    }
    pub fn len(&self) -> usize {
        self.edge_normal(self.edges)
    }
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// What the optimization starts from, in the frame.
pub struct SphereInput<'a> {
    pub mesh: &'a PolyMesh,
    /// Per vertex: the congruence's radius r(u, v) (frame units) and unit line, and f's unit normal.
    pub radii: &'a [f64],
    pub lines: &'a [DVec3],
    pub normals: &'a [DVec3],
    /// The lattice polylines (a, v, b), for the fairness term.
    pub polylines: &'a [[u32; 3]],
    pub on_boundary: &'a [bool],
    /// The reference in the frame.
    pub reference: &'a Reference,
    /// cos² of the angles the hinges aim at: θ for the node axes, α for the support planes.
    pub cos2_theta: f64,
    pub cos2_alpha: f64,
    /// θ and α (degrees), less a small margin: the projection's hinges.
    pub limits: [f64; 2],
}

/// What a run did.
#[derive(Clone, Debug, Default)]
pub struct SphereOutcome {
    pub warm_up_iterations: usize,
    pub iterations: usize,
    pub projection_iterations: usize,
    pub iteration_ms: Vec<f64>,
    pub phase_ms: PhaseTimes,
    /// The terms after the full optimization (before the projection).
    pub terms: Vec<TermStats>,
}

/// The initial spheres of Fig. 24 (left): per face, the mean of its corners' centres
/// q + r n and radii r.
pub fn initial_spheres(mesh: &PolyMesh, radii: &[f64], normals: &[DVec3]) -> Vec<Sphere> {
    mesh.faces
        .iter()
        .map(|face| {
            let c = face.corners();
            let k = c.len() as f64;
            let centre = c.iter().map(|&v| mesh.positions[v as usize] + radii[v as usize] * normals[v as usize]).sum::<DVec3>() / k;
            let r = c.iter().map(|&v| radii[v as usize]).sum::<f64>() / k;
            Sphere::from_center_radius(centre, r)
        })
        .collect()
}

/// The vertices and spheres of `x`.
pub fn unpack(layout: &SphereLayout, x: &[f64]) -> (Vec<DVec3>, Vec<Sphere>) {
    let vertices = (0..layout.vertices).map(|v| v3(x, layout.vertex(v))).collect();
    let spheres = (0..layout.faces).map(|f| Sphere::from_array(x[layout.sphere(f)..layout.sphere(f) + 5].try_into().unwrap())).collect();
    (vertices, spheres)
}

/// The terms of Eq. 10 and of the projection, by name.
#[derive(Clone, Copy)]
struct SphereTerms {
    sphere: TermId,
    unit: TermId,
    supp: TermId,
    star_unit: TermId,
    torsal: TermId,
    edge_unit: TermId,
    tangent: TermId,
    point: TermId,
    boundary: TermId,
    centre: TermId,
    panel: TermId,
    fair: TermId,
    reg_sphere: TermId,
    reg_normal: TermId,
    angle: TermId,
    axis: TermId,
    fan: TermId,
    separation: TermId,
    exact_angle: TermId,
    exact_axis: TermId,
    exact_fan: TermId,
}

impl SphereTerms {
    fn all(&self) -> [TermId; 21] {
        [
            self.boundary,
            self.panel,
            self.sphere,
            self.unit,
            self.supp,
            self.star_unit,
            self.torsal,
            self.edge_unit,
            self.tangent,
            self.point,
            self.centre,
            self.fair,
            self.reg_sphere,
            self.reg_normal,
            self.angle,
            self.axis,
            self.fan,
            self.separation,
            self.exact_angle,
            self.exact_axis,
            self.exact_fan,
        ]
    }

    /// Sphericity (Eq. 10's E_sphere, E_unit, E_supp) at the weights `w`, the support term's at `supp`.
    fn sphericity(&self, w: &SphereWeights, supp: f64) -> [(TermId, f64); 4] {
        [(self.sphere, w.sphere), (self.unit, w.unit), (self.supp, supp), (self.star_unit, w.unit)]
    }

    /// The equations of exactness, each at weight 1.
    fn exact(&self) -> [(TermId, f64); 4] {
        [(self.sphere, 1.0), (self.unit, 1.0), (self.supp, 1.0), (self.star_unit, 1.0)]
    }

    /// The hinges at θ and α that an exact mesh keeps, and the separation of the spheres.
    fn hinged(&self, w: &SphereWeights) -> [(TermId, f64); 4] {
        [(self.exact_angle, w.support_angle), (self.exact_axis, w.axis_angle), (self.exact_fan, w.axis_angle), (self.separation, 1.0)]
    }

    /// Proximity to the reference (Sec. 5.2): tangent and point distance of the vertices, and of
    /// the centres.
    fn proximity(&self, w: &SphereWeights) -> [(TermId, f64); 5] {
        [(self.tangent, w.prox_f), (self.point, w.prox_f), (self.centre, w.prox_c), (self.panel, w.prox_panel), (self.boundary, w.prox_boundary)]
    }

    /// Every term at weight 0 but `weights`.
    fn set(&self, problem: &mut Problem, weights: &[(TermId, f64)]) {
        for id in self.all() {
            problem.set_weight(id, 0.0);
        }
        for &(id, wt) in weights {
            problem.set_weight(id, wt);
        }
    }
}

/// The optimization's problem on `input` with all the terms at their weights, starting from
/// `input.mesh`'s vertices, `spheres` and the star normals `star_normals` (one per star).
fn sphere_problem<'a>(
    input: &SphereInput<'a>,
    stars: &QuadStars,
    w: &SphereWeights,
    spheres: &[Sphere],
    star_normals: &[DVec3],
) -> (Problem<'a>, SphereTerms, SphereLayout, Vec<f64>) {
    let mesh = input.mesh;
    let layout = SphereLayout { faces: mesh.face_count(), vertices: mesh.vertex_count(), stars: stars.stars.len(), edges: stars.edges.len() };
    let mut x = vec![0.0; layout.len()];
    for (f, s) in spheres.iter().enumerate() {
        x[layout.sphere(f)..layout.sphere(f) + 5].copy_from_slice(&s.to_array());
    }
    for (v, p) in mesh.positions.iter().enumerate() {
        x[layout.vertex(v)..layout.vertex(v) + 3].copy_from_slice(&p.to_array());
    }
    for (s, n) in star_normals.iter().enumerate() {
        x[layout.star_normal(s)..layout.star_normal(s) + 3].copy_from_slice(&n.to_array());
    }
    let axis = |v: u32| match stars.star_of[v as usize] {
        Some(s) => NodeAxis::Variable(layout.star_normal(s)),
        None => NodeAxis::Fixed(input.lines[v as usize]),
    };
    let mut torsal_edges = Vec::with_capacity(layout.edges);
    for (e, &[u, w]) in stars.edges.iter().enumerate() {
        let (pu, pw) = (mesh.positions[u as usize], mesh.positions[w as usize]);
        let l = input.lines[u as usize] + input.lines[w as usize];
        let n = (pu - pw).cross(l).try_normalize().unwrap_or(DVec3::Z);
        x[layout.edge_normal(e)..layout.edge_normal(e) + 3].copy_from_slice(&n.to_array());
        torsal_edges.push((layout.vertex(u as usize), layout.vertex(w as usize), axis(u), axis(w), layout.edge_normal(e)));
    }

    let mut problem = Problem::new(layout.len());
    let pairs: Vec<(usize, usize)> = mesh
        .faces
        .iter()
        .enumerate()
        .flat_map(|(f, face)| face.corners().iter().map(move |&v| (layout.vertex(v as usize), layout.sphere(f))))
        .collect();
    let sphere_id = problem.add_term(PointOnSphere::new(pairs).with_name("sphere"), w.sphere);
    let sphere_offsets: Vec<usize> = (0..layout.faces).map(|f| layout.sphere(f)).collect();
    let unit_id = problem.add_term(UnitLength::spheres(sphere_offsets).with_name("sphere_unit"), w.unit);
    let star_terms: Vec<(Vec<usize>, usize)> = stars
        .stars
        .iter()
        .enumerate()
        .map(|(s, (_, faces))| (faces.iter().map(|&f| layout.sphere(f as usize)).collect(), layout.star_normal(s)))
        .collect();
    let supp_id = problem.add_term(CentrePlanarity { stars: star_terms }, w.supp);
    let star_normal_offsets: Vec<usize> = (0..layout.stars).map(|s| layout.star_normal(s)).collect();
    let star_unit_id = problem.add_term(UnitLength::vectors(star_normal_offsets).with_name("axis_unit"), w.unit);
    let torsal_id = problem.add_term(TorsalPlane { edges: torsal_edges }, w.torsal_plane);
    let edge_normals: Vec<usize> = (0..layout.edges).map(|e| layout.edge_normal(e)).collect();
    let edge_unit_id = problem.add_term(UnitLength::vectors(edge_normals).with_name("torsal_plane_unit"), w.unit);
    let vertex_offsets: Vec<usize> = (0..layout.vertices).map(|v| layout.vertex(v)).collect();
    let tangent = ReferenceProximity::tangent(input.reference, vertex_offsets.clone());
    let mut point = ReferenceProximity::point(input.reference, vertex_offsets, vec![w.epsilon.sqrt(); layout.vertices]);
    point.share_closest_with(&tangent);
    let lookups = tangent.lookups();
    let tangent_id = problem.add_term(tangent.with_name("vertex_proximity"), w.prox_f);
    let point_id = problem.add_term(point.with_name("vertex_proximity_point"), w.prox_f);
    let boundary_offsets: Vec<usize> = (0..layout.vertices).filter(|&v| input.on_boundary[v]).map(|v| layout.vertex(v)).collect();
    let boundary_id = problem.add_term(BoundaryProximity::new(input.reference, boundary_offsets, &x), w.prox_boundary);
    let centre_faces: Vec<(usize, DVec3, DVec3)> = mesh
        .faces
        .iter()
        .enumerate()
        .map(|(f, face)| {
            let l = face.corners().iter().map(|&v| input.lines[v as usize]).sum::<DVec3>().normalize_or_zero();
            (layout.sphere(f), spheres[f].center().unwrap_or(DVec3::ZERO), l)
        })
        .collect();
    let centre_id = problem.add_term(CentreProximity { faces: centre_faces, epsilon: w.epsilon }, w.prox_c);
    let corners: Vec<Vec<usize>> = mesh.faces.iter().map(|face| face.corners().iter().map(|&v| layout.vertex(v as usize)).collect()).collect();
    let targets = CentroidTargets::new(input.reference, corners, &x);
    let panel_id = problem.add_term(PanelProximity { spheres: (0..layout.faces).map(|f| layout.sphere(f)).collect(), targets }, w.prox_panel);
    let fair_id = problem.add_term(polyline_fairness(input.polylines, input.on_boundary, &stars.edges, |v| layout.vertex(v)), w.fair);
    let quads: Vec<Vec<usize>> = stars.stars.iter().map(|(_, faces)| faces.iter().map(|&f| layout.sphere(f as usize)).collect()).collect();
    let axes: Vec<(usize, usize)> = stars.stars.iter().enumerate().map(|(s, &(v, _))| (layout.star_normal(s), v as usize)).collect();
    let fans: Vec<([usize; 3], usize)> = stars.fans.iter().map(|&(v, faces)| (faces.map(|f| layout.sphere(f as usize)), v as usize)).collect();
    // The proximity terms come first, so their lookups are fresh when the hinges prepare.
    let normals = VertexNormals::new(input.reference, (0..layout.vertices).map(|v| layout.vertex(v)).collect(), input.normals.to_vec(), &x)
        .with_lookups(lookups);
    // The hinges at the targets (with margins) for the optimization, and at θ and α themselves
    // (less a margin) for the projection.
    let mut hinges = |cos2_alpha: f64, cos2_theta: f64, suffix: &str| {
        // At a singular vertex the planes aim at most at what its valence allows.
        let alpha = cos2_alpha.sqrt().acos().to_degrees();
        let stars =
            quads.iter().map(|q| (q.clone(), super::sphere_terms::support_plane_aim_deg(q.len(), alpha).to_radians().cos().powi(2))).collect();
        let angle = Hinge::new(CentreQuadAngle { stars }).with_name(format!("support_plane_angle{suffix}"));
        let axis = Hinge::new(AxisNormalAngle { axes: axes.clone(), normals: normals.clone(), cos2: cos2_theta })
            .with_name(format!("axis_normal_angle{suffix}"));
        let fan = Hinge::new(FanAxisAngle { fans: fans.clone(), normals: normals.clone(), cos2: cos2_theta })
            .with_name(format!("fan_axis_normal_angle{suffix}"));
        (problem.add_term(angle, 0.0), problem.add_term(axis, 0.0), problem.add_term(fan, 0.0))
    };
    let (angle_id, axis_id, fan_id) = hinges(input.cos2_alpha, input.cos2_theta, "");
    let (exact_angle_id, exact_axis_id, exact_fan_id) =
        hinges(input.limits[1].to_radians().cos().powi(2), input.limits[0].to_radians().cos().powi(2), "_limit");
    let topo = crate::geometry::mesh::topology::Topology::new(mesh);
    let pairs: Vec<(usize, usize, f64)> = topo
        .interior_edges()
        .filter_map(|(_, f, g)| {
            let (cf, cg) = (spheres[f as usize].center()?, spheres[g as usize].center()?);
            Some((layout.sphere(f as usize), layout.sphere(g as usize), cf.distance_squared(cg)))
        })
        .collect();
    let separation_id = problem.add_term(Hinge::new(CentreSeparation { pairs, share: CENTRE_SEPARATION }).with_name("centre_separation"), 1.0);
    let sphere_vars: Vec<usize> = (0..5 * layout.faces).collect();
    let reg_sphere_id = problem.add_term(Proximal::new(sphere_vars).with_name("regularization_spheres"), w.reg_sphere);
    let normal_vars: Vec<usize> = (layout.star_normal(0)..layout.len()).collect();
    let reg_normal_id = problem.add_term(Proximal::new(normal_vars).with_name("regularization_normals"), w.reg_normal);
    for f in 0..layout.faces {
        problem.group_variables(layout.sphere(f)..layout.sphere(f) + 5);
    }
    for v in 0..layout.vertices {
        problem.group_variables(layout.vertex(v)..layout.vertex(v) + 3);
    }
    for s in 0..layout.stars {
        problem.group_variables(layout.star_normal(s)..layout.star_normal(s) + 3);
    }
    for e in 0..layout.edges {
        problem.group_variables(layout.edge_normal(e)..layout.edge_normal(e) + 3);
    }
    let terms = SphereTerms {
        sphere: sphere_id,
        unit: unit_id,
        supp: supp_id,
        star_unit: star_unit_id,
        torsal: torsal_id,
        edge_unit: edge_unit_id,
        tangent: tangent_id,
        point: point_id,
        boundary: boundary_id,
        centre: centre_id,
        panel: panel_id,
        fair: fair_id,
        reg_sphere: reg_sphere_id,
        reg_normal: reg_normal_id,
        angle: angle_id,
        axis: axis_id,
        fan: fan_id,
        separation: separation_id,
        exact_angle: exact_angle_id,
        exact_axis: exact_axis_id,
        exact_fan: exact_fan_id,
    };
    (problem, terms, layout, x)
}

/// One phase: the solver on `problem` from `x` for at most `max` iterations, each reported to
/// `hook`; the full optimization's iteration times and terms kept in `outcome`. Returns the
/// iterations and the damping ε it ended with.
fn run_phase(
    problem: &mut Problem,
    x: &mut [f64],
    layout: &SphereLayout,
    phase: SpherePhase,
    max: usize,
    solver: &mut Solver,
    outcome: &mut SphereOutcome,
    hook: &mut SphereHook,
) -> Result<(usize, f64), Cancelled> {
    solver.options.max_iterations = max;
    let report = solver.solve(problem, x, |it| {
        let (v, s) = unpack(layout, it.x);
        hook(phase, it.iteration, it.terms, &v, &s)
    });
    outcome.phase_ms.add(&report.phase_ms);
    if phase == SpherePhase::Full {
        outcome.iteration_ms.extend_from_slice(&report.iteration_ms);
        outcome.terms = report.terms.clone();
    }
    if report.termination == Termination::Cancelled {
        return Err(Cancelled);
    }
    Ok((report.iterations, report.epsilon))
}

/// The projection to exactness (see the module docs): a quadratic penalty first (the equations
/// of exactness at weights growing to 10⁴ against the hinges and the proximity to the reference:
/// straight Gauss–Newton from the optimized state lands on an exact mesh up to 2.5 % of the
/// diagonal off the reference, where the penalty's is within 1.5 %); then the equations by
/// Gauss–Newton with a tiny damping, with the hinges at θ and α (the exact solutions form a large
/// family: land on one that keeps them), then with the hinges at [`FAINT_HINGES`] (where they
/// pull against the equations the pass before stalls short of exactness, and the equations
/// alone would then drift off α: corpus 40_10 ended at 74.92°), then the equations alone, so
/// that nothing pulls against exactness; `equations` are further equations held in every pass
/// (the moulds' curvatures).
/// Returns the iterations.
fn project(
    problem: &mut Problem,
    terms: &SphereTerms,
    layout: &SphereLayout,
    w: &SphereWeights,
    x: &mut [f64],
    equations: &[TermId],
    (phase, max): (SpherePhase, usize),
    clock: Clock,
    outcome: &mut SphereOutcome,
    hook: &mut SphereHook,
) -> Result<usize, Cancelled> {
    let held: Vec<(TermId, f64)> = equations.iter().map(|&id| (id, 1.0)).collect();
    // The quadratic penalty toward exactness: the equations at growing weights against the
    // hinges and the proximity to the reference, so that the passes after start near the exact
    // mesh closest to the reference and move the vertices little.
    problem.fix_range(layout.edge_normal(0)..layout.len());
    let mut penalty = Solver::new(SolverOptions { clock, ..SolverOptions::default() });
    let mut iterations = 0;
    let mut last: Option<(f64, f64)> = None;
    for scale in PENALTY_WEIGHTS {
        let exact: Vec<(TermId, f64)> = terms.exact().iter().chain(&held).map(|&(id, wt)| (id, wt * scale)).collect();
        terms.set(problem, &[&exact[..], &terms.hinged(w)[..], &terms.proximity(w)[..]].concat());
        // A pass starts at the damping the last one ended with, grown as the normal matrix grows
        // with the weights (μ = ε² scales with them), instead of finding it again by rejected steps.
        if let Some((last_scale, epsilon)) = last {
            penalty.options.initial_epsilon = epsilon * (scale / last_scale).sqrt();
        }
        let (n, epsilon) = run_phase(problem, x, layout, phase, PENALTY_ITERATIONS.min(max), &mut penalty, outcome, hook)?;
        iterations += n;
        last = Some((scale, epsilon));
    }
    terms.set(problem, &[&terms.exact()[..], &terms.hinged(w)[..], &held[..]].concat());
    let equations: usize = terms.exact().iter().chain(&held).map(|&(id, _)| problem.term(id).residual_count()).sum();
    let mut projection = Solver::new(SolverOptions {
        clock,
        min_epsilon: 1e-7,
        energy_tolerance: EXACT_ENERGY_PER_EQUATION * equations as f64,
        relative_decrease_tolerance: 0.0,
        step_tolerance: 1e-16,
        ..SolverOptions::default()
    });
    // The passes with hinges stop where they stall (10 iterations that do not gain an order of
    // magnitude): they only steer within the exact family, and the last pass reaches exactness.
    projection.options.decrease_window = STALL_WINDOW;
    projection.options.relative_decrease_tolerance = STALL_DECREASE;
    iterations += run_phase(problem, x, layout, phase, max, &mut projection, outcome, hook)?.0;
    // Where the hinges and the equations pull apart, that pass stalls short of exactness; with
    // the hinges faint the equations win, while the hinges still steer within the exact family.
    let faint: Vec<(TermId, f64)> = terms.hinged(w).iter().map(|&(id, wt)| (id, wt * FAINT_HINGES)).collect();
    terms.set(problem, &[&terms.exact()[..], &faint[..], &held[..]].concat());
    iterations += run_phase(problem, x, layout, phase, max, &mut projection, outcome, hook)?.0;
    // The equations alone run until exact: on fine meshes their descent is steady but slow
    // (2964 quads: 167 iterations, most at a gain ratio near 0.7 before it turns quadratic), so
    // this pass may take [`LAST_PASS_ITERATIONS`] times the others' budget, and stops early only
    // where it has stagnated.
    projection.options.decrease_window = STAGNATION_WINDOW;
    projection.options.relative_decrease_tolerance = STAGNATION_DECREASE;
    terms.set(problem, &[&terms.exact()[..], &held[..]].concat());
    iterations += run_phase(problem, x, layout, phase, LAST_PASS_ITERATIONS * max, &mut projection, outcome, hook)?.0;
    Ok(iterations)
}

/// Runs the warm-up, the full optimization and the projection (see the module docs) with
/// `params`' sphere weights, iterations and decrease tolerance (the full optimization stops early
/// when its decrease window of iterations lowers its energy by at most that fraction); returns
/// the vertices, the spheres (normalized) and what happened.
pub(crate) fn optimize_spheres(
    input: &SphereInput,
    stars: &QuadStars,
    params: &SqParams,
    clock: Clock,
    hook: &mut SphereHook,
) -> Result<(Vec<DVec3>, Vec<Sphere>, SphereOutcome), Cancelled> {
    let (w, iterations) = (&params.sphere_weights, params.sphere_iterations);
    let spheres = initial_spheres(input.mesh, input.radii, input.normals);
    let star_normals: Vec<DVec3> = stars.stars.iter().map(|&(v, _)| input.lines[v as usize]).collect();
    let (mut problem, terms, layout, mut x) = sphere_problem(input, stars, w, &spheres, &star_normals);
    let mut outcome = SphereOutcome::default();
    let mut solver = Solver::new(SolverOptions { clock, ..SolverOptions::default() });

    // Warm-up: the spheres and the star normals move; sphericity and a small support weight.
    let regularization = [(terms.reg_sphere, w.reg_sphere), (terms.reg_normal, w.reg_normal), (terms.separation, 1.0)];
    terms.set(&mut problem, &[&terms.sphericity(w, w.warm_up_supp)[..], &regularization[..]].concat());
    problem.fix_range(layout.vertex(0)..layout.star_normal(0));
    problem.fix_range(layout.edge_normal(0)..layout.len());
    outcome.warm_up_iterations = run_phase(&mut problem, &mut x, &layout, SpherePhase::WarmUp, iterations[0], &mut solver, &mut outcome, hook)?.0;

    // The full optimization (Eq. 10).
    let support = [
        (terms.torsal, w.torsal_plane),
        (terms.edge_unit, w.unit),
        (terms.fair, w.fair),
        (terms.angle, w.support_angle),
        (terms.axis, w.axis_angle),
        (terms.fan, w.axis_angle),
    ];
    terms.set(&mut problem, &[&terms.sphericity(w, w.supp)[..], &support[..], &terms.proximity(w)[..], &regularization[..]].concat());
    for i in 0..layout.len() {
        problem.unfix(i);
    }
    solver.options.relative_decrease_tolerance = params.sphere_decrease_tolerance;
    solver.options.decrease_window = params.sphere_decrease_window;
    outcome.iterations = run_phase(&mut problem, &mut x, &layout, SpherePhase::Full, iterations[1], &mut solver, &mut outcome, hook)?.0;

    outcome.projection_iterations =
        project(&mut problem, &terms, &layout, w, &mut x, &[], (SpherePhase::Projection, iterations[2]), clock, &mut outcome, hook)?;
    let (v, s) = unpack(&layout, &x);
    Ok((v, s.into_iter().map(|s| s.normalized()).collect(), outcome))
}

/// The projection to exactness from an exact state (`input.mesh`'s vertices, `spheres`, and per
/// star the normal of its centres' plane), with every face's curvature held at `curvatures`
/// (frame units, signed along the face's normal; NaN: free): the SQ mesh whose panels have their
/// moulds' radii. The system stays underdetermined (F more equations on 5F + 3V + 3S unknowns
/// with 4F + 4S before), so Gauss–Newton lands on a nearby exact solution. Returns the vertices,
/// the spheres (normalized) and the iterations.
pub(crate) fn project_to_curvatures(
    input: &SphereInput,
    stars: &QuadStars,
    spheres: &[Sphere],
    curvatures: &[f64],
    params: &SqParams,
    clock: Clock,
    hook: &mut SphereHook,
) -> Result<(Vec<DVec3>, Vec<Sphere>, usize), Cancelled> {
    let w = &params.sphere_weights;
    let star_normals: Vec<DVec3> = stars.stars.iter().map(|(v, faces)| centre_plane_normal(spheres, faces, input.lines[*v as usize])).collect();
    let (mut problem, terms, layout, mut x) = sphere_problem(input, stars, w, spheres, &star_normals);
    // A normalized sphere's curvature along its normal is 2a: hold a at |κ|/2 with the sign of
    // the start's a, so that no panel is asked to turn over.
    let (faces, halves): (Vec<usize>, Vec<f64>) = curvatures
        .iter()
        .enumerate()
        .filter(|(_, k)| k.is_finite())
        .map(|(f, &k)| (layout.sphere(f), 0.5 * k.abs().copysign(x[layout.sphere(f)])))
        .unzip();
    let mould = problem.add_term(Anchor::new(faces, halves).with_name("mould_curvature"), 1.0);
    let mut outcome = SphereOutcome::default();
    // First the curvatures are reached softly, the vertices and centres near the reference
    // (Eq. 10's proximity terms), so the projection after starts close to an exact mesh.
    terms.set(&mut problem, &[&terms.sphericity(w, w.supp)[..], &terms.proximity(w)[..], &terms.hinged(w)[..]].concat());
    problem.fix_range(layout.edge_normal(0)..layout.len());
    let max = params.sphere_iterations[2];
    let mut solver = Solver::new(SolverOptions { clock, ..SolverOptions::default() });
    let mut iterations = run_phase(&mut problem, &mut x, &layout, SpherePhase::Moulds, max, &mut solver, &mut outcome, hook)?.0;
    iterations += project(&mut problem, &terms, &layout, w, &mut x, &[mould], (SpherePhase::Moulds, max), clock, &mut outcome, hook)?;
    let (v, s) = unpack(&layout, &x);
    Ok((v, s.into_iter().map(|s| s.normalized()).collect(), iterations))
}

/// The unit normal of the plane through the centres of `faces`' spheres (least squares, the
/// smallest principal direction), on the side of `toward`; `toward` where there are no centres.
fn centre_plane_normal(spheres: &[Sphere], faces: &[u32], toward: DVec3) -> DVec3 {
    let centres: Vec<DVec3> = faces.iter().filter_map(|&f| spheres[f as usize].center()).collect();
    if centres.len() < 3 {
        return toward;
    }
    let mean = centres.iter().copied().sum::<DVec3>() / centres.len() as f64;
    let rows: Vec<[f64; 3]> = centres.iter().map(|c| (*c - mean).to_array()).collect();
    let n = DVec3::from_array(crate::geometry::linalg::Svd::new(&rows).v[2]).try_normalize().unwrap_or(toward);
    if n.dot(toward) < 0.0 {
        -n
    } else {
        n
    }
}

/// The congruence's line and radius at a parameter: bilinear in the points of the grid G
/// (`n` × `n`, point (i, j) at i + n j) over the domain.
pub(crate) fn on_grid<T: Copy + std::ops::Mul<f64, Output = T> + std::ops::Add<Output = T>>(
    surface: &BSplineSurface,
    n: usize,
    values: &[T],
    uv: [f64; 2],
) -> T {
    let ((u0, u1), (v0, v1)) = surface.domain();
    let s = ((uv[0] - u0) / (u1 - u0) * (n - 1) as f64).clamp(0.0, (n - 1) as f64);
    let t = ((uv[1] - v0) / (v1 - v0) * (n - 1) as f64).clamp(0.0, (n - 1) as f64);
    let (i, j) = ((s.floor() as usize).min(n - 2), (t.floor() as usize).min(n - 2));
    let (fs, ft) = (s - i as f64, t - j as f64);
    let at = |a: usize, b: usize| values[(i + a) + n * (j + b)];
    at(0, 0) * ((1.0 - fs) * (1.0 - ft)) + at(1, 0) * (fs * (1.0 - ft)) + at(0, 1) * ((1.0 - fs) * ft) + at(1, 1) * (fs * ft)
}
