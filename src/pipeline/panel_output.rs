//! What every panel method sends and writes, in one place: display fields of meshes, panels,
//! support structure and curvature, and the export files with the shared report.

use crate::guarantees::Verdict;
use glam::DVec3;

use super::fields::{field, Field};
use crate::congruence::central_spheres::CurvatureField;
use crate::congruence::support_structure::{SupportGeometry, SupportStructure};
use crate::export::absolute_sphere_extras;
use crate::export::report::{ExactSurfacesReport, InputCounts, OutputCounts};
use crate::export::rhino::{RhinoInput, RhinoModel, RHINO_MODEL_FILE, RHINO_MODEL_MIME};
use crate::export::schedule::MouldRecord;
use crate::export::schedule::SupportRecord;
use crate::export::step::write_exact_step;
use crate::export::{build_schedule_with, panel_files, write_glb, write_obj, ExportFile, MouldReport, PanelMetrics, Report, SnapMisses, SnapReport};
use crate::geometry::absolute_sphere::AbsoluteSphere;
use crate::geometry::mesh::topology::Topology;
use crate::geometry::mesh::TriMesh;
use crate::panels::exact_surface::ExactSurfaces;
use crate::panels::moulds::{Fabrication, MouldAssignment, MouldFits, MouldSnap, SnapLimit};
use crate::panels::panel::Panel;
use crate::panels::sphere_mesh::SphereMesh;
use crate::panels::{display_panels, DISPLAY_PANEL_TRIANGLE_BUDGET};
use crate::progress::Clock;
use crate::reference::Reference;
use crate::units::format_length;

/// Points as f32 triples.
pub(crate) fn f32s(points: impl Iterator<Item = DVec3>) -> Vec<f32> {
    points.flat_map(|p| [p.x as f32, p.y as f32, p.z as f32]).collect()
}

/// Positions, normals, triangles and the edges to draw (of the faces as loaded: a quad's
/// diagonal is not one).
pub fn mesh_fields(mesh: &TriMesh, edges: &[[u32; 2]]) -> Vec<Field> {
    vec![
        Field::f32(field::POSITIONS, 3, f32s(mesh.positions.iter().copied())),
        Field::f32(field::NORMALS, 3, f32s(mesh.vertex_normals().into_iter())),
        Field::u32(field::TRIANGLES, 3, mesh.triangles.iter().flatten().copied().collect()),
        Field::u32(field::EDGES, 2, edges.iter().flatten().copied().collect()),
    ]
}

/// [`mesh_fields`] of a triangle mesh with all its edges.
pub(crate) fn triangle_mesh_fields(mesh: &TriMesh) -> Vec<Field> {
    mesh_fields(mesh, Topology::new(mesh).edges())
}

/// Per-vertex curvature fields for the viewer's colour maps and central spheres.
pub(crate) fn curvature_fields(c: &CurvatureField) -> Vec<Field> {
    let v = &c.vertices;
    vec![
        Field::f32(field::MEAN_CURVATURE, 1, v.iter().map(|x| x.mean as f32).collect()),
        Field::f32(field::K1, 1, v.iter().map(|x| x.k1 as f32).collect()),
        Field::f32(field::K2, 1, v.iter().map(|x| x.k2 as f32).collect()),
        Field::f32(field::K1_MINUS_K2, 1, v.iter().map(|x| (x.k1 - x.k2).abs() as f32).collect()),
        Field::f32(field::CENTRAL_SPHERES, 5, c.central_spheres.iter().flat_map(|s| [s.a, s.b.x, s.b.y, s.b.z, s.c]).map(|x| x as f32).collect()),
        Field::u32(field::BOUNDARY, 1, c.boundary.iter().map(|&b| b as u32).collect()),
    ]
}

/// The panels as display fields: positions with their sphere normals, triangles, and the
/// boundary arcs as line segments.
pub(crate) fn panel_fields(panels: &[Panel]) -> Vec<Field> {
    let (mut pos, mut nrm, mut tri, mut edges) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for p in panels {
        let base = pos.len() as u32;
        pos.extend(p.positions.iter().copied());
        nrm.extend(p.positions.iter().map(|&x| p.normal_at(x)));
        tri.extend(p.triangles.iter().flat_map(|t| t.map(|i| i + base)));
        for arc in &p.arc_vertices {
            for w in arc.windows(2) {
                edges.extend([w[0] + base, w[1] + base]);
            }
        }
    }
    vec![
        Field::f32(field::PANEL_POSITIONS, 3, f32s(pos.into_iter())),
        Field::f32(field::PANEL_NORMALS, 3, f32s(nrm.into_iter())),
        Field::u32(field::PANEL_TRIANGLES, 3, tri),
        Field::u32(field::PANEL_EDGES, 2, edges),
    ]
}

