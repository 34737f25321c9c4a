//! Import: meshes from Wavefront OBJ, glTF 2.0 (`.gltf` with embedded `data:` buffers) and GLB,
//! and B-spline surfaces from the authors' JSON format ([`bspline`]); [`import_file`] takes
//! either.
//!
//! [`import_mesh`] detects the format, parses it into triangles (OBJ polygons are triangulated,
//! glTF node transforms applied), welds coincident vertices ([`crate::geometry::mesh::weld`]), drops
//! degenerate faces and reports [`MeshStats`]. Every failure is an [`ImportError`] whose message
//! starts with the file name and says what to fix; no input can make the importer panic.

mod base64;
pub mod bspline;
mod gltf;
mod obj;
mod raw;

use crate::geometry::bspline::BSplineSurface;
use crate::geometry::mesh::topology::{MeshStats, Topology};
use crate::geometry::mesh::weld::weld_with_face_map;
use crate::geometry::mesh::{Face, PolyMesh, TriMesh};
use serde::{Deserialize, Serialize};

use raw::{check_scale, Ctx, RawMesh};
pub use raw::{ImportError, MAX_BYTES, MAX_COORDINATE, MAX_TRIANGLES, MAX_VERTICES, MIN_DIAGONAL};

/// Vertices closer than this fraction of the bounding-box diagonal are merged.
pub(crate) const WELD_TOLERANCE: f64 = 1e-7;

/// Input file formats.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Format {
    Obj,
    Gltf,
    Glb,
    /// A B-spline surface in the authors' JSON format.
    BSplineJson,
}

/// A B-spline surface read from a file.
#[derive(Debug, Clone, PartialEq)]
pub struct ImportedBSpline {
    pub surface: BSplineSurface,
    pub notes: Vec<String>,
}

/// What a file holds.
#[derive(Debug, Clone, PartialEq)]
pub enum ImportedFile {
    Mesh(Imported),
    BSpline(ImportedBSpline),
}

