//! Panels out and the run report: panel arcs and tessellation, the support strips, GLB (with the
//! Khronos glTF validator), OBJ, the panel schedule (CSV/JSON), closest-point queries and
//! `report.json`.
//!
//! The sphere meshes are built here by hand, so these tests do not depend on the ST pipeline:
//! - `cap`: a grid on the unit sphere, every face sphere the same sphere (all kinks 0);
//! - `omega(..)`: a bumpy height field whose face spheres pass through their 3 vertices and are
//!   orthogonal to a given Ω (the null vector of the 4×5 system of the notes, by cofactors);
//! - `flat`: a planar grid with plane "spheres";
//! - `mixed`: an Ω mesh with one vertex moved so that one face sphere degenerates to a plane.
#![cfg(not(target_arch = "wasm32"))] // native: reads ../shared, spawns processes

mod common;

use std::collections::HashMap;

use common::{khronos_validate, temp_dir};
use glam::DVec3;
use serde_json::Value;
use spherical_faces::congruence::support_structure::{support_element, support_strips, NodeAxes, SupportElement, SupportGeometry, SupportStructure};
use spherical_faces::export::glb::glb_json;
use spherical_faces::export::report::{InputCounts, OutputCounts};
use spherical_faces::export::schedule::PanelSchedule;
use spherical_faces::export::*;
use spherical_faces::geometry::absolute_sphere::AbsoluteSphere;
use spherical_faces::geometry::closest::{closest_point_brute_force, TriangleBvh};
use spherical_faces::geometry::mesh::TriMesh;
use spherical_faces::geometry::sphere::Sphere;
use spherical_faces::import::import_mesh;
use spherical_faces::panels::deviation::{max_deviation, max_distance_to_reference, panel_samples, ARC_SEGMENTS, MAX_SAMPLES};
use spherical_faces::panels::panel::Panel;
use spherical_faces::panels::sphere_mesh::{BoundaryArcRule, SphereMesh};
use spherical_faces::panels::tessellate::triangle_chord_error;
use spherical_faces::panels::*;
use spherical_faces::reference::Reference;
use spherical_faces::st_support::report::AbsoluteSphereSection;

/// The corners of triangle face `f`.
fn tri(sm: &SphereMesh, f: usize) -> [DVec3; 3] {
    let p = sm.mesh.face_points(f);
    [p[0], p[1], p[2]]
}

/// The sphere mesh's own triangles as a reference surface.
fn reference_of(sm: &SphereMesh) -> Reference {
    Reference::from_triangles(sm.mesh.triangulated())
}

// ---------------------------------------------------------------------------------------------
// Fixtures

