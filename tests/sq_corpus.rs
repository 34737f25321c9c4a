//! A corpus of generated roofs of one-signed H: gently perturbed domes, vaults and saddles
//! (degree-3 B-splines over a span of 10, noise 0.05), the kinds architects bring. Every SQ run
//! either meets every guarantee or says it does not: its verdict is checked against the
//! guarantees recomputed here from the delivered vertices and face spheres alone (points on the
//! spheres, coplanar centres around inner vertices, node axes within θ, support planes at ≥ α,
//! quads only). No silent miss.
#![cfg(not(target_arch = "wasm32"))]

use glam::DVec3;
use spherical_faces::geometry::bspline::{BSplineBasis, BSplineSurface};
use spherical_faces::panels::moulds::Fabrication;
use spherical_faces::progress::Clock;
use spherical_faces::reference::Reference;
use spherical_faces::rng::Rng;
use spherical_faces::sq::params::{RadiusStart, SqParams};
use spherical_faces::sq::radius::{check_mean_curvature, SamplingGrid};
use spherical_faces::sq::sphere_optimization::QuadStars;
use spherical_faces::sq::{compute, SqError};

/// Which kind of roof.
#[derive(Clone, Copy, Debug)]
enum Kind {
    Dome,
    Vault,
    Saddle,
}

/// A degree-3 B-spline with 7 × 7 control points over [−5, 5]² of height `z` plus noise.
fn roof(kind: Kind, seed: u64) -> BSplineSurface {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15 ^ seed.wrapping_mul(0x2545_f491_4f6c_dd1d));
    let (n, p) = (7, 3);
    let basis = || BSplineBasis::clamped_uniform(p, n, (0.0, 1.0)).unwrap();
    let (bu, bv) = (basis(), basis());
    let (gu, gv) = (bu.greville(), bv.greville());
    let (a, b, c) = (rng.range(0.8, 1.2), rng.range(0.8, 1.2), rng.range(-0.3, 0.3));
    let z = |x: f64, y: f64| match kind {
        Kind::Dome => 3.0 * a - 0.06 * a * x * x - 0.06 * b * y * y + 0.01 * c * x * y,
        Kind::Vault => 4.0 * a - 0.12 * a * x * x - 0.01 * b * y * y + 0.02 * c * x,
        // H > 0 needs the convex curvature to win: 0.09 x² against 0.03 y².
        Kind::Saddle => 1.0 + 0.09 * a * x * x - 0.03 * b * y * y + 0.01 * c * x * y,
    };
    let mut control = Vec::with_capacity(n * n);
    for &v in &gv {
        for &u in &gu {
            let (x, y) = (10.0 * u - 5.0, 10.0 * v - 5.0);
            control.push(DVec3::new(x, y, z(x, y) + rng.range(-0.05, 0.05)));
        }
    }
    BSplineSurface::new(bu, bv, control, vec![1.0; n * n]).unwrap()
}

/// Independently of the method's figures: whether the delivered SQ mesh meets every guarantee.
fn recheck(mesh: &spherical_faces::sq::sq_mesh::SqMesh, normals: &[DVec3], diag: f64, theta: f64, alpha: f64) -> Vec<String> {
    let sm = &mesh.sphere_mesh;
    let m = &sm.mesh;
    let mut misses = Vec::new();
    if m.faces.is_empty() || m.faces.iter().any(|f| f.len() != 4) {
        misses.push("quads only".to_string());
    }
    for (f, face) in m.faces.iter().enumerate() {
        for &v in face.corners() {
            let d = sm.face_spheres[f].distance(m.positions[v as usize]);
            if !(d <= 1e-8 * diag) {
                misses.push(format!("vertex {v} off the sphere of face {f} by {:.1e}", d / diag));
            }
        }
    }
    for (_, faces) in &QuadStars::new(m).stars {
        let c: Vec<DVec3> = faces.iter().map(|&f| sm.face_spheres[f as usize].center().unwrap_or(DVec3::splat(f64::NAN))).collect();
        // Every further centre against the plane of the first three (three centres always lie
        // in a plane: a singular vertex of valence 3): |volume| / |area vector| away.
        for k in 3..c.len() {
            let volume = (c[1] - c[0]).cross(c[2] - c[0]).dot(c[k] - c[0]).abs();
            let edge = (c[1] - c[0]).length().max((c[2] - c[0]).length()).max((c[k] - c[0]).length());
            let area = (c[1] - c[0]).cross(c[2] - c[0]).length().max((c[2] - c[0]).cross(c[k] - c[0]).length());
            if !(volume <= 1e-8 * diag * area.max(1e-300)) && edge > 0.0 {
                misses.push(format!("centres not coplanar: {:.1e}", volume / area / diag));
            }
        }
    }
    for ((_, d), n) in mesh.support.node_axes.axes.iter().zip(normals) {
        let angle = d.cross(*n).length().atan2(d.dot(*n).abs()).to_degrees();
        if !(angle <= theta) {
            misses.push(format!("node axis {angle:.2}° off the normal"));
        }
    }
    if !(mesh.figures.min_torsal_plane_angle_deg >= alpha) {
        misses.push(format!("support planes at {:.2}°", mesh.figures.min_torsal_plane_angle_deg));
    }
    misses
}

