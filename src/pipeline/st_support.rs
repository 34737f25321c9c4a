//! The "ST with support structure" method end to end (Sec. 4, issue 3): face spheres orthogonal
//! to Ω, node axes, support elements, panels, exports and the shared report. Used by the worker
//! session and by `spherical-faces st-support`.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::protocol::Field;
use crate::absolute_sphere::Histogram;
use crate::absolute_sphere::{estimate_absolute_sphere, AbsoluteSphereParams};
use crate::curvature::{jet_fit, CurvatureField, JetParams};
use crate::remesh::{local_spheres_orthogonal, mean_edge_length, pliant_remesh, RemeshParams, SizingBounds, SizingField};
use crate::st_angle::StSizing;
use crate::export::{self, AbsoluteSphereReport, Metrics, Report, SupportGeometry};
use crate::mesh::{Topology, TriMesh};
use crate::panels::{build_panels, sphere_normal, Panel};
use crate::sphere_mesh::AbsoluteSphere;
use crate::st_support::{st_support_with_curvature, Clock, StSupportParams, StSupportResult};

/// Panel tessellation chord error, relative to the bbox diagonal (issue 3 §4).
pub const CHORD_TOLERANCE: f64 = 1e-4;

/// The method's parameters as the design link and the CLI give them (lengths relative to the
/// bounding-box diagonal).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StSupportRequest {
    pub optimize_radius: bool,
    pub support_depth: f64,
    pub axis_length: f64,
    /// Radii are rounded to multiples of this (× diag) before counting distinct ones.
    pub radius_tolerance: f64,
    /// Remesh first (issue 4 §2): with the sizing field of the local spheres orthogonal to Ω
    /// (Fig. 16, bottom; ε × diag), uniformly to about N faces, or not at all.
    #[serde(default = "no_remesh")]
    pub remesh: StSizing,
    pub jet: JetParams,
}

fn no_remesh() -> StSizing {
    StSizing::None
}

impl Default for StSupportRequest {
    fn default() -> Self {
        Self {
            optimize_radius: false,
            support_depth: 0.02,
            axis_length: 0.1,
            radius_tolerance: 1e-3,
            remesh: StSizing::None,
            jet: JetParams::default(),
        }
    }
}

/// Neighbours of a local sphere orthogonal to Ω (`remesh::local_spheres_orthogonal`).
pub const LOCAL_SPHERE_POINTS: usize = 16;

/// The reference remeshed as `req.remesh` asks, with its topology and curvature; `None` when no
/// remeshing is asked for. The sizing field of the adaptive variant uses local least-squares
/// spheres orthogonal to the Ω estimated on the reference (Sec. 3, Fig. 16 bottom).
fn remeshed_reference(
    mesh: &TriMesh,
    topo: &Topology,
    field: &CurvatureField,
    req: &StSupportRequest,
    progress: &mut dyn FnMut(&str, usize, usize) -> bool,
) -> Result<Option<(TriMesh, Topology, CurvatureField)>, String> {
    let sizing = match req.remesh {
        StSizing::None => return Ok(None),
        StSizing::UniformFaces(n) => SizingField::uniform_for_face_count(mesh, n),
        StSizing::Adaptive { epsilon } => {
            if !progress("sizing", 0, 1) {
                return Err("cancelled".into());
            }
            let estimate = estimate_absolute_sphere(mesh, field, &AbsoluteSphereParams::default())?;
            let spheres = local_spheres_orthogonal(mesh, topo, &estimate.omega, LOCAL_SPHERE_POINTS);
            // Faces finer than the reference's facets would fit its creases, not the surface.
            let mut bounds = SizingBounds::for_mesh(mesh, topo);
            bounds.g_min = mean_edge_length(mesh, topo).min(bounds.g_max);
            let sphere_of = |i: usize| spheres[i];
            let mut p = |done, total| progress("sizing", done, total);
            SizingField::from_sphere_fn(mesh, topo, &sphere_of, epsilon * mesh.bbox_diagonal(), bounds, &mut p)
                .ok_or("cancelled")?
        }
    };
    let remeshed = pliant_remesh(mesh, &sizing, &RemeshParams::default(), &mut |done, total| progress("remesh", done, total))
        .ok_or("cancelled")?;
    if remeshed.face_count() == 0 {
        return Err("remeshing produced no faces".into());
    }
    let rtopo = Topology::new(&remeshed);
    let rfield = jet_fit(&remeshed, &rtopo, &req.jet, &mut |d, t| progress("curvature", d, t)).ok_or("cancelled")?;
    Ok(Some((remeshed, rtopo, rfield)))
}

