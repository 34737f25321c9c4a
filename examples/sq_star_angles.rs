// Development aid: runs SQ on one B-spline JSON and prints the stars whose support planes meet
// below α, with their valence, parameters and distance to the nearest singular vertex.
use spherical_faces::panels::moulds::Fabrication;
use spherical_faces::pipeline::session::Loaded;
use spherical_faces::progress::Clock;
use spherical_faces::sq::compute;
use spherical_faces::sq::params::SqParams;
use spherical_faces::sq::sphere_optimization::QuadStars;
use spherical_faces::sq::sq_mesh::star_support_plane_angle_deg;

fn main() {
    let name = std::env::args().nth(1).unwrap();
    let loaded = Loaded::from_file(&std::fs::read(&name).unwrap(), &name).unwrap();
    let params = SqParams::default();
    let r = compute(&loaded.surface, &params, &Fabrication::default(), Clock::native(), &mut |_| Ok(())).unwrap();
    let q = r.quad_mesh.as_ref().unwrap();
    let f = r.sq_mesh.as_ref().unwrap();
    let sm = &f.mesh.sphere_mesh;
    let mesh = &sm.mesh;
    let cones: Vec<[f64; 2]> = q.singular.iter().map(|(v, _)| q.uv[*v as usize]).collect();
    let stars = QuadStars::new(mesh);
    let mut low = Vec::new();
    for (v, faces) in &stars.stars {
        let worst = star_support_plane_angle_deg(sm, &f.mesh.support.node_axes.axes, *v, faces);
        if worst < params.alpha_deg {
            let uv = f.uv[*v as usize];
            let d = cones.iter().map(|c| ((c[0] - uv[0]).powi(2) + (c[1] - uv[1]).powi(2)).sqrt()).fold(f64::INFINITY, f64::min);
            low.push((worst, faces.len(), uv, d));
        }
    }
    low.sort_by(|a, b| a.0.total_cmp(&b.0));
    println!("{} stars, {} below α; singular at {cones:?}", stars.stars.len(), low.len());
    for (w, m, uv, d) in low.iter().take(25) {
        println!("  {w:.2}° valence {m} at ({:.2}, {:.2}), {d:.2} from a singular vertex", uv[0], uv[1]);
    }
}
