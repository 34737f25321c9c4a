//! ST meshes with support structure (Sec. 4): the absolute sphere Ω (synthetic recovery of m,
//! the LM Jacobian, the orientation flip, the trivial sphere and the plane case, the
//! minimal-surface refusal) and the full construction on the reference meshes `tri_mesh.obj`,
//! `botanic-garden-bubble-0.obj` (quads, triangulated by the importer) and `cmc1.obj`.
#![cfg(not(target_arch = "wasm32"))] // native: reads ../shared, spawns processes

mod common;

use common::load;
use glam::DVec3;
use spherical_faces::congruence::central_spheres::{jet_fit, JetParams};
use spherical_faces::geometry::absolute_sphere::AbsoluteSphere;
use spherical_faces::geometry::mesh::topology::Topology;
use spherical_faces::geometry::mesh::{PolyMesh, TriMesh};
use spherical_faces::panels::moulds::Fabrication;
use spherical_faces::panels::sphere_mesh::BoundaryArcRule;
use spherical_faces::progress::{ignore, Cancelled, Clock, OnProgress};
use spherical_faces::reference::Reference;
use spherical_faces::rng::Rng;
use spherical_faces::samples::{sphere_cap, Sample};
use spherical_faces::st_support::absolute_sphere::{
    center_from_normals, e_center, e_center_residuals, estimate_absolute_sphere, m0_from_normal_lines, spherical_barycenter, AbsoluteSphereParams,
};
use spherical_faces::st_support::metrics::{metrics, Counts};
use spherical_faces::st_support::{compute, guarantees, StSupportError, StSupportParams, StSupportResult};
use spherical_faces::stats::{summary_stats, Histogram};

const MESHES: [&str; 3] = ["tri_mesh", "botanic-garden-bubble-0", "cmc1"];

fn st_support(mesh: &TriMesh, params: &StSupportParams, progress: &mut OnProgress) -> Result<StSupportResult, StSupportError> {
    compute(&Reference::from_triangles(mesh.clone()), params, &Fabrication::default(), Clock::native(), progress)
}

fn run(mesh: &TriMesh, optimize_radius: bool) -> StSupportResult {
    let params = StSupportParams { optimize_radius, ..Default::default() };
    st_support(mesh, &params, &mut ignore).expect("st-support succeeds")
}

/// A wavy patch z = f(x, y) over [−5, 5]² (points only) with normals pointing exactly away from m.
fn synthetic(m: DVec3, rng: &mut Rng, noise: f64) -> (Vec<DVec3>, Vec<DVec3>) {
    let mut pts = Vec::new();
    let mut nrm = Vec::new();
    for i in 0..15 {
        for j in 0..15 {
            let (x, y) = (-5.0 + i as f64 * 10.0 / 14.0, -5.0 + j as f64 * 10.0 / 14.0);
            let p = DVec3::new(x, y, 0.3 * (0.7 * x).sin() * (0.5 * y).cos());
            pts.push(p);
            nrm.push(((p - m).normalize() + rng.vec(noise)).normalize());
        }
    }
    (pts, nrm)
}

#[test]
fn center_is_recovered_when_normals_point_away_from_it() {
    let mut rng = Rng(1);
    let params = AbsoluteSphereParams::default();
    for m in [DVec3::new(0.5, -1.0, -8.0), DVec3::new(3.0, 2.0, -2.0), DVec3::new(-1.0, 0.0, -30.0)] {
        let (pts, nrm) = synthetic(m, &mut rng, 0.0);
        let m0 = m0_from_normal_lines(&pts, &nrm).unwrap();
        assert!((m0 - m).length() < 1e-9 * m.length(), "m0 {m0} vs {m}");
        let (est, normals) = center_from_normals(&pts, &nrm, &params).unwrap();
        assert!(!est.flipped);
        assert!((est.m - m).length() < 1e-9 * m.length(), "m {} vs {m}", est.m);
        assert!(est.e_m < 1e-20);
        assert_eq!(normals, nrm);
        // Normals pointing toward m: m0 is on the positive side, the orientation is flipped and
        // m is recovered with the negated normals.
        let inward: Vec<DVec3> = nrm.iter().map(|n| -*n).collect();
        let (est, normals) = center_from_normals(&pts, &inward, &params).unwrap();
        assert!(est.flipped);
        assert_eq!(normals, nrm);
        assert!((est.m - m).length() < 1e-9 * m.length());
    }
    // With noisy normals the LM reaches a stationary point of E_center that beats m0.
    let m = DVec3::new(0.5, -1.0, -8.0);
    let (pts, nrm) = synthetic(m, &mut rng, 0.05);
    let (est, normals) = center_from_normals(&pts, &nrm, &params).unwrap();
    assert!(est.e_m <= est.e_m0);
    let (r, g) = e_center_residuals(&pts, &normals, est.m);
    let grad = r.iter().zip(&g).fold(DVec3::ZERO, |s, (ri, gi)| s + *gi * *ri);
    assert!(grad.length() < 1e-10, "gradient {grad}");
    for _ in 0..20 {
        let d = rng.vec(0.05);
        assert!(e_center(&pts, &normals, est.m + d) >= est.e_m);
    }
    assert!((est.m - m).length() < 1.5, "{} vs {m}", est.m);
}