/// A file produced for download or for the CLI's output folder.
#[derive(Clone, Debug, PartialEq)]
pub struct ExportFile {
    pub name: String,
    pub mime: String,
    pub bytes: Vec<u8>,
}

/// The files every panel method writes: GLB, OBJ, the schedule as CSV and JSON, report.json.
pub fn panel_files(glb: Vec<u8>, obj: String, schedule: &export::PanelSchedule, report: &Report) -> Vec<ExportFile> {
    let file = |name: &str, mime: &str, bytes: Vec<u8>| ExportFile { name: name.into(), mime: mime.into(), bytes };
    vec![
        file("panels.glb", "model/gltf-binary", glb),
        file("panels.obj", "text/plain", obj.into_bytes()),
        file("panels.csv", "text/csv", schedule.to_csv().into_bytes()),
        file("panels.json", "application/json", schedule.to_json().into_bytes()),
        file("report.json", "application/json", report.to_json().into_bytes()),
    ]
}

/// Data for the histograms of Fig. 14 and the Ω display.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StSupportSummary {
    pub report: Report,
    pub omega: AbsoluteSphere,
    pub m0: [f64; 3],
    pub m: [f64; 3],
    pub flipped: bool,
    /// angle(v − m, n) in degrees, for m0 and for the optimized m.
    pub angles_m0: Histogram,
    pub angles_m: Histogram,
    /// The R_i² of the central spheres (or the distances d_i when Ω is a plane).
    pub r2: Histogram,
    pub distinct_radii: usize,
}


pub struct StSupportOutput {
    pub result: StSupportResult,
    pub panels: Vec<Panel>,
    pub support: SupportGeometry,
    pub axes: Vec<(DVec3, DVec3)>,
    pub summary: StSupportSummary,
    pub files: Vec<ExportFile>,
}

