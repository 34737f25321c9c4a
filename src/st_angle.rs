//! Angle-minimizing ST meshes with adapted face size (paper Sec. 3 end, Sec. 5.2; issue 4 §4).
//!
//! Pipeline ([`st_angle`]): jet fit of the reference → refusal when the central spheres are
//! unusable (H ≈ 0, minimal surfaces) → sizing field (influence zones of the central spheres, or
//! a uniform field for a face count) → pliant remeshing → jet fit of the remeshed mesh (face
//! central spheres) → initialization → staged optimization with [`crate::solver`] → exact
//! re-fit of every face sphere through its three vertices → metrics.
//!
//! **Initialization.** Every face sphere is the member of the pencil through its three vertices
//! ([`Sphere::through_points_family`], orthonormal basis s₀ (plane), s₁) closest to the face's
//! central sphere C (the normalized mean of its vertices' central spheres): maximizing ⟨s, C⟩
//! over cos θ s₀ + sin θ s₁ gives θ = atan2(⟨s₁, C⟩, ⟨s₀, C⟩). It is oriented like the face
//! (cos θ ≥ 0; else negated).
//!
//! **Optimization** (in a frame centred at the reference's bounding box and scaled by its
//! diagonal, so weights are dimensionless). Variables: the face spheres (5-blocks (a, b, c),
//! first) and the vertices (3-blocks, after). Terms ([`build_problem`]):
//! - `sphere`: ψ_f(v) for the three corners of every face (E_sphere);
//! - `unit`: bᵀb − 4ac − 1 (E_unit);
//! - `angle`: ⟨s_f, s_g⟩ − 1 for every interior edge (exact bilinear Jacobian; ⟨s_f, s_g⟩ is the
//!   cosine of the kink angle for spheres oriented alike);
//! - `tangent_distance`: n_v·(v − q_v), q_v the closest reference point, n_v the reference normal
//!   there (barycentric vertex normals), updated in [`Term::prepare`] (vertices glide, Sec. 5.2);
//! - `point_distance`: v − q_v (small weight; ×[`BOUNDARY_POINT_FACTOR`] on boundary vertices so
//!   the boundary does not slide off);
//! - `face_distance`: ψ_f(r_f) with r_f the reference point closest to face f's centroid
//!   ([`FaceProximity`], same weight schedule as the proximity terms): keeps the panels, not
//!   only the vertices, near the reference;
//! - `fairness`: uniform Laplacian v − mean(neighbours) at interior vertices (small weight);
//! - `edge_orthogonality` (variant (a) option, off by default): for every interior edge, the
//!   circle's plane contains the reference normal at the edge midpoint, written as
//!   ⟨a_g b_f − a_f b_g, n_e⟩ / |…| ≈ 0 — see [`EdgeOrthogonality`].
//!
//! The stages ([`StAngleStage`]) scale the proximity weights (larger first, then relaxed); a last
//! stage with E_sphere dominating is followed by the exact projection: each face sphere is
//! replaced by the member of its vertices' pencil closest to the optimized sphere, so the
//! vertex–sphere residual is at rounding level.
//!
//! **Variant (b)** (Fig. 12 bottom): the same spheres, but each interior edge arc is cut from
//! each face sphere by the *bisecting plane* of the two face planes (the plane through the edge
//! containing n_f + n_g). Both cut curves pass through the edge's vertices but differ in between.
//! **Gap measure**: for 33 points x₀ = p + t (q − p), t ∈ [0, 1], on the chord, the line
//! x₀ + h w in the bisecting plane (w ⟂ edge) meets each sphere at h_f, h_g (root nearest 0);
//! the gap is max |h_f − h_g| over the samples and edges (relative to the diagonal). The panels
//! and exports of variant (b) cut each sphere the same way
//! ([`crate::panels::EdgeArcs::BisectingPlanes`]); `panels::arc_gaps` measures the same gap on
//! the panels' own arcs.
//!
//! **Boundary arcs**: [`BoundaryArcRule::Parallel`]`(0)`: with a zero direction `build_panels`
//! falls back to the plane through the edge and the sphere normal at its start, i.e. the plane
//! through the edge and the face sphere's centre (a great-circle arc; straight for planes).

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::curvature::{jet_fit, CurvatureField, JetParams, PLANAR_TOLERANCE};
use crate::export::closest::{ClosestHit, TriangleBvh};
use std::cell::RefCell;
use std::rc::Rc;
use crate::mesh::{Topology, TriMesh};
use crate::panels::{build_panels_with, EdgeArcs};
use crate::remesh::{pliant_remesh, RemeshParams, SizingBounds, SizingField, DEFAULT_EPSILON};
use crate::solver::{
    InversiveProduct, IterationReport, JacobianSink, Linear, PhaseTimes, PointOnSphere, Problem, SolveReport, Solver,
    Hinge, SolverOptions, Term, TermId, TermStats, Termination, UnitLength,
};
use crate::sphere::Sphere;
use crate::sphere_mesh::{BoundaryArcRule, SphereMesh};

/// Panel tessellation chord error for the distance metric, relative to the diagonal.
pub const CHORD_TOLERANCE: f64 = 1e-4;
/// Boundary vertices get this factor on their point-distance residuals.
pub const BOUNDARY_POINT_FACTOR: f64 = 10.0;
/// Gap samples per edge (variant (b)).
pub const GAP_SAMPLES: usize = 33;

/// Edge variant (Fig. 12).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum StVariant {
    /// Edges are the intersection circles of adjacent spheres.
    #[default]
    A,
    /// Spheres cut by the bisecting face planes (small gaps, reported).
    B,
}

