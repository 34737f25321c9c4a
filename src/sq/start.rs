//! The starting sphere congruence of Sec. 5.1: the central congruence r = 1/H, or constant radii.
//!
//! With a constant radius r the centres c = f + r n form an offset of f, so c_u × c_v ∥ n: the
//! lines are the normals (θ = 0), the torsal directions the principal directions and the torsal
//! planes orthogonal (Sec. 2.5, the remark after (c)). It meets (b) and (c) at the start, at the
//! cost of (a), which the final optimization (Eq. 10) restores by fitting every face sphere to its
//! quad. The offset is singular where r is a principal radius 1/κ (a focal point), so r is
//! chosen away from every 1/κ on G.
//!
//! A sphere patch is the trivial case: every central sphere is the surface itself
//! ([`spherical_reference`]), the lines are the normals through its centre, every direction is
//! torsal, and every quad mesh on it is exact with one sphere.

use glam::DVec3;

use crate::geometry::bspline::BSplineFunction;

use super::radius::SamplingGrid;

/// Least |(1 − r κ1)(1 − r κ2)| over G for a constant radius r: the offset's area element
/// relative to the surface's.
pub(crate) const MIN_OFFSET_AREA: f64 = 0.25;

/// The constant radius of the constant start (frame units), with the sign of H: the harmonic
/// mean of the central radii when the offset stays regular there, else half the smallest
/// principal radius on G.
pub fn constant_radius(grid: &SamplingGrid, sign: f64) -> f64 {
    let frames = &grid.frames;
    let mean_h = frames.iter().map(|f| f.mean * sign).sum::<f64>() / frames.len().max(1) as f64;
    let max_k = frames.iter().map(|f| f.k1.abs().max(f.k2.abs())).fold(0.0, f64::max);
    let area = |r: f64| frames.iter().map(|f| ((1.0 - r * f.k1) * (1.0 - r * f.k2)).abs()).fold(f64::INFINITY, f64::min);
    let harmonic = sign / mean_h;
    if mean_h > 0.0 && area(harmonic) >= MIN_OFFSET_AREA {
        return harmonic;
    }
    sign * 0.5 / max_k.max(f64::MIN_POSITIVE)
}

/// The radius function r ≡ `r` on the basis of `function` (a B-spline basis sums to one).
pub(crate) fn constant_function(function: &BSplineFunction, r: f64) -> BSplineFunction {
    BSplineFunction { coefficients: vec![r; function.coefficients.len()], ..function.clone() }
}

/// Relative spread of the central spheres below which the reference is one sphere.
pub(crate) const SPHERE_TOLERANCE: f64 = 1e-9;

/// The reference's one sphere (centre, radius in frame units) when every point of G is umbilic
/// with the same central sphere.
pub fn spherical_reference(grid: &SamplingGrid) -> Option<(DVec3, f64)> {
    let frames = &grid.frames;
    let first = frames.first()?;
    if !(first.mean.abs() > 0.0) {
        return None;
    }
    let r = 1.0 / first.mean;
    let centre = first.point + r * first.normal;
    let tol = SPHERE_TOLERANCE * (1.0 + r.abs());
    frames
        .iter()
        // Umbilic: H² − K = ((κ1 − κ2)/2)² vanishes (κ1 − κ2 itself carries the square root's
        // rounding, about 1e-8).
        .all(|f| (f.mean * f.mean - f.gauss).abs() * r * r <= tol && (1.0 / f.mean - r).abs() <= tol && (f.point + r * f.normal).distance(centre) <= tol)
        .then_some((centre, r.abs()))
}
