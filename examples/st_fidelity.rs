//! Fidelity and quality of ST meshes with adapted face size (Sec. 3) on every shared reference
//! mesh, for both edge variants (Fig. 12), as two tables:
//!
//!     cargo run --release --example st_fidelity [-- EPSILON [MESH | sample:KEY ...]]
//!
//! "Panel distance" is the largest distance of a panel's samples to the reference
//! ([`max_deviation`]), relative to the diagonal: its median, 99th percentile and maximum over the
//! panels, and the maximum over the panels that touch the boundary. Needs `../shared` beside the
//! repo. Minimal surfaces (H ≈ 0) are refused by the method and listed as such.

use spherical_faces::geometry::mesh::topology::Topology;
use spherical_faces::import::import_mesh;
use spherical_faces::panels::deviation::max_deviation;
use spherical_faces::panels::edge_arcs::EdgeArcs;
use spherical_faces::panels::moulds::Fabrication;
use spherical_faces::progress::Clock;
use spherical_faces::reference::Reference;
use spherical_faces::remeshing::Sizing;
use spherical_faces::samples::Sample;
use spherical_faces::st_adapted::compute;
use spherical_faces::st_adapted::params::StAdaptedParams;
use spherical_faces::st_adapted::terms::boundary_vertices;
use spherical_faces::stats::{median, percentile};

const MESHES: [&str; 8] = ["tri_dome", "tri_mesh", "botanic-garden-bubble-0", "cmc1", "flower_cmc1", "chebyshev_sphere", "conical1", "enneper2"];

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let epsilon: f64 = args.first().map_or(2e-3, |s| s.parse().expect("EPSILON is a number"));
    let names: Vec<String> = if args.len() > 1 { args[1..].to_vec() } else { MESHES.iter().map(|s| s.to_string()).collect() };
    println!("ε = {epsilon} (relative to the diagonal)\n");
    println!("| reference | variant | faces | panel distance: median / p99 / max | boundary panels max | max vertex distance | max / ε |");
    println!("|---|---|---|---|---|---|---|");
    let mut quality = Vec::new();
    for name in &names {
        let reference = match name.strip_prefix("sample:") {
            Some(key) => Reference::from_triangles(Sample::from_key(key).expect("a sample's key").mesh()),
            None => {
                let path = format!("{}/../shared/data/meshes/{name}.obj", env!("CARGO_MANIFEST_DIR"));
                let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
                Reference::from_triangles(import_mesh(&bytes, &format!("{name}.obj")).expect("imports").mesh)
            }
        };
        for variant in [EdgeArcs::Intersection, EdgeArcs::BisectingPlanes] {
            let mut params = StAdaptedParams { sizing: Sizing::Adaptive { epsilon }, variant, ..Default::default() };
            if let Some(w) = std::env::var("ST_EDGE_CIRCLE").ok().and_then(|s| s.parse().ok()) {
                params.weights.edge_circle = w;
            }
            let t0 = std::time::Instant::now();
            let r = match compute(&reference, &params, &Fabrication::default(), Clock::native(), &mut |_| Ok(())) {
                Ok(r) => r,
                Err(e) => {
                    println!("| {name} | {variant:?} | refused: {e} | | | | |");
                    break;
                }
            };
            let seconds = t0.elapsed().as_secs_f64();
            let diag = r.diag;
            let topo = Topology::new(&r.sphere_mesh.mesh);
            let boundary = boundary_vertices(&topo);
            let distances: Vec<f64> = r.panels.iter().map(|p| max_deviation(p, &reference) / diag).collect();
            let boundary_max = r
                .sphere_mesh
                .mesh
                .faces
                .iter()
                .zip(&distances)
                .filter(|(face, _)| face.corners().iter().any(|&v| boundary[v as usize]))
                .map(|(_, &d)| d)
                .fold(0.0, f64::max);
            if std::env::var("ST_FIDELITY_DETAIL").is_ok() {
                detail(&reference, &r, &distances, &boundary);
            }
            let m = &r.metrics;
            println!(
                "| {name} | {} | {} | {:.4} / {:.4} / {:.4} | {:.4} | {:.4} | {:.1} |",
                if variant == EdgeArcs::Intersection { "a" } else { "b" },
                m.faces,
                median(&distances).unwrap_or(0.0),
                percentile(distances.iter().copied(), 0.99),
                m.max_distance_to_reference,
                boundary_max,
                m.max_vertex_distance_to_reference,
                m.max_distance_to_reference / epsilon,
            );
            if r.initial_shape.flipped_faces + m.flipped_faces > 0 {
                println!("<!-- {name}: flipped faces {} initially, {} at the end -->", r.initial_shape.flipped_faces, m.flipped_faces);
                let mesh = &r.sphere_mesh.mesh;
                for f in 0..mesh.face_count() {
                    let pts = mesh.face_points(f);
                    let c = pts.iter().sum::<glam::DVec3>() / pts.len() as f64;
                    let hit = reference.closest_point(c).unwrap();
                    let n = mesh.face_area_vector(f);
                    if n.dot(hit.normal.unwrap()) < 0.0 {
                        let corners = mesh.faces[f].corners();
                        println!(
                            "<!--   face {f}: corners on boundary {:?}, area {:.2e}, reference triangle {} bary {:?} -->",
                            corners.iter().map(|&v| boundary[v as usize]).collect::<Vec<_>>(),
                            n.length() / (r.diag * r.diag),
                            hit.triangle,
                            hit.barycentric
                        );
                    }
                }
            }
            for w in &r.warnings {
                println!("<!-- {name} ({variant:?}): warning: {w} -->");
            }
            quality.push((name.clone(), variant, m.clone(), r.iterations, r.angle_iteration_median_ms, seconds, r.warnings.len()));
        }
    }
    println!("\n| reference | variant | kink mean / max (°) | vertex–sphere residual | flipped faces | iterations | median iteration (ms) | total (s) | warnings |");
    println!("|---|---|---|---|---|---|---|---|---|");
    for (name, variant, m, iterations, it_ms, seconds, warnings) in quality {
        println!(
            "| {name} | {} | {:.3} / {:.3} | {:.1e} | {} | {iterations} | {:.2} | {seconds:.2} | {warnings} |",
            if variant == EdgeArcs::Intersection { "a" } else { "b" },
            m.mean_kink_angle_deg,
            m.max_kink_angle_deg,
            m.max_vertex_sphere_residual,
            m.flipped_faces,
            it_ms.unwrap_or(f64::NAN),
        );
    }
}

