//! `spherical-faces`: the native command line over the same pipeline as the browser app.

use std::process::ExitCode;

use spherical_faces::curvature::{jet_fit, JetParams};
use spherical_faces::import::import_mesh;
use spherical_faces::mesh::Topology;

const USAGE: &str = "usage: spherical-faces info <mesh.obj|.gltf|.glb>";

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("info") if args.len() == 2 => match info(&args[1]) {
            Ok(json) => {
                println!("{json}");
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("error: {e}");
                ExitCode::from(2)
            }
        },
        Some("-h" | "--help" | "help") => {
            println!("{USAGE}");
            ExitCode::SUCCESS
        }
        _ => {
            eprintln!("{USAGE}");
            ExitCode::from(2)
        }
    }
}

/// One JSON object: counts after triangulation and welding, and the jet-fitted mean curvature.
fn info(path: &str) -> Result<String, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("{path}: {e}"))?;
    let name = std::path::Path::new(path).file_name().map_or(path.into(), |n| n.to_string_lossy().into_owned());
    let imported = import_mesh(&bytes, &name).map_err(|e| e.to_string())?;
    let topology = Topology::new(&imported.mesh);
    let field = jet_fit(&imported.mesh, &topology, &JetParams::default(), &mut |_, _| true)
        .ok_or("curvature computation was cancelled")?;
    let s = &imported.stats;
    let c = &field.summary;
    let json = serde_json::json!({
        "vertices": s.vertices,
        "faces": s.faces,
        "boundary_loops": s.boundary_loops,
        "non_manifold_edges": s.non_manifold_edges,
        "bbox_diagonal": imported.mesh.bbox_diagonal(),
        "mean_curvature": {"min": c.min_h, "max": c.max_h, "mean": c.mean_h},
        "h_changes_sign": c.h_changes_sign,
    });
    Ok(json.to_string())
}
