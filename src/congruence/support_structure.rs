//! The support structure of an ST mesh (Sec. 2.2, 4, Fig. 1): node axes, the planar support
//! elements between them, and their tessellation for display and export.
//!
//! **Node axes.** The face spheres around a vertex v pass through v and a second common point v̄;
//! the node axis is the line v v̄ ([`star_axis`]). For an ST mesh with support structure every
//! node axis passes through the centre m of the absolute sphere Ω (Sec. 2.4).
//!
//! [`node_axes`] is the one definition every method uses: from the star's spheres where they
//! determine the line, else a direction the method gives (toward m, or the normal), projected
//! into the plane of the vertex's one edge circle where it has exactly one.
//!
//! **Edge circles.** [`edge_circle`]: the circle of an edge's arc, in the radical plane of its two
//! face spheres, or in a plane through the edge the method names ([`EdgePlane`]).
//!
//! **Support elements.** Per edge, the annulus sector in the plane of the edge's circle between
//! the two node axes ([`support_element`]); [`support_strips`] tessellates them along the panels'
//! own arc points, so the support meets the panels exactly. [`SupportStructure`] holds the node
//! axes, the elements and their strips: the one result shape of every method with support.

// Negated float comparisons are deliberate: they also reject NaN.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::geometry::circle::Circle;
use crate::geometry::linalg::Svd;
use crate::geometry::mesh::topology::Topology;
use crate::geometry::mesh::TriMesh;
use crate::geometry::sphere::Sphere;
use crate::params::ParamRange;
use crate::progress::{Cancelled, OnProgress, Progress};

/// The node axis of a vertex star: the line through v and the second common point v̄ of the
/// spheres around v. See [`star_axis`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct StarAxis {
    /// Unit direction of the line v v̄ (sign arbitrary).
    pub direction: DVec3,
    /// v̄; None when it is at infinity (all spheres are planes).
    pub second_point: Option<DVec3>,
    /// σ₃/σ₁ of the system below: how well the spheres determine the line (0 = not at all).
    pub condition: f64,
}

/// The depth of the support elements, relative to the bounding-box diagonal.
pub const SUPPORT_DEPTH_RANGE: ParamRange<f64> = ParamRange::new("support depth", 1e-4, 0.5);
/// The length of the drawn node axes, relative to the diagonal.
pub const AXIS_LENGTH_RANGE: ParamRange<f64> = ParamRange::new("axis length", 0.0, 10.0);

/// Minimum [`StarAxis::condition`] accepted by [`second_common_point`] and [`star_axis`]'s
/// callers in this crate: below it the spheres are nearly coaxal (e.g. all equal, as on a sphere)
/// and the line is not determined to better than ≈ 1e-10 relative.
pub const STAR_AXIS_MIN_CONDITION: f64 = 1e-6;

