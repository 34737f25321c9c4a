#![cfg(not(target_arch = "wasm32"))] // native: reads ../shared
//! Panels for edge variant (b) (paper Fig. 12 bottom): every face sphere is cut by the bisecting
//! planes of the adjacent face planes, one arc per panel, small gaps between panels.
//!
//! Fixtures (sphere meshes built here, one face sphere per face through its three vertices):
//! - `common`: a spherical cap, every face sphere the cap's sphere (gaps 0);
//! - `perturbed`: the cap with its interior vertices moved, each face sphere the member of its
//!   vertices' pencil closest to the cap sphere (the spheres differ: gaps > 0);
//! - `mixed`: `perturbed` with every fifth face a plane (a = 0 exactly);
//! - `flat`: a planar grid with plane "spheres" (straight edges only).

mod common;

use std::collections::HashMap;

use glam::DVec3;
use serde_json::Value;
use spherical_faces::export::{build_schedule, write_glb, write_obj};
use spherical_faces::geometry::mesh::topology::Topology;
use spherical_faces::geometry::mesh::TriMesh;
use spherical_faces::geometry::sphere::Sphere;
use spherical_faces::import::import_mesh;
use spherical_faces::panels::arc::Arc;
use spherical_faces::panels::edge_arcs::EdgeArcs;
use spherical_faces::panels::gaps::{arc_gaps, max_arc_gap, EdgeGap, GAP_SAMPLES};
use spherical_faces::panels::panel::Panel;
use spherical_faces::panels::sphere_mesh::{BoundaryArcRule, SphereMesh};
use spherical_faces::panels::*;
use spherical_faces::reference::Reference;
use spherical_faces::rng::Rng;
use spherical_faces::samples;

/// The gaps of the panels of `sm` ([`arc_gaps`]).
fn gaps_of(sm: &SphereMesh, panels: &[Panel], samples: usize) -> Vec<EdgeGap> {
    arc_gaps(panels, sm.topology(), samples)
}

/// The largest gap of the panels of `sm` ([`max_arc_gap`]).
fn max_gap_of(sm: &SphereMesh, panels: &[Panel], samples: usize) -> f64 {
    max_arc_gap(panels, sm.topology(), samples).0
}

/// The test's own measure of the variant (b) gap, from the spheres alone: at 31 chord points
/// x₀ = p + t (q − p) of every interior edge, the line x₀ + h w in the bisecting plane (w ⟂ edge)
/// meets each sphere at the root h nearest the chord; the gap is the largest |h_f − h_g|.
fn gap_along_bisecting_lines(sm: &SphereMesh) -> f64 {
    let mesh = sm.mesh.triangulated();
    let hit = |s: &Sphere, x0: DVec3, w: DVec3| -> Option<f64> {
        let psi = s.eval(x0);
        let bq = (2.0 * s.a * x0 - s.b).dot(w);
        let disc = bq * bq - 4.0 * s.a * psi;
        if disc < 0.0 {
            return None;
        }
        let den = bq + bq.signum() * disc.sqrt();
        if den == 0.0 {
            return (psi == 0.0).then_some(0.0);
        }
        Some(-2.0 * psi / den)
    };
    let mut worst = 0.0f64;
    for ((a, b), [(f, _), (g, _)]) in interior_edges(&mesh) {
        let (p, q) = (mesh.positions[a as usize], mesh.positions[b as usize]);
        let e = (q - p).normalize_or_zero();
        let nsum = mesh.face_area_vector(f).normalize_or_zero() + mesh.face_area_vector(g).normalize_or_zero();
        let w = (nsum - nsum.dot(e) * e).normalize_or_zero();
        if w == DVec3::ZERO {
            continue;
        }
        for k in 1..GAP_SAMPLES - 1 {
            let x0 = p + (k as f64 / (GAP_SAMPLES - 1) as f64) * (q - p);
            if let (Some(hf), Some(hg)) = (hit(&sm.face_spheres[f], x0, w), hit(&sm.face_spheres[g], x0, w)) {
                worst = worst.max((hf - hg).abs());
            }
        }
    }
    worst
}

