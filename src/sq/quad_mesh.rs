//! Sec. 5.2, first part: the quad mesh along the torsal cross field, and Q′.
//!
//! 1. The torsal directions of the optimized congruence (per quad of G, in parameters) are combed
//!    into a cross field and integrated to a quad mesh with about N faces
//!    ([`crate::remeshing::quad_remeshing`]).
//! 2. **Q′**: the zigzag is removed by letting the mesh glide over the reference while its
//!    polylines are faired (second differences, Tang et al. 2014): the glide terms of
//!    [`crate::reference::proximity`] (tangent distance and ε times point distance), the fairness
//!    and E_reg, in the frame of the bounding box. Vertices on the patch boundary stay where the
//!    remesh put them (on the boundary curve).
//! 3. Each vertex's (u, v) is its closest point on the reference.
//!
//! A torsal field with singular points (an umbilic, where the directions turn about a point, as on
//! a paraboloid of revolution) needs singular vertices there: valence 3 at a quarter turn, 5 at
//! minus one ([`crate::remeshing::seamless`]). At such a vertex the support planes cannot meet at
//! more than 60° (three) or 72° (five), and the final optimization does not yet reach its
//! guarantees from such a mesh, so the remesh then follows the parameter lines, and the result
//! says so in a warning with the singular points it found.

use std::collections::HashSet;

use glam::DVec3;

use crate::geometry::bspline::BSplineSurface;
use crate::geometry::mesh::PolyMesh;
use crate::progress::{Cancelled, Clock};
use crate::reference::assumptions::Warning;
use crate::reference::proximity::ReferenceProximity;
use crate::reference::Reference;
use crate::remeshing::quad_remeshing::{
    coverage, edge_field_angles, prepare, quad_remesh, quad_remesh_prepared, CrossField, QuadRemesh, QuadRemeshParams, SingularPoint,
};
use crate::solver::{Linear, Problem, Proximal, Solver, SolverOptions, TermStats, Termination};

use super::error::SqError;
use super::params::SqParams;
use super::sphere_terms::support_plane_bound_deg;

/// The quad mesh of Sec. 5.2 before the final optimization (model units).
#[derive(Clone, Debug)]
pub struct SqQuadMesh {
    /// The combed torsal field.
    pub torsal: CrossField,
    /// The singular points of the torsal field (on the remesh's fine grid, index in quarter
    /// turns); with any, the mesh follows the parameter lines ([`SqQuadMesh::parameter_lines`]).
    pub singular_points: Vec<SingularPoint>,
    /// The singular vertices of the mesh: (vertex, index in quarter turns), valence 4 − index.
    pub singular: Vec<(u32, i32)>,
    /// Fine triangles the integration folded (0 when the mesh follows the field).
    pub folded_triangles: usize,
    /// The mesh as extracted, and Q′.
    pub remesh: PolyMesh,
    pub mesh: PolyMesh,
    /// (u, v) of Q′'s vertices (closest points).
    pub uv: Vec<[f64; 2]>,
    /// The lattice polylines as triples (a, v, b), straight on through v.
    pub polylines: Vec<[u32; 3]>,
    pub on_boundary: Vec<bool>,
    /// Covered share of the patch's area.
    pub coverage: f64,
    /// Cells dropped as degenerate by the remesh.
    pub dropped: usize,
    /// Angles (deg) between the edges of the remesh and of Q′ and the torsal directions.
    pub remesh_edge_angles_deg: Vec<f64>,
    pub edge_angles_deg: Vec<f64>,
    pub fairing_iterations: usize,
    pub warnings: Vec<Warning>,
}

impl SqQuadMesh {
    /// Whether the mesh follows the parameter lines: the torsal field has singular points.
    pub fn parameter_lines(&self) -> bool {
        !self.singular_points.is_empty()
    }
}