impl StVariant {
    /// The panel edges of the variant.
    pub fn edge_arcs(self) -> EdgeArcs {
        match self {
            StVariant::A => EdgeArcs::Intersection,
            StVariant::B => EdgeArcs::BisectingPlanes,
        }
    }
}

/// How the reference is remeshed first.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum StSizing {
    /// Influence zones of the central spheres, ε relative to the bbox diagonal.
    Adaptive { epsilon: f64 },
    /// Uniform field for about this many faces.
    UniformFaces(usize),
    /// Use the reference triangulation as is (no remeshing).
    None,
}

/// Term weights (frame scaled to diagonal 1).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct StAngleWeights {
    pub sphere: f64,
    pub unit: f64,
    pub angle: f64,
    pub tangent_distance: f64,
    pub point_distance: f64,
    /// Face sphere through the reference point closest to the face centroid (limits bulging).
    pub face_distance: f64,
    pub fairness: f64,
    /// Variant (a) option: edge circles orthogonal to the reference; 0 = off.
    pub edge_orthogonality: f64,
    /// Barrier against folded faces ([`FaceOrientation`] under a hinge).
    pub orientation: f64,
}

impl Default for StAngleWeights {
    fn default() -> Self {
        Self {
            sphere: 1000.0,
            unit: 1000.0,
            angle: 1.0,
            tangent_distance: 100.0,
            point_distance: 10.0,
            face_distance: 100.0,
            fairness: 1.0,
            edge_orthogonality: 0.0,
            orientation: 1000.0,
        }
    }
}

/// One optimization stage: proximity weights × `proximity_scale`, sphere/unit weights ×
/// `sphere_scale`, at most `iterations` solver iterations.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StAngleStage {
    pub name: String,
    pub proximity_scale: f64,
    pub sphere_scale: f64,
    pub iterations: usize,
}

/// Parameters of [`st_angle`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct StAngleParams {
    pub sizing: StSizing,
    pub variant: StVariant,
    pub remesh: RemeshParams,
    pub jet: JetParams,
    pub weights: StAngleWeights,
    pub stages: Vec<StAngleStage>,
    /// Refuse when fewer than this fraction of reference vertices have a usable central sphere.
    pub min_usable_fraction: f64,
    /// A vertex is usable when |H| ≥ this × (|k₁| + |k₂|)/2 (and not planar).
    pub min_curvature_ratio: f64,
    /// Initial LM regularization ε of the first stage; later stages continue from the last ε.
    pub initial_epsilon: f64,
    /// Hard-fix the boundary vertices of the remeshed mesh (they lie on the reference boundary).
    pub fix_boundary: bool,
    /// Hard-fix the vertices of remeshed edges whose faces meet at more than
    /// `remesh.feature_angle_deg` (feature curves kept by the remesher).
    pub fix_features: bool,
}

impl StAngleParams {
    /// Default stages with the given iteration counts per stage (proximity, angle, relax, close).
    pub fn stages_with(iterations: [usize; 4]) -> Vec<StAngleStage> {
        let mk = |name: &str, p: f64, s: f64, it: usize| StAngleStage {
            name: name.into(),
            proximity_scale: p,
            sphere_scale: s,
            iterations: it,
        };
        vec![
            mk("proximity", 10.0, 1.0, iterations[0]),
            mk("angle", 1.0, 1.0, iterations[1]),
            mk("relax", 0.5, 1.0, iterations[2]),
            mk("close", 0.5, 1000.0, iterations[3]),
        ]
    }
}

impl Default for StAngleParams {
    fn default() -> Self {
        Self {
            sizing: StSizing::Adaptive { epsilon: DEFAULT_EPSILON },
            variant: StVariant::A,
            remesh: RemeshParams::default(),
            jet: JetParams::default(),
            weights: StAngleWeights::default(),
            stages: Self::stages_with([5, 15, 15, 10]),
            min_usable_fraction: 0.5,
            min_curvature_ratio: 0.1,
            initial_epsilon: 0.1,
            fix_boundary: true,
            fix_features: true,
        }
    }
}