/// Runs the method on `mesh` with its curvature `field`; `progress(stage, done, total)` returning
/// false cancels with Err("cancelled").
pub fn run(
    mesh: &TriMesh,
    topo: &Topology,
    field: &CurvatureField,
    req: &StSupportRequest,
    clock: Clock,
    progress: &mut dyn FnMut(&str, usize, usize) -> bool,
) -> Result<StSupportOutput, String> {
    let params = StSupportParams {
        optimize_radius: req.optimize_radius,
        support_depth: req.support_depth,
        axis_length: req.axis_length,
        jet: req.jet.clone(),
        clock,
        ..StSupportParams::default()
    };
    let remeshed = remeshed_reference(mesh, topo, field, req, progress)?;
    let (work, work_topo, work_field) = match &remeshed {
        Some((m, t, f)) => (m, t, f),
        None => (mesh, topo, field),
    };
    let result = st_support_with_curvature(work, work_topo, work_field, &params, progress)?;
    let diag = result.diag;
    let now = || clock.0.map_or(0.0, |f| f());

    let t = now();
    if !progress("panels", 0, 1) {
        return Err("cancelled".into());
    }
    let panels = build_panels(&result.sphere_mesh, CHORD_TOLERANCE * diag);
    let support = export::support_geometry(&panels, &result.support);
    let axes = export::node_axis_segments(&result.support, result.axis_length);
    let panels_ms = now() - t;

    let t = now();
    if !progress("export", 0, 1) {
        return Err("cancelled".into());
    }
    let schedule = export::build_schedule(&panels, mesh, req.radius_tolerance * diag);
    let mut extras = serde_json::json!({ "absolute_sphere": export::absolute_sphere_extras(&result.omega) });
    extras["method"] = "st-support".into();
    let glb = export::write_glb(&panels, Some(&support), Some(&axes), extras);
    let obj = export::write_obj(&panels, Some(&support), Some(&axes));
    let export_ms = now() - t;

    let m = &result.metrics;
    let mut report = Report::for_panels("st-support", mesh, &result.sphere_mesh.mesh, panels.len());
    report.absolute_sphere = Some(AbsoluteSphereReport::from(&result.omega));
    report.metrics = Metrics {
        max_vertex_sphere_residual: Some(m.max_vertex_sphere_residual),
        max_orthogonality_residual: Some(m.max_orthogonality_residual),
        max_node_axis_offset: Some(m.max_node_axis_offset),
        mean_axis_normal_angle_deg: Some(m.mean_axis_normal_angle_deg),
        max_axis_normal_angle_deg: Some(m.max_axis_normal_angle_deg),
        mean_kink_angle_deg: Some(m.mean_kink_angle_deg),
        max_kink_angle_deg: Some(m.max_kink_angle_deg),
        max_distance_to_reference: Some(schedule.max_deviation / diag),
        extra: [
            ("max_center_plane_residual", serde_json::json!(m.max_center_plane_residual)),
            ("distinct_radii", serde_json::json!(schedule.distinct_radii)),
            ("axes_from_spheres", serde_json::json!(m.axes_from_spheres)),
            ("degenerate_faces", serde_json::json!(m.degenerate_faces)),
            ("remesh", serde_json::to_value(req.remesh).unwrap_or_default()),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect(),
    };
    for (stage, ms) in &result.timings_ms {
        report.add_timing(stage.clone(), *ms);
    }
    report.add_timing("panels", panels_ms);
    report.add_timing("export", export_ms);

    let a = &result.absolute;
    let r2_values = if a.at_infinity { &a.d_samples } else { &a.r2_samples };
    let summary = StSupportSummary {
        report: report.clone(),
        omega: result.omega,
        m0: a.m0.to_array(),
        m: a.m.to_array(),
        flipped: a.flipped,
        angles_m0: Histogram::new(&a.angles_m0_deg, 36),
        angles_m: Histogram::new(&a.angles_m_deg, 36),
        r2: Histogram::new(r2_values, 36),
        distinct_radii: schedule.distinct_radii,
    };
    let files = panel_files(glb, obj, &schedule, &report);
    Ok(StSupportOutput { result, panels, support, axes, summary, files })
}

/// Well-known field names of the method's snapshot.
pub mod fields {
    pub const PANEL_POSITIONS: &str = "panels.positions";
    pub const PANEL_NORMALS: &str = "panels.normals";
    pub const PANEL_TRIANGLES: &str = "panels.triangles";
    /// Boundary arcs of every panel as line segments over the panel positions.
    pub const PANEL_EDGES: &str = "panels.edges";
    pub const SUPPORT_POSITIONS: &str = "support.positions";
    pub const SUPPORT_TRIANGLES: &str = "support.triangles";
    pub const AXES_POSITIONS: &str = "axes.positions";
    pub const AXES_LINES: &str = "axes.lines";
    pub const ENVELOPE_POSITIONS: &str = "envelope2.positions";
    pub const ENVELOPE_TRIANGLES: &str = "envelope2.triangles";
}

pub(crate) fn f32s(points: impl Iterator<Item = DVec3>) -> Vec<f32> {
    points.flat_map(|p| [p.x as f32, p.y as f32, p.z as f32]).collect()
}

/// The panels as display fields: positions with their sphere normals, triangles, and the
/// boundary arcs as line segments.
pub fn panel_fields(panels: &[Panel]) -> Vec<Field> {
    let (mut pos, mut nrm, mut tri, mut edges) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for p in panels {
        let base = pos.len() as u32;
        pos.extend(p.positions.iter().copied());
        nrm.extend(p.positions.iter().map(|&x| sphere_normal(&p.sphere, x)));
        tri.extend(p.triangles.iter().flat_map(|t| t.map(|i| i + base)));
        for arc in &p.arc_vertices {
            for w in arc.windows(2) {
                edges.extend([w[0] + base, w[1] + base]);
            }
        }
    }
    vec![
        Field::f32(fields::PANEL_POSITIONS, 3, f32s(pos.into_iter())),
        Field::f32(fields::PANEL_NORMALS, 3, f32s(nrm.into_iter())),
        Field::u32(fields::PANEL_TRIANGLES, 3, tri),
        Field::u32(fields::PANEL_EDGES, 2, edges),
    ]
}

/// Display fields: panels, support, node axes, second envelope.
pub fn display_fields(out: &StSupportOutput) -> Vec<Field> {
    let mut fields = panel_fields(&out.panels);
    fields.extend([
        Field::f32(fields::SUPPORT_POSITIONS, 3, f32s(out.support.positions.iter().copied())),
        Field::u32(fields::SUPPORT_TRIANGLES, 3, out.support.triangles.iter().flatten().copied().collect()),
        Field::f32(fields::AXES_POSITIONS, 3, f32s(out.axes.iter().flat_map(|&(a, b)| [a, b]))),
        Field::u32(fields::AXES_LINES, 2, (0..2 * out.axes.len() as u32).collect()),
    ]);
    if let Some(env) = &out.result.second_envelope {
        fields.push(Field::f32(fields::ENVELOPE_POSITIONS, 3, f32s(env.positions.iter().copied())));
        fields.push(Field::u32(fields::ENVELOPE_TRIANGLES, 3, env.triangles.iter().flatten().copied().collect()));
    }
    fields
}
