//! Quad remeshing along a cross field on a B-spline patch (Sec. 5.2, 6.2: "we integrate [the
//! torsal field] to a quad mesh").
//!
//! The paper used Rhino plug-ins (libigl anisotropic remeshing, libQEx). Here the reference is one
//! patch f(u, v) over a rectangle and the cross field is known on a grid of that rectangle, so the
//! field is integrated directly in the parameter domain:
//!
//! 1. **Combing** ([`CrossField::comb`]): the two directions of every grid cell are labelled
//!    family 0 and 1 and given signs consistently, by a breadth-first walk that matches each cell
//!    to an already combed neighbour (in 3D, through f_u and f_v). Cells without directions take
//!    their neighbours' mean. [`CrossField::at`] interpolates bilinearly between cell centres.
//! 2. **Integration** ([`integrate`]): two scalar functions φ0, φ1, piecewise linear on a fine
//!    triangulated grid of the domain extended by a margin. φ0 is constant along family 1 and grows
//!    at unit 3D speed along family 0, and vice versa, in the least-squares sense per triangle:
//!    w_dir ⟨∇φ0, t1⟩ = 0 and ⟨∇φ0, t0⟩ = 1, with t_k the parameter vector of family k scaled to
//!    unit length in 3D. The direction rows weigh more, so the level sets follow the field and the
//!    spacing stays as even as the field allows. One sparse linear solve per function.
//! 3. **Extraction** ([`quad_remesh`]): the vertices are the points where (φ0, φ1) hits the
//!    lattice (o0 + k h, o1 + l h), found per fine triangle by inverting the linear map. Lattice
//!    points outside the patch are moved to where their iso-line meets the patch boundary (a root
//!    of the other φ along the boundary); the faces are the lattice cells whose four corners exist.
//!    Cells that come out degenerate (an edge < 0.15 h, area < 0.15 h², a fold or a corner angle
//!    over 170°) are dropped, and so is the smaller outer quad at a vertex with three (no
//!    re-entrant corners in the outline). h is chosen for the target face count and the lattice offsets for the
//!    largest covered area.
//!
//! **Why this route.** A stripe pattern (Knöppel et al. 2015) or a seamless parametrization with
//! quantization (Bommes et al., libQEx) handle singular cross fields on surfaces of any topology;
//! they need a global mixed-integer or eigenvalue solve, and a cut graph. Our field lives on one
//! disk-like patch and is the torsal field of a congruence with real torsal directions everywhere,
//! so it has no singularities and combs globally: two real-valued functions suffice, and their
//! lattice is a regular quad mesh by construction (every face a quad, no T-junctions, no folds as
//! long as the two families stay apart). The price is that a field with singularities cannot be
//! meshed this way; combing then leaves a seam, which the remesh reports as folded triangles.

// Negated float comparisons are deliberate: they also reject NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use std::collections::{HashMap, VecDeque};
use std::fmt;

use glam::{DVec2, DVec3};

use crate::geometry::bspline::BSplineSurface;
use crate::geometry::mesh::{Face, PolyMesh};
use crate::solver::{Linear, Problem, Solver, SolverOptions};

/// A cross field on an n × n grid of a rectangle: per cell (i + (n − 1) j) two parameter
/// directions, family 0 and family 1, combed (consistent labels and signs).
#[derive(Clone, Debug, PartialEq)]
pub struct CrossField {
    /// Points per direction of the grid.
    pub n: usize,
    pub domain: ((f64, f64), (f64, f64)),
    /// Per cell: the two directions (du, dv), any length.
    pub directions: Vec<[DVec2; 2]>,
    /// Cells that had no directions of their own (filled from their neighbours).
    pub filled: usize,
}

