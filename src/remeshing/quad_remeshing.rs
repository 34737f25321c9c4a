//! Quad remeshing along a cross field on a B-spline patch (Sec. 5.2, 6.2: "we integrate [the
//! torsal field] to a quad mesh").
//!
//! The paper used Rhino plug-ins (libigl anisotropic remeshing, libQEx). Here the reference is one
//! patch f(u, v) over a rectangle and the cross field is known on a grid of that rectangle, so the
//! field is integrated in the parameter domain, on a fine triangulated grid of the domain extended
//! by a margin:
//!
//! 1. **The field** ([`CrossField`], [`super::cross_field`]): one cross per fine triangle, from
//!    the cells' crosses without combing. Its singular points and their indices are found; a
//!    cluster of them (a dome's umbilic turns the field by a full turn) becomes quarter-turn
//!    points, the only ones a quad mesh has ([`split_singularities`]).
//! 2. **Integration** ([`integrate`]): two scalar functions φ0, φ1, piecewise linear on the fine
//!    grid. φ0 is constant along family 1 and grows at unit 3D speed along family 0, and vice
//!    versa, in the least-squares sense per triangle: w_dir ⟨∇φ0, t1⟩ = 0 and ⟨∇φ0, t0⟩ = 1, with
//!    t_k the parameter vector of family k scaled to unit length in 3D. The direction rows weigh
//!    more, so the level sets follow the field and the spacing stays as even as the field allows.
//!    With singular points, the grid is cut from each to the border and the functions jump across
//!    the cuts by the seamless transitions of [`super::seamless`], with the singular points on
//!    lattice points (the integer step of MIQ).
//! 3. **Extraction** ([`quad_remesh`]): the vertices are the points where (φ0, φ1) hits the
//!    lattice (o0 + k h, o1 + l h), found per fine triangle by inverting the linear map; beside a
//!    cut they are also known by their index on the other side, so the cells across a cut close
//!    up (libQEx's idea, on a grid). Lattice points outside the patch are moved to where their
//!    iso-line meets the patch boundary (a root of the other φ along the boundary); the faces are
//!    the lattice cells whose four corners exist. Cells that come out degenerate (an edge < 0.15 h,
//!    area < 0.15 h², a fold or a corner angle over 170°) are dropped, so are slivers along the
//!    boundary (two corners on it, both edges inward from them < 0.3 h), and so is the smaller outer
//!    quad at a vertex with three that is not singular (no re-entrant corners in the outline), as
//!    long as that takes quads within one edge of the boundary; deeper, only boundary quads go. h
//!    is chosen for the target face count (with singular points: on the field as prepared, whose
//!    singular points stay) and, without singular points, the lattice offsets for the largest
//!    covered area.
//!
//! The result is quads only: valence 4 inside, 3 at a point of index +1/4 and 5 at −1/4
//! ([`QuadRemesh::singular`]).

// Negated float comparisons are deliberate: they also reject NaN.

use std::collections::{HashMap, HashSet};
use std::fmt;

use glam::{DVec2, DVec3};

use crate::geometry::bspline::{BSplineSurface, SurfaceDerivatives};
use crate::geometry::mesh::{Face, PolyMesh};
use crate::solver::{Linear, Problem, Solver, SolverOptions};

pub use super::cross_field::{split_singularities, Cross, CrossField, FineGrid, SingularPoint};
use super::seamless::{turn, Cuts};

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
    pub grid: FineGrid,
    /// Node indices of the domain's corners: [i0, i1] along u, [j0, j1] along v.
    pub inside: [[usize; 2]; 2],
    /// φ0 and φ1 per node (on a cut: its left copy).
    pub phi: [Vec<f64>; 2],
    /// Per triangle: (φ0, φ1) at its corners, with the transitions across the cuts.
    pub corners: Vec<[DVec2; 3]>,
    /// The singular points of the field that was integrated (quarter turns only).
    pub singular: Vec<SingularPoint>,
    /// The cuts through them (none without singular points).
    pub cuts: Cuts,
    /// Per cut: the lattice index of its singular point (φ(s) / h, integers).
    pub cone_keys: Vec<[i32; 2]>,
}

impl Integration {
    /// φ_k at (u, v), linear on the grid's triangles.
    pub fn value(&self, k: usize, p: DVec2) -> f64 {
        let g = &self.grid;
        let s = ((p.x - g.origin[0]) / g.step[0]).clamp(0.0, (g.nu - 1) as f64);
        let t = ((p.y - g.origin[1]) / g.step[1]).clamp(0.0, (g.nv - 1) as f64);
        let (i, j) = ((s.floor() as usize).min(g.nu - 2), (t.floor() as usize).min(g.nv - 2));
        let (fs, ft) = (s - i as f64, t - j as f64);
        let cell = 2 * (i + (g.nu - 1) * j);
        if fs + ft <= 1.0 {
            let c = self.corners[cell];
            c[0][k] + fs * (c[1][k] - c[0][k]) + ft * (c[2][k] - c[0][k])
        } else {
            // Corners (1, 1), (0, 1), (1, 0).
            let c = self.corners[cell + 1];
            c[0][k] + (1.0 - fs) * (c[1][k] - c[0][k]) + (1.0 - ft) * (c[2][k] - c[0][k])
        }
    }
}