#[test]
fn e_center_jacobian_matches_finite_differences() {
    let mut rng = Rng(2);
    let (pts, nrm) = synthetic(DVec3::new(1.0, 0.0, -6.0), &mut rng, 0.2);
    for _ in 0..10 {
        let m = DVec3::new(0.0, 0.0, -4.0) + rng.vec(3.0);
        let (r, g) = e_center_residuals(&pts, &nrm, m);
        let h = 1e-6;
        for k in 0..3 {
            let mut e = DVec3::ZERO;
            e[k] = h;
            let (rp, _) = e_center_residuals(&pts, &nrm, m + e);
            let (rm, _) = e_center_residuals(&pts, &nrm, m - e);
            for i in 0..pts.len() {
                let fd = (rp[i] - rm[i]) / (2.0 * h);
                assert!((fd - g[i][k]).abs() < 1e-7 * (1.0 + g[i][k].abs()), "i {i} k {k}: fd {fd} vs {}", g[i][k]);
            }
        }
        assert!((r.iter().map(|x| x * x).sum::<f64>() - e_center(&pts, &nrm, m)).abs() < 1e-12);
    }
}

#[test]
fn spherical_barycenter_and_histogram() {
    let a = DVec3::new(1.0, 2.0, 2.0) / 3.0;
    let (u, v) = (a.any_orthonormal_vector(), a.cross(a.any_orthonormal_vector()));
    // Symmetric about a: the Karcher mean is a.
    let normals: Vec<DVec3> = (0..12)
        .map(|k| {
            let phi = k as f64 * std::f64::consts::TAU / 12.0;
            (a * 0.6f64.cos() + (u * phi.cos() + v * phi.sin()) * 0.6f64.sin()).normalize()
        })
        .collect();
    assert!((spherical_barycenter(&normals).unwrap() - a).length() < 1e-14);
    // Unequal spread: the Karcher mean minimizes the sum of squared geodesic distances.
    let n2 = vec![DVec3::Z, DVec3::Z, DVec3::X];
    let b = spherical_barycenter(&n2).unwrap();
    let angle = b.dot(DVec3::Z).acos();
    assert!((angle - std::f64::consts::FRAC_PI_2 / 3.0).abs() < 1e-12, "{angle}");
    let h = Histogram::new(&[0.0, 1.0, 2.0, 3.0, 4.0], 4);
    assert_eq!(h.counts, vec![1, 1, 1, 2]);
    assert_eq!(summary_stats(&[3.0, 1.0, 2.0]), (2.0, 2.0, 3.0));
}

#[test]
fn sphere_cap_stays_trivial() {
    let mesh = Sample::SphereCap.mesh();
    let r = run(&mesh, false);
    let centre = DVec3::new(0.0, 0.0, -20.0 * (12.0f64 / 20.0).asin().cos());
    let est = &r.absolute;
    assert!(!est.flipped && !est.at_infinity);
    assert!((est.m - centre).length() < 1e-3 * r.diag, "m {} vs {centre}", est.m);
    // Ω is (about) the imaginary sphere R² = −r²: every face sphere is the cap's own sphere.
    match r.omega {
        AbsoluteSphere::Sphere { r2, .. } => assert!((r2 + 400.0).abs() < 0.05 * 400.0, "R² {r2}"),
        _ => panic!("plane"),
    }
    let m = &r.metrics;
    assert!(m.mean_kink_angle_deg < 0.05 && m.max_kink_angle_deg < 0.5, "{m:?}");
    assert!(m.mean_axis_normal_angle_deg < 0.1, "{m:?}");
    assert!(m.max_vertex_sphere_residual < 1e-12 && m.max_orthogonality_residual < 1e-12);
    assert!(m.max_node_axis_offset < 1e-9);
    for s in &r.sphere_mesh.face_spheres {
        assert!((s.center().unwrap() - centre).length() < 0.05 * 20.0);
        // Oriented like the outward faces: the normal b − 2ax = (c − x)/r points away from the
        // centre, so r < 0.
        assert!(s.signed_radius().unwrap() < 0.0);
    }
    assert!(r.support.node_axes.axes.iter().all(|(p, d)| d.is_finite() && p.is_finite()));
}