impl CrossField {
    /// Combs per-cell direction pairs (unordered, unsigned; None where a cell has none) on the
    /// surface `surface` (see the module docs). None when no cell has directions.
    pub fn comb(surface: &BSplineSurface, n: usize, raw: &[Option<[[f64; 2]; 2]>]) -> Option<Self> {
        let cells = n - 1;
        assert_eq!(raw.len(), cells * cells, "one entry per grid cell");
        let domain = surface.domain();
        let ((u0, u1), (v0, v1)) = domain;
        let centre = |q: usize| {
            let (i, j) = (q % cells, q / cells);
            (u0 + (i as f64 + 0.5) * (u1 - u0) / cells as f64, v0 + (j as f64 + 0.5) * (v1 - v0) / cells as f64)
        };
        let tangents: Vec<(DVec3, DVec3)> = (0..raw.len())
            .map(|q| {
                let (u, v) = centre(q);
                let d = surface.derivatives(u, v);
                (d.su, d.sv)
            })
            .collect();
        let in3d = |q: usize, d: DVec2| (tangents[q].0 * d.x + tangents[q].1 * d.y).normalize_or_zero();
        let start = {
            let mid = (cells / 2) + cells * (cells / 2);
            if raw[mid].is_some() { Some(mid) } else { raw.iter().position(Option::is_some) }
        }?;
        let mut out: Vec<Option<[DVec2; 2]>> = vec![None; raw.len()];
        // The start cell: family 0 is the one nearer f_u.
        let [a, b] = raw[start].unwrap().map(DVec2::from);
        let su = tangents[start].0.normalize_or_zero();
        let (a, b) = if in3d(start, a).dot(su).abs() >= in3d(start, b).dot(su).abs() { (a, b) } else { (b, a) };
        let a = if in3d(start, a).dot(su) < 0.0 { -a } else { a };
        let sv = tangents[start].1.normalize_or_zero();
        let b = if in3d(start, b).dot(sv) < 0.0 { -b } else { b };
        out[start] = Some([a, b]);
        let neighbours = |q: usize| {
            let (i, j) = (q % cells, q / cells);
            let mut v = Vec::with_capacity(4);
            if i > 0 {
                v.push(q - 1);
            }
            if i + 1 < cells {
                v.push(q + 1);
            }
            if j > 0 {
                v.push(q - cells);
            }
            if j + 1 < cells {
                v.push(q + cells);
            }
            v
        };
        // Breadth first over the cells with directions, then fill the others.
        let mut queue = VecDeque::from([start]);
        let mut seen = vec![false; raw.len()];
        seen[start] = true;
        while let Some(q) = queue.pop_front() {
            let [a0, b0] = out[q].unwrap();
            let (ta, tb) = (in3d(q, a0), in3d(q, b0));
            for r in neighbours(q) {
                if seen[r] {
                    continue;
                }
                let Some(pair) = raw[r] else { continue };
                seen[r] = true;
                let [x, y] = pair.map(DVec2::from);
                let (tx, ty) = (in3d(r, x), in3d(r, y));
                let (x, y, tx, ty) =
                    if tx.dot(ta).abs() + ty.dot(tb).abs() >= ty.dot(ta).abs() + tx.dot(tb).abs() { (x, y, tx, ty) } else { (y, x, ty, tx) };
                let x = if tx.dot(ta) < 0.0 { -x } else { x };
                let y = if ty.dot(tb) < 0.0 { -y } else { y };
                out[r] = Some([x, y]);
                queue.push_back(r);
            }
        }
        let mut filled = 0;
        loop {
            let missing: Vec<usize> = (0..raw.len()).filter(|&q| out[q].is_none()).collect();
            if missing.is_empty() {
                break;
            }
            let mut progress = false;
            for q in missing {
                let known: Vec<[DVec2; 2]> = neighbours(q).into_iter().filter_map(|r| out[r]).collect();
                if known.is_empty() {
                    continue;
                }
                let sum = known.iter().fold([DVec2::ZERO; 2], |s, k| [s[0] + k[0], s[1] + k[1]]);
                out[q] = Some(sum);
                filled += 1;
                progress = true;
            }
            if !progress {
                break;
            }
        }
        let directions = out.into_iter().map(|d| d.unwrap_or([DVec2::X, DVec2::Y])).collect();
        Some(Self { n, domain, directions, filled })
    }

    /// The two directions at (u, v), bilinear between cell centres (clamped to the domain).
    pub fn at(&self, u: f64, v: f64) -> [DVec2; 2] {
        let cells = self.n - 1;
        let ((u0, u1), (v0, v1)) = self.domain;
        let s = ((u - u0) / (u1 - u0) * cells as f64 - 0.5).clamp(0.0, (cells - 1) as f64);
        let t = ((v - v0) / (v1 - v0) * cells as f64 - 0.5).clamp(0.0, (cells - 1) as f64);
        let (i, j) = ((s.floor() as usize).min(cells.saturating_sub(2)), (t.floor() as usize).min(cells.saturating_sub(2)));
        if cells == 1 {
            return self.directions[0];
        }
        let (fs, ft) = (s - i as f64, t - j as f64);
        let d = |a: usize, b: usize| self.directions[(i + a) + cells * (j + b)];
        let mut out = [DVec2::ZERO; 2];
        for (k, o) in out.iter_mut().enumerate() {
            *o = (1.0 - fs) * (1.0 - ft) * d(0, 0)[k] + fs * (1.0 - ft) * d(1, 0)[k] + (1.0 - fs) * ft * d(0, 1)[k] + fs * ft * d(1, 1)[k];
        }
        out
    }

