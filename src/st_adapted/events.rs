//! What the ST method reports while it runs (its stage streams these to the app).

use glam::DVec3;

use crate::geometry::mesh::TriMesh;
use crate::geometry::sphere::Sphere;
use crate::panels::sphere_mesh::SphereMesh;
use crate::progress::{Cancelled, Progress};
use crate::solver::TermStats;

/// What the method reports while it runs; answering `Err(Cancelled)` stops it.
pub enum StAdaptedEvent<'a> {
    /// Progress of a step ("jet_fit", "sizing", "remesh", "init", "optimize", "metrics"); a step
    /// starts with 0 of 0.
    Progress(Progress<'a>),
    /// The sizing field g at the reference vertices (absolute lengths), before remeshing.
    Sizing { values: &'a [f64] },
    /// The triangulation after remeshing.
    Remeshed { mesh: &'a TriMesh },
    /// The face spheres from the central spheres, before optimization.
    Initialized { sphere_mesh: &'a SphereMesh },
    /// After every solver iteration: the optimizer stage, the iteration over all stages (`done`
    /// of `total`), its energy and per-term statistics, and the current vertices and face
    /// spheres (model coordinates).
    Iteration { progress: Progress<'a>, energy: f64, terms: &'a [TermStats], vertices: &'a [DVec3], spheres: &'a [Sphere] },
    /// After each round toward fewer moulds ([`super::moulds::fewer_moulds`]): the panels as moved.
    MouldRound { round: usize, sphere_mesh: &'a SphereMesh },
}

/// What the method reports to while it runs.
pub type OnEvent<'a> = dyn FnMut(StAdaptedEvent) -> Result<(), Cancelled> + 'a;
