//! Mesh import: Wavefront OBJ, glTF 2.0 (`.gltf` with embedded `data:` buffers) and GLB.
//!
//! [`import_mesh`] detects the format, parses it into triangles (OBJ polygons are triangulated,
//! glTF node transforms applied), welds coincident vertices ([`crate::mesh::weld`]), drops
//! degenerate faces and reports [`MeshStats`]. Every failure is an [`ImportError`] whose message
//! starts with the file name and says what to fix; no input can make the importer panic.

mod base64;
mod gltf;
mod obj;

use crate::mesh::weld::weld;
use crate::mesh::{MeshStats, Topology, TriMesh};
use glam::DVec3;
use serde::{Deserialize, Serialize};
use std::fmt;

/// Largest accepted triangle count (after triangulation, before welding).
pub const MAX_TRIANGLES: usize = 2_000_000;
/// Largest accepted input size in bytes (512 MiB).
pub const MAX_BYTES: usize = 512 << 20;
/// Largest accepted vertex count before welding: three per triangle.
pub const MAX_VERTICES: usize = 3 * MAX_TRIANGLES;
/// Vertices closer than this fraction of the bounding-box diagonal are merged.
pub const WELD_TOLERANCE: f64 = 1e-7;

/// Input file formats.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Format {
    Obj,
    Gltf,
    Glb,
}

/// A cleaned triangle mesh ready for the pipeline.
#[derive(Debug, Clone, PartialEq)]
pub struct Imported {
    /// Welded triangle mesh without degenerate faces or unreferenced vertices.
    pub mesh: TriMesh,
    pub stats: MeshStats,
    pub format: Format,
    /// Faces in the source: OBJ `f` statements, glTF triangles (per node instance).
    pub source_polygons: usize,
    /// Vertices merged into an earlier one within the weld tolerance.
    pub merged_vertices: usize,
    /// Faces dropped: fewer than three distinct vertices, zero area, duplicates.
    pub dropped_faces: usize,
    /// Human-readable warnings, e.g. "skipped 2 line primitives".
    pub notes: Vec<String>,
}

/// Why a file could not be imported. `Display` starts with the file name.
#[derive(Debug, Clone, PartialEq)]
pub enum ImportError {
    /// Nothing to import: empty file, no faces, or only degenerate faces.
    Empty { file: String, reason: String },
    /// Over a limit: `count` `what` (e.g. "triangles", "bytes") exceed `limit`.
    TooLarge { file: String, what: String, count: u64, limit: u64 },
    /// Broken syntax or structure; `line` is 1-based for text formats.
    Malformed { file: String, line: Option<usize>, message: String },
    /// Valid input using something this importer does not handle.
    Unsupported { file: String, message: String },
}

impl ImportError {
    /// The file name the error refers to.
    pub fn file(&self) -> &str {
        match self {
            ImportError::Empty { file, .. }
            | ImportError::TooLarge { file, .. }
            | ImportError::Malformed { file, .. }
            | ImportError::Unsupported { file, .. } => file,
        }
    }

    /// The 1-based line of a malformed text file, when known.
    pub fn line(&self) -> Option<usize> {
        match self {
            ImportError::Malformed { line, .. } => *line,
            _ => None,
        }
    }
}

impl fmt::Display for ImportError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ImportError::Empty { file, reason } => write!(f, "{file}: {reason}"),
            ImportError::TooLarge { file, what, count, limit } => {
                write!(f, "{file}: {count} {what} exceed the limit of {limit}")?;
                if what == "bytes" {
                    write!(f, " ({} MiB)", limit >> 20)?;
                }
                Ok(())
            }
            ImportError::Malformed { file, line: Some(line), message } => {
                write!(f, "{file}: line {line}: {message}")
            }
            ImportError::Malformed { file, line: None, message } => write!(f, "{file}: {message}"),
            ImportError::Unsupported { file, message } => write!(f, "{file}: {message}"),
        }
    }
}

impl std::error::Error for ImportError {}

/// Error construction for the parsers: carries the display file name.
pub(crate) struct Ctx {
    pub file: String,
}

impl Ctx {
    pub fn malformed(&self, line: Option<usize>, message: impl Into<String>) -> ImportError {
        ImportError::Malformed { file: self.file.clone(), line, message: message.into() }
    }

    pub fn unsupported(&self, message: impl Into<String>) -> ImportError {
        ImportError::Unsupported { file: self.file.clone(), message: message.into() }
    }

    pub fn empty(&self, reason: impl Into<String>) -> ImportError {
        ImportError::Empty { file: self.file.clone(), reason: reason.into() }
    }

    pub fn too_large(&self, what: &str, count: u64, limit: usize) -> ImportError {
        ImportError::TooLarge { file: self.file.clone(), what: what.into(), count, limit: limit as u64 }
    }

    /// Rejects counts over [`MAX_TRIANGLES`] / [`MAX_VERTICES`].
    pub fn check_limits(&self, triangles: u64, vertices: u64) -> Result<(), ImportError> {
        if triangles > MAX_TRIANGLES as u64 {
            return Err(self.too_large("triangles", triangles, MAX_TRIANGLES));
        }
        if vertices > MAX_VERTICES as u64 {
            return Err(self.too_large("vertices", vertices, MAX_VERTICES));
        }
        Ok(())
    }
}