/// Progress events. Returning false from the hook cancels (Err("cancelled")).
pub enum StAngleEvent<'a> {
    /// A pipeline stage starts ("jet_fit", "remesh", "init", "optimize", "metrics").
    Stage(&'a str),
    /// Progress within a long stage ("jet_fit", "sizing", "remesh").
    Progress { stage: &'a str, done: usize, total: usize },
    /// The sizing field g at the reference vertices (absolute lengths), before remeshing.
    Sizing { values: &'a [f64] },
    /// The triangulation after remeshing.
    Remeshed { mesh: &'a TriMesh },
    /// The face spheres from the central spheres, before optimization.
    Initialized { sphere_mesh: &'a SphereMesh },
    /// After every solver iteration.
    Iteration {
        stage: &'a str,
        /// Global iteration counter over all stages.
        iteration: usize,
        energy: f64,
        terms: &'a [TermStats],
        ms: Option<f64>,
        /// Current vertices and face spheres (model coordinates) for a snapshot.
        vertices: &'a [DVec3],
        spheres: &'a [Sphere],
    },
}

/// Quality of an ST mesh (lengths relative to the reference diagonal).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StAngleMetrics {
    /// max over faces and corners of | |v − c| − r |, relative.
    pub max_vertex_sphere_residual: f64,
    /// Kink angles over interior edges (degrees).
    pub mean_kink_angle_deg: f64,
    pub max_kink_angle_deg: f64,
    /// Sampled over the panels (export::max_distance_to_reference), relative.
    pub max_distance_to_reference: f64,
    /// Max vertex distance to the reference, relative.
    pub max_vertex_distance_to_reference: f64,
    /// Variant (b): largest gap between adjacent cut curves (see module docs), relative.
    pub max_gap: Option<f64>,
    pub faces: usize,
    pub interior_edges: usize,
    /// Faces whose normal points against the reference normal at the closest point of their
    /// centroid (should be 0).
    pub flipped_faces: usize,
    /// Variant (b): the gap of `max_gap` divided by its edge's length.
    pub max_gap_over_edge_length: Option<f64>,
}

/// Output of [`st_angle`].
#[derive(Clone, Debug)]
pub struct StAngleResult {
    pub sphere_mesh: SphereMesh,
    pub initial_sphere_mesh: SphereMesh,
    pub remeshed: TriMesh,
    pub initial_metrics: StAngleMetrics,
    pub metrics: StAngleMetrics,
    /// Solver iterations over all stages.
    pub iterations: usize,
    /// Per-iteration times (ms) when a clock was given.
    pub iteration_ms: Vec<f64>,
    /// Median of `iteration_ms`.
    pub angle_iteration_median_ms: Option<f64>,
    /// Stage timings (ms) when a clock was given: jet_fit, sizing, remesh, init, optimize, metrics.
    pub timings_ms: Vec<(String, f64)>,
    pub diag: f64,
    pub variant: StVariant,
    /// Final term statistics.
    pub terms: Vec<TermStats>,
}

const CANCELLED: &str = "cancelled";

// ---------------------------------------------------------------------------------------------
// Terms

/// Closest reference points of the vertices, shared by the proximity terms so that each moved
/// vertex is looked up once per evaluation point (see [`ReferenceProximity::share_closest_with`]).
#[derive(Debug, Default)]
struct ClosestCache {
    /// Position each entry was computed for (NaN: never).
    pos: Vec<DVec3>,
    /// (closest point, interpolated unit normal).
    hits: Vec<(DVec3, DVec3)>,
}

/// Closest point on the reference, searched only within the distance to `previous` (a point on
/// the reference, so the closest one is at most that far): the same hit as an unbounded search,
/// visiting a small part of the BVH.
fn closest_near(bvh: &TriangleBvh, p: DVec3, previous: Option<DVec3>) -> Option<ClosestHit> {
    previous
        .and_then(|q| bvh.closest_point_within(p, p.distance(q) * (1.0 + 1e-9) + 1e-300))
        .or_else(|| bvh.closest_point(p))
}

/// Proximity to the reference (Sec. 5.2): per vertex either the tangent-plane distance
/// n·(v − q) (one residual) or the point distance v − q (three residuals, scaled per vertex),
/// with (q, n) the closest reference point and its normal, refreshed in [`Term::prepare`].
/// Vertices that did not move since the last lookup are not looked up again, and two terms
/// over the same vertices can share their lookups ([`Self::share_closest_with`]).
pub struct ReferenceProximity<'a> {
    name: String,
    bvh: &'a TriangleBvh,
    /// Reference vertex normals (unit) and triangles, to interpolate normals.
    normals: &'a [DVec3],
    triangles: &'a [[u32; 3]],
    /// Vertex block offsets.
    offsets: Vec<usize>,
    /// Per-vertex residual scale.
    scales: Vec<f64>,
    point: bool,
    closest: Vec<(DVec3, DVec3)>,
    cache: Rc<RefCell<ClosestCache>>,
}

impl<'a> ReferenceProximity<'a> {
    /// Tangent-plane distance n·(v − q).
    pub fn tangent(bvh: &'a TriangleBvh, reference: &'a TriMesh, normals: &'a [DVec3], offsets: Vec<usize>) -> Self {
        Self::new("tangent_distance", bvh, reference, normals, offsets, None, false)
    }

    /// Point distance v − q, residuals scaled by `scales` (per vertex).
    pub fn point(
        bvh: &'a TriangleBvh,
        reference: &'a TriMesh,
        normals: &'a [DVec3],
        offsets: Vec<usize>,
        scales: Vec<f64>,
    ) -> Self {
        Self::new("point_distance", bvh, reference, normals, offsets, Some(scales), true)
    }

    fn new(
        name: &str,
        bvh: &'a TriangleBvh,
        reference: &'a TriMesh,
        normals: &'a [DVec3],
        offsets: Vec<usize>,
        scales: Option<Vec<f64>>,
        point: bool,
    ) -> Self {
        let n = offsets.len();
        let cache = ClosestCache { pos: vec![DVec3::NAN; n], hits: vec![(DVec3::ZERO, DVec3::Z); n] };
        Self {
            name: name.into(),
            bvh,
            normals,
            triangles: &reference.triangles,
            scales: scales.unwrap_or_else(|| vec![1.0; n]),
            offsets,
            point,
            closest: vec![(DVec3::ZERO, DVec3::Z); n],
            cache: Rc::new(RefCell::new(cache)),
        }
    }

    /// Shares the closest-point lookups with `other` (same reference and vertex offsets): the
    /// first of the two to prepare at a point looks the moved vertices up, the other reuses them.
    pub fn share_closest_with(&mut self, other: &Self) {
        assert!(self.offsets == other.offsets && std::ptr::eq(self.bvh, other.bvh), "different vertices or reference");
        self.cache = other.cache.clone();
    }

    /// Closest points and normals currently used.
    pub fn closest(&self) -> &[(DVec3, DVec3)] {
        &self.closest
    }
}

impl Term for ReferenceProximity<'_> {
    fn name(&self) -> &str {
        &self.name
    }
    fn residual_count(&self) -> usize {
        if self.point {
            3 * self.offsets.len()
        } else {
            self.offsets.len()
        }
    }
    fn prepare(&mut self, x: &[f64]) {
        let mut cache = self.cache.borrow_mut();
        let cache = &mut *cache;
        for (k, &o) in self.offsets.iter().enumerate() {
            let v = DVec3::new(x[o], x[o + 1], x[o + 2]);
            if !v.is_finite() {
                continue;
            }
            if cache.pos[k] != v {
                let previous = cache.pos[k].is_finite().then_some(cache.hits[k].0);
                if let Some(hit) = closest_near(self.bvh, v, previous) {
                    let t = self.triangles[hit.triangle];
                    let w = hit.barycentric;
                    let n = (w[0] * self.normals[t[0] as usize]
                        + w[1] * self.normals[t[1] as usize]
                        + w[2] * self.normals[t[2] as usize])
                        .try_normalize()
                        .unwrap_or(cache.hits[k].1);
                    cache.hits[k] = (hit.point, n);
                    cache.pos[k] = v;
                }
            }
            if cache.pos[k] == v {
                self.closest[k] = cache.hits[k];
            }
        }
    }
    fn eval(&self, x: &[f64], r: &mut [f64], jac: &mut JacobianSink) {
        for (k, &o) in self.offsets.iter().enumerate() {
            let v = DVec3::new(x[o], x[o + 1], x[o + 2]);
            let (q, n) = self.closest[k];
            let s = self.scales[k];
            if self.point {
                let d = (v - q) * s;
                for i in 0..3 {
                    r[3 * k + i] = d[i];
                    jac.add(3 * k + i, o + i, s);
                }
            } else {
                r[k] = n.dot(v - q) * s;
                jac.add_block(k, o, &[n.x * s, n.y * s, n.z * s]);
            }
        }
    }
}

/// Face spheres near the reference: ψ_f(r_f), r_f the reference point closest to the centroid of
/// face f's current vertices (refreshed in [`Term::prepare`]; constant in the Jacobian). For a
/// normalized sphere ψ ≈ the signed distance of r_f to it, so this bounds the panels' bulge.
pub struct FaceProximity<'a> {
    name: String,
    bvh: &'a TriangleBvh,
    /// (sphere offset, three vertex offsets) per face.
    faces: Vec<(usize, [usize; 3])>,
    targets: Vec<DVec3>,
    /// Centroid each target was computed for (NaN: never).
    centroids: Vec<DVec3>,
}

