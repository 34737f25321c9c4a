//! Tessellation of a panel (3 or 4 circular sides) for display and export: the arc points on
//! its boundary, a grid inside, zippers between them. See the [`super`] module docs.

// Negated float comparisons are deliberate: they also reject NaN.

use glam::DVec3;

use super::arc::Arc;
use crate::geometry::sphere::Sphere;

/// Highest subdivision level of one panel (at most about 2 · N² = 131,072 triangles).
pub const MAX_LEVEL: usize = 256;
/// The most triangles one panel's tessellation can have: a quad's M × N grid at [`MAX_LEVEL`]
/// and the zippers to four sides of at most [`super::arc::MAX_ARC_SEGMENTS`] points each.
pub const MAX_PANEL_TRIANGLES: usize = 2 * MAX_LEVEL * MAX_LEVEL + 4 * (super::arc::MAX_ARC_SEGMENTS + MAX_LEVEL + 2);
/// Fraction of the chord tolerance allowed for the sagitta of an arc segment. The flat triangles
/// on a boundary segment deviate from the sphere by a bit more than its sagitta (their longest
/// edge is a little longer than the segment), so leave them room.
pub(crate) const ARC_TOL_FACTOR: f64 = 0.5;

/// The tessellation of one panel.
#[derive(Clone, Debug, PartialEq)]
pub struct Tessellation {
    /// Vertices; the first ones are the panel's corners, in order.
    pub positions: Vec<DVec3>,
    /// Triangles (indices into `positions`), oriented like the face.
    pub triangles: Vec<[u32; 3]>,
    /// Sum of the triangle areas.
    pub area: f64,
    /// Per side k: indices into `positions` of the points of arc k, from corner k to corner k + 1.
    pub arc_vertices: Vec<Vec<u32>>,
}

/// Tessellates a panel on `sphere` with corners `corners` (3 or 4) from its sides (arc k and its
/// points, from corner k to corner k + 1), with chord error ≤ `tol`, at levels up to `max_level`
/// (at most [`MAX_LEVEL`]).
pub fn tessellate(sphere: &Sphere, sides: Vec<(Arc, Vec<DVec3>)>, corners: &[DVec3], tol: f64, max_level: usize) -> Tessellation {
    let max_level = max_level.clamp(1, MAX_LEVEL);
    let nc = corners.len();
    let n_side: Vec<usize> = sides.iter().map(|s| s.1.len() - 1).collect();
    // Corners first, then the inner points of each side.
    let mut base: Vec<DVec3> = corners.to_vec();
    let mut arc_vertices: Vec<Vec<u32>> = Vec::with_capacity(nc);
    for (k, (_, pts)) in sides.iter().enumerate() {
        let mut ids = vec![k as u32];
        for &x in &pts[1..pts.len() - 1] {
            ids.push(base.len() as u32);
            base.push(x);
        }
        ids.push(((k + 1) % nc) as u32);
        arc_vertices.push(ids);
    }
    let arcs: Vec<Arc> = sides.iter().map(|s| s.0).collect();

    let q = match corners {
        [a, b, c] => triangle_q_max(*a, *b, *c),
        _ => triangle_q_max(corners[0], corners[1], corners[2]).max(triangle_q_max(corners[0], corners[2], corners[3])),
    };
    let estimate = (sphere.a.abs() * q / tol).sqrt().ceil();
    let estimate = if estimate.is_finite() { (estimate as usize).min(max_level) } else { max_level };
    // Grid levels: one for a triangle; along sides 0/2 and 1/3 for a quad.
    let mut levels = match nc {
        3 => [n_side.iter().copied().max().unwrap_or(1).max(estimate).clamp(1, max_level); 2],
        _ => [n_side[0].max(n_side[2]).max(estimate).clamp(1, max_level), n_side[1].max(n_side[3]).max(estimate).clamp(1, max_level)],
    };
    let (mut best_err, mut stalled) = (f64::INFINITY, 0);
    loop {
        let (positions, triangles) = match nc {
            3 => {
                let arcs3 = [arcs[0], arcs[1], arcs[2]];
                let tri = [corners[0], corners[1], corners[2]];
                grid(sphere, &arcs3, &tri, &base, &arc_vertices, &n_side, levels[0])
            }
            _ => quad_grid(sphere, &arcs, corners, &base, &arc_vertices, &n_side, levels),
        };
        let err = triangles
            .iter()
            .map(|t| triangle_chord_error(sphere, positions[t[0] as usize], positions[t[1] as usize], positions[t[2] as usize]))
            .fold(0.0, f64::max);
        // Stop when fine enough, at the cap, or when three refinements in a row did not help (a
        // panel whose arcs cross at a corner: invalid input, see `Panel::folded_triangles`).
        if err < 0.99 * best_err {
            best_err = err;
            stalled = 0;
        } else {
            stalled += 1;
        }
        if err <= tol || levels.iter().all(|&l| l >= max_level) || stalled >= 3 {
            let area = triangles
                .iter()
                .map(|t| {
                    let [a, b, c] = t.map(|i| positions[i as usize]);
                    0.5 * (b - a).cross(c - a).length()
                })
                .sum();
            return Tessellation { positions, triangles, area, arc_vertices };
        }
        for level in &mut levels {
            let grow = (*level as f64 * (err / tol).sqrt() * 1.05).ceil() as usize;
            *level = grow.max(*level + 1).min(max_level);
        }
    }
}

