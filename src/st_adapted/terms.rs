//! The residual terms of the angle-minimizing ST optimization (see the [`super`] module docs)
//! and the problem they make. The variables are one pencil angle θ_f per face (first) and the
//! vertices (3-blocks, after): face f's sphere is the member s_f = cos θ_f s₀ + sin θ_f s₁ of the
//! pencil through its three vertices ([`crate::geometry::pencil`]), so it passes through them
//! exactly and every sphere term reaches the vertices through the chain rule.

use std::cell::RefCell;
use std::rc::Rc;

use glam::DVec3;

use super::params::StAdaptedWeights;
use crate::geometry::dual::{Dual, D3};
use crate::geometry::mesh::topology::Topology;
use crate::geometry::mesh::TriMesh;
use crate::geometry::pencil::{pencil_angle, pencil_member, PencilMember};
use crate::geometry::sphere::Sphere;
use crate::reference::proximity::{value_gradient, CentroidTargets, ClosestLookups, ReferenceProximity};
use crate::reference::Reference;
use crate::solver::terms::v3;
use crate::solver::{Band, Hinge, JacobianSink, Linear, Problem, Term, TermId};

/// Boundary vertices get this factor on their point-distance residuals.
pub const BOUNDARY_POINT_FACTOR: f64 = 10.0;

/// Least oriented area a face keeps, as a fraction of its initial area ([`FaceOrientation`]).
pub(crate) const MIN_AREA_FRACTION: f64 = 0.2;

/// The share of its initial oriented area along the reference normal that a face keeps in every
/// step ([`FaceOrientation::along`]): a margin, since that normal is taken at the centroid's
/// initial closest point.
pub(crate) const UNFOLDED_AREA_FRACTION: f64 = 0.1;

/// Face orientation (no folded panels while vertices glide; the optimization also takes no step
/// that folds a face, [`FaceOrientation::keeps_orientation`]): per face, the residual
/// g = τ − ((b − a) × (c − a))·n / A₀ with n the face's initial unit normal and A₀ its initial
/// |(b − a) × (c − a)|. Under [`Hinge`] it is the inequality "oriented area ≥ τ × initial area".
pub struct FaceOrientation {
    items: Vec<[usize; 3]>,
    normals: Vec<DVec3>,
    inv_areas: Vec<f64>,
    tau: f64,
}

impl FaceOrientation {
    /// `items`: the offsets of each face's three vertices in `x`, counter-clockwise.
    pub fn new(items: Vec<[usize; 3]>, x: &[f64], tau: f64) -> Self {
        let (mut normals, mut inv_areas) = (Vec::with_capacity(items.len()), Vec::with_capacity(items.len()));
        for o in &items {
            let [a, b, c] = o.map(|k| DVec3::new(x[k], x[k + 1], x[k + 2]));
            let area = (b - a).cross(c - a);
            let len = area.length();
            normals.push(if len > 0.0 { area / len } else { DVec3::ZERO });
            inv_areas.push(if len > 0.0 { 1.0 / len } else { 0.0 });
        }
        Self { items, normals, inv_areas, tau }
    }
}

impl FaceOrientation {
    /// The faces with `normal(centroid)` as their normals, each signed to the side its face
    /// starts on (zero where there is none or the face is degenerate).
    pub fn along(items: Vec<[usize; 3]>, x: &[f64], normal: impl Fn(DVec3) -> Option<DVec3>) -> Self {
        let normals = items
            .iter()
            .map(|o| {
                let [a, b, c] = o.map(|k| DVec3::new(x[k], x[k + 1], x[k + 2]));
                let side = (b - a).cross(c - a);
                match normal((a + b + c) / 3.0) {
                    Some(n) if side.dot(n) != 0.0 => n * side.dot(n).signum(),
                    _ => DVec3::ZERO,
                }
            })
            .collect();
        // Each face keeps at least this share of its initial oriented area along its normal.
        let inv_areas = items
            .iter()
            .zip(&normals)
            .map(|(o, n): (&[usize; 3], &DVec3)| {
                let [a, b, c] = o.map(|k| DVec3::new(x[k], x[k + 1], x[k + 2]));
                let area = (b - a).cross(c - a).dot(*n);
                if area > 0.0 {
                    1.0 / area
                } else {
                    0.0
                }
            })
            .collect();
        Self { items, normals, inv_areas, tau: UNFOLDED_AREA_FRACTION }
    }

