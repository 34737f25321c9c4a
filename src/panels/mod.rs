//! Panels: the spherical triangles and quads of a [`SphereMesh`], bounded by circular arcs,
//! tessellated for display and export (Sec. 3, 4, 5; Fig. 12).
//!
//! # Arcs
//! **Variant (a)** ([`EdgeArcs::Intersection`], Fig. 12 top; [`build_panels`]): every mesh edge
//! gets one [`Arc`], computed once and shared by both adjacent panels:
//! - an interior edge uses the intersection circle of the two face spheres. Its plane is the
//!   radical plane a₂ψ₁ − a₁ψ₂ = 0, computed in coordinates local to the edge's first vertex
//!   (ψᵢ(p + y) = aᵢ|y|² + ⟨gᵢ, y⟩ + ψᵢ(p), gᵢ = ∇ψᵢ(p)), so its normal is a₂g₁ − a₁g₂; it is
//!   made exactly orthogonal to the edge, then cut with the more curved of the two spheres. When
//!   that normal is ill-conditioned (the spheres are identical or meet at an angle below ~1e-9,
//!   or both faces are planes) the edge falls back to the boundary rule below, on the more curved
//!   sphere;
//! - a boundary edge (one face) uses its plane from [`SphereMesh::boundary_planes`] if it has
//!   one, else the plane through its two vertices and the rule's point m
//!   (`Through(m)`) or direction a (`Parallel(a)`). If m lies on the edge's line (or a is
//!   parallel to it), the plane through the edge and the sphere normal at the first vertex is
//!   used instead.
//!
//! **Variant (b)** ([`EdgeArcs::BisectingPlanes`], Fig. 12 bottom): an interior edge pq between
//! faces f and g is cut by the *bisecting plane* of the two face planes, the plane through the
//! edge containing n_f + n_g (unit face normals; n_f − n_g if the two faces traverse the edge in
//! the same direction, i.e. are inconsistently oriented). This is well conditioned also for
//! nearly coplanar faces. Each of the two panels gets its own arc: its own sphere cut by that
//! plane. Both arcs run between the (shared) vertices p and q, but differ in between: the small
//! gaps of variant (b), measured by [`arc_gaps`]. If n_f ± n_g is (nearly) parallel to the edge
//! (faces folded onto each other), the plane through the edge containing n_f (else n_g) is used;
//! if that fails too, each face gets its boundary-rule arc. Boundary and non-manifold edges are
//! treated as in variant (a).
//!
//! **Variant (a) where it bounds** ([`bisect_unbuildable_arcs`]): the interior edges listed in
//! [`SphereMesh::bisected_edges`] are cut as in variant (b) also in variant (a), where the
//! intersection circle would make a panel's arcs cross or sweep too wide.
//!
//! A plane cut with a plane is a straight edge ([`Arc::is_straight`]). Of the two arcs of the
//! circle between the vertices, the one whose midpoint is nearer the adjacent face triangle(s)
//! (sum of the distances to the planar triangles) is taken: the panel-side arc, normally the
//! minor one.
//!
//! Circles are built from the edge itself (chord midpoint, in-plane offset h of the centre), not
//! from the sphere centres, so nearly flat spheres with centres far away keep full precision.
//!
//! **Orientation.** `panel.arcs[k]` runs from corner k to corner k+1 (mod 3 or 4), and
//! runs counter-clockwise about `arc.circle.normal`; the two panels of an edge therefore carry
//! the same circle with opposite normals.
//!
//! # Tessellation
//! With tolerance `tol` (absolute; callers pass 1e-4 of the bounding-box diagonal):
//! - each arc is split into n equal-angle segments with sagitta ≤ 0.5·tol (straight edges: one
//!   segment). In variant (a) the arc points of an edge are computed once, so adjacent panels
//!   share them bit-exactly; in variant (b) each panel samples its own arc (only the two edge
//!   vertices are shared);
//! - a triangle's interior is the level-N barycentric grid of its corner triangle without its
//!   boundary points, N ≥ 3 and ≥ the three arc segment counts (N = 1, the corner triangle
//!   alone, when all three sides are single segments and that is fine enough). Grid points are a
//!   transfinite blend of the three arcs (planar barycentric point plus Σₖ (1 − λ_opposite)
//!   times the bulge of arc k), projected radially onto the sphere from its centre
//!   (orthogonally for a plane). A quad's interior is the (M × N) grid of the Coons patch of its
//!   four arcs, projected the same way. The ring between the grid and the arc points is closed
//!   by a zipper per side, so any arc point counts fit without folds;
//! - N starts from the estimate √(|a|·Q/tol) (Q: squared circumradius-like size of the corner
//!   triangle, see [`triangle_chord_error`]) and grows until the exact chord error of every
//!   triangle, max over the triangle of the distance to the sphere, is ≤ tol (or N reaches
//!   [`tessellate::MAX_LEVEL`], or three refinements in a row did not reduce the error: only for invalid
//!   panels whose arcs cross, see [`Panel::folded_triangles`]).
//!
//! [`Panel::area`] is the sum of the tessellation triangle areas; it differs from the true
//! spherical area by a relative amount of the order of tol/r (usually less).