/// A result's panels as display fields ([`panel_fields`], within
/// [`DISPLAY_PANEL_TRIANGLE_BUDGET`] triangles: [`display_panels`]) with each panel vertex's mould
/// ([`field::PANEL_MOULDS`]), as the export assigned them ([`export_panels`]).
pub(crate) fn result_panel_fields(panels: &[Panel], moulds: &MouldAssignment) -> Vec<Field> {
    let panels = &*display_panels(panels, DISPLAY_PANEL_TRIANGLE_BUDGET);
    let per_vertex = panels.iter().zip(&moulds.panel_mould).flat_map(|(p, &m)| std::iter::repeat_n(m, p.positions.len())).collect();
    let mut fields = panel_fields(panels);
    fields.push(Field::u32(field::PANEL_MOULDS, 1, per_vertex));
    fields
}

/// The support strips and the node axes (segments) as display fields.
pub(crate) fn support_fields(support: &SupportGeometry, axes: &[(DVec3, DVec3)]) -> Vec<Field> {
    vec![
        Field::f32(field::SUPPORT_POSITIONS, 3, f32s(support.positions.iter().copied())),
        Field::u32(field::SUPPORT_TRIANGLES, 3, support.triangles.iter().flatten().copied().collect()),
        Field::f32(field::AXES_POSITIONS, 3, f32s(axes.iter().flat_map(|&(a, b)| [a, b]))),
        Field::u32(field::AXES_LINES, 2, (0..2 * axes.len() as u32).collect()),
    ]
}

/// Whether a method cut its panels from their moulds with no deviation.
#[derive(Clone, Copy, Debug)]
pub enum Snapping<'a> {
    /// It snapped them to these moulds' radii where it could.
    Snapped(&'a MouldSnap),
    /// It did not, for this reason.
    Not(SnapLimit),
}

impl<'a> Snapping<'a> {
    /// The snap of a method's rounds toward fewer moulds: the moulds, or why none was kept;
    /// None when they were not asked for.
    pub(crate) fn of(rounds: Option<&'a Result<MouldSnap, SnapLimit>>) -> Self {
        match rounds {
            Some(Ok(snap)) => Snapping::Snapped(snap),
            Some(Err(limit)) => Snapping::Not(*limit),
            None => Snapping::Not(SnapLimit::NotAsked),
        }
    }
}

/// What a panel method exports: see [`PanelExport::new`].
pub struct PanelExport<'a> {
    pub method: &'a str,
    pub sphere_mesh: &'a SphereMesh,
    pub panels: &'a [Panel],
    pub diag: f64,
    pub radius_tolerance: f64,
    /// The model unit and the moulds asked for.
    pub fabrication: Fabrication,
    /// The method's own section of the report.
    pub section: serde_json::Value,
    pub timings: &'a [(String, f64)],
    /// Goes to the GLB's `asset.extras` (with the method).
    pub extras: serde_json::Value,
    /// The support structure: its strips and node axes for the GLB and OBJ, its elements for
    /// the schedule (`support.csv` and the JSON).
    pub support: Option<&'a SupportStructure>,
    /// The absolute sphere Ω of ST with support structure, for `panels.3dm`.
    pub omega: Option<&'a AbsoluteSphere>,
    /// The report's warnings.
    pub warnings: Vec<String>,
    /// Each panel's largest distance to the reference, when the method measured it already.
    pub deviations: Option<&'a [f64]>,
    /// The method's verdict on the result, for the report.
    pub verdict: Option<&'a Verdict>,
    /// The panels' mould fits before the method moved them onto fewer moulds.
    pub moulds_before: Option<&'a MouldFits>,
    /// The moulds the method snapped its panels to, or why it did not.
    pub snapping: Snapping<'a>,
    /// The panels' and support elements' exact surfaces, when the method's verdict measured
    /// them already ([`crate::panels::buildability`]): the CAD files write these.
    pub exact: Option<&'a ExactSurfaces>,
}

impl<'a> PanelExport<'a> {
    /// The export of a panel method (its key in reports and files: "st", "st-support"): its
    /// sphere mesh and panels, lengths relative to `diag` (of the mesh the method ran on), radii
    /// closer than `radius_tolerance` × `diag` counted as one, its own section of the report
    /// (a serializable type of the method's) and its timings; the moulds and units as
    /// `fabrication` asks.
    pub fn new(
        method: &'a str,
        sphere_mesh: &'a SphereMesh,
        panels: &'a [Panel],
        diag: f64,
        radius_tolerance: f64,
        fabrication: Fabrication,
        section: &impl serde::Serialize,
        timings: &'a [(String, f64)],
    ) -> Self {
        let extras = serde_json::json!({});
        Self {
            method,
            sphere_mesh,
            panels,
            diag,
            radius_tolerance,
            fabrication,
            section: serde_json::to_value(section).expect("a report section serializes"),
            timings,
            extras,
            support: None,
            omega: None,
            warnings: Vec::new(),
            deviations: None,
            verdict: None,
            moulds_before: None,
            snapping: Snapping::Not(SnapLimit::NotAsked),
            exact: None,
        }
    }

