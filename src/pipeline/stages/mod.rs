//! One file per stage: each runs a method on the loaded reference, streams to a [`Sink`] and
//! returns its summary. `protocol.rs` lists them; the session runs them.
//!
//! [`Sink`]: super::sink::Sink

pub mod curvature;
pub mod sq;
pub mod st_adapted;
pub mod st_support;

use std::fmt;

use crate::progress::Cancelled;
use crate::sq::SqError;
use crate::st_adapted::StAdaptedError;
use crate::st_support::StSupportError;

/// Why a stage gave no result.
#[derive(Clone, Debug, PartialEq)]
pub enum StageError {
    Cancelled,
    StAdapted(StAdaptedError),
    StSupport(StSupportError),
    Sq(SqError),
}

impl fmt::Display for StageError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StageError::Cancelled => f.write_str("cancelled"),
            StageError::StAdapted(e) => e.fmt(f),
            StageError::StSupport(e) => e.fmt(f),
            StageError::Sq(e) => e.fmt(f),
        }
    }
}

impl std::error::Error for StageError {}

impl StageError {
    /// The face count to remesh to when the method refused the size of its input.
    pub fn remesh_to(&self) -> Option<usize> {
        match self {
            StageError::StAdapted(crate::st_adapted::StAdaptedError::TooManyFaces(e))
            | StageError::StSupport(crate::st_support::StSupportError::TooManyFaces(e)) => Some(e.suggested()),
            _ => None,
        }
    }
}

impl From<Cancelled> for StageError {
    fn from(_: Cancelled) -> Self {
        StageError::Cancelled
    }
}

impl From<StAdaptedError> for StageError {
    fn from(e: StAdaptedError) -> Self {
        match e {
            StAdaptedError::Cancelled => StageError::Cancelled,
            e => StageError::StAdapted(e),
        }
    }
}

impl From<StSupportError> for StageError {
    fn from(e: StSupportError) -> Self {
        match e {
            StSupportError::Cancelled => StageError::Cancelled,
            e => StageError::StSupport(e),
        }
    }
}

impl From<SqError> for StageError {
    fn from(e: SqError) -> Self {
        match e {
            SqError::Cancelled => StageError::Cancelled,
            e => StageError::Sq(e),
        }
    }
}
