//! Glide terms (Sec. 5.2, "letting the mesh glide over the reference surface"): residuals that
//! keep vertices and face spheres near the reference R while they move along it. Shared by every
//! method's optimization; each is a [`Term`] checked against finite differences in the tests.

use std::cell::RefCell;
use std::rc::Rc;

use glam::DVec3;

use super::{Reference, SearchStart};
use crate::solver::terms::v3;
use crate::solver::{JacobianSink, Term};

/// Closest reference points of the vertices, shared by the proximity terms so that each moved
/// vertex is looked up once per evaluation point (see [`ReferenceProximity::share_closest_with`]).
#[derive(Debug, Default)]
struct ClosestCache {
    /// Position each entry was computed for (NaN: never).
    pos: Vec<DVec3>,
    /// (closest point, interpolated unit normal).
    hits: Vec<(DVec3, DVec3)>,
    /// Where each search ended, where the next one starts.
    starts: Vec<Option<SearchStart>>,
}

/// Read access to a [`ReferenceProximity`]'s closest points (see [`ReferenceProximity::lookups`]).
#[derive(Clone, Debug)]
pub struct ClosestLookups(Rc<RefCell<ClosestCache>>);

impl ClosestLookups {
    /// The unit normal found for vertex `k` (an index into the term's offsets) when it was at
    /// `position`; None when it was looked up elsewhere (or not yet).
    pub fn normal_at(&self, k: usize, position: DVec3) -> Option<DVec3> {
        let c = self.0.borrow();
        (c.pos.get(k) == Some(&position)).then(|| c.hits[k].1)
    }
}

/// Proximity to the reference (Sec. 5.2): per vertex either the tangent-plane distance
/// n·(v − q) (one residual) or the point distance v − q (three residuals, scaled per vertex),
/// with (q, n) the closest reference point and its normal, refreshed in [`Term::prepare`].
/// Vertices that did not move since the last lookup are not looked up again, and two terms
/// over the same vertices can share their lookups ([`Self::share_closest_with`]).
pub struct ReferenceProximity<'a> {
    name: String,
    reference: &'a Reference,
    /// Vertex block offsets.
    offsets: Vec<usize>,
    /// Per-vertex residual scale.
    scales: Vec<f64>,
    point: bool,
    closest: Vec<(DVec3, DVec3)>,
    cache: Rc<RefCell<ClosestCache>>,
}

impl<'a> ReferenceProximity<'a> {
    /// Tangent-plane distance n·(v − q).
    pub fn tangent(reference: &'a Reference, offsets: Vec<usize>) -> Self {
        Self::new("tangent_distance", reference, offsets, None, false)
    }

    /// Point distance v − q, residuals scaled by `scales` (per vertex).
    pub fn point(reference: &'a Reference, offsets: Vec<usize>, scales: Vec<f64>) -> Self {
        Self::new("point_distance", reference, offsets, Some(scales), true)
    }

    fn new(name: &str, reference: &'a Reference, offsets: Vec<usize>, scales: Option<Vec<f64>>, point: bool) -> Self {
        let n = offsets.len();
        let cache = ClosestCache { pos: vec![DVec3::NAN; n], hits: vec![(DVec3::ZERO, DVec3::Z); n], starts: vec![None; n] };
        Self {
            name: name.into(),
            reference,
            scales: scales.unwrap_or_else(|| vec![1.0; n]),
            offsets,
            point,
            closest: vec![(DVec3::ZERO, DVec3::Z); n],
            cache: Rc::new(RefCell::new(cache)),
        }
    }

    /// Sets the name shown in reports.
    pub fn with_name(mut self, name: impl Into<String>) -> Self {
        self.name = name.into();
        self
    }

    /// Shares the closest-point lookups with `other` (same reference and vertex offsets): the
    /// first of the two to prepare at a point looks the moved vertices up, the other reuses them.
    pub fn share_closest_with(&mut self, other: &Self) {
        assert!(self.offsets == other.offsets && std::ptr::eq(self.reference, other.reference), "different vertices or reference");
        self.cache = other.cache.clone();
    }

    /// Closest points and normals currently used.
    pub fn closest(&self) -> &[(DVec3, DVec3)] {
        &self.closest
    }

    /// A read handle on the lookups this term makes (shared with [`Self::share_closest_with`]):
    /// other terms over the same vertices, prepared after it, can take its normals instead of
    /// looking the vertices up again.
    pub fn lookups(&self) -> ClosestLookups {
        ClosestLookups(self.cache.clone())
    }
}