impl<'a> FaceProximity<'a> {
    pub fn new(bvh: &'a TriangleBvh, faces: Vec<(usize, [usize; 3])>, x: &[f64]) -> Self {
        let n = faces.len();
        let mut t = Self {
            name: "face_distance".into(),
            bvh,
            targets: vec![DVec3::ZERO; n],
            centroids: vec![DVec3::NAN; n],
            faces,
        };
        t.prepare(x);
        t
    }
}

impl Term for FaceProximity<'_> {
    fn name(&self) -> &str {
        &self.name
    }
    fn residual_count(&self) -> usize {
        self.faces.len()
    }
    fn prepare(&mut self, x: &[f64]) {
        for (k, &(_, vs)) in self.faces.iter().enumerate() {
            let c = (v3(x, vs[0]) + v3(x, vs[1]) + v3(x, vs[2])) / 3.0;
            if !c.is_finite() || c == self.centroids[k] {
                continue;
            }
            let previous = self.centroids[k].is_finite().then_some(self.targets[k]);
            if let Some(hit) = closest_near(self.bvh, c, previous) {
                self.targets[k] = hit.point;
                self.centroids[k] = c;
            }
        }
    }
    fn eval(&self, x: &[f64], r: &mut [f64], jac: &mut JacobianSink) {
        for (k, &(so, _)) in self.faces.iter().enumerate() {
            let p = self.targets[k];
            let q = p.length_squared();
            r[k] = x[so] * q - v3(x, so + 1).dot(p) + x[so + 4];
            jac.add_block(k, so, &[q, -p.x, -p.y, -p.z, 1.0]);
        }
    }
}

/// Variant (a) option: the plane of the intersection circle of s_f and s_g (normal
/// m = a_g b_f − a_f b_g) should contain the reference normal n_e at the edge, i.e. the edge
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