#[test]
fn distant_centre_makes_omega_a_plane() {
    // A very flat cap: its centre is ≈ 59 diagonals away, beyond `far_factor` = 50.
    let mesh = sphere_cap(2000.0, 12.0, 12);
    let r = run(&mesh, false);
    let est = &r.absolute;
    assert!(est.at_infinity, "m {} R² {:?}", est.m, est.omega);
    let (axis, d) = match r.omega {
        AbsoluteSphere::Plane { axis, d } => (axis, d),
        _ => panic!("not a plane"),
    };
    assert!((axis - DVec3::Z).length() < 1e-9);
    assert!(d < -1500.0, "d {d}");
    assert_eq!(r.sphere_mesh.boundary_arcs, BoundaryArcRule::Parallel(axis));
    let m = &r.metrics;
    assert_eq!(m.max_orthogonality_residual, 0.0);
    assert!(m.max_center_plane_residual < 1e-9, "{m:?}");
    assert!(m.max_vertex_sphere_residual < 1e-9);
    assert!(m.max_node_axis_offset < 1e-9, "{m:?}");
    let verdict = guarantees::verdict(m, &r.omega, &panels_of(&r), 1.0);
    let names: Vec<&str> = verdict.guarantees.iter().map(|g| g.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "max_vertex_sphere_residual",
            "max_center_plane_residual",
            "max_node_axis_offset",
            "panels_with_crossing_arcs",
            "panels_without_exact_surface",
            "support_elements_that_fold",
            "max_distance_to_reference"
        ]
    );
    assert!(verdict.holds(), "{}", verdict.failure_text());
    // Node axes are parallel to a, toward −a; the second points are the reflections.
    for (v, (p, dir)) in r.support.node_axes.axes.iter().enumerate() {
        assert!(dir.dot(-axis) > 1.0 - 1e-12);
        if let Some(q) = r.support.node_axes.second_points[v] {
            let refl = *p - 2.0 * (p.dot(axis) - d) * axis;
            assert!((q - refl).length() < 1e-9 * (refl - *p).length().max(r.diag));
        }
    }
    assert!(r.second_envelope.is_some());
}

#[test]
fn minimal_surface_is_refused_with_a_clear_message() {
    let mesh = load("enneper2");
    let err = st_support(&mesh, &StSupportParams::default(), &mut ignore).unwrap_err().to_string();
    assert!(err.contains("no usable central spheres") && err.contains("H ≈ 0 on") && err.contains("minimal surface"), "{err}");
    // The same from the estimate itself, with the counts.
    let topo = Topology::new(&mesh);
    let field = jet_fit(&mesh, &topo, &JetParams::default(), &mut spherical_faces::progress::ignore).unwrap();
    let err = estimate_absolute_sphere(&mesh, &field, &AbsoluteSphereParams::default()).unwrap_err().to_string();
    assert!(err.contains(&format!("of {} vertices", mesh.vertex_count())), "{err}");
}

#[test]
fn cancellation_stops_the_run() {
    let mesh = Sample::SphereCap.mesh();
    let mut seen = Vec::new();
    let err = st_support(&mesh, &StSupportParams::default(), &mut |p| {
        seen.push(p.step.to_string());
        if p.step == "face_spheres" {
            Err(Cancelled)
        } else {
            Ok(())
        }
    })
    .unwrap_err();
    assert_eq!(err, StSupportError::Cancelled);
    // It stopped at the first face-sphere report: nothing after it ran.
    assert!(seen.iter().any(|s| s == "jet_fit") && seen.iter().any(|s| s == "absolute_sphere"));
    assert_eq!(seen.last().map(String::as_str), Some("face_spheres"));
    assert_eq!(seen.iter().filter(|s| *s == "face_spheres").count(), 1);
}

/// The full method on the three reference meshes: the residual bounds of Sec. 4, the inversion property
/// for R² > 0, the support-element geometry, and the R optimization.
#[test]
fn reference_meshes_meet_the_bounds() {
    for name in MESHES {
        let mesh = load(name);
        let plain = run(&mesh, false);
        check_result(name, &mesh, &plain);
        let opt = run(&mesh, true);
        check_result(name, &mesh, &opt);
        assert!(
            opt.metrics.mean_kink_angle_deg <= plain.metrics.mean_kink_angle_deg + 1e-9,
            "{name}: optimized {} vs estimate {}",
            opt.metrics.mean_kink_angle_deg,
            plain.metrics.mean_kink_angle_deg
        );
        assert!((opt.mean_kink_estimate_deg - plain.metrics.mean_kink_angle_deg).abs() < 1e-9);
    }
}

