//! Prints the singular points of the SQ torsal field as the remesh prepares it (Sec. 5.2):
//! `cargo run --release --example sq_singular -- FILE.json ...`; DUMP=DIR also writes the remesh
//! along the field (singular vertices and all, before Q′'s fairing) as DIR/NAME_uv.obj, and on
//! the surface, with the patch's outline as comments, as DIR/NAME_xyz.obj.

use spherical_faces::pipeline::session::Loaded;
use spherical_faces::progress::Clock;
use spherical_faces::remeshing::quad_remeshing::{prepare, quad_remesh, CrossField, QuadRemeshParams};
use spherical_faces::sq::params::SqParams;

fn main() {
    for a in std::env::args().skip(1) {
        let loaded = Loaded::from_file(&std::fs::read(&a).expect("readable"), &a).expect("loads");
        let params = SqParams::default();
        let c = spherical_faces::sq::compute_congruence(&loaded.surface, &params, Clock::native(), &mut |_| Ok(())).expect("congruence");
        // As SQ remeshes: on the patch with its parameters at one speed.
        let given = loaded.surface.spline().expect("a B-spline");
        let (patch, torsal_uv) = spherical_faces::sq::quad_mesh::isotropic(given, &c.torsal_uv);
        let surface = &patch.surface;
        let field = CrossField::new(surface, c.grid, &torsal_uv).expect("a field");
        let rp = QuadRemeshParams { target_faces: params.faces, ..QuadRemeshParams::default() };
        let prepared = prepare(surface, &field, &rp).expect("prepared");
        println!(
            "{a}: start {:?}, grid {}, fine {}x{}, spacing {:.3}",
            c.start, c.grid, prepared.field.grid.nu, prepared.field.grid.nv, prepared.spacing
        );
        for s in &prepared.field.singular {
            let uv = prepared.field.grid.uv(s.node);
            let p = surface.point(uv.x, uv.y);
            println!("  quarters {:+} at uv ({:.3}, {:.3}) xyz ({:.2}, {:.2}, {:.2})", s.quarters, uv.x, uv.y, p.x, p.y, p.z);
        }
        // DUMP=DIR: the remesh along the torsal field, singular vertices and all, as OBJ in the
        // parameter plane (z 0).
        if let Ok(dir) = std::env::var("DUMP") {
            let q = quad_remesh(surface, &field, &rp).expect("a remesh");
            println!("  singular vertices {:?}, dropped {}", q.singular, q.dropped);
            let name = std::path::Path::new(&a).file_stem().unwrap().to_string_lossy().to_string();
            let mut out = String::new();
            for w in &q.uv {
                let [u, v] = patch.to_given(*w);
                out += &format!("v {u} {v} 0\n");
            }
            for f in &q.mesh.faces {
                out += &format!("f {}\n", f.corners().iter().map(|c| (c + 1).to_string()).collect::<Vec<_>>().join(" "));
            }
            std::fs::write(format!("{dir}/{name}_uv.obj"), out).unwrap();
            // The same mesh on the surface, and the patch's outline, in model units.
            let mut out = String::new();
            for p in &q.mesh.positions {
                out += &format!("v {} {} {}\n", p.x, p.y, p.z);
            }
            for f in &q.mesh.faces {
                out += &format!("f {}\n", f.corners().iter().map(|c| (c + 1).to_string()).collect::<Vec<_>>().join(" "));
            }
            let ((u0, u1), (v0, v1)) = given.domain();
            for k in 0..400 {
                let t = k as f64 / 100.0;
                let (u, v) = match k / 100 {
                    0 => (u0 + (u1 - u0) * t, v0),
                    1 => (u1, v0 + (v1 - v0) * (t - 1.0)),
                    2 => (u1 - (u1 - u0) * (t - 2.0), v1),
                    _ => (u0, v1 - (v1 - v0) * (t - 3.0)),
                };
                let p = given.point(u, v);
                out += &format!("# outline {} {} {}\n", p.x, p.y, p.z);
            }
            std::fs::write(format!("{dir}/{name}_xyz.obj"), out).unwrap();
        }
    }
}
