//! `report.json`: the run report every method writes, typed.
//!
//! ```json
//! {"method": "st-support",
//!  "input":  {"vertices": N, "faces": N},
//!  "output": {"vertices": N, "faces": N, "panels": N},
//!  "absolute_sphere": {"center": [x,y,z], "r2": x, "at_infinity": false, "axis": null},
//!  "metrics": {"max_vertex_sphere_residual": x, ...},
//!  "timings_ms": {"<stage>": x, ...}}
//! ```
//!
//! Lengths in `metrics` are relative to the reference's bounding-box diagonal; angles are in
//! degrees. Metrics a method does not compute are `None` and left out of the JSON.
//! `absolute_sphere` is left out for methods without one. Timings are in milliseconds, keyed by
//! stage name (sorted). Non-finite numbers are written as null.

use std::collections::BTreeMap;
use std::io;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::geometry::absolute_sphere::AbsoluteSphere;
use crate::guarantees::{Guarantee, Verdict};
use crate::remeshing::Sizing;
use crate::sq::params::RadiusBasis;

/// Vertex and face counts of the input mesh.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct InputCounts {
    pub vertices: usize,
    pub faces: usize,
}

/// Vertex, face and panel counts of the result (the mesh with spherical faces).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct OutputCounts {
    pub vertices: usize,
    pub faces: usize,
    pub panels: usize,
}

/// Ω in the report. At infinity, `center` and `r2` are null and `axis` (with the plane offset
/// `d`, ⟨x, axis⟩ = d) is set; otherwise `axis` is null and `d` is left out.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AbsoluteSphereReport {
    pub center: Option<[f64; 3]>,
    pub r2: Option<f64>,
    pub at_infinity: bool,
    pub axis: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub d: Option<f64>,
}

impl From<&AbsoluteSphere> for AbsoluteSphereReport {
    fn from(o: &AbsoluteSphere) -> Self {
        match *o {
            AbsoluteSphere::Sphere { center, r2 } => Self {
                center: Some(center.to_array()),
                r2: Some(r2),
                at_infinity: false,
                axis: None,
                d: None,
            },
            AbsoluteSphere::Plane { axis, d } => Self {
                center: None,
                r2: None,
                at_infinity: true,
                axis: Some(axis.to_array()),
                d: Some(d),
            },
        }
    }
}

/// The metrics of a run; `None` when a method has no such metric.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Metrics {
    /// max over panels and their corners of | |v − c| − r |, relative.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_vertex_sphere_residual: Option<f64>,
    /// max |(|c − m|² − r² − R²)| / diag² (0 if Ω is at infinity).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_orthogonality_residual: Option<f64>,
    /// max distance from m to each node axis (computed from the star's spheres), relative.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_node_axis_offset: Option<f64>,
    /// Node axis vs reference normal, degrees.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mean_axis_normal_angle_deg: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_axis_normal_angle_deg: Option<f64>,
    /// Kink angle between adjacent panels, degrees.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mean_kink_angle_deg: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_kink_angle_deg: Option<f64>,
    /// Sampled over the panel surfaces, relative.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_distance_to_reference: Option<f64>,
    /// Solver iterations of the angle optimization.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub angle_iterations: Option<usize>,
    /// Vertices whose node axis comes from their star's spheres.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub axes_from_spheres: Option<usize>,
    /// Faces whose sphere could not be made orthogonal to Ω.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub degenerate_faces: Option<usize>,
    /// Distinct panel radii after rounding to the radius tolerance (planes count as one more).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub distinct_radii: Option<usize>,
    /// Faces whose normal points against the reference normal at their centroid.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flipped_faces: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub initial_flipped_faces: Option<usize>,
    /// Kink angles before optimizing, degrees.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub initial_max_kink_angle_deg: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub initial_mean_kink_angle_deg: Option<f64>,
    /// Ω a plane: max distance of a face sphere's centre from it, relative.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_center_plane_residual: Option<f64>,
    /// Variant (b): the largest gap between the two arcs of an edge, relative.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_gap: Option<f64>,
    /// Variant (b): the same gap, measured on the exported panels' arcs, relative.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_panel_arc_gap: Option<f64>,
    /// Largest vertex distance to the reference, relative.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_vertex_distance_to_reference: Option<f64>,
    /// How the reference was remeshed first.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub remesh: Option<Sizing>,
    /// Edge variant (Fig. 12): "a" or "b".
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub variant: Option<String>,
    /// SQ (Sec. 5.1): the largest angle between a line of the congruence and the normal on G,
    /// degrees; before the optimization (the central congruence of the fitted r) and after.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_line_normal_angle_deg: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub initial_max_line_normal_angle_deg: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mean_line_normal_angle_deg: Option<f64>,
    /// SQ: the smallest angle between the two torsal planes of a grid quad, degrees.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min_torsal_plane_angle_deg: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub initial_min_torsal_plane_angle_deg: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mean_torsal_plane_angle_deg: Option<f64>,
    /// SQ: grid quads whose torsal directions are not real.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub quads_without_real_torsal_directions: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub initial_quads_without_real_torsal_directions: Option<usize>,
    /// SQ: E_LC per term (dimensionless, c_u and c_v normalized) after both steps, and after
    /// step 1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lc_residual: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lc_residual_step1: Option<f64>,
    /// SQ: largest |r − 1/H| of the radius fit on G, relative to the mean |1/H|.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius_fit_error: Option<f64>,
    /// SQ: solver iterations of the line-congruence and the torsal step.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub line_congruence_iterations: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub torsal_iterations: Option<usize>,
    /// SQ (Sec. 5.2): max over inner vertices of the distance of their face centres to the plane
    /// through them, relative.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_centre_face_planarity: Option<f64>,
    /// SQ: max over interior edges of |⟨l, n_uw⟩| for the node axes l at both ends and the unit
    /// normal n_uw of the edge's torsal plane (the plane of its circle).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_torsal_plane_residual: Option<f64>,
    /// SQ: the congruence's min torsal-plane angle on G when the run went on to the SQ mesh
    /// (then `min_torsal_plane_angle_deg` is the mesh's, between the support planes at a node).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub congruence_min_torsal_plane_angle_deg: Option<f64>,
    /// SQ: angle between the mesh edges and the torsal directions at the edge midpoints, deg
    /// (edges not along the patch boundary).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mean_edge_torsal_angle_deg: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_edge_torsal_angle_deg: Option<f64>,
    /// SQ: the covered share of the patch's area.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub coverage: Option<f64>,
    /// SQ: iterations of the final optimization (warm-up, full, projection).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub final_iterations: Option<[usize; 3]>,
}