fn v3(x: &[f64], o: usize) -> DVec3 {
    DVec3::new(x[o], x[o + 1], x[o + 2])
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

// ---------------------------------------------------------------------------------------------
// Problem

/// Handles of the terms of [`build_problem`].
#[derive(Clone, Debug)]
pub struct StAngleTerms {
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

/// Mesh connectivity used by the optimization.
#[derive(Clone, Debug, Default)]
pub struct FaceAdjacency {
    /// Interior edges: (v_lo, v_hi, face f, face g).
    pub interior: Vec<(u32, u32, usize, usize)>,
    pub boundary_vertex: Vec<bool>,
    pub neighbors: Vec<Vec<u32>>,
}

impl FaceAdjacency {
    pub fn new(mesh: &TriMesh) -> Self {
        let nv = mesh.vertex_count();
        let mut edges: Vec<(u32, u32, usize)> = Vec::with_capacity(3 * mesh.face_count());
        for (f, t) in mesh.triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                edges.push((a.min(b), a.max(b), f));
            }
        }
        edges.sort_unstable();
        let mut interior = Vec::new();
        let mut boundary_vertex = vec![false; nv];
        let mut neighbors = vec![Vec::new(); nv];
        let mut i = 0;
        while i < edges.len() {
            let mut j = i + 1;
            while j < edges.len() && edges[j].0 == edges[i].0 && edges[j].1 == edges[i].1 {
                j += 1;
            }
            let (a, b) = (edges[i].0, edges[i].1);
            neighbors[a as usize].push(b);
            neighbors[b as usize].push(a);
            if j - i == 2 {
                interior.push((a, b, edges[i].2, edges[i + 1].2));
            } else {
                boundary_vertex[a as usize] = true;
                boundary_vertex[b as usize] = true;
            }
            i = j;
        }
        Self { interior, boundary_vertex, neighbors }
    }
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
/// reference (`bvh` of it, its unit vertex `normals`), all in the same coordinates. `x` is the
/// starting point (for the scales of the edge-orthogonality term).
pub fn build_problem<'a>(
    mesh: &TriMesh,
    adjacency: &FaceAdjacency,
    reference: &'a TriMesh,
    bvh: &'a TriangleBvh,
    normals: &'a [DVec3],
    weights: &StAngleWeights,
    x: &[f64],
) -> (Problem<'a>, StAngleTerms) {
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
    let edge_pairs = adjacency.interior.iter().map(|&(_, _, f, g)| (sphere_offset(f), sphere_offset(g))).collect();
    let angle = problem.add_term(InversiveProduct::new(edge_pairs, 1.0).with_name("angle"), weights.angle);
    let offsets: Vec<usize> = (0..nv).map(|v| vertex_offset(nf, v)).collect();
    let scales = (0..nv).map(|v| if adjacency.boundary_vertex[v] { BOUNDARY_POINT_FACTOR } else { 1.0 }).collect();
    let tangent = ReferenceProximity::tangent(bvh, reference, normals, offsets.clone());
    let mut point = ReferenceProximity::point(bvh, reference, normals, offsets, scales);
    point.share_closest_with(&tangent);
    let tangent_distance = problem.add_term(tangent, weights.tangent_distance);
    let point_distance = problem.add_term(point, weights.point_distance);
    let face_items = (0..nf)
        .map(|f| (sphere_offset(f), mesh.triangles[f].map(|v| vertex_offset(nf, v as usize))))
        .collect();
    let face_distance = problem.add_term(FaceProximity::new(bvh, face_items, x), weights.face_distance);
    let mut lap = Linear::new().with_name("fairness");
    for v in 0..nv {
        let nb = &adjacency.neighbors[v];
        if adjacency.boundary_vertex[v] || nb.is_empty() {
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
        let items: Vec<_> = adjacency
            .interior
            .iter()
            .map(|&(a, b, f, g)| (sphere_offset(f), sphere_offset(g), vertex_offset(nf, a as usize), vertex_offset(nf, b as usize)))
            .collect();
        let en: Vec<DVec3> = adjacency
            .interior
            .iter()
            .map(|&(_, _, f, g)| (mesh.face_area_vector(f).normalize_or_zero() + mesh.face_area_vector(g).normalize_or_zero()).normalize_or_zero())
            .collect();
        problem.add_term(EdgeOrthogonality::new(items, en, x), weights.edge_orthogonality)
    });
    (problem, StAngleTerms { sphere, unit, angle, tangent_distance, point_distance, face_distance, fairness, edge_orthogonality, orientation })
}

// ---------------------------------------------------------------------------------------------
// Geometry helpers

/// The member of the pencil through `p` closest to `target` (max ⟨s, target⟩), oriented like the
/// triangle (component along the plane member ≥ 0).
pub fn closest_family_member(p: [DVec3; 3], target: &Sphere) -> Sphere {
    let [s0, s1] = Sphere::through_points_family(p);
    let theta = s1.inversive_product(target).atan2(s0.inversive_product(target));
    let (sn, cs) = theta.sin_cos();
    let s = Sphere::combine(&s0, cs, &s1, sn);
    if cs < 0.0 {
        s.flipped()
    } else {
        s
    }
}

/// Initial face spheres: closest pencil members to the mean of the vertices' central spheres.
pub fn initial_spheres(mesh: &TriMesh, vertex_spheres: &[Sphere]) -> Vec<Sphere> {
    (0..mesh.face_count())
        .map(|f| {
            let t = mesh.triangles[f];
            let mut c = [0.0; 5];
            for &v in &t {
                let a = vertex_spheres[v as usize].to_array();
                for i in 0..5 {
                    c[i] += a[i] / 3.0;
                }
            }
            let c = Sphere::from_array(c);
            let c = if c.discriminant() > 0.0 { c.normalized() } else { c };
            closest_family_member(mesh.face_points(f), &c)
        })
        .collect()
}

/// Replaces every sphere by the member of its vertices' pencil closest to it (max ⟨s, s_opt⟩,
/// exact incidence), keeping the optimized sphere's orientation.
pub fn project_spheres(mesh: &TriMesh, spheres: &[Sphere]) -> Vec<Sphere> {
    (0..mesh.face_count())
        .map(|f| {
            let [s0, s1] = Sphere::through_points_family(mesh.face_points(f));
            let target = &spheres[f];
            let theta = s1.inversive_product(target).atan2(s0.inversive_product(target));
            let (sn, cs) = theta.sin_cos();
            Sphere::combine(&s0, cs, &s1, sn)
        })
        .collect()
}

/// Signed offset h of the sphere along x₀ + h w (root of ψ nearest 0), None if no real root.
fn line_hit(s: &Sphere, x0: DVec3, w: DVec3) -> Option<f64> {
    let psi = s.eval(x0);
    let bq = (2.0 * s.a * x0 - s.b).dot(w);
    let disc = bq * bq - 4.0 * s.a * psi;
    if disc < 0.0 {
        return None;
    }
    let den = bq + bq.signum() * disc.sqrt();
    if den == 0.0 {
        return if psi == 0.0 { Some(0.0) } else { None };
    }
    Some(-2.0 * psi / den)
}

/// Variant (b) gap (absolute): see the module docs.
pub fn max_gap(mesh: &TriMesh, spheres: &[Sphere], adjacency: &FaceAdjacency) -> f64 {
    max_gap_with_ratio(mesh, spheres, adjacency).0
}

