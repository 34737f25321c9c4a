//! The metrics of ST meshes with support structure (Sec. 4) on the shared reference meshes, with
//! and without the optimized radius (Fig. 16, right), as a table:
//!
//!     cargo run --release --example st_support_metrics
//!
//! Needs `../shared` beside the repo.

use spherical_faces::geometry::absolute_sphere::AbsoluteSphere;
use spherical_faces::import::import_mesh;
use spherical_faces::panels::moulds::Fabrication;
use spherical_faces::progress::{ignore, Clock};
use spherical_faces::reference::Reference;
use spherical_faces::st_support::{compute, StSupportParams};
use spherical_faces::stats::summary_stats;

fn main() {
    for name in ["tri_mesh", "botanic-garden-bubble-0", "cmc1"] {
        let path = format!("{}/../shared/data/meshes/{name}.obj", env!("CARGO_MANIFEST_DIR"));
        let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
        let mesh = import_mesh(&bytes, &format!("{name}.obj")).expect("imports").mesh;
        let reference = Reference::from_triangles(mesh);
        for optimize_radius in [false, true] {
            let params = StSupportParams { optimize_radius, ..Default::default() };
            let r = compute(&reference, &params, &Fabrication::default(), Clock::native(), &mut ignore).expect("st-support succeeds");
            let est = &r.absolute;
            let (a0, m0med, m0max) = summary_stats(&est.angles_m0_deg);
            let (a1, m1med, m1max) = summary_stats(&est.angles_m_deg);
            let (r2mean, r2med, _) = summary_stats(&est.r2_samples);
            let m = &r.metrics;
            let omega = match r.omega {
                AbsoluteSphere::Sphere { center, r2 } => {
                    format!("m = {:.4?}, R² = {r2:.4} ({:.4} diag²)", center.to_array(), r2 / (r.diag * r.diag))
                }
                AbsoluteSphere::Plane { axis, d } => format!("plane a = {:.4?}, d = {d:.4}", axis.to_array()),
            };
            let mesh = reference.mesh();
            println!("== {name} (V {}, F {}, diag {:.4}) optimize_radius = {optimize_radius}", mesh.vertex_count(), mesh.face_count(), r.diag);
            println!("   Ω: {omega}; at_infinity {}; flipped {}; mean-R² estimate {:?}", est.at_infinity, est.flipped, est.omega);
            println!("   m0 = {:.4?}  angle(v−m0, n) mean/median/max = {a0:.3}/{m0med:.3}/{m0max:.3}°", est.m0.to_array());
            println!(
                "   m  = {:.4?}  angle(v−m,  n) mean/median/max = {a1:.3}/{m1med:.3}/{m1max:.3}°  (E_center {:.4} → {:.4}, E_∞ {:.4}, {} LM its)",
                est.m.to_array(),
                est.e_center_m0,
                est.e_center_m,
                est.e_center_infinity,
                est.lm_iterations
            );
            println!(
                "   R_i²: mean {r2mean:.4}, median {r2med:.4} over {} usable central spheres ({} skipped)",
                est.usable_spheres, est.skipped_spheres
            );
            println!(
                "   metrics: vertex_sphere {:.2e}, orthogonality {:.2e}, node_axis_offset {:.2e}, axis–normal mean/max {:.3}/{:.3}°, kink mean/max {:.3}/{:.3}° ({} interior edges; estimate's mean kink {:.3}°), axes from stars {}",
                m.max_vertex_sphere_residual,
                m.max_orthogonality_residual,
                m.max_node_axis_offset,
                m.mean_axis_normal_angle_deg,
                m.max_axis_normal_angle_deg,
                m.mean_kink_angle_deg,
                m.max_kink_angle_deg,
                m.interior_edges,
                r.mean_kink_estimate_deg,
                m.axes_from_spheres
            );
            let t: Vec<String> = r.timings_ms.iter().map(|(s, t)| format!("{s} {t:.1}")).collect();
            println!("   timings ms: {}", t.join(", "));
        }
    }
}
