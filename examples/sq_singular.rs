//! Prints the singular points of the SQ torsal field as the remesh prepares it (Sec. 5.2):
//! `cargo run --release --example sq_singular -- FILE.json ...`; DUMP=DIR also writes the remesh
//! along the field (singular vertices and all, before Q′'s fairing) as DIR/NAME_uv.obj.

use spherical_faces::pipeline::session::Loaded;
use spherical_faces::progress::Clock;
use spherical_faces::remeshing::quad_remeshing::{prepare, quad_remesh, CrossField, QuadRemeshParams};
use spherical_faces::sq::params::SqParams;

fn main() {
    for a in std::env::args().skip(1) {
        let loaded = Loaded::from_file(&std::fs::read(&a).expect("readable"), &a).expect("loads");
        let params = SqParams::default();
        let c = spherical_faces::sq::compute_congruence(&loaded.surface, &params, Clock::native(), &mut |_| Ok(())).expect("congruence");
        let surface = loaded.surface.spline().expect("a B-spline");
        let field = CrossField::new(surface, c.grid, &c.torsal_uv).expect("a field");
        let rp = QuadRemeshParams { target_faces: params.faces, ..QuadRemeshParams::default() };
        let prepared = prepare(surface, &field, &rp).expect("prepared");
        println!("{a}: start {:?}, grid {}, fine {}x{}, spacing {:.3}", c.start, c.grid, prepared.field.grid.nu, prepared.field.grid.nv, prepared.spacing);
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
                out += &format!("v {} {} 0\n", w[0], w[1]);
            }
            for f in &q.mesh.faces {
                out += &format!("f {}\n", f.corners().iter().map(|c| (c + 1).to_string()).collect::<Vec<_>>().join(" "));
            }
            std::fs::write(format!("{dir}/{name}_uv.obj"), out).unwrap();
        }
    }
}