/// The report of one run.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Report {
    pub method: String,
    pub input: InputCounts,
    pub output: OutputCounts,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub absolute_sphere: Option<AbsoluteSphereReport>,
    pub metrics: Metrics,
    pub timings_ms: BTreeMap<String, f64>,
    /// SQ (Sec. 5): the parameters of the run: solver iterations in all, points per direction of
    /// G, θ and α (degrees), the basis of r, and the stage the run stopped after.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub iterations: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub grid: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub theta_deg: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub alpha_deg: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius_basis: Option<RadiusBasis>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stopped_after: Option<String>,
    /// What a user should know about the run (e.g. a boundary strip of the other sign of H).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// Whether the result meets every guarantee of its method ([`crate::guarantees`]), and
    /// each guarantee with its measured figure; left out by a method that measures none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub meets_guarantees: Option<bool>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub guarantees: Vec<Guarantee>,
}

impl Report {
    pub fn new(method: impl Into<String>) -> Self {
        Self {
            method: method.into(),
            ..Self::default()
        }
    }

    /// The report of a panel method: the counts of its input and output, Ω if it has one, its
    /// metrics and its step timings (ms, in order; a repeated step adds up).
    pub fn for_panels(
        method: &str,
        input: InputCounts,
        output: OutputCounts,
        absolute_sphere: Option<&AbsoluteSphere>,
        metrics: Metrics,
        timings: &[(String, f64)],
    ) -> Self {
        let mut r = Self::new(method);
        r.input = input;
        r.output = output;
        r.absolute_sphere = absolute_sphere.map(AbsoluteSphereReport::from);
        r.metrics = metrics;
        for (step, ms) in timings {
            r.add_timing(step.clone(), *ms);
        }
        r
    }

    /// Records the verdict of the run.
    pub fn set_verdict(&mut self, verdict: &Verdict) {
        self.meets_guarantees = Some(verdict.holds());
        self.guarantees = verdict.guarantees.clone();
    }

    /// The missed guarantees in one line, "" when there are none.
    pub fn failure_text(&self) -> String {
        Verdict::new(self.guarantees.clone()).failure_text()
    }

    /// Records a stage time (ms); a repeated stage adds up.
    pub fn add_timing(&mut self, stage: impl Into<String>, ms: f64) {
        *self.timings_ms.entry(stage.into()).or_insert(0.0) += ms;
    }

    /// Pretty-printed JSON with a trailing newline.
    pub fn to_json(&self) -> String {
        let mut s = serde_json::to_string_pretty(self).expect("the report serializes");
        s.push('\n');
        s
    }

    pub fn from_json(text: &str) -> serde_json::Result<Self> {
        serde_json::from_str(text)
    }

    /// Writes `dir/report.json` (creating `dir`); returns the path.
    pub fn write(&self, dir: &Path) -> io::Result<PathBuf> {
        std::fs::create_dir_all(dir)?;
        let path = dir.join("report.json");
        std::fs::write(&path, self.to_json())?;
        Ok(path)
    }
}
