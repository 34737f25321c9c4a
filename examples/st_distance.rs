//! Where ST panels lie farthest from the reference (Sec. 3): per shared mesh and ε, the panels
//! farthest away, and for each: its boundary corners, its corners' and its centroid's distance,
//! and where on the panel its farthest sample lies (an arc: boundary, bisected or intersection;
//! or its inside), against the bound 2ε.
//!
//!     cargo run --release --example st_distance [-- EPSILON [MESH ...]]

use spherical_faces::import::{import_file, ImportedFile};
use spherical_faces::panels::deviation::panel_samples;
use spherical_faces::panels::moulds::Fabrication;
use spherical_faces::progress::Clock;
use spherical_faces::reference::Reference;
use spherical_faces::remeshing::Sizing;
use spherical_faces::st_adapted::compute;
use spherical_faces::st_adapted::params::StAdaptedParams;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let epsilon: f64 = args.first().map_or(2e-3, |s| s.parse().expect("EPSILON"));
    let names: Vec<String> = if args.len() > 1 { args[1..].to_vec() } else { vec!["M2_eq_quad2".into()] };
    for name in &names {
        // A shared mesh by name, or a path (a B-spline .json, say).
        let path = if name.contains('/') { name.clone() } else { format!("{}/../shared/data/meshes/{name}.obj", env!("CARGO_MANIFEST_DIR")) };
        let reference = match import_file(&std::fs::read(&path).unwrap(), &path).unwrap() {
            ImportedFile::BSpline(b) => Reference::from_bspline(b.surface).unwrap(),
            ImportedFile::Mesh(m) => Reference::from_triangles(m.mesh),
        };
        let params = StAdaptedParams { sizing: Sizing::Adaptive { epsilon }, ..StAdaptedParams::default() };
        let r = compute(&reference, &params, &Fabrication::default(), Clock::native(), &mut |_| Ok(())).unwrap();
        let diag = r.diag;
        let bound = params.distance_bound(reference.facet_sagitta());
        let sm = &r.sphere_mesh;
        let topo = sm.topology();
        println!(
            "{name} ε {epsilon}: {} panels, distance {:.2e} (bound {bound:.2e}, facet sagitta {:.2e}), vertices {:.2e}",
            r.panels.len(),
            r.metrics.max_distance_to_reference,
            reference.facet_sagitta(),
            r.metrics.max_vertex_distance_to_reference
        );
        let far: Vec<(usize, f64)> = sm
            .mesh
            .positions
            .iter()
            .enumerate()
            .map(|(v, &x)| (v, reference.closest_point(x).map_or(f64::NAN, |h| h.point.distance(x)) / diag))
            .filter(|&(_, d)| d > 0.5 * bound)
            .collect();
        for (v, d) in far.iter().take(6) {
            let before = r.remeshed.positions[*v];
            let d0 = reference.closest_point(before).map_or(f64::NAN, |h| h.point.distance(before)) / diag;
            let x = sm.mesh.positions[*v];
            let hit = reference.closest_point(x).unwrap();
            let normal_part = hit.normal.map_or(f64::NAN, |n| n.dot(x - hit.point).abs()) / diag;
            println!(
                "  vertex {v}: {d:.2e} (along the normal {normal_part:.2e}; in the remesh {d0:.2e}), boundary {}, barycentric {:?}",
                topo.is_boundary_vertex(*v),
                hit.barycentric
            );
        }
        for p in &r.panels {
            for (k, a) in p.arcs.iter().enumerate() {
                if a.sweep().to_degrees() > 150.0 {
                    let (u, v) = (p.corners[k], p.corners[(k + 1) % p.corners.len()]);
                    let faces = topo.edge_index(u, v).map_or(0, |e| topo.edge_faces(e).len());
                    println!(
                        "  panel {} side {k}: sweeps {:.1}°, edge with {faces} faces, bisected {}, sphere radius / edge {:.3}",
                        p.face,
                        a.sweep().to_degrees(),
                        sm.bisected_edges.contains(&[u.min(v), u.max(v)]),
                        0.5 / p.sphere.a.abs() / a.from.distance(a.to)
                    );
                }
            }
        }
        let mut order: Vec<usize> = (0..r.panels.len()).collect();
        order.sort_by(|&a, &b| r.panel_deviations[b].total_cmp(&r.panel_deviations[a]));
        let dist = |x| reference.closest_point(x).map_or(f64::NAN, |h| h.point.distance(x)) / diag;
        for &f in order.iter().take(8) {
            let p = &r.panels[f];
            let corners: Vec<String> = p.corners.iter().map(|&v| format!("{:.1e}", dist(sm.mesh.positions[v as usize]))).collect();
            let boundary = p.corners.iter().filter(|&&v| topo.is_boundary_vertex(v as usize)).count();
            let centroid = p.corners.iter().map(|&v| sm.mesh.positions[v as usize]).sum::<glam::DVec3>() / p.corners.len() as f64;
            let centroid_on = dist(p.sphere.closest_point(centroid));
            // Where the farthest sample lies: arc k or inside.
            let n = p.corners.len();
            let mut worst = (0.0, String::new());
            for (k, a) in p.arcs.iter().enumerate() {
                let (u, v) = (p.corners[k], p.corners[(k + 1) % n]);
                let kind = match topo.edge_index(u, v).map(|e| topo.edge_faces(e).len()) {
                    Some(1) => "boundary arc",
                    _ if sm.bisected_edges.contains(&[u.min(v), u.max(v)]) => "bisected arc",
                    _ => "intersection arc",
                };
                for x in a.sample(16) {
                    let d = dist(x);
                    if d > worst.0 {
                        worst = (d, format!("{kind} {k} (sagitta {:.1e})", a.sagitta() / diag));
                    }
                }
            }
            for x in panel_samples(p) {
                let d = dist(x);
                if d > worst.0 * 1.0001 {
                    worst = (d, "inside".into());
                }
            }
            println!(
                "  panel {f}: {:.2e} ({:.1}× bound), boundary corners {boundary}, corners [{}], centroid {centroid_on:.1e}, farthest at {} {:.2e}",
                r.panel_deviations[f] / diag,
                r.panel_deviations[f] / diag / bound,
                corners.join(", "),
                worst.1,
                worst.0
            );
        }
    }
}
