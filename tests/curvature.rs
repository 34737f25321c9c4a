//! Jet-fitted curvature against closed forms: sphere, torus, cylinder, plane, the Enneper minimal
//! surface, and degenerate input. Run with `-- --nocapture` to see the measured errors.
#![cfg(not(target_arch = "wasm32"))] // native: reads ../shared, spawns processes

mod common;

use glam::DVec3;
use spherical_faces::congruence::central_spheres::{jet_fit, CurvatureField, JetParams, PLANAR_TOLERANCE, SIGN_CHANGE_THRESHOLD};
use spherical_faces::geometry::mesh::topology::Topology;
use spherical_faces::geometry::mesh::TriMesh;
use spherical_faces::progress::Cancelled;
use spherical_faces::samples::{cylinder_patch, plane_patch, sphere_patch, torus_closed_form, torus_patch};

fn fit(mesh: &TriMesh) -> CurvatureField {
    fit_with(mesh, &JetParams::default())
}

fn fit_with(mesh: &TriMesh, params: &JetParams) -> CurvatureField {
    let topo = Topology::new(mesh);
    let field = jet_fit(mesh, &topo, params, &mut spherical_faces::progress::ignore).expect("not cancelled");
    assert_all_finite(&field);
    field
}

fn flipped(mesh: &TriMesh) -> TriMesh {
    TriMesh::new(mesh.positions.clone(), mesh.triangles.iter().map(|t| [t[0], t[2], t[1]]).collect())
}

fn assert_all_finite(field: &CurvatureField) {
    for (i, c) in field.vertices.iter().enumerate() {
        let ok = c.k1.is_finite()
            && c.k2.is_finite()
            && c.mean.is_finite()
            && c.normal.is_finite()
            && c.dir1.is_finite()
            && c.dir2.is_finite()
            && c.k1 >= c.k2
            && (c.normal.length() - 1.0).abs() < 1e-9
            && (c.dir1.length() - 1.0).abs() < 1e-9
            && (c.dir2.length() - 1.0).abs() < 1e-9;
        assert!(ok, "vertex {i}: {c:?}");
        let s = field.central_spheres[i];
        assert!(s.is_finite(), "sphere {i}: {s:?}");
        assert!((s.discriminant() - 1.0).abs() < 1e-6, "sphere {i} not normalized: {s:?}");
    }
    let s = &field.summary;
    assert!(s.min_h.is_finite() && s.max_h.is_finite() && s.mean_h.is_finite());
}

fn interior(field: &CurvatureField) -> impl Iterator<Item = usize> + '_ {
    (0..field.vertices.len()).filter(|&v| !field.boundary[v])
}

#[test]
fn sphere_mean_curvature_and_central_sphere_centre() {
    let mut worst_h: f64 = 0.0;
    let mut worst_c: f64 = 0.0;
    // Square patches ±0.6 rad (±34°) around the pole; 30 and 48 cells across: edges of 2.3° and
    // 1.4° of arc.
    for (radius, n) in [(0.5, 30), (3.0, 48), (40.0, 30), (40.0, 48)] {
        {
            let mesh = sphere_patch(radius, 0.6, n);
            for (orientation, m) in [(-1.0, mesh.clone()), (1.0, flipped(&mesh))] {
                let field = fit(&m);
                assert_eq!(field.summary.failed_fits, 0);
                assert_eq!(field.summary.low_degree_fits, 0);
                for v in interior(&field) {
                    let c = field.vertices[v];
                    // Outward normals: H = −1/R; flipped (inward): +1/R.
                    let err = (c.mean * radius - orientation).abs();
                    worst_h = worst_h.max(err);
                    assert!(err < 0.005, "R={radius} n={n} orientation {orientation}: H·R = {}", c.mean * radius);
                    let centre = field.central_spheres[v].center().expect("a sphere, not a plane");
                    let ce = centre.length() / radius;
                    worst_c = worst_c.max(ce);
                    assert!(ce < 0.005, "R={radius} n={n}: centre {centre} (|c|/R = {ce})");
                    assert!((field.central_spheres[v].signed_radius().unwrap().abs() / radius - 1.0).abs() < 0.005);
                }
                assert!(!field.summary.h_changes_sign);
            }
        }
    }
    println!("sphere: max |H·R − (±1)| = {worst_h:.2e}, max |centre − c|/R = {worst_c:.2e} (interior vertices)");
}