/// The common line through v of normalized spheres that all pass through v (at least 3 of them).
///
/// Every pair's radical plane a_jψ_i − a_iψ_j = 0 contains v and v̄; in the frame y = (x − v)/S
/// the line is y = t ℓ, and it meets sphere j again where ⟨N_j(v), ℓ⟩ = a_j S τ with t = τ/|ℓ|²
/// (N_j = b_j − 2a_j v, the normal at v). So (ℓ, τ) is the least-squares null vector of the k × 4
/// matrix with rows [N_j, −a_j S]: the pairwise radical-plane conditions are the differences of
/// these rows, solved for all pairs at once by a Jacobi SVD. S = min |r_j| keeps |ℓ| ≥ 1/√5
/// (|v̄ − v| ≤ 2 min |r_j|), so the direction is well conditioned even when v̄ is far.
/// All planes: the direction is the common line of the planes and v̄ is at infinity.
/// None for fewer than 3 spheres or non-finite input; check `condition` against
/// [`STAR_AXIS_MIN_CONDITION`].
pub fn star_axis(spheres: &[Sphere], v: DVec3) -> Option<StarAxis> {
    if spheres.len() < 3 || !v.is_finite() || spheres.iter().any(|s| !s.is_finite()) {
        return None;
    }
    let amax = spheres.iter().map(|s| s.a.abs()).fold(0.0, f64::max);
    if amax == 0.0 {
        let rows: Vec<[f64; 3]> = spheres.iter().map(|s| s.normal_at(v).to_array()).collect();
        let svd = Svd::new(&rows);
        let condition = if svd.sigma[0] > 0.0 { svd.sigma[1] / svd.sigma[0] } else { 0.0 };
        let direction = DVec3::from_array(svd.v[2]).try_normalize()?;
        return Some(StarAxis { direction, second_point: None, condition });
    }
    let scale = 0.5 / amax;
    let rows: Vec<[f64; 4]> = spheres
        .iter()
        .map(|s| {
            let n = s.normal_at(v);
            [n.x, n.y, n.z, -s.a * scale]
        })
        .collect();
    let svd = Svd::new(&rows);
    let condition = if svd.sigma[0] > 0.0 { svd.sigma[2] / svd.sigma[0] } else { 0.0 };
    let [lx, ly, lz, tau] = svd.v[3];
    let l = DVec3::new(lx, ly, lz);
    let l2 = l.length_squared();
    if !(l2 > 0.0) {
        return None;
    }
    let direction = l / l2.sqrt();
    let second = v + (scale * tau / l2) * l;
    Some(StarAxis { direction, second_point: second.is_finite().then_some(second), condition })
}

/// The second common point v̄ of the spheres around a vertex v (all passing through v): see
/// [`star_axis`]. None when it is not determined (fewer than 3 spheres, condition below
/// [`STAR_AXIS_MIN_CONDITION`]) or at infinity.
pub fn second_common_point(spheres: &[Sphere], v: DVec3) -> Option<DVec3> {
    star_axis(spheres, v).filter(|a| a.condition >= STAR_AXIS_MIN_CONDITION).and_then(|a| a.second_point)
}

/// The node axes of a sphere mesh (Sec. 2.2), from [`node_axes`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NodeAxes {
    /// Per vertex: the vertex and its unit node axis, toward the support side.
    pub axes: Vec<(DVec3, DVec3)>,
    /// Per vertex: v̄ from the star's spheres (None where they do not determine it, or at
    /// infinity).
    pub second_points: Vec<Option<DVec3>>,
    /// Per vertex: whether its axis comes from its star's spheres ([`star_axis`] with condition
    /// at least [`STAR_AXIS_MIN_CONDITION`]).
    pub from_spheres: Vec<bool>,
}

impl NodeAxes {
    /// The axes as display segments (v, v + length · direction), toward the support side.
    pub fn segments(&self, length: f64) -> Vec<(DVec3, DVec3)> {
        self.axes.iter().filter_map(|&(v, d)| Some((v, v + length * d.try_normalize()?))).collect()
    }

    /// Per vertex: the angle (deg) between its node axis, as a line, and `normals[v]`.
    pub(crate) fn normal_angles_deg(&self, normals: &[DVec3]) -> Vec<f64> {
        self.axes.iter().zip(normals).map(|(&(_, d), n)| d.cross(*n).length().atan2(d.dot(*n).abs()).to_degrees()).collect()
    }

    /// Vertices whose axis comes from their star's spheres.
    pub(crate) fn count_from_spheres(&self) -> usize {
        self.from_spheres.iter().filter(|&&b| b).count()
    }
}