// ---------------------------------------------------------------------------------------------
// Fixtures

const CAP_RADIUS: f64 = 2.0;

fn cap() -> (TriMesh, Sphere) {
    let mesh = samples::sphere_cap(CAP_RADIUS, 1.6, 5);
    let theta_max = (1.6f64 / CAP_RADIUS).asin();
    let center = DVec3::new(0.0, 0.0, -CAP_RADIUS * theta_max.cos());
    (mesh, Sphere::from_center_radius(center, CAP_RADIUS).normalized())
}

/// Per face: the member of its vertices' pencil closest to `target` (max ⟨s, target⟩ over
/// cos θ s₀ + sin θ s₁), oriented like the face.
fn spheres_toward(mesh: &TriMesh, target: &Sphere) -> Vec<Sphere> {
    (0..mesh.face_count())
        .map(|f| {
            let [s0, s1] = Sphere::through_points_family(mesh.face_points(f));
            let th = s1.inversive_product(target).atan2(s0.inversive_product(target));
            let s = Sphere::combine(&s0, th.cos(), &s1, th.sin()).normalized();
            if th.cos() < 0.0 {
                s.flipped()
            } else {
                s
            }
        })
        .collect()
}

fn sphere_mesh(mesh: TriMesh, face_spheres: Vec<Sphere>) -> SphereMesh {
    SphereMesh::new(mesh, face_spheres, BoundaryArcRule::Parallel(DVec3::ZERO))
}

fn common() -> SphereMesh {
    let (mesh, s) = cap();
    let spheres = spheres_toward(&mesh, &s);
    sphere_mesh(mesh, spheres)
}

fn perturbed() -> SphereMesh {
    let (mut mesh, s) = cap();
    let topo = Topology::new(&mesh);
    let mut rng = Rng(7);
    for v in 0..mesh.vertex_count() {
        let d = rng.vec(0.04);
        if !topo.is_boundary_vertex(v) {
            mesh.positions[v] += d;
        }
    }
    let spheres = spheres_toward(&mesh, &s);
    sphere_mesh(mesh, spheres)
}

fn mixed() -> SphereMesh {
    let mut sm = perturbed();
    for f in (0..sm.mesh.face_count()).step_by(5) {
        let p0 = sm.mesh.face_points(f)[0];
        sm.face_spheres[f] = Sphere::plane(p0, sm.mesh.face_area_vector(f).normalize());
    }
    sm
}

fn flat() -> SphereMesh {
    let mesh = samples::plane_patch(2.0, 1.0, 6, 3);
    let spheres = (0..mesh.face_count()).map(|f| Sphere::plane(mesh.face_points(f)[0], DVec3::Z)).collect();
    sphere_mesh(mesh, spheres)
}

fn fixtures() -> Vec<(&'static str, SphereMesh)> {
    vec![("common", common()), ("perturbed", perturbed()), ("mixed", mixed()), ("flat", flat())]
}

fn diag(sm: &SphereMesh) -> f64 {
    sm.mesh.bbox_diagonal()
}

fn panels_b(sm: &SphereMesh) -> Vec<Panel> {
    build_panels_with(sm, 1e-4 * diag(sm), EdgeArcs::BisectingPlanes)
}

/// An interior edge (lo, hi) and its two (face, side) pairs, side k from corner k to corner k+1.
type InteriorEdge = ((u32, u32), [(usize, usize); 2]);

/// The interior edges of `mesh`, sorted.
fn interior_edges(mesh: &TriMesh) -> Vec<InteriorEdge> {
    let mut m: HashMap<(u32, u32), Vec<(usize, usize)>> = HashMap::new();
    for (f, t) in mesh.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            m.entry((a.min(b), a.max(b))).or_default().push((f, k));
        }
    }
    let mut v: Vec<_> = m.into_iter().filter(|(_, s)| s.len() == 2).map(|(e, s)| (e, [s[0], s[1]])).collect();
    v.sort_unstable_by_key(|(e, _)| *e);
    v
}