/// A patch over a domain rescaled so that both parameters run at the same mean speed in space
/// ([`BSplineSurface::isotropic_scale`]): the cross field measures its angles, its singular
/// points and the turns across its cuts in the parameter plane, and on a patch whose parameters
/// run at speeds 10 : 1 (a knot vector over [0, 13] against [0, 1]) the two torsal directions
/// there lie a few degrees apart: a dome with two umbilics showed one singular point and a
/// seamless map that collapsed over half the patch (Sec. 5.2).
pub struct IsotropicPatch {
    pub surface: BSplineSurface,
    /// Per parameter, its speed relative to the given patch's ([`BSplineSurface::rescaled`]).
    pub scale: [f64; 2],
}

impl IsotropicPatch {
    /// The patch `given` at one speed.
    pub fn of(given: &BSplineSurface) -> Self {
        let scale = given.isotropic_scale(ISOTROPY_SAMPLES);
        Self { surface: given.rescaled(scale), scale }
    }

    /// A unit (du, dv) of the given patch as a direction here (not unit).
    pub fn direction(&self, d: [f64; 2]) -> [f64; 2] {
        [d[0] * self.scale[0], d[1] * self.scale[1]]
    }

    /// A point (u, v) here in the given patch's parameters (the domains start alike).
    pub fn to_given(&self, w: [f64; 2]) -> [f64; 2] {
        let ((u0, _), (v0, _)) = self.surface.domain();
        [u0 + (w[0] - u0) / self.scale[0], v0 + (w[1] - v0) / self.scale[1]]
    }
}

/// The patch `given` at one speed ([`IsotropicPatch`]) and `torsal_uv` in its parameters.
pub fn isotropic(given: &BSplineSurface, torsal_uv: &[Option<[[f64; 2]; 2]>]) -> (IsotropicPatch, Vec<Option<[[f64; 2]; 2]>>) {
    let patch = IsotropicPatch::of(given);
    let directions = torsal_uv.iter().map(|d| d.map(|[a, b]| [patch.direction(a), patch.direction(b)])).collect();
    (patch, directions)
}

/// Samples per parameter of the mean speeds in [`isotropic`].
const ISOTROPY_SAMPLES: usize = 16;

/// Called after every fairing iteration with the iteration, the term statistics and the
/// vertices (model units); false cancels.
pub type FairingHook<'h> = dyn FnMut(usize, &[TermStats], &[DVec3]) -> Result<(), Cancelled> + 'h;

/// Second differences along the lattice polylines (triples a, v, b joined by mesh edges), per
/// coordinate, over the vertex 3-blocks at `offset(v)`. Triples with a vertex on the patch
/// boundary are left out: the boundary cuts the last segment of a polyline short, and fairing it
/// would drag the polyline off the torsal direction.
pub(crate) fn polyline_fairness(polylines: &[[u32; 3]], on_boundary: &[bool], edges: &[[u32; 2]], offset: impl Fn(usize) -> usize) -> Linear {
    let edge_set: HashSet<[u32; 2]> = edges.iter().copied().collect();
    let joined = |a: u32, b: u32| edge_set.contains(&[a.min(b), a.max(b)]);
    let mut fair = Linear::new();
    for &[a, v, b] in polylines {
        if !(joined(a, v) && joined(v, b)) || [a, v, b].iter().any(|&i| on_boundary[i as usize]) {
            continue;
        }
        for c in 0..3 {
            fair.push_row(&[(offset(a as usize) + c, 1.0), (offset(v as usize) + c, -2.0), (offset(b as usize) + c, 1.0)], 0.0);
        }
    }
    fair.with_name("fairness")
}