/// An (n × n)-cell grid over [−1, 1]², mapped by `f`, triangulated counter-clockwise seen from
/// +z (alternating diagonals).
fn grid(n: usize, f: impl Fn(f64, f64) -> DVec3) -> TriMesh {
    let mut positions = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            positions.push(f(-1.0 + 2.0 * i as f64 / n as f64, -1.0 + 2.0 * j as f64 / n as f64));
        }
    }
    let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    let mut triangles = Vec::new();
    for j in 0..n {
        for i in 0..n {
            if (i + j) % 2 == 0 {
                triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            } else {
                triangles.push([id(i, j), id(i + 1, j), id(i, j + 1)]);
                triangles.push([id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
    }
    TriMesh::new(positions, triangles)
}

fn face_normal(mesh: &TriMesh, f: usize) -> DVec3 {
    mesh.face_area_vector(f).normalize()
}

/// Orients a normalized sphere so that its outward normal −∇ψ agrees with the face normal.
fn orient(s: Sphere, mesh: &TriMesh, f: usize) -> Sphere {
    let [a, b, c] = mesh.face_points(f);
    let x = (a + b + c) / 3.0;
    if (s.b - 2.0 * s.a * x).dot(face_normal(mesh, f)) < 0.0 {
        Sphere { a: -s.a, b: -s.b, c: -s.c }
    } else {
        s
    }
}

fn det4(m: [[f64; 4]; 4]) -> f64 {
    let mut det = 0.0;
    for c in 0..4 {
        let mut sub = [[0.0; 3]; 3];
        for r in 1..4 {
            let mut k = 0;
            for cc in 0..4 {
                if cc != c {
                    sub[r - 1][k] = m[r][cc];
                    k += 1;
                }
            }
        }
        let d3 = sub[0][0] * (sub[1][1] * sub[2][2] - sub[1][2] * sub[2][1]) - sub[0][1] * (sub[1][0] * sub[2][2] - sub[1][2] * sub[2][0])
            + sub[0][2] * (sub[1][0] * sub[2][1] - sub[1][1] * sub[2][0]);
        det += if c % 2 == 0 { 1.0 } else { -1.0 } * m[0][c] * d3;
    }
    det
}

/// Null vector of a 4×5 matrix by cofactors: sᵢ = (−1)ⁱ det(M without column i).
fn null_vector(rows: [[f64; 5]; 4]) -> [f64; 5] {
    let mut s = [0.0; 5];
    for (i, si) in s.iter_mut().enumerate() {
        let mut m = [[0.0; 4]; 4];
        for r in 0..4 {
            let mut k = 0;
            for c in 0..5 {
                if c != i {
                    m[r][k] = rows[r][c];
                    k += 1;
                }
            }
        }
        *si = if i % 2 == 0 { 1.0 } else { -1.0 } * det4(m);
    }
    s
}

fn point_row(p: DVec3) -> [f64; 5] {
    [p.length_squared(), -p.x, -p.y, -p.z, 1.0]
}

/// The face sphere through the three vertices, orthogonal to Ω (notes: "Linear conditions").
fn sphere_orthogonal(tri: [DVec3; 3], omega: &AbsoluteSphere) -> Sphere {
    let om = match *omega {
        AbsoluteSphere::Sphere { center: m, r2 } => [m.length_squared() - r2, -m.x, -m.y, -m.z, 1.0],
        AbsoluteSphere::Plane { axis, d } => [-2.0 * d, axis.x, axis.y, axis.z, 0.0],
    };
    let s = null_vector([point_row(tri[0]), point_row(tri[1]), point_row(tri[2]), om]);
    Sphere { a: s[0], b: DVec3::new(s[1], s[2], s[3]), c: s[4] }.normalized()
}

fn bumpy(x: f64, y: f64) -> DVec3 {
    DVec3::new(x, y, 0.35 * (x * x + 0.6 * y * y) + 0.03 * (3.0 * x + 1.0).sin() * (2.0 * y).cos())
}

const M_REAL: DVec3 = DVec3::new(0.05, -0.1, -3.0);
const M_IMAG: DVec3 = DVec3::new(0.05, -0.1, 1.8);
const M_STRESS: DVec3 = DVec3::new(0.05, -0.1, 1.6);
const R2_REAL: f64 = 19.8;

fn omega_mesh(omega: AbsoluteSphere, rule: BoundaryArcRule) -> SphereMesh {
    let mesh = grid(6, bumpy);
    let face_spheres = (0..mesh.face_count()).map(|f| orient(sphere_orthogonal(mesh.face_points(f), &omega), &mesh, f)).collect();
    SphereMesh::new(mesh, face_spheres, rule)
}

/// Ω real (R² > 0), centre below the surface (on its convex side): face radii about 1.5–2.5.
fn omega_real() -> SphereMesh {
    omega_mesh(AbsoluteSphere::Sphere { center: M_REAL, r2: R2_REAL }, BoundaryArcRule::Through(M_REAL))
}

/// Ω imaginary (R² < 0), centre near the centres of curvature.
fn omega_imaginary() -> SphereMesh {
    omega_mesh(AbsoluteSphere::Sphere { center: M_IMAG, r2: -3.2 }, BoundaryArcRule::Through(M_IMAG))
}

/// A poor Ω on purpose: small face spheres (r ≈ 0.3 on faces of size 0.33), arcs up to ~110°,
/// kinks of tens of degrees.
fn omega_stress() -> SphereMesh {
    omega_mesh(AbsoluteSphere::Sphere { center: M_STRESS, r2: 2.0 }, BoundaryArcRule::Through(M_STRESS))
}

fn omega_at_infinity() -> (SphereMesh, DVec3) {
    let a = DVec3::new(0.1, -0.05, 1.0).normalize();
    (omega_mesh(AbsoluteSphere::Plane { axis: a, d: 1.8 }, BoundaryArcRule::Parallel(a)), a)
}

const R_CAP: f64 = 1.3;

fn cap() -> SphereMesh {
    let mesh = grid(5, |x, y| R_CAP * DVec3::new(x, y, 1.6).normalize());
    let s = Sphere::from_center_radius(DVec3::ZERO, -R_CAP);
    let face_spheres = vec![s; mesh.face_count()];
    for f in 0..mesh.face_count() {
        assert_eq!(orient(s, &mesh, f), s, "cap orientation");
    }
    SphereMesh::new(mesh, face_spheres, BoundaryArcRule::Through(DVec3::ZERO))
}

fn flat() -> SphereMesh {
    let mesh = grid(4, |x, y| DVec3::new(x, 0.5 * y, 0.0));
    let face_spheres = (0..mesh.face_count()).map(|f| Sphere::plane(mesh.face_points(f)[0], DVec3::Z)).collect();
    SphereMesh::new(mesh, face_spheres, BoundaryArcRule::Through(DVec3::new(0.0, 0.0, 2.0)))
}

const PLANAR_FACE: usize = 0;

/// `omega_imaginary` with vertex 8 moved so that the plane of face 0 passes through m: the face
/// sphere orthogonal to Ω degenerates to that plane (set exactly), its neighbours stay spheres.
fn mixed() -> SphereMesh {
    let mut mesh = grid(6, bumpy);
    let t = mesh.triangles[PLANAR_FACE];
    assert_eq!(t, [0, 1, 8]);
    let (v0, v1) = (mesh.positions[0], mesh.positions[1]);
    // det[v1 − v0, v8 − v0, m − v0] is linear in z8.
    let det = |z: f64| {
        let v8 = DVec3::new(mesh.positions[8].x, mesh.positions[8].y, z);
        (v1 - v0).cross(v8 - v0).dot(M_IMAG - v0)
    };
    let (d0, d1) = (det(0.0), det(1.0));
    mesh.positions[8].z = -d0 / (d1 - d0);
    let omega = AbsoluteSphere::Sphere { center: M_IMAG, r2: -3.2 };
    let mut face_spheres: Vec<Sphere> = (0..mesh.face_count()).map(|f| orient(sphere_orthogonal(mesh.face_points(f), &omega), &mesh, f)).collect();
    assert!(face_spheres[PLANAR_FACE].a.abs() < 1e-9, "{:?}", face_spheres[PLANAR_FACE]);
    let p = mesh.face_points(PLANAR_FACE);
    face_spheres[PLANAR_FACE] = Sphere::plane(p[0], face_normal(&mesh, PLANAR_FACE));
    SphereMesh::new(mesh, face_spheres, BoundaryArcRule::Through(M_IMAG))
}

fn all_fixtures() -> Vec<(&'static str, SphereMesh)> {
    vec![
        ("cap", cap()),
        ("omega_real", omega_real()),
        ("omega_imaginary", omega_imaginary()),
        ("omega_stress", omega_stress()),
        ("omega_at_infinity", omega_at_infinity().0),
        ("flat", flat()),
        ("mixed", mixed()),
    ]
}

fn tol_for(sm: &SphereMesh) -> f64 {
    1e-4 * sm.mesh.bbox_diagonal()
}

/// Distance from x to a generalized sphere, computed from centre and radius (planes: from ψ).
fn dist(s: &Sphere, x: DVec3) -> f64 {
    if s.a == 0.0 {
        s.eval(x).abs() / s.b.length()
    } else {
        ((x - s.center().unwrap()).length() - s.signed_radius().unwrap().abs()).abs()
    }
}

/// Edge (sorted vertex pair) -> [(panel index, side)].
fn edge_map(panels: &[Panel]) -> HashMap<(u32, u32), Vec<(usize, usize)>> {
    let mut m: HashMap<(u32, u32), Vec<(usize, usize)>> = HashMap::new();
    for (i, p) in panels.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (p.corners[k], p.corners[(k + 1) % 3]);
            m.entry((a.min(b), a.max(b))).or_default().push((i, k));
        }
    }
    m
}

fn arc_points(p: &Panel, k: usize) -> Vec<DVec3> {
    p.arc_vertices[k].iter().map(|&i| p.positions[i as usize]).collect()
}

fn support_for(sm: &SphereMesh, m: DVec3, depth: f64) -> SupportStructure {
    let axes: Vec<(DVec3, DVec3)> = sm.mesh.positions.iter().map(|&v| (v, (m - v).normalize())).collect();
    let n = axes.len();
    SupportStructure {
        node_axes: NodeAxes { axes, second_points: vec![None; n], from_spheres: vec![false; n] },
        depth,
        axis_length: 0.1,
        ..SupportStructure::default()
    }
}

/// JSON trees equal up to 1 ulp-ish in numbers (serde_json's default float parser is not
/// correctly rounded).
fn assert_close(a: &Value, b: &Value) {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            assert!((x - y).abs() <= 1e-15 * x.abs().max(y.abs()), "{x} vs {y}");
        }
        (Value::Array(x), Value::Array(y)) => {
            assert_eq!(x.len(), y.len());
            x.iter().zip(y).for_each(|(x, y)| assert_close(x, y));
        }
        (Value::Object(x), Value::Object(y)) => {
            assert_eq!(x.keys().collect::<Vec<_>>(), y.keys().collect::<Vec<_>>());
            x.iter().for_each(|(k, v)| assert_close(v, &y[k]));
        }
        _ => assert_eq!(a, b),
    }
}

fn total_triangles(panels: &[Panel]) -> usize {
    panels.iter().map(|p| p.triangles.len()).sum()
}

// ---------------------------------------------------------------------------------------------
// Panels

#[test]
fn fixtures_are_what_they_claim() {
    for (name, sm) in all_fixtures() {
        let diag = sm.mesh.bbox_diagonal();
        for f in 0..sm.mesh.face_count() {
            let s = sm.face_spheres[f];
            assert!((s.discriminant() - 1.0).abs() < 1e-12, "{name}: face {f} not normalized");
            for v in tri(&sm, f) {
                assert!(dist(&s, v) < 1e-12 * diag, "{name}: face {f} sphere misses a vertex");
            }
        }
    }
    // Orthogonality to Ω: |c − m|² − r² = R².
    for (sm, m, r2) in [(omega_real(), M_REAL, R2_REAL), (omega_imaginary(), M_IMAG, -3.2), (omega_stress(), M_STRESS, 2.0)] {
        for s in &sm.face_spheres {
            let (c, r) = (s.center().unwrap(), s.signed_radius().unwrap());
            assert!(((c - m).length_squared() - r * r - r2).abs() < 1e-9);
        }
    }
    let radii: Vec<f64> = omega_real().face_spheres.iter().map(|s| s.signed_radius().unwrap().abs()).collect();
    assert!(radii.iter().all(|&r| r > 1.0 && r < 4.0), "{radii:?}");
}