/// The node axes of the sphere mesh with vertices `positions`, connectivity `topo` and a sphere
/// per face: at v, the line v v̄ of [`star_axis`] when its condition reaches
/// [`STAR_AXIS_MIN_CONDITION`]; else `toward(v)`, projected into the plane of v's edge circle
/// ([`edge_circle`] with `plane`) when v has exactly one interior edge. Every axis is oriented
/// like `toward(v)`, the support side.
pub fn node_axes(
    positions: &[DVec3],
    topo: &Topology,
    spheres: &[Sphere],
    toward: &dyn Fn(usize) -> DVec3,
    plane: &dyn Fn([DVec3; 2]) -> EdgePlane,
    progress: &mut OnProgress,
) -> Result<NodeAxes, Cancelled> {
    let nv = positions.len();
    // The one interior edge of a vertex, where it has exactly one.
    let mut interior: Vec<(u32, Option<usize>)> = vec![(0, None); nv];
    for (e, edge) in topo.edges().iter().enumerate() {
        if topo.edge_faces(e).len() == 2 {
            for &v in edge {
                let slot = &mut interior[v as usize];
                slot.0 += 1;
                slot.1 = Some(e);
            }
        }
    }
    let mut out = NodeAxes { axes: Vec::with_capacity(nv), second_points: vec![None; nv], from_spheres: vec![false; nv] };
    let mut star = Vec::new();
    for v in 0..nv {
        if v % 1024 == 0 {
            progress(Progress::new("node_axes", v, nv))?;
        }
        let p = positions[v];
        let side = toward(v);
        star.clear();
        star.extend(topo.vertex_faces(v).iter().map(|&f| spheres[f as usize]));
        let direction = match star_axis(&star, p).filter(|a| a.condition >= STAR_AXIS_MIN_CONDITION) {
            Some(axis) => {
                out.second_points[v] = axis.second_point;
                out.from_spheres[v] = true;
                axis.direction
            }
            None => match interior[v] {
                (1, Some(e)) => {
                    let [(f, _), (g, _)] = topo.edge_faces(e) else { unreachable!("an interior edge has two faces") };
                    let ends = topo.edges()[e].map(|i| positions[i as usize]);
                    edge_circle(&spheres[*f as usize], Some(&spheres[*g as usize]), ends, plane(ends))
                        .and_then(|c| (side - side.dot(c.normal) * c.normal).try_normalize())
                        .unwrap_or(side)
                }
                _ => side,
            },
        };
        out.axes.push((p, if direction.dot(side) < 0.0 { -direction } else { direction }));
    }
    progress(Progress::new("node_axes", nv, nv))?;
    Ok(out)
}

/// A plane through an edge (u, w) that a method offers beside the radical plane of the edge's two
/// face spheres ([`edge_circle`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum EdgePlane {
    /// Through the edge and a point (m of Ω, Sec. 4): the radical plane in theory, as it contains
    /// both node axes; the better conditioned of the two is used.
    Through(DVec3),
    /// Through the edge, parallel to a direction (the axis a of a plane Ω): likewise.
    Parallel(DVec3),
    /// Through the edge with this normal, used only where the two spheres coincide (their
    /// common edge may then be any circle through u and w); a zero normal offers none.
    WhereCoincident(DVec3),
}