/// Remeshes along the torsal field (per quad of the `grid` × `grid` sampling grid, unit (du, dv)
/// directions, as [`super::SqCongruence::torsal_uv`]) and fairs the result into Q′ (see the
/// module docs). `hook` sees every fairing iteration (terms, vertices in model units); false
/// cancels.
pub fn quad_mesh(
    reference: &Reference,
    grid: usize,
    torsal_uv: &[Option<[[f64; 2]; 2]>],
    params: &SqParams,
    clock: Clock,
    hook: &mut FairingHook,
) -> Result<SqQuadMesh, SqError> {
    let given = reference.spline().ok_or(SqError::NotBSpline)?;
    let torsal = CrossField::new(given, grid, torsal_uv).ok_or(SqError::NoTorsalField)?;
    let remesh_params = QuadRemeshParams { target_faces: params.faces, ..QuadRemeshParams::default() };
    let mut warnings = Vec::new();
    // The remesh runs on the patch with its parameters at one speed (see `isotropic`) and gives
    // its (u, v) back in the given ones.
    let (patch, iso_torsal_uv) = isotropic(given, torsal_uv);
    let surface = &patch.surface;
    let field = CrossField::new(surface, grid, &iso_torsal_uv).ok_or(SqError::NoTorsalField)?;
    let prepared = prepare(surface, &field, &remesh_params)?;
    let singular_points = prepared.field.singular.clone();
    let remesh = if singular_points.is_empty() {
        quad_remesh_prepared(surface, prepared, &remesh_params)?
    } else {
        let lines = vec![Some([[1.0, 0.0], [0.0, 1.0]]); (grid - 1).pow(2)];
        let field = CrossField::new(surface, grid, &lines).ok_or(SqError::NoTorsalField)?;
        let (three, five) = (singular_points.iter().filter(|s| s.quarters > 0).count(), singular_points.iter().filter(|s| s.quarters < 0).count());
        warnings.push(Warning::SingularTorsalField {
            valence_3: three,
            valence_5: five,
            bound_deg: [support_plane_bound_deg(3), support_plane_bound_deg(5)],
        });
        quad_remesh(surface, &field, &remesh_params)?
    };
    if remesh.folded_triangles > 0 {
        warnings.push(Warning::FoldedFieldTriangles { triangles: remesh.folded_triangles });
    }
    let QuadRemesh { mesh: mut remesh, mut uv, mut polylines, mut on_boundary, dropped, singular, folded_triangles, .. } = remesh;
    reach_the_boundary(surface, &mut remesh, &mut uv, &mut on_boundary);
    extend_to_the_boundary(surface, &mut remesh, &mut uv, &mut on_boundary, &mut polylines);
    let remesh_edge_angles_deg = edge_field_angles(surface, &field, &remesh, &uv, &on_boundary);
    for w in &mut uv {
        *w = patch.to_given(*w);
    }
    let surface = given;

    // Q′ in the frame of the bounding box.
    let (lo, hi) = reference.mesh().bbox();
    let (t, s) = (0.5 * (lo + hi), reference.diagonal());
    let framed = reference.in_frame(t, s);
    let nv = remesh.vertex_count();
    let mut x: Vec<f64> = remesh.positions.iter().flat_map(|p| ((*p - t) / s).to_array()).collect();
    let offsets: Vec<usize> = (0..nv).map(|v| 3 * v).collect();
    let mut problem = Problem::new(3 * nv);
    let tangent = ReferenceProximity::tangent(&framed, offsets.clone());
    let mut point = ReferenceProximity::point(&framed, offsets, vec![params.sphere_weights.epsilon.sqrt(); nv]);
    point.share_closest_with(&tangent);
    problem.add_term(tangent.with_name("glide_tangent"), 1.0);
    problem.add_term(point.with_name("glide_point"), 1.0);
    let edges = crate::geometry::mesh::topology::Topology::new(&remesh).edges().to_vec();
    problem.add_term(polyline_fairness(&polylines, &on_boundary, &edges, |v| 3 * v), params.fairing_weight);
    problem.add_term(Proximal::new((0..3 * nv).collect()), 0.05);
    for (v, &b) in on_boundary.iter().enumerate() {
        problem.group_variables(3 * v..3 * v + 3);
        if b {
            problem.fix_range(3 * v..3 * v + 3);
        }
    }
    let mut solver = Solver::new(SolverOptions { max_iterations: params.fairing_iterations, clock, ..SolverOptions::default() });
    let report = solver.solve(&mut problem, &mut x, |it| {
        let pts: Vec<DVec3> = it.x.chunks(3).map(|c| t + s * DVec3::new(c[0], c[1], c[2])).collect();
        hook(it.iteration, it.terms, &pts)
    });
    if report.termination == Termination::Cancelled {
        return Err(SqError::Cancelled);
    }
    // Closest points: the (u, v) of Q′'s vertices.
    let start = reference.spline_reference().ok_or(SqError::NotBSpline)?;
    let mut positions = Vec::with_capacity(nv);
    let mut q_uv = Vec::with_capacity(nv);
    for v in 0..nv {
        let p = t + s * DVec3::new(x[3 * v], x[3 * v + 1], x[3 * v + 2]);
        let (w, _, _) = start.closest_point(p, uv[v]);
        positions.push(p);
        q_uv.push(w);
    }
    let mesh = PolyMesh::new(positions, remesh.faces.clone());
    let edge_angles_deg = edge_field_angles(surface, &torsal, &mesh, &q_uv, &on_boundary);
    let coverage = coverage(surface, &mesh.faces, &q_uv);
    if coverage < 0.9 {
        warnings.push(Warning::PartialCoverage { coverage });
    }
    Ok(SqQuadMesh {
        torsal,
        singular_points,
        singular,
        folded_triangles,
        remesh,
        mesh,
        uv: q_uv,
        polylines,
        on_boundary,
        coverage,
        dropped,
        remesh_edge_angles_deg,
        edge_angles_deg,
        fairing_iterations: report.iterations,
        warnings,
    })
}