/// The worst panels: each interior edge's kink angle and the tilt of its intersection circle's
/// plane against the reference normal at the edge midpoint (sin φ = |⟨m̂, n⟩|, 0 when the plane
/// contains the normal), and where the farthest sample lies.
fn detail(reference: &Reference, r: &spherical_faces::st_adapted::StAdaptedResult, distances: &[f64], boundary: &[bool]) {
    use glam::DVec3;
    let sm = &r.sphere_mesh;
    let topo = sm.topology();
    let mut order: Vec<usize> = (0..distances.len()).collect();
    order.sort_by(|&a, &b| distances[b].total_cmp(&distances[a]));
    let initial_panels = spherical_faces::panels::build_panels_with(&r.initial_sphere_mesh, 1e-4 * r.diag, r.variant);
    let initial: Vec<f64> = initial_panels.iter().map(|p| max_deviation(p, reference) / r.diag).collect();
    println!(
        "  initial sphere mesh: panel distance median {:.4} / p99 {:.4} / max {:.4}",
        median(&initial).unwrap_or(0.0),
        percentile(initial.iter().copied(), 0.99),
        initial.iter().copied().fold(0.0, f64::max)
    );
    for &f in order.iter().take(4) {
        let face = sm.mesh.faces[f].corners();
        let on_boundary: Vec<bool> = face.iter().map(|&v| boundary[v as usize]).collect();
        let far = spherical_faces::panels::deviation::panel_samples(&r.panels[f])
            .into_iter()
            .max_by(|a, b| reference.bvh().distance(*a).total_cmp(&reference.bvh().distance(*b)))
            .unwrap();
        let hit = reference.closest_point(far).unwrap();
        let on_ref_boundary = hit.barycentric.iter().any(|&b| b < 1e-9);
        println!("  panel {f}: distance {:.4} (initially {:.4}), vertices on boundary {on_boundary:?}, farthest point's foot on a reference edge: {on_ref_boundary}", distances[f], initial[f]);
        for (e, g, h) in topo.interior_edges() {
            let (g, h) = (g as usize, h as usize);
            if g != f && h != f {
                continue;
            }
            let [a, b] = topo.edges()[e];
            let (pa, pb) = (sm.mesh.positions[a as usize], sm.mesh.positions[b as usize]);
            let (sg, sh) = (sm.face_spheres[g], sm.face_spheres[h]);
            let m = sh.a * sg.b - sg.a * sh.b;
            let n = reference.closest_point(0.5 * (pa + pb)).and_then(|p| p.normal).unwrap_or(DVec3::Z);
            let tilt = (m.normalize_or_zero().dot(n)).abs();
            let arc = spherical_faces::panels::edge_arc_points(sm, &r.panels, [a, b]).unwrap_or_default();
            let dir = (pb - pa).normalize();
            let side = n.cross(dir);
            let (mut sideways, mut along_n) = (0.0f64, 0.0f64);
            for q in &arc {
                let d = *q - pa;
                let off = d - dir * d.dot(dir);
                sideways = sideways.max(off.dot(side).abs());
                along_n = along_n.max(off.dot(n).abs());
            }
            println!(
                "    edge {a}-{b} (length {:.4}): kink {:.3}°, sin φ {:.3}, arc off the chord: sideways {:.4}, along n {:.4}, radii {:.3} / {:.3}",
                (pa - pb).length() / r.diag,
                sg.kink_angle(&sh).to_degrees(),
                tilt,
                sideways / r.diag,
                along_n / r.diag,
                sg.signed_radius().unwrap_or(f64::INFINITY) / r.diag,
                sh.signed_radius().unwrap_or(f64::INFINITY) / r.diag
            );
        }
    }
}
