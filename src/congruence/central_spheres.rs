//! Per-vertex curvature by jet fitting (Cazals & Pouget 2005) and the central spheres of paper
//! Sec. 2.6 (Def. 2.9).
//!
//! For each vertex v:
//! 1. **Neighbourhood**: k-rings grown from the one-ring (breadth first, generation-stamped visited
//!    array) until there are at least `max(min_points, ⌈1.5·coefficients⌉ + 1)` points (v included)
//!    or `max_rings` rings were taken.
//! 2. **Frame**: the area-weighted vertex normal (when the face normals around v cancel: the PCA
//!    normal of the neighbourhood, oriented toward +z), and a tangent basis.
//! 3. **Fit**: least squares, by Householder QR, of the height function z = J(x, y) of degree
//!    `degree` with constant and linear terms, in coordinates scaled to unit mean neighbour
//!    distance. Fewer points than coefficients or a rank-deficient system drops the degree (to 2 at
//!    the lowest), counted in `low_degree_fits`. If the fitted slope exceeds ≈ 27° (a bad input
//!    normal) the fit is repeated once in the jet's own normal frame.
//! 4. **Shape operator** of the graph at (0, 0), exact with the gradient: principal curvatures
//!    k1 ≥ k2, directions, jet normal, H = (k1 + k2)/2.
//!
//! **Sign convention**: curvatures are measured w.r.t. the unit normal `n` oriented like the mesh's
//! area-weighted vertex normal (i.e. by the face orientation); κ > 0 where the surface bends toward
//! `n`. An outward-oriented sphere of radius R has κ1 = κ2 = H = −1/R.
//!
//! The **central sphere** (Def. 2.9) touches the surface at the vertex position f with the jet
//! normal n and has curvature H: centre f + n/H, radius 1/H, stored normalized as
//! [`Sphere::from_point_normal_curvature`]`(f, n, H)`, which is finite for every H and the tangent
//! plane at H = 0. The sphere passes through the vertex itself (not the jet's projection of it).
//!
//! **Accuracy** (measured in `tests/curvature.rs`, smooth input): degree 3 converges as O(h²).
//! On a torus R = 3, r = 1 the worst relative error of H is 12% at 12° per edge around the tube
//! and 1.8% at 5°; degree 4 (3-ring neighbourhoods, ≈ 2.5× slower) reaches 1.1% at 10°. Spheres:
//! |H·R ∓ 1| ≤ 0.3% at 2.3° per edge. Speed: ≈ 0.25 s per 100k vertices (degree 3, release).
//!
//! A vertex whose neighbourhood cannot be fitted (isolated, collinear or coincident neighbours,
//! non-finite input) gets zero curvature, the frame normal, its tangent plane as central sphere,
//! and is counted in `failed_fits`. No output is ever NaN or infinite.

use crate::params::{LinkFields, LinkReader, LinkWriter, ParamRange};
use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::jet::{coefficient_count, tangent_basis, JetFitter};
use crate::geometry::mesh::topology::Topology;
use crate::geometry::mesh::TriMesh;
use crate::geometry::sphere::Sphere;
use crate::progress::{Cancelled, OnProgress, Progress};

/// A vertex is *planar* when |H| · bbox diagonal < this. A sphere of radius 1000 diagonals is
/// indistinguishable from a plane for design purposes.
pub const PLANAR_TOLERANCE: f64 = 1e-3;

/// `h_changes_sign` needs vertices with H · diag above `+SIGN_CHANGE_THRESHOLD` and others below
/// `−SIGN_CHANGE_THRESHOLD` (central spheres with radii under 5 bbox diagonals on both sides),
/// each on at least [`SIGN_CHANGE_MIN_FRACTION`] of the fitted vertices.
///
/// Measured: a smooth one-signed shell (the Dome sample) stays below −0.8; the WaveRoof sample
/// spans [−3.5, 2.1]. The Enneper mesh `enneper2.obj` (H = 0 in theory, but its vertices lie up to
/// 5e-4·diag off the smooth surface), as imported, reads H·diag in [−0.84, 1.78] (boundary
/// included; interior |H|·diag ≤ 0.79, rms 0.14), with 13% of the vertices above +0.2 and 3% below
/// −0.2. So it honestly reports a sign change: its H is zero up to noise, which is what matters to
/// central-sphere methods. A threshold hiding that noise (≥ 0.85) would also hide real sign
/// changes of gently curved roofs.
pub const SIGN_CHANGE_THRESHOLD: f64 = 0.2;