/// Unit normal of the bisecting plane of an interior edge, from the mesh alone: the plane through
/// the edge containing n_f + n_g.
fn bisecting_normal(mesh: &TriMesh, e: (u32, u32), f: usize, g: usize) -> DVec3 {
    let (p, q) = (mesh.positions[e.0 as usize], mesh.positions[e.1 as usize]);
    let d = mesh.face_area_vector(f).normalize() + mesh.face_area_vector(g).normalize();
    (q - p).cross(d).normalize()
}

fn max_residual(s: &Sphere, pts: impl IntoIterator<Item = DVec3>) -> f64 {
    pts.into_iter().map(|x| s.distance(x)).fold(0.0, f64::max)
}

// ---------------------------------------------------------------------------------------------
// Geometry

#[test]
fn tessellation_lies_on_the_face_spheres() {
    for (name, sm) in fixtures() {
        let d = diag(&sm);
        let panels = panels_b(&sm);
        assert_eq!(panels.len(), sm.mesh.face_count());
        let mut worst = 0.0f64;
        for p in &panels {
            // The panel sphere is the given face sphere (normalized), not a substitute.
            let given = sm.face_spheres[p.face].normalized();
            assert!((p.sphere.a - given.a).abs() <= 1e-12 * given.a.abs().max(1.0 / d), "{name}: sphere {}", p.face);
            worst = worst.max(max_residual(&p.sphere, p.positions.iter().copied()));
            for arc in &p.arcs {
                worst = worst.max(max_residual(&p.sphere, (0..=16).map(|j| arc.point(j as f64 / 16.0))));
            }
        }
        println!("{name}: max tessellation/arc distance to the face sphere = {:.3e} · diag", worst / d);
        assert!(worst <= 1e-9 * d, "{name}: {worst:e}");
    }
}

#[test]
fn interior_arcs_lie_in_the_bisecting_planes_and_end_at_the_vertices() {
    for (name, sm) in fixtures() {
        let d = diag(&sm);
        let mesh = &sm.mesh.triangulated();
        let panels = panels_b(&sm);
        let mut worst = 0.0f64;
        for (e, sides) in interior_edges(mesh) {
            let n = bisecting_normal(mesh, e, sides[0].0, sides[1].0);
            let p = mesh.positions[e.0 as usize];
            for (f, k) in sides {
                let panel = &panels[f];
                let arc = panel.arcs[k];
                let (c0, c1) = (panel.corners[k], panel.corners[(k + 1) % 3]);
                // Exact end points: the mesh vertices, bit for bit.
                assert_eq!(arc.from, mesh.positions[c0 as usize], "{name}");
                assert_eq!(arc.to, mesh.positions[c1 as usize], "{name}");
                let ids = &panel.arc_vertices[k];
                assert_eq!(panel.positions[ids[0] as usize], mesh.positions[c0 as usize]);
                assert_eq!(panel.positions[*ids.last().unwrap() as usize], mesh.positions[c1 as usize]);
                // Every arc point (tessellated and analytic) in the bisecting plane.
                let pts = ids.iter().map(|&i| panel.positions[i as usize]).chain((0..=16).map(|j| arc.point(j as f64 / 16.0)));
                for x in pts {
                    worst = worst.max((x - p).dot(n).abs());
                }
                // The circle's plane is that plane.
                assert!(arc.circle.normal.cross(n).length() < 1e-9, "{name}: edge {e:?}");
            }
        }
        println!("{name}: max distance of an interior arc point to its bisecting plane = {:.3e} · diag", worst / d);
        assert!(worst <= 1e-9 * d, "{name}: {worst:e}");
    }
}

