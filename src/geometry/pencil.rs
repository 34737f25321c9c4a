//! The pencil of spheres through three points as one angle (Sec. 3): every normalized sphere
//! through p₀, p₁, p₂ is, up to orientation,
//!
//! ```text
//! s(θ) = cos θ s₀ + sin θ s₁,
//! ```
//!
//! with s₀ = (0, n̂, ⟨n̂, p₀⟩) the plane of the points (n̂ the unit normal of (p₁ − p₀) × (p₂ − p₀))
//! and s₁ = (1/(2ρ), m/ρ, (|m|² − ρ²)/(2ρ)) their circumsphere (centre m the circumcentre, radius
//! ρ the circumradius), an inversive-orthonormal basis: ⟨s₀, s₁⟩ = ⟨n̂, m − p₀⟩/ρ = 0. The same
//! basis as [`Sphere::through_points_family`], in closed form, so that it can be differentiated.
//!
//! A face sphere kept this way passes through its vertices exactly wherever they move: the
//! incidence ψ_f(v) = 0 of Sec. 3 holds by construction and the sphere has one unknown, not five.
//! [`pencil_member`] gives s(θ) with its derivatives by θ and by the nine coordinates (forward
//! differentiation with [`super::dual::Dual`] numbers).

use glam::DVec3;

use super::dual::{Dual, D3};
use super::sphere::Sphere;

/// A face sphere of the pencil through three points with its Jacobian.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PencilMember {
    /// (a, b, c) of s(θ), normalized.
    pub sphere: [f64; 5],
    /// ∂s/∂θ = −sin θ s₀ + cos θ s₁.
    pub d_theta: [f64; 5],
    /// ∂s_i/∂p: row i, columns (p₀.x, p₀.y, p₀.z, p₁.x, …, p₂.z).
    pub d_points: [[f64; 9]; 5],
}

impl PencilMember {
    pub fn sphere(&self) -> Sphere {
        Sphere::from_array(self.sphere)
    }

    /// The Jacobian row of a scalar g(s) with gradient `grad` = ∂g/∂s: (∂g/∂θ, ∂g/∂p).
    pub fn chain(&self, grad: &[f64; 5]) -> (f64, [f64; 9]) {
        let mut dp = [0.0; 9];
        let mut dt = 0.0;
        for ((g, dth), row) in grad.iter().zip(&self.d_theta).zip(&self.d_points) {
            dt += g * dth;
            for (d, r) in dp.iter_mut().zip(row) {
                *d += g * r;
            }
        }
        (dt, dp)
    }
}

/// s(θ) of the pencil through `p` and its Jacobian (see the module docs). Collinear or coincident
/// points have no pencil: the result is not finite.
pub fn pencil_member(p: [DVec3; 3], theta: f64) -> PencilMember {
    let [s0, s1] = pencil_basis_dual(p);
    let (sn, cs) = theta.sin_cos();
    let mut m = PencilMember { sphere: [0.0; 5], d_theta: [0.0; 5], d_points: [[0.0; 9]; 5] };
    for i in 0..5 {
        m.sphere[i] = cs * s0[i].v + sn * s1[i].v;
        m.d_theta[i] = -sn * s0[i].v + cs * s1[i].v;
        for j in 0..9 {
            m.d_points[i][j] = cs * s0[i].d[j] + sn * s1[i].d[j];
        }
    }
    m
}

/// The basis [s₀, s₁] of the pencil through `p` (see the module docs).
pub(crate) fn pencil_basis(p: [DVec3; 3]) -> [Sphere; 2] {
    pencil_basis_dual(p).map(|s| Sphere::from_array(s.map(|d| d.v)))
}

/// The angle θ of the pencil member closest to `target` (max ⟨s(θ), target⟩).
pub(crate) fn pencil_angle(p: [DVec3; 3], target: &Sphere) -> f64 {
    let [s0, s1] = pencil_basis(p);
    s1.inversive_product(target).atan2(s0.inversive_product(target))
}

fn pencil_basis_dual(p: [DVec3; 3]) -> [[Dual<9>; 5]; 2] {
    let q: [D3<9>; 3] = std::array::from_fn(|k| D3::variable(p[k], 3 * k));
    let u = q[1] - q[0];
    let w = q[2] - q[0];
    let n = u.cross(w);
    let nn = n.dot(n);
    let n_len = nn.sqrt();
    let n_hat = n * n_len.recip();
    // Circumcentre m = p₀ + (|u|² (w × n) + |w|² (n × u)) / (2|n|²).
    let m = q[0] + (w.cross(n) * u.dot(u) + n.cross(u) * w.dot(w)) * (nn * 2.0).recip();
    let e = m - q[0];
    let rho = e.dot(e).sqrt();
    let inv_rho = rho.recip();
    let s0 = [Dual::constant(0.0), n_hat.x, n_hat.y, n_hat.z, n_hat.dot(q[0])];
    let s1 = [inv_rho * 0.5, m.x * inv_rho, m.y * inv_rho, m.z * inv_rho, (m.dot(m) - rho * rho) * inv_rho * 0.5];
    [s0, s1]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn points() -> [DVec3; 3] {
        [DVec3::new(0.1, -0.2, 0.3), DVec3::new(0.6, 0.1, 0.25), DVec3::new(0.2, 0.5, 0.4)]
    }

    #[test]
    fn members_pass_through_the_points_and_are_normalized() {
        let p = points();
        for theta in [-1.2, -0.3, 0.0, 0.4, 1.5] {
            let s = pencil_member(p, theta).sphere();
            assert!((s.discriminant() - 1.0).abs() < 1e-13);
            for q in p {
                assert!(s.eval(q).abs() < 1e-13, "{}", s.eval(q));
            }
        }
    }

    #[test]
    fn basis_matches_the_family() {
        let p = points();
        let [a0, a1] = pencil_basis(p);
        let [b0, b1] = Sphere::through_points_family(p);
        for (x, y) in a0.to_array().iter().zip(b0.to_array()).chain(a1.to_array().iter().zip(b1.to_array())) {
            assert!((x - y).abs() < 1e-12, "{x} vs {y}");
        }
        assert!(a0.inversive_product(&a1).abs() < 1e-14);
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        let p = points();
        let theta = 0.37;
        let m = pencil_member(p, theta);
        let h = 1e-6;
        let at = |p: [DVec3; 3], t: f64| pencil_member(p, t).sphere;
        let (sp, sm) = (at(p, theta + h), at(p, theta - h));
        for i in 0..5 {
            assert!(((sp[i] - sm[i]) / (2.0 * h) - m.d_theta[i]).abs() < 1e-7);
        }
        for j in 0..9 {
            let (mut pp, mut pm) = (p, p);
            pp[j / 3][j % 3] += h;
            pm[j / 3][j % 3] -= h;
            let (sp, sm) = (at(pp, theta), at(pm, theta));
            for i in 0..5 {
                let fd = (sp[i] - sm[i]) / (2.0 * h);
                assert!((fd - m.d_points[i][j]).abs() < 1e-6 * (1.0 + fd.abs()), "∂s{i}/∂x{j}: {fd} vs {}", m.d_points[i][j]);
            }
        }
    }

    #[test]
    fn angle_recovers_a_member() {
        let p = points();
        let s = pencil_member(p, 0.8).sphere();
        assert!((pencil_angle(p, &s) - 0.8).abs() < 1e-12);
    }
}
