//! Estimating the absolute sphere Ω of an ST mesh with support structure (Sec. 4, Eq. 7).
//!
//! 1. **m0**: the point closest, in least squares, to the vertex normal lines G_i = v_i + t n_i
//!    (Eq. 7): the normal equations QᵀQ m0 = Qᵀb with Q_i = [n_i]ₓ (the cross-product matrix,
//!    Q_i x = n_i × x) and b_i = Q_i v_i. QᵀQ = Σ (I − n_i n_iᵀ) (unit n_i), solved in the frame
//!    centred at the bounding-box centre and scaled by its diagonal.
//! 2. **Orientation**: m should lie on the negative side of the surface, where the node axes go.
//!    m0 is on the *positive* side when the mean over the vertices of cos∠(m0 − v_i, n_i) is > 0
//!    (the normals point toward m0 on average). Then the orientation is flipped: n_i → −n_i (and
//!    H_i → −H_i, which leaves every central sphere and R_i² unchanged). `flipped` reports it;
//!    the ST construction then also reverses the triangles' winding.
//! 3. **m**: Levenberg–Marquardt on E_center(m) = Σ (1 − ⟨v_i − m, n_i⟩/|v_i − m|)² from m0, with
//!    the analytic Jacobian ∂r_i/∂m = (n_i − ⟨u_i, n_i⟩ u_i)/|v_i − m|, u_i = (v_i − m)/|v_i − m|
//!    ([`e_center_residuals`]), in the normalized frame.
//! 4. **R²** = mean of R_i² = |m − c_i|² − r_i² over the usable central spheres, evaluated as
//!    |m − v_i|² − 2⟨n_i, m − v_i⟩/H_i (no cancellation between huge |m − c_i|² and r_i²).
//! 5. **m at infinity**: when |m − bbox centre| > `far_factor` · diag, or when E_center(m) is not
//!    at least `min_gain` (relative) below E_∞ = Σ(1 − ⟨a, n_i⟩)², the value of E_center for m
//!    at infinity in the direction −a, Ω becomes the plane ⟨x, a⟩ = d: a is the spherical
//!    barycentre (Karcher mean) of the unit normals, started at their normalized mean; d is the
//!    mean of ⟨c_i, a⟩ over the usable central sphere centres. Node axes are then parallel to a,
//!    and the support side is −a.
//!
//! **Usable central spheres**: a vertex whose H is ≈ 0 has a central sphere that is (nearly) its
//! tangent plane, with a meaningless huge R_i². H ≈ 0 means planar (|H|·diag <
//! [`crate::congruence::central_spheres::PLANAR_TOLERANCE`]) or |H| < `min_curvature_ratio` · (|κ1| + |κ2|)/2 (the
//! principal curvatures nearly cancel). Those are skipped. When fewer than `min_usable_fraction`
//! of the vertices are usable (a minimal surface: on `enneper2.obj` ≈ 90% of the vertices have
//! |H| < 0.1 (|κ1| + |κ2|)/2, against ≤ 10% on the architectural test meshes) the estimate
//! refuses with an error saying so.

// Negated float comparisons are deliberate: they also reject NaN.

use glam::{DMat3, DVec3};
use serde::{Deserialize, Serialize};

use crate::congruence::central_spheres::{CurvatureField, UnusableCentralSpheres};
use crate::geometry::absolute_sphere::AbsoluteSphere;
use crate::geometry::linalg::sym3_eigen;
use crate::geometry::mesh::{bbox, TriMesh};

/// Parameters of [`estimate_absolute_sphere`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct AbsoluteSphereParams {
    /// m is at infinity when |m − bbox centre| > far_factor · diag. Default 50: the node axes of
    /// such an Ω differ from parallel ones by at most ≈ 1/50 rad ≈ 1.1° over the mesh.
    pub far_factor: f64,
    /// m is at infinity unless E_center(m) ≤ (1 − min_gain) · E_∞. Default 0.02.
    pub min_gain: f64,
    /// Central spheres with |H| < min_curvature_ratio · (|κ1| + |κ2|)/2 are skipped. Default 0.1.
    pub min_curvature_ratio: f64,
    /// Refuse when fewer than this fraction of the vertices have usable central spheres.
    /// Default 0.5.
    pub min_usable_fraction: f64,
    /// Levenberg–Marquardt iteration limit. Default 200.
    pub max_iterations: usize,
}