/// The level-N tessellation of a panel: returns positions (the `base` points followed by the
/// interior grid points) and the triangles.
///
/// N = 1 (only possible when every side is a single segment): the corner triangle. Otherwise
/// (N ≥ 3) the interior points of the level-N barycentric grid (all barycentric coordinates
/// ≥ 1/N) are triangulated as a regular grid, and the ring between them and the boundary (the
/// arc points) is closed side by side by a zipper: along side k, the arc points and the grid row
/// next to that side are merged by their parameter along the side. Every zipper triangle has
/// either its base on the boundary and its apex on the row or vice versa, so nothing folds
/// whatever the arc point counts are.
fn grid(
    sphere: &Sphere,
    arcs: &[Arc; 3],
    tri: &[DVec3; 3],
    base: &[DVec3],
    arc_vertices: &[Vec<u32>],
    n_side: &[usize],
    level: usize,
) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let mut positions = base.to_vec();
    if level <= 1 && n_side.iter().all(|&n| n == 1) {
        return (positions, vec![[0, 1, 2]]);
    }
    let nn = level.max(3);
    // Interior grid point (i, a, b), i + a + b = N, all ≥ 1, stored by (a', b') = (a − 1, b − 1)
    // in the level-M grid, M = N − 3.
    let m = nn - 3;
    let row_start = |b: usize| -> usize { b * (m + 1) - b * (b.saturating_sub(1)) / 2 };
    let mut ids = vec![0u32; (m + 1) * (m + 2) / 2];
    for b in 0..=m {
        for a in 0..=(m - b) {
            let (ga, gb) = (a + 1, b + 1);
            let gi = nn - ga - gb;
            let lam = [gi as f64 / nn as f64, ga as f64 / nn as f64, gb as f64 / nn as f64];
            let x = blend(arcs, tri, lam);
            positions.push(project_to_sphere(sphere, tri[0], x));
            ids[row_start(b) + a] = (positions.len() - 1) as u32;
        }
    }
    let g = |a: usize, b: usize| ids[row_start(b) + a];
    let mut triangles = Vec::with_capacity(nn * nn);
    for b in 0..m {
        for a in 0..(m - b) {
            triangles.push([g(a, b), g(a + 1, b), g(a, b + 1)]);
            if a + b + 2 <= m {
                triangles.push([g(a + 1, b), g(a + 1, b + 1), g(a, b + 1)]);
            }
        }
    }
    // The grid row next to each side, from near corner k to near corner k+1, with its parameter
    // along the side: side 0 (b = 1, a up), side 1 (i = 1, b up), side 2 (a = 1, i up).
    for (k, bnd) in arc_vertices.iter().enumerate() {
        let row: Vec<(u32, f64)> = (0..=m)
            .map(|s| {
                let (a, b) = match k {
                    0 => (s, 0),
                    1 => (m - s, s),
                    _ => (0, m - s),
                };
                // Grid coordinates (i, a, b) of this point, and the parameter along side k.
                let (ga, gb) = ((a + 1) as f64, (b + 1) as f64);
                let gi = nn as f64 - ga - gb;
                let t = match k {
                    0 => ga / (gi + ga),
                    1 => gb / (ga + gb),
                    _ => gi / (gb + gi),
                };
                (g(a, b), t)
            })
            .collect();
        zipper(bnd, &row, &mut triangles);
    }
    (positions, triangles)
}