    /// The two directions at (u, v) as unit 3D tangent vectors of `surface`.
    pub fn at_3d(&self, surface: &BSplineSurface, u: f64, v: f64) -> [DVec3; 2] {
        let d = surface.derivatives(u, v);
        self.at(u, v).map(|t| (d.su * t.x + d.sv * t.y).normalize_or_zero())
    }
}

/// Settings of the remesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuadRemeshParams {
    /// Faces to aim at.
    pub target_faces: usize,
    /// Fine grid cells per lattice spacing.
    pub resolution: usize,
    /// Weight of the direction rows against the spacing rows.
    pub direction_weight: f64,
}

impl Default for QuadRemeshParams {
    fn default() -> Self {
        Self { target_faces: 237, resolution: 4, direction_weight: 10.0 }
    }
}

/// Why a remesh failed.
#[derive(Clone, Debug, PartialEq)]
pub enum QuadRemeshError {
    /// Fewer than 4 target faces, or more than 100 000.
    TargetFaces(usize),
    /// The integrated functions did not give a single face.
    Empty,
    /// The linear solve did not give finite values.
    NotFinite,
}

impl fmt::Display for QuadRemeshError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::TargetFaces(n) => write!(f, "{n} target faces is outside [4, 100000]"),
            Self::Empty => write!(f, "the torsal field integrates to no quad inside the patch: its two families run (nearly) parallel"),
            Self::NotFinite => write!(f, "integrating the torsal field gave non-finite values"),
        }
    }
}

impl std::error::Error for QuadRemeshError {}

/// The two functions of the integration on a fine grid over the extended domain.
#[derive(Clone, Debug)]
pub struct Integration {
    /// Nodes per direction; node (i, j) at i + nu j.
    pub nu: usize,
    pub nv: usize,
    /// Parameters of node (0, 0) and the spacing.
    pub origin: [f64; 2],
    pub step: [f64; 2],
    /// Node indices of the domain's corners: [i0, i1] along u, [j0, j1] along v.
    pub inside: [[usize; 2]; 2],
    /// φ0 and φ1 per node.
    pub phi: [Vec<f64>; 2],
}

impl Integration {
    fn uv(&self, i: usize, j: usize) -> DVec2 {
        DVec2::new(self.origin[0] + i as f64 * self.step[0], self.origin[1] + j as f64 * self.step[1])
    }

    /// φ_k at (u, v), linear on the grid's triangles.
    pub fn value(&self, k: usize, p: DVec2) -> f64 {
        let s = ((p.x - self.origin[0]) / self.step[0]).clamp(0.0, (self.nu - 1) as f64);
        let t = ((p.y - self.origin[1]) / self.step[1]).clamp(0.0, (self.nv - 1) as f64);
        let (i, j) = ((s.floor() as usize).min(self.nu - 2), (t.floor() as usize).min(self.nv - 2));
        let (fs, ft) = (s - i as f64, t - j as f64);
        let f = &self.phi[k];
        let at = |a: usize, b: usize| f[(i + a) + self.nu * (j + b)];
        if fs + ft <= 1.0 {
            at(0, 0) + fs * (at(1, 0) - at(0, 0)) + ft * (at(0, 1) - at(0, 0))
        } else {
            at(1, 1) + (1.0 - fs) * (at(0, 1) - at(1, 1)) + (1.0 - ft) * (at(1, 0) - at(1, 1))
        }
    }
}