    /// The exact surfaces the method's verdict measured: the CAD files hold these.
    pub(crate) fn with_exact_surfaces(self, exact: &'a ExactSurfaces) -> Self {
        Self { exact: Some(exact), ..self }
    }

    /// The moulds the method snapped its panels to ([`MouldSnap`]), or why it did not.
    pub(crate) fn with_snapping(self, snapping: Snapping<'a>) -> Self {
        Self { snapping, ..self }
    }

    /// The verdict the report carries ([`crate::guarantees`]).
    pub(crate) fn with_verdict(self, verdict: &'a Verdict) -> Self {
        Self { verdict: Some(verdict), ..self }
    }

    /// The warnings the report carries (the failed assumptions of the reference).
    pub(crate) fn with_warnings(self, warnings: &[impl ToString]) -> Self {
        Self { warnings: warnings.iter().map(ToString::to_string).collect(), ..self }
    }

    pub(crate) fn with_extras(self, extras: serde_json::Value) -> Self {
        Self { extras, ..self }
    }

    /// The absolute sphere Ω: in the GLB's extras and `panels.3dm`.
    pub(crate) fn with_absolute_sphere(self, omega: &'a AbsoluteSphere) -> Self {
        let mut extras = self.extras.clone();
        if let (Some(e), serde_json::Value::Object(o)) = (extras.as_object_mut(), absolute_sphere_extras(omega)) {
            e.extend(o);
        }
        Self { omega: Some(omega), extras, ..self }
    }

    /// The support structure (its strips and elements) and the node axes.
    pub(crate) fn with_support(self, support: &'a SupportStructure) -> Self {
        Self { support: Some(support), ..self }
    }

    /// The mould fits of the panels before the method moved them onto fewer moulds.
    pub(crate) fn with_moulds_before(self, fits: Option<&'a MouldFits>) -> Self {
        Self { moulds_before: fits, ..self }
    }

    /// Each panel's [`crate::panels::deviation::max_deviation`] from the reference, measured by
    /// the method: the schedule takes them instead of measuring again.
    pub(crate) fn with_deviations(self, deviations: &'a [f64]) -> Self {
        Self { deviations: Some(deviations), ..self }
    }
}

/// The shared moulds section of the report: the assignment, its count against the tolerance,
/// and the count before the method moved its panels onto fewer moulds, if it did.
pub(crate) fn mould_report(fits: &MouldFits, moulds: &MouldAssignment, snapped: &[bool], e: &PanelExport) -> MouldReport {
    let t = moulds.tolerance;
    MouldReport {
        units: e.fabrication.units,
        target: e.fabrication.moulds,
        tolerance: t,
        tolerance_relative: if e.diag > 0.0 { t / e.diag } else { t },
        count: moulds.moulds.len(),
        max_deviation: moulds.panel_deviation.iter().copied().fold(0.0, f64::max),
        moulds: MouldRecord::of(moulds),
        against_tolerance: fits.against_tolerance(t, e.diag),
        against_tolerance_before: e.moulds_before.map(|f| f.against_tolerance(t, e.diag)).unwrap_or_default(),
        snap: snap_report(fits, moulds, snapped, e.snapping),
    }
}

/// The panels with exactly their mould's radius (`snapped`, measured), and the others by the
/// reason the method gives, with their largest fit deviation and radius miss.
fn snap_report(fits: &MouldFits, moulds: &MouldAssignment, snapped: &[bool], snapping: Snapping) -> SnapReport {
    let mut report = SnapReport::default();
    for (i, &on) in snapped.iter().enumerate() {
        if on {
            report.snapped += 1;
            continue;
        }
        let reason = match snapping {
            Snapping::Snapped(s) => s.limits.get(i).copied().flatten().unwrap_or(SnapLimit::Missed),
            Snapping::Not(reason) => reason,
        };
        let radius_miss = fits.radius_miss(i, moulds.moulds[moulds.panel_mould[i] as usize].curvature);
        let at = match report.not_snapped.iter().position(|m| m.reason == reason) {
            Some(at) => at,
            None => {
                report.not_snapped.push(SnapMisses { reason, panels: 0, max_deviation: 0.0, max_radius_miss: None });
                report.not_snapped.len() - 1
            }
        };
        let m = &mut report.not_snapped[at];
        m.panels += 1;
        m.max_deviation = m.max_deviation.max(moulds.panel_deviation[i]);
        m.max_radius_miss = match (m.max_radius_miss, radius_miss) {
            (Some(a), Some(b)) => Some(a.max(b)),
            (a, b) => a.or(b),
        };
    }
    report
}