#[test]
fn no_folded_triangles_and_chord_error_within_tolerance() {
    for (name, sm) in fixtures() {
        let tol = 1e-4 * diag(&sm);
        let panels = panels_b(&sm);
        let folded: usize = panels.iter().map(Panel::folded_triangles).sum();
        let err = panels.iter().map(Panel::chord_error).fold(0.0, f64::max);
        let tris: usize = panels.iter().map(|p| p.triangles.len()).sum();
        println!("{name}: {tris} triangles, folded {folded}, chord error {:.3} tol", err / tol);
        assert_eq!(folded, 0, "{name}");
        assert!(err <= tol, "{name}: {err:e} > {tol:e}");
        for p in &panels {
            // Every tessellation triangle non-degenerate, every position used.
            let mut used = vec![false; p.positions.len()];
            for t in &p.triangles {
                let [a, b, c] = t.map(|i| p.positions[i as usize]);
                assert!((b - a).cross(c - a).length() > 0.0, "{name}: degenerate triangle in panel {}", p.face);
                t.iter().for_each(|&i| used[i as usize] = true);
            }
            assert!(used.iter().all(|&u| u), "{name}: unused position in panel {}", p.face);
        }
    }
}

#[test]
fn plane_faces_give_straight_edges() {
    let sm = mixed();
    let panels = panels_b(&sm);
    let planar: Vec<&Panel> = panels.iter().filter(|p| p.is_planar()).collect();
    assert_eq!(planar.len(), sm.mesh.face_count().div_ceil(5));
    for p in planar {
        assert!(p.arcs.iter().all(Arc::is_straight), "panel {}", p.face);
        assert_eq!(p.triangles.len(), 1);
    }
    // A spherical panel next to a plane one keeps its curved arc: the edge has a gap.
    let gaps = gaps_of(&sm, &panels, GAP_SAMPLES);
    let plane_sphere: Vec<f64> = gaps.iter().filter(|g| panels[g.faces[0]].is_planar() != panels[g.faces[1]].is_planar()).map(|g| g.gap).collect();
    assert!(plane_sphere.len() >= 10, "{}", plane_sphere.len());
    let plane_sphere = plane_sphere.into_iter().fold(f64::INFINITY, f64::min);
    println!("mixed: smallest plane/sphere edge gap = {:.3e} · diag", plane_sphere / diag(&sm));
    assert!(plane_sphere > 1e-6 * diag(&sm));

    let flat = flat();
    let panels = panels_b(&flat);
    assert!(panels.iter().all(|p| p.arcs.iter().all(Arc::is_straight) && p.triangles.len() == 1));
    assert_eq!(max_gap_of(&flat, &panels, GAP_SAMPLES), 0.0);
    let area: f64 = panels.iter().map(|p| p.area).sum();
    assert!((area - 2.0).abs() < 1e-12, "{area}");
}

// ---------------------------------------------------------------------------------------------
// Gaps

#[test]
fn gap_is_zero_when_the_faces_share_one_sphere() {
    let sm = common();
    let d = diag(&sm);
    let panels = panels_b(&sm);
    let ours = max_gap_of(&sm, &panels, GAP_SAMPLES);
    let theirs = gap_along_bisecting_lines(&sm);
    println!("common sphere: max arc gap = {:.3e} · diag, line measure = {:.3e} · diag", ours / d, theirs / d);
    assert!(ours <= 1e-9 * d, "{ours:e}");
    assert!(theirs <= 1e-9 * d, "{theirs:e}");
    // Variant (b) arcs are genuinely per panel (the bisecting plane, not the intersection
    // circle, which does not exist for identical spheres).
    assert_eq!(gaps_of(&sm, &panels, GAP_SAMPLES).len(), interior_edges(&sm.mesh.triangulated()).len());
}

