//! The SQ mesh with support structure out of the final optimization (Sec. 5.2, Fig. 19, 25):
//! spherical quad panels, node axes, planar support elements, and the figures of exactness.
//!
//! - **Panels**: every face a spherical quad bounded by four circular arcs
//!   ([`crate::panels::build_panels`], variant (a)): an interior edge's arc is the intersection
//!   circle of its two face spheres through its end vertices. A boundary edge's arc is its face
//!   sphere cut by the plane through the edge that contains the mean of its two node axes, the
//!   plane its support element would lie in.
//! - **Node axes** ([`crate::congruence::support_structure::node_axes`], the one definition):
//!   the line through the vertex and the second common point of its spheres, computed from the
//!   spheres, not assumed; where they do not determine it (a boundary vertex of two faces, a
//!   corner), the reference normal, projected into the plane of the vertex's one edge circle
//!   where it has one. Axes point to the side of the sphere centres (the support side).
//! - **Support elements**: per interior edge, the planar element in the plane of the edge's circle
//!   between the two node axes, of the settable depth
//!   ([`crate::congruence::support_structure::support_element`]), tessellated along the panels'
//!   own arc points.

// Negated float comparisons are deliberate: they also reject NaN.

use std::collections::HashMap;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::congruence::support_structure::{edge_circle, node_axes, support_element, support_strips, EdgePlane, NodeAxes, SupportStructure};
use crate::geometry::linalg::Svd;
use crate::geometry::mesh::PolyMesh;
use crate::geometry::sphere::Sphere;
use crate::panels::panel::Panel;
use crate::panels::sphere_mesh::{BoundaryArcRule, SphereMesh};
use crate::panels::{build_panels, edge_arc_points, DEFAULT_CHORD_TOLERANCE};

use super::sphere_optimization::QuadStars;

/// How exact the SQ mesh is (lengths relative to the bounding-box diagonal).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SqMeshFigures {
    /// max over faces and corners of |dist(v, sphere)|.
    #[serde(deserialize_with = "crate::guarantees::f64_or_nan")]
    pub max_vertex_sphere_residual: f64,
    /// max over inner vertices of the distance of their four sphere centres to the
    /// least-squares plane through them.
    #[serde(deserialize_with = "crate::guarantees::f64_or_nan")]
    pub max_centre_face_planarity: f64,
    /// max over interior edges whose ends both have axes from spheres of |⟨l, n_uw⟩| for both
    /// axes l, n_uw the unit normal of the edge's circle (its torsal plane): the sine of the angle
    /// between axis and plane.
    #[serde(deserialize_with = "crate::guarantees::f64_or_nan")]
    pub max_torsal_plane_residual: f64,
    /// Angle between node axes and the reference normals (deg).
    #[serde(deserialize_with = "crate::guarantees::f64_or_nan")]
    pub max_axis_normal_angle_deg: f64,
    #[serde(deserialize_with = "crate::guarantees::f64_or_nan")]
    pub mean_axis_normal_angle_deg: f64,
    /// min over inner vertices of four edges of the angle between the support planes of two
    /// consecutive edges.
    #[serde(deserialize_with = "crate::guarantees::f64_or_nan")]
    pub min_torsal_plane_angle_deg: f64,
    /// The same at the singular vertices of three and of five edges (None without any), for the
    /// bound of [`super::sphere_terms::support_plane_bound_deg`].
    pub min_support_plane_angle_valence_3_deg: Option<f64>,
    pub min_support_plane_angle_valence_5_deg: Option<f64>,
    /// The first inner vertex whose support planes cannot be measured (two consecutive face
    /// spheres meet in no circle through their edge), if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unmeasured_support_planes: Option<u32>,
    /// max distance of a vertex to the reference.
    #[serde(deserialize_with = "crate::guarantees::f64_or_nan")]
    pub max_vertex_distance_to_reference: f64,
    /// Vertices whose node axis comes from three or more spheres.
    pub axes_from_spheres: usize,
}

/// The SQ mesh with its panels and support structure (model units).
#[derive(Clone, Debug)]
pub struct SqMesh {
    pub sphere_mesh: SphereMesh,
    pub panels: Vec<Panel>,
    /// Node axes toward the support side, support elements and their strips.
    pub support: SupportStructure,
    pub figures: SqMeshFigures,
}