/// A cleaned mesh ready for the pipeline.
#[derive(Debug, Clone, PartialEq)]
pub struct Imported {
    /// Welded triangle mesh without degenerate faces or unreferenced vertices.
    pub mesh: TriMesh,
    /// The faces as in the file, over the same vertices: quads where both of a quad's
    /// triangles were kept, else triangles. Triangulating them (a quad from its corner 0) gives
    /// `mesh.triangles`, in order.
    pub faces: Vec<Face>,
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

impl Imported {
    /// The surface with its faces as in the file (3 or 4 corners).
    pub fn surface(&self) -> PolyMesh {
        PolyMesh::new(self.mesh.positions.clone(), self.faces.clone())
    }
}

/// The base name of a path, for messages ("dir/a.obj" -> "a.obj").
fn display_name(file_name: &str) -> String {
    let base = file_name.rsplit(['/', '\\']).next().unwrap_or(file_name);
    if base.is_empty() {
        "input".to_string()
    } else {
        crate::text::clip(base, 120)
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
        return Some(if bspline::looks_like_bspline(text) { Format::BSplineJson } else { Format::Gltf });
    }
    match extension(file_name).as_str() {
        "obj" => Some(Format::Obj),
        "gltf" => Some(Format::Gltf),
        "glb" => Some(Format::Glb),
        "json" => Some(Format::BSplineJson),
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

/// Imports a mesh (OBJ, glTF, GLB) or a B-spline surface (JSON) from memory. `file_name` is used
/// for format detection (after the content) and error messages.
pub fn import_file(bytes: &[u8], file_name: &str) -> Result<ImportedFile, ImportError> {
    let ctx = Ctx { file: display_name(file_name) };
    let format = file_format(bytes, file_name, &ctx)?;
    if format == Format::BSplineJson {
        let (surface, notes) = bspline::parse(bytes, &ctx)?;
        return Ok(ImportedFile::BSpline(ImportedBSpline { surface, notes }));
    }
    mesh_of_format(bytes, format, &ctx).map(ImportedFile::Mesh)
}

/// Imports an OBJ, glTF or GLB file from memory. `file_name` is used for format detection
/// (after the content) and error messages.
pub fn import_mesh(bytes: &[u8], file_name: &str) -> Result<Imported, ImportError> {
    let ctx = Ctx { file: display_name(file_name) };
    let format = file_format(bytes, file_name, &ctx)?;
    mesh_of_format(bytes, format, &ctx)
}

/// The format of a non-empty file within the size limit.
fn file_format(bytes: &[u8], file_name: &str, ctx: &Ctx) -> Result<Format, ImportError> {
    if bytes.len() > MAX_BYTES {
        return Err(ctx.too_large("bytes", bytes.len() as u64, MAX_BYTES));
    }
    if bytes.iter().all(|b| b.is_ascii_whitespace()) {
        return Err(ctx.empty("file is empty"));
    }
    match detect_format(bytes, file_name) {
        Some(f) => Ok(f),
        None if looks_like_obj(bytes) => Ok(Format::Obj),
        None => {
            let ext = extension(file_name);
            let what = if ext.is_empty() { "this file".to_string() } else { format!("'.{ext}' files") };
            Err(ctx
                .unsupported(format!("cannot import {what}; expected a Wavefront .obj, a glTF 2.0 .gltf, a .glb or a B-spline surface .json file")))
        }
    }
}

fn mesh_of_format(bytes: &[u8], format: Format, ctx: &Ctx) -> Result<Imported, ImportError> {
    let raw = match format {
        Format::Obj => obj::parse(bytes, ctx)?,
        Format::Gltf => self::gltf::parse_gltf(bytes, ctx)?,
        Format::Glb => self::gltf::parse_glb(bytes, ctx)?,
        Format::BSplineJson => return Err(ctx.unsupported("this is a B-spline surface, not a mesh")),
    };
    finish(raw, format, ctx)
}

/// Welds, validates and measures a parsed mesh.
fn finish(raw: RawMesh, format: Format, ctx: &Ctx) -> Result<Imported, ImportError> {
    let RawMesh { positions, triangles, source_polygons, dropped_faces, mut notes, quads } = raw;
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
    check_scale(&raw_mesh.positions, ctx)?;
    let (mesh, report, face_map) = weld_with_face_map(&raw_mesh, WELD_TOLERANCE * diag);
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
    let faces = polygon_faces(&mesh, &quads, &face_map);
    Ok(Imported {
        mesh,
        faces,
        stats,
        format,
        source_polygons,
        merged_vertices: report.merged_vertices,
        dropped_faces: dropped_faces + report.dropped_faces,
        notes,
    })
}

/// The faces of the welded `mesh`: a quad where both triangles of an input quad survived
/// next to each other and still form a quad (4 distinct corners, split from corner 0), else
/// triangles.
fn polygon_faces(mesh: &TriMesh, quads: &[usize], face_map: &[u32]) -> Vec<Face> {
    let mut quad_at = vec![false; mesh.face_count()];
    for &q in quads {
        let (a, b) = (face_map[q], face_map[q + 1]);
        if a == u32::MAX || b != a.wrapping_add(1) {
            continue;
        }
        let ([p, q1, r], [p2, r2, s]) = (mesh.triangles[a as usize], mesh.triangles[b as usize]);
        if p == p2 && r == r2 && s != q1 {
            quad_at[a as usize] = true;
        }
    }
    let mut faces = Vec::with_capacity(mesh.face_count());
    let mut f = 0;
    while f < mesh.face_count() {
        let t = mesh.triangles[f];
        if quad_at[f] {
            faces.push(Face::quad([t[0], t[1], t[2], mesh.triangles[f + 1][2]]));
            f += 2;
        } else {
            faces.push(Face::triangle(t));
            f += 1;
        }
    }
    faces
}