    /// Whether every face (with an initial orientation) keeps a positive oriented area along its
    /// normal: no face folds over.
    pub fn keeps_orientation(&self, x: &[f64]) -> bool {
        self.items.iter().zip(&self.normals).zip(&self.inv_areas).all(|((o, n), inv)| {
            let [a, b, c] = o.map(|i| DVec3::new(x[i], x[i + 1], x[i + 2]));
            *n == DVec3::ZERO || (b - a).cross(c - a).dot(*n) * inv > self.tau
        })
    }
}

impl Term for FaceOrientation {
    fn name(&self) -> &str {
        "orientation"
    }
    fn residual_count(&self) -> usize {
        self.items.len()
    }
    fn eval(&self, x: &[f64], r: &mut [f64], jac: &mut JacobianSink) {
        for (k, o) in self.items.iter().enumerate() {
            let (n, inv) = (self.normals[k], self.inv_areas[k]);
            if inv == 0.0 {
                r[k] = -1.0; // a degenerate initial face has no orientation to keep
                continue;
            }
            let [a, b, c] = o.map(|i| DVec3::new(x[i], x[i + 1], x[i + 2]));
            let (u, w) = (b - a, c - a);
            r[k] = self.tau - u.cross(w).dot(n) * inv;
            // ∂/∂b (u × w)·n = w × n, ∂/∂c = n × u, ∂/∂a = −(both).
            let db = -w.cross(n) * inv;
            let dc = -n.cross(u) * inv;
            let da = -(db + dc);
            for (off, d) in [(o[0], da), (o[1], db), (o[2], dc)] {
                for i in 0..3 {
                    jac.add(k, off + i, d[i]);
                }
            }
        }
    }
}

/// The face spheres at a point x: s_f is the member θ_f = x[f] of the pencil through face f's
/// vertices. Computed once per point (with their Jacobians) and shared by the terms that use them.
#[derive(Clone)]
pub struct FaceSpheres {
    shared: Rc<SharedSpheres>,
}

struct SharedSpheres {
    /// The offsets of each face's three vertices, counter-clockwise.
    corners: Vec<[usize; 3]>,
    /// (θ and the nine coordinates of every face, the members there).
    cache: RefCell<(Vec<f64>, Vec<PencilMember>)>,
}

impl FaceSpheres {
    pub fn new(corners: Vec<[usize; 3]>) -> Self {
        Self { shared: Rc::new(SharedSpheres { corners, cache: RefCell::new((Vec::new(), Vec::new())) }) }
    }

    /// Calls `f` with the members at `x` (recomputed only when θ or a corner changed).
    pub fn with<R>(&self, x: &[f64], f: impl FnOnce(&[PencilMember]) -> R) -> R {
        let corners = &self.shared.corners;
        let mut cache = self.shared.cache.borrow_mut();
        let (key, members) = &mut *cache;
        let fresh = key.len() == 10 * corners.len()
            && corners
                .iter()
                .zip(key.chunks_exact(10))
                .enumerate()
                .all(|(k, (c, kk))| kk[0] == x[angle_offset(k)] && c.iter().enumerate().all(|(i, &o)| kk[1 + 3 * i..4 + 3 * i] == x[o..o + 3]));
        if !fresh {
            key.clear();
            members.clear();
            for (k, c) in corners.iter().enumerate() {
                let theta = x[angle_offset(k)];
                key.push(theta);
                for &o in c {
                    key.extend_from_slice(&x[o..o + 3]);
                }
                members.push(pencil_member(c.map(|o| DVec3::new(x[o], x[o + 1], x[o + 2])), theta));
            }
        }
        f(members)
    }

    /// Adds the Jacobian row `row` of a scalar g(s_f), given ∂g/∂s_f = `grad`.
    pub(crate) fn add_chain(&self, jac: &mut JacobianSink, row: usize, f: usize, member: &PencilMember, grad: &[f64; 5]) {
        let (dt, dp) = member.chain(grad);
        jac.add(row, angle_offset(f), dt);
        for (k, &o) in self.shared.corners[f].iter().enumerate() {
            jac.add_block(row, o, &dp[3 * k..3 * k + 3]);
        }
    }
}

/// ∂⟨s, t⟩/∂s of the inversive product ⟨s, t⟩ = bᵀb′ − 2(a c′ + a′ c) ([`Sphere::inversive_product`]).
fn inversive_product_gradient(t: &[f64; 5]) -> [f64; 5] {
    [-2.0 * t[4], t[1], t[2], t[3], -2.0 * t[0]]
}