/// The unit normal of the support plane of edge uw between two face spheres: the plane of their
/// circle; where the two spheres coincide (panels of one sphere, whose common edge may be any
/// circle through u and w), the plane through the edge and the mean of its node axes `axes`.
pub(crate) fn support_plane_normal(s1: &Sphere, s2: &Sphere, [u, w]: [DVec3; 2], axes: [DVec3; 2]) -> Option<DVec3> {
    let substitute = (w - u).cross(axes[0] + axes[1]);
    edge_circle(s1, Some(s2), [u, w], EdgePlane::WhereCoincident(substitute)).map(|c| c.normal)
}

/// Builds the SQ mesh from the optimized vertices and face spheres (model units); `normals` are
/// the reference normals at the vertices; `depth` and `axis_length` absolute.
pub fn sq_mesh(mesh: PolyMesh, spheres: Vec<Sphere>, normals: &[DVec3], stars: &QuadStars, diag: f64, depth: f64, axis_length: f64) -> SqMesh {
    let sm = SphereMesh::new(mesh, spheres, BoundaryArcRule::Parallel(DVec3::ZERO));
    let node_axes = support_side_axes(&sm, normals);
    let axes = &node_axes.axes;
    let topo = sm.topology();
    let mut planes = HashMap::new();
    for (e, &[lo, hi]) in topo.edges().iter().enumerate() {
        if topo.edge_faces(e).len() == 1 {
            let (p, q) = (sm.mesh.positions[lo as usize], sm.mesh.positions[hi as usize]);
            let d = axes[lo as usize].1 + axes[hi as usize].1;
            if let Some(n) = (q - p).cross(d).try_normalize() {
                planes.insert([lo, hi], n);
            }
        }
    }
    let sm = sm.with_boundary_planes(planes);
    let panels = build_panels(&sm, DEFAULT_CHORD_TOLERANCE * diag);
    let topo = sm.topology();
    let mut support_elements = Vec::new();
    for (e, &[lo, hi]) in topo.edges().iter().enumerate() {
        let faces = topo.edge_faces(e);
        if faces.len() != 2 {
            continue;
        }
        let (f, k) = faces[0];
        let circle = panels[f as usize].arcs[k as usize].circle;
        let (u, w) = (sm.mesh.positions[lo as usize], sm.mesh.positions[hi as usize]);
        if let Some(el) = support_element([lo, hi], circle, [u, w], [axes[lo as usize].1, axes[hi as usize].1], depth) {
            support_elements.push(el);
        }
    }
    let support_geometry = support_strips(&support_elements, |el| edge_arc_points(&sm, &panels, el.edge));
    let figures = figures(&sm, &node_axes, normals, stars, diag);
    SqMesh {
        sphere_mesh: sm,
        panels,
        support: SupportStructure { node_axes, depth, elements: support_elements, geometry: support_geometry, axis_length },
        figures,
    }
}

/// The node axes of the SQ mesh: toward the side of the sphere centres around each vertex, the
/// reference normal where the spheres do not determine them.
fn support_side_axes(sm: &SphereMesh, normals: &[DVec3]) -> NodeAxes {
    let (mesh, spheres) = (&sm.mesh, &sm.face_spheres);
    let topo = sm.topology();
    let toward = |v: usize| {
        let p = mesh.positions[v];
        let side: f64 = topo.vertex_faces(v).iter().filter_map(|&f| spheres[f as usize].center()).map(|c| (c - p).dot(normals[v])).sum();
        if side < 0.0 {
            -normals[v]
        } else {
            normals[v]
        }
    };
    let none = |_: [DVec3; 2]| EdgePlane::WhereCoincident(DVec3::ZERO);
    node_axes(&mesh.positions, topo, spheres, &toward, &none, &mut crate::progress::ignore).expect("ignore never cancels")
}

/// The smaller of two figures, NaN when either is (a figure that cannot be measured fails).
fn nan_min(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else {
        a.min(b)
    }
}