/// The field on the fine grid (step 1 of the module docs): `cells` × `cells` cells over the
/// domain plus `margin` on every side, the surface's derivatives and the field's cross per
/// triangle, its singular points split into quarter turns for lattice spacing `spacing`
/// (singular points closer than `reach`, a 3D length, form one cluster).
#[derive(Clone, Debug)]
pub struct FieldGrid {
    pub grid: FineGrid,
    pub cells: usize,
    pub margin: usize,
    pub frames: Vec<SurfaceDerivatives>,
    pub crosses: Vec<Cross>,
    pub singular: Vec<SingularPoint>,
}

impl FieldGrid {
    pub fn new(surface: &BSplineSurface, field: &CrossField, cells: usize, margin: usize, spacing: f64, reach: f64) -> Self {
        let ((u0, u1), (v0, v1)) = surface.domain();
        let step = [(u1 - u0) / cells as f64, (v1 - v0) / cells as f64];
        let (nu, nv) = (cells + 2 * margin + 1, cells + 2 * margin + 1);
        let grid = FineGrid { nu, nv, origin: [u0 - margin as f64 * step[0], v0 - margin as f64 * step[1]], step };
        let centres: Vec<[f64; 2]> = (0..grid.triangle_count())
            .map(|t| {
                let c = grid.centroid(t);
                surface.clamp([c.x, c.y])
            })
            .collect();
        let frames: Vec<SurfaceDerivatives> = centres.iter().map(|c| surface.derivatives(c[0], c[1])).collect();
        let mut crosses: Vec<Cross> = centres.iter().map(|c| field.cross_at(c[0], c[1])).collect();
        let k = frames.len() as f64;
        let scale = DVec2::new(frames.iter().map(|d| d.su.length()).sum::<f64>() / k, frames.iter().map(|d| d.sv.length()).sum::<f64>() / k);
        let singular = split_singularities(&grid, &mut crosses, reach, spacing, scale);
        Self { grid, cells, margin, frames, crosses, singular }
    }
}

/// A remesh before its integration: the sizes for `params` and the field on the fine grid, whose
/// singular points tell what the remesh will place ([`prepare`]).
#[derive(Clone, Debug)]
pub struct Prepared {
    /// The patch's area (a 32 × 32 tessellation) and the first lattice spacing h.
    pub patch_area: f64,
    pub spacing: f64,
    pub field: FieldGrid,
}

/// The sizes of a remesh with `params` and the field on its fine grid (no solve).
pub fn prepare(surface: &BSplineSurface, field: &CrossField, params: &QuadRemeshParams) -> Result<Prepared, QuadRemeshError> {
    let target = params.target_faces;
    if !(4..=100_000).contains(&target) {
        return Err(QuadRemeshError::TargetFaces(target));
    }
    let (mesh, _) = surface.tessellate([32, 32]);
    let patch_area: f64 = (0..mesh.face_count()).map(|f| mesh.face_area_vector(f).length()).sum();
    let per_side = (target as f64).sqrt();
    let cells = ((params.resolution.max(2) as f64) * per_side).ceil() as usize;
    let margin = (cells as f64 * 2.5 / per_side).ceil() as usize + 2;
    let spacing = (patch_area / target as f64).sqrt();
    // Singular points within this distance of each other are one cluster (an umbilic's noise).
    let reach = 4.0 * spacing;
    Ok(Prepared { patch_area, spacing, field: FieldGrid::new(surface, field, cells, margin, spacing, reach) })
}

