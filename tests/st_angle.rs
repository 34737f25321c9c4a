//! Angle-minimizing ST meshes (issue 4 §4). Run with `-- --nocapture` for the numbers.
#![cfg(not(target_arch = "wasm32"))] // native: reads ../shared

use glam::DVec3;
use spherical_faces::curvature::{jet_fit, JetParams};
use spherical_faces::export::closest::TriangleBvh;
use spherical_faces::import::import_mesh;
use spherical_faces::mesh::{Topology, TriMesh};
use spherical_faces::remesh::RemeshParams;
use spherical_faces::solver::{check_jacobian, TermId};
use spherical_faces::sphere::Sphere;
use spherical_faces::st_angle::{
    build_problem, closest_family_member, initial_spheres, max_gap, pack, st_angle, FaceAdjacency, StAngleEvent,
    StAngleParams, StAngleResult, StAngleWeights, StSizing, StVariant,
};

fn load(name: &str) -> TriMesh {
    let path = format!("{}/../shared/data/meshes/{name}.obj", env!("CARGO_MANIFEST_DIR"));
    let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    import_mesh(&bytes, &format!("{name}.obj")).expect("imports").mesh
}

fn clock() -> f64 {
    use std::sync::OnceLock;
    static START: OnceLock<std::time::Instant> = OnceLock::new();
    START.get_or_init(std::time::Instant::now).elapsed().as_secs_f64() * 1e3
}

fn params(sizing: StSizing, variant: StVariant, iterations: [usize; 4]) -> StAngleParams {
    StAngleParams {
        sizing,
        variant,
        remesh: RemeshParams { rounds: 6, ..Default::default() },
        stages: StAngleParams::stages_with(iterations),
        ..Default::default()
    }
}

fn run(name: &str, p: &StAngleParams) -> StAngleResult {
    let mesh = load(name);
    let mut log = Vec::new();
    let r = st_angle(&mesh, p, Some(clock), &mut |e| {
        if let StAngleEvent::Iteration { stage, iteration, energy, terms, .. } = e {
            let angle = terms.iter().find(|t| t.name == "angle").map_or(0.0, |t| t.max_abs);
            log.push(format!("  {stage:>9} it {iteration:3} E {energy:.3e} max(1-cos) {angle:.2e}"));
        }
        true
    })
    .unwrap_or_else(|e| panic!("{name}: {e}"));
    if std::env::var("ST_ANGLE_LOG").is_ok() {
        println!("{}", log.join("\n"));
    }
    println!(
        "{name} {:?} {:?}: {} faces, {} iterations, median {:?} ms/iteration, timings {:?}\n  initial {:?}\n  final   {:?}",
        p.sizing,
        p.variant,
        r.metrics.faces,
        r.iterations,
        r.angle_iteration_median_ms,
        r.timings_ms,
        r.initial_metrics,
        r.metrics
    );
    for t in &r.terms {
        println!("    term {:>20} w {:.1e} mean {:.2e} max {:.2e} E {:.2e}", t.name, t.weight, t.mean_abs, t.max_abs, t.energy);
    }
    r
}

fn check_result(name: &str, r: &StAngleResult) {
    let (i, f) = (&r.initial_metrics, &r.metrics);
    assert!(f.max_vertex_sphere_residual <= 1e-8, "{name}: residual {}", f.max_vertex_sphere_residual);
    assert!(f.mean_kink_angle_deg < i.mean_kink_angle_deg, "{name}: mean kink {} → {}", i.mean_kink_angle_deg, f.mean_kink_angle_deg);
    assert!(f.max_kink_angle_deg < i.max_kink_angle_deg, "{name}: max kink {} → {}", i.max_kink_angle_deg, f.max_kink_angle_deg);
    assert!(f.max_distance_to_reference.is_finite());
    assert_eq!(r.sphere_mesh.face_spheres.len(), r.sphere_mesh.mesh.face_count());
}