/// The guarantees of the delivered panels, recomputed: arcs that cross, support elements that
/// fold, the panels' distance against `params.max_distance` (sampled on the reference's
/// triangulation), and the share of the patch the quads cover at their vertices' parameters.
fn recheck_panels(reference: &Reference, f: &spherical_faces::sq::SqFinal, params: &SqParams) -> Vec<String> {
    use spherical_faces::panels::exact_surface::{arcs_cross, support_patch};
    let mut misses = Vec::new();
    let crossing = f.mesh.panels.iter().filter(|p| arcs_cross(&p.sphere, &p.arcs)).count();
    if crossing > 0 {
        misses.push(format!("{crossing} panels whose arcs cross"));
    }
    let folding = f.mesh.support.elements.iter().filter(|e| support_patch(e).is_err()).count();
    if folding > 0 {
        misses.push(format!("{folding} support elements that fold"));
    }
    let far = f.mesh.panels.iter().map(|p| spherical_faces::panels::deviation::max_deviation(p, reference)).fold(0.0, f64::max);
    if !(far <= params.max_distance * reference.diagonal()) {
        misses.push(format!("panels {:.2e} of the diagonal away", far / reference.diagonal()));
    }
    let share = spherical_faces::remeshing::quad_remeshing::coverage(reference.spline().unwrap(), &f.mesh.sphere_mesh.mesh.faces, &f.uv);
    if !(share >= spherical_faces::sq::guarantees::MIN_COVERAGE) {
        misses.push(format!("{:.1} % of the patch covered", 100.0 * share));
    }
    if f.exact.panels.iter().any(|p| p.is_err()) && crossing == 0 {
        misses.push("panels without their exact surface".into());
    }
    misses
}

/// The guarantees the delivered SQ mesh misses, recomputed here ([`recheck`], [`recheck_panels`]).
fn delivered_misses(reference: &Reference, result: &spherical_faces::sq::SqResult, params: &SqParams) -> Vec<String> {
    let f = result.sq_mesh.as_ref().expect("the SQ mesh");
    let normals: Vec<DVec3> = f.uv.iter().map(|uv| reference.spline().unwrap().derivatives(uv[0], uv[1]).normal().unwrap()).collect();
    let mut misses = recheck(&f.mesh, &normals, reference.diagonal(), params.theta_deg, params.alpha_deg);
    misses.extend(recheck_panels(reference, f, params));
    misses
}