/// The report and the panel files of a panel method: `panels.glb`, `panels.obj`, the schedule
/// as `panels.csv` and `panels.json` (distances to the `reference` as loaded) and `support.csv`;
/// the caller adds `report.json` ([`crate::export::report_file`]) once the report is complete.
/// Also the panels' moulds, for the display ([`result_panel_fields`]).
pub(crate) fn export_panels(reference: &Reference, e: PanelExport, clock: Clock) -> (Report, Vec<ExportFile>, MouldAssignment) {
    let t0 = clock.now();
    let fits = MouldFits::of(e.panels);
    let moulds = match e.snapping {
        Snapping::Snapped(snap) => fits.on_moulds(&snap.moulds),
        Snapping::Not(_) => e.fabrication.assign(&fits, e.diag),
    };
    let snapped: Vec<bool> =
        moulds.panel_mould.iter().enumerate().map(|(i, &j)| fits.has_mould_radius(i, moulds.moulds[j as usize].curvature, e.diag)).collect();
    let units = e.fabrication.units;
    let mut schedule = build_schedule_with(e.panels, reference, e.radius_tolerance * e.diag, e.deviations).with_moulds(&moulds, &snapped, units);
    schedule.support_elements = e.support.map(|s| SupportRecord::of(&s.elements)).unwrap_or_default();
    let mut extras = e.extras.clone();
    extras["method"] = e.method.into();
    extras["units"] = units.symbol().into();
    let axes = e.support.map(SupportStructure::axis_segments);
    let (geometry, axes) = (e.support.map(|s| &s.geometry), axes.as_deref());
    let glb = write_glb(e.panels, geometry, axes, Some(&moulds), extras);
    let obj = write_obj(e.panels, geometry, axes);
    let kinks = e.sphere_mesh.kink_angles_deg();
    let mesh = reference.mesh();
    let output = &e.sphere_mesh.mesh;
    let mut report = Report::new(e.method);
    report.input = InputCounts { vertices: mesh.vertex_count(), faces: mesh.face_count() };
    report.output = OutputCounts { vertices: output.vertex_count(), faces: output.face_count(), panels: e.panels.len() };
    report.metrics = Some(PanelMetrics {
        mean_kink_angle_deg: crate::stats::mean(&kinks),
        max_kink_angle_deg: kinks.iter().copied().fold(0.0, f64::max),
        max_distance_to_reference: schedule.max_deviation / e.diag,
        distinct_radii: schedule.distinct_radii,
        units,
        diagonal: e.diag,
        max_distance: schedule.max_deviation,
    });
    report.moulds = Some(mould_report(&fits, &moulds, &snapped, &e));
    report.sections.insert(e.method.to_string(), e.section);
    let measured;
    let exact = match e.exact {
        Some(exact) => exact,
        None => {
            measured = ExactSurfaces::of(e.panels, e.support.map_or(&[][..], |s| &s.elements[..]));
            &measured
        }
    };
    report.exact_surfaces = Some(ExactSurfacesReport::of(exact));
    let step = write_exact_step("panels", e.panels, exact, units, e.diag);
    let rhino = RhinoModel::of(&RhinoInput { panels: e.panels, exact, moulds: &moulds, support: e.support, omega: e.omega, units });
    report.add_timings(e.timings);
    report.add_timing("export", clock.now() - t0);
    report.warnings = e.warnings;
    if let Some(v) = e.verdict {
        report.set_verdict(v);
    }
    let mut files = panel_files(glb, obj, &schedule);
    files.push(ExportFile::new("panels.step", "model/step", step.into_bytes()));
    files.push(ExportFile::new(RHINO_MODEL_FILE, RHINO_MODEL_MIME, rhino.to_json().into_bytes()));
    if !schedule.support_elements.is_empty() {
        let csv = SupportRecord::to_csv(&schedule.support_elements);
        files.push(ExportFile::new("support.csv", "text/csv", csv.into_bytes()));
    }
    (report, files, moulds)
}

/// `summary`, then the exact surfaces of `panels.step` and `panels.3dm` and the moulds of the report: how many,
/// within what, in model units.
pub fn with_moulds(summary: String, report: &Report) -> String {
    let summary = match &report.exact_surfaces {
        Some(e) => format!("{summary}; CAD surfaces (panels.step, panels.3dm): {}", e.describe()),
        None => summary,
    };
    match &report.moulds {
        Some(m) => format!(
            "{summary}; {} mould{} within {} (largest fit deviation {}; moulds.csv); {}",
            m.count,
            if m.count == 1 { "" } else { "s" },
            format_length(m.tolerance, m.units),
            format_length(m.max_deviation, m.units),
            m.snap.describe(report.output.panels, m.units),
        ),
        None => summary,
    }
}