#[test]
fn gap_is_positive_where_the_spheres_differ_and_agrees_with_the_line_measure() {
    for (name, sm) in [("perturbed", perturbed()), ("mixed", mixed())] {
        let d = diag(&sm);
        let panels = panels_b(&sm);
        let gaps = gaps_of(&sm, &panels, GAP_SAMPLES);
        assert_eq!(gaps.len(), interior_edges(&sm.mesh.triangulated()).len());
        let mut smallest = f64::INFINITY;
        for g in &gaps {
            let [f, h] = g.faces;
            let kink = sm.face_spheres[f].kink_angle(&sm.face_spheres[h]);
            // Two planes cut by their bisecting plane both give the straight edge: no gap.
            let planes = sm.face_spheres[f].a == 0.0 && sm.face_spheres[h].a == 0.0;
            if kink > 1e-4 && !planes {
                smallest = smallest.min(g.gap);
                assert!(g.gap > 0.0, "{name}: edge {:?} kink {kink} but no gap", g.edge);
            }
        }
        let ours = max_gap_of(&sm, &panels, GAP_SAMPLES);
        let theirs = gap_along_bisecting_lines(&sm);
        let fine = max_gap_of(&sm, &panels, 1001);
        println!(
            "{name}: max arc gap = {:.6e} · diag (33 samples), {:.6e} · diag (1001 samples); line measure = {:.6e} · diag; |diff| = {:.3e} · diag; smallest gap at kink > 1e-4: {:.3e} · diag",
            ours / d,
            fine / d,
            theirs / d,
            (ours - theirs).abs() / d,
            smallest / d
        );
        assert!(ours > 1e-4 * d, "{name}: {ours:e}");
        assert!((ours - theirs).abs() <= 1e-9 * d, "{name}: {ours:e} vs {theirs:e}");
        // Finer sampling can only find a larger gap, and not much larger (smooth in t).
        assert!(fine >= ours && fine <= 1.05 * ours, "{name}: {fine:e} vs {ours:e}");

        // The same spheres with variant (a) arcs: one shared arc per edge, no gap at all.
        let a = build_panels(&sm, 1e-4 * d);
        assert_eq!(max_gap_of(&sm, &a, GAP_SAMPLES), 0.0);
    }
}

#[test]
fn gap_per_edge_matches_a_direct_sphere_computation() {
    // Independent of `Arc`: on the line x₀ + s w in the bisecting plane (w ⟂ edge), solve
    // ψ(x₀ + s w) = 0 for the root nearest the chord, for both spheres.
    let sm = perturbed();
    let mesh = &sm.mesh.triangulated();
    let panels = panels_b(&sm);
    let gaps: HashMap<[u32; 2], f64> = gaps_of(&sm, &panels, 9).into_iter().map(|g| (g.edge, g.gap)).collect();
    let root = |s: &Sphere, x0: DVec3, w: DVec3| -> f64 {
        // a s² + β s + ψ(x₀) = 0, β = ⟨2a x₀ − b, w⟩.
        let (a, beta, c) = (s.a, (2.0 * s.a * x0 - s.b).dot(w), s.eval(x0));
        if a == 0.0 {
            return -c / beta;
        }
        let disc = (beta * beta - 4.0 * a * c).sqrt();
        let r1 = (-beta + disc) / (2.0 * a);
        let r2 = (-beta - disc) / (2.0 * a);
        if r1.abs() < r2.abs() {
            r1
        } else {
            r2
        }
    };
    let mut worst = 0.0f64;
    for (e, [(f, _), (g, _)]) in interior_edges(mesh) {
        let (p, q) = (mesh.positions[e.0 as usize], mesh.positions[e.1 as usize]);
        let w = bisecting_normal(mesh, e, f, g).cross(q - p).normalize();
        let direct = (1..8)
            .map(|j| {
                let x0 = p + (j as f64 / 8.0) * (q - p);
                (root(&panels[f].sphere, x0, w) - root(&panels[g].sphere, x0, w)).abs()
            })
            .fold(0.0, f64::max);
        worst = worst.max((direct - gaps[&[e.0, e.1]]).abs());
    }
    println!("per-edge gap vs direct root computation: max |diff| = {:.3e} · diag", worst / diag(&sm));
    assert!(worst <= 1e-10 * diag(&sm), "{worst:e}");
}