#[test]
fn no_generated_roof_misses_a_guarantee_silently() {
    let params = SqParams { grid: 14, faces: 120, ..SqParams::default() };
    let mut rows = Vec::new();
    let (mut met, mut buildable) = (0, 0);
    let mut seed = 0u64;
    for (k, kind) in [Kind::Dome, Kind::Vault, Kind::Saddle].into_iter().cycle().take(21).enumerate() {
        // The next seed whose roof has H of one sign (the noise can flip a flat saddle's H).
        let surface = loop {
            seed += 1;
            let s = roof(kind, seed);
            let grid = SamplingGrid::new(&s, params.grid).unwrap();
            if check_mean_curvature(&s, &grid, 1.0, params.faces).is_ok_and(|signs| signs.warnings.is_empty()) {
                break s;
            }
            assert!(seed < 1000, "no {kind:?} of one-signed H");
        };
        let reference = Reference::from_bspline(surface).unwrap();
        let result = match compute(&reference, &params, &Fabrication::default(), Clock::native(), &mut |_| Ok(())) {
            Ok(r) => r,
            Err(e @ SqError::MeanCurvatureNearZero { .. }) => panic!("{kind:?} {k}: {e}"),
            Err(e) => panic!("{kind:?} {k}: {e}"),
        };
        let misses = delivered_misses(&reference, &result, &params);
        assert_eq!(result.verdict.holds(), misses.is_empty(), "{kind:?} {k}: verdict {} against {misses:?}", result.verdict.failure_text());
        if !result.verdict.holds() {
            assert!(!result.verdict.failure_text().is_empty());
        }
        // The method's own guarantees (exactness, θ, α, quads); the delivered panels' distance
        // and coverage are counted apart: these roofs are remeshed to 120 quads only.
        let panels_only =
            ["panels_with_crossing_arcs", "panels_without_exact_surface", "support_elements_that_fold", "max_distance_to_reference", "coverage"];
        met += usize::from(result.verdict.failures().all(|g| panels_only.contains(&g.name.as_str())));
        buildable += usize::from(result.verdict.holds());
        let singular = result.quad_mesh.as_ref().filter(|q| q.parameter_lines()).map_or(0, |q| q.singular_points.len());
        rows.push(format!(
            "{kind:?} {k}: start {:?}, {}{}",
            result.congruence.start,
            if singular > 0 { format!("parameter lines ({singular} singular points), ") } else { String::new() },
            if misses.is_empty() { "meets".into() } else { result.verdict.failure_text() }
        ));
    }
    println!("{}", rows.join("\n"));
    // The method is meant to hold on such roofs: most runs meet its guarantees of exactness, θ
    // and α; each run's panels are measured too, and every miss is named (above).
    println!("{met} of 21 meet exactness, θ and α; {buildable} of 21 every guarantee");
    assert!(met >= 20 && buildable >= 19, "{met} of 21 meet exactness, θ and α, {buildable} every guarantee:\n{}", rows.join("\n"));
}

/// The shared surfaces at their settings: the verdict equals the guarantees recomputed from the
/// delivered mesh, and the roofs the method is built for (the vault, `tunnel_arch`, the saddle
/// roof at the paper's Fig. 19 settings, the cylinder and the sphere patch) meet every guarantee.
#[test]
fn the_shared_surfaces_meet_their_guarantees_or_say_so() {
    use spherical_faces::import::{import_file, ImportedFile};
    use spherical_faces::samples::Sample;
    let shared = |name: &str| {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../shared/data/bsplines/{name}.json"));
        match import_file(&std::fs::read(&path).unwrap(), name) {
            Ok(ImportedFile::BSpline(b)) => b.surface,
            other => panic!("{name}: {other:?}"),
        }
    };
    let cases: Vec<(&str, BSplineSurface, f64, f64, bool)> = vec![
        ("vault", Sample::Vault.bspline().unwrap(), 20.0, 75.0, true),
        ("tunnel_arch", shared("tunnel_arch"), 20.0, 75.0, true),
        ("saddle_roof", shared("saddle_roof"), 15.0, 45.0, true),
        ("cylinder_patch", shared("cylinder_patch"), 20.0, 75.0, true),
        ("sphere_patch", shared("sphere_patch"), 20.0, 75.0, true),
        ("paraboloid_dome", shared("paraboloid_dome"), 20.0, 75.0, false),
    ];
    for (name, surface, theta, alpha, must_meet) in cases {
        let reference = Reference::from_bspline(surface).unwrap();
        let params = SqParams { theta_deg: theta, alpha_deg: alpha, ..SqParams::default() };
        let result = compute(&reference, &params, &Fabrication::default(), Clock::native(), &mut |_| Ok(())).unwrap();
        let misses = delivered_misses(&reference, &result, &params);
        assert_eq!(result.verdict.holds(), misses.is_empty(), "{name}: verdict {} against {misses:?}", result.verdict.failure_text());
        assert!(!must_meet || result.verdict.holds(), "{name}: {}", result.verdict.failure_text());
    }
}

