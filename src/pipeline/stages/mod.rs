//! One file per stage: the curvature, and one per method, each implementing
//! [`super::method::Method`]. `protocol.rs` lists the methods; the session runs them.

pub mod curvature;
pub mod sq;
pub mod st_adapted;
pub mod st_support;

use std::fmt;

use crate::progress::Cancelled;

/// Why a stage gave no result.
#[derive(Clone, Debug, PartialEq)]
pub enum StageError {
    Cancelled,
    /// The method refused its input or failed on it, in words for the user.
    Refused(Refusal),
}

/// A method's refusal: what it says, and the face count to remesh to first when it refused the
/// size of its input.
#[derive(Clone, Debug, PartialEq)]
pub struct Refusal {
    pub message: String,
    pub remesh_to: Option<usize>,
}

impl fmt::Display for StageError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StageError::Cancelled => f.write_str("cancelled"),
            StageError::Refused(r) => f.write_str(&r.message),
        }
    }
}

impl std::error::Error for StageError {}

impl StageError {
    /// A method's error, with the face count to remesh to when it refused its input's size.
    pub fn refused(error: &dyn fmt::Display, remesh_to: Option<usize>) -> Self {
        StageError::Refused(Refusal { message: error.to_string(), remesh_to })
    }

    /// The face count to remesh to when the method refused the size of its input.
    pub fn remesh_to(&self) -> Option<usize> {
        match self {
            StageError::Refused(r) => r.remesh_to,
            StageError::Cancelled => None,
        }
    }
}

impl From<Cancelled> for StageError {
    fn from(_: Cancelled) -> Self {
        StageError::Cancelled
    }
}
