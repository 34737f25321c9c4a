//! Panels: the spherical triangles of a [`SphereMesh`], bounded by circular arcs, tessellated for
//! display and export (issue 3, §4).
//!
//! # Arcs
//! **Variant (a)** ([`EdgeArcs::Intersection`], Fig. 12 top; [`build_panels`]): every mesh edge
//! gets one [`Arc`], computed once and shared by both adjacent panels:
//! - an interior edge uses the intersection circle of the two face spheres. Its plane is the
//!   radical plane a₂ψ₁ − a₁ψ₂ = 0, computed in coordinates local to the edge's first vertex
//!   (ψᵢ(p + y) = aᵢ|y|² + ⟨gᵢ, y⟩ + ψᵢ(p), gᵢ = ∇ψᵢ(p)), so its normal is a₂g₁ − a₁g₂; it is
//!   made exactly orthogonal to the edge, then cut with the more curved of the two spheres. When
//!   that normal is ill-conditioned (the spheres are identical or meet at an angle below ~1e-9,
//!   or both faces are planes) the edge falls back to the boundary rule below, on the more curved
//!   sphere;
//! - a boundary edge (one face) uses the plane through its two vertices and the rule's point m
//!   (`Through(m)`) or direction a (`Parallel(a)`). If m lies on the edge's line (or a is
//!   parallel to it), the plane through the edge and the sphere normal at the first vertex is
//!   used instead.
//!
//! **Variant (b)** ([`EdgeArcs::BisectingPlanes`], Fig. 12 bottom): an interior edge pq between
//! faces f and g is cut by the *bisecting plane* of the two face planes, the plane through the
//! edge containing n_f + n_g (unit face normals; n_f − n_g if the two faces traverse the edge in
//! the same direction, i.e. are inconsistently oriented). This is well conditioned also for
//! nearly coplanar faces. Each of the two panels gets its own arc: its own sphere cut by that
//! plane. Both arcs run between the (shared) vertices p and q, but differ in between: the small
//! gaps of variant (b), measured by [`arc_gaps`]. If n_f ± n_g is (nearly) parallel to the edge
//! (faces folded onto each other), the plane through the edge containing n_f (else n_g) is used;
//! if that fails too, each face gets its boundary-rule arc. Boundary and non-manifold edges are
//! treated as in variant (a).
//!
//! A plane cut with a plane is a straight edge ([`Arc::is_straight`]). Of the two arcs of the
//! circle between the vertices, the one whose midpoint is nearer the adjacent face triangle(s)
//! (sum of the distances to the planar triangles) is taken: the panel-side arc, normally the
//! minor one.
//!
//! Circles are built from the edge itself (chord midpoint, in-plane offset h of the centre), not
//! from the sphere centres, so nearly flat spheres with centres far away keep full precision.
//!
//! **Orientation.** `panel.arcs[k]` runs from corner k to corner k+1 (mod 3) of the panel, and
//! runs counter-clockwise about `arc.circle.normal`; the two panels of an edge therefore carry
//! the same circle with opposite normals.
//!
//! # Tessellation
//! With tolerance `tol` (absolute; callers pass 1e-4 of the bounding-box diagonal):
//! - each arc is split into n equal-angle segments with sagitta ≤ 0.5·tol (straight edges: one
//!   segment). In variant (a) the arc points of an edge are computed once, so adjacent panels
//!   share them bit-exactly; in variant (b) each panel samples its own arc (only the two edge
//!   vertices are shared);
//! - the panel interior is the level-N barycentric grid of its corner triangle without its
//!   boundary points, N ≥ 3 and ≥ the three arc segment counts (N = 1, the corner triangle
//!   alone, when all three sides are single segments and that is fine enough). Grid points are a
//!   transfinite blend of the three arcs (planar barycentric point plus Σₖ (1 − λ_opposite)
//!   times the bulge of arc k), projected radially onto the sphere from its centre
//!   (orthogonally for a plane). The ring between the grid and the arc points is closed by a
//!   zipper per side (see `grid`), so any arc point counts fit without folds;
//! - N starts from the estimate √(|a|·Q/tol) (Q: squared circumradius-like size of the corner
//!   triangle, see [`triangle_chord_error`]) and grows until the exact chord error of every
//!   triangle, max over the triangle of the distance to the sphere, is ≤ tol (or N reaches
//!   [`MAX_LEVEL`], or three refinements in a row did not reduce the error: only for invalid
//!   panels whose arcs cross, see [`Panel::folded_triangles`]).
//!
//! [`Panel::area`] is the sum of the tessellation triangle areas; it differs from the true
//! spherical area by a relative amount of the order of tol/r (usually less).

use std::collections::HashMap;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::export::closest::closest_point_on_triangle;
use crate::sphere::Sphere;
use crate::sphere_mesh::{BoundaryArcRule, Circle, SphereMesh};

/// Most segments of one arc.
pub const MAX_ARC_SEGMENTS: usize = 4096;
/// Highest barycentric subdivision level of one panel (at most about N² = 65536 triangles).
pub const MAX_LEVEL: usize = 256;
/// Fraction of the chord tolerance allowed for the sagitta of an arc segment. The flat triangles
/// on a boundary segment deviate from the sphere by a bit more than its sagitta (their longest
/// edge is a little longer than the segment), so leave them room.
const ARC_TOL_FACTOR: f64 = 0.5;