/// The circle of the arc of edge (u, w) on face sphere `s1` (and `s2`, the other face's sphere,
/// for an interior edge), with `plane` beside the radical plane of s1 and s2.
///
/// [`EdgePlane::Through`] and [`EdgePlane::Parallel`]: in theory the arc's plane is both the
/// radical plane and that plane, since it contains u, w, ū, w̄ and so both node axes.
/// Numerically the radical plane is ill-conditioned when the two spheres nearly coincide (its tilt
/// errs by ≈ ε / sin φ, φ the kink angle: 1e-7 rad at φ ≈ 1e-9 rad, which occurs after optimizing
/// R), and the other plane when m is nearly on the edge's line. So the better conditioned of the
/// two is used: the radical circle ([`Circle::intersection`]) when sin φ ≥ sin ∠(w − u, m − u)
/// (resp. ∠(w − u, a)), else the plane's cut of s1 (or s2 if s1 is a plane), its normal oriented
/// like c₁ − c₂. Boundary edges: the plane's cut.
///
/// [`EdgePlane::WhereCoincident`]: the radical circle, and the plane's cut of s1 where the two
/// spheres coincide (centres and radii within 1e-9 of the radius) or the edge is a boundary edge.
///
/// None when no real circle results (e.g. both spheres planes, or coincident spheres without a
/// plane).
pub fn edge_circle(s1: &Sphere, s2: Option<&Sphere>, [u, w]: [DVec3; 2], plane: EdgePlane) -> Option<Circle> {
    let e = w - u;
    let cut = |s: &Sphere, n: DVec3| Circle::plane_cut(s, u, n);
    let (n, q_plane) = match plane {
        EdgePlane::WhereCoincident(n) => {
            return match s2 {
                Some(s2) if !coincide(s1, s2) => Circle::intersection(s1, s2),
                _ => cut(s1, n),
            };
        }
        EdgePlane::Through(m) => {
            let n = e.cross(m - u);
            (n, n.length() / (e.length() * (m - u).length()))
        }
        EdgePlane::Parallel(a) => {
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
    let plane_circle = if s1.a != 0.0 { cut(s1, n) } else { s2.and_then(|s| cut(s, n)) };
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

/// Two spheres that are one: centres and radii within 1e-9 of the radius.
fn coincide(s1: &Sphere, s2: &Sphere) -> bool {
    match (s1.center().zip(s1.signed_radius()), s2.center().zip(s2.signed_radius())) {
        (Some((c1, r1)), Some((c2, r2))) => c1.distance(c2) + (r1 - r2).abs() <= 1e-9 * r1.abs().max(r2.abs()),
        _ => false,
    }
}

/// The torsion-free support structure of a sphere mesh (Sec. 2.2, 4, 5.2, Fig. 1): its node axes,
/// the planar support elements between them and their strips along the panels' arcs; the one
/// result shape of ST meshes with support structure and SQ meshes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SupportStructure {
    pub node_axes: NodeAxes,
    /// Depth of the support elements, along the node axes (absolute).
    pub depth: f64,
    pub elements: Vec<SupportElement>,
    /// The elements as strips along the panels' arcs.
    pub geometry: SupportGeometry,
    /// Length of the displayed axis segments (absolute).
    pub axis_length: f64,
}

impl SupportStructure {
    /// The node axes as display segments of `axis_length`, toward the support side.
    pub fn axis_segments(&self) -> Vec<(DVec3, DVec3)> {
        self.node_axes.segments(self.axis_length)
    }
}

/// A planar support element of an ST mesh with support structure (Sec. 2.2, 4, Fig. 1): the
/// annulus sector in the plane of an edge's circle, between the two node axes, bounded by the
/// edge arc (outer) and its offset toward m by the support depth (inner). Built by
/// [`support_element`]; the inner circle is concentric with the outer one (radius ∓ depth) where the node
/// axes reach it, else the circle through the offset corners and the offset arc midpoint.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SupportElement {
    /// The mesh edge (lo, hi), vertex ids.
    pub edge: [u32; 2],
    /// The circle of the edge arc, through both edge vertices; its normal is the element's plane
    /// normal.
    pub circle: Circle,
    /// The circle of the inner (offset) arc, in the same plane, through corners[2] and corners[3].
    pub inner_circle: Circle,
    /// [v_lo, v_hi, inner point on v_hi's node axis, inner point on v_lo's node axis]: the arc
    /// runs from corners[0] to corners[1] (the shorter way), the inner arc from corners[3] to
    /// corners[2].
    pub corners: [DVec3; 4],
}

/// Triangles of the support structure: one planar strip per support element.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SupportGeometry {
    pub positions: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
}

impl SupportGeometry {
    pub fn to_mesh(&self) -> TriMesh {
        TriMesh::new(self.positions.clone(), self.triangles.clone())
    }
}

