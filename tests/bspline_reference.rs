//! A B-spline as the reference surface: its tessellation, the exact closest point with its
//! (u, v), the exact curvature at the vertices, loading through the session (files and the vault
//! sample) and the CLI's `info`.
#![cfg(not(target_arch = "wasm32"))] // native: reads ../shared, spawns the CLI

mod common;

use glam::DVec3;
use spherical_faces::congruence::central_spheres::JetParams;
use spherical_faces::geometry::bspline::BSplineSurface;
use spherical_faces::import::{import_file, Format, ImportedFile};
use spherical_faces::pipeline::session::Loaded;
use spherical_faces::progress::ignore;
use spherical_faces::reference::proximity::ReferenceProximity;
use spherical_faces::reference::Reference;
use spherical_faces::samples::Sample;
use spherical_faces::solver::Term;

fn spline(name: &str) -> BSplineSurface {
    match import_file(&common::shared_bytes(&format!("data/bsplines/{name}.json")), name) {
        Ok(ImportedFile::BSpline(b)) => b.surface,
        other => panic!("{name}: {other:?}"),
    }
}

#[test]
fn the_tessellation_is_a_quad_grid_on_the_surface_within_its_tolerance() {
    for name in ["tunnel_arch", "torus_patch", "paraboloid_dome_deg5"] {
        let s = spline(name);
        let r = Reference::from_bspline(s.clone()).unwrap();
        let sr = r.spline_reference().unwrap();
        let [su, sv] = sr.segments;
        assert_eq!(r.surface().faces.len(), su * sv);
        assert!(r.surface().faces.iter().all(|f| f.len() == 4));
        assert_eq!(r.mesh().face_count(), 2 * su * sv);
        let stats = r.topology().stats(r.mesh());
        assert_eq!((stats.boundary_loops, stats.non_manifold_edges), (1, 0), "{name}");
        // Vertices on the surface; faces oriented like S_u × S_v.
        for (p, uv) in r.mesh().positions.iter().zip(&sr.uv) {
            assert!((*p - s.point(uv[0], uv[1])).length() < 1e-12 * r.diagonal());
        }
        for f in 0..r.mesh().face_count() {
            let t = r.mesh().triangles[f];
            let uv = (0..3).fold([0.0; 2], |a, k| [a[0] + sr.uv[t[k] as usize][0] / 3.0, a[1] + sr.uv[t[k] as usize][1] / 3.0]);
            assert!(r.mesh().face_area_vector(f).dot(s.frame(uv[0], uv[1]).unwrap().normal) > 0.0, "{name}: face {f} flipped");
        }
        // Chords: the surface at the midpoints of the quads' diagonals stays within the tolerance
        // (the bound is for the edges; diagonals are √2 longer: twice the sagitta).
        let tol = 5e-4 * spherical_faces::geometry::mesh::bbox_diagonal(s.control_points());
        let mut worst = 0.0f64;
        for f in &r.surface().faces {
            let c = f.corners();
            let (a, b) = (c[0] as usize, c[2] as usize);
            let mid_uv = [(sr.uv[a][0] + sr.uv[b][0]) / 2.0, (sr.uv[a][1] + sr.uv[b][1]) / 2.0];
            let chord_mid = (r.mesh().positions[a] + r.mesh().positions[b]) / 2.0;
            worst = worst.max((s.point(mid_uv[0], mid_uv[1]) - chord_mid).length());
        }
        assert!(worst < 2.5 * tol, "{name}: the tessellation deviates by {worst} (tolerance {tol})");
    }
}

#[test]
fn closest_points_are_exact_and_carry_their_parameters() {
    let s = spline("tunnel_arch");
    let r = Reference::from_bspline(s.clone()).unwrap();
    let ((u0, u1), (v0, v1)) = s.domain();
    let d = r.diagonal();
    for k in 0..50 {
        let (a, b) = (((k as f64) * 0.618_033_988 + 0.1) % 1.0, ((k as f64) * 0.414_213_562 + 0.3) % 1.0);
        let uv = [u0 + (u1 - u0) * (0.03 + 0.94 * a), v0 + (v1 - v0) * (0.03 + 0.94 * b)];
        let f = s.frame(uv[0], uv[1]).unwrap();
        // Off the surface along the normal, by up to 2 % of the diagonal (less than the radii of
        // curvature): the foot is the closest point.
        let offset = (k as f64 / 50.0 - 0.5) * 0.04 * d;
        let hit = r.closest_point(f.point + offset * f.normal).unwrap();
        let found = hit.uv.expect("a B-spline gives (u, v)");
        assert!((found[0] - uv[0]).abs() < 1e-9 * (u1 - u0) && (found[1] - uv[1]).abs() < 1e-9 * (v1 - v0), "{uv:?} → {found:?}");
        assert!((hit.point - f.point).length() < 1e-9 * d);
        assert!((hit.normal.unwrap() - f.normal).length() < 1e-9);
    }
    // Beyond the boundary: the closest point is on the boundary curve u = u1.
    let f = s.frame(u1, 0.5 * (v0 + v1)).unwrap();
    let outside = f.point + 0.05 * d * (f.su.normalize());
    let hit = r.closest_point(outside).unwrap();
    assert!((hit.uv.unwrap()[0] - u1).abs() < 1e-12, "{:?}", hit.uv);
}