/// Integrates the field on its fine grid (step 2 of the module docs), with lattice spacing
/// `spacing` for the singular points.
pub fn integrate(fg: &FieldGrid, direction_weight: f64, spacing: f64) -> Result<Integration, QuadRemeshError> {
    let FieldGrid { grid, cells, margin, frames, crosses, singular } = fg;
    let (grid, cells, margin, singular) = (*grid, *cells, *margin, singular.clone());
    let (nu, nv) = (grid.nu, grid.nv);
    let n = grid.node_count();
    let nt = grid.triangle_count();
    let cuts = Cuts::new(&grid, crosses, &singular);
    // Two unknown vectors side by side: φ0 at [0, n), φ1 at [n, 2n).
    let var = |node: usize, k: usize| k * n + node;
    let mut rows = Linear::new();
    for (t, d) in frames.iter().enumerate() {
        let dirs = cuts.combed[t].directions().map(|t| {
            let len = (d.su * t.x + d.sv * t.y).length();
            if len > 0.0 {
                t / len
            } else {
                DVec2::ZERO
            }
        });
        // ∇φ on the triangle from its corners: φ = φ_a + (x − x_a)·∇φ.
        let c = grid.triangle(t);
        let p = c.map(|node| grid.uv(node));
        let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
        let det = e1.perp_dot(e2);
        // ∇φ = [(φ1 − φ0) e2⊥ − (φ2 − φ0) e1⊥] / det with e⊥ = (e.y, −e.x).
        let g1 = DVec2::new(e2.y, -e2.x) / det;
        let g2 = DVec2::new(-e1.y, e1.x) / det;
        for k in 0..2 {
            for (dir, w, target) in [(dirs[1 - k], direction_weight, 0.0), (dirs[k], 1.0, 1.0)] {
                // ⟨∇φ_k, dir⟩ = Σ corner coefficient · φ_k(corner).
                let coeff = [-(g1 + g2).dot(dir), g1.dot(dir), g2.dot(dir)];
                // Columns may repeat (a cut corner refers to its singular point): the solver sums them.
                let row: Vec<(usize, f64)> = c
                    .iter()
                    .enumerate()
                    .flat_map(|(corner, &node)| cuts.corner_terms(t, node, k).into_iter().map(move |(nd, j, a)| (var(nd, j), w * coeff[corner] * a)))
                    .collect();
                rows.push_row(&row, -w * target);
            }
        }
    }
    let mut problem = Problem::new(2 * n);
    problem.add_term(rows.with_name("cross_field_integration"), 1.0);
    let mid = grid.node(nu / 2, nv / 2);
    problem.fix(var(mid, 0));
    problem.fix(var(mid, 1));
    let mut x = vec![0.0; 2 * n];
    let mut solver = Solver::new(SolverOptions { max_iterations: 4, initial_epsilon: 1e-6, min_epsilon: 1e-9, ..SolverOptions::default() });
    solver.solve(&mut problem, &mut x, |_| Ok(()));
    // The integer step (greedy, as MIQ): the singular point nearest to a free lattice point is
    // fixed there and the rest solved again, until all are fixed.
    let mut keys: Vec<Option<[i32; 2]>> = vec![None; cuts.cuts.len()];
    let mut taken = HashSet::new();
    while keys.iter().any(Option::is_none) {
        let nearest = |c: usize| {
            let s = cuts.cuts[c].path[0];
            let p = DVec2::new(x[var(s, 0)], x[var(s, 1)]) / spacing;
            let base = p.round();
            (-1..=1)
                .flat_map(|a| (-1..=1).map(move |b| [base.x as i32 + a, base.y as i32 + b]))
                .filter(|k| !taken.contains(k))
                .map(|k| (p.distance(DVec2::new(k[0] as f64, k[1] as f64)), k))
                .min_by(|a, b| a.0.total_cmp(&b.0))
                .unwrap_or((f64::INFINITY, [base.x as i32, base.y as i32]))
        };
        let (c, (_, key)) = (0..keys.len()).filter(|&c| keys[c].is_none()).map(|c| (c, nearest(c))).min_by(|a, b| a.1 .0.total_cmp(&b.1 .0)).unwrap();
        taken.insert(key);
        keys[c] = Some(key);
        let s = cuts.cuts[c].path[0];
        for k in 0..2 {
            x[var(s, k)] = key[k] as f64 * spacing;
            problem.fix(var(s, k));
        }
        problem.unfix(var(mid, 0));
        problem.unfix(var(mid, 1));
        solver.solve(&mut problem, &mut x, |_| Ok(()));
    }
    let cone_keys: Vec<[i32; 2]> = keys.into_iter().map(Option::unwrap).collect();
    if x.iter().any(|v| !v.is_finite()) {
        return Err(QuadRemeshError::NotFinite);
    }
    let phi = [x[..n].to_vec(), x[n..].to_vec()];
    let at = |node: usize| DVec2::new(phi[0][node], phi[1][node]);
    let corners = (0..nt).map(|t| grid.triangle(t).map(|node| cuts.corner_value(t, node, at))).collect();
    Ok(Integration { grid, inside: [[margin, margin + cells], [margin, margin + cells]], phi, corners, singular, cuts, cone_keys })
}

/// The quad mesh of a remesh.
#[derive(Clone, Debug)]
pub struct QuadRemesh {
    /// Quads, counter-clockwise about f_u × f_v.
    pub mesh: PolyMesh,
    /// (u, v) of every vertex.
    pub uv: Vec<[f64; 2]>,
    /// The lattice polylines as triples (a, v, b) of consecutive vertices, straight on through v.
    pub polylines: Vec<[u32; 3]>,
    /// Vertices moved onto the patch boundary.
    pub on_boundary: Vec<bool>,
    /// The lattice spacing h (3D length) and the faces it gave.
    pub spacing: f64,
    /// Cells dropped as degenerate.
    pub dropped: usize,
    /// Fine triangles whose image is folded (0 when the integration follows the field).
    pub folded_triangles: usize,
    /// The singular vertices: (vertex, index in quarter turns), valence 4 − index.
    pub singular: Vec<(u32, i32)>,
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
    /// Per point: its parameters, its lattice coordinates (k, l) in the chart of the triangle it
    /// was found in, and that triangle.
    points: Vec<(DVec2, [i32; 2], usize)>,
    /// Per point and direction (+k, +l, −k, −l): the neighbouring lattice point and the quarter
    /// turns from this point's directions to the neighbour's (non-zero across a cut).
    next: Vec<[Option<(usize, i32)>; 4]>,
    folded: usize,
}

/// The unit step of direction d (0: +k, 1: +l, 2: −k, 3: −l).
fn step(d: i32) -> DVec2 {
    match d.rem_euclid(4) {
        0 => DVec2::X,
        1 => DVec2::Y,
        2 => -DVec2::X,
        _ => -DVec2::Y,
    }
}

