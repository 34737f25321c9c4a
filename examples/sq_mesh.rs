//! Runs the whole SQ method (Sec. 5) and prints the quad mesh, the figures of exactness, the
//! iterations and where the final optimization's time goes:
//! `cargo run --release --example sq_mesh -- FILE.json|sample:vault ...`.
//! Environment: FACES (the number of quads N), FULL / PROJ (iterations of the full optimization / the projection), FAIRIT /
//! FAIRW (Q′ fairing iterations / weight), V (print the terms during the final optimization),
//! DUMP (each face's worst vertex distance to its sphere, and its radius), FAR (the vertices
//! farthest from the reference), PHASES (the farthest vertex after each phase).

use spherical_faces::panels::moulds::Fabrication;
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
        if let Some(n) = std::env::var("FULL").ok().and_then(|v| v.parse().ok()) {
            params.sphere_iterations[1] = n;
        }
        if let Some(n) = std::env::var("PROJ").ok().and_then(|v| v.parse().ok()) {
            params.sphere_iterations[2] = n;
        }
        if let Some(n) = std::env::var("FACES").ok().and_then(|v| v.parse().ok()) {
            params.faces = n;
        }
        if let Some(n) = std::env::var("FAIRIT").ok().and_then(|v| v.parse().ok()) {
            params.fairing_iterations = n;
        }
        if let Some(n) = std::env::var("FAIRW").ok().and_then(|v| v.parse().ok()) {
            params.fairing_weight = n;
        }
        let verbose = std::env::var("V").is_ok();
        // PHASES: the farthest vertex from the reference (of the diagonal) after each phase.
        let phases = std::env::var("PHASES").is_ok();
        let diag = loaded.surface.diagonal();
        let mut last_phase: Option<(spherical_faces::sq::sphere_optimization::SpherePhase, f64)> = None;
        let mut phase_log: Vec<String> = Vec::new();
        let t0 = std::time::Instant::now();
        let r = spherical_faces::sq::compute(&loaded.surface, &params, &Fabrication::default(), Clock::native(), &mut |e| {
            if let SqEvent::Spheres { phase, iteration, terms, positions, .. } = e {
                if phases {
                    {
                        let far =
                            positions.iter().map(|p| loaded.surface.closest_point(*p).map_or(0.0, |q| q.point.distance(*p))).fold(0.0, f64::max)
                                / diag;
                        if let Some((ph, d)) = last_phase {
                            if ph != phase || iteration == 1 {
                                phase_log.push(format!("{ph:?} {d:.2e}"));
                            }
                        }
                        last_phase = Some((phase, far));
                    }
                }
                if verbose && (iteration % 10 == 1 || phase != spherical_faces::sq::sphere_optimization::SpherePhase::Full) {
                    let t: Vec<String> =
                        terms.iter().filter(|t| t.weight > 0.0).map(|t| format!("{}={:.2e}/{:.1e}", t.name, t.energy, t.max_abs)).collect();
                    println!("  {:?} {iteration}: {}", phase, t.join(" "));
                }
            }
            Ok(())
        })
        .unwrap();
        if let Some((ph, d)) = last_phase {
            phase_log.push(format!("{ph:?} {d:.2e}"));
        }
        if phases {
            println!("  farthest vertex after each phase: {}", phase_log.join(", "));
        }
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        let q = r.quad_mesh.as_ref().unwrap();
        let f = r.sq_mesh.as_ref().unwrap();
        let stat = |v: &[f64]| (v.iter().sum::<f64>() / v.len() as f64, v.iter().cloned().fold(0.0, f64::max));
        println!(
            "{a}: {ms:.0} ms, faces {} coverage {:.3} dropped {} singular vertices {} remesh angles {:?} Q' angles {:?} final angles {:?}",
            q.mesh.face_count(),
            q.coverage,
            q.dropped,
            q.singular.len(),
            stat(&q.remesh_edge_angles_deg),
            stat(&q.edge_angles_deg),
            stat(&f.edge_angles_deg)
        );
        println!("  {:?}", f.mesh.figures);
        println!(
            "  iterations {} {} {} final it median {:?} timings {:?}",
            f.outcome.warm_up_iterations,
            f.outcome.iterations,
            f.outcome.projection_iterations,
            r.final_iteration_median_ms(),
            r.timings_ms
        );
        println!("  congruence: {:?}", r.congruence.figures);
        let rr = &r.congruence.radii;
        println!(
            "  radii min {:.3} max {:.3} start {:?} diag-rel faces",
            rr.iter().cloned().fold(f64::INFINITY, f64::min),
            rr.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
            r.congruence.start
        );
        println!("  phases {:?}", f.outcome.phase_ms);
        if std::env::var("DUMP").is_ok() {
            dump(&f.mesh);
        }
        if std::env::var("FAR").is_ok() {
            // The vertices farthest from the reference, with (u, v), boundary flag and valence.
            let spline = loaded.surface.spline_reference().unwrap();
            let diag = loaded.surface.diagonal();
            let mesh = &f.mesh.sphere_mesh.mesh;
            let mut far: Vec<(f64, usize)> =
                mesh.positions.iter().enumerate().map(|(v, p)| (spline.closest_point(*p, f.uv[v]).1.distance(*p) / diag, v)).collect();
            let signed: Vec<f64> = mesh
                .positions
                .iter()
                .enumerate()
                .map(|(v, p)| {
                    let (_, q, n) = spline.closest_point(*p, f.uv[v]);
                    (*p - q).dot(n.unwrap_or(glam::DVec3::Z)) / diag
                })
                .collect();
            let pos = signed.iter().filter(|&&x| x > 0.0).count();
            println!(
                "  vertex distance: mean {:.2e}, signed mean {:.2e}, {} of {} on the normal's side",
                far.iter().map(|x| x.0).sum::<f64>() / far.len() as f64,
                signed.iter().sum::<f64>() / signed.len() as f64,
                pos,
                signed.len()
            );
            far.sort_by(|a, b| b.0.total_cmp(&a.0));
            let valence = |v: usize| mesh.faces.iter().filter(|fc| fc.corners().contains(&(v as u32))).count();
            for &(d, v) in far.iter().take(6) {
                println!("  far vertex {v}: {d:.2e} of the diagonal at uv {:?}, boundary {}, faces {}", f.uv[v], q.on_boundary[v], valence(v));
            }
        }
    }
}

/// DUMP: per face, its worst vertex distance to its sphere and its signed radius (model units).
#[allow(dead_code)]
pub fn dump(f: &spherical_faces::sq::sq_mesh::SqMesh) {
    let sm = &f.sphere_mesh;
    for (i, (face, s)) in sm.mesh.faces.iter().zip(&sm.face_spheres).enumerate() {
        let d = face.corners().iter().map(|&v| s.distance(sm.mesh.positions[v as usize]).abs()).fold(0.0, f64::max);
        println!("face {i} res {d:.3e} r {:?} corners {:?}", s.signed_radius(), face.corners());
    }
}