/// A proximity term follows a vertex from one solver step to the next, each search starting where
/// the last ended: it finds what a search from scratch finds, on the degree-10 rough roof, where
/// the point moves by steps from 1e-9 of the diagonal (Newton's last step) to a few percent.
#[test]
fn a_search_started_where_the_last_ended_finds_the_closest_point() {
    let r = Loaded::from_file(&common::shared_bytes("data/bsplines/hard/roof_rough.json"), "roof_rough.json").unwrap().surface;
    let s = r.spline().unwrap().clone();
    let ((u0, u1), (v0, v1)) = s.domain();
    let d = r.diagonal();
    let mut term = ReferenceProximity::point(&r, vec![0], vec![1.0]);
    let mut step = 0.03 * d;
    for k in 0..60 {
        let t = k as f64 / 60.0;
        let f = s.frame(u0 + (u1 - u0) * (0.2 + 0.6 * t), v0 + (v1 - v0) * (0.5 + 0.3 * (7.0 * t).sin())).unwrap();
        let p = f.point + 0.01 * d * (3.0 * t).cos() * f.normal;
        for p in [p, p + step * f.su.normalize(), p + step * DVec3::new(0.3, -0.2, 0.1)] {
            term.prepare(&[p.x, p.y, p.z]);
            let (q, n) = term.closest()[0];
            let cold = r.closest_point(p).unwrap();
            assert!((q - cold.point).length() < 1e-12 * d, "step {k}: {q} vs {} ({:.1e} of the diagonal)", cold.point, (q - cold.point).length() / d);
            assert!((n - cold.normal.unwrap()).length() < 1e-9);
            // The foot of the perpendicular: the residual is normal to the surface.
            let fq = s.frame(cold.uv.unwrap()[0], cold.uv.unwrap()[1]).unwrap();
            let r = p - q;
            assert!(r.dot(fq.su.normalize()).abs() < 1e-11 * d && r.dot(fq.sv.normalize()).abs() < 1e-11 * d, "step {k}: residual {r} not normal");
        }
        step = (step * 0.5).max(1e-9 * d);
    }
}

#[test]
fn curvature_of_a_bspline_reference_is_exact() {
    let s = spline("torus_patch");
    let r = Reference::from_bspline(s.clone()).unwrap();
    let field = r.curvature(&JetParams::default(), &mut ignore).unwrap();
    let sr = r.spline_reference().unwrap();
    for (v, c) in field.vertices.iter().enumerate() {
        let f = s.frame(sr.uv[v][0], sr.uv[v][1]).unwrap();
        assert_eq!((c.mean, c.k1, c.k2), (f.mean, f.k1, f.k2));
        // The central sphere: centre f + n/H.
        let sphere = field.central_spheres[v];
        assert!((sphere.center().unwrap() - (f.point + f.normal / f.mean)).length() < 1e-9);
    }
    assert!(!field.summary.h_changes_sign && field.summary.failed_fits == 0);
}

#[test]
fn the_vault_sample_is_a_one_signed_bspline() {
    let s = Sample::Vault.bspline().unwrap();
    let diag = spherical_faces::geometry::mesh::bbox_diagonal(s.control_points());
    let (mut min_h, mut max_h) = (f64::INFINITY, f64::NEG_INFINITY);
    for i in 0..=100 {
        for j in 0..=100 {
            let f = s.frame(i as f64 / 100.0, j as f64 / 100.0).unwrap();
            min_h = min_h.min(f.mean);
            max_h = max_h.max(f.mean);
        }
    }
    assert!(max_h * diag < -0.5, "H < 0 everywhere, well away from 0: [{min_h}, {max_h}]");
    // As described: 18 m long, 14 m wide at the ends, standing on z = 0.
    let (lo, hi) = (s.point(0.0, 0.0), s.point(1.0, 1.0));
    assert!((lo - DVec3::new(-7.0, 0.0, 0.0)).length() < 1e-12 && (hi - DVec3::new(7.0, 18.0, 0.0)).length() < 1e-12);
    // Loaded through the session: a B-spline reference with its info.
    let loaded = Loaded::from_sample(Sample::Vault);
    assert!(loaded.surface.spline().is_some());
    let info = loaded.info.bspline.as_ref().unwrap();
    assert_eq!((info.degree, info.control), ([5, 5], [9, 8]));
    assert_eq!(Sample::Vault.mesh().positions, loaded.surface.mesh().positions);
}

#[test]
fn a_bspline_file_loads_through_the_session() {
    let bytes = common::shared_bytes("data/bsplines/tunnel_arch.json");
    let loaded = Loaded::from_file(&bytes, "tunnel_arch.json").unwrap();
    assert_eq!(loaded.info.format, Some(Format::BSplineJson));
    let b = loaded.info.bspline.as_ref().unwrap();
    assert_eq!((b.degree, b.control, b.domain), ([5, 6], [12, 13], [[0.0, 10.0], [0.0, 12.0]]));
    // README: H in [−0.155426, −0.079371].
    assert!((b.mean_curvature[0] + 0.155426).abs() < 1e-5 && (b.mean_curvature[1] + 0.079371).abs() < 1e-5, "{b:?}");
    let err = Loaded::from_file(b"{\"degreeU\": 2}", "broken.json").err().unwrap().to_string();
    assert_eq!(err, "broken.json: missing key 'degreeV'");
}

#[test]
fn the_cli_info_describes_a_bspline() {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_spherical-faces"))
        .args(["info", common::shared_path("data/bsplines/torus_patch.json").to_str().unwrap()])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let j: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(j["bspline"]["degree"], serde_json::json!([2, 2]));
    assert_eq!(j["bspline"]["control_points"], serde_json::json!([5, 3]));
    assert_eq!(j["bspline"]["rational"], true);
    let h = &j["bspline"]["mean_curvature"];
    assert!((h["min"].as_f64().unwrap() + 0.625).abs() < 1e-4 && (h["max"].as_f64().unwrap() + 4.0 / 7.0).abs() < 1e-4, "{h}");
    assert_eq!(j["h_changes_sign"], false);
}