/// A circular arc from `from` to `to`, counter-clockwise about `circle.normal`. A straight edge
/// has `circle.radius = +∞`, `circle.center` at the chord midpoint and `circle.normal` normal to
/// a plane containing the edge.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Arc {
    pub circle: Circle,
    pub from: DVec3,
    pub to: DVec3,
}

/// A spherical (or planar) triangle panel.
#[derive(Clone, Debug, PartialEq)]
pub struct Panel {
    /// Face index in the [`SphereMesh`] (= panel id).
    pub face: usize,
    /// The face sphere (normalized), oriented like the face.
    pub sphere: Sphere,
    /// Mesh vertex ids of the corners, in face order.
    pub corners: [u32; 3],
    /// `arcs[k]` runs from corner k to corner (k+1) mod 3.
    pub arcs: [Arc; 3],
    /// Tessellation vertices; `positions[0..3]` are the corners.
    pub positions: Vec<DVec3>,
    /// Tessellation triangles (indices into `positions`), oriented like the face.
    pub triangles: Vec<[u32; 3]>,
    /// Sum of the tessellation triangle areas.
    pub area: f64,
    /// `arc_vertices[k]`: indices into `positions` of the points of arc k, from corner k to corner
    /// (k+1) mod 3 inclusive. In variant (a) the neighbour across that edge has the same points
    /// in reverse; in variant (b) only the two end points (the mesh vertices) are shared.
    pub arc_vertices: [Vec<u32>; 3],
}

impl Arc {
    /// A straight edge from `from` to `to`; `plane_normal` is the normal of a plane containing it
    /// (made orthogonal to the edge).
    pub fn straight(from: DVec3, to: DVec3, plane_normal: DVec3) -> Arc {
        let e = (to - from).normalize_or_zero();
        let n = (plane_normal - plane_normal.dot(e) * e).try_normalize().unwrap_or_else(|| e.any_orthonormal_vector());
        Arc { circle: Circle { center: 0.5 * (from + to), normal: n, radius: f64::INFINITY }, from, to }
    }

    pub fn is_straight(&self) -> bool {
        !self.circle.radius.is_finite()
    }

    /// The same edge traversed from `to` to `from` (normal flipped, so still counter-clockwise).
    pub fn reversed(&self) -> Arc {
        Arc { circle: Circle { normal: -self.circle.normal, ..self.circle }, from: self.to, to: self.from }
    }

    pub fn chord_length(&self) -> f64 {
        self.from.distance(self.to)
    }

    /// Orthonormal basis of the circle's plane: u from the centre toward `from`, v = n × u (the
    /// arc's tangent direction at `from`).
    fn basis(&self) -> (DVec3, DVec3) {
        let n = self.circle.normal;
        let d = self.from - self.circle.center;
        let u = (d - d.dot(n) * n).try_normalize().unwrap_or_else(|| n.any_orthonormal_vector());
        (u, n.cross(u))
    }

    /// The angle swept from `from` to `to`, in (0, 2π); 0 for a straight or degenerate arc.
    /// Computed from the chord (cos θ = 1 − L²/2r², sin θ = ⟨to − from, v⟩/r), which stays
    /// accurate when the centre is far away.
    pub fn sweep(&self) -> f64 {
        let r = self.circle.radius;
        if !r.is_finite() || r <= 0.0 {
            return 0.0;
        }
        let (_, v) = self.basis();
        let chord = self.to - self.from;
        let l = chord.length();
        if l == 0.0 {
            return 0.0;
        }
        let half = (l / (2.0 * r)).min(1.0).asin();
        if chord.dot(v) >= 0.0 {
            2.0 * half
        } else {
            2.0 * std::f64::consts::PI - 2.0 * half
        }
    }

    /// Arc length (chord length when straight).
    pub fn length(&self) -> f64 {
        if self.is_straight() {
            self.chord_length()
        } else {
            self.circle.radius * self.sweep()
        }
    }

    /// The point at parameter t ∈ [0, 1] (uniform in angle); exactly `from` at 0 and `to` at 1.
    pub fn point(&self, t: f64) -> DVec3 {
        if t <= 0.0 {
            return self.from;
        }
        if t >= 1.0 {
            return self.to;
        }
        if self.is_straight() {
            return self.from + t * (self.to - self.from);
        }
        let r = self.circle.radius;
        let (u, v) = self.basis();
        let phi = t * self.sweep();
        let s = (0.5 * phi).sin();
        // c + r(cos φ u + sin φ v), written relative to `from` = c + r u.
        self.from + (r * phi.sin()) * v - (2.0 * r * s * s) * u
    }

    /// Largest distance between the arc and its chord (0 when straight).
    pub fn sagitta(&self) -> f64 {
        segment_sagitta(self.circle.radius, self.sweep())
    }

    /// Number of equal-angle segments whose sagitta is at most `tol` (1 for straight arcs), at
    /// most [`MAX_ARC_SEGMENTS`], and at most 90° each.
    pub fn segments_for(&self, tol: f64) -> usize {
        let r = self.circle.radius;
        let theta = self.sweep();
        if !r.is_finite() || theta <= 0.0 {
            return 1;
        }
        // Sagitta of a segment of angle Δ: 2r sin²(Δ/4) ≤ tol.
        let x = tol / (2.0 * r);
        let dmax = if x >= 1.0 || !x.is_finite() { std::f64::consts::PI } else { 4.0 * x.sqrt().asin() };
        let dmax = dmax.clamp(1e-12, 0.5 * std::f64::consts::PI);
        let n = (theta / dmax).ceil();
        if n.is_finite() {
            (n as usize).clamp(1, MAX_ARC_SEGMENTS)
        } else {
            MAX_ARC_SEGMENTS
        }
    }