impl Default for AbsoluteSphereParams {
    fn default() -> Self {
        Self { far_factor: 50.0, min_gain: 0.02, min_curvature_ratio: 0.1, min_usable_fraction: 0.5, max_iterations: 200 }
    }
}

/// m0, the orientation decision and the LM-optimized m ([`center_from_normals`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CenterEstimate {
    /// Least-squares intersection of the normal lines (Eq. 7). Orientation independent.
    pub m0: DVec3,
    /// The LM minimizer of E_center from m0, with the (possibly flipped) normals.
    pub m: DVec3,
    /// m0 was on the positive side: the normals were negated before the LM.
    pub flipped: bool,
    /// E_center at m0 and at m (with the final orientation).
    pub e_m0: f64,
    pub e_m: f64,
    pub iterations: usize,
}

/// The estimated absolute sphere with the data of Fig. 14.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AbsoluteSphereEstimate {
    pub omega: AbsoluteSphere,
    pub m0: DVec3,
    /// The LM-optimized m (also when Ω was then declared a plane: where the LM ended).
    pub m: DVec3,
    pub flipped: bool,
    pub at_infinity: bool,
    /// The plane's axis a when at infinity.
    pub axis: Option<DVec3>,
    /// The working unit normals n_i (the jet normals, negated when `flipped`).
    pub normals: Vec<DVec3>,
    /// Fig. 14 left, green: ∠(v_i − m0, n_i) in degrees, per vertex.
    pub angles_m0_deg: Vec<f64>,
    /// Fig. 14 left, red: ∠(v_i − m, n_i) in degrees for the optimized m (for m at infinity:
    /// ∠(a, n_i)).
    pub angles_m_deg: Vec<f64>,
    /// Fig. 14 right: R_i² = |m − c_i|² − r_i² of the usable central spheres.
    pub r2_samples: Vec<f64>,
    /// The vertex of each entry of `r2_samples`.
    pub r2_vertices: Vec<u32>,
    /// For the plane: d_i = ⟨c_i, a⟩ of the usable central sphere centres (empty otherwise).
    pub d_samples: Vec<f64>,
    pub e_center_m0: f64,
    pub e_center_m: f64,
    /// E_center for m at infinity in direction −a.
    pub e_center_infinity: f64,
    pub lm_iterations: usize,
    pub usable_spheres: usize,
    pub skipped_spheres: usize,
}

/// E_center(m) = Σ (1 − ⟨v_i − m, n_i⟩/|v_i − m|)² (unit normals; see [`e_center_residuals`]).
pub fn e_center(points: &[DVec3], normals: &[DVec3], m: DVec3) -> f64 {
    points.iter().zip(normals).map(|(v, n)| residual(*v, *n, m).powi(2)).sum()
}

/// 1 − ⟨u, n⟩ evaluated as ½|u − n|² (equal for unit u, n): accurate for small angles, where
/// E_center is quartic in the angle and 1 − cos would round to 0 below ≈ 1e-8 rad.
fn residual(v: DVec3, n: DVec3, m: DVec3) -> f64 {
    let w = v - m;
    let l = w.length();
    if l > 0.0 {
        0.5 * (w / l - n).length_squared()
    } else {
        1.0
    }
}

/// The residuals r_i = 1 − ⟨u_i, n_i⟩ = ½|u_i − n_i|² (unit n_i), u_i = (v_i − m)/|v_i − m|, and
/// their analytic gradients
/// ∂r_i/∂m = (n_i − ⟨u_i, n_i⟩ u_i)/|v_i − m| (the columns of the 3 × N Jacobianᵀ).
pub fn e_center_residuals(points: &[DVec3], normals: &[DVec3], m: DVec3) -> (Vec<f64>, Vec<DVec3>) {
    points
        .iter()
        .zip(normals)
        .map(|(v, n)| {
            let w = *v - m;
            let l = w.length();
            if !(l > 0.0) {
                return (1.0, DVec3::ZERO);
            }
            let u = w / l;
            let c = u.dot(*n);
            (0.5 * (u - *n).length_squared(), (*n - c * u) / l)
        })
        .unzip()
}