/// The lattice points (o0 + k h, o1 + l h) of (φ0, φ1), per fine triangle, and their neighbours.
fn lattice_points(g: &Integration, h: f64, offset: [f64; 2]) -> Lattice {
    let mut points: Vec<(DVec2, [i32; 2], usize)> = Vec::new();
    let mut folded = 0;
    let mut by_position: HashMap<(i64, i64), usize> = HashMap::new();
    let mut in_triangle: Vec<Vec<usize>> = vec![Vec::new(); g.corners.len()];
    let quantum = 1e-9 * (g.grid.step[0] + g.grid.step[1]);
    let o = DVec2::from(offset);
    // Corners in lattice units.
    let corners: Vec<[DVec2; 3]> = g.corners.iter().map(|c| c.map(|p| (p - o) / h)).collect();
    for (t, ph) in corners.iter().enumerate() {
        let uv = g.grid.triangle(t).map(|node| g.grid.uv(node));
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
        for k in lo.x.ceil() as i32..=hi.x.floor() as i32 {
            for l in lo.y.ceil() as i32..=hi.y.floor() as i32 {
                let p = DVec2::new(k as f64, l as f64) - ph[0];
                let b1 = p.perp_dot(e2) / det;
                let b2 = e1.perp_dot(p) / det;
                let eps = -1e-12;
                if !(b1 >= eps && b2 >= eps && b1 + b2 <= 1.0 - eps) {
                    continue;
                }
                let x = uv[0] + b1 * (uv[1] - uv[0]) + b2 * (uv[2] - uv[0]);
                let cell = ((x.x / quantum).round() as i64, (x.y / quantum).round() as i64);
                by_position.entry(cell).or_insert_with(|| {
                    points.push((x, [k, l], t));
                    in_triangle[t].push(points.len() - 1);
                    points.len() - 1
                });
            }
        }
    }
    let mut next = vec![[None; 4]; points.len()];
    // Without cuts the chart is one and a lattice index names one point.
    if g.cuts.cuts.is_empty() {
        let index: HashMap<[i32; 2], usize> = points.iter().enumerate().map(|(id, p)| (p.1, id)).collect();
        for (id, p) in points.iter().enumerate() {
            for d in 0..4 {
                let e = step(d as i32);
                next[id][d] = index.get(&[p.1[0] + e.x as i32, p.1[1] + e.y as i32]).map(|&q| (q, 0));
            }
        }
        return Lattice { points, next, folded };
    }
    // Neighbours: a walk over the triangles near the segment to the neighbour's lattice point, in
    // this point's chart (across a cut, the transition x_from = M^σ (x_to − s) + s).
    let cones: Vec<DVec2> = g.cone_keys.iter().map(|k| DVec2::new(k[0] as f64, k[1] as f64)).collect();
    // Per triangle: the walk that last reached it and its chart there (ρ, shift).
    let mut stamp: Vec<u32> = vec![u32::MAX; corners.len()];
    let mut chart: Vec<(i32, DVec2)> = vec![(0, DVec2::ZERO); corners.len()];
    let mut walk = 0u32;
    let mut queue: Vec<usize> = Vec::new();
    for (id, &(_, key, start)) in points.iter().enumerate() {
        let here = DVec2::new(key[0] as f64, key[1] as f64);
        for d in 0..4 {
            let target = here + step(d);
            walk += 1;
            queue.clear();
            stamp[start] = walk;
            chart[start] = (0, DVec2::ZERO);
            queue.push(start);
            let mut head = 0;
            'walk: while head < queue.len() {
                let t = queue[head];
                head += 1;
                let (rho, shift) = chart[t];
                for &q in &in_triangle[t] {
                    let kq = points[q].1;
                    let x = turn(rho, DVec2::new(kq[0] as f64, kq[1] as f64)) + shift;
                    if q != id && x.distance(target) < 0.25 {
                        next[id][d as usize] = Some((q, rho));
                        break 'walk;
                    }
                }
                for &(s, _) in &g.cuts.adjacency[t] {
                    if stamp[s] == walk {
                        continue;
                    }
                    let (rho_s, shift_s) = match g.cuts.crossings.get(&(t, s)) {
                        None => (rho, shift),
                        Some(&(c, sigma)) => (rho + sigma, shift + turn(rho, cones[c] - turn(sigma, cones[c]))),
                    };
                    let near = corners[s].iter().any(|p| (turn(rho_s, *p) + shift_s).distance(target) <= 1.3);
                    if near {
                        stamp[s] = walk;
                        chart[s] = (rho_s, shift_s);
                        queue.push(s);
                    }
                }
            }
        }
    }
    Lattice { points, next, folded }
}

/// The point on side `side` of the rectangle near `x` where φ_k = value (linear search over the
/// fine grid nodes of that side, nearest root to `x`), or `x` when there is none within `reach`.
fn boundary_root(g: &Integration, rect: Rect, side: usize, k: usize, value: f64, x: DVec2, reach: f64) -> DVec2 {
    let along_u = side >= 2;
    let (count, step) = if along_u { (g.inside[0][1] - g.inside[0][0], g.grid.step[0]) } else { (g.inside[1][1] - g.inside[1][0], g.grid.step[1]) };
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

/// Which quads the outline's re-entrant corners may take ([`drop_reentrant_corners`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Outline {
    /// Any: the outline ends without re-entrant corners.
    AnyQuad,
    /// Only quads with a corner on the patch boundary: a notch at the boundary is not carried on
    /// into the patch, a column at a time.
    BoundaryQuads,
}