struct TorusErrors {
    h: f64,
    k1: f64,
    k2: f64,
    k1_abs: f64,
    dir_deg: f64,
}

fn torus_errors(big_r: f64, r: f64, nu: usize, nv: usize, u_range: (f64, f64), v_range: (f64, f64)) -> TorusErrors {
    torus_errors_with(big_r, r, nu, nv, u_range, v_range, &JetParams::default())
}

fn torus_errors_with(big_r: f64, r: f64, nu: usize, nv: usize, u_range: (f64, f64), v_range: (f64, f64), params: &JetParams) -> TorusErrors {
    let mesh = torus_patch(big_r, r, u_range, v_range, nu, nv);
    let field = fit_with(&mesh, params);
    assert_eq!(field.summary.failed_fits, 0);
    let mut e = TorusErrors { h: 0.0, k1: 0.0, k2: 0.0, k1_abs: 0.0, dir_deg: 0.0 };
    for v in interior(&field) {
        let p = mesh.positions[v];
        let rho = p.x.hypot(p.y);
        let vv = p.z.atan2(rho - big_r);
        let u = p.y.atan2(p.x);
        let (k_mer, k_par) = torus_closed_form(big_r, r, vv);
        // W.r.t. the outward normal both change sign; k_par > k_mer for R > 2r.
        let (k1, k2) = (-k_par, -k_mer);
        let h = 0.5 * (k1 + k2);
        let c = field.vertices[v];
        e.h = e.h.max((c.mean - h).abs() / h.abs());
        // κ1 (parallel) vanishes at the top and bottom circles: relative to max |κ| = 1/r there.
        e.k1 = e.k1.max((c.k1 - k1).abs() / k1.abs().max(1.0 / r));
        e.k1_abs = e.k1_abs.max((c.k1 - k1).abs() * r);
        e.k2 = e.k2.max((c.k2 - k2).abs() / k2.abs());
        let parallel = DVec3::new(-u.sin(), u.cos(), 0.0);
        let meridian = DVec3::new(-vv.sin() * u.cos(), -vv.sin() * u.sin(), vv.cos());
        let a1 = c.dir1.dot(parallel).abs().min(1.0).acos().to_degrees();
        let a2 = c.dir2.dot(meridian).abs().min(1.0).acos().to_degrees();
        e.dir_deg = e.dir_deg.max(a1).max(a2);
    }
    e
}

fn print_torus(label: &str, e: &TorusErrors) {
    println!(
        "{label}: max rel err H {:.2}%, k1 {:.2}% (of max(|k1|, 1/r)), k2 {:.2}%; |k1 err|·r {:.1e}; principal directions within {:.2}°",
        100.0 * e.h,
        100.0 * e.k1,
        100.0 * e.k2,
        e.k1_abs,
        e.dir_deg
    );
}

const FULL: (f64, f64) = (0.0, std::f64::consts::TAU);

#[test]
fn torus_principal_curvatures_and_directions() {
    // R = 3, r = 1. H is hardest: at the inner equator H = −1/4 is a difference of −1 and +1/2.
    // Default parameters (degree 3) on a torus with 72 edges around the tube (5° each, 0.087 r)
    // and 144 around the ring: every vertex interior.
    let e = torus_errors(3.0, 1.0, 144, 72, FULL, FULL);
    print_torus("torus 144x72, degree 3", &e);
    assert!(e.h < 0.02 && e.k1 < 0.02 && e.k2 < 0.02);
    assert!(e.dir_deg < 0.5);
    // Degree 4 reaches the same accuracy at half the resolution: 36 edges around the tube (10°).
    let p4 = JetParams::with_degree(4);
    let e4 = torus_errors_with(3.0, 1.0, 72, 36, FULL, FULL, &p4);
    print_torus("torus 72x36, degree 4", &e4);
    assert!(e4.h < 0.02 && e4.k1 < 0.02 && e4.k2 < 0.02);
    assert!(e4.dir_deg < 0.5);
    // A 60 × 30 patch (half the ring, the whole tube, with boundary): degree 3 is O(h²) and ≈ 11%
    // off in H at 12° per edge, degree 4 ≈ 2.5%.
    let half = (0.0, std::f64::consts::PI);
    let c = torus_errors(3.0, 1.0, 60, 30, half, FULL);
    print_torus("torus patch 60x30 (half ring), degree 3", &c);
    let c4 = torus_errors_with(3.0, 1.0, 60, 30, half, FULL, &p4);
    print_torus("torus patch 60x30 (half ring), degree 4", &c4);
    assert!(c.h < 0.15 && c.k2 < 0.06 && c.dir_deg < 1.0);
    assert!(c4.h < 0.04 && c4.k2 < 0.02 && c4.dir_deg < 1.0);
    // Second-order convergence of degree 3: halving the edge length divides the error by ≈ 4.
    let f = torus_errors(3.0, 1.0, 120, 60, half, FULL);
    println!("degree 3 error ratio 60x30 / 120x60: H {:.2}, k2 {:.2}", c.h / f.h, c.k2 / f.k2);
    assert!(c.h / f.h > 3.0 && c.k2 / f.k2 > 3.0);
}

