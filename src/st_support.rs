//! ST meshes with support structure (paper Sec. 4, issue 3 §3).
//!
//! Input: a triangle mesh (the reference's own triangulation) and its curvature field.
//! 1. Ω is estimated ([`crate::absolute_sphere`]). When m0 lay on the positive side the working
//!    orientation is flipped: the output mesh has every triangle's winding reversed, so that its
//!    normals point away from m (the support structure is on the negative side).
//! 2. Each face sphere passes through its triangle's three vertices and is orthogonal to Ω
//!    ([`Sphere::through_points_orthogonal`]: the null vector of the 4 × 5 system, a plane where
//!    it must), oriented like the (working) face normal.
//! 3. Option `optimize_radius` (Fig. 16 right): the vertices and m (or the axis a) stay fixed and
//!    R² (or the plane offset d) is chosen to minimize the mean kink angle over the interior
//!    edges: a scan of R² = R̂² + w sinh(u), u ∈ [−8, 8] step 0.5 (w = mean |m − v_i|²; R̂² the
//!    mean-R² estimate, u = 0; for the plane d = d̂ + diag · sinh(u)), refined by golden-section
//!    search in the best cell. R² may end up ≤ 0. The result is never worse than R̂².
//! 4. Node axes: the line through v and the second common point v̄ of the spheres around v, from
//!    those spheres ([`star_axis`]), not assumed. Where a star does not determine it (fewer than 3
//!    faces, or nearly coaxal spheres: condition < [`STAR_AXIS_MIN_CONDITION`]) the axis is the
//!    line v m (or parallel to a) and does not count in `max_node_axis_offset`.
//! 5. Support elements: per edge the arc circle (interior edges: the intersection circle of the
//!    two face spheres; boundary edges: the [`BoundaryArcRule`] plane through the edge and m, or
//!    parallel to a), and the annulus sector between the node axes with the given depth
//!    ([`SupportElement`]).
//! 6. The second envelope: the mesh inverted in Ω (same triangles). Given for R² > 0 (Fig. 10),
//!    also for R² < 0 (anti-inversion: the spheres pass through the anti-inverted vertices too)
//!    and for a plane Ω (reflection); None for R² = 0 (it degenerates to m).
//!
//! Timings: the library never reads a clock itself (std's `Instant` panics on wasm32). The caller
//! passes `params.clock`, a plain `fn() -> f64` in milliseconds (e.g. [`native_clock_ms`] or
//! `performance.now()` in the worker); without it the timings are 0.

// Negated float comparisons are deliberate: they also reject NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::absolute_sphere::{estimate_absolute_sphere, AbsoluteSphereEstimate, AbsoluteSphereParams};
use crate::curvature::{jet_fit, CurvatureField, JetParams};
use crate::mesh::{Topology, TriMesh};
use crate::sphere::{star_axis, Sphere, STAR_AXIS_MIN_CONDITION};
use crate::sphere_mesh::{AbsoluteSphere, BoundaryArcRule, Circle, SphereMesh, SupportElement, SupportStructure};

/// A millisecond clock supplied by the caller (see the module documentation). It never affects
/// results: all clocks compare equal and it is not serialized.
#[derive(Clone, Copy, Default)]
pub struct Clock(pub Option<fn() -> f64>);

impl std::fmt::Debug for Clock {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(if self.0.is_some() { "Clock(Some)" } else { "Clock(None)" })
    }
}

impl PartialEq for Clock {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl Clock {
    fn now(&self) -> f64 {
        self.0.map_or(0.0, |f| f())
    }
}

/// Milliseconds since the first call, from `std::time::Instant` (native only).
#[cfg(not(target_arch = "wasm32"))]
pub fn native_clock_ms() -> f64 {
    use std::sync::OnceLock;
    use std::time::Instant;
    static START: OnceLock<Instant> = OnceLock::new();
    START.get_or_init(Instant::now).elapsed().as_secs_f64() * 1e3
}

/// Parameters of [`st_support`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct StSupportParams {
    /// Choose R² (or d) minimizing the mean kink angle instead of the mean of the R_i².
    pub optimize_radius: bool,
    /// Depth of the support elements, relative to the bbox diagonal. Default 0.02.
    pub support_depth: f64,
    /// Length of the displayed node-axis segments, relative to the bbox diagonal. Default 0.1.
    pub axis_length: f64,
    pub jet: JetParams,
    pub absolute: AbsoluteSphereParams,
    #[serde(skip)]
    pub clock: Clock,
}

