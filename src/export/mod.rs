//! Writers of a panelled mesh: GLB ([`glb`]), OBJ ([`obj`]), the panel schedule as CSV and JSON
//! ([`schedule`]), the exact surfaces as STEP ([`step`]) and the `report.json` every method
//! shares ([`report`]).
//!
//! The geometry written is exactly what [`crate::panels::build_panels`] tessellated, plus the
//! support structure ([`crate::congruence::support_structure::SupportGeometry`]) and the node
//! axes as line segments.

pub mod glb;
pub mod obj;
pub mod report;
pub mod rhino;
pub mod schedule;
pub mod step;

pub use glb::{absolute_sphere_extras, write_glb};
pub use obj::{write_mesh_obj, write_obj};
pub use report::{MouldReport, PanelMetrics, Report, SnapMisses, SnapReport, REPORT_SCHEMA};
pub use schedule::{build_schedule, build_schedule_with, count_distinct_radii, PanelSchedule};

/// A file for download or for the CLI's output folder.
#[derive(Clone, Debug, PartialEq)]
pub struct ExportFile {
    pub name: String,
    pub mime: String,
    pub bytes: Vec<u8>,
}

impl ExportFile {
    pub fn new(name: &str, mime: &str, bytes: Vec<u8>) -> Self {
        Self { name: name.into(), mime: mime.into(), bytes }
    }
}

/// `report.json`, the last file of every run.
pub fn report_file(report: &Report) -> ExportFile {
    ExportFile::new("report.json", "application/json", report.to_json().into_bytes())
}

/// The panel files every panel method writes, in this order: `panels.glb`, `panels.obj`, the
/// schedule as `panels.csv` and `panels.json`, and its mould table as `moulds.csv` when it has
/// one (`report.json` follows with [`report_file`]).
pub fn panel_files(glb: Vec<u8>, obj: String, schedule: &PanelSchedule) -> Vec<ExportFile> {
    let file = ExportFile::new;
    let mut files = vec![
        file("panels.glb", "model/gltf-binary", glb),
        file("panels.obj", "text/plain", obj.into_bytes()),
        file("panels.csv", "text/csv", schedule.to_csv().into_bytes()),
        file("panels.json", "application/json", schedule.to_json().into_bytes()),
    ];
    if !schedule.moulds.is_empty() {
        let csv = schedule::MouldRecord::to_csv(&schedule.moulds, schedule.units);
        files.push(file("moulds.csv", "text/csv", csv.into_bytes()));
    }
    files
}