#[test]
fn cylinder() {
    let r = 2.0;
    let mesh = cylinder_patch(r, 2.0, 8.0, 24, 30);
    let mut worst: f64 = 0.0;
    for (sign, m) in [(-1.0, mesh.clone()), (1.0, flipped(&mesh))] {
        let field = fit(&m);
        for v in interior(&field) {
            let c = field.vertices[v];
            // Outward: κ = 0 along the axis, −1/r around it; inward: +1/r and 0.
            let (k1, k2) = if sign < 0.0 { (0.0, -1.0 / r) } else { (1.0 / r, 0.0) };
            let e = ((c.k1 - k1).abs().max((c.k2 - k2).abs()) * r).max((c.mean - sign / (2.0 * r)).abs() * 2.0 * r);
            worst = worst.max(e);
            assert!(e < 0.01, "vertex {v}: {c:?}");
            let axis_dir = if sign < 0.0 { c.dir1 } else { c.dir2 };
            assert!(axis_dir.y.abs() > 0.9999, "axis direction {axis_dir}");
        }
    }
    println!("cylinder: max error of k1, k2, H relative to 1/r: {worst:.2e}");
}

#[test]
fn plane_is_flat() {
    // A tilted plane with in-plane jitter of the vertices.
    let mut mesh = plane_patch(10.0, 6.0, 20, 12);
    let (e1, e2) = (DVec3::new(1.0, 0.0, 0.3).normalize(), DVec3::new(0.0, 1.0, -0.2).normalize());
    for (i, p) in mesh.positions.iter_mut().enumerate() {
        let jx = 0.08 * ((i as f64 * 12.9898).sin() * 43758.5453).fract();
        let jy = 0.08 * ((i as f64 * 78.233).sin() * 12345.678).fract();
        *p = DVec3::new(1.0, 2.0, 3.0) + (p.x + jx) * e1 + (p.y + jy) * e2;
    }
    let field = fit(&mesh);
    let diag = mesh.bbox_diagonal();
    let mut worst: f64 = 0.0;
    for (v, c) in field.vertices.iter().enumerate() {
        worst = worst.max(c.k1.abs().max(c.k2.abs()) * diag);
        assert!(field.planar[v]);
        let s = field.central_spheres[v];
        assert!(s.is_plane(1e-9) && s.is_finite());
        assert!(s.eval(mesh.positions[v]).abs() < 1e-9 * diag);
    }
    assert!(worst < 1e-9, "max |k|·diag = {worst}");
    assert_eq!(field.summary.planar_vertices, mesh.vertex_count());
    assert!(!field.summary.h_changes_sign);
    assert_eq!(field.summary.failed_fits, 0);
    println!("plane: max |k|·diag = {worst:.2e}");
}

/// Distance from `p` to Enneper's surface s (u − u³/3 + uv², v − v³/3 + u²v, u² − v²) by Gauss–Newton
/// on (u, v) from a few starts.
fn distance_to_enneper(p: DVec3, s: f64) -> f64 {
    let point = |u: f64, v: f64| s * DVec3::new(u - u * u * u / 3.0 + u * v * v, v - v * v * v / 3.0 + u * u * v, u * u - v * v);
    let mut best = f64::INFINITY;
    let root = |t: f64| (t.abs() / s).sqrt();
    for (mut u, mut v) in [(p.x / s, p.y / s), (0.5 * p.x / s, 0.5 * p.y / s), (root(p.z).copysign(p.x), root(-p.z).copysign(p.y))] {
        for _ in 0..60 {
            let r = point(u, v) - p;
            let ju = s * DVec3::new(1.0 - u * u + v * v, 2.0 * u * v, 2.0 * u);
            let jv = s * DVec3::new(2.0 * u * v, 1.0 - v * v + u * u, -2.0 * v);
            let (a, b, c) = (ju.dot(ju), ju.dot(jv), jv.dot(jv));
            let det = a * c - b * b;
            if det.abs() < 1e-14 {
                break;
            }
            let (gu, gv) = (ju.dot(r), jv.dot(r));
            u -= (c * gu - b * gv) / det;
            v -= (a * gv - b * gu) / det;
        }
        best = best.min((point(u, v) - p).length());
    }
    best
}