/// The hard surfaces (`../shared/data/bsplines/hard`: real roofs' dimensionless curvature, H of
/// both signs on four of them) at the defaults and at the paper's Fig. 19 settings (θ 15°,
/// α 45°): none is refused, every verdict equals the guarantees recomputed from the delivered
/// mesh, and the figures that hold today do not slip: the exact SQ meshes (vertices on their
/// spheres, coplanar centres: 12 of 14), the runs whose panels are all buildable (8) and those
/// that meet every guarantee (8).
#[test]
fn the_hard_surfaces_run_and_say_what_they_miss() {
    use spherical_faces::import::{import_file, ImportedFile};
    let names = ["tunnel_bulged", "roof_rough", "tower_top", "wavy_canopy", "bezier_blob", "revolved_bell", "umbilic_dome"];
    let (mut exact, mut buildable, mut met, mut rows) = (0, 0, 0, Vec::new());
    for name in names {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../shared/data/bsplines/hard/{name}.json"));
        let Ok(ImportedFile::BSpline(b)) = import_file(&std::fs::read(&path).unwrap(), name) else { panic!("{name}") };
        let reference = Reference::from_bspline(b.surface).unwrap();
        for (theta, alpha) in [(20.0, 75.0), (15.0, 45.0)] {
            let params = SqParams { theta_deg: theta, alpha_deg: alpha, ..SqParams::default() };
            let result = compute(&reference, &params, &Fabrication::default(), Clock::native(), &mut |_| Ok(()))
                .unwrap_or_else(|e| panic!("{name}: refused: {e}"));
            let misses = delivered_misses(&reference, &result, &params);
            assert_eq!(result.verdict.holds(), misses.is_empty(), "{name} θ {theta}: verdict {} against {misses:?}", result.verdict.failure_text());
            let holds = |g: &str| result.verdict.guarantees.iter().any(|x| x.name == g && x.holds);
            exact += usize::from(holds("max_vertex_sphere_residual") && holds("max_centre_face_planarity"));
            buildable += usize::from(holds("panels_with_crossing_arcs") && holds("panels_without_exact_surface"));
            met += usize::from(result.verdict.holds());
            // Constant radii first; the central start only after a miss, and the result kept
            // misses no more guarantees than the other.
            let attempts = &result.congruence.attempts;
            assert_eq!(attempts[0].start, RadiusStart::Constant, "{name}");
            let weighed: Vec<usize> = attempts.iter().filter_map(|a| a.final_misses.as_ref().map(Vec::len)).collect();
            let missed = result.verdict.failures().count();
            assert!(weighed.iter().all(|&m| missed <= m), "{name} θ {theta}: kept {missed} misses of {weighed:?}");
            if ["tunnel_bulged", "umbilic_dome", "roof_rough", "revolved_bell"].contains(&name) {
                // The tunnel's and the roof's lattices stop short of sides of their patches: a
                // row of quads out to them covers them. The roof's mesh comes within the distance
                // once moved rigidly onto its reference. The bell's H changes sign.
                assert!(result.verdict.holds(), "{name} θ {theta}: {}", result.verdict.failure_text());
            }
            rows.push(format!(
                "{name} θ {theta} α {alpha}: start {:?}, {}",
                result.congruence.start,
                if misses.is_empty() { "meets".into() } else { result.verdict.failure_text() }
            ));
        }
    }
    println!("{}\n{exact} of 14 exact, {buildable} buildable, {met} meet every guarantee", rows.join("\n"));
    assert!(exact >= 12 && buildable >= 8 && met >= 8, "{exact} exact, {buildable} buildable, {met} meet:\n{}", rows.join("\n"));
}