#[test]
fn panel_vertices_lie_on_their_spheres() {
    for (name, sm) in all_fixtures() {
        let diag = sm.mesh.bbox_diagonal();
        let panels = build_panels(&sm, tol_for(&sm));
        assert_eq!(panels.len(), sm.mesh.face_count());
        for (i, p) in panels.iter().enumerate() {
            assert_eq!(p.face, i);
            assert_eq!(p.corners, sm.mesh.faces[i].corners());
            assert_eq!(p.positions[0..3].to_vec(), sm.mesh.face_points(i));
            assert!(!p.triangles.is_empty());
            for &x in &p.positions {
                let d = dist(&p.sphere, x);
                assert!(d <= 1e-9 * diag, "{name}: panel {i}: vertex {x} is {d:e} off its sphere");
            }
            for t in &p.triangles {
                assert!(t.iter().all(|&v| (v as usize) < p.positions.len()));
                assert!(t[0] != t[1] && t[1] != t[2] && t[0] != t[2]);
                // Oriented like the face.
                let [a, b, c] = t.map(|v| p.positions[v as usize]);
                let n = (b - a).cross(c - a).normalize();
                let outward = p.normal_at((a + b + c) / 3.0);
                assert!(n.dot(outward) > 0.0, "{name}: panel {i}: folded triangle ({})", n.dot(outward));
            }
            assert!(p.area > 0.0);
            assert_eq!(p.folded_triangles(), 0);
        }
    }
}

#[test]
fn arcs_lie_on_both_neighbouring_spheres() {
    for (name, sm) in all_fixtures() {
        let diag = sm.mesh.bbox_diagonal();
        let panels = build_panels(&sm, tol_for(&sm));
        for (edge, inc) in edge_map(&panels) {
            for &(i, k) in &inc {
                let arc = &panels[i].arcs[k];
                let (a, b) = (panels[i].corners[k], panels[i].corners[(k + 1) % 3]);
                assert_eq!(arc.from, sm.mesh.positions[a as usize]);
                assert_eq!(arc.to, sm.mesh.positions[b as usize]);
                assert!((arc.circle.normal.length() - 1.0).abs() < 1e-12);
                for x in arc_points(&panels[i], k) {
                    for &(j, _) in &inc {
                        let d = dist(&panels[j].sphere, x);
                        assert!(d <= 1e-9 * diag, "{name}: edge {edge:?}: arc point {d:e} off panel {j}'s sphere");
                    }
                    // And on the arc's own circle (or its line).
                    let c = arc.circle;
                    let rel = x - c.center;
                    assert!(rel.dot(c.normal).abs() <= 1e-9 * diag, "{name}: arc point off the circle plane");
                    if !arc.is_straight() {
                        assert!(((rel - rel.dot(c.normal) * c.normal).length() - c.radius).abs() <= 1e-9 * diag);
                    }
                }
            }
        }
    }
}

#[test]
fn arc_planes_pass_through_m_or_contain_the_axis() {
    // Spheres orthogonal to Ω have their radical planes through m; the boundary rule puts m in the
    // plane too. With Ω at infinity, every arc plane contains the direction a.
    for (sm, m) in [(omega_real(), M_REAL), (omega_imaginary(), M_IMAG), (omega_stress(), M_STRESS)] {
        let diag = sm.mesh.bbox_diagonal();
        let panels = build_panels(&sm, tol_for(&sm));
        for p in &panels {
            for arc in &p.arcs {
                assert!(!arc.is_straight());
                let off = (m - arc.circle.center).dot(arc.circle.normal).abs();
                assert!(off <= 1e-9 * diag, "arc plane misses m by {off:e}");
            }
        }
    }
    let (sm, a) = omega_at_infinity();
    for p in build_panels(&sm, tol_for(&sm)) {
        for arc in &p.arcs {
            assert!(arc.circle.normal.dot(a).abs() < 1e-9, "arc plane does not contain the axis");
        }
    }
}

#[test]
fn adjacent_panels_share_boundary_vertices() {
    for (name, sm) in all_fixtures() {
        let panels = build_panels(&sm, tol_for(&sm));
        let mut interior = 0;
        for (edge, inc) in edge_map(&panels) {
            for &(i, k) in &inc {
                let pts = arc_points(&panels[i], k);
                assert_eq!(pts[0], panels[i].positions[k]);
                assert_eq!(*pts.last().unwrap(), panels[i].positions[(k + 1) % 3]);
            }
            if let [(i, k), (j, l)] = inc[..] {
                interior += 1;
                let a = arc_points(&panels[i], k);
                let mut b = arc_points(&panels[j], l);
                b.reverse();
                assert_eq!(a, b, "{name}: edge {edge:?}: panels {i} and {j} disagree on their arc points");
                // Same circle, opposite orientation.
                let (ca, cb) = (panels[i].arcs[k].circle, panels[j].arcs[l].circle);
                assert_eq!(ca.normal, -cb.normal);
                assert_eq!(ca.radius, cb.radius);
            }
        }
        assert!(interior > 0);
    }
}

#[test]
fn chord_error_is_within_tolerance() {
    for (name, sm) in all_fixtures() {
        let diag = sm.mesh.bbox_diagonal();
        let mut counts = Vec::new();
        for rel in [1e-2, 1e-3, 1e-4, if name == "omega_stress" { 3e-5 } else { 1e-5 }] {
            let tol = rel * diag;
            let panels = build_panels(&sm, tol);
            for (i, p) in panels.iter().enumerate() {
                let ce = p.chord_error();
                assert!(ce <= tol, "{name}: panel {i}: chord error {ce:e} > {tol:e}");
                // Sampled: centroids, edge midpoints and a few more barycentric points.
                for t in &p.triangles {
                    let [a, b, c] = t.map(|v| p.positions[v as usize]);
                    for (u, v) in [(1.0 / 3.0, 1.0 / 3.0), (0.5, 0.0), (0.0, 0.5), (0.5, 0.5), (0.2, 0.6), (0.6, 0.2)] {
                        let x = a + u * (b - a) + v * (c - a);
                        let d = dist(&p.sphere, x);
                        assert!(d <= tol * (1.0 + 1e-9), "{name}: panel {i}: sample {d:e} off the sphere > {tol:e}");
                        assert!(d <= ce * (1.0 + 1e-6) + 1e-12 * diag, "{name}: chord_error underestimates");
                    }
                }
                // Boundary segments against their true arcs.
                for k in 0..3 {
                    let arc = &p.arcs[k];
                    let pts = arc_points(p, k);
                    let n = pts.len() - 1;
                    for s in 0..n {
                        let on_arc = arc.point((s as f64 + 0.5) / n as f64);
                        let chord_mid = 0.5 * (pts[s] + pts[s + 1]);
                        let d = on_arc.distance(chord_mid);
                        assert!(d <= tol, "{name}: panel {i} arc {k}: segment sagitta {d:e} > {tol:e}");
                    }
                }
            }
            counts.push(total_triangles(&panels));
        }
        if name == "flat" {
            assert!(counts.iter().all(|&c| c == sm.mesh.face_count()), "{name}: {counts:?}");
        } else {
            assert!(counts.windows(2).all(|w| w[0] <= w[1]), "{name}: {counts:?}");
            assert!(counts[3] > counts[0], "{name}: {counts:?}");
        }
    }
}