impl SupportElement {
    /// The element as a strip of triangles between `outer`, points on its arc from `corners[0]`
    /// to `corners[1]` (the panels' own arc points), and as many points on its inner arc from
    /// `corners[3]` to `corners[2]`, at the same fractions of arc length and turning the same
    /// way about the element's normal. Positions alternate outer, inner; None for fewer than two
    /// outer points or a degenerate circle.
    pub fn strip(&self, outer: &[DVec3]) -> Option<(Vec<DVec3>, Vec<[u32; 3]>)> {
        let n = outer.len().checked_sub(1).filter(|&n| n >= 1)?;
        let normal = self.circle.normal;
        let in_plane = |c: &Circle, x: DVec3| {
            let d = x - c.center;
            (d - d.dot(normal) * normal).try_normalize()
        };
        let (outer_circle, inner_circle) = (Circle { normal, ..self.circle }, Circle { normal, ..self.inner_circle });
        let u = in_plane(&outer_circle, outer[0])?;
        let end = outer_circle.angle_of(u, outer[n]);
        // The way the outer arc turns: through its middle point (one segment: the minor arc).
        let sweep = if n == 1 {
            end
        } else {
            let mid = outer_circle.angle_of(u, outer[n / 2]);
            if mid * end > 0.0 && mid.abs() < end.abs() {
                end
            } else {
                end - std::f64::consts::TAU.copysign(end)
            }
        };
        let ui = in_plane(&inner_circle, self.corners[3])?;
        let mut inner_sweep = inner_circle.angle_of(ui, self.corners[2]);
        if inner_sweep * sweep < 0.0 {
            inner_sweep += std::f64::consts::TAU.copysign(sweep);
        }
        let lengths: Vec<f64> = outer.windows(2).map(|w| w[0].distance(w[1])).collect();
        let total: f64 = lengths.iter().sum();
        if !(total > 0.0) || !inner_sweep.is_finite() {
            return None;
        }
        let mut positions = Vec::with_capacity(2 * (n + 1));
        let mut walked = 0.0;
        for (j, &x) in outer.iter().enumerate() {
            let y = match j {
                0 => self.corners[3],
                _ if j == n => self.corners[2],
                _ => inner_circle.point_at(ui, inner_sweep * walked / total),
            };
            positions.push(x);
            positions.push(y);
            walked += lengths.get(j).copied().unwrap_or(0.0);
        }
        let triangles = (0..n as u32)
            .flat_map(|j| {
                let (x0, y0, x1, y1) = (2 * j, 2 * j + 1, 2 * j + 2, 2 * j + 3);
                [[x0, x1, y1], [x0, y1, y0]]
            })
            .collect();
        Some((positions, triangles))
    }
}

/// The strips of `elements` ([`SupportElement::strip`]), each along the arc points
/// `outer(element)` gives (from the element's `edge[0]` to `edge[1]`); elements without arc
/// points or with a degenerate strip are left out.
pub fn support_strips(elements: &[SupportElement], outer: impl Fn(&SupportElement) -> Option<Vec<DVec3>>) -> SupportGeometry {
    let mut out = SupportGeometry::default();
    for el in elements {
        let Some((positions, triangles)) = outer(el).and_then(|pts| el.strip(&pts)) else { continue };
        let base = out.positions.len() as u32;
        out.positions.extend(positions);
        out.triangles.extend(triangles.into_iter().map(|t| t.map(|i| i + base)));
    }
    out
}

/// The annulus sector of an edge: outer arc on `circle`, inner arc on the concentric circle of
/// radius ρ ∓ depth (toward the side the node axes point to), corners where the node axes (projected
/// into the plane) meet it. Falls back to the corners v + depth·d and the circle through them and
/// the offset arc midpoint when an axis does not reach the concentric circle.
pub fn support_element(edge: [u32; 2], circle: Circle, p: [DVec3; 2], dirs: [DVec3; 2], depth: f64) -> Option<SupportElement> {
    if !(depth > 0.0 && depth.is_finite()) {
        return None;
    }
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
            (Circle::through(a, b, mid)?, [p[0], p[1], b, a])
        }
    };
    corners.iter().all(|c| c.is_finite()).then_some(SupportElement { edge, circle, inner_circle: inner, corners })
}