impl Default for StSupportParams {
    fn default() -> Self {
        Self {
            optimize_radius: false,
            support_depth: 0.02,
            axis_length: 0.1,
            jet: JetParams::default(),
            absolute: AbsoluteSphereParams::default(),
            clock: Clock::default(),
        }
    }
}

/// The report metrics of issue 3 §6 (lengths relative to the bbox diagonal, angles in degrees),
/// without `max_distance_to_reference` (computed from the tessellated panels by the exporter),
/// plus counts that qualify them.
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
    /// Faces whose sphere could not be made orthogonal to Ω (they keep their triangle's plane).
    pub degenerate_faces: usize,
    /// Edges without a support element (both face spheres planes, or no circle).
    pub edges_without_support: usize,
}

/// Everything [`st_support`] produces.
#[derive(Clone, Debug, PartialEq)]
pub struct StSupportResult {
    /// The mesh (winding reversed when `absolute.flipped`), its face spheres and the boundary arc
    /// rule (through m, or parallel to a).
    pub sphere_mesh: SphereMesh,
    /// Node axes (vertex, unit direction toward the support side) and the absolute depth.
    pub support: SupportStructure,
    pub support_elements: Vec<SupportElement>,
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
    pub diag: f64,
    pub metrics: StSupportMetrics,
    /// (stage, milliseconds) in execution order.
    pub timings_ms: Vec<(String, f64)>,
}

impl StSupportResult {
    /// The node axes as display segments [v, v + axis_length · direction] (toward the support
    /// side).
    pub fn node_axis_segments(&self) -> Vec<[DVec3; 2]> {
        self.support.node_axes.iter().map(|(p, d)| [*p, *p + self.axis_length * *d]).collect()
    }
}

const CANCELLED: &str = "cancelled";

/// Runs the whole method on a mesh: curvature (jet fit with `params.jet`), then
/// [`st_support_with_curvature`]. `progress(stage, done, total)` returning false cancels
/// (Err("cancelled")).
pub fn st_support(
    mesh: &TriMesh,
    params: &StSupportParams,
    progress: &mut dyn FnMut(&str, usize, usize) -> bool,
) -> Result<StSupportResult, String> {
    if mesh.face_count() == 0 || mesh.vertex_count() == 0 {
        return Err("the reference has no faces".into());
    }
    let t0 = params.clock.now();
    let topo = Topology::new(mesh);
    let field = jet_fit(mesh, &topo, &params.jet, &mut |d, t| progress("curvature", d, t)).ok_or(CANCELLED)?;
    let curvature_ms = params.clock.now() - t0;
    let mut result = st_support_with_curvature(mesh, &topo, &field, params, progress)?;
    result.timings_ms.insert(0, ("curvature".into(), curvature_ms));
    Ok(result)
}

/// Stage timer.
struct Timer<'a> {
    clock: &'a Clock,
    last: f64,
    out: Vec<(String, f64)>,
}

impl Timer<'_> {
    fn lap(&mut self, stage: &str) {
        let now = self.clock.now();
        self.out.push((stage.to_string(), now - self.last));
        self.last = now;
    }
}