#[test]
fn flat_panels_stay_flat() {
    let sm = flat();
    let panels = build_panels(&sm, tol_for(&sm));
    let mut area = 0.0;
    for p in &panels {
        assert!(p.is_planar());
        assert!(p.arcs.iter().all(|a| a.is_straight()));
        assert!(p.positions.iter().all(|x| x.z == 0.0));
        assert_eq!(p.triangles.len(), 1);
        assert_eq!(p.chord_error(), 0.0);
        area += p.area;
    }
    assert!((area - 2.0 * 1.0).abs() < 1e-12, "{area}");
}

#[test]
fn plane_panels_next_to_spheres_have_circular_edges_in_their_plane() {
    let sm = mixed();
    let diag = sm.mesh.bbox_diagonal();
    let panels = build_panels(&sm, tol_for(&sm));
    let edges = edge_map(&panels);
    let p = &panels[PLANAR_FACE];
    assert!(p.is_planar());
    let n = p.sphere.b;
    let mut curved = 0;
    for k in 0..3 {
        let (a, b) = (p.corners[k], p.corners[(k + 1) % 3]);
        let inc = &edges[&(a.min(b), a.max(b))];
        if inc.len() == 2 {
            // Neighbour is a sphere: the edge is a proper circle arc lying in the plane.
            assert!(!p.arcs[k].is_straight());
            assert!(p.arcs[k].circle.normal.cross(n).length() < 1e-9);
            curved += 1;
        } else {
            // Boundary edge: the rule plane through m is the face plane itself: straight.
            assert!(p.arcs[k].is_straight());
        }
        for x in arc_points(p, k) {
            assert!((x - p.positions[0]).dot(n).abs() < 1e-12 * diag);
        }
    }
    assert_eq!(curved, 2);
    for x in &p.positions {
        assert!((*x - p.positions[0]).dot(n).abs() < 1e-12 * diag);
    }
}

/// Spherical excess of the geodesic triangle with unit corners a, b, c.
fn excess(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    2.0 * a.dot(b.cross(c)).abs().atan2(1.0 + a.dot(b) + b.dot(c) + c.dot(a))
}

#[test]
fn cap_panels_are_geodesic_triangles_with_the_right_area() {
    // All face spheres are the same sphere: the intersection is undefined and the boundary rule
    // through the centre gives great circles; each panel is a geodesic triangle.
    let sm = cap();
    let tol = tol_for(&sm);
    let panels = build_panels(&sm, tol);
    let (mut area, mut exact) = (0.0, 0.0);
    for p in &panels {
        for arc in &p.arcs {
            assert!((arc.circle.radius - R_CAP).abs() < 1e-12);
            assert!(arc.circle.center.length() < 1e-12);
        }
        let [a, b, c] = [p.positions[0], p.positions[1], p.positions[2]].map(|x| x / R_CAP);
        let e = R_CAP * R_CAP * excess(a, b, c);
        // Flat triangles may be a little larger or smaller than their geodesic counterparts
        // (skinny ones near their circumcircle project smaller): compare at O(tol/R).
        assert!((p.area - e).abs() <= e * 4.0 * tol / R_CAP, "{} vs {e}", p.area);
        area += p.area;
        exact += e;
    }
    assert!((area - exact).abs() <= exact * 4.0 * tol / R_CAP);
}