pub mod arc;
pub mod buildability;
pub mod deviation;
pub mod edge_arcs;
pub mod exact_surface;
pub mod gaps;
pub mod moulds;
pub mod panel;
pub mod sphere_mesh;
pub mod tessellate;

/// Radii closer than this, relative to the diagonal, count as one in the schedule.
pub const RADIUS_TOLERANCE_RANGE: crate::params::ParamRange<f64> = crate::params::ParamRange::new("radius tolerance", 1e-9, 1.0);

use glam::DVec3;

use crate::geometry::sphere::Sphere;
use arc::Arc;
use edge_arcs::{bisecting_plane_normal, cut_arc, edge_arc, face_triangles, usable_sphere, EdgeArcs};
use panel::Panel;
use sphere_mesh::SphereMesh;
use tessellate::{tessellate, ARC_TOL_FACTOR};

/// The chord tolerance of exported panels and of the distance metrics, relative to the
/// bounding-box diagonal.
pub const DEFAULT_CHORD_TOLERANCE: f64 = 1e-4;

/// Builds, arcs and tessellates every panel of `sm`, with chord error ≤ `chord_tolerance`
/// (absolute length; a non-positive or non-finite value means 1e-4 of the bounding-box
/// diagonal). Panel i is face i. Variant (a) edges: `build_panels_with(sm, tol,
/// EdgeArcs::Intersection)`.
pub fn build_panels(sm: &SphereMesh, chord_tolerance: f64) -> Vec<Panel> {
    build_panels_with(sm, chord_tolerance, EdgeArcs::Intersection)
}

/// [`build_panels`] with the interior edge arcs of the given variant (Fig. 12).
/// The most tessellation triangles of all panels together, about: glass panels stay far below
/// it, degenerate faces' panels (huge spheres, crossing arcs) would otherwise take
/// [`tessellate::MAX_PANEL_TRIANGLES`] each.
pub const PANEL_TRIANGLE_BUDGET: usize = 4_000_000;

/// The budget of a live view's panels, sent every 100 ms while an optimization runs: a diverging
/// run's huge spheres must not bring the view to a crawl (glass panels stay far below it).
pub const LIVE_PANEL_TRIANGLE_BUDGET: usize = 250_000;

/// The subdivision level cap of each of `faces` panels under `budget` triangles: at least
/// `min_level`, at most [`tessellate::MAX_LEVEL`].
pub fn level_cap(faces: usize, budget: usize, min_level: usize) -> usize {
    let level = (budget as f64 / (2 * faces.max(1)) as f64).sqrt() as usize;
    level.clamp(min_level, tessellate::MAX_LEVEL)
}

/// The most triangles a result's panels are drawn with, in all.
pub const DISPLAY_PANEL_TRIANGLE_BUDGET: usize = 500_000;

