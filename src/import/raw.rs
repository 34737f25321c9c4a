//! What the format parsers share: the size limits, the raw mesh they produce before welding,
//! and the typed [`ImportError`] whose message starts with the file name.

use std::fmt;

use glam::DVec3;

use crate::text::printable;

/// Largest accepted triangle count (after triangulation, before welding).
pub const MAX_TRIANGLES: usize = 2_000_000;
/// Largest accepted input size in bytes (512 MiB).
pub const MAX_BYTES: usize = 512 << 20;
/// Largest accepted vertex count before welding: three per triangle.
pub const MAX_VERTICES: usize = 3 * MAX_TRIANGLES;

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
        ImportError::Malformed { file: self.file.clone(), line, message: printable(&message.into()) }
    }

    pub(crate) fn unsupported(&self, message: impl Into<String>) -> ImportError {
        ImportError::Unsupported { file: self.file.clone(), message: printable(&message.into()) }
    }

    pub fn empty(&self, reason: impl Into<String>) -> ImportError {
        ImportError::Empty { file: self.file.clone(), reason: printable(&reason.into()) }
    }

    pub fn too_large(&self, what: &str, count: u64, limit: usize) -> ImportError {
        ImportError::TooLarge { file: self.file.clone(), what: what.into(), count, limit: limit as u64 }
    }

    /// Rejects counts over [`MAX_TRIANGLES`] / [`MAX_VERTICES`].
    pub(crate) fn check_limits(&self, triangles: u64, vertices: u64) -> Result<(), ImportError> {
        if triangles > MAX_TRIANGLES as u64 {
            return Err(self.too_large("triangles", triangles, MAX_TRIANGLES));
        }
        if vertices > MAX_VERTICES as u64 {
            return Err(self.too_large("vertices", vertices, MAX_VERTICES));
        }
        Ok(())
    }
}

/// The coordinate range the geometry computes with: lengths are squared (and areas multiplied),
/// which overflows beyond about 1e154 and underflows below 1e-154.
pub const MAX_COORDINATE: f64 = 1e100;
/// The smallest bounding-box diagonal, see [`MAX_COORDINATE`].
pub const MIN_DIAGONAL: f64 = 1e-100;

/// Refuses a model whose scale the geometry cannot compute with: its largest coordinate and
/// its extent (the largest side of its bounding box, computed without squaring).
pub(crate) fn check_scale(positions: &[DVec3], ctx: &Ctx) -> Result<(), ImportError> {
    let largest = positions.iter().map(|p| p.abs().max_element()).fold(0.0, f64::max);
    let (lo, hi) = positions.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
    let diag = if positions.is_empty() { 0.0 } else { (hi - lo).max_element() };
    if largest > MAX_COORDINATE {
        return Err(ctx.unsupported(format!(
            "coordinates reach {largest:.3e}, beyond the range this program computes in (up to {MAX_COORDINATE:e}): rescale the model"
        )));
    }
    if diag > 0.0 && diag < MIN_DIAGONAL {
        return Err(ctx.unsupported(format!(
            "the model is {diag:.3e} across, below the range this program computes in (at least {MIN_DIAGONAL:e}): rescale the model"
        )));
    }
    Ok(())
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
    /// The first of the two consecutive triangles of every quad (the quad's corner 0 is the
    /// first corner of both).
    pub quads: Vec<usize>,
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
