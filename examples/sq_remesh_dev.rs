use spherical_faces::pipeline::session::Loaded;
use spherical_faces::progress::Clock;
use spherical_faces::samples::Sample;
use spherical_faces::sq::params::SqParams;
use spherical_faces::sq::SqEvent;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    for a in args {
        let loaded = match a.strip_prefix("sample:") {
            Some(k) => Loaded::from_sample(Sample::from_key(k).expect("a sample")),
            None => Loaded::from_file(&std::fs::read(&a).expect("readable"), &a).expect("loads"),
        };
        let mut params = SqParams::default();
        if let Some(n) = std::env::var("FULL").ok().and_then(|v| v.parse().ok()) { params.sphere_iterations[1] = n; }
        if let Some(n) = std::env::var("PROJ").ok().and_then(|v| v.parse().ok()) { params.sphere_iterations[2] = n; }
        if let Some(n) = std::env::var("FAIRIT").ok().and_then(|v| v.parse().ok()) { params.fairing_iterations = n; }
        if let Some(n) = std::env::var("FAIRW").ok().and_then(|v| v.parse().ok()) { params.fairing_weight = n; }
        let verbose = std::env::var("V").is_ok();
        let t0 = std::time::Instant::now();
        let r = spherical_faces::sq::compute(&loaded.surface, &params, Clock::native(), &mut |e| {
            if let SqEvent::Spheres { phase, iteration, terms, .. } = e {
                if verbose && (iteration % 10 == 1 || phase != spherical_faces::sq::sphere_optimization::SpherePhase::Full) {
                    let t: Vec<String> = terms.iter().filter(|t| t.weight > 0.0).map(|t| format!("{}={:.2e}/{:.1e}", t.name, t.energy, t.max_abs)).collect();
                    println!("  {:?} {iteration}: {}", phase, t.join(" "));
                }
            }
            Ok(())
        }).unwrap();
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        let q = r.quad_mesh.as_ref().unwrap();
        let f = r.sq_mesh.as_ref().unwrap();
        let stat = |v: &[f64]| (v.iter().sum::<f64>() / v.len() as f64, v.iter().cloned().fold(0.0, f64::max));
        println!("{a}: {ms:.0} ms, faces {} coverage {:.3} dropped {} param-lines {} remesh angles {:?} Q' angles {:?} final angles {:?}",
            q.mesh.face_count(), q.coverage, q.dropped, q.parameter_lines, stat(&q.remesh_edge_angles_deg), stat(&q.edge_angles_deg), stat(&f.edge_angles_deg));
        println!("  {:?}", f.mesh.figures);
        println!("  iterations {} {} {} final it median {:?} timings {:?}", f.outcome.warm_up_iterations, f.outcome.iterations, f.outcome.projection_iterations, r.final_iteration_median_ms(), r.timings_ms);
        println!("  congruence: {:?}", r.congruence.figures);
        println!("  phases {:?}", f.outcome.phase_ms);
        if let Ok(v) = std::env::var("FAN") { for v in v.split(",") { probe_fan(f, loaded.surface.spline().unwrap(), v.parse().unwrap()); } }
        if let Ok(v) = std::env::var("PROBE") { for v in v.split(",") { probe(&f.mesh.sphere_mesh, v.parse().unwrap()); } }
    }
}
#[allow(dead_code)]
pub fn probe(sm: &spherical_faces::panels::sphere_mesh::SphereMesh, v: u32) {
    use glam::DVec3;
    let p = sm.mesh.positions[v as usize];
    let faces: Vec<usize> = sm.mesh.faces.iter().enumerate().filter(|(_, f)| f.corners().contains(&v)).map(|(i, _)| i).collect();
    let cs: Vec<DVec3> = faces.iter().map(|&f| sm.face_spheres[f].center().unwrap()).collect();
    let n = (cs[1] - cs[0]).cross(cs[2] - cs[0]).normalize();
    let d = (p - cs[0]).dot(n);
    let vp = p - 2.0 * d * n;
    println!("vertex {v}: faces {faces:?} radii {:?}", faces.iter().map(|&f| sm.face_spheres[f].signed_radius().unwrap()).collect::<Vec<_>>());
    println!("  centres {:?}", cs);
    println!("  4th centre off plane {:.3e}, psi(v) {:?} psi(v') {:?} |v'-v| {:.3e}", (cs[3] - cs[0]).dot(n), faces.iter().map(|&f| sm.face_spheres[f].eval(p)).collect::<Vec<_>>(), faces.iter().map(|&f| sm.face_spheres[f].eval(vp)).collect::<Vec<_>>(), (vp - p).length());
}
#[allow(dead_code)]
pub fn probe_fan(f: &spherical_faces::sq::SqFinal, surface: &spherical_faces::geometry::bspline::BSplineSurface, v: usize) {
    let sm = &f.mesh.sphere_mesh;
    let faces: Vec<usize> = sm.mesh.faces.iter().enumerate().filter(|(_, fc)| fc.corners().contains(&(v as u32))).map(|(i, _)| i).collect();
    let cs: Vec<glam::DVec3> = faces.iter().map(|&g| sm.face_spheres[g].center().unwrap()).collect();
    let n = (cs[0] - cs[1]).cross(cs[1] - cs[2]).normalize();
    let uv = f.uv[v];
    let sn = surface.derivatives(uv[0], uv[1]).normal().unwrap();
    println!("fan {v}: faces {faces:?} centre-plane angle {:.3} axis {:?} axis angle {:.3}", n.dot(sn).abs().acos().to_degrees(), f.mesh.node_axes[v].1, f.mesh.node_axes[v].1.dot(sn).abs().acos().to_degrees());
}