/// The panels as drawn, within `budget` triangles about: each panel over its share (at the
/// subdivision level [`level_cap`] of the budget) is tessellated again at that level, its arcs
/// at most 4 × that level in segments. Glass panels stay far below their share and are drawn as
/// measured; the ballooning or folded panels of a failed result would otherwise take the whole
/// measurement's budget ([`PANEL_TRIANGLE_BUDGET`]) on screen.
pub fn display_panels(panels: &[Panel], budget: usize) -> std::borrow::Cow<'_, [Panel]> {
    let level = level_cap(panels.len(), budget, 2);
    let share = 2 * level * level + 4 * (5 * level + 2);
    if panels.iter().all(|p| p.triangles.len() <= share) {
        return std::borrow::Cow::Borrowed(panels);
    }
    let coarse = |p: &Panel| {
        if p.triangles.len() <= share {
            return p.clone();
        }
        let sides = p.arcs.iter().zip(&p.arc_vertices).map(|(arc, ids)| (*arc, arc.sample((ids.len() - 1).clamp(1, 4 * level)))).collect();
        let corners: Vec<DVec3> = p.positions[..p.corners.len()].to_vec();
        // No chord tolerance: the level alone bounds it.
        let t = tessellate(&p.sphere, sides, &corners, 0.0, level);
        Panel { positions: t.positions, triangles: t.triangles, area: t.area, arc_vertices: t.arc_vertices, ..p.clone() }
    };
    std::borrow::Cow::Owned(panels.iter().map(coarse).collect())
}

pub fn build_panels_with(sm: &SphereMesh, chord_tolerance: f64, edge_arcs: EdgeArcs) -> Vec<Panel> {
    build_panels_within(sm, chord_tolerance, edge_arcs, level_cap(sm.mesh.face_count(), PANEL_TRIANGLE_BUDGET, 32))
}

/// The panels of a live view: [`build_panels_with`] under [`LIVE_PANEL_TRIANGLE_BUDGET`].
pub(crate) fn build_live_panels(sm: &SphereMesh, chord_tolerance: f64, edge_arcs: EdgeArcs) -> Vec<Panel> {
    build_panels_within(sm, chord_tolerance, edge_arcs, level_cap(sm.mesh.face_count(), LIVE_PANEL_TRIANGLE_BUDGET, 4))
}

/// Every face's arcs (Fig. 12), side k from corner k to corner k + 1, and the usable sphere each
/// is cut from: what a panel is before it is tessellated.
pub struct FaceArcs {
    /// Per face: its sphere, or the plane of its first triangle where the sphere is unusable.
    pub spheres: Vec<Sphere>,
    /// Per face and side: the arc as computed along its edge (from the edge's lower vertex),
    /// whether the side runs the other way, and whether the edge's arc is shared by its faces
    /// (its samples are then capped by the subdivision level, as one sampling serves both).
    sides: Vec<Vec<(Arc, bool, bool)>>,
}