/// E_angle (Sec. 3): ⟨s_f, s_g⟩ − 1 for every interior edge, the cosine of the kink angle minus 1
/// for normalized spheres oriented alike.
pub struct KinkAngle {
    spheres: FaceSpheres,
    /// (f, g) per interior edge.
    edges: Vec<(usize, usize)>,
}

impl Term for KinkAngle {
    fn name(&self) -> &str {
        "angle"
    }
    fn residual_count(&self) -> usize {
        self.edges.len()
    }
    fn eval(&self, x: &[f64], r: &mut [f64], jac: &mut JacobianSink) {
        self.spheres.with(x, |m| {
            for (k, &(f, g)) in self.edges.iter().enumerate() {
                let (sf, sg) = (&m[f].sphere, &m[g].sphere);
                r[k] = Sphere::from_array(*sf).inversive_product(&Sphere::from_array(*sg)) - 1.0;
                self.spheres.add_chain(jac, k, f, &m[f], &inversive_product_gradient(sg));
                self.spheres.add_chain(jac, k, g, &m[g], &inversive_product_gradient(sf));
            }
        });
    }
}

/// Face spheres near the reference: ψ_f(r_f), r_f the reference point closest to the centroid of
/// face f's vertices ([`CentroidTargets`], refreshed in [`Term::prepare`]; constant in the Jacobian).
/// For a normalized sphere ψ ≈ the signed distance of r_f to it, so this bounds the panels' bulge.
/// Clones share their targets (the tolerance band looks nothing up again).
#[derive(Clone)]
pub struct FaceDistance<'a> {
    spheres: FaceSpheres,
    targets: Rc<RefCell<CentroidTargets<'a>>>,
}

impl Term for FaceDistance<'_> {
    fn name(&self) -> &str {
        "face_distance"
    }
    fn residual_count(&self) -> usize {
        self.targets.borrow().len()
    }
    fn prepare(&mut self, x: &[f64]) {
        self.targets.borrow_mut().update(x);
    }
    fn eval(&self, x: &[f64], r: &mut [f64], jac: &mut JacobianSink) {
        let targets = self.targets.borrow();
        self.spheres.with(x, |m| {
            for (f, member) in m.iter().enumerate() {
                let g = value_gradient(targets.target(f));
                r[f] = g.iter().zip(&member.sphere).map(|(g, s)| g * s).sum();
                self.spheres.add_chain(jac, f, f, member, &g);
            }
        });
    }
}

/// Variant (a) (Fig. 12 left, Sec. 6.1 "nice intersection circles"): the edge circle of two
/// adjacent faces is the intersection circle of their spheres, and its arc between the edge's
/// vertices p, q should stay over the edge, not bulge sideways out of the surface's footprint.
/// Residual per interior edge: the arc's sideways bulge (L²/8) κ sin φ, with L = |p − q|, κ the
/// circle's curvature and φ the tilt of its plane from the reference normal n_e at the edge
/// (sin φ = ⟨m̂, n_e⟩, m = a_g b_f − a_f b_g the plane's normal; 0 when the circle is orthogonal
/// to R). The curvature comes from the pencil of s_f, s_g: κ is twice the largest a over its
/// unit members, κ² = 4 ((a_f − a_g)² + 2 a_f a_g (1 − c)) / (1 − c²), c = ⟨s_f, s_g⟩, so two
/// nearly tangent spheres of different radii, whose circle is small, pay for it. n_e is the mean
/// of the reference normals at the closest points of p and q, taken in [`Term::prepare`] from the
/// proximity terms' lookups (constant in the Jacobian).
pub struct EdgeCircle {
    spheres: FaceSpheres,
    /// (f, g, offset of p, offset of q) per interior edge.
    edges: Vec<(usize, usize, usize, usize)>,
    /// (p, q) as vertex indices, the keys of `lookups`.
    ends: Vec<(usize, usize)>,
    lookups: ClosestLookups,
    normals: Vec<DVec3>,
}

