//! The reference surface R every method approximates: a mesh (faces of 3 or 4 corners, as
//! loaded) or a B-spline surface f(u, v) with its tessellation ([`bspline`]), triangulated for
//! the algorithms, with its derived quantities computed on first use and kept
//! (geometry-central's `require` pattern): connectivity, vertex normals, the closest-point
//! hierarchy and the curvature (jet-fitted on a mesh, one fit per parameter set, so a method run
//! after the curvature stage fits nothing again; exact on a B-spline).
//!
//! Queries: [`Reference::closest_point`] gives the closest point, the normal there (interpolated
//! on a mesh, exact on a B-spline) and, on a B-spline, its (u, v).

pub mod assumptions;
pub mod bspline;
pub mod proximity;

use std::cell::{OnceCell, RefCell};
use std::fmt;
use std::rc::Rc;

use glam::DVec3;

use self::bspline::{SplineReference, SplineReferenceError};

/// The factor on the largest sampled distance between the facets and the B-spline
/// ([`Reference::tessellation_error`]) that covers the facets' points between the samples.
pub const TESSELLATION_ERROR_MARGIN: f64 = 1.5;
use crate::congruence::central_spheres::{jet_fit, CurvatureField, JetParams};
use crate::geometry::bspline::BSplineSurface;
use crate::geometry::closest::{ClosestHit, TriangleBvh};
use crate::geometry::mesh::topology::Topology;
use crate::geometry::mesh::{PolyMesh, TriMesh};
use crate::progress::{Cancelled, OnProgress};

/// A point of the reference surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    pub point: DVec3,
    /// The unit normal there (barycentric blend of the vertex normals on a mesh, exact on a
    /// B-spline); None where it vanishes.
    pub normal: Option<DVec3>,
    /// The triangle of [`Reference::mesh`] the point lies on (nearest to it on a B-spline), and
    /// its barycentric coordinates.
    pub triangle: usize,
    pub barycentric: [f64; 3],
    /// Parameter values on a B-spline (a mesh has none).
    pub uv: Option<[f64; 2]>,
}

impl SurfacePoint {
    /// Where a search for a point near this one starts ([`Reference::closest_point_near`]).
    pub fn search_start(&self) -> SearchStart {
        SearchStart { triangle: self.triangle, uv: self.uv }
    }
}

/// Where a point's last closest-point search ended: the next search for it, after it moved,
/// starts there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SearchStart {
    /// The triangle of [`Reference::mesh`] nearest to it.
    pub triangle: usize,
    /// Its parameters on a B-spline.
    pub uv: Option<[f64; 2]>,
}

/// Why a reference surface cannot be used.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ReferenceError {
    NoFaces,
    InvalidVertices,
    DegenerateBoundingBox,
}

impl fmt::Display for ReferenceError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ReferenceError::NoFaces => "the reference has no faces",
            ReferenceError::InvalidVertices => "the reference has invalid vertex indices or coordinates",
            ReferenceError::DegenerateBoundingBox => "the reference has a degenerate bounding box",
        })
    }
}

impl std::error::Error for ReferenceError {}

/// The reference surface and its cached derived data.
pub struct Reference {
    surface: PolyMesh,
    mesh: TriMesh,
    diagonal: f64,
    topology: OnceCell<Topology>,
    vertex_normals: OnceCell<Vec<DVec3>>,
    bvh: OnceCell<TriangleBvh>,
    boundary_bvh: OnceCell<TriangleBvh>,
    facet_sagitta: OnceCell<f64>,
    tessellation_error: OnceCell<f64>,
    max_dihedral_angle_deg: OnceCell<f64>,
    curvature: RefCell<Option<(JetParams, Rc<CurvatureField>)>>,
    spline: Option<SplineReference>,
}

impl Reference {
    /// A reference with faces of 3 or 4 corners; the algorithms see its triangulation
    /// ([`PolyMesh::triangulated`]).
    pub fn new(surface: PolyMesh) -> Self {
        let mesh = surface.triangulated();
        Self::with_triangulation(surface, mesh)
    }