/// How near the patch boundary, × the mean length of its edges in (u, v), a vertex on the
/// mesh's boundary is moved onto it ([`reach_the_boundary`]): farther ones would stretch their
/// quads enough to cost the support planes their angle α.
const BOUNDARY_REACH: f64 = 0.3;

/// The vertices on the mesh's boundary that the lattice left short of the patch boundary, less
/// than [`BOUNDARY_REACH`] of their edges' length away in (u, v), moved onto it (onto a corner of the domain
/// when near two sides) and held there as boundary vertices: the panels then cover the patch up
/// to its boundary instead of leaving a strip along it.
fn reach_the_boundary(surface: &crate::geometry::bspline::BSplineSurface, mesh: &mut PolyMesh, uv: &mut [[f64; 2]], on_boundary: &mut [bool]) {
    let ((u0, u1), (v0, v1)) = surface.domain();
    let (length, outer) = outer_vertices(surface, mesh, uv);
    for v in 0..uv.len() {
        if !outer[v] || on_boundary[v] || !length[v].is_finite() {
            continue;
        }
        let near = BOUNDARY_REACH * length[v];
        let [u, w] = uv[v];
        let (du, dw) = ((u - u0).min(u1 - u) / (u1 - u0), (w - v0).min(v1 - w) / (v1 - v0));
        let mut moved = [u, w];
        if du < near {
            moved[0] = if u - u0 < u1 - u { u0 } else { u1 };
        }
        if dw < near {
            moved[1] = if w - v0 < v1 - w { v0 } else { v1 };
        }
        if moved != [u, w] {
            uv[v] = moved;
            mesh.positions[v] = surface.point(moved[0], moved[1]);
            on_boundary[v] = true;
        }
    }
}

