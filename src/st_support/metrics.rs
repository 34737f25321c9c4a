//! The figures of an ST mesh with support structure (Sec. 4), measured on the result: vertices
//! on their spheres, spheres orthogonal to Ω (or centres in the plane Ω), node axes through m,
//! axis–normal angles and kinks.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::congruence::support_structure::NodeAxes;
use crate::geometry::absolute_sphere::AbsoluteSphere;
use crate::panels::sphere_mesh::SphereMesh;
use crate::stats::mean;

/// The metrics of the method (lengths relative to the bbox diagonal, angles in degrees), without
/// `max_distance_to_reference` (measured on the tessellated panels against the original
/// reference when the schedule is built), plus counts that qualify them.
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
    /// Sliver faces (their sphere is unreliable) and faces whose sphere could not be made
    /// orthogonal to Ω (they keep their triangle's plane).
    pub degenerate_faces: usize,
    /// Edges without a support element (both face spheres planes, or no circle).
    pub edges_without_support: usize,
}

/// Counts the figures qualify, from the steps that made the result.
pub struct Counts {
    pub degenerate_faces: usize,
    pub edges_without_support: usize,
}

/// The figures of `sphere_mesh` (diagonal `diag`) against `omega`, with its node axes and the
/// reference normals.
pub fn metrics(sphere_mesh: &SphereMesh, omega: &AbsoluteSphere, axes: &NodeAxes, normals: &[DVec3], diag: f64, counts: Counts) -> StSupportMetrics {
    let mesh = &sphere_mesh.mesh;
    let kinks = sphere_mesh.kink_angles_deg();
    let mut metrics = StSupportMetrics {
        degenerate_faces: counts.degenerate_faces,
        edges_without_support: counts.edges_without_support,
        interior_edges: kinks.len(),
        ..Default::default()
    };
    for (f, s) in sphere_mesh.face_spheres.iter().enumerate() {
        for p in mesh.face_points(f) {
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
    let m = omega.center();
    let angles = axes.normal_angles_deg(normals);
    metrics.max_axis_normal_angle_deg = angles.iter().copied().fold(0.0, f64::max);
    for (v, &(p, d)) in axes.axes.iter().enumerate() {
        if axes.from_spheres[v] {
            metrics.axes_from_spheres += 1;
            let offset = match (m, omega) {
                (Some(m), _) => (m - p).cross(d).length() / diag,
                (None, AbsoluteSphere::Plane { axis, .. }) => d.cross(*axis).length(),
                _ => 0.0,
            };
            metrics.max_node_axis_offset = metrics.max_node_axis_offset.max(offset);
        }
    }
    metrics.mean_axis_normal_angle_deg = angles.iter().sum::<f64>() / angles.len() as f64;
    metrics.mean_kink_angle_deg = mean(&kinks);
    metrics.max_kink_angle_deg = kinks.iter().copied().fold(0.0, f64::max);
    metrics
}