/// Bounding-box centre and diagonal of points (diag 1 when degenerate).
fn frame(points: &[DVec3]) -> (DVec3, f64) {
    let (lo, hi) = bbox(points);
    let d = (hi - lo).length();
    (0.5 * (lo + hi), if d > 0.0 && d.is_finite() { d } else { 1.0 })
}

/// m0 of Eq. (7): QᵀQ m0 = Qᵀb with Q_i = [n_i]ₓ, b_i = Q_i v_i, i.e.
/// Σ (|n_i|² I − n_i n_iᵀ) m0 = Σ (|n_i|² I − n_i n_iᵀ) v_i (QᵀQ = −[n]ₓ² = |n|²I − nnᵀ). Solved by
/// a symmetric eigen-decomposition in the normalized frame; directions with eigenvalue below
/// 1e-12 · trace (all normals parallel to them) are left at the bbox centre. None for no points.
pub fn m0_from_normal_lines(points: &[DVec3], normals: &[DVec3]) -> Option<DVec3> {
    if points.is_empty() {
        return None;
    }
    let (t, s) = frame(points);
    let mut a = DMat3::ZERO;
    let mut rhs = DVec3::ZERO;
    for (v, n) in points.iter().zip(normals) {
        let y = (*v - t) / s;
        let q = DMat3::from_diagonal(DVec3::splat(n.length_squared())) - DMat3::from_cols(*n * n.x, *n * n.y, *n * n.z);
        a += q;
        rhs += q * y;
    }
    let (vals, vecs) = sym3_eigen([[a.x_axis.x, a.y_axis.x, a.z_axis.x], [a.x_axis.y, a.y_axis.y, a.z_axis.y], [a.x_axis.z, a.y_axis.z, a.z_axis.z]]);
    let trace = vals.iter().sum::<f64>().abs();
    let mut y = DVec3::ZERO;
    for k in 0..3 {
        if vals[k] > 1e-12 * trace {
            y += vecs[k] * (vecs[k].dot(rhs) / vals[k]);
        }
    }
    let m0 = t + s * y;
    m0.is_finite().then_some(m0)
}

/// Sec. 4 "Estimating the center m": m0 (Eq. 7), the orientation flip, LM on E_center.
/// `normals` are unit vertex normals of the mesh orientation. The returned normals are the
/// working ones (negated when flipped).
pub fn center_from_normals(points: &[DVec3], normals: &[DVec3], params: &AbsoluteSphereParams) -> Option<(CenterEstimate, Vec<DVec3>)> {
    let m0 = m0_from_normal_lines(points, normals)?;
    let n = points.len() as f64;
    let side = points.iter().zip(normals).map(|(v, nn)| (m0 - *v).normalize_or_zero().dot(*nn)).sum::<f64>() / n;
    let flipped = side > 0.0;
    let normals: Vec<DVec3> = if flipped { normals.iter().map(|x| -*x).collect() } else { normals.to_vec() };
    let (m, iterations) = levenberg_marquardt(points, &normals, m0, params);
    let est = CenterEstimate { m0, m, flipped, e_m0: e_center(points, &normals, m0), e_m: e_center(points, &normals, m), iterations };
    Some((est, normals))
}