/// Per vertex, the mean length of its edges in (u, v) over the domain's sides (NaN without
/// edges), and whether it is on the mesh's boundary.
fn outer_vertices(surface: &crate::geometry::bspline::BSplineSurface, mesh: &PolyMesh, uv: &[[f64; 2]]) -> (Vec<f64>, Vec<bool>) {
    let ((u0, u1), (v0, v1)) = surface.domain();
    let topology = crate::geometry::mesh::topology::Topology::new(mesh);
    let mut reach = vec![(0.0f64, 0usize); uv.len()];
    let mut outer = vec![false; uv.len()];
    for (e, &[a, b]) in topology.edges().iter().enumerate() {
        let (a, b) = (a as usize, b as usize);
        let l = ((uv[a][0] - uv[b][0]) / (u1 - u0)).hypot((uv[a][1] - uv[b][1]) / (v1 - v0));
        for v in [a, b] {
            reach[v].0 += l;
            reach[v].1 += 1;
        }
        if topology.edge_faces(e).len() == 1 {
            outer[a] = true;
            outer[b] = true;
        }
    }
    (reach.iter().map(|&(l, k)| if k == 0 { f64::NAN } else { l / k as f64 }).collect(), outer)
}

/// The farthest the mesh's boundary may stand from a side of the patch, × the mean length of
/// its edges in (u, v), for a row of quads to be added out to that side ([`extend_to_the_boundary`]).
const BOUNDARY_ROW: f64 = 2.0;

/// A boundary edge gets a quad out to a side only when it runs along the side: its shadow on
/// the side is at least this share of its length in (u, v).
const EDGE_ALONG_SIDE: f64 = 0.7;