#[test]
fn enneper_minimal_surface_has_small_mean_curvature() {
    let mesh = common::load("enneper2");
    let field = fit(&mesh);
    let diag = mesh.bbox_diagonal();
    let topo = Topology::new(&mesh);
    // Interior vertices, and those at least 2 rings away from the boundary.
    let mut near_boundary = vec![false; mesh.vertex_count()];
    for v in 0..mesh.vertex_count() {
        if topo.is_boundary_vertex(v) {
            near_boundary[v] = true;
            for &w in topo.vertex_neighbors(v) {
                near_boundary[w as usize] = true;
            }
        }
    }
    let (mut max_int, mut max_deep, mut max_all, mut max_k, mut sq, mut n) = (0.0f64, 0.0f64, 0.0f64, 0.0f64, 0.0, 0);
    for (v, c) in field.vertices.iter().enumerate() {
        let h = c.mean.abs() * diag;
        max_all = max_all.max(h);
        max_k = max_k.max(c.k1.abs().max(c.k2.abs()) * diag);
        if !field.boundary[v] {
            max_int = max_int.max(h);
            sq += h * h;
            n += 1;
            if !near_boundary[v] {
                max_deep = max_deep.max(h);
            }
        }
    }
    // The mesh is not sampled exactly from the smooth surface: its vertices lie up to ≈ 5e-4·diag
    // off Enneper's surface (scale 3), which is what the jet reads as mean curvature.
    let off = mesh.positions.iter().map(|&p| distance_to_enneper(p, 3.0)).fold(0.0, f64::max);
    let beyond = |sign: f64| field.vertices.iter().filter(|c| sign * c.mean * diag > SIGN_CHANGE_THRESHOLD).count();
    println!("enneper: {} vertices above +{SIGN_CHANGE_THRESHOLD}, {} below −{SIGN_CHANGE_THRESHOLD}", beyond(1.0), beyond(-1.0));
    println!(
        "enneper: {} vertices, diag {diag:.2}, vertices up to {:.1e}·diag off the smooth surface; |H|·diag: interior max {max_int:.3} (rms {:.3}), ≥ 2 rings from the boundary {max_deep:.3}, all {max_all:.3}; max |k|·diag {max_k:.1}; {:?}",
        mesh.vertex_count(),
        off / diag,
        (sq / n as f64).sqrt(),
        field.summary
    );
    assert!(off / diag < 1e-3);
    assert!(max_int < 1.0, "interior |H|·diag {max_int}");
    assert!(max_deep < 0.5, "|H|·diag two rings in {max_deep}");
    // Relative to the principal curvatures, H is small: |H| ≤ 4% of the largest |k|.
    assert!(max_int < 0.04 * max_k);
    // Honest outcome: at this noise level H takes both signs beyond the threshold on > 1% of the
    // vertices, so the summary reports a sign change (and central-sphere methods refuse it).
    assert!(field.summary.h_changes_sign);
}