#[test]
fn nearly_flat_spheres_keep_precision() {
    // Face spheres with radii around 1e7 (centres far away): vertices still on their spheres.
    let mesh = grid(3, |x, y| DVec3::new(x, y, 1e-8 * (x * x + y * y)));
    // R² = 0: every face sphere passes through m, 5e7 above the grid.
    let m = DVec3::new(0.0, 0.0, 5e7);
    let omega = AbsoluteSphere::Sphere { center: m, r2: 0.0 };
    let face_spheres = (0..mesh.face_count()).map(|f| orient(sphere_orthogonal(mesh.face_points(f), &omega), &mesh, f)).collect();
    let sm = SphereMesh::new(mesh, face_spheres, BoundaryArcRule::Through(m));
    let diag = sm.mesh.bbox_diagonal();
    let panels = build_panels(&sm, tol_for(&sm));
    for p in &panels {
        assert!(p.sphere.signed_radius().unwrap().abs() > 1e6);
        for &x in &p.positions {
            let d = 2.0 * p.sphere.eval(x).abs();
            assert!(d < 1e-9 * diag, "{d:e}");
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Closest points

#[test]
fn closest_point_queries_match_brute_force() {
    let sm = omega_real();
    let bvh = TriangleBvh::new(&sm.mesh.triangulated());
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut rnd = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    for _ in 0..500 {
        let p = DVec3::new(1.5 * rnd(), 1.5 * rnd(), 0.3 + rnd());
        let h = bvh.closest_point(p).unwrap();
        let g = closest_point_brute_force(&sm.mesh.triangulated(), p).unwrap();
        assert!((h.distance - g.distance).abs() <= 1e-15, "{} vs {}", h.distance, g.distance);
        assert!((h.distance - h.point.distance(p)).abs() < 1e-15);
    }
    // Points on the mesh are at distance 0.
    for f in 0..sm.mesh.face_count() {
        let [a, b, c] = tri(&sm, f);
        assert!(bvh.distance((a + b + c) / 3.0) < 1e-15);
    }
}

// ---------------------------------------------------------------------------------------------
// Support structure

/// The support elements of a sphere mesh with the given node axes, cut from its panels' arcs.
fn elements(sm: &SphereMesh, panels: &[Panel], support: &SupportStructure) -> Vec<SupportElement> {
    let topo = sm.topology();
    topo.edges()
        .iter()
        .enumerate()
        .filter_map(|(e, &[a, b])| {
            let (f, k) = topo.edge_faces(e)[0];
            let arc = panels[f as usize].arcs[k as usize];
            let (p, q) = (sm.mesh.positions[a as usize], sm.mesh.positions[b as usize]);
            let dirs = [support.node_axes.axes[a as usize].1, support.node_axes.axes[b as usize].1];
            (!arc.is_straight()).then(|| support_element([a, b], arc.circle, [p, q], dirs, support.depth)).flatten()
        })
        .collect()
}

/// The strips of `elements` along the panels' own arc points.
fn strips(sm: &SphereMesh, panels: &[Panel], elements: &[SupportElement]) -> SupportGeometry {
    let topo = sm.topology();
    support_strips(elements, |el| {
        let e = topo.edge_index(el.edge[0], el.edge[1])?;
        let (f, k) = topo.edge_faces(e)[0];
        let p = &panels[f as usize];
        let mut points = p.arc_points(k as usize);
        if p.corners[k as usize] != el.edge[0] {
            points.reverse();
        }
        Some(points)
    })
}

#[test]
fn support_strips_are_planar_and_bounded_by_the_node_axes() {
    let sm = omega_real();
    let diag = sm.mesh.bbox_diagonal();
    let depth = 0.03 * diag;
    let support = support_for(&sm, M_REAL, depth);
    let panels = build_panels(&sm, tol_for(&sm));
    let els = elements(&sm, &panels, &support);
    assert_eq!(els.len(), sm.topology().edges().len(), "every edge has its element");
    let geo = strips(&sm, &panels, &els);
    let edges = edge_map(&panels);
    let expected: usize = edges.values().map(|inc| 2 * (panels[inc[0].0].arc_vertices[inc[0].1].len() - 1)).sum();
    assert_eq!(geo.triangles.len(), expected);
    assert!(geo.triangles.iter().flatten().all(|&v| (v as usize) < geo.positions.len()));
    // Every arc point of the panels appears: the strips meet the panels exactly.
    let has = |x: DVec3| geo.positions.contains(&x);
    for p in &panels {
        for k in 0..3 {
            for x in arc_points(p, k) {
                assert!(has(x));
            }
        }
    }
    // Each element is bounded by the two node axes: its inner corners lie on them, toward the
    // support side, on the inner circle, and the strip reaches them.
    for el in &els {
        for (k, &v) in el.edge.iter().enumerate() {
            let (pv, d) = support.node_axes.axes[v as usize];
            let inner = el.corners[3 - k];
            assert!((inner - pv).cross(d).length() < 1e-9 * diag, "inner corner off the node axis");
            assert!((inner - pv).dot(d) > 0.0, "inner corner on the wrong side");
            let ic = el.inner_circle;
            assert!(((inner - ic.center).length() - ic.radius).abs() < 1e-9 * diag, "inner corner off the inner circle");
            assert!(has(inner));
        }
        // The inner arc is the concentric circle a depth inside the outer one.
        assert!((el.inner_circle.center - el.circle.center).length() < 1e-9 * diag);
        assert!(((el.circle.radius - el.inner_circle.radius).abs() - depth).abs() < 1e-9 * diag);
    }
    // Planarity: every triangle lies in the plane of the arc it hangs from (which contains m).
    for t in &geo.triangles {
        let [a, b, c] = t.map(|v| geo.positions[v as usize]);
        let n = (b - a).cross(c - a);
        if n.length() > 1e-12 {
            let n = n.normalize();
            assert!((M_REAL - a).dot(n).abs() < 1e-9 * diag, "support strip not in a plane through m");
        }
    }
    // No depth, no elements.
    assert!(elements(&sm, &panels, &SupportStructure { depth: 0.0, ..support.clone() }).is_empty());
    let segs = support.axis_segments();
    assert_eq!(segs.len(), sm.mesh.vertex_count());
    for (s, (v, _)) in segs.iter().zip(&support.node_axes.axes) {
        assert!((s.0.distance(s.1) - 0.1).abs() < 1e-12 && s.0 == *v);
    }
}

// ---------------------------------------------------------------------------------------------
// GLB

struct Scene {
    sm: SphereMesh,
    panels: Vec<Panel>,
    support: SupportGeometry,
    axes: Vec<(DVec3, DVec3)>,
    extras: Value,
}

fn scene() -> Scene {
    let sm = omega_real();
    let diag = sm.mesh.bbox_diagonal();
    let panels = build_panels(&sm, tol_for(&sm));
    let st = support_for(&sm, M_REAL, 0.03 * diag);
    let support = strips(&sm, &panels, &elements(&sm, &panels, &st));
    let axes = SupportStructure { axis_length: 0.1 * diag, ..st }.axis_segments();
    let extras = absolute_sphere_extras(&AbsoluteSphere::Sphere { center: M_REAL, r2: R2_REAL });
    Scene { sm, panels, support, axes, extras }
}

fn f32_at(bin: &[u8], at: usize) -> f32 {
    f32::from_le_bytes(bin[at..at + 4].try_into().unwrap())
}

#[test]
fn glb_structure() {
    let s = scene();
    let glb = write_glb(&s.panels, Some(&s.support), Some(&s.axes), None, s.extras.clone());
    // Header and chunks.
    assert_eq!(&glb[0..4], b"glTF");
    assert_eq!(u32::from_le_bytes(glb[4..8].try_into().unwrap()), 2);
    assert_eq!(u32::from_le_bytes(glb[8..12].try_into().unwrap()) as usize, glb.len());
    let jlen = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    assert_eq!(&glb[16..20], b"JSON");
    assert_eq!(jlen % 4, 0);
    let bstart = 20 + jlen;
    let blen = u32::from_le_bytes(glb[bstart..bstart + 4].try_into().unwrap()) as usize;
    assert_eq!(&glb[bstart + 4..bstart + 8], b"BIN\0");
    assert_eq!(blen % 4, 0);
    assert_eq!(bstart + 8 + blen, glb.len());
    let bin = &glb[bstart + 8..];
    let j = glb_json(&glb).unwrap();

    // Scene and named nodes.
    let nodes = j["nodes"].as_array().unwrap();
    let names: Vec<&str> = nodes.iter().map(|n| n["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["panels", "support", "node_axes"]);
    assert_eq!(j["scene"], 0);
    assert_eq!(j["scenes"][0]["nodes"], serde_json::json!([0, 1, 2]));
    let mesh_of = |name: &str| {
        let n = nodes.iter().find(|n| n["name"] == name).unwrap();
        &j["meshes"][n["mesh"].as_u64().unwrap() as usize]
    };
    // One primitive per panel.
    let prims = mesh_of("panels")["primitives"].as_array().unwrap();
    assert_eq!(prims.len(), s.panels.len());
    let ex = &nodes[0]["extras"];
    assert_eq!(ex["panel_count"], s.panels.len());
    assert_eq!(ex["panels"].as_array().unwrap().len(), s.panels.len());
    let p7 = &ex["panels"][7];
    let s7 = s.panels[7].sphere;
    assert_eq!(p7["a"].as_f64().unwrap(), s7.a);
    assert_eq!(p7["radius"].as_f64().unwrap(), s7.signed_radius().unwrap().abs());
    assert_eq!(p7["center"][2].as_f64().unwrap(), s7.center().unwrap().z);
    assert_eq!(j["asset"]["extras"]["absolute_sphere"]["r2"], R2_REAL);
    assert_eq!(j["asset"]["version"], "2.0");
    // Accessors: POSITION min/max match the f32 data; index counts match the panels.
    for (i, prim) in prims.iter().enumerate() {
        assert_eq!(prim["extras"]["panel"], i);
        let acc = &j["accessors"][prim["attributes"]["POSITION"].as_u64().unwrap() as usize];
        assert_eq!(acc["count"], s.panels[i].positions.len());
        let view = &j["bufferViews"][acc["bufferView"].as_u64().unwrap() as usize];
        let base = view["byteOffset"].as_u64().unwrap() as usize + acc["byteOffset"].as_u64().unwrap() as usize;
        for c in 0..3 {
            let vals: Vec<f32> = (0..s.panels[i].positions.len()).map(|k| f32_at(bin, base + 12 * k + 4 * c)).collect();
            let lo = vals.iter().copied().fold(f32::INFINITY, f32::min);
            let hi = vals.iter().copied().fold(f32::NEG_INFINITY, f32::max);
            // (serde_json's default float parsing may be 1 ulp off in f64; exact in f32.)
            assert_eq!(acc["min"][c].as_f64().unwrap() as f32, lo);
            assert_eq!(acc["max"][c].as_f64().unwrap() as f32, hi);
        }
        let idx = &j["accessors"][prim["indices"].as_u64().unwrap() as usize];
        assert_eq!(idx["count"], 3 * s.panels[i].triangles.len());
        assert_eq!(prim["mode"], 4);
    }
    let axes = &mesh_of("node_axes")["primitives"][0];
    assert_eq!(axes["mode"], 1);
    assert_eq!(j["accessors"][axes["attributes"]["POSITION"].as_u64().unwrap() as usize]["count"], 2 * s.axes.len());
    for v in j["bufferViews"].as_array().unwrap() {
        assert_eq!(v["byteOffset"].as_u64().unwrap() % 4, 0);
    }
    assert_eq!(j["buffers"][0]["byteLength"], blen);

    // Without support and axes: only the panels node; without panels: an empty panels node.
    let only = glb_json(&write_glb(&s.panels, None, None, None, Value::Null)).unwrap();
    assert_eq!(only["nodes"].as_array().unwrap().len(), 1);
    assert!(only["asset"].get("extras").is_none());
    let empty = write_glb(&[], None, None, None, Value::Null);
    assert_eq!(empty.len() % 4, 0);
    assert_eq!(glb_json(&empty).unwrap()["nodes"][0]["extras"]["panel_count"], 0);
}

#[test]
fn glb_reimports_with_the_panel_triangles() {
    let s = scene();
    let n_panel = total_triangles(&s.panels);
    let panels_only = write_glb(&s.panels, None, None, None, s.extras.clone());
    let im = import_mesh(&panels_only, "panels.glb").unwrap();
    assert_eq!(im.mesh.face_count(), n_panel, "notes: {:?}", im.notes);
    // Shared arc points weld: the result is one connected surface with as many vertices as
    // distinct points.
    let mut distinct: Vec<[u32; 3]> =
        s.panels.iter().flat_map(|p| p.positions.iter().map(|x| [x.x as f32, x.y as f32, x.z as f32].map(f32::to_bits))).collect();
    distinct.sort_unstable();
    distinct.dedup();
    assert_eq!(im.mesh.vertex_count(), distinct.len());

    let full = write_glb(&s.panels, Some(&s.support), Some(&s.axes), None, s.extras.clone());
    let im = import_mesh(&full, "panels.glb").unwrap();
    assert_eq!(im.mesh.face_count(), n_panel + s.support.triangles.len(), "notes: {:?}", im.notes);
    // Panel primitives counted from the JSON chunk.
    let j = glb_json(&full).unwrap();
    let panels_mesh = j["nodes"][0]["mesh"].as_u64().unwrap() as usize;
    assert_eq!(j["meshes"][panels_mesh]["primitives"].as_array().unwrap().len(), s.sm.mesh.face_count());
}

#[test]
fn glb_passes_the_khronos_validator() {
    let s = scene();
    let dir = temp_dir("validator");
    let cases = [
        ("full.glb", write_glb(&s.panels, Some(&s.support), Some(&s.axes), None, s.extras.clone())),
        ("panels.glb", write_glb(&s.panels, None, None, None, Value::Null)),
        ("flat.glb", {
            let f = flat();
            write_glb(&build_panels(&f, tol_for(&f)), None, None, None, Value::Null)
        }),
        ("empty.glb", write_glb(&[], None, None, None, Value::Null)),
    ];
    for (name, bytes) in cases {
        let path = dir.join(name);
        std::fs::write(&path, &bytes).unwrap();
        let (ok, summary) = khronos_validate(&path);
        eprintln!("{name}: {}", serde_json::to_string(&summary).unwrap());
        assert!(ok && summary["numErrors"] == 0, "{name}: the validator reports errors: {summary:#}");
        assert_eq!(summary["numWarnings"], 0, "{name}: {summary:#}");
    }
    // The validator does catch a broken file (so a pass means something).
    let mut bad = write_glb(&s.panels, None, None, None, Value::Null);
    let jlen = u32::from_le_bytes(bad[12..16].try_into().unwrap()) as usize;
    bad.truncate(20 + jlen + 8 + 16);
    let n = bad.len() as u32;
    bad[8..12].copy_from_slice(&n.to_le_bytes());
    let path = dir.join("broken.glb");
    std::fs::write(&path, &bad).unwrap();
    let (ok, summary) = khronos_validate(&path);
    assert!(!ok && summary["numErrors"].as_u64().unwrap() > 0, "{summary:#}");
    let _ = std::fs::remove_dir_all(&dir);
}

// ---------------------------------------------------------------------------------------------
// OBJ

#[test]
fn obj_has_groups_per_kind_and_reimports() {
    let s = scene();
    let text = write_obj(&s.panels, Some(&s.support), Some(&s.axes));
    let lines: Vec<&str> = text.lines().collect();
    for o in ["o panels", "o support", "o node_axes", "g support", "g node_axes"] {
        assert_eq!(lines.iter().filter(|l| **l == o).count(), 1, "{o}");
    }
    for p in &s.panels {
        assert!(lines.contains(&format!("g panel_{}", p.face).as_str()));
    }
    assert_eq!(lines.iter().filter(|l| l.starts_with("l ")).count(), s.axes.len());
    let order: Vec<usize> = ["o panels", "o support", "o node_axes"].iter().map(|o| lines.iter().position(|l| l == o).unwrap()).collect();
    assert!(order.windows(2).all(|w| w[0] < w[1]));
    // Re-import: panel triangles (+ support), lines skipped.
    let n_panel = total_triangles(&s.panels);
    let im = import_mesh(write_obj(&s.panels, None, None).as_bytes(), "panels.obj").unwrap();
    assert_eq!(im.mesh.face_count(), n_panel);
    let im = import_mesh(text.as_bytes(), "panels.obj").unwrap();
    assert_eq!(im.mesh.face_count(), n_panel + s.support.triangles.len());
    assert!(im.notes.iter().any(|n| n.contains("line")), "{:?}", im.notes);
    // Coordinates round-trip exactly (shortest f64 formatting).
    assert_eq!(lines[1..3], ["o panels", "g panel_0"]);
    let v: Vec<f64> = lines[3].split_whitespace().skip(1).map(|t| t.parse().unwrap()).collect();
    assert_eq!(DVec3::new(v[0], v[1], v[2]), s.panels[0].positions[0]);
}

// ---------------------------------------------------------------------------------------------
// Schedule

#[test]
fn schedule_csv_and_json() {
    let sm = mixed();
    let diag = sm.mesh.bbox_diagonal();
    let panels = build_panels(&sm, tol_for(&sm));
    let sched = build_schedule(&panels, &reference_of(&sm), 1e-3);
    assert_eq!(sched.panel_count, panels.len());
    assert_eq!(sched.planar_panels, 1);

    // CSV: header plus one row per panel, same column count everywhere.
    let csv = sched.to_csv();
    let rows: Vec<&str> = csv.lines().collect();
    assert_eq!(rows.len(), panels.len() + 1);
    assert_eq!(rows[0], PanelSchedule::csv_header(3));
    let header: Vec<&str> = rows[0].split(',').collect();
    for col in
        ["id", "v0_id", "v2_z", "sphere_center_x", "sphere_radius", "plane_normal_z", "edge0_radius", "edge2_normal_z", "area", "max_deviation"]
    {
        assert!(header.contains(&col), "{col}");
    }
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    for (i, row) in rows[1..].iter().enumerate() {
        let cells: Vec<&str> = row.split(',').collect();
        assert_eq!(cells.len(), header.len(), "row {i}");
        assert_eq!(cells[col("id")].parse::<usize>().unwrap(), i);
        assert_eq!(cells[col("v1_id")].parse::<u32>().unwrap(), panels[i].corners[1]);
        assert_eq!(cells[col("v1_x")].parse::<f64>().unwrap(), panels[i].positions[1].x);
        let planar = i == PLANAR_FACE;
        assert_eq!(cells[col("sphere_radius")].is_empty(), planar, "row {i}");
        assert_eq!(cells[col("plane_normal_x")].is_empty(), !planar, "row {i}");
        if !planar {
            let r: f64 = cells[col("sphere_radius")].parse().unwrap();
            assert_eq!(r, panels[i].sphere.signed_radius().unwrap().abs());
        }
        for k in 0..3 {
            let cell = cells[col(&format!("edge{k}_radius"))];
            assert_eq!(cell.is_empty(), panels[i].arcs[k].is_straight(), "row {i} edge {k}");
            if !cell.is_empty() {
                assert_eq!(cell.parse::<f64>().unwrap(), panels[i].arcs[k].circle.radius);
            }
        }
        assert_eq!(cells[col("area")].parse::<f64>().unwrap(), panels[i].area);
        assert!(cells[col("max_deviation")].parse::<f64>().unwrap() >= 0.0);
    }

    // JSON parses and round-trips.
    let text = sched.to_json();
    let v: Value = serde_json::from_str(&text).unwrap();
    assert_eq!(v["panels"].as_array().unwrap().len(), panels.len());
    assert_eq!(v["distinct_radii"], sched.distinct_radii);
    let p0 = &v["panels"][0];
    assert!(p0["sphere"]["radius"].is_null() && p0["sphere"]["plane"] == true);
    assert_eq!(p0["sphere"]["normal"].as_array().unwrap().len(), 3);
    assert_eq!(p0["edges"].as_array().unwrap().len(), 3);
    assert_eq!(p0["edges"][0]["from"], panels[0].corners[0]);
    let back: PanelSchedule = serde_json::from_str(&text).unwrap();
    assert_close(&serde_json::to_value(&back).unwrap(), &serde_json::to_value(&sched).unwrap());

    // Deviation: positive, small, and matching a brute-force evaluation.
    assert!(sched.max_deviation > 0.0 && sched.max_deviation_relative < 0.05);
    assert_eq!(sched.max_deviation_relative, sched.max_deviation / diag);
    assert_eq!(max_distance_to_reference(&panels, &TriangleBvh::new(&sm.mesh.triangulated()), diag), sched.max_deviation_relative);
    // Every panel's: the searches started from the last hit and the skipped samples change
    // nothing.
    let bvh = TriangleBvh::new(&sm.mesh.triangulated());
    for (k, p) in panels.iter().enumerate() {
        let brute = panel_samples(p).into_iter().map(|x| closest_point_brute_force(&sm.mesh.triangulated(), x).unwrap().distance).fold(0.0, f64::max);
        assert_eq!(max_deviation(p, &bvh), brute, "panel {k}");
        assert_eq!(sched.panels[k].max_deviation, brute, "panel {k}");
    }
}

#[test]
fn a_panel_past_the_sample_cap_is_measured_on_an_even_subset() {
    // The cap's panels at a chord tolerance of 1e-7 of the diagonal: tessellations of several
    // thousand points, as a degenerate panel has at the default tolerance.
    let sm = cap();
    let diag = sm.mesh.bbox_diagonal();
    let panels = build_panels(&sm, 1e-7 * diag);
    let bvh = TriangleBvh::new(&sm.mesh.triangulated());
    let dense: Vec<&Panel> = panels.iter().filter(|p| p.positions.len() + p.triangles.len() > 2 * MAX_SAMPLES).collect();
    assert!(!dense.is_empty(), "{:?}", panels.iter().map(|p| p.positions.len()).collect::<Vec<_>>());
    for p in dense {
        let samples = panel_samples(p);
        assert!(samples.len() <= MAX_SAMPLES + 2 + p.arcs.len() * (ARC_SEGMENTS + 1), "{} samples", samples.len());
        // Every tessellation vertex against the thinned measure: the face's sagitta either way.
        let every = p.positions.iter().map(|x| bvh.closest_point(*x).unwrap().distance).fold(0.0, f64::max);
        let thinned = max_deviation(p, &bvh);
        assert!((thinned - every).abs() <= 0.02 * every, "thinned {thinned:e}, every vertex {every:e}");
    }
}

#[test]
fn deviation_from_the_reference() {
    // A flat panel set against its own reference: 0.
    let f = flat();
    let panels = build_panels(&f, tol_for(&f));
    assert!(max_distance_to_reference(&panels, &TriangleBvh::new(&f.mesh.triangulated()), f.mesh.bbox_diagonal()) < 1e-15);
    // The cap against its inscribed triangle mesh: the panels bulge out by about the face
    // sagitta, never more than the largest face chord error.
    let sm = cap();
    let panels = build_panels(&sm, tol_for(&sm));
    let bound = (0..sm.mesh.face_count())
        .map(|f| {
            let [a, b, c] = tri(&sm, f);
            triangle_chord_error(&sm.face_spheres[f], a, b, c)
        })
        .fold(0.0, f64::max);
    let bvh = TriangleBvh::new(&sm.mesh.triangulated());
    let dev = panels.iter().map(|p| max_deviation(p, &bvh)).fold(0.0, f64::max);
    assert!(dev > 0.2 * bound && dev <= bound * (1.0 + 1e-9), "{dev} vs {bound}");
}

#[test]
fn distinct_radii_counting() {
    assert_eq!(count_distinct_radii([Some(1.0), Some(1.0004), Some(-1.0), Some(2.0)], 1e-3), 2);
    assert_eq!(count_distinct_radii([Some(1.0), Some(1.0004), Some(2.0)], 1e-4), 3);
    assert_eq!(count_distinct_radii([Some(1.0), None, None, Some(f64::INFINITY)], 0.1), 2);
    assert_eq!(count_distinct_radii([Some(1.0), Some(1.0 + 1e-15)], 0.0), 2);
    assert_eq!(count_distinct_radii(Vec::<Option<f64>>::new(), 1.0), 0);
    // The cap: one radius; Ω meshes: many, fewer with a coarser tolerance.
    let sm = cap();
    let panels = build_panels(&sm, tol_for(&sm));
    assert_eq!(build_schedule(&panels, &reference_of(&sm), 1e-6).distinct_radii, 1);
    let sm = omega_real();
    let panels = build_panels(&sm, tol_for(&sm));
    let fine = build_schedule(&panels, &reference_of(&sm), 1e-9).distinct_radii;
    let coarse = build_schedule(&panels, &reference_of(&sm), 0.5).distinct_radii;
    assert!(fine > coarse && coarse >= 1 && fine <= panels.len(), "{fine} {coarse}");
    let f = flat();
    assert_eq!(build_schedule(&build_panels(&f, tol_for(&f)), &reference_of(&f), 1e-3).distinct_radii, 1);
}

#[test]
fn panel_files_are_the_four_files_and_the_report_follows() {
    let s = scene();
    let sched = build_schedule(&s.panels, &reference_of(&s.sm), 1e-4);
    let glb = write_glb(&s.panels, Some(&s.support), Some(&s.axes), None, s.extras.clone());
    let obj = write_obj(&s.panels, Some(&s.support), Some(&s.axes));
    let mut files = panel_files(glb, obj, &sched);
    files.push(report_file(&Report::new("st-support")));
    let names: Vec<&str> = files.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(names, ["panels.glb", "panels.obj", "panels.csv", "panels.json", "report.json"]);
    assert!(files.iter().all(|f| !f.bytes.is_empty()));
    let json: Value = serde_json::from_slice(&files[3].bytes).unwrap();
    assert_close(&json, &serde_json::to_value(&sched).unwrap());
    let csv = std::str::from_utf8(&files[2].bytes).unwrap();
    assert_eq!(csv.lines().count(), s.panels.len() + 1);
    assert_eq!(glb_json(&files[0].bytes).unwrap()["nodes"].as_array().unwrap().len(), 3);
    assert_eq!(Report::from_json(std::str::from_utf8(&files[4].bytes).unwrap()).unwrap().method, "st-support");
}

// ---------------------------------------------------------------------------------------------
// report.json

/// A figure that cannot be measured (NaN) is written as null and read back as NaN, so a summary
/// with such a figure still reaches the app.
#[test]
fn sections_read_back_with_unmeasurable_figures() {
    use spherical_faces::sq::metrics::CongruenceFigures;
    use spherical_faces::sq::report::QuadMeshSection;
    use spherical_faces::sq::sq_mesh::SqMeshFigures;
    let mesh = SqMeshFigures { min_torsal_plane_angle_deg: f64::NAN, ..SqMeshFigures::default() };
    let back: SqMeshFigures = serde_json::from_str(&serde_json::to_string(&mesh).unwrap()).unwrap();
    assert!(back.min_torsal_plane_angle_deg.is_nan());
    let quads = QuadMeshSection {
        coverage: 0.5,
        mean_edge_torsal_angle_deg: f64::NAN,
        max_edge_torsal_angle_deg: f64::NAN,
        follows: Default::default(),
        singular_points_by_valence: [(3, 2)].into(),
        singular_vertices_by_valence: Default::default(),
    };
    let back: QuadMeshSection = serde_json::from_str(&serde_json::to_string(&quads).unwrap()).unwrap();
    assert!(back.mean_edge_torsal_angle_deg.is_nan() && back.coverage == 0.5);
    assert_eq!(back.singular_points_by_valence, quads.singular_points_by_valence);
    let c = CongruenceFigures { max_line_normal_angle_deg: f64::NAN, ..CongruenceFigures::default() };
    let back: CongruenceFigures = serde_json::from_str(&serde_json::to_string(&c).unwrap()).unwrap();
    assert!(back.max_line_normal_angle_deg.is_nan());
}

#[test]
fn report_schema() {
    let mut r = Report::new("st-support");
    r.input = InputCounts { vertices: 49, faces: 72 };
    r.output = OutputCounts { vertices: 49, faces: 72, panels: 72 };
    r.metrics = Some(PanelMetrics {
        mean_kink_angle_deg: 1.25,
        max_kink_angle_deg: 3.5,
        max_distance_to_reference: 2e-3,
        distinct_radii: 15,
        ..Default::default()
    });
    let omega: AbsoluteSphereSection = (&AbsoluteSphere::Sphere { center: M_STRESS, r2: 2.0 }).into();
    r.set_section(&serde_json::json!({ "absolute_sphere": omega, "max_node_axis_offset": 1e-13 }));
    r.add_timing("absolute_sphere", 1.5);
    r.add_timing("panels", 2.0);
    r.add_timing("panels", 1.0);
    let text = r.to_json();
    let v: Value = serde_json::from_str(&text).unwrap();
    let keys: Vec<&String> = v.as_object().unwrap().keys().collect();
    for k in ["schema", "method", "input", "output", "metrics", "st-support", "timings_ms"] {
        assert!(keys.iter().any(|x| *x == k), "{k}");
    }
    assert_eq!(v["schema"], REPORT_SCHEMA);
    assert_eq!(v["method"], "st-support");
    assert_eq!(v["output"]["panels"], 72);
    let section = &v["st-support"];
    assert_eq!(section["absolute_sphere"]["center"][2], M_STRESS.z);
    assert_eq!(section["absolute_sphere"]["at_infinity"], false);
    assert!(section["absolute_sphere"]["axis"].is_null());
    assert!(section["absolute_sphere"].get("d").is_none());
    assert_eq!(section["max_node_axis_offset"], 1e-13);
    let m = v["metrics"].as_object().unwrap();
    assert_eq!(m.len(), 7, "the shared section: {m:?}");
    assert_eq!(m["max_kink_angle_deg"], 3.5);
    assert_eq!(m["distinct_radii"], 15);
    assert!(!m.contains_key("max_node_axis_offset"), "a method's figure stays in its section");
    assert_eq!(v["timings_ms"]["panels"], 3.0);
    assert_close(&serde_json::to_value(Report::from_json(&text).unwrap()).unwrap(), &serde_json::to_value(&r).unwrap());
    // The section reads back as a type; a NaN written as null reads back as NaN.
    let back: Value = r.section().unwrap();
    assert_eq!(back["max_node_axis_offset"], 1e-13);
    let mut nan = r.clone();
    nan.metrics.as_mut().unwrap().max_kink_angle_deg = f64::NAN;
    let read = Report::from_json(&nan.to_json()).unwrap();
    assert!(read.metrics.unwrap().max_kink_angle_deg.is_nan());

    // Ω at infinity; a method without panels or a section.
    let inf: AbsoluteSphereSection = (&AbsoluteSphere::Plane { axis: DVec3::Z, d: 0.5 }).into();
    let v = serde_json::to_value(&inf).unwrap();
    assert!(v["center"].is_null() && v["r2"].is_null() && v["at_infinity"] == true);
    assert_eq!(v["axis"], serde_json::json!([0.0, 0.0, 1.0]));
    let plain = Report::new("other");
    let v: Value = serde_json::from_str(&plain.to_json()).unwrap();
    assert!(v.get("metrics").is_none() && v.get("other").is_none());

    let dir = temp_dir("report");
    let path = r.write(&dir).unwrap();
    assert_eq!(path, dir.join("report.json"));
    let back = Report::from_json(&std::fs::read_to_string(&path).unwrap()).unwrap();
    assert_close(&serde_json::to_value(back).unwrap(), &serde_json::to_value(&r).unwrap());
    let _ = std::fs::remove_dir_all(&dir);
}

/// The panels as drawn stay within their triangle budget, each on its sphere with its corners,
/// and panels within their share are drawn as measured.
#[test]
fn drawn_panels_are_bounded_and_stay_on_their_spheres() {
    let mut coarsened = 0;
    for (name, sm) in all_fixtures() {
        let panels = build_panels(&sm, tol_for(&sm));
        let total: usize = panels.iter().map(|p| p.triangles.len()).sum();
        assert!(matches!(display_panels(&panels, 10 * total), std::borrow::Cow::Borrowed(_)), "{name}: within the budget, as measured");
        let budget = total / 4;
        let drawn = display_panels(&panels, budget);
        let drawn_total: usize = drawn.iter().map(|p| p.triangles.len()).sum();
        // The per-panel share at level_cap, with its zippers: at most about 1.5 × the budget.
        assert!(drawn_total <= budget * 3 / 2 + 64 * panels.len(), "{name}: {drawn_total} triangles drawn for a budget of {budget}");
        if matches!(drawn, std::borrow::Cow::Owned(_)) {
            assert!(drawn_total < total, "{name}: {drawn_total} of {total}");
            coarsened += 1;
        }
        let diag = sm.mesh.bbox_diagonal();
        for (p, q) in panels.iter().zip(drawn.iter()) {
            assert_eq!(p.positions[..p.corners.len()], q.positions[..q.corners.len()], "{name}: corners kept");
            for &x in &q.positions {
                assert!(q.sphere.eval(x).abs() <= 1e-9 * diag.max(1.0), "{name}: a drawn point off its sphere by {:e}", q.sphere.eval(x));
            }
            assert_eq!(q.arc_vertices.len(), p.arc_vertices.len());
        }
    }
    assert!(coarsened >= 3, "only {coarsened} fixtures were drawn coarser");
}