impl Term for ReferenceProximity<'_> {
    fn name(&self) -> &str {
        &self.name
    }
    fn residual_count(&self) -> usize {
        if self.point {
            3 * self.offsets.len()
        } else {
            self.offsets.len()
        }
    }
    fn prepare(&mut self, x: &[f64]) {
        let mut cache = self.cache.borrow_mut();
        let cache = &mut *cache;
        for (k, &o) in self.offsets.iter().enumerate() {
            let v = DVec3::new(x[o], x[o + 1], x[o + 2]);
            if !v.is_finite() {
                continue;
            }
            if cache.pos[k] != v {
                if let Some(hit) = self.reference.closest_point_near(v, cache.starts[k]) {
                    cache.hits[k] = (hit.point, hit.normal.unwrap_or(cache.hits[k].1));
                    cache.starts[k] = Some(hit.search_start());
                    cache.pos[k] = v;
                }
            }
            if cache.pos[k] == v {
                self.closest[k] = cache.hits[k];
            }
        }
    }
    fn eval(&self, x: &[f64], r: &mut [f64], jac: &mut JacobianSink) {
        for (k, &o) in self.offsets.iter().enumerate() {
            let v = DVec3::new(x[o], x[o + 1], x[o + 2]);
            let (q, n) = self.closest[k];
            let s = self.scales[k];
            if self.point {
                let d = (v - q) * s;
                for i in 0..3 {
                    r[3 * k + i] = d[i];
                    jac.add(3 * k + i, o + i, s);
                }
            } else {
                r[k] = n.dot(v - q) * s;
                jac.add_block(k, o, &[n.x * s, n.y * s, n.z * s]);
            }
        }
    }
}

/// The reference point closest to the centroid of each group of vertices (a face's corners),
/// refreshed by [`CentroidTargets::update`] (a group whose centroid did not move is not looked up
/// again): the targets of the ST method's face distance.
pub struct CentroidTargets<'a> {
    reference: &'a Reference,
    /// The offsets of each group's vertices.
    groups: Vec<Vec<usize>>,
    targets: Vec<DVec3>,
    /// Where each target's search ended, where the next one starts.
    starts: Vec<Option<SearchStart>>,
    /// Centroid each target was computed for (NaN: never).
    centroids: Vec<DVec3>,
}

impl<'a> CentroidTargets<'a> {
    pub fn new(reference: &'a Reference, groups: Vec<Vec<usize>>, x: &[f64]) -> Self {
        let n = groups.len();
        let mut t = Self { reference, groups, targets: vec![DVec3::ZERO; n], starts: vec![None; n], centroids: vec![DVec3::NAN; n] };
        t.update(x);
        t
    }

    /// Looks up the groups whose centroid moved.
    pub fn update(&mut self, x: &[f64]) {
        for (k, vs) in self.groups.iter().enumerate() {
            let c = vs[1..].iter().fold(v3(x, vs[0]), |s, &o| s + v3(x, o)) / vs.len() as f64;
            if !c.is_finite() || c == self.centroids[k] {
                continue;
            }
            if let Some(hit) = self.reference.closest_point_near(c, self.starts[k]) {
                self.targets[k] = hit.point;
                self.starts[k] = Some(hit.search_start());
                self.centroids[k] = c;
            }
        }
    }

    /// The reference point closest to group `k`'s centroid.
    pub fn target(&self, k: usize) -> DVec3 {
        self.targets[k]
    }

    pub fn len(&self) -> usize {
        self.groups.len()
    }

    pub fn is_empty(&self) -> bool {
        self.groups.is_empty()
    }
}

/// ∂ψ(p)/∂(a, b, c) = (|p|², −p, 1): the gradient of a sphere's value at a fixed point.
pub(crate) fn value_gradient(p: DVec3) -> [f64; 5] {
    [p.length_squared(), -p.x, -p.y, -p.z, 1.0]
}

/// Proximity of the boundary vertices to the reference's boundary curve: v − b per vertex, b the
/// boundary point closest to v, refreshed in [`Term::prepare`] (fixed within an iteration), so a
/// boundary vertex slides along the boundary but does not leave it and the mesh keeps covering
/// the reference up to its boundary.
pub struct BoundaryProximity<'a> {
    reference: &'a Reference,
    /// Vertex block offsets.
    offsets: Vec<usize>,
    targets: Vec<DVec3>,
}

impl<'a> BoundaryProximity<'a> {
    /// The vertices at `offsets`, their targets looked up at `x`.
    pub fn new(reference: &'a Reference, offsets: Vec<usize>, x: &[f64]) -> Self {
        let targets = vec![DVec3::ZERO; offsets.len()];
        let mut term = Self { reference, offsets, targets };
        term.prepare(x);
        term
    }
}

impl Term for BoundaryProximity<'_> {
    fn name(&self) -> &str {
        "boundary_proximity"
    }
    fn residual_count(&self) -> usize {
        3 * self.offsets.len()
    }
    fn prepare(&mut self, x: &[f64]) {
        let boundary = self.reference.boundary_bvh();
        for (k, &o) in self.offsets.iter().enumerate() {
            let v = v3(x, o);
            if let Some(hit) = v.is_finite().then(|| boundary.closest_point(v)).flatten() {
                self.targets[k] = hit.point;
            }
        }
    }
    fn eval(&self, x: &[f64], r: &mut [f64], jac: &mut JacobianSink) {
        for (k, &o) in self.offsets.iter().enumerate() {
            let d = v3(x, o) - self.targets[k];
            for i in 0..3 {
                r[3 * k + i] = d[i];
                jac.add(3 * k + i, o + i, 1.0);
            }
        }
    }
}