/// The method with a precomputed topology and curvature field (see the module documentation).
pub fn st_support_with_curvature(
    mesh: &TriMesh,
    topo: &Topology,
    field: &CurvatureField,
    params: &StSupportParams,
    progress: &mut dyn FnMut(&str, usize, usize) -> bool,
) -> Result<StSupportResult, String> {
    let nv = mesh.vertex_count();
    let nf = mesh.face_count();
    if nf == 0 || nv == 0 {
        return Err("the reference has no faces".into());
    }
    if field.vertices.len() != nv || topo.vertex_count() != nv {
        return Err("the curvature field does not match the mesh".into());
    }
    if mesh.triangles.iter().flatten().any(|&v| v as usize >= nv) || mesh.positions.iter().any(|p| !p.is_finite()) {
        return Err("the reference has invalid vertex indices or coordinates".into());
    }
    let diag = mesh.bbox_diagonal();
    if !(diag > 0.0) || !diag.is_finite() {
        return Err("the reference has a degenerate bounding box".into());
    }
    let mut timer = Timer { clock: &params.clock, last: params.clock.now(), out: Vec::new() };
    let mut step = |stage: &str, done: usize, total: usize| {
        if progress(stage, done, total) {
            Ok(())
        } else {
            Err(CANCELLED.to_string())
        }
    };

    // --- Ω ---
    step("absolute_sphere", 0, 1)?;
    let absolute = estimate_absolute_sphere(mesh, field, &params.absolute)?;
    step("absolute_sphere", 1, 1)?;
    timer.lap("absolute_sphere");
    let triangles: Vec<[u32; 3]> = if absolute.flipped {
        mesh.triangles.iter().map(|t| [t[0], t[2], t[1]]).collect()
    } else {
        mesh.triangles.clone()
    };
    let work = TriMesh::new(mesh.positions.clone(), triangles);
    let normals = &absolute.normals;
    let edge_faces = edge_faces(&work, topo);
    let interior: Vec<[u32; 2]> = edge_faces.iter().filter(|f| f.len() == 2).map(|f| [f[0], f[1]]).collect();

    // --- Optimize R² (or d) ---
    let mut omega = absolute.omega;
    let mut optimized_parameter = None;
    let families: Option<Vec<[Sphere; 2]>> =
        params.optimize_radius.then(|| (0..nf).map(|f| Sphere::through_points_family(work.face_points(f))).collect());
    let mean_kink_estimate_deg;
    if let Some(families) = &families {
        step("optimize_radius", 0, 1)?;
        let (best, value, initial) = optimize_parameter(&work, &absolute, families, &interior, &mut step)?;
        mean_kink_estimate_deg = initial;
        if value < initial {
            omega = with_parameter(&absolute.omega, best);
            optimized_parameter = Some(best);
        } else {
            optimized_parameter = Some(parameter_of(&absolute.omega));
        }
        step("optimize_radius", 1, 1)?;
        timer.lap("optimize_radius");
    } else {
        mean_kink_estimate_deg = f64::NAN;
    }

    // --- Face spheres ---
    let mut face_spheres = Vec::with_capacity(nf);
    let mut degenerate_faces = 0;
    for f in 0..nf {
        if f % 1024 == 0 {
            step("face_spheres", f, nf)?;
        }
        let p = work.face_points(f);
        let s = match Sphere::through_points_orthogonal(p, &omega) {
            Some(s) if s.is_finite() => s,
            _ => {
                degenerate_faces += 1;
                Sphere::through_points_family(p)[0]
            }
        };
        face_spheres.push(s);
    }
    step("face_spheres", nf, nf)?;
    timer.lap("face_spheres");
    let kinks: Vec<f64> = interior
        .iter()
        .map(|[f, g]| face_spheres[*f as usize].kink_angle(&face_spheres[*g as usize]).to_degrees())
        .collect();
    let mean_kink_estimate_deg = if mean_kink_estimate_deg.is_nan() { mean(&kinks) } else { mean_kink_estimate_deg };

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
            step("node_axes", v, nv)?;
        }
        let p = work.positions[v];
        let toward = support_dir(p, normals[v]);
        star.clear();
        star.extend(topo.vertex_faces(v).iter().map(|&f| face_spheres[f as usize]));
        let mut dir = toward;
        if let Some(axis) = star_axis(&star, p).filter(|a| a.condition >= STAR_AXIS_MIN_CONDITION) {
            dir = if axis.direction.dot(toward) < 0.0 { -axis.direction } else { axis.direction };
            second_points[v] = axis.second_point;
            axis_from_spheres[v] = true;
        }
        node_axes.push((p, dir));
    }
    step("node_axes", nv, nv)?;
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
            step("support_elements", e, topo.edges().len())?;
        }
        let faces = &edge_faces[e];
        let (u, w) = (work.positions[edge[0] as usize], work.positions[edge[1] as usize]);
        let circle = faces.first().and_then(|&f1| {
            let s2 = (faces.len() == 2).then(|| &face_spheres[faces[1] as usize]);
            edge_circle(&face_spheres[f1 as usize], s2, u, w, &rule)
        });
        let element = circle.and_then(|c| {
            support_element(*edge, c, [u, w], [node_axes[edge[0] as usize].1, node_axes[edge[1] as usize].1], depth)
        });
        match element {
            Some(el) => support_elements.push(el),
            None => edges_without_support += 1,
        }
    }
    step("support_elements", topo.edges().len(), topo.edges().len())?;
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
    step("metrics", 0, 1)?;
    let mut metrics = StSupportMetrics {
        degenerate_faces,
        edges_without_support,
        interior_edges: interior.len(),
        ..Default::default()
    };
    for (f, s) in face_spheres.iter().enumerate() {
        for p in work.face_points(f) {
            metrics.max_vertex_sphere_residual = metrics.max_vertex_sphere_residual.max(s.distance(p) / diag);
        }
        let defect = omega.orthogonality_defect(s);
        match omega {
            AbsoluteSphere::Sphere { .. } => {
                let rel = if s.a.abs() > 1e-300 { defect / (diag * diag) } else { defect / diag };
                metrics.max_orthogonality_residual = metrics.max_orthogonality_residual.max(rel);
            }
            AbsoluteSphere::Plane { .. } => {
                metrics.max_center_plane_residual = metrics.max_center_plane_residual.max(defect / diag);
            }
        }
    }
    let mut angle_sum = 0.0;
    for v in 0..nv {
        let (p, d) = node_axes[v];
        let a = d.cross(normals[v]).length().atan2(d.dot(normals[v]).abs()).to_degrees();
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
    step("metrics", 1, 1)?;
    timer.lap("metrics");

    let sphere_mesh = SphereMesh { mesh: work, face_spheres, boundary_arcs: rule };
    Ok(StSupportResult {
        sphere_mesh,
        support: SupportStructure { node_axes, depth },
        support_elements,
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
        timings_ms: timer.out,
    })
}

