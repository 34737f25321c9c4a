//! The residual terms of the angle-minimizing ST optimization (see the [`super`] module docs)
//! and the problem they make: face spheres (5-blocks (a, b, c), first) and vertices (3-blocks,
//! after) as variables.

use glam::DVec3;

use super::params::StAdaptedWeights;
use crate::geometry::mesh::TriMesh;
use crate::geometry::mesh::topology::Topology;
use crate::geometry::sphere::Sphere;
use crate::reference::proximity::{FaceProximity, ReferenceProximity};
use crate::reference::Reference;
use crate::solver::{Hinge, InversiveProduct, JacobianSink, Linear, PointOnSphere, Problem, Term, TermId, UnitLength};
use crate::solver::terms::v3;

/// Boundary vertices get this factor on their point-distance residuals.
pub const BOUNDARY_POINT_FACTOR: f64 = 10.0;

/// Least oriented area a face keeps, as a fraction of its initial area ([`FaceOrientation`]).
pub const MIN_AREA_FRACTION: f64 = 0.2;

/// Face orientation (no folded panels while vertices glide): per face, the residual
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

/// Variant (a) option: the plane of the intersection circle of s_f and s_g (normal
/// m = a_g b_f − a_f b_g) should contain the reference normal n_e at the edge, i.e. the edge
/// circle is orthogonal to the reference: residual ⟨m, n_e⟩ / ℓ_e with ℓ_e = |m| at the
/// initial state (a fixed scale, so the residual stays polynomial); n_e is refreshed in
/// [`Term::prepare`] from the vertices' closest reference points.
pub struct EdgeOrthogonality {
    name: String,
    /// (sphere f, sphere g, vertex p, vertex q) offsets.
    items: Vec<(usize, usize, usize, usize)>,
    scales: Vec<f64>,
    normals: Vec<DVec3>,
}

impl EdgeOrthogonality {
    /// `normals`: initial reference normal per edge; `x`: point for the scales.
    pub fn new(items: Vec<(usize, usize, usize, usize)>, normals: Vec<DVec3>, x: &[f64]) -> Self {
        let scales = items
            .iter()
            .map(|&(f, g, _, _)| {
                let m = x[g] * v3(x, f + 1) - x[f] * v3(x, g + 1);
                let l = m.length();
                if l > 1e-12 {
                    1.0 / l
                } else {
                    0.0
                }
            })
            .collect();
        Self { name: "edge_orthogonality".into(), items, scales, normals }
    }

    /// Sets the per-edge reference normals.
    pub fn set_normals(&mut self, normals: Vec<DVec3>) {
        self.normals = normals;
    }
}

impl Term for EdgeOrthogonality {
    fn name(&self) -> &str {
        &self.name
    }
    fn residual_count(&self) -> usize {
        self.items.len()
    }
    fn eval(&self, x: &[f64], r: &mut [f64], jac: &mut JacobianSink) {
        for (k, &(f, g, _, _)) in self.items.iter().enumerate() {
            let (af, bf) = (x[f], v3(x, f + 1));
            let (ag, bg) = (x[g], v3(x, g + 1));
            let n = self.normals[k];
            let s = self.scales[k];
            let m = ag * bf - af * bg;
            r[k] = s * m.dot(n);
            jac.add(k, f, -s * bg.dot(n));
            jac.add_block(k, f + 1, &[s * ag * n.x, s * ag * n.y, s * ag * n.z]);
            jac.add(k, g, s * bf.dot(n));
            jac.add_block(k, g + 1, &[-s * af * n.x, -s * af * n.y, -s * af * n.z]);
        }
    }
}

