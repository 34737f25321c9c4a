//! Meshes with adapted face size (Sec. 3): influence zones and the sizing field g
//! ([`influence_zones`], Fig. 13), and pliant remeshing to it ([`pliant`]) on a halfedge mesh;
//! quad meshes along a cross field on a B-spline patch (Sec. 5.2): [`cross_field`], [`seamless`]
//! and [`quad_remeshing`]. The sizing's kinds, ε and N with their ranges, and how a link holds
//! them.
//!
//! Typical use:
//! ```no_run
//! # use spherical_faces::geometry::mesh::{topology::Topology, TriMesh};
//! # use spherical_faces::congruence::central_spheres::{jet_fit, JetParams};
//! # use spherical_faces::remeshing::{SizingField, RemeshParams, pliant_remesh, DEFAULT_EPSILON};
//! # use spherical_faces::progress::ignore;
//! # let reference = TriMesh::default();
//! let topo = Topology::new(&reference);
//! let field = jet_fit(&reference, &topo, &JetParams::default(), &mut ignore).unwrap();
//! let sizing = SizingField::from_curvature(&reference, &topo, &field, DEFAULT_EPSILON);
//! let remeshed = pliant_remesh(&reference, &sizing, &RemeshParams::default(), &mut ignore).unwrap();
//! ```

pub mod cross_field;
pub mod influence_zones;
pub mod pliant;
pub mod quad_remeshing;
pub mod seamless;

use serde::{Deserialize, Serialize};

use crate::geometry::mesh::topology::Topology;
use crate::geometry::mesh::TriMesh;
use crate::geometry::sphere::Sphere;
use crate::params::{LinkReader, LinkWriter, ParamRange};
use crate::progress::{Cancelled, OnProgress};
use crate::reference::assumptions::Warning;

pub use influence_zones::{influence_zone, local_spheres_orthogonal, mean_edge_length, zone_diameter, SizingBounds, SizingField, DEFAULT_EPSILON};
pub use pliant::{
    face_cap, pliant_remesh, pliant_remesh_with_stats, RemeshError, RemeshOutput, RemeshParams, RoundStats, COLLAPSE_BELOW, SPLIT_ABOVE,
    TARGET_FACTOR,
};

/// The most faces any remesh may ask for, in the CLI, the design link and the app alike.
pub const MAX_FACES: usize = 200_000;
/// The fewest.
pub const MIN_FACES: usize = 4;
/// A uniform remesh's face count N.
pub const FACES_RANGE: ParamRange<usize> = ParamRange::new("faces", MIN_FACES, MAX_FACES);
/// The sizing field's tolerance ε, relative to the bounding-box diagonal.
pub const EPSILON_RANGE: ParamRange<f64> = ParamRange::new("ε", 1e-7, 0.1);
/// The face count of a uniform remesh when none is given.
pub(crate) const DEFAULT_FACES: usize = 600;

/// A remesh refused, with the reference's failed assumptions (folds, slivers), which often say
/// why; one type for every method that remeshes.
#[derive(Clone, Debug, PartialEq)]
pub struct RemeshRefused {
    pub error: pliant::RemeshError,
    pub warnings: Vec<Warning>,
}

impl std::fmt::Display for RemeshRefused {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.error.fmt(f)?;
        self.warnings.iter().try_for_each(|w| write!(f, "; {w}"))
    }
}

impl std::error::Error for RemeshRefused {}

/// The most faces a triangle method (ST, ST with support structure) works on: beyond it the
/// panels outgrow the browser worker's memory (200k faces with support structure: 2.6 GB and a
/// 500 MB schedule), so the user is asked to remesh first.
pub const MAX_METHOD_FACES: usize = 40_000;

/// Why [`Sizing::guarded_field`] or [`Sizing::remesh_to`] gave no mesh.
#[derive(Clone, Debug, PartialEq)]
pub enum GuardedRemeshError {
    Cancelled,
    NoFaces,
    /// The remesh missed its target, with the reference's failed assumptions.
    Refused(RemeshRefused),
    TooManyFaces(TooManyFaces),
}

/// A method's size guard: it would work on more faces than it handles.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TooManyFaces {
    pub faces: usize,
    pub limit: usize,
}

impl TooManyFaces {
    /// The face count to remesh to: half the limit.
    pub fn suggested(&self) -> usize {
        (self.limit / 2).max(MIN_FACES)
    }
}

impl std::fmt::Display for TooManyFaces {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "this would make about {} faces, more than the method handles ({}): remesh to about {} faces first",
            self.faces,
            self.limit,
            self.suggested()
        )
    }
}

impl std::error::Error for TooManyFaces {}

/// How the reference is remeshed before a method runs (Sec. 3).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Sizing {
    /// Influence zones of per-vertex spheres, ε relative to the bbox diagonal.
    Adaptive { epsilon: f64 },
    /// Uniform field for about this many faces.
    UniformFaces(usize),
    /// Use the reference triangulation as is (no remeshing).
    None,
}

/// The kind of a [`Sizing`], as links and the app name it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SizingKind {
    None,
    Adaptive,
    Faces,
}

impl SizingKind {
    pub const ALL: [SizingKind; 3] = [SizingKind::Adaptive, SizingKind::Faces, SizingKind::None];

    pub fn of(sizing: Sizing) -> Self {
        match sizing {
            Sizing::None => SizingKind::None,
            Sizing::Adaptive { .. } => SizingKind::Adaptive,
            Sizing::UniformFaces(_) => SizingKind::Faces,
        }
    }