fn mean(v: &[f64]) -> f64 {
    if v.is_empty() {
        0.0
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}

/// The faces of each edge of `topo.edges()`.
fn edge_faces(mesh: &TriMesh, topo: &Topology) -> Vec<Vec<u32>> {
    let edges = topo.edges();
    let mut out = vec![Vec::new(); edges.len()];
    for (f, t) in mesh.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let key = [a.min(b), a.max(b)];
            if let Ok(e) = edges.binary_search(&key) {
                out[e].push(f as u32);
            }
        }
    }
    out
}

/// R² of a sphere Ω, d of a plane.
fn parameter_of(omega: &AbsoluteSphere) -> f64 {
    match *omega {
        AbsoluteSphere::Sphere { r2, .. } => r2,
        AbsoluteSphere::Plane { d, .. } => d,
    }
}

fn with_parameter(omega: &AbsoluteSphere, x: f64) -> AbsoluteSphere {
    match *omega {
        AbsoluteSphere::Sphere { center, .. } => AbsoluteSphere::Sphere { center, r2: x },
        AbsoluteSphere::Plane { axis, .. } => AbsoluteSphere::Plane { axis, d: x },
    }
}

/// Mean kink angle (deg) over `interior` for Ω, from the precomputed pencils (world frame).
fn mean_kink_for(families: &[[Sphere; 2]], interior: &[[u32; 2]], omega: &AbsoluteSphere) -> f64 {
    let o = omega.coefficients();
    let spheres: Vec<Sphere> = families
        .iter()
        .map(|[s0, s1]| {
            let (alpha, beta) = (s1.inversive_product(&o), s0.inversive_product(&o));
            let h = alpha.hypot(beta);
            if !(h > 0.0) {
                return *s0;
            }
            let sign = if alpha < 0.0 { -1.0 } else { 1.0 };
            Sphere::combine(s0, sign * alpha / h, s1, -sign * beta / h)
        })
        .collect();
    mean(
        &interior
            .iter()
            .map(|[f, g]| spheres[*f as usize].kink_angle(&spheres[*g as usize]).to_degrees())
            .collect::<Vec<_>>(),
    )
}