    /// A triangle mesh reference.
    pub fn from_triangles(mesh: TriMesh) -> Self {
        Self::with_triangulation(PolyMesh::from(&mesh), mesh)
    }

    /// A B-spline reference with its tessellation ([`SplineReference::new`]).
    pub fn from_bspline(surface: BSplineSurface) -> Result<Self, SplineReferenceError> {
        let (spline, tessellation) = SplineReference::new(surface)?;
        let mesh = tessellation.triangulated();
        Ok(Self { spline: Some(spline), ..Self::with_triangulation(tessellation, mesh) })
    }

    fn with_triangulation(surface: PolyMesh, mesh: TriMesh) -> Self {
        Self {
            diagonal: mesh.bbox_diagonal(),
            surface,
            mesh,
            topology: OnceCell::new(),
            vertex_normals: OnceCell::new(),
            bvh: OnceCell::new(),
            boundary_bvh: OnceCell::new(),
            facet_sagitta: OnceCell::new(),
            tessellation_error: OnceCell::new(),
            max_dihedral_angle_deg: OnceCell::new(),
            curvature: RefCell::new(None),
            spline: None,
        }
    }

    /// The B-spline surface, when the reference is one.
    pub fn spline(&self) -> Option<&BSplineSurface> {
        self.spline.as_ref().map(|s| &s.surface)
    }

    /// The B-spline surface with its tessellation's parameters.
    pub fn spline_reference(&self) -> Option<&SplineReference> {
        self.spline.as_ref()
    }

    /// The surface as loaded (faces of 3 or 4 corners).
    pub fn surface(&self) -> &PolyMesh {
        &self.surface
    }

    /// Its triangulation, which the algorithms work on.
    pub fn mesh(&self) -> &TriMesh {
        &self.mesh
    }

    /// The bounding-box diagonal: the unit of every relative tolerance.
    pub fn diagonal(&self) -> f64 {
        self.diagonal
    }

    /// Connectivity of [`Self::mesh`].
    pub fn topology(&self) -> &Topology {
        self.topology.get_or_init(|| Topology::new(&self.mesh))
    }

    /// Area-weighted unit vertex normals of [`Self::mesh`].
    pub fn vertex_normals(&self) -> &[DVec3] {
        self.vertex_normals.get_or_init(|| self.mesh.vertex_normals())
    }

    /// The closest-point hierarchy of [`Self::mesh`].
    pub fn bvh(&self) -> &TriangleBvh {
        self.bvh.get_or_init(|| TriangleBvh::new(&self.mesh))
    }

    /// The closest-point hierarchy of the boundary of [`Self::mesh`]: its edges with one
    /// face, each as a degenerate triangle (a, b, b). Empty for a closed surface.
    pub(crate) fn boundary_bvh(&self) -> &TriangleBvh {
        self.boundary_bvh.get_or_init(|| {
            let topology = self.topology();
            let p = &self.mesh.positions;
            let segments = (0..topology.edges().len())
                .filter(|&e| topology.edge_faces(e).len() == 1)
                .map(|e| {
                    let [a, b] = topology.edges()[e];
                    [p[a as usize], p[b as usize], p[b as usize]]
                })
                .collect();
            TriangleBvh::from_triangles(segments)
        })
    }

    /// How far the facets lie from the smooth surface through the vertices, relative to the
    /// diagonal ([`facet_sagitta`]): no smooth panel comes closer to the facets. 0 for a
    /// B-spline reference, whose distances are measured to the spline.
    pub fn facet_sagitta(&self) -> f64 {
        *self.facet_sagitta.get_or_init(|| match self.spline {
            Some(_) => 0.0,
            None => facet_sagitta(&self.mesh, self.vertex_normals()),
        })
    }