/// Re-entrant corners: at a vertex with three quads that do not close around it (a missing cell
/// beside it, not a singular vertex), the smaller of its two outer quads that `outline` allows
/// (`boundary`: the vertices on the patch boundary) is dropped. With `repeat`, until no such
/// corner is left (an outline without re-entrant corners, for a lattice that runs along the patch
/// boundary); otherwise once, so that a lattice running across the boundary does not lose its
/// outline cell by cell. Returns how many were dropped.
fn drop_reentrant_corners(faces: &mut Vec<Vec<u32>>, pts: &[DVec3], outline: Outline, boundary: &[bool], repeat: bool) -> usize {
    // The quads around each vertex, ascending; kept up to date as quads are dropped, so that a
    // repeated drop costs the quads it touches, not a new pass over the mesh.
    let mut incident: Vec<Vec<usize>> = vec![Vec::new(); pts.len()];
    for (f, ids) in faces.iter().enumerate() {
        for &v in ids {
            incident[v as usize].push(f);
        }
    }
    // The quad dropped at vertex v, if v is a re-entrant corner: three quads, of which the outer
    // two share an edge with one other quad only.
    let corner_quad = |faces: &[Vec<u32>], incident: &[Vec<usize>], v: usize| -> Option<usize> {
        let fs = &incident[v];
        if fs.len() != 3 {
            return None;
        }
        let shares = |a: usize, b: usize| faces[a].iter().filter(|x| faces[b].contains(x)).count() >= 2;
        fs.iter()
            .copied()
            .filter(|&a| fs.iter().filter(|&&b| b != a && shares(a, b)).count() == 1)
            .filter(|&a| outline == Outline::AnyQuad || faces[a].iter().any(|&x| boundary[x as usize]))
            .min_by(|&a, &b| quad_area(pts, &faces[a]).total_cmp(&quad_area(pts, &faces[b])))
    };
    if !repeat {
        let mut drop: Vec<usize> = (0..pts.len()).filter_map(|v| corner_quad(faces, &incident, v)).collect();
        drop.sort_unstable();
        drop.dedup();
        for &f in drop.iter().rev() {
            faces.remove(f);
        }
        return drop.len();
    }
    let mut dropped = 0;
    while let Some(f) = (0..pts.len()).find_map(|v| corner_quad(faces, &incident, v)) {
        for &v in &faces[f] {
            incident[v as usize].retain(|&g| g != f);
        }
        let last = faces.len() - 1;
        if f != last {
            for &v in &faces[last] {
                let fs = &mut incident[v as usize];
                fs.iter_mut().filter(|g| **g == last).for_each(|g| *g = f);
                fs.sort_unstable();
            }
        }
        faces.swap_remove(f);
        dropped += 1;
    }
    dropped
}

/// The vertices on the patch boundary (`boundary`) and those one edge of `faces` from it.
fn near_the_boundary(faces: &[Vec<u32>], boundary: &[bool]) -> Vec<bool> {
    let mut near = boundary.to_vec();
    for f in faces {
        for k in 0..f.len() {
            let (a, b) = (f[k] as usize, f[(k + 1) % f.len()] as usize);
            if boundary[a] || boundary[b] {
                near[a] = true;
                near[b] = true;
            }
        }
    }
    near
}