/// The vault's SQ mesh at the defaults, which meets every guarantee: the exact mesh the broken
/// meshes below start from.
fn exact_vault() -> (Reference, SqParams, spherical_faces::sq::SqResult) {
    let reference = Reference::from_bspline(spherical_faces::samples::Sample::Vault.bspline().unwrap()).unwrap();
    let params = SqParams::default();
    let result = compute(&reference, &params, &Fabrication::default(), Clock::native(), &mut |_| Ok(())).unwrap();
    assert!(result.verdict.holds(), "{}", result.verdict.failure_text());
    (reference, params, result)
}

/// The final check on a deliberately broken SQ mesh: one vertex of the vault's exact mesh moved
/// off its spheres by 1e-4 of the diagonal fails the vertex–sphere guarantee, and the report of
/// such a result says `meets_guarantees: false` with the figure.
#[test]
fn a_broken_sq_mesh_fails_its_final_check() {
    use spherical_faces::geometry::mesh::PolyMesh;
    use spherical_faces::sq::guarantees::{verdict, Delivered};
    use spherical_faces::sq::sq_mesh::sq_mesh;
    let (reference, params, result) = exact_vault();
    let f = result.sq_mesh.as_ref().unwrap();
    let (diag, sm) = (reference.diagonal(), &f.mesh.sphere_mesh);
    let normals: Vec<DVec3> = f.uv.iter().map(|uv| reference.spline().unwrap().derivatives(uv[0], uv[1]).normal().unwrap()).collect();
    let mut positions = sm.mesh.positions.clone();
    let v = positions.len() / 2;
    positions[v] += 1e-4 * diag * normals[v];
    let broken = PolyMesh::new(positions, sm.mesh.faces.clone());
    let stars = QuadStars::new(&broken);
    let out = sq_mesh(broken, sm.face_spheres.clone(), &normals, &stars, diag, params.support_depth * diag, params.axis_length * diag);
    let (_, panels, coverage) = spherical_faces::sq::measure_panels(&reference, &out, &f.uv);
    let delivered =
        Delivered::SqMesh { mesh: &out.sphere_mesh.mesh, figures: &out.figures, panels: &panels, max_distance: params.max_distance, coverage };
    let check = verdict(&result.congruence.figures, delivered, params.theta_deg, params.alpha_deg);
    assert!(!check.holds());
    let missed: Vec<&str> = check.failures().map(|g| g.name.as_str()).collect();
    assert!(missed.contains(&"max_vertex_sphere_residual"), "{missed:?}");
    let g = check.failures().find(|g| g.name == "max_vertex_sphere_residual").unwrap();
    assert!((g.measured - 1e-4).abs() < 2e-5, "the figure measures the move: {}", g.measured);
    let mut report = spherical_faces::export::Report::new("sq");
    report.set_verdict(&check);
    let json: serde_json::Value = serde_json::from_str(&report.to_json()).unwrap();
    assert_eq!(json["meets_guarantees"], false);
    let text = report.failure_text();
    assert!(text.contains(&format!("max_vertex_sphere_residual {:.2e}", g.measured)) && text.contains("must be ≤ 1.00e-8"), "{text}");
}

