//! Built-in reference surfaces, generated in code as regular, consistently oriented triangulations
//! (normals up/outward), plus the parametric patches the tests check against closed forms.
//!
//! Units are metres for the architectural samples.

use crate::geometry::bspline::surface::TESSELLATION_TOLERANCE;
use crate::geometry::bspline::{BSplineBasis, BSplineSurface};
use crate::geometry::mesh::TriMesh;
use glam::DVec3;
use serde::{Deserialize, Serialize};
use std::f64::consts::{PI, TAU};

/// A built-in reference surface.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Sample {
    #[default]
    Dome,
    TorusPatch,
    SphereCap,
    WaveRoof,
    /// A B-spline surface: the SQ method's sample.
    Vault,
}

impl Sample {
    pub const ALL: [Sample; 5] = [Sample::Dome, Sample::TorusPatch, Sample::SphereCap, Sample::WaveRoof, Sample::Vault];

    /// Stable key for URLs and the CLI.
    pub fn key(self) -> &'static str {
        match self {
            Sample::Dome => "dome",
            Sample::TorusPatch => "torus",
            Sample::SphereCap => "sphere-cap",
            Sample::WaveRoof => "wave-roof",
            Sample::Vault => "vault",
        }
    }

    pub fn from_key(key: &str) -> Option<Sample> {
        Sample::ALL.into_iter().find(|s| s.key() == key)
    }

    pub fn title(self) -> &'static str {
        match self {
            Sample::Dome => "Free-form dome",
            Sample::TorusPatch => "Curved barrel vault (torus patch)",
            Sample::SphereCap => "Spherical cap",
            Sample::WaveRoof => "Wave roof",
            Sample::Vault => "Bulging vault (B-spline)",
        }
    }

    pub fn description(self) -> &'static str {
        match self {
            Sample::Dome => {
                "A 30 m × 20 m shell over a rounded-rectangle footprint, 7 m high, apex shifted \
                 off-centre. Its mean curvature keeps one sign everywhere, boundary included. \
                 1801 vertices, 3456 triangles."
            }
            Sample::TorusPatch => {
                "A barrel vault of 5 m radius bent around a 16 m axis: a torus patch (R = 16 m, \
                 r = 5 m, 80° of the ring, the upper half of the tube). Principal curvatures are known \
                 in closed form; H keeps one sign. 2109 vertices, 4032 triangles."
            }
            Sample::SphereCap => {
                "A shallow spherical cap: radius 20 m, 24 m span, 4 m rise. Every central sphere is the \
                 sphere itself. 1801 vertices, 3456 triangles."
            }
            Sample::WaveRoof => {
                "A 32 m × 20 m canopy with gentle undulations: the mean curvature changes sign, so \
                 central spheres pass through planes. 1519 vertices, 2880 triangles."
            }
            Sample::Vault => {
                "A barrel vault 18 m long, 14 m wide and 5.2 m high at its ends, bulging to 15.9 m wide \
                 and 5.9 m high at mid-length: a degree-5 B-spline surface with 9 × 8 control points. \
                 Its mean curvature keeps one sign, so the SQ method (Sec. 5) runs on it. Tessellated \
                 with 2520 vertices, 4840 triangles."
            }
        }
    }

    /// The B-spline surface of a B-spline sample (the vault); None for the mesh samples.
    pub fn bspline(self) -> Option<BSplineSurface> {
        match self {
            Sample::Vault => Some(vault()),
            _ => None,
        }
    }

    /// The triangle mesh, normals up/outward.
    pub fn mesh(self) -> TriMesh {
        match self {
            Sample::Dome => dome(24),
            Sample::TorusPatch => torus_patch(16.0, 5.0, (-0.7, 0.7), (0.0, PI), 56, 36),
            Sample::SphereCap => sphere_cap(20.0, 12.0, 24),
            Sample::WaveRoof => wave_roof(48, 30),
            Sample::Vault => {
                let v = vault();
                v.tessellate(v.tessellation_segments(TESSELLATION_TOLERANCE)).0.triangulated()
            }
        }
    }
}