/// Integrates the field (step 2 of the module docs) on a grid of `cells` × `cells` fine cells
/// over the domain plus `margin` cells on every side.
pub fn integrate(surface: &BSplineSurface, field: &CrossField, cells: usize, margin: usize, direction_weight: f64) -> Result<Integration, QuadRemeshError> {
    let ((u0, u1), (v0, v1)) = surface.domain();
    let step = [(u1 - u0) / cells as f64, (v1 - v0) / cells as f64];
    let (nu, nv) = (cells + 2 * margin + 1, cells + 2 * margin + 1);
    let origin = [u0 - margin as f64 * step[0], v0 - margin as f64 * step[1]];
    let node = |i: usize, j: usize| i + nu * j;
    let n = nu * nv;
    // Two unknown vectors side by side: φ0 at [0, n), φ1 at [n, 2n).
    let mut rows = Linear::new();
    for j in 0..nv - 1 {
        for i in 0..nu - 1 {
            let centre = [origin[0] + (i as f64 + 0.5) * step[0], origin[1] + (j as f64 + 0.5) * step[1]];
            let c = surface.clamp(centre);
            let d = surface.derivatives(c[0], c[1]);
            let t = field.at(c[0], c[1]).map(|t| {
                let len = (d.su * t.x + d.sv * t.y).length();
                if len > 0.0 { t / len } else { DVec2::ZERO }
            });
            // Two triangles: (00, 10, 01) with ∇φ = ((φ10 − φ00)/Δu, (φ01 − φ00)/Δv), and
            // (11, 01, 10) with ∇φ = ((φ11 − φ01)/Δu, (φ11 − φ10)/Δv).
            let tris = [
                [(node(i + 1, j), node(i, j)), (node(i, j + 1), node(i, j))],
                [(node(i + 1, j + 1), node(i, j + 1)), (node(i + 1, j + 1), node(i + 1, j))],
            ];
            for [(ua, ub), (va, vb)] in tris {
                for k in 0..2 {
                    let off = k * n;
                    // ⟨∇φ_k, t⟩ as a linear row: (φ[ua] − φ[ub]) t.x/Δu + (φ[va] − φ[vb]) t.y/Δv.
                    let row = |t: DVec2, w: f64| {
                        let (a, b) = (w * t.x / step[0], w * t.y / step[1]);
                        [(off + ua, a), (off + ub, -a), (off + va, b), (off + vb, -b)]
                    };
                    rows.push_row(&row(t[1 - k], direction_weight), 0.0);
                    rows.push_row(&row(t[k], 1.0), -1.0);
                }
            }
        }
    }
    let mut problem = Problem::new(2 * n);
    problem.add_term(rows.with_name("cross_field_integration"), 1.0);
    let mid = node(nu / 2, nv / 2);
    problem.fix(mid);
    problem.fix(n + mid);
    let mut x = vec![0.0; 2 * n];
    let mut solver = Solver::new(SolverOptions { max_iterations: 4, initial_epsilon: 1e-6, min_epsilon: 1e-9, ..SolverOptions::default() });
    solver.solve(&mut problem, &mut x, |_| true);
    if x.iter().any(|v| !v.is_finite()) {
        return Err(QuadRemeshError::NotFinite);
    }
    let phi = [x[..n].to_vec(), x[n..].to_vec()];
    Ok(Integration { nu, nv, origin, step, inside: [[margin, margin + cells], [margin, margin + cells]], phi })
}

/// The quad mesh of a remesh.
#[derive(Clone, Debug)]
pub struct QuadRemesh {
    /// Quads, counter-clockwise about f_u × f_v.
    pub mesh: PolyMesh,
    /// (u, v) of every vertex.
    pub uv: Vec<[f64; 2]>,
    /// The lattice index (k, l) of every vertex.
    pub lattice: Vec<[i32; 2]>,
    /// Vertices moved onto the patch boundary.
    pub on_boundary: Vec<bool>,
    /// The lattice spacing h (3D length) and the faces it gave.
    pub spacing: f64,
    /// Cells dropped as degenerate.
    pub dropped: usize,
    /// Fine triangles whose image is folded (0 for a combable field).
    pub folded_triangles: usize,
}

/// Where the patch boundary is: the domain rectangle.
#[derive(Clone, Copy)]
struct Rect {
    lo: DVec2,
    hi: DVec2,
}

impl Rect {
    fn contains(&self, p: DVec2, eps: DVec2) -> bool {
        p.x >= self.lo.x - eps.x && p.x <= self.hi.x + eps.x && p.y >= self.lo.y - eps.y && p.y <= self.hi.y + eps.y
    }

    /// Where the segment a (inside) → b (outside) leaves the rectangle, and which side
    /// (0: u = lo, 1: u = hi, 2: v = lo, 3: v = hi).
    fn exit(&self, a: DVec2, b: DVec2) -> (DVec2, usize) {
        let d = b - a;
        let mut best = (1.0, 0);
        for (side, (val, comp)) in [(self.lo.x, 0), (self.hi.x, 0), (self.lo.y, 1), (self.hi.y, 1)].into_iter().enumerate() {
            let dc = if comp == 0 { d.x } else { d.y };
            let ac = if comp == 0 { a.x } else { a.y };
            if dc.abs() > 0.0 {
                let t = (val - ac) / dc;
                if (0.0..best.0).contains(&t) {
                    best = (t, side);
                }
            }
        }
        (self.clamp(a + best.0 * d), best.1)
    }