/// The verdict is measured on the panels, not taken from the method: a vertex moved off its
/// spheres by 1e-6 of the diagonal misses the vertex–sphere guarantee by that much.
#[test]
fn a_vertex_off_its_spheres_misses_the_guarantee() {
    let r = run(&load("cmc1"), false);
    assert!(guarantees::verdict(&r.metrics, &r.omega, &panels_of(&r), 1.0).holds());
    let mut moved = r.sphere_mesh.clone();
    let n = r.absolute.normals[7];
    moved.mesh.positions[7] += 1e-6 * r.diag * n;
    let counts = Counts { degenerate_faces: r.metrics.degenerate_faces, edges_without_support: r.metrics.edges_without_support };
    let m = metrics(&moved, &r.omega, &r.support.node_axes, &r.absolute.normals, r.diag, counts);
    let verdict = guarantees::verdict(&m, &r.omega, &panels_of(&r), 1.0);
    let missed: Vec<&str> = verdict.failures().map(|g| g.name.as_str()).collect();
    assert_eq!(missed, ["max_vertex_sphere_residual"], "{}", verdict.failure_text());
    let g = &verdict.guarantees[0];
    assert!((g.measured - 1e-6).abs() < 1e-7, "{g}");
    assert!(verdict.failure_text().contains("max_vertex_sphere_residual"));
}

/// What stops the result's panels from being built, with no distance measured (0 for every panel).
fn panels_of(r: &StSupportResult) -> spherical_faces::panels::buildability::Buildability {
    let distances = vec![0.0; r.panels.len()];
    spherical_faces::panels::buildability::Buildability::of_panels(&r.panels, Some(&r.support.elements), &distances, r.diag, Default::default())
}

fn check_result(name: &str, mesh: &TriMesh, r: &StSupportResult) {
    let m = &r.metrics;
    assert!(m.max_vertex_sphere_residual <= 1e-9, "{name}: {m:?}");
    assert!(m.max_orthogonality_residual <= 1e-9, "{name}: {m:?}");
    assert!(m.max_node_axis_offset <= 1e-9, "{name}: {m:?}");
    assert_eq!(m.degenerate_faces, 0, "{name}");
    assert_eq!(m.edges_without_support, 0, "{name}");
    // Every vertex with at least 3 faces gets its axis from its star.
    let topo = Topology::new(mesh);
    let with_star = (0..mesh.vertex_count()).filter(|&v| topo.vertex_faces(v).len() >= 3).count();
    assert_eq!(m.axes_from_spheres, with_star, "{name}");
    let sm = &r.sphere_mesh;
    assert_eq!(sm.face_spheres.len(), mesh.face_count());
    assert_eq!(r.support.elements.len(), topo.edges().len());
    // Face spheres are oriented like the (working) faces.
    for (f, s) in sm.face_spheres.iter().enumerate() {
        let p = sm.mesh.face_points(f);
        let [a, b, c] = [p[0], p[1], p[2]];
        let n = (b - a).cross(c - a);
        assert!(s.normal_at(a).dot(n) > 0.0, "{name}: face {f} misoriented");
        assert!((s.discriminant() - 1.0).abs() < 1e-12);
    }
    // Working orientation: reversed winding iff flipped.
    let same = sm.mesh.faces == PolyMesh::from(mesh).faces;
    assert_eq!(same, !r.absolute.flipped, "{name}");
    match r.omega {
        AbsoluteSphere::Sphere { center, r2 } => {
            // For R² > 0 every star's second common point is the inversion of v in Ω (and for
            // R² < 0 the anti-inversion).
            let mut checked = 0;
            for (v, q) in r.support.node_axes.second_points.iter().enumerate() {
                if let Some(q) = q {
                    let p = sm.mesh.positions[v];
                    let inv = r.omega.invert(p).unwrap();
                    let scale = (inv - center).length().max(r.diag);
                    assert!((*q - inv).length() <= 1e-9 * scale, "{name} v{v}: {q} vs {inv} (R² {r2})");
                    checked += 1;
                }
            }
            assert_eq!(checked, m.axes_from_spheres);
            // The second envelope lies on the face spheres too.
            let env = r.second_envelope.as_ref().unwrap();
            for (f, s) in sm.face_spheres.iter().enumerate() {
                for p in env.face_points(f) {
                    assert!(s.distance(p) <= 1e-9 * (p - center).length().max(r.diag), "{name}: envelope off face {f}");
                }
            }
            // Support elements: planar, through m, bounded by the node axes.
            let depth = r.support.depth;
            for el in &r.support.elements {
                let c = el.circle;
                let off = m_dist(center, c.center, c.normal) / r.diag;
                assert!(off < 1e-9, "{name}: m not in the element plane of {:?}: {off:e}", el.edge);
                for (k, v) in el.edge.iter().enumerate() {
                    let p = el.corners[k];
                    assert_eq!(p, sm.mesh.positions[*v as usize]);
                    assert!((((p - c.center).length() - c.radius).abs()) < 1e-9 * r.diag);
                    assert!(m_dist(p, c.center, c.normal) < 1e-9 * r.diag);
                    // The inner corner is on the node axis, in the plane, on the inner circle.
                    let q = el.corners[3 - k];
                    let (_, dir) = r.support.node_axes.axes[*v as usize];
                    assert!((q - p).cross(dir).length() < 1e-9 * r.diag, "{name}: inner corner off the axis");
                    assert!((q - p).dot(dir) > 0.0);
                    assert!(m_dist(q, c.center, c.normal) < 1e-9 * r.diag);
                    let ic = el.inner_circle;
                    assert!((((q - ic.center).length() - ic.radius).abs()) < 1e-9 * r.diag);
                    assert!((q - p).length() < 20.0 * depth);
                }
            }
        }
        AbsoluteSphere::Plane { .. } => {}
    }
    for s in &r.timings_ms {
        assert!(s.1 >= 0.0 && s.1.is_finite());
    }
}

