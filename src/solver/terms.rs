//! Ready-made terms.
//!
//! Block conventions (offsets into the variable vector):
//! - point / vector: 3 consecutive variables (x, y, z);
//! - generalized sphere: 5 consecutive variables (a, b₁, b₂, b₃, c) of
//!   ψ(p) = a|p|² − ⟨b, p⟩ + c (the convention of `crate::geometry::sphere::Sphere::to_array`), normalized
//!   when bᵀb − 4ac = 1;
//! - plane: unit normal n (3-block) and offset d (1 variable): n·p − d = 0.
//!
//! Every term has a default name and a `with_name` builder.

use super::problem::{JacobianSink, Term};
use glam::DVec3;

/// The 3-block of `x` at offset `o` (a vertex, a normal, the b of a sphere).
#[inline]
pub(crate) fn v3(x: &[f64], o: usize) -> DVec3 {
    DVec3::new(x[o], x[o + 1], x[o + 2])
}

#[inline]
fn sph(x: &[f64], o: usize) -> (f64, DVec3, f64) {
    (x[o], DVec3::new(x[o + 1], x[o + 2], x[o + 3]), x[o + 4])
}

macro_rules! named {
    ($t:ty) => {
        impl $t {
            /// Sets the name shown in reports.
            pub fn with_name(mut self, name: impl Into<String>) -> Self {
                self.name = name.into();
                self
            }
        }
    };
}

// ---------------------------------------------------------------------------------------------

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum UnitKind {
    /// |v|² − 1 over a block of this dimension.
    Vector(usize),
    /// bᵀb − 4ac − 1 over a 5-block (a, b, c).
    Sphere,
}

/// Unit-length constraints, one residual per block:
/// - [`UnitLength::vectors`]: |v|² − 1 for 3-blocks (unit normals);
/// - [`UnitLength::spheres`]: bᵀb − 4ac − 1 for generalized-sphere 5-blocks (a, b, c).
#[derive(Clone, Debug)]
pub struct UnitLength {
    name: String,
    offsets: Vec<usize>,
    kind: UnitKind,
}
named!(UnitLength);

impl UnitLength {
    /// |v|² − 1 for the 3-blocks starting at `offsets`.
    pub fn vectors(offsets: Vec<usize>) -> Self {
        Self::vectors_dim(offsets, 3)
    }

    /// |v|² − 1 for blocks of `dim` variables.
    pub fn vectors_dim(offsets: Vec<usize>, dim: usize) -> Self {
        Self { name: "unit_length".into(), offsets, kind: UnitKind::Vector(dim) }
    }

    /// bᵀb − 4ac − 1 for the generalized-sphere 5-blocks starting at `offsets`.
    pub fn spheres(offsets: Vec<usize>) -> Self {
        Self { name: "sphere_normalization".into(), offsets, kind: UnitKind::Sphere }
    }
}