/// Small dense LM on the 3 unknowns of m, in the frame y = (m − t)/s. Stops when a step changes
/// E by less than 1e-15 relative, the step is below 1e-13 (relative), the damping exceeds 1e16,
/// m runs beyond `2 far_factor` diagonals, or after `max_iterations`.
///
/// Not [`crate::solver`]: a 3 × 3 system solved in closed form needs no sparse factorization,
/// and E_center is so flat at its minimum that the two iterations (Marquardt's diag(JᵀJ)
/// damping here, ε²I there) reach the same E to 2e-15 but m 1e-9 of the diagonal apart on
/// `tri_mesh.obj`, which moves the face spheres by 1e-7.
fn levenberg_marquardt(points: &[DVec3], normals: &[DVec3], m0: DVec3, params: &AbsoluteSphereParams) -> (DVec3, usize) {
    let (t, s) = frame(points);
    let ys: Vec<DVec3> = points.iter().map(|p| (*p - t) / s).collect();
    let mut y = (m0 - t) / s;
    let mut e = e_center(&ys, normals, y);
    let mut lambda = 1e-3;
    let mut it = 0;
    while it < params.max_iterations {
        it += 1;
        let (r, g) = e_center_residuals(&ys, normals, y);
        let mut jtj = DMat3::ZERO;
        let mut jtr = DVec3::ZERO;
        for (ri, gi) in r.iter().zip(&g) {
            jtj += DMat3::from_cols(*gi * gi.x, *gi * gi.y, *gi * gi.z);
            jtr += *gi * *ri;
        }
        let diag = DVec3::new(jtj.x_axis.x, jtj.y_axis.y, jtj.z_axis.z);
        let floor = 1e-12 * (diag.x + diag.y + diag.z).max(f64::MIN_POSITIVE);
        let mut accepted = false;
        while lambda < 1e16 {
            let damp = DMat3::from_diagonal(lambda * diag.max(DVec3::splat(floor)));
            let step = -((jtj + damp).inverse() * jtr);
            if !step.is_finite() {
                lambda *= 10.0;
                continue;
            }
            let y_new = y + step;
            let e_new = e_center(&ys, normals, y_new);
            if e_new < e {
                let small_step = step.length() <= 1e-13 * (1.0 + y.length());
                let small_gain = e - e_new <= 1e-15 * e;
                y = y_new;
                e = e_new;
                lambda = (lambda * 0.3).max(1e-12);
                accepted = true;
                if small_step || small_gain {
                    return (t + s * y, it);
                }
                break;
            }
            lambda *= 10.0;
        }
        if !accepted || y.length() > 2.0 * params.far_factor {
            break;
        }
    }
    (t + s * y, it)
}

/// Spherical barycentre (Karcher/Fréchet mean on S²) of unit vectors: started at their
/// normalized mean, then y ← exp_y(mean log_y(n_i)) until the step is below 1e-15. None when the
/// mean vanishes.
pub fn spherical_barycenter(normals: &[DVec3]) -> Option<DVec3> {
    let mut a = normals.iter().fold(DVec3::ZERO, |s, n| s + *n).try_normalize()?;
    for _ in 0..100 {
        let mut g = DVec3::ZERO;
        for n in normals {
            let c = n.dot(a).clamp(-1.0, 1.0);
            let perp = *n - c * a;
            let l = perp.length();
            if l > 1e-300 {
                g += perp * (l.atan2(c) / l);
            }
        }
        g /= normals.len() as f64;
        let theta = g.length();
        if !(theta > 1e-15) {
            break;
        }
        a = (a * theta.cos() + g * (theta.sin() / theta)).normalize();
    }
    Some(a)
}

/// The angle ∠(x, n) in degrees.
fn angle_deg(x: DVec3, n: DVec3) -> f64 {
    let l = x.length() * n.length();
    if !(l > 0.0) {
        return 0.0;
    }
    // atan2 form: accurate near 0° and 180°.
    x.cross(n).length().atan2(x.dot(n)).to_degrees()
}

/// Why Ω could not be estimated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AbsoluteSphereError {
    NoVertices,
    NoCentralSpheres(UnusableCentralSpheres),
    /// The normal lines gave no finite centre.
    NoCenter,
}

impl std::fmt::Display for AbsoluteSphereError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            AbsoluteSphereError::NoVertices => f.write_str("the reference has no vertices"),
            AbsoluteSphereError::NoCentralSpheres(e) => {
                write!(f, "{e}; ST meshes with support structure need central spheres to estimate the absolute sphere")
            }
            AbsoluteSphereError::NoCenter => f.write_str(
                "could not estimate the centre m of the absolute sphere: the normals neither meet near a point nor are parallel \
                 enough for Ω at infinity",
            ),
        }
    }
}