impl FaceArcs {
    /// The arcs of every face of `sm`, interior edges of the given variant.
    pub fn of(sm: &SphereMesh, edge_arcs: EdgeArcs) -> Self {
        let mesh = &sm.mesh;
        let topo = sm.topology();
        let diag = mesh.bbox_diagonal().max(f64::MIN_POSITIVE);
        let faces = mesh.face_count();
        let spheres: Vec<Sphere> = (0..faces)
            .map(|f| {
                let s = sm.face_spheres.get(f).copied().unwrap_or(Sphere { a: f64::NAN, b: DVec3::NAN, c: f64::NAN });
                usable_sphere(&s, &mesh.face_points(f))
            })
            .collect();
        let corner = |f: usize, k: usize| mesh.faces[f].corners()[k];
        let mut sides: Vec<Vec<Option<(Arc, bool, bool)>>> = mesh.faces.iter().map(|f| vec![None; f.len()]).collect();
        for (e, &[lo, hi]) in topo.edges().iter().enumerate() {
            let inc: Vec<(usize, usize)> = topo.edge_faces(e).iter().map(|&(f, k)| (f as usize, k as usize)).collect();
            let (p, q) = (mesh.positions[lo as usize], mesh.positions[hi as usize]);
            if inc.len() == 2 && (edge_arcs == EdgeArcs::BisectingPlanes || sm.bisected_edges.contains(&[lo, hi])) {
                // Variant (b), Fig. 12 bottom: every panel cuts its own sphere with the bisecting plane.
                let [(f, kf), (g, kg)] = [inc[0], inc[1]];
                let consistent = (corner(f, kf) == lo) != (corner(g, kg) == lo);
                let plane = bisecting_plane_normal(p, q, mesh.face_area_vector(f), mesh.face_area_vector(g), consistent);
                let tris = [face_triangles(mesh, f), face_triangles(mesh, g)];
                for &(h, k) in &inc {
                    let arc = match plane {
                        Some(n) => cut_arc(p, q, n, &spheres[h], &tris, diag),
                        None => edge_arc(p, q, &[h], &spheres, mesh, sm.boundary_arcs, diag),
                    };
                    sides[h][k] = Some((arc, corner(h, k) != lo, false));
                }
                continue;
            }
            if let (&[(f, k)], Some(&n)) = (inc.as_slice(), sm.boundary_planes.get(&[lo, hi])) {
                let arc = cut_arc(p, q, n, &spheres[f], &[face_triangles(mesh, f)], diag);
                sides[f][k] = Some((arc, corner(f, k) != lo, false));
                continue;
            }
            let groups: Vec<Vec<usize>> = if inc.len() <= 2 {
                vec![inc.iter().map(|&(f, _)| f).collect()]
            } else {
                // Non-manifold edge: every face gets its own boundary-rule arc.
                inc.iter().map(|&(f, _)| vec![f]).collect()
            };
            for group in groups {
                let arc = edge_arc(p, q, &group, &spheres, mesh, sm.boundary_arcs, diag);
                for &(f, k) in inc.iter().filter(|(f, _)| group.contains(f)) {
                    sides[f][k] = Some((arc, corner(f, k) != lo, true));
                }
            }
        }
        let sides = sides.into_iter().map(|f| f.into_iter().map(|s| s.expect("every face side has an arc")).collect()).collect();
        Self { spheres, sides }
    }

    /// The arcs of face `f` in its corners' order.
    pub fn arcs(&self, f: usize) -> Vec<Arc> {
        self.sides[f].iter().map(|&(arc, reversed, _)| if reversed { arc.reversed() } else { arc }).collect()
    }

    /// Whether the arcs of face `f` cross one another ([`exact_surface::arcs_cross`]).
    pub fn cross(&self, f: usize) -> bool {
        exact_surface::arcs_cross(&self.spheres[f], &self.arcs(f))
    }

    /// The faces whose arcs cross one another.
    pub fn crossing(&self) -> Vec<usize> {
        (0..self.sides.len()).filter(|&f| self.cross(f)).collect()
    }
}

/// The widest an arc may sweep in variant (a) before its edge is bisected, and the widest a
/// bisecting plane's arc may sweep for its edge to be bisected: well under the half circle that
/// one rational quadratic holds (the CAD files, [`exact_surface`]).
pub const MAX_SWEEP_DEG: f64 = 150.0;