/// The coverage guarantee on a deliberately broken SQ mesh: the vault's exact mesh with the
/// quads of a band across its middle taken out still has every panel on its sphere, but leaves
/// a hole in the patch; the verdict misses `coverage` with its figure, which is the patch's
/// share without the band, and the report says `meets_guarantees: false`.
#[test]
fn an_sq_mesh_with_a_hole_misses_its_coverage() {
    use spherical_faces::geometry::mesh::PolyMesh;
    use spherical_faces::sq::guarantees::{verdict, Delivered, MIN_COVERAGE};
    use spherical_faces::sq::sq_mesh::sq_mesh;
    let (reference, params, result) = exact_vault();
    let f = result.sq_mesh.as_ref().unwrap();
    assert!(f.coverage >= MIN_COVERAGE, "{}", f.coverage);
    let (diag, sm) = (reference.diagonal(), &f.mesh.sphere_mesh);
    let ((u0, u1), _) = reference.spline().unwrap().domain();
    // The quads whose vertices' u all lie in the middle fifth of the domain.
    let band = |face: &spherical_faces::geometry::mesh::Face| {
        face.corners().iter().all(|&v| {
            let t = (f.uv[v as usize][0] - u0) / (u1 - u0);
            (0.4..=0.6).contains(&t)
        })
    };
    let keep: Vec<usize> = (0..sm.mesh.faces.len()).filter(|&k| !band(&sm.mesh.faces[k])).collect();
    assert!(keep.len() < sm.mesh.faces.len(), "the band holds quads");
    let holed = PolyMesh::new(sm.mesh.positions.clone(), keep.iter().map(|&k| sm.mesh.faces[k]).collect());
    let spheres = keep.iter().map(|&k| sm.face_spheres[k]).collect();
    let normals: Vec<DVec3> = f.uv.iter().map(|uv| reference.spline().unwrap().derivatives(uv[0], uv[1]).normal().unwrap()).collect();
    let stars = QuadStars::new(&holed);
    let out = sq_mesh(holed, spheres, &normals, &stars, diag, params.support_depth * diag, params.axis_length * diag);
    let (_, panels, coverage) = spherical_faces::sq::measure_panels(&reference, &out, &f.uv);
    assert!(coverage < f.coverage - 0.05 && coverage < MIN_COVERAGE, "the hole shows: {coverage} of {}", f.coverage);
    let delivered =
        Delivered::SqMesh { mesh: &out.sphere_mesh.mesh, figures: &out.figures, panels: &panels, max_distance: params.max_distance, coverage };
    let check = verdict(&result.congruence.figures, delivered, params.theta_deg, params.alpha_deg);
    let missed: Vec<&str> = check.failures().map(|g| g.name.as_str()).collect();
    assert!(missed.contains(&"coverage"), "{missed:?}");
    assert!(!missed.contains(&"max_vertex_sphere_residual") && !missed.contains(&"panels_with_crossing_arcs"), "the panels are whole: {missed:?}");
    let mut report = spherical_faces::export::Report::new("sq");
    report.set_verdict(&check);
    let json: serde_json::Value = serde_json::from_str(&report.to_json()).unwrap();
    assert_eq!(json["meets_guarantees"], false);
    let text = report.failure_text();
    let g = check.failures().find(|g| g.name == "coverage").unwrap();
    assert_eq!(g.measured, coverage);
    assert!(text.contains("coverage ") && text.contains("must be ≥ 9.50e-1 of the patch area"), "{text}");
}

/// A corpus of our own (`tests/data/corpus40`: `make_hard.py corpus 40 24`; towers, canopies,
/// blobs, bells, domes, tunnels and roofs, H of both signs on most) at the defaults: none is
/// refused, not for a sign change of H either, every verdict equals the guarantees recomputed
/// from the delivered mesh, and the runs that meet every guarantee today (13 of 24) do not slip.
#[test]
fn our_hard_corpus_runs_and_says_what_it_misses() {
    use spherical_faces::import::{import_file, ImportedFile};
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/corpus40");
    let mut files: Vec<_> =
        std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().path()).filter(|p| p.extension().is_some_and(|e| e == "json")).collect();
    files.sort();
    assert_eq!(files.len(), 24);
    let params = SqParams::default();
    let (mut met, mut rows) = (0, Vec::new());
    for path in files {
        let name = path.file_stem().unwrap().to_string_lossy().to_string();
        let Ok(ImportedFile::BSpline(b)) = import_file(&std::fs::read(&path).unwrap(), &name) else { panic!("{name}") };
        let reference = Reference::from_bspline(b.surface).unwrap();
        let result = compute(&reference, &params, &Fabrication::default(), Clock::native(), &mut |_| Ok(()))
            .unwrap_or_else(|e| panic!("{name}: refused: {e}"));
        let misses = delivered_misses(&reference, &result, &params);
        assert_eq!(result.verdict.holds(), misses.is_empty(), "{name}: verdict {} against {misses:?}", result.verdict.failure_text());
        met += usize::from(result.verdict.holds());
        rows.push(format!(
            "{name}: start {:?}, {}",
            result.congruence.start,
            if misses.is_empty() { "meets".into() } else { result.verdict.failure_text() }
        ));
    }
    println!("{}\n{met} of 24 meet every guarantee", rows.join("\n"));
    assert!(met >= 13, "{met} of 24 meet:\n{}", rows.join("\n"));
}