/// κ sin φ of the intersection circle of s_f and s_g (see [`EdgeCircle`]) and its gradient by
/// (s_f, s_g); None where the circle is undefined (tangent or equal spheres).
fn edge_circle_bulge(sf: &[f64; 5], sg: &[f64; 5], n: DVec3) -> Option<(f64, [f64; 10])> {
    let v: [Dual<10>; 10] = std::array::from_fn(|k| Dual::variable(if k < 5 { sf[k] } else { sg[k - 5] }, k));
    let (af, cf, ag, cg) = (v[0], v[4], v[5], v[9]);
    let bf = D3 { x: v[1], y: v[2], z: v[3] };
    let bg = D3 { x: v[6], y: v[7], z: v[8] };
    let c = bf.dot(bg) - (af * cg + ag * cf) * 2.0;
    let one_minus_c = Dual::constant(1.0) - c;
    let da = af - ag;
    let q = da * da + af * ag * one_minus_c * 2.0;
    let sine_denominator = one_minus_c * (Dual::constant(1.0) + c);
    let m = bf * ag - bg * af;
    let mm = m.dot(m);
    if !(one_minus_c.v > 1e-14 && q.v > 1e-300 && mm.v > 1e-300 && sine_denominator.v > 0.0) {
        return None;
    }
    let kappa = (q / sine_denominator).sqrt() * 2.0;
    let sin_phi = m.dot(D3::constant(n)) / mm.sqrt();
    let k = kappa * sin_phi;
    k.v.is_finite().then_some((k.v, k.d))
}

impl Term for EdgeCircle {
    fn name(&self) -> &str {
        "edge_circle"
    }
    fn residual_count(&self) -> usize {
        self.edges.len()
    }
    fn prepare(&mut self, x: &[f64]) {
        for (k, (&(_, _, po, qo), &(p, q))) in self.edges.iter().zip(&self.ends).enumerate() {
            if let (Some(a), Some(b)) = (self.lookups.normal_at(p, v3(x, po)), self.lookups.normal_at(q, v3(x, qo))) {
                self.normals[k] = (a + b).normalize_or(self.normals[k]);
            }
        }
    }
    fn eval(&self, x: &[f64], r: &mut [f64], jac: &mut JacobianSink) {
        self.spheres.with(x, |m| {
            for (k, &(f, g, po, qo)) in self.edges.iter().enumerate() {
                // No intersection circle to bend (equal or tangent spheres): residual 0, with
                // the same Jacobian pattern, so the solver keeps its symbolic factorization.
                let (bulge, grad) = edge_circle_bulge(&m[f].sphere, &m[g].sphere, self.normals[k]).unwrap_or((0.0, [0.0; 10]));
                let d = v3(x, po) - v3(x, qo);
                let l2 = d.length_squared() / 8.0;
                r[k] = l2 * bulge;
                let gf: [f64; 5] = std::array::from_fn(|i| l2 * grad[i]);
                let gg: [f64; 5] = std::array::from_fn(|i| l2 * grad[5 + i]);
                self.spheres.add_chain(jac, k, f, &m[f], &gf);
                self.spheres.add_chain(jac, k, g, &m[g], &gg);
                let dp = d * (bulge / 4.0);
                jac.add_block(k, po, &dp.to_array());
                jac.add_block(k, qo, &(-dp).to_array());
            }
        });
    }
}

/// Variant (a): the two panels of an interior edge pq bulge alike over it. A normalized sphere
/// (curvature 2a) rises (L²/8)·2a over a chord of length L = |p − q|, so the panels' sagittas
/// over pq differ by (L²/4)(a_f − a_g), the residual. Where that exceeds τ (in a [`Band`]), the
/// spheres meet in a small circle whose arc leaves the surface sideways, the overhang that
/// [`EdgeCircle`]'s small-arc estimate underrates near the boundary of a surface whose H
/// changes sign (a nearly flat sphere beside a small one, Sec. 6.3).
pub struct SagittaMatch {
    spheres: FaceSpheres,
    /// (f, g, offset of p, offset of q) per interior edge.
    edges: Vec<(usize, usize, usize, usize)>,
}

impl Term for SagittaMatch {
    fn name(&self) -> &str {
        "sagitta_match"
    }
    fn residual_count(&self) -> usize {
        self.edges.len()
    }
    fn eval(&self, x: &[f64], r: &mut [f64], jac: &mut JacobianSink) {
        self.spheres.with(x, |m| {
            for (k, &(f, g, po, qo)) in self.edges.iter().enumerate() {
                let d = v3(x, po) - v3(x, qo);
                let l2 = d.length_squared() / 4.0;
                let da = m[f].sphere[0] - m[g].sphere[0];
                r[k] = l2 * da;
                self.spheres.add_chain(jac, k, f, &m[f], &[l2, 0.0, 0.0, 0.0, 0.0]);
                self.spheres.add_chain(jac, k, g, &m[g], &[-l2, 0.0, 0.0, 0.0, 0.0]);
                let dp = d * (da / 2.0);
                jac.add_block(k, po, &dp.to_array());
                jac.add_block(k, qo, &(-dp).to_array());
            }
        });
    }
}