    /// `segments + 1` points along the arc, equal in angle, with exact endpoints.
    pub fn sample(&self, segments: usize) -> Vec<DVec3> {
        let n = segments.max(1);
        (0..=n).map(|j| self.point(j as f64 / n as f64)).collect()
    }

    /// The arc point above the chord point `from + t (to − from)`, t ∈ [0, 1]: the arc's
    /// intersection with the line through that chord point orthogonal to the chord in the arc's
    /// plane (the chord point itself for a straight arc). Of the circle's two points on that line
    /// the one on this arc is taken: with w = normal × (to − from)/|to − from| the arc lies on the
    /// −w side of the centre, so the offset is s = h − √(h² + l²/4 − u²), h = ⟨centre − chord
    /// midpoint, w⟩, u the signed distance from the chord midpoint (rationalized when h ≥ 0, the
    /// minor arc, to keep precision for huge radii).
    pub fn point_over_chord(&self, t: f64) -> DVec3 {
        let e = self.to - self.from;
        let x0 = self.from + t * e;
        let l = e.length();
        if self.is_straight() || l == 0.0 {
            return x0;
        }
        let eh = e / l;
        let w = self.circle.normal.cross(eh).normalize_or_zero();
        let h = (self.circle.center - 0.5 * (self.from + self.to)).dot(w);
        let u = (t - 0.5) * l;
        let rest = ((0.5 * l - u.abs()) * (0.5 * l + u.abs())).max(0.0); // l²/4 − u²
        let root = (h * h + rest).sqrt();
        let s = if h >= 0.0 { -rest / (root + h) } else { h - root };
        x0 + s * w
    }

    /// Sagitta of one of `segments` equal segments.
    pub fn segment_sagitta(&self, segments: usize) -> f64 {
        segment_sagitta(self.circle.radius, self.sweep() / segments.max(1) as f64)
    }
}

/// Sagitta of a circular segment of radius r and angle θ: 2r sin²(θ/4) (0 for r = ∞).
fn segment_sagitta(r: f64, theta: f64) -> f64 {
    if !r.is_finite() {
        return 0.0;
    }
    let s = (0.25 * theta).sin();
    2.0 * r * s * s
}

impl Panel {
    /// Exact chord error of the tessellation: max over its triangles of the largest distance
    /// between the triangle and the panel's sphere (see [`triangle_chord_error`]).
    pub fn chord_error(&self) -> f64 {
        let s = self.sphere;
        self.triangles
            .iter()
            .map(|t| {
                triangle_chord_error(
                    &s,
                    self.positions[t[0] as usize],
                    self.positions[t[1] as usize],
                    self.positions[t[2] as usize],
                )
            })
            .fold(0.0, f64::max)
    }

    /// Tessellation triangles facing against the panel's outward normal −∇ψ. Non-zero only when
    /// the panel itself is invalid: two of its arcs cross near a corner (the curved corner angle
    /// is negative), which happens for extreme kinks between neighbouring spheres.
    pub fn folded_triangles(&self) -> usize {
        self.triangles
            .iter()
            .filter(|t| {
                let [a, b, c] = t.map(|i| self.positions[i as usize]);
                (b - a).cross(c - a).dot(self.normal_at((a + b + c) / 3.0)) < 0.0
            })
            .count()
    }

    /// True when the panel's sphere is a plane (a = 0).
    pub fn is_planar(&self) -> bool {
        self.sphere.a == 0.0
    }

    /// Outward unit normal of the panel surface at `x` (on or near the sphere): −∇ψ/|∇ψ|, the
    /// reference-normal side.
    pub fn normal_at(&self, x: DVec3) -> DVec3 {
        sphere_normal(&self.sphere, x)
    }
}

/// −∇ψ(x)/|∇ψ(x)|: the unit normal of a generalized sphere on its oriented ("outward") side.
pub fn sphere_normal(s: &Sphere, x: DVec3) -> DVec3 {
    (s.b - 2.0 * s.a * x).try_normalize().unwrap_or(DVec3::Z)
}

/// Distance from `x` to a normalized generalized sphere, from ψ(x): |x − c| = √(r² + 2rψ), so
/// the distance is 2|ψ| / (1 + √(1 + 4aψ)). Exact for planes and accurate for huge radii.
pub fn distance_to_sphere(s: &Sphere, x: DVec3) -> f64 {
    let psi = s.eval(x);
    2.0 * psi.abs() / (1.0 + (1.0 + 4.0 * s.a * psi).max(0.0).sqrt())
}

/// Largest distance between triangle `x0 x1 x2` (corners on the normalized sphere `s`) and the
/// sphere. For x = Σβᵢxᵢ, ψ(x) = Σβᵢψ(xᵢ) − a·Q(β) with Q = Σ_{i<j} βᵢβⱼ|xᵢ − xⱼ|², and
/// max_T Q is the squared circumradius for an acute triangle, else (longest edge / 2)².
/// Corner residuals ψ(xᵢ) are added as an upper bound.
pub fn triangle_chord_error(s: &Sphere, x0: DVec3, x1: DVec3, x2: DVec3) -> f64 {
    let q = triangle_q_max(x0, x1, x2);
    let psi = s.a.abs() * q;
    let curved = 2.0 * psi / (1.0 + (1.0 - 4.0 * s.a * s.a * q).max(0.0).sqrt());
    let residual = [x0, x1, x2].iter().map(|&x| distance_to_sphere(s, x)).fold(0.0, f64::max);
    curved + residual
}