    fn clamp(&self, p: DVec2) -> DVec2 {
        p.clamp(self.lo, self.hi)
    }
}

/// The lattice's vertices before the faces are chosen.
struct Lattice {
    points: HashMap<(i32, i32), DVec2>,
    folded: usize,
}

/// The lattice points (o0 + k h, o1 + l h) of (φ0, φ1), per fine triangle.
fn lattice_points(g: &Integration, h: f64, offset: [f64; 2]) -> Lattice {
    let mut points = HashMap::new();
    let mut folded = 0;
    let node = |i: usize, j: usize| i + g.nu * j;
    for j in 0..g.nv - 1 {
        for i in 0..g.nu - 1 {
            for tri in [[(i, j), (i + 1, j), (i, j + 1)], [(i + 1, j + 1), (i, j + 1), (i + 1, j)]] {
                let uv = tri.map(|(a, b)| g.uv(a, b));
                let ph = tri.map(|(a, b)| DVec2::new(g.phi[0][node(a, b)], g.phi[1][node(a, b)]));
                let (e1, e2) = (ph[1] - ph[0], ph[2] - ph[0]);
                let det = e1.perp_dot(e2);
                if det == 0.0 || !det.is_finite() {
                    continue;
                }
                let orient = (uv[1] - uv[0]).perp_dot(uv[2] - uv[0]);
                if det * orient < 0.0 {
                    folded += 1;
                }
                let lo = ph[0].min(ph[1]).min(ph[2]);
                let hi = ph[0].max(ph[1]).max(ph[2]);
                let k0 = ((lo.x - offset[0]) / h).ceil() as i32;
                let k1 = ((hi.x - offset[0]) / h).floor() as i32;
                let l0 = ((lo.y - offset[1]) / h).ceil() as i32;
                let l1 = ((hi.y - offset[1]) / h).floor() as i32;
                for k in k0..=k1 {
                    for l in l0..=l1 {
                        if points.contains_key(&(k, l)) {
                            continue;
                        }
                        let p = DVec2::new(offset[0] + k as f64 * h, offset[1] + l as f64 * h) - ph[0];
                        let b1 = p.perp_dot(e2) / det;
                        let b2 = e1.perp_dot(p) / det;
                        let eps = -1e-12;
                        if b1 >= eps && b2 >= eps && b1 + b2 <= 1.0 - eps {
                            points.insert((k, l), uv[0] + b1 * (uv[1] - uv[0]) + b2 * (uv[2] - uv[0]));
                        }
                    }
                }
            }
        }
    }
    Lattice { points, folded }
}

/// The point on side `side` of the rectangle near `x` where φ_k = value (linear search over the
/// fine grid nodes of that side, nearest root to `x`), or `x` when there is none within `reach`.
fn boundary_root(g: &Integration, rect: Rect, side: usize, k: usize, value: f64, x: DVec2, reach: f64) -> DVec2 {
    let along_u = side >= 2;
    let (count, step) = if along_u { (g.inside[0][1] - g.inside[0][0], g.step[0]) } else { (g.inside[1][1] - g.inside[1][0], g.step[1]) };
    let point = |m: usize| -> DVec2 {
        let t = m as f64 * step;
        match side {
            0 => DVec2::new(rect.lo.x, rect.lo.y + t),
            1 => DVec2::new(rect.hi.x, rect.lo.y + t),
            2 => DVec2::new(rect.lo.x + t, rect.lo.y),
            _ => DVec2::new(rect.lo.x + t, rect.hi.y),
        }
    };
    let mut best: Option<(f64, DVec2)> = None;
    let mut prev = (point(0), g.value(k, point(0)) - value);
    for m in 1..=count {
        let p = point(m);
        let f = g.value(k, p) - value;
        if prev.1 == 0.0 || prev.1 * f < 0.0 {
            let t = if prev.1 == f { 0.0 } else { prev.1 / (prev.1 - f) };
            let root = prev.0 + t * (p - prev.0);
            let d = root.distance(x);
            if best.is_none_or(|(bd, _)| d < bd) {
                best = Some((d, root));
            }
        }
        prev = (p, f);
    }
    match best {
        Some((d, root)) if d <= reach => root,
        _ => x,
    }
}