/// What a format parser produces: raw triangles before welding.
#[derive(Debug, Default)]
pub(crate) struct RawMesh {
    pub positions: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
    pub source_polygons: usize,
    /// Faces the parser dropped already (fewer than three distinct vertices).
    pub dropped_faces: usize,
    pub notes: Vec<String>,
}

/// Shortens user-provided text for an error message.
pub(crate) fn excerpt(bytes: &[u8]) -> String {
    let s = String::from_utf8_lossy(bytes);
    let mut out: String = s.chars().take(40).collect();
    if s.chars().nth(40).is_some() {
        out.push('…');
    }
    out
}

/// The base name of a path, for messages ("dir/a.obj" -> "a.obj").
fn display_name(file_name: &str) -> String {
    let base = file_name.rsplit(['/', '\\']).next().unwrap_or(file_name);
    if base.is_empty() {
        "input".to_string()
    } else {
        base.to_string()
    }
}

fn extension(file_name: &str) -> String {
    match file_name.rsplit_once('.') {
        Some((_, ext)) if !ext.contains(['/', '\\']) => ext.to_ascii_lowercase(),
        _ => String::new(),
    }
}

/// Detects the format by content (GLB magic, JSON object), then by extension.
pub fn detect_format(bytes: &[u8], file_name: &str) -> Option<Format> {
    if bytes.starts_with(b"glTF") {
        return Some(Format::Glb);
    }
    let text = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    if text.iter().find(|b| !b.is_ascii_whitespace()) == Some(&b'{') {
        return Some(Format::Gltf);
    }
    match extension(file_name).as_str() {
        "obj" => Some(Format::Obj),
        "gltf" => Some(Format::Gltf),
        "glb" => Some(Format::Glb),
        _ => None,
    }
}

/// Whether unknown-extension text looks like OBJ: a `v` or `f` statement near the start.
fn looks_like_obj(bytes: &[u8]) -> bool {
    let head = &bytes[..bytes.len().min(1 << 16)];
    head.split(|&b| b == b'\n').any(|l| {
        let l = l.trim_ascii_start();
        (l.starts_with(b"v") || l.starts_with(b"f")) && l.get(1).is_some_and(|b| *b == b' ' || *b == b'\t')
    })
}

/// Imports an OBJ, glTF or GLB file from memory. `file_name` is used for format detection
/// (after the content) and error messages.
pub fn import_mesh(bytes: &[u8], file_name: &str) -> Result<Imported, ImportError> {
    let ctx = Ctx { file: display_name(file_name) };
    if bytes.len() > MAX_BYTES {
        return Err(ctx.too_large("bytes", bytes.len() as u64, MAX_BYTES));
    }
    if bytes.iter().all(|b| b.is_ascii_whitespace()) {
        return Err(ctx.empty("file is empty"));
    }
    let format = match detect_format(bytes, file_name) {
        Some(f) => f,
        None if looks_like_obj(bytes) => Format::Obj,
        None => {
            let ext = extension(file_name);
            let what = if ext.is_empty() { "this file".to_string() } else { format!("'.{ext}' files") };
            return Err(ctx.unsupported(format!(
                "cannot import {what}; expected a Wavefront .obj, a glTF 2.0 .gltf or a .glb file"
            )));
        }
    };
    let raw = match format {
        Format::Obj => obj::parse(bytes, &ctx)?,
        Format::Gltf => self::gltf::parse_gltf(bytes, &ctx)?,
        Format::Glb => self::gltf::parse_glb(bytes, &ctx)?,
    };
    finish(raw, format, &ctx)
}

/// Welds, validates and measures a parsed mesh.
fn finish(raw: RawMesh, format: Format, ctx: &Ctx) -> Result<Imported, ImportError> {
    let RawMesh { positions, triangles, source_polygons, dropped_faces, mut notes } = raw;
    if triangles.is_empty() {
        let mut reason = "no faces found".to_string();
        if !notes.is_empty() {
            reason += &format!(" ({})", notes.join("; "));
        }
        return Err(ctx.empty(reason));
    }
    if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
        return Err(ctx.malformed(None, format!("vertex {} has a non-finite coordinate", i + 1)));
    }
    if let Some(t) = triangles.iter().find(|t| t.iter().any(|&v| v as usize >= positions.len())) {
        // Parsers check indices; this guards the invariant.
        return Err(ctx.malformed(None, format!("face {t:?} refers to a missing vertex")));
    }
    let raw_mesh = TriMesh::new(positions, triangles);
    let diag = raw_mesh.referenced_diagonal();
    let (mesh, report) = weld(&raw_mesh, WELD_TOLERANCE * diag);
    let total_faces = raw_mesh.triangles.len();
    drop(raw_mesh);
    if mesh.triangles.is_empty() {
        return Err(ctx.empty(format!("all {total_faces} faces are degenerate (zero area or repeated vertices)")));
    }
    if report.merged_vertices > 0 {
        notes.push(format!("merged {} coincident vertices", report.merged_vertices));
    }
    if report.dropped_faces > 0 {
        notes.push(format!("dropped {} degenerate or duplicate faces", report.dropped_faces));
    }
    if report.removed_unreferenced > 0 {
        notes.push(format!("removed {} unused vertices", report.removed_unreferenced));
    }
    let stats = Topology::new(&mesh).stats(&mesh);
    Ok(Imported {
        mesh,
        stats,
        format,
        source_polygons,
        merged_vertices: report.merged_vertices,
        dropped_faces: dropped_faces + report.dropped_faces,
        notes,
    })
}