/// max over the triangle of Σ_{i<j} βᵢβⱼ|xᵢ − xⱼ|² (the negated power of the point w.r.t. the
/// circumcircle): R² when acute, (ℓ_max/2)² otherwise.
fn triangle_q_max(x0: DVec3, x1: DVec3, x2: DVec3) -> f64 {
    let l = [x1.distance_squared(x2), x2.distance_squared(x0), x0.distance_squared(x1)];
    let lmax = l[0].max(l[1]).max(l[2]);
    let acute = l[0] < l[1] + l[2] && l[1] < l[2] + l[0] && l[2] < l[0] + l[1];
    if acute {
        let a2 = (x1 - x0).cross(x2 - x0).length_squared(); // (2·area)²
        if a2 > 0.0 {
            return (l[0] * l[1] * l[2] / (4.0 * a2)).min(lmax);
        }
    }
    0.25 * lmax
}

/// Projects `x` radially onto the sphere (from its centre; orthogonally for a plane) by Newton
/// steps along ∇ψ, in coordinates local to `base` (a point on or near the sphere, e.g. a panel
/// corner: this keeps precision for huge radii).
pub fn project_to_sphere(s: &Sphere, base: DVec3, x: DVec3) -> DVec3 {
    let g0 = 2.0 * s.a * base - s.b;
    let psi0 = s.eval(base);
    let mut y = x - base;
    for _ in 0..12 {
        let psi = s.a * y.length_squared() + g0.dot(y) + psi0;
        let g = 2.0 * s.a * y + g0;
        let gg = g.length_squared();
        if gg.is_nan() || gg <= 0.0 {
            break;
        }
        let step = (psi / gg) * g;
        y -= step;
        if step.length() <= 1e-16 * (1.0 + y.length()) {
            break;
        }
    }
    let p = base + y;
    if p.is_finite() {
        p
    } else {
        x
    }
}

/// Normalized face sphere, or the plane of the face triangle when the given sphere is unusable
/// (non-finite or imaginary).
fn usable_sphere(s: &Sphere, tri: [DVec3; 3]) -> Sphere {
    let n = s.normalized();
    if n.is_finite() && (n.discriminant() - 1.0).abs() < 1e-6 {
        return n;
    }
    let normal = (tri[1] - tri[0]).cross(tri[2] - tri[0]).try_normalize().unwrap_or(DVec3::Z);
    Sphere::plane(tri[0], normal)
}

/// How the arcs of interior edges are cut (Fig. 12; see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum EdgeArcs {
    /// Variant (a): the intersection circle of the two face spheres, one arc shared by both
    /// panels (no gaps).
    #[default]
    Intersection,
    /// Variant (b): each face sphere cut by the bisecting plane of the two face planes, one arc
    /// per panel (small gaps between adjacent panels, see [`arc_gaps`]).
    BisectingPlanes,
}

/// Builds, arcs and tessellates every panel of `sm`, with chord error ≤ `chord_tolerance`
/// (absolute length; a non-positive or non-finite value means 1e-4 of the bounding-box
/// diagonal). Panel i is face i. Variant (a) edges: `build_panels_with(sm, tol,
/// EdgeArcs::Intersection)`.
pub fn build_panels(sm: &SphereMesh, chord_tolerance: f64) -> Vec<Panel> {
    build_panels_with(sm, chord_tolerance, EdgeArcs::Intersection)
}

