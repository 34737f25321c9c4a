//! Built-in samples: identity, mesh hygiene (orientation, manifoldness, sizes) and their curvature
//! against closed forms. Run with `-- --nocapture` to see the measured numbers.
#![cfg(not(target_arch = "wasm32"))] // native: reads ../shared, spawns processes

use glam::DVec3;
use spherical_faces::congruence::central_spheres::{jet_fit, CurvatureField, JetParams, SIGN_CHANGE_THRESHOLD};
use spherical_faces::geometry::mesh::topology::Topology;
use spherical_faces::geometry::mesh::TriMesh;
use spherical_faces::samples::{dome_height, torus_closed_form, Sample};
use std::collections::HashMap;

fn fit(mesh: &TriMesh) -> CurvatureField {
    let topo = Topology::new(mesh);
    jet_fit(mesh, &topo, &JetParams::default(), &mut spherical_faces::progress::ignore).unwrap()
}

#[test]
fn keys_round_trip() {
    let mut keys: Vec<&str> = Sample::ALL.iter().map(|s| s.key()).collect();
    assert_eq!(keys, ["dome", "torus", "sphere-cap", "wave-roof", "vault"]);
    for s in Sample::ALL {
        assert_eq!(Sample::from_key(s.key()), Some(s));
        assert!(!s.title().is_empty() && !s.description().is_empty());
        let json = serde_json::to_string(&s).unwrap();
        assert_eq!(serde_json::from_str::<Sample>(&json).unwrap(), s);
    }
    keys.dedup();
    assert_eq!(keys.len(), 5);
    assert_eq!(Sample::from_key("Dome"), None);
    assert_eq!(Sample::from_key(""), None);
    assert_eq!(Sample::default(), Sample::Dome);
}

#[test]
fn meshes_are_clean_and_oriented() {
    for s in Sample::ALL {
        let mesh = s.mesh();
        let (nv, nf) = (mesh.vertex_count(), mesh.face_count());
        println!("{}: {nv} vertices, {nf} triangles, bbox {:?}, diag {:.1}", s.key(), mesh.bbox(), mesh.bbox_diagonal());
        assert!((1000..=5000).contains(&nv), "{}: {nv} vertices", s.key());
        assert!(s.description().contains(&format!("{nv} vertices")), "{}: description out of date", s.key());
        assert!(s.description().contains(&format!("{nf} triangles")), "{}: description out of date", s.key());
        assert!(mesh.positions.iter().all(|p| p.is_finite()));
        // No degenerate triangles: area above 1% of the mean.
        let areas: Vec<f64> = (0..nf).map(|f| mesh.face_area_vector(f).length()).collect();
        let mean = areas.iter().sum::<f64>() / nf as f64;
        assert!(areas.iter().all(|&a| a > 0.01 * mean), "{}: sliver", s.key());
        // Consistent orientation: every directed edge once, interior edges used both ways.
        let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
        for t in &mesh.triangles {
            for k in 0..3 {
                *directed.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
            }
        }
        assert!(directed.values().all(|&c| c == 1), "{}: repeated directed edge", s.key());
        let topo = Topology::new(&mesh);
        let stats = topo.stats(&mesh);
        assert_eq!(stats.non_manifold_edges, 0);
        assert_eq!(stats.boundary_loops, 1, "{}", s.key());
        for (e, &c) in topo.edges().iter().zip(topo.edge_face_counts()) {
            if c == 2 {
                assert!(directed.contains_key(&(e[0], e[1])) && directed.contains_key(&(e[1], e[0])));
            }
        }
        // Every vertex is used.
        let mut used = vec![false; nv];
        mesh.triangles.iter().flatten().for_each(|&v| used[v as usize] = true);
        assert!(used.iter().all(|&u| u));
        // Normals up or outward.
        let normals = mesh.vertex_normals();
        for (v, n) in normals.iter().enumerate() {
            let p = mesh.positions[v];
            let outward = match s {
                Sample::TorusPatch => {
                    // From the tube's core circle (R = 16) outward.
                    let core = DVec3::new(p.x, p.y, 0.0).normalize() * 16.0;
                    n.dot((p - core).normalize()) > 0.99
                }
                Sample::SphereCap => n.dot((p - DVec3::new(0.0, 0.0, -16.0)).normalize()) > 0.999,
                _ => n.z > 0.0,
            };
            assert!(outward, "{}: vertex {v} normal {n}", s.key());
        }
    }
}

/// Exact mean curvature of the dome's height function (w.r.t. the upward normal), by central
/// differences: 2H W³ = (1 + g_y²) g_xx − 2 g_x g_y g_xy + (1 + g_x²) g_yy.
fn dome_exact_h(x: f64, y: f64) -> f64 {
    let g = |x: f64, y: f64| dome_height(x / 15.0, y / 10.0);
    let e = 1e-3;
    let gx = (g(x + e, y) - g(x - e, y)) / (2.0 * e);
    let gy = (g(x, y + e) - g(x, y - e)) / (2.0 * e);
    let gxx = (g(x + e, y) - 2.0 * g(x, y) + g(x - e, y)) / (e * e);
    let gyy = (g(x, y + e) - 2.0 * g(x, y) + g(x, y - e)) / (e * e);
    let gxy = (g(x + e, y + e) - g(x + e, y - e) - g(x - e, y + e) + g(x - e, y - e)) / (4.0 * e * e);
    let w2 = 1.0 + gx * gx + gy * gy;
    ((1.0 + gy * gy) * gxx - 2.0 * gx * gy * gxy + (1.0 + gx * gx) * gyy) / (2.0 * w2.powf(1.5))
}