/// Handles of the terms of [`build_problem`].
#[derive(Clone, Debug)]
pub struct StAdaptedTerms {
    pub angle: TermId,
    pub tangent_distance: TermId,
    pub point_distance: TermId,
    pub face_distance: TermId,
    pub fairness: TermId,
    pub edge_circle: Option<TermId>,
    /// The sagitta match band (variant (a), with a tolerance).
    pub sagitta_match: Option<TermId>,
    /// The tolerance band (vertices, face centroids), when the problem has a tolerance.
    pub tolerance: Option<[TermId; 2]>,
    pub orientation: TermId,
}

/// Vertices on an edge without exactly two faces (boundary or non-manifold): they keep their
/// place on the reference boundary and get no fairness term.
pub fn boundary_vertices(topology: &Topology) -> Vec<bool> {
    let mut boundary = vec![false; topology.vertex_count()];
    for (e, &[a, b]) in topology.edges().iter().enumerate() {
        if topology.edge_face_counts()[e] != 2 {
            boundary[a as usize] = true;
            boundary[b as usize] = true;
        }
    }
    boundary
}

/// Offset of face f's pencil angle θ_f.
pub(crate) fn angle_offset(f: usize) -> usize {
    f
}

/// Offset of vertex v's block in a problem with `faces` faces.
pub fn vertex_offset(faces: usize, v: usize) -> usize {
    faces + 3 * v
}

/// The variable vector: the pencil angle of each face's sphere, then the vertices. Each sphere is
/// replaced by the member of its face's pencil closest to it (itself when it passes through the
/// face's vertices).
pub fn pack(mesh: &TriMesh, spheres: &[Sphere]) -> Vec<f64> {
    let mut x = Vec::with_capacity(spheres.len() + 3 * mesh.vertex_count());
    x.extend(spheres.iter().enumerate().map(|(f, s)| pencil_angle(mesh.face_points(f), s)));
    for v in &mesh.positions {
        x.extend_from_slice(&v.to_array());
    }
    x
}

/// Inverse of [`pack`]: the vertices and the face spheres of `x` over `triangles`.
pub fn unpack(x: &[f64], triangles: &[[u32; 3]], vertices: usize) -> (Vec<DVec3>, Vec<Sphere>) {
    let nf = triangles.len();
    let verts: Vec<DVec3> = (0..vertices).map(|v| v3(x, vertex_offset(nf, v))).collect();
    let spheres = triangles.iter().enumerate().map(|(f, t)| pencil_member(t.map(|v| verts[v as usize]), x[angle_offset(f)]).sphere()).collect();
    (verts, spheres)
}