    pub fn key(self) -> &'static str {
        match self {
            SizingKind::None => "none",
            SizingKind::Adaptive => "adaptive",
            SizingKind::Faces => "faces",
        }
    }

    pub fn label(self) -> &'static str {
        match self {
            SizingKind::None => "keep the reference triangulation",
            SizingKind::Adaptive => "adaptive (influence zones, ε)",
            SizingKind::Faces => "uniform, about N faces",
        }
    }

    pub fn from_key(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.key() == s)
    }

    /// The sizing of this kind with ε and N (the one the kind uses).
    pub fn sizing(self, epsilon: f64, faces: usize) -> Sizing {
        match self {
            SizingKind::None => Sizing::None,
            SizingKind::Adaptive => Sizing::Adaptive { epsilon },
            SizingKind::Faces => Sizing::UniformFaces(faces),
        }
    }
}

impl Sizing {
    /// ε or N against its range.
    pub fn check(self) -> Result<(), crate::params::ParamError> {
        match self {
            Sizing::Adaptive { epsilon } => EPSILON_RANGE.check(epsilon).map(|_| ()),
            Sizing::UniformFaces(n) => FACES_RANGE.check(n).map(|_| ()),
            Sizing::None => Ok(()),
        }
    }

    /// `&{key}=kind` and the value the kind uses (`&eps=…` or `&faces=…`).
    pub fn write_link(self, key: &str, link: &mut LinkWriter) {
        link.text(key, SizingKind::of(self).key());
        match self {
            Sizing::None => {}
            Sizing::Adaptive { epsilon } => link.number("eps", epsilon),
            Sizing::UniformFaces(n) => link.count("faces", n),
        }
    }

    /// Reads what [`Self::write_link`] wrote: the kind under `key`, with ε or N where the link
    /// has them (else the current ones, or the defaults).
    pub fn read_link(&mut self, key: &str, link: &mut LinkReader) {
        let kind = link.parsed(key, SizingKind::from_key);
        let epsilon = link.number("eps", EPSILON_RANGE);
        let faces = link.count("faces", FACES_RANGE);
        let kind = kind.unwrap_or(SizingKind::of(*self));
        let epsilon = epsilon.unwrap_or(match *self {
            Sizing::Adaptive { epsilon } => epsilon,
            _ => DEFAULT_EPSILON,
        });
        let faces = faces.unwrap_or(match *self {
            Sizing::UniformFaces(n) => n,
            _ => DEFAULT_FACES,
        });
        *self = kind.sizing(epsilon, faces);
    }

    /// The size guard: the faces the method will work on (the mesh's own, N, or what the
    /// adaptive `field` asks for) must not exceed `limit`.
    pub fn check_size(&self, mesh: &TriMesh, field: Option<&SizingField>, limit: usize) -> Result<(), TooManyFaces> {
        let faces = match (*self, field) {
            (Sizing::UniformFaces(n), _) => n,
            (Sizing::Adaptive { .. }, Some(field)) => field.expected_faces(mesh).min(usize::MAX as f64) as usize,
            _ => mesh.face_count(),
        };
        if faces > limit {
            Err(TooManyFaces { faces, limit })
        } else {
            Ok(())
        }
    }

    /// The sizing field a method asks for on `mesh` (the influence zones of `sphere_of(i)`, ε × the
    /// bbox diagonal, clamped to `bounds`; the uniform field for about N faces) behind the size
    /// guard ([`Self::check_size`], before any remeshing); None for [`Sizing::None`] (keep the
    /// mesh), the mesh checked for size. [`Self::remesh_to`] remeshes to it.
    pub fn guarded_field(
        &self,
        mesh: &TriMesh,
        topo: &Topology,
        sphere_of: &dyn Fn(usize) -> Sphere,
        bounds: SizingBounds,
        progress: &mut OnProgress,
    ) -> Result<Option<SizingField>, GuardedRemeshError> {
        let field = match *self {
            Sizing::Adaptive { epsilon } => {
                let eps = epsilon * mesh.bbox_diagonal();
                let field = SizingField::from_sphere_fn(mesh, topo, sphere_of, eps, bounds, progress);
                Some(field.map_err(|Cancelled| GuardedRemeshError::Cancelled)?)
            }
            Sizing::UniformFaces(n) => Some(SizingField::uniform_for_face_count(mesh, n)),
            Sizing::None => None,
        };
        self.check_size(mesh, field.as_ref(), MAX_METHOD_FACES).map_err(GuardedRemeshError::TooManyFaces)?;
        Ok(field)
    }

    /// The pliant remesh to `field` behind the target guard ([`Self::check_reached`]). A
    /// refusal carries `warnings()`, the reference's failed assumptions.
    pub fn remesh_to(
        &self,
        mesh: &TriMesh,
        field: &SizingField,
        params: &RemeshParams,
        warnings: &dyn Fn() -> Vec<Warning>,
        progress: &mut OnProgress,
    ) -> Result<TriMesh, GuardedRemeshError> {
        let refused = |error| GuardedRemeshError::Refused(RemeshRefused { error, warnings: warnings() });
        let remeshed = pliant_remesh(mesh, field, params, progress).map_err(|e| match e {
            pliant::RemeshError::Cancelled => GuardedRemeshError::Cancelled,
            pliant::RemeshError::NoFaces => GuardedRemeshError::NoFaces,
            error => refused(error),
        })?;
        self.check_reached(remeshed.face_count()).map_err(refused)?;
        Ok(remeshed)
    }

    /// Refuses a uniform remesh whose `faces` miss the target N by more than [`TARGET_FACTOR`].
    pub fn check_reached(&self, faces: usize) -> Result<(), pliant::RemeshError> {
        match *self {
            Sizing::UniformFaces(target) if faces * TARGET_FACTOR < target || faces > TARGET_FACTOR * target => {
                Err(pliant::RemeshError::TargetMissed { target, faces })
            }
            _ => Ok(()),
        }
    }
}
