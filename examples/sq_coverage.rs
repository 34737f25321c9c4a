//! Where the SQ panels leave the patch uncovered: a character map of the parameter domain for
//! the remesh, Q′ and the final mesh ('#' covered, '.' not), with each coverage:
//! `cargo run --release --example sq_coverage -- FILE.json|sample:vault ...`.

use spherical_faces::geometry::bspline::BSplineSurface;
use spherical_faces::geometry::mesh::Face;
use spherical_faces::panels::moulds::Fabrication;
use spherical_faces::pipeline::session::Loaded;
use spherical_faces::progress::Clock;
use spherical_faces::remeshing::quad_remeshing::coverage;
use spherical_faces::samples::Sample;
use spherical_faces::sq::params::SqParams;

fn inside(poly: &[[f64; 2]], p: [f64; 2]) -> bool {
    let mut odd = false;
    for k in 0..poly.len() {
        let (a, b) = (poly[k], poly[(k + 1) % poly.len()]);
        if (a[1] > p[1]) != (b[1] > p[1]) && p[0] < a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]) {
            odd = !odd;
        }
    }
    odd
}

fn map(surface: &BSplineSurface, faces: &[Face], uv: &[[f64; 2]]) {
    let ((u0, u1), (v0, v1)) = surface.domain();
    let (nu, nv) = (72, 28);
    for j in (0..nv).rev() {
        let line: String = (0..nu)
            .map(|i| {
                let p = [u0 + (i as f64 + 0.5) / nu as f64 * (u1 - u0), v0 + (j as f64 + 0.5) / nv as f64 * (v1 - v0)];
                let hit = faces.iter().any(|f| inside(&f.corners().iter().map(|&c| uv[c as usize]).collect::<Vec<_>>(), p));
                if hit {
                    '#'
                } else {
                    '.'
                }
            })
            .collect();
        println!("  {line}");
    }
}

fn main() {
    for a in std::env::args().skip(1) {
        let loaded = match a.strip_prefix("sample:") {
            Some(k) => Loaded::from_sample(Sample::from_key(k).expect("a sample")),
            None => Loaded::from_file(&std::fs::read(&a).expect("readable"), &a).expect("loads"),
        };
        let params = SqParams::default();
        let r = spherical_faces::sq::compute(&loaded.surface, &params, &Fabrication::default(), Clock::native(), &mut |_| Ok(())).expect("runs");
        let s = loaded.surface.spline().expect("a B-spline");
        let q = r.quad_mesh.as_ref().expect("Q′");
        println!("{a}: Q′ {} quads, coverage {:.4}", q.mesh.faces.len(), coverage(s, &q.mesh.faces, &q.uv));
        map(s, &q.mesh.faces, &q.uv);
        if let Some(f) = &r.sq_mesh {
            println!("final: coverage {:.4}", f.coverage);
            map(s, &f.mesh.sphere_mesh.mesh.faces, &f.uv);
        }
        println!("verdict: {}", if r.verdict.holds() { "meets".into() } else { r.verdict.failure_text() });
    }
}