/// [`build_panels`] with the interior edge arcs of the given variant (Fig. 12).
pub fn build_panels_with(sm: &SphereMesh, chord_tolerance: f64, edge_arcs: EdgeArcs) -> Vec<Panel> {
    let mesh = &sm.mesh;
    let diag = mesh.bbox_diagonal().max(f64::MIN_POSITIVE);
    let tol = if chord_tolerance > 0.0 && chord_tolerance.is_finite() { chord_tolerance } else { 1e-4 * diag };
    let faces = mesh.triangles.len();
    let spheres: Vec<Sphere> = (0..faces)
        .map(|f| {
            let s = sm.face_spheres.get(f).copied().unwrap_or(Sphere { a: f64::NAN, b: DVec3::NAN, c: f64::NAN });
            usable_sphere(&s, mesh.face_points(f))
        })
        .collect();

    // Edge -> incident (face, side) pairs; side k runs from corner k to corner k+1.
    let mut edge_faces: HashMap<(u32, u32), Vec<(usize, usize)>> = HashMap::new();
    for (f, t) in mesh.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            edge_faces.entry((a.min(b), a.max(b))).or_default().push((f, k));
        }
    }
    let mut keys: Vec<(u32, u32)> = edge_faces.keys().copied().collect();
    keys.sort_unstable();

    // Per (face, side): the arc in the panel's direction and its points.
    type Side = Option<(Arc, Vec<DVec3>)>;
    let mut side_arcs: Vec<[Side; 3]> = vec![[None, None, None]; faces];
    for key in keys {
        let inc = &edge_faces[&key];
        let (p, q) = (mesh.positions[key.0 as usize], mesh.positions[key.1 as usize]);
        if edge_arcs == EdgeArcs::BisectingPlanes && inc.len() == 2 {
            // Variant (b), Fig. 12 bottom: every panel cuts its own sphere with the bisecting plane.
            let [(f, kf), (g, kg)] = [inc[0], inc[1]];
            let consistent = (mesh.triangles[f][kf] == key.0) != (mesh.triangles[g][kg] == key.0);
            let plane = bisecting_plane_normal(p, q, mesh.face_area_vector(f), mesh.face_area_vector(g), consistent);
            let tris = [mesh.face_points(f), mesh.face_points(g)];
            for &(h, k) in inc {
                let arc = match plane {
                    Some(n) => cut_arc(p, q, n, &spheres[h], &tris, diag),
                    None => edge_arc(p, q, &[h], &spheres, mesh, sm.boundary_arcs, diag),
                };
                let pts = arc.sample(arc.segments_for(ARC_TOL_FACTOR * tol));
                side_arcs[h][k] = Some(if mesh.triangles[h][k] == key.0 {
                    (arc, pts)
                } else {
                    (arc.reversed(), pts.into_iter().rev().collect())
                });
            }
            continue;
        }
        let groups: Vec<Vec<usize>> = if inc.len() <= 2 {
            vec![inc.iter().map(|&(f, _)| f).collect()]
        } else {
            // Non-manifold edge: every face gets its own boundary-rule arc.
            inc.iter().map(|&(f, _)| vec![f]).collect()
        };
        for group in groups {
            let arc = edge_arc(p, q, &group, &spheres, mesh, sm.boundary_arcs, diag);
            let n = arc.segments_for(ARC_TOL_FACTOR * tol);
            let pts = arc.sample(n);
            for &(f, k) in inc.iter().filter(|(f, _)| group.contains(f)) {
                let forward = mesh.triangles[f][k] == key.0;
                side_arcs[f][k] = Some(if forward {
                    (arc, pts.clone())
                } else {
                    (arc.reversed(), pts.iter().rev().copied().collect())
                });
            }
        }
    }

    (0..faces)
        .map(|f| {
            let sides = std::mem::take(&mut side_arcs[f]);
            let [s0, s1, s2] = sides.map(|s| s.expect("every face side has an arc"));
            tessellate(f, mesh.triangles[f], spheres[f], [s0, s1, s2], mesh.face_points(f), tol)
        })
        .collect()
}

/// The gap of one interior edge between the arcs of its two panels (variant (b), Fig. 12).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EdgeGap {
    /// Mesh vertex ids, lower first.
    pub edge: [u32; 2],
    /// Face ids of the two panels, in panel order.
    pub faces: [usize; 2],
    /// Largest distance between the two arcs over the sampled chord points (see [`arc_gaps`]).
    pub gap: f64,
}

/// The gaps between the two panel arcs of every interior (two-panel) edge, sorted by edge.
///
/// **Definition** (the one of [`crate::st_angle::max_gap`], evaluated on the panels' arcs rather
/// than on the spheres): for the chord points x₀ = p + t (q − p), t = j/(samples − 1),
/// j = 1 … samples − 2, each arc's point above x₀ ([`Arc::point_over_chord`]: on the line through
/// x₀ orthogonal to the chord in the arc's plane) is taken, and the gap is the largest distance
/// between the two arcs' points. For variant (b) both arcs lie in the edge's bisecting plane, so
/// this is max |h_f − h_g| of `max_gap`; with `samples` = [`crate::st_angle::GAP_SAMPLES`] the
/// sample points are the same, and the two agree up to rounding, except where a panel-side arc is
/// the major arc (`max_gap` takes the sphere point nearest the chord, i.e. the minor arc) or for
/// degenerate (folded or inconsistently oriented) face pairs. Variant (a) panels give 0 (one
/// shared arc). `samples` < 3 is taken as 3 (the chord midpoint only).
pub fn arc_gaps(panels: &[Panel], samples: usize) -> Vec<EdgeGap> {
    let samples = samples.max(3);
    let mut sides: HashMap<(u32, u32), Vec<(usize, usize)>> = HashMap::new();
    for (i, p) in panels.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (p.corners[k], p.corners[(k + 1) % 3]);
            sides.entry((a.min(b), a.max(b))).or_default().push((i, k));
        }
    }
    let mut out: Vec<EdgeGap> = sides
        .into_iter()
        .filter(|(_, v)| v.len() == 2)
        .map(|(key, v)| {
            // Both arcs from vertex key.0 to key.1, so that equal t means the same chord point.
            let [a, b] = [v[0], v[1]].map(|(i, k)| {
                let arc = panels[i].arcs[k];
                if panels[i].corners[k] == key.0 {
                    arc
                } else {
                    arc.reversed()
                }
            });
            let gap = (1..samples - 1)
                .map(|j| {
                    let t = j as f64 / (samples - 1) as f64;
                    a.point_over_chord(t).distance(b.point_over_chord(t))
                })
                .fold(0.0, f64::max);
            EdgeGap { edge: [key.0, key.1], faces: [panels[v[0].0].face, panels[v[1].0].face], gap }
        })
        .collect();
    out.sort_unstable_by_key(|g| g.edge);
    out
}

/// The largest of [`arc_gaps`] (0 without interior edges); absolute, in model units.
pub fn max_arc_gap(panels: &[Panel], samples: usize) -> f64 {
    arc_gaps(panels, samples).iter().map(|g| g.gap).fold(0.0, f64::max)
}