#[test]
fn family_member_passes_through_points_and_is_closest() {
    let p = [DVec3::new(0.0, 0.0, 0.1), DVec3::new(1.0, 0.1, 0.0), DVec3::new(0.2, 1.0, 0.05)];
    let target = Sphere::from_center_radius(DVec3::new(0.3, 0.3, 2.0), 2.0).normalized();
    let s = closest_family_member(p, &target);
    for q in p {
        assert!(s.distance(q) < 1e-12);
    }
    let best = s.inversive_product(&target);
    let [s0, s1] = Sphere::through_points_family(p);
    for k in 0..64 {
        let th = k as f64 * std::f64::consts::TAU / 64.0;
        let m = Sphere::combine(&s0, th.cos(), &s1, th.sin());
        assert!(m.inversive_product(&target) <= best + 1e-12);
    }
    // Oriented like the triangle.
    let n = (p[1] - p[0]).cross(p[2] - p[0]);
    assert!(s.normal_at(p[0]).dot(n) > 0.0);
}

#[test]
fn every_term_has_a_correct_jacobian() {
    let reference = load("tri_mesh");
    let diag = reference.bbox_diagonal();
    let (lo, hi) = reference.bbox();
    let t = 0.5 * (lo + hi);
    let nref = TriMesh::new(reference.positions.iter().map(|&p| (p - t) / diag).collect(), reference.triangles.clone());
    // A small patch of the reference as the mesh: its first faces.
    let c0 = nref.face_points(0).iter().sum::<DVec3>() / 3.0;
    let mut order: Vec<usize> = (0..nref.face_count()).collect();
    let dist = |f: usize| (nref.face_points(f).iter().sum::<DVec3>() / 3.0).distance(c0);
    order.sort_by(|&a, &b| dist(a).total_cmp(&dist(b)));
    let faces: Vec<[u32; 3]> = order[..40].iter().map(|&f| nref.triangles[f]).collect();
    let mut used: Vec<u32> = faces.iter().flatten().copied().collect();
    used.sort_unstable();
    used.dedup();
    let remap = |v: u32| used.binary_search(&v).unwrap() as u32;
    let mut rng = 12345u64;
    let mut rnd = || {
        rng = rng.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((rng >> 11) as f64 / (1u64 << 53) as f64) - 0.5
    };
    let positions: Vec<DVec3> = used.iter().map(|&v| nref.positions[v as usize] + 1e-3 * DVec3::new(rnd(), rnd(), rnd())).collect();
    let mesh = TriMesh::new(positions, faces.iter().map(|t| t.map(remap)).collect());
    let topo = Topology::new(&nref);
    let field = jet_fit(&nref, &topo, &JetParams::default(), &mut |_, _| true).unwrap();
    let vs: Vec<Sphere> = used.iter().map(|&v| field.central_spheres[v as usize]).collect();
    let spheres = initial_spheres(&mesh, &vs);
    let adjacency = FaceAdjacency::new(&mesh);
    assert!(!adjacency.interior.is_empty());
    let bvh = TriangleBvh::new(&nref);
    let normals = nref.vertex_normals();
    let mut x = pack(&mesh.positions, &spheres);
    for xi in x.iter_mut() {
        *xi += 1e-3 * rnd();
    }
    let weights = StAngleWeights { edge_orthogonality: 1.0, ..Default::default() };
    let (mut problem, _) = build_problem(&mesh, &adjacency, &nref, &bvh, &normals, &weights, &x);
    problem.prepare(&x);
    for i in 0..problem.num_terms() {
        let term = problem.term(TermId(i));
        let err = check_jacobian(term, &x, 1e-6);
        println!("{:>20}: FD error {err:.2e}", term.name());
        assert!(err < 1e-6, "{}: {err}", term.name());
    }
}

#[test]
fn tri_mesh_optimization_lowers_kinks() {
    let p = params(StSizing::UniformFaces(250), StVariant::A, [3, 10, 10, 8]);
    let r = run("tri_mesh", &p);
    check_result("tri_mesh", &r);
    assert_eq!(r.metrics.flipped_faces, 0);
}

#[test]
fn bubble_optimization_lowers_kinks_variant_b() {
    let p = params(StSizing::UniformFaces(250), StVariant::B, [3, 10, 10, 8]);
    let r = run("botanic-garden-bubble-0", &p);
    check_result("bubble", &r);
    assert_eq!(r.metrics.flipped_faces, 0);
    let gap = r.metrics.max_gap.expect("variant b reports the gap");
    assert!(gap.is_finite() && gap >= 0.0);
    // Recomputing the gap on the result matches.
    let a = FaceAdjacency::new(&r.sphere_mesh.mesh);
    let g = max_gap(&r.sphere_mesh.mesh, &r.sphere_mesh.face_spheres, &a) / r.diag;
    assert!((g - gap).abs() <= 1e-12 + 1e-9 * gap);
}