    /// How far the triangulation's facets lie from the B-spline, absolute (0 for a mesh
    /// reference, which is its facets): the largest distance to the spline of the facets'
    /// centroids and edge midpoints, × [`TESSELLATION_ERROR_MARGIN`] for the points between them.
    /// A point's distance to the spline exceeds its distance to the facets by at most this.
    pub fn tessellation_error(&self) -> f64 {
        *self.tessellation_error.get_or_init(|| {
            let Some(spline) = &self.spline else { return 0.0 };
            let p = &self.mesh.positions;
            let mut error = 0.0f64;
            for t in &self.mesh.triangles {
                let [a, b, c] = t.map(|v| v as usize);
                for w in [[1.0 / 3.0; 3], [0.5, 0.5, 0.0], [0.0, 0.5, 0.5], [0.5, 0.0, 0.5]] {
                    let x = w[0] * p[a] + w[1] * p[b] + w[2] * p[c];
                    let start = [0, 1].map(|k| w[0] * spline.uv[a][k] + w[1] * spline.uv[b][k] + w[2] * spline.uv[c][k]);
                    error = error.max(spline.closest_point(x, start).1.distance(x));
                }
            }
            TESSELLATION_ERROR_MARGIN * error
        })
    }

    /// The distance from `p` to the surface, given the closest point `hit` of the triangulation:
    /// on a B-spline, to its exact closest point from there; on a mesh, the hit's.
    pub fn distance_from_hit(&self, p: DVec3, hit: ClosestHit) -> f64 {
        match &self.spline {
            Some(_) => self.surface_point_of(p, hit, None).point.distance(p),
            None => hit.distance,
        }
    }

    /// The largest angle (degrees) between the normals of two facets sharing an interior edge of
    /// the triangulation: how sharply the reference itself bends from facet to facet, against
    /// which the panels' kinks are judged.
    pub(crate) fn max_dihedral_angle_deg(&self) -> f64 {
        *self.max_dihedral_angle_deg.get_or_init(|| {
            let normal = |f: u32| {
                let t = self.mesh.triangles[f as usize].map(|v| self.mesh.positions[v as usize]);
                (t[1] - t[0]).cross(t[2] - t[0]).normalize_or_zero()
            };
            let topo = self.topology();
            (0..topo.edges().len())
                .filter_map(|e| match topo.edge_faces(e) {
                    [(f, _), (g, _)] => Some(normal(*f).dot(normal(*g)).clamp(-1.0, 1.0).acos().to_degrees()),
                    _ => None,
                })
                .fold(0.0, f64::max)
        })
    }

    /// The jet-fitted curvature with `params`: computed once per parameter set (the last one
    /// is kept).
    pub fn curvature(&self, params: &JetParams, progress: &mut OnProgress) -> Result<Rc<CurvatureField>, Cancelled> {
        if let Some(field) = self.cached_curvature(params) {
            return Ok(field);
        }
        let field = Rc::new(match &self.spline {
            Some(spline) => {
                let topology = self.topology();
                let boundary = (0..self.mesh.vertex_count()).map(|v| topology.is_boundary_vertex(v)).collect();
                spline.curvature(&self.mesh.positions, boundary, self.diagonal)
            }
            None => jet_fit(&self.mesh, self.topology(), params, progress)?,
        });
        *self.curvature.borrow_mut() = Some((params.clone(), field.clone()));
        Ok(field)
    }

    /// The curvature computed with `params`, if it is.
    pub(crate) fn cached_curvature(&self, params: &JetParams) -> Option<Rc<CurvatureField>> {
        self.curvature.borrow().as_ref().filter(|(p, _)| p == params).map(|(_, f)| f.clone())
    }

    /// Faces, finite coordinates, valid indices and a bounding box with extent.
    pub fn validate(&self) -> Result<(), ReferenceError> {
        let m = &self.mesh;
        if m.face_count() == 0 || m.vertex_count() == 0 {
            return Err(ReferenceError::NoFaces);
        }
        if m.triangles.iter().flatten().any(|&v| v as usize >= m.vertex_count()) || m.positions.iter().any(|p| !p.is_finite()) {
            return Err(ReferenceError::InvalidVertices);
        }
        if !(self.diagonal > 0.0 && self.diagonal.is_finite()) {
            return Err(ReferenceError::DegenerateBoundingBox);
        }
        Ok(())
    }

    /// The closest point of the surface to `p` (None for an empty surface).
    pub fn closest_point(&self, p: DVec3) -> Option<SurfacePoint> {
        self.bvh().closest_point(p).map(|hit| self.surface_point_of(p, hit, None))
    }