/// The vault's half-span, height and length, metres, and its bulge at mid-length (relative).
const VAULT_HALF_SPAN: f64 = 7.0;
const VAULT_HEIGHT: f64 = 5.5;
const VAULT_LENGTH: f64 = 18.0;
const VAULT_BULGE: [f64; 2] = [0.15, 0.15];

/// The vault: degree 5 × 5, 9 control points across (U, a convex arch polygon standing on the
/// ground) and 8 along (V), the arch scaled by (1 + b sin(π t)) in width and height at t along
/// the length. Convex arch polygons and a concave scale profile keep both principal curvatures of
/// one sign (normal S_u × S_v up and outward, H < 0).
pub fn vault() -> BSplineSurface {
    const ACROSS: usize = 9;
    const ALONG: usize = 8;
    // Unit arch polygon: straight up from the ground, then around a half-ellipse.
    let arch: Vec<(f64, f64)> = (0..ACROSS)
        .map(|i| match i {
            0 => (-1.0, 0.0),
            1 => (-1.0, 0.35),
            i if i == ACROSS - 2 => (1.0, 0.35),
            i if i == ACROSS - 1 => (1.0, 0.0),
            i => {
                let t = PI * (i - 1) as f64 / (ACROSS - 3) as f64;
                (-t.cos(), 0.35 + 0.65 * t.sin())
            }
        })
        .collect();
    let mut control = Vec::with_capacity(ACROSS * ALONG);
    for j in 0..ALONG {
        let t = j as f64 / (ALONG - 1) as f64;
        let (sx, sz) = (1.0 + VAULT_BULGE[0] * (PI * t).sin(), 1.0 + VAULT_BULGE[1] * (PI * t).sin());
        for &(x, z) in &arch {
            control.push(DVec3::new(VAULT_HALF_SPAN * sx * x, VAULT_LENGTH * t, VAULT_HEIGHT * sz * z));
        }
    }
    let u = BSplineBasis::clamped_uniform(5, ACROSS, (0.0, 1.0)).expect("a valid basis");
    let v = BSplineBasis::clamped_uniform(5, ALONG, (0.0, 1.0)).expect("a valid basis");
    BSplineSurface::new(u, v, control, vec![1.0; ACROSS * ALONG]).expect("a valid surface")
}

// --- Architectural samples -------------------------------------------------------------------

/// Dome half-length (x), half-width (y) and apex scale, metres.
const DOME_A: f64 = 15.0;
const DOME_B: f64 = 10.0;
const DOME_H: f64 = 7.0;
/// Squareness of the footprint m(u, v) = u² + v² − c u² v² = 1 (0 is an ellipse).
const DOME_SQUARE: f64 = 0.5;
/// Apex shift: the height is scaled by (1 + s u).
const DOME_SHIFT: f64 = 0.2;

/// Height of the dome over the normalized footprint coordinates (u, v) = (x/a, y/b); zero on the
/// footprint boundary m(u, v) = 1.
pub fn dome_height(u: f64, v: f64) -> f64 {
    let m = u * u + v * v - DOME_SQUARE * u * u * v * v;
    DOME_H * (1.0 - m) * (1.0 + DOME_SHIFT * u)
}

/// The free-form dome with `rings` concentric rings (1 + 3 rings (rings + 1) vertices).
pub fn dome(rings: usize) -> TriMesh {
    disc_mesh(rings, |rho, phi| {
        // Boundary of the footprint along the ray at angle φ: m(ρ cos φ, ρ sin φ) = 1, i.e.
        // A ρ⁴ − ρ² + 1 = 0 with A = c cos²φ sin²φ.
        let (s, c) = phi.sin_cos();
        let a4 = DOME_SQUARE * c * c * s * s;
        let r2 = if a4 > 1e-12 { (1.0 - (1.0 - 4.0 * a4).sqrt()) / (2.0 * a4) } else { 1.0 };
        let (u, v) = (rho * r2.sqrt() * c, rho * r2.sqrt() * s);
        DVec3::new(DOME_A * u, DOME_B * v, dome_height(u, v))
    })
}