/// Variant (a) where its arcs bound panels: every interior edge of a face whose arcs cross, and
/// every interior edge whose intersection arc sweeps more than [`MAX_SWEEP_DEG`], is cut by its
/// bisecting plane instead, as in variant (b), and again for the faces whose arcs then cross,
/// until no edge is left to bisect. Two nearly tangent spheres of different radii meet in a
/// small circle whose arc leaves the face sideways (Sec. 6.1, Fig. 12); the bisecting plane cuts
/// each sphere nearly along the normal, with a small gap between the two panels
/// ([`gaps::arc_gaps`]). An edge whose bisecting plane would cut an arc wider than
/// [`MAX_SWEEP_DEG`] keeps its intersection arc.
pub fn bisect_unbuildable_arcs(mut sm: SphereMesh) -> SphereMesh {
    let max_sweep = MAX_SWEEP_DEG.to_radians();
    let mut kept = std::collections::BTreeSet::new();
    loop {
        let arcs = FaceArcs::of(&sm, EdgeArcs::Intersection);
        let crossing: std::collections::BTreeSet<usize> = arcs.crossing().into_iter().collect();
        let topo = sm.topology();
        let mut candidates = Vec::new();
        for (f, face) in sm.mesh.faces.iter().enumerate() {
            let c = face.corners();
            for (k, &(arc, _, _)) in arcs.sides[f].iter().enumerate() {
                let (a, b) = (c[k], c[(k + 1) % c.len()]);
                let edge = [a.min(b), a.max(b)];
                let interior = topo.edge_index(a, b).is_some_and(|e| topo.edge_faces(e).len() == 2);
                if interior && !sm.bisected_edges.contains(&edge) && !kept.contains(&edge) && (crossing.contains(&f) || arc.sweep() > max_sweep) {
                    candidates.push(edge);
                }
            }
        }
        candidates.sort_unstable();
        candidates.dedup();
        if candidates.is_empty() {
            return sm;
        }
        sm.bisected_edges.extend(candidates.iter().copied());
        // The bisecting plane's arcs of the candidates: too wide ones keep their intersection arc.
        let bisected = FaceArcs::of(&sm, EdgeArcs::Intersection);
        for (f, face) in sm.mesh.faces.iter().enumerate() {
            let c = face.corners();
            for (k, &(arc, _, _)) in bisected.sides[f].iter().enumerate() {
                let (a, b) = (c[k], c[(k + 1) % c.len()]);
                let edge = [a.min(b), a.max(b)];
                if arc.sweep() > max_sweep && candidates.binary_search(&edge).is_ok() {
                    kept.insert(edge);
                }
            }
        }
        sm.bisected_edges.retain(|e| !kept.contains(e));
    }
}

/// [`build_panels_with`] with each panel's subdivision level at most `max_level`.
fn build_panels_within(sm: &SphereMesh, chord_tolerance: f64, edge_arcs: EdgeArcs, max_level: usize) -> Vec<Panel> {
    let mesh = &sm.mesh;
    let diag = mesh.bbox_diagonal().max(f64::MIN_POSITIVE);
    let tol = if chord_tolerance > 0.0 && chord_tolerance.is_finite() { chord_tolerance } else { 1e-4 * diag };
    let FaceArcs { spheres, sides } = FaceArcs::of(sm, edge_arcs);
    sides
        .into_iter()
        .enumerate()
        .map(|(f, face_sides)| {
            let sides: Vec<(Arc, Vec<DVec3>)> = face_sides
                .into_iter()
                .map(|(arc, reversed, shared)| {
                    let n = arc.segments_for(ARC_TOL_FACTOR * tol);
                    let pts = arc.sample(if shared { n.min(4 * max_level) } else { n });
                    if reversed {
                        (arc.reversed(), pts.into_iter().rev().collect())
                    } else {
                        (arc, pts)
                    }
                })
                .collect();
            let arcs = sides.iter().map(|s| s.0).collect();
            let t = tessellate(&spheres[f], sides, &mesh.face_points(f), tol, max_level);
            Panel {
                face: f,
                sphere: spheres[f],
                corners: mesh.faces[f].corners().to_vec(),
                arcs,
                positions: t.positions,
                triangles: t.triangles,
                area: t.area,
                arc_vertices: t.arc_vertices,
            }
        })
        .collect()
}

