//! Where ST panels with crossing arcs come from (Sec. 3): per shared mesh and ε, the panels whose
//! intersection arcs cross at the start (central spheres on the remesh) and after the
//! optimization, before their edges are bisected, and for each such panel: on the boundary or
//! not, its smallest corner angle, its largest kink and the smallest radius of its edge circles
//! against its sphere's; then the edges the delivered panels cut by bisecting planes and the
//! panels that still cross.
//!
//!     cargo run --release --example st_crossings [-- EPSILON [MESH ...]]

use spherical_faces::geometry::mesh::topology::Topology;
use spherical_faces::import::import_mesh;
use spherical_faces::panels::build_panels_with;
use spherical_faces::panels::exact_surface::{ExactSurfaceError, ExactSurfaces};
use spherical_faces::panels::moulds::Fabrication;
use spherical_faces::progress::Clock;
use spherical_faces::reference::Reference;
use spherical_faces::remeshing::Sizing;
use spherical_faces::st_adapted::compute;
use spherical_faces::st_adapted::params::StAdaptedParams;
use spherical_faces::st_adapted::terms::boundary_vertices;

fn crossing(panels: &[spherical_faces::panels::panel::Panel]) -> Vec<usize> {
    ExactSurfaces::of(panels, &[]).refused_panels().filter(|(_, e)| matches!(e, ExactSurfaceError::ArcsCross)).map(|(i, _)| i).collect()
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let sizing = match args.first().map(|s| s.as_str()) {
        Some(s) if s.starts_with("faces:") => Sizing::UniformFaces(s[6..].parse().expect("faces:N")),
        Some(s) => Sizing::Adaptive { epsilon: s.parse().expect("EPSILON") },
        None => Sizing::Adaptive { epsilon: 2e-3 },
    };
    let epsilon = match sizing {
        Sizing::Adaptive { epsilon } => epsilon,
        _ => f64::NAN,
    };
    let names: Vec<String> = if args.len() > 1 { args[1..].to_vec() } else { vec!["botanic-garden-bubble-0".into()] };
    for name in &names {
        let path = format!("{}/../shared/data/meshes/{name}.obj", env!("CARGO_MANIFEST_DIR"));
        let mesh = import_mesh(&std::fs::read(&path).unwrap(), &path).unwrap();
        let reference = Reference::from_triangles(mesh.mesh);
        let params = StAdaptedParams { sizing, ..StAdaptedParams::default() };
        let r = compute(&reference, &params, &Fabrication::default(), Clock::native(), &mut |_| Ok(())).unwrap();
        let tol = 1e-4 * r.diag;
        let initial = crossing(&build_panels_with(&r.initial_sphere_mesh, tol, params.variant));
        let mut intersection = r.sphere_mesh.clone();
        intersection.bisected_edges.clear();
        let intersection_panels = build_panels_with(&intersection, tol, params.variant);
        let fin = crossing(&intersection_panels);
        let delivered = format!(
            "  delivered: {} edges bisected, {} panels whose arcs cross, gap {:?}",
            r.sphere_mesh.bisected_edges.len(),
            crossing(&r.panels).len(),
            r.metrics.max_gap
        );
        println!(
            "{name} ε {epsilon}: {} faces, crossing at start {}, after {}; kink max {:.2}°, vertex distance {:.2e}, panel distance {:.2e}",
            r.panels.len(),
            initial.len(),
            fin.len(),
            r.metrics.max_kink_angle_deg,
            r.metrics.max_vertex_distance_to_reference,
            r.metrics.max_distance_to_reference
        );
        println!("{delivered}");
        if std::env::var("TERMS").is_ok() {
            for t in &r.terms {
                println!(
                    "    term {:>20} w {:.1e} active {} mean {:.2e} max {:.2e} E {:.2e}",
                    t.name, t.weight, t.active, t.mean_abs, t.max_abs, t.energy
                );
            }
        }
        let m = &r.sphere_mesh.mesh;
        let topo = Topology::new(&spherical_faces::geometry::mesh::TriMesh::new(
            m.positions.clone(),
            m.faces.iter().map(|f| [f.corners()[0], f.corners()[1], f.corners()[2]]).collect(),
        ));
        let boundary = boundary_vertices(&topo);
        for &f in fin.iter().take(12) {
            let p = &intersection_panels[f];
            let c = m.faces[f].corners();
            let pts: Vec<_> = c.iter().map(|&v| m.positions[v as usize]).collect();
            let min_angle = (0..3)
                .map(|k| {
                    let (a, b, o) = (pts[(k + 1) % 3], pts[(k + 2) % 3], pts[k]);
                    (a - o).angle_between(b - o).to_degrees()
                })
                .fold(f64::INFINITY, f64::min);
            let on_boundary = c.iter().filter(|&&v| boundary[v as usize]).count();
            let s = r.sphere_mesh.face_spheres[f];
            let radius = if s.a.abs() > 0.0 { 1.0 / (2.0 * s.a.abs()) } else { f64::INFINITY };
            let radii: Vec<String> = p.arcs.iter().map(|a| format!("{:.3}", a.circle.radius / radius)).collect();
            let sweeps: Vec<String> = p.arcs.iter().map(|a| format!("{:.0}", a.sweep().to_degrees())).collect();
            println!(
                "  panel {f}: boundary corners {on_boundary}, min angle {min_angle:.1}°, edge-circle radius / sphere radius [{}], sweeps° [{}], was crossing at start: {}",
                radii.join(", "),
                sweeps.join(", "),
                initial.contains(&f)
            );
        }
    }
}