#[test]
fn enneper_is_refused() {
    let mesh = load("enneper2");
    let err = st_angle(&mesh, &StAngleParams::default(), None, &mut |_| true).expect_err("minimal surface refused");
    println!("enneper2: {err}");
    assert!(err.contains("no usable central spheres"), "{err}");
}

#[test]
fn cancel_from_hook() {
    let mesh = load("tri_mesh");
    let p = params(StSizing::UniformFaces(150), StVariant::A, [3, 3, 3, 3]);
    let mut n = 0;
    let err = st_angle(&mesh, &p, None, &mut |e| {
        if matches!(e, StAngleEvent::Iteration { .. }) {
            n += 1;
        }
        n < 2
    })
    .expect_err("cancelled");
    assert_eq!(err, "cancelled");
}

#[test]
fn adaptive_vs_uniform_distance_at_equal_face_count() {
    let name = "tri_mesh";
    let eps = std::env::var("ST_ANGLE_EPS").ok().and_then(|s| s.parse().ok()).unwrap_or(2e-3);
    let pa = params(StSizing::Adaptive { epsilon: eps }, StVariant::A, [3, 10, 10, 8]);
    let ra = run(name, &pa);
    let pu = params(StSizing::UniformFaces(ra.metrics.faces), StVariant::A, [3, 10, 10, 8]);
    let ru = run(name, &pu);
    println!(
        "adaptive ε={eps}: {} faces, dist {:.3e} (init {:.3e}); uniform: {} faces, dist {:.3e} (init {:.3e})",
        ra.metrics.faces,
        ra.metrics.max_distance_to_reference,
        ra.initial_metrics.max_distance_to_reference,
        ru.metrics.faces,
        ru.metrics.max_distance_to_reference,
        ru.initial_metrics.max_distance_to_reference
    );
    check_result("adaptive", &ra);
    check_result("uniform", &ru);
    assert_eq!(ra.metrics.flipped_faces + ru.metrics.flipped_faces, 0);
    let ratio = ru.metrics.faces as f64 / ra.metrics.faces as f64;
    assert!((0.8..1.25).contains(&ratio), "face counts differ too much: {ratio}");
    assert!(
        ra.metrics.max_distance_to_reference < ru.metrics.max_distance_to_reference,
        "adaptive {} ≥ uniform {}",
        ra.metrics.max_distance_to_reference,
        ru.metrics.max_distance_to_reference
    );
}

/// Prints ms per angle iteration at about 600 faces:
/// `cargo test --release --test st_angle -- --ignored --nocapture timing`.
#[test]
#[ignore]
fn timing_about_600_faces() {
    for name in ["tri_mesh", "botanic-garden-bubble-0"] {
        let p = params(StSizing::UniformFaces(600), StVariant::A, [3, 10, 10, 8]);
        let r = run(name, &p);
        check_result(name, &r);
        // Not asserted: at ~600 faces the bubble ends with a couple of flipped faces (reported).
        println!(
            "TIMING {name}: {} faces, median {:.3} ms/iteration, flipped faces {}",
            r.metrics.faces,
            r.angle_iteration_median_ms.unwrap(),
            r.metrics.flipped_faces
        );
    }
}

#[test]
fn report_has_the_st_schema() {
    let mesh = load("tri_mesh");
    let p = params(StSizing::UniformFaces(120), StVariant::B, [2, 3, 3, 3]);
    let r = st_angle(&mesh, &p, Some(clock), &mut |_| true).unwrap();
    let (report, files) = spherical_faces::pipeline::st_angle::report_and_files(&mesh, &r, 1e-3);
    let json: serde_json::Value = serde_json::from_str(&report.to_json()).unwrap();
    assert_eq!(json["method"], "st");
    for k in ["max_vertex_sphere_residual", "mean_kink_angle_deg", "max_kink_angle_deg", "max_distance_to_reference", "max_gap", "angle_iterations"] {
        assert!(json["metrics"][k].is_number(), "{k} in {json}");
    }
    assert!(json["timings_ms"]["angle_iteration_median"].is_number());
    let names: Vec<&str> = files.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(names, ["panels.glb", "panels.obj", "panels.csv", "panels.json", "report.json"]);
    println!("{}", report.to_json());
}
