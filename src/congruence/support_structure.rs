//! The support structure of an ST mesh (Sec. 2.2, 4, Fig. 1): node axes, the planar support
//! elements between them, and their tessellation for display and export.
//!
//! **Node axes.** The face spheres around a vertex v pass through v and a second common point v̄;
//! the node axis is the line v v̄ ([`star_axis`]). For an ST mesh with support structure every
//! node axis passes through the centre m of the absolute sphere Ω (Sec. 2.4).
//!
//! **Support elements.** Per edge, the annulus sector in the plane of the edge's circle between
//! the two node axes ([`support_element`]); [`support_strips`] tessellates them along the panels'
//! own arc points, so the support meets the panels exactly.

// Negated float comparisons are deliberate: they also reject NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::geometry::circle::Circle;
use crate::geometry::linalg::Svd;
use crate::geometry::mesh::TriMesh;
use crate::geometry::sphere::Sphere;

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
        let condition = if svd.sigma[0] > 0.0 {
            svd.sigma[1] / svd.sigma[0]
        } else {
            0.0
        };
        let direction = DVec3::from_array(svd.v[2]).try_normalize()?;
        return Some(StarAxis {
            direction,
            second_point: None,
            condition,
        });
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
    let condition = if svd.sigma[0] > 0.0 {
        svd.sigma[2] / svd.sigma[0]
    } else {
        0.0
    };
    let [lx, ly, lz, tau] = svd.v[3];
    let l = DVec3::new(lx, ly, lz);
    let l2 = l.length_squared();
    if !(l2 > 0.0) {
        return None;
    }
    let direction = l / l2.sqrt();
    let second = v + (scale * tau / l2) * l;
    Some(StarAxis {
        direction,
        second_point: second.is_finite().then_some(second),
        condition,
    })
}

/// The second common point v̄ of the spheres around a vertex v (all passing through v): see
/// [`star_axis`]. None when it is not determined (fewer than 3 spheres, condition below
/// [`STAR_AXIS_MIN_CONDITION`]) or at infinity.
pub fn second_common_point(spheres: &[Sphere], v: DVec3) -> Option<DVec3> {
    star_axis(spheres, v)
        .filter(|a| a.condition >= STAR_AXIS_MIN_CONDITION)
        .and_then(|a| a.second_point)
}

/// The torsion-free support structure of an ST mesh (Sec. 2.2, 4, Fig. 1).
#[derive(Clone, Debug, PartialEq)]
pub struct SupportStructure {
    /// Per vertex: a point on the node axis (the vertex itself) and its unit direction, pointing
    /// from the vertex toward the support side (toward m, or along −a).
    pub node_axes: Vec<(DVec3, DVec3)>,
    /// Depth of the planar support elements, along the node axes.
    pub depth: f64,
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

impl SupportStructure {
    /// The node axes as display segments (v, v + length · direction), toward the support side.
    pub fn axis_segments(&self, length: f64) -> Vec<(DVec3, DVec3)> {
        self.node_axes
            .iter()
            .filter_map(|&(v, d)| {
                let d = d.try_normalize()?;
                Some((v, v + length * d))
            })
            .collect()
    }
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
        let (outer_circle, inner_circle) = (
            Circle {
                normal,
                ..self.circle
            },
            Circle {
                normal,
                ..self.inner_circle
            },
        );
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
pub fn support_strips(
    elements: &[SupportElement],
    outer: impl Fn(&SupportElement) -> Option<Vec<DVec3>>,
) -> SupportGeometry {
    let mut out = SupportGeometry::default();
    for el in elements {
        let Some((positions, triangles)) = outer(el).and_then(|pts| el.strip(&pts)) else {
            continue;
        };
        let base = out.positions.len() as u32;
        out.positions.extend(positions);
        out.triangles
            .extend(triangles.into_iter().map(|t| t.map(|i| i + base)));
    }
    out
}

/// The annulus sector of an edge: outer arc on `circle`, inner arc on the concentric circle of
/// radius ρ ∓ depth (toward the side the node axes point to), corners where the node axes (projected
/// into the plane) meet it. Falls back to the corners v + depth·d and the circle through them and
/// the offset arc midpoint when an axis does not reach the concentric circle.
pub fn support_element(
    edge: [u32; 2],
    circle: Circle,
    p: [DVec3; 2],
    dirs: [DVec3; 2],
    depth: f64,
) -> Option<SupportElement> {
    if !(depth > 0.0 && depth.is_finite()) {
        return None;
    }
    let n = circle.normal;
    let d: [DVec3; 2] = [0, 1].map(|k| {
        (dirs[k] - dirs[k].dot(n) * n)
            .try_normalize()
            .unwrap_or(dirs[k])
    });
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
        let t = [-q - s, -q + s]
            .into_iter()
            .filter(|t| *t > 0.0)
            .fold(f64::INFINITY, f64::min);
        t.is_finite().then(|| p[k] + t * d[k])
    };
    let (inner, corners) = match (hit(0), hit(1)) {
        (Some(a), Some(b)) => (
            Circle {
                center: circle.center,
                normal: n,
                radius: inner_r,
            },
            [p[0], p[1], b, a],
        ),
        _ => {
            let (a, b) = (p[0] + depth * d[0], p[1] + depth * d[1]);
            let mid_dir = (0.5 * (p[0] + p[1]) - circle.center).try_normalize()?;
            let mid = circle.center + rho * mid_dir + depth * (d[0] + d[1]).try_normalize()?;
            (Circle::through(a, b, mid)?, [p[0], p[1], b, a])
        }
    };
    corners
        .iter()
        .all(|c| c.is_finite())
        .then_some(SupportElement {
            edge,
            circle,
            inner_circle: inner,
            corners,
        })
}