/// A spherical cap of radius `radius` spanning a circle of radius `base_radius` (< radius) on
/// z = 0, rising toward +z, outward normals; `rings` concentric rings, evenly spaced in arc length.
pub fn sphere_cap(radius: f64, base_radius: f64, rings: usize) -> TriMesh {
    let theta_max = (base_radius / radius).clamp(-1.0, 1.0).asin();
    let center = DVec3::new(0.0, 0.0, -radius * theta_max.cos());
    disc_mesh(rings, |rho, phi| {
        let theta = rho * theta_max;
        let (st, ct) = theta.sin_cos();
        center + radius * DVec3::new(st * phi.cos(), st * phi.sin(), ct)
    })
}

/// The undulating canopy over [−16, 16] × [−10, 10] m, `nx` × `ny` grid cells.
pub(crate) fn wave_roof(nx: usize, ny: usize) -> TriMesh {
    grid_mesh(nx, ny, false, false, |s, t| {
        let (x, y) = (-16.0 + 32.0 * s, -10.0 + 20.0 * t);
        let z = 6.0 + 0.9 * (TAU * x / 16.0 + 0.4 * y / 10.0).cos() * (1.0 - 0.3 * (y / 10.0).powi(2)) - 1.5 * (y / 10.0).powi(2);
        DVec3::new(x, y, z)
    })
}

// --- Parametric patches with closed-form curvature --------------------------------------------

/// Torus patch (R + r cos v) (cos u, sin u, 0) + r sin v (0, 0, 1) over `u_range` × `v_range` with
/// `nu` × `nv` grid cells, outward normals. A range spanning 2π (or more) closes up (no seam).
pub fn torus_patch(big_r: f64, small_r: f64, u_range: (f64, f64), v_range: (f64, f64), nu: usize, nv: usize) -> TriMesh {
    let wrap_u = (u_range.1 - u_range.0).abs() >= TAU - 1e-9;
    let wrap_v = (v_range.1 - v_range.0).abs() >= TAU - 1e-9;
    grid_mesh(nu, nv, wrap_u, wrap_v, |s, t| {
        let u = u_range.0 + s * (u_range.1 - u_range.0);
        let v = v_range.0 + t * (v_range.1 - v_range.0);
        let rho = big_r + small_r * v.cos();
        DVec3::new(rho * u.cos(), rho * u.sin(), small_r * v.sin())
    })
}

/// Principal curvatures of the torus at parameter `v` w.r.t. the **inward** normal:
/// (meridian 1/r, parallel cos v / (R + r cos v)). W.r.t. the outward normal of [`torus_patch`]
/// (the convention of `jet_fit` on it) both change sign: κ_meridian = −1/r,
/// κ_parallel = −cos v / (R + r cos v). The meridian direction is ∂/∂v, the parallel ∂/∂u.
pub fn torus_closed_form(big_r: f64, small_r: f64, v: f64) -> (f64, f64) {
    (1.0 / small_r, v.cos() / (big_r + small_r * v.cos()))
}

/// A square sphere patch around the +z axis of the sphere of radius `radius` centred at the
/// origin: the gnomonic image of an `n` × `n` grid on [−tan α, tan α]² (α = `half_angle`), outward
/// normals (κ = −1/R w.r.t. them).
pub fn sphere_patch(radius: f64, half_angle: f64, n: usize) -> TriMesh {
    let t = half_angle.tan();
    grid_mesh(n, n, false, false, |s, q| radius * DVec3::new(t * (2.0 * s - 1.0), t * (2.0 * q - 1.0), 1.0).normalize())
}

/// A cylinder patch of radius `radius` with axis along y, spanning the angle `angle` around +z
/// and the length `length` (centred at y = 0), `n_around` × `n_along` cells, outward normals
/// (κ1 = 0 along the axis, κ2 = −1/r around it, H = −1/(2r)).
pub fn cylinder_patch(radius: f64, angle: f64, length: f64, n_around: usize, n_along: usize) -> TriMesh {
    grid_mesh(n_around, n_along, false, false, |s, t| {
        let phi = (s - 0.5) * angle;
        DVec3::new(radius * phi.sin(), (t - 0.5) * length, radius * phi.cos())
    })
}