impl std::error::Error for AbsoluteSphereError {}

/// Estimates Ω for a mesh and its curvature field (paper Sec. 4; see the module documentation).
/// Errors: no vertices, or too few usable central spheres (a minimal surface).
pub fn estimate_absolute_sphere(
    mesh: &TriMesh,
    field: &CurvatureField,
    params: &AbsoluteSphereParams,
) -> Result<AbsoluteSphereEstimate, AbsoluteSphereError> {
    let nv = mesh.vertex_count().min(field.vertices.len());
    if nv == 0 {
        return Err(AbsoluteSphereError::NoVertices);
    }
    let points = &mesh.positions[..nv];
    let diag = mesh.bbox_diagonal();
    let usable = field
        .usable_central_spheres(nv, diag, params.min_curvature_ratio, params.min_usable_fraction)
        .map_err(AbsoluteSphereError::NoCentralSpheres)?;
    let usable_count = usable.iter().filter(|&&u| u).count();
    let skipped = nv - usable_count;
    let jet_normals: Vec<DVec3> = field.vertices[..nv].iter().map(|c| c.normal).collect();
    let (center, normals) = center_from_normals(points, &jet_normals, params).ok_or(AbsoluteSphereError::NoCenter)?;
    let (t, _) = frame(points);
    let axis = spherical_barycenter(&normals);
    let e_inf = axis.map_or(f64::INFINITY, |a| normals.iter().map(|n| (1.0 - a.dot(*n)).powi(2)).sum());
    let far = (center.m - t).length() > params.far_factor * diag;
    let no_gain = !(center.e_m <= (1.0 - params.min_gain) * e_inf);
    let at_infinity = (far || no_gain || !center.m.is_finite()) && axis.is_some();

    let angles_m0_deg: Vec<f64> = points.iter().zip(&normals).map(|(v, n)| angle_deg(*v - center.m0, *n)).collect();
    let mut r2_samples = Vec::with_capacity(usable_count);
    let mut r2_vertices = Vec::with_capacity(usable_count);
    let mut d_samples = Vec::new();
    let (omega, angles_m_deg) = if at_infinity {
        let a = axis.unwrap();
        for i in (0..nv).filter(|&i| usable[i]) {
            let c = &field.vertices[i];
            let centre = points[i] + c.normal / c.mean;
            d_samples.push(centre.dot(a));
            r2_vertices.push(i as u32);
        }
        let d = d_samples.iter().sum::<f64>() / d_samples.len() as f64;
        if !d.is_finite() {
            return Err(AbsoluteSphereError::NoCenter);
        }
        let angles = normals.iter().map(|n| angle_deg(a, *n)).collect();
        (AbsoluteSphere::Plane { axis: a, d }, angles)
    } else {
        let m = center.m;
        for i in (0..nv).filter(|&i| usable[i]) {
            let c = &field.vertices[i];
            let w = m - points[i];
            r2_samples.push(w.length_squared() - 2.0 * c.normal.dot(w) / c.mean);
            r2_vertices.push(i as u32);
        }
        let r2 = r2_samples.iter().sum::<f64>() / r2_samples.len() as f64;
        if !m.is_finite() || !r2.is_finite() {
            return Err(AbsoluteSphereError::NoCenter);
        }
        let angles = points.iter().zip(&normals).map(|(v, n)| angle_deg(*v - m, *n)).collect();
        (AbsoluteSphere::Sphere { center: m, r2 }, angles)
    };
    Ok(AbsoluteSphereEstimate {
        omega,
        m0: center.m0,
        m: center.m,
        flipped: center.flipped,
        at_infinity,
        axis: if at_infinity { axis } else { None },
        normals,
        angles_m0_deg,
        angles_m_deg,
        r2_samples,
        r2_vertices,
        d_samples,
        e_center_m0: center.e_m0,
        e_center_m: center.e_m,
        e_center_infinity: e_inf,
        lm_iterations: center.iterations,
        usable_spheres: usable_count,
        skipped_spheres: skipped,
    })
}