/// Scan + golden section of the mean kink angle over R² = R̂² + w sinh(u) (or d = d̂ + diag sinh u).
/// Returns (best parameter, its mean kink, the mean kink at the estimate).
fn optimize_parameter(
    mesh: &TriMesh,
    absolute: &AbsoluteSphereEstimate,
    families: &[[Sphere; 2]],
    interior: &[[u32; 2]],
    step: &mut dyn FnMut(&str, usize, usize) -> Result<(), String>,
) -> Result<(f64, f64, f64), String> {
    let base = absolute.omega;
    let x0 = parameter_of(&base);
    let w = match base {
        AbsoluteSphere::Sphere { center, .. } => {
            mesh.positions.iter().map(|p| (*p - center).length_squared()).sum::<f64>() / mesh.vertex_count() as f64
        }
        AbsoluteSphere::Plane { .. } => mesh.bbox_diagonal(),
    };
    let w = if w > 0.0 && w.is_finite() { w } else { 1.0 };
    let x_of = |u: f64| x0 + w * u.sinh();
    let f = |u: f64| mean_kink_for(families, interior, &with_parameter(&base, x_of(u)));
    let (n, h) = (16i32, 0.5);
    let mut best = (0.0, f(0.0));
    let initial = best.1;
    for k in -n..=n {
        if k % 4 == 0 {
            step("optimize_radius", (k + n) as usize, (2 * n + 1) as usize)?;
        }
        let u = k as f64 * h;
        let v = if k == 0 { initial } else { f(u) };
        if v < best.1 {
            best = (u, v);
        }
    }
    // Golden section in [u* − h, u* + h].
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let (mut a, mut b) = (best.0 - h, best.0 + h);
    let (mut c, mut d) = (b - g * (b - a), a + g * (b - a));
    let (mut fc, mut fd) = (f(c), f(d));
    for _ in 0..40 {
        if fc < fd {
            b = d;
            d = c;
            fd = fc;
            c = b - g * (b - a);
            fc = f(c);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + g * (b - a);
            fd = f(d);
        }
        if b - a < 1e-7 {
            break;
        }
    }
    for (u, v) in [(c, fc), (d, fd)] {
        if v < best.1 {
            best = (u, v);
        }
    }
    Ok((x_of(best.0), best.1, initial))
}

/// The circle of the arc of edge (u, w) on face sphere `s1` (and `s2`, the other face's sphere, for
/// an interior edge). In theory the arc's plane is both the radical plane of s1 and s2 and the
/// [`BoundaryArcRule`] plane through u, w and m (or parallel to a), since it contains u, w, ū, w̄
/// and so both node axes. Numerically the radical plane is ill-conditioned when the two spheres
/// nearly coincide (its tilt errs by ≈ ε / sin φ, φ the kink angle: 1e-7 rad at φ ≈ 1e-9 rad,
/// which occurs after optimizing R), and the rule plane when m is nearly on the edge's line. So
/// the better conditioned of the two is used: the radical circle ([`Circle::intersection`]) when
/// sin φ ≥ sin ∠(w − u, m − u) (resp. ∠(w − u, a)), else the rule plane's cut of s1 (or s2 if s1
/// is a plane), its normal oriented like c₁ − c₂. Boundary edges: the rule plane. None when no
/// real circle results (e.g. both spheres planes).
pub fn edge_circle(s1: &Sphere, s2: Option<&Sphere>, u: DVec3, w: DVec3, rule: &BoundaryArcRule) -> Option<Circle> {
    let e = w - u;
    let (n, q_plane) = match *rule {
        BoundaryArcRule::Through(m) => {
            let n = e.cross(m - u);
            (n, n.length() / (e.length() * (m - u).length()))
        }
        BoundaryArcRule::Parallel(a) => {
            let n = e.cross(a);
            (n, n.length() / (e.length() * a.length()))
        }
    };
    let q_plane = if q_plane.is_finite() { q_plane } else { 0.0 };
    let radical = |s2: &Sphere| Circle::intersection(s1, s2);
    if let Some(s2) = s2 {
        if s1.kink_angle(s2).sin() >= q_plane {
            if let Some(c) = radical(s2) {
                return Some(c);
            }
        }
    }
    let cut = |s: &Sphere| Circle::plane_cut(s, u, n);
    let plane_circle = if s1.a != 0.0 { cut(s1) } else { s2.and_then(cut) };
    match plane_circle {
        Some(mut c) => {
            if let (Some(c1), Some(c2)) = (s1.center(), s2.and_then(|s| s.center())) {
                if c.normal.dot(c1 - c2) < 0.0 {
                    c.normal = -c.normal;
                }
            }
            Some(c)
        }
        None => s2.and_then(radical),
    }
}