/// Area of the quad `f` over `pts`: half the cross product of its diagonals.
fn quad_area(pts: &[DVec3], f: &[u32]) -> f64 {
    quad_area_vector(pts, f).length()
}

fn quad_area_vector(pts: &[DVec3], f: &[u32]) -> DVec3 {
    let p = |k: usize| pts[f[k] as usize];
    0.5 * (p(2) - p(0)).cross(p(3) - p(1))
}

/// No re-entrant corners: a vertex with three quads (a dropped cell beside it) loses the smaller
/// of its two outer quads, until none is left. Returns how many were dropped.
fn drop_reentrant_corners(faces: &mut Vec<Vec<u32>>, pts: &[DVec3]) -> usize {
    let mut dropped = 0;
    loop {
        let mut incident: HashMap<u32, Vec<usize>> = HashMap::new();
        for (f, ids) in faces.iter().enumerate() {
            for &v in ids {
                incident.entry(v).or_default().push(f);
            }
        }
        let mut keys: Vec<u32> = incident.iter().filter(|(_, fs)| fs.len() == 3).map(|(v, _)| *v).collect();
        keys.sort_unstable();
        let shares = |a: usize, b: usize| faces[a].iter().filter(|x| faces[b].contains(x)).count() >= 2;
        // The outer two of the three share an edge with one other quad only.
        let drop: Vec<usize> = keys
            .iter()
            .filter_map(|v| {
                let fs = &incident[v];
                let outer = fs.iter().copied().filter(|&a| fs.iter().filter(|&&b| b != a && shares(a, b)).count() == 1);
                outer.min_by(|&a, &b| quad_area(pts, &faces[a]).total_cmp(&quad_area(pts, &faces[b])))
            })
            .collect();
        let Some(&f) = drop.first() else { break };
        faces.swap_remove(f);
        dropped += 1;
    }
    dropped
}