/// The optimization problem over `mesh` (faces' pencil angles and vertices, see [`pack`]) against
/// the reference, both in the same coordinates; `topology` is the mesh's. `x` is the starting
/// point (for the initial face orientations and the first closest-point lookups). `tolerance`:
/// the half-width τ of the tolerance band (same units), beyond which vertices and face centroids
/// pay `weights.tolerance` ([`Band`]), and adjacent panels whose sagittas differ by more pay
/// `weights.sagitta_match` ([`SagittaMatch`]).
pub fn build_problem<'a>(
    mesh: &TriMesh,
    topology: &Topology,
    reference: &'a Reference,
    weights: &StAdaptedWeights,
    tolerance: Option<f64>,
    x: &[f64],
) -> (Problem<'a>, StAdaptedTerms) {
    let boundary = boundary_vertices(topology);
    let interior: Vec<(u32, u32, usize, usize)> =
        topology.interior_edges().map(|(e, f, g)| (topology.edges()[e][0], topology.edges()[e][1], f as usize, g as usize)).collect();
    let nf = mesh.face_count();
    let nv = mesh.vertex_count();
    let mut problem = Problem::new(nf + 3 * nv);
    // Angles and vertices are the blocks of the fill-reducing ordering.
    for f in 0..nf {
        problem.group_variables(angle_offset(f)..angle_offset(f) + 1);
    }
    for v in 0..nv {
        problem.group_variables(vertex_offset(nf, v)..vertex_offset(nf, v) + 3);
    }
    let corners: Vec<[usize; 3]> = mesh.triangles.iter().map(|t| t.map(|v| vertex_offset(nf, v as usize))).collect();
    let spheres = FaceSpheres::new(corners.clone());
    let edges: Vec<(usize, usize)> = interior.iter().map(|&(_, _, f, g)| (f, g)).collect();
    let angle = problem.add_term(KinkAngle { spheres: spheres.clone(), edges: edges.clone() }, weights.angle);
    let offsets: Vec<usize> = (0..nv).map(|v| vertex_offset(nf, v)).collect();
    let scales = (0..nv).map(|v| if boundary[v] { BOUNDARY_POINT_FACTOR } else { 1.0 }).collect();
    let tangent = ReferenceProximity::tangent(reference, offsets.clone());
    let mut point = ReferenceProximity::point(reference, offsets.clone(), scales);
    point.share_closest_with(&tangent);
    // The tolerance band's vertex rows: the tangent distance again, on the same lookups.
    let mut vertex_band = ReferenceProximity::tangent(reference, offsets);
    vertex_band.share_closest_with(&tangent);
    let lookups = tangent.lookups();
    let tangent_distance = problem.add_term(tangent, weights.tangent_distance);
    let point_distance = problem.add_term(point, weights.point_distance);
    let targets = CentroidTargets::new(reference, corners.iter().map(|c| c.to_vec()).collect(), x);
    let face = FaceDistance { spheres: spheres.clone(), targets: Rc::new(RefCell::new(targets)) };
    let face_distance = problem.add_term(face.clone(), weights.face_distance);
    let mut lap = Linear::new().with_name("fairness");
    for (v, &on_boundary) in boundary.iter().enumerate() {
        let nb = topology.vertex_neighbors(v);
        if on_boundary || nb.is_empty() {
            continue;
        }
        let w = 1.0 / nb.len() as f64;
        for i in 0..3 {
            let mut row = vec![(vertex_offset(nf, v) + i, 1.0)];
            row.extend(nb.iter().map(|&u| (vertex_offset(nf, u as usize) + i, -w)));
            lap.push_row(&row, 0.0);
        }
    }
    let fairness = problem.add_term(lap, weights.fairness);
    // The tolerance band: vertices and face centroids farther than τ from the reference.
    let tolerance_terms = tolerance.filter(|_| weights.tolerance > 0.0).map(|tau| {
        [
            problem.add_term(Band::new(vertex_band, tau).with_name("vertex_tolerance"), weights.tolerance),
            problem.add_term(Band::new(face, tau).with_name("face_tolerance"), weights.tolerance),
        ]
    });
    // No step folds a face: each keeps the side of the reference normal at its centroid's closest
    // point that it starts on (the folded-face count of the metrics, with normals held fixed).
    let unfolded = FaceOrientation::along(corners.clone(), x, |c| reference.closest_point(c).and_then(|p| p.normal));
    problem.set_admissible(move |x| unfolded.keeps_orientation(x));
    let orientation =
        problem.add_term(Hinge::new(FaceOrientation::new(corners.clone(), x, MIN_AREA_FRACTION)).with_name("orientation"), weights.orientation);
    // (f, g, offset of p, offset of q) per interior edge pq.
    let edge_faces: Vec<_> = interior.iter().map(|&(a, b, f, g)| (f, g, vertex_offset(nf, a as usize), vertex_offset(nf, b as usize))).collect();
    let edge_circle = (weights.edge_circle > 0.0).then(|| {
        let ends = interior.iter().map(|&(a, b, _, _)| (a as usize, b as usize)).collect();
        // Until the proximity terms have looked the vertices up: the mean of the faces' normals.
        let normals = interior
            .iter()
            .map(|&(_, _, f, g)| (mesh.face_area_vector(f).normalize_or_zero() + mesh.face_area_vector(g).normalize_or_zero()).normalize_or_zero())
            .collect();
        problem.add_term(
            EdgeCircle { spheres: spheres.clone(), edges: edge_faces.clone(), ends, lookups: lookups.clone(), normals },
            weights.edge_circle,
        )
    });
    let sagitta_match = tolerance.filter(|_| weights.sagitta_match > 0.0).map(|tau| {
        problem
            .add_term(Band::new(SagittaMatch { spheres: spheres.clone(), edges: edge_faces }, tau).with_name("sagitta_match"), weights.sagitta_match)
    });
    let terms = StAdaptedTerms {
        angle,
        tangent_distance,
        point_distance,
        face_distance,
        fairness,
        edge_circle,
        sagitta_match,
        orientation,
        tolerance: tolerance_terms,
    };
    (problem, terms)
}