#[test]
fn point_over_chord_on_known_arcs() {
    use spherical_faces::geometry::circle::Circle;
    // Circle of radius 2 about the origin in the xy-plane; chord from (2,0,0) to (0,2,0).
    let c = Circle { center: DVec3::ZERO, normal: DVec3::Z, radius: 2.0 };
    let minor = Arc { circle: c, from: DVec3::new(2.0, 0.0, 0.0), to: DVec3::new(0.0, 2.0, 0.0) };
    let major = Arc { circle: Circle { normal: -DVec3::Z, ..c }, ..minor };
    for t in [0.0, 0.1, 0.5, 0.77, 1.0] {
        let x0 = minor.from + t * (minor.to - minor.from);
        // Points on the circle on the line x₀ + s(1,1,0)/√2.
        let dir = DVec3::new(1.0, 1.0, 0.0).normalize();
        let b = x0.dot(dir);
        let disc = (b * b - x0.length_squared() + 4.0).sqrt();
        let (s_out, s_in) = (-b + disc, -b - disc);
        assert!((minor.point_over_chord(t) - (x0 + s_out * dir)).length() < 1e-14, "t = {t}");
        assert!((major.point_over_chord(t) - (x0 + s_in * dir)).length() < 1e-14, "t = {t}");
        assert!((minor.reversed().point_over_chord(1.0 - t) - minor.point_over_chord(t)).length() < 1e-14);
    }
    // A huge, nearly flat arc keeps precision: sagitta l²/(8r).
    let r = 1e9;
    let flat = Arc {
        circle: Circle { center: DVec3::new(0.0, -r * (1.0 - 0.25e-18f64).sqrt(), 0.0), normal: DVec3::Z, radius: r },
        from: DVec3::new(0.5, 0.0, 0.0),
        to: DVec3::new(-0.5, 0.0, 0.0),
    };
    let s = flat.point_over_chord(0.5).y;
    assert!((s - 1.0 / (8.0 * r)).abs() < 1e-6 / (8.0 * r), "{s:e}");
    let straight = Arc::straight(DVec3::ZERO, DVec3::X, DVec3::Z);
    assert_eq!(straight.point_over_chord(0.3), DVec3::new(0.3, 0.0, 0.0));
}

// ---------------------------------------------------------------------------------------------
// Variant (a) unchanged, exports

#[test]
fn variant_a_is_build_panels() {
    for (name, sm) in fixtures() {
        let tol = 1e-4 * diag(&sm);
        assert_eq!(build_panels(&sm, tol), build_panels_with(&sm, tol, EdgeArcs::Intersection), "{name}");
        assert_eq!(EdgeArcs::default(), EdgeArcs::Intersection);
    }
    // Variant (b) really differs where the spheres differ.
    let sm = perturbed();
    let tol = 1e-4 * diag(&sm);
    assert_ne!(build_panels(&sm, tol), panels_b(&sm));
}

#[test]
fn exports_accept_variant_b_panels() {
    for (name, sm) in [("perturbed", perturbed()), ("mixed", mixed())] {
        let panels = panels_b(&sm);
        let total: usize = panels.iter().map(|p| p.triangles.len()).sum();

        let glb = write_glb(&panels, None, None, None, Value::Null);
        let im = import_mesh(&glb, "variant-b.glb").unwrap();
        assert_eq!(im.mesh.face_count(), total, "{name}: notes {:?}", im.notes);
        assert_eq!(im.dropped_faces, 0, "{name}");
        // Nothing but identical (f32) points welds: the gaps keep the arc points of adjacent
        // panels apart, so every interior edge is a seam of two boundary curves.
        let mut distinct: Vec<[u32; 3]> =
            panels.iter().flat_map(|p| p.positions.iter().map(|x| [x.x as f32, x.y as f32, x.z as f32].map(f32::to_bits))).collect();
        distinct.sort_unstable();
        distinct.dedup();
        assert_eq!(im.mesh.vertex_count(), distinct.len(), "{name}");
        let a = build_panels(&sm, 1e-4 * diag(&sm));
        let im_a = import_mesh(&write_glb(&a, None, None, None, Value::Null), "variant-a.glb").unwrap();
        println!(
            "{name}: GLB re-import {} triangles, {} vertices, {} boundary vertices (variant (a): {} triangles, {} vertices, {} boundary vertices)",
            im.mesh.face_count(),
            im.mesh.vertex_count(),
            im.stats.boundary_vertices,
            im_a.mesh.face_count(),
            im_a.mesh.vertex_count(),
            im_a.stats.boundary_vertices
        );
        let interior_arc_points: usize = interior_edges(&sm.mesh.triangulated())
            .iter()
            .map(|(_, [(f, k), (g, l)])| panels[*f].arc_vertices[*k].len() + panels[*g].arc_vertices[*l].len() - 4)
            .sum();
        assert!(im.stats.boundary_vertices >= interior_arc_points + im_a.stats.boundary_vertices.min(1), "{name}");

        let obj = write_obj(&panels, None, None);
        let faces = obj.lines().filter(|l| l.starts_with("f ")).count();
        assert_eq!(faces, total, "{name}");
        let im = import_mesh(obj.as_bytes(), "variant-b.obj").unwrap();
        assert_eq!(im.mesh.face_count(), total, "{name}");

        let schedule = build_schedule(&panels, &Reference::from_triangles(sm.mesh.triangulated()), 1e-3);
        assert_eq!(schedule.panel_count, sm.mesh.face_count());
        assert!(schedule.panels.iter().all(|r| r.triangles > 0 && r.area > 0.0));
    }
}