/// The points of the panels' arc along mesh edge `edge` (from `edge[0]` to `edge[1]`), taken
/// from the first panel at that edge: the outer side of a support element, so the support meets
/// the panels exactly.
pub fn edge_arc_points(sm: &SphereMesh, panels: &[Panel], edge: [u32; 2]) -> Option<Vec<DVec3>> {
    let topo = sm.topology();
    let e = topo.edge_index(edge[0], edge[1])?;
    let &(f, k) = topo.edge_faces(e).first()?;
    let panel = panels.get(f as usize)?;
    let mut points = panel.arc_points(k as usize);
    if panel.corners[k as usize] != edge[0] {
        points.reverse();
    }
    Some(points)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::circle::Circle;
    use tessellate::{project_to_sphere, triangle_chord_error};

    #[test]
    fn arc_point_sweep_and_sagitta() {
        // Quarter circle of radius 2 in the xy-plane, from (2,0,0) to (0,2,0), ccw about +z.
        let c = Circle { center: DVec3::ZERO, normal: DVec3::Z, radius: 2.0 };
        let arc = Arc { circle: c, from: DVec3::new(2.0, 0.0, 0.0), to: DVec3::new(0.0, 2.0, 0.0) };
        assert!((arc.sweep() - std::f64::consts::FRAC_PI_2).abs() < 1e-14);
        let m = arc.point(0.5);
        assert!((m - DVec3::new(2f64.sqrt(), 2f64.sqrt(), 0.0)).length() < 1e-14);
        assert!((arc.sagitta() - (2.0 - 2f64.sqrt())).abs() < 1e-14);
        // Reversed: ccw about −z, same points.
        let rev = arc.reversed();
        assert!((rev.sweep() - arc.sweep()).abs() < 1e-14);
        assert!((rev.point(0.25) - arc.point(0.75)).length() < 1e-14);
        // The major arc (ccw about −z from (2,0,0) to (0,2,0)).
        let major = Arc { circle: Circle { normal: -DVec3::Z, ..c }, ..arc };
        assert!((major.sweep() - 1.5 * std::f64::consts::PI).abs() < 1e-14);
        assert!((major.point(0.5) + m).length() < 1e-14);
        // Segment counts honour the tolerance.
        for tol in [1e-1, 1e-3, 1e-6] {
            let n = arc.segments_for(tol);
            assert!(arc.segment_sagitta(n) <= tol);
            assert!(n == 1 || arc.segment_sagitta(n - 1) > tol);
        }
    }

    #[test]
    fn projection_is_radial() {
        let s = Sphere::from_center_radius(DVec3::new(0.3, -0.2, 1.0), -1.7);
        let c = s.center().unwrap();
        let x = DVec3::new(1.0, 0.5, 0.2);
        let y = project_to_sphere(&s, c + DVec3::new(1.7, 0.0, 0.0), x);
        assert!(s.eval(y).abs() < 1e-15);
        assert!((y - c).normalize().cross((x - c).normalize()).length() < 1e-14);
        let pl = Sphere::plane(DVec3::new(0.0, 0.0, 1.0), DVec3::new(0.0, 0.6, 0.8));
        let y = project_to_sphere(&pl, DVec3::new(0.0, 0.0, 1.0), x);
        assert!(pl.eval(y).abs() < 1e-15);
        assert!((y - x).cross(DVec3::new(0.0, 0.6, 0.8)).length() < 1e-15);
    }

    #[test]
    fn chord_error_formula_matches_sphere_distance() {
        let s = Sphere::from_center_radius(DVec3::ZERO, 1.0);
        let on = |v: DVec3| v.normalize();
        let t = [on(DVec3::new(1.0, 0.1, 0.2)), on(DVec3::new(0.9, 0.4, 0.1)), on(DVec3::new(0.95, 0.1, 0.5))];
        let e = triangle_chord_error(&s, t[0], t[1], t[2]);
        // Brute force over the triangle.
        let mut best: f64 = 0.0;
        let n = 200;
        for i in 0..=n {
            for j in 0..=(n - i) {
                let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                let x = t[0] + u * (t[1] - t[0]) + v * (t[2] - t[0]);
                best = best.max(1.0 - x.length());
            }
        }
        assert!(e >= best - 1e-15 && e - best < 1e-6 * e, "{e} vs {best}");
        assert!((s.distance(DVec3::new(0.0, 0.0, 3.0)) - 2.0).abs() < 1e-15);
        assert!((s.distance(DVec3::new(0.0, 0.2, 0.0)) - 0.8).abs() < 1e-15);
    }
}