/// Normal of the bisecting plane of edge p→q between two faces with area vectors `af`, `ag`
/// (variant (b), Fig. 12): the plane through the edge containing n_f + n_g (n_f − n_g when the
/// faces are not `consistent`ly oriented along the edge). If that direction is (nearly) along
/// the edge, the plane containing n_f, else n_g; `None` when all are degenerate.
pub fn bisecting_plane_normal(p: DVec3, q: DVec3, af: DVec3, ag: DVec3, consistent: bool) -> Option<DVec3> {
    let eh = (q - p).try_normalize()?;
    let (nf, ng) = (af.normalize_or_zero(), ag.normalize_or_zero());
    let sum = if consistent { nf + ng } else { nf - ng };
    [sum, nf, ng].into_iter().find_map(|d| {
        let n = eh.cross(d);
        (n.length() > 1e-6 && n.is_finite()).then(|| n.normalize())
    })
}

/// The arc of edge p→q shared by `faces` (one or two faces).
fn edge_arc(
    p: DVec3,
    q: DVec3,
    faces: &[usize],
    spheres: &[Sphere],
    mesh: &crate::mesh::TriMesh,
    rule: BoundaryArcRule,
    diag: f64,
) -> Arc {
    let e = q - p;
    let l = e.length();
    let tris: Vec<[DVec3; 3]> = faces.iter().map(|&f| mesh.face_points(f)).collect();
    // The more curved sphere (ties: lower face index) carries the cut.
    let cut_face = faces.iter().copied().fold(faces[0], |best, f| if spheres[f].a.abs() > spheres[best].a.abs() { f } else { best });
    let s_cut = spheres[cut_face];
    if l == 0.0 {
        return Arc::straight(p, q, DVec3::Z);
    }
    let eh = e / l;
    if let [f1, f2] = faces {
        let (s1, s2) = (spheres[*f1], spheres[*f2]);
        let g1 = 2.0 * s1.a * p - s1.b;
        let g2 = 2.0 * s2.a * p - s2.b;
        let n = s2.a * g1 - s1.a * g2;
        let scale = s1.a.abs() * g1.length() + s2.a.abs() * g2.length();
        let nl = n.length();
        if nl > 1e-9 * scale && nl.is_finite() && (n.dot(eh) / nl).abs() < 1e-4 {
            return cut_arc(p, q, n, &s_cut, &tris, diag);
        }
    }
    // Boundary rule (also the fallback for ill-conditioned interior edges).
    let g = -(2.0 * s_cut.a * p - s_cut.b);
    let rule_normal = match rule {
        BoundaryArcRule::Through(m) => eh.cross(m - p),
        BoundaryArcRule::Parallel(a) => eh.cross(a),
    };
    let ref_len = match rule {
        BoundaryArcRule::Through(m) => (m - p).length(),
        BoundaryArcRule::Parallel(a) => a.length(),
    };
    let n = if rule_normal.length() > 1e-9 * ref_len && rule_normal.is_finite() { rule_normal } else { eh.cross(g) };
    if !n.is_finite() || n.length() == 0.0 {
        let fallback = tris[0][1] - tris[0][0];
        return Arc::straight(p, q, (tris[0][2] - tris[0][0]).cross(fallback).cross(e));
    }
    cut_arc(p, q, n, &s_cut, &tris, diag)
}

/// The arc p→q of the circle where the plane through p with normal `n` (made orthogonal to the
/// edge) cuts the sphere `s`; the arc nearer the triangles `tris`.
fn cut_arc(p: DVec3, q: DVec3, n: DVec3, s: &Sphere, tris: &[[DVec3; 3]], diag: f64) -> Arc {
    let e = q - p;
    let l = e.length();
    let eh = e / l;
    let n = (n - n.dot(eh) * eh).normalize();
    let w = n.cross(eh);
    let mid = 0.5 * (p + q);
    // A plane, or a sphere so flat (r > 5e11·diag) that it deviates from its tangent plane by
    // < 1e-12·diag over the model: a plane cut of it is a straight edge.
    if s.a.abs() * diag <= 1e-12 {
        return Arc::straight(p, q, n);
    }
    // Circle centre = M + h w, h = ⟨C − p, w⟩ with C − p = −∇ψ(p)/(2a).
    let g = 2.0 * s.a * p - s.b;
    let h = -g.dot(w) / (2.0 * s.a);
    let half = 0.5 * l;
    let r = half.hypot(h);
    // Distance from the chord midpoint to the near arc point: r − |h| = (l/2)²/(r + |h|).
    let near = half * half / (r + h.abs());
    if !h.is_finite() || !r.is_finite() || near <= 1e-13 * diag {
        return Arc::straight(p, q, n);
    }
    let sign_h = if h >= 0.0 { 1.0 } else { -1.0 };
    // The two arc midpoints lie on the bisector through M: M − sign(h)(r − |h|) w (near side)
    // and M + sign(h)(r + |h|) w.
    let m_near = mid - sign_h * near * w;
    let m_far = mid + sign_h * (r + h.abs()) * w;
    let score = |x: DVec3| -> f64 {
        tris.iter().map(|t| closest_point_on_triangle(x, t[0], t[1], t[2]).0.distance(x)).sum()
    };
    let chosen = if score(m_far) < score(m_near) { m_far } else { m_near };
    // p → chosen → q is counter-clockwise about ±n.
    let orient = (chosen - p).cross(q - p).dot(n);
    let normal = if orient >= 0.0 { n } else { -n };
    Arc { circle: Circle { center: mid + h * w, normal, radius: r }, from: p, to: q }
}