/// The rectangle [−w/2, w/2] × [−h/2, h/2] in z = 0, `nx` × `ny` cells, normals +z.
pub fn plane_patch(width: f64, height: f64, nx: usize, ny: usize) -> TriMesh {
    grid_mesh(nx, ny, false, false, |s, t| DVec3::new((s - 0.5) * width, (t - 0.5) * height, 0.0))
}

// --- Triangulations --------------------------------------------------------------------------

/// A regular grid of `nu` × `nv` cells over (s, t) ∈ [0, 1]², each cell split along the same
/// diagonal (valence 6 inside). Triangles are counter-clockwise in (s, t), so normals follow
/// ∂p/∂s × ∂p/∂t. Wrapped directions identify s = 1 with s = 0 (t likewise).
fn grid_mesh(nu: usize, nv: usize, wrap_u: bool, wrap_v: bool, pos: impl Fn(f64, f64) -> DVec3) -> TriMesh {
    let (nu, nv) = (nu.max(1), nv.max(1));
    let (cu, cv) = (if wrap_u { nu } else { nu + 1 }, if wrap_v { nv } else { nv + 1 });
    let mut positions = Vec::with_capacity(cu * cv);
    for j in 0..cv {
        for i in 0..cu {
            positions.push(pos(i as f64 / nu as f64, j as f64 / nv as f64));
        }
    }
    let idx = |i: usize, j: usize| ((j % cv) * cu + (i % cu)) as u32;
    let mut triangles = Vec::with_capacity(2 * nu * nv);
    for j in 0..nv {
        for i in 0..nu {
            let (a, b, c, d) = (idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1));
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
    }
    TriMesh::new(positions, triangles)
}

/// A triangulated disc: a centre vertex and `rings` rings, ring k with 6k vertices at polar angles
/// 2πi/(6k), consecutive rings stitched by angle. `pos(ρ, φ)` maps ρ = k/rings ∈ [0, 1] and φ to
/// space; triangles are counter-clockwise in the (ρ cos φ, ρ sin φ) plane.
fn disc_mesh(rings: usize, pos: impl Fn(f64, f64) -> DVec3) -> TriMesh {
    let rings = rings.max(1);
    let mut positions = vec![pos(0.0, 0.0)];
    let mut start = vec![0usize]; // first vertex of ring k
    for k in 1..=rings {
        start.push(positions.len());
        let n = 6 * k;
        for i in 0..n {
            positions.push(pos(k as f64 / rings as f64, TAU * i as f64 / n as f64));
        }
    }
    let mut triangles = Vec::with_capacity(6 * rings * rings);
    for j in 0..6 {
        triangles.push([0, (1 + j) as u32, (1 + (j + 1) % 6) as u32]);
    }
    for k in 2..=rings {
        let (na, nb) = (6 * (k - 1), 6 * k);
        let a = |i: usize| (start[k - 1] + i % na) as u32;
        let b = |j: usize| (start[k] + j % nb) as u32;
        let (mut i, mut j) = (0usize, 0usize);
        while i < na || j < nb {
            // Next angles as fractions of the full turn, compared exactly in integers:
            // (i + 1)/na vs (j + 1)/nb.
            let advance_outer = i == na || (j < nb && (j + 1) * na <= (i + 1) * nb);
            if advance_outer {
                triangles.push([a(i), b(j), b(j + 1)]);
                j += 1;
            } else {
                triangles.push([a(i), b(j), a(i + 1)]);
                i += 1;
            }
        }
    }
    TriMesh::new(positions, triangles)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn disc_counts() {
        for r in 1..5 {
            let m = disc_mesh(r, |rho, phi| DVec3::new(rho * phi.cos(), rho * phi.sin(), 0.0));
            assert_eq!(m.vertex_count(), 1 + 3 * r * (r + 1));
            assert_eq!(m.face_count(), 6 * r * r);
            for f in 0..m.face_count() {
                assert!(m.face_area_vector(f).z > 0.0, "face {f} of {r} rings");
            }
        }
    }
}
