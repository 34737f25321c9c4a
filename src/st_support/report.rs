//! The section `"st-support"` of `report.json` (Sec. 4): Ω, how the reference was remeshed, and
//! the figures of the support structure beyond the shared panel metrics.

use serde::{Deserialize, Serialize};

use super::moulds::StSupportMouldRound;
use super::StSupportResult;
use crate::geometry::absolute_sphere::AbsoluteSphere;
use crate::guarantees::f64_or_nan;
use crate::panels::moulds::{MouldOutcome, MouldRoundsSection};
use crate::remeshing::Sizing;

/// Ω in the report. At infinity, `center` and `r2` are null and `axis` (with the plane offset
/// `d`, ⟨x, axis⟩ = d) is set; otherwise `axis` is null and `d` is left out.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AbsoluteSphereSection {
    pub center: Option<[f64; 3]>,
    pub r2: Option<f64>,
    pub at_infinity: bool,
    pub axis: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub d: Option<f64>,
}

impl From<&AbsoluteSphere> for AbsoluteSphereSection {
    fn from(o: &AbsoluteSphere) -> Self {
        match *o {
            AbsoluteSphere::Sphere { center, r2 } => Self { center: Some(center.to_array()), r2: Some(r2), at_infinity: false, axis: None, d: None },
            AbsoluteSphere::Plane { axis, d } => Self { center: None, r2: None, at_infinity: true, axis: Some(axis.to_array()), d: Some(d) },
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StSupportSection {
    /// The Ω the face spheres are orthogonal to.
    pub absolute_sphere: AbsoluteSphereSection,
    /// How the reference was remeshed first.
    pub remesh: Sizing,
    /// max over faces and their corners of | |v − c| − r |, relative to the diagonal.
    #[serde(deserialize_with = "f64_or_nan")]
    pub max_vertex_sphere_residual: f64,
    /// max |(|c − m|² − r² − R²)| / diag² (0 if Ω is at infinity).
    #[serde(deserialize_with = "f64_or_nan")]
    pub max_orthogonality_residual: f64,
    /// Ω a plane: max distance of a face sphere's centre from it, relative.
    #[serde(deserialize_with = "f64_or_nan")]
    pub max_center_plane_residual: f64,
    /// max distance from m to each node axis computed from its star's spheres, relative.
    #[serde(deserialize_with = "f64_or_nan")]
    pub max_node_axis_offset: f64,
    /// Node axis against the reference normal (degrees).
    #[serde(deserialize_with = "f64_or_nan")]
    pub mean_axis_normal_angle_deg: f64,
    #[serde(deserialize_with = "f64_or_nan")]
    pub max_axis_normal_angle_deg: f64,
    /// Vertices whose node axis comes from their star's spheres.
    pub axes_from_spheres: usize,
    /// Faces whose sphere could not be made orthogonal to Ω, and slivers.
    pub degenerate_faces: usize,
    /// The rounds toward fewer moulds (`optimize_moulds`); their distance is the panels'.
    #[serde(flatten)]
    pub moulds: MouldRoundsSection<StSupportMouldRound>,
}

impl StSupportSection {
    pub fn of(result: &StSupportResult, remesh: Sizing) -> Self {
        let m = &result.metrics;
        Self {
            absolute_sphere: (&result.omega).into(),
            remesh,
            max_vertex_sphere_residual: m.max_vertex_sphere_residual,
            max_orthogonality_residual: m.max_orthogonality_residual,
            max_center_plane_residual: m.max_center_plane_residual,
            max_node_axis_offset: m.max_node_axis_offset,
            mean_axis_normal_angle_deg: m.mean_axis_normal_angle_deg,
            max_axis_normal_angle_deg: m.max_axis_normal_angle_deg,
            axes_from_spheres: m.axes_from_spheres,
            degenerate_faces: m.degenerate_faces,
            moulds: MouldOutcome::section(result.moulds.as_ref()),
        }
    }
}