/// A candidate mesh at spacing h and offsets.
fn extract(surface: &BSplineSurface, g: &Integration, h: f64, offset: [f64; 2], final_pass: bool) -> Option<(QuadRemesh, f64)> {
    let ((u0, u1), (v0, v1)) = surface.domain();
    let rect = Rect { lo: DVec2::new(u0, v0), hi: DVec2::new(u1, v1) };
    let eps = DVec2::new(1e-12 * (u1 - u0), 1e-12 * (v1 - v0));
    let lattice = lattice_points(g, h, offset);
    let inside = |p: DVec2| rect.contains(p, eps);
    // Outside points with inside neighbours move to the boundary.
    let mut positions: HashMap<(i32, i32), (DVec2, bool)> = HashMap::new();
    let reach = 4.0 * (g.step[0].max(g.step[1])) * 8.0;
    for (&(k, l), &p) in &lattice.points {
        if inside(p) {
            positions.insert((k, l), (rect.clamp(p), false));
            continue;
        }
        let mut crossings = Vec::new();
        for (dk, dl) in [(1, 0), (-1, 0), (0, 1), (0, -1)] {
            let Some(&q) = lattice.points.get(&(k + dk, l + dl)) else { continue };
            if !inside(q) {
                continue;
            }
            let (x, side) = rect.exit(q, p);
            // Along a k-edge φ1 is constant (= its lattice value), along an l-edge φ0.
            let (fk, value) = if dk != 0 { (1, offset[1] + l as f64 * h) } else { (0, offset[0] + k as f64 * h) };
            let root = boundary_root(g, rect, side, fk, value, x, reach);
            crossings.push((root, side));
        }
        match crossings.as_slice() {
            [] => {}
            [(x, _)] => {
                positions.insert((k, l), (*x, true));
            }
            many => {
                let mean = many.iter().fold(DVec2::ZERO, |s, (x, _)| s + *x) / many.len() as f64;
                // The nearest boundary point of the mean.
                let to_side = [mean.x - u0, u1 - mean.x, mean.y - v0, v1 - mean.y];
                let (side, _) = to_side.iter().enumerate().fold((0, f64::INFINITY), |b, (s, &d)| {
                    let scaled = d / if s < 2 { u1 - u0 } else { v1 - v0 };
                    if scaled < b.1 { (s, scaled) } else { b }
                });
                let snapped = match side {
                    0 => DVec2::new(u0, mean.y),
                    1 => DVec2::new(u1, mean.y),
                    2 => DVec2::new(mean.x, v0),
                    _ => DVec2::new(mean.x, v1),
                };
                positions.insert((k, l), (rect.clamp(snapped), true));
            }
        }
    }
    // Faces: lattice cells with four corners, at least one of them inside.
    let mut keys: Vec<(i32, i32)> = positions.keys().copied().collect();
    keys.sort_unstable();
    let mut index: HashMap<(i32, i32), u32> = HashMap::new();
    let mut uv = Vec::new();
    let mut pts = Vec::new();
    let mut lattice_ids = Vec::new();
    let mut boundary = Vec::new();
    for key in &keys {
        let (p, b) = positions[key];
        index.insert(*key, uv.len() as u32);
        uv.push([p.x, p.y]);
        pts.push(surface.point(p.x, p.y));
        lattice_ids.push([key.0, key.1]);
        boundary.push(b);
    }
    let mut faces = Vec::new();
    let mut dropped = 0;
    let mut area = 0.0;
    let min_edge = 0.15 * h;
    for &(k, l) in &keys {
        let corners = [(k, l), (k + 1, l), (k + 1, l + 1), (k, l + 1)];
        let Some(ids) = corners.iter().map(|c| index.get(c).copied()).collect::<Option<Vec<u32>>>() else { continue };
        if ids.iter().all(|&i| boundary[i as usize]) {
            continue;
        }
        let p: Vec<DVec3> = ids.iter().map(|&i| pts[i as usize]).collect();
        let mid = uv[ids[0] as usize];
        let d = surface.derivatives(mid[0], mid[1]);
        let normal = d.su.cross(d.sv).normalize_or_zero();
        let a = quad_area_vector(&pts, &ids);
        let short = (0..4).any(|c| p[c].distance(p[(c + 1) % 4]) < min_edge);
        // Corner angle over 170° or a corner turning the wrong way (both sides of the normal).
        let bad_corner = (0..4).any(|c| {
            let (prev, next) = (p[(c + 3) % 4] - p[c], p[(c + 1) % 4] - p[c]);
            let turn = next.cross(prev).dot(normal);
            prev.normalize_or_zero().dot(next.normalize_or_zero()) < (170f64).to_radians().cos() || turn.abs() < 1e-12 * h * h
        });
        let signed = a.dot(normal);
        if short || bad_corner || signed.abs() < 0.15 * h * h {
            dropped += 1;
            continue;
        }
        area += a.length();
        faces.push(ids);
    }
    if final_pass {
        dropped += drop_reentrant_corners(&mut faces, &pts);
        area = faces.iter().map(|f| quad_area(&pts, f)).sum();
    }
    if faces.is_empty() {
        return None;
    }
    // Orientation: counter-clockwise about f_u × f_v (the lattice cells all turn the same way).
    let turn = faces.iter().map(|f| {
        let c = uv[f[0] as usize];
        let d = surface.derivatives(c[0], c[1]);
        quad_area_vector(&pts, f).dot(d.su.cross(d.sv)).signum()
    });
    let positive = turn.sum::<f64>() >= 0.0;
    let mut used = vec![u32::MAX; uv.len()];
    let mut out_uv = Vec::new();
    let mut out_pts = Vec::new();
    let mut out_lat = Vec::new();
    let mut out_b = Vec::new();
    let mut out_faces = Vec::new();
    for f in faces {
        let f: Vec<u32> = if positive { f } else { f.into_iter().rev().collect() };
        let ids: Vec<u32> = f
            .iter()
            .map(|&i| {
                if used[i as usize] == u32::MAX {
                    used[i as usize] = out_uv.len() as u32;
                    out_uv.push(uv[i as usize]);
                    out_pts.push(pts[i as usize]);
                    out_lat.push(lattice_ids[i as usize]);
                    out_b.push(boundary[i as usize]);
                }
                used[i as usize]
            })
            .collect();
        out_faces.push(Face::quad([ids[0], ids[1], ids[2], ids[3]]));
    }
    let remesh = QuadRemesh {
        mesh: PolyMesh::new(out_pts, out_faces),
        uv: out_uv,
        lattice: out_lat,
        on_boundary: out_b,
        spacing: h,
        dropped,
        folded_triangles: lattice.folded,
    };
    Some((remesh, area))
}