/// The most points of one fit's neighbourhood. A vertex of valence 10,000 (a fan-triangulated
/// polygon) would otherwise put 10,000 points into the fit of each of its neighbours: the work
/// would grow with the square of the valence. Larger one-rings are sampled evenly.
pub const MAX_NEIGHBOURHOOD: usize = 96;

/// Each side of a sign change needs at least this fraction of the successfully fitted vertices
/// (and at least one vertex), so that a few noisy fits (e.g. at corners) do not decide it.
pub const SIGN_CHANGE_MIN_FRACTION: f64 = 0.01;

/// How often `progress` is called, in vertices.
const PROGRESS_EVERY: usize = 1024;

/// Parameters of the jet fit.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(default)]
pub struct JetParams {
    /// Polynomial degree, 2..=4 (clamped). Default 3.
    pub degree: u8,
    /// Grow rings until the neighbourhood (the vertex included) has at least this many points. The
    /// fit always asks for at least ⌈1.5·coefficients⌉ + 1 points (10, 16, 24 for degree 2, 3, 4).
    /// Default 16: the 2-ring (19 points) of a regular valence-6 mesh.
    pub min_points: usize,
    /// Never grow more than this many rings (≥ 1). Default 4.
    pub max_rings: usize,
}

impl Default for JetParams {
    fn default() -> Self {
        Self { degree: 3, min_points: min_points_for_degree(3), max_rings: 4 }
    }
}

/// The jet's degree and its most rings, as a design sets them.
pub const JET_DEGREE_RANGE: ParamRange<usize> = ParamRange::new("jet degree", 2, 4);
pub const JET_RINGS_RANGE: ParamRange<usize> = ParamRange::new("jet rings", 1, 8);

impl LinkFields for JetParams {
    fn write_link(&self, link: &mut LinkWriter) {
        link.count("jet_degree", self.degree as usize);
        link.count("jet_rings", self.max_rings);
    }

    fn read_link(&mut self, link: &mut LinkReader) {
        let mut degree = self.degree as usize;
        link.set_count("jet_degree", JET_DEGREE_RANGE, &mut degree);
        self.degree = degree as u8;
        link.set_count("jet_rings", JET_RINGS_RANGE, &mut self.max_rings);
    }
}

impl JetParams {
    /// Defaults for degree `degree` (clamped to 2..=4).
    pub fn with_degree(degree: u8) -> Self {
        let degree = degree.clamp(2, 4);
        Self { degree, min_points: min_points_for_degree(degree), ..Self::default() }
    }
}

/// ⌈1.5 · coefficients⌉ + 1: the least neighbourhood size for a fit of degree `degree`.
pub const fn min_points_for_degree(degree: u8) -> usize {
    let n = coefficient_count(degree);
    (3 * n).div_ceil(2) + 1
}

/// Curvature at one vertex. See the module documentation for the sign convention.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
pub struct VertexCurvature {
    /// Principal curvatures, k1 ≥ k2.
    pub k1: f64,
    pub k2: f64,
    /// H = (k1 + k2)/2.
    pub mean: f64,
    /// Unit jet normal, oriented like the mesh vertex normal.
    pub normal: DVec3,
    /// Unit principal directions of k1 and k2; (dir1, dir2, normal) is right-handed orthonormal.
    pub dir1: DVec3,
    pub dir2: DVec3,
}

