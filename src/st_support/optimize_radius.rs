//! Optimizing the radius of Ω (Fig. 16, right): with the vertices and m (or the axis a) fixed,
//! R² (or the plane offset d) is chosen to minimize the mean kink angle over the interior edges:
//! a scan of R² = R̂² + w sinh(u), u ∈ [−8, 8] step 0.5 (w = mean |m − v_i|²; R̂² the mean-R²
//! estimate, u = 0; for the plane d = d̂ + diag · sinh(u)), refined by golden-section search in
//! the best cell. R² may end up ≤ 0. The result is never worse than R̂².

// Negated float comparisons are deliberate: they also reject NaN.

use super::absolute_sphere::AbsoluteSphereEstimate;
use crate::geometry::absolute_sphere::AbsoluteSphere;
use crate::geometry::mesh::TriMesh;
use crate::geometry::sphere::Sphere;
use crate::progress::{Cancelled, OnProgress, Progress};
use crate::stats::mean;

/// R² of a sphere Ω, d of a plane.
pub(crate) fn parameter_of(omega: &AbsoluteSphere) -> f64 {
    match *omega {
        AbsoluteSphere::Sphere { r2, .. } => r2,
        AbsoluteSphere::Plane { d, .. } => d,
    }
}

pub(crate) fn with_parameter(omega: &AbsoluteSphere, x: f64) -> AbsoluteSphere {
    match *omega {
        AbsoluteSphere::Sphere { center, .. } => AbsoluteSphere::Sphere { center, r2: x },
        AbsoluteSphere::Plane { axis, .. } => AbsoluteSphere::Plane { axis, d: x },
    }
}

/// Mean kink angle (deg) over `interior` for Ω, from the precomputed pencils (world frame).
fn mean_kink_for(families: &[[Sphere; 2]], interior: &[[u32; 2]], omega: &AbsoluteSphere) -> f64 {
    let o = omega.coefficients();
    let spheres: Vec<Sphere> = families
        .iter()
        .map(|[s0, s1]| {
            let (alpha, beta) = (s1.inversive_product(&o), s0.inversive_product(&o));
            let h = alpha.hypot(beta);
            if !(h > 0.0) {
                return *s0;
            }
            let sign = if alpha < 0.0 { -1.0 } else { 1.0 };
            Sphere::combine(s0, sign * alpha / h, s1, -sign * beta / h)
        })
        .collect();
    mean(&interior.iter().map(|[f, g]| spheres[*f as usize].kink_angle(&spheres[*g as usize]).to_degrees()).collect::<Vec<_>>())
}

/// Scan + golden section of the mean kink angle over R² = R̂² + w sinh(u) (or d = d̂ + diag sinh u).
/// Returns (best parameter, its mean kink, the mean kink at the estimate).
pub(crate) fn optimize_parameter(
    mesh: &TriMesh,
    absolute: &AbsoluteSphereEstimate,
    families: &[[Sphere; 2]],
    interior: &[[u32; 2]],
    progress: &mut OnProgress,
) -> Result<(f64, f64, f64), Cancelled> {
    let base = absolute.omega;
    let x0 = parameter_of(&base);
    let w = match base {
        AbsoluteSphere::Sphere { center, .. } => {
            mesh.positions.iter().map(|p| (*p - center).length_squared()).sum::<f64>() / mesh.vertex_count() as f64
        }
        AbsoluteSphere::Plane { .. } => mesh.bbox_diagonal(),
    };
    let w = if w > 0.0 && w.is_finite() { w } else { 1.0 };
    let x_of = |u: f64| x0 + w * u.sinh();
    let f = |u: f64| mean_kink_for(families, interior, &with_parameter(&base, x_of(u)));
    let (n, h) = (16i32, 0.5);
    let mut best = (0.0, f(0.0));
    let initial = best.1;
    for k in -n..=n {
        if k % 4 == 0 {
            progress(Progress::new("optimize_radius", (k + n) as usize, (2 * n + 1) as usize))?;
        }
        let u = k as f64 * h;
        let v = if k == 0 { initial } else { f(u) };
        if v < best.1 {
            best = (u, v);
        }
    }
    // Golden section in [u* − h, u* + h].
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let (mut a, mut b) = (best.0 - h, best.0 + h);
    let (mut c, mut d) = (b - g * (b - a), a + g * (b - a));
    let (mut fc, mut fd) = (f(c), f(d));
    for _ in 0..40 {
        if fc < fd {
            b = d;
            d = c;
            fd = fc;
            c = b - g * (b - a);
            fc = f(c);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + g * (b - a);
            fd = f(d);
        }
        if b - a < 1e-7 {
            break;
        }
    }
    for (u, v) in [(c, fc), (d, fd)] {
        if v < best.1 {
            best = (u, v);
        }
    }
    Ok((x_of(best.0), best.1, initial))
}

/// The Ω of step 3: the estimate, or with `optimize` the R² (or d) of least mean kink.
pub struct ChosenOmega {
    pub omega: AbsoluteSphere,
    /// The optimized parameter when optimized (the estimate's when the scan found nothing
    /// better).
    pub optimized_parameter: Option<f64>,
    /// The mean kink angle (deg) with the estimate, when optimized.
    pub mean_kink_estimate_deg: Option<f64>,
}

/// Step 3 on the working `mesh` with its `interior` edges (face pairs).
pub fn choose_omega(
    mesh: &TriMesh,
    absolute: &AbsoluteSphereEstimate,
    interior: &[[u32; 2]],
    optimize: bool,
    progress: &mut OnProgress,
) -> Result<ChosenOmega, Cancelled> {
    if !optimize {
        return Ok(ChosenOmega { omega: absolute.omega, optimized_parameter: None, mean_kink_estimate_deg: None });
    }
    progress(Progress::new("optimize_radius", 0, 1))?;
    let families: Vec<[Sphere; 2]> = (0..mesh.face_count()).map(|f| Sphere::through_points_family(mesh.face_points(f))).collect();
    let (best, value, initial) = optimize_parameter(mesh, absolute, &families, interior, progress)?;
    let chosen = if value < initial {
        ChosenOmega { omega: with_parameter(&absolute.omega, best), optimized_parameter: Some(best), mean_kink_estimate_deg: Some(initial) }
    } else {
        ChosenOmega { omega: absolute.omega, optimized_parameter: Some(parameter_of(&absolute.omega)), mean_kink_estimate_deg: Some(initial) }
    };
    progress(Progress::new("optimize_radius", 1, 1))?;
    Ok(chosen)
}