    /// [`Self::closest_point`], started from triangle `previous` of [`Self::mesh`] (e.g. the
    /// triangle of a moving point's last closest point): the same point as an unstarted search,
    /// visiting a small part of the hierarchy.
    pub(crate) fn closest_point_near(&self, p: DVec3, previous: Option<SearchStart>) -> Option<SurfacePoint> {
        let bvh = self.bvh();
        match previous {
            Some(s) => bvh.closest_point_from(p, s.triangle),
            None => bvh.closest_point(p),
        }
        .map(|hit| self.surface_point_of(p, hit, previous))
    }

    /// [`Self::closest_point`] on the B-spline, started from a hit on the tessellation (the
    /// point `p` it was the closest to): from where this point's `previous` search ended when it
    /// ended on the same triangle (a point that moved a little is a Newton step or two from
    /// there), else from the hit's parameters.
    fn surface_point_of(&self, p: DVec3, hit: ClosestHit, previous: Option<SearchStart>) -> SurfacePoint {
        let Some(spline) = &self.spline else { return self.surface_point(hit) };
        let t = self.mesh.triangles[hit.triangle];
        let w = hit.barycentric;
        let start = previous
            .filter(|s| s.triangle == hit.triangle)
            .and_then(|s| s.uv)
            .unwrap_or_else(|| [0, 1].map(|k| (0..3).map(|c| w[c] * spline.uv[t[c] as usize][k]).sum::<f64>()));
        let (uv, point, normal) = spline.closest_point(p, start);
        SurfacePoint { point, normal, triangle: hit.triangle, barycentric: w, uv: Some(uv) }
    }

    fn surface_point(&self, hit: ClosestHit) -> SurfacePoint {
        let t = self.mesh.triangles[hit.triangle];
        let w = hit.barycentric;
        let n = self.vertex_normals();
        let normal = (w[0] * n[t[0] as usize] + w[1] * n[t[1] as usize] + w[2] * n[t[2] as usize]).try_normalize();
        SurfacePoint { point: hit.point, normal, triangle: hit.triangle, barycentric: w, uv: None }
    }

    /// The same surface moved by −`t` and scaled by 1/`s` (the frame y = (x − t)/s in which an
    /// optimization's weights are dimensionless).
    pub fn in_frame(&self, t: DVec3, s: f64) -> Reference {
        let inv = 1.0 / s;
        let mesh = TriMesh::new(self.mesh.positions.iter().map(|&p| (p - t) * inv).collect(), self.mesh.triangles.clone());
        let surface = PolyMesh::new(mesh.positions.clone(), self.surface.faces.clone());
        let spline = self.spline.as_ref().map(|sp| SplineReference { surface: sp.surface.in_frame(t, s), ..sp.clone() });
        Self { spline, ..Self::with_triangulation(surface, mesh) }
    }
}

/// The median over the triangles of `mesh` of the height of the smooth surface through its
/// vertices over the triangle, relative to the bounding-box diagonal. With the surface's second
/// fundamental form II the height of a quadratic vanishing at the corners is
/// (1/18) Σ_edges eᵀ II e at the centroid, and eᵀ II e ≈ ⟨n_b − n_a, b − a⟩ for the edge e = b − a
/// with vertex normals n (exact on a sphere: ℓ²/(6R) for an equilateral triangle of side ℓ). The
/// edge terms are summed in absolute value, so that on a saddle, where they cancel at the
/// centroid, the bulge elsewhere in the triangle still counts.
fn facet_sagitta(mesh: &TriMesh, vertex_normals: &[DVec3]) -> f64 {
    let p = &mesh.positions;
    let sagitta: Vec<f64> = mesh
        .triangles
        .iter()
        .map(|t| {
            let t = t.map(|v| v as usize);
            let edge = |a: usize, b: usize| (vertex_normals[b] - vertex_normals[a]).dot(p[b] - p[a]).abs();
            (edge(t[0], t[1]) + edge(t[1], t[2]) + edge(t[2], t[0])) / 18.0
        })
        .collect();
    crate::stats::median(&sagitta).unwrap_or(0.0) / mesh.bbox_diagonal().max(f64::MIN_POSITIVE)
}