/// Remeshes the patch along `field` (see the module docs) for about `params.target_faces` quads.
pub fn quad_remesh(surface: &BSplineSurface, field: &CrossField, params: &QuadRemeshParams) -> Result<QuadRemesh, QuadRemeshError> {
    let target = params.target_faces;
    if !(4..=100_000).contains(&target) {
        return Err(QuadRemeshError::TargetFaces(target));
    }
    let (mesh, _) = surface.tessellate([32, 32]);
    let patch_area: f64 = (0..mesh.face_count()).map(|f| mesh.face_area_vector(f).length()).sum();
    let per_side = (target as f64).sqrt();
    let cells = ((params.resolution.max(2) as f64) * per_side).ceil() as usize;
    let margin = (cells as f64 * 2.5 / per_side).ceil() as usize + 2;
    let g = integrate(surface, field, cells, margin, params.direction_weight)?;
    let [i0, i1] = g.inside[0];
    let [j0, j1] = g.inside[1];
    let range = |k: usize| {
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for j in j0..=j1 {
            for i in i0..=i1 {
                let v = g.phi[k][i + g.nu * j];
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
        (lo, hi)
    };
    let ranges = [range(0), range(1)];
    // h for the target count: faces ≈ covered area / h²; a few corrections, then the offsets.
    let mut h = (patch_area / target as f64).sqrt();
    let centred = |h: f64, shift: [f64; 2]| [0, 1].map(|k| 0.5 * (ranges[k].0 + ranges[k].1) + shift[k] * h);
    for _ in 0..4 {
        let Some((m, _)) = extract(surface, &g, h, centred(h, [0.0, 0.0]), false) else { break };
        let faces = m.mesh.face_count() as f64;
        h *= (faces / target as f64).sqrt();
    }
    // Offsets: quarter steps, the largest covered area among face counts within 10 % of the best.
    let mut best: Option<([f64; 2], f64)> = None;
    for s0 in [0.0, 0.25, 0.5, 0.75] {
        for s1 in [0.0, 0.25, 0.5, 0.75] {
            let Some((m, area)) = extract(surface, &g, h, centred(h, [s0, s1]), true) else { continue };
            let score = area - 0.02 * patch_area * (m.mesh.face_count() as f64 - target as f64).abs() / target as f64;
            if best.is_none_or(|(_, b)| score > b) {
                best = Some(([s0, s1], score));
            }
        }
    }
    let (shift, _) = best.ok_or(QuadRemeshError::Empty)?;
    extract(surface, &g, h, centred(h, shift), true).map(|(m, _)| m).ok_or(QuadRemeshError::Empty)
}

/// The area of the patch covered by the mesh (sum of the quads' triangle areas) over the patch's
/// area (a 64 × 64 tessellation).
pub fn coverage(surface: &BSplineSurface, mesh: &PolyMesh) -> f64 {
    let (reference, _) = surface.tessellate([64, 64]);
    let total: f64 = (0..reference.face_count()).map(|f| reference.face_area_vector(f).length()).sum();
    let covered: f64 = (0..mesh.face_count()).map(|f| mesh.face_area_vector(f).length()).sum();
    covered / total
}

/// Per edge of `mesh` (vertex parameters `uv`) that does not run along the patch boundary (not
/// both ends `on_boundary`): the angle (degrees) at its midpoint between the edge and the nearer
/// of the field's two directions, both in the tangent plane there.
pub fn edge_field_angles(surface: &BSplineSurface, field: &CrossField, mesh: &PolyMesh, uv: &[[f64; 2]], on_boundary: &[bool]) -> Vec<f64> {
    let topo = crate::geometry::mesh::topology::Topology::new(mesh);
    topo.edges()
        .iter()
        .filter(|[a, b]| !(on_boundary[*a as usize] && on_boundary[*b as usize]))
        .map(|&[a, b]| {
            let (pa, pb) = (uv[a as usize], uv[b as usize]);
            let mid = surface.clamp([0.5 * (pa[0] + pb[0]), 0.5 * (pa[1] + pb[1])]);
            let d = surface.derivatives(mid[0], mid[1]);
            let n = d.su.cross(d.sv).normalize_or_zero();
            let e = mesh.positions[b as usize] - mesh.positions[a as usize];
            let e = (e - e.dot(n) * n).normalize_or_zero();
            field
                .at_3d(surface, mid[0], mid[1])
                .iter()
                .map(|t| {
                    let t = (*t - t.dot(n) * n).normalize_or_zero();
                    e.dot(t).abs().min(1.0).acos().to_degrees()
                })
                .fold(f64::INFINITY, f64::min)
        })
        .collect()
}