/// Distance of x from the plane through p with unit normal n.
fn m_dist(x: DVec3, p: DVec3, n: DVec3) -> f64 {
    (x - p).dot(n).abs()
}

/// Every built-in sample runs (the app's default is the Dome) with sane output.
#[test]
fn samples_run() {
    for sample in Sample::ALL {
        let mesh = sample.mesh();
        for opt in [false, true] {
            let r = run(&mesh, opt);
            let m = &r.metrics;
            println!("{:?} opt={opt}: Ω {:?} inf {} flipped {} {m:?}", sample, r.omega, r.absolute.at_infinity, r.absolute.flipped);
            assert!(
                m.max_vertex_sphere_residual <= 1e-9 && m.max_orthogonality_residual <= 1e-9 && m.max_center_plane_residual <= 1e-9,
                "{sample:?}: {m:?}"
            );
            assert!(m.max_node_axis_offset <= 1e-9, "{sample:?}: {m:?}");
            assert!(m.mean_kink_angle_deg.is_finite() && m.mean_axis_normal_angle_deg.is_finite());
        }
    }
}

/// With remeshing first, the distances in the report and the schedule are measured to the
/// reference as loaded, not to the remesh the method ran on.
#[test]
fn remeshed_runs_measure_distances_to_the_original_reference() {
    use spherical_faces::panels::deviation::max_deviation;
    use spherical_faces::pipeline::method::export;
    use spherical_faces::pipeline::stages::st_support::StSupportStage;
    use spherical_faces::remeshing::Sizing;
    let reference = common::load_reference("tri_mesh");
    let params = StSupportParams { remesh: Sizing::UniformFaces(300), ..Default::default() };
    let result = compute(&reference, &params, &Fabrication::default(), Clock::default(), &mut ignore).unwrap();
    assert_ne!(result.sphere_mesh.mesh.face_count(), reference.mesh().face_count(), "remeshed");
    let (report, files) = export::<StSupportStage>(&reference, &result, &params, &Fabrication::default(), Clock::default());
    let to_original = result.panels.iter().map(|p| max_deviation(p, &reference)).fold(0.0, f64::max);
    let remesh = Reference::from_triangles(result.sphere_mesh.mesh.triangulated());
    let to_remesh = result.panels.iter().map(|p| max_deviation(p, remesh.bvh())).fold(0.0, f64::max);
    assert_eq!(report.metrics.map(|m| m.max_distance_to_reference), Some(to_original / result.diag));
    assert!((to_original - to_remesh).abs() > 1e-3 * to_original, "{to_original} vs {to_remesh}: the two measures should differ");
    let schedule: serde_json::Value = serde_json::from_slice(&files[3].bytes).unwrap();
    assert_eq!(schedule["reference_diagonal"], reference.diagonal());
    assert_eq!(report.input.faces, reference.mesh().face_count());
}