/// [`max_gap`] and the largest gap / edge length.
pub fn max_gap_with_ratio(mesh: &TriMesh, spheres: &[Sphere], adjacency: &FaceAdjacency) -> (f64, f64) {
    let mut worst = 0.0f64;
    let mut ratio = 0.0f64;
    for &(a, b, f, g) in &adjacency.interior {
        let (p, q) = (mesh.positions[a as usize], mesh.positions[b as usize]);
        let e = (q - p).normalize_or_zero();
        let nsum = mesh.face_area_vector(f).normalize_or_zero() + mesh.face_area_vector(g).normalize_or_zero();
        // Bisecting plane: through the edge, containing n_f + n_g; w is its in-plane direction ⟂ e.
        let w = (nsum - nsum.dot(e) * e).normalize_or_zero();
        if w == DVec3::ZERO {
            continue;
        }
        for k in 1..GAP_SAMPLES - 1 {
            let t = k as f64 / (GAP_SAMPLES - 1) as f64;
            let x0 = p + t * (q - p);
            if let (Some(hf), Some(hg)) = (line_hit(&spheres[f], x0, w), line_hit(&spheres[g], x0, w)) {
                worst = worst.max((hf - hg).abs());
                ratio = ratio.max((hf - hg).abs() / p.distance(q));
            }
        }
    }
    (worst, ratio)
}

/// Metrics of a sphere mesh against the reference (see [`StAngleMetrics`]).
pub fn metrics(sm: &SphereMesh, reference: &TriMesh, variant: StVariant) -> StAngleMetrics {
    let diag = reference.bbox_diagonal().max(f64::MIN_POSITIVE);
    let mesh = &sm.mesh;
    let adjacency = FaceAdjacency::new(mesh);
    let mut res = 0.0f64;
    for (f, t) in mesh.triangles.iter().enumerate() {
        for &v in t {
            res = res.max(sm.face_spheres[f].distance(mesh.positions[v as usize]));
        }
    }
    let kinks: Vec<f64> = adjacency
        .interior
        .iter()
        .map(|&(_, _, f, g)| sm.face_spheres[f].kink_angle(&sm.face_spheres[g]).to_degrees())
        .collect();
    let mean = if kinks.is_empty() { 0.0 } else { kinks.iter().sum::<f64>() / kinks.len() as f64 };
    let max = kinks.iter().copied().fold(0.0, f64::max);
    let panels = build_panels_with(sm, CHORD_TOLERANCE * diag, variant.edge_arcs());
    let dist = crate::export::max_distance_to_reference(&panels, reference);
    let bvh = TriangleBvh::new(reference);
    let vdist = mesh.positions.iter().map(|&p| bvh.distance(p)).fold(0.0, f64::max) / diag;
    let gap = (variant == StVariant::B).then(|| max_gap_with_ratio(mesh, &sm.face_spheres, &adjacency));
    let ref_normals = reference.vertex_normals();
    let flipped_faces = (0..mesh.face_count())
        .filter(|&f| {
            let c = mesh.face_points(f).iter().sum::<DVec3>() / 3.0;
            let Some(hit) = bvh.closest_point(c) else { return false };
            let t = reference.triangles[hit.triangle];
            let w = hit.barycentric;
            let n = w[0] * ref_normals[t[0] as usize] + w[1] * ref_normals[t[1] as usize] + w[2] * ref_normals[t[2] as usize];
            mesh.face_area_vector(f).dot(n) < 0.0
        })
        .count();
    StAngleMetrics {
        max_vertex_sphere_residual: res / diag,
        mean_kink_angle_deg: mean,
        max_kink_angle_deg: max,
        max_distance_to_reference: dist,
        max_vertex_distance_to_reference: vdist,
        max_gap: gap.map(|g| g.0 / diag),
        max_gap_over_edge_length: gap.map(|g| g.1),
        faces: mesh.face_count(),
        interior_edges: adjacency.interior.len(),
        flipped_faces,
    }
}

/// Whether the reference's central spheres are usable; Err with a clear message if not.
pub fn check_central_spheres(mesh: &TriMesh, field: &CurvatureField, params: &StAngleParams) -> Result<(), String> {
    let nv = mesh.vertex_count().min(field.vertices.len());
    if nv == 0 {
        return Err("the reference has no vertices".into());
    }
    let diag = mesh.bbox_diagonal();
    let usable = (0..nv)
        .filter(|&i| {
            let c = &field.vertices[i];
            let planar = field.planar.get(i).copied().unwrap_or(false) || c.mean.abs() * diag < PLANAR_TOLERANCE;
            let ratio_ok = c.mean.abs() >= params.min_curvature_ratio * 0.5 * (c.k1.abs() + c.k2.abs());
            !planar && ratio_ok && c.mean.is_finite() && c.mean != 0.0
        })
        .count();
    if usable == 0 || (usable as f64) < params.min_usable_fraction * nv as f64 {
        return Err(format!(
            "the reference has no usable central spheres: H ≈ 0 on {} of {nv} vertices (minimal surface?); \
             the angle-minimizing ST method initializes its face spheres from central spheres and its face size \
             from their influence zones",
            nv - usable
        ));
    }
    Ok(())
}

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
    /// Whether the hook cancelled.
    pub cancelled: bool,
    /// The last stage's report.
    pub last: Option<SolveReport>,
}