/// Whole-mesh statistics of a curvature field.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct CurvatureSummary {
    /// Min, max and mean of H over the successfully fitted vertices (0 if there are none).
    pub min_h: f64,
    pub max_h: f64,
    pub mean_h: f64,
    /// H takes clearly both signs: see [`SIGN_CHANGE_THRESHOLD`] and [`SIGN_CHANGE_MIN_FRACTION`].
    pub h_changes_sign: bool,
    pub boundary_vertices: usize,
    /// Vertices with |H|·diag < [`PLANAR_TOLERANCE`] (failed fits included: their H is 0).
    pub planar_vertices: usize,
    /// Fits that used a lower degree than requested.
    pub low_degree_fits: usize,
    /// Vertices without a fit (zero curvature reported).
    pub failed_fits: usize,
    /// The most points one fit used (at most [`MAX_NEIGHBOURHOOD`]).
    pub largest_neighbourhood: usize,
}

/// Per-vertex curvature and central spheres of a mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct CurvatureField {
    pub vertices: Vec<VertexCurvature>,
    /// Normalized central spheres (Def. 2.9), one per vertex; planes where H = 0.
    pub central_spheres: Vec<Sphere>,
    pub boundary: Vec<bool>,
    pub planar: Vec<bool>,
    pub summary: CurvatureSummary,
}

/// Refusal of the central-sphere methods: too few vertices have a usable central sphere (H ≈ 0
/// on most of the surface, e.g. a minimal surface).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct UnusableCentralSpheres {
    /// Vertices whose central sphere is not usable ([`CurvatureField::is_usable`]).
    pub unusable: usize,
    pub vertices: usize,
}

impl std::fmt::Display for UnusableCentralSpheres {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "the reference has no usable central spheres: H ≈ 0 on {} of {} vertices (minimal surface?)", self.unusable, self.vertices)
    }
}

impl std::error::Error for UnusableCentralSpheres {}

impl CurvatureField {
    /// Whether vertex `i`'s central sphere is usable: not planar (|H| · `diag` ≥
    /// [`PLANAR_TOLERANCE`]), |H| ≥ `min_curvature_ratio` · (|κ1| + |κ2|)/2 (the principal
    /// curvatures do not nearly cancel), H finite and non-zero.
    pub fn is_usable(&self, i: usize, diag: f64, min_curvature_ratio: f64) -> bool {
        let c = &self.vertices[i];
        let planar = self.planar.get(i).copied().unwrap_or(false) || c.mean.abs() * diag < PLANAR_TOLERANCE;
        let ratio_ok = c.mean.abs() >= min_curvature_ratio * 0.5 * (c.k1.abs() + c.k2.abs());
        !planar && ratio_ok && c.mean.is_finite() && c.mean != 0.0
    }

    /// [`Self::is_usable`] for the first `vertices` vertices; an error when none or fewer than
    /// `min_fraction` of them are usable.
    pub(crate) fn usable_central_spheres(
        &self,
        vertices: usize,
        diag: f64,
        min_curvature_ratio: f64,
        min_fraction: f64,
    ) -> Result<Vec<bool>, UnusableCentralSpheres> {
        let nv = vertices.min(self.vertices.len());
        let usable: Vec<bool> = (0..nv).map(|i| self.is_usable(i, diag, min_curvature_ratio)).collect();
        let count = usable.iter().filter(|&&u| u).count();
        if count == 0 || (count as f64) < min_fraction * nv as f64 {
            return Err(UnusableCentralSpheres { unusable: nv - count, vertices: nv });
        }
        Ok(usable)
    }
}