/// Closes the ring between the boundary points `bnd` of a side (from its first corner to its
/// last) and the grid row next to it (points with their parameter along the side): the two are
/// merged by parameter, so every triangle has its base on one and its apex on the other, and
/// nothing folds whatever the point counts are.
fn zipper(bnd: &[u32], row: &[(u32, f64)], triangles: &mut Vec<[u32; 3]>) {
    let n = bnd.len() - 1;
    let (mut j, mut l) = (0usize, 0usize);
    while j < n || l < row.len() - 1 {
        let advance_boundary = l == row.len() - 1 || (j < n && (j + 1) as f64 / n as f64 <= row[l + 1].1);
        if advance_boundary {
            triangles.push([bnd[j], bnd[j + 1], row[l].0]);
            j += 1;
        } else {
            triangles.push([bnd[j], row[l + 1].0, row[l].0]);
            l += 1;
        }
    }
}

/// The level-(M, N) tessellation of a quad panel: returns positions (the `base` points followed
/// by the interior grid points) and the triangles.
///
/// M = N = 1 (only when every side is a single segment): the corner quad as two triangles.
/// Otherwise (M, N ≥ 2) the interior points (i/M, j/N), 0 < i < M, 0 < j < N, of the Coons patch
/// of the four arcs ([`coons`]), projected radially onto the sphere, are triangulated as a
/// regular grid, and the ring to the arc points is closed by a [`zipper`] per side.
fn quad_grid(
    sphere: &Sphere,
    arcs: &[Arc],
    quad: &[DVec3],
    base: &[DVec3],
    arc_vertices: &[Vec<u32>],
    n_side: &[usize],
    levels: [usize; 2],
) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let mut positions = base.to_vec();
    if levels.iter().all(|&l| l <= 1) && n_side.iter().all(|&n| n == 1) {
        return (positions, vec![[0, 1, 2], [0, 2, 3]]);
    }
    let (m, n) = (levels[0].max(2), levels[1].max(2));
    let first = positions.len() as u32;
    for j in 1..n {
        for i in 1..m {
            let x = coons(arcs, quad, i as f64 / m as f64, j as f64 / n as f64);
            positions.push(project_to_sphere(sphere, quad[0], x));
        }
    }
    let g = |i: usize, j: usize| first + ((j - 1) * (m - 1) + (i - 1)) as u32;
    let mut triangles = Vec::with_capacity(2 * m * n);
    for j in 1..n - 1 {
        for i in 1..m - 1 {
            triangles.push([g(i, j), g(i + 1, j), g(i + 1, j + 1)]);
            triangles.push([g(i, j), g(i + 1, j + 1), g(i, j + 1)]);
        }
    }
    // The grid row next to each side, from near corner k to near corner k + 1, with its
    // parameter along the side.
    let (mf, nf) = (m as f64, n as f64);
    for (k, bnd) in arc_vertices.iter().enumerate() {
        let row: Vec<(u32, f64)> = match k {
            0 => (1..m).map(|i| (g(i, 1), i as f64 / mf)).collect(),
            1 => (1..n).map(|j| (g(m - 1, j), j as f64 / nf)).collect(),
            2 => (1..m).rev().map(|i| (g(i, n - 1), (m - i) as f64 / mf)).collect(),
            _ => (1..n).rev().map(|j| (g(1, j), (n - j) as f64 / nf)).collect(),
        };
        zipper(bnd, &row, &mut triangles);
    }
    (positions, triangles)
}

/// The Coons patch of a quad's four arcs at (s, t) ∈ [0, 1]²: the two ruled blends of opposite
/// arcs minus the bilinear blend of the corners. Arc 0 runs at t = 0 from corner 0 to 1, arc 1 at
/// s = 1 from corner 1 to 2, arc 2 at t = 1 from corner 2 back to 3, arc 3 at s = 0 from corner 3
/// back to 0, so the patch reproduces every arc on its side.
fn coons(arcs: &[Arc], q: &[DVec3], s: f64, t: f64) -> DVec3 {
    let bottom = arcs[0].point(s);
    let right = arcs[1].point(t);
    let top = arcs[2].point(1.0 - s);
    let left = arcs[3].point(1.0 - t);
    let bilinear = (1.0 - s) * (1.0 - t) * q[0] + s * (1.0 - t) * q[1] + s * t * q[2] + (1.0 - s) * t * q[3];
    (1.0 - t) * bottom + t * top + (1.0 - s) * left + s * right - bilinear
}