/// Runs the optimization stages of `params` on a problem from [`build_problem`] (weights set per
/// stage, ε carried from stage to stage), starting at `x` (updated). `hook(stage, report)` is
/// called after every iteration; returning false cancels.
pub fn run_stages(
    problem: &mut Problem,
    ids: &StAngleTerms,
    x: &mut [f64],
    params: &StAngleParams,
    solver: &mut Solver,
    hook: &mut dyn FnMut(&str, &IterationReport) -> bool,
) -> StageRun {
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
        problem.set_weight(ids.sphere, w.sphere * stage.sphere_scale);
        problem.set_weight(ids.unit, w.unit * stage.sphere_scale);
        solver.options.max_iterations = stage.iterations;
        solver.options.initial_epsilon = epsilon;
        let name = stage.name.as_str();
        let report = solver.solve(problem, x, |rep| hook(name, rep));
        run.iterations += report.iterations;
        run.iteration_ms.extend_from_slice(&report.iteration_ms);
        run.numeric_factorizations += report.numeric_factorizations;
        let p = &report.phase_ms;
        run.phase_ms.symbolic += p.symbolic;
        run.phase_ms.evaluate += p.evaluate;
        run.phase_ms.assemble += p.assemble;
        run.phase_ms.factorize_solve += p.factorize_solve;
        epsilon = report.epsilon.max(1e-6);
        let cancelled = report.termination == Termination::Cancelled;
        run.last = Some(report);
        if cancelled {
            run.cancelled = true;
            break;
        }
    }
    run
}

fn median(v: &[f64]) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    let mut s = v.to_vec();
    s.sort_by(|a, b| a.total_cmp(b));
    let n = s.len();
    Some(if n % 2 == 1 { s[n / 2] } else { 0.5 * (s[n / 2 - 1] + s[n / 2]) })
}

fn scaled(mesh: &TriMesh, t: DVec3, inv: f64) -> TriMesh {
    TriMesh::new(mesh.positions.iter().map(|&p| (p - t) * inv).collect(), mesh.triangles.clone())
}

/// The optimization in its normalized frame: the reference and the remeshed mesh moved by the
/// reference's bbox centre `t` and scaled to diagonal 1, with the reference's BVH and normals,
/// the initial point and the vertices `params` hard-fixes (boundary, feature curves).
pub struct OptimizationFrame {
    pub t: DVec3,
    pub diag: f64,
    pub reference: TriMesh,
    pub bvh: TriangleBvh,
    pub normals: Vec<DVec3>,
    pub mesh: TriMesh,
    pub adjacency: FaceAdjacency,
    /// The initial point ([`pack`]).
    pub x0: Vec<f64>,
    /// Hard-fixed vertices.
    pub fixed: Vec<usize>,
}

impl OptimizationFrame {
    /// `init`: one face sphere per face of `remeshed`, model coordinates.
    pub fn new(reference: &TriMesh, remeshed: &TriMesh, init: &[Sphere], params: &StAngleParams) -> Self {
        let diag = reference.bbox_diagonal();
        let (lo, hi) = reference.bbox();
        let t = 0.5 * (lo + hi);
        let nref = scaled(reference, t, 1.0 / diag);
        let bvh = TriangleBvh::new(&nref);
        let normals = nref.vertex_normals();
        let mesh = scaled(remeshed, t, 1.0 / diag);
        let adjacency = FaceAdjacency::new(&mesh);
        let spheres: Vec<Sphere> = init.iter().map(|s| s.in_frame(t, diag).normalized()).collect();
        let x0 = pack(&mesh.positions, &spheres);
        let nv = mesh.vertex_count();
        let mut fixed = vec![false; nv];
        if params.fix_boundary {
            for v in 0..nv {
                fixed[v] |= adjacency.boundary_vertex[v];
            }
        }
        if params.fix_features {
            let cos_max = params.remesh.feature_angle_deg.to_radians().cos();
            for &(a, b, f, g) in &adjacency.interior {
                let (nf, ng) = (mesh.face_area_vector(f).normalize_or_zero(), mesh.face_area_vector(g).normalize_or_zero());
                if nf.dot(ng) < cos_max {
                    fixed[a as usize] = true;
                    fixed[b as usize] = true;
                }
            }
        }
        let fixed = (0..nv).filter(|&v| fixed[v]).collect();
        Self { t, diag, reference: nref, bvh, normals, mesh, adjacency, x0, fixed }
    }

    /// [`build_problem`] at the initial point, with the fixed vertices fixed.
    pub fn problem(&self, weights: &StAngleWeights) -> (Problem<'_>, StAngleTerms) {
        let (mut problem, ids) =
            build_problem(&self.mesh, &self.adjacency, &self.reference, &self.bvh, &self.normals, weights, &self.x0);
        let nf = self.mesh.face_count();
        for &v in &self.fixed {
            let o = vertex_offset(nf, v);
            problem.fix_range(o..o + 3);
        }
        (problem, ids)
    }

    /// Vertices and face spheres of `x`, in model coordinates.
    pub fn to_model(&self, x: &[f64]) -> (Vec<DVec3>, Vec<Sphere>) {
        let (verts, sph) = unpack(x, self.mesh.face_count(), self.mesh.vertex_count());
        let verts = verts.iter().map(|&p| self.t + p * self.diag).collect();
        let sph = sph.iter().map(|s| s.from_frame(self.t, self.diag).normalized()).collect();
        (verts, sph)
    }
}