#[test]
fn dome_keeps_one_sign_of_mean_curvature() {
    let mesh = Sample::Dome.mesh();
    let diag = mesh.bbox_diagonal();
    // The surface itself, at every vertex (boundary included).
    let exact_max = mesh.positions.iter().map(|p| dome_exact_h(p.x, p.y) * diag).fold(f64::NEG_INFINITY, f64::max);
    let exact_min = mesh.positions.iter().map(|p| dome_exact_h(p.x, p.y) * diag).fold(f64::INFINITY, f64::min);
    // The jet fit, every vertex.
    let field = fit(&mesh);
    let (lo, hi) = (field.summary.min_h * diag, field.summary.max_h * diag);
    let mut worst_rel: f64 = 0.0;
    for (v, c) in field.vertices.iter().enumerate() {
        if !field.boundary[v] {
            let p = mesh.positions[v];
            let h = dome_exact_h(p.x, p.y);
            worst_rel = worst_rel.max((c.mean - h).abs() / h.abs());
        }
    }
    println!(
        "dome: exact H·diag in [{exact_min:.2}, {exact_max:.2}]; jet H·diag in [{lo:.2}, {hi:.2}] (all vertices), interior max rel err {:.2}%; {:?}",
        100.0 * worst_rel,
        field.summary
    );
    // Margin: the flattest spot still has a central sphere of radius < 1.5 diagonals (H·diag
    // −0.84 measured), far from both zero and the sign-change threshold.
    assert!(exact_max < -0.6, "the dome surface has H·diag up to {exact_max}");
    assert!(hi < -0.6, "jet H·diag up to {hi}");
    assert!(hi < -3.0 * SIGN_CHANGE_THRESHOLD);
    assert!(!field.summary.h_changes_sign);
    assert_eq!(field.summary.failed_fits, 0);
    assert_eq!(field.summary.planar_vertices, 0);
    assert!(worst_rel < 0.05);
}

#[test]
fn sphere_cap_is_its_own_central_sphere() {
    let mesh = Sample::SphereCap.mesh();
    let field = fit(&mesh);
    let centre = DVec3::new(0.0, 0.0, -16.0);
    let (mut eh, mut ec): (f64, f64) = (0.0, 0.0);
    for v in (0..mesh.vertex_count()).filter(|&v| !field.boundary[v]) {
        eh = eh.max((field.vertices[v].mean * 20.0 + 1.0).abs());
        ec = ec.max((field.central_spheres[v].center().unwrap() - centre).length() / 20.0);
    }
    println!("sphere cap: max |H·R + 1| {eh:.2e}, max |centre − c|/R {ec:.2e} (interior)");
    assert!(eh < 0.005 && ec < 0.005);
    assert!(!field.summary.h_changes_sign);
}

#[test]
fn wave_roof_changes_sign() {
    let mesh = Sample::WaveRoof.mesh();
    let field = fit(&mesh);
    let diag = mesh.bbox_diagonal();
    println!("wave roof: H·diag in [{:.2}, {:.2}]; {:?}", field.summary.min_h * diag, field.summary.max_h * diag, field.summary);
    assert!(field.summary.h_changes_sign);
    assert_eq!(field.summary.failed_fits, 0);
}

#[test]
fn torus_sample_matches_closed_form() {
    let mesh = Sample::TorusPatch.mesh();
    let field = fit(&mesh);
    let (big_r, r) = (16.0, 5.0);
    let (mut eh, mut e1, mut e2): (f64, f64, f64) = (0.0, 0.0, 0.0);
    for v in (0..mesh.vertex_count()).filter(|&v| !field.boundary[v]) {
        let p = mesh.positions[v];
        let vv = p.z.atan2(p.x.hypot(p.y) - big_r);
        let (k_mer, k_par) = torus_closed_form(big_r, r, vv);
        let (k1, k2) = (-k_par, -k_mer); // outward normal
        let c = field.vertices[v];
        eh = eh.max((c.mean - 0.5 * (k1 + k2)).abs() / (0.5 * (k1 + k2)).abs());
        e1 = e1.max((c.k1 - k1).abs() * r);
        e2 = e2.max((c.k2 - k2).abs() / k2.abs());
    }
    println!("torus sample: max rel err H {:.2}%, k2 (meridian) {:.2}%, |k1 err|·r {:.2}% (interior)", 100.0 * eh, 100.0 * e2, 100.0 * e1);
    assert!(eh < 0.03 && e2 < 0.02 && e1 < 0.02);
    assert!(!field.summary.h_changes_sign);
    assert!(field.summary.max_h < 0.0);
}