/// Jet-fitted curvature of every vertex. Reports step "jet_fit" every 1024 vertices and at the
/// end.
pub fn jet_fit(mesh: &TriMesh, topo: &Topology, params: &JetParams, progress: &mut OnProgress) -> Result<CurvatureField, Cancelled> {
    let nv = mesh.vertex_count().min(topo.vertex_count());
    let degree = params.degree.clamp(2, 4);
    let min_points = params.min_points.max(min_points_for_degree(degree));
    let max_rings = params.max_rings.max(1);
    let diag = mesh.bbox_diagonal();
    let diag = if diag.is_finite() { diag } else { 0.0 };
    let pos = &mesh.positions;
    let normals = frame_normals(mesh);

    let mut ring = RingCollector::new(nv);
    let mut fitter = JetFitter::new();
    let mut vertices = Vec::with_capacity(nv);
    let mut central_spheres = Vec::with_capacity(nv);
    let mut boundary = Vec::with_capacity(nv);
    let mut low_degree_fits = 0;
    let mut largest_neighbourhood = 0;
    let mut failed = vec![false; nv];

    for v in 0..nv {
        if v % PROGRESS_EVERY == 0 && v > 0 {
            progress(Progress::new("jet_fit", v, nv))?;
        }
        boundary.push(topo.is_boundary_vertex(v));
        ring.collect(topo, v, min_points, max_rings);
        largest_neighbourhood = largest_neighbourhood.max(ring.points.len());
        let f = pos[v];
        let pts = ring.points.iter().map(|&i| pos[i as usize]);
        let n0 = normals[v].or_else(|| JetFitter::pca_normal(pts.clone(), DVec3::Z)).unwrap_or(DVec3::Z);
        let geo = if f.is_finite() { fitter.fit(f, n0, pts, degree) } else { None };
        let (vc, sphere) = match geo {
            Some(g) => {
                if g.degree < degree {
                    low_degree_fits += 1;
                }
                let mean = 0.5 * (g.k1 + g.k2);
                let vc = VertexCurvature { k1: g.k1, k2: g.k2, mean, normal: g.normal, dir1: g.dir1, dir2: g.dir2 };
                (vc, Sphere::from_point_normal_curvature(f, g.normal, mean))
            }
            None => {
                failed[v] = true;
                let (t1, t2) = tangent_basis(n0);
                let vc = VertexCurvature { k1: 0.0, k2: 0.0, mean: 0.0, normal: n0, dir1: t1, dir2: t2 };
                let fp = if f.is_finite() { f } else { DVec3::ZERO };
                (vc, Sphere::plane(fp, n0))
            }
        };
        let sphere = if sphere.is_finite() { sphere } else { Sphere::plane(DVec3::ZERO, vc.normal) };
        vertices.push(vc);
        central_spheres.push(sphere);
    }
    progress(Progress::new("jet_fit", nv, nv))?;

    let planar: Vec<bool> = vertices.iter().map(|c| c.mean.abs() * diag < PLANAR_TOLERANCE).collect();
    let mut summary = summarize(&vertices, &failed, &boundary, &planar, diag, low_degree_fits);
    summary.largest_neighbourhood = largest_neighbourhood;
    Ok(CurvatureField { vertices, central_spheres, boundary, planar, summary })
}

impl CurvatureField {
    /// The field of curvatures known exactly at the vertices `positions` (a parametric reference
    /// surface): central spheres, planar flags and summary as [`jet_fit`] makes them.
    pub(crate) fn from_vertex_curvatures(positions: &[DVec3], vertices: Vec<VertexCurvature>, boundary: Vec<bool>, diag: f64) -> Self {
        let central_spheres = positions
            .iter()
            .zip(&vertices)
            .map(|(&f, c)| {
                let s = Sphere::from_point_normal_curvature(f, c.normal, c.mean);
                if s.is_finite() {
                    s
                } else {
                    Sphere::plane(DVec3::ZERO, c.normal)
                }
            })
            .collect();
        let planar: Vec<bool> = vertices.iter().map(|c| c.mean.abs() * diag < PLANAR_TOLERANCE).collect();
        let summary = summarize(&vertices, &vec![false; vertices.len()], &boundary, &planar, diag, 0);
        Self { vertices, central_spheres, boundary, planar, summary }
    }
}