/// Tessellates one panel from its three sides (arcs and points, in the panel's direction).
fn tessellate(
    face: usize,
    corners: [u32; 3],
    sphere: Sphere,
    sides: [(Arc, Vec<DVec3>); 3],
    tri: [DVec3; 3],
    tol: f64,
) -> Panel {
    let n_side = [sides[0].1.len() - 1, sides[1].1.len() - 1, sides[2].1.len() - 1];
    // Corners first, then the inner points of each side.
    let mut base: Vec<DVec3> = tri.to_vec();
    let mut arc_vertices: [Vec<u32>; 3] = [vec![], vec![], vec![]];
    for k in 0..3 {
        let pts = &sides[k].1;
        let mut ids = vec![k as u32];
        for &x in &pts[1..pts.len() - 1] {
            ids.push(base.len() as u32);
            base.push(x);
        }
        ids.push(((k + 1) % 3) as u32);
        arc_vertices[k] = ids;
    }
    let arcs = [sides[0].0, sides[1].0, sides[2].0];

    let q = triangle_q_max(tri[0], tri[1], tri[2]);
    let estimate = (sphere.a.abs() * q / tol).sqrt().ceil();
    let estimate = if estimate.is_finite() { (estimate as usize).min(MAX_LEVEL) } else { MAX_LEVEL };
    let mut level = n_side.iter().copied().max().unwrap_or(1).max(estimate).max(1);
    let (mut best_err, mut stalled) = (f64::INFINITY, 0);
    loop {
        let (positions, triangles) = grid(&sphere, &arcs, &tri, &base, &arc_vertices, &n_side, level);
        let err = triangles
            .iter()
            .map(|t| {
                triangle_chord_error(
                    &sphere,
                    positions[t[0] as usize],
                    positions[t[1] as usize],
                    positions[t[2] as usize],
                )
            })
            .fold(0.0, f64::max);
        // Stop when fine enough, at the cap, or when three refinements in a row did not help (a
        // panel whose arcs cross at a corner: invalid input, see `Panel::folded_triangles`).
        if err < 0.99 * best_err {
            best_err = err;
            stalled = 0;
        } else {
            stalled += 1;
        }
        if err <= tol || level >= MAX_LEVEL || stalled >= 3 {
            let area = triangles
                .iter()
                .map(|t| {
                    let [a, b, c] = t.map(|i| positions[i as usize]);
                    0.5 * (b - a).cross(c - a).length()
                })
                .sum();
            return Panel { face, sphere, corners, arcs, positions, triangles, area, arc_vertices };
        }
        let grow = (level as f64 * (err / tol).sqrt() * 1.05).ceil() as usize;
        level = grow.max(level + 1).min(MAX_LEVEL);
    }
}

/// The level-N tessellation of a panel: returns positions (the `base` points followed by the
/// interior grid points) and the triangles.
///
/// N = 1 (only possible when every side is a single segment): the corner triangle. Otherwise
/// (N ≥ 3) the interior points of the level-N barycentric grid (all barycentric coordinates
/// ≥ 1/N) are triangulated as a regular grid, and the ring between them and the boundary (the
/// arc points) is closed side by side by a zipper: along side k, the arc points and the grid row
/// next to that side are merged by their parameter along the side. Every zipper triangle has
/// either its base on the boundary and its apex on the row or vice versa, so nothing folds
/// whatever the arc point counts are.
fn grid(
    sphere: &Sphere,
    arcs: &[Arc; 3],
    tri: &[DVec3; 3],
    base: &[DVec3],
    arc_vertices: &[Vec<u32>; 3],
    n_side: &[usize; 3],
    level: usize,
) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let mut positions = base.to_vec();
    if level <= 1 && n_side.iter().all(|&n| n == 1) {
        return (positions, vec![[0, 1, 2]]);
    }
    let nn = level.max(3);
    // Interior grid point (i, a, b), i + a + b = N, all ≥ 1, stored by (a', b') = (a − 1, b − 1)
    // in the level-M grid, M = N − 3.
    let m = nn - 3;
    let row_start = |b: usize| -> usize { b * (m + 1) - b * (b.saturating_sub(1)) / 2 };
    let mut ids = vec![0u32; (m + 1) * (m + 2) / 2];
    for b in 0..=m {
        for a in 0..=(m - b) {
            let (ga, gb) = (a + 1, b + 1);
            let gi = nn - ga - gb;
            let lam = [gi as f64 / nn as f64, ga as f64 / nn as f64, gb as f64 / nn as f64];
            let x = blend(arcs, tri, lam);
            positions.push(project_to_sphere(sphere, tri[0], x));
            ids[row_start(b) + a] = (positions.len() - 1) as u32;
        }
    }
    let g = |a: usize, b: usize| ids[row_start(b) + a];
    let mut triangles = Vec::with_capacity(nn * nn);
    for b in 0..m {
        for a in 0..(m - b) {
            triangles.push([g(a, b), g(a + 1, b), g(a, b + 1)]);
            if a + b + 2 <= m {
                triangles.push([g(a + 1, b), g(a + 1, b + 1), g(a, b + 1)]);
            }
        }
    }
    // The grid row next to each side, from near corner k to near corner k+1, with its parameter
    // along the side: side 0 (b = 1, a up), side 1 (i = 1, b up), side 2 (a = 1, i up).
    for (k, bnd) in arc_vertices.iter().enumerate() {
        let row: Vec<(u32, f64)> = (0..=m)
            .map(|s| {
                let (a, b) = match k {
                    0 => (s, 0),
                    1 => (m - s, s),
                    _ => (0, m - s),
                };
                // Grid coordinates (i, a, b) of this point, and the parameter along side k.
                let (ga, gb) = ((a + 1) as f64, (b + 1) as f64);
                let gi = nn as f64 - ga - gb;
                let t = match k {
                    0 => ga / (gi + ga),
                    1 => gb / (ga + gb),
                    _ => gi / (gb + gi),
                };
                (g(a, b), t)
            })
            .collect();
        let n = bnd.len() - 1;
        let (mut j, mut l) = (0usize, 0usize);
        while j < n || l < row.len() - 1 {
            let advance_boundary = l == row.len() - 1 || (j < n && (j + 1) as f64 / n as f64 <= row[l + 1].1);
            if advance_boundary {
                triangles.push([bnd[j], bnd[j + 1], row[l].0]);
                j += 1;
            } else {
                triangles.push([bnd[j], row[l + 1].0, row[l].0]);
                l += 1;
            }
        }
    }
    (positions, triangles)
}