/// Where an edge of the mesh's boundary stands short of one side of the patch, beyond what
/// [`reach_the_boundary`] moves and within [`BOUNDARY_ROW`] edges, one quad out to that side:
/// its new corners are the edge's ends moved across onto the side, held there as boundary
/// vertices. The strip the lattice left along the side is then covered by panels.
fn extend_to_the_boundary(
    surface: &crate::geometry::bspline::BSplineSurface,
    mesh: &mut PolyMesh,
    uv: &mut Vec<[f64; 2]>,
    on_boundary: &mut Vec<bool>,
    polylines: &mut Vec<[u32; 3]>,
) {
    let ((u0, u1), (v0, v1)) = surface.domain();
    let (length, outer) = outer_vertices(surface, mesh, uv);
    let scaled = |p: [f64; 2]| [(p[0] - u0) / (u1 - u0), (p[1] - v0) / (v1 - v0)];
    let area = |p: &[[f64; 2]]| (0..p.len()).map(|i| p[i][0] * p[(i + 1) % p.len()][1] - p[(i + 1) % p.len()][0] * p[i][1]).sum::<f64>();
    // A vertex's place on side k (0: u0, 1: u1, 2: v0, 3: v1), when its gap to the side is
    // beyond the reach and within a row.
    let across = |v: usize, k: usize| -> Option<[f64; 2]> {
        if !outer[v] || on_boundary[v] || !length[v].is_finite() {
            return None;
        }
        let [u, w] = scaled(uv[v]);
        let gap = [u, 1.0 - u, w, 1.0 - w][k];
        let within = gap > BOUNDARY_REACH * length[v] && gap <= BOUNDARY_ROW * length[v];
        within.then_some([[u0, uv[v][1]], [u1, uv[v][1]], [uv[v][0], v0], [uv[v][0], v1]][k])
    };
    let topology = crate::geometry::mesh::topology::Topology::new(&*mesh);
    let mut planned = Vec::new();
    for (e, &[a, b]) in topology.edges().iter().enumerate() {
        let &[(f, k)] = topology.edge_faces(e) else { continue };
        // The edge as its face runs it, a → b: the new quad runs it b → a.
        let c = mesh.faces[f as usize].corners();
        let (a, b) = if c[k as usize] == a { (a, b) } else { (b, a) };
        // The side the edge faces: its outward normal in (u, v), to the right of a → b in a
        // face that turns counter-clockwise.
        let face_uv: Vec<[f64; 2]> = c.iter().map(|&v| scaled(uv[v as usize])).collect();
        let (qa, qb) = (scaled(uv[a as usize]), scaled(uv[b as usize]));
        let turn = area(&face_uv).signum();
        let out = [turn * (qb[1] - qa[1]), -turn * (qb[0] - qa[0])];
        let side = if out[0].abs() > out[1].abs() { usize::from(out[0] > 0.0) } else { 2 + usize::from(out[1] > 0.0) };
        let (Some(pa), Some(pb)) = (across(a as usize, side), across(b as usize, side)) else { continue };
        // Only an edge along the side, whose quad turns the way its face does.
        let (qa2, qb2) = (scaled(pa), scaled(pb));
        if (qa2[0] - qb2[0]).hypot(qa2[1] - qb2[1]) < EDGE_ALONG_SIDE * (qa[0] - qb[0]).hypot(qa[1] - qb[1]) {
            continue;
        }
        if area(&[qb, qa, qa2, qb2]) * turn <= 0.0 {
            continue;
        }
        planned.push((a, b, side, pa, pb));
    }
    // New vertices by (vertex, side): at a corner of the lattice the two rows part.
    let mut moved: std::collections::HashMap<(u32, usize), u32> = std::collections::HashMap::new();
    let mut faces = Vec::new();
    for (a, b, side, pa, pb) in planned {
        let mut corner = |v: u32, p: [f64; 2]| -> u32 {
            *moved.entry((v, side)).or_insert_with(|| {
                uv.push(p);
                on_boundary.push(true);
                mesh.positions.push(surface.point(p[0], p[1]));
                (uv.len() - 1) as u32
            })
        };
        let (a2, b2) = (corner(a, pa), corner(b, pb));
        faces.push(crate::geometry::mesh::Face::quad([b, a, a2, b2]));
    }
    // The mesh line through each moved vertex goes on across the new row: fairing spaces the
    // row and the one inside it evenly.
    let mut moved: Vec<(u32, u32)> = moved.into_iter().map(|((v, _), new)| (v, new)).collect();
    moved.sort_unstable();
    for (v, new) in moved {
        let inner: Vec<u32> = topology
            .vertex_faces(v as usize)
            .iter()
            .flat_map(|&f| mesh.faces[f as usize].corners().to_vec())
            .filter(|&w| w != v)
            .filter(|&w| topology.edge_index(v, w).is_some_and(|e| topology.edge_faces(e).len() == 2))
            .collect();
        if let [w, ..] = inner[..] {
            if inner.iter().all(|&x| x == w) {
                polylines.push([new, v, w]);
            }
        }
    }
    mesh.faces.extend(faces);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::bspline::{BSplineBasis, BSplineSurface};
    use crate::geometry::mesh::topology::Topology;
    use crate::geometry::mesh::Face;

    /// The unit square z = 0 as a bilinear patch.
    fn square() -> BSplineSurface {
        let basis = || BSplineBasis::clamped_uniform(1, 2, (0.0, 1.0)).unwrap();
        let control = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(1.0, 1.0, 0.0)];
        BSplineSurface::new(basis(), basis(), control, vec![1.0; 4]).unwrap()
    }

    /// A 4 × 3 lattice of quads 0.2 by 0.22 over u in [0.1, 0.9], v in [0, 0.66], its lower row
    /// on the side v = 0, counter-clockwise; the side v = 1 is about 1.6 edges away, u = 0 and
    /// u = 1 half an edge.
    fn lattice() -> (PolyMesh, Vec<[f64; 2]>, Vec<bool>) {
        let (nu, nv) = (5, 4);
        let uv: Vec<[f64; 2]> = (0..nv).flat_map(|j| (0..nu).map(move |i| [0.1 + 0.2 * i as f64, 0.22 * j as f64])).collect();
        let id = |i: usize, j: usize| (i + nu * j) as u32;
        let faces =
            (0..nv - 1).flat_map(|j| (0..nu - 1).map(move |i| Face::quad([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]))).collect();
        let positions = uv.iter().map(|p| DVec3::new(p[0], p[1], 0.0)).collect();
        let on_boundary = uv.iter().map(|p| p[1] == 0.0).collect();
        (PolyMesh::new(positions, faces), uv, on_boundary)
    }

    #[test]
    fn the_isotropic_patch_maps_points_and_directions_back_to_the_given_one() {
        // u over [0, 10] runs ten times slower than v over [0, 1] on the unit square.
        let given = square().rescaled([10.0, 1.0]);
        let patch = IsotropicPatch::of(&given);
        assert!((patch.scale[0] - 0.1).abs() < 1e-9 && (patch.scale[1] - 1.0).abs() < 1e-9, "{:?}", patch.scale);
        for w in [[0.0, 0.0], [0.3, 0.7], [1.0, 0.25]] {
            let back = patch.to_given(w);
            assert!(patch.surface.point(w[0], w[1]).distance(given.point(back[0], back[1])) < 1e-12);
            // The same tangent vector through both parameter planes.
            let d = [0.6, 0.8];
            let (a, b) = (patch.surface.derivatives(w[0], w[1]), given.derivatives(back[0], back[1]));
            let e = patch.direction(d);
            assert!((a.su * e[0] + a.sv * e[1]).distance(b.su * d[0] + b.sv * d[1]) < 1e-12);
        }
    }

    #[test]
    fn a_strip_along_a_side_gets_a_row_of_quads_out_to_it() {
        let surface = square();
        let (mut mesh, mut uv, mut on_boundary) = lattice();
        let mut polylines = Vec::new();
        let before = mesh.face_count();
        reach_the_boundary(&surface, &mut mesh, &mut uv, &mut on_boundary);
        // u = 0.1 and u = 0.9 are half an edge from their sides: beyond the reach, within a row.
        assert!(uv.iter().all(|p| p[0] >= 0.1 - 1e-12 && p[0] <= 0.9 + 1e-12));
        extend_to_the_boundary(&surface, &mut mesh, &mut uv, &mut on_boundary, &mut polylines);
        // A quad out to u = 0 and u = 1 on each side edge of the lattice but the lowest, whose
        // lower vertex is on v = 0 already, and out to v = 1 on every top edge; the top corners
        // of the lattice move to both their sides, so only the patch's corners stay open.
        assert_eq!(mesh.face_count() - before, 2 + 2 + 4);
        let new: Vec<usize> = (20..uv.len()).collect();
        assert_eq!(new.len(), 3 + 3 + 5);
        assert!(new.iter().all(|&v| on_boundary[v]));
        assert!(new.iter().all(|&v| uv[v].iter().any(|&c| c == 0.0 || c == 1.0)), "{uv:?}");
        // Every new quad turns the way the lattice does, and the mesh stays manifold.
        let area = |f: &Face| {
            let c = f.corners();
            (0..4).map(|k| uv[c[k] as usize][0] * uv[c[(k + 1) % 4] as usize][1] - uv[c[(k + 1) % 4] as usize][0] * uv[c[k] as usize][1]).sum::<f64>()
        };
        assert!(mesh.faces.iter().all(|f| area(f) > 0.0));
        assert!(Topology::new(&mesh).edge_face_counts().iter().all(|&k| k <= 2));
        // The mesh lines go on across the new rows (not at the lattice's corners, where none
        // comes in).
        assert_eq!(polylines.len(), new.len() - 4);
        for [a, v, b] in &polylines {
            let (pa, pv, pb) = (uv[*a as usize], uv[*v as usize], uv[*b as usize]);
            let cross = (pv[0] - pa[0]) * (pb[1] - pv[1]) - (pv[1] - pa[1]) * (pb[0] - pv[0]);
            assert!(cross.abs() < 1e-12, "{a} {v} {b} not on one line");
        }
    }
}