/// The circle through three points (None when collinear).
fn circle_through(a: DVec3, b: DVec3, c: DVec3) -> Option<Circle> {
    let (ab, ac) = (b - a, c - a);
    let n = ab.cross(ac);
    let n2 = n.length_squared();
    if !(n2 > 1e-30 * ab.length_squared() * ac.length_squared()) {
        return None;
    }
    let center = a + (ab.length_squared() * ac.cross(n) + ac.length_squared() * n.cross(ab)) / (2.0 * n2);
    Some(Circle { center, normal: n / n2.sqrt(), radius: (a - center).length() })
}

/// The annulus sector of an edge: outer arc on `circle`, inner arc on the concentric circle of
/// radius ρ ∓ depth (toward the side the node axes point to), corners where the node axes (projected
/// into the plane) meet it. Falls back to the corners v + depth·d and the circle through them and
/// the offset arc midpoint when an axis does not reach the concentric circle.
fn support_element(
    edge: [u32; 2],
    circle: Circle,
    p: [DVec3; 2],
    dirs: [DVec3; 2],
    depth: f64,
) -> Option<SupportElement> {
    let n = circle.normal;
    let d: [DVec3; 2] = [0, 1].map(|k| (dirs[k] - dirs[k].dot(n) * n).try_normalize().unwrap_or(dirs[k]));
    let proj: [f64; 2] = [0, 1].map(|k| (p[k] - circle.center).dot(d[k]));
    let shrink = proj[0] + proj[1] < 0.0;
    let rho = circle.radius;
    let inner_r = if shrink { rho - depth } else { rho + depth };
    // |p − C + t d|² = ρ'², |p − C| = ρ: t² + 2 t q + (ρ² − ρ'²) = 0; the smallest t > 0.
    let hit = |k: usize| -> Option<DVec3> {
        let q = proj[k];
        let c0 = (rho - inner_r) * (rho + inner_r);
        let disc = q * q - c0;
        if !(inner_r > 0.0) || disc < 0.0 {
            return None;
        }
        let s = disc.sqrt();
        let t = [-q - s, -q + s].into_iter().filter(|t| *t > 0.0).fold(f64::INFINITY, f64::min);
        t.is_finite().then(|| p[k] + t * d[k])
    };
    let (inner, corners) = match (hit(0), hit(1)) {
        (Some(a), Some(b)) => (Circle { center: circle.center, normal: n, radius: inner_r }, [p[0], p[1], b, a]),
        _ => {
            let (a, b) = (p[0] + depth * d[0], p[1] + depth * d[1]);
            let mid_dir = (0.5 * (p[0] + p[1]) - circle.center).try_normalize()?;
            let mid = circle.center + rho * mid_dir + depth * (d[0] + d[1]).try_normalize()?;
            (circle_through(a, b, mid)?, [p[0], p[1], b, a])
        }
    };
    corners.iter().all(|c| c.is_finite()).then_some(SupportElement { edge, circle, inner_circle: inner, corners })
}