/// The angle-minimizing ST method end to end (see the module docs).
pub fn st_angle(
    reference: &TriMesh,
    params: &StAngleParams,
    clock: Option<fn() -> f64>,
    hook: &mut dyn FnMut(StAngleEvent) -> bool,
) -> Result<StAngleResult, String> {
    let now = || clock.map_or(0.0, |c| c());
    let mut timings: Vec<(String, f64)> = Vec::new();
    if reference.face_count() == 0 {
        return Err("the reference has no faces".into());
    }
    if reference.triangles.iter().flatten().any(|&v| v as usize >= reference.vertex_count())
        || reference.positions.iter().any(|p| !p.is_finite())
    {
        return Err("the reference has invalid vertex indices or coordinates".into());
    }
    let diag = reference.bbox_diagonal();
    if !(diag > 0.0) || !diag.is_finite() {
        return Err("the reference has a degenerate bounding box".into());
    }

    // Curvature of the reference and the refusal.
    if !hook(StAngleEvent::Stage("jet_fit")) {
        return Err(CANCELLED.into());
    }
    let t0 = now();
    let topo = Topology::new(reference);
    let mut cancelled = false;
    let field = jet_fit(reference, &topo, &params.jet, &mut |done, total| {
        cancelled = !hook(StAngleEvent::Progress { stage: "jet_fit", done, total });
        !cancelled
    });
    let field = match field {
        Some(f) => f,
        None if cancelled => return Err(CANCELLED.into()),
        None => return Err("the jet fit failed".into()),
    };
    check_central_spheres(reference, &field, params)?;
    timings.push(("jet_fit".into(), now() - t0));

    // Sizing and remeshing.
    if !hook(StAngleEvent::Stage("remesh")) {
        return Err(CANCELLED.into());
    }
    let t0 = now();
    let sizing = match params.sizing {
        StSizing::Adaptive { epsilon } => {
            let bounds = SizingBounds::for_mesh(reference, &topo);
            let sphere_of = |i: usize| field.central_spheres.get(i).copied().unwrap_or_else(|| Sphere::plane(reference.positions[i], DVec3::Z));
            let mut progress = |done, total| hook(StAngleEvent::Progress { stage: "sizing", done, total });
            let s = SizingField::from_sphere_fn(reference, &topo, &sphere_of, epsilon * diag, bounds, &mut progress);
            Some(s.ok_or(CANCELLED)?)
        }
        StSizing::UniformFaces(n) => Some(SizingField::uniform_for_face_count(reference, n)),
        StSizing::None => None,
    };
    timings.push(("sizing".into(), now() - t0));
    if let Some(s) = &sizing {
        if !hook(StAngleEvent::Sizing { values: s.values() }) {
            return Err(CANCELLED.into());
        }
    }
    let t0 = now();
    let remeshed = match &sizing {
        Some(s) => {
            let mut progress = |done, total| hook(StAngleEvent::Progress { stage: "remesh", done, total });
            pliant_remesh(reference, s, &params.remesh, &mut progress).ok_or(CANCELLED)?
        }
        None => reference.clone(),
    };
    timings.push(("remesh".into(), now() - t0));
    if remeshed.face_count() == 0 {
        return Err("remeshing produced no faces".into());
    }
    if !hook(StAngleEvent::Remeshed { mesh: &remeshed }) {
        return Err(CANCELLED.into());
    }

    // Central spheres of the remeshed mesh and the initialization.
    if !hook(StAngleEvent::Stage("init")) {
        return Err(CANCELLED.into());
    }
    let t0 = now();
    let rtopo = Topology::new(&remeshed);
    let rfield = jet_fit(&remeshed, &rtopo, &params.jet, &mut |_, _| true).ok_or("the jet fit of the remeshed mesh failed")?;
    let init = initial_spheres(&remeshed, &rfield.central_spheres);
    let rule = BoundaryArcRule::Parallel(DVec3::ZERO);
    let initial_sphere_mesh = SphereMesh { mesh: remeshed.clone(), face_spheres: init.clone(), boundary_arcs: rule };
    timings.push(("init".into(), now() - t0));
    if !hook(StAngleEvent::Initialized { sphere_mesh: &initial_sphere_mesh }) {
        return Err(CANCELLED.into());
    }

    // Optimization in the normalized frame.
    if !hook(StAngleEvent::Stage("optimize")) {
        return Err(CANCELLED.into());
    }
    let t0 = now();
    let frame = OptimizationFrame::new(reference, &remeshed, &init, params);
    let mut x = frame.x0.clone();
    let (mut problem, ids) = frame.problem(&params.weights);
    let mut solver = Solver::new(SolverOptions { clock, ..SolverOptions::default() });
    let mut iteration = 0usize;
    let run = run_stages(&mut problem, &ids, &mut x, params, &mut solver, &mut |name, rep| {
        iteration += 1;
        let (verts, sph) = frame.to_model(rep.x);
        let go = hook(StAngleEvent::Iteration {
            stage: name,
            iteration,
            energy: rep.energy,
            terms: rep.terms,
            ms: rep.ms,
            vertices: &verts,
            spheres: &sph,
        });
        if !go {
            cancelled = true;
        }
        go
    });
    if cancelled {
        return Err(CANCELLED.into());
    }
    let iteration_ms = run.iteration_ms;
    problem.prepare(&x);
    let terms = problem.term_stats(&x);
    let (verts, sph) = frame.to_model(&x);
    let mesh_out = TriMesh::new(verts, remeshed.triangles.clone());
    // Exact incidence: the pencil member closest to each optimized sphere.
    let face_spheres = project_spheres(&mesh_out, &sph);
    let sphere_mesh = SphereMesh { mesh: mesh_out, face_spheres, boundary_arcs: rule };
    timings.push(("optimize".into(), now() - t0));

    if !hook(StAngleEvent::Stage("metrics")) {
        return Err(CANCELLED.into());
    }
    let t0 = now();
    let initial_metrics = metrics(&initial_sphere_mesh, reference, params.variant);
    let final_metrics = metrics(&sphere_mesh, reference, params.variant);
    timings.push(("metrics".into(), now() - t0));
    let angle_iteration_median_ms = median(&iteration_ms);
    Ok(StAngleResult {
        sphere_mesh,
        initial_sphere_mesh,
        remeshed,
        initial_metrics,
        metrics: final_metrics,
        iterations: iteration,
        iteration_ms,
        angle_iteration_median_ms,
        timings_ms: if clock.is_some() { timings } else { Vec::new() },
        diag,
        variant: params.variant,
        terms,
    })
}