/// A candidate mesh at spacing h and offsets; `final_pass`: the mesh itself, with its outline's
/// re-entrant corners resolved (not only a count).
fn extract(surface: &BSplineSurface, g: &Integration, h: f64, offset: [f64; 2], final_pass: bool) -> Option<(QuadRemesh, f64)> {
    let ((u0, u1), (v0, v1)) = surface.domain();
    let rect = Rect { lo: DVec2::new(u0, v0), hi: DVec2::new(u1, v1) };
    let eps = DVec2::new(1e-12 * (u1 - u0), 1e-12 * (v1 - v0));
    let lattice = lattice_points(g, h, offset);
    let inside = |p: DVec2| rect.contains(p, eps);
    // Outside points with inside neighbours move to the boundary.
    let mut positions: Vec<Option<(DVec2, bool)>> = vec![None; lattice.points.len()];
    let reach = 4.0 * (g.grid.step[0].max(g.grid.step[1])) * 8.0;
    for (id, &(p, [k, l], _)) in lattice.points.iter().enumerate() {
        if inside(p) {
            positions[id] = Some((rect.clamp(p), false));
            continue;
        }
        let mut crossings = Vec::new();
        for d in 0..4 {
            let Some((q, _)) = lattice.next[id][d] else { continue };
            let q = lattice.points[q].0;
            if !inside(q) {
                continue;
            }
            let (x, side) = rect.exit(q, p);
            // Along a k-edge φ1 is constant (= its lattice value), along an l-edge φ0.
            let (fk, value) = if d % 2 == 0 { (1, offset[1] + l as f64 * h) } else { (0, offset[0] + k as f64 * h) };
            let root = boundary_root(g, rect, side, fk, value, x, reach);
            crossings.push((root, side));
        }
        match crossings.as_slice() {
            [] => {}
            [(x, _)] => positions[id] = Some((*x, true)),
            many => {
                let mean = many.iter().fold(DVec2::ZERO, |s, (x, _)| s + *x) / many.len() as f64;
                // The nearest boundary point of the mean.
                let to_side = [mean.x - u0, u1 - mean.x, mean.y - v0, v1 - mean.y];
                let (side, _) = to_side.iter().enumerate().fold((0, f64::INFINITY), |b, (s, &d)| {
                    let scaled = d / if s < 2 { u1 - u0 } else { v1 - v0 };
                    if scaled < b.1 {
                        (s, scaled)
                    } else {
                        b
                    }
                });
                let snapped = match side {
                    0 => DVec2::new(u0, mean.y),
                    1 => DVec2::new(u1, mean.y),
                    2 => DVec2::new(mean.x, v0),
                    _ => DVec2::new(mean.x, v1),
                };
                positions[id] = Some((rect.clamp(snapped), true));
            }
        }
    }
    let uv: Vec<[f64; 2]> = positions.iter().map(|p| p.map_or([0.0; 2], |(p, _)| [p.x, p.y])).collect();
    let pts: Vec<DVec3> = uv.iter().zip(&positions).map(|(w, p)| if p.is_some() { surface.point(w[0], w[1]) } else { DVec3::ZERO }).collect();
    let boundary: Vec<bool> = positions.iter().map(|p| p.is_some_and(|(_, b)| b)).collect();
    // The singular points' vertices: each cut's cone, where its node is.
    let cones: HashMap<usize, i32> = g
        .cuts
        .cuts
        .iter()
        .filter_map(|cut| {
            let at = g.grid.uv(cut.path[0]);
            let id = lattice.points.iter().position(|p| p.0.distance(at) < 1e-9 * (g.grid.step[0] + g.grid.step[1]))?;
            Some((id, g.singular.iter().find(|s| s.node == cut.path[0]).map_or(0, |s| s.quarters)))
        })
        .collect();
    // Faces: from every point in every direction, four steps turning left each time (in the
    // chart of the point reached), back to the start; at least one corner inside.
    let mut seen: HashSet<[u32; 4]> = HashSet::new();
    let mut faces = Vec::new();
    let mut dropped = 0;
    let mut area = 0.0;
    let min_edge = 0.15 * h;
    for start in 0..lattice.points.len() {
        if positions[start].is_none() {
            continue;
        }
        // Closed by the last corner's step, or (when the last corner is singular, whose steps miss
        // the directions beyond a quarter turn) by the start's own step back.
        'cell: for (d0, close_at_start) in (0..4i32).flat_map(|d| [(d, false), (d, true)]) {
            if close_at_start && cones.contains_key(&start) {
                continue;
            }
            let mut ids = vec![start as u32];
            let (mut at, mut d) = (start, d0);
            for corner in 0..3 {
                let Some((n, rho)) = lattice.next[at][d.rem_euclid(4) as usize] else { continue 'cell };
                if positions[n].is_none() || (close_at_start && corner < 2 && cones.contains_key(&n)) {
                    continue 'cell;
                }
                (at, d) = (n, d + rho + 1);
                ids.push(n as u32);
            }
            let closes = if close_at_start {
                lattice.next[start][(d0 + 1).rem_euclid(4) as usize].map(|(n, _)| n) == Some(at)
            } else {
                lattice.next[at][d.rem_euclid(4) as usize].map(|(n, _)| n) == Some(start)
            };
            if !closes {
                continue;
            }
            let mut sorted = [ids[0], ids[1], ids[2], ids[3]];
            sorted.sort_unstable();
            if sorted.windows(2).any(|w| w[0] == w[1]) || !seen.insert(sorted) {
                continue;
            }
            if ids.iter().all(|&i| boundary[i as usize]) {
                continue;
            }
            let p: Vec<DVec3> = ids.iter().map(|&i| pts[i as usize]).collect();
            let mid = uv[ids[0] as usize];
            let dv = surface.derivatives(mid[0], mid[1]);
            let normal = dv.su.cross(dv.sv).normalize_or_zero();
            let a = quad_area_vector(&pts, &ids);
            let short = (0..4).any(|c| p[c].distance(p[(c + 1) % 4]) < min_edge);
            // A sliver along the boundary: two corners on it, and both edges from them inward short.
            let on = |c: usize| boundary[ids[c % 4] as usize];
            let inward = (0..4).filter(|&c| on(c) != on(c + 1));
            let sliver = (0..4).filter(|&c| on(c)).count() == 2
                && inward.clone().count() == 2
                && inward.clone().all(|c| p[c].distance(p[(c + 1) % 4]) < BOUNDARY_SLIVER * h);
            // Corner angle over 170° or a corner turning the wrong way (both sides of the normal).
            let bad_corner = (0..4).any(|c| {
                let (prev, next) = (p[(c + 3) % 4] - p[c], p[(c + 1) % 4] - p[c]);
                let turn = next.cross(prev).dot(normal);
                prev.normalize_or_zero().dot(next.normalize_or_zero()) < (170f64).to_radians().cos() || turn.abs() < 1e-12 * h * h
            });
            let signed = a.dot(normal);
            if short || sliver || bad_corner || signed.abs() < 0.15 * h * h {
                dropped += 1;
                continue;
            }
            area += a.length();
            faces.push(ids);
        }
    }
    if final_pass {
        // An outline without re-entrant corners, unless reaching it drops a quad more than one
        // edge in from the boundary: then its notches ran on into the patch, and only quads on
        // the boundary go.
        let repeat = g.cuts.cuts.is_empty();
        let mut convex = faces.clone();
        let n = drop_reentrant_corners(&mut convex, &pts, Outline::AnyQuad, &boundary, repeat);
        let near = near_the_boundary(&faces, &boundary);
        let kept: HashSet<&Vec<u32>> = convex.iter().collect();
        if faces.iter().filter(|f| !kept.contains(f)).all(|f| f.iter().any(|&v| near[v as usize])) {
            faces = convex;
            dropped += n;
        } else {
            dropped += drop_reentrant_corners(&mut faces, &pts, Outline::BoundaryQuads, &boundary, repeat);
        }
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
    let mut out_b = Vec::new();
    let mut out_faces = Vec::new();
    let mut singular = Vec::new();
    for f in faces {
        let f: Vec<u32> = if positive { f } else { f.into_iter().rev().collect() };
        let ids: Vec<u32> = f
            .iter()
            .map(|&i| {
                if used[i as usize] == u32::MAX {
                    used[i as usize] = out_uv.len() as u32;
                    if let Some(&q) = cones.get(&(i as usize)) {
                        singular.push((out_uv.len() as u32, q));
                    }
                    out_uv.push(uv[i as usize]);
                    out_pts.push(pts[i as usize]);
                    out_b.push(boundary[i as usize]);
                }
                used[i as usize]
            })
            .collect();
        out_faces.push(Face::quad([ids[0], ids[1], ids[2], ids[3]]));
    }
    // Polylines: straight on through every regular vertex.
    let mut polylines = Vec::new();
    for (id, next) in lattice.next.iter().enumerate() {
        if used[id] == u32::MAX || cones.contains_key(&id) {
            continue;
        }
        for d in 0..2 {
            if let (Some((a, _)), Some((b, _))) = (next[d + 2], next[d]) {
                if used[a] != u32::MAX && used[b] != u32::MAX {
                    polylines.push([used[a], used[id], used[b]]);
                }
            }
        }
    }
    let remesh = QuadRemesh {
        mesh: PolyMesh::new(out_pts, out_faces),
        uv: out_uv,
        polylines,
        on_boundary: out_b,
        spacing: h,
        dropped,
        folded_triangles: lattice.folded,
        singular,
    };
    Some((remesh, area))
}

/// A cell with two corners on the patch boundary whose both edges inward from them are shorter
/// than this × h is a sliver and dropped: its panel's arcs would cross as soon as the vertices
/// glide, and the cells inside reach the boundary instead (h is a cell's side).
const BOUNDARY_SLIVER: f64 = 0.3;

/// Remeshes the patch along `field` (see the module docs) for about `params.target_faces` quads.
pub fn quad_remesh(surface: &BSplineSurface, field: &CrossField, params: &QuadRemeshParams) -> Result<QuadRemesh, QuadRemeshError> {
    quad_remesh_prepared(surface, prepare(surface, field, params)?, params)
}

/// [`quad_remesh`] from its [`prepare`]d field.
pub(crate) fn quad_remesh_prepared(surface: &BSplineSurface, prepared: Prepared, params: &QuadRemeshParams) -> Result<QuadRemesh, QuadRemeshError> {
    let target = params.target_faces;
    let Prepared { patch_area, spacing: mut h, field: fg } = prepared;
    let mut g = integrate(&fg, params.direction_weight, h)?;
    if !g.singular.is_empty() {
        // The singular points sit on the lattice of spacing h, offset 0: a few corrections of h
        // for the face count, then the mesh. The field and its singular points stay as
        // prepared; only their lattice points change with h.
        for _ in 0..3 {
            let count = extract(surface, &g, h, [0.0; 2], false).map_or(0, |(m, _)| m.mesh.face_count());
            if count == 0 || (count as f64 - target as f64).abs() <= 0.1 * target as f64 {
                break;
            }
            h *= (count as f64 / target as f64).sqrt();
            g = integrate(&fg, params.direction_weight, h)?;
        }
        return extract(surface, &g, h, [0.0; 2], true).map(|(m, _)| m).ok_or(QuadRemeshError::Empty);
    }
    let [i0, i1] = g.inside[0];
    let [j0, j1] = g.inside[1];
    let range = |k: usize| {
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for j in j0..=j1 {
            for i in i0..=i1 {
                let v = g.phi[k][g.grid.node(i, j)];
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
        (lo, hi)
    };
    let ranges = [range(0), range(1)];
    // h for the target count: faces ≈ covered area / h²; a few corrections, then the offsets.
    let centred = |h: f64, shift: [f64; 2]| [0, 1].map(|k| 0.5 * (ranges[k].0 + ranges[k].1) + shift[k] * h);
    for _ in 0..4 {
        let Some((m, _)) = extract(surface, &g, h, centred(h, [0.0, 0.0]), false) else { break };
        let faces = m.mesh.face_count() as f64;
        h *= (faces / target as f64).sqrt();
    }
    // Offsets: quarter steps, the largest covered area among face counts within 10 % of the best.
    let mut best: Option<(QuadRemesh, f64)> = None;
    for s0 in [0.0, 0.25, 0.5, 0.75] {
        for s1 in [0.0, 0.25, 0.5, 0.75] {
            let Some((m, area)) = extract(surface, &g, h, centred(h, [s0, s1]), true) else { continue };
            let score = area - 0.02 * patch_area * (m.mesh.face_count() as f64 - target as f64).abs() / target as f64;
            if best.as_ref().is_none_or(|b| score > b.1) {
                best = Some((m, score));
            }
        }
    }
    best.map(|b| b.0).ok_or(QuadRemeshError::Empty)
}

/// Cells per direction of the parameter grid [`coverage`] measures on.
const COVERAGE_CELLS: usize = 128;

/// The share of the patch's area that the faces cover: each cell of a
/// [`COVERAGE_CELLS`]² grid over the parameter domain, weighted by the surface's area element
/// |f_u × f_v| at its centre, counts when its centre lies in the (u, v) polygon of some face
/// (`uv` per vertex, the closest points). Faces that overlap or fold count their area once.
pub fn coverage(surface: &BSplineSurface, faces: &[crate::geometry::mesh::Face], uv: &[[f64; 2]]) -> f64 {
    let ((u0, u1), (v0, v1)) = surface.domain();
    let n = COVERAGE_CELLS;
    let (du, dv) = ((u1 - u0) / n as f64, (v1 - v0) / n as f64);
    if !(du > 0.0 && dv > 0.0) {
        return 0.0;
    }
    let centre = |i: usize, j: usize| [u0 + (i as f64 + 0.5) * du, v0 + (j as f64 + 0.5) * dv];
    let mut covered = vec![false; n * n];
    for face in faces {
        let poly: Vec<[f64; 2]> = face.corners().iter().map(|&c| uv[c as usize]).collect();
        let (lo, hi) = poly.iter().fold(([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]), |(lo, hi), p| {
            ([lo[0].min(p[0]), lo[1].min(p[1])], [hi[0].max(p[0]), hi[1].max(p[1])])
        });
        if !(lo[0].is_finite() && hi[0].is_finite() && lo[1].is_finite() && hi[1].is_finite()) {
            continue;
        }
        let cell = |x: f64, x0: f64, d: f64| (((x - x0) / d - 0.5).max(0.0) as usize).min(n - 1);
        for j in cell(lo[1], v0, dv)..=(cell(hi[1], v0, dv) + 1).min(n - 1) {
            for i in cell(lo[0], u0, du)..=(cell(hi[0], u0, du) + 1).min(n - 1) {
                if !covered[j * n + i] && inside(&poly, centre(i, j)) {
                    covered[j * n + i] = true;
                }
            }
        }
    }
    let (mut total, mut inside_area) = (0.0, 0.0);
    for j in 0..n {
        for i in 0..n {
            let [u, v] = centre(i, j);
            let d = surface.derivatives(u, v);
            let w = d.su.cross(d.sv).length();
            total += w;
            if covered[j * n + i] {
                inside_area += w;
            }
        }
    }
    if total > 0.0 {
        inside_area / total
    } else {
        0.0
    }
}

/// Whether `p` lies inside the polygon (even–odd rule).
fn inside(poly: &[[f64; 2]], p: [f64; 2]) -> bool {
    let mut odd = false;
    for k in 0..poly.len() {
        let (a, b) = (poly[k], poly[(k + 1) % poly.len()]);
        if (a[1] > p[1]) != (b[1] > p[1]) {
            let x = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
            if p[0] < x {
                odd = !odd;
            }
        }
    }
    odd
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A 6 × 5 grid of quads with a notch in its bottom row, whose quads are twice as tall as the
    /// rest: the outline loses boundary quads until no corner is re-entrant, and no quad off the
    /// boundary goes with them, although those are the smaller ones.
    #[test]
    fn a_notch_at_the_boundary_drops_boundary_quads_only() {
        let (nx, ny) = (6u32, 5u32);
        let id = |i: u32, j: u32| i + (nx + 1) * j;
        let pts: Vec<DVec3> =
            (0..=ny).flat_map(|j| (0..=nx).map(move |i| DVec3::new(i as f64, if j == 0 { 0.0 } else { 0.5 + 0.5 * j as f64 }, 0.0))).collect();
        let boundary: Vec<bool> = (0..=ny).flat_map(|j| (0..=nx).map(move |i| i == 0 || i == nx || j == 0 || j == ny)).collect();
        let mut faces: Vec<Vec<u32>> = (0..ny)
            .flat_map(|j| (0..nx).map(move |i| (i, j)))
            .filter(|&(i, j)| (i, j) != (3, 0))
            .map(|(i, j)| vec![id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)])
            .collect();
        let inner: Vec<Vec<u32>> = faces.iter().filter(|f| f.iter().all(|&v| !boundary[v as usize])).cloned().collect();
        let dropped = drop_reentrant_corners(&mut faces, &pts, Outline::BoundaryQuads, &boundary, true);
        assert!((1..=5).contains(&dropped), "{dropped} dropped");
        for f in &inner {
            assert!(faces.contains(f), "inner quad {f:?} dropped");
        }
        // No re-entrant corner is left.
        let mut count = HashMap::new();
        for f in &faces {
            for &v in f {
                *count.entry(v).or_insert(0) += 1;
            }
        }
        assert!(count.values().all(|&n| n != 3), "{count:?}");
    }
}