/// The smallest angle (deg) between the support planes of consecutive edges at vertex `v`, whose
/// faces are `faces` in order around it: the planes of consecutive face pairs, whose shared edge
/// runs from v to their other common corner. NaN when a plane cannot be measured.
pub fn star_support_plane_angle_deg(sm: &SphereMesh, axes: &[(DVec3, DVec3)], v: u32, faces: &[u32]) -> f64 {
    let (mesh, spheres) = (&sm.mesh, &sm.face_spheres);
    let m = faces.len();
    let p = mesh.positions[v as usize];
    let planes: Vec<Option<DVec3>> = (0..m)
        .map(|k| {
            let (f, g) = (faces[k] as usize, faces[(k + 1) % m] as usize);
            let other = mesh.faces[f].corners().iter().copied().find(|&c| c != v && mesh.faces[g].corners().contains(&c))?;
            support_plane_normal(&spheres[f], &spheres[g], [p, mesh.positions[other as usize]], [axes[v as usize].1, axes[other as usize].1])
        })
        .collect();
    (0..m)
        .map(|k| match (planes[k], planes[(k + 1) % m]) {
            (Some(a), Some(b)) => a.dot(b).abs().min(1.0).acos().to_degrees(),
            _ => f64::NAN,
        })
        .fold(90.0, nan_min)
}

/// The figures of [`SqMeshFigures`] except the distance to the reference.
fn figures(sm: &SphereMesh, node_axes: &NodeAxes, normals: &[DVec3], stars: &QuadStars, diag: f64) -> SqMeshFigures {
    let (axes, from_spheres) = (&node_axes.axes, &node_axes.from_spheres);
    let spheres = &sm.face_spheres;
    let mut out = SqMeshFigures { min_torsal_plane_angle_deg: 90.0, ..SqMeshFigures::default() };
    out.max_vertex_sphere_residual = sm.max_vertex_sphere_residual() / diag;
    for (v, faces) in &stars.stars {
        let m = faces.len();
        let centres: Vec<DVec3> = faces.iter().filter_map(|&f| spheres[f as usize].center()).collect();
        if centres.len() < m {
            out.max_centre_face_planarity = f64::INFINITY;
            continue;
        }
        let mid = centres.iter().sum::<DVec3>() / m as f64;
        let rows: Vec<[f64; 3]> = centres.iter().map(|c| (*c - mid).to_array()).collect();
        let n = DVec3::from_array(Svd::new(&rows).v[2]).normalize_or_zero();
        let worst = centres.iter().map(|c| (*c - mid).dot(n).abs()).fold(0.0, f64::max);
        out.max_centre_face_planarity = out.max_centre_face_planarity.max(worst / diag);
        let star_min = star_support_plane_angle_deg(sm, axes, *v, faces);
        if star_min.is_nan() {
            out.unmeasured_support_planes.get_or_insert(*v);
        }
        if m == 4 {
            out.min_torsal_plane_angle_deg = nan_min(out.min_torsal_plane_angle_deg, star_min);
        } else {
            let slot = if m == 3 { &mut out.min_support_plane_angle_valence_3_deg } else { &mut out.min_support_plane_angle_valence_5_deg };
            *slot = Some(slot.map_or(star_min, |a| nan_min(a, star_min)));
        }
    }
    let topo = sm.topology();
    for (e, &[u, w]) in topo.edges().iter().enumerate() {
        let [(f, _), (g, _)] = topo.edge_faces(e) else {
            continue;
        };
        if !(from_spheres[u as usize] && from_spheres[w as usize]) {
            continue;
        }
        let ends = [sm.mesh.positions[u as usize], sm.mesh.positions[w as usize]];
        let plane = EdgePlane::WhereCoincident(DVec3::ZERO);
        if let Some(c) = edge_circle(&spheres[*f as usize], Some(&spheres[*g as usize]), ends, plane) {
            let (du, dw) = (axes[u as usize].1, axes[w as usize].1);
            out.max_torsal_plane_residual = out.max_torsal_plane_residual.max(du.dot(c.normal).abs()).max(dw.dot(c.normal).abs());
        }
    }
    let angles = node_axes.normal_angles_deg(normals);
    out.max_axis_normal_angle_deg = angles.iter().copied().fold(0.0, f64::max);
    out.mean_axis_normal_angle_deg = angles.iter().sum::<f64>() / angles.len().max(1) as f64;
    out.axes_from_spheres = node_axes.count_from_spheres();
    out
}