/// Transfinite blend: Σλᵢ Pᵢ + Σₖ (1 − λ_{k+2}) dₖ(λ_{k+1}/(1 − λ_{k+2})), where dₖ(t) is
/// arc k's offset from its chord at parameter t. It reproduces every arc on its side.
fn blend(arcs: &[Arc; 3], tri: &[DVec3; 3], lam: [f64; 3]) -> DVec3 {
    let mut x = lam[0] * tri[0] + lam[1] * tri[1] + lam[2] * tri[2];
    for k in 0..3 {
        let w = 1.0 - lam[(k + 2) % 3];
        if w <= 0.0 || arcs[k].is_straight() {
            continue;
        }
        let t = lam[(k + 1) % 3] / w;
        let chord = tri[k] + t * (tri[(k + 1) % 3] - tri[k]);
        x += w * (arcs[k].point(t) - chord);
    }
    x
}

/// Largest distance between triangle `x0 x1 x2` (corners on the normalized sphere `s`) and the
/// sphere. For x = Σβᵢxᵢ, ψ(x) = Σβᵢψ(xᵢ) − a·Q(β) with Q = Σ_{i<j} βᵢβⱼ|xᵢ − xⱼ|², and
/// max_T Q is the squared circumradius for an acute triangle, else (longest edge / 2)².
/// Corner residuals ψ(xᵢ) are added as an upper bound.
pub fn triangle_chord_error(s: &Sphere, x0: DVec3, x1: DVec3, x2: DVec3) -> f64 {
    let q = triangle_q_max(x0, x1, x2);
    let psi = s.a.abs() * q;
    let curved = 2.0 * psi / (1.0 + (1.0 - 4.0 * s.a * s.a * q).max(0.0).sqrt());
    let residual = [x0, x1, x2].iter().map(|&x| s.distance(x)).fold(0.0, f64::max);
    curved + residual
}

/// max over the triangle of Σ_{i<j} βᵢβⱼ|xᵢ − xⱼ|² (the negated power of the point w.r.t. the
/// circumcircle): R² when acute, (ℓ_max/2)² otherwise.
pub(crate) fn triangle_q_max(x0: DVec3, x1: DVec3, x2: DVec3) -> f64 {
    let l = [x1.distance_squared(x2), x2.distance_squared(x0), x0.distance_squared(x1)];
    let lmax = l[0].max(l[1]).max(l[2]);
    let acute = l[0] < l[1] + l[2] && l[1] < l[2] + l[0] && l[2] < l[0] + l[1];
    if acute {
        let a2 = (x1 - x0).cross(x2 - x0).length_squared(); // (2·area)²
        if a2 > 0.0 {
            return (l[0] * l[1] * l[2] / (4.0 * a2)).min(lmax);
        }
    }
    0.25 * lmax
}

/// Projects `x` radially onto the sphere (from its centre; orthogonally for a plane) by Newton
/// steps along ∇ψ, in coordinates local to `base` (a point on or near the sphere, e.g. a panel
/// corner: this keeps precision for huge radii).
pub(crate) fn project_to_sphere(s: &Sphere, base: DVec3, x: DVec3) -> DVec3 {
    let g0 = 2.0 * s.a * base - s.b;
    let psi0 = s.eval(base);
    let mut y = x - base;
    for _ in 0..12 {
        let psi = s.a * y.length_squared() + g0.dot(y) + psi0;
        let g = 2.0 * s.a * y + g0;
        let gg = g.length_squared();
        if gg.is_nan() || gg <= 0.0 {
            break;
        }
        let step = (psi / gg) * g;
        y -= step;
        if step.length() <= 1e-16 * (1.0 + y.length()) {
            break;
        }
    }
    let p = base + y;
    if p.is_finite() {
        p
    } else {
        x
    }
}