impl Term for UnitLength {
    fn name(&self) -> &str {
        &self.name
    }
    fn residual_count(&self) -> usize {
        self.offsets.len()
    }
    fn eval(&self, x: &[f64], r: &mut [f64], jac: &mut JacobianSink) {
        match self.kind {
            UnitKind::Vector(d) => {
                for (i, &o) in self.offsets.iter().enumerate() {
                    let v = &x[o..o + d];
                    r[i] = v.iter().map(|t| t * t).sum::<f64>() - 1.0;
                    for (k, &t) in v.iter().enumerate() {
                        jac.add(i, o + k, 2.0 * t);
                    }
                }
            }
            UnitKind::Sphere => {
                for (i, &o) in self.offsets.iter().enumerate() {
                    let (a, b, c) = sph(x, o);
                    r[i] = b.length_squared() - 4.0 * a * c - 1.0;
                    jac.add_block(i, o, &[-4.0 * c, 2.0 * b.x, 2.0 * b.y, 2.0 * b.z, -4.0 * a]);
                }
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------

/// Soft anchor: x_i − target_i for listed variables (closeness to an initial state, soft
/// boundary conditions). For hard-fixed variables use `Problem::fix`.
#[derive(Clone, Debug)]
pub struct Anchor {
    name: String,
    indices: Vec<usize>,
    targets: Vec<f64>,
}
named!(Anchor);

impl Anchor {
    pub fn new(indices: Vec<usize>, targets: Vec<f64>) -> Self {
        assert_eq!(indices.len(), targets.len());
        Self { name: "anchor".into(), indices, targets }
    }

    /// Anchors variables `start..start + targets.len()`.
    pub fn block(start: usize, targets: &[f64]) -> Self {
        Self::new((start..start + targets.len()).collect(), targets.to_vec())
    }

    /// Anchors the listed variables at their current values in `x`.
    pub fn at_current(indices: Vec<usize>, x: &[f64]) -> Self {
        let targets = indices.iter().map(|&i| x[i]).collect();
        Self::new(indices, targets)
    }
}

impl Term for Anchor {
    fn name(&self) -> &str {
        &self.name
    }
    fn residual_count(&self) -> usize {
        self.indices.len()
    }
    fn eval(&self, x: &[f64], r: &mut [f64], jac: &mut JacobianSink) {
        for (k, (&i, &t)) in self.indices.iter().zip(&self.targets).enumerate() {
            r[k] = x[i] - t;
            jac.add(k, i, 1.0);
        }
    }
}

// ---------------------------------------------------------------------------------------------

/// The regularizer E_reg of Tang et al. 2014: x_i − x_i⁰ for the listed variables, with x⁰ the
/// point the solver evaluates (set in [`Term::prepare`]). Its residuals are zero and its Jacobian
/// rows are the identity, so it damps those variables in every step (weight w adds w·I to their
/// block of the normal equations) without changing the energy.
#[derive(Clone, Debug)]
pub struct Proximal {
    name: String,
    indices: Vec<usize>,
    at: Vec<f64>,
}
named!(Proximal);

impl Proximal {
    pub fn new(indices: Vec<usize>) -> Self {
        let at = vec![0.0; indices.len()];
        Self { name: "regularization".into(), indices, at }
    }
}

impl Term for Proximal {
    fn name(&self) -> &str {
        &self.name
    }
    fn residual_count(&self) -> usize {
        self.indices.len()
    }
    fn prepare(&mut self, x: &[f64]) {
        for (a, &i) in self.at.iter_mut().zip(&self.indices) {
            *a = x[i];
        }
    }
    fn eval(&self, x: &[f64], r: &mut [f64], jac: &mut JacobianSink) {
        for (k, &i) in self.indices.iter().enumerate() {
            r[k] = x[i] - self.at[k];
            jac.add(k, i, 1.0);
        }
    }
}

// ---------------------------------------------------------------------------------------------

/// One-sided wrapper: residual max(0, g) for every residual g of the inner term; residuals with
/// g ≤ 0 are switched off (zero residual, Jacobian row ignored). Use it for inequalities
/// g(x) ≤ 0. A NaN g stays active (so the solver rejects the point).
#[derive(Clone, Debug)]
pub struct Hinge<T> {
    name: String,
    inner: T,
}

impl<T: Term> Hinge<T> {
    pub fn new(inner: T) -> Self {
        Self { name: format!("hinge({})", inner.name()), inner }
    }

    pub fn with_name(mut self, name: impl Into<String>) -> Self {
        self.name = name.into();
        self
    }

    pub fn inner(&self) -> &T {
        &self.inner
    }
}

impl<T: Term> Term for Hinge<T> {
    fn name(&self) -> &str {
        &self.name
    }
    fn residual_count(&self) -> usize {
        self.inner.residual_count()
    }
    fn eval(&self, x: &[f64], r: &mut [f64], jac: &mut JacobianSink) {
        self.inner.eval(x, r, jac);
        for (i, ri) in r.iter_mut().enumerate() {
            if *ri <= 0.0 {
                *ri = 0.0;
                jac.deactivate(i);
            }
        }
    }
    fn prepare(&mut self, x: &[f64]) {
        self.inner.prepare(x);
    }
}

// ---------------------------------------------------------------------------------------------

/// Tolerance-band wrapper: for every residual g of the inner term, 0 inside the band |g| ≤ τ
/// (row switched off) and a logarithmic wall outside, sign(g) τ ln(|g|/τ) (≈ |g| − τ just
/// outside, slope τ/|g| further out): outliers are pulled in, but one that cannot come in (a
/// reference coarser than the band) does not swamp the other terms. A NaN g stays active (so the
/// solver rejects the point).
#[derive(Clone, Debug)]
pub struct Band<T> {
    name: String,
    inner: T,
    half_width: f64,
}

impl<T: Term> Band<T> {
    /// `half_width` τ must be positive and finite.
    pub fn new(inner: T, half_width: f64) -> Self {
        assert!(half_width > 0.0 && half_width.is_finite(), "a tolerance band needs 0 < τ < ∞, not {half_width}");
        Self { name: format!("band({})", inner.name()), inner, half_width }
    }

    pub fn inner(&self) -> &T {
        &self.inner
    }

    pub fn with_name(mut self, name: impl Into<String>) -> Self {
        self.name = name.into();
        self
    }
}

impl<T: Term> Term for Band<T> {
    fn name(&self) -> &str {
        &self.name
    }
    fn residual_count(&self) -> usize {
        self.inner.residual_count()
    }
    fn eval(&self, x: &[f64], r: &mut [f64], jac: &mut JacobianSink) {
        let mark = jac.mark();
        self.inner.eval(x, r, jac);
        let tau = self.half_width;
        // The stretch |g|/τ, written 1 + (|g| − τ)/τ; d/dg [τ ln(stretch)] = 1/stretch (rows
        // inside the band are switched off below).
        let stretch = |g: f64| 1.0 + (g.abs() - tau) / tau;
        jac.scale_rows_since(mark, |i| 1.0 / stretch(r[i]).max(1.0));
        for (i, ri) in r.iter_mut().enumerate() {
            if ri.abs() <= tau {
                *ri = 0.0;
                jac.deactivate(i);
            } else {
                *ri = ri.signum() * tau * stretch(*ri).ln();
            }
        }
    }
    fn prepare(&mut self, x: &[f64]) {
        self.inner.prepare(x);
    }
}

// ---------------------------------------------------------------------------------------------

/// Sparse affine residuals r_k = Σ_j a_kj x_j + c_k (linear constraints, fairness stencils,
/// with [`Hinge`] linear inequalities).
#[derive(Clone, Debug)]
pub struct Linear {
    name: String,
    row_ptr: Vec<usize>,
    cols: Vec<usize>,
    coeffs: Vec<f64>,
    constants: Vec<f64>,
}
named!(Linear);

impl Default for Linear {
    fn default() -> Self {
        Self::new()
    }
}

impl Linear {
    pub fn new() -> Self {
        Self { name: "linear".into(), row_ptr: vec![0], cols: Vec::new(), coeffs: Vec::new(), constants: Vec::new() }
    }

    /// Appends the residual Σ coeffs.1 · x[coeffs.0] + constant; returns its row.
    pub fn push_row(&mut self, coeffs: &[(usize, f64)], constant: f64) -> usize {
        for &(j, a) in coeffs {
            self.cols.push(j);
            self.coeffs.push(a);
        }
        self.row_ptr.push(self.cols.len());
        self.constants.push(constant);
        self.constants.len() - 1
    }

    /// Builder form of [`Linear::push_row`].
    pub fn row(mut self, coeffs: &[(usize, f64)], constant: f64) -> Self {
        self.push_row(coeffs, constant);
        self
    }
}

impl Term for Linear {
    fn name(&self) -> &str {
        &self.name
    }
    fn residual_count(&self) -> usize {
        self.constants.len()
    }
    fn eval(&self, x: &[f64], r: &mut [f64], jac: &mut JacobianSink) {
        for (k, rk) in r.iter_mut().enumerate() {
            let mut s = self.constants[k];
            for e in self.row_ptr[k]..self.row_ptr[k + 1] {
                s += self.coeffs[e] * x[self.cols[e]];
                jac.add(k, self.cols[e], self.coeffs[e]);
            }
            *rk = s;
        }
    }
}

// ---------------------------------------------------------------------------------------------

/// Variable points on variable generalized spheres: ψ_s(p) = a|p|² − ⟨b, p⟩ + c, one residual
/// per (point offset, sphere offset) pair (E_sphere). For a normalized sphere ψ is about the
/// signed distance near the sphere.
#[derive(Clone, Debug)]
pub struct PointOnSphere {
    name: String,
    pairs: Vec<(usize, usize)>,
}
named!(PointOnSphere);

impl PointOnSphere {
    /// `pairs`: (point 3-block offset, sphere 5-block offset).
    pub fn new(pairs: Vec<(usize, usize)>) -> Self {
        Self { name: "point_on_sphere".into(), pairs }
    }
}

impl Term for PointOnSphere {
    fn name(&self) -> &str {
        &self.name
    }
    fn residual_count(&self) -> usize {
        self.pairs.len()
    }
    fn eval(&self, x: &[f64], r: &mut [f64], jac: &mut JacobianSink) {
        for (i, &(po, so)) in self.pairs.iter().enumerate() {
            let p = v3(x, po);
            let (a, b, c) = sph(x, so);
            r[i] = a * p.length_squared() - b.dot(p) + c;
            jac.add_block(i, so, &[p.length_squared(), -p.x, -p.y, -p.z, 1.0]);
            let dp = 2.0 * a * p - b;
            jac.add_block(i, po, &[dp.x, dp.y, dp.z]);
        }
    }
}

/// Fixed data points on one variable generalized sphere: ψ_s(p_i) = a|p_i|² − ⟨b, p_i⟩ + c.
/// With [`UnitLength::spheres`] this is algebraic (≈ geometric) sphere fitting.
#[derive(Clone, Debug)]
pub struct SphereFit {
    name: String,
    sphere: usize,
    points: Vec<DVec3>,
}
named!(SphereFit);

impl SphereFit {
    pub fn new(sphere: usize, points: Vec<DVec3>) -> Self {
        Self { name: "sphere_fit".into(), sphere, points }
    }
}

impl Term for SphereFit {
    fn name(&self) -> &str {
        &self.name
    }
    fn residual_count(&self) -> usize {
        self.points.len()
    }
    fn eval(&self, x: &[f64], r: &mut [f64], jac: &mut JacobianSink) {
        let (a, b, c) = sph(x, self.sphere);
        for (i, p) in self.points.iter().enumerate() {
            let q = p.length_squared();
            r[i] = a * q - b.dot(*p) + c;
            jac.add_block(i, self.sphere, &[q, -p.x, -p.y, -p.z, 1.0]);
        }
    }
}

// ---------------------------------------------------------------------------------------------

/// Inversive product of pairs of variable generalized spheres minus a target:
/// ⟨s, t⟩ − target with ⟨s, t⟩ = b_s·b_t − 2(a_s c_t + a_t c_s). For normalized spheres ⟨s, t⟩ is
/// the cosine of the intersection angle: target 1 asks for tangency (no kink), 0 for
/// orthogonality.
#[derive(Clone, Debug)]
pub struct InversiveProduct {
    name: String,
    pairs: Vec<(usize, usize)>,
    target: f64,
}
named!(InversiveProduct);

impl InversiveProduct {
    /// `pairs` of sphere 5-block offsets.
    pub fn new(pairs: Vec<(usize, usize)>, target: f64) -> Self {
        Self { name: "inversive_product".into(), pairs, target }
    }
}

impl Term for InversiveProduct {
    fn name(&self) -> &str {
        &self.name
    }
    fn residual_count(&self) -> usize {
        self.pairs.len()
    }
    fn eval(&self, x: &[f64], r: &mut [f64], jac: &mut JacobianSink) {
        for (i, &(fo, go)) in self.pairs.iter().enumerate() {
            let (af, bf, cf) = sph(x, fo);
            let (ag, bg, cg) = sph(x, go);
            r[i] = bf.dot(bg) - 2.0 * (af * cg + ag * cf) - self.target;
            jac.add_block(i, fo, &[-2.0 * cg, bg.x, bg.y, bg.z, -2.0 * ag]);
            jac.add_block(i, go, &[-2.0 * cf, bf.x, bf.y, bf.z, -2.0 * af]);
        }
    }
}

/// Inversive product of variable spheres with one fixed sphere (a, b₁, b₂, b₃, c) minus a target
/// (e.g. target 0 with the absolute sphere Ω: orthogonality).
#[derive(Clone, Debug)]
pub struct InversiveProductFixed {
    name: String,
    spheres: Vec<usize>,
    fixed: [f64; 5],
    target: f64,
}
named!(InversiveProductFixed);

impl InversiveProductFixed {
    pub fn new(spheres: Vec<usize>, fixed: [f64; 5], target: f64) -> Self {
        Self { name: "inversive_product_fixed".into(), spheres, fixed, target }
    }
}

impl Term for InversiveProductFixed {
    fn name(&self) -> &str {
        &self.name
    }
    fn residual_count(&self) -> usize {
        self.spheres.len()
    }
    fn eval(&self, x: &[f64], r: &mut [f64], jac: &mut JacobianSink) {
        let [ao, b1, b2, b3, co] = self.fixed;
        let bo = DVec3::new(b1, b2, b3);
        for (i, &so) in self.spheres.iter().enumerate() {
            let (a, b, c) = sph(x, so);
            r[i] = b.dot(bo) - 2.0 * (a * co + ao * c) - self.target;
            jac.add_block(i, so, &[-2.0 * co, bo.x, bo.y, bo.z, -2.0 * ao]);
        }
    }
}

// ---------------------------------------------------------------------------------------------

/// Points on variable planes: n·p − d, one residual per (point 3-block, normal 3-block, offset
/// variable) triple. Pair with [`UnitLength::vectors`] on the normals.
#[derive(Clone, Debug)]
pub struct PointOnPlane {
    name: String,
    items: Vec<(usize, usize, usize)>,
}
named!(PointOnPlane);

impl PointOnPlane {
    /// `items`: (point offset, normal offset, offset-variable index).
    pub fn new(items: Vec<(usize, usize, usize)>) -> Self {
        Self { name: "point_on_plane".into(), items }
    }
}

impl Term for PointOnPlane {
    fn name(&self) -> &str {
        &self.name
    }
    fn residual_count(&self) -> usize {
        self.items.len()
    }
    fn eval(&self, x: &[f64], r: &mut [f64], jac: &mut JacobianSink) {
        for (i, &(po, no, d)) in self.items.iter().enumerate() {
            let p = v3(x, po);
            let n = v3(x, no);
            r[i] = n.dot(p) - x[d];
            jac.add_block(i, po, &[n.x, n.y, n.z]);
            jac.add_block(i, no, &[p.x, p.y, p.z]);
            jac.add(i, d, -1.0);
        }
    }
}

// ---------------------------------------------------------------------------------------------

/// A term from a closure `f(x, r, jac)` (same contract as [`Term::eval`]).
pub struct FnTerm<F> {
    name: String,
    count: usize,
    f: F,
}

impl<F: Fn(&[f64], &mut [f64], &mut JacobianSink)> FnTerm<F> {
    pub fn new(name: impl Into<String>, residual_count: usize, f: F) -> Self {
        Self { name: name.into(), count: residual_count, f }
    }
}

impl<F: Fn(&[f64], &mut [f64], &mut JacobianSink)> Term for FnTerm<F> {
    fn name(&self) -> &str {
        &self.name
    }
    fn residual_count(&self) -> usize {
        self.count
    }
    fn eval(&self, x: &[f64], r: &mut [f64], jac: &mut JacobianSink) {
        (self.f)(x, r, jac)
    }
}