#[test]
fn degenerate_input_stays_finite() {
    // An isolated vertex next to a single triangle.
    let m = TriMesh::new(vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(5.0, 5.0, 5.0)], vec![[0, 1, 2]]);
    let field = fit(&m);
    assert_eq!(field.summary.failed_fits, 4); // 3 points cannot carry a quadratic jet
    assert!(field.central_spheres.iter().all(|s| s.is_plane(0.0)));
    // A flat hexagonal fan: coplanar ring.
    let mut pos = vec![DVec3::ZERO];
    pos.extend((0..6).map(|i| {
        let a = i as f64 * std::f64::consts::TAU / 6.0;
        DVec3::new(a.cos(), a.sin(), 0.0)
    }));
    let tris: Vec<[u32; 3]> = (0..6).map(|i| [0, 1 + i, 1 + (i + 1) % 6]).collect();
    let fan = TriMesh::new(pos, tris);
    let field = fit(&fan);
    assert_eq!(field.vertices[0].mean, 0.0);
    assert!((field.vertices[0].normal - DVec3::Z).length() < 1e-12);
    // Collinear and coincident points, zero-area triangles.
    let m = TriMesh::new(vec![DVec3::ZERO, DVec3::X, 2.0 * DVec3::X, 3.0 * DVec3::X, DVec3::X], vec![[0, 1, 2], [1, 2, 3], [2, 3, 4], [0, 4, 1]]);
    fit(&m);
    // NaN and infinite positions.
    let mut bad = sphere_patch(1.0, 0.5, 6);
    bad.positions[10] = DVec3::new(f64::NAN, 0.0, 1.0);
    bad.positions[20] = DVec3::new(0.0, f64::INFINITY, 1.0);
    let field = fit(&bad);
    assert!(field.summary.failed_fits >= 2);
    // Empty mesh.
    let field = fit(&TriMesh::default());
    assert!(field.vertices.is_empty());
    // Out-of-spec parameters are clamped.
    for params in [
        JetParams { degree: 0, min_points: 0, max_rings: 0 },
        JetParams { degree: 9, min_points: 10_000, max_rings: 100 },
        JetParams { degree: 4, ..JetParams::default() },
        JetParams { degree: 2, max_rings: 1, ..JetParams::default() },
    ] {
        let f = fit_with(&sphere_patch(2.0, 0.5, 8), &params);
        // One ring (max_rings clamped to 1) cannot carry a jet at boundary vertices (≤ 4 neighbours).
        let expected = if params.max_rings <= 1 { f.summary.boundary_vertices } else { 0 };
        assert!(f.summary.failed_fits <= expected, "{params:?}: {:?}", f.summary);
    }
}

#[test]
fn progress_and_cancel() {
    let mesh = torus_patch(3.0, 1.0, (0.0, 6.0), (0.0, 6.0), 60, 40);
    let topo = Topology::new(&mesh);
    let mut calls = Vec::new();
    let field = jet_fit(&mesh, &topo, &JetParams::default(), &mut |p| {
        assert_eq!(p.step, "jet_fit");
        calls.push((p.done, p.total));
        Ok(())
    });
    assert!(field.is_ok());
    let n = mesh.vertex_count();
    assert_eq!(calls.last(), Some(&(n, n)));
    assert!(calls.len() > n / 1024);
    assert!(calls.windows(2).all(|w| w[0].0 < w[1].0));
    let mut count = 0;
    let cancelled = jet_fit(&mesh, &topo, &JetParams::default(), &mut |_| {
        count += 1;
        Err(Cancelled)
    });
    assert_eq!(cancelled.err(), Some(Cancelled));
    assert_eq!(count, 1);
}

#[test]
fn planar_tolerance_is_relative() {
    // A sphere of radius 10⁴ diagonals is planar, one of 10 diagonals is not.
    for (radius, planar) in [(1e5, true), (100.0, false)] {
        let mesh = sphere_patch(radius, 10.0 / radius, 10);
        let field = fit(&mesh);
        let diag = mesh.bbox_diagonal();
        assert_eq!(field.planar.iter().all(|&p| p), planar, "R/diag = {}", radius / diag);
        assert_eq!(diag / radius < PLANAR_TOLERANCE, planar);
    }
}

/// Timing on a ~100k-vertex closed torus: `cargo test --release --test curvature -- --ignored --nocapture`.
#[test]
#[ignore]
fn timing_100k_vertices() {
    let mesh = torus_patch(3.0, 1.0, (0.0, std::f64::consts::TAU), (0.0, std::f64::consts::TAU), 500, 200);
    let topo = Topology::new(&mesh);
    for degree in [2, 3, 4] {
        let params = JetParams::with_degree(degree);
        let t = std::time::Instant::now();
        let field = jet_fit(&mesh, &topo, &params, &mut spherical_faces::progress::ignore).unwrap();
        let dt = t.elapsed();
        println!("jet_fit degree {degree} on {} vertices: {:.1} ms", mesh.vertex_count(), dt.as_secs_f64() * 1e3);
        assert_eq!(field.summary.failed_fits, 0);
    }
}