/// Handles of the terms of [`build_problem`].
#[derive(Clone, Debug)]
pub struct StAdaptedTerms {
    pub sphere: TermId,
    pub unit: TermId,
    pub angle: TermId,
    pub tangent_distance: TermId,
    pub point_distance: TermId,
    pub face_distance: TermId,
    pub fairness: TermId,
    pub edge_orthogonality: Option<TermId>,
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

/// Offset of face f's sphere block.
pub fn sphere_offset(f: usize) -> usize {
    5 * f
}

/// Offset of vertex v's block in a problem with `faces` faces.
pub fn vertex_offset(faces: usize, v: usize) -> usize {
    5 * faces + 3 * v
}

/// The variable vector: face spheres then vertices.
pub fn pack(vertices: &[DVec3], spheres: &[Sphere]) -> Vec<f64> {
    let mut x = Vec::with_capacity(5 * spheres.len() + 3 * vertices.len());
    for s in spheres {
        x.extend_from_slice(&s.to_array());
    }
    for v in vertices {
        x.extend_from_slice(&v.to_array());
    }
    x
}

/// Inverse of [`pack`].
pub fn unpack(x: &[f64], faces: usize, vertices: usize) -> (Vec<DVec3>, Vec<Sphere>) {
    let spheres = (0..faces)
        .map(|f| {
            let o = sphere_offset(f);
            Sphere::from_array([x[o], x[o + 1], x[o + 2], x[o + 3], x[o + 4]])
        })
        .collect();
    let verts = (0..vertices).map(|v| v3(x, vertex_offset(faces, v))).collect();
    (verts, spheres)
}

/// The optimization problem over `mesh` (faces' spheres and vertices, see [`pack`]) against the
/// reference, both in the same coordinates; `topology` is the mesh's. `x` is the starting point
/// (for the initial face orientations and the scales of the edge-orthogonality term).
pub fn build_problem<'a>(
    mesh: &TriMesh,
    topology: &Topology,
    reference: &'a Reference,
    weights: &StAdaptedWeights,
    x: &[f64],
) -> (Problem<'a>, StAdaptedTerms) {
    let boundary = boundary_vertices(topology);
    let interior: Vec<(u32, u32, usize, usize)> = topology
        .interior_edges()
        .map(|(e, f, g)| (topology.edges()[e][0], topology.edges()[e][1], f as usize, g as usize))
        .collect();
    let nf = mesh.face_count();
    let nv = mesh.vertex_count();
    let mut problem = Problem::new(5 * nf + 3 * nv);
    // Spheres and vertices are the blocks of the fill-reducing ordering.
    for f in 0..nf {
        problem.group_variables(sphere_offset(f)..sphere_offset(f) + 5);
    }
    for v in 0..nv {
        problem.group_variables(vertex_offset(nf, v)..vertex_offset(nf, v) + 3);
    }
    let pairs: Vec<(usize, usize)> = mesh
        .triangles
        .iter()
        .enumerate()
        .flat_map(|(f, t)| t.map(|v| (vertex_offset(nf, v as usize), sphere_offset(f))))
        .collect();
    let sphere = problem.add_term(PointOnSphere::new(pairs).with_name("sphere"), weights.sphere);
    let unit = problem.add_term(UnitLength::spheres((0..nf).map(sphere_offset).collect()).with_name("unit"), weights.unit);
    let edge_pairs = interior.iter().map(|&(_, _, f, g)| (sphere_offset(f), sphere_offset(g))).collect();
    let angle = problem.add_term(InversiveProduct::new(edge_pairs, 1.0).with_name("angle"), weights.angle);
    let offsets: Vec<usize> = (0..nv).map(|v| vertex_offset(nf, v)).collect();
    let scales = (0..nv).map(|v| if boundary[v] { BOUNDARY_POINT_FACTOR } else { 1.0 }).collect();
    let tangent = ReferenceProximity::tangent(reference, offsets.clone());
    let mut point = ReferenceProximity::point(reference, offsets, scales);
    point.share_closest_with(&tangent);
    let tangent_distance = problem.add_term(tangent, weights.tangent_distance);
    let point_distance = problem.add_term(point, weights.point_distance);
    let face_items = (0..nf)
        .map(|f| (sphere_offset(f), mesh.triangles[f].iter().map(|&v| vertex_offset(nf, v as usize)).collect()))
        .collect();
    let face_distance = problem.add_term(FaceProximity::new(reference, face_items, x), weights.face_distance);
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
    let corners = mesh.triangles.iter().map(|t| t.map(|v| vertex_offset(nf, v as usize))).collect();
    let orientation =
        problem.add_term(Hinge::new(FaceOrientation::new(corners, x, MIN_AREA_FRACTION)).with_name("orientation"), weights.orientation);
    let edge_orthogonality = (weights.edge_orthogonality > 0.0).then(|| {
        let items: Vec<_> = interior
            .iter()
            .map(|&(a, b, f, g)| (sphere_offset(f), sphere_offset(g), vertex_offset(nf, a as usize), vertex_offset(nf, b as usize)))
            .collect();
        let en: Vec<DVec3> = interior
            .iter()
            .map(|&(_, _, f, g)| (mesh.face_area_vector(f).normalize_or_zero() + mesh.face_area_vector(g).normalize_or_zero()).normalize_or_zero())
            .collect();
        problem.add_term(EdgeOrthogonality::new(items, en, x), weights.edge_orthogonality)
    });
    (problem, StAdaptedTerms { sphere, unit, angle, tangent_distance, point_distance, face_distance, fairness, edge_orthogonality, orientation })
}