fn summarize(
    vertices: &[VertexCurvature],
    failed: &[bool],
    boundary: &[bool],
    planar: &[bool],
    diag: f64,
    low_degree_fits: usize,
) -> CurvatureSummary {
    let (mut min_h, mut max_h, mut sum, mut n) = (f64::INFINITY, f64::NEG_INFINITY, 0.0, 0usize);
    let (mut pos, mut neg) = (0usize, 0usize);
    for (c, &bad) in vertices.iter().zip(failed) {
        if bad {
            continue;
        }
        min_h = min_h.min(c.mean);
        max_h = max_h.max(c.mean);
        sum += c.mean;
        n += 1;
        let s = c.mean * diag;
        if s > SIGN_CHANGE_THRESHOLD {
            pos += 1;
        } else if s < -SIGN_CHANGE_THRESHOLD {
            neg += 1;
        }
    }
    let need = ((SIGN_CHANGE_MIN_FRACTION * n as f64).ceil() as usize).max(1);
    CurvatureSummary {
        min_h: if n > 0 { min_h } else { 0.0 },
        max_h: if n > 0 { max_h } else { 0.0 },
        mean_h: if n > 0 { sum / n as f64 } else { 0.0 },
        h_changes_sign: pos >= need && neg >= need,
        boundary_vertices: boundary.iter().filter(|&&b| b).count(),
        planar_vertices: planar.iter().filter(|&&p| p).count(),
        low_degree_fits,
        failed_fits: failed.iter().filter(|&&b| b).count(),
        largest_neighbourhood: 0,
    }
}

/// Area-weighted unit vertex normals following the face orientation; None where the incident
/// face normals cancel (or there are none, or the input is not finite).
fn frame_normals(mesh: &TriMesh) -> Vec<Option<DVec3>> {
    let nv = mesh.vertex_count();
    let mut sum = vec![DVec3::ZERO; nv];
    let mut mag = vec![0.0f64; nv];
    for (f, t) in mesh.triangles.iter().enumerate() {
        if t.iter().any(|&v| v as usize >= nv) {
            continue;
        }
        let a = mesh.face_area_vector(f);
        let l = a.length();
        for &v in t {
            sum[v as usize] += a;
            mag[v as usize] += l;
        }
    }
    sum.iter()
        .zip(&mag)
        .map(|(s, &m)| {
            let l = s.length();
            (l > 1e-9 * m && l.is_finite()).then(|| *s / l)
        })
        .collect()
}

/// Breadth-first k-ring collection with a generation-stamped visited array (no per-vertex
/// allocation, no clearing).
struct RingCollector {
    stamp: Vec<u32>,
    generation: u32,
    points: Vec<u32>,
}

impl RingCollector {
    fn new(n: usize) -> Self {
        Self { stamp: vec![0; n], generation: 0, points: Vec::with_capacity(64) }
    }

    /// Fills `points` with v and its rings: at least one ring, then more until `min_points` points
    /// or `max_rings` rings (or the component is exhausted), never more than
    /// [`MAX_NEIGHBOURHOOD`] points. A one-ring larger than that is taken with an even stride, so
    /// the work per vertex is bounded whatever the valences.
    fn collect(&mut self, topo: &Topology, v: usize, min_points: usize, max_rings: usize) {
        if self.generation == u32::MAX {
            self.stamp.iter_mut().for_each(|s| *s = 0);
            self.generation = 0;
        }
        self.generation += 1;
        let g = self.generation;
        self.points.clear();
        self.points.push(v as u32);
        self.stamp[v] = g;
        let (mut start, mut end, mut rings) = (0usize, 1usize, 0usize);
        while rings < max_rings && (rings == 0 || self.points.len() < min_points) {
            'ring: for i in start..end {
                let p = self.points[i] as usize;
                let neighbours = topo.vertex_neighbors(p);
                let stride = neighbours.len().div_ceil(MAX_NEIGHBOURHOOD).max(1);
                for &w in neighbours.iter().step_by(stride) {
                    if self.points.len() >= MAX_NEIGHBOURHOOD {
                        break 'ring;
                    }
                    let w = w as usize;
                    if w < self.stamp.len() && self.stamp[w] != g {
                        self.stamp[w] = g;
                        self.points.push(w as u32);
                    }
                }
            }
            if self.points.len() == end {
                break;
            }
            start = end;
            end = self.points.len();
            rings += 1;
        }
    }
}