/// Transfinite blend: Σλᵢ Pᵢ + Σₖ (1 − λ_{k+2}) dₖ(λ_{k+1}/(1 − λ_{k+2})), where dₖ(t) is
/// arc k's offset from its chord at parameter t. It reproduces every arc on its side.
fn blend(arcs: &[Arc; 3], tri: &[DVec3; 3], lam: [f64; 3]) -> DVec3 {
    let mut x = lam[0] * tri[0] + lam[1] * tri[1] + lam[2] * tri[2];
    for k in 0..3 {
        let w = 1.0 - lam[(k + 2) % 3];
        if w <= 0.0 || arcs[k].is_straight() {
            continue;
        }
        let t = lam[(k + 1) % 3] / w;
        let chord = tri[k] + t * (tri[(k + 1) % 3] - tri[k]);
        x += w * (arcs[k].point(t) - chord);
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arc_point_sweep_and_sagitta() {
        // Quarter circle of radius 2 in the xy-plane, from (2,0,0) to (0,2,0), ccw about +z.
        let c = Circle { center: DVec3::ZERO, normal: DVec3::Z, radius: 2.0 };
        let arc = Arc { circle: c, from: DVec3::new(2.0, 0.0, 0.0), to: DVec3::new(0.0, 2.0, 0.0) };
        assert!((arc.sweep() - std::f64::consts::FRAC_PI_2).abs() < 1e-14);
        let m = arc.point(0.5);
        assert!((m - DVec3::new(2f64.sqrt(), 2f64.sqrt(), 0.0)).length() < 1e-14);
        assert!((arc.sagitta() - (2.0 - 2f64.sqrt())).abs() < 1e-14);
        // Reversed: ccw about −z, same points.
        let rev = arc.reversed();
        assert!((rev.sweep() - arc.sweep()).abs() < 1e-14);
        assert!((rev.point(0.25) - arc.point(0.75)).length() < 1e-14);
        // The major arc (ccw about −z from (2,0,0) to (0,2,0)).
        let major = Arc { circle: Circle { normal: -DVec3::Z, ..c }, ..arc };
        assert!((major.sweep() - 1.5 * std::f64::consts::PI).abs() < 1e-14);
        assert!((major.point(0.5) + m).length() < 1e-14);
        // Segment counts honour the tolerance.
        for tol in [1e-1, 1e-3, 1e-6] {
            let n = arc.segments_for(tol);
            assert!(arc.segment_sagitta(n) <= tol);
            assert!(n == 1 || arc.segment_sagitta(n - 1) > tol);
        }
    }

    #[test]
    fn projection_is_radial() {
        let s = Sphere::from_center_radius(DVec3::new(0.3, -0.2, 1.0), -1.7);
        let c = s.center().unwrap();
        let x = DVec3::new(1.0, 0.5, 0.2);
        let y = project_to_sphere(&s, c + DVec3::new(1.7, 0.0, 0.0), x);
        assert!(s.eval(y).abs() < 1e-15);
        assert!((y - c).normalize().cross((x - c).normalize()).length() < 1e-14);
        let pl = Sphere::plane(DVec3::new(0.0, 0.0, 1.0), DVec3::new(0.0, 0.6, 0.8));
        let y = project_to_sphere(&pl, DVec3::new(0.0, 0.0, 1.0), x);
        assert!(pl.eval(y).abs() < 1e-15);
        assert!((y - x).cross(DVec3::new(0.0, 0.6, 0.8)).length() < 1e-15);
    }

    #[test]
    fn chord_error_formula_matches_sphere_distance() {
        let s = Sphere::from_center_radius(DVec3::ZERO, 1.0);
        let on = |v: DVec3| v.normalize();
        let t = [on(DVec3::new(1.0, 0.1, 0.2)), on(DVec3::new(0.9, 0.4, 0.1)), on(DVec3::new(0.95, 0.1, 0.5))];
        let e = triangle_chord_error(&s, t[0], t[1], t[2]);
        // Brute force over the triangle.
        let mut best: f64 = 0.0;
        let n = 200;
        for i in 0..=n {
            for j in 0..=(n - i) {
                let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                let x = t[0] + u * (t[1] - t[0]) + v * (t[2] - t[0]);
                best = best.max(1.0 - x.length());
            }
        }
        assert!(e >= best - 1e-15 && e - best < 1e-6 * e, "{e} vs {best}");
        assert!((distance_to_sphere(&s, DVec3::new(0.0, 0.0, 3.0)) - 2.0).abs() < 1e-15);
        assert!((distance_to_sphere(&s, DVec3::new(0.0, 0.2, 0.0)) - 0.8).abs() < 1e-15);
    }
}
