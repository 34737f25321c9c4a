//! The starting sphere congruence of Sec. 5.1: the central congruence r = 1/H, or constant radii.
//!
//! With a constant radius r the centres c = f + r n form an offset of f, so c_u × c_v =
//! (1 − rκ1)(1 − rκ2) f_u × f_v ∥ n: the lines are the normals (θ = 0), the torsal directions the
//! principal directions and the torsal planes orthogonal (Sec. 2.5, the remark after (c)). It meets
//! (b) and (c) at the start, at the cost of (a), which the final optimization (Eq. 10) restores by
//! fitting every face sphere to its quad. It exists whatever the sign of H (Sec. 6.3), and the
//! congruence optimization leaves it as it is (nothing in (b) or (c) to mend, and E_LC would only
//! drift its lines off the normals). Fig. 24 starts each face sphere from r, so r is chosen for
//! the panels ([`constant_radius`]): near 1 / mean |H|, the sphere that fits them best on average,
//! where its offset stays regular and its panels within the promised distance.
//!
//! A sphere patch is the trivial case: every central sphere is the surface itself
//! ([`spherical_reference`]), the lines are the normals through its centre, every direction is
//! torsal, and every quad mesh on it is exact with one sphere.

use glam::DVec3;

use crate::geometry::bspline::BSplineFunction;

use super::radius::SamplingGrid;

/// The constant radius of the constant start (frame units), with the sign `sign` of the dominant
/// H, for about `faces` panels and the promised distance `max_distance` (frame units): of the
/// radii from 1 / mean |H| over G (the sphere that fits the panels best on average) down to the
/// panel size (a face sphere must hold its panel), in steps of 2^(−1/2), the one with the fewest
/// misses on G ([`constant_start_misses`]), the largest among equals; and those misses. None
/// when H vanishes on all of G.
pub fn constant_radius(grid: &SamplingGrid, sign: f64, faces: usize, max_distance: f64) -> Option<(f64, usize)> {
    let frames = &grid.frames;
    let mean = frames.iter().map(|f| f.mean.abs()).sum::<f64>() / frames.len().max(1) as f64;
    if !(mean > 0.0 && mean.is_finite()) {
        return None;
    }
    let area: f64 = (0..grid.quad_count())
        .map(|q| {
            let c = grid.quad(q).map(|p| frames[p].point);
            0.5 * ((c[1] - c[0]).cross(c[3] - c[0]).length() + (c[1] - c[2]).cross(c[3] - c[2]).length())
        })
        .sum();
    let panel = (area / faces.max(1) as f64).sqrt();
    let mut best = (1.0 / mean, usize::MAX);
    let mut r = 1.0 / mean;
    loop {
        let misses = constant_start_misses(grid, sign * r, panel, max_distance);
        if misses < best.1 {
            best = (r, misses);
        }
        r *= std::f64::consts::FRAC_1_SQRT_2;
        if misses == 0 || r < panel {
            break;
        }
    }
    Some((sign * best.0, best.1))
}

/// The points of G where the constant start of radius `r` cannot meet the guarantees, for
/// panels of side `panel` and the promised distance `max_distance` (all frame units): where its
/// offset nearly collapses ([`MIN_OFFSET_AREA`]), or where a sphere of radius r through a
/// panel's corners stands off the surface by more than the promised distance, max |κ_i − 1/r| ·
/// ρ² / 2 over the principal curvatures, ρ² = panel² / 2 the panel's half diagonal squared.
pub fn constant_start_misses(grid: &SamplingGrid, r: f64, panel: f64, max_distance: f64) -> usize {
    let rho2 = 0.5 * panel * panel;
    grid.frames
        .iter()
        .filter(|f| {
            let collapsed = !(((1.0 - r * f.k1) * (1.0 - r * f.k2)).abs() >= MIN_OFFSET_AREA);
            let far = !((f.k1 - 1.0 / r).abs().max((f.k2 - 1.0 / r).abs()) * rho2 / 2.0 <= max_distance);
            collapsed || far
        })
        .count()
}

/// Least |(1 − rκ1)(1 − rκ2)| at a point of G, the offset's area element relative to the
/// surface's, below which the constant start counts the point as a miss: the centres of
/// neighbouring face spheres nearly coincide there (near a focal point; everywhere on a nearly
/// spherical patch), and the node axes, normal to their plane, are lost.
pub(crate) const MIN_OFFSET_AREA: f64 = 0.25;

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
        .all(|f| {
            (f.mean * f.mean - f.gauss).abs() * r * r <= tol && (1.0 / f.mean - r).abs() <= tol && (f.point + r * f.normal).distance(centre) <= tol
        })
        .then_some((centre, r.abs()))
}