#[test]
fn tri_dome_panels() {
    let mesh = common::load("tri_dome");
    // Face spheres fitted per face: the member of the vertices' pencil (cos θ s₀ + sin θ s₁,
    // normalized for every θ) minimizing Σ ψ² over the opposite vertices of the neighbours
    // (smallest eigenvector of a 2 × 2 matrix), oriented like the face.
    let mut spheres = Vec::new();
    let edges = interior_edges(&mesh);
    let mut opposite: Vec<Vec<DVec3>> = vec![Vec::new(); mesh.face_count()];
    for (e, [(f, _), (g, _)]) in &edges {
        for (x, y) in [(*f, *g), (*g, *f)] {
            let v = mesh.triangles[y].iter().copied().find(|&v| v != e.0 && v != e.1).unwrap();
            opposite[x].push(mesh.positions[v as usize]);
        }
    }
    for f in 0..mesh.face_count() {
        let [s0, s1] = Sphere::through_points_family(mesh.face_points(f));
        let (mut m00, mut m01, mut m11) = (0.0, 0.0, 0.0);
        for &x in &opposite[f] {
            let (u, v) = (s0.eval(x), s1.eval(x));
            (m00, m01, m11) = (m00 + u * u, m01 + u * v, m11 + v * v);
        }
        // Smallest eigenvector of [[m00, m01], [m01, m11]]: angle ½ atan2(2 m01, m00 − m11) + π/2.
        let th = 0.5 * (2.0 * m01).atan2(m00 - m11) + std::f64::consts::FRAC_PI_2;
        let s = Sphere::combine(&s0, th.cos(), &s1, th.sin()).normalized();
        spheres.push(if th.cos() < 0.0 { s.flipped() } else { s });
    }
    let sm = sphere_mesh(mesh, spheres);
    let d = diag(&sm);
    let panels = panels_b(&sm);
    let folded: usize = panels.iter().map(Panel::folded_triangles).sum();
    let ours = max_gap_of(&sm, &panels, GAP_SAMPLES);
    let theirs = gap_along_bisecting_lines(&sm);
    let res = panels.iter().map(|p| max_residual(&p.sphere, p.positions.iter().copied())).fold(0.0, f64::max);
    println!(
        "tri_dome: {} faces, folded {folded}, residual {:.3e} · diag, max arc gap {:.6e} · diag, max_gap {:.6e} · diag",
        sm.mesh.face_count(),
        res / d,
        ours / d,
        theirs / d
    );
    assert_eq!(folded, 0);
    assert!(res <= 1e-9 * d);
    assert!((ours - theirs).abs() <= 1e-9 * d, "{ours:e} vs {theirs:e}");
}
